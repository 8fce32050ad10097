"""The report of ``trackfuse reproduce``: per paper, what was reproduced and what was not.

:func:`write_reproduction_report` reads finished run folders (each one's
``tables/paper_vs_reproduced.csv``, in the :data:`trackfuse.reports.HEADLINE_COLUMNS` schema,
its figures and its config) and writes :data:`REPORT_MD` and :data:`REPORT_HTML` into the
output root. One section per paper: the citation, a count of verdicts, one row per paper
item compared (the paper's value beside ours with its 95 % interval, the verdict and a
one-line reason linking to ``docs/papers/``), then each main figure of the paper's own configs
(a figure whose :class:`~trackfuse.experiments.base.FigureSpec` names a paper figure or table)
beside what the paper itself shows, and a link to the main figure of every other config: the
first figure of its ``outputs.figures`` that was drawn (the experiment's declared order when
it says ``all``). The page needs no network and no JavaScript; its images are the run
folders' PNG files, linked by relative paths.

Links into ``docs/`` (the headline table's ``docs`` column) point at the checkout that holds
the running code (else the current folder): relative to the output folder when it lies inside
that checkout, so they survive moving the whole checkout; an absolute path otherwise, so they
survive moving the output folder. A page found in neither is named without a link.
"""

from __future__ import annotations

import html
import os
import re
from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import pandas as pd

import trackfuse
from trackfuse.plots.algorithms import OUR_ROLES, look
from trackfuse.reported import PAPERS, Paper
from trackfuse.reports import HEADLINE_COLUMNS, HEADLINE_TABLE, VERDICTS, wanted_figures
from trackfuse.results import atomic_write
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
    """Everything the report shows for one paper (an experiment with reported results):
    ``figures`` drawn beside the paper's claims (from the paper's own configs, or from every
    config when none of those ran), ``linked`` the other configs' main figures."""

    key: str
    citation: str
    claims: dict[str, str]
    rows: pd.DataFrame
    figures: list[MainFigure] = field(default_factory=list)
    linked: list[MainFigure] = field(default_factory=list)
    configs: list[str] = field(default_factory=list)
    problems: list[str] = field(default_factory=list)
    others: dict[str, dict[str, int]] = field(default_factory=dict)

    def verdict_counts(self, ours: bool | None = None) -> dict[str, int]:
        """How many compared items got each verdict (in :data:`VERDICTS` order): of every
        row, or (``ours``) only of the rows about our methods and other variants, or (not
        ``ours``) only of the rest (:func:`about_ours`)."""
        rows = self.rows
        if ours is not None and len(rows):
            rows = rows[rows["algorithm"].map(about_ours) == ours]
        counts = rows["verdict"].value_counts() if len(rows) else pd.Series()
        return {v: int(counts.get(v, 0)) for v in VERDICTS}


def about_ours(algorithm: object) -> bool:
    """Whether a headline row's ``algorithm`` is one of ours or another variant
    (:data:`trackfuse.plots.algorithms.ROLES`), not the paper's method or its baseline; a
    row with no algorithm, or with a reference solver (the exact optimum answering the
    paper's claim about the Hungarian method), is about the paper's claim itself."""
    return isinstance(algorithm, str) and bool(algorithm) and \
        look(algorithm).role in OUR_ROLES


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
    source = str(run.manifest.get("config_file") or run.path.parent.name)
    return Path(source).stem


def main_figure_names(wanted: Sequence[str], drawn: Collection[str],
                      paper_items: Mapping[str, str], own: bool) -> list[str]:
    """Which drawn figures stand for a run in the report: for one of the paper's own configs
    every drawn figure that names a paper item (``paper_items[name]`` non-empty), in
    ``wanted`` order; for any other config the first of ``wanted`` that was drawn (its
    declared main figure)."""
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
    """One :class:`PaperSection` per paper among the complete runs in ``folders``, in the
    order of ``papers`` (experiment name -> paper); other experiments' runs are skipped."""
    sections: dict[str, PaperSection] = {}
    for folder in folders:
        run = load(folder)
        key = str(run.config["experiment"])
        paper = papers.get(key)
        if paper is None:
            continue
        section = sections.setdefault(key, PaperSection(
            key, paper.citation, _claims(paper),
            pd.DataFrame(columns=["config", *HEADLINE_COLUMNS])))
        try:
            rows = _headline(run)
        except ValueError as err:
            section.problems.append(str(err))
            rows = pd.DataFrame()
        own = _config_name(run) in paper.configs or not paper.configs
        if len(rows) and own:
            section.rows = rows if section.rows.empty else pd.concat(
                [section.rows, rows], ignore_index=True)
        elif len(rows):
            counts = rows["verdict"].value_counts()
            section.others[_config_name(run)] = {v: int(counts.get(v, 0)) for v in VERDICTS}
        (section.figures if own else section.linked).extend(_main_figures(run, own))
        section.configs.append(_config_name(run))
    for section in sections.values():
        section.rows = _merge_repeats(section.rows)
        if not section.figures:
            section.figures, section.linked = section.linked, []
    return [sections[k] for k in papers if k in sections]


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


