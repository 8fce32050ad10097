"""Probabilistic data association for one or two passive az/el sensors (numba-compiled):
per scan predict, place each sensor's returns, gate, and update with the exact collapse of
the per-hypothesis MGEKF (or EKF) updates. Variants (``method``): ``mspda_parallel``,
``mspda_sequential``, ``nn``, ``paper_approx`` (W000-1). Equations: ``docs/papers/twin_sensor.md``,
"Two-sensor PDA"; numpy oracle ``tests/pda_reference.py`` (pinned to 1e-9).

References: Bar-Shalom & Fortmann, *Tracking and Data Association*, 1988; Bar-Shalom & Li,
*Multitarget-Multisensor Tracking*, 1995, ch. 8; Pao & Frei, Proc. ACC, 1995."""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from trackfuse.tracking.pda_options import METHODS, Estimates, PDAOptions

SEQUENTIAL, NEAREST, PAPER_APPROX = (METHODS.index(m) for m in (
    "mspda_sequential", "nn", "paper_approx"))
LOG_2PI = math.log(2.0 * math.pi)
TWO_PI = 2.0 * math.pi
JIT = {"cache": True, "nogil": True, "error_model": "numpy"}
#: Callees run only from compiled code: no Python or C entry point to compile for them.
INNER = {**JIT, "no_cpython_wrapper": True, "no_cfunc_wrapper": True}
#: The sensor indices (and each sensor's first row in the moments) as int64
#: values: a literal 0 or 1 in a call would compile one more copy of the called function
#: per constant, each about a second of the first run after installing.
_FIRST, _SECOND = np.int64(0), np.int64(1)
_FIRST_ROWS, _SECOND_ROWS = np.int64(0), np.int64(2)


def run_filter(sc, b, options: PDAOptions) -> Estimates:
    """Run one algorithm over every trial of twin_sensor batch ``b`` in scenario ``sc``."""
    N, K, S = b.detected.shape
    out = Estimates(np.empty((N, K, 6)), np.empty((N, K, 6, 6)), np.empty((N, K, S), np.int64),
                    np.empty((N, K), dtype=bool))
    c = np.ascontiguousarray  # one compiled specialization for every call
    _filter_batch(
        c(b.x0), c(sc.P0), c(sc.F), c(sc.Q_filter), c(sc.sensor_pos[1:]), c(sc.R), c(sc.P_D),
        c(b.los), c(b.z_target), c(b.detected), c(b.clutter), c(b.clutter_ok), float(sc.gamma),
        float(options.P_G), sc.clutter_model == "in_gate", float(sc.clutter_mean),
        float(sc.window_density), METHODS.index(options.method), options.covariance == "mgekf",
        options.joint_cov == "full", options.density == "nonparametric",
        options.mg_at == "combined", out.X, out.P, out.n_valid, out.inside)
    return out


# Columns of a sensor's geometry row ``geom[s]`` (see :func:`_geometry`): target-minus-sensor
# position (m), predicted azimuth and elevation (rad), ``det S``, gate area (rad^2) and the
# clutter density used (1/rad^2).
D, ZH, DET, AREA, LAM = 0, 3, 5, 6, 7


@njit(**JIT)
def _filter_batch(x0, P0, F, Q, sensor_pos, R, P_D, los, z_target, detected, clutter,
                  clutter_ok, gamma, P_G, in_gate, clutter_mean, window_density, method, mgekf,
                  joint_full, nonparametric, mg_combined, X_out, P_out, m_out, inside_out):
    """Filter every trial into ``X_out`` (N, K, 6), ``P_out`` (N, K, 6, 6) (NaN once diverged),
    ``m_out`` (N, K, S), ``inside_out`` (N, K); ``sensor_pos`` (K, S, 3) for scans 1..K."""
    N, K, S = detected.shape
    M = clutter.shape[3] + 1  # the target return first, then the clutter slots
    lin, mom = Linearized(S, M), Moments(M)
    z, valid, lam_true = np.empty((S, M, 2)), np.empty((S, M), np.bool_), np.empty(S)
    X, P, Xp, Pp = np.empty(6), np.empty((6, 6)), np.empty(6), np.empty((6, 6))
    pair = S == 2 and method != SEQUENTIAL
    for n in range(N):
        _copy_state(x0[n], P0, X, P)
        diverged = False
        for k in range(K):
            if diverged:  # as the oracle: no return validated, target outside every gate
                X_out[n, k], P_out[n, k], m_out[n, k], inside_out[n, k] = np.nan, np.nan, 0, False
                continue
            _predict(X, P, F, Q, Xp, Pp, mom.FP)
            inside_out[n, k] = _observe(
                Xp, Pp, sensor_pos[k], R, los[n, k], z_target[n, k], detected[n, k],
                clutter[n, k], clutter_ok[n, k], gamma, in_gate, clutter_mean, window_density,
                lin, z, valid, lam_true)
            if pair:
                for s in range(S):  # the geometry at the prediction is already in place
                    _linearize(z[s], valid[s], lam_true[s], gamma, mgekf, nonparametric, lin, s)
                _pair_update(Xp, Pp, R, P_D, P_G, method, joint_full, mg_combined, lin, mom, X, P)
            else:
                _copy_state(Xp, Pp, X, P)
                for s in range(S):
                    if s > 0:  # sensor 1 sees the prediction, whose geometry is in place
                        _geometry(X, P, sensor_pos[k, s], R[s], lin, s)
                    _linearize(z[s], valid[s], lam_true[s], gamma, mgekf, nonparametric, lin, s)
                    _single_update(X, P, R[s], P_D[s], P_G, method == NEAREST, mg_combined,
                                   lin, s, mom)
            for s in range(S):  # element by element: see _copy_state
                m_out[n, k, s] = lin.m[s]
            diverged = _symmetrize_and_check(X, P)
            if diverged:
                X[:] = np.nan
                P[:, :] = np.nan
            _copy_state(X, P, X_out[n, k], P_out[n, k])


