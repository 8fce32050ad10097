"""A run's record, ``manifest.json``: one typed :class:`Manifest`, written and read here only.

The runner writes it when a session starts, every few seconds while batches finish, and when
the run stops (``interrupted``) or ends (``complete``, with the final files' sizes and
checksums and the report's files); ``plot`` rewrites it after a redraw. Every reader
(``load``, ``runs``, ``compare``, the runner's resume) gets a :class:`Manifest` whose fields
have the types below or is refused with one :class:`ManifestError` naming the file and the
key. Only ``status`` is required: manifests of older versions lack some keys (their fields
are ``None``, and stay left out when written back), and keys this version does not know are
kept, unread, in :attr:`Manifest.extra`. The JSON keys are the field names, in field order.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

from trackfuse.regular_files import open_regular
from trackfuse.results import MANIFEST, RunFolderError, RunStatus, atomic_write

MAX_MANIFEST_BYTES = 10_000_000
STATUSES = (RunStatus.RUNNING, RunStatus.INTERRUPTED, RunStatus.COMPLETE)


class ManifestError(RunFolderError):
    """A ``manifest.json`` that is no trackfuse manifest or has a key of the wrong type:
    ``source`` is the file, ``key`` the offending key (``None``: not a JSON object)."""

    def __init__(self, source: Path, key: str | None, message: str):
        self.source, self.key = source, key
        super().__init__(f"{source}: {message}")


@dataclass(frozen=True)
class Manifest:
    """What ``manifest.json`` records of one run (times are ISO-8601 text in UTC)."""

    status: str  # one of STATUSES
    run_id: str | None = None
    name: str | None = None  # the user's label (--name)
    experiment: str | None = None
    plugin_folder: str | None = None  # where a plugin experiment was imported from
    config_file: str | None = None  # the config the run was made from
    command: list[str] | None = None
    git: dict[str, Any] | None = None  # repository, commit, dirty
    config_sha256: str | None = None
    code_fingerprint: dict[str, Any] | None = None  # sha256, modules
    trackfuse_path: str | None = None
    versions: dict[str, Any] | None = None  # library -> version (None: not installed)
    platform: str | None = None
    cpu: list[dict[str, Any]] | dict[str, Any] | None = None  # older runs: one dict
    host: str | None = None
    root_seed: int | None = None
    executor: str | None = None
    executor_requested: str | None = None
    cluster: dict[str, Any] | None = None  # only on a batch-system cluster
    workers: int | None = None
    points: int | None = None
    draw_points: list[int] | None = None
    trials_per_point: int | None = None
    batch_size: int | None = None
    trials_total: int | None = None
    trials_done: int | None = None
    trials_failed: int | None = None
    first_started: str | None = None
    started: str | None = None
    finished: str | None = None
    sessions: int | None = None
    per_point_wall_s: dict[str, float] | None = None  # str(point) -> seconds
    report_files: list[str] | None = None  # relative to the run folder; ours to delete
    sequential: dict[str, Any] | None = None  # only for a sequential run
    rows: int | None = None  # the keys from here on: once complete
    figure_errors: list[str] | None = None
    files: dict[str, dict[str, Any]] | None = None  # final file -> bytes, sha256 (rows)
    extra: dict[str, Any] = field(default_factory=dict)  # keys this version does not know

    def to_dict(self) -> dict[str, Any]:
        """The JSON object, keys in field order, then :attr:`extra`; a ``None`` is left out
        (a key the run lacks) except where the runner writes it as ``null`` (no name, no
        plugin folder, not in git, not finished)."""
        out = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name != "extra" and (value is not None or f.name in _WRITTEN_AS_NULL):
                out[f.name] = value
        return {**out, **self.extra}

    @classmethod
    def from_dict(cls, data: Any, source: Path) -> Manifest:
        """The manifest in the JSON value ``data`` read from ``source``, validated."""
        if not isinstance(data, dict):
            raise ManifestError(source, None, "not a trackfuse manifest (not a JSON object)")
        if data.get("status") not in STATUSES:
            shown = repr(data["status"])[:40] if "status" in data else "missing"
            raise ManifestError(source, "status", f"status {shown}; allowed: "
                                + ", ".join(STATUSES))
        for key, (check, allowed) in _CHECKS.items():
            if data.get(key) is not None and not check(data[key]):
                raise ManifestError(source, key, f"{key} {_shown(data[key])}; allowed: {allowed}")
        known = {f.name for f in fields(cls)} - {"extra"}
        return cls(**{k: v for k, v in data.items() if k in known},
                   extra={k: v for k, v in data.items() if k not in known})


def read_manifest(folder: Path) -> Manifest | None:
    """The manifest of run folder ``folder``, or ``None`` if it has none; a
    :class:`~trackfuse.results.RunFolderError` (a :class:`ManifestError` for one that is
    not valid) in one line if it cannot be used."""
    path = Path(folder) / MANIFEST
    try:
        with open_regular(path) as fh:  # a FIFO in its place must not hang the reader
            data = fh.read(MAX_MANIFEST_BYTES + 1)
    except FileNotFoundError:
        return None
    except OSError as err:
        raise RunFolderError(f"{path}: unreadable ({err.strerror or type(err).__name__})") \
            from None
    try:
        parsed = json.loads(data.decode("utf-8")) if len(data) <= MAX_MANIFEST_BYTES else None
    except (UnicodeDecodeError, ValueError, RecursionError):
        parsed = None
    return Manifest.from_dict(parsed, path)


def write_manifest(folder: Path, manifest: Manifest) -> None:
    """Write ``manifest`` as run folder ``folder``'s ``manifest.json``, atomically."""
    text = json.dumps(manifest.to_dict(), indent=2, sort_keys=False) + "\n"
    atomic_write(Path(folder) / MANIFEST, text)


