"""Merging parts into trials.csv: plain parts are copied, the rest go through the csv module,
and either way the merged file is what the csv module writes for the rows (issue 16)."""

from __future__ import annotations

import csv
import io
import random

from trackfuse.results import BatchSpan, RunFolder, csv_records, rows_to_csv


def test_csv_records_equals_the_csv_reader_on_random_text():
    rng = random.Random(3)
    alphabet = ["a", "7", ",", "\n", '"', "\r", " ", "é"]
    for _ in range(3000):
        text = "".join(rng.choice(alphabet) for _ in range(rng.randrange(0, 30)))
        plain = text.replace('"', "").replace("\r", "") if rng.random() < 0.7 else text
        assert csv_records(plain) == list(csv.reader(io.StringIO(plain, newline=""))), plain


def _csv(columns: list[str], rows: list[list[str]]) -> str:
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(columns)
    writer.writerows(rows)
    return buf.getvalue()


def test_merge_equals_the_csv_module_for_plain_quoted_and_reordered_parts(tmp_path):
    folder = RunFolder(tmp_path / "run")
    folder.parts.mkdir(parents=True)
    spans = [BatchSpan(0, b, 2 * b, 2 * b + 2) for b in range(4)]
    rows = [  # plain; a quoted cell; columns in another order; a missing column
        [{"point": 0, "trial": t, "algorithm": "a/b", "x": 0.1 * t} for t in (0, 1)],
        [{"point": 0, "trial": t, "algorithm": 'say "hi", then\nstop', "x": 1.5}
         for t in (2, 3)],
        [{"point": 0, "trial": t, "x": float(t), "algorithm": "c"} for t in (4, 5)],
        [{"point": 0, "trial": t, "algorithm": "d"} for t in (6, 7)],
    ]
    for span, part_rows in zip(spans, rows, strict=True):
        folder.write_part(span, rows_to_csv(part_rows), len(part_rows), rows_to_csv([]), 0)
    record = folder.merge(lambda: iter(spans), "trials", "trials.csv")
    columns = ["point", "trial", "algorithm", "x"]
    expected = _csv(columns, [[str(r.get(c, "")) for c in columns]
                              for part in rows for r in part])
    written = (folder.path / "trials.csv").read_text()
    assert written == expected
    assert record["rows"] == 8


def test_merge_reads_back_as_the_cells_written_and_plain_parts_as_csv_writes_them(tmp_path):
    rng = random.Random(11)
    alphabet = ["a", "7", " ", "é", ".", "-", ",", '"', "\n", "\r"]
    for case in range(40):
        folder = RunFolder(tmp_path / f"run{case}")
        folder.parts.mkdir(parents=True)
        plain = case % 2 == 0  # cells that need no quotes in every other case
        spans = [BatchSpan(0, b, 3 * b, 3 * b + 3) for b in range(3)]
        tables = []
        for span in spans:
            rows = [{"point": 0, "trial": t,
                     "text": "".join(rng.choice(alphabet[:6] if plain else alphabet)
                                     for _ in range(rng.randrange(0, 6))),
                     "x": rng.random()} for t in range(span.first, span.stop)]
            folder.write_part(span, rows_to_csv(rows), len(rows), rows_to_csv([]), 0)
            tables.append(rows)
        folder.merge(lambda spans=spans: iter(spans), "trials", "trials.csv")
        columns = ["point", "trial", "text", "x"]
        cells = [[str(r[c]) for c in columns] for rows in tables for r in rows]
        written = (folder.path / "trials.csv").read_bytes().decode()
        assert list(csv.reader(io.StringIO(written, newline=""))) == [columns, *cells]
        if plain:
            assert written == _csv(columns, cells)


def test_a_carriage_return_in_a_cell_is_quoted():
    # csv's writer leaves it bare with a \n terminator; its reader then splits the row
    text = rows_to_csv([{"point": 0, "error": "one\rtwo"}])
    assert list(csv.reader(io.StringIO(text, newline=""))) == [["point", "error"],
                                                               ["0", "one\rtwo"]]
