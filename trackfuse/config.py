"""Load a YAML scenario config, apply command-line overrides, and validate it
(``docs/configs.md``). Every problem is one :class:`ConfigError` line naming the file (or
option), the dotted key, what was given and what is allowed::

    configs/x.yaml: params.clutter.mean: got -1; allowed: a number >= 0"""

from __future__ import annotations

import difflib
import math
import os
import re
import reprlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from trackfuse import experiments
from trackfuse.cluster_settings import SETTING_KEYS, ClusterSettings, settings_problem
from trackfuse.cluster_settings import settings as cluster_settings
from trackfuse.experiments.base import Experiment, Param
from trackfuse.regular_files import NotARegularFile
from trackfuse.results import MANIFEST
from trackfuse.safe_yaml import YamlInputError, read_yaml_file
from trackfuse.sequential import SequentialRule
from trackfuse.store import STORES, parquet_problem
from trackfuse.sweep import MAX_POINTS, SweepError, count_points, parse_axis_values

TOP_LEVEL = ("experiment", "title", "trials", "seed", "batch_size", "params", "sweep",
             "sweep_mode", "outputs", "trial_timeout", "cluster")
OUTPUT_KEYS = ("figures", "formats", "store")
FORMATS = ("png", "pdf", "svg")
MAX_TRIALS = 10**9


class ConfigError(ValueError):
    """A config problem; ``str(err)`` is the one line shown: ``source: key: got X; allowed: Y``."""

    def __init__(self, source: str, key: str, message: str):
        self.source, self.key, self.message = source, key, message
        text = f"{source}: {key}: {message}" if key else f"{source}: {message}"
        super().__init__("".join(c if c.isprintable() else repr(c)[1:-1] for c in text))

    @property
    def allowed(self) -> str:
        """What the key accepts, as the message states it after ``allowed:`` ('' if none)."""
        _, said, allowed = self.message.rpartition("; allowed: ")
        return allowed if said else ""

    @property
    def suggestion(self) -> str:
        """The closest valid name the message offers (``did you mean 'x'?``), or ''."""
        found = re.search(r"did you mean '([^']*)'\?", self.message)
        return found.group(1) if found else ""


@dataclass
class Config:
    """A validated config. ``params`` holds every schema key (defaults filled in)."""

    source: str
    experiment: Experiment
    title: str
    trials: int
    seed: int
    batch_size: int
    params: dict[str, Any]
    sweep: dict[str, list[Any]]
    sweep_mode: str
    figures: list[str] | str = "all"
    formats: list[str] = field(default_factory=lambda: ["png", "pdf"])
    reference: str = ""
    #: Seconds a trial may run before it is failed (``None``: no limit); not part of the
    #: run id: it decides only whether a hung trial ends the run or fails.
    trial_timeout: float | None = None
    #: Where the trial rows are kept: ``"csv"`` or ``"parquet"`` (:mod:`trackfuse.store`).
    store: str = STORES[0]
    #: The sequential rule when ``trials`` is one (``trials`` is then its ``max``).
    sequential: SequentialRule | None = None
    #: The ``cluster`` section (``--cluster``); where a run computes is not in its run id.
    cluster: ClusterSettings = field(default_factory=ClusterSettings)

    @property
    def experiment_ref(self) -> str:
        """How the config named its experiment (a registered name or ``module:ATTR``)."""
        return self.reference or self.experiment.name

    def to_dict(self) -> dict[str, Any]:
        """The resolved config as plain data (what ``config.yaml`` of a run holds)."""
        return {
            "experiment": self.experiment_ref,
            "title": self.title,
            "trials": self.sequential.as_config() if self.sequential else self.trials,
            "seed": self.seed,
            "batch_size": self.batch_size,
            "params": dict(self.params),
            "sweep": {k: list(v) for k, v in self.sweep.items()},
            "sweep_mode": self.sweep_mode,
            "outputs": {"figures": self.figures, "formats": list(self.formats),
                        # only when not the default: a CSV run keeps the run id it had
                        **({"store": self.store} if self.store != STORES[0] else {})},
            **({} if self.trial_timeout is None else {"trial_timeout": self.trial_timeout}),
        }


