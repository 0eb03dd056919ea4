"""Park et al. 2017: case selection, phase durations and total time; ruckig agrees."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from harness.peers.park import (
    PAPER_LIMITS,
    PAPER_MOVES,
    canonical_phases,
    case3_T1_as_printed,
    distance_of,
    park_profile,
    select_case,
)
from harness.peers.ruckig_ref import time_optimal

J, A, V = 5000.0, 3000.0, 6000.0  # the paper's §4 (degrees)




def test_paper_parameters():
    assert PAPER_LIMITS == {"J": J, "A": A, "V": V}
    assert PAPER_MOVES == {"I": 20000.0, "II": 6000.0, "III": 2000.0}


def test_case_I_paper_numbers():
    """P = 20000°: T1 = A/J = 0.6 s, T2 = V/A - A/J = 1.4 s, T4 = P/V - (2 T1 + T2) = 11/15 s."""
    p = park_profile(20000.0, V, A, J)
    assert p.case == "I"
    np.testing.assert_allclose(p.T, [0.6, 1.4, 0.6, 11 / 15, 0.6, 1.4, 0.6], rtol=1e-14)
    assert p.total_time == pytest.approx(20000 / 6000 + 6000 / 3000 + 3000 / 5000, rel=1e-14)
    assert p.total_time == pytest.approx(5.933333333333, rel=1e-12)
    assert p.v_peak == pytest.approx(V) and p.a_peak == pytest.approx(A)


def test_case_II_paper_numbers():
    """P = 6000°: T1 = 0.6 s and T2 = (-1.8 + sqrt(0.36 + 8)) / 2 (eq. 12)."""
    p = park_profile(6000.0, V, A, J)
    assert p.case == "II"
    T2 = (-1.8 + math.sqrt(0.36 + 8.0)) / 2
    np.testing.assert_allclose(p.T, [0.6, T2, 0.6, 0.0, 0.6, T2, 0.6], rtol=1e-14, atol=1e-15)
    assert T2 == pytest.approx(0.5456832294800961, rel=1e-14)
    assert p.total_time == pytest.approx(4 * 0.6 + 2 * T2, rel=1e-14)
    assert p.total_time == pytest.approx(3.491366458960, rel=1e-12)
    # peak speed below V (the case's definition), from v_p = A (T1 + T2)
    assert p.v_peak == pytest.approx(3000 * (0.6 + T2)) and p.v_peak < V


def test_case_III_paper_numbers():
    """P = 2000°: T1 = (P / 2J)^(1/3) = 0.2^(1/3), a_peak = J T1 < A."""
    p = park_profile(2000.0, V, A, J)
    assert p.case == "III"
    T1 = 0.2 ** (1 / 3)
    np.testing.assert_allclose(p.T, [T1, 0, T1, 0, T1, 0, T1], rtol=1e-14, atol=0)
    assert p.total_time == pytest.approx(2.339214190570, rel=1e-12)
    assert p.a_peak == pytest.approx(5000 * T1) and p.a_peak < A


def test_case_III_as_printed_misses_the_distance():
    """The paper's printed Case III root (T1 = (P A / 2J²)^(1/4)) does not travel P."""
    T1p = case3_T1_as_printed(2000.0, A, J)
    assert T1p == pytest.approx(0.12 ** 0.25, rel=1e-14)
    travelled = distance_of((T1p, 0, T1p, 0, T1p, 0, T1p), J)
    assert travelled == pytest.approx(2 * J * T1p ** 3, rel=1e-12)
    assert travelled / 2000.0 - 1 == pytest.approx(0.0194, abs=2e-4)  # 1.9 % too far
    T1 = park_profile(2000.0, V, A, J).T[0]
    assert distance_of((T1, 0, T1, 0, T1, 0, T1), J) == pytest.approx(2000.0, rel=1e-13)


@pytest.mark.parametrize("case,P", list(PAPER_MOVES.items()))
def test_paper_moves_against_ruckig(case, P):
    p = park_profile(P, V, A, J)
    r = time_optimal(P, V, A, J)
    assert p.case == case
    assert p.total_time == pytest.approx(r.duration, rel=1e-9)
    d1, j1 = canonical_phases(p.T, p.jerks)
    d2, j2 = canonical_phases(r.phases, r.jerks)
    np.testing.assert_allclose(d1, d2, rtol=1e-9)
    np.testing.assert_array_equal(np.sign(j1), np.sign(j2))
    # sampled through ruckig's at_time
    t = np.linspace(0, r.duration, 41)
    xr, vr, ar = r.at_time(t)
    xp, vp, ap, _ = p.motion().evaluate(t)
    np.testing.assert_allclose(xp, xr, atol=1e-9 * P)
    np.testing.assert_allclose(vp, vr, atol=1e-9 * V)
    np.testing.assert_allclose(ap, ar, atol=1e-9 * A)


