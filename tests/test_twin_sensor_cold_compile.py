"""The first-run compile of the twin-sensor kernel on two cores (cold_compile)."""

import hashlib
import os
import pickle
import subprocess
import sys
from pathlib import Path
from types import SimpleNamespace

import numba
import pda_reference as reference
import pytest
import twin_sensor_pinned as pinned

from trackfuse.experiments.twin_sensor import cold_compile
from trackfuse.experiments.twin_sensor.cold_compile import (
    HELPER,
    callee_args,
    compile_in,
    compile_on_two_cores,
)
from trackfuse.experiments.twin_sensor.model import score_estimates
from trackfuse.experiments.twin_sensor.preload import load_kernel
from trackfuse.tracking import pda as k

ROOT = Path(__file__).resolve().parents[1]


@pytest.mark.slow
def test_the_callees_are_compiled_for_the_signatures_filter_batch_asks_for():
    """Compiling ``_filter_batch`` anew adds no signature to a callee compiled from
    ``callee_args`` (a mismatch would compile that callee twice on the first run)."""
    load_kernel()  # loads _filter_batch for its one signature
    for dispatcher, args in callee_args().items():
        compile_in(dispatcher, args)
    before = {d: list(d.signatures) for d in callee_args()}
    fresh = numba.njit(**{**k.JIT, "cache": False})(k._filter_batch.py_func)
    fresh.compile(k._filter_batch.signatures[0])
    assert {d: list(d.signatures) for d in callee_args()} == before


def test_only_an_index_of_this_numba_python_and_source_is_the_kernel_cached(tmp_path,
                                                                             monkeypatch):
    """After a numba upgrade or an edit of the filter numba ignores the old index and
    compiles: that compile must use both cores, so the old index must not count as cached.
    An index written before the source file (a wheel's, unpacked in any order) counts."""
    monkeypatch.setattr(k, "_filter_batch",
                        SimpleNamespace(stats=SimpleNamespace(cache_path=str(tmp_path))))
    name = f"kernel._filter_batch-1.py{sys.version_info.major}{sys.version_info.minor}.nbi"
    source = Path(k.__file__).read_bytes()

    def index(version, stamp=hashlib.sha256(source).digest(), file_name=name) -> bool:
        for old in tmp_path.iterdir():
            old.unlink()
        with (tmp_path / file_name).open("wb") as f:
            pickle.dump(version, f, protocol=-1)
            f.write(pickle.dumps((stamp, {}), protocol=-1))
        os.utime(tmp_path / file_name, (0, 0))  # older than the source
        return cold_compile.kernel_cached()

    assert index(numba.__version__)
    assert not index("0.1.0")  # written by another numba
    assert not index(numba.__version__, hashlib.sha256(source + b"#").digest())  # edited
    assert not index(numba.__version__, file_name=name.replace(".py3", ".py2"))  # Python
    (tmp_path / name).write_bytes(b"not a pickle")
    assert not cold_compile.kernel_cached()


def test_the_helper_stops_when_its_parent_closes_its_stdin(tmp_path):
    """A helper whose fork server is gone stops before it has compiled anything."""
    helper = subprocess.Popen([sys.executable, "-c", HELPER, *sys.path],
                              stdin=subprocess.PIPE, stderr=subprocess.DEVNULL,
                              env=dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path)))
    helper.stdin.close()
    assert helper.wait(timeout=120) != 0
    assert not list(tmp_path.rglob("*_pair_update*.nbi"))


@pytest.mark.parametrize("owner, name, value", [(cold_compile, "HELPER", "raise SystemExit(3)"),
                                               (sys, "executable", "/nonexistent/python")],
                         ids=["helper-exits-3", "no-python"])
def test_a_failing_helper_does_not_fail_the_load(monkeypatch, owner, name, value):
    """The load goes on without the helper, and the kernel it leaves loaded equals the
    numpy reference (to 1e-9) on a small batch."""
    monkeypatch.setattr(owner, name, value)
    compile_on_two_cores()
    load_kernel()
    algorithm = "mspda_parallel/mgekf"
    p, sc, batch, rules = pinned.setup({}, trials=3)
    options = pinned.options(p, sc, algorithm)
    got = score_estimates(sc, batch, k.run_filter(sc, batch, options), rules)
    pinned.assert_pinned(got, reference.run_filter(sc, batch, options, rules))
    assert got["n_valid"].mean() > 1.0  # the clutter was gated: the PDA path ran


@pytest.mark.slow  # compiles the kernel from an empty cache (25-40 s on two cores)
def test_a_cold_two_core_compile_loads_the_pair_update_and_equals_the_reference(tmp_path):
    """From an empty cache: the fork server's load takes ``_pair_update`` from the helper's
    cache entry (never compiles it), and the kernel so compiled passes the kernel tests
    (numpy reference to 1e-9)."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    probe = ("import trackfuse.experiments.twin_sensor.preload; "
             "from trackfuse.tracking import pda as k; "
             "s = k._pair_update.stats; assert s.cache_hits and not s.cache_misses, s")
    subprocess.run([sys.executable, "-c", probe], env=env, check=True)
    subprocess.run([sys.executable, "-m", "pytest", "-q", "--all", "-p", "no:cacheprovider",
                    str(ROOT / "tests" / "test_twin_sensor_kernel.py")], env=env, check=True)
