"""Jerk times tuned on the time-varying model: ``optimal`` and ``robust``.

The paper's rule (:func:`harness.tuning.rule.tune_djl`: each jerk time = the modal
period at the start of its stage) cancels each stage's vibration only to first
order: damping leaves a remainder per stage, the mode drifts within a stage,
and the four remainders add with phases set by the stage timings.  Here the
jerk times are instead chosen by minimising the residual vibration itself,
computed on the scheduled plant with the Z motion (the fast engine,
:mod:`harness.simulation.fast_axis`), over whole samples N_F1..N_F4:

* ``optimal`` — the smallest residual on the nominal mode map;
* ``robust`` — the smallest *worst* residual over a stated uncertainty: the
  whole map f(z) scaled by 1 + e, |e| ≤ ``map_error`` (21 or more points, 1 %
  apart), and, optionally, every mode's damping scaled by factors in a range.

Both searches start from the paper's jerk times and from JL's (four equal jerk
times N: a DJL whose four jerk times are equal *is* the JL profile, bit for
bit), keep the best point ever evaluated, and so never return worse than JL
when JL's jerk time is feasible (always under the default constraints).

Constraints (:class:`TuningOptions`): the motion no longer than JL's (or than
a bound in s), and each jerk time within a band around the local periods (the
modal period at the start of its stage).

The search is a multi-start pattern search on the integer grid: from each
start, coordinate moves of ±s samples (s = 16, 8, 4, 2, 1) and the four
diagonal moves of the two middle stages, accepted when they lower the
objective, until no move of the smallest step does; every evaluation is
cached.  One evaluation plans the move (C), reuses the Z motion and the mode
frequencies along it (they depend on the motion time only, cached), samples
the reference to the end of the motion and steps the plant (C): about 50 µs
nominal, 21 plant runs for the robust objective.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..compiled import engine as _compiled_engine
from ..plant import hermite_mid
from ..scenario import Scenario
from ..simulation.session import Session
from ..tuning_options import TuningOptions
from ..uncertainty import Perturbation
from .rule import TuningResult

__all__ = [
    "STEPS",
    "Objective",
    "SearchReport",
    "pattern_search",
    "tune_optimal",
]

STEPS = (16, 8, 4, 2, 1)
"""Pattern-search step sizes (samples)."""


class Objective:
    """Residual vibration of one profile of one scenario as a function of its jerk times.

    Parameters
    ----------
    sc : Scenario
        A single-move scenario.
    session : Session
        A session; the searches run on its fast engine (:meth:`Session.fast`).
    profile : {"JL", "DJL"}
        The profile whose jerk times are searched.

    Notes
    -----
    The Z move is synchronised with the excited axis' motion time, so z(t),
    the mode frequencies along it and their value at the end of the motion
    depend on the motion time only: they are computed once per motion time,
    for every perturbation asked for, with the plant's *adjoint*
    (``harness._engine.adjoint_modes``): the sensitivity of the final state to
    the input of every step.  A move's final state under a perturbation is then
    one dot product with its samples (a, j), equal to stepping the plant to
    ~1e-13 relative (tested); the residual is its free-oscillation amplitude.
    """

    def __init__(self, sc: Scenario, session: Session, profile: str) -> None:
        session = session.fast()
        if profile not in ("JL", "DJL"):
            raise ValueError(f"profile must be JL or DJL, got {profile!r}")
        self.sc, self.session, self.profile = sc, session, profile
        self.Te = sc.simulation.Te
        self.h = sc.simulation.step
        self.m = int(round(self.h / self.Te))
        self.modes = sc.modemap.scheduled()
        self.pivot = sc.z.z0 + 0.5 * sc.z.distance
        self._z: dict[float, tuple[int, np.ndarray, np.ndarray, np.ndarray]] = {}
        self._psi: dict[tuple[float, int], tuple[Any, ...]] = {}
        self._sets: dict[int, tuple[Perturbation, ...]] = {}
        self.evaluations = 0

    def plan(self, N: Sequence[int]) -> float:
        """Plan the move with jerk times ``N`` (samples); return its motion time (s)."""
        T_F = tuple(n * self.Te for n in N)
        if self.profile == "JL":
            T_F = (T_F[0],) * 4
        return self.session.axis.plan(self.session.move_params(self.sc, self.profile, T_F))

    def _z_path(self, T_x: float) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
        """``k_end``, the mid-step Z positions, z at the end, and the nominal f per mode."""
        got = self._z.get(T_x)
        if got is None:
            s, sc = self.session, self.sc
            v_z, _ = s.z_velocity(sc, T_x)
            s.z_axis.plan(s.z_move_params(sc, v_z))
            t_end = sc.move.t_start + T_x
            k_end = int(math.ceil(t_end / self.h - 1e-9))
            Z = s.z_axis.samples(0, int(round(self.h / s.z_axis.planned.Te)), k_end + 1)
            z, v_z = Z[0], Z[1]
            zm = hermite_mid(z[:-1], v_z[:-1], z[1:], v_z[1:], self.h)
            got = (k_end, zm, np.array([z[k_end]]),
                   np.vstack([m.f_array(zm) for m in self.modes]))
            self._z[T_x] = got
        return got

    def _adjoint(self, T_x: float, points: tuple[Perturbation, ...]) -> tuple[Any, ...]:
        """Return the plant's sensitivities for a motion time and perturbations (cached)."""
        key = (T_x, id(points))
        got = self._psi.get(key)
        if got is not None and self._sets.get(id(points)) is not points:
            got = None  # another tuple at the same address
        if got is None:
            k_end, zm, z_end, f_nom = self._z_path(T_x)
            rows_f, zeta, gain, f_end = [], [], [], []
            for p in points:
                for i, m in enumerate(self.modes):
                    rows_f.append(p.frequencies(m.f_array, zm, self.pivot, f_nom[i]))
                    zeta.append(p.zeta(m.zeta))
                    gain.append(m.gain)
                    f_end.append(float(p.frequencies(m.f_array, z_end, self.pivot)[0]))
            R = len(rows_f)
            psi = np.empty((R, k_end, 2, 2))
            if k_end:
                _compiled_engine().adjoint_modes(
                    self.h, np.ascontiguousarray(np.vstack(rows_f)), np.array(zeta),
                    np.array(gain), k_end, psi)
            z_arr, w = np.array(zeta), 2.0 * np.pi * np.array(f_end)
            # the final state is psi_a @ a + psi_j @ j, rows (mode x point, state)
            psi_a = np.ascontiguousarray(psi[:, :, :, 0].transpose(0, 2, 1).reshape(2 * R, -1))
            psi_j = np.ascontiguousarray(psi[:, :, :, 1].transpose(0, 2, 1).reshape(2 * R, -1))
            got = (k_end, psi_a, psi_j, z_arr * w, w * np.sqrt(1.0 - z_arr * z_arr),
                   len(self.modes))
            if len(self._psi) >= 256:
                self._psi.clear()
            self._psi[key] = got
            self._sets[id(points)] = points
        return got

    def residuals(self, N: Sequence[int], points: Sequence[Perturbation] = (Perturbation(),)
                  ) -> tuple[float, np.ndarray]:
        """Motion time and residual (m) under each perturbation.

        Parameters
        ----------
        N : sequence of int
            Jerk times (samples): four, or one for JL.
        points : sequence of Perturbation
            The perturbations (default: the nominal map).

        Returns
        -------
        motion_time : float
            Of the planned move (s).
        residual : ndarray
            One per point: the free-oscillation amplitude when the reference
            ends, summed over the modes.
        """
        self.evaluations += 1
        T_x = self.plan(N)
        pts = points if isinstance(points, tuple) else tuple(points)
        k_end, psi_a, psi_j, sig, wd, nm = self._adjoint(T_x, pts)
        u = self.session.axis.samples(0, self.m, k_end + 1)
        final = psi_a @ u[2, :k_end] + psi_j @ u[3, :k_end]
        eps, deps = final[0::2], final[1::2]  # at the end of the motion, each row
        amp = np.hypot(eps, (deps + sig * eps) / wd)
        return T_x, amp.reshape(len(pts), nm).sum(axis=1)


