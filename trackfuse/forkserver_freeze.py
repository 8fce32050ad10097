"""Imported last by the process pool's fork server (:mod:`trackfuse.executors`), after the
runner and the experiment's preload modules: it moves every object loaded so far out of the
garbage collector's view (:func:`gc.freeze`).

Those objects (modules, compiled kernels) live as long as the processes do. Frozen, the
collector neither walks them in every full collection of every worker (which would also
copy the pages the workers share with the fork server) nor in the fork server's own
collections at exit, which otherwise take about half a second after the run has ended.
"""

import gc

gc.freeze()
