"""The run report (trackfuse/reports.py): display of intervals, figures not drawn, and the
page as a browser shows it."""

from __future__ import annotations

import ast
import dataclasses
import errno
import os
import subprocess
import sys
from pathlib import Path

import pandas as pd
import pytest
import toy_report
from browser import broken_links, chromium, decoded_images
from PIL import Image

from trackfuse import reports
from trackfuse.harness import run_data
from trackfuse.reportkit.style import RC
from trackfuse.reports import (
    VERDICTS,
    display_table,
    headline_row,
    write_report,
)

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def toy_run(tmp_path_factory):
    return run_data(tmp_path_factory.mktemp("reports"), "toy_gaussian",
                    sweep={"mu": [0.0, 1.0]}, trials=20, seed=4)


def _facts(index_md: Path) -> str:
    """The run facts of an ``index.md``: its ``## Run`` section."""
    return index_md.read_text().split("\n## Run\n")[1].split("\n## ")[0]


def test_each_interval_pair_becomes_one_column_after_its_estimate():
    table = pd.DataFrame({"algorithm": ["a"], "rmse_km": [1.23456], "rmse_km_ci_low": [1.0],
                          "rmse_km_ci_high": [1.5], "lost_pct": [2.0],
                          "lost_pct_ci_low": [0.5], "lost_pct_ci_high": [7.25]})
    shown = display_table(table)
    assert list(shown.columns) == ["algorithm", "rmse_km", "rmse_km 95 % CI", "lost_pct",
                                   "lost_pct 95 % CI"]
    assert shown.loc[0, "lost_pct 95 % CI"] == "0.500\u20137.25"  # three significant figures


def test_a_headline_row_shows_the_papers_value_as_printed_and_no_interval_of_an_exact_one():
    """ESM's Table 1 row read 'paper 0.05937, ours 0.05937 [0.05937, 0.05937], differs'
    (the paper prints 0.059375; ours is 0.0593688, exact) and its trials '<NA>'."""
    row = headline_row("Table 1", "CI", "", 0.059375, 0.0593688, float("nan"), float("nan"),
                       "1", None, "differs", "exact 0.0593688 is not 0.059375", "docs",
                       claim="AHP CI")
    table = pd.DataFrame([row, headline_row("Fig. 2", "rate", "a", 0.8959186, 0.9, 0.8, 0.95,
                                            "1", 50, "agrees", "", "docs", claim="rate")],
                         columns=reports.HEADLINE_COLUMNS).astype({"trials": "Int64"})
    shown = display_table(table)
    assert shown["paper_value"].tolist() == ["0.059375", "0.8959"]
    assert shown.loc[0, "95 % CI"] == "" and shown.loc[1, "95 % CI"] == "0.800\u20130.950"
    first = reports.markdown_table(shown).splitlines()[2].split(" | ")
    assert first[3:8] == ["0.059375", "0.0594", "", "1", ""]  # paper, ours, CI, unit, trials


def test_the_report_prepares_its_module_once_before_it_draws(toy_run):
    toy_report.PREPARED.clear()
    write_report(toy_run)
    assert [toy_run.path] == toy_report.PREPARED