def pattern_search(f: Callable[[tuple[int, ...]], float], starts: Sequence[tuple[int, ...]],
                   lo: Sequence[int], hi: Sequence[int], *, steps: Sequence[int] = STEPS,
                   tied: bool = False, max_evaluations: int = 20000
                   ) -> tuple[tuple[int, ...], float, dict[tuple[int, ...], float]]:
    """Minimise ``f`` over integer points in the box [lo, hi] from several starts.

    Parameters
    ----------
    f : callable
        Objective of an integer point (``inf`` = infeasible).
    starts : sequence of tuple of int
        Start points (clipped into the box).
    lo, hi : sequence of int
        Bounds (inclusive).
    steps : sequence of int
        Step sizes, largest first.
    tied : bool
        Also try moving coordinates 1 and 2 together (the two middle stages).
    max_evaluations : int
        Stop after that many distinct points.

    Returns
    -------
    best : tuple of int
        The best point evaluated (the first start on ties).
    value : float
        Its objective.
    cache : dict
        Every point evaluated and its value.
    """
    cache: dict[tuple[int, ...], float] = {}
    lo_t, hi_t = tuple(int(x) for x in lo), tuple(int(x) for x in hi)

    def ev(p: tuple[int, ...]) -> float:
        v = cache.get(p)
        if v is None:
            v = float(f(p))
            cache[p] = v
        return v

    dim = len(lo_t)
    best: tuple[int, ...] | None = None
    best_v = math.inf
    for s0 in starts:
        x = tuple(min(max(int(v), lo_t[i]), hi_t[i]) for i, v in enumerate(s0))
        fx = ev(x)
        for s in steps:
            improved = True
            while improved and len(cache) < max_evaluations:
                improved = False
                moves = [tuple(x[k] + (d if k == i else 0) for k in range(dim))
                         for i in range(dim) for d in (s, -s)]
                if tied and dim == 4:
                    moves += [tuple(x[k] + (d if k in (1, 2) else 0) for k in range(dim))
                              for d in (s, -s)]
                    moves += [tuple(x[k] + (d if k == 1 else -d if k == 2 else 0)
                                    for k in range(dim)) for d in (s, -s)]
                for y in moves:
                    if any(y[k] < lo_t[k] or y[k] > hi_t[k] for k in range(dim)):
                        continue
                    fy = ev(y)
                    if fy < fx:
                        x, fx, improved = y, fy, True
        if fx < best_v or best is None:
            best, best_v = x, fx
    assert best is not None
    # the best point ever evaluated (a start may be better than another start's descent)
    for p, v in cache.items():
        if v < best_v:
            best, best_v = p, v
    return best, best_v, cache


