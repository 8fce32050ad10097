"""Last check of a ``passive_assoc`` config: the paper's scene has only its ten targets, so a
config asking it for more is refused before any trial runs."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from trackfuse.association.passive_scene import PAPER_TARGETS
from trackfuse.sweep import expand

#: The keys that decide how many targets a point's scene can have.
SCENE_KEYS = ("scene.mode", "targets.n")


def config_problem(params: Mapping[str, Any], sweep: Mapping[str, list[Any]],
                   mode: str) -> tuple[str, str] | None:
    """``("targets.n", problem)`` for the first sweep point (or the params when neither
    scene key is swept) asking the paper scene for more targets than it has, else ``None``."""
    axes = {k: v for k, v in sweep.items() if k in SCENE_KEYS}
    for point in expand(axes, mode):
        p = {**params, **point.values}
        if p["scene.mode"] == "paper" and int(p["targets.n"]) > len(PAPER_TARGETS):
            where = ", ".join(f"{k}={v}" for k, v in point.values.items())
            return "targets.n", (f"got {p['targets.n']}"
                                 + (f" at the sweep point {where}" if where else "")
                                 + f"; allowed with scene.mode: paper: 1..{len(PAPER_TARGETS)}"
                                 " (the paper's targets M1-M10; scene.mode: random takes up"
                                 " to 2000)")
    return None
