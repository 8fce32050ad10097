"""How each algorithm is drawn: one colour, marker, fill and emphasis (:data:`ROLES`) per method
in every figure (``docs/plugins.md``, roles and palette). Pure data: no matplotlib."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

VERMILLION, BLUE, GREEN, PURPLE = "#D55E00", "#0072B2", "#009E73", "#CC79A7"
ORANGE, SKY, BLACK, WINE = "#E69F00", "#56B4E9", "#000000", "#882255"
GREYS = ("#555555", "#888888", "#AAAAAA")
#: Every role a :class:`Look` may have (see the module docstring).
ROLES = ("paper", "paper_baseline", "ours", "reference", "variant")
EMPHASISED = ("paper", "paper_baseline", "ours")


@dataclass(frozen=True)
class Look:
    """How one algorithm is drawn: ``label`` (short legend entry), ``marker`` (matplotlib, ``""``
    for none), ``open`` (hollow marker), ``role`` (one of :data:`ROLES`)."""

    label: str
    colour: str
    marker: str
    role: str = "variant"
    open: bool = False
    dashed: bool = False

    def __post_init__(self) -> None:
        if self.role not in ROLES:
            raise ValueError(f"{self.label!r}: role {self.role!r} is not one of {ROLES}")

    @property
    def emphasised(self) -> bool:
        """Paper, paper-baseline and our methods get thick lines and interval bands."""
        return self.role in EMPHASISED

    def line(self) -> dict:
        """Matplotlib keyword arguments of a curve in this look."""
        face = "white" if self.open else self.colour
        return {"color": self.colour, "marker": self.marker or None, "label": self.label,
                "markerfacecolor": face, "markeredgecolor": self.colour,
                "linewidth": 1.6 if self.emphasised else 0.9,
                "zorder": 3 if self.emphasised else 2,
                "linestyle": "--" if self.role == "reference" or self.dashed else "-"}


def look_of(looks: Mapping[str, Look], name: str) -> Look:
    """The look of ``name``, else its association's, else a grey dot labelled ``name``."""
    if name in looks:
        return looks[name]
    base, _, variant = name.partition("/")
    found = looks.get(base, Look(base, GREYS[1], "."))
    if variant:
        return Look(f"{found.label}, {variant.upper()}", found.colour, found.marker,
                    found.role, found.open, found.dashed)
    return found
