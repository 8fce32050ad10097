"""Where batches run: in this process, a local forkserver process pool, or dask.

Every executor is an :class:`Executor` whose :meth:`~Executor.imap_unordered` yields results as
batches finish, keeping about twice as many batches submitted as there are workers (memory
stays flat). Results carry their (point, batch) identity, so completion order never reaches the
output files. A dead pool worker restarts the pool and its batches are resubmitted; dask
retries on its own; a scheduler file is checked here first (dask would wait forever for a
missing one). Details: docs/runner.md and docs/cluster.md.
"""

from __future__ import annotations

import json
import logging
import multiprocessing
import os
import pickle
import signal
import socket
import threading
import warnings
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from itertools import islice
from pathlib import Path
from typing import Any, Protocol

from trackfuse.child_processes import ctrl_c_held, setup_child

KINDS = ("serial", "process", "dask")
MAX_POOL_RESTARTS = 3
MAX_SCHEDULER_FILE_BYTES = 1_000_000
PROBE_TIMEOUT_S = 5.0
_END = object()


class ExecutorError(RuntimeError):
    """The executor cannot start (missing extra, unreachable scheduler...)."""


class Executor(Protocol):
    """Runs a function on tasks somewhere; ``kind`` names where (:data:`KINDS`), for the
    manifest; ``workers`` is how many run at once."""

    kind: str
    workers: int

    def imap_unordered(self, fn: Callable, tasks: Iterable) -> Iterator[Any]:
        """``fn(task)`` of every task, in the order they finish."""

    def loading(self) -> bool:
        """Whether the workers are still loading the experiment's code (for the progress
        line; ``False`` where not known)."""

    def close(self, abort: bool = False) -> None:
        """Release the workers; ``abort``: at once, the run stops (an interrupt, an error)."""


def default_workers() -> int:
    """Cores available to this process."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


class SerialExecutor:
    """Run every batch in this process, in order."""

    kind = "serial"
    workers = 1

    def imap_unordered(self, fn: Callable, tasks: Iterable) -> Iterator[Any]:
        for task in tasks:
            yield fn(task)

    def loading(self) -> bool:
        """Whether the workers are still loading the experiment's code: not known here."""
        return False

    def close(self, abort: bool = False) -> None:
        pass


BLAS_THREAD_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS")
#: Warning filter (``-W`` syntax) for the resource tracker's "leaked semaphore objects"
#: warning, printed after a ``kill -9`` of the run when the tracker cleans them up.
TRACKER_LEAK_WARNING = "ignore:resource_tracker:UserWarning"


#: Said on a Ctrl-C while the first batch is handed to the pool, which waits for the fork
#: server to load the experiment's code (seconds on a first run, which compiles it).
STOPPING_WHEN_LOADED = "stopping once the worker processes have loaded the experiment's code"


def _imported_from_working_directory() -> bool:
    """Whether this process imported trackfuse from the working directory's ``trackfuse``."""
    home = Path(__file__).resolve().parents[1]
    return home == Path.cwd().resolve()


def _start_forkserver_single_threaded() -> None:
    """Start the fork server with one BLAS thread per worker (no oversubscription of cores).

    The server is started once per process and every worker forks from it, so the
    environment it starts with is what the workers' numpy sees.
    """
    from multiprocessing import forkserver

    saved = {k: os.environ.get(k) for k in (*BLAS_THREAD_VARS, "PYTHONSAFEPATH", "PYTHONWARNINGS")}
    for key in BLAS_THREAD_VARS:
        os.environ.setdefault(key, "1")
    # the resource tracker started with the server outlives a ``kill -9`` of this process,
    # cleans up the pool's semaphores and warned about them on the user's terminal
    os.environ["PYTHONWARNINGS"] = ",".join(
        filter(None, (saved["PYTHONWARNINGS"], TRACKER_LEAK_WARNING)))
    if not _imported_from_working_directory():
        # the server runs ``python -c``, whose module path starts with the working directory
        # (Python 3.11 drops the path it is given): a ``trackfuse`` folder there, such as
        # another version's source, would be what the workers import
        os.environ["PYTHONSAFEPATH"] = "1"
    # started with Ctrl-C ignored (inherited through exec), so a Ctrl-C while it loads its
    # modules prints no traceback of its own: the main process stops the run
    main_thread = threading.current_thread() is threading.main_thread()
    handler = signal.signal(signal.SIGINT, signal.SIG_IGN) if main_thread else None
    try:
        forkserver.ensure_running()
    finally:
        if main_thread:
            signal.signal(signal.SIGINT, handler)
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def start_fork_server(preload: Sequence[str] = ()) -> None:
    """Start the fork server that process pools fork their workers from, unless it runs.

    It imports :mod:`trackfuse.batch` and ``preload`` (then freezes them:
    :mod:`trackfuse.forkserver_freeze`) in its own process, about a second for the twin-sensor
    kernel; the caller goes on meanwhile. The command line starts it as soon as it knows the
    experiment, so that this overlaps its own work before the first batch.
    """
    ctx = multiprocessing.get_context("forkserver")
    # heard only by a fork server not yet running (the first of a process)
    ctx.set_forkserver_preload(["trackfuse.batch", *preload, "trackfuse.forkserver_freeze"])
    _start_forkserver_single_threaded()


