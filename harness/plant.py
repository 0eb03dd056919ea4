"""The flexible axis: second-order modes driven by the reference acceleration.

Model (Béarée 2014, eq. 3-4; Béarée & Olabi 2013, §3.1): the elastic
deflection ε of the load obeys, for each mode,

    ε̈ + 2ζω ε̇ + ω² ε = -g q̈

where q̈ is the reference acceleration (m/s²), ω = 2πf and g a participation
factor (1 by default: the paper's equation).  The load position is q + Σ ε_i.

Time stepping
-------------
The generator's acceleration is piecewise linear: its jerk is constant on
every sample interval.  Over one step [t_k, t_k + h] the input is therefore
known exactly, q̈(t_k + τ) = u0 + s·τ, and the mode is advanced *exactly* (for
a frozen ω) as the sum of

* the particular solution for a linear input, ε_p(τ) = α + βτ with
  β = -g·s/ω² and α = (-g·u0 - 2ζωβ)/ω²;
* the free oscillation of the deviation from it, propagated by the
  closed-form transition matrix Φ(h) = exp(A·h) of the damped oscillator.

This is the exact discretisation of a piecewise-linear (first-order-hold)
input, not a zero-order hold: with a constant mode it reproduces the
continuous-time response at the samples to rounding error.

Scheduling (mode frequency following z(t))
------------------------------------------
python-control has no LPV facility.  When ω follows the Z position, each step
uses the exact transition above with ω frozen at its value at the *middle* of
the step, ω(z(t_k + h/2)) (the exponential midpoint rule, a second-order
Magnus integrator).  The state (ε, ε̇) is continuous across steps, as it is in
the time-varying ODE.  The local error is O(h³·dω/dt), the global error O(h²);
with h = 1 ms on a 5-20 Hz mode it is orders of magnitude below the 1 % the
harness promises: ``tests/test_plant.py`` checks it against
``scipy.integrate.solve_ivp`` (DOP853, rtol 1e-11) on the continuous
time-varying ODE, and checks the second-order convergence.  The Z position at
mid-step comes from the Z generator's output: the cubic Hermite interpolant of
(z, v_z) at both ends of the step, exact for the generator's piecewise-cubic
z(t) when the step is one sample.

Examples
--------
>>> import numpy as np
>>> from harness.plant import Mode, simulate_mode
>>> t = np.arange(0, 1.0, 1e-3)
>>> a = np.where(t < 0.5, 1.0, 0.0)   # samples of a piecewise-linear acceleration
>>> r = simulate_mode(t, a, Mode(f=5.0, zeta=0.02))
>>> r.eps.shape
(1000,)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # python-control and scipy.signal take ~1.5 s to import: loaded on use
    import control as ct  # deferred: python-control is heavy to import

__all__ = [
    "Mode",
    "ModeResponse",
    "ScheduledMode",
    "ScheduledPlant",
    "axis_ss",
    "free_amplitude",
    "free_response",
    "hermite_mid",
    "mode_ss",
    "simulate_mode",
    "step_mode",
    "step_mode_jerk",
    "transition",
    "transitions",
]


@dataclass(frozen=True)
class Mode:
    """A lightly damped vibration mode of the axis.

    Parameters
    ----------
    f : float
        Natural frequency (Hz), > 0.
    zeta : float
        Damping ratio, in [0, 1).
    gain : float
        Participation factor g of the mode: its deflection obeys
        ε̈ + 2ζω ε̇ + ω² ε = -g q̈ (1 = the paper's equation).
    """

    f: float
    zeta: float
    gain: float = 1.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.f) and self.f > 0):
            raise ValueError(f"mode frequency must be > 0 Hz, got {self.f!r}")
        if not (0.0 <= self.zeta < 1.0):
            raise ValueError(f"damping ratio must be in [0, 1), got {self.zeta!r}")

    @property
    def omega(self) -> float:
        """Natural angular frequency ω = 2πf (rad/s)."""
        return 2.0 * math.pi * self.f

    @property
    def omega_d(self) -> float:
        """Damped angular frequency ω√(1-ζ²) (rad/s)."""
        return self.omega * math.sqrt(1.0 - self.zeta**2)

    @property
    def sigma(self) -> float:
        """Decay rate ζω (1/s)."""
        return self.zeta * self.omega

    @property
    def period(self) -> float:
        """Natural period 1/f (s): the jerk time that cancels the mode (§3.1)."""
        return 1.0 / self.f


def mode_ss(mode: Mode) -> ct.StateSpace:
    """State-space model of one mode: input q̈ (m/s²), output ε (m).

    States (ε, ε̇); ε̈ + 2ζω ε̇ + ω² ε = -g q̈ (Béarée 2014, eq. 3-4).

    Parameters
    ----------
    mode : Mode

    Returns
    -------
    control.StateSpace
        Continuous-time, named signals ``qdd`` → ``eps``.
    """
    import control as ct  # deferred: python-control is heavy to import

    w = mode.omega
    A = [[0.0, 1.0], [-w * w, -2.0 * mode.zeta * w]]
    B = [[0.0], [-mode.gain]]
    C = [[1.0, 0.0]]
    return ct.ss(A, B, C, [[0.0]], inputs=["qdd"], outputs=["eps"], states=["eps", "deps"])


def axis_ss(modes: Sequence[Mode]) -> ct.StateSpace:
    """All modes in parallel: input q̈, output the total deflection Σ ε_i.

    Parameters
    ----------
    modes : sequence of Mode

    Returns
    -------
    control.StateSpace
        2·len(modes) states (ε_i, ε̇_i), input ``qdd``, output ``eps``.
    """
    import control as ct  # deferred: python-control is heavy to import

    if not modes:
        raise ValueError("at least one mode is needed")
    n = len(modes)
    A = np.zeros((2 * n, 2 * n))
    B = np.zeros((2 * n, 1))
    C = np.zeros((1, 2 * n))
    states = []
    for i, m in enumerate(modes):
        w = m.omega
        A[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = [[0.0, 1.0], [-w * w, -2.0 * m.zeta * w]]
        B[2 * i + 1, 0] = -m.gain
        C[0, 2 * i] = 1.0
        states += [f"eps{i}", f"deps{i}"]
    return ct.ss(A, B, C, [[0.0]], inputs=["qdd"], outputs=["eps"], states=states)


# --------------------------------------------------------------- one step


def transition(omega: float, zeta: float, h: float) -> tuple[float, float, float, float]:
    """Closed-form state-transition matrix Φ = exp(A h) of the damped oscillator.

    Parameters
    ----------
    omega : float
        Natural angular frequency (rad/s), > 0.
    zeta : float
        Damping ratio in [0, 1).
    h : float
        Time step (s).

    Returns
    -------
    tuple of float
        (Φ11, Φ12, Φ21, Φ22) for the state (ε, ε̇).
    """
    sig = zeta * omega
    wd = omega * math.sqrt(1.0 - zeta * zeta)
    e = math.exp(-sig * h)
    c = math.cos(wd * h)
    s = math.sin(wd * h) / wd
    return (e * (c + sig * s), e * s, -e * omega * omega * s, e * (c - sig * s))


def transitions(omega: np.ndarray, zeta: np.ndarray, h: float) -> np.ndarray:
    """:func:`transition` for arrays of modes (the same operations), shape (..., 2, 2).

    Parameters
    ----------
    omega, zeta : ndarray
        Natural angular frequencies (rad/s) and damping ratios, broadcast together.
    h : float
        Time step (s).

    Returns
    -------
    ndarray
        Φ for each mode, ``[..., i, j]`` = Φ_(i+1)(j+1).
    """
    sig = zeta * omega
    wd = omega * np.sqrt(1.0 - zeta * zeta)
    e = np.exp(-sig * h)
    c = np.cos(wd * h)
    s = np.sin(wd * h) / wd
    phi = np.empty((*np.shape(sig), 2, 2))
    phi[..., 0, 0] = e * (c + sig * s)
    phi[..., 0, 1] = e * s
    phi[..., 1, 0] = -e * omega * omega * s
    phi[..., 1, 1] = e * (c - sig * s)
    return phi


def step_mode(
    eps: float, deps: float, omega: float, zeta: float, gain: float, h: float,
    u0: float, u1: float,
) -> tuple[float, float]:
    """Advance one mode exactly over a step with a linear input.

    The input q̈ goes linearly from ``u0`` to ``u1`` over ``h``; ω is constant
    over the step.

    Parameters
    ----------
    eps, deps : float
        State at the start of the step (m, m/s).
    omega, zeta, gain : float
        Mode parameters (rad/s, -, -).
    h : float
        Step (s).
    u0, u1 : float
        Reference acceleration at the start and end of the step (m/s²).

    Returns
    -------
    tuple of float
        (ε, ε̇) at the end of the step.
    """
    return step_mode_jerk(eps, deps, omega, zeta, gain, h, u0, (u1 - u0) / h)


def step_mode_jerk(
    eps: float, deps: float, omega: float, zeta: float, gain: float, h: float,
    u0: float, jerk: float,
) -> tuple[float, float]:
    """Advance one mode exactly over a step whose input has a constant jerk.

    The input is q̈(t_k + τ) = ``u0`` + ``jerk``·τ over the step: the
    generator's own semantics (``a`` at a sample, ``j`` over the sample
    interval that starts there), exact for every profile when the step is one
    sample, AL's acceleration steps included.  Same formula as
    :func:`step_mode` with the slope given instead of the end value.

    Parameters
    ----------
    eps, deps : float
        State at the start of the step (m, m/s).
    omega, zeta, gain : float
        Mode parameters (rad/s, -, -).
    h : float
        Step (s).
    u0 : float
        Reference acceleration at the start of the step (m/s²).
    jerk : float
        Reference jerk over the step (m/s³).

    Returns
    -------
    tuple of float
        (ε, ε̇) at the end of the step.
    """
    sig = zeta * omega
    w2 = omega * omega
    wd = omega * math.sqrt(1.0 - zeta * zeta)
    e = math.exp(-sig * h)
    c = math.cos(wd * h)
    s = math.sin(wd * h) / wd
    beta = -gain * jerk / w2
    alpha = (-gain * u0 - 2.0 * sig * beta) / w2
    d1 = eps - alpha
    d2 = deps - beta
    return (alpha + beta * h + e * ((c + sig * s) * d1 + s * d2),
            beta + e * (-w2 * s * d1 + (c - sig * s) * d2))


def hermite_mid(z0: float, v0: float, z1: float, v1: float, h: float) -> float:
    """Value at mid-step of the cubic Hermite interpolant of (z, v) at both ends.

    Exact for a cubic z(t), hence for the generator's output over one sample.
    """
    return 0.5 * (z0 + z1) + 0.125 * h * (v0 - v1)


# ----------------------------------------------------------- whole signals


@dataclass
class ModeResponse:
    """Response of one mode (or the sum of several) to a sampled acceleration.

    Attributes
    ----------
    t : ndarray
        Sample times (s).
    eps : ndarray
        Deflection ε (m).
    deps : ndarray
        Deflection rate ε̇ (m/s).
    f : ndarray
        Mode frequency applied over the interval that starts at each sample (Hz;
        the last value repeats).
    """

    t: np.ndarray
    eps: np.ndarray
    deps: np.ndarray
    f: np.ndarray

    def plot(self, title: str | None = None):
        """Plot ε(t) and f(t); return the figure."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        fig, (ax1, ax2) = plt.subplots(2, 1, sharex=True, figsize=(8, 5))
        ax1.plot(self.t, self.eps * 1e3)
        ax1.set_ylabel("ε [mm]")
        ax1.grid(True, alpha=0.3)
        ax2.plot(self.t, self.f)
        ax2.set_ylabel("f [Hz]")
        ax2.set_xlabel("t [s]")
        ax2.grid(True, alpha=0.3)
        fig.suptitle(title or "Deflection of the load")
        fig.tight_layout()
        return fig


