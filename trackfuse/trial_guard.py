"""What plugin code may not do to its process (``docs/runner.md``, "Failed trials"): ``os._exit``
raises :class:`PluginExit`, a trial past ``trial_timeout`` gets :class:`TrialTimeout`, and
non-daemon threads it left are listed by :func:`threads_left`."""

from __future__ import annotations

import ctypes
import multiprocessing
import os
import signal
import sys
import threading
import weakref
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from typing import Any

_real_exit = os._exit
#: (process id, thread id) of the threads whose plugin code is guarded now.
_guarded: set[tuple[int, int]] = set()
_left: weakref.WeakSet[threading.Thread] = weakref.WeakSet()
_exit_hook_set = False
_timeouts = 0  # trials this process interrupted at their time limit


class PluginExit(BaseException):
    """``os._exit`` called by plugin code: a failure of that code, not the process's end."""

    def __init__(self, code: int):
        super().__init__(f"os._exit({code}) called; the process was kept")


class TrialTimeout(BaseException):
    """A trial ran longer than the run's trial time limit (a ``BaseException``: a plugin's
    ``except Exception`` does not swallow it)."""

    def __init__(self, seconds: float):
        super().__init__(f"the trial ran longer than the limit of {seconds:g} s "
                         "(trial_timeout, --trial-timeout)")


#: What plugin code run in this process may raise and be failed for, not stop the run:
#: any error, ``sys.exit`` and ``os._exit`` (Ctrl-C still stops it).
PLUGIN_FAILURES = (Exception, SystemExit, PluginExit)


def _timeout_of(limit: float) -> type[TrialTimeout]:
    """:class:`TrialTimeout` for ``limit``, built without arguments as a cross-thread one is."""
    def init(self: TrialTimeout) -> None:
        TrialTimeout.__init__(self, limit)
    return type("TrialTimeout", (TrialTimeout,), {"__init__": init})


def timeouts() -> int:
    """How many trials this process has stopped at their time limit (its worker is replaced)."""
    return _timeouts


def _timed_out() -> None:
    global _timeouts
    _timeouts += 1


def _exit_unless_guarded(code: int) -> None:
    """``os._exit`` while some thread is guarded: :class:`PluginExit` in that thread."""
    if (os.getpid(), threading.get_ident()) in _guarded:
        raise PluginExit(code)
    _real_exit(code)


@contextmanager
def guarded(limit: float | None = None) -> Iterator[None]:
    """Run plugin code in this thread with ``os._exit`` raising :class:`PluginExit`, within
    ``limit`` seconds (``None``: no limit), and note the non-daemon threads it leaves."""
    me = (os.getpid(), threading.get_ident())
    before = set(threading.enumerate())
    outer = me in _guarded
    _guarded.add(me)
    os._exit = _exit_unless_guarded
    try:
        with _time_limit(limit):
            yield
    finally:
        if not outer:
            _guarded.discard(me)
        if not _guarded:
            os._exit = _real_exit
        _note_threads(before)


def _note_threads(before: set[threading.Thread]) -> None:
    new = [t for t in threading.enumerate() if t not in before and not t.daemon]
    if new:
        _left.update(new)
        if multiprocessing.parent_process() is not None:
            _end_without_waiting_at_exit()


def threads_left() -> list[threading.Thread]:
    """The non-daemon threads plugin code started and left running, still alive."""
    return [t for t in _left if t.is_alive()]


def _end_without_waiting_at_exit() -> None:
    """Make this child process (a pool worker) end at its exit without waiting for the
    threads its trials left: multiprocessing joins every non-daemon thread first."""
    global _exit_hook_set
    if not _exit_hook_set:
        from multiprocessing import util
        util.Finalize(None, _exit_now, exitpriority=-100)
        _exit_hook_set = True


def _exit_now() -> None:
    if threads_left():
        for stream in (sys.stdout, sys.stderr):
            with suppress(OSError, ValueError, AttributeError):
                stream.flush()
        _real_exit(0)


@contextmanager
def _time_limit(limit: float | None) -> Iterator[None]:
    """Raise :class:`TrialTimeout` in this thread once ``limit`` seconds have passed."""
    if not limit:
        yield
    elif threading.current_thread() is threading.main_thread():
        with _alarm(limit):
            yield
    else:
        with _async_alarm(limit):
            yield


@contextmanager
def _alarm(limit: float) -> Iterator[None]:
    def expire(signum: int, frame: Any) -> None:
        _timed_out()
        raise TrialTimeout(limit)

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, limit)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


@contextmanager
def _async_alarm(limit: float) -> Iterator[None]:
    """:class:`TrialTimeout` raised in this thread by a timer, withdrawn if the block ends first."""
    ident, lock, state = threading.get_ident(), threading.Lock(), {"active": True}

    def expire() -> None:
        with lock:
            if state["active"]:
                _timed_out()
                ctypes.pythonapi.PyThreadState_SetAsyncExc(
                    ctypes.c_ulong(ident), ctypes.py_object(_timeout_of(limit)))
                state["fired"] = True

    timer = threading.Timer(limit, expire)
    timer.daemon = True
    timer.start()
    try:
        yield
    finally:
        with lock:
            state["active"] = False
            timer.cancel()
            if state.get("fired"):
                ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(ident), None)