@njit(**INNER)
def Linearized(S, M):  # noqa: N802 (builds a record, read as a type)
    """Per-sensor arrays of one scan, reused for every trial and scan.

    Geometry (:func:`_geometry`): ``geom (S, 8)`` (columns :data:`D`, :data:`ZH`, ...),
    ``H (S, 2, 3)`` position columns of the Jacobian, ``PHt (S, 6, 2)``, ``Sm, Si (S, 2, 2)``
    innovation covariance and its inverse, ``Kg (S, 6, 2)`` gain. Hypotheses
    (:func:`_linearize`): ``nu (S, M, 2)``, ``G (S, M, 2, 3)``, ``log_n (S, M)`` of each
    validated return, whose indices are the first ``m (S,)`` entries of ``ok (S, M)``; then
    the weights ``w (S, M)`` of the one-sensor hypotheses and ``B (M, M)`` of the pairs."""
    return _Lin(np.empty((S, 8)), np.empty((S, 2, 3)), np.empty((S, 6, 2)),
                np.empty((S, 2, 2)), np.empty((S, 2, 2)), np.empty((S, 6, 2)),
                np.empty((S, M, 2)), np.empty((S, M, 2, 3)), np.empty((S, M)),
                np.empty((S, M), np.int64), np.zeros(S, np.int64), np.empty((S, M)),
                np.empty((M, M)))


_Lin = namedtuple("_Lin", "geom H PHt Sm Si Kg nu G log_n ok m w B")


@njit(**INNER)
def _copy_state(X, P, X_to, P_to):
    """``X_to = X`` (6,), ``P_to = P`` (6, 6) element by element (cheaper to compile)."""
    for i in range(6):
        X_to[i] = X[i]
        for j in range(6):
            P_to[i, j] = P[i, j]


@njit(**INNER)
def _wrap(a):
    """Angle (rad) mapped to [-pi, pi), as ``(a + pi) % 2pi - pi`` computes it; an angle
    within one turn skips the remainder (exact there: ``x`` itself or ``x + 2pi``)."""
    x = a + math.pi
    if 0.0 < x < TWO_PI:
        return x - math.pi
    if -TWO_PI < x < 0.0:
        return (x + TWO_PI) - math.pi
    return x % TWO_PI - math.pi


@njit(**INNER)
def _predict(X, P, F, Q, Xp, Pp, FP):
    """``Xp = F X``, ``Pp = F P F' + Q`` (``FP`` (6, 6): scratch). The zero entries of ``F``
    are skipped: their products are zeros, which leave a sum started at +0.0 unchanged
    while ``X``, ``P`` and ``F P`` are finite (a diverged trial is not predicted), so the
    bits are those of the full products."""
    for i in range(6):
        acc = 0.0
        for j in range(6):
            FP[i, j] = 0.0
        for a in range(6):
            f = F[i, a]
            if f != 0.0:
                acc += f * X[a]
                for j in range(6):
                    FP[i, j] += f * P[a, j]
        Xp[i] = acc
    for i in range(6):
        for j in range(6):
            acc = 0.0
            for a in range(6):
                f = F[j, a]
                if f != 0.0:
                    acc += FP[i, a] * f
            Pp[i, j] = acc + Q[i, j]


@njit(**INNER)
def _inv2(A, out):
    """Closed-form inverse of a 2x2 matrix into ``out``; returns the determinant."""
    det = A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    out[0, 0], out[0, 1] = A[1, 1] / det, -A[0, 1] / det
    out[1, 0], out[1, 1] = -A[1, 0] / det, A[0, 0] / det
    return det


@njit(**INNER)
def _mahalanobis2(n0, n1, Si):
    """``nu' Si nu`` for ``nu = (n0, n1)`` and a 2x2 ``Si``, summed as the oracle does."""
    return (n0 * Si[0, 0] + n1 * Si[1, 0]) * n0 + (n0 * Si[0, 1] + n1 * Si[1, 1]) * n1


