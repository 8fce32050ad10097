"""The execution step: run a plan's batches on an :class:`~trackfuse.executors.Executor` and
store each finished batch as its parts, in whatever order they finish.

Where the batches run is a :class:`Placement` (what the command line asked for); the
executor it opens is serial, a process pool, dask, or a batch system's dask workers
(:mod:`trackfuse.cluster`). Dask workers import their own installation, so before any batch
is sent they are checked against the run id's code and library versions
(:func:`check_dask_workers`).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass
from functools import partial
from typing import Any

from trackfuse.batch import BatchResult, BatchTask, execute_batch
from trackfuse.cluster import JobqueueExecutor
from trackfuse.cluster_settings import ClusterSettings
from trackfuse.environment import environment_difference, worker_environment
from trackfuse.executors import DaskExecutor, Executor, ExecutorError, make_executor
from trackfuse.experiments.base import Experiment
from trackfuse.results import RunFolder


@dataclass(frozen=True)
class Placement:
    """Where a run's batches are to run: ``kind`` (:data:`~trackfuse.executors.KINDS`) on
    ``workers`` workers, or a dask scheduler (``scheduler`` address or ``scheduler_file``),
    or the jobs of batch system ``cluster`` (:data:`~trackfuse.cluster_settings.CLUSTER_KINDS`)."""

    kind: str = "process"
    workers: int = 1
    scheduler: str | None = None
    scheduler_file: str | None = None
    cluster: str | None = None

    @property
    def on_dask(self) -> bool:
        """Whether the batches run on dask workers (see :func:`make_executor`)."""
        return self.kind == "dask" or bool(self.scheduler or self.scheduler_file
                                           or self.cluster)

    @property
    def pooled(self) -> bool:
        """Whether the batches run in a local process pool (sent to it by pickle)."""
        return self.kind == "process" and self.workers > 1 and not self.on_dask

    def open(self, cluster_settings: ClusterSettings, preload: Iterable[str] = ()) -> Executor:
        """The executor; a process pool's workers fork with ``preload`` imported."""
        if self.cluster:
            return JobqueueExecutor(self.cluster, cluster_settings)
        return make_executor(self.kind, self.workers, self.scheduler, self.scheduler_file,
                             tuple(preload))


def check_dask_workers(executor: DaskExecutor, experiment: Experiment, code_digest: str,
                       libraries: Mapping[str, Any]) -> list[dict[str, Any]]:
    """Refuse (:class:`~trackfuse.executors.ExecutorError`) dask workers that would compute
    with other code or library versions than the run id names; return the CPUs
    (:func:`~trackfuse.environment.cpu`) of the workers. Workers that join later are not
    checked."""
    found = executor.worker_environments(partial(worker_environment, experiment))
    for address, environment in sorted(found.items()):
        if why := environment_difference(code_digest, dict(libraries), environment):
            raise ExecutorError(f"dask worker {address} {why}: install the same trackfuse "
                                "and libraries on every worker")
    return list({repr(e["cpu"]): e["cpu"] for e in found.values()}.values())


def stored_batches(executor: Executor, tasks: Iterable[BatchTask],
                   folder: RunFolder) -> Iterator[BatchResult]:
    """Run ``tasks`` on ``executor``; yield each batch's result once its parts are saved in
    ``folder`` (:meth:`~trackfuse.results.RunFolder.write_part`, checksummed)."""
    for result in executor.imap_unordered(execute_batch, tasks):
        folder.write_part(result.span, result.trials_csv, result.trial_rows,
                          result.timings_csv, result.timing_rows)
        yield result
