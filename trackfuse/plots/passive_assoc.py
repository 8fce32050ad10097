"""Figures and report tables of the ``passive_assoc`` experiment (paper 002).

Paper 002 associates the measurements of two passive infrared sensors by an improved
partheno-genetic algorithm (PGA). Its only results figure, Fig. 2, plots association
accuracy against the number of genetic operations; the other figures here are this
project's studies of the same experiment.

Figures (returned by :func:`figures`, keyed by file name):

* ``convergence``: paper Fig. 2 analogue (E002-conv). Measurement-level accuracy against
  the genetic operation count ``t`` for each PGA variant, one panel per sweep point, with
  the exact optimum (LSA) as a shaded reference.
* ``at_optimum``: no paper counterpart. The fraction of runs whose PGA solution reaches
  the exact optimum ``J*``, against ``t``, in the same panels.
* ``noise``: no paper counterpart (E002-sigma). Accuracy and whole-solution-correct rate of
  the exact optimum and of the PGA at its final checkpoint, against the angle noise sigma,
  with the two readings of the paper's noise figure (0.005 rad as a standard deviation or
  as a variance) marked.
* ``scale``: no paper counterpart. Solve time, objective gap ``J* - J`` and accuracy
  against the number of targets N.

Table (returned by :func:`tables`): ``final``, every metric per point and algorithm at its
last checkpoint, including the ablation variants that the figures leave out.

Everything is drawn from the saved tables; no trial is recomputed. ``summary`` is the long
format of :mod:`trackfuse.stats` (columns ``point``, the swept keys, ``algorithm``, ``ops``,
``metric``, ``n``, ``mean``, ``ci_low``, ``ci_high``), with the timing rows
(``metric == "solve_time_s"``, seconds) appended by the runner; ``trials`` is not needed.
``config`` supplies the sweep axes and the fixed parameter
values written into panel titles; its values are read, never simulated.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from trackfuse.plots.style import band, legend_below, new_figure, reference_line

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: Legend label of every algorithm of the experiment.
LABELS = {"exact": "exact optimum (LSA)", "pga_paper": "PGA, paper-like",
          "pga_repair": "PGA + re-pair, staged",
          "pga_evict": "PGA + evicting re-pair, staged (ours)",
          "pga_anneal": "ours + annealing",
          "pga_repair_joint": "PGA + re-pair, joint evaluation (ablation)",
          "pga_staged": "PGA, staged, no re-pair (ablation)"}
#: PGA variants drawn in the figures (the ablations appear only in the ``final`` table).
FIGURE_VARIANTS = ("pga_paper", "pga_repair", "pga_evict", "pga_anneal")
#: Metrics that live in [0, 1] (fractions and rates); their interval ends are clipped.
BOUNDED = ("accuracy", "precision", "recall", "correct", "at_opt")


# ---------------------------------------------------------------------------------------
# Shared helpers


def _swept(config: dict) -> list[str]:
    """Swept parameter keys of ``config``, the ``algorithms`` axis excluded."""
    return [k for k in config.get("sweep", {}) if k != "algorithms"]


def _point_label(values: dict[str, Any], config: dict, noise: bool = True) -> str:
    """Panel title: target count and scene, angle noise (rad) unless ``noise`` is False,
    detection probability; ``values`` (swept key -> value) override ``config['params']``."""
    p = {**config.get("params", {}), **values}
    mode = p.get("scene.mode", "paper")
    n = int(p.get("targets.n", 10))
    label = f"N = {n} ({f'M1-M{n}' if mode == 'paper' else 'random'})"
    if noise:
        reading = "" if p.get("noise.reading", "std") == "std" else " (variance reading)"
        label += f", sigma = {float(p.get('noise.sigma', 0.005)):g} rad{reading}"
    return label + f", P_D = {p.get('sensor.p_d', 0.95)}"


def _pga_names(summary: pd.DataFrame) -> list[str]:
    """PGA variants present in the summary, ablations left to the tables."""
    present = set(summary["algorithm"])
    return [name for name in FIGURE_VARIANTS if name in present]


def _final_ops(summary: pd.DataFrame, algorithm: str) -> int:
    """Last checkpoint (operation count) of ``algorithm`` in the summary."""
    return int(summary.loc[summary["algorithm"] == algorithm, "ops"].max())


def _by_x(summary: pd.DataFrame, xkey: str, algorithm: str, metric: str,
          ops: int | None) -> pd.DataFrame:
    """Summary rows of one algorithm and metric (at ``ops`` unless None), sorted by ``xkey``."""
    sel = summary[(summary["algorithm"] == algorithm) & (summary["metric"] == metric)]
    if ops is not None:
        sel = sel[sel["ops"] == ops]
    return sel.sort_values(xkey)


def _clip(values: ArrayLike, metric: str) -> np.ndarray:
    """Keep interval ends of proportions/accuracies inside [0, 1]."""
    v = np.asarray(values, dtype=float)
    return np.clip(v, 0.0, 1.0) if metric in BOUNDED else v


# ---------------------------------------------------------------------------------------
# convergence and at_optimum: metric against genetic operations, one panel per point


def _points(summary: pd.DataFrame, config: dict) -> list[tuple[int, dict[str, Any]]]:
    """``(point, {swept key: value})`` for every sweep point, in point order."""
    keys = [k for k in _swept(config) if k in summary]
    first = summary.drop_duplicates("point").sort_values("point")
    return [(int(r["point"]), {k: r[k] for k in keys}) for _, r in first.iterrows()]


def _metric(summary: pd.DataFrame, point: int, algorithm: str, metric: str) -> pd.DataFrame:
    """Summary rows of one point, algorithm and metric, sorted by operation count."""
    return _by_x(summary[summary["point"] == point], "ops", algorithm, metric, None)


def _convergence_figure(summary: pd.DataFrame, config: dict, metric: str, ylabel: str,
                        title: str, reference: float | None) -> Figure:
    """``metric`` (mean and 95 % band) of each PGA variant against the operation count.

    One panel per sweep point, log-scaled operation axis (symlog, linear below 10). The
    exact optimum is drawn as a dashed line at ``reference`` when given (1.0 for the
    at-optimum rate), otherwise at its own mean ``metric`` with its 95 % interval shaded.
    """
    points = _points(summary, config)
    fig, axes = new_figure(ncols=len(points), width=4.2, height=3.4)
    axes = np.atleast_1d(axes)
    for ax, (point, values) in zip(axes, points, strict=True):
        for name in _pga_names(summary):
            s = _metric(summary, point, name, metric)
            band(ax, s["ops"], s["mean"], _clip(s["ci_low"], metric),
                 _clip(s["ci_high"], metric), LABELS[name])
        exact = _metric(summary, point, "exact", metric)
        if reference is not None:
            reference_line(ax, reference, "exact optimum (LSA)")
        elif len(exact):
            e = exact.iloc[0]
            reference_line(ax, float(e["mean"]), "exact optimum (LSA), 95 % CI shaded")
            ax.axhspan(*_clip([e["ci_low"], e["ci_high"]], metric), color="k", alpha=0.08,
                       lw=0)
            ax.annotate(f"{e['mean']:.3f}", (0.02, float(e["mean"])),
                        xycoords=("axes fraction", "data"), va="bottom", fontsize=8)
        ax.set_xscale("symlog", linthresh=10)
        ax.set_xlim(0, summary["ops"].max())
        ax.set_ylim(-0.02, 1.04)
        ax.set_xlabel("genetic operations t (count)")
        ax.set_ylabel(ylabel)
        ax.set_title(_point_label(values, config), fontsize=8)
    legend_below(fig, axes[0], max_cols=4)
    fig.suptitle(title)
    return fig


# ---------------------------------------------------------------------------------------
# noise: exact and final-checkpoint PGA against the angle noise sigma


def _noise_figure(summary: pd.DataFrame, config: dict) -> Figure:
    """Accuracy (top row) and whole-solution-correct rate (bottom row) against sigma (rad).

    One column per combination of the other swept keys; the exact optimum solid, each PGA
    variant dotted at its final checkpoint; grey verticals at sigma = 0.005 and
    sqrt(0.005) rad, the paper's noise figure read as a standard deviation or a variance.
    """
    groups = [k for k in _swept(config) if k != "noise.sigma" and k in summary]
    parts = list(summary.groupby(groups, sort=True)) if groups else [((), summary)]
    fig, axes = new_figure(ncols=len(parts), nrows=2, width=3.8, height=3.0)
    axes = np.asarray(axes).reshape(2, len(parts))
    rows = (("accuracy", "measurement-level accuracy (fraction)"),
            ("correct", "whole solution correct (rate)"))
    for col, (key, part) in enumerate(parts):
        values = dict(zip(groups, np.atleast_1d(key), strict=True))
        for (metric, ylabel), ax in zip(rows, axes[:, col], strict=True):
            for algorithm in ["exact", *_pga_names(part)]:
                ops = None if algorithm == "exact" else _final_ops(part, algorithm)
                sel = _by_x(part, "noise.sigma", algorithm, metric, ops)
                label = LABELS[algorithm] + (f", {ops} ops" if ops else "")
                band(ax, sel["noise.sigma"], sel["mean"], _clip(sel["ci_low"], metric),
                     _clip(sel["ci_high"], metric), label,
                     linestyle="-" if algorithm == "exact" else ":")
            for x in (0.005, np.sqrt(0.005)):
                ax.axvline(x, color="grey", lw=0.8, ls="--")
            ax.set_xscale("log")
            ax.set_xlabel("angle noise sigma (rad)")
            ax.set_ylabel(ylabel)
            ax.set_ylim(-0.02, 1.04)
        axes[0, col].set_title(_point_label(values, config, noise=False), fontsize=8)
    legend_below(fig, axes[0, 0], max_cols=4)
    fig.suptitle("Paper 002 (E002-sigma): exact MAP accuracy (the ceiling) vs angle noise; "
                 "grey: sigma = 0.005 and sqrt(0.005) rad, the two readings")
    return fig


# ---------------------------------------------------------------------------------------
# scale: solve time, objective gap and accuracy against the number of targets


def _time_table(summary: pd.DataFrame) -> pd.DataFrame | None:
    """Solve-time rows (s) of the summary (the runner appends them from timings.csv; a
    summary of raw trial rows carries them as an ordinary metric); None when absent."""
    rows = summary[summary["metric"] == "solve_time_s"]
    if rows.empty:
        return None
    return rows[["algorithm", "targets.n", "ops", "mean", "ci_low", "ci_high"]]


def _scale_figure(summary: pd.DataFrame, config: dict) -> Figure:
    """Three panels against the number of targets N (log axis), PGA at its final checkpoint.

    Solve time per scan (ms, log axis), objective gap ``J* - J`` (nats, symlog axis; PGA
    variants only) and measurement-level accuracy (fraction), the exact optimum included.
    """
    fig, axes = new_figure(ncols=3, width=3.9, height=3.4)
    names = ["exact", *_pga_names(summary)]
    times = _time_table(summary)
    ax = axes[0]
    if times is not None:
        for name in names:
            t = times[times["algorithm"] == name].sort_values("targets.n")
            t = t[t["ops"] == t["ops"].max()]
            band(ax, t["targets.n"], t["mean"] * 1e3, np.maximum(t["ci_low"], 0) * 1e3,
                 t["ci_high"] * 1e3, LABELS[name])
        ax.set_yscale("log")
    else:
        ax.text(0.5, 0.5, "solve times are in timings.csv,\nwhich was not passed to the figure",
                ha="center", va="center", transform=ax.transAxes)
    ax.set_ylabel("solve time per scan (ms)")
    for name in names[1:]:
        ops = _final_ops(summary, name)
        s = _by_x(summary, "targets.n", name, "gap", ops)
        band(axes[1], s["targets.n"], s["mean"], np.maximum(s["ci_low"], 0), s["ci_high"],
             LABELS[name], color=f"C{names.index(name)}")
    axes[1].set_yscale("symlog", linthresh=1.0)
    axes[1].set_ylabel("objective gap J* - J (nats)")
    for name in names:
        ops = None if name == "exact" else _final_ops(summary, name)
        s = _by_x(summary, "targets.n", name, "accuracy", ops)
        band(axes[2], s["targets.n"], s["mean"], _clip(s["ci_low"], "accuracy"),
             _clip(s["ci_high"], "accuracy"), LABELS[name])
    axes[2].set_ylabel("measurement-level accuracy (fraction)")
    legend_below(fig, axes[2], max_cols=4)
    for ax in axes:
        ax.set_xscale("log")
        ax.set_xlabel("number of targets N (count)")
    p = config.get("params", {})
    # the budget of the first PGA variant drawn, if any
    budget = f"{_final_ops(summary, names[1])} ops" if len(names) > 1 else ""
    fig.suptitle(f"Paper 002 scale study: {p.get('scene.mode', 'random')} scenes in the "
                 f"M1-M10 box, sigma = {p.get('noise.sigma', 0.005)} rad"
                 + (f", PGA budget {budget}" if budget else ""))
    return fig


# ---------------------------------------------------------------------------------------
# Entry points of the experiment


def figures(trials: pd.DataFrame, summary: pd.DataFrame, config: dict) -> dict[str, Figure]:
    """Paper-style figures for the swept axes present in ``config``.

    * ``convergence`` (paper Fig. 2 analogue) and ``at_optimum`` (fraction of runs at the
      exact optimum): one panel per sweep point (at most 6), when PGA rows with more than
      one checkpoint exist.
    * ``noise`` (E002-sigma) when ``noise.sigma`` is swept.
    * ``scale`` when ``targets.n`` is swept over at least 3 values.

    Mean accuracy is drawn with its 95 % Student-t band (a per-trial accuracy is not a 0/1
    outcome; a Wilson interval over pooled measurements would ignore their within-scan
    correlation); rates (``correct``, ``at_opt``) with 95 % Wilson bands.
    """
    out: dict[str, Figure] = {}
    swept = _swept(config)
    n_points = summary["point"].nunique()
    pgas = _pga_names(summary)
    if pgas and summary.loc[summary["algorithm"].isin(pgas), "ops"].nunique() > 1 \
            and n_points <= 6:
        out["convergence"] = _convergence_figure(
            summary, config, "accuracy", "measurement-level accuracy (fraction)",
            "Paper 002, Fig. 2 analogue: association accuracy vs genetic operations", None)
        out["at_optimum"] = _convergence_figure(
            summary, config, "at_opt", "runs at the exact optimum (rate)",
            "Paper 002: fraction of runs whose PGA solution reaches J*", 1.0)
    if "noise.sigma" in swept:
        out["noise"] = _noise_figure(summary, config)
    if "targets.n" in swept and len(config["sweep"]["targets.n"]) >= 3:
        out["scale"] = _scale_figure(summary, config)
    return out


def tables(trials: pd.DataFrame, summary: pd.DataFrame, config: dict) -> dict[str, pd.DataFrame]:
    """``final``: per point and algorithm at its last checkpoint, mean and 95 % CI of the
    accuracy, whole-solution-correct rate, at-optimum rate, gap (nats), precision and recall
    (columns ``<metric>``, ``<metric>_lo``, ``<metric>_hi``), rounded to 4 digits."""
    keys = ["point", *[k for k in _swept(config) if k in summary], "algorithm"]
    last = summary.groupby(["point", "algorithm"])["ops"].transform("max")
    final = summary[summary["ops"] == last]
    out = None
    for metric in ("accuracy", "correct", "at_opt", "gap", "precision", "recall"):
        m = final[final["metric"] == metric][[*keys, "ops", "n", "mean", "ci_low", "ci_high"]]
        m = m.assign(ci_low=_clip(m["ci_low"], metric), ci_high=_clip(m["ci_high"], metric))
        m = m.rename(columns={"mean": metric, "ci_low": f"{metric}_lo",
                              "ci_high": f"{metric}_hi"})
        out = m if out is None else out.merge(m.drop(columns=["n"]), on=[*keys, "ops"])
    return {"final": out.sort_values(keys).reset_index(drop=True).round(4)}


__all__ = ["BOUNDED", "FIGURE_VARIANTS", "LABELS", "figures", "tables"]
