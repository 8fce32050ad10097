"""S-D assignment by Lagrangian relaxation (docs/papers/sd_assignment.md): brute force on
small problems, the exact 2-D solver at S = 2, the plain reference pinned to the kernel."""

import numpy as np
import pytest
from sd_reference import brute_force, lagrangian

from trackfuse.association.assignment import BRUTE_FORCE, solve_exact
from trackfuse.association.sd_assignment import (
    checked_costs,
    reduce_tail,
    solve_sd,
    solve_sd_exact,
)


def random_costs(rng: np.random.Generator, shape: tuple[int, ...], scale: float = 3.0
                 ) -> np.ndarray:
    """Gaussian tuple costs (mean -1 nat), 0 for every tuple of at most one real index."""
    cost = rng.normal(-1.0, scale, size=shape)
    cost[(np.indices(shape) > 0).sum(axis=0) <= 1] = 0.0
    return cost


def assert_feasible(tuples: np.ndarray, shape: tuple[int, ...]) -> None:
    """Every real index of every sensor in exactly one tuple, no all-dummy tuple."""
    assert (tuples > 0).any(axis=1).all()
    for s, n in enumerate(shape):
        assert np.array_equal(np.bincount(tuples[:, s], minlength=n)[1:], np.ones(n - 1))


def small_problems(seed: int, count: int, sensors: int = 3):
    rng = np.random.default_rng(seed)
    for _ in range(count):
        shape = tuple(int(n) + 1 for n in rng.integers(2, 5, size=sensors))  # 2-4 each
        yield random_costs(rng, shape)


@pytest.mark.parametrize("sensors,count", [(3, 40), (4, 6)])
def test_bounds_hold_against_brute_force(sensors, count):
    """dual <= optimum <= primal, gap >= 0 and equal to its definition, on every problem
    whose feasible assignments can all be enumerated."""
    reached = 0
    for cost in small_problems(sensors, count, sensors):
        optimum, _ = brute_force(cost)
        result = solve_sd(cost)
        assert_feasible(result.tuples, cost.shape)
        assert np.isclose(np.minimum(cost, 0)[tuple(result.tuples.T)].sum(), result.primal)
        assert result.dual <= optimum + 1e-9 <= result.primal + 2e-9
        assert result.gap >= 0.0
        assert result.gap == pytest.approx((result.primal - result.dual)
                                           / max(abs(result.primal), 1.0))
        assert result.gap <= 0.01 or result.iterations == 100
        reached += abs(result.primal - optimum) <= 1e-9 * max(1.0, abs(optimum))
    assert reached >= count // 2  # the relaxation is not a random guess


def test_every_declared_tuple_has_negative_cost():
    for cost in small_problems(5, 20):
        result = solve_sd(cost)
        declared = result.declared
        assert (np.minimum(cost, 0)[tuple(declared.T)] < 0.0).all()
        assert ((result.tuples > 0).sum(axis=1) >= 2).sum() == len(declared)


def test_the_exact_solver_is_the_brute_force_optimum():
    for cost in small_problems(2, 40):
        optimum, _ = brute_force(cost)
        exact = solve_sd_exact(cost)
        assert_feasible(exact.tuples, cost.shape)
        assert exact.primal == pytest.approx(optimum, abs=1e-9)
        assert exact.gap == 0.0


def test_two_sensors_equal_the_exact_2d_solver():
    rng = np.random.default_rng(11)
    for _ in range(30):
        m1, m2 = rng.integers(0, 7, size=2)
        gain = rng.normal(0.0, 4.0, size=(m1, m2))
        cost = np.zeros((m1 + 1, m2 + 1))
        cost[1:, 1:] = -gain
        result = solve_sd(cost)
        for method in ("lsa_clip", BRUTE_FORCE):
            exact = solve_exact(gain, method)
            assert -result.primal == pytest.approx(exact.objective, abs=1e-9)
        pairs = {(i - 1, j - 1) for i, j in result.declared}
        assert pairs == {(i, j) for i, j in enumerate(solve_exact(gain).partner1) if j >= 0}
        assert result.gap == 0.0 and result.iterations == 1


@pytest.mark.parametrize("sensors,seed", [(3, 21), (4, 22)])
def test_the_compiled_solver_is_pinned_to_the_plain_reference(sensors, seed):
    rng = np.random.default_rng(seed)
    for _ in range(25):
        shape = tuple(int(n) + 1 for n in rng.integers(0, 6, size=sensors))
        cost = random_costs(rng, shape)
        result = solve_sd(cost, max_gap=1e-6, max_iter=40)
        primal, dual, iterations, declared = lagrangian(cost, max_gap=1e-6, max_iter=40)
        assert result.iterations == iterations
        assert result.primal == pytest.approx(primal, rel=1e-9, abs=1e-9)
        assert result.dual == pytest.approx(dual, rel=1e-9, abs=1e-9)
        mine = sorted(map(tuple, result.declared.tolist()))
        assert mine == [tuple(t) for t in declared.tolist()]


def test_the_tail_minimum_is_numpys():
    rng = np.random.default_rng(4)
    cube, utail = rng.normal(size=(4, 5, 7)), rng.normal(size=7)
    low, arg = reduce_tail(cube, utail)
    assert np.array_equal(low, (cube - utail).min(axis=2))
    assert np.array_equal(arg, (cube - utail).argmin(axis=2))


def test_a_feasible_relaxed_solution_stops_at_zero_gap():
    """Separable costs: every target's tuple is far cheaper than any mix, so the first
    relaxed solution is feasible (zero subgradient) and optimal."""
    cost = np.zeros((4, 4, 4))
    for i in range(1, 4):
        cost[i, i, i] = -50.0
    result = solve_sd(cost)
    assert result.iterations == 1 and result.gap == 0.0 and result.primal == -150.0
    assert sorted(map(tuple, result.declared.tolist())) == [(1, 1, 1), (2, 2, 2), (3, 3, 3)]


def test_nonnegative_tuples_are_split_into_singletons():
    cost = np.zeros((2, 2, 2))
    cost[1, 1, 1] = 3.0  # worse than three false alarms
    result = solve_sd(cost)
    assert result.primal == 0.0 and len(result.declared) == 0
    assert_feasible(result.tuples, cost.shape)


def test_missing_measurements_and_infinite_costs_are_handled():
    cost = np.zeros((3, 1, 3))  # the second sensor saw nothing
    cost[1, 0, 2], cost[2, 0, 1], cost[1, 0, 1] = -4.0, -1.0, np.inf
    result = solve_sd(cost)
    assert result.primal == -5.0
    assert sorted(map(tuple, result.declared.tolist())) == [(1, 0, 2), (2, 0, 1)]


@pytest.mark.parametrize("bad", ["singleton", "nan", "one_axis"])
def test_malformed_cost_tensors_are_refused(bad):
    cost = np.zeros((2, 3, 2))
    if bad == "singleton":
        cost[0, 2, 0] = -1.0
    elif bad == "nan":
        cost[1, 1, 1] = np.nan
    else:
        cost = np.zeros(3)
    with pytest.raises(ValueError):
        checked_costs(cost)
