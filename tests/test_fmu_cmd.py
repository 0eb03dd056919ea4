"""Per-command values and command errors (issue 34), in FMI 2 and FMI 3 through fmpy.

docs/generator.md, "Per-command values" and "Command errors", states the rules these tests
hold the FMU to:

1. each per-command value changes exactly what it names, for the move it is latched with
   (at the execute edge), and the next move without it has the parameter's value again:
   cmd_v_max the peak velocity, cmd_a_max / cmd_d_max the acceleration / deceleration
   levels, cmd_profile and cmd_T_F the jerk ramps, cmd_shaper the impulses the output is
   made of; a stop uses the stopped move's values or its own;
2. a bad command (an execute or stop edge whose values are invalid) returns OK, sets
   cmd_error and cmd_error_id (the code of spec.CMD_ERRORS), logs the input and its value,
   and leaves every other output bit for bit as a run without it; the next valid command
   clears the error;
3. FMU states saved in the middle of a move with per-command values replay bit for bit;
4. the cmd_* inputs left at 0 (or set to values that no edge latches) change nothing;
5. random commands with random values (hypothesis; DJL_CMD_EXAMPLES examples, 12 by
   default): every one lands on its target within the limits in force.

Every number is checked against an independent computation: the peak velocity against
cmd_v_max, the landing against target, a ramp's length against cmd_T_F / Te, the shaped
output against the sum of delayed copies of an unshaped run -- never against the FMU's own
figures.
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
        "T_F1": 0.08, "T_F2": 0.08, "T_F3": 0.06, "T_F4": 0.05}
"""A commanded axis at rest at x0 = 0 (distance 0): moves come from execute edges."""

OUTS = ("x", "v", "a", "j")
FLAGS = ("stage", "done", "cmd_error", "cmd_error_id")
CMD_ZERO: dict[str, Any] = {
    "cmd_v_max": 0.0, "cmd_a_max": 0.0, "cmd_d_max": 0.0, "cmd_profile": 0,
    "cmd_T_F": [0.0] * 4, "cmd_shaper": 0, "cmd_shaper_n": 0,
    "cmd_shaper_amplitude": [0.0] * spec.MAX_SHAPER_IMPULSES,
    "cmd_shaper_delay": [0.0] * spec.MAX_SHAPER_IMPULSES}
CODE = {name: code for code, name, _, _ in spec.CMD_ERRORS}


class Run:
    """One instance driven step by step (h = Te), every output recorded after each step."""

    def __init__(self, g: GeneratorFMU, params: Mapping[str, Any] | None = None,
                 before: Mapping[str, Any] | None = None) -> None:
        self.g = g
        g._call(g.fmu.reset)   # as tests/_command_checks.py's Driver: a fresh instance
        g._initialized = False
        g.time = g.start_time
        g._setup()
        g.log.clear()
        g.set({**AXIS, **(params or {}), **(before or {})})
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
        return np.array([r[(OUTS + FLAGS).index(name)] for r in self.rows])

    def motion(self) -> np.ndarray:
        """x, v, a, j, stage, done: every output but the command error's."""
        return np.array(self.rows)[:, :6]


@pytest.fixture(scope="module")
def inst(fmus: dict[int, Path]) -> Iterator[dict[int, GeneratorFMU]]:
    gs = {v: GeneratorFMU(fmus[v], instance_name=f"cmd{v}", debug_logging=True) for v in (2, 3)}
    yield gs
    for g in gs.values():
        g.close()


@pytest.fixture(params=[2, 3], ids=["fmi2", "fmi3"])
def g(request: pytest.FixtureRequest, inst: dict[int, GeneratorFMU]) -> GeneratorFMU:
    return inst[request.param]


def _move(k0: int, target: float, **cmd: Any) -> dict[int, dict[str, Any]]:
    """An execute edge at step k0 with the per-command values cmd, which are set back to 0
    at the next step (with the edge's falling side): a latched value outlives its input."""
    back = {n: CMD_ZERO[n.removesuffix("_code")] for n in cmd}
    return {k0: {"target": target, **cmd, "execute": True}, k0 + 1: {**back, "execute": False}}


def _script(*parts: dict[int, dict[str, Any]]) -> dict[int, dict[str, Any]]:
    out: dict[int, dict[str, Any]] = {}
    for p in parts:
        for k, d in p.items():
            out.setdefault(k, {}).update(d)
    return out


