"""Command-line overrides: positional KEY=VALUE, bracket lists, errors blamed on their source,
figure names checked at validation."""

from __future__ import annotations

import pytest
import yaml
from conftest import ROOT, trackfuse

from trackfuse.config import ConfigError, build, load
from trackfuse.sweep import SweepError, parse_sets, parse_sweeps

CONFIG = "experiment: toy_experiments:GAUSSIAN\ntrials: 3\nsweep: {mu: [0, 1]}\n"


def test_positional_overrides_work_like_set(write_config):
    path = write_config(CONFIG)
    positional = trackfuse("run", path, "--dry-run", "sigma=2.5", "mu=0.5", "trials=4")
    with_set = trackfuse("run", path, "--dry-run", "--set", "sigma=2.5", "--set", "mu=0.5",
                         "--set", "trials=4")
    assert positional.returncode == 0, positional.stderr
    assert positional.stdout == with_set.stdout
    resolved = yaml.safe_load(positional.stdout.split("\n# ")[0])
    assert resolved["params"]["sigma"] == 2.5 and resolved["sweep"] == {}
    assert resolved["trials"] == 4
    assert trackfuse("validate", path, "n=2").returncode == 0
    refused = trackfuse("validate", path, "n")
    assert refused.returncode == 2 and refused.stderr.startswith("error: --set: got 'n'")


def test_sweep_list_values_keep_their_commas():
    result = trackfuse("run", "twin_sensor_orbit", "--dry-run", "--sweep",
                       "algorithms=[nn/ekf,nn/mgekf],[nn/ekf]")
    assert result.returncode == 0, result.stderr
    resolved = yaml.safe_load(result.stdout.split("\n# ")[0])
    assert resolved["sweep"]["algorithms"] == [["nn/ekf", "nn/mgekf"], ["nn/ekf"]]


def test_errors_name_the_override_not_the_file(write_config):
    path = write_config(CONFIG)
    # (--set items, --sweep items, source, key, allowed, did-you-mean, what it says otherwise)
    cases = [(["n=0"], [], "--set", "n", "an integer >= 1", "", "got 0"),
             (["trials=-2"], [], "--set", "trials", "an integer in [1, 1000000000]", "",
              "got -2"),
             (["sigam=1"], [], "--set", "sigam", "", "sigma", "unknown parameter"),
             ([], ["label=a,c"], "--sweep", "label", "one of a, b", "", "got 'c'"),
             ([], ["mu=range(0,1,0)"], "--sweep", "mu", "", "", "step must not be 0")]
    for sets, sweeps, source, key, allowed, suggestion, says in cases:
        with pytest.raises(ConfigError) as err:
            load(path, parse_sets(sets), parse_sweeps(sweeps))
        error = err.value
        assert (error.source, error.key, error.allowed, error.suggestion) == \
            (source, key, allowed, suggestion), str(error)
        assert says in error.message and str(path) not in str(error)
    with pytest.raises(ConfigError) as in_file:
        load(write_config(CONFIG + "params: {n: 0}\n", "bad"))
    assert (in_file.value.source, in_file.value.key) == (str(path.parent / "bad.yaml"),
                                                         "params.n")
    for override in (["--set", "n=0"], ["n=0"]):  # the command line blames the override
        result = trackfuse("validate", path, *override)
        assert result.returncode == 2
        assert result.stderr == "error: --set: n: got 0; allowed: an integer >= 1\n"


def test_an_experiments_own_check_blames_the_override_that_set_the_key():
    """--set targets.n=50 (the paper's scene has 10 targets) was blamed on the config file."""
    config = ROOT / "configs" / "ci" / "passive_assoc_ci.yaml"
    for sets, sweeps, source, says in (
            (["targets.n=50"], [], "--set", "got 50; allowed with scene.mode: paper: 1..10"),
            ([], ["targets.n=5,50"], "--sweep", "got 50 at the sweep point targets.n=50; "
                                                "allowed with scene.mode: paper: 1..10")):
        with pytest.raises(ConfigError) as err:
            load(config, parse_sets(sets), parse_sweeps(sweeps))
        assert (err.value.source, err.value.key) == (source, "targets.n")
        assert err.value.message.startswith(says), str(err.value)
    result = trackfuse("validate", config, "targets.n=50")  # a positional override too
    assert result.returncode == 2 and result.stderr.startswith("error: --set: targets.n: ")
    assert load(config, {"scene.mode": "paper"}).params["targets.n"] <= 10  # the file's n


