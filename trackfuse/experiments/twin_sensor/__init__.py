"""Paper 000: airborne twin-sensor synchronous angle-only tracking (``twin_sensor``).

The science (scenario, simulation, filters, PCRLB) is :mod:`.model`; the figures and tables
are :mod:`.report`, which reads saved runs only. See ``docs/papers/twin_sensor.md``.
"""

from __future__ import annotations

from trackfuse.experiments.base import Experiment, FigureSpec
from trackfuse.experiments.twin_sensor.checks import config_problem
from trackfuse.experiments.twin_sensor.model import PARAMS, ROW_METRICS, run_batch, run_trial

FIGURES = {
    "loss_vs_clutter": FigureSpec(
        "Fig. 1 (redrawn at the paper's scenario, else an analogue): tracks lost (angle "
        "rule: azimuth or elevation off the truth by more than 3 sigma for 3 scans) against "
        "the mean number of false returns, the paper's fused-gate PDA (reconstruction) and "
        "our corrected parallel PDA with the MGEKF, 95 % Wilson error bars, the paper's "
        "claim (< 5 % up to 9) shaded at the paper's scenario", "Fig. 1"),
    "loss_vs_clutter_ablation": FigureSpec(
        "Fig. 1 ablation: tracks lost (angle rule) against false returns for every algorithm "
        "run (EKF, sequential PDA, nearest neighbour), 95 % Wilson error bars; a curve "
        "equal to one drawn over it at every level is drawn wider around it"),
    "loss_gate_and_nees_vs_clutter": FigureSpec(
        "Diagnostic: the filter-dependent flags against false returns, tracks lost by the "
        "gate rule (target outside every gate for 3 scans) and filters whose final position "
        "NEES exceeds its chi-square quantile (inconsistent, not lost)"),
    "loss_vs_manoeuvring_index": FigureSpec(
        "Extension: tracks lost (angle and gate rules) against the manoeuvring index "
        "sqrt(q) T^2 / (r sigma) of the truth, with clutter; crosses: without clutter"),
    "range_error_vs_time": FigureSpec(
        "Fig. 2 (the paper's scenario and method, else an analogue): range RMSE "
        "against time with 95 % bands (a second filter's as dashed edges; coinciding curves "
        "show a filled marker in an open one), the square-root PCRLB of the truth and filter "
        "models, five single runs; errors are correlated across scans, so a curve below the "
        "bound at every scan is one sample of runs, not a filter beating the bound", "Fig. 2"),
    "anees_vs_time": FigureSpec(
        "Diagnostic: 6-state ANEES against time with its 95 % chi-square band (above it: "
        "overconfident; below it: conservative), every panel on one log axis"),
    "final_range_rmse_vs_sweep": FigureSpec(
        "Range RMSE at the last scan against the swept axis with 95 % bootstrap intervals "
        "beside the square-root PCRLB of the truth and filter models; every point runs the "
        "same targets and noise, so the points' errors move together; a point whose RMSE a "
        "few flagged runs carry is not joined to its neighbours"),
}

EXPERIMENT = Experiment(
    name="twin_sensor",
    title="Paper 000: twin-sensor angle-only tracking (MGEKF, fused-gate PDA) vs PCRLB",
    params=PARAMS,
    run_trial=run_trial,
    run_batch=run_batch,
    metrics=ROW_METRICS,
    report="trackfuse.experiments.twin_sensor.report",
    figures=FIGURES,
    row_keys=("algorithm", "scan"),
    batch_size=100,
    check=config_problem,
    preload=("trackfuse.experiments.twin_sensor.preload",),
)

__all__ = ["EXPERIMENT", "FIGURES"]
