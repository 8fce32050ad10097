"""trackfuse.runstate: `runs`, `plot`, `compare` and `run` agree on a run's state."""

from __future__ import annotations

import json
import shutil

import pytest
from typer.testing import CliRunner

from trackfuse.catalog import find_runs
from trackfuse.config import load
from trackfuse.runner import Runner
from trackfuse_cli.main import app

CFG = "experiment: toy_gaussian\ntrials: 4\nseed: 1\n"


def _cli(*args):
    return CliRunner().invoke(app, [str(a) for a in args])


def test_a_killed_run_is_stopped_for_runs_plot_and_compare(write_config, tmp_path):
    """After kill -9, `runs` said stopped while `plot` and `compare` said `run is running`
    (and to run the command again, which a running run would refuse)."""
    cfg = write_config(CFG)
    base = Runner(load(cfg), tmp_path / "a", progress=False, plots=False).run().folder
    killed = Runner(load(cfg), tmp_path / "b", progress=False, plots=False).run().folder
    manifest = json.loads((killed / "manifest.json").read_text())
    (killed / "manifest.json").write_text(json.dumps({**manifest, "status": "running"}))
    assert find_runs(killed)[0].status == "stopped"  # no live process holds it
    plotted, compared = _cli("plot", killed), _cli("compare", base, killed)
    for result in (plotted, compared):
        assert result.exit_code == 2
        assert f"{killed}: run is stopped, not complete; its process ended" in result.stderr
        assert "run is running" not in result.stderr


def test_a_run_whose_report_files_were_removed_has_no_report_until_redrawn(write_config,
                                                                          tmp_path):
    """Deleting figures/ left a run listed `complete` with an index of missing images, and
    `trackfuse run` again found nothing to draw."""
    cfg = write_config(CFG)
    folder = Runner(load(cfg), tmp_path, progress=False).run().folder
    assert find_runs(tmp_path)[0].status == "complete"
    shutil.rmtree(folder / "figures")
    assert find_runs(tmp_path)[0].status == "complete, no report"
    again = Runner(load(cfg), tmp_path, progress=False).run()
    assert again.status == "already complete" and again.report is not None
    assert (folder / "figures" / "estimate.png").exists()
    assert find_runs(tmp_path)[0].status == "complete"
    (folder / "tables" / "paper_vs_reproduced.md").unlink()
    assert find_runs(tmp_path)[0].status == "complete, no report"
    assert _cli("plot", folder).exit_code == 0
    assert find_runs(tmp_path)[0].status == "complete"


@pytest.mark.parametrize("status", [None, "", "finished"])
def test_a_manifest_without_a_known_status_is_damaged(status, write_config, tmp_path):
    """A manifest without a status was listed with an empty status (and `plot` said "run is
    , not complete"): it is damaged, and the same run command rebuilds it."""
    cfg = write_config(CFG)
    folder = Runner(load(cfg), tmp_path, progress=False, plots=False).run().folder
    manifest = json.loads((folder / "manifest.json").read_text())
    manifest.pop("status")
    (folder / "manifest.json").write_text(json.dumps(
        manifest if status is None else {**manifest, "status": status}))
    assert find_runs(tmp_path)[0].status == "damaged"
    plotted = _cli("plot", folder)
    assert plotted.exit_code == 2
    assert plotted.stderr.startswith(f"error: {folder / 'manifest.json'}: status ")
    again = Runner(load(cfg), tmp_path, progress=False, plots=False).run()
    assert again.folder == folder and find_runs(tmp_path)[0].status == "complete, no report"
