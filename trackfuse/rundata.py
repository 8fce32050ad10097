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

:func:`load` of a complete run first checks every final file against the size and SHA-256
that ``manifest.json`` recorded when the run finished, so a truncated or edited
``trials.csv`` is refused (one line) rather than plotted; a run that is not complete is
refused in the words of :func:`trackfuse.runstate.run_state` (``stopped`` after a kill).
Plotting a run of a plugin experiment (``package.module:ATTR``) imports that module, as
running it did.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import pandas as pd

from trackfuse import experiments
from trackfuse.experiments.base import Experiment
from trackfuse.regular_files import open_regular
from trackfuse.results import (
    CONFIG,
    FAILED_ROW,
    MANIFEST,
    SUMMARY,
    TIMING_SUMMARY,
    TIMINGS,
    RunFolder,
    RunFolderError,
    RunStatus,
)
from trackfuse.runstate import DAMAGED, STOPPED, run_state
from trackfuse.safe_yaml import YamlInputError, read_yaml_file
from trackfuse.seeding import draw_points
from trackfuse.store import parquet_problem, read_trials, trials_file
from trackfuse.sweep import expand


@dataclass
class RunData:
    """A run folder, read (frames load on first use): complete unless :func:`load` was
    told not to require it."""

    path: Path
    config: dict[str, Any]
    manifest: dict[str, Any]
    #: The experiment object that produced the run when the caller holds it (the harness);
    #: otherwise :attr:`experiment` looks the config's name up.
    given: Experiment | None = field(default=None, repr=False)

    @cached_property
    def experiment(self) -> Experiment:
        """The experiment that produced the run (imported on first use)."""
        if self.given is not None:
            return self.given
        name = str(self.config["experiment"])
        try:
            return experiments.get(name)
        except experiments.PluginError as err:
            return self._plugin_from_its_folder(name, err)
        except experiments.UnknownExperiment:
            raise RunFolderError(f"{self.path}: unknown experiment {name[:80]!r}; allowed: "
                                 + ", ".join(experiments.names())) from None

    def _plugin_from_its_folder(self, name: str, err: Exception) -> Experiment:
        """Plugin ``name`` imported from the folder the run recorded in its manifest
        (``plugin_folder``), which the caller's Python path lacks; else ``err``."""
        folder = self.manifest.get("plugin_folder")
        if not isinstance(folder, str) or not Path(folder).is_dir():
            raise RunFolderError(f"{self.path}: {err}") from None
        experiments.add_plugin_folder(folder)
        try:
            return experiments.get(name)
        except experiments.PluginError as again:
            raise RunFolderError(f"{self.path}: {again} (also looked in {folder}, where "
                                 "the run found it)") from None

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
        """``timings.csv``: the ``*_time_s`` measurements (per trial or per batch); empty
        when the run wrote none."""
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

    @cached_property
    def draw_points(self) -> list[int]:
        """The draw point of every sweep point, whose point stream its trials drew
        (:func:`~trackfuse.seeding.draw_points`): ``trial_streams(seed, draw_points[p], t)``
        re-simulates trial ``t`` of point ``p``. As the manifest recorded them; a run
        written before they were recorded gets them from the current code's
        :attr:`~trackfuse.experiments.base.Param.draws` flags."""
        recorded = self.manifest.get("draw_points")
        if isinstance(recorded, list) and all(isinstance(p, int) for p in recorded):
            return list(recorded)
        points = expand(self.sweep, self.config.get("sweep_mode", "grid"))
        return draw_points(points, self.experiment.drawing)


def succeeded_rows(trials: pd.DataFrame) -> pd.DataFrame:
    """The rows of ``trials`` (of ``trials.csv``) not left by a failed trial."""
    if "status" in trials:
        return trials[trials["status"].astype(str) != FAILED_ROW]
    return trials


def swept_keys(config: dict[str, Any]) -> list[str]:
    """The swept parameter keys of a resolved ``config``, in config order (each is a column
    of ``trials.csv`` and ``summary.csv``)."""
    return list(config.get("sweep") or {})


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


def load(path: str | Path, require_complete: bool = True,
         experiment: Experiment | None = None) -> RunData:
    """Open the run folder ``path`` (raise :class:`RunFolderError` with one line if not).

    With ``require_complete`` the run must be complete and its final files must match the
    sizes and checksums in its manifest. ``experiment``: the object that produced the run
    (:attr:`RunData.given`), if the caller holds it.
    """
    path = Path(path)
    manifest = RunFolder(path).read_manifest() if path.is_dir() else None
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
    return RunData(path, config, manifest, experiment)


def _not_a_run(path: Path) -> str:
    """Why ``path``, which holds no readable manifest, is no run folder (``plot`` and
    ``compare`` say the same)."""
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
