"""The house font embedded in PDFs subset once per process, not once per file.

matplotlib embeds each PDF's TrueType font (``pdf.fonttype`` 42) as a subset of exactly the
glyphs that file draws, made anew by fontTools for every file: about 0.05-0.1 CPU-s a PDF,
a tenth of a ``trackfuse reproduce``'s drawing. :func:`prepare` subsets a font once, with
matplotlib's own subsetter and options, to every glyph of :data:`SUPERSET` (Latin, Greek,
the punctuation, super- and subscripts, ligatures and math signs our labels use); a PDF
whose glyphs all lie in it embeds that subset (about 60 KB of font instead of about 13 KB),
any other PDF its own exact subset as before. The text is drawn by the same glyphs either
way, so a PDF renders the same.

It replaces a private matplotlib function (``_backend_pdf_ps.get_glyphs_subset``, called by
the PDF backend for each embedded TrueType font): :func:`install` does so only while that
function still has the signature and result type written for here, and otherwise leaves
matplotlib's own behaviour in place (``docs/outputs.md``, "Figures' fonts").
"""

from __future__ import annotations

import inspect
import io
from collections.abc import Callable, Iterable
from contextlib import AbstractContextManager

from matplotlib.backends import _backend_pdf_ps

#: Characters (code points) whose glyphs the shared subset holds.
SUPERSET: tuple[int, ...] = (
    *range(0x20, 0x7F), *range(0xA0, 0x100),  # ASCII, Latin-1 (°, ±, ×, µ, ·, ²)
    *range(0x391, 0x3CA),  # Greek
    *range(0x2010, 0x2045),  # dashes, quotes, bullets, ellipsis, per mille
    *range(0x2070, 0x209D),  # super- and subscripts
    *range(0x2190, 0x2194),  # arrows
    0x2202, 0x2207, 0x2208, 0x2211, 0x2212, 0x221A, 0x221D, 0x221E, 0x222B,
    0x2248, 0x2260, 0x2264, 0x2265,  # math signs: minus, root, approx, <=, >=
    *range(0xFB00, 0xFB05),  # ligatures ff, fi, fl, ffi, ffl
)

#: ``(font file, face index)`` -> (subset font as bytes, original -> subset glyph index).
_subsets: dict[tuple[str, int], tuple[bytes, dict[int, int]]] = {}
_matplotlib_subset: Callable[..., AbstractContextManager] = _backend_pdf_ps.get_glyphs_subset


def supported() -> bool:
    """Whether matplotlib's subsetter has the signature and result this module replaces."""
    results = getattr(_backend_pdf_ps, "SubsetResults", None)
    try:
        parameters = list(inspect.signature(_matplotlib_subset).parameters)
    except (TypeError, ValueError):
        return False
    return (parameters == ["fontfile", "glyphs"] and results is not None
            and getattr(results, "_fields", ()) == ("font", "glyph_index_map")
            and hasattr(results, "_as_cm") and hasattr(_backend_pdf_ps, "font_as_file"))


def install() -> bool:
    """Route matplotlib's PDF font subsetting through :func:`glyphs_subset` (idempotent);
    ``False`` (matplotlib's own subsetting kept) when :func:`supported` is not."""
    if not supported():
        return False
    _backend_pdf_ps.get_glyphs_subset = glyphs_subset
    return True


def prepare(fontfile: str) -> None:
    """Subset ``fontfile`` (matplotlib's ``FontPath``, a path with its ``face_index``) to
    :data:`SUPERSET`, once per process: done before the drawing processes fork, they all
    share it."""
    if not supported():
        return
    key = (str(fontfile), getattr(fontfile, "face_index", 0))
    if key in _subsets:
        return
    from matplotlib.font_manager import get_font

    charmap = get_font(fontfile).get_charmap()
    glyphs = {charmap[c] for c in SUPERSET if c in charmap}
    with _matplotlib_subset(fontfile, glyphs) as subset:
        data = _backend_pdf_ps.font_as_file(subset.font).getvalue()
        _subsets[key] = (data, dict(subset.glyph_index_map))


def glyphs_subset(fontfile: str, glyphs: Iterable[int]) -> AbstractContextManager:
    """matplotlib's ``get_glyphs_subset``: the prepared subset of ``fontfile`` when it holds
    every one of ``glyphs``, else matplotlib's own exact subset."""
    glyphs = set(glyphs)
    found = _subsets.get((str(fontfile), getattr(fontfile, "face_index", 0)))
    if found is None or not glyphs <= found[1].keys():
        return _matplotlib_subset(fontfile, glyphs)
    from fontTools.ttLib import TTFont

    data, index_map = found
    font = TTFont(io.BytesIO(data), recalcTimestamp=False, recalcBBoxes=False)
    return _backend_pdf_ps.SubsetResults(font, dict(index_map))._as_cm()
