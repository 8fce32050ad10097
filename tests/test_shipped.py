"""How a config NAME is found: ./configs first (like `reproduce`), then the shipped configs."""

from __future__ import annotations

from pathlib import Path

import pytest
from conftest import trackfuse

from trackfuse.shipped import config_folders, config_path, configs_folder

CI = "ci/twin_sensor_ci"


def _edited_checkout(tmp_path: Path) -> Path:
    """A folder with ./configs/ci/twin_sensor_ci.yaml edited to 3 trials (shipped: 8)."""
    shipped = (configs_folder() / f"{CI}.yaml").read_text()
    assert "trials: 8\n" in shipped
    local = tmp_path / "configs" / f"{CI}.yaml"
    local.parent.mkdir(parents=True)
    local.write_text(shipped.replace("trials: 8\n", "trials: 3\n"))
    return local


def test_a_name_means_the_working_directorys_configs_file_when_present(tmp_path, monkeypatch):
    """`run ci/twin_sensor_ci` took the installed copy although ./configs held an edited
    one, which `reproduce` would run: the two commands disagreed."""
    _edited_checkout(tmp_path)
    monkeypatch.chdir(tmp_path)
    assert config_path(Path(CI)) == Path("configs") / f"{CI}.yaml"
    assert config_path(Path(f"{CI}.yaml")) == Path("configs") / f"{CI}.yaml"
    assert config_folders()[0] == Path("configs")  # reproduce's default folder
    # a name ./configs lacks still finds the shipped config
    assert config_path(Path("twin_sensor_orbit")) == configs_folder() / "twin_sensor_orbit.yaml"
    (tmp_path / "mine.yaml").write_text("x")
    assert config_path(Path("mine.yaml")) == Path("mine.yaml")  # an existing path as given


def test_run_dry_run_validate_and_run_name_the_file_they_used(tmp_path):
    _edited_checkout(tmp_path)
    dry = trackfuse("run", CI, "--dry-run", cwd=tmp_path)
    assert dry.returncode == 0, dry.stderr
    plan = dry.stdout.splitlines()[-1]
    assert plan.startswith(f"# configs/{CI}.yaml: 3 points x 3 trials"), plan
    ok = trackfuse("validate", CI, cwd=tmp_path)
    assert ok.stdout.strip() == f"ok: configs/{CI}.yaml: twin_sensor, 3 points x 3 trials"
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    shipped = trackfuse("validate", CI, cwd=elsewhere).stdout.strip()
    # the shipped config, wherever the CLI imports trackfuse from (the checkout or, as in
    # CI, an installed copy)
    assert shipped.startswith("ok: /") and str(tmp_path) not in shipped
    assert shipped.endswith(f"/configs/{CI}.yaml: twin_sensor, 3 points x 8 trials")


@pytest.mark.slow
def test_run_by_name_says_which_file_it_ran(tmp_path):
    (tmp_path / "configs").mkdir()
    (tmp_path / "configs" / "toy.yaml").write_text("experiment: toy_experiments:TRIVIAL\n"
                                                   "trials: 2\nseed: 1\n")
    result = trackfuse("run", "toy", "--out", "out", "--no-plots", "--no-progress",
                       cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[0] == "config: configs/toy.yaml"
    by_path = trackfuse("run", "configs/toy.yaml", "--out", "out", "--no-plots",
                        "--no-progress", cwd=tmp_path)
    assert not by_path.stdout.startswith("config:")


def test_a_config_that_is_neither_a_file_nor_a_name_suggests_the_closest_names(tmp_path):
    """`trackfuse run twin_sensor_ci` said only "no such file", though ci/twin_sensor_ci
    exists."""
    missing = trackfuse("run", "twin_sensor_ci", "--dry-run", cwd=tmp_path)
    assert missing.returncode == 2
    assert missing.stderr.splitlines() == [
        "error: twin_sensor_ci: no such file, nor a config of that name in ./configs or the "
        "shipped configs; did you mean 'ci/twin_sensor_ci'?"]
    typo = trackfuse("validate", "twin_sensor_orbt.yaml", cwd=tmp_path)
    assert typo.returncode == 2 and "did you mean 'twin_sensor_orbit'" in typo.stderr
    (tmp_path / "configs").mkdir()
    (tmp_path / "configs" / "my_study.yaml").write_text("experiment: twin_sensor\n")
    mine = trackfuse("validate", "my_stduy", cwd=tmp_path)  # the local configs count too
    assert mine.stderr.strip().endswith("did you mean 'my_study'?")
    nothing = trackfuse("validate", "zzz", cwd=tmp_path)
    assert nothing.returncode == 2 and len(nothing.stderr.splitlines()) == 1
    assert nothing.stderr.strip().endswith("allowed: a YAML file or a config name such as "
                                           "twin_sensor_orbit or ci/twin_sensor_ci")
