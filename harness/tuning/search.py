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
from operator import add, le
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

_TWO_PI = 2.0 * math.pi


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
    for every perturbation asked for, with the plant's *adjoint*: the
    sensitivity of the final state to the input (a, j) of every step, kept as
    suffix sums (``harness._engine.adjoint_sums``).  Over one constant-jerk
    piece of the plan, a is linear and j constant in the step index, so a
    move's final state under a perturbation is three differences of those sums
    per piece (``Plan.adjoint_residuals``), equal to stepping the plant to
    ~1e-12 relative (tested); the residual is its free-oscillation amplitude.
    :meth:`worst` stops at the first point whose residual reaches a bound:
    what a search needs to reject a candidate.
    """

    _MAX_BYTES = 64 << 20
    """Memory kept for the sums of the motion times seen (then dropped)."""

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
        self._sums: dict[tuple[float, int], list[Any]] = {}
        self._ends: dict[float, tuple[np.ndarray, np.ndarray, list[float]]] = {}
        self._zeta = [float(m.zeta) for m in self.modes]
        self._sets: dict[int, tuple[Perturbation, ...]] = {}
        self._bytes = 0
        self._engine = _compiled_engine()
        self._base = session.move_params(sc, profile)
        self._first: Any = None
        self.evaluations = 0

    def _T_F(self, N: Sequence[int]) -> tuple[float, ...]:
        T_F = tuple(n * self.Te for n in N)
        return (T_F[0],) * 4 if self.profile == "JL" else T_F

    def plan(self, N: Sequence[int]) -> float:
        """Plan the move with jerk times ``N`` (samples); return its motion time (s)."""
        return self.session.axis.plan(self.session.move_params(self.sc, self.profile,
                                                               self._T_F(N)))

    def _plan(self, N: Sequence[int]) -> Any:
        """Return the compiled plan for jerk times ``N`` (the session's axis left as it was).

        The first is planned from the move's parameters, the others re-plan it with
        other jerk times (``Plan.replan``: the same plan, no parameters read).
        """
        Te = self.Te
        T = ((float(N[0] * Te),) * 4 if self.profile == "JL" else
             (float(N[0] * Te), float(N[1] * Te), float(N[2] * Te), float(N[3] * Te)))
        try:
            if self._first is None:
                p = dict(self._base)
                p.update({f"T_F{i + 1}": t for i, t in enumerate(T)})
                self._first = self._engine.plan(p, 0.0)
                return self._first
            return self._first.replan(*T)
        except self._engine.PlanError:
            self.plan(N)  # raises the axis' PlanError, named
            raise  # pragma: no cover

    def _z_path(self, T_x: float) -> tuple[int, np.ndarray, np.ndarray, np.ndarray]:
        """``k_end``, the mid-step Z positions, z at the end, and the nominal f per mode."""
        got = self._z.get(T_x)
        if got is None:
            s, sc, eng = self.session, self.sc, self._engine
            # the Z move of Session.z_velocity and z_move_params, planned here directly
            zp = s.z_move_params(sc, sc.z.v_max)
            try:
                if sc.z.moves and sc.z.sync:
                    zp["v_max"] = eng.sync_velocity(dict(zp), float(T_x), float(sc.z.v_max),
                                                    0.0)[0]
                zplan = eng.plan(zp, 0.0)
            except eng.PlanError:
                s.z_axis.plan(s.z_move_params(sc, s.z_velocity(sc, T_x)[0]))  # named
                raise  # pragma: no cover
            t_end = sc.move.t_start + T_x
            k_end = int(math.ceil(t_end / self.h - 1e-9))
            Z = np.empty((eng.N_SAMPLE_VARS, k_end + 1))
            zplan.sample_into(Z, 0, int(round(self.h / zplan.Te)), k_end + 1)
            z, v_z = Z[0], Z[1]
            zm = hermite_mid(z[:-1], v_z[:-1], z[1:], v_z[1:], self.h)
            got = (k_end, zm, np.array([z[k_end]]),
                   np.vstack([m.f_array(zm) for m in self.modes]))
            if len(self._z) >= 4096:
                self._z.clear()
            self._z[T_x] = got
        return got

    def _adjoint(self, T_x: float, points: tuple[Perturbation, ...]) -> list[Any]:
        """Return the adjoint sums for a motion time and perturbations (cached).

        Each point's rows are computed when first needed (:meth:`_point`): a
        candidate rejected on one point costs that point's adjoint only.
        """
        key = (T_x, id(points))
        got = self._sums.get(key)
        if got is not None and self._sets.get(id(points)) is not points:
            got = None  # another tuple at the same address
        if got is None:
            k_end, _, _, f_nom = self._z_path(T_x)
            R = len(points) * len(self.modes)
            S = np.empty((R, 2, 3, k_end + 1))
            fill = None
            if all(p.is_scale_only for p in points):  # the points' rows computed in C
                zeta, gain, f_end = self._scale_only(T_x)
                fill = (self.h, np.ascontiguousarray(f_nom), zeta, gain, np.array(f_end),
                        np.array([1.0 + p.scale for p in points]))
            got = [k_end, S, np.zeros(R), np.ones(R), len(self.modes), np.empty(len(points)),
                   np.zeros(len(points), dtype=np.uint8), T_x, fill]
            if self._bytes + S.nbytes > self._MAX_BYTES:
                self._sums.clear()
                self._bytes = 0
            self._sums[key] = got
            self._bytes += S.nbytes
            self._sets[id(points)] = points
        return got

    def _point(self, entry: list[Any], p: Perturbation, q: int) -> None:
        """Compute the adjoint sums of point ``q`` (perturbation ``p``) of a cache entry."""
        k_end, S, sig, wd, nm, _, ready, T_x, _ = entry
        _, zm, z_end, f_nom = self._z_path(T_x)
        if p.is_scale_only:  # the nominal rows, each frequency times 1 + scale in C
            zeta, gain, f_end = self._scale_only(T_x)
            c, r0 = 1.0 + p.scale, q * nm
            self._engine.adjoint_sums(self.h, f_nom, zeta, gain, k_end, S[r0:r0 + nm], c)
            for i, (z, fe) in enumerate(zip(self._zeta, f_end, strict=True)):
                w = _TWO_PI * (fe * c)
                sig[r0 + i] = z * w
                wd[r0 + i] = w * math.sqrt(1.0 - z * z)
            ready[q] = 1
            return
        rows_f, zeta, gain, f_end = [], [], [], []
        for i, m in enumerate(self.modes):
            rows_f.append(p.frequencies(m.f_array, zm, self.pivot, f_nom[i]))
            zeta.append(p.zeta(m.zeta))
            gain.append(m.gain)
            f_end.append(float(p.frequencies(m.f_array, z_end, self.pivot)[0]))
        rows = slice(q * nm, (q + 1) * nm)
        self._engine.adjoint_sums(self.h, np.ascontiguousarray(np.vstack(rows_f)),
                                  np.array(zeta), np.array(gain), k_end, S[rows])
        z_arr, w = np.array(zeta), 2.0 * np.pi * np.array(f_end)
        sig[rows] = z_arr * w
        wd[rows] = w * np.sqrt(1.0 - z_arr * z_arr)
        ready[q] = 1

    def _scale_only(self, T_x: float) -> tuple[np.ndarray, np.ndarray, list[float]]:
        """Damping ratios, gains and nominal end frequencies of the modes at ``T_x``."""
        got = self._ends.get(T_x)
        if got is None:
            z_end = self._z_path(T_x)[2]
            got = (np.array(self._zeta), np.array([m.gain for m in self.modes]),
                   [float(m.f_array(z_end)[0]) for m in self.modes])
            if len(self._ends) >= 4096:
                self._ends.clear()
            self._ends[T_x] = got
        return got

    def worst(self, N: Sequence[int], points: tuple[Perturbation, ...], order: np.ndarray,
              bound: float = math.inf, max_motion_time: float = math.inf
              ) -> tuple[float, float, bool, np.ndarray | None]:
        """Return the largest residual over ``points``, or one that reaches ``bound``.

        Parameters
        ----------
        N : sequence of int
            Jerk times (samples): four, or one for JL.
        points : tuple of Perturbation
            The perturbations.
        order : ndarray of int64
            Indices of the points in the order they are computed (the likeliest
            to reach ``bound`` first).
        bound : float
            Stop at the first point whose residual is >= bound.
        max_motion_time : float
            A longer motion is infeasible: ``inf``, computing nothing.

        Returns
        -------
        motion_time : float
            Of the planned move (s).
        value : float
            The largest residual (m) over the points computed.
        exact : bool
            Every point was computed (``value`` is the worst case); otherwise
            ``value`` >= ``bound`` is a lower bound of it.
        residuals : ndarray or None
            When exact, the residual of each point (a view, overwritten by the
            next call); None otherwise.
        """
        self.evaluations += 1
        pl = self._plan(N)
        T_x = pl.motion_time
        if T_x > max_motion_time:
            return T_x, math.inf, True, None
        entry = self._sums.get((T_x, id(points)))
        if entry is None or self._sets.get(id(points)) is not points:
            entry = self._adjoint(T_x, points)
        k_end, S, sig, wd, nm, out, ready, _, fill = entry
        q = pl.adjoint_residuals(self.m, k_end, S, sig, wd, nm, order, bound, out, ready, 0,
                                 fill)
        while q < 0:  # a point not computed yet at this motion time
            q = -q - 1
            p = int(order[q])
            self._point(entry, points[p], p)
            q = pl.adjoint_residuals(self.m, k_end, S, sig, wd, nm, order, bound, out, ready, q)
        if q == len(order):
            return T_x, max(out.tolist()), True, out
        return T_x, out.item(int(order[q - 1])), False, None

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
        pts = points if isinstance(points, tuple) else tuple(points)
        T_x, _, _, r = self.worst(N, pts, np.arange(len(pts), dtype=np.int64))
        assert r is not None
        return T_x, r.copy()


def pattern_search(f: Callable[..., Any], starts: Sequence[tuple[int, ...]],
                   lo: Sequence[int], hi: Sequence[int], *, steps: Sequence[int] = STEPS,
                   tied: bool = False, max_evaluations: int = 20000, bounded: bool = False
                   ) -> tuple[tuple[int, ...], float, dict[tuple[int, ...], float]]:
    """Minimise ``f`` over integer points in the box [lo, hi] from several starts.

    Parameters
    ----------
    f : callable
        Objective of an integer point (``inf`` = infeasible); with ``bounded``,
        ``f(point, bound)`` returns ``(value, exact)``, where a value that is not
        exact is a lower bound of the objective, >= ``bound``.
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
    bounded : bool
        ``f`` takes the bound a move must beat (the objective at the current
        point) and may stop as soon as the objective is known to reach it: a
        move is accepted only when it lowers the objective, so the search takes
        the very path, and returns the very point, it takes with exact values.

    Returns
    -------
    best : tuple of int
        The best point evaluated (the first start on ties).
    value : float
        Its objective.
    cache : dict
        Every point evaluated and its value (with ``bounded``, a lower bound for
        those rejected before their value was known).
    """
    cache: dict[tuple[int, ...], float] = {}
    lower: dict[tuple[int, ...], float] = {}  # bounded: rejected points' lower bounds
    lo_t, hi_t = tuple(int(x) for x in lo), tuple(int(x) for x in hi)

    def ev(p: tuple[int, ...], bound: float = math.inf) -> float:
        v = cache.get(p)
        if v is not None:
            return v
        if not bounded:
            v = float(f(p))
            cache[p] = v
            return v
        lb = lower.get(p)
        if lb is not None and lb >= bound:
            return lb
        v, exact = f(p, bound)
        v = float(v)
        if exact:
            cache[p] = v
            lower.pop(p, None)
        else:
            lower[p] = v
        return v

    dim = len(lo_t)
    deltas = []
    for s in steps:
        ds = [tuple(d if k == i else 0 for k in range(dim)) for i in range(dim) for d in (s, -s)]
        if tied and dim == 4:
            ds += [tuple(d if k in (1, 2) else 0 for k in range(dim)) for d in (s, -s)]
            ds += [tuple(d if k == 1 else -d if k == 2 else 0 for k in range(dim))
                   for d in (s, -s)]
        deltas.append((s, ds))
    best: tuple[int, ...] | None = None
    best_v = math.inf
    for s0 in starts:
        x = tuple(min(max(int(v), lo_t[i]), hi_t[i]) for i, v in enumerate(s0))
        fx = ev(x)
        for _s, ds in deltas:
            improved = True
            while improved and len(cache) + len(lower) < max_evaluations:
                improved = False
                # the moves around the point where this sweep starts
                moves = [tuple(map(add, x, d)) for d in ds]
                for y in moves:
                    if not all(map(le, lo_t, y)) or not all(map(le, y, hi_t)):
                        continue
                    fy = ev(y, fx)
                    if fy < fx:
                        x, fx, improved = y, fy, True
        if fx < best_v or best is None:
            best, best_v = x, fx
    assert best is not None
    # the best point ever evaluated (a start may be better than another start's descent); a
    # rejected point's objective is >= the point it was compared with, never below best_v
    for p, v in cache.items():
        if v < best_v:
            best, best_v = p, v
    return best, best_v, {**lower, **cache}


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

    # the points in the order they are computed: the worst at the current point first (the
    # likeliest to reject a move without computing the others)
    order = [np.arange(len(points), dtype=np.int64)]
    t_max = bound * (1.0 + 1e-12)

    def value(N: tuple[int, ...], at_least: float = math.inf) -> tuple[float, bool]:
        full = N * 4 if len(N) == 1 else N
        _, v, exact, r = obj.worst(full, points, order[0], at_least, t_max)
        if r is not None:  # a complete evaluation: the next current point
            order[0] = np.argsort(-r, kind="stable")
        return v, exact

    if profile == "JL":
        # one dimension: every jerk time in the band
        cache = {(n,): value((n,))[0] for n in range(lo[0], hi[0] + 1)}
        best = min(cache, key=lambda p: (cache[p], abs(p[0] - n_jl)))
        best_v = cache[best]
        N = (best[0],) * 4
        start: tuple[int, ...] = (n_jl,)
    else:
        # the robust objective is smoother: fewer starts
        starts = _starts(tuple(int(x) for x in paper.N_F) if paper is not None else None, n_jl,
                         every_mix=method == "optimal")
        best, best_v, cache = pattern_search(value, starts, lo, hi, tied=True, bounded=True)
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
