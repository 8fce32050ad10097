"""Run an experiment in memory: the real runner (serial, no report) on a throw-away folder, so
its numbers are those ``trackfuse run`` writes for the same config (``docs/plugins.md``)::

    from trackfuse import harness
    trials, summary = harness.run("twin_sensor", params={"scan.count": 5},
                                  sweep={"clutter.mean": [0, 4]}, trials=20, seed=1)"""

from __future__ import annotations

import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import pandas as pd

from trackfuse.config import build
from trackfuse.experiments import add_plugin_folder, file_reference
from trackfuse.experiments.base import Experiment
from trackfuse.rundata import RunData, load
from trackfuse.runner import Runner


def _config(experiment: str | Experiment, params: Mapping[str, Any] | None,
            sweep: Mapping[str, list[Any]] | None, trials: int, seed: int,
            sweep_mode: str, batch_size: int | None):
    given = experiment if isinstance(experiment, Experiment) else None
    if given is None and (by_file := file_reference(experiment)) is not None:
        folder, experiment = by_file
        add_plugin_folder(folder)
    sweep = dict(sweep or {})
    fixed = {k: v for k, v in (params or {}).items() if k not in sweep}
    raw: dict[str, Any] = {"experiment": experiment if given is None else given.name,
                           "trials": trials, "seed": seed, "params": fixed, "sweep": sweep,
                           "sweep_mode": sweep_mode}
    if batch_size is not None:
        raw["batch_size"] = batch_size
    return build(raw, "harness", experiment=given)


def run_data(out: str | Path, experiment: str | Experiment,
             params: Mapping[str, Any] | None = None,
             sweep: Mapping[str, list[Any]] | None = None, *, trials: int = 10, seed: int = 0,
             sweep_mode: str = "grid", batch_size: int | None = None) -> RunData:
    """Run ``experiment`` (a name, ``module:ATTR``, ``path/module.py:ATTR`` or an
    :class:`Experiment`, run as given) into ``out`` and return the complete run. ``params`` are
    dotted overrides, ``sweep`` maps a key to its values, ``trials`` per point.

    The run id covers the name, not the object: two objects of one name need their own ``out``,
    or the second resumes the first's run."""
    config = _config(experiment, params, sweep, trials, seed, sweep_mode, batch_size)
    runner = Runner(config, Path(out), workers=1, executor="serial", plots=False,
                    progress=False, command=["trackfuse.harness"])
    return load(runner.run().folder, experiment=config.experiment)


def run(experiment: str | Experiment, params: Mapping[str, Any] | None = None,
        sweep: Mapping[str, list[Any]] | None = None, *, trials: int = 10, seed: int = 0,
        sweep_mode: str = "grid",
        batch_size: int | None = None) -> tuple[pd.DataFrame, pd.DataFrame]:
    """``(trials, summary)`` frames of ``experiment`` (see :func:`run_data`); the summary
    includes the timing metrics (``*_time_s``). Nothing is kept on disk."""
    with tempfile.TemporaryDirectory(prefix="trackfuse-harness-") as tmp:
        data = run_data(tmp, experiment, params, sweep, trials=trials, seed=seed,
                        sweep_mode=sweep_mode, batch_size=batch_size)
        return data.trials, data.summary


__all__ = ["run", "run_data"]
