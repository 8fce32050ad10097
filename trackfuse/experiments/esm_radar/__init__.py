"""Paper 001: ESM-to-radar track association by improved fuzzy evaluation (``esm_radar``).

The science (scenario, TDOA-DF, manoeuvre index, fuzzy evaluation, references) is
:mod:`.model`; the figures and tables are :mod:`.report`, which reads saved runs only. See
``docs/papers/esm_radar.md``.
"""

from __future__ import annotations

from trackfuse.experiments.base import Experiment, FigureSpec
from trackfuse.experiments.esm_radar.checks import config_problem
from trackfuse.experiments.esm_radar.model import PARAMS, ROW_METRICS, run_batch, run_trial
from trackfuse.reportkit.looks import (
    BLACK,
    BLUE,
    GREEN,
    GREYS,
    ORANGE,
    PURPLE,
    VERMILLION,
    Look,
)
from trackfuse.reportkit.spec import Plot

LOOKS = {
    "improved": Look("improved fuzzy (paper)", VERMILLION, "s", "paper"),
    "traditional": Look("traditional fuzzy (paper)", BLUE, "o", "paper_baseline"),
    "improved_gauss": Look("improved, Gaussian (ours)", GREEN, "D", "ours"),
    "traditional_5f": Look("traditional, 5 factors", BLUE, "v"),
    "improved_static": Look("improved, static weights", GREYS[0], "^"),
    "improved_3f": Look("improved, 3 factors", GREYS[1], "<"),
    "improved_no_range": Look("improved, no range", GREYS[2], "P"),
    "improved_l2": Look("improved, L2 membership", GREYS[2], ">"),
    "chi2": Look("χ² ML reference", BLACK, "o", "reference", open=True),
    "chi2_lrt": Look("χ² reference, may abstain", GREYS[0], "X", "reference"),
    "chi2_5f": Look("χ², 5 factors", GREYS[1], "d", "reference", open=True),
    "counting": Look("counting test (history)", ORANGE, "v", "ours"),
    "sprt": Look("sequential test (SPRT)", PURPLE, "X", "ours"),
}
#: The x of a rate figure is chosen per run (the report): the first numeric swept key of
#: more than two values as a curve, else the first swept key as categories.
_RATE = Plot(("correct",), "target.separation", max_columns=3)

FIGURES = {
    "correct_rate": FigureSpec(
        "Correct-association rate (%) of the paper's method, its baseline and ours (those "
        "run), 95 % Wilson intervals (bands on a curve, bars in categories), against "
        "separation (Fig. 3), radar range error (Fig. 4) or the swept setting; open stars: "
        "the paper's Table 3 values at the points at its setting, right of our markers; "
        "dotted: chance (50 %)", "Table 3, Figs. 3-4", _RATE),
    "correct_rate_ablations": FigureSpec(
        "The same for the ablations of the paper's method that the config runs (each one "
        "change to it, named in the legend) beside the paper's method", "", _RATE),
    "correct_rate_references": FigureSpec(
        "The same for the chi-square maximum-likelihood references beside the paper's two "
        "methods", "", _RATE),
    "history_rates": FigureSpec(
        "Correct (top), false (middle: a wrong radar track chosen) and missed (bottom: no "
        "decision) association rates (%), 95 % Wilson intervals, of the counting test and "
        "Wald's sequential test over the track history beside the chi-square reference and "
        "the paper's fuzzy methods, same trials; dotted: the counting test's binomial design "
        "false-association rate", "",
        Plot(("correct", "wrong", "missed"), "target.separation",
             ("traditional", "improved", "chi2", "counting", "sprt"), width="single",
             panel_height=1.55)),
    "trajectory": FigureSpec(
        "True tracks and the ESM TDOA-DF location of one saved trial, its manoeuvre index "
        "and (where a dynamic-weight algorithm ran) range weight per scan, and the ESM range "
        "error per scan over all trials",
        "Figs. 1-2"),
    "manoeuvre": FigureSpec(
        "Mean manoeuvre index per scan and, where a dynamic-weight algorithm ran, the mean "
        "range weight of the paper's method (dotted: its static AHP weight), 95 % t bands, one "
        "curve per setting of the ESM track", ""),
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
    looks=LOOKS,
)

__all__ = ["EXPERIMENT", "FIGURES", "LOOKS"]
