"""The house rules a reviewer would otherwise check by hand: imports flow one way, the runner
draws nothing, functions stay short, experiments declare what their reports draw."""

from __future__ import annotations

import ast
import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from trackfuse import experiments

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = {"trackfuse": ROOT / "trackfuse", "trackfuse_cli": ROOT / "cli"}
MAX_FUNCTION_LINES = 60


def _modules() -> dict[str, Path]:
    """Every module of the installed packages by dotted name."""
    found = {}
    for package, folder in PACKAGES.items():
        for path in sorted(folder.rglob("*.py")):
            parts = list(path.relative_to(folder).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            found[".".join([package, *parts])] = path
    return found


MODULES = _modules()


def _is_ours(name: str) -> bool:
    return name.split(".")[0] in ("trackfuse", "cli", "trackfuse_cli")


def _imported(node: ast.Import | ast.ImportFrom, module: str) -> list[str]:
    """Module names an import statement of ``module`` loads (ours only)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if _is_ours(a.name)]
    base = node.module or ""
    if node.level:
        package = module.rsplit(".", node.level)[0]
        base = f"{package}.{base}" if base else package
    if not _is_ours(base):
        return []
    return [f"{base}.{a.name}" if f"{base}.{a.name}" in MODULES else base for a in node.names]


def _function_level_imports(tree: ast.AST) -> list[tuple[int, str]]:
    out = []
    for fn in ast.walk(tree):
        if isinstance(fn, (ast.FunctionDef, ast.AsyncFunctionDef)):
            for node in ast.walk(fn):
                if isinstance(node, ast.Import | ast.ImportFrom):
                    names = [a.name for a in node.names] if isinstance(node, ast.Import) \
                        else [node.module or "."]
                    out += [(node.lineno, n) for n in names if _is_ours(n) or n == "."]
    return out


# Function-level imports allowed for start-up time, each with its reason: the twin-sensor
# kernel (the PDA's and IPDA's) and the nested clutter's arrival count import numba (about
# 0.5 s), which only a running batch needs; so does the compiled
# PGA loop, which only a running passive_assoc trial needs, and the S-D assignment's kernels
# (solver and tuple costs), which only a running passive_sd trial needs; the house style
# imports matplotlib (about 0.4 s), which only drawing needs (the runner imports reports).
LAZY_IMPORTS = {("trackfuse.experiments.twin_sensor.model",
                 "trackfuse.tracking.pda"),
                ("trackfuse.experiments.twin_sensor.model",
                 "trackfuse.tracking.ipda"),
                ("trackfuse.experiments.twin_sensor.model",
                 "trackfuse.tracking.nested_clutter"),
                ("trackfuse.experiments.passive_assoc.model",
                 "trackfuse.association.pga_search"),
                ("trackfuse.experiments.passive_sd.model",
                 "trackfuse.association.sd_assignment"),
                ("trackfuse.experiments.passive_sd.model",
                 "trackfuse.association.sd_costs"),
                ("trackfuse.reports", "trackfuse.reportkit.style")}


def test_no_function_level_import_between_our_modules():
    # The command line (trackfuse_cli) is exempt: its commands import the runner, pandas and
    # matplotlib when they run, so `--help`, `list` and `validate` start quickly.
    found = [f"{path.relative_to(ROOT)}:{line} imports {name}"
             for module, path in MODULES.items() if module.split(".")[0] == "trackfuse"
             for line, name in _function_level_imports(ast.parse(path.read_text()))
             if (module, name) not in LAZY_IMPORTS]
    assert not found, "\n".join(found)


def _graph() -> dict[str, set[str]]:
    graph = {}
    for module, path in MODULES.items():
        tree = ast.parse(path.read_text())
        edges: set[str] = set()
        for node in tree.body:
            nodes = [node]
            if isinstance(node, ast.If):  # TYPE_CHECKING blocks load nothing at run time
                nodes = [] if "TYPE_CHECKING" in ast.unparse(node.test) else node.body
            for n in nodes:
                if isinstance(n, ast.Import | ast.ImportFrom):
                    edges |= {m.replace("cli.", "trackfuse_cli.", 1) for m in _imported(n, module)}
        graph[module] = {e for e in edges if e in MODULES and e != module}
    return graph


def _cycle(graph: dict[str, set[str]]) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state and (found := visit(nxt)):
                return found
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (found := visit(node)):
            return found
    return None


def test_no_import_cycle():
    assert _cycle(_graph()) is None, " -> ".join(_cycle(_graph()) or [])


def test_the_cycle_finder_finds_a_cycle():
    assert _cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert _cycle({"a": {"b"}, "b": set()}) is None


def test_reports_import_the_science_never_the_reverse():
    graph = _graph()
    for name in experiments.BUILTIN:
        package = f"trackfuse.experiments.{name}"
        science = [m for m in graph if m.startswith(package) and not m.endswith(".report")]
        for module in science:
            assert f"{package}.report" not in graph[module], module
            assert not any(m.startswith("trackfuse.plots") for m in graph[module]), module


# The layers of the house, bottom first. A module may import its own group and any group of
# a lower layer; groups side by side in one layer import none of each other. A name ending
# in "." is a package prefix; "*" stands for any one experiment. Every module must be placed.
LAYERS: list[dict[str, tuple[str, ...]]] = [
    {"foundation": ("trackfuse", "trackfuse.coerce", "trackfuse.regular_files",
                    "trackfuse.safe_yaml", "trackfuse.chi2", "trackfuse.stats",
                    "trackfuse.sweep", "trackfuse.seeding", "trackfuse.spawned_streams",
                    "trackfuse.rowformat",
                    "trackfuse.sequential", "trackfuse.trial_guard", "trackfuse.progress",
                    "trackfuse.child_processes", "trackfuse.cluster_settings",
                    "trackfuse.forkserver_freeze", "trackfuse.shipped", "trackfuse.heap")},
    {"disk format": ("trackfuse.results", "trackfuse.manifest", "trackfuse.store",
                     "trackfuse.runlock",
                     "trackfuse.runstate", "trackfuse.runfiles", "trackfuse.catalog",
                     "trackfuse.summary", "trackfuse.failures"),
     "experiment contract": ("trackfuse.experiments", "trackfuse.experiments.base",
                             "trackfuse.rowtable", "trackfuse.trial_rows",
                             "trackfuse.reportkit.looks", "trackfuse.reportkit.spec"),
     "science": ("trackfuse.tracking.", "trackfuse.association.", "trackfuse.interop.",
                 "trackfuse.precompile")},
    {"experiments": ("trackfuse.experiments.*.",),
     "set-up": ("trackfuse.config", "trackfuse.fingerprint", "trackfuse.environment")},
    {"reports": ("trackfuse.experiments.*.report", "trackfuse.experiments.*.paper",
                 "trackfuse.experiments.*.tables", "trackfuse.reportkit.",
                 "trackfuse.reported", "trackfuse.rundata", "trackfuse.reports",
                 "trackfuse.reproduction", "trackfuse.compare")},
    {"runner": ("trackfuse.runner", "trackfuse.plan", "trackfuse.execution",
                "trackfuse.finish", "trackfuse.batch", "trackfuse.executors",
                "trackfuse.cluster", "trackfuse.harness")},
    {"command line": ("trackfuse_cli.", "trackfuse.__main__")},
]


def _pattern_fits(pattern: str, module: str) -> int:
    """How closely ``pattern`` names ``module`` (0: not at all; longer patterns win)."""
    regex = re.escape(pattern.rstrip(".")).replace(r"\*", r"[^.]+")
    regex += r"(\..+)?" if pattern.endswith(".") else ""
    return len(pattern) if re.fullmatch(regex, module) else 0


def _place(module: str, layers: list[dict[str, tuple[str, ...]]]) -> tuple[int, str] | None:
    """(layer, group) of ``module``: the group whose pattern names it most closely."""
    fits = [(_pattern_fits(p, module), level, group) for level, groups in enumerate(layers)
            for group, patterns in groups.items() for p in patterns]
    score, level, group = max(fits)
    return (level, group) if score else None


def _all_imports() -> dict[str, set[str]]:
    """Every import between our modules, wherever it stands (in a function, or only for
    type checking: a type named is a dependence too)."""
    graph = {}
    for module, path in MODULES.items():
        edges: set[str] = set()
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import | ast.ImportFrom):
                edges |= {m.replace("cli.", "trackfuse_cli.", 1) for m in _imported(node, module)}
        graph[module] = {e for e in edges if e in MODULES and e != module}
    return graph


def _layer_breaches(graph: dict[str, set[str]],
                    layers: list[dict[str, tuple[str, ...]]]) -> list[str]:
    """Each import that points up a layer or across to a side-by-side group, and each module
    placed in no group."""
    found = [f"{m}: in no layer" for m in sorted(graph) if _place(m, layers) is None]
    for module, imports in sorted(graph.items()):
        here = _place(module, layers)
        for imported in sorted(imports):
            there = _place(imported, layers)
            if here and there and (there[0] > here[0]
                                   or there[0] == here[0] and there[1] != here[1]):
                found.append(f"{module} ({here[1]}) imports {imported} ({there[1]})")
    return found


def test_imports_point_down_the_layers():
    assert not _layer_breaches(_all_imports(), LAYERS), "\n".join(
        _layer_breaches(_all_imports(), LAYERS))
    stale = [p for groups in LAYERS for patterns in groups.values() for p in patterns
             if not p.endswith(".") and "*" not in p and p not in MODULES]
    assert not stale, f"layers name modules that do not exist: {stale}"


def test_the_layer_check_finds_an_upward_and_a_sideways_import():
    layers = [{"low": ("p.a",)}, {"left": ("p.b.",), "right": ("p.*.c",)}, {"top": ("p.d",)}]
    graph = {"p.a": {"p.d"}, "p.b.x": {"p.a"}, "p.q.c": {"p.b.x"}, "p.d": {"p.q.c"},
             "p.e": set()}
    assert _layer_breaches(graph, layers) == [
        "p.e: in no layer", "p.a (low) imports p.d (top)",
        "p.q.c (right) imports p.b.x (left)"]


@pytest.mark.parametrize("module", ["trackfuse.runner", "trackfuse_cli.main",
                                    "trackfuse.experiments.twin_sensor",
                                    "trackfuse.experiments.esm_radar",
                                    "trackfuse.experiments.passive_assoc"])
def test_importing_loads_no_matplotlib(module):
    code = (f"import sys, {module}\n"
            "print(sorted(m for m in sys.modules if m.split('.')[0] == 'matplotlib'))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=ROOT).stdout.strip()
    assert out == "[]", out


def test_every_function_is_short():
    long = []
    for path in MODULES.values():
        rel = str(path.relative_to(ROOT))
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                lines = node.end_lineno - node.lineno + 1
                if lines > MAX_FUNCTION_LINES:
                    long.append(f"{rel}:{node.lineno} {node.name}: {lines} lines")
    assert not long, "\n".join(long)


@pytest.mark.parametrize("name", list(experiments.BUILTIN))
def test_experiments_declare_their_report(name):
    exp = experiments.get(name)
    assert exp.report == f"trackfuse.experiments.{name}.report"
    assert exp.figures and all(spec.caption for spec in exp.figures.values())
    names = [m.name for m in exp.metrics]
    assert len(names) == len(set(names)) and all(m.unit for m in exp.metrics)
    assert all(m.better in (None, "lower", "higher") for m in exp.metrics)
    assert exp.binary_metrics and set(exp.directions) <= set(names)


@pytest.mark.parametrize("name", list(experiments.BUILTIN))
def test_a_caption_holds_for_every_run_of_its_experiment(name):
    """Every run's report shows the same captions: the orbit run's read like a manual of
    other configs (twin_sensor_close's 0-150 axis, twin_sensor_baseline's 40 km point), up
    to 980 characters; what a config adds is said in its panels and docs/papers/."""
    configs = {p.stem for p in (ROOT / "configs").rglob("*.yaml")} | {"fig1_claim"}
    for figure, spec in experiments.get(name).figures.items():
        assert len(spec.caption) <= 400, (figure, len(spec.caption))
        assert not [c for c in configs if c in spec.caption], figure


@pytest.mark.parametrize("name", list(experiments.BUILTIN))
def test_schema_spells_units_one_way(name):
    for p in experiments.get(name).params:
        if p.kind in (int, float) and p.choices is None:
            assert p.unit and p.unit not in ("probability", "dimensionless"), p.key
            assert p.low is not None and p.high is not None, p.key
        if "probability" in p.doc.lower() and p.kind is float and p.unit == "1":
            assert 0.0 <= p.low <= p.high <= 1.0, p.key


#: Test files about the project as a whole rather than one module.
CROSS_CUTTING = {"structure", "docs", "packaging", "fault_matrix", "tamper_matrix"}


def test_every_test_file_names_the_module_it_tests():
    names = set()
    for module in MODULES:
        parts = module.split(".")[1:]
        names |= {parts[-1], "_".join(parts)} if parts else set()
    names -= {"__main__", "main", "model", "report"}
    strays = []
    for path in sorted(Path(__file__).parent.glob("test_*.py")):
        stem = path.stem.removeprefix("test_")
        if stem not in CROSS_CUTTING and not any(stem == n or stem.startswith(f"{n}_")
                                                 for n in names):
            strays.append(path.name)
    assert not strays, f"test files that map to no module: {strays}"


def test_every_benchmark_script_imports():
    """benchmarks/esm_radar_speed.py imported a name the experiment no longer exported and
    stopped before measuring anything; nothing ran it."""
    import runpy
    import sys
    folder = ROOT / "benchmarks"
    sys.path.insert(0, str(folder))  # a script's siblings, as when it is run
    try:
        for script in sorted(folder.glob("*.py")):
            runpy.run_path(str(script), run_name="imported_by_a_test")
    finally:
        sys.path.remove(str(folder))


# The test suite's own rules: `pytest` runs the fast suite quietly, the slow tests carry the
# registered `slow` marker, and no test is switched on or off by an environment variable.

def test_the_slow_marker_is_registered_and_the_default_run_is_quiet_and_strict():
    options = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["pytest"][
        "ini_options"]
    assert any(marker.startswith("slow:") for marker in options["markers"])
    assert set(options["addopts"].split()) >= {"-q", "--strict-markers"}


def test_no_test_is_gated_by_an_environment_variable():
    gate = re.compile(r"skip(?:if)?\([^)]*(?:os\.environ|os\.getenv)", re.S)
    gated = [path.name for path in sorted((ROOT / "tests").glob("test_*.py"))
             if gate.search(path.read_text(encoding="utf-8"))]
    assert not gated, gated