@njit(**INNER)
def _observe(Xp, Pp, sensor_pos, R, los, z_target, detected, clutter, clutter_ok, gamma,
             in_gate, clutter_mean, window_density, lin, z, valid, lam_true):
    """One scan's geometry at the prediction and returns placed for gating, every sensor
    (``sensor_pos`` (S, 3), ``los`` (S, 2), ...); True when the target is in some gate."""
    inside = False
    for s in range(len(lam_true)):
        _geometry(Xp, Pp, sensor_pos[s], R[s], lin, s)
        inside |= _in_gate(los[s], lin, s, gamma)
        lam_true[s] = _place_returns(
            z_target[s], detected[s], clutter[s], clutter_ok[s], gamma, in_gate, clutter_mean,
            window_density, lin, s, z[s], valid[s])
    return inside


@njit(**INNER)
def _geometry(X, P, pos, R, lin, s):
    """Sensor ``s`` seen from ``(X, P)``: relative position, predicted angles, ``H``,
    ``PHt = P[:, :3] H'``, ``S`` and its inverse, gate area and gain, into ``lin``."""
    g, H, PHt, Sm, Si, Kg = lin.geom[s], lin.H[s], lin.PHt[s], lin.Sm[s], lin.Si[s], lin.Kg[s]
    dx, dy, dz = X[0] - pos[0], X[1] - pos[1], X[2] - pos[2]
    g[D], g[D + 1], g[D + 2] = dx, dy, dz
    g[ZH], g[ZH + 1] = math.atan2(dy, dx), math.atan2(dz, math.hypot(dx, dy))
    rh2 = dx * dx + dy * dy
    rh = math.sqrt(rh2)
    r2 = rh2 + dz * dz
    H[0, 0], H[0, 1], H[0, 2] = -dy / rh2, dx / rh2, 0.0
    H[1, 0], H[1, 1], H[1, 2] = -dx * dz / (rh * r2), -dy * dz / (rh * r2), rh / r2
    for i in range(6):
        for j in range(2):
            PHt[i, j] = P[i, 0] * H[j, 0] + P[i, 1] * H[j, 1] + P[i, 2] * H[j, 2]
    for i in range(2):
        for j in range(2):
            Sm[i, j] = H[i, 0] * PHt[0, j] + H[i, 1] * PHt[1, j] + H[i, 2] * PHt[2, j] + R[i, j]
    g[DET] = _inv2(Sm, Si)
    for i in range(6):
        for j in range(2):
            Kg[i, j] = PHt[i, 0] * Si[0, j] + PHt[i, 1] * Si[1, j]


@njit(**INNER)
def _gate_area(gamma, det):
    """Area (rad^2) of the gate ``nu' S^-1 nu <= gamma`` of a 2x2 ``S`` with determinant ``det``."""
    return math.pi * gamma * math.sqrt(det)


@njit(**INNER)
def _in_gate(los, lin, s, gamma):
    """Whether the noise-free target return ``los`` lies in sensor ``s``'s gate at ``lin``."""
    g = lin.geom[s]
    n0, n1 = _wrap(los[0] - g[ZH]), _wrap(los[1] - g[ZH + 1])
    return _mahalanobis2(n0, n1, lin.Si[s]) <= gamma


@njit(**INNER)
def _place_returns(z_target, detected, clutter, clutter_ok, gamma, in_gate, clutter_mean,
                   window_density, lin, s, z, valid):
    """Sensor ``s``'s returns at one scan into ``z (M, 2)``, ``valid (M,)``: the target
    return, then the clutter (unit-disk draws mapped into the gate at the geometry in ``lin``,
    or absolute window angles). Returns the true clutter density (1/rad^2)."""
    z[0, 0], z[0, 1] = z_target[0], z_target[1]
    valid[0] = detected
    for c in range(clutter.shape[0]):
        valid[1 + c] = clutter_ok[c]
    if not in_gate:
        for c in range(clutter.shape[0]):
            z[1 + c, 0], z[1 + c, 1] = clutter[c, 0], clutter[c, 1]
        return window_density
    g, Sm = lin.geom[s], lin.Sm[s]
    l11 = math.sqrt(Sm[0, 0])  # lower Cholesky factor of S
    l21 = Sm[1, 0] / l11
    l22 = math.sqrt(Sm[1, 1] - l21 * l21)
    root = math.sqrt(gamma)
    for c in range(clutter.shape[0]):
        if clutter_ok[c]:
            u0, u1 = clutter[c, 0], clutter[c, 1]
            z[1 + c, 0] = g[ZH] + root * (u0 * l11 + u1 * 0.0)
            z[1 + c, 1] = g[ZH + 1] + root * (u0 * l21 + u1 * l22)
    return clutter_mean / _gate_area(gamma, g[DET])


