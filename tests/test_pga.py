"""Partheno-genetic algorithm of paper 002 (docs/papers/passive_assoc.md)."""

import hashlib

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pga_reference import exchange, is_feasible, repair, swap_columns, unpair

from trackfuse.association.assignment import (
    PairWeights,
    objective,
    pair_weights,
    solve_exact,
)
from trackfuse.association.passive_scene import (
    SENSORS,
    scene_targets,
    simulate_scan,
    true_partners,
)
from trackfuse.association.pga import column_ranks
from trackfuse.association.pga_search import pga


def random_weights(rng, m1, m2):
    a = rng.normal(0, 5, (m1, m2))
    return PairWeights(a=a, a_i0=rng.normal(-3, 1, m1), a_0j=rng.normal(-3, 1, m2),
                       chi2=np.zeros((m1, m2)))


def table(gain):
    return [[0.0] * gain.shape[1]] + gain.tolist()


PINNED_DIGEST = "2091a76df04a7a53cf78a9cf172a59b7bfc523bcb4727813b5375c3fb6a24ea7"


def J(col_row, w):
    return sum(w[r][j] for j, r in enumerate(col_row))


unit = st.floats(0, 1, exclude_max=True)


@settings(max_examples=120, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m1=st.integers(1, 6), extra=st.integers(0, 4),
       moves=st.lists(st.tuples(st.sampled_from("xmre"), unit, unit),
                      max_size=40))
def test_operators_keep_feasibility_and_report_exact_deltas(seed, m1, extra, moves):
    rng = np.random.default_rng(seed)
    m2 = m1 + extra
    w = table(rng.normal(size=(m1, m2)))
    x = [0] * m2
    for r, j in enumerate(rng.permutation(m2)[:m1].tolist(), start=1):
        x[j] = r
    for kind, u, v in moves:
        before, pairs = J(x, w), sum(1 for r in x if r)
        if kind == "x" and m2 >= 2:
            j1 = int(u * m2)
            j2 = (j1 + 1 + int(v * (m2 - 1))) % m2
            d = swap_columns(x, w, j1, j2)
            assert sum(1 for r in x if r) == pairs  # crossover keeps the number of pairs
        elif kind == "m" and pairs:
            paired = [j for j in range(m2) if x[j]]
            d = unpair(x, w, paired[int(u * len(paired))])
            assert sum(1 for r in x if r) == pairs - 1
        elif kind == "e" and pairs < m1:
            free = sorted(set(range(1, m1 + 1)) - set(x))
            c = int(v * m2)
            d = exchange(x, w, free[int(u * len(free))], c)
            assert sum(1 for r in x if r) in (pairs, pairs + 1)
        elif kind == "r" and pairs < m1:
            free = sorted(set(range(1, m1 + 1)) - set(x))
            empty = [j for j in range(m2) if x[j] == 0]
            d = repair(x, w, free[int(u * len(free))], empty[int(v * len(empty))])
            assert sum(1 for r in x if r) == pairs + 1
        else:
            continue
        assert is_feasible(x, m1)
        assert J(x, w) == pytest.approx(before + d, abs=1e-9)


def test_repair_refuses_an_infeasible_move():
    w = table(np.zeros((2, 3)))
    with pytest.raises(ValueError):
        repair([1, 0, 2], w, 1, 1)  # row 1 is already paired
    with pytest.raises(ValueError):
        repair([1, 0, 0], w, 2, 0)  # column 0 is occupied
    with pytest.raises(ValueError):
        exchange([1, 0, 2], w, 2, 1)  # row 2 is already paired


def test_column_ranks_are_descending_ranks_with_the_dummy_row():
    a = np.array([[3.0, -1.0], [1.0, 5.0]])
    a_0j = np.array([2.0, 0.0])
    # column 0: [2, 3, 1] -> ranks [2, 1, 3]; column 1: [0, -1, 5] -> [2, 3, 1]
    np.testing.assert_array_equal(column_ranks(a, a_0j), [[2, 2], [1, 3], [3, 1]])


VARIANTS = [dict(repair_moves=False, staged=False), dict(repair_moves=True, staged=True),
            dict(repair_moves=True, staged=True, accept="anneal", t0=2.0),
            dict(repair_moves=True, staged=True, evict=True),
            dict(repair_moves=False, staged=True, roulette="better", second="uniform",
                 init="standard")]


@pytest.mark.parametrize("options", VARIANTS)
@pytest.mark.parametrize("shape", [(4, 7), (7, 4), (6, 6), (1, 3), (0, 3), (3, 1)])
def test_pga_solutions_are_feasible_and_bounded_by_the_optimum(options, shape):
    rng = np.random.default_rng(sum(shape))
    w = random_weights(rng, *shape)
    best = solve_exact(w.gain).objective
    res = pga(w, rng, ops=300, checkpoints=[0, 10, 100, 300, 5000], **options)
    np.testing.assert_array_equal(res.checkpoints, [0, 10, 100, 300])
    assert res.partner1.shape == (4, shape[0])
    for k in range(4):
        p1 = res.partner1[k]
        real = p1[p1 >= 0]
        assert len(set(real.tolist())) == len(real) and np.all(real < shape[1])
        assert res.objective[k] == pytest.approx(objective(w.gain, p1))
        assert res.objective[k] <= best + 1e-9
    assert np.all(np.diff(res.objective) >= -1e-12)  # best-so-far never decreases
    assert np.all(np.diff(res.elapsed_s) >= 0)


