"""Experiment ``passive_assoc``: paper 002, two-sensor passive association. One trial is one
scan: the exact dummy-augmented assignment (``exact``, ``ops = 0``) and each PGA variant of
:data:`VARIANTS` on the same weights, one row per checkpoint; ``gap`` and ``at_opt`` are
against that trial's ``J*``. Model and metrics: ``docs/papers/passive_assoc.md``.

Streams: ``truth, noise, shuffle, algo`` are children of the common stream, false alarms come
from the point stream; each variant takes a fixed child of ``algo`` by its position in
:data:`VARIANTS` (append new ones at the end), so the algorithm list changes no other number."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from trackfuse.association.assignment import COSTS, EXACT, pair_weights, solve_exact
from trackfuse.association.passive_scene import scene_targets, simulate_scan, true_partners
from trackfuse.association.pga import CHECKPOINTS
from trackfuse.experiments.base import FRACTION, NON_NEGATIVE, Metric, Param
from trackfuse.seeding import TrialStreams

#: PGA variants: name -> options of :func:`trackfuse.association.pga.pga`.
VARIANTS = {
    "pga_paper": {"repair_moves": False, "staged": False, "accept": "monotone"},
    "pga_repair": {"repair_moves": True, "staged": True, "accept": "monotone"},
    "pga_evict": {"repair_moves": True, "staged": True, "evict": True, "accept": "monotone"},
    "pga_anneal": {"repair_moves": True, "staged": True, "evict": True, "accept": "anneal"},
    "pga_repair_joint": {"repair_moves": True, "staged": False, "accept": "monotone"},
    "pga_staged": {"repair_moves": False, "staged": True, "accept": "monotone"},
}
ALGORITHMS = ("exact", *VARIANTS)
#: Relative tolerance of ``at_opt``: ``|J* - J| <= AT_OPT_RTOL max(1, |J*|)``; a ``J`` above
#: ``J*`` by more is :class:`ExactSolverError`.
AT_OPT_RTOL = 1e-9


class ExactSolverError(RuntimeError):
    """A PGA assignment beat the "exact" optimum ``J*`` by more than the rounding tolerance:
    the exact solver returned a poorer assignment than the optimum."""


PARAMS = (
    Param("scene.mode", "paper", "target set: the paper's M1..Mn, or n uniform in their box",
          kind=str, choices=("paper", "random"), label="targets",
          words=(("paper", "paper's M1-MN"), ("random", "random targets"))),
    Param("targets.n", 10, "number of targets (paper scene: first n of M1-M10)", "count", kind=int,
          low=1, high=2000, label="targets", symbol="N"),
    Param("noise.sigma", 0.005, "the paper's angle-error figure (azimuth and elevation, both "
          "sensors), read as a standard deviation or a variance per noise.reading", "rad", low=1e-7,
          high=1.0, draws=False, label="angle noise", symbol="σ"),
    Param("noise.reading", "std", "reading of noise.sigma: 'std' (sigma = value) or "
          "'variance' (sigma = sqrt(value), in rad^2)", kind=str, choices=("std", "variance"),
          draws=False, label="noise reading",
          words=(("std", "σ read as sd"), ("variance", "σ read as variance"))),
    Param("sensor.p_d", 0.95, "detection probability of each sensor", "1", low=1e-3, high=1.0,
          draws=False, label="detection probability", symbol="$P_D$"),
    Param("clutter.p_f", 0.05, "false alarms per sensor: Poisson(p_f N) or Binomial(N, p_f)", "1",
          low=0.0, high=1.0, label="false-alarm rate", symbol="$p_f$"),
    Param("clutter.model", "poisson", "false-alarm count model", kind=str,
          choices=("poisson", "binomial")),
    Param("clutter.margin", 0.1, "FOV box margin around the true target angles", "rad", low=0.0,
          high=1.0),
    Param("assoc.p_f", 0.05, "the paper's false-measurement likelihood p_f in a_i0 = ln p_f "
          "(cost 'paper' only)", "1", low=1e-12, high=1.0, draws=False),
    Param("assoc.tri", "unit_normal", "triangulation of a candidate pair", kind=str,
          choices=("paper", "unit_normal", "wls", "ml"), draws=False),
    Param("assoc.cost", "paper", "assignment weights: the paper's (sign-corrected, with the "
          "Gaussian normalising term), its eq. 17 as printed (without it), or Pattipati's "
          "FOV-normalised likelihood ratio", kind=str, choices=COSTS, draws=False),
    Param("assoc.exact", "lsa_clip", "exact solver for the reference optimum", kind=str,
          choices=EXACT, draws=False),
    Param("algorithms", ["exact", "pga_paper", "pga_evict"], "solvers reported per trial",
          kind=list, choices=ALGORITHMS, draws=False),
    Param("pga.ops", 1000, "genetic operations per PGA run", "count", kind=int, low=0, high=10**7,
          draws=False, label="genetic operations"),
    Param("pga.checkpoints", list(CHECKPOINTS), "operation counts at which the best "
          "solution is scored (values above pga.ops are ignored; pga.ops itself is always "
          "scored)", "count", kind=list, item_kind=int, low=0, high=10**7, draws=False),
    Param("pga.p_m", 0.2, "mutation probability per genetic operation", "1", low=0.0, high=1.0,
          draws=False, label="mutation probability", symbol="$p_m$"),
    Param("pga.init", "random_B", "initial individual: random injection or identity "
          "(paper eq. 31)", kind=str, choices=("random_B", "standard"), draws=False),
    Param("pga.roulette", "worse", "roulette direction: badly placed columns swapped more "
          "often ('worse') or well placed ones ('better')", kind=str, choices=("worse", "better"),
          draws=False),
    Param("pga.second", "roulette", "second crossover column: roulette over the rest or "
          "uniform", kind=str, choices=("roulette", "uniform"), draws=False),
    Param("pga.t0", 2.0, "initial annealing temperature (pga_anneal)", "nat", low=1e-9, high=1e6,
          draws=False),
    Param("pga.t1", 0.01, "final annealing temperature (pga_anneal)", "nat", low=1e-9, high=1e6,
          draws=False),
)


def sigma_of(params: dict[str, Any]) -> float:
    """Angle noise standard deviation (rad) under the configured reading of the paper."""
    value = float(params["noise.sigma"])
    return value if params["noise.reading"] == "std" else float(np.sqrt(value))


def score(partner1: np.ndarray, partner2: np.ndarray, truth1: np.ndarray,
          truth2: np.ndarray) -> dict[str, float]:
    """Accuracy, pair precision/recall and correctness of ``partner1``, ``partner2`` (-1: dummy)."""
    n_meas = len(partner1) + len(partner2)
    hits = int(np.sum(partner1 == truth1) + np.sum(partner2 == truth2))
    declared = int(np.sum(partner1 >= 0))
    true_pairs = int(np.sum(truth1 >= 0))
    good = int(np.sum((partner1 >= 0) & (partner1 == truth1)))
    return {
        "accuracy": hits / n_meas if n_meas else 1.0,
        "precision": good / declared if declared else 1.0,
        "recall": good / true_pairs if true_pairs else 1.0,
        "correct": int(hits == n_meas),
        "pairs": declared,
    }


def _partner2(partner1: np.ndarray, m2: int) -> np.ndarray:
    p2 = np.full(m2, -1)
    rows = np.flatnonzero(partner1 >= 0)
    p2[partner1[rows]] = rows
    return p2


def run_trial(params: dict[str, Any], streams: TrialStreams) -> list[dict[str, Any]]:
    """One scan: simulate, weigh, solve exactly and by each (compiled) PGA variant; rows per
    checkpoint."""
    import scipy.optimize  # noqa: F401 - on use, and before the exact solve is timed

    from trackfuse.association.pga_search import pga  # numba: on use

    truth, noise, shuffle, algo = streams.common.spawn(4)
    clutter = streams.point
    sigma = sigma_of(params)
    targets = scene_targets(int(params["targets.n"]), params["scene.mode"], truth)
    scan = simulate_scan(targets, sigma, sigma, params["sensor.p_d"], params["clutter.p_f"],
                         noise, clutter, shuffle, clutter=params["clutter.model"],
                         margin=params["clutter.margin"])
    truth1, truth2 = true_partners(*scan.labels)
    start = time.perf_counter()
    weights = pair_weights(*scan.z, *scan.sensors, sigma, sigma, params["sensor.p_d"],
                           params["assoc.p_f"], cost=params["assoc.cost"],
                           tri=params["assoc.tri"], psi=scan.psi)
    weights_time = time.perf_counter() - start
    gain = weights.gain
    start = time.perf_counter()
    exact = solve_exact(gain, params["assoc.exact"])
    exact_time = time.perf_counter() - start
    j_star = exact.objective
    tol = AT_OPT_RTOL * max(1.0, abs(j_star))

    def row(name: str, ops: int, partner1: np.ndarray, objective: float, elapsed: float):
        gap = j_star - objective
        if gap < -tol:  # no feasible assignment beats the optimum
            raise ExactSolverError(
                f"{name} after {ops} operations reached the objective {objective!r}, above "
                f"the optimum J* = {j_star!r} of the exact solver "
                f"{params['assoc.exact']!r}: the exact solver is wrong")
        gap = 0.0 if abs(gap) <= tol else gap  # at J*: what is left is rounding residue
        return {"algorithm": name, "ops": ops,
                **score(partner1, _partner2(partner1, gain.shape[1]), truth1, truth2),
                "at_opt": int(gap == 0.0), "gap": gap, "objective": objective,
                "solve_time_s": elapsed, "weights_time_s": weights_time}

    wanted = set(params["algorithms"])
    rows = []
    if "exact" in wanted:
        rows.append(row("exact", 0, exact.partner1, j_star, exact_time))
    variant_streams = algo.spawn(len(VARIANTS))  # one Generator per variant, listed or not
    for stream, (name, options) in zip(variant_streams, VARIANTS.items(), strict=True):
        if name not in wanted:
            continue
        result = pga(weights, stream, ops=int(params["pga.ops"]),
                              checkpoints=[int(c) for c in params["pga.checkpoints"]],
                              p_m=params["pga.p_m"], init=params["pga.init"],
                              roulette=params["pga.roulette"], second=params["pga.second"],
                              t0=params["pga.t0"], t1=params["pga.t1"], **options)
        for k, ops in enumerate(result.checkpoints.tolist()):
            rows.append(row(name, ops, result.partner1[k], float(result.objective[k]),
                            float(result.elapsed_s[k])))
    return rows



ROW_METRICS = (
    Metric("accuracy", "1", "measurement-level accuracy: measurements given their true "
           "partner (or the dummy)", better="higher", bounds=FRACTION,
           label="correct association rate"),
    Metric("precision", "1", "declared pairs that are true pairs", better="higher",
           bounds=FRACTION, label="pair precision"),
    Metric("recall", "1", "true pairs that are declared", better="higher", bounds=FRACTION,
           label="pair recall"),
    Metric("correct", "1", "the whole assignment is right", binary=True, better="higher",
           label="whole solution correct"),
    Metric("pairs", "pairs", "declared pairs", bounds=NON_NEGATIVE, label="declared pairs"),
    Metric("at_opt", "1", "the solution reaches the exact optimum J*", binary=True,
           better="higher", label="runs at the exact optimum"),
    Metric("gap", "nat", "J* - J, the objective gap to the exact optimum (log-likelihood "
           "ratio)", better="lower", bounds=NON_NEGATIVE, label="objective gap J* − J"),
    Metric("objective", "nat", "the objective J of the solution (log-likelihood ratio)",
           label="objective J"),
    Metric("solve_time_s", "s", "wall seconds of the solver", label="solve time per scan"),
    Metric("weights_time_s", "s", "wall seconds of the pair weights"),
)
"""Every metric column of the rows (see the module docstring)."""

__all__ = ["ROW_METRICS", "run_trial", "score", "sigma_of"]
