"""Buffer modes, the queue and min_duration (issue 34, items 2 and 4), in FMI 2 and FMI 3.

docs/generator.md, "Buffer modes, the queue and synchronisation", states the rules these
tests hold the FMU to:

1. buffered commands run one after another: each starts from rest once the move before it
   has ended (shaper copies included), in the order given, and is the same move as one
   commanded from rest on its own;
2. blending passes the intermediate target at the blend speed -- the lower of the two
   moves' v_max, or the highest speed the shorter move can still stop from -- with every
   limit of each move respected on its own samples, no stop in between, and lands on the
   final target exactly; moves going opposite ways do not blend (they stop in between);
3. aborting (0, the start value) replaces the move and discards the queue
   (command_aborted); a stop discards it too;
4. bad commands (a buffer_mode or min_duration out of range, a full queue) set cmd_error
   with their code, return OK and leave the move in progress and the queue bit for bit as
   a run without them;
5. min_duration: a move lasts at least that long; wiring one instance's time_to_rest to
   another's min_duration makes both end on the same sample;
6. FMU states saved with a queue replay bit for bit, in the same and another instance;
7. random programs (hypothesis; DJL_QUEUE_EXAMPLES examples, 10 by default): every move
   lands on its target, every sample within the limits of the move it belongs to.

The numbers are checked against independent computations: the blend speed against the
AL stopping distance v^2 / (2 d), the positions against the outputs' own jerk integrated
sample by sample (exact cubics), the limits against the commanded values.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from harness.fmu import spec
from harness.fmu.runner import GeneratorFMU

TE = 1e-3
AXIS = {"profile": 3, "Te": TE, "distance": 0.0, "v_max": 1.0, "a_max": 10.0, "d_max": 10.0,
        "T_F1": 0.04, "T_F2": 0.04, "T_F3": 0.03, "T_F4": 0.025}
"""A commanded axis at rest at x0 = 0 (distance 0): moves come from execute edges."""

OUTS = ("x", "v", "a", "j")
FLAGS = ("stage", "done", "active", "command_aborted", "queue_length", "time_to_rest",
         "cmd_error", "cmd_error_id")
NAMES = OUTS + FLAGS
CODE = {name: code for code, name, _, _ in spec.CMD_ERRORS}
BUFFERED, BLENDING = 1, 2


class Run:
    """One instance driven step by step (h = Te), every output recorded after each step."""

    def __init__(self, g: GeneratorFMU, params: Mapping[str, Any] | None = None) -> None:
        self.g = g
        g._call(g.fmu.reset)
        g._initialized = False
        g.time = g.start_time
        g._setup()
        g.log.clear()
        g.set({**AXIS, **(params or {})})
        g.initialize()
        self.vr = g.vr(OUTS)
        self.rows: list[list[float]] = []

    def step(self, sets: Mapping[str, Any] | None = None) -> None:
        if sets:
            self.g.set(sets)
        self.g.do_step(TE)
        row = list(self.g.get_reals(self.vr))
        row += [float(self.g.get(n)) for n in FLAGS]
        self.rows.append(row)

    def play(self, script: Mapping[int, Mapping[str, Any]], n: int) -> None:
        for k in range(n):
            self.step(script.get(k))

    def col(self, name: str) -> np.ndarray:
        return np.array([r[NAMES.index(name)] for r in self.rows])

    def motion(self) -> np.ndarray:
        """x, v, a, j, stage, done, active, queue_length: the outputs but the error's."""
        return np.array(self.rows)[:, :8]


@pytest.fixture(scope="module")
def inst(fmus: dict[int, Path]) -> Iterator[dict[int, GeneratorFMU]]:
    gs = {v: GeneratorFMU(fmus[v], instance_name=f"queue{v}", debug_logging=True)
          for v in (2, 3)}
    yield gs
    for g in gs.values():
        g.close()


@pytest.fixture(params=[2, 3], ids=["fmi2", "fmi3"])
def g(request: pytest.FixtureRequest, inst: dict[int, GeneratorFMU]) -> GeneratorFMU:
    return inst[request.param]


def cmd(k0: int, target: float, mode: int = 0, **values: Any) -> dict[int, dict[str, Any]]:
    """An execute edge at step k0 with buffer_mode and per-command values; every value set
    back to its start at the next step (a latched value outlives its input)."""
    back = {n: ([0.0] * len(v) if isinstance(v, list) else 0) for n, v in values.items()}
    return {k0: {"target": target, "buffer_mode": mode, **values, "execute": True},
            k0 + 1: {"buffer_mode": 0, **back, "execute": False}}


