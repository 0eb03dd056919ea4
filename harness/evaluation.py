"""Metrics of one case: run every profile of a scenario and measure it.

:func:`run_case` tunes the jerk times (through the session's engine), runs
each profile and measures it (:func:`profile_metrics`) against the settling
band of the case; :class:`ProfileMetrics` holds the Table 1 quantities.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from .metrics import residual_peak, rise_time, settling_time
from .plant import free_amplitude
from .tuning import TuningResult

if TYPE_CHECKING:
    from .cosim import CoSimResult, Session
    from .scenario import Scenario

__all__ = ["ProfileMetrics", "profile_metrics", "run_case"]


@dataclass
class ProfileMetrics:
    """Table 1 quantities of one profile.

    Attributes
    ----------
    residual : float
        Peak |ε| after the reference has ended (m).
    free_amplitude : float
        Amplitude of the free oscillation when the reference ends (m; sum over
        the modes).
    motion_time : float
        Duration of the reference (s): the paper's "theoretical rise time".
    rise_time : float
        From the start until the load first reaches the target (s).
    settling_time : float
        From the start until the load stays within ±band of the target (s);
        ``inf`` if it never does (undamped mode).
    band : float
        The settling band used (m).
    """

    residual: float
    free_amplitude: float
    motion_time: float
    rise_time: float
    settling_time: float
    band: float


def profile_metrics(run: CoSimResult, band: float) -> ProfileMetrics:
    """Metrics of one run, the settling band given.

    When the load is not provably settled at the end of the record (the sum of
    the modes' free-oscillation amplitudes there exceeds the band), the record
    is continued analytically with the free response (:meth:`CoSimResult.extend`)
    until it is.
    """
    t, err = run.t, run.error
    # the default band is a sampled value of |ε| itself: a sample at the band (to rounding)
    # counts as inside
    band_in = band * (1.0 + 1e-9)
    A_final = sum(free_amplitude(run.final_state[2 * i], run.final_state[2 * i + 1], m)
                  for i, m in enumerate(run.final_modes))
    if A_final > band_in:
        # time for the envelope Σ A_i e^{-σ_i τ} to fall below the band
        need = 0.0
        nm = len(run.final_modes)
        for i, m in enumerate(run.final_modes):
            Ai = free_amplitude(run.final_state[2 * i], run.final_state[2 * i + 1], m)
            if Ai * nm > band_in:
                need = max(need, math.inf if m.sigma == 0
                           else math.log(Ai * nm / band_in) / m.sigma)
        if math.isfinite(need) and need < 3600.0:
            te, ee = run.extend(need + run.step)
            t = np.concatenate((t, te))
            err = np.concatenate((err, ee + (run.x[-1] - run.target)))
            ts = settling_time(t, err, band_in, run.t_start)
        else:
            ts = math.inf
    else:
        ts = settling_time(t, err, band_in, run.t_start)
    return ProfileMetrics(
        residual=residual_peak(run.t, run.eps, run.t_end),
        free_amplitude=run.free_amplitude,
        motion_time=run.motion_time,
        rise_time=rise_time(run.t, run.load, run.target, run.t_start, start=run.x0),
        settling_time=ts,
        band=band,
    )


def _jerk_times(sc: Scenario, profile: str, tuning: TuningResult | None
                ) -> tuple[float, float, float, float] | None:
    if profile == "AL":
        return None
    if tuning is not None:
        return tuning.T_F
    if profile == "JL":
        assert sc.compare.JL_T_F is not None
        return (sc.compare.JL_T_F,) * 4
    assert sc.compare.DJL_T_F is not None
    return sc.compare.DJL_T_F


def run_case(sc: Scenario, session: Session, *, keep_runs: bool = True):
    """Tune, co-simulate and measure every profile of a single-move scenario.

    Parameters
    ----------
    sc : Scenario
        A scenario without sweep (or one case of a sweep).
    session : Session
        The FMU instances to use.
    keep_runs : bool
        Keep the time series (False in sweeps, to save memory).

    Returns
    -------
    harness.results.ScenarioResult
    """
    from .results import ProfileOutcome, ScenarioResult

    runs: dict[str, CoSimResult] = {}
    tunings: dict[str, TuningResult | None] = {}
    for prof in sc.compare.profiles:
        tunings[prof] = session.tune(sc, prof)
        runs[prof] = session.run(sc, prof, _jerk_times(sc, prof, tunings[prof]))
    if sc.simulation.band is not None:
        band, source = sc.simulation.band, "given in the scenario"
    elif "DJL" in runs:
        band = residual_peak(runs["DJL"].t, runs["DJL"].eps, runs["DJL"].t_end)
        source = "largest residual of DJL (the paper's band)"
    else:
        name = min(runs, key=lambda p: residual_peak(runs[p].t, runs[p].eps, runs[p].t_end))
        band = residual_peak(runs[name].t, runs[name].eps, runs[name].t_end)
        source = f"largest residual of {name} (no DJL run)"
    if not band > 0:
        band, source = 1e-9, source + "; zero, so 1 nm"
    outcomes = {}
    for prof, run in runs.items():
        met = profile_metrics(run, band)
        outcomes[prof] = ProfileOutcome(prof, run if keep_runs else None, tunings[prof], met,
                                        run.T_F, run.z_v_max, run.z_synced)
    return ScenarioResult(sc, outcomes, band, source)


