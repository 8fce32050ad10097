"""Last check of an ``esm_radar`` config: refused before any trial runs when a dynamic-weights
algorithm needs an ``alpha_max`` that ``alpha.max_mode`` cannot give for ``alpha.index``
(:func:`~.model.alpha_max_problem`)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from trackfuse.experiments.esm_radar.model import (
    ALGORITHMS,
    alpha_max_problem,
    factor_names,
    uses_alpha_max,
)
from trackfuse.sweep import expand

#: The keys that decide whether a point needs ``alpha_max`` and whether it can have one.
ALPHA_KEYS = ("algorithms", "baseline.factors", "alpha.index", "alpha.max_mode")


def config_problem(params: Mapping[str, Any], sweep: Mapping[str, list[Any]],
                   mode: str) -> tuple[str, str] | None:
    """``(key, problem)`` for the first sweep point (or the params when nothing relevant is
    swept) whose dynamic-weight algorithms cannot get ``alpha_max``, else ``None``."""
    axes = {k: v for k, v in sweep.items() if k in ALPHA_KEYS}
    for point in expand(axes, mode):
        p = {**params, **point.values}
        users = [a for a in p["algorithms"]
                 if uses_alpha_max(ALGORITHMS[a], factor_names(ALGORITHMS[a], p))]
        problem = alpha_max_problem(p) if users else None
        if problem is not None:
            where = ", ".join(f"{k}={v}" for k, v in point.values.items())
            return "alpha.max_mode", (f"{problem} (needed by the dynamic weights of "
                                      f"{', '.join(users)}"
                                      + (f", at the sweep point {where})" if where else ")"))
    return None
