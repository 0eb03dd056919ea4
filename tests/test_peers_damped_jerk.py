"""Damped-jerk law (Béarée 2014 §4.2): the filter, its zero residual, JL as its ζ = 0 case."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad
from test_peers_reference import simulate_motion

from harness.fmu.runner import generate
from harness.peers.damped_jerk import (
    DampedJerkFilter,
    DampedJerkMotion,
    damped_jerk_profile,
    damping_sweep,
)
from harness.peers.shapers import al_profile
from harness.peers.trajectory import from_fmu

MOVE = {"distance": 0.4, "v_max": 0.5, "a_max": 4.0, "d_max": 4.0}
F = 7.3




@pytest.fixture(scope="module")
def al(fmu2):
    return al_profile(MOVE, fmu=fmu2)


@settings(max_examples=30, deadline=None)
@given(st.floats(0.5, 100.0), st.floats(0.0, 0.5), st.integers(1, 3))
def test_kernel_unit_area_and_zero_at_the_pole(f, zeta, k):
    """∫h = 1 and ∫h(t) e^{-pt} dt = 0 at the mode pole (quadrature, not transfer())."""
    flt = DampedJerkFilter(f, zeta, k)
    area = quad(lambda t: flt.kernel(t), 0, flt.T, limit=200)[0]
    assert area == pytest.approx(1.0, rel=1e-9)
    w = 2 * math.pi * f
    p = complex(-zeta * w, w * math.sqrt(1 - zeta ** 2))
    re = quad(lambda t: float(flt.kernel(t)) * (np.exp(-p * t)).real, 0, flt.T, limit=400)[0]
    im = quad(lambda t: float(flt.kernel(t)) * (np.exp(-p * t)).imag, 0, flt.T, limit=400)[0]
    assert abs(complex(re, im)) < 1e-8
    assert abs(flt.transfer(p)) < 1e-12
    assert flt.transfer(0.0) == pytest.approx(1.0)


def test_two_impulse_shaper_and_leaky_integrator():
    """H(s) = c (1 - K e^{-sT}) / (s + λ): the shaper [c, -cK] at [0, T], K = e^{-ζωT}."""
    flt = DampedJerkFilter(10.0, 0.1)
    A, t = flt.shaper
    assert t[1] == pytest.approx(1 / (10.0 * math.sqrt(1 - 0.01)))  # one damped period
    assert A[1] / A[0] == pytest.approx(-math.exp(-0.1 * 2 * math.pi * 10.0 * t[1]))
    s = np.array([3.0 + 40j, -2.0 + 7j, 100j])
    direct = (A[0] + A[1] * np.exp(-s * t[1])) / (s + flt.lam)
    np.testing.assert_allclose(flt.transfer(s), direct, rtol=1e-12)


def test_undamped_case_is_the_fmu_jl(fmu2, al):
    """ζ = 0: AL filtered by the damped-jerk law = the FMU's JL with T_F = 1/f, per sample."""
    jl = generate(dict(MOVE, profile=2, T_F1=0.1), fmu=fmu2)
    m = DampedJerkMotion.from_al(al, DampedJerkFilter(10.0, 0.0))
    s = m.sample(1e-3, t_stop=jl.t[-1])
    for name in ("x", "v", "a", "j"):
        np.testing.assert_allclose(getattr(s, name), getattr(jl, name), rtol=0,
                                   atol=1e-9 * max(1.0, np.abs(getattr(jl, name)).max()))
    assert s.motion_time == pytest.approx(jl.motion_time, abs=1e-12)


@pytest.mark.parametrize("zeta,k", [(0.0, 1), (0.05, 1), (0.15, 1), (0.05, 2)])
def test_zero_residual_at_tuned_damped_mode(al, zeta, k):
    m = DampedJerkMotion.from_al(al, DampedJerkFilter(F, zeta, k))
    ref = simulate_motion(al.to_motion(), F, zeta)
    got = simulate_motion(m, F, zeta)
    assert ref > 1e-4
    assert got < 1e-7 * ref


