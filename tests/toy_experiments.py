"""Experiments defined for the runner's tests only (never shipped in the package)."""

from __future__ import annotations

import dataclasses
from fractions import Fraction

import numpy as np

from trackfuse.experiments import register
from trackfuse.experiments.base import Experiment, FigureSpec, Metric, Param
from trackfuse.rowtable import RowTable
from trackfuse.seeding import TrialStreams


def gaussian_trial(params, streams: TrialStreams) -> list[dict]:
    """Sample mean of ``n`` draws from N(mu, sigma^2), two 'algorithms' on the same data.

    The draws are standard normals from the common stream, scaled by the point's parameters
    (common random numbers); the synthetic failures come from the point-specific stream.
    """
    x = params["mu"] + params["sigma"] * streams.common.standard_normal(int(params["n"]))
    if params["fail_every"] and streams.point.integers(params["fail_every"]) == 0:
        raise FloatingPointError("synthetic divergence")
    return [
        {"algorithm": "mean", "estimate": float(x.mean()), "covered":
            int(abs(x.mean() - params["mu"]) < 1.96 * params["sigma"] / np.sqrt(len(x)))},
        {"algorithm": "median", "estimate": float(np.median(x)), "covered":
            int(abs(np.median(x) - params["mu"]) < 1.96 * params["sigma"] / np.sqrt(len(x)))},
    ]


GAUSSIAN_METRICS = (
    Metric("estimate", "m", "the estimate of mu", better=None),
    Metric("covered", "1", "the 95 % interval covers mu", binary=True, better="higher"),
)
GAUSSIAN_FIGURES = {"estimate": FigureSpec("mean estimate per algorithm with its 95 % t band",
                                          "Fig. 1")}


def gaussian_batch(params, streams) -> list[list[dict]]:
    return [gaussian_trial(params, s) for s in streams]


def cluttered_trial(params, streams: TrialStreams) -> list[dict]:
    """Clutter ``density * U`` (U from the point stream) plus noise from the common stream,
    times ``gain``: ``density`` changes what is simulated, ``gain`` only what is computed."""
    uniform, noise = float(streams.point.random()), float(streams.common.normal())
    return [{"algorithm": "a", "uniform": uniform, "noise": noise,
             "estimate": params["gain"] * (params["density"] * uniform + noise)}]


CLUTTERED = register(Experiment(
    name="toy_cluttered",
    title="Clutter from the point stream, a setting that draws nothing",
    params=(Param("density", 1.0, "clutter scale", "1", low=0.0),
            Param("gain", 1.0, "applied to the data, not to what is drawn", "1",
                  draws=False)),
    run_trial=cluttered_trial,
    batch_size=4,
))


def trivial_trial(params, streams: TrialStreams) -> list[dict]:
    """One uniform draw: measures the runner's per-trial overhead."""
    return [{"algorithm": "a", "value": float(streams.point.random())}]


def burn_trial(params, streams: TrialStreams) -> list[dict]:
    """CPU-bound trial: a fixed amount of dense linear algebra."""
    a = streams.point.standard_normal((60, 60))
    total = 0.0
    for _ in range(int(params["work"])):
        total += float(np.linalg.eigvalsh(a @ a.T)[-1])
    return [{"algorithm": "burn", "value": total}]


GAUSSIAN = register(Experiment(
    name="toy_gaussian",
    title="Coverage of the sample mean",
    params=(
        Param("mu", 0.0, "true mean", "m"),
        Param("sigma", 1.0, "noise standard deviation", "m", low=0.0),
        Param("n", 10, "samples per trial", "", kind=int, low=1),
        Param("fail_every", 0, "make ~1/k trials raise (0 = never)", "", kind=int, low=0),
        Param("label", "a", "a string choice", "", kind=str, choices=("a", "b")),
        Param("p_d", 0.9, "a probability", "", low=0.0, high=1.0),
    ),
    run_trial=gaussian_trial,
    run_batch=gaussian_batch,
    metrics=GAUSSIAN_METRICS,
    report="toy_report",
    figures=GAUSSIAN_FIGURES,
    batch_size=7,
))

#: The Gaussian toy with a figure only a sweep over sigma can draw (toy_report says why not).
PICKY = register(dataclasses.replace(GAUSSIAN, name="toy_picky", figures={
    **GAUSSIAN_FIGURES, "estimate_vs_sigma": FigureSpec("mean estimate against sigma")}))

TRIVIAL = register(Experiment(
    name="toy_trivial",
    title="Almost no work per trial (runner overhead)",
    params=(Param("x", 1.0, "a number", ""),),
    run_trial=trivial_trial,
    batch_size=2000,
))

