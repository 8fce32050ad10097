"""Compile (or load) the numba kernels once, on tiny inputs: ``python -m trackfuse.precompile``.

Building the wheel runs it so the cache ships with the package; the fork server calls the
same functions. Where the cache was built and when numba ignores it:
``docs/benchmarks.md``, "First run". The S-D kernels need scipy, which the build
environment lacks, so they compile on first use.
"""

from __future__ import annotations

import sys
from types import SimpleNamespace

import numpy as np

from trackfuse.association.assignment import PairWeights
from trackfuse.association.pga_search import pga
from trackfuse.association.sd_assignment import solve_sd
from trackfuse.association.sd_costs import tuple_costs
from trackfuse.tracking.ipda import run_ipda
from trackfuse.tracking.nested_clutter import kept_arrivals, padded_disk_points
from trackfuse.tracking.pda import run_filter, symmetrized


def _tiny_batch() -> tuple[SimpleNamespace, SimpleNamespace, SimpleNamespace]:
    """``(scenario, batch, options)`` of one trial, two scans, two sensors, one clutter slot, typed
    as a simulated batch (without PDAOptions, which would import scipy).
    """
    N, K, S, C = 1, 2, 2, 1
    angles = np.full((N, K, S, 2), 0.1)
    scenario = SimpleNamespace(
        P0=np.eye(6) * 1e6, F=np.eye(6), Q_filter=np.eye(6), R=np.stack([np.eye(2) * 1e-4] * S),
        sensor_pos=np.zeros((K + 1, S, 3)), P_D=np.ones(S), gamma=9.21, clutter_model="in_gate",
        clutter_mean=1.0, window_density=1.0)
    batch = SimpleNamespace(
        x0=np.array([[1e5, 1e5, 1e3, 0.0, 0.0, 0.0]]), los=angles, z_target=angles,
        detected=np.ones((N, K, S), bool), clutter=np.zeros((N, K, S, C, 2)),
        clutter_ok=np.ones((N, K, S, C), bool))
    options = SimpleNamespace(method="mspda_parallel", covariance="mgekf", joint_cov="full",
                              density="parametric", mg_at="hypothesis", P_G=0.99)
    return scenario, batch, options


def load_pda_filter() -> None:
    """Run the PDA filter (:mod:`trackfuse.tracking.pda`) on a tiny batch and symmetrise its
    covariances as the scoring does."""
    symmetrized(run_filter(*_tiny_batch()).P)


def load_clutter_arrivals() -> None:
    """Run the nested clutter's arrival count and placement
    (:mod:`trackfuse.tracking.nested_clutter`)."""
    kept_arrivals(np.full((2, 2, 3), 0.5), 0.5, np.ones(2, dtype=np.bool_),
                  np.zeros(2, dtype=np.int64))
    padded_disk_points(np.ones((1, 1, 1), dtype=np.int64), np.full((2, 1), 0.5), 1)


def load_ipda_filter() -> None:
    """Run the IPDA filter (:mod:`trackfuse.tracking.ipda`) on a tiny batch."""
    run_ipda(*_tiny_batch(), SimpleNamespace(persistence=0.98, initial=0.5))


def load_pga() -> None:
    """Run the compiled PGA search (:mod:`trackfuse.association.pga_search`) on 2 x 3."""
    a = np.arange(6.0).reshape(2, 3)
    weights = PairWeights(a=a, a_i0=np.zeros(2), a_0j=np.zeros(3), chi2=np.zeros((2, 3)))
    pga(weights, np.random.default_rng(0), ops=10, repair_moves=True, staged=True, evict=True,
        accept="anneal")


def load_sd_kernels() -> None:
    """Cost and solve a small three-sensor scan with the S-D compiled kernels."""
    z = [np.array([[0.5, 0.2], [0.7, 0.3]]), np.array([[0.1, 0.2]]), np.array([[1.0, 0.1]])]
    sensors = np.array([[0.0, 0.0, 0.0], [0.0, 20e3, 7e3], [20e3, 0.0, 0.0]])
    solve_sd(tuple_costs(z, sensors, 0.01, 0.01, 0.9, 0.05))


def main() -> int:
    """Load every kernel; one that cannot compile here is named on stderr. Returns their number."""
    failed = 0
    for load in (load_pda_filter, load_clutter_arrivals, load_ipda_filter, load_pga,
                 load_sd_kernels):
        try:
            load()
        except ImportError as error:
            print(f"{load.__name__}: {error}", file=sys.stderr)
            failed += 1
    return failed


if __name__ == "__main__":
    sys.exit(main())
