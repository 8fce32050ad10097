"""The numpy oracle of the compiled PDA filter (:mod:`trackfuse.tracking.pda`), batched over
trials: the same equations in array form, which the kernel tests pin the filter to (1e-9).

One call updates ``N`` independent filters (one per Monte Carlo trial) with the validated
returns of one scan. The hypothesis weights, the association variants (``method``), the
state update and the clutter density are those of :mod:`trackfuse.tracking.pda`'s module
docstring (``docs/papers/twin_sensor.md``, Algorithms); only the evaluation differs: arrays
over trials here, scalar loops per trial there.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from trackfuse.experiments.twin_sensor.model import (
    Batch,
    LossRules,
    Scenario,
    score_estimates,
)
from trackfuse.tracking.models import wrap
from trackfuse.tracking.pda_options import Estimates, PDAOptions
from trackfuse.tracking.sensors import (
    azel,
    azel_jacobian,
    ellipse_points,
    gate_volume,
    inv2,
    modified_position_rows,
)

LOG_2PI = float(np.log(2.0 * np.pi))


@dataclass(frozen=True)
class SensorReturns:
    """One scan of one sensor for a batch of ``N`` trials.

    Attributes
    ----------
    z : (N, M, 2) candidate azimuth/elevation returns (rad); padding entries must be finite.
    valid : (N, M) which entries are real returns.
    pos : (3,) or (N, 3) sensor position (m).
    R : (2, 2) measurement noise covariance (rad^2).
    P_D : detection probability.
    lam : (N,) clutter spatial density (1/rad^2) used by ``density="parametric"``.
    """

    z: np.ndarray
    valid: np.ndarray
    pos: np.ndarray
    R: np.ndarray
    P_D: float
    lam: np.ndarray


@dataclass(frozen=True)
class _Linearized:
    """A sensor linearized and gated at a state: shapes as in :class:`SensorReturns`."""

    H: np.ndarray  # (N, 2, 6)
    S: np.ndarray  # (N, 2, 2)
    K: np.ndarray  # (N, 6, 2)
    nu: np.ndarray  # (N, M, 2), zero where not validated
    G: np.ndarray  # (N, M, 2, 3) position columns of G_h (the rest are zero), zero if invalid
    ok: np.ndarray  # (N, M) validated
    m: np.ndarray  # (N,) validated count
    V: np.ndarray  # (N,) gate volume (rad^2)
    log_n: np.ndarray  # (N, M) log N(nu; 0, S), -inf where not validated
    lam: np.ndarray  # (N,) clutter density actually used
    d: np.ndarray  # (N, 3) predicted target-minus-sensor position (m)


def linearize(X: np.ndarray, P: np.ndarray, ret: SensorReturns,
              options: PDAOptions) -> _Linearized:
    """Predicted angles, Jacobian, innovation covariance, gain and gate for one sensor.

    ``X: (N, 6)``, ``P: (N, 6, 6)``; validated returns satisfy ``nu' S^-1 nu <= gamma``
    (``options.gamma``); ``options.covariance`` and ``options.density`` choose ``G`` and
    ``lam``.
    """
    gamma = options.gamma
    d = X[:, :3] - ret.pos
    H = azel_jacobian(d)
    PHt = P @ H.transpose(0, 2, 1)
    S = H @ PHt + ret.R
    Sinv, det = inv2(S)
    K = PHt @ Sinv
    nu = wrap(ret.z - azel(d)[:, None, :])
    d2 = ((nu @ Sinv) * nu).sum(axis=2)
    with np.errstate(invalid="ignore"):
        ok = ret.valid & (d2 <= gamma) & (det > 0)[:, None]
    m = ok.sum(axis=1)
    V = gate_volume(S, gamma)
    with np.errstate(divide="ignore", invalid="ignore"):
        logdet = np.log(det)
    log_n = np.where(ok, -0.5 * d2 - LOG_2PI - 0.5 * logdet[:, None], -np.inf)
    if options.covariance == "mgekf":
        with np.errstate(divide="ignore", invalid="ignore"):
            G = modified_position_rows(ret.z, d[:, None, :])
    else:
        G = np.broadcast_to(H[:, None, :, :3], nu.shape[:2] + (2, 3))
    G = np.where(ok[..., None, None], G, 0.0)
    nu = np.where(ok[..., None], nu, 0.0)
    lam = m / V if options.density == "nonparametric" else np.asarray(ret.lam, dtype=float)
    return _Linearized(H, S, K, nu, G, ok, m, V, log_n, lam, d)


def _at_combined(lin: _Linearized, w: np.ndarray) -> _Linearized:
    """``lin`` with every hypothesis's modified rows evaluated at the combined return
    ``zbar = h(Xp) + sum_i w_i nu_i / sum_i w_i`` (W000-4 alternative ``mg_at = "combined"``);
    with no weight on any return ``zbar = h(Xp)``, where the modified rows equal ``H``."""
    total = w.sum(axis=1)
    nu_bar = _wsum(w, lin.nu) / np.where(total > 0, total, 1.0)[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        G = modified_position_rows(wrap(azel(lin.d) + nu_bar), lin.d)
    return replace(lin, G=np.where(lin.ok[..., None, None], G[:, None], 0.0))


def _log_null(lin: _Linearized, P_D: float, P_G: float) -> np.ndarray:
    """``log f_s(0)``: ``(N,)``; zero when the sensor has no validated return."""
    with np.errstate(divide="ignore"):
        val = np.log1p(-P_D * P_G) + np.log(lin.lam)
    return np.where(lin.m > 0, val, 0.0)


def _normalize(logs: Sequence[np.ndarray], nearest: bool) -> list[np.ndarray]:
    """Turn log weights (each ``(N, ...)``) into probabilities over all of them together.

    Rows where every weight is zero (possible only when ``lambda = 0`` and nothing was
    validated, which the null alone explains) put all mass on the first array (the null).
    With ``nearest`` the mass goes entirely to the largest weight.
    """
    n = logs[0].shape[0]
    flat = np.concatenate([a.reshape(n, -1) for a in logs], axis=1)
    top = flat.max(axis=1, keepdims=True)
    dead = ~np.isfinite(top[:, 0])
    flat[dead, 0] = 0.0
    top[dead] = 0.0
    if nearest:
        beta = np.zeros_like(flat)
        beta[np.arange(n), flat.argmax(axis=1)] = 1.0
    else:
        beta = flat
        beta -= top
        np.exp(beta, out=beta)
        beta /= beta.sum(axis=1, keepdims=True)
    out, start = [], 0
    for a in logs:
        size = int(np.prod(a.shape[1:], dtype=int))
        out.append(beta[:, start:start + size].reshape(a.shape))
        start += size
    return out


def _wsum(b: np.ndarray, A: np.ndarray) -> np.ndarray:
    """``sum_m b[n, m] A[n, m, ...]`` for ``b: (N, M)``, ``A: (N, M, ...)``."""
    n, m = b.shape
    return (b[:, None, :] @ A.reshape(n, m, -1))[:, 0].reshape((n,) + A.shape[2:])


def _wouter(b: np.ndarray, U: np.ndarray, V: np.ndarray) -> np.ndarray:
    """``sum_m b[n, m] U[n, m] V[n, m]'`` for ``U: (N, M, a, k)``, ``V: (N, M, c, k)``."""
    n, m, a, k = U.shape
    Uw = (b[:, :, None, None] * U).transpose(0, 2, 1, 3).reshape(n, a, m * k)
    return Uw @ V.transpose(0, 1, 3, 2).reshape(n, m * k, V.shape[2])


