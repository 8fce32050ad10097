"""Setup of the processes a run forks: pool workers and drawing processes.

Ctrl-C in a terminal reaches every process of the group. The main process stops the run
(one line, exit 130) and ends its children, so they ignore it: otherwise each printed its
own ``KeyboardInterrupt`` traceback. (The fork server starts with it ignored:
:mod:`trackfuse.executors`.)

A main process that is killed (``kill -9``, out of memory), or interrupted while its pool was
still starting a worker, cannot end every child, and an idle pool worker waits for work
forever: it holds a copy of its own task queue, so the queue never reports that the other end
is gone, and it keeps the fork server alive too (multiprocessing hands every child the fork
server's keep-alive pipe). So each child watches the main process and ends when it does.
"""

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
    """A pool worker's or drawing process's start: ignore Ctrl-C, and end when the process
    ``main_pid`` (the run's main process) ends."""
    ignore_ctrl_c()
    threading.Thread(target=_exit_with, args=(main_pid,), name="trackfuse-exit-with-main",
                     daemon=True).start()


def _exit_with(pid: int) -> None:
    """Wait (without using the CPU where Linux's pidfd exists) until process ``pid`` has
    ended, then end this process at once."""
    try:
        handle = os.pidfd_open(pid)
    except (AttributeError, OSError):  # not Linux, or ``pid`` is gone already
        while process_alive(pid):
            time.sleep(1.0)
    else:
        select.select([handle], [], [])
    os._exit(1)


def process_alive(pid: int) -> bool:
    """Whether process ``pid`` runs on this host: it exists and, where ``/proc`` tells, has
    not ended (a killed process stays a zombie until its parent reaps it; ``trackfuse runs``
    listed a run killed by ``kill -9`` as running until then)."""
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
    """Hold a Ctrl-C or SIGTERM that arrives inside the block until the block ends, then
    raise it as the handler in place would. Around what starts a child process (a pool's
    ``submit``, the first submit of a fork pool): one arriving inside ``Process.start`` or
    ``os.fork`` left a worker the pool did not know of, which printed a traceback after the
    command had exited, or was raised inside a fork hook, printed as "Exception ignored" and
    lost (the run went on and exited 0). ``held_words``, if given, go to standard error as
    the first signal is held (a block that can last seconds). Only in the main thread
    (elsewhere a no-op)."""
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

