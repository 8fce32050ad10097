"""Paper 000: airborne twin-sensor synchronous angle-only tracking (MGEKF + fused-gate PDA).

Reproduces and extends Wang, Wang & Yang, "Fusion algorithm for airborne twin-sensor
synchronous angle-only tracking", Control and Decision 20(10), 2005. A target is observed
for ``scan.count`` scans by one or two az/el sensors on an orbiting platform, with Poisson
clutter ``in_gate`` (mapped into each filter's own gate from common draws, so comparisons
stay paired) or in a fixed ``window``. Every algorithm starts from the same
``x0 ~ N(x_true(0), P0)``; adding one never changes the simulated data. Everything is drawn
from the trial's common stream, and clutter is nested across levels (:mod:`.clutter`: a
lower level's returns are a subset of a higher level's).

Rows: ``row_keys = ("algorithm", "scan")``, one row per algorithm and scan ``k = 1..K`` with
:data:`METRICS` (and :data:`EXISTENCE_METRICS` for IPDA); CPU time per batch goes to
``timings.csv``. Model, metrics, loss rules and the defaults the paper leaves open:
``docs/papers/twin_sensor.md``. Figures and tables: :mod:`.report`.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property, lru_cache
from itertools import product
from typing import Any

import numpy as np

from trackfuse.chi2 import chi2_quantile
from trackfuse.experiments.base import FRACTION, NON_NEGATIVE, Metric, Param
from trackfuse.experiments.twin_sensor.stonesoup import (
    STONESOUP_ALGORITHMS,
    STONESOUP_PARAMS,
    is_stonesoup,
    run_stonesoup,
)
from trackfuse.rowtable import RowTable
from trackfuse.seeding import TrialStreams
from trackfuse.spawned_streams import spawn_shared
from trackfuse.tracking.initialization import los_prior_covariance, range_cue_sd
from trackfuse.tracking.ipda_options import ExistenceModel, track_decisions
from trackfuse.tracking.models import cv_process_noise, cv_transition, wrap
from trackfuse.tracking.pcrlb import (
    information_recursion,
    irf_q2_interp,
    measurement_information,
    position_bound,
    range_bound,
)
from trackfuse.tracking.pda_options import METHODS, Estimates, PDAOptions
from trackfuse.tracking.platforms import baseline_offset, orbit_positions, straight_positions
from trackfuse.tracking.sensors import (
    azel,
    azel_jacobian,
    gate_threshold,
    gate_volume,
)

FILTERS = {"mgekf": "mgekf", "ekf": "ekf_joseph"}
MAX_SENSORS = 2
ALGORITHMS = tuple(f"{a}/{f}" for a, f in product(METHODS, FILTERS))
#: Integrated PDA (track existence beside the parallel PDA's estimate), with each filter;
#: not in the default list (``docs/papers/twin_sensor.md``, Track existence).
IPDA_ALGORITHMS = tuple(f"ipda/{f}" for f in FILTERS)

PARAMS = (
    Param("scan.period", 1.0, "Sampling period T", "s", low=1e-3, high=100.0),
    Param("scan.count", 20, "Number of scans after initialization at t = 0", "scans", kind=int,
          low=1, high=1000),
    Param("target.position", [0.0, 128558.0, 4000.0], "True target position at t = 0 (x, y, z)",
          "m", kind=list, length=3, low=-1e7, high=1e7),
    Param("target.velocity", [0.0, 0.0, 0.0], "True target velocity at t = 0 (x, y, z)", "m/s",
          kind=list, length=3, low=-1e4, high=1e4),
    Param("target.q", 0.0, "Truth process-noise acceleration variance (0 = stationary or exact "
          "CV truth)", "m^2/s^4", low=0.0, high=1e6, label="truth process noise q",
          symbol="q"),
    Param("platform.motion", "orbit", "Platform trajectory of sensor 1", kind=str,
          choices=("orbit", "straight")),
    Param("platform.start", [153209.0, 0.0, 2000.0], "Platform position at t = 0 (x, y, z)", "m",
          kind=list, length=3, low=-1e7, high=1e7),
    Param("platform.speed", 500.0, "Horizontal platform speed", "m/s", low=0.0, high=5000.0),
    Param("platform.climb", 50.0, "Vertical platform rate", "m/s", low=-1000.0, high=1000.0),
    Param("platform.direction", 1, "Orbit sense: +1 counter-clockwise, -1 clockwise", "1", kind=int,
          choices=(1, -1)),
    Param("platform.heading", 90.0, "Course of straight flight, from +x towards +y", "deg",
          low=-360.0, high=360.0),
    Param("sensors.count", 2, "Number of sensors (1 = sensor 1 only)", "sensors", kind=int,
          low=1, high=2, label="sensors", symbol="sensors"),
    Param("sensors.baseline", 0.0, "Horizontal formation offset of sensor 2 from sensor 1",
          "m", low=0.0, high=1e6, label="sensor baseline", symbol="baseline"),
    Param("sensors.baseline_angle", 90.0, "Direction of the baseline from the initial line of "
          "sight (90 = broadside)", "deg", low=-360.0, high=360.0),
    Param("sensors.sigma_az", 0.01, "Azimuth noise standard deviation of sensor 1 (paper: 0.01)",
          "rad", low=1e-6, high=1.0, draws=False),
    Param("sensors.sigma_el_ratio", 1.0, "Elevation noise standard deviation relative to the "
          "azimuth one (1: equal accuracy, the default sigma_el = 0.01 rad)", "1", low=1e-3,
          high=1e3, draws=False),
    Param("sensors.pd", 1.0, "Detection probability of sensor 1", "1", low=0.0, high=1.0,
          draws=False),
    Param("sensor2.noise_ratio", 1.0, "Sensor 2 noise standard deviations relative to sensor 1",
          "1", low=1e-3, high=1e3, draws=False),
    Param("sensor2.pd_ratio", 1.0, "Sensor 2 detection probability relative to sensor 1", "1",
          low=0.0, high=1.0, draws=False),
    Param("clutter.model", "in_gate", "Clutter model: uniform in each filter's gate, or in a "
          "fixed window about the true line of sight", kind=str, choices=("in_gate", "window"),
          label="clutter model", words=(("in_gate", "clutter in the gate"),
                                        ("window", "clutter in a window"))),
    Param("clutter.mean", 0.0, "Mean number of false returns per sensor and scan (in the gate "
          "or window)", "returns/scan", low=0.0, high=200.0,
          label="mean false returns per sensor and scan", symbol="clutter"),
    Param("clutter.window", 0.1, "Half-width of the window clutter box in azimuth and elevation",
          "rad", low=1e-4, high=1.0),
    Param("init.range_cue", "absolute", "How the radar range cue's standard deviation is "
          "given: in metres (init.sigma_range) or as a fraction of the true initial range "
          "(init.sigma_range_fraction)", kind=str, choices=("absolute", "relative"), draws=False),
    Param("init.sigma_range", 20000.0, "Initial range standard deviation of an absolute cue "
          "(paper default: 20 km = 10 % of 200 km)", "m", low=1.0, high=1e7, draws=False,
          label="range cue standard deviation", symbol="range cue sd"),
    Param("init.sigma_range_fraction", 0.1, "Initial range standard deviation of a relative "
          "cue, as a fraction of the true range from sensor 1 at t = 0", "1", low=1e-4, high=10.0,
          draws=False),
    Param("init.sigma_angle", float(0.01 / np.sqrt(2.0)), "Initial cross-range standard "
          "deviation per axis, as an angle", "rad", low=1e-7, high=1.0, draws=False),
    Param("init.sigma_velocity", 30.0, "Initial velocity standard deviation per axis", "m/s",
          low=1e-3, high=1e4, draws=False),
    Param("filter.q", 900.0, "Filter process-noise acceleration variance", "m^2/s^4", low=0.0,
          high=1e8, draws=False, label="filter process noise q", symbol="filter q"),
    Param("gate.pg", 0.99, "Gate probability P_G", "1", low=0.5, high=0.999999, draws=False),
    Param("filter.mg_at", "hypothesis", "Where the MGEKF modified rows are evaluated: each "
          "hypothesis's own returns, or the beta-weighted combined return (W000-4)", kind=str,
          choices=("hypothesis", "combined"), draws=False),
    Param("pda.joint_cov", "full", "Joint innovation covariance of the pair hypotheses", kind=str,
          choices=("full", "blockdiag"), draws=False),
    Param("pda.density", "parametric", "Clutter density: true value or m_s / V_s", kind=str,
          choices=("parametric", "nonparametric"), draws=False),
    Param("algorithms", list(ALGORITHMS), "Algorithm variants run on the same data, as "
          "association/filter", kind=list,
          choices=ALGORITHMS + IPDA_ALGORITHMS + STONESOUP_ALGORITHMS, draws=False),
    Param("ipda.persistence", 0.98, "IPDA: probability that an existing target still exists "
          "at the next scan (Markov chain of existence, no birth)", "1", low=1e-6, high=1.0,
          draws=False),
    Param("ipda.initial", 0.5, "IPDA: existence probability of the track at t = 0", "1",
          low=1e-6, high=0.999999, draws=False),
    Param("ipda.confirm", 0.95, "IPDA: a track is confirmed when its existence probability "
          "reaches this (above ipda.terminate)", "1", low=1e-6, high=0.999999, draws=False),
    Param("ipda.terminate", 0.05, "IPDA: a track is terminated when its existence "
          "probability falls below this (below ipda.confirm)", "1", low=1e-6, high=0.999999,
          draws=False),
    Param("loss.window", 3, "Consecutive scans with the target outside every gate that mean "
          "a lost track (gate rule)", "scans", kind=int, low=1, high=1000, draws=False),
    Param("loss.angle_sigmas", 3.0, "Angle rule: a scan counts as off-target when the "
          "estimate's azimuth or elevation seen from sensor 1 is further than this many "
          "sensor-1 noise standard deviations from the true one", "1", low=0.1, high=1e3,
          draws=False),
    Param("loss.angle_window", 3, "Consecutive off-target scans that mean a lost track "
          "(angle rule)", "scans", kind=int, low=1, high=1000, draws=False),
    Param("loss.nees_quantile", 0.999, "Chi-square (3 dof) quantile above which the final "
          "position NEES marks the filter inconsistent", "1", low=0.5, high=0.999999, draws=False),
    *STONESOUP_PARAMS,
)


@dataclass(frozen=True)
class Scenario:
    """Everything deterministic about a trial, derived from the params.

    ``K`` scans, ``S`` sensors: ``times`` (K+1,) s, ``platform`` (K+1, 3) m, ``sensor_pos``
    (K+1, S, 3) m, ``R`` (S, 2, 2) rad^2, ``P_D`` (S,), ``x_start`` (6,) m and m/s,
    ``P0, F, Q_filter`` (6, 6); ``q_truth`` truth acceleration variance (m^2/s^4), ``gamma``
    gate threshold (chi-square, 2 dof) with probability ``P_G``, ``clutter_mean`` false returns
    per sensor and scan, ``window`` half-width (rad) of the window clutter box.
    """

    K: int
    times: np.ndarray
    platform: np.ndarray
    sensor_pos: np.ndarray
    R: np.ndarray
    P_D: np.ndarray
    x_start: np.ndarray
    P0: np.ndarray
    F: np.ndarray
    Q_filter: np.ndarray
    q_truth: float
    gamma: float
    P_G: float
    clutter_model: str
    clutter_mean: float
    window: float

    @cached_property
    def P0_chol(self) -> np.ndarray:
        """Lower Cholesky factor of ``P0: (6, 6)`` (draws ``x0``; computed once, not per trial)."""
        return np.linalg.cholesky(self.P0)

    @cached_property
    def noise_sd(self) -> np.ndarray:
        """Angle noise standard deviations ``(S, 2)`` (rad), the square roots of ``diag R``."""
        return np.sqrt(np.diagonal(self.R, axis1=1, axis2=2))

    @property
    def window_density(self) -> float:
        """True density (1/rad^2) of ``window`` clutter: ``clutter_mean`` over the box area."""
        return self.clutter_mean / (2.0 * self.window) ** 2


def placements(params: Mapping[str, Any]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where everything is, from resolved ``params``: ``times: (K+1,)`` s, the platform
    ``(K+1, 3)`` m and the sensors ``(K+1, S, 3)`` m at every scan."""
    T, K = float(params["scan.period"]), int(params["scan.count"])
    times = T * np.arange(K + 1)
    target = np.asarray(params["target.position"], dtype=float)
    start = np.asarray(params["platform.start"], dtype=float)
    if params["platform.motion"] == "orbit":
        platform = orbit_positions(times, start, target[:2], float(params["platform.speed"]),
                                   float(params["platform.climb"]),
                                   int(params["platform.direction"]))
    else:
        platform = straight_positions(times, start, float(params["platform.speed"]),
                                      np.radians(float(params["platform.heading"])),
                                      float(params["platform.climb"]))
    S = int(params["sensors.count"])
    los_az = float(np.arctan2(target[1] - start[1], target[0] - start[0]))
    offsets = [np.zeros(3), baseline_offset(los_az, float(params["sensors.baseline"]),
                                            np.radians(float(params["sensors.baseline_angle"])))]
    return times, platform, np.stack([platform + offsets[s] for s in range(S)], axis=1)