def sibling_manifests(folder: Path) -> list[Manifest]:
    """The valid manifests of the other run folders beside ``folder`` (same config stem),
    skipping anything that is not a run's manifest."""
    found = []
    parent = Path(folder).parent
    if not parent.is_dir():
        return found
    for entry in sorted(parent.iterdir()):
        if entry == Path(folder) or not entry.is_dir():
            continue
        try:
            manifest = read_manifest(entry)
        except RunFolderError:
            continue
        if manifest is not None:
            found.append(manifest)
    return found


def _shown(value: Any) -> str:
    text = json.dumps(value) if isinstance(value, (dict, list)) else repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _is_int(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_list_of(kind: Callable[[Any], bool]) -> Callable[[Any], bool]:
    return lambda value: isinstance(value, list) and all(map(kind, value))


def _is_str(value: Any) -> bool:
    return isinstance(value, str)


def _is_dict(value: Any) -> bool:
    return isinstance(value, dict)


def _is_seconds(value: Any) -> bool:
    return isinstance(value, dict) and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) for v in value.values())


_TEXT = (_is_str, "text")
_COUNT = (_is_int, "an integer")
_OBJECT = (_is_dict, "a JSON object")
_TEXTS = (_is_list_of(_is_str), "a list of texts")
#: Per key: a test of a value that is not ``None``, and what it allows in words.
_CHECKS: dict[str, tuple[Callable[[Any], bool], str]] = {
    "run_id": _TEXT, "name": _TEXT, "experiment": _TEXT, "plugin_folder": _TEXT,
    "config_file": _TEXT, "command": _TEXTS, "git": _OBJECT, "config_sha256": _TEXT,
    "code_fingerprint": _OBJECT, "trackfuse_path": _TEXT, "versions": _OBJECT,
    "platform": _TEXT, "cpu": (lambda v: isinstance(v, (list, dict)), "a list or an object"),
    "host": _TEXT, "root_seed": _COUNT, "executor": _TEXT, "executor_requested": _TEXT,
    "cluster": _OBJECT, "workers": _COUNT, "points": _COUNT,
    "draw_points": (_is_list_of(_is_int), "a list of integers"),
    "trials_per_point": _COUNT, "batch_size": _COUNT, "trials_total": _COUNT,
    "trials_done": _COUNT, "trials_failed": _COUNT, "first_started": _TEXT,
    "started": _TEXT, "finished": _TEXT, "sessions": _COUNT,
    "per_point_wall_s": (_is_seconds, "an object of seconds"), "report_files": _TEXTS,
    "sequential": _OBJECT, "rows": _COUNT, "figure_errors": _TEXTS,
    "files": _OBJECT,
}
_WRITTEN_AS_NULL = frozenset({"name", "plugin_folder", "git", "finished"})

__all__ = ["Manifest", "ManifestError", "read_manifest", "sibling_manifests",
           "write_manifest"]
