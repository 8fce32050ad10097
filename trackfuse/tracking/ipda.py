"""Integrated PDA (IPDA): the parallel PDA of :mod:`trackfuse.tracking.pda` plus the probability
``psi`` that the target exists (numba-compiled).

The state estimate is the PDA's, bit for bit. Existence is a two-state Markov chain with
persistence ``p_s``, updated by the scan's likelihood ratio, taken from the PDA's null
weight ``beta_0`` without a second pass over the returns:

    psi = c psi_pred / (beta_0 (1 - psi_pred) + c psi_pred),   c = prod_s (1 - P_Ds P_G)

(defined when ``beta_0 = 0``). Equations: ``docs/papers/twin_sensor.md``, "Track existence
(IPDA)"; oracle ``tests/ipda_reference.py`` (pinned to 1e-9).

References: Musicki, Evans & Stankovic, IEEE TAC 39(6), 1994; Musicki & Evans, IEEE TAES
40(3), 2004.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from trackfuse.tracking.ipda_options import ExistenceModel
from trackfuse.tracking.pda import (
    _FIRST,
    JIT,
    Linearized,
    Moments,
    _copy_state,
    _linearize,
    _observe,
    _pair_update,
    _predict,
    _single_update,
    _symmetrize_and_check,
)
from trackfuse.tracking.pda_options import METHODS, Estimates, PDAOptions

PARALLEL = METHODS.index("mspda_parallel")


def run_ipda(sc, b, options: PDAOptions, model: ExistenceModel
             ) -> tuple[Estimates, np.ndarray]:
    """Run IPDA over every trial: :class:`Estimates` as ``pda.run_filter`` (``options.method`` must
    be ``"mspda_parallel"``) and existence probabilities (N, K), NaN once a trial diverges.
    """
    if options.method != "mspda_parallel":
        raise ValueError(f"IPDA's state update is the parallel PDA's, got {options.method!r}")
    N, K, S = b.detected.shape
    out = Estimates(np.empty((N, K, 6)), np.empty((N, K, 6, 6)), np.empty((N, K, S), np.int64),
                    np.empty((N, K), dtype=bool))
    existence = np.empty((N, K))
    c = np.ascontiguousarray
    _ipda_batch(
        c(b.x0), c(sc.P0), c(sc.F), c(sc.Q_filter), c(sc.sensor_pos[1:]), c(sc.R), c(sc.P_D),
        c(b.los), c(b.z_target), c(b.detected), c(b.clutter), c(b.clutter_ok), float(sc.gamma),
        float(options.P_G), sc.clutter_model == "in_gate", float(sc.clutter_mean),
        float(sc.window_density), options.covariance == "mgekf", options.joint_cov == "full",
        options.density == "nonparametric", options.mg_at == "combined",
        float(model.persistence), float(model.initial), out.X, out.P, out.n_valid, out.inside,
        existence)
    return out, existence


@njit(**JIT)
def _ipda_batch(x0, P0, F, Q, sensor_pos, R, P_D, los, z_target, detected, clutter,
                clutter_ok, gamma, P_G, in_gate, clutter_mean, window_density, mgekf,
                joint_full, nonparametric, mg_combined, persistence, initial, X_out, P_out,
                m_out, inside_out, psi_out):
    """``pda._filter_batch``'s outputs, same bits, plus ``psi_out`` (N, K) after each update."""
    N, K, S = detected.shape
    M = clutter.shape[3] + 1
    lin, mom = Linearized(S, M), Moments(M)
    z, valid, lam_true = np.empty((S, M, 2)), np.empty((S, M), np.bool_), np.empty(S)
    X, P, Xp, Pp = np.empty(6), np.empty((6, 6)), np.empty(6), np.empty((6, 6))
    miss = 1.0  # prod_s (1 - P_Ds P_G)
    for s in range(S):
        miss *= 1.0 - P_D[s] * P_G
    for n in range(N):
        _copy_state(x0[n], P0, X, P)
        psi = initial
        diverged = False
        for k in range(K):
            if diverged:
                X_out[n, k], P_out[n, k], m_out[n, k], inside_out[n, k] = np.nan, np.nan, 0, False
                psi_out[n, k] = np.nan
                continue
            _predict(X, P, F, Q, Xp, Pp, mom.FP)
            inside_out[n, k] = _observe(
                Xp, Pp, sensor_pos[k], R, los[n, k], z_target[n, k], detected[n, k],
                clutter[n, k], clutter_ok[n, k], gamma, in_gate, clutter_mean, window_density,
                lin, z, valid, lam_true)
            for s in range(S):
                _linearize(z[s], valid[s], lam_true[s], gamma, mgekf, nonparametric, lin, s)
            if S == 2:
                b_null = _pair_update(Xp, Pp, R, P_D, P_G, PARALLEL, joint_full, mg_combined,
                                      lin, mom, X, P)
            else:
                _copy_state(Xp, Pp, X, P)
                b_null = _single_update(X, P, R[0], P_D[0], P_G, False, mg_combined, lin,
                                        _FIRST, mom)
            psi_pred = persistence * psi
            psi = miss * psi_pred / (b_null * (1.0 - psi_pred) + miss * psi_pred)
            for s in range(S):
                m_out[n, k, s] = lin.m[s]
            diverged = _symmetrize_and_check(X, P)
            if diverged:
                X[:] = np.nan
                P[:, :] = np.nan
                psi = np.nan
            _copy_state(X, P, X_out[n, k], P_out[n, k])
            psi_out[n, k] = psi
