"""Figures and report table of the twin_sensor experiment (paper 000).

Wang, Wang & Yang, "Fusion algorithm for airborne twin-sensor synchronous angle-only
tracking", Control and Decision 20(10), 2005. :func:`figures` and :func:`tables` follow the
:class:`~trackfuse.experiments.base.Experiment` contract: they receive ``trials`` (the tidy
``trials.csv`` frame, one row per point, trial, algorithm and scan, with the swept values as
columns), ``summary`` (unused: the chi-square RMSE bands need the per-trial squared errors)
and ``config`` (the resolved config as a plain dict).

Figures (the keys of :func:`figures`, which name the files)
------------------------------------------------------------
``loss_gate_vs_clutter``, ``loss_nees_vs_clutter``
    Paper Fig. 1: tracks lost (%) at the last scan against the mean number of false returns
    per sensor and scan, every algorithm with its 95 % Wilson band, one panel per value of the
    other swept keys; once for the gate rule and once for the NEES rule. Drawn only when
    ``clutter.mean`` is swept (``configs/twin_sensor_orbit.yaml``).
``range_rmse_vs_time``
    Paper Fig. 2: range RMSE (km) against time, MGEKF beside EKF for the first association
    listed, with 95 % chi-square bands, beside the square-root PCRLB of the truth model and of
    the filter's ``q``; one panel per sweep point (at most nine, evenly spread).
``anees_vs_time``
    Extension (consistency): 6-state ANEES against time with its 95 % chi-square band.
``final_range_rmse_vs_<key>``
    Extension (``configs/twin_sensor_baseline.yaml``): range RMSE (km) at the last scan
    against the only swept axis, beside the square-root PCRLB on a fine grid of that axis.
    Drawn only when exactly one numeric key is swept.

Table
-----
``final_scan``: per point and algorithm at the last scan, loss rates with 95 % Wilson
intervals, range RMSE (all runs and runs not lost), range bias, position RMSE, ANEES,
validated returns (mean over all scans) and the range PCRLB.

Saved data vs recomputed
------------------------
Every curve, band and table entry is drawn from ``trials.csv``; no trial is re-run. Only the
PCRLB references are recomputed, from the config alone, by
:func:`trackfuse.experiments.twin_sensor.bounds` (deterministic and cached). The experiment
module imports this one to declare its figures, so :func:`figures` and :func:`tables` import
``bounds`` and the parameter schema when called (not at import time) and hand them to the
helpers that need them.
"""

from __future__ import annotations

import textwrap
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure
from scipy import stats

from trackfuse.experiments.base import Param
from trackfuse.plots.style import band, legend_below, new_figure
from trackfuse.stats import nees_band, wilson_interval

BoundsFn = Callable[..., tuple[np.ndarray, np.ndarray]]
"""``bounds(params, q_model=None) -> (range_bound, position_bound)``, each ``(K,)`` metres."""

LABELS = {"mspda_parallel": "parallel PDA", "mspda_sequential": "sequential PDA",
          "nn": "nearest neighbour", "paper_approx": "paper approx. (reconstruction)"}
"""Legend names of the association variants of :mod:`trackfuse.tracking.pda`."""


# --------------------------------------------------------------------------------------------
# Shared helpers


def _swept(config: dict) -> list[str]:
    """The swept parameter keys, in config order."""
    return list((config.get("sweep") or {}).keys())


def _point_params(config: dict, frame: pd.DataFrame) -> dict[str, Any]:
    """Resolved params of the sweep point of ``frame``'s first row."""
    params = dict(config["params"])
    for key in _swept(config):
        value = frame[key].iloc[0]
        params[key] = value.item() if hasattr(value, "item") else value
    return params


def _label(name: str) -> str:
    """Legend label of an ``association/filter`` algorithm name."""
    assoc, filt = name.split("/")
    return f"{LABELS.get(assoc, assoc)}, {filt.upper()}"


def _headline(algorithms: Sequence[str]) -> list[str]:
    """Algorithms sharing the first listed association (MGEKF beside EKF)."""
    first = algorithms[0].split("/")[0]
    return [a for a in algorithms if a.split("/")[0] == first]