# ------------------------------------------------ 1. each value changes what it names


def test_cmd_v_max_is_the_peak_velocity_of_its_move_only(g):
    """1 m at cmd_v_max = 0.4 m/s: the axis cruises at 0.4 m/s (the landing on a sample
    lowers it by less than 1e-3) and lands on the target; the next move, without it, at the
    parameter's v_max = 1 m/s."""
    r = Run(g)
    r.play(_script(_move(2, 1.0, cmd_v_max=0.4), _move(3500, 0.0)), 6000)
    v, x = r.col("v"), r.col("x")
    first, second = v[:3500], v[3500:]
    assert 0.4 * (1 - 1e-3) <= first.max() <= 0.4 * (1 + 1e-12)
    assert x[3499] == pytest.approx(1.0, abs=1e-12) and v[3499] == 0.0
    assert 1.0 * (1 - 1e-3) <= -second.min() <= 1.0 * (1 + 1e-12)
    assert x[-1] == pytest.approx(0.0, abs=1e-12)
    # 1 m at 0.4 m/s cruises for most of 2.5 s: the move lasts at least d / v
    moving = np.nonzero(np.abs(first) > 0)[0]
    assert (moving[-1] - moving[0] + 1) * TE >= 1.0 / 0.4
    assert not r.col("cmd_error").any()


def test_cmd_a_max_and_cmd_d_max_are_the_levels_of_their_move_only(g):
    """cmd_a_max = 4 m/s2: the acceleration peaks at 4, the deceleration stays at the
    parameter's 10; cmd_d_max = 3 m/s2 on the next move: the deceleration peaks at 3, the
    acceleration at the parameter's 10; a third move has both parameters again."""
    r = Run(g)
    r.play(_script(_move(2, 1.0, cmd_a_max=4.0), _move(2000, 0.0, cmd_d_max=3.0),
                   _move(4000, 1.0)), 6000)
    a = r.col("a")
    m1, m2, m3 = a[:2000], a[2000:4000], a[4000:]
    # move 1 goes up: acceleration > 0, deceleration < 0; move 2 goes down: mirrored.  A
    # level may lie below its limit (the landing on a sample recomputes it: 2.9914 for 3),
    # never above; 1 % tells 3 and 4 from the parameters' 10

    assert 4.0 * (1 - 1e-2) <= m1.max() <= 4.0 * (1 + 1e-12)
    assert 10.0 * (1 - 1e-2) <= -m1.min() <= 10.0 * (1 + 1e-12)
    assert 10.0 * (1 - 1e-2) <= -m2.min() <= 10.0 * (1 + 1e-12)   # accelerating downwards
    assert 3.0 * (1 - 1e-2) <= m2.max() <= 3.0 * (1 + 1e-12)       # decelerating
    assert 10.0 * (1 - 1e-2) <= m3.max() <= 10.0 * (1 + 1e-12)
    assert 10.0 * (1 - 1e-2) <= -m3.min() <= 10.0 * (1 + 1e-12)
    x = r.col("x")
    for k, target in ((1999, 1.0), (3999, 0.0), (5999, 1.0)):
        assert x[k] == pytest.approx(target, abs=1e-12)


def _ramps(run: Run, k0: int, k1: int) -> list[tuple[int, int]]:
    """(stage, length in samples) of each run of constant nonzero jerk in [k0, k1)."""
    j, stage = run.col("j")[k0:k1], run.col("stage")[k0:k1]
    out: list[tuple[int, int]] = []
    i = 0
    while i < len(j):
        if j[i] == 0.0:
            i += 1
            continue
        n = 1
        while i + n < len(j) and abs(j[i + n] - j[i]) <= 1e-9 * abs(j[i]):
            n += 1
        out.append((int(stage[i]), n))
        i += n
    return out


