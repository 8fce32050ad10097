"""What the three reproduced papers themselves report, for "paper vs reproduced" tables.

Only what each paper states: numbers, the shape of its figures, and its claims. These values
are for comparison and are never used to tune a model. ``docs/papers/*.md`` discusses where
we agree and where we differ.

Each :class:`Reported` item names the paper's figure or table, the quantity, the paper's
value (a number, or ``None`` when the paper gives only words) and the paper's words.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Reported:
    """One reported result of a paper.

    ``where``: the paper's figure or table (e.g. ``"Table 3"``). ``quantity``: what is
    measured, in our words. ``value``: the paper's number (``None`` if it gives only text).
    ``unit``: unit of ``value``. ``runs``: Monte Carlo runs behind it, when stated.
    ``claim``: the paper's statement, paraphrased.
    """

    where: str
    quantity: str
    value: float | None
    unit: str
    runs: int | None
    claim: str


@dataclass(frozen=True)
class Paper:
    """A reproduced paper: short id, citation, its reported results and ``configs``, the
    shipped configs (file stems) that reproduce its figures and tables as written."""

    key: str
    citation: str
    results: tuple[Reported, ...]
    configs: tuple[str, ...] = ()

    def result(self, quantity: str) -> Reported:
        """The reported result whose ``quantity`` is ``quantity``."""
        return next(r for r in self.results if r.quantity == quantity)


TWIN_SENSOR = Paper(
    key="twin_sensor",
    citation=("Wang Yongcheng, Wang Hongfei, Yang Chengwu, \"Fusion algorithm for airborne "
              "twin-sensor synchronous angle-only tracking\", Control and Decision 20(10), "
              "2005, 1143-1146"),
    configs=("twin_sensor_orbit", "twin_sensor_fig1_claim", "twin_sensor_rmse_vs_bound"),
    results=(
        Reported("Fig. 1", "loss rate up to 9 false returns", 0.05, "fraction", 50,
                 "fused-gate PDAF: with a mean number of false returns within 9 the "
                 "percentage of lost tracks is generally below 5 %; the curve rises with "
                 "clutter density"),
        Reported("Fig. 2", "range error against time", None, "m", None,
                 "the MGEKF tracks well with false returns present (no numbers given)"),
    ),
)

ESM_RADAR = Paper(
    key="esm_radar",
    citation=("Zhang Xiaoqiang, Wang Xing, Zhou Dongqing, Du Wenhong, Yu Yuan, \"An "
              "ESM-radar track correlation algorithm based on improved fuzzy comprehensive "
              "evaluation\", J. Air Force Eng. Univ. (Nat. Sci.) 18(1), 2017, 44-49"),
    configs=("esm_radar_snake_cross", "esm_radar_separation", "esm_radar_range_error"),
    results=(
        Reported("Table 3", "improved: correct rate", 0.740, "fraction", 500,
                 "improved fuzzy comprehensive evaluation, 200 m separation: 130 / 370 / 0 "
                 "runs to radar tracks 1 / 2 / 3"),
        Reported("Table 3", "traditional: correct rate", 0.552, "fraction", 500,
                 "traditional multi-factor fuzzy decision, 200 m separation: 224 / 276 / 0 "
                 "runs to radar tracks 1 / 2 / 3"),
        Reported("Table 3", "improved: runs to radar track 1", 130, "runs", 500, ""),
        Reported("Table 3", "improved: runs to radar track 2", 370, "runs", 500, ""),
        Reported("Table 3", "improved: runs to radar track 3", 0, "runs", 500, ""),
        Reported("Table 3", "traditional: runs to radar track 1", 224, "runs", 500, ""),
        Reported("Table 3", "traditional: runs to radar track 2", 276, "runs", 500, ""),
        Reported("Table 3", "traditional: runs to radar track 3", 0, "runs", 500, ""),
        Reported("Table 1", "AHP lambda_max", 5.2375, "", None, "largest eigenvalue"),
        Reported("Table 1", "AHP CI", 0.059375, "", None, "consistency index"),
        Reported("Table 1", "AHP CR", 0.053, "", None, "consistency ratio (RI = 1.12)"),
        Reported("Fig. 3", "correct rate against separation", None, "fraction", None,
                 "both methods degrade when the targets are close; the improved one is "
                 "clearly higher at close separation; the gap narrows as separation grows"),
        Reported("Fig. 4", "correct rate against radar range error", None, "fraction", None,
                 "both decline as the radar range error grows; the improved one stays "
                 "higher throughout"),
    ),
)

#: Paper 001's printed AHP weights for (range, speed, angle, TDOA, phase).
ESM_RADAR_WEIGHTS = (0.51, 0.26, 0.13, 0.07, 0.03)

PASSIVE_ASSOC = Paper(
    key="passive_assoc",
    citation=("Liu Hang, Dou Lihua, Xin Bin, Dong Lingxun, \"Data association for passive "
              "sensor based on improved partheno-genetic algorithm\", Control and Decision "
              "23(4), 2008, 464-467"),
    configs=("passive_association",),
    results=(
        Reported("Fig. 2", "accuracy against genetic operations", None, "fraction", 50,
                 "5, 7 and 10 targets all converge to a high correct association rate; a "
                 "finite number of crossovers and mutations reaches the optimal solution "
                 "(no numbers or axis ranges given)"),
        Reported("Sec. 1", "Hungarian method on the dummy formulation", None, "", None,
                 "the Hungarian method cannot handle the formulation with missed "
                 "detections and false alarms"),
    ),
)

PAPERS = {p.key: p for p in (TWIN_SENSOR, ESM_RADAR, PASSIVE_ASSOC)}
