"""Figures of the twin_sensor experiment (paper 000), drawn by the report kit.

Wang, Wang & Yang, "Fusion algorithm for airborne twin-sensor synchronous angle-only
tracking", Control and Decision 20(10), 2005. Every figure is a
:class:`~trackfuse.reportkit.spec.Plot` of the run's ``summary.csv`` drawn by
:func:`trackfuse.reportkit.render.draw` (journal slot, style, looks of
:data:`~trackfuse.experiments.twin_sensor.LOOKS`); this module only chooses, per run, what
each plot shows (which algorithms, which clutter levels, the paper's claim where the run is
at the paper's scenario) and draws the one thing a summary row cannot hold: the square-root
PCRLB, recomputed from the config by :func:`~trackfuse.experiments.twin_sensor.model.bounds`.
Captions: :data:`~trackfuse.experiments.twin_sensor.FIGURES`; the science:
``docs/papers/twin_sensor.md``. Tables: :mod:`.tables`.

A wanted figure that a run cannot draw is returned as a one-line reason (a ``str``).
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import replace
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from trackfuse.experiments.twin_sensor import FIG1, FIGURES
from trackfuse.experiments.twin_sensor.model import IPDA_ALGORITHMS, bounds
from trackfuse.experiments.twin_sensor.tables import (
    CLAIM,
    CLAIM_UP_TO,
    MAIN_RULE,
    at_paper,
    headline_pair,
    main_algorithms,
    tables,
)
from trackfuse.reportkit import render
from trackfuse.reportkit.spec import MAX_ENTRIES, Plot, Reference, Scale
from trackfuse.rundata import RunData, swept_keys
from trackfuse.stats import nees_band
from trackfuse.tracking.pda_options import METHODS

__all__ = ["fig1_headline", "figures", "prepare", "tables"]

FIG2_LEVELS = (0.0, 9.0, 15.0)
"""Clutter levels (mean false returns) of the Fig. 2 panels at the paper's scenario, the
nearest swept ones; a departure shows its lowest, middle and highest level."""
PER_KEY = 3
"""The most values of one swept key a time figure shows (at most 3 x 3 panels)."""
CLAIM_LABEL = "paper: < 5 % up to 9"
LAST = {"scan": "last"}
BOUND, BOUND_MODEL, BOUND_BOTH = ("√PCRLB (truth)", "√PCRLB (filter's q)",
                                  "√PCRLB (truth = filter's q)")
"""Legend labels of the bounds: the truth model's, the filter's ``q``'s, or one where they
differ by less than 1 %."""


def _fig_words(run: RunData, number: int) -> str:
    """"Paper Fig. n redrawn" at the paper's scenario with the paper's method run, else
    "Fig. n analogue"."""
    paper_method = any(a.startswith("paper_approx/") for a in run.params["algorithms"])
    return (f"Paper Fig. {number} redrawn" if at_paper(run).all() and paper_method
            else f"Fig. {number} analogue")


def _zipped(run: RunData) -> str:
    """A reason when the sweep zips several keys (no single swept axis), else ``""``."""
    keys = swept_keys(run.config)
    if run.config.get("sweep_mode", "grid") == "zip" and len(keys) > 1:
        return "no single axis: the sweep zips " + ", ".join(keys)
    return ""


def _curves(names: list[str], room: int = MAX_ENTRIES) -> tuple[str, ...]:
    """At most ``room`` of ``names``; beyond, the MGEKF and other filters' curves (the EKF's
    are in the Fig. 2 figures)."""
    if len(names) > room:
        names = [n for n in names if not n.endswith("/ekf")]
    return tuple(dict.fromkeys(names))[:room]


def _x_scale(values: list[Any]) -> Scale:
    """Symmetric-log for a grid whose two closest values are nearer than a tenth of its
    span while one gap takes 40 % of it (clutter 0, 10, 15, 20, 40, 50, 150: a linear axis
    piles the low values up), else linear (an even grid 0, 1, ..., 15)."""
    v = np.unique(np.asarray(values, dtype=float))
    if len(v) < 4 or v[0] < 0:
        return "linear"
    gaps, span = np.diff(v), v[-1] - v[0]
    return "symlog" if gaps.min() < 0.1 * span and gaps.max() >= 0.4 * span else "linear"


def _loss(run: RunData, plot: Plot, title: str) -> Figure | str:
    """A loss figure against clutter, or the reason the run has none."""
    if "clutter.mean" not in swept_keys(run.config):
        hint = "; see loss_vs_manoeuvring_index" if "target.q" in run.sweep else ""
        return "clutter.mean is not swept" + hint
    plot = replace(plot, xscale=_x_scale(run.sweep["clutter.mean"]))
    return _zipped(run) or render.draw(run, plot, title)


def _loss_main(run: RunData) -> Figure | str:
    """Fig. 1: tracks lost (angle rule) against clutter, the paper's method and ours, the
    paper's claim where the run is at its scenario with clutter in the gate."""
    claim = bool(at_paper(run).all()) and run.params["clutter.model"] == "in_gate"
    refs = (Reference(band=(0.0, CLAIM.value), until=CLAIM_UP_TO, label=CLAIM_LABEL),) \
        if claim else ()
    plot = Plot((MAIN_RULE,), "clutter.mean",
                tuple(main_algorithms(run.params["algorithms"])), refs, at=LAST)
    return _loss(run, plot, f"{_fig_words(run, 1)}: tracks lost against false returns")


