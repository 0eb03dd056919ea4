"""Why the paper's tuning rule leaves a remainder: closed forms.

The paper (Béarée & Olabi 2013, §3.1, eq. 20-21) tunes each constant-jerk
stage to the modal period, which cancels the stage's vibration on an
*undamped*, *stationary* mode.  On the flexible axis of the harness,
ε̈ + 2ζω ε̇ + ω² ε = −q̈ with ω = ω(z(t)), three things are left:

* **damping** — a ramp of length T leaves, relative to the AL level A/(ω ω_d)
  (the free amplitude an unfiltered step of A leaves),
  ``|exp(pT) − 1| / (ωT)``, p = −ζω + iω_d (:func:`stage_remainder`); at
  T = 2π/ω that is (1 − e^{−2πζ})/(2π) + ζ³/8 ≈ ζ(1 − πζ), and no jerk time makes it
  vanish (:func:`optimal_jerk_time`);
* **drift within the stage** — a mode going linearly from f0 to f1 = f0(1 + δ)
  during a ramp of length 1/f0 leaves ≈ c·|δ| to first order, with c = 0.874
  (mode frozen at the stage end, the harness's free amplitude) or c = 0.639
  (about the moving quasi-static deflection): the accumulated phase gives only
  |δ|/2 of it, the change of the modal compliance 1/ω² between the two jerk
  kinks the rest (:func:`drift_remainder`, :data:`DRIFT_COEFFICIENT`);
* **the four stages add as vectors** — each stage's remainder is carried to
  the end of the motion, rotated by the phase the mode accumulates from the
  stage end and decayed by the damping; the residual is their vector sum, at
  most the sum of their magnitudes (:func:`four_stage_bound`,
  :func:`constant_mode_phasors` exact for a constant mode,
  :func:`stage_phasors` to first order on the moving mode, with the WKB
  residual of a whole move :func:`moving_mode_residual`).

The derivations and the numbers of the default scenarios are in
``docs/tuning.md``; :func:`plot_jerk_times` draws the jerk times of the paper's,
the optimal and the robust tuning against the local periods.

Conventions
-----------
A free oscillation of the mode is represented by the complex number
``w = (ε̇ + ζωe)/ω_d + i·e``, e the deviation from the quasi-static deflection
−a/ω²; ``|w|`` is the harness's free amplitude
(:func:`harness.plant.free_amplitude`) and w evolves as ``w·exp(p t)`` when
the mode is free and constant.  Remainders are fractions of the AL level
A/(ω ω_d) of the stage's acceleration step A at the stage-start frequency
(relative to A/ω² instead, multiply by 1/√(1 − ζ²): 1.00045 at ζ = 0.03).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..scenario import Scenario
from ..simulation.axis import stage_starts
from ..simulation.master import CoSimResult
from ..simulation.session import Session
from .rule import TuningResult

if TYPE_CHECKING:
    from matplotlib.figure import Figure  # a type only: matplotlib is heavy to import

__all__ = [
    "DRIFT_COEFFICIENT",
    "PHASE_RULE_COEFFICIENT",
    "StagePhasors",
    "constant_mode_phasors",
    "damped_period_remainder",
    "drift_phasor",
    "drift_remainder",
    "four_stage_bound",
    "move_phasors",
    "moving_mode_residual",
    "optimal_jerk_time",
    "plot_jerk_times",
    "stage_phasor",
    "stage_remainder",
    "stage_remainder_first_order",
    "stage_phasors",
]

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

REFERENCES = ("moving", "frozen")
"""Where a drifting stage's remainder is measured from (see :func:`drift_phasor`)."""

DRIFT_COEFFICIENT: dict[str, float] = {
    "frozen": math.hypot(math.pi, 4.5) / (2.0 * math.pi),
    "moving": math.hypot(math.pi, 2.5) / (2.0 * math.pi),
    "phase_only": 0.5,
}
"""First-order remainder / |δ| of one undamped stage, T_F = 1/f0, f linear f0 → f0(1 + δ).

``frozen``: the free amplitude at the stage end with the mode frozen there
(√(π² + (9/2)²)/(2π) = 0.8735); ``moving``: about the quasi-static deflection
that keeps moving with the mode (√(π² + (5/2)²)/(2π) = 0.6390); ``phase_only``:
eq. 21 with ωT_F replaced by the accumulated phase ∫ω dt (what the paper's
§3.2 reasoning, and claim 4's estimate, account for)."""