def test_cmd_profile_and_cmd_T_F_are_the_ramps_of_their_move_only(g):
    """AL: no jerk at all; JL with cmd_T_F[1] = 20 ms: four ramps of 20 samples; DJL with
    cmd_T_F = 10/30/20/40 ms: ramps of 10, 30, 20, 40 samples in stages 1..4; then a move
    without them: the parameter's DJL ramps of 80/80/60/50 samples."""
    r = Run(g)
    r.play(_script(_move(2, 1.0, cmd_profile=1),
                   _move(2000, 0.0, cmd_profile=2, cmd_T_F=[0.02, 0.0, 0.0, 0.0]),
                   _move(4000, 1.0, cmd_profile=3, cmd_T_F=[0.01, 0.03, 0.02, 0.04]),
                   _move(6000, 0.0)), 8000)
    j, x = r.col("j"), r.col("x")
    assert not j[:2000].any()
    assert 10.0 * (1 - 1e-2) <= np.abs(r.col("a")[:2000]).max() <= 10.0 * (1 + 1e-12)
    assert _ramps(r, 2000, 4000) == [(1, 20), (2, 20), (3, 20), (4, 20)]
    assert np.abs(j[2000:4000]).max() == pytest.approx(10.0 / 0.02, rel=1e-9)
    assert _ramps(r, 4000, 6000) == [(1, 10), (2, 30), (3, 20), (4, 40)]
    assert _ramps(r, 6000, 8000) == [(1, 80), (2, 80), (3, 60), (4, 50)]
    for k, target in ((1999, 1.0), (3999, 0.0), (5999, 1.0), (7999, 0.0)):
        assert x[k] == pytest.approx(target, abs=1e-12)


def test_cmd_T_F_alone_keeps_the_parameter_profile(g):
    """cmd_profile = 0 with cmd_T_F[3] = 10 ms: the parameter's DJL, stage 3 alone
    changed (the 0 elements are the parameters T_F1, T_F2, T_F4)."""
    r = Run(g)
    r.play(_move(2, 1.0, cmd_T_F=[0.0, 0.0, 0.01, 0.0]), 2000)
    assert _ramps(r, 0, 2000) == [(1, 80), (2, 80), (3, 10), (4, 50)]


def _shifted(x: np.ndarray, d: int) -> np.ndarray:
    return np.concatenate([np.full(d, x[0]), x[:-d]]) if d else x


@pytest.mark.parametrize(("cmd", "impulses"), [
    ({"cmd_shaper": 1}, [(0.5, 0), (0.5, 50)]),       # ZV at f_shaper = 10 Hz, zeta 0
    ({"cmd_shaper": 2}, [(0.25, 0), (0.5, 50), (0.25, 100)]),    # ZVD
    ({"cmd_shaper": 4, "cmd_shaper_n": 3, "cmd_shaper_amplitude": [0.2, 0.5, 0.3],
      "cmd_shaper_delay": [0.0, 0.013, 0.031]}, [(0.2, 0), (0.5, 13), (0.3, 31)]),
], ids=["ZV", "ZVD", "custom"])
def test_cmd_shaper_shapes_its_move_only(g, cmd, impulses):
    """The shaped move is the sum of the unshaped move's copies, A_i p(t - t_i) (p from a
    run without a shaper); the next move with cmd_shaper = 0 is the parameter's (none):
    the same as in the run that never had one."""
    plain = Run(g)
    plain.play(_script(_move(2, 0.5), _move(1500, -0.2)), 2500)
    p = np.array(plain.rows)
    shaped = Run(g)
    shaped.play(_script(_move(2, 0.5, **cmd), _move(1500, -0.2)), 2500)
    s = np.array(shaped.rows)
    for col in (0, 1):   # x, v
        want = sum(A * _shifted(p[:1500, col], d) for A, d in impulses)
        assert np.abs(s[:1500, col] - want).max() <= 1e-12 * (1 + np.abs(p[:, col]).max())
    assert s[1499, 0] == pytest.approx(0.5, abs=1e-12) and s[1499, 1] == 0.0
    # back to the parameter's shaper (none): the move from the same rest is the plain one
    assert np.abs(s[1500:, :4] - p[1500:, :4]).max() <= 1e-12
    assert not s[:, 6].any()


