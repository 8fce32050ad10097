"""A headline row (:data:`trackfuse.reports.HEADLINE_COLUMNS`) in a reader's words: the
method by its display name, the paper's value as the paper gives it, ours with its 95 %
interval in the house number format (:mod:`trackfuse.reportkit.numberformat`)."""

from __future__ import annotations

from functools import cache

import pandas as pd

from trackfuse import experiments
from trackfuse.reportkit.looks import Look, look_of
from trackfuse.reportkit.numberformat import sig3, with_interval

#: The columns of a headline table as a reader sees it (:func:`reader_cells`).
READER_HEADERS = ["paper item", "what we measured", "method", "paper",
                  "ours (95 % interval)", "runs", "verdict", "why"]


def text(value: object) -> str:
    """A cell as text, ``""`` for a missing value."""
    return "" if value is None or pd.isna(value) else str(value)


@cache
def _looks() -> dict[str, Look]:
    """The looks every built-in experiment declares (algorithm names are unique across
    them)."""
    return {name: look for experiment in experiments.BUILTIN
            for name, look in experiments.get(experiment).looks.items()}


def method(algorithm: object) -> str:
    """An algorithm's display name (its declared legend label); ``""`` for none."""
    name = text(algorithm)
    return look_of(_looks(), name).label if name else ""


def ours(row: pd.Series) -> str:
    """Our estimate with its 95 % interval in the house format."""
    if pd.isna(row["reproduced"]):
        return ""
    return with_interval(float(row["reproduced"]), float(row["ci_low"]),
                         float(row["ci_high"]), text(row["unit"]))


def paper_value(row: pd.Series) -> str:
    """The paper's value as the paper gives it: a rate in %, a printed number as printed,
    words as words."""
    value = row["paper_value"]
    try:
        number = float(value)
    except (TypeError, ValueError):
        return text(value)
    if text(row["unit"]) == "fraction":
        return f"{sig3(100 * number)} %"
    return f"{number:.6g}"


def reader_cells(row: pd.Series) -> list[str]:
    """One headline row as the cells of :data:`READER_HEADERS` (the reason last)."""
    trials = row["trials"]
    return [text(row["paper_item"]), text(row["quantity"]), method(row["algorithm"]),
            paper_value(row), ours(row), "" if pd.isna(trials) else str(int(trials)),
            text(row["verdict"]), text(row["reason"])]
