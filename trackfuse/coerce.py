"""Plain values from loose ones: a count read from a manifest that may be damaged or older
than this version, and an exception as one line of text of bounded length.
"""

from __future__ import annotations

import traceback
from typing import Any

#: Longest :func:`one_line` text by default (characters): an error inside a message.
MESSAGE_CHARS = 300


def int_or(value: Any, default: int = 0) -> int:
    """``value`` if it is an ``int`` (a ``bool`` is not), else ``default``."""
    return value if isinstance(value, int) and not isinstance(value, bool) else default


def one_line(err: BaseException, limit: int = MESSAGE_CHARS) -> str:
    """``err`` as Python's last traceback line reads (``ValueError: bad value``; a type
    outside the builtins with its module; notes included), every run of white space one
    space, and at most ``limit`` characters (a longer text is cut and ends in ``...``)."""
    text = " ".join("".join(traceback.format_exception_only(type(err), err)).split())
    return text if len(text) <= limit else text[:limit - 3] + "..."
