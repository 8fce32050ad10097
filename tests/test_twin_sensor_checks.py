"""A twin_sensor config whose geometry has no bearing is refused before any trial runs."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import trackfuse

from trackfuse.config import ConfigError, build
from trackfuse.experiments.twin_sensor.checks import GEOMETRY_KEYS
from trackfuse.experiments.twin_sensor.model import (
    PARAMS,
    build_scenario,
    placements,
    truth_trajectory,
)

PLATFORM_START = [153209.0, 0.0, 2000.0]
ORBIT = Path(__file__).resolve().parents[1] / "configs" / "twin_sensor_orbit.yaml"


def _raw(params: dict, sweep: dict | None = None, mode: str = "grid") -> dict:
    return {"experiment": "twin_sensor", "params": params, "sweep": sweep or {},
            "sweep_mode": mode}


def test_a_target_on_the_orbit_centre_line_is_a_config_error():
    raw = _raw({"target.position": [153209.0, 0.0, 9000.0]})
    with pytest.raises(ConfigError, match=r"cfg\.yaml: params\.target\.position: the orbit "
                                          r"starts 0 m .*allowed: platform\.start at least 1 m"):
        build(raw, "cfg.yaml")


def test_a_target_on_the_platform_in_straight_flight_is_a_config_error():
    raw = _raw({"platform.motion": "straight", "target.position": PLATFORM_START})
    with pytest.raises(ConfigError, match=r"the target is 0 m from sensor 1 at scan 0"):
        build(raw, "cfg.yaml")


def test_a_platform_flying_through_the_target_is_caught_at_that_scan():
    # 500 m/s along +y from the start, level: the platform reaches the target at scan 10.
    raw = _raw({"platform.motion": "straight", "platform.climb": 0.0,
                "target.position": [153209.0, 5000.0, 2000.0]})
    with pytest.raises(ConfigError, match=r"0 m from sensor 1 at scan 10"):
        build(raw, "cfg.yaml")
    raw["params"]["target.position"] = [153209.0, 5000.0, 2002.0]
    build(raw, "cfg.yaml")


def test_the_second_sensor_is_checked_too():
    # Sensor 2 sits 1000 m from sensor 1 along the initial line of sight: on the target.
    raw = _raw({"platform.motion": "straight", "platform.speed": 0.0, "platform.climb": 0.0,
                "sensors.baseline": 1000.0, "sensors.baseline_angle": 0.0,
                "target.position": [153209.0, 1000.0, 2000.0]})
    with pytest.raises(ConfigError, match=r"from sensor 2 at scan 0"):
        build(raw, "cfg.yaml")
    raw["params"]["sensors.count"] = 1
    build(raw, "cfg.yaml")


@pytest.mark.parametrize("mode", ["grid", "zip"])
def test_a_degenerate_sweep_point_names_the_swept_key_and_the_point(mode):
    sweep = {"platform.start": [[0.0, 0.0, 2000.0], [0.0, 128558.0, 1000.0]],
             "clutter.mean": [1.0, 2.0]}
    with pytest.raises(ConfigError, match=r"sweep\.platform\.start: the orbit starts 0 m .*"
                                          r"at the sweep point platform\.start=\[0\.0, "
                                          r"128558\.0, 1000\.0\]"):
        build(_raw({}, sweep, mode), "cfg.yaml")


def test_the_shipped_orbit_geometry_passes():
    assert build(_raw({}), "cfg.yaml").params["target.position"] == [0.0, 128558.0, 4000.0]


def test_the_error_names_the_key_the_config_changed_not_any_swept_one():
    raw = _raw({"target.position": [153209.0, 0.0, 9000.0]},
               {"sensors.baseline": [0.0, 500.0]})
    with pytest.raises(ConfigError, match=r"cfg\.yaml: params\.target\.position: the orbit"):
        build(raw, "cfg.yaml")
    raw = _raw({"platform.start": [0.0, 128558.0, 1000.0]})
    with pytest.raises(ConfigError, match=r"cfg\.yaml: params\.platform\.start: the orbit"):
        build(raw, "cfg.yaml")


def test_every_key_that_places_target_platform_or_sensors_is_checked():
    """The check sweeps over exactly the keys that place things: those ``placements`` reads
    and the target's velocity. A new geometry key that nobody listed fails here."""
    read: set[str] = set()

    class Recording(dict):
        def __getitem__(self, key):
            read.add(key)
            return super().__getitem__(key)

    for motion in ("orbit", "straight"):
        placements(Recording({p.key: p.default for p in PARAMS} | {"platform.motion": motion}))
    assert read | {"target.velocity"} == set(GEOMETRY_KEYS)


def test_the_check_places_things_as_the_simulation_does():
    """The check's noise-free truth and sensors are the scenario's."""
    params = {p.key: p.default for p in PARAMS} | {"target.velocity": [30.0, -20.0, 1.0],
                                                    "sensors.baseline": 800.0}
    sc = build_scenario(params)
    times, platform, sensors = placements(params)
    np.testing.assert_array_equal(sensors, sc.sensor_pos)
    np.testing.assert_array_equal(platform, sc.platform)
    truth = truth_trajectory(sc, None)[:, :3]
    np.testing.assert_allclose(np.asarray(params["target.position"]) + times[:, None]
                               * np.asarray(params["target.velocity"]), truth, atol=1e-6)


def test_validating_a_config_does_not_import_scipy():
    """The geometry check runs at every config load: it must not pull in scipy (0.2 s of
    start-up before the workers can start)."""
    probe = ("import sys; from trackfuse.config import load; "
             f"load({str(ORBIT)!r}); assert 'scipy' not in sys.modules, 'scipy imported'")
    subprocess.run([sys.executable, "-c", probe], check=True)


@pytest.mark.parametrize("key", ["target.position", "platform.start", "target.velocity"])
def test_validate_refuses_a_position_or_velocity_beyond_any_scenario(key, write_config):
    """`target.position: [0, 1e160, 4000]` was accepted: the run reported complete with every
    metric NaN under pages of numpy overflow warnings."""
    cfg = write_config(f"experiment: twin_sensor\ntrials: 2\nparams:\n  {key}: [0.0, 1e160, 0.0]\n")
    result = trackfuse("validate", cfg)
    assert result.returncode == 2 and result.stderr.count("\n") == 1, result.stderr
    assert f"params.{key}:" in result.stderr and "allowed: a list of 3 numbers in" in result.stderr
