"""The tamper matrix (#37): every damage done to a complete run folder, against every command
that reads or writes run folders.

Whatever the damage, each command must end (a FIFO must not hang it), say what is wrong in
one line (no traceback, exit 0-3), write and delete nothing outside the run folder (never
through a link), keep every file it did not write, and never record fewer saved trials than
the folder holds. A new attack is one line in :data:`DAMAGES`; a new command one line in
:data:`COMMANDS`. The commands run in this process (the matrix is large), under an alarm
that turns a hang into a failure.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import signal
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import pytest
from typer.testing import CliRunner

from trackfuse.config import load
from trackfuse.runner import Runner
from trackfuse_cli.main import app

pytestmark = pytest.mark.slow  # every damage against every command

CONFIG = "experiment: toy_experiments:GAUSSIAN\ntrials: 6\nseed: 1\nsweep: {mu: [0, 1]}\n"
#: Seconds a command may take before it counts as hung (each takes well under one).
HANG_S = 30
#: Files of the folder outside every run, which no command may touch (names that the
#: report writes or that an old cleanup's patterns matched).
OUTSIDE = {"keep.csv": "a,b\n1,2\n", "keep.md": "# notes\n", "estimate.png": "not a png",
           "p000000-b0000000.trials.csv": "not a part\n", "paper_vs_reproduced.csv": "x\n"}


class Hang(BaseException):
    """A command still running after :data:`HANG_S` seconds."""


@contextmanager
def deadline(seconds: int) -> Iterator[None]:
    """Raise :class:`Hang` in the block after ``seconds`` (a blocked ``open`` included)."""
    def expire(signum, frame):
        raise Hang(f"still running after {seconds} s")

    before = signal.signal(signal.SIGALRM, expire)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, before)


@dataclass
class Scene:
    """A copy of the complete run, its config, and a folder outside it."""

    out: Path
    run: Path
    cfg: Path
    outside: Path
    kept: dict[Path, bytes] = field(default_factory=dict)  # files of the user's, and bytes

    def keep(self, path: Path, text: str) -> None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
        self.kept[path] = path.read_bytes()

    def manifest(self) -> dict | None:
        path = self.run / "manifest.json"
        return json.loads(path.read_text()) if path.is_file() and not path.is_symlink() \
            else None

    def edit_manifest(self, **changes) -> None:
        (self.run / "manifest.json").write_text(json.dumps({**self.manifest(), **changes}))


# -- damages: each changes the scene in place ---------------------------------------------
def link_out(name: str) -> Callable[[Scene], None]:
    """Replace the run's folder ``name`` by a link to the outside folder."""
    def damage(s: Scene) -> None:
        shutil.rmtree(s.run / name, ignore_errors=True)
        (s.run / name).symlink_to(s.outside, target_is_directory=True)
    return damage


def file_link_out(name: str, target: str) -> Callable[[Scene], None]:
    """Replace the run's file ``name`` by a link to a file outside."""
    def damage(s: Scene) -> None:
        (s.run / name).unlink(missing_ok=True)
        (s.run / name).symlink_to(s.outside / target)
    return damage


def user_file(name: str) -> Callable[[Scene], None]:
    """A file of the user's in the run folder, which must survive every command."""
    return lambda s: s.keep(s.run / name, f"the user's own {name}\n")


def fifo(name: str) -> Callable[[Scene], None]:
    """A FIFO (no writer ever comes) in place of ``name``."""
    def damage(s: Scene) -> None:
        path = s.run / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.unlink(missing_ok=True)
        os.mkfifo(path)
    return damage


def status(value: str) -> Callable[[Scene], None]:
    """The run's manifest says ``value`` (a stopped or running run, resumed from parts/)."""
    return lambda s: s.edit_manifest(status=value)


def both(*damages: Callable[[Scene], None]) -> Callable[[Scene], None]:
    def damage(s: Scene) -> None:
        for one in damages:
            one(s)
    return damage


def report_files_outside(s: Scene) -> None:
    """A manifest whose report_files names files outside the run folder (and its data)."""
    s.edit_manifest(report_files=[f"../../../outside/{n}" for n in OUTSIDE]
                    + [str(s.outside / "keep.md"), "figures/../../../../outside/keep.csv",
                       "trials.csv", "config.yaml", "figures", "tables/"])


