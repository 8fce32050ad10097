"""Sweep axes: value parsing, ``--set``/``--sweep`` overrides, and expansion into points (grid,
last axis fastest, or ``sweep_mode: zip``); syntax in ``docs/configs.md``."""

from __future__ import annotations

import itertools
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from decimal import Decimal
from typing import Any

from trackfuse.safe_yaml import YamlInputError, load_yaml

_RANGE = re.compile(r"^\s*range\s*\((.*)\)\s*$")
#: A decimal number, exponent allowed (``1e-3``, ``-2.5E+4``, ``.5``): no nan or inf words.
_DECIMAL = re.compile(r"^[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")
MAX_POINTS = 1_000_000


class SweepError(ValueError):
    """A malformed axis or override; the message says what is allowed."""


@dataclass(frozen=True)
class SweepPoint:
    """One point of the sweep: its index and the swept values (dotted key -> value)."""

    index: int
    values: dict[str, Any]


def _number(text: str) -> float | int:
    value = load_yaml(text)
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        value = float(text)
    return value


def parse_range(text: str) -> list[float | int]:
    """Expand ``"range(a, b, s)"``: integers as Python's ``range``, floats as the decimals
    ``a + i * s`` computed in decimal, each the float nearest to it."""
    match = _RANGE.match(text)
    if not match:
        raise SweepError(f"got {text!r}; allowed: a list or 'range(start, stop, step)'")
    try:
        parts = [_number(p.strip()) for p in match.group(1).split(",")]
    except ValueError:  # YamlInputError included
        raise SweepError(f"got {text!r}; range() takes numbers") from None
    if not 1 <= len(parts) <= 3 or any(not math.isfinite(p) for p in parts):
        raise SweepError(f"got {text!r}; allowed: range(stop), range(start, stop[, step])")
    start, stop, step = ([0] + parts + [1])[-3:] if len(parts) == 1 else (parts + [1])[:3]
    if step == 0:
        raise SweepError(f"got {text!r}; the step must not be 0")
    count = _range_length(start, stop, step)
    if count is None or count > MAX_POINTS:
        raise SweepError(f"got {text!r}; more than {MAX_POINTS} values")
    if count == 0:
        raise SweepError(f"got {text!r}; the range is empty")
    if all(isinstance(p, int) for p in (start, stop, step)):
        return list(range(start, stop, step))
    first, by = _decimal(start), _decimal(step)
    return [float(first + i * by) for i in range(count)]


def _decimal(number: float | int) -> Decimal:
    """``number`` as the decimal it is written as (a float by its shortest ``repr``)."""
    return Decimal(repr(number)) if isinstance(number, float) else Decimal(number)


def _range_length(start: float, stop: float, step: float) -> int | None:
    """Number of values of the range, computed without building it (``None`` if infinite)."""
    if all(isinstance(p, int) for p in (start, stop, step)):
        return max(0, -((start - stop) // step))  # exact for any size of int
    span = (float(stop) - float(start)) / float(step)
    if not math.isfinite(span):
        return None
    return max(0, math.ceil(span - 1e-9))


def parse_axis_values(spec: Any) -> list[Any]:
    """Values of one axis from a config entry (a list or a range string)."""
    if isinstance(spec, str):
        if _RANGE.match(spec):
            return parse_range(spec)
        spec = [parse_scalar(s) for s in split_values(spec)] if "," in spec else [spec]
    if not isinstance(spec, list):
        spec = [spec]
    if not spec:
        raise SweepError("the axis is empty; allowed: a non-empty list or 'range(a, b, s)'")
    return spec


def split_values(text: str) -> list[str]:
    """Split ``text`` at the commas outside brackets, braces, parentheses and quotes:
    ``"[a,b],[c]"`` -> ``["[a,b]", "[c]"]``; raise :class:`SweepError` if they do not balance."""
    parts, depth, quote, start = [], 0, "", 0
    for i, char in enumerate(text):
        if quote:
            quote = "" if char == quote else quote
        elif char in "'\"":
            quote = char
        elif char in "([{":
            depth += 1
        elif char in ")]}":
            depth -= 1
            if depth < 0:
                break
        elif char == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    if depth or quote:
        raise SweepError(f"got {text!r}; unbalanced brackets or quotes")
    return parts + [text[start:]]


def parse_scalar(text: str) -> Any:
    """Parse an override value as a config file's YAML scalar or flow list, except that ``1e-3``
    becomes a float; a quoted value stays a string."""
    text = text.strip()
    try:
        value = load_yaml(text) if text else ""
    except YamlInputError:
        return text
    if isinstance(value, str) and value == text and _DECIMAL.match(text):
        return float(text)
    return value


def parse_override(text: str) -> tuple[str, str]:
    """Split ``"key=value"``; raise :class:`SweepError` if there is no ``=`` or no key."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise SweepError(f"got {text!r}; allowed: key=value")
    return key.strip(), value


def parse_sets(items: list[str]) -> dict[str, Any]:
    """``--set`` items to ``{key: value}``; a key given twice is refused."""
    sets: dict[str, Any] = {}
    for key, value in map(parse_override, items):
        if key in sets:
            raise SweepError(f"{key}: given twice; allowed: one value per key")
        sets[key] = parse_scalar(value)
    return sets


def parse_sweeps(items: list[str]) -> dict[str, Any]:
    """``--sweep`` items to ``{key: [values]}`` (comma lists or ``range(...)``)."""
    axes: dict[str, Any] = {}
    for item in items:
        key, value = parse_override(item)
        if key in axes:
            raise SweepError(f"{key}: given twice; allowed: one axis per key")
        value = value.strip()
        if not value:
            raise SweepError(f"got {item!r}; the axis is empty")
        axes[key] = value if _RANGE.match(value) else [parse_scalar(v)
                                                        for v in split_values(value)]
    return axes


def count_points(sweep: Mapping[str, list[Any]], mode: str = "grid") -> int:
    """Number of sweep points without building them."""
    if not sweep:
        return 1
    lengths = [len(v) for v in sweep.values()]
    return lengths[0] if mode == "zip" else math.prod(lengths)


def expand(sweep: Mapping[str, list[Any]], mode: str = "grid") -> list[SweepPoint]:
    """All sweep points, indexed from 0; one empty point when there are no axes."""
    if not sweep:
        return [SweepPoint(0, {})]
    keys = list(sweep)
    if mode == "zip":
        combos = zip(*(sweep[k] for k in keys), strict=True)
    else:
        total = count_points(sweep, mode)
        if total > MAX_POINTS:
            raise SweepError(f"the grid has {total} points; at most {MAX_POINTS}")
        combos = itertools.product(*(sweep[k] for k in keys))
    return [SweepPoint(i, dict(zip(keys, c, strict=True))) for i, c in enumerate(combos)]
