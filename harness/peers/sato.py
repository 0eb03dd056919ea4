"""Designed jerk times under a fixed positioning time (Sato & Shirase 2021).

Sato & Shirase (Precision Engineering 71, 2021, §3-5) shape a rest-to-rest
positioning move of length ``L`` done in a fixed total time ``T_SUM`` with
four constant-jerk stages and no constant-acceleration or constant-velocity
stage: ``T_1`` (acceleration rises to ``A_1``, jerk ``J_1``), ``T_2``
(acceleration falls to 0, ``J_2``), ``T_3`` (deceleration grows to ``A_2``,
``J_3``), ``T_4`` (back to 0, ``J_4``), ``T_SUM = T_1 + T_2 + T_3 + T_4``.
Given ``L``, ``T_SUM`` and ``T_1`` one of three conditions fixes the profile:

* Condition I   ``T_1 = T_2``, ``T_3 = T_4``:  ``L = T_SUM A_1 T_1 / 2``        (eq. 20)
* Condition II  ``T_1 = T_3``, ``T_2 = T_4``:  ``L = (1/2 + R + R²/2) A_1 T_1²`` (eq. 21)
* Condition III ``T_1 = T_4``, ``T_2 = T_3``:  ``L = (2R + 1) T_SUM A_1 T_1 / 6`` (eq. 14, 18),
  ``J_1 = 6 L / (T_1² T_SUM (2R + 1))``                                         (eq. 19)

with ``R = (T_SUM - 2 T_1) / (2 T_1)`` (eq. 17: the ratio of the second jerk
time of each condition to ``T_1``) and ``A_1 = J_1 T_1``.  The other jerks
follow from zero end velocity and acceleration: ``J_2 = -A_1/T_2``,
``A_2 = -A_1 (T_1 + T_2)/(T_3 + T_4)``, ``J_3 = A_2/T_3``, ``J_4 = -A_2/T_4``
(Condition III: ``J_2 = -J_1/R``, eq. 27).

Residual vibration (§4.1): for an undamped mode ``G(s) = ω²/(s² + ω²)``
driven by the acceleration, each jerk step leaves a sine of amplitude
``ΔJ/ω``; Table 1 sums them (eq. 28 for Condition III):

    Amp_III = (2 J_1 / ω) [(1 + 1/R) sin(ω R T_1) - sin(ω T_SUM / 2)]

Amp is the amplitude of ``G(s) a`` (an acceleration, m/s²); the deflection of
the flexible axis of this project (``ε'' + ω² ε = -a``) is ``Amp / ω²`` (m).

Re-derived (see ``docs/peers.md``): eq. 14, 18-21 and the three rows of
Table 1 check out exactly.  Garbled or wrong in the text: eq. (5), second line,
``A_1 τ_1`` should be ``A_1 τ_2``; eq. (8) ``J_2 T_3²`` should be ``J_3 T_3²``;
eq. (23) ``(J_3 + J_4) e^{+ζω T_3}`` should be ``(-J_3 + J_4) e^{ζω T_3}`` with
the step convention of its other terms; eq. (26) has ``+J_1`` for its first
term (``-J_1`` by eq. 23) and ``(-J_1 + J_3)`` for ``(-J_2 + J_3)``.  None of
these reach eq. 28 or Table 1, which are correct.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .context import PeerContext, PeerSpec, placed
from .residual import free_deflection, residual_amplitude
from .trajectory import PiecewiseJerk

CONDITIONS = ("I", "II", "III")
#: The paper's example (§4.2, §5): 1 mm in 40 ms, 30 Hz mode, T_1 = 10 ms vs 1 ms.
PAPER_EXAMPLE = {"L": 1e-3, "f": 30.0, "T_SUM": 0.040, "T1_conventional": 0.010,
                 "T1_designed": 0.001}


def ratio_R(T_SUM: np.ndarray | float, T1: np.ndarray | float) -> np.ndarray | float:
    """Eq. (17): ``R = (T_SUM - 2 T_1) / (2 T_1)``."""
    return (np.asarray(T_SUM) - 2.0 * np.asarray(T1)) / (2.0 * np.asarray(T1))


def jerk_J1(L: float, T_SUM: np.ndarray | float, T1: np.ndarray | float,
            condition: str = "III") -> np.ndarray | float:
    """First jerk ``J_1`` (m/s³) that moves ``L`` in ``T_SUM`` (eq. 19, 20, 21)."""
    R = ratio_R(T_SUM, T1)
    T1 = np.asarray(T1)
    T_SUM = np.asarray(T_SUM)
    if condition == "I":
        A1 = 2.0 * L / (T_SUM * T1)
    elif condition == "II":
        A1 = L / ((0.5 + R + 0.5 * R * R) * T1 * T1)
    elif condition == "III":
        A1 = 6.0 * L / ((2.0 * R + 1.0) * T_SUM * T1)
    else:
        raise ValueError(f"condition must be one of {CONDITIONS}, got {condition!r}")
    return A1 / T1


def amplitude_table1(condition: str, J1: np.ndarray | float, T1: np.ndarray | float,
                     T_SUM: np.ndarray | float, omega_n: float) -> np.ndarray | float:
    """Residual amplitude of Table 1 (undamped), as printed (m/s²).

    Condition III returns eq. (28) with its sign; I and II return the
    (non-negative) modulus.
    """
    R = ratio_R(T_SUM, T1)
    w = omega_n
    T1 = np.asarray(T1)
    if condition == "I":
        re = (-np.cos(2 * w * T1) + 2 * np.cos(w * T1) - 2 / R**2 * np.cos(R * w * T1)
              + 1 / R**2 * np.cos(2 * R * w * T1) - (1 - 1 / R**2))
        im = (-np.sin(2 * w * T1) + 2 * np.sin(w * T1) + 2 / R**2 * np.sin(R * w * T1)
              - 1 / R**2 * np.sin(2 * R * w * T1))
        return np.asarray(J1) / w * np.sqrt(re**2 + im**2)
    if condition == "II":
        re = ((-1 + 1 / R) * np.cos(w * (1 + R) * T1) - (-1 - 1 / R) * np.cos(w * R * T1)
              - (1 + 1 / R) * np.cos(w * T1) - (-1 + 1 / R))
        im = ((-1 - 1 / R) * np.sin(w * (1 + R) * T1) - (-1 - 1 / R) * np.sin(w * R * T1)
              + (1 + 1 / R) * np.sin(w * T1))
        return np.asarray(J1) / w * np.sqrt(re**2 + im**2)
    if condition == "III":
        return 2 * np.asarray(J1) / w * ((1 + 1 / R) * np.sin(w * R * T1)
                                         - np.sin(w * np.asarray(T_SUM) / 2))
    raise ValueError(f"condition must be one of {CONDITIONS}, got {condition!r}")


@dataclass(frozen=True)
class SatoProfile:
    """A four-jerk-time positioning profile of Sato & Shirase.

    Attributes
    ----------
    condition : {"I", "II", "III"}
    L, T_SUM : float
        Distance (m) and total positioning time (s).
    T : tuple of 4 float
        Jerk times T_1 .. T_4 (s).
    J : tuple of 4 float
        Jerks J_1 .. J_4 (m/s³).
    A1, A2 : float
        Peak acceleration and deceleration (m/s², A2 < 0).
    R : float
        Eq. (17).
    """

    condition: str
    L: float
    T_SUM: float
    T: tuple[float, float, float, float]
    J: tuple[float, float, float, float]
    A1: float
    A2: float
    R: float
    params: dict[str, Any] = field(default_factory=dict)

    def motion(self, t0: float = 0.0, name: str | None = None) -> PiecewiseJerk:
        """Return the exact profile (starting at ``t0`` from 0)."""
        return PiecewiseJerk.from_jerk(
            self.T, self.J, t0=t0,
            name=name or f"Sato cond. {self.condition} (T1 = {1e3 * self.T[0]:.3g} ms)",
            params=dict(self.params))

    def amplitude(self, f: float) -> float:
        """Table 1 amplitude at mode frequency ``f`` (Hz), as printed (m/s², signed for III)."""
        return float(amplitude_table1(self.condition, self.J[0], self.T[0], self.T_SUM,
                                      2 * np.pi * f))

    def deflection_amplitude(self, f: float) -> float:
        """Residual deflection of the mode from Table 1, ``|Amp| / ω²`` (m)."""
        return abs(self.amplitude(f)) / (2 * np.pi * f) ** 2

    def plot(self, title: str | None = None):
        """Position, velocity, acceleration and jerk; return the Figure."""
        return self.motion().plot(title=title)


def sato_profile(L: float, T_SUM: float, T1: float, condition: str = "III") -> SatoProfile:
    """Build the profile of one condition (eq. 14-21).

    Parameters
    ----------
    L : float
        Distance (m, > 0).
    T_SUM : float
        Total positioning time (s).
    T1 : float
        First jerk time (s), ``0 < T1 < T_SUM / 2``.
    condition : {"I", "II", "III"}

    Returns
    -------
    SatoProfile
    """
    if condition not in CONDITIONS:
        raise ValueError(f"condition must be one of {CONDITIONS}, got {condition!r}")
    if not (L > 0 and T_SUM > 0):
        raise ValueError("L and T_SUM must be positive")
    if not 0.0 < T1 < T_SUM / 2:
        raise ValueError(f"T1 must be in (0, T_SUM/2) = (0, {T_SUM / 2:g}) s, got {T1:g}")
    R = float(ratio_R(T_SUM, T1))
    T2nd = R * T1
    T = {"I": (T1, T1, T2nd, T2nd), "II": (T1, T2nd, T1, T2nd),
         "III": (T1, T2nd, T2nd, T1)}[condition]
    J1 = float(jerk_J1(L, T_SUM, T1, condition))
    A1 = J1 * T1
    J2 = -A1 / T[1]
    A2 = -A1 * (T[0] + T[1]) / (T[2] + T[3])
    J3 = A2 / T[2]
    J4 = -A2 / T[3]
    return SatoProfile(condition, L, T_SUM, T, (J1, J2, J3, J4), A1, A2, R,
                       {"L": L, "T_SUM": T_SUM, "T1": T1, "condition": condition})


@dataclass
class AmplitudeMap:
    """Residual amplitude over (T_1, T_SUM) for the three conditions (Fig. 8).

    Attributes
    ----------
    L, f : float
        Distance (m) and mode frequency (Hz).
    T1, T_SUM : ndarray
        Grid axes (s).
    amp : dict of str to ndarray
        ``|Amp|`` of Table 1 (m/s²), shape ``(len(T_SUM), len(T1))``; NaN
        where ``T1 >= T_SUM / 2`` (the white area of the figure).
    """

    L: float
    f: float
    T1: np.ndarray
    T_SUM: np.ndarray
    amp: dict[str, np.ndarray]

    def deflection(self, condition: str) -> np.ndarray:
        """Residual deflection ``|Amp| / ω²`` (m)."""
        return self.amp[condition] / (2 * np.pi * self.f) ** 2

    def t1_effect(self, condition: str, T1_short: float) -> np.ndarray:
        """Per ``T_SUM`` row: amplitude at ``T1_short`` / amplitude at ``T1 = T_SUM/4``.

        ``T1 = T_SUM/4`` is the conventional profile (four equal jerk times, the
        same for the three conditions).  Below 1: shortening T_1 helps.
        """
        out = np.empty(self.T_SUM.size)
        for i, ts in enumerate(self.T_SUM):
            w = 2 * np.pi * self.f
            a_short = abs(amplitude_table1(condition, jerk_J1(self.L, ts, T1_short, condition),
                                           T1_short, ts, w))
            a_conv = abs(amplitude_table1(condition, jerk_J1(self.L, ts, ts / 4, condition),
                                          ts / 4, ts, w))
            out[i] = a_short / a_conv
        return out

    def plot(self, title: str | None = None):
        """Three maps (µm of deflection), as Fig. 8 (a)-(c); return the Figure."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        fig, axes = plt.subplots(1, 3, figsize=(13, 4), sharey=True)
        vmax = max(np.nanmax(self.deflection(c)) for c in CONDITIONS) * 1e6
        for ax, c in zip(axes, CONDITIONS, strict=True):
            im = ax.pcolormesh(1e3 * self.T1, 1e3 * self.T_SUM, 1e6 * self.deflection(c),
                               shading="auto", vmin=0.0, vmax=vmax, cmap="viridis")
            ax.set_title({"I": "(a) Condition I: T1 = T2, T3 = T4",
                          "II": "(b) Condition II: T1 = T3, T2 = T4",
                          "III": "(c) Condition III: T1 = T4, T2 = T3"}[c], fontsize="small")
            ax.set_xlabel("T1 [ms]")
        axes[0].set_ylabel("T_SUM [ms]")
        fig.colorbar(im, ax=axes, label="residual deflection [µm]")
        fig.suptitle(title or f"Residual amplitude map, L = {1e3 * self.L:g} mm, "
                     f"f = {self.f:g} Hz (Sato & Shirase 2021, Fig. 8)")
        return fig


