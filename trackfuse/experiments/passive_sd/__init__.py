"""S-D assignment of three or more passive sensors beside the two-sensor exact assignment
(``passive_sd``).

The science (sensor geometry, tuple costs, Lagrangian relaxation, the exact optimum, scoring)
is :mod:`.model`; the figures and tables are :mod:`.report`, which reads saved runs only;
:mod:`.preload` loads the compiled kernel once in the process pool's fork server. See
``docs/papers/sd_assignment.md``.
"""

from __future__ import annotations

from trackfuse.experiments.base import Experiment, FigureSpec
from trackfuse.experiments.passive_sd.model import PARAMS, ROW_METRICS, run_trial

FIGURES = {
    "ghosts": FigureSpec(
        "declared tuples that are ghosts (measurements of different targets or false "
        "alarms), mean per trial with its 95 % interval, against the swept geometry or "
        "target count; one panel per other sweep value", ""),
    "found": FigureSpec(
        "targets localised by a tuple of their own measurements (fraction of all targets), "
        "mean with its 95 % interval, against the swept geometry or target count", ""),
    "duality_gap": FigureSpec(
        "distribution of the Lagrangian relaxation's relative duality gap per trial "
        "(empirical CDF), one curve per target count, one panel per value of the other "
        "swept keys (geometry pooled), with the configured stopping gap", ""),
}

EXPERIMENT = Experiment(
    name="passive_sd",
    title="S-D assignment of S passive sensors (Lagrangian relaxation) vs two sensors",
    params=PARAMS,
    run_trial=run_trial,
    metrics=ROW_METRICS,
    report="trackfuse.experiments.passive_sd.report",
    figures=FIGURES,
    row_keys=("algorithm",),
    batch_size=25,
    preload=("trackfuse.experiments.passive_sd.preload",),
)

__all__ = ["EXPERIMENT", "FIGURES"]
