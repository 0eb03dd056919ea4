"""Input shaper designs (ZV, ZVD, MZV, EI): impulse amplitudes and times.

An input shaper is a sequence of impulses ``A_i`` at times ``t_i`` with
``sum A_i = 1``; the shaped reference is ``q*(t) = sum_i A_i q(t - t_i)``
(Béarée 2014 §4.1, eq. 20-21).  Against a mode ``ω, ζ``
(``ω_d = ω √(1-ζ²)``, damped period ``T_d = 2π/ω_d``) its residual vibration is

    V(ω, ζ) = exp(-ζω t_N) |sum_i A_i exp(ζω t_i) exp(j ω_d t_i)|

times that of the unshaped reference (the percentage vibration of Singer &
Seering 1990; ``|F(p) exp(p t_N)|`` with ``F`` the shaper's transfer function
and ``p = -ζω + jω_d`` the mode pole).  Both amplitudes are taken at the end
of their own motion (the shaped one ends ``t_N`` later); at the same instant
the ratio is ``exp(ζω t_N)`` times larger.

Shapers (``K = exp(-ζπ/√(1-ζ²))``):

* ZV  (Béarée 2014 eq. 20): ``A = [1, K] / (1 + K)``, ``t = [0, T_d/2]``;
  zero residual at the tuned mode, adds half a damped period.
* ZVD: ``A = [1, 2K, K²] / (1 + K)²``, ``t = [0, T_d/2, T_d]``; also a zero
  derivative of V in ω (more robust), adds a full damped period.
* MZV: three impulses spaced by ``3 T_d / 8`` (phase 3π/4),
  ``A ∝ [1 - 1/√2, (√2 - 1) K', (1 - 1/√2) K'²]`` with
  ``K' = exp(-0.75 ζπ/√(1-ζ²))``; zero residual, adds ``3 T_d / 4``
  (between ZV and ZVD in robustness and length).
* SI (specified insensitivity, Singhose, Seering & Singer 1996; :func:`si_shaper`):
  three impulses, V <= 5 % over a stated band of frequencies, as short as that
  allows;
* EI (extra-insensitive, Singhose et al. 1994): three impulses; the residual
  at the tuned mode is the tolerance ``V_tol`` (5 % by default), not zero,
  with a local maximum there and zeros on either side, which widens the band
  where ``V <= V_tol``.  Undamped: ``A = [(1+V)/4, (1-V)/2, (1+V)/4]``,
  ``t = [0, T/2, T]``; with damping the seven design equations (unit sum,
  V = V_tol and dV/dω = 0 at ω, zero residual at two unknown frequencies)
  are solved numerically from the undamped solution (by continuation in ζ,
  for ζ <= 0.3: above, the two zeros merge and the design degenerates).

The shaper itself (impulses, transfer function, sensitivity curve) needs neither
the FMU nor a plant: the harness's lower layers use it (the recommendation's
shaper candidates); :mod:`harness.peers.shapers` convolves it with a profile.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["SHAPERS", "V_TOL", "Shaper", "band_vibration", "ei", "make_shaper", "mzv",
           "si_shaper", "zv", "zvd"]

SHAPERS = ("ZV", "ZVD", "MZV", "EI")


@dataclass(frozen=True)
class Shaper:
    """A sequence of impulses tuned to one mode.

    Attributes
    ----------
    name : str
    A : ndarray
        Impulse amplitudes (sum 1).
    t : ndarray
        Impulse times (s), ``t[0] = 0``.
    f, zeta : float
        Mode the shaper is tuned to (Hz, damping ratio).
    """

    name: str
    A: np.ndarray
    t: np.ndarray
    f: float
    zeta: float

    @property
    def duration(self) -> float:
        """Time the shaper adds to a motion (s): its last impulse time."""
        return float(self.t[-1])

    def transfer(self, s: complex | np.ndarray) -> complex | np.ndarray:
        """``F(s) = sum A_i exp(-s t_i)`` (eq. 21)."""
        s = np.asarray(s)
        return np.sum(self.A * np.exp(-np.multiply.outer(s, self.t)), axis=-1)

    def residual_ratio(self, f: float | np.ndarray, zeta: float | None = None
                       ) -> float | np.ndarray:
        """Percentage vibration ``V(ω, ζ)`` (fraction) on a mode ``f``, ``zeta``.

        Residual of the shaped motion at its end over that of the unshaped one
        at its end.  ``zeta`` defaults to the design damping.
        """
        zeta = self.zeta if zeta is None else zeta
        omega = 2 * np.pi * np.asarray(f, dtype=float)
        p = -zeta * omega + 1j * omega * np.sqrt(1 - zeta ** 2)
        # |F(p)| = |sum A_i exp(-p t_i)|, referred to the time of the last impulse
        val = np.abs(self.transfer(p) * np.exp(p * self.t[-1]))
        return float(val) if np.ndim(val) == 0 else val

    def quantized(self, Te: float) -> Shaper:
        """Return the same impulses with each time rounded to the nearest multiple of ``Te``."""
        return Shaper(self.name, self.A.copy(), np.round(self.t / Te) * Te, self.f, self.zeta)

    def plot(self, title: str | None = None):
        """Impulses and the sensitivity curve V(f) around the tuned mode; return the Figure."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(10, 3.5))
        ax1.stem(1e3 * self.t, self.A)
        ax1.set_xlabel("t [ms]")
        ax1.set_ylabel("impulse amplitude")
        f = self.f * np.linspace(0.3, 1.7, 400)
        ax2.plot(f / self.f, 100 * self.residual_ratio(f))
        ax2.set_xlabel("f / f_tuned")
        ax2.set_ylabel("residual [% of unshaped]")
        for ax in (ax1, ax2):
            ax.grid(True, alpha=0.3)
        fig.suptitle(title or f"{self.name} shaper, {self.f:g} Hz, ζ = {self.zeta:g}")
        fig.tight_layout()
        return fig


