"""The config's ``cluster`` section, checked without importing dask (``docs/cluster.md``); a
setting left out falls back to dask's jobqueue configuration, and workers retire
:data:`LIFETIME_MARGIN_S` before the walltime."""

from __future__ import annotations

import re
from dataclasses import dataclass, fields
from typing import Any

#: The batch systems ``--cluster`` takes (``local``: the same jobs as local processes).
CLUSTER_KINDS = ("slurm", "pbs", "local")
#: Seconds before the walltime at which a worker retires, and the spread of that moment.
LIFETIME_MARGIN_S, LIFETIME_STAGGER_S = 300, 120
#: Lines every job script runs before its workers start: one BLAS thread per worker.
PROLOGUE = ("export OMP_NUM_THREADS=1", "export OPENBLAS_NUM_THREADS=1",
            "export MKL_NUM_THREADS=1")


@dataclass(frozen=True)
class ClusterSettings:
    """The config's ``cluster`` section; ``None`` leaves a setting to dask's config."""

    queue: str | None = None
    account: str | None = None
    cores: int | None = None
    processes: int | None = None
    memory: str | None = None
    walltime: str | None = None
    min_jobs: int = 0
    max_jobs: int = 1
    job_extra_directives: tuple[str, ...] = ()
    interface: str | None = None

    def job_kwargs(self, kind: str) -> dict[str, Any]:
        """Keyword arguments of the dask-jobqueue cluster of ``kind``: the settings,
        a lifetime ending before the walltime, and :data:`PROLOGUE` (not for ``local``)."""
        given = {"cores": self.cores, "memory": self.memory, "walltime": self.walltime,
                 "interface": self.interface,
                 "processes": self.processes or self.cores}
        if kind != "local":
            given.update(queue=self.queue, account=self.account)
        kwargs = {k: v for k, v in given.items() if v is not None}
        if self.job_extra_directives:
            kwargs["job_extra_directives"] = list(self.job_extra_directives)
        seconds = walltime_seconds(self.walltime) if kind != "local" else None
        if seconds is not None and seconds > 2 * LIFETIME_MARGIN_S:
            kwargs["worker_extra_args"] = ["--lifetime", f"{seconds - LIFETIME_MARGIN_S}s",
                                           "--lifetime-stagger", f"{LIFETIME_STAGGER_S}s"]
        if kind != "local":  # a local job runs its command without a shell
            kwargs["job_script_prologue"] = list(PROLOGUE)
        return kwargs


#: The keys a ``cluster`` section may hold.
SETTING_KEYS = tuple(f.name for f in fields(ClusterSettings))
_WALLTIME = re.compile(r"^(?:(\d+)-)?(?:(\d+):)?(\d+):(\d+)$")


def walltime_seconds(text: str | None) -> int | None:
    """Seconds of a walltime ``[D-]HH:MM:SS`` or ``MM:SS`` (SLURM, PBS), else ``None``."""
    match = _WALLTIME.match(str(text or "").strip())
    if not match:
        return None
    days, hours, minutes, seconds = (int(g) if g else 0 for g in match.groups())
    if match.group(2) is None:  # MM:SS
        hours, minutes, seconds = 0, minutes, seconds
    return ((days * 24 + hours) * 60 + minutes) * 60 + seconds


def settings_problem(section: dict[str, Any]) -> tuple[str, str] | None:
    """``(key, what is allowed)`` of the first bad entry of a ``cluster`` section, or ``None``."""
    texts = ("queue", "account", "memory", "walltime", "interface")
    for key, value in section.items():
        if key not in SETTING_KEYS:
            return key, f"unknown key; allowed: {', '.join(SETTING_KEYS)}"
        if key in texts and not isinstance(value, str):
            return key, "a string"
        if key in ("cores", "processes", "max_jobs", "min_jobs") and (
                isinstance(value, bool) or not isinstance(value, int)
                or value < (0 if key == "min_jobs" else 1)):
            return key, f"an integer >= {0 if key == 'min_jobs' else 1}"
        if key == "job_extra_directives" and not (
                isinstance(value, list) and all(isinstance(v, str) for v in value)):
            return key, "a list of strings (#SBATCH / #PBS lines without the prefix)"
    if section.get("min_jobs", 0) > section.get("max_jobs", 1):
        return "min_jobs", "at most max_jobs"
    if "walltime" in section and walltime_seconds(section["walltime"]) is None:
        return "walltime", "HH:MM:SS or D-HH:MM:SS"
    return None


def settings(section: dict[str, Any]) -> ClusterSettings:
    """A checked (:func:`settings_problem`) ``cluster`` section as settings."""
    values = dict(section)
    if "job_extra_directives" in values:
        values["job_extra_directives"] = tuple(values["job_extra_directives"])
    return ClusterSettings(**values)
