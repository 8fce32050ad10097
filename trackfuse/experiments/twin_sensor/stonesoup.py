"""Stone Soup's filters on exactly the returns our twin_sensor filters see (paired comparison).

Algorithms ``stonesoup_pda/ekf``, ``/ukf`` and ``/pf`` run Stone Soup's predictors,
updaters and ``PDAHypothesiser`` on the trial's :class:`~.model.Batch`; two sensors update
sequentially. Clutter placement, parameters and what Stone Soup cannot do:
``docs/stonesoup.md``. The particle filter draws from the trial's common stream
(:func:`trackfuse.interop.stonesoup.algorithm_random_state`), so rows are byte-identical for
any executor and after resume.
"""

from __future__ import annotations

import importlib.util
from collections.abc import Mapping, Sequence
from contextlib import suppress
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from trackfuse.experiments.base import Param
from trackfuse.interop import stonesoup as ss
from trackfuse.seeding import TrialStreams
from trackfuse.tracking.pda_options import Estimates
from trackfuse.tracking.sensors import ellipse_points, gate_volume, inv2

if TYPE_CHECKING:
    from trackfuse.experiments.twin_sensor.model import Batch, Scenario

PREFIX = "stonesoup_"
STONESOUP_FILTERS = ("ekf", "ukf", "pf")
STONESOUP_ALGORITHMS = tuple(f"{PREFIX}pda/{f}" for f in STONESOUP_FILTERS)
NO_CLUTTER_DENSITY = 1e-200
"""Clutter density (1/rad^2) given to Stone Soup for none: the limit ``lambda -> 0+`` (all
weight on a validated return). Not smaller: Stone Soup's hypothesis normalisation multiplies
a ``Probability`` by a float, which leaves log space and overflows to NaN near 1e-300."""
STONESOUP_PARAMS = (
    Param("stonesoup.particles", 500, "Particles of the Stone Soup particle filter "
          "(stonesoup_pda/pf)", "particles", kind=int, low=10, high=1_000_000, draws=False),
    Param("stonesoup.process_noise", "ours", "Process noise of the Stone Soup filters: our "
          "discrete white-noise acceleration Q (paired with ours) or Stone Soup's "
          "ConstantVelocity (continuous white noise)", kind=str, choices=("ours", "cv"),
          draws=False),
    Param("stonesoup.jacobian", "numerical", "Measurement Jacobian of the Stone Soup EKF: its "
          "own finite difference or the analytic one (docs/stonesoup.md)", kind=str,
          choices=("numerical", "analytic"), draws=False),
)


def is_stonesoup(algorithm: str) -> bool:
    """Whether ``algorithm`` (``association/filter``) names a Stone Soup algorithm."""
    return algorithm.startswith(PREFIX)


def missing_stonesoup(params: Mapping[str, Any],
                      sweep: Mapping[str, list[Any]]) -> tuple[str, str] | None:
    """``("algorithms", problem)`` when a configured or swept Stone Soup algorithm cannot run
    because Stone Soup is not installed; else ``None``.
    """
    chosen = [*params.get("algorithms", []), *(a for value in sweep.get("algorithms", [])
                                              for a in value)]
    wanted = sorted({a for a in chosen if is_stonesoup(a)})
    if wanted and importlib.util.find_spec("stonesoup") is None:
        return "algorithms", (f"{wanted[0]} needs Stone Soup, which is not installed; "
                              "install it with: pip install 'trackfuse[stonesoup]'")
    return None


@dataclass
class _Filter:
    """The Stone Soup components of one algorithm for one trial."""

    predictor: Any
    updater: Any
    static_predictor: Any  # zero-time identity prediction between sensors
    random_state: np.random.RandomState
    resampler: ss.SeededSystematicResampler | None
    particles: int
    exact_jacobian: bool


def run_stonesoup(algorithm: str, params: dict[str, Any], sc: Scenario, b: Batch,
                  streams: Sequence[TrialStreams]) -> Estimates:
    """Run the Stone Soup ``algorithm`` over every trial of the batch ``b``."""
    ss.require_stonesoup()
    kind = algorithm.partition("/")[2]
    if algorithm not in STONESOUP_ALGORITHMS:
        raise ValueError(f"unknown Stone Soup algorithm {algorithm!r}; "
                         f"choose from {STONESOUP_ALGORITHMS}")
    N, S = b.x0.shape[0], sc.R.shape[0]
    out = Estimates(np.full((N, sc.K, 6), np.nan), np.full((N, sc.K, 6, 6), np.nan),
                    np.zeros((N, sc.K, S)), np.zeros((N, sc.K), dtype=bool))
    for n, trial in enumerate(streams):
        flt = _components(kind, params, sc, ss.algorithm_random_state(trial.common, algorithm))
        # a numerical failure leaves the scans not reached NaN: scored as diverged
        with suppress(np.linalg.LinAlgError, ValueError, FloatingPointError, ZeroDivisionError):
            _track(flt, sc, b, n, out)
    return out


