"""Wall time of redrawing a finished run's report (what ``trackfuse plot <folder>`` does).

Times :func:`trackfuse.reports.write_report` on :func:`trackfuse.rundata.load` of each run
folder given (a complete run of, e.g., ``configs/twin_sensor_orbit.yaml``), best of
``--repeat`` (the machine may be shared), then prints a per-figure breakdown: the time to
draw each figure (the report module's ``figures``) and to save it in each format, and the time
of ``tables``. Each repeat is a fresh process state only for the data (``load`` again); the
report module stays imported, as in a long session. ``--import`` adds the one-off import time
of the report module and matplotlib, which a fresh ``trackfuse plot`` process pays.

To compare two versions of the code on the same folder under the same load, run this script
once with each checkout's interpreter, one right after the other (``--repeat 3`` each).

Usage: ``python benchmarks/report_speed.py RUN_FOLDER [RUN_FOLDER ...] [--repeat 3]
[--profile]``
"""

from __future__ import annotations

import argparse
import cProfile
import importlib
import io
import pstats
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


def time_report(folder: Path, repeat: int) -> float:
    """Best wall time (s) of ``write_report(load(folder))`` over ``repeat`` runs."""
    best = float("inf")
    for _ in range(repeat):
        start = time.perf_counter()
        report = reports.write_report(rundata.load(folder))
        best = min(best, time.perf_counter() - start)
        if report.errors:
            print("  report errors:", *report.errors, sep="\n    ")
    return best


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
    for name in run.experiment.figures:
        start = time.perf_counter()
        made = module.figures(run, [name])
        drawn = time.perf_counter() - start
        fig = made.get(name)
        if not hasattr(fig, "savefig"):
            print(f"  {name:<32} not drawn: {fig}")
            continue
        saves = []
        for fmt in formats:
            start = time.perf_counter()
            reports.save_figure(fig, folder / "figures", name, [fmt])
            saves.append(f"{fmt} {time.perf_counter() - start:5.2f} s")
        print(f"  {name:<32} draw {drawn:5.2f} s, save " + ", ".join(saves))


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
            rundata.load(work)  # checksums match: the copy is byte-identical
            importlib.import_module(rundata.load(work).experiment.report)
            print(f"{folder}: write_report best of {args.repeat}: "
                  f"{time_report(work, args.repeat):.2f} s")
            breakdown(work)
            if args.profile:
                profiler = cProfile.Profile()
                profiler.runcall(reports.write_report, rundata.load(work))
                out = io.StringIO()
                pstats.Stats(profiler, stream=out).sort_stats("cumulative").print_stats(25)
                print(out.getvalue())


if __name__ == "__main__":
    main()