def did_you_mean(word: str, options) -> str:
    """``"; did you mean 'x'?"`` for the closest option, or ``""``."""
    close = difflib.get_close_matches(str(word), [str(o) for o in options], n=1, cutoff=0.6)
    return f"; did you mean '{close[0]}'?" if close else ""


_SHORT = reprlib.Repr()
for _limit, _value in (("maxlevel", 3), ("maxtuple", 4), ("maxlist", 4), ("maxdict", 4),
                       ("maxset", 4), ("maxstring", 58), ("maxlong", 40), ("maxother", 58)):
    setattr(_SHORT, _limit, _value)


#: What a mistyped config key looks like (echoed in a did-you-mean); anything else is
#: not echoed.
_KEY_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_.-]{0,39}$")


def _check_top_level(source: str, raw: dict[Any, Any]) -> None:
    """Refuse an unknown top-level key with a did-you-mean; a file whose keys are not key names is
    not a config and is refused without echoing its text."""
    for key in raw:
        if key not in TOP_LEVEL and not (isinstance(key, str) and _KEY_NAME.match(key)):
            raise ConfigError(source, "", "not a trackfuse config: a top-level key is not a "
                              f"key name; allowed: a YAML mapping of {', '.join(TOP_LEVEL)}")
        if key not in TOP_LEVEL:
            raise ConfigError(source, str(key), "unknown top-level key"
                              f"{did_you_mean(key, TOP_LEVEL)}; allowed: {', '.join(TOP_LEVEL)}")


def _describe(value: Any) -> str:
    """A repr of ``value`` cut to 60 characters, never rendering more than it prints."""
    try:
        text = _SHORT.repr(value)
    except (ValueError, RecursionError):  # e.g. an int too long to convert to text
        text = f"<{type(value).__name__}>"
    return text if len(text) <= 60 else text[:57] + "..."


def allowed_text(p: Param) -> str:
    if p.choices is not None:
        options = ", ".join(str(c) for c in p.choices)
        if p.kind is list:
            return f"a non-empty list drawn from {options}, each at most once"
        return f"one of {options}"
    numbers = "integers" if p.item_kind is int else "numbers"
    names = {float: "a number", int: "an integer", bool: "true or false", str: "a string",
             list: f"a non-empty list of {numbers}" if p.length is None
             else f"a list of {p.length} {numbers}"}
    text = names.get(p.kind, p.kind.__name__)
    if p.low is not None and p.high is not None:
        text += f" in [{p.low:g}, {p.high:g}]"
    elif p.low is not None:
        text += f" >= {p.low:g}"
    elif p.high is not None:
        text += f" <= {p.high:g}"
    return text


def _scalar(p: Param, value: Any, kind: type) -> Any:
    """Coerce one scalar to ``kind`` and check it; raise ``ValueError`` if not allowed."""
    if kind is bool:
        if isinstance(value, bool):
            return value
        raise ValueError
    if kind is str or (p.choices is not None and all(isinstance(c, str) for c in p.choices)):
        if not isinstance(value, str) or (p.choices is not None and value not in p.choices):
            raise ValueError
        return value
    if isinstance(value, bool):
        raise ValueError
    if isinstance(value, str):
        value = float(value.strip())
    if not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError
    if kind is int:
        if float(value) != int(value):
            raise ValueError
        value = int(value)
    else:
        value = float(value)
    if (p.low is not None and value < p.low) or (p.high is not None and value > p.high):
        raise ValueError
    if p.choices is not None and value not in p.choices:
        raise ValueError
    return value


def _element_kind(p: Param) -> type:
    """The type of each item of a list parameter."""
    return str if p.choices is not None and isinstance(p.choices[0], str) else p.item_kind


