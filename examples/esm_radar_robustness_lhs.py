"""How robust is the Table 3 match of paper 001 (docs/papers/esm_radar.md, "How robust is
the match: all settings at once")?

``examples/esm_radar_robustness_lhs.yaml`` runs the Table 3 scene (200 m separation, radar
range sd 1 %, the paper's two methods) at 40 joint settings of seven values the paper leaves
open, each under both readings of the radar's TDOA/phase factors (80 points, 500 trials
each). The 40 settings are a Latin hypercube over the ranges in :data:`RANGES`, drawn once with
:data:`DESIGN_SEED` and written out literally in the config; ``design`` prints that block
again, so the config can be checked against its recipe.

Usage::

    python examples/esm_radar_robustness_lhs.py design      # the config's sweep block
    trackfuse run examples/esm_radar_robustness_lhs.yaml --no-plots
    python examples/esm_radar_robustness_lhs.py judge \\
        results/esm_radar_robustness_lhs/seed20170638-<id> --png lhs.png --csv lhs.csv

``judge`` reads the run's ``summary.csv`` (each point's correct count is its ``n`` times its
``mean``), compares each method's count with the paper's (370 and 276 of 500) as two
independent samples with :func:`trackfuse.reportkit.verdicts.against_paper_sample`
(Newcombe's hybrid score interval of ours minus the paper's, 95 %: consistent when it holds
0), prints the share of settings under which each number is consistent, per radar-factor
model, and draws every setting's rate with its 95 % Wilson interval, coloured by verdict.
"""

from __future__ import annotations

import argparse
import math
import textwrap
from pathlib import Path

import numpy as np
import pandas as pd
from scipy.stats import qmc

from trackfuse.reportkit.style import panels
from trackfuse.reportkit.verdicts import AGREES, against_paper_sample

DESIGN_SEED = 638
N_SETTINGS = 40
G = 9.80665  # m/s^2
#: The open settings and their plausible ranges (low, high, scale); the reasons are in the
#: docs. ``snake.peak_g`` is not a parameter: the weave's period follows from its amplitude
#: A and peak lateral acceleration a as P = 2 pi sqrt(A / a).
RANGES: dict[str, tuple[float, float, str]] = {
    "snake.amplitude": (500.0, 2000.0, "log"),       # m
    "snake.peak_g": (1.0, 4.0, "linear"),            # g
    "geometry.baseline": (5000.0, 20000.0, "log"),   # m
    "scan.count": (30, 100, "log"),                  # scans at 1 s
    "alpha.window": (3, 10, "integer"),              # scans
    "alpha.false_alarm": (0.001, 0.05, "log"),       # 1
    "alpha.accel_change_sd": (0.02, 0.2, "log"),     # m/s^2
}
#: The paper's Table 3 (500 runs): correct associations of each method.
PAPER = {"improved": (370, 500), "traditional": (276, 500)}
MODELS = ("derived", "table")


def _scaled(u: float, low: float, high: float, scale: str) -> float:
    """A unit-interval draw ``u`` mapped onto [low, high] on the given scale."""
    if scale == "log":
        return math.exp(math.log(low) + u * (math.log(high) - math.log(low)))
    if scale == "integer":
        return float(min(int(low + u * (high - low + 1)), high))
    return low + u * (high - low)


def design() -> pd.DataFrame:
    """The 40 settings: one row each, the config's keys as columns, rounded as written."""
    units = qmc.LatinHypercube(d=len(RANGES), seed=DESIGN_SEED).random(N_SETTINGS)
    raw = pd.DataFrame({k: [_scaled(u, *RANGES[k]) for u in units[:, i]]
                        for i, k in enumerate(RANGES)})
    amplitude = (raw["snake.amplitude"] / 10).round() * 10
    return pd.DataFrame({
        "snake.amplitude": amplitude,
        "snake.period": (2 * np.pi * np.sqrt(amplitude / (raw["snake.peak_g"] * G))).round(1),
        "geometry.baseline": (raw["geometry.baseline"] / 100).round() * 100,
        "scan.count": raw["scan.count"].round().astype(int),
        "alpha.window": raw["alpha.window"].astype(int),
        "alpha.false_alarm": [float(f"{v:.2g}") for v in raw["alpha.false_alarm"]],
        "alpha.accel_change_sd": [float(f"{v:.2g}") for v in raw["alpha.accel_change_sd"]],
    })


def sweep_block(settings: pd.DataFrame) -> str:
    """The config's zipped sweep: every setting under each radar-factor model in turn."""
    def values(column: list) -> str:
        return ", ".join(f"{v:g}" if isinstance(v, float) else str(v) for v in column)

    def entry(key: str, text: str) -> str:
        return textwrap.fill(f"  {key}: [{text}]", width=94, subsequent_indent=" " * 4,
                             break_on_hyphens=False)

    lines = ["sweep:", entry("radar.factor_model",
                             ", ".join(m for m in MODELS for _ in settings.index))]
    lines += [entry(key, values(settings[key].tolist() * len(MODELS)))
              for key in settings.columns]
    return "\n".join(lines) + "\nsweep_mode: zip"


