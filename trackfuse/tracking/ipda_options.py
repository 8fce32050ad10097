"""IPDA's existence model and the confirmation and termination decisions.

Apart from the compiled filter so that config checks and scoring import no numba.
Equations: ``docs/papers/twin_sensor.md``, "Track existence (IPDA)".
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class ExistenceModel:
    """Existence model and decisions: ``persistence`` in (0, 1] (no birth), ``initial`` existence
    at t = 0, thresholds ``0 < terminate < confirm < 1``.
    """

    persistence: float = 0.98
    initial: float = 0.5
    confirm: float = 0.95
    terminate: float = 0.05

    def __post_init__(self) -> None:
        if not 0.0 < self.persistence <= 1.0:
            raise ValueError(f"persistence must lie in (0, 1], got {self.persistence}")
        if not 0.0 < self.initial < 1.0:
            raise ValueError(f"initial existence must lie in (0, 1), got {self.initial}")
        if not 0.0 < self.terminate < self.confirm < 1.0:
            raise ValueError("thresholds must satisfy 0 < terminate < confirm < 1, got "
                             f"terminate={self.terminate}, confirm={self.confirm}")

    @classmethod
    def from_params(cls, params: Mapping[str, Any]) -> ExistenceModel:
        """The model of resolved twin-sensor ``params`` (the ``ipda.*`` keys)."""
        return cls(float(params["ipda.persistence"]), float(params["ipda.initial"]),
                   float(params["ipda.confirm"]), float(params["ipda.terminate"]))


def track_decisions(existence: np.ndarray, model: ExistenceModel
                    ) -> tuple[np.ndarray, np.ndarray]:
    """``(confirmed, terminated)`` (N, K) bool from ``existence`` (N, K), NaN from divergence on.

    Both permanent: terminated from the first scan below ``terminate`` or NaN; confirmed from
    the first scan before that reaching ``confirm``.
    """
    with np.errstate(invalid="ignore"):
        low = ~(existence >= model.terminate)  # NaN counts as below
        high = existence >= model.confirm
    terminated = np.logical_or.accumulate(low, axis=1)
    confirmed = np.logical_or.accumulate(high & ~terminated, axis=1)
    return confirmed, terminated