@pytest.mark.parametrize("zeta", [0.05, 0.15])
def test_jl_leaves_residual_on_damped_mode(fmu2, al, zeta):
    """JL with T_F = 1/f (FMU) on a damped mode: residual = the closed form of damping_sweep."""
    # f with a whole number of samples per period: T_F = 1/f exactly
    f = 1 / 0.125
    jl = from_fmu(generate(dict(MOVE, profile=2, T_F1=0.125), fmu=fmu2))
    ratio = simulate_motion(jl.to_motion(), f, zeta) / simulate_motion(al.to_motion(), f, zeta)
    sweep = damping_sweep(np.array([zeta]), f=f)
    assert ratio == pytest.approx(sweep.residual["JL, T_F = 1/f"][0] / 100, rel=1e-6)
    assert ratio > 0.03  # JL cannot cancel a damped mode
    # the damped-jerk filter tuned to the same mode cancels it
    dj = DampedJerkMotion.from_al(al, DampedJerkFilter(f, zeta))
    assert simulate_motion(dj, f, zeta) < 1e-7 * simulate_motion(al.to_motion(), f, zeta)


def test_damped_jerk_shape(al):
    """Jerk decays as e^{-ζωt} over one damped period; limits of the AL profile are kept."""
    zeta, f = 0.1, 20.0  # T ≈ 50 ms < the AL's 125 ms acceleration stage
    flt = DampedJerkFilter(f, zeta)
    m = DampedJerkMotion.from_al(al, flt)
    t0 = float(m.tau[0])
    j = m.evaluate(t0 + np.array([0.0, flt.T / 2, flt.T - 1e-9]))[3]
    w = 2 * math.pi * f
    np.testing.assert_allclose(j[1] / j[0], math.exp(-zeta * w * flt.T / 2), rtol=1e-9)
    np.testing.assert_allclose(j[2] / j[0], flt.K, rtol=1e-6)
    assert j[0] == pytest.approx(4.0 * flt.c, rel=1e-3)  # c ΔA, ΔA = the AL's first step
    s = m.sample(1e-3)
    assert s.x[-1] == pytest.approx(0.4, abs=1e-12)
    assert np.abs(s.v).max() <= 0.5 * (1 + 1e-12)
    assert np.abs(s.a).max() <= 4.0 * (1 + 1e-12)
    assert m.motion_time == pytest.approx(al.motion_time + flt.T, rel=1e-12)
    # x' = v and v' = a inside a stage (central differences)
    t = t0 + 0.3 * flt.T
    h = 1e-6
    xp, vp, _, _ = m.evaluate([t + h])
    xm, vm, _, _ = m.evaluate([t - h])
    x, v, a, _ = m.evaluate([t])
    assert (xp[0] - xm[0]) / (2 * h) == pytest.approx(v[0], rel=1e-7)
    assert (vp[0] - vm[0]) / (2 * h) == pytest.approx(a[0], rel=1e-6)


def test_damping_sweep_and_profile(fmu2):
    import matplotlib.figure

    sw = damping_sweep(np.array([0.0, 0.02, 0.1]))
    assert np.all(sw.residual["damped jerk"] < 1e-10)
    assert sw.residual["JL, T_F = 1/f"][0] < 1e-10
    # the ζ < 10 % region: JL leaves less than 8 % of the AL residual
    assert 0 < sw.residual["JL, T_F = 1/f"][2] < 8.0
    assert isinstance(sw.plot(), matplotlib.figure.Figure)
    s = damped_jerk_profile(MOVE, F, 0.05, fmu=fmu2)
    assert s.x[-1] == pytest.approx(0.4, abs=1e-12)
    assert s.params["dj_zeta"] == 0.05


def test_bad_arguments(al):
    with pytest.raises(ValueError):
        DampedJerkFilter(-1.0)
    with pytest.raises(ValueError):
        DampedJerkFilter(1.0, 1.2)
    with pytest.raises(ValueError):
        DampedJerkFilter(1.0, 0.1, 0)
    from harness.peers.trajectory import PiecewiseJerk

    jl = DampedJerkMotion.from_al(al, DampedJerkFilter(F)).sample(1e-3)
    not_al = PiecewiseJerk.from_samples(jl.t, jl.x, jl.v, jl.a, jl.j)  # jerk not zero
    with pytest.raises(ValueError):
        DampedJerkMotion.from_al(not_al, DampedJerkFilter(F))
