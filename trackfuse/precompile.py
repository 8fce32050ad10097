"""Compile (or load) the numba kernels once, on tiny inputs: ``python -m trackfuse.precompile``.

Each kernel has one compiled version (every option is a runtime value), so one call on any
input of the right types puts it into numba's on-disk cache (or loads it from there).
Building the wheel runs this module (``setup.py``): the cache, written beside each kernel
module in the build tree, ships inside the installed package, keyed by the source's content,
this Python, numba's version and this machine's CPU, so the first run after ``pip install .``
loads the kernels instead of compiling them. Where any of those differ numba ignores the
files and compiles on first use, as without them. The process pool's fork server calls the
same functions (the experiments' ``preload`` modules).
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from trackfuse.association.assignment import PairWeights
from trackfuse.tracking.pda_options import PDAOptions


def load_pda_filter() -> None:
    """Run the PDA filter (:mod:`trackfuse.tracking.pda`) on one trial of two scans, two
    sensors and one clutter slot, with the arrays typed as a simulated batch is."""
    from trackfuse.tracking.pda import run_filter  # numba: only where a kernel is wanted

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
    run_filter(scenario, batch, PDAOptions(P_G=0.99))


def load_pga() -> None:
    """Run the compiled PGA search (:mod:`trackfuse.association.pga_search`) on a 2 x 3
    problem."""
    from trackfuse.association.pga_search import pga  # numba: only where a kernel is wanted

    a = np.arange(6.0).reshape(2, 3)
    weights = PairWeights(a=a, a_i0=np.zeros(2), a_0j=np.zeros(3), chi2=np.zeros((2, 3)))
    pga(weights, np.random.default_rng(0), ops=10, repair_moves=True, staged=True, evict=True,
        accept="anneal")


if __name__ == "__main__":
    load_pda_filter()
    load_pga()
