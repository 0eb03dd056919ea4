"""The commanded-FMU examples (issue #12) run, fast and headless; the fmpy snippets of the docs.

The commanded snippet is docs/fmu.md's ("Commanded while it runs"), the parametric one the
README's ("From fmpy, in ten lines"); both run here as they are written there.
"""

from __future__ import annotations

import os
import re
import runpy
import time
from pathlib import Path

import numpy as np
import pytest

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _in(tmp_path: Path, fn):
    cwd = os.getcwd()
    os.chdir(tmp_path)
    try:
        return fn()
    finally:
        os.chdir(cwd)


def test_commanded_targets_example(tmp_path, capsys, fmus):
    from harness.fmu.build import default_fmu

    default_fmu(2)  # the example's FMU, built (once) before the clock starts
    t0 = time.perf_counter()
    mod = _in(tmp_path, lambda: runpy.run_path(str(EXAMPLES / "commanded_targets.py"),
                                               run_name="__main__"))
    assert time.perf_counter() - t0 < 10.0
    out = capsys.readouterr().out
    assert "moves ended (busy falls)" in out
    assert (tmp_path / "djl-fmu-out" / "commanded_targets.png").stat().st_size > 10_000

    # what it shows: the same simulation, on the FMI 2 and FMI 3 FMUs alike
    t, v = mod["simulate"](fmu=fmus[2])
    t3, v3 = mod["simulate"](fmu=fmus[3])
    for name in ("x", "v", "a", "j", "busy", "stage"):
        np.testing.assert_array_equal(v[name], v3[name])
    Te, P = mod["Te"], mod["PARAMS"]
    assert np.allclose(np.diff(t), Te, rtol=1e-9)
    busy = v["busy"].astype(bool)
    ends = np.flatnonzero(busy[:-1] & ~busy[1:]) + 1
    assert len(ends) == 3  # the 0.3 m order replaced mid-move, the stopped move, the last one

    def k(ts: float) -> int:
        return int(round(ts / Te))

    # each command's edge acts from the next sample: busy turns true one sample later
    for t_cmd in (0.05, 0.40, 1.20, 2.00):
        assert busy[k(t_cmd) + 1]
    assert not busy[k(0.05)] and not busy[k(1.20)] and not busy[k(2.00)]
    # the moves end on their targets at rest: 0.1 m (the second order), then -0.05 m
    for kk, target in ((ends[0], 0.10), (ends[2], -0.05)):
        assert abs(v["x"][kk] - target) <= 1e-9 * 0.45
        assert v["v"][kk] == 0.0 and v["a"][kk] == 0.0
    # the stop: at rest short of the 0.45 m target, further than where the stop came
    x_stop = v["x"][ends[1]]
    assert v["x"][k(1.45)] < x_stop < 0.45 and v["v"][ends[1]] == 0.0
    assert np.all(v["x"][ends[1]:k(2.0) + 1] == x_stop)
    # limits
    assert np.max(np.abs(v["v"])) <= P["v_max"] * (1 + 1e-12)
    assert np.max(np.abs(v["a"])) <= max(P["a_max"], P["d_max"]) * (1 + 1e-12)
    # stage: 0 at rest, 1..4 while moving
    assert np.all(v["stage"][~busy] == 0) and set(np.unique(v["stage"])) <= {0, 1, 2, 3, 4}


def test_online_fmode_example(tmp_path, capsys):
    from harness.fmu.build import default_fmu

    default_fmu(2)
    t0 = time.perf_counter()
    _in(tmp_path, lambda: runpy.run_path(str(EXAMPLES / "online_fmode.py"), run_name="__main__"))
    assert time.perf_counter() - t0 < 10.0
    out = capsys.readouterr().out
    assert "DJL-online" in out and "round(1/(f Te))" in out
    assert (tmp_path / "djl-fmu-out" / "online_fmode.png").stat().st_size > 10_000


ROOT = EXAMPLES.parent


def _python_block(doc: str, after: str) -> str:
    """The first ```python block of ``doc`` (a path under the repository) after ``after``."""
    text = (ROOT / doc).read_text()
    m = re.search(r"```python\n(.*?)```", text[text.index(after):], re.S)
    assert m, f"{doc}: no python block after {after!r}"
    return m.group(1)


