"""Config validation: good configs resolve; every bad one is a one-line error, exit 2."""

from __future__ import annotations

import pytest
from conftest import trackfuse

from trackfuse.config import TOP_LEVEL, ConfigError, build, load

GOOD = """
experiment: toy_experiments:GAUSSIAN
trials: 4
seed: 3
params: {sigma: 2.5, n: 3}
sweep:
  mu: range(0, 1, 0.25)
  label: [a, b]
"""


def test_good_config_resolves_defaults_and_sweep(write_config):
    cfg = load(write_config(GOOD))
    assert cfg.params["sigma"] == 2.5 and cfg.params["p_d"] == 0.9
    assert cfg.sweep == {"mu": [0.0, 0.25, 0.5, 0.75], "label": ["a", "b"]}
    assert cfg.batch_size == 7  # the experiment's default


def test_nested_params_and_overrides(write_config):
    cfg = load(write_config(GOOD), sets={"mu": 1.5, "trials": 9}, sweeps={"n": "range(1,3)"})
    assert "mu" not in cfg.sweep and cfg.params["mu"] == 1.5  # --set removes the axis
    assert cfg.trials == 9 and cfg.sweep["n"] == [1, 2]


PARAMS_OF_TOY = "parameter names of 'toy_gaussian' (see `trackfuse list toy_gaussian`)"