SLOW_LOADING = register(dataclasses.replace(
    TRIVIAL, name="toy_slow_loading", title="Workers that load slowly (a first run compiling)",
    preload=("slow_preload",)))

BURN = register(Experiment(
    name="toy_burn",
    title="CPU-bound trials (parallel speed-up)",
    params=(Param("work", 20, "eigen-decompositions per trial", "", kind=int, low=1),),
    run_trial=burn_trial,
    batch_size=4,
))


def crash_once_trial(params, streams: TrialStreams) -> list[dict]:
    """Like the Gaussian trial, but the first trial run in any worker process kills that
    worker (SIGKILL, as the out-of-memory killer does) once per marker file: a worker dying
    mid-batch."""
    import multiprocessing
    import os
    import signal

    if multiprocessing.parent_process() is not None:
        try:
            os.close(os.open(params["marker"], os.O_CREAT | os.O_EXCL))
        except FileExistsError:
            pass
        else:
            os.kill(os.getpid(), signal.SIGKILL)
    return [{"algorithm": "a", "value": float(streams.point.normal())}]


CRASH = register(Experiment(
    name="toy_crash",
    title="A worker dies once mid-batch",
    params=(Param("marker", "/nonexistent/marker", "file created when the worker dies", "",
                  kind=str),),
    run_trial=crash_once_trial,
    batch_size=5,
))


def doomed_trial(params, streams: TrialStreams) -> list[dict]:
    """Kill the worker process (SIGKILL) on every trial run in one: a pool that cannot
    finish anything."""
    import multiprocessing
    import os
    import signal

    if multiprocessing.parent_process() is not None:
        os.kill(os.getpid(), signal.SIGKILL)
    return [{"algorithm": "a", "value": float(streams.point.normal())}]


DOOMED = register(Experiment(
    name="toy_doomed",
    title="Every worker dies on its first trial",
    params=(),
    run_trial=doomed_trial,
    batch_size=5,
))


class _ShownFloat(float):
    """A float that prints as something else (a plugin's unit-carrying number, say)."""

    def __repr__(self) -> str:
        return "3 m"


class _FalseList(list):
    """A list whose truth cannot be told."""

    def __bool__(self) -> bool:
        raise RuntimeError("no truth here")


class _Unlisted(list):
    """A list whose items cannot be listed."""

    def __iter__(self):
        raise RuntimeError("no items")

    def __len__(self) -> int:
        raise RuntimeError("no items")


class _KeylessDict(dict):
    """A row dict whose keys cannot be listed by any means."""

    def __iter__(self):
        raise RuntimeError("no keys")

    def keys(self):
        raise RuntimeError("no keys")


class _Incomparable:
    """A result that cannot be compared with anything."""

    def __eq__(self, other: object) -> bool:
        raise RuntimeError("cannot compare")

    __hash__ = object.__hash__


class _HiddenDict(dict):
    """A row dict whose items cannot be listed."""

    def items(self):
        raise RuntimeError("no items")

    def keys(self):
        raise RuntimeError("no keys")


def _leave_a_thread() -> None:
    """Start a non-daemon thread that outlives the trial by far (a plugin's watchdog)."""
    import threading
    import time

    threading.Thread(target=time.sleep, args=(600,), name="plugin-leftover").start()


def _misbehave(how: str, value: float) -> list[dict] | object:
    """What a trial that misbehaves the way ``how`` names does or returns (UNRULY_WAYS)."""
    import os
    import sys
    import time

    if how == "exit":
        sys.exit(0)
    if how == "os_exit":
        os._exit(0)
    if how == "interrupt":
        raise KeyboardInterrupt
    if how == "raise":
        raise RuntimeError("synthetic failure")
    if how == "raise_surrogate":
        raise ValueError("bad \udcff byte")
    if how == "hang":  # a loop that never ends (a dask worker's thread is cut between sleeps)
        while True:
            time.sleep(0.01)
    if how == "thread":
        _leave_a_thread()
        return [{"algorithm": "a", "value": value}]
    return {"none": None, "empty": [], "not_rows": ["a", "b"],
            "no_metric": [{"algorithm": "a", "valeu": value}],
            "no_row_key": [{"method": "a", "value": value}],
            "param_column": [{"algorithm": "a", "value": value, "every": 1.0}],
            "status_column": [{"algorithm": "a", "value": value, "status": "failed",
                               "error": "fake"}],
            "trial_column": [{"algorithm": "a", "value": value, "trial": 99}],
            "text_metric": [{"algorithm": "a", "value": "many"}],
            "complex_metric": [{"algorithm": "a", "value": np.complex128(value)}],
            "float_subclass": [{"algorithm": "a", "value": _ShownFloat(value)}],
            "object_metric": [{"algorithm": "a", "value": Fraction(1, 3)}],
            "duplicate_rows": [{"algorithm": "a", "value": value},
                               {"algorithm": "a", "value": value}],
            "non_str_key": [{"algorithm": "a", "value": value, 7: 1.0}],
            "bool_raises": _FalseList([{"algorithm": "a", "value": value}]),
            "eq_raises": _Incomparable(),
            "items_raise": [_HiddenDict(algorithm="a", value=value)],
            "iter_raises": _Unlisted([{"algorithm": "a", "value": value}]),
            "row_iter_raises": [_KeylessDict(algorithm="a", value=value)],
            "surrogate": [{"algorithm": "\ud800", "value": value}],
            }[how]