def _lti_response(a: np.ndarray, h: float, mode: Mode, eps0: float, deps0: float):
    """Exact response for a constant mode, vectorised with lfilter."""
    from scipy.signal import lfilter  # deferred: scipy is heavy to import

    w = mode.omega
    p11, p12, p21, p22 = transition(w, mode.zeta, h)
    # x_{k+1} = Φ x_k + G0 u_k + G1 u_{k+1}: coefficients from step_mode's formula
    g0 = step_mode(0.0, 0.0, w, mode.zeta, mode.gain, h, 1.0, 0.0)
    g1 = step_mode(0.0, 0.0, w, mode.zeta, mode.gain, h, 0.0, 1.0)
    n = a.size
    w1 = np.zeros(n)
    w2 = np.zeros(n)
    # w_k enters x_{k+1}: place it at index k+1 of the filtered sequence
    w1[1:] = g0[0] * a[:-1] + g1[0] * a[1:]
    w2[1:] = g0[1] * a[:-1] + g1[1] * a[1:]
    den = [1.0, -(p11 + p22), p11 * p22 - p12 * p21]
    # X(z) = (zI - Φ)^-1 (z x0 + z^-1-delayed inputs), adj(zI - Φ) = [[z-p22, p12], [p21, z-p11]]
    eps = lfilter([1.0, -p22], den, w1) + lfilter([0.0, p12], den, w2)
    deps = lfilter([0.0, p21], den, w1) + lfilter([1.0, -p11], den, w2)
    if eps0 or deps0:
        imp = np.zeros(n)
        imp[0] = 1.0
        eps += eps0 * lfilter([1.0, -p22], den, imp) + deps0 * lfilter([0.0, p12], den, imp)
        deps += eps0 * lfilter([0.0, p21], den, imp) + deps0 * lfilter([1.0, -p11], den, imp)
    return eps, deps


