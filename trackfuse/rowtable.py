"""A batch's rows as columns, which a vectorized ``run_batch`` may return instead of dicts: the
CSV is written column by column, byte-identical to dict rows and far cheaper. Timings are
the batch's, in a separate small table (``docs/outputs.md``, ``timings.csv``)."""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from trackfuse.rowformat import csv_cell, format_value


def column_cells(values: np.ndarray | Sequence[Any]) -> list[str]:
    """The CSV fields ``(R,)`` of one column, as ``format_value`` writes each value."""
    a = np.asarray(values)
    if a.dtype.kind == "b":
        return np.where(a, "1", "0").tolist()
    if a.dtype.kind == "f":
        return list(map(repr, a.astype(float, copy=False).tolist()))
    if a.dtype.kind in "iu":
        return list(map(str, a.tolist()))
    quoted: dict[str, str] = {}  # labels (algorithm names) repeat: each is quoted once
    cells = []
    for value in a.tolist():
        if type(value) is str:
            if value not in quoted:
                quoted[value] = csv_cell(value)
            cells.append(quoted[value])
        else:
            cells.append(csv_cell(format_value(value)))
    return cells


@dataclass(frozen=True)
class Constant:
    """One value repeated on every row of :func:`columns_csv`."""

    value: Any


def columns_csv(columns: Mapping[str, np.ndarray | Sequence[Any] | Constant], rows: int) -> str:
    """CSV text, header first, of ``rows`` rows of ``columns`` ((rows,) arrays or Constants)."""
    cells: list[Sequence[str]] = []
    for name, values in columns.items():
        if isinstance(values, Constant):
            cells.append([csv_cell(format_value(values.value))] * rows)
            continue
        column = column_cells(values)
        if len(column) != rows:
            raise ValueError(f"column {name!r} has {len(column)} rows, expected {rows}")
        cells.append(column)
    return _csv_text([csv_cell(name) for name in columns], cells)


def _csv_text(header: list[str], cells: Sequence[Sequence[str]]) -> str:
    """CSV text of the ``header`` fields and one list of ready fields per column."""
    lines = [",".join(header)]
    lines.extend(map(",".join, zip(*cells, strict=True)))
    return "\n".join(lines) + "\n"


def frame_csv(frame) -> str:
    """``frame.to_csv(index=False)`` byte for byte, about twice as fast for float columns; frames
    with other column types, unusual names or fewer than two columns are written by pandas."""
    names = list(frame.columns)
    if len(names) < 2 or len(set(names)) < len(names) \
            or not all(type(n) is str for n in names) or not _plain_texts(names):
        return frame.to_csv(index=False)
    cells: list[list[str]] = []
    for name in frame.columns:
        column = frame[name]
        dtype = column.dtype
        values = column.tolist()
        if isinstance(dtype, np.dtype) and dtype == np.float64:
            cells.append(["" if v != v else repr(v) for v in values])
        elif isinstance(dtype, np.dtype) and dtype.kind in "iu":
            cells.append(list(map(str, values)))
        elif dtype.kind == "O" and all(type(v) is str for v in values) \
                and _plain_texts(set(values)):
            cells.append(values)
        else:
            return frame.to_csv(index=False)
    return _csv_text(names, cells)


def _plain_texts(texts) -> bool:
    """Whether none of ``texts`` is empty or needs CSV quoting (:func:`csv_cell`)."""
    return all(t and csv_cell(t) == t for t in texts)


@dataclass(frozen=True)
class RowTable(Sequence[list[dict[str, Any]]]):
    """Rows of a batch of ``N`` trials as columns: ``trial`` (R,) int, each row's trial
    (``0..N-1``, non-decreasing, every trial present); ``columns`` name -> (R,) values of the row
    keys and metrics (no runner or ``*_time_s`` columns); ``timings`` name -> (T,) values, one per
    timed unit of the batch, may be empty."""

    trial: np.ndarray
    columns: dict[str, np.ndarray]
    timings: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def trials(self) -> int:
        """Number of trials ``N`` in the batch."""
        return int(self.trial[-1]) + 1 if len(self.trial) else 0

    @property
    def rows(self) -> int:
        """Number of rows ``R``."""
        return len(self.trial)

    def check(self, trials: int) -> None:
        """Raise ``TypeError`` unless the table holds ``trials`` trials in order, a value a row."""
        counts = np.bincount(np.asarray(self.trial, dtype=int), minlength=trials) \
            if len(self.trial) and int(np.min(self.trial)) >= 0 else np.zeros(0, dtype=int)
        if len(counts) != trials or not (counts > 0).all() or \
                (np.diff(self.trial) < 0).any():
            raise TypeError(f"run_batch returned a RowTable that does not hold the rows of "
                            f"{trials} trials in order")
        deep = {k: np.shape(v) for k, v in self.columns.items() if np.ndim(v) != 1}
        if deep:
            name, shape = next(iter(deep.items()))
            raise TypeError(f"run_batch returned a RowTable whose column {name!r} has shape "
                            f"{shape}; allowed: one value per row, shape ({len(self.trial)},)")
        bad = [k for k, v in self.columns.items() if len(v) != len(self.trial)]
        if bad:
            raise TypeError(f"run_batch returned a RowTable whose columns {bad} do not have "
                            "one value per row")

    def __len__(self) -> int:
        return self.trials

    def __getitem__(self, i: int) -> list[dict[str, Any]]:  # type: ignore[override]
        if not -self.trials <= i < self.trials:
            raise IndexError(i)
        at = np.flatnonzero(self.trial == i % self.trials)
        values = [np.asarray(v)[at].tolist() for v in self.columns.values()]
        return [dict(zip(self.columns, row, strict=True)) for row in zip(*values, strict=True)]

    def __iter__(self) -> Iterator[list[dict[str, Any]]]:
        return (self[i] for i in range(self.trials))