def _panels(n: int, width: float = 4.4, height: float = 3.3,
            ncols: int | None = None) -> tuple[Figure, np.ndarray, float]:
    """``(fig, axes, figure_width_in)`` for ``n`` panels in ``ncols`` columns (default: one
    row up to four, else rows of three); ``axes: (n,)``, panel ``width`` and ``height`` in
    inches. Unused axes are hidden."""
    ncols = ncols or (n if n <= 4 else 3)
    fig, axes = new_figure(ncols=ncols, nrows=int(np.ceil(n / ncols)), width=width,
                           height=height)
    axes = np.atleast_1d(axes)
    for ax in axes[n:]:
        ax.set_visible(False)
    return fig, axes[:n], width * ncols


def _point_title(keys: Sequence[str], frame: pd.DataFrame) -> str:
    """Panel title ``"mean=5, count=2"`` from the values of ``keys`` in ``frame``'s first row."""
    parts = []
    for key in keys:
        value = frame[key].iloc[0]
        text = f"{value:g}" if isinstance(value, (int, float, np.number)) else str(value)
        parts.append(f"{key.split('.')[-1]}={text}")
    return ", ".join(parts) or "all trials"


def _select_points(trials: pd.DataFrame, limit: int = 9) -> list[int]:
    """Every sweep point, or ``limit`` of them evenly spread over the point indices."""
    points = sorted(trials["point"].unique())
    if len(points) <= limit:
        return points
    idx = np.linspace(0, len(points) - 1, limit).round().astype(int)
    return [points[i] for i in sorted(set(idx))]


def _rmse_band(sq: pd.Series) -> tuple[float, float, float]:
    """RMSE from squared errors with its 95% chi-square interval (zero-mean Gaussian errors):
    ``n MSE / RMSE_true^2 ~ chi2(n)``. Units: the square root of ``sq``'s."""
    n, mse = len(sq), float(sq.mean())
    lo, hi = stats.chi2.ppf([0.975, 0.025], n)
    return np.sqrt(mse), np.sqrt(n * mse / lo), np.sqrt(n * mse / hi)


def _suptitle(fig: Figure, config: dict, what: str, width_in: float) -> None:
    """Config title over ``what``, each wrapped to the figure width (inches)."""
    chars = max(40, int(width_in * 10))
    title = textwrap.fill(str(config.get("title", "twin_sensor")), chars)
    fig.suptitle(f"{title}\n{textwrap.fill(what, chars)}")


# --------------------------------------------------------------------------------------------
# Figures


def _loss_figure(trials: pd.DataFrame, config: dict, rule: str, x_key: str) -> Figure:
    """Paper Fig. 1: loss rate (%) at the last scan under ``rule`` (``"lost_gate"`` or
    ``"lost_nees"``) against ``x_key``, one panel per value of the other swept keys."""
    last = trials[trials["scan"] == trials["scan"].max()]
    params = config["params"]
    swept = _swept(config)
    others = [k for k in swept if k != x_key]
    groups = [g for _, g in last.groupby(others, sort=True)] if others else [last]
    where = ("gate or window" if "clutter.model" in swept
             else "gate" if params["clutter.model"] == "in_gate" else "window")
    fig, axes, fig_width = _panels(len(groups), width=6.4 if len(groups) == 1 else 4.6,
                                   height=3.4, ncols=min(4, len(groups)))
    for ax, frame in zip(axes, groups, strict=True):
        for name in config["params"]["algorithms"]:
            g = frame[frame["algorithm"] == name].groupby(x_key)[rule].agg(["sum", "count"])
            lo, hi = wilson_interval(g["sum"], g["count"])
            band(ax, g.index, 100 * g["sum"] / g["count"], 100 * lo, 100 * hi, _label(name),
                 linestyle="-" if name.endswith("mgekf") else "--")
        ax.set_title(_point_title(others, frame))
        ax.set_xlabel(f"mean false returns per sensor and scan in the {where} (returns/scan)")
        ax.set_ylabel("tracks lost (%)")
        ax.set_ylim(-2, 102)
    legend_below(fig, axes[0])
    if rule == "lost_gate":
        n = "loss.window" if "loss.window" in swept else params["loss.window"]
        what = f"target outside every gate for >= {n} scans"
    else:
        q = "loss.nees_quantile" if "loss.nees_quantile" in swept else params["loss.nees_quantile"]
        what = f"final position NEES > chi2_3({q})"
    _suptitle(fig, config, f"loss rate ({what}), 95% Wilson bands", fig_width)
    return fig


