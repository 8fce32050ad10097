"""A finished run as its reports read it: the run folder's files (:mod:`trackfuse.runfiles`)
and the experiment that produced it.

The one reader of saved results: ``trackfuse plot``, ``trackfuse compare``, the reports and
users' notebooks go through :func:`load` (``trackfuse.load``; usage:
``docs/outputs.md#loading-results``). The experiment is looked up only when asked for, so
reading the frames of a run never imports its experiment; a plugin experiment
(``package.module:ATTR``) is imported as running it did.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import pandas as pd

from trackfuse import experiments
from trackfuse.experiments.base import Experiment
from trackfuse.results import RunFolderError
from trackfuse.rowformat import FAILED_ROW
from trackfuse.runfiles import RunFiles, read_run
from trackfuse.seeding import draw_points
from trackfuse.sweep import expand


@dataclass
class RunData(RunFiles):
    """A run folder, read, with the experiment that produced it."""

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
        folder = self.manifest.plugin_folder
        if folder is None or not Path(folder).is_dir():
            raise RunFolderError(f"{self.path}: {err}") from None
        experiments.add_plugin_folder(folder)
        try:
            return experiments.get(name)
        except experiments.PluginError as again:
            raise RunFolderError(f"{self.path}: {again} (also looked in {folder}, where "
                                 "the run found it)") from None

    @cached_property
    def draw_points(self) -> list[int]:
        """The draw point of every sweep point (:func:`~trackfuse.seeding.draw_points`):
        ``trial_streams(seed, draw_points[p], t)`` re-simulates trial ``t`` of point ``p``.
        As the manifest recorded them, else from the experiment's current ``draws`` flags."""
        if self.manifest.draw_points is not None:
            return list(self.manifest.draw_points)
        points = expand(self.sweep, self.config.get("sweep_mode", "grid"))
        return draw_points(points, self.experiment.drawing)


def load(path: str | Path, require_complete: bool = True,
         experiment: Experiment | None = None) -> RunData:
    """Open the run folder ``path`` (:func:`trackfuse.runfiles.read_run`: one-line
    :class:`RunFolderError` if it cannot). ``experiment``: the object that produced the run
    (:attr:`RunData.given`), if the caller holds it."""
    files = read_run(path, require_complete)
    return RunData(files.path, files.config, files.manifest, experiment)


def succeeded_rows(trials: pd.DataFrame) -> pd.DataFrame:
    """The rows of ``trials`` (of ``trials.csv``) not left by a failed trial."""
    if "status" in trials:
        return trials[trials["status"].astype(str) != FAILED_ROW]
    return trials


def swept_keys(config: dict[str, Any]) -> list[str]:
    """The swept parameter keys of a resolved ``config``, in config order (each is a column
    of ``trials.csv`` and ``summary.csv``)."""
    return list(config.get("sweep") or {})