def amplitude_map(L: float = 1e-3, f: float = 30.0, T1: np.ndarray | None = None,
                  T_SUM: np.ndarray | None = None) -> AmplitudeMap:
    """Fig. 8: Table 1 amplitudes over a grid of (T_1, T_SUM).

    Parameters
    ----------
    L : float
        Distance (m); default 1 mm as in the paper.
    f : float
        Mode frequency (Hz); default 30 Hz.
    T1, T_SUM : ndarray, optional
        Grid axes (s); default T_1 = 1..50 ms, T_SUM = 20..100 ms by 1 ms.
    """
    T1 = np.arange(1, 51) * 1e-3 if T1 is None else np.asarray(T1, dtype=float)
    T_SUM = np.arange(20, 101) * 1e-3 if T_SUM is None else np.asarray(T_SUM, dtype=float)
    TT1, TTS = np.meshgrid(T1, T_SUM)
    valid = TT1 < TTS / 2
    w = 2 * np.pi * f
    amp = {}
    with np.errstate(divide="ignore", invalid="ignore"):
        for c in CONDITIONS:
            a = np.abs(amplitude_table1(c, jerk_J1(L, TTS, TT1, c), TT1, TTS, w))
            amp[c] = np.where(valid, a, np.nan)
    return AmplitudeMap(L, f, T1, T_SUM, amp)


