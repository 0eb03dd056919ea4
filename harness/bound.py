"""The physical limit as a measure: a lower bound on the worst-case settling time.

For a single-move scenario and an uncertainty set (a sequence of
:class:`harness.uncertainty.Perturbation`), :func:`settling_bound` computes how
soon ANY reference profile under the same limits can make the load settle at
every point of the set, as a linear programme, and replays its own optimal
profile through an independent integration (:func:`replay`).

What is bounded
---------------
The admissible references are those of the generator's sampling grid: a
piecewise-constant jerk on the samples ``Te`` from the motion's start (the
first sample at or after ``t_start``), from rest at ``x0`` to rest at
``x0 + distance`` at the motion time ``T = N·Te``, with

* ``|j| <= j_max`` on every sample interval (default: the largest jerk of the
  scenario's JL, ``max(a_max, d_max) / T_F``, ``T_F`` the JL jerk time the
  harness tunes; ``= a_max / T_F`` on X and Y);
* the acceleration within the move's limits, direction-aware as the generator
  plans them: for a positive move ``-d_max <= a <= a_max`` (it accelerates with
  ``a_max`` and brakes with ``d_max``), mirrored for a negative one; exact, the
  acceleration being linear between samples;
* ``|v| <= v_max`` at the samples (a relaxation: v is quadratic between the
  samples, and a reversal, ``v < 0``, is allowed: the set only grows, the
  bound stays a lower bound).

The plant is the harness's (:mod:`harness.plant`): every mode of the scenario's
map, its frequency frozen over each sample at the Z position of mid-sample
(:func:`harness.plant.hermite_mid`), stepped exactly for the piecewise-linear
acceleration (the operations of :func:`harness.plant.step_mode_jerk`); each
point's frequencies are ``Perturbation.frequencies(mode.f_array, z, pivot)``,
its damping ``Perturbation.zeta``, the pivot the middle of the Z travel.  The Z
move is synchronised with ``T`` as the harness does it
(``Session.z_velocity(sc, T)``, then the Z generator's own samples), so z(t)
depends on T alone.

The load error ``e = x + Σε - target`` is required within ``±band`` at every
**sample** from the settling sample ``m`` on, at every point.  For each T the
least such ``m`` (``m*(T)``) is found by a bracketing search on m, each step a
linear programme; the bound is the least over the motion times searched.  (A
profile may rest before T; it then counts with Z synchronised to T: the set
only grows.)  A negative move is solved mirrored (the plant is linear, the
band symmetric).  Every profile whose
motion time is one of them has a sampled error outside the band at some sample
``>= m* - 1``, so its settling time as the harness measures it
(:func:`harness.metrics.settling_time`: the last exit, interpolated between
samples) is at least ``(m* - 1)·Te`` after the motion's start: that is
:attr:`SettlingBound.t_settle`.  The LP's own optimal profile settles within
one sample above it.  For the continuous ODE the statement holds up to the
plant's discretisation (the frozen mid-sample frequency, O(Te²)): the replay
measures that.

The linear programme
--------------------
Decision variables: the acceleration at the N + 1 samples (``a_0 = a_N = 0``
fixed; the jerk of sample k is ``(a_{k+1} - a_k)/Te``, bounded by two
inequality rows), the velocity at the samples (bounded; an equality chain, the
trapezoid rule, exact for a linear acceleration), and the position from the
settling sample to the end (a short chain; the whole travel is one equality
row).  The modal states enter as follows: the state of every (point, mode)
channel at sample m is a dense linear function of the accelerations (its
rows are computed by one backward pass of the state-transition products,
the adjoint of the stepping), and from m on the states are variables tied by
the exact one-sample recursion until both axes rest; after that the plant is
free and time-invariant, and the error at each later sample is a fixed linear
function of the state at rest.  Variables are scaled (accelerations by the
limit, positions and deflections by the band).  Objective: minimise ``t``, the
largest ``|e|/band`` over the constrained samples; ``m`` is feasible when
``t* <= 1`` (to 1e-6).  Solved by HiGHS (``scipy.optimize.linprog``), interior
point first, dual simplex as a fallback.

The horizon
-----------
After both axes rest, each mode oscillates freely,
``ε(t) = R e^{-σt} cos(ω_d t - φ)``.  The LP constrains every sample from
``m`` to the rest sample, and then a window of half a damped period plus
``τ* = -ln(cos(ω_d Te / 2)) / σ`` of the slowest channel.  Within any half
period of samples one sample lies within ``ω_d Te / 2`` of a crest of the
cosine, so for a point with one mode the window gives
``R e^{-σ t_w} cos(ω_d Te/2) <= band`` at its end t_w, hence
``|ε(t)| <= band`` for every t past the window, samples and continuous time
alike: with one mode per point (X, Y) the finite window is exactly the
infinite-horizon sampled condition.  With several modes per point the window
is a relaxation (the bound stays a lower bound) and the settling of the
optimal profile is measured on a record extended until the modes' envelope
is inside the band.  Undamped, the window leaves a relative slack of
``1/cos(ω Te/2) - 1`` (2e-4 at 10 Hz).

The uncertainty points
----------------------
The LP holds a subset of the points (each range's two ends, the most nominal
point and five more spread over the set); each solution found feasible is
checked on every point with the harness's compiled plant
(:func:`harness.simulation.master.step_plant`), and the (up to three) worst
points it misses are added and the LP solved again.  A subset's LP is a
relaxation, so an infeasible one proves infeasibility for the whole set, and
a solution that meets every point proves feasibility.

The search over T
-----------------
The motion times searched run from the shortest the limits allow
(``T_min``, LP bisection on the kinematics alone) to ``T_min + P_max``
(``P_max`` the longest modal period), a quarter of ``P_max`` apart, then
``±P_max/8`` around the best.  At the first one (``T_min + P_max/2``) the
settling sample is bracketed by the secant of ``ln t*`` and closed by
interpolation; at each further T one LP asks whether ``m_best - 1`` is
feasible.  A longer motion time admits the shorter profiles (the reference
may rest early; only the Z synchronisation differs), so ``m*(T)`` falls
steeply from ``T_min`` and levels off within about ``P_max/2``.  Far beyond,
it may still gain a sample or two: a slower Z keeps the mode stiffer while
the reference creeps inside the band (Y: 0.682 s instead of 0.683 s at
T = 1.19 s).  The bound is the least ``m*`` over the motion times searched
(:attr:`SettlingBound.searched`); give ``T_range`` to search others.

Cost
----
About 20-30 LPs of 3,000-11,000 rows: X with the nine map scales 0.90 ... 1.10
in about 25 s, Y in about 8 s; the 41-point scoring set in about 30 s and 10 s
(two shared cores, the replay included, under a second).

Examples
--------
>>> import numpy as np
>>> from harness.bound import settling_bound
>>> from harness.scenario import load_scenario
>>> from harness.uncertainty import Perturbation
>>> pts = [Perturbation(scale=s - 1.0) for s in np.linspace(0.9, 1.1, 9)]
>>> b = settling_bound(load_scenario("Y"), pts)                      # doctest: +SKIP
>>> round(b.t_settle, 3), round(b.replay_worst_settle, 3)           # doctest: +SKIP
"""

from __future__ import annotations

import hashlib
import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import __version__
from .files import write_text
from .fmu.build import cache_dir
from .metrics import settling_time
from .plant import Mode, ScheduledMode, free_amplitude, hermite_mid, transitions
from .scenario import Scenario
from .simulation.axis import PlantInput
from .simulation.master import step_plant
from .simulation.session import Session
from .tuning.tune import jerk_times, tune_profile
from .uncertainty import Perturbation

__all__ = [
    "FEASIBILITY_TOL",
    "BoundSummary",
    "Replay",
    "SettlingBound",
    "bound_summary",
    "replay",
    "settling_bound",
]

FEASIBILITY_TOL = 1e-6
"""A settling sample is feasible when the LP's largest ``|e|/band`` is <= 1 + this."""

_ACCEPT_TOL = 1e-4
"""A solution the compiled plant finds over the band by less than this (relative) on a point
the LP already holds is accepted: the difference is the LP's own tolerance."""