def check_value(p: Param, value: Any) -> Any:
    """Return ``value`` coerced to the parameter's type, or raise ``ValueError``."""
    if p.kind is list:
        items = value if isinstance(value, list) else [value]
        if not items or (p.length is not None and len(items) != p.length):
            raise ValueError
        coerced = [_scalar(p, v, _element_kind(p)) for v in items]
        if p.choices is not None and len(set(coerced)) < len(coerced):
            raise ValueError  # [exact, exact]: a sweep point equal to [exact]
        return coerced
    return _scalar(p, value, p.kind)


def flatten(mapping: Mapping, prefix: str = "") -> dict[str, Any]:
    """Flatten nested mappings into dotted keys (``{a: {b: 1}} -> {"a.b": 1}``); :class:`KeyError`
    for a key two spellings give (``a.b: 1`` beside ``a: {b: 2}``)."""
    flat: dict[str, Any] = {}
    for key, value in mapping.items():
        dotted = f"{prefix}{key}"
        items = flatten(value, dotted + ".") if isinstance(value, Mapping) and value \
            else {dotted: value}
        for name, item in items.items():
            if name in flat:
                raise KeyError(name)
            flat[name] = item
    return flat


def _validated(source: str, exp: Experiment, where: str, key: str, value: Any) -> Any:
    """``value`` checked against parameter ``key``; errors name ``source`` and ``where.key``."""
    p = exp.schema.get(key)
    if p is None:
        raise ConfigError(source, _dotted(where, key),
                          f"unknown parameter of '{exp.name}'{did_you_mean(key, exp.schema)}"
                          f" (see `trackfuse list {experiments.reference(exp)}`)")
    try:
        return check_value(p, value)
    except (ValueError, TypeError, OverflowError):
        raise ConfigError(source, _dotted(where, key),
                          f"got {_bad_part(p, value)}; allowed: {allowed_text(p)}"
                          f"{_sweep_hint(source, p, value)}") from None


def _sweep_hint(source: str, p: Param, value: Any) -> str:
    """A hint to sweep a parameter given several values by ``--set``, else ``""``."""
    if source != SET or p.kind is list:
        return ""
    if isinstance(value, list) and len(value) > 1:
        values = ",".join(map(str, value))
    elif isinstance(value, str) and "," in value:
        values = value
    else:
        return ""
    return f"; to run each value, sweep it: --sweep {p.key}={values}"


def _bad_part(p: Param, value: Any) -> str:
    """``value`` described for an error: a list by its first bad item, with a did-you-mean."""
    if p.kind is not list or not isinstance(value, list) or not value:
        return _describe(value)
    for item in value:
        try:
            _scalar(p, item, _element_kind(p))
        except (ValueError, TypeError, OverflowError):
            hint = did_you_mean(item, p.choices) \
                if isinstance(item, str) and p.choices else ""
            return f"{_describe(item)} in the list{hint}"
    return _describe(value)


def _int(source: str, key: str, value: Any, low: int, high: int = MAX_TRIALS) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise ConfigError(source, key,
                          f"got {_describe(value)}; allowed: an integer in [{low}, {high}]")
    return value


SEQUENTIAL_KEYS, UNTIL_KEYS = ("min", "max", "until"), ("metric", "half_width")


def _trials(source: str, exp: Experiment, value: Any) -> tuple[int, SequentialRule | None]:
    """``trials``: a count, or a sequential rule whose ``max`` is the count planned."""
    if not isinstance(value, Mapping):
        return _int(source, "trials", value, 1), None
    _known_keys(source, "trials", value, SEQUENTIAL_KEYS)
    until = value.get("until")
    if not isinstance(until, Mapping):
        raise ConfigError(source, "trials.until", f"got {_describe(until)}; allowed: a mapping "
                                                  "{metric: NAME, half_width: NUMBER}")
    _known_keys(source, "trials.until", until, UNTIL_KEYS)
    low = _int(source, "trials.min", value.get("min"), 2)
    high = _int(source, "trials.max", value.get("max"), low)
    names = [m.name for m in exp.metrics if not m.categorical]
    metric = until.get("metric")
    if metric not in names:
        raise ConfigError(source, "trials.until.metric", f"got {_describe(metric)}"
                          f"{did_you_mean(metric, names)}; allowed: "
                          f"{', '.join(names) or 'none (the experiment declares no metric)'}")
    width = until.get("half_width")
    if isinstance(width, bool) or not isinstance(width, (int, float)) \
            or not 0 < width < math.inf:
        raise ConfigError(source, "trials.until.half_width", f"got {_describe(width)}; "
                          "allowed: a number > 0 (in the metric's unit)")
    return high, SequentialRule(low, high, str(metric), float(width))