def _check_mode(f: float, zeta: float) -> tuple[float, float]:
    if not f > 0.0:
        raise ValueError(f"mode frequency must be positive, got {f!r}")
    if not 0.0 <= zeta < 1.0:
        raise ValueError(f"damping ratio must be in [0, 1), got {zeta!r}")
    sq = np.sqrt(1.0 - zeta ** 2)
    return 1.0 / (f * sq), sq  # damped period, sqrt(1 - zeta^2)


def zv(f: float, zeta: float = 0.0) -> Shaper:
    """Zero-vibration shaper (Béarée 2014 eq. 20)."""
    Td, sq = _check_mode(f, zeta)
    K = np.exp(-zeta * np.pi / sq)
    return Shaper("ZV", np.array([1.0, K]) / (1 + K), np.array([0.0, Td / 2]), f, zeta)


def zvd(f: float, zeta: float = 0.0) -> Shaper:
    """Zero-vibration-and-derivative shaper."""
    Td, sq = _check_mode(f, zeta)
    K = np.exp(-zeta * np.pi / sq)
    return Shaper("ZVD", np.array([1.0, 2 * K, K * K]) / (1 + K) ** 2,
                  np.array([0.0, Td / 2, Td]), f, zeta)


def mzv(f: float, zeta: float = 0.0) -> Shaper:
    """Three-impulse shaper with 3π/4 spacing ("modified ZV")."""
    Td, sq = _check_mode(f, zeta)
    K = np.exp(-0.75 * zeta * np.pi / sq)
    a1 = 1.0 - 1.0 / np.sqrt(2.0)
    A = np.array([a1, (np.sqrt(2.0) - 1.0) * K, a1 * K * K])
    return Shaper("MZV", A / A.sum(), np.array([0.0, 0.375 * Td, 0.75 * Td]), f, zeta)


