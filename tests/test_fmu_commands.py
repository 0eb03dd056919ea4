"""The commanded generator FMU (issue #12): target/execute/stop/f_mode in, busy/stage out.

Driven through fmpy's low-level slaves (FMI 2, and FMI 3 for a subset), inputs set between
doStep calls.  Every check is made on the recorded outputs against the interface contract of
issue #12 and elementary kinematics (tests/_command_checks.py), never against the planner:

1. random command sequences (hypothesis): execute / stop / f_mode changes fired while the
   motion accelerates, cruises, decelerates or rests; the motion ends at the last target at
   rest, limits hold, x, v, a are continuous with the reported jerk, stage and busy agree
   with j and done, stops come to rest and stay there;
2. with the new inputs untouched, or set to their start values, the outputs are bit for bit
   those of the FMU before the interface existed (hashes recorded from 8f30fb7);
3. bad input values are refused by name and change nothing (a bad target: taken, its
   command refused with cmd_error, tests/test_fmu_cmd.py);
4. FMU states taken in the middle of a commanded move replay bit for bit;
5. jerk_source = 2: each stage lasts round(1/(f_mode Te)) samples for the f_mode of its start.

The larger campaign runs on demand: DJL_FMU_COMMAND_CAMPAIGN=<examples> pytest -k campaign.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from _command_checks import (
    SHORTENED,
    START,
    Axis,
    Driver,
    Event,
    Record,
    Script,
    StopCount,
    Tolerances,
    check_all,
    check_stage_ramps,
    check_stops,
    expect_fmu_error,
    f_for,
    f_index,
    n_of_f,
    phase_of,
    profile_samples,
    rest_to_rest_moves,
)
from hypothesis import HealthCheck, given, settings
from hypothesis import event as _event
from hypothesis import note as _note
from hypothesis import strategies as st

from harness.fmu.runner import FMUError, GeneratorFMU, generate

HERE = Path(__file__).resolve().parent
CAMPAIGN = int(os.environ.get("DJL_FMU_COMMAND_CAMPAIGN", "0") or 0)
"""Examples of the on-demand campaign (0: skipped)."""


def _n(default: int) -> int:
    """Example count: the default, or 10x under HYPOTHESIS_PROFILE=thorough."""
    return default * 10 if os.environ.get("HYPOTHESIS_PROFILE") == "thorough" else default


# ------------------------------------------------------------------ instances


@pytest.fixture(scope="module")
def pool(fmus: dict[int, Path]) -> Iterator[dict[int, tuple[GeneratorFMU, GeneratorFMU]]]:
    """Per FMI version an instance under test and a scout (reused: reset between examples)."""
    out = {}
    for v in (2, 3):
        # (logging: the exceptions the checks allow are those the FMU reports)
        g = GeneratorFMU(fmus[v], instance_name=f"commanded{v}", debug_logging=True)
        scout = GeneratorFMU(fmus[v], instance_name=f"scout{v}")
        scout.initialize()
        out[v] = (g, scout)
    yield out
    for g, scout in out.values():
        g.close()
        scout.close()


# ----------------------------------------------------------------- strategies


def _log_uniform(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0**e)


def _f_value(Te: float) -> st.SearchStrategy[float]:
    """An f_mode whose jerk time is 1..25 samples, away from rounding ties."""
    return st.builds(lambda n, d: f_for(n, Te, d), st.integers(1, 25), st.floats(-0.4, 0.4))


@st.composite
def axes(draw: st.DrawFn, *, jerk_source: int | None = None,
         profiles: tuple[int, ...] = (1, 2, 3), short_stage: int = 1,
         jerk_sources: tuple[int, ...] = (1, 2)) -> Axis:
    Te = draw(st.sampled_from([1e-3, 1e-3, 5e-4, 2e-3]))
    profile = draw(st.sampled_from(profiles))
    js = jerk_source if jerk_source is not None else (
        1 if profile == 1 else draw(st.sampled_from(jerk_sources)))
    v_max = draw(_log_uniform(0.05, 2.0))
    t_acc = draw(st.integers(4, 100))            # samples to reach v_max at a_max
    a_max = v_max / (t_acc * Te)
    d_max = draw(st.one_of(st.just(a_max), _log_uniform(0.3, 3.0).map(lambda r: r * a_max)))
    N = tuple(draw(st.integers(1, 25)) for _ in range(4))
    dither = tuple(draw(st.floats(-0.4, 0.4)) for _ in range(4))
    f0 = draw(st.one_of(st.none(), _f_value(Te))) if js >= 2 else None
    ax = Axis(profile=profile, jerk_source=js, Te=Te, v_max=v_max, a_max=a_max, d_max=d_max,
              N=N, dither=dither, x0=draw(st.floats(-1.0, 1.0)),  # type: ignore[arg-type]
              short_stage=short_stage, f_mode0=f0)
    if draw(st.integers(0, 3)) == 0:   # sometimes commands interrupt a parametric move
        rel = draw(st.floats(0.05, 2.0)) * draw(st.sampled_from([1.0, -1.0]))
        ax = Axis(**{**ax.__dict__, "distance": rel * ax.char_distance(_n_max(ax, ()))})
    return ax


def _n_max(ax: Axis, fs: tuple[float, ...] | list[float]) -> int:
    if ax.jerk_source == 1:
        return max(ax.jerk_times(), default=1)
    f0 = ax.f_mode0 if ax.f_mode0 is not None else float(START["f_mode"])
    n = max(n_of_f(f, ax.Te) for f in (f0, *fs))
    return 4 * n if ax.jerk_source == 3 else n   # 3: extrapolated f_mode, longer ones too


@st.composite
def events(draw: st.DrawFn, ax: Axis, *, n: tuple[int, int] = (1, 6),
           kinds: tuple[str, ...] = ("execute", "execute", "execute", "execute", "stop", "stop",
                                     "exec_stop", "fmode", "sweep", "target"),
           ) -> list[Event]:
    out = []
    count = draw(st.integers(*n))
    for i in range(count):
        kind = "execute" if i == 0 and draw(st.booleans()) else draw(st.sampled_from(kinds))
        phase = draw(st.sampled_from(["acc", "cruise", "dec", "rest", "any", "early"]))
        rel = draw(st.one_of(
            st.floats(-3.0, 3.0),
            st.builds(lambda m, s: m * s, _log_uniform(1e-4, 0.1), st.sampled_from([1.0, -1.0])),
            st.just(0.0), st.just(math.nan)))
        hold = draw(st.sampled_from([1, 1, 1, 2, 5]))
        f: tuple[float, ...] = ()
        if kind == "fmode":
            f = (draw(_f_value(ax.Te)),)
        elif kind == "sweep":
            f = tuple(draw(st.lists(_f_value(ax.Te), min_size=2, max_size=60)))
        out.append(Event(kind, phase, draw(st.floats(0.0, 1.0)), rel, hold, f))
    return out


def _run(pool: dict[int, tuple[GeneratorFMU, GeneratorFMU]], version: int, ax: Axis,
         evs: list[Event], h_ratio: float) -> tuple[Driver, Script]:
    g, scout = pool[version]
    fs = [f for e in evs for f in e.f]
    n_max = _n_max(ax, fs)
    drv = Driver(g, ax)
    script = Script(drv, scout, h_ratio * ax.Te, n_max, ax.char_distance(n_max))
    note(f"axis {ax}")
    for e in evs:
        note(f"event {e}")
        script.fire(e)
    script.finish()
    return drv, script


def note(msg: str) -> None:
    """hypothesis.note inside a hypothesis test, nothing elsewhere."""
    try:
        _note(msg)
    except Exception:  # noqa: BLE001 - not in a hypothesis test
        pass


def event(msg: str) -> None:
    try:
        _event(msg)
    except Exception:  # noqa: BLE001
        pass


def _param_end(ax: Axis) -> float:
    return ax.x0 + ax.distance


def _check(drv: Driver, script: Script) -> None:
    for kind, phase in script.fired:
        event(f"{kind} while {phase}")
    counts = check_all(drv, param_end=_param_end(drv.axis))
    event(f"rest-to-rest moves checked: {min(counts['rest_to_rest'], 2)}+")
    event(f"ramps checked: {min(counts['ramps'], 5)}+")


# ---------------------------------------------- 1. random command sequences


@settings(max_examples=_n(45), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(st.data(), st.sampled_from([1.0, 1.0, 1.0, 0.37]))
def test_random_command_sequences(pool, data, h_ratio):
    ax = data.draw(axes())
    evs = data.draw(events(ax))
    drv, script = _run(pool, 2, ax, evs, h_ratio)
    _check(drv, script)


@settings(max_examples=_n(12), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(st.data(), st.sampled_from([1.0, 0.37]))
def test_random_command_sequences_fmi3(pool, data, h_ratio):
    ax = data.draw(axes())
    evs = data.draw(events(ax, n=(1, 4)))
    drv, script = _run(pool, 3, ax, evs, h_ratio)
    _check(drv, script)


@settings(max_examples=_n(10), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(st.data(), st.sampled_from([1.0, 0.37]))
def test_fmi2_and_fmi3_agree_bit_for_bit(pool, data, h_ratio):
    """The same inputs at the same steps give the same outputs through either FMI version."""
    ax = data.draw(axes())
    evs = data.draw(events(ax, n=(1, 4)))
    drv2, _ = _run(pool, 2, ax, evs, h_ratio)
    g3 = pool[3][0]
    drv3 = Driver(g3, ax)
    _replay_steps(drv3, drv2.rec)
    assert np.array_equal(drv2.rec.rows(), drv3.rec.rows())


def _replay_steps(drv: Driver, rec: Record, upto: int | None = None) -> None:
    """Play the inputs of ``rec`` step by step on ``drv`` (its first ``upto`` steps)."""
    for s in rec.steps[:upto]:
        want = {"target": s.target, "execute": s.execute, "stop": s.stop, "f_mode": s.f_mode}
        drv.set(**{n: v for n, v in want.items() if drv.cur[n] != v})
        drv.step(s.h)


@settings(max_examples=_n(10), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(st.data())
def test_a_command_changes_nothing_before_its_sample(pool, data):
    """Drop the last command: up to the sample where it takes effect the motion is the same.

    Up to the point where it was set every output is the same; before its sample x, v, a,
    j and stage are; at the sample itself x, v and a (the command shapes what follows).
    """
    ax = data.draw(axes())
    evs = data.draw(events(ax, n=(2, 5)))
    h_ratio = data.draw(st.sampled_from([1.0, 0.37]))
    drv, _ = _run(pool, 2, ax, evs, h_ratio)
    rec = drv.rec
    cmds = rec.commands()
    if not cmds:
        return
    last = cmds[-1]
    other = Driver(pool[2][1], ax)   # the scout, free now
    _replay_steps(other, rec, last.step)
    # the same steps without the last edge: execute and stop stay as they were before it
    held = {"execute": other.cur["execute"], "stop": other.cur["stop"]}
    for s in rec.steps[last.step:]:
        want = {"target": s.target, "f_mode": s.f_mode, **held}
        other.set(**{n: v for n, v in want.items() if other.cur[n] != v})
        other.step(s.h)
    a, b = rec.rows(), other.rec.rows()
    tol = rec.ttol
    t = np.array(rec.t)
    # up to the point where it was set: everything
    assert np.array_equal(a[:last.step + 1], b[:last.step + 1])
    # before its sample: the motion (t, x, v, a, j, stage; done and busy may already change).
    # Between the point where it was set and its sample x, v, a may differ by rounding: the
    # FMU evaluates them from the new plan there.  At its sample: x, v (JL, DJL: a).
    before = t < last.sample - tol
    at = np.abs(t - last.sample) <= tol
    assert np.array_equal(a[before][:, [0, 4, 7]], b[before][:, [0, 4, 7]])   # t, j, stage
    xs = float(np.abs(a[:, 1]).max())
    lims = {1: 4e-16 * (xs + ax.v_max * ax.Te), 2: 16e-16 * ax.v_max, 3: 16e-16 * ax.level}
    for col, lim in lims.items():
        sel = before | at if (col < 3 or ax.profile != 1) else before
        assert np.abs(a[sel, col] - b[sel, col]).max(initial=0.0) <= lim, col


@pytest.mark.parametrize("h_ratio", [1.0, 0.37])
@pytest.mark.parametrize("profile", [1, 2, 3])
def test_a_command_acts_from_the_first_sample_after_its_step(fmu, profile, h_ratio):
    """docs/generator.md, "When a command acts": a command seen by the DoStep from t takes
    effect at the first generator sample strictly after t, b = floor(u) + 1.  An execute from
    rest moves the axis over the sample interval that starts at b (not before, not one sample
    later); a stop while cruising starts slowing down there."""
    Te = 1e-3
    h = h_ratio * Te
    ax = Axis(profile=profile, Te=Te, v_max=0.5, a_max=5.0, d_max=8.0, N=(4, 5, 6, 7), x0=0.1)
    with GeneratorFMU(fmu) as g:
        drv = Driver(g, ax)
        drv.run(13, h)
        drv.set(target=0.4, execute=True)
        t_cmd = drv.time
        drv.step(h)
        drv.set(execute=False)
        drv.run(round(6 * Te / h), h)
        rec = drv.rec

        def first_sample_after(tc: float) -> float:
            """b = floor(u) + 1, u = tc in samples (within 1e-9 of a sample: on it)."""
            return (math.floor(tc / Te + 1e-9) + 1) * Te

        s = first_sample_after(t_cmd)
        assert s > t_cmd + 0.5 * Te * (h_ratio == 1.0)   # on a sample: the next one
        t = np.array(rec.t)
        x = np.array(rec.x)
        j = np.array(rec.j)
        assert np.all(x[t <= s + 1e-9 * Te] == 0.1), "moved before the command's sample"
        assert np.all(j[t < s - 1e-9 * Te] == 0.0), "a jerk before the command's sample"
        # over the sample interval [s, s + Te) the axis moves: x beyond s differs from 0.1
        first_after = int(np.argmax(t > s + 1e-9 * Te))
        assert t[first_after] <= s + Te + 1e-9 * Te
        assert x[first_after] != 0.1, (
            f"execute set at t = {t_cmd!r}: still at rest at t = {t[first_after]!r}, its "
            f"sample being {s!r}")
        # a stop while cruising: deceleration from its sample on
        while phase_of(drv.rec.v[-1], drv.rec.a[-1], ax) != "cruise":
            drv.step(h)
        drv.run(3, h)
        drv.set(stop=True)
        t_stop = drv.time
        drv.step(h)
        drv.set(stop=False)
        drv.run(round(4 * Te / h), h)
        s = first_sample_after(t_stop)
        t = np.array(rec.t)
        v = np.array(rec.v)
        before = t <= s + 1e-9 * Te
        v_cruise = v[before][-1]
        assert np.all(v[before][-3:] == v_cruise), "slowed down before the stop's sample"
        first_after = int(np.argmax(t > s + 1e-9 * Te))
        assert abs(v[first_after]) < abs(v_cruise), (
            f"stop set at t = {t_stop!r}: still cruising at t = {t[first_after]!r}, its "
            f"sample being {s!r}")


PHASES = ["acc", "cruise", "dec"]


@pytest.mark.parametrize("version", [2, 3])
@pytest.mark.parametrize("kind", ["execute", "stop", "exec_stop"])
@pytest.mark.parametrize("phase", PHASES)
@pytest.mark.parametrize("profile,js", [(1, 1), (2, 1), (3, 1), (2, 2), (3, 2)],
                         ids=["AL", "JL", "DJL", "JL-fmode", "DJL-fmode"])
def test_command_in_each_phase(pool, version, kind, phase, profile, js):
    """Each command lands where it is meant to (accelerating, cruising, decelerating)."""
    ax = Axis(profile=profile, jerk_source=js, Te=1e-3, v_max=0.5, a_max=5.0, d_max=8.0,
              N=(12, 7, 9, 15), dither=(0.2, -0.3, 0.1, 0.4), x0=0.1,
              f_mode0=f_for(11, 1e-3, 0.2) if js == 2 else None)
    evs = [Event("execute", "early", 0.0, 6.0), Event(kind, phase, 0.4, -2.5),
           Event("execute", "any", 0.5, 1.5)]
    if kind != "execute":
        evs = evs[:2]
    drv, script = _run(pool, version, ax, evs, 1.0)
    assert script.fired[1] == (kind, phase), script.fired
    check_all(drv, param_end=_param_end(ax))


STOP_IN_DECELERATION = [
    (1, (1, 1, 1, 1), 0.0), (1, (1, 1, 1, 1), 0.5), (2, (15, 15, 15, 15), 0.0),
    (2, (15, 15, 15, 15), 0.5), (2, (15, 15, 15, 15), 0.97), (3, (12, 7, 9, 15), 0.0),
    (3, (12, 7, 9, 15), 0.5), (3, (12, 7, 9, 15), 0.97), (3, (3, 20, 25, 2), 0.3),
    (3, (3, 20, 25, 2), 0.97),
    # a stop one sample into stage 3 (DJL, N = 3, 20, 25, 2 samples): ending the deceleration
    # at once would take a stage-4 ramp of 24 samples and rest 66 um past the target; the
    # FMU keeps the move, which rests first
    pytest.param(3, (3, 20, 25, 2), 0.0),
]


@pytest.mark.parametrize("profile, N, frac", STOP_IN_DECELERATION)
def test_stop_in_deceleration_does_not_pass_the_target(pool, profile, N, frac):
    """A stop while slowing down rests before (or at) the move's target, with clean ramps."""
    ax = Axis(profile=profile, Te=1e-3, v_max=0.5, a_max=5.0, d_max=3.0, N=N)
    evs = [Event("execute", "early", 0.0, 1.3), Event("stop", "dec", frac)]
    drv, script = _run(pool, 2, ax, evs, 1.0)
    assert script.fired[1] == ("stop", "dec")
    check_all(drv)
    check_stage_ramps(drv.rec)
    assert check_stops(drv.rec) == StopCount(1, 0)


