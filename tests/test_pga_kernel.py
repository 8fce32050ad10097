"""The compiled PGA loop is bit for bit the Python reference (docs/papers/passive_assoc.md)."""

import itertools

import numpy as np
import pga_reference as reference
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import trackfuse.association.pga as pga_setup
from trackfuse.association.assignment import PairWeights, pair_weights
from trackfuse.association.passive_scene import SENSORS, scene_targets, simulate_scan
from trackfuse.association.pga_search import pga as pga_compiled
from trackfuse.experiments.passive_assoc.model import VARIANTS


def random_weights(rng, m1, m2, integer=False):
    """Random weights; ``integer`` gives many equal gains (ties in the ranks, dJ = 0)."""
    draw = (lambda *s: rng.integers(-3, 3, s).astype(float)) if integer else \
        (lambda *s: rng.normal(0, 5, s))
    return PairWeights(a=draw(m1, m2), a_i0=draw(m1) - 2, a_0j=draw(m2) - 2,
                       chi2=np.zeros((m1, m2)))


def assert_identical(weights, seed, **options):
    """Run both implementations from the same generator state; every field of the result
    but the wall times must be equal exactly (``array_equal``, no tolerance)."""
    want = reference.pga(weights, np.random.default_rng(seed), **options)
    got = pga_compiled(weights, np.random.default_rng(seed), **options)
    np.testing.assert_array_equal(got.checkpoints, want.checkpoints)
    np.testing.assert_array_equal(got.partner1, want.partner1)
    assert got.objective.tobytes() == want.objective.tobytes()  # bit for bit, NaN-proof
    assert got.elapsed_s.shape == want.elapsed_s.shape
    assert np.all(np.diff(got.elapsed_s) >= 0)
    return want


#: Every combination of the options of pga() (evict only acts with repair_moves).
OPTIONS = [dict(roulette=r, second=s, repair_moves=rep, staged=st_, evict=ev, accept=acc,
                init=init)
           for r, s, rep, st_, ev, acc, init in itertools.product(
               ("worse", "better"), ("roulette", "uniform"), (False, True), (False, True),
               (False, True), ("monotone", "anneal"), ("random_B", "standard"))
           if rep or not ev]
SHAPES = [(1, 1), (1, 2), (2, 1), (2, 2), (3, 5), (5, 3), (6, 6), (7, 12), (12, 7), (12, 12),
          (0, 4), (4, 0), (9, 11)]


@pytest.mark.parametrize("options", OPTIONS, ids=lambda o: "-".join(map(str, o.values())))
def test_every_option_combination_matches_the_reference(options):
    rng = np.random.default_rng(len(str(options)))
    moved = 0
    for m1, m2 in SHAPES:
        weights = random_weights(rng, m1, m2, integer=bool(rng.integers(2)))
        res = assert_identical(weights, int(rng.integers(2**32)), ops=400,
                               checkpoints=[0, 1, 10, 50, 200], p_m=float(rng.uniform(0, 1)),
                               t0=float(rng.uniform(0.1, 5)), t1=0.01, **options)
        moved += not np.array_equal(res.partner1[0], res.partner1[-1])
    assert moved >= 3  # the runs do search: equal results are not equal initial solutions


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m1=st.integers(1, 12), m2=st.integers(1, 12),
       variant=st.sampled_from(list(VARIANTS)), p_m=st.sampled_from([0.0, 0.01, 0.05, 0.2, 1.0]),
       integer=st.booleans())
def test_random_problems_of_the_experiment_variants_match(seed, m1, m2, variant, p_m, integer):
    rng = np.random.default_rng(seed)
    assert_identical(random_weights(rng, m1, m2, integer), seed, ops=300, p_m=p_m, t0=2.0,
                     checkpoints=[0, 10, 20, 50, 100, 200], **VARIANTS[variant])


@pytest.mark.parametrize("m1, m2", [(30, 40), (50, 50), (60, 45)])
@pytest.mark.parametrize("variant", ["pga_paper", "pga_evict", "pga_anneal"])
def test_larger_problems_across_blocks_of_draws_match(monkeypatch, m1, m2, variant):
    monkeypatch.setattr(pga_setup, "_BLOCK", 97)  # checkpoints inside and across blocks
    weights = random_weights(np.random.default_rng(m1 * m2), m1, m2)
    res = assert_identical(weights, m1 + m2, ops=3000, checkpoints=[0, 96, 97, 500, 1000],
                           t0=2.0, **VARIANTS[variant])
    np.testing.assert_array_equal(res.checkpoints, [0, 96, 97, 500, 1000, 3000])


@pytest.mark.parametrize("variant", list(VARIANTS))
@pytest.mark.parametrize("n, sigma", [(5, 0.005), (10, 0.005), (10, 0.0707), (10, 0.0)])
def test_paper_scenes_match(variant, n, sigma):
    for seed in range(3):
        rng = np.random.default_rng(seed)
        scan = simulate_scan(scene_targets(n, "paper", rng), sigma, sigma, 0.95, 0.05, rng,
                             rng, rng)
        weights = pair_weights(*scan.z, *SENSORS, 0.005, 0.005, 0.95, 0.05)
        assert_identical(weights, 100 + seed, ops=1000, t0=2.0, **VARIANTS[variant])


@pytest.mark.parametrize("ops, checkpoints", [(0, [0, 10]), (5, []), (50, [50, 50, 7]),
                                              (20, [0, 1, 2, 3, 19, 20, 1000])])
def test_budgets_and_checkpoint_lists_match(ops, checkpoints):
    weights = random_weights(np.random.default_rng(ops), 4, 6)
    assert_identical(weights, 3, ops=ops, checkpoints=checkpoints, repair_moves=True)


@pytest.mark.parametrize("change", [dict(t0=2.5), dict(p_m=0.25), dict(second="uniform"),
                                    dict(staged=True), dict(roulette="better")])
def test_a_changed_option_changes_the_result(change):
    # the comparison above is sensitive: one option off gives other solutions
    differ = 0
    for seed in range(5):
        weights = random_weights(np.random.default_rng(seed), 8, 10)
        options = dict(ops=300, accept="anneal", t0=2.0, repair_moves=True)
        base = reference.pga(weights, np.random.default_rng(seed), **options)
        other = pga_compiled(weights, np.random.default_rng(seed), **{**options, **change})
        differ += not np.array_equal(other.partner1, base.partner1)
    assert differ


@pytest.mark.parametrize("bad", [dict(roulette="best"), dict(second="random"),
                                 dict(accept="greedy"), dict(init="zero")])
def test_unknown_options_are_refused_like_the_reference(bad):
    weights = random_weights(np.random.default_rng(0), 3, 4)
    with pytest.raises(ValueError):
        reference.pga(weights, np.random.default_rng(0), **bad)
    with pytest.raises(ValueError):
        pga_compiled(weights, np.random.default_rng(0), **bad)
