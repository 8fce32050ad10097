"""An exception as one line of text of bounded length."""

from __future__ import annotations

import traceback

#: Longest :func:`one_line` text by default (characters): an error inside a message.
MESSAGE_CHARS = 300


def one_line(err: BaseException, limit: int = MESSAGE_CHARS) -> str:
    """``err`` as Python's last traceback line reads (``ValueError: bad value``; a type
    outside the builtins with its module; notes included), every run of white space one
    space, and at most ``limit`` characters (a longer text is cut and ends in ``...``)."""
    text = " ".join("".join(traceback.format_exception_only(type(err), err)).split())
    return text if len(text) <= limit else text[:limit - 3] + "..."
