"""Open a file found inside a run folder only if it is a regular file, without blocking: a
FIFO or device there would hang the command, so it stops with one line instead."""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path
from typing import BinaryIO


class NotARegularFile(OSError):
    """A FIFO, socket, device or folder where a regular file belongs; ``strerror`` says which."""


def _kind(mode: int) -> str:
    """What a non-regular file is, in a few words."""
    for test, words in ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISSOCK, "a socket"),
                        (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                        (stat.S_ISDIR, "a folder")):
        if test(mode):
            return words
    return "not a regular file"


def open_regular(path: str | Path) -> BinaryIO:
    """``path`` opened for binary reading if it is (or links to) a regular file, else
    :class:`NotARegularFile`; the usual ``OSError`` when it cannot be opened. Never blocks."""
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            raise NotARegularFile(errno.EINVAL, f"{_kind(mode)}, not a regular file",
                                  str(path))
        os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def non_regular(path: str | Path) -> str | None:
    """What ``path`` is if it exists and is no regular file (``a FIFO (named pipe)``), or None."""
    try:
        mode = os.stat(path).st_mode
    except OSError:
        return None
    return None if stat.S_ISREG(mode) else _kind(mode)
