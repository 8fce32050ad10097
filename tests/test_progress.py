"""trackfuse.progress: the bar fits 80 columns, plain lines read well, phases are announced."""

from __future__ import annotations

import io
import re
import time

from rich.console import Console

from trackfuse.progress import (
    SLOW_START_WORDS,
    PhaseLog,
    RunProgress,
    duration_text,
    fit_label,
    plain_line,
)


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


def _shown(sink: io.StringIO) -> list[str]:
    text = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", sink.getvalue())
    return text.replace("\r", "\n").splitlines()


def test_a_slow_start_says_a_first_run_compiles_while_the_workers_load():
    sink = io.StringIO()
    console = Console(file=sink, width=80, force_terminal=True, color_system=None)
    bar = RunProgress(12000, 0, "twin_sensor [seed20051001-0123456789ab]", console=console,
                      loading=lambda: True, slow_start_s=0.05)
    with bar:
        bar._slow_start.join()
        bar._bar.refresh()
        slow = [line for line in _shown(sink) if "/12000" in line][-1]
        bar.advance(3000)
    last = [line for line in _shown(sink) if "/12000" in line][-1]
    assert SLOW_START_WORDS in slow and len(slow) <= 80, slow
    assert SLOW_START_WORDS not in last and "trials/s" in last, last


def test_nothing_is_said_of_a_start_that_is_not_slow():
    for loading, batch_first in ((lambda: True, True), (lambda: False, False), (None, False)):
        sink = io.StringIO()
        console = Console(file=sink, width=80, force_terminal=True, color_system=None)
        with RunProgress(10, 0, "exp", console=console, loading=loading,
                         slow_start_s=0.2) as bar:
            if batch_first:
                bar.advance(5)
                # no thread left to keep the report from forking its drawing processes
                assert not bar._slow_start.is_alive()
            time.sleep(0.3)
        assert all(SLOW_START_WORDS not in line for line in _shown(sink))


def test_a_slow_start_is_one_plain_line_in_a_log(capsys):
    console = Console(file=io.StringIO(), force_terminal=False)
    with RunProgress(10, 0, "exp", console=console, loading=lambda: True,
                     slow_start_s=0.05) as bar:
        bar._slow_start.join()
        bar.advance(10)
    lines = capsys.readouterr().err.splitlines()
    assert lines[0] == "exp: 0/10 trials (0%)"
    assert lines[1] == ("exp: the workers are still loading the experiment's code; a first "
                        "run after installing compiles it first")
    assert len(lines) == 3 and lines[2].startswith("exp: 10/10 trials (100%)")


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