def test_a_stop_takes_the_stopped_move_s_values_or_its_own(g):
    """A stop during a move at cmd_d_max = 2 m/s2 decelerates at 2 (the stopped move's),
    a stop with its own cmd_d_max = 5 at 5 -- not at the parameter's 10."""
    for own, level in ((None, 2.0), (5.0, 5.0)):
        r = Run(g)
        stop = {"stop": True} if own is None else {"stop": True, "cmd_d_max": own}
        r.play(_script(_move(2, 2.0, cmd_d_max=2.0), {600: stop}, {601: {"stop": False}}),
               1800)
        a, v = r.col("a"), r.col("v")
        assert v[599] > 0.99   # cruising at 1 m/s when the stop comes
        # (the stop's level: v / whole samples, within a sample of 500 of d_max)
        assert level * (1 - 1e-2) <= -a[600:].min() <= level * (1 + 1e-12)
        assert v[-1] == 0.0 and r.col("done")[-1] == 1.0
        # at rest after the stop, short of the target
        assert r.col("x")[-1] < 2.0


def test_a_lower_cmd_v_max_during_a_faster_move_stops_first_then_moves_within_it(g):
    """A command whose cmd_v_max is below the speed the axis has: the axis comes to rest
    (with the command's d_max), then moves to the target, never above cmd_v_max after its
    speed first falls below it."""
    r = Run(g)
    r.play(_script(_move(2, 3.0), _move(400, 2.0, cmd_v_max=0.3)), 8000)
    v, x = r.col("v"), r.col("x")
    assert v[399] > 0.99
    below = np.nonzero(np.abs(v[400:]) <= 0.3)[0][0] + 400
    assert np.abs(v[below:]).max() <= 0.3 * (1 + 1e-12)
    assert x[-1] == pytest.approx(2.0, abs=1e-12) and v[-1] == 0.0
    assert np.abs(r.col("a")).max() <= 10.0 * (1 + 1e-12)


def test_fmi2_integer_aliases_of_the_command_enumerations(fmus):
    """FMI 2: cmd_profile_code and cmd_shaper_code share the value references of the
    Enumerations (FMI 2.0, 2.2.7) and set them."""
    with GeneratorFMU(fmus[2]) as g2:
        for name in ("cmd_profile", "cmd_shaper"):
            alias, var = g2.variable(name + "_code"), g2.variable(name)
            assert alias.type == "Integer" and var.type == "Enumeration"
            assert alias.valueReference == var.valueReference and alias.causality == "input"
        r = Run(g2)
        r.play(_move(2, 1.0, cmd_profile_code=2, cmd_T_F=[0.02, 0, 0, 0]), 2000)
        assert _ramps(r, 0, 2000) == [(1, 20), (2, 20), (3, 20), (4, 20)]


# ------------------------------------------------------------- 2. command errors


BAD = [
    # (name, the values of the bad command, its code, the text its message names)
    ("target NaN", {"target": math.nan}, "TARGET", "target = nan"),
    ("target inf", {"target": math.inf}, "TARGET", "target = inf"),
    ("target 1e301", {"target": -1e301}, "TARGET", "target = -1e+301"),
    ("target too far", {"target": 1e300}, "NO_MOTION", "target = 1.0000000000000001e+300"),
    ("cmd_v_max < 0", {"cmd_v_max": -1.0}, "V_MAX", "cmd_v_max = -1"),
    ("cmd_v_max NaN", {"cmd_v_max": math.nan}, "V_MAX", "cmd_v_max = nan"),
    ("cmd_a_max inf", {"cmd_a_max": math.inf}, "A_MAX", "cmd_a_max = inf"),
    ("cmd_d_max < 0", {"cmd_d_max": -5.0}, "D_MAX", "cmd_d_max = -5"),
    ("cmd_profile 4", {"cmd_profile": 4}, "PROFILE", "cmd_profile = 4"),
    ("cmd_profile -1", {"cmd_profile": -1}, "PROFILE", "cmd_profile = -1"),
    ("cmd_T_F < Te/2", {"cmd_T_F": [0.0, 0.0004, 0.0, 0.0]}, "T_F", "cmd_T_F[2] = 0.0004"),
    ("cmd_T_F NaN", {"cmd_T_F": [math.nan, 0.0, 0.0, 0.0]}, "T_F", "cmd_T_F[1] = nan"),
    ("cmd_shaper 6", {"cmd_shaper": 6}, "SHAPER", "cmd_shaper = 6"),
    ("too many impulses", {"cmd_shaper": 4, "cmd_shaper_n": 9}, "SHAPER_N",
     "cmd_shaper_n = 9"),
    ("amplitudes sum 0.9", {"cmd_shaper": 4, "cmd_shaper_n": 2,
                            "cmd_shaper_amplitude": [0.5, 0.4]}, "SHAPER_AMPLITUDE",
     "cmd_shaper_amplitude[1..2] sum to 0.9"),
    ("negative delay", {"cmd_shaper": 4, "cmd_shaper_n": 2, "cmd_shaper_amplitude": [0.5, 0.5],
                        "cmd_shaper_delay": [0.0, -0.01]}, "SHAPER_DELAY",
     "cmd_shaper_delay[2] = -0.01"),
    ("delay beyond the memory", {"cmd_shaper": 4, "cmd_shaper_n": 1,
                                 "cmd_shaper_amplitude": [1.0], "cmd_shaper_delay": [5.0]},
     "SHAPER_DELAY", "cmd_shaper_delay[1] = 5"),
    ("shaper while moving", {"cmd_shaper": 1}, "SHAPER_WHILE_MOVING", "cmd_shaper = 1"),
]