def _known_keys(source: str, key: str, mapping: Mapping, allowed: tuple[str, ...]) -> None:
    for name in mapping:
        if name not in allowed:
            raise ConfigError(source, f"{key}.{name}", f"unknown key{did_you_mean(name, allowed)}"
                                                       f"; allowed: {', '.join(allowed)}")


SET, SWEEP = "--set", "--sweep"
"""The source named by errors in command-line overrides (not the YAML file they override)."""
OVERRIDABLE_TOP_LEVEL = ("trials", "seed", "batch_size", "title", "sweep_mode", "trial_timeout")
#: The longest trial time limit (s): a day (``setitimer`` takes any float, a typo does not).
MAX_TRIAL_TIMEOUT = 86_400.0


def build(raw: Any, source: str, sets: Mapping[str, Any] | None = None,
          sweeps: Mapping[str, Any] | None = None, *,
          experiment: Experiment | None = None) -> Config:
    """Validate a parsed YAML document plus ``sets`` (``--set``; a swept key loses its axis) and
    ``sweeps`` (``--sweep``) into a :class:`Config`, blaming the option, not the file.
    ``experiment`` bypasses the lookup of ``raw["experiment"]``."""
    if raw is None:
        raise ConfigError(source, "", "the file is empty; expected a mapping with at least "
                                      "'experiment'")
    if not isinstance(raw, Mapping):
        raise ConfigError(source, "", f"expected a mapping at the top level, got "
                                      f"{type(raw).__name__}")
    raw = dict(raw)
    _check_top_level(source, raw)
    sets = dict(sets or {})
    origin = {key: source for key in TOP_LEVEL}
    for key in [k for k in sets if k in OVERRIDABLE_TOP_LEVEL]:
        raw[key], origin[key] = sets.pop(key), SET

    if experiment is not None:
        raw["experiment"] = experiment.name
    name = raw.get("experiment")
    exp = experiment or _experiment(source, name)

    title = raw.get("title", exp.title)
    if not isinstance(title, str):
        raise ConfigError(origin["title"], "title", f"got {_describe(title)}; allowed: a string")
    trials, sequential = _trials(origin["trials"], exp, raw.get("trials", 1))
    seed = _int(origin["seed"], "seed", raw.get("seed", 0), 0, 2**63 - 1)
    batch_size = _int(origin["batch_size"], "batch_size", raw.get("batch_size", exp.batch_size),
                      1, 10**6)
    params = _params(source, exp, raw.get("params") or {})
    for key, value in sets.items():
        params[key] = _validated(SET, exp, "", key, value)
    sweep = _sweep(source, exp, raw.get("sweep") or {}, dict(sweeps or {}), dropped=set(sets))
    _check_set_once(source, exp, params, raw.get("params") or {}, raw.get("sweep") or {},
                    overridden={*sets, *(sweeps or {})})
    for key in sweep:  # the sweep's values are used: the resolved config holds no other
        params[key] = exp.schema[key].default
    mode = _sweep_mode(origin["sweep_mode"], raw.get("sweep_mode", "grid"), sweep)
    _check_distinct(source, sweep, mode, set(sweeps or {}))
    if count_points(sweep, mode) > MAX_POINTS:
        raise ConfigError(source, "sweep", f"the {mode} has {count_points(sweep, mode)} points;"
                                           f" allowed: at most {MAX_POINTS}")
    figures, formats = _outputs(source, exp, raw.get("outputs") or {})
    store = _store(source, (raw.get("outputs") or {}).get("store", STORES[0]))
    cluster = _cluster(source, raw.get("cluster") or {})
    _check_experiment(exp, params, sweep, mode, source, set(sets), set(sweeps or {}))
    return Config(source, exp, title, trials, seed, batch_size, params, sweep, mode, figures,
                  formats, name, _trial_timeout(origin["trial_timeout"], raw.get("trial_timeout")),
                  store, sequential, cluster)


