"""Paper 002: two-sensor passive association by an improved partheno-genetic algorithm
(``passive_assoc``).

The science (scene, pair weights, exact and PGA solvers, scoring) is :mod:`.model`; the
figures and tables are :mod:`.report`, which reads saved runs only; :mod:`.preload` loads the
compiled PGA loop once in the process pool's fork server. See
``docs/papers/passive_assoc.md``.
"""

from __future__ import annotations

from trackfuse.experiments.base import Experiment, FigureSpec
from trackfuse.experiments.passive_assoc.checks import config_problem
from trackfuse.experiments.passive_assoc.model import PARAMS, ROW_METRICS, run_trial

FIGURES = {
    "convergence": FigureSpec(
        "measurement-level accuracy against the number of genetic operations per PGA "
        "variant, exact optimum as reference, one panel per sweep point; each variant starts "
        "from its own random individual, so at 0 operations the curves differ by chance "
        "alone", "Fig. 2"),
    "at_optimum": FigureSpec(
        "fraction of runs whose PGA solution reaches the exact optimum against the number "
        "of genetic operations, 95 % Wilson bands", ""),
    "noise": FigureSpec(
        "accuracy and whole-solution-correct rate against the angle noise (drawn when "
        "noise.sigma is swept)", ""),
    "scale": FigureSpec(
        "median solve time (ms, log axis, order-statistic interval; measured on the machine "
        "named under CPU in this run's provenance), mean objective gap "
        "(bootstrap-t interval, an open upper end drawn as an arrow) and accuracy against the "
        "number of targets (drawn when targets.n, swept over at least 2 values, is the only "
        "swept key); the paper's scenes as unjoined categories, random scenes as curves",
        ""),
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
)

__all__ = ["EXPERIMENT", "FIGURES"]