def _text(value: object) -> str:
    return "" if pd.isna(value) else str(value)


def _ours(row: pd.Series) -> str:
    value = row["reproduced"]
    if pd.isna(value):
        return ""
    text = f"{value:.4g}"
    if not (pd.isna(row["ci_low"]) or pd.isna(row["ci_high"])):
        text += f" [{row['ci_low']:.4g}, {row['ci_high']:.4g}]"
    unit = _text(row["unit"])
    return f"{text} {unit}".strip() if unit not in ("1", "fraction") else text


def _counted(counts: Mapping[str, int]) -> str:
    return ", ".join(f"{n} {v}" for v, n in counts.items() if n) or "none"


def _summary_line(section: PaperSection) -> str:
    """The section's verdicts counted: the paper's methods and claims apart from ours and
    other variants, so that our methods' agreement does not pass for the paper's."""
    total = sum(section.verdict_counts().values())
    line = (f"{total} paper items compared in the paper's own configs: the paper's methods and "
            "claims "
            f"{_counted(section.verdict_counts(ours=False))}; ours and other variants "
            f"{_counted(section.verdict_counts(ours=True))}."
            if total else "No paper item could be compared from the paper's own configs.")
    others = "; ".join(f"{name}: {_counted(counts)}" for name, counts in section.others.items())
    return line + (f" Other configs (their own index.html): {others}." if others else "")


#: The checkout holding the running code (its ``docs/`` sits beside ``trackfuse/``).
CHECKOUT = Path(trackfuse.__file__).resolve().parent.parent


def _doc_link(docs: object, out: Path, checkouts: Sequence[Path] | None = None
              ) -> tuple[str, str]:
    """``(href, text)`` for the ``docs`` column (``docs/papers/<page>.md#<anchor>``): the page in
    the first of ``checkouts`` (default: :data:`CHECKOUT`, then the current folder) that
    holds it, linked relative to ``out`` when ``out`` lies inside that checkout, else by
    its absolute path (see the module docstring); no link when no checkout holds it."""
    target = "" if pd.isna(docs) else str(docs)
    page, _, anchor = target.partition("#")
    suffix = f"#{anchor}" if anchor else ""
    for root in checkouts if checkouts is not None else (CHECKOUT, Path.cwd()):
        local = root.resolve() / page
        if target and local.is_file():
            inside = out.resolve().is_relative_to(root.resolve())
            return (os.path.relpath(local, out.resolve()) if inside else str(local)) + suffix, \
                target
    return "", target


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


def report_markdown(sections: Sequence[PaperSection], out: Path) -> str:
    """The whole report as Markdown; image and doc links relative to ``out``."""
    lines = ["# trackfuse reproduce: paper reported vs reproduced", "",
             "Each paper item is set against our estimate with its 95 % interval; "
             "`agrees` means the paper's number lies inside our interval (or the data show "
             "its claim), `differs` that it lies outside (or the data contradict the claim), "
             "`inconclusive` that the data can do neither, `not comparable` that the config "
             "cannot answer it or the paper gives no number to set beside ours; the reason "
             "is in one line. Links into "
             "`docs/` point at the checkout that ran the code: relative when this folder lies "
             "inside it, absolute otherwise.", ""]
    for s in sections:
        lines += [f"## {s.key}", "", f"*{s.citation}*", "", _summary_line(s), ""]
        if not s.rows.empty:
            lines += ["| config | paper item | quantity | algorithm | paper | ours [95 % CI] "
                      "| verdict | reason |", "|---|---|---|---|---|---|---|---|"]
        for _, r in s.rows.iterrows():
            link, text = _doc_link(r["docs"], out)
            reason = (f"{r['reason']} ([{text}]({link}))" if link
                      else f"{r['reason']} ({text})" if text else str(r["reason"]))
            cells = [r["config"], r["paper_item"], r["quantity"], _text(r["algorithm"]),
                     _text(r["paper_value"]), _ours(r), f"**{r['verdict']}**", reason]
            lines.append("| " + " | ".join(str(c).replace("|", "\\|") for c in cells) + " |")
        lines += [""] if not s.rows.empty else []
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
    return "\n".join(lines) + "\n"


