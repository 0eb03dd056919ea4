"""Input shapers tuned for the worst case of an uncertainty set, on the time-varying plant.

A shaper convolves a profile p with impulses: Σ Aᵢ·p(t − dᵢ) (amplitudes ≥ 0
summing to 1: the same bounds as p, the same landing, a motion longer by the
last delay).  :func:`robust_shaper` designs one for a given base profile (JL or
DJL with its jerk times) so that the **worst-case settling time over the
tuning set** of the scenario's uncertainty is least.

The evaluation is exact for whole-sample delays: the plant is linear in its
input, so the state when the shaped reference ends is Σ Aᵢ·C(dᵢ), C(d) the
final state of the base profile delayed by d samples.  For a total delay D the
Z move is synchronised with the shaped motion (it depends on D only); the
plant's adjoint (``harness._engine.adjoint_modes``) gives the sensitivity of
the final state to every input sample, and one FFT correlation gives C(d) for
every d ≤ D at once, under every perturbation.  A design's worst-case settling
is estimated from its residual at each perturbation (the free oscillation's
decay into the band after the motion); the best designs are then re-measured
on the full record by the caller (:mod:`harness.recommend`).

The search: the last delay D over 0.3–1.6 damped periods of the tuned mode at
the end of the motion, the middle delay of a three-impulse shaper over 0.3–0.7
D, amplitudes on a grid of the simplex; coarse, then refined around the best.

:func:`optimal_shaper` goes further, on the *exact* settling time rather than
its estimate: the load error at every sample near the end of the motion is
linear in the amplitudes too (:meth:`ShapedObjective.window`: the final states
C(d) taken back through the inputs that follow each sample), so for a span D the
shaper whose error enters the band earliest at every point, over every delay
0..D at once, is a linear programme (solved here, :class:`_MinimaxLP`, with no
solver to import).  Up to 8 impulses (what the generator FMU takes); with
``signed``, amplitudes of either sign, the shaped profile's jerk, acceleration
and velocity then kept within the base's bounds on every sample.
:meth:`ShapedObjective.settling_times` evaluates a design exactly (the numbers
of :func:`harness.scoring.score_uncertainty`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..compiled import engine as _compiled_engine
from ..plant import hermite_mid, transitions
from ..scenario import Scenario
from ..simulation.session import Session
from ..simulation.shaped_axis import ShaperSpec
from ..uncertainty import Perturbation

__all__ = ["Quiet", "ShapedObjective", "ShapedWindow", "ShaperTuning", "optimal_shaper",
           "robust_shaper"]


def _patch(center: tuple[float, ...], radius: float = 0.06, step: float = 0.01) -> np.ndarray:
    """Simplex points within ``radius`` of ``center`` (each amplitude), on a grid of ``step``."""
    n = len(center)
    offs = np.arange(-radius, radius + step / 2, step)
    if n == 2:
        a2 = np.clip(center[1] + offs, 0.0, 1.0)
        return np.unique(np.vstack([1.0 - a2, a2]), axis=1)
    g2, g3 = np.meshgrid(center[1] + offs, center[2] + offs, indexing="ij")
    a2, a3 = g2.ravel(), g3.ravel()
    ok = (a2 >= -1e-12) & (a3 >= -1e-12) & (a2 + a3 <= 1.0 + 1e-12)
    a2, a3 = np.clip(a2[ok], 0.0, 1.0), np.clip(a3[ok], 0.0, 1.0)
    return np.vstack([np.clip(1.0 - a2 - a3, 0.0, 1.0), a2, a3])


def _simplex(n: int, step: float) -> np.ndarray:
    """Points of the (n−1)-simplex on a grid of ``step``: shape (n, G), columns sum to 1."""
    k = int(round(1.0 / step))
    if n == 1:
        return np.ones((1, 1))
    if n == 2:
        a = np.arange(k + 1) / k
        return np.vstack([1.0 - a, a])
    pts = [(i, j) for i in range(k + 1) for j in range(k + 1 - i)]
    a2 = np.array([p[0] for p in pts]) / k
    a3 = np.array([p[1] for p in pts]) / k
    return np.vstack([1.0 - a2 - a3, a2, a3])


@dataclass
class ShapedWindow:
    """The load error near the end of a shaped motion, per delay (:meth:`ShapedObjective.window`).

    Attributes
    ----------
    E : ndarray
        Shape (points, D + 1, k_end − k_w + 1): the load error (m) at the
        samples k_w..k_end of the base delayed by d samples, at each point.
    k_w, k_end : int
        The window's first sample and the shaped motion's end (samples from 0).
    T : float
        The shaped motion time (s).
    rest : bool
        The Z axis rests from ``k_end`` on (the plant is free after it).
    """

    E: np.ndarray
    k_w: int
    k_end: int
    T: float
    rest: bool


class ShapedObjective:
    """Worst-case settling of a base profile shaped by impulses, per design (exact residuals).

    Parameters
    ----------
    sc : Scenario
        A single-move scenario.
    session : Session
        Plans on its fast engine (:meth:`Session.fast`).
    profile : {"JL", "DJL"}
        The base profile.
    T_F : sequence of 4 float
        Its jerk times (s).
    points : sequence of Perturbation
        The uncertainty set to take the worst case over.
    band : float
        The settling band (m).
    """

    def __init__(self, sc: Scenario, session: Session, profile: str,
                 T_F: tuple[float, ...], points: tuple[Perturbation, ...], band: float) -> None:
        if not band > 0:
            raise ValueError(f"band must be > 0 m, got {band!r}")
        self.sc, self.s, self.points, self.band = sc, session.fast(), tuple(points), band
        self.Te = sc.simulation.Te
        self.h = sc.simulation.step
        if abs(self.h - self.Te) > 1e-12 * self.Te:
            raise ValueError("the shaper tuning needs the communication step equal to Te")
        self.params = self.s.move_params(sc, profile, T_F)
        self.T_base = self.s.axis.plan(self.params)
        self.modes = sc.modemap.scheduled()
        self.pivot = sc.z.z0 + 0.5 * sc.z.distance
        self._C: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray, float]] = {}
        self._u: np.ndarray | None = None
        self._fft: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        self._adjoint: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int,
                                       bool]] = {}
        self._window: dict[int, ShapedWindow] = {}
        self.T_F = tuple(float(t) for t in T_F)
        self._xs: np.ndarray | None = None
        tm = sc.modemap.tuned
        f_end = float(tm.f(sc.z.z0 + sc.z.distance))
        self.period = 1.0 / (f_end * math.sqrt(1.0 - tm.zeta ** 2))
        self.lead = self.period
        self.evaluations = 0

    def _base_fft(self, k_end: int, L: int) -> tuple[np.ndarray, np.ndarray]:
        """FFTs of the base's (a, j) over ``k_end`` samples, zero-padded to ``L``."""
        if self._u is None or self._u.shape[1] < k_end:
            self.s.axis.plan(self.params)
            self._u = self.s.axis.samples(0, 1, 2 * k_end + 1)[2:4]
            self._fft.clear()
        got = self._fft.get(L)
        if got is None:
            # the base is at rest past its end: its samples past k_end are 0 (or absent)
            a = self._u[0].copy()
            j = self._u[1].copy()
            got = (np.fft.rfft(a[:L], L), np.fft.rfft(j[:L], L))
            self._fft[L] = got
        return got

    def correlations(self, D: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
        """C(d) for d = 0..D, the shaped motion ``D`` samples longer than the base (cached).

        Returns
        -------
        C : ndarray
            Shape (rows, 2, D + 1): the final state (ε, ε̇) of each row (a mode
            under a perturbation) for the base delayed by d samples.
        sig, wd : ndarray
            σ and ω_d of each row at the end of the motion.
        T : float
            The shaped motion time (s).
        """
        got = self._C.get(D)
        if got is not None:
            return got
        sc, s = self.sc, self.s
        T = self.T_base + D * self.Te
        v_z, _ = s.z_velocity(sc, T)
        s.z_axis.plan(s.z_move_params(sc, v_z))
        k_end = int(math.ceil((sc.move.t_start + T) / self.h - 1e-9))
        Z = s.z_axis.samples(0, 1, k_end + 2)
        z, vz = Z[0, : k_end + 1], Z[1, : k_end + 1]
        zm = hermite_mid(z[:-1], vz[:-1], z[1:], vz[1:], self.h)
        z_end = np.array([z[k_end]])
        rows_f, zeta, gain, f_end = [], [], [], []
        for p in self.points:
            for m in self.modes:
                rows_f.append(p.frequencies(m.f_array, zm, self.pivot))
                zeta.append(p.zeta(m.zeta))
                gain.append(m.gain)
                f_end.append(float(p.frequencies(m.f_array, z_end, self.pivot)[0]))
        R = len(rows_f)
        psi = np.empty((R, k_end, 2, 2))
        _compiled_engine().adjoint_modes(self.h, np.ascontiguousarray(np.vstack(rows_f)),
                                         np.array(zeta), np.array(gain), k_end, psi)
        # C[r, i, d] = sum_k psi[r, k, i, :] . u[k - d]: a correlation, by FFT over k; the
        # base input is zero from the end of its motion on (before k_end - D), so no wrap
        # reaches the lags 0..D once L >= k_end + D + 1
        L = 1 << int(math.ceil(math.log2(k_end + D + 1)))
        Fa, Fj = self._base_fft(k_end, L)
        Pa = np.fft.rfft(psi[:, :, :, 0].transpose(0, 2, 1), L)  # (R, 2, L/2+1)
        Pj = np.fft.rfft(psi[:, :, :, 1].transpose(0, 2, 1), L)
        corr = np.fft.irfft(Pa * np.conj(Fa) + Pj * np.conj(Fj), L)
        C = corr[:, :, : D + 1]
        w = 2.0 * np.pi * np.array(f_end)
        z_arr = np.array(zeta)
        got = (C, z_arr * w, w * np.sqrt(1.0 - z_arr * z_arr), T)
        if len(self._C) >= 512:
            self._C.clear()
        self._C[D] = got
        if len(self._adjoint) >= 8:  # the window needs them: the last few spans only
            self._adjoint.pop(next(iter(self._adjoint)))
        rest = bool(vz[k_end] == 0.0) and bool(np.all(Z[1, k_end:] == 0.0))
        self._adjoint[D] = (psi, np.vstack(rows_f), z_arr, np.array(gain), k_end, rest)
        return got

    def residuals(self, amplitudes: np.ndarray, delays: tuple[int, ...]
                  ) -> tuple[np.ndarray, np.ndarray, float]:
        """Residual (m) of each mode at each point, for amplitude columns ``amplitudes``.

        Parameters
        ----------
        amplitudes : ndarray
            Shape (n, G): G designs with the same ``delays`` (samples, increasing from 0).
        delays : tuple of int
            The delays.

        Returns
        -------
        amp : ndarray
            Shape (points, modes, G).
        sig : ndarray
            σ of each row (points x modes).
        T : float
            The shaped motion time (s).
        """
        self.evaluations += amplitudes.shape[1]
        C, sig, wd, T = self.correlations(int(delays[-1]))
        M = C[:, :, list(delays)]  # (R, 2, n)
        final = np.einsum("rsn,ng->rsg", M, amplitudes)
        eps, deps = final[:, 0], final[:, 1]
        amp = np.hypot(eps, (deps + sig[:, None] * eps) / wd[:, None])
        return amp.reshape(len(self.points), len(self.modes), -1), sig, T

    def settling_estimates(self, amplitudes: np.ndarray, delays: list[tuple[int, ...]]
                           ) -> np.ndarray:
        """:meth:`settling_estimate` of every (delays, amplitude column) pair; one last delay.

        Returns
        -------
        ndarray
            Shape (len(delays), G).
        """
        D = int(delays[0][-1])
        if any(int(d[-1]) != D for d in delays):
            raise ValueError("the delays must share their last delay")
        self.evaluations += amplitudes.shape[1] * len(delays)
        C, sig, wd, T = self.correlations(D)
        idx = np.array(delays)  # (M, n)
        M = C[:, :, idx]  # (R, 2, M, n)
        final = np.einsum("rsmn,ng->rsmg", M, amplitudes)
        eps, deps = final[:, 0], final[:, 1]
        amp = np.hypot(eps, (deps + sig[:, None, None] * eps) / wd[:, None, None])
        nm = len(self.modes)
        amp = amp.reshape(len(self.points), nm, *amp.shape[1:])
        s = sig.reshape(len(self.points), nm)[:, :, None, None]
        over = np.log(np.maximum(amp * nm, self.band) / self.band)  # 0 inside the band
        with np.errstate(divide="ignore", invalid="ignore"):  # undamped: never settles
            need = np.where(over > 0, over / s, 0.0)
        return T + need.max(axis=1).max(axis=0)

    def settling_estimate(self, amplitudes: np.ndarray, delays: tuple[int, ...]) -> np.ndarray:
        """Worst-case settling (s, from the motion's start) of each design: estimate.

        The motion time plus, at the worst point, the time the modes' free
        oscillation takes to decay into the band (as
        :func:`harness.evaluation.profile_metrics` extends a record).
        """
        amp, sig, T = self.residuals(amplitudes, delays)
        nm = len(self.modes)
        s = sig.reshape(len(self.points), nm)[:, :, None]
        over = np.log(np.maximum(amp * nm, self.band) / self.band)  # 0 inside the band
        with np.errstate(divide="ignore", invalid="ignore"):  # undamped: never settles
            need = np.where(over > 0, over / s, 0.0)
        return T + need.max(axis=1).max(axis=0)

    # ---------------------------------------------------------- exact settling

    def _base(self, k_end: int) -> np.ndarray:
        """Return the base's x, v, a, j at the samples 0..``k_end`` (rows; at rest past its end)."""
        if self._xs is None or self._xs.shape[1] < k_end + 1:
            self.s.axis.plan(self.params)
            self._xs = self.s.axis.samples(0, 1, k_end + 1)[:4].copy()
        return self._xs[:, : k_end + 1]

    def _adjoint_of(self, D: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, int,
                                           bool]:
        """Return the adjoint of span ``D`` (computed again if it was dropped)."""
        got = self._adjoint.get(D)
        if got is None:
            self._C.pop(D, None)
            self.correlations(D)
            got = self._adjoint[D]
        return got

    def window(self, D: int) -> ShapedWindow:
        """Load error at every point, near the end of the motion, of the base delayed by d ≤ D.

        The plant being linear, the error of a design is Σ Aᵢ·E[:, dᵢ] on every
        sample of the window (from ``lead`` seconds before the base's end to the
        shaped motion's end).  The modal state at each window sample is the final
        state C(d) with the inputs after the sample removed (the adjoint's
        partial sums) and propagated back by the inverse one-step transitions.

        Parameters
        ----------
        D : int
            The span (samples): the shaped motion is ``D`` samples longer than the base.

        Returns
        -------
        ShapedWindow
        """
        got = self._window.get(D)
        if got is not None:
            return got
        C, _, _, T = self.correlations(D)
        psi, F, zeta, _, k_end, rest = self._adjoint_of(D)
        h = self.h
        k_w = max(0, k_end - D - max(1, int(math.ceil(self.lead / h))))
        W = k_end - k_w
        B = self._base(k_end)
        x0, target = self.sc.move.x0, self.sc.move.target

        def delayed(row: np.ndarray, before: float, idx: np.ndarray) -> np.ndarray:
            return np.concatenate([np.full(D, before), row])[idx]

        idx = np.arange(k_w, k_end + 1)[None, :] - np.arange(D + 1)[:, None] + D  # (D+1, W+1)
        xd = delayed(B[0], x0, idx) - target
        U = np.stack([delayed(B[2], 0.0, idx[:, :-1]), delayed(B[3], 0.0, idx[:, :-1])],
                     axis=1)  # (D+1, 2, W)
        R = psi.shape[0]
        # the inputs of samples j >= k, mapped to the final state: partial sums from the end
        ps = psi[:, k_w:k_end].transpose(1, 0, 2, 3).reshape(W, 2 * R, 2)
        contrib = np.matmul(ps, U.transpose(2, 1, 0)).reshape(W, R, 2, D + 1)
        part = np.zeros((W + 1, R, 2, D + 1))
        part[:W] = np.cumsum(contrib[::-1], axis=0)[::-1]
        # Φ(k_end, k)^-1 for every window sample k, every row
        phi = transitions(2.0 * np.pi * F[:, k_w:k_end], zeta[:, None], h)  # (R, W, 2, 2)
        det = phi[..., 0, 0] * phi[..., 1, 1] - phi[..., 0, 1] * phi[..., 1, 0]
        inv = np.empty_like(phi)
        inv[..., 0, 0], inv[..., 1, 1] = phi[..., 1, 1] / det, phi[..., 0, 0] / det
        inv[..., 0, 1], inv[..., 1, 0] = -phi[..., 0, 1] / det, -phi[..., 1, 0] / det
        back = np.empty((W + 1, R, 2, 2))
        back[W] = np.eye(2)
        for i in range(W - 1, -1, -1):
            back[i] = np.matmul(inv[:, i], back[i + 1])
        eps = np.matmul(back, C[None] - part)[:, :, 0, :]  # (W+1, R, D+1)
        P, nm = len(self.points), len(self.modes)
        E = eps.reshape(W + 1, P, nm, D + 1).sum(axis=2).transpose(1, 2, 0) + xd[None]
        got = ShapedWindow(E, k_w, k_end, T, rest)
        if len(self._window) >= 8:
            self._window.pop(next(iter(self._window)))
        self._window[D] = got
        return got

    def settling_times(self, amplitudes: np.ndarray, delays: list[tuple[int, ...]],
                       band: float | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Return the exact settling time of every design at every point (s, from the start).

        What :func:`harness.scoring.score_uncertainty` measures (the last exit
        from the band, interpolated between samples; the free oscillation after
        the motion stepped sample by sample while an exit can remain), computed
        from :meth:`window` and the final states.

        Parameters
        ----------
        amplitudes : ndarray
            Shape (n, G): G amplitude columns.
        delays : list of tuple of int
            M delay sets of n impulses sharing their last delay.
        band : float, optional
            The band (m); default the objective's.

        Returns
        -------
        worst : ndarray
            Shape (M, G): the worst over the points.
        each : ndarray
            Shape (points, M, G).  A design with no exit in the window gets the
            window's start (an upper bound).
        """
        D = int(delays[0][-1])
        if any(int(d[-1]) != D for d in delays):
            raise ValueError("the delays must share their last delay")
        band_in = (self.band if band is None else band) * (1.0 + 1e-9)
        win = self.window(D)
        C, sig, wd, _ = self.correlations(D)
        idx = np.array(delays)
        A = np.asarray(amplitudes, dtype=float)
        self.evaluations += A.shape[1] * len(delays)
        e = np.einsum("pmnk,ng->pmgk", win.E[:, idx, :], A)  # (P, M, G, W+1)
        P, nm = len(self.points), len(self.modes)
        fin = np.einsum("rsmn,ng->rmgs", C[:, :, idx], A)  # (R, M, G, 2)
        fin = fin.reshape(P, nm, *fin.shape[1:])
        s_, w_ = sig.reshape(P, nm), wd.reshape(P, nm)
        amp = np.hypot(fin[..., 0], (fin[..., 1] + s_[:, :, None, None] * fin[..., 0])
                       / w_[:, :, None, None])  # (P, nm, M, G)
        with np.errstate(divide="ignore", invalid="ignore"):
            need = np.where(amp * nm > band_in,
                            np.log(np.maximum(amp * nm, band_in) / band_in)
                            / s_[:, :, None, None], 0.0).max(axis=1)  # (P, M, G)
        never = ~np.isfinite(need) | (need > 3600.0)
        J = int(math.ceil(float(np.max(np.where(never, 0.0, need))) / self.h)) + 2
        tau = self.h * np.arange(1, J + 1)
        free = np.zeros((*e.shape[:3], J))
        for i in range(nm):
            e0, de0 = fin[:, i, ..., 0, None], fin[:, i, ..., 1, None]
            s1, w1 = s_[:, i, None, None, None], w_[:, i, None, None, None]
            free += np.exp(-s1 * tau) * (e0 * np.cos(w1 * tau)
                                         + (de0 + s1 * e0) / w1 * np.sin(w1 * tau))
        seq = np.abs(np.concatenate([e, free], axis=-1))
        out = seq > band_in
        n_all = seq.shape[-1]
        last = n_all - 1 - np.argmax(out[..., ::-1], axis=-1)
        last = np.minimum(last, n_all - 2)
        e0 = np.take_along_axis(seq, last[..., None], -1)[..., 0]
        e1 = np.take_along_axis(seq, last[..., None] + 1, -1)[..., 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            frac = np.where(e0 != e1, (e0 - band_in) / (e0 - e1), 1.0)
        t = (win.k_w + last + frac) * self.h - self.sc.move.t_start
        t = np.where(out.any(axis=-1), t, win.k_w * self.h - self.sc.move.t_start)
        t = np.where(never, math.inf, t)
        return t.max(axis=0), t

    def kinematics(self, D: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Return v, a and j at the samples 0..k_end of the base delayed by d ≤ D.

        Returns
        -------
        v, a, j : ndarray
            Shape (k_end + 1, D + 1) each: a design's are ``M @ A`` (its delays' columns).
        """
        k_end = self._adjoint_of(D)[4]
        B = self._base(k_end)
        idx = np.arange(k_end + 1)[:, None] - np.arange(D + 1)[None, :] + D
        v, a, j = (np.concatenate([np.zeros(D), B[r]])[idx] for r in (1, 2, 3))
        return v, a, j


@dataclass
class ShaperTuning:
    """The result of :func:`robust_shaper`.

    Attributes
    ----------
    shaper : ShaperSpec
        The design (delays in samples of Te).
    estimate : float
        Its estimated worst-case settling over the set (s, from the start).
    residual_worst : float
        Its largest residual over the set (m).
    motion_time : float
        The shaped motion time (s).
    evaluations : int
        Designs evaluated.
    seconds : float
        Time of the search.
    candidates : list of tuple
        The best designs met, ``(estimate, ShaperSpec)``, best first (for an
        exact re-measurement).
    """

    shaper: ShaperSpec
    estimate: float
    residual_worst: float
    motion_time: float
    evaluations: int
    seconds: float
    candidates: list[tuple[float, ShaperSpec]] = field(default_factory=list)


def robust_shaper(sc: Scenario, session: Session, profile: str, T_F: tuple[float, ...],
                  band: float, *, impulses: int = 3,
                  points: tuple[Perturbation, ...] | None = None,
                  keep: int = 4, objective: ShapedObjective | None = None) -> ShaperTuning:
    """Design the shaper of ``impulses`` impulses with the least worst-case settling time.

    Parameters
    ----------
    sc : Scenario
        A single-move scenario (its uncertainty gives the default tuning set).
    session : Session
        Plans the base profile and the Z move (fast engine).
    profile : {"JL", "DJL"}
        The base profile.
    T_F : tuple of float
        Its jerk times (s).
    band : float
        The settling band (m).
    impulses : {2, 3}
        Impulses of the shaper.
    points : tuple of Perturbation, optional
        The set minimised over (default ``sc.uncertainty.tuning_set()``).
    keep : int
        How many of the best designs to return in ``candidates``.
    objective : ShapedObjective, optional
        One already built for this base and set (its correlations are shared,
        e.g. by the two- and three-impulse searches and :func:`optimal_shaper`).

    Returns
    -------
    ShaperTuning
    """
    if impulses not in (2, 3):
        raise ValueError(f"impulses must be 2 or 3, got {impulses!r}")
    t0 = time.perf_counter()
    pts = sc.uncertainty.tuning_set().points if points is None else tuple(points)
    obj = objective if objective is not None else ShapedObjective(sc, session, profile, T_F,
                                                                  pts, band)
    ev0 = obj.evaluations
    tm = sc.modemap.tuned
    z_end = sc.z.z0 + sc.z.distance
    Td = 1.0 / (tm.f(z_end) * math.sqrt(1.0 - tm.zeta ** 2))
    n_d = max(4, int(round(Td / obj.Te)))
    best: list[tuple[float, tuple[float, ...], tuple[int, ...]]] = []

    def consider(delays: list[tuple[int, ...]], grid: np.ndarray) -> None:
        est = obj.settling_estimates(grid, delays)  # (M, G)
        flat = np.argsort(est, axis=None)[:keep]
        for f in flat:
            m, g = divmod(int(f), est.shape[1])
            best.append((float(est[m, g]), tuple(float(x) for x in grid[:, g]), delays[m]))

    def middles(D: int, step: int) -> list[int]:
        lo, hi = max(1, int(0.3 * D)), min(D - 1, int(math.ceil(0.7 * D)))
        return list(range(lo, hi + 1, step)) or [max(1, D // 2)]

    coarse = _simplex(impulses, 0.05)
    for D in range(max(2, int(0.3 * n_d)), int(1.6 * n_d) + 1, 4):
        if impulses == 2:
            consider([(0, D)], coarse)
        else:
            consider([(0, d2, D) for d2 in middles(D, 4)], coarse)
    best.sort(key=lambda x: x[0])
    # refine around the best few: every delay +/- 4 samples, amplitudes +/- 0.06 by 0.01
    seeds: dict[tuple[int, ...], tuple[float, ...]] = {}
    for _, A, delays in best:
        if delays not in seeds:
            seeds[delays] = A
        if len(seeds) == 3:
            break
    for delays, A in seeds.items():
        D0 = delays[-1]
        patch = _patch(A)
        for D in range(max(2, D0 - 4), D0 + 5):
            mids = [()] if impulses == 2 else [(d2,) for d2 in range(max(1, delays[1] - 4),
                                                                      min(D - 1, delays[1] + 4)
                                                                      + 1)]
            consider([(0, *mid, D) for mid in mids], patch)
    best.sort(key=lambda x: x[0])
    seen: set[tuple[Any, ...]] = set()
    cands: list[tuple[float, ShaperSpec]] = []
    for est, A, delays in best:
        key = (tuple(round(a, 6) for a in A), delays)
        if key in seen:
            continue
        seen.add(key)
        # amplitudes to 1e-6, the first one making the sum 1 exactly
        rest = [round(a / sum(A), 6) for a in A[1:]]
        spec = ShaperSpec((1.0 - sum(rest), *rest), delays, f"robust {impulses}-impulse")
        cands.append((est, spec))
        if len(cands) >= keep:
            break
    est, spec = cands[0]
    amp, _, T = obj.residuals(np.array(spec.amplitudes)[:, None], spec.delays)
    return ShaperTuning(spec, est, float(amp.sum(axis=1).max()), T, obj.evaluations - ev0,
                        time.perf_counter() - t0, cands)


class _MinimaxLP:
    """``min t`` s.t. ``B x − τ t ≤ c`` (rows added as it goes), ``Σ x = s0``, ``x ≥ 0``.

    Solved by a revised simplex on its dual, whose basis has ``n + 1``
    columns whatever the number of rows (the primal has few variables and
    many rows)::

        min c·y − s0 λ   s.t.   Bᵀy − λ·1 − s = 0,   τ·y = 1,   y, s ≥ 0,   λ free

    The primal solution is the dual's simplex multipliers: ``x = π[:n]``,
    ``t = −π[n]``.  Rows added after a solve are new dual columns: the basis
    stays feasible and the next solve starts from it.  An unbounded dual is
    an infeasible primal.

    Parameters
    ----------
    n : int
        Primal variables.
    s0 : float
        Their sum.
    """

    def __init__(self, n: int, s0: float) -> None:
        self.n, self.s0 = n, float(s0)
        self._B = np.empty((256, n))
        self._tau = np.empty(256)
        self._c = np.empty(256)
        self.m = 0
        self.basis: np.ndarray | None = None  # keys: y_i -> i; λ+ -> -1; λ- -> -2; s_j -> -3-j
        self.iterations = 0
        self.x = np.zeros(n)
        self.t = math.inf

    def add(self, B: np.ndarray, tau: float, c: np.ndarray | float) -> None:
        """Add the rows ``B x − tau·t ≤ c``."""
        B = np.atleast_2d(np.asarray(B, dtype=float))
        k = B.shape[0]
        if self.m + k > self._B.shape[0]:
            cap = max(2 * self._B.shape[0], self.m + k)
            self._B = np.vstack([self._B[: self.m], np.empty((cap - self.m, self.n))])
            self._tau = np.concatenate([self._tau[: self.m], np.empty(cap - self.m)])
            self._c = np.concatenate([self._c[: self.m], np.empty(cap - self.m)])
        self._B[self.m:self.m + k] = B
        self._tau[self.m:self.m + k] = tau
        self._c[self.m:self.m + k] = c
        self.m += k

    def _columns(self, keys: np.ndarray) -> np.ndarray:
        n = self.n
        M = np.zeros((n + 1, keys.size))
        y = keys >= 0
        M[:n, y] = self._B[keys[y]].T
        M[n, y] = self._tau[keys[y]]
        M[:n, keys == -1] = -1.0
        M[:n, keys == -2] = 1.0
        s = np.flatnonzero(keys <= -3)
        M[-3 - keys[s], s] = -1.0
        return M

    def _costs(self, keys: np.ndarray) -> np.ndarray:
        out = np.zeros(keys.size)
        y = keys >= 0
        out[y] = self._c[keys[y]]
        out[keys == -1] = -self.s0
        out[keys == -2] = self.s0
        return out

    def solve(self, max_iter: int | None = None) -> bool:
        """Optimise from the current basis; return False if infeasible or not converged."""
        n, m = self.n, self.m
        if self.basis is None:
            rows = np.flatnonzero(self._tau[:m] > 0)
            if rows.size == 0:
                return False
            # start from the single row whose dual value is best (y = that row alone)
            r = self._B[rows] / self._tau[rows, None]
            value = self._c[rows] / self._tau[rows] - self.s0 * r.min(axis=1)
            i0 = int(rows[np.argmin(value)])
            r0 = self._B[i0] / self._tau[i0]
            j0 = int(np.argmin(r0))
            self.basis = np.array([i0, -1 if r0[j0] >= 0 else -2]
                                  + [-3 - j for j in range(n) if j != j0])
        B, tau, c = self._B[:m], self._tau[:m], self._c[:m]
        keys = self.basis.copy()
        inv: np.ndarray | None = None
        fresh = 0
        degenerate = 0
        for _ in range(max_iter or 40 * (n + 1) + 400):
            if inv is None or fresh >= 40:  # the inverse afresh, then updated by each pivot
                try:
                    inv = np.linalg.inv(self._columns(keys))
                except np.linalg.LinAlgError:
                    return False
                fresh = 0
            xB = inv[:, n]  # the basis's values: inv @ (0, ..., 0, 1)
            pi = self._costs(keys) @ inv
            sp = float(pi[:n].sum())
            d = np.concatenate([c - B @ pi[:n] - tau * pi[n], [sp - self.s0, self.s0 - sp],
                                pi[:n]])
            pos = np.where(keys >= 0, keys, m - 1 - keys)
            d[pos] = np.inf  # the basic columns
            bland = degenerate > 30  # Bland's rule against cycling
            if bland:
                better = np.flatnonzero(d < -1e-9)
                if better.size == 0:
                    self.basis = keys
                    return self._done(pi)
                q = int(better[0])
            else:
                q = int(np.argmin(d))
                if d[q] >= -1e-9:
                    self.basis = keys
                    return self._done(pi)
            kq = q if q < m else m - 1 - q
            if kq >= 0:
                u = inv[:, :n] @ B[kq] + inv[:, n] * tau[kq]
            elif kq > -3:
                u = inv[:, :n].sum(axis=1) * (-1.0 if kq == -1 else 1.0)
            else:
                u = -inv[:, -3 - kq]
            ok = u > 1e-9
            if not ok.any():
                self.basis = keys
                return False  # the dual is unbounded: no x meets the rows
            with np.errstate(divide="ignore"):
                ratio = np.where(ok, np.maximum(xB, 0.0) / np.where(ok, u, 1.0), np.inf)
            th = float(ratio.min())
            ties = np.flatnonzero(ratio <= th + 1e-12)
            r = int(ties[np.argmin(pos[ties])]) if bland else int(ties[np.argmax(u[ties])])
            degenerate = degenerate + 1 if th <= 1e-12 else 0
            keys[r] = kq
            row = inv[r] / u[r]
            inv -= np.outer(u, row)
            inv[r] = row
            fresh += 1
            self.iterations += 1
        self.basis = keys
        return False

    def _done(self, pi: np.ndarray) -> bool:
        self.x = pi[: self.n].copy()
        self.t = float(-pi[self.n])
        return True


_POLYGON = 16
"""Sides of the polygon inside which the residual's phasor is kept (an inner approximation)."""


def _phasor_polygon(C: np.ndarray, sig: np.ndarray, wd: np.ndarray,
                    support: np.ndarray) -> np.ndarray:
    """Rows whose values bound a residual's phasor from inside: shape (rows, polygon, n)."""
    th = 2.0 * np.pi * np.arange(_POLYGON) / _POLYGON
    V0 = C[:, 0, support]
    V1 = (C[:, 1, support] + sig[:, None] * V0) / wd[:, None]
    return np.cos(th)[None, :, None] * V0[:, None] + np.sin(th)[None, :, None] * V1[:, None]


@dataclass
class Quiet:
    """Modes a design must leave quiet: each one's residual within its own bound.

    Attributes
    ----------
    objective : ShapedObjective
        The same base, planned on a scenario whose modes are the ones to keep
        quiet (:meth:`harness.tuning.graceful.UnmodelledModes.scenario`), at its points.
    bound : ndarray
        The most each row's residual may be (m): one per (point, mode) row of
        the objective, points first.
    """

    objective: ShapedObjective
    bound: np.ndarray

    def ratio(self, amplitudes: np.ndarray, delays: tuple[int, ...]) -> float:
        """Return the largest residual over its bound of a design (≤ 1: quiet)."""
        amp, _, _ = self.objective.residuals(np.asarray(amplitudes, float)[:, None], delays)
        return float(np.max(amp[..., 0].ravel() / self.bound))


def _lp_sweep(obj: ShapedObjective, D: int, support: np.ndarray, signed: bool, target: float,
              residual: float, limits: tuple[tuple[np.ndarray, float, float], ...],
              minimax: np.ndarray | None = None, deadlines: np.ndarray | None = None,
              quiet: Quiet | None = None) -> tuple[int, np.ndarray, float] | None:
    """Return the earliest settling sample reachable with impulses at ``support``, the design, t.

    The error at every point of ``minimax`` (default every point) is kept
    within ``target`` bands from sample m to the motion's end, the residual
    oscillation after it within ``residual`` bands (its phasor inside a
    polygon); m goes down four samples at a time, then one, each linear
    programme starting from the last success's basis, until it fails.  A point
    with a finite ``deadlines`` entry (s from the motion's start) keeps its
    error within ``target`` bands from that instant on whatever m: the window's
    samples from it, and its residual within ``residual`` bands grown by the
    decay from the motion's end to the deadline.  ``quiet``: the residual of
    other modes kept within a fraction of the band.  ``signed``: amplitudes in
    [−1, 1] (as ``x = A + 1 ≥ 0``), the kinematic ``limits`` (rows ``M @ A``
    within [lo, hi]) added where the solution breaks them.  Amplitudes at
    delays 0 and D are kept ≥ 0.001 (the span stays D).
    """
    C, sig, wd, T_end = obj.correlations(D)
    n = support.size
    shift = 1.0 if signed else 0.0
    lp = _MinimaxLP(n, 1.0 + shift * n)

    def rows(G: np.ndarray, tau: float, c: np.ndarray | float) -> None:
        # G A − tau t ≤ c with A = x − shift
        lp.add(G, tau, c + shift * G.sum(axis=1))

    P, nm = len(obj.points), len(obj.modes)
    mm = np.ones(P, bool) if minimax is None else np.asarray(minimax, bool)
    dl = np.full(P, math.inf) if deadlines is None else np.asarray(deadlines, float)
    cos_p = math.cos(math.pi / _POLYGON)
    poly = _phasor_polygon(C, sig, wd, support).reshape(P, nm, _POLYGON, n)
    scale = nm * target / (residual * obj.band * cos_p)
    rows(poly[mm].reshape(-1, n) * scale, 1.0, 0.0)
    ends = np.zeros((2, n))
    ends[0, 0] = ends[1, -1] = -1.0
    rows(ends, 0.0, -1e-3)
    if quiet is not None:
        Cq, sq, wq, _ = quiet.objective.correlations(D)
        q = _phasor_polygon(Cq, sq, wq, support) / (quiet.bound[:, None, None] * cos_p)
        rows(q.reshape(-1, n), 0.0, 1.0)
    win = None
    sig_p = sig.reshape(P, nm).min(axis=1)
    for p in np.flatnonzero(np.isfinite(dl)):
        grow = math.exp(float(sig_p[p]) * max(0.0, float(dl[p]) - T_end))
        rows(poly[p].reshape(-1, n) * nm / (residual * obj.band * cos_p * grow), 0.0, 1.0)
        k_p = int(math.ceil((float(dl[p]) + obj.sc.move.t_start) / obj.h - 1e-9))
        if win is None:
            win = obj.window(D)
        if k_p <= win.k_end:
            G = win.E[p, support, max(k_p, win.k_w) - win.k_w:].T / (obj.band * target)
            rows(np.vstack([G, -G]), 0.0, 1.0)
    # first the motion's end alone (every copy landed: the error is the modes' deflection),
    # from the final states: a span that cannot settle within the motion costs no window
    nm_rows = C[:, 0, support].reshape(P, nm, n).sum(axis=1)[mm] / obj.band
    rows(np.vstack([nm_rows, -nm_rows]), 1.0, 0.0)
    if not lp.solve() or lp.t > target:
        return None
    win = obj.window(D)
    best = None
    kept: set[tuple[int, float, int]] = set()  # the kinematic rows added (limit, side, sample)
    step, m, snap = 4, win.k_end, None
    while m - 1 > win.k_w:
        m_lo = max(m - step, win.k_w + 1)
        G = win.E[mm][:, support, m_lo - win.k_w: m - win.k_w] / obj.band  # samples m_lo..m-1
        G = G.transpose(2, 0, 1).reshape(-1, n)
        if step > 1:
            snap = (lp.m, None if lp.basis is None else lp.basis.copy(), set(kept))
        rows(np.vstack([G, -G]), 1.0, 0.0)
        ok = True
        while True:
            if not lp.solve():
                ok = False
                break
            if not signed:
                break
            A = lp.x - 1.0
            added = False
            for which, (M, low, high) in enumerate(limits):
                scale = max(abs(low), abs(high))
                val = M @ A
                for sign, bad in ((1.0, np.flatnonzero(val > high + 1e-9 * scale)),
                                  (-1.0, np.flatnonzero(val < low - 1e-9 * scale))):
                    bad = np.array([k for k in bad if (which, sign, int(k)) not in kept], int)
                    if bad.size:
                        k = bad[np.argsort(-sign * val[bad])[:16]]
                        kept.update((which, sign, int(i)) for i in k)
                        rows(sign * M[k] / scale, 0.0, (high if sign > 0 else -low) / scale)
                        added = True
            big = [int(i) for i in np.flatnonzero(np.abs(A) > 1.0 + 1e-9) if (-1, 0, i) not in kept]
            if big:
                kept.update((-1, 0, i) for i in big)
                unit = np.eye(n)[big]
                rows(np.vstack([unit, -unit]), 0.0, np.ones(2 * len(big)))
                added = True
            if not added:
                break
        if not ok or lp.t > target:
            if step == 1 or snap is None:
                return best
            lp.m, lp.basis, kept = snap  # back to the last success, then sample by sample
            step = 1
            continue
        m = m_lo
        best = (m, lp.x - shift, lp.t)
    return best


def optimal_shaper(sc: Scenario, session: Session, profile: str, T_F: tuple[float, ...],
                   band: float, *, spans: tuple[int, ...], signed: bool = False,
                   points: tuple[Perturbation, ...] | None = None, margin: float = 0.05,
                   residual: float | None = None, max_impulses: int = 8, keep: int = 4,
                   enough: int | None = None, objective: ShapedObjective | None = None,
                   minimax: np.ndarray | None = None, deadlines: np.ndarray | None = None,
                   quiet: Quiet | None = None) -> ShaperTuning:
    """Design the shaper of each span whose exact worst-case settling time is least (LP).

    For a span D (the last delay, in samples), every shaper with whole-sample
    delays 0..D is a linear combination of the delayed bases: the load error at
    every sample near the end (:meth:`ShapedObjective.window`) and the residual
    oscillation after the motion are linear in the amplitudes.  The earliest
    sample m from which the error can stay within ``(1 − margin)·band`` at every
    point of the set, the residual oscillation within ``residual·band``, is
    found by linear programmes (:class:`_MinimaxLP`), m going down sample by
    sample.  The margins keep the design robust between the points of the
    set: the exact settling time turns with the phase of the oscillation,
    which moves by about a radian between two points of the tuning set, and a
    design held exactly at the band on the points leaves it in between.  The
    design settles within the motion (after it, the residual is below the band):
    a span too short for that has none.

    The support is found in stages: every second delay, then the neighbours
    of the delays used, then the ``max_impulses`` largest impulses (0 and D
    always kept), each stage a sweep of its own.

    Parameters
    ----------
    sc : Scenario
        A single-move scenario.
    session : Session
        Plans the base profile and the Z move (fast engine).
    profile : {"JL", "DJL"}
        The base profile.
    T_F : tuple of float
        Its jerk times (s).
    band : float
        The settling band (m).
    spans : tuple of int
        The spans D to design for (samples).
    signed : bool
        Allow negative amplitudes (each in [−1, 1]).  The bounds of the base
        then no longer follow from the amplitudes: they are kept explicitly,
        on every sample of the shaped profile -- |j| no higher than the base's
        largest jerk, the acceleration within [−d_max, a_max] and the velocity
        within [0, v_max] (mirrored for a negative move): a jerk-limited,
        monotone reference.
    points : tuple of Perturbation, optional
        The set minimised over (default ``sc.uncertainty.tuning_set()``).
    margin : float
        The fraction of the band kept free at every point of the set, near the
        end of the motion.
    residual : float, optional
        The residual oscillation after the motion is kept within this fraction
        of the band at every point of the set (the free oscillation decays
        slowly: a residual above the band between two points of the set would
        leave it at a later crest).  Default ``1 − margin`` when the scenario's
        uncertainty has one range (its tuning set a grid whose neighbours are
        2.5 % apart), 0.65 when it has several (their box is represented by
        its corners: measured on X, a design held at 0.95 of the band there
        left it 0.24 s later at the middle of an edge of the box).
    max_impulses : int
        Most impulses of a design (the generator FMU's custom shaper takes 8).
    keep : int
        How many designs to return in ``candidates``.
    enough : int, optional
        Stop once this many spans (taken in increasing order) have a design.
    objective : ShapedObjective, optional
        One already built for this base and set (its caches are shared).
    minimax : ndarray of bool, optional
        The points (of ``points``) whose worst-case settling is minimised;
        default every point.
    deadlines : ndarray, optional
        Per point, an instant (s from the motion's start) from which its error
        must stay within the band whatever the rest (``inf``: none): the
        yardstick of a graceful design (:mod:`harness.tuning.graceful`).
    quiet : Quiet, optional
        Modes whose residual must stay within a fraction of the band (the
        unmodelled modes the design assumes).

    Returns
    -------
    ShaperTuning
        ``estimate`` is the exact worst-case settling time over the
        ``minimax`` points in the band itself (not the margin's);
        ``candidates`` one design per span that has one, best first.

    Raises
    ------
    ValueError
        If no span admits a design.
    """
    if not 0.0 <= margin < 1.0:
        raise ValueError(f"margin must be in [0, 1), got {margin!r}")
    if residual is None:
        residual = 1.0 - margin if sum(sc.uncertainty.active.values()) <= 1 else 0.65
    if not 0.0 < residual <= 1.0:
        raise ValueError(f"residual must be in (0, 1], got {residual!r}")
    if max_impulses < 2:
        raise ValueError(f"max_impulses must be >= 2, got {max_impulses!r}")
    t0 = time.perf_counter()
    pts = sc.uncertainty.tuning_set().points if points is None else tuple(points)
    obj = objective if objective is not None else ShapedObjective(sc, session, profile, T_F,
                                                                  pts, band)
    ev0 = obj.evaluations
    target = 1.0 - margin
    sgn = 1.0 if sc.move.distance >= 0 else -1.0
    m = sc.move
    name = "signed" if signed else "positive"
    found: list[tuple[float, ShaperSpec, float, float]] = []
    for D in sorted({int(d) for d in spans if int(d) >= 2}):
        if enough is not None and len(found) >= enough:
            break
        if not obj._adjoint_of(D)[5]:
            continue  # Z still moves after the motion: the free part is not the modes' own
        limits: tuple[tuple[np.ndarray, float, float], ...] = ()
        if signed:
            v, a, j = obj.kinematics(D)
            j_max = float(np.max(np.abs(j[:, 0])))
            lo_a, hi_a = (-m.d_max, m.a_max) if sgn > 0 else (-m.a_max, m.d_max)
            lo_v, hi_v = (0.0, m.v_max) if sgn > 0 else (-m.v_max, 0.0)
            limits = ((j, -j_max, j_max), (a, lo_a, hi_a), (v, lo_v, hi_v))

        def sweep(sup: np.ndarray, D: int = D,
                  limits: tuple[tuple[np.ndarray, float, float], ...] = limits
                  ) -> tuple[int, np.ndarray, float] | None:
            sub = tuple((M[:, sup], lo, hi) for M, lo, hi in limits)
            return _lp_sweep(obj, D, sup, signed, target, residual, sub, minimax, deadlines,
                             quiet)

        # every second delay, then the neighbours of those used, then the largest impulses
        sup = np.unique(np.r_[np.arange(0, D + 1, 2), D])
        got = sweep(sup)
        if got is None:
            continue
        used = sup[np.abs(got[1]) > 1e-9]
        near = np.unique(np.clip(np.r_[used - 1, used, used + 1, 0, D], 0, D))
        again = sweep(near)
        if again is not None:
            sup, got = near, again
        x = np.zeros(D + 1)
        x[sup] = got[1]
        order = [int(d) for d in np.argsort(-np.abs(x)) if abs(x[d]) > 1e-9 and d not in (0, D)]
        sup = np.array(sorted([0, *order[: max_impulses - 2], D]))
        got = sweep(sup)
        if got is None:
            continue
        A = got[1] if signed else np.maximum(got[1], 0.0)
        use = (np.abs(A) > 1e-9) | (sup == 0) | (sup == D)
        A, delays = A[use], tuple(int(d) for d in sup[use])
        rest = [float(a) for a in A[1:]]
        spec = ShaperSpec((1.0 - math.fsum(rest), *rest), delays,
                          f"robust {len(delays)}-impulse ({name}, LP)")
        amps = np.array(spec.amplitudes)
        if signed and any(np.max((M[:, list(delays)] @ amps - hi) / max(abs(lo), abs(hi))) > 1e-9
                          or np.min((M[:, list(delays)] @ amps - lo) / max(abs(lo), abs(hi)))
                          < -1e-9 for M, lo, hi in limits):
            continue  # the rounding of the sum broke a bound
        _, each = obj.settling_times(amps[:, None], [delays])
        amp, _, T = obj.residuals(amps[:, None], delays)
        on = slice(None) if minimax is None else np.asarray(minimax, bool)
        found.append((float(each[on, 0, 0].max()), spec, float(amp.sum(axis=1)[on].max()), T))
    if not found:
        raise ValueError(f"{sc.name}: no {name} shaper of span {sorted(spans)} samples settles "
                         f"within the motion at every point")
    found.sort(key=lambda f: f[0])
    est, spec, res, T = found[0]
    return ShaperTuning(spec, est, res, T, obj.evaluations - ev0, time.perf_counter() - t0,
                        [(f[0], f[1]) for f in found[:keep]])