def build_scenario(params: dict[str, Any]) -> Scenario:
    """The deterministic part of the experiment for resolved ``params``."""
    times, platform, sensor_pos = placements(params)
    T, K, S = float(params["scan.period"]), len(times) - 1, sensor_pos.shape[1]
    target = np.asarray(params["target.position"], dtype=float)
    sigma_az = float(params["sensors.sigma_az"])
    sig = np.array([sigma_az, sigma_az * float(params["sensors.sigma_el_ratio"])])
    ratios = [1.0, float(params["sensor2.noise_ratio"])]
    R = np.stack([np.diag((ratios[s] * sig) ** 2) for s in range(S)])
    pd_ratio = [1.0, float(params["sensor2.pd_ratio"])]
    P_D = np.array([float(params["sensors.pd"]) * pd_ratio[s] for s in range(S)])
    x_start = np.concatenate([target, np.asarray(params["target.velocity"], dtype=float)])
    sigma_range = range_cue_sd(str(params["init.range_cue"]), target - platform[0],
                               float(params["init.sigma_range"]),
                               float(params["init.sigma_range_fraction"]))
    P0 = los_prior_covariance(target - platform[0], sigma_range,
                              float(params["init.sigma_angle"]),
                              float(params["init.sigma_velocity"]))
    P_G = float(params["gate.pg"])
    return Scenario(K, times, platform, sensor_pos, R, P_D, x_start, P0, cv_transition(T),
                    cv_process_noise(T, float(params["filter.q"])), float(params["target.q"]),
                    gate_threshold(P_G, 2), P_G, str(params["clutter.model"]),
                    float(params["clutter.mean"]), float(params["clutter.window"]))


