"""Give the C heap's free memory back to the operating system between large, short-lived
allocations (a chunk of rows read and summarised), so the process's resident size stays at
one chunk however many are read.

glibc keeps freed blocks of a few MiB in its heap once it has seen one freed (its mmap
threshold rises with them), and the heap then grows slowly from chunk to chunk with the
fragments that small long-lived objects pin; ``malloc_trim`` hands its free pages back. On
other C libraries (macOS, musl) this does nothing.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools
from collections.abc import Callable


@functools.cache
def _malloc_trim() -> Callable[[int], int] | None:
    """glibc's ``malloc_trim``, or ``None`` where the C library has none."""
    name = ctypes.util.find_library("c")
    try:
        return ctypes.CDLL(name).malloc_trim if name else None
    except (OSError, AttributeError):
        return None


def release_free_memory() -> None:
    """Return the heap's free pages to the operating system (where the C library can)."""
    trim = _malloc_trim()
    if trim is not None:
        trim(0)
