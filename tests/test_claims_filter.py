"""Claims 1 and 2: the moving average as a comb notch, JL = AL * moving average.

References are independent of the code under test: numerical quadrature of
the rectangle's Fourier integral, direct sums, np.convolve, and numbers
computed by hand (k / (N Te)).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

from harness.claims import Settings
from harness.claims import formulas as fm
from harness.claims.registry import run_claim
from harness.claims.signals import (
    dtft,
    refine_minimum,
    rfft_spectrum,
    spectrum_foh,
    spectrum_pwl_inside,
    spectrum_zoh,
)
from harness.fmu.runner import generate


def _ft_quad(fun, t0: float, t1: float, f: float) -> complex:
    w = 2 * np.pi * f
    re = quad(lambda t: fun(t) * np.cos(w * t), t0, t1, limit=400, epsabs=1e-13)[0]
    im = quad(lambda t: -fun(t) * np.sin(w * t), t0, t1, limit=400, epsabs=1e-13)[0]
    return re + 1j * im


# ----------------------------------------------------------------- formulas

@pytest.mark.parametrize("f", [0.3, 7.0, 20.0, 33.3, 95.0])
def test_ma_continuous_is_the_transform_of_the_unit_rectangle(f):
    T_F = 0.05
    ref = _ft_quad(lambda t: 1.0 / T_F, 0.0, T_F, f)
    assert abs(fm.ma_continuous(f, T_F) - ref) < 1e-10


@settings(max_examples=40, deadline=None)
@given(N=st.integers(2, 200), Te=st.sampled_from([1e-4, 5e-4, 1e-3, 2e-3]),
       x=st.floats(0.001, 0.499))
def test_ma_discrete_is_the_direct_sum(N, Te, x):
    f = x / Te  # below Nyquist
    direct = np.sum(np.exp(-2j * np.pi * f * Te * np.arange(N))) / N
    assert abs(fm.ma_discrete(f, N, Te) - direct) < 1e-12


@settings(max_examples=30, deadline=None)
@given(N=st.integers(2, 120), k=st.integers(1, 60))
def test_ma_discrete_zeros_at_k_over_N_Te(N, k):
    Te = 1e-3
    if k % N == 0:
        k += 1
    assert abs(fm.ma_discrete(k / (N * Te), N, Te)) < 1e-12
    assert abs(fm.ma_discrete(0.0, N, Te) - 1.0) < 1e-15


def test_refine_minimum_finds_a_known_zero():
    fmin, depth = refine_minimum(lambda x: np.atleast_1d(np.sin(np.pi * x)), 2.7, 3.2)
    assert fmin == pytest.approx(3.0, abs=1e-8)
    assert depth < 1e-7


# ---------------------------------------------------- exact spectra of samples

@pytest.mark.parametrize("f", [0.7, 13.0, 41.0])
def test_spectrum_zoh_and_foh_match_quadrature(f):
    Te = 0.01
    x = np.array([0.0, 1.0, 3.0, -2.0, 0.5, 0.0])
    t = Te * np.arange(x.size)
    # piecewise constant: x[k] on [t_k, t_k + Te); piecewise linear through the samples
    ref_zoh = sum(_ft_quad(lambda tt, k=k: x[k], t[k], t[k] + Te, f) for k in range(x.size))
    ref_foh = _ft_quad(lambda tt: np.interp(tt, t, x), t[0], t[-1], f)
    assert abs(spectrum_zoh(x, Te, [f])[0] - ref_zoh) < 1e-10
    assert abs(spectrum_foh(x, Te, [f])[0] - ref_foh) < 1e-10


def test_spectrum_pwl_inside_keeps_end_jumps():
    Te = 0.01
    t = np.arange(0, 0.3 + Te / 2, Te)
    x = 6.0 - 12.0 * t / 0.3  # jumps to/from 0 at both ends
    for f in (1.3, 9.0):
        ref = _ft_quad(lambda tt: 6.0 - 12.0 * tt / 0.3, 0.0, 0.3, f)
        assert abs(spectrum_pwl_inside(x, Te, [f])[0] - ref) < 1e-10


def test_rfft_spectrum_agrees_with_dtft():
    Te = 1e-3
    x = np.sin(np.linspace(0, 3, 50)) ** 2
    f, X = rfft_spectrum(x, Te, 256, "foh")
    assert np.allclose(X[5:9], Te * np.sinc(f[5:9] * Te) ** 2 * dtft(x, Te, f[5:9]), atol=1e-14)


# ---------------------------------------------------------------- the claims

def test_claim1_product_numbers(fmu2):
    res = run_claim(1, Settings(fast=True, fmu=fmu2))
    assert res.error is None, res.error
    assert res.passed, [c.describe() for c in res.failed_checks()]
    case1, case2 = res.data.cases
    assert (case1.N, case2.N) == (50, 52)  # round(52.3 ms / 1 ms) = 52
    # notch positions measured on the FMU: k / (N Te) computed by hand
    assert case2.notches[:, 3] == pytest.approx([1 / 0.052, 2 / 0.052, 3 / 0.052], rel=1e-7)
    assert case1.notches[:, 3] == pytest.approx([20.0, 40.0, 60.0], rel=1e-7)
    # measured impulse response: N samples of 1/(N Te), then zeros
    assert np.allclose(case2.h_fmu[:52], 1 / 0.052, rtol=1e-12)
    assert np.all(case2.h_fmu[52:] == 0.0)
    assert len(res.figures) == 1


def test_claim2_product_checks(fmu2):
    res = run_claim(2, Settings(fast=True, fmu=fmu2))
    assert res.error is None, res.error
    assert res.passed, [c.describe() for c in res.failed_checks()]


@settings(max_examples=6, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(distance=st.floats(0.01, 1.0), v_max=st.floats(0.2, 2.0), a_max=st.floats(2.0, 20.0),
       N=st.integers(3, 90), v_e=st.sampled_from([0.0, 0.1]))
def test_jl_acceleration_is_the_moving_average_of_al(fmu2, distance, v_max, a_max, N, v_e):
    v_e = min(v_e, 0.5 * v_max)
    tr = generate({"profile": 2, "distance": distance, "v_max": v_max, "a_max": a_max,
                   "d_max": a_max, "T_F1": N * 1e-3, "v_e": v_e}, fmu=fmu2)
    assert tr.N_F[0] == N
    # np.convolve, with the one-sample shift of the FMU's convention (a_AL[k] holds on
    # [t_k, t_k + Te)): a[k] = mean(a_AL[k-N .. k-1])
    ma = np.convolve(tr.a_AL, np.ones(N) / N)[: tr.a.size]
    ma = np.r_[0.0, ma[:-1]]
    assert np.max(np.abs(tr.a - ma)) <= 1e-12 * a_max
    jerk = (tr.a_AL - np.r_[np.zeros(N), tr.a_AL[:-N]]) / (N * 1e-3)
    assert np.max(np.abs(tr.j - jerk)) <= 1e-9 * a_max / (N * 1e-3)