PHASE_RULE_COEFFICIENT: dict[str, float] = {
    "frozen": 4.5 / (2.0 * math.pi),
    "moving": 2.5 / (2.0 * math.pi),
}
"""First-order remainder / |δ| left when the stage lasts one cycle of the moving
mode (∫ω dt = 2π: the ``phase`` rule; the period at the stage's middle to first
order): the phase term is cancelled, the compliance term is not (0.716, 0.398)."""


# ------------------------------------------------------------------ one stage


def _omega(f: ArrayLike) -> FloatArray:
    f_arr = np.asarray(f, dtype=float)
    if np.any(~np.isfinite(f_arr)) or np.any(f_arr <= 0.0):
        raise ValueError("mode frequencies must be finite and > 0 Hz")
    return 2.0 * np.pi * f_arr


def _check_zeta(zeta: ArrayLike) -> FloatArray:
    z = np.asarray(zeta, dtype=float)
    if np.any(~np.isfinite(z)) or np.any(z < 0.0) or np.any(z >= 1.0):
        raise ValueError("damping ratios must be in [0, 1)")
    return z


def stage_phasor(T_F: ArrayLike, f: ArrayLike, zeta: ArrayLike = 0.0) -> ComplexArray:
    """Complex remainder of one constant-jerk stage on a constant damped mode (exact).

    A ramp of the acceleration from 0 to A in T_F (jerk A/T_F) leaves, at its
    end, the free oscillation ``w = (A/(ω ω_d))·ρ`` about −A/ω², with

        ρ = e^{−2iφ} (e^{pT_F} − 1) / (ωT_F),   p = −ζω + iω_d,  sin φ = ζ.

    Derivation: during the ramp ε = ε_p + free part, with the particular
    solution ε_p = −jt/ω² + 2ζj/ω³ (j = A/T_F); from rest, the free part starts
    at (−2ζj/ω³, j/ω²), whose w is (j/(ω²ω_d))·e^{−2iφ}; after T_F it has become
    that times e^{pT_F}, and the deviation from the new equilibrium −A/ω² is the
    free part minus its initial value.

    Parameters
    ----------
    T_F : array_like
        Jerk time (s), ≥ 0 (0: the unfiltered step, ρ = i·e^{−iφ}).
    f : array_like
        Natural frequency of the mode (Hz).
    zeta : array_like
        Damping ratio in [0, 1).

    Returns
    -------
    ndarray of complex
        ρ, a fraction of the AL level A/(ω ω_d); broadcast over the inputs.
    """
    T = np.asarray(T_F, dtype=float)
    if np.any(T < 0.0) or np.any(~np.isfinite(T)):
        raise ValueError("jerk times must be finite and >= 0 s")
    w = _omega(f)
    z = _check_zeta(zeta)
    T, w, z = np.broadcast_arrays(T, w, z)
    s = np.sqrt(1.0 - z * z)
    p = w * (-z + 1j * s)
    rot = (s - 1j * z) ** 2  # e^{-2i phi}
    x = w * T
    with np.errstate(invalid="ignore", divide="ignore"):
        rho = rot * np.expm1(p * T) / np.where(x > 0.0, x, 1.0)
    return np.where(x > 0.0, rho, rot * (p / w))


def stage_remainder(T_F: ArrayLike, f: ArrayLike, zeta: ArrayLike = 0.0) -> FloatArray:
    """Residual of one constant-jerk stage on a constant damped mode, exact (eq. 20).

    ``r = |e^{pT_F} − 1| / (ωT_F)
        = √(1 − 2e^{−ζωT_F} cos(ω_d T_F) + e^{−2ζωT_F}) / (ωT_F)``,

    the free-oscillation amplitude at the end of the ramp relative to the AL
    level A/(ω ω_d).  For ζ = 0 it is eq. 21's |sin(ωT_F/2)/(ωT_F/2)|.  At
    T_F = 2π/ω (the paper's rule) it is (1 − e^{−2πζ})/(2π) + ζ³/8 + O(ζ⁴)
    (0.02734 at ζ = 0.03, 0.03537 at ζ = 0.04); at the damped period 2π/ω_d it
    is exactly √(1 − ζ²)(1 − e^{−2πζ/√(1−ζ²)})/(2π) (:func:`damped_period_remainder`).

    Parameters
    ----------
    T_F : array_like
        Jerk time (s), ≥ 0.
    f : array_like
        Natural frequency (Hz).
    zeta : array_like
        Damping ratio in [0, 1).

    Returns
    -------
    ndarray
        r (1 for T_F = 0).
    """
    return np.abs(stage_phasor(T_F, f, zeta))


