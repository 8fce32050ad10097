"""Registry of experiment kinds, looked up by name.

Built-in experiments live in modules of this package; each exposes ``EXPERIMENT``. A config
may also name any importable experiment as ``"package.module:ATTRIBUTE"``.
"""

from __future__ import annotations

import importlib

from trackfuse.experiments.base import Experiment, Param

BUILTIN: dict[str, str] = {
    "twin_sensor": "trackfuse.experiments.twin_sensor",
    "esm_radar": "trackfuse.experiments.esm_radar",
    "passive_assoc": "trackfuse.experiments.passive_assoc",
}

_registered: dict[str, Experiment] = {}


class UnknownExperiment(KeyError):
    """Raised for a name that is neither built in, registered, nor ``module:attr``."""


def register(experiment: Experiment) -> Experiment:
    """Register an experiment defined outside this package (e.g. in tests)."""
    _registered[experiment.name] = experiment
    return experiment


def names() -> list[str]:
    """Every experiment name a config may use (built-in first)."""
    return list(BUILTIN) + sorted(n for n in _registered if n not in BUILTIN)


def get(name: str) -> Experiment:
    """Return the experiment called ``name``."""
    if name in _registered:
        return _registered[name]
    if name in BUILTIN:
        return importlib.import_module(BUILTIN[name]).EXPERIMENT
    if ":" in name:
        module, _, attr = name.partition(":")
        try:
            found = getattr(importlib.import_module(module), attr)
        except (ImportError, AttributeError) as err:
            raise UnknownExperiment(name) from err
        if isinstance(found, Experiment):
            return found
    raise UnknownExperiment(name)


__all__ = ["Experiment", "Param", "UnknownExperiment", "get", "names", "register"]
