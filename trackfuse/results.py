"""The run folder on disk: atomic files, verified per-batch parts, the merged CSVs.

Every file is written to a temporary name in its folder and renamed into place, so a killed
process leaves the old file or the new one, never half of one. A part that fails its header or
checksum check raises :class:`PartDamaged` and is recomputed, never merged. The folder's layout
is in docs/outputs.md ("The run folder"); the part header and its checks in docs/runner.md.
"""

from __future__ import annotations

import contextlib
import csv
import hashlib
import io
import json
import os
import re
from collections.abc import Callable, Iterable, Iterator, Sequence
from dataclasses import dataclass
from enum import StrEnum
from operator import itemgetter
from pathlib import Path
from typing import Any, BinaryIO

import yaml

from trackfuse.regular_files import NotARegularFile, open_regular
from trackfuse.rowformat import TIME_SUFFIX, csv_cell, format_value

TRIALS, TIMINGS, SUMMARY, MANIFEST, CONFIG = (
    "trials.csv", "timings.csv", "summary.csv", "manifest.json", "config.yaml")
TIMING_SUMMARY = "timings_summary.csv"
#: ``trials.csv`` in Parquet, which a run with ``outputs.store: parquet`` keeps instead.
TRIALS_PARQUET = "trials.parquet"
FINAL_FILES = (CONFIG, TRIALS, TRIALS_PARQUET, TIMINGS, SUMMARY, TIMING_SUMMARY)
REPORT_DIRS = ("figures", "tables", "notes")
INDEX_MD, INDEX_HTML = "index.md", "index.html"
INDEX_FILES = (INDEX_MD, INDEX_HTML)
#: Manifest key: the report's files, relative to the run folder (written with the report);
#: the only files of ``figures/`` and ``tables/`` trackfuse ever deletes.
REPORT_FILES = "report_files"
PART_KINDS = ("trials", "timings")
PART_MAGIC = "#trackfuse-part 1"
_PART_NAME = re.compile(r"^p(\d{6})-b(\d{7})\.(trials|timings)\.csv$")
_PART_HEADER = re.compile(r"^#trackfuse-part 1 point=(\d+) batch=(\d+) first=(\d+) "
                          r"stop=(\d+) rows=(\d+) bytes=(\d+) sha256=([0-9a-f]{64})\n$")
_TEMPORARY = re.compile(r"^\..+\.tmp(\.\w+)?$")


class RunStatus(StrEnum):
    """A run's status: in ``manifest.json`` (``RUNNING``, ``INTERRUPTED``, ``COMPLETE``) or
    as the outcome of a ``run()`` that found nothing to do (``ALREADY_COMPLETE``)."""

    RUNNING = "running"
    INTERRUPTED = "interrupted"
    COMPLETE = "complete"
    ALREADY_COMPLETE = "already complete"


class RunFolderError(ValueError):
    """A run folder or output root that cannot be used as it is; ``str(err)`` is one line."""