@njit(**INNER)
def _modified_rows(z0, z1, g, G):
    """Song-Speyer modified position rows ``G (2, 3)`` at angles ``(z0, z1)``, geometry ``g``."""
    c_th, s_th = math.cos(z0), math.sin(z0)
    c_ph, s_ph = math.cos(z1), math.sin(z1)
    rho = g[D] * c_th + g[D + 1] * s_th
    inv_el = 1.0 / (rho * c_ph + g[D + 2] * s_ph)
    inv_az = 1.0 / rho
    G[0, 0], G[0, 1], G[0, 2] = -s_th * inv_az, c_th * inv_az, 0.0
    G[1, 0], G[1, 1], G[1, 2] = -s_ph * c_th * inv_el, -s_ph * s_th * inv_el, c_ph * inv_el


@njit(**INNER)
def _linearize(z, valid, lam_true, gamma, mgekf, nonparametric, lin, s):
    """Gate sensor ``s``'s returns ``z (M, 2)`` at the geometry in ``lin``: innovations,
    ``G`` rows (modified rows or ``H``) and log-likelihoods of the validated returns, their
    count and the clutter density used (oracle: ``pda_reference.linearize``)."""
    g, H, Si = lin.geom[s], lin.H[s], lin.Si[s]
    nu, G, log_n, ok = lin.nu[s], lin.G[s], lin.log_n[s], lin.ok[s]
    det = g[DET]
    half_logdet = 0.5 * math.log(det) if det > 0 else np.nan
    count = 0
    for i in range(z.shape[0]):
        if not valid[i]:
            continue
        n0, n1 = _wrap(z[i, 0] - g[ZH]), _wrap(z[i, 1] - g[ZH + 1])
        d2 = _mahalanobis2(n0, n1, Si)
        if not (d2 <= gamma and det > 0):
            continue
        nu[i, 0], nu[i, 1] = n0, n1
        log_n[i] = -0.5 * d2 - LOG_2PI - half_logdet
        if mgekf:
            _modified_rows(z[i, 0], z[i, 1], g, G[i])
        else:
            for r in range(2):
                for c in range(3):
                    G[i, r, c] = H[r, c]
        ok[count] = i
        count += 1
    lin.m[s] = count
    g[AREA] = _gate_area(gamma, det)
    g[LAM] = count / g[AREA] if nonparametric else lam_true


@njit(**INNER)
def _log_null(lin, s, P_D, P_G):
    """``log f_s(0)`` of sensor ``s``: zero when it validated nothing."""
    if lin.m[s] == 0:
        return 0.0
    return math.log1p(-P_D * P_G) + _log(lin.geom[s, LAM])


@njit(**INNER)
def _log(x):
    """``math.log(x)`` as compiled code computes it (``-inf`` at 0, NaN below), also without JIT."""
    if x > 0:
        return math.log(x)
    return -np.inf if x == 0 else np.nan


@njit(**INNER)
def _at_combined(lin, s, w):
    """Re-evaluate sensor ``s``'s modified rows of every validated return at the combined
    return ``h(Xp) + sum w_i nu_i / sum w_i`` (``mg_at = "combined"``), weights ``w (M,)``."""
    g, nu, G, ok = lin.geom[s], lin.nu[s], lin.G[s], lin.ok[s]
    total, n0, n1 = 0.0, 0.0, 0.0
    for a in range(lin.m[s]):
        i = ok[a]
        total += w[i]
        n0 += w[i] * nu[i, 0]
        n1 += w[i] * nu[i, 1]
    scale = total if total > 0 else 1.0
    _modified_rows(_wrap(g[ZH] + n0 / scale), _wrap(g[ZH + 1] + n1 / scale), g, G[ok[0]])
    for a in range(1, lin.m[s]):
        for r in range(2):
            for c in range(3):
                G[ok[a], r, c] = G[ok[0], r, c]


@njit(**INNER)
def _nan_max(a, b):
    """``max(a, b)`` that propagates NaN, as ``numpy.max`` does."""
    if math.isnan(a) or math.isnan(b):
        return np.nan
    return a if a >= b else b


@njit(**INNER)
def _beats(value, best):
    """``numpy.argmax``'s rule: a later entry wins only if larger, or NaN after no NaN."""
    if math.isnan(best):
        return False
    return math.isnan(value) or value > best


