"""Tables on a report page: cells that are or start like a number (``74.0 % (71.7–79.2)``) get
class ``num`` and are right-aligned with three significant figures; prose stays left so it
wraps at the page's width."""

from __future__ import annotations

import html
import math
import re
from collections.abc import Sequence
from numbers import Integral, Real
from typing import Any

import numpy as np
import pandas as pd

from trackfuse.reportkit.numberformat import sig3

#: The style of a table of the house: the page's other rules come from the page itself.
TABLE_CSS = ("table{border-collapse:collapse;font-size:90%;margin:1em 0}"
             "td,th{border:1px solid #ccc;padding:2px 6px;vertical-align:top;text-align:left}"
             "th{background:#f3f3f3}td.num,th.num{text-align:right;white-space:nowrap}")
_NUMBER = re.compile(r"^[\[(]?[+\-\u2212]?(\d|\.\d)")


def cell_text(value: Any) -> str:
    """A cell's text: numbers with three significant figures, empty for a missing value."""
    if value is None or value is pd.NA or (isinstance(value, float) and math.isnan(value)):
        return ""
    if isinstance(value, bool | np.bool_):
        return str(value)
    if isinstance(value, Integral):
        return str(int(value))
    if isinstance(value, Real):
        return sig3(float(value))
    return str(value)


def is_number(text: str) -> bool:
    """Whether a cell's text reads as a number (or a number with its interval)."""
    return bool(_NUMBER.match(text.strip()))


def html_table(headers: Sequence[str], rows: Sequence[Sequence[Any]],
               raw: Sequence[int] = (), row_class: Sequence[str] | None = None) -> str:
    """An HTML table of ``rows`` under ``headers`` (``raw`` columns are HTML already)."""
    texts = [[c if j in raw else html.escape(cell_text(c)) for j, c in enumerate(row)]
             for row in rows]
    numeric = [bool(rows) and j not in raw and all(
        is_number(html.unescape(r[j])) for r in texts if r[j]) and any(r[j] for r in texts)
        for j in range(len(headers))]
    head = "".join(f"<th{' class=num' if n else ''}>{html.escape(h)}</th>"
                   for h, n in zip(headers, numeric, strict=True))
    body = []
    for i, row in enumerate(texts):
        cls = f" class='{html.escape(row_class[i])}'" if row_class else ""
        body.append(f"<tr{cls}>" + "".join(
            f"<td{' class=num' if n else ''}>{c}</td>" for c, n in zip(row, numeric,
                                                                         strict=True)) + "</tr>")
    return f"<table><tr>{head}</tr>{''.join(body)}</table>"


def frame_html(table: pd.DataFrame) -> str:
    """:func:`html_table` of a data frame (its columns as headers)."""
    return html_table([str(c) for c in table.columns],
                      [list(r) for r in table.itertuples(index=False)])
