"""The common motion representation and the exact residual computation."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_peers_reference import simulate_motion

from harness.fmu.runner import generate
from harness.peers.residual import (
    free_deflection,
    residual_amplitude,
    robustness_curve,
)
from harness.peers.trajectory import PiecewiseJerk, SampledTrajectory, from_fmu

MOVE = {"distance": 0.4, "v_max": 0.5, "a_max": 4.0, "d_max": 4.0}




@pytest.fixture(scope="module")
def fmu_moves(fmu2):
    return {prof: generate(dict(MOVE, profile=prof, T_F1=0.08), fmu=fmu2) for prof in (1, 2, 3)}


def test_from_jerk_matches_hand_integration():
    # +J for 1 s, -J for 2 s, +J for 1 s: a triangle up and down, rest to rest
    J = 3.0
    m = PiecewiseJerk.from_jerk([1, 2, 1], [J, -J, J])
    x, v, a, j = m.evaluate([0.5, 1.0, 2.0, 4.0, 5.0])
    np.testing.assert_allclose(a, [1.5, 3.0, 0.0, 0.0, 0.0], atol=1e-15)
    # v(1) = J/2, v(2) = J/2 + J*1 - J/2 = J, x(4) = 2*J (symmetric S, peak v = J at t=2)
    np.testing.assert_allclose(v[[1, 2]], [J / 2, J], rtol=1e-15)
    assert x[3] == pytest.approx(2 * J, rel=1e-14)
    assert x[4] == pytest.approx(2 * J, rel=1e-14)
    assert j[0] == J and j[1] == -J and j[4] == 0.0
    assert m.t_start == 0.0 and m.t_end == 4.0


def test_evaluate_left_and_right_of_a_step():
    m = PiecewiseJerk.from_jerk([1.0], [0.0], a0=2.0)  # AL-like: a = 2 on [0, 1)
    assert m.evaluate([0.0], side="left")[2][0] == 0.0
    assert m.evaluate([0.0], side="right")[2][0] == 2.0
    assert m.evaluate([1.0], side="left")[2][0] == 2.0


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(0.01, 1.0), min_size=1, max_size=6),
       st.lists(st.floats(-50, 50), min_size=6, max_size=6),
       st.floats(0.0, 2.0), st.floats(-1, 1))
def test_derivatives_are_consistent(durations, jerks, a0, v0):
    """x' = v, v' = a (central differences) inside every piece."""
    m = PiecewiseJerk.from_jerk(durations, jerks[: len(durations)], a0=a0, v0=v0)
    mids = 0.5 * (m.tb[:-1] + m.tb[1:])
    h = 1e-5 * np.min(np.diff(m.tb))
    xp, vp, ap, _ = m.evaluate(mids + h)
    xm, vm, am, _ = m.evaluate(mids - h)
    x, v, a, j = m.evaluate(mids)
    scale = 1 + np.abs(v).max() + np.abs(a).max() + np.abs(j).max()
    np.testing.assert_allclose((xp - xm) / (2 * h), v, atol=1e-6 * scale)
    np.testing.assert_allclose((vp - vm) / (2 * h), a, atol=1e-6 * scale)
    np.testing.assert_allclose((ap - am) / (2 * h), j, atol=1e-5 * scale)


@settings(max_examples=20, deadline=None)
@given(st.lists(st.floats(0.05, 1.0), min_size=2, max_size=4),
       st.lists(st.floats(-0.3, 0.3), min_size=4, max_size=4),
       st.lists(st.floats(-1, 1), min_size=4, max_size=4))
def test_weighted_sum_is_the_sum_of_shifted_copies(durs, delays, weights):
    n = len(durs)
    base = [PiecewiseJerk.from_jerk(durs, [5.0 * (-1) ** k for k in range(n)], t0=0.1 * i)
            for i in range(n)]
    s = PiecewiseJerk.weighted_sum(base, weights[:n], delays[:n])
    t = np.linspace(-1, 6, 997)
    direct = [sum(w * b.evaluate(t - d)[k] for b, w, d in zip(base, weights, delays,
                                                              strict=False))
              for k in range(3)]
    for k in range(3):
        np.testing.assert_allclose(s.evaluate(t)[k], direct[k], atol=1e-11)


@pytest.mark.parametrize("profile", [1, 2, 3])
def test_fmu_samples_are_exact_pieces(fmu_moves, profile):
    """The FMU's jerk is constant per sample: each piece lands on the next sample."""
    tr = fmu_moves[profile]
    st_ = from_fmu(tr)
    m = st_.to_motion()
    x, v, a, _ = m.evaluate(tr.t[1:], side="left")
    np.testing.assert_allclose(x, tr.x[1:], rtol=0, atol=1e-12)
    np.testing.assert_allclose(v, tr.v[1:], rtol=0, atol=1e-12)
    if profile != 1:  # AL acceleration steps at samples; JL/DJL are continuous
        np.testing.assert_allclose(a, tr.a[1:], rtol=0, atol=1e-9)
    # sampling the rebuilt motion gives back the FMU's samples (its semantics)
    back = m.sample(tr.params["Te"], t_stop=tr.t[-1])
    for name in ("x", "v", "a", "j"):
        np.testing.assert_allclose(getattr(back, name), getattr(tr, name), rtol=0, atol=1e-9)
    assert st_.motion_time == tr.motion_time
    assert st_.t_end == pytest.approx(tr.t_end)