def truth_trajectory(sc: Scenario, rng: np.random.Generator | None) -> np.ndarray:
    """True states ``(K+1, 6)``; CV with process noise ``q_truth`` when ``rng`` is given.

    Closed form of ``x(k+1) = F x(k) + G a(k)``: ``v(k) = v0 + T sum_{j<k} a(j)`` and
    ``p(k) = p0 + sum_{j<k} (T v(j) + T^2/2 a(j))``.
    """
    T = sc.times[1] - sc.times[0] if sc.K else 0.0
    accel = (np.sqrt(sc.q_truth) * rng.standard_normal((sc.K, 3)) if rng is not None
             and sc.q_truth > 0 else np.zeros((sc.K, 3)))
    v = np.empty((sc.K + 1, 3))
    v[0] = sc.x_start[3:]
    v[1:] = sc.x_start[3:] + T * np.cumsum(accel, axis=0)
    p = np.empty((sc.K + 1, 3))
    p[0] = sc.x_start[:3]
    p[1:] = sc.x_start[:3] + np.cumsum(T * v[:-1] + 0.5 * T**2 * accel, axis=0)
    return np.concatenate([p, v], axis=1)


@dataclass(frozen=True)
class Batch:
    """The simulated data of ``N`` trials, clutter padded to ``C`` slots with a validity mask.

    ``x_true: (N, K+1, 6)``; ``x0: (N, 6)`` filter initialization; ``detected: (N, K, S)``;
    ``los: (N, K, S, 2)`` noise-free target returns (rad); ``z_target: (N, K, S, 2)`` noisy
    target returns (rad); ``clutter: (N, K, S, C, 2)`` unit-disk points (in_gate) or absolute
    angles (window), zero where ``clutter_ok: (N, K, S, C)`` is False.
    """

    x_true: np.ndarray
    x0: np.ndarray
    detected: np.ndarray
    los: np.ndarray
    z_target: np.ndarray
    clutter: np.ndarray
    clutter_ok: np.ndarray


