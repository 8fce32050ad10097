"""Where a command's CPU time goes, process by process (Linux).

Runs one command (by default the README's main command into a temporary folder) and polls
``/proc`` every 10 ms for every process it starts: the command itself, the process pool's
fork server and its workers, the drawing processes. For each it prints when it started
(seconds after the command) and the CPU seconds (user + system) it had used when last seen,
then the wall time and the sum. The sum over processes, divided by the cores, bounds the
wall time from below however well the work is overlapped. A process's last ~10 ms are
missed, so each figure is a slight underestimate.

    python benchmarks/process_cpu.py [--repeats 3] [-- trackfuse run CONFIG ...]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TICK = os.sysconf("SC_CLK_TCK")


@dataclass
class Seen:
    """One process of the command's tree as last seen in ``/proc``."""

    parent: int
    started_s: float
    cpu_s: float
    command: str


def _stat(pid: str) -> tuple[int, float] | None:
    """``(parent pid, CPU seconds)`` of ``pid``, or ``None`` if it is gone."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()
    return int(fields[1]), (int(fields[11]) + int(fields[12])) / TICK


def _command_line(pid: str) -> str:
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode()[:100]
    except OSError:
        return "?"


def profile(argv: list[str]) -> tuple[float, dict[int, Seen]]:
    """Run ``argv``; return its wall time (s) and every process of its tree."""
    start = time.perf_counter()
    root = subprocess.Popen(argv, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    seen: dict[int, Seen] = {}
    while root.poll() is None:
        for pid in filter(str.isdigit, os.listdir("/proc")):
            stat = _stat(pid)
            if stat is None:
                continue
            parent, cpu = stat
            if int(pid) == root.pid or parent in seen or int(pid) in seen:
                known = seen.get(int(pid))
                seen[int(pid)] = Seen(parent, known.started_s if known else
                                      time.perf_counter() - start, cpu,
                                      known.command if known else _command_line(pid))
        time.sleep(0.01)
    return time.perf_counter() - start, seen


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("command", nargs="*", help="the command (default: the main command)")
    args = parser.parse_args()
    walls, sums = [], []
    for _ in range(args.repeats):
        with tempfile.TemporaryDirectory(prefix="trackfuse-cpu-") as out:
            argv = args.command or [sys.executable, "-m", "trackfuse", "run",
                                    str(ROOT / "configs" / "twin_sensor_orbit.yaml"),
                                    "--workers", "2", "--no-progress", "--out", out]
            wall, seen = profile(argv)
        for pid, s in sorted(seen.items(), key=lambda kv: kv[1].started_s):
            print(f"  pid {pid:7d}  starts {s.started_s:5.2f} s  CPU {s.cpu_s:5.2f} s  "
                  f"{s.command or '(the command)'}")
        total = sum(s.cpu_s for s in seen.values())
        print(f"wall {wall:.2f} s, CPU {total:.2f} s over {len(seen)} processes")
        walls.append(wall)
        sums.append(total)
    print(f"median of {args.repeats}: wall {statistics.median(walls):.2f} s, "
          f"CPU {statistics.median(sums):.2f} s")


if __name__ == "__main__":
    main()