class ProcessExecutor:
    """A local process pool with a bounded number of batches in flight."""

    kind = "process"

    def __init__(self, workers: int, preload: Sequence[str] = ()):
        self.workers = workers
        start_fork_server(preload)
        self._ctx = multiprocessing.get_context("forkserver")
        # this process's children before the pool: an aborted pool ends only its own
        self._other_children = set(multiprocessing.active_children())
        self._pool = self._new_pool()
        self._forked = False

    def _new_pool(self) -> ProcessPoolExecutor:
        """A pool that starts all its workers at its first ``submit``, before its manager
        thread runs: started one per ``submit`` instead (Python 3.11 does so under the fork
        server), a worker can start while the manager thread, a worker having died, iterates
        over the workers or has closed their queue, which prints a traceback (CPython
        bpo-43498)."""
        pool = ProcessPoolExecutor(self.workers, mp_context=self._ctx,
                                   initializer=setup_child, initargs=(os.getpid(),))
        pool._safe_to_dynamically_spawn_children = False
        return pool

    def loading(self) -> bool:
        """Whether the fork server is still loading (on a first run, compiling) the
        experiment's code: the pool's first ``submit`` forks the workers, which returns only
        once the fork server has loaded it."""
        return not self._forked

    def imap_unordered(self, fn: Callable, tasks: Iterable) -> Iterator[Any]:
        """``fn(task)`` of every task as batches finish. A dead worker breaks the pool: it is
        replaced and the batches it held are submitted again (at most
        :data:`MAX_POOL_RESTARTS` times). A result asking for its worker to be replaced
        (``renew_worker``) stops submission until the batches in flight are done, then every
        worker is replaced."""
        todo = _Todo(tasks)
        pending: dict[Future, Any] = {}
        restarts = 0
        renew = False
        while True:
            try:
                if not renew:
                    self._submit(fn, todo, pending)
                if pending:
                    renew = (yield from self._finished(pending, todo)) or renew
                elif renew:
                    self._renew_workers()
                    renew = False
                else:
                    return
            except BrokenProcessPool:
                restarts += 1
                if restarts > MAX_POOL_RESTARTS:
                    self._pool.shutdown(wait=True, cancel_futures=True)  # see _restart
                    raise ExecutorError(
                        f"the worker processes died {restarts} times (out of memory, or "
                        "killed?); the batches they finished are saved: run the same command "
                        "to resume, or add --executor serial to see the failure in this "
                        "process") from None
                todo.again(pending.values())
                pending.clear()
                self._restart()

    def _submit(self, fn: Callable, todo: _Todo, pending: dict[Future, Any]) -> None:
        """Submit tasks until ``2 * workers + 1`` are in flight or none is left; a task the
        broken pool refuses goes back to ``todo`` (and the :class:`BrokenProcessPool` on)."""
        while len(pending) < 2 * self.workers + 1 and (task := todo.next()) is not _END:
            try:
                with ctrl_c_held(None if self._forked else STOPPING_WHEN_LOADED):
                    pending[self._pool.submit(fn, task)] = task
            except BrokenProcessPool:
                todo.again([task])
                raise
            self._forked = True

    @staticmethod
    def _finished(pending: dict[Future, Any], todo: _Todo) -> Iterator[Any]:
        """Yield the results of the batches that finish next; return whether one asked for
        its worker to be replaced. Batches a dead worker broke go back to ``todo``, then a
        :class:`BrokenProcessPool` is raised."""
        done, _ = wait(pending, return_when=FIRST_COMPLETED)
        renew = broken = False
        for future in done:
            task = pending.pop(future)
            if isinstance(future.exception(), BrokenProcessPool):
                todo.again([task])
                broken = True
                continue
            result = future.result()
            renew = renew or getattr(result, "renew_worker", False)
            yield result
        if broken:
            raise BrokenProcessPool("a worker process died")
        return renew

    def _restart(self) -> None:
        """A worker died: replace the pool (unfinished batches are resubmitted by the caller).
        The broken pool's manager thread ends its workers itself; waiting for it to finish
        keeps its queue's feeder thread from writing to a pipe already closed."""
        self._pool.shutdown(wait=True, cancel_futures=True)
        self._pool = self._new_pool()

    def _renew_workers(self) -> None:
        """Replace the idle pool's workers with fresh ones: a trial was interrupted at its
        time limit in one of them, wherever it was (a lock held, a module half set up)."""
        self._end_workers()
        self._pool = self._new_pool()

    def _end_workers(self) -> None:
        """Shut the pool down and end its workers at once (no other child process)."""
        self._pool.shutdown(wait=False, cancel_futures=True)
        for process in set(multiprocessing.active_children()) - self._other_children:
            process.terminate()
            process.join()

    def close(self, abort: bool = False) -> None:
        """Shut the pool down once its workers are idle; with ``abort`` (the run stops on an
        interrupt or an error) end them at once instead: their batches are lost anyway, and
        a worker caught while the pool hands it work can wait for it forever, so that
        Python's exit, which waits for every child process, would never come."""
        if not abort:
            self._pool.shutdown(wait=True, cancel_futures=True)
            return
        self._end_workers()


