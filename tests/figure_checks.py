"""Figure checks for the tests (not the package's: nothing draws with them).

:func:`journal_problems` judges a figure as a journal would print it: its width one of
the slots (3.5 in, 7.16 in), at most 8.5 in tall, every text inside the canvas, none below
7 pt, legends of at most 6 entries, the saved PDF's fonts TrueType, no host-dependent text.

:func:`text_overlaps` finds texts that overlap or run off the figure,
:func:`alike_legend_entries` legend entries a reader cannot tell apart, and
:func:`inside_canvas` whether everything drawn lies inside the saved figure, and
:func:`smallest_printed_text` the smallest text once the figure is printed at page width.
"""

from __future__ import annotations

import io
import re
from unittest import mock

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_hex
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from matplotlib.text import Text

from trackfuse.reportkit.spec import MAX_ENTRIES, SLOTS
from trackfuse.reportkit.style import MAX_HEIGHT_IN, MIN_POINTS, context

OUTSIDE = "<outside the figure>"
"""The partner :func:`text_overlaps` gives a text that runs off the figure."""


def text_overlaps(fig: Figure, tolerance_px: float = 1.0) -> list[tuple[str, str]]:
    """Pairs of text elements drawn in ``fig`` whose boxes overlap, and texts that run off
    the figure (paired with :data:`OUTSIDE`: they would be cut when saved).

    The figure is drawn once while every :class:`~matplotlib.text.Text` that actually
    renders (visible, non-empty, inside its axes' view) is recorded; boxes are in display
    pixels and overlap when they share more than ``tolerance_px`` in both directions; a text
    is outside when it passes an edge of the figure by more than ``tolerance_px``.
    Returns ``[(text_a, text_b), ...]``; empty for a clean figure. A figure made without a
    canvas (:func:`new_figure`) is given an Agg canvas first.
    """
    drawn = _rendered_texts(fig)
    renderer = fig.canvas.get_renderer()
    boxes = [(t.get_text(), t.get_window_extent(renderer)) for t in drawn]
    page = fig.bbox
    found = [(text, OUTSIDE) for text, b in boxes
             if min(b.x0 - page.x0, b.y0 - page.y0, page.x1 - b.x1, page.y1 - b.y1)
             < -tolerance_px]
    for i, (text_a, a) in enumerate(boxes):
        for text_b, b in boxes[i + 1:]:
            dx = min(a.x1, b.x1) - max(a.x0, b.x0)
            dy = min(a.y1, b.y1) - max(a.y0, b.y0)
            if dx > tolerance_px and dy > tolerance_px:
                found.append((text_a, text_b))
    return found


def _look(handle) -> tuple:
    """What a reader sees of a legend handle: a line's colour, dashes, width class, marker
    and marker fill, or a patch's face colour and hatch."""
    if isinstance(handle, Line2D):
        return ("line", to_hex(handle.get_color(), keep_alpha=False), str(handle.get_linestyle()),
                handle.get_linewidth() >= 1.8, handle.get_marker(),
                str(handle.get_markerfacecolor()))
    if isinstance(handle, Patch):
        return ("patch", to_hex(handle.get_facecolor(), keep_alpha=False), handle.get_hatch())
    return ("other", id(handle))


def alike_legend_entries(fig: Figure) -> list[tuple[str, str]]:
    """Pairs of labels in one legend of ``fig`` (figure or axes legends) whose entries look
    the same (:func:`_look`): a reader cannot tell which curve is which."""
    legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes if ax.get_legend())]
    found = []
    for legend in legends:
        seen: dict[tuple, str] = {}
        for handle, text in zip(legend.legend_handles, legend.get_texts(), strict=True):
            look = _look(handle)
            if look in seen:
                found.append((seen[look], text.get_text()))
            seen.setdefault(look, text.get_text())
    return found


def inside_canvas(fig: Figure) -> bool:
    """Whether every drawn artist (titles, legends, labels) lies inside the saved figure
    (to 0.01 inch): a legend or label pushed off the canvas is cut when saved."""
    if not hasattr(fig.canvas, "get_renderer"):
        FigureCanvasAgg(fig)
    box = fig.get_tightbbox(fig.canvas.get_renderer())
    return (box.x0 >= -0.01 and box.y0 >= -0.01 and box.x1 <= fig.get_figwidth() + 0.01
            and box.y1 <= fig.get_figheight() + 0.01)