def test_a_typo_in_outputs_figures_is_refused_at_validation(write_config):
    path = write_config(CONFIG + "outputs: {figures: [estimat]}\n")
    with pytest.raises(ConfigError) as err:
        load(path)
    assert (err.value.key, err.value.suggestion, err.value.allowed) == \
        ("outputs.figures", "estimate", "estimate")
    result = trackfuse("run", "--no-progress", path)  # refused before anything runs
    assert result.returncode == 2
    assert result.stderr.startswith(f"error: {path}: outputs.figures: unknown figure")
    listed = trackfuse("list", "toy_experiments:GAUSSIAN")
    assert "\n  estimate (paper Fig. 1)\n" in listed.stdout  # every figure name is listed


def test_a_resolved_config_with_a_swept_key_loads_again():
    """`--sweep` over a key the file sets wrote that value under params in the run's
    config.yaml, which the set-and-swept check then refused to load."""
    config = load(ROOT / "configs" / "passive_scale.yaml", {}, {"pga.ops": [1000, 20000]})
    assert config.params["pga.ops"] == config.experiment.schema["pga.ops"].default
    again = build(config.to_dict(), "config.yaml")
    assert again.to_dict() == config.to_dict()


@pytest.mark.parametrize("items, parse", [(["a=1", "a=2"], "sets"), (["a=1", "a=2,3"], "sweeps")])
def test_a_key_given_twice_on_the_command_line_is_refused(items, parse):
    """`--set k=1 --set k=2` kept the last value without a word."""
    with pytest.raises(SweepError, match="a: given twice"):
        (parse_sets if parse == "sets" else parse_sweeps)(items)


@pytest.mark.parametrize("key", ["trials", "seed", "batch_size"])
def test_a_top_level_key_cannot_be_swept_and_is_not_called_an_unknown_parameter(key):
    """`--sweep trials=1,2` said "unknown parameter of 'toy_gaussian'"."""
    raw = yaml.safe_load(CONFIG)
    with pytest.raises(ConfigError) as from_option:
        build(raw, "c.yaml", sweeps={key: [1, 2]})
    with pytest.raises(ConfigError) as from_file:
        build({**raw, "sweep": {key: [1, 2]}}, "c.yaml")
    for error, source, blamed in ((from_option.value, "--sweep", key),
                                  (from_file.value, "c.yaml", f"sweep.{key}")):
        assert (error.source, error.key) == (source, blamed)
        assert error.message.startswith("a top-level key cannot be swept")
        assert error.allowed.startswith("the parameters of 'toy_gaussian'")


def test_a_list_of_counts_takes_integers_and_a_list_of_choices_each_once():
    """pga.checkpoints=[1.5] ran as operation 1, and algorithms [exact, exact] as [exact]:
    `--sweep 'pga.checkpoints=[1.5],[1]'` gave two sweep points of the same run."""
    config = ROOT / "configs" / "ci" / "passive_assoc_ci.yaml"
    with pytest.raises(ConfigError) as counts:
        load(config, parse_sets(["pga.checkpoints=[1.5]"]))
    assert (counts.value.source, counts.value.key, counts.value.allowed) == \
        ("--set", "pga.checkpoints", "a non-empty list of integers in [0, 1e+07]")
    assert counts.value.message.startswith("got 1.5 in the list")
    with pytest.raises(ConfigError) as choices:
        load(config, {}, parse_sweeps(["algorithms=[exact],[exact,exact]"]))
    assert (choices.value.source, choices.value.key) == ("--sweep", "algorithms")
    assert choices.value.message.startswith("got ['exact', 'exact']")
    assert choices.value.allowed.startswith("a non-empty list drawn from exact, ")
    assert choices.value.allowed.endswith(", each at most once")
    resolved = trackfuse("run", config, "--dry-run", "--set", "pga.checkpoints=[0, 10.0]")
    assert resolved.returncode == 0, resolved.stderr
    assert yaml.safe_load(resolved.stdout.split("\n# ")[0])["params"]["pga.checkpoints"] == \
        [0, 10]


def test_a_quoted_override_stays_a_string_and_a_word_is_read_as_a_config_reads_it():
    """`--set mode='nan'` and `--set 'mode="nan"'` were refused though nan is an allowed
    choice (both became the float NaN); the same value in a config file was accepted."""
    import dataclasses

    from toy_experiments import GAUSSIAN

    from trackfuse.experiments.base import Param
    assert parse_sets(["a=nan", "b='nan'", 'c="1.5"', "d=1e-3", "e=inf", "f=2"]) == \
        {"a": "nan", "b": "nan", "c": "1.5", "d": 0.001, "e": "inf", "f": 2}
    mode = Param("mode", "zero", "what to fill with", "", kind=str, choices=("zero", "nan"))
    experiment = dataclasses.replace(GAUSSIAN, params=(*GAUSSIAN.params, mode))
    for given in ("mode=nan", "mode='nan'", 'mode="nan"'):
        config = build({"experiment": experiment.name, "trials": 2}, "cfg.yaml",
                       parse_sets([given]), experiment=experiment)
        assert config.params["mode"] == "nan", given
