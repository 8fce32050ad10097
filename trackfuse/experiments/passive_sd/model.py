"""Experiment ``passive_sd``: S-D assignment of ``sensors.n`` >= 2 passive sensors in one scan,
solved by ``sd_lagrangian``, ``sd_exact`` (integer program, the reference) and ``exact_2d``
(sensors 1 and 2 alone). Scene, metrics and streams: ``docs/papers/sd_assignment.md``,
"Experiment passive_sd".

Streams: ``truth, noise, shuffle`` are the first three children of the common stream (as in
``passive_assoc``); false alarms come from the point stream in sensor order, sensor 3's
scaled to its field of view (``sensor3.baseline`` is ``draws=False``)."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from trackfuse.association.assignment import COSTS, solve_exact
from trackfuse.association.passive_scene import (
    KM,
    PAPER_BOX,
    SENSORS,
    scene_targets,
    simulate_scan,
)
from trackfuse.experiments.base import FRACTION, NON_NEGATIVE, Metric, Param
from trackfuse.seeding import TrialStreams

ALGORITHMS = ("sd_lagrangian", "sd_exact", "exact_2d")
#: Choices of ``assoc.position`` (module docstring).
POSITIONS = ("fitted", "marginal")
#: Volume (m^3) of the box the targets are drawn in: the position prior of the marginal cost.
PRIOR_VOLUME = float(np.prod(PAPER_BOX[1] - PAPER_BOX[0]))
#: Relative tolerance of ``at_opt``; a Lagrangian primal below the exact optimum by more is
#: :class:`ExactSolverError`.
AT_OPT_RTOL = 1e-9
#: Position (km) of sensor 4, used when ``sensors.n`` is 4.
SENSOR4_KM = (20.0, 20.0, 0.0)


class ExactSolverError(RuntimeError):
    """The Lagrangian relaxation found a feasible solution cheaper than the "exact"
    optimum: the integer program returned a poorer solution than the optimum."""


PARAMS = (
    Param("targets.n", 10, "number of targets, uniform in the box of paper 002's M1-M10",
          "count", kind=int, low=1, high=40, label="targets", symbol="N"),
    Param("sensors.n", 3, "number of sensors S of the S-D assignment (S1, S2 of paper 002, "
          "then S3, S4)", kind=int, choices=(2, 3, 4), label="sensors", symbol="S"),
    Param("sensor3.baseline", 20.0, "x coordinate of sensor 3 at (x, 0, 0): its distance "
          "from sensor 1", "km", low=0.001, high=100.0, draws=False,
          label="sensor 3 baseline"),
    Param("noise.sigma", 0.005, "angle noise standard deviation (azimuth and elevation, "
          "every sensor)", "rad", low=1e-7, high=1.0, draws=False, label="angle noise",
          symbol="σ"),
    Param("sensor.p_d", 0.95, "detection probability of each sensor", "1", low=1e-3,
          high=1.0, draws=False, label="detection probability", symbol="$P_D$"),
    Param("clutter.p_f", 0.05, "false alarms per sensor: Poisson(p_f N) or Binomial(N, p_f)",
          "1", low=0.0, high=1.0, label="false-alarm rate", symbol="$p_f$"),
    Param("clutter.model", "poisson", "false-alarm count model", kind=str,
          choices=("poisson", "binomial")),
    Param("clutter.margin", 0.1, "FOV box margin around the true target angles", "rad",
          low=0.0, high=1.0),
    Param("assoc.p_f", 0.05, "the false-measurement likelihood p_f of the 'paper' cost",
          "1", low=1e-12, high=1.0, draws=False),
    Param("assoc.cost", "paper", "tuple cost: paper 002's weights or Pattipati's "
          "FOV-normalised likelihood ratio, with the missed-detection term", kind=str,
          choices=COSTS, draws=False),
    Param("assoc.position", "fitted", "target position in the tuple likelihood: fitted "
          "(generalised ratio, paper 002's at two sensors) or integrated over the box the "
          "targets are drawn in (marginal ratio)", kind=str, choices=POSITIONS, draws=False,
          label="target position", words=(("fitted", "position fitted"),
                                          ("marginal", "position integrated out"))),
    Param("algorithms", list(ALGORITHMS), "solvers reported per trial", kind=list,
          choices=ALGORITHMS, draws=False),
    Param("sd.max_gap", 0.01, "relative duality gap at which the relaxation stops", "1",
          low=0.0, high=1.0, draws=False),
    Param("sd.max_iter", 100, "iteration limit of the relaxation", "count", kind=int,
          low=1, high=100_000, draws=False),
)


def sensor_positions(params: dict[str, Any]) -> np.ndarray:
    """(S, 3) sensor positions in m (module docstring)."""
    third = np.array([[float(params["sensor3.baseline"]) * KM, 0.0, 0.0]])
    every = np.vstack([SENSORS, third, np.array([SENSOR4_KM]) * KM])
    return every[:int(params["sensors.n"])]


def prior_volume(params: dict[str, Any]) -> float | None:
    """The position prior's volume (m^3) for ``assoc.position: marginal``, else None."""
    return PRIOR_VOLUME if params["assoc.position"] == "marginal" else None


