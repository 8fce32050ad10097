"""trackfuse: Monte Carlo experiment runner for passive multi-sensor tracking studies.

Load a finished run's frames and config::

    import trackfuse
    run = trackfuse.load("results/twin_sensor_orbit/seed20051001-...")
    run.trials, run.summary, run.config, run.manifest

:func:`load` is :func:`trackfuse.rundata.load` (see ``docs/outputs.md#loading-results``). It is
bound on first use (PEP 562), so importing ``trackfuse.config`` or running ``trackfuse list``
loads no pandas.
"""

import importlib
from typing import Any

__version__ = "0.1.0"

_LAZY = {"load": "trackfuse.rundata"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'trackfuse' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])
