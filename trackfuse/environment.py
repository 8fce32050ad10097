"""What a run's numbers depend on besides config, seed and code: library versions and the CPU.
Kept out of the fingerprinted modules so editing it changes no run id."""

from __future__ import annotations

import contextlib
import importlib
import importlib.metadata
import os
import platform
from pathlib import Path
from typing import Any

import numpy as np
import threadpoolctl

from trackfuse.experiments.base import Experiment
from trackfuse.fingerprint import code_fingerprint

NUMERIC_LIBRARIES = ("numpy", "scipy", "pandas", "numba", "stonesoup")
"""Libraries whose arithmetic or CSV formatting writes numbers (Stone Soup's in its own
configs): with Python's version, their versions are part of the run id, so an upgrade (or
installing Stone Soup) computes anew instead of serving or resuming an old folder."""

ROUNDING_VARIABLES = ("NPY_DISABLE_CPU_FEATURES", "NPY_ENABLE_CPU_FEATURES", "OPENBLAS_CORETYPE")
"""Environment variables that choose numpy's or OpenBLAS's vector code, recorded when set."""


def version(distribution: str) -> str | None:
    """Installed version of ``distribution`` without importing it (``None``: not installed)."""
    try:
        return importlib.metadata.version(distribution)
    except importlib.metadata.PackageNotFoundError:
        return None


def library_versions() -> dict[str, str | None]:
    """``{"python": ..., library: version or None}`` for :data:`NUMERIC_LIBRARIES`."""
    return {"python": platform.python_version(), **{d: version(d) for d in NUMERIC_LIBRARIES}}


def _numpy_simd() -> list[str] | None:
    """The vector extensions numpy dispatches to on this CPU; ``None`` where not exposed."""
    for module in ("numpy._core._multiarray_umath", "numpy.core._multiarray_umath"):
        with contextlib.suppress(ImportError, AttributeError):
            umath = importlib.import_module(module)
            return [k for k in umath.__cpu_dispatch__ if umath.__cpu_features__.get(k)]
    return None


def _numpy_blas() -> list[str] | None:
    """The BLAS numpy calls and the kernel it chose for this CPU (``["openblas SkylakeX"]``),
    numpy's bundled copy when it has one; ``None`` when no BLAS is found."""
    found = threadpoolctl.threadpool_info()
    blas = [lib for lib in found if lib.get("user_api") == "blas"]
    home = Path(np.__file__).resolve().parent
    own = [lib for lib in blas if Path(lib["filepath"]).resolve().parent
           in (home, home.with_name("numpy.libs"))]
    words = {f"{lib['internal_api']} {lib.get('architecture') or 'default'}"
             for lib in own or blas}
    return sorted(words) or None


def cpu() -> dict[str, Any]:
    """This CPU's ``model``, ``numpy_simd``, ``blas`` and the set :data:`ROUNDING_VARIABLES`:
    another CPU can round the last bit of some results differently."""
    model = platform.processor() or platform.machine()
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    settings = {v: os.environ[v] for v in ROUNDING_VARIABLES if v in os.environ}
    return {"model": model, "numpy_simd": _numpy_simd(), "blas": _numpy_blas(),
            "settings": settings}


def recorded_cpus(recorded: Any) -> list[dict[str, Any]]:
    """The CPUs (:func:`cpu`) a manifest's ``cpu`` names: a list, or one (older runs)."""
    found = recorded if isinstance(recorded, list) else [recorded]
    return [c for c in found if isinstance(c, dict)]


def unseen_cpus(current: list[dict[str, Any]],
                seen: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The CPUs of ``current`` that differ from every one of ``seen`` in a key both record."""
    def alike(one: dict[str, Any], other: dict[str, Any]) -> bool:
        return all(one[key] == other[key] for key in one.keys() & other.keys())
    return [c for c in current if not any(alike(c, s) for s in seen)]


def cpu_words(machine: dict[str, Any]) -> str:
    """One CPU of :func:`cpu` in words: model, numpy extensions, BLAS kernel, rounding settings."""
    simd = machine.get("numpy_simd")
    words = f"{machine.get('model')}, numpy {'/'.join(simd) if simd else 'baseline'}"
    if blas := machine.get("blas"):
        words += ", " + "/".join(blas)
    settings = machine.get("settings") or {}
    return words + "".join(f", {k}={v}" for k, v in settings.items())


def worker_environment(experiment: Experiment) -> dict[str, Any]:
    """``code`` fingerprint, ``libraries`` and ``cpu`` of this process, run on each dask worker."""
    return {"code": code_fingerprint(experiment).digest, "libraries": library_versions(),
            "cpu": cpu()}


def environment_difference(code: str, libraries: dict[str, str | None],
                           found: dict[str, Any]) -> str | None:
    """How a worker's ``found`` environment differs from this run's, in words, or ``None``."""
    if found.get("code") != code:
        return "runs other trackfuse code (another version or edited source)"
    theirs = found.get("libraries") or {}
    changed = [f"{lib} {theirs.get(lib)} (here {ours})" for lib, ours in libraries.items()
               if theirs.get(lib) != ours]
    return "has other library versions: " + ", ".join(changed) if changed else None
