"""The report of ``trackfuse reproduce``: per paper, what was reproduced and what was not.

Reads finished run folders (``tables/paper_vs_reproduced.csv``, figures, config) and writes
:data:`REPORT_MD` and :data:`REPORT_HTML` with the ``docs/papers/`` notes beside them: the
bottom line, then per paper every compared row, each main figure beside the paper's, and
links to every run (``docs/outputs.md``).
"""

from __future__ import annotations

import html
import importlib
import os
import re
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

from trackfuse.reported import PAPERS, Paper
from trackfuse.reportkit.headline import READER_HEADERS, method, ours, reader_cells
from trackfuse.reportkit.headline import text as _text
from trackfuse.reportkit.htmltable import TABLE_CSS, html_table
from trackfuse.reportkit.notes import note_href, write_notes
from trackfuse.reportkit.verdicts import Line, bottom_line
from trackfuse.reports import HEADLINE_COLUMNS, HEADLINE_TABLE, save_figure, wanted_figures
from trackfuse.results import INDEX_HTML, atomic_write
from trackfuse.rundata import RunData, load

#: Headline columns a report module may leave out: without them a row is listed with its
#: config but answers no paper item of the bottom line.
OPTIONAL_COLUMNS = ("claim", "setting")
REPORT_MD = "REPORT.md"
REPORT_HTML = "report.html"


@dataclass(frozen=True)
class MainFigure:
    """A run's figure that stands for a paper figure or table: PNG path, caption, paper item."""

    png: Path
    caption: str
    paper_item: str
    config: str


@dataclass
class PaperSection:
    """One paper's part of the report: ``rows`` (headline rows with a ``config`` column),
    ``figures`` beside the paper's claims, ``linked`` other main figures, ``runs`` folders.
    """

    paper: Paper
    claims: dict[str, str]
    rows: pd.DataFrame
    figures: list[MainFigure] = field(default_factory=list)
    linked: list[MainFigure] = field(default_factory=list)
    runs: dict[str, Path] = field(default_factory=dict)
    problems: list[str] = field(default_factory=list)

    @property
    def key(self) -> str:
        return self.paper.key

    @property
    def title(self) -> str:
        """The paper's title in words (from its citation)."""
        found = re.search(r'"([^"]+)"', self.paper.citation)
        return found.group(1) if found else self.paper.key

    def lines(self) -> list[Line]:
        """The bottom line: one verdict per paper item that declares its answer."""
        return bottom_line(self.paper.results, self.rows, self.runs)


def _headline(run: RunData) -> pd.DataFrame:
    """The run's headline rows with a ``config`` column (empty frame if it has none)."""
    path = run.path / "tables" / f"{HEADLINE_TABLE}.csv"
    if not path.exists():
        return pd.DataFrame(columns=["config", *HEADLINE_COLUMNS])
    rows = pd.read_csv(path, keep_default_na=False, na_values=[""])
    for optional in OPTIONAL_COLUMNS:  # a plugin's table need not name the item it judges
        if optional not in rows.columns:
            rows[optional] = ""
    missing = [c for c in HEADLINE_COLUMNS if c not in rows.columns]
    if missing:
        raise ValueError(f"{path}: headline table lacks columns {missing}")
    rows = rows[list(HEADLINE_COLUMNS)].copy()
    rows.insert(0, "config", _config_name(run))
    return rows


def _config_name(run: RunData) -> str:
    source = run.manifest.config_file or run.path.parent.name
    return Path(source).stem


def main_figure_names(wanted: Sequence[str], drawn: Collection[str],
                      paper_items: Mapping[str, str], own: bool) -> list[str]:
    """Drawn figures that stand for a run: for the paper's own configs each one naming a paper
    item, in ``wanted`` order; for any other config its first drawn ``wanted`` figure.
    """
    present = [name for name in wanted if name in drawn]
    if own:
        return [name for name in present if paper_items.get(name)]
    return present[:1]


def _main_figures(run: RunData, own: bool) -> list[MainFigure]:
    specs = run.experiment.figures
    folder = run.path / "figures"
    drawn = {name for name in specs if (folder / f"{name}.png").exists()}
    names = main_figure_names(wanted_figures(run), drawn,
                              {n: s.paper for n, s in specs.items()}, own)
    return [MainFigure(folder / f"{name}.png", specs[name].caption, specs[name].paper,
                       _config_name(run)) for name in names]