def simulate(sc: Scenario, streams: Sequence[TrialStreams]) -> Batch:
    """Draw each trial's truth, initialization, target returns and clutter from its streams.

    Everything comes from the trial's common stream (the same at every sweep point), from
    three spawned children: truth, initialization, and the sensor returns (detections and
    noise, then the clutter, read last so that the clutter level changes nothing else).
    Detections, noise and clutter are drawn for :data:`MAX_SENSORS` sensors, so a one-sensor
    point sees sensor 1's returns of a two-sensor point; the clutter is nested across levels
    (:mod:`~trackfuse.tracking.nested_clutter`). Per trial only the random draws run
    in a loop; what is computed from them is computed for the whole batch at once (element
    by element, so a trial's numbers do not depend on the batch it is in).
    """
    from trackfuse.tracking.nested_clutter import (  # numba: on use
        NestedClutter,
        padded_disk_points,
    )

    N, K, S = len(streams), sc.K, sc.R.shape[0]
    moving = sc.q_truth > 0  # else the truth draws nothing and is the same in every trial
    x_true, x0_normal = np.empty((N, K + 1, 6)), np.empty((N, 6))
    if not moving:
        x_true[:] = truth_trajectory(sc, None)
    uniform, normal = np.empty((N, K, MAX_SENSORS)), np.empty((N, K, MAX_SENSORS, 2))
    wanted = np.tile(np.arange(MAX_SENSORS) < S, K)  # clutter cells: scan-, sensor-major
    nested = NestedClutter(sc.clutter_mean, N, K * MAX_SENSORS, wanted)
    for n, (truth, init, trial_returns) in enumerate(spawn_shared(streams, 3)):
        if moving:
            with truth as rng:
                x_true[n] = truth_trajectory(sc, rng)
        with init as rng:
            rng.standard_normal(out=x0_normal[n])
        with trial_returns as rng:
            uniform[n] = rng.random((K, MAX_SENSORS))
            normal[n] = rng.standard_normal((K, MAX_SENSORS, 2))
            nested.draw(n, rng)  # last, so the clutter level changes nothing else
    counts = np.ascontiguousarray(nested.counts.reshape(N, K, MAX_SENSORS)[..., :S])
    draws = nested.uniforms()
    x0 = x_true[:, 0] + np.matmul(sc.P0_chol, x0_normal[..., None])[..., 0]  # N(x(0), P0)
    detected = (uniform < _padded(sc.P_D))[..., :S]
    los = azel(x_true[:, 1:, None, :3] - sc.sensor_pos[1:])
    z_target = wrap(los + sc.noise_sd * normal[:, :, :S])
    C = max(int(counts.max()) if counts.size else 0, 1)
    if sc.clutter_model == "in_gate":
        clutter, ok = padded_disk_points(counts, draws, C)
    else:
        clutter, ok = _window_points(sc, draws, los, counts, C)
    return Batch(x_true, x0, detected, los, z_target, clutter, ok)


