"""trackfuse.catalog: finding run folders; `trackfuse runs`; --name."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys

from typer.testing import CliRunner

from trackfuse.catalog import find_runs
from trackfuse.config import load
from trackfuse.runlock import HOLDER_FILE
from trackfuse.runner import Runner
from trackfuse.runstate import DAMAGED
from trackfuse_cli.main import app

NO_REPORT = "complete, no report"


def test_runs_lists_run_folders_with_their_name_and_plot_lists_a_folder_of_runs(
        write_config, tmp_path):
    cfg = write_config("experiment: toy_gaussian\ntrials: 4\nseed: 1\n", name="gauss")
    out = tmp_path / "out"
    Runner(load(cfg), out, progress=False, plots=False, name="first try").run()
    Runner(load(cfg, {"seed": 2}), out, progress=False, plots=False).run()
    found = find_runs(out)
    assert sorted((r.stem, r.name, r.status, r.trials_done) for r in found) == \
        [("gauss", "", NO_REPORT, 4), ("gauss", "first try", NO_REPORT, 4)]
    again = Runner(load(cfg), out, progress=False, plots=False)  # resume keeps the name
    again.run()
    assert json.loads((again.folder.path / "manifest.json").read_text())["name"] == "first try"
    listed = CliRunner().invoke(app, ["runs", str(out)])
    assert listed.exit_code == 0 and "first try" in listed.stdout
    plotted = CliRunner().invoke(app, ["plot", str(out / "gauss")])  # lists them, draws none
    assert plotted.exit_code == 2 and "first try" in plotted.stdout
    assert "a folder of 2 runs, not a run" in plotted.stderr


def test_a_run_whose_process_has_ended_is_listed_as_stopped_not_running(write_config,
                                                                        tmp_path):
    """After kill -9 (or a full disk) `trackfuse runs` showed `running 0/N` for good."""
    cfg = write_config("experiment: toy_gaussian\ntrials: 4\nseed: 1\n", name="gauss")
    runner = Runner(load(cfg), tmp_path, progress=False, plots=False)
    runner.run()
    path = runner.folder.path
    manifest = json.loads((path / "manifest.json").read_text())
    (path / "manifest.json").write_text(json.dumps({**manifest, "status": "running"}))
    holder = path / HOLDER_FILE

    def status_with(pid: int | None) -> str:
        holder.unlink(missing_ok=True)
        if pid is not None:
            holder.write_text(json.dumps({"pid": pid, "host": platform.node()}))
        return find_runs(tmp_path)[0].status

    ended = subprocess.Popen([sys.executable, "-c", "pass"])
    ended.wait()
    assert status_with(os.getpid()) == "running"  # its process is alive
    assert status_with(ended.pid) == "stopped"  # killed while holding the folder
    assert status_with(None) == "stopped"  # ended without marking the run


def test_a_stopped_run_shows_the_trials_its_saved_parts_hold(write_config, tmp_path):
    """The manifest's trials_done is written when a session starts or ends, so a killed run
    showed the count at its start; the saved batches are what a resume keeps."""
    cfg = write_config("experiment: toy_gaussian\ntrials: 10\nseed: 1\nbatch_size: 3\n"
                       "sweep:\n  mu: [0.0, 1.0]\n", name="gauss")
    runner = Runner(load(cfg), tmp_path, progress=False, plots=False)
    runner.run()
    path = runner.folder.path
    manifest = json.loads((path / "manifest.json").read_text())
    assert find_runs(tmp_path)[0].trials_done == 20
    (path / "manifest.json").write_text(json.dumps({**manifest, "status": "running",
                                                    "trials_done": 0}))
    parts = path / "parts"
    parts.mkdir()
    for name in ("p000000-b0000000.trials", "p000000-b0000000.timings",  # 3 trials
                 "p000000-b0000003.trials", "p000000-b0000003.timings",  # the last: 1 trial
                 "p000001-b0000001.trials",  # its timings part is missing: not saved
                 "p000002-b0000000.trials", "p000002-b0000000.timings",  # no point 2
                 "p000001-b0000004.trials", "p000001-b0000004.timings",  # no batch 4
                 ".p000001-b0000002.trials.csv.tmp"):  # a temporary file
        (parts / f"{name}.csv").write_text("")
    stopped = find_runs(tmp_path)[0]
    assert (stopped.status, stopped.trials_done, stopped.trials_total) == ("stopped", 4, 20)


def test_a_complete_run_renamed_by_name_keeps_its_results(write_config, tmp_path):
    """--name on a complete run was ignored without a word (the run returned before its
    manifest was written)."""
    cfg = write_config("experiment: toy_gaussian\ntrials: 4\nseed: 1\n", name="gauss")
    Runner(load(cfg), tmp_path, progress=False, plots=False).run()
    again = Runner(load(cfg), tmp_path, progress=False, plots=False, name="relabelled")
    trials = (again.folder.path / "trials.csv").read_bytes()
    assert again.run().status == "already complete"
    assert find_runs(tmp_path)[0].name == "relabelled"
    assert (again.folder.path / "trials.csv").read_bytes() == trials


def test_damaged_folders_and_runs_without_a_report_are_listed_as_such(write_config,
                                                                      tmp_path):
    """A run whose trials.csv had grown after it finished was listed `complete`; a folder
    with a cut manifest was left out of the list (and `runs` on it said `no runs`)."""
    cfg = write_config("experiment: toy_gaussian\ntrials: 4\nseed: 1\n", name="gauss")
    runners = [Runner(load(cfg, {"seed": seed}), tmp_path, progress=False, plots=plots)
               for seed, plots in ((1, True), (2, True), (3, True), (4, False))]
    for runner in runners:
        runner.run()
    grown, cut, intact, no_plots = (r.folder.path for r in runners)
    with open(grown / "trials.csv", "a") as fh:
        fh.write("garbage\n")
    manifest = (cut / "manifest.json").read_text()
    (cut / "manifest.json").write_text(manifest[: len(manifest) // 2])
    status = {r.path: r.status for r in find_runs(tmp_path)}
    assert status == {grown: DAMAGED, cut: DAMAGED, intact: "complete", no_plots: NO_REPORT}
    (intact / "index.html").unlink()  # stopped while drawing its report
    assert {r.path: r.status for r in find_runs(intact)} == {intact: NO_REPORT}
    listed = CliRunner().invoke(app, ["runs", str(cut)])
    assert listed.exit_code == 0 and DAMAGED in listed.stdout


def test_a_run_with_failed_trials_is_listed_with_their_count(write_config, tmp_path):
    """`trackfuse runs` listed a run with failed trials as `complete, no report`, as if every
    trial had given a result; its manifest says complete, with the failures counted."""
    cfg = write_config("experiment: toy_gaussian\ntrials: 12\nseed: 11\n"
                       "params: {fail_every: 3}\n", name="gauss")
    plotted = Runner(load(cfg), tmp_path, progress=False).run()
    bare = Runner(load(cfg, {"seed": 12}), tmp_path, progress=False, plots=False).run()
    assert plotted.failed_trials and bare.failed_trials
    status = {r.path: r.status for r in find_runs(tmp_path)}
    assert status == {plotted.folder: f"complete, {plotted.failed_trials} failed",
                      bare.folder: f"complete, {bare.failed_trials} failed, no report"}
    manifest = json.loads((bare.folder / "manifest.json").read_text())
    assert (manifest["status"], manifest["trials_failed"]) == ("complete", bare.failed_trials)
    listed = CliRunner().invoke(app, ["runs", str(tmp_path)])
    assert f"complete, {bare.failed_trials} failed, no report" in listed.stdout


def test_a_folder_this_user_may_not_read_is_skipped(write_config, tmp_path, monkeypatch):
    """`trackfuse runs /proc` ended in a PermissionError traceback (/proc/1/cwd); so would
    another user's folder under a shared results root."""
    cfg = write_config("experiment: toy_gaussian\ntrials: 4\nseed: 1\n", name="gauss")
    Runner(load(cfg), tmp_path / "out", progress=False, plots=False).run()
    (tmp_path / "out" / "locked").mkdir()
    is_dir = type(tmp_path).is_dir

    def refusing(path):
        if path.name == "locked":
            raise PermissionError(13, "Permission denied", str(path))
        return is_dir(path)

    monkeypatch.setattr(type(tmp_path), "is_dir", refusing)
    assert [r.stem for r in find_runs(tmp_path / "out")] == ["gauss"]


def test_runs_shows_markup_and_escape_sequences_in_names_as_text(write_config, tmp_path):
    """A --name of `[/]` crashed `trackfuse runs` (rich's MarkupError); `[bold red]`,
    `[link=...]` and raw escape sequences were rendered on the terminal."""
    cfg = write_config("experiment: toy_gaussian\ntrials: 2\nseed: 1\n", name="gauss")
    names = ["[/]", "[bold red]loud", "[link=http://e.x]c[/link]", "\x1b[31mred\x07"]
    for seed, name in enumerate(names):
        Runner(load(cfg, {"seed": seed}), tmp_path / "out", executor="serial", progress=False,
               plots=False, name=name).run()
    listed = CliRunner().invoke(app, ["runs", str(tmp_path / "out")])
    assert listed.exit_code == 0, listed.output
    assert "\x1b" not in listed.output
    for shown in names[:3] + ["\\x1b[31mred\\x07"]:
        assert shown in listed.output
