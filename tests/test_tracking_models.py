"""CV model and platform geometry (docs/papers/twin_sensor.md, Model)."""

import numpy as np

from trackfuse.tracking.models import cv_noise_gain, cv_process_noise, cv_transition, wrap
from trackfuse.tracking.platforms import baseline_offset, orbit_positions, straight_positions


def test_process_noise_blocks_symmetric_and_rank_three():
    T, q = 2.0, 900.0
    Q = cv_process_noise(T, q)
    np.testing.assert_allclose(Q, Q.T)
    np.testing.assert_allclose(Q[:3, :3], q * T**4 / 4 * np.eye(3))
    np.testing.assert_allclose(Q[3:, :3], q * T**3 / 2 * np.eye(3))  # not T^3/4 (OCR)
    np.testing.assert_allclose(Q[3:, 3:], q * T**2 * np.eye(3))
    assert np.linalg.matrix_rank(Q) == 3


def test_transition_moves_position_by_velocity():
    F = cv_transition(0.5)
    x = np.array([1.0, 2.0, 3.0, 10.0, -4.0, 2.0])
    np.testing.assert_allclose(F @ x, [6.0, 0.0, 4.0, 10.0, -4.0, 2.0])
    # constant acceleration a over T moves the state by G a exactly
    a = np.array([1.0, -2.0, 0.5])
    np.testing.assert_allclose(cv_noise_gain(0.5) @ a, np.r_[0.125 * a, 0.5 * a])


def test_wrap_range_and_identity():
    a = np.linspace(-20, 20, 1001)
    w = wrap(a)
    assert np.all(w >= -np.pi) and np.all(w < np.pi)
    np.testing.assert_allclose(np.sin(w), np.sin(a), atol=1e-12)
    np.testing.assert_allclose(np.cos(w), np.cos(a), atol=1e-12)


def test_paper_orbit_geometry():
    t = np.arange(21.0)
    centre = np.array([0.0, 128558.0])
    p = orbit_positions(t, np.array([153209.0, 0.0, 2000.0]), centre, 500.0, 50.0, 1)
    np.testing.assert_allclose(p[0], [153209.0, 0.0, 2000.0], atol=1e-6)
    radius = np.hypot(*(p[:, :2] - centre).T)
    np.testing.assert_allclose(radius, 200000.4, rtol=1e-6)
    np.testing.assert_allclose(p[:, 2], 2000.0 + 50.0 * t)
    step = np.linalg.norm(np.diff(p[:, :2], axis=0), axis=1)
    np.testing.assert_allclose(step, 500.0, rtol=1e-5)  # chord of a 2.5 mrad arc
    # counter-clockwise: the phase increases
    phase = np.unwrap(np.arctan2(p[:, 1] - centre[1], p[:, 0] - centre[0]))
    np.testing.assert_allclose(np.degrees(phase[0]), -40.0, atol=1e-3)
    assert np.all(np.diff(phase) > 0)
    cw = orbit_positions(t, np.array([153209.0, 0.0, 2000.0]), centre, 500.0, 50.0, -1)
    assert np.all(np.diff(np.arctan2(cw[:, 1] - centre[1], cw[:, 0] - centre[0])) < 0)


def test_straight_flight_and_baseline():
    p = straight_positions(np.array([0.0, 2.0]), np.zeros(3), 100.0, np.pi / 2, 5.0)
    np.testing.assert_allclose(p[1], [0.0, 200.0, 10.0], atol=1e-9)
    off = baseline_offset(np.radians(140.0), 5000.0, np.pi / 2)
    assert abs(np.linalg.norm(off) - 5000.0) < 1e-9 and off[2] == 0.0
    los = np.array([np.cos(np.radians(140.0)), np.sin(np.radians(140.0)), 0.0])
    assert abs(off @ los) < 1e-9  # broadside