@njit(**INNER)
def _single_update(X, P, R, P_D, P_G, nearest, mg_combined, lin, s, mom):
    """Single-sensor PDA update of ``(X, P)`` in place with sensor ``s``; returns the null
    hypothesis's weight (oracle: ``pda_reference._single_update``)."""
    ok, w, m = lin.ok[s], lin.w[s], lin.m[s]
    log0 = _log_null(lin, s, P_D, P_G)
    log_pd = _log(P_D)
    top = log0
    for a in range(m):
        i = ok[a]
        w[i] = log_pd + lin.log_n[s, i]
        top = _nan_max(top, w[i])
    if not math.isfinite(top):  # nothing explains the data but the null
        log0, top = 0.0, 0.0
    if nearest:
        best, best_val = -1, log0
        for a in range(m):
            if _beats(w[ok[a]], best_val):
                best, best_val = ok[a], w[ok[a]]
        for a in range(m):
            w[ok[a]] = 1.0 if ok[a] == best else 0.0
        b0 = 1.0 if best < 0 else 0.0
    else:
        b0 = math.exp(log0 - top)
        total = b0
        for a in range(m):
            w[ok[a]] = math.exp(w[ok[a]] - top)
            total += w[ok[a]]
        b0 /= total
        for a in range(m):
            w[ok[a]] /= total
    if mg_combined and m > 0:
        _at_combined(lin, s, w)
    _clear(mom)
    bsum = _single_moments(lin, s, w, P, mom, _FIRST_ROWS)
    _class_terms(lin.Kg[s], R, P, bsum, mom)
    _collapse(X, P, b0, mom)
    return b0


_Mom = namedtuple("_Mom", "nub NN Gbar C dx dP GP KR KA FP Cx S12inv K12 R12 blocks W col r c")


@njit(**INNER)
def Moments(M):  # noqa: N802 (builds a record, read as a type)
    """Weighted moments of one hypothesis class (``n = 2`` or ``4`` rows used):
    ``nub = sum b nu (4,)``, ``NN = sum b nu nu' (4, 4)``, ``Gbar = sum b G (4, 3)``,
    ``C = sum b G P33 G' (4, 4)``; the update sums ``dx (6,)``, ``dP (6, 6)``; scratch,
    allocated once for every trial and scan: ``GP (4, 6)``, ``KR, KA (6, 4)``, ``FP (6, 6)``
    (:func:`_predict`), the pair update's ``Cx (2, 2)``, ``S12inv, R12 (4, 4)``, ``K12 (6,
    4)``, ``blocks (5, 2, 2)`` (:func:`_block_inverse`), ``W (2, 3)`` and per return slot
    ``col, r, c (M,)``."""
    return _Mom(np.zeros(4), np.zeros((4, 4)), np.zeros((4, 3)), np.zeros((4, 4)),
                np.zeros(6), np.zeros((6, 6)), np.zeros((4, 6)), np.zeros((6, 4)),
                np.zeros((6, 4)), np.zeros((6, 6)), np.zeros((2, 2)), np.zeros((4, 4)),
                np.zeros((6, 4)), np.zeros((4, 4)), np.zeros((5, 2, 2)), np.zeros((2, 3)),
                np.zeros(M), np.zeros(M), np.zeros(M))


@njit(**INNER)
def _clear(mom):
    """Zero the moments and the update sums."""
    _clear_class(mom)
    mom.dx[:] = 0.0
    mom.dP[:, :] = 0.0


@njit(**INNER)
def _clear_class(mom):
    """Zero the moments only (the next hypothesis class adds to the same update sums)."""
    mom.nub[:] = 0.0
    mom.NN[:, :] = 0.0
    mom.Gbar[:, :] = 0.0
    mom.C[:, :] = 0.0


@njit(**INNER)
def _single_moments(lin, s, w, P, mom, off):
    """Add sensor ``s``'s moments with weights ``w (M,)`` to rows ``off, off + 1`` of ``mom``;
    returns ``sum w`` (oracle: ``pda_reference._single_moments``)."""
    nu, G, ok = lin.nu[s], lin.G[s], lin.ok[s]
    nub, NN, Gbar, C = mom.nub, mom.NN, mom.Gbar, mom.C
    bsum = 0.0
    for a in range(lin.m[s]):
        i = ok[a]
        b = w[i]
        bsum += b
        Gi = G[i]
        for r in range(2):
            gp0 = Gi[r, 0] * P[0, 0] + Gi[r, 1] * P[1, 0] + Gi[r, 2] * P[2, 0]
            gp1 = Gi[r, 0] * P[0, 1] + Gi[r, 1] * P[1, 1] + Gi[r, 2] * P[2, 1]
            gp2 = Gi[r, 0] * P[0, 2] + Gi[r, 1] * P[1, 2] + Gi[r, 2] * P[2, 2]
            nub[off + r] += b * nu[i, r]
            for c in range(2):
                NN[off + r, off + c] += b * nu[i, r] * nu[i, c]
                C[off + r, off + c] += b * (gp0 * Gi[c, 0] + gp1 * Gi[c, 1] + gp2 * Gi[c, 2])
            for c in range(3):
                Gbar[off + r, c] += b * Gi[r, c]
    return bsum


