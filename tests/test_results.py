"""Resume state is verified, never trusted: damaged parts are recomputed, damaged final files
rebuilt, and what cannot be repaired is refused in one line (issue 14).

Every test starts from one finished reference run of a small toy config (2 sweep points x 10
trials in batches of 5: 4 batches, 8 part files, with a timings file) and checks the promise
of docs/runner.md, Resume: after any damage, re-running the same command either writes a
``trials.csv`` byte-identical to the reference or stops with one ``error:`` line (exit 2).
"""

from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest
from typer.testing import CliRunner

from trackfuse.config import load
from trackfuse.results import RunFolder, atomic_write
from trackfuse.runner import RunInterrupted, Runner
from trackfuse_cli.main import app

pytestmark = pytest.mark.slow  # every damage of every file of a run folder, each through a resume

CFG = """
experiment: toy_experiments:TIMED
trials: 10
seed: 7
params: {n: 3}
sweep: {mu: [0, 1]}
"""


def cli(*args) -> object:
    return CliRunner().invoke(app, [str(a) for a in args], catch_exceptions=True)


def check_contract(result, allowed=(0, 2)) -> None:
    """No traceback; stderr holds only ``warning:``/``error:`` lines; an error is one line."""
    assert result.exception is None or isinstance(result.exception, SystemExit), \
        repr(result.exception)
    assert result.exit_code in allowed, (result.exit_code, result.stdout, result.stderr)
    lines = result.stderr.strip().splitlines()
    assert all(line.startswith(("warning: ", "error: ")) for line in lines), result.stderr
    errors = [line for line in lines if line.startswith("error: ")]
    assert len(errors) == (result.exit_code == 2), result.stderr


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """A finished run: (config path, output root, run folder, trials.csv bytes).

    Its ``parts/`` are kept (the state of a run killed after its manifest said complete and
    before the resume state was dropped), so tests can damage them."""
    root = tmp_path_factory.mktemp("reference")
    config = root / "cfg.yaml"
    config.write_text(CFG)
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(RunFolder, "drop_resume_state", lambda self: None)
        outcome = Runner(load(config), root / "out", executor="serial", progress=False).run()
    return config, root / "out", outcome.folder, (outcome.folder / "trials.csv").read_bytes()


@pytest.fixture
def copy(reference, tmp_path):
    """A fresh copy of the reference output root; returns (config, out, folder)."""
    config, out, folder, _ = reference
    shutil.copytree(out, tmp_path / "out")
    return config, tmp_path / "out", tmp_path / "out" / folder.relative_to(out)


def as_interrupted(folder: Path) -> None:
    """Turn a finished folder into the state a run killed before its merge leaves."""
    for name in ("trials.csv", "timings.csv", "summary.csv", "timings_summary.csv"):
        (folder / name).unlink()
    manifest = json.loads((folder / "manifest.json").read_text())
    manifest["status"] = "interrupted"
    manifest.pop("files")
    (folder / "manifest.json").write_text(json.dumps(manifest))


def rerun(config: Path, out: Path):
    return cli("run", config, "--out", out, "--executor", "serial", "--no-progress",
               "--no-plots")


def part(folder: Path, point: int, batch: int, kind: str = "trials") -> Path:
    return folder / "parts" / f"p{point:06d}-b{batch:07d}.{kind}.csv"


def resumes_to_reference(config, out, folder, want: bytes, warning: str = "") -> None:
    result = rerun(config, out)
    check_contract(result, allowed=(0,))
    assert warning in result.stderr
    assert (folder / "trials.csv").read_bytes() == want
    assert json.loads((folder / "manifest.json").read_text())["status"] == "complete"


# -- the cases of the issue, one by one --------------------------------------------------------
def _cut_mid_row(path: Path) -> None:
    data = path.read_bytes()
    path.write_bytes(data[:len(data) - 7])


def _swap(a: Path, b: Path) -> None:
    data = a.read_bytes()
    a.write_bytes(b.read_bytes())
    b.write_bytes(data)


def _flip_one_byte(path: Path) -> None:
    data = bytearray(path.read_bytes())
    data[-3] = ord("7") if data[-3] != ord("7") else ord("8")  # same size, other digit
    path.write_bytes(bytes(data))


