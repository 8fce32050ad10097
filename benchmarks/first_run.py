"""The first run after installing beside a warm run, figures included: current vs a baseline.

Both versions are installed side by side as in ``end_to_end.py`` (``pip install`` of the
commit into its own venv) and timed alternately. For each version and repeat:

* ``cold``: ``trackfuse run configs/twin_sensor_orbit.yaml --workers 2`` (the README's main
  command, figures and report included) with numba's cache as ``pip install`` left it: every
  ``.nbi``/``.nbc`` file under the venv deleted, then the ones the install wrote put back
  (the current version's wheel ships its compiled kernels, ``setup.py``; the baseline's none);
  ``NUMBA_CACHE_DIR`` unset, so numba uses the cache beside the installed modules,
* ``warm``: the same command again right after (the cache as the cold run left it),
* ``empty``: the same command with no numba cache at all (every ``.nbi``/``.nbc`` deleted):
  what a machine pays whose numba version or CPU differs from the one that built the wheel,
* ``reinstall``: ``pip install --no-deps --force-reinstall`` of the version's source
  (building its wheel, which compiles the current version's kernels), timed once.

Prints wall seconds, median [min, max] over the repeats, and each version's median cold/warm
ratio (the goal of issue 43: at most 1.5).

    python benchmarks/first_run.py [--baseline b359dda] [--repeats 3]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from end_to_end import MAIN_CONFIG, install

RUN = ["run", MAIN_CONFIG, "--workers", "2", "--no-progress"]


def cache_files(home: Path) -> list[Path]:
    """numba's cache files under the version's venv."""
    venv = home / "venv"
    return [*venv.rglob("*.nbi"), *venv.rglob("*.nbc")]


def shipped_cache(home: Path, stash: Path) -> None:
    """Copy the cache files the install wrote (the venv as installed) into ``stash``."""
    for path in cache_files(home):
        target = stash / path.relative_to(home)
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(path, target)


def reset_cache(home: Path, stash: Path | None) -> None:
    """Delete every cache file under the venv, then restore ``stash`` (if given)."""
    for path in cache_files(home):
        path.unlink()
    if stash is not None:
        for saved in [*stash.rglob("*.nbi"), *stash.rglob("*.nbc")]:
            shutil.copy2(saved, home / saved.relative_to(stash))


def timed_run(home: Path) -> float:
    """Wall seconds of the main command in ``home/src`` with that version's venv."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    with tempfile.TemporaryDirectory() as out:
        cmd = [str(home / "venv" / "bin" / "trackfuse"), *RUN, "--out", out]
        t0 = time.perf_counter()
        subprocess.run(cmd, cwd=home / "src", env=env, check=True, capture_output=True)
        return time.perf_counter() - t0


def reinstall(home: Path) -> float:
    """Wall seconds of reinstalling the version from its source (its wheel rebuilt)."""
    cmd = [str(home / "venv" / "bin" / "pip"), "install", "--quiet", "--no-deps",
           "--force-reinstall", str(home / "src")]
    t0 = time.perf_counter()
    subprocess.run(cmd, check=True, capture_output=True)
    return time.perf_counter() - t0


def cell(values: list[float]) -> str:
    return f"{statistics.median(values):6.2f} [{min(values):.2f}, {max(values):.2f}]"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--baseline", default="b359dda")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    homes = {"baseline": install(args.baseline), "current": install("HEAD")}
    lines = ("cold", "warm", "empty", "reinstall")
    times: dict[str, dict[str, list[float]]] = {v: {line: [] for line in lines} for v in homes}
    with tempfile.TemporaryDirectory() as stash_root:
        stashes = {v: Path(stash_root) / v for v in homes}
        for version, home in homes.items():
            reset_cache(home, None)  # so the stash holds what the install wrote, no more
            times[version]["reinstall"].append(reinstall(home))
            stashes[version].mkdir()
            shipped_cache(home, stashes[version])
        for rep in range(args.repeats):
            for version in list(homes)[::1 if rep % 2 == 0 else -1]:
                home = homes[version]
                reset_cache(home, stashes[version])
                times[version]["cold"].append(timed_run(home))
                times[version]["warm"].append(timed_run(home))
                reset_cache(home, None)
                times[version]["empty"].append(timed_run(home))
            for version, home in homes.items():  # leave each venv as installed
                reset_cache(home, stashes[version])
    print(f"baseline {homes['baseline'].name}, current {homes['current'].name}: trackfuse "
          f"{' '.join(RUN)}; wall seconds, median [min, max] of {args.repeats}")
    for version, per_line in times.items():
        for line, values in per_line.items():
            print(f"{version:<9} {line:<10} {cell(values)}")
        ratio = statistics.median(per_line["cold"]) / statistics.median(per_line["warm"])
        print(f"{version:<9} cold/warm  {ratio:6.2f}")


if __name__ == "__main__":
    sys.exit(main())
