"""Residual vibration that a motion leaves on one second-order mode, computed exactly.

The mode is the flexible axis of Béarée 2014 (eq. 3): the deflection ε of the
load obeys ``ε'' + 2 ζ ω ε' + ω² ε = -a(t)`` where ``a`` is the reference
acceleration.  Once the motion is over (``a = 0``) the deflection is a free
oscillation; with ``p = -ζω + jω_d`` (``ω_d = ω √(1-ζ²)``) and

    U(p) = ∫ a(τ) exp(-p (τ - t_ref)) dτ            (over the motion)

it is exactly ``ε(t) = -Im(exp(p (t - t_ref)) U) / ω_d`` for every ``t`` after
the end of the motion (convolution with the impulse response
``exp(-ζωt) sin(ω_d t) / ω_d``).  Its envelope at ``t_ref`` is ``|U| / ω_d``:
that is the *residual amplitude* reported here (m, for ``a`` in m/s²).  The
default ``t_ref`` is the end of the motion.

``U`` is integrated by Gauss-Legendre quadrature on the smooth pieces of the
motion (between its breakpoints, subdivided so that ``|p| h <= 1``), which is
exact to rounding for the piecewise-polynomial and piecewise-exponential laws
of this package.  The tests check it against ``scipy.integrate.solve_ivp``.
Sato & Shirase's amplitude (their eq. 28) is that of ``G(s) a`` with
``G = ω²/(s² + 2ζωs + ω²)``, i.e. ``ω²`` times this one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .trajectory import Motion, SampledTrajectory

_GL_N = 16
_GL_X, _GL_W = np.polynomial.legendre.leggauss(_GL_N)


def _poles(f: np.ndarray, zeta: float) -> tuple[np.ndarray, np.ndarray]:
    if np.any(f <= 0.0):
        raise ValueError("mode frequencies must be positive")
    if not 0.0 <= zeta < 1.0:
        raise ValueError(f"damping ratio must be in [0, 1), got {zeta}")
    omega = 2 * np.pi * f
    omega_d = omega * np.sqrt(1.0 - zeta ** 2)
    return -zeta * omega + 1j * omega_d, omega_d


def quadrature_nodes(motion: Motion, p_max: float, h_max: float | None = None
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights covering the motion.

    Parameters
    ----------
    motion : Motion
    p_max : float
        Largest ``|p|`` (rad/s) the nodes must integrate ``exp(-p t)`` for.
    h_max : float, optional
        Longest sub-interval (s); default ``1 / p_max``.

    Returns
    -------
    tau, w : ndarray
        Nodes (s) and weights (s).
    """
    t0, t1 = motion.t_start, motion.t_end
    bp = motion.breakpoints()
    bp = np.unique(np.r_[t0, bp[(bp > t0) & (bp < t1)], t1])
    if bp.size < 2:
        return np.zeros(0), np.zeros(0)
    h_max = h_max or 1.0 / p_max
    lengths = np.diff(bp)
    n_sub = np.maximum(1, np.ceil(lengths / h_max).astype(int))
    edges = np.concatenate([np.linspace(a, b, n + 1)[:-1] for a, b, n in
                            zip(bp[:-1], bp[1:], n_sub, strict=True)] + [bp[-1:]])
    a, b = edges[:-1], edges[1:]
    half = 0.5 * (b - a)
    tau = (0.5 * (a + b))[:, None] + half[:, None] * _GL_X[None, :]
    w = half[:, None] * _GL_W[None, :]
    return tau.ravel(), w.ravel()


def laplace_at_poles(motion: Motion, f: float | Sequence[float] | np.ndarray,
                     zeta: float = 0.0, t_ref: float | None = None) -> np.ndarray:
    """``U(p) = ∫ a(τ) exp(-p (τ - t_ref)) dτ`` at the mode poles ``p`` (m/s).

    Parameters
    ----------
    motion : Motion
    f : float or array_like
        Mode frequencies (Hz).
    zeta : float
        Damping ratio, in [0, 1).
    t_ref : float, optional
        Reference time (s); default the end of the motion.
    """
    f = np.atleast_1d(np.asarray(f, dtype=float))
    p, _ = _poles(f, zeta)
    t_ref = motion.t_end if t_ref is None else t_ref
    tau, w = quadrature_nodes(motion, float(np.max(np.abs(p))))
    if tau.size == 0:
        return np.zeros(f.shape, dtype=complex)
    a = motion.evaluate(tau)[2]
    return np.exp(-np.outer(p, tau - t_ref)) @ (w * a)


