"""Sato & Shirase 2021: profiles of Conditions I-III, Table 1 / eq. 28 against simulation."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_peers_reference import simulate_residual

from harness.peers.residual import residual_amplitude
from harness.peers.sato import (
    CONDITIONS,
    PAPER_EXAMPLE,
    amplitude_map,
    amplitude_table1,
    fig10_example,
    jerk_J1,
    sato_profile,
)

F = 30.0
W = 2 * math.pi * F




def integrate_jerks(T, J):
    """End state of four constant-jerk stages from rest (plain closed-form steps)."""
    x = v = a = 0.0
    for h, j in zip(T, J, strict=True):
        x += v * h + a * h * h / 2 + j * h ** 3 / 6
        v += a * h + j * h * h / 2
        a += j * h
    return x, v, a


def simulate_amp(prof, f=F, zeta=0.0):
    """|Amp| of G(s) a (m/s²) by solve_ivp: ω² times the deflection of ε'' + ω²ε = -a."""
    bounds = np.r_[0.0, np.cumsum(prof.T)]

    def acc(t, side):
        k = int(np.searchsorted(bounds, t, side="right" if side == "right" else "left")) - 1
        k = min(max(k, 0), 3)
        a0 = sum(prof.J[i] * prof.T[i] for i in range(k))
        return a0 + prof.J[k] * (t - bounds[k])

    w = 2 * math.pi * f
    return w * w * simulate_residual(acc, bounds[:-1], bounds[-1], f, zeta)


@pytest.mark.parametrize("condition", CONDITIONS)
def test_profiles_move_L_and_stop(condition):
    """Eq. 14, 18-21: the jerks J1..J4 move exactly L in T_SUM and end at rest."""
    L, T_SUM, T1 = 1e-3, 0.04, 0.007
    p = sato_profile(L, T_SUM, T1, condition)
    assert sum(p.T) == pytest.approx(T_SUM, rel=1e-14)
    x, v, a = integrate_jerks(p.T, p.J)
    assert x == pytest.approx(L, rel=1e-12)
    assert abs(v) < 1e-15 and abs(a) < 1e-12
    assert p.R == pytest.approx((T_SUM - 2 * T1) / (2 * T1))
    equal = {"I": ((0, 1), (2, 3)), "II": ((0, 2), (1, 3)), "III": ((0, 3), (1, 2))}[condition]
    for i, k in equal:
        assert p.T[i] == pytest.approx(p.T[k])


def test_condition_III_jerks_paper_relations():
    """Eq. 19 and eq. 27: J1 = 6L/(T1² T_SUM (2R+1)), J2 = -J1/R, J3 = J2, J4 = J1."""
    p = sato_profile(1e-3, 0.04, 0.001, "III")
    R = (0.04 - 0.002) / 0.002
    assert p.R == pytest.approx(19.0)
    assert p.J[0] == pytest.approx(6e-3 / (1e-6 * 0.04 * (2 * R + 1)), rel=1e-14)
    assert p.J[0] == pytest.approx(3846.153846153846, rel=1e-12)
    assert p.J[1] == pytest.approx(-p.J[0] / R)
    assert p.J[2] == pytest.approx(p.J[1]) and p.J[3] == pytest.approx(p.J[0])
    assert p.A2 == pytest.approx(-p.A1)


def test_conventional_profile_is_the_same_for_all_conditions():
    """T1 = T_SUM/4: four equal jerk times (R = 1), J1 = 500 m/s³ for 1 mm in 40 ms."""
    profs = [sato_profile(1e-3, 0.04, 0.01, c) for c in CONDITIONS]
    for p in profs:
        assert p.R == pytest.approx(1.0)
        np.testing.assert_allclose(p.T, [0.01] * 4, rtol=1e-14)
        np.testing.assert_allclose(p.J, [500.0, -500.0, -500.0, 500.0], rtol=1e-12)
    amps = [abs(p.amplitude(F)) for p in profs]
    np.testing.assert_allclose(amps, amps[0], rtol=1e-12)


@settings(max_examples=12, deadline=None)
@given(st.floats(0.02, 0.1), st.floats(0.02, 0.98), st.sampled_from(CONDITIONS))
def test_table1_against_simulation(T_SUM, frac, condition):
    """Each row of Table 1 equals the residual of the simulated mode (1e-6 relative)."""
    T1 = frac * T_SUM / 2
    p = sato_profile(1e-3, T_SUM, T1, condition)
    sim = simulate_amp(p)
    formula = abs(p.amplitude(F))
    scale = abs(sato_profile(1e-3, T_SUM, T_SUM / 4, condition).amplitude(F))
    assert formula == pytest.approx(sim, rel=1e-6, abs=1e-8 * scale)


@pytest.mark.parametrize("T1", [0.001, 0.003, 0.01, 0.015, 0.0199])
def test_eq28_condition_III_against_simulation(T1):
    p = sato_profile(1e-3, 0.04, T1, "III")
    amp28 = 2 * p.J[0] / W * ((1 + 1 / p.R) * math.sin(W * p.R * T1) - math.sin(W * 0.02))
    assert p.amplitude(F) == pytest.approx(amp28, rel=1e-13)
    assert abs(amp28) == pytest.approx(simulate_amp(p), rel=1e-7)


def test_exact_residual_module_agrees_with_table1():
    for c in CONDITIONS:
        p = sato_profile(1e-3, 0.05, 0.008, c)
        assert residual_amplitude(p.motion(), F) == pytest.approx(p.deflection_amplitude(F),
                                                                  rel=1e-9)


def test_fig10_example_reduction():
    """T_SUM = 40 ms, 1 mm, 30 Hz: T1 = 10 ms -> 1 ms cuts the residual by 56.9 %."""
    r = fig10_example()
    assert PAPER_EXAMPLE["T_SUM"] == 0.040 and PAPER_EXAMPLE["f"] == 30.0
    assert r.conventional.T[0] == 0.010 and r.designed.T[0] == 0.001
    sim = (simulate_amp(r.conventional), simulate_amp(r.designed))
    np.testing.assert_allclose(r.amp_formula, sim, rtol=1e-7)
    np.testing.assert_allclose(np.array(r.deflection) * W ** 2, sim, rtol=1e-7)
    assert sim[0] == pytest.approx(13.2093, rel=1e-4)  # m/s², i.e. 372 µm of deflection
    assert sim[1] == pytest.approx(5.6968, rel=1e-4)   # 160 µm
    assert 1 - sim[1] / sim[0] == pytest.approx(0.5687, abs=1e-4)
    assert r.reduction == pytest.approx(1 - sim[1] / sim[0], rel=1e-6)
    assert r.reduction_formula == pytest.approx(r.reduction, rel=1e-9)


def test_fig10_with_damping_still_reduces():
    r = fig10_example(zeta=0.05)
    sim = (simulate_amp(r.conventional, zeta=0.05), simulate_amp(r.designed, zeta=0.05))
    np.testing.assert_allclose(np.array(r.deflection) * W ** 2, sim, rtol=1e-6)
    assert r.reduction > 0.4


def test_fig8_claims_hold_below_about_1_7_periods():
    """§4.2: shortening T1 reduces the residual in Condition III only (T_SUM <= 50 ms)."""
    m = amplitude_map(T_SUM=np.arange(20, 51) * 1e-3)
    r3 = m.t1_effect("III", 0.001)
    r1 = m.t1_effect("I", 0.001)
    r2 = m.t1_effect("II", 0.001)
    assert np.all(r3 < 0.9)               # at least 10 % less, up to 98 % less
    assert r3.min() < 0.05
    assert np.all(np.abs(r1 - 1) < 0.16)  # "not significantly affected"
    assert np.all(np.abs(r2 - 1) < 0.16)


def test_fig8_claim_fails_for_longer_positioning_times():
    """Past the conventional profile's first zero (T_SUM ≈ 68 ms) a short T1 can do worse."""
    m = amplitude_map(T_SUM=np.array([0.060, 0.064]))
    assert np.all(m.t1_effect("III", 0.001) > 1.5)


