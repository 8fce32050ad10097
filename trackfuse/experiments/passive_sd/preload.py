"""Load the S-D assignment's compiled kernels (the relaxation's tail minimum, the tuple
chi-square) once, in the fork server (``Experiment.preload``), for every worker to inherit."""

from __future__ import annotations

from trackfuse.precompile import load_sd_kernels

load_sd_kernels()