def _loss_ablation(run: RunData) -> Figure | str:
    """Fig. 1 for every algorithm run (at most six curves: :func:`_curves`)."""
    algorithms = list(run.params["algorithms"])
    if not set(algorithms) - set(main_algorithms(algorithms)):
        return "no algorithm beyond loss_vs_clutter's was run"
    plot = Plot((MAIN_RULE,), "clutter.mean", _curves(algorithms), at=LAST)
    return _loss(run, plot, "Fig. 1 ablation: tracks lost against false returns")


def _existence(run: RunData) -> Figure | str:
    """IPDA's tracks terminated and confirmed against clutter beside every algorithm's
    losses (:data:`~trackfuse.experiments.twin_sensor.FIGURES`' declared plot)."""
    algorithms = list(run.params["algorithms"])
    ipda = [a for a in algorithms if a in IPDA_ALGORITHMS]
    if not ipda:
        return "no IPDA algorithm was run"
    plot = FIGURES["existence_vs_clutter"].plot  # IPDA's curves kept first of at most six
    plot = replace(plot, algorithms=_curves(ipda + main_algorithms(algorithms) + algorithms))
    return _loss(run, plot, "Track existence against false returns")


def _loss_flags(run: RunData) -> Figure | str:
    """The two filter-dependent flags against clutter, a row each."""
    plot = Plot(("lost_gate", "inconsistent_nees"), "clutter.mean",
                _curves(list(run.params["algorithms"])), at=LAST)
    return _loss(run, plot, "Diagnostic: filter-dependent flags against false returns")


def _loss_index(run: RunData) -> Figure | str:
    """Tracks lost (angle and gate rules) against the truth's q at its one clutter level
    (twin_sensor_hard: the filter's q zipped with it)."""
    if "target.q" not in run.sweep:
        return "target.q is not swept"
    levels = sorted({float(p["clutter.mean"]) for p in run.points} - {0.0})
    held = [p for p in run.points if float(p["clutter.mean"]) == (levels or [0.0])[0]]
    if len(levels) != 1 or len({p["target.q"] for p in held}) < 3:
        return "needs one non-zero clutter level and at least 3 target.q values"
    if any(p["target.q"] != p["filter.q"] for p in run.points):
        return "needs filter.q equal to target.q at every point"
    plot = Plot((MAIN_RULE, "lost_gate"), "target.q", _curves(list(run.params["algorithms"])),
                at={**LAST, "clutter.mean": levels[0]}, together=("filter.q",),
                xscale="symlog")
    return render.draw(run, plot, "Extension: tracks lost against the manoeuvring noise")