def _bad_run(g: GeneratorFMU, bad: Mapping[str, Any] | None, kind: str = "execute",
             params: Mapping[str, Any] | None = None) -> Run:
    """A move to 0.6 m, the (bad) command in the middle of it at step 150, a valid move to
    0.2 m at step 1200 (mid-move as well)."""
    r = Run(g, params)
    script = _script(_move(3, 0.6), _move(1200, 0.2))
    if bad is not None:
        edge = {kind: True}
        keep = {"target": 0.6} if "target" in bad else {}
        back = {n: CMD_ZERO[n] for n in bad if n != "target"}
        script = _script(script, {150: {**bad, **edge}}, {151: {kind: False, **back, **keep}})
    r.play(script, 2200)
    return r


@pytest.mark.parametrize(("case", "bad", "code", "text"), BAD, ids=[b[0] for b in BAD])
def test_a_bad_command_sets_cmd_error_and_changes_nothing_else(g, case, bad, code, text):
    ref = _bad_run(g, None)
    g.log.clear()
    r = _bad_run(g, bad)   # any error: do_step raises; none may
    assert np.array_equal(r.motion(), ref.motion()), case
    err, eid = r.col("cmd_error"), r.col("cmd_error_id")
    assert not err[:150].any() and not eid[:150].any()
    assert err[150:1200].all() and (eid[150:1200] == CODE[code]).all()
    assert not err[1200:].any() and not eid[1200:].any()   # the next valid command clears it
    msgs = [str(m) for m in g.log if "command refused" in str(m)]
    assert len(msgs) == 1 and text in msgs[0] and f"cmd_error_id = {CODE[code]}" in msgs[0], msgs
    assert r.col("x")[-1] == pytest.approx(0.2, abs=1e-12)


@pytest.mark.parametrize(("bad", "code"), [({"cmd_d_max": -1.0}, "D_MAX"),
                                           ({"cmd_T_F": [0.0, 0.0, 0.0, -0.01]}, "T_F"),
                                           ({"cmd_profile": 9}, "PROFILE")])
def test_a_bad_stop_sets_cmd_error_and_the_move_goes_on(g, bad, code):
    ref = _bad_run(g, None)
    r = _bad_run(g, bad, kind="stop")
    assert np.array_equal(r.motion(), ref.motion())
    assert (r.col("cmd_error_id")[150:1200] == CODE[code]).all()
    assert not r.col("cmd_error")[1200:].any()


def test_a_stop_ignores_a_bad_target_and_the_shaper_inputs(g):
    """A stop does not go to target nor change the shaper: a NaN target or a cmd_shaper
    left set does not make it an error."""
    r = Run(g)
    r.play(_script(_move(3, 0.6), {150: {"target": math.nan, "cmd_shaper": 7, "stop": True}},
                   {151: {"stop": False}}), 800)
    assert not r.col("cmd_error").any()
    assert r.col("v")[-1] == 0.0 and 0.0 < r.col("x")[-1] < 0.6


def test_cmd_profile_with_jerk_times_from_f_mode_is_an_error(g):
    """jerk_source = 2: the jerk times come from f_mode; cmd_profile or cmd_T_F is refused
    (cmd_error_id 7), cmd_v_max is taken."""
    params = {"jerk_source": 2}
    ref = _bad_run(g, None, params=params)
    r = _bad_run(g, {"cmd_profile": 2}, params=params)
    assert np.array_equal(r.motion(), ref.motion())
    assert (r.col("cmd_error_id")[150:1200] == CODE["JERK_WITH_F_MODE"]).all()
    r = Run(g, params)
    r.play(_move(3, 1.0, cmd_v_max=0.3), 5000)
    assert not r.col("cmd_error").any()
    assert 0.3 * (1 - 1e-3) <= r.col("v").max() <= 0.3 * (1 + 1e-12)
    assert r.col("x")[-1] == pytest.approx(1.0, abs=1e-12)


