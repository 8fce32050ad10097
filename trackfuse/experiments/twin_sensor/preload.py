"""Load the compiled filter loop once, in the process pool's fork server.

The fork server imports this module (``Experiment.preload``) before it forks workers: the
compiled PDA filter (:mod:`trackfuse.tracking.pda`) is loaded from numba's on-disk cache,
or compiled on the first run on a machine, here once (on two cores: :mod:`.cold_compile`),
and every worker inherits it in memory instead of loading it (about 0.6 s each) or
compiling it (about 25 s each) on its own.
"""

from __future__ import annotations

from trackfuse.experiments.twin_sensor.cold_compile import compile_on_two_cores, kernel_cached
from trackfuse.experiments.twin_sensor.model import (
    ALGORITHMS,
    FILTERS,
    PARAMS,
    build_scenario,
    simulate,
    stack,
)
from trackfuse.seeding import trial_streams
from trackfuse.tracking.pda import run_filter
from trackfuse.tracking.pda_options import PDAOptions


def load_kernel() -> None:
    """Run the kernel once on one trial of the default scenario (every option is a runtime
    value, so this one call loads the only compiled version)."""
    params = {p.key: p.default for p in PARAMS}
    sc = build_scenario(params)
    batch = stack([simulate(sc, trial_streams(0, 0, 0))])
    assoc, filt = ALGORITHMS[0].split("/")
    if not kernel_cached():
        compile_on_two_cores()
    run_filter(sc, batch, PDAOptions(assoc, FILTERS[filt], P_G=sc.P_G))


load_kernel()
