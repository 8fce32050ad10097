"""Dask workers started through SLURM or PBS by dask-jobqueue (``--cluster slurm|pbs``;
``local`` for tests): the run then goes as on any dask cluster. Settings, walltime and lost
batches: ``docs/cluster.md``."""

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
        """``{worker address: probe()}`` of the worker that runs ``probe`` as a task (an adaptive
        cluster submits a job for it); workers that join later are not checked."""
        from distributed import get_worker

        def located() -> tuple[str, dict[str, Any]]:
            return get_worker().address, probe()

        address, environment = self._client.submit(located, pure=False).result()
        return {address: environment}