def judged(folder: Path) -> pd.DataFrame:
    """One row per point and method: our count, its Wilson interval and the verdict against
    the paper's count."""
    summary = pd.read_csv(folder / "summary.csv")
    rows = summary[(summary["metric"] == "correct") & summary["algorithm"].isin(PAPER)]
    out = []
    for r in rows.to_dict("records"):
        k, n = int(round(r["mean"] * r["n"])), int(r["n"])
        verdict = against_paper_sample(k, n, *PAPER[r["algorithm"]])
        out.append({"point": r["point"], "model": r["radar.factor_model"],
                    "algorithm": r["algorithm"], "correct": k, "n": n, "rate": k / n,
                    "ci_low": r["ci_low"], "ci_high": r["ci_high"],
                    "difference": verdict.estimate,
                    "diff_low": verdict.low, "diff_high": verdict.high,
                    "consistent": verdict.word == AGREES})
    return pd.DataFrame(out)


def shares(table: pd.DataFrame) -> str:
    """The share of settings under which each number is consistent, per model."""
    lines = []
    for (model, algorithm), g in table.groupby(["model", "algorithm"], sort=False):
        lines.append(f"{algorithm:12s} '{model}': consistent under {int(g['consistent'].sum())}"
                     f" of {len(g)} settings ({100 * g['consistent'].mean():.0f} %); rates "
                     f"{g['rate'].min():.3f} to {g['rate'].max():.3f}, median "
                     f"{g['rate'].median():.3f}")
    return "\n".join(lines)


def figure(table: pd.DataFrame, settings: pd.DataFrame, png: Path) -> None:
    """Each setting's correct rate (%) with its 95 % Wilson interval, one panel per model,
    settings ordered by their number of scans; filled markers where the rate is consistent
    with the paper's, open where it differs; the paper's rates as dashed lines."""
    order = np.argsort(settings["scan.count"].to_numpy(), kind="stable")
    fig, grid = panels(1, 2, "double", panel_height=2.1, extra_height=0.0)
    axes = grid[0]
    colours = {"improved": "tab:blue", "traditional": "tab:orange"}
    markers = {"improved": "o", "traditional": "s"}
    for ax, model in zip(axes, MODELS, strict=True):
        for shift, algorithm in zip((-0.17, 0.17), PAPER, strict=True):
            g = table[(table["model"] == model) & (table["algorithm"] == algorithm)]
            g = g.reset_index(drop=True).iloc[order]
            x = np.arange(len(g)) + shift
            rate, low, high = (100 * g[c].to_numpy() for c in ("rate", "ci_low", "ci_high"))
            ax.errorbar(x, rate, yerr=[rate - low, high - rate], fmt="none",
                        ecolor=colours[algorithm], elinewidth=0.8)
            for ok in (True, False):
                m = g["consistent"].to_numpy() == ok
                ax.plot(x[m], rate[m], markers[algorithm], ms=3.5, color=colours[algorithm],
                        mfc=colours[algorithm] if ok else "white",
                        label=f"{algorithm}: {'consistent with' if ok else 'differs from'}"
                              " the paper")
            k, n = PAPER[algorithm]
            ax.axhline(100 * k / n, color=colours[algorithm], ls="--", lw=0.9,
                       label=f"paper's {algorithm} ({100 * k / n:.1f} %, {k}/{n})")
        ax.set_title(f"radar factors '{model}' (bars: 95 % Wilson intervals)", fontsize=8)
        ax.set_ylabel("correct association (%)")
        ax.set_ylim(40, 104)
        ax.set_xticks(np.arange(len(order)))
        ax.set_xticklabels(settings["scan.count"].to_numpy()[order], fontsize=7)
        ax.tick_params(axis="x", labelrotation=90)
    axes[-1].set_xlabel("setting, labelled by its number of scans (1 s each)")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, fontsize=7, ncol=3, loc="outside lower center")
    fig.savefig(png, dpi=200)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)
    sub.add_parser("design", help="print the config's sweep block")
    judge = sub.add_parser("judge", help="verdicts, shares and the figure of a run")
    judge.add_argument("run_dir", type=Path)
    judge.add_argument("--png", type=Path, help="where to write the figure")
    judge.add_argument("--csv", type=Path, help="where to write the per-point verdicts")
    args = parser.parse_args()
    if args.command == "design":
        print(sweep_block(design()))
        return
    table = judged(args.run_dir)
    print(shares(table))
    if args.csv:
        table.to_csv(args.csv, index=False)
    if args.png:
        figure(table, design(), args.png)


if __name__ == "__main__":
    main()