def test_sampled_trajectory_semantics():
    # jerk switches in the middle of a sample: j[k] is the mean jerk over the interval
    m = PiecewiseJerk.from_jerk([0.0015, 0.003, 0.0015], [100.0, -100.0, 100.0])
    s = m.sample(1e-3)
    assert isinstance(s, SampledTrajectory)
    assert s.j[0] == pytest.approx(100.0)
    # [1, 2] ms: +100 for 0.5 ms then -100 for 0.5 ms: mean 0
    assert s.j[1] == pytest.approx(0.0, abs=1e-9)
    a1 = m.evaluate([1e-3])[2][0]
    a2 = m.evaluate([2e-3])[2][0]
    assert s.j[1] == pytest.approx((a2 - a1) / 1e-3)
    assert s.done[-1] and not s.done[0]
    assert s.distance == pytest.approx(m.x[-1])


@pytest.mark.parametrize("zeta", [0.0, 0.04])
@pytest.mark.parametrize("profile", [1, 2, 3])
def test_residual_matches_solve_ivp(fmu_moves, profile, zeta):
    m = from_fmu(fmu_moves[profile]).to_motion()
    f = 6.3
    got = residual_amplitude(m, f, zeta)
    ref = simulate_motion(m, f, zeta)
    assert got == pytest.approx(ref, rel=1e-7, abs=1e-12 * residual_amplitude(
        from_fmu(fmu_moves[1]).to_motion(), f, zeta))


def test_free_deflection_is_the_envelope(fmu_moves):
    m = from_fmu(fmu_moves[2]).to_motion()
    f = 9.0
    t = m.t_end + np.linspace(0, 1 / f, 2001)
    eps = free_deflection(m, f, 0.0, t)
    assert np.abs(eps).max() == pytest.approx(residual_amplitude(m, f), rel=1e-5)
    with pytest.raises(ValueError):
        free_deflection(m, f, 0.0, [m.t_end - 0.1])


def test_residual_vectorised_over_frequency(fmu_moves):
    m = from_fmu(fmu_moves[1]).to_motion()
    f = np.array([3.0, 5.0, 8.0])
    vec = residual_amplitude(m, f, 0.02)
    one = [residual_amplitude(m, fi, 0.02) for fi in f]
    np.testing.assert_allclose(vec, one, rtol=1e-12)


def test_robustness_curve_plot(fmu_moves, fmu2):
    import matplotlib.figure

    jl = generate(dict(MOVE, profile=2, T_F1=0.07), fmu=fmu2)
    motions = {"AL": from_fmu(fmu_moves[1]), "JL": from_fmu(jl)}
    # JL with T_F = 70 ms cancels 1/T_F: the curve has its zero at error 0
    rc = robustness_curve(motions, 1 / 0.07, 0.0, np.linspace(-0.3, 0.3, 13), reference="AL")
    pc = rc.percent()
    np.testing.assert_allclose(pc["AL"], 100.0)
    assert pc["JL"][6] < 1e-8
    assert pc["JL"][0] > 5.0
    assert isinstance(rc.plot(), matplotlib.figure.Figure)
    assert isinstance(from_fmu(fmu_moves[2]).plot(others=[from_fmu(fmu_moves[1])]),
                      matplotlib.figure.Figure)