def test_a_bad_target_before_step_mode_is_taken_and_changes_nothing(g):
    """Set in Instantiated mode, a NaN target is taken (no error): the parametric move and
    everything after are as without it until an execute uses it."""
    ref = Run(g, {"distance": 0.3})
    ref.play({}, 600)
    r = Run(g, {"distance": 0.3}, before={"target": math.nan})
    r.play({}, 600)
    assert np.array_equal(np.array(r.rows), np.array(ref.rows))
    assert math.isnan(g.get("target"))


# ------------------------------------------------------------------- 3. FMU state


def test_fmu_state_with_per_command_values_replays_bit_for_bit(inst):
    """Saved in the middle of a move with its own limits, jerk times and shaper (the inputs
    already set back to 0: the latched values are in the state), then a mid-move command
    with other values and a stop: restored in the same instance, and deserialised into
    another one with other parameters, the run is the same to the bit."""
    pre = _script(_move(2, 0.8, cmd_v_max=0.5, cmd_a_max=6.0, cmd_d_max=4.0, cmd_profile=3,
                        cmd_T_F=[0.02, 0.03, 0.01, 0.04], cmd_shaper=1))
    # (cmd_shaper = 1 again: 0 would ask for the parameter's shaper, none, while moving)
    post = _script(_move(100, -0.3, cmd_v_max=0.7, cmd_T_F=[0.0, 0.0, 0.015, 0.0],
                         cmd_shaper=1),
                   {500: {"stop": True, "cmd_d_max": 3.0}}, {501: {"stop": False}})
    for v, g in inst.items():
        r = Run(g)
        r.play(pre, 300)
        saved = g.time
        state = g.get_state()
        data = g.serialize_state(state)
        r.rows = []
        r.play(post, 1500)
        first = np.array(r.rows)
        assert not first[:, 6].any(), "every command accepted"
        # moving down, the stop decelerates (a > 0) at its own 3 m/s2
        assert 3.0 * (1 - 1e-2) <= first[500:, 2].max() <= 3.0 * (1 + 1e-12)
        g.set_state(state, saved)
        r.rows = []
        r.play(post, 1500)
        assert np.array_equal(np.array(r.rows), first), f"FMI {v}: restored"
        g.free_state(state)
        # another instance, other parameters: the state holds everything
        with GeneratorFMU(g.path) as other:
            o = Run(other, {"profile": 1, "v_max": 2.0, "a_max": 1.0, "d_max": 1.0,
                            "distance": -0.2})
            s2 = other.deserialize_state(data)
            other.set_state(s2, saved)
            other.free_state(s2)
            o.rows = []
            o.play(post, 1500)
            assert np.array_equal(np.array(o.rows), first), f"FMI {v}: deserialised"


# ------------------------------------------------- 4. the inputs left alone change nothing


SEQUENCE = _script(_move(5, 0.7), _move(300, -0.2), {700: {"stop": True}},
                   {701: {"stop": False}}, _move(900, 0.4))


def test_cmd_inputs_at_zero_or_never_latched_change_nothing(g):
    """A commanded sequence (executes mid-move, a stop): the cmd_* inputs never set, set to
    0 at every step, or set to other values between the edges and back to 0 before each
    one (no edge latches them) give the same outputs, bit for bit."""
    base = Run(g)
    base.play(SEQUENCE, 1800)
    zero = Run(g)
    for k in range(1800):
        zero.step({**CMD_ZERO, **SEQUENCE.get(k, {})})
    assert np.array_equal(np.array(zero.rows), np.array(base.rows))
    busy = Run(g)
    edges = {k for k, d in SEQUENCE.items() if d.get("execute") or d.get("stop")}
    for k in range(1800):
        sets = dict(SEQUENCE.get(k, {}))
        if k + 1 in edges or k in edges:
            sets = {**CMD_ZERO, **sets}
        elif k % 7 == 0:
            sets = {"cmd_v_max": 0.1, "cmd_a_max": -3.0, "cmd_profile": 1, "cmd_shaper": 4,
                    "cmd_T_F": [0.2, 0.0, math.nan, 0.0], **sets}
        busy.step(sets)
    assert np.array_equal(np.array(busy.rows), np.array(base.rows))


