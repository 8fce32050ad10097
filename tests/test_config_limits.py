"""Configs that are hostile or unlucky: bounded reads, no alias bombs, no duplicate keys, no
overflowing ranges, and plugin references that are refused before anything runs (issue 14)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import time

import pytest
from conftest import cli_env, trackfuse
from typer.testing import CliRunner

from trackfuse.config import ConfigError, load
from trackfuse_cli.main import app

BOMB = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{c}: &{c} [{', '.join([f'*{p}'] * 9)}]\n"
    for p, c in zip("abcdefgh", "bcdefghi", strict=True)) + "experiment: *i\n"

BAD = {
    "duplicate top-level key": ("experiment: toy_gaussian\ntrials: 3\ntrials: 4\n",
                                ": line 3: duplicate key 'trials'"),
    "duplicate parameter": ("experiment: toy_gaussian\nparams:\n  mu: 1\n  mu: 2\n",
                            ": line 4: duplicate key 'mu'"),
    "integer range overflow": ("experiment: toy_gaussian\n"
                               "sweep: {mu: 'range(0, 100000000000000000000)'}\n",
                               "sweep.mu: got 'range(0, 100000000000000000000)'; more than"),
    "float range overflow": ("experiment: toy_gaussian\nsweep: {mu: 'range(0, 1e300, 1e-300)'}",
                             "; more than 1000000 values"),
    "infinite span": ("experiment: toy_gaussian\nsweep: {mu: 'range(-1e308, 1e308)'}",
                      "; more than 1000000 values"),
    "empty module": ("experiment: ':x'", "expected package.module:ATTRIBUTE"),
    "relative module": ("experiment: '.x:y'", "expected package.module:ATTRIBUTE"),
    "module opening a GUI": ("experiment: 'idlelib.idle:x'", "idlelib.idle does not define x"),
    "GUI module naming what it defines": ("experiment: 'idlelib.idle:main'",
                                          "idlelib.idle runs code when imported"),
    "a __main__ module": ("experiment: 'tkinter.__main__:x'", "a __main__ module"),
    "missing module": ("experiment: 'no_such_pkg.mod:X'", "No module named 'no_such_pkg'"),
    "not an experiment": ("experiment: 'json.decoder:JSONDecoder'",
                          "JSONDecoder is a type, not a trackfuse Experiment"),
    "alias bomb": (BOMB, "aliases expand to more than 100000 values"),
    "recursive alias": ("experiment: toy_gaussian\nparams: &p {mu: *p}\n",
                        "an alias refers to the value that contains it"),
    "merge key twice": ("experiment: toy_gaussian\nx: &x {mu: 1}\ny: &y {mu: 2}\n"
                        "params:\n  <<: *x\n  <<: *y\n", ": line 6: merge key '<<' given twice"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_config_is_one_line_naming_the_file(case, write_config):
    text, expected = BAD[case]
    path = write_config(text, "bad")
    t0 = time.perf_counter()
    with pytest.raises(ConfigError) as err:
        load(path)
    assert time.perf_counter() - t0 < 5
    message = str(err.value)
    assert message.startswith(f"{path}: ") and "\n" not in message
    assert expected in message, message
    assert "idlelib.idle" not in sys.modules and "tkinter.__main__" not in sys.modules


def test_cli_refuses_an_alias_bomb_quickly(write_config, tmp_path):
    path = write_config(BOMB, "bomb")
    result = trackfuse("validate", path, timeout=30)  # a subprocess: a hang fails, not blocks
    assert result.returncode == 2
    assert result.stderr == f"error: {path}: aliases expand to more than 100000 values\n"
    t0 = time.perf_counter()
    result = CliRunner().invoke(app, ["run", str(path), "--out", str(tmp_path)])
    assert time.perf_counter() - t0 < 5 and result.exit_code == 2
    assert result.stderr == f"error: {path}: aliases expand to more than 100000 values\n"


def test_validate_dev_zero_reads_a_bounded_amount():
    result = trackfuse("validate", "/dev/zero", timeout=30)
    assert result.returncode == 2
    assert result.stderr.startswith("error: /dev/zero: larger than 1000000 bytes")


def test_validate_of_a_directory_is_one_line(tmp_path):
    result = CliRunner().invoke(app, ["validate", str(tmp_path)])
    assert result.exit_code == 2 and result.stderr.count("\n") == 1
    assert result.stderr.startswith(f"error: {tmp_path}: a folder; allowed: a YAML config file")


def _plugin(folder, name: str, body: str) -> None:
    (folder / f"{name}.py").write_text(textwrap.dedent(body))


EXPERIMENT = """
    from toy_experiments import GAUSSIAN
    import pathlib
    _MARK = pathlib.Path(__file__).with_suffix(".imported").write_text("yes")
    EXPERIMENT = GAUSSIAN
