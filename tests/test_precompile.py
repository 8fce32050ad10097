"""Ahead-of-time compile (trackfuse.precompile, run when the wheel is built): it must compile
exactly the versions a run uses, else the shipped cache is never read."""

from numba import typeof

from trackfuse import precompile
from trackfuse.association import pga_search
from trackfuse.experiments import get
from trackfuse.experiments.passive_assoc.model import run_trial as passive_trial
from trackfuse.seeding import trial_streams
from trackfuse.tracking import ipda, pda


def argument_types(monkeypatch, module, name, call) -> set:
    """The numba types of every call ``call()`` makes to the compiled ``module.name``."""
    seen, compiled = set(), getattr(module, name)

    def record(*args):
        seen.add(tuple(typeof(a) for a in args))
        return compiled(*args)

    with monkeypatch.context() as m:
        m.setattr(module, name, record)
        call()
    return seen


def test_the_pda_filter_is_precompiled_for_the_types_a_run_passes(monkeypatch):
    experiment = get("twin_sensor")
    runs = set()
    for overrides in ({}, {"sensors.count": 1, "clutter.model": "window"}):
        params = {**experiment.defaults(), "clutter.mean": 3.0, **overrides}
        streams = [trial_streams(0, 0, t) for t in range(2)]
        runs |= argument_types(monkeypatch, pda, "_filter_batch",
                               lambda p=params, s=streams: experiment.run_batch(p, s))
    ahead = argument_types(monkeypatch, pda, "_filter_batch", precompile.load_pda_filter)
    assert len(ahead) == 1 and runs == ahead


def test_the_ipda_filter_is_precompiled_for_the_types_a_run_passes(monkeypatch):
    experiment = get("twin_sensor")
    runs = set()
    for overrides in ({}, {"sensors.count": 1, "clutter.model": "window"}):
        params = {**experiment.defaults(), "clutter.mean": 3.0, "algorithms": ["ipda/ekf"],
                  **overrides}
        streams = [trial_streams(0, 0, t) for t in range(2)]
        runs |= argument_types(monkeypatch, ipda, "_ipda_batch",
                               lambda p=params, s=streams: experiment.run_batch(p, s))
    ahead = argument_types(monkeypatch, ipda, "_ipda_batch", precompile.load_ipda_filter)
    assert len(ahead) == 1 and runs == ahead


def test_the_pga_search_is_precompiled_for_the_types_a_trial_passes(monkeypatch):
    params = get("passive_assoc").defaults()
    trial = argument_types(monkeypatch, pga_search, "_search",
                           lambda: passive_trial(params, trial_streams(0, 0, 0)))
    ahead = argument_types(monkeypatch, pga_search, "_search", precompile.load_pga)
    assert trial and trial == ahead
