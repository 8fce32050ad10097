"""Fuzzed configs and overrides: a valid config or a one-line error with exit 2, nothing else."""

from __future__ import annotations

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from typer.testing import CliRunner

from trackfuse.config import TOP_LEVEL
from trackfuse_cli.main import app

KEYS = [*TOP_LEVEL, "params.mu", "params.sigma", "params.n", "params.p_d", "params.label",
        "trails", "param", "sweep.mu", "sweep.n", "sweep.label", "outputs.figures",
        "outputs.formats"]
scalars = st.one_of(st.none(), st.booleans(), st.integers(-10**30, 10**30),
                    st.floats(allow_nan=True, allow_infinity=True), st.text(max_size=12),
                    st.sampled_from(["range(0, 5)", "range(1, 0)", "range(0,1,0)", "range(1e9)",
                                     "toy_gaussian", "toy_experiments:GAUSSIAN", "grid", "zip",
                                     "a", "b", "all", "png"]))
values = st.recursive(scalars, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=6), inner, max_size=4)),
    max_leaves=12)


def nest(flat: dict) -> dict:
    doc: dict = {}
    for key, value in flat.items():
        head, _, tail = key.partition(".")
        if tail and isinstance(doc.get(head, {}), dict):
            doc.setdefault(head, {})[tail] = value
        else:
            doc[head] = value
    return doc


documents = st.builds(nest, st.dictionaries(st.sampled_from(KEYS), values, max_size=7)).map(
    lambda d: {"experiment": "toy_gaussian", **d} if "experiment" not in d else d)
overrides = st.lists(st.tuples(st.sampled_from(["--set", "--sweep"]), st.one_of(
    st.text(max_size=15),
    st.builds(lambda k, v: f"{k}={v}", st.sampled_from(["mu", "n", "sigma", "label", "trials",
                                                        "seed", "p_d", "nope"]),
              st.text(max_size=10)))), max_size=3)


def check(result) -> None:
    assert result.exception is None or isinstance(result.exception, SystemExit), (
        repr(result.exception))
    assert result.exit_code in (0, 2), result.output
    if result.exit_code == 2:
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr


def invoke(args: list[str]):
    return CliRunner().invoke(app, args, catch_exceptions=True)


@pytest.mark.slow
@settings(max_examples=250, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                  HealthCheck.function_scoped_fixture])
@given(doc=documents, extra=overrides)
def test_random_documents_validate_or_fail_in_one_line(doc, extra, tmp_path):
    path = tmp_path / "fuzz.yaml"
    path.write_text(yaml.safe_dump(doc, allow_unicode=True))
    flags = [x for pair in extra for x in pair]
    check(invoke(["validate", str(path), *flags]))
    check(invoke(["run", str(path), "--dry-run", "--out", str(tmp_path / "o"), *flags]))


@pytest.mark.slow
@settings(max_examples=250, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(text=st.text(max_size=200), cut=st.integers(0, 200))
def test_mutated_yaml_text_validates_or_fails_in_one_line(text, cut, tmp_path):
    base = ("experiment: toy_gaussian\ntrials: 3\nparams: {mu: 1.5, n: 2}\n"
            "sweep:\n  sigma: range(1, 3)\n")
    path = tmp_path / "fuzz.yaml"
    path.write_text(base[:cut] + text + base[cut:])
    check(invoke(["validate", str(path)]))
