"""The test suite's own rules: `pytest` runs the fast suite quietly, the slow tests carry the
registered `slow` marker (run by `pytest -m slow` or `--all`), and no test is switched on or
off by an environment variable (a gate nobody sets is a test that never runs)."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_the_slow_marker_is_registered_and_the_default_run_is_quiet_and_strict():
    options = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"][
        "ini_options"]
    assert any(marker.startswith("slow:") for marker in options["markers"])
    assert set(options["addopts"].split()) >= {"-q", "--strict-markers"}


def test_no_test_is_gated_by_an_environment_variable():
    gate = re.compile(r"skip(?:if)?\([^)]*(?:os\.environ|os\.getenv)", re.S)
    gated = [path.name for path in sorted((ROOT / "tests").glob("test_*.py"))
             if gate.search(path.read_text(encoding="utf-8"))]
    assert not gated, gated