def script(*parts: dict[int, dict[str, Any]]) -> dict[int, dict[str, Any]]:
    out: dict[int, dict[str, Any]] = {}
    for p in parts:
        for k, d in p.items():
            out.setdefault(k, {}).update(d)
    return out


def integrate(r: Run, k0: int = 0) -> np.ndarray:
    """x, v, a rebuilt from the jerk output alone (exact cubics over each sample, from the
    state at k0): an independent account of where the outputs say the axis goes."""
    x, v, a, j = (r.col(n) for n in OUTS)
    out = np.empty((len(x) - k0, 3))
    s = np.array([x[k0], v[k0], a[k0]])
    for i, k in enumerate(range(k0, len(x))):
        out[i] = s
        jj = j[k]
        s = np.array([s[0] + s[1] * TE + s[2] * TE**2 / 2 + jj * TE**3 / 6,
                      s[1] + s[2] * TE + jj * TE**2 / 2, s[2] + jj * TE])
    return out


# ---------------------------------------------------------------- 1. buffered


def test_buffered_commands_run_one_after_another_from_rest(g):
    """Three buffered commands given while the first move runs: each starts only once the
    one before rests, in order, lands on its target, and is the very move an execute from
    rest gives (the same samples); queue_length counts them down, active is true only
    while the last one moves, done only at the very end."""
    r = Run(g)
    prog = script(cmd(2, 0.3), cmd(20, 0.5, BUFFERED), cmd(22, 0.1, BUFFERED),
                  cmd(24, 0.4, BUFFERED, cmd_v_max=0.3))
    r.play(prog, 3500)
    x, v = r.col("x"), r.col("v")
    assert not r.col("cmd_error").any()
    ql = r.col("queue_length")
    assert ql[19] == 0 and ql[20] == 1 and ql[22] == 2 and ql[24] == 3
    assert np.all(np.diff(ql[25:]) <= 0), "the queue only empties"
    # rests between moves: the runs of v == 0 after the start split the program in four
    moving = np.abs(v) > 0
    starts = np.flatnonzero(moving[1:] & ~moving[:-1]) + 1
    ends = np.flatnonzero(moving[:-1] & ~moving[1:]) + 1
    assert len(starts) == 4 and len(ends) == 4, (starts, ends)
    for k, target in zip(ends, (0.3, 0.5, 0.1, 0.4), strict=True):
        assert x[k] == pytest.approx(target, abs=1e-12)
    # each buffered move starts within two samples of the previous one's rest
    assert np.all(starts[1:] - ends[:-1] <= 2)
    assert ql[ends[0]] == 3 and ql[starts[1]] == 2 and ql[starts[2]] == 1 and ql[starts[3]] == 0
    done = r.col("done").astype(bool)
    assert not done[3:ends[3]].any() and done[ends[3] + 1:].all()
    active = r.col("active").astype(bool)
    assert active[3:20].all() and not active[20:starts[3] - 1].any()
    assert active[starts[3]:ends[3]].all() and not active[ends[3] + 1:].any()
    # the same as each move commanded from rest on its own (an aborting execute at rest)
    v_max = {3: 0.3}
    for i in (1, 2, 3):
        alone = Run(g, {"x0": float(x[ends[i - 1]])})
        k0 = starts[i] - 1
        alone.play(script(cmd(0, (0.3, 0.5, 0.1, 0.4)[i],
                              **({"cmd_v_max": v_max[i]} if i in v_max else {}))), 1500)
        ref = alone.col("x")
        first = int(np.flatnonzero(np.abs(alone.col("v")) > 0)[0])
        n = ends[i] - k0
        assert np.array_equal(x[k0:ends[i] + 1], ref[first - 1:first - 1 + n + 1]), i
    assert np.max(np.abs(v[starts[3]:ends[3]])) <= 0.3 * (1 + 1e-12)


