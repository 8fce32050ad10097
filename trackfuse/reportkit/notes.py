"""The notes on each paper (``docs/papers/*.md``, shipped as ``trackfuse.papers``) rendered as
HTML beside a report, so a reason's link such as ``esm_radar.md#table-3`` lands in a browser
and in an installed package. Headings get GitHub's ids; links to files not rendered beside
a note keep their text only."""

from __future__ import annotations

import html
import re
from collections.abc import Collection
from pathlib import Path

from markdown_it import MarkdownIt
from markdown_it.token import Token

import trackfuse
from trackfuse.results import atomic_write

#: Where a report's ``docs`` links point, and the folder they are rendered into.
DOCS_PREFIX = "docs/papers/"
NOTES = "notes"
_CSS = ("body{font-family:sans-serif;max-width:50em;margin:2em auto;padding:0 1em;"
        "line-height:1.5}table{border-collapse:collapse;font-size:90%}"
        "td,th{border:1px solid #ccc;padding:2px 6px;text-align:left}"
        "pre{background:#f6f6f6;padding:.5em;overflow-x:auto}code{background:#f6f6f6}")


def notes_folder() -> Path | None:
    """The notes: ``trackfuse/papers`` installed, else a checkout's ``docs/papers``, else None."""
    package = Path(trackfuse.__file__).resolve().parent
    for folder in (package / "papers", package.parent / "docs" / "papers"):
        if folder.is_dir() and any(folder.glob("*.md")):
            return folder
    return None


def slug(text: str) -> str:
    """GitHub's id of a heading (``"W001-2 radar TDOA"`` -> ``"w001-2-radar-tdoa"``)."""
    return re.sub(r"[^\w\- ]", "", text.strip().lower()).replace(" ", "-")


def _heading_ids(tokens: list[Token]) -> None:
    """Give each heading its :func:`slug` as id, ``-1``, ``-2`` ... after a repeat."""
    seen: dict[str, int] = {}
    for opening, inline in zip(tokens, tokens[1:], strict=False):
        if opening.type != "heading_open":
            continue
        text = "".join(c.content for c in inline.children or [] if c.type in ("text",
                                                                                "code_inline"))
        base = slug(text)
        count = seen.get(base, 0)
        seen[base] = count + 1
        opening.attrSet("id", base if count == 0 else f"{base}-{count}")


def _local_links(tokens: list[Token], rendered: set[str]) -> None:
    """Point links to rendered notes at their pages; unlink those to files not rendered."""
    for token in (t for t in tokens for t in [t, *(t.children or [])]):
        if token.type != "link_open":
            continue
        href = str(token.attrGet("href") or "")
        page, _, anchor = href.partition("#")
        if not page or "://" in page or href.startswith("mailto:"):
            continue
        if Path(page).name in rendered and Path(page).suffix == ".md":
            token.attrSet("href", f"{Path(page).stem}.html" + (f"#{anchor}" if anchor else ""))
        else:
            token.tag = "span"
            token.attrs = {}
            token.type = "span_open"


def render_note(text: str, title: str, rendered: set[str], back: str) -> str:
    """One note (Markdown ``text``) as an HTML page linking to the other ``rendered`` notes."""
    md = MarkdownIt("commonmark").enable("table")
    tokens = md.parse(text)
    _heading_ids(tokens)
    _local_links(tokens, rendered)
    body = md.renderer.render(tokens, md.options, {})
    return (f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>"
            f"{html.escape(title)}</title><style>{_CSS}</style></head><body>"
            f"<p><a href='{html.escape(back)}'>Back to the report</a></p>{body}</body></html>\n")


def write_notes(out: Path, back: str, only: Collection[str] | None = None) -> dict[str, str]:
    """Render every note, or ``only`` those named, into ``out/notes/`` with links ``back`` to the
    report; returns ``{"docs/papers/<name>.md": "notes/<name>.html"}``."""
    folder = notes_folder()
    wanted = None if only is None else {str(d).partition("#")[0] for d in only}
    sources = [p for p in sorted(folder.glob("*.md")) if wanted is None
               or f"{DOCS_PREFIX}{p.name}" in wanted] if folder is not None else []
    if not sources:
        return {}
    (out / NOTES).mkdir(parents=True, exist_ok=True)
    rendered = {p.name for p in sources}
    written = {}
    for source in sources:
        text = source.read_text(encoding="utf-8")
        title = next((line.lstrip("# ") for line in text.splitlines() if line.startswith("#")),
                     source.stem)
        atomic_write(out / NOTES / f"{source.stem}.html",
                     render_note(text, title, rendered, back))
        written[f"{DOCS_PREFIX}{source.name}"] = f"{NOTES}/{source.stem}.html"
    return written


def note_href(docs: str, written: dict[str, str]) -> str:
    """The link of a ``docs/papers/<name>.md#<anchor>`` entry to its rendered note, or ``""``."""
    page, _, anchor = str(docs).partition("#")
    target = written.get(page)
    return "" if target is None else target + (f"#{anchor}" if anchor else "")
