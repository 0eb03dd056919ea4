"""Input shapers: impulses, zero residual at the tuned mode (by simulation), added time."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_peers_reference import simulate_motion

from harness.peers.shapers import (
    SHAPERS,
    al_profile,
    ei,
    make_shaper,
    mzv,
    shape,
    shaped_al,
    zv,
    zvd,
)

MOVE = {"distance": 0.4, "v_max": 0.5, "a_max": 4.0, "d_max": 4.0}
F = 7.3  # Hz, not a harmonic of the move's own times




@pytest.fixture(scope="module")
def al(fmu2):
    return al_profile(MOVE, fmu=fmu2)


@settings(max_examples=60, deadline=None)
@given(st.floats(0.5, 200.0), st.floats(0.0, 0.3), st.sampled_from(SHAPERS))
def test_impulse_sums_are_one(f, zeta, name):
    s = make_shaper(name, f, zeta)
    assert s.A.sum() == pytest.approx(1.0, abs=1e-12)
    assert np.all(s.A > 0)
    assert s.t[0] == 0.0 and np.all(np.diff(s.t) > 0)


def test_textbook_values_undamped():
    T = 1 / F
    s = zv(F)
    np.testing.assert_allclose(s.A, [0.5, 0.5])
    np.testing.assert_allclose(s.t, [0, T / 2])
    s = zvd(F)
    np.testing.assert_allclose(s.A, [0.25, 0.5, 0.25])
    np.testing.assert_allclose(s.t, [0, T / 2, T])
    s = ei(F, 0.0, 0.05)
    np.testing.assert_allclose(s.A, [0.2625, 0.475, 0.2625])
    s = mzv(F)
    np.testing.assert_allclose(s.t, [0, 3 * T / 8, 3 * T / 4])
    np.testing.assert_allclose(s.A, [1 - 1 / math.sqrt(2), math.sqrt(2) - 1, 1 - 1 / math.sqrt(2)])


def test_zv_damped_matches_bearee_eq20():
    zeta = 0.1
    K = math.exp(-zeta * math.pi / math.sqrt(1 - zeta ** 2))
    s = zv(F, zeta)
    np.testing.assert_allclose(s.A, [1 / (1 + K), K / (1 + K)], rtol=1e-14)
    assert s.duration == pytest.approx(math.pi / (2 * math.pi * F * math.sqrt(1 - zeta ** 2)))


@pytest.mark.parametrize("zeta", [0.0, 0.05])
@pytest.mark.parametrize("name", ["ZV", "ZVD", "MZV"])
def test_zero_residual_at_tuned_mode_by_simulation(al, name, zeta):
    s = make_shaper(name, F, zeta)
    m = shape(al.to_motion(), s)
    ref = simulate_motion(al.to_motion(), F, zeta)
    got = simulate_motion(m, F, zeta)
    assert ref > 1e-4  # the AL move does excite the mode
    assert got < 1e-7 * ref


@pytest.mark.parametrize("zeta", [0.0, 0.05])
def test_ei_leaves_its_tolerance_at_tuned_mode(al, zeta):
    s = ei(F, zeta, 0.05)
    m = shape(al.to_motion(), s)
    ratio = simulate_motion(m, F, zeta) / simulate_motion(al.to_motion(), F, zeta)
    assert ratio == pytest.approx(0.05, rel=1e-5)
    # and nearly zero at the two frequencies either side (found on a grid)
    f = F * np.linspace(0.7, 1.3, 601)
    V = s.residual_ratio(f)
    lo, hi = f < F, f > F
    assert V[lo].min() < 2e-3 and V[hi].min() < 2e-3
    # V <= 5 % over a wide band: the point of EI
    band = f[V <= 0.05 + 1e-9]
    assert band.min() < 0.86 * F and band.max() > 1.14 * F


def test_sensitivity_formula_against_simulation(al):
    """ZV off its mode: V = |cos(π f / (2 f0))| when undamped (shaped vs AL residual)."""
    s = zv(F)
    f = 1.2 * F
    ratio = simulate_motion(shape(al.to_motion(), s), f) / simulate_motion(al.to_motion(), f)
    assert ratio == pytest.approx(abs(math.cos(math.pi * 1.2 / 2)), rel=1e-6)
    assert s.residual_ratio(f) == pytest.approx(abs(math.cos(math.pi * 1.2 / 2)), rel=1e-12)
    s = zvd(F, 0.05)
    ratio = simulate_motion(shape(al.to_motion(), s), f, 0.05) / simulate_motion(
        al.to_motion(), f, 0.05)
    assert s.residual_ratio(f) == pytest.approx(ratio, rel=1e-6)


@pytest.mark.parametrize("name,periods", [("ZV", 0.5), ("ZVD", 1.0), ("MZV", 0.75)])
def test_added_motion_time(al, name, periods):
    """The shaped move ends exactly the shaper's length after the AL move (ZV: T_d / 2)."""
    zeta = 0.05
    Td = 1 / (F * math.sqrt(1 - zeta ** 2))
    m = shape(al.to_motion(), make_shaper(name, F, zeta))
    end = al.t_end + periods * Td
    x, v, a, _ = m.evaluate([end - 1e-4, end, end + 0.5])
    target = MOVE["distance"]
    assert x[0] < target - 1e-9  # still moving just before
    assert x[1] == pytest.approx(target, abs=1e-12) and x[2] == pytest.approx(target, abs=1e-12)
    assert abs(v[1]) < 1e-12 and abs(a[1]) < 1e-12
    assert m.motion_time == pytest.approx(al.motion_time + periods * Td, rel=1e-12)


def test_shaped_samples_keep_limits_and_endpoints(fmu2):
    s = shaped_al(MOVE, zvd(F, 0.02), fmu=fmu2)
    assert s.name == "AL*ZVD"
    assert s.x[-1] == pytest.approx(0.4, abs=1e-12)
    assert np.abs(s.v).max() <= 0.5 * (1 + 1e-12)
    assert np.abs(s.a).max() <= 4.0 * (1 + 1e-12)
    assert s.params["shaper"] == "ZVD"


def test_quantized_delays(fmu2, al):
    """A controller at Te rounds the delays: small residual left, delays on the grid."""
    s = zv(F)
    q = s.quantized(1e-3)
    np.testing.assert_allclose(q.t / 1e-3, np.round(q.t / 1e-3), atol=1e-9)
    sq = shaped_al(MOVE, s, quantize=True, fmu=fmu2)
    ratio = simulate_motion(sq.to_motion(), F) / simulate_motion(al.to_motion(), F)
    # delay error 0.5 ms at most: |cos(π f (T/2 + δ))| <= sin(π F δ) ~ 1.1 %
    assert 1e-4 < ratio < math.sin(math.pi * F * 0.5e-3) + 1e-6


def test_bad_modes_and_plot():
    import matplotlib.figure

    with pytest.raises(ValueError):
        zv(-1.0)
    with pytest.raises(ValueError):
        zvd(10.0, 1.0)
    with pytest.raises(ValueError):
        make_shaper("XYZ", 10.0)
    with pytest.raises(ValueError):
        ei(10.0, 0.5)
    assert isinstance(ei(10.0, 0.05).plot(), matplotlib.figure.Figure)
