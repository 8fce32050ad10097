"""Figures and tables of ``passive_sd`` runs from the saved CSVs: the declared plots of
:data:`~trackfuse.experiments.passive_sd.FIGURES` at the run's x (:func:`x_key`), and the
tables ``final`` and ``versus_exact`` (``docs/papers/sd_assignment.md``, "Experiment
passive_sd")."""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import replace
from typing import Any

import pandas as pd
from matplotlib.figure import Figure

from trackfuse.experiments.passive_sd import FIGURES
from trackfuse.reportkit import render
from trackfuse.reportkit.spec import Reference
from trackfuse.rundata import RunData, succeeded_rows, swept_keys

#: Swept keys a figure can take as its x axis, in order of preference.
X_KEYS = ("sensor3.baseline", "targets.n", "noise.sigma", "clutter.p_f", "sensor.p_d")


def x_key(config: dict[str, Any]) -> str | None:
    """The x of every figure: the first key of :data:`X_KEYS` swept over 2 values or more."""
    sweep = config.get("sweep") or {}
    return next((k for k in X_KEYS if len(sweep.get(k, ())) >= 2), None)


def figures(run: RunData, wanted: Collection[str]) -> dict[str, Figure | str]:
    """The ``wanted`` figures at the run's x, the stopping gap dotted on ``duality_gap``; a
    one-line reason for one not drawn."""
    x = x_key(run.config)
    out: dict[str, Figure | str] = {}
    for name in (n for n in FIGURES if n in wanted):
        plot = FIGURES[name].plot
        if x is None:
            out[name] = f"needs one of {', '.join(X_KEYS)} swept (the x axis)"
            continue
        if name == "duality_gap":
            plot = replace(plot, references=(
                Reference(y=float(run.params["sd.max_gap"]), label="stopping gap"),))
        out[name] = render.draw(run, replace(plot, x=x))
    return out


def versus_exact(trials: pd.DataFrame, config: dict[str, Any]) -> pd.DataFrame:
    """Per point: the relaxation's trials at the exact optimum, its duality gaps and iterations."""
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


__all__ = ["figures", "tables", "versus_exact", "x_key"]