def test_buffered_waits_for_the_shaper_copies(g):
    """With a ZV shaper at 8 Hz (a copy 62.5 ms late) a buffered command starts only once
    the last copy has rested: after the plan's end plus the shaper's delay."""
    r = Run(g, {"shaper": 1, "f_shaper": 8.0})
    r.play(script(cmd(2, 0.3), cmd(10, 0.0, BUFFERED)), 1800)
    x, v = r.col("x"), r.col("v")
    moving = np.abs(v) > 0
    ends = np.flatnonzero(moving[:-1] & ~moving[1:]) + 1
    starts = np.flatnonzero(moving[1:] & ~moving[:-1]) + 1
    assert len(starts) == 2 and x[ends[0]] == pytest.approx(0.3, abs=1e-12)
    assert 1 <= starts[1] - ends[0] <= 2
    assert x[ends[1]] == pytest.approx(0.0, abs=1e-12)


# ---------------------------------------------------------------- 2. blending


def _blend(g: GeneratorFMU, x1: float, x2: float, a_values: dict, b_values: dict,
           params: dict | None = None, n: int = 3000) -> Run:
    r = Run(g, params)
    r.play(script(cmd(2, x1, 0, **a_values), cmd(30, x2, BLENDING, **b_values)), n)
    assert not r.col("cmd_error").any()
    return r


def _pass_sample(r: Run, x1: float) -> int:
    """The sample at which the axis is at x1 (the plan of A ends there exactly)."""
    x = r.col("x")
    k = int(np.argmin(np.abs(x - x1)))
    assert x[k] == pytest.approx(x1, abs=1e-12), (x[k], x1)
    return k


@pytest.mark.parametrize("va,vb", [(1.0, 0.6), (0.5, 0.9)], ids=["B-slower", "A-slower"])
def test_blending_passes_the_target_at_the_lower_v_max_within_each_moves_limits(g, va, vb):
    """A to 0.4 m at v_max va, then B blending to 1.2 m at vb: at 0.4 m the axis moves at
    min(va, vb) with zero acceleration, never stops in between, keeps A's limits before and
    B's after, and lands on 1.2 m exactly (the jerk integrated agrees)."""
    r = _blend(g, 0.4, 1.2, {"cmd_v_max": va, "cmd_a_max": 8.0},
               {"cmd_v_max": vb, "cmd_a_max": 5.0, "cmd_d_max": 4.0})
    x, v, a = r.col("x"), r.col("v"), r.col("a")
    k = _pass_sample(r, 0.4)
    assert v[k] == pytest.approx(min(va, vb), rel=1e-12)
    assert a[k] == pytest.approx(0.0, abs=1e-9)
    end = int(np.flatnonzero(np.abs(v) > 0)[-1]) + 1
    assert x[end] == pytest.approx(1.2, abs=1e-12) and v[end] == 0.0
    first = int(np.flatnonzero(np.abs(v) > 0)[0])
    assert np.all(v[first:end] > 0), "no stop between the two moves"
    assert np.all(np.abs(v[:k + 1]) <= va * (1 + 1e-12))
    assert np.all(a[:k + 1] <= 8.0 * (1 + 1e-12)) and np.all(a[:k + 1] >= -10.0 * (1 + 1e-12))
    assert np.all(np.abs(v[k:]) <= vb * (1 + 1e-12))
    assert np.all(a[k:] <= 5.0 * (1 + 1e-12)) and np.all(a[k:] >= -4.0 * (1 + 1e-12))
    xi = integrate(r)
    assert np.max(np.abs(xi[:, 0] - x)) < 1e-9 and np.max(np.abs(xi[:, 1] - v)) < 1e-7


def test_blending_speed_is_what_the_short_move_can_stop_from(g):
    """B (AL, d_max 2 m/s2) only 2 cm past A's target: it cannot stop from min(v_max) = 1
    m/s, so the axis passes at the highest speed it can stop from, which an AL stop gives
    in closed form: v^2 / (2 d) = the 2 cm less the sample cruised at v."""
    d_b, gap = 2.0, 0.02
    r = _blend(g, 0.5, 0.5 + gap, {}, {"cmd_profile": 1, "cmd_d_max": d_b})
    v = r.col("v")
    k = _pass_sample(r, 0.5)
    vb = v[k]
    # independent: the largest v with v^2 / (2 d) + v Te <= gap
    expect = -d_b * TE + math.sqrt((d_b * TE) ** 2 + 2 * d_b * gap)
    assert 0.0 < vb < 1.0
    assert vb == pytest.approx(expect, rel=2e-2)
    assert r.col("x")[-1] == pytest.approx(0.5 + gap, abs=1e-12)
    assert np.all(r.col("a")[k:] >= -d_b * (1 + 1e-12))
    first = int(np.flatnonzero(np.abs(v) > 0)[0])
    end = int(np.flatnonzero(np.abs(v) > 0)[-1])
    assert np.all(v[first:end] > 0)


