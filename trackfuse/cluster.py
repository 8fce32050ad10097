"""Dask workers started through a batch system (SLURM, PBS) by dask-jobqueue.

``trackfuse run CONFIG --cluster slurm`` (or ``pbs``) starts a dask scheduler in the
``trackfuse`` process and submits batch jobs that each start dask workers connecting back
to it; the run's batches then go to those workers as on any dask cluster (the runner's dask
path: the workers' code and library versions are checked against the run id, results are
ordered by (point, batch), so the files are byte-identical to a serial run). The number of
jobs adapts between ``min_jobs`` and ``max_jobs`` to the work queued.

Settings come from the config's ``cluster`` section
(:class:`~trackfuse.cluster_settings.ClusterSettings`: ``queue``,
``account``, ``cores``, ``processes``, ``memory``, ``walltime``, ``min_jobs``,
``max_jobs``, ``job_extra_directives``, ``interface``), each falling back to dask's own
configuration (``jobqueue.slurm.*`` / ``jobqueue.pbs.*`` in ``~/.config/dask/jobqueue.yaml``)
when not given. The section is not part of the resolved config: where a run computes never
changes its numbers or its run id.

Walltime. A job that reaches its walltime is killed by the batch system with the workers in
it. Each worker is told to retire five minutes before its job's walltime (``--lifetime``,
:mod:`trackfuse.cluster_settings`, staggered, as dask-jobqueue advises), handing its queued
batches back, and
the adaptive cluster submits a new job; a batch whose worker dies anyway (killed, out of
memory) is run again on another worker by the scheduler (up to
``distributed.scheduler.allowed-failures`` times). A batch is a pure function of its task,
so a batch run twice gives the same bytes. ``--cluster local`` runs the same jobs as local
processes (dask-jobqueue's ``LocalCluster``): what the tests use.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from trackfuse.cluster_settings import CLUSTER_KINDS, ClusterSettings
from trackfuse.executors import DaskExecutor, ExecutorError


def _cluster_class(kind: str) -> type:
    try:
        import dask_jobqueue
        from dask_jobqueue.local import LocalCluster
    except ImportError:
        raise ExecutorError("--cluster needs the cluster extra: "
                            "pip install 'trackfuse[cluster]'") from None
    return {"slurm": dask_jobqueue.SLURMCluster, "pbs": dask_jobqueue.PBSCluster,
            "local": LocalCluster}[kind]


def job_script(kind: str, given: ClusterSettings, scheduler: str = "tcp://SCHEDULER:8786"
               ) -> str:
    """The job script ``--cluster kind`` submits, for a scheduler at ``scheduler``, made
    without starting one (dask-jobqueue's job class)."""
    job_class = _cluster_class(kind).job_cls
    return job_class(scheduler=scheduler, name="trackfuse-worker",
                     **given.job_kwargs(kind)).job_script()


class JobqueueExecutor(DaskExecutor):
    """The dask executor on an adaptive dask-jobqueue cluster (see the module docstring)."""

    def __init__(self, kind: str, given: ClusterSettings):
        if kind not in CLUSTER_KINDS:
            raise ExecutorError(f"--cluster: got {kind!r}; allowed: {', '.join(CLUSTER_KINDS)}")
        cluster_class = _cluster_class(kind)
        from distributed import Client
        self._cluster = None
        try:
            self._cluster = cluster_class(**given.job_kwargs(kind),
                                          scheduler_options={"dashboard_address": ":0"})
            self._cluster.adapt(minimum_jobs=given.min_jobs, maximum_jobs=given.max_jobs)
            self._client = Client(self._cluster)
        except Exception as err:  # noqa: BLE001 - dask-jobqueue raises many kinds
            if self._cluster is not None:
                self._cluster.close()
            text = " ".join(str(err).split())[:200] or type(err).__name__
            raise ExecutorError(f"--cluster {kind}: cannot start the cluster: {text}") from None
        per_job = self._cluster._dummy_job.worker_processes
        #: Batches kept in flight follow the most workers the cluster may reach.
        self.workers = max(1, given.max_jobs * per_job)
        self.kind_of_cluster = kind

    def worker_environments(self, probe: Callable[[], dict[str, Any]]) -> dict[str, Any]:
        """``{worker address: probe()}`` of the worker that runs ``probe`` as a task: an
        adaptive cluster may have no worker until work is queued (the task makes it submit
        a job, which a queue may hold a while: the run waits for it). Workers that join
        later are not checked, as on any dask cluster."""
        from distributed import get_worker

        def located() -> tuple[str, dict[str, Any]]:
            return get_worker().address, probe()

        address, environment = self._client.submit(located, pure=False).result()
        return {address: environment}