_FIRST_POINTS = 5
"""Points of the set, evenly spaced in its order, the first LPs hold (besides its corners)."""

_ADD_POINTS = 3
"""Points added to the LP at most per round (the worst violated ones)."""

_REPLAY_RTOL = 1e-11
_REPLAY_ATOL = 1e-16
"""DOP853 tolerances of the replay (relative; absolute, m and m/s)."""

_MAX_EXTENSION = 60.0
"""Longest free decay the settling measurements follow past the rest (s)."""


# ------------------------------------------------------------------ results


@dataclass
class Replay:
    """A reference replayed through the continuous time-varying ODE at every point.

    Attributes
    ----------
    t : ndarray
        Sample times (s, absolute).
    error : ndarray
        Load error ``x + Σε - target`` at each point and sample (m), shape (P, n).
    settle : ndarray
        Settling time of each point (s, from ``t_start``; ``inf`` if never).
    band : float
        The band (m).
    seconds : float
        Wall time of the integration (s).
    """

    t: np.ndarray
    error: np.ndarray
    settle: np.ndarray
    band: float
    seconds: float

    @property
    def worst_settle(self) -> float:
        """Return the worst settling time over the points (s)."""
        return float(np.max(self.settle))


@dataclass
class SettlingBound:
    """The lower bound on the worst-case settling time, and the profile that reaches it.

    Attributes
    ----------
    scenario : str
        Scenario name.
    t_settle : float
        The bound (s, from ``t_start``): every admissible profile of a motion time
        searched has a settling time (as the harness measures it) of at least this.
    settle_sample : int
        ``m*``: the first sample (from the motion's start) from which the optimal
        profile's sampled error stays in the band at every point.
    motion_time : float
        The motion time T of the optimal profile (s); Z is synchronised with it.
    rest_time : float
        When the optimal profile comes to rest (s from the motion's start, <= T).
    jerk : ndarray
        The optimal profile's jerk on each sample (m/s³), N values.
    x, v, a : ndarray
        Its position (m), velocity (m/s) and acceleration (m/s²) at the N + 1
        samples from the motion's start.
    t : ndarray
        Sample times of the error records (s, absolute).
    error_min, error_max : ndarray
        Envelope over the points of the load error on the harness's plant (m).
    band : float
        The settling band (m).
    j_max : float
        The jerk limit (m/s³).
    points : tuple of Perturbation
        The uncertainty set.
    plant_settle : ndarray
        Settling time of the optimal profile at each point on the harness's
        (discrete) plant (s).
    replay_settle : ndarray
        The same through the independent integration (:func:`replay`) (s).
    replay_worst_settle : float
        Their worst (s).
    replay_peak : float
        Largest ``|e|/band`` of the replay at or after the settle sample.
    searched : list of tuple
        ``(T, m, exact)`` for each motion time searched: ``m`` the least feasible
        settling sample there (``exact``), or a lower bound on it (the best so
        far, when ``m - 1`` was infeasible there; -1: never settles).
    lp_points : tuple of int
        Indices of the points the LPs were built on (the rest were checked only).
    lp_solves : int
        LPs solved (the kinematic ones for ``T_min`` included).
    lp_size : dict
        Rows, columns and non-zeros of the LP that found the optimum.
    tail : int
        Samples of the free window after the rest (the horizon, see the module notes).
    seconds : float
        Wall time (s), the replay included.
    replay_seconds : float
        Wall time of the replay alone (s).
    t_start : float
        Start of the motion (s).
    """

    scenario: str
    t_settle: float
    settle_sample: int
    motion_time: float
    rest_time: float
    jerk: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    t: np.ndarray
    error_min: np.ndarray
    error_max: np.ndarray
    band: float
    j_max: float
    points: tuple[Perturbation, ...]
    plant_settle: np.ndarray
    replay_settle: np.ndarray
    replay_worst_settle: float
    replay_peak: float
    searched: list[tuple[float, int, bool]]
    lp_points: tuple[int, ...]
    lp_solves: int
    lp_size: dict[str, int]
    tail: int
    seconds: float
    replay_seconds: float
    t_start: float = 0.0
    notes: list[str] = field(default_factory=list)

    @property
    def plant_worst_settle(self) -> float:
        """Return the optimal profile's worst settling time on the harness's plant (s)."""
        return float(np.max(self.plant_settle))

    def rows(self) -> list[dict[str, Any]]:
        """Return one CSV row per point: the point, its settling times, and the bound's figures."""
        common = {
            "scenario": self.scenario, "bound_s": self.t_settle,
            "motion_time_s": self.motion_time, "rest_time_s": self.rest_time,
            "band_m": self.band, "j_max_m_s3": self.j_max,
            "replay_worst_settle_s": self.replay_worst_settle, "lp_solves": self.lp_solves,
            "seconds": self.seconds,
        }
        return [{**common, "point": p.label(), "scale": p.scale, "slope": p.slope,
                 "shift_m": p.shift, "damping": p.damping,
                 "plant_settle_s": float(self.plant_settle[i]),
                 "replay_settle_s": float(self.replay_settle[i]),
                 "in_lp": i in self.lp_points}
                for i, p in enumerate(self.points)]

    def plot(self, title: str | None = None) -> Any:
        """Plot the optimal profile and the envelope of the load error over the points.

        Returns
        -------
        matplotlib.figure.Figure
        """
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        n = self.jerk.size
        tk = self.t[0] + self.motion_time * np.arange(n + 1) / n
        fig, (ax1, ax2, ax3) = plt.subplots(3, 1, sharex=True, figsize=(8, 7))
        ax1.plot(tk, self.v, label="v [m/s]")
        ax1.plot(tk, self.a, label="a [m/s²]")
        ax1.set_ylabel("v, a")
        ax1.legend(fontsize="small")
        ax2.step(tk[:-1], self.jerk, where="post")
        ax2.axhline(self.j_max, color="grey", lw=0.8, ls="--")
        ax2.axhline(-self.j_max, color="grey", lw=0.8, ls="--")
        ax2.set_ylabel("j [m/s³]")
        scale = 1e6
        ax3.fill_between(self.t, self.error_min * scale, self.error_max * scale, alpha=0.4,
                         label=f"load error, {len(self.points)} points")
        ax3.axhline(self.band * scale, color="k", lw=0.8)
        ax3.axhline(-self.band * scale, color="k", lw=0.8)
        ax3.axvline(self.t_start + self.t_settle, color="C3", lw=1.0,
                    label=f"bound {self.t_settle:.3f} s")
        lim = 20 * self.band * scale
        ax3.set_ylim(-lim, lim)
        ax3.set_ylabel("e [µm]")
        ax3.set_xlabel("t [s]")
        ax3.legend(fontsize="small")
        for ax in (ax1, ax2, ax3):
            ax.grid(True, alpha=0.3)
        fig.suptitle(title or f"{self.scenario}: settling bound {self.t_settle:.3f} s "
                     f"(replayed {self.replay_worst_settle:.3f} s)")
        fig.tight_layout()
        return fig


# ------------------------------------------------------------------ checks


def _positive(value: object, name: str) -> float:
    """Return ``value`` as a float, or raise ValueError naming ``name`` unless finite and > 0."""
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{name} must be a number > 0, got {value!r}")
    v = float(value)
    if not (math.isfinite(v) and v > 0.0):
        raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    return v


def _check_points(points: Sequence[Perturbation]) -> tuple[Perturbation, ...]:
    """Return the points as a tuple; raise ValueError (naming ``points``) if empty or not points."""
    pts = tuple(getattr(points, "points", points))
    if not pts:
        raise ValueError("points: the uncertainty set is empty")
    bad = [p for p in pts if not isinstance(p, Perturbation)]
    if bad:
        raise ValueError(f"points must be harness.uncertainty.Perturbation, got {bad[0]!r}")
    return pts


def _check_scenario(sc: Scenario) -> None:
    """Raise ValueError (naming ``sc``) for a sweep scenario or a move of zero length."""
    if not isinstance(sc, Scenario):
        raise ValueError(f"sc must be a harness.scenario.Scenario, got {type(sc).__name__}")
    if sc.is_sweep:
        raise ValueError(f"sc: scenario {sc.name!r} is a sweep; give one of its cases "
                         f"(sc.cases())")
    if sc.move.distance == 0.0:
        raise ValueError("sc: the move has zero length")


