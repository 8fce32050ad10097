"""Start-up time of the everyday commands: ``list``, ``validate`` and ``--help``.

Each command is run as a fresh process (``python -m trackfuse ...``, the way a user's shell
pays for it) several times; the median and the range of the wall times are printed, and the
median CPU time (user + system) of the process, which a busy machine inflates less than the
wall time. Goal: at most 0.5 s wall each (issue: the everyday CLI).

    python benchmarks/startup.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "plugin_example"  # the working folder: its plugin is found there
COMMANDS = {
    "trackfuse --help": ["--help"],
    "trackfuse list": ["list"],
    "trackfuse list twin_sensor": ["list", "twin_sensor"],
    "trackfuse validate configs/twin_sensor_orbit.yaml":
        ["validate", str(ROOT / "configs" / "twin_sensor_orbit.yaml")],
    # the same without the science's imports (scipy.stats...): a plugin declared in a module
    # that imports only trackfuse.experiments.base and numpy
    "trackfuse validate examples/plugin_example/coin.yaml":
        ["validate", str(ROOT / "examples" / "plugin_example" / "coin.yaml")],
}
GOAL_S = 0.5


def _children_cpu_s() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def timed_runs(args: list[str], repeats: int) -> tuple[list[float], list[float]]:
    """Wall and CPU seconds of ``repeats`` fresh runs of ``python -m trackfuse ARGS`` (output
    discarded); raises if the command fails."""
    walls, cpus = [], []
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), _children_cpu_s()
        subprocess.run([sys.executable, "-m", "trackfuse", *args], cwd=EXAMPLE, check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        walls.append(time.perf_counter() - t0)
        cpus.append(_children_cpu_s() - c0)
    return walls, cpus


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    print(f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f}")
    timed_runs(["--help"], 1)  # warm the file cache and the byte-code cache
    for label, command in COMMANDS.items():
        walls, cpus = timed_runs(command, args.repeats)
        median = statistics.median(walls)
        verdict = "ok" if median <= GOAL_S else f"over the {GOAL_S} s goal"
        print(f"{label:52s} wall median {median:.3f} s (min {min(walls):.3f}, max "
              f"{max(walls):.3f}), CPU median {statistics.median(cpus):.3f} s, "
              f"{args.repeats} runs: {verdict}")


if __name__ == "__main__":
    main()
