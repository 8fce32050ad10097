"""Az/el measurement model, Jacobian, MGEKF identities and gates (docs/papers/twin_sensor.md)."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from pda_reference import unit_disk

from trackfuse.tracking.models import wrap
from trackfuse.tracking.sensors import (
    azel,
    azel_jacobian,
    ellipse_points,
    gate_threshold,
    gate_volume,
    modified_rows,
)

coord = st.floats(-3e5, 3e5, allow_nan=False)


def relative_position(dx, dy, dz):
    d = np.array([dx, dy, dz])
    # keep away from the vertical (rh -> 0) where azimuth is undefined
    if np.hypot(dx, dy) < 1e3:
        d[0] += 2e3
    return d


@settings(max_examples=60, deadline=None)
@given(coord, coord, st.floats(-2e4, 2e4))
def test_jacobian_matches_central_differences(dx, dy, dz):
    d = relative_position(dx, dy, dz)
    H = azel_jacobian(d)
    num = np.zeros((2, 6))
    for j in range(3):
        h = 1e-3 * max(abs(d[j]), 1.0)
        e = np.zeros(3)
        e[j] = h
        num[:, j] = wrap(azel(d + e) - azel(d - e)) / (2 * h)
    scale = np.abs(H[:, :3]).max()
    np.testing.assert_allclose(H, num, rtol=0, atol=1e-6 * scale)
    assert np.all(H[:, 3:] == 0)


def test_jacobian_corrects_the_ocr_signs():
    d = np.array([-153209.0, 128558.0, 2000.0])
    H = azel_jacobian(d)
    rh2 = d[0] ** 2 + d[1] ** 2
    r2 = rh2 + d[2] ** 2
    # row 2, first entry has x (not y); second entry is negative
    np.testing.assert_allclose(H[1, 0], -d[0] * d[2] / (np.sqrt(rh2) * r2))
    np.testing.assert_allclose(H[1, 1], -d[1] * d[2] / (np.sqrt(rh2) * r2))


@settings(max_examples=80, deadline=None)
@given(coord, coord, st.floats(-2e4, 2e4), st.floats(-5e3, 5e3), st.floats(-5e3, 5e3),
       st.floats(-2e3, 2e3))
def test_mgekf_identities_hold_exactly(dx, dy, dz, ex, ey, ez):
    """tan(th - thbar) = g_az (x - xbar), tan(ph - phbar') = g_el (x - xbar)."""
    d_bar = relative_position(dx, dy, dz)
    d_true = d_bar + np.array([ex, ey, ez])
    if np.hypot(*d_true[:2]) < 1e3:
        return
    z = azel(d_true)
    g = modified_rows(z, d_bar)
    dx_state = np.r_[d_true - d_bar, 0.0, 0.0, 0.0]
    th_bar = np.arctan2(d_bar[1], d_bar[0])
    rho = d_bar[0] * np.cos(z[0]) + d_bar[1] * np.sin(z[0])
    if abs(rho) < 1e3:
        return
    ph_bar = np.arctan2(d_bar[2], rho)
    lhs = np.array([np.tan(wrap(z[0] - th_bar)), np.tan(z[1] - ph_bar)])
    np.testing.assert_allclose(g @ dx_state, lhs, rtol=1e-10, atol=1e-10)


def test_modified_rows_tend_to_the_jacobian_without_error():
    d = np.array([-1.5e5, 1.3e5, 2.0e3])
    np.testing.assert_allclose(modified_rows(azel(d), d), azel_jacobian(d), rtol=1e-12)


def test_modified_rows_2d_form_of_song_speyer():
    """In the plane, with bearing beta from the y axis, g = [cos b, -sin b]/(x sin b + y cos b)."""
    xbar, ybar, beta = 3.0e4, 5.0e4, 0.7
    d = np.array([xbar, ybar, 0.0])
    th = np.pi / 2 - beta  # azimuth from +x
    g = modified_rows(np.array([th, 0.0]), d)[0, :2]
    quoted = np.array([np.cos(beta), -np.sin(beta)]) / (xbar * np.sin(beta) + ybar * np.cos(beta))
    # d(beta) = -d(th), so the rows differ by a sign
    np.testing.assert_allclose(g, -quoted, rtol=1e-12)


def test_gate_volume_and_uniform_ellipse_points():
    S = np.array([[[4e-4, 1e-4], [1e-4, 2e-4]]])
    gamma = gate_threshold(0.99)
    assert abs(gamma - 9.2103) < 1e-3
    V = gate_volume(S, gamma)[0]
    np.testing.assert_allclose(V, np.pi * gamma * np.sqrt(np.linalg.det(S[0])))
    rng = np.random.default_rng(1)
    u = unit_disk(rng, 20000)[None]
    z = ellipse_points(u, np.zeros((1, 2)), S, gamma)[0]
    d2 = np.einsum("ma,ab,mb->m", z, np.linalg.inv(S[0]), z)
    assert d2.max() <= gamma * (1 + 1e-12)
    # uniform in the ellipse: d2/gamma is uniform on [0, 1]
    assert abs(np.mean(d2 / gamma) - 0.5) < 0.01
    # gate probability of a Gaussian innovation
    nu = rng.multivariate_normal(np.zeros(2), S[0], 40000)
    inside = np.einsum("ma,ab,mb->m", nu, np.linalg.inv(S[0]), nu) <= gamma
    assert abs(inside.mean() - 0.99) < 0.003


def test_closed_form_2x2_inverse_and_cholesky():
    from trackfuse.tracking.sensors import chol2, inv2

    rng = np.random.default_rng(0)
    A = rng.normal(size=(50, 2, 2))
    S = A @ A.transpose(0, 2, 1) + 0.1 * np.eye(2)
    inv, det = inv2(S)
    np.testing.assert_allclose(inv, np.linalg.inv(S), rtol=1e-10)
    np.testing.assert_allclose(det, np.linalg.det(S), rtol=1e-10)
    np.testing.assert_allclose(chol2(S), np.linalg.cholesky(S), rtol=1e-10)
    bad = np.array([[[1.0, 2.0], [2.0, 1.0]], [[np.nan, 0.0], [0.0, 1.0]]])
    assert not np.isfinite(chol2(bad)).all(axis=(1, 2)).any()  # no exception, NaN instead
