"""The reproduce report (trackfuse/reproduction.py): one section per paper with verdicts,
main figures beside the paper's claims, and a page a browser loads with every image."""

from __future__ import annotations

import pytest
from browser import chromium, decoded_images

from trackfuse.config import load
from trackfuse.harness import run_data
from trackfuse.reported import Paper, Reported
from trackfuse.reproduction import REPORT_HTML, REPORT_MD, collect, write_reproduction_report
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


@pytest.mark.skipif(chromium() is None, reason="no Chromium on this machine (.ci/run "
                    "installs Debian's chromium package)")
def test_the_report_page_loads_in_a_browser_with_every_image_decoded(runs, tmp_path):
    root, folders = runs
    page = write_reproduction_report(folders, root, TOY_PAPER)
    assert page == root / REPORT_HTML
    images = decoded_images(page, tmp_path / "report.png")
    assert len(images) == 1 and all(ok for _, ok in images)