def _claims(paper: Paper) -> dict[str, str]:
    """The paper's words per item (``"Table 3"``), its non-empty claims joined by "; "."""
    claims: dict[str, list[str]] = {}
    for result in paper.results:
        found = claims.setdefault(result.where, [])
        if result.claim and result.claim not in found:
            found.append(result.claim)
    return {where: "; ".join(found) for where, found in claims.items()}


def collect(folders: Sequence[Path],
            papers: Mapping[str, Paper] = PAPERS) -> list[PaperSection]:
    """One :class:`PaperSection` per paper among the complete runs in ``folders``, in ``papers``
    order; other experiments are skipped and every config's headline rows kept.
    """
    sections: dict[str, PaperSection] = {}
    own_figures: dict[str, list[MainFigure]] = {}
    for folder in folders:
        run = load(folder)
        key = str(run.config["experiment"])
        paper = papers.get(key)
        if paper is None:
            continue
        section = sections.setdefault(key, PaperSection(
            paper, _claims(paper), pd.DataFrame(columns=["config", *HEADLINE_COLUMNS])))
        name = _config_name(run)
        section.runs[name] = run.path
        try:
            rows = _headline(run)
        except ValueError as err:
            section.problems.append(str(err))
            rows = pd.DataFrame()
        if len(rows):
            section.rows = rows if section.rows.empty else pd.concat(
                [section.rows, rows], ignore_index=True)
        own = name in paper.configs or not paper.configs
        figures = _main_figures(run, own)
        (own_figures.setdefault(key, []) if own else section.linked).extend(figures)
    for key, section in sections.items():
        section.rows = _merge_repeats(section.rows)
        shown, more = one_per_item(own_figures.get(key, []), section.paper)
        section.figures, section.linked = shown, more + section.linked
        if not section.figures:
            section.figures, section.linked = section.linked, []
    return [sections[k] for k in papers if k in sections]


def one_per_item(figures: Sequence[MainFigure], paper: Paper
                 ) -> tuple[list[MainFigure], list[MainFigure]]:
    """``(shown, linked)``: each paper item's figure once, from the config declared to
    answer one of its items when that config drew it (else the first), the others linked."""
    answering = {(r.where, r.answer.config) for r in paper.results if r.answer}
    def answers(f: MainFigure) -> bool:
        return any((item, f.config) in answering for item in paper_item_names(f.paper_item))
    ranked = sorted(figures, key=lambda f: not answers(f))  # stable: answering ones first
    shown: dict[str, MainFigure] = {}
    for f in ranked:
        shown.setdefault(f.paper_item, f)
    kept = [f for f in figures if shown.get(f.paper_item) is f]
    return kept, [f for f in figures if shown.get(f.paper_item) is not f]


def _merge_repeats(rows: pd.DataFrame) -> pd.DataFrame:
    """One row per distinct comparison: a row that several configs give identically (the
    AHP table, say) is kept once with its configs joined by ", "."""
    if rows.empty:
        return rows
    same = [c for c in HEADLINE_COLUMNS if c not in ("trials", "docs")]
    keys = rows[same].map(_text).agg("|".join, axis=1)
    configs = rows.groupby(keys, sort=False)["config"].agg(", ".join)
    kept = rows.loc[~keys.duplicated()].copy()
    kept["config"] = configs.loc[keys[~keys.duplicated()]].to_numpy()
    return kept.reset_index(drop=True)


_ITEM = re.compile(r"(Figs?|Tables?)\.?\s*(\d+)(?:\s*-\s*(\d+))?$")


def paper_item_names(paper_items: str) -> list[str]:
    """The single items named in ``paper_items``: ``"Table 3, Figs. 3-4"`` -> ``["Table 3",
    "Fig. 3", "Fig. 4"]``; a part that is no figure or table (``"Abstract"``) kept as is."""
    names = []
    for part in (p.strip() for p in paper_items.split(",")):
        match = _ITEM.match(part)
        if not match:
            names.append(part)
            continue
        kind = "Fig. " if match[1].startswith("Fig") else "Table "
        first = int(match[2])
        names += [f"{kind}{n}" for n in range(first, int(match[3] or first) + 1)]
    return names


def paper_claims(section: PaperSection, paper_items: str) -> str:
    """What the paper states for the items named in ``paper_items`` ("Table 3, Figs. 3-4")."""
    found = [f"{where}: {section.claims[where]}" for where in paper_item_names(paper_items)
             if section.claims.get(where)]
    return " ".join(found) or f"{paper_items} (the paper gives no number for it)"