def _true_tuple(labels: tuple[np.ndarray, ...]) -> dict[tuple[int, int], frozenset]:
    """The true tuple (a set of ``(sensor, index)``, index from 1) of every measurement."""
    by_target: dict[int, set] = {}
    for s, lab in enumerate(labels):
        for i, t in enumerate(lab):
            if t >= 0:
                by_target.setdefault(int(t), set()).add((s, i + 1))
    truth = {}
    for s, lab in enumerate(labels):
        for i, t in enumerate(lab):
            group = by_target.get(int(t), set())
            truth[(s, i + 1)] = frozenset(group if t >= 0 and len(group) >= 2
                                          else {(s, i + 1)})
    return truth


def score(tuples: np.ndarray, labels: tuple[np.ndarray, ...], n_targets: int
          ) -> dict[str, float]:
    """Accuracy, ghosts and found targets of a partition ``tuples`` (K, S) given the target
    ``labels`` (one (m_s,) array per sensor, -1 for a false alarm)."""
    truth = _true_tuple(labels)
    hits, ghosts, declared, found = 0, 0, 0, set()
    for row in tuples:
        members = frozenset((s, int(i)) for s, i in enumerate(row) if i > 0)
        hits += sum(truth[m] == members for m in members)
        if len(members) < 2:
            continue
        declared += 1
        targets = {int(labels[s][i - 1]) for s, i in members}
        if len(targets) == 1 and -1 not in targets:
            found |= targets
        else:
            ghosts += 1
    n_meas = len(truth)
    return {"accuracy": hits / n_meas if n_meas else 1.0, "correct": int(hits == n_meas),
            "ghost_rate": ghosts / declared if declared else 0.0, "ghosts": ghosts,
            "found": len(found) / n_targets, "tuples": declared}


def _exact_2d(scan, params: dict[str, Any], sigma: float) -> tuple[np.ndarray, float]:
    """Sensors 1 and 2 alone, solved exactly: tuples (K, 2) and the objective."""
    from trackfuse.association.sd_costs import tuple_costs  # numba: on use

    cost = tuple_costs(scan.z[:2], scan.sensors[:2], sigma, sigma, params["sensor.p_d"],
                       params["assoc.p_f"], params["assoc.cost"], scan.psi[:2],
                       prior_volume(params))
    match = solve_exact(-cost[1:, 1:])
    rows = np.stack([np.arange(1, cost.shape[0]), match.partner1 + 1], 1)
    alone = np.flatnonzero(match.partner2 < 0) + 1
    rows = np.concatenate([rows, np.stack([np.zeros(len(alone), int), alone], 1)])
    return rows.reshape(-1, 2), match.objective