def _rendered_texts(fig: Figure) -> list[Text]:
    """Every :class:`~matplotlib.text.Text` that renders when ``fig`` is drawn (visible,
    non-empty, inside its axes' view), drawing it once (given an Agg canvas if it has none)."""
    if not hasattr(fig.canvas, "get_renderer"):
        FigureCanvasAgg(fig)
    drawn: list[Text] = []
    original = Text.draw

    def recording(self: Text, renderer) -> None:
        original(self, renderer)
        if self.get_visible() and self.get_text().strip():
            drawn.append(self)

    with mock.patch.object(Text, "draw", recording):  # every Text of this process, briefly
        fig.canvas.draw()
    return drawn


def smallest_printed_text(fig: Figure, width_in: float = SLOTS["double"]) -> tuple[float, str]:
    """``(size in pt, text)`` of the smallest text of ``fig`` once the figure is scaled to
    ``width_in`` inches wide (never enlarged): a 9 pt label of an 11 in figure prints at
    5.9 pt on a 7.16 in page."""
    scale = min(1.0, width_in / fig.get_figwidth())
    return min((t.get_fontsize() * scale, t.get_text()) for t in _rendered_texts(fig))



#: Words that only a host could put in a figure: a CPU model, a core or worker count.
HOST_WORDS = re.compile(r"\b(Intel|AMD|Xeon|EPYC|Ryzen|CPU|cores?|workers?)\b")


def pdf_font_types(pdf: bytes) -> set[str]:
    """The ``/Subtype`` of every font object of a PDF file (``Type3``, ``TrueType``,
    ``Type0``/``CIDFontType2`` for TrueType as Type 42, ``Type1``)."""
    found = (re.findall(rb"/Type\s*/Font\b[^>]*?/Subtype\s*/(\w+)", pdf)
             + re.findall(rb"/Subtype\s*/(\w+)[^>]*?/Type\s*/Font\b", pdf))
    return {name.decode() for name in found}


def saved_pdf(fig: Figure) -> bytes:
    """``fig`` saved as a PDF the way the report saves it (in the journal style)."""
    out = io.BytesIO()
    with context():
        fig.savefig(out, format="pdf")
    return out.getvalue()


def journal_problems(fig: Figure, pdf: bytes | None = None) -> list[str]:
    """What a journal would reject in ``fig`` (empty when nothing): a width other than a
    slot, taller than a page, text off the canvas or overlapping, text below 7 pt at its
    printed size (its own: it is drawn at a slot's width), a legend of more than 6
    entries, a Type 3 font in its PDF (``pdf``: the saved bytes, else saved here), text
    naming the host."""
    problems = []
    width, height = fig.get_size_inches()
    if not any(abs(width - slot) < 0.005 for slot in SLOTS.values()):
        problems.append(f"width {width:.2f} in is not a slot {sorted(SLOTS.values())}")
    if height > MAX_HEIGHT_IN + 0.005:
        problems.append(f"height {height:.2f} in > {MAX_HEIGHT_IN}")
    texts = _rendered_texts(fig)
    problems += [f"text {t.get_text()!r} at {t.get_fontsize():g} pt" for t in texts
                 if t.get_fontsize() < MIN_POINTS - 1e-9]
    problems += [f"text {a!r} {'off the canvas' if b == OUTSIDE else f'over {b!r}'}"
                 for a, b in text_overlaps(fig)]
    if not inside_canvas(fig):
        problems.append("something drawn off the canvas")
    legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes if ax.get_legend())]
    problems += [f"legend of {len(lg.get_texts())} entries" for lg in legends
                 if len(lg.get_texts()) > MAX_ENTRIES]
    problems += [f"host text {t.get_text()!r}" for t in texts if HOST_WORDS.search(t.get_text())]
    types = pdf_font_types(saved_pdf(fig) if pdf is None else pdf)
    if "Type3" in types or not types & {"TrueType", "CIDFontType2"}:
        problems.append(f"PDF font types {sorted(types)}, not TrueType")
    return problems


def internal_names(fig: Figure, experiment) -> list[str]:
    """Texts of ``fig`` that show a reader an internal name: a parameter key
    (``baseline.spread``), an algorithm id (``paper_approx/mgekf``, ``nis_tdoa``) or a
    plain-ASCII unit (``m^2``, ``(1)``)."""
    ids = {*experiment.schema, *experiment.algorithms,
           *(str(c) for p in experiment.params if p.choices and p.kind is str for c in p.choices)}
    words = {i for i in ids if "." in i or "_" in i or "/" in i}
    found = []
    for text in (t.get_text() for t in _rendered_texts(fig)):
        plain = re.sub(r"\$[^$]*\$", "", text)  # mathtext symbols (p_m) are typeset
        if any(re.search(rf"(?<![\w.]){re.escape(w)}(?![\w.])", plain) for w in words) \
                or re.search(r"\^\d|\(1\)", plain):
            found.append(text)
    return found