def test_pga_is_a_pure_function_of_its_generator():
    w = random_weights(np.random.default_rng(1), 6, 8)
    a = pga(w, np.random.default_rng(5), ops=200)
    b = pga(w, np.random.default_rng(5), ops=200)
    np.testing.assert_array_equal(a.partner1, b.partner1)
    np.testing.assert_array_equal(a.objective, b.objective)


def noise_free_problem(n, seed):
    rng = np.random.default_rng(seed)
    sc = simulate_scan(scene_targets(n, "paper", rng), 0.0, 0.0, 1.0, 0.0, rng, rng, rng)
    w = pair_weights(*sc.z, *SENSORS, 0.005, 0.005, 0.95, 0.05)
    return w, true_partners(*sc.labels)[0]


@pytest.mark.parametrize("evict", [False, True])
@pytest.mark.parametrize("n", [5, 7, 10])
def test_improved_pga_returns_the_truth_without_noise_and_false_alarms(n, evict):
    for seed in range(5):
        w, truth = noise_free_problem(n, seed)
        res = pga(w, np.random.default_rng(100 + seed), ops=1000, repair_moves=True,
                  staged=True, evict=evict)
        np.testing.assert_array_equal(res.partner1[-1], truth)


def test_paper_like_pga_stalls_below_the_optimum():
    # W002-2: with monotone acceptance and no re-pair move an unpaired row is never paired
    # again, so the paper-like PGA fails on noise-free 10-target scenes the improved one
    # always solves (measured: 1 of these 20 solved after 1000 operations).
    solved = 0
    for seed in range(20):
        w, truth = noise_free_problem(10, seed)
        res = pga(w, np.random.default_rng(200 + seed), ops=1000)
        solved += int(np.array_equal(res.partner1[-1], truth))
    assert solved <= 5


def test_paper_like_pga_never_increases_the_number_of_pairs():
    w, _ = noise_free_problem(10, 0)
    res = pga(w, np.random.default_rng(0), ops=1000, checkpoints=range(0, 1001, 50))
    pairs = np.sum(res.partner1 >= 0, axis=1)
    assert pairs[0] == 10 and np.all(np.diff(pairs) <= 0)


def test_uniforms_drawn_in_blocks_give_the_same_run(monkeypatch):
    import trackfuse.association.pga as module

    w = random_weights(np.random.default_rng(2), 5, 7)
    options = dict(ops=700, checkpoints=[0, 350, 700], repair_moves=True, staged=True,
                   evict=True, accept="anneal")
    whole = pga(w, np.random.default_rng(9), **options)
    monkeypatch.setattr(module, "_BLOCK", 64)
    blocks = pga(w, np.random.default_rng(9), **options)
    np.testing.assert_array_equal(whole.partner1, blocks.partner1)
    np.testing.assert_array_equal(whole.objective, blocks.objective)


@pytest.mark.parametrize("ops, checkpoints, expected", [
    (5000, [0, 10, 100, 1000], [0, 10, 100, 1000, 5000]),  # the budget beyond the list
    (300, [0, 10, 100, 1000], [0, 10, 100, 300]),           # counts above ops dropped
    (50, [], [50]),
    (0, [0, 10], [0]),
])
def test_the_budget_is_always_a_checkpoint(ops, checkpoints, expected):
    w = random_weights(np.random.default_rng(3), 5, 6)
    res = pga(w, np.random.default_rng(4), ops=ops, checkpoints=checkpoints)
    np.testing.assert_array_equal(res.checkpoints, expected)


def test_the_budget_checkpoint_scores_the_whole_run():
    # a 5000-operation run scored at 5000 equals the same run with 5000 listed explicitly,
    # and it can differ from its own 1000-operation checkpoint (no silent truncation)
    w, _ = noise_free_problem(10, 3)
    implicit = pga(w, np.random.default_rng(8), ops=5000, checkpoints=[1000],
                   repair_moves=True, staged=True, evict=True)
    explicit = pga(w, np.random.default_rng(8), ops=5000, checkpoints=[1000, 5000],
                   repair_moves=True, staged=True, evict=True)
    np.testing.assert_array_equal(implicit.partner1, explicit.partner1)
    np.testing.assert_array_equal(implicit.objective, explicit.objective)
    short = pga(w, np.random.default_rng(8), ops=1000, checkpoints=[1000],
                repair_moves=True, staged=True, evict=True)
    np.testing.assert_array_equal(implicit.partner1[0], short.partner1[0])
    assert implicit.objective[1] >= implicit.objective[0]


def test_random_stream_use_is_pinned():
    """The PGA's use of its stream is pinned: a digest of the solutions and objectives of
    every variant, both orientations, recorded from the implementation before the setup /
    operation / collection split (any change to the order or meaning of the draws of
    :class:`Draws` changes it, and with it every published trials.csv)."""
    rng = np.random.default_rng(2)
    w = random_weights(rng, 6, 9)
    flipped = PairWeights(a=w.a.T, a_i0=w.a_0j, a_0j=w.a_i0, chi2=np.zeros((9, 6)))
    digest = hashlib.sha256()
    for options in VARIANTS:
        for weights in (w, flipped):
            res = pga(weights, np.random.default_rng(11), ops=500,
                      checkpoints=[0, 20, 100, 500], **options)
            digest.update(res.partner1.astype(np.int64).tobytes())
            digest.update(np.round(res.objective, 9).tobytes())
    assert digest.hexdigest() == PINNED_DIGEST
