"""Imported last by the fork server (:mod:`trackfuse.executors`): :func:`gc.freeze` on every
object loaded so far (modules, kernels), so no collection walks them, in workers (which would
copy the shared pages) or at the fork server's exit (about 0.5 s)."""

import gc

gc.freeze()
