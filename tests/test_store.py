"""outputs.store: parquet keeps trials.parquet instead of trials.csv: the same rows and
types, byte-identical for any worker count, read by load, plot and compare."""

from __future__ import annotations

import json

import pandas as pd
import pytest
from typer.testing import CliRunner

import trackfuse
from trackfuse.config import ConfigError, load
from trackfuse.runner import Runner
from trackfuse.store import CHUNK_ROWS, chunks, write_parquet
from trackfuse_cli.main import app

pytest.importorskip("pyarrow")

CONFIG = ("experiment: toy_gaussian\ntrials: 30\nseed: 5\nparams: {fail_every: 4}\n"
          "sweep: {mu: [0.0, 1.0], label: [a, b]}\n")


def _run(write_config, tmp_path, store: str, workers: int = 1, executor: str = "serial"):
    cfg = write_config(CONFIG + f"outputs: {{store: {store}}}\n", name=f"g_{store}")
    return Runner(load(cfg), tmp_path / f"out{workers}", workers=workers, executor=executor,
                  progress=False, plots=False).run().folder


def test_parquet_holds_the_csv_rows_and_types_and_its_checksum(write_config, tmp_path):
    csv_run = _run(write_config, tmp_path, "csv")
    parquet_run = _run(write_config, tmp_path, "parquet")
    assert not (parquet_run / "trials.csv").exists() and (parquet_run / "trials.parquet").exists()
    from_csv, from_parquet = trackfuse.load(csv_run), trackfuse.load(parquet_run)
    assert (from_parquet.trials["status"] == "failed").any()  # text, with missing values
    pd.testing.assert_frame_equal(from_csv.trials, from_parquet.trials)
    pd.testing.assert_frame_equal(from_csv.summary, from_parquet.summary)
    files = json.loads((parquet_run / "manifest.json").read_text())["files"]
    assert "trials.csv" not in files and files["trials.parquet"]["rows"] == len(from_csv.trials)
    with open(parquet_run / "trials.parquet", "r+b") as fh:  # a changed byte is refused
        fh.seek(100)
        byte = fh.read(1)
        fh.seek(100)
        fh.write(bytes([byte[0] ^ 1]))
    refused = CliRunner().invoke(app, ["plot", str(parquet_run)])
    assert refused.exit_code == 2 and "trials.parquet" in refused.stderr


def test_parquet_is_byte_identical_for_any_worker_count(write_config, tmp_path):
    one = _run(write_config, tmp_path, "parquet")
    two = _run(write_config, tmp_path, "parquet", workers=2, executor="process")
    assert (one / "trials.parquet").read_bytes() == (two / "trials.parquet").read_bytes()
    assert one.name == two.name
    cfg = write_config(CONFIG + "outputs: {store: parquet}\n", name="g_parquet")
    again = Runner(load(cfg), tmp_path / "out1", executor="serial", progress=False,
                   plots=False).run()  # found complete: its checksums verified, not rewritten
    assert again.status == "already complete" and again.computed_trials == 0
    assert (again.folder / "trials.parquet").read_bytes() == \
        (two / "trials.parquet").read_bytes()


def test_plot_and_compare_read_a_parquet_run(write_config, tmp_path):
    parquet_run = _run(write_config, tmp_path, "parquet")
    csv_run = _run(write_config, tmp_path, "csv")
    plotted = CliRunner().invoke(app, ["plot", str(parquet_run)])
    assert plotted.exit_code == 0, plotted.output
    compared = CliRunner().invoke(app, ["compare", str(csv_run), str(parquet_run), "--json"])
    assert compared.exit_code == 0, compared.output
    cells = json.loads(compared.stdout)["cells"]
    assert cells and all(c["diff"] == 0 for c in cells)


def test_types_are_those_of_the_whole_csv_across_chunks(tmp_path):
    """An integer column with a gap in a later chunk is float, as pandas reads the whole
    file; a text column empty in a whole chunk stays text."""
    n = CHUNK_ROWS + 10
    csv = tmp_path / "trials.csv"
    csv.write_text("trial,count,error\n" + "".join(f"{t},1,\n" for t in range(n - 1))
                   + f"{n - 1},,ValueError: x\n")
    whole = pd.read_csv(csv, low_memory=False)
    assert [c["count"].dtype.kind for c in chunks(csv)] == ["i", "f"]
    write_parquet(csv, tmp_path / "trials.parquet")
    pd.testing.assert_frame_equal(pd.read_parquet(tmp_path / "trials.parquet"), whole)
    assert not csv.exists()


def test_an_unknown_store_is_one_line(write_config):
    cfg = write_config("experiment: toy_gaussian\noutputs: {store: hdf5}\n")
    with pytest.raises(ConfigError) as err:
        load(cfg)
    assert err.value.key == "outputs.store" and "csv, parquet" in err.value.message