def _trial_timeout(source: str, value: Any) -> float | None:
    """The trial time limit (s) given as ``trial_timeout``, ``None`` when not given."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, int | float) or \
            not 0 < value <= MAX_TRIAL_TIMEOUT:
        raise ConfigError(source, "trial_timeout", f"got {_describe(value)}; allowed: seconds, "
                                                   f"a number in (0, {MAX_TRIAL_TIMEOUT:g}]")
    return float(value)


def _check_experiment(exp: Experiment, params: dict[str, Any], sweep: dict[str, list[Any]],
                      mode: str, source: str, sets: set[str], sweeps: set[str]) -> None:
    """``Experiment.check``, its problem blamed where the key's value came from."""
    problem = exp.check(params, sweep, mode) if exp.check is not None else None
    if problem is None:
        return
    key, message = problem
    if key in sweeps or key in sets:
        raise ConfigError(SWEEP if key in sweeps else SET, key, message)
    raise ConfigError(source, _dotted("sweep" if key in sweep else "params", key), message)


def _params(source: str, exp: Experiment, params_raw: Any) -> dict[str, Any]:
    """Every schema parameter: the defaults, overridden by the config's ``params``."""
    if not isinstance(params_raw, Mapping):
        raise ConfigError(source, "params", f"got {_describe(params_raw)}; allowed: a mapping "
                                            "of parameter names to values")
    params = exp.defaults()
    _check_key_names(source, "params", exp, params_raw)
    try:
        given = flatten(params_raw)
    except KeyError as err:
        raise ConfigError(source, f"params.{err.args[0]}", "given twice (dotted and nested); "
                                                           "allowed: one of the two") from None
    for key, value in given.items():
        params[key] = _validated(source, exp, "params", str(key), value)
    return params


def _check_key_names(source: str, section: str, exp: Experiment, mapping: Mapping,
                     prefix: str = "") -> None:
    """Refuse a key that is not a string (YAML's ``~:`` or ``1:``) at any depth of
    ``mapping``, naming it as written."""
    for key, value in mapping.items():
        if not isinstance(key, str):
            got = "a null key (~)" if key is None else f"the key {_describe(key)}"
            raise ConfigError(source, section + (f".{prefix[:-1]}" if prefix else ""),
                              f"got {got}; allowed: parameter names of '{exp.name}' (see "
                              f"`trackfuse list {experiments.reference(exp)}`)")
        if isinstance(value, Mapping):
            _check_key_names(source, section, exp, value, f"{prefix}{key}.")


def _sweep(source: str, exp: Experiment, sweep_raw: Any, sweeps: dict[str, Any],
           dropped: set[str]) -> dict[str, list[Any]]:
    """Every sweep axis (the config's, replaced by ``--sweep``, less keys ``--set`` fixed),
    validated."""
    if not isinstance(sweep_raw, Mapping):
        raise ConfigError(source, "sweep", f"got {_describe(sweep_raw)}; allowed: a mapping of "
                                           "parameter names to value lists or 'range(a, b, s)'")
    _check_key_names(source, "sweep", exp, sweep_raw)
    axes = {str(k): (source, "sweep", v) for k, v in sweep_raw.items()}
    axes.update({str(k): (SWEEP, "", v) for k, v in sweeps.items()})
    sweep: dict[str, list[Any]] = {}
    for key, (where, section, spec) in axes.items():
        if key in dropped:
            continue
        if key in TOP_LEVEL and key not in exp.schema:  # not "unknown parameter"
            raise ConfigError(where, _dotted(section, key), "a top-level key cannot be swept "
                              f"(one value per run: set it, or run once per value); allowed: "
                              f"the parameters of '{exp.name}' (see "
                              f"`trackfuse list {experiments.reference(exp)}`)")
        if key not in exp.schema:
            _validated(where, exp, section, key, None)
        try:
            values = parse_axis_values(spec)
        except SweepError as err:
            raise ConfigError(where, _dotted(section, key), str(err)) from None
        sweep[key] = [_validated(where, exp, section, key, v) for v in values]
    return sweep


