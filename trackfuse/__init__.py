"""trackfuse: Monte Carlo experiment runner for passive multi-sensor tracking studies.

Load a finished run's frames and config::

    import trackfuse
    run = trackfuse.load("results/twin_sensor_orbit/seed20051001-...")
    run.trials, run.summary, run.config, run.manifest
    table = trackfuse.runs("results")   # every run as one row of a DataFrame

:func:`load` is :func:`trackfuse.rundata.load` (see ``docs/outputs.md#loading-results``),
:func:`runs` is :func:`trackfuse.catalog.runs`. They are
bound on first use (PEP 562), so importing ``trackfuse.config`` or running ``trackfuse list``
loads no pandas.
"""

import importlib
from typing import Any

__version__ = "0.1.0"

_LAZY = {"load": "trackfuse.rundata", "runs": "trackfuse.catalog"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name]), name)
    raise AttributeError(f"module 'trackfuse' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])