def stage_remainder_first_order(T_F: ArrayLike, f: ArrayLike,
                                zeta: ArrayLike = 0.0) -> FloatArray:
    """:func:`stage_remainder` to first order in ζ: ``|e^{ix} − 1 − ζx e^{ix}| / x``, x = ωT_F.

    From e^{pT} = e^{−ζx}e^{ix√(1−ζ²)} = (1 − ζx)e^{ix} + O(ζ²) (the complex
    form: expanding the square root of eq. 20 is not uniform near x = 2π).
    At x = 2πk it is exactly ζ: the first jerk kink's response decays by
    e^{−ζωT_F} ≈ 1 − ζωT_F before the second kink cancels it, a mismatch of
    ζωT_F·(A/T_F)/ω³ = ζ·A/ω² — the estimate "about ζ·A/ω²" holds, to first
    order (the exact value is ζ(1 − πζ + …)·A/(ωω_d), 9 % lower at ζ = 0.03).
    The error is O(ζ²).

    Parameters
    ----------
    T_F : array_like
        Jerk time (s), > 0.
    f : array_like
        Natural frequency (Hz).
    zeta : array_like
        Damping ratio in [0, 1).

    Returns
    -------
    ndarray
    """
    T = np.asarray(T_F, dtype=float)
    if np.any(T <= 0.0):
        raise ValueError("jerk times must be > 0 s")
    x = _omega(f) * T
    z = _check_zeta(zeta)
    ex = np.exp(1j * x)
    return np.abs(ex - 1.0 - z * x * ex) / x


def damped_period_remainder(zeta: ArrayLike) -> FloatArray:
    """Remainder of a stage whose jerk time is the *damped* period 2π/ω_d (exact).

    There e^{pT} = e^{−2πζ/√(1−ζ²)} is real: ``r = √(1−ζ²)(1 − e^{−2πζ/√(1−ζ²)})/(2π)``,
    > 0 for every ζ > 0.

    Parameters
    ----------
    zeta : array_like
        Damping ratio in [0, 1).

    Returns
    -------
    ndarray
    """
    z = _check_zeta(zeta)
    s = np.sqrt(1.0 - z * z)
    return s * -np.expm1(-2.0 * np.pi * z / s) / (2.0 * np.pi)


def optimal_jerk_time(f: float, zeta: float, cycles: int = 1) -> tuple[float, float]:
    """Jerk time that minimises :func:`stage_remainder` near ``cycles`` periods, and the minimum.

    The minimum is not at the period: to first orders it is at
    T_d(1 + πζ³), T_d = 2π/ω_d the damped period (1.000535 periods at
    ζ = 0.03), and its depth is (1 − e^{−2πkζ})/(2πk) ≈ ζ(1 − πkζ) for the k-th
    minimum: never 0 for ζ > 0 (|e^{pT}| = e^{−ζωT} < 1), and hardly lower than
    at the period itself (by about ζ³/8: 4·10⁻⁶ at ζ = 0.03).

    Parameters
    ----------
    f : float
        Natural frequency (Hz).
    zeta : float
        Damping ratio in [0, 1).
    cycles : int
        Which minimum: near ``cycles`` natural periods (≥ 1).

    Returns
    -------
    T_opt : float
        The jerk time (s).
    r_min : float
        :func:`stage_remainder` there.
    """
    from scipy.optimize import minimize_scalar  # deferred: scipy is heavy to import

    if cycles < 1:
        raise ValueError("cycles must be >= 1")
    P = 1.0 / float(f)

    def r(T: float) -> float:
        return float(stage_remainder(T, f, zeta))

    res = minimize_scalar(r, bounds=((cycles - 0.25) * P, (cycles + 0.25) * P),
                          method="bounded", options={"xatol": 1e-12 * P})
    return float(res.x), float(res.fun)


