"""One batch of trials, run in a worker: seeds, the experiment's code, CSV text. Whatever a
trial raises or wrongly returns becomes one ``failed`` row; workers load this module, so it
imports no pandas, matplotlib or orchestration."""

from __future__ import annotations

import multiprocessing
import signal
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from trackfuse.coerce import one_line
from trackfuse.experiments.base import Experiment
from trackfuse.results import BatchSpan, rows_to_csv, split_timings
from trackfuse.rowformat import FAILED_ROW, TIME_SUFFIX
from trackfuse.rowtable import Constant, RowTable, columns_csv
from trackfuse.seeding import batch_streams, seed_numpy_global, trial_streams
from trackfuse.trial_guard import guarded, timeouts
from trackfuse.trial_rows import checked_rows, table_problem, table_suspect

#: Longest error text of a failed trial's row (characters): the record in ``trials.csv``
#: to diagnose the failure from, so longer than an error inside a message.
ERROR_CHARS = 500
_user_interrupt = threading.Event()
_sigint_watched = threading.Event()


@dataclass(frozen=True)
class BatchTask:
    """Everything a worker needs for one batch (picklable); ``trial_timeout`` in s or ``None``."""

    experiment: Experiment
    params: dict[str, Any]
    swept: dict[str, Any]
    seed: int
    span: BatchSpan
    draw_point: int
    trial_timeout: float | None = None


@dataclass(frozen=True)
class BatchResult:
    """A finished batch as CSV text, ready to store."""

    span: BatchSpan
    trials_csv: str
    trial_rows: int
    timings_csv: str
    timing_rows: int
    wall_s: float
    #: A trial of it was interrupted at its time limit: its worker is to be replaced.
    renew_worker: bool = False


def _on_sigint(signum: int, frame: object) -> None:
    _user_interrupt.set()
    raise KeyboardInterrupt


def _marking(handler: Callable[[int, object], None]) -> Callable[[int, object], None]:
    """``handler`` (the command line's SIGTERM), first marking the stop as the user's."""
    def mark_then_stop(signum: int, frame: object) -> None:
        _user_interrupt.set()
        handler(signum, frame)
    return mark_then_stop


@contextmanager
def watch_sigint() -> Iterator[None]:
    """Mark Ctrl-C and SIGTERM as the user's, unlike a trial's own ``KeyboardInterrupt``."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    _user_interrupt.clear()
    restore: dict[int, Any] = {}
    sigint = signal.getsignal(signal.SIGINT)
    if sigint is signal.default_int_handler:
        restore[signal.SIGINT] = sigint
        _sigint_watched.set()
        signal.signal(signal.SIGINT, _on_sigint)
    elif callable(sigint):  # a handler of the caller's (dask's, a notebook's) still marks
        restore[signal.SIGINT] = sigint
        _sigint_watched.set()
        signal.signal(signal.SIGINT, _marking(sigint))
    term = signal.getsignal(signal.SIGTERM)
    if callable(term):
        restore[signal.SIGTERM] = term
        signal.signal(signal.SIGTERM, _marking(term))
    try:
        yield
    finally:
        for signum, handler in restore.items():
            signal.signal(signum, handler)
        _sigint_watched.clear()


def _is_user_interrupt(err: BaseException) -> bool:
    """A ``KeyboardInterrupt`` that must stop the run rather than fail a trial."""
    if not isinstance(err, KeyboardInterrupt):
        return False
    if _user_interrupt.is_set():
        return True
    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        return False  # Ctrl-C cannot reach this process (a background job): the trial raised it
    in_main = threading.current_thread() is threading.main_thread() and \
        multiprocessing.parent_process() is None
    return in_main and not _sigint_watched.is_set()


def _failure(prefix: dict[str, Any], err: BaseException) -> dict[str, Any]:
    """The ``failed`` row of a trial that raised or returned ``err``, its text made valid UTF-8."""
    text = one_line(err, ERROR_CHARS).encode("utf-8", "backslashreplace").decode("utf-8")
    return {**prefix, "algorithm": "", "status": FAILED_ROW, "error": text}


def _table_trials(experiment: Experiment, table: RowTable, producer: str
                  ) -> RowTable | list[Any]:
    """``table`` if its columns pass, else each trial's rows or the error failing them all."""
    try:
        if problem := table_problem(experiment, table, producer):
            return [problem] * table.trials
        try:
            suspect = table_suspect(experiment, table)
        except Exception:  # noqa: BLE001 - a value whose str() raises: found trial by trial
            suspect = True
        return list(table) if suspect else table
    except Exception as err:  # noqa: BLE001 - the plugin's table cannot be read
        return [TypeError(f"{producer} returned a RowTable that cannot be read: "
                          f"{one_line(err)}")] * table.trials


