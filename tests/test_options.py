"""cli/options.py: one-line usage errors, --version, help text, choices, completion."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import pytest
from conftest import cli_env, trackfuse
from typer.testing import CliRunner

import trackfuse as package
from trackfuse.config import load
from trackfuse.executors import KINDS
from trackfuse.runner import Runner
from trackfuse_cli.main import app
from trackfuse_cli.options import Executor


@pytest.mark.parametrize("args, expected", [
    (["run", "--workers", "x", "cfg.yaml"], "'--workers'"),
    (["run"], "Missing argument 'CONFIG'"),
    (["run", "cfg.yaml", "--executor", "threads"], "'--executor'"),
    (["validate", "cfg.yaml", "--no-such-option"], "No such option: --no-such-option"),
    (["run", "cfg.yaml", "--trials", "0"], "'--trials': got 0; "),
    (["run", "cfg.yaml", "--trials", "-3"], "'--trials': got -3; allowed: an integer >= 1"),
    # typer read 2.0 as 2 where a config's trials: 10.0 is refused
    (["run", "cfg.yaml", "--trials", "2.0"], "'--trials': got 2.0; allowed: an integer >= 1"),
    (["run", "cfg.yaml", "--workers", "1e3"], "'--workers': got 1e3; allowed: an integer"),
    (["run", "cfg.yaml", "--seed", "0.5"], "'--seed': got 0.5; allowed: an integer >= 0"),
    (["reproduce", "--workers", "2.0"], "'--workers': got 2.0; allowed: an integer from 0 "
                                        "to 1024"),
    # a pool of 2**31 workers crashed in the standard library, with a traceback
    (["run", "cfg.yaml", "--workers", "2147483647"], "'--workers': got 2147483647; allowed: "
                                                      "an integer from 0 to 1024"),
    # Python's own "Exceeds the limit (4300 digits)" message, with a hint at sys
    (["run", "cfg.yaml", "--trials", "9" * 5000], "'--trials': got 99999"),
    (["run", "cfg.yaml", "--seed", "x1"], "'--seed': got x1; "),
    (["frobnicate"], "No such command 'frobnicate'"),
])
def test_usage_errors_are_one_line_with_exit_2(args, expected):
    result = trackfuse(*args)
    assert result.returncode == 2, result.stderr
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and expected in lines[0], lines
    assert "╭" not in result.stderr and "Traceback" not in result.stderr


def test_an_option_out_of_the_configs_range_is_blamed_on_the_option(write_config):
    """A huge --trials was blamed on --set, which the command line did not use."""
    cfg = write_config("experiment: toy_gaussian\ntrials: 4\nseed: 1\n")
    result = CliRunner().invoke(app, ["run", str(cfg), "--trials", "99999999999999",
                                      "--dry-run"])
    assert result.exit_code == 2
    assert result.stderr.strip() == ("error: --trials: got 99999999999999; allowed: an integer "
                                     "in [1, 1000000000]")


def test_version():
    result = trackfuse("--version")
    assert result.returncode == 0 and result.stdout.strip() == f"trackfuse {package.__version__}"


def test_executor_choices_are_the_executors_kinds():
    assert tuple(e.value for e in Executor) == KINDS


@pytest.mark.parametrize("command", ["run", "reproduce", "validate", "list", "compare"])
def test_help_shows_no_type_placeholders_or_contradicting_defaults(command):
    """Options show a metavar (N, KEY=VALUE, FOLDER), flags nothing; typer's own --help
    keeps its ``<bool>``."""
    result = CliRunner().invoke(app, [command, "--help"], env={"COLUMNS": "160"})
    assert result.exit_code == 0
    rows = [line.strip("│ ") for line in result.stdout.splitlines()
            if line.strip("│ ").startswith("--") and not line.strip("│ ").startswith("--help")]
    assert rows
    for row in rows:
        for placeholder in ("<bool>", "<int>", "<str>", "<float>", "<path>", "<list[str]>"):
            assert placeholder not in row, row
    assert "[default: 0]" not in result.stdout


@pytest.mark.parametrize("command", ["reproduce", "plot", "compare", "validate", "list"])
def test_help_paragraphs_are_reflowed_not_broken_mid_sentence(command):
    """typer kept the source line breaks of a docstring's later paragraphs, so a sentence
    broke after "first. Plotting" and went on in a new line."""
    result = CliRunner().invoke(app, [command, "--help"], env={"COLUMNS": "400"})
    text = result.stdout.split("╭")[0].split("Usage:")[1]
    paragraphs = [p.strip().splitlines() for p in re.split(r"\n\s*\n", text) if p.strip()]
    assert len(paragraphs) >= 3  # usage line, summary, at least one more paragraph
    for lines in paragraphs[1:]:
        assert len(lines) == 1 and lines[0].endswith("."), lines


def test_reproduce_offers_the_run_options():
    text = CliRunner().invoke(app, ["reproduce", "--help"], env={"COLUMNS": "200"}).stdout
    for option in ("--no-plots", "--set", "--dry-run", "--scheduler", "--executor"):
        assert option in text, option


def test_shell_completion_is_offered_and_completes_experiment_names():
    text = CliRunner().invoke(app, ["--help"], env={"COLUMNS": "120"}).stdout
    assert "--install-completion" in text and "--show-completion" in text
    result = CliRunner().invoke(app, [], env={"_TRACKFUSE_COMPLETE": "complete_bash",
                                              "COMP_WORDS": "trackfuse list twin",
                                              "COMP_CWORD": "2"}, prog_name="trackfuse")
    assert "twin_sensor" in result.stdout


def test_no_command_prints_help_and_exits_2():
    result = trackfuse()
    assert result.returncode == 2 and "Usage: " in result.stdout


def _closed_stdout(*args: str) -> subprocess.CompletedProcess:
    """``trackfuse ARGS`` writing into a pipe whose reader has gone (``| head -1`` after its
    line)."""
    read, write = os.pipe()
    os.close(read)
    try:
        return subprocess.run([sys.executable, "-m", "trackfuse", *args], stdout=write,
                              stderr=subprocess.PIPE, env=cli_env(), text=True, timeout=120)
    finally:
        os.close(write)


@pytest.mark.slow
def test_a_closed_stdout_is_silent_and_keeps_the_commands_exit_status(write_config, tmp_path):
    """`trackfuse list twin_sensor | head -1` and `compare A B | head -1` exited 1 with
    nothing on stderr, and compare's 1 means "regression"."""
    listed = _closed_stdout("list", "twin_sensor")
    assert (listed.returncode, listed.stderr) == (0, "")
    folders = []
    for name, shift in (("base", 0.0), ("worse", 0.3), ("again", 0.0)):
        cfg = write_config(f"experiment: toy_experiments:SHIFTED\ntrials: 200\nseed: 1\n"
                           f"params: {{shift: {shift}}}\n", name=name)
        folders.append(str(Runner(load(cfg), tmp_path / "out", progress=False,
                                  plots=False).run().folder))
    passed = _closed_stdout("compare", folders[0], folders[2], "--fail-on-regression")
    assert (passed.returncode, passed.stderr) == (0, "")
    plain = _closed_stdout("compare", *folders[:2])
    assert (plain.returncode, plain.stderr) == (0, "")
    gated = _closed_stdout("compare", *folders[:2], "--fail-on-regression")
    assert gated.returncode == 1 and gated.stderr.startswith("error: 1 regressions")
