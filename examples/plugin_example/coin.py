"""A minimal trackfuse experiment plugin: estimate a coin's bias by the sample mean.

Run it from this folder (trackfuse puts the current folder on the path)::

    cd examples/plugin_example
    trackfuse run coin.yaml --out /tmp/coin-results

See ``docs/plugins.md`` for the contract.
"""

from __future__ import annotations

from trackfuse.experiments.base import Experiment, FigureSpec, Metric, Param
from trackfuse.reportkit.looks import GREEN, Look
from trackfuse.reportkit.spec import Plot, Reference
from trackfuse.seeding import TrialStreams


def run_trial(params, streams: TrialStreams) -> list[dict]:
    """Toss ``tosses`` coins of bias ``p`` (common stream: every point reuses the same
    uniforms) and report the estimate's error and whether a 95 % Wald interval covers p."""
    p, n = float(params["p"]), int(params["tosses"])
    heads = int((streams.common.random(n) < p).sum())
    estimate = heads / n
    half_width = 1.96 * (estimate * (1 - estimate) / n) ** 0.5
    return [{"algorithm": "sample_mean", "abs_error": abs(estimate - p),
             "covered": int(abs(estimate - p) <= half_width)}]


EXPERIMENT = Experiment(
    name="coin",
    title="Coin bias by the sample mean (plugin example)",
    params=(
        Param("p", 0.3, "probability of heads", "1", low=0.0, high=1.0, label="true bias p"),
        Param("tosses", 50, "tosses per trial", "tosses", kind=int, low=1, high=10**6,
              label="tosses", symbol="n"),
    ),
    run_trial=run_trial,
    metrics=(
        Metric("abs_error", "1", "absolute error of the estimated bias", better="lower",
               label="mean absolute error"),
        Metric("covered", "1", "the 95 % Wald interval covers p", binary=True,
               better="higher", label="Wald interval covers p"),
    ),
    report="coin_report",
    # The figures as data: the report kit draws them (no matplotlib in this plugin).
    figures={
        "error": FigureSpec("Mean absolute error of the sample mean against the true bias, "
                            "95 % Student-t band",
                            plot=Plot(("abs_error",), "p")),
        "coverage": FigureSpec("Coverage of the 95 % Wald interval against the true bias, "
                               "95 % Wilson band; dashed: the nominal 95 %",
                               plot=Plot(("covered",), "p",
                                         references=(Reference(y=0.95, label="nominal"),))),
    },
    looks={"sample_mean": Look("sample mean", GREEN, "o", "ours")},
)
