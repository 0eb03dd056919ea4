"""JL and DJL as moving-average filtering of the AL profile (issue #2, §2.1–2.3).

The AL profile that the FMU outputs beside the reference (x_AL, v_AL, a_AL) is
the filter input; here it is filtered with numpy, independently of the
generator's closed form, and compared sample by sample.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from harness.fmu.runner import generate

from _motion_checks import check_end_and_limits, jerk_runs, motion_start, moving_average_check


@pytest.mark.parametrize("short_stage", [1, 2])
@pytest.mark.parametrize("case", [
    {"distance": 0.4},                                   # v_max reached
    {"distance": 0.02},                                  # triangular
    {"distance": -0.3, "v0": -0.2, "v_e": -0.05},        # moving start and end
    {"n_segments": 17, "seg_distance": [0.12] * 17,
     "seg_v_end": [0.3, 0.5, 0.5, 0.0, 0.2] * 3 + [0.4, 0.0]},  # multi-segment
])
def test_jl_is_moving_average_of_al(fmu, case, short_stage):
    p = {"profile": 2, "T_F1": 0.037, "v_max": 0.6, "a_max": 5.0, "d_max": 3.0,
         "short_stage": short_stage, "t_start": 0.05, **case}
    tr = generate(p, fmu=fmu)
    check_end_and_limits(tr)
    N = tr.N_F[0]
    assert N == round(0.037 / 1e-3)
    ea, ev, ex = moving_average_check(tr, N)
    assert ea <= 1e-12 * 5.0
    assert ev <= 1e-12 * 0.6
    assert ex <= 1e-12 * 1.0


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(T_F=st.floats(0.002, 0.2), d=st.floats(0.001, 1.0), v0=st.floats(0.0, 1.0),
       rule=st.sampled_from([1, 2]))
def test_jl_moving_average_random(fmu2, T_F, d, v0, rule):
    p = {"profile": 2, "T_F1": T_F, "distance": d + 2 * v0 * (1.2 + 2 * T_F), "v0": v0,
         "v_max": 1.0, "a_max": 3.0, "d_max": 3.0, "short_stage": rule}
    tr = generate(p, fmu=fmu2)
    ea, ev, ex = moving_average_check(tr, tr.N_F[0])
    assert max(ea / 3.0, ev, ex) <= 1e-11


def _steps_of(a_al: np.ndarray) -> list[tuple[int, float]]:
    """(sample, amplitude) of the steps of a piecewise-constant AL acceleration."""
    d = np.diff(np.concatenate([[0.0], a_al]))
    idx = np.nonzero(np.abs(d) > 1e-9 * np.abs(a_al).max())[0]
    return [(int(k), float(d[k])) for k in idx]


def _ramp(n: int, start: int, N: int) -> np.ndarray:
    """Unit step at ``start`` filtered by an N-sample moving average, sampled at 0..n-1."""
    k = np.arange(n) - start
    return np.clip(k / N, 0.0, 1.0)


@pytest.mark.parametrize("T_F", [(0.08, 0.08, 0.06, 0.05), (0.02, 0.03, 0.06, 0.08),
                                 (0.05, 0.011, 0.073, 0.02)])
def test_djl_is_sum_of_separately_filtered_steps(fmu, T_F):
    """Eq. (11), Fig. 7: a_DJL = sum_i a_i step(t - T_i) * F_i with the i-th filter."""
    p = {"profile": 3, "distance": 0.4, "v_max": 1.0, "a_max": 10.0, "d_max": 10.0,
         **{f"T_F{i + 1}": t for i, t in enumerate(T_F)}}
    tr = generate(p, fmu=fmu)
    check_end_and_limits(tr)
    steps = _steps_of(tr.a_AL)
    assert len(steps) == 4, steps
    assert steps[0][1] > 0 and steps[1][1] < 0 and steps[2][1] < 0 and steps[3][1] > 0
    N = [round(t / 1e-3) for t in T_F]
    assert tuple(N) == tr.N_F
    a = sum(A * _ramp(len(tr.t), k, N[i]) for i, (k, A) in enumerate(steps))
    assert np.abs(a - tr.a).max() <= 1e-12 * 10.0
    # the four amplitudes are [a, -a, -d, d] (eq. 11)
    assert steps[0][1] == pytest.approx(-steps[1][1], rel=1e-12)
    assert steps[2][1] == pytest.approx(-steps[3][1], rel=1e-12)


@pytest.mark.parametrize("T_F", [(0.02, 0.06, 0.03, 0.09), (0.09, 0.03, 0.07, 0.01)])
def test_djl_commutation_times(fmu2, T_F):
    """Eq. (14)-(16) re-derived: a filtered step A at tau with N samples adds A (t - tau - N/2)
    to the velocity, so the peak velocity is v0 + a (T_1 + (T_F2 - T_F1)/2) and the
    deceleration removes d (T_3 - T_2 + (T_F4 - T_F3)/2).  (The extracted eq. (16) lost
    the T_d of T_3 = T_2 + T_d - (T_F4 - T_F3)/2.)"""
    Te = 1e-3
    p = {"profile": 3, "distance": 0.5, "v0": 0.1, "v_e": 0.2, "v_max": 0.8, "a_max": 6.0,
         "d_max": 4.0, **{f"T_F{i + 1}": t for i, t in enumerate(T_F)}}
    tr = generate(p, fmu=fmu2)
    check_end_and_limits(tr)
    (k1, a1), (k2, _), (k3, d3), (k4, _) = _steps_of(tr.a_AL)
    N1, N2, N3, N4 = tr.N_F
    v_peak = tr.v[(k2 + N2 + k3) // 2]  # in the cruise
    assert np.allclose(tr.v[k2 + N2:k3], v_peak, rtol=1e-12, atol=0)
    T1, T2, T3 = (k2 - k1) * Te, (k3 - k1) * Te, (k4 - k1) * Te
    assert v_peak == pytest.approx(0.1 + a1 * (T1 + (N2 - N1) * Te / 2), rel=1e-12)
    assert 0.2 == pytest.approx(v_peak + d3 * (T3 - T2 + (N4 - N3) * Te / 2), rel=1e-12)
    # limits: the recomputed levels never exceed the requested ones
    assert 0 < a1 <= 6.0 and 0 < -d3 <= 4.0 and v_peak <= 0.8


def test_paper_fallback_single_jerk_time_when_T1_would_be_negative(fmu2):
    """short_stage = 2 (the paper's rule): T_1 = T_a - (T_F2 - T_F1)/2 < 0 -> T_F2 := T_F1."""
    Te = 1e-3
    # tiny velocity change: T_a = 0.05/10 = 5 ms, while (T_F2 - T_F1)/2 = 35 ms
    p = {"profile": 3, "short_stage": 2, "distance": 0.5, "v0": 0.95, "v_e": 0.95,
         "v_max": 1.0, "a_max": 10.0, "d_max": 10.0,
         "T_F1": 0.01, "T_F2": 0.08, "T_F3": 0.03, "T_F4": 0.03}
    tr = generate(p, fmu=fmu2, debug_logging=True)
    check_end_and_limits(tr)
    k0 = int(np.searchsorted(tr.t, motion_start(tr) - 1e-9))
    steps = _steps_of(tr.a_AL)
    (k1, a1), (k2, _) = steps[:2]
    Ta = k2 - k1                     # whole samples of the AL acceleration stage
    N1 = round(0.01 / Te)
    assert Ta < N1 and Ta < (0.08 - 0.01) / 2 / Te   # T_1 = T_a - (T_F2 - T_F1)/2 < 0
    # two ramps of the same T_F1, offset by T_a: +J for T_a, 0 for N1 - T_a, -J for T_a
    J = a1 / 0.01
    acc = [r for r in jerk_runs(tr.j) if r.start < k0 + 2 * N1]
    assert [(r.start - k0, r.length) for r in acc] == [(0, Ta), (N1, Ta)]
    assert acc[0].jerk == pytest.approx(J, rel=1e-12)
    assert acc[1].jerk == pytest.approx(-J, rel=1e-12)
    assert any("one jerk time used" in r.message and "T_F2 := T_F1" in r.message
               for r in tr.log), [str(r) for r in tr.log]


def test_stretch_rule_keeps_every_stage_at_its_jerk_time(fmu2):
    """Default rule on the same short acceleration: the stage is lengthened instead."""
    p = {"profile": 3, "short_stage": 1, "distance": 0.5, "v0": 0.95, "v_e": 0.95,
         "v_max": 1.0, "a_max": 10.0, "d_max": 10.0,
         "T_F1": 0.01, "T_F2": 0.08, "T_F3": 0.03, "T_F4": 0.03}
    tr = generate(p, fmu=fmu2)
    check_end_and_limits(tr)
    k0 = int(np.searchsorted(tr.t, motion_start(tr) - 1e-9))
    lengths = [r.length for r in jerk_runs(tr.j) if r.start >= k0]
    assert lengths[:2] == [10, 80], lengths
    assert sorted(lengths[2:]) == [30, 30]


def test_jl_jerk_is_a_over_T_F_and_never_exceeds_it_in_paper_mode(fmu2):
    """Paper rule: ramps may overlap (T_a < T_F); the jerk magnitude stays a/T_F."""
    p = {"profile": 2, "short_stage": 2, "distance": 0.02, "T_F1": 0.1, "v_max": 1.0,
         "a_max": 10.0, "d_max": 10.0}
    tr = generate(p, fmu=fmu2)
    check_end_and_limits(tr)
    a_level = np.abs(tr.a_AL).max()
    assert np.abs(tr.j).max() == pytest.approx(a_level / 0.1, rel=1e-12)
    # the peak acceleration is below the AL level: the ramps overlapped
    assert np.abs(tr.a).max() < a_level * 0.99


def test_djl_segments_do_not_overlap_ramps_of_different_lengths(fmu2):
    """Multi-segment DJL: a segment starts its first stage only once the ramps of the
    previous one are over.  Otherwise segment 1's long deceleration ramp (100 samples)
    would still be running while segment 2's short acceleration ramps (5 and 30
    samples) complete, and their different lags add up above v_max."""
    p = {"profile": 3, "v_max": 1.0, "a_max": 10.0, "d_max": 10.0,
         "T_F1": 0.005, "T_F2": 0.03, "T_F3": 0.1, "T_F4": 0.1,
         "n_segments": 2, "seg_distance": [0.3, 0.6], "seg_v_end": [0.2, 1.0]}
    tr = generate(p, fmu=fmu2)
    check_end_and_limits(tr)          # |v| <= v_max among the rest
    runs = jerk_runs(tr.j)
    # segment 1: +a/T_F1, -a/T_F2, -d/T_F3, +d/T_F4; segment 2 starts with +a'/T_F1
    lengths = [r.length for r in runs]
    assert lengths[:4] == [5, 30, 100, 100], lengths
    end_seg1 = runs[3].start + runs[3].length
    assert runs[4].start >= end_seg1, (runs[4].start, end_seg1)
    # and the velocity really was at the boundary value in between
    assert tr.v[end_seg1] == pytest.approx(0.2, rel=1e-12)
