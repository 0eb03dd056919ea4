"""The fast engine (harness._engine + harness.simulation.fast_axis) against the FMU engine and
the Python plant.

The fast engine must be the same computation as the reference one, not an
approximation of it: the generator outputs equal the FMU's, its refusals carry
the FMU's messages, the Z synchronisation and the plant equal their Python
counterparts, and every move of both embedded sweeps gives the same jerk times
and metrics through both engines (1e-9 relative).
"""

from __future__ import annotations

import dataclasses
import math
import os
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_generator_invariants import multi_moves, single_moves

from harness import _engine
from harness._resources import fmu_src_dir
from harness.fmu.codegen import CORE_SOURCES, FMU_SOURCES
from harness.fmu.runner import FMUError, GeneratorFMU
from harness.plant import step_mode_jerk
from harness.scenario import load_scenario
from harness.simulation.fast_axis import FastAxis, PlanError
from harness.simulation.fmu_axis import FMUAxis
from harness.simulation.master import cosimulate, map_error_residuals
from harness.simulation.session import Session
from harness.tuning.tune import tune_profile

# the core and the FMU model (run_program)
CORE = [str(fmu_src_dir() / f) for f in (*CORE_SOURCES, *FMU_SOURCES)]

REAL = ("x", "v", "a", "j", "x_AL", "v_AL", "a_AL")


def _n(default: int) -> int:
    return default * 10 if os.environ.get("HYPOTHESIS_PROFILE") == "thorough" else default


def _fmu_samples(fmu, p, count, step=1, start_time=0.0):
    with GeneratorFMU(fmu, params=p, start_time=start_time) as g:
        g.initialize()
        _, vals = g.record(count - 1, p.get("Te", 1e-3) * step, REAL)
        calc = {k: g.get(k) for k in ("motion_time", "v_reached", "a_reached", "d_reached")}
        calc["N_F"] = tuple(int(g.get(f"N_F{i}")) for i in range(1, 5))
    return np.vstack([vals[k] for k in REAL]), calc


