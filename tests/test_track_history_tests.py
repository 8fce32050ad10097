"""Counting test and SPRT over the track history (docs/papers/esm_radar.md, "Tests over the
track history"): the false-association rate against its binomial design value."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.stats import chi2, ncx2

from trackfuse.association.track_history_tests import (
    binomial_tail,
    counting_decision,
    counting_threshold,
    sprt_decision,
)

F, P_GATE, P_FALSE, ALPHA, BETA = 4, 0.99, 0.1, 0.01, 0.01
GAMMA = chi2.ppf(P_GATE, F)


def wrong_track_m2(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    """Squared distances of another target's track: noncentral chi-square whose
    probability of falling inside the gate is exactly P_FALSE."""
    lam = brentq(lambda x: ncx2.cdf(GAMMA, F, x) - P_FALSE, 1e-6, 500.0)
    return ncx2.rvs(F, lam, size=shape, random_state=rng)


def test_the_threshold_is_the_least_count_within_the_design_rate():
    for n in (5, 10, 20, 50):
        m = counting_threshold(n, P_FALSE, ALPHA)
        assert binomial_tail(n, P_FALSE, m) <= ALPHA < binomial_tail(n, P_FALSE, m - 1)
    assert binomial_tail(3, 0.5, 0) == pytest.approx(1.0)
    assert counting_threshold(4, 0.9, 1e-6) == 5  # no count is rare enough: never associate


def test_the_false_association_rate_is_the_binomial_design_value():
    """Simulated tracks of other targets: the rate of counts at the threshold matches the
    binomial tail (at most ALPHA), within 4 binomial standard errors."""
    rng, n, trials = np.random.default_rng(1), 20, 40_000
    m = counting_threshold(n, P_FALSE, ALPHA)
    design = binomial_tail(n, P_FALSE, m)
    chosen, _ = counting_decision(wrong_track_m2(rng, (trials, n, 1)), GAMMA, n, m)
    rate = np.mean(chosen == 0)
    assert abs(rate - design) <= 4.0 * math.sqrt(design * (1 - design) / trials)
    assert design <= ALPHA


def test_the_missed_association_rate_is_the_binomial_design_value():
    rng, n, trials = np.random.default_rng(2), 10, 40_000
    m = counting_threshold(n, 0.5, ALPHA)  # a hard design: few spare hits
    missed_design = 1.0 - binomial_tail(n, P_GATE, m)
    own = chi2.rvs(F, size=(trials, n, 1), random_state=rng)
    chosen, _ = counting_decision(own, GAMMA, n, m)
    rate = np.mean(chosen == -1)
    assert abs(rate - missed_design) <= 4.0 * math.sqrt(missed_design / trials) + 1e-4


def test_the_sequential_test_keeps_wald_s_bounds():
    rng, k, trials = np.random.default_rng(3), 200, 20_000
    wrong, _ = sprt_decision(wrong_track_m2(rng, (trials, k, 1)), GAMMA, P_GATE, P_FALSE,
                             ALPHA, BETA)
    own, _ = sprt_decision(chi2.rvs(F, size=(trials, k, 1), random_state=rng), GAMMA,
                           P_GATE, P_FALSE, ALPHA, BETA)
    assert np.mean(wrong == 0) <= ALPHA / (1 - BETA)
    assert np.mean(own == -1) <= BETA / (1 - ALPHA)


def test_several_associated_tracks_compete():
    # track 0 inside the gate 8 of 10 scans, track 2 all 10, track 1 never
    m2 = np.full((10, 3), 100.0)
    m2[:8, 0] = 1.0
    m2[:, 2] = 2.0
    chosen, counts = counting_decision(m2, GAMMA, 10, 5)
    assert chosen == 2 and counts.tolist() == [8, 0, 10]
    m2[:, 0] = 1.0  # now tied at 10: the smaller summed distance wins
    assert counting_decision(m2, GAMMA, 10, 5)[0] == 0
    assert counting_decision(np.full((10, 3), 100.0), GAMMA, 10, 5)[0] == -1
    # the SPRT takes the track accepted first
    late = np.full((30, 2), 1.0)
    late[:5, 0] = 100.0
    assert sprt_decision(late, GAMMA, P_GATE, P_FALSE, ALPHA, BETA)[0] == 1