# the case boundaries for the paper's limits: V reached from P = V (V/A + A/J) = 15600 deg,
# A reached from P = 2 A^3 / J^2 = 2160 deg (random moves rarely fall this close)
@pytest.mark.parametrize("case,P", [("II", 15500.0), ("I", 15700.0),
                                    ("III", 2100.0), ("II", 2200.0)])
def test_moves_either_side_of_the_case_boundaries(case, P):
    p = park_profile(P, V, A, J)
    assert p.case == case
    assert p.total_time == pytest.approx(time_optimal(P, V, A, J).duration, rel=1e-9)
    assert p.motion().x[-1] == pytest.approx(P, rel=1e-12)


limits = st.tuples(st.floats(0.01, 10.0), st.floats(0.1, 50.0), st.floats(1.0, 2000.0))


@settings(max_examples=150, deadline=None)
@given(limits, st.floats(-3.0, 3.0), st.sampled_from([-1.0, 1.0]))
def test_random_moves_against_ruckig(lim, logP, sign):
    """Durations equal to 1e-9 relative; the profile lands on P at rest within the limits."""
    Vr, Ar, Jr = lim
    P = sign * 10.0 ** logP
    p = park_profile(P, Vr, Ar, Jr)
    r = time_optimal(P, Vr, Ar, Jr)
    assert p.total_time == pytest.approx(r.duration, rel=1e-9)
    d1, _ = canonical_phases(p.T, p.jerks)
    d2, _ = canonical_phases(r.phases, r.jerks)
    if d1.size == d2.size:
        np.testing.assert_allclose(d1, d2, rtol=1e-7, atol=1e-9 * r.duration)
    m = p.motion()
    assert m.x[-1] == pytest.approx(P, rel=1e-10)
    assert abs(m.v[-1]) <= 1e-9 * Vr and abs(m.a[-1]) <= 1e-9 * Ar
    t = np.linspace(0, p.total_time, 501)
    _, v, a, j = m.evaluate(t)
    assert np.abs(v).max() <= Vr * (1 + 1e-9)
    assert np.abs(a).max() <= Ar * (1 + 1e-9)
    assert np.abs(j).max() <= Jr * (1 + 1e-12)


@settings(max_examples=100, deadline=None)
@given(limits, st.floats(-3.0, 3.0))
def test_case_says_which_limits_are_reached(lim, logP):
    Vr, Ar, Jr = lim
    P = 10.0 ** logP
    p = park_profile(P, Vr, Ar, Jr)
    tol = 1e-9
    reaches_v = p.v_peak >= Vr * (1 - tol)
    reaches_a = p.a_peak >= Ar * (1 - tol)
    expected = {(True, True): "I", (False, True): "II", (False, False): "III",
                (True, False): "IV"}[(reaches_v, reaches_a)]
    if p.case != expected:  # only acceptable on a boundary
        assert min(abs(p.v_peak / Vr - 1), abs(p.a_peak / Ar - 1)) < 1e-6, (p, expected)
    assert select_case(P, Vr, Ar, Jr) == p.case


def test_case_IV_outside_the_paper():
    """V < A²/J: the speed limit is hit while the acceleration still ramps."""
    p = park_profile(10.0, 1.0, 10.0, 10.0)  # A²/J = 10 > V = 1
    assert p.case == "IV"
    assert p.T[1] == 0.0 and p.T[3] > 0.0
    assert p.v_peak == pytest.approx(1.0) and p.a_peak < 10.0
    assert p.total_time == pytest.approx(time_optimal(10.0, 1.0, 10.0, 10.0).duration, rel=1e-9)


def test_bad_limits_and_plot():
    import matplotlib.figure

    with pytest.raises(ValueError):
        park_profile(1.0, 0.0, 1.0, 1.0)
    with pytest.raises(ValueError):
        park_profile(1.0, 1.0, float("inf"), 1.0)
    assert isinstance(park_profile(20000.0, V, A, J).plot(), matplotlib.figure.Figure)


def test_negative_move_is_mirrored():
    p = park_profile(-6000.0, V, A, J)
    q = park_profile(6000.0, V, A, J)
    assert p.T == q.T
    t = np.linspace(0, q.total_time, 11)
    np.testing.assert_allclose(p.motion().evaluate(t)[0], -q.motion().evaluate(t)[0])


def test_phase_shorter_than_the_time_resolution_is_folded():
    """A closed form can leave a phase of 1e-17 s (found by hypothesis: P = -1, V = 0.01,
    A = 0.1, J = 1): the motion is still built, lands on P at rest, breakpoints increasing."""
    p = park_profile(-1.0, 0.010000000000000002, 0.1, 1.0)
    assert min(t for t in p.T if t > 0) < 1e-15
    m = p.motion()
    assert np.all(np.diff(m.tb) > 0)
    assert m.x[-1] == pytest.approx(-1.0, rel=1e-10)
    assert abs(m.v[-1]) <= 1e-12 and abs(m.a[-1]) <= 1e-12
