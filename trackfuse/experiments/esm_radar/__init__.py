"""Paper 001: ESM-to-radar track association by improved fuzzy evaluation (``esm_radar``).

The science (scenario, TDOA-DF, manoeuvre index, fuzzy evaluation, references) is
:mod:`.model`; the figures and tables are :mod:`.report`, which reads saved runs only. See
``docs/papers/esm_radar.md``.
"""

from __future__ import annotations

from trackfuse.experiments.base import Experiment, FigureSpec
from trackfuse.experiments.esm_radar.model import PARAMS, ROW_METRICS, run_batch, run_trial

FIGURES = {
    "correct_rate": FigureSpec(
        "correct-association rate per algorithm with 95 % Wilson bands against the swept "
        "axis (bars per algorithm when nothing numeric is swept)", "Figs. 3-4, Table 3"),
    "trajectory": FigureSpec(
        "true tracks and the ESM TDOA-DF location track of one trial, and the manoeuvre "
        "index and range weight of the improved algorithm per scan", "Figs. 1-2"),
    "manoeuvre": FigureSpec(
        "mean manoeuvre index against time with and without the snake, for the default "
        "detector and the paper's literal index, 95 % t bands", ""),
}

EXPERIMENT = Experiment(
    name="esm_radar",
    title="Paper 001: ESM-to-radar track association (improved fuzzy evaluation)",
    params=PARAMS,
    run_trial=run_trial,
    run_batch=run_batch,
    metrics=ROW_METRICS,
    report="trackfuse.experiments.esm_radar.report",
    figures=FIGURES,
    row_keys=("algorithm",),
    batch_size=100,
)

__all__ = ["EXPERIMENT", "FIGURES"]
