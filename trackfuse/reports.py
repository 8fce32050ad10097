"""A finished run's report: tables, figures, ``index.md`` and ``index.html``.

Reads only the run folder and the experiment's report module (``figures``, ``tables`` and
an optional ``prepare``: ``docs/runner.md``, "The experiment contract"). A figure or table
the run cannot give is a one-line reason; one that raises costs only itself. Files are
written atomically and reproducibly (same bytes on a redraw); a redraw removes only the
earlier report files it did not write again. matplotlib is imported only to draw. Users'
view: ``docs/outputs.md``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import gc
import html
import importlib
import math
import multiprocessing
import os
import threading
from collections.abc import Callable, Collection, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any

import pandas as pd

from trackfuse.child_processes import ctrl_c_held, setup_child
from trackfuse.coerce import one_line
from trackfuse.environment import cpu_words, recorded_cpus
from trackfuse.failures import first_failure
from trackfuse.manifest import Manifest
from trackfuse.reportkit.headline import READER_HEADERS, reader_cells
from trackfuse.reportkit.htmltable import TABLE_CSS, cell_text, frame_html, html_table
from trackfuse.reportkit.notes import NOTES, note_href, write_notes
from trackfuse.reportkit.numberformat import interval_text
from trackfuse.reportkit.verdicts import VERDICTS
from trackfuse.results import (
    INDEX_FILES,
    INDEX_HTML,
    INDEX_MD,
    REPORT_FILES,
    RunFolder,
    RunFolderError,
    atomic_write,
    removed_words,
)
from trackfuse.rowformat import FAILED_ROW
from trackfuse.rowtable import frame_csv
from trackfuse.rundata import RunData, swept_keys
from trackfuse.store import trials_file
from trackfuse.trial_guard import PLUGIN_FAILURES, guarded

PNG_DPI = 200
#: zlib level of PNG files: 1 halves the encoding time of level 6 for files ~1.3x larger.
PNG_COMPRESSION = 1
#: At most this many processes draw one run's figures (one per core when fewer).
MAX_DRAWING_PROCESSES = 4
#: New objects between the garbage collector's youngest-generation passes in a drawing
#: process (Python's default: 700): it lives for one run's figures, and matplotlib allocates
#: tens of thousands of objects a figure.
DRAWING_GC_THRESHOLD = 10_000
HEADLINE_TABLE = "paper_vs_reproduced"
#: A report table longer than this is folded (closed ``<details>``) in ``index.html`` and
#: linked, not written out, in ``index.md``.
FOLDED_TABLE_ROWS = 30
#: Columns of every experiment's headline table, one row per paper item compared:
#: ``paper_item`` the paper's figure or table ("Table 3"); ``quantity`` in words;
#: ``algorithm`` our algorithm name; ``paper_value`` what the paper reports (number or words);
#: ``reproduced`` our estimate (number, in ``unit``) with its 95 % interval
#: ``ci_low``/``ci_high``; ``trials`` behind it; ``verdict`` one of :data:`VERDICTS`;
#: ``reason`` one line; ``docs`` a link into ``docs/papers/`` with the longer explanation;
#: ``claim`` the :attr:`~trackfuse.reported.Reported.quantity` of the paper item it judges
#: and ``setting`` its swept setting (:func:`~trackfuse.reportkit.verdicts.setting_text`),
#: by which the reproduction report finds the row that answers each item.
HEADLINE_COLUMNS = ("paper_item", "quantity", "algorithm", "paper_value", "reproduced",
                    "ci_low", "ci_high", "unit", "trials", "verdict", "reason", "docs",
                    "claim", "setting")


def headline_row(paper_item: str, quantity: str, algorithm: str, paper_value: Any,
                 reproduced: float, ci_low: float, ci_high: float, unit: str,
                 trials: int | None, verdict: str, reason: str, docs: str, *, claim: str,
                 setting: str = "") -> dict[str, Any]:
    """One headline-table row in :data:`HEADLINE_COLUMNS` order (NaN for no value); ValueError for
    a ``verdict`` not in :data:`VERDICTS`.
    """
    if verdict not in VERDICTS:
        raise ValueError(f"verdict {verdict!r} is not one of {VERDICTS}")
    return dict(zip(HEADLINE_COLUMNS, (paper_item, quantity, algorithm, paper_value,
                                       float(reproduced), float(ci_low), float(ci_high), unit,
                                       trials, verdict, reason, docs, claim, setting),
                    strict=True))


#: Why a table is not written when its report module returns it without rows.
NO_ROWS = "no rows for this config"
#: What each file of a run folder holds (figures and tables add their own captions).
FILES = {
    "config.yaml": "the resolved config: every parameter, defaults included",
    "manifest.json": "status, versions, git repository and commit, code fingerprint, "
                     "command, times, trial counts, checksums of the final files",
    "trials.csv": "one row per sweep point, trial and row key: swept values and metrics",
    "trials.parquet": "trials.csv in Parquet (outputs.store: parquet)",
    "timings.csv": "wall and CPU time columns, kept out of trials.csv",
    "summary.csv": "per point, row key and metric: n, mean, std, 95 % interval",
    "timings_summary.csv": "the summary of the timing columns",
    INDEX_MD: "this report as Markdown",
    INDEX_HTML: "this report as a web page",
}
#: A figure file's words in the file list, by its suffix.
FIGURE_FILES = {".png": "the figure above, image (PNG)", ".pdf": "the figure above, vector (PDF)",
                ".svg": "the figure above, vector (SVG)"}


@dataclass
class Report:
    """What :func:`write_report` wrote: figure and table files, the index, the paper ``notes`` (and
    their ``note_pages``), one message per failed figure or table, the reasons in
    ``not_drawn`` and ``not_tabulated``, and the earlier files ``removed``.
    """

    figures: list[Path] = field(default_factory=list)
    tables: list[Path] = field(default_factory=list)
    index: Path | None = None
    errors: list[str] = field(default_factory=list)
    not_drawn: dict[str, str] = field(default_factory=dict)
    not_tabulated: dict[str, str] = field(default_factory=dict)
    removed: list[Path] = field(default_factory=list)
    notes: list[Path] = field(default_factory=list)
    note_pages: dict[str, str] = field(default_factory=dict)

    def manifest_entries(self, run_path: Path) -> dict[str, Any]:
        """What the run's manifest records of this report: its problems and its files,
        relative to the run folder ``run_path`` (:func:`trackfuse.runstate.has_report`)."""
        files = [*self.figures, *self.tables, *self.notes, run_path / INDEX_MD,
                 run_path / INDEX_HTML]
        return {"figure_errors": list(self.errors),
                REPORT_FILES: [p.relative_to(run_path).as_posix() for p in files]}


class NothingToDraw(RunFolderError):
    """A run no report can be drawn from (:func:`undrawable`); ``str(err)`` is one line."""


def md_text(text: Any) -> str:
    """``text`` for Markdown: ``<``, ``>`` and ``&`` escaped, so raw HTML in a title, a name
    or a table cell is shown, never rendered (as ``index.html`` does)."""
    return html.escape(str(text), quote=False)


def markdown_table(table: pd.DataFrame) -> str:
    """A GitHub-style Markdown table; numbers with three significant figures
    (:func:`~trackfuse.reportkit.htmltable.cell_text`); text as :func:`md_text` writes it."""
    def cell(v: Any) -> str:
        return md_text(cell_text(v)).replace("|", "\\|")

    lines = ["| " + " | ".join(map(cell, table.columns)) + " |",
             "|" + "|".join("---" for _ in table.columns) + "|"]
    lines += ["| " + " | ".join(cell(v) for v in row) + " |"
              for row in table.itertuples(index=False)]
    return "\n".join(lines) + "\n"


def as_printed(value: Any) -> Any:
    """A paper's number as the paper prints it: up to 6 significant digits when that is the
    exact value (``5.2375``, ``0.059375``), else 4; anything else unchanged."""
    if not isinstance(value, float) or not math.isfinite(value):
        return value
    six = f"{value:.6g}"
    return six if float(six) == value else f"{value:.4g}"


def display_table(table: pd.DataFrame) -> pd.DataFrame:
    """``table`` for reading: each ``<q>_ci_low``/``<q>_ci_high`` pair becomes one ``<q> 95 % CI``
    column after ``<q>`` (three significant figures); paper values as printed. CSVs keep numbers.
    """
    shown = table.copy()
    if "paper_value" in shown.columns:
        shown["paper_value"] = [as_printed(v) for v in shown["paper_value"]]
    for low in [c for c in table.columns if str(c) == "ci_low" or str(c).endswith("_ci_low")]:
        stem = str(low)[: -len("ci_low")]
        high = f"{stem}ci_high"
        stem = stem.rstrip("_")
        if high not in shown.columns:
            continue
        text = [interval_text(lo, hi) for lo, hi in zip(shown[low], shown[high], strict=True)]
        at = list(shown.columns).index(low)
        shown = shown.drop(columns=[low, high])
        shown.insert(min(at, len(shown.columns)), f"{stem} 95 % CI".lstrip(), text)
    return shown


def provenance(run: RunData) -> str:
    """One line naming what produced a run's figures: config file, experiment, seed, trials
    per point and run id (embedded in every figure file: :func:`save_figure`)."""
    source = Path(run.manifest.config_file or "").name or "(no file)"
    return (f"trackfuse {run.config.get('experiment')}, config {source}, seed "
            f"{run.config.get('seed')}, {_runs_per_point(run.config.get('trials'))}, run "
            f"{run.manifest.run_id}")


def _runs_per_point(trials: Any) -> str:
    """``50 runs per point``, or ``up to 20000 runs per point (sequential)``."""
    if isinstance(trials, dict):
        return f"up to {trials.get('max')} runs per point (sequential)"
    return f"{trials} runs per point"


def save_figure(fig, folder: Path, name: str, formats: Sequence[str],
                source: str = "") -> list[Path]:
    """Save ``fig`` as ``folder/name.<fmt>`` per format, reproducibly and atomically, with
    ``source`` in the file's metadata. The layout is computed for the first format and kept
    for the others (``fig`` keeps it): constrained layout costs about as much as drawing.
    """
    written = []
    for i, fmt in enumerate(formats):
        if i == 1:
            fig.set_layout_engine("none")
        path = folder / f"{name}.{fmt}"
        tmp = folder / f".{name}.{os.getpid()}.tmp.{fmt}"
        metadata = {"pdf": {"CreationDate": None, "ModDate": None, "Subject": source},
                    "png": {"Source": source},
                    "svg": {"Date": None, "Description": source}}.get(fmt)
        extra = {"pil_kwargs": {"compress_level": PNG_COMPRESSION}} if fmt == "png" else {}
        fig.savefig(tmp, format=fmt, dpi=PNG_DPI, metadata=metadata, **extra)
        tmp.replace(path)
        written.append(path)
    return written


def _module(run: RunData, report: Report) -> ModuleType | None:
    """The experiment's report module, or ``None`` (no report declared, or it fails to
    import: one message in ``report.errors``)."""
    if not run.experiment.report:
        return None
    try:
        with guarded():
            return importlib.import_module(run.experiment.report)
    except PLUGIN_FAILURES as err:  # a report bug must not lose the run
        report.errors.append(f"report module {run.experiment.report}: {one_line(err)}")
        return None


def _write_tables(run: RunData, module: ModuleType, report: Report) -> dict[str, pd.DataFrame]:
    if not hasattr(module, "tables"):  # tables are optional
        return {}
    folder = run.path / "tables"
    folder.mkdir(exist_ok=True)
    try:
        with guarded():
            made = module.tables(run)
    except PLUGIN_FAILURES as err:  # a report bug must not lose the run
        report.errors.append(f"tables: {one_line(err)}")
        return {}
    if not isinstance(made, dict) or not all(
            isinstance(t, str | pd.DataFrame) for t in made.values()):
        report.errors.append(f"tables: returned {type(made).__name__}; expected a dict of "
                             "table name to DataFrame (or to a one-line reason it is empty)")
        return {}
    written = {}
    for name, table in made.items():
        if isinstance(table, str) or table.empty:
            report.not_tabulated[name] = table if isinstance(table, str) else NO_ROWS
            continue
        for suffix, text in ((".csv", frame_csv(table)),
                             (".md", markdown_table(display_table(table)))):
            atomic_write(folder / f"{name}{suffix}", text)
            report.tables.append(folder / f"{name}{suffix}")
        written[name] = table
    return written


def _draw(run: RunData, module: ModuleType, names: Sequence[str],
          formats: Sequence[str]) -> Report:
    """Draw and save the figures ``names``, one at a time (the report's ``figures``,
    ``errors`` and ``not_drawn`` parts for them)."""
    from trackfuse.reportkit.style import context, shared_pdf_font  # matplotlib: docstring

    if "pdf" in formats:
        shared_pdf_font()
    part, source = Report(), provenance(run)
    for name in names:
        try:
            with context(), guarded():  # every text of the figure in the house sizes
                fig = module.figures(run, [name]).get(name)
        except PLUGIN_FAILURES as err:  # one figure's bug must not lose the others
            part.errors.append(f"figure {name}: {one_line(err)}")
            continue
        if fig is None or isinstance(fig, str):
            part.not_drawn[name] = fig or "the experiment's report drew nothing for this config"
            continue
        try:
            with context():  # the journal style's PDF font type (TrueType) at save time
                part.figures += save_figure(fig, run.path / "figures", name, formats, source)
        except OSError:  # the disk (full, unwritable), not the figure: the run stops, resumable
            raise
        except Exception as err:  # noqa: BLE001 - one figure's bug must not lose the others
            part.errors.append(f"figure {name}: {one_line(err)}")
    return part


#: What a forked drawing process needs, set by the parent just before it forks.
_FORK_STATE: tuple[RunData, ModuleType, Sequence[str]] | None = None


def _draw_in_fork(name: str) -> Report:
    assert _FORK_STATE is not None
    run, module, formats = _FORK_STATE
    return _draw(run, module, [name], formats)


def _drawing_child(main_pid: int) -> None:
    """Start of a forked drawing process: :func:`setup_child`, then the garbage collector set
    to never scan the objects inherited from the main process (``gc.freeze``: they outlive
    the drawing, and scanning them writes to memory pages shared with it) and to pass over
    new ones less often (:data:`DRAWING_GC_THRESHOLD`)."""
    setup_child(main_pid)
    gc.freeze()
    gc.set_threshold(DRAWING_GC_THRESHOLD)


def drawing_processes(figures: int) -> int:
    """Processes to draw ``figures`` figures with: up to one per available core, and 1 where
    forking is unavailable or unsafe (another thread is running)."""
    if "fork" not in multiprocessing.get_all_start_methods() or threading.active_count() > 1:
        return 1
    return max(1, min(figures, len(os.sched_getaffinity(0)), MAX_DRAWING_PROCESSES))


def _write_figures(run: RunData, module: ModuleType, wanted: Sequence[str],
                   formats: Sequence[str], report: Report, meanwhile: Callable[[], None]) -> None:
    """Draw ``wanted`` in forked processes (each saves its own files, so bytes do not depend on
    who drew what), call ``meanwhile`` here, and merge their parts in order.
    """
    global _FORK_STATE
    (run.path / "figures").mkdir(exist_ok=True)
    processes = drawing_processes(len(wanted))
    if processes == 1:
        meanwhile()
        parts = [_draw(run, module, wanted, formats)]
    else:
        from trackfuse.reportkit.style import warm_up  # matplotlib: see the module docstring

        run.trials, run.summary  # noqa: B018 - read once here, inherited by the forks
        warm_up(tuple(formats), PNG_DPI)
        _FORK_STATE = (run, module, formats)
        try:
            with ProcessPoolExecutor(processes, multiprocessing.get_context("fork"),
                                     initializer=_drawing_child,
                                     initargs=(os.getpid(),)) as pool:
                try:
                    with ctrl_c_held():  # the forks: see ctrl_c_held
                        drawing = [pool.submit(_draw_in_fork, name) for name in wanted]
                    meanwhile()
                    parts = [future.result() for future in drawing]
                except KeyboardInterrupt:  # stop now: no figure more
                    pool.shutdown(wait=False, cancel_futures=True)
                    raise
        finally:
            _FORK_STATE = None
    position = {name: i for i, name in enumerate(wanted)}
    for part in parts:
        report.errors += part.errors
        report.not_drawn.update(part.not_drawn)
        report.figures += part.figures
    order = {f".{fmt}": i for i, fmt in enumerate(formats)}
    report.figures.sort(key=lambda p: (position.get(p.stem, len(position)), order[p.suffix]))
    report.not_drawn = {n: report.not_drawn[n] for n in wanted if n in report.not_drawn}


def figure_formats(config: dict[str, Any]) -> list[str]:
    """The file formats of a run's figures: the resolved config's ``outputs.formats``."""
    return list((config.get("outputs") or {}).get("formats") or ["png", "pdf"])


def load_drawing(formats: Sequence[str]) -> None:
    """Import matplotlib and warm up the house style for ``formats`` (the runner calls it in a
    thread while workers compute); runs no experiment code.
    """
    from trackfuse.reportkit.style import warm_up  # matplotlib: see the module docstring

    warm_up(tuple(formats), PNG_DPI)


def _prepare(run: RunData, module: ModuleType) -> None:
    """The report module's optional ``prepare(run)``, computed once into caches the drawing
    processes inherit; a failure is left to the figures and tables to report.
    """
    if hasattr(module, "prepare"):
        with contextlib.suppress(*PLUGIN_FAILURES), guarded():
            module.prepare(run)


def wanted_figures(run: RunData) -> list[str]:
    """The figures the config asks for (``outputs.figures``), or every declared one for ``all``."""
    choice = (run.config.get("outputs") or {}).get("figures", "all")
    return list(run.experiment.figures) if choice == "all" else list(choice)


def undrawable(run: RunData) -> str | None:
    """Why no report can be drawn from ``run``'s ``trials.csv`` (unreadable, no rows, a
    column the runner writes in every row missing, every trial failed), or ``None``."""
    where = trials_file(run.path)
    try:
        trials = run.trials
    except RunFolderError as err:
        return str(err)
    if trials.empty:
        return f"{where}: no rows"
    swept = swept_keys(run.config)
    missing = [c for c in ("point", "trial", *swept) if c not in trials]
    if missing:
        return (f"{where}: no column {missing[0][:80]!r} (every row starts with point, trial "
                "and the swept keys)")
    if "status" in trials and (trials["status"].astype(str) == FAILED_ROW).all():
        return (f"every trial failed ({len(trials)} of {len(trials)}; first: "
                f"{first_failure(trials, swept)})")
    return None


def _remove_earlier(run: RunData, keep: Collection[Path], report: Report) -> None:
    """Delete the files an earlier draw wrote (the manifest's ``report_files``: never a
    file of the user's) other than ``keep``, naming them in ``report.removed``."""
    for path in RunFolder(run.path).report_files(run.manifest.report_files):
        if path not in keep:
            path.unlink()
            report.removed.append(path)


def write_report(run: RunData, wanted: Collection[str] | None = None,
                 formats: Sequence[str] | None = None) -> Report:
    """Draw ``run``'s tables and figures, remove an earlier draw's leftovers, write the index.

    ``run.manifest`` then lists the files written (the caller saves it). Raises
    :class:`~trackfuse.results.RunFolderError` for a ``figures/`` or ``tables/`` that is a link
    or not a folder, :class:`NothingToDraw` for a run :func:`undrawable` names a reason for.
    """
    RunFolder(run.path).check_layout()  # never write or delete through a link
    why = undrawable(run)
    if why is not None:
        earlier = Report()
        _remove_earlier(run, (), earlier)
        raise NothingToDraw(f"{why}: nothing to draw" + (
            f"; the earlier report was removed ({removed_words(earlier.removed, run.path)})"
            if earlier.removed else ""))
    if wanted is None:
        wanted = wanted_figures(run)
    formats = list(formats or figure_formats(run.config))
    report = Report()
    module = _module(run, report)
    tables: dict[str, pd.DataFrame] = {}
    if module is not None:
        _prepare(run, module)
        _write_figures(run, module, list(wanted), formats, report,
                       meanwhile=lambda: tables.update(_write_tables(run, module, report)))
    if HEADLINE_TABLE in tables:  # its reasons link into the notes on the paper
        report.note_pages = write_notes(run.path, f"../{INDEX_HTML}",
                                        tables[HEADLINE_TABLE]["docs"])
        report.notes = [run.path / page for page in report.note_pages.values()]
    written = {*report.figures, *report.tables, *report.notes,
               *(run.path / n for n in INDEX_FILES)}
    _remove_earlier(run, written, report)  # it would look like a result of this one
    md = index_markdown(run, tables, report)
    atomic_write(run.path / INDEX_MD, md)
    atomic_write(run.path / INDEX_HTML, index_html(run, tables, report))
    report.index = run.path / INDEX_HTML
    run.manifest = dataclasses.replace(  # a redraw's
        run.manifest, report_files=report.manifest_entries(run.path)[REPORT_FILES])
    return report


def _run_facts(run: RunData) -> list[tuple[str, str]]:
    m, c = run.manifest, run.config
    versions = ", ".join(f"{k} {'not installed' if v is None else v}"
                         for k, v in (m.versions or {}).items())
    sweep = "; ".join(f"{k} = {', '.join(map(str, v))}" for k, v in run.sweep.items())
    return [
        ("experiment", f"{c['experiment']}: {c.get('title', '')}"),
        ("config", m.config_file or ""),
        ("command", " ".join(m.command or [])),
        ("sweep", sweep or "none (one point)"),
        ("trials", f"{_per_point_text(run)}, {m.trials_total} in all, "
                   f"{m.trials_failed or 0} failed{_first_failure_text(run)}"),
        ("root seed", str(c.get("seed"))),
        ("run id", m.run_id or run.path.name),
        ("code", _code_text(m)),
        ("versions", versions),
        ("CPU", "; ".join(map(cpu_words, recorded_cpus(m.cpu))) or "not recorded"),
        ("started", m.first_started or m.started or ""),
        # the runner writes the report before it records the finishing time
        *([("finished", m.finished)] if m.finished else []),
    ]


def _per_point_text(run: RunData) -> str:
    """``50 per point``, or for a sequential run its rule, each point's count and the
    points stopped at ``max`` (from the manifest's ``sequential``)."""
    trials, record = run.config.get("trials"), run.manifest.sequential
    if not isinstance(trials, dict) or not isinstance(record, dict):
        return f"{trials} per point"
    until = trials.get("until") or {}
    at_max = record.get("stopped_at_max") or []
    return (f"sequential, until the 95 % interval of {until.get('metric')} is within "
            f"+-{until.get('half_width')} in every cell ({trials.get('min')} to "
            f"{trials.get('max')} per point, looks at {record.get('looks')}): per point "
            f"{record.get('trials')}; stopped at max without meeting it: "
            + (f"points {at_max}" if at_max else "none"))


def _first_failure_text(run: RunData) -> str:
    """``; first: point 0 (...), trial 0: ValueError: ...`` for a run with failed trials."""
    if not run.manifest.trials_failed:
        return ""
    first = first_failure(run.trials, swept_keys(run.config))
    return f"; first: {first}" if first else ""


def _code_text(manifest: Manifest) -> str:
    git = manifest.git or {}
    where = (f"{git.get('repository')} at {git.get('commit')}"
             + (" with uncommitted changes" if git.get("dirty") else "")) if git \
        else "not run from a git checkout"
    code = manifest.code_fingerprint or {}
    return f"{where}; code fingerprint {str(code.get('sha256', ''))[:12]}"


def _captions(run: RunData) -> dict[str, str]:
    return {name: spec.caption for name, spec in run.experiment.figures.items()}


def _figure_names(report: Report) -> list[str]:
    return list(dict.fromkeys(p.stem for p in report.figures))


#: Figure formats a browser shows as an image, best first; a figure written in none of them
#: (``outputs.formats: [pdf]``) is linked, not shown.
SHOWN_FORMATS = ("png", "svg")


def _figure_link(report: Report, name: str) -> tuple[str, bool]:
    """``(path relative to the run folder, shown as an image?)`` of figure ``name``."""
    written = {p.suffix.lstrip("."): p for p in report.figures if p.stem == name}
    fmt = next((f for f in SHOWN_FORMATS if f in written), None) or next(iter(written))
    return f"figures/{written[fmt].name}", fmt in SHOWN_FORMATS


def _headline_cells(table: pd.DataFrame, report: Report, link: bool) -> list[list[str]]:
    """The headline rows in a reader's words (:func:`~trackfuse.reportkit.headline.reader_cells`),
    the reason last, followed, when ``link``, by an HTML link to its section of the notes."""
    rows = []
    for _, row in table.iterrows():
        cells = reader_cells(row)
        href = note_href(str(row.get("docs", "")), report.note_pages)
        if link:
            cells[-1] = html.escape(cells[-1]) + (
                f" (<a href='{html.escape(href)}'>more</a>)" if href else "")
        elif href:
            cells[-1] += f" ([more]({href}))"
        rows.append(cells)
    return rows


def index_markdown(run: RunData, tables: dict[str, pd.DataFrame], report: Report) -> str:
    """The report as Markdown: paper against run, what was run, figures, other tables (long ones
    linked), then what was not drawn and the files.
    """
    esc = md_text
    lines = [f"# {esc(run.config.get('title') or run.config['experiment'])}", ""]
    headline, others = _split_tables(tables)
    for name in headline:
        lines += ["## Paper against reproduced", "",
                  "| " + " | ".join(READER_HEADERS) + " |",
                  "|" + "|".join("---" for _ in READER_HEADERS) + "|"]
        lines += ["| " + " | ".join(esc(c).replace("|", "\\|") for c in cells) + " |"
                  for cells in _headline_cells(tables[name], report, link=False)] + [""]
    lines += ["## Run", ""] + [f"- **{k}**: {esc(v)}" for k, v in _run_facts(run)] + [""]
    captions = _captions(run)
    for name in _figure_names(report):
        path, shown = _figure_link(report, name)
        lines += [f"## Figure: {esc(name)}", "", f"![{esc(name)}]({path})" if shown else
                  f"[{esc(name)}]({path})", "", esc(captions.get(name, "")), ""]
    for name in others:
        rows = len(tables[name])
        lines += [f"## Table: {esc(name)}", "", markdown_table(display_table(tables[name]))
                  if rows <= FOLDED_TABLE_ROWS else  # Markdown cannot fold it: a link
                  f"{rows} rows: [tables/{name}.md](tables/{name}.md) (also "
                  f"[tables/{name}.csv](tables/{name}.csv))", ""]
    for heading, reasons in (("Not drawn", report.not_drawn),
                             ("Not tabulated", report.not_tabulated)):
        if reasons:
            lines += [f"## {heading}", ""] + [f"- {esc(n)}: {esc(why)}"
                                              for n, why in reasons.items()]
            lines += [""]
    if report.errors:
        lines += ["## Problems", ""] + [f"- {esc(e)}" for e in report.errors] + [""]
    lines += ["## Files", ""] + [f"- `{f}`: {esc(d)}" for f, d in _file_list(run, report)]
    return "\n".join(lines) + "\n"


def _split_tables(tables: dict[str, pd.DataFrame]) -> tuple[list[str], list[str]]:
    """``(headline, others)``: the paper-vs-reproduced table goes before the figures, every
    other table (per-point detail) after them, in the report module's order."""
    headline = [n for n in tables if n == HEADLINE_TABLE]
    return headline, [n for n in tables if n != HEADLINE_TABLE]


def _file_list(run: RunData, report: Report) -> list[tuple[str, str]]:
    """The run folder's files with a few words each (a figure's caption is with the figure:
    each file of it is named by its format)."""
    files = [(f, d) for f, d in FILES.items() if (run.path / f).exists() or f.startswith("index")]
    files += [(f"tables/{p.name}", "report table") for p in report.tables]
    files += [(f"figures/{p.name}", FIGURE_FILES.get(p.suffix, "figure"))
              for p in report.figures]
    files += [(f"{NOTES}/{p.name}", "the notes on the paper, which the reasons link to")
              for p in report.notes]
    return files


_CSS = ("body{font-family:sans-serif;max-width:70em;margin:2em auto;padding:0 1em;"
        "line-height:1.4}" + TABLE_CSS + "img{max-width:100%}figure{margin:2em 0}"
        "dt{font-weight:bold;float:left;width:8em}dd{margin-left:9em}")


def _contents(run: RunData, tables: dict[str, pd.DataFrame], report: Report) -> str:
    """The page's table of contents: the paper table, the run, each figure and table."""
    esc = html.escape
    headline, others = _split_tables(tables)
    items = [("paper", "Paper against reproduced")] if headline else []
    items += [("run", "Run: config, seed, code, machine")]
    items += [(f"figure-{n}", f"Figure: {n}") for n in _figure_names(report)]
    items += [(f"table-{n}", f"Table: {n}") for n in others]
    items += [(h.lower().replace(" ", "-"), h) for h, r in (
        ("Not drawn", report.not_drawn), ("Not tabulated", report.not_tabulated),
        ("Problems", report.errors)) if r]
    items += [("files", "Files")]
    return ("<h2 id='contents'>Contents</h2><ul>" + "".join(
        f"<li><a href='#{esc(a)}'>{esc(t)}</a></li>" for a, t in items) + "</ul>")


def index_html(run: RunData, tables: dict[str, pd.DataFrame], report: Report) -> str:
    """The run's report as one HTML page (no JavaScript; images beside it): the paper
    against this run first, a table of contents, then the run, figures and tables."""
    esc = html.escape
    title = esc(str(run.config.get("title") or run.config["experiment"]))
    parts = [f"<!DOCTYPE html><html lang='en'><head><meta charset='utf-8'><title>{title}"
             f"</title><style>{_CSS}</style></head><body><h1>{title}</h1>"]
    headline, others = _split_tables(tables)
    parts += ["<h2 id='paper'>Paper against reproduced</h2>" + html_table(
        READER_HEADERS, _headline_cells(tables[name], report, link=True),
        raw=[len(READER_HEADERS) - 1]) for name in headline]
    parts.append(_contents(run, tables, report))
    parts.append("<h2 id='run'>Run</h2><dl>" + "".join(
        f"<dt>{esc(k)}</dt><dd>{esc(v)}</dd>" for k, v in _run_facts(run)) + "</dl>")
    captions = _captions(run)
    for name in _figure_names(report):
        path, shown = _figure_link(report, name)
        body = (f"<img src='{esc(path)}' alt='{esc(name)}'>" if shown
                else f"<a href='{esc(path)}'>{esc(path)}</a>")
        parts.append(f"<figure id='figure-{esc(name)}'>{body}"
                     f"<figcaption><b>{esc(name)}</b>: {esc(captions.get(name, ''))}"
                     "</figcaption></figure>")
    parts += [_table_part(name, tables[name]) for name in others]
    for heading, reasons in (("Not drawn", report.not_drawn),
                             ("Not tabulated", report.not_tabulated)):
        if reasons:
            parts.append(f"<h2 id='{heading.lower().replace(' ', '-')}'>{heading}</h2><ul>"
                         + "".join(f"<li>{esc(n)}: {esc(why)}</li>"
                                   for n, why in reasons.items()) + "</ul>")
    if report.errors:
        parts.append("<h2 id='problems'>Problems</h2><ul>"
                     + "".join(f"<li>{esc(e)}</li>" for e in report.errors) + "</ul>")
    parts.append("<h2 id='files'>Files</h2><ul>" + "".join(
        f"<li><code>{esc(f)}</code>: {esc(d)}</li>" for f, d in _file_list(run, report))
        + "</ul></body></html>")
    return "\n".join(parts) + "\n"


def _table_part(name: str, table: pd.DataFrame) -> str:
    """A table of the page under its heading; folded (closed) when it is long."""
    esc = html.escape
    rows = len(table)
    if rows > FOLDED_TABLE_ROWS:
        return (f"<details id='table-{esc(name)}'><summary><h2 style='display:inline'>Table: "
                f"{esc(name)}</h2> ({rows} rows; also <a href='tables/{esc(name)}.csv'>tables/"
                f"{esc(name)}.csv</a>)</summary>{_html_table(table)}</details>")
    return f"<h2 id='table-{esc(name)}'>Table: {esc(name)}</h2>" + _html_table(table)


def _html_table(table: pd.DataFrame) -> str:
    return frame_html(display_table(table))