#: What each verdict word means, in one line each (the page's key).
VERDICT_WORDS = (
    ("agrees", "our result is consistent with the paper's number (its sample and ours), or "
               "shows its claim"),
    ("differs", "the paper's number lies outside what both samples allow, or the data exclude "
                "the smallest effect that counts as the claim (declared before the run)"),
    ("inconclusive", "the runs can neither show nor exclude the claim"),
    ("not comparable", "the run cannot answer it, or the paper gives no number"),
)


def answered_by(line: Line) -> str:
    """The config (and method, setting) declared to answer the line's item, in words."""
    answer = line.item.answer
    assert answer is not None
    parts = [answer.config, method(answer.algorithm)]
    parts += [f"{k} = {v}" for k, v in answer.setting.items()]
    return ", ".join(p for p in parts if p)


def _deciding(line: Line) -> pd.Series | None:
    """The answering row whose verdict is the line's (the first), or ``None``."""
    rows = line.answering[line.answering["verdict"] == line.verdict]
    return rows.iloc[0] if len(rows) else None


def _supporting_rows(line: Line) -> list[list[str]]:
    """The other configs' (and settings') rows for the line's item: config, method,
    quantity, ours, verdict."""
    return [[_text(r["config"]), method(r["algorithm"]), _text(r["quantity"]), ours(r),
             _text(r["verdict"])] for _, r in line.supporting.iterrows()]


SUPPORT_HEADERS = ["config", "method", "what we measured", "ours (95 % interval)", "verdict"]
ROW_HEADERS = ["config", *READER_HEADERS]


def _row_cells(row: pd.Series) -> list[str]:
    return [_text(row["config"]), *reader_cells(row)]


def report_markdown(sections: Sequence[PaperSection], out: Path,
                    notes: Mapping[str, str] | None = None) -> str:
    """The whole report as Markdown; image, run and note links relative to ``out``."""
    notes = notes or {}
    lines = ["# Paper reported against reproduced", "", "## Bottom line", "",
             "One verdict per paper item, from the config declared to answer it; "
             + "; ".join(f"**{w}**: {m}" for w, m in VERDICT_WORDS) + ".", "",
             "| paper | item | the paper says | verdict | answered by | why |",
             "|---|---|---|---|---|---|"]
    for s in sections:
        for line in s.lines():
            lines.append(_md_row([s.title, line.item.where, line.item.claim,
                                  f"**{line.verdict}**", answered_by(line),
                                  line.reason + _md_note(line, notes)]))
    lines += [""]
    for s in sections:
        lines += [f"## {s.title}", "", f"*{s.paper.citation}*", ""]
        for line in (x for x in s.lines() if len(x.supporting)):
            lines += [f"Other verdicts on {line.item.where}, {line.item.claim}:", ""]
            lines += [f"- {r[0]}, {r[1] or 'no method'}: {r[2]}: {r[3]} **{r[4]}**"
                      for r in _supporting_rows(line)] + [""]
        lines += [f"- problem: {p}" for p in s.problems] + ([""] if s.problems else [])
        for f in s.figures:
            rel = os.path.relpath(f.png, out)
            lines += [f"### {f.paper_item} ({f.config})", "",
                      f"Paper: {paper_claims(s, f.paper_item)}", "",
                      f"![{f.paper_item}, {f.config}]({rel})", "", f"Ours: {f.caption}", ""]
        if s.linked:
            lines += ["Main figures of the other configs: " + ", ".join(
                f"[{f.config}: {f.png.stem}]({os.path.relpath(f.png, out)})"
                for f in s.linked), ""]
    lines += ["## Runs", ""] + [
        f"- [{name}]({os.path.relpath(folder / INDEX_HTML, out)})"
        for s in sections for name, folder in s.runs.items()]
    return "\n".join(lines) + "\n"


def _md_row(cells: Sequence[str]) -> str:
    return "| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |"


def _md_note(line: Line, notes: Mapping[str, str]) -> str:
    row = _deciding(line)
    href = note_href(_text(row["docs"]), notes) if row is not None else ""
    return f" ([more]({href}))" if href else ""


