"""Plugins: the real cause of a failure in one line, the current folder on the path, and
installed plugins registered through the entry-point group."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import ROOT, cli_env, trackfuse

from trackfuse.experiments import ENTRY_POINT_GROUP

EXAMPLE = ROOT / "examples" / "plugin_example"
SCRIPT = Path(sys.executable).with_name("trackfuse")  # the console script, not python -m


def _validate(tmp_path: Path, experiment: str) -> str:
    (tmp_path / "c.yaml").write_text(f"experiment: {experiment}\n")
    result = trackfuse("validate", "c.yaml", cwd=tmp_path)
    assert result.returncode == 2
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in result.stderr
    return lines[0]


def test_each_plugin_failure_names_its_own_cause(tmp_path):
    (tmp_path / "needs_dep.py").write_text("import not_installed_dep\nEXPERIMENT = 1\n")
    (tmp_path / "typo_plugin.py").write_text("EXPERIMENT = 1\n")
    assert "no module named 'elsewhere' on the Python path" in \
        _validate(tmp_path, "elsewhere:EXPERIMENT")
    assert "importing needs_dep failed: ModuleNotFoundError: No module named " \
        "'not_installed_dep'" in _validate(tmp_path, "needs_dep:EXPERIMENT")
    assert "typo_plugin does not define EXPERIMNT at its top level; did you mean " \
        "'EXPERIMENT'?" in _validate(tmp_path, "typo_plugin:EXPERIMNT")
    # it read "ModuleNotFoundError: __path__ attribute not found on 'typo_plugin'"
    assert "name the module, not its file: typo_plugin:EXPERIMENT" in \
        _validate(tmp_path, "typo_plugin.py:EXPERIMENT")


def test_the_console_script_finds_a_plugin_in_the_current_folder(tmp_path):
    for name in ("coin.py", "coin_report.py", "coin.yaml"):
        shutil.copy(EXAMPLE / name, tmp_path / name)
    env = {k: v for k, v in cli_env().items() if k != "PYTHONPATH"}
    result = subprocess.run([str(SCRIPT), "validate", "coin.yaml"], cwd=tmp_path, env=env,
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith("ok: coin.yaml: coin, 3 points")


def _install_entry_point(site: Path) -> None:
    """What `pip install examples/plugin_example` leaves: the modules and a dist-info
    folder whose entry_points.txt names the experiment."""
    for name in ("coin.py", "coin_report.py"):
        shutil.copy(EXAMPLE / name, site / name)
    info = site / "trackfuse_coin_example-0.1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: trackfuse-coin-example\n"
                                   "Version: 0.1.0\n")
    (info / "entry_points.txt").write_text(f"[{ENTRY_POINT_GROUP}]\ncoin = coin:EXPERIMENT\n")


@pytest.mark.slow
def test_an_installed_plugin_is_listed_validated_and_run_by_name(tmp_path):
    site = tmp_path / "site"
    site.mkdir()
    _install_entry_point(site)
    work = tmp_path / "work"
    work.mkdir()
    (work / "c.yaml").write_text("experiment: coin\ntrials: 20\nseed: 1\n"
                                 "sweep: {p: [0.2, 0.5]}\noutputs: {formats: [png]}\n")
    env = cli_env()
    env["PYTHONPATH"] = f"{site}:{env['PYTHONPATH']}"

    def cli(*args):
        return subprocess.run([sys.executable, "-m", "trackfuse", *args], cwd=work, env=env,
                              capture_output=True, text=True, timeout=300)

    listed = cli("list")
    assert "coin" in listed.stdout and "plugin trackfuse-coin-example 0.1.0" in listed.stdout
    assert "coin = p" not in listed.stdout  # listing does not import the plugin
    assert "p = 0.3" in cli("list", "coin").stdout
    assert cli("validate", "c.yaml").returncode == 0
    ran = cli("run", "c.yaml", "--out", str(tmp_path / "out"), "--workers", "1",
              "--no-progress")
    assert ran.returncode == 0, ran.stderr
    assert "report: " in ran.stdout


def test_the_readme_plugin_runs_output_is_ignored_by_git():
    """`cd examples/plugin_example && trackfuse run coin.yaml` left results/ untracked: only
    the top-level results/ was ignored."""
    inside = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--is-inside-work-tree"],
                            capture_output=True, text=True)
    if inside.returncode != 0:
        pytest.skip("not a git checkout")
    ignored = ["examples/plugin_example/results/coin/seed1-0123456789/trials.csv",
               "results/twin_sensor_orbit/seed1-0123456789/trials.csv"]
    kept = ["results/README.md", "examples/plugin_example/coin.yaml"]
    check = subprocess.run(["git", "-C", str(ROOT), "check-ignore", "--no-index", *ignored,
                            *kept], capture_output=True, text=True)
    assert check.stdout.split() == ignored


def test_a_plugins_hints_name_what_trackfuse_list_takes(tmp_path):
    """`--set gate.pgg=1` on a plugin said "see `trackfuse list cvtrack`", which lists
    nothing: a plugin loaded by module:ATTRIBUTE is listed by that reference."""
    shutil.copy(EXAMPLE / "coin.py", tmp_path / "coin.py")
    (tmp_path / "c.yaml").write_text("experiment: coin:EXPERIMENT\ntrials: 2\n")
    result = trackfuse("validate", "c.yaml", "--set", "no_such_key=1", cwd=tmp_path)
    assert result.returncode == 2 and "(see `trackfuse list coin:EXPERIMENT`)" in result.stderr
    listed = trackfuse("list", "coin:EXPERIMENT", cwd=tmp_path)
    assert listed.returncode == 0, listed.stderr


@pytest.mark.slow
def test_a_report_module_off_the_path_is_refused_before_the_run(tmp_path):
    """A plugin whose report module was not on the path ran every trial, then failed to
    draw (exit 1): now `run` refuses it at once, `--no-plots` runs, `validate` warns."""
    source = (EXAMPLE / "coin.py").read_text()
    (tmp_path / "coin.py").write_text(source.replace('"coin_report"', '"coin_report_gone"'))
    (tmp_path / "c.yaml").write_text("experiment: coin:EXPERIMENT\ntrials: 2\n")
    refused = trackfuse("run", "c.yaml", "--out", "out", cwd=tmp_path)
    assert refused.returncode == 2 and not (tmp_path / "out").exists()
    assert refused.stderr == ("error: c.yaml: the report module 'coin_report_gone' of 'coin' "
                              "is not on the Python path; allowed: run from the folder that "
                              "holds it, add that folder to PYTHONPATH, or --no-plots\n")
    bare = trackfuse("run", "c.yaml", "--out", "out", "--no-plots", "--no-progress",
                     cwd=tmp_path)
    assert bare.returncode == 0, bare.stderr
    checked = trackfuse("validate", "c.yaml", cwd=tmp_path)
    assert checked.returncode == 0 and checked.stderr.startswith("warning: c.yaml: the report")
