"""Problems found by using the command line as a demanding user would (Ctrl-C from a
terminal, kill -9, typos, empty options, folders of runs, mismatched runs): each test failed
before its fix."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import ROOT, cli_env, trackfuse

from trackfuse.child_processes import process_alive
from trackfuse.config import ConfigError, load
from trackfuse.executors import STOPPING_WHEN_LOADED, default_workers
from trackfuse.sweep import parse_sets

pytestmark = pytest.mark.slow  # signals, kills and runs through the real command line

CI = ROOT / "configs" / "ci"
PASSIVE = CI / "passive_assoc_ci.yaml"
SLOW_ARGS = ("--set", "trials=40", "--set", "batch_size=2", "--no-progress")


def _children(pid: int) -> list[int]:
    """Direct children of ``pid`` (Linux /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
            found.append(int(entry.name))
    return found


def _cmdline(pid: int) -> str:
    try:
        return (Path("/proc") / str(pid) / "cmdline").read_bytes().replace(b"\0", b" ").decode()
    except OSError:
        return ""


def _wait_for_fork_server(pid: int, timeout: float = 60) -> int:
    """The pid of the fork server the run ``pid`` starts, as soon as it exists."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        for child in _children(pid):
            if "multiprocessing.forkserver" in _cmdline(child):
                return child
        time.sleep(0.01)
    pytest.fail("the run started no fork server")


def _start(out: Path, workers: int = 2, ctrl_c: signal.Handlers = signal.SIG_DFL
           ) -> subprocess.Popen:
    """The run as a terminal starts it: its own process group, Ctrl-C not ignored (a test
    session started in the background, as `.ci/run &` is, ignores it and would pass that on);
    ``ctrl_c`` SIG_IGN starts it as a shell's background job."""
    return subprocess.Popen([sys.executable, "-m", "trackfuse", "run", str(PASSIVE),
                             "--out", str(out), *SLOW_ARGS, "--workers", str(workers)],
                            env=cli_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, ctrl_c))


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_terminal_ctrl_c_while_the_fork_server_loads_prints_no_traceback(tmp_path):
    """A terminal's Ctrl-C reaches the whole process group, the fork server included.

    Pressed in the first seconds of a run (while the fork server imports the preload
    modules), it printed the fork server's 20-80 line ``KeyboardInterrupt`` traceback.
    """
    proc = _start(tmp_path / "out")
    try:
        _wait_for_fork_server(proc.pid)
        time.sleep(0.2)
        os.killpg(proc.pid, signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert "forkserver.py" not in err and "process.py" not in err, err  # no child's traceback
    if proc.returncode == 0:
        # CPython drops a KeyboardInterrupt raised inside a callback of its import machinery
        # ("Exception ignored in"), or (2 of 270 runs) loses the Ctrl-C while modules load
        # without a word, and the run goes on to completion: rare, not the children's doing
        assert "Exception ignored in" in err or "Traceback" not in err, err
        return
    assert proc.returncode == 130, (proc.returncode, err)
    assert "Traceback" not in err, err
    assert err.strip().startswith("interrupted:"), err


def test_ctrl_c_caught_after_it_left_an_exec_exits_130(write_config, tmp_path):
    """A Ctrl-C whose ``KeyboardInterrupt`` left code run by ``exec`` of a string (a dataclass
    being built while a module loads) ended ``python -m trackfuse`` by SIGINT after its
    ``interrupted:`` line (CPython 3.11 to 3.13): the test above's few runs in a hundred."""
    path = write_config("experiment: toy_experiments:CTRL_C_IN_EXEC\ntrials: 4\nseed: 1\n")
    result = trackfuse("run", path, "--out", tmp_path / "out", "--executor", "serial",
                       "--no-plots", "--no-progress",
                       preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert result.returncode == 130, (result.returncode, result.stderr)
    assert result.stderr.startswith("interrupted:") and "Traceback" not in result.stderr


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_kill_9_of_a_run_leaves_no_fork_server_behind(tmp_path):
    """After ``kill -9`` of ``trackfuse run`` its fork server (about 160 MB), resource
    tracker and idle workers stayed alive for good: ten kills left 1.9 GB of orphans. Then
    the resource tracker warned of "leaked semaphore objects" on the terminal, after the
    shell's prompt."""
    proc = _start(tmp_path / "out")
    server = _wait_for_fork_server(proc.pid)
    leftovers: list[int] = []
    try:
        deadline = time.monotonic() + 60
        while not _children(server) and time.monotonic() < deadline:
            time.sleep(0.05)
        leftovers = [server, *_children(server),
                     *(c for c in _children(proc.pid) if c != server)]
        proc.kill()
        proc.wait(timeout=30)
        time.sleep(5)
        alive = [pid for pid in leftovers if process_alive(pid)]
        assert not alive, f"still running after the run was killed: {alive}"
        stderr = proc.communicate(timeout=30)[1]
        assert "leaked" not in stderr and "Warning" not in stderr, stderr
    finally:
        for pid in leftovers:
            if process_alive(pid):
                os.kill(pid, signal.SIGKILL)


def test_plot_of_a_folder_that_is_not_a_run_exits_nonzero(tmp_path):
    """``trackfuse plot results/`` listed the runs, drew nothing and exited 0, so a script
    (`trackfuse plot DIR && publish`) took it for success."""
    out = tmp_path / "results"
    done = trackfuse("run", PASSIVE, "--out", out, "--set", "trials=1", "--executor", "serial",
                     "--no-plots", "--no-progress")
    assert done.returncode == 0, done.stderr
    result = trackfuse("plot", out)
    assert result.returncode == 2, result.stdout
    assert len(result.stderr.strip().splitlines()) == 1
    assert not list(out.rglob("figures/*.png"))


def test_unknown_algorithm_is_named_even_when_it_is_not_among_the_first_four(write_config):
    """A typo in the fifth algorithm was cut from the message: `got ['exact', ..., ...]`."""
    text = PASSIVE.read_text().replace("pga_anneal]", "pga_aneal]")
    assert "pga_aneal" in text
    with pytest.raises(ConfigError) as err:
        load(write_config(text))
    assert (err.value.key, err.value.suggestion) == ("params.algorithms", "pga_anneal")
    assert "'pga_aneal'" in err.value.message, str(err.value)


def test_a_value_repeated_in_a_grid_sweep_axis_is_refused(write_config):
    """`targets.n: [5, 5]` ran two points with the same parameters and different numbers
    (the point stream differs), and the figures joined them by a vertical line at N = 5
    that reads as an interval."""
    text = PASSIVE.read_text().replace("targets.n: [5, 10]", "targets.n: [5, 5]")
    with pytest.raises(ConfigError) as err:
        load(write_config(text))
    assert (err.value.key, err.value.allowed) == ("sweep.targets.n", "distinct values")


def test_empty_out_is_refused_instead_of_writing_into_the_current_folder(tmp_path):
    """`--out ''` (an unset shell variable: `--out "$OUT"`) silently wrote into the
    current folder."""
    result = trackfuse("run", PASSIVE, "--out", "", "--set", "trials=1", "--executor",
                       "serial", "--no-plots", "--no-progress", cwd=tmp_path)
    assert result.returncode == 2, result.stdout
    assert not (tmp_path / "passive_assoc_ci").exists()


def _small_run(out: Path, *extra: str) -> Path:
    done = trackfuse("run", PASSIVE, "--out", out, "--set", "trials=3", "--executor", "serial",
                     "--no-plots", "--no-progress", *extra)
    assert done.returncode == 0, done.stderr
    return next(out.rglob("manifest.json")).parent


def test_compare_tolerance_for_an_unknown_metric_is_refused(tmp_path):
    """`--tolerance accuraci=0.5` (a typo) was accepted and silently ignored, so a CI gate
    ran without the tolerance its author wrote."""
    run, again = _small_run(tmp_path / "a"), _small_run(tmp_path / "b")
    result = trackfuse("compare", run, again, "--fail-on-regression", "--tolerance",
                       "accuraci=0.5")
    assert result.returncode == 2, result.stdout
    assert "accuraci" in result.stderr and len(result.stderr.strip().splitlines()) == 1


def test_compare_says_which_cells_only_one_run_has(tmp_path):
    """A base run over ``targets.n: [5, 10]`` against one over ``[5]``: the 10-target cells
    were dropped without a word. (A run repeating a sweep value, which made compare count
    base trials twice, is now refused: test_a_value_repeated_in_a_grid_sweep_axis_is_refused.)
    """
    base = _small_run(tmp_path / "base")
    new = _small_run(tmp_path / "new", "--sweep", "targets.n=5")
    result = trackfuse("compare", base, new, "--json")
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert report["only_base"] == len(report["cells"]) > 0 and report["only_new"] == 0
    assert max(cell["n_base"] for cell in report["cells"]) <= 3
    text = trackfuse("compare", base, new)
    assert f"{report['only_base']} cells only in BASE" in text.stdout


def test_more_workers_than_cores_is_said_in_one_line():
    """`--workers 1000` started 1000 processes without a word."""
    workers = default_workers() + 1  # one more than this host's usable cores, on any host
    result = trackfuse("run", PASSIVE, "--workers", str(workers), "--dry-run")
    assert result.returncode == 0, result.stderr
    warnings = [line for line in result.stderr.splitlines() if line.startswith("warning:")]
    assert len(warnings) == 1 and warnings[0].startswith(f"warning: --workers {workers}: ")


@pytest.mark.parametrize(("workers", "ctrl_c"), [(2, signal.SIG_DFL), (1, signal.SIG_DFL),
                                               (1, signal.SIG_IGN)])
def test_sigterm_stops_a_run_as_ctrl_c_does(tmp_path, workers, ctrl_c):
    """A batch scheduler's time limit (or ``kill``, ``docker stop``) sends SIGTERM: the run
    died with exit 143, a resource-tracker warning about leaked semaphores and a manifest
    left 'running' with no trial counted, though its saved batches were resumable. With one
    worker (batches in this process) the stop was read as the trial's own error: the batch
    was re-run trial by trial and the run went on to the end, exit 0."""
    out = tmp_path / "out"
    proc = _start(out, workers, ctrl_c)
    try:
        deadline = time.monotonic() + 60
        # two batches' trials parts: the first batch is then counted too (a batch's parts
        # are written just before the run counts it, so one batch's two parts were a race)
        while len(list(out.glob("*/*/parts/*.trials.csv"))) < 2 \
                and time.monotonic() < deadline:
            time.sleep(0.05)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
    assert proc.returncode == 130, err
    assert err.strip().startswith("interrupted:") and "\n" not in err.strip(), err
    manifest = json.loads(next(out.glob("*/*/manifest.json")).read_text())
    assert manifest["status"] == "interrupted" and manifest["trials_done"] > 0  # parts saved


@pytest.mark.parametrize("value", ["[1, 2]", "[1, 2, 3, 4]"])
def test_a_position_without_three_coordinates_is_refused_before_the_run(value):
    """`validate` accepted `target.position: [1, 2]`; `run` then failed every trial and
    wrote a 'complete' manifest of failed trials."""
    with pytest.raises(ConfigError) as err:
        load(ROOT / "configs" / "twin_sensor_orbit.yaml", parse_sets([f"target.position={value}"]))
    assert (err.value.source, err.value.key) == ("--set", "target.position")
    assert err.value.allowed.startswith("a list of 3 numbers"), str(err.value)


def test_running_a_no_plots_run_again_draws_its_report(tmp_path):
    """After `run --no-plots`, the same command without it printed `already complete` and
    drew nothing: the run never got its figures, tables or index unless the user found
    `trackfuse plot`."""
    args = ("run", PASSIVE, "--out", tmp_path, "--set", "trials=2", "--executor", "serial",
            "--no-progress")
    assert trackfuse(*args, "--no-plots").returncode == 0
    assert not list(tmp_path.glob("*/*/index.html"))
    again = trackfuse(*args)
    assert again.returncode == 0, again.stderr
    index = next(tmp_path.glob("*/*/index.html"))
    assert f"report: {index}" in again.stdout and list(index.parent.glob("figures/*.png"))


def test_reproduce_names_every_bad_config_before_running_any(tmp_path):
    """`reproduce` stopped at the first bad config, so several were found one run at a time."""
    (tmp_path / "a.yaml").write_text("experiment: nope\n")
    (tmp_path / "b.yaml").write_text(PASSIVE.read_text().replace("trials:", "trials: 0 #"))
    (tmp_path / "c.yaml").write_text(PASSIVE.read_text())
    result = trackfuse("reproduce", tmp_path, "--out", tmp_path / "out", "--no-progress")
    assert result.returncode == 2, result.stdout
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 2 and "a.yaml" in lines[0] and "b.yaml: trials" in lines[1], lines
    assert not (tmp_path / "out").exists()


def test_a_parameter_set_and_swept_in_one_file_is_refused(write_config):
    """`params.clutter.mean: 3` beside `sweep: {clutter.mean: [0, 1]}` passed `validate`:
    the sweep won and the resolved config still showed 3 under params."""
    cfg = write_config("experiment: twin_sensor\nparams:\n  clutter:\n    mean: 3\n"
                       "sweep:\n  clutter.mean: [0, 1]\n")
    with pytest.raises(ConfigError) as err:
        load(cfg)
    assert (err.value.source, err.value.key) == (str(cfg), "params.clutter.mean")
    assert err.value.message.startswith("also swept (sweep.clutter.mean)")
    assert err.value.allowed == "the key under params or under sweep, not both"
    assert load(cfg, parse_sets(["clutter.mean=2"])).params["clutter.mean"] == 2  # settled
    template = trackfuse("list", "twin_sensor", "--format", "yaml").stdout  # every default
    swept = write_config(template.replace("sweep: {}", "sweep: {clutter.mean: [0, 1]}"),
                         name="template")
    assert "sweep: {clutter.mean" in swept.read_text()
    assert load(swept).sweep == {"clutter.mean": [0, 1]}  # a default left in place: no clash


def test_an_option_and_a_set_of_the_same_key_are_refused():
    """`--trials 5 --set trials=7` ran 5 trials without a word."""
    result = trackfuse("run", PASSIVE, "--trials", "5", "--set", "trials=7", "--dry-run")
    assert result.returncode == 2, result.stdout
    assert result.stderr == "error: --trials 5 and --set trials=7: give trials once\n"


def test_a_bad_set_fails_reproduce_in_one_line_and_a_bad_choice_reads_plainly():
    """A bad `--set` printed the same error once per config (7 lines); a bad choice said
    "Invalid value for '--executor': Value error, 'foo' is not one of ..."."""
    result = trackfuse("reproduce", CI, "--set", "clutter.mean=-1", "--dry-run")
    assert result.returncode == 2
    assert len(result.stderr.splitlines()) == 1, result.stderr
    assert result.stderr.startswith("error: --set: clutter.mean: got -1; allowed: ")
    choice = trackfuse("run", PASSIVE, "--executor", "foo", "--dry-run")
    assert choice.returncode == 2 and "'--executor': 'foo' is not one of" in choice.stderr


def test_an_interrupted_command_that_saves_nothing_does_not_speak_of_resuming(tmp_path):
    """SIGTERM to `validate` (blocked reading a named pipe) said "run the same command again
    to resume": validate has nothing to resume."""
    fifo = tmp_path / "cfg.yaml"
    os.mkfifo(fifo)
    proc = subprocess.Popen([sys.executable, "-m", "trackfuse", "validate", str(fifo)],
                            env=cli_env(), stderr=subprocess.PIPE, text=True)
    wchan = Path(f"/proc/{proc.pid}/wchan")
    deadline = time.monotonic() + 60
    while wchan.read_text() != "wait_for_partner" and time.monotonic() < deadline:
        time.sleep(0.05)  # until it blocks opening the pipe: its handlers are in place
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130 and err == "interrupted\n", err


CTRL_C_AS_A_WORKER_STARTS = """
import os, runpy, signal, subprocess
from multiprocessing import popen_forkserver
launch = popen_forkserver.Popen._launch
def launch_then_ctrl_c(self, process_obj):
    launch(self, process_obj)
    # a slow worker: held before it reads its semaphores until this process has had time
    # to stop the run
    os.kill(self.pid, signal.SIGSTOP)
    # released once this process has exited (the bug: the worker then finds its semaphores
    # gone), or after 5 s (fixed: this process waits for the worker it ends)
    subprocess.Popen(["sh", "-c", f"for i in $(seq 100); do kill -0 {os.getpid()} || break; "
                      f"sleep 0.05; done; kill -CONT {self.pid}"])
    os.kill(os.getpid(), signal.SIGINT)
popen_forkserver.Popen._launch = launch_then_ctrl_c
runpy.run_module("trackfuse", run_name="__main__")
"""


def test_ctrl_c_while_a_worker_starts_leaves_no_worker_behind(write_config, tmp_path):
    """A Ctrl-C inside ``Process.start`` (the pool starting a worker) left a worker the pool
    did not know of: it outlived the command and printed a traceback once its semaphores
    were gone. Here every worker start is followed by a Ctrl-C while the worker is held
    until the command has exited (at most 5 s); the captured output ends only when every
    process holding the pipes has ended."""
    path = write_config("experiment: toy_experiments:GAUSSIAN\ntrials: 40\nseed: 1\n"
                        "batch_size: 2\n")
    result = subprocess.run(
        [sys.executable, "-c", CTRL_C_AS_A_WORKER_STARTS, "run", str(path), "--out",
         str(tmp_path / "out"), "--workers", "2", "--no-plots", "--no-progress"],
        env=cli_env(), capture_output=True, text=True, timeout=120,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    assert result.returncode == 130, (result.returncode, result.stderr)
    stderr = result.stderr.removeprefix(STOPPING_WHEN_LOADED + "\n")  # held at a start
    # (the test's own helper shell may add "kill: No such process" after it)
    assert stderr.startswith("interrupted:") and "Traceback" not in stderr, result.stderr


def test_list_suggests_the_closest_experiment():
    """`list twin_sensr` named the allowed experiments but, unlike a config, no close one."""
    result = trackfuse("list", "twin_sensr")
    assert result.returncode == 2
    assert "unknown experiment 'twin_sensr'; did you mean 'twin_sensor'?" in result.stderr


@pytest.mark.parametrize("option", ["--scheduler", "--scheduler-file"])
def test_an_empty_scheduler_is_refused_not_run_here(write_config, option):
    """`--scheduler ""` (an unset shell variable) silently ran on this machine."""
    from typer.testing import CliRunner

    from trackfuse_cli.main import app
    path = write_config("experiment: toy_experiments:GAUSSIAN\ntrials: 2\n")
    result = CliRunner().invoke(app, ["run", str(path), option, " ", "--dry-run"])
    assert result.exit_code == 2 and result.stdout == ""
    assert result.stderr.startswith(f"error: {option}: got an empty value; allowed: ")


def test_a_metric_given_two_tolerances_is_refused():
    """`--tolerance m=1 --tolerance m=2` was accepted, the last one winning unsaid."""
    from typer.testing import CliRunner

    from trackfuse_cli.main import app
    result = CliRunner().invoke(app, ["compare", "base", "new", "--tolerance", "m=1",
                                      "--tolerance", "m=2"])
    assert result.exit_code == 2
    assert result.stderr == "error: --tolerance: m given twice (1 and 2); allowed: one " \
                            "tolerance per metric\n"