#: Weighted moments of one hypothesis class over a batch of ``N`` trials with ``n``
#: measurement rows (2 for one sensor, 4 for a pair): ``(bsum: (N,), nu_bar: (N, n),
#: NN: (N, n, n), Gbar: (N, n, 3), C: (N, n, n))``, see :func:`_class_terms`.
Moments = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


def _class_terms(K: np.ndarray, R: np.ndarray, P: np.ndarray, bsum: np.ndarray,
                 nu_bar: np.ndarray, NN: np.ndarray, Gbar: np.ndarray,
                 C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Contribution of one hypothesis class sharing gain ``K: (N, 6, n)``.

    ``R: (n, n)`` measurement noise (rad^2), ``P: (N, 6, 6)`` the predicted covariance;
    ``bsum: (N,)`` the class's total weight, ``nu_bar: (N, n)`` and ``NN: (N, n, n)`` the
    weighted sums of ``nu_h`` and ``nu_h nu_h'`` (rad, rad^2), ``Gbar: (N, n, 3)`` and
    ``C: (N, n, n)`` those of ``G_h`` (position columns, rad/m) and ``G_h Pp G_h'``.
    Returns ``(dx, dP)`` with ``dx = K sum beta nu: (N, 6)`` and
    ``dP = sum beta [P_h + dx_h dx_h']: (N, 6, 6)`` where ``dx_h = K nu_h``.
    """
    KGP = K @ (Gbar @ P[:, :3, :])
    Kt = K.transpose(0, 2, 1)
    dP = (bsum[:, None, None] * (P + K @ R @ Kt) - KGP - KGP.transpose(0, 2, 1)
          + K @ (C + NN) @ Kt)
    return (K @ nu_bar[:, :, None])[:, :, 0], dP


def _single_moments(lin: _Linearized, b: np.ndarray, P: np.ndarray) -> Moments:
    """Weighted moments (:data:`Moments`, ``n = 2``) of one sensor's hypotheses with weights
    ``b: (N, M)`` at the predicted covariance ``P: (N, 6, 6)``."""
    GP = lin.G @ P[:, None, :3, :3]
    nu = lin.nu[..., None]
    return (b.sum(axis=1), _wsum(b, lin.nu), _wouter(b, nu, nu), _wsum(b, lin.G),
            _wouter(b, GP, lin.G))


def _collapse_single(X: np.ndarray, P: np.ndarray, lin: _Linearized, R: np.ndarray,
                     b0: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """One sensor's collapsed update ``(X: (N, 6), P: (N, 6, 6))`` from the prediction
    ``X: (N, 6)``, ``P: (N, 6, 6)``, noise ``R: (2, 2)`` (rad^2) and the weights of the
    null ``b0: (N,)`` and of each return ``b: (N, M)``."""
    dx, dP = _class_terms(lin.K, R, P, *_single_moments(lin, b, P))
    P_new = b0[:, None, None] * P + dP - dx[:, :, None] * dx[:, None, :]
    return X + dx, P_new


def _pair_moments(l1: _Linearized, l2: _Linearized, B: np.ndarray, P: np.ndarray) -> Moments:
    """Weighted moments (:data:`Moments`, ``n = 4``) of the joint hypotheses ``(i, j)`` with
    weights ``B: (N, M1, M2)`` at the predicted covariance ``P: (N, 6, 6)``."""
    n, m1, m2 = B.shape
    r, c = B.sum(axis=2), B.sum(axis=1)
    P33 = P[:, None, :3, :3]
    G1P, G2P = l1.G @ P33, l2.G @ P33
    nu1, nu2 = l1.nu[..., None], l2.nu[..., None]
    nu_bar = np.concatenate([_wsum(r, l1.nu), _wsum(c, l2.nu)], axis=1)
    N12 = l1.nu.transpose(0, 2, 1) @ (B @ l2.nu)
    NN = _blocks(_wouter(r, nu1, nu1), N12, _wouter(c, nu2, nu2))
    Gbar = np.concatenate([_wsum(r, l1.G), _wsum(c, l2.G)], axis=1)
    W = (B @ l2.G.reshape(n, m2, 6)).reshape(n, m1, 2, 3)
    C12 = _wouter(np.ones((n, m1)), G1P, W)
    C = _blocks(_wouter(r, G1P, l1.G), C12, _wouter(c, G2P, l2.G))
    return r.sum(axis=1), nu_bar, NN, Gbar, C


def _blocks(A: np.ndarray, B: np.ndarray, D: np.ndarray) -> np.ndarray:
    """``[[A, B], [B', D]]: (N, 4, 4)`` from 2x2 blocks ``(N, 2, 2)``."""
    out = np.empty(A.shape[:-2] + (4, 4))
    out[..., :2, :2], out[..., :2, 2:] = A, B
    out[..., 2:, :2], out[..., 2:, 2:] = B.transpose(0, 2, 1), D
    return out


def pair_weights(X: np.ndarray, P: np.ndarray, r1: SensorReturns, r2: SensorReturns,
                 options: PDAOptions
                 ) -> tuple[list[np.ndarray], _Linearized, _Linearized, np.ndarray]:
    """Association probabilities of the two-sensor hypotheses at the prediction ``(X, P)``.

    Returns ``(beta_00: (N,), beta_i0: (N, M1), beta_0j: (N, M2), beta_ij: (N, M1, M2))``
    summing to one per trial, plus the two linearized sensors and ``K12: (N, 6, 4)``.
    """
    method, P_G = options.method, options.P_G
    l1 = linearize(X, P, r1, options)
    l2 = linearize(X, P, r2, options)
    C = l1.H @ P @ l2.H.transpose(0, 2, 1)
    S12inv, det12 = _block_inverse(l1.S, C, l2.S)
    H12 = np.concatenate([l1.H, l2.H], axis=1)
    K12 = P @ H12.transpose(0, 2, 1) @ S12inv
    ok = l1.ok[:, :, None] & l2.ok[:, None, :]
    if method == "paper_approx":
        log_pair, log_1, log_2, log_00 = _paper_logs(l1, l2, S12inv, det12, ok, r1.P_D,
                                                     r2.P_D, P_G)
    else:
        f1, f2 = _log_null(l1, r1.P_D, P_G), _log_null(l2, r2.P_D, P_G)
        with np.errstate(divide="ignore"):
            lp1, lp2 = np.log(r1.P_D), np.log(r2.P_D)
        log_1 = lp1 + l1.log_n + f2[:, None]
        log_2 = f1[:, None] + lp2 + l2.log_n
        log_00 = f1 + f2
        if options.joint_cov == "full":
            log_pair = _log_joint(l1, l2, S12inv, det12)
            log_pair += lp1 + lp2
            np.putmask(log_pair, ~ok, -np.inf)
        else:
            log_pair = lp1 + lp2 + l1.log_n[:, :, None] + l2.log_n[:, None, :]
    betas = _normalize([log_00, log_1, log_2, log_pair], nearest=method == "nn")
    return betas, l1, l2, K12


def _pair_update(X: np.ndarray, P: np.ndarray, r1: SensorReturns, r2: SensorReturns,
                 options: PDAOptions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Both sensors' joint update of the prediction ``X: (N, 6)``, ``P: (N, 6, 6)``:
    ``(X: (N, 6), P: (N, 6, 6), validated counts: (N, 2))``."""
    (b00, b1, b2, B), l1, l2, K12 = pair_weights(X, P, r1, r2, options)
    if options.covariance == "mgekf" and options.mg_at == "combined":
        l1, l2 = _at_combined(l1, b1 + B.sum(axis=2)), _at_combined(l2, b2 + B.sum(axis=1))
    R12 = np.zeros((4, 4))
    R12[:2, :2], R12[2:, 2:] = r1.R, r2.R
    dxa, dPa = _class_terms(l1.K, r1.R, P, *_single_moments(l1, b1, P))
    dxb, dPb = _class_terms(l2.K, r2.R, P, *_single_moments(l2, b2, P))
    dxc, dPc = _class_terms(K12, R12, P, *_pair_moments(l1, l2, B, P))
    dx = dxa + dxb + dxc
    P_new = b00[:, None, None] * P + dPa + dPb + dPc - dx[:, :, None] * dx[:, None, :]
    return X + dx, P_new, np.stack([l1.m, l2.m], axis=1)


def _block_inverse(A: np.ndarray, B: np.ndarray,
                   D: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse ``(N, 4, 4)`` and determinant ``(N,)`` of ``[[A, B], [B', D]]`` with 2x2
    blocks ``(N, 2, 2)``.

    Schur complement ``Sc = D - B' A^-1 B`` with closed-form 2x2 inverses, so a diverged
    trial yields non-finite numbers instead of stopping the batch.
    """
    Ainv, detA = inv2(A)
    AinvB = Ainv @ B
    Scinv, detSc = inv2(D - B.transpose(0, 2, 1) @ AinvB)
    TR = -AinvB @ Scinv
    TL = Ainv - TR @ AinvB.transpose(0, 2, 1)
    return _blocks(TL, TR, Scinv), detA * detSc


def _log_joint(l1: _Linearized, l2: _Linearized, S12inv: np.ndarray,
               det12: np.ndarray) -> np.ndarray:
    """``log N([nu_1i; nu_2j]; 0, S_12)``: ``(N, M1, M2)`` from ``S12inv: (N, 4, 4)``, the
    inverse of ``S_12``, and its determinant ``det12: (N,)`` (in-place arithmetic: hot
    path)."""
    A, Bc, D = S12inv[:, :2, :2], S12inv[:, :2, 2:], S12inv[:, 2:, 2:]
    with np.errstate(invalid="ignore", divide="ignore"):
        logdet = np.log(det12)
    row = -0.5 * ((l1.nu @ A) * l1.nu).sum(axis=2) - (2.0 * LOG_2PI + 0.5 * logdet)[:, None]
    col = -0.5 * ((l2.nu @ D) * l2.nu).sum(axis=2)
    out = (l1.nu @ -Bc) @ l2.nu.transpose(0, 2, 1)
    out += row[:, :, None]
    out += col[:, None, :]
    return out


def _paper_logs(l1: _Linearized, l2: _Linearized, S12inv: np.ndarray, det12: np.ndarray,
                ok: np.ndarray, P_D1: float, P_D2: float,
                P_G: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Log weights of the ``paper_approx`` reconstruction (see the module docstring):
    ``(log_pair: (N, M1, M2), log_1: (N, M1), log_2: (N, M2), log_00: (N,))``; ``ok:
    (N, M1, M2)`` marks the pairs both of whose returns are validated, ``S12inv`` and
    ``det12`` as in :func:`_log_joint`."""
    P_D = 1.0 - (1.0 - P_D1) * (1.0 - P_D2)
    P_Gf = 1.0 - (1.0 - P_G) ** 2
    m_k = (l1.m + 1) * (l2.m + 1)
    m_f = l1.m + l2.m
    Lam = l1.lam * l1.V + l2.lam * l2.V
    log_vf = np.log(l1.V) + np.log(l2.V)
    with np.errstate(divide="ignore", invalid="ignore"):
        log_00 = np.where(m_f > 0, np.log1p(-P_D * P_Gf) + np.log(Lam) - np.log(m_f), 0.0)
        common = np.where(m_k > 1, np.log(P_D) + log_vf - np.log(m_k - 1.0), 0.0)[:, None]
    log_1 = common + l1.log_n - np.log(l2.V)[:, None]
    log_2 = common + l2.log_n - np.log(l1.V)[:, None]
    log_pair = _log_joint(l1, l2, S12inv, det12)
    log_pair += common[:, :, None]
    np.putmask(log_pair, ~ok, -np.inf)
    return log_pair, log_1, log_2, log_00


def single_weights(lin: _Linearized, P_D: float, P_G: float,
                   nearest: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Single-sensor PDA probabilities ``(beta_0: (N,), beta_i: (N, M))`` of a linearized
    sensor (Bar-Shalom & Fortmann 1988, eq. 6.2-34 with a Poisson clutter model)."""
    with np.errstate(divide="ignore"):
        log_i = np.log(P_D) + lin.log_n
    b0, b = _normalize([_log_null(lin, P_D, P_G), log_i], nearest=nearest)
    return b0, b


def _single_update(X: np.ndarray, P: np.ndarray, ret: SensorReturns,
                   options: PDAOptions) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One sensor's update of the prediction ``X: (N, 6)``, ``P: (N, 6, 6)``:
    ``(X: (N, 6), P: (N, 6, 6), validated count: (N,))``."""
    lin = linearize(X, P, ret, options)
    b0, b = single_weights(lin, ret.P_D, options.P_G, nearest=options.method == "nn")
    if options.covariance == "mgekf" and options.mg_at == "combined":
        lin = _at_combined(lin, b)
    X_new, P_new = _collapse_single(X, P, lin, ret.R, b0, b)
    return X_new, P_new, lin.m


def pda_update(X: np.ndarray, P: np.ndarray, returns: Sequence[SensorReturns],
               options: PDAOptions | None = None
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One PDA scan update of ``N`` filters with one or two sensors.

    Parameters
    ----------
    X : (N, 6) predicted states (m, m/s).
    P : (N, 6, 6) predicted covariances.
    returns : one :class:`SensorReturns` per sensor (1 or 2).
    options : association method, covariance form, gate probability (:class:`PDAOptions`;
        default ``PDAOptions()``).

    Returns
    -------
    X : (N, 6), P : (N, 6, 6) updated; m : (N, n_sensors) validated counts (for the
    sequential method, sensor 2 is gated at the sensor-1 posterior).
    """
    options = options if options is not None else PDAOptions()
    if len(returns) == 1 or options.method == "mspda_sequential":
        counts = []
        for ret in returns:
            X, P, m = _single_update(X, P, ret, options)
            counts.append(m)
        return X, P, np.stack(counts, axis=1)
    if len(returns) != 2:
        raise ValueError("one or two sensors are supported")
    return _pair_update(X, P, returns[0], returns[1], options)


def _scan_returns(sc: Scenario, b: Batch, k: int, Xp: np.ndarray,
                  Pp: np.ndarray) -> tuple[list[SensorReturns], np.ndarray]:
    """Returns of every sensor at scan ``k`` and whether the noise-free target return lies
    inside at least one sensor's gate, ``(N,)`` bool, for predictions ``Xp: (N, 6)``,
    ``Pp: (N, 6, 6)``."""
    N = Xp.shape[0]
    returns, inside = [], np.zeros(N, dtype=bool)
    for s in range(sc.R.shape[0]):
        pos = sc.sensor_pos[k, s]
        d = Xp[:, :3] - pos
        zh = azel(d)
        H = azel_jacobian(d)
        S_s = H @ Pp @ H.transpose(0, 2, 1) + sc.R[s]
        nu_true = wrap(b.los[:, k - 1, s] - zh)
        d2_true = ((nu_true[:, None] @ inv2(S_s)[0])[:, 0] * nu_true).sum(axis=1)
        with np.errstate(invalid="ignore"):
            inside |= d2_true <= sc.gamma
        if sc.clutter_model == "in_gate":
            zc = ellipse_points(b.clutter[:, k - 1, s], zh, S_s, sc.gamma)
            lam = sc.clutter_mean / gate_volume(S_s, sc.gamma)
        else:
            zc = b.clutter[:, k - 1, s]
            lam = np.full(N, sc.window_density)
        z = np.concatenate([b.z_target[:, k - 1, s][:, None], zc], axis=1)
        valid = np.concatenate([b.detected[:, k - 1, s][:, None], b.clutter_ok[:, k - 1, s]],
                               axis=1)
        returns.append(SensorReturns(z, valid, pos, sc.R[s], float(sc.P_D[s]), lam))
    return returns, inside


def run_filter(sc: Scenario, b: Batch, options: PDAOptions,
               rules: LossRules) -> dict[str, np.ndarray]:
    """Run one algorithm (its association and filter choices in ``options``) over a batch;
    every metric of :data:`~trackfuse.experiments.twin_sensor.model.METRICS` is returned as
    ``(N, K)``.

    The numpy oracle of :func:`trackfuse.tracking.pda.run_filter` (which the experiment
    runs): the tests pin the two together to 1e-9 and the speed benchmark times both. A
    trial whose mean or covariance stops being finite has diverged: NaN from that scan on,
    as in the filter."""
    N = b.x0.shape[0]
    X = b.x0.copy()
    P = np.broadcast_to(sc.P0, (N, 6, 6)).copy()
    est = Estimates(np.empty((N, sc.K, 6)), np.empty((N, sc.K, 6, 6)),
                    np.empty((N, sc.K, len(sc.R))), np.empty((N, sc.K), dtype=bool))
    diverged = np.zeros(N, dtype=bool)
    for k in range(1, sc.K + 1):
        Xp = X @ sc.F.T
        Pp = sc.F @ P @ sc.F.T + sc.Q_filter
        returns, inside = _scan_returns(sc, b, k, Xp, Pp)
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            X, P, m = pda_update(Xp, Pp, returns, options)
        P = 0.5 * (P + P.transpose(0, 2, 1))
        diverged |= ~(np.isfinite(X).all(axis=1) & np.isfinite(P).all(axis=(1, 2)))
        X[diverged], P[diverged] = np.nan, np.nan
        est.X[:, k - 1], est.P[:, k - 1], est.n_valid[:, k - 1] = X, P, m
        est.inside[:, k - 1] = inside
    return score_estimates(sc, b, est, rules)


def unit_disk(rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` points ``(n, 2)`` uniform in the unit disk (polar sampling with sqrt radius)."""
    return disk_points(rng.random(n), rng.random(n))


def disk_points(u_radius: np.ndarray, u_angle: np.ndarray) -> np.ndarray:
    """Unit-disk points (n, 2) from uniforms: radius ``sqrt(u_radius)``, angle ``2 pi u_angle``."""
    r = np.sqrt(u_radius)
    a = 2.0 * np.pi * u_angle
    out = np.empty(r.shape + (2,))
    np.multiply(r, np.cos(a), out=out[..., 0])
    np.multiply(r, np.sin(a), out=out[..., 1])
    return out
