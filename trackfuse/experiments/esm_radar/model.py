"""Experiment ``esm_radar``: paper 001, ESM-to-radar track association. Every algorithm of
:data:`ALGORITHMS` picks a radar track from one trial's data (the truth is track 2); model
and metrics: ``docs/papers/esm_radar.md``."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from trackfuse.association import ahp
from trackfuse.association.dynamic_weights import dynamic_weights
from trackfuse.association.esm_scenario import (
    ANGULAR,
    FACTORS,
    ESMNoise,
    RadarNoise,
    SnakeCross,
    esm_factors,
    nominal_sd,
    radar_factors,
    true_factors,
)
from trackfuse.association.fuzzy import (
    compose,
    decide_mean,
    decide_vote,
    gaussian_membership,
    gaussian_posterior_membership,
    inverse_distance_membership,
)
from trackfuse.association.manoeuvre import (
    ca_innovations,
    cv_innovations,
    manoeuvre_index,
    nis_threshold,
    windowed_nis,
)
from trackfuse.association.tdoa_df import C
from trackfuse.association.time_align import bracket, interpolate, interpolate_covariance
from trackfuse.association.track_history_tests import (
    counting_decision,
    counting_threshold,
    sprt_decision,
)
from trackfuse.association.track_likelihood import (
    abstaining_decision,
    gaussian_nll_terms,
    ml_track_decision,
)
from trackfuse.chi2 import chi2_quantile
from trackfuse.experiments.base import NON_NEGATIVE, Metric, Param
from trackfuse.rowtable import RowTable
from trackfuse.seeding import TrialStreams
from trackfuse.tracking.models import wrap

TRUE_TRACK = 1  # 0-based index of radar track 2
N_TRACKS = 3
EPS_FRACTION = 1e-3  # eps_i = 1e-3 sqrt(sigma_E^2 + sigma_R^2), floor of the 1/d membership
UNINFORMATIVE_VAR = 1e24  # m^2: variance given to an ESM range that could not be computed


@dataclass(frozen=True)
class Variant:
    """How one algorithm evaluates the association: ``factors`` (or ``"baseline"``), ``membership``
    (``gaussian``, ``l1``, ``l2``, ``posterior``, ``"param"``; ``chi2``/``chi2_lrt`` for ML),
    ``dynamic`` weights, ``decision``, a one-line ``summary`` and ``subset_weights`` (``ahp``
    of the sub-block or ``rescaled``)."""

    factors: tuple[str, ...] | str
    membership: str
    dynamic: bool = False
    decision: str = "mean"
    summary: str = ""
    subset_weights: str = "ahp"


FIVE = FACTORS
THREE = ("range", "speed", "angle")
ALGORITHMS: dict[str, Variant] = {
    "traditional": Variant("baseline", "gaussian", False, "param",
                           "baseline factors, Gaussian grade, static AHP weights"),
    "traditional_5f": Variant(FIVE, "gaussian", False, "param",
                              "5 factors, Gaussian grade, static AHP weights"),
    "improved": Variant(FIVE, "param", True, "mean",
                        "paper 001: 5 factors, 1/d membership, dynamic weights"),
    "improved_static": Variant(FIVE, "param", False, "mean", "improved, static weights"),
    "improved_no_range": Variant(FIVE[1:], "param", False, "mean",
                                 "improved without range, static weights rescaled",
                                 subset_weights="rescaled"),
    "improved_3f": Variant(THREE, "param", True, "mean", "improved, 3 factors"),
    "improved_l2": Variant(FIVE, "l2", True, "mean", "improved, L2 1/d membership"),
    "improved_gauss": Variant(FIVE, "posterior", True, "mean",
                              "improved, Gaussian posterior membership"),
    "chi2": Variant(("speed", "angle", "tdoa", "phase"), "chi2",
                    summary="ML track-to-track reference, ESM range excluded"),
    "chi2_lrt": Variant(("speed", "angle", "tdoa", "phase"), "chi2_lrt",
                        summary="chi2 with a no-decision outcome (LR threshold, chi2 gate)"),
    "chi2_5f": Variant(FIVE, "chi2",
                       summary="ML on all 5 factors, linearized TDOA-DF range covariance"),
    "counting": Variant(("speed", "angle", "tdoa", "phase"), "counting",
                        summary="counting test: scans inside the chi2 gate, binomial threshold"),
    "sprt": Variant(("speed", "angle", "tdoa", "phase"), "sprt",
                    summary="Wald's sequential test on the chi2 gate indicators"),
}

PARAMS = (
    Param("algorithms", ["traditional", "improved", "chi2"],
          "association algorithms run on every trial (same data)", kind=list,
          choices=tuple(ALGORITHMS), draws=False),
    Param("scan.count", 50, "ESM samples per trial K", "samples", kind=int, low=3, high=10_000),
    Param("esm.period", 1.0, "ESM sampling period", "s", low=1e-3, high=600.0),
    Param("radar.period", 1.0, "radar sampling period", "s", low=1e-3, high=600.0),
    Param("esm.offset", 0.0, "time of the first ESM sample after the first radar sample", "s",
          low=0.0, high=600.0),
    Param("time_align", False,
          "interpolate radar factors to ESM times (eq. 1, corrected eq. 2); else hold the "
          "latest radar sample", kind=bool, draws=False),
    Param("geometry.baseline", 10_000.0, "A2 - A1 along x (A1 at the origin)", "m", low=1.0,
          high=1e6),
    Param("target.separation", 200.0, "T2 - T1 along x", "m", low=0.0, high=1e5,
          label="T1–T2 separation", symbol="separation"),
    Param("snake.amplitude", 1000.0, "snake manoeuvre amplitude A", "m", low=0.0, high=1e5,
          label="snake amplitude", symbol="A",
          words=((0.0, "no weave"), (1000.0, "1 km weave"))),
    Param("snake.period", 40.0, "snake manoeuvre period P_w", "s", low=1.0, high=1e4),
    Param("snake.speed", 200.0, "T1/T2 speed toward the own aircraft V", "m/s", low=0.0,
          high=3000.0),
    Param("crossing.time", 30.0, "time t_c at which T3 crosses the T1/T2 centre line", "s", low=1.0,
          high=1e4),
    Param("phase.d_over_lambda", 0.5, "interferometer spacing over wavelength", "1", low=0.01,
          high=100.0,
          label="interferometer spacing d/λ", symbol="d/λ"),
    Param("radar.factor_model", "table",
          "radar TDOA/phase: 'table' = own noise (Table 2), 'derived' = from radar position",
          kind=str, choices=("table", "derived"),
          label="radar factors",
          words=(("table", "'table' (own noise)"), ("derived", "'derived' (from position)"))),
    Param("radar.sigma_range_coef", 0.01, "radar range sd as a fraction of range", "1/R", low=0.0,
          high=1.0,
          label="radar range sd / range", symbol="$\\sigma_R/R$"),
    Param("radar.sigma_speed", 10.0, "radar speed sd", "m/s", low=0.0, high=1e4),
    Param("radar.sigma_angle", 8e-3, "radar bearing sd", "rad", low=0.0, high=3.0),
    Param("radar.sigma_tdoa", 3e-8, "radar TDOA sd ('table' model)", "s", low=0.0, high=1e-3),
    Param("radar.sigma_phase", 0.5, "radar phase sd ('table' model)", "rad", low=0.0, high=10.0),
    Param("esm.sigma_speed", 20.0, "ESM speed sd (> 0: memberships divide by the summed "
          "variance)", "m/s", low=1e-6, high=1e4),
    Param("esm.sigma_angle", 0.03, "ESM bearing sd", "rad", low=1e-6, high=3.0),
    Param("esm.sigma_tdoa", 3e-8, "ESM TDOA sd", "s", low=1e-12, high=1e-3),
    Param("esm.sigma_phase", 1.0, "ESM phase sd (> 0)", "rad", low=1e-6, high=10.0),
    Param("esm.min_denominator", 1.0,
          "TDOA-DF guard: |2(u'b - dr)| below this flags the sample invalid", "m", low=0.0,
          high=1e5),
    Param("noise.scale", 1.0,
          "multiplies every simulated noise draw (0 = noise-free data); the algorithms keep "
          "the nominal sigmas", "1", low=0.0, high=100.0),
    Param("weights", "root_exact", "AHP weights: root method, eigenvector, or the paper's "
          "rounded set (5 factors only; subsets use the root method)", kind=str,
          choices=("root_exact", "eigen", "paper_rounded"), draws=False),
    Param("membership_norm", "l1", "normalization of the 1/d membership of 'improved'", kind=str,
          choices=("l1", "l2"), draws=False),
    Param("alpha.index", "nis_tdoa",
          "manoeuvre index: 'nis_tdoa' = windowed NIS of a constant-acceleration filter on the "
          "ESM range difference c*dt (default), 'literal' = paper eq. 8-13, residual of a CV "
          "filter on the TDOA-DF range over its measurement variance (needs alpha.max_mode "
          "'fixed' or 'running_max')", kind=str, choices=("nis_tdoa", "literal"), draws=False,
          label="manoeuvre index",
          words=(("nis_tdoa", "NIS index"), ("literal", "literal index"))),
    Param("alpha.window", 5, "scans N averaged in the manoeuvre index", "samples", kind=int, low=1,
          high=10_000, draws=False),
    Param("alpha.max_mode", "chi2",
          "alpha_max of eq. 14: 'chi2' = quantile 1 - alpha.false_alarm of chi2(N)/N, the "
          "no-manoeuvre distribution of the 'nis_tdoa' index (so only with alpha.index "
          "'nis_tdoa'); 'fixed' = alpha.max; 'running_max' = running maximum of alpha",
          kind=str, choices=("chi2", "fixed", "running_max"), draws=False,
          label="α_max mode", words=(("chi2", "α_max chi-square"), ("fixed", "α_max fixed"),
                                          ("running_max", "α_max running max"))),
    Param("alpha.false_alarm", 0.01, "'chi2' mode: probability that the index of a "
          "non-manoeuvring target exceeds alpha_max in a window", "1", low=1e-9, high=0.5,
          draws=False),
    Param("alpha.max", 10.0, "alpha_max of eq. 14 in 'fixed' mode", "1", low=1e-6, high=1e9,
          draws=False,
          label="α_max"),
    Param("alpha.accel_change_sd", 0.05,
          "'nis_tdoa': sd of the range-difference acceleration change over one period "
          "(DWPA process noise)", "m/s^2", low=0.0, high=1e4, draws=False),
    Param("alpha.q", 1.0, "'literal': white acceleration variance of the range CV filter",
          "m^2/s^4", low=0.0, high=1e6, draws=False),
    Param("lrt.threshold", float(np.log(19.0)),
          "chi2_lrt: least best-vs-second log-likelihood ratio to declare a track "
          "(log 19: 95 % between the two)", "nat", low=0.0, high=1e6, draws=False),
    Param("gate.alpha", 0.001, "chi2_lrt: false-rejection probability of the chi-square "
          "goodness-of-fit gate on the best track (0 = no gate)", "1", low=0.0, high=0.5,
          draws=False),
    Param("history.p_gate", 0.99, "counting, sprt: probability that a scan of the ESM's own "
          "radar track falls inside the chi-square gate (the gate's quantile)", "1", low=0.5,
          high=0.999999, draws=False),
    Param("history.p_false", 0.1, "counting, sprt: declared probability that a scan of "
          "another target's radar track falls inside the gate (must be below "
          "history.p_gate)", "1", low=1e-6, high=0.99, draws=False),
    Param("history.alpha", 0.01, "counting, sprt: design false-association rate", "1",
          low=1e-9, high=0.5, draws=False),
    Param("counting.window", 20, "counting: the last n scans counted (all when n exceeds "
          "scan.count)", "samples", kind=int, low=1, high=10_000, draws=False),
    Param("sprt.beta", 0.01, "sprt: design missed-association rate", "1", low=1e-9,
          high=0.5, draws=False),
    Param("baseline.factors", ["range", "speed", "angle"], "factors of 'traditional'", kind=list,
          choices=FACTORS, draws=False),
    Param("baseline.tau", 0.5, "Gaussian grade exp(-tau d^2/(s_E^2+s_R^2))", "1", low=1e-6,
          high=1e6, draws=False),
    Param("baseline.spread", "nominal",
          "spread of the traditional Gaussian grade: 'nominal' = sensor sd at the scenario's "
          "noise-free geometry, averaged over the scans (static, default); 'trial_mean' = "
          "per-trial time mean of the sd from the measured values (static); 'per_sample' = "
          "sd recomputed at every scan from the measured bearing/TDOA/range (handicapped: "
          "sharp when the ESM range falls short)", kind=str,
          choices=("nominal", "trial_mean", "per_sample"), draws=False,
          label="spread", words=(("nominal", "spread nominal"),
                                     ("trial_mean", "spread trial mean"),
                                     ("per_sample", "spread per sample"))),
    Param("baseline.decision", "mean", "'traditional' decision: mean membership or majority "
          "vote of per-scan decisions", kind=str, choices=("mean", "vote"), draws=False),
)


@dataclass
class Simulated:
    """Aligned data of a batch of N trials (K ESM scans, J = 3 radar tracks, 5 factors)."""

    t: np.ndarray          # (K,) ESM times, s
    truth_p: np.ndarray    # (K, 3, 2) true positions at the ESM times, m
    x_esm: np.ndarray      # (N, K, 5) ESM factors
    P_esm: np.ndarray      # (N, K, 5, 5)
    esm_valid: np.ndarray  # (N, K) bool
    x_radar: np.ndarray    # (N, K, J, 5) radar factors aligned to the ESM times
    P_radar: np.ndarray    # (N, K, J, 5, 5)
    alpha: np.ndarray      # (N, K) manoeuvre index, NaN where not defined yet
    sd_nominal: np.ndarray  # (2, 5) ESM and radar sd at the noise-free geometry


def sensor_noise(params: Mapping[str, Any]) -> tuple[ESMNoise, RadarNoise]:
    """The ESM and radar accuracies of ``params`` (paper 001 Table 2 by default)."""
    return (ESMNoise(params["esm.sigma_speed"], params["esm.sigma_angle"],
                     params["esm.sigma_tdoa"], params["esm.sigma_phase"]),
            RadarNoise(params["radar.sigma_range_coef"], params["radar.sigma_speed"],
                       params["radar.sigma_angle"], params["radar.sigma_tdoa"],
                       params["radar.sigma_phase"]))


def manoeuvre_alpha(params: Mapping[str, Any], x_esm: np.ndarray, P_esm: np.ndarray,
                    index: str) -> np.ndarray:
    """Manoeuvre index ``alpha`` (N, K) of the ESM track from ``x_esm`` (N, K, 5) and ``P_esm``
    (``index`` ``"nis_tdoa"`` or ``"literal"``); NaN at start-up or without an ESM range."""
    T, window = params["esm.period"], params["alpha.window"]
    if index == "nis_tdoa":
        nu, S = ca_innovations(C * x_esm[..., 3], C**2 * P_esm[..., 3, 3], T,
                               params["alpha.accel_change_sd"] ** 2)
        return windowed_nis(nu, S, window)
    if index == "literal":
        R_n = P_esm[..., 0, 0]
        return manoeuvre_index(cv_innovations(x_esm[..., 0], R_n, T, params["alpha.q"])[0], R_n,
                               window)
    raise ValueError(f"unknown manoeuvre index {index!r}")


def alpha_max_problem(params: Mapping[str, Any]) -> str | None:
    """Why ``alpha.max_mode`` cannot be used with ``alpha.index`` (one line), else ``None``:
    ``chi2`` mode needs the ``nis_tdoa`` index."""
    if params["alpha.max_mode"] == "chi2" and params["alpha.index"] != "nis_tdoa":
        return (f"'chi2' needs alpha.index 'nis_tdoa', not {params['alpha.index']!r}; allowed "
                "with the 'literal' index: 'fixed' (alpha.max) or 'running_max'")
    return None


def uses_alpha_max(variant: Variant, names: tuple[str, ...]) -> bool:
    """Whether ``variant`` cuts its range weight by the manoeuvre index."""
    return variant.dynamic and names[0] == "range"


def alpha_max(params: Mapping[str, Any]) -> tuple[float, str]:
    """``alpha_max`` and the :func:`dynamic_weights` mode for ``params``, or ``ValueError``."""
    problem = alpha_max_problem(params)
    if problem is not None:
        raise ValueError(f"alpha.max_mode: {problem}")
    mode = params["alpha.max_mode"]
    if mode == "chi2":
        return nis_threshold(params["alpha.window"], params["alpha.false_alarm"]), "fixed"
    return params["alpha.max"], mode


def scenario(params: Mapping[str, Any]) -> SnakeCross:
    """The noise-free three-target scenario of ``params``."""
    return SnakeCross(separation=params["target.separation"],
                      amplitude=params["snake.amplitude"],
                      snake_period=params["snake.period"], speed=params["snake.speed"],
                      t_cross=params["crossing.time"])


def esm_times(params: Mapping[str, Any]) -> np.ndarray:
    """ESM sample times (K,) in s: ``esm.offset + esm.period * k``, k = 0..K-1."""
    return params["esm.offset"] + params["esm.period"] * np.arange(params["scan.count"])


def simulate(params: Mapping[str, Any], streams: Sequence[TrialStreams]) -> Simulated:
    """Draw and align one trial's sensor data per stream: fixed-shape standard normals from the
    common stream, scaled afterwards, so sweeps of separation or accuracy share the noise."""
    scen = scenario(params)
    A1 = np.zeros(2)
    A2 = np.array([params["geometry.baseline"], 0.0])
    dl, model = params["phase.d_over_lambda"], params["radar.factor_model"]
    K, TR = params["scan.count"], params["radar.period"]
    t = esm_times(params)
    M = int(np.floor(t[-1] / TR + 1e-9)) + 2
    p_k, v_k = scen.states(t)
    p_m, v_m = scen.states(TR * np.arange(M))
    f_esm = true_factors(p_k[:, TRUE_TRACK], v_k[:, TRUE_TRACK], A1, A2, dl)
    f_radar = true_factors(p_m, v_m, A1, A2, dl)

    z_esm, z_radar = [], []
    for trial in streams:
        g_esm, g_radar = trial.common.spawn(2)
        z_esm.append(g_esm.standard_normal((K, 4)))
        z_radar.append(g_radar.standard_normal((M, N_TRACKS, 5)))
    scale = params["noise.scale"]
    esm_noise, radar_noise = sensor_noise(params)
    x_e, P_e, valid = esm_factors(f_esm, scale * np.stack(z_esm), esm_noise, A1, A2,
                                  params["esm.min_denominator"])
    x_r, P_r = radar_factors(f_radar, scale * np.stack(z_radar), radar_noise, model, A1, A2,
                             dl)
    sd_nominal = np.stack(nominal_sd(f_esm, esm_noise, radar_noise, model, A1, A2, dl,
                                     params["esm.min_denominator"]))

    m1, a = bracket(t, TR, M)
    if params["time_align"] and np.any(a > 0):
        x_rk = np.stack([interpolate(x_r[..., i], m1, a, angular=bool(ANGULAR[i]), axis=1)
                         for i in range(5)], axis=-1)
        P_rk = interpolate_covariance(P_r, m1, a, axis=1)
    else:  # synchronous sensors, or no alignment: the latest radar sample
        x_rk, P_rk = x_r[:, m1], P_r[:, m1]
    alpha = manoeuvre_alpha(params, x_e, P_e, params["alpha.index"])
    return Simulated(t, p_k, x_e, P_e, valid, x_rk, P_rk, alpha, sd_nominal)


def static_weights(factors: Sequence[str], method: str) -> np.ndarray:
    """AHP weights of ``factors`` from Table 1: ``root_exact`` or ``eigen`` on the sub-matrix, or
    ``paper_rounded`` (full set only; subsets fall back to the root method)."""
    idx = [FACTORS.index(f) for f in factors]
    if method == "paper_rounded" and len(idx) == len(FACTORS):
        return np.array(ahp.PAPER_001_WEIGHTS)
    sub = ahp.PAPER_001_JUDGEMENT[np.ix_(idx, idx)]
    return ahp.weights(sub, "eigen" if method == "eigen" else "root")


def variant_weights(variant: Variant, names: Sequence[str], method: str) -> np.ndarray:
    """Static weights (F,) of ``variant`` on ``names``: of the subset, or the five-factor weights
    rescaled (``subset_weights = "rescaled"``)."""
    if variant.subset_weights == "ahp":
        return static_weights(names, method)
    five = static_weights(FACTORS, method)
    kept = five[[FACTORS.index(f) for f in names]]
    return kept / kept.sum()


def factor_names(variant: Variant, params: Mapping[str, Any]) -> tuple[str, ...]:
    """The factor names ``variant`` uses, in :data:`FACTORS` order."""
    names = params["baseline.factors"] if variant.factors == "baseline" else variant.factors
    return tuple(f for f in FACTORS if f in set(names))


@dataclass
class Differences:
    """ESM-minus-radar factor differences of a batch, with summed variances ``var`` and spreads."""

    d: np.ndarray               # (N, K, J, 5) differences, angle and phase wrapped
    var: np.ndarray             # (N, K, J, 5) summed ESM + radar variances, per scan
    S: np.ndarray               # (N, K, J, 5, 5) difference covariances
    var_nominal: np.ndarray     # (5,) summed variances at the noise-free geometry
    var_trial_mean: np.ndarray  # (N, 1, 1, 5) summed per-trial time-mean variances
    ml_cache: dict = field(default_factory=dict)  # ML decisions by factor subset


def _summed_variance(sd_esm: np.ndarray, sd_radar: np.ndarray) -> np.ndarray:
    """``sd_esm^2 + sd_radar^2``; an undefined ESM range gets an uninformative variance."""
    var = np.square(sd_esm) + np.square(sd_radar)
    return np.where(np.isfinite(var), var, UNINFORMATIVE_VAR)


def static_spreads(sim: Simulated) -> tuple[np.ndarray, np.ndarray]:
    """Static spreads of the traditional grade: ``var_nominal`` (5,) and ``var_trial_mean``
    (N, 1, 1, 5) (``docs/papers/esm_radar.md``, "Traditional baseline")."""
    var_nominal = _summed_variance(sim.sd_nominal[0], sim.sd_nominal[1])
    # Invalid TDOA-DF samples are carried forward, so a trial's ESM range sd is NaN at
    # every scan or at none: its time mean is NaN exactly when the trial has no ESM range.
    sd_e = np.sqrt(np.diagonal(sim.P_esm, axis1=-2, axis2=-1))          # (N, K, 5)
    sd_r = np.sqrt(np.diagonal(sim.P_radar, axis1=-2, axis2=-1))        # (N, K, J, 5)
    var_trial = _summed_variance(sd_e.mean(axis=1), sd_r.mean(axis=(1, 2)))
    return var_nominal, var_trial[:, None, None, :]


def differences(sim: Simulated) -> Differences:
    """Factor differences and their (co)variances between the ESM track and each radar track."""
    d = sim.x_esm[:, :, None, :] - sim.x_radar
    d[..., ANGULAR] = wrap(d[..., ANGULAR])
    S = sim.P_esm[:, :, None] + sim.P_radar
    # A trial whose TDOA-DF inversion never succeeded has no ESM range: make that factor
    # uninformative (zero difference, huge variance, no correlation) for every track.
    missing = np.isnan(d[..., 0])
    if missing.any():
        d[..., 0] = np.where(missing, 0.0, d[..., 0])
        S[..., 0, :] = np.where(missing[..., None], 0.0, S[..., 0, :])
        S[..., :, 0] = np.where(missing[..., None], 0.0, S[..., :, 0])
        S[..., 0, 0] = np.where(missing, UNINFORMATIVE_VAR, S[..., 0, 0])
    var_nominal, var_trial_mean = static_spreads(sim)
    return Differences(d, np.diagonal(S, axis1=-2, axis2=-1).copy(), S, var_nominal,
                       var_trial_mean)


def baseline_variance(diff: Differences, rule: str) -> np.ndarray:
    """``sigma_E^2 + sigma_R^2`` of the traditional grade by ``rule`` (``nominal``, ``trial_mean``,
    ``per_sample``; W001-8), broadcastable to (N, K, J, 5)."""
    if rule == "nominal":
        return diff.var_nominal
    if rule == "trial_mean":
        return diff.var_trial_mean
    if rule == "per_sample":
        return diff.var
    raise ValueError(f"unknown baseline spread {rule!r}")


def membership(kind: str, d: np.ndarray, diff: Differences, idx: Sequence[int],
               params: Mapping[str, Any]) -> np.ndarray:
    """Memberships ``R`` (N, K, F, J) of one fuzzy algorithm from ``d`` (N, K, J, F); ``kind``
    ``gaussian``, ``posterior``, ``l1`` or ``l2``."""
    dd = np.swapaxes(d, -1, -2)
    if kind == "gaussian":
        var = baseline_variance(diff, params["baseline.spread"])[..., idx]
        return gaussian_membership(dd, np.swapaxes(np.broadcast_to(var, d.shape), -1, -2),
                                   params["baseline.tau"])
    vv = np.swapaxes(diff.var[..., idx], -1, -2)
    if kind == "posterior":
        return gaussian_posterior_membership(dd, vv, 0.5)
    return inverse_distance_membership(dd, EPS_FRACTION * np.sqrt(vv), kind)


def evaluate(variant: Variant, diff: Differences, alpha: np.ndarray,
             params: Mapping[str, Any]) -> dict[str, np.ndarray]:
    """Run one algorithm on a batch: dict of (N,) ``chosen`` (0-based), ``margin``,
    ``range_weight_mean``, ``range_weight_min``; fuzzy variants add ``weights`` (N, K, F) and
    ``range_weights`` (N, K)."""
    names = factor_names(variant, params)
    idx = [FACTORS.index(f) for f in names]
    N, K = alpha.shape
    d = diff.d[..., idx]
    if variant.membership in ("counting", "sprt"):
        return history_test(variant.membership, d, diff.S[..., idx, :][..., idx], params)
    if variant.membership in ("chi2", "chi2_lrt"):
        key = tuple(idx)
        if key not in diff.ml_cache:
            diff.ml_cache[key] = ml_track_decision(d, diff.S[..., idx, :][..., idx])
        j, margin, D = diff.ml_cache[key]
        if variant.membership == "chi2_lrt":
            D_best = np.take_along_axis(D, j[..., None], axis=-1)[..., 0]
            j = abstaining_decision(j, margin, D_best, K * len(idx), params["lrt.threshold"],
                                    params["gate.alpha"])
        zero = np.zeros(N)
        return {"chosen": j, "margin": margin, "range_weight_mean": zero,
                "range_weight_min": zero}
    kind = params["membership_norm"] if variant.membership == "param" else variant.membership
    R = membership(kind, np.abs(d), diff, idx, params)
    a0 = variant_weights(variant, names, params["weights"])
    if uses_alpha_max(variant, names):
        a_max, mode = alpha_max(params)
        a = dynamic_weights(a0, np.nan_to_num(alpha, nan=0.0), a_max, mode)
    else:
        a = np.broadcast_to(a0, (N, K, len(idx)))
    b = compose(a, R)                                                # (N, K, J)
    decision = params["baseline.decision"] if variant.decision == "param" else variant.decision
    j, margin = decide_vote(b) if decision == "vote" else decide_mean(b)
    a_range = a[..., 0] if names[0] == "range" else np.zeros((N, K))
    return {"chosen": j, "margin": margin, "range_weight_mean": a_range.mean(axis=-1),
            "range_weight_min": a_range.min(axis=-1), "weights": a, "range_weights": a_range}


def history_test(kind: str, d: np.ndarray, S: np.ndarray, params: Mapping[str, Any]
                 ) -> dict[str, np.ndarray]:
    """The counting test or the SPRT (``kind``) on differences ``d`` (N, K, J, F) with
    covariances ``S`` (N, K, J, F, F): the :func:`evaluate` result, ``margin`` the winner's
    lead in count (counting) or in log-likelihood ratio (sprt, nats) over the runner-up."""
    p_gate, p_false = params["history.p_gate"], params["history.p_false"]
    if p_false >= p_gate:
        raise ValueError(f"history.p_false {p_false} must be below history.p_gate {p_gate}")
    m2, _ = gaussian_nll_terms(d, S)                                   # (N, K, J)
    gamma = chi2_quantile(p_gate, d.shape[-1])
    if kind == "counting":
        n = min(int(params["counting.window"]), m2.shape[1])
        threshold = counting_threshold(n, p_false, params["history.alpha"])
        j, score = counting_decision(m2, gamma, n, threshold)
    else:
        j, score = sprt_decision(m2, gamma, p_gate, p_false, params["history.alpha"],
                                 params["sprt.beta"])
    top2 = -np.sort(-score.astype(float), axis=-1)[..., :2]
    zero = np.zeros(len(m2))
    return {"chosen": j, "margin": top2[..., 0] - top2[..., 1], "range_weight_mean": zero,
            "range_weight_min": zero}


#: Per-scan columns (``;``-separated, one value per ESM scan, ``nan`` where undefined) and
#: the format of their values. The ESM-track series are written once per trial, on its first
#: row; ``range_weight_per_scan`` on the rows of algorithms with dynamic weights.
SCAN_SERIES = {
    "alpha_per_scan": ".3g",                   # manoeuvre index alpha(k), 1
    "esm_range_error_per_scan_m": ".0f",       # TDOA-DF range minus true range of T2, m
    "esm_bearing_error_per_scan_mrad": ".1f",  # ESM bearing minus true bearing of T2, mrad
    "range_weight_per_scan": ".3g",            # range factor's weight a_1(k), 1
}


def encode_series(values: np.ndarray, fmt: str) -> list[str]:
    """Per-scan CSV cells: each row of ``values`` (N, K) as ``fmt`` joined by ``;`` (N strings)."""
    a = np.asarray(values, dtype=float)
    a = np.where(np.isfinite(a), a, np.nan)  # %-formatting writes inf as inf
    line = ";".join([f"%{fmt}"] * a.shape[-1])
    return [line % tuple(row) for row in a.tolist()]


def decode_series(cells: Sequence[str]) -> np.ndarray:
    """The (N, K) array of N per-scan cells written by :func:`encode_series`."""
    return np.array([[float(v) for v in str(cell).split(";")] for cell in cells])


def esm_errors(sim: Simulated) -> tuple[np.ndarray, np.ndarray]:
    """ESM range error (m) and wrapped bearing error (rad) of target 2, (N, K) each; NaN without a
    range."""
    truth = sim.truth_p[:, TRUE_TRACK]                                  # (K, 2), A1 at 0
    r_true = np.hypot(truth[:, 0], truth[:, 1])
    theta_true = np.arctan2(truth[:, 1], truth[:, 0])
    return sim.x_esm[..., 0] - r_true, wrap(sim.x_esm[..., 2] - theta_true)


def _esm_track_columns(sim: Simulated) -> dict[str, np.ndarray | list[str]]:
    """Per-trial columns (N,) of the ESM track: summaries, then :data:`SCAN_SERIES`."""
    alpha = np.nan_to_num(sim.alpha, nan=0.0)
    defined = np.isfinite(sim.alpha).sum(axis=-1)
    dr, dtheta = esm_errors(sim)
    return {
        "alpha_mean": np.divide(alpha.sum(axis=-1), defined, out=np.zeros(len(alpha)),
                                where=defined > 0),
        "alpha_peak": alpha.max(axis=-1),
        "esm_invalid": (~sim.esm_valid).sum(axis=-1),
        "esm_range_sigma_m": np.sqrt(sim.P_esm[..., 0, 0]).mean(axis=-1),
        "alpha_per_scan": encode_series(sim.alpha, SCAN_SERIES["alpha_per_scan"]),
        "esm_range_error_per_scan_m": encode_series(
            dr, SCAN_SERIES["esm_range_error_per_scan_m"]),
        "esm_bearing_error_per_scan_mrad": encode_series(
            1e3 * dtheta, SCAN_SERIES["esm_bearing_error_per_scan_mrad"])}


def run_batch(params: Mapping[str, Any], streams: Sequence[TrialStreams]) -> RowTable:
    """Vectorized trials: rows trial-major, one per algorithm (see the module docstring)."""
    sim = simulate(params, streams)
    esm = _esm_track_columns(sim)
    diff = differences(sim)
    results = {name: evaluate(ALGORITHMS[name], diff, sim.alpha, params)
               for name in params["algorithms"]}
    N, A = len(streams), len(results)

    def per_row(key: str) -> np.ndarray:  # (N,) per algorithm -> (N * A,) trial-major
        return np.stack([res[key] for res in results.values()], axis=1).reshape(-1)

    chosen = per_row("chosen").astype(np.int64)
    columns: dict[str, np.ndarray] = {
        "algorithm": np.tile(np.array(list(results), dtype=object), N),
        "chosen": chosen + 1, "correct": (chosen == TRUE_TRACK).astype(np.int64),
        "decided": (chosen >= 0).astype(np.int64),
        **{key: per_row(key).astype(float)
           for key in ("margin", "range_weight_mean", "range_weight_min")}}
    for key, values in esm.items():
        if key in SCAN_SERIES:  # on the first row of each trial only
            cells = np.full((N, A), "", dtype=object)
            cells[:, 0] = values
            columns[key] = cells.reshape(-1)
        else:
            columns[key] = np.repeat(values, A)
    weights = np.full((N, A), "", dtype=object)
    for a, (name, res) in enumerate(results.items()):
        if ALGORITHMS[name].dynamic and "range_weights" in res:
            weights[:, a] = encode_series(res["range_weights"],
                                          SCAN_SERIES["range_weight_per_scan"])
    columns["range_weight_per_scan"] = weights.reshape(-1)
    return RowTable(np.repeat(np.arange(N), A), columns)


def run_trial(params: Mapping[str, Any], streams: TrialStreams) -> list[dict]:
    """One trial (the batch form with a single trial)."""
    return run_batch(params, [streams])[0]



ROW_METRICS = (
    Metric("chosen", "track", "radar track chosen, 1..3, or 0 for no decision",
           categorical=True),
    Metric("correct", "1", "the ESM track was associated with its radar track", binary=True,
           better="higher", label="correct association rate"),
    Metric("decided", "1", "a radar track was chosen (always 1 except for chi2_lrt, "
           "counting and sprt)",
           binary=True),
    Metric("margin", "1", "decision statistic's lead of the winner over the runner-up"),
    Metric("range_weight_mean", "1", "range factor's weight, mean over the scans"),
    Metric("range_weight_min", "1", "range factor's weight, minimum over the scans"),
    Metric("alpha_mean", "1", "manoeuvre index, mean over the scans where it is defined"),
    Metric("alpha_peak", "1", "manoeuvre index, maximum over the scans"),
    Metric("esm_invalid", "samples", "TDOA-DF samples carried forward", bounds=NON_NEGATIVE),
    Metric("esm_range_sigma_m", "m", "mean 1-sigma of the TDOA-DF range",
           bounds=NON_NEGATIVE),
)
"""Every metric column of the rows (see the module docstring)."""
