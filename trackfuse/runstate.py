"""What state a run folder is in, decided in one place for ``trackfuse runs``, ``plot``,
``compare`` and ``run``.

The manifest records the run's own status (``running``, ``interrupted``, ``complete``) and
how many of its trials failed; the folder tells the rest. A run marked running whose
process has ended is :data:`STOPPED` (resumable); a complete run whose final files are
missing or differ from what its manifest records is :data:`DAMAGED`; a complete run has a
report when ``index.html`` and every file the manifest records the report wrote are there.
This module reads manifests and file sizes only (checksums when asked), so listing many
runs stays quick.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from trackfuse.manifest import Manifest
from trackfuse.results import INDEX_HTML, RunFolder, RunStatus
from trackfuse.runlock import held_by_a_live_process

#: A run whose manifest says running but whose process has ended (killed, or stopped by a
#: full disk): resumable by running the same command again.
STOPPED = "stopped"
#: A folder whose manifest cannot be read, or a complete run whose final files do not match
#: what its manifest records.
DAMAGED = "damaged"


@dataclass(frozen=True)
class RunState:
    """A run's state: ``status`` (a manifest status, :data:`STOPPED` or :data:`DAMAGED`),
    and for a complete run its failed trials and whether its report is all there;
    ``problem`` says what is damaged."""

    status: str
    failed: int = 0
    report: bool = False
    problem: str | None = None

    @property
    def complete(self) -> bool:
        return self.status == RunStatus.COMPLETE

    def __str__(self) -> str:
        """``complete``, ``complete, 2 failed, no report``, ``stopped``..."""
        if not self.complete:
            return self.status
        return ", ".join(["complete", *([f"{self.failed} failed"] if self.failed else []),
                          *([] if self.report else ["no report"])])


def has_report(path: Path, manifest: Manifest) -> bool:
    """Whether run folder ``path`` holds its whole report: ``index.html`` and every file in
    the manifest's :data:`REPORT_FILES` (a manifest from before it was recorded: the index
    alone)."""
    names = manifest.report_files or []
    return (path / INDEX_HTML).is_file() and all((path / n).is_file() for n in names)


def run_state(path: Path, manifest: Manifest, checksums: bool = False) -> RunState:
    """The state of run folder ``path`` with the manifest ``manifest``; ``checksums``
    compares the final files' checksums too, not only their sizes."""
    status = manifest.status  # one of the manifest's statuses (trackfuse.manifest)
    if status == RunStatus.RUNNING and not held_by_a_live_process(path):
        return RunState(STOPPED)
    if status != RunStatus.COMPLETE:
        return RunState(status)
    problem = RunFolder(path).check_final_files(manifest.files, checksums=checksums)
    if problem is not None:
        return RunState(DAMAGED, problem=problem)
    return RunState(status, manifest.trials_failed or 0, has_report(path, manifest))
