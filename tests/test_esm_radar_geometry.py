"""TDOA-DF inversion, scenario geometry, time alignment and the manoeuvre index."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from trackfuse.association.esm_scenario import (
    FACTORS,
    ESMNoise,
    RadarNoise,
    SnakeCross,
    esm_factors,
    position_factor_jacobian,
    position_factors,
    radar_factors,
    true_factors,
)
from trackfuse.association.manoeuvre import (
    FIRST_CA_INNOVATION,
    ca_innovations,
    cv_innovations,
    manoeuvre_index,
    nis_threshold,
    windowed_nis,
)
from trackfuse.association.tdoa_df import (
    C,
    carry_forward,
    tdoa_df_jacobian,
    tdoa_df_range,
    tdoa_df_range_sigma,
)
from trackfuse.association.time_align import bracket, interpolate, interpolate_covariance

A1 = np.zeros(2)
A2 = np.array([10_000.0, 0.0])
coord = st.floats(-50_000, 50_000)


@settings(max_examples=100, deadline=None)
@given(coord, coord, st.floats(-3.0, 3.0), st.floats(1_000, 30_000))
def test_tdoa_df_exact_without_noise(x, y, phi, blen):
    p = np.array([x, y])
    b = blen * np.array([np.cos(phi), np.sin(phi)])
    r_true = np.linalg.norm(p)
    dr = r_true - np.linalg.norm(p - b)
    D = 2 * (p @ b / r_true - dr) if r_true > 0 else 0.0
    if r_true < 100 or abs(D) < 1e-3 * blen:
        return  # emitter on a platform or along the ambiguous asymptote
    r, valid = tdoa_df_range(np.arctan2(y, x), dr, b)
    assert valid
    assert r == pytest.approx(r_true, rel=1e-7)


def test_tdoa_df_guard_flags_and_carries():
    b = np.array([1000.0, 0.0])
    # Bearing along +x with dr = |b| cos(0) = 1000 m: zero denominator.
    r, valid = tdoa_df_range(np.array([0.3, 0.0, 0.3]), np.array([100.0, 1000.0, 100.0]), b)
    np.testing.assert_array_equal(valid, [True, False, True])
    assert np.isnan(r[1])
    filled = carry_forward(r[None], valid[None])[0]
    assert filled[1] == r[0]
    # r <= 0 is invalid too (the emitter would be behind A1).
    _, v2 = tdoa_df_range(np.array([np.pi]), np.array([0.0]), b)
    assert not v2[0]
    # Leading invalid samples take the first valid value; all-invalid rows stay NaN.
    x = np.array([[np.nan, 2.0, np.nan, 4.0], [np.nan] * 4])
    v = ~np.isnan(x)
    np.testing.assert_array_equal(carry_forward(x, v)[0], [2.0, 2.0, 2.0, 4.0])
    assert np.all(np.isnan(carry_forward(x, v)[1]))


def test_tdoa_df_jacobian_matches_central_differences():
    rng = np.random.default_rng(3)
    th = rng.uniform(0.6, 1.2, 20)
    dr = rng.uniform(1000, 5000, 20)
    h_t, h_d = 1e-6, 1e-3
    num_t = (tdoa_df_range(th + h_t, dr, A2, 0)[0] - tdoa_df_range(th - h_t, dr, A2, 0)[0]) / (
        2 * h_t)
    num_d = (tdoa_df_range(th, dr + h_d, A2, 0)[0] - tdoa_df_range(th, dr - h_d, A2, 0)[0]) / (
        2 * h_d)
    j_t, j_d = tdoa_df_jacobian(th, dr, A2)
    np.testing.assert_allclose(j_t, num_t, rtol=1e-6)
    np.testing.assert_allclose(j_d, num_d, rtol=1e-6)


def test_esm_range_sigma_about_3km_at_24km():
    f = true_factors(np.array([13200.0, 20000.0]), np.zeros(2), A1, A2, 0.5)
    assert f[0] == pytest.approx(np.hypot(13200, 20000))
    s = tdoa_df_range_sigma(f[2], C * f[3], A2, 0.03, C * 3e-8)
    assert 2500 < s < 4000  # about 3.3 km at the start of the scenario


def test_snake_cross_geometry():
    sc = SnakeCross(separation=200.0)
    t = np.arange(0.0, 50.0, 0.5)
    p, v = sc.states(t)
    np.testing.assert_allclose(p[:, 1] - p[:, 0], np.broadcast_to([200.0, 0.0], (len(t), 2)))
    np.testing.assert_allclose(p[0, :, :], [[13000, 20000], [13200, 20000], [10200, 15000]])
    # T3 crosses the T1/T2 centre line at t_c = 30 s.
    p30, _ = sc.states(np.array([30.0]))
    np.testing.assert_allclose(p30[0, 2], [13100.0, 14000.0])
    np.testing.assert_allclose(v[0, 2], [96.6667, -33.3333], atol=1e-3)
    # Velocity is the derivative of position; peak lateral acceleration ~2.5 g.
    np.testing.assert_allclose(np.gradient(p[:, 0, 0], t)[2:-2], v[2:-2, 0, 0], rtol=1e-2,
                               atol=1.0)
    assert 1000 * (2 * np.pi / 40) ** 2 == pytest.approx(24.67, abs=0.01)
    tf = np.arange(0.0, 40.0, 0.01)  # ... and the simulated T1 reaches it
    accel = np.gradient(sc.states(tf)[1][:, 0, 0], tf)
    assert np.abs(accel).max() == pytest.approx(24.67, abs=0.01)


def test_true_factors_consistent_with_tdoa_df_and_phase():
    p, v = SnakeCross().states(np.arange(0, 50.0))
    f = true_factors(p, v, A1, A2, 0.5)
    assert f.shape == (50, 3, len(FACTORS))
    r, valid = tdoa_df_range(f[..., 2], C * f[..., 3], A2)
    assert valid.all()
    np.testing.assert_allclose(r, f[..., 0], rtol=1e-9)
    np.testing.assert_allclose(f[..., 4], np.pi * np.cos(f[..., 2]))
    np.testing.assert_allclose(f[:, 0, 1], f[:, 1, 1])  # T1 and T2 fly the same manoeuvre


def test_position_factor_jacobian():
    r, th = np.array([20_000.0, 15_000.0]), np.array([0.9, 1.2])
    h = 1e-3
    t_r = (position_factors(r + h, th, A1, A2, 0.5)[0]
           - position_factors(r - h, th, A1, A2, 0.5)[0]) / (2 * h)
    t_t = (position_factors(r, th + 1e-7, A1, A2, 0.5)[0]
           - position_factors(r, th - 1e-7, A1, A2, 0.5)[0]) / 2e-7
    p_t = (position_factors(r, th + 1e-7, A1, A2, 0.5)[1]
           - position_factors(r, th - 1e-7, A1, A2, 0.5)[1]) / 2e-7
    g_r, g_t, h_t = position_factor_jacobian(r, th, A1, A2, 0.5)
    np.testing.assert_allclose([g_r, g_t, h_t], [t_r, t_t, p_t], rtol=1e-5)


def test_sensor_factor_covariances_match_monte_carlo():
    rng = np.random.default_rng(7)
    p, v = SnakeCross().states(np.array([0.0, 1.0]))
    f = true_factors(p, v, A1, A2, 0.5)
    n = 20000
    x, P, valid = esm_factors(f[:, 1], rng.standard_normal((n, 2, 4)), ESMNoise(), A1, A2)
    assert valid.all()
    e = x[:, 0] - f[0, 1]
    emp = np.cov(e[:, [0, 2, 3]].T)
    mod = P[:, 0][:, [0, 2, 3]][:, :, [0, 2, 3]].mean(axis=0)
    np.testing.assert_allclose(np.diag(emp)[1:], np.diag(mod)[1:], rtol=0.05)
    assert np.sqrt(emp[0, 0]) == pytest.approx(np.sqrt(mod[0, 0]), rel=0.15)
    for model in ("table", "derived"):
        xr, Pr = radar_factors(f, rng.standard_normal((n, 2, 3, 5)), RadarNoise(), model, A1,
                               A2, 0.5)
        er = xr[:, 0, 1] - f[0, 1]
        emp_r, mod_r = np.cov(er.T), Pr[:, 0, 1].mean(axis=0)
        sd_e, sd_m = np.sqrt(np.diag(emp_r)), np.sqrt(np.diag(mod_r))
        np.testing.assert_allclose(sd_e, sd_m, rtol=0.05)
        np.testing.assert_allclose(emp_r / np.outer(sd_e, sd_e), mod_r / np.outer(sd_m, sd_m),
                                   atol=0.03)


def test_time_alignment_interpolation_and_variance():
    t_radar = np.arange(0.0, 12.0)
    y = 3.0 * t_radar[:, None] + np.array([1.0, -2.0])  # linear in time, 2 tracks
    t = np.array([0.0, 0.25, 5.5, 10.9])
    m1, a = bracket(t, 1.0, len(t_radar))
    np.testing.assert_allclose(interpolate(y, m1, a), 3.0 * t[:, None] + [1.0, -2.0])
    # Angles across the +-pi cut interpolate along the short arc.
    ang = np.array([np.pi - 0.1, -np.pi + 0.1, -np.pi + 0.3])
    out = interpolate(ang, np.array([0]), np.array([0.5]), angular=True)
    assert abs(abs(out[0]) - np.pi) < 1e-12
    # Variance of the interpolant of independent unit-variance samples.
    rng = np.random.default_rng(1)
    z = rng.standard_normal((200_000, 2))
    unit = np.ones(2)  # two unit-variance radar samples
    for frac in (0.0, 0.3, 0.5):
        emp = np.var((1 - frac) * z[:, 0] + frac * z[:, 1])
        assert emp == pytest.approx(interpolate_covariance(unit, [0], [frac])[0], rel=0.02)
    grid = np.linspace(0, 1, 11)
    assert np.all(interpolate_covariance(unit, np.zeros(11, int), grid) <= 1.0)
    # Batched covariances along a sample axis: the interpolant of each matrix entry.
    P = rng.random((4, 12, 3, 2, 2))
    Pk = interpolate_covariance(P, m1, a, axis=1)
    np.testing.assert_allclose(Pk[:, 2], (1 - a[2]) ** 2 * P[:, 5] + a[2] ** 2 * P[:, 6])
    with pytest.raises(ValueError):
        bracket(np.array([11.5]), 1.0, len(t_radar))


def test_cv_innovations_zero_for_constant_velocity_and_alpha_near_one_for_noise():
    t = np.arange(60.0)
    z = 20_000.0 - 150.0 * t
    V = cv_innovations(z[None], np.full((1, 60), 1e4), 1.0, 0.0)[0]
    assert np.all(np.isnan(V[0, :2]))
    np.testing.assert_allclose(V[0, 2:], 0.0, atol=1e-8)
    rng = np.random.default_rng(2)
    R = np.full((400, 60), 300.0**2)
    zn = z + 300.0 * rng.standard_normal((400, 60))
    alpha = manoeuvre_index(cv_innovations(zn, R, 1.0, 1.0)[0], R, 5)
    assert np.isnan(alpha[:, :2]).all()
    assert 0.95 < alpha[:, 30:].mean() < 1.4  # residual variance is R plus prediction variance


def test_cv_innovation_variance_is_the_spread_of_the_innovations():
    """With the CV model true (white acceleration variance q), each scan's innovations have
    the variance S the filter states, so the NIS has mean 1 (a wrong S, e.g. without the
    prediction variance, fails: the two-point start alone makes it 6 R at scan 2)."""
    rng = np.random.default_rng(6)
    T, q, sigma = 2.0, 0.5, 9.0
    F = np.array([[1.0, T], [0.0, 1.0]])
    G = np.array([T * T / 2, T])
    state = np.tile([4000.0, -30.0], (20_000, 1))
    x = np.empty((20_000, 40))
    for k in range(40):
        x[:, k] = state[:, 0]
        state = state @ F.T + np.sqrt(q) * rng.standard_normal((20_000, 1)) * G
    nu, S = cv_innovations(x + sigma * rng.standard_normal(x.shape), sigma**2, T, q)
    assert np.isnan(nu[:, :2]).all() and np.isnan(S[:, :2]).all()
    for k in (2, 3, 10, 39):
        assert np.var(nu[:, k]) == pytest.approx(S[0, k], rel=0.04), k
    assert np.nanmean(nu**2 / S) == pytest.approx(1.0, abs=0.02)


def test_manoeuvre_index_rises_with_acceleration():
    t = np.arange(60.0)
    z = 20_000.0 - 150.0 * t - 0.5 * 40.0 * np.clip(t - 30, 0, None) ** 2
    R = np.full((1, 60), 10.0**2)
    alpha = manoeuvre_index(cv_innovations(z[None], R, 1.0, 1.0)[0], R, 5)[0]
    assert alpha[25] < 1e-6 and alpha[40] > 10


def test_manoeuvre_index_window():
    V = np.array([[np.nan, np.nan, 1.0, 2.0, 3.0, 4.0]])
    a = manoeuvre_index(V, np.ones_like(V), 2)
    np.testing.assert_allclose(a[0], [np.nan, np.nan, 1.0, 2.5, 6.5, 12.5])


def test_ca_filter_follows_constant_acceleration_exactly():
    t = np.arange(30.0)
    z = 4000.0 + 30.0 * t + 0.5 * 1.2 * t**2  # a quadratic: the CA model holds exactly
    nu, S = ca_innovations(z[None], 81.0, 1.0, 0.0)
    assert np.isnan(nu[0, :FIRST_CA_INNOVATION]).all()
    np.testing.assert_allclose(nu[0, FIRST_CA_INNOVATION:], 0.0, atol=1e-8)
    assert (S[0, FIRST_CA_INNOVATION:] > 81.0).all()
    # The three-point start covariance is exact: the first innovation's variance S matches
    # its Monte Carlo variance.
    rng = np.random.default_rng(4)
    zn = z + 9.0 * rng.standard_normal((20_000, 30))
    nu, S = ca_innovations(zn, 81.0, 1.0, 0.0)
    assert np.var(nu[:, 3]) == pytest.approx(S[0, 3], rel=0.03)


def test_windowed_nis_is_chi2_without_manoeuvre():
    """With the model true, N alpha ~ chi2(N): mean 1 and the stated exceedance rate."""
    rng = np.random.default_rng(5)
    sigma_v = 0.05
    # Truth: the DWPA process itself, x(k+1) = F x(k) + G v(k), v ~ N(0, sigma_v^2).
    F = np.array([[1.0, 1.0, 0.5], [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]])
    G = np.array([0.5, 1.0, 1.0])
    state = np.tile([4000.0, 30.0, 0.5], (4000, 1))
    x = np.empty((4000, 50))
    for k in range(50):
        x[:, k] = state[:, 0]
        state = state @ F.T + sigma_v * rng.standard_normal((4000, 1)) * G
    z = x + 9.0 * rng.standard_normal(x.shape)
    nu, S = ca_innovations(z, 81.0, 1.0, sigma_v**2)
    alpha = windowed_nis(nu, S, 5)
    first = FIRST_CA_INNOVATION + 4
    assert np.isnan(alpha[:, :first]).all() and np.isfinite(alpha[:, first:]).all()
    assert alpha[:, first:].mean() == pytest.approx(1.0, abs=0.04)
    exceed = (alpha[:, first:] > nis_threshold(5, 0.01)).mean()
    assert 0.006 < exceed < 0.016
    assert nis_threshold(5, 0.01) == pytest.approx(15.086 / 5, rel=1e-4)


def test_windowed_nis_window_arithmetic():
    nu = np.array([[np.nan, np.nan, np.nan, 1.0, 2.0, 3.0, 4.0]])
    S = np.ones_like(nu)
    np.testing.assert_allclose(windowed_nis(nu, S, 2)[0],
                               [np.nan, np.nan, np.nan, np.nan, 2.5, 6.5, 12.5])
