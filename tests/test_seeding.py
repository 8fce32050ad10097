"""Seeding: which sweep points share their point stream (draw points)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from trackfuse.config import build, load
from trackfuse.runner import Runner
from trackfuse.seeding import draw_points
from trackfuse.sweep import expand

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
SHIPPED = sorted(CONFIGS.rglob("*.yaml"))
#: The Stone Soup configs load only with the ``stonesoup`` extra (CI tests them apart).
NEEDS_EXTRA = {"twin_sensor_stonesoup", "twin_sensor_stonesoup_jacobian"}
HAS_STONESOUP = importlib.util.find_spec("stonesoup") is not None
LOADABLE = [p for p in SHIPPED if HAS_STONESOUP or p.stem not in NEEDS_EXTRA]


def test_points_with_equal_drawing_values_share_the_first_ones_index():
    points = expand({"clutter": [0, 5], "p_m": [0.0, 0.1, 0.2]})  # p_m varies fastest
    assert draw_points(points, {"clutter"}) == [0, 0, 0, 3, 3, 3]
    assert draw_points(points, {"p_m"}) == [0, 1, 2, 0, 1, 2]
    assert draw_points(points, {"clutter", "p_m"}) == list(range(6))
    assert draw_points(points, set()) == [0] * 6


def test_zipped_points_compare_every_drawing_value_and_lists_by_their_items():
    points = expand({"q": [0, 9, 0, 9], "filter": [1, 2, 3, 4], "clutter": [0, 0, 4, 0]},
                    "zip")
    assert draw_points(points, {"q", "clutter"}) == [0, 1, 2, 1]
    lists = expand({"algorithms": [["a", "b"], ["a"], ["a", "b"]], "x": [1, 1, 2]}, "zip")
    assert draw_points(lists, {"algorithms"}) == [0, 1, 0]
    assert draw_points(lists, {"algorithms", "x"}) == [0, 1, 2]


def test_a_sweep_without_axes_is_its_own_draw_point():
    assert draw_points(expand({}), {"clutter"}) == [0]


def _mapped(path: Path) -> tuple[list, list[int]]:
    """The sweep points of a shipped config and their draw points."""
    config = load(path)
    points = expand(config.sweep, config.sweep_mode)
    return points, draw_points(points, config.experiment.drawing)


@pytest.mark.parametrize("path", LOADABLE, ids=lambda p: p.stem)
def test_a_draw_point_is_the_first_point_with_the_same_simulated_values(path):
    config = load(path)
    drawing = [k for k in config.sweep if config.experiment.schema[k].draws]
    points, mapped = _mapped(path)
    for point, draw in zip(points, mapped, strict=True):
        same = [q.index for q in points
                if all(q.values[k] == point.values[k] for k in drawing)]
        assert draw == same[0]


def test_only_the_shipped_configs_with_a_non_drawing_axis_share_clutter_across_points():
    """Every other shipped config draws exactly the clutter it drew before draw points
    existed (each point its own stream), so its numbers are unchanged; these are the ones
    whose sweep adds a parameter that changes only what is computed, and the angle-noise
    study, whose noise levels share their false alarms."""
    sharing = set()
    for path in LOADABLE:
        points, mapped = _mapped(path)
        if mapped != [p.index for p in points]:
            sharing.add(path.stem)
    expected = {"passive_mutation", "passive_mutation_ci", "twin_sensor_range",
                "twin_sensor_stonesoup_jacobian", "esm_radar_baseline_spread",
                "esm_radar_weave", "passive_noise", "passive_noise_ci", "passive_best_pm",
                "passive_3sensor", "passive_3sensor_ci"}
    assert sharing == {name for name in expected if HAS_STONESOUP or name not in NEEDS_EXTRA}


def test_the_mutation_study_shares_clutter_across_p_m_and_not_across_targets():
    assert _mapped(CONFIGS / "passive_mutation.yaml")[1] == [0, 1, 2] * 4  # p_m x targets.n
    assert _mapped(CONFIGS / "twin_sensor_range.yaml")[1] == [0] * 9  # cue x filter q
    assert _mapped(CONFIGS / "passive_noise.yaml")[1] == [0, 1, 2] * 5  # sigma x targets.n


def test_numpy_s_global_generator_gives_each_trial_the_same_numbers_on_every_executor(
        tmp_path):
    """A plugin drawing from ``np.random`` directly (the docs forbid it) got numbers that
    depended on the worker and the batches it had run before: the runner now seeds the
    global generator per trial, and gives the caller's process its own sequence back."""
    config = build({"experiment": "toy_experiments:GLOBAL_NUMPY", "trials": 12, "seed": 4},
                   "global.yaml")
    np.random.seed(99)
    expected_next = np.random.random()
    np.random.seed(99)
    runs = [Runner(config, tmp_path / kind, executor=kind, workers=2, plots=False,
                   progress=False).run() for kind in ("serial", "process")]
    assert np.random.random() == expected_next
    texts = [(run.folder / "trials.csv").read_text() for run in runs]
    assert texts[0] == texts[1]
    values = [line.split(",")[-1] for line in texts[0].splitlines()[1:]]
    assert len(set(values)) == 12