def _range_figure(trials: pd.DataFrame, config: dict, bounds: BoundsFn) -> Figure:
    """Paper Fig. 2: range RMSE (km) against time (s) per sweep point, beside the square-root
    PCRLB of the truth model and of the filter model."""
    points = _select_points(trials)
    fig, axes, fig_width = _panels(len(points))
    names = _headline(config["params"]["algorithms"])
    for ax, pt in zip(axes, points, strict=True):
        frame = trials[trials["point"] == pt]
        params = _point_params(config, frame)
        period = float(params["scan.period"])
        for name in names:
            g = frame[frame["algorithm"] == name].groupby("scan")["range_sq_err_m2"]
            vals = np.array([_rmse_band(s) for _, s in g]) / 1e3
            band(ax, np.array(list(g.groups), dtype=float) * period, vals[:, 0], vals[:, 1],
                 vals[:, 2], _label(name), linestyle="-" if name.endswith("mgekf") else "--")
        times = np.arange(1, int(params["scan.count"]) + 1) * period
        rb, _ = bounds(params)
        ax.plot(times, rb / 1e3, "k--", lw=1.0, label="sqrt PCRLB (truth model)")
        rf, _ = bounds(params, q_model=float(params["filter.q"]))
        ax.plot(times, rf / 1e3, "k:", lw=1.0, label="sqrt PCRLB (filter model q)")
        ax.set_xlabel("time t (s)")
        ax.set_ylabel("range RMSE (km)")
        ax.set_ylim(bottom=0)
        ax.set_title(_point_title(_swept(config), frame))
    legend_below(fig, axes[0])
    _suptitle(fig, config, "range RMSE (95% chi-square bands) vs square-root PCRLB",
              fig_width)
    return fig


def _nees_figure(trials: pd.DataFrame, config: dict) -> Figure:
    """Extension: 6-state ANEES against time (s) per sweep point, with its 95% chi-square
    band for the number of runs."""
    points = _select_points(trials)
    fig, axes, fig_width = _panels(len(points))
    names = _headline(config["params"]["algorithms"])
    for ax, pt in zip(axes, points, strict=True):
        frame = trials[trials["point"] == pt]
        period = float(_point_params(config, frame)["scan.period"])
        for name in names:
            anees = frame[frame["algorithm"] == name].groupby("scan")["nees"].mean()
            ax.plot(anees.index * period, anees, marker="o", label=_label(name),
                    linestyle="-" if name.endswith("mgekf") else "--")
        n_runs = int(frame["trial"].nunique())
        lo, hi = nees_band(6, n_runs)
        ax.axhspan(lo, hi, color="k", alpha=0.12, label=f"95% chi2 band, {n_runs} runs")
        ax.axhline(6.0, color="k", lw=0.8)
        ax.set_ylim(bottom=0)
        ax.set_xlabel("time t (s)")
        ax.set_ylabel("ANEES (6-state, dimensionless)")
        ax.set_title(_point_title(_swept(config), frame))
    legend_below(fig, axes[0])
    _suptitle(fig, config, "average NEES vs its 95% chi-square band", fig_width)
    return fig


def _final_figure(trials: pd.DataFrame, config: dict, x_param: Param,
                  bounds: BoundsFn) -> Figure:
    """Extension: range RMSE (km) at the last scan against the swept ``x_param`` (a baseline
    is shown in km), beside the square-root PCRLB on a 41-point grid plus the swept values."""
    x_key = x_param.key
    last = trials[trials["scan"] == trials["scan"].max()]
    fig, ax = new_figure(width=5.6, height=3.6)
    scale = 1e3 if x_key == "sensors.baseline" else 1.0
    for name in _headline(config["params"]["algorithms"]):
        g = last[last["algorithm"] == name].groupby(x_key)["range_sq_err_m2"]
        vals = np.array([_rmse_band(s) for _, s in g]) / 1e3
        band(ax, np.array(list(g.groups), dtype=float) / scale, vals[:, 0], vals[:, 1],
             vals[:, 2], _label(name), linestyle="-" if name.endswith("mgekf") else "--")
    base = _point_params(config, last)
    values = last[x_key].astype(float)
    grid = np.unique(np.concatenate([np.linspace(values.min(), values.max(), 41), values]))
    bound_km = [bounds({**base, x_key: x_param.kind(v)})[0][-1] / 1e3 for v in grid]
    ax.plot(grid / scale, bound_km, "k--", lw=1.0, label="sqrt PCRLB (truth model)")
    unit = "km" if scale == 1e3 else x_param.unit
    ax.set_xlabel(f"{x_key} ({unit})")
    ax.set_ylabel("final range RMSE (km)")
    ax.set_ylim(bottom=0)
    ax.legend()
    ax.set_title(textwrap.fill(f"{config.get('title', 'twin_sensor')}: range RMSE at the last "
                               "scan (95% chi-square bands)", 50))
    return fig