def _components(kind: str, params: dict[str, Any], sc: Scenario,
                rs: np.random.RandomState) -> _Filter:
    """Predictor, updater and (particle filter) resampler of filter ``kind``."""
    # Stone Soup is optional and slow to import: on first use (run_stonesoup checked it)
    from stonesoup.models.transition.linear import (
        CombinedLinearGaussianTransitionModel,
        ConstantVelocity,
    )
    from stonesoup.predictor.kalman import ExtendedKalmanPredictor, UnscentedKalmanPredictor
    from stonesoup.predictor.particle import ParticlePredictor
    from stonesoup.updater.kalman import ExtendedKalmanUpdater, UnscentedKalmanUpdater
    from stonesoup.updater.particle import ParticleUpdater

    if params["stonesoup.process_noise"] == "ours":
        transition = ss.transition_model(sc.F, sc.Q_filter, rs)
    else:
        transition = CombinedLinearGaussianTransitionModel(
            [ConstantVelocity(float(params["filter.q"]))] * 3)
        transition.random_state = rs
    static = ss.transition_model(np.eye(6), np.zeros((6, 6)), rs)
    exact = params["stonesoup.jacobian"] == "analytic"
    if kind == "ekf":
        return _Filter(ExtendedKalmanPredictor(transition), ExtendedKalmanUpdater(None),
                       ExtendedKalmanPredictor(static), rs, None, 0, exact)
    if kind == "ukf":
        return _Filter(UnscentedKalmanPredictor(transition), UnscentedKalmanUpdater(None),
                       UnscentedKalmanPredictor(static), rs, None, 0, exact)
    return _Filter(ParticlePredictor(transition), ParticleUpdater(None),
                   ParticlePredictor(static), rs, ss.SeededSystematicResampler(rs),
                   int(params["stonesoup.particles"]), exact)


def _track(flt: _Filter, sc: Scenario, b: Batch, n: int, out: Estimates) -> None:
    """Filter trial ``n`` of ``b`` scan by scan, writing into ``out``."""
    from stonesoup.hypothesiser.probability import PDAHypothesiser  # see _components

    if flt.resampler is None:
        state = ss.gaussian_prior(b.x0[n], sc.P0, sc.times[0])
    else:
        state = ss.particle_prior(b.x0[n], sc.P0, sc.times[0], flt.particles, flt.random_state)
    S = sc.R.shape[0]
    for k in range(1, sc.K + 1):
        when = ss.timestamp(sc.times[k])
        models = [ss.angle_model(sc.sensor_pos[k, s], sc.R[s], flt.random_state,
                                 flt.exact_jacobian) for s in range(S)]
        prediction = flt.predictor.predict(state, timestamp=when)
        gates = [ss.measurement_gate(flt.updater.predict_measurement(prediction, m))
                 for m in models]
        out.inside[n, k - 1] = any(_in_gate(b.los[n, k - 1, s], *gates[s], sc.gamma)
                                   for s in range(S))
        for s in range(S):
            z, lam = _returns(sc, b, n, k, s, *gates[s])
            predictor = flt.predictor if s == 0 else flt.static_predictor
            hypothesiser = PDAHypothesiser(predictor, flt.updater, clutter_spatial_density=lam,
                                           prob_detect=float(sc.P_D[s]), prob_gate=sc.P_G)
            hypotheses = hypothesiser.hypothesise(state, ss.detections(z, sc.times[k],
                                                                       models[s]), when)
            out.n_valid[n, k - 1, s] = len(hypotheses) - 1
            if flt.resampler is None:
                state = ss.gaussian_pda_update(hypotheses, flt.updater)
            else:
                state = ss.particle_pda_update(hypotheses, flt.updater, flt.resampler)
        out.X[n, k - 1], out.P[n, k - 1] = ss.estimate(state)


def _in_gate(los: np.ndarray, centre: np.ndarray, S: np.ndarray, gamma: float) -> bool:
    """Whether the noise-free return ``los: (2,)`` lies in the gate ``(centre, S)``."""
    nu = np.angle(np.exp(1j * (los - centre)))  # wrapped to (-pi, pi]
    with np.errstate(invalid="ignore"):
        return bool(nu @ inv2(S)[0] @ nu <= gamma)


def _returns(sc: Scenario, b: Batch, n: int, k: int, s: int, centre: np.ndarray,
             S: np.ndarray) -> tuple[np.ndarray, float]:
    """Returns ``(M, 2)`` rad of sensor ``s`` at scan ``k`` of trial ``n`` as this filter sees them
    (target return if detected, then clutter), and the clutter density.
    """
    target = b.z_target[n, k - 1, s][None] if b.detected[n, k - 1, s] else np.empty((0, 2))
    draws = b.clutter[n, k - 1, s][b.clutter_ok[n, k - 1, s]]
    if sc.clutter_model == "in_gate":
        clutter = ellipse_points(draws[None], centre[None], S[None], sc.gamma)[0]
        lam = sc.clutter_mean / float(gate_volume(S, sc.gamma))
    else:
        clutter, lam = draws, sc.window_density
    return np.concatenate([target, clutter]), max(lam, NO_CLUTTER_DENSITY)
