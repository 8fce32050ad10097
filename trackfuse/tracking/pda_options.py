"""What the PDA filter is asked and returns, apart from it so that reading options imports no
numba."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from trackfuse.tracking.sensors import gate_threshold

METHODS = ("mspda_parallel", "mspda_sequential", "nn", "paper_approx")
COVARIANCES = ("mgekf", "ekf_joseph")
JOINT_COVS = ("full", "blockdiag")
DENSITIES = ("parametric", "nonparametric")
MG_AT = ("hypothesis", "combined")


@dataclass(frozen=True)
class PDAOptions:
    """How the PDA filter associates and updates: ``method`` (:data:`METHODS`), ``covariance``
    (``"mgekf"`` or ``"ekf_joseph"``), ``joint_cov`` in ``w_ij``, clutter ``density``, ``mg_at``
    (W000-4), gate probability ``P_G`` and derived ``gamma = chi2_{n_z}^-1(P_G)``."""

    method: str = "mspda_parallel"
    covariance: str = "mgekf"
    joint_cov: str = "full"
    density: str = "parametric"
    mg_at: str = "hypothesis"
    P_G: float = 0.99
    n_z: int = 2
    gamma: float = field(init=False)

    def __post_init__(self) -> None:
        for name, allowed in (("method", METHODS), ("covariance", COVARIANCES),
                              ("joint_cov", JOINT_COVS), ("density", DENSITIES),
                              ("mg_at", MG_AT)):
            if getattr(self, name) not in allowed:
                raise ValueError(f"unknown PDA {name} {getattr(self, name)!r}; "
                                 f"choose from {allowed}")
        if not 0.0 < self.P_G < 1.0:
            raise ValueError(f"gate probability P_G must lie in (0, 1), got {self.P_G}")
        object.__setattr__(self, "gamma", gate_threshold(self.P_G, self.n_z))



@dataclass(frozen=True)
class Estimates:
    """Filter output over ``N`` trials and ``K`` scans: ``X`` (N, K, 6), ``P`` (N, K, 6, 6) (NaN
    after a failure), ``n_valid`` (N, K, S), ``inside`` (N, K) noise-free return in a gate."""

    X: np.ndarray
    P: np.ndarray
    n_valid: np.ndarray
    inside: np.ndarray