def _check_set_once(source: str, exp: Experiment, params: Mapping[str, Any],
                    params_raw: Mapping, sweep_raw: Mapping, overridden: set[str]) -> None:
    """Refuse a file that both sets a parameter away from its default and sweeps it."""
    flat = flatten(params_raw)
    both = [key for key in map(str, sweep_raw) if key in flat and key not in overridden
            and params[key] != exp.schema[key].default]
    if both:
        raise ConfigError(source, f"params.{both[0]}", f"also swept (sweep.{both[0]}), whose "
                          "values would be used and this one never; allowed: the key under "
                          "params or under sweep, not both")


def _dotted(section: str, key: str) -> str:
    return f"{section}.{key}" if section else key


def _sweep_mode(source: str, mode: Any, sweep: dict[str, list[Any]]) -> str:
    """``grid`` or ``zip`` (whose axes must have equal lengths)."""
    if mode not in ("grid", "zip"):
        raise ConfigError(source, "sweep_mode", f"got {_describe(mode)}; allowed: grid, zip")
    if mode == "zip" and len({len(v) for v in sweep.values()}) > 1:
        lengths = ", ".join(f"{k}={len(v)}" for k, v in sweep.items())
        raise ConfigError(source, "sweep", f"zip needs axes of equal length, got {lengths}")
    return mode


def _check_distinct(source: str, sweep: dict[str, list[Any]], mode: str,
                    from_options: set[str]) -> None:
    """Refuse a sweep with two equal points (a repeated grid value or zipped combination), which
    would be read as two settings."""
    if mode == "zip":
        seen: set[str] = set()
        for values in zip(*sweep.values(), strict=True):
            text = repr(values)
            if text in seen:
                got = ", ".join(f"{k}={v!r}" for k, v in zip(sweep, values, strict=True))
                raise ConfigError(source, "sweep", f"the point {got} comes twice; allowed: "
                                                   "distinct points")
            seen.add(text)
        return
    for key, values in sweep.items():
        seen = set()
        for value in values:
            if repr(value) in seen:
                where, section = (SWEEP, "") if key in from_options else (source, "sweep")
                raise ConfigError(where, _dotted(section, key), f"got {value!r} twice; "
                                                                "allowed: distinct values")
            seen.add(repr(value))


def _allowed_experiments() -> str:
    return ", ".join(experiments.names()) + ", or package.module:ATTRIBUTE"


def unknown_experiment(name: str) -> str:
    """The error for a name that is neither an experiment nor a plugin: the closest name, and what
    is allowed."""
    return (f"unknown experiment {_describe(name)}{did_you_mean(name, experiments.names())}"
            f"; allowed: {_allowed_experiments()}")


def _experiment(source: str, name: Any) -> Experiment:
    """The experiment a config names (a registered name or ``package.module:ATTR``)."""
    allowed = _allowed_experiments()
    if name is None:
        raise ConfigError(source, "experiment", f"missing; allowed: {allowed}")
    if not isinstance(name, str):
        raise ConfigError(source, "experiment", f"got {_describe(name)}; allowed: {allowed}")
    try:
        return experiments.get(name)
    except experiments.UnknownExperiment:
        raise ConfigError(source, "experiment", unknown_experiment(name)) from None
    except experiments.PluginError as err:
        raise ConfigError(source, "experiment", str(err)) from None


