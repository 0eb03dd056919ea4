"""Jerk-time tuning: JL at the end of the motion, DJL at the start of each stage (§3.2, §4)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from harness.fmu.runner import generate
from harness.scenario import load_scenario
from harness.simulation.axis import MoveSamples, stage_starts
from harness.simulation.session import Session
from harness.tuning.rule import sinc_residual, tune_djl, tune_jl
from harness.tuning.tune import tune_profile

Te = 1e-3


def fake_move(starts, N, t_end=None, merged_gap=False):
    """A stand-in for the FMU: a_AL steps at the four stage starts (+a, 0, -a, 0)."""
    t_end = t_end if t_end is not None else starts[3] + N[3] * Te
    n = int(round((t_end + 0.01) / Te)) + 1
    t = Te * np.arange(n)
    a_AL = np.zeros(n)
    a_AL[(t >= starts[0] - 1e-12) & (t < starts[1] - 1e-12)] = 1.0
    a_AL[(t >= starts[2] - 1e-12) & (t < starts[3] - 1e-12)] = -1.0
    z = np.zeros(n)
    return MoveSamples(t, z, z, z, z, a_AL, t_end, tuple(N), 0.0)


def identity(t):
    return t


# ----------------------------------------------------------- without FMU


def test_constant_mode_gives_four_equal_jerk_times():
    P = 0.1234

    def plan(T_F):
        N = [int(round(x / Te)) for x in T_F]
        return fake_move([0.0, 0.3, 0.8, 1.1], N), identity

    res = tune_djl(plan, lambda z: P, Te, initial=0.2)
    assert res.N_F == (123, 123, 123, 123)
    assert res.converged and res.iterations == 2
    assert res.T_F == pytest.approx((0.123,) * 4)
    assert res.history == [(200,) * 4, (123,) * 4]


def test_djl_is_a_fixed_point_of_the_start_rule():
    """Stage starts move with the jerk times; the result reproduces itself."""
    P = lambda z: 0.08 + 0.05 * z  # noqa: E731 - period grows along the motion

    def plan(T_F):
        N = [int(round(x / Te)) for x in T_F]
        starts = [0.0, 0.2 + 0.5 * N[0] * Te, 0.7 + N[1] * Te, 0.75 + N[1] * Te + N[2] * Te]
        return fake_move(starts, N), identity

    res = tune_djl(plan, P, Te, initial=P(0.0))
    assert res.converged
    starts = res.instants
    assert res.N_F == tuple(int(round(P(t) / Te)) for t in starts)
    assert res.N_F[0] == 80 and res.N_F[3] > res.N_F[2] > res.N_F[1] > res.N_F[0]
    assert res.periods == pytest.approx([P(t) for t in starts])


def test_merged_middle_stages_share_the_period_at_their_start():
    P = lambda z: 0.1 + 0.1 * z  # noqa: E731

    def plan(T_F):
        N = [int(round(x / Te)) for x in T_F]
        s1 = 0.3
        # no constant velocity: stage 3 starts when stage 2 ends
        return fake_move([0.0, s1, s1 + N[1] * Te, 0.9], N), identity

    res = tune_djl(plan, P, Te, initial=0.1)
    assert res.merged
    assert res.N_F[1] == res.N_F[2] == int(round(P(0.3) / Te))


def test_rounding_cycle_returns_the_closest_member():
    """Stage 4 starts earlier when it is longer: the integer fixed point does not exist.

    N4 -> round((0.1012 + 0.5 (1 - 2 N4 Te)) / Te) = round(601.2 - N4): 300 -> 301 -> 300.
    Mismatch |N4 Te - P(start)| is 1.2 ms for 300 and 0.8 ms for 301: 301 is kept.
    """
    P = lambda z: 0.1012 + 0.5 * z  # noqa: E731

    def plan(T_F):
        N = [int(round(x / Te)) for x in T_F]
        return fake_move([0.0, 0.05, 0.1, 1.0 - 2 * N[3] * Te], N, t_end=1.5), identity

    res = tune_djl(plan, P, Te, initial=0.300, max_iter=30)
    assert not res.converged
    assert res.N_F[3] == 301
    assert res.history[-1] == res.N_F


def test_jl_tuned_to_the_period_at_the_end_of_the_motion():
    P = lambda z: 0.1 + 0.05 * z  # noqa: E731

    def plan(T_F):
        N = int(round(T_F[0] / Te))
        return fake_move([0.0, 0.3, 0.6, 0.9], [N] * 4, t_end=1.0 + N * Te), identity

    res = tune_jl(plan, P, Te, initial=0.1)
    # N = round(150 + 0.05 N) -> 158
    assert res.N_F == (158,) * 4 and res.converged
    assert res.instants[0] == pytest.approx(1.158)


def test_phase_rule_makes_each_stage_one_modal_cycle():
    f = lambda t: 10.0 - 4.0 * t  # noqa: E731 - frequency falling during the motion

    def plan(T_F):
        N = [int(round(x / Te)) for x in T_F]
        return fake_move([0.0, 0.4, 0.8, 1.2], N), identity

    res = tune_djl(plan, lambda z: 1.0 / f(z), Te, initial=0.1, rule="phase")
    for s, n in zip(res.instants, res.N_F, strict=True):
        # ∫ f dt over [s, s + T] = 1 in closed form: 10 T - 2 ((s+T)^2 - s^2) = 1
        T = (10 - 4 * s - math.sqrt((10 - 4 * s) ** 2 - 8)) / 4
        assert n == int(round(T / Te))
    with pytest.raises(ValueError):
        tune_djl(plan, lambda z: 0.1, Te, initial=0.1, rule="middle")


def test_sinc_residual_is_eq21_normalised():
    assert sinc_residual(0.2, 0.1) == pytest.approx(0.0, abs=1e-15)
    assert sinc_residual(0.1, 0.1) == pytest.approx(0.0, abs=1e-15)
    assert sinc_residual(1e-9, 0.1) == pytest.approx(1.0)
    assert sinc_residual(0.12, 0.1) == pytest.approx(abs(math.sin(1.2 * math.pi) / (1.2 * math.pi)))


def test_stage_starts_reads_the_a_al_steps():
    mv = fake_move([0.0, 0.25, 0.6, 0.9], [100, 110, 120, 130])
    starts, merged = stage_starts(mv)
    assert starts == pytest.approx([0.0, 0.25, 0.6, 0.9]) and not merged
    with pytest.raises(ValueError):
        stage_starts(dataclasses.replace(mv, a_AL=np.zeros_like(mv.a_AL)))


# ---------------------------------------------------------------- with FMU


def _jerk_from_ramps(t, starts, N, levels):
    """Fig. 7: the DJL jerk is the sum of four ramps, step i of height levels[i] filtered by a
    moving average of N[i] samples, i.e. jerk levels[i] / (N[i] Te) over N[i] samples."""
    j = np.zeros_like(t)
    for s, n, lv in zip(starts, N, levels, strict=True):
        j[(t >= s - 1e-9) & (t < s + n * Te - 1e-9)] += lv / (n * Te)
    return j


@pytest.mark.parametrize("name", ["X", "Y"])
def test_default_scenarios_djl_tuning_with_the_fmu(fmu2, name):
    sc = load_scenario(name)
    with Session(fmu2) as s:
        djl = tune_profile(s, sc, "DJL")
        jl = tune_profile(s, sc, "JL")
        run = s.run(sc, "DJL", djl.T_F)
    assert djl.converged and 1 <= djl.iterations <= 8
    # the FMU applied the jerk times asked for
    assert run.N_F == djl.N_F
    # independent check: the FMU's jerk output is the sum of four ramps starting at the stage
    # starts (ramps may overlap with short_stage = 2, so the jerk alone does not show them)
    params = Session.move_params(sc, "DJL", djl.T_F)
    tr = generate(params, fmu=fmu2)
    a_lv = [float(tr.a_AL[np.searchsorted(tr.t, s - 1e-9)]) for s in djl.instants]
    levels = [a_lv[0], -a_lv[0], a_lv[2], -a_lv[2]]
    j_rec = _jerk_from_ramps(tr.t, djl.instants, djl.N_F, levels)
    np.testing.assert_allclose(tr.j, j_rec, atol=1e-9 * np.max(np.abs(tr.j)))
    if name == "Y":
        # no constant-velocity stage: the middle stages are contiguous, one merged stage
        assert djl.merged and djl.N_F[1] == djl.N_F[2]
        assert djl.instants[2] == pytest.approx(djl.instants[1] + djl.N_F[1] * Te)
    else:
        assert not djl.merged
    # the period at each stage start, from a separately generated Z trajectory
    ztr = generate(Session.z_move_params(sc, run.z_v_max), fmu=fmu2, t_stop=tr.t[-1])
    z_at = [float(np.interp(ti, ztr.t, ztr.x)) for ti in djl.instants]
    expected = tuple(int(round(sc.modemap.period(z) / Te)) for z in z_at)
    if name == "Y":
        expected = (expected[0], expected[1], expected[1], expected[3])
    assert djl.N_F == expected
    # the mode falls along the motion: the jerk times grow stage after stage
    assert list(djl.N_F) == sorted(djl.N_F)
    # JL: the period at the end of the motion, where Z has arrived (synchronised)
    assert jl.N_F[0] == int(round(sc.modemap.period(sc.z.z0 + sc.z.distance) / Te))
    assert jl.z[0] == pytest.approx(sc.z.z0 + sc.z.distance, abs=1e-9)


def test_constant_mode_with_the_fmu(fmu3):
    from harness.modemap import ConstantLaw, ModeMap, ModeSpec

    sc = load_scenario("X")
    sc = dataclasses.replace(sc, modemap=ModeMap((ModeSpec(ConstantLaw(7.3), 0.02),)))
    with Session(fmu3) as s:
        djl = tune_profile(s, sc, "DJL")
        jl = tune_profile(s, sc, "JL")
    n = int(round(1 / 7.3 / Te))
    assert djl.N_F == (n,) * 4 and jl.N_F == (n,) * 4
    assert djl.converged and jl.converged
