"""Load the compiled tail minimum of the S-D assignment once, in the process pool's fork
server (``Experiment.preload``): every worker inherits it instead of loading it itself."""

from __future__ import annotations

import numpy as np

from trackfuse.association.sd_assignment import solve_sd


def load_kernel() -> None:
    """Solve a small fixed 3-D problem (the kernel has one compiled version)."""
    cost = np.zeros((2, 2, 2))
    cost[1, 1, 1] = -1.0
    solve_sd(cost)


load_kernel()
