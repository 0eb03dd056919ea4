"""How a run is scored: its settling time, its peaks, its worst case over an uncertainty set.

* :func:`settling_of` -- the settling time into a band, the record continued
  analytically when the load is not provably settled at its end;
* :func:`peaks` -- the largest |v|, |a|, |j| of the reference (``inf`` jerk
  where the acceleration steps: no jerk limit);
* :func:`score_uncertainty` -- the worst residual and the worst-case settling
  time over a scenario's uncertainty (its scoring set by default), the
  reference planned on the nominal map, the band fixed.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .metrics import settling_time
from .plant import free_amplitude
from .scenario import Scenario
from .simulation.master import CoSimResult, perturbed
from .uncertainty import UncertaintySet

__all__ = ["peaks", "score_uncertainty", "settling_of"]


def settling_of(run: CoSimResult, band: float) -> float:
    """Settling time of a run into ±band (s), the record extended analytically if needed."""
    t, err = run.t, run.error
    # a band made of a residual may equal a sample of |ε| (ζ = 0): a sample at the band
    # (to rounding) counts as inside
    band_in = band * (1.0 + 1e-9)
    amps = [free_amplitude(run.final_state[2 * i], run.final_state[2 * i + 1], m)
            for i, m in enumerate(run.final_modes)]
    if sum(amps) <= band_in:
        return settling_time(t, err, band_in, run.t_start)
    # time for the envelope Σ A_i e^{-σ_i τ} to fall below the band
    need = 0.0
    nm = len(run.final_modes)
    for Ai, m in zip(amps, run.final_modes, strict=True):
        if Ai * nm > band_in:
            need = max(need, math.inf if m.sigma == 0 else math.log(Ai * nm / band_in) / m.sigma)
    if not (math.isfinite(need) and need < 3600.0):
        return math.inf
    te, ee = run.extend(need + run.step)
    t = np.concatenate((t, te))
    err = np.concatenate((err, ee + (run.x[-1] - run.target)))
    return settling_time(t, err, band_in, run.t_start)


def peaks(run: CoSimResult) -> dict[str, float]:
    """Largest |v|, |a|, |j| of a run's reference (``j_peak`` inf where ``a`` steps)."""
    h = run.step
    a_scale = max(1.0, float(np.max(np.abs(run.a)))) if run.a.size else 1.0
    steps = run.a.size > 1 and bool(np.any(
        np.abs(run.a[1:] - (run.a[:-1] + run.j[:-1] * h)) > 1e-9 * a_scale))
    return {"v_peak": float(np.max(np.abs(run.v))), "a_peak": float(np.max(np.abs(run.a))),
            "j_peak": math.inf if steps else float(np.max(np.abs(run.j)))}


def score_uncertainty(run: CoSimResult, sc: Scenario, band: float,
                      points: UncertaintySet | None = None) -> dict[str, Any]:
    """Worst residual and worst settling time of a run over the scenario's uncertainty.

    The reference stays the one planned on the nominal map; the plant is re-run
    for every perturbation of the scoring set
    (:func:`harness.simulation.master.perturbed`) and measured in the same band.

    Parameters
    ----------
    run : CoSimResult
        The nominal run (full record).
    sc : Scenario
        Its scenario (``sc.uncertainty``, the mode map).
    band : float
        The settling band (m), fixed for every point and every profile.
    points : UncertaintySet, optional
        Default: ``sc.uncertainty.scoring_set()``.

    Returns
    -------
    dict
        ``residual_worst``, ``settling_time_worst``, ``worst_point``.
    """
    uset = sc.uncertainty.scoring_set() if points is None else points
    pivot = sc.z.z0 + 0.5 * sc.z.distance
    worst_r, worst_t, where = 0.0, -math.inf, ""
    for p, r in zip(uset.points, perturbed(run, sc.modemap.scheduled(), uset.points, pivot,
                                        full=False),
                    strict=True):
        worst_r = max(worst_r, r.free_amplitude)
        ts = settling_of(r, band)
        if ts > worst_t or (math.isnan(ts) and not where):
            worst_t, where = ts, p.label()
    return {"residual_worst": worst_r, "settling_time_worst": worst_t, "worst_point": where}
