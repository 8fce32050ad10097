"""The reproduce report (trackfuse/reproduction.py): a bottom line with one verdict per paper
item, a table of contents, each main figure once beside the paper's claims, links to every
run's page and to the rendered notes, and a page a browser loads with every image decoded
and every link resolving."""

from __future__ import annotations

import pandas as pd
import pytest
from browser import broken_links, chromium, decoded_images

from trackfuse.config import load
from trackfuse.harness import run_data
from trackfuse.reported import ESM_RADAR, Answer, Beside, Paper, Reported
from trackfuse.reproduction import (
    REPORT_HTML,
    REPORT_MD,
    MainFigure,
    PaperSection,
    _claims,
    collect,
    main_figure_names,
    one_per_item,
    paper_claims,
    paper_item_names,
    write_reproduction_report,
)
from trackfuse.runner import Runner

TOY_PAPER = {"toy_gaussian": Paper("toy_gaussian", 'A. Author, "A toy paper", 2026', (
    Reported("Fig. 1", "coverage", 0.95, "fraction", 50, "the interval covers mu 95 % of "
             "the time", answer=Answer("paper", "mean")),), configs=("paper",))}
NEEDS_BROWSER = pytest.mark.skipif(chromium() is None, reason="no Chromium on this machine "
                                   "(.ci/run installs Debian's chromium package)")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("reproduce")
    folders = []
    for name, sigma in (("paper", 1.0), ("extension", 2.0)):
        config = root / f"{name}.yaml"
        config.write_text(f"experiment: toy_gaussian\ntrials: 30\nseed: 9\n"
                          f"params: {{sigma: {sigma}}}\n")
        outcome = Runner(load(config), root, executor="serial", progress=False).run()
        folders.append(outcome.folder)
    trivial = run_data(root, "toy_trivial", trials=3)
    return root, folders + [trivial.path]


def test_one_section_per_paper_with_every_configs_rows_and_one_figure_per_item(runs):
    root, folders = runs
    sections = collect(folders, TOY_PAPER)
    assert [s.key for s in sections] == ["toy_gaussian"]
    section = sections[0]
    # two algorithms; both configs give the same coverage (it does not depend on sigma), so
    # each row is listed once with both configs; no toy_trivial
    assert len(section.rows) == 2
    assert set(section.rows["config"]) == {"paper, extension"}
    assert [(f.config, f.paper_item) for f in section.figures] == [("paper", "Fig. 1")]
    assert [f.config for f in section.linked] == ["extension"]
    assert set(section.runs) == {"paper", "extension"}


def test_the_bottom_line_gives_one_verdict_from_the_declared_config(runs):
    root, folders = runs
    (line,) = collect(folders, TOY_PAPER)[0].lines()
    assert list(line.answering["config"]) == ["paper, extension"]
    assert list(line.answering["algorithm"]) == ["mean"]
    assert list(line.supporting["algorithm"]) == ["median"]
    assert line.verdict == line.answering["verdict"].iloc[0]


def test_a_comparison_that_several_configs_give_identically_is_listed_once(runs):
    root, folders = runs
    toy = TOY_PAPER["toy_gaussian"]
    paper = {"toy_gaussian": Paper(toy.key, toy.citation, toy.results, ("paper", "again"))}
    copy = root / "again.yaml"
    copy.write_text((root / "paper.yaml").read_text())
    again = Runner(load(copy), root, executor="serial", progress=False).run()
    section = collect([folders[0], again.folder], paper)[0]
    assert len(section.rows) == 2 and set(section.rows["config"]) == {"paper, again"}
    assert section.lines()[0].answering["config"].tolist() == ["paper, again"]


def test_the_markdown_starts_with_the_bottom_line_and_links_every_run(runs):
    root, folders = runs
    write_reproduction_report(folders, root, TOY_PAPER)
    text = (root / REPORT_MD).read_text()
    assert text.index("## Bottom line") < text.index("## A toy paper") < text.index("## Runs")
    row = next(line for line in text.splitlines() if line.startswith("| A toy paper | Fig. 1 |"))
    assert "the interval covers mu 95 %" in row and "| paper, mean |" in row
    assert "(notes/twin_sensor.html#metrics)" in row  # the reason's link to its note
    assert ("**agrees**" in row or "**differs**" in row)
    for name in ("paper", "extension"):
        link = next(line for line in text.splitlines() if line.startswith(f"- [{name}]("))
        assert (root / link.split("(")[1].rstrip(")")).name == "index.html"
        assert (root / link.split("(")[1].rstrip(")")).is_file()
    for line in text.splitlines():
        if line.startswith("!["):
            assert (root / line.split("(")[1].rstrip(")")).is_file()


def test_the_page_reads_bottom_line_contents_papers_runs(runs):
    root, folders = runs
    page = write_reproduction_report(folders, root, TOY_PAPER).read_text()
    order = [page.index(x) for x in ("id='bottom-line'", "id='contents'",
                                     "id='paper-toy_gaussian'", "id='runs'")]
    assert order == sorted(order)
    # the other verdicts on the item fold under its row; numbers sit in the house format
    assert "1 more verdict from other configs, methods or settings</summary>" in page
    assert "W000" not in page and "paper_vs_reproduced" not in page
    assert page.count("<img ") == 1  # each figure once


