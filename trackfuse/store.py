"""Where a run keeps its trial rows: ``trials.csv``, or ``trials.parquet`` converted from it in
chunks with ``read_csv``'s column types (``docs/outputs.md``). Every reader goes through
:func:`trials_file`, :func:`read_trials` and :func:`chunks`."""

from __future__ import annotations

import importlib.util
import os
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from trackfuse.heap import release_free_memory
from trackfuse.results import TRIALS, TRIALS_PARQUET, sha256_file

if TYPE_CHECKING:  # validating a config (which names the store) loads no pandas
    import pandas as pd

#: The values ``outputs.store`` may take, the default first.
STORES = ("csv", "parquet")
#: Rows per chunk when converting and reading (the summary's chunk, and a row group).
CHUNK_ROWS = 200_000
#: The compression of ``trials.parquet``: zstd at its default level.
COMPRESSION = "zstd"


def parquet_problem() -> str | None:
    """Why ``outputs.store: parquet`` cannot be used here (pyarrow missing), else ``None``."""
    if importlib.util.find_spec("pyarrow") is None:
        return "parquet needs pyarrow: pip install 'trackfuse[parquet]'"
    return None


def trials_file(folder: Path) -> Path:
    """The run's rows in ``folder``: ``trials.parquet`` if there is one, else ``trials.csv``."""
    parquet = Path(folder) / TRIALS_PARQUET
    return parquet if parquet.is_file() else Path(folder) / TRIALS


def read_trials(path: Path) -> pd.DataFrame:
    """All of ``trials.csv`` or ``trials.parquet`` at ``path``, typed as ``read_csv`` would."""
    import pandas as pd
    if path.suffix == ".parquet":
        return pd.read_parquet(path)
    return pd.read_csv(path, low_memory=False)


def chunks(path: Path, chunk_rows: int = CHUNK_ROWS,
           columns: Iterable[str] | None = None) -> Iterator[pd.DataFrame]:
    """``path`` (CSV or Parquet) in chunks of <= ``chunk_rows`` rows, only ``columns`` if given.
    The heap's free memory is given back before each next chunk is read
    (:func:`~trackfuse.heap.release_free_memory`): a caller that drops a chunk before asking
    for the next keeps one chunk in memory, flat in the number of chunks."""
    for chunk in _read_chunks(path, chunk_rows, None if columns is None else set(columns)):
        yield chunk
        del chunk
        release_free_memory()


def _read_chunks(path: Path, chunk_rows: int, wanted: set[str] | None
                 ) -> Iterator[pd.DataFrame]:
    """The chunks of :func:`chunks`, as the CSV or Parquet reader gives them."""
    import pandas as pd
    if path.suffix == ".parquet":
        import pyarrow.parquet as pq
        reader = pq.ParquetFile(path)
        names = [c for c in reader.schema_arrow.names if wanted is None or c in wanted]
        for batch in reader.iter_batches(batch_size=chunk_rows, columns=names):
            frame = batch.to_pandas()
            del batch  # the Arrow batch is not held while the caller reads the next
            yield frame
        return
    try:
        yield from pd.read_csv(path, chunksize=chunk_rows, low_memory=False,
                               usecols=None if wanted is None else (lambda c: c in wanted))
    except pd.errors.EmptyDataError:
        return


def _common_dtype(kinds: set[str]) -> str:
    """The type of a column whose chunks read as ``kinds``, as the whole CSV would type it."""
    if len(kinds) == 1:
        return next(iter(kinds))
    if kinds <= {"i", "f"}:
        return "f"
    return "O"


def _column_kinds(csv_path: Path) -> tuple[dict[str, str], dict[str, Any]]:
    """Each column's common kind over all chunks of ``csv_path`` and its whole-file dtype."""
    kinds: dict[str, set[str]] = {}
    example: dict[str, Any] = {}
    for chunk in chunks(csv_path):
        for column, dtype in chunk.dtypes.items():
            kind = dtype.kind  # "O" for text (object or pandas' string type)
            kinds.setdefault(column, set()).add(kind)
            example.setdefault((column, kind), dtype)
    common = {column: _common_dtype(found) for column, found in kinds.items()}
    dtypes = {column: example.get((column, kind), object)
              for column, kind in common.items()}
    return common, dtypes


def write_parquet(csv_path: Path, target: Path) -> dict[str, Any]:
    """Convert the CSV at ``csv_path`` to Parquet at ``target`` (atomically) and remove the
    CSV; return ``{"rows", "bytes", "sha256"}`` of the Parquet file for the manifest."""
    import pandas as pd
    import pyarrow as pa
    import pyarrow.parquet as pq
    kinds, dtypes = _column_kinds(csv_path)
    wanted = {c: ("float64" if kinds[c] == "f" else dtypes[c]) for c in kinds}
    tmp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
    rows, writer = 0, None
    try:
        for chunk in chunks(csv_path):
            table = pa.Table.from_pandas(chunk.astype(wanted), preserve_index=False)
            if writer is None:
                writer = pq.ParquetWriter(tmp, table.schema, compression=COMPRESSION)
            writer.write_table(table.cast(writer.schema), row_group_size=CHUNK_ROWS)
            rows += len(chunk)
        if writer is None:  # no rows: keep the header's columns
            empty = pd.read_csv(csv_path, nrows=0)
            pq.write_table(pa.Table.from_pandas(empty, preserve_index=False), tmp,
                           compression=COMPRESSION)
        else:
            writer.close()
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException:
        if writer is not None:
            writer.close()
        tmp.unlink(missing_ok=True)
        raise
    csv_path.unlink()
    return {"rows": rows, "bytes": target.stat().st_size, "sha256": sha256_file(target)}