def test_loading_ahead_runs_no_experiment_code():
    """What the runner loads while its workers compute: libraries only, never a report
    module (report code belongs to the report step)."""
    code = ("import sys\n"
            "from trackfuse.reports import load_drawing\n"
            "load_drawing(['png'])\n"
            "print(sorted(m for m in sys.modules if m.startswith('trackfuse.experiments.')"
            " and m != 'trackfuse.experiments.base'), 'matplotlib' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.strip()
    assert out == "[] True"


def test_a_wanted_figure_the_report_cannot_draw_is_listed_with_its_reason(toy_run):
    report = write_report(toy_run, wanted=["estimate", "not_a_figure_of_this_run"])
    assert [p.name for p in report.figures] == ["estimate.png", "estimate.pdf"]
    assert list(report.not_drawn) == ["not_a_figure_of_this_run"]
    assert "## Not drawn" in (toy_run.path / "index.md").read_text()
    assert "Not drawn" in (toy_run.path / "index.html").read_text()


def test_the_report_draws_by_default_what_the_config_asks_for_in_its_order(toy_run):
    """``wanted_figures`` is the one choice of figures (the reproduce report reads it too):
    ``all`` means every declared figure, a list is kept as given, unknown names included."""
    listed = dataclasses.replace(toy_run, config={
        **toy_run.config, "outputs": {**toy_run.config.get("outputs", {}),
                                      "figures": ["not_a_figure_of_this_run", "estimate"]}})
    assert reports.wanted_figures(listed) == ["not_a_figure_of_this_run", "estimate"]
    report = write_report(listed)
    assert [p.stem for p in report.figures] == ["estimate", "estimate"]
    assert list(report.not_drawn) == ["not_a_figure_of_this_run"]
    every = dataclasses.replace(toy_run, config={
        **toy_run.config, "outputs": {**toy_run.config.get("outputs", {}), "figures": "all"}})
    assert reports.wanted_figures(every) == list(toy_run.experiment.figures) == ["estimate"]
    assert write_report(every).not_drawn == {}


@pytest.mark.parametrize(("formats", "shown", "linked"), [
    (["pdf"], "", "figures/estimate.pdf"), (["svg", "pdf"], "figures/estimate.svg", ""),
    (["pdf", "png"], "figures/estimate.png", "")])
def test_the_index_shows_a_figure_in_a_format_that_was_written(toy_run, formats, shown,
                                                               linked):
    """With `outputs.formats: [pdf]` both index pages embedded figures/*.png, which did not
    exist: every image of the report was broken."""
    write_report(toy_run, formats=formats)
    markdown = (toy_run.path / "index.md").read_text()
    page = (toy_run.path / "index.html").read_text()
    if shown:
        assert f"![estimate]({shown})" in markdown and f"<img src='{shown}'" in page
    else:
        assert "![" not in markdown and "<img" not in page
        assert f"[estimate]({linked})" in markdown and f"<a href='{linked}'>" in page
    assert (toy_run.path / (shown or linked)).exists()
    write_report(toy_run)  # the other tests read the default report


def test_a_full_disk_while_saving_a_figure_stops_the_report_before_its_index(toy_run,
                                                                          monkeypatch):
    """A full disk was recorded as one figure's fault ('Not drawn: OSError [Errno 28]') and
    an index was written beside the missing figures, as if the report were complete."""
    for index in ("index.html", "index.md"):
        (toy_run.path / index).unlink(missing_ok=True)

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(reports, "save_figure", full)
    with pytest.raises(OSError, match="No space left"):
        write_report(toy_run)
    assert not (toy_run.path / "index.html").exists()
    monkeypatch.undo()
    write_report(toy_run)  # the other tests read the default report


def test_the_index_written_while_the_run_finishes_prints_no_none(toy_run):
    """The runner writes the report before it marks the run complete, so its manifest has
    no finishing time yet; a package that is not installed has no version. Neither may be
    printed as the word None."""
    m = toy_run.manifest
    running = dataclasses.replace(toy_run, manifest=dataclasses.replace(
        m, finished=None, versions={**m.versions, "stonesoup": None}))
    write_report(running)
    facts = _facts(toy_run.path / "index.md")
    assert "None" not in facts
    assert f"**started**: {m.started}" in facts and "stonesoup not installed" in facts


def test_the_headline_table_shows_its_interval_as_one_column(toy_run):
    write_report(toy_run)
    text = (toy_run.path / "tables" / "paper_vs_reproduced.md").read_text()
    assert "ci_low" not in text.splitlines()[0] and "95 % CI" in text.splitlines()[0]
    csv = pd.read_csv(toy_run.path / "tables" / "paper_vs_reproduced.csv")
    assert {"ci_low", "ci_high"} <= set(csv.columns)


@pytest.mark.slow
@pytest.mark.skipif(chromium() is None, reason="no Chromium on this machine (.ci/run "
                    "installs Debian's chromium package)")
def test_the_run_page_loads_in_a_browser_with_every_image_decoded_and_link_resolving(
        toy_run, tmp_path):
    report = write_report(toy_run)
    shot = tmp_path / "index.png"
    images = decoded_images(toy_run.path / "index.html", shot)
    assert images == [("figures/estimate.png", True)]
    assert shot.stat().st_size > 10_000
    # the contents, the reasons' links into the rendered note (its section lands), the note
    # back to the page
    assert report.notes == [toy_run.path / "notes" / "twin_sensor.html"]
    count, broken = broken_links(toy_run.path / "index.html")
    assert count >= 5 and not broken
    page = (toy_run.path / "index.html").read_text()
    assert "href='notes/twin_sensor.html#metrics'" in page
    assert broken_links(report.notes[0])[1] == []


@pytest.mark.slow
def test_figures_drawn_in_two_processes_are_the_bytes_drawn_in_one(tmp_path, monkeypatch):
    run = run_data(tmp_path, "twin_sensor", {"algorithms": ["mspda_parallel/mgekf"]},
                   sweep={"clutter.mean": [0.0, 9.0]}, trials=2, seed=1)
    monkeypatch.setattr(reports.threading, "active_count", lambda: 1)  # other tests' threads
    monkeypatch.setattr(reports.os, "sched_getaffinity", lambda pid: {0, 1})  # any host: 2
    assert reports.drawing_processes(6) == 2
    two = write_report(run)
    files = {p.name: p.read_bytes() for p in two.figures}
    monkeypatch.setattr(reports, "drawing_processes", lambda figures: 1)
    one = write_report(run)
    assert [p.name for p in one.figures] == [p.name for p in two.figures]
    assert len(files) >= 6 and one.not_drawn == two.not_drawn
    assert {p.name: p.read_bytes() for p in one.figures} == files


def test_a_table_without_rows_is_not_written_as_a_result(toy_run, monkeypatch):
    tables = toy_report.tables(toy_run)
    folder = toy_run.path / "tables"
    folder.mkdir(exist_ok=True)
    (folder / "empty.csv").write_text("stale result\n")  # left by an earlier drawing
    monkeypatch.setattr(toy_run, "manifest", dataclasses.replace(
        toy_run.manifest, report_files=["tables/empty.csv"]))
    monkeypatch.setattr(toy_report, "tables", lambda run: {
        **tables, "empty": pd.DataFrame(columns=["a", "b"]), "why": "nothing at the setting"})
    report = write_report(toy_run)
    names = {p.name for p in report.tables}
    assert "paper_vs_reproduced.csv" in names and not names & {"empty.csv", "why.csv"}
    assert not (folder / "empty.csv").exists() and not (folder / "why.md").exists()
    assert report.not_tabulated == {"empty": reports.NO_ROWS, "why": "nothing at the setting"}
    text = (toy_run.path / "index.md").read_text()
    assert "## Not tabulated" in text and "- why: nothing at the setting" in text
    assert "## Table: empty" not in text
    assert "Not tabulated" in (toy_run.path / "index.html").read_text()


def test_the_headline_table_comes_before_the_figures_and_detail_tables_after(toy_run,
                                                                             monkeypatch):
    """A reader sees the paper comparison, then the figures; long per-point tables come last,
    ``index.html`` folds them (a closed ``<details>`` linking the CSV) and ``index.md``
    links them."""
    tables = toy_report.tables(toy_run)
    long = pd.DataFrame({"point": range(reports.FOLDED_TABLE_ROWS + 1), "x": 1.5})
    short = pd.DataFrame({"point": [0], "x": [2.5]})
    monkeypatch.setattr(toy_report, "tables", lambda run: {"long_detail": long,
                                                           "short_detail": short, **tables})
    write_report(toy_run)
    md = (toy_run.path / "index.md").read_text()
    order = [md.index(h) for h in ("## Paper against reproduced", "## Figure: estimate",
                                   "## Table: long_detail", "## Table: short_detail")]
    assert order == sorted(order)
    # index.md links a long table (the orbit run's 1,346-row paired_loss made it 208 KB)
    assert "## Table: long_detail\n\n31 rows: [tables/long_detail.md](tables/long_detail.md)" \
        in md and "| 30 | 1.50 |" not in md and "| 0 | 2.50 |" in md
    assert (toy_run.path / "tables" / "long_detail.md").exists()
    page = (toy_run.path / "index.html").read_text()
    assert page.index("Paper against reproduced</h2>") < page.index("<h2 id='contents'>") \
        < page.index("<figure") < page.index(
        "<details id='table-long_detail'><summary><h2 style='display:inline'>Table: "
        "long_detail</h2> (31 rows; also <a href='tables/long_detail.csv'>") \
        < page.index("<h2 id='table-short_detail'>Table: short_detail</h2>")
    assert page.count("<details") == 1


def test_the_index_names_every_cpu_that_computed_the_run(toy_run):
    """docs/runner.md (run id): the last bits depend on the CPU, so the report says which."""
    m = toy_run.manifest
    older = {"model": "an older machine", "numpy_simd": [], "settings": {"OPENBLAS_CORETYPE":
                                                                        "Haswell"}}
    mixed = dataclasses.replace(toy_run, manifest=dataclasses.replace(m, cpu=[*m.cpu, older]))
    write_report(mixed)
    facts = _facts(toy_run.path / "index.md")
    here = m.cpu[0]
    assert f"**CPU**: {here['model']}, numpy {'/'.join(here['numpy_simd'])}, " \
           f"{'/'.join(here['blas'])}; an older machine, numpy baseline, " \
           "OPENBLAS_CORETYPE=Haswell" in facts
    write_report(toy_run)  # the other tests read the default report


def test_a_redraw_removes_what_it_no_longer_draws_and_names_the_failing_figure(
        toy_run, monkeypatch):
    """A figure or table that raised on a redraw left the earlier draw's file in place (the
    folder looked current) and was reported as `figures: KeyError: 'point'`."""
    write_report(toy_run)
    figures, tables = toy_run.path / "figures", toy_run.path / "tables"
    assert (figures / "estimate.png").exists() and (tables / "paper_vs_reproduced.csv").exists()

    def broken(*args):
        raise KeyError("point")

    monkeypatch.setattr(toy_report, "figures", broken)
    monkeypatch.setattr(toy_report, "tables", broken)
    report = write_report(toy_run)
    assert sorted(report.errors) == ["figure estimate: KeyError: 'point'",
                                     "tables: KeyError: 'point'"]
    assert not list(figures.glob("estimate.*")) and not list(tables.glob("*"))
    assert "figures/estimate" not in (toy_run.path / "index.md").read_text()
    monkeypatch.undo()
    write_report(toy_run)  # the other tests read the default report


def test_a_headline_row_refuses_a_verdict_that_is_not_one_of_the_four():
    row = headline_row("Fig. 1", "q", "a", "0.9", 1, 0, 2, "m", 3, "inconclusive", "r", "d",
                       claim="c")
    assert list(row) == list(reports.HEADLINE_COLUMNS) and row["reproduced"] == 1.0
    with pytest.raises(ValueError, match="verdict 'agree' is not one of"):
        headline_row("Fig. 1", "q", "a", "0.9", 1, 0, 2, "m", 3, "agree", "r", "d", claim="c")


def test_no_report_module_spells_a_verdict_out():
    """The verdicts are named through :data:`trackfuse.reports.VERDICTS` (``AGREES``, ...),
    so a typo is a ``NameError``, not a fifth verdict."""
    for path in sorted((ROOT / "trackfuse" / "experiments").glob("*/report.py")):
        words = [node.value for node in ast.walk(ast.parse(path.read_text()))
                 if isinstance(node, ast.Constant) and node.value in VERDICTS]
        assert not words, f"{path.relative_to(ROOT)} spells out {words}"


def test_every_figure_file_names_what_produced_it(toy_run):
    """A figure copied out of its run folder said nothing of its config, seed or run."""
    report = write_report(toy_run, wanted=["estimate"])
    png, pdf = report.figures
    source = Image.open(png).text["Source"]
    assert source == reports.provenance(toy_run)
    assert "seed 4" in source and "20 runs per point" in source
    assert toy_run.manifest.run_id in source
    assert source.encode() in pdf.read_bytes()  # the PDF's Subject, uncompressed


def test_text_a_figure_adds_after_its_axes_takes_the_house_sizes(toy_run, monkeypatch):
    """The toy report's legend (made after ``panels`` returned, as the esm and passive
    figures' legends and titles were) came out in matplotlib's 10 pt, not the house size."""
    sizes = []
    save = reports.save_figure

    def spy(fig, *args, **kwargs):
        legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes if ax.get_legend())]
        sizes.extend(t.get_fontsize() for legend in legends for t in legend.get_texts())
        return save(fig, *args, **kwargs)

    monkeypatch.setattr(reports, "save_figure", spy)
    monkeypatch.setattr(reports, "drawing_processes", lambda figures: 1)
    write_report(toy_run, wanted=["estimate"])
    assert sizes and set(sizes) == {RC["legend.fontsize"]}


