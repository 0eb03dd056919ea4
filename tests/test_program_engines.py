"""The compiled engine takes the same commands as the FMU (issue 34, item 6).

:func:`harness.simulation.program.run_program` plays a program of commands with the FMU's
model compiled into :mod:`harness._engine` (one call) or with the FMU through fmpy (one
FMI call per step).  Every output after every step must be the same, bit for bit, in FMI 2
and FMI 3: aborting, buffered and blending commands, per-command values, min_duration, a
stop, bad commands (cmd_error), jerk times from f_mode, a shaper; and random programs
(hypothesis, DJL_PROGRAM_EXAMPLES examples, 6 by default).  Bad programs are refused by
name.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from harness.simulation.program import ProgramError, run_program

TE = 1e-3
AXIS = {"profile": 3, "Te": TE, "distance": 0.0, "v_max": 1.0, "a_max": 10.0, "d_max": 10.0,
        "T_F1": 0.04, "T_F2": 0.04, "T_F3": 0.03, "T_F4": 0.025}


def edge(t: float, **values: Any) -> list[tuple[float, dict[str, Any]]]:
    """An execute edge at t with values, execute back to False a step later."""
    return [(t, {**values, "execute": True}), (t + TE, {"execute": False})]


PROGRAMS: dict[str, tuple[dict[str, Any], list[tuple[float, dict[str, Any]]], float]] = {
    "buffered+blended": (AXIS, [*edge(0.002, target=0.3, cmd_v_max=0.7),
                                *edge(0.004, target=0.6, buffer_mode=2),
                                *edge(0.006, target=0.2, buffer_mode=1, cmd_a_max=4.0),
                                *edge(0.008, target=0.25, buffer_mode=1, min_duration=0.9,
                                      cmd_v_max=0.0, cmd_a_max=0.0)], 4.0),
    "abort+stop+errors": (AXIS, [*edge(0.002, target=0.5),
                                 *edge(0.010, target=0.9, buffer_mode=1),
                                 *edge(0.020, target=math.nan, buffer_mode=0),
                                 *edge(0.030, target=0.1, buffer_mode=7),
                                 *edge(0.100, target=-0.2, buffer_mode=0, cmd_profile=2,
                                       cmd_T_F=[0.02, 0, 0, 0]),
                                 (0.300, {"stop": True}), (0.301, {"stop": False}),
                                 *edge(0.800, target=0.1, min_duration=-1.0),
                                 *edge(0.900, target=0.1, min_duration=0.0)], 2.5),
    "f_mode+shaper": ({**AXIS, "jerk_source": 3, "shaper": 1, "f_shaper": 9.0},
                      [(0.0, {"f_mode": 12.0}), *edge(0.002, target=0.4),
                       (0.100, {"f_mode": 9.0}), *edge(0.150, target=0.7, buffer_mode=2),
                       (0.400, {"f_mode": 15.0})], 2.5),
}


@pytest.mark.parametrize("name", list(PROGRAMS))
def test_compiled_engine_and_fmu_give_the_same_outputs(name: str, fmus: dict[int, Path]):
    params, program, t_end = PROGRAMS[name]
    c = run_program(params, program, t_end)
    assert c.engine == "compiled"
    for v in (2, 3):
        f = run_program(params, program, t_end, engine="fmu", fmu=fmus[v])
        assert set(f.outputs) == set(c.outputs)
        for n in c.outputs:
            assert np.array_equal(c[n], f[n]), (name, v, n)
        np.testing.assert_array_equal(c.t, f.t)
    # what the program did (not a tautology of the comparison above)
    if name == "buffered+blended":
        assert c["queue_length"].max() == 3 and not c["cmd_error"].any()
        assert c["x"][-1] == pytest.approx(0.25, abs=1e-12) and c["done"][-1] == 1
    elif name == "abort+stop+errors":
        assert {int(x) for x in c["cmd_error_id"]} >= {0, 1, 14, 15}
        assert c["command_aborted"].any()


EXAMPLES = int(os.environ.get("DJL_PROGRAM_EXAMPLES", "6"))


@st.composite
def programs(draw: st.DrawFn) -> list[tuple[float, dict[str, Any]]]:
    out: list[tuple[float, dict[str, Any]]] = []
    t = 0.002
    for _ in range(draw(st.integers(1, 6))):
        kind = draw(st.sampled_from(["exec", "exec", "exec", "stop"]))
        if kind == "stop":
            out += [(t, {"stop": True}), (t + TE, {"stop": False})]
        else:
            out += edge(t, target=draw(st.floats(-0.8, 0.8)),
                        buffer_mode=draw(st.integers(0, 2)),
                        cmd_v_max=draw(st.sampled_from([0.0, 0.3, 0.8])),
                        min_duration=draw(st.sampled_from([0.0, 0.0, 0.5])))
        t += TE * draw(st.integers(2, 400))
    return out


@settings(max_examples=EXAMPLES, deadline=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(prog=programs())
def test_random_programs_give_the_same_outputs(prog, fmus):
    c = run_program(AXIS, prog, 3.0)
    f = run_program(AXIS, prog, 3.0, engine="fmu", fmu=fmus[3])
    for n in c.outputs:
        assert np.array_equal(c[n], f[n]), n


@pytest.mark.parametrize("program,fragment", [
    ([(0.0015, {"execute": True})], "not a communication point"),
    ([(0.01, {"execute": True}), (0.005, {"execute": False})], "comes before"),
    ([(0.0, {"speed": 1.0})], "not inputs of the FMU"),
])
def test_bad_programs_are_refused_by_name(program, fragment):
    with pytest.raises(ProgramError, match=fragment):
        run_program(AXIS, program, 0.1)


def test_a_parameter_the_fmu_refuses_is_refused_by_the_engine():
    with pytest.raises(ValueError, match="v_max"):
        run_program({**AXIS, "v_max": -1.0}, [], 0.1)
