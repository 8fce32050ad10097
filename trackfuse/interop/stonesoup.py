"""Stone Soup adapter: our angle returns in, our estimate arrays out, every random draw seeded
from the trial (``docs/stonesoup.md``); imports without Stone Soup installed."""

from __future__ import annotations

import zlib
from collections.abc import Sequence
from datetime import datetime, timedelta
from functools import lru_cache
from types import SimpleNamespace
from typing import TYPE_CHECKING

import numpy as np

from trackfuse.tracking.sensors import azel_jacobian

if TYPE_CHECKING:
    from stonesoup.types.state import GaussianState, ParticleState

STONESOUP_MISSING = ("Stone Soup is not installed: pip install 'trackfuse[stonesoup]' (needed "
                     "by the stonesoup_* algorithms and trackfuse.interop.stonesoup)")


@lru_cache(maxsize=1)
def stonesoup_types() -> SimpleNamespace:
    """Stone Soup's classes, imported on first use; ImportError with :data:`STONESOUP_MISSING`."""
    try:
        from stonesoup.models.measurement.nonlinear import CartesianToElevationBearing
        from stonesoup.models.transition.linear import (
            LinearGaussianTimeInvariantTransitionModel,
        )
        from stonesoup.types.array import CovarianceMatrix, StateVector, StateVectors
        from stonesoup.types.detection import Detection
        from stonesoup.types.state import GaussianState, ParticleState
        from stonesoup.types.update import Update
    except ModuleNotFoundError as error:  # the optional extra is not installed
        if not (error.name or "").startswith("stonesoup"):
            raise
        raise ImportError(STONESOUP_MISSING) from None

    class ElevationBearingExactJacobian(CartesianToElevationBearing):
        """``CartesianToElevationBearing`` with the analytic Jacobian (``docs/stonesoup.md``)."""

        def jacobian(self, state, **kwargs) -> np.ndarray:
            """``H`` (2, 6) rad/m, rows (elevation, bearing), Stone Soup state order."""
            d = (np.asarray(state.state_vector, dtype=float)[list(self.mapping), 0]
                 - np.asarray(self.translation_offset, dtype=float)[:, 0])
            return azel_jacobian(d)[::-1][:, TO_STONESOUP]

    return SimpleNamespace(
        CartesianToElevationBearing=CartesianToElevationBearing,
        ElevationBearingExactJacobian=ElevationBearingExactJacobian,
        LinearGaussianTimeInvariantTransitionModel=LinearGaussianTimeInvariantTransitionModel,
        CovarianceMatrix=CovarianceMatrix, StateVector=StateVector, StateVectors=StateVectors,
        Detection=Detection, GaussianState=GaussianState, ParticleState=ParticleState,
        Update=Update)


def logsumexp(a: np.ndarray, axis: int | None = None) -> np.ndarray:
    """``scipy.special.logsumexp``, imported on first use (see :func:`stonesoup_types`)."""
    from scipy.special import logsumexp as scipy_logsumexp

    return scipy_logsumexp(a, axis=axis)


TO_STONESOUP = np.array([0, 3, 1, 4, 2, 5])
"""Stone Soup state component ``i`` is our component ``TO_STONESOUP[i]``."""
FROM_STONESOUP = np.argsort(TO_STONESOUP)
"""Our state component ``j`` is Stone Soup's component ``FROM_STONESOUP[j]``."""
EPOCH = datetime(2000, 1, 1)
"""The ``datetime`` of our ``t = 0`` (any fixed instant: only differences matter)."""
_STREAM_KEY = 0x5705  # spawn-key branch of Stone Soup's randomness (far above spawn counters)


def require_stonesoup() -> None:
    """Raise ``ImportError`` with a one-line message when Stone Soup is not installed."""
    stonesoup_types()


def timestamp(t: float) -> datetime:
    """The Stone Soup timestamp of our time ``t`` (s)."""
    return EPOCH + timedelta(seconds=float(t))


