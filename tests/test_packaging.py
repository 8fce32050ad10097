"""The installed layout: every package listed, the CLI under its own import name."""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path

from setuptools import find_packages

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_every_package_is_listed_and_the_cli_is_renamed():
    listed = PYPROJECT["tool"]["setuptools"]["packages"]
    assert sorted(listed) == sorted([*find_packages(str(ROOT), include=["trackfuse*"]),
                                     "trackfuse_cli"])
    assert PYPROJECT["tool"]["setuptools"]["package-dir"] == {"trackfuse_cli": "cli"}
    assert PYPROJECT["project"]["scripts"]["trackfuse"] == "trackfuse_cli.main:app"


def test_python_dash_m_trackfuse_runs_the_cli(tmp_path):
    out = subprocess.run([sys.executable, "-m", "trackfuse", "list"], capture_output=True,
                         text=True, check=True, cwd=tmp_path).stdout
    assert "twin_sensor" in out and "passive_assoc" in out
