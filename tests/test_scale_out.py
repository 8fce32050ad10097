"""Scale-out and survival: dask executor, dead workers, kill -9 resume (issue 6)."""

from __future__ import annotations

import csv
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
from trackfuse.executors import ExecutorError, make_executor
from trackfuse.runner import Runner

CFG = """
experiment: toy_experiments:GAUSSIAN
trials: 31
seed: 5
params: {n: 3}
sweep: {mu: [0, 1, 2]}
"""


@pytest.fixture(scope="module")
def dask_address():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    try:
        yield cluster.scheduler_address
    finally:
        cluster.close()


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


def _parts_are_whole(folder: Path, trials_per_batch: dict[str, int]) -> None:
    for part in folder.glob("parts/*.trials.csv"):
        with open(part, newline="") as fh:
            rows = list(csv.reader(fh))
        header, body = rows[0], rows[1:]
        assert all(len(r) == len(header) for r in body), part
        name = part.name.split(".")[0]
        assert len(body) == trials_per_batch[name], part


def test_kill_9_at_random_moments_then_resume_equals_uninterrupted(write_config, tmp_path):
    path = write_config("experiment: toy_experiments:BURN\ntrials: 240\nseed: 9\n"
                        "batch_size: 4\nparams: {work: 12}\n", "burn")
    out = tmp_path / "out"
    command = [sys.executable, "-m", "cli.main", "run", str(path), "--out", str(out),
               "--workers", "2", "--no-plots", "--no-progress"]
    rng = random.Random(1234)
    kills = 0
    for _ in range(8):
        proc = subprocess.Popen(command, env=cli_env(), stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL, start_new_session=True)
        time.sleep(rng.uniform(0.3, 2.5))
        if proc.poll() is None:
            os.kill(proc.pid, signal.SIGKILL)
            kills += 1
        proc.wait(timeout=30)
        folder = next(out.glob("burn/*"), None)
        if folder is not None:
            _parts_are_whole(folder, {f"p000000-b{b:07d}": 4 for b in range(60)})
    assert kills >= 4, "the runs finished before they could be killed"
    final = subprocess.run(command, env=cli_env(), capture_output=True, text=True, timeout=300)
    assert final.returncode == 0, final.stderr
    reference = trackfuse("run", path, "--out", tmp_path / "ref", "--executor", "serial",
                          "--no-plots", "--no-progress", timeout=300)
    assert reference.returncode == 0, reference.stderr
    got = next(out.glob("burn/*/trials.csv")).read_bytes()
    assert got == next((tmp_path / "ref").glob("burn/*/trials.csv")).read_bytes()
    assert not list(out.glob("burn/*/.*.tmp")) and not list(out.glob("burn/*/parts/.*.tmp"))
