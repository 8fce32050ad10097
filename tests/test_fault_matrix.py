"""Fault x executor: every way a trial can misbehave, on every executor (issue 37).

A trial of a toy plugin misbehaves on request (``tests/toy_experiments.py``: ``how`` of
``toy_unruly`` for row dicts, of ``toy_unruly_table`` for a batch's RowTable). Each fault
must end as ``failed`` rows whose error says what went wrong, in a complete run whose
``trials.csv`` is the same on every executor. A new fault is one line of :data:`FAULTS`
(and, if the toy cannot do it yet, one entry of its ``_misbehave``).

A trial that calls ``os._exit`` or outlasts the run's time limit is a failed row too
(:mod:`trackfuse.trial_guard`); a thread left running, and a worker killed outright, have
tests of their own below: they need a subprocess.
"""

from __future__ import annotations

import json
import signal
from pathlib import Path

import pandas as pd
import pytest
from conftest import trackfuse

from trackfuse.config import build
from trackfuse.runner import Runner

pytestmark = pytest.mark.slow  # every fault on every executor, dask included

#: fault -> (toy experiment, its ``how``, text every failed row's error holds, or ``None``
#: for rows that are right however odd their container: they are kept[, config keys])
FAULTS = {
    "sys.exit": ("UNRULY", "exit", "SystemExit: 0"),
    "os._exit": ("UNRULY", "os_exit", "PluginExit: os._exit(0) called; the process was kept"),
    "hang": ("UNRULY", "hang", "TrialTimeout: the trial ran longer than the limit of 0.3 s",
             {"trial_timeout": 0.3}),
    "KeyboardInterrupt": ("UNRULY", "interrupt", "KeyboardInterrupt"),
    "raise": ("UNRULY", "raise", "RuntimeError: synthetic failure"),
    "raise lone surrogate": ("UNRULY", "raise_surrogate", "ValueError: bad \\udcff byte"),
    "None": ("UNRULY", "none", "run_trial returned NoneType"),
    "[]": ("UNRULY", "empty", "run_trial returned an empty list"),
    "non-dict rows": ("UNRULY", "not_rows", "run_trial returned list; expected a non-empty"),
    "no metric": ("UNRULY", "no_metric", "without the declared metric value; the rows have "
                                         "algorithm, valeu"),
    "no row key": ("UNRULY", "no_row_key", "without the row key algorithm; the rows have "
                                           "method, value"),
    "parameter column": ("UNRULY", "param_column", "named like a parameter or a runner "
                                                   "column (point, trial, status, error): every"),
    "status column": ("UNRULY", "status_column", "runner column (point, trial, status, "
                                                 "error): error, status"),
    "trial column": ("UNRULY", "trial_column", "runner column (point, trial, status, error): "
                                               "trial"),
    "word metric": ("UNRULY", "text_metric", "returned 'many' of type str for the metric value"),
    "complex metric": ("UNRULY", "complex_metric", "of type complex128 for the metric value"),
    "float subclass": ("UNRULY", "float_subclass", "3 m of type _ShownFloat for the metric"),
    "object metric": ("UNRULY", "object_metric", "Fraction(1, 3) of type Fraction for the metric"),
    "duplicate rows": ("UNRULY", "duplicate_rows", "two rows of one trial with algorithm=a"),
    "non-str key": ("UNRULY", "non_str_key", "column names that are not strings: 7"),
    "__bool__ raises": ("UNRULY", "bool_raises", None),
    "__iter__ raises": ("UNRULY", "iter_raises", "returned a _Unlisted that cannot be read: "
                                                 "RuntimeError: no items"),
    "__eq__ raises": ("UNRULY", "eq_raises", "run_trial returned _Incomparable; expected"),
    "items() raises": ("UNRULY", "items_raise", None),
    "row __iter__ raises": ("UNRULY", "row_iter_raises", "returned a list that cannot be "
                                                         "read: RuntimeError: no keys"),
    "lone surrogate": ("UNRULY", "surrogate", "not valid Unicode: '\\ud800'"),
    "table complex": ("UNRULY_TABLE", "complex_metric", "of type complex for the metric value"),
    "table word": ("UNRULY_TABLE", "text_metric", "'many' of type str for the metric value"),
    "table object": ("UNRULY_TABLE", "object_metric", "of type Fraction for the metric value"),
    "table duplicate": ("UNRULY_TABLE", "duplicate_rows", "two rows of one trial with "
                                                          "algorithm=a"),
    "table timings": ("UNRULY_TABLE", "short_timings", "timing columns differ in length "
                                                       "('algorithm' 1, 'cpu_time_s' 2)"),
    "table surrogate": ("UNRULY_TABLE", "surrogate", "not valid Unicode: '\\ud800'"),
    "table status": ("UNRULY_TABLE", "status_column", "runner column (point, trial, status, "
                                                      "error): status"),
}
TRIALS = 20
#: Faults also run on dask (each costs seconds there): the ones executors used to differ on.
ON_DASK = ("sys.exit", "os._exit", "hang", "KeyboardInterrupt", "lone surrogate",
           "table timings")