def _one_trial(task: BatchTask, trial: int) -> Any:
    """What ``run_trial`` returns for ``trial``, or what it raised."""
    try:
        with guarded(task.trial_timeout):
            seed_numpy_global(task.seed, task.draw_point, trial)
            return task.experiment.run_trial(task.params,
                                             trial_streams(task.seed, task.draw_point, trial))
    except BaseException as err:  # noqa: BLE001 - recorded in the CSV, the run goes on
        if _is_user_interrupt(err):
            raise
        return err


@contextmanager
def _numpy_global_kept() -> Iterator[None]:
    """Restore numpy's global generator after the trials reseeded it."""
    state = np.random.get_state()
    try:
        yield
    finally:
        np.random.set_state(state)


def _run_trials(task: BatchTask, trials: range) -> tuple[Any, str]:
    """What the batch's trials returned and which function returned it: ``run_batch`` first; if it
    raises, times out or miscounts, each trial reruns on its own seed and limit."""
    if task.experiment.run_batch is not None:
        limit = task.trial_timeout and task.trial_timeout * len(trials)
        try:
            with guarded(limit):
                seed_numpy_global(task.seed, task.draw_point, trials[0])
                batch = task.experiment.run_batch(
                    task.params, batch_streams(task.seed, task.draw_point, trials))
            if isinstance(batch, RowTable):
                batch.check(len(trials))
            elif not isinstance(batch, list) or len(batch) != len(trials):
                raise TypeError("run_batch returned the wrong number of trials")
            return batch, "run_batch"
        except BaseException as err:  # noqa: BLE001 - isolate the failing trial(s) one by one
            if _is_user_interrupt(err):
                raise
    return [_one_trial(task, t) for t in trials], "run_trial"


def execute_batch(task: BatchTask) -> BatchResult:
    """Run one batch in a worker; failed trials become ``failed`` rows, a missing declared metric
    fails all, and a trial stopped at its limit asks for a new worker (``renew_worker``)."""
    before = timeouts()
    result = _execute(task)
    return replace(result, renew_worker=True) if timeouts() > before else result


def _execute(task: BatchTask) -> BatchResult:
    """:func:`execute_batch`, but for replacing the worker."""
    t0 = time.perf_counter()
    span = task.span
    trials = range(span.first, span.stop)
    with _numpy_global_kept():
        batch, producer = _run_trials(task, trials)
    if isinstance(batch, RowTable):
        batch = _table_trials(task.experiment, batch, producer)
        if isinstance(batch, RowTable):
            return _table_result(task, batch, t0)
    per_trial = [checked_rows(result, producer, task.experiment) for result in batch]
    rows: list[dict[str, Any]] = []
    for trial, result in zip(trials, per_trial, strict=True):
        prefix = {"point": span.point, "trial": trial, **task.swept}
        if isinstance(result, BaseException):
            rows.append(_failure(prefix, result))
        else:
            rows.extend({**prefix, **row} for row in result)
    keys = ["point", "trial", *task.swept, *task.experiment.row_keys]
    trial_rows, timing_rows = split_timings(rows, keys)
    return BatchResult(span, rows_to_csv(trial_rows), len(trial_rows), rows_to_csv(timing_rows),
                       len(timing_rows), time.perf_counter() - t0)


def _table_result(task: BatchTask, table: RowTable, t0: float) -> BatchResult:
    """CSV parts of a RowTable batch: the trial rows and one timings row per timing entry."""
    span = task.span
    swept = {k: Constant(v) for k, v in task.swept.items()}
    metrics = {k: v for k, v in table.columns.items() if not k.endswith(TIME_SUFFIX)}
    trials_csv = columns_csv({"point": Constant(span.point), "trial": span.first + table.trial,
                              **swept, **metrics}, table.rows)
    timed = len(next(iter(table.timings.values()), ()))
    timings_csv = columns_csv({"point": Constant(span.point), "trial": Constant(span.first),
                               "trials": Constant(span.trials), **swept, **table.timings},
                              timed) if timed else rows_to_csv([])
    return BatchResult(span, trials_csv, table.rows, timings_csv, timed,
                       time.perf_counter() - t0)


__all__ = ["BatchResult", "BatchTask", "execute_batch", "watch_sigint"]
