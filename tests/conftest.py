"""Shared fixtures: the toy experiments and helpers to run the real CLI."""

from __future__ import annotations

import contextlib
import math
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

TESTS = Path(__file__).resolve().parent
sys.path.insert(0, str(TESTS))

import toy_experiments  # noqa: E402,F401 - registers the toy experiments

ROOT = TESTS.parent

# No test may depend on the host's terminal, locale or timezone: each test process, and the
# CLI subprocesses it starts (cli_env copies os.environ), sees the same ones everywhere.
os.environ.update({"COLUMNS": "80", "LINES": "24", "TZ": "UTC", "LC_ALL": "C.UTF-8",
                   "LANG": "C.UTF-8"})
os.environ.pop("NO_COLOR", None)
os.environ.pop("FORCE_COLOR", None)

from trackfuse.experiments.base import Param  # noqa: E402
from trackfuse.results import RunFolder  # noqa: E402


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption("--all", action="store_true",
                     help="run the slow tests too (by default only the fast suite runs)")


_SLOW_LEFT_OUT = pytest.StashKey[int]()


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Leave the ``slow`` tests out of a plain ``pytest`` (the fast suite); ``-m EXPR`` or
    ``--all`` chooses otherwise."""
    if config.getoption("--all") or config.option.markexpr:
        return
    slow = [item for item in items if item.get_closest_marker("slow")]
    if slow:
        items[:] = [item for item in items if not item.get_closest_marker("slow")]
        config.hook.pytest_deselected(items=slow)
        config.stash[_SLOW_LEFT_OUT] = len(slow)


def pytest_terminal_summary(terminalreporter, config: pytest.Config) -> None:
    if left_out := config.stash.get(_SLOW_LEFT_OUT, 0):
        terminalreporter.write_line(f"{left_out} slow tests left out: `pytest -m slow` runs "
                                    "them, `pytest --all` everything")


def cli_env() -> dict[str, str]:
    """Environment for a ``trackfuse`` subprocess that can import the toy experiments."""
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(TESTS), str(ROOT),
                                                      env.get("PYTHONPATH", "")]))
    env.pop("CI", None)
    return env


def trackfuse(*args: str, cwd: Path | None = None, timeout: float = 120,
              **kw) -> subprocess.CompletedProcess:
    """Run the real CLI (``python -m trackfuse``) and capture its output."""
    return subprocess.run([sys.executable, "-m", "trackfuse", *map(str, args)], cwd=cwd,
                          env=cli_env(), capture_output=True, text=True, timeout=timeout, **kw)


def another_value(param: Param, current):
    """A valid value of ``param`` other than ``current`` (near it, for numbers)."""
    if param.kind is list:
        options = list(param.choices or current)
        return [options[-1]] if [options[-1]] != current else [options[0]]
    if param.choices:
        return next(c for c in param.choices if c != current)
    if param.kind is bool:
        return not current
    low = -math.inf if param.low is None else param.low
    high = math.inf if param.high is None else param.high
    for value in (2 * current, (current + high) / 2, (current + low) / 2, current + 1):
        value = param.kind(value)
        if value != current and low <= value <= high:
            return value
    raise ValueError(f"{param.key}: no other value near {current}")


@pytest.fixture
def write_config(tmp_path):
    """Write a YAML text to ``tmp_path/<name>.yaml`` and return its path."""
    def write(text: str, name: str = "cfg") -> Path:
        path = tmp_path / f"{name}.yaml"
        path.write_text(text)
        return path
    return write


@contextlib.contextmanager
def ctrl_c_at_part(n: int) -> Iterator[None]:
    """Inside the block, a Ctrl-C (``KeyboardInterrupt``) as a run is about to store its
    ``n``-th finished batch (``RunFolder.write_part``, in the run's own process)."""
    original, calls = RunFolder.write_part, [0]

    def write_part(self, *args) -> None:
        calls[0] += 1
        if calls[0] == n:
            raise KeyboardInterrupt
        original(self, *args)

    RunFolder.write_part = write_part
    try:
        yield
    finally:
        RunFolder.write_part = original