def _config(fault: str, seed: int = 3):
    experiment, how, _, *extra = FAULTS[fault]
    return build({"experiment": f"toy_experiments:{experiment}", "trials": TRIALS,
                  "seed": seed, "params": {"how": how}, **(extra[0] if extra else {})},
                 f"{how}.yaml")


def _run(fault: str, out: Path, **executor) -> Path:
    outcome = Runner(_config(fault), out, progress=False, plots=False, **executor).run()
    return outcome.folder


@pytest.fixture(scope="module")
def serial_runs(tmp_path_factory):
    """fault -> the run folder of its serial run (computed once, compared with the rest)."""
    runs: dict[str, Path] = {}

    def get(fault: str) -> Path:
        if fault not in runs:
            runs[fault] = _run(fault, tmp_path_factory.mktemp("serial"), executor="serial")
        return runs[fault]
    return get


def _check_failed_rows(folder: Path, expected: str | None) -> None:
    trials = pd.read_csv(folder / "trials.csv", keep_default_na=False)
    if expected is None:
        assert "status" not in trials and len(trials) == TRIALS
        return
    failed = trials[trials["status"] == "failed"]
    assert len(failed) > 0, "no trial misbehaved: the test tested nothing"
    assert sorted(set(trials["trial"])) == list(range(TRIALS))
    assert failed["error"].str.contains(expected, regex=False).all(), failed["error"].iloc[0]
    manifest = json.loads((folder / "manifest.json").read_text())
    assert manifest["status"] == "complete" and manifest["trials_failed"] == len(failed)
    summary = pd.read_csv(folder / "summary.csv")
    ok = trials[trials["status"] != "failed"]
    if len(ok):  # the trials that behaved are summarised, and only they
        assert summary["n"].max() == len(ok)


@pytest.mark.parametrize("fault", list(FAULTS))
def test_a_fault_is_a_failed_row_in_serial(fault, serial_runs):
    _check_failed_rows(serial_runs(fault), FAULTS[fault][2])


def test_a_trials_keyboard_interrupt_is_a_failed_row_under_a_callers_sigint_handler(tmp_path):
    """A caller that installed its own Ctrl-C handler (dask's cluster does) keeps a trial's
    own KeyboardInterrupt a failed row: only a real Ctrl-C stops the run."""
    previous = signal.signal(signal.SIGINT, lambda signum, frame: None)
    try:
        folder = _run("KeyboardInterrupt", tmp_path, executor="serial", workers=1)
    finally:
        signal.signal(signal.SIGINT, previous)
    _check_failed_rows(folder, FAULTS["KeyboardInterrupt"][2])
    assert signal.getsignal(signal.SIGINT) is previous


@pytest.mark.parametrize("fault", list(FAULTS))
def test_a_fault_is_the_same_failed_row_in_the_process_pool(fault, serial_runs, tmp_path):
    folder = _run(fault, tmp_path, executor="process", workers=2)
    _check_failed_rows(folder, FAULTS[fault][2])
    assert (folder / "trials.csv").read_bytes() == \
        (serial_runs(fault) / "trials.csv").read_bytes()


@pytest.fixture(scope="module")
def dask_address():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    try:
        yield cluster.scheduler_address
    finally:
        cluster.close()


