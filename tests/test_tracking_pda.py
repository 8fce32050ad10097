"""Two-sensor PDA (docs/papers/twin_sensor.md): weights, reductions, closed-form collapse."""

import itertools

import numpy as np
import pytest
from pda_reference import (
    SensorReturns,
    linearize,
    pair_weights,
    pda_update,
    single_weights,
)
from scipy.stats import chi2, multivariate_normal

from trackfuse.tracking.models import wrap
from trackfuse.tracking.pda_options import PDAOptions
from trackfuse.tracking.sensors import azel, azel_jacobian, gate_threshold, modified_rows

P_G = 0.99


def opts(method="mspda_parallel", covariance="mgekf", **kw):
    """PDA options at the module's gate probability."""
    return PDAOptions(method, covariance, P_G=kw.pop("P_G", P_G), **kw)
SENSORS = (np.array([153209.0, 0.0, 2000.0]), np.array([150000.0, 4000.0, 2100.0]))
R = np.diag([1e-4, 1.5e-4])


def predicted(rng, N):
    """Predicted states (N, 6) and covariances (N, 6, 6) near the paper's target."""
    X = np.array([0.0, 128558.0, 4000.0, 0, 0, 0]) + rng.normal(0, 1, (N, 6)) * [2e3, 2e3,
                                                                                  300, 5, 5, 2]
    A = rng.normal(size=(N, 6, 6)) * np.array([1.5e3, 1.5e3, 800, 20, 20, 20])[:, None]
    P = A @ A.transpose(0, 2, 1) / 6 + np.diag([1e6, 1e6, 1e5, 50, 50, 50])
    return X, P


def returns_for(rng, X, P, pos, M, P_D=0.9, lam=300.0, spread=2.0):
    """Returns scattered around the predicted angles, with random padding and validity."""
    N = X.shape[0]
    d = X[:, :3] - pos
    H = azel_jacobian(d)
    S = H @ P @ H.transpose(0, 2, 1) + R
    L = np.linalg.cholesky(S)
    z = azel(d)[:, None] + spread * np.einsum("nab,nmb->nma", L, rng.normal(size=(N, M, 2)))
    valid = rng.random((N, M)) < 0.8
    return SensorReturns(z, valid, pos, R, P_D, np.full(N, lam))


def brute_force(X, P, rets, betas, covariance, zbar=None):
    """The documented update literally: an MGEKF/EKF update per hypothesis, then moments.

    ``zbar`` (one ``(N, 2)`` array per sensor) evaluates the modified rows there instead of at
    each hypothesis's own returns (``mg_at = "combined"``)."""
    b00, b1, b2, B = betas
    out_X, out_P = [], []
    for n in range(X.shape[0]):
        hyps = [((), b00[n])]
        hyps += [(((0, i),), b1[n, i]) for i in range(b1.shape[1])]
        hyps += [(((1, j),), b2[n, j]) for j in range(b2.shape[1])]
        hyps += [(((0, i), (1, j)), B[n, i, j])
                 for i, j in itertools.product(range(B.shape[1]), range(B.shape[2]))]
        means, covs, ws = [], [], []
        for used, w in hyps:
            if w == 0:
                continue
            if not used:
                means.append(X[n])
                covs.append(P[n])
                ws.append(w)
                continue
            Hs, Gs, nus, Rs = [], [], [], []
            for s, i in used:
                d = X[n, :3] - rets[s].pos
                z = rets[s].z[n, i]
                Hs.append(azel_jacobian(d))
                z_g = z if zbar is None else zbar[s][n]
                Gs.append(modified_rows(z_g, d) if covariance == "mgekf" else azel_jacobian(d))
                nus.append(wrap(z - azel(d)))
                Rs.append(rets[s].R)
            H, G, nu = np.vstack(Hs), np.vstack(Gs), np.concatenate(nus)
            Rm = np.zeros((len(nu), len(nu)))
            for b, Rb in enumerate(Rs):
                Rm[2 * b:2 * b + 2, 2 * b:2 * b + 2] = Rb
            K = P[n] @ H.T @ np.linalg.inv(H @ P[n] @ H.T + Rm)
            A = np.eye(6) - K @ G
            means.append(X[n] + K @ nu)
            covs.append(A @ P[n] @ A.T + K @ Rm @ K.T)
            ws.append(w)
        ws = np.array(ws)
        m = np.einsum("h,ha->a", ws, np.array(means))
        dev = np.array(means) - m
        out_X.append(m)
        out_P.append(np.einsum("h,hab->ab", ws, np.array(covs))
                     + np.einsum("h,ha,hb->ab", ws, dev, dev))
    return np.array(out_X), np.array(out_P)