def test_tables_of_the_wrong_type_are_a_report_error_not_a_traceback(toy_run, monkeypatch):
    """A plugin's tables() returning a list ended the run in a traceback, listed 'stopped'."""
    import toy_report
    monkeypatch.setattr(toy_report, "tables", lambda run: [pd.DataFrame({"a": [1]})])
    report = write_report(toy_run)
    assert report.errors == ["tables: returned list; expected a dict of table name to "
                             "DataFrame (or to a one-line reason it is empty)"]
    assert report.index is not None and report.figures


def test_index_md_shows_raw_html_from_titles_and_names_as_text(toy_run, monkeypatch):
    """index.html escaped them; index.md kept `<script>` from a title, a figure's reason
    or a table cell, which a Markdown viewer renders."""
    monkeypatch.setitem(toy_run.config, "title", "<script>alert(1)</script> & co")
    report = reports.Report(not_drawn={"<img src=x onerror=alert(2)>": "<b>why</b>"},
                            errors=["figure <i>x</i>: failed"])
    table = pd.DataFrame({"algorithm": ["<a href='http://example.com'>a</a>"], "n": [1.0]})
    md = reports.index_markdown(toy_run, {"<t>": table}, report)
    assert "<" not in md.replace("&lt;", "")
    for shown in ("# &lt;script&gt;alert(1)&lt;/script&gt; &amp; co",
                  "- &lt;img src=x onerror=alert(2)&gt;: &lt;b&gt;why&lt;/b&gt;",
                  "- figure &lt;i&gt;x&lt;/i&gt;: failed", "## Table: &lt;t&gt;",
                  "| &lt;a href='http://example.com'&gt;a&lt;/a&gt; | 1.00 |"):
        assert shown in md


