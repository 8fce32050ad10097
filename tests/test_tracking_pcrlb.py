"""PCRLB (docs/papers/twin_sensor.md): the reference table within 1 %, and the IRF sanity values."""

import numpy as np
import pytest

from trackfuse.tracking.initialization import los_prior_covariance
from trackfuse.tracking.models import cv_process_noise, cv_transition
from trackfuse.tracking.pcrlb import (
    Q2_TABLES,
    _q2_table,
    information_recursion,
    irf_q2,
    irf_q2_interp,
    measurement_information,
    position_bound,
    q2_grid,
    range_bound,
)
from trackfuse.tracking.platforms import orbit_positions

TARGET = np.array([0.0, 128558.0, 4000.0])
T = np.arange(21.0)
PLATFORM = orbit_positions(T, np.array([153209.0, 0.0, 2000.0]), TARGET[:2], 500.0, 50.0, 1)
X_TRUE = np.tile(np.r_[TARGET, 0.0, 0.0, 0.0], (21, 1))
R2 = np.stack([np.diag([1e-4, 1e-4])] * 2)  # two co-located sensors, 0.01 rad


@pytest.mark.parametrize(("sigma_r0", "q", "expected_km"), [
    (20e3, 0.0, [20.0, 19.8, 18.8, 15.2]),
    (20e3, 900.0, [20.0, 19.8, 19.0, 17.9]),
    (2e3, 0.0, [2.00, 2.01, 2.02, 2.08]),
])
def test_spec_table_with_prior(sigma_r0, q, expected_km):
    P0 = los_prior_covariance(TARGET - PLATFORM[0], sigma_r0, 0.01 / np.sqrt(2), 30.0)
    Jz = measurement_information(X_TRUE[1:], np.stack([PLATFORM[1:]] * 2, axis=1), R2)
    Jinv = information_recursion(np.linalg.inv(P0), cv_transition(1.0),
                                 cv_process_noise(1.0, q), Jz)
    rb = range_bound(Jinv, X_TRUE, PLATFORM)
    np.testing.assert_allclose(rb[[1, 5, 10, 20]] / 1e3, expected_km, rtol=0.01)


def test_spec_table_without_prior_position_only():
    """Known-stationary target, no prior: J = sum of the looks at t = 0..k (k + 1 scans)."""
    Jz = measurement_information(X_TRUE, np.stack([PLATFORM] * 2, axis=1), R2).sum(axis=1)
    J = np.cumsum(Jz[:, :3, :3], axis=0)
    for k, expected in [(5, 134.5), (10, 53.7), (20, 20.3)]:
        Jinv = np.linalg.inv(J[k])
        u = (TARGET - PLATFORM[k]) / np.linalg.norm(TARGET - PLATFORM[k])
        assert abs(np.sqrt(u @ Jinv @ u) / 1e3 / expected - 1) < 0.01
    Jinv = np.linalg.inv(J[20])
    u = (TARGET - PLATFORM[20]) / np.linalg.norm(TARGET - PLATFORM[20])
    cross = np.sqrt(np.trace(Jinv) - u @ Jinv @ u)
    assert abs(cross / 1e3 - 0.67) < 0.01


def test_two_colocated_sensors_double_the_information_and_irf_scales_it():
    one = measurement_information(X_TRUE[1:], PLATFORM[1:, None], R2[:1])
    two = measurement_information(X_TRUE[1:], np.stack([PLATFORM[1:]] * 2, axis=1), R2)
    np.testing.assert_allclose(two.sum(1), 2 * one.sum(1))
    P0 = los_prior_covariance(TARGET - PLATFORM[0], 20e3, 0.007, 30.0)
    J0, F, Q = np.linalg.inv(P0), cv_transition(1.0), cv_process_noise(1.0, 0.0)
    full = information_recursion(J0, F, Q, two)
    half = information_recursion(J0, F, Q, two, q2=np.full((20, 2), 0.5))
    np.testing.assert_allclose(half, information_recursion(J0, F, Q, one), rtol=1e-8,
                               atol=1e-12)
    assert np.all(position_bound(half) >= position_bound(full))