# ------------------------------------------------------------------ the plant


def _one_step(omega: np.ndarray, zeta: np.ndarray, gain: np.ndarray, h: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return the exact one-step maps of :func:`harness.plant.step_mode_jerk`, vectorised.

    ``s' = Φ s + ga·u0 + gj·jerk`` for the state s = (ε, ε̇), the input
    ``u0 + jerk·τ`` over the step; the same operations as ``step_mode_jerk``
    (particular solution α + βτ, the deviation propagated by Φ).

    Returns
    -------
    phi : ndarray
        Shape (..., 2, 2).
    ga, gj : ndarray
        Shape (..., 2).
    """
    sig = zeta * omega
    w2 = omega * omega
    phi = transitions(omega, zeta, h)
    # zero state: α = (-g u0 - 2σβ)/ω², β = -g jerk/ω²; s' = (α + βh, β) - Φ (α, β)
    d_alpha = np.stack([1.0 - phi[..., 0, 0], -phi[..., 1, 0]], axis=-1)
    d_beta = np.stack([h - phi[..., 0, 1], 1.0 - phi[..., 1, 1]], axis=-1)
    ga = (-gain / w2)[..., None] * d_alpha
    gj = (2.0 * sig * gain / (w2 * w2))[..., None] * d_alpha + (-gain / w2)[..., None] * d_beta
    return phi, ga, gj


@dataclass
class _Context:
    """What the searches need that does not depend on the motion time."""

    sc: Scenario
    session: Session
    points: tuple[Perturbation, ...]
    modes: list[ScheduledMode]
    band: float
    j_max: float
    Te: float
    k0: int
    t_start: float
    sign: float
    distance: float
    a_lo: float
    a_hi: float
    v_max: float
    pivot: float
    zeta: np.ndarray
    gain: np.ndarray
    progress: bool
    lp_solves: int = 0
    lp_points: list[int] = field(default_factory=list)

    @property
    def nm(self) -> int:
        """Modes per point."""
        return len(self.modes)

    def say(self, text: str) -> None:
        """Print a progress line (with ``progress=True``)."""
        if self.progress:
            print(f"[bound {self.sc.name}] {text}", file=sys.stderr, flush=True)

    def omega(self, z: np.ndarray) -> np.ndarray:
        """Return the angular frequency of every (point, mode) channel at ``z``, shape (n, Q)."""
        z = np.asarray(z, dtype=float)
        cols = [2.0 * math.pi * p.frequencies(m.f_array, z, self.pivot)
                for p in self.points for m in self.modes]
        return np.stack(cols, axis=-1)


@dataclass
class _Schedule:
    """The plant of one motion time: per-sample maps of every channel, Z synchronised."""

    N: int
    n_rest: int
    tail: int
    phi: np.ndarray
    ga: np.ndarray
    gj: np.ndarray
    phi_rest: np.ndarray
    omega_rest: np.ndarray
    zm: np.ndarray
    z_end: float

    def phi_at(self, n: int) -> np.ndarray:
        """Return Φ of the step from sample n, shape (Q, 2, 2)."""
        return self.phi[n] if n < self.n_rest else self.phi_rest


def _schedule(ctx: _Context, N: int) -> _Schedule:
    """Plan Z for the motion time ``N·Te`` as the harness does and step maps of every channel."""
    s, sc, Te = ctx.session, ctx.sc, ctx.Te
    v_z, _ = s.z_velocity(sc, N * Te)
    T_z = s.z_axis.plan(Session.z_move_params(sc, v_z))
    kz = int(round(s.z_axis.motion_start() / Te))
    n_z = kz + int(math.ceil(T_z / Te - 1e-9)) - ctx.k0 if sc.z.moves else 0
    n_rest = max(N, n_z)
    Z = s.z_axis.points(ctx.k0 + n_rest, Te, ("x", "v"))
    z = np.asarray(Z["x"][ctx.k0:], dtype=float)
    vz = np.asarray(Z["v"][ctx.k0:], dtype=float)
    zm = hermite_mid(z[:-1], vz[:-1], z[1:], vz[1:], Te)
    om = ctx.omega(zm) if n_rest else np.zeros((0, ctx.zeta.size))
    phi, ga, gj = _one_step(om, ctx.zeta[None, :], ctx.gain[None, :], Te)
    om_r = ctx.omega(np.array([z[-1]]))[0]
    phi_r, _, _ = _one_step(om_r, ctx.zeta, ctx.gain, Te)
    wd = om_r * np.sqrt(1.0 - ctx.zeta**2)
    sig = ctx.zeta * om_r
    with np.errstate(divide="ignore"):
        tau = np.where(sig > 0.0, -np.log(np.cos(0.5 * wd * Te)) / np.where(sig > 0, sig, 1.0),
                       0.0)
    tail = int(math.ceil(float(np.max(math.pi / wd + tau)) / Te)) + 2
    return _Schedule(N, n_rest, tail, phi, ga, gj, phi_r, om_r, zm, float(z[-1]))


def _state_rows(sch: _Schedule, chans: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Return the state at sample m of the channels as linear maps of the input.

    One backward pass of the adjoint: ``λ_k = Ψ(m, k+1)``, so that
    ``s_m = Σ_k λ_k (ga_k a_k + gj_k j_k)`` over the steps k < min(m, N).

    Returns
    -------
    ca, cj : ndarray
        Shape (len(chans), 2, K), K = min(m, N): the coefficients of ``a_k`` and ``j_k``.
    """
    K = min(m, sch.N)
    q = chans.size
    lam = np.broadcast_to(np.eye(2), (q, 2, 2)).copy()
    if m > sch.n_rest:  # free, time-invariant steps after the rest: a matrix power
        lam = np.stack([np.linalg.matrix_power(sch.phi_rest[c], m - sch.n_rest) for c in chans])
    top = min(m, sch.n_rest)
    ca = np.zeros((q, 2, K))
    cj = np.zeros((q, 2, K))
    phi = sch.phi[:, chans]
    ga = sch.ga[:, chans]
    gj = sch.gj[:, chans]
    for k in range(top - 1, -1, -1):
        if k < K:
            ca[:, :, k] = np.einsum("qrc,qc->qr", lam, ga[k])
            cj[:, :, k] = np.einsum("qrc,qc->qr", lam, gj[k])
        lam = np.einsum("qrc,qcd->qrd", lam, phi[k])
    return ca, cj


# ------------------------------------------------------------------ the LP


class _Rows:
    """Sparse rows in COO triplets."""

    def __init__(self) -> None:
        self.r: list[np.ndarray] = []
        self.c: list[np.ndarray] = []
        self.v: list[np.ndarray] = []
        self.n = 0

    def add(self, cols: Any, vals: Any) -> int:
        """Append one row; return its index."""
        cols = np.asarray(cols, dtype=np.int64).ravel()
        self.r.append(np.full(cols.size, self.n, dtype=np.int64))
        self.c.append(cols)
        self.v.append(np.broadcast_to(np.asarray(vals, dtype=float), cols.shape).ravel())
        self.n += 1
        return self.n - 1

    def block(self, count: int, parts: Sequence[tuple[np.ndarray, Any]]) -> None:
        """Append ``count`` rows; row i holds ``(cols[i], vals[i])`` of every part."""
        base = self.n + np.arange(count, dtype=np.int64)
        for cols, vals in parts:
            cols = np.asarray(cols, dtype=np.int64)
            self.r.append(base)
            self.c.append(cols)
            self.v.append(np.broadcast_to(np.asarray(vals, dtype=float), cols.shape).copy())
        self.n += count

    def matrix(self, ncol: int) -> Any:
        """Return the rows as a CSR matrix."""
        from scipy import sparse  # deferred: scipy is heavy to import

        if not self.r:
            return sparse.csr_matrix((0, ncol))
        return sparse.csr_matrix((np.concatenate(self.v),
                                  (np.concatenate(self.r), np.concatenate(self.c))),
                                 shape=(self.n, ncol))


@dataclass
class _Solution:
    """One LP's outcome."""

    t: float
    jerk: np.ndarray | None
    size: dict[str, int]


def _linprog(c: np.ndarray, a_ub: Any, b_ub: np.ndarray, a_eq: Any, b_eq: np.ndarray,
             bounds: np.ndarray, methods: Sequence[str] = ("highs-ipm", "highs-ds", "highs")
             ) -> Any:
    """Solve with HiGHS, trying the next method when one does not finish."""
    from scipy.optimize import linprog  # deferred: scipy is heavy to import

    res = None
    for method in methods:
        res = linprog(c, A_ub=a_ub, b_ub=b_ub, A_eq=a_eq, b_eq=b_eq, bounds=bounds,
                      method=method)
        if res.status in (0, 2):  # optimal, or infeasible (the kinematics alone)
            return res
    return res


def _settle_lp(ctx: _Context, sch: _Schedule, m: int, subset: Sequence[int]) -> _Solution:
    """Minimise the largest ``|e|/band`` from sample m on, at the points of ``subset``."""
    N, Te, B = sch.N, ctx.Te, ctx.band
    A = max(-ctx.a_lo, ctx.a_hi)
    V, J, D = ctx.v_max, ctx.j_max, ctx.distance
    pts = np.asarray(subset, dtype=np.int64)
    chans = (pts[:, None] * ctx.nm + np.arange(ctx.nm)[None, :]).ravel()
    Q = chans.size
    om = float(np.mean(sch.omega_rest[chans]))
    sc2 = np.array([1.0, om])  # ε in band units, ε̇ in band·ω units
    n_e = max(sch.n_rest, m)
    mx = min(m, N)
    iA, iV = 0, N + 1
    iX = 2 * N + 2 - mx  # x_n, n in [mx, N]
    iS = 2 * N + 2 + (N - mx + 1)
    it = iS + 2 * Q * (n_e - m + 1)
    nvar = it + 1

    def S(n: int | np.ndarray, q: int | np.ndarray, r: int) -> Any:
        return iS + ((np.asarray(n) - m) * Q + q) * 2 + r

    k = np.arange(N)
    eq = _Rows()
    cva = Te * A / (2.0 * V)
    eq.block(N, [(iV + k + 1, 1.0), (iV + k, -1.0), (iA + k, -cva), (iA + k + 1, -cva)])
    # the whole travel: x_N - x_0 = Σ Te v_k + Te² (2 a_k + a_{k+1}) / 6   (band units)
    row = np.zeros(2 * N + 2)
    row[iV + k] += Te * V / B
    row[iA + k] += Te**2 * A / (3.0 * B)
    row[iA + k + 1] += Te**2 * A / (6.0 * B)
    nz = np.flatnonzero(row)
    i_travel = eq.add(nz, row[nz])
    kk = np.arange(mx, N)
    eq.block(kk.size, [(iX + kk + 1, 1.0), (iX + kk, -1.0), (iV + kk, -Te * V / B),
                       (iA + kk, -Te**2 * A / (3.0 * B)), (iA + kk + 1, -Te**2 * A / (6.0 * B))])
    # the channels' state at m, dense in the accelerations (j_k = (a_{k+1} - a_k)/Te)
    ca, cj = _state_rows(sch, chans, m)
    K = ca.shape[2]
    coef = np.zeros((Q, 2, K + 1))
    if K:
        coef[:, :, :K] += ca - cj / Te
        coef[:, :, 1:] += cj / Te
    ak = iA + np.arange(K + 1)
    for q in range(Q):
        for r in range(2):
            if K:
                eq.add(np.concatenate(([S(m, q, r)], ak)),
                       np.concatenate(([1.0], -coef[q, r] * A / (B * sc2[r]))))
            else:
                eq.add([S(m, q, r)], [1.0])
    # the exact one-sample recursion from m to the rest
    qq = np.arange(Q)
    for n in range(m, n_e):
        ph = sch.phi_at(n)[chans]
        for r in range(2):
            parts = [(S(n + 1, qq, r), 1.0), (S(n, qq, 0), -ph[:, r, 0] / sc2[r]),
                     (S(n, qq, 1), -ph[:, r, 1] * sc2[1] / sc2[r])]
            if n < N:
                g_a = sch.ga[n, chans, r]
                g_j = sch.gj[n, chans, r]
                parts += [(np.full(Q, iA + n), -(g_a - g_j / Te) * A / (B * sc2[r])),
                          (np.full(Q, iA + n + 1), -(g_j / Te) * A / (B * sc2[r]))]
            eq.block(Q, parts)
    b_eq = np.zeros(eq.n)
    b_eq[i_travel] = abs(D) / B
    ub = _Rows()
    slope = Te * J / A
    ub.block(N, [(iA + k + 1, 1.0), (iA + k, -1.0)])
    ub.block(N, [(iA + k + 1, -1.0), (iA + k, 1.0)])
    groups = [np.flatnonzero(np.repeat(np.arange(pts.size), ctx.nm) == i)
              for i in range(pts.size)]
    for n in range(m, n_e + 1):
        for g in groups:
            for sgn in (1.0, -1.0):
                cols = [*S(n, g, 0).tolist(), it]
                vals = [sgn] * g.size + [-1.0]
                if n < N:
                    cols.append(iX + n)
                    vals.append(sgn)
                ub.add(cols, vals)
    pw = np.broadcast_to(np.eye(2), (Q, 2, 2)).copy()
    ph_r = sch.phi_rest[chans]
    for _ in range(sch.tail):
        pw = np.einsum("qrc,qcd->qrd", ph_r, pw)
        for g in groups:
            cols = [*S(n_e, g, 0).tolist(), *S(n_e, g, 1).tolist(), it]
            base = np.concatenate((pw[g, 0, 0] * sc2[0], pw[g, 0, 1] * sc2[1]))
            ub.add(cols, np.concatenate((base, [-1.0])))
            ub.add(cols, np.concatenate((-base, [-1.0])))
    b_ub = np.zeros(ub.n)
    b_ub[:2 * N] = slope
    lo = np.full(nvar, -np.inf)
    hi = np.full(nvar, np.inf)
    lo[iA:iA + N + 1], hi[iA:iA + N + 1] = ctx.a_lo / A, ctx.a_hi / A
    lo[iV:iV + N + 1], hi[iV:iV + N + 1] = -1.0, 1.0
    for i in (iA, iA + N, iV, iV + N, iX + N):
        lo[i] = hi[i] = 0.0
    lo[it] = 0.0
    c = np.zeros(nvar)
    c[it] = 1.0
    a_eq, a_ub = eq.matrix(nvar), ub.matrix(nvar)
    size = {"rows": int(eq.n + ub.n), "cols": int(nvar), "nnz": int(a_eq.nnz + a_ub.nnz)}
    res = _linprog(c, a_ub, b_ub, a_eq, b_eq, np.column_stack((lo, hi)))
    ctx.lp_solves += 1
    if res.status != 0:
        return _Solution(math.inf, None, size)
    a = res.x[iA:iA + N + 1] * A
    return _Solution(float(res.x[it]), np.diff(a) / Te, size)


def _kinematic_lp(ctx: _Context, N: int) -> bool:
    """Return True if a rest-to-rest move of N samples meets the limits (an LP, no plant)."""
    Te, A, V = ctx.Te, max(-ctx.a_lo, ctx.a_hi), ctx.v_max
    D = abs(ctx.distance)
    k = np.arange(N)
    iA, iV, nvar = 0, N + 1, 2 * N + 2
    eq = _Rows()
    cva = Te * A / (2.0 * V)
    eq.block(N, [(iV + k + 1, 1.0), (iV + k, -1.0), (iA + k, -cva), (iA + k + 1, -cva)])
    row = np.zeros(nvar)
    row[iV + k] += Te * V / D
    row[iA + k] += Te**2 * A / (3.0 * D)
    row[iA + k + 1] += Te**2 * A / (6.0 * D)
    nz = np.flatnonzero(row)
    eq.add(nz, row[nz])
    b_eq = np.zeros(eq.n)
    b_eq[-1] = 1.0
    ub = _Rows()
    ub.block(N, [(iA + k + 1, 1.0), (iA + k, -1.0)])
    ub.block(N, [(iA + k + 1, -1.0), (iA + k, 1.0)])
    b_ub = np.full(ub.n, Te * ctx.j_max / A)
    lo = np.full(nvar, -1.0)
    hi = np.full(nvar, 1.0)
    lo[iA:iA + N + 1], hi[iA:iA + N + 1] = ctx.a_lo / A, ctx.a_hi / A
    for i in (iA, iA + N, iV, iV + N):
        lo[i] = hi[i] = 0.0
    res = _linprog(np.zeros(nvar), ub.matrix(nvar), b_ub, eq.matrix(nvar), b_eq,
                   np.column_stack((lo, hi)), ("highs-ds", "highs-ipm", "highs"))
    ctx.lp_solves += 1
    return bool(res.status == 0)


def _shortest_motion(ctx: _Context) -> int:
    """Return the fewest samples of a rest-to-rest move under the limits (LP bisection).

    Bracketed by the acceleration-limited move (no jerk limit: shorter than any
    admissible one) and that move averaged over ``(a_max + d_max) / j_max``
    (admissible in continuous time).
    """
    D, V, a, d, Te = abs(ctx.distance), ctx.v_max, ctx.a_hi, -ctx.a_lo, ctx.Te
    if V * V * (a + d) / (2.0 * a * d) <= D:  # the velocity limit is reached
        t_al = D / V + V / (2.0 * a) + V / (2.0 * d)
    else:
        v_peak = math.sqrt(2.0 * D * a * d / (a + d))
        t_al = v_peak / a + v_peak / d
    lo = max(1, int(math.floor(t_al / Te)) - 1)
    while lo > 1 and _kinematic_lp(ctx, lo):
        lo = max(1, lo // 2)
    step = int(math.ceil((a + d) / ctx.j_max / Te)) + 2
    hi = lo + step
    while not _kinematic_lp(ctx, hi):
        lo, hi = hi, hi + step
        step *= 2
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if _kinematic_lp(ctx, mid):
            hi = mid
        else:
            lo = mid
    return hi


# ------------------------------------------------------------------ profiles and plants


def _kinematics(jerk: np.ndarray, Te: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Return x - x0, v, a at the samples of a jerk profile from rest (exact cubics)."""
    j = np.asarray(jerk, dtype=float)
    a = np.concatenate(([0.0], np.cumsum(j * Te)))
    v = np.concatenate(([0.0], np.cumsum(Te * a[:-1] + 0.5 * Te**2 * j)))
    x = np.concatenate(([0.0], np.cumsum(Te * v[:-1] + 0.5 * Te**2 * a[:-1] + Te**3 / 6.0 * j)))
    return x, v, a


def _polish(jerk: np.ndarray, ctx: _Context) -> np.ndarray:
    """Return the jerk corrected (least norm, on the samples off their limit) to land exactly.

    The LP meets the end conditions to its tolerance; the three residuals
    (a_N, v_N, x_N - distance) are removed by the smallest change of the jerk
    samples that are not at a limit.
    """
    Te = ctx.Te
    N = jerk.size
    k = np.arange(N)
    # a_N, v_N, x_N as linear functionals of the jerk
    M = np.vstack((np.full(N, Te),
                   Te**2 * (N - k - 0.5),
                   Te**3 * ((N - k - 1) ** 2 / 2.0 + (N - k - 1) / 2.0 + 1.0 / 6.0)))
    x, v, a = _kinematics(jerk, Te)
    r = np.array([a[-1], v[-1], x[-1] - abs(ctx.distance)])
    free = np.abs(jerk) < ctx.j_max * (1.0 - 1e-6)
    if free.sum() < 3:
        return jerk
    Mf = M[:, free]
    out = jerk.copy()
    out[free] -= Mf.T @ np.linalg.solve(Mf @ Mf.T, r)
    return out


def _perturbed_modes(ctx: _Context, p: Perturbation) -> list[ScheduledMode]:
    """Return the scenario's modes with a point's damping (frequencies come separately)."""
    return [ScheduledMode(m.f_of_z, p.zeta(m.zeta), m.gain, m.name, m.f_of_z_array)
            for m in ctx.modes]


def _plant_errors(ctx: _Context, sch: _Schedule, jerk: np.ndarray, n_end: int,
                  which: Sequence[int] | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Run the harness's compiled plant (:func:`step_plant`) for each point; return the errors.

    Returns
    -------
    err : ndarray
        Load error at samples 0..n_end from the motion's start (mirrored to a
        positive move), shape (P, n_end + 1).
    final : ndarray
        The modal states at n_end, shape (P, 2 nm).
    """
    Te, N = ctx.Te, jerk.size
    x, _, a = _kinematics(jerk, Te)
    a_in = np.zeros(n_end)
    j_in = np.zeros(n_end)
    a_in[:min(N, n_end)] = a[:min(N, n_end)]
    j_in[:min(N, n_end)] = jerk[:min(N, n_end)]
    xe = np.full(n_end + 1, abs(ctx.distance))
    xe[:min(N, n_end) + 1] = x[:min(N, n_end) + 1]
    zm = np.concatenate((sch.zm, np.full(max(0, n_end - sch.zm.size), sch.z_end)))[:n_end]
    idx = range(len(ctx.points)) if which is None else which
    err = np.empty((len(idx), n_end + 1))
    final = np.empty((len(idx), 2 * ctx.nm))
    inp = PlantInput(a_in, j_in)
    for row, i in enumerate(idx):
        p = ctx.points[i]
        f_mid = np.vstack([p.frequencies(m.f_array, zm, ctx.pivot) for m in ctx.modes])
        eps, states = step_plant(inp, Te, f_mid, _perturbed_modes(ctx, p), n_end)
        err[row] = xe + eps - abs(ctx.distance)
        final[row] = states[-1]
    return err, final


def _extend_needed(states: np.ndarray, modes: Sequence[Mode], band: float) -> float:
    """Return how long the free modes need until their envelope Σ A e^{-σt} is in the band (s)."""
    need = 0.0
    nm = len(modes)
    for i, m in enumerate(modes):
        amp = free_amplitude(float(states[2 * i]), float(states[2 * i + 1]), m)
        if amp * nm > band:
            need = max(need, math.inf if m.sigma == 0 else math.log(amp * nm / band) / m.sigma)
    return need


def _settle_of(t: np.ndarray, err: np.ndarray, band: float, t_start: float) -> float:
    """Return the harness's settling time of a sampled error that ends inside the band for good."""
    s = settling_time(t, err, band * (1.0 + 1e-9), t_start)
    return math.inf if math.isnan(s) else s


# ------------------------------------------------------------------ the replay


def replay(sc: Scenario, jerk: Sequence[float] | np.ndarray, points: Sequence[Perturbation], *,
           band: float, session: Session | None = None) -> Replay:
    """Replay a jerk profile through the continuous time-varying ODE at every point.

    Independent of the harness's plant: ``scipy.integrate.solve_ivp`` (DOP853,
    rtol 1e-11) on ``ε̈ + 2ζω(t)ε̇ + ω(t)²ε = -g q̈(t)`` for every mode and
    point, restarted at every sample (the input is a polynomial on each), with
    ``q̈`` the profile's exact piecewise-linear acceleration and ``ω(t)`` the
    point's law at ``z(t)``, the Z generator's exact piecewise cubic,
    continuous in t (no frozen mid-step value).  Z is synchronised with the
    profile's motion time as the harness does.  Once both axes rest the plant is
    free and time-invariant: one integration carries it until every point's
    envelope is provably inside the band.

    Parameters
    ----------
    sc : Scenario
        A single-move scenario.
    jerk : array_like
        Jerk on each sample from the motion's start (m/s³): the motion time is
        ``len(jerk)·Te``; the profile must rest at the target at its end.
    points : sequence of Perturbation
        The uncertainty points.
    band : float
        Settling band (m).
    session : Session, optional
        A session for the Z generator (default: a fast-engine one, closed after).

    Returns
    -------
    Replay
    """
    _check_scenario(sc)
    pts = _check_points(points)
    band = _positive(band, "band")
    j = np.asarray(jerk, dtype=float).ravel()
    if j.size == 0 or not np.all(np.isfinite(j)):
        raise ValueError("jerk must be a non-empty array of finite values")
    own = session is None
    s = Session(engine="fast") if own else session
    try:
        return _replay(sc, j, pts, band, s)
    finally:
        if own:
            s.close()


def _replay(sc: Scenario, jerk: np.ndarray, pts: tuple[Perturbation, ...], band: float,
            s: Session) -> Replay:
    """Integrate (see :func:`replay`)."""
    from scipy.integrate import solve_ivp  # deferred: scipy is heavy to import

    t0 = time.perf_counter()
    Te = sc.simulation.Te
    s.axis.plan(Session.move_params(sc, "AL"))
    k0 = int(round(s.axis.motion_start() / Te))
    N = jerk.size
    sign = 1.0 if sc.move.distance > 0 else -1.0
    jerk = sign * jerk  # mirrored to a positive move (the plant is linear, the band symmetric)
    x, _, a = _kinematics(jerk, Te)
    v_z, _ = s.z_velocity(sc, N * Te)
    T_z = s.z_axis.plan(Session.z_move_params(sc, v_z))
    kz = int(round(s.z_axis.motion_start() / Te))
    n_z = kz + int(math.ceil(T_z / Te - 1e-9)) - k0 if sc.z.moves else 0
    n_rest = max(N, n_z)
    Z = s.z_axis.points(k0 + n_rest, Te, ("x", "v", "a", "j"))
    zx, zv, za, zj = (np.asarray(Z[key][k0:], dtype=float) for key in ("x", "v", "a", "j"))
    modes = sc.modemap.scheduled()
    nm = len(modes)
    pivot = sc.z.z0 + sc.z.distance / 2.0
    P = len(pts)
    zeta = np.array([p.zeta(m.zeta) for p in pts for m in modes])
    gain = np.array([m.gain for _ in pts for m in modes])
    scale_only = [p.is_scale_only for p in pts]
    factor = np.array([1.0 + p.scale for p in pts])

    def omega(z: float) -> np.ndarray:
        za_ = np.array([z])
        out = np.empty((P, nm))
        for i, m in enumerate(modes):
            base = float(m.f_array(za_)[0])
            for q, p in enumerate(pts):
                out[q, i] = base * factor[q] if scale_only[q] else \
                    float(p.frequencies(m.f_array, za_, pivot)[0])
        return 2.0 * math.pi * out.ravel()

    def rhs_of(k: int) -> Callable[[float, np.ndarray], np.ndarray]:
        ak, jk = (a[k], jerk[k]) if k < N else (0.0, 0.0)
        if k < n_rest:
            z0, v0, a0, j0 = zx[k], zv[k], za[k], zj[k]
        else:
            z0, v0, a0, j0 = zx[-1], 0.0, 0.0, 0.0

        def rhs(tau: float, y: np.ndarray) -> np.ndarray:
            w = omega(z0 + v0 * tau + 0.5 * a0 * tau * tau + j0 * tau**3 / 6.0)
            e, de = y[0::2], y[1::2]
            out = np.empty_like(y)
            out[0::2] = de
            out[1::2] = -2.0 * zeta * w * de - w * w * e - gain * (ak + jk * tau)
            return out

        return rhs

    y = np.zeros(2 * P * nm)
    eps = np.zeros((P, n_rest + 1))
    for k in range(n_rest):
        sol = solve_ivp(rhs_of(k), (0.0, Te), y, method="DOP853", rtol=_REPLAY_RTOL,
                        atol=_REPLAY_ATOL)
        y = sol.y[:, -1]
        eps[:, k + 1] = y[0::2].reshape(P, nm).sum(axis=1)
    # both axes rest: free and time-invariant; integrate until every envelope is inside
    w_r = omega(float(zx[-1])).reshape(P, nm)
    need = np.empty(P)
    for q in range(P):
        mq = [Mode(float(w_r[q, i] / (2.0 * math.pi)), float(zeta[q * nm + i]),
                   float(gain[q * nm + i])) for i in range(nm)]
        need[q] = _extend_needed(y[2 * q * nm:2 * (q + 1) * nm], mq, band)
    extra = int(math.ceil(min(float(np.max(need)), _MAX_EXTENSION) / Te)) + 2
    tau = Te * np.arange(1, extra + 1)
    sol = solve_ivp(rhs_of(n_rest), (0.0, float(tau[-1])), y, method="DOP853",
                    rtol=_REPLAY_RTOL, atol=_REPLAY_ATOL, t_eval=tau)
    eps_tail = sol.y[0::2].reshape(P, nm, -1).sum(axis=1)
    n_tot = n_rest + extra
    xs = np.full(n_tot + 1, abs(sc.move.distance))
    xs[:N + 1] = x
    err = np.concatenate((eps, eps_tail), axis=1) + xs[None, :] - abs(sc.move.distance)
    t = (k0 + np.arange(n_tot + 1)) * Te
    settle = np.array([math.inf if need[q] > _MAX_EXTENSION else
                       _settle_of(t, err[q], band, sc.move.t_start) for q in range(P)])
    return Replay(t, sign * err, settle, band, time.perf_counter() - t0)


# ------------------------------------------------------------------ the search


@dataclass
class _Probe:
    """Feasibility of one settling sample at one motion time."""

    feasible: bool
    t: float
    jerk: np.ndarray | None = None
    peaks: np.ndarray | None = None
    size: dict[str, int] = field(default_factory=dict)


def _probe(ctx: _Context, sch: _Schedule, m: int) -> _Probe:
    """Decide whether settling from sample m is feasible at every point.

    The LP holds the points of ``ctx.lp_points``; a solution is checked on every
    point with the compiled plant, and the worst points it misses are added (for
    good) until the LP is infeasible (then so is the whole set) or its solution
    meets every point.
    """
    subset = sorted(set(ctx.lp_points))
    while True:
        t0 = time.perf_counter()
        sol = _settle_lp(ctx, sch, m, subset)
        head = f"T = {sch.N * ctx.Te:.3f} s, m = {m}: t* = {sol.t:.4g}"
        if sol.jerk is None or sol.t > 1.0 + FEASIBILITY_TOL:
            ctx.say(f"{head} (infeasible), {len(subset)} points, "
                    f"{time.perf_counter() - t0:.2f} s")
            return _Probe(False, sol.t)
        n_end = max(sch.n_rest, m) + sch.tail
        err, _ = _plant_errors(ctx, sch, sol.jerk, n_end)
        peak = np.max(np.abs(err[:, m:]), axis=1) / ctx.band
        worst = int(np.argmax(peak))
        ctx.say(f"{head}, all points {peak[worst]:.4g}, {len(subset)} points, "
                f"{time.perf_counter() - t0:.2f} s")
        held = set(subset)
        out = [int(i) for i in np.argsort(-peak) if peak[i] > 1.0 + FEASIBILITY_TOL
               and int(i) not in held][:_ADD_POINTS]
        if not out:
            if peak[worst] > 1.0 + _ACCEPT_TOL:  # over at a point the LP holds
                raise RuntimeError(f"the LP's solution misses the band at a point it holds "
                                   f"({peak[worst]:.6g} x band): numerical trouble")
            return _Probe(True, sol.t, sol.jerk, peak, sol.size)
        subset = sorted(held.union(out))
        ctx.lp_points = subset


def _crossing(cache: dict[int, _Probe]) -> float | None:
    """Estimate where t* crosses 1: the secant of ln t* through the two probes nearest to it."""
    pts = sorted(((abs(math.log(p.t)), m, math.log(p.t)) for m, p in cache.items()
                  if 0.0 < p.t < math.inf))[:2]
    if len(pts) < 2:
        return None
    (_, m1, l1), (_, m2, l2) = pts
    slope = (l2 - l1) / (m2 - m1)
    return m1 - l1 / slope if slope < 0.0 else None


def _least_settle(ctx: _Context, sch: _Schedule, guess: int, below: int | None
                  ) -> tuple[int | None, _Probe | None]:
    """Return the least feasible settling sample at this motion time and its probe.

    The brackets (an infeasible sample below, a feasible one above) are found by
    the secant of ln t* (steps doubling when it is not available), then closed
    by interpolation, bisection when that stalls.  With ``below`` given, only a
    settling sample < ``below`` is of interest: ``below - 1`` is tried first and
    (None, None) returned if infeasible.  (None, None) too when no sample up to
    ``_MAX_EXTENSION`` past the rest is feasible.
    """
    cache: dict[int, _Probe] = {}

    def probe(m: int) -> _Probe:
        if m <= 0:  # the load starts a whole move away from the target, outside the band
            return _Probe(False, math.inf)
        if m not in cache:
            cache[m] = _probe(ctx, sch, m)
        return cache[m]

    lo: int | None = None
    hi: int | None = None
    if below is not None:
        if not probe(below - 1).feasible:
            return None, None
        hi = below - 1
    elif probe(guess).feasible:
        hi = guess
    else:
        lo = guess
    step = max(2, sch.tail // 16)
    while lo is None or hi is None:
        est = _crossing(cache)
        if lo is None:  # going down from a feasible one
            assert hi is not None
            cand = hi - step if est is None else int(math.floor(est)) - 1
            m = min(hi - 1, max(cand, hi - 4 * step))
            if probe(m).feasible:
                hi = m
            else:
                lo = m
        else:  # going up from an infeasible one
            if lo > sch.n_rest + _MAX_EXTENSION / ctx.Te:  # never settles (undamped)
                return None, None
            cand = lo + step if est is None else int(math.ceil(est)) + 1
            m = max(lo + 1, min(cand, lo + 4 * step))
            if probe(m).feasible:
                hi = m
            else:
                lo = m
        step *= 2
    while hi - lo > 1:  # interpolate ln t* between the brackets; bisect when it stalls
        t_lo, t_hi = probe(lo).t, cache[hi].t
        mid = (lo + hi) // 2
        if math.isfinite(t_lo) and t_lo > 1.0 and t_hi > 0.0:
            f = math.log(t_lo) / (math.log(t_lo) - math.log(t_hi))
            mid = min(max(lo + 1, int(round(lo + f * (hi - lo)))), hi - 1)
        if probe(mid).feasible:
            hi = mid
        else:
            lo = mid
    return hi, cache[hi]


def _first_points(pts: Sequence[Perturbation]) -> list[int]:
    """Return the points the LPs start from: each range's two ends and the most nominal point."""
    out = set()
    for key in ("scale", "slope", "shift", "damping"):
        vals = np.array([getattr(p, key) for p in pts], dtype=float)
        if np.ptp(vals) > 0:
            out.update((int(np.argmin(vals)), int(np.argmax(vals))))
    off = [abs(p.scale) + abs(p.slope) + abs(p.shift) + abs(math.log(p.damping)) for p in pts]
    out.add(int(np.argmin(off)))
    order = sorted(range(len(pts)), key=lambda i: (pts[i].scale, pts[i].slope, pts[i].shift,
                                                    pts[i].damping))
    out.update(order[int(round(x))] for x in np.linspace(0, len(pts) - 1, _FIRST_POINTS))
    return sorted(out)


def _resolve_band(sc: Scenario, s: Session) -> float:
    """Return the scenario's settling band as ``simulation.settle_band`` resolves it (m)."""
    spec = sc.simulation.settle_band
    residuals: dict[str, float] = {}
    need = spec.needs
    if need is not None:
        tuning = tune_profile(s, sc, need)
        T_F = jerk_times(sc, need, tuning)
        run = s.run(sc, need, T_F, t_stop=s.t_stop_after_motion(sc, need, T_F))
        residuals[need] = run.free_amplitude
    band, _ = spec.half_width(residuals)
    return float(band)


def _check_T_range(T_range: object) -> tuple[float, float] | None:
    """Return ``T_range`` as two floats; raise ValueError (naming it) unless 0 < lo <= hi."""
    if T_range is None:
        return None
    try:
        t_lo, t_hi = (float(v) for v in T_range)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise ValueError(f"T_range must be (T_lo, T_hi) in s, got {T_range!r}") from None
    if not (math.isfinite(t_lo) and math.isfinite(t_hi) and 0.0 < t_lo <= t_hi):
        raise ValueError(f"T_range must be (T_lo, T_hi) with 0 < T_lo <= T_hi, got {T_range!r}")
    return t_lo, t_hi


def _motion_times(ctx: _Context, n_min: int, T_range: tuple[float, float] | None, p_max: float
                  ) -> tuple[list[int], int]:
    """Return the grid of motion times (samples) to search and the refinement's step."""
    Te = ctx.Te
    if T_range is None:
        lo, hi = n_min, n_min + int(math.ceil(p_max / Te))
    else:
        t_lo, t_hi = T_range
        lo = max(n_min, int(math.ceil(t_lo / Te - 1e-9)))
        hi = max(lo, int(math.floor(t_hi / Te + 1e-9)))
    step = max(1, int(round(0.25 * p_max / Te)))
    grid = list(range(lo, hi + 1, step))
    if hi - grid[-1] > step // 2:
        grid.append(hi)
    return grid, max(1, step // 2)


def settling_bound(sc: Scenario, points: Sequence[Perturbation], *, band: float | None = None,
                   j_max: float | None = None, session: Session | None = None,
                   T_range: tuple[float, float] | None = None, progress: bool = False
                   ) -> SettlingBound:
    """Return a lower bound on the worst-case settling time any reference can reach.

    See the module notes for what is bounded, the LP, the horizon and the search.

    Parameters
    ----------
    sc : Scenario
        A single-move scenario (not a sweep).
    points : sequence of Perturbation
        The uncertainty set (e.g. ``UncertaintySpec().scoring_set().points``, or
        an :class:`~harness.uncertainty.UncertaintySet`).
    band : float, optional
        Settling band (m); default the scenario's ``simulation.settle_band``
        resolved as the harness does (1 % of AL's nominal residual by default).
    j_max : float, optional
        Jerk limit (m/s³); default the largest jerk of the scenario's JL,
        ``max(a_max, d_max) / T_F`` with the harness's JL jerk time ``T_F``.
    session : Session, optional
        Generator instances for Z (and the band's and JL's runs); default a
        fast-engine session, closed after.
    T_range : (float, float), optional
        Motion times to search (s); default ``(T_min, T_min + 2 P_max)``.
    progress : bool
        Print a line per LP to stderr.

    Returns
    -------
    SettlingBound

    Raises
    ------
    ValueError
        A sweep scenario (``sc``), an empty or malformed uncertainty set
        (``points``), ``band`` or ``j_max`` not finite and > 0, a malformed
        ``T_range``.
    """
    _check_scenario(sc)
    pts = _check_points(points)
    if band is not None:
        band = _positive(band, "band")
    if j_max is not None:
        j_max = _positive(j_max, "j_max")
    times = _check_T_range(T_range)
    own = session is None
    s = Session(engine="fast") if own else session
    try:
        return _settling_bound(sc, pts, band, j_max, s, times, progress)
    finally:
        if own:
            s.close()


def _settling_bound(sc: Scenario, pts: tuple[Perturbation, ...], band: float | None,
                    j_max: float | None, s: Session, T_range: tuple[float, float] | None,
                    progress: bool) -> SettlingBound:
    """Compute (see :func:`settling_bound`)."""
    t_wall = time.perf_counter()
    mv, Te = sc.move, sc.simulation.Te
    if band is None:
        band = _resolve_band(sc, s)
    if j_max is None:
        T_F = tune_profile(s, sc, "JL")
        tf = jerk_times(sc, "JL", T_F)
        assert tf is not None
        j_max = max(mv.a_max, mv.d_max) / float(tf[0])
    s.axis.plan(Session.move_params(sc, "AL"))
    k0 = int(round(s.axis.motion_start() / Te))
    modes = sc.modemap.scheduled()
    ctx = _Context(
        sc=sc, session=s, points=pts, modes=modes, band=band, j_max=j_max, Te=Te, k0=k0,
        t_start=mv.t_start, sign=1.0 if mv.distance > 0 else -1.0, distance=abs(mv.distance),
        a_lo=-mv.d_max, a_hi=mv.a_max, v_max=mv.v_max, pivot=sc.z.z0 + sc.z.distance / 2.0,
        zeta=np.array([p.zeta(m.zeta) for p in pts for m in modes]),
        gain=np.array([m.gain for _ in pts for m in modes]),
        progress=progress)
    ctx.lp_points = _first_points(pts)
    n_min = _shortest_motion(ctx)
    sch0 = _schedule(ctx, n_min)
    w_min = float(np.min(np.concatenate((ctx.omega(sch0.zm).ravel(), sch0.omega_rest))))
    p_max = 2.0 * math.pi / w_min
    grid, refine = _motion_times(ctx, n_min, T_range, p_max)
    ctx.say(f"band {band * 1e6:.3f} um, j_max {j_max:.4g} m/s3, T_min {n_min * Te:.3f} s, "
            f"motion times {[round(n * Te, 3) for n in grid]}")
    searched: dict[int, tuple[int, bool]] = {}
    best: tuple[int, int, _Probe] | None = None  # (m, N, probe)
    schedules: dict[int, _Schedule] = {}

    def visit(N: int) -> None:
        nonlocal best
        if N in searched:
            return
        sch = schedules.setdefault(N, _schedule(ctx, N))
        if best is None:
            m, pr = _least_settle(ctx, sch, n_min, None)
        else:
            m, pr = _least_settle(ctx, sch, best[0], best[0])
        if m is None or pr is None:  # m*(N) >= the best so far, or never settles
            searched[N] = (best[0] if best is not None else -1, False)
            return
        searched[N] = (m, True)
        if best is None or m < best[0]:
            best = (m, N, pr)

    order = sorted(grid, key=lambda n: abs(n - grid[min(2, len(grid) - 1)]))  # from T_min + P/2
    for N in order:
        visit(N)
    if best is None:
        raise RuntimeError(f"{sc.name}: no admissible profile settles within "
                           f"{_MAX_EXTENSION:g} s of its end at any motion time searched")
    for N in (best[1] - refine, best[1] + refine):  # refine around the best
        if len(grid) > 1 and grid[0] <= N <= grid[-1]:
            visit(N)
    m_star, N_best, pr = best
    sch = schedules[N_best]
    assert pr.jerk is not None
    jerk = _polish(pr.jerk, ctx)
    x, v, a = _kinematics(jerk, Te)
    moving = np.flatnonzero((np.abs(v) > 1e-12) | (np.abs(a) > 1e-12)
                            | (np.abs(x - ctx.distance) > 1e-12))
    rest = int(moving[-1]) + 1 if moving.size else 0
    # the optimal profile on the harness's plant, extended until provably settled
    n_end = max(sch.n_rest, m_star) + sch.tail
    err, final = _plant_errors(ctx, sch, jerk, n_end)
    extra = 0
    for q, p in enumerate(pts):
        mq = [Mode(float(p.frequencies(md.f_array, np.array([sch.z_end]), ctx.pivot)[0]),
                   p.zeta(md.zeta), md.gain) for md in modes]
        extra = max(extra, int(math.ceil(min(_extend_needed(final[q], mq, band),
                                             _MAX_EXTENSION) / Te)))
    if extra:
        err, _ = _plant_errors(ctx, sch, jerk, n_end + extra + 2)
    t = (k0 + np.arange(err.shape[1])) * Te
    plant_settle = np.array([_settle_of(t, e, band, mv.t_start) for e in err])
    rp = _replay(sc, ctx.sign * jerk, pts, band, s)
    m_rp = min(m_star, rp.error.shape[1] - 1)
    replay_peak = float(np.max(np.abs(rp.error[:, m_rp:])) / band)
    t_settle = (k0 + m_star - 1) * Te - mv.t_start
    sgn = ctx.sign
    return SettlingBound(
        scenario=sc.name, t_settle=max(0.0, t_settle), settle_sample=m_star,
        motion_time=N_best * Te, rest_time=rest * Te, jerk=sgn * jerk,
        x=mv.x0 + sgn * x, v=sgn * v, a=sgn * a, t=t,
        error_min=np.min(sgn * err, axis=0), error_max=np.max(sgn * err, axis=0), band=band,
        j_max=j_max, points=pts, plant_settle=plant_settle, replay_settle=rp.settle,
        replay_worst_settle=rp.worst_settle, replay_peak=replay_peak,
        searched=sorted((n * Te, m, ok) for n, (m, ok) in searched.items()),
        lp_points=tuple(ctx.lp_points), lp_solves=ctx.lp_solves, lp_size=dict(pr.size),
        tail=sch.tail, seconds=time.perf_counter() - t_wall, replay_seconds=rp.seconds,
        t_start=mv.t_start)


# ------------------------------------------------------------ the cached summary


@dataclass(frozen=True)
class BoundSummary:
    """What a table needs of a :class:`SettlingBound` (kept on disk between runs).

    Attributes
    ----------
    t_settle : float
        The bound on the worst-case settling time (s, from the motion's start).
    motion_time : float
        Motion time of the profile that reaches it (s).
    replay_worst_settle : float
        That profile's worst settling through the independent integration (s).
    j_max : float
        The jerk limit (m/s³).
    band : float
        The band (m).
    points : int
        Points of the uncertainty set.
    label : str
        The set, in words.
    seconds : float
        Wall time of the computation (s; the original one when cached).
    cached : bool
        Read from the disk cache.
    """

    t_settle: float
    motion_time: float
    replay_worst_settle: float
    j_max: float
    band: float
    points: int
    label: str
    seconds: float
    cached: bool = False

    def describe(self) -> str:
        """Return one line: the bound, how it was obtained, and its check."""
        return (f"physical limit: no profile with |j| <= {self.j_max:.4g} m/s3 under the same "
                f"v_max, a_max settles sooner than {self.t_settle:.3f} s in the worst case of the "
                f"{self.label} (LP over piecewise-constant jerk, exact plant; its own profile "
                f"replayed by an independent integration settles at "
                f"{self.replay_worst_settle:.3f} s; {self.seconds:.0f} s"
                + (", cached)" if self.cached else ")"))


def _bound_key(sc: Scenario, band: float, pts: tuple[Perturbation, ...]) -> str:
    h = hashlib.sha256(Path(__file__).read_bytes())
    case = (sc.move, sc.z, sc.modemap, sc.simulation.Te, sc.simulation.step,
            sc.simulation.short_stage, sc.compare.JL_T_F, sc.compare.jl_tuning,
            sc.compare.period_band)
    h.update(repr((case, pts, float(band).hex(), __version__)).encode())
    return h.hexdigest()[:32]


def bound_summary(sc: Scenario, band: float, points: Any = None, *,
                  session: Session | None = None, cache: bool = True,
                  cache_root: Path | None = None) -> BoundSummary:
    """Return the bound on the worst-case settling time, from the disk cache when it has it.

    Parameters
    ----------
    sc : Scenario
        A single-move scenario.
    band : float
        The settling band (m) the methods are measured in.
    points : UncertaintySet or sequence of Perturbation, optional
        Default: the scenario's scoring set (what every table reports on).
    session : Session, optional
        Generator instances (see :func:`settling_bound`).
    cache : bool
        Keep the result on disk, keyed by the move, the map, the points, the
        band and this module's code (the LP of X takes about 30 s).
    cache_root : Path, optional
        Default: next to the FMU builds (``$DJL_FMU_CACHE``).

    Returns
    -------
    BoundSummary
    """
    uset = sc.uncertainty.scoring_set() if points is None else points
    label = getattr(uset, "label", f"{len(tuple(getattr(uset, 'points', uset)))} points")
    pts = _check_points(getattr(uset, "points", uset))
    band = _positive(band, "band")
    path = None
    if cache:
        root = cache_root if cache_root is not None else cache_dir()
        path = root / "bound" / f"{_bound_key(sc, band, pts)}.json"
        if path.is_file():
            try:
                d = json.loads(path.read_text(encoding="utf-8"))
                return BoundSummary(**{**d, "cached": True})
            except (OSError, ValueError, TypeError):
                pass  # damaged: computed again and rewritten
    b = settling_bound(sc, pts, band=band, session=session)
    out = BoundSummary(b.t_settle, b.motion_time, b.replay_worst_settle, b.j_max, b.band,
                       len(pts), str(label), b.seconds)
    if path is not None:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            d = {k: v for k, v in out.__dict__.items() if k != "cached"}
            write_text(path, json.dumps(d, indent=1))
        except OSError:
            pass  # a read-only cache: computed again next time
    return out
