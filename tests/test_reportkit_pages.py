"""The pieces every report page is built from: the notes rendered to HTML, the number format
and the table alignment (trackfuse/reportkit)."""

import re

import pytest

from trackfuse.reportkit.htmltable import html_table
from trackfuse.reportkit.notes import notes_folder, render_note, slug, write_notes
from trackfuse.reportkit.numberformat import sig3, with_interval


@pytest.mark.parametrize(("heading", "anchor"), [
    ("W001-2 radar TDOA and phase", "w001-2-radar-tdoa-and-phase"),
    ("Fig. 1: tracks lost against false returns", "fig-1-tracks-lost-against-false-returns"),
    ("Statistics: intervals, tests and what their 95 % means",
     "statistics-intervals-tests-and-what-their-95--means"),
    ("Interferometer spacing (`esm_radar_phase.yaml`, seed 20170104)",
     "interferometer-spacing-esm_radar_phaseyaml-seed-20170104"),
])
def test_headings_get_the_ids_github_gives_them(heading, anchor):
    assert slug(heading.replace("`", "")) == anchor
    page = render_note(f"# Title\n\n## {heading}\n\ntext\n", "t", set(), "../report.html")
    assert f'id="{anchor}"' in page


def test_a_repeated_heading_gets_a_numbered_id_and_foreign_links_lose_only_their_link():
    page = render_note("## Figures\n\n## Figures\n\nsee [the runner](../runner.md#x), "
                       "[other](other.md#y) and [here](#figures)\n", "t", {"other.md"}, "b")
    assert 'id="figures"' in page and 'id="figures-1"' in page
    assert "runner.md" not in page and "the runner" in page
    assert 'href="other.html#y"' in page and 'href="#figures"' in page


def test_every_note_ships_and_every_anchor_the_reports_link_to_lands(tmp_path):
    """The anchors the three experiments' headline rows link to, in their rendered notes."""
    assert notes_folder() is not None
    written = write_notes(tmp_path, "../report.html")
    assert set(written) >= {f"docs/papers/{n}.md" for n in ("twin_sensor", "esm_radar",
                                                            "passive_assoc")}
    assert set(written) == {f"docs/papers/{p.name}" for p in notes_folder().glob("*.md")}
    used = {"esm_radar": ["table-3", "table-1-ahp-weights", "fig-3-separation",
                          "fig-4-radar-range-error", "w001-2-radar-tdoa-and-phase"],
            "twin_sensor": ["fig-1-tracks-lost-against-false-returns",
                            "fig-2-range-error-against-time", "metrics"],
            "passive_assoc": ["fig-2", "w002-1-the-hungarian-method"]}
    for name, anchors in used.items():
        page = (tmp_path / "notes" / f"{name}.html").read_text()
        ids = set(re.findall(r'id="([^"]+)"', page))
        assert set(anchors) <= ids, (name, set(anchors) - ids)


@pytest.mark.parametrize(("value", "text"), [
    (74.0, "74.0"), (0.0593688, "0.0594"), (130, "130"), (1234.5, "1230"), (99.96, "100"),
    (-8.2, "\u22128.20"), (0, "0"), (5.2375, "5.24"), (0.000123456, "0.000123"),
])
def test_three_significant_figures(value, text):
    assert sig3(value) == text


def test_a_rate_and_a_difference_with_their_intervals():
    assert with_interval(0.74, 0.717, 0.792, "fraction") == "74.0 % (71.7\u201379.2)"
    assert with_interval(-0.012, -0.0734, 0.0495, "fraction difference") == \
        "\u22121.20 points (\u22127.34 to +4.95)"
    assert with_interval(5.2375, float("nan"), float("nan"), "1") == "5.24"


def test_prose_left_numbers_right():
    page = html_table(["method", "ours", "why"], [["PDA", "74.0 % (71.7\u201379.2)",
                                                    "a long reason in words"]])
    cells = re.findall(r"<td( class=num)?>", page)
    assert cells == ["", " class=num", ""]
