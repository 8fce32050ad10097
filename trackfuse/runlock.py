"""One writer per run folder (``docs/runner.md``, "One writer per run folder"): ``run`` and
``plot`` hold a ``filelock`` on ``<run>/.lock`` and record the holder in
``<run>/.lock.holder.json``; that file beside a free lock means a killed holder, taken over
with a warning."""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from collections.abc import Callable
from contextlib import suppress
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from filelock import FileLock, Timeout

from trackfuse.child_processes import process_alive
from trackfuse.regular_files import open_regular
from trackfuse.results import RunFolderError, atomic_write

LOCK_FILE = ".lock"
HOLDER_FILE = ".lock.holder.json"
HOLDER_WAIT_S = 2.0
#: How long taking the lock waits for it (s): long enough for a --dry-run's glance at it
#: (:func:`busy_problem`) to pass, short beside a run that holds it.
LOCK_WAIT_S = 0.5


class RunFolderBusy(RunFolderError):
    """Another process holds the run folder's lock; ``str(err)`` names it in one line."""


def _describe(holder: dict[str, Any] | None) -> str:
    if not holder:
        return "another trackfuse process"
    return (f"trackfuse pid {holder.get('pid', '?')} on {holder.get('host', '?')} "
            f"(since {holder.get('since', '?')})")


class RunLock:
    """Hold the lock of run folder ``path`` (created if needed) in a ``with`` block; ``warn`` gets a
    line when a killed process's lock is taken over. Raises :class:`RunFolderBusy` or
    :class:`RunFolderError`."""

    def __init__(self, path: Path, warn: Callable[[str], None]):
        self.path, self.warn = Path(path), warn
        self._lock: FileLock | None = None

    def __enter__(self) -> RunLock:
        try:
            self.path.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise RunFolderError(f"{self.path}: cannot create the run folder "
                                 f"({err.strerror or type(err).__name__})") from None
        lock = FileLock(str(self.path / LOCK_FILE))
        try:
            lock.acquire(timeout=LOCK_WAIT_S)
        except Timeout:
            raise RunFolderBusy(f"{self.path}: in use by {_describe(self._current_holder())}; "
                                "wait for it to finish (or stop it) and run again") from None
        except OSError as err:
            raise RunFolderError(f"{self.path / LOCK_FILE}: cannot lock "
                                 f"({err.strerror or type(err).__name__})") from None
        self._lock = lock
        try:
            previous = self.holder()
            if previous is not None:
                self.warn(f"{self.path}: taking over from {_describe(previous)}, which stopped "
                          "without releasing the run folder")
            atomic_write(self.path / HOLDER_FILE, json.dumps({
                "pid": os.getpid(), "host": platform.node(),
                "since": datetime.now(UTC).isoformat(timespec="seconds"),
                "command": sys.argv[:20]}) + "\n")
        except OSError as err:
            self._release()
            raise RunFolderError(f"{self.path / HOLDER_FILE}: cannot write "
                                 f"({err.strerror or type(err).__name__})") from None
        except BaseException:
            self._release()
            raise
        return self

    def _current_holder(self) -> dict[str, Any] | None:
        """The holder, waiting up to :data:`HOLDER_WAIT_S` for a new one to record itself."""
        deadline = time.monotonic() + HOLDER_WAIT_S
        while (holder := self.holder()) is None and time.monotonic() < deadline:
            time.sleep(0.05)
        return holder

    def holder(self) -> dict[str, Any] | None:
        """Who holds (or last held without releasing) the lock, if recorded."""
        path = self.path / HOLDER_FILE
        try:
            with open_regular(path) as fh:  # a FIFO put there must not hang a listing
                holder = json.loads(fh.read(100_000).decode("utf-8"))
        except FileNotFoundError:
            return None
        except (OSError, UnicodeDecodeError, ValueError):
            return {"pid": "?", "host": "? (unreadable holder file)"}
        return holder if isinstance(holder, dict) else {"pid": "?", "host": "?"}

    def __exit__(self, *exc: object) -> None:
        self._release()

    def _release(self) -> None:
        if self._lock is None:
            return
        with suppress(OSError):  # the next holder reports a take-over; the lock is released
            (self.path / HOLDER_FILE).unlink(missing_ok=True)
        self._lock.release()
        self._lock = None


def creation_problem(path: Path) -> str | None:
    """Why run folder ``path`` could not be created and written (one line, as
    :class:`RunLock` would stop), or ``None``; creates nothing (``--dry-run``)."""
    existing = path
    while not os.path.lexists(existing) and existing.parent != existing:
        existing = existing.parent
    if not existing.is_dir():  # a file, or a link to nothing or to a file
        return f"{path}: cannot create the run folder ({existing} is not a folder)"
    if not os.access(existing, os.W_OK | os.X_OK):
        return f"{path}: cannot create the run folder ({existing}: permission denied)"
    if existing != path and (why := _stores_no_folders(existing)):
        return f"{path}: cannot create the run folder ({existing}: {why})"
    return None


def _stores_no_folders(folder: Path) -> str | None:
    """Why no folder can be made in ``folder`` whatever the permissions say (read-only, or a file
    system without blocks and inodes such as ``/proc``), else ``None``."""
    try:
        fs = os.statvfs(folder)
    except (AttributeError, OSError):
        return None
    if fs.f_flag & getattr(os, "ST_RDONLY", 1):
        return "a read-only file system"
    if fs.f_blocks == 0 and fs.f_files == 0:
        return "a file system that stores no files, such as /proc"
    return None


def busy_problem(path: Path) -> str | None:
    """The line :class:`RunLock` would stop with if another process holds ``path``'s lock now, else
    ``None``, asked without taking the lock."""
    try:
        import fcntl
        fd = os.open(path / LOCK_FILE, os.O_RDONLY | os.O_NONBLOCK)  # a FIFO: no wait
    except (ImportError, OSError):
        return None
    try:
        fcntl.flock(fd, fcntl.LOCK_SH | fcntl.LOCK_NB)
    except OSError:
        return f"{path}: in use by {_describe(RunLock(path, lambda _: None).holder())}"
    finally:
        os.close(fd)  # releases the shared lock, if taken
    return None


def held_by_a_live_process(path: Path) -> bool:
    """Whether run folder ``path`` looks held, from its holder file alone (a listing must not take
    the lock); a holder on another host is taken as alive."""
    holder = RunLock(path, lambda _: None).holder()
    if holder is None:
        return False
    pid = holder.get("pid")
    if holder.get("host") != platform.node() or not isinstance(pid, int):
        return True
    return process_alive(pid)
