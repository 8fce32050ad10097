"""Docs that resolve: every weakness code and docs/ path cited in the code exists, the
README's and the docs' links resolve on GitHub and on the mkdocs site alike, every docs page
is in the site, the commands and configs the docs name exist, and the examples the docs
describe run."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from conftest import cli_env

from trackfuse import harness

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
CODE = [*ROOT.glob("trackfuse/**/*.py"), *ROOT.glob("cli/*.py"), *ROOT.glob("tests/*.py"),
        *ROOT.glob("examples/**/*.py"), ROOT / "README.md"]
PAPER_OF = {"0": "twin_sensor", "1": "esm_radar", "2": "passive_assoc"}
WEAKNESS = re.compile(r"\bW00(\d)-(\d+)\b")
DOC_PATH = re.compile(r"\bdocs/[\w/.-]+\.md\b")


def _cited(pattern: re.Pattern) -> dict[str, set[str]]:
    found: dict[str, set[str]] = {}
    for path in CODE:
        for match in pattern.finditer(path.read_text(encoding="utf-8")):
            found.setdefault(match.group(0), set()).add(str(path.relative_to(ROOT)))
    return found


def test_every_weakness_code_is_answered_by_its_paper_page():
    cited = _cited(WEAKNESS)
    assert cited, "no W-codes found: the pattern or the file list is wrong"
    missing = [f"{code} (cited in {', '.join(sorted(where))})"
               for code, where in sorted(cited.items())
               if code not in (DOCS / "papers" / f"{PAPER_OF[code[3]]}.md").read_text()]
    assert not missing, "\n".join(missing)


def test_every_docs_path_cited_exists():
    cited = _cited(DOC_PATH)
    assert cited
    missing = [f"{p} (cited in {', '.join(sorted(w))})" for p, w in sorted(cited.items())
               if not (ROOT / p).exists()]
    assert not missing, "\n".join(missing)


def test_nothing_cites_the_private_spec():
    spec = re.compile(r"\bSPEC\b")
    assert not [str(p) for p in CODE if spec.search(p.read_text(encoding="utf-8"))]


def _anchors(path: Path) -> set[str]:
    """The anchors of ``path``'s headings that GitHub and the docs site (mkdocs, Python-
    Markdown's toc) both give: a link must work in the repository and on the site alike."""
    found = set()
    for heading in re.findall(r"^#+ (.+)$", path.read_text(), flags=re.M):
        text = heading.strip().lower().replace("`", "")
        github = re.sub(r"[^\w\- ]", "", text).replace(" ", "-")
        site = re.sub(r"[-\s]+", "-", re.sub(r"[^\w\s-]", "", text).strip())
        if github == site:
            found.add(github)
    return found


LINKED = [ROOT / "README.md", *sorted(DOCS.rglob("*.md"))]


@pytest.mark.parametrize("page", LINKED, ids=lambda p: str(p.relative_to(ROOT)))
def test_links_between_docs_resolve(page):
    for target in re.findall(r"\]\(([^)]+)\)", page.read_text()):
        if target.startswith(("http://", "https://")):
            continue
        file, _, anchor = target.partition("#")
        path = (page.parent / file).resolve() if file else page
        assert path.exists(), f"{page.name}: {target}"
        if page.parent == DOCS or DOCS in page.parents:
            assert DOCS in path.parents, f"{page.name}: {target} is outside the docs site"
        if anchor and path.suffix == ".md":
            assert anchor in _anchors(path), f"{page.name}: {target}"


def test_every_docs_page_is_in_the_site_and_every_site_page_exists():
    site = yaml.safe_load((ROOT / "mkdocs.yml").read_text())
    assert site["docs_dir"] == "docs"

    def leaves(nav) -> list[str]:
        if isinstance(nav, str):
            return [nav]
        items = nav.values() if isinstance(nav, dict) else nav
        return [page for item in items for page in leaves(item)]

    in_nav = leaves(site["nav"])
    assert len(in_nav) == len(set(in_nav))
    assert set(in_nav) == {str(p.relative_to(DOCS)) for p in DOCS.rglob("*.md")}