def test_an_int64_beyond_32_bits_is_taken_and_refused_at_the_edge(inst):
    """FMI 3 sets an Enumeration as Int64: 2^40 for cmd_profile is kept (saturated to the
    32-bit range, no error at set) and the execute that would use it is refused (code 5)."""
    g = inst[3]
    r = Run(g)
    vr = g.variable("cmd_profile").valueReference
    g._call(g.fmu.setInt64, [vr], [2**40])
    assert g._call(g.fmu.getInt64, [vr], 1)[0] == 2**31 - 1
    r.play(_move(2, 0.5), 10)
    assert r.col("cmd_error_id")[-1] == CODE["PROFILE"] and r.col("v")[-1] == 0.0


# ------------------------------------------- 5. random commands with their own values


@st.composite
def _commands(draw: st.DrawFn) -> list[tuple[int, dict[str, Any]]]:
    """1..5 executes at random steps (mid-move, at rest), each with random valid values."""
    n = draw(st.integers(1, 5))
    ks = sorted(draw(st.lists(st.integers(3, 1500), min_size=n, max_size=n, unique=True)))
    out = []
    for k in ks:
        # (on a grid of 1 um: a distance of 1e-308 m is a planner's refusal of its own,
        # whatever the command's values)
        c: dict[str, Any] = {"target": draw(st.integers(-10**6, 10**6)) * 1e-6}
        c["cmd_v_max"] = draw(st.sampled_from([0.0, 0.15, 0.4, 1.7]))
        c["cmd_a_max"] = draw(st.sampled_from([0.0, 3.0, 25.0]))
        c["cmd_d_max"] = draw(st.sampled_from([0.0, 2.0, 18.0]))
        c["cmd_profile"] = draw(st.integers(0, 3))
        c["cmd_T_F"] = [draw(st.sampled_from([0.0, 0.005, 0.021, 0.07])) for _ in range(4)]
        out.append((k, c))
    return out


@settings(max_examples=int(os.environ.get("DJL_CMD_EXAMPLES", "12")), deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(cmds=_commands())
def test_random_commands_land_on_their_target_within_their_limits(g, cmds):
    """Every command accepted; the axis ends at rest exactly on the last target; |v| and
    |a| never pass the largest limits in force; after the last command, once the speed is
    within its cmd_v_max and not rising (at once, after the acceleration in progress has
    ramped down, or after the stop a slower command starts with) it stays within it."""
    r = Run(g)
    script = _script(*[_move(k, c["target"], **{n: v for n, v in c.items() if n != "target"})
                       for k, c in cmds])
    k_last, last = cmds[-1]
    r.play(script, k_last + 2)
    for _ in range(40):
        if r.col("done")[-1] and r.col("v")[-1] == 0.0 and len(r.rows) > k_last + 2:
            break
        r.play({}, 500)
    v, a, x = r.col("v"), r.col("a"), r.col("x")
    assert not r.col("cmd_error").any(), [str(m) for m in g.log if "refused" in str(m)]
    assert x[-1] == pytest.approx(last["target"], abs=1e-12) and v[-1] == 0.0
    vmax = max([AXIS["v_max"]] + [c["cmd_v_max"] for _, c in cmds])
    amax = max([AXIS["a_max"], AXIS["d_max"]] + [max(c["cmd_a_max"], c["cmd_d_max"])
                                                for _, c in cmds])
    assert np.abs(v).max() <= vmax * (1 + 1e-9) and np.abs(a).max() <= amax * (1 + 1e-9)
    # within its cmd_v_max once there and no longer rising (the acceleration the command
    # found ramps down as started: the speed may pass a cmd_v_max it was just below)
    v_cmd = last["cmd_v_max"] or AXIS["v_max"]
    after, rising = np.abs(v[k_last:]), (a * v)[k_last:] > 0.0
    within = np.nonzero((after <= v_cmd) & ~rising)[0]
    assert within.size and after[within[0]:].max() <= v_cmd * (1 + 1e-9)
