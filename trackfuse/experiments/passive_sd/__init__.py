"""S-D assignment of three or more passive sensors beside the two-sensor exact assignment
(``passive_sd``).

Science in :mod:`.model`, figures and tables in :mod:`.report`
(``docs/papers/sd_assignment.md``)."""

from __future__ import annotations

from trackfuse.experiments.base import Experiment, FigureSpec
from trackfuse.experiments.passive_sd.model import PARAMS, ROW_METRICS, run_trial
from trackfuse.reportkit.looks import BLACK, BLUE, GREEN, Look
from trackfuse.reportkit.spec import Plot, Reference

LOOKS = {
    "sd_lagrangian": Look("S-D relaxation, all sensors", GREEN, "o", "ours"),
    "sd_exact": Look("exact S-D optimum", BLACK, "", "reference"),
    "exact_2d": Look("exact 2-D, sensors 1 and 2", BLUE, "s", "paper_baseline"),
}
#: The x of every figure is chosen per run (the report): the swept sensor-3 baseline, else
#: the swept target count (or another swept key of ``report.X_KEYS``).
_X = "sensor3.baseline"
_EXACT = Reference(algorithm="sd_exact")
_BESIDE = ("sd_lagrangian", "exact_2d")

FIGURES = {
    "accuracy": FigureSpec(
        "Measurements put in their true tuple (%, mean over trials, 95 % t bands) by the S-D "
        "Lagrangian relaxation over all sensors and by the exact two-sensor assignment of "
        "sensors 1 and 2 (paper 002's problem) on the same scans; dashed: the exact S-D "
        "optimum (integer program) with its interval in grey, where the run solved it; one "
        "panel per setting of the other swept keys", "",
        Plot(("accuracy",), _X, _BESIDE, (_EXACT,), columns="targets.n")),
    "ghosts": FigureSpec(
        "Declared tuples that are ghosts (measurements of different targets or false alarms; "
        "%, mean per trial, 95 % t bands), the same methods and layout", "",
        Plot(("ghost_rate",), _X, _BESIDE, (_EXACT,), columns="targets.n")),
    "found": FigureSpec(
        "Targets localised by a tuple of their own measurements (% of all targets, mean, "
        "95 % t bands), the same methods and layout", "",
        Plot(("found",), _X, _BESIDE, (_EXACT,), columns="targets.n")),
    "duality_gap": FigureSpec(
        "The Lagrangian relaxation's relative duality gap (primal − dual) / max(|primal|, 1) "
        "when it stops (mean over trials, 95 % t bands); dotted: the configured stopping gap "
        "of the config, which a trial misses only at its iteration limit. How "
        "often it reaches the exact optimum is the versus_exact table", "",
        Plot(("duality_gap",), _X, ("sd_lagrangian",), columns="targets.n")),
    "time": FigureSpec(
        "Wall time of each solver per scan (log axis, mean over trials, 95 % t bands; the "
        "tuple costs, shared by the S-D methods, excluded), on the machine named in the "
        "run's provenance", "",
        Plot(("solve_time_s",), _X, ("sd_lagrangian", "sd_exact", "exact_2d"),
             columns="targets.n", yscale="log")),
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
    looks=LOOKS,
)

__all__ = ["EXPERIMENT", "FIGURES", "LOOKS"]