def simulate_mode(
    t: np.ndarray,
    a: np.ndarray,
    mode: Mode,
    *,
    f: Callable[[float], float] | np.ndarray | None = None,
    state0: tuple[float, float] = (0.0, 0.0),
    z: np.ndarray | None = None,
    v_z: np.ndarray | None = None,
) -> ModeResponse:
    """Deflection of one mode driven by a sampled reference acceleration.

    Parameters
    ----------
    t : ndarray
        Uniform sample times (s).
    a : ndarray
        Reference acceleration at ``t`` (m/s²), linear between samples (as the
        generator produces it: constant jerk over each sample interval).
    mode : Mode
        The mode (its ``f`` is used when ``f`` is not given).
    f : callable or ndarray, optional
        Time-varying frequency (Hz): a function of time, evaluated at the middle
        of each interval, or an array of ``len(t) - 1`` per-interval values; with
        ``z`` given, a function of the Z position (m), evaluated at the cubic
        Hermite midpoint of (z, v_z) on each interval (:func:`hermite_mid`).  The
        scheme is the exponential midpoint rule described in the module notes.
    state0 : tuple of float
        (ε, ε̇) at ``t[0]``.
    z, v_z : ndarray, optional
        Z position (m) and velocity (m/s) at ``t``, when ``f`` is a law f(z).

    Returns
    -------
    ModeResponse

    Notes
    -----
    Exact (to rounding) for a constant mode: the transition over each interval
    is the closed-form solution for a linear input.
    """
    t = np.asarray(t, dtype=float)
    a = np.asarray(a, dtype=float)
    if t.shape != a.shape or t.ndim != 1 or t.size < 2:
        raise ValueError("t and a must be 1-D arrays of the same length (>= 2)")
    h = float(t[1] - t[0])
    if not np.allclose(np.diff(t), h, rtol=1e-9, atol=1e-12):
        raise ValueError("t must be uniformly sampled")
    if f is None:
        eps, deps = _lti_response(a, h, mode, *state0)
        return ModeResponse(t, eps, deps, np.full(t.size, mode.f))
    if z is not None:
        if not callable(f) or v_z is None:
            raise ValueError("with z, give v_z and f as a function of z")
        z = np.asarray(z, dtype=float)
        v_z = np.asarray(v_z, dtype=float)
        if z.shape != t.shape or v_z.shape != t.shape:
            raise ValueError("z and v_z must have the shape of t")
        zm = hermite_mid(z[:-1], v_z[:-1], z[1:], v_z[1:], h)
        fk = np.array([f(float(zz)) for zz in zm], dtype=float)
    elif callable(f):
        fk = np.array([f(tk + 0.5 * h) for tk in t[:-1]], dtype=float)
    else:
        fk = np.asarray(f, dtype=float)
        if fk.shape != (t.size - 1,):
            raise ValueError(f"f must hold len(t) - 1 = {t.size - 1} values, got {fk.shape}")
    if not np.all(fk > 0):
        raise ValueError("mode frequency must stay > 0")
    eps = np.empty(t.size)
    deps = np.empty(t.size)
    e, de = state0
    eps[0], deps[0] = e, de
    zeta, gain = mode.zeta, mode.gain
    two_pi = 2.0 * math.pi
    al = a.tolist()
    for k, fv in enumerate(fk.tolist()):
        e, de = step_mode(e, de, two_pi * fv, zeta, gain, h, al[k], al[k + 1])
        eps[k + 1] = e
        deps[k + 1] = de
    return ModeResponse(t, eps, deps, np.append(fk, fk[-1]))


