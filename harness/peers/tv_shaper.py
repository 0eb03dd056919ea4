"""A time-varying ZV input shaper: each impulse placed and weighted from the mode at that moment.

The idea is Chang & Park 2005, the time-varying input shaper cited as [12] by
Béarée & Olabi 2013: on a mode whose frequency changes during the motion
(here with the Z position, ``ω(t) = 2π f(z(t))``), the impulses of the shaper
follow the mode instead of being fixed at the values of one configuration.
The paper is not available here; what is implemented is derived below and in
``docs/peers.md`` ("A time-varying ZV shaper").

**Design.**  Read the reference acceleration as a train of impulses
``a(τ) dτ``.  On the mode ``ε'' + 2ζω(t) ε' + ω(t)² ε = -a(t)`` with ω slowly
varying, the free response to an impulse ``I`` at ``τ`` is, to first order
(WKB: write ``ε = exp(-∫ζω) u``, then ``u'' + ω_d(t)² u ≈ 0``, whose solutions
are ``ω_d^{-1/2} exp(±jΦ)``),

    ε(t) ≈ -I exp(-∫_τ^t ζω ds) sin(Φ(t) - Φ(τ)) / √(ω_d(τ) ω_d(t)),   Φ(t) = ∫ ω_d ds.

Two impulses ``A_1`` at ``τ`` and ``A_2`` at ``σ`` cancel for every later
``t`` when ``Φ(σ) - Φ(τ) = π`` (half a *local* damped period: the phase the
mode really accumulates in between) and
``A_2 / A_1 = exp(-∫_τ^σ ζω ds) √(ω_d(σ) / ω_d(τ))``.  With ζ constant,
``∫ ζω ds = ζ/√(1-ζ²) ∫ ω_d ds = ζπ/√(1-ζ²)``: the damping factor is the ZV
shaper's ``K`` whatever the drift, so

    A_2(τ) = K r / (1 + K r),  A_1(τ) = 1 - A_2(τ),  r = √(ω_d(σ(τ)) / ω_d(τ)),
    K = exp(-ζπ/√(1-ζ²)).

Each impulse ``a(τ) dτ`` is replaced by ``A_1(τ) a(τ) dτ`` at ``τ`` and
``A_2(τ) a(τ) dτ`` at ``σ(τ)``: the shaped acceleration is
``A_1(t) a(t) + A_2(τ) a(τ) / σ'(τ)`` with ``τ = σ⁻¹(t)``.  On a constant mode
``σ(τ) = τ + T_d/2`` and ``r = 1``: this is the ZV shaper exactly.  Rule
``"start"`` (for comparison) freezes the mode at the first impulse instead:
``σ = τ + π/ω_d(τ)``, ``A_2 = K/(1+K)`` (a ZV shaper re-tuned at each instant,
the phase error accumulated over the delay is not corrected).

**Implementation.**  :func:`shape_time_varying` maps a piecewise-jerk
reference piece by piece (pieces no longer than ``h_max``, by default the
generator's sample): on each piece ``[s, e)`` the first copy is weighted by
``1 - W`` and the second copy is the piece mapped linearly onto
``[σ(s), σ(e))`` and weighted by ``W``, ``W = A_2`` at mid-piece.  Each copy
then conserves the velocity change of its piece exactly, so the shaped
reference ends at rest; the result is again a
:class:`~harness.peers.trajectory.PiecewiseJerk` (exact position and velocity).
The linear map and the per-piece weight differ from the continuous design by
O(h²σ'') and O(h A_2'), about 1e-8 s and 1e-6 here.

**Position.**  Unlike a constant shaper, a time-varying one moves the
end point: the displacement of a rest-to-rest acceleration is ``-∫ t a dt``,
and the second copies add ``-∫ Δ(τ) A_2(τ) a(τ) dτ`` (``Δ = σ - τ``), which
is zero only when ``Δ A_2`` is constant (on the default scenario X, about
4 mm out of 0.4 m).  :func:`design_for_scenario` therefore plans the
unshaped reference for the distance that makes the *shaped* one end on the
target (a fixed-point iteration, converged to 1e-12 m), and, because the Z
move is synchronised with the shaped motion time which itself depends on
z(t), iterates on that time too.  On a constant mode no correction is needed
and none is made.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .context import PeerContext, PeerSpec
from .trajectory import PiecewiseJerk

__all__ = ["RULES", "TVDesign", "TimeVaryingZV", "design_for_scenario", "shape_time_varying",
           "z_of_t"]

RULES = ("phase", "start")
"""Rules of the time-varying ZV shaper: ``"phase"`` (default: Φ(σ) - Φ(τ) = π,
WKB-weighted amplitudes) or ``"start"`` (mode frozen at the first impulse)."""

_GL_X, _GL_W = np.polynomial.legendre.leggauss(4)


class TimeVaryingZV:
    """ZV shaper whose delay and amplitudes follow a mode ``f(t)``.

    Parameters
    ----------
    f_of_t : callable
        Mode frequency (Hz) as a function of time (s), vectorised over arrays.
    zeta : float
        Damping ratio of the mode, in [0, 1).
    t0, t1 : float
        Span of times (s) where the shaper is evaluated (impulse times, first
        and second, must lie in it).
    rule : {"phase", "start"}
        See the module notes.
    step : float, optional
        Step (s) of the tabulated phase Φ(t) (default: 1/200 of the shortest
        period over the span, at most 1 ms); the phase between table points is
        integrated by 4-point Gauss-Legendre from the nearest point.
    """

    def __init__(self, f_of_t: Callable[[np.ndarray], np.ndarray], zeta: float, t0: float,
                 t1: float, *, rule: str = "phase", step: float | None = None) -> None:
        if rule not in RULES:
            raise ValueError(f"unknown rule {rule!r}; choose from {RULES}")
        if not 0.0 <= zeta < 1.0:
            raise ValueError(f"damping ratio must be in [0, 1), got {zeta!r}")
        if not t1 > t0:
            raise ValueError(f"empty span [{t0}, {t1}]")
        self.f_of_t, self.zeta, self.rule = f_of_t, float(zeta), rule
        self.t0, self.t1 = float(t0), float(t1)
        self._sq = math.sqrt(1.0 - self.zeta ** 2)
        self.K = math.exp(-self.zeta * math.pi / self._sq)
        f_probe = np.asarray(f_of_t(np.linspace(t0, t1, 201)), dtype=float)
        if not np.all(f_probe > 0.0):
            raise ValueError("the mode frequency must stay > 0 over the span")
        if step is None:
            step = min(1e-3, 1.0 / (200.0 * float(f_probe.max())))
        n = max(1, int(math.ceil((self.t1 - self.t0) / step)))
        self._h = (self.t1 - self.t0) / n
        self._grid = self.t0 + self._h * np.arange(n + 1)
        self._phi = np.concatenate(([0.0], np.cumsum(self._integral(self._grid[:-1],
                                                                    self._grid[1:]))))

    @classmethod
    def constant(cls, f: float, zeta: float, t0: float, t1: float, *,
                 rule: str = "phase") -> TimeVaryingZV:
        """Return the shaper on a mode of constant frequency ``f`` (Hz): the ZV shaper."""
        return cls(lambda t: np.full(np.shape(t), float(f)), zeta, t0, t1, rule=rule)

    # ------------------------------------------------------------ the mode

    def omega_d(self, t: np.ndarray | float) -> np.ndarray:
        """Damped angular frequency of the mode at ``t`` (rad/s)."""
        f = np.asarray(self.f_of_t(np.asarray(t, dtype=float)), dtype=float)
        return 2.0 * math.pi * self._sq * f

    def _integral(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """∫_a^b ω_d dt, one 4-point Gauss-Legendre rule per interval."""
        a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
        half = 0.5 * (b - a)
        nodes = (0.5 * (a + b))[..., None] + half[..., None] * _GL_X
        return half * (self.omega_d(nodes) @ _GL_W)

    def phase(self, t: np.ndarray | float) -> np.ndarray:
        """Phase ``Φ(t) = ∫_{t0}^t ω_d ds`` of the mode (rad).

        Raises
        ------
        ValueError
            If a time lies outside the span ``[t0, t1]``.
        """
        t = np.asarray(t, dtype=float)
        tol = 1e-12 * max(1.0, abs(self.t1))
        if np.any(t < self.t0 - tol) or np.any(t > self.t1 + tol):
            raise ValueError(f"time outside the shaper's span [{self.t0:g}, {self.t1:g}] s")
        k = np.clip(np.rint((t - self.t0) / self._h).astype(int), 0, self._grid.size - 1)
        return self._phi[k] + self._integral(self._grid[k], t)

    # ------------------------------------------------------------ the shaper

    def second_time(self, tau: np.ndarray | float) -> np.ndarray:
        """Time ``σ(τ)`` of the second impulse for a first impulse at ``τ`` (s)."""
        tau = np.asarray(tau, dtype=float)
        w0 = self.omega_d(tau)
        sigma = tau + math.pi / w0
        if self.rule == "start":
            return sigma
        target = self.phase(tau) + math.pi
        for _ in range(30):  # Newton on Φ(σ) = Φ(τ) + π (Φ' = ω_d > 0)
            step = (self.phase(sigma) - target) / self.omega_d(sigma)
            sigma = sigma - step
            if np.all(np.abs(step) <= 1e-15 * np.maximum(1.0, np.abs(sigma))):
                break
        return sigma

    def delay(self, tau: np.ndarray | float) -> np.ndarray:
        """Delay ``Δ(τ) = σ(τ) - τ`` of the second impulse (s)."""
        tau = np.asarray(tau, dtype=float)
        return self.second_time(tau) - tau

    def amplitudes(self, tau: np.ndarray | float,
                   sigma: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Amplitudes ``(A_1, A_2)`` of the two impulses for a first impulse at ``τ``.

        ``sigma`` (the second impulse times) may be given to save their computation.
        """
        tau = np.asarray(tau, dtype=float)
        if self.rule == "start":
            A2 = np.full(tau.shape, self.K / (1.0 + self.K))
        else:
            sigma = self.second_time(tau) if sigma is None else sigma
            kr = self.K * np.sqrt(self.omega_d(sigma) / self.omega_d(tau))
            A2 = kr / (1.0 + kr)
        return 1.0 - A2, A2