def _window_points(sc: Scenario, draws: np.ndarray, los: np.ndarray, counts: np.ndarray,
                   slots: int) -> tuple[np.ndarray, np.ndarray]:
    """``window`` clutter ``(N, K, S, slots, 2)`` (rad) and its validity ``(N, K, S, slots)``
    from the uniforms ``(2, total)`` on [0, 1) behind it (trial-, scan-, sensor-major), the
    lines of sight ``(N, K, S, 2)`` (rad) and the counts ``(N, K, S)``: azimuth and
    elevation uniform on ``[-window, window)`` about the line of sight; zero where not
    valid."""
    ok = np.arange(slots) < counts[..., None]
    clutter = np.zeros(ok.shape + (2,))
    centre = np.repeat(los.reshape(-1, 2), counts.ravel(), axis=0)
    points = centre + sc.window * (2.0 * draws.T - 1.0)
    points[:, 0] = wrap(points[:, 0])
    clutter.reshape(-1, 2)[np.flatnonzero(ok)] = points
    return clutter, ok


def _padded(P_D: np.ndarray) -> np.ndarray:
    """Detection probabilities ``(MAX_SENSORS,)``: ``P_D: (S,)`` padded with zeros."""
    return np.concatenate([P_D, np.zeros(MAX_SENSORS - len(P_D))])


@dataclass(frozen=True)
class LossRules:
    """Track-loss and consistency rules (``docs/papers/twin_sensor.md``, Metrics).

    ``gate_window`` and ``angle_window`` consecutive scans for the gate and angle rules,
    ``angle_sigmas`` sensor-1 noise sds for the angle rule, ``nees_limit`` the position-NEES
    threshold of the consistency flag.
    """

    gate_window: int
    angle_sigmas: float
    angle_window: int
    nees_limit: float

    @classmethod
    def from_params(cls, params: dict[str, Any]) -> LossRules:
        """The rules of resolved ``params``."""
        return cls(int(params["loss.window"]), float(params["loss.angle_sigmas"]),
                   int(params["loss.angle_window"]),
                   chi2_quantile(float(params["loss.nees_quantile"]), 3))