def drift_phasor(T_F: ArrayLike, f0: ArrayLike, f1: ArrayLike, zeta: ArrayLike = 0.0, *,
                 reference: str = "moving") -> ComplexArray:
    """Complex remainder of a stage on a mode drifting linearly, to first order in ζ and δ.

    The mode goes linearly in time from f0 (stage start) to f1 = f0(1 + δ)
    (stage end).  With x = 2πf0·T_F, the normalised remainder (fraction of
    the AL level at the stage start) is

        ρ ≈ [(e^{ix} − 1) − ζ(x e^{ix} + 2i(e^{ix} − 1)) + δ·D(x)] / x,
        D(x) = 3 − e^{ix}/2 + (ix/2) e^{ix} − sin x/(2x) − (4i/x)(1 − e^{ix})  [+ 2],

    the ``+ 2`` for ``reference="frozen"``.  Derivation (ζ = 0): with
    e = ε + u/ω² (u = jt the ramp) the mode obeys ë + ω²e = d²(u/ω²)/dt²: two
    impulses j/ω0² at 0 and −j/ω1² at T_F (the jerk kinks, weighted by the
    modal compliance where they happen), and a distributed force
    −4jδ/(T_F ω0²) + O(δ²).  Propagating them with the WKB solutions
    (ω0ω(t))^{−1/2} sin ∫ω dt gives the formula.  At x = 2π (T_F = 1/f0,
    the paper's start rule): ρ ≈ [−2πζ + (5/2)δ + iπδ]/(2π) — the imaginary
    part iπδ is the phase ∫ω dt − 2π = πδ accumulated by the drifting mode,
    the real part the compliance: the first kink's response, j/ω0² carried with
    the WKB amplitude (ω0ω1)^{−1/2}, and the second kink's, j/ω1² at ω1, no
    longer cancel, (j/ω0³)[(1 − δ/2) − (1 − 3δ)] = (j/ω0³)(5/2)δ; the frozen
    measure adds the velocity of the quasi-static deflection, A·d(1/ω²)/dt,
    i.e. 2δ.  For a falling frequency (δ < 0) the compliance term adds to the
    damping term.

    Parameters
    ----------
    T_F : array_like
        Jerk time (s), > 0.
    f0, f1 : array_like
        Mode frequency at the start and at the end of the stage (Hz).
    zeta : array_like
        Damping ratio.
    reference : {"moving", "frozen"}
        ``"frozen"``: the free amplitude at the stage end with the mode frozen
        there, about −A/ω1² (what :func:`harness.plant.free_amplitude` measures,
        and claim 4: a mode that stops drifting at the stage end);
        ``"moving"``: about the quasi-static deflection −A/ω(t)², which keeps
        moving when the mode keeps drifting (the part that propagates as a free
        oscillation; the difference, A·d(1/ω²)/dt, is not an oscillation).

    Returns
    -------
    ndarray of complex
        ρ; error O(ζ² + δ² + ζδ) (for δ ≪ x²: the rate of change must stay
        adiabatic).
    """
    if reference not in REFERENCES:
        raise ValueError(f"reference must be one of {REFERENCES}, got {reference!r}")
    T = np.asarray(T_F, dtype=float)
    if np.any(T <= 0.0):
        raise ValueError("jerk times must be > 0 s")
    w0 = _omega(f0)
    delta = _omega(f1) / w0 - 1.0
    z = _check_zeta(zeta)
    x = w0 * T
    ex = np.exp(1j * x)
    D = 3.0 - ex / 2.0 + 0.5j * x * ex - np.sin(x) / (2.0 * x) - 4j / x * (1.0 - ex)
    if reference == "frozen":
        D = D + 2.0
    return ((ex - 1.0) - z * (x * ex + 2j * (ex - 1.0)) + delta * D) / x


def drift_remainder(T_F: ArrayLike, f0: ArrayLike, f1: ArrayLike, zeta: ArrayLike = 0.0, *,
                    reference: str = "moving") -> FloatArray:
    """Remainder of a stage on a linearly drifting mode, first order: ``|drift_phasor|``.

    With T_F = 1/f0 (the paper's start rule) and ζ = 0 it is
    ``DRIFT_COEFFICIENT[reference]·|δ|``: 0.874|δ| (frozen) or 0.639|δ|
    (moving), where the accumulated phase alone gives |δ|/2.  The ``phase``
    rule (one cycle of the moving mode, T_F ≈ (1 − δ/2)/f0, i.e. the period at
    the stage's middle to first order) cancels the phase term only and leaves
    ``PHASE_RULE_COEFFICIENT[reference]·|δ|`` (0.716|δ|, 0.398|δ|): no
    constant-jerk time cancels the compliance term, which is in quadrature with
    what a change of T_F moves (d(e^{ix} − 1)/dx = i at x = 2π).

    Parameters
    ----------
    T_F : array_like
        Jerk time (s), > 0.
    f0, f1 : array_like
        Mode frequency at the start and the end of the stage (Hz).
    zeta : array_like
        Damping ratio.
    reference : {"moving", "frozen"}
        See :func:`drift_phasor`.

    Returns
    -------
    ndarray
    """
    return np.abs(drift_phasor(T_F, f0, f1, zeta, reference=reference))


# ------------------------------------------------------------ four stages


