"""The run record (trackfuse.manifest): manifests written before the Manifest type read back
and write back byte for byte; the runner writes the same keys in the same order; a damaged or
foreign manifest.json is refused by every reader in one line naming the file and the key."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest
from conftest import ROOT
from typer.testing import CliRunner

from trackfuse.catalog import find_runs
from trackfuse.config import load as load_config
from trackfuse.manifest import Manifest, ManifestError, read_manifest, write_manifest
from trackfuse.rundata import load
from trackfuse.runner import Runner
from trackfuse.runstate import DAMAGED
from trackfuse_cli.main import app

BEFORE = ROOT / "tests" / "manifests" / "complete_sequential.json"
CFG = ("experiment: toy_experiments:GAUSSIAN\nseed: 4\n"
       "trials: {min: 20, max: 200, until: {metric: estimate, half_width: 0.2}}\n"
       "sweep: {sigma: [0.5, 1.0]}\n")


def test_a_manifest_written_before_the_type_reads_and_writes_back_byte_for_byte(tmp_path):
    (tmp_path / "manifest.json").write_bytes(BEFORE.read_bytes())
    manifest = read_manifest(tmp_path)
    assert manifest.status == "complete" and manifest.trials_done == 42
    assert manifest.sequential["trials"] == [21, 21] and manifest.extra == {}
    out = tmp_path / "again"
    out.mkdir()
    write_manifest(out, manifest)
    assert (out / "manifest.json").read_bytes() == BEFORE.read_bytes()


def test_the_runner_writes_the_keys_it_wrote_before_in_the_same_order(write_config, tmp_path):
    config = load_config(write_config(CFG, "seq"))
    outcome = Runner(config, tmp_path, progress=False, executor="serial").run()
    written = json.loads((outcome.folder / "manifest.json").read_text())
    assert list(written) == list(json.loads(BEFORE.read_text()))
    assert written["files"].keys() == json.loads(BEFORE.read_text())["files"].keys()


def test_keys_of_a_newer_version_are_kept(tmp_path):
    text = json.dumps({"status": "interrupted", "name": None, "plugin_folder": None,
                       "git": None, "trials_done": 3, "finished": None,
                       "from_the_future": [1]})
    (tmp_path / "manifest.json").write_text(text)
    manifest = read_manifest(tmp_path)
    assert manifest.extra == {"from_the_future": [1]} and manifest.trials_done == 3
    write_manifest(tmp_path, manifest)
    assert json.loads((tmp_path / "manifest.json").read_text()) == json.loads(text)


@pytest.mark.parametrize(("content", "key"), [
    ({"name": "x"}, "status"),  # a foreign JSON object: no status
    ({"status": "done"}, "status"),
    ({"status": "complete", "trials_failed": "3"}, "trials_failed"),
    ({"status": "complete", "trials_done": True}, "trials_done"),
    ({"status": "complete", "report_files": "index.html"}, "report_files"),
    ({"status": "complete", "draw_points": [0, 1.5]}, "draw_points"),
    ({"status": "running", "per_point_wall_s": {"0": "fast"}}, "per_point_wall_s"),
    ({"status": "complete", "files": []}, "files"),
    ([1, 2], None),
])
def test_a_damaged_or_foreign_manifest_is_one_error_naming_the_key(content, key, tmp_path):
    (tmp_path / "manifest.json").write_text(json.dumps(content))
    with pytest.raises(ManifestError) as caught:
        read_manifest(tmp_path)
    assert caught.value.key == key and caught.value.source == tmp_path / "manifest.json"
    assert "\n" not in str(caught.value)


@pytest.fixture(scope="module")
def finished(tmp_path_factory):
    out = tmp_path_factory.mktemp("finished")
    (out / "seq.yaml").write_text(CFG)
    return Runner(load_config(out / "seq.yaml"), out / "out", progress=False,
                  executor="serial").run().folder


def test_every_reader_refuses_a_manifest_with_a_key_of_the_wrong_type(finished, tmp_path):
    """plot, load, runs and a resumed run: one line naming manifest.json and the key."""
    folder = tmp_path / "out" / "seq" / finished.name
    shutil.copytree(finished, folder)
    recorded = json.loads((folder / "manifest.json").read_text())
    (folder / "manifest.json").write_text(json.dumps({**recorded, "trials_failed": "none"}))
    with pytest.raises(ManifestError) as caught:
        load(folder)
    assert caught.value.key == "trials_failed"
    plotted = CliRunner().invoke(app, ["plot", str(folder)])
    assert plotted.exit_code != 0 and plotted.stderr.count("\n") == 1
    assert f"{folder / 'manifest.json'}: trials_failed" in plotted.stderr
    assert [run.status for run in find_runs(tmp_path / "out")] == [DAMAGED]


def test_a_record_round_trips_through_its_json(tmp_path):
    manifest = Manifest("running", run_id="seed1-abc", command=["trackfuse", "run"],
                        per_point_wall_s={"0": 1.5}, cluster={"kind": "local"})
    write_manifest(tmp_path, manifest)
    assert read_manifest(tmp_path) == manifest
    assert "rows" not in json.loads(Path(tmp_path / "manifest.json").read_text())
