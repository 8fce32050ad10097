"""AHP weights and consistency against paper 001 Table 1 and textbook properties."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from trackfuse.association import ahp

B = ahp.PAPER_001_JUDGEMENT


def test_paper_001_lambda_ci_cr():
    lam = ahp.lambda_max(B)
    assert lam == pytest.approx(5.2375, abs=1e-4)
    assert ahp.consistency_index(lam, 5) == pytest.approx(0.059375, abs=1e-4)
    assert ahp.consistency_ratio(B) == pytest.approx(0.053, abs=1e-3)


def test_paper_001_root_and_eigen_weights():
    np.testing.assert_allclose(ahp.root_weights(B), [0.5100, 0.2638, 0.1296, 0.0636, 0.0329],
                               atol=1e-4)
    np.testing.assert_allclose(ahp.eigen_weights(B), [0.5128, 0.2615, 0.1290, 0.0634, 0.0333],
                               atol=1e-4)
    # Row geometric means of paper 001 Table 1.
    g = np.exp(np.log(B).mean(axis=1))
    np.testing.assert_allclose(g, [3.9363, 2.0362, 1.0, 0.4911, 0.2540], atol=1e-4)


def test_eigen_weights_are_the_principal_eigenvector():
    w = ahp.eigen_weights(B)
    np.testing.assert_allclose(B @ w, ahp.lambda_max(B) * w, rtol=1e-10)
    assert ahp.lambda_max(B, w) == pytest.approx(ahp.lambda_max(B), rel=1e-12)


def test_three_factor_baseline_weights():
    sub = B[:3, :3]
    np.testing.assert_allclose(ahp.root_weights(sub), [0.637, 0.258, 0.105], atol=1e-3)
    assert ahp.lambda_max(sub) == pytest.approx(3.0385, abs=1e-4)
    assert ahp.consistency_ratio(sub) == pytest.approx(0.033, abs=1e-3)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(0.05, 20.0), min_size=3, max_size=9))
def test_consistent_matrix_recovers_weights(values):
    w = np.array(values) / np.sum(values)
    M = w[:, None] / w[None, :]
    np.testing.assert_allclose(ahp.root_weights(M), w, rtol=1e-9)
    np.testing.assert_allclose(ahp.eigen_weights(M), w, rtol=1e-7)
    assert ahp.lambda_max(M) == pytest.approx(len(w), rel=1e-9)
    assert abs(ahp.consistency_ratio(M)) < 1e-8


def test_inconsistency_raises_cr():
    M = B.copy()
    M[0, 4], M[4, 0] = 1 / 9, 9.0  # reverse the strongest judgement
    assert ahp.consistency_ratio(M) > 0.1 > ahp.consistency_ratio(B)


def test_rejects_bad_input():
    with pytest.raises(ValueError):
        ahp.root_weights(np.array([[1.0, -1.0], [1.0, 1.0]]))
    with pytest.raises(ValueError):
        ahp.weights(B, "median")