def _starts(paper: tuple[int, ...] | None, n_jl: int, every_mix: bool = True
            ) -> list[tuple[int, ...]]:
    """Start points: the paper's jerk times, JL's, and mixes of the two, stage by stage.

    The residual is a sum of four stage remainders whose phases depend on all
    the jerk times: its minima are many and narrow, so a descent from one
    start finds the nearest; the mixes of the two reference points (all 14,
    or the 4 that take one stage from the paper's) spread the starts over the
    region where the good ones lie, deterministically.
    """
    jl = (n_jl,) * 4
    if paper is None:
        return [jl]
    out = [paper, jl]
    for mask in range(1, 15) if every_mix else (1, 2, 4, 8):
        p = tuple(paper[i] if mask >> i & 1 else n_jl for i in range(4))
        if p not in out:
            out.append(p)
    return out


@dataclass
class SearchReport:
    """How a tuned result was found (kept on :class:`harness.tuning.rule.TuningResult`).

    Attributes
    ----------
    method : str
        ``optimal`` or ``robust``.
    nominal, worst : float
        The result's residual (m) on the nominal map, and its worst case over
        the scoring set (never the set it was tuned on).
    jl_nominal, jl_worst : float
        The same for JL.
    start : tuple of int
        The first start point.
    evaluations : int
        Points evaluated.
    seconds : float
        Time of the search.
    tuned_on, scored_on : str
        The uncertainty sets minimised over (robust; ``nominal map`` for
        optimal) and reported on.
    bounds : tuple
        The box of jerk times searched (samples).
    max_motion_time : float
        The motion-time bound (s; inf: none).
    notes : list of str
        Anything to report.
    """

    method: str
    nominal: float
    worst: float
    jl_nominal: float
    jl_worst: float
    start: tuple[int, ...]
    evaluations: int
    seconds: float
    tuned_on: str = ""
    scored_on: str = ""
    bounds: tuple[tuple[int, ...], tuple[int, ...]] = ((), ())
    max_motion_time: float = math.inf
    notes: list[str] = field(default_factory=list)


