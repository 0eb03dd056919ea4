"""How a run is scored: its settling time, its peaks, its worst case over an uncertainty set.

* :func:`settling_of` -- the settling time into a band, the record continued
  analytically when the load is not provably settled at its end;
* :func:`peaks` -- the largest |v|, |a|, |j| of the reference (``inf`` jerk
  where the acceleration steps: no jerk limit);
* :func:`score_uncertainty` -- the worst residual and the worst-case settling
  time over a scenario's uncertainty (its scoring set by default), the
  reference planned on the nominal map, the band fixed;
* :func:`score_points` -- the same, point by point (:class:`PointScores`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .metrics import settling_time
from .plant import ScheduledMode, free_amplitude, hermite_mid
from .scenario import Scenario
from .simulation.master import CoSimResult, scheduled, step_plant
from .uncertainty import Perturbation, UncertaintySet

__all__ = ["PointScores", "peaks", "score_points", "score_uncertainty", "settling_of"]


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


def _free_from(run: CoSimResult) -> int:
    """Return the first point from which the plant is free to the end of the record.

    No input over any later step (the reference has ended, no shaper piece left)
    and Z at rest (its position constant, its velocity zero): from there the
    plant is time-invariant and its response the modes' free oscillation.
    """
    inp = run.plant_input
    assert inp is not None
    h, n = run.step, run.t.size - 1
    active = np.flatnonzero((inp.a[:n] != 0.0) | (inp.j[:n] != 0.0))
    k = int(active[-1]) + 1 if active.size else 0
    later = [i for i in inp.pieces if i < n]
    if later:
        k = max(k, max(later) + 1)
    moving = np.flatnonzero((np.diff(run.z) != 0.0) | (run.v_z[:-1] != 0.0) | (run.v_z[1:] != 0.0))
    if moving.size:
        k = max(k, int(moving[-1]) + 1)
    k_end = min(n, math.ceil(run.t_end / h - 1e-9))
    return min(n, max(k, k_end))


def _free_tails(state: np.ndarray, sig: np.ndarray, wd: np.ndarray,
                tau: np.ndarray) -> np.ndarray:
    """Return Σ of the modes' free responses, per row, at the times ``tau``.

    ``state`` (P, 2M) the (ε, ε̇) of each mode; ``sig``, ``wd`` (P, M) the decay
    rates and damped angular frequencies; ``tau`` (P, W) the times since the
    state.  The arithmetic of :func:`harness.plant.free_response`.
    """
    out = np.zeros(tau.shape)
    for i in range(sig.shape[1]):
        e, de = state[:, 2 * i, None], state[:, 2 * i + 1, None]
        s, w = sig[:, i, None], wd[:, i, None]
        out += np.exp(-s * tau) * (e * np.cos(w * tau) + (de + s * e) / w * np.sin(w * tau))
    return out


def _settling_free(run: CoSimResult, eps: np.ndarray, k_free: int, state: np.ndarray,
                   f: np.ndarray, zeta: np.ndarray, band: float) -> np.ndarray:
    """Settling times (s) of runs whose deflection is ``eps`` to point ``k_free``, free after.

    One row per perturbed plant: ``eps`` (P, k_free + 1) the stepped deflection,
    ``state`` (P, 2M) the modes' state at ``k_free``, ``f``, ``zeta`` (P, M) the
    modes there.  The same numbers as :func:`settling_of` on each full record
    (same samples, same interpolation, same band tolerance), but the free part
    is only evaluated where an exit can still be: backwards from the instant
    the envelope Σ Aᵢ e^{−σᵢ τ} is provably inside the band, one damped
    period at a time, every row at once.
    """
    h = run.step
    band_in = band * (1.0 + 1e-9)
    t = run.t
    n = t.size - 1
    P, M = f.shape
    off = float(run.x[-1] - run.target)  # the reference at rest from k_free on
    w = 2.0 * np.pi * f
    sig, wd = zeta * w, w * np.sqrt(1.0 - zeta**2)
    amps = np.hypot(state[:, 0::2], (state[:, 1::2] + sig * state[:, 0::2]) / wd)  # (P, M)
    room = band_in - abs(off)
    out_t = np.full(P, np.nan)
    last = np.full(P, -1, dtype=np.int64)  # the last point outside the band, if free
    if room > 0.0:
        over = amps * M > room
        with np.errstate(divide="ignore", invalid="ignore"):
            need_m = np.where(over, np.log(np.maximum(amps * M, room) / room) / sig, 0.0)
        need = need_m.max(axis=1) if M else np.zeros(P)
        never = ~np.isfinite(need) | (need - (t[-1] - t[k_free]) >= 3600.0)
        out_t[never] = math.inf
        todo = (amps.sum(axis=1) > room) & ~never
        hi = np.where(todo, np.ceil(np.where(todo, need, 0.0) / h).astype(np.int64) + 1, 0)
        W = max(2, int(math.ceil(float(np.max(1.0 / f)) / h)) + 1)
        while todo.any():
            rows = np.flatnonzero(todo)
            lo = np.maximum(1, hi[rows] - W + 1)
            k = lo[:, None] + np.arange(W)[None, :]  # (R, W), masked beyond hi
            valid = k <= hi[rows, None]
            e = np.abs(_free_tails(state[rows], sig[rows], wd[rows], h * k) + off)
            outside = (e > band_in) & valid
            found = outside.any(axis=1)
            idx = W - 1 - np.argmax(outside[:, ::-1], axis=1)
            last[rows[found]] = k_free + k[found, idx[found]]
            hi[rows] = lo - 1
            todo[rows[found]] = False
            todo[rows[~found & (lo <= 1)]] = False
    else:
        out_t[:] = math.nan
        return out_t
    # the exit in the free part: interpolate between the two free samples, every row at once
    fr = np.flatnonzero(last >= 0)
    if fr.size:
        k0 = last[fr]
        tau = h * np.stack([k0 - k_free, k0 + 1 - k_free], axis=1).astype(float)
        e = np.abs(_free_tails(state[fr], sig[fr], wd[fr], tau) + off)
        e0, e1 = e[:, 0], e[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            frac = np.where(e0 != e1, (e0 - band_in) / (e0 - e1), 1.0)
        t0 = np.where(k0 <= n, t[np.minimum(k0, n)], t[-1] + (k0 - n) * h)
        t1 = np.where(k0 + 1 <= n, t[np.minimum(k0 + 1, n)], t[-1] + (k0 + 1 - n) * h)
        out_t[fr] = t0 + frac * (t1 - t0) - run.t_start
    # no exit in the free part: the last one is in the stepped part (if any)
    sel = t[:k_free + 1] >= run.t_start - 1e-12
    for r in np.flatnonzero((last < 0) & ~np.isinf(out_t)).tolist():
        err = np.abs(run.x[:k_free + 1] + eps[r] - run.target)
        ks = np.flatnonzero((err > band_in) & sel)
        if ks.size == 0:
            out_t[r] = 0.0
            continue
        k0 = int(ks[-1])
        e0 = float(err[k0])
        if k0 + 1 <= k_free:
            e1 = float(err[k0 + 1])
        else:
            tau1 = np.array([[(k0 + 1 - k_free) * h]])
            e1 = abs(float(_free_tails(state[r:r + 1], sig[r:r + 1], wd[r:r + 1],
                                       tau1)[0, 0]) + off)
        frac = (e0 - band_in) / (e0 - e1) if e0 != e1 else 1.0
        t0 = float(t[k0])
        t1 = float(t[k0 + 1]) if k0 + 1 <= n else float(t[-1]) + (k0 + 1 - n) * h
        out_t[r] = t0 + frac * (t1 - t0) - run.t_start
    return out_t


@dataclass(frozen=True)
class PointScores:
    """Residual and settling time of one run at every point of an uncertainty set.

    Attributes
    ----------
    points : tuple of Perturbation
        The points, in the set's order.
    residual : ndarray
        Residual (m) at each point: the free oscillation's amplitude when the
        reference ends (summed over the modes).
    settling : ndarray
        Settling time (s, from the motion's start) at each point, in the fixed band.
    """

    points: tuple[Perturbation, ...]
    residual: np.ndarray
    settling: np.ndarray

    def worst(self) -> dict[str, Any]:
        """Return ``residual_worst``, ``settling_time_worst``, ``worst_point`` (the worst case)."""
        worst_t, where = -math.inf, ""
        for p, t in zip(self.points, self.settling.tolist(), strict=True):
            if t > worst_t or (math.isnan(t) and not where):
                worst_t, where = t, p.label()
        return {"residual_worst": float(self.residual.max()) if self.points else 0.0,
                "settling_time_worst": worst_t, "worst_point": where}


def score_points(run: CoSimResult, sc: Scenario, band: float,
                 points: UncertaintySet | Sequence[Perturbation]) -> PointScores:
    """Residual and settling time of a run at every point of a set (the reference unchanged).

    The numbers of :func:`score_uncertainty`, point by point.

    Parameters
    ----------
    run : CoSimResult
        The nominal run (full record).
    sc : Scenario
        Its scenario (the mode map).
    band : float
        The settling band (m), fixed for every point.
    points : UncertaintySet or sequence of Perturbation
        The points.

    Returns
    -------
    PointScores
    """
    if run.plant_input is None:
        raise ValueError("the run keeps no plant input (made by an older master?)")
    if not band > 0:
        raise ValueError(f"band must be > 0, got {band!r}")
    pts = list(getattr(points, "points", points))
    pivot = sc.z.z0 + 0.5 * sc.z.distance
    sm = scheduled(sc.modemap.scheduled())
    h, n = run.step, run.t.size - 1
    k_free = _free_from(run)
    k_end = min(n, math.ceil(run.t_end / h - 1e-9))
    z, v_z = run.z, run.v_z
    zm = hermite_mid(z[:k_free], v_z[:k_free], z[1:k_free + 1], v_z[1:k_free + 1], h)
    ends = np.array([z[k_end], z[k_free]])
    nominal_mid = [m.f_array(zm) for m in sm]
    nominal_end = [m.f_array(ends) for m in sm]
    P, M = len(pts), len(sm)
    # every (point, mode) pair is one row of a single compiled plant run (the modes are
    # independent; the points' deflections are the sums of their own rows)
    rows: list[ScheduledMode] = []
    f_rows: list[np.ndarray] = []
    f_end = np.empty((P, M))
    f_free = np.empty((P, M))
    z_free = np.empty((P, M))
    for r, p in enumerate(pts):
        for i, m in enumerate(sm):
            rows.append(ScheduledMode(m.f_of_z, p.zeta(m.zeta), m.gain, m.name, m.f_of_z_array))
            f_rows.append(p.frequencies(m.f_array, zm, pivot, nominal_mid[i]))
            fe = p.frequencies(m.f_array, ends, pivot, nominal_end[i])
            f_end[r, i], f_free[r, i] = float(fe[0]), float(fe[1])
            z_free[r, i] = rows[-1].zeta
    f_mid = np.vstack(f_rows) if k_free else np.zeros((P * M, 0))
    _, states = step_plant(run.plant_input, h, f_mid, rows, k_free)  # (k_free + 1, 2 P M)
    eps = states[:, 0::2].reshape(k_free + 1, P, M).sum(axis=2).T  # (P, k_free + 1)
    state_free = states[k_free].reshape(P, 2 * M)
    se = states[k_end].reshape(P, M, 2)
    w = 2.0 * np.pi * f_end
    sig = z_free * w
    resid = np.hypot(se[:, :, 0], (se[:, :, 1] + sig * se[:, :, 0])
                     / (w * np.sqrt(1.0 - z_free**2))).sum(axis=1)
    ts = _settling_free(run, eps, k_free, state_free, f_free, z_free, band)
    return PointScores(tuple(pts), resid, np.asarray(ts, dtype=float))


def score_uncertainty(run: CoSimResult, sc: Scenario, band: float,
                      points: UncertaintySet | None = None) -> dict[str, Any]:
    """Worst residual and worst settling time of a run over the scenario's uncertainty.

    The reference stays the one planned on the nominal map; the plant is re-run
    for every perturbation of the scoring set and measured in the same band:
    the numbers of :func:`harness.simulation.master.perturbed` and
    :func:`settling_of`, computed faster (the plant stepped in C only until it
    is free -- the reference ended, Z at rest --, the free oscillation after it
    evaluated analytically where an exit from the band can still be).

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
    return score_points(run, sc, band, uset).worst()
