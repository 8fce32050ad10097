"""--cluster slurm|pbs|local (dask-jobqueue): the job script it submits, its settings from
the config's cluster section or dask's config, and runs on an adaptive local job cluster
identical to serial, a worker dying mid-batch included."""

from __future__ import annotations

import json

import pytest
from conftest import cli_env, trackfuse

from trackfuse.cluster_settings import ClusterSettings, walltime_seconds
from trackfuse.config import ConfigError, build, load
from trackfuse.runner import Runner

pytest.importorskip("dask_jobqueue")
from trackfuse.cluster import job_script  # noqa: E402

SECTION = ("cluster: {queue: short, account: proj42, cores: 8, memory: 16GB, "
           "walltime: '02:00:00', max_jobs: 20, job_extra_directives: ['--exclusive']}\n")
CFG = "experiment: toy_experiments:GAUSSIAN\ntrials: 31\nseed: 5\nsweep: {mu: [0, 1, 2]}\n"


def test_the_slurm_job_script_asks_for_the_config_sections_resources(write_config):
    config = load(write_config(CFG + SECTION))
    script = job_script("slurm", config.cluster, "tcp://10.1.2.3:8786")
    for line in ("#SBATCH -p short", "#SBATCH -A proj42", "#SBATCH --cpus-per-task=8",
                 "#SBATCH -t 02:00:00", "#SBATCH --exclusive", "export OMP_NUM_THREADS=1"):
        assert line in script.splitlines(), line
    worker = script.strip().splitlines()[-1]
    assert "tcp://10.1.2.3:8786" in worker and "--nworkers 8" in worker
    assert "--nthreads 1" in worker  # one process of one thread per core
    assert "--lifetime 6900s" in worker  # retires 5 minutes before the 2 h walltime
    pbs = job_script("pbs", config.cluster)
    assert "#PBS -q short" in pbs and "#PBS -l walltime=02:00:00" in pbs


def test_a_setting_left_out_comes_from_dasks_jobqueue_config():
    dask = pytest.importorskip("dask")
    with dask.config.set({"jobqueue.slurm.queue": "from-dask-config",
                          "jobqueue.slurm.walltime": "00:30:00"}):
        script = job_script("slurm", ClusterSettings(cores=2, memory="4GB"))
    assert "#SBATCH -p from-dask-config" in script and "#SBATCH -t 00:30:00" in script


def test_dry_run_prints_the_job_script(write_config):
    cfg = write_config(CFG + SECTION)
    shown = trackfuse("run", cfg, "--cluster", "slurm", "--dry-run")
    assert shown.returncode == 0, shown.stderr
    assert "#   #SBATCH -p short" in shown.stdout


def test_the_cluster_section_is_not_part_of_the_run_id(write_config, tmp_path):
    plain = Runner(load(write_config(CFG, "a")), tmp_path, progress=False)
    placed = Runner(load(write_config(CFG + SECTION, "b")), tmp_path, progress=False)
    assert plain.run_id == placed.run_id and "cluster" not in placed.resolved


@pytest.mark.parametrize(("section", "key"), [
    ("{walltime: 2h}", "cluster.walltime"), ("{cores: 0}", "cluster.cores"),
    ("{min_jobs: 3, max_jobs: 2}", "cluster.min_jobs"), ("{queues: a}", "cluster.queues"),
    ("{job_extra_directives: -x}", "cluster.job_extra_directives"), ("[a]", "cluster")])
def test_a_bad_cluster_setting_is_one_line_naming_its_key(write_config, section, key):
    with pytest.raises(ConfigError) as err:
        load(write_config(CFG + f"cluster: {section}\n"))
    assert err.value.key == key and "allowed" in err.value.message


def test_walltimes_in_the_batch_systems_spellings():
    assert walltime_seconds("02:00:00") == 7200 and walltime_seconds("1-00:00:00") == 86400
    assert walltime_seconds("30:00") == 1800 and walltime_seconds("2h") is None


@pytest.fixture
def workers_import_the_toys(monkeypatch):
    """Job workers are fresh processes: they find the toy experiments on PYTHONPATH."""
    monkeypatch.setenv("PYTHONPATH", cli_env()["PYTHONPATH"])


def _run(config, out, **kw):
    return Runner(config, out, progress=False, plots=False, **kw).run()


def test_a_local_job_cluster_run_equals_a_serial_one(write_config, tmp_path,
                                                    workers_import_the_toys):
    config = load(write_config(CFG + "cluster: {cores: 1, memory: 1GB, max_jobs: 2}\n"))
    serial = _run(config, tmp_path / "s", executor="serial")
    jobs = _run(config, tmp_path / "j", cluster="local")
    assert (jobs.folder / "trials.csv").read_bytes() == \
        (serial.folder / "trials.csv").read_bytes()
    manifest = json.loads((jobs.folder / "manifest.json").read_text())
    assert manifest["executor"] == "dask" and manifest["cluster"]["kind"] == "local"
    assert manifest["cluster"]["max_jobs"] == 2


def test_a_job_worker_killed_mid_batch_is_replaced_and_loses_nothing(tmp_path,
                                                                     workers_import_the_toys):
    """As a walltime kill: the worker process dies (os._exit) inside a batch; the scheduler
    runs the batch again on another worker (the adaptive cluster starts another job)."""
    marker = tmp_path / "died"
    config = build({"experiment": "toy_experiments:CRASH", "trials": 40, "seed": 2,
                    "params": {"marker": str(marker)},
                    "cluster": {"cores": 1, "memory": "1GB", "max_jobs": 2}}, "crash.yaml")
    reference = _run(config, tmp_path / "ref", executor="serial")
    survived = _run(config, tmp_path / "jobs", cluster="local")
    assert marker.exists(), "the worker never died: the test tested nothing"
    assert (survived.folder / "trials.csv").read_bytes() == \
        (reference.folder / "trials.csv").read_bytes()
