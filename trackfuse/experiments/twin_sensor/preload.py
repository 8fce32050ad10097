"""Load the compiled filter loop once, in the process pool's fork server.

The fork server imports this module (``Experiment.preload``) before it forks workers: the
compiled PDA filter (:mod:`trackfuse.tracking.pda`) is loaded from numba's on-disk cache,
or compiled on the first run on a machine, here once (on two cores: :mod:`.cold_compile`),
and every worker inherits it in memory instead of loading it (about 0.6 s each) or
compiling it (about 25 s each) on its own.
"""

from __future__ import annotations

from trackfuse.experiments.twin_sensor.cold_compile import compile_on_two_cores, kernel_cached
from trackfuse.precompile import load_pda_filter


def load_kernel() -> None:
    """Load the filter (compiling it on two cores if numba's cache lacks it)."""
    if not kernel_cached():
        compile_on_two_cores()
    load_pda_filter()


load_kernel()
