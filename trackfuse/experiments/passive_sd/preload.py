"""Load the compiled kernels of the S-D assignment once, in the process pool's fork server
(``Experiment.preload``): the tail minimum of the relaxation
(:mod:`trackfuse.association.sd_assignment`) and the tuple chi-square
(:mod:`trackfuse.association.sd_costs`), loaded from numba's on-disk cache or compiled on the
first run on a machine, here once; every worker inherits them instead of loading or
compiling them itself."""

from __future__ import annotations

import numpy as np

from trackfuse.association.sd_assignment import solve_sd
from trackfuse.association.sd_costs import tuple_costs


def load_kernels() -> None:
    """Cost and solve a small fixed scan of three sensors (each kernel has one compiled
    version: the number of sensors and measurements are runtime values)."""
    z = [np.array([[0.5, 0.2], [0.7, 0.3]]), np.array([[0.1, 0.2]]), np.array([[1.0, 0.1]])]
    sensors = np.array([[0.0, 0.0, 0.0], [0.0, 20e3, 7e3], [20e3, 0.0, 0.0]])
    solve_sd(tuple_costs(z, sensors, 0.01, 0.01, 0.9, 0.05))


load_kernels()
