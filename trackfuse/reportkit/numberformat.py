"""One number format for every table and figure: three significant figures, rates in %
(``74.0 % (71.7–79.2)``), rate differences in signed percentage points
(``+1.60 points (−3.90 to +7.00)``)."""

from __future__ import annotations

import math

MINUS = "\u2212"


def sig3(value: float, signed: bool = False) -> str:
    """``value`` with three significant figures and no exponent (``0.0594``, ``1230``), a true
    minus sign, ``+`` when ``signed``; ``""`` for NaN."""
    if not math.isfinite(value):
        return "" if math.isnan(value) else ("∞" if value > 0 else f"{MINUS}∞")
    if value == 0:
        return "0"
    digits = 2 - math.floor(math.log10(abs(value)))
    rounded = round(value, digits)
    if rounded and math.floor(math.log10(abs(rounded))) > 2 - digits:  # 99.96 -> 100
        digits -= 1
        rounded = round(value, digits)
    text = f"{abs(rounded):.{max(digits, 0)}f}"
    sign = MINUS if rounded < 0 else "+" if signed else ""
    return sign + text


def scaled(value: float, unit: str) -> float:
    """``value`` in its shown unit: fractions and their differences times 100, else as it is."""
    return 100 * value if unit in ("fraction", "fraction difference") else value


def shown_unit(unit: str) -> str:
    """The unit after a shown value: ``%``, ``points``, nothing for ``1``, else the unit."""
    if unit in ("fraction", "%"):
        return "%"
    if unit in ("points", "fraction difference"):
        return "points"
    return "" if unit in ("1", "", "runs") else unit


def interval_text(low: float, high: float, signed: bool = False) -> str:
    """A 95 % interval to 3 significant figures: ``71.7–79.2``, ``−3.90 to +7.00``; NaN: ``""``."""
    if pd_isna(low) or pd_isna(high):
        return ""
    if low >= 0 and high >= 0 and not signed:
        return f"{sig3(low)}\u2013{sig3(high)}"
    return f"{sig3(low, signed)} to {sig3(high, signed)}"


def pd_isna(value: object) -> bool:
    """Whether ``value`` is missing (None, NaN or pandas' NA)."""
    try:
        return value is None or math.isnan(float(value))  # type: ignore[arg-type]
    except (TypeError, ValueError):
        return True


def with_interval(value: float, low: float, high: float, unit: str) -> str:
    """``value`` and its 95 % interval in the house format (interval left out when NaN)."""
    if not math.isfinite(value):
        return ""
    signed = shown_unit(unit) == "points"
    words = shown_unit(unit)
    text = sig3(scaled(value, unit), signed) + (f" {words}" if words else "")
    if math.isnan(low) or math.isnan(high):
        return text
    return f"{text} ({interval_text(scaled(low, unit), scaled(high, unit), signed)})"
