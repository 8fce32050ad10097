"""What the IPDA filter (:mod:`trackfuse.tracking.ipda`) is asked about track existence, and
the confirmation and termination decisions taken from its existence probabilities.

Kept apart from the compiled filter so that reading the options (a config check, scoring)
does not import numba. The equations are in ``docs/papers/twin_sensor.md`` (Track
existence).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np


@dataclass(frozen=True)
class ExistenceModel:
    """The existence model and the track decisions of IPDA.

    ``persistence``: probability that a target existing at one scan still exists at the next
    (the Markov chain's ``p_11``; no birth, ``p_21 = 0``), in (0, 1]. ``initial``: the
    existence probability of the track at ``t = 0``, in (0, 1). ``confirm``: a track is
    confirmed at the first scan its existence probability reaches this; ``terminate``: it
    is terminated at the first scan its existence probability falls below this
    (``0 < terminate < confirm < 1``).
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
    """``(confirmed, terminated)``, both ``(N, K)`` bool, from the existence probabilities
    ``existence: (N, K)`` of ``N`` tracks at scans ``1..K`` (NaN from a diverged scan on).

    ``terminated`` is permanent from the first scan whose existence is below
    ``model.terminate`` or NaN; ``confirmed`` is permanent from the first scan, before any
    termination, whose existence reaches ``model.confirm`` (a track terminated later stays
    counted as confirmed: it was a confirmed track).
    """
    with np.errstate(invalid="ignore"):
        low = ~(existence >= model.terminate)  # NaN counts as below
        high = existence >= model.confirm
    terminated = np.logical_or.accumulate(low, axis=1)
    confirmed = np.logical_or.accumulate(high & ~terminated, axis=1)
    return confirmed, terminated