def test_blending_the_other_way_stops_in_between(g):
    """B goes back: no blend (v_b = 0), the axis rests at A's target, then moves to B's as
    a buffered command would."""
    r = _blend(g, 0.4, 0.1, {}, {})
    x, v = r.col("x"), r.col("v")
    moving = np.abs(v) > 0
    ends = np.flatnonzero(moving[:-1] & ~moving[1:]) + 1
    assert len(ends) == 2
    assert x[ends[0]] == pytest.approx(0.4, abs=1e-12)
    assert x[ends[1]] == pytest.approx(0.1, abs=1e-12)


def test_blending_behind_the_parametric_move(g):
    """The parametric move (distance 0.4 m from t = 0) followed by a blending command to
    0.9 m at v_max 0.5: the axis passes 0.4 m at 0.5 m/s, lands on 0.9 m."""
    r = Run(g, {"distance": 0.4})
    r.play(script(cmd(5, 0.9, BLENDING, cmd_v_max=0.5)), 3000)
    assert not r.col("cmd_error").any()
    k = _pass_sample(r, 0.4)
    assert r.col("v")[k] == pytest.approx(0.5, rel=1e-12)
    assert r.col("x")[-1] == pytest.approx(0.9, abs=1e-12)


def test_blending_with_another_shaper_waits_as_buffered(g):
    """B asks for a ZV shaper while A has none: a shaper changes only from rest, so B does
    not blend: the axis rests at A's target, then B runs shaped; no error."""
    r = _blend(g, 0.4, 0.8, {}, {"cmd_shaper": 1})
    x, v = r.col("x"), r.col("v")
    moving = np.abs(v) > 0
    ends = np.flatnonzero(moving[:-1] & ~moving[1:]) + 1
    assert len(ends) == 2 and x[ends[0]] == pytest.approx(0.4, abs=1e-12)
    assert x[-1] == pytest.approx(0.8, abs=1e-12)
    assert any("waits as buffered" in m.message for m in g.log)


def test_blending_with_min_duration_waits_as_buffered(g):
    """B blending with a min_duration of its own: its duration counts from rest, so the
    axis rests at A's target, then B lasts at least min_duration."""
    r = _blend(g, 0.4, 0.6, {}, {"min_duration": 1.0})
    x, v = r.col("x"), r.col("v")
    moving = np.abs(v) > 0
    ends = np.flatnonzero(moving[:-1] & ~moving[1:]) + 1
    starts = np.flatnonzero(moving[1:] & ~moving[:-1]) + 1
    assert len(ends) == 2 and x[ends[0]] == pytest.approx(0.4, abs=1e-12)
    assert (ends[1] - starts[1] + 2) * TE >= 1.0 - 1e-9
    assert x[-1] == pytest.approx(0.6, abs=1e-12)


def test_a_chain_of_blends_lands_on_the_last_target(g):
    """Four moves blended one after another (given at once): the axis passes 0.2, 0.5 and
    0.9 m without stopping, at the lower v_max of each pair, and rests on 1.0 m."""
    r = Run(g)
    r.play(script(cmd(2, 0.2, 0, cmd_v_max=0.8), cmd(4, 0.5, BLENDING, cmd_v_max=0.6),
                  cmd(6, 0.9, BLENDING, cmd_v_max=0.7), cmd(8, 1.0, BLENDING)), 4000)
    assert not r.col("cmd_error").any()
    v = r.col("v")
    for x1, vb in ((0.2, 0.6), (0.5, 0.6)):
        k = _pass_sample(r, x1)
        assert v[k] == pytest.approx(vb, rel=1e-12)
    k = _pass_sample(r, 0.9)
    assert 0.0 < v[k] <= 0.7 * (1 + 1e-12)
    first = int(np.flatnonzero(np.abs(v) > 0)[0])
    end = int(np.flatnonzero(np.abs(v) > 0)[-1])
    assert np.all(v[first:end] > 0)
    assert r.col("x")[-1] == pytest.approx(1.0, abs=1e-12)


# ---------------------------------------------------------------- 3. aborting, stop


