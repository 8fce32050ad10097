"""Scale-out and survival: dask executor, dead workers, kill -9 resume (issue 6)."""

from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import cli_env, trackfuse

from trackfuse.config import build, load
from trackfuse.executors import (
    STOPPING_WHEN_LOADED,
    ExecutorError,
    ProcessExecutor,
    make_executor,
)
from trackfuse.results import BatchSpan, read_part
from trackfuse.runner import Runner

pytestmark = pytest.mark.slow  # kills, resumes and dask clusters

CFG = """
experiment: toy_experiments:GAUSSIAN
trials: 31
seed: 5
params: {n: 3}
sweep: {mu: [0, 1, 2]}
"""


def _local_cluster(workers: int):
    """The scheduler address of a dask LocalCluster of ``workers`` one-thread processes,
    closed after the test."""
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=workers, threads_per_worker=1,
                                       processes=True, dashboard_address=None)
    try:
        yield cluster.scheduler_address
    finally:
        cluster.close()


@pytest.fixture(scope="module")
def dask_address():
    yield from _local_cluster(2)


def run(config, out, **kw):
    return Runner(config, out, progress=False, plots=False, **kw).run()


def test_serial_process_and_dask_write_identical_csv(write_config, tmp_path, dask_address):
    config = load(write_config(CFG))
    serial = run(config, tmp_path / "s", executor="serial")
    pooled = run(config, tmp_path / "p", executor="process", workers=2)
    dasked = run(config, tmp_path / "d", executor="dask", scheduler=dask_address)
    want = (serial.folder / "trials.csv").read_bytes()
    assert want == (pooled.folder / "trials.csv").read_bytes()
    assert want == (dasked.folder / "trials.csv").read_bytes()
    assert want.count(b"\n") == 1 + 3 * 31 * 2


@pytest.mark.parametrize("executor", ["process", "dask"])
def test_a_worker_dying_mid_batch_loses_nothing(executor, tmp_path, dask_address):
    marker = tmp_path / "died"
    raw = {"experiment": "toy_experiments:CRASH", "trials": 40, "seed": 2,
           "params": {"marker": str(marker)}}
    config = build(raw, "crash.yaml")
    reference = run(config, tmp_path / "ref", executor="serial")
    extra = {"scheduler": dask_address} if executor == "dask" else {"workers": 2}
    survived = run(config, tmp_path / executor, executor=executor, **extra)
    assert marker.exists(), "the worker never died: the test tested nothing"
    assert (survived.folder / "trials.csv").read_bytes() == (reference.folder /
                                                             "trials.csv").read_bytes()


