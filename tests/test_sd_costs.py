"""Tuple costs from S lines of sight (docs/papers/sd_assignment.md, Costs)."""

import numpy as np
import pytest
from sd_reference import subset_fit as reference_fit

from trackfuse.association.assignment import pair_weights
from trackfuse.association.passive_scene import (
    SENSORS,
    los_angles,
    scene_targets,
    simulate_scan,
)
from trackfuse.association.sd_costs import occam_term, subset_fit, tuple_costs
from trackfuse.association.triangulation import common_perpendicular_midpoint, intersect

THREE = np.vstack([SENSORS, [[15000.0, -2000.0, 1000.0]]])
SIGMA, P_D, P_F = 0.005, 0.9, 0.05


def scan(sensors: np.ndarray, seed: int = 3, n: int = 8):
    rng = [np.random.default_rng(seed + k) for k in range(4)]
    targets = scene_targets(n, "random", rng[0])
    return simulate_scan(targets, SIGMA, SIGMA, P_D, P_F, rng[1], rng[2], rng[3],
                         sensors=sensors)


def test_two_lines_meet_at_the_common_perpendicular_midpoint():
    rng = np.random.default_rng(0)
    z1, z2 = rng.uniform(0.1, 1.2, size=(50, 2)), rng.uniform(0.1, 1.2, size=(50, 2))
    both = intersect([z1, z2], SENSORS)
    assert np.allclose(both, common_perpendicular_midpoint(z1, z2, *SENSORS), atol=1e-6)


def test_noise_free_lines_of_sight_meet_at_the_target():
    targets = scene_targets(10, "paper", np.random.default_rng(0))
    z = [los_angles(targets, s) for s in THREE]
    assert np.allclose(intersect(z, THREE), targets, atol=1e-6)


@pytest.mark.parametrize("cost", ["paper", "pattipati"])
def test_two_sensor_costs_are_minus_the_pair_gains(cost):
    s = scan(SENSORS)
    weights = pair_weights(*s.z, *s.sensors, SIGMA, SIGMA, P_D, P_F, cost=cost, psi=s.psi)
    c = tuple_costs(s.z, s.sensors, SIGMA, SIGMA, P_D, P_F, cost=cost, psi=s.psi)
    assert c.shape == (len(s.z[0]) + 1, len(s.z[1]) + 1)
    assert np.allclose(c[1:, 1:], -weights.gain, rtol=1e-9, atol=1e-6)
    assert not c[0].any() and not c[:, 0].any()


def test_a_third_sensor_adds_the_missed_detection_term_to_pairs():
    three = scan(THREE)
    two = scan(SENSORS)
    assert all(np.array_equal(a, b) for a, b in zip(three.z[:2], two.z, strict=False))
    c3 = tuple_costs(three.z, three.sensors, SIGMA, SIGMA, P_D, P_F)
    c2 = tuple_costs(two.z, two.sensors, SIGMA, SIGMA, P_D, P_F)
    assert np.allclose(c3[:, :, 0], c2 - np.log(1.0 - P_D) * (c2 != 0), rtol=1e-12)
    singles = (np.indices(c3.shape) > 0).sum(axis=0) <= 1
    assert not c3[singles].any()


def test_the_true_triple_is_the_cheapest_tuple_of_its_measurements():
    s = scan(THREE, n=6)
    c = tuple_costs(s.z, s.sensors, SIGMA, SIGMA, P_D, P_F)
    where = [{int(t): i + 1 for i, t in enumerate(lab) if t >= 0} for lab in s.labels]
    seen = [t for t in range(6) if all(t in w for w in where)]
    assert seen
    for t in seen:
        i, j, k = (w[t] for w in where)
        assert c[i, j, k] < 0.0
        assert c[i, j, k] <= c[i, j, :].min() and c[i, j, k] <= c[:, j, k].min()


def test_parallel_lines_of_sight_cost_infinity():
    sensors = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    z = [np.array([[0.3, 0.2]]), np.array([[0.3, 0.2]])]
    c = tuple_costs(z, sensors, SIGMA, SIGMA, P_D, P_F)
    assert c[1, 1] == np.inf


def test_an_unknown_cost_form_is_refused():
    with pytest.raises(ValueError, match="unknown cost"):
        tuple_costs([np.zeros((1, 2))] * 2, SENSORS, SIGMA, SIGMA, P_D, P_F, cost="other")


@pytest.mark.parametrize("sensors", [2, 3, 4])
def test_the_compiled_fit_is_pinned_to_the_numpy_reference(sensors):
    every = np.vstack([THREE, [[20000.0, 20000.0, 0.0]]])[:sensors]
    s = scan(every, n=7)
    chi2, logdet = subset_fit(list(s.z), every, SIGMA, 2 * SIGMA)
    chi2_ref, logdet_ref = reference_fit(list(s.z), every, SIGMA, 2 * SIGMA)
    assert chi2.shape == logdet.shape == tuple(len(z) for z in s.z)
    assert np.allclose(chi2, chi2_ref, rtol=1e-9, atol=1e-9)
    assert np.allclose(logdet, logdet_ref, rtol=1e-9, atol=1e-9)


def test_the_marginal_cost_charges_each_tuple_its_occam_term():
    s = scan(THREE, n=5)
    volume = 3.6e12
    fitted = tuple_costs(s.z, s.sensors, SIGMA, SIGMA, P_D, P_F)
    marginal = tuple_costs(s.z, s.sensors, SIGMA, SIGMA, P_D, P_F, volume=volume)
    _, logdet = reference_fit(list(s.z), s.sensors, SIGMA, SIGMA)
    assert np.allclose(marginal[1:, 1:, 1:], fitted[1:, 1:, 1:] - occam_term(logdet, volume),
                       rtol=1e-9)
    singles = (np.indices(fitted.shape) > 0).sum(axis=0) <= 1
    assert not marginal[singles].any()
    # two lines of sight of a target 11-15 km away, 0.01 rad, a 3,650 km^3 box: about -12 nats
    target = np.array([[10e3, 10e3, 5e3]])
    z = [los_angles(target, p) for p in SENSORS]
    _, logdet = subset_fit(z, SENSORS, 0.01, 0.01)
    assert -13.0 < float(occam_term(logdet, 3.65e12)[0, 0]) < -10.0


def test_parallel_lines_of_sight_cost_infinity_in_the_marginal_form_too():
    sensors = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    z = [np.array([[0.3, 0.2]]), np.array([[0.3, 0.2]])]
    assert tuple_costs(z, sensors, SIGMA, SIGMA, P_D, P_F, volume=1e12)[1, 1] == np.inf
