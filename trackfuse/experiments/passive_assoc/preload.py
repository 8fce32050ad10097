"""Load the compiled PGA loop once, in the process pool's fork server.

The fork server imports this module (``Experiment.preload``) before it forks workers: the
compiled search loop (:mod:`trackfuse.association.pga_search`) is loaded from numba's
on-disk cache, or compiled on the first run on a machine, here once, and every worker
inherits it in memory instead of loading or compiling it on its own.
"""

from __future__ import annotations

import numpy as np

from trackfuse.association.assignment import PairWeights
from trackfuse.association.pga_search import pga


def load_kernel() -> None:
    """Run the compiled loop once on a small fixed problem (every option is a runtime
    value, so this one call loads the only compiled version)."""
    a = np.arange(6.0).reshape(2, 3)
    weights = PairWeights(a=a, a_i0=np.zeros(2), a_0j=np.zeros(3), chi2=np.zeros((2, 3)))
    pga(weights, np.random.default_rng(0), ops=10, repair_moves=True, staged=True,
                 evict=True, accept="anneal")


load_kernel()
