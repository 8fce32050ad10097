"""Cost of compiling the twin-sensor kernel: the first run after installing, baseline vs now.

Both versions are installed side by side as in ``end_to_end.py`` and timed alternately, each
cold measurement with its own new, empty ``NUMBA_CACHE_DIR`` (as after installing):

* ``first run``: ``trackfuse run configs/twin_sensor_orbit.yaml --workers 2 --no-plots``,
* ``preload cold``: ``python -c "import trackfuse.experiments.twin_sensor.preload"`` (what
  the process pool's fork server does first: load or compile the kernel),
* ``preload warm``: the same import with the kernel already in the cache (what every later
  run pays).

Each line gives wall seconds and the CPU seconds (user + sys) of the process and the
children it waited for (the command's fork server is not waited for: its CPU is missing
from the ``first run`` line), as the median and range over the repeats.

    python benchmarks/first_run.py [--baseline 0c1f4e6] [--repeats 3] [--warm-repeats 5]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from end_to_end import MAIN_CONFIG, install

PRELOAD = "import trackfuse.experiments.twin_sensor.preload"


def timed(home: Path, cache: str, *cmd: str) -> tuple[float, float]:
    """Wall and CPU seconds (user + sys, waited-for children) of ``cmd`` run in ``home/src``
    with that version's venv first on ``PATH`` and numba's cache in ``cache``."""
    env = dict(os.environ, NUMBA_CACHE_DIR=cache,
               PATH=f"{home / 'venv' / 'bin'}{os.pathsep}{os.environ['PATH']}")
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=home / "src", env=env, check=True, capture_output=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def cold(home: Path, *cmd: str) -> tuple[float, float]:
    """:func:`timed` with a new, empty numba cache."""
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as out:
        return timed(home, cache, *(a.replace("{out}", out) for a in cmd))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default="0c1f4e6")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--warm-repeats", type=int, default=5)
    args = parser.parse_args()
    homes = {"baseline": install(args.baseline), "current": install("HEAD")}
    run = ["trackfuse", "run", MAIN_CONFIG, "--workers", "2", "--no-plots", "--no-progress",
           "--out", "{out}"]
    lines = {"first run": run, "preload cold": ["python", "-c", PRELOAD]}
    times: dict[str, dict[str, list]] = {k: {v: [] for v in homes} for k in
                                         [*lines, "preload warm"]}
    for rep in range(args.repeats):
        for version in list(homes)[::1 if rep % 2 == 0 else -1]:
            for line, cmd in lines.items():
                times[line][version].append(cold(homes[version], *cmd))
    with tempfile.TemporaryDirectory() as caches:
        for version, home in homes.items():  # fill each version's cache, untimed
            timed(home, f"{caches}/{version}", "python", "-c", PRELOAD)
        for rep in range(args.warm_repeats):
            for version in list(homes)[::1 if rep % 2 == 0 else -1]:
                times["preload warm"][version].append(
                    timed(homes[version], f"{caches}/{version}", "python", "-c", PRELOAD))
    print(f"baseline {homes['baseline'].name}, current {homes['current'].name}; "
          "median [min, max] seconds")
    for line, per_version in times.items():
        for version, values in per_version.items():
            cells = [f"{statistics.median(v):6.2f} [{min(v):.2f}, {max(v):.2f}]"
                     for v in zip(*values, strict=True)]
            print(f"{line:<13} {version:<9} wall {cells[0]}  cpu {cells[1]}")


if __name__ == "__main__":
    sys.exit(main())
