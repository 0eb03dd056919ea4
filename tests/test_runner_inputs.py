"""GeneratorFMU.set_inputs: the commanded inputs (issue #12) from Python, strict types."""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.fmu.runner import FMUError, GeneratorFMU, LogRecord

REST = {"profile": 3, "distance": 0.0, "v_max": 0.5, "a_max": 4.0, "d_max": 4.0,
        "T_F1": 0.03, "T_F2": 0.04, "T_F3": 0.05, "T_F4": 0.06}
"""No parametric move: the axis waits at x0 = 0 for a command."""


@pytest.fixture
def gen(fmu):
    with GeneratorFMU(fmu, params=REST) as g:
        g.initialize()
        yield g


def _run_until_rest(g: GeneratorFMU, t_max: float = 3.0) -> None:
    Te = float(g.get("Te"))
    for _ in range(int(round(t_max / Te))):
        g.do_step(Te)
        if not g.get("busy"):
            return
    raise AssertionError("the move did not end")


def test_an_execute_edge_moves_to_the_target_and_a_second_needs_a_false_in_between(gen):
    gen.set_inputs(target=0.2, execute=True)
    gen.do_step(1e-3)
    assert gen.get("busy")
    _run_until_rest(gen)
    assert gen.get("x") == pytest.approx(0.2, rel=1e-9, abs=1e-12)
    assert gen.get("v") == 0.0 and gen.get("a") == 0.0
    # execute still true: setting it again is no edge, nothing moves
    gen.set_inputs(target=0.35, execute=True)
    for _ in range(50):
        gen.do_step(1e-3)
    assert not gen.get("busy") and gen.get("x") == pytest.approx(0.2, rel=1e-9)
    # False, then True: a new command
    gen.set_inputs(execute=False)
    gen.do_step(1e-3)
    gen.set_inputs(execute=True)
    gen.do_step(1e-3)
    _run_until_rest(gen)
    assert gen.get("x") == pytest.approx(0.35, rel=1e-9)


def test_a_stop_edge_brings_the_axis_to_rest_short_of_the_target(gen):
    gen.set_inputs(target=0.4, execute=True)
    for _ in range(300):
        gen.do_step(1e-3)
    x_then, v_then = gen.get("x"), gen.get("v")
    assert v_then > 0.1
    gen.set_inputs(stop=True)
    _run_until_rest(gen)
    x = gen.get("x")
    assert x_then < x < 0.4 and gen.get("v") == 0.0 and gen.get("a") == 0.0
    for _ in range(100):  # and stays there
        gen.do_step(1e-3)
    assert gen.get("x") == x


@pytest.mark.parametrize("kw", [
    {"execute": 1}, {"execute": 1.0}, {"stop": "yes"}, {"stop": 0},
    {"target": True}, {"target": "0.1"}, {"f_mode": False}, {"f_mode": [5.0]},
])
def test_wrong_types_are_refused_naming_the_input_and_nothing_is_set(gen, kw):
    name = next(iter(kw))
    good = {"f_mode": 7.5} if name == "target" else {"target": 0.123}
    with pytest.raises(TypeError, match=name):
        gen.set_inputs(**good, **kw)
    # the good input of the same call was not set either
    assert gen.get("target") == 0.0 and gen.get("f_mode") == 10.0


def test_numpy_scalars_and_ints_are_taken(gen):
    gen.set_inputs(target=np.float64(0.05), f_mode=np.int64(8), execute=np.bool_(True))
    assert gen.get("target") == 0.05 and gen.get("f_mode") == 8.0 and gen.get("execute")
    gen.set_inputs(target=1)
    assert gen.get("target") == 1.0


@pytest.mark.parametrize(("name", "value"), [
    ("f_mode", math.nan), ("f_mode", math.inf), ("f_mode", 0.0), ("f_mode", -3.0),
])
def test_values_the_fmu_refuses_raise_fmu_error_naming_the_input(gen, name, value):
    before = gen.get(name)
    with pytest.raises(FMUError) as err:
        gen.set_inputs(**{name: value})
    msg = str(err.value)
    assert f"setting {name} = {value!r}" in msg
    assert name in err.value.log[-1].message  # the FMU's own message names it too
    assert err.value.variable == name
    assert gen.get(name) == before  # unchanged
    gen.set_inputs(target=0.1, execute=True)  # the instance is still usable
    _run_until_rest(gen)
    assert gen.get("x") == pytest.approx(0.1, rel=1e-9)


@pytest.mark.parametrize("value", [math.nan, math.inf, -math.inf, 2e300])
def test_a_bad_target_is_taken_and_its_execute_refused_with_cmd_error(gen, value):
    """Issue 34: an importer must not stop at a bad target.  The value is taken when set;
    the execute edge that would use it is refused by the doStep (status OK) with
    cmd_error = true, cmd_error_id = 1 (spec.CMD_ERRORS), and the axis stays where it was."""
    gen.set_inputs(target=value, execute=True)
    got = gen.get("target")
    assert got == value or (math.isnan(got) and math.isnan(value))
    x = gen.get("x")
    gen.do_step(1e-3)
    assert gen.get("cmd_error") and gen.get("cmd_error_id") == 1
    assert gen.get("x") == x and gen.get("v") == 0.0
    gen.set_inputs(target=0.1, execute=False)
    gen.do_step(1e-3)
    gen.set_inputs(execute=True)  # a valid command clears the error
    _run_until_rest(gen)
    assert not gen.get("cmd_error") and gen.get("cmd_error_id") == 0
    assert gen.get("x") == pytest.approx(0.1, rel=1e-9)


def test_refusal_stops_at_the_refused_input_in_the_documented_order(gen):
    # order: target, f_mode, stop, execute; target is set before f_mode is refused
    with pytest.raises(FMUError, match="f_mode"):
        gen.set_inputs(target=0.2, f_mode=-1.0, execute=True)
    assert gen.get("target") == 0.2 and not gen.get("execute")


def test_fmu_error_without_a_variable_keeps_its_message():
    log = [LogRecord(3, "logStatusError", "bad thing")]
    e = FMUError("fmi2DoStep", 3, log)
    assert str(e) == "fmi2DoStep failed with status 3: bad thing" and e.variable is None
