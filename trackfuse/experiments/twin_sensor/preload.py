"""Load the compiled filter once, in the process pool's fork server, before it forks workers.

Each worker then inherits it instead of loading it (about 0.6 s) or compiling it (about
25 s) on its own; a cold cache compiles on two cores (:mod:`.cold_compile`).
"""

from __future__ import annotations

from trackfuse.experiments.twin_sensor.cold_compile import compile_on_two_cores, kernel_cached
from trackfuse.precompile import load_clutter_arrivals, load_pda_filter


def load_kernel() -> None:
    """Load the filter (compiling it on two cores if numba's cache lacks it) and the clutter
    simulation's kernel."""
    if not kernel_cached():
        compile_on_two_cores()
    load_pda_filter()
    load_clutter_arrivals()


load_kernel()