def four_stage_bound(amplitudes: Sequence[float], T_F: Sequence[float],
                     f_start: Sequence[float], zeta: float,
                     f_end: Sequence[float] | None = None, *,
                     reference: str = "moving") -> float:
    """Sum of the magnitudes of the stage remainders (m): the bound of their vector sum.

    ``Σ_i |A_i|/(ω_i ω_d,i) · r_i`` with ω_i the local frequency at the start
    of stage i and r_i :func:`stage_remainder` (or, with ``f_end``,
    :func:`drift_remainder`, first order in the drift).  The residual at the end
    of the motion is the *vector* sum of the four remainders, each rotated by
    the phase the mode accumulates from its stage end to the end of the motion
    and decayed on the way (:func:`constant_mode_phasors`, :func:`stage_phasors`);
    its magnitude is at most this sum.  For a constant mode that is a rigorous
    bound (the decay only lowers it).  On the moving mode it is an estimate:
    it leaves out the growth of an oscillation's amplitude as ω falls after the
    stage ((ω_i/ω_end)^{1/2}, ≤ 1.13 on scenario X) and the small term of the
    quasi-static deflection drifting along the motion (:attr:`StagePhasors.drift`).

    Parameters
    ----------
    amplitudes : sequence of float
        The four acceleration steps A_i (m/s²): a_reached, −a_reached,
        −d_reached, d_reached for a positive move.
    T_F : sequence of float
        The four jerk times (s).
    f_start : sequence of float
        Mode frequency at each stage start (Hz).
    zeta : float
        Damping ratio.
    f_end : sequence of float, optional
        Mode frequency at each stage end (Hz): include the drift within the
        stages (:func:`drift_remainder`).
    reference : {"moving", "frozen"}
        With ``f_end``: see :func:`drift_phasor`.

    Returns
    -------
    float
        The bound (m), for a participation factor 1.
    """
    A = np.abs(np.asarray(amplitudes, dtype=float))
    T = np.asarray(T_F, dtype=float)
    w = _omega(f_start)
    if not (A.shape == T.shape == w.shape):
        raise ValueError("amplitudes, T_F and f_start must have the same length")
    if f_end is None:
        r = stage_remainder(T, f_start, zeta)
    else:
        r = drift_remainder(T, f_start, f_end, zeta, reference=reference)
    wd = w * math.sqrt(1.0 - zeta**2)
    return float(np.sum(A / (w * wd) * r))


def constant_mode_phasors(amplitudes: Sequence[float], starts: Sequence[float],
                          T_F: Sequence[float], f: float, zeta: float,
                          t_end: float) -> ComplexArray:
    """Contribution of each stage to the residual at ``t_end``, constant mode (exact, m).

    ``w_i = (A_i/(ω ω_d)) ρ_i e^{p(t_end − t_i − T_i)}``, ρ_i the
    :func:`stage_phasor`; the free oscillation at ``t_end`` is Σ w_i exactly
    (integrate w = −(1/ω_d)∫ a(s) e^{p(t_end − s)} ds by parts over each ramp),
    so the residual is |Σ w_i| ≤ Σ |w_i|.

    Parameters
    ----------
    amplitudes : sequence of float
        Acceleration steps A_i (m/s²), signed.
    starts : sequence of float
        Stage starts t_i (s).
    T_F : sequence of float
        Jerk times (s).
    f : float
        Mode frequency (Hz).
    zeta : float
        Damping ratio.
    t_end : float
        End of the motion (s), at or after every stage end.

    Returns
    -------
    ndarray of complex
        w_i (m), for a participation factor 1.
    """
    w = float(_omega(f))
    wd = w * math.sqrt(1.0 - zeta**2)
    p = complex(-zeta * w, wd)
    out = np.empty(len(amplitudes), dtype=complex)
    for i, (A, t0, T) in enumerate(zip(amplitudes, starts, T_F, strict=True)):
        rho = complex(stage_phasor(T, f, zeta))
        out[i] = A / (w * wd) * rho * np.exp(p * (t_end - t0 - T))
    return out


def _grid(t: FloatArray, f: FloatArray, t0: float, t1: float, points: Sequence[float],
          refine: int) -> tuple[FloatArray, FloatArray]:
    """Return a fine grid on [t0, t1] through ``points`` and the frequency there (linear)."""
    k0 = max(int(np.searchsorted(t, t0, side="right")) - 1, 0)
    k1 = min(int(np.searchsorted(t, t1, side="left")) + 1, t.size)
    base = t[k0:k1]
    n = max(1, refine)
    fine = (base[:-1, None] + np.diff(base)[:, None] * (np.arange(n) / n)[None, :]).ravel()
    s = np.unique(np.concatenate([fine, [t0, t1], [q for q in points if t0 <= q <= t1]]))
    s = s[(s >= t0) & (s <= t1)]
    return s, np.interp(s, t, f)