ROW_METRICS = (
    Metric("range_err_m", "m", "signed range error from platform 1 (its mean is the range "
           "bias)"),
    Metric("range_sq_err_m2", "m^2", "squared range error (its mean is the range MSE)",
           better="lower", bounds=NON_NEGATIVE),
    Metric("pos_sq_err_m2", "m^2", "squared position error (its mean is the position MSE)",
           better="lower", bounds=NON_NEGATIVE),
    Metric("nees", "1", "6-state normalized estimation error squared", bounds=NON_NEGATIVE,
           label="ANEES (6 states)"),
    Metric("nees_pos", "1", "position normalized estimation error squared",
           bounds=NON_NEGATIVE),
    Metric("n_valid", "returns", "validated returns per sensor (mean over sensors)",
           bounds=NON_NEGATIVE),
    Metric("lost_gate", "1", "lost by the gate rule (permanent)", binary=True, better="lower",
           label="lost, gate rule"),
    Metric("lost_angle", "1", "lost by the angle rule (permanent)", binary=True,
           better="lower", label="tracks lost"),
    Metric("inconsistent_nees", "1", "position NEES above its chi-square quantile",
           binary=True, better="lower", label="inconsistent filters"),
    Metric("existence", "1", "IPDA's probability that the target exists, after the scan's "
           "update (NaN for the other algorithms)", bounds=FRACTION, optional=True),
    Metric("confirmed", "1", "IPDA track confirmed by this scan (existence reached "
           "ipda.confirm before any termination; permanent)", binary=True, better="higher",
           optional=True, label="tracks confirmed"),
    Metric("lost_existence", "1", "IPDA track terminated by this scan (existence below "
           "ipda.terminate; permanent): the target exists throughout, so a loss",
           binary=True, better="lower", optional=True, label="tracks terminated"),
    Metric("cpu_time_s", "s", "CPU seconds per trial and scan of this algorithm, one value "
           "per batch (timings.csv)"),
)
"""Every metric column of the rows (``docs/papers/twin_sensor.md``, Metrics)."""
METRICS = tuple(m.name for m in ROW_METRICS
                if not m.name.endswith("_time_s") and not m.optional)
"""Per-scan metric columns of every trial's rows (:func:`score_estimates`)."""
EXISTENCE_METRICS = tuple(m.name for m in ROW_METRICS if m.optional)
"""Per-scan columns of the runs with an IPDA algorithm (:func:`score_existence`), NaN on
the other algorithms' rows."""
BINARY_METRICS = tuple(m.name for m in ROW_METRICS if m.binary)
"""The 0/1 metric columns (Wilson intervals in the summary)."""


def angle_off_target(X: np.ndarray, sensor: np.ndarray, los_true: np.ndarray,
                     sigma: np.ndarray, sigmas: float) -> np.ndarray:
    """Angle rule (...,) bool: the estimate ``X`` (..., 6) seen from ``sensor`` (..., 3) m is more
    than ``sigmas`` noise sds ``sigma`` (2,) rad from ``los_true`` (..., 2) rad in az or el.

    Non-finite estimates count as off target.
    """
    with np.errstate(invalid="ignore"):
        err = np.abs(wrap(azel(X[..., :3] - sensor) - los_true)) / sigma
        return ~(err <= sigmas).all(axis=-1)


def _runs(flags: np.ndarray) -> np.ndarray:
    """Length of the run of consecutive True values ending at each scan: ``(N, K)`` int for
    ``flags: (N, K)`` bool (0 where the flag is False)."""
    runs = np.zeros(flags.shape, dtype=int)
    count = np.zeros(flags.shape[0], dtype=int)
    for k in range(flags.shape[1]):
        count = np.where(flags[:, k], count + 1, 0)
        runs[:, k] = count
    return runs