def test_a_figure_is_laid_out_once_for_all_its_formats(tmp_path):
    """Constrained layout ran again for each format (PNG, then PDF), as costly as drawing;
    the later formats now keep the layout of the first."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(3.5, 2.0), layout="constrained")
    fig.add_subplot().set_xlabel("x (m)")
    engine = fig.get_layout_engine()
    calls = []
    execute = engine.execute
    engine.execute = lambda f: calls.append(f) or execute(f)
    written = reports.save_figure(fig, tmp_path, "f", ["png", "pdf", "svg"])
    assert [p.name for p in written] == ["f.png", "f.pdf", "f.svg"]
    assert all(p.stat().st_size > 0 for p in written) and len(calls) == 1


def test_drawing_processes_leave_the_inherited_objects_to_the_main_process(tmp_path,
                                                                          monkeypatch):
    """A forked drawing process's garbage collector never scans what it inherited (it
    only wrote to memory shared with the main process) and runs less often."""
    import gc

    run = run_data(tmp_path / "run", "toy_gaussian", sweep={"mu": [0.0, 1.0]}, trials=5,
                   seed=4)
    child, seen = reports._drawing_child, tmp_path / "children"
    seen.mkdir()

    def recording(main_pid: int) -> None:
        child(main_pid)
        (seen / str(os.getpid())).write_text(
            f"{gc.get_freeze_count()} {gc.get_threshold()[0]}")

    monkeypatch.setattr(reports, "_drawing_child", recording)
    monkeypatch.setattr(reports.threading, "active_count", lambda: 1)  # other tests' threads
    monkeypatch.setattr(reports.os, "sched_getaffinity", lambda pid: {0, 1})  # any host: 2
    assert reports.drawing_processes(6) == 2
    before = gc.get_freeze_count(), gc.get_threshold()  # another test may have frozen some
    write_report(run, wanted=["estimate", "estimate_vs_sigma"])  # two: drawn in forks
    states = [p.read_text().split() for p in seen.iterdir()]
    assert states and all(int(frozen) > before[0] for frozen, _ in states)
    assert all(int(threshold) == reports.DRAWING_GC_THRESHOLD for _, threshold in states)
    # the main process's own collector is left as it was (frozen objects may die, not grow)
    assert gc.get_freeze_count() <= before[0] and gc.get_threshold() == before[1]
