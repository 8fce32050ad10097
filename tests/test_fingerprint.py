"""The run id covers the code that computes the numbers; the manifest says what ran."""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import ROOT, TESTS, cli_env, ctrl_c_at_part
from toy_experiments import GAUSSIAN

from trackfuse.config import load
from trackfuse.environment import recorded_cpus, unseen_cpus
from trackfuse.experiments import get
from trackfuse.fingerprint import NUMBERS_PATH, code_fingerprint
from trackfuse.runner import RunInterrupted, Runner

PLUGIN = '''
from trackfuse.experiments.base import Experiment, Param

SHIFT = {shift}


def trial(params, streams):
    return [{{"algorithm": "a", "value": float(streams.common.normal()) + SHIFT}}]


EXPERIMENT = Experiment(name="shifty", title="toy plugin", run_trial=trial,
                        params=(Param("unused", 0.0, "no effect"),))
'''

CONFIG = """experiment: shifty_plugin:EXPERIMENT
trials: 4
seed: 3
"""


def _cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(cwd), str(TESTS), str(ROOT)])
    return subprocess.run([sys.executable, "-m", "trackfuse", *args], cwd=cwd, env=env,
                          capture_output=True, text=True, timeout=120)


def _runs(out: Path) -> list[Path]:
    return sorted(p for p in (out / "shifty").iterdir() if p.is_dir())