def test_stop_one_sample_into_stage_3_rests_short_of_the_target(fmu):
    # DJL, N = 1, 1, 3, 1 samples, Te = 1 ms, execute to 0.007 m, stop before step 8 (stage 3
    # under way): ending the deceleration at once would rest at 0.0070553 m, 55 um past the
    # target; the move in progress rests first and is kept
    ax = Axis(profile=3, Te=1e-3, v_max=1.0, a_max=250.0, d_max=250.0, N=(1, 1, 3, 1))
    with GeneratorFMU(fmu) as g:
        drv = _play(g, ax, [(0, {"target": 0.007, "execute": True}), (1, {"execute": False}),
                            (8, {"stop": True}), (9, {"stop": False})], 40)
        check_all(drv)
        assert drv.rec.x[-1] <= 0.007 + 1e-9 * 0.007, drv.rec.x[-1]
        assert check_stops(drv.rec) == StopCount(1, 0)


@settings(max_examples=_n(40), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(st.data())
def test_a_stop_rests_between_where_it_acts_and_the_target(pool, data):
    """Random axes (AL, JL, DJL; jerk times fixed or from f_mode), an execute from rest, a stop
    in a random phase of the move (speeding up, cruising, slowing down) and, with f_mode, new
    jerk times around it: the stop rests between the position at the stop and the target
    (docs/generator.md, "Commanded moves").  Nothing follows the stop, so it is always
    checkable: the check must count it, checked."""
    ax = data.draw(axes())
    ax = Axis(**{**ax.__dict__, "distance": 0.0})
    rel = data.draw(st.floats(0.05, 3.0)) * data.draw(st.sampled_from([1.0, -1.0]))
    phase = data.draw(st.sampled_from(PHASES))
    evs = [Event("execute", "early", 0.0, rel), Event("stop", phase, data.draw(st.floats(0, 1)))]
    if ax.jerk_source == 2 and data.draw(st.booleans()):
        f = data.draw(st.lists(_f_value(ax.Te), min_size=2, max_size=6))
        evs.insert(1, Event("sweep", phase, data.draw(st.floats(0, 1)), f=tuple(f)))
    drv, script = _run(pool, 2, ax, evs, 1.0)
    event(f"stop while {script.fired[-1][1]}")
    check_all(drv)
    assert check_stops(drv.rec) == StopCount(1, 0)


@pytest.mark.skipif(not CAMPAIGN, reason="on demand: DJL_FMU_COMMAND_CAMPAIGN=<examples>")
@pytest.mark.slow
@settings(max_examples=max(CAMPAIGN, 1), deadline=None, derandomize=False,
          suppress_health_check=list(HealthCheck))
@given(st.data(), st.sampled_from([1.0, 1.0, 0.37]), st.sampled_from([2, 2, 2, 3]),
       st.sampled_from([1, 1, 2]))
def test_campaign_random_command_sequences(pool, data, h_ratio, version, short_stage):
    """The larger campaign: more examples, longer scripts, the overlap rule too, and
    jerk_source = 3 (f_mode extrapolated; general invariants only)."""
    ax = data.draw(axes(short_stage=short_stage, jerk_sources=(1, 2, 3)))
    evs = data.draw(events(ax, n=(1, 12)))
    drv, script = _run(pool, version, ax, evs, h_ratio)
    _check(drv, script)


# ------------------------------- fractional steps: the same as whole samples


@settings(max_examples=_n(10), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(st.data())
def test_fractional_steps_are_the_whole_sample_run_in_between(pool, data):
    """Commands set at points between samples act at the next sample.

    A run with h = 0.37 Te and a run with h = Te given each command at the sample where it
    takes effect (f_mode: the value in force at the step holding that sample) describe the
    same piecewise cubic: every point of the first lies on the second.
    """
    ax = data.draw(axes())
    evs = data.draw(events(ax, n=(1, 5)))
    drv, _ = _run(pool, 2, ax, evs, 0.37)
    rec = drv.rec
    Te = ax.Te
    # the whole-sample equivalent
    n = math.ceil((rec.t[-1] - rec.start_time) / Te) + 2
    by_sample: dict[int, dict[str, Any]] = {}
    for i, s in enumerate(rec.steps):
        if not (s.exec_edge or s.stop_edge):
            continue
        k = round((rec.effect_sample(s.t) - rec.start_time) / Te)
        if k in by_sample or k - 1 in by_sample:
            # two edges from different steps act at the same sample, or at consecutive ones
            # (a one-sample pulse cannot rise twice): not comparable with a whole-sample run
            event("fractional: edges too close, skipped")
            return
        by_sample[k] = {"step": i}
        if s.exec_edge:
            by_sample[k]["execute"] = s.target
        if s.stop_edge:
            by_sample[k]["stop"] = True
    # f_mode in force for a stage starting at sample k: that of the last step from t < k Te
    # (docs/generator.md, "When a command acts")
    starts = np.array([s.t for s in rec.steps])
    fvals = [s.f_mode for s in rec.steps]

    def f_for_sample(k: int) -> float:
        i = int(np.searchsorted(starts, rec.start_time + k * Te - rec.ttol, side="left")) - 1
        return fvals[i] if i >= 0 else rec.f_init

    # the whole-sample run: the inputs acting at sample k are set before the step from
    # (k - 1) Te, the last one that starts before k
    lag = 1
    whole = Driver(pool[2][1], ax)   # the scout, free now
    for q in range(n):
        cmd = by_sample.get(q + lag, {})
        want: dict[str, Any] = {"execute": "execute" in cmd, "stop": "stop" in cmd,
                                "f_mode": f_for_sample(q + lag)}
        if "execute" in cmd:
            want["target"] = cmd["execute"]
        whole.set(**{name: v for name, v in want.items() if whole.cur[name] != v})
        whole.step(Te)
    check_all(whole)
    # every point of the fractional run on the whole-sample cubic, taken backwards from the
    # next sample with the interval's jerk from the change of a (AL: a from the change of v)
    W = whole.rec.arrays()
    F = rec.arrays()
    u = np.array(profile_samples(rec))        # the FMU's profile time, in samples
    k = np.floor(u).astype(int)
    sig = (k + 1 - u) * Te
    if ax.profile == 1:
        acc = (W["v"][k + 1] - W["v"][k]) / Te
        x = W["x"][k + 1] - W["v"][k + 1] * sig + acc * sig**2 / 2
        v = W["v"][k + 1] - acc * sig
        a_err = 0.0
    else:
        j = (W["a"][k + 1] - W["a"][k]) / Te
        a = W["a"][k + 1] - j * sig
        v = W["v"][k + 1] - W["a"][k + 1] * sig + j * sig**2 / 2
        x = W["x"][k + 1] - W["v"][k + 1] * sig + W["a"][k + 1] * sig**2 / 2 - j * sig**3 / 6
        a_err = float(np.abs(a - F["a"]).max())
    xs = max(np.abs(W["x"]).max(), 1e-300)
    assert np.abs(x - F["x"]).max() <= 1e-9 * ax.v_max * Te + 1e-15 * xs, rec.describe()
    assert np.abs(v - F["v"]).max() <= 1e-9 * ax.level * Te + 1e-15 * ax.v_max
    assert a_err <= 1e-9 * ax.level
    on = u == k
    kk = k[on]
    for name in ("x", "v", "a", "done"):
        assert np.array_equal(F[name][on], W[name][kk]), name


# ------------------------------------------------ 2. untouched inputs change nothing


REFERENCE = json.loads((HERE / "_command_reference.json").read_text())
"""Hashes of the outputs of the FMU before the commanded interface (git 8f30fb7)."""

REF_NAMES = ("x", "v", "a", "j", "x_AL", "v_AL", "a_AL", "done", "segment")


def _digest(arr: np.ndarray) -> str:
    a = np.asarray(arr)
    a = a.astype("<f8") if a.dtype.kind == "f" else a.astype("<i8")
    return hashlib.sha256(np.ascontiguousarray(a).tobytes()).hexdigest()


@pytest.mark.parametrize("case", sorted(REFERENCE["cases"]))
def test_no_command_is_bit_identical_to_the_fmu_before_commands(fmu, case):
    ref = REFERENCE["cases"][case]
    tr = generate(ref["params"], fmu=fmu, dt=ref["dt"], t_stop=ref["t_stop"])
    assert len(tr.t) == ref["n"]
    got = {n: _digest(getattr(tr, n)) for n in REF_NAMES}
    assert got == ref["sha256"], [n for n in REF_NAMES if got[n] != ref["sha256"][n]]


def _parametric_cases() -> list[tuple[str, dict[str, Any], float, float]]:
    return [(name, c["params"], c["dt"], c["t_stop"])
            for name, c in sorted(REFERENCE["cases"].items())]


class _ParamAxis(Axis):
    """An Axis whose FMU parameters are given as they are (the reference cases)."""

    def __init__(self, raw: dict[str, Any]) -> None:
        super().__init__(profile=int(raw.get("profile", 3)), Te=float(raw.get("Te", 1e-3)),
                         v_max=float(raw.get("v_max", 1.0)), a_max=float(raw.get("a_max", 10.0)),
                         d_max=float(raw.get("d_max", 10.0)))
        object.__setattr__(self, "raw", dict(raw))

    def params(self) -> dict[str, Any]:
        return dict(self.raw)  # type: ignore[attr-defined]


def _drive_untouched(g: GeneratorFMU, params: dict[str, Any], dt: float, n: int,
                     how: str, rng: np.random.Generator) -> np.ndarray:
    """Run ``params`` with the new inputs left alone or set in ways that must be inert."""
    before: dict[str, Any] = {}
    in_init: dict[str, Any] = {}
    if how in ("start values", "start values every step"):
        before, in_init = dict(START), dict(START)
    elif how == "held high from initialisation":
        in_init = {"execute": True, "stop": True}
    elif how == "high before initialisation, then falling":
        before = {"execute": True, "stop": True}
    p = {**params, "jerk_source": 1} if how == "start values" else params
    drv = Driver(g, _ParamAxis(p), before_init=before, in_init=in_init)
    for i in range(n):
        if how == "start values every step":
            drv.set(**START)
        elif how == "inert inputs":
            # jerk_source = 1 ignores f_mode; a target without an execute edge does nothing
            drv.set(f_mode=float(rng.uniform(0.5, 400.0)), target=float(rng.uniform(-5, 5)))
        elif how == "high before initialisation, then falling" and i == 7:
            drv.set(execute=False)
        elif how == "high before initialisation, then falling" and i == 11:
            drv.set(stop=False)
        elif how == "held high from initialisation" and i % 5 == 0:
            drv.set(target=float(rng.uniform(-5, 5)))
        drv.step(dt)
    return drv.rec.rows()


HOWS = ["start values", "start values every step", "inert inputs",
        "held high from initialisation", "high before initialisation, then falling"]


@pytest.mark.parametrize("case", _parametric_cases(), ids=lambda c: c[0])
def test_inert_inputs_change_no_output(fmu, case):
    """Inputs at their start values, f_mode with jerk_source = 1, targets without an edge,
    execute/stop held high from initialisation (no edge) or only falling: outputs bit for
    bit those of a run that sets nothing, and those of harness.fmu.runner.generate."""
    name, params, dt, t_stop = case
    rng = np.random.default_rng(12)
    n = round(t_stop / dt)
    with GeneratorFMU(fmu) as g:
        base = _drive_untouched(g, params, dt, n, "nothing", rng)
        for how in HOWS:
            rows = _drive_untouched(g, params, dt, n, how, rng)
            diff = np.nonzero(~np.all(rows == base, axis=1))[0]
            assert diff.size == 0, f"{how}: outputs differ from t = {base[diff[0], 0]}"
    tr = generate(params, fmu=fmu, dt=dt, t_stop=t_stop)
    for col, nm in enumerate(("x", "v", "a", "j"), 1):
        assert np.array_equal(base[:, col], getattr(tr, nm)), nm
    assert np.array_equal(base[:, 5].astype(bool), tr.done)
    assert np.array_equal(base[:, 6].astype(bool), ~tr.done), "busy is not done"


# ---------------------------------------------------------------- 3. bad inputs


BAD_F_MODES = [math.nan, 0.0, -0.0, -1.0, math.inf, -math.inf]


SCRIPT_STEPS = 1000
"""Steps of the scripted run of the bad-input tests (its moves end well within them)."""


def _cmd_axis(js: int = 1, profile: int = 3) -> Axis:
    return Axis(profile=profile, jerk_source=js, Te=1e-3, v_max=0.5, a_max=5.0, d_max=8.0,
                N=(12, 7, 9, 15), x0=0.1, f_mode0=f_for(10, 1e-3, 0.1) if js == 2 else None)


def _scripted(drv: Driver, bad: tuple[str, float] | None, at: int,
              expect_refused: bool = True) -> list[str]:
    """A move, then (maybe) a bad set at step ``at``, then an execute that uses the target."""
    msgs: list[str] = []
    for k in range(SCRIPT_STEPS):
        if k == 3:
            drv.set(target=0.4, execute=True)
        if k == 4:
            drv.set(execute=False)
        if k == at and bad is not None:
            name, value = bad
            before = dict(drv.cur)
            if expect_refused:
                e = expect_fmu_error(lambda n=name, v=value: drv.set_raw(n, v), name)
                msgs.append(str(e))
                assert drv.cur == before
                # the value is kept: read it back
                assert drv.g.get(name) == before[name]
            else:
                drv.set_raw(name, value)
        if k == at + 2:
            drv.set(execute=True)   # a new move to the kept target
        if k == at + 3:
            drv.set(execute=False)
        drv.step(1e-3)
    return msgs


# A bad target (NaN, infinite, beyond 1e300 m) is taken when set since issue 34; the
# execute that would use it is refused at its edge with cmd_error: tests/test_fmu_cmd.py.


@pytest.mark.parametrize("js", [1, 2])
@pytest.mark.parametrize("value", BAD_F_MODES, ids=str)
def test_bad_f_mode_in_step_mode_is_refused_and_changes_nothing(fmu, value, js):
    with GeneratorFMU(fmu) as g:
        ref = Driver(g, _cmd_axis(js))
        _scripted(ref, None, 120)
        drv = Driver(g, _cmd_axis(js))
        _scripted(drv, ("f_mode", value), 120)
        assert np.array_equal(drv.rec.rows(), ref.rec.rows())
        check_all(drv)


@pytest.mark.parametrize("period", [0.1, 0.49, 1.5e8, 1e9], ids=lambda p: f"{p}Te")
def test_f_mode_out_of_range_in_step_mode_with_jerk_source_2(fmu, period):
    """With Te known, a period outside [Te/2, 1e8 Te] is refused at set time."""
    f = 1.0 / (period * 1e-3)
    with GeneratorFMU(fmu) as g:
        ref = Driver(g, _cmd_axis(2))
        _scripted(ref, None, 120)
        drv = Driver(g, _cmd_axis(2))
        _scripted(drv, ("f_mode", f), 120)
        assert np.array_equal(drv.rec.rows(), ref.rec.rows())


@pytest.mark.parametrize("period", [0.1, 1e9], ids=lambda p: f"{p}Te")
def test_f_mode_out_of_range_with_jerk_source_1_changes_nothing(fmu, period):
    """jerk_source = 1 never uses f_mode: refused or not, the outputs are the same."""
    f = 1.0 / (period * 1e-3)
    with GeneratorFMU(fmu) as g:
        ref = Driver(g, _cmd_axis(1))
        _scripted(ref, None, 120)
        drv = Driver(g, _cmd_axis(1))
        try:
            drv.set_raw("f_mode", f)
        except FMUError as e:
            assert "f_mode" in str(e)
        _scripted(drv, None, 120)
        assert np.array_equal(drv.rec.rows()[:, 1:], ref.rec.rows()[:, 1:])


class _BadInitDriver(Driver):
    """A Driver whose initialisation sets a bad value of one input (in Instantiated or
    Initialization mode) and records how the FMU refuses it.

    Refusals allowed: at set time (the value is kept), or, for a period out of range before
    Te is fixed, at exitInitializationMode, after which setting a good value and exiting
    again must work (``good``); a refusal by doStep is left to the caller.
    """

    def __init__(self, g: GeneratorFMU, ax: Axis, mode: str, name: str, value: float,
                 good: float | None = None) -> None:
        self.bad_name, self.bad_value, self.good = name, value, good
        self.refused: list[tuple[str, str]] = []
        super().__init__(g, ax, **{("before_init" if mode == "instantiated" else "in_init"):
                                   {name: value}})

    def set(self, **inputs: Any) -> None:
        for n_, v_ in inputs.items():
            if n_ == self.bad_name and _same_float(v_, self.bad_value):
                before = self.cur[n_]
                try:
                    self.set_raw(n_, v_)
                except FMUError as e:
                    assert e.status == 3 and n_ in str(e), str(e)
                    assert self.cur[n_] == before
                    self.refused.append(("set", str(e)))
            else:
                self.set_raw(n_, v_)

    def _exit_initialization(self) -> None:
        try:
            super()._exit_initialization()
        except FMUError as e:
            assert e.status == 3 and self.bad_name in str(e), str(e)
            self.refused.append(("exitInitializationMode", str(e)))
            assert self.good is not None, "refused at exitInitializationMode"
            # the instance stays usable: a good value, and initialisation completes
            self.set_raw(self.bad_name, self.good)
            super()._exit_initialization()


def _same_float(a: Any, b: float) -> bool:
    return isinstance(a, float) and (a == b or (a != a and b != b))


@pytest.mark.parametrize("mode", ["instantiated", "initialization"])
@pytest.mark.parametrize("value", BAD_F_MODES, ids=str)
def test_bad_f_mode_before_step_mode_is_refused(fmu, mode, value):
    ax = _cmd_axis(2)
    with GeneratorFMU(fmu) as g:
        ref = Driver(g, ax)
        _scripted(ref, None, 120)
        drv = _BadInitDriver(g, ax, mode, "f_mode", value)
        assert [w for w, _ in drv.refused] == ["set"]
        assert drv.cur["f_mode"] == ax.f_mode0 and g.get("f_mode") == ax.f_mode0
        _scripted(drv, None, 120)
        assert np.array_equal(drv.rec.rows(), ref.rec.rows())


@pytest.mark.parametrize("mode", ["instantiated", "initialization"])
@pytest.mark.parametrize("period", [0.1, 1e9], ids=lambda p: f"{p}Te")
def test_f_mode_out_of_range_before_step_mode(fmu, mode, period):
    """Before Step mode Te may still change: refused at set time, or by the doStep that
    uses it (naming f_mode, nothing advanced); once f_mode is fixed the run is as if it had
    never been bad."""
    ax = _cmd_axis(2)
    good = ax.f_mode0
    assert good is not None
    bad = 1.0 / (period * ax.Te)
    with GeneratorFMU(fmu) as g:
        ref = Driver(g, ax)
        _scripted(ref, None, 120)
        drv = _BadInitDriver(g, ax, mode, "f_mode", bad, good)
        refusals = 0
        k = 0
        while k < SCRIPT_STEPS:
            if k == 3:
                drv.set(target=0.4, execute=True)
            if k == 4:
                drv.set(execute=False)
            if k == 122:
                drv.set(execute=True)
            if k == 123:
                drv.set(execute=False)
            t0, out0 = drv.g.time, drv.outputs()
            try:
                drv.step(1e-3)
            except FMUError as e:
                refusals += 1
                assert refusals == 1 and not drv.refused and drv.cur["f_mode"] == bad, str(e)
                assert e.status == 3 and "f_mode" in str(e), str(e)
                assert drv.g.time == t0 and drv.outputs() == out0, "the refused step advanced"
                drv.set(f_mode=good)
                continue   # the same step again
            k += 1
        assert drv.cur["f_mode"] == good
        assert np.array_equal(drv.rec.rows(), ref.rec.rows())


@pytest.mark.parametrize("params, fragments", [
    ({"profile": 1}, ["jerk_source"]),
    ({"n_segments": 2, "seg_distance": [0.1, 0.2], "seg_v_end": [0.0, 0.0]}, ["jerk_source"]),
    ({"v_e": 0.2}, ["jerk_source"]),
], ids=["AL", "n_segments", "v_e"])
@pytest.mark.parametrize("js", [2, 3])
def test_jerk_source_2_needs_a_single_rest_to_rest_jl_or_djl(fmu, params, fragments, js):
    with GeneratorFMU(fmu, params={**params, "jerk_source": js}) as g:
        with pytest.raises(FMUError) as info:
            g.initialize()
        assert info.value.status == 3
        for f in fragments:
            assert f in str(info.value)
    # the same parameters with jerk_source = 1 are fine
    with GeneratorFMU(fmu, params=params) as g:
        g.initialize()


@pytest.mark.parametrize("value", [0, 4, -1, 2**31 - 1])
def test_jerk_source_out_of_range_is_refused_naming_it(fmu, value):
    with GeneratorFMU(fmu) as g:
        try:
            g.set({"jerk_source": value})
        except FMUError as e:
            assert e.status == 3 and "jerk_source" in str(e)
            return
        with pytest.raises(FMUError) as info:
            g.initialize()
        assert f"jerk_source = {value}" in str(info.value)


# ------------------------------------------------------------------- 4. FMU state


def _continue(drv: Driver, script: list[tuple[int, dict[str, Any]]], n: int, h: float) -> None:
    todo: dict[int, dict[str, Any]] = {}
    for q, d in script:
        todo.setdefault(q, {}).update(d)
    k0 = drv.k
    for k in range(k0, k0 + n):
        if k - k0 in todo:
            drv.set(**todo[k - k0])
        drv.step(h)


STATE_CASES = {
    # (axis, inputs before the save (step: values), steps before the save,
    #  inputs after it (relative step: values), steps after it)
    "djl-mid-move": (_cmd_axis(1), [(5, {"target": -0.3, "execute": True}),
                                    (6, {"execute": False})], 150,
                     [(30, {"target": 0.6, "execute": True}), (31, {"execute": False}),
                      (200, {"stop": True}), (260, {"execute": True, "target": 0.0})], 900),
    "jl-fmode-replan": (_cmd_axis(2, 2),
                        [(2, {"target": 0.5, "execute": True})]
                        + [(k, {"f_mode": f_for(5 + (k % 17), 1e-3, 0.3)})
                           for k in range(3, 140)], 140,
                        [(0, {"execute": False})]
                        + [(k, {"f_mode": f_for(3 + (k % 23), 1e-3, -0.2)})
                           for k in range(1, 300)]
                        + [(120, {"execute": True, "target": -0.2})], 900),
    "djl-fmode-edge-pending": (_cmd_axis(2, 3),
                               [(2, {"target": 0.5, "execute": True}),
                                (3, {"execute": False}),
                                (60, {"f_mode": f_for(4, 1e-3)}),
                                (90, {"target": 0.1, "execute": True})], 90,
                               [(5, {"execute": False}), (40, {"f_mode": f_for(19, 1e-3)}),
                                (70, {"stop": True})], 700),
}


@pytest.mark.parametrize("name", sorted(STATE_CASES))
def test_fmu_state_in_a_commanded_move_replays_bit_for_bit(fmu, name):
    """get/set and serialise/deserialise in the middle of a commanded move (inputs set
    before the save belong to the state, even an edge not yet stepped over)."""
    ax, pre, n_pre, post, n_post = STATE_CASES[name]
    with GeneratorFMU(fmu) as g, GeneratorFMU(fmu) as other:
        drv = Driver(g, ax)
        pre_d: dict[int, dict[str, Any]] = {}
        for q, d in pre:
            pre_d.setdefault(q, {}).update(d)
        for k in range(n_pre + 1):
            if k in pre_d:
                drv.set(**pre_d[k])   # at k = n_pre: set, not yet stepped over
            if k < n_pre:
                drv.step(1e-3)
        t_saved = g.time
        state = g.get_state()
        data = g.serialize_state(state)
        cur, prev, last = dict(drv.cur), dict(drv.prev), dict(drv.last_step_inputs)
        n_rec = len(drv.rec.t)
        _continue(drv, post, n_post, 1e-3)
        drv.run_until_done(1e-3, 20000)
        n_post = len(drv.rec.t) - n_rec
        first = drv.rec.rows()[n_rec:]
        assert not np.all(np.array(drv.rec.j[n_rec:]) == 0.0), "the case should move"
        # restore in the same instance; the inputs come from the state
        g.set_state(state, t_saved)
        drv.cur, drv.prev, drv.last_step_inputs = dict(cur), dict(prev), dict(last)
        drv.rec.t, drv.rec.x = drv.rec.t[:n_rec], drv.rec.x[:n_rec]
        for fld in ("v", "a", "j", "done", "busy", "stage"):
            setattr(drv.rec, fld, getattr(drv.rec, fld)[:n_rec])
        drv.rec.steps = drv.rec.steps[:n_rec - 1]
        _continue(drv, post, n_post, 1e-3)
        second = drv.rec.rows()[n_rec:]
        assert np.array_equal(first, second)
        g.free_state(state)
        # deserialised into another instance, other parameters: the state holds everything
        other_ax = Axis(profile=1, v_max=2.0, a_max=1.0, d_max=1.0, distance=-0.2)
        d2 = Driver(other, other_ax)
        s2 = other.deserialize_state(data)
        other.set_state(s2, t_saved)
        other.free_state(s2)
        d2.axis = ax
        d2.cur, d2.prev, d2.last_step_inputs = dict(cur), dict(prev), dict(last)
        d2.rec = Record(axis=ax, start_time=0.0)
        d2._read()
        _continue(d2, post, n_post, 1e-3)
        third = d2.rec.rows()[1:]
        assert np.array_equal(first, third)


# -------------------------------------- 5. jerk_source = 2: stage lengths from f_mode


def _stage_runs(rec: Record) -> list[tuple[int, int, float, int]]:
    """(start sample, length, jerk, stage label) of each constant-jerk ramp, steps h = Te.

    The jerk of sample interval k is the change of a over it (the reported j of a point may
    predate an input set there); a ramp is a maximal run of one non-zero jerk, split where
    a passes through 0 (the end of acceleration runs straight into the start of deceleration
    with the same jerk when both levels and jerk times are equal).
    """
    Te = rec.axis.Te
    a = np.array(rec.a)
    J = np.diff(a) / Te
    st_ = np.array(rec.stage)
    scale = np.abs(J).max() if J.size else 0.0
    ea = 1e-12 * rec.axis.level
    out = []
    k = 0
    while k < len(J):
        if abs(J[k]) <= 1e-9 * scale:
            k += 1
            continue
        s = k
        while (k + 1 < len(J) and abs(J[k + 1] - J[s]) <= 1e-7 * abs(J[s])
               and abs(a[k + 1]) > ea):
            k += 1
        out.append((s, k - s + 1, float(J[s]), int(st_[s + 1])))
        k += 1
    return out


@st.composite
def fmode_scripts(draw: st.DrawFn) -> tuple[Axis, list[tuple[int, dict[str, Any]]], int]:
    Te = 1e-3
    profile = draw(st.sampled_from([2, 3]))
    v_max = draw(_log_uniform(0.05, 1.0))
    a_max = v_max / (draw(st.integers(5, 80)) * Te)
    d_max = draw(st.one_of(st.just(a_max), _log_uniform(0.3, 3.0).map(lambda r: r * a_max)))
    f0 = draw(_f_value(Te))
    ax = Axis(profile=profile, jerk_source=2, Te=Te, v_max=v_max, a_max=a_max, d_max=d_max,
              f_mode0=f0)
    dc = ax.char_distance(25)
    script: list[tuple[int, dict[str, Any]]] = []
    k = 1
    every_step = draw(st.booleans())
    n_moves = draw(st.integers(1, 3))
    x = 0.0
    for _ in range(n_moves):
        x += draw(st.floats(0.05, 2.5)) * dc * draw(st.sampled_from([1.0, -1.0]))
        script.append((k, {"target": x, "execute": True}))
        script.append((k + 1, {"execute": False}))
        k += draw(st.integers(30, 900))
    end = k + 2000
    if every_step:
        for q in range(0, end):
            script.append((q, {"f_mode": draw(_f_value(Te))} if q % 3 else {}))
    else:
        for _ in range(draw(st.integers(1, 12))):
            script.append((draw(st.integers(0, k)), {"f_mode": draw(_f_value(Te))}))
    if draw(st.integers(0, 3)) == 0:
        script.append((draw(st.integers(5, k)), {"stop": True}))
    merged: dict[int, dict[str, Any]] = {}
    for q, d in sorted(script, key=lambda p: p[0]):
        merged.setdefault(q, {}).update(d)
    # a stop pulse lasts one step
    for q, d in list(merged.items()):
        if d.get("stop"):
            merged.setdefault(q + 1, {})["stop"] = False
    return ax, sorted(merged.items()), end


@pytest.fixture(scope="module")
def logged(fmus: dict[int, Path]) -> Iterator[GeneratorFMU]:
    """An FMI 2 instance that logs events: the exceptions to the jerk_source = 2 rule are
    logged (docs/generator.md, "Jerk times from f_mode")."""
    g = GeneratorFMU(fmus[2], instance_name="logged", debug_logging=True)
    yield g
    g.close()


@settings(max_examples=_n(25), deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(fmode_scripts())
def test_jerk_source_2_stage_lasts_the_period_of_f_mode_at_its_start(logged, script):
    """docs/generator.md, "Jerk times from f_mode": every ramp has the jerk time of the
    f_mode read before its start, or one of the documented exceptions; no move passes its
    target."""
    ax, todo, end = script
    drv = _play(logged, ax, todo, end)
    check_all(drv)
    check_no_pass(drv.rec)
    n_clean = check_fmode_ramps(drv.rec, logged.log)
    event(f"clean ramps checked: {min(n_clean, 4)}+")


def _play(g: GeneratorFMU, ax: Axis, todo: list[tuple[int, dict[str, Any]]],
          end: int) -> Driver:
    """Steps of Te with the inputs of ``todo`` (step: values); stops once done after them."""
    drv = Driver(g, ax)
    plan = dict(todo)
    last = max(plan, default=0)
    for k in range(end):
        if k in plan:
            drv.set(**{n: v for n, v in plan[k].items() if drv.cur[n] != v})
        drv.step(ax.Te)
        if drv.rec.done[-1] and k > last + 5:
            break
    return drv


_KEPT = re.compile(r"the stage starting at t = ([-+0-9.eE]+) s keeps its planned jerk time")


def check_fmode_ramps(rec: Record, log: list[Any]) -> int:
    """jerk_source = 2: ramps against the rule of docs/generator.md, "Jerk times from f_mode".

    The rule: a ramp a stage starts at sample k lasts N = round(1/(f Te)) samples, f the
    f_mode of the step from k - 1 (steps of Te), with jerk level / (N Te).  The exceptions,
    each as documented: (1) a stage logged as keeping its planned jerk time, or after a
    command logged as keeping the planned jerk times, has the jerk time of an f_mode read
    before (any of them); (2) the ending ramp of a stage a command cuts short may be longer
    (away from the command it is not clean), or shortened, logged as a warning (then only
    level / Te bounds its jerk); (3) a stop's last ramp, split over two samples, lasts N + 1.

    Every ramp: |jerk| <= max(a_max, d_max) / (N Te) for the shortest jerk time N it may have
    (a ramp that overlaps one of the opposite jerk may show up later than it starts, the sum
    flat meanwhile: then any jerk time read since that opposite run began; a ramp placed to
    the fraction of a sample shows as contiguous runs of one sign: the first one's).
    A clean ramp (from a = 0 to a plateau or from a plateau to a = 0, a constant for the
    longest jerk time in force before it and right after it, away from any command) lasts one
    of the jerk times it may have.  Returns the clean ramps checked.
    """
    ax = rec.axis
    Te = ax.Te
    msgs = [r.message for r in log]
    kept = {round(float(m.group(1)) / Te) for q in msgs for m in [_KEPT.search(q)] if m}
    command_kept = any("keep their planned jerk times" in q for q in msgs)
    shortened = any(SHORTENED in q for q in msgs)
    stops = any(c.kind == "stop" for c in rec.commands())
    a = np.array(rec.a)
    J = np.diff(a) / Te
    jscale = max(np.abs(J).max() if J.size else 0.0, 1e-300)
    flat = np.abs(J) <= 1e-9 * jscale
    ea = 1e-12 * ax.level
    f_of = [s.f_mode for s in rec.steps]
    cmd_samples = [c.step for c in rec.commands()]
    P = max(n_of_f(f, Te) for f in set(rec.f_values()))   # no overlap from earlier ramps
    runs = _stage_runs(rec)
    assert runs, "no stage ran"
    n_clean = 0
    before: tuple[int, float, int] | None = None   # the last run: its end, jerk, bound
    for s, length, jerk, label in runs:
        fi = f_index(s)
        f = f_of[fi] if fi >= 0 else rec.f_init
        want = n_of_f(f, Te)
        allowed = {want}
        if s in kept or command_kept:   # exception 1: an f_mode read before
            allowed |= {n_of_f(q, Te) for q in [rec.f_init, *f_of[:max(fi, 0) + 1]]}
        lengths = allowed | ({n + 1 for n in allowed} if stops else set())   # exception 3
        if shortened:   # exception 2b: an ending ramp shortened, to one sample at least
            lengths |= set(range(1, max(allowed) + 1))
        ctx = (f"stage {label} from sample {s} lasts {length} samples (jerk {jerk:.6g}, a "
               f"{a[s]!r} -> {a[s + length]!r}); f_mode {f!r} Hz (step {fi}) gives {want} "
               f"samples, the documented exceptions allow {sorted(lengths)}\n" + rec.describe())
        n_bound = 1 if shortened else min(allowed)   # exception 2b
        # Ramps overlap: a ramp that starts while one of the opposite jerk is still running
        # leaves the sum flat for a while, so the visible run starts later than the ramp
        # (e.g. the end of a deceleration stage cut by a command, a sample after it began:
        # the two 2-sample ramps cancel for one sample, and the second appears as a
        # 1-sample run).  Its jerk time is then the one read when the hidden start was,
        # somewhere since the opposite run began.
        prev = s - 1
        while prev >= 0 and flat[prev]:
            prev -= 1
        if (prev >= 0 and prev < s - 1 and abs(a[s]) > ea and J[prev] * jerk < 0.0
                and s - prev <= P):
            p0 = prev
            while p0 > 0 and not flat[p0 - 1] and J[p0 - 1] * J[prev] > 0.0:
                p0 -= 1
            hidden = {n_of_f(f_of[i] if i >= 0 else rec.f_init, Te)
                      for i in range(f_index(p0), fi + 1)}
            n_bound = min(n_bound, *hidden)
        # A ramp that starts between samples (a landing's ending ramp, placed to the
        # fraction of a sample) shows as contiguous runs of one sign and different jerks:
        # one ramp, with the jerk time of the run it started in.
        if before is not None and before[0] == s and before[1] * jerk > 0.0:
            n_bound = min(n_bound, before[2])
        before = (s + length, jerk, n_bound)
        assert abs(jerk) * n_bound * Te <= ax.level * (1 + 1e-9), "jerk above the bound: " + ctx
        e = s + length
        clean = (s >= P and e < len(J) and flat[s - P:s].all() and flat[e]
                 and (abs(a[s]) <= ea or abs(a[e]) <= ea)
                 and not any(s - 1 <= c <= e + 1 for c in cmd_samples))
        if clean:
            assert length in lengths, ctx
            n_clean += 1
    return n_clean


def check_no_pass(rec: Record) -> int:
    """No move from rest passes its target, nor backs up, whatever f_mode does (landing wins,
    docs/generator.md); returns the moves checked."""
    tol = Tolerances.of(rec)
    moves = rest_to_rest_moves(rec)
    for m in moves:
        sg = m.direction
        x = sg * np.array(rec.x[m.p0:m.p_end + 1])
        over = x.max() - sg * m.cmd.target
        assert over <= tol.x + 1e-9 * abs(m.cmd.target - rec.x[m.p0]), (
            f"the move to {m.cmd.target!r} passes it by {over:.3e}\n" + rec.describe())
        assert np.all(np.diff(x) >= -tol.x), f"the move to {m.cmd.target!r} backs up\n" + \
            rec.describe()
    return len(moves)


# ------------------------------- the cases the random tests found (docs/generator.md)


def _reported_jerk_mismatches(rec: Record) -> list[tuple[int, float, float]]:
    """Points (steps of Te) whose reported j is not the jerk applied over the next sample,
    leaving out those where an input had just been set (their j may predate it)."""
    a = np.array(rec.a)
    J = np.diff(a) / rec.axis.Te
    out = []
    for k in range(len(J)):
        if rec.steps[k].changed:
            continue
        if abs(J[k] - rec.j[k]) > 1e-9 * max(abs(J[k]), abs(rec.j[k]), 1e-300):
            out.append((k, rec.j[k], float(J[k])))
    return out


def test_reported_jerk_is_the_jerk_applied_with_jerk_source_2(fmu):
    """j at a point is the jerk over the sample interval that starts there (JL, f_mode
    10 Hz -> 1000 Hz while stage 3 runs; its stage 4 starts right after it)."""
    ax = Axis(profile=2, jerk_source=2, Te=1e-3, v_max=1.0, a_max=250.0, d_max=250.0)
    with GeneratorFMU(fmu) as g:
        drv = _play(g, ax, [(0, {"target": 0.104, "execute": True}), (1, {"execute": False}),
                            (201, {"f_mode": 1000.0})], 3000)
        assert _reported_jerk_mismatches(drv.rec) == []
        check_all(drv)


FMODE_JERK_TIME_CASES = {
    # f_mode changed right after the execute: every later stage must take the new jerk time
    "stages-after-an-f_mode-change": (
        Axis(profile=2, jerk_source=2, v_max=1.0, a_max=200.0, d_max=200.0, f_mode0=1000.0),
        [(1, {"target": 0.001875, "execute": True}),
         (2, {"execute": False, "f_mode": 250.0})],
        "JL, f_mode 1000 Hz at the execute (step 1), 250 Hz from step 2 on: stages 2, 3, 4 "
        "(from samples 5, 6, 9) last 1 sample (jerk +-156250 m/s3, 1000 Hz) where 250 Hz "
        "gives 4"),
    # the stop's stages
    "stop-stages-after-an-f_mode-change": (
        Axis(profile=2, jerk_source=2, v_max=1.0, a_max=200.0, d_max=200.0, f_mode0=500.0),
        [(1, {"target": 0.03, "execute": True}), (2, {"execute": False}),
         (5, {"stop": True}), (6, {"stop": False}), (8, {"f_mode": 1000.0})],
        "JL, a stop at step 5 with f_mode 500 Hz, 1000 Hz from step 8 on: the stop's stage 4 "
        "(from sample 12) lasts 2 samples (jerk 1e5 m/s3, 500 Hz) where 1000 Hz gives 1"),
    # an execute while a stage of the old jerk time runs
    "execute-during-a-long-stage": (
        Axis(profile=2, jerk_source=2, v_max=1.0, a_max=250.0, d_max=250.0, distance=0.104),
        [(201, {"f_mode": 1000.0}), (202, {"target": 0.05303993066666667, "execute": True}),
         (203, {"execute": False})],
        "JL, parametric move with f_mode 10 Hz (stages of 100 samples), 1000 Hz from step "
        "201, an execute to the current position at step 202: the ramp from sample 203 lasts "
        "97 samples (jerk 1.61 m/s3) where 1000 Hz gives 1, and the axis runs 51 mm past the "
        "new target before coming back"),
}


@pytest.mark.parametrize("name", sorted(FMODE_JERK_TIME_CASES))
def test_fmode_jerk_time_is_read_when_each_stage_starts(fmus, name):
    """Each case follows the documented rule or one of its exceptions (1: landing wins, the
    stages keep their planned jerk time of 1 sample; 3: the stop's last ramp split over two
    samples; 2a: the ramp ending stage 3 lasts until its starting ramp ends, the target
    being behind the stopping distance of the ramps that run)."""
    ax, todo, _ = FMODE_JERK_TIME_CASES[name]
    with GeneratorFMU(fmus[2], debug_logging=True) as g:
        drv = _play(g, ax, todo, 3000)
        check_all(drv)
        check_fmode_ramps(drv.rec, g.log)


@pytest.mark.parametrize("when", ["cruise", "dec"])
@pytest.mark.parametrize("f_new", [1e-3, 1000.0, 1900.0])
def test_an_extreme_f_mode_is_clamped_refused_or_never_followed_into_an_overshoot(
        fmus, f_new, when):
    """docs/generator.md, "Jerk times from f_mode": f_mode = 1/Te and 1.9/Te give one sample
    (the clamp), 2.5/Te is refused by name with the previous value kept; 10^-3 Hz (10^6
    samples) is followed only where it lands.  A move then lands on its target without
    passing it, and a stop rests between where it acts and the target."""
    Te = 1e-3
    ax = Axis(profile=3, jerk_source=2, Te=Te, v_max=0.5, a_max=5.0, d_max=5.0,
              f_mode0=f_for(20, Te))
    for stop in (False, True):
        with GeneratorFMU(fmus[2], debug_logging=True) as g:
            drv = Driver(g, ax)
            drv.set(target=0.3, execute=True)
            drv.step(Te)
            drv.set(execute=False)
            while phase_of(drv.rec.v[-1], drv.rec.a[-1], ax) != when:
                drv.step(Te)
            expect_fmu_error(lambda d=drv: d.set_raw("f_mode", 2.5 / Te), "f_mode", "2500")
            assert drv.cur["f_mode"] != 2.5 / Te
            drv.set(f_mode=f_new)
            if stop:
                drv.set(stop=True)
            drv.run(3, Te)
            drv.set(stop=False)
            drv.run_until_done(Te, 20000)
            check_all(drv)
            rec = drv.rec
            if stop:
                assert check_stops(rec) == StopCount(1, 0)
            else:
                assert abs(rec.x[-1] - 0.3) <= 1e-9 * 0.3
            assert max(rec.x) <= 0.3 * (1 + 1e-9), "passed the target"
            assert np.all(np.diff(rec.x) >= -Tolerances.of(rec).x), "backed up"
