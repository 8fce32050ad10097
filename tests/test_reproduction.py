"""The reproduce report (trackfuse/reproduction.py): one section per paper with verdicts,
main figures beside the paper's claims, and a page a browser loads with every image."""

from __future__ import annotations

import pandas as pd
import pytest
from browser import chromium, decoded_images

from trackfuse.config import load
from trackfuse.harness import run_data
from trackfuse.reported import ESM_RADAR, Paper, Reported
from trackfuse.reports import VERDICTS
from trackfuse.reproduction import (
    REPORT_HTML,
    REPORT_MD,
    PaperSection,
    _claims,
    _doc_link,
    _summary_line,
    collect,
    main_figure_names,
    paper_claims,
    paper_item_names,
    write_reproduction_report,
)
from trackfuse.runner import Runner

TOY_PAPER = {"toy_gaussian": Paper("toy_gaussian", "A. Author, a toy paper, 2026", (
    Reported("Fig. 1", "coverage", 0.95, "fraction", 50, "the interval covers mu 95 % of "
             "the time"),), configs=("paper",))}


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


def test_one_section_per_paper_with_every_headline_row_and_main_figure(runs):
    root, folders = runs
    sections = collect(folders, TOY_PAPER)
    assert [s.key for s in sections] == ["toy_gaussian"]
    section = sections[0]
    assert len(section.rows) == 2  # two algorithms of the paper's config; no toy_trivial
    assert sum(section.verdict_counts().values()) == 2
    assert sum(section.others["extension"].values()) == 2  # the other config: counts only
    assert [(f.config, f.paper_item) for f in section.figures] == [("paper", "Fig. 1")]
    assert [f.config for f in section.linked] == ["extension"]


def test_a_comparison_that_several_configs_give_identically_is_listed_once(runs):
    root, folders = runs
    toy = TOY_PAPER["toy_gaussian"]
    paper = {"toy_gaussian": Paper(toy.key, toy.citation, toy.results, ("paper", "again"))}
    copy = root / "again.yaml"
    copy.write_text((root / "paper.yaml").read_text())
    again = Runner(load(copy), root, executor="serial", progress=False).run()
    section = collect([folders[0], again.folder], paper)[0]
    assert len(section.rows) == 2 and set(section.rows["config"]) == {"paper, again"}


def test_the_markdown_names_paper_value_our_interval_and_verdict(runs):
    root, folders = runs
    write_reproduction_report(folders, root, TOY_PAPER)
    text = (root / REPORT_MD).read_text()
    assert "## toy_gaussian" in text and "2 paper items compared in the paper's own" in text
    assert "Other configs (their own index.html): extension: " in text
    row = next(line for line in text.splitlines() if line.startswith("| paper | Fig. 1"))
    assert "| 0.95 |" in row and "[" in row and ("**agrees**" in row or "**differs**" in row)
    assert "Paper: Fig. 1: the interval covers mu 95 % of the time" in text
    for line in text.splitlines():
        if line.startswith("!["):
            assert (root / line.split("(")[1].rstrip(")")).is_file()


def test_a_paper_none_of_whose_configs_ran_gets_no_empty_table(runs):
    """A reproduce of configs that are not the paper's own (configs/ci) printed a header-only
    table under "No paper item could be compared"."""
    root, folders = runs
    toy = TOY_PAPER["toy_gaussian"]
    paper = {"toy_gaussian": Paper(toy.key, toy.citation, toy.results, ("not-run",))}
    out = root / "none"
    out.mkdir()
    write_reproduction_report(folders, out, paper)
    text = (out / REPORT_MD).read_text()
    assert "No paper item could be compared" in text and "| config |" not in text
    assert "<table>" not in (out / REPORT_HTML).read_text()


@pytest.mark.slow
@pytest.mark.skipif(chromium() is None, reason="no Chromium on this machine (.ci/run "
                    "installs Debian's chromium package)")
def test_the_report_page_loads_in_a_browser_with_every_image_decoded(runs, tmp_path):
    root, folders = runs
    page = write_reproduction_report(folders, root, TOY_PAPER)
    assert page == root / REPORT_HTML
    images = decoded_images(page, tmp_path / "report.png")
    assert len(images) == 1 and all(ok for _, ok in images)


def test_a_paper_item_shows_every_claim_of_its_tables_and_figures():
    section = PaperSection("esm_radar", "", _claims(ESM_RADAR), pd.DataFrame())
    text = paper_claims(section, "Table 3, Figs. 3-4")
    # Table 3 has several results, most without words: the words are not lost among them
    assert "Table 3: improved fuzzy comprehensive evaluation" in text
    assert "traditional multi-factor fuzzy decision" in text
    assert "Fig. 3: both methods degrade" in text and "Fig. 4: both decline" in text
    assert paper_item_names("Figs. 1-2, Abstract") == ["Fig. 1", "Fig. 2", "Abstract"]
    assert paper_claims(section, "Figs. 1-2").endswith("(the paper gives no number for it)")


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


def test_doc_links_stay_valid_wherever_the_report_folder_is(tmp_path):
    checkout = tmp_path / "checkout"
    page = checkout / "guide" / "x.md"  # any page of the checkout (not a real docs page)
    page.parent.mkdir(parents=True)
    page.write_text("# x\n")
    inside, outside = checkout / "results" / "repro", tmp_path / "elsewhere" / "repro"
    link, text = _doc_link("guide/x.md#table-3", inside, [checkout])
    assert text == "guide/x.md#table-3"
    assert link == "../../guide/x.md#table-3"  # moves with the checkout
    link, _ = _doc_link("guide/x.md#table-3", outside, [checkout])
    assert link == f"{page.resolve()}#table-3"  # survives moving the report folder
    assert _doc_link("guide/missing.md", outside, [checkout]) == ("", "guide/missing.md")


def test_the_summary_counts_the_papers_methods_apart_from_ours():
    """The reproduce report said "10 agrees, 9 differs" for paper 002 when every "agrees"
    was one of our variants and every row of the paper's PGA differed."""
    rows = pd.DataFrame({"algorithm": ["pga_paper", "pga_evict", "pga_anneal", None, "exact"],
                         "verdict": ["differs", "agrees", "agrees", "differs", "differs"]})
    section = PaperSection("toy", "a paper", {}, rows)
    assert section.verdict_counts(ours=False) == {**dict.fromkeys(VERDICTS, 0), "differs": 3}
    assert _summary_line(section).startswith(
        "5 paper items compared in the paper's own configs: the paper's methods and claims "
        "3 differs; ours and other variants 2 agrees.")