# ------------------------------------------------------------ free motion


def free_amplitude(eps: float, deps: float, mode: Mode) -> float:
    """Amplitude of the free oscillation that starts from (ε, ε̇).

    After the reference has ended (q̈ = 0) the mode oscillates freely,
    ε(τ) = e^{-ζωτ} [ε cos ω_d τ + (ε̇ + ζω ε)/ω_d sin ω_d τ]; this returns the
    initial amplitude of that damped sinusoid, √(ε² + ((ε̇ + ζωε)/ω_d)²).

    Parameters
    ----------
    eps, deps : float
        State when the reference ends (m, m/s).
    mode : Mode
        The mode at that time (its frequency then).

    Returns
    -------
    float
        Amplitude (m).
    """
    return math.hypot(eps, (deps + mode.sigma * eps) / mode.omega_d)


def free_response(eps: float, deps: float, mode: Mode, tau: np.ndarray) -> np.ndarray:
    """Free oscillation ε(τ) from the state (ε, ε̇) at τ = 0 (no input).

    Parameters
    ----------
    eps, deps : float
        Initial state (m, m/s).
    mode : Mode
    tau : ndarray
        Times since the initial state (s).

    Returns
    -------
    ndarray
        ε(τ) (m).
    """
    tau = np.asarray(tau, dtype=float)
    wd, sig = mode.omega_d, mode.sigma
    return np.exp(-sig * tau) * (eps * np.cos(wd * tau) + (deps + sig * eps) / wd
                                 * np.sin(wd * tau))