def _integrate(tb: np.ndarray, a: np.ndarray, j: np.ndarray, x0: float,
               v0: float) -> tuple[np.ndarray, np.ndarray]:
    """Position and velocity at the breakpoints of a piecewise-linear acceleration."""
    h = np.diff(tb)
    a_, j_ = a[:-1], j[:-1]
    v = v0 + np.concatenate(([0.0], np.cumsum(a_ * h + j_ * h * h / 2)))
    x = x0 + np.concatenate(([0.0], np.cumsum(v[:-1] * h + a_ * h * h / 2
                                              + j_ * h ** 3 / 6)))
    return x, v


def _pieces(motion: PiecewiseJerk, h_max: float
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Pieces of the motion where it accelerates, none longer than ``h_max``.

    Returns starts, ends, acceleration at each start and jerk (arrays).
    """
    tb = motion.tb
    s, e = tb[:-1], tb[1:]
    act = (motion.a[:-1] != 0.0) | (motion.j[:-1] != 0.0)
    s, e = s[act], e[act]
    n = np.maximum(1, np.ceil((e - s) / h_max - 1e-9).astype(int))
    starts = np.concatenate([np.linspace(a, b, k + 1)[:-1] for a, b, k in
                             zip(s, e, n, strict=True)]) if s.size else np.zeros(0)
    ends = np.concatenate([np.linspace(a, b, k + 1)[1:] for a, b, k in
                           zip(s, e, n, strict=True)]) if s.size else np.zeros(0)
    if s.size:  # exact piece ends (linspace's last point is b already)
        _, _, a0, j0 = motion.evaluate(starts, side="right")
    else:
        a0 = j0 = np.zeros(0)
    return starts, ends, a0, j0


def _copy_values(u: np.ndarray, start: np.ndarray, end: np.ndarray, a: np.ndarray,
                 j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Acceleration just after ``u`` and jerk there of a sum of disjoint sorted pieces."""
    i = np.searchsorted(start, u, side="right") - 1
    ic = np.clip(i, 0, max(start.size - 1, 0))
    inside = (i >= 0) & (u < end[ic]) if start.size else np.zeros(u.shape, dtype=bool)
    av = np.where(inside, a[ic] + j[ic] * (u - start[ic]), 0.0) if start.size else np.zeros(
        u.shape)
    jv = np.where(inside, j[ic], 0.0) if start.size else np.zeros(u.shape)
    return av, jv


def shape_time_varying(motion: PiecewiseJerk, shaper: TimeVaryingZV, *, h_max: float = 1e-3,
                       name: str | None = None, merge_tol: float = 1e-12) -> PiecewiseJerk:
    """Apply the time-varying ZV shaper to a piecewise-jerk reference.

    Parameters
    ----------
    motion : PiecewiseJerk
        Reference to shape, at rest before and after its motion.
    shaper : TimeVaryingZV
        Its span must cover the motion and the second impulses.
    h_max : float
        Longest piece mapped at once (s); the generator's sample by default.
    name : str, optional
        Label (default ``"<motion>*TV-ZV"``).
    merge_tol : float
        Breakpoints closer than ``merge_tol * max(1, |t|)`` are merged.

    Returns
    -------
    PiecewiseJerk
        The shaped reference (exact piecewise-jerk; see the module notes for
        its end point).

    Raises
    ------
    ValueError
        If the second impulse times are not increasing (a mode changing too
        fast for the design), or a time falls outside the shaper's span.
    """
    if not h_max > 0.0:
        raise ValueError(f"h_max must be positive, got {h_max!r}")
    s, e, a, j = _pieces(motion, h_max)
    label = name or f"{motion.name}*TV-ZV"
    if s.size == 0:
        return PiecewiseJerk(motion.tb[:1], motion.x[:1], motion.v[:1], np.zeros(1),
                             np.zeros(1), name=label, params=dict(motion.params))
    # σ at every piece edge (each interior edge is shared: one value)
    edges = np.unique(np.concatenate((s, e)))
    sig_e = shaper.second_time(edges)
    s2 = sig_e[np.searchsorted(edges, s)]
    e2 = sig_e[np.searchsorted(edges, e)]
    c = (e2 - s2) / (e - s)
    if np.any(c <= 0.0) or np.any(np.diff(sig_e) <= 0.0):
        raise ValueError("the second impulse times are not increasing: the mode changes too "
                         "fast for a time-varying ZV shaper")
    mid = 0.5 * (s + e)
    _, W = shaper.amplitudes(mid)
    a1, j1 = (1.0 - W) * a, (1.0 - W) * j
    a2, j2 = W * a / c, W * j / (c * c)
    u = np.unique(np.concatenate((s, e, s2, e2)))
    scale = np.maximum(1.0, np.abs(u))
    new = np.ones(u.size, dtype=bool)
    new[1:] = np.diff(u) > merge_tol * scale[1:]
    starts = np.flatnonzero(new)
    last = np.r_[starts[1:] - 1, u.size - 1]
    t_keep, t_eval = u[starts], u[last]
    av1, jv1 = _copy_values(t_eval, s, e, a1, j1)
    av2, jv2 = _copy_values(t_eval, s2, e2, a2, j2)
    acc, jerk = av1 + av2, jv1 + jv2
    acc[-1] = jerk[-1] = 0.0
    x0 = float(motion.evaluate(t_keep[0])[0][0])
    v0 = float(motion.evaluate(t_keep[0])[1][0])
    x, v = _integrate(t_keep, acc, jerk, x0, v0)
    params = dict(motion.params)
    params.update({"shaper": "TV-ZV", "shaper_rule": shaper.rule, "shaper_zeta": shaper.zeta})
    return PiecewiseJerk(t_keep, x, v, acc, jerk, name=label, params=params)


def z_of_t(zs: Any, t: np.ndarray) -> np.ndarray:
    """Z position at the times ``t`` from generator samples (piecewise-cubic, exact).

    Parameters
    ----------
    zs : harness.simulation.axis.MoveSamples
        The Z move sampled at every generator sample (``t, x, v, a, j``).
    t : ndarray
        Times (s); after the last sample the position is extrapolated with the
        last sample's state (at rest once the move is over).
    """
    t = np.asarray(t, dtype=float)
    T0, Te = float(zs.t[0]), float(zs.t[1] - zs.t[0])
    k = np.clip(np.floor((t - T0) / Te + 1e-9).astype(int), 0, zs.t.size - 1)
    tau = t - zs.t[k]
    return zs.x[k] + zs.v[k] * tau + zs.a[k] * tau ** 2 / 2 + zs.j[k] * tau ** 3 / 6


@dataclass
class TVDesign:
    """A time-varying ZV shaper designed for a scenario (:func:`design_for_scenario`).

    Attributes
    ----------
    motion : PiecewiseJerk
        The shaped reference.
    base : PiecewiseJerk
        The unshaped reference it was made from (planned for ``base_distance``).
    shaper : TimeVaryingZV
        The shaper, on the mode along the Z move synchronised with ``motion``.
    base_distance : float
        Distance the unshaped reference was planned for (m).
    distance_correction : float
        ``base_distance`` minus the move's distance (m): what the time-varying
        delays would otherwise add to the travel.
    iterations : int
        Fixed-point iterations used.
    sync_mismatch : float
        Change of the shaped motion time in the last iteration (s); 0 when
        the Z move used in the design is exactly the one simulated.
    """

    motion: PiecewiseJerk
    base: PiecewiseJerk
    shaper: TimeVaryingZV
    base_distance: float
    distance_correction: float
    iterations: int
    sync_mismatch: float


def design_for_scenario(sc: Any, session: Any, base: Callable[[float], PiecewiseJerk], *,
                        name: str = "TV-ZV", rule: str = "phase", max_iter: int = 40,
                        tol: float = 1e-12) -> TVDesign:
    """Time-varying ZV shaper on the scenario's tuned mode along its Z move.

    The frequency is ``f(z(t))`` of the tuned mode with ``z(t)`` the Z move of
    the scenario synchronised with the *shaped* motion (as the co-simulation
    runs it), and the unshaped reference is planned for the distance that puts
    the shaped one on the target; both by fixed-point iteration (see the
    module notes).

    Parameters
    ----------
    sc : harness.scenario.Scenario
    session : harness.simulation.session.Session
        Its Z axis plans the synchronised Z move.
    base : callable
        ``base(distance) -> PiecewiseJerk``: the unshaped reference (e.g. the
        generator's AL or JL profile) for a given signed distance.
    name : str
        Label of the shaped reference.
    rule : {"phase", "start"}
        Rule of :class:`TimeVaryingZV`.
    max_iter : int
        Largest number of iterations.
    tol : float
        Tolerance on the end point (relative to max(1 m, |distance|)) and on
        the motion time (s).

    Returns
    -------
    TVDesign
    """
    mode = sc.modemap.tuned
    zeta = float(mode.zeta)
    D = float(sc.move.distance)
    Te = float(sc.simulation.Te)
    z_lo, z_hi = sorted((sc.z.z0, sc.z.z0 + sc.z.distance))
    f_min = float(np.min(mode.f_array(np.linspace(z_lo, z_hi, 201))))
    corr = 0.0
    ref = base(D)
    T = ref.motion_time + 0.5 / (f_min * math.sqrt(1 - zeta ** 2))
    mot: PiecewiseJerk | None = None
    shaper: TimeVaryingZV | None = None
    mismatch = math.inf
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007 - the count is reported
        ref = base(D + corr)
        v_z, _ = session.z_velocity(sc, T)
        t1 = ref.t_end + 2.0 / f_min + 2 * Te
        zp = session.z_move_params(sc, v_z)
        T_z = session.z_axis.plan(zp)
        zs = session.z_axis.sample(zp, t_stop=Te * math.ceil(
            max(t1, sc.move.t_start + T_z) / Te + 1.0))
        shaper = TimeVaryingZV(lambda t, zs=zs: mode.f_array(z_of_t(zs, t)), zeta,
                               ref.t_start, t1, rule=rule)
        mot = shape_time_varying(ref, shaper, h_max=Te, name=name)
        err = mot.distance - D
        mismatch = mot.motion_time - T
        if abs(err) <= tol * max(1.0, abs(D)) and abs(mismatch) <= tol:
            break
        corr -= err
        T = mot.motion_time
    else:
        # not converged: ``ref`` and ``corr`` must still describe ``mot``
        corr += err
    assert mot is not None and shaper is not None
    return TVDesign(mot, ref, shaper, D + corr, corr, it, mismatch)


def build_tv_shaped(ctx: PeerContext, name: str) -> tuple[PiecewiseJerk, PeerSpec]:
    """Peers "AL*TV-ZV", "JL*TV-ZV": a time-varying ZV shaper along the synchronised Z move."""
    prof = name[:2]
    des = design_for_scenario(ctx.sc, ctx.session, lambda d: ctx.base(prof, d), name=name)
    sh = des.shaper
    d0 = float(sh.delay(des.base.t_start)[()])
    d1 = float(sh.delay(des.base.t_end)[()])
    jl_txt = f"JL T_F {ctx.T_F_JL * 1e3:.0f} ms; " if prof == "JL" else ""
    return des.motion, PeerSpec(
        name, f"{jl_txt}tuned mode f(z(t)) along the synchronised Z move, zeta = "
              f"{ctx.zeta:g}; delay {d0 * 1e3:.1f} -> {d1 * 1e3:.1f} ms; {prof} planned for "
              f"{des.distance_correction * 1e3:+.3g} mm so that the shaped move ends "
              "on the target",
        {"zeta": ctx.zeta, "rule": sh.rule, "delay_start": d0, "delay_end": d1,
         "distance_correction": des.distance_correction,
         "iterations": des.iterations, "sync_mismatch": des.sync_mismatch})
