"""Figures and tables of ``passive_sd`` runs, drawn from the saved CSVs only.

Figures (:data:`trackfuse.experiments.passive_sd.FIGURES`):

* ``ghosts`` and ``found``: the mean ghost rate and the fraction of targets localised, with
  their 95 % Student-t intervals (from ``summary.csv``), against the swept sensor-3
  baseline (or, without it, the swept target count), one panel per value of the other
  swept keys. The S-D methods and the two-sensor baseline share each panel's scans.
* ``duality_gap``: the empirical CDF of ``sd_lagrangian``'s relative duality gap per trial
  (``trials.csv``), one curve per target count (when swept), one panel per value of the
  other swept keys but the x axis's (the geometry is pooled), with the configured stopping
  gap.

Tables: ``final`` (every metric's mean and interval per point and algorithm) and
``versus_exact`` (per point: how often the relaxation reached the exact optimum, its mean
and largest duality gap and its mean iterations).
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from trackfuse.plots.algorithms import line_kwargs, look
from trackfuse.plots.style import band, legend_below, legend_entries, new_figure, wants_log_axis
from trackfuse.rundata import RunData, succeeded_rows, swept_keys

#: Swept keys a figure can take as its x axis, in order of preference.
X_KEYS = ("sensor3.baseline", "targets.n", "noise.sigma", "clutter.p_f", "sensor.p_d")
#: Width and height (in) of one panel.
PANEL = (2.4, 2.2)
UNITS = {"sensor3.baseline": "km", "noise.sigma": "rad"}
#: Line styles of the duality-gap curves: one algorithm's colour, one style per group.
LINE_STYLES = ("-", "--", "-.", (0, (1, 1)), (0, (5, 1, 1, 1, 1, 1)))


def _x_key(config: dict[str, Any]) -> str | None:
    swept = swept_keys(config)
    return next((k for k in X_KEYS if k in swept), None)


def label(keys: list[str], values: Any) -> str:
    """A short title for the values of swept ``keys``: a word as itself, a number as
    ``name = value`` with the key's last dotted part (``fitted, n = 5``)."""
    values = values if isinstance(values, tuple) else (values,)
    return ", ".join(str(v) if isinstance(v, str) else f"{k.split('.')[-1]} = {v}"
                     for k, v in zip(keys, values, strict=True))


def _panels(frame: pd.DataFrame, config: dict[str, Any], skip: Collection[str]
            ) -> list[tuple[str, pd.DataFrame]]:
    """``(title, rows)`` per combination of the swept keys not in ``skip``."""
    others = [k for k in swept_keys(config) if k not in skip]
    if not others:
        return [("", frame)]
    return [(label(others, values), rows)
            for values, rows in frame.groupby(others, sort=True)]


def _curve(ax: Axes, rows: pd.DataFrame, name: str, x_key: str) -> None:
    """Mean against ``x_key`` in the algorithm's look, with a band when emphasised."""
    rows = rows.sort_values(x_key)
    x = rows[x_key].to_numpy(float)
    kw = line_kwargs(name)
    if look(name).role == "reference":  # thin and dashed: on top, so a curve under it shows
        kw["zorder"] = 4
    if look(name).emphasised:
        band(ax, x, rows["mean"], rows["ci_low"], rows["ci_high"], **kw)
    else:
        ax.plot(x, rows["mean"], **kw)