_CSS = ("body{font-family:sans-serif;max-width:80em;margin:2em auto;padding:0 1em;"
        "line-height:1.4}" + TABLE_CSS +
        ".agrees td.v{background:#e6f4ea}.differs td.v{background:#fce8e6}"
        ".inconclusive td.v{background:#fef7e0}"
        ".pair{display:grid;grid-template-columns:1fr 2fr;gap:1em;margin:1.5em 0;"
        "border-top:1px solid #ddd;padding-top:1em}img{max-width:100%}"
        "section{margin-bottom:3em}details table{font-size:85%}td.why{min-width:24em}"
        "th.paper{text-align:left;background:#e8eef7}")
#: The bottom line's columns; the one of :data:`BOTTOM_NUMBER` holds numbers.
BOTTOM_HEADERS = ("item", "the paper says", "verdict", "ours (95 % interval)", "answered by",
                  "why")
BOTTOM_NUMBER = 3


def _bottom_row(line: Line, notes: Mapping[str, str]) -> str:
    """One row of the bottom line; the other verdicts on its item folded in its reason."""
    esc = html.escape
    row = _deciding(line)
    href = note_href(_text(row["docs"]), notes) if row is not None else ""
    why = esc(line.reason) + (f" (<a href='{esc(href)}'>more</a>)" if href else "")
    if len(line.supporting):
        more = len(line.supporting)
        why += (f"<details><summary>{more} more verdict{'s' if more > 1 else ''} from other "
                "configs, methods or settings</summary>"
                + html_table(SUPPORT_HEADERS, _supporting_rows(line)) + "</details>")
    cells = [line.item.where, line.item.claim, line.verdict,
             ours(row) if row is not None else "", answered_by(line)]
    classes = ["", "", "v", "num", ""]
    tds = "".join(f"<td class='{c}'>{esc(text)}</td>" for c, text in zip(classes, cells,
                                                                          strict=True))
    return (f"<tr class='{esc(line.verdict.replace(' ', '-'))}'>{tds}"
            f"<td class='why'>{why}</td></tr>")


def _bottom_line_html(sections: Sequence[PaperSection], notes: Mapping[str, str]) -> str:
    """The first screen: the bottom line, a heading row per paper, with the key to its
    verdict words."""
    head = "".join(f"<th class='{'num' if i == BOTTOM_NUMBER else ''}'>{h}</th>"
                   for i, h in enumerate(BOTTOM_HEADERS))
    body = "".join(
        f"<tr><th colspan='{len(BOTTOM_HEADERS)}' class='paper'><a href='#paper-"
        f"{html.escape(s.key)}'>{html.escape(s.title)}</a></th></tr>"
        + "".join(_bottom_row(line, notes) for line in s.lines()) for s in sections)
    key = "".join(f"<li><b>{w}</b>: {html.escape(m)}</li>" for w, m in VERDICT_WORDS)
    return (f"<h2 id='bottom-line'>Bottom line</h2><p>One verdict per paper item, from the "
            f"config declared to answer it.</p><table><tr>{head}</tr>{body}</table>"
            f"<ul>{key}</ul>")


def _contents_html(sections: Sequence[PaperSection]) -> str:
    esc = html.escape
    items = "".join(
        f"<li><a href='#paper-{esc(s.key)}'>{esc(s.title)}</a><ul>"
        + "".join(f"<li><a href='#{esc(s.key)}-{_anchor(f)}'>{esc(f.paper_item or f.png.stem)} "
                  f"({esc(f.config)})</a></li>" for f in s.figures)
        + f"<li><a href='#{esc(s.key)}-rows'>every compared row</a></li></ul></li>"
        for s in sections)
    return (f"<h2 id='contents'>Contents</h2><ul><li><a href='#bottom-line'>Bottom line</a>"
            f"</li>{items}<li><a href='#runs'>Runs: each config's own page</a></li></ul>")


def _anchor(f: MainFigure) -> str:
    return re.sub(r"[^a-z0-9]+", "-", f"{f.paper_item or f.png.stem} {f.config}".lower()
                  ).strip("-")


