"""Spectra and minima of sampled signals, exact for the generator's sample semantics.

The generator's outputs are exact samples of a profile whose jerk is constant
on each sampling interval: the acceleration ``a`` of a JL / DJL profile is the
piecewise-linear interpolant of its samples, and the AL acceleration
``a_AL[k]`` is the (constant) value on ``[t_k, t_k + Te)``.  The continuous
Fourier transform of such a signal is therefore exactly the discrete-time
Fourier transform (DTFT) of its samples times a known kernel:

* piecewise constant (zero-order hold): ``Te exp(-j omega Te/2) sinc(f Te)``;
* piecewise linear (first-order hold, signal 0 at both ends): ``Te sinc(f Te)^2``;

so spectra computed this way are those of the FMU's continuous profile, not
an approximation of it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import minimize_scalar

FloatArray = NDArray[np.float64]
ComplexArray = NDArray[np.complex128]


def dtft(x: ArrayLike, Te: float, f: ArrayLike, t0: float = 0.0) -> ComplexArray:
    """``sum_k x[k] exp(-j 2 pi f (t0 + k Te))`` at arbitrary frequencies ``f`` (Hz)."""
    x = np.asarray(x, dtype=float)
    f = np.atleast_1d(np.asarray(f, dtype=float))
    k = np.arange(x.size)
    out = np.empty(f.size, dtype=complex)
    step = max(1, 4_000_000 // max(x.size, 1))
    for i in range(0, f.size, step):
        fi = f[i:i + step]
        out[i:i + step] = np.exp(-2j * np.pi * np.outer(fi, k * Te)) @ x
    return out * np.exp(-2j * np.pi * f * t0)


def spectrum_zoh(x: ArrayLike, Te: float, f: ArrayLike, t0: float = 0.0) -> ComplexArray:
    """Fourier transform of the piecewise-constant signal ``x[k]`` on ``[t0 + k Te, ...)``."""
    f = np.asarray(f, dtype=float)
    kern = Te * np.exp(-1j * np.pi * f * Te) * np.sinc(f * Te)
    return kern * dtft(x, Te, f, t0)


def spectrum_foh(x: ArrayLike, Te: float, f: ArrayLike, t0: float = 0.0) -> ComplexArray:
    """Fourier transform of the piecewise-linear interpolant of ``x`` (zero at both ends)."""
    f = np.asarray(f, dtype=float)
    return Te * np.sinc(f * Te) ** 2 * dtft(x, Te, f, t0)


def spectrum_pwl_inside(x: ArrayLike, Te: float, f: ArrayLike) -> ComplexArray:
    """Fourier transform of the piecewise-linear interpolant of ``x`` on ``[0, (n-1) Te]`` only.

    Unlike :func:`spectrum_foh`, the signal is zero outside the sampled span
    (jumps at both ends are kept): each interval ``[t_k, t_k + Te]`` is
    integrated exactly for a linear segment from ``x[k]`` to ``x[k+1]``,
    ``int_0^Te (x0 (1 - s/Te) + x1 s/Te) exp(-j w s) ds = x0 c0 + x1 c1``.
    """
    x = np.asarray(x, dtype=float)
    w = 2 * np.pi * np.asarray(f, dtype=float)
    if np.any(w == 0):
        raise ValueError("f must be nonzero")
    e = np.exp(-1j * w * Te)
    c_all = (1 - e) / (1j * w)
    c1 = (e * (1 + 1j * w * Te) - 1) / (w**2 * Te)
    c0 = c_all - c1
    return c0 * dtft(x[:-1], Te, f) + c1 * dtft(x[1:], Te, f, t0=0.0)


def rfft_spectrum(x: ArrayLike, Te: float, n_fft: int, hold: str) -> tuple[FloatArray,
                                                                           ComplexArray]:
    """FFT (zero-padded to ``n_fft``) of samples, with the hold kernel: ``(f, X(f))``.

    ``hold`` is ``"zoh"`` (piecewise constant) or ``"foh"`` (piecewise linear).
    """
    x = np.asarray(x, dtype=float)
    if n_fft < x.size:
        raise ValueError("n_fft shorter than the signal")
    X = np.fft.rfft(x, n_fft)
    f = np.fft.rfftfreq(n_fft, Te)
    if hold == "zoh":
        kern = Te * np.exp(-1j * np.pi * f * Te) * np.sinc(f * Te)
    elif hold == "foh":
        kern = Te * np.sinc(f * Te) ** 2
    else:
        raise ValueError(f"hold must be 'zoh' or 'foh', not {hold!r}")
    return f, kern * X


def refine_minimum(fun, lo: float, hi: float, xtol: float = 1e-12) -> tuple[float, float]:
    """Minimum of ``|fun(f)|`` on ``[lo, hi]`` (Brent on ``|fun|^2``): ``(f_min, |fun(f_min)|)``."""
    res = minimize_scalar(lambda x: float(np.abs(np.ravel(fun(x))[0]) ** 2), bounds=(lo, hi),
                          method="bounded", options={"xatol": xtol, "maxiter": 500})
    return float(res.x), float(np.sqrt(max(res.fun, 0.0)))


def refine_maximum(fun, lo: float, hi: float, xtol: float = 1e-10) -> tuple[float, float]:
    """Maximum of ``|fun(f)|`` on ``[lo, hi]``: ``(f_max, |fun(f_max)|)``."""
    res = minimize_scalar(lambda x: -float(np.abs(np.ravel(fun(x))[0])), bounds=(lo, hi),
                          method="bounded", options={"xatol": xtol, "maxiter": 500})
    return float(res.x), float(-res.fun)


def local_maxima(y: ArrayLike) -> NDArray[np.intp]:
    """Return the indices of the strict interior local maxima of ``y``."""
    y = np.asarray(y, dtype=float)
    return np.nonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:]))[0] + 1


def db(x: ArrayLike, floor: float = 1e-15) -> FloatArray:
    """``20 log10(max(|x|, floor))``."""
    return 20.0 * np.log10(np.maximum(np.abs(np.asarray(x)), floor))
