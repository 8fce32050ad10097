"""Experiment ``passive_assoc``: paper 002, two-sensor passive association by (improved) PGA.

One trial simulates one scan of the two infrared sensors of paper 002 (targets M1..Mn, or
``n`` random targets in the same box), computes the assignment weights, solves the
dummy-augmented 2-D assignment exactly (the reference the paper says cannot be computed,
weakness W002-1) and runs each requested PGA variant on the same weights, scoring the best
solution at every checkpoint of the operation count (SPEC 4, E002-conv, E002-sigma).

Algorithms (``algorithms`` parameter):

* ``exact``: the exact optimum (``assoc.exact``), one row with ``ops = 0`` (sentinel: the
  exact solver has no operation count).
* ``pga_paper``: the paper-like improved PGA (roulette column-swap crossover, unpairing
  mutation, monotone acceptance), one row per checkpoint.
* ``pga_repair``: the same plus the re-pair move of SPEC 4.5, which makes the search chain
  irreducible (W002-2), and staged evaluation (crossover and mutation offspring accepted
  separately, see :mod:`trackfuse.association.pga`).
* ``pga_evict``: ours: ``pga_repair`` whose re-pair move may also evict the occupant of a
  column (one step for "swap an unpaired row into a pair").
* ``pga_anneal``: ``pga_evict`` with simulated-annealing acceptance (``pga.t0 -> pga.t1``).
* ``pga_repair_joint`` and ``pga_staged``: ablations, the re-pair move without staged
  evaluation and staged evaluation without the re-pair move.

Row metrics (``gap`` and ``at_opt`` are relative to the exact optimum ``J*`` of the same
trial, computed even when ``exact`` is not listed):

* ``accuracy``: measurement-level accuracy, the fraction of all measurements of both sensors
  whose assigned partner (other-sensor index or dummy) is the true one (SPEC 4.6).
* ``precision`` / ``recall``: correct pairs over declared pairs / over true pairs (1 when
  the denominator is 0: no false pair declared / no pair to find).
* ``correct``: 1 iff the whole partition equals the truth; ``at_opt``: 1 iff
  ``J* - J <= 1e-9 max(1, |J*|)``.
* ``gap``: ``J* - J`` (nats), ``objective``: ``J``, ``pairs``: number of declared pairs.
* ``solve_time_s`` (wall time of the solver up to the checkpoint) and ``weights_time_s``
  (triangulation and weights, shared by all solvers); the runner files these under
  timings.csv.

Random streams: ``truth, noise, clutter, shuffle, algo = rng.spawn(5)``; the PGA variants
take fixed children of ``algo`` by their position in :data:`VARIANTS` (append new variants
at the end), so adding or removing an algorithm in a config changes no other number.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import pandas as pd

from trackfuse.association.assignment import pair_weights, solve_exact
from trackfuse.association.passive_scene import scene_targets, simulate_scan, true_partners
from trackfuse.association.pga import CHECKPOINTS, pga
from trackfuse.experiments.base import Experiment, Param
from trackfuse.plots.style import band, new_figure, reference_line

#: PGA variants: name -> options of :func:`trackfuse.association.pga.pga`.
VARIANTS = {
    "pga_paper": {"repair_moves": False, "staged": False, "accept": "monotone"},
    "pga_repair": {"repair_moves": True, "staged": True, "accept": "monotone"},
    "pga_evict": {"repair_moves": True, "staged": True, "evict": True, "accept": "monotone"},
    "pga_anneal": {"repair_moves": True, "staged": True, "evict": True, "accept": "anneal"},
    "pga_repair_joint": {"repair_moves": True, "staged": False, "accept": "monotone"},
    "pga_staged": {"repair_moves": False, "staged": True, "accept": "monotone"},
}
ALGORITHMS = ("exact", *VARIANTS)
LABELS = {"exact": "exact optimum (LSA)", "pga_paper": "PGA, paper-like",
          "pga_repair": "PGA + re-pair, staged",
          "pga_evict": "PGA + evicting re-pair, staged (ours)",
          "pga_anneal": "ours + annealing",
          "pga_repair_joint": "PGA + re-pair, joint evaluation (ablation)",
          "pga_staged": "PGA, staged, no re-pair (ablation)"}
FIGURE_VARIANTS = ("pga_paper", "pga_repair", "pga_evict", "pga_anneal")
BOUNDED = ("accuracy", "precision", "recall", "correct", "at_opt")
AT_OPT_RTOL = 1e-9

PARAMS = (
    Param("scene.mode", "paper", "target set: the paper's M1..Mn, or n uniform in their box",
          kind=str, choices=("paper", "random")),
    Param("targets.n", 10, "number of targets (paper scene: first n of M1-M10)", "count",
          kind=int, low=1, high=2000),
    Param("noise.sigma", 0.005, "the paper's angle-error figure (azimuth and elevation, both "
          "sensors), read as a standard deviation or a variance per noise.reading", "rad",
          low=1e-7, high=1.0),
    Param("noise.reading", "std", "reading of noise.sigma: 'std' (sigma = value) or "
          "'variance' (sigma = sqrt(value), in rad^2)", kind=str, choices=("std", "variance")),
    Param("sensor.p_d", 0.95, "detection probability of each sensor", "probability",
          low=1e-3, high=1.0),
    Param("clutter.p_f", 0.05, "false alarms per sensor: Poisson(p_f N) or Binomial(N, p_f)",
          "probability", low=0.0, high=1.0),
    Param("clutter.model", "poisson", "false-alarm count model", kind=str,
          choices=("poisson", "binomial")),
    Param("clutter.margin", 0.1, "FOV box margin around the true target angles", "rad",
          low=0.0, high=1.0),
    Param("assoc.p_f", 0.05, "the paper's false-measurement likelihood p_f in a_i0 = ln p_f "
          "(cost 'paper' only)", "probability", low=1e-12, high=1.0),
    Param("assoc.tri", "unit_normal", "triangulation of a candidate pair", kind=str,
          choices=("paper", "unit_normal", "wls", "ml")),
    Param("assoc.cost", "paper", "assignment weights: the paper's (sign-corrected) or "
          "Pattipati's FOV-normalised likelihood ratio", kind=str,
          choices=("paper", "pattipati")),
    Param("assoc.exact", "lsa_clip", "exact solver for the reference optimum", kind=str,
          choices=("lsa_clip", "lsa_augmented")),
    Param("algorithms", ["exact", "pga_paper", "pga_evict"], "solvers reported per trial",
          kind=list, choices=ALGORITHMS),
    Param("pga.ops", 1000, "genetic operations per PGA run", "count", kind=int, low=0,
          high=10**7),
    Param("pga.checkpoints", list(CHECKPOINTS), "operation counts at which the best "
          "solution is scored (values above pga.ops are ignored)", "count", kind=list,
          low=0, high=10**7),
    Param("pga.p_m", 0.2, "mutation probability per genetic operation", "probability",
          low=0.0, high=1.0),
    Param("pga.init", "random_B", "initial individual: random injection or identity "
          "(paper eq. 31)", kind=str, choices=("random_B", "standard")),
    Param("pga.roulette", "worse", "roulette direction: badly placed columns swapped more "
          "often ('worse') or well placed ones ('better')", kind=str,
          choices=("worse", "better")),
    Param("pga.second", "roulette", "second crossover column: roulette over the rest or "
          "uniform", kind=str, choices=("roulette", "uniform")),
    Param("pga.t0", 2.0, "initial annealing temperature (pga_anneal)", "nat", low=1e-9,
          high=1e6),
    Param("pga.t1", 0.01, "final annealing temperature (pga_anneal)", "nat", low=1e-9,
          high=1e6),
)


def sigma_of(params: dict[str, Any]) -> float:
    """Angle noise standard deviation (rad) under the configured reading of the paper."""
    value = float(params["noise.sigma"])
    return value if params["noise.reading"] == "std" else float(np.sqrt(value))


def score(partner1: np.ndarray, partner2: np.ndarray, truth1: np.ndarray,
          truth2: np.ndarray) -> dict[str, float]:
    """Accuracy, pair precision/recall and whole-solution correctness of an assignment.

    partner1 (m1,), partner2 (m2,): assigned partners (-1 = dummy); truth1, truth2 likewise.
    """
    n_meas = len(partner1) + len(partner2)
    hits = int(np.sum(partner1 == truth1) + np.sum(partner2 == truth2))
    declared = int(np.sum(partner1 >= 0))
    true_pairs = int(np.sum(truth1 >= 0))
    good = int(np.sum((partner1 >= 0) & (partner1 == truth1)))
    return {
        "accuracy": hits / n_meas if n_meas else 1.0,
        "precision": good / declared if declared else 1.0,
        "recall": good / true_pairs if true_pairs else 1.0,
        "correct": int(hits == n_meas),
        "pairs": declared,
    }


def _partner2(partner1: np.ndarray, m2: int) -> np.ndarray:
    p2 = np.full(m2, -1)
    rows = np.flatnonzero(partner1 >= 0)
    p2[partner1[rows]] = rows
    return p2


def run_trial(params: dict[str, Any], rng: np.random.Generator) -> list[dict[str, Any]]:
    """One scan: simulate, weigh, solve exactly and by each PGA variant; rows per checkpoint."""
    truth, noise, clutter, shuffle, algo = rng.spawn(5)
    sigma = sigma_of(params)
    targets = scene_targets(int(params["targets.n"]), params["scene.mode"], truth)
    scan = simulate_scan(targets, sigma, sigma, params["sensor.p_d"], params["clutter.p_f"],
                         noise, clutter, shuffle, clutter=params["clutter.model"],
                         margin=params["clutter.margin"])
    truth1, truth2 = true_partners(*scan.labels)
    start = time.perf_counter()
    weights = pair_weights(*scan.z, *scan.sensors, sigma, sigma, params["sensor.p_d"],
                           params["assoc.p_f"], cost=params["assoc.cost"],
                           tri=params["assoc.tri"], psi=scan.psi)
    weights_time = time.perf_counter() - start
    gain = weights.gain
    start = time.perf_counter()
    exact = solve_exact(gain, params["assoc.exact"])
    exact_time = time.perf_counter() - start
    j_star = exact.objective
    tol = AT_OPT_RTOL * max(1.0, abs(j_star))

    def row(name: str, ops: int, partner1: np.ndarray, objective: float, elapsed: float):
        gap = max(j_star - objective, 0.0)
        return {"algorithm": name, "ops": ops,
                **score(partner1, _partner2(partner1, gain.shape[1]), truth1, truth2),
                "at_opt": int(gap <= tol), "gap": gap, "objective": objective,
                "solve_time_s": elapsed, "weights_time_s": weights_time}

    wanted = set(params["algorithms"])
    rows = []
    if "exact" in wanted:
        rows.append(row("exact", 0, exact.partner1, j_star, exact_time))
    streams = algo.spawn(len(VARIANTS))
    for stream, (name, options) in zip(streams, VARIANTS.items(), strict=True):
        if name not in wanted:
            continue
        result = pga(weights, stream, ops=int(params["pga.ops"]),
                     checkpoints=[int(c) for c in params["pga.checkpoints"]],
                     p_m=params["pga.p_m"], init=params["pga.init"],
                     roulette=params["pga.roulette"], second=params["pga.second"],
                     t0=params["pga.t0"], t1=params["pga.t1"], **options)
        for k, ops in enumerate(result.checkpoints.tolist()):
            rows.append(row(name, ops, result.partner1[k], float(result.objective[k]),
                            float(result.elapsed_s[k])))
    return rows


# ---------------------------------------------------------------------------------------
# Figures and tables (from the saved tables only)


def _swept(config: dict) -> list[str]:
    return [k for k in config.get("sweep", {}) if k != "algorithms"]


def _point_label(values: dict[str, Any], config: dict, noise: bool = True) -> str:
    p = {**config.get("params", {}), **values}
    mode = p.get("scene.mode", "paper")
    n = int(p.get("targets.n", 10))
    label = f"N = {n} ({f'M1-M{n}' if mode == 'paper' else 'random'})"
    if noise:
        reading = "" if p.get("noise.reading", "std") == "std" else " (variance reading)"
        label += f", sigma = {float(p.get('noise.sigma', 0.005)):g} rad{reading}"
    return label + f", P_D = {p.get('sensor.p_d', 0.95)}"


def _points(summary: pd.DataFrame, config: dict) -> list[tuple[int, dict[str, Any]]]:
    keys = [k for k in _swept(config) if k in summary]
    first = summary.drop_duplicates("point").sort_values("point")
    return [(int(r["point"]), {k: r[k] for k in keys}) for _, r in first.iterrows()]


def _metric(summary: pd.DataFrame, point: int, algorithm: str, metric: str) -> pd.DataFrame:
    sel = summary[(summary["point"] == point) & (summary["algorithm"] == algorithm)
                  & (summary["metric"] == metric)]
    return sel.sort_values("ops")


def _pga_names(summary: pd.DataFrame) -> list[str]:
    """PGA variants present in the summary, ablations left to the tables."""
    present = set(summary["algorithm"])
    return [name for name in FIGURE_VARIANTS if name in present]


def _clip(values, metric: str) -> np.ndarray:
    """Keep interval ends of proportions/accuracies inside [0, 1]."""
    v = np.asarray(values, dtype=float)
    return np.clip(v, 0.0, 1.0) if metric in BOUNDED else v


def _legend_below(fig, ax) -> None:
    handles, labels = ax.get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=min(len(labels), 4))


def _convergence(summary: pd.DataFrame, config: dict, metric: str, ylabel: str,
                 title: str, reference: float | None) -> Any:
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
    _legend_below(fig, axes[0])
    fig.suptitle(title)
    return fig


def _by_x(summary: pd.DataFrame, config: dict, xkey: str, algorithm: str, metric: str,
          ops: int | None) -> pd.DataFrame:
    sel = summary[(summary["algorithm"] == algorithm) & (summary["metric"] == metric)]
    if ops is not None:
        sel = sel[sel["ops"] == ops]
    return sel.sort_values(xkey)


def _final_ops(summary: pd.DataFrame, name: str) -> int:
    return int(summary.loc[summary["algorithm"] == name, "ops"].max())


def _noise_figure(summary: pd.DataFrame, config: dict) -> Any:
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
                sel = _by_x(part, config, "noise.sigma", algorithm, metric, ops)
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
    _legend_below(fig, axes[0, 0])
    fig.suptitle("Paper 002 (E002-sigma): exact MAP accuracy (the ceiling) vs angle noise; "
                 "grey: sigma = 0.005 and sqrt(0.005) rad, the two readings")
    return fig


def _time_table(trials: pd.DataFrame, summary: pd.DataFrame) -> pd.DataFrame | None:
    """Mean solve time per targets.n and algorithm at the final checkpoint, if available."""
    if "solve_time_s" in trials:
        final = trials[trials["ops"] == trials.groupby("algorithm")["ops"].transform("max")]
        g = final.groupby(["algorithm", "targets.n"])["solve_time_s"]
        out = g.agg(["mean", "std", "count"]).reset_index()
        half = 1.96 * out["std"].fillna(0) / np.sqrt(out["count"])
        return out.assign(ci_low=out["mean"] - half, ci_high=out["mean"] + half)
    rows = summary[summary["metric"] == "solve_time_s"]
    if rows.empty:
        return None
    return rows[["algorithm", "targets.n", "ops", "mean", "ci_low", "ci_high"]]


def _scale_figure(trials: pd.DataFrame, summary: pd.DataFrame, config: dict) -> Any:
    fig, axes = new_figure(ncols=3, width=3.9, height=3.4)
    names = ["exact", *_pga_names(summary)]
    times = _time_table(trials, summary)
    ax = axes[0]
    if times is not None:
        for name in names:
            t = times[times["algorithm"] == name].sort_values("targets.n")
            if "ops" in t:
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
        s = _by_x(summary, config, "targets.n", name, "gap", ops)
        band(axes[1], s["targets.n"], s["mean"], np.maximum(s["ci_low"], 0), s["ci_high"],
             LABELS[name], color=f"C{names.index(name)}")
    axes[1].set_yscale("symlog", linthresh=1.0)
    axes[1].set_ylabel("objective gap J* - J (nats)")
    for name in names:
        ops = None if name == "exact" else _final_ops(summary, name)
        s = _by_x(summary, config, "targets.n", name, "accuracy", ops)
        band(axes[2], s["targets.n"], s["mean"], _clip(s["ci_low"], "accuracy"),
             _clip(s["ci_high"], "accuracy"), LABELS[name])
    axes[2].set_ylabel("measurement-level accuracy (fraction)")
    _legend_below(fig, axes[2])
    for ax in axes:
        ax.set_xscale("log")
        ax.set_xlabel("number of targets N (count)")
    p = config.get("params", {})
    budget = ", ".join(f"{_final_ops(summary, n)} ops" for n in names[1:][:1])
    fig.suptitle(f"Paper 002 scale study: {p.get('scene.mode', 'random')} scenes in the "
                 f"M1-M10 box, sigma = {p.get('noise.sigma', 0.005)} rad"
                 + (f", PGA budget {budget}" if budget else ""))
    return fig


def figures(trials: pd.DataFrame, summary: pd.DataFrame, config: dict) -> dict[str, Any]:
    """Paper-style figures for the swept axes present in ``config``.

    * ``convergence`` (paper Fig. 2 analogue) and ``at_optimum`` (fraction of runs at the
      exact optimum and mean gap): one panel per sweep point (at most 6), when PGA rows with
      more than one checkpoint exist.
    * ``noise`` (E002-sigma) when ``noise.sigma`` is swept.
    * ``scale`` when ``targets.n`` is swept over at least 3 values.

    Mean accuracy is drawn with its 95 % Student-t band (a per-trial accuracy is not a 0/1
    outcome; a Wilson interval over pooled measurements would ignore their within-scan
    correlation); rates (``correct``, ``at_opt``) with 95 % Wilson bands.
    """
    out: dict[str, Any] = {}
    swept = _swept(config)
    n_points = summary["point"].nunique()
    pgas = _pga_names(summary)
    if pgas and summary.loc[summary["algorithm"].isin(pgas), "ops"].nunique() > 1 \
            and n_points <= 6:
        out["convergence"] = _convergence(
            summary, config, "accuracy", "measurement-level accuracy (fraction)",
            "Paper 002, Fig. 2 analogue: association accuracy vs genetic operations", None)
        fig = _convergence(summary, config, "at_opt", "runs at the exact optimum (rate)",
                           "Paper 002: fraction of runs whose PGA solution reaches J*", 1.0)
        out["at_optimum"] = fig
    if "noise.sigma" in swept:
        out["noise"] = _noise_figure(summary, config)
    if "targets.n" in swept and len(config["sweep"]["targets.n"]) >= 3:
        out["scale"] = _scale_figure(trials, summary, config)
    return out


def tables(trials: pd.DataFrame, summary: pd.DataFrame, config: dict) -> dict[str, pd.DataFrame]:
    """``final``: per point and algorithm at its last checkpoint, mean and 95 % CI of the
    accuracy, whole-solution-correct rate, at-optimum rate and gap."""
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


EXPERIMENT = Experiment(
    name="passive_assoc",
    title="Paper 002: two-sensor passive association, improved PGA vs the exact optimum",
    params=PARAMS,
    run_trial=run_trial,
    figures=figures,
    tables=tables,
    row_keys=("algorithm", "ops"),
    binary_metrics=("correct", "at_opt"),
    batch_size=25,
    description=__doc__.splitlines()[0],
)

__all__ = ["EXPERIMENT", "run_trial", "score", "sigma_of"]