def tune_optimal(sc: Scenario, session: Session, profile: str, method: str,
                 paper: TuningResult | None, jl: TuningResult,
                 options: TuningOptions | None = None) -> TuningResult:
    """Search the jerk times of ``profile`` that minimise the residual (or its worst case).

    Parameters
    ----------
    sc : Scenario
        A single-move scenario.
    session : Session
        A session (the search runs on its fast engine, :meth:`Session.fast`).
    profile : {"JL", "DJL"}
        The profile tuned.
    method : {"optimal", "robust"}
        Minimise the nominal residual, or its worst case over the tuning set
        of the scenario's uncertainty (:meth:`~harness.uncertainty.UncertaintySpec.tuning_set`).
    paper : TuningResult, optional
        The paper's tuning of DJL (start point, and the local periods of the
        band); None for JL.
    jl : TuningResult
        JL tuned to the period at the end of the motion (a start point, and the
        fallback that makes the result never worse than JL).
    options : TuningOptions, optional
        Constraints (defaults: no motion-time bound, band ±50 % around the
        local periods).

    Returns
    -------
    TuningResult
        ``rule`` is ``method``; ``search`` holds a :class:`SearchReport`.
    """
    if method not in ("optimal", "robust"):
        raise ValueError(f"method must be 'optimal' or 'robust', got {method!r}")
    opts = options or TuningOptions()
    t0 = time.perf_counter()
    obj = Objective(sc, session, profile)
    tuning = sc.uncertainty.tuning_set()
    scoring = sc.uncertainty.scoring_set()
    points = tuning.points if method == "robust" else (Perturbation(),)
    n_jl = int(jl.N_F[0])
    T_jl = obj.plan((n_jl,) * 4)
    bound = math.inf
    if opts.max_motion_time == "JL":
        bound = T_jl
    elif isinstance(opts.max_motion_time, (int, float)):
        bound = float(opts.max_motion_time)
    if profile == "JL":
        periods = [jl.periods[0]]
    else:
        assert paper is not None
        periods = list(paper.periods)
    Te = sc.simulation.Te
    b = opts.period_band
    lo = [max(1, math.floor((1.0 - b) * P / Te)) for P in periods]
    hi = [max(lo[i], math.ceil((1.0 + b) * P / Te)) for i, P in enumerate(periods)]
    # JL's jerk time is always allowed
    lo = [min(x, n_jl) for x in lo]
    hi = [max(x, n_jl) for x in hi]
    if opts.jerk_limit == "JL":  # no stage's jerk above JL's: no jerk time below JL's
        lo = [max(x, n_jl) for x in lo]
        hi = [max(x, lo[i]) for i, x in enumerate(hi)]

    def value(N: tuple[int, ...]) -> float:
        full = N * 4 if len(N) == 1 else N
        T, r = obj.residuals(full, points)
        if T > bound * (1.0 + 1e-12):
            return math.inf
        return float(np.max(r))

    if profile == "JL":
        # one dimension: every jerk time in the band
        cache = {(n,): value((n,)) for n in range(lo[0], hi[0] + 1)}
        best = min(cache, key=lambda p: (cache[p], abs(p[0] - n_jl)))
        best_v = cache[best]
        N = (best[0],) * 4
        start: tuple[int, ...] = (n_jl,)
    else:
        # the robust objective is smoother: fewer starts
        starts = _starts(tuple(int(x) for x in paper.N_F) if paper is not None else None, n_jl,
                         every_mix=method == "optimal")
        best, best_v, cache = pattern_search(value, starts, lo, hi, tied=True)
        N = best
        start = starts[0]
    # JL's point is in the box and was evaluated (a start, or the 1-D scan): the search's
    # best is never worse (what makes "never worse than JL" hold)
    assert best_v <= cache[(n_jl,) if profile == "JL" else (n_jl,) * 4]
    # report the nominal and the worst case of the result, and JL's
    # reported on the scoring set, the plant stepped forward (not through the adjoint)
    fast = session.fast()
    rw = fast.residuals_under(sc, profile, tuple(n * Te for n in N), scoring.points)
    jw = fast.residuals_under(sc, "JL", (n_jl * Te,) * 4, scoring.points)
    report = SearchReport(method, float(rw[0]), float(np.max(rw)), float(jw[0]),
                          float(np.max(jw)), start, len(cache), time.perf_counter() - t0,
                          tuning.label if method == "robust" else "nominal map", scoring.label,
                          (tuple(lo), tuple(hi)), bound)
    obj.plan(N)  # leave the axis planned with the result
    base = paper if (paper is not None and profile == "DJL") else jl
    return TuningResult(profile, method, tuple(n * Te for n in N), tuple(N),  # type: ignore[arg-type]
                        base.instants, base.z, base.periods, base.merged, [tuple(N)], True,
                        search=report)
