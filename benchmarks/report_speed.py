"""Time of redrawing a finished run's report (what ``trackfuse plot <folder>`` does).

For each run folder given (a complete run of, e.g., ``configs/twin_sensor_orbit.yaml``) it
prints, on a copy of the folder:

* ``trackfuse plot``: wall time of the real command in a fresh process (imports included);
* ``write_report(load(folder))`` in this process: the first call (cold: it pays one-off
  caches such as the PCRLB's clutter table) and the best of ``--repeat`` further calls, each
  as wall time and as this process's CPU time (CPU time is what the work costs on an idle
  core; wall time grows when other jobs share the machine);
* a per-figure breakdown: the time to draw each figure (the report module's ``figures``) and
  to save it in each format (wall), in the style the report uses, the CPU time of all of
  them together, the time of ``tables`` and of reading ``trials.csv``.

To compare two versions of the code on the same folder under the same load, run this script
with each checkout on ``PYTHONPATH``, one right after the other.

Usage: ``python benchmarks/report_speed.py RUN_FOLDER [RUN_FOLDER ...] [--repeat 3]
[--profile]``
"""

from __future__ import annotations

import argparse
import cProfile
import importlib
import io
import pstats
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from trackfuse import reports, rundata


def _copy(folder: Path, into: Path) -> Path:
    """A copy of ``folder``'s data files in ``into`` (the report rewrites figures/ and tables/
    and must not touch the original run)."""
    target = into / folder.name
    target.mkdir()
    for path in folder.iterdir():
        if path.is_file():
            (target / path.name).write_bytes(path.read_bytes())
    return target


def time_report(folder: Path) -> tuple[float, float]:
    """``(wall_s, cpu_s)`` of one ``write_report(load(folder))``."""
    wall, cpu = time.perf_counter(), time.process_time()
    report = reports.write_report(rundata.load(folder))
    if report.errors:
        print("  report errors:", *report.errors, sep="\n    ")
    return time.perf_counter() - wall, time.process_time() - cpu


def time_plot_command(folder: Path) -> float:
    """Wall time (s) of ``python -m trackfuse plot folder`` in a fresh process."""
    start = time.perf_counter()
    subprocess.run([sys.executable, "-m", "trackfuse", "plot", str(folder)], check=True,
                   capture_output=True)
    return time.perf_counter() - start


def breakdown(folder: Path) -> None:
    """Print the time of ``tables`` and of drawing and saving each figure."""
    run = rundata.load(folder)
    module = importlib.import_module(run.experiment.report)
    start = time.perf_counter()
    run.trials  # noqa: B018 - the CSV read, timed on its own
    print(f"  read trials.csv          {time.perf_counter() - start:6.2f} s")
    start = time.perf_counter()
    module.tables(run)
    print(f"  tables                   {time.perf_counter() - start:6.2f} s")
    formats = (run.config.get("outputs") or {}).get("formats") or ["png", "pdf"]
    total = 0.0
    for name in run.experiment.figures:
        with _house_style():  # drawn and saved as the report does
            start, cpu = time.perf_counter(), time.process_time()
            made = module.figures(run, [name])
            drawn, total = time.perf_counter() - start, total + time.process_time() - cpu
            fig = made.get(name)
            if not hasattr(fig, "savefig"):
                print(f"  {name:<32} not drawn: {fig}")
                continue
            saves = []
            for fmt in formats:
                start, cpu = time.perf_counter(), time.process_time()
                reports.save_figure(fig, folder / "figures", name, [fmt])
                saves.append(f"{fmt} {time.perf_counter() - start:5.2f} s")
                total += time.process_time() - cpu
        print(f"  {name:<32} draw {drawn:5.2f} s, save " + ", ".join(saves))
    print(f"  every figure drawn and saved   {total:6.2f} s CPU (this process, one at a time)")


def _house_style():
    """The style context the report draws and saves in (the report kit's, or before it
    existed the plots package's), so that this script times either version of the code."""
    try:
        from trackfuse.reportkit.style import context
    except ImportError:
        from trackfuse.plots.style import context
    return context()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("folders", nargs="+", type=Path)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--profile", action="store_true",
                        help="print the 25 most expensive calls (cumulative) of one report")
    args = parser.parse_args()
    start = time.perf_counter()
    importlib.import_module("matplotlib.backends.backend_agg")
    print(f"import matplotlib (agg): {time.perf_counter() - start:.2f} s "
          f"(python {sys.version.split()[0]})")
    with tempfile.TemporaryDirectory(prefix="trackfuse-report-speed-") as tmp:
        for folder in args.folders:
            work = _copy(folder, Path(tmp))
            importlib.import_module(rundata.load(work).experiment.report)
            print(f"{folder}:")
            print(f"  trackfuse plot (fresh process) {time_plot_command(work):6.2f} s wall")
            cold = time_report(work)
            warm = min((time_report(work) for _ in range(args.repeat)), key=lambda t: t[0])
            print(f"  write_report cold              {cold[0]:6.2f} s wall, {cold[1]:6.2f} s CPU")
            print(f"  write_report warm, best of {args.repeat}   {warm[0]:6.2f} s wall, "
                  f"{warm[1]:6.2f} s CPU")
            breakdown(work)
            if args.profile:
                profiler = cProfile.Profile()
                profiler.runcall(reports.write_report, rundata.load(work))
                out = io.StringIO()
                pstats.Stats(profiler, stream=out).sort_stats("cumulative").print_stats(25)
                print(out.getvalue())


if __name__ == "__main__":
    main()
