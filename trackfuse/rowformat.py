"""The row format: the columns the runner adds to every trial row and how one value is
written as one CSV cell. Shared by the experiment contract, a trial's row table and the run
folder's files, so none of them imports another for it.
"""

from __future__ import annotations

import math
from typing import Any

#: Suffix of a timing column (seconds), kept out of ``trials.csv`` in ``timings.csv``.
TIME_SUFFIX = "_time_s"
FAILED_ROW = "failed"
"""``status`` of the one row a contained trial failure leaves in ``trials.csv``."""
RUNNER_COLUMNS = ("point", "trial", "status", "error")
"""Row columns the runner writes itself (a failed trial's row carries ``status`` and
``error``); never metrics, so an experiment may not name a metric after them."""


def format_value(value: Any) -> str:
    """One CSV cell: shortest round-trip repr for floats, ints as ints, bools as 0/1."""
    if hasattr(value, "dtype") and hasattr(value, "item"):
        value = value.item()  # numpy scalar -> Python scalar
    if value is None:
        return ""
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, float):
        return "nan" if math.isnan(value) else repr(value)
    if isinstance(value, (list, tuple)):
        return ";".join(format_value(v) for v in value)
    return str(value)


def csv_cell(text: str) -> str:
    """``text`` as one CSV field: quoted where it holds a comma, a quote or a line break
    (``\\r`` too, which :mod:`csv`'s writer leaves bare with a ``\\n`` line terminator)."""
    if "," in text or '"' in text or "\n" in text or "\r" in text:
        return '"' + text.replace('"', '""') + '"'
    return text