"""


def test_a_plugin_import_error_is_shown_in_one_line(write_config, tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(tmp_path))
    _plugin(tmp_path, "broken_plugin", "import no_such_dependency_xyz\nEXPERIMENT = None\n")
    _plugin(tmp_path, "exiting_plugin", "import sys\nEXPERIMENT = sys.exit(3)\n")
    for ref, expected in (
            ("broken_plugin:EXPERIMENT", "importing broken_plugin failed: ModuleNotFoundError: "
                                         "No module named 'no_such_dependency_xyz'"),
            ("exiting_plugin:EXPERIMENT", "importing exiting_plugin failed: SystemExit: 3")):
        with pytest.raises(ConfigError) as err:
            load(write_config(f"experiment: '{ref}'\n", "plug"))
        assert expected in str(err.value) and "\n" not in str(err.value)


def test_plugins_are_imported_only_for_the_config_that_names_them(write_config, tmp_path,
                                                                 monkeypatch):
    """validate/run of config A imports A's module only; list and plot of A never import B."""
    plugins = tmp_path / "plugins"
    plugins.mkdir()
    _plugin(plugins, "plugin_a", EXPERIMENT)
    _plugin(plugins, "plugin_b", EXPERIMENT)
    env_path = f"{plugins}"
    a = write_config("experiment: plugin_a:EXPERIMENT\ntrials: 3\n", "a")
    write_config("experiment: plugin_b:EXPERIMENT\ntrials: 3\n", "b")

    def cli(*args):
        env = cli_env()
        env["PYTHONPATH"] = f"{env_path}{os.pathsep}{env['PYTHONPATH']}"
        return subprocess.run([sys.executable, "-m", "trackfuse", *map(str, args)], env=env,
                              capture_output=True, text=True, timeout=120)

    assert cli("list").returncode == 0
    assert not list(plugins.glob("*.imported"))
    assert cli("validate", a).returncode == 0
    assert [p.name for p in plugins.glob("*.imported")] == ["plugin_a.imported"]
    monkeypatch.syspath_prepend(str(plugins))
    result = CliRunner().invoke(app, ["run", str(a), "--out", str(tmp_path / "out"),
                                      "--executor", "serial", "--no-progress"])
    assert result.exit_code == 0, result.stderr
    (plugins / "plugin_a.imported").unlink()
    folder = next((tmp_path / "out" / "a").iterdir())
    assert cli("plot", folder).returncode == 0
    assert [p.name for p in plugins.glob("*.imported")] == ["plugin_a.imported"]


def test_a_file_that_is_not_a_config_is_never_echoed(write_config):
    """`validate /etc/shadow` printed its first line as an 'unknown top-level key'."""
    secret = "root:$6$Zx9secret$hash:19000:0:99999:7:::"
    path = write_config(f"{secret}\ndaemon:*:19000:0:99999:7:::\n", "shadow")
    with pytest.raises(ConfigError) as err:
        load(path)
    message = str(err.value)
    assert err.value.key == "" and "Zx9secret" not in message and "19000" not in message
    assert str(err.value).startswith(f"{path}: not a trackfuse config")
    mistyped = write_config("experiment: toy_gaussian\ntrails: 3\n", "typo")
    with pytest.raises(ConfigError) as err:  # a key name is still named, with a did-you-mean
        load(mistyped)
    assert err.value.key == "trails" and "did you mean 'trials'" in str(err.value)