def metric_figure(run: RunData, metric: str, ylabel: str) -> Figure | str:
    """``metric`` against the swept geometry or target count, one panel per other sweep
    value (module docstring); a reason string when nothing suitable is swept."""
    config = run.config
    x_key = _x_key(config)
    if x_key is None:
        return f"needs one of {', '.join(X_KEYS)} swept (the x axis)"
    summary = run.summary[run.summary["metric"] == metric]
    panels = _panels(summary, config, [x_key])
    ncols = min(3, len(panels))
    nrows = -(-len(panels) // ncols)
    fig, axes = new_figure(ncols, nrows, *PANEL)
    axes = np.atleast_1d(axes)
    for ax, (title, rows) in zip(axes, panels, strict=False):
        for name in [a for a in run.config["params"]["algorithms"] if a in set(rows.algorithm)]:
            _curve(ax, rows[rows["algorithm"] == name], name, x_key)
        if wants_log_axis(summary[x_key]):
            ax.set_xscale("log")
        unit = UNITS.get(x_key)
        ax.set_xlabel(f"{x_key} ({unit})" if unit else x_key)
        ax.set_ylabel(ylabel)
        ax.set_ylim(0.0, min(1.0, 1.1 * float(summary["ci_high"].max())) or 1.0)
        ax.set_title(title)
    for ax in axes[len(panels):]:
        ax.set_visible(False)
    legend_below(fig, *legend_entries(axes[:len(panels)]))
    return fig


def gap_figure(run: RunData) -> Figure | str:
    """Empirical CDF of ``sd_lagrangian``'s relative duality gap (module docstring)."""
    trials = succeeded_rows(run.trials)
    mine = trials[trials["algorithm"] == "sd_lagrangian"]
    if mine.empty:
        return "needs the algorithm sd_lagrangian"
    swept = swept_keys(run.config)
    curve_keys = ["targets.n"] if "targets.n" in swept else []
    panels = _panels(mine, run.config, [_x_key(run.config), *curve_keys])
    fig, axes = new_figure(len(panels), 1, 3.4, 2.8)
    axes = np.atleast_1d(axes)
    stop = 100.0 * float(run.config["params"]["sd.max_gap"])
    for ax, (title, rows) in zip(axes, panels, strict=True):
        groups = rows.groupby(curve_keys, sort=True) if curve_keys else [((), rows)]
        for k, (values, group) in enumerate(groups):
            gap = np.sort(group["duality_gap"].to_numpy(float)) * 100.0
            ax.step(np.concatenate([[0.0], gap]), np.arange(len(gap) + 1) / len(gap),
                    where="post", label=label(curve_keys, values) or "all trials",
                    color=look("sd_lagrangian").colour, linewidth=1.2,
                    linestyle=LINE_STYLES[k % len(LINE_STYLES)])
        ax.axvline(stop, color="0.4", linestyle=":", linewidth=1.0, label="stopping gap")
        ax.set_xlabel("relative duality gap per trial (%)")
        ax.set_ylabel("fraction of trials (ECDF)")
        ax.set_ylim(0.0, 1.02)
        ax.set_title(title)
    legend_below(fig, *legend_entries(axes), column_width=1.6)
    return fig


def figures(run: RunData, wanted: Collection[str]) -> dict[str, Figure | str]:
    """The ``wanted`` figures (module docstring); a one-line reason for one not drawn."""
    drawers: dict[str, Callable[[], Figure | str]] = {
        "ghosts": lambda: metric_figure(run, "ghost_rate", "ghost rate"),
        "found": lambda: metric_figure(run, "found", "targets found"),
        "duality_gap": lambda: gap_figure(run),
    }
    return {name: draw() for name, draw in drawers.items() if name in wanted}


def versus_exact(trials: pd.DataFrame, config: dict[str, Any]) -> pd.DataFrame:
    """Per point: the relaxation's trials, the fraction at the exact optimum, the mean and
    largest relative duality gap and the mean iterations."""
    mine = succeeded_rows(trials)
    mine = mine[mine["algorithm"] == "sd_lagrangian"]
    keys = ["point", *swept_keys(config)]
    return mine.groupby(keys, sort=True).agg(
        trials=("at_opt", "size"), at_opt=("at_opt", "mean"),
        mean_gap=("duality_gap", "mean"), max_gap=("duality_gap", "max"),
        mean_iterations=("iterations", "mean")).reset_index()


def tables(run: RunData) -> dict[str, pd.DataFrame | str]:
    """``final`` and ``versus_exact`` (module docstring), rounded to 4 digits."""
    paired = versus_exact(run.trials, run.config)
    return {"final": run.summary.round(4),
            "versus_exact": paired.round(4) if len(paired) else
            "needs the algorithm sd_lagrangian"}


__all__ = ["figures", "gap_figure", "metric_figure", "tables", "versus_exact"]
