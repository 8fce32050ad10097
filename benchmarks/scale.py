"""Growth of a large twin_sensor study with its number of trials: time, memory, disk, resume.

Runs the orbit scenario (``configs/twin_sensor_orbit.yaml``: 16 clutter levels, 20 scans a
trial) with two algorithms (nearest neighbour and parallel PDA, both MGEKF; 40 per-scan rows
a trial) as ``trackfuse run --workers 2 --no-plots`` under ``/usr/bin/time -v`` (with
``--executor dask``: on a dask LocalCluster of 2 workers), for each ``--sizes`` total number
of trials (16 x the trials per level, so 1,000 is rounded to 992).
For each size it records, as one JSON line in ``--record``:

* wall seconds and the 1-minute load average before, during (mean) and after, and CPU
  seconds of every process (the machine is shared: CPU seconds are what the load does not
  stretch),
* peak resident memory of every process of the run's tree (sampled every 0.2 s: the
  command, the fork server, the two workers), and the largest single process as the kernel
  counts it,
* disk: ``trials.csv``, the run folder's peak while running (parts plus merged file; sampled
  every 5 s), and
  ``trials.parquet`` written from that CSV by :func:`trackfuse.store.write_parquet` (what
  ``outputs.store: parquet`` runs at the end of a run), with the conversion's time and memory,
* for sizes in ``--resume``: a second run killed with SIGKILL (the whole process group) once
  half of its batches are stored, then the same command again; ``trials.csv`` and
  ``summary.csv`` compared byte for byte with the uninterrupted run's.

``figure`` fits wall = start-up + trials x per-trial cost to the recorded points, prints
each point's deviation from the fit and draws time, memory and disk against trials.

    python benchmarks/scale.py run --sizes 1000 10000 100000 --resume 10000 \\
        --record docs/images/scale.jsonl
    python benchmarks/scale.py run --sizes 1000000 --record docs/images/scale.jsonl
    python benchmarks/scale.py figure --record docs/images/scale.jsonl --png docs/images/scale.png
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path

import psutil

LEVELS = 16  # the orbit config's clutter levels: range(0, 16, 1)
BATCH = 100  # twin_sensor's batch size: trials per part
ALGORITHMS = "algorithms=[nn/mgekf,mspda_parallel/mgekf]"
TRACKFUSE = str(Path(sys.executable).with_name("trackfuse"))


EXECUTOR = ["--executor", "process"]  # --executor dask: a 2-worker dask LocalCluster


def command(per_level: int, out: Path) -> list[str]:
    """The measured ``trackfuse run`` of ``per_level`` trials at each clutter level."""
    return [TRACKFUSE, "run", "twin_sensor_orbit", "--trials", str(per_level), "--set",
            ALGORITHMS, "--workers", "2", *EXECUTOR, "--out", str(out), "--no-plots",
            "--no-progress"]


def folder_bytes(folder: Path) -> int:
    """Bytes of the files under ``folder`` (files removed meanwhile are skipped)."""
    total = 0
    for root, _, names in os.walk(folder):
        for name in names:
            with contextlib.suppress(OSError):
                total += os.stat(os.path.join(root, name)).st_size
    return total


class Sampler(threading.Thread):
    """Peak RSS and last-seen CPU seconds of each process under ``pid`` (by pid), and peak
    bytes under ``out``."""

    def __init__(self, pid: int, out: Path):
        super().__init__(daemon=True)
        self.root, self.out, self.stop = psutil.Process(pid), out, threading.Event()
        self.peaks: dict[int, tuple[int, str]] = {}
        self.cpu: dict[int, float] = {}
        self.disk, self.loads = 0, []

    def role(self, proc: psutil.Process) -> str:
        """A short name for a process of the run: its command line, abbreviated."""
        with contextlib.suppress(psutil.Error):
            line = " ".join(proc.cmdline())
            if "forkserver" in line and "forkserver" in " ".join(proc.parent().cmdline()):
                return "worker"
            for key, name in (("forkserver", "fork server"), ("compile_pair_update",
                              "compile helper"), ("write_parquet", "parquet"),
                              ("resource_tracker", "resource tracker"),
                              ("trackfuse run", "command"), ("/usr/bin/time", "time")):
                if key in line:
                    return name
            return line[:40]
        return "?"

    def run(self) -> None:
        tick = 0
        while not self.stop.is_set():
            with contextlib.suppress(psutil.Error):
                for proc in [self.root, *self.root.children(recursive=True)]:
                    with contextlib.suppress(psutil.Error):
                        rss = proc.memory_info().rss
                        self.cpu[proc.pid] = sum(proc.cpu_times()[:2])
                        old = self.peaks.get(proc.pid)
                        if old is None or rss > old[0]:
                            self.peaks[proc.pid] = (rss, old[1] if old else self.role(proc))
            if tick % 25 == 0:  # every 5 s: walking 10^4 parts costs CPU the run shares
                self.disk = max(self.disk, folder_bytes(self.out))
                self.loads.append(os.getloadavg()[0])
            tick += 1
            time.sleep(0.2)


def timed(argv: list[str], out: Path) -> dict:
    """Run ``argv`` under ``/usr/bin/time -v``; wall s, peaks by process, peak disk, loads."""
    report = out / "time-v.txt"
    load0 = os.getloadavg()[0]
    start = time.perf_counter()
    proc = subprocess.Popen(["/usr/bin/time", "-v", "-o", str(report), *argv],
                            stdout=subprocess.DEVNULL)
    sampler = Sampler(proc.pid, out)
    sampler.start()
    code = proc.wait()
    wall = time.perf_counter() - start
    sampler.stop.set()
    sampler.join()
    if code != 0:
        raise SystemExit(f"{argv[:3]} failed with exit status {code}")
    text = report.read_text()
    def field(name: str) -> float:
        return float(re.search(rf"{name}: ([0-9.]+)", text).group(1))
    peaks = sorted(((rss / 2**20, role) for rss, role in sampler.peaks.values()
                    if role != "time"), reverse=True)
    return {"wall_s": wall, "load_before": load0, "load_after": os.getloadavg()[0],
            "load_mean": sum(sampler.loads) / max(len(sampler.loads), 1),
            "max_rss_mib": field(r"Maximum resident set size \(kbytes\)") / 1024,
            "process_peaks_mib": peaks,
            "process_cpu_s": sorted(((cpu, sampler.peaks[pid][1]) for pid, cpu in
                                     sampler.cpu.items() if sampler.peaks[pid][1] != "time"),
                                    reverse=True),
            "peak_disk_bytes": max(sampler.disk, folder_bytes(out))}


def run_folder(out: Path) -> Path:
    """The one run folder that ``trackfuse run --out out`` made."""
    found = [p.parent for p in out.rglob("trials.csv")]
    if len(found) != 1:
        raise SystemExit(f"{out}: expected one trials.csv, found {len(found)}")
    return found[0]


def killed_and_resumed(per_level: int, out: Path) -> dict:
    """Kill a run (SIGKILL, whole group) at half its batches, resume it; return times."""
    half = LEVELS * math.ceil(per_level / BATCH) / 2
    start = time.perf_counter()
    proc = subprocess.Popen(command(per_level, out), stdout=subprocess.DEVNULL,
                            start_new_session=True)
    stored = 0
    while proc.poll() is None and stored < half:
        time.sleep(0.1)
        stored = sum(1 for p in out.rglob("parts/*.trials.csv"))
    if proc.poll() is not None:
        raise SystemExit("the run finished before half of its batches were stored")
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    killed_at = time.perf_counter() - start
    resumed = time.perf_counter()
    subprocess.run(command(per_level, out), stdout=subprocess.DEVNULL, check=True)
    return {"killed_after_s": killed_at, "parts_at_kill": stored,
            "resume_s": time.perf_counter() - resumed}


def identical(a: Path, b: Path) -> bool:
    """``cmp``: the two files hold the same bytes."""
    return subprocess.run(["cmp", "-s", str(a), str(b)]).returncode == 0


def to_parquet(folder: Path) -> dict:
    """Convert ``folder/trials.csv`` to Parquet as the runner does; its size, time, memory."""
    code = ("import sys; from pathlib import Path; from trackfuse.store import write_parquet;"
            "f = Path(sys.argv[1]); write_parquet(f / 'trials.csv', f / 'trials.parquet')")
    measured = timed([sys.executable, "-c", code, str(folder)], folder.parent)
    return {"parquet_bytes": (folder / "trials.parquet").stat().st_size,
            "parquet_s": measured["wall_s"], "parquet_rss_mib": measured["max_rss_mib"]}


def measure(total: int, resume: bool, scratch: Path, save: Callable[[dict], None]) -> None:
    """Every figure of one size (``total`` trials, rounded to a multiple of 16), saved as
    each step ends (a run of 10^6 trials takes an hour or more on a shared machine)."""
    per_level = max(1, round(total / LEVELS))
    out = Path(tempfile.mkdtemp(prefix=f"scale{total}-", dir=scratch))
    record = {"trials": per_level * LEVELS, "per_level": per_level,
              "date": datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC"),
              **timed(command(per_level, out), out)}
    folder = run_folder(out)
    record["csv_bytes"] = (folder / "trials.csv").stat().st_size
    with open(folder / "trials.csv", "rb") as fh:
        record["rows"] = sum(1 for _ in fh) - 1
    save(record)
    if resume:
        other = Path(tempfile.mkdtemp(prefix=f"resume{total}-", dir=scratch))
        record.update(killed_and_resumed(per_level, other))
        again = run_folder(other)
        record["resume_identical"] = all(identical(folder / n, again / n)
                                         for n in ("trials.csv", "summary.csv"))
        subprocess.run(["rm", "-rf", str(other)], check=True)
        save(record)
    record.update(to_parquet(folder))
    save(record)
    subprocess.run(["rm", "-rf", str(out)], check=True)


def saver(path: Path) -> Callable[[dict], None]:
    """A function that writes a record into the JSON lines at ``path``, replacing the
    record of the same number of trials."""
    def save(record: dict) -> None:
        kept = [r for r in read_records(path) if r["trials"] != record["trials"]]
        path.write_text("".join(json.dumps(r) + "\n" for r in [*kept, record]))
    return save


def read_records(path: Path) -> list[dict]:
    """The records at ``path`` (none if it does not exist)."""
    if not path.exists():
        return []
    records = [json.loads(line) for line in path.read_text().splitlines() if line]
    for record in records:  # CPU of the whole tree: /usr/bin/time misses the pool's workers
        if "process_cpu_s" in record:
            record["cpu_s"] = sum(cpu for cpu, _ in record["process_cpu_s"])
    return records


def fit(records: list[dict], key: str = "wall_s") -> tuple[float, float]:
    """``(start-up s, s per trial)`` of ``key`` = a + b x trials, fitted to the records by
    least squares on the relative residuals (each point's error as a share of its value)."""
    import numpy as np
    trials = np.array([r["trials"] for r in records], float)
    seconds = np.array([r[key] for r in records], float)
    design = np.column_stack([np.ones_like(trials), trials]) / seconds[:, None]
    (a, b), *_ = np.linalg.lstsq(design, np.ones_like(trials), rcond=None)
    return float(a), float(b)


def figure(records: list[dict], png: Path) -> None:
    """Time, memory and disk against trials, three panels, 7.16 in wide."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    records = sorted(records, key=lambda r: r["trials"])
    n = [r["trials"] for r in records]
    fig, axes = plt.subplots(1, 3, figsize=(7.16, 2.5), layout="constrained")
    line = np.geomspace(min(n), max(n), 50)
    timed = [r for r in records if "cpu_s" in r]
    for key, name, mark, these in (("wall_s", "wall", "o", records),
                                   ("cpu_s", "CPU", "s", timed)):
        if len(these) < 2:
            continue
        a, b = fit(these, key)
        dots = axes[0].loglog([r["trials"] for r in these], [r[key] for r in these], mark,
                              label=f"{name}: {a:.0f} s + {b * 1e3:.2f} ms/trial")
        axes[0].loglog(line, a + b * line, "-", lw=0.8, color=dots[0].get_color())
    axes[0].set(xlabel="trials", ylabel="seconds", title="time")
    axes[1].semilogx(n, [r["process_peaks_mib"][0][0] for r in records], "o-",
                     label="largest process")
    axes[1].semilogx(n, [sum(p for p, _ in r["process_peaks_mib"]) for r in records], "s--",
                     label="sum of the processes' peaks")
    axes[1].set(xlabel="trials", ylabel="peak RSS (MiB)", title="memory", ylim=(0, None))
    axes[2].loglog(n, [r["csv_bytes"] / 1e6 for r in records], "o-", label="trials.csv")
    axes[2].loglog(n, [r["peak_disk_bytes"] / 1e6 for r in records], "^:",
                   label="run folder, peak")
    converted = [r for r in records if "parquet_bytes" in r]
    axes[2].loglog([r["trials"] for r in converted],
                   [r["parquet_bytes"] / 1e6 for r in converted], "s--", label="trials.parquet")
    axes[2].set(xlabel="trials", ylabel="MB", title="disk")
    for ax in axes:
        ax.legend(fontsize=6, frameon=False)
        ax.grid(alpha=0.3, lw=0.5)
    fig.savefig(png, dpi=200)


def deviations(records: list[dict], key: str) -> dict[int, float]:
    """Each record's ``key`` against the fitted start-up + per-trial line, in percent, by
    trials (printed with the fit)."""
    a, b = fit(records, key)
    print(f"fit: {key} = {a:.2f} s + trials x {b * 1e3:.4f} ms")
    return {r["trials"]: (r[key] / (a + b * r["trials"]) - 1) * 100 for r in records}


def report(records: list[dict]) -> None:
    """One line a size, with its deviations from the fitted lines (two sizes or more)."""
    records = sorted(records, key=lambda r: r["trials"])
    timed = [r for r in records if "cpu_s" in r]
    wall = deviations(records, "wall_s") if len(records) > 1 else {}
    cpu = deviations(timed, "cpu_s") if len(timed) > 1 else {}
    for r in records:
        shown = [(mib, role) for mib, role in r["process_peaks_mib"] if mib >= 5]
        peaks = ", ".join(f"{role} {mib:.0f}" for mib, role in shown)
        used = ", ".join(f"{role} {s:.1f}" for s, role in r.get("process_cpu_s", []) if s >= 0.1)
        resume = (f"; resume after kill -9 at {r['parts_at_kill']} parts: "
                  f"{'identical' if r['resume_identical'] else 'DIFFERENT'}"
                  if "resume_identical" in r else "")
        print(f"{r['trials']:>9,d} trials ({r['date']}, load {r['load_before']:.1f}/"
              f"{r['load_mean']:.1f}/{r['load_after']:.1f}): wall {r['wall_s']:.1f} s"
              f" ({wall.get(r['trials'], 0):+.1f} %)"
              + (f", CPU {r['cpu_s']:.1f} s ({cpu.get(r['trials'], 0):+.1f} %): {used}"
                 if "cpu_s" in r else "")
              + f"; peak RSS MiB {peaks}; csv {r['csv_bytes'] / 1e6:.1f} MB, folder peak "
              f"{r['peak_disk_bytes'] / 1e6:.1f} MB{parquet(r)}{resume}")


def parquet(record: dict) -> str:
    """``, parquet SIZE (TIME, MEMORY)`` of a record, if its CSV was converted."""
    if "parquet_bytes" not in record:
        return ""
    return (f", parquet {record['parquet_bytes'] / 1e6:.1f} MB ({record['parquet_s']:.1f} s, "
            f"{record['parquet_rss_mib']:.0f} MiB)")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("action", choices=["run", "figure"])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 10_000, 100_000])
    parser.add_argument("--resume", type=int, nargs="*", default=[10_000],
                        help="sizes whose run is also killed at half-way and resumed")
    parser.add_argument("--record", type=Path, required=True, help="JSON lines, one a size")
    parser.add_argument("--scratch", type=Path, default=Path(tempfile.gettempdir()))
    parser.add_argument("--png", type=Path)
    parser.add_argument("--executor", choices=["process", "dask"], default="process")
    args = parser.parse_args()
    EXECUTOR[1] = args.executor
    if args.action == "run":
        for total in args.sizes:
            measure(total, total in args.resume, args.scratch, saver(args.record))
    records = read_records(args.record)
    report(records)
    if args.png is not None:
        figure(records, args.png)


if __name__ == "__main__":
    main()