# -------------------------------------------------------- scheduled plant


@dataclass(frozen=True)
class ScheduledMode:
    """A mode whose frequency is a function of the Z position.

    Parameters
    ----------
    f_of_z : callable
        z (m) → natural frequency (Hz); called with Python floats, once per step.
    zeta : float
        Damping ratio in [0, 1).
    gain : float
        Participation factor (see :class:`Mode`).
    name : str
        Label.
    f_of_z_array : callable, optional
        The same law on an array of positions (vectorised, same values); used
        by the fast engine (:mod:`harness.simulation.fast_axis`).  Without it the scalar law
        is applied element by element.
    """

    f_of_z: Callable[[float], float]
    zeta: float
    gain: float = 1.0
    name: str = ""
    f_of_z_array: Callable[[np.ndarray], np.ndarray] | None = None

    def f_array(self, z: np.ndarray) -> np.ndarray:
        """Frequencies (Hz) at an array of positions (m)."""
        z = np.asarray(z, dtype=float)
        if self.f_of_z_array is not None:
            return np.asarray(self.f_of_z_array(z), dtype=float)
        law = self.f_of_z
        return np.fromiter((law(zz) for zz in z.ravel().tolist()), float, z.size).reshape(z.shape)

    def at(self, z: float) -> Mode:
        """Return the frozen mode at position ``z``."""
        return Mode(float(self.f_of_z(z)), self.zeta, self.gain)


