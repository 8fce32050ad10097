"""Registry of experiment kinds, looked up by name.

Built-ins are subpackages exposing ``EXPERIMENT``; a config may also name a plugin
``"package.module:ATTRIBUTE"`` or an entry point of :data:`ENTRY_POINT_GROUP` (built-in
names win). Plugin modules are read before they run and refused unless they do no work on
import (``docs/runner.md``, "Configs are code"); errors are one line (:class:`PluginError`).
"""

from __future__ import annotations

import ast
import difflib
import importlib
import importlib.metadata
import importlib.util
import re
import sys
from dataclasses import dataclass
from pathlib import Path

from trackfuse.coerce import one_line
from trackfuse.experiments.base import Experiment, Param

BUILTIN: dict[str, str] = {
    "twin_sensor": "trackfuse.experiments.twin_sensor",
    "esm_radar": "trackfuse.experiments.esm_radar",
    "passive_assoc": "trackfuse.experiments.passive_assoc",
    "passive_sd": "trackfuse.experiments.passive_sd",
}
ENTRY_POINT_GROUP = "trackfuse.experiments"
MAX_SOURCE_BYTES = 5_000_000
_MODULE_PATH = re.compile(r"^[A-Za-z_]\w*(\.[A-Za-z_]\w*)*$", re.ASCII)

_registered: dict[str, Experiment] = {}


class UnknownExperiment(KeyError):
    """Raised for a name that is neither built in, registered, nor ``module:attr``."""


class PluginError(ValueError):
    """A ``package.module:ATTRIBUTE`` reference that cannot be used; ``str(err)`` is one line."""


def register(experiment: Experiment) -> Experiment:
    """Register an experiment defined outside this package (e.g. in tests)."""
    _registered[experiment.name] = experiment
    return experiment


@dataclass(frozen=True)
class Listed:
    """One experiment as ``trackfuse list`` shows it, found without importing it: ``origin``
    (built-in, registered, or plugin with version) and ``reference`` (module or ``module:ATTR``).
    """

    name: str
    origin: str
    reference: str
    description: str


def _entry_points() -> dict[str, importlib.metadata.EntryPoint]:
    """Installed plugins by name (entry-point group :data:`ENTRY_POINT_GROUP`)."""
    found = importlib.metadata.entry_points(group=ENTRY_POINT_GROUP)
    return {ep.name: ep for ep in found if ep.name not in BUILTIN}


def names() -> list[str]:
    """Every experiment name a config may use (built-in first, then installed plugins and
    registered experiments)."""
    return list(BUILTIN) + sorted((set(_entry_points()) | set(_registered)) - set(BUILTIN))


def listing() -> list[Listed]:
    """Every named experiment, in :func:`names` order, without importing any of them."""
    plugins = _entry_points()
    found = []
    for name in names():
        if name in BUILTIN:
            found.append(Listed(name, "built-in", BUILTIN[name],
                                _docstring_summary(BUILTIN[name], name)))
        elif name in _registered:
            found.append(Listed(name, "registered", "", _registered[name].title))
        else:
            ep = plugins[name]
            dist = f" {ep.dist.name} {ep.dist.version}" if ep.dist is not None else ""
            found.append(Listed(name, f"plugin{dist}", ep.value, "(imported when used)"))
    return found


def _docstring_summary(module: str, name: str) -> str:
    """The summary (first paragraph, on one line) of ``module``'s docstring, read from its
    source without running it, without a closing ``(name)``: the listing names it."""
    try:
        spec = importlib.util.find_spec(module)
        with open(spec.origin, "rb") as fh:
            doc = ast.get_docstring(ast.parse(fh.read())) or ""
    except (OSError, SyntaxError, ValueError, TypeError, AttributeError, ImportError):
        return ""
    summary = " ".join(doc.strip().split("\n\n")[0].split()).replace("``", "").rstrip(".")
    return summary.removesuffix(f"({name})").rstrip()


def reference(experiment: Experiment) -> str:
    """What ``trackfuse list`` takes for ``experiment``: its known name, else ``module:ATTR``."""
    if experiment.name in names():
        return experiment.name
    module = sys.modules.get(getattr(experiment.run_trial, "__module__", ""))
    found = [k for k, v in vars(module).items() if v is experiment] if module else []
    return f"{module.__name__}:{found[0]}" if found else experiment.name


def report_problem(experiment: Experiment) -> str | None:
    """Why the report module cannot be imported (found without importing it), else ``None``: a run
    would otherwise find out after its last trial.
    """
    if not experiment.report:
        return None
    try:
        found = importlib.util.find_spec(experiment.report) is not None
    except (ImportError, ValueError):  # a parent package that is not there
        found = False
    return None if found else (f"the report module {experiment.report!r} of "
                               f"'{experiment.name}' is not on the Python path")


def get(name: str) -> Experiment:
    """The experiment called ``name``: built in, registered, an entry-point name or ``module:ATTR``.

    Raises :class:`UnknownExperiment` for an unknown plain name, :class:`PluginError` for a
    refused or failing plugin.
    """
    if name in _registered:
        return _registered[name]
    if name in BUILTIN:
        return importlib.import_module(BUILTIN[name]).EXPERIMENT
    if ":" in name:
        return _plugin(name)
    plugin = _entry_points().get(name)
    if plugin is not None:
        try:
            return _plugin(plugin.value)
        except PluginError as err:
            raise PluginError(f"entry point {name!r} ({ENTRY_POINT_GROUP}): {err}") from None
    raise UnknownExperiment(name)


