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
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .. import _engine
from ..plant import hermite_mid
from ..scenario import Scenario
from ..simulation.session import Session
from ..simulation.shaped_axis import ShaperSpec
from ..uncertainty import Perturbation

__all__ = ["ShapedObjective", "ShaperTuning", "robust_shaper"]


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
        Z = s.z_axis.samples(0, 1, k_end + 1)
        z, vz = Z[0], Z[1]
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
        _engine.adjoint_modes(self.h, np.ascontiguousarray(np.vstack(rows_f)), np.array(zeta),
                              np.array(gain), k_end, psi)
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
                  keep: int = 4) -> ShaperTuning:
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

    Returns
    -------
    ShaperTuning
    """
    if impulses not in (2, 3):
        raise ValueError(f"impulses must be 2 or 3, got {impulses!r}")
    t0 = time.perf_counter()
    pts = sc.uncertainty.tuning_set().points if points is None else tuple(points)
    obj = ShapedObjective(sc, session, profile, T_F, pts, band)
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
    return ShaperTuning(spec, est, float(amp.sum(axis=1).max()), T, obj.evaluations,
                        time.perf_counter() - t0, cands)