@njit(**INNER)
def _class_terms(Kg, R, P, bsum, mom):
    """Add one hypothesis class with gain ``Kg (6, n)`` to the update sums: ``dx += K nub``,
    ``dP += bsum (P + K R K') - K Gbar P[:3] - (.)' + K (C + NN) K'``
    (oracle: ``pda_reference._class_terms``)."""
    n = Kg.shape[1]
    nub, NN, Gbar, C, dx, dP = mom.nub, mom.NN, mom.Gbar, mom.C, mom.dx, mom.dP
    GP, KR, KA = mom.GP, mom.KR, mom.KA
    for r in range(n):
        for c in range(6):
            GP[r, c] = Gbar[r, 0] * P[0, c] + Gbar[r, 1] * P[1, c] + Gbar[r, 2] * P[2, c]
    for i in range(6):
        for a in range(n):
            dx[i] += Kg[i, a] * nub[a]
            kr, ka = 0.0, 0.0
            for b in range(n):
                kr += Kg[i, b] * R[b, a]
                ka += Kg[i, b] * (C[b, a] + NN[b, a])
            KR[i, a], KA[i, a] = kr, ka
    for i in range(6):
        for j in range(6):
            krk, kak, kgp_ij, kgp_ji = 0.0, 0.0, 0.0, 0.0
            for a in range(n):
                krk += KR[i, a] * Kg[j, a]
                kak += KA[i, a] * Kg[j, a]
                kgp_ij += Kg[i, a] * GP[a, j]
                kgp_ji += Kg[j, a] * GP[a, i]
            dP[i, j] += bsum * (P[i, j] + krk) - kgp_ij - kgp_ji + kak


@njit(**INNER)
def _collapse(X, P, b0, mom):
    """``X += dx``, ``P = b0 P + dP - dx dx'`` in place."""
    dx, dP = mom.dx, mom.dP
    for i in range(6):
        for j in range(6):
            P[i, j] = b0 * P[i, j] + dP[i, j] - dx[i] * dx[j]
    for i in range(6):
        X[i] += dx[i]