@dataclass
class Fig10Result:
    """Conventional against designed jerk times (§5, Fig. 10).

    Attributes
    ----------
    conventional, designed : SatoProfile
    f, zeta : float
        Mode (Hz) and damping ratio of the simulation.
    amp_formula : tuple of float
        |Amp| of eq. 28 (m/s²), conventional then designed (undamped).
    deflection : tuple of float
        Residual deflection (m) computed exactly on the mode (with ``zeta``).
    """

    conventional: SatoProfile
    designed: SatoProfile
    f: float
    zeta: float
    amp_formula: tuple[float, float]
    deflection: tuple[float, float]

    @property
    def reduction(self) -> float:
        """Residual reduction ``1 - designed/conventional`` (fraction), from the simulation."""
        return 1.0 - self.deflection[1] / self.deflection[0]

    @property
    def reduction_formula(self) -> float:
        """Residual reduction from eq. 28."""
        return 1.0 - self.amp_formula[1] / self.amp_formula[0]

    def plot(self, title: str | None = None):
        """Acceleration profiles and the residual deflection of both (Fig. 9-10)."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import


        fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 6))
        t_after = np.linspace(0, 0.2, 800)
        for prof, lab in ((self.conventional, "conventional"), (self.designed, "designed")):
            m = prof.motion()
            t = np.linspace(0, prof.T_SUM, 400)
            ax1.plot(1e3 * t, m.evaluate(t)[2], label=f"{lab}, T1 = {1e3 * prof.T[0]:g} ms")
            eps = free_deflection(m, self.f, self.zeta, m.t_end + t_after)
            ax2.plot(1e3 * (m.t_end + t_after), 1e6 * eps, label=lab)
        ax1.set_xlabel("t [ms]")
        ax1.set_ylabel("a [m/s²]")
        ax1.legend(fontsize="small")
        ax1.grid(True, alpha=0.3)
        ax2.set_xlabel("t [ms]")
        ax2.set_ylabel("residual deflection [µm]")
        ax2.legend(fontsize="small")
        ax2.grid(True, alpha=0.3)
        fig.suptitle(title or f"Sato & Shirase Fig. 10: T_SUM = {1e3 * self.designed.T_SUM:g} ms, "
                     f"{self.f:g} Hz; residual reduced by {100 * self.reduction:.1f} %")
        fig.tight_layout()
        return fig


def fig10_example(L: float = 1e-3, f: float = 30.0, T_SUM: float = 0.040,
                  T1_conventional: float = 0.010, T1_designed: float = 0.001,
                  zeta: float = 0.0) -> Fig10Result:
    """Compute the paper's example: Condition III, T_1 = 10 ms (conventional) against 1 ms.

    The residual is computed exactly on the mode ``ε'' + 2ζωε' + ω²ε = -a``
    (:func:`harness.peers.residual.residual_amplitude`), and from eq. 28.
    """
    conv = sato_profile(L, T_SUM, T1_conventional, "III")
    des = sato_profile(L, T_SUM, T1_designed, "III")
    amp = (abs(conv.amplitude(f)), abs(des.amplitude(f)))
    defl = (float(residual_amplitude(conv.motion(), f, zeta)),
            float(residual_amplitude(des.motion(), f, zeta)))
    return Fig10Result(conv, des, f, zeta, amp, defl)


def sato_design(distance: float, v_max: float, a_max: float, f: float, Te: float,
                T_SUM_min: float) -> tuple[float, float]:
    """Pick ``(T_SUM, T_1)`` of a Condition III profile for a move (see the module notes).

    Condition III: peak velocity ``1.5 L / (T_SUM - T_1)``, peak acceleration
    ``6 L / (T_SUM (T_SUM - T_1))`` (from eq. 18-19).

    Parameters
    ----------
    distance : float
        Move length (m, its magnitude is used).
    v_max, a_max : float
        Limits to keep (a_max: the smaller of acceleration and deceleration).
    f : float
        Mode frequency the jerk times are designed for (Hz).
    Te : float
        Grid of T_SUM and T_1 (s).
    T_SUM_min : float
        Shortest positioning time wanted (s).

    Returns
    -------
    T_SUM, T1 : float
    """
    L = abs(distance)
    n = int(math.ceil(T_SUM_min / Te - 1e-9))
    for _ in range(1_000_000):
        T_SUM = n * Te
        t1_max = min(T_SUM - 1.5 * L / v_max, T_SUM - 6.0 * L / (a_max * T_SUM),
                     T_SUM / 2 - Te)
        k_max = int(math.floor(t1_max / Te + 1e-9))
        if k_max >= 1:
            T1 = Te * np.arange(1, k_max + 1)
            amp = np.abs(amplitude_table1("III", jerk_J1(L, T_SUM, T1, "III"), T1, T_SUM,
                                          2 * math.pi * f))
            return T_SUM, float(T1[int(np.argmin(amp))])
        n += 1
    raise RuntimeError("no feasible Sato profile")  # pragma: no cover


def build_sato(ctx: PeerContext, name: str) -> tuple[PiecewiseJerk, PeerSpec]:
    """Peer "Sato III": Condition III, T_SUM = the JL's motion time (longer if the limits ask).

    T_1 (a whole number of samples) minimises eq. 28 at the end-of-motion frequency.
    """
    m, s = ctx.sc.move, ctx.sc.simulation
    T_SUM, T1 = sato_design(m.distance, m.v_max, min(m.a_max, m.d_max), ctx.f_end, s.Te,
                            ctx.motion_time_JL)
    prof = sato_profile(abs(m.distance), T_SUM, T1, "III")
    mot = placed(prof.motion(name=name), m.t_start, m.x0, ctx.sign)
    return mot, PeerSpec(name, f"T_SUM = {T_SUM * 1e3:.0f} ms, T1 = {T1 * 1e3:.0f} ms "
                               f"(eq. 28 minimised at {ctx.f_end:.4g} Hz)",
                         {"T_SUM": T_SUM, "T1": T1, "f": ctx.f_end})