DAMAGE = {
    "part emptied": (lambda f: part(f, 0, 1).write_bytes(b""), "no valid part header"),
    "part cut to its header line": (
        lambda f: part(f, 0, 1).write_bytes(part(f, 0, 1).read_bytes().split(b"\n")[0] + b"\n"),
        "bytes of CSV where"),
    "part cut in the middle of a row": (lambda f: _cut_mid_row(part(f, 1, 0)),
                                        "bytes of CSV where"),
    "two parts swapped": (lambda f: _swap(part(f, 0, 0), part(f, 1, 1)), "not this batch"),
    "part of random bytes": (lambda f: part(f, 1, 1).write_bytes(os.urandom(300)),
                             "no valid part header"),
    "part with one digit changed (same size)": (lambda f: _flip_one_byte(part(f, 0, 1)),
                                                "checksum differs"),
    "timings part emptied": (lambda f: part(f, 1, 0, "timings").write_bytes(b""),
                             "no valid part header"),
    "stray copy in parts/": (
        lambda f: shutil.copy(part(f, 0, 1), f / "parts" / "p000000-b0000001 (copy).trials.csv"),
        "ignoring files that are not parts of this run: p000000-b0000001 (copy).trials.csv"),
    "binary manifest.json": (lambda f: (f / "manifest.json").write_bytes(os.urandom(200)),
                             "manifest.json: not a trackfuse manifest"),
    "manifest.json a JSON list": (lambda f: (f / "manifest.json").write_text("[1, 2]"),
                                  "manifest.json: not a trackfuse manifest"),
}


@pytest.mark.parametrize("case", sorted(DAMAGE))
def test_a_damaged_resume_state_is_repaired_with_a_warning(case, copy, reference):
    config, out, folder = copy
    as_interrupted(folder)
    damage, warning = DAMAGE[case]
    damage(folder)
    resumes_to_reference(config, out, folder, reference[3], warning)


def test_a_damaged_manifest_is_replaced_when_the_report_is_drawn(copy, reference):
    """Every part is there, the manifest is not: the runner warns that it writes a new one
    and must finish the run with its report too (not refuse the damaged manifest when it
    opens the run folder for the report)."""
    config, out, folder = copy
    as_interrupted(folder)
    (folder / "manifest.json").write_text("[1, 2]")
    result = cli("run", config, "--out", out, "--executor", "serial", "--no-progress")
    check_contract(result, allowed=(0,))
    assert "manifest.json: not a trackfuse manifest" in result.stderr
    assert (folder / "trials.csv").read_bytes() == reference[3]
    assert json.loads((folder / "manifest.json").read_text())["status"] == "complete"


def test_parts_being_a_file_is_refused_in_one_line(copy, reference):
    config, out, folder = copy
    as_interrupted(folder)
    shutil.rmtree(folder / "parts")
    (folder / "parts").write_text("not a folder")
    result = rerun(config, out)
    check_contract(result, allowed=(2,))
    assert "parts: exists but is not a folder" in result.stderr
    (folder / "parts").unlink()
    resumes_to_reference(config, out, folder, reference[3])


