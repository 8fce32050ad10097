"""trackfuse.progress: the bar fits 80 columns, plain lines read well, phases are announced."""

from __future__ import annotations

import io
import re

from rich.console import Console

from trackfuse.progress import PhaseLog, RunProgress, duration_text, fit_label, plain_line


def test_durations_read_as_seconds_minutes_or_hours():
    assert [duration_text(s) for s in (0.4, 42, 185, 3723, float("nan"), float("inf"))] == \
        ["0 s", "42 s", "3:05", "1:02:03", "unknown", "unknown"]
    # a phase of a small run read "took 0 s"
    assert [duration_text(s, tenths=True) for s in (0.04, 0.34, 9.94, 9.96, 42, 185)] == \
        ["0.0 s", "0.3 s", "9.9 s", "10 s", "42 s", "3:05"]


def test_plain_line_has_no_eta_before_a_rate_and_formats_it_after():
    assert plain_line("exp", 0, 1000, 0.0) == "exp: 0/1,000 trials (0%)"
    assert plain_line("exp", 250, 1000, 2.0) == \
        "exp: 250/1,000 trials (25%), 2 trials/s, ETA 6:15"


def test_label_drops_the_run_id_first_then_ellipsises():
    label = "twin_sensor [seed20051001-0123456789ab]"
    assert fit_label(label, 60) == label
    assert fit_label(label, 20) == "twin_sensor"
    assert fit_label(label, 8) == "twin_se…"


def test_bar_at_80_columns_keeps_the_count_and_eta_visible():
    sink = io.StringIO()
    console = Console(file=sink, width=80, force_terminal=True, color_system=None)
    bar = RunProgress(12000, 0, "twin_sensor [seed20051001-0123456789ab]", console=console)
    with bar:
        bar.advance(3000)
    text = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", sink.getvalue())
    last = [line for line in text.replace("\r", "\n").splitlines() if "/12000" in line][-1]
    assert len(last) <= 80 and last.startswith("twin_sensor "), last
    assert "3000/12000" in last and "25%" in last and "ETA" in last, last


def test_phase_log_names_each_phase_and_the_time_of_the_previous_one():
    lines: list[str] = []
    log = PhaseLog("exp", write=lines.append)
    log("merging")
    log("summarising")
    assert lines[0] == "exp: merging..."
    assert lines[1].startswith("exp: summarising... (merging took ") and lines[1].endswith("s)")
    quiet: list[str] = []
    PhaseLog("exp", enabled=False, write=quiet.append)("merging")
    assert quiet == []


def test_rate_is_timed_from_the_first_batch_not_from_the_workers_start_up(monkeypatch):
    clock = [100.0]
    monkeypatch.setattr("trackfuse.progress.time.monotonic", lambda: clock[0])
    bar = RunProgress(1000, 0, "exp", enabled=False)
    assert bar.rate() == 0.0  # nothing timed yet: no ETA
    clock[0] = 130.0  # 30 s of start-up (a first run compiling its kernel), then a batch
    bar.advance(50, busy_s=0.5)
    assert bar.rate() == 100.0
    clock[0] = 130.5
    bar.advance(50, busy_s=0.5)
    assert bar.rate() == 100.0
    assert plain_line("exp", bar.done, bar.total, bar.rate()).endswith("ETA 9 s")
