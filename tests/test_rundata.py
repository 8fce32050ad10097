"""``trackfuse plot`` on damaged or foreign folders: a one-line error (exit 2), never a
traceback, and never figures drawn from files that do not match the manifest (issue 14)."""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from trackfuse import rundata
from trackfuse.config import ConfigError, load, read_yaml
from trackfuse.results import RunFolderError
from trackfuse.runner import Runner
from trackfuse.safe_yaml import MAX_BYTES
from trackfuse_cli.main import app

CFG = """
experiment: toy_experiments:GAUSSIAN
trials: 6
seed: 2
params: {n: 3}
sweep: {mu: [0, 1]}
outputs: {formats: [png]}
"""


def plot(folder: Path):
    return CliRunner().invoke(app, ["plot", str(folder)], catch_exceptions=True)


def check(result, allowed=(0, 1, 2)) -> None:
    assert result.exception is None or isinstance(result.exception, SystemExit), \
        repr(result.exception)
    assert result.exit_code in allowed, (result.exit_code, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert all(line.startswith(("warning: ", "error: ")) for line in lines), result.stderr
    if result.exit_code == 2:
        assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr


@pytest.fixture(scope="module")
def finished(tmp_path_factory) -> Path:
    root = tmp_path_factory.mktemp("plot")
    (root / "cfg.yaml").write_text(CFG)
    return Runner(load(root / "cfg.yaml"), root / "out", executor="serial",
                  progress=False).run().folder


def _replace(path: Path, data: bytes | None) -> None:
    """Write ``data`` at ``path`` (``None``: make it a directory)."""
    if path.is_dir():
        shutil.rmtree(path)
    elif path.exists():
        path.unlink()
    if data is None:
        path.mkdir()
    else:
        path.write_bytes(data)


def _config_without_experiment(folder: Path) -> bytes:
    return b"\n".join(line for line in (folder / "config.yaml").read_bytes().splitlines()
                      if not line.startswith(b"experiment:")) + b"\n"


CASES = {
    "manifest is a list": ("manifest.json", lambda f: b"[1, 2, 3]", "not a trackfuse manifest"),
    "manifest is a string": ("manifest.json", lambda f: b'"complete"',
                             "not a trackfuse manifest"),
    "manifest is binary": ("manifest.json", lambda f: bytes(range(256)),
                           "not a trackfuse manifest"),
    "manifest is a directory": ("manifest.json", lambda f: None, "manifest.json: unreadable"),
    "config missing": ("config.yaml", "delete", "config.yaml: missing"),
    "config is a list": ("config.yaml", lambda f: b"- 1\n- 2\n", "config.yaml: does not match"),
    "config lacks experiment": ("config.yaml", _config_without_experiment,
                                "config.yaml: does not match"),
    "config names an unknown experiment": (
        "config.yaml",
        lambda f: (f / "config.yaml").read_bytes().replace(b"toy_experiments:GAUSSIAN",
                                                           b"toy_experiments:NOPE"),
        "config.yaml: does not match"),
    "config is not YAML": ("config.yaml", lambda f: b"experiment: [unclosed\n",
                           "config.yaml: does not match"),
    "trials missing": ("trials.csv", "delete", "trials.csv: missing"),
    "trials empty": ("trials.csv", lambda f: b"", "trials.csv: does not match"),
    "trials ragged": ("trials.csv", lambda f: (f / "trials.csv").read_bytes() + b"1,2\n",
                      "trials.csv: does not match"),
    "trials garbage": ("trials.csv", lambda f: os.urandom(500), "trials.csv: does not match"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_plot_on_a_damaged_folder_is_one_line(case, finished, tmp_path):
    folder = tmp_path / "run"
    shutil.copytree(finished, folder)
    name, make, expected = CASES[case]
    if make == "delete":
        (folder / name).unlink()
    else:
        _replace(folder / name, make(folder))
    result = plot(folder)
    check(result, allowed=(2,))
    assert expected in result.stderr, result.stderr
    assert not (folder / "figures" / "estimate.png").exists() or \
        (folder / "figures" / "estimate.png").read_bytes() == \
        (finished / "figures" / "estimate.png").read_bytes()


def test_plot_on_a_plain_file_is_one_line(tmp_path):
    path = tmp_path / "file.csv"
    path.write_text("a,b\n1,2\n")
    result = plot(path)
    check(result, allowed=(2,))
    assert "not a run folder" in result.stderr


def _forge(folder: Path, name: str) -> None:
    """Make the manifest's checksum of ``name`` match its (damaged) content."""
    manifest = json.loads((folder / "manifest.json").read_text())
    data = (folder / name).read_bytes()
    manifest["files"][name] = {"bytes": len(data), "sha256": hashlib.sha256(data).hexdigest()}
    (folder / "manifest.json").write_text(json.dumps(manifest))


FORGED = {"config is a list": "not a trackfuse run's config",
          "config lacks experiment": "not a trackfuse run's config",
          "config names an unknown experiment": "toy_experiments does not define NOPE",
          "config is not YAML": "config.yaml: unreadable (invalid YAML"}


@pytest.mark.parametrize("case", sorted(FORGED))
def test_plot_on_a_bad_config_with_a_forged_checksum_is_one_line(case, finished, tmp_path):
    """The same config damage with the manifest's checksum updated to match it: the config's
    own checks still refuse it in one line."""
    folder = tmp_path / "run"
    shutil.copytree(finished, folder)
    name, make, _ = CASES[case]
    _replace(folder / name, make(folder))
    _forge(folder, name)
    result = plot(folder)
    check(result, allowed=(2,))
    assert FORGED[case] in result.stderr, result.stderr


def test_an_oversize_config_is_refused_by_plot_as_by_validate(finished, tmp_path):
    """The run folder's reader read MAX_BYTES + 1 bytes and parsed them without checking
    the size: padded with two-byte characters cut on a character boundary, a config larger
    than MAX_BYTES was read truncated (here: the saved config, plotted without a word)."""
    folder = tmp_path / "run"
    shutil.copytree(finished, folder)
    head = (folder / "config.yaml").read_bytes() + b"#"
    head += b" " * ((MAX_BYTES + 1 - len(head)) % 2)  # the cut falls between characters
    (folder / "config.yaml").write_bytes(head + "é".encode() * (MAX_BYTES // 2) + b"\n")
    _forge(folder, "config.yaml")
    result = plot(folder)
    check(result, allowed=(2,))
    assert f"config.yaml: unreadable (larger than {MAX_BYTES} bytes" in result.stderr
    with pytest.raises(RunFolderError, match="unreadable \\(larger than"):
        rundata.load(folder)
    with pytest.raises(ConfigError, match=f"config.yaml: larger than {MAX_BYTES} bytes"):
        read_yaml(folder / "config.yaml")


@pytest.mark.parametrize("data", [b"", b"point,trial\n1\n", bytes(range(256)) * 3,
                                  b"pt,trial,mu,algorithm,estimate\n0,0,0,mean,0.5\n"])
def test_plot_of_forged_garbage_trials_refuses_and_removes_the_old_report(data, finished,
                                                                          tmp_path):
    """If the manifest was forged to match a garbage trials.csv (a renamed column, no rows),
    plot printed a raw warning per figure and table (KeyError: 'point') and left the old
    figures and tables in place, so the folder looked complete. Now: one line naming
    trials.csv, and no report file left that could pass for this data's."""
    folder = tmp_path / "run"
    shutil.copytree(finished, folder)
    assert any((folder / "figures").iterdir()) and any((folder / "tables").iterdir())
    (folder / "trials.csv").write_bytes(data)
    _forge(folder, "trials.csv")
    result = plot(folder)
    check(result, allowed=(2,))
    assert "trials.csv" in result.stderr and "the earlier report was removed" in result.stderr
    assert not any((folder / "figures").iterdir()) and not any((folder / "tables").iterdir())
    assert not (folder / "index.html").exists() and not (folder / "index.md").exists()


@pytest.mark.parametrize("outputs", ["outputs: fig\n", "outputs: [png]\n",
                                     "outputs: {figures: 5}\n", "outputs: {formats: png}\n"])
def test_a_config_whose_outputs_is_no_mapping_fails_plot_in_one_line(outputs, finished,
                                                                      tmp_path):
    """A config.yaml cut inside `outputs` (found by the fuzz test below) made plot fail with
    "'str' object has no attribute 'get'"."""
    folder = tmp_path / "run"
    shutil.copytree(finished, folder)
    config = (folder / "config.yaml").read_text()
    (folder / "config.yaml").write_text(config[: config.index("outputs:")] + outputs)
    _forge(folder, "config.yaml")
    result = plot(folder)
    check(result)
    assert result.exit_code == 2 and "outputs not a mapping" in result.stderr


json_values = st.recursive(st.one_of(st.none(), st.booleans(), st.integers(), st.text(max_size=8),
                                     st.floats(allow_nan=False)),
                           lambda inner: st.one_of(st.lists(inner, max_size=3),
                                                   st.dictionaries(st.text(max_size=8), inner,
                                                                   max_size=3)),
                           max_leaves=8)
contents = st.one_of(
    st.just("keep"), st.just("keep"), st.just("keep"), st.just("delete"), st.just("directory"),
    st.binary(max_size=300),
    json_values.map(lambda v: json.dumps(v).encode()),
    st.integers(0, 2000).map(lambda cut: ("cut", cut)),
    st.sampled_from([b"", b"status: complete\n", b"experiment: toy_gaussian\nparams: {}\n",
                     b"point,trial\n1\n", b"&a [*a]\n"]))


def _apply(folder: Path, name: str, content, forge: bool) -> None:
    path = folder / name
    if content == "keep":
        return
    if content == "delete":
        path.unlink()
        return
    if content == "directory":
        _replace(path, None)
        return
    if isinstance(content, tuple):
        content = path.read_bytes()[: content[1]]
    path.write_bytes(content)
    if forge and name != "manifest.json":
        _forge(folder, name)


@settings(max_examples=120, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(manifest=contents, config=contents, trials=contents, summary=contents,
       forge=st.booleans())
@pytest.mark.slow
def test_fuzzed_run_folders_plot_or_fail_in_one_line(manifest, config, trials, summary, forge,
                                                     finished):
    """Random replacements of the files plot reads, with or without a manifest forged to
    match them: exit 0, 1 (a figure failed, with warnings) or 2 (one line), no traceback."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) / "run"
        shutil.copytree(finished, folder)
        for name, content in (("config.yaml", config), ("trials.csv", trials),
                              ("summary.csv", summary)):
            _apply(folder, name, content, forge and (folder / "manifest.json").is_file())
        _apply(folder, "manifest.json", manifest, False)
        check(plot(folder))


def test_timings_are_read_through_the_run(finished, tmp_path):
    """timings.csv is read by the run (one-line errors), empty when the run timed nothing;
    passive_assoc's scale figure read it with pandas itself."""
    assert rundata.load(finished).timings.empty
    (tmp_path / "cfg.yaml").write_text(CFG.replace("GAUSSIAN", "TIMED"))
    timed = Runner(load(tmp_path / "cfg.yaml"), tmp_path / "out", executor="serial",
                   progress=False, plots=False).run().folder
    timings = rundata.load(timed).timings
    assert len(timings) == 24 and (timings["estimate_time_s"] > 0).all()  # 2 algorithms
    assert list(timings[["point", "trial"]].drop_duplicates().itertuples(index=False)) == \
        [(p, t) for p in range(2) for t in range(6)]