def test_dask_without_the_extra_is_a_one_line_error(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(ExecutorError, match=r"pip install 'trackfuse\[dask\]'"):
        make_executor("dask", 2)


def test_unreachable_scheduler_is_a_one_line_error(write_config, tmp_path):
    result = trackfuse("run", write_config(CFG), "--scheduler", "tcp://127.0.0.1:9",
                       "--out", tmp_path, timeout=120)
    assert result.returncode == 2
    assert result.stderr.startswith("error: cannot connect to tcp://127.0.0.1:9")
    assert "Traceback" not in result.stderr


def _parts_are_whole(folder: Path, trials: int, batch_size: int) -> int:
    """Every part on disk passes the full verification of the merge; returns their count."""
    parts = sorted(folder.glob("parts/p*.trials.csv"))
    for part in parts:
        batch = int(part.name.split("-b")[1].split(".")[0])
        span = BatchSpan(0, batch, batch * batch_size, min((batch + 1) * batch_size, trials))
        for kind in ("trials", "timings"):
            read_part(folder / "parts" / f"{span.name}.{kind}.csv", span, kind)
    return len(parts)


def _wait_for_more_parts(out: Path, proc, before: int, timeout: float = 60) -> None:
    deadline = time.monotonic() + timeout
    while proc.poll() is None and time.monotonic() < deadline and \
            len(list(out.glob("burn/*/parts/*.trials.csv"))) <= before:
        time.sleep(0.02)


def test_kill_9_at_random_moments_then_resume_equals_uninterrupted(write_config, tmp_path):
    """Each run is killed at a random moment after it wrote its first new part (while the
    workers compute and the parent writes parts); every part left is whole."""
    path = write_config("experiment: toy_experiments:BURN\ntrials: 320\nseed: 9\n"
                        "batch_size: 4\nparams: {work: 60}\n", "burn")
    out = tmp_path / "out"
    command = [sys.executable, "-m", "trackfuse", "run", str(path), "--out", str(out),
               "--workers", "2", "--no-plots", "--no-progress"]
    rng = random.Random(1234)
    kills, parts, most = 0, 0, 0
    for _ in range(4):
        proc = subprocess.Popen(command, env=cli_env(), stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, start_new_session=True)
        _wait_for_more_parts(out, proc, parts)
        time.sleep(rng.uniform(0.0, 0.3))
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            kills += 1
        proc.wait(timeout=30)
        folder = next(out.glob("burn/*"), None)
        if folder is not None:  # a run that finished has dropped its parts (complete)
            parts = _parts_are_whole(folder, 320, 4)
            most = max(most, parts)
    assert kills >= 3, "the runs finished before they could be killed"
    assert most > 0, "no run was killed after it wrote parts"
    final = subprocess.run(command, env=cli_env(), capture_output=True, text=True, timeout=300)
    assert final.returncode == 0, final.stderr
    reference = run(load(path), tmp_path / "ref", executor="serial")
    got = next(out.glob("burn/*/trials.csv")).read_bytes()
    assert got == (reference.folder / "trials.csv").read_bytes()
    assert not list(out.glob("burn/*/.*.tmp")) and not list(out.glob("burn/*/parts/.*.tmp"))


@pytest.mark.parametrize("how", ["exit", "interrupt", "none"])
def test_dask_contains_trials_that_exit_or_return_garbage(how, tmp_path, dask_address):
    """sys.exit(0) or KeyboardInterrupt inside a dask worker used to kill it (KilledWorker);
    now each is a failed row, as on the other executors, and the CSVs are identical."""
    config = build({"experiment": "toy_experiments:UNRULY", "trials": 30, "seed": 5,
                    "params": {"how": how}}, "unruly.yaml")
    serial = run(config, tmp_path / "s", executor="serial")
    dasked = run(config, tmp_path / "d", executor="dask", scheduler=dask_address)
    assert 0 < dasked.failed_trials == serial.failed_trials < 30
    assert (dasked.folder / "trials.csv").read_bytes() == (serial.folder /
                                                           "trials.csv").read_bytes()


def test_scheduler_file_missing_or_garbage_is_one_line_without_waiting(write_config,
                                                                      tmp_path):
    garbage = tmp_path / "scheduler.json"
    garbage.write_bytes(b"\x00\xffnot json")
    listish = tmp_path / "list.json"
    listish.write_text("[1, 2]")
    for path, expected in ((tmp_path / "missing.json", "no such file"),
                           (garbage, "not a dask scheduler file"),
                           (listish, "not a dask scheduler file")):
        t0 = time.monotonic()
        result = trackfuse("run", write_config(CFG), "--scheduler-file", path, "--out",
                           tmp_path / "out", timeout=60)
        assert time.monotonic() - t0 < 30
        assert result.returncode == 2
        assert result.stderr == f"error: --scheduler-file {path}: {expected}" + \
            result.stderr.split(expected, 1)[1]
        assert result.stderr.count("\n") == 1


def test_pool_workers_fork_with_the_batch_code_loaded_frozen_and_no_pandas():
    # a fresh process, so that its fork server starts with this code's preload list
    code = ("from trackfuse.executors import ProcessExecutor\n"
            "if __name__ == '__main__':\n"
            "    pool = ProcessExecutor(2)\n"
            "    probe = \"(__import__('gc').get_freeze_count(), 'trackfuse.batch' in "
            "__import__('sys').modules, 'pandas' in __import__('sys').modules)\"\n"
            "    print(list(pool.imap_unordered(eval, [probe] * 2)))\n"
            "    pool.close()\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=120).stdout
    results = eval(out)  # noqa: S307 - the list printed above
    assert len(results) == 2
    assert all(frozen > 10_000 and loaded and not pandas for frozen, loaded, pandas in results)


def test_the_pool_says_it_is_loading_until_the_fork_server_has_loaded_the_preload():
    # the progress bar's "first run compiles" rests on this: a fresh process, with a preload
    # module that takes 1 s, as a compiling kernel takes ten
    code = ("import threading, time\n"
            "from trackfuse.executors import ProcessExecutor\n"
            "if __name__ == '__main__':\n"
            "    t0 = time.monotonic()\n"
            "    pool = ProcessExecutor(2, ['slow_preload'])\n"
            "    ready_at = []\n"
            "    def watch():\n"
            "        while pool.loading():\n"
            "            time.sleep(0.01)\n"
            "        ready_at.append(time.monotonic() - t0)\n"
            "    watcher = threading.Thread(target=watch)\n"
            "    watcher.start()\n"
            "    done = sorted(pool.imap_unordered(abs, [-1, -2]))\n"
            "    watcher.join()\n"
            "    pool.close()\n"
            "    print([done, pool.loading(), ready_at[0]])\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=120, env=cli_env()).stdout
    done, loading_after, ready_s = eval(out)  # noqa: S307 - printed above
    assert done == [1, 2] and not loading_after
    assert ready_s >= 1.0  # not before the preload module had loaded


def test_a_ctrl_c_while_the_workers_load_says_the_run_stops_once_they_have(write_config,
                                                                           tmp_path):
    """The first batch's submit holds a Ctrl-C until the fork server has loaded the code
    (ten seconds or more on a first run, which compiles it): the command said nothing."""
    path = write_config("experiment: toy_experiments:SLOW_LOADING\ntrials: 4\nseed: 1\n")
    env = {**cli_env(), "TRACKFUSE_TEST_PRELOAD_S": "3"}
    command = [sys.executable, "-m", "trackfuse", "run", str(path), "--out", str(tmp_path),
               "--workers", "2", "--no-plots"]
    with subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          env=env) as proc:
        first = proc.stderr.readline()  # the progress line, just before the first submit
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        _, rest = proc.communicate(timeout=60)
    assert first.rstrip().endswith("0/4 trials (0%)"), first
    assert proc.returncode == 130, rest
    lines = rest.splitlines()
    assert lines[0] == STOPPING_WHEN_LOADED, rest
    assert lines[-1].startswith("interrupted: 0/4 trials saved"), rest


def test_workers_dying_every_time_is_a_one_line_error(write_config, tmp_path):
    path = write_config("experiment: toy_experiments:DOOMED\ntrials: 20\nseed: 1\n")
    result = trackfuse("run", path, "--out", tmp_path / "out", "--workers", "2",
                       "--no-plots", "--no-progress", timeout=120)
    assert result.returncode != 0
    assert result.stderr.startswith("error: the worker processes died 4 times")
    assert result.stderr.count("\n") == 1 and "Traceback" not in result.stderr
    assert not list(tmp_path.glob("out/*/*/trials.csv")), "an unfinished run looks complete"
    # what the message advises: the same command in this process finishes the run
    again = trackfuse("run", path, "--out", tmp_path / "out", "--executor", "serial",
                      "--no-plots", "--no-progress", timeout=120)
    assert again.returncode == 0, again.stderr
    assert next(tmp_path.glob("out/*/*/trials.csv")).read_text().count("\n") == 1 + 20


def test_workers_import_this_trackfuse_not_one_in_the_working_directory(tmp_path):
    """The fork server runs ``python -c`` in our working directory; another version's
    ``trackfuse`` folder there (a source checkout) must not be what the workers import."""
    shadow = tmp_path / "checkout"
    (shadow / "trackfuse").mkdir(parents=True)
    (shadow / "trackfuse" / "__init__.py").write_text("SHADOW = True\n")
    script = tmp_path / "probe.py"
    script.write_text(
        "import trackfuse\n"
        "from trackfuse.executors import ProcessExecutor\n"
        "if __name__ == '__main__':\n"
        "    pool = ProcessExecutor(2)\n"
        "    probe = \"__import__('trackfuse').__file__\"\n"
        "    print(trackfuse.__file__, *pool.imap_unordered(eval, [probe] * 2))\n"
        "    pool.close()\n")
    out = subprocess.run([sys.executable, str(script)], cwd=shadow, capture_output=True,
                         text=True, check=True, timeout=120).stdout.split()
    assert len(out) == 3 and "checkout" not in out[0]
    assert out[1] == out[2] == out[0]


def test_an_aborted_pool_ends_its_busy_workers_at_once():
    """An interrupted run closed its pool by waiting for the workers; a worker caught while
    the pool handed it work waited forever, and so did the run's exit (Python waits for
    every child): 1 of 12 runs stopped by SIGINT hung. Aborting ends the workers instead,
    and only them: a child the caller started before the pool is left alone."""
    code = ("import time\n"
            "from trackfuse.executors import ProcessExecutor\n"
            "from multiprocessing import active_children, get_context\n"
            "if __name__ == '__main__':\n"
            "    mine = get_context('spawn').Process(target=time.sleep, args=(60,))\n"
            "    mine.start()\n"
            "    pool = ProcessExecutor(2)\n"
            "    busy = pool.imap_unordered(time.sleep, [0.0, 60.0, 60.0])\n"
            "    next(busy)\n"
            "    start = time.monotonic()\n"
            "    pool.close(abort=True)\n"
            "    print(time.monotonic() - start, active_children() == [mine])\n"
            "    mine.terminate()\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, timeout=50).stdout
    seconds, only_mine = out.split()
    assert float(seconds) < 10 and only_mine == "True"


def _patch_workers(address: str, **replacements) -> None:
    """Replace ``trackfuse.environment`` functions in every worker of ``address``."""
    distributed = pytest.importorskip("distributed")

    def patch() -> None:
        import trackfuse.environment as environment

        for name, value in replacements.items():
            setattr(environment, name, lambda value=value: value)

    with distributed.Client(address) as client:
        client.run(patch)


@pytest.fixture
def own_cluster():
    """A cluster of its own, since a test here changes what its workers report."""
    yield from _local_cluster(1)


def test_a_dask_worker_with_other_library_versions_is_refused(write_config, tmp_path,
                                                              own_cluster):
    """A worker imports its own installation: with another numpy it would compute numbers the
    run id does not name, so the run refuses it in one line and writes no batch."""
    from trackfuse.environment import library_versions

    _patch_workers(own_cluster, library_versions={**library_versions(), "numpy": "1.0.0"})
    config = load(write_config(CFG))
    with pytest.raises(ExecutorError, match=r"dask worker tcp://\S+ has other library "
                                            r"versions: numpy 1\.0\.0 \(here "):
        run(config, tmp_path / "d", executor="dask", scheduler=own_cluster)
    assert not list((tmp_path / "d").rglob("part-*"))


def test_the_manifest_records_the_dask_workers_cpus(write_config, tmp_path, own_cluster):
    """The CPU that computed the batches is the workers', not the command's machine's."""
    import json

    worker_cpu = {"model": "a worker's CPU", "numpy_simd": None, "settings": {}}
    _patch_workers(own_cluster, cpu=worker_cpu)
    done = run(load(write_config(CFG)), tmp_path / "d", executor="dask",
               scheduler=own_cluster)
    manifest = json.loads((done.folder / "manifest.json").read_text())
    assert manifest["cpu"] == [worker_cpu]


def test_environment_difference_names_other_code_before_versions():
    from trackfuse.environment import environment_difference

    ours = {"python": "3.11.2", "numpy": "2.3.0"}
    same = {"code": "abc", "libraries": dict(ours), "cpu": {}}
    assert environment_difference("abc", ours, same) is None
    assert "other trackfuse code" in environment_difference("abd", ours, same)
    older = {**same, "libraries": {**ours, "numpy": "2.2.0"}}
    assert environment_difference("abc", ours, older) == (
        "has other library versions: numpy 2.2.0 (here 2.3.0)")


def test_a_lambda_run_trial_is_refused_before_the_pool_in_one_line(tmp_path):
    """A lambda (or nested) run_trial failed at the first batch with a PicklingError
    traceback and left the run stopped; serial and dask (cloudpickle) run it."""
    (tmp_path / "lambdaplug.py").write_text(
        "from trackfuse.experiments.base import Experiment, Metric\n"
        "EXPERIMENT = Experiment(name='lambdaplug', title='t', params=(),\n"
        "    run_trial=lambda params, streams: [{'algorithm': 'a', 'v': 1.0}],\n"
        "    metrics=(Metric('v', '1', 'one'),))\n")
    (tmp_path / "cfg.yaml").write_text("experiment: lambdaplug:EXPERIMENT\ntrials: 4\n")
    pooled = trackfuse("run", "cfg.yaml", "--workers", "2", "--no-plots", "--no-progress",
                       "--out", "out", cwd=tmp_path)
    assert pooled.returncode == 2, pooled.stderr
    assert pooled.stderr.startswith("error: cfg.yaml: experiment lambdaplug: its run_trial "
                                    "cannot be sent to the worker processes")
    assert pooled.stderr.count("\n") == 1 and not (tmp_path / "out").exists()
    serial = trackfuse("run", "cfg.yaml", "--executor", "serial", "--no-plots",
                       "--no-progress", "--out", "out", cwd=tmp_path)
    assert serial.returncode == 0, serial.stderr


def test_unpicklable_names_the_function_that_cannot_be_sent():
    def nested(params, streams):
        return []

    from trackfuse.executors import unpicklable
    from trackfuse.experiments.base import Experiment
    assert unpicklable(Experiment(name="n", title="t", params=(), run_trial=abs)) is None
    why = unpicklable(Experiment(name="n", title="t", params=(), run_trial=abs,
                                 run_batch=nested))
    assert why.startswith("its run_batch cannot be sent")


@pytest.mark.slow
def test_dask_workers_dying_every_time_is_one_line_and_exit_2_as_on_the_pool(write_config,
                                                                             tmp_path):
    """A batch whose dask workers died on it four times gave a KilledWorker traceback after
    about 60 lines of the cluster's log, exit 1 (the process pool: one line, exit 2)."""
    pytest.importorskip("distributed")
    path = write_config("experiment: toy_experiments:DOOMED\ntrials: 10\nseed: 1\n")
    result = trackfuse("run", path, "--out", tmp_path / "out", "--executor", "dask",
                       "--workers", "2", "--no-plots", "--no-progress", timeout=300)
    assert result.returncode == 2, result.stderr
    assert result.stderr.startswith("error: dask workers died each time they ran one batch")
    assert result.stderr.count("\n") == 1, result.stderr


def test_the_pool_replaces_its_workers_after_a_result_asks_for_it():
    """A trial interrupted at its time limit was stopped wherever it was: its worker is
    replaced once the batches in flight are done, and the run goes on in fresh ones."""
    from toy_experiments import worker_pid

    pool = ProcessExecutor(1)
    try:
        results = list(pool.imap_unordered(worker_pid, [True, *[False] * 6]))
    finally:
        pool.close()
    first = results[0].pid
    assert len(results) == 7 and results[-1].pid != first
    assert [r.pid for r in results[3:]] == [results[-1].pid] * 4  # in flight: on the old one
