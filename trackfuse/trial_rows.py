"""What a trial may return (rules: ``docs/plugins.md``, ``run_trial``), checked one way for row
dicts and a RowTable: anything else fails the trial with a :class:`TypeError` naming the
column. A RowTable is checked by column first, and trial by trial only when suspect."""

from __future__ import annotations

from typing import Any

import numpy as np

from trackfuse.coerce import one_line
from trackfuse.experiments.base import Experiment
from trackfuse.rowformat import RUNNER_COLUMNS, TIME_SUFFIX, format_value
from trackfuse.rowtable import RowTable, column_cells

#: Plain numbers a metric may be given as (``None`` too: an empty cell).
NUMBER_TYPES = (int, float, bool)


def _is_number(value: Any) -> bool:
    """Whether ``value`` is a plain or numpy ``int``, ``float`` or ``bool`` (or None)."""
    return value is None or type(value) in NUMBER_TYPES or \
        isinstance(value, np.integer | np.floating | np.bool_)


def checked_rows(result: Any, producer: str, experiment: Experiment
                 ) -> list[dict[str, str]] | BaseException:
    """``result`` as ``trials.csv`` cells if valid, else the error (returned, not raised)."""
    if isinstance(result, BaseException):
        return result
    try:
        return _rows(result, producer, experiment)
    except TypeError as err:
        return err
    except Exception as err:  # noqa: BLE001 - the result's own methods raised
        return TypeError(f"{producer} returned a {type(result).__name__} that cannot be "
                         f"read: {one_line(err)}")


def _rows(result: Any, producer: str, experiment: Experiment) -> list[dict[str, str]]:
    """:func:`checked_rows`, raising the ``TypeError`` (or whatever the result raises)."""
    rows = list(result) if isinstance(result, list) else None
    if not rows or not all(isinstance(r, dict) for r in rows):
        got = f"an empty {type(result).__name__}" if rows == [] else type(result).__name__
        raise TypeError(f"{producer} returned {got}; expected a non-empty list of row dicts")
    rows = [dict(r) for r in rows]  # plain dicts: a subclass's own items() is never called
    columns: dict[Any, None] = {}
    for row in rows:
        columns.update(dict.fromkeys(row))
    if problem := column_problem(experiment, list(columns), producer):
        raise problem
    for row in rows:
        for metric in experiment.metrics:
            if not _is_number(value := row.get(metric.name)):
                raise _value_error(producer, value, metric.name)
    cells = [{k: format_value(v) for k, v in row.items()} for row in rows]
    if problem := _duplicate_problem(experiment, cells, producer) or \
            _text_problem([*columns, *(c for row in cells for c in row.values())], producer):
        raise problem
    return cells


def _value_error(producer: str, value: Any, metric: str) -> TypeError:
    return TypeError(f"{producer} returned {_shown(value)} of type {type(value).__name__} for "
                     f"the metric {metric}; allowed: a real number (int, float or a numpy "
                     "one; NaN where it does not apply)")


def _shown(value: Any) -> str:
    """``repr(value)`` cut to 40 characters, or the type's name if ``repr`` raises."""
    try:
        return f"{value!r:.40}"
    except Exception:  # noqa: BLE001 - a value whose repr raises is shown by its type
        return f"a {type(value).__name__}"


def column_problem(experiment: Experiment, columns: list[Any], producer: str
                   ) -> TypeError | None:
    """A ``TypeError`` naming what is wrong with the column names of rows (not a string, a missing
    metric or row key, a parameter's or runner column's name), else ``None``."""
    if odd := [_shown(c) for c in columns if type(c) is not str]:
        return TypeError(f"{producer} returned rows with column names that are not strings: "
                         f"{', '.join(odd)}; allowed: str")
    have = f"; the rows have {', '.join(sorted(columns))}"
    for what, names in (("declared metric", experiment.missing_metrics(columns)),
                        ("row key", [k for k in experiment.row_keys if k not in columns])):
        if names:
            return TypeError(f"{producer} returned rows without the {what}"
                             f"{'s' if len(names) > 1 else ''} {', '.join(names)}{have}")
    if clash := sorted(c for c in columns if c in experiment.schema or c in RUNNER_COLUMNS):
        return TypeError(f"{producer} returned rows with a column named like a parameter or a "
                         f"runner column ({', '.join(RUNNER_COLUMNS)}): {', '.join(clash)}; "
                         "allowed: metric and row key names of their own")
    return None


def _duplicate_problem(experiment: Experiment, cells: list[dict[str, str]], producer: str
                       ) -> TypeError | None:
    """A ``TypeError`` if two of one trial's rows (as CSV cells) have the same row keys."""
    seen: set[tuple[str, ...]] = set()
    for row in cells:
        key = tuple(row[k] for k in experiment.row_keys)
        if key in seen:
            named = ", ".join(f"{k}={v}" for k, v in zip(experiment.row_keys, key, strict=True))
            return TypeError(f"{producer} returned two rows of one trial with {named}; "
                             f"allowed: one row per trial and row key "
                             f"({', '.join(experiment.row_keys)})")
        seen.add(key)
    return None


def _text_problem(texts: list[str], producer: str) -> TypeError | None:
    """A ``TypeError`` if one of ``texts`` cannot be written as UTF-8 (a lone surrogate)."""
    try:
        "".join(texts).encode("utf-8")
    except UnicodeEncodeError:
        bad = next(t for t in texts if not t.isascii() and not _encodes(t))
        return TypeError(f"{producer} returned text that is not valid Unicode: "
                         f"{ascii(bad):.60}; allowed: text that can be written as UTF-8")
    return None


def _encodes(text: str) -> bool:
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return False
    return True


def table_problem(experiment: Experiment, table: RowTable, producer: str) -> TypeError | None:
    """What is wrong with a batch's RowTable as a whole (its column names, or a timing
    table whose columns differ in length), else ``None``: every trial of the batch fails."""
    if problem := column_problem(experiment, list(table.columns), producer):
        return problem
    lengths = {name: len(values) for name, values in table.timings.items()}
    if len(set(lengths.values())) > 1 or any(type(k) is not str for k in lengths):
        said = ", ".join(f"{_shown(k)} {n}" for k, n in lengths.items())
        return TypeError(f"{producer} returned a RowTable whose timing columns differ in "
                         f"length ({said}); allowed: columns of one length, named by strings")
    return None


def table_suspect(experiment: Experiment, table: RowTable) -> bool:
    """Whether a RowTable's values may break the rules, so its trials are checked one by one."""
    metrics = {m.name for m in experiment.metrics}
    for name, values in table.columns.items():
        array = np.asarray(values)
        if name in metrics and array.dtype.kind not in "biuf" and \
                not (array.dtype.kind == "O" and all(map(_is_number, array.tolist()))):
            return True
        if array.dtype.kind in "OUS" and not name.endswith(TIME_SUFFIX) and \
                _text_problem(column_cells(list(set(array.tolist()))), "") is not None:
            return True
    keys = [np.asarray(table.trial).tolist(), *map(_key_values, (table.columns[k] for k in
                                                                 experiment.row_keys))]
    return len(set(zip(*keys, strict=True))) < table.rows


def _key_values(values: np.ndarray) -> list[Any]:
    """A row key column's values, comparable as its CSV cells (NaN is one key)."""
    array = np.asarray(values)
    return column_cells(array) if array.dtype.kind == "f" else array.tolist()