def test_irf_sanity_values():
    for lam_w, expected in [(0.0, 1.0), (0.01, 0.87), (0.05, 0.56), (0.1, 0.37), (0.2, 0.20)]:
        assert abs(irf_q2(lam_w, 1.0, n_samples=40000)[0] - expected) < 0.025
    assert irf_q2(0.0, 0.8) == (0.8, 0.0)
    assert irf_q2(0.05, 0.8, n_samples=40000)[0] < irf_q2(0.05, 1.0, n_samples=40000)[0]
    q = irf_q2_interp(np.array([0.0, 1e-3, 0.05]), 1.0)
    assert q[0] == 1.0 and abs(q[2] - 0.55) < 0.03
    _, table = _q2_table(1.0)
    assert not table.flags.writeable  # the lru_cache shares it


def _first_order_slope(h=0.1, n_r=40):
    """``-dq2/dlam_w`` at 0 for ``P_D = 1`` by quadrature: one clutter point ``z_c`` on the
    12 x 12 square beside the target ``z_t = (r, 0)`` (isotropy), ``s`` their weighted mean:
    ``int_0^inf r e^(-r^2/2) int (r^2 - |s|^2) / 2 dz_c dr``."""
    g = np.arange(-6.0, 6.0 + h / 2, h)
    X, Y = np.meshgrid(g, g, indexing="ij")
    e_c = np.exp(-0.5 * (X**2 + Y**2))
    x, w = np.polynomial.legendre.leggauss(n_r)
    r = 4.5 * (x + 1.0)[:, None, None]  # Gauss-Legendre on [0, 9]
    e_t = np.exp(-0.5 * r**2)
    s2 = ((e_t * r + e_c * X) ** 2 + (e_c * Y) ** 2) / (e_t + e_c) ** 2
    F = 0.5 * (r**2 - s2).sum(axis=(1, 2)) * h * h
    return 4.5 * np.sum(w * r[:, 0, 0] * e_t[:, 0, 0] * F)


def test_irf_matches_its_first_order_limit_within_its_error_bar():
    """q2 = 1 - c1 lam_w + O(lam_w^2): an independent check of the estimator and its s.e."""
    lam_w = 1e-5
    q, se = irf_q2(lam_w, 1.0)
    c1 = _first_order_slope()
    assert abs(c1 - 13.878) < 1e-3  # converged (13.87805 on finer grids)
    assert se / lam_w < 0.1  # slope known to 0.7 % or better
    assert abs((1.0 - q) / lam_w - c1) < 4 * se / lam_w


@pytest.mark.parametrize("P_D", sorted(Q2_TABLES))
def test_the_stored_q2_tables_bound_and_decrease(P_D):
    """Clutter garbles the measurement set: q2 <= P_D, non-increasing in density, without any
    post-processing of the Monte Carlo values."""
    table = np.array(Q2_TABLES[P_D])
    assert table[0] == P_D and np.all(table <= P_D)
    assert np.all(np.diff(table) < 0)


@pytest.mark.parametrize(("P_D", "points"), [(1.0, [1, 18, 28]), (0.8, [1, 18])])
def test_the_stored_q2_tables_are_the_monte_carlo(P_D, points):
    """To 1e-12, not bit for bit: np.exp's last bit depends on the CPU's vector unit. Point 28
    (lam_w = 0.28, P_D = 1) has the table's largest relative standard error (0.12 %)."""
    for i in points:
        q, se = irf_q2(q2_grid()[i], P_D)
        np.testing.assert_allclose(q, Q2_TABLES[P_D][i], rtol=1e-12, atol=0)
        assert se <= 0.002 * q


def test_a_table_computed_on_demand_lies_between_the_stored_ones():
    """A detection probability not stored is tabulated with fewer samples: its ``q2`` must
    still be at most ``P_D``, fall with clutter and lie between the ``P_D`` 0.8 and 1 tables
    (information grows with ``P_D``)."""
    lam = np.geomspace(1e-4, 3.0, 12)
    low, mid, high = (irf_q2_interp(lam, P_D) for P_D in (0.8, 0.9, 1.0))
    assert np.all(mid <= 0.9) and np.all(np.diff(mid) < 0)
    assert np.all((low < mid) & (mid < high))


def test_no_detection_gives_no_information_not_nan():
    assert irf_q2(0.5, 0.0) == (0.0, 0.0)
    assert np.all(irf_q2_interp(np.array([0.0, 0.01, 2.0]), 0.0) == 0.0)
