"""PCRLB (docs/papers/twin_sensor.md): the reference table within 1 %, and the IRF sanity values."""

import numpy as np
import pytest

from trackfuse.tracking.initialization import los_prior_covariance
from trackfuse.tracking.models import cv_process_noise, cv_transition
from trackfuse.tracking.pcrlb import (
    Q2_TABLES,
    compute_q2_table,
    information_recursion,
    irf_q2,
    irf_q2_interp,
    measurement_information,
    position_bound,
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
        assert abs(irf_q2(lam_w, 1.0, n_samples=40000) - expected) < 0.025
    assert irf_q2(0.0, 0.8) == 0.8
    assert irf_q2(0.05, 0.8) < irf_q2(0.05, 1.0)
    grid = np.array([0.0, 1e-3, 0.05, 0.2, 1.0])
    q = irf_q2_interp(grid, 1.0)
    assert q[0] == 1.0 and np.all(np.diff(q) < 0)
    assert abs(q[2] - 0.55) < 0.03


@pytest.mark.parametrize("P_D", sorted(Q2_TABLES))
def test_the_stored_q2_tables_are_the_monte_carlo(P_D):
    """To 1e-12, not bit for bit: np.exp's last bit depends on the CPU's vector unit."""
    np.testing.assert_allclose(compute_q2_table(P_D), Q2_TABLES[P_D], rtol=1e-12, atol=0)