def score_estimates(sc: Scenario, b: Batch, est: Estimates,
                    rules: LossRules) -> dict[str, np.ndarray]:
    """Every metric of :data:`METRICS` as (N, K) for per-scan :class:`Estimates` ``est``.

    Ours and another library's are scored alike: ``P`` is symmetrised, a trial is NaN from its
    first non-finite scan, and losses are permanent (both rules on divergence).
    """
    from trackfuse.tracking.pda import symmetrized  # numba: on use

    X = est.X.copy()
    P, finite_P = symmetrized(np.ascontiguousarray(est.P, dtype=float))
    bad = ~(np.isfinite(X).all(axis=2) & finite_P)
    diverged = np.logical_or.accumulate(bad, axis=1)
    X[diverged], P[diverged] = np.nan, np.nan
    scans = np.arange(1, sc.K + 1)
    off = angle_off_target(X, sc.sensor_pos[scans, 0], b.los[:, :, 0], sc.noise_sd[0],
                           rules.angle_sigmas)
    lost_gate = np.logical_or.accumulate(
        (_runs(~est.inside) >= rules.gate_window) | diverged, axis=1)
    lost_angle = np.logical_or.accumulate((_runs(off) >= rules.angle_window) | diverged,
                                          axis=1)
    x_true = b.x_true[:, scans]
    e = X - x_true
    platform = sc.platform[scans]
    range_err = (np.linalg.norm(X[..., :3] - platform, axis=-1)
                 - np.linalg.norm(x_true[..., :3] - platform, axis=-1))
    nees_pos = _nees(e[..., :3], P[..., :3, :3])
    with np.errstate(invalid="ignore"):
        inconsistent = (nees_pos > rules.nees_limit) | diverged
    return {"range_err_m": range_err, "range_sq_err_m2": range_err**2,
            "pos_sq_err_m2": (e[..., :3] ** 2).sum(axis=-1), "nees": _nees(e, P),
            "nees_pos": nees_pos, "n_valid": est.n_valid.mean(axis=-1),
            "lost_gate": lost_gate, "lost_angle": lost_angle,
            "inconsistent_nees": inconsistent}


def _nees(e: np.ndarray, P: np.ndarray) -> np.ndarray:
    """``e' P^-1 e`` (...,) for ``e`` (..., n), ``P`` (..., n, n); NaN where either is not finite,
    the pseudo-inverse where ``P`` is singular.
    """
    finite = np.isfinite(P).all(axis=(-2, -1)) & np.isfinite(e).all(axis=-1)
    out = np.full(e.shape[:-1], np.nan)
    if finite.any():
        n = e.shape[-1]
        Pf, ef = (P, e) if finite.all() else (P[finite], e[finite])  # no copy if all are
        try:
            out[finite] = (ef * np.linalg.solve(Pf, ef[..., None])[..., 0]).sum(axis=-1).ravel()
        except np.linalg.LinAlgError:
            out[finite] = [_nees_one(x, Q) for x, Q in zip(ef.reshape(-1, n),
                                                           Pf.reshape(-1, n, n), strict=True)]
    return out


def _nees_one(e: np.ndarray, P: np.ndarray) -> float:
    """``e' P^-1 e`` of one ``e: (n,)``, ``P: (n, n)``; the pseudo-inverse if ``P`` is singular."""
    try:
        return float((e * np.linalg.solve(P, e[:, None])[:, 0]).sum())
    except np.linalg.LinAlgError:
        return float(e @ np.linalg.pinv(P) @ e)


def run_batch(params: dict[str, Any], streams: Sequence[TrialStreams]) -> RowTable:
    """Run a batch of trials; each trial's data comes from its own streams only.

    Rows are trial-major, then algorithm, then scan; the CPU time of each algorithm over
    the whole batch, per trial and scan, is the batch's timing table. A run with an IPDA
    algorithm also has the :data:`EXISTENCE_METRICS` columns (NaN for the others).
    """
    sc = build_scenario(params)
    batch = simulate(sc, streams)
    N, K = len(streams), sc.K
    rules = LossRules.from_params(params)
    names = list(params["algorithms"])
    results, cpu = [], []
    for name in names:
        t0 = time.process_time()
        results.append(_run_algorithm(name, params, sc, batch, streams, rules))
        cpu.append((time.process_time() - t0) / (N * K))
    A = len(names)
    columns: dict[str, np.ndarray] = {
        "algorithm": np.tile(np.repeat(np.array(names, dtype=object), K), N),
        "scan": np.tile(np.arange(1, K + 1), N * A)}
    keys = METRICS + (EXISTENCE_METRICS if set(names) & set(IPDA_ALGORITHMS) else ())
    for key in keys:  # (N, A, K) -> rows in trial, algorithm, scan order
        values = np.stack([res.get(key, np.full((N, K), np.nan)) for res in results],
                          axis=1).reshape(-1)
        columns[key] = values.astype(int) if key in METRICS and key in BINARY_METRICS \
            else values
    return RowTable(np.repeat(np.arange(N), A * K), columns,
                    {"algorithm": np.array(names, dtype=object), "cpu_time_s": np.array(cpu)})