@functools.lru_cache(maxsize=64)
def ei(f: float, zeta: float = 0.0, V_tol: float = 0.05) -> Shaper:
    """Extra-insensitive shaper with tolerance ``V_tol`` (residual V_tol at the tuned mode)."""
    Td, _ = _check_mode(f, zeta)
    if not 0.0 < V_tol < 1.0:
        raise ValueError(f"V_tol must be in (0, 1), got {V_tol!r}")
    if zeta > 0.3:
        raise ValueError(f"the EI design is solved for zeta <= 0.3 only, got {zeta!r}")
    A0 = np.array([(1 + V_tol) / 4, (1 - V_tol) / 2, (1 + V_tol) / 4])
    t0 = np.array([0.0, Td / 2, Td])
    if zeta == 0.0:
        return Shaper("EI", A0, t0, f, zeta)
    from scipy.optimize import fsolve  # deferred: scipy is heavy to import

    omega = 2 * np.pi * f
    sq = np.sqrt(1 - zeta ** 2)
    p0 = -zeta * omega + 1j * omega * sq

    def resid_complex(A: np.ndarray, t: np.ndarray, w: float) -> complex:
        p = -zeta * w + 1j * w * sq
        return complex(np.sum(A * np.exp(-p * (t - t[-1]))))

    def eqs(z: np.ndarray) -> np.ndarray:
        A = z[:3]
        t = np.r_[0.0, z[3:5] / omega]
        zl, zh = resid_complex(A, t, z[5] * omega), resid_complex(A, t, z[6] * omega)
        # V(w) = |S(w)|, S(w) = sum A_i exp(-p(w) (t_i - t_N)); dV/dw = Re(conj(S) dS/dw) / V
        dp = -zeta + 1j * sq
        e = A * np.exp(-p0 * (t - t[-1]))
        S = np.sum(e)
        dS = np.sum(-dp * (t - t[-1]) * e)
        return np.array([A.sum() - 1.0, abs(S) - V_tol, (np.conj(S) * dS).real * omega,
                         zl.real, zl.imag, zh.real, zh.imag])

    # start from the undamped solution, whose zeros are at cos(w T/2) = -(1 - V)/(1 + V),
    # and follow the damping up (continuation) when it is large
    c = np.arccos(-(1 - V_tol) / (1 + V_tol))
    z = np.r_[A0, np.pi, 2 * np.pi, c / np.pi, 2 - c / np.pi]
    n_steps = max(1, int(np.ceil(zeta / 0.02)))
    target = zeta
    for k in range(1, n_steps + 1):
        zeta = target * k / n_steps
        sq = np.sqrt(1 - zeta ** 2)
        p0 = -zeta * omega + 1j * omega * sq
        z, _, ok, msg = fsolve(eqs, z, full_output=True, xtol=1e-13)
    if ok != 1 or np.max(np.abs(eqs(z))) > 1e-9:
        raise RuntimeError(f"EI shaper design did not converge for f={f}, zeta={target}: {msg}")
    return Shaper("EI", z[:3], np.r_[0.0, z[3:5] / omega], f, target)


def make_shaper(name: str, f: float, zeta: float = 0.0, **kw: Any) -> Shaper:
    """Shaper by name (``"ZV"``, ``"ZVD"``, ``"MZV"``, ``"EI"``)."""
    try:
        fn = {"ZV": zv, "ZVD": zvd, "MZV": mzv, "EI": ei}[name.upper()]
    except KeyError:
        raise ValueError(f"unknown shaper {name!r}; choose from {SHAPERS}") from None
    return fn(f, zeta, **kw)


# ------------------------------------------------ specified insensitivity

V_TOL = 0.05
"""The vibration tolerance of the SI shaper: V(f) ≤ 5 % over the band."""


