"""Metrics on signals whose answers are known in closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq

from harness.metrics import (
    change_percent,
    motion_time,
    percent_of,
    residual_peak,
    rise_time,
    settling_time,
    table2_stats,
)


def test_residual_peak_after_the_end():
    t = np.linspace(0, 2, 2001)
    eps = np.where(t < 1.0, 5.0 * np.sin(7 * t), 0.3 * np.exp(-(t - 1.0)) * np.cos(20 * t))
    assert residual_peak(t, eps, 1.0) == pytest.approx(np.max(np.abs(eps[1000:])))
    assert residual_peak(t, eps, 1.0) <= 0.3
    assert math.isnan(residual_peak(t, eps, 3.0))


def test_settling_time_of_steps():
    t = np.arange(0, 4.0, 0.01)
    e = np.where(t < 1.0, 1.0, np.where(t < 2.0, 0.5, 0.1))
    # |e| > 0.2 until the sample before t = 2: linear interpolation puts the crossing inside
    # the last interval [1.99, 2.00], at (0.5 - 0.2) / (0.5 - 0.1) of it
    assert settling_time(t, e, 0.2) == pytest.approx(1.99 + 0.01 * 0.3 / 0.4)
    assert settling_time(t, e, 0.2, t_start=0.5) == pytest.approx(1.99 + 0.0075 - 0.5)
    assert settling_time(t, e, 2.0) == 0.0
    assert math.isnan(settling_time(t, e, 0.05))
    with pytest.raises(ValueError):
        settling_time(t, e, 0.0)


@settings(max_examples=30, deadline=None)
@given(A=st.floats(0.5, 5.0), sigma=st.floats(0.3, 3.0), f=st.floats(1.0, 12.0),
       ratio=st.floats(0.02, 0.6))
def test_settling_time_of_a_damped_cosine(A, sigma, f, ratio):
    """e = A e^{-σt} cos ωt: the last exit from the band follows the last extremum above it.

    Extrema of e are at tan(ωt) = -σ/ω, i.e. t_k = (kπ - atan(σ/ω))/ω (k = 0 at t = 0);
    the settling time is the crossing of |e| = band just after the last extremum whose
    |e| exceeds the band, found with brentq.
    """
    w = 2 * math.pi * f
    band = ratio * A
    e_of = lambda t: A * math.exp(-sigma * t) * math.cos(w * t)  # noqa: E731
    phi = math.atan(sigma / w)
    k = 1
    last = 0.0
    while True:
        tk = (k * math.pi - phi) / w
        if abs(e_of(tk)) <= band:
            break
        last = tk
        k += 1
    t_next = (k * math.pi - phi) / w
    expected = brentq(lambda t: abs(e_of(t)) - band, last, last + math.pi / (2 * w)) \
        if last > 0 else brentq(lambda t: abs(e_of(t)) - band, 0.0, t_next)
    dt = 1e-5 * (2 * math.pi / w)
    t = np.arange(0.0, expected + 3.0 * math.pi / w, dt)
    got = settling_time(t, A * np.exp(-sigma * t) * np.cos(w * t), band)
    assert got == pytest.approx(expected, abs=2 * dt)


def test_rise_time_of_a_ramp_and_of_an_oscillation():
    t = np.arange(0.0, 2.0, 0.01)
    x = np.clip(t / 1.234, 0, 1) * 0.4
    assert rise_time(t, x, 0.4) == pytest.approx(1.234, abs=0.01)
    # overshooting load: first crossing of the target, from below
    xl = 0.4 * (1 - np.exp(-3 * t) * np.cos(8 * t))
    t_cross = brentq(lambda s: math.exp(-3 * s) * math.cos(8 * s), 0.0, 0.3)
    assert t_cross == pytest.approx(math.pi / 16)
    assert rise_time(t, xl, 0.4) == pytest.approx(t_cross, abs=1e-3)
    # negative move, later start
    assert rise_time(t, -x, -0.4, t_start=0.2, start=0.0) == pytest.approx(1.034, abs=0.01)
    assert math.isnan(rise_time(t, 0.5 * x, 0.4))


def test_motion_time_from_reference_samples():
    t = np.arange(0.0, 2.0, 1e-3)
    T = 1.25
    s = np.clip(t / T, 0, 1)
    x = 0.3 * (10 * s**3 - 15 * s**4 + 6 * s**5)
    v = 0.3 / T * (30 * s**2 - 60 * s**3 + 30 * s**4) * (t < T)
    assert motion_time(t, x, v) == pytest.approx(T, abs=1.5e-3)
    assert motion_time(t, x, v, t_start=0.25) == pytest.approx(T - 0.25, abs=1.5e-3)
    assert math.isnan(motion_time(t[:1000], x[:1000], v[:1000]))


def test_percentages_and_table2_statistics():
    assert percent_of(0.6, 4.7) == pytest.approx(12.766, abs=1e-3)  # Table 1, DJL in X
    assert change_percent(1.11, 1.51) == pytest.approx(-26.49, abs=1e-2)
    assert math.isnan(percent_of(1.0, 0.0))
    st_ = table2_stats([-10.0, -20.0, -30.0, float("nan")])
    assert (st_.mean, st_.max, st_.min, st_.std, st_.n) == (-20.0, -30.0, -10.0, 10.0, 3)
    assert math.isnan(table2_stats([]).mean)
    assert table2_stats([-5.0]).std == 0.0
