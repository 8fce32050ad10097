"""Read a run folder's files (config, manifest, trials, summary, timings) as plain frames.

The disk-side reader: it needs no experiment registry, so any finished run can be read
without the code that produced it. :mod:`trackfuse.rundata` adds the experiment on top.
What :func:`read_run` checks: ``docs/outputs.md#loading-results``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import Any

import pandas as pd

from trackfuse.manifest import Manifest, read_manifest
from trackfuse.regular_files import open_regular
from trackfuse.results import (
    CONFIG,
    MANIFEST,
    SUMMARY,
    TIMING_SUMMARY,
    TIMINGS,
    RunFolderError,
    RunStatus,
)
from trackfuse.runstate import DAMAGED, STOPPED, run_state
from trackfuse.safe_yaml import YamlInputError, read_yaml_file
from trackfuse.store import parquet_problem, read_trials, trials_file
from trackfuse.sweep import expand


@dataclass
class RunFiles:
    """A run folder's files, read (frames load on first use)."""

    path: Path
    config: dict[str, Any]
    manifest: Manifest

    @cached_property
    def trials(self) -> pd.DataFrame:
        """``trials.csv`` (or ``trials.parquet``): one row per point, trial and row key."""
        path = trials_file(self.path)
        if path.suffix == ".csv":
            return _read_csv(path)
        try:
            return read_trials(path)
        except ImportError:
            raise RunFolderError(f"{path}: {parquet_problem()}") from None
        except (OSError, ValueError) as err:  # pyarrow's errors are either
            raise RunFolderError(f"{path}: unreadable ({type(err).__name__})") from None

    @cached_property
    def timings(self) -> pd.DataFrame:
        """``timings.csv`` (the ``*_time_s`` measurements); empty when the run wrote none."""
        if not (self.path / TIMINGS).exists():
            return pd.DataFrame()
        return _read_csv(self.path / TIMINGS)

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
        with open_regular(path) as fh:  # a FIFO in its place must not hang the reader
            return pd.read_csv(fh, low_memory=False)
    except FileNotFoundError:
        raise RunFolderError(f"{path}: missing") from None
    except OSError as err:
        raise RunFolderError(f"{path}: unreadable ({err.strerror or type(err).__name__})") \
            from None
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as err:
        raise RunFolderError(f"{path}: unreadable ({type(err).__name__})") from None


def read_run(path: str | Path, require_complete: bool = True) -> RunFiles:
    """Open the run folder ``path`` (raise :class:`RunFolderError` with one line if not).

    With ``require_complete`` the run must be complete and its final files must match the
    sizes and SHA-256 sums in its manifest."""
    path = Path(path)
    manifest = read_manifest(path) if path.is_dir() else None
    if manifest is None:
        raise RunFolderError(f"{path}: {_not_a_run(path)}; allowed: a run folder, "
                             "<out>/<config>/<run-id> (`trackfuse runs` lists them)")
    if require_complete:
        state = run_state(path, manifest, checksums=True)
        if state.status == DAMAGED:
            raise RunFolderError(f"{state.problem}; run the same `trackfuse run` command "
                                 "again to rebuild the final files (it recomputes what it "
                                 "must)")
        if not state.complete:
            raise RunFolderError(f"{path}: run is {state.status[:40]}, not complete; "
                                 + _NOT_COMPLETE.get(state.status, _FINISH))
    config = _read_config(path / CONFIG)
    if not isinstance(config, dict) or not isinstance(config.get("experiment"), str) \
            or not isinstance(config.get("params"), dict) or not _outputs_readable(config):
        raise RunFolderError(f"{path / CONFIG}: not a trackfuse run's config (no experiment "
                             "or params, or outputs not a mapping of figure names and "
                             "formats)")
    return RunFiles(path, config, manifest)


def _not_a_run(path: Path) -> str:
    """Why ``path``, which holds no readable manifest, is no run folder."""
    if not path.exists():
        return "no such file or folder"
    return f"not a run folder: no {MANIFEST}" if path.is_dir() else "not a run folder: a file"


_FINISH = "run the same `trackfuse run` command again to finish it"
#: What to do about a run that is not complete, by its state (others: :data:`_FINISH`).
_NOT_COMPLETE = {
    RunStatus.RUNNING: "another process is computing it: wait for it to finish",
    STOPPED: "its process ended before it finished (killed?): run the same `trackfuse run` "
             "command again to resume it",
}


def _outputs_readable(config: dict[str, Any]) -> bool:
    """Whether a saved config's ``outputs`` is what the report reads: a mapping whose
    ``figures`` is ``"all"`` or a list of names and whose ``formats`` is a list of names."""
    outputs = config.get("outputs") or {}
    if not isinstance(outputs, dict):
        return False
    figures, formats = outputs.get("figures", "all"), outputs.get("formats") or []
    return (figures == "all" or isinstance(figures, list)
            and all(isinstance(f, str) for f in figures)) \
        and isinstance(formats, list) and all(isinstance(f, str) for f in formats)


def _read_config(path: Path) -> Any:
    try:
        return read_yaml_file(path, regular_only=True)
    except FileNotFoundError:
        raise RunFolderError(f"{path}: missing") from None
    except OSError as err:
        raise RunFolderError(f"{path}: unreadable ({err.strerror or type(err).__name__})") \
            from None
    except YamlInputError as err:
        raise RunFolderError(f"{path}: unreadable ({err})"[:300]) from None