def _best_at(t3: float, A: np.ndarray, ratios: np.ndarray, freqs: np.ndarray,
             zeta: float) -> tuple[float, np.ndarray, np.ndarray]:
    """Return the best (least worst V over ``freqs``) design of total delay ``t3``.

    V(f) = |A₁ e^{−σ t₃} + A₂ e^{σ (t₂ − t₃) + iω_d t₂} + A₃ e^{iω_d t₃}|, over the
    amplitude grid ``A`` (G, 3) and the middle delays ``ratios * t3``.
    """
    w = 2.0 * np.pi * freqs
    sig, wd = zeta * w, w * math.sqrt(1.0 - zeta * zeta)
    t2 = ratios * t3
    e2 = np.exp(sig[None, :] * (t2[:, None] - t3) + 1j * wd[None, :] * t2[:, None])  # (R, F)
    e3 = np.exp(1j * wd * t3)                                                         # (F,)
    e1 = np.exp(-sig * t3)                                                            # (F,)
    V = np.abs(A[:, 0, None, None] * e1[None, None, :] + A[:, 1, None, None] * e2[None]
               + A[:, 2, None, None] * e3[None, None, :]).max(axis=2)                 # (G, R)
    g, r = np.unravel_index(int(np.argmin(V)), V.shape)
    return float(V[g, r]), A[g], np.array([0.0, float(t2[r]), t3])


@functools.lru_cache(maxsize=64)
def si_shaper(f: float, zeta: float, band: float, *, v_tol: float = V_TOL) -> Shaper:
    """Return the shortest three-impulse shaper with V ≤ ``v_tol`` over f·(1 ± band).

    Parameters
    ----------
    f : float
        Design frequency (Hz).
    zeta : float
        Damping ratio.
    band : float
        Half-width of the band, relative (e.g. 0.1).
    v_tol : float
        Vibration tolerance over the band.

    Returns
    -------
    Shaper
        Amplitudes ≥ 0 summing to 1; delays 0 < t2 < t3.

    Notes
    -----
    A direct search over the total delay t3 (a 2 % step of the damped period,
    then a 0.2 % step below the first feasible one), the middle delay
    (0.35..0.65 of t3) and the amplitudes (a grid of step 1/40): the first
    t3 whose best design keeps V ≤ v_tol over 81 points of the band wins.
    Without any, the design with the least worst V.
    """
    if not (f > 0 and 0.0 <= zeta < 1.0 and 0.0 <= band < 1.0):
        raise ValueError(f"bad SI design inputs f={f!r}, zeta={zeta!r}, band={band!r}")
    Td = 1.0 / (f * math.sqrt(1.0 - zeta * zeta))
    freqs = f * (1.0 + np.linspace(-band, band, 81)) if band > 0 else np.array([f])
    k = 40
    grid = np.array([(i, j) for i in range(k + 1) for j in range(k + 1 - i)], float) / k
    A = np.column_stack([1.0 - grid.sum(1), grid[:, 0], grid[:, 1]])
    ratios = np.arange(0.35, 0.651, 0.025)
    best: tuple[float, np.ndarray, np.ndarray] | None = None
    prev = 0.5 * Td
    for t3 in Td * np.arange(0.5, 2.0 + 1e-9, 0.02):
        cand = _best_at(float(t3), A, ratios, freqs, zeta)
        if best is None or cand[0] < best[0]:
            best = cand
        if cand[0] <= v_tol:
            for t3f in np.arange(prev, t3, 0.002 * Td):  # refine below the first feasible
                fine = _best_at(float(t3f), A, ratios, freqs, zeta)
                if fine[0] <= v_tol:
                    cand = fine
                    break
            return Shaper("SI", cand[1] / cand[1].sum(), cand[2], f, zeta)
        prev = float(t3)
    assert best is not None
    return Shaper("SI", best[1] / best[1].sum(), best[2], f, zeta)


def band_vibration(shaper: Shaper, f: float, zeta: float, band: float) -> float:
    """Return the worst V(f') of ``shaper`` over f' in f·(1 ± band) (201 points)."""
    freqs = f * (1.0 + np.linspace(-band, band, 201))
    w = 2.0 * np.pi * freqs
    sig, wd = zeta * w, w * math.sqrt(1.0 - zeta * zeta)
    tn = float(shaper.t[-1])
    ph = np.exp(sig[:, None] * (shaper.t[None, :] - tn) + 1j * wd[:, None] * shaper.t[None, :])
    return float(np.abs(ph @ shaper.A).max())
