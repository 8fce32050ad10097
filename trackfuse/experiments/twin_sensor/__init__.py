"""Paper 000: airborne twin-sensor synchronous angle-only tracking (``twin_sensor``).

The science (scenario, simulation, filters, PCRLB) is :mod:`.model`; the figures and tables
are :mod:`.report`, which reads saved runs only. See ``docs/papers/twin_sensor.md``.
"""

from __future__ import annotations

from trackfuse.experiments.base import Experiment, FigureSpec
from trackfuse.experiments.twin_sensor.model import PARAMS, ROW_METRICS, run_batch, run_trial

FIGURES = {
    "loss_gate_vs_clutter": FigureSpec(
        "tracks lost (gate rule) at the last scan against the mean number of false returns, "
        "95 % Wilson bands (drawn when clutter.mean is swept)", "Fig. 1"),
    "loss_angle_vs_clutter": FigureSpec(
        "tracks lost (filter-independent angle rule) at the last scan against the mean number "
        "of false returns, 95 % Wilson bands (drawn when clutter.mean is swept)", "Fig. 1"),
    "inconsistent_nees_vs_clutter": FigureSpec(
        "filters whose final position NEES exceeds its chi-square quantile (not a loss) "
        "against clutter (drawn when clutter.mean is swept)", ""),
    "range_rmse_vs_time": FigureSpec(
        "range RMSE against time with 95 % chi-square bands beside the square-root PCRLB of "
        "the truth and filter models, one panel per sweep point", "Fig. 2"),
    "anees_vs_time": FigureSpec(
        "6-state ANEES against time with its 95 % chi-square band", ""),
    "final_range_rmse_vs_sweep": FigureSpec(
        "range RMSE at the last scan against the only swept axis beside the square-root "
        "PCRLB (drawn when exactly one numeric key is swept)", ""),
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
)

__all__ = ["EXPERIMENT", "FIGURES"]
