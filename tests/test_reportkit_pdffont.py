"""The house font is subset once per process for every PDF (trackfuse.reportkit.pdffont),
and each PDF still embeds a TrueType (CIDFontType2) font holding every glyph it draws."""

from __future__ import annotations

import io
import re
import zlib
from pathlib import Path

from fontTools.ttLib import TTFont
from matplotlib.backends import _backend_pdf_ps
from matplotlib.font_manager import FontProperties, findfont, get_font

from trackfuse import reports
from trackfuse.reportkit import pdffont, style

#: Labels of the kinds our figures draw (no "fi"/"fl": ligatures take other character codes).
LABEL = "Range error (m) ± 0.5 %, P_D = 0.95, σ² −2 ≤ 3 km, n₁"


def _objects(pdf: bytes) -> dict[int, bytes]:
    """Each object of ``pdf`` (its number -> its bytes between ``obj`` and ``endobj``)."""
    found = re.finditer(rb"(\d+) 0 obj\n(.*?)\nendobj", pdf, re.S)
    return {int(m.group(1)): m.group(2) for m in found}


def _stream(obj: bytes) -> bytes:
    start, end = obj.index(b"stream\n") + len(b"stream\n"), obj.rindex(b"endstream")
    return zlib.decompressobj().decompress(obj[start:end])


def _ref(obj: bytes, key: bytes) -> int:
    return int(re.search(rb"/" + key + rb" (\d+) 0 R", obj).group(1))


def embedded_glyphs(pdf: bytes) -> list[dict[int, str]]:
    """Per embedded TrueType font: character code -> name of the glyph the font draws it with
    (through the CIDToGIDMap into the embedded font file)."""
    objects, fonts = _objects(pdf), []
    for obj in objects.values():
        if b"/Subtype /CIDFontType2" not in obj:
            continue
        font = TTFont(io.BytesIO(_stream(objects[_ref(objects[_ref(obj, b"FontDescriptor")],
                                                      b"FontFile2")])))
        gids = _stream(objects[_ref(obj, b"CIDToGIDMap")])
        order = font.getGlyphOrder()
        fonts.append({cid: order[int.from_bytes(gids[2 * cid:2 * cid + 2], "big")]
                      for cid in range(len(gids) // 2) if gids[2 * cid:2 * cid + 2] != b"\0\0"})
    return fonts


def _pdf(text: str, tmp_path: Path) -> bytes:
    fig, axes = style.panels(1, 1, "single")
    with style.context():
        axes[0, 0].plot([0, 1], [0, 1], label=text)
        axes[0, 0].set_xlabel(text)
        reports.save_figure(fig, tmp_path, "f", ["pdf"])
    return (tmp_path / "f.pdf").read_bytes()


def _house_glyph_names(text: str) -> dict[int, str]:
    path = findfont(FontProperties(family=style.RC["font.family"]))
    charmap, names = get_font(path).get_charmap(), TTFont(path).getGlyphOrder()
    return {ord(c): names[charmap[ord(c)]] for c in set(text)}


def _count_matplotlib_subsets(monkeypatch) -> list[int]:
    """Count the calls of matplotlib's own subsetter from here on."""
    calls: list[int] = []
    own = pdffont._matplotlib_subset

    def counted(fontfile, glyphs):
        calls.append(1)
        return own(fontfile, glyphs)

    monkeypatch.setattr(pdffont, "_matplotlib_subset", counted)
    return calls


def test_pdf_takes_the_shared_subset_and_embeds_every_glyph_drawn(tmp_path, monkeypatch):
    style.shared_pdf_font()
    calls = _count_matplotlib_subsets(monkeypatch)
    pdf = _pdf(LABEL, tmp_path)
    assert not calls  # the shared subset, not a new one
    (embedded,) = embedded_glyphs(pdf)
    for code, name in _house_glyph_names(LABEL).items():
        assert embedded.get(code) == name, chr(code)


def test_glyph_outside_the_superset_gets_matplotlibs_exact_subset(tmp_path, monkeypatch):
    style.shared_pdf_font()
    text = "Дальность ⌘"  # Cyrillic and a sign the shared subset lacks
    calls = _count_matplotlib_subsets(monkeypatch)
    pdf = _pdf(text, tmp_path)
    assert calls  # matplotlib's own exact subset
    (embedded,) = embedded_glyphs(pdf)
    for code, name in _house_glyph_names(text).items():
        assert embedded.get(code) == name, chr(code)


def test_a_changed_matplotlib_subsetter_is_left_alone(monkeypatch):
    def changed(fontfile, glyphs, options):  # a new signature
        raise AssertionError("not to be called")

    monkeypatch.setattr(pdffont, "_matplotlib_subset", changed)
    monkeypatch.setattr(_backend_pdf_ps, "get_glyphs_subset", changed)
    assert not pdffont.supported()
    assert not pdffont.install()
    assert _backend_pdf_ps.get_glyphs_subset is changed

