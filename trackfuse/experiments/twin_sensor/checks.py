"""Last checks of a ``twin_sensor`` config: what the schema's per-key limits cannot see.

Refused before any trial: Stone Soup asked for but absent, a degenerate noise-free geometry
(target on a sensor, orbit started on the target's vertical), or ``ipda.terminate`` not
below ``ipda.confirm``. Truth process noise can still bring a rare trial closer.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from trackfuse.experiments.twin_sensor.model import PARAMS, placements
from trackfuse.experiments.twin_sensor.stonesoup import missing_stonesoup
from trackfuse.sweep import expand

#: The keys that place the target, the platform and the sensors at every scan.
GEOMETRY_KEYS = ("scan.period", "scan.count", "target.position", "target.velocity",
                 "platform.motion", "platform.start", "platform.speed", "platform.climb",
                 "platform.direction", "platform.heading", "sensors.count",
                 "sensors.baseline", "sensors.baseline_angle")
#: Smallest distance (m) allowed between the noise-free target and a sensor, and smallest
#: horizontal distance between an orbit's start and its centre (the target).
MIN_SEPARATION_M = 1.0
#: Each parameter's default (an error names a key the config changed, if one did).
DEFAULTS = {p.key: p.default for p in PARAMS}


def config_problem(params: Mapping[str, Any], sweep: Mapping[str, list[Any]],
                   mode: str) -> tuple[str, str] | None:
    """``(key, problem)`` for the first thing this config cannot run, else ``None``."""
    return (missing_stonesoup(params, sweep) or geometry_problem(params, sweep, mode)
            or threshold_problem(params, sweep, mode))


def threshold_problem(params: Mapping[str, Any], sweep: Mapping[str, list[Any]],
                      mode: str) -> tuple[str, str] | None:
    """``(key, problem)`` when a sweep point's ``ipda.terminate`` is not below ``ipda.confirm``."""
    keys = ("ipda.terminate", "ipda.confirm")
    for point in expand({k: v for k, v in sweep.items() if k in keys}, mode):
        values = {**params, **point.values}
        terminate, confirm = float(values[keys[0]]), float(values[keys[1]])
        if terminate >= confirm:
            where = ", ".join(f"{k}={v}" for k, v in point.values.items())
            return _blamed(keys, params, sweep), (
                f"ipda.terminate={terminate:g} is not below ipda.confirm={confirm:g}"
                + (f" (at the sweep point {where})" if where else "")
                + "; allowed: ipda.terminate < ipda.confirm")
    return None


def geometry_problem(params: Mapping[str, Any], sweep: Mapping[str, list[Any]],
                     mode: str) -> tuple[str, str] | None:
    """``(key, problem)`` for the first degenerate geometry, each swept combination checked once."""
    axes = {k: v for k, v in sweep.items() if k in GEOMETRY_KEYS}
    checked: set[str] = set()
    for point in expand(axes, mode):
        seen = repr(sorted(point.values.items()))
        if seen in checked:
            continue
        checked.add(seen)
        problem = _separation_problem({**params, **point.values})
        if problem is not None:
            keys, text = problem
            where = ", ".join(f"{k}={v}" for k, v in point.values.items())
            return _blamed(keys, params, sweep), text + (f" (at the sweep point {where})"
                                                         if where else "")
    return None


def _blamed(keys: tuple[str, ...], params: Mapping[str, Any],
            sweep: Mapping[str, list[Any]]) -> str:
    """The key to name for a degenerate geometry: the first swept, else the first changed from its
    default, else the first.
    """
    return next((k for k in keys if k in sweep), None) or next(
        (k for k in keys if params[k] != DEFAULTS[k]), keys[0])


def _separation_problem(params: dict[str, Any]) -> tuple[tuple[str, ...], str] | None:
    """``(keys, what is degenerate)`` about one point's geometry, else ``None``."""
    target = np.asarray(params["target.position"], dtype=float)
    start = np.asarray(params["platform.start"], dtype=float)
    radius = float(np.hypot(*(start[:2] - target[:2])))
    if params["platform.motion"] == "orbit" and radius < MIN_SEPARATION_M:
        return ("target.position", "platform.start"), (
            f"the orbit starts {radius:.3g} m from the target's vertical line, its centre; "
            f"allowed: platform.start at least {MIN_SEPARATION_M:g} m from target.position "
            "horizontally")
    times, _, sensors = placements(params)
    velocity = np.asarray(params["target.velocity"], dtype=float)
    truth = target + times[:, None] * velocity  # noise-free constant velocity, (K+1, 3)
    distance = np.linalg.norm(truth[:, None, :] - sensors, axis=-1)
    k, s = np.unravel_index(int(np.argmin(distance)), distance.shape)
    if distance[k, s] < MIN_SEPARATION_M:
        return ("target.position", "platform.start", "sensors.baseline",
                "sensors.baseline_angle", "platform.motion"), (
            f"the target is {distance[k, s]:.3g} m from sensor {s + 1} at scan {k}, where it "
            f"has no bearing; allowed: the target at least {MIN_SEPARATION_M:g} m from every "
            "sensor at every scan (move target.position or platform.start, or change the "
            "platform's motion)")
    return None
