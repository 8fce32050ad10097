"""Memberships, composition, decisions and dynamic weights (docs/papers/esm_radar.md)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from trackfuse.association import ahp
from trackfuse.association.dynamic_weights import dynamic_weights
from trackfuse.association.fuzzy import (
    compose,
    decide_mean,
    decide_vote,
    gaussian_membership,
    gaussian_posterior_membership,
    inverse_distance_membership,
)
from trackfuse.tracking.models import wrap

distances = arrays(float, (4, 3), elements=st.floats(0.0, 1e4))
A5 = ahp.root_weights(ahp.PAPER_001_JUDGEMENT)


@settings(max_examples=60, deadline=None)
@given(distances, st.floats(1e-3, 10.0))
def test_membership_rows_are_distributions(d, eps):
    for R in (inverse_distance_membership(d, eps, "l1"),
              gaussian_posterior_membership(d, np.full_like(d, 50.0**2))):
        assert np.all(R >= 0) and np.all(R <= 1)
        np.testing.assert_allclose(R.sum(axis=-1), 1.0, rtol=1e-12)
    R2 = inverse_distance_membership(d, eps, "l2")
    np.testing.assert_allclose(np.linalg.norm(R2, axis=-1), 1.0, rtol=1e-12)


@settings(max_examples=60, deadline=None)
@given(distances)
def test_closer_track_gets_larger_membership(d):
    for R in (inverse_distance_membership(d, 1e-3), gaussian_membership(d, 1e6),
              gaussian_posterior_membership(d, np.full_like(d, 1e6))):
        order = np.argsort(d, axis=-1, kind="stable")
        r_sorted = np.take_along_axis(R, order, axis=-1)
        assert np.all(np.diff(r_sorted, axis=-1) <= 1e-15)


def test_inverse_distance_values_and_floor():
    R = inverse_distance_membership(np.array([1.0, 2.0, 4.0]), 1e-3)
    np.testing.assert_allclose(R, np.array([4, 2, 1]) / 7)
    # A zero distance is floored at eps, not infinite: it takes all but eps-sized mass.
    R0 = inverse_distance_membership(np.array([0.0, 1.0, 1.0]), 1e-3)
    np.testing.assert_allclose(R0, np.array([1000, 1, 1]) / 1002)


def test_gaussian_grade_and_stable_posterior():
    np.testing.assert_allclose(gaussian_membership(np.array([0.0, 1.0]), 1.0), [1.0,
                               np.exp(-0.5)])
    # Far-off tracks underflow in exp(); the softmax form still returns a distribution.
    R = gaussian_posterior_membership(np.array([1e4, 1e4 + 1, 2e4]), np.array(1.0))
    np.testing.assert_allclose(R.sum(), 1.0)
    assert R[0] > 0.6 and R[2] == 0.0


def test_wrap_range():
    a = wrap(np.array([np.pi, -np.pi, 3 * np.pi + 0.1, 0.2]))
    assert np.all(a >= -np.pi) and np.all(a < np.pi)
    np.testing.assert_allclose(a[2:], [-np.pi + 0.1, 0.2])


def test_compose_weighted_average_keeps_distribution():
    rng = np.random.default_rng(0)
    R = rng.random((7, 5, 3))
    R /= R.sum(axis=-1, keepdims=True)
    b = compose(A5, R)
    np.testing.assert_allclose(b.sum(axis=-1), 1.0)
    np.testing.assert_allclose(b[2], A5 @ R[2])


def test_decisions():
    b = np.array([[0.2, 0.5, 0.3], [0.6, 0.3, 0.1], [0.2, 0.45, 0.35]])
    j, margin = decide_mean(b)
    assert j == 1 and margin == pytest.approx((1.25 - 1.0) / 3)
    jv, mv = decide_vote(b)
    assert jv == 1 and mv == pytest.approx(1 / 3)
    # Vote tie (one scan each for tracks 0 and 1) broken by the larger mean membership.
    jt, _ = decide_vote(np.array([[0.9, 0.1, 0.0], [0.3, 0.4, 0.3]]))
    assert jt == 0
    # Batched shapes.
    jb, _ = decide_mean(np.stack([b, b[:, ::-1]]))
    np.testing.assert_array_equal(jb, [1, 1])


@settings(max_examples=80, deadline=None)
@given(arrays(float, st.integers(1, 40), elements=st.floats(0.0, 1e6)),
       st.floats(1e-3, 1e3), st.sampled_from(["fixed", "running_max"]))
def test_dynamic_weights_sum_to_one_for_any_alpha(alpha, alpha_max, mode):
    a = dynamic_weights(A5, alpha, alpha_max, mode)
    assert a.shape == (len(alpha), 5)
    np.testing.assert_allclose(a.sum(axis=-1), 1.0, rtol=1e-12)
    assert np.all(a[:, 1:] > 0) and np.all(a[:, 0] >= 0)
    # Only the range weight falls; the others keep their static ratios.
    np.testing.assert_allclose(a[:, 1:] / a[:, 1:2], np.broadcast_to(A5[1:] / A5[1], (len(alpha),
                               4)), rtol=1e-10)
    assert np.all(a[:, 0] <= A5[0] + 1e-15)


@settings(max_examples=40, deadline=None)
@given(arrays(float, 30, elements=st.floats(0.0, 10.0)))
def test_range_weight_bounds_when_alpha_below_alpha_max(alpha):
    a = dynamic_weights(A5, alpha, 10.0)
    lo = A5[0] * np.exp(-1) / (A5[0] * np.exp(-1) + 1 - A5[0])
    assert lo == pytest.approx(0.277, abs=1e-3)
    assert np.all(a[:, 0] >= lo - 1e-12) and np.all(a[:, 0] <= A5[0] + 1e-12)


def test_dynamic_weights_lag_and_values():
    alpha = np.array([10.0, 0.0, 5.0])
    a = dynamic_weights(A5, alpha, 10.0)
    np.testing.assert_allclose(a[0], A5)               # scan 0: static weights
    a1p = A5[0] * np.exp(-1.0)                          # from alpha(0) = alpha_max
    np.testing.assert_allclose(a[1, 0], a1p / (a1p + A5[1:].sum()))
    np.testing.assert_allclose(a[2], A5)               # from alpha(1) = 0
    # Batched over trials.
    ab = dynamic_weights(A5, np.stack([alpha, alpha[::-1]]), 10.0)
    np.testing.assert_allclose(ab[0], a)


def test_printed_eq16_diverges_but_corrected_does_not():
    # W001-3: with a'_1 = 0.3 held for 20 steps the printed recursion blows up.
    a1 = np.array([0.51, 0.26, 0.13, 0.07, 0.03])
    printed = a1.copy()
    for _ in range(20):
        D = 0.3 + a1[1:].sum()
        printed = np.concatenate([[0.3 / D], printed[1:] / D])
    assert printed.sum() > 40
    alpha = np.full(21, 10.0 * np.sqrt(np.log(0.51 / 0.3)))
    np.testing.assert_allclose(dynamic_weights(a1, alpha, 10.0).sum(axis=-1), 1.0)
