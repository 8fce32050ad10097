"""Setup of the processes a run forks (pool workers, drawing processes): they ignore Ctrl-C,
which the main process handles (``docs/runner.md``), and each watches the main process and
ends when it does, since an idle pool worker would otherwise wait forever after a
``kill -9``."""

from __future__ import annotations

import os
import select
import signal
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager


def ignore_ctrl_c() -> None:
    """Leave Ctrl-C to the main process."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def setup_child(main_pid: int) -> None:
    """A child process's start: ignore Ctrl-C, end when ``main_pid`` ends."""
    ignore_ctrl_c()
    threading.Thread(target=_exit_with, args=(main_pid,), name="trackfuse-exit-with-main",
                     daemon=True).start()


def _exit_with(pid: int) -> None:
    """Wait (via pidfd where Linux has it) until process ``pid`` has ended, then end at once."""
    try:
        handle = os.pidfd_open(pid)
    except (AttributeError, OSError):  # not Linux, or ``pid`` is gone already
        while process_alive(pid):
            time.sleep(1.0)
    else:
        select.select([handle], [], [])
    os._exit(1)


def process_alive(pid: int) -> bool:
    """Whether process ``pid`` runs on this host: it exists and (per ``/proc``) no zombie."""
    another_user = False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # it exists, under another user: /proc tells its state
        another_user = True
    try:
        with open(f"/proc/{pid}/stat", "rb") as fh:
            state = fh.read().rsplit(b")", 1)[1].split()[0]
    except FileNotFoundError:  # gone meanwhile, hidden (hidepid), or no /proc (not Linux)
        return another_user or not os.path.exists("/proc/self")
    except (OSError, IndexError):
        return True
    return state not in (b"Z", b"X")


#: The signals that stop a command (Ctrl-C, and SIGTERM, which the command line maps to it).
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextmanager
def ctrl_c_held(held_words: str | None = None) -> Iterator[None]:
    """Hold a Ctrl-C or SIGTERM that arrives inside the block, then raise it as the handler would:
    around what starts a child, where one would leave a worker the pool does not know.
    ``held_words`` go to standard error when the first is held. Main thread only."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught: list[tuple[int, object]] = []

    def hold(signum: int, frame: object) -> None:
        if held_words and not caught:
            print(held_words, file=sys.stderr, flush=True)
        caught.append((signum, frame))

    handlers = {s: signal.signal(s, hold) for s in STOP_SIGNALS}
    try:
        yield
    finally:
        for s, handler in handlers.items():
            signal.signal(s, handler)
        if caught:
            signum, frame = caught[0]
            handler = handlers[signum]
            if callable(handler):
                handler(signum, frame)
            elif handler == signal.SIG_DFL:
                signal.raise_signal(signum)

