"""The papers' closed forms, as the claims use them (re-derived where garbled).

Paper ``000`` is Béarée & Olabi 2013 (RCIM 29(2)), paper ``003`` is Béarée 2014
(Assises MUGV, in French).  Every function names its equation.  Where the
extracted text of an equation is garbled or wrong, the docstring says so and
gives the derivation actually used; :data:`DERIVATIONS` collects these notes
for the report.

Units are SI: s, m, m/s², m/s³, rad/s for ``omega``, Hz for ``f``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]

# --------------------------------------------------------------------------
# Moving-average filter (000 eq. 5, 7, 8)
# --------------------------------------------------------------------------


def ma_continuous(f: ArrayLike, T_F: float) -> ComplexArray:
    """Frequency response of the continuous moving average, 000 eq. (5).

    ``F(s) = (1 - exp(-T_F s)) / (T_F s)`` at ``s = j 2 pi f``, i.e.
    ``exp(-j pi f T_F) sinc(f T_F)`` (normalised sinc): zeros at
    ``f = k / T_F``, envelope ``1 / (pi f T_F)``.
    """
    f = np.asarray(f, dtype=float)
    return np.exp(-1j * np.pi * f * T_F) * np.sinc(f * T_F)


def ma_discrete(f: ArrayLike, N: int, Te: float) -> ComplexArray:
    """Frequency response of the N-tap moving average, 000 eq. (7)-(8).

    ``F(z) = (1 - z^-N) / (N (1 - z^-1))`` at ``z = exp(j 2 pi f Te)``:
    ``exp(-j pi f (N-1) Te) sin(pi f N Te) / (N sin(pi f Te))`` (Dirichlet
    kernel).  Zeros at ``f = k / (N Te)`` for ``k`` not a multiple of ``N``.
    """
    f = np.asarray(f, dtype=float)
    x = np.pi * f * Te
    s = np.sin(x)
    with np.errstate(invalid="ignore", divide="ignore"):
        mag = np.where(np.abs(s) < 1e-300, 1.0, np.sin(N * x) / (N * s))
    return np.exp(-1j * x * (N - 1)) * mag


def ma_zero_frequencies(T_F: float, k: ArrayLike) -> FloatArray:
    """Notch frequencies ``k / T_F`` of the continuous moving average (Hz)."""
    return np.asarray(k, dtype=float) / T_F


# --------------------------------------------------------------------------
# Residual vibration of impulse / jerk-step series (000 eq. 17-21)
# --------------------------------------------------------------------------


def damped_omega(omega: ArrayLike, zeta: ArrayLike) -> FloatArray:
    """``omega_d = omega sqrt(1 - zeta^2)`` (rad/s)."""
    return np.asarray(omega, dtype=float) * np.sqrt(1.0 - np.asarray(zeta, dtype=float) ** 2)


def vib_impulses(omega: float, zeta: float, A: ArrayLike, T: ArrayLike) -> float:
    """Percentage vibration of an impulse series, 000 eq. (18), corrected.

    ``Vib = exp(-zeta omega T_n) |sum_i A_i exp(zeta omega T_i) exp(j omega_d T_i)|``

    is the free-oscillation amplitude left at ``T_n`` by impulses ``A_i`` at
    ``T_i`` on a mode (``omega``, ``zeta``), divided by the amplitude left by
    one unit impulse.  The extracted text defines ``T_n = sum_i T_i``; that is
    wrong: ``T_n`` is the time of the *last* impulse, ``max_i T_i`` (the
    exponential only moves the amplitude to the instant the series ends).
    Both readings coincide for the two-impulse series of eq. (20), which is
    why the paper's eq. (20) is right.
    """
    A = np.asarray(A, dtype=float)
    T = np.asarray(T, dtype=float)
    T_n = float(T.max())
    wd = float(damped_omega(omega, zeta))
    z = np.sum(A * np.exp(-zeta * omega * (T_n - T)) * np.exp(1j * wd * T))
    return float(abs(z))


def vib_jerk_stage(T_F: ArrayLike, omega: ArrayLike, zeta: ArrayLike = 0.0) -> FloatArray:
    """Residual of one constant-jerk stage relative to the AL step, 000 eq. (20)-(21).

    A stage raising the acceleration from 0 to ``a_max`` in ``T_F`` (jerk
    steps ``+a_max/T_F`` at 0 and ``-a_max/T_F`` at ``T_F``) leaves a free
    oscillation of amplitude

    ``a_max / (omega omega_d) * exp(-zeta omega T_F)
    sqrt(1 + exp(2 zeta omega T_F) - 2 exp(zeta omega T_F) cos(omega_d T_F)) / (omega T_F)``

    at ``T_F``, where ``a_max / (omega omega_d)`` is what an acceleration step
    ``a_max`` (the acceleration-limited profile, ``T_F -> 0``) leaves.  The
    returned ratio is the paper's eq. (20) divided by ``omega a_max``, the
    value eq. (20) takes when ``T_F -> 0``: the paper's Fig. 11 plots this
    ratio ("full scale corresponds to the acceleration-limited profile").

    For ``zeta = 0`` it reduces to ``|sin(omega T_F / 2) / (omega T_F / 2)|``:
    eq. (21) of the paper, whose text says "Eq. (9) is rewritten" (a typo
    for eq. (20)) and drops the absolute value; ``2 a_max/T_F sin(omega T_F/2)``
    follows from eq. (20) with ``zeta = 0`` because
    ``sqrt(2 - 2 cos x) = 2 |sin(x/2)|``.
    """
    T_F = np.asarray(T_F, dtype=float)
    omega = np.asarray(omega, dtype=float)
    zeta = np.asarray(zeta, dtype=float)
    wd = damped_omega(omega, zeta)
    x = zeta * omega * T_F
    with np.errstate(invalid="ignore", divide="ignore"):
        num = np.sqrt(np.maximum(np.exp(-2 * x) + 1.0 - 2.0 * np.exp(-x) * np.cos(wd * T_F),
                                 0.0))
        out = num / (omega * T_F)
    return np.where(T_F > 0, out, 1.0)


def vib_eq21_sinc(T_F: ArrayLike, omega: float) -> FloatArray:
    """000 eq. (21) normalised by ``omega a_max``: ``|sin(omega T_F/2) / (omega T_F/2)|``."""
    x = np.asarray(T_F, dtype=float) * omega / 2.0
    return np.abs(np.sinc(x / np.pi))


def jerk_series_residual(t_switch: ArrayLike, delta_j: ArrayLike, omega: float,
                         zeta: float) -> float:
    """Free-oscillation amplitude (m) after a series of jerk steps, 000 eq. (17)-(18).

    The reference jerk is ``sum_i delta_j[i] H(t - t_switch[i])`` (000 eq. 17
    with ``j_max A_i = delta_j[i]``).  Each jerk step is a unit impulse of
    snap whose oscillatory response on ``eps'' + 2 zeta omega eps' + omega^2
    eps = -q''`` has amplitude ``1 / (omega^2 omega_d)``; the series leaves,
    at its last switching time,

    ``exp(-zeta omega T_n) |sum_i delta_j[i] exp(zeta omega t_i) exp(j omega_d t_i)|
    / (omega^2 omega_d)``

    (eq. 18 with ``T_n`` the last switching time).  The amplitude is measured
    about the quasi-static deflection ``-a / omega^2`` of the acceleration
    ``a`` that follows (0 at the end of a move).
    """
    d = np.asarray(delta_j, dtype=float)
    t = np.asarray(t_switch, dtype=float)
    wd = float(damped_omega(omega, zeta))
    return vib_impulses(omega, zeta, d, t) / (omega**2 * wd)


def al_reference_amplitude(a: float, omega: float, zeta: float) -> float:
    """Free-oscillation amplitude (m) an acceleration step ``a`` leaves: ``a/(omega omega_d)``."""
    return abs(a) / (omega * float(damped_omega(omega, zeta)))


# --------------------------------------------------------------------------
# Acceleration spectra of the motion laws (003 eq. 6-16), P in m, T in s
# --------------------------------------------------------------------------


def _series(x: np.ndarray, coef) -> np.ndarray:
    """``sum_n coef(n) x^(2n+1)`` for n = 1..12 (|x| < 1: the terms fall below 1e-20)."""
    out = np.zeros_like(x)
    for n in range(12, 0, -1):
        out = out + coef(n) * x ** (2 * n + 1)
    return out


def _sin_minus_xcos(x: np.ndarray) -> np.ndarray:
    """``sin x - x cos x``, by its series ``sum (-1)^(n+1) 2n x^(2n+1)/(2n+1)!`` for |x| < 1."""
    series = _series(np.where(np.abs(x) < 1, x, 0.0),
                     lambda n: (-1) ** (n + 1) * 2 * n / math.factorial(2 * n + 1))
    return np.where(np.abs(x) < 1, series, np.sin(x) - x * np.cos(x))


def _quintic_core(x: np.ndarray) -> np.ndarray:
    """``(3 - x^2) sin x - 3 x cos x``; series ``x^5/15 - x^7/210 + ...`` for |x| < 1.

    Coefficient of ``x^(2n+1)``: ``(-1)^n (3/(2n+1)! + 1/(2n-1)! - 3/(2n)!)``
    (zero for n = 0, 1).
    """
    series = _series(np.where(np.abs(x) < 1, x, 0.0),
                     lambda n: (-1) ** n * (3 / math.factorial(2 * n + 1)
                                            + 1 / math.factorial(2 * n - 1)
                                            - 3 / math.factorial(2 * n)))
    return np.where(np.abs(x) < 1, series, (3.0 - x**2) * np.sin(x) - 3.0 * x * np.cos(x))


def cubic_acceleration(t: ArrayLike, P: float = 1.0, T: float = 1.0) -> FloatArray:
    """003 eq. (6): ``q''(t) = P/T^2 (6 - 12 t/T)`` on [0, T], 0 elsewhere."""
    t = np.asarray(t, dtype=float)
    return np.where((t >= 0) & (t <= T), P / T**2 * (6.0 - 12.0 * t / T), 0.0)


def quintic_acceleration(t: ArrayLike, P: float = 1.0, T: float = 1.0) -> FloatArray:
    """003 eq. (10): ``q''(t) = 60 P/T^3 (t - 3 t^2/T + 2 t^3/T^2)`` on [0, T]."""
    t = np.asarray(t, dtype=float)
    a = 60.0 * P / T**3 * (t - 3.0 * t**2 / T + 2.0 * t**3 / T**2)
    return np.where((t >= 0) & (t <= T), a, 0.0)


def spectrum_cubic(omega: ArrayLike, P: float = 1.0, T: float = 1.0) -> ComplexArray:
    """003 eq. (7): Fourier transform of the cubic law's acceleration (complex)."""
    w = np.asarray(omega, dtype=float)
    x = w * T / 2.0
    with np.errstate(invalid="ignore", divide="ignore"):
        # (2/T) sin x - omega cos x = (2/T)(sin x - x cos x), x = omega T/2
        core = (2.0 / T) * _sin_minus_xcos(x)
        out = 1j * 12.0 * P / (w**2 * T**2) * np.exp(-1j * x) * core
    return np.where(w == 0, 0.0 + 0.0j, out)