def _kernel(s: FloatArray, f: FloatArray, zeta: float
            ) -> tuple[FloatArray, ComplexArray, ComplexArray, FloatArray]:
    """Return ω_d, p, e^{∫_s^{end} p} and ∫_s^{end} ω_d (WKB propagation to the last point)."""
    w = 2.0 * np.pi * f
    wd = w * math.sqrt(1.0 - zeta**2)
    p = -zeta * w + 1j * wd
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (p[1:] + p[:-1]) * np.diff(s))])
    to_end = cum[-1] - cum
    return wd, p, np.exp(to_end), to_end.imag


def _trapz(y: np.ndarray, x: FloatArray) -> Any:
    return np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x))


def moving_mode_residual(t: ArrayLike, a: ArrayLike, f: ArrayLike, zeta: float,
                         t_end: float | None = None, *, refine: int = 8) -> complex:
    """Free oscillation left at ``t_end`` by an acceleration on a drifting mode (WKB, m).

    ``w(t_end) = −(ω_d(t_end))^{−1/2} ∫ a(s) ω_d(s)^{−1/2} exp(∫_s^{t_end} p dτ) ds``,
    p = −ζω + iω_d: the first-order (WKB, slowly varying ω) solution of
    ε̈ + 2ζωε̇ + ω²ε = −a, the generalisation of eq. 17-18 to a moving mode —
    the amplitude of each part of the input is weighted by ω^{−1/2} and its
    phase is the phase the mode accumulates until the end.  ``|w|`` is the
    residual (the harness's free amplitude) when a(t_end) = 0 and the mode has
    stopped drifting; exact for a constant mode.

    Parameters
    ----------
    t : array_like
        Increasing sample times (s).
    a : array_like
        Reference acceleration at ``t`` (m/s²), linear between samples.
    f : array_like
        Mode frequency at ``t`` (Hz), interpolated linearly.
    zeta : float
        Damping ratio.
    t_end : float, optional
        End of the motion (s); default: the last sample.
    refine : int
        Quadrature points per sample interval.

    Returns
    -------
    complex
        w (m) for a participation factor 1; the residual is ``abs(w)``.
    """
    t_arr = np.asarray(t, dtype=float)
    a_arr = np.asarray(a, dtype=float)
    f_arr = np.asarray(f, dtype=float)
    te = float(t_arr[-1]) if t_end is None else float(t_end)
    s, fs = _grid(t_arr, f_arr, float(t_arr[0]), te, [], refine)
    wd, _, E, _ = _kernel(s, fs, zeta)
    acc = np.interp(s, t_arr, a_arr)
    return complex(-wd[-1] ** -0.5 * _trapz(acc * wd**-0.5 * E, s))


@dataclass(frozen=True)
class StagePhasors:
    """A move's residual split into its four stage contributions (first order, WKB).

    Attributes
    ----------
    stages : tuple of complex
        Contribution of each stage at the end of the motion (m): its remainder
        carried to t_end (rotated by the phase accumulated since the stage,
        decayed by the damping).
    drift : complex
        The term of the quasi-static deflection −a/ω² changing along the motion
        (m); 0 for a constant mode.
    phases : tuple of float
        Phase the mode accumulates from each stage end to t_end, ∫ω_d dt (rad):
        a map error e rotates stage i's contribution by about e·phases[i].
    decays : tuple of float
        ∫ζω dt from each stage end to t_end: the contribution was
        e^{decays[i]} times larger at the stage end.
    relative : tuple of float
        ``|stages[i]|·e^{decays[i]}`` as a fraction of the stage's AL level
        |A_i|/(ω ω_d) at its start: the stage's remainder when it ends.
    """

    stages: tuple[complex, ...]
    drift: complex
    phases: tuple[float, ...]
    decays: tuple[float, ...]
    relative: tuple[float, ...]

    @property
    def total(self) -> complex:
        """Σ stages + drift: the free oscillation at the end of the motion (m)."""
        return complex(sum(self.stages) + self.drift)

    @property
    def residual(self) -> float:
        """|total| (m)."""
        return abs(self.total)

    @property
    def bound(self) -> float:
        """Σ |stages| + |drift| (m): what the vector sum can reach at most."""
        return float(sum(abs(s) for s in self.stages) + abs(self.drift))

    @property
    def cancellation(self) -> float:
        """Return residual / bound: 1 when the contributions line up, ≪ 1 when they cancel."""
        b = self.bound
        return self.residual / b if b > 0 else 0.0