def _run_algorithm(name: str, params: dict[str, Any], sc: Scenario, batch: Batch,
                   streams: Sequence[TrialStreams], rules: LossRules) -> dict[str, np.ndarray]:
    """Every metric, ``(N, K)`` each, of algorithm ``name`` (``association/filter``) on
    ``batch``: :data:`METRICS`, and :data:`EXISTENCE_METRICS` for IPDA."""
    from trackfuse.tracking.ipda import run_ipda  # numba: on use
    from trackfuse.tracking.pda import run_filter

    if is_stonesoup(name):  # Stone Soup's filters, scored by our metrics
        return score_estimates(sc, batch, run_stonesoup(name, params, sc, batch, streams),
                               rules)
    assoc, filt = name.split("/")
    options = PDAOptions("mspda_parallel" if assoc == "ipda" else assoc, FILTERS[filt],
                         str(params["pda.joint_cov"]), str(params["pda.density"]),
                         str(params["filter.mg_at"]), sc.P_G)
    if assoc != "ipda":
        return score_estimates(sc, batch, run_filter(sc, batch, options), rules)
    model = ExistenceModel.from_params(params)
    est, existence = run_ipda(sc, batch, options, model)
    return {**score_estimates(sc, batch, est, rules), **score_existence(existence, model)}


def score_existence(existence: np.ndarray, model: ExistenceModel) -> dict[str, np.ndarray]:
    """The :data:`EXISTENCE_METRICS` as ``(N, K)`` from IPDA's existence probabilities
    ``existence: (N, K)``: the probability itself and the confirmation and termination
    flags (:func:`trackfuse.tracking.ipda_options.track_decisions`; the target exists at
    every scan, so a termination is a lost track)."""
    confirmed, terminated = track_decisions(existence, model)
    return {"existence": existence, "confirmed": confirmed.astype(float),
            "lost_existence": terminated.astype(float)}


def run_trial(params: dict[str, Any], streams: TrialStreams) -> list[dict]:
    """One trial: the batch form with a batch of one (identical data and algebra); rows
    without the timing column (it is the batch's, see :func:`run_batch`)."""
    return run_batch(params, [streams])[0]


# --------------------------------------------------------------------------------------------
# PCRLB reference (recomputed from the config; deterministic)


def bounds(params: dict[str, Any], q_model: float | None = None,
           truth_samples: int = 200) -> tuple[np.ndarray, np.ndarray]:
    """Range and position PCRLB ``(K,)`` each (m) at scans ``1..K`` for ``params``.

    The truth-model bound uses ``target.q`` (``q_model=None``); pass the filter's ``q`` for
    the filter-model bound. Clutter and missed detections enter through the IRF ``q2``: for
    ``in_gate`` clutter the density is ``clutter.mean / V_s`` with the gate of an ideal filter
    whose predicted covariance is the bound's own; for ``window`` clutter it is the true
    density. A random (``target.q > 0``) truth is averaged over ``truth_samples`` trajectories
    from a fixed seed. Both arrays are cached and read-only (copy one to change it).
    """
    key = tuple(sorted((k, tuple(v) if isinstance(v, list) else v) for k, v in params.items()))
    return _bounds_cached(key, q_model, truth_samples)


@lru_cache(maxsize=256)
def _bounds_cached(key: tuple, q_model: float | None, truth_samples: int):
    params = {k: list(v) if isinstance(v, tuple) else v for k, v in key}
    sc = build_scenario(params)
    if sc.q_truth > 0:
        rng = np.random.default_rng(0)
        x = np.stack([truth_trajectory(sc, rng) for _ in range(truth_samples)])
        x_mean = x.mean(axis=0)
    else:
        x = x_mean = truth_trajectory(sc, None)
    Jz = measurement_information(x[..., 1:, :], sc.sensor_pos[1:], sc.R)
    q = sc.q_truth if q_model is None else q_model
    Q = cv_process_noise(sc.times[1] - sc.times[0], q)

    def q2(k: int, Pp: np.ndarray) -> np.ndarray:
        if sc.clutter_mean == 0:
            return sc.P_D.copy()
        out = np.empty(len(sc.P_D))
        for s, P_D in enumerate(sc.P_D):
            if sc.clutter_model == "in_gate":
                H = azel_jacobian(x_mean[k, :3] - sc.sensor_pos[k, s])
                lam = sc.clutter_mean / gate_volume(H @ Pp @ H.T + sc.R[s], sc.gamma)
            else:
                lam = sc.window_density
            out[s] = irf_q2_interp(lam * sc.noise_sd[s].prod(), float(P_D))
        return out

    Jinv = information_recursion(np.linalg.inv(sc.P0), sc.F, Q, Jz, q2)
    out = range_bound(Jinv[1:], x_mean[1:], sc.platform[1:]), position_bound(Jinv[1:])
    for bound in out:
        bound.flags.writeable = False  # the cache hands these arrays to every caller
    return out