def test_aborting_discards_the_queue_and_says_so(g):
    r = Run(g)
    r.play(script(cmd(2, 0.5), cmd(10, 0.8, BUFFERED), cmd(12, 0.9, BUFFERED),
                  cmd(100, -0.2), cmd(1500, 0.0)), 2500)
    ql, ab = r.col("queue_length"), r.col("command_aborted")
    assert ql[99] == 2 and ql[100] == 0
    assert not ab[:100].any() and ab[100:1500].all() and not ab[1500:].any()
    x = r.col("x")
    assert x[1499] == pytest.approx(-0.2, abs=1e-12) and x[-1] == pytest.approx(0.0, abs=1e-12)
    assert x.max() < 0.5


def test_a_stop_discards_the_queue(g):
    r = Run(g)
    r.play(script(cmd(2, 0.5), cmd(10, 0.8, BUFFERED), {100: {"stop": True}},
                  {101: {"stop": False}}), 1500)
    assert r.col("queue_length")[100] == 0 and r.col("command_aborted")[100] == 1
    assert r.col("x")[-1] < 0.5 and r.col("done")[-1] == 1


# ---------------------------------------------------------------- 4. bad commands


@pytest.mark.parametrize("bad,code", [({"buffer_mode": 3}, "BUFFER_MODE"),
                                      ({"buffer_mode": -1}, "BUFFER_MODE"),
                                      ({"min_duration": -1.0}, "MIN_DURATION"),
                                      ({"min_duration": math.nan}, "MIN_DURATION"),
                                      ({"min_duration": math.inf}, "MIN_DURATION"),
                                      ({"min_duration": 1e13}, "MIN_DURATION")])
def test_a_bad_buffer_mode_or_min_duration_is_refused_and_changes_nothing(g, bad, code):
    base_prog = script(cmd(2, 0.5), cmd(10, 0.8, BUFFERED))
    base = Run(g)
    base.play(base_prog, 1500)
    r = Run(g)
    bad_prog = script(base_prog, {50: {"target": -0.3, **bad, "execute": True}},
                      {51: {"execute": False, "buffer_mode": 0, "min_duration": 0.0}})
    r.play(bad_prog, 1500)
    err, eid = r.col("cmd_error"), r.col("cmd_error_id")
    assert not err[:50].any() and err[50:].all() and np.all(eid[50:] == CODE[code])
    assert np.array_equal(r.motion(), base.motion())
    assert any(("buffer_mode" in m.message or "min_duration" in m.message) and "refused"
               in m.message for m in g.log)


def test_a_full_queue_refuses_the_next_command_and_keeps_the_queue(g):
    """16 buffered commands wait; the 17th is code 16; the 16 then run as if it had not
    been given, and a valid command afterwards clears the error."""
    cap = spec.QUEUE_CAPACITY
    moves = [cmd(2, 0.05)] + [cmd(4 + 2 * i, 0.05 * (i + 2), BUFFERED) for i in range(cap)]
    base = Run(g)
    base.play(script(*moves), 400)
    r = Run(g)
    r.play(script(*moves, cmd(4 + 2 * cap, 9.0, BUFFERED)), 400)
    assert base.col("queue_length").max() == cap
    err = r.col("cmd_error")
    k = 4 + 2 * cap
    assert err[k] == 1 and r.col("cmd_error_id")[k] == CODE["QUEUE_FULL"]
    assert np.array_equal(r.motion(), base.motion())


# ---------------------------------------------------------------- 5. min_duration


def _end_step(r: Run) -> int:
    v = r.col("v")
    return int(np.flatnonzero(np.abs(v) > 0)[-1]) + 1


def test_min_duration_makes_a_move_last_at_least_that_long(g):
    """0.1 m asks about 0.2 s at the limits; with min_duration = 0.8 s it lasts 0.8 s to
    within a sample (at least), cruising below v_max; a min_duration below the move's
    own duration changes nothing (bit for bit)."""
    # the edge is read at the step from t = 2 Te; row k holds the outputs at (k + 1) Te
    fast = Run(g)
    fast.play(script(cmd(2, 0.1)), 1200)
    t_fast = (_end_step(fast) + 1 - 2) * TE
    slow = Run(g)
    slow.play(script(cmd(2, 0.1, min_duration=0.8)), 1200)
    t_slow = (_end_step(slow) + 1 - 2) * TE
    assert t_fast < 0.4
    assert 0.8 - 1e-9 <= t_slow <= 0.8 + 2 * TE
    assert slow.col("x")[-1] == pytest.approx(0.1, abs=1e-12)
    same = Run(g)
    same.play(script(cmd(2, 0.1, min_duration=t_fast / 2)), 1200)
    assert np.array_equal(same.motion(), fast.motion())