def _section_html(s: PaperSection, out: Path) -> str:
    esc = html.escape
    parts = [f"<section id='paper-{esc(s.key)}'><h2>{esc(s.title)}</h2>"
             f"<p><i>{esc(s.paper.citation)}</i></p>"]
    parts += [f"<p>problem: {esc(p)}</p>" for p in s.problems]
    for f in s.figures:
        rel = esc(os.path.relpath(f.png, out))
        item = f.paper_item or f.png.stem
        says = (paper_claims(s, f.paper_item) if f.paper_item
                else "a figure of our own: the paper has none")
        parts.append(
            f"<div class='pair' id='{esc(s.key)}-{_anchor(f)}'><div><h3>{esc(item)}: "
            f"the paper</h3><p>{esc(says)}</p></div>"
            f"<figure><img src='{rel}' alt='{esc(item)}, {esc(f.config)}'>"
            f"<figcaption>Ours ({esc(f.config)}): {esc(f.caption)}</figcaption></figure></div>")
    if s.linked:
        parts.append("<p>Main figures of the other configs: " + ", ".join(
            f"<a href='{esc(os.path.relpath(f.png, out))}'>{esc(f.config)}: "
            f"{esc(f.png.stem)}</a>" for f in s.linked) + "</p>")
    rows = [_row_cells(r) for _, r in s.rows.iterrows()]
    parts.append(f"<details id='{esc(s.key)}-rows'><summary>Every compared row ({len(rows)}, "
                 "every config)</summary>"
                 + (html_table(ROW_HEADERS, rows) if rows else "<p>none</p>") + "</details>")
    return "".join(parts) + "</section>"


def report_html(sections: Sequence[PaperSection], out: Path,
                notes: Mapping[str, str] | None = None) -> str:
    """The whole report as one HTML page (no JavaScript); images, runs and notes linked
    relative to ``out``."""
    esc = html.escape
    notes = notes or {}
    runs = "".join(f"<li><a href='{esc(os.path.relpath(folder / INDEX_HTML, out))}'>"
                   f"{esc(name)}</a></li>" for s in sections for name, folder in s.runs.items())
    parts = ["<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
             "<title>Paper reported against reproduced</title>"
             f"<style>{_CSS}</style></head><body>"
             "<h1>Paper reported against reproduced</h1>",
             _bottom_line_html(sections, notes), _contents_html(sections),
             *(_section_html(s, out) for s in sections),
             f"<h2 id='runs'>Runs</h2><p>Each config's own page, with its run facts, every "
             f"figure and table:</p><ul>{runs}</ul></body></html>"]
    return "\n".join(parts) + "\n"


def _draw_beside(section: PaperSection, out: Path) -> None:
    """Draw the paper's :class:`~trackfuse.reported.Beside` figure into ``out/figures/``
    when both of its runs are in ``section``, and show it for its paper item in place of
    the paper config's own figure (which is then linked)."""
    beside = section.paper.beside
    if beside is None or not {beside.paper, beside.analogue} <= section.runs.keys():
        return
    module, function = beside.draw.split(":")
    fig = getattr(importlib.import_module(module), function)(
        load(section.runs[beside.paper]), load(section.runs[beside.analogue]))
    if isinstance(fig, str):
        section.problems.append(f"{beside.item} beside {beside.analogue}: {fig}")
        return
    (out / "figures").mkdir(exist_ok=True)
    name = re.sub(r"[^a-z0-9]+", "_", f"{section.key} {beside.item}".lower())
    png = save_figure(fig, out / "figures", name, ["png"])[0]
    caption = (f"left, the paper's scenario ({beside.paper}); right, the analogue "
               f"({beside.analogue}) where the effect shows; 95 % intervals")
    shown = MainFigure(png, caption, beside.item, f"{beside.paper} + {beside.analogue}")
    replaced = [f for f in section.figures if f.paper_item == beside.item]
    section.figures = [shown if f.paper_item == beside.item else f for f in section.figures]
    if not replaced:
        section.figures.append(shown)
    section.linked = replaced + section.linked


def write_reproduction_report(folders: Sequence[Path], out: Path,
                              papers: Mapping[str, Paper] = PAPERS) -> Path:
    """Write ``out/REPORT.md`` and ``out/report.html`` for the runs in ``folders``, with the
    notes of ``docs/papers/`` rendered into ``out/notes/``; returns the HTML path."""
    out.mkdir(parents=True, exist_ok=True)
    sections = collect(folders, papers)
    for section in sections:
        _draw_beside(section, out)
    notes = write_notes(out, f"../{REPORT_HTML}")
    atomic_write(out / REPORT_MD, report_markdown(sections, out, notes))
    atomic_write(out / REPORT_HTML, report_html(sections, out, notes))
    return out / REPORT_HTML
