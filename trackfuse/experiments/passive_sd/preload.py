"""Load the compiled kernels of the S-D assignment once, in the process pool's fork server
(``Experiment.preload``): the tail minimum of the relaxation
(:mod:`trackfuse.association.sd_assignment`) and the tuple chi-square
(:mod:`trackfuse.association.sd_costs`), loaded from numba's on-disk cache or compiled on the
first run on a machine, here once; every worker inherits them instead of loading or
compiling them itself."""

from __future__ import annotations

from trackfuse.precompile import load_sd_kernels

load_sd_kernels()