@pytest.mark.parametrize("covariance", ["mgekf", "ekf_joseph"])
@pytest.mark.parametrize("method", ["mspda_parallel", "nn", "paper_approx"])
def test_closed_form_collapse_equals_per_hypothesis_mixture(method, covariance):
    rng = np.random.default_rng(7)
    X, P = predicted(rng, 6)
    rets = [returns_for(rng, X, P, SENSORS[0], 5), returns_for(rng, X, P, SENSORS[1], 4)]
    betas, *_ = pair_weights(X, P, *rets, opts(method, covariance))
    Xn, Pn, m = pda_update(X, P, rets, opts(method, covariance))
    Xb, Pb = brute_force(X, P, rets, betas, covariance)
    np.testing.assert_allclose(Xn, Xb, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(Pn, Pb, rtol=1e-7, atol=1e-6 * np.abs(Pb).max())
    assert np.all(m <= np.array([5, 4]))


@pytest.mark.parametrize("method", ["mspda_parallel", "nn", "paper_approx"])
@pytest.mark.parametrize("joint_cov", ["full", "blockdiag"])
def test_weights_sum_to_one_and_vanish_off_gate(method, joint_cov):
    rng = np.random.default_rng(3)
    X, P = predicted(rng, 8)
    rets = [returns_for(rng, X, P, SENSORS[0], 6), returns_for(rng, X, P, SENSORS[1], 5)]
    (b00, b1, b2, B), l1, l2, _ = pair_weights(X, P, *rets,
                                               opts(method, joint_cov=joint_cov))
    total = b00 + b1.sum(1) + b2.sum(1) + B.sum((1, 2))
    np.testing.assert_allclose(total, 1.0, rtol=1e-12)
    assert np.all(b1[~l1.ok] == 0) and np.all(b2[~l2.ok] == 0)
    assert np.all(B[~(l1.ok[:, :, None] & l2.ok[:, None, :])] == 0)
    if method == "nn":
        flat = np.concatenate([b00[:, None], b1, b2, B.reshape(8, -1)], axis=1)
        assert np.all(np.sort(flat, axis=1)[:, -1] == 1.0)


def test_pair_weights_match_the_formulas_of_spec_1_6():
    rng = np.random.default_rng(11)
    X, P = predicted(rng, 1)
    r1 = returns_for(rng, X, P, SENSORS[0], 3, P_D=0.8, lam=200.0, spread=1.0)
    r2 = returns_for(rng, X, P, SENSORS[1], 2, P_D=0.7, lam=500.0, spread=1.0)
    r1 = SensorReturns(r1.z, np.ones((1, 3), bool), r1.pos, R, 0.8, r1.lam)
    r2 = SensorReturns(r2.z, np.ones((1, 2), bool), r2.pos, R, 0.7, r2.lam)
    wide = opts(P_G=1.0 - 1e-15)  # a gate wide enough to validate every return
    assert wide.gamma > 60.0
    (b00, b1, b2, B), l1, l2, _ = pair_weights(X, P, r1, r2, wide)
    d1, d2 = X[0, :3] - r1.pos, X[0, :3] - r2.pos
    H = np.vstack([azel_jacobian(d1), azel_jacobian(d2)])
    S12 = H @ P[0] @ H.T + np.block([[R, np.zeros((2, 2))], [np.zeros((2, 2)), R]])
    nu1 = wrap(r1.z[0] - azel(d1))
    nu2 = wrap(r2.z[0] - azel(d2))
    n1 = [multivariate_normal(np.zeros(2), S12[:2, :2]).pdf(v) for v in nu1]
    n2 = [multivariate_normal(np.zeros(2), S12[2:, 2:]).pdf(v) for v in nu2]
    assert l1.ok.all() and l2.ok.all()
    f1, f2 = (1 - 0.8 * wide.P_G) * 200.0, (1 - 0.7 * wide.P_G) * 500.0
    w = {(0, 0): f1 * f2}
    w.update({(i + 1, 0): 0.8 * n1[i] * f2 for i in range(3)})
    w.update({(0, j + 1): f1 * 0.7 * n2[j] for j in range(2)})
    w.update({(i + 1, j + 1): 0.8 * 0.7 * multivariate_normal(np.zeros(4), S12).pdf(
        np.r_[nu1[i], nu2[j]]) for i in range(3) for j in range(2)})
    tot = sum(w.values())
    np.testing.assert_allclose(b00[0], w[0, 0] / tot, rtol=1e-9)
    np.testing.assert_allclose(b1[0], [w[i, 0] / tot for i in (1, 2, 3)], rtol=1e-9)
    np.testing.assert_allclose(b2[0], [w[0, j] / tot for j in (1, 2)], rtol=1e-9)
    np.testing.assert_allclose(B[0], [[w[i, j] / tot for j in (1, 2)] for i in (1, 2, 3)],
                               rtol=1e-9)


def test_reduces_to_single_sensor_pdaf_when_sensor_two_is_silent():
    rng = np.random.default_rng(5)
    X, P = predicted(rng, 10)
    r1 = returns_for(rng, X, P, SENSORS[0], 6, P_D=0.9, lam=400.0, spread=1.5)
    empty = SensorReturns(np.zeros((10, 1, 2)), np.zeros((10, 1), bool), SENSORS[1], R, 0.0,
                          np.full(10, 400.0))
    (b00, b1, b2, B), l1, _, _ = pair_weights(X, P, r1, empty, opts())
    # Bar-Shalom's closed form: beta_i = e_i / (b + sum e), b = lam |2 pi S|^1/2 (1 - PD PG)/PD
    d2 = np.einsum("nma,nab,nmb->nm", l1.nu, np.linalg.inv(l1.S), l1.nu)
    e = np.where(l1.ok, np.exp(-0.5 * d2), 0.0)
    b = 400.0 * np.sqrt(np.linalg.det(2 * np.pi * l1.S)) * (1 - 0.9 * P_G) / 0.9
    np.testing.assert_allclose(b1, e / (b + e.sum(1))[:, None], rtol=1e-9, atol=1e-300)
    np.testing.assert_allclose(b00, b / (b + e.sum(1)), rtol=1e-9)
    assert np.all(b2 == 0) and np.all(B == 0)
    X2, P2, _ = pda_update(X, P, [r1, empty], opts())
    X1, P1, _ = pda_update(X, P, [r1], opts())
    np.testing.assert_allclose(X2, X1, rtol=1e-12)
    np.testing.assert_allclose(P2, P1, rtol=1e-9, atol=1e-9 * np.abs(P1).max())


def test_no_clutter_and_perfect_detection_puts_all_mass_on_the_true_pair():
    rng = np.random.default_rng(9)
    X, P = predicted(rng, 5)
    truth = X[:, :3] + rng.normal(0, 300, (5, 3))
    rets = [SensorReturns(azel(truth - pos)[:, None], np.ones((5, 1), bool), pos, R, 1.0,
                          np.full(5, lam)) for pos, lam in zip(SENSORS, (1e-9, 1e-9),
                                                               strict=True)]
    (b00, b1, b2, B), *_ = pair_weights(X, P, *rets, opts())
    np.testing.assert_allclose(B[:, 0, 0], 1.0, atol=1e-9)
    lam0 = [SensorReturns(r.z, r.valid, r.pos, R, 1.0, np.zeros(5)) for r in rets]
    (b00, b1, b2, B), *_ = pair_weights(X, P, *lam0, opts())
    assert np.all(B[:, 0, 0] == 1.0)


def test_mixture_equals_closed_form_pdaf_for_a_linear_update():
    """One sensor, EKF covariance (linear H at the prediction): Bar-Shalom's PDAF formulas."""
    rng = np.random.default_rng(21)
    X, P = predicted(rng, 12)
    ret = returns_for(rng, X, P, SENSORS[0], 7, P_D=0.85, lam=250.0, spread=1.5)
    lin = linearize(X, P, ret, opts(covariance="ekf_joseph"))
    b0, b = single_weights(lin, 0.85, P_G)
    Xn, Pn, _ = pda_update(X, P, [ret], opts(covariance="ekf_joseph"))
    nu_c = np.einsum("nm,nma->na", b, lin.nu)
    K = lin.K
    X_ref = X + np.einsum("nab,nb->na", K, nu_c)
    Pc = P - K @ lin.S @ K.transpose(0, 2, 1)
    spread = np.einsum("nm,nma,nmb->nab", b, lin.nu, lin.nu) - np.einsum("na,nb->nab", nu_c,
                                                                            nu_c)
    P_ref = (b0[:, None, None] * P + (1 - b0)[:, None, None] * Pc
             + K @ spread @ K.transpose(0, 2, 1))
    np.testing.assert_allclose(Xn, X_ref, rtol=1e-10)
    np.testing.assert_allclose(Pn, P_ref, rtol=1e-7, atol=1e-7 * np.abs(P_ref).max())


def test_sequential_with_one_sensor_is_the_pdaf_and_two_sensors_regate():
    rng = np.random.default_rng(2)
    X, P = predicted(rng, 4)
    r1 = returns_for(rng, X, P, SENSORS[0], 4)
    r2 = returns_for(rng, X, P, SENSORS[1], 4)
    Xs, Ps, _ = pda_update(X, P, [r1], opts("mspda_sequential"))
    Xp, Pp, _ = pda_update(X, P, [r1], opts())
    np.testing.assert_allclose(Xs, Xp)
    X2, P2, m = pda_update(X, P, [r1, r2], opts("mspda_sequential"))
    X1, P1, _ = pda_update(Xs, Ps, [r2], opts())
    np.testing.assert_allclose(X2, X1)
    np.testing.assert_allclose(P2, P1)
    assert m.shape == (4, 2)
    # sensor 2 is gated at the sensor-1 posterior, not at the prediction
    np.testing.assert_array_equal(m[:, 0], linearize(X, P, r1, opts()).m)
    np.testing.assert_array_equal(m[:, 1], linearize(Xs, Ps, r2, opts()).m)
    _, _, m_par = pda_update(X, P, [r1, r2], opts())
    assert not np.array_equal(m[:, 1], m_par[:, 1])


@pytest.mark.parametrize("bad", [dict(method="jpda"), dict(covariance="ukf"),
                                 dict(joint_cov="diag"), dict(density="guess"),
                                 dict(mg_at="mean"), dict(P_G=1.0), dict(P_G=0.0)])
def test_unknown_options_rejected_at_construction(bad):
    with pytest.raises(ValueError):
        PDAOptions(**bad)


@pytest.mark.parametrize("P_G, n_z", [(0.99, 2), (0.95, 2), (0.999, 1), (0.9, 4)])
def test_gate_threshold_follows_the_gate_probability_and_dimension(P_G, n_z):
    options = PDAOptions(P_G=P_G, n_z=n_z)
    assert options.gamma == pytest.approx(chi2.ppf(P_G, n_z), rel=1e-12)
    assert options.gamma == gate_threshold(P_G, n_z)
    assert PDAOptions().gamma == pytest.approx(9.2103, abs=1e-4)  # chi2_2^-1(0.99)


@pytest.mark.parametrize("method", ["mspda_parallel", "mspda_sequential", "nn", "paper_approx"])
@pytest.mark.parametrize("lam", [0.0, 300.0])
def test_no_validated_returns_means_no_update(method, lam):
    """Regression: paper_approx divided by m_k - 1 = 0 when both sensors were silent."""
    rng = np.random.default_rng(4)
    X, P = predicted(rng, 3)
    empty = [SensorReturns(np.zeros((3, 2, 2)), np.zeros((3, 2), bool), pos, R, 0.9,
                           np.full(3, lam)) for pos in SENSORS]
    Xn, Pn, m = pda_update(X, P, empty, opts(method))
    np.testing.assert_allclose(Xn, X)
    np.testing.assert_allclose(Pn, P, rtol=1e-12)
    assert np.all(m == 0)


def test_a_diverged_trial_does_not_break_the_batch():
    rng = np.random.default_rng(6)
    X, P = predicted(rng, 3)
    P[1] = np.nan
    rets = [returns_for(rng, X, P, pos, 3) for pos in SENSORS]
    Xn, Pn, _ = pda_update(X, P, rets, opts())
    assert np.isfinite(Xn[[0, 2]]).all() and np.isfinite(Pn[[0, 2]]).all()


def test_combined_modified_rows_equal_the_mixture_with_g_at_the_combined_return():
    rng = np.random.default_rng(17)
    X, P = predicted(rng, 5)
    rets = [returns_for(rng, X, P, SENSORS[0], 4), returns_for(rng, X, P, SENSORS[1], 3)]
    (b00, b1, b2, B), l1, l2, _ = pair_weights(X, P, *rets, opts())
    zbar = []
    for ret, lin, w in ((rets[0], l1, b1 + B.sum(2)), (rets[1], l2, b2 + B.sum(1))):
        tot = w.sum(1, keepdims=True)
        nu = (w[:, :, None] * lin.nu).sum(1) / np.where(tot > 0, tot, 1.0)
        zbar.append(azel(X[:, :3] - ret.pos) + nu)
    Xn, Pn, _ = pda_update(X, P, rets, opts(mg_at="combined"))
    Xb, Pb = brute_force(X, P, rets, (b00, b1, b2, B), "mgekf", zbar)
    np.testing.assert_allclose(Xn, Xb, rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(Pn, Pb, rtol=1e-7, atol=1e-6 * np.abs(Pb).max())
    Xh, Ph, _ = pda_update(X, P, rets, opts())
    assert not np.allclose(Ph, Pn)  # the choice matters


def test_compiled_wrap_is_the_floor_remainder_bit_for_bit():
    """The filter's angle wrap skips the remainder within one turn; it must give exactly what
    ``(a + pi) % 2pi - pi`` gives in compiled code, near the turn's ends included."""
    from numba import njit

    from trackfuse.tracking.pda import TWO_PI, _wrap

    @njit
    def both(a, ours, remainder):
        for i in range(a.size):
            ours[i] = _wrap(a[i])
            remainder[i] = (a[i] + np.pi) % TWO_PI - np.pi

    rng = np.random.default_rng(5)
    edges = np.array([0.0, -0.0, np.pi, -np.pi, TWO_PI, -TWO_PI, 3 * np.pi, -3 * np.pi])
    a = np.concatenate([rng.uniform(-20.0, 20.0, 200_000), edges,
                        *(e + rng.normal(0.0, s, 2000) for e in edges for s in (1e-9, 1e-15)),
                        [np.nan, np.inf, -np.inf, 1e300]])
    ours, remainder = np.empty_like(a), np.empty_like(a)
    both(a, ours, remainder)
    np.testing.assert_array_equal(ours, remainder)
    assert (np.signbit(ours) == np.signbit(remainder)).all()


def test_symmetrized_is_numpys_half_sum_and_flags_the_non_finite():
    """The scoring's compiled symmetrisation gives numpy's ``0.5 * (P + P')`` bit for bit and
    marks exactly the covariances with a non-finite entry."""
    from trackfuse.tracking.pda import symmetrized

    rng = np.random.default_rng(9)
    P = rng.normal(0.0, 1e4, (7, 5, 6, 6))
    P[2, 3, 1, 4], P[4, 0, 5, 5] = np.nan, np.inf
    P[6, 4, 0, 2] = P[6, 4, 2, 0] = 1.7e308  # finite, but their sum overflows
    out, finite = symmetrized(P)
    with np.errstate(over="ignore"):  # the overflow is meant
        np.testing.assert_array_equal(out, 0.5 * (P + P.transpose(0, 1, 3, 2)))
    np.testing.assert_array_equal(finite, np.isfinite(out).all(axis=(2, 3)))
    assert finite.sum() == 7 * 5 - 3


def test_predict_skipping_the_transitions_zeros_keeps_every_bit():
    """The prediction skips the zero entries of F; with finite X and P (zeros and negative
    zeros among them) it gives exactly the full products ``F X`` and ``F P F' + Q``."""
    from numba import njit

    from trackfuse.tracking.models import cv_process_noise, cv_transition
    from trackfuse.tracking.pda import _predict

    @njit
    def predicted(X, P, F, Q):
        Xp, Pp, FP = np.empty(6), np.empty((6, 6)), np.empty((6, 6))
        _predict(X, P, F, Q, Xp, Pp, FP)
        return Xp, Pp

    @njit
    def full(X, P, F, Q):  # every product, in the same order
        Xp, FP, Pp = np.zeros(6), np.zeros((6, 6)), np.zeros((6, 6))
        for i in range(6):
            for a in range(6):
                Xp[i] += F[i, a] * X[a]
                for j in range(6):
                    FP[i, j] += F[i, a] * P[a, j]
        for i in range(6):
            for j in range(6):
                acc = 0.0
                for a in range(6):
                    acc += FP[i, a] * F[j, a]
                Pp[i, j] = acc + Q[i, j]
        return Xp, Pp

    rng = np.random.default_rng(3)
    F, Q = cv_transition(0.7), cv_process_noise(0.7, 900.0)
    for _ in range(200):
        X, P = rng.normal(0.0, 1e4, 6), rng.normal(0.0, 1e3, (6, 6))
        X[rng.random(6) < 0.3], P[rng.random((6, 6)) < 0.3] = -0.0, 0.0
        P[rng.random((6, 6)) < 0.2] = -0.0
        for ours, theirs in zip(predicted(X, P, F, Q), full(X, P, F, Q), strict=True):
            np.testing.assert_array_equal(ours, theirs)
            assert (np.signbit(ours) == np.signbit(theirs)).all()
