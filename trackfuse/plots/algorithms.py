"""One look per algorithm, the same in every figure of every experiment.

Each algorithm name (unique across the experiments) has a legend label, a colour, a marker
and a *role* that sets its emphasis:

* ``paper``: the paper's own method, as the paper describes it (thick, vermillion);
* ``paper_baseline``: the baseline the paper compares against (thick);
* ``ours``: this project's improvement (thick);
* ``reference``: a bound or exact optimum (black, dashed, no band);
* ``variant``: other variants and ablations (thin, no band, drawn behind).

Colours follow the Okabe-Ito palette, which stays distinct under colour-vision deficiency.
Our methods are green circles and the paper's vermillion squares in every experiment, and no
colour means two different methods (purple is only annealing; greys are other variants); a
variant of a method may take its colour, drawn thin with a marker of its own
(``traditional_5f`` beside ``traditional``).
The two filters of ``twin_sensor`` share an association's colour and marker and differ by
line style (MGEKF solid, EKF dashed, with open markers).
"""

from __future__ import annotations

from trackfuse.reportkit.looks import (
    BLACK,
    BLUE,
    GREEN,
    GREYS,
    ORANGE,
    PURPLE,
    SKY,
    VERMILLION,
    Look,
)

PAPER_ROLES = ("paper", "paper_baseline")
"""The roles of what the paper ran (its method and its baseline)."""
OUR_ROLES = ("ours", "variant")
"""The roles of what this project adds (its methods and other variants)."""


LOOKS: dict[str, Look] = {
    # paper 000 (twin_sensor): association variants
    "paper_approx": Look("paper's fused-gate PDA", VERMILLION, "s", "paper"),
    "mspda_parallel": Look("parallel PDA (corrected)", GREEN, "o", "ours"),
    "mspda_sequential": Look("sequential PDA", BLUE, "^", "variant"),
    "nn": Look("nearest neighbour", GREYS[0], "h", "variant"),
    # paper 001 (esm_radar)
    "improved": Look("improved fuzzy evaluation (paper)", VERMILLION, "s", "paper"),
    "traditional": Look("traditional fuzzy decision (paper's baseline)", BLUE, "o",
                        "paper_baseline"),
    "improved_gauss": Look("improved, Gaussian membership (ours)", GREEN, "o", "ours"),
    "traditional_5f": Look("traditional, 5 factors", BLUE, "v", "variant"),
    "improved_static": Look("improved, static weights", GREYS[0], "^", "variant"),
    "improved_3f": Look("improved, 3 factors", GREYS[1], "<", "variant"),
    "improved_no_range": Look("improved, no range factor", GREYS[2], "P", "variant"),
    "improved_l2": Look("improved, L2 membership", GREYS[2], ">", "variant"),
    "chi2": Look("chi-square ML reference", BLACK, "", "reference"),
    "chi2_lrt": Look("chi-square reference, may abstain", GREYS[0], "", "reference"),
    "chi2_5f": Look("chi-square, 5 factors (diagnostic)", GREYS[1], "", "reference"),
    "counting": Look("counting test, track history", GREYS[0], "v", "variant"),
    "sprt": Look("sequential test (SPRT)", GREYS[1], "X", "variant"),
    # paper 002 (passive_assoc)
    "pga_paper": Look("partheno-genetic algorithm (paper)", VERMILLION, "s", "paper"),
    "pga_evict": Look("PGA + evicting re-pair (ours)", GREEN, "o", "ours"),
    "pga_anneal": Look("ours + annealing", PURPLE, "D", "ours"),
    "pga_repair": Look("PGA + re-pair", BLUE, "^", "variant"),
    "pga_repair_joint": Look("PGA + re-pair, joint evaluation", GREYS[1], "<", "variant"),
    "pga_staged": Look("PGA, staged, no re-pair", GREYS[2], ">", "variant"),
    "exact": Look("exact optimum (assignment)", BLACK, "", "reference"),
    # S passive sensors (passive_sd)
    "sd_lagrangian": Look("S-D Lagrangian relaxation, all sensors (ours)", GREEN, "o", "ours"),
    "sd_exact": Look("exact S-D optimum (integer program)", BLACK, "", "reference"),
    "exact_2d": Look("exact 2-D assignment, sensors 1 and 2", BLUE, "s", "paper_baseline"),
    # Stone Soup's filters in twin_sensor (docs/stonesoup.md): one look per filter
    "stonesoup_pda/ekf": Look("Stone Soup EKF + PDA", SKY, "v", "paper_baseline"),
    "stonesoup_pda/ukf": Look("Stone Soup UKF + PDA", ORANGE, "D", "paper_baseline"),
    "stonesoup_pda/pf": Look("Stone Soup particle filter + PDA", "#882255", "P",
                             "paper_baseline"),
}

FILTER_LABELS = {"mgekf": "MGEKF", "ekf": "EKF"}


def look(name: str) -> Look:
    """The look of ``name``; ``association/filter`` names take the association's look."""
    if name in LOOKS:  # a look of its own for one association/filter pair
        return LOOKS[name]
    base, _, filt = name.partition("/")
    found = LOOKS.get(base, Look(base, GREYS[1], ".", "variant"))
    if filt:
        found = Look(f"{found.label}, {FILTER_LABELS.get(filt, filt)}", found.colour,
                     found.marker, found.role)
    return found


def line_kwargs(name: str) -> dict:
    """Matplotlib keyword arguments for a curve of ``name`` (colour, marker, width, style)."""
    lk = look(name)
    open_marker = name.endswith("/ekf")
    kwargs = {"color": lk.colour, "marker": lk.marker or None, "label": lk.label,
              "linewidth": 2.0 if lk.emphasised else 1.0,
              "zorder": 3 if lk.emphasised else 2,
              "linestyle": "--" if lk.role == "reference" or open_marker else "-"}
    if open_marker:
        kwargs["markerfacecolor"] = "none"
    return kwargs
