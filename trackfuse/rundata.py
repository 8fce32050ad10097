"""Read a finished run folder: its config, manifest, trials and summary, as plain frames.

This is the one reader of saved results: ``trackfuse plot``, ``trackfuse compare``, the
reports and users' own notebooks all go through :func:`load`::

    import trackfuse
    run = trackfuse.load("results/twin_sensor_orbit/seed20051001-...")
    run.trials.query("algorithm == 'mspda_parallel/mgekf' and scan == 20")
    run.summary            # point x row keys x metric: n, mean, std, ci_low, ci_high
    run.point_params(3)    # every parameter of sweep point 3, defaults included

Column names of swept parameters keep their dots (``clutter.mean``); in pandas ``query``
write them in backticks: ``run.trials.query("`clutter.mean` == 5")``.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import pandas as pd
import yaml

from trackfuse import experiments
from trackfuse.experiments.base import Experiment
from trackfuse.results import CONFIG, MANIFEST, SUMMARY, TRIALS
from trackfuse.sweep import expand

TIMING_SUMMARY = "timings_summary.csv"


class RunFolderError(ValueError):
    """A folder that is not a complete, readable run; ``str(err)`` is one line."""


@dataclass
class RunData:
    """A complete run folder, read (frames load on first use)."""

    path: Path
    config: dict[str, Any]
    manifest: dict[str, Any]

    @cached_property
    def experiment(self) -> Experiment:
        """The experiment that produced the run (imported on first use)."""
        try:
            return experiments.get(str(self.config["experiment"]))
        except experiments.UnknownExperiment as err:
            raise RunFolderError(f"{self.path}: unknown experiment "
                                 f"{self.config['experiment']!r}: {err}") from None

    @cached_property
    def trials(self) -> pd.DataFrame:
        """``trials.csv``: one row per point, trial and row key."""
        return _read_csv(self.path / TRIALS)

    @cached_property
    def summary(self) -> pd.DataFrame:
        """``summary.csv`` with the timing summary appended (metrics ``*_time_s``)."""
        frames = [_read_csv(self.path / SUMMARY)]
        if (self.path / TIMING_SUMMARY).exists():
            frames.append(_read_csv(self.path / TIMING_SUMMARY))
        return pd.concat(frames, ignore_index=True)

    @property
    def params(self) -> dict[str, Any]:
        """The resolved parameters shared by every point (swept keys at their config value)."""
        return dict(self.config["params"])

    @property
    def sweep(self) -> dict[str, list[Any]]:
        return dict(self.config.get("sweep") or {})

    @cached_property
    def points(self) -> list[dict[str, Any]]:
        """Every sweep point's full parameters, in point order (the config's own expansion)."""
        return [{**self.params, **p.values}
                for p in expand(self.sweep, self.config.get("sweep_mode", "grid"))]

    def point_params(self, point: int) -> dict[str, Any]:
        """Every parameter of sweep point ``point``, with its schema types."""
        return self.points[point]


def _read_csv(path: Path) -> pd.DataFrame:
    try:
        return pd.read_csv(path, low_memory=False)
    except FileNotFoundError:
        raise RunFolderError(f"{path}: missing") from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as err:
        raise RunFolderError(f"{path}: unreadable ({type(err).__name__})") from None


def load(path: str | Path, require_complete: bool = True) -> RunData:
    """Open the run folder ``path`` (raise :class:`RunFolderError` with one line if not)."""
    path = Path(path)
    if not path.is_dir():
        raise RunFolderError(f"{path}: not a run folder (not a directory)")
    try:
        manifest = json.loads((path / MANIFEST).read_text(encoding="utf-8"))
        config = yaml.safe_load((path / CONFIG).read_text(encoding="utf-8"))
    except FileNotFoundError as err:
        raise RunFolderError(f"{path}: not a run folder (no {Path(err.filename).name})") \
            from None
    except (OSError, UnicodeDecodeError, ValueError, yaml.YAMLError) as err:
        raise RunFolderError(f"{path}: unreadable run folder ({type(err).__name__})") from None
    if not isinstance(manifest, dict) or not isinstance(config, dict) \
            or "experiment" not in config or not isinstance(config.get("params"), dict):
        raise RunFolderError(f"{path}: manifest.json or config.yaml is not a trackfuse run's")
    if require_complete and manifest.get("status") != "complete":
        raise RunFolderError(f"{path}: run is {manifest.get('status')}, not complete; run the "
                             "same `trackfuse run` command again to finish it")
    return RunData(path, config, manifest)