def plugin_folder(ref: str) -> str | None:
    """The Python-path folder plugin ``ref`` was imported from, which ``plot`` and ``compare`` add
    to the path; ``None`` for built-in, registered or entry-point names.
    """
    module = sys.modules.get(ref.partition(":")[0]) if ":" in ref else None
    file = getattr(module, "__file__", None)
    if not file:
        return None
    folder = Path(file).resolve().parent
    depth = ref.partition(":")[0].count(".") + (Path(file).name == "__init__.py")
    return str(folder.parents[depth - 1] if depth else folder)


def add_plugin_folder(folder: str | Path) -> None:
    """Put ``folder`` at the end of the Python path (never in front: it shadows nothing),
    so a plugin module in it can be imported."""
    folder = str(folder)
    if folder not in sys.path:
        sys.path.append(folder)
        importlib.invalidate_caches()


def file_reference(ref: str) -> tuple[Path, str] | None:
    """``(folder, "module:ATTR")`` for ``path/to/module.py:ATTR`` naming an existing file, else
    ``None``."""
    file, _, attr = ref.rpartition(":")
    path = Path(file)
    if path.suffix != ".py" or not path.is_file() or not attr.isidentifier():
        return None
    return path.resolve().parent, f"{path.stem}:{attr}"


def _plugin(ref: str) -> Experiment:
    module, _, attr = ref.partition(":")
    where = f"cannot use {ref[:80]!r}"
    if module.endswith(".py"):  # a file name: Python read it as the package 'cvtrack'
        raise PluginError(f"{where}: name the module, not its file: "
                          f"{module.removesuffix('.py')}:{attr}")
    if not _MODULE_PATH.match(module) or not attr.isidentifier():
        raise PluginError(f"{where}: expected package.module:ATTRIBUTE with an absolute "
                          "module path and an attribute name")
    if "__main__" in module.split("."):
        raise PluginError(f"{where}: a __main__ module is a program's entry point; name the "
                          "module that defines the experiment")
    _check_source(module, attr, where)
    try:
        found = getattr(importlib.import_module(module), attr)
    except KeyboardInterrupt:
        raise
    except BaseException as err:  # noqa: BLE001 - SystemExit included: a config is code
        raise PluginError(f"{where}: importing {module} failed: {one_line(err)}") from None
    if not isinstance(found, Experiment):
        raise PluginError(f"{where}: {attr} is a {type(found).__name__}, not a "
                          "trackfuse Experiment")
    return found


def _check_source(module: str, attr: str, where: str) -> None:
    """Refuse ``module`` unless its source binds ``attr`` and does no work at import."""
    try:
        spec = importlib.util.find_spec(module)
    except KeyboardInterrupt:
        raise
    except BaseException as err:  # noqa: BLE001 - a parent package failed to import
        raise PluginError(f"{where}: cannot locate {module}: {one_line(err)}") from None
    if spec is None:
        raise PluginError(f"{where}: no module named {module!r} on the Python path (run "
                          "trackfuse from the folder that holds it, or add that folder to "
                          "PYTHONPATH)")
    origin = spec.origin if spec.has_location else None
    if origin is None or not origin.endswith(".py"):
        raise PluginError(f"{where}: {module} is not a Python source module")
    try:
        with open(origin, "rb") as fh:
            tree = ast.parse(fh.read(MAX_SOURCE_BYTES + 1), filename=origin)
    except (OSError, SyntaxError, ValueError) as err:
        raise PluginError(f"{where}: cannot read {module}: {one_line(err)}") from None
    defined = _top_level_names(tree.body)
    if attr not in defined:
        close = difflib.get_close_matches(attr, sorted(defined), n=1, cutoff=0.6)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise PluginError(f"{where}: {module} does not define {attr} at its top level{hint}")
    line = _first_bare_call(tree.body)
    if line is not None:
        raise PluginError(f"{where}: {module} runs code when imported (a call statement at "
                          f"line {line}); a plugin module may only import, define and assign")


def _top_level_names(body: list[ast.stmt]) -> set[str]:
    """Names bound by the statements of ``body`` (descending into if/try/with blocks)."""
    found: set[str] = set()
    for stmt in body:
        if isinstance(stmt, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            found.add(stmt.name)
        elif isinstance(stmt, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            targets = stmt.targets if isinstance(stmt, ast.Assign) else [stmt.target]
            for target in targets:
                found.update(n.id for n in ast.walk(target) if isinstance(n, ast.Name))
        elif isinstance(stmt, (ast.Import, ast.ImportFrom)):
            found.update((a.asname or a.name).split(".")[0] for a in stmt.names)
        for block in _blocks(stmt):
            found |= _top_level_names(block)
    return found


def _first_bare_call(body: list[ast.stmt]) -> int | None:
    """Line of the first call statement run at import, outside ``if __name__ == ...``."""
    for stmt in body:
        if isinstance(stmt, ast.Expr) and isinstance(stmt.value, (ast.Call, ast.Await)):
            return stmt.lineno
        if isinstance(stmt, ast.If) and "__name__" in ast.unparse(stmt.test):
            continue
        for block in _blocks(stmt):
            line = _first_bare_call(block)
            if line is not None:
                return line
    return None


def _blocks(stmt: ast.stmt) -> list[list[ast.stmt]]:
    """Statement lists run as part of ``stmt`` at module level (not function bodies)."""
    if isinstance(stmt, (ast.If, ast.For, ast.While)):
        return [stmt.body, stmt.orelse]
    if isinstance(stmt, ast.With):
        return [stmt.body]
    if isinstance(stmt, ast.Try):
        return [stmt.body, stmt.orelse, stmt.finalbody, *(h.body for h in stmt.handlers)]
    return []


__all__ = ["ENTRY_POINT_GROUP", "Experiment", "Listed", "Param", "PluginError",
           "UnknownExperiment", "get", "listing", "names", "register"]
