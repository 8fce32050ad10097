"""Progress of a run: a rich bar on a terminal, plain periodic lines otherwise (CI logs), and
one line per phase after the last trial (merging, summarising, drawing)."""

from __future__ import annotations

import math
import sys
import threading
import time
from collections.abc import Callable

from rich.console import Console
from rich.markup import escape
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskProgressColumn,
    TextColumn,
    TimeRemainingColumn,
)
from rich.table import Column

PLAIN_EVERY_S = 10.0
#: Columns the bar needs besides the label: count, percent, rate, "ETA", time left, gaps.
FIXED_WIDTH = 48
MIN_BAR_WIDTH = 10
#: Seconds after which the bar says why the workers are slow to start, if they are still
#: loading the experiment's code: that takes about one second, or on a first run after
#: installing, compiling its kernels, ten or more.
SLOW_START_S = 3.0
SLOW_START_WORDS = "first run compiles"


def duration_text(seconds: float, tenths: bool = False) -> str:
    """``"42 s"``, ``"3:05"`` or ``"1:02:03"``; ``"unknown"`` if not finite. ``tenths``: below 10 s
    in tenths (``"0.3 s"``)."""
    if not math.isfinite(seconds) or seconds < 0:
        return "unknown"
    if tenths and round(seconds, 1) < 10:
        return f"{seconds:.1f} s"
    whole = round(seconds)
    if whole < 60:
        return f"{whole} s"
    hours, rest = divmod(whole, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


def fit_label(label: str, width: int) -> str:
    """``label`` cut to ``width``: first its trailing ``" [...]"`` run id, then with an ellipsis."""
    if len(label) <= width:
        return label
    if label.endswith("]") and " [" in label:
        label = label[:label.rindex(" [")]
    return label if len(label) <= width else label[:max(width - 1, 1)] + "…"


class RunProgress:
    """Trials done / total with rate and ETA, as a context manager: a bar on a terminal, else
    plain lines. The rate is timed from the first finished batch's start, so start-up does not
    skew the ETA; after ``slow_start_s`` of ``loading()`` it says a first run compiles."""

    def __init__(self, total: int, done: int, label: str, enabled: bool = True,
                 console: Console | None = None, loading: Callable[[], bool] | None = None,
                 slow_start_s: float = SLOW_START_S):
        self.total, self.done, self.label = total, done, label
        self.start_done = done
        self._t0: float | None = None  # when the first finished batch started
        self._loading = loading
        self._slow_start = threading.Timer(slow_start_s, self._say_slow_start)
        self._slow_start.daemon = True
        self._last_print, self._printed = time.monotonic(), -1
        console = console or Console(stderr=True)
        self._rich = enabled and console.is_terminal
        self._plain = enabled and not self._rich
        if self._rich:
            room = max(console.width - FIXED_WIDTH - MIN_BAR_WIDTH, 8)
            shown = fit_label(label, room)
            self._bar = Progress(
                TextColumn("{task.description}", table_column=Column(no_wrap=True)),
                BarColumn(bar_width=None), MofNCompleteColumn(), TaskProgressColumn(),
                TextColumn("{task.fields[rate]}"), TextColumn("ETA"), TimeRemainingColumn(),
                console=console, expand=True)
            self._task = self._bar.add_task(escape(shown), total=total, completed=done,
                                            rate="starting workers")

    def __enter__(self) -> RunProgress:
        if self._rich:
            self._bar.start()
        elif self._plain:
            self._line()
        if (self._rich or self._plain) and self._loading is not None:
            self._slow_start.start()
        return self

    def __exit__(self, *exc) -> None:
        self._stop_slow_start()
        if self._rich:
            self._bar.stop()
        elif self._plain and self.done != self._printed:
            self._line()

    def rate(self) -> float:
        """Trials per second since the first finished batch started; 0 before one has finished."""
        if self._t0 is None:
            return 0.0
        return (self.done - self.start_done) / max(time.monotonic() - self._t0, 1e-9)

    def advance(self, trials: int, busy_s: float = 0.0) -> None:
        """Count ``trials`` more done, by a batch that computed for ``busy_s`` seconds."""
        if self._t0 is None:
            self._t0 = time.monotonic() - busy_s
            self._stop_slow_start()
        self.done += trials
        if self._rich:
            self._bar.update(self._task, completed=self.done, rate=f"{self.rate():,.0f} trials/s")
        elif self._plain and time.monotonic() - self._last_print >= PLAIN_EVERY_S:
            self._line()

    def _say_slow_start(self) -> None:
        """The slow-start words, from the timer's thread, if the workers are still loading."""
        if self._t0 is not None or self._loading is None or not self._loading():
            return
        if self._rich:
            self._bar.update(self._task, rate=SLOW_START_WORDS)
        else:
            print(f"{self.label}: the workers are still loading the experiment's code; a "
                  "first run after installing compiles it first", file=sys.stderr, flush=True)

    def _stop_slow_start(self) -> None:
        """Cancel the slow-start timer and wait for its thread (a thread left running would
        keep the report from forking its drawing processes)."""
        self._slow_start.cancel()
        if self._slow_start.is_alive():
            self._slow_start.join()

    def _line(self) -> None:
        self._last_print = time.monotonic()
        self._printed = self.done
        print(plain_line(self.label, self.done, self.total, self.rate()), file=sys.stderr,
              flush=True)


def plain_line(label: str, done: int, total: int, rate: float) -> str:
    """One progress line for logs; the rate and ETA only once trials have been timed."""
    pct = 100.0 * done / max(total, 1)
    text = f"{label}: {done:,}/{total:,} trials ({pct:.0f}%)"
    if rate > 0:
        text += f", {rate:,.0f} trials/s, ETA {duration_text((total - done) / rate)}"
    return text


class PhaseLog:
    """Announces each phase after the last trial on stderr with the previous phase's time."""

    def __init__(self, label: str, enabled: bool = True,
                 write: Callable[[str], None] | None = None):
        self.label, self.enabled = label, enabled
        self._write = write or (lambda text: print(text, file=sys.stderr, flush=True))
        self._previous: tuple[str, float] | None = None

    def __call__(self, phase: str) -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        took = ""
        if self._previous is not None:
            seconds = now - self._previous[1]
            took = f" ({self._previous[0]} took {duration_text(seconds, tenths=True)})"
        self._previous = (phase, now)
        self._write(f"{self.label}: {phase}...{took}")