def run_trial(params: dict[str, Any], streams: TrialStreams) -> list[dict[str, Any]]:
    """One scan of S sensors: simulate, cost the tuples, solve by each algorithm."""
    from trackfuse.association.sd_assignment import solve_sd, solve_sd_exact  # numba: on use
    from trackfuse.association.sd_costs import tuple_costs

    truth, noise, shuffle = streams.common.spawn(3)
    sigma, n = float(params["noise.sigma"]), int(params["targets.n"])
    targets = scene_targets(n, "random", truth)
    scan = simulate_scan(targets, sigma, sigma, params["sensor.p_d"], params["clutter.p_f"],
                         noise, streams.point, shuffle, clutter=params["clutter.model"],
                         margin=params["clutter.margin"], sensors=sensor_positions(params))
    wanted = params["algorithms"]
    start = time.perf_counter()
    cost = tuple_costs(scan.z, scan.sensors, sigma, sigma, params["sensor.p_d"],
                       params["assoc.p_f"], params["assoc.cost"], scan.psi,
                       prior_volume(params))
    costs_time = time.perf_counter() - start
    solved = {}
    for name in ("sd_exact", "sd_lagrangian"):  # the optimum first: at_opt needs it
        if name in wanted or (name == "sd_exact" and "sd_lagrangian" in wanted):
            start = time.perf_counter()
            result = solve_sd_exact(cost) if name == "sd_exact" else solve_sd(
                cost, float(params["sd.max_gap"]), int(params["sd.max_iter"]))
            solved[name] = (result, time.perf_counter() - start)
    rows = [_sd_row(name, *solved[name], solved["sd_exact"][0].primal, scan, n, costs_time)
            for name in ALGORITHMS if name in wanted and name in solved]
    if "exact_2d" in wanted:
        start = time.perf_counter()
        tuples, objective = _exact_2d(scan, params, sigma)
        elapsed = time.perf_counter() - start
        rows.append({"algorithm": "exact_2d", **score(tuples, scan.labels[:2], n),
                     "objective": objective, "duality_gap": 0.0, "at_opt": np.nan,
                     "iterations": 0, "solve_time_s": elapsed, "costs_time_s": costs_time})
    return rows


def _sd_row(name: str, result, elapsed: float, optimum: float, scan, n: int,
            costs_time: float) -> dict[str, Any]:
    """The row of an S-D solver; :class:`ExactSolverError` when it beats the ``optimum`` (nats)."""
    tol = AT_OPT_RTOL * max(1.0, abs(optimum))
    if result.primal < optimum - tol:
        raise ExactSolverError(f"{name} reached the cost {result.primal!r}, below the "
                               f"integer program's optimum {optimum!r}")
    return {"algorithm": name, **score(result.tuples, scan.labels, n),
            "objective": -result.primal, "duality_gap": result.gap,
            "at_opt": int(result.primal <= optimum + tol), "iterations": result.iterations,
            "solve_time_s": elapsed, "costs_time_s": costs_time}


ROW_METRICS = (
    Metric("accuracy", "1", "measurements put in their true tuple", better="higher",
           bounds=FRACTION, label="correct association rate"),
    Metric("correct", "1", "the whole partition is right", binary=True, better="higher"),
    Metric("ghost_rate", "1", "declared tuples whose measurements are not all from one "
           "target", better="lower", bounds=FRACTION, label="ghost tuples"),
    Metric("ghosts", "tuples", "declared tuples not all from one target", better="lower",
           bounds=NON_NEGATIVE),
    Metric("found", "1", "targets localised by a tuple of their own measurements",
           better="higher", bounds=FRACTION, label="targets found"),
    Metric("tuples", "tuples", "declared tuples (two or more measurements)",
           bounds=NON_NEGATIVE),
    Metric("objective", "nat", "minus the summed tuple cost (log-likelihood ratio)"),
    Metric("duality_gap", "1", "relative duality gap (primal - dual) / max(|primal|, 1)",
           better="lower", bounds=NON_NEGATIVE, label="relative duality gap"),
    Metric("at_opt", "1", "the solution reaches the exact S-D optimum", binary=True,
           better="higher"),
    Metric("iterations", "count", "relaxed problems solved", bounds=NON_NEGATIVE),
    Metric("solve_time_s", "s", "wall seconds of the solver", label="solve time"),
    Metric("costs_time_s", "s", "wall seconds of the tuple costs"),
)
"""Every metric column of the rows (see the module docstring)."""

__all__ = ["ALGORITHMS", "PARAMS", "ROW_METRICS", "run_trial", "score", "sensor_positions"]