#: Every way an unruly trial can misbehave (its ``how``).
UNRULY_WAYS = ("exit", "os_exit", "interrupt", "raise", "raise_surrogate", "hang", "thread",
               "none", "empty", "not_rows", "no_metric", "no_row_key", "param_column",
               "status_column", "trial_column", "text_metric", "complex_metric",
               "float_subclass", "object_metric", "duplicate_rows", "non_str_key",
               "bool_raises", "iter_raises", "eq_raises", "items_raise", "row_iter_raises",
               "surrogate")


def unruly_trial(params, streams: TrialStreams) -> list[dict]:
    """About one trial in ``every`` misbehaves the way ``how`` names (:func:`_misbehave`).
    Which trials misbehave depends on the point stream only (the same on every executor)."""
    value = float(streams.common.normal())
    if streams.point.integers(params["every"]) == 0:
        return _misbehave(params["how"], value)
    return [{"algorithm": "a", "value": value}]


UNRULY = register(Experiment(
    name="toy_unruly",
    title="Trials that exit, interrupt or return garbage",
    params=(Param("how", "exit", "how the bad trials misbehave", "", kind=str,
                  choices=UNRULY_WAYS),
            Param("every", 4, "about one trial in this many misbehaves", "", kind=int, low=1)),
    run_trial=unruly_trial,
    metrics=(Metric("value", "1", "the trial's normal draw"),),
    batch_size=5,
))

TABLE_WAYS = ("complex_metric", "text_metric", "object_metric", "duplicate_rows",
              "short_timings", "surrogate", "status_column")


def unruly_table_batch(params, streams) -> RowTable:
    """A batch of one row per trial as a RowTable; in the trials where the point stream
    says so (as in :func:`unruly_trial`), a value misbehaves the way ``how`` names (a
    column of other values, a second row, timings of two lengths)."""
    how, n = params["how"], len(streams)
    bad = np.array([s.point.integers(params["every"]) == 0 for s in streams])
    value = np.array([s.common.normal() for s in streams])
    trial = np.arange(n)
    algorithm = np.array(["a"] * n, dtype=object)
    columns = {"algorithm": algorithm, "value": value}
    timings = {"algorithm": np.array(["a"]), "cpu_time_s": np.array([0.5])}
    if how == "complex_metric":
        columns["value"] = np.where(bad, value + 1j, value)
    elif how in ("text_metric", "object_metric"):
        odd = "many" if how == "text_metric" else Fraction(1, 3)
        columns["value"] = np.array([odd if b else v for b, v in zip(bad, value, strict=True)],
                                    dtype=object)
    elif how == "surrogate":
        algorithm[bad] = "\ud800"
    elif how == "status_column":
        columns["status"] = np.where(bad, "failed", "")
    elif how == "short_timings":
        timings["cpu_time_s"] = np.array([0.5, 0.25])
    elif how == "duplicate_rows":
        trial = np.repeat(trial, np.where(bad, 2, 1))
        columns = {k: np.repeat(v, np.where(bad, 2, 1)) for k, v in columns.items()}
    return RowTable(trial, columns, timings)


def unruly_table_trial(params, streams: TrialStreams) -> list[dict]:
    """One trial of :func:`unruly_table_batch`, as rows."""
    return unruly_table_batch(params, [streams])[0]


UNRULY_TABLE = register(Experiment(
    name="toy_unruly_table",
    title="A batch form whose RowTable holds bad values",
    params=(Param("how", "complex_metric", "what is wrong in the table", "", kind=str,
                  choices=TABLE_WAYS),
            Param("every", 4, "about one trial in this many misbehaves", "", kind=int, low=1)),
    run_trial=unruly_table_trial,
    run_batch=unruly_table_batch,
    metrics=(Metric("value", "1", "the trial's normal draw"),),
    batch_size=5,
))


