"""Units and labels as print shows them (``m²/s⁴``, ``√q T²/(rσ)``) from the declarations' ASCII
(``"m^2/s^4"``, ``"1"`` for dimensionless). Pure string work: no matplotlib."""

from __future__ import annotations

import re

SUPERSCRIPTS = str.maketrans("0123456789-", "⁰¹²³⁴⁵⁶⁷⁸⁹⁻")
#: Plain-ASCII unit spellings and their printed form, applied before the exponents.
WORDS = {"sqrt": "√", "sigma": "σ", "deg": "°"}


def unit_text(unit: str) -> str:
    """The printed form of a declared unit (``"m^2/s^4"`` -> ``"m²/s⁴"``, ``"1"`` -> nothing)."""
    if unit in ("", "1"):
        return ""
    text = re.sub(r"\^(-?\d+)", lambda m: m.group(1).translate(SUPERSCRIPTS), unit)
    for word, symbol in WORDS.items():
        text = re.sub(rf"\b{word}\b\s*", symbol, text)
    return text


def axis_label(label: str, unit: str, percent: bool = False, scale: str = "") -> str:
    """``label (unit)`` for an axis, ``%`` for ``percent``, a non-linear ``scale`` named too."""
    shown = "%" if percent else unit_text(unit)
    inside = ", ".join(part for part in (shown, f"{scale} scale" if scale else "") if part)
    return f"{label} ({inside})" if inside else label


def number(value: float) -> str:
    """A tick or title number: ``g`` format, a minus sign rather than a hyphen."""
    return f"{value:g}".replace("-", "−")


#: Mathtext commands of declared symbols and their plain-text letters.
MATH_LETTERS = {r"\sigma": "σ", r"\lambda": "λ", r"\alpha": "α"}


def plain(text: str) -> str:
    """``text`` with its mathtext unwrapped for a table cell (``$P_D$`` -> ``P_D``)."""
    for command, letter in MATH_LETTERS.items():
        text = text.replace(command, letter)
    return re.sub(r"[${}\\]", "", text)