def _time_at(run: RunData) -> dict[str, Any]:
    """The settings a time figure shows (``Plot.at``): the clutter levels of
    :data:`FIG2_LEVELS` (a departure: lowest, middle, highest), at most :data:`PER_KEY`
    values of each other swept key (first, middle, last); every point of a zipped sweep."""
    if run.config.get("sweep_mode", "grid") == "zip":
        return {}
    held: dict[str, Any] = {}
    for key in (k for k in swept_keys(run.config) if k != "algorithms"):
        values = list(dict.fromkeys(run.sweep[key]))
        if all(isinstance(v, int | float) for v in values):
            values.sort()
        if key == "clutter.mean":
            wanted = FIG2_LEVELS if at_paper(run).all() else \
                (values[0], values[len(values) // 2], values[-1])
            held[key] = tuple(dict.fromkeys(min(values, key=lambda v, w=w: abs(float(v) - w))
                                            for w in wanted))
        elif len(values) > PER_KEY:
            held[key] = (values[0], values[len(values) // 2], values[-1])
    return held


def _matched_q(run: RunData) -> tuple[str, ...]:
    """``("filter.q",)`` when the filter's q is the truth's at every point and the truth's
    is swept (twin_sensor_hard): one key to the panels, the caption says they are equal."""
    matched = all(p["target.q"] == p["filter.q"] for p in run.points)
    return ("filter.q",) if matched and "target.q" in swept_keys(run.config) else ()


def _point_of(run: RunData, cell: dict[str, Any]) -> dict[str, Any]:
    """The parameters of the first sweep point at the panel setting ``cell``."""
    return next(p for p in run.points if all(p.get(k) == v for k, v in cell.items()))


def _bound_lines(ax: Axes, x: np.ndarray, truth: np.ndarray, model: np.ndarray) -> None:
    """The square-root PCRLB of the truth model (dashed) and of the filter's q (dotted), or
    one dash-dot curve where they differ by less than 1 % everywhere."""
    if np.all(np.abs(model - truth) <= 0.01 * truth):
        ax.plot(x, truth, color="k", linestyle="-.", linewidth=0.9, label=BOUND_BOTH)
        return
    ax.plot(x, truth, color="k", linestyle="--", linewidth=0.9, label=BOUND)
    ax.plot(x, model, color="k", linestyle=":", linewidth=1.0, label=BOUND_MODEL)


def _time_bounds(run: RunData) -> render.Decorate:
    """Draws the range bound of a time panel's point against the scan."""
    def decorate(ax: Axes, _metric: str, cell: dict[str, Any], factor: float) -> None:
        params = _point_of(run, cell)
        truth = bounds(params)[0]
        model = bounds(params, q_model=float(params["filter.q"]))[0]
        _bound_lines(ax, np.arange(1, len(truth) + 1), factor * truth, factor * model)
    return decorate


def _final_bounds(run: RunData, x_key: str) -> render.Decorate:
    """Draws the range bound at the last scan of each point of a panel against ``x_key``."""
    def decorate(ax: Axes, _metric: str, cell: dict[str, Any], factor: float) -> None:
        points = [p for p in run.points if all(p.get(k) == v for k, v in cell.items())]
        points.sort(key=lambda p: float(p[x_key]))
        x = np.array([float(p[x_key]) for p in points])
        truth = np.array([bounds(p)[0][-1] for p in points])
        model = np.array([bounds(p, q_model=float(p["filter.q"]))[0][-1] for p in points])
        _bound_lines(ax, x, factor * truth, factor * model)
    return decorate


def _range_vs_time(run: RunData) -> Figure | str:
    """Fig. 2: range RMSE against the scan, the headline pair (MGEKF beside EKF) and the
    Fig. 1 main curves, with the square-root PCRLB."""
    algorithms = run.params["algorithms"]
    names = _curves(headline_pair(algorithms) + main_algorithms(algorithms), MAX_ENTRIES - 2)
    plot = Plot(("range_sq_err_m2",), "scan", names, at=_time_at(run), root="range RMSE",
                xscale="linear", panel_height=1.6, together=_matched_q(run))
    return render.draw(run, plot, f"{_fig_words(run, 2)}: range RMSE against time",
                       _time_bounds(run))


def _anees_vs_time(run: RunData) -> Figure | str:
    """6-state ANEES against the scan on a log axis, its 95 % chi-square band shaded."""
    algorithms = run.params["algorithms"]
    names = _curves(headline_pair(algorithms) + main_algorithms(algorithms), MAX_ENTRIES - 1)
    low, high = nees_band(6, int(run.config["trials"]))

    def band(ax: Axes, _metric: str, _cell: dict[str, Any], _factor: float) -> None:
        ax.axhspan(low, high, color="k", alpha=0.1, linewidth=0, label="95 % band, consistent")

    plot = Plot(("nees",), "scan", names, at=_time_at(run), xscale="linear", yscale="log",
                panel_height=1.6, together=_matched_q(run))
    return render.draw(run, plot, "Diagnostic: ANEES against time", band)


def _final_x_key(run: RunData) -> str:
    """The swept axis of the final-RMSE figure, or a reason starting with "no "."""
    numeric = [k for k in swept_keys(run.config)
               if all(isinstance(v, int | float) for v in run.sweep[k])]
    if _zipped(run):
        return _zipped(run)
    if not numeric:
        return "no numeric key is swept"
    return "clutter.mean" if "clutter.mean" in numeric else numeric[0]


def _final_rmse(run: RunData) -> Figure | str:
    """Range RMSE at the last scan against the swept axis beside the square-root PCRLB."""
    x_key = _final_x_key(run)
    if x_key.startswith("no "):
        return x_key
    algorithms = run.params["algorithms"]
    other = [a for a in algorithms if a.split("/")[0] not in METHODS]
    names = _curves(headline_pair(algorithms) + main_algorithms(algorithms) + other,
                    MAX_ENTRIES - 2)
    plot = Plot(("range_sq_err_m2",), x_key, names, at=LAST, root="final range RMSE",
                xscale=_x_scale(run.sweep[x_key]) if x_key == "clutter.mean" else "auto")
    quantified = x_key == "clutter.mean" and _fig_words(run, 2).endswith("redrawn")
    title = ("Paper Fig. 2 quantified: final" if quantified else "Final") + " range RMSE"
    return render.draw(run, plot, title, _final_bounds(run, x_key))


DRAWERS: dict[str, Callable[[RunData], Figure | str]] = {
    "loss_vs_clutter": _loss_main,
    "loss_vs_clutter_ablation": _loss_ablation,
    "existence_vs_clutter": _existence,
    "loss_gate_and_nees_vs_clutter": _loss_flags,
    "loss_vs_manoeuvring_index": _loss_index,
    "range_error_vs_time": _range_vs_time,
    "anees_vs_time": _anees_vs_time,
    "final_range_rmse_vs_sweep": _final_rmse,
}
"""Figure name (:data:`~trackfuse.experiments.twin_sensor.FIGURES`) -> its drawing."""


def figures(run: RunData, wanted: Collection[str]) -> dict[str, Figure | str]:
    """The ``wanted`` figures; a one-line reason for each that this run cannot draw."""
    return {name: draw(run) for name, draw in DRAWERS.items() if name in wanted}


def fig1_headline(paper: RunData, analogue: RunData) -> Figure | str:
    """Paper 000's Fig. 1 told whole, for the reproduction report: tracks lost against
    clutter at the paper's scenario (``twin_sensor_fig1_claim``: flat at 0 %, the true
    result there) beside the close geometry where loss rises (``twin_sensor_close``, two
    sensors), one y axis, the paper's claim (below 5 % up to 9) in both panels."""
    plot = replace(FIG1, at={**FIG1.at, "sensors.count": 2})
    return render.draw_beside([(paper, "paper's scenario (redrawn)"),
                               (analogue, "close geometry (analogue)")], plot,
                              "Paper 000 Fig. 1: tracks lost against false returns")


def prepare(run: RunData) -> None:
    """Compute the square-root PCRLBs (truth model and the filter's ``q``) of every sweep
    point into :func:`~trackfuse.experiments.twin_sensor.model.bounds`' cache, from the
    config alone: the table and the range figures all use them (``trackfuse.reports`` calls
    this ahead, so they are computed once)."""
    for params in run.points:
        bounds(params)
        bounds(params, q_model=float(params["filter.q"]))