def spectrum_cubic_mag(Omega: ArrayLike, P: float = 1.0, T: float = 1.0) -> FloatArray:
    """003 eq. (9): ``6P/(T pi^2 Omega^2) |sin(pi Omega) - pi Omega cos(pi Omega)|``.

    ``Omega = omega T / (2 pi)``.  Follows from eq. (8) (checked).
    """
    x = np.pi * np.asarray(Omega, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = 6.0 * P / (T * x**2) * np.abs(_sin_minus_xcos(x))
    return np.where(x == 0, 0.0, out)


def spectrum_quintic_mag(Omega: ArrayLike, P: float = 1.0, T: float = 1.0) -> FloatArray:
    """003 eq. (11): magnitude of the quintic law's acceleration spectrum.

    ``30P/(T pi^4 Omega^4) |(3 - pi^2 Omega^2) sin(pi Omega) - 3 pi Omega cos(pi Omega)|``.
    Near ``Omega = 0`` the bracket cancels (it is ``x^5/15 - x^7/210 + ...``,
    ``x = pi Omega``): its series is used below ``x = 1``.
    """
    x = np.pi * np.asarray(Omega, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = 30.0 * P / (T * x**4) * np.abs(_quintic_core(x))
    return np.where(x == 0, 0.0, out)


def spectrum_al_mag(Omega: ArrayLike, alpha: float, P: float = 1.0, T: float = 1.0
                    ) -> FloatArray:
    """003 eq. (15): magnitude of the acceleration-limited law's acceleration spectrum.

    ``2P/((1-alpha) alpha T pi Omega) |sin((1-alpha) pi Omega) sin(alpha pi Omega)|``.
    Acceleration-limited law with ``T_a = alpha T`` and ``A_max = P/(alpha (1-alpha) T^2)``
    (eq. 13).  Eq. (14) writes the transform without the factor
    ``exp(-j omega T/2)`` (time origin at mid-move); the magnitude is unaffected.
    """
    x = np.pi * np.asarray(Omega, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = 2.0 * P / ((1 - alpha) * alpha * T * x) * np.abs(
            np.sin((1 - alpha) * x) * np.sin(alpha * x))
    return np.where(x == 0, 0.0, out)


def spectrum_jl_mag(Omega: ArrayLike, alpha: float, beta: float, P: float = 1.0,
                    T: float = 1.0) -> FloatArray:
    """003 eq. (16): jerk-limited law, ``T_a = alpha T``, jerk time ``T_j = beta T_a``.

    ``2P / ((1-alpha)(1-beta) beta alpha^2 T pi^2 Omega^2)
    |sin((1-alpha) pi Omega) sin(alpha (1-beta) pi Omega) sin(alpha beta pi Omega)|``

    Re-derived (and confirmed): the acceleration is a trapezoid
    ``A rect(T_a - T_j) * rect(T_j)/T_j`` minus its copy delayed by
    ``T - T_a``, with ``A = P / (alpha (1-beta) (1-alpha) T^2)``.  It is the
    AL law with ``T_a' = T_a - T_j`` and ``T' = T - T_j`` times
    ``|sinc(omega T_j / 2)|``: :func:`jl_equals_al_times_filter`.
    """
    x = np.pi * np.asarray(Omega, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = 2.0 * P / ((1 - alpha) * (1 - beta) * beta * alpha**2 * T * x**2) * np.abs(
            np.sin((1 - alpha) * x) * np.sin(alpha * (1 - beta) * x) * np.sin(alpha * beta * x))
    return np.where(x == 0, 0.0, out)


def jl_equals_al_times_filter(Omega: ArrayLike, alpha: float, beta: float, P: float = 1.0,
                              T: float = 1.0) -> FloatArray:
    """Eq. (15) for the JL's acceleration-limited input, times the filter's ``|sinc|``.

    The JL law (``alpha``, ``beta``, ``T``) is the AL law with
    ``T' = T - T_j``, ``alpha' = (T_a - T_j)/T'`` filtered by a moving average
    of length ``T_j = alpha beta T`` (003 Fig. 7, 000 §2.1).  Equal to
    :func:`spectrum_jl_mag` identically.
    """
    T_j = alpha * beta * T
    T_al = T - T_j
    alpha_al = (alpha * T - T_j) / T_al
    Omega = np.asarray(Omega, dtype=float)
    f = Omega / T
    return spectrum_al_mag(f * T_al, alpha_al, P, T_al) * np.abs(np.sinc(f * T_j))


@dataclass(frozen=True)
class LawParameters:
    """Generator FMU parameters reproducing a law of 003 §3 (P = distance, T = duration)."""

    distance: float
    v_max: float
    a_max: float
    T_F: float

    def fmu_params(self, profile: int) -> dict[str, float]:
        """Parameters for :func:`harness.fmu.runner.generate`."""
        p = {"profile": profile, "distance": self.distance, "v_max": self.v_max,
             "a_max": self.a_max, "d_max": self.a_max, "v0": 0.0, "v_e": 0.0}
        if self.T_F > 0:
            p["T_F1"] = self.T_F
        return p


def al_law(alpha: float, P: float = 1.0, T: float = 1.0) -> LawParameters:
    """AL law of 003 eq. (12)-(13): ``A_max = P/(alpha(1-alpha)T^2)``, ``V = A_max alpha T``."""
    A = P / (alpha * (1 - alpha) * T**2)
    return LawParameters(P, A * alpha * T, A, 0.0)


def jl_law(alpha: float, beta: float, P: float = 1.0, T: float = 1.0) -> LawParameters:
    """JL law of 003 eq. (16)-(17) as the FMU's AL input plus a moving average ``T_j``.

    ``T_j = beta alpha T``, ``A_max = P/(alpha(1-beta)(1-alpha)T^2)``,
    ``V = P/((1-alpha)T)``; the FMU plans the AL profile of duration
    ``T - T_j`` and its filter adds ``T_j``.
    """
    if not 0 < beta < 1:
        raise ValueError("beta must be in (0, 1) for a constant-acceleration plateau")
    A = P / (alpha * (1 - beta) * (1 - alpha) * T**2)
    return LawParameters(P, P / ((1 - alpha) * T), A, alpha * beta * T)


# --------------------------------------------------------------------------
# Vibration filters (003 eq. 18-22)
# --------------------------------------------------------------------------


@dataclass(frozen=True)
class ZVShaper:
    """Zero-vibration shaper of 003 eq. (20)-(21).

    ``A_1 = 1/(1+K)``, ``A_2 = K/(1+K)`` at ``t = 0`` and ``T_ZV`` with
    ``T_ZV = pi / (omega sqrt(1 - zeta^2))`` and
    ``K = exp(-zeta pi / sqrt(1 - zeta^2))``.  (The matrix of eq. (20) is
    garbled in the extracted text; this is the standard ZV shaper it
    describes, amplitudes summing to 1.)
    """

    A1: float
    A2: float
    T_ZV: float
    K: float

    @classmethod
    def tuned(cls, omega: float, zeta: float) -> ZVShaper:
        """Shaper for the mode (``omega`` rad/s, ``zeta``)."""
        r = np.sqrt(1.0 - zeta**2)
        K = float(np.exp(-zeta * np.pi / r))
        return cls(1.0 / (1.0 + K), K / (1.0 + K), float(np.pi / (omega * r)), K)

    def magnitude(self, omega: ArrayLike) -> FloatArray:
        """003 eq. (22): ``sqrt(4 A1 A2 cos^2(omega T_ZV / 2) + (A1 - A2)^2)``."""
        w = np.asarray(omega, dtype=float)
        return np.sqrt(4 * self.A1 * self.A2 * np.cos(w * self.T_ZV / 2) ** 2
                       + (self.A1 - self.A2) ** 2)

    def response(self, omega: ArrayLike) -> ComplexArray:
        """003 eq. (21) at ``s = j omega``: ``A1 + A2 exp(-j omega T_ZV)``."""
        w = np.asarray(omega, dtype=float)
        return self.A1 + self.A2 * np.exp(-1j * w * self.T_ZV)


def biquad_inverse_tf(omega1: float, zeta1: float, tau_a: float, tau_b: float):
    """Inverse-model filter of 003 eq. (18), normalised to unit static gain.

    Eq. (18) as printed, ``(s^2 + 2 zeta omega s + omega^2) / ((1 + tau_a s)(1 + tau_b s))``,
    has static gain ``omega^2``: it inverts the modal denominator but would
    scale a position reference by ``omega^2``.  As a trajectory prefilter it
    must pass the final position unchanged, so we divide by ``omega^2``.
    """
    import control as ct  # deferred: python-control is heavy to import

    num = np.array([1.0, 2 * zeta1 * omega1, omega1**2]) / omega1**2
    den = np.polymul([tau_a, 1.0], [tau_b, 1.0])
    return ct.tf(num, den)


def notch_tf(omega_a: float, omega_b: float, Q: float):
    """Notch filter of 003 eq. (19): ``(s^2 + omega_a^2) / (s^2 + omega_b/Q s + omega_b^2)``."""
    import control as ct  # deferred: python-control is heavy to import

    return ct.tf([1.0, 0.0, omega_a**2], [1.0, omega_b / Q, omega_b**2])


def mode_tf(omega1: float, zeta1: float):
    """003 eq. (4): ``epsilon / q'' = -1 / (s^2 + 2 zeta omega s + omega^2)``."""
    import control as ct  # deferred: python-control is heavy to import

    return ct.tf([-1.0], [1.0, 2 * zeta1 * omega1, omega1**2])


PAPERS = {"000": "Béarée & Olabi 2013", "003": "Béarée 2014"}
"""The papers' file numbers (``000 eq. (18)``) and how the report names them."""


def paper_ref(key: str) -> str:
    """Name the paper of a reference such as ``000 eq. (18)``: ``Béarée & Olabi 2013, eq. (18)``.

    The report shows these, never the file numbers of the papers.
    """
    num, _, rest = key.partition(" ")
    return f"{PAPERS[num]}, {rest}" if num in PAPERS and rest else key


DERIVATIONS: dict[str, str] = {
    "000 eq. (18)": (
        "The text defines T_n = sum_i T_i. T_n must be the time of the last impulse "
        "(max_i T_i): exp(-zeta omega T_n) only carries the amplitude to the instant the "
        "series ends. Both coincide for the two-impulse series of eq. (20)."),
    "000 eq. (20)-(21)": (
        "Eq. (21) says 'Eq. (9) is rewritten': it is eq. (20) with zeta = 0, since "
        "sqrt(2 - 2 cos x) = 2|sin(x/2)|, giving Vib = 2 a_max/T_F |sin(omega T_F/2)| = "
        "omega a_max |sinc(omega T_F/2)| (the absolute value is missing in the text). "
        "Fig. 11's 'percentage' is Vib / (omega a_max), the value eq. (20) takes when "
        "T_F -> 0 (the acceleration-limited step). We derived the same ratio from the "
        "residues of -1/(s^2 (s^2 + 2 zeta omega s + omega^2)) (one snap impulse leaves "
        "1/(omega^2 omega_d)) against -1/(s (s^2 + ...)) (one acceleration step leaves "
        "1/(omega omega_d))."),
    "003 eq. (14)": (
        "The complex transform omits exp(-j omega T/2) (time origin at mid-move); "
        "eq. (15), a magnitude, is unaffected."),
    "003 eq. (16)": (
        "Re-derived from the trapezoidal acceleration (A = P/(alpha(1-beta)(1-alpha)T^2)); "
        "the printed formula is right. It equals eq. (15) for the JL's AL input "
        "(T' = T - T_j, alpha' = (alpha T - T_j)/T') times |sinc(omega T_j/2)|."),
    "003 eq. (16), beta > 1/2": (
        "Eq. (16) is symmetric in beta <-> 1 - beta. For beta > 1/2 the jerk time "
        "T_j = beta T_a exceeds the AL acceleration stage T_a - T_j: the convolution's ramps "
        "then last (1 - beta) T_a and the peak acceleration is A (1 - beta)/beta, i.e. the "
        "profile of beta' = 1 - beta. The FMU reproduces it with short_stage = 2; its default "
        "(short_stage = 1) stretches the stage instead, a longer move with the same jerk time."),
    "003 eq. (18)": (
        "The inverse-model biquad as printed has static gain omega_1^2; as a position "
        "prefilter it is divided by omega_1^2 (unit static gain)."),
    "003 eq. (20)": (
        "The impulse matrix is garbled in the text; it is the standard ZV shaper "
        "A = [1/(1+K), K/(1+K)] at t = [0, T_ZV]. Eq. (22) checked: "
        "|A1 + A2 exp(-j w T)|^2 = (A1 - A2)^2 + 4 A1 A2 cos^2(w T/2)."),
    "003 §4.1 (ZV minima)": (
        "The text places the ZV shaper's attenuation at (2k+1) omega_1; the minima of "
        "|F_ZV(j omega)| are at (2k+1) pi/T_ZV = (2k+1) omega_d (omega_1 sqrt(1-zeta^2)), and "
        "they are not zeros when zeta > 0 (depth (1-K)/(1+K)): the ZV cancels the damped "
        "pole, off the j omega axis."),
}
"""Garbled or wrong equations of the papers and what the claims use instead."""