def state_to_stonesoup(x: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Our ``x: (6,)``, ``P: (6, 6)`` reordered to Stone Soup's ``(6, 1)``, ``(6, 6)``."""
    return x[TO_STONESOUP][:, None], P[np.ix_(TO_STONESOUP, TO_STONESOUP)]


def state_from_stonesoup(x: np.ndarray, P: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stone Soup's ``x: (6, 1)`` or ``(6,)``, ``P: (6, 6)`` back in our order."""
    x = np.asarray(x, dtype=float).reshape(6)
    return x[FROM_STONESOUP], np.asarray(P, dtype=float)[np.ix_(FROM_STONESOUP, FROM_STONESOUP)]


def estimate(state) -> tuple[np.ndarray, np.ndarray]:
    """Mean (6,) and covariance (6, 6) of a Gaussian or particle state, in our order."""
    return state_from_stonesoup(state.mean, state.covar)


def gaussian_prior(x: np.ndarray, P: np.ndarray, t: float) -> GaussianState:
    """Stone Soup Gaussian state from our ``x: (6,)``, ``P: (6, 6)`` at time ``t`` (s)."""
    T = stonesoup_types()
    xs, Ps = state_to_stonesoup(x, P)
    return T.GaussianState(xs, Ps, timestamp=timestamp(t))


def particle_prior(x: np.ndarray, P: np.ndarray, t: float, count: int,
                   random_state: np.random.RandomState) -> ParticleState:
    """``count`` equally weighted particles drawn from ``N(x, P)`` (our order) at ``t`` (s)."""
    T = stonesoup_types()
    draws = x[:, None] + np.linalg.cholesky(P) @ random_state.standard_normal((6, count))
    return T.ParticleState(T.StateVectors(draws[TO_STONESOUP]),
                         log_weight=np.full(count, -np.log(count)), timestamp=timestamp(t))


def transition_model(F: np.ndarray, Q: np.ndarray,
                     random_state: np.random.RandomState | None = None):
    """Time-invariant Stone Soup transition with our ``F, Q`` (6, 6): predict only at scan times."""
    T = stonesoup_types()
    model = T.LinearGaussianTimeInvariantTransitionModel(
        transition_matrix=F[np.ix_(TO_STONESOUP, TO_STONESOUP)],
        covariance_matrix=Q[np.ix_(TO_STONESOUP, TO_STONESOUP)])
    model.random_state = random_state
    return model


def angle_model(sensor: np.ndarray, R: np.ndarray,
                random_state: np.random.RandomState | None = None,
                exact_jacobian: bool = False):
    """Azimuth/elevation model of a sensor at ``sensor`` (3,) m with ``R`` (2, 2) rad^2."""
    T = stonesoup_types()
    kind = T.ElevationBearingExactJacobian if exact_jacobian else T.CartesianToElevationBearing
    model = kind(ndim_state=6, mapping=(0, 2, 4),
                 noise_covar=R[::-1, ::-1].copy(), translation_offset=T.StateVector(sensor))
    model.random_state = random_state
    return model


def detections(z: np.ndarray, t: float, model) -> list:
    """Detections of ``z`` (M, 2) rad at ``t`` s, as a list: the order fixes the weights' sums."""
    T = stonesoup_types()
    when = timestamp(t)
    return [T.Detection(T.StateVector(zi[::-1]), timestamp=when, measurement_model=model)
            for zi in np.asarray(z, dtype=float).reshape(-1, 2)]


def measurement_gate(prediction) -> tuple[np.ndarray, np.ndarray]:
    """Centre (2,) rad and innovation covariance ``S`` (2, 2) of a measurement prediction."""
    centre = np.asarray(prediction.mean, dtype=float).reshape(2)[::-1].copy()
    return centre, np.asarray(prediction.covar, dtype=float)[::-1, ::-1].copy()


def algorithm_random_state(common: np.random.Generator, algorithm: str) -> np.random.RandomState:
    """A ``RandomState`` that depends on (root seed, trial, algorithm) only."""
    seq = common.bit_generator.seed_seq
    key = (*seq.spawn_key, _STREAM_KEY, zlib.crc32(algorithm.encode()))
    return np.random.RandomState(np.random.PCG64(np.random.SeedSequence(seq.entropy,
                                                                        spawn_key=key)))


class SeededSystematicResampler:
    """Systematic resampling (Kitagawa 1996) from its own ``random_state``, only when the ESS
    ``1 / sum w^2`` is below ``ess_fraction`` times the count."""

    def __init__(self, random_state: np.random.RandomState, ess_fraction: float = 0.5):
        self.random_state = random_state
        self.ess_fraction = ess_fraction

    def resample(self, particles, nparts: int | None = None):
        """Resampled particles, or ``particles`` when the ESS is high."""
        n = len(particles) if nparts is None else nparts
        log_w = np.asarray(particles.log_weight, dtype=float)
        weights = np.exp(log_w - logsumexp(log_w))
        if nparts is None and 1.0 / np.sum(weights**2) >= self.ess_fraction * len(weights):
            return particles
        cdf = np.cumsum(weights)
        cdf[-1] = 1.0
        u = (self.random_state.uniform() + np.arange(n)) / n
        resampled = particles[np.searchsorted(cdf, u)]
        resampled.log_weight = np.full(n, -np.log(n))
        return resampled


def gaussian_pda_update(hypotheses: Sequence, updater):
    """PDA update of a Gaussian prediction, as Stone Soup's ``PDAUpdater(gm_method=True)``: each
    hypothesis updated by ``updater``, then collapsed with ``beta_h`` in floats."""
    T = stonesoup_types()
    states = [updater.update(h) if h else h.prediction for h in hypotheses]
    beta = np.array([float(h.probability) for h in hypotheses])
    mean, covar = collapse(np.stack([np.asarray(s.state_vector, dtype=float)[:, 0]
                                     for s in states]),
                           np.stack([np.asarray(s.covar, dtype=float) for s in states]), beta)
    prediction = hypotheses[0].prediction
    return T.Update.from_state(prediction, T.StateVector(mean), T.CovarianceMatrix(covar),
                             hypothesis=hypotheses, timestamp=prediction.timestamp)


def collapse(x: np.ndarray, P: np.ndarray, weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Moment-matched Gaussian (n,), (n, n) of means (H, n), covariances (H, n, n), weights (H,)."""
    w = weights / weights.sum()
    mean = w @ x
    d = x - mean
    return mean, np.einsum("h,hij->ij", w, P) + (w[:, None] * d).T @ d


def particle_pda_update(hypotheses: Sequence, updater, resampler: SeededSystematicResampler):
    """PDA update of a particle prediction: weights ``sum_h beta_h w_h``, then ``resampler``."""
    T = stonesoup_types()
    prediction = hypotheses[0].prediction
    terms = []
    for h in hypotheses:
        log_w = updater.update(h).log_weight if h else prediction.log_weight
        terms.append(h.probability.log_value + np.asarray(log_w, dtype=float))
    combined = logsumexp(np.stack(terms), axis=0)
    combined -= logsumexp(combined)
    update = T.Update.from_state(prediction, log_weight=combined, hypothesis=hypotheses,
                               timestamp=prediction.timestamp)
    return resampler.resample(update)