def atomic_write(path: Path, data: str | bytes) -> None:
    """Write ``data`` to ``path`` via a temporary file, fsync and rename. On an error (a
    full disk, ``path`` a folder) the temporary file is removed and the ``OSError`` names
    ``path``."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    try:
        with open(tmp, "wb") as fh:
            fh.write(data.encode() if isinstance(data, str) else data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except OSError as err:
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
        err.filename, err.filename2 = str(path), None
        raise


def config_hash(resolved: dict[str, Any]) -> str:
    """sha256 (hex) of the parts of a resolved config that determine the numbers."""
    science = {k: resolved[k] for k in ("experiment", "trials", "seed", "batch_size", "params",
                                        "sweep", "sweep_mode")}
    return hashlib.sha256(json.dumps(science, sort_keys=True, default=str).encode()).hexdigest()


def run_id(resolved: dict[str, Any], version: str, code: str,
           libraries: dict[str, str | None]) -> str:
    """Stable id of everything that determines the numbers: the config's science, the
    package version, ``code``, the fingerprint of the code that computes them
    (:func:`trackfuse.fingerprint.code_fingerprint`), and the versions of the ``libraries``
    whose arithmetic and formatting write them (name -> version)."""
    blob = json.dumps({"config": config_hash(resolved), "version": version, "code": code,
                       "libraries": libraries}, sort_keys=True)
    return f"seed{resolved['seed']}-{hashlib.sha256(blob.encode()).hexdigest()[:10]}"


def csv_line(cells: Iterable[str]) -> str:
    """One CSV record, newline included; what :func:`csv.reader` reads back as ``cells``."""
    fields = [csv_cell(c) for c in cells]
    return '""\n' if fields == [""] else ",".join(fields) + "\n"


def rows_to_csv(rows: Sequence[dict[str, Any]]) -> str:
    """CSV text (with header) for ``rows``; columns in order of first appearance."""
    columns: dict[str, None] = {}
    for row in rows:
        columns.update(dict.fromkeys(row))
    lines = [csv_line(columns)]
    lines += [csv_line([format_value(row.get(c)) for c in columns]) for row in rows]
    return "".join(lines)


@dataclass(frozen=True, order=True, slots=True)
class BatchSpan:
    """One batch: trials ``first .. stop-1`` of sweep point ``point``, batch number ``batch``.
    A run keeps one for each finished batch (the runner's set of them): about 200 bytes a
    batch in that set."""

    point: int
    batch: int
    first: int
    stop: int

    @property
    def name(self) -> str:
        return f"p{self.point:06d}-b{self.batch:07d}"

    @property
    def trials(self) -> int:
        return self.stop - self.first


def parse_part_name(name: str) -> tuple[int, int, str] | None:
    """``(point, batch, kind)`` of a part file's name, else ``None``."""
    match = _PART_NAME.match(name)
    return (int(match.group(1)), int(match.group(2)), match.group(3)) if match else None


def part_names(folder: Path) -> Iterator[tuple[int, int, str]]:
    """``(point, batch, kind)`` of every part file named in ``folder`` (none if missing)."""
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return
    for entry in entries:
        parsed = parse_part_name(entry.name)
        if parsed is not None:
            yield parsed


def _open_part(path: Path) -> BinaryIO:
    """A part opened for reading; a part that is not a regular file (a FIFO, a device) was
    not written by trackfuse, so it is neither read nor deleted: :class:`RunFolderError`."""
    try:
        return open_regular(path)
    except NotARegularFile as err:
        raise RunFolderError(f"{path}: {err.strerror}; trackfuse writes only regular files "
                             "there: move it away and run again") from None


class PartDamaged(Exception):
    """A part that does not hold what its batch must hold; it is recomputed, never merged."""

    def __init__(self, span: BatchSpan, kind: str, reason: str):
        self.span, self.kind = span, kind
        super().__init__(f"parts/{span.name}.{kind}.csv: {reason}")


def sha256_file(path: Path) -> str:
    """SHA-256 of a file's bytes, read in 1 MiB blocks."""
    digest = hashlib.sha256()
    with open_regular(path) as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def part_bytes(span: BatchSpan, csv_text: str, rows: int) -> bytes:
    """A part: the header line (identity, row count, size, checksum) and the CSV text."""
    body = csv_text.encode()
    header = (f"{PART_MAGIC} point={span.point} batch={span.batch} first={span.first} "
              f"stop={span.stop} rows={rows} bytes={len(body)} "
              f"sha256={hashlib.sha256(body).hexdigest()}\n")
    return header.encode() + body


def _part_header(line: bytes, span: BatchSpan, kind: str) -> tuple[int, int, str]:
    """``(rows, bytes, sha256)`` from a part's first line, checked against ``span``."""
    match = _PART_HEADER.match(line.decode("ascii", errors="replace"))
    if not match:
        raise PartDamaged(span, kind, "no valid part header (empty, cut, overwritten, or not "
                                      "written by this version)")
    point, batch, first, stop = (int(g) for g in match.groups()[:4])
    if (point, batch, first, stop) != (span.point, span.batch, span.first, span.stop):
        raise PartDamaged(span, kind, f"holds batch {batch} of point {point} (trials {first} to "
                                      f"{stop - 1}), not this batch")
    return int(match.group(5)), int(match.group(6)), match.group(7)


@dataclass(frozen=True)
class PartText:
    """A verified part: its ``columns`` and ``data``, the CSV text of its rows after the
    header line, each row as :func:`csv_line` writes it."""

    columns: list[str]
    data: str
    rows: int

    def records(self) -> list[list[str]]:
        """The cells of every row."""
        return csv_records(self.data)


def _plain(text: str) -> bool:
    """No field of CSV ``text`` is quoted: none holds ``"``, a comma or a line break."""
    return not ('"' in text or "\r" in text)


def csv_records(text: str) -> list[list[str]]:
    """The records of CSV ``text``, as :func:`csv.reader` gives them; text with no quoted
    field (no ``"`` or ``\\r``) is split on newlines and commas directly, several times
    faster and with the same result (a blank line is an empty record)."""
    if not _plain(text):
        return list(csv.reader(io.StringIO(text, newline="")))
    return [line.split(",") if line else [] for line in _lines(text)]


def _lines(text: str) -> list[str]:
    """The lines of ``text`` without their newlines (no empty last line for a final one)."""
    lines = text.split("\n")
    if lines[-1] == "":
        lines.pop()
    return lines


def read_part(path: Path, span: BatchSpan, kind: str) -> PartText:
    """Read a part in full and verify it.

    Raises :class:`PartDamaged` unless the header names ``span``, the checksum and size match,
    every row has every column and belongs to ``span.point``, and the trial indices are within
    the batch (for a trials part: every trial of the batch is present).
    """
    try:
        with _open_part(path) as fh:
            rows, size, digest = _part_header(fh.readline(512), span, kind)
            body = fh.read(size + 1)
    except OSError as err:
        raise PartDamaged(span, kind, f"unreadable ({err.strerror or type(err).__name__})") \
            from None
    if len(body) != size:
        raise PartDamaged(span, kind, f"{len(body)} bytes of CSV where {size} were written")
    if hashlib.sha256(body).hexdigest() != digest:
        raise PartDamaged(span, kind, "checksum differs from the one recorded when it was "
                                      "written")
    try:
        text = body.decode("utf-8")
        if _plain(text):  # the usual part: checked without splitting every cell
            header, _, data = text.partition("\n")
            columns = header.split(",") if header else []
            if not _rows_fit(body[len(header.encode()) + 1:], span, kind, columns, rows):
                lines = _lines(data)  # something is off: find what, line by line
                widths = [line.count(",") + 1 if line else 0 for line in lines]
                _check_rows(span, kind, columns, widths, lambda reach: [
                    line.split(",", reach) for line in lines], rows)
            return PartText(columns, data if data.endswith("\n") or not data else data + "\n",
                            rows)
        records = list(csv.reader(io.StringIO(text, newline="")))
    except (UnicodeDecodeError, csv.Error) as err:
        raise PartDamaged(span, kind, f"not CSV text ({type(err).__name__})") from None
    columns, data = (records[0], records[1:]) if records else ([], [])
    _check_rows(span, kind, columns, [len(row) for row in data], lambda reach: data, rows)
    return PartText(columns, "".join(map(csv_line, data)), rows)


def _rows_fit(data: bytes, span: BatchSpan, kind: str, columns: list[str], rows: int) -> bool:
    """Whether the rows of a part pass :func:`_check_rows`, shown with array operations on
    the bytes (about ten times faster than splitting its lines): ``data`` is the plain CSV
    (no quotes) after the header line, whose ``columns`` start with ``point, trial``.
    ``False`` means "not shown", not "damaged": :func:`_check_rows` then says what is wrong.
    """
    import numpy as np  # loaded by every run; kept out of the command line's start-up

    n = len(columns)
    if rows == 0 or columns[:2] != ["point", "trial"] or not data.endswith(b"\n"):
        return False
    b = np.frombuffer(data, dtype=np.uint8)
    ends = np.flatnonzero(b == ord("\n"))
    commas = np.flatnonzero(b == ord(","))
    if len(ends) != rows or len(commas) != rows * (n - 1):
        return False
    # row i's first cell ends at the first comma of group i, so each group starts in its own
    # row; with rows x (n - 1) commas in all, every row then holds exactly n cells
    commas = commas.reshape(rows, n - 1)
    starts = np.r_[0, ends[:-1] + 1]
    point = str(span.point).encode()
    if (commas[:, 0] - starts != len(point)).any() or any(
            (b[starts + i] != c).any() for i, c in enumerate(point)):
        return False
    first = commas[:, 0] + 1  # the trial cell: digits up to the next comma or line end
    width = (commas[:, 1] if n > 2 else ends) - first
    if width.min() < 1 or width.max() > 9:
        return False
    trial = np.zeros(rows, dtype=np.int64)
    for i in range(int(width.max())):
        inside = i < width
        digit = b[np.where(inside, first + i, first)].astype(np.int64) - ord("0")
        if ((digit < 0) | (digit > 9))[inside].any():
            return False
        trial = np.where(inside, 10 * trial + digit, trial)
    if trial.min() < span.first or trial.max() >= span.stop:
        return False
    return kind != "trials" or len(np.unique(trial)) == span.trials


def _check_rows(span: BatchSpan, kind: str, columns: list[str], widths: list[int],
                cells: Callable[[int], Sequence[Sequence[str]]], rows: int) -> None:
    """Check a part's rows: ``widths`` their number of cells, ``cells(reach)`` at least
    their first ``reach`` cells (asked for once the widths are right)."""
    if len(widths) != rows:
        raise PartDamaged(span, kind, f"{len(widths)} rows where {rows} were written")
    if not widths:
        if kind == "trials":
            raise PartDamaged(span, kind, "no rows")
        return
    if "point" not in columns or "trial" not in columns:
        raise PartDamaged(span, kind, "no point or trial column")
    wrong = set(widths) - {len(columns)}
    if wrong:
        raise PartDamaged(span, kind, f"a row has {min(wrong)} cells for {len(columns)} "
                                      "columns")
    at_point, at_trial = columns.index("point"), columns.index("trial")
    heads = cells(max(at_point, at_trial) + 1)
    points = set(map(itemgetter(at_point), heads)) - {str(span.point)}
    if points:
        raise PartDamaged(span, kind, f"a row of point {min(points)[:20]!r}")
    seen: set[int] = set()
    for text in sorted(set(map(itemgetter(at_trial), heads))):
        trial = int(text) if text.isascii() and text.isdigit() else -1
        if not span.first <= trial < span.stop:
            raise PartDamaged(span, kind, f"trial {text[:20]!r} is not one of trials "
                                          f"{span.first} to {span.stop - 1}")
        seen.add(trial)
    if kind == "trials" and len(seen) != span.trials:
        missing = sorted(set(range(span.first, span.stop)) - seen)
        raise PartDamaged(span, kind, f"trials missing: {', '.join(map(str, missing[:5]))}"
                                      + (" ..." if len(missing) > 5 else ""))


@dataclass
class PartScan:
    """What :meth:`RunFolder.scan_parts` found: whole batches, damaged parts (removed), strays."""

    finished: set[BatchSpan]
    damaged: list[str]
    stray: list[str]


class RunFolder:
    """One run's folder: verified parts for resume, merge into final CSVs, manifest.

    Every method that writes expects the caller to hold the folder's lock
    (:class:`trackfuse.runlock.RunLock`).
    """

    def __init__(self, path: Path):
        self.path = Path(path)
        self.parts = self.path / "parts"

    # -- state ------------------------------------------------------------------------------
    def check_layout(self) -> None:
        """Raise :class:`RunFolderError` if a file of the run is not a regular file or a
        folder of it is not a folder (nothing this class would overwrite or delete)."""
        for folder in (self.parts, *(self.path / d for d in REPORT_DIRS)):
            if folder.is_symlink():
                raise RunFolderError(f"{folder}: a link (to {os.readlink(folder)}); trackfuse "
                                     "writes and deletes only inside the run folder, never "
                                     "through a link: replace it with a folder and run again")
            if folder.exists() and not folder.is_dir():
                raise RunFolderError(f"{folder}: exists but is not a folder; move it away and "
                                     "run again")
        for name in (MANIFEST, *FINAL_FILES):
            path = self.path / name
            if path.exists() and not path.is_file():
                raise RunFolderError(f"{path}: exists but is not a regular file; move it away "
                                     "and run again")

    def prepare(self, resolved: dict[str, Any]) -> dict[str, Any]:
        """Check the layout, remove temporaries of killed runs, write ``config.yaml``.

        Returns ``{"bytes", "sha256"}`` of ``config.yaml``; raises :class:`RunFolderError`
        where :meth:`check_layout` does.
        """
        self.check_layout()
        try:
            self.parts.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise RunFolderError(f"{self.parts}: cannot create ({err.strerror})") from None
        self.remove_temporaries()
        data = yaml.safe_dump(resolved, sort_keys=False).encode()
        atomic_write(self.path / CONFIG, data)
        return {"bytes": len(data), "sha256": hashlib.sha256(data).hexdigest()}

    def report_files(self, recorded: list[str] | None) -> list[Path]:
        """The files of ``recorded`` (the manifest's :data:`REPORT_FILES`: what the report
        wrote) that are still there (not folders): ``index.md``, ``index.html`` and plain
        names directly in one of :data:`REPORT_DIRS`; any other entry (``../x``,
        ``trials.csv``) is ignored."""
        found = []
        for entry in recorded or []:
            parts = str(entry).split("/")
            if not (parts in ([n] for n in INDEX_FILES) or len(parts) == 2
                    and parts[0] in REPORT_DIRS and parts[1] not in ("", ".", "..")):
                continue
            path = self.path.joinpath(*parts)
            if os.path.lexists(path) and not path.is_dir():
                found.append(path)
        return list(dict.fromkeys(found))

    def clear(self, report_files: list[str] | None) -> list[str]:
        """Delete what trackfuse wrote of an earlier run, for a fresh start in the same
        folder (``--force``; call only with the lock held, after :meth:`check_layout`): its
        parts, final files, index, the ``report_files`` its manifest lists (``None`` for an
        unreadable one), then the manifest. Other files stay, and so do the folders that
        hold them. Returns what it removed, relative to the folder."""
        owned = [*self.report_files(report_files),
                 *(self.path / n for n in (*FINAL_FILES, *INDEX_FILES, MANIFEST))]
        removed = self._remove_parts()
        for path in dict.fromkeys(owned):
            if os.path.lexists(path):
                path.unlink()
                removed.append(path.relative_to(self.path).as_posix())
        for folder in REPORT_DIRS:
            with contextlib.suppress(OSError):  # not empty: it holds files of the user's
                (self.path / folder).rmdir()
        return removed

    def drop_resume_state(self) -> None:
        """Delete ``parts/`` once the final files are written, verified and recorded in a
        ``complete`` manifest: they hold every row, so the parts would be a second copy.
        Only parts and temporaries are deleted (a file of the user's keeps the folder)."""
        self._remove_parts()

    def _remove_parts(self) -> list[str]:
        """Delete the parts and temporaries in ``parts/`` (regular files by those names),
        then the folder if that empties it; return their paths relative to the run folder.
        Trials parts go first, so a kill midway still leaves no trials part without its
        timings part (the order :meth:`write_part` keeps)."""
        try:
            entries = [e for e in os.scandir(self.parts) if e.is_file(follow_symlinks=False)]
        except OSError:  # no parts/ (or not a folder: check_layout says so)
            return []
        ours = [e for e in entries if _TEMPORARY.match(e.name) or parse_part_name(e.name)]
        ours.sort(key=lambda e: not e.name.endswith(".trials.csv"))
        for entry in ours:
            Path(entry.path).unlink(missing_ok=True)
        with contextlib.suppress(OSError):  # not empty: it holds files of the user's
            self.parts.rmdir()
        return [f"parts/{e.name}" for e in ours]

    def remove_temporaries(self) -> None:
        """Delete temporary files left by killed runs (call only with the lock held)."""
        for folder in (self.path, self.parts, *(self.path / d for d in REPORT_DIRS)):
            if not folder.is_dir():
                continue
            for entry in os.scandir(folder):
                if _TEMPORARY.match(entry.name) and entry.is_file(follow_symlinks=False):
                    Path(entry.path).unlink(missing_ok=True)

    def part_path(self, span: BatchSpan, kind: str) -> Path:
        return self.parts / f"{span.name}.{kind}.csv"

    def scan_parts(self, span_of: Callable[[int, int], BatchSpan | None]) -> PartScan:
        """Find the finished batches in ``parts/`` without reading them in full.

        ``span_of(point, batch)`` gives the batch a part name must stand for, or ``None`` if the
        plan has no such batch. A batch is finished if both its parts have a header naming it
        and the size the header records; parts that fail are removed (their batch is
        recomputed). Files that are not parts of this plan are reported as stray and left alone.
        """
        candidates: set[BatchSpan] = set()
        stray: list[str] = []
        for entry in os.scandir(self.parts):
            parsed = parse_part_name(entry.name)
            span = span_of(*parsed[:2]) if parsed else None
            if span is None:
                if not _TEMPORARY.match(entry.name):
                    stray.append(entry.name)
            elif parsed[2] == "trials":
                candidates.add(span)
        scan = PartScan(set(), [], sorted(stray))
        for span in sorted(candidates):
            try:
                for kind in PART_KINDS:
                    self._check_part_size(span, kind)
            except PartDamaged as err:
                scan.damaged.append(str(err))
                self.drop_part(span)
            else:
                scan.finished.add(span)
        return scan

    def _check_part_size(self, span: BatchSpan, kind: str) -> None:
        path = self.part_path(span, kind)
        try:
            with _open_part(path) as fh:
                line = fh.readline(512)
                size = os.fstat(fh.fileno()).st_size
        except OSError as err:
            raise PartDamaged(span, kind, f"unreadable ({err.strerror or type(err).__name__})") \
                from None
        _, body, _ = _part_header(line, span, kind)
        if size != len(line) + body:
            raise PartDamaged(span, kind, f"{size - len(line)} bytes of CSV where {body} were "
                                          "written")

    def write_part(self, span: BatchSpan, trials_csv: str, trial_rows: int, timings_csv: str,
                   timing_rows: int) -> None:
        """Store one finished batch (timings first, so a trials part implies both)."""
        atomic_write(self.part_path(span, "timings"), part_bytes(span, timings_csv, timing_rows))
        atomic_write(self.part_path(span, "trials"), part_bytes(span, trials_csv, trial_rows))

    def drop_part(self, span: BatchSpan) -> None:
        """Remove both parts of a batch (so it is recomputed)."""
        for kind in PART_KINDS:
            path = self.part_path(span, kind)
            try:
                path.unlink(missing_ok=True)
            except OSError as err:
                raise RunFolderError(f"{path}: damaged and cannot be removed ({err.strerror}); "
                                     "move it away and run again") from None

    def check_final_files(self, files: dict[str, Any] | None,
                          checksums: bool = True) -> str | None:
        """``None`` if every final file matches the size and checksum ``files`` (the
        manifest's record of them) holds, else one line saying what does not.
        ``checksums=False`` compares sizes only (no file is read)."""
        if not isinstance(files, dict) or (TRIALS not in files and TRIALS_PARQUET not in files):
            return f"{self.path / MANIFEST}: no checksums of the final files"
        for name, record in files.items():
            path = self.path / str(name)
            if name not in FINAL_FILES or not isinstance(record, dict):
                return f"{self.path / MANIFEST}: unexpected files entry {str(name)[:40]!r}"
            if not path.is_file():
                return f"{path}: missing"
            if path.stat().st_size != record.get("bytes") or checksums and \
                    sha256_file(path) != record.get("sha256"):
                return f"{path}: does not match the size and checksum in manifest.json"
        return None

    # -- merge ------------------------------------------------------------------------------
    def merge(self, spans: Callable[[], Iterable[BatchSpan]], kind: str,
              target: str) -> dict[str, Any]:
        """Concatenate the verified ``kind`` parts of ``spans()`` (in order) into ``target``.

        ``spans`` is called twice (a header pass, then a data pass), so the batch list is never
        held whole. Parts may have different columns; the merged header is their union in
        order of first appearance and missing cells are empty. Memory stays at one part.
        Returns ``{"rows", "bytes", "sha256"}`` of the written file; raises :class:`PartDamaged`
        (writing nothing) if a part fails :func:`read_part`.
        """
        header: dict[str, None] = {}
        for span in spans():
            header.update(dict.fromkeys(self._part_columns(span, kind)))
        columns = list(header)
        tmp = self.path / f".{target}.{os.getpid()}.tmp"
        digest, rows, size = hashlib.sha256(), 0, 0
        try:
            with open(tmp, "wb") as out:
                for block, count in self._merged_blocks(spans(), kind, columns):
                    out.write(block)
                    digest.update(block)
                    size += len(block)
                    rows += count
                out.flush()
                os.fsync(out.fileno())
            os.replace(tmp, self.path / target)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise
        return {"rows": rows, "bytes": size, "sha256": digest.hexdigest()}

    def _part_columns(self, span: BatchSpan, kind: str) -> list[str]:
        """The CSV header of a part, from its first two lines (the part is checked later)."""
        try:
            with _open_part(self.part_path(span, kind)) as fh:
                _part_header(fh.readline(512), span, kind)
                line = fh.readline(1 << 20).decode("utf-8")
        except OSError as err:
            raise PartDamaged(span, kind, f"unreadable ({err.strerror or type(err).__name__})") \
                from None
        except UnicodeDecodeError:
            raise PartDamaged(span, kind, "not CSV text") from None
        return next(csv.reader([line]), [])

    def _merged_blocks(self, spans: Iterable[BatchSpan], kind: str,
                       columns: list[str]) -> Iterable[tuple[bytes, int]]:
        """``(CSV bytes, rows)`` per part, the header line with the first; a part with other
        columns than ``columns`` is rewritten with empty cells for its missing columns."""
        header = csv_line(columns)
        for span in spans:
            part = read_part(self.part_path(span, kind), span, kind)
            if part.columns == columns:
                text = part.data
            else:
                index = [part.columns.index(c) if c in part.columns else -1 for c in columns]
                text = "".join(csv_line([row[i] if i >= 0 else "" for i in index])
                               for row in part.records())
            yield (header + text).encode(), part.rows
            header = ""
        if header:
            yield header.encode(), 0


def removed_words(removed: Sequence[str | Path], folder: Path | None = None,
                  shown: int = 4) -> str:
    """``3 files trackfuse wrote: trials.csv, ...`` for a one-line message saying what was
    deleted; paths relative to ``folder`` when given."""
    names = [Path(p).relative_to(folder).as_posix() if folder else str(p) for p in removed]
    more = f" and {len(names) - shown} more" if len(names) > shown else ""
    noun = "file" if len(names) == 1 else "files"
    return f"{len(names)} {noun} trackfuse wrote: {', '.join(names[:shown])}{more}"


def split_timings(rows: list[dict[str, Any]], keys: Sequence[str]) -> tuple[list[dict], list[dict]]:
    """Split rows into (trial rows without ``*_time_s`` columns, timing rows with ``keys``)."""
    trial_rows, timing_rows = [], []
    for row in rows:
        times = {k: v for k, v in row.items() if k.endswith(TIME_SUFFIX)}
        trial_rows.append({k: v for k, v in row.items() if not k.endswith(TIME_SUFFIX)})
        if times:
            timing_rows.append({**{k: row[k] for k in keys if k in row}, **times})
    return trial_rows, timing_rows
