"""The installed layout: every package listed, the CLI under its own import name."""

from __future__ import annotations

import hashlib
import pickle
import subprocess
import sys
import tomllib
import zipfile
from pathlib import Path

import numba
import pytest
from setuptools import find_packages

from trackfuse.shipped import config_path, configs_folder

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_every_package_is_listed_and_the_cli_is_renamed():
    listed = PYPROJECT["tool"]["setuptools"]["packages"]
    config_folders = [f"trackfuse.configs.{d.name}" for d in (ROOT / "configs").iterdir()
                      if d.is_dir() and any(d.glob("*.yaml"))]
    assert sorted(listed) == sorted([*find_packages(str(ROOT), include=["trackfuse*"]),
                                     "trackfuse_cli", "trackfuse.configs", "trackfuse.papers",
                                     *config_folders])
    assert PYPROJECT["tool"]["setuptools"]["package-dir"] == {
        "trackfuse_cli": "cli", "trackfuse.configs": "configs",
        "trackfuse.papers": "docs/papers"}
    assert PYPROJECT["project"]["scripts"]["trackfuse"] == "trackfuse_cli.main:app"


def test_python_dash_m_trackfuse_runs_the_cli(tmp_path):
    out = subprocess.run([sys.executable, "-m", "trackfuse", "list"], capture_output=True,
                         text=True, check=True, cwd=tmp_path).stdout
    assert "twin_sensor" in out and "passive_assoc" in out


def test_shipped_configs_run_by_name_outside_a_checkout(tmp_path):
    """`trackfuse validate twin_sensor_orbit` in an empty folder finds the shipped config,
    and every shipped paper config is there."""
    shipped = configs_folder()
    assert shipped is not None
    assert {p.name for p in shipped.glob("*.yaml")} == \
        {p.name for p in (ROOT / "configs").glob("*.yaml")}
    out = subprocess.run([sys.executable, "-m", "trackfuse", "validate", "twin_sensor_orbit"],
                         capture_output=True, text=True, cwd=tmp_path)
    assert out.returncode == 0 and "ok:" in out.stdout, out.stderr
    assert config_path(Path("ci/passive_assoc_ci")).is_file()


@pytest.mark.slow  # builds the wheel in pip's build environment, compiling the kernels
def test_the_wheel_ships_the_kernels_compiled_for_its_own_sources(tmp_path):
    """setup.py packs numba's cache of both kernels beside their modules, stamped with the
    shipped sources (else numba would ignore it and compile on the first run)."""
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps",
                    "-q", "-w", str(tmp_path), str(ROOT)], check=True, capture_output=True)
    with zipfile.ZipFile(next(tmp_path.glob("trackfuse-*.whl"))) as wheel:
        names = wheel.namelist()
        for module, kernel in (("trackfuse/tracking/pda", "_filter_batch"),
                               ("trackfuse/association/pga_search", "_search")):
            folder, stem = module.rsplit("/", 1)
            index = [n for n in names if n.startswith(f"{folder}/__pycache__/{stem}.{kernel}-")
                     and n.endswith(".nbi")]
            assert len(index) == 1, (module, index)
            with wheel.open(index[0]) as f:
                assert pickle.load(f) == numba.__version__
                stamp, entries = pickle.loads(f.read())
            assert stamp == hashlib.sha256(wheel.read(f"{module}.py")).digest()
            assert len(entries) == 1  # one compiled version, the one a run asks for
