"""One writer per run folder: concurrent runs refuse in one line naming the holder, a lock
left by a killed run is taken over, temporaries of a live run are never deleted (issue 14)."""

from __future__ import annotations

import json
import os
import platform
import re
import signal
import subprocess
import sys
import time

import pytest
from conftest import cli_env

from trackfuse.runlock import HOLDER_FILE, RunFolderBusy, RunLock

pytestmark = pytest.mark.slow  # concurrent and killed runs of one folder

BURN = "experiment: toy_experiments:BURN\ntrials: 300\nseed: 3\nparams: {work: 30}\n"
BUSY = re.compile(r"^error: (?P<folder>\S+): in use by trackfuse pid (?P<pid>\d+) on "
                  r"(?P<host>\S+) \(since [^)]+\); wait for it to finish \(or stop it\) and run "
                  r"again$")


def command(path, out) -> list[str]:
    return [sys.executable, "-m", "trackfuse", "run", str(path), "--out", str(out),
            "--executor", "serial", "--no-plots", "--no-progress"]


def wait_for_parts(out, proc, timeout=60.0) -> None:
    deadline = time.monotonic() + timeout
    while not list(out.glob("*/*/parts/*.trials.csv")):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "no part appeared"
        time.sleep(0.05)


def test_four_runs_of_one_folder_at_once_compute_each_trial_once(write_config, tmp_path):
    """The issue's scenario: four `trackfuse run` of one config into one folder at once."""
    path = write_config(BURN, "burn")
    out = tmp_path / "out"
    procs = [subprocess.Popen(command(path, out), env=cli_env(), stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True) for _ in range(4)]
    outputs = [p.communicate(timeout=300) for p in procs]
    results = [(p.pid, p.returncode, so, se) for p, (so, se) in zip(procs, outputs,
                                                                    strict=True)]
    computed = {pid: int(m.group(1)) for pid, _, so, _ in results
                if (m := re.search(r"\((\d+) computed now\)", so))}
    assert sum(computed.values()) == 300, results
    writer = max(computed, key=computed.get)
    for _pid, code, _, stderr in results:
        assert "Traceback" not in stderr
        if code == 2:
            match = BUSY.match(stderr.strip())
            assert match and stderr.count("\n") == 1, stderr
            assert int(match["pid"]) == writer and match["host"] == platform.node()
        else:
            assert code == 0, stderr
    assert any(code == 2 for _, code, _, _ in results), "the runs did not overlap"
    folder = next(out.glob("burn/*"))
    assert json.loads((folder / "manifest.json").read_text())["status"] == "complete"
    assert not (folder / HOLDER_FILE).exists()


def test_a_refused_run_leaves_the_writer_and_its_temporaries_alone(write_config, tmp_path):
    path = write_config(BURN.replace("trials: 300", "trials: 5000"), "burn")
    out = tmp_path / "out"
    # restore Ctrl-C for the writer (a shell running tests in the background ignores it)
    writer = subprocess.Popen(command(path, out), env=cli_env(), stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True,
                              preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    wait_for_parts(out, writer)
    folder = next(out.glob("burn/*"))
    planted = folder / "parts" / f".p000000-b0000999.trials.csv.{writer.pid}.tmp"
    planted.write_text("being written")
    second = subprocess.run(command(path, out), env=cli_env(), capture_output=True, text=True,
                            timeout=120)
    assert second.returncode == 2 and BUSY.match(second.stderr.strip()), second.stderr
    assert planted.exists()
    assert writer.poll() is None, "the writer finished before the second run started"
    writer.send_signal(signal.SIGINT)
    _, err = writer.communicate(timeout=120)
    assert writer.returncode == 130, err
    assert "run the same command again to resume" in err and "Traceback" not in err


def test_a_lock_left_by_a_killed_run_is_taken_over(write_config, tmp_path):
    path = write_config(BURN, "burn")
    out = tmp_path / "out"
    victim = subprocess.Popen(command(path, out), env=cli_env(), stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL, start_new_session=True)
    wait_for_parts(out, victim)
    os.killpg(victim.pid, signal.SIGKILL)
    victim.wait(timeout=30)
    folder = next(out.glob("burn/*"))
    assert json.loads((folder / HOLDER_FILE).read_text())["pid"] == victim.pid
    again = subprocess.run(command(path, out), env=cli_env(), capture_output=True, text=True,
                           timeout=300)
    assert again.returncode == 0, again.stderr
    assert f"taking over from trackfuse pid {victim.pid} on {platform.node()}" in again.stderr
    assert json.loads((folder / "manifest.json").read_text())["status"] == "complete"
    assert not (folder / HOLDER_FILE).exists()


def test_the_lock_in_process_refuses_a_second_holder_and_is_released(tmp_path):
    warnings: list[str] = []
    with RunLock(tmp_path / "run", warnings.append):
        with pytest.raises(RunFolderBusy, match=rf"in use by trackfuse pid {os.getpid()} "), \
                RunLock(tmp_path / "run", warnings.append):
            pass
        holder = json.loads((tmp_path / "run" / HOLDER_FILE).read_text())
        assert holder["pid"] == os.getpid() and holder["host"] == platform.node()
    assert not (tmp_path / "run" / HOLDER_FILE).exists()
    with RunLock(tmp_path / "run", warnings.append):
        pass
    assert warnings == []


@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs Linux's /proc")
def test_dry_run_into_a_file_system_that_stores_no_files_says_why_not_new(write_config):
    """`--dry-run --out /proc` said '(new)' while the run refused it (no such file)."""
    from conftest import trackfuse
    path = write_config("experiment: toy_experiments:GAUSSIAN\ntrials: 2\n")
    planned = trackfuse("run", path, "--out", "/proc", "--dry-run")
    ran = trackfuse("run", path, "--out", "/proc", "--no-progress")
    for result in (planned, ran):
        assert result.returncode == 2 and "(new)" not in result.stdout
        assert result.stderr.startswith("error: /proc/cfg/") and \
            "cannot create the run folder" in result.stderr


def test_dry_run_into_a_read_only_file_system_says_why(tmp_path, monkeypatch):
    from trackfuse import runlock

    class ReadOnly:
        f_flag, f_blocks, f_files = os.ST_RDONLY, 100, 100

    monkeypatch.setattr(runlock.os, "statvfs", lambda folder: ReadOnly)
    problem = runlock.creation_problem(tmp_path / "out" / "run")
    assert problem == f"{tmp_path / 'out' / 'run'}: cannot create the run folder ({tmp_path}: " \
                      "a read-only file system)"