def test_time_to_rest_wired_to_min_duration_ends_two_instances_together(inst):
    """Instance A: 0.7 m DJL; instance B (JL, other jerk time): 0.1 m, executed one step
    later with min_duration = A's time_to_rest.  B rests on A's last sample or the next
    (its motion time is whole samples: the fastest that is at least A's)."""
    for v, ga in inst.items():
        with GeneratorFMU(ga.path, instance_name="B") as gb:
            a = Run(ga)
            b = Run(gb, {"profile": 2, "T_F1": 0.03})
            for k in range(1500):
                # a master's communication point: read every output, set, step both
                sets_b = ({"target": 0.1, "execute": True,
                           "min_duration": float(ga.get("time_to_rest"))} if k == 3 else None)
                a.step({"target": 0.7, "execute": True} if k == 2 else None)
                b.step(sets_b)
            assert 0 <= _end_step(b) - _end_step(a) <= 1, f"FMI {v}"
            assert b.col("x")[-1] == pytest.approx(0.1, abs=1e-12)
            assert np.abs(b.col("v")).max() < 0.5


# ---------------------------------------------------------------- 6. FMU state


def test_fmu_state_with_a_queue_replays_bit_for_bit(inst):
    pre = script(cmd(2, 0.3), cmd(5, 0.6, BLENDING, cmd_v_max=0.5),
                 cmd(7, 0.2, BUFFERED, cmd_a_max=4.0), cmd(9, 0.25, BUFFERED, min_duration=0.6))
    for v, g in inst.items():
        r = Run(g)
        r.play(pre, 100)
        assert r.col("queue_length")[-1] == 3
        saved = g.time
        state = g.get_state()
        data = g.serialize_state(state)
        r.rows = []
        r.play({}, 2500)
        first = np.array(r.rows)
        assert first[-1, NAMES.index("x")] == pytest.approx(0.25, abs=1e-12)
        g.set_state(state, saved)
        r.rows = []
        r.play({}, 2500)
        assert np.array_equal(np.array(r.rows), first), f"FMI {v}: restored"
        g.free_state(state)
        with GeneratorFMU(g.path) as other:
            o = Run(other, {"profile": 1, "v_max": 2.0, "distance": -0.2})
            s2 = other.deserialize_state(data)
            other.set_state(s2, saved)
            other.free_state(s2)
            o.rows = []
            o.play({}, 2500)
            assert np.array_equal(np.array(o.rows), first), f"FMI {v}: deserialised"


# ---------------------------------------------------------------- 7. random programs


EXAMPLES = int(os.environ.get("DJL_QUEUE_EXAMPLES", "10"))


@st.composite
def programs(draw: st.DrawFn) -> list[tuple[int, float, int, float, float, float]]:
    n = draw(st.integers(2, 5))
    out = []
    for i in range(n):
        out.append((2 + 3 * i, draw(st.floats(-0.6, 0.6)), 0 if i == 0 else draw(st.sampled_from(
            [BUFFERED, BLENDING])), draw(st.floats(0.2, 1.0)), draw(st.floats(2.0, 10.0)),
            draw(st.floats(2.0, 10.0))))
    return out


@settings(max_examples=EXAMPLES, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(prog=programs())
def test_random_programs_land_within_each_moves_limits(inst, prog):
    g = inst[3]
    r = Run(g)
    parts = [cmd(k, tgt, mode, cmd_v_max=vm, cmd_a_max=am, cmd_d_max=dm)
             for k, tgt, mode, vm, am, dm in prog]
    prog_script = script(*parts)
    for k in range(30000):   # until the program has ended (at most 30 s)
        r.step(prog_script.get(k))
        if k > 20 and r.rows[-1][NAMES.index("done")]:
            break
    assert not r.col("cmd_error").any()
    assert r.col("done")[-1] == 1
    x, v, a = r.col("x"), r.col("v"), r.col("a")
    assert x[-1] == pytest.approx(prog[-1][1], abs=1e-12)
    # never beyond the largest limits commanded (each sample belongs to one move)
    assert np.abs(v).max() <= max(p[3] for p in prog) * (1 + 1e-9)
    assert np.abs(a).max() <= max(max(p[4], p[5]) for p in prog) * (1 + 1e-9)
    xi = integrate(r)
    assert np.max(np.abs(xi[:, 0] - x)) < 1e-9