@pytest.mark.slow
@pytest.mark.parametrize("fault", ON_DASK)
def test_a_fault_is_the_same_failed_row_on_dask(fault, serial_runs, tmp_path, dask_address):
    folder = _run(fault, tmp_path, executor="dask", scheduler=dask_address)
    _check_failed_rows(folder, FAULTS[fault][2])
    assert (folder / "trials.csv").read_bytes() == \
        (serial_runs(fault) / "trials.csv").read_bytes()


@pytest.mark.parametrize("executor", [pytest.param(("--executor", "serial"),
                                                   marks=pytest.mark.slow),
                                      ("--workers", "2")])
def test_a_thread_a_trial_leaves_running_does_not_hold_the_run_s_exit(executor, tmp_path):
    """A non-daemon thread left by a trial: the process pool waited for its worker in the
    pool's shutdown for ever, before merging; serially the run wrote everything and never
    exited. Now both end with the run's status (the thread sleeps 10 minutes)."""
    (tmp_path / "thread.yaml").write_text("experiment: toy_experiments:UNRULY\ntrials: 8\n"
                                          "seed: 3\nparams: {how: thread}\n")
    result = trackfuse("run", "thread.yaml", *executor, "--no-plots", "--no-progress",
                       "--out", "out", cwd=tmp_path, timeout=90)
    assert result.returncode == 0, result.stderr
    assert next(tmp_path.glob("out/thread/*/summary.csv")).is_file()


@pytest.mark.slow
def test_trial_timeout_fails_the_hung_trials_and_the_run_goes_on(tmp_path):
    (tmp_path / "hang.yaml").write_text("experiment: toy_experiments:UNRULY\ntrials: 10\n"
                                        "seed: 3\nparams: {how: hang}\n")
    result = trackfuse("run", "hang.yaml", "--workers", "2", "--trial-timeout", "0.5",
                       "--no-plots", "--no-progress", "--out", "out", cwd=tmp_path)
    assert result.returncode == 3, result.stderr
    assert "TrialTimeout: the trial ran longer than the limit of 0.5 s" in result.stderr
    assert result.stderr.count("\n") == 1
    for bad in ("0", "-1", "nan", "1e9"):
        refused = trackfuse("run", "hang.yaml", "--trial-timeout", bad, "--out", "out",
                            cwd=tmp_path)
        assert refused.returncode == 2 and refused.stderr.startswith(
            "error: --trial-timeout: got "), refused.stderr


@pytest.mark.parametrize("how", [*(pytest.param(how, marks=pytest.mark.slow) for how in
                                   ("figures_exit", "figures_os_exit", "tables_exit")),
                                 "tables_os_exit"])
def test_a_report_that_exits_is_a_report_error_not_a_silent_success(how, tmp_path):
    """A report module's figures() or tables() calling sys.exit(0) or os._exit(0) ended the
    run with exit status 0 and no report, the run left 'running'."""
    (tmp_path / "r.yaml").write_text("experiment: toy_experiments:UNRULY_REPORT\ntrials: 4\n"
                                     f"params: {{report_how: {how}}}\n")
    result = trackfuse("run", "r.yaml", "--executor", "serial", "--no-progress", "--out",
                       "out", cwd=tmp_path)
    assert result.returncode == 1, result.stderr
    kind = "figure values" if how.startswith("figures") else "tables"
    error = "PluginExit: os._exit(0) called" if how.endswith("os_exit") else "SystemExit: 0"
    assert f"warning: {kind}: " in result.stderr and error in result.stderr
    folder = next(tmp_path.glob("out/r/*"))
    assert json.loads((folder / "manifest.json").read_text())["status"] == "complete"
    assert (folder / "index.html").is_file()


def test_a_run_whose_last_session_died_unrecorded_says_so_as_it_resumes(tmp_path):
    """A serial run ended by its trial (SIGKILL, a crash in compiled code: nothing a guard
    can catch) left its manifest 'running'; the next run resumed without a word."""
    config = _config("raise")
    warnings: list[str] = []
    first = Runner(config, tmp_path, executor="serial", plots=False, progress=False).run()
    manifest = json.loads((first.folder / "manifest.json").read_text())
    (first.folder / "manifest.json").write_text(json.dumps({**manifest, "status": "running"}))
    Runner(config, tmp_path, executor="serial", plots=False, progress=False,
           warn=warnings.append).run()
    assert [w for w in warnings if "stopped before the run ended without recording why" in w]
