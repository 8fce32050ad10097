"""Paper 000: airborne twin-sensor synchronous angle-only tracking (``twin_sensor``).

The science (scenario, simulation, filters, PCRLB) is :mod:`.model`; the figures and tables
are :mod:`.report`, which reads saved runs only. See ``docs/papers/twin_sensor.md``.
"""

from __future__ import annotations

from dataclasses import replace

from trackfuse.experiments.base import Experiment, FigureSpec
from trackfuse.experiments.twin_sensor.checks import config_problem
from trackfuse.experiments.twin_sensor.model import PARAMS, ROW_METRICS, run_batch, run_trial
from trackfuse.reportkit.looks import (
    BLUE,
    GREEN,
    GREYS,
    ORANGE,
    PURPLE,
    SKY,
    VERMILLION,
    WINE,
    Look,
)
from trackfuse.reportkit.spec import Plot, Reference

_ASSOCIATIONS = {
    "paper_approx": Look("paper's fused-gate PDA", VERMILLION, "s", "paper"),
    "mspda_parallel": Look("parallel PDA (corrected)", GREEN, "o", "ours"),
    "mspda_sequential": Look("sequential PDA", BLUE, "^"),
    "nn": Look("nearest neighbour", GREYS[0], "h"),
    "ipda": Look("IPDA (parallel, with existence)", PURPLE, "*", "ours"),
}
#: Every association with each filter: the MGEKF solid, the EKF dashed with open markers.
LOOKS = {
    **{f"{name}/mgekf": replace(look, label=f"{look.label}, MGEKF")
       for name, look in _ASSOCIATIONS.items()},
    **{f"{name}/ekf": replace(look, label=f"{look.label}, EKF", open=True, dashed=True)
       for name, look in _ASSOCIATIONS.items()},
    "stonesoup_pda/ekf": Look("Stone Soup EKF + PDA", SKY, "v", "paper_baseline"),
    "stonesoup_pda/ukf": Look("Stone Soup UKF + PDA", ORANGE, "D", "paper_baseline"),
    "stonesoup_pda/pf": Look("Stone Soup particle filter + PDA", WINE, "P", "paper_baseline"),
}
#: Paper 000's Fig. 1 as the report kit draws it: tracks lost (angle rule, last scan)
#: against clutter, the paper's pair, the paper's claim shaded.
FIG1 = Plot(("lost_angle",), "clutter.mean", ("paper_approx/mgekf", "mspda_parallel/mgekf"),
            (Reference(band=(0.0, 0.05), label="paper: < 5 % up to 9", until=9.0),),
            at={"scan": "last"})

FIGURES = {
    "loss_vs_clutter": FigureSpec(
        "Fig. 1 (redrawn at the paper's scenario, else an analogue): tracks lost (angle rule: "
        "azimuth or elevation off by more than 3 sigma for 3 scans) against the mean number "
        "of false returns, the paper's fused-gate PDA (reconstruction) and our corrected "
        "parallel PDA, MGEKF, 95 % Wilson intervals shaded; grey: the paper's claim (below "
        "5 % up to 9); a curve equal to another is drawn a little to its right", "Fig. 1"),
    "loss_vs_clutter_ablation": FigureSpec(
        "Fig. 1 ablation: tracks lost (angle rule) against false returns for every algorithm "
        "run (EKF, sequential PDA, nearest neighbour; of more than six, the MGEKF ones: the "
        "EKF's are beside them in Fig. 2), 95 % Wilson intervals shaded for the paper's "
        "method and ours; a curve equal to another at every level is drawn a little to its "
        "right"),
    "existence_vs_clutter": FigureSpec(
        "Track existence: at the last scan against the mean number of false returns, tracks "
        "lost by the angle rule (every algorithm), IPDA's tracks terminated (existence below "
        "ipda.terminate at some scan, while the target exists throughout) and confirmed "
        "(existence reached ipda.confirm first), 95 % Wilson intervals", "",
        Plot(("lost_angle", "lost_existence", "confirmed"), "clutter.mean",
             at={"scan": "last"}, xscale="linear")),
    "loss_gate_and_nees_vs_clutter": FigureSpec(
        "Diagnostic: the filter-dependent flags against false returns, a row each: tracks "
        "lost by the gate rule (target outside every gate for 3 scans) and filters whose "
        "final position NEES exceeds its chi-square quantile (inconsistent, not lost)"),
    "loss_vs_manoeuvring_index": FigureSpec(
        "Extension: tracks lost (angle and gate rules) against the truth's process noise q "
        "(the filter's q equal to it; the manoeuvring index √q T²/(rσ) grows with √q) at "
        "the run's one clutter level; symmetric-log axis, linear below the first q > 0"),
    "range_error_vs_time": FigureSpec(
        "Fig. 2 (the paper's scenario and method, else an analogue): range RMSE against the "
        "scan, 95 % intervals shaded (Student-t of the mean squared error, square-rooted), "
        "the √PCRLB of the truth model (dashed) and of the filter's q (dotted; dash-dot where "
        "they agree); errors are correlated across scans, so a curve below the bound at every "
        "scan is one sample of runs, not a filter beating it", "Fig. 2"),
    "anees_vs_time": FigureSpec(
        "Diagnostic: 6-state ANEES against the scan, log axis, with the 95 % chi-square band "
        "of a consistent filter's ANEES shaded grey (above it: overconfident; below it: "
        "conservative); the panels of Fig. 2"),
    "final_range_rmse_vs_sweep": FigureSpec(
        "Range RMSE at the last scan against the swept axis with 95 % intervals (Student-t "
        "of the mean squared error, square-rooted; the final_scan table gives bootstrap-t "
        "ones) beside the √PCRLB of the truth and filter models; every point runs the same "
        "targets and noise, so the points' errors move together"),
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
    looks=LOOKS,
    row_labels={"scan": ("scan", "count")},
)

__all__ = ["EXPERIMENT", "FIG1", "FIGURES", "LOOKS"]