def ctrl_c_in_exec_trial(params, streams: TrialStreams) -> list[dict]:
    """Ctrl-C pressed while the trial runs code made from a string, as building a dataclass
    or a namedtuple does: the ``KeyboardInterrupt`` leaves an ``exec``."""
    import os
    import signal

    exec("os.kill(os.getpid(), signal.SIGINT)", {"os": os, "signal": signal})
    return [{"algorithm": "a", "value": float(streams.point.random())}]


CTRL_C_IN_EXEC = register(Experiment(
    name="toy_ctrl_c_in_exec",
    title="Ctrl-C inside exec",
    params=(Param("x", 1.0, "a number", ""),),
    run_trial=ctrl_c_in_exec_trial,
))

MIX = np.linspace(-1.0, 1.0, 24).reshape(8, 3)


def projected_trial(params, streams: TrialStreams) -> list[dict]:
    """Eight standard normals projected on three fixed directions (one matrix-vector product)."""
    y = streams.common.standard_normal(8) @ MIX
    return [{"algorithm": "project", "y0": float(y[0]), "y1": float(y[1]), "y2": float(y[2])}]


def projected_batch(params, streams) -> list[list[dict]]:
    """The same as a single matrix product over the batch: BLAS may sum in another order, so
    the last bits may depend on how many trials share the batch (as in twin_sensor)."""
    x = np.stack([s.common.standard_normal(8) for s in streams])
    y = x @ MIX
    return [[{"algorithm": "project", "y0": float(r[0]), "y1": float(r[1]), "y2": float(r[2])}]
            for r in y]


PROJECTED = register(Experiment(
    name="toy_projected",
    title="A vectorized batch form (batched algebra)",
    params=(Param("scale", 1.0, "unused", ""),),
    run_trial=projected_trial,
    run_batch=projected_batch,
    batch_size=16,
))


def timed_trial(params, streams: TrialStreams) -> list[dict]:
    """The Gaussian trial plus a wall-time column (kept out of trials.csv by the runner)."""
    import time

    t0 = time.perf_counter()
    rows = gaussian_trial(params, streams)
    return [{**row, "estimate_time_s": time.perf_counter() - t0} for row in rows]


TIMED = register(Experiment(
    name="toy_timed",
    title="The Gaussian toy with timings",
    params=GAUSSIAN.params,
    run_trial=timed_trial,
    metrics=GAUSSIAN_METRICS,
    report="toy_report",
    figures=GAUSSIAN_FIGURES,
    batch_size=5,
))


def shifted_trial(params, streams: TrialStreams) -> list[dict]:
    """A miss of ``shift + N(0, 1)`` (m): a regression of known size for ``compare``."""
    return [{"algorithm": "a", "miss": params["shift"] + float(streams.common.normal())}]


SHIFTED = register(Experiment(
    name="toy_shifted",
    title="A metric shifted by a known amount",
    params=(Param("shift", 0.0, "added to every error", "m"),),
    run_trial=shifted_trial,
    metrics=(Metric("miss", "m", "a miss distance, lower is better", better="lower"),),
))


def global_numpy_trial(params, streams: TrialStreams) -> list[dict]:
    """Draws from numpy's global generator, which the docs forbid: the runner seeds it per
    trial, so even this is the same on every executor."""
    return [{"algorithm": "a", "value": float(np.random.normal())}]


GLOBAL_NUMPY = register(Experiment(
    name="toy_global_numpy",
    title="A trial that draws from np.random directly",
    params=(Param("x", 1.0, "a number", ""),),
    run_trial=global_numpy_trial,
    batch_size=3,
))


REPORT_WAYS = ("figures_exit", "figures_os_exit", "tables_exit", "tables_os_exit")

UNRULY_REPORT = register(Experiment(
    name="toy_unruly_report",
    title="A report whose figures() or tables() end the process",
    params=(Param("report_how", "tables_exit", "how the report misbehaves", "", kind=str,
                  choices=REPORT_WAYS, draws=False),),
    run_trial=trivial_trial,
    metrics=(Metric("value", "1", "a uniform draw"),),
    report="toy_unruly_report",
    figures={"values": FigureSpec("nothing")},
))


@dataclasses.dataclass(frozen=True)
class WorkerPid:
    """A result saying which worker process computed it, and whether to replace it."""

    pid: int
    renew_worker: bool


def worker_pid(renew: bool) -> WorkerPid:
    """The worker's process id (for tests of the pool's replacing its workers)."""
    import os

    return WorkerPid(os.getpid(), renew)