def test_the_readme_fits_and_ci_runs_its_commands_verbatim():
    """The README is one short page whose first code block holds the two set-up commands;
    .ci/run runs the test command exactly as written there, and builds the site strictly."""
    readme = (ROOT / "README.md").read_text()
    assert len(readme.splitlines()) <= 200
    setup = re.search(r"```bash\n(.+?)\n```", readme, flags=re.S).group(1).splitlines()
    assert setup[0].startswith("pip install . && trackfuse run configs/")
    assert (ROOT / setup[0].split()[-1]).exists()
    ci = (ROOT / ".ci" / "run").read_text().splitlines()
    assert setup[1] == "pip install '.[test]' && pytest" and setup[1] in ci
    assert any(line.startswith("pytest -m slow") for line in ci)
    assert any("mkdocs build --strict" in line for line in ci)


def _code_lines() -> list[tuple[str, str]]:
    """(page, line) of every line inside a fenced code block of the README and the docs."""
    lines = []
    for page in LINKED:
        for block in re.findall(r"^```[\w]*\n(.*?)^```", page.read_text(), flags=re.M | re.S):
            lines += [(page.name, line) for line in block.splitlines()]
    return lines


def test_the_commands_in_the_docs_are_real_commands_and_options():
    """Every ``trackfuse SUBCOMMAND --option`` written in a code block of the README or the
    docs names a subcommand and options the command line has (a renamed option fails here)."""
    import typer.main

    from trackfuse_cli.main import app
    cli = typer.main.get_command(app)
    options = {name: {o for p in cmd.params for o in p.opts} for name, cmd in
               cli.commands.items()}
    options[""] = {o for p in cli.params for o in p.opts}
    checked, command = 0, None
    for page, line in _code_lines():
        words = line.split()
        if words[:1] == ["trackfuse"]:
            command = "" if len(words) < 2 or words[1].startswith("-") else words[1]
            assert command in options, f"{page}: {line}"
        elif not (line.startswith(" ") and words and words[0].startswith("[")):
            command = None  # not a continuation of a command's synopsis
        if command is None:
            continue
        for option in re.findall(r"(?<![\w-])--[a-z][\w-]*", line.split("#")[0]):
            assert option in options[command], f"{page}: trackfuse {command} {option}: {line}"
            checked += 1
    assert checked > 40


def test_every_config_the_docs_name_is_shipped():
    named = {m for page in LINKED for m in re.findall(r"\bconfigs/[\w/]+\.yaml", page.read_text())}
    assert len(named) > 20
    hypothetical = {"configs/x.yaml", "configs/my.yaml"}
    assert not [p for p in named - hypothetical if not (ROOT / p).exists()]


def test_the_docs_site_builds_strictly(tmp_path):
    """mkdocs (the ``docs`` extra) builds the site with no warning: a link or anchor between
    pages that does not resolve fails the build."""
    pytest.importorskip("mkdocs")
    proc = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir",
                           str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "site" / "statistics" / "index.html").exists()


