"""What the three reproduced papers report (numbers, figure shapes, claims), for "paper vs
reproduced" tables; never used to tune a model. Margins and answering configs are declared
here, before any run, and read by :mod:`trackfuse.reportkit.verdicts`."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from trackfuse.association.ahp import PAPER_001_WEIGHTS


@dataclass(frozen=True)
class Answer:
    """The headline rows that answer a paper item: shipped config ``config`` (file stem), for
    ``algorithm`` (all when empty) at ``setting`` (param key -> value; all when empty)."""

    config: str
    algorithm: str = ""
    setting: Mapping[str, object] = field(default_factory=dict)


@dataclass(frozen=True)
class Beside:
    """A paper figure told whole: the paper's own scenario (config ``paper``) beside an
    ``analogue`` config, drawn by ``draw`` (``"module:function"``) for ``item``."""

    item: str
    paper: str
    analogue: str
    draw: str


@dataclass(frozen=True)
class Reported:
    """One reported result: ``where`` in the paper, ``quantity``, ``value`` (``None`` for words
    only) in ``unit``, ``runs`` behind it, ``claim`` paraphrased; ``margin`` is the smallest
    effect that counts as the claim (a fraction for rates, negative for a decline, why in
    ``margin_why``) and ``answer`` the config giving its verdict (``None``: not judged)."""

    where: str
    quantity: str
    value: float | None
    unit: str
    runs: int | None
    claim: str
    margin: float | None = None
    margin_why: str = ""
    answer: Answer | None = None


@dataclass(frozen=True)
class Paper:
    """A reproduced paper: short id, citation, its reported results and ``configs``, the
    shipped configs (file stems) that reproduce its figures and tables as written."""

    key: str
    citation: str
    results: tuple[Reported, ...]
    configs: tuple[str, ...] = ()
    beside: Beside | None = None

    def result(self, quantity: str) -> Reported:
        """The reported result whose ``quantity`` is ``quantity``."""
        return next(r for r in self.results if r.quantity == quantity)


#: Why 2 percentage points is the smallest rise of paper 000's Fig. 1 that counts: one run of
#: its 50 per level; a smaller rise cannot show in the paper's curve.
ONE_RUN_OF_50 = "one run of the paper's 50 per level: a smaller rise cannot show in its curve"
#: Why 5 percentage points is the smallest change in paper 001's Figs. 3-4 that counts.
VISIBLE_ON_RATE_AXIS = ("the smallest change that reads as a change on the paper's "
                        "correct-rate axis (its Table 3 methods differ by 18.8 points)")

TWIN_SENSOR = Paper(
    key="twin_sensor",
    citation=("Wang Yongcheng, Wang Hongfei, Yang Chengwu, \"Fusion algorithm for airborne "
              "twin-sensor synchronous angle-only tracking\", Control and Decision 20(10), "
              "2005, 1143-1146"),
    configs=("twin_sensor_orbit", "twin_sensor_fig1_claim", "twin_sensor_rmse_vs_bound"),
    beside=Beside("Fig. 1", "twin_sensor_fig1_claim", "twin_sensor_close",
                  "trackfuse.experiments.twin_sensor.report:fig1_headline"),
    results=(
        Reported("Fig. 1", "loss rate up to 9 false returns", 0.05, "fraction", 50,
                 "fused-gate PDAF: with a mean number of false returns within 9 the "
                 "percentage of lost tracks is generally below 5 %",
                 answer=Answer("twin_sensor_fig1_claim", "paper_approx/mgekf")),
        Reported("Fig. 1", "loss rises with clutter", None, "fraction", 50,
                 "the curve of lost tracks rises with clutter density", margin=0.02,
                 margin_why=ONE_RUN_OF_50,
                 answer=Answer("twin_sensor_fig1_claim", "paper_approx/mgekf")),
        Reported("Fig. 2", "range error against time", None, "m", None,
                 "the MGEKF tracks well with false returns present (no numbers given)",
                 answer=Answer("twin_sensor_orbit", "paper_approx/mgekf")),
    ),
)

#: Paper 001's Table 3 setting of the radar's own factors, declared before any run: its
#: Table 2 as written (the radar's TDOA and phase with their own noise).
AS_WRITTEN = {"radar.factor_model": "table"}

ESM_RADAR = Paper(
    key="esm_radar",
    citation=("Zhang Xiaoqiang, Wang Xing, Zhou Dongqing, Du Wenhong, Yu Yuan, \"An "
              "ESM-radar track correlation algorithm based on improved fuzzy comprehensive "
              "evaluation\", J. Air Force Eng. Univ. (Nat. Sci.) 18(1), 2017, 44-49"),
    configs=("esm_radar_snake_cross", "esm_radar_separation", "esm_radar_range_error"),
    results=(
        Reported("Table 3", "improved: correct rate", 0.740, "fraction", 500,
                 "improved fuzzy comprehensive evaluation, 200 m separation: 130 / 370 / 0 "
                 "runs to radar tracks 1 / 2 / 3",
                 answer=Answer("esm_radar_snake_cross", "improved", AS_WRITTEN)),
        Reported("Table 3", "traditional: correct rate", 0.552, "fraction", 500,
                 "traditional multi-factor fuzzy decision, 200 m separation: 224 / 276 / 0 "
                 "runs to radar tracks 1 / 2 / 3",
                 answer=Answer("esm_radar_snake_cross", "traditional", AS_WRITTEN)),
        Reported("Table 3", "improved: runs to radar track 1", 130, "runs", 500, ""),
        Reported("Table 3", "improved: runs to radar track 2", 370, "runs", 500, ""),
        Reported("Table 3", "improved: runs to radar track 3", 0, "runs", 500, ""),
        Reported("Table 3", "traditional: runs to radar track 1", 224, "runs", 500, ""),
        Reported("Table 3", "traditional: runs to radar track 2", 276, "runs", 500, ""),
        Reported("Table 3", "traditional: runs to radar track 3", 0, "runs", 500, ""),
        Reported("Table 1", "AHP lambda_max", 5.2375, "", None, "largest eigenvalue 5.2375",
                 answer=Answer("esm_radar_snake_cross")),
        Reported("Table 1", "AHP CI", 0.059375, "", None, "consistency index 0.059375",
                 answer=Answer("esm_radar_snake_cross")),
        Reported("Table 1", "AHP CR", 0.053, "", None, "consistency ratio 0.053 (RI = 1.12)",
                 answer=Answer("esm_radar_snake_cross")),
        Reported("Table 1", "AHP weights", None, "", None,
                 "weights 0.51, 0.26, 0.13, 0.07, 0.03 (range, speed, angle, TDOA, phase)",
                 answer=Answer("esm_radar_snake_cross")),
        Reported("Fig. 3", "both degrade when close", None, "fraction", None,
                 "both methods degrade when the targets are close", margin=-0.05,
                 margin_why=VISIBLE_ON_RATE_AXIS,
                 answer=Answer("esm_radar_separation", "", AS_WRITTEN)),
        Reported("Fig. 3", "clearly higher when close", None, "fraction", None,
                 "the improved one is clearly higher at close separation", margin=0.05,
                 margin_why=VISIBLE_ON_RATE_AXIS,
                 answer=Answer("esm_radar_separation", "improved", AS_WRITTEN)),
        Reported("Fig. 3", "gap narrows", None, "fraction", None,
                 "the gap narrows as separation grows", margin=0.05,
                 margin_why=VISIBLE_ON_RATE_AXIS,
                 answer=Answer("esm_radar_separation", "improved", AS_WRITTEN)),
        Reported("Abstract", "always higher", None, "fraction", None,
                 "the improved method is always higher as separation varies",
                 answer=Answer("esm_radar_separation", "improved", AS_WRITTEN)),
        Reported("Fig. 4", "both decline with range error", None, "fraction", None,
                 "both decline as the radar range error grows", margin=-0.05,
                 margin_why=VISIBLE_ON_RATE_AXIS,
                 answer=Answer("esm_radar_range_error", "", AS_WRITTEN)),
        Reported("Fig. 4", "higher throughout", None, "fraction", None,
                 "the improved one stays higher throughout",
                 answer=Answer("esm_radar_range_error", "improved", AS_WRITTEN)),
    ),
)

#: Paper 001's printed AHP weights for (range, speed, angle, TDOA, phase): the science's
#: constant, which the model also offers as an input (``paper_rounded``).
ESM_RADAR_WEIGHTS = PAPER_001_WEIGHTS

PASSIVE_ASSOC = Paper(
    key="passive_assoc",
    citation=("Liu Hang, Dou Lihua, Xin Bin, Dong Lingxun, \"Data association for passive "
              "sensor based on improved partheno-genetic algorithm\", Control and Decision "
              "23(4), 2008, 464-467"),
    configs=("passive_association",),
    results=(
        Reported("Fig. 2", "high correct rate", None, "fraction", 50,
                 "5, 7 and 10 targets all converge to a high correct association rate (no "
                 "numbers or axis ranges given)", margin=0.05,
                 margin_why="high read as within 5 points of the exact optimum's accuracy, "
                            "the ceiling of this objective",
                 answer=Answer("passive_association", "pga_paper")),
        Reported("Fig. 2", "optimum reached", None, "fraction", 50,
                 "a finite number of crossovers and mutations reaches the optimal solution",
                 answer=Answer("passive_association", "pga_paper")),
        Reported("Sec. 1", "Hungarian method on the dummy formulation", None, "", None,
                 "the Hungarian method cannot handle the formulation with missed "
                 "detections and false alarms", answer=Answer("passive_association")),
    ),
)

PAPERS = {p.key: p for p in (TWIN_SENSOR, ESM_RADAR, PASSIVE_ASSOC)}