def figures(trials: pd.DataFrame, summary: pd.DataFrame, config: dict) -> dict[str, Figure]:
    """Loss vs clutter (both rules), range RMSE vs time with sqrt PCRLB, ANEES vs time, and
    final range RMSE vs the swept axis when there is exactly one."""
    from trackfuse.experiments.twin_sensor import PARAMS, bounds  # imports this module

    swept = _swept(config)
    figs: dict[str, Figure] = {}
    if "clutter.mean" in swept:
        figs["loss_gate_vs_clutter"] = _loss_figure(trials, config, "lost_gate", "clutter.mean")
        figs["loss_nees_vs_clutter"] = _loss_figure(trials, config, "lost_nees", "clutter.mean")
    figs["range_rmse_vs_time"] = _range_figure(trials, config, bounds)
    figs["anees_vs_time"] = _nees_figure(trials, config)
    if len(swept) == 1 and pd.api.types.is_numeric_dtype(trials[swept[0]]):
        x_param = next(p for p in PARAMS if p.key == swept[0])
        figs[f"final_range_rmse_vs_{swept[0].replace('.', '_')}"] = _final_figure(
            trials, config, x_param, bounds)
    return figs


# --------------------------------------------------------------------------------------------
# Tables


def tables(trials: pd.DataFrame, summary: pd.DataFrame, config: dict) -> dict[str, pd.DataFrame]:
    """Per point and algorithm at the last scan: loss rates (95% Wilson), range RMSE over all
    and over non-lost runs, range bias, position RMSE, ANEES and the range PCRLB; plus the
    validated returns per sensor and scan averaged over *all* scans (lengths in km, rates in
    %)."""
    from trackfuse.experiments.twin_sensor import bounds  # imports this module

    last = trials[trials["scan"] == trials["scan"].max()]
    swept = _swept(config)
    n_valid = {key: s.mean() for key, s in trials.groupby(["point", "algorithm"])["n_valid"]}
    rows = []
    for (pt, name), g in last.groupby(["point", "algorithm"], sort=True):
        n = len(g)
        params = _point_params(config, g)
        rec: dict[str, Any] = {"point": pt, **{k: g[k].iloc[0] for k in swept},
                               "algorithm": name, "trials": n}
        for rule in ("lost_gate", "lost_nees"):
            k = int(g[rule].sum())
            lo, hi = wilson_interval(k, n)
            rec[f"{rule}_pct"] = 100 * k / n
            rec[f"{rule}_ci95_pct"] = f"[{100 * float(lo):.1f}, {100 * float(hi):.1f}]"
        kept = g[g["lost_gate"] == 0]
        rec["range_rmse_km"] = np.sqrt(g["range_sq_err_m2"].mean()) / 1e3
        rec["range_rmse_not_lost_km"] = (np.sqrt(kept["range_sq_err_m2"].mean()) / 1e3
                                         if len(kept) else np.nan)
        rec["range_pcrlb_km"] = bounds(params)[0][-1] / 1e3
        rec["range_bias_km"] = g["range_err_m"].mean() / 1e3
        rec["pos_rmse_km"] = np.sqrt(g["pos_sq_err_m2"].mean()) / 1e3
        rec["anees"] = g["nees"].mean()
        rec["n_valid"] = n_valid[pt, name]
        rows.append(rec)
    return {"final_scan": pd.DataFrame(rows)}