def test_the_plugin_example_runs_through_the_cli(tmp_path):
    example = ROOT / "examples" / "plugin_example"
    env = cli_env()
    env["PYTHONPATH"] = f"{example}:{env['PYTHONPATH']}"
    proc = subprocess.run([sys.executable, "-m", "trackfuse", "run", "coin.yaml", "--out",
                           str(tmp_path), "--workers", "1", "--no-progress"], cwd=example,
                          env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    report = Path(proc.stdout.strip().splitlines()[-1].removeprefix("report: "))
    assert report.name == "index.html" and report.exists()
    # two figures declared as data, drawn by the report kit: the plugin has no matplotlib
    assert {p.name for p in (report.parent / "figures").iterdir()} == {"error.png",
                                                                    "coverage.png"}
    assert not any(re.search(r"^\s*(from|import) matplotlib", (example / name).read_text(), re.M)
                   for name in ("coin.py", "coin_report.py"))
    assert (report.parent / "tables" / "coverage.csv").exists()
    listed = subprocess.run([sys.executable, "-m", "trackfuse", "list", "coin:EXPERIMENT"],
                            cwd=example, env=env, capture_output=True, text=True, timeout=60)
    assert listed.returncode == 0 and "error" in listed.stdout and "tosses" in listed.stdout


def _example_on_a_small_run(tmp_path, config: str, example: str, trials: int = 20,
                            run_args: tuple[str, ...] = (),
                            example_args: tuple[str, ...] = ()) -> list[str]:
    """The output lines of ``examples/<example>`` on a ``trials``-trial run of
    ``configs/<config>`` (both must exit 0)."""
    env = cli_env()
    proc = subprocess.run([sys.executable, "-m", "trackfuse", "run", f"configs/{config}",
                           "--trials", str(trials), *run_args, "--out", str(tmp_path),
                           "--workers", "1", "--no-plots", "--no-progress"], cwd=ROOT,
                          env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    folder = re.search(r"^wrote (.+?): \d+ rows", proc.stdout, flags=re.M).group(1)
    proc = subprocess.run([sys.executable, f"examples/{example}", folder, *example_args],
                          cwd=ROOT, env=env, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return proc.stdout.splitlines()


@pytest.mark.slow
def test_the_esm_radar_spread_example_runs_on_a_run_folder(tmp_path):
    """examples/esm_radar_spread.py (docs/papers/esm_radar.md, W001-8) on a small run."""
    lines = _example_on_a_small_run(tmp_path, "esm_radar_baseline_spread.yaml",
                                    "esm_radar_spread.py")
    assert lines[0].startswith("correlation of the per-sample TDOA-DF range sd")
    assert len(lines) == 3 and all("of 20 trials change" in line for line in lines[1:])


@pytest.mark.slow
def test_the_esm_radar_cv_nis_example_runs_on_a_run_folder(tmp_path):
    """examples/esm_radar_cv_nis.py (docs/papers/esm_radar.md, W001-4) on a small run of the
    weave config: it recomputes the run's own index, and the weave raises every NIS."""
    lines = _example_on_a_small_run(tmp_path, "esm_radar_weave.yaml", "esm_radar_cv_nis.py")
    assert lines[0] == "point 0, straight flight, 20 trials:"
    means = [float(re.search(r"c dt ([\d.]+) \[", line).group(1)) for line in lines
             if "mean NIS" in line]
    assert len(means) == 8 and all(w > s for s, w in zip(means[:4], means[4:], strict=True))


@pytest.mark.slow
def test_the_interval_coverage_example_runs_on_a_run_folder(tmp_path):
    """examples/interval_coverage.py (docs/statistics.md) on 100 trials of the orbit
    config's nearest neighbour: all three measurements, one null comparison."""
    lines = _example_on_a_small_run(
        tmp_path, "twin_sensor_orbit.yaml", "interval_coverage.py", trials=100,
        run_args=("--set", "algorithms=[nn/mgekf,nn/ekf]"),
        example_args=("--replications", "20"))
    assert lines[0].startswith("population: 100 runs per level, twin_sensor seed 20051001")
    assert sum("report (bootstrap-t)" in line for line in lines) == 8
    assert sum("Wilson over 500 pairs covers" in line for line in lines) == 4
    assert re.fullmatch(r"3\. Null comparisons .*: \d of 1 flag .* in any of 3200 gated "
                        r"cells .*", lines[-1])


@pytest.mark.slow
def test_the_gap_coverage_example_measures_against_the_run_mean_gap(tmp_path):
    """examples/gap_coverage.py (docs/papers/passive_assoc.md, Metrics and intervals) on 40
    trials of two PGA variants: one line per N and variant, whose true value is the mean gap
    of the run's 40 trials at the variant's last checkpoint, and whose coverages are
    fractions of the 20 samples."""
    lines = _example_on_a_small_run(
        tmp_path, "passive_association.yaml", "gap_coverage.py", trials=40,
        run_args=("--set", "algorithms=[pga_paper,pga_evict]"),
        example_args=("--runs", "10", "--replications", "20"))
    assert lines[0] == ("population: 40-40 runs per point, passive_assoc seed 20080401; 20 "
                        "samples of 10 runs (nominal 0.95)")
    trials = pd.read_csv(next(tmp_path.rglob("trials.csv")))
    final = trials[trials["ops"] == 1000].groupby(["targets.n", "algorithm"])["gap"].mean()
    assert len(lines) == 1 + len(final) == 7
    for line in lines[1:]:
        n, algorithm, truth = re.match(r"  targets.n = (\d+), (\w+) at ops 1000: .* mean gap "
                                       r"(\S+);", line).groups()
        assert float(truth) == pytest.approx(final[int(n), algorithm], rel=1e-5, abs=1e-9)
        covers = re.findall(r"(?:bootstrap-t\)|percentile) ([\d.]+) \(s\.e\.", line)
        assert len(covers) == 2 and all(float(c) * 20 % 1 == 0 for c in covers), line


def test_the_gap_coverage_example_covers_a_normal_mean_at_the_nominal_level():
    """The coverage examples/gap_coverage.py measures is of the population mean: for a
    normal population both intervals cover it in 0.95 of 400 samples of 50, within 3 Monte
    Carlo standard errors (a wrong truth, swapped or misplaced bounds would miss by far)."""
    spec = importlib.util.spec_from_file_location("gap_coverage",
                                                  ROOT / "examples" / "gap_coverage.py")
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    population = np.random.default_rng(1).normal(10.0, 3.0, 5000)
    m = example.measure(population, 50, 400, np.random.default_rng(0))
    assert m["truth"] == population.mean() and m["report_intervals"].shape == (400, 2)
    for hits in (m["report"], m["percentile"]):
        assert abs(hits.mean() - 0.95) < 3 * np.sqrt(0.95 * 0.05 / 400)


@pytest.mark.slow
def test_the_first_update_example_prints_shift_and_formula():
    """examples/first_update_shift.py (docs/papers/twin_sensor.md, W000-3) on 200 trials."""
    proc = subprocess.run([sys.executable, "examples/first_update_shift.py", "--trials", "200",
                           "--only", "paper", "cue_2km"], cwd=ROOT, env=cli_env(),
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[1].startswith("paper: ") and lines[1].endswith("formula 2000 m")
    assert lines[2].startswith("cue_2km: ") and lines[2].endswith("formula 20 m")


@pytest.mark.slow
def test_the_first_update_example_pairs_a_runs_own_trials(tmp_path, monkeypatch):
    """``--run`` (the number docs/results.md quotes): the shift is the run's scan-1 mean minus the
    prior mean on the same trials, its paired interval far narrower than the scan-1 mean's
    (which carries the prior's spread); a run whose scan-1 errors are not the code's own
    is refused rather than paired with the wrong priors."""
    run = harness.run_data(tmp_path / "run", "twin_sensor",
                           {"algorithms": ["mspda_parallel/mgekf"]},
                           {"clutter.mean": [0.0, 3.0]}, trials=30, seed=5)

    def example(folder: Path) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "examples/first_update_shift.py", "--run",
                               str(folder)], cwd=ROOT, env=cli_env(), capture_output=True,
                              text=True, timeout=120)

    proc = example(run.path)
    assert proc.returncode == 0, proc.stderr
    assert "point 0 (clutter 0), 30 trials" in proc.stdout
    numbers = [[float(v) for v in m] for m in re.findall(
        r"(-?\d+) \[(-?\d+), (-?\d+)\] m", proc.stdout)]
    (shift, s_lo, s_hi), (scan1, c_lo, c_hi), (prior, _, _) = numbers
    assert abs(shift - (scan1 - prior)) <= 1.5  # each printed to the metre
    assert 3 * (s_hi - s_lo) < c_hi - c_lo
    spec = importlib.util.spec_from_file_location("first_update_shift",
                                                  ROOT / "examples" / "first_update_shift.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    shifted = run.trials.copy()  # trial 0's scan-1 error moved by 1 m: not the code's own
    shifted.loc[(shifted["scan"] == 1) & (shifted["trial"] == 0), "range_err_m"] += 1.0
    run.trials = shifted
    monkeypatch.setattr(module, "load", lambda folder: run)
    with pytest.raises(SystemExit, match="scan-1 errors"):
        module.run_shift(run.path)


def test_the_stonesoup_rounding_example_compares_two_numpy_settings():
    """examples/stonesoup_jacobian_rounding.py (docs/stonesoup.md): both child processes run
    and every line is printed (on a CPU without AVX-512 the two settings agree)."""
    pytest.importorskip("stonesoup")
    proc = subprocess.run([sys.executable, "examples/stonesoup_jacobian_rounding.py"],
                          cwd=ROOT, env=cli_env(), capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stdout.splitlines()
    assert lines[0].startswith("3000 states;") and len(lines) == 11
    assert lines[1].startswith("atan2: largest error") and lines[2].startswith("asin: ")
    assert lines[4].startswith("  x < 0: the settings differ in ")
    assert lines[7].startswith("  x >= 0: the settings differ in ")
    assert lines[-1].startswith("  the state of tests/test_stonesoup.py (x = -23.8 km)")