# case: (config text, the key blamed, what the error says is allowed ('' when the problem
# has no list of allowed values), the closest name it offers, what it says otherwise)
BAD = {
    "bad_yaml": ("experiment: [unclosed", "", "", "", "invalid YAML: line 1"),
    "empty_file": ("", "", "", "", "the file is empty"),
    "not_mapping": ("- 1\n- 2", "", "", "", "expected a mapping"),
    "unknown_top_key": ("experiment: toy_gaussian\ntrails: 5", "trails",
                        ", ".join(TOP_LEVEL), "trials", ""),
    "unknown_param": ("experiment: toy_gaussian\nparams: {sigam: 1}", "params.sigam", "",
                      "sigma", "unknown parameter"),
    "wrong_type": ("experiment: toy_gaussian\nparams: {n: many}", "params.n",
                   "an integer >= 1", "", ""),
    "negative_sigma": ("experiment: toy_gaussian\nparams: {sigma: -0.1}", "params.sigma",
                       "a number >= 0", "", ""),
    "probability": ("experiment: toy_gaussian\nparams: {p_d: 1.2}", "params.p_d",
                    "a number in [0, 1]", "", ""),
    "unknown_experiment": ("experiment: toy_gausian", "experiment", "EXPERIMENTS",
                           "toy_gaussian", ""),
    "missing_experiment": ("trials: 3", "experiment", "EXPERIMENTS", "", "missing"),
    "empty_sweep": ("experiment: toy_gaussian\nsweep: {mu: []}", "sweep.mu",
                    "a non-empty list or 'range(a, b, s)'", "", ""),
    "empty_range": ("experiment: toy_gaussian\nsweep: {mu: 'range(5, 1)'}", "sweep.mu", "",
                    "", "the range is empty"),
    "zero_step": ("experiment: toy_gaussian\nsweep: {mu: 'range(0, 1, 0)'}", "sweep.mu", "",
                  "", "must not be 0"),
    "negative_trials": ("experiment: toy_gaussian\ntrials: -5", "trials",
                        "an integer in [1, 1000000000]", "", ""),
    "bool_as_number": ("experiment: toy_gaussian\nparams: {mu: true}", "params.mu",
                       "a number", "", "got True"),
    "bad_choice": ("experiment: toy_gaussian\nsweep: {label: [a, c]}", "sweep.label",
                   "one of a, b", "", "got 'c'"),
    "zip_lengths": ("experiment: toy_gaussian\nsweep_mode: zip\nsweep: {mu: [1, 2], n: [1]}",
                    "sweep", "", "", "zip needs axes of equal length"),
    "nan": ("experiment: toy_gaussian\nparams: {mu: .nan}", "params.mu", "a number", "",
            "got nan"),
    "bad_format": ("experiment: toy_gaussian\noutputs: {formats: [gif]}", "outputs.formats",
                   "a list of png, pdf, svg", "", ""),
    "params_not_mapping": ("experiment: toy_gaussian\nparams: [1, 2]", "params",
                           "a mapping of parameter names to values", "", ""),
    # a null key read as the unknown parameter 'params.None'
    "null_param_key": ("experiment: toy_gaussian\nparams: {~: 1}", "params", PARAMS_OF_TOY,
                       "", "null key"),
    "null_nested_key": ("experiment: toy_gaussian\nparams: {a: {~: 1}}", "params.a",
                        PARAMS_OF_TOY, "", "null key"),
    "number_sweep_key": ("experiment: toy_gaussian\nsweep: {1: [1, 2]}", "sweep", PARAMS_OF_TOY,
                         "", "the key 1"),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_config_names_file_key_and_what_is_allowed(case, write_config):
    text, key, allowed, suggestion, says = BAD[case]
    path = write_config(text, case)
    with pytest.raises(ConfigError) as err:
        load(path)
    error = err.value
    assert (error.source, error.key, error.suggestion) == (str(path), key, suggestion)
    if allowed == "EXPERIMENTS":
        assert error.allowed.startswith("twin_sensor, esm_radar, passive_assoc, ")
        assert error.allowed.endswith(", or package.module:ATTRIBUTE")
    else:
        assert error.allowed == allowed
    assert says in error.message and "\n" not in str(error)


def test_a_config_error_reads_file_key_got_and_allowed(write_config):
    """The one message family every config error follows (README, docs/configs.md)."""
    path = write_config(BAD["negative_sigma"][0])
    with pytest.raises(ConfigError) as err:
        load(path)
    assert str(err.value) == f"{path}: params.sigma: got -0.1; allowed: a number >= 0"


@pytest.mark.parametrize("case", ["bad_yaml", "unknown_param", "negative_sigma", "empty_sweep",
                                  "unknown_experiment"])
def test_cli_reports_bad_config_in_one_line_exit_2(case, write_config):
    path = write_config(BAD[case][0], case)
    for command in (["validate", path], ["run", path, "--dry-run"]):
        result = trackfuse(*command)
        assert result.returncode == 2, result.stderr
        assert "Traceback" not in result.stderr + result.stdout
        lines = result.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith(f"error: {path}: ")


def test_cli_bad_override_and_missing_file(tmp_path, write_config):
    path = write_config(GOOD)
    result = trackfuse("validate", path, "--set", "sigma")
    assert result.returncode == 2 and "allowed: key=value" in result.stderr
    result = trackfuse("validate", path, "--set", "n=0")
    assert result.returncode == 2
    assert "error: --set: n: got 0; allowed: an integer >= 1" in result.stderr
    result = trackfuse("validate", tmp_path / "nope.yaml")
    assert result.returncode == 2 and "nope.yaml: no such file" in result.stderr


def test_every_top_level_value_type_is_checked():
    for key, value, blamed in [("title", 3, "title"), ("seed", -1, "seed"),
                               ("batch_size", 0, "batch_size"), ("sweep", [1], "sweep"),
                               ("outputs", {"figures": 3}, "outputs.figures"),
                               ("sweep_mode", "cartesian", "sweep_mode")]:
        with pytest.raises(ConfigError) as err:
            build({"experiment": "toy_gaussian", key: value}, "x.yaml")
        assert (err.value.source, err.value.key) == ("x.yaml", blamed)
        assert err.value.allowed, str(err.value)


def test_a_parameter_given_dotted_and_nested_is_refused_and_an_override_is_not(write_config):
    """``clutter.mean: 3`` beside ``clutter: {mean: 4}`` validated, and the later one won
    unseen (4, or 3 with the order reversed); a literal duplicate key was refused already.
    A ``--set`` of a key the file gives once (either spelling) stays an override."""
    dotted_first = "params:\n  clutter.mean: 3\n  clutter:\n    mean: 4\n"
    nested_first = "params:\n  clutter:\n    mean: 4\n  clutter.mean: 3\n"
    for name, params in (("dotted_first", dotted_first), ("nested_first", nested_first)):
        path = write_config(f"experiment: twin_sensor\ntrials: 4\n{params}", name)
        with pytest.raises(ConfigError) as err:
            load(path)
        assert (err.value.source, err.value.key, err.value.allowed) == \
            (str(path), "params.clutter.mean", "one of the two")
        assert err.value.message.startswith("given twice (dotted and nested)")
    for command in (["validate", path], ["run", path, "--dry-run"]):
        result = trackfuse(*command)
        assert result.returncode == 2, result.stdout
        assert len(result.stderr.splitlines()) == 1
        assert result.stderr.startswith(f"error: {path}: params.clutter.mean: given twice")
    with pytest.raises(ConfigError) as equal:  # equal values too
        build({"experiment": "twin_sensor", "params": {"clutter.mean": 3,
                                                       "clutter": {"mean": 3}}}, "x.yaml")
    assert equal.value.key == "params.clutter.mean"
    for name, params in (("nested", "{clutter: {mean: 4}}"), ("dotted", "{clutter.mean: 4}")):
        path = write_config(f"experiment: twin_sensor\ntrials: 4\nparams: {params}\n", name)
        assert load(path, sets={"clutter.mean": 5}).params["clutter.mean"] == 5
    result = trackfuse("run", path, "--dry-run", "clutter.mean=6")  # the command line's too
    assert result.returncode == 0 and "clutter.mean: 6.0" in result.stdout, result.stderr



def test_trial_timeout_is_seconds_left_out_of_the_resolved_config_unless_given():
    base = {"experiment": "toy_gaussian"}
    assert build(base, "c.yaml").trial_timeout is None
    assert "trial_timeout" not in build(base, "c.yaml").to_dict()  # config.yaml as before
    config = build({**base, "trial_timeout": 30}, "c.yaml")
    assert config.trial_timeout == 30.0 and config.to_dict()["trial_timeout"] == 30.0
    assert build(base, "c.yaml", sets={"trial_timeout": 2.5}).trial_timeout == 2.5
    for bad in (0, -1, True, "soon", float("nan"), 1e9):
        with pytest.raises(ConfigError) as caught:
            build({**base, "trial_timeout": bad}, "c.yaml")
        assert (caught.value.source, caught.value.key) == ("c.yaml", "trial_timeout")
