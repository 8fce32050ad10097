"""The numpy oracle of the compiled IPDA filter (:mod:`trackfuse.tracking.ipda`), batched over
trials: the state update is the PDA oracle's (``pda_reference``, parallel method) and the
existence update evaluates the likelihood ratio ``Lambda`` from its sums over the
validated returns (``docs/papers/twin_sensor.md``, Track existence), where the kernel takes
it from the null hypothesis's weight. The kernel tests pin the two to 1e-9.
"""

from __future__ import annotations

import numpy as np
import pda_reference as pda

from trackfuse.experiments.twin_sensor.model import (
    Batch,
    LossRules,
    Scenario,
    score_estimates,
    score_existence,
)
from trackfuse.tracking.ipda_options import ExistenceModel
from trackfuse.tracking.pda_options import Estimates, PDAOptions


def _detected_term(lin, P_D: float) -> np.ndarray:
    """``P_D sum_i N(nu_i; 0, S) / lambda``: ``(N,)``, zero where nothing was validated or
    ``P_D = 0``."""
    total = np.exp(lin.log_n).sum(axis=1)
    with np.errstate(divide="ignore", invalid="ignore"):
        term = P_D * total / lin.lam
    return np.where((lin.m > 0) & (P_D > 0), term, 0.0)


def likelihood_ratio(Xp: np.ndarray, Pp: np.ndarray, returns: list[pda.SensorReturns],
                     options: PDAOptions) -> np.ndarray:
    """``Lambda: (N,)`` of one scan's validated returns (target exists against all
    clutter) at the predictions ``Xp: (N, 6)``, ``Pp: (N, 6, 6)``, one or two sensors."""
    lins = [pda.linearize(Xp, Pp, ret, options) for ret in returns]
    miss = [1.0 - ret.P_D * options.P_G for ret in returns]
    if len(returns) == 1:
        return miss[0] + _detected_term(lins[0], returns[0].P_D)
    (l1, l2), (r1, r2) = lins, returns
    if options.joint_cov == "full":
        C = l1.H @ Pp @ l2.H.transpose(0, 2, 1)
        S12inv, det12 = pda._block_inverse(l1.S, C, l2.S)
        log_pair = pda._log_joint(l1, l2, S12inv, det12)
    else:
        log_pair = l1.log_n[:, :, None] + l2.log_n[:, None, :]
    ok = l1.ok[:, :, None] & l2.ok[:, None, :]
    pair_sum = np.where(ok, np.exp(log_pair), 0.0).sum(axis=(1, 2))
    both = (l1.m > 0) & (l2.m > 0) & (r1.P_D * r2.P_D > 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        pair = np.where(both, r1.P_D * r2.P_D * pair_sum / (l1.lam * l2.lam), 0.0)
    return (miss[0] * miss[1] + miss[1] * _detected_term(l1, r1.P_D)
            + miss[0] * _detected_term(l2, r2.P_D) + pair)


def existence_update(psi: np.ndarray, Lam: np.ndarray, persistence: float) -> np.ndarray:
    """``psi: (N,)`` after one scan: predicted by the Markov chain, updated with ``Lam``
    (an infinite ratio, a return where no clutter is expected, gives 1)."""
    pred = persistence * psi
    with np.errstate(invalid="ignore"):
        out = Lam * pred / (1.0 - pred + Lam * pred)
    return np.where(np.isposinf(Lam), 1.0, out)


def run_ipda(sc: Scenario, b: Batch, options: PDAOptions, model: ExistenceModel,
             rules: LossRules) -> dict[str, np.ndarray]:
    """Every metric of an IPDA run, ``(N, K)`` each, as the experiment scores it: those of
    ``pda_reference.run_filter`` with the parallel PDA, and the existence metrics."""
    N = b.x0.shape[0]
    X = b.x0.copy()
    P = np.broadcast_to(sc.P0, (N, 6, 6)).copy()
    psi = np.full(N, model.initial)
    existence = np.empty((N, sc.K))
    est = Estimates(np.empty((N, sc.K, 6)), np.empty((N, sc.K, 6, 6)),
                    np.empty((N, sc.K, len(sc.R))), np.empty((N, sc.K), dtype=bool))
    diverged = np.zeros(N, dtype=bool)
    for k in range(1, sc.K + 1):
        Xp = X @ sc.F.T
        Pp = sc.F @ P @ sc.F.T + sc.Q_filter
        returns, inside = pda._scan_returns(sc, b, k, Xp, Pp)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            X, P, m = pda.pda_update(Xp, Pp, returns, options)
            psi = existence_update(psi, likelihood_ratio(Xp, Pp, returns, options),
                                   model.persistence)
        P = 0.5 * (P + P.transpose(0, 2, 1))
        diverged |= ~(np.isfinite(X).all(axis=1) & np.isfinite(P).all(axis=(1, 2)))
        X[diverged], P[diverged], psi[diverged] = np.nan, np.nan, np.nan
        est.X[:, k - 1], est.P[:, k - 1], est.n_valid[:, k - 1] = X, P, m
        est.inside[:, k - 1], existence[:, k - 1] = inside, psi
    return {**score_estimates(sc, b, est, rules), **score_existence(existence, model)}
