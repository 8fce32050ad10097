"""Run an experiment in memory: trials and summary frames from params, a sweep and a seed.

The harness is the real runner on a throw-away folder (serial executor, no report), so its
numbers are the numbers ``trackfuse run`` writes for the same config, seeding, batching,
summary and intervals included::

    from trackfuse import harness
    trials, summary = harness.run("twin_sensor", params={"scan.count": 5},
                                  sweep={"clutter.mean": [0, 4]}, trials=20, seed=1)

:func:`run_data` keeps the folder and returns it as :class:`~trackfuse.rundata.RunData`,
which is what report modules read (figure tests draw from it).

A plugin is named as in a config (``"coin:EXPERIMENT"``, found on the Python path) or by
its file from any folder (``"examples/plugin_example/coin.py:EXPERIMENT"``): the file's
folder is added to the end of the Python path and the run records ``coin:EXPERIMENT``.
"""

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
    """Run ``experiment`` (a name, a plugin's ``module:ATTR`` or ``path/module.py:ATTR``, or
    an :class:`Experiment`) into ``out`` and return the
    complete run. ``params`` override defaults (dotted keys; a swept key's value is
    ignored); ``sweep`` maps a key to its values; ``trials`` per sweep point; ``seed`` the
    root seed; ``batch_size`` default: the experiment's.

    An :class:`Experiment` object is run as it is, never looked up by its name (two objects
    of one name, or a ``dataclasses.replace`` of a built-in, each run their own code), and
    the returned run's :attr:`~trackfuse.rundata.RunData.experiment` is that object. The
    folder records the name only, and the run id covers the config and the source files,
    not the object: give two objects of one name, defined in one module, their own
    ``out`` (as :func:`run` does), or the second resumes the first's finished run."""
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