def _count(p, step=1):
    ax = FastAxis()
    T = ax.plan(p)
    n = int(math.ceil((T + p.get("t_start", 0.0)) / p.get("Te", 1e-3))) + 5
    return max(2, min(n // step + 2, 4000))


@settings(max_examples=_n(40), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(single_moves(), st.sampled_from([1, 3]))
def test_samples_equal_the_fmu_outputs(fmu2, p, step):
    """Same planner, same evaluator, same time grid: the outputs are the FMU's, bit for bit."""
    count = _count(p, step)
    ref, calc = _fmu_samples(fmu2, p, count, step)
    ax = FastAxis()
    T = ax.plan(p)
    got = ax.samples(0, step, count)
    assert np.array_equal(got, ref)
    assert T == calc["motion_time"]
    assert ax.N_F() == calc["N_F"]
    for k in ("v_reached", "a_reached", "d_reached"):
        assert ax.get(k) == calc[k]


@settings(max_examples=_n(10), deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(multi_moves())
def test_multi_segment_samples_equal_the_fmu_outputs(fmu3, p):
    count = _count(p)
    ref, calc = _fmu_samples(fmu3, p, count)
    ax = FastAxis()
    assert ax.plan(p) == calc["motion_time"]
    assert np.array_equal(ax.samples(0, 1, count), ref)


def test_start_time_and_off_grid_t_start_follow_the_fmu(fmu2):
    p = {"profile": 2, "distance": 0.2, "T_F1": 0.03, "t_start": 0.12345}
    ref, _ = _fmu_samples(fmu2, p, 600, start_time=0.01)
    ax = FastAxis()
    ax.plan(p, start_time=0.01)
    assert ax.planned.shifted  # 0.12345 is not on the grid 0.01 + k ms: next sample
    assert ax.motion_start() == pytest.approx(0.124)
    assert np.array_equal(ax.samples(0, 1, 600), ref)


@pytest.mark.parametrize("params, name", [
    ({"Te": -1.0}, "Te"), ({"v_max": 0.0}, "v_max"), ({"T_F3": float("nan")}, "T_F3"),
    ({"profile": 7}, "profile"), ({"n_segments": 40}, "n_segments"),
    ({"distance": 1e-3, "v0": 5.0, "v_e": 5.0, "v_max": 5.0}, None),
])
def test_refusals_carry_the_fmus_message(fmu2, params, name):
    with pytest.raises(FMUError) as ref:
        with GeneratorFMU(fmu2, params=params) as g:
            g.initialize()
    with pytest.raises(PlanError) as got:
        FastAxis(name="X").plan(params)
    assert isinstance(got.value, ValueError)
    msg = str(got.value)
    assert msg.startswith("X: ")
    # the FMU logs "<function>: <status>: <message>"; the engine raises the message itself
    assert msg[3:] in str(ref.value)
    if name is not None:
        assert name in msg


@pytest.mark.parametrize("params, exc, text", [
    ({"bogus": 1.0}, KeyError, "bogus"),
    ({"v_max": "fast"}, TypeError, "v_max"),
    ({"profile": 2.5}, ValueError, "profile"),
    ({"profile": True}, TypeError, "profile"),
    ({"seg_distance": [0.1] * 33}, ValueError, "seg_distance"),
    ({"seg_distance": 3}, TypeError, "seg_distance"),
    ({"profile": 10**30}, ValueError, "profile"),
])
def test_bad_parameter_values_are_named(params, exc, text):
    with pytest.raises(exc, match=text):
        _engine.plan(params)
    assert FastAxis().plan({"distance": 0.1}) > 0  # nothing else broke


def test_sample_into_checks_its_buffer():
    pl = _engine.plan({"distance": 0.1})
    with pytest.raises(ValueError, match="float64"):
        pl.sample_into(np.empty((7, 5)), 0, 1, 6)
    with pytest.raises(ValueError, match="float64"):
        pl.sample_into(np.empty((7, 5), dtype=np.float32), 0, 1, 5)
    with pytest.raises(BufferError):
        pl.sample_into(b"x" * 280, 0, 1, 5)
    with pytest.raises(ValueError, match="step"):
        pl.sample_into(np.empty((7, 5)), 0, 0, 5)


@pytest.mark.parametrize("dz, v_cap, target", [(0.45, 2.0, 1.058), (0.1, 2.0, 0.5),
                                                (0.5, 0.3, 1.0), (0.3, 2.0, 0.2)])
def test_z_synchronisation_equals_the_python_bisection(fmu2, dz, v_cap, target):
    base = {"profile": 2, "distance": dz, "a_max": 8.0, "d_max": 8.0, "T_F1": 0.04,
            "T_F2": 0.04, "T_F3": 0.04, "T_F4": 0.04, "short_stage": 2}
    with FMUAxis(fmu2) as ax:
        ref = ax.sync_velocity(base, target, v_cap)
    got = FastAxis().sync_velocity(base, target, v_cap)
    assert got == ref


def test_step_modes_equals_the_python_step():
    rng = np.random.default_rng(3)
    n, h = 300, 1e-3
    a = rng.normal(size=n + 1)
    j = rng.normal(size=n + 1) * 100
    f = np.vstack([6 + rng.random(n), 20 + rng.random(n)])
    zeta, gain = np.array([0.03, 0.0]), np.array([1.0, 0.4])
    state = np.array([1e-4, -2e-3, 0.0, 1e-3])
    eps, states = np.empty(n + 1), np.empty((n + 1, 4))
    _engine.step_modes(a, j, h, f, zeta, gain, n, state.copy(), eps, states)
    st_ = [1e-4, -2e-3, 0.0, 1e-3]
    for k in range(n):
        for i in range(2):
            st_[2 * i], st_[2 * i + 1] = step_mode_jerk(st_[2 * i], st_[2 * i + 1],
                                                        2 * math.pi * f[i, k], zeta[i], gain[i],
                                                        h, a[k], j[k])
        assert states[k + 1].tolist() == st_
        assert eps[k + 1] == st_[0] + st_[2]


@pytest.mark.parametrize("bad, text", [("f", "frequency"), ("zeta", "damping"),
                                       ("short", "at least")])
def test_step_modes_refuses_bad_inputs(bad, text):
    n = 10
    a, j = np.zeros(n + 1), np.zeros(n + 1)
    f, zeta = np.full((1, n), 5.0), np.array([0.02])
    if bad == "f":
        f[0, 4] = -1.0
    elif bad == "zeta":
        zeta[0] = 1.0
    else:
        a = np.zeros(3)
    with pytest.raises(ValueError, match=text):
        _engine.step_modes(a, j, 1e-3, f, zeta, np.ones(1), n, np.zeros(2), np.empty(n + 1),
                           np.empty((n + 1, 2)))


def test_plan_residuals_equal_stepping_the_samples():
    """Plan.residuals (one pass in C, no samples kept) against step_modes over sampled a, j
    and the free amplitude of harness.plant, for two modes and three factors."""
    from harness.plant import Mode, free_amplitude

    pl = _engine.plan({"profile": 3, "distance": 0.3, "v_max": 0.6, "a_max": 3.0,
                       "d_max": 3.0, "T_F1": 0.11, "T_F2": 0.09, "T_F3": 0.12, "T_F4": 0.1,
                       "t_start": 0.05})
    m, h = 2, 2e-3
    k_end = int(math.ceil((pl.motion_time + 0.05) / h))
    rng = np.random.default_rng(5)
    f_mid = np.ascontiguousarray(np.vstack([7 + rng.random(k_end), 18 + rng.random(k_end)]))
    zeta, gain, f_end = np.array([0.03, 0.01]), np.array([1.0, 0.3]), np.array([7.2, 18.4])
    factors = np.array([0.9, 1.0, 1.07])
    got = np.empty(3)
    pl.residuals(m, k_end, h, f_mid, zeta, gain, f_end, factors, got)
    X = np.empty((7, k_end + 1))
    pl.sample_into(X, 0, m, k_end + 1)
    for q, c in enumerate(factors):
        state, eps, states = np.zeros(4), np.empty(k_end + 1), np.empty((k_end + 1, 4))
        _engine.step_modes(X[2].copy(), X[3].copy(), h, f_mid * c, zeta, gain, k_end, state,
                           eps, states)
        ref = sum(free_amplitude(state[2 * i], state[2 * i + 1],
                                 Mode(f_end[i] * c, zeta[i], gain[i])) for i in range(2))
        assert got[q] == pytest.approx(ref, rel=1e-12)
    with pytest.raises(ValueError, match="damping"):
        pl.residuals(m, k_end, h, f_mid, np.array([1.0, 0.0]), gain, f_end, factors, got)
    with pytest.raises(ValueError, match="f_mid"):
        pl.residuals(m, k_end + 5, h, f_mid, zeta, gain, f_end, factors, got)


def test_map_error_residuals_equal_runs_on_the_scaled_map():
    sc = load_scenario("X")
    with Session(engine="fast") as s:
        tun = tune_profile(s, sc, "DJL")
        params = s.move_params(sc, "DJL", tun.T_F)
        T = s.axis.plan(params)
        v, _ = s.z_velocity(sc, T)
        zp = s.z_move_params(sc, v)
        s.z_axis.plan(zp)  # the master takes the two axes planned
        errors = [-0.1, 0.0, 0.05]
        got = map_error_residuals(s.axis, s.z_axis, sc.modemap.scheduled(),
                                  [1 + e for e in errors])
        for e, r in zip(errors, got, strict=True):
            scaled = dataclasses.replace(sc, modemap=sc.modemap.scaled(1 + e))
            run = s.run(scaled, "DJL", tun.T_F)
            assert r == pytest.approx(run.free_amplitude, rel=1e-12)
    assert got[1] < got[0]  # the nominal map is the tuned one


@pytest.mark.parametrize("name", ["X", "Y"])
@pytest.mark.parametrize("profile", ["AL", "JL", "DJL"])
def test_scenario_runs_equal_through_both_engines(fmu2, name, profile):
    sc = load_scenario(name)
    with Session(fmu2) as ref, Session(engine="fast") as fast:
        tr, tf = tune_profile(ref, sc, profile), tune_profile(fast, sc, profile)
        assert (tr is None) == (tf is None)
        T_F = tr.T_F if tr else None
        if tr:
            assert tf.T_F == tr.T_F and tf.history == tr.history
        a, b = ref.run(sc, profile, T_F), fast.run(sc, profile, T_F)
    assert a.engine == "fmu" and b.engine == "fast"
    for k in ("t", "x", "v", "a", "j", "z", "v_z", "eps", "f"):
        np.testing.assert_allclose(getattr(b, k), getattr(a, k), rtol=1e-12, atol=1e-15,
                                   err_msg=k)
    assert b.plan_info == a.plan_info
    assert b.free_amplitude == pytest.approx(a.free_amplitude, rel=1e-12)
    assert b.final_state == pytest.approx(a.final_state, rel=1e-12, abs=1e-18)


def test_cosimulate_on_fast_axes_refuses_a_step_off_the_grid():
    ax, az = FastAxis(), FastAxis()
    ax.plan({"distance": 0.1})
    az.plan({"distance": 0.0})
    with pytest.raises(ValueError, match="whole multiple"):
        cosimulate(ax, az, [], 1.0, 1.5e-3)


@pytest.mark.parametrize("api", ["full", "limited"])
def test_engine_source_is_clean_under_strict_c99(tmp_path, api):
    """harness/_engine.c compiles under -std=c99 -Wall -Wextra -Wpedantic -Werror, with the
    full C API and with the limited one of the abi3 wheels (Py_LIMITED_API 3.11: a macro
    outside it, such as PyTuple_GET_ITEM, is then undeclared)."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc not available")
    src = Path(__file__).resolve().parents[1] / "harness" / "_engine.c"
    if not src.is_file():
        pytest.skip("not a source checkout")
    cmd = ["gcc", "-std=c99", "-O2", "-fPIC", "-shared", "-Wall", "-Wextra", "-Wpedantic",
           "-Werror", "-fvisibility=hidden", f"-I{sysconfig.get_paths()['include']}",
           *(["-DPy_LIMITED_API=0x030b0000"] if api == "limited" else []),
           f"-I{fmu_src_dir()}", str(src), *CORE, "-o",
           str(tmp_path / "_engine.so"), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    syms = subprocess.run(["nm", "-D", "--defined-only", str(tmp_path / "_engine.so")],
                          capture_output=True, text=True).stdout
    exported = {line.split()[-1] for line in syms.splitlines() if " T " in line}
    assert exported == {"PyInit__engine"}


_ASAN_SCRIPT = """
import numpy as np
import _engine
rng = np.random.default_rng(1)
for i in range(3000):
    p = {"profile": int(rng.integers(1, 4)), "short_stage": int(rng.integers(1, 3)),
         "distance": float(rng.normal()), "v_max": float(rng.uniform(0.01, 3)),
         "a_max": float(rng.uniform(0.1, 20)), "d_max": float(rng.uniform(0.1, 20)),
         "T_F1": float(rng.uniform(0, 0.3)), "T_F2": float(rng.uniform(0, 0.3)),
         "T_F3": float(rng.uniform(0, 0.3)), "T_F4": float(rng.uniform(0, 0.3)),
         "v0": float(rng.normal()) * 0.1, "t_start": float(rng.uniform(-0.01, 0.1))}
    try:
        pl = _engine.plan(p)
    except (_engine.PlanError, ValueError):
        continue
    n = min(int(pl.k_end) + 20, 3000)
    out = np.empty((7, n))
    pl.sample_into(out, -5, 1, n)
    try:
        _engine.sync_velocity({**p, "v0": 0.0}, pl.motion_time * 1.5, 3.0)
    except _engine.PlanError:
        pass
    eps, states = np.empty(n + 1), np.empty((n + 1, 2))
    _engine.step_modes(np.append(out[2], 0.0), np.append(out[3], 0.0), 1e-3,
                       np.full((1, n), 7.0), np.array([0.03]), np.ones(1), n, np.zeros(2),
                       eps, states)
    res = np.empty(3)
    pl.residuals(1, n, 1e-3, np.full((2, n), 7.0), np.array([0.03, 0.0]), np.ones(2),
                 np.array([7.0, 9.0]), np.array([0.9, 1.0, 1.1]), res)
print("ok")
"""


@pytest.mark.slow
def test_engine_under_asan_and_ubsan(tmp_path):
    """The extension, built with AddressSanitizer + UBSan, on 3000 random (also invalid) plans."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc not available")
    libasan = subprocess.run(["gcc", "-print-file-name=libasan.so"], capture_output=True,
                             text=True).stdout.strip()
    src = Path(__file__).resolve().parents[1] / "harness" / "_engine.c"
    if not (src.is_file() and Path(libasan).is_file()):
        pytest.skip("not a source checkout, or gcc has no AddressSanitizer runtime")
    pkg = tmp_path  # the module alone (top-level _engine): no package, no matplotlib
    ext = sysconfig.get_config_var("EXT_SUFFIX")
    cmd = ["gcc", "-std=c99", "-g", "-O1", "-fPIC", "-shared", "-fsanitize=address,undefined",
           "-fno-sanitize-recover=all", "-fno-omit-frame-pointer",
           f"-I{sysconfig.get_paths()['include']}", f"-I{fmu_src_dir()}", str(src),
           *CORE, "-o", str(pkg / f"_engine{ext}"), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    env = {**os.environ, "LD_PRELOAD": libasan, "PYTHONPATH": str(tmp_path),
           "ASAN_OPTIONS": "detect_leaks=0:abort_on_error=0",
           "UBSAN_OPTIONS": "print_stacktrace=1"}
    proc = subprocess.run([sys.executable, "-c", _ASAN_SCRIPT], capture_output=True, text=True,
                          env=env, timeout=600, cwd=tmp_path)
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stdout + proc.stderr
    assert "runtime error" not in proc.stderr, proc.stderr


def _same(a: float, b: float) -> bool:
    if math.isinf(a) or math.isinf(b) or math.isnan(a) or math.isnan(b):
        return (math.isinf(a) and a == b) or (math.isnan(a) and math.isnan(b))
    return abs(a - b) <= 1e-9 * max(abs(a), abs(b), 1e-300)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["sweep-X", "sweep-Y"])
def test_every_sweep_move_is_the_same_through_both_engines(fmu2, name):
    """Issue #8: every move of both embedded sweeps through both engines gives the same
    jerk times and residual, settling and motion times to 1e-9 relative."""
    from harness.evaluation import run_case

    sc = load_scenario(name)
    cases = sc.cases()
    assert len(cases) == 50
    with Session(fmu2) as ref, Session(engine="fast") as fast:
        for case in cases:
            a = run_case(case, ref, keep_runs=False)
            b = run_case(case, fast, keep_runs=False)
            assert a.band == pytest.approx(b.band, rel=1e-9)
            for prof, pa in a.profiles.items():
                pb = b.profiles[prof]
                assert pb.T_F == pa.T_F, (case.name, prof)
                for key in ("residual", "settling_time", "motion_time", "free_amplitude",
                            "rise_time"):
                    va, vb = getattr(pa.metrics, key), getattr(pb.metrics, key)
                    assert _same(va, vb), (case.name, prof, key, va, vb)


# ------------------------------------------- the robust search's objective (issue 18)


def _adjoint_case():
    pl = _engine.plan({"profile": 3, "distance": 0.3, "v_max": 0.6, "a_max": 3.0,
                       "d_max": 3.0, "T_F1": 0.11, "T_F2": 0.09, "T_F3": 0.12, "T_F4": 0.1,
                       "t_start": 0.05})
    m, h = 2, 2e-3
    k_end = int(math.ceil((pl.motion_time + 0.05) / h))
    rng = np.random.default_rng(7)
    f_nom = np.ascontiguousarray(np.vstack([7 + rng.random(k_end), 18 + rng.random(k_end)]))
    zeta, gain, f_end = np.array([0.03, 0.01]), np.array([1.0, 0.3]), np.array([7.2, 18.4])
    return pl, m, h, k_end, f_nom, zeta, gain, f_end


def test_adjoint_sums_give_the_residuals_of_stepping_the_plant():
    """Plan.adjoint_residuals (three differences of adjoint_sums per constant-jerk piece)
    against Plan.residuals (the plant stepped over every sample), two modes, three map
    scales, a start off the communication grid; the bound stops at the first point reaching
    it; adjoint_sums' psi equals adjoint_modes' (their cumulative sums)."""
    pl, m, h, k_end, f_nom, zeta, gain, f_end = _adjoint_case()
    factors = np.array([0.9, 1.0, 1.07])
    ref = np.empty(3)
    pl.residuals(m, k_end, h, f_nom, zeta, gain, f_end, factors, ref)
    R = 2 * len(factors)
    S = np.empty((R, 2, 3, k_end + 1))
    for q, c in enumerate(factors):
        _engine.adjoint_sums(h, f_nom, zeta, gain, k_end, S[2 * q:2 * q + 2], c)
    w = 2 * np.pi * np.outer(factors, f_end).ravel()
    z = np.tile(zeta, 3)
    sig, wd = z * w, w * np.sqrt(1 - z * z)
    out, ready, order = np.empty(3), np.ones(3, dtype=np.uint8), np.array([2, 0, 1])
    assert pl.adjoint_residuals(m, k_end, S, sig, wd, 2, order, math.inf, out, ready, 0) == 3
    np.testing.assert_allclose(out, ref, rtol=1e-10)
    # a bound: stops after the first point at or above it
    out2 = np.full(3, -1.0)
    n = pl.adjoint_residuals(m, k_end, S, sig, wd, 2, order, out[2] * 0.5, out2, ready, 0)
    assert n == 1 and out2[2] == out[2] and out2[0] == -1.0
    # a point not ready: -(position + 1), the points before it done
    ready[0] = 0
    assert pl.adjoint_residuals(m, k_end, S, sig, wd, 2, order, math.inf, out2, ready, 0) == -2
    # the fill: the missing point computed in C, as the rows above
    S2, sig2, wd2 = S.copy(), sig.copy(), wd.copy()
    S2[0:2] = 0.0
    n = pl.adjoint_residuals(m, k_end, S2, sig2, wd2, 2, order, math.inf, out2, ready, 0,
                             (h, f_nom, zeta, gain, f_end, factors))
    assert n == 3 and ready[0] == 1
    np.testing.assert_array_equal(S2, S)
    np.testing.assert_array_equal(out2, out)
    # the same psi as adjoint_modes
    psi = np.empty((2, k_end, 2, 2))
    _engine.adjoint_modes(h, f_nom, zeta, gain, k_end, psi)
    np.testing.assert_allclose(S[2:4, :, 0, 0], psi[:, :, :, 0].sum(axis=1), rtol=1e-12,
                               atol=1e-12 * np.abs(psi).max() * k_end)


def test_replan_equals_planning_the_same_parameters():
    base = {"profile": 3, "distance": 0.3, "v_max": 0.6, "a_max": 3.0, "d_max": 3.0,
            "T_F1": 0.11, "T_F2": 0.09, "T_F3": 0.12, "T_F4": 0.1, "t_start": 0.05}
    pl = _engine.plan(base)
    new = {**base, "T_F1": 0.05, "T_F2": 0.2, "T_F3": 0.07, "T_F4": 0.15}
    a, b = pl.replan(0.05, 0.2, 0.07, 0.15), _engine.plan(new)
    assert a.motion_time == b.motion_time and a.N_F == b.N_F and a.offset == b.offset
    X, Y = np.empty((7, 900)), np.empty((7, 900))
    a.sample_into(X, 0, 1, 900)
    b.sample_into(Y, 0, 1, 900)
    np.testing.assert_array_equal(X, Y)
    with pytest.raises(_engine.PlanError, match="T_F2"):
        pl.replan(0.05, -1.0, 0.07, 0.15)
    shaped = _engine.plan({**base, "shaper": 1, "f_shaper": 8.0})
    with pytest.raises(ValueError, match="unshaped"):
        shaped.replan(0.1, 0.1, 0.1, 0.1)


@pytest.mark.parametrize("fn", ["adjoint_modes", "adjoint_sums"])
def test_adjoint_rows_refuse_a_bad_damping_or_frequency(fn):
    """Both adjoint functions check their rows the same way, naming the row (and step)."""
    n, h = 5, 1e-3
    f = np.full((1, n), 8.0)
    out = np.empty(1 * n * 4) if fn == "adjoint_modes" else np.empty(6 * (n + 1))

    def call(f_rows, zeta):
        if fn == "adjoint_modes":
            return _engine.adjoint_modes(h, f_rows, np.array([zeta]), np.array([1.0]), n,
                                         out.reshape(1, n, 2, 2))
        return _engine.adjoint_sums(h, f_rows, np.array([zeta]), np.array([1.0]), n,
                                    out.reshape(1, 6, n + 1), 1.0)

    call(f, 0.05)  # accepted
    with pytest.raises(ValueError, match="row 0: damping ratio 1 not in"):
        call(f, 1.0)
    bad = f.copy()
    bad[0, 3] = np.nan
    with pytest.raises(ValueError, match="row 0: frequency nan Hz at step 3"):
        call(bad, 0.05)
