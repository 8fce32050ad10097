"""Start-up time of the everyday commands: ``list``, ``validate`` and ``--help``.

Each command is run as a fresh process (``python -m trackfuse ...``, the way a user's shell
pays for it) several times; the median and the range of the wall times are printed. Goal:
at most 0.5 s each (issue: the everyday CLI).

    python benchmarks/startup.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = {
    "trackfuse --help": ["--help"],
    "trackfuse list": ["list"],
    "trackfuse list twin_sensor": ["list", "twin_sensor"],
    "trackfuse validate configs/twin_sensor_orbit.yaml":
        ["validate", str(ROOT / "configs" / "twin_sensor_orbit.yaml")],
}
GOAL_S = 0.5


def wall_times(args: list[str], repeats: int) -> list[float]:
    """Seconds of ``repeats`` fresh runs of ``python -m trackfuse ARGS`` (output discarded);
    raises if the command fails."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-m", "trackfuse", *args], cwd=ROOT, check=True,
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        times.append(time.perf_counter() - t0)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    args = parser.parse_args()
    wall_times(["--help"], 1)  # warm the file cache and the byte-code cache
    for label, command in COMMANDS.items():
        times = wall_times(command, args.repeats)
        median = statistics.median(times)
        verdict = "ok" if median <= GOAL_S else f"over the {GOAL_S} s goal"
        print(f"{label:55s} median {median:.3f} s (min {min(times):.3f}, max "
              f"{max(times):.3f}, {args.repeats} runs) {verdict}")


if __name__ == "__main__":
    main()
