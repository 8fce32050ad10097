"""End-to-end wall time of the user's commands, today's code beside a baseline commit.

Absolute times differ between machines by 2x or more, so each command is timed for both
versions in the same run, alternating, and the ratio is what counts. Each version is
installed non-editable into its own virtual environment under ``.bench/`` (cached by commit),
exactly as a new user installs it, and runs its own shipped configs:

* ``run``: ``trackfuse run configs/twin_sensor_orbit.yaml --workers 2`` (figures included),
* ``run --no-plots``: the same without figures (simulation, filters, CSVs and summaries: the
  compute part, apart from the drawing),
* ``reproduce``: ``trackfuse reproduce configs --workers 2`` (every paper config, figures
  included; the two versions may ship different sets of configs, so the config counts are
  printed beside the times),
* ``reproduce-same``: the same command, both versions on the baseline's configs folder (the
  like-for-like comparison when the shipped configs have changed),
* ``startup``: ``trackfuse --help``, ``trackfuse list`` and ``trackfuse validate`` of the
  orbit config (what a ``--set`` trial-and-error loop pays each time),
* ``first run``: ``run --no-plots`` once with numba's on-disk cache emptied, as the first run
  after installing: the current version compiles its filter kernel then (once per install).
  Every other line is timed after an untimed run of each version's CI configs, so that all
  compiled kernels are cached (with ``--skip first`` too).

    python benchmarks/end_to_end.py [--baseline 6f49e5c] [--repeats 3] [--skip reproduce first]

The current version is the working tree's committed ``HEAD`` (uncommitted changes are not
measured). Prints the minimum and median over the repeats and the ratio baseline/current.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
CACHE = ROOT / ".bench"
MAIN_CONFIG = "configs/twin_sensor_orbit.yaml"


def _git(*args: str) -> str:
    return subprocess.run(["git", "-C", str(ROOT), *args], check=True, capture_output=True,
                          text=True).stdout.strip()


def install(commit: str) -> Path:
    """Export ``commit`` and install it into its own venv; return the source folder."""
    sha = _git("rev-parse", "--short=10", commit)
    home = CACHE / sha
    src, env = home / "src", home / "venv"
    if not (env / "bin" / "trackfuse").exists():
        src.mkdir(parents=True, exist_ok=True)
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", sha],
                                 check=True, capture_output=True).stdout
        subprocess.run(["tar", "-x", "-C", str(src)], input=archive, check=True)
        venv.create(env, with_pip=True)
        subprocess.run([str(env / "bin" / "pip"), "install", "--quiet", str(src)], check=True)
    return home


def timed(home: Path, *args: str, out: Path | None = None) -> float:
    """Wall seconds of ``trackfuse ARGS`` run in ``home/src`` with that version's venv."""
    cmd = [str(home / "venv" / "bin" / "trackfuse"), *args]
    if out is not None:
        cmd += ["--out", str(out), "--no-progress"]
    t0 = time.perf_counter()
    subprocess.run(cmd, cwd=home / "src", check=True, capture_output=True)
    return time.perf_counter() - t0


def measure(homes: dict[str, Path], commands: dict[str, list[str]], repeats: int,
            writes: set[str]) -> dict[str, dict[str, list[float]]]:
    """Times per command and version, alternating the versions' order every repeat."""
    times: dict[str, dict[str, list[float]]] = {c: {v: [] for v in homes} for c in commands}
    for rep in range(repeats):
        order = list(homes) if rep % 2 == 0 else list(reversed(homes))
        for command, args in commands.items():
            for version in order:
                with tempfile.TemporaryDirectory() as out:
                    where = Path(out) if command in writes else None
                    times[command][version].append(timed(homes[version], *args, out=where))
    return times


def first_run(home: Path) -> float:
    """Wall seconds of ``run --no-plots`` with numba's on-disk cache of ``home`` emptied."""
    for cached in (home / "venv").rglob("*.nb[ic]"):
        cached.unlink()
    with tempfile.TemporaryDirectory() as out:
        return timed(home, "run", MAIN_CONFIG, "--workers", "2", "--no-plots", out=Path(out))


def warm_up(home: Path) -> None:
    """Run the version's CI configs once, untimed: every compiled kernel (the twin-sensor
    filter, the passive PGA loop) is then in numba's on-disk cache, as after a user's first
    runs, so no timed command pays for a compilation."""
    with tempfile.TemporaryDirectory() as out:
        timed(home, "reproduce", "configs/ci", "--workers", "2", out=Path(out))


def config_count(home: Path) -> int:
    return len(list((home / "src" / "configs").glob("*.yaml")))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default="6f49e5c")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--skip", nargs="*", default=[],
                        choices=["run", "reproduce", "reproduce-same", "startup", "first"],
                        help="skip commands by first word (run skips both run lines)")
    args = parser.parse_args()
    homes = {"baseline": install(args.baseline), "current": install("HEAD")}
    commands = {
        "run": ["run", MAIN_CONFIG, "--workers", "2"],
        "run --no-plots": ["run", MAIN_CONFIG, "--workers", "2", "--no-plots"],
        "reproduce": ["reproduce", "configs", "--workers", "2"],
        "reproduce-same": ["reproduce", str(homes["baseline"] / "src" / "configs"),
                           "--workers", "2"],
        "startup --help": ["--help"],
        "startup list": ["list"],
        "startup validate": ["validate", MAIN_CONFIG],
    }
    commands = {k: v for k, v in commands.items() if k.split()[0] not in args.skip}
    firsts = {} if "first" in args.skip else \
        {name: first_run(home) for name, home in homes.items()}
    for home in homes.values():
        warm_up(home)
    times = measure(homes, commands, args.repeats,
                    writes={"run", "run --no-plots", "reproduce", "reproduce-same"})
    if firsts:
        times["first run --no-plots"] = {name: [t] for name, t in firsts.items()}
    for name, home in homes.items():
        print(f"{name}: {home.name}, {config_count(home)} paper configs")
    print(f"{'command':<18} {'baseline min/median s':>22} {'current min/median s':>21} "
          f"{'ratio (median)':>15}")
    for command, per_version in times.items():
        base, cur = per_version["baseline"], per_version["current"]
        ratio = statistics.median(base) / statistics.median(cur)
        print(f"{command:<18} {min(base):>10.2f} / {statistics.median(base):<9.2f} "
              f"{min(cur):>9.2f} / {statistics.median(cur):<9.2f} {ratio:>14.2f}x")


if __name__ == "__main__":
    sys.exit(main())