def stage_phasors(t: ArrayLike, f: ArrayLike, zeta: float, starts: Sequence[float],
                  T_F: Sequence[float], amplitudes: Sequence[float], t_end: float, *,
                  refine: int = 8) -> StagePhasors:
    """Split :func:`moving_mode_residual` of a four-stage move into its stages.

    The acceleration is a(s) = Σ A_i ρ_i(s), ρ_i the unit ramp of stage i
    (0 before t_i, 1 after t_i + T_i).  With K(s) = (ω_d(s)ω_d(t_end))^{−1/2}
    exp(∫_s^{t_end} p), integrating ∫ a K ds by parts with K = −d(K/p)/ds +
    e^{∫p} d(κ/p)/ds (κ = K e^{−∫p}) gives exactly, since Σ A_i = 0,

        w(t_end) = Σ_i A_i S_i + D,
        S_i = −(1/T_i) ∫_{t_i}^{t_i+T_i} K(s)/p(s) ds,
        D   = −∫ a(s) e^{∫_s^{t_end} p} d(κ/p).

    For a constant mode D = 0 and A_i S_i are :func:`constant_mode_phasors`.

    Parameters
    ----------
    t : array_like
        Increasing sample times (s) covering the stages and ``t_end``.
    f : array_like
        Mode frequency at ``t`` (Hz).
    zeta : float
        Damping ratio.
    starts, T_F, amplitudes : sequence of float
        Stage starts (s), jerk times (s), acceleration steps (m/s², signed,
        summing to 0).
    t_end : float
        End of the motion (s).
    refine : int
        Quadrature points per sample interval.

    Returns
    -------
    StagePhasors
    """
    t_arr = np.asarray(t, dtype=float)
    f_arr = np.asarray(f, dtype=float)
    A = [float(x) for x in amplitudes]
    if abs(sum(A)) > 1e-9 * max(1.0, max(abs(x) for x in A)):
        raise ValueError("the acceleration steps must sum to 0 (a rest-to-rest move)")
    t0 = min(float(x) for x in starts)
    pts = [float(x) for x in starts] + [float(x) + float(T) for x, T in zip(starts, T_F,
                                                                            strict=True)]
    s, fs = _grid(t_arr, f_arr, t0, float(t_end), pts, refine)
    wd, p, E, ph = _kernel(s, fs, zeta)
    K = (wd * wd[-1]) ** -0.5 * E
    cum_decay = np.concatenate([[0.0], np.cumsum(0.5 * (zeta * 2 * np.pi * (fs[1:] + fs[:-1]))
                                                 * np.diff(s))])
    decay_to_end = cum_decay[-1] - cum_decay
    stages, phases, decays, rel = [], [], [], []
    acc = np.zeros(s.size)
    for Ai, ti, Ti in zip(A, starts, T_F, strict=True):
        ti, Ti = float(ti), float(Ti)
        m = (s >= ti - 1e-12) & (s <= ti + Ti + 1e-12)
        Si = -_trapz((K / p)[m], s[m]) / Ti
        stages.append(complex(Ai * Si))
        acc += Ai * np.clip((s - ti) / Ti, 0.0, 1.0)
        k_end = min(int(np.searchsorted(s, ti + Ti - 1e-12)), s.size - 1)
        k_start = min(int(np.searchsorted(s, ti - 1e-12)), s.size - 1)
        phases.append(float(ph[k_end]))
        decays.append(float(decay_to_end[k_end]))
        w_s = 2 * np.pi * fs[k_start]
        al = abs(Ai) / (w_s * wd[k_start]) if Ai else 1.0
        rel.append(float(abs(Ai * Si) * math.exp(decays[-1]) / al))
    q = (wd[-1] ** -0.5) * wd**-0.5 / p  # κ/p
    mid = 0.5 * ((acc * E)[1:] + (acc * E)[:-1])
    D = complex(-np.sum(mid * np.diff(q)))
    return StagePhasors(tuple(stages), D, tuple(phases), tuple(decays), tuple(rel))


