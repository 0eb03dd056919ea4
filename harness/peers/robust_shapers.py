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

import numpy as np

from ..shaper_designs import V_TOL, band_vibration, si_shaper
from .context import PeerContext, PeerSpec
from .shapers import Shaper, shape, zvd
from .trajectory import PiecewiseJerk

__all__ = ["V_TOL", "band_vibration", "build_mm_zvd", "build_si", "mm_zvd", "si_shaper"]

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
