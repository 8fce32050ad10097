"""Experiments defined for the runner's tests only (never shipped in the package)."""

from __future__ import annotations

import dataclasses

import numpy as np

from trackfuse.experiments import register
from trackfuse.experiments.base import Experiment, FigureSpec, Metric, Param
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
    worker (``os._exit``) once per marker file: a worker dying mid-batch."""
    import multiprocessing
    import os

    if multiprocessing.parent_process() is not None:
        try:
            os.close(os.open(params["marker"], os.O_CREAT | os.O_EXCL))
        except FileExistsError:
            pass
        else:
            os._exit(1)
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
    """Kill the worker process (``os._exit``) on every trial run in one: a pool that cannot
    finish anything."""
    import multiprocessing
    import os

    if multiprocessing.parent_process() is not None:
        os._exit(1)
    return [{"algorithm": "a", "value": float(streams.point.normal())}]


DOOMED = register(Experiment(
    name="toy_doomed",
    title="Every worker dies on its first trial",
    params=(),
    run_trial=doomed_trial,
    batch_size=5,
))


UNRULY_WAYS = ("exit", "interrupt", "none", "empty", "not_rows", "raise", "no_metric",
               "no_row_key", "param_column", "text_metric")


def unruly_trial(params, streams: TrialStreams) -> list[dict]:
    """About one trial in ``every`` misbehaves the way ``how`` names: ``sys.exit(0)``, raise
    ``KeyboardInterrupt``, return ``None``, ``[]``, a list of non-dicts, rows that lack the
    declared metric (a misspelt key) or the row key, carry a parameter's name as a column
    or a word as a metric, or raise an error.
    Which trials misbehave depends on the point stream only (the same on every executor)."""
    import sys

    value = float(streams.common.normal())
    if streams.point.integers(params["every"]) == 0:
        how = params["how"]
        if how == "exit":
            sys.exit(0)
        if how == "interrupt":
            raise KeyboardInterrupt
        if how == "raise":
            raise RuntimeError("synthetic failure")
        return {"none": None, "empty": [], "not_rows": ["a", "b"],
                "no_metric": [{"algorithm": "a", "valeu": value}],
                "no_row_key": [{"method": "a", "value": value}],
                "param_column": [{"algorithm": "a", "value": value, "every": 1.0}],
                "text_metric": [{"algorithm": "a", "value": "many"}]}[how]
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