class _Todo:
    """Tasks still to submit: those a broken pool handed back first, then new ones."""

    def __init__(self, tasks: Iterable):
        self._new, self._again = iter(tasks), []

    def next(self) -> Any:
        """The next task, or ``_END``."""
        return self._again.pop() if self._again else next(self._new, _END)

    def again(self, tasks: Iterable) -> None:
        self._again.extend(tasks)


class DaskExecutor:
    """Batches on a dask.distributed cluster (existing scheduler or a LocalCluster)."""

    kind = "dask"

    def __init__(self, workers: int, address: str | None = None,
                 scheduler_file: str | None = None):
        try:
            from distributed import Client, LocalCluster
        except ImportError:
            raise ExecutorError("the dask executor needs the dask extra: "
                                "pip install 'trackfuse[dask]'") from None
        self._cluster = None
        if scheduler_file:
            address = scheduler_address(scheduler_file)
        if address:
            _probe(address)
        try:
            if address:
                self._client = Client(address=address, timeout="20s")
            else:
                # its log lines (a worker restarted, a task failed) are said in one line
                # by imap_unordered, or not at all; its HTTP server takes another port if
                # 8787 is taken, with a warning that is no business of the run
                with warnings.catch_warnings():
                    warnings.filterwarnings("ignore", "Port .* is already in use")
                    self._cluster = LocalCluster(n_workers=workers, threads_per_worker=1,
                                                 processes=True, dashboard_address=None,
                                                 silence_logs=logging.CRITICAL)
                self._client = Client(self._cluster)
            info = self._client.scheduler_info()
        except Exception as err:  # noqa: BLE001 - dask raises many kinds; one line for all
            target = address or "a LocalCluster"
            text = " ".join(str(err).split())[:200] or type(err).__name__
            raise ExecutorError(f"cannot connect to {target}: {text}") from None
        self.workers = max(1, sum(w.get("nthreads", 1) for w in info["workers"].values()))

    def loading(self) -> bool:
        """Whether the workers are still loading the experiment's code: not known here."""
        return False

    def imap_unordered(self, fn: Callable, tasks: Iterable) -> Iterator[Any]:
        from distributed import as_completed

        tasks = iter(tasks)
        first = [self._client.submit(fn, t, pure=False)
                 for t in islice(tasks, 2 * self.workers + 1)]
        stream = as_completed(first)
        for future in stream:
            for task in islice(tasks, 1):
                stream.add(self._client.submit(fn, task, pure=False))
            yield _result(future)
            future.release()

    def worker_environments(self, probe: Callable[[], dict[str, Any]]) -> dict[str, Any]:
        """``{worker address: probe()}`` for every worker connected now (each computes its
        own in its own installation)."""
        return self._client.run(probe)

    def close(self, abort: bool = False) -> None:
        self._client.close()
        if self._cluster is not None:
            self._cluster.close()