def test_a_paper_none_of_whose_configs_ran_gets_no_bottom_line_row_that_pretends(runs):
    root, folders = runs
    toy = TOY_PAPER["toy_gaussian"]
    item = Reported("Fig. 1", "coverage", 0.95, "fraction", 50, "covers",
                    answer=Answer("not-run"))
    paper = {"toy_gaussian": Paper(toy.key, toy.citation, (item,), ("not-run",))}
    (line,) = collect(folders, paper)[0].lines()
    assert line.verdict == "not comparable" and line.reason == "not-run was not run"


@pytest.mark.slow
@NEEDS_BROWSER
def test_the_report_page_loads_with_every_image_decoded_and_every_link_resolving(runs,
                                                                                 tmp_path):
    root, folders = runs
    page = write_reproduction_report(folders, root, TOY_PAPER)
    assert page == root / REPORT_HTML
    images = decoded_images(page, tmp_path / "report.png")
    assert len(images) == 1 and all(ok for _, ok in images)
    count, broken = broken_links(page)
    assert count >= 6 and not broken  # contents, runs, the note's section
    note = root / "notes" / "twin_sensor.html"
    count, broken = broken_links(note)
    assert count >= 2 and not broken  # back to the report, within the note


def test_a_paper_item_shows_every_claim_of_its_tables_and_figures():
    section = PaperSection(ESM_RADAR, _claims(ESM_RADAR), pd.DataFrame())
    text = paper_claims(section, "Table 3, Figs. 3-4")
    # Table 3 has several results, most without words: the words are not lost among them
    assert "Table 3: improved fuzzy comprehensive evaluation" in text
    assert "traditional multi-factor fuzzy decision" in text
    assert "Fig. 3: both methods degrade" in text and "Fig. 4: both decline" in text
    assert paper_item_names("Figs. 1-2, Abstract") == ["Fig. 1", "Fig. 2", "Abstract"]
    assert paper_claims(section, "Figs. 1-2").endswith("(the paper gives no number for it)")


def test_each_paper_item_shows_the_figure_of_the_config_that_answers_it(tmp_path):
    figures = [MainFigure(tmp_path / f"{c}.png", "", "Table 3", c)
               for c in ("esm_radar_separation", "esm_radar_snake_cross")]
    shown, linked = one_per_item(figures, ESM_RADAR)
    assert [f.config for f in shown] == ["esm_radar_snake_cross"]
    assert [f.config for f in linked] == ["esm_radar_separation"]


def test_another_config_is_shown_by_its_declared_main_figure():
    paper_items = {"loss_vs_clutter": "Fig. 1", "loss_vs_manoeuvring_index": "",
                   "range_error_vs_time": "Fig. 2", "final_range_rmse_vs_sweep": ""}
    drawn = {"loss_vs_manoeuvring_index", "range_error_vs_time", "final_range_rmse_vs_sweep"}
    declared = list(paper_items)
    # a config listing its main figure first is shown by it, not by a paper figure
    wanted = ["loss_vs_manoeuvring_index", "loss_vs_clutter", "range_error_vs_time"]
    assert main_figure_names(wanted, drawn, paper_items, own=False) == wanted[:1]
    # 'all': the first declared figure that was drawn
    assert main_figure_names(declared, drawn, paper_items, own=False) == [
        "loss_vs_manoeuvring_index"]
    # the paper's own config: every drawn paper figure, in the wanted order
    assert main_figure_names(declared, drawn, paper_items, own=True) == ["range_error_vs_time"]


def toy_beside(paper_run, analogue_run):
    """Two panels, one per run: each run's mean of ``estimate`` (a figure for the test)."""
    from matplotlib.figure import Figure
    fig = Figure(figsize=(7.16, 2.5))
    for ax, run in zip(fig.subplots(1, 2), (paper_run, analogue_run), strict=True):
        ax.bar([0], [run.summary["mean"].iloc[0]])
    return fig


def test_a_paper_figure_told_whole_is_drawn_and_shown_for_its_item(runs, tmp_path):
    """A paper whose figure is told whole (its scenario beside an analogue, paper 000's
    Fig. 1) shows that figure for the item, and links the paper config's own."""
    root, folders = runs
    paper = {"toy_gaussian": TOY_PAPER["toy_gaussian"].__class__(
        **{**vars(TOY_PAPER["toy_gaussian"]),
           "beside": Beside("Fig. 1", "paper", "extension", "test_reproduction:toy_beside")})}
    html_path = write_reproduction_report(folders, tmp_path, paper)
    assert (tmp_path / "figures" / "toy_gaussian_fig_1.png").exists()
    page = html_path.read_text()
    assert "figures/toy_gaussian_fig_1.png" in page and "paper + extension" in page