def test_amplitude_map_grid_and_plot():
    import matplotlib.figure

    m = amplitude_map(T1=np.arange(1, 31) * 1e-3, T_SUM=np.arange(20, 61, 5) * 1e-3)
    for c in CONDITIONS:
        a = m.amp[c]
        assert a.shape == (9, 30)
        TT1, TTS = np.meshgrid(m.T1, m.T_SUM)
        assert np.all(np.isnan(a[TT1 >= TTS / 2]))
        assert np.all(np.isfinite(a[TT1 < TTS / 2]))
        # one cell against the direct formula
        i, k = 4, 5  # T_SUM = 40 ms, T1 = 6 ms
        p = sato_profile(1e-3, 0.04, 0.006, c)
        assert a[i, k] == pytest.approx(abs(p.amplitude(30.0)), rel=1e-12)
    assert isinstance(m.plot(), matplotlib.figure.Figure)
    assert isinstance(fig10_example().plot(), matplotlib.figure.Figure)


def test_bad_arguments():
    with pytest.raises(ValueError):
        sato_profile(1e-3, 0.04, 0.02, "III")  # T1 = T_SUM/2: R = 0
    with pytest.raises(ValueError):
        sato_profile(1e-3, 0.04, 0.01, "IV")
    with pytest.raises(ValueError):
        jerk_J1(1e-3, 0.04, 0.01, "V")
    with pytest.raises(ValueError):
        amplitude_table1("X", 1.0, 0.01, 0.04, W)