def _result(future: Any) -> Any:
    """A dask future's result; the workers dying on its batch as often as the scheduler
    allows (``distributed.scheduler.allowed-failures``) said in one line, as the process
    pool says it (a ``KilledWorker`` traceback)."""
    from distributed import KilledWorker

    try:
        return future.result()
    except KilledWorker:
        raise ExecutorError(
            "dask workers died each time they ran one batch (out of memory, or killed?); the "
            "batches they finished are saved: run the same command to resume, or add "
            "--executor serial to see the failure in this process") from None


def _probe(address: str) -> None:
    """Fail at once if a ``tcp://host:port`` scheduler refuses connections (dask itself
    retries for its whole timeout); other protocols are left to dask."""
    scheme, _, rest = address.partition("://")
    host, _, port = rest.rpartition(":")
    if scheme != "tcp" or not port.isdigit():
        return
    try:
        socket.create_connection((host.strip("[]"), int(port)), PROBE_TIMEOUT_S).close()
    except OSError as err:
        raise ExecutorError(f"cannot connect to {address}: {err.strerror or err}") from None


def scheduler_address(path: str) -> str:
    """The address in a dask scheduler file, or :class:`ExecutorError` in one line."""
    where = f"--scheduler-file {path}"
    try:
        with open(path, "rb") as fh:
            data = fh.read(MAX_SCHEDULER_FILE_BYTES + 1)
    except FileNotFoundError:
        raise ExecutorError(f"{where}: no such file (start the scheduler with "
                            "`dask scheduler --scheduler-file ...` first)") from None
    except OSError as err:
        raise ExecutorError(f"{where}: cannot read ({err.strerror})") from None
    try:
        info = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError, RecursionError):
        info = None
    if not isinstance(info, dict) or not isinstance(info.get("address"), str) \
            or "://" not in info["address"]:
        raise ExecutorError(f"{where}: not a dask scheduler file (no scheduler address)")
    return info["address"]


def unpicklable(experiment: Any) -> str | None:
    """Why the process pool's workers cannot be sent ``experiment`` (an
    :class:`~trackfuse.experiments.base.Experiment`), else ``None``: a ``lambda`` or a
    function defined inside another is pickled by name, which its module does not have
    (serial and dask, whose cloudpickle sends code by value, run it)."""
    try:
        pickle.dumps(experiment)
    except Exception as err:  # noqa: BLE001 - pickle raises many kinds; which field says it
        bad = [name for name in ("run_trial", "run_batch", "check")
               if not _pickles(getattr(experiment, name, None))]
        what = f"its {bad[0]}" if bad else "its declaration"
        return (f"{what} cannot be sent to the worker processes ({type(err).__name__}: a "
                "lambda or a function defined inside another function cannot be pickled); "
                "allowed: a function defined at the top level of its module, or "
                "--executor serial or dask")
    return None


def _pickles(value: Any) -> bool:
    try:
        pickle.dumps(value)
    except Exception:  # noqa: BLE001 - any failure to pickle
        return False
    return True


def make_executor(kind: str, workers: int, address: str | None = None,
                  scheduler_file: str | None = None, preload: Sequence[str] = ()):
    """Build the executor named ``kind`` (see :data:`KINDS`); a process pool's workers fork
    with the modules ``preload`` already imported."""
    if address or scheduler_file:
        kind = "dask"
    if kind == "serial" or (kind == "process" and workers <= 1):
        return SerialExecutor()
    if kind == "process":
        return ProcessExecutor(workers, preload)
    if kind == "dask":
        return DaskExecutor(workers, address, scheduler_file)
    raise ExecutorError(f"unknown executor {kind!r}; allowed: {', '.join(KINDS)}")