class ScheduledPlant:
    """Modes whose frequencies follow z(t), stepped by a co-simulation master.

    Each :meth:`step` advances every mode exactly for a linear input, with ω
    frozen at the Z position of mid-step (see the module notes).  Pure Python
    floats: a step costs about a microsecond per mode, no python-control object
    is built in the loop.

    Parameters
    ----------
    modes : sequence of ScheduledMode or Mode
        A plain :class:`Mode` is a constant mode.
    """

    def __init__(self, modes: Sequence[ScheduledMode | Mode]) -> None:
        if not modes:
            raise ValueError("at least one mode is needed")
        self.modes: list[ScheduledMode] = []
        for m in modes:
            if isinstance(m, Mode):
                fc = m.f
                m = ScheduledMode(lambda z, fc=fc: fc, m.zeta, m.gain)
            if not (0.0 <= m.zeta < 1.0):
                raise ValueError(f"damping ratio must be in [0, 1), got {m.zeta!r}")
            self.modes.append(m)
        self._laws = [m.f_of_z for m in self.modes]
        self._zeta = [m.zeta for m in self.modes]
        self._gain = [m.gain for m in self.modes]
        self.state = [0.0] * (2 * len(self.modes))

    def reset(self, state: Sequence[float] | None = None) -> None:
        """Set the state (ε_0, ε̇_0, ε_1, ε̇_1, ...); zero by default."""
        self.state = [0.0] * (2 * len(self.modes)) if state is None else [float(s) for s in state]

    def step(self, h: float, u0: float, u1: float, z_mid: float) -> float:
        """Advance all modes by ``h``; return the total deflection Σε at the end.

        Parameters
        ----------
        h : float
            Step (s).
        u0, u1 : float
            Reference acceleration at the start and the end of the step (m/s²).
        z_mid : float
            Z position at mid-step (m), see :func:`hermite_mid`.
        """
        return self.step_jerk(h, u0, (u1 - u0) / h, z_mid)

    def step_jerk(self, h: float, u0: float, jerk: float, z_mid: float) -> float:
        """Advance all modes by ``h`` with the input u0 + jerk·τ; return Σε at the end.

        Parameters
        ----------
        h : float
            Step (s).
        u0 : float
            Reference acceleration at the start of the step (m/s²).
        jerk : float
            Reference jerk over the step (m/s³): the generator's ``j`` output.
        z_mid : float
            Z position at mid-step (m), see :func:`hermite_mid`.
        """
        st = self.state
        total = 0.0
        two_pi = 2.0 * math.pi
        for i, law in enumerate(self._laws):
            f = law(z_mid)
            if not f > 0.0:
                raise ValueError(f"mode {i}: frequency {f!r} Hz at z = {z_mid} m is not > 0")
            e, de = step_mode_jerk(st[2 * i], st[2 * i + 1], two_pi * f, self._zeta[i],
                                   self._gain[i], h, u0, jerk)
            st[2 * i] = e
            st[2 * i + 1] = de
            total += e
        return total

    def frequencies(self, z: float) -> list[float]:
        """Mode frequencies (Hz) at position ``z``."""
        return [float(law(z)) for law in self._laws]

    def free_amplitudes(self, z: float) -> list[float]:
        """Amplitude of each mode's free oscillation from the current state, at ``z``."""
        return [free_amplitude(self.state[2 * i], self.state[2 * i + 1], m.at(z))
                for i, m in enumerate(self.modes)]