def _outputs(source: str, exp: Experiment, outputs: Any) -> tuple[list[str] | str, list[str]]:
    if not isinstance(outputs, Mapping):
        raise ConfigError(source, "outputs", f"got {_describe(outputs)}; allowed: a mapping "
                                             "with 'figures' and 'formats'")
    for key in outputs:
        if key not in OUTPUT_KEYS:
            raise ConfigError(source, f"outputs.{key}", "unknown key"
                              f"{did_you_mean(key, OUTPUT_KEYS)}; allowed: "
                              f"{', '.join(OUTPUT_KEYS)}")
    figures = outputs.get("figures", "all")
    if figures != "all" and not (isinstance(figures, list)
                                 and all(isinstance(f, str) for f in figures)):
        raise ConfigError(source, "outputs.figures",
                          f"got {_describe(figures)}; allowed: 'all' or a list of figure names")
    for name in figures if isinstance(figures, list) else []:
        if name not in exp.figures:
            known = ", ".join(exp.figures) or "none (the experiment draws no figures)"
            raise ConfigError(source, "outputs.figures", f"unknown figure {_describe(name)}"
                              f"{did_you_mean(name, list(exp.figures))}; allowed: {known}")
    formats = outputs.get("formats", ["png", "pdf"])
    if isinstance(formats, str):
        formats = [formats]
    if not isinstance(formats, list) or not formats or any(f not in FORMATS for f in formats):
        raise ConfigError(source, "outputs.formats",
                          f"got {_describe(formats)}; allowed: a list of {', '.join(FORMATS)}")
    return figures, formats


def _cluster(source: str, section: Any) -> ClusterSettings:
    """The ``cluster`` section (:mod:`trackfuse.cluster_settings`), checked."""
    if not isinstance(section, Mapping):
        raise ConfigError(source, "cluster", f"got {_describe(section)}; allowed: a mapping of "
                                             f"{', '.join(SETTING_KEYS)}")
    if problem := settings_problem(dict(section)):
        key, allowed = problem
        got = "" if allowed.startswith("unknown") else \
            f"got {_describe(section.get(key))}; allowed: "
        raise ConfigError(source, f"cluster.{key}", got + allowed)
    return cluster_settings(dict(section))


def _store(source: str, store: Any) -> str:
    """``outputs.store``: one of :data:`~trackfuse.store.STORES`, Parquet only with pyarrow."""
    if store not in STORES:
        raise ConfigError(source, "outputs.store", f"got {_describe(store)}; allowed: "
                                                   f"{', '.join(STORES)}")
    if store == "parquet" and (problem := parquet_problem()):
        raise ConfigError(source, "outputs.store", f"{problem}; allowed without it: csv")
    return store


def read_yaml(path: str | Path) -> Any:
    """Parse a YAML config file, every problem a :class:`ConfigError`; a run folder's
    ``config.yaml`` must be a regular file."""
    in_run_folder = os.path.lexists(Path(path).parent / MANIFEST)
    try:
        return read_yaml_file(path, regular_only=in_run_folder)
    except NotARegularFile as err:
        raise ConfigError(str(path), "", f"{err.strerror}, in a run folder; allowed: a YAML "
                                         "config file") from None
    except FileNotFoundError:
        raise ConfigError(str(path), "", "no such file") from None
    except IsADirectoryError:
        raise ConfigError(str(path), "", "a folder; allowed: a YAML config file (a run "
                                         "folder keeps its config as config.yaml)") from None
    except OSError as err:
        raise ConfigError(str(path), "", f"cannot read: {err.strerror or type(err).__name__}"
                          ) from None
    except YamlInputError as err:
        raise ConfigError(str(path), "", str(err)) from None


def load(path: str | Path, sets: Mapping[str, Any] | None = None,
         sweeps: Mapping[str, Any] | None = None) -> Config:
    """Read, override and validate the config at ``path``."""
    return build(read_yaml(path), str(path), sets, sweeps)