DAMAGES: dict[str, Callable[[Scene], None]] = {
    "tables/ a link out": link_out("tables"),
    "figures/ a link out": link_out("figures"),
    "parts/ a link out": link_out("parts"),
    "parts/ a link out, run stopped": both(status("running"), link_out("parts")),
    "a table file a link out": file_link_out("tables/paper_vs_reproduced.csv", "keep.csv"),
    "a figure file a link out": file_link_out("figures/estimate.png", "estimate.png"),
    "index.html a link out": file_link_out("index.html", "keep.md"),
    "manifest.json a link out": file_link_out("manifest.json", "keep.md"),
    "trials.csv a link out": file_link_out("trials.csv", "keep.csv"),
    "config.yaml a link out": file_link_out("config.yaml", "keep.md"),
    "the lock file a link out": file_link_out(".lock", "keep.csv"),
    "the lock's holder file a link out": file_link_out(".lock.holder.json", "keep.md"),
    "user file in tables/": user_file("tables/my_notes.md"),
    "user file in figures/, a figure's name in another format": user_file(
        "figures/estimate.svg"),
    "user file in parts/": user_file("parts/mine.txt"),
    "user file in parts/, run stopped": both(status("running"), user_file("parts/mine.txt")),
    "report_files naming files outside": report_files_outside,
    "FIFO as manifest.json": fifo("manifest.json"),
    "FIFO in parts/, run stopped": both(status("running"),
                                        fifo("parts/p000000-b0000000.trials.csv")),
    "FIFO as config.yaml": fifo("config.yaml"),
    "FIFO as timings_summary.csv": fifo("timings_summary.csv"),
    "FIFO as the lock's holder file, run stopped": both(status("running"),
                                                        fifo(".lock.holder.json")),
    "FIFO as the lock file": fifo(".lock"),
    "FIFO as a sibling run's manifest": fifo("../seed9-0000000000/manifest.json"),
}

SERIAL = ("--executor", "serial", "--no-progress")
COMMANDS: dict[str, Callable[[Scene], list]] = {
    "plot": lambda s: ["plot", s.run],
    "run (resume)": lambda s: ["run", s.cfg, "--out", s.out, *SERIAL],
    "run --force": lambda s: ["run", s.cfg, "--out", s.out, "--force", *SERIAL],
    "run, another seed": lambda s: ["run", s.cfg, "--out", s.out, "--set", "seed=2", *SERIAL],
    "run --dry-run": lambda s: ["run", s.cfg, "--out", s.out, "--dry-run"],
    "runs": lambda s: ["runs", s.out],
    "compare": lambda s: ["compare", s.run, s.run],
    "validate the run's config.yaml": lambda s: ["validate", s.run / "config.yaml"],
    "run the run's config.yaml --dry-run": lambda s: ["run", s.run / "config.yaml", "--out",
                                                      s.out, "--dry-run"],
}


@pytest.fixture(scope="module")
def complete_run(tmp_path_factory) -> tuple[Path, Path]:
    """``(output root, run folder)`` of a complete run with its report."""
    root = tmp_path_factory.mktemp("tamper")
    (root / "cfg.yaml").write_text(CONFIG)
    runner = Runner(load(root / "cfg.yaml"), root / "out", executor="serial", progress=False)
    runner.run()
    return root / "out", runner.folder.path


@pytest.fixture
def scene(complete_run, tmp_path) -> Scene:
    """A copy of the complete run in ``tmp_path``, its config, and the outside folder."""
    out, run = complete_run
    scene = Scene(tmp_path / "out", tmp_path / "out" / run.relative_to(out),
                  tmp_path / "cfg.yaml", tmp_path / "outside")
    shutil.copytree(out, scene.out, symlinks=True)
    scene.cfg.write_text(CONFIG)
    scene.outside.mkdir()
    for name, text in OUTSIDE.items():
        (scene.outside / name).write_text(text)
    return scene


def _snapshot(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir())}


@pytest.mark.slow  # 216 commands, about 90 s: `pytest -m slow` or `pytest --all`
@pytest.mark.parametrize("command", COMMANDS)
@pytest.mark.parametrize("damage", DAMAGES)
def test_no_command_hangs_writes_outside_or_deletes_what_it_did_not_write(
        scene, damage, command):
    saved = scene.manifest()["trials_done"]
    DAMAGES[damage](scene)
    outside = _snapshot(scene.outside)

    with deadline(HANG_S):
        result = CliRunner().invoke(app, [str(a) for a in COMMANDS[command](scene)])

    assert result.exception is None or isinstance(result.exception, SystemExit), \
        f"{type(result.exception).__name__}: {result.exception}"
    assert result.exit_code in (0, 1, 2, 3) and "Traceback" not in result.output
    if result.exit_code == 2:
        assert len([line for line in result.stderr.splitlines()
                    if line.startswith("error:")]) == 1, result.stderr
    assert _snapshot(scene.outside) == outside, "a file outside the run folder changed"
    for path, data in scene.kept.items():
        assert path.is_file() and path.read_bytes() == data, f"{path.name} of the user's lost"
    manifest = scene.manifest()
    assert manifest is None or manifest["trials_done"] >= min(saved, manifest["trials_total"])


