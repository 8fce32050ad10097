"""Compile the PDA filter on two cores when numba's on-disk cache lacks it.

numba compiles one function at a time per process: a helper process compiles
``_pair_update`` (about half the work) into the cache while this one compiles the other
callees; ``_filter_batch`` is compiled last. Whatever the helper does, numba compiles here
what the cache lacks, so the result is the same.
"""

from __future__ import annotations

import hashlib
import os
import pickle
import subprocess
import sys
import threading
from pathlib import Path

import numba
import numpy as np
from numba import typeof

from trackfuse.tracking import pda as k

#: The helper's program: this process's module path (its argument list) first, so that it
#: imports the same kernel file, whose path names its folder in numba's cache.
HELPER = ("import sys; sys.path[:] = sys.argv[1:]; "
          "from trackfuse.experiments.twin_sensor.cold_compile import compile_pair_update; "
          "compile_pair_update()")


def kernel_cached() -> bool:
    """Whether numba's cache holds a current index of ``_filter_batch`` for this Python, numba and
    source. A wrong answer costs time only.
    """
    source = Path(k.__file__)
    st = source.stat()
    stamps = (hashlib.sha256(source.read_bytes()).digest(), (st.st_mtime, st.st_size))
    python = f".py{sys.version_info.major}{sys.version_info.minor}"
    index = Path(k._filter_batch.stats.cache_path).glob(f"*._filter_batch-*{python}*.nbi")
    return any(index_stamp(p) in stamps for p in index)


def index_stamp(path: Path) -> object:
    """The source stamp of cache index ``path`` if this numba version wrote it, else ``None``."""
    try:
        with path.open("rb") as f:
            version = pickle.load(f)  # numba's own cache file: numba unpickles it too
            if version != numba.__version__:
                return None
            stamp, _ = pickle.loads(f.read())
    except (OSError, pickle.UnpicklingError, EOFError, ValueError, TypeError):
        return None
    return stamp


def callee_args() -> dict:
    """``{dispatcher: args}`` typed as ``_filter_batch`` passes them (only the types are used)."""
    lin, mom = k.Linearized.py_func(2, 2), k.Moments.py_func(2)
    x, P, R, s = np.empty(6), np.empty((6, 6)), np.empty((2, 2)), 0
    z, ok = np.empty((2, 2)), np.empty(2, np.bool_)
    return {
        k._pair_update: (x, P, np.empty((2, 2, 2)), x, 0.0, 0, False, False, lin, mom, x, P),
        k.Linearized: (2, 2), k.Moments: (2,),
        k._single_update: (x, P, R, 0.0, 0.0, False, False, lin, s, mom),
        k._geometry: (x, P, x, R, lin, s), k._in_gate: (x, lin, s, 0.0),
        k._place_returns: (x, False, z, ok, 0.0, False, 0.0, 0.0, lin, s, z, ok),
        k._linearize: (z, ok, 0.0, 0.0, False, False, lin, s),
        k._copy_state: (x, P, x, P), k._predict: (x, P, P, P, x, P, P),
        k._symmetrize_and_check: (x, P),
    }


def compile_in(dispatcher, args: tuple) -> None:
    """Compile (or load from the cache) ``dispatcher`` for the numba types of ``args``."""
    dispatcher.compile(tuple(typeof(a) for a in args))


def compile_pair_update() -> None:
    """The helper process: cache ``_pair_update``; exits when its parent closes stdin or dies."""
    threading.Thread(target=lambda: (sys.stdin.read(), os._exit(1)), daemon=True).start()
    compile_in(k._pair_update, callee_args()[k._pair_update])


def compile_on_two_cores() -> None:
    """Compile the kernel's callees beside a helper process, then wait for it."""
    try:
        helper = subprocess.Popen([sys.executable, "-c", HELPER, *sys.path], stdin=subprocess.PIPE,
                                  stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except OSError:  # no helper: _filter_batch compiles everything here
        return
    with helper:  # on an error here, closing stdin stops the helper
        for dispatcher, args in callee_args().items():
            if dispatcher is not k._pair_update:
                compile_in(dispatcher, args)
        helper.wait()
