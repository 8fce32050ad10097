"""Triangulation and scenario geometry of paper 002 (docs/papers/passive_assoc.md)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from trackfuse.association.passive_scene import PAPER_TARGETS, SENSORS, los_angles
from trackfuse.association.triangulation import (
    METHODS,
    angle_jacobian,
    angle_residuals,
    common_perpendicular_midpoint,
    least_squares,
    triangulate,
)

S1, S2 = SENSORS


def test_paper_angles_match_spec_check_values():
    deg = np.degrees
    for k, s1, s2 in ((0, (54.46, 6.63), (-68.96, -23.31)), (4, (63.43, 18.54), (-26.57, -6.38)),
                      (7, (59.74, 55.22), (-48.81, 50.73))):
        np.testing.assert_allclose(deg(los_angles(PAPER_TARGETS[k], S1)), s1, atol=0.01)
        np.testing.assert_allclose(deg(los_angles(PAPER_TARGETS[k], S2)), s2, atol=0.01)
    r = np.linalg.norm(PAPER_TARGETS - S1, axis=1)
    assert r.min() == pytest.approx(8660.25, abs=1) and r.max() == pytest.approx(24351.6, abs=1)


@pytest.mark.parametrize("method", METHODS)
def test_noise_free_paper_targets_are_recovered(method):
    z1, z2 = los_angles(PAPER_TARGETS, S1), los_angles(PAPER_TARGETS, S2)
    p = triangulate(z1, z2, S1, S2, method=method, sigma=(0.005, 0.005))
    np.testing.assert_allclose(p, PAPER_TARGETS, atol=1e-6)


coords = st.floats(-30e3, 30e3)
point = st.tuples(coords, coords, st.floats(-5e3, 30e3)).map(np.array)


@settings(max_examples=60, deadline=None)
@given(p=point, s2=point)
def test_noise_free_random_geometry_is_exact_for_both_linear_forms(p, s2):
    # keep the target away from both sensors and off the baseline (a degenerate geometry)
    base = s2 - S1
    off = np.linalg.norm(np.cross(p - S1, base)) / max(np.linalg.norm(base), 1.0)
    if min(np.linalg.norm(p - S1), np.linalg.norm(p - s2), off, np.linalg.norm(base)) < 500:
        return
    z1, z2 = los_angles(p[None], S1), los_angles(p[None], s2)
    for form in ("paper", "unit_normal"):
        if form == "paper" and min(abs(np.cos(z1[0, 0])), abs(np.cos(z2[0, 0]))) < 0.05:
            continue  # W002-8: the elimination row loses z as cos(a) -> 0
        got = least_squares(z1, z2, S1, s2, form)
        np.testing.assert_allclose(got[0], p, atol=1e-6 * np.linalg.norm(p) + 1e-6)


def test_ocr_literal_row_is_wrong_without_noise():
    # OCR row 2 of A: [sin a, 0, -cos a cos b] (sin alpha instead of sin beta): ~5.4 km
    z1, z2 = los_angles(PAPER_TARGETS, S1), los_angles(PAPER_TARGETS, S2)
    rows, rhs = [], []
    for z, s in ((z1, S1), (z2, S2)):
        a, b = z[:, 0], z[:, 1]
        rows += [np.stack([np.sin(a), -np.cos(a), 0 * a], -1),
                 np.stack([np.sin(a), 0 * a, -np.cos(a) * np.cos(b)], -1)]
        rhs += [rows[-2] @ s, rows[-1] @ s]
    A, B = np.stack(rows, 1), np.stack(rhs, 1)
    p = np.linalg.solve(np.swapaxes(A, 1, 2) @ A, np.swapaxes(A, 1, 2) @ B[..., None])[..., 0]
    assert np.linalg.norm(p - PAPER_TARGETS, axis=1).max() > 1000.0


@settings(max_examples=50, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), sigma=st.sampled_from([1e-4, 5e-3, 0.05]))
def test_unit_normal_ls_is_common_perpendicular_midpoint(seed, sigma):
    rng = np.random.default_rng(seed)
    z1 = los_angles(PAPER_TARGETS, S1) + rng.normal(0, sigma, (10, 2))
    z2 = los_angles(PAPER_TARGETS, S2) + rng.normal(0, sigma, (10, 2))
    ls = least_squares(z1, z2, S1, S2, "unit_normal")
    mid = common_perpendicular_midpoint(z1, z2, S1, S2)
    np.testing.assert_allclose(triangulate(z1, z2, S1, S2), mid, atol=1e-9)
    np.testing.assert_allclose(ls, mid, atol=1e-6)


def test_angle_jacobian_matches_central_differences():
    rng = np.random.default_rng(3)
    p = PAPER_TARGETS + rng.normal(0, 500, PAPER_TARGETS.shape)
    for s in (S1, S2):
        J = angle_jacobian(p, s)
        h = 1e-2
        for k in range(3):
            e = np.zeros(3)
            e[k] = h
            fd = (los_angles(p + e, s) - los_angles(p - e, s)) / (2 * h)
            np.testing.assert_allclose(J[:, :, k], fd, rtol=1e-6, atol=1e-12)


def test_ml_and_wls_lower_the_angle_chi_square():
    # ML minimises the normalised angle residuals, so it can only improve on the LS points;
    # WLS weights by range and must be at least close to ML (chi^2 of LS is ~1.3).
    rng = np.random.default_rng(11)
    sigma = 0.005
    z1 = np.tile(los_angles(PAPER_TARGETS, S1), (40, 1))
    z2 = np.tile(los_angles(PAPER_TARGETS, S2), (40, 1))
    z1 = z1 + rng.normal(0, sigma, z1.shape)
    z2 = z2 + rng.normal(0, sigma, z2.shape)

    def chi2(method):
        p = triangulate(z1, z2, S1, S2, method=method, sigma=(sigma, sigma))
        return np.sum((angle_residuals(p, z1, z2, S1, S2) / sigma) ** 2, axis=1)

    ls, wls, ml = chi2("unit_normal"), chi2("wls"), chi2("ml")
    assert np.all(ml <= ls + 1e-9) and np.all(ml <= wls + 1e-9)
    assert ml.mean() == pytest.approx(1.0, abs=0.2)  # 4 residuals - 3 parameters = 1 dof
    assert ls.mean() > ml.mean() + 0.1


def test_unknown_method_raises():
    z = los_angles(PAPER_TARGETS[:1], S1)
    with pytest.raises(ValueError):
        triangulate(z, z, S1, S2, method="nope")