@njit(**INNER)
def _pair_update(Xp, Pp, R, P_D, P_G, method, joint_full, mg_combined, lin, mom, X, P):
    """Two-sensor PDA update of ``(Xp, Pp)`` into ``(X, P)``; returns the null's weight."""
    H, PHt = lin.H, lin.PHt
    Cx = mom.Cx  # H1 P H2'
    for i in range(2):
        for j in range(2):
            Cx[i, j] = (H[0, i, 0] * PHt[1, 0, j] + H[0, i, 1] * PHt[1, 1, j]
                        + H[0, i, 2] * PHt[1, 2, j])
    S12inv, K12 = mom.S12inv, mom.K12
    det12 = _block_inverse(lin.Sm[0], Cx, lin.Sm[1], S12inv, mom.blocks)
    K12[:, :] = 0.0
    for i in range(6):
        for j in range(4):
            for a in range(4):
                K12[i, j] += PHt[a // 2, i, a % 2] * S12inv[a, j]
    log00, top = _pair_log_weights(lin, S12inv, det12, P_D, P_G, method, joint_full, mom.col)
    b00 = _normalize_pair(lin, log00, top, method == NEAREST)
    if mg_combined:
        _pair_at_combined(lin)
    _clear(mom)
    for s in range(2):
        bsum = _single_moments(lin, s, lin.w[s], Pp, mom, _FIRST_ROWS)
        _class_terms(lin.Kg[s], R[s], Pp, bsum, mom)
        _clear_class(mom)
    bsum = _pair_moments(lin, Pp, mom)
    R12 = mom.R12  # block-diagonal; its other entries stay zero
    for i in range(2):
        for j in range(2):
            R12[i, j], R12[2 + i, 2 + j] = R[0, i, j], R[1, i, j]
    _class_terms(K12, R12, Pp, bsum, mom)
    _copy_state(Xp, Pp, X, P)
    _collapse(X, P, b00, mom)
    return b00


@njit(**INNER)
def _block_inverse(A, Bx, D_, out, blocks):
    """Inverse of ``[[A, Bx], [Bx', D_]]`` (2x2 blocks) into ``out (4, 4)`` by the Schur
    complement (``blocks (5, 2, 2)``: scratch); returns the determinant (oracle:
    ``pda_reference._block_inverse``)."""
    Ai, Sc, Sci, AiB, TR = blocks[0], blocks[1], blocks[2], blocks[3], blocks[4]
    detA = _inv2(A, Ai)
    for i in range(2):
        for j in range(2):
            AiB[i, j] = Ai[i, 0] * Bx[0, j] + Ai[i, 1] * Bx[1, j]
    for i in range(2):
        for j in range(2):
            Sc[i, j] = D_[i, j] - (Bx[0, i] * AiB[0, j] + Bx[1, i] * AiB[1, j])
    detSc = _inv2(Sc, Sci)
    for i in range(2):
        for j in range(2):
            TR[i, j] = -(AiB[i, 0] * Sci[0, j] + AiB[i, 1] * Sci[1, j])
    for i in range(2):
        for j in range(2):
            out[i, j] = Ai[i, j] - (TR[i, 0] * AiB[j, 0] + TR[i, 1] * AiB[j, 1])
            out[i, 2 + j] = TR[i, j]
            out[2 + j, i] = TR[i, j]
            out[2 + i, 2 + j] = Sci[i, j]
    return detA * detSc


@njit(**INNER)
def _pair_log_weights(lin, S12inv, det12, P_D, P_G, method, joint_full, col):
    """Log weights of the two-sensor hypotheses into ``lin.w`` (one return) and ``lin.B`` (both);
    returns the null's and the largest (oracle: ``pda_reference.pair_weights``); ``col``
    (M,): scratch."""
    ok, m, log_n, nu, w, B, geom = lin.ok, lin.m, lin.log_n, lin.nu, lin.w, lin.B, lin.geom
    m1, m2 = m[0], m[1]
    if method == PAPER_APPROX:
        P_Dor = 1.0 - (1.0 - P_D[0]) * (1.0 - P_D[1])
        P_Gf = 1.0 - (1.0 - P_G) ** 2
        m_k, m_f = (m1 + 1) * (m2 + 1), m1 + m2
        lam_area = geom[0, LAM] * geom[0, AREA] + geom[1, LAM] * geom[1, AREA]
        log00 = (math.log1p(-P_Dor * P_Gf) + _log(lam_area) - math.log(m_f)
                 if m_f > 0 else 0.0)
        common = (_log(P_Dor) + (math.log(geom[0, AREA]) + math.log(geom[1, AREA]))
                  - math.log(m_k - 1.0) if m_k > 1 else 0.0)
        off1, off2 = common - math.log(geom[1, AREA]), common - math.log(geom[0, AREA])
        pair_add = common
    else:
        f1 = _log_null(lin, _FIRST, P_D[0], P_G)
        f2 = _log_null(lin, _SECOND, P_D[1], P_G)
        lp1, lp2 = _log(P_D[0]), _log(P_D[1])
        log00 = f1 + f2
        off1, off2 = lp1 + f2, f1 + lp2
        pair_add = lp1 + lp2
    top = log00
    for a in range(m1):
        i = ok[0, a]
        w[0, i] = off1 + log_n[0, i]
        top = _nan_max(top, w[0, i])
    for b in range(m2):
        j = ok[1, b]
        w[1, j] = off2 + log_n[1, j]
        top = _nan_max(top, w[1, j])
    joint = method == PAPER_APPROX or joint_full
    half_logdet12 = 0.5 * math.log(det12) if det12 > 0 else (
        -np.inf if det12 == 0 else np.nan)
    const = 2.0 * LOG_2PI + half_logdet12
    # col: each sensor-2 return's own term, once (not once per pair)
    for b in range(m2):
        j = ok[1, b]
        col[b] = -0.5 * _mahalanobis2(nu[1, j, 0], nu[1, j, 1], S12inv[2:, 2:])
    for a in range(m1):
        i = ok[0, a]
        n0, n1 = nu[0, i, 0], nu[0, i, 1]
        row = -0.5 * _mahalanobis2(n0, n1, S12inv[:2, :2]) - const
        x0 = -(n0 * S12inv[0, 2] + n1 * S12inv[1, 2])  # -nu_1i' S12inv[:2, 2:]
        x1 = -(n0 * S12inv[0, 3] + n1 * S12inv[1, 3])
        for b in range(m2):
            j = ok[1, b]
            if joint:
                B[i, j] = (x0 * nu[1, j, 0] + x1 * nu[1, j, 1] + row + col[b]) + pair_add
            else:
                B[i, j] = pair_add + log_n[0, i] + log_n[1, j]
            top = _nan_max(top, B[i, j])
    return log00, top


@njit(**INNER)
def _normalize_pair(lin, log00, top, nearest):
    """Log weights in ``lin.w``, ``lin.B`` to probabilities in place; returns the null's. All zero:
    all mass to the null; ``nearest``: all mass on the first largest, in the oracle's order."""
    ok, m, w, B = lin.ok, lin.m, lin.w, lin.B
    m1, m2 = m[0], m[1]
    if not math.isfinite(top):
        log00, top = 0.0, 0.0
    if nearest:
        best_val, kind, bi, bj = log00, -1, -1, -1
        for s in range(2):
            for a in range(m[s]):
                if _beats(w[s, ok[s, a]], best_val):
                    best_val, kind, bi = w[s, ok[s, a]], s, ok[s, a]
        for a in range(m1):
            for b in range(m2):
                if _beats(B[ok[0, a], ok[1, b]], best_val):
                    best_val, kind, bi, bj = B[ok[0, a], ok[1, b]], 2, ok[0, a], ok[1, b]
        for s in range(2):
            for a in range(m[s]):
                w[s, ok[s, a]] = 1.0 if (kind == s and bi == ok[s, a]) else 0.0
        for a in range(m1):
            for b in range(m2):
                B[ok[0, a], ok[1, b]] = 1.0 if (kind == 2 and bi == ok[0, a]
                                                and bj == ok[1, b]) else 0.0
        return 1.0 if kind < 0 else 0.0
    b00 = math.exp(log00 - top)
    total = b00
    for s in range(2):
        for a in range(m[s]):
            i = ok[s, a]
            w[s, i] = math.exp(w[s, i] - top)
            total += w[s, i]
    for a in range(m1):
        for b in range(m2):
            i, j = ok[0, a], ok[1, b]
            B[i, j] = math.exp(B[i, j] - top)
            total += B[i, j]
    for s in range(2):
        for a in range(m[s]):
            w[s, ok[s, a]] /= total
    for a in range(m1):
        for b in range(m2):
            B[ok[0, a], ok[1, b]] /= total
    return b00 / total


@njit(**INNER)
def _pair_at_combined(lin):
    """``mg_at = "combined"`` for both sensors: each sensor's weight of a return is its
    one-sensor hypothesis plus every pair that uses it."""
    ok, m, w, B = lin.ok, lin.m, lin.w, lin.B
    M = w.shape[1]
    w1, w2 = np.zeros(M), np.zeros(M)
    for a in range(m[0]):
        i = ok[0, a]
        w1[i] = w[0, i]
        for b in range(m[1]):
            w1[i] += B[i, ok[1, b]]
    for b in range(m[1]):
        j = ok[1, b]
        w2[j] = w[1, j]
        for a in range(m[0]):
            w2[j] += B[ok[0, a], j]
    if m[0] > 0:
        _at_combined(lin, _FIRST, w1)
    if m[1] > 0:
        _at_combined(lin, _SECOND, w2)


@njit(**INNER)
def _pair_moments(lin, P, mom):
    """Moments of the joint hypotheses ``(i, j)`` weighted by ``lin.B`` into ``mom`` (4 rows);
    returns ``sum B`` (oracle: ``pda_reference._pair_moments``). Cross blocks:
    ``sum B_ij nu_1i nu_2j'`` and ``sum_i G_1i P33 (sum_j B_ij G_2j)'``."""
    ok, m, nu, G, B = lin.ok, lin.m, lin.nu, lin.G, lin.B
    r, c, W = mom.r, mom.c, mom.W
    r[:] = 0.0
    c[:] = 0.0
    NN, C = mom.NN, mom.C
    for a in range(m[0]):
        i = ok[0, a]
        v0, v1 = 0.0, 0.0  # sum_j B_ij nu_2j
        W[:, :] = 0.0  # sum_j B_ij G_2j
        for b in range(m[1]):
            j = ok[1, b]
            Bij = B[i, j]
            r[i] += Bij
            c[j] += Bij
            v0 += Bij * nu[1, j, 0]
            v1 += Bij * nu[1, j, 1]
            for p in range(2):
                for q in range(3):
                    W[p, q] += Bij * G[1, j, p, q]
        G1 = G[0, i]
        for p in range(2):
            gp0 = G1[p, 0] * P[0, 0] + G1[p, 1] * P[1, 0] + G1[p, 2] * P[2, 0]
            gp1 = G1[p, 0] * P[0, 1] + G1[p, 1] * P[1, 1] + G1[p, 2] * P[2, 1]
            gp2 = G1[p, 0] * P[0, 2] + G1[p, 1] * P[1, 2] + G1[p, 2] * P[2, 2]
            NN[p, 2] += nu[0, i, p] * v0
            NN[p, 3] += nu[0, i, p] * v1
            for q in range(2):
                C[p, 2 + q] += gp0 * W[q, 0] + gp1 * W[q, 1] + gp2 * W[q, 2]
    bsum = _single_moments(lin, _FIRST, r, P, mom, _FIRST_ROWS)
    _single_moments(lin, _SECOND, c, P, mom, _SECOND_ROWS)
    for p in range(2):
        for q in range(2):
            NN[2 + q, p] = NN[p, 2 + q]
            C[2 + q, p] = C[p, 2 + q]
    return bsum


@njit(**JIT)
def symmetrized(P):
    """``(P + P') / 2`` of covariances ``P (N, K, n, n)``, and whether each is finite
    ``(N, K)`` bool: numpy's ``0.5 * (P + P')`` element for element, in one pass."""
    N, K, n, _ = P.shape
    out, finite = np.empty(P.shape), np.empty((N, K), np.bool_)
    for a in range(N):
        for b in range(K):
            ok = True
            for i in range(n):
                for j in range(i, n):
                    v = 0.5 * (P[a, b, i, j] + P[a, b, j, i])
                    out[a, b, i, j] = v
                    out[a, b, j, i] = v
                    ok = ok and math.isfinite(v)
            finite[a, b] = ok
    return out, finite


@njit(**INNER)
def _symmetrize_and_check(X, P):
    """``P = (P + P') / 2`` in place; True when ``X`` or ``P`` is not finite (diverged)."""
    bad = False
    for i in range(6):
        bad |= not math.isfinite(X[i])
        for j in range(i, 6):
            v = 0.5 * (P[i, j] + P[j, i])
            P[i, j] = v
            P[j, i] = v
            bad |= not math.isfinite(v)
    return bad