# -- what the matrix cannot see: the words, and the interrupt's count ----------------------
def test_a_link_out_is_refused_in_one_line_naming_it(scene):
    link_out("tables")(scene)
    for args in (["plot", scene.run], ["run", scene.cfg, "--out", scene.out, "--force", *SERIAL]):
        result = CliRunner().invoke(app, [str(a) for a in args])
        assert result.exit_code == 2
        assert result.stderr.startswith(f"error: {scene.run / 'tables'}: a link (to ")
        assert (scene.run / "tables").is_symlink()


def test_force_names_what_it_removed_and_keeps_the_users_files(scene):
    scene.keep(scene.run / "tables" / "my_notes.md", "mine\n")
    scene.keep(scene.run / "parts" / "mine.txt", "mine\n")
    said: list[str] = []
    Runner(load(scene.cfg), scene.out, executor="serial", progress=False, plots=False,
           force=True, warn=said.append).run()
    removed = next(line for line in said if "--force removed" in line)
    count = re.search(r"--force removed (\d+) files trackfuse wrote", removed)
    assert "tables/paper_vs_reproduced.csv" in removed and count and int(count[1]) >= 10
    assert (scene.run / "tables" / "my_notes.md").read_text() == "mine\n"
    assert (scene.run / "parts" / "mine.txt").read_text() == "mine\n"
    assert not (scene.run / "tables" / "paper_vs_reproduced.csv").exists()
    assert not (scene.run / "figures").exists()  # emptied, so removed


def test_plot_names_an_earlier_draws_file_it_removes_and_nothing_else(scene):
    manifest = scene.manifest()
    scene.edit_manifest(report_files=[*manifest["report_files"], "figures/old.png"])
    (scene.run / "figures" / "old.png").write_text("an earlier draw's figure")
    scene.keep(scene.run / "figures" / "mine.png", "mine\n")
    result = CliRunner().invoke(app, ["plot", str(scene.run)])
    assert result.exit_code == 0, result.output
    assert "removed 1 file trackfuse wrote: figures/old.png" in result.stdout
    assert not (scene.run / "figures" / "old.png").exists()
    assert "figures/old.png" not in scene.manifest()["report_files"]


def test_an_interrupt_before_the_parts_are_verified_keeps_the_saved_count(scene,
                                                                          monkeypatch):
    """SIGTERM while the scan of parts/ hung on a FIFO rewrote the manifest to
    trials_done 0 and said '0/12 trials saved' of a run whose parts held them."""
    from trackfuse.results import RunFolder
    from trackfuse.runner import RunInterrupted
    scene.edit_manifest(status="interrupted", trials_done=7)

    def interrupted(self, span_of):
        raise KeyboardInterrupt

    monkeypatch.setattr(RunFolder, "scan_parts", interrupted)
    with pytest.raises(RunInterrupted) as caught:
        Runner(load(scene.cfg), scene.out, executor="serial", progress=False).run()
    assert caught.value.done == 7 and scene.manifest()["trials_done"] == 7


def test_a_fifo_config_named_on_the_command_line_is_read(tmp_path):
    """``trackfuse run <(generate)``: a pipe the user names is the user's choice."""
    import threading
    pipe = tmp_path / "config.yaml"
    os.mkfifo(pipe)
    writer = threading.Thread(target=pipe.write_text, args=(CONFIG,), daemon=True)
    writer.start()
    with deadline(HANG_S):
        result = CliRunner().invoke(app, ["validate", str(pipe)])
    assert result.exit_code == 0 and result.stdout.startswith("ok:"), result.output


def test_reproduce_refuses_a_fifo_among_the_configs_it_finds(tmp_path):
    """A config `reproduce` finds in its folder is not named by the user: a FIFO there
    hung it."""
    folder = tmp_path / "configs"
    folder.mkdir()
    (folder / "a.yaml").write_text(CONFIG)
    os.mkfifo(folder / "b.yaml")
    with deadline(HANG_S):
        result = CliRunner().invoke(app, ["reproduce", str(folder), "--out",
                                          str(tmp_path / "out"), "--dry-run"])
    assert result.exit_code == 2
    assert result.stderr == f"error: {folder / 'b.yaml'}: a FIFO (named pipe), not a config " \
                            f"file; allowed: YAML files in {folder}\n"