def move_phasors(session: Session, sc: Scenario, T_F: Sequence[float], profile: str = "DJL",
                 mode: int | None = None) -> tuple[StagePhasors, CoSimResult]:
    """Co-simulate one profile of a single-move scenario and split its residual by stage.

    Parameters
    ----------
    session : Session
        A harness session (``Session(engine="fast")`` is fastest).
    sc : Scenario
        A single-move scenario.
    T_F : sequence of float
        The four jerk times (s).
    profile : {"DJL", "JL"}
        The profile.
    mode : int, optional
        Index of the mode analysed; default: the tuned mode.

    Returns
    -------
    phasors : StagePhasors
        For that mode, multiplied by its participation factor.
    run : CoSimResult
        The co-simulation (its ``free_amplitudes[mode]`` is the residual the
        phasors approximate).
    """
    i = sc.modemap.tune if mode is None else mode
    spec = sc.modemap.modes[i]
    move = session.axis.sample(Session.move_params(sc, profile, T_F))
    starts, _ = stage_starts(move)
    run = session.run(sc, profile, T_F)
    Te = sc.simulation.Te
    T_applied = [n * Te for n in move.N_F]
    pi = run.plan_info
    sign = 1.0 if sc.move.distance >= 0 else -1.0
    a_r, d_r = float(pi["a_reached"]), float(pi["d_reached"])
    amps = [sign * a_r, -sign * a_r, -sign * d_r, sign * d_r]
    ph = stage_phasors(run.t, run.f[i], spec.zeta, starts, T_applied, amps, run.t_end)
    g = spec.gain
    if g != 1.0:
        ph = StagePhasors(tuple(g * s for s in ph.stages), g * ph.drift, ph.phases, ph.decays,
                          ph.relative)
    return ph, run


# ------------------------------------------------------------------ figure

_METHOD_COLOURS = {"paper": "tab:blue", "optimal": "tab:red", "robust": "tab:green"}
_STAGE_MARKERS = ("o", "s", "^", "v")


def plot_jerk_times(results: Mapping[str, Sequence[TuningResult]], *, ax: Any = None,
                    title: str | None = None) -> Figure:
    """Jerk times against the local modal periods at the stage starts, per tuning method.

    One marker per stage and move (shape: stage 1-4), one colour per method;
    the diagonal y = x is the paper's rule (each jerk time = the period where
    its stage starts).

    Parameters
    ----------
    results : mapping of str to sequence of TuningResult
        Method name (e.g. ``"paper"``, ``"optimal"``, ``"robust"``) → the DJL
        tunings of a set of moves (:func:`harness.tuning.tune.tune_profile`).  The x
        value is ``TuningResult.periods`` (the local periods at the stage starts
        of the paper's plan, which the optimal and robust results carry).
    ax : matplotlib Axes, optional
        Where to draw; default: a new figure.
    title : str, optional
        Axes title.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import
    from matplotlib.lines import Line2D  # deferred: matplotlib is heavy to import

    if ax is None:
        fig, ax = plt.subplots(figsize=(8.0, 5.6))
    else:
        fig = ax.figure
    xs: list[float] = []
    ys: list[float] = []
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    handles = []
    for k, (method, tunings) in enumerate(results.items()):
        c = _METHOD_COLOURS.get(method, colours[k % len(colours)])
        paper = method == "paper"
        n = 0
        for tu in tunings:
            if len(tu.periods) != 4:
                continue
            n += 1
            for i in range(4):
                P, T = 1e3 * tu.periods[i], 1e3 * tu.T_F[i]
                # the paper's points (on the diagonal) drawn filled, on top
                ax.plot(P, T, _STAGE_MARKERS[i], color=c, ms=4.0 if paper else 5.0,
                        mfc=c if paper else "none", mew=1.0, alpha=0.9,
                        zorder=3 if paper else 2)
                xs.append(P)
                ys.append(T)
        handles.append(Line2D([], [], color=c, marker="o", ls="",
                              mfc=c if paper else "none", label=f"{method} ({n} moves)"))
    if not xs:
        xs, ys = [0.0, 1.0], [0.0, 1.0]
    px = 0.05 * (max(xs) - min(xs) or 1.0)
    py = 0.05 * (max(ys) - min(ys) or 1.0)
    x_lim = (min(xs) - px, max(xs) + px)
    y_lim = (min(min(ys), x_lim[0]) - py, max(max(ys), x_lim[1]) + py)
    d = np.array([min(x_lim[0], y_lim[0]), max(x_lim[1], y_lim[1])])
    ax.plot(d, d, "k-", lw=0.8, zorder=1)
    handles.append(Line2D([], [], color="k", lw=0.8, label="jerk time = local period"))
    handles += [Line2D([], [], color="0.4", marker=m, ls="", mfc="none",
                       label=f"stage {i + 1}") for i, m in enumerate(_STAGE_MARKERS)]
    ax.set_xlim(*x_lim)
    ax.set_ylim(*y_lim)
    ax.set_xlabel("local modal period at the stage start [ms]")
    ax.set_ylabel("jerk time T_Fi [ms]")
    ax.grid(True, alpha=0.3)
    ax.legend(handles=handles, fontsize="small", loc="center left", bbox_to_anchor=(1.02, 0.5))
    ax.set_title(title or "DJL jerk times against the local periods", fontsize="medium")
    fig.tight_layout()
    return fig