@pytest.mark.slow
def test_editing_the_experiment_code_gives_new_numbers_in_a_new_folder(tmp_path):
    (tmp_path / "shifty.yaml").write_text(CONFIG)
    plugin = tmp_path / "shifty_plugin.py"
    plugin.write_text(PLUGIN.format(shift=0.0))
    args = ("run", "shifty.yaml", "--out", "out", "--workers", "1", "--no-progress",
            "--no-plots")
    first = _cli(*args, cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    plugin.write_text(PLUGIN.format(shift=100.0))
    second = _cli(*args, cwd=tmp_path)
    assert second.returncode == 0, second.stderr
    assert "already complete" not in second.stdout
    assert "holds this config from other code" in second.stderr
    old, new = _runs(tmp_path / "out")
    values = [json.loads((p / "manifest.json").read_text())["rows"] for p in (old, new)]
    assert values == [4, 4]
    means = sorted(float((p / "trials.csv").read_text().splitlines()[1].split(",")[-1])
                   for p in (old, new))
    assert means[1] - means[0] == pytest.approx(100.0, abs=1e-9)
    third = _cli(*args, cwd=tmp_path)  # unchanged code: the new folder is reused
    assert "already complete" in third.stdout and len(_runs(tmp_path / "out")) == 2


def test_force_recomputes_into_the_same_folder(write_config, tmp_path):
    cfg = write_config("experiment: toy_gaussian\ntrials: 6\nseed: 1\nbatch_size: 3\n")
    config = load(cfg)
    first = Runner(config, tmp_path / "out", progress=False, plots=False).run()
    reference = (first.folder / "trials.csv").read_bytes()
    (first.folder / "parts").mkdir(exist_ok=True)  # complete runs keep no resume state
    stale = first.folder / "parts" / "stale-note.txt"
    stale.write_text("left by an old run")
    again = Runner(config, tmp_path / "out", progress=False, plots=False).run()
    assert again.status == "already complete"
    forced = Runner(config, tmp_path / "out", progress=False, plots=False, force=True).run()
    assert forced.folder == first.folder and forced.status == "complete"
    assert forced.computed_trials == 6 and stale.exists()  # not trackfuse's: left alone
    assert (forced.folder / "trials.csv").read_bytes() == reference


def test_manifest_records_the_repository_run_from_and_the_executor_used(write_config,
                                                                         tmp_path, monkeypatch):
    repo = tmp_path / "repo"
    repo.mkdir()
    for cmd in (["init", "-q"], ["-c", "user.email=a@b", "-c", "user.name=a", "commit", "-q",
                                 "--allow-empty", "-m", "x"]):
        subprocess.run(["git", "-C", str(repo), *cmd], check=True)
    (repo / "tracked.txt").write_text("v1")
    subprocess.run(["git", "-C", str(repo), "add", "tracked.txt"], check=True)
    monkeypatch.chdir(repo)
    cfg = write_config("experiment: toy_gaussian\ntrials: 2\nseed: 1\n")
    outcome = Runner(load(cfg), tmp_path / "out", workers=1, executor="process",
                     progress=False, plots=False).run()
    manifest = json.loads((outcome.folder / "manifest.json").read_text())
    head = subprocess.run(["git", "-C", str(repo), "rev-parse", "HEAD"], capture_output=True,
                          text=True, check=True).stdout.strip()
    assert manifest["git"] == {"repository": str(repo.resolve()), "commit": head,
                               "dirty": True}
    assert manifest["executor"] == "serial" and manifest["executor_requested"] == "process"
    assert manifest["versions"]["matplotlib"] and "stonesoup" in manifest["versions"]
    assert manifest["code_fingerprint"]["sha256"] == code_fingerprint(GAUSSIAN).digest


def test_fingerprint_covers_the_experiment_its_imports_and_the_numbers_path():
    modules = code_fingerprint(get("passive_assoc")).modules
    assert "trackfuse.experiments.passive_assoc.model" in modules
    assert not any(m.endswith(".report") or m.startswith("trackfuse.plots") for m in modules)
    assert "trackfuse.association.pga" in modules  # imported by the experiment
    assert set(NUMBERS_PATH) <= set(modules)
    assert "toy_experiments" in code_fingerprint(GAUSSIAN).modules
    # Every CSV cell of every run is written by the row format, whatever the experiment imports.
    assert "trackfuse.rowformat" in code_fingerprint(GAUSSIAN).modules


def test_fingerprinting_runs_none_of_the_modules_it_hashes():
    # reading the kernel's source must not import it (numba, about 0.5 s, in every run)
    code = ("import sys\n"
            "from trackfuse.experiments import get\n"
            "from trackfuse.fingerprint import code_fingerprint\n"
            "modules = code_fingerprint(get('twin_sensor')).modules\n"
            "print('trackfuse.tracking.pda' in modules, "
            "'trackfuse.tracking.pda' in sys.modules, 'numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT).stdout.split()
    assert out == ["True", "False", "False"]


def test_other_library_versions_give_a_new_folder_and_say_which(write_config, tmp_path,
                                                                monkeypatch):
    """numpy's last bits may change with its version: an upgrade computes anew beside the
    old folder (never resumes into it nor serves it), and says which library changed."""
    import trackfuse.runner as runner_module

    config = load(write_config("experiment: toy_gaussian\ntrials: 6\nseed: 1\n"))
    first = Runner(config, tmp_path, progress=False, plots=False).run()
    upgraded = {**runner_module.library_versions(), "numpy": "99.0.0"}
    monkeypatch.setattr(runner_module, "library_versions", lambda: upgraded)
    notes: list[str] = []
    second = Runner(config, tmp_path, progress=False, plots=False, warn=notes.append).run()
    assert second.folder != first.folder and second.computed_trials == 6
    assert len(notes) == 1 and "other versions (numpy " in notes[0]
    assert notes[0].split("(numpy ")[1].startswith(f"{first_numpy(first.folder)}, now 99.0.0")
    manifest = json.loads((second.folder / "manifest.json").read_text())
    assert manifest["versions"]["numpy"] == "99.0.0"
    assert [set(c) for c in manifest["cpu"]] == [{"model", "numpy_simd", "blas",
                                                          "settings"}]
    assert (second.folder / "trials.csv").read_bytes() == (first.folder /
                                                           "trials.csv").read_bytes()


def first_numpy(folder: Path) -> str:
    return json.loads((folder / "manifest.json").read_text())["versions"]["numpy"]


def test_resuming_on_a_cpu_with_other_vector_extensions_says_so(write_config, tmp_path):
    config = load(write_config("experiment: toy_gaussian\ntrials: 8\nseed: 1\n"
                               "batch_size: 2\n"))
    with ctrl_c_at_part(3), pytest.raises(RunInterrupted) as err:
        Runner(config, tmp_path, executor="serial", progress=False, plots=False).run()
    manifest_path = err.value.folder / "manifest.json"
    manifest = json.loads(manifest_path.read_text())
    this_cpu = manifest["cpu"]
    notes: list[str] = []
    with ctrl_c_at_part(1), pytest.raises(RunInterrupted):  # resumed on the same CPU: silent
        Runner(config, tmp_path, executor="serial", progress=False, plots=False,
               warn=notes.append).run()
    assert notes == []
    older = {"model": "an older machine", "numpy_simd": ["SSE42"], "settings": {}}
    manifest_path.write_text(json.dumps({**manifest, "cpu": [older]}))  # an older run's
    resumed = Runner(config, tmp_path, executor="serial", progress=False, plots=False,
                     warn=notes.append).run()
    assert resumed.computed_trials == 4
    assert len(notes) == 1 and "resuming on another CPU" in notes[0]
    assert "the saved batches: an older machine, numpy SSE42)" in notes[0]
    assert json.loads(manifest_path.read_text())["cpu"] == [older, *this_cpu]


def test_a_sibling_manifest_with_damaged_versions_is_no_run_to_note(write_config, tmp_path,
                                                                     monkeypatch):
    """A sibling whose manifest fails validation (trackfuse.manifest) is skipped like any
    folder that is not a run: no note, no traceback."""
    import trackfuse.runner as runner_module

    config = load(write_config("experiment: toy_gaussian\ntrials: 4\nseed: 1\n"))
    first = Runner(config, tmp_path, progress=False, plots=False).run()
    manifest = json.loads((first.folder / "manifest.json").read_text())
    (first.folder / "manifest.json").write_text(json.dumps({**manifest, "versions": [1, 2]}))
    monkeypatch.setattr(runner_module, "library_versions",
                        lambda: {"python": "3", "numpy": None})
    notes: list[str] = []
    again = Runner(config, tmp_path, progress=False, plots=False, warn=notes.append).run()
    assert notes == [] and again.folder != first.folder and again.computed_trials == 4


def test_the_recorded_blas_kernel_is_the_one_openblas_runs():
    """docs/runner.md (run id): OPENBLAS_CORETYPE picks OpenBLAS's kernel, so it must change
    what the manifest's ``cpu`` says (Nehalem's kernel runs on every x86-64 CPU since 2008)."""
    probe = "from trackfuse.environment import cpu; print(cpu()['blas'])"
    env = {k: v for k, v in cli_env().items() if k != "OPENBLAS_CORETYPE"}
    default = subprocess.run([sys.executable, "-c", probe], env=env, text=True,
                             capture_output=True, check=True).stdout
    if "openblas" not in default or platform.machine() not in ("x86_64", "AMD64"):
        pytest.skip(f"numpy does not use OpenBLAS on x86-64 here: {default.strip()}")
    forced = subprocess.run([sys.executable, "-c", probe], text=True, capture_output=True,
                            env={**env, "OPENBLAS_CORETYPE": "Nehalem"}, check=True).stdout
    assert forced.strip() == "['openblas Nehalem']"


def test_a_cpu_recorded_before_blas_was_is_compared_on_the_rest():
    here = {"model": "m", "numpy_simd": ["AVX2"], "blas": ["openblas Haswell"], "settings": {}}
    older = {"model": "m", "numpy_simd": ["AVX2"], "settings": {}}
    assert unseen_cpus([here], [older]) == []
    assert unseen_cpus([here], [{**older, "numpy_simd": ["SSE42"]}]) == [here]
    assert unseen_cpus([here], [{**here, "blas": ["openblas SkylakeX"]}]) == [here]


@pytest.mark.parametrize("recorded", [{"model": "AMD EPYC"}, [{"model": "AMD EPYC"}], None])
def test_every_manifest_form_of_the_cpu_is_read(recorded):
    """A manifest from before the CPUs were listed holds one dict, or none: the run page's
    provenance reads each form."""
    found = recorded_cpus(recorded)
    assert [c["model"] for c in found] == ([] if recorded is None else ["AMD EPYC"])
