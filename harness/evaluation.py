"""Metrics of one case: run every profile of a scenario and measure it.

:func:`run_case` tunes the jerk times (:func:`harness.tuning.tune.tune_profile`),
runs each profile (:meth:`harness.simulation.session.Session.run`) and
measures it (:func:`profile_metrics`) against one settling band shared by
every profile of the case (``simulation.settle_band``, see
:class:`harness.metrics.SettleBand`), and also against the paper's band (DJL's
residual) when DJL runs; optionally it measures each profile's robustness to a
map error (:mod:`harness.robustness`).  :class:`ProfileMetrics` holds the
Table 1 quantities.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from .metrics import NO_BAND, ZERO_BAND_NOTE, residual_peak, rise_time
from .recommend import recommend as recommend_profile
from .results import ProfileOutcome, ScenarioResult
from .robustness import robustness as robustness_curves
from .scenario import Scenario
from .scoring import peaks, score_uncertainty, settling_of
from .simulation.master import CoSimResult
from .simulation.session import Session
from .simulation.shaped_axis import ShaperSpec
from .tuning.rule import TuningResult
from .tuning.tune import jerk_times, tune_profile

__all__ = ["ROBUSTNESS_MODES", "ProfileMetrics", "peaks", "profile_metrics", "run_case",
           "score_uncertainty"]

ROBUSTNESS_MODES = ("worst", "curves")
"""Values of ``run_case(..., robustness=...)`` besides False / True."""


@dataclass
class ProfileMetrics:
    """Table 1 quantities of one profile.

    Attributes
    ----------
    residual : float
        Residual vibration (m): the amplitude of the free oscillation when the
        reference ends, summed over the modes
        (:func:`harness.metrics.residual_amplitude`).  Every comparison
        (% of AL, DJL vs JL, Table 2, the paper's band) uses it.
    free_amplitude : float
        The same number (m), under its former name (CSV ``free_amplitude_m``).
    motion_time : float
        Duration of the reference (s): the paper's "theoretical rise time".
    rise_time : float
        From the start until the load first reaches the target (s).
    settling_time : float
        From the start until the load stays within ±band of the target (s);
        ``inf`` if it never does (undamped mode).
    band : float
        The settling band used (m), the same for every profile of the case.
    residual_peak : float
        Peak |ε| after the motion (sampled) (m): secondary, phase-dependent.
    settling_time_paper : float
        Settling time (s) into the paper's band, DJL's residual (Table 2's
        definition); NaN when DJL was not run.
    paper_band : float
        That band (m); NaN when DJL was not run.
    residual_worst : float
        Largest residual (m) over the scoring set of the scenario's
        uncertainty (:meth:`harness.uncertainty.UncertaintySpec.scoring_set`),
        the reference planned on the nominal map; NaN when not scored.
    settling_time_worst : float
        Largest settling time (s) into ``band`` over the same set: the time
        after which the load is within the band whatever the real map; NaN
        when not scored, ``inf`` if some point never settles.
    worst_point : str
        The perturbation of that worst settling time (``"scale -10 %"``).
    v_peak, a_peak, j_peak : float
        Largest |v| (m/s), |a| (m/s²) and |j| (m/s³) of the reference at the
        communication points; ``j_peak`` is ``inf`` for a reference whose
        acceleration steps (AL: no jerk limit).
    """

    residual: float
    free_amplitude: float
    motion_time: float
    rise_time: float
    settling_time: float
    band: float
    residual_peak: float = math.nan
    settling_time_paper: float = math.nan
    paper_band: float = math.nan
    residual_worst: float = math.nan
    settling_time_worst: float = math.nan
    worst_point: str = ""
    v_peak: float = math.nan
    a_peak: float = math.nan
    j_peak: float = math.nan


def profile_metrics(run: CoSimResult, band: float, *,
                    paper_band: float | None = None) -> ProfileMetrics:
    """Metrics of one run, the settling band given.

    When the load is not provably settled at the end of the record (the sum of
    the modes' free-oscillation amplitudes there exceeds the band), the record
    is continued analytically with the free response (:meth:`CoSimResult.extend`)
    until it is.

    Parameters
    ----------
    run : CoSimResult
        The co-simulation of one profile.
    band : float
        Settling band (m), > 0.
    paper_band : float, optional
        The paper's band (DJL's residual, m): adds ``settling_time_paper``.

    Returns
    -------
    ProfileMetrics
    """
    residual = run.free_amplitude
    if paper_band is None or not math.isfinite(paper_band):
        ts_paper, pb = math.nan, math.nan
    else:
        pb = float(paper_band)
        ts_paper = settling_of(run, pb)
    return ProfileMetrics(
        residual=residual,
        free_amplitude=residual,
        motion_time=run.motion_time,
        rise_time=rise_time(run.t, run.load, run.target, run.t_start, start=run.x0),
        settling_time=ts_paper if pb == band else settling_of(run, band),
        band=band,
        residual_peak=residual_peak(run.t, run.eps, run.t_end),
        settling_time_paper=ts_paper,
        paper_band=pb,
        **peaks(run),
    )


def _robustness_mode(robustness: bool | str | None) -> str | None:
    if robustness is None or robustness is False:
        return None
    if robustness is True:
        return "curves"
    if robustness in ROBUSTNESS_MODES:
        return str(robustness)
    raise ValueError(f"robustness must be False, True, 'worst' or 'curves', got {robustness!r}")


def run_case(sc: Scenario, session: Session, *, keep_runs: bool = True,
             robustness: bool | str | None = False,
             robustness_session: Session | None = None,
             score_worst_cases: bool = True, recommend: bool = False) -> ScenarioResult:
    """Tune, co-simulate and measure every profile of a single-move scenario.

    Parameters
    ----------
    sc : Scenario
        A scenario without sweep (or one case of a sweep).
    session : Session
        The FMU instances to use.
    keep_runs : bool
        Keep the time series (False in sweeps, to save memory).
    robustness : bool or {"worst", "curves"}
        Residual of each profile when the whole mode map is off by a factor
        1 + e (jerk times tuned on the nominal map; :mod:`harness.robustness`),
        over the span of the scenario's uncertainty, ``m = sc.uncertainty.map_scale``:

        * False (default): not computed;
        * ``"worst"``: only the worst case over e in ±m (21 points; 1 % apart
          at the default m = 0.1), stored on each profile as
          ``worst_map_residual``;
        * ``"curves"`` or True: the curves over e in ±2m (41 points) kept on
          the result as ``.robustness``
          (:class:`harness.robustness.RobustnessResult`), and the worst case
          over ±m taken from them (the same 21 points).
    robustness_session : Session, optional
        Session for the map-error runs (default: ``session``); e.g. the fast
        engine's when ``session`` drives the FMUs (same results, see
        ``tests/test_engine.py``), since they are many.
    score_worst_cases : bool
        Score every profile over the scenario's uncertainty (its scoring set,
        :func:`score_uncertainty`): worst residual, worst-case settling time in
        the case's band (on by default).
    recommend : bool
        Add the profile ``recommended`` (:func:`harness.recommend.recommend`):
        the robust-tuned member of DJL, JL*shaper, DJL*shaper that settles first
        in the worst case of the tuning set, at a jerk no higher than JL's.

    Returns
    -------
    harness.results.ScenarioResult
        With ``band`` / ``band_source`` (``simulation.settle_band``) and
        ``paper_band`` (DJL's residual, NaN without DJL).

    Raises
    ------
    ValueError
        If ``robustness`` is none of the above, or if the settling band is the
        paper's (DJL's residual) and DJL is not among the profiles.
    """
    mode = _robustness_mode(robustness)
    runs: dict[str, CoSimResult] = {}
    tunings: dict[str, TuningResult | None] = {}
    for prof in sc.compare.profiles:
        tunings[prof] = tune_profile(session, sc, prof)
        runs[prof] = session.run(sc, prof, jerk_times(sc, prof, tunings[prof]))
    residuals = {p: r.free_amplitude for p, r in runs.items()}

    spec = sc.simulation.settle_band
    source = spec.label
    if spec.needs == "AL" and "AL" not in runs:
        # the default band (a fraction of AL's residual) in a scenario that does not compare
        # AL: AL is run for the band only (an explicit one is refused when the file is loaded)
        al = session.run(sc, "AL", None, t_stop=session.t_stop_after_motion(sc, "AL", None))
        residuals_band = {**residuals, "AL": al.free_amplitude}
        source += " (AL run for the band only)"
    else:
        residuals_band = residuals
    band, fell_back = spec.half_width(residuals_band)
    if fell_back:
        source += ZERO_BAND_NOTE
    paper_band = math.nan
    if "DJL" in runs:
        paper_band = residuals["DJL"] if residuals["DJL"] > 0 else NO_BAND

    jerk = {p: jerk_times(sc, p, tunings[p]) for p in runs}
    curves = None
    worst: dict[str, float] = {}
    rs = session if robustness_session is None else robustness_session
    unc = sc.uncertainty  # the span of the map-error curves and of their worst case
    if mode == "curves":
        curves = robustness_curves(sc, rs, jerk, errors=unc.curve_errors())
        worst = curves.worst(unc.map_scale)
    elif mode == "worst":
        worst = robustness_curves(sc, rs, jerk, errors=unc.worst_errors()).worst(unc.map_scale)

    rec = None
    shapers: dict[str, ShaperSpec | None] = {}
    if recommend:
        rec = recommend_profile(sc, session, band, jl=tunings.get("JL"))
        shapers["recommended"] = rec.best.shaper
        jerk["recommended"] = rec.best.T_F
        runs["recommended"] = rec.run(sc, session)
        tunings["recommended"] = None
        if mode is not None:  # its map-error residuals like the others' (curve or worst case)
            errs = curves.errors if curves is not None else unc.worst_errors()
            res_e = np.asarray(rec.map_error_residuals(sc, rs, errs), float)
            if curves is not None:
                curves.residual["recommended"] = res_e
                curves.T_F["recommended"] = tuple(rec.best.T_F)
            sel = np.abs(np.asarray(errs)) <= unc.map_scale + 1e-12
            worst["recommended"] = float(np.max(res_e[sel]))
    outcomes = {}
    scoring = unc.scoring_set() if score_worst_cases else None
    for prof, run in runs.items():
        met = profile_metrics(run, band, paper_band=paper_band)
        if scoring is not None:
            met = dataclasses.replace(met, **score_uncertainty(run, sc, band, scoring))
        params = rec.fmu_parameters(sc) if prof == "recommended" and rec is not None \
            else session.move_params(sc, prof, jerk[prof], shapers.get(prof))
        outcomes[prof] = ProfileOutcome(
            prof, run if keep_runs else None, tunings[prof], met, run.T_F, run.z_v_max,
            run.z_synced, plan_info=dict(run.plan_info),
            worst_map_residual=worst.get(prof, math.nan),
            method=(f"{rec.best.family}: {rec.best.label(sc.simulation.Te)}"
                    if prof == "recommended" and rec is not None
                    else _method(prof, jerk[prof], sc.simulation.Te)),
            fmu_parameters=params, z_fmu_parameters=session.z_move_params(sc, run.z_v_max))
    return ScenarioResult(sc, outcomes, band, source, paper_band=paper_band, robustness=curves,
                          scoring_label=scoring.label if scoring is not None else "",
                          recommendation=rec)


def _method(profile: str, T_F: tuple[float, ...] | None, Te: float) -> str:
    """Return a profile in words: ``AL``, ``JL T_F 152 ms``, ``DJL T_F 118/120/142 ms``."""
    if T_F is None:
        return profile
    ms = "/".join(f"{t * 1e3:.0f}" for t in (T_F[:1] if profile.startswith("JL") else T_F))
    return f"{profile} T_F {ms} ms"