_CSS = ("body{font-family:sans-serif;max-width:80em;margin:2em auto;padding:0 1em;"
        "line-height:1.4}table{border-collapse:collapse;font-size:90%;margin:1em 0}"
        "td,th{border:1px solid #ccc;padding:2px 6px;vertical-align:top}"
        "th{background:#f3f3f3}.agrees{background:#e6f4ea}.differs{background:#fce8e6}"
        ".inconclusive{background:#fef7e0}"
        ".pair{display:grid;grid-template-columns:1fr 2fr;gap:1em;margin:1.5em 0;"
        "border-top:1px solid #ddd;padding-top:1em}img{max-width:100%}"
        "section{margin-bottom:3em}")


def _html_rows(section: PaperSection, out: Path) -> str:
    esc = html.escape
    if section.rows.empty:
        return ""
    head = ("<tr><th>config</th><th>paper item</th><th>quantity</th><th>algorithm</th>"
            "<th>paper</th><th>ours [95 % CI]</th><th>verdict</th><th>reason</th></tr>")
    body = []
    for _, r in section.rows.iterrows():
        link, text = _doc_link(r["docs"], out)
        more = (f" (<a href='{esc(link)}'>{esc(text)}</a>)" if link
                else f" ({esc(text)})" if text else "")
        verdict = str(r["verdict"])
        body.append(
            f"<tr class='{esc(verdict.replace(' ', '-'))}'>" + "".join(
                f"<td>{esc(_text(c))}</td>" for c in (r["config"], r["paper_item"],
                                                      r["quantity"], r["algorithm"],
                                                      r["paper_value"], _ours(r)))
            + f"<td><b>{esc(verdict)}</b></td><td>{esc(str(r['reason']))}{more}</td></tr>")
    return f"<table>{head}{''.join(body)}</table>"


def report_html(sections: Sequence[PaperSection], out: Path) -> str:
    """The whole report as one HTML page (no JavaScript); images linked relative to ``out``."""
    esc = html.escape
    parts = ["<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'>"
             "<title>trackfuse reproduce: paper reported vs reproduced</title>"
             f"<style>{_CSS}</style></head><body>"
             "<h1>Paper reported vs reproduced</h1>"]
    for s in sections:
        parts.append(f"<section><h2>{esc(s.key)}</h2><p><i>{esc(s.citation)}</i></p>"
                     f"<p>{esc(_summary_line(s))}</p>{_html_rows(s, out)}"
                     + "".join(f"<p>problem: {esc(p)}</p>" for p in s.problems))
        for f in s.figures:
            rel = esc(os.path.relpath(f.png, out))
            parts.append(
                f"<div class='pair'><div><h3>{esc(f.paper_item)}: the paper</h3>"
                f"<p>{esc(paper_claims(s, f.paper_item))}</p></div>"
                f"<figure><img src='{rel}' alt='{esc(f.paper_item)}, {esc(f.config)}'>"
                f"<figcaption>Ours ({esc(f.config)}): {esc(f.caption)}</figcaption>"
                "</figure></div>")
        if s.linked:
            parts.append("<p>Main figures of the other configs: " + ", ".join(
                f"<a href='{esc(os.path.relpath(f.png, out))}'>{esc(f.config)}: "
                f"{esc(f.png.stem)}</a>" for f in s.linked) + "</p>")
        parts.append("</section>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"


def write_reproduction_report(folders: Sequence[Path], out: Path,
                              papers: Mapping[str, Paper] = PAPERS) -> Path:
    """Write ``out/REPORT.md`` and ``out/report.html`` for the runs in ``folders``;
    returns the HTML path."""
    out.mkdir(parents=True, exist_ok=True)
    sections = collect(folders, papers)
    atomic_write(out / REPORT_MD, report_markdown(sections, out))
    atomic_write(out / REPORT_HTML, report_html(sections, out))
    return out / REPORT_HTML
