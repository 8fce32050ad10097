"""Load the compiled PGA loop once, in the process pool's fork server.

The fork server imports this module (``Experiment.preload``) before it forks workers: the
compiled search loop (:mod:`trackfuse.association.pga_search`) is loaded from numba's
on-disk cache, or compiled on the first run on a machine, here once, and every worker
inherits it in memory instead of loading or compiling it on its own.
"""

from __future__ import annotations

from trackfuse.precompile import load_pga

load_pga()
