"""Claim 5: the acceleration spectra of Béarée 2014 (eq. 6-16).

The closed forms are checked against numerical quadrature of the Fourier
integral of the time laws written independently here; the claim's FFT-based
numbers against those closed forms' extrema found by an optimiser.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad
from scipy.optimize import minimize_scalar

from harness.claims import Settings
from harness.claims import formulas as fm
from harness.claims.registry import run_claim


def _ft(acc, breaks, T, Omega):
    """Fourier transform of acc(t) on [0, T] at Omega = omega T / 2 pi (quadrature)."""
    w = 2 * np.pi * Omega / T
    pts = [0.0, *sorted(b for b in breaks if 0 < b < T), T]
    re = im = 0.0
    for t0, t1 in zip(pts[:-1], pts[1:], strict=True):
        re += quad(lambda t: acc(t) * np.cos(w * t), t0, t1, limit=200, epsabs=1e-12)[0]
        im += quad(lambda t: -acc(t) * np.sin(w * t), t0, t1, limit=200, epsabs=1e-12)[0]
    return re + 1j * im


def _trapezoid_law(alpha, beta, P=1.0, T=1.0):
    """JL acceleration: ramps of T_j, plateau, zero, mirrored (beta <= 1/2)."""
    Ta, Tj = alpha * T, alpha * beta * T
    A = P / (alpha * (1 - beta) * (1 - alpha) * T**2)

    def pulse(t):
        if t < 0 or t > Ta:
            return 0.0
        return A * min(t / Tj, 1.0, (Ta - t) / Tj)

    return (lambda t: pulse(t) - pulse(t - (T - Ta))), [Tj, Ta - Tj, Ta, T - Ta,
                                                         T - Ta + Tj, T - Tj]


OMEGAS = [0.37, 1.0, 2.6, 5.5, 11.2]


@pytest.mark.parametrize("Om", OMEGAS)
def test_cubic_eq7_and_eq9(Om):
    ref = _ft(lambda t: 6.0 - 12.0 * t, [], 1.0, Om)
    w = 2 * np.pi * Om
    assert abs(fm.spectrum_cubic(w) - ref) < 1e-9
    assert fm.spectrum_cubic_mag(Om) == pytest.approx(abs(ref), abs=1e-9)


@pytest.mark.parametrize("Om", [*OMEGAS, 0.004])
def test_quintic_eq11(Om):
    ref = _ft(lambda t: 60.0 * (t - 3 * t**2 + 2 * t**3), [], 1.0, Om)
    assert fm.spectrum_quintic_mag(Om) == pytest.approx(abs(ref), abs=1e-9)


@settings(max_examples=15, deadline=None)
@given(alpha=st.floats(0.05, 0.5), Om=st.floats(0.1, 15.0))
def test_al_eq15(alpha, Om):
    A = 1.0 / (alpha * (1 - alpha))
    ref = _ft(lambda t: A if t < alpha else (-A if t > 1 - alpha else 0.0),
              [alpha, 1 - alpha], 1.0, Om)
    assert fm.spectrum_al_mag(Om, alpha) == pytest.approx(abs(ref), abs=1e-8)


@settings(max_examples=15, deadline=None)
@given(alpha=st.floats(0.1, 0.5), beta=st.floats(0.05, 0.5), Om=st.floats(0.1, 15.0))
def test_jl_eq16_and_filter_identity(alpha, beta, Om):
    acc, breaks = _trapezoid_law(alpha, beta)
    ref = abs(_ft(acc, breaks, 1.0, Om))
    assert fm.spectrum_jl_mag(Om, alpha, beta) == pytest.approx(ref, abs=1e-8)
    assert fm.jl_equals_al_times_filter(Om, alpha, beta) == pytest.approx(ref, abs=1e-8)
    # eq. (16) is symmetric in beta <-> 1 - beta
    assert fm.spectrum_jl_mag(Om, alpha, 1 - beta) == pytest.approx(ref, abs=1e-8)


def _lobe_peaks(mag, n):
    """First n local maxima of a closed form: dense grid, then a bounded optimiser."""
    x = np.linspace(0.05, n + 3.0, 200001)
    y = mag(x)
    idx = np.nonzero((y[1:-1] > y[:-2]) & (y[1:-1] >= y[2:]))[0][:n] + 1
    peaks = []
    for i in idx:
        r = minimize_scalar(lambda v: -float(mag(np.array(v))), bounds=(x[i - 1], x[i + 1]),
                            method="bounded", options={"xatol": 1e-12})
        peaks.append(-r.fun)
    return np.array(peaks)


def test_claim5_numbers(fmu2):
    res = run_claim(5, Settings(fast=True, fmu=fmu2))
    assert res.error is None, res.error
    assert res.product_passed, [c.describe() for c in res.failed_checks()]
    lob = res.data.lobes
    cub = _lobe_peaks(fm.spectrum_cubic_mag, 4)
    qui = _lobe_peaks(fm.spectrum_quintic_mag, 4)
    # FFT lobes (grid of 1/16 s^-1 in fast mode) against the closed forms' maxima
    assert lob[:4, 2] == pytest.approx(cub, rel=2e-3)
    assert lob[:4, 4] == pytest.approx(qui, rel=2e-3)
    ratios = cub[1:4] / qui[1:4]
    assert ratios == pytest.approx([1.737, 2.415, 3.067], abs=2e-3)
    lobes_check = next(c for c in res.checks if "ratio 2 to 3" in c.name)
    assert lobes_check.passed == bool(np.all((ratios >= 2) & (ratios <= 3)))
    first = next(c for c in res.checks if "first lobe" in c.name)
    assert first.passed and first.measured == pytest.approx(qui[0] / cub[0], rel=2e-3)