@pytest.mark.parametrize("v", [2, 3], ids=["fmi2", "fmi3"])
def test_readme_fmpy_snippet(tmp_path, fmus, v, capsys):
    """The code of docs/fmu.md, "Commanded while it runs" (commands as an fmpy input table; in
    the README until issue 36), run as written there, on both FMUs."""
    import shutil

    shutil.copy(fmus[v], tmp_path / "JerkLimitedTrajectory.fmu")
    code = _python_block("docs/fmu.md", "From fmpy, the commands as a signal table")
    assert "input=signals" in code and 'print(res["time"][ends], res["x"][ends])' in code

    def snippet():
        namespace: dict = {}
        exec(compile(code, "docs/fmu.md (commanded fmpy snippet)", "exec"), namespace)
        return namespace["res"], namespace["ends"]

    res, ends = _in(tmp_path, snippet)
    out = capsys.readouterr().out
    # runs without warnings but fmpy's, one for each input the table leaves out: the
    # per-command values, buffer_mode and min_duration (issue 34), at their start values (the
    # parameters', aborting, none); in FMI 2 each element of an array (FMI 3: the array) and
    # the Integer aliases of the Enumeration inputs
    from harness.fmu import spec

    warned = [ln for ln in out.splitlines() if "Warning" in ln or "missing input" in ln]
    names = [re.fullmatch(r'Warning: missing input for variable "([^"]+)"', ln) for ln in warned]
    assert warned and all(names), out
    left_out = [w for w in spec.VARIABLES if w.causality == "input"
                and w.name not in ("target", "execute", "stop", "f_mode")]
    expected = {w.name if w.size == 1 or v == 3 else f"{w.name}[{i}]" for w in left_out
                for i in range(1, w.size + 1)}
    if v == 2:
        expected |= {w.name + spec.FMI2_ENUM_ALIAS_SUFFIX for w in left_out
                     if w.type == "Enumeration"}
    assert sorted(m.group(1) for m in names) == sorted(expected), out
    # what the snippet prints (a command read at t acts from the next sample, t + 1 ms)
    np.testing.assert_allclose(res["time"][ends], [1.062, 1.586], rtol=0, atol=1e-9)
    assert res["x"][ends[1]] == pytest.approx(0.197214, abs=1e-6)
    t, x, vel = res["time"], res["x"], res["v"]
    assert np.allclose(np.diff(t), 1e-3, rtol=1e-9)
    # the first execute, read at the doStep from 0.1 s: the outputs at 0.1 s are those of
    # the axis at rest, the move starts at the next sample (busy; its jerk ramp from there)
    k01 = int(np.argmin(np.abs(t - 0.1)))
    assert not res["busy"][k01] and res["busy"][k01 + 1]
    assert res["a"][k01] == 0.0 and res["a"][k01 + 1] == 0.0 and res["a"][k01 + 2] > 0.0
    assert abs(x[ends[0]] - 0.1) <= 1e-9 * 0.3 and vel[ends[0]] == 0.0
    # the first order (0.3 m) was replaced before it was reached
    assert x[int(np.argmin(np.abs(t - 0.5)))] < 0.3 and x.max() < 0.3
    # the stop: at rest, short of 0.4 m, past where it was at the stop, until the end
    k14 = int(np.argmin(np.abs(t - 1.4)))
    assert x[k14] < x[ends[1]] < 0.4 and np.all(x[ends[1]:] == x[ends[1]])
    assert np.all(vel[ends[1]:] == 0.0) and not res["busy"][-1]


@pytest.mark.parametrize("v", [2, 3], ids=["fmi2", "fmi3"])
def test_readme_parametric_fmpy_example(tmp_path, fmus, v, capsys):
    """The README's "From fmpy, in ten lines", run as written there, on both FMUs: the DJL
    move ends on 0.4 m, its motion at 1.13 s, as its comment says."""
    import shutil

    shutil.copy(fmus[v], tmp_path / "JerkLimitedTrajectory.fmu")
    code = _python_block("README.md", "## From fmpy, in ten lines")
    assert len(code.strip().splitlines()) <= 12
    namespace: dict = {}
    _in(tmp_path, lambda: exec(compile(code, "README.md (fmpy example)", "exec"), namespace))
    res = namespace["res"]
    assert res["x"][-1] == pytest.approx(0.4, abs=1e-12)
    assert res["time"][res["done"].argmax()] == pytest.approx(1.13, abs=1e-9)
    assert np.all(res["done"][res["done"].argmax():]) and res["v"][-1] == 0.0
    printed = capsys.readouterr().out.split()
    assert float(printed[-2]) == pytest.approx(0.4) and float(printed[-1]) == pytest.approx(1.13)


def test_motion_program_example(tmp_path, capsys, fmus):
    """Issue 34's example: a queued program (blends at the lower v_max, a buffered move
    after) and two instances ending together through time_to_rest -> min_duration."""
    mod = _in(tmp_path, lambda: runpy.run_path(str(EXAMPLES / "motion_program.py"),
                                               run_name="__main__"))
    out = capsys.readouterr().out
    assert "passes 0.2 m at 0.500 m/s" in out and "passes 0.5 m at 0.500 m/s" in out
    assert (tmp_path / "djl-fmu-out" / "motion_program.png").stat().st_size > 10_000
    assert (tmp_path / "djl-fmu-out" / "axis_b_input.csv").read_text().startswith("time,")
    for v in (2, 3):
        p = mod["run_program"](fmu=fmus[v])
        assert p["x"][-1] == pytest.approx(0.1, abs=1e-12) and p["done"][-1] == 1
        assert p["queue_length"].max() == 3
        a, b, wired = mod["synchronised"](fmu=fmus[v])
        ends = [int(np.flatnonzero(np.abs(r["v"]) > 0)[-1]) + 1 for r in (a, b)]
        assert 0 <= ends[1] - ends[0] <= 1 and wired > 0.5
