"""Paper 001: ESM-to-radar track association by improved fuzzy evaluation (``esm_radar``).

The science (scenario, TDOA-DF, manoeuvre index, fuzzy evaluation, references) is
:mod:`.model`; the figures and tables are :mod:`.report`, which reads saved runs only. See
``docs/papers/esm_radar.md``.
"""

from __future__ import annotations

from trackfuse.experiments.base import Experiment, FigureSpec
from trackfuse.experiments.esm_radar.checks import config_problem
from trackfuse.experiments.esm_radar.model import PARAMS, ROW_METRICS, run_batch, run_trial

FIGURES = {
    "correct_rate": FigureSpec(
        "correct-association rate (%) of the paper's method, its baseline and ours (those "
        "run) with 95 % Wilson intervals, against separation (Fig. 3) or radar range error "
        "(Fig. 4), as categories for a sweep of two settings, or one row per method, beside "
        "the paper's values (open stars, just right of their setting); the titles name the "
        "radar-factor model of the rates beside the stars",
        "Table 3, Figs. 3-4"),
    "correct_rate_ablations": FigureSpec(
        "the same for the ablations of the paper's method that the config runs (each one "
        "change to it, named in the legend) beside the paper's method", ""),
    "correct_rate_references": FigureSpec(
        "the same for the chi-square maximum-likelihood references beside the paper's two "
        "methods", ""),
    "trajectory": FigureSpec(
        "true tracks and the ESM TDOA-DF location of one saved trial, its manoeuvre index "
        "and (where a dynamic-weight algorithm ran) range weight per scan, and the ESM range "
        "error per scan over all trials",
        "Figs. 1-2"),
    "manoeuvre": FigureSpec(
        "mean manoeuvre index per scan and, where a dynamic-weight algorithm ran, the mean "
        "range weight of the paper's method, 95 % t bands, one curve per setting of the ESM "
        "track", ""),
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
    check=config_problem,
)

__all__ = ["EXPERIMENT", "FIGURES"]