def residual_amplitude(motion: Motion | SampledTrajectory,
                       f: float | Sequence[float] | np.ndarray, zeta: float = 0.0,
                       t_ref: float | None = None) -> np.ndarray | float:
    """Envelope of the free deflection left by the motion, at ``t_ref`` (m).

    Parameters
    ----------
    motion : Motion or SampledTrajectory
        A sampled trajectory is taken through its exact motion when it has one
        (:meth:`SampledTrajectory.to_motion`).
    f : float or array_like
        Mode frequency (Hz).
    zeta : float
        Damping ratio.
    t_ref : float, optional
        Time at which the envelope is taken; default the end of the motion.

    Returns
    -------
    float or ndarray
        ``|U(p)| / ω_d``, shaped like ``f``.
    """
    m = motion.to_motion() if isinstance(motion, SampledTrajectory) else motion
    f_arr = np.asarray(f, dtype=float)
    _, omega_d = _poles(np.atleast_1d(f_arr), zeta)
    amp = np.abs(laplace_at_poles(m, f_arr, zeta, t_ref)) / omega_d
    return float(amp[0]) if f_arr.ndim == 0 else amp.reshape(f_arr.shape)


def free_deflection(motion: Motion, f: float, zeta: float, t: np.ndarray) -> np.ndarray:
    """Deflection ε(t) (m) for times after the end of the motion (free oscillation)."""
    t = np.asarray(t, dtype=float)
    if np.any(t < motion.t_end - 1e-12 * max(1.0, abs(motion.t_end))):
        raise ValueError("free_deflection only holds after the end of the motion")
    p, omega_d = _poles(np.atleast_1d(float(f)), zeta)
    U = laplace_at_poles(motion, f, zeta, motion.t_end)[0]
    return -np.imag(np.exp(p[0] * (t - motion.t_end)) * U) / omega_d[0]


@dataclass
class RobustnessCurve:
    """Residual amplitude of one or more motions against the mode-frequency error.

    Attributes
    ----------
    f_tuned : float
        Frequency the methods were tuned to (Hz).
    zeta : float
        Damping ratio of the simulated mode.
    error : ndarray
        Relative frequency error ``f_actual / f_tuned - 1``.
    residual : dict of str to ndarray
        Residual amplitude (m) per method, at each error.
    reference : str or None
        Method the percentages refer to (e.g. ``"AL"``).
    """

    f_tuned: float
    zeta: float
    error: np.ndarray
    residual: dict[str, np.ndarray]
    reference: str | None = None

    def percent(self) -> dict[str, np.ndarray]:
        """Residuals in % of the reference method at the same actual frequency."""
        if self.reference is None:
            raise ValueError("no reference method")
        ref = self.residual[self.reference]
        return {k: 100.0 * v / ref for k, v in self.residual.items()}

    def plot(self, title: str | None = None):
        """Residual (in % of the reference, or in µm) against the frequency error."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        fig, ax = plt.subplots(figsize=(7, 4))
        data = self.percent() if self.reference else {
            k: v * 1e6 for k, v in self.residual.items()}
        for k, v in data.items():
            ax.plot(100 * self.error, v, label=k)
        ax.set_xlabel("mode frequency error f/f_tuned - 1 [%]")
        ax.set_ylabel(f"residual [% of {self.reference}]" if self.reference else "residual [µm]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small")
        ax.set_title(title or f"robustness, tuned to {self.f_tuned:.3g} Hz, ζ = {self.zeta:.3g}")
        fig.tight_layout()
        return fig


def robustness_curve(motions: dict[str, Motion | SampledTrajectory], f_tuned: float,
                     zeta: float = 0.0, errors: Sequence[float] | np.ndarray | None = None,
                     reference: str | None = None) -> RobustnessCurve:
    """Residual of each motion on a stationary mode at ``f_tuned (1 + error)``.

    Parameters
    ----------
    motions : dict
        Motions by method name.
    f_tuned : float
        Nominal mode frequency (Hz).
    zeta : float
        Damping ratio of the mode.
    errors : array_like, optional
        Relative frequency errors; default -50 % .. +50 % in 1 % steps.
    reference : str, optional
        Name of the method the percentages refer to.
    """
    err = np.linspace(-0.5, 0.5, 101) if errors is None else np.asarray(errors, dtype=float)
    f = f_tuned * (1.0 + err)
    res = {k: np.asarray(residual_amplitude(m, f, zeta)) for k, m in motions.items()}
    return RobustnessCurve(f_tuned, zeta, err, res, reference)
