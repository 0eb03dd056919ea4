"""Two more shapers a user would pick when the mode is uncertain, or not alone.

* ``JL*SI`` -- a **specified-insensitivity** shaper (Singhose, Seering & Singer
  1996): three impulses designed on the tuned mode at the end of the motion,
  its residual-vibration ratio V(f) kept at or below 5 % over the frequency
  band of the scenario's uncertainty (the end frequency ×(1 ± map_scale)),
  as short as that allows;
* ``JL*MM-ZVD`` -- a **multi-mode** shaper: the convolution of a ZVD shaper per
  mode of the map, each designed for that mode at the end of the motion (for
  a scenario with two modes; with one it is the ZVD).

Both act on the generator's JL profile (its jerk time, the same jerk bound)
and keep exact delays (the shaped reference is exact; the FMU's custom shaper
takes the same amplitudes and delays).  The design is stationary: the mode at
the end of the motion; the worst case on the moving mode is what ``compare``
measures.
"""

from __future__ import annotations

import math

import numpy as np

from .context import PeerContext, PeerSpec
from .shapers import Shaper, shape, zvd
from .trajectory import PiecewiseJerk

__all__ = ["band_vibration", "build_mm_zvd", "build_si", "mm_zvd", "si_shaper"]

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


def mm_zvd(freqs: list[float], zetas: list[float]) -> Shaper:
    """Return the convolution of one ZVD per mode (frequencies in Hz, damping ratios)."""
    A, t = np.array([1.0]), np.array([0.0])
    for f, z in zip(freqs, zetas, strict=True):
        s = zvd(f, z)
        A = np.outer(A, s.A).ravel()
        t = np.add.outer(t, s.t).ravel()
    order = np.argsort(t, kind="stable")
    A, t = A[order], t[order]
    # merge coincident impulses
    keep_t, keep_A = [float(t[0])], [float(A[0])]
    for ti, ai in zip(t[1:].tolist(), A[1:].tolist(), strict=True):
        if abs(ti - keep_t[-1]) <= 1e-12:
            keep_A[-1] += ai
        else:
            keep_t.append(ti)
            keep_A.append(ai)
    return Shaper("MM-ZVD", np.array(keep_A), np.array(keep_t), float(freqs[0]),
                  float(zetas[0]))


def build_si(ctx: PeerContext, name: str) -> tuple[PiecewiseJerk, PeerSpec]:
    """Peer ``JL*SI``: JL convolved with the SI shaper for the uncertainty's band."""
    band = float(ctx.sc.uncertainty.map_scale)
    sh = si_shaper(ctx.f_end, ctx.zeta, band)
    v = band_vibration(sh, ctx.f_end, ctx.zeta, band)
    mot = shape(ctx.base("JL"), sh, name=name)
    return mot, PeerSpec(name, f"JL T_F {ctx.T_F_JL * 1e3:.0f} ms; SI: V <= {v * 100:.1f} % over "
                               f"{ctx.f_end:.4g} Hz x (1 +/- {band:g}), zeta = {ctx.zeta:g}; "
                               f"adds {sh.duration * 1e3:.0f} ms",
                         {"f": ctx.f_end, "zeta": ctx.zeta, "band": band, "V_max": v,
                          "A": sh.A.tolist(), "t": sh.t.tolist()})


def build_mm_zvd(ctx: PeerContext, name: str) -> tuple[PiecewiseJerk, PeerSpec]:
    """Peer ``JL*MM-ZVD``: JL convolved with one ZVD per mode of the map (end of the motion)."""
    z_end = ctx.sc.z.z0 + ctx.sc.z.distance
    modes = ctx.sc.modemap.modes
    freqs = [float(m.f(z_end)) for m in modes]
    zetas = [float(m.zeta) for m in modes]
    sh = mm_zvd(freqs, zetas)
    mot = shape(ctx.base("JL"), sh, name=name)
    txt = ", ".join(f"{f:.4g} Hz" for f in freqs)
    return mot, PeerSpec(name, f"JL T_F {ctx.T_F_JL * 1e3:.0f} ms; ZVD for each mode at the "
                               f"end ({txt}); adds {sh.duration * 1e3:.0f} ms",
                         {"f": freqs, "zeta": zetas, "A": sh.A.tolist(), "t": sh.t.tolist()})
