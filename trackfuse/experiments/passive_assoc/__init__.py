"""Paper 002: two-sensor passive association by an improved partheno-genetic algorithm
(``passive_assoc``).

Science in :mod:`.model`, figures and tables in :mod:`.report`
(``docs/papers/passive_assoc.md``)."""

from __future__ import annotations

from trackfuse.experiments.base import Experiment, FigureSpec
from trackfuse.experiments.passive_assoc.checks import config_problem
from trackfuse.experiments.passive_assoc.model import PARAMS, ROW_METRICS, run_trial
from trackfuse.reportkit.looks import BLACK, BLUE, GREEN, GREYS, PURPLE, VERMILLION, Look
from trackfuse.reportkit.spec import Plot, Reference

#: The PGA variants drawn in the figures (the ablations appear only in the tables).
FIGURE_VARIANTS = ("pga_paper", "pga_repair", "pga_evict", "pga_anneal")

LOOKS = {
    "pga_paper": Look("PGA (paper)", VERMILLION, "s", "paper"),
    "pga_evict": Look("PGA + evicting re-pair (ours)", GREEN, "o", "ours"),
    "pga_anneal": Look("ours + annealing", PURPLE, "D", "ours"),
    "pga_repair": Look("PGA + re-pair", BLUE, "^"),
    "pga_repair_joint": Look("PGA + re-pair, joint", GREYS[1], "<"),
    "pga_staged": Look("PGA, staged", GREYS[2], ">"),
    "exact": Look("exact optimum", BLACK, "", "reference"),
}

_EXACT = Reference(algorithm="exact")
FIGURES = {
    "convergence": FigureSpec(
        "Correct association rate (mean over runs, 95 % Student-t bands) against the number "
        "of genetic operations for the paper's PGA, the PGA with re-pair and our two "
        "variants; dashed: the exact optimum with its interval in grey; one panel per sweep "
        "point. Each variant starts from its own random individual, so at 0 operations the "
        "curves differ by chance alone", "Fig. 2",
        Plot(("accuracy",), "ops", FIGURE_VARIANTS, (_EXACT,), columns="targets.n")),
    "at_optimum": FigureSpec(
        "Runs whose PGA solution reaches the exact optimum J* (%, 95 % Wilson bands) against "
        "the number of genetic operations, one panel per sweep point", "",
        Plot(("at_opt",), "ops", FIGURE_VARIANTS, columns="targets.n")),
    "noise": FigureSpec(
        "Correct association rate (top) and whole solution correct (bottom, %) against the "
        "angle noise σ, the exact optimum and each PGA variant at its last checkpoint, 95 % "
        "bands; dotted verticals: σ = 0.005 rad and √0.005 rad, the paper's noise figure "
        "read as a standard deviation or as a variance (drawn when noise.sigma is swept)", "",
        Plot(("accuracy", "correct"), "noise.sigma", ("exact", *FIGURE_VARIANTS),
             (Reference(x=(0.005, 0.005 ** 0.5)),), at={"ops": "last"})),
    "scale": FigureSpec(
        "Mean solve time per scan (log axis; on the machine named in the run's provenance), "
        "mean objective gap J* − J (symlog, linear below 1 nat) and correct association rate "
        "against the number of targets, at each algorithm's last checkpoint, 95 % t "
        "intervals (drawn when targets.n alone is swept); the paper's scenes M1-MN as "
        "unjoined categories, random scenes as curves", "",
        Plot(("solve_time_s", "gap", "accuracy"), "targets.n", ("exact", *FIGURE_VARIANTS),
             at={"ops": "last"}, yscale={"solve_time_s": "log", "gap": "symlog"},
             width="single", panel_height=1.8)),
}

EXPERIMENT = Experiment(
    name="passive_assoc",
    title="Paper 002: two-sensor passive association, improved PGA vs the exact optimum",
    params=PARAMS,
    run_trial=run_trial,
    metrics=ROW_METRICS,
    report="trackfuse.experiments.passive_assoc.report",
    figures=FIGURES,
    row_keys=("algorithm", "ops"),
    batch_size=25,
    preload=("trackfuse.experiments.passive_assoc.preload",),
    check=config_problem,
    looks=LOOKS,
    row_labels={"ops": ("genetic operations", "count")},
)

__all__ = ["EXPERIMENT", "FIGURES", "FIGURE_VARIANTS", "LOOKS"]
