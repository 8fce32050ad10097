"""Last checks of a ``twin_sensor`` config: what the schema's per-key limits cannot see.

A config is refused before any trial runs when it asks for Stone Soup on a machine without
it, or when its geometry has no bearing to measure: a target on a sensor (zero range) or an
orbit started on the target's vertical (zero radius). Only the noise-free truth is checked;
truth process noise (``target.q``) can still bring a rare trial closer.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from trackfuse.experiments.twin_sensor.model import build_scenario, truth_trajectory
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


def config_problem(params: Mapping[str, Any], sweep: Mapping[str, list[Any]],
                   mode: str) -> tuple[str, str] | None:
    """``(key, problem)`` for the first thing this config cannot run, else ``None``."""
    return missing_stonesoup(params, sweep) or geometry_problem(params, sweep, mode)


def geometry_problem(params: Mapping[str, Any], sweep: Mapping[str, list[Any]],
                     mode: str) -> tuple[str, str] | None:
    """``(key, problem)`` when some sweep point's geometry is degenerate, else ``None``.

    Each distinct combination of the swept :data:`GEOMETRY_KEYS` is checked once.
    """
    axes = {k: v for k, v in sweep.items() if k in GEOMETRY_KEYS}
    for point in expand(axes, mode):
        problem = _separation_problem({**params, **point.values})
        if problem is not None:
            where = ", ".join(f"{k}={v}" for k, v in point.values.items())
            key = next(iter(point.values), "target.position")
            return key, problem + (f" (at the sweep point {where})" if where else "")
    return None


def _separation_problem(params: dict[str, Any]) -> str | None:
    """What is degenerate about one point's geometry, else ``None``."""
    target = np.asarray(params["target.position"], dtype=float)
    start = np.asarray(params["platform.start"], dtype=float)
    radius = float(np.hypot(*(start[:2] - target[:2])))
    if params["platform.motion"] == "orbit" and radius < MIN_SEPARATION_M:
        return (f"the orbit starts {radius:.3g} m from the target's vertical line, its centre; "
                f"allowed: platform.start at least {MIN_SEPARATION_M:g} m from target.position "
                "horizontally")
    with np.errstate(divide="ignore", invalid="ignore"):
        sc = build_scenario(dict(params))
    truth = truth_trajectory(sc, None)[:, None, :3]
    distance = np.linalg.norm(truth - sc.sensor_pos, axis=-1)
    k, s = np.unravel_index(int(np.argmin(distance)), distance.shape)
    if distance[k, s] < MIN_SEPARATION_M:
        return (f"the target is {distance[k, s]:.3g} m from sensor {s + 1} at scan {k}, where "
                "it has no bearing; allowed: the target at least "
                f"{MIN_SEPARATION_M:g} m from every sensor at every scan (move target.position "
                "or platform.start, or change the platform's motion)")
    return None
