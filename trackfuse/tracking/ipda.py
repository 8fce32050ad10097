"""Integrated PDA (IPDA) for one or two passive az/el sensors: the parallel PDA of
:mod:`trackfuse.tracking.pda` plus the probability that the target exists (numba-compiled).

The state estimate is the PDA's: given that the target exists, IPDA's association
probabilities are the PDA's (one sensor: the PDAF; two: the parallel multisensor PDA with the
fused update). What IPDA adds is the existence probability ``psi`` of the track
(``docs/papers/twin_sensor.md``, Track existence), a two-state Markov chain (exists, does
not) predicted and updated every scan:

    psi_pred = p_s psi                                 (p_s: persistence, no birth)
    psi      = Lambda psi_pred / (1 - psi_pred + Lambda psi_pred)

where ``Lambda`` is the likelihood ratio of the scan's validated returns under "the target
exists" against "all are clutter" (Poisson clutter of density ``lambda_s``). One sensor:

    Lambda = 1 - P_D P_G + P_D sum_i N(nu_i; 0, S) / lambda

(Musicki, Evans & Stankovic 1994); two sensors, every joint hypothesis of the fused update:

    Lambda = (1 - P_D1 P_G)(1 - P_D2 P_G) + P_D1 (1 - P_D2 P_G) sum_i N_1i / lambda_1
             + (1 - P_D1 P_G) P_D2 sum_j N_2j / lambda_2
             + P_D1 P_D2 sum_ij N([nu_1i; nu_2j]; 0, S_12) / (lambda_1 lambda_2).

Both are the sum of the PDA's unnormalized hypothesis weights over the weight the "all
clutter" hypothesis would have, so ``Lambda = prod_s (1 - P_Ds P_G) / beta_0`` with
``beta_0`` the PDA's probability of the hypothesis that no sensor saw the target; the
kernel takes it from there (no second pass over the returns):

    psi = c psi_pred / (beta_0 (1 - psi_pred) + c psi_pred),   c = prod_s (1 - P_Ds P_G),

which stays defined when ``beta_0 = 0`` (no clutter expected, a return validated: ``psi =
1``). The numpy oracle, ``tests/ipda_reference.py``, evaluates ``Lambda`` from the sums
above instead; the tests pin the two to 1e-9.

References
----------
D. Musicki, R. Evans and S. Stankovic, "Integrated probabilistic data association", IEEE
Trans. Automatic Control 39(6), 1994.
D. Musicki and R. Evans, "Joint integrated probabilistic data association: JIPDA", IEEE
Trans. Aerospace and Electronic Systems 40(3), 2004 (the Markov chains of existence).
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
    _geometry,
    _in_gate,
    _linearize,
    _pair_update,
    _place_returns,
    _predict,
    _single_update,
    _symmetrize_and_check,
)
from trackfuse.tracking.pda_options import METHODS, Estimates, PDAOptions

PARALLEL = METHODS.index("mspda_parallel")


def run_ipda(sc, b, options: PDAOptions, model: ExistenceModel
             ) -> tuple[Estimates, np.ndarray]:
    """Run IPDA over every trial of a batch: the per-scan estimates (as
    :func:`trackfuse.tracking.pda.run_filter` with ``options.method = "mspda_parallel"``,
    which ``options.method`` must be) and the existence probabilities ``(N, K)`` (NaN from
    the scan a trial diverges).

    ``sc`` and ``b`` are the scenario and batch of
    :func:`trackfuse.tracking.pda.run_filter`; ``model`` the existence model.
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
    """Filter every trial of a batch; the outputs of ``pda._filter_batch`` plus
    ``psi_out: (N, K)``, the existence probability after each scan's update. The state
    update is ``pda._filter_batch``'s for the parallel method, step for step (the
    estimates are the same bits)."""
    N, K, S = detected.shape
    M = clutter.shape[3] + 1
    lin, mom = Linearized(S, M), Moments()
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
            _predict(X, P, F, Q, Xp, Pp)
            inside = False
            for s in range(S):
                _geometry(Xp, Pp, sensor_pos[k, s], R[s], lin, s)
                inside |= _in_gate(los[n, k, s], lin, s, gamma)
                lam_true[s] = _place_returns(
                    z_target[n, k, s], detected[n, k, s], clutter[n, k, s], clutter_ok[n, k, s],
                    gamma, in_gate, clutter_mean, window_density, lin, s, z[s], valid[s])
                _linearize(z[s], valid[s], lam_true[s], gamma, mgekf, nonparametric, lin, s)
            inside_out[n, k] = inside
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
