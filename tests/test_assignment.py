"""Weights and exact solvers of paper 002 (docs/papers/passive_assoc.md)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from trackfuse.association.assignment import (
    BRUTE_FORCE,
    COSTS,
    EXACT,
    objective,
    pair_weights,
    solve_exact,
)
from trackfuse.association.passive_scene import (
    SENSORS,
    los_angles,
    scene_targets,
    simulate_scan,
    true_partners,
)

S1, S2 = SENSORS


def assert_feasible(sol, m1, m2):
    assert sol.partner1.shape == (m1,) and sol.partner2.shape == (m2,)
    for i, j in enumerate(sol.partner1):
        if j >= 0:
            assert sol.partner2[j] == i
    for j, i in enumerate(sol.partner2):
        if i >= 0:
            assert sol.partner1[i] == j


gains = st.tuples(st.integers(0, 5), st.integers(0, 5)).flatmap(
    lambda shape: arrays(np.float64, shape, elements=st.floats(-20, 20)))


@settings(max_examples=300, deadline=None)
@given(gain=gains)
def test_exact_solvers_agree_with_brute_force(gain):
    m1, m2 = gain.shape
    brute = solve_exact(gain, BRUTE_FORCE)
    for method in EXACT:
        sol = solve_exact(gain, method)
        assert_feasible(sol, m1, m2)
        # the reported objective is the sum of the declared pairs' gains (counted here
        # independently of assignment.objective, which from_pairs itself uses)
        pairs = [(i, j) for i, j in enumerate(sol.partner1.tolist()) if j >= 0]
        assert sol.objective == pytest.approx(sum(gain[i, j] for i, j in pairs))
        assert objective(gain, sol.partner1) == sol.objective
        assert sol.objective == pytest.approx(brute.objective, abs=1e-9)
        # an optimum never declares a pair with a negative gain
        rows = np.flatnonzero(sol.partner1 >= 0)
        assert np.all(gain[rows, sol.partner1[rows]] >= -1e-12)


def scan(seed, n=5, sigma=0.005, p_d=0.95, p_f=0.05):
    rng = np.random.default_rng(seed)
    t, noise, clutter, shuffle = rng.spawn(4)
    return simulate_scan(scene_targets(n, "paper", t), sigma, sigma, p_d, p_f, noise, clutter,
                         shuffle)


def test_exact_equals_enumeration_on_200_paper_scenes():
    for seed in range(200):
        sc = scan(seed)
        w = pair_weights(*sc.z, S1, S2, 0.005, 0.005, 0.95, 0.05)
        brute = solve_exact(w.gain, BRUTE_FORCE).objective
        for method in ("lsa_clip", "lsa_augmented"):
            assert solve_exact(w.gain, method).objective == pytest.approx(brute, abs=1e-9)


@pytest.mark.parametrize("method", [*EXACT, BRUTE_FORCE])
@pytest.mark.parametrize("cost", COSTS)
def test_noise_free_scene_without_false_alarms_gives_the_truth(method, cost):
    for n in (5, 7, 10):
        if method == BRUTE_FORCE and n > 7:
            continue
        rng = np.random.default_rng(n)
        sc = simulate_scan(scene_targets(n, "paper", rng), 0.0, 0.0, 1.0, 0.0, rng, rng, rng)
        w = pair_weights(*sc.z, S1, S2, 0.005, 0.005, 0.95, 0.05, cost=cost, psi=sc.psi)
        sol = solve_exact(w.gain, method)
        t1, t2 = true_partners(*sc.labels)
        np.testing.assert_array_equal(sol.partner1, t1)
        np.testing.assert_array_equal(sol.partner2, t2)


def test_paper_weights_sign_and_implied_gate():
    # docs/papers/passive_assoc.md (W002-4): a pair beats two unpaired measurements iff
    # chi2 < 46.8 (sigma 0.005, P_D 0.95,
    # p_f 0.05), and the weight decreases with chi2 (the sign of eq. 17 corrected).
    sigma, p_d, p_f = 0.005, 0.95, 0.05
    threshold = 4 * np.log(p_d / (2 * np.pi * sigma**2 * p_f))
    assert threshold == pytest.approx(46.8, abs=0.05)
    sc = scan(4, n=10)
    w = pair_weights(*sc.z, S1, S2, sigma, sigma, p_d, p_f)
    np.testing.assert_allclose(w.a_i0, np.log(p_f))
    np.testing.assert_allclose(w.gain > 0, w.chi2 < threshold)
    order = np.argsort(w.chi2, axis=None)
    assert np.all(np.diff(w.a.ravel()[order]) <= 1e-12)


def test_the_printed_eq_17_pairs_below_chi2_11_8_whatever_the_angle_unit():
    """Eq. 17 as printed has no Gaussian normalising term: the pairing threshold is
    4 ln(P_D / p_f) = 11.8, the same for every sigma (the sign-corrected "paper" weight's is
    46.8 at sigma = 0.005 rad and moves with it)."""
    p_d, p_f = 0.95, 0.05
    threshold = 4 * np.log(p_d / p_f)
    assert threshold == pytest.approx(11.8, abs=0.05)
    sc = scan(4, n=10)
    for sigma in (0.005, 0.02):
        w = pair_weights(*sc.z, S1, S2, sigma, sigma, p_d, p_f, cost="printed")
        np.testing.assert_allclose(w.a_i0, np.log(p_f))
        np.testing.assert_allclose(w.gain > 0, w.chi2 < threshold)
        np.testing.assert_allclose(w.a, 2 * np.log(p_d) - 0.5 * w.chi2)


def test_pattipati_weights_use_fov_area():
    sc = scan(5, n=7)
    sigma, p_d = 0.005, 0.95
    w = pair_weights(*sc.z, S1, S2, sigma, sigma, p_d, 0.05, cost="pattipati", psi=sc.psi)
    expected = np.sum(np.log(p_d * sc.psi / (2 * np.pi * sigma**2))) - 0.5 * w.chi2
    np.testing.assert_allclose(w.gain, expected)
    np.testing.assert_allclose(w.a_i0, 0.0)
    np.testing.assert_allclose(w.a_0j, 0.0)


def test_true_pairs_have_chi_square_near_its_mean():
    # chi2 of a true pair with the LS point: 4 residuals, 3 parameters, LS not ML: ~1.3
    rng = np.random.default_rng(0)
    chis = []
    for _ in range(200):
        sc = simulate_scan(scene_targets(10, "paper", rng), 0.005, 0.005, 1.0, 0.0, rng, rng,
                           rng)
        w = pair_weights(*sc.z, S1, S2, 0.005, 0.005, 0.95, 0.05)
        t1, _ = true_partners(*sc.labels)
        chis.append(w.chi2[np.arange(len(t1)), t1])
    assert 1.1 < np.mean(chis) < 1.5


def test_near_ghosts_of_the_paper_target_set():
    # W002-6: noise-free, the wrong pairs (M5, M6) and (M6, M5) have chi2 of only 0.6 and 0.9
    z1 = los_angles(scene_targets(10, "paper", None), S1)
    z2 = los_angles(scene_targets(10, "paper", None), S2)
    w = pair_weights(z1, z2, S1, S2, 0.005, 0.005, 0.95, 0.05)
    assert w.chi2[4, 5] == pytest.approx(0.6, abs=0.1)
    assert w.chi2[5, 4] == pytest.approx(0.9, abs=0.1)
    np.testing.assert_allclose(np.diag(w.chi2), 0.0, atol=1e-9)


def test_unknown_options_raise():
    with pytest.raises(ValueError):
        solve_exact(np.zeros((2, 2)), "hungarian?")
    with pytest.raises(ValueError):
        pair_weights(np.zeros((1, 2)), np.zeros((1, 2)), S1, S2, 0.01, 0.01, 0.9, 0.1,
                     cost="nope")