def test_a_truncated_trials_csv_is_refused_by_plot_and_rebuilt_by_run(copy, reference):
    config, out, folder = copy
    data = (folder / "trials.csv").read_bytes()
    (folder / "trials.csv").write_bytes(data[: len(data) // 2])
    result = cli("plot", folder)
    check_contract(result, allowed=(2,))
    assert "trials.csv: does not match the size and checksum in manifest.json" in result.stderr
    resumes_to_reference(config, out, folder, reference[3], "rebuilding the final files")
    check_contract(cli("plot", folder), allowed=(0,))


def test_temporaries_of_a_killed_run_are_removed_on_resume(copy, reference):
    config, out, folder = copy
    as_interrupted(folder)
    (folder / "tables").mkdir(exist_ok=True)
    leftovers = [folder / "figures" / ".estimate.tmp.png",  # runner figures
                 folder / "figures" / ".estimate.4242.tmp.pdf",  # reports.py figures
                 folder / "tables" / ".table.csv.4242.tmp",  # atomic_write
                 folder / "parts" / ".p000000-b0000000.trials.csv.4242.tmp",
                 folder / ".trials.csv.4242.tmp"]
    for path in leftovers:
        path.write_text("half written")
    keep = folder / "tables" / "notes.txt"
    keep.write_text("mine")
    resumes_to_reference(config, out, folder, reference[3])
    assert not any(path.exists() for path in leftovers) and keep.read_text() == "mine"


@pytest.mark.parametrize("stage", ["merge", "summary", "figures"])
def test_ctrl_c_during_the_finish_leaves_an_interrupted_run_that_resumes(
        stage, copy, reference, monkeypatch):
    config, out, folder = copy
    as_interrupted(folder)
    target = {"merge": (RunFolder, "merge"), "summary": ("trackfuse.finish.summarize", None),
              "figures": ("trackfuse.runner.write_report", None)}[stage]

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    if target[1] is None:
        monkeypatch.setattr(target[0], interrupt)
    else:
        monkeypatch.setattr(*target, interrupt)
    result = cli("run", config, "--out", out, "--executor", "serial", "--no-progress")
    assert result.exit_code == 130, result.stderr
    assert result.stderr.startswith("interrupted: 20/20 trials saved in ")
    assert "run the same command again to resume" in result.stderr
    assert json.loads((folder / "manifest.json").read_text())["status"] == "interrupted"
    assert not list(folder.glob(".*.tmp"))
    monkeypatch.undo()
    resumes_to_reference(config, out, folder, reference[3])


def test_ctrl_c_in_the_runner_api_raises_run_interrupted(copy, monkeypatch):
    config, out, folder = copy
    as_interrupted(folder)

    def interrupt(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr("trackfuse.finish.summarize", interrupt)
    with pytest.raises(RunInterrupted) as err:
        Runner(load(config), out, executor="serial", progress=False).run()
    assert err.value.done == err.value.total == 20


# -- the tamper matrix -----------------------------------------------------------------------
def _directory(path: Path) -> None:
    path.unlink()
    path.mkdir()
    (path / "inside").write_text("x")


TAMPER = {
    "deleted": lambda p: p.unlink(),
    "emptied": lambda p: p.write_bytes(b""),
    "halved": lambda p: p.write_bytes(p.read_bytes()[: p.stat().st_size // 2]),
    "first line only": lambda p: p.write_bytes(p.read_bytes().split(b"\n")[0] + b"\n"),
    "random bytes": lambda p: p.write_bytes(os.urandom(max(p.stat().st_size, 1))),
    "one byte changed": lambda p: p.write_bytes(bytes(
        [b ^ 0x01 if i == p.stat().st_size // 2 else b
         for i, b in enumerate(p.read_bytes())])),
    "a directory": _directory,
}


def _files(folder: Path) -> list[str]:
    return sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())


def test_the_reference_folder_holds_every_kind_of_file(reference):
    names = _files(reference[2])
    for expected in ("config.yaml", "manifest.json", "trials.csv", "timings.csv", "summary.csv",
                     "timings_summary.csv", "figures/estimate.png", ".lock", "index.md",
                     "index.html", "parts/p000001-b0000001.timings.csv",
                     "tables/paper_vs_reproduced.csv", "notes/twin_sensor.html"):
        assert expected in names
    assert len(names) == 8 + 2 + 2 + 2 + 1 + 7  # files, figures, index, table, note, parts


@pytest.mark.parametrize("state", ["complete", "interrupted"])
@pytest.mark.parametrize("tamper", sorted(TAMPER))
def test_tamper_matrix_every_file_every_damage(state, tamper, reference, tmp_path):
    """For every file of a run folder and every damage: the re-run gives the reference bytes,
    or one error line; after removing what it names, the re-run gives the reference bytes."""
    config, out, folder, want = reference
    for name in _files(folder):
        if state == "interrupted" and name in ("trials.csv", "timings.csv", "summary.csv",
                                               "timings_summary.csv"):
            continue
        root = tmp_path / f"{len(list(tmp_path.iterdir()))}"
        shutil.copytree(out, root)
        copied = root / folder.relative_to(out)
        if state == "interrupted":
            as_interrupted(copied)
        TAMPER[tamper](copied / name)
        result = rerun(config, root)
        check_contract(result)
        if result.exit_code == 2:
            damaged = copied / name
            shutil.rmtree(damaged) if damaged.is_dir() else damaged.unlink(missing_ok=True)
            result = rerun(config, root)
            check_contract(result, allowed=(0,))
        assert (copied / "trials.csv").read_bytes() == want, (name, result.stderr)
        manifest = json.loads((copied / "manifest.json").read_text())
        assert manifest["status"] == "complete", name


def test_a_complete_run_keeps_no_second_copy_and_still_refuses_to_recompute(tmp_path):
    config = tmp_path / "cfg.yaml"
    config.write_text(CFG)
    first = Runner(load(config), tmp_path / "out", executor="serial", progress=False,
                   plots=False).run()
    assert not (first.folder / "parts").exists()
    again = Runner(load(config), tmp_path / "out", executor="serial", progress=False,
                   plots=False).run()
    assert again.status == "already complete" and again.computed_trials == 0
    want = (first.folder / "trials.csv").read_bytes()
    (first.folder / "trials.csv").write_bytes(want[:-5])
    warnings = []
    repaired = Runner(load(config), tmp_path / "out", executor="serial", progress=False,
                      plots=False, warn=warnings.append).run()
    assert repaired.computed_trials == repaired.total_trials
    assert (first.folder / "trials.csv").read_bytes() == want
    assert any("rebuilding the final files" in w for w in warnings)


def test_a_write_that_fails_leaves_no_temporary_file_and_names_its_target(tmp_path):
    """`plot` of a run whose index.html was a folder left `.index.html.<pid>.tmp` behind and
    named that temporary file in its error."""
    target = tmp_path / "index.html"
    target.mkdir()
    with pytest.raises(IsADirectoryError) as caught:
        atomic_write(target, "<html>")
    assert caught.value.filename == str(target)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["index.html"]
