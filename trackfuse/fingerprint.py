"""The code that produced a run's numbers, as one digest for the run id.

A run folder is reused only if its run id matches, so the id changes whenever the code that
computes the numbers does. :func:`code_fingerprint` hashes the source of the experiment's own
modules (those defining ``run_trial``/``run_batch`` and, transitively, what they import from
their own package or trackfuse) and of :data:`NUMBERS_PATH`, read with :mod:`ast` (nothing is
run). Report code is left out; library versions are covered by :mod:`trackfuse.environment`.
See ``docs/runner.md``, "Run id and code fingerprint".
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
import sys
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from importlib.machinery import ModuleSpec, PathFinder
from pathlib import Path

from trackfuse.experiments.base import Experiment

#: trackfuse modules every run's numbers pass through (trial seeding, batch execution,
#: CSV cells, summary statistics).
NUMBERS_PATH = ("trackfuse.seeding", "trackfuse.batch", "trackfuse.runner",
                "trackfuse.results", "trackfuse.rowformat", "trackfuse.summary",
                "trackfuse.stats")


@dataclass(frozen=True)
class CodeFingerprint:
    """``digest``: sha256 (hex) over ``modules``, the sorted module names that were hashed."""

    digest: str
    modules: tuple[str, ...]


def _spec(module: str) -> ModuleSpec | None:
    """Where ``module`` would be loaded from, found without importing it or its parents
    (``importlib.util.find_spec`` imports the parent package, and ``a.b.c`` for a name ``c``
    imported from module ``a.b`` would run ``a.b``, compiled kernel and all)."""
    parent, _, _ = module.rpartition(".")
    try:
        if not parent or module in sys.modules:
            return importlib.util.find_spec(module)
        outer = _spec(parent)
        if outer is None or outer.submodule_search_locations is None:
            return None  # the parent is not a package: ``module`` is a name inside it
        return PathFinder.find_spec(module, list(outer.submodule_search_locations))
    except (ImportError, ValueError):
        return None


def _source_file(module: str) -> Path | None:
    spec = _spec(module)
    if spec is None or not spec.origin or not spec.has_location:
        return None
    return Path(spec.origin)


def _imports(module: str, path: Path) -> set[str]:
    """Absolute names of the modules ``module`` (source at ``path``) imports, at any depth
    of its code (function-level imports included)."""
    try:
        tree = ast.parse(path.read_bytes())
    except (SyntaxError, ValueError, OSError):
        return set()
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found: set[str] = set()
    for node in _statements(tree.body):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                try:
                    base = importlib.util.resolve_name("." * node.level + base, package)
                except (ImportError, ValueError):
                    continue
            found.add(base)
            found.update(f"{base}.{alias.name}" for alias in node.names)  # submodules
    return found


def _statements(body: list[ast.AST]) -> Iterator[ast.AST]:
    """Every statement in ``body`` and in the bodies nested in it (functions, classes,
    branches, loops, ``try``, ``with``, ``match``): where an import can be, without walking
    the expressions, which hold none."""
    for node in body:
        yield node
        for field in ("body", "orelse", "finalbody", "handlers", "cases"):
            nested = getattr(node, field, None)
            if isinstance(nested, list):
                yield from _statements(nested)


def _closure(roots: Iterable[str], tops: set[str]) -> dict[str, Path]:
    """Every module reachable from ``roots`` through imports inside the packages ``tops``."""
    files: dict[str, Path] = {}
    todo = list(roots)
    while todo:
        module = todo.pop()
        if module in files or module.partition(".")[0] not in tops:
            continue
        path = _source_file(module)
        if path is None or not path.is_file():
            continue
        files[module] = path
        if path.suffix == ".py":
            todo.extend(_imports(module, path))
    return files


def code_fingerprint(experiment: Experiment) -> CodeFingerprint:
    """Fingerprint of the code that computes ``experiment``'s numbers (see module doc)."""
    roots = {f.__module__ for f in (experiment.run_trial, experiment.run_batch)
             if f is not None and getattr(f, "__module__", None)}
    tops = {"trackfuse"} | {r.partition(".")[0] for r in roots}
    files = _closure(roots, tops)
    files.update((m, path) for m in NUMBERS_PATH if (path := _source_file(m)) is not None)
    digest = hashlib.sha256()
    for module in sorted(files):
        digest.update(module.encode() + b"\0" + files[module].read_bytes() + b"\0")
    return CodeFingerprint(digest.hexdigest(), tuple(sorted(files)))
