"""The FMU through fmpy: bad inputs, state machine, FMU state, instances, steps, time."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from harness.fmu.runner import FMUError, GeneratorFMU, generate

from _motion_checks import check_end_and_limits

# ----------------------------------------------------------------- helpers


def _healthy_afterwards(fmu) -> None:
    """Nothing else broke: a fresh instance in the same process still runs correctly."""
    tr = generate({"profile": 2, "distance": 0.1}, fmu=fmu)
    check_end_and_limits(tr)


def _expect_init_error(fmu, params: dict, *fragments: str) -> None:
    with GeneratorFMU(fmu, params=params) as g:
        with pytest.raises(FMUError) as info:
            g.initialize()
        err = info.value
        assert err.status == 3
        msg = str(err)
        for f in fragments:
            assert f in msg, (f, msg)
        # the error also went through the logger callback, in the error category
        assert any(r.status == 3 and r.category == "logStatusError" for r in g.log)
        # no NaN in the outputs, even now
        for name in ("x", "v", "a", "j"):
            value = g.get(name)
            assert math.isfinite(value), (name, value)
    _healthy_afterwards(fmu)


BAD_PARAMETERS = [
    ({"v_max": -1.0}, ["v_max = -1"]),
    ({"v_max": 0.0}, ["v_max = 0"]),
    ({"v_max": math.nan}, ["v_max = nan"]),
    ({"v_max": math.inf}, ["v_max = inf"]),
    ({"a_max": -2.0}, ["a_max = -2"]),
    ({"a_max": 0.0}, ["a_max = 0"]),
    ({"a_max": math.nan}, ["a_max = nan"]),
    ({"a_max": -math.inf}, ["a_max = -inf"]),
    ({"d_max": 0.0}, ["d_max = 0"]),
    ({"d_max": math.nan}, ["d_max = nan"]),
    ({"d_max": math.inf}, ["d_max = inf"]),
    ({"Te": 0.0}, ["Te = 0"]),
    ({"Te": -1e-3}, ["Te = -0.001"]),
    ({"Te": math.nan}, ["Te = nan"]),
    ({"T_F1": 0.0}, ["T_F1 = 0"]),
    ({"T_F3": -0.05}, ["T_F3 = -0.05"]),
    ({"T_F4": math.nan}, ["T_F4 = nan"]),
    ({"T_F2": 0.0004}, ["T_F2 = 0.0004", "rounds to 0 samples"]),
    ({"profile": 2, "T_F1": 0.00049}, ["T_F1 = 0.00049", "rounds to 0 samples"]),
    ({"profile": 5}, ["profile = 5"]),
    ({"profile": 4}, ["distance = 0.4", "the table ends 0 m from x0"]),  # an empty table
    ({"profile": 0}, ["profile = 0"]),
    ({"short_stage": 3}, ["short_stage = 3"]),
    ({"n_segments": -1}, ["n_segments = -1"]),
    ({"n_segments": 33}, ["n_segments = 33"]),
    ({"v_e": 1.5}, ["v_e = 1.5", "v_max = 1"]),
    ({"v0": -2.0, "distance": -0.5}, ["v0 = -2"]),
    ({"v_e": math.inf}, ["v_e = inf"]),
    ({"distance": math.nan}, ["distance = nan"]),
    ({"x0": math.inf}, ["x0 = inf"]),
    ({"t_start": math.nan}, ["t_start = nan"]),
    ({"v_e": 0.9, "distance": 0.001}, ["distance = 0.001", "too short"]),
    ({"profile": 2, "T_F1": 0.02, "v0": 1.0, "v_e": 1.0, "distance": 0.0404},
     ["distance = 0.0404", "cruising at 1 m/s", "whole samples of 0.001 m", "speed dip"]),
    ({"v0": -0.0, "v_e": -0.9, "distance": -0.001},
     ["distance = -0.001", "too short", "from 0 m/s to -0.9 m/s"]),
    ({"v_e": -0.2}, ["v_e = -0.2", "direction reverses"]),
    ({"n_segments": 3, "seg_distance": [0.2, 0.2, 0.2], "seg_v_end": [0.5, 2.0, 0.0]},
     ["seg_v_end[2] = 2"]),
    ({"n_segments": 3, "seg_distance": [0.9, 0.01, 0.5], "seg_v_end": [1.0, 0.0, 0.0],
      "a_max": 1.0, "d_max": 1.0},
     ["seg_distance[2] = 0.01", "too short"]),
    # the cruise before it is rounded to 301 samples: 0.4 mm less is left for the braking
    ({"profile": 1, "v0": 1.0, "a_max": 10.0, "d_max": 10.0, "n_segments": 3,
      "seg_distance": [0.3006, 0.0497, 0.1], "seg_v_end": [1.0, 0.0, 0.0]},
     ["seg_distance[2] = 0.0497", "too short",
      "rounding the earlier segments to whole samples left it 0.0493 m"]),
    ({"n_segments": 2, "seg_distance": [0.2, math.nan], "seg_v_end": [0.0, 0.0]},
     ["seg_distance[2] = nan"]),
    ({"n_segments": 2, "seg_distance": [0.2, -0.2], "seg_v_end": [0.3, 0.0]},
     ["seg_v_end[1] = 0.3", "direction reverses"]),
]


@pytest.mark.parametrize("params,fragments", BAD_PARAMETERS,
                         ids=[next(iter(p)) + "=" + str(next(iter(p.values())))[:12]
                              for p, _ in BAD_PARAMETERS])
def test_bad_parameter_is_an_fmi_error_naming_it(fmu, params, fragments):
    _expect_init_error(fmu, params, *fragments)


OVERFLOWING = [
    # issue #10: accepted before, with +-inf outputs
    ({"x0": 1.797e308, "distance": 1e305}, ["x0 = 1.797e+308"]),
    ({"x0": 1e300, "distance": 1e299}, ["distance = 1e+299", "1e+300 m"]),
    ({"v_max": 1e300, "v0": 1e300, "v_e": 1e300, "distance": 1e299, "t_start": 1e9},
     ["v0 = 1e+300", "t_start = 1e+09", "before the motion starts"]),
    ({"v_max": 1e300, "v0": 1e300, "v_e": 1e300, "distance": 1e299},
     ["v_e = 1e+300", "after the motion"]),
    ({"n_segments": 3, "v_max": 1e290, "seg_distance": [4e299, 4e299, 4e299],
      "seg_v_end": [0.0, 0.0, 0.0]},
     ["seg_distance[3]"]),
]


@pytest.mark.parametrize("params, fragments", OVERFLOWING)
def test_parameters_whose_outputs_would_overflow_are_refused(fmu, params, fragments):
    """No infinity in any output: such sets are refused at initialisation, by name."""
    _expect_init_error(fmu, params, *fragments)


def test_large_but_finite_motions_are_accepted(fmu):
    """The bounds refuse only what overflows: a 1 km/s start 1e9 s ahead is fine."""
    p = {"v_max": 1e3, "v0": 1e3, "v_e": 1e3, "t_start": 1e9, "distance": 1e3}
    with GeneratorFMU(fmu, params=p) as g:
        g.initialize()
        assert g.get("x") == pytest.approx(-1e12)
        g.do_step(1e9 + 2.0)
        assert math.isfinite(g.get("x")) and g.get("v") == pytest.approx(1e3)


def test_non_zero_end_speed_refusal_says_from_where_every_distance_lands(fmu):
    """The refusal gives the minimum and the distance from which all land; check both."""
    p = {"profile": 2, "T_F1": 0.03, "v0": 0.9, "v_e": 1.0, "v_max": 1.0, "distance": 0.05774}
    with GeneratorFMU(fmu, params=p) as g:
        with pytest.raises(FMUError) as info:
            g.initialize()
    msg = str(info.value)
    found = re.search(r"the minimum is about ([0-9.e+-]+) m and from about ([0-9.e+-]+) m on "
                      r"every distance lands", msg)
    assert found, msg
    d_min, d_all = float(found.group(1)), float(found.group(2))
    assert d_min <= p["distance"] < d_all
    for d in np.linspace(d_all, 1.5 * d_all, 13):
        check_end_and_limits(generate({**p, "distance": float(d)}, fmu=fmu))


def _backward_taylor(ref_t, ref, t):
    """Profile values at ``t`` from the next whole sample backwards (independent of the FMU's
    forward evaluation): the jerk of the interval is the finite difference of ``a``."""
    Te = ref_t[1] - ref_t[0]
    k = np.floor((t - ref_t[0]) / Te + 1e-9).astype(int)
    sig = ref_t[k + 1] - t
    j = (ref["a"][k + 1] - ref["a"][k]) / Te
    a = ref["a"][k + 1] - j * sig
    v = ref["v"][k + 1] - ref["a"][k + 1] * sig + 0.5 * j * sig**2
    x = ref["x"][k + 1] - ref["v"][k + 1] * sig + 0.5 * ref["a"][k + 1] * sig**2 - j * sig**3 / 6
    return x, v, a, j


@pytest.mark.parametrize("kwargs, Te", [
    ({"stop_time": 1.2345}, 1e-3),              # stop time not a whole number of samples
    ({"output_interval": 0.0025}, 1e-3),        # 2.5 samples a step
    ({"output_interval": 0.001}, 2e-3),         # Te = 2 ms with the default 1 ms step
    ({"output_interval": 0.37e-3, "stop_time": 1.3}, 1e-3),
])
def test_any_communication_step_gives_the_profile_at_that_time(fmu, kwargs, Te):
    """fmpy's own loop with steps that are not whole samples: every point on the profile."""
    from fmpy import simulate_fmu

    params = {"Te": Te, "t_start": 0.1}
    names = ["x", "v", "a", "j", "a_AL"]
    res = simulate_fmu(str(fmu), start_values=params, output=names, **{"stop_time": 1.5, **kwargs})
    stop = kwargs.get("stop_time", 1.5)
    assert res["time"][-1] == pytest.approx(stop, abs=1e-12)
    ref = simulate_fmu(str(fmu), start_values=params, output=names, output_interval=Te,
                       stop_time=stop + 2 * Te)
    x, v, a, j = _backward_taylor(ref["time"], ref, res["time"])
    assert np.max(np.abs(res["x"] - x)) < 1e-12
    assert np.max(np.abs(res["v"] - v)) < 1e-9
    assert np.max(np.abs(res["a"] - a)) < 1e-6
    on_grid = np.abs(res["time"] / Te - np.round(res["time"] / Te)) < 1e-6
    between = ~on_grid
    # j and a_al are those of the interval that holds the point (a whole sample: the next one)
    assert np.allclose(res["j"][between], j[between], rtol=1e-6, atol=1e-6)
    k = np.floor(res["time"] / Te + 1e-9).astype(int)
    assert np.array_equal(res["a_AL"], ref["a_AL"][k])
    # on whole samples the values are the per-sample values, bit for bit
    kk = np.round(res["time"][on_grid] / Te).astype(int)
    for n in names:
        assert np.array_equal(res[n][on_grid], ref[n][kk]), n
    check_end_and_limits(generate({"t_start": 0.1, "Te": Te}, fmu=fmu))


def test_whole_multiple_steps_are_bit_identical(fmu):
    """A step of 3 Te gives every third per-sample value exactly (today's values)."""
    with GeneratorFMU(fmu) as g1, GeneratorFMU(fmu) as g3:
        g1.initialize()
        g3.initialize()
        _, one = g1.record(1200, 1e-3, ["x", "v", "a", "j", "x_AL", "v_AL", "a_AL"])
        _, three = g3.record(400, 3e-3, ["x", "v", "a", "j", "x_AL", "v_AL", "a_AL"])
    for n in one:
        assert np.array_equal(one[n][::3], three[n]), n


def test_fractional_steps_then_whole_steps(fmu):
    """Steps of Te/3 add up to whole samples: afterwards the values are the samples again."""
    with GeneratorFMU(fmu) as g, GeneratorFMU(fmu) as ref:
        g.initialize()
        ref.initialize()
        for _ in range(300):
            g.do_step(1e-3 / 3)
        ref.do_step(0.1)
        for name in ("x", "v", "a", "j"):
            assert g.get(name) == ref.get(name), name
        g.do_step(0.2)
        ref.do_step(0.2)
        assert g.get("x") == ref.get("x")


def test_step_from_the_wrong_time(fmu):
    with GeneratorFMU(fmu) as g:
        g.initialize()
        g.time = 0.5  # the FMU is at 0
        with pytest.raises(FMUError) as info:
            g.do_step(1e-3)
        assert "currentCommunicationPoint = 0.5" in str(info.value)
    _healthy_afterwards(fmu)


def test_unknown_value_reference(fmu):
    with GeneratorFMU(fmu) as g:
        g.initialize()
        get = g.fmu.getFloat64 if g.fmi_version == 3 else g.fmu.getReal
        with pytest.raises(FMUError) as info:
            g._call(get, [999])
        assert "unknown value reference 999" in str(info.value)
    with GeneratorFMU(fmu) as g:
        setter = g.fmu.setFloat64 if g.fmi_version == 3 else g.fmu.setReal
        with pytest.raises(FMUError) as info:
            g._call(setter, [12345], [1.0])
        assert "unknown value reference 12345" in str(info.value)
    _healthy_afterwards(fmu)


def test_wrong_type_and_outputs_cannot_be_set(fmu):
    with GeneratorFMU(fmu) as g:
        vr = g.variable("done").valueReference
        get = g.fmu.getFloat64 if g.fmi_version == 3 else g.fmu.getReal
        g.initialize()
        with pytest.raises(FMUError) as info:
            g._call(get, [vr])
        assert "done" in str(info.value) and "Boolean" in str(info.value)
    with GeneratorFMU(fmu) as g:
        with pytest.raises(FMUError) as info:
            g.set({"x": 1.0})
        assert "x (value reference" in str(info.value) and "output" in str(info.value)
    _healthy_afterwards(fmu)


def test_calls_out_of_order(fmu):
    # doStep before initialization
    with GeneratorFMU(fmu) as g:
        with pytest.raises(FMUError) as info:
            g._call(g.fmu.doStep, currentCommunicationPoint=0.0, communicationStepSize=1e-3)
        assert "must not be called in state Instantiated" in str(info.value)
    # a fixed parameter after initialization
    with GeneratorFMU(fmu) as g:
        g.initialize()
        with pytest.raises(FMUError) as info:
            g.set({"v_max": 2.0})
        assert "v_max is a fixed parameter" in str(info.value)
    # exit initialization twice
    with GeneratorFMU(fmu) as g:
        g.initialize()
        with pytest.raises(FMUError) as info:
            g._call(g.fmu.exitInitializationMode)
        assert "must not be called in state StepMode" in str(info.value)
    # after an error only reset (and free) bring it back
    with GeneratorFMU(fmu, params={"v_max": -1.0}) as g:
        with pytest.raises(FMUError):
            g.initialize()
        with pytest.raises(FMUError) as info:
            g._call(g.fmu.doStep, currentCommunicationPoint=0.0, communicationStepSize=1e-3)
        assert "state Error" in str(info.value)
        g.fmu.reset()
        g._initialized = False
        if g.fmi_version == 2:
            g.fmu.setupExperiment(startTime=0.0)
        g.set({"distance": 0.2})
        g.initialize()
        g.do_step(1.0)
        assert g.get("x") == pytest.approx(0.2, rel=1e-12)
    _healthy_afterwards(fmu)


def test_fmi3_array_with_wrong_count():
    from harness.fmu.build import default_fmu

    with GeneratorFMU(default_fmu(3)) as g:
        vr = g.variable("seg_distance").valueReference
        with pytest.raises(FMUError) as info:
            g._call(g.fmu.setFloat64, [vr], [0.1, 0.2])
        assert "nValues" in str(info.value)


def test_fmi2_instantiation_with_wrong_guid(fmu2):
    from fmpy import extract, read_model_description
    from fmpy.fmi2 import FMU2Slave

    md = read_model_description(str(fmu2))
    unz = extract(str(fmu2))
    s = FMU2Slave(guid="{00000000-0000-0000-0000-000000000000}", unzipDirectory=unz,
                  modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bad")
    with pytest.raises(Exception, match="[Ff]ailed to instantiate"):
        s.instantiate()
    _healthy_afterwards(fmu2)


# -------------------------------------------------------------- FMU state

def _record(g: GeneratorFMU, n: int, h: float) -> np.ndarray:
    vrs = g.vr(["x", "v", "a", "j", "x_AL", "v_AL", "a_AL"])
    out = []
    for _ in range(n):
        g.do_step(h)
        out.append(g.get_reals(vrs) + [float(g.get("done"))])
    return np.array(out)


def test_fmu_state_restore_is_bit_identical(fmu):
    p = {"profile": 3, "distance": 0.3, "T_F2": 0.12, "v0": 0.1, "t_start": 0.01}
    with GeneratorFMU(fmu, params=p) as g:
        g.initialize()
        _record(g, 123, 1e-3)
        t_saved = g.time
        state = g.get_state()
        first = _record(g, 600, 1e-3)
        g.set_state(state, t_saved)
        second = _record(g, 600, 1e-3)
        assert np.array_equal(first, second)
        # serialised into another instance with other parameters: it takes everything
        data = g.serialize_state(state)
        g.free_state(state)
        with GeneratorFMU(fmu, params={"profile": 1, "distance": -2.0}) as h:
            h.initialize()
            h.set_state(h.deserialize_state(data), t_saved)
            third = _record(h, 600, 1e-3)
        assert np.array_equal(first, third)
        assert first[-1, -1] == 1.0  # reached the end


def test_corrupt_serialized_state_is_refused(fmu):
    with GeneratorFMU(fmu) as g:
        g.initialize()
        state = g.get_state()
        data = bytearray(g.serialize_state(state))
        g.free_state(state)
    bad_header = bytearray(data)
    bad_header[0] ^= 0xFF
    for blob, fragment in ((bad_header, "not a state of this FMU"),
                           (data[:100], "100 bytes")):
        with GeneratorFMU(fmu) as g:
            g.initialize()
            with pytest.raises(FMUError) as info:
                g._call(g.deserialize_state, bytes(blob))
            assert fragment in str(info.value)
    _healthy_afterwards(fmu)


def test_instances_are_independent(fmus):
    pa = {"profile": 2, "distance": 0.4, "T_F1": 0.05}
    pb = {"profile": 3, "distance": -0.2, "T_F3": 0.1}
    alone_a = generate(pa, fmu=fmus[2], t_stop=0.8)
    alone_b = generate(pb, fmu=fmus[3], t_stop=0.8)
    with GeneratorFMU(fmus[2], params=pa, instance_name="a") as a, \
            GeneratorFMU(fmus[3], params=pb, instance_name="b") as b, \
            GeneratorFMU(fmus[2], params=pb, instance_name="c") as c:
        for g in (a, b, c):
            g.initialize()
        xa, xb, xc = [a.get("x")], [b.get("x")], [c.get("x")]
        for _ in range(800):
            for g, acc in ((a, xa), (b, xb), (c, xc)):
                g.do_step(1e-3)
                acc.append(g.get("x"))
    assert np.array_equal(xa, alone_a.x)
    assert np.array_equal(xb, alone_b.x)
    assert np.array_equal(xc, alone_b.x)   # FMI 2 and FMI 3 agree too


# ----------------------------------------------------------- steps, time

@pytest.mark.parametrize("k", [2, 7, 50])
def test_any_whole_multiple_of_Te(fmu, k):
    fine = generate({"profile": 3}, fmu=fmu, t_stop=0.7)
    coarse = generate({"profile": 3}, fmu=fmu, t_stop=0.7, dt=k * 1e-3)
    for name in ("x", "v", "a", "j", "done"):
        assert np.array_equal(getattr(coarse, name), getattr(fine, name)[::k][:len(coarse.t)])


def test_start_time_and_t_start(fmu):
    base = generate({"profile": 2}, fmu=fmu)
    late = generate({"profile": 2, "t_start": 10.25}, fmu=fmu, start_time=10.0)
    k = round(0.25 / 1e-3)
    assert np.all(late.x[:k + 1] == 0.0)
    assert late.t_end == pytest.approx(late.t[late.done.argmax()], abs=1e-9)
    n = len(base.t)
    for name in ("x", "v", "a", "j"):
        np.testing.assert_array_equal(getattr(late, name)[k:k + n], getattr(base, name))


def test_t_start_between_samples_starts_at_the_next_sample(fmu):
    tr = generate({"profile": 2, "t_start": 0.1234}, fmu=fmu, debug_logging=True)
    moving = np.nonzero(tr.j)[0]
    assert tr.t[moving[0]] == pytest.approx(0.124)
    assert tr.t_end == pytest.approx(tr.t[tr.done.argmax()], abs=1e-12)
    assert any("not a sample of the generator" in r.message for r in tr.log)
    check_end_and_limits(tr)


def test_moving_before_the_start(fmu):
    tr = generate({"profile": 2, "v0": 0.3, "distance": 0.5, "t_start": 0.2, "x0": 1.0},
                  fmu=fmu)
    k = round(0.2 / 1e-3)
    np.testing.assert_allclose(tr.x[:k + 1], 1.0 + 0.3 * (tr.t[:k + 1] - 0.2), rtol=0,
                               atol=1e-15)
    assert np.all(tr.v[:k + 1] == 0.3)
    check_end_and_limits(tr)


def test_no_drift_over_a_long_motion(fmu2):
    """10 million samples: positions stay exact; one doStep may cover them all."""
    Te, v = 1e-4, 1.0
    p = {"profile": 3, "Te": Te, "distance": 1000.0, "v_max": v, "a_max": 2.0, "d_max": 2.0,
         "T_F1": 0.05, "T_F2": 0.07, "T_F3": 0.09, "T_F4": 0.03, "x0": 5.0}
    tr = generate(p, fmu=fmu2, dt=1.0, t_stop=1002.0)
    check_end_and_limits(tr)
    # the cruise is exactly linear in time (no accumulated rounding)
    cruise = (tr.t > 10) & (tr.t < 990)
    slope = np.diff(tr.x[cruise]) / np.diff(tr.t[cruise])
    assert np.abs(slope - slope[0]).max() <= 1e-11
    with GeneratorFMU(fmu2, params=p) as g:
        g.initialize()
        g.do_step(1002.0)  # one step over 10,020,000 samples
        assert g.get("x") == pytest.approx(1005.0, rel=1e-15, abs=1e-12)
        assert g.get("done")


# ------------------------------------------- null pointers (issue #10, item 4)

def _raw(g: GeneratorFMU):
    """The instance handle and the low-level FMI function prefix of fmpy."""
    return g.fmu.component, ("fmi2" if g.fmi_version == 2 else "fmi3")


def test_null_value_arrays_are_errors_with_a_message_and_harmless(fmu):
    import ctypes

    with GeneratorFMU(fmu) as g:
        h, pre = _raw(g)
        vr = (ctypes.c_uint * 1)(g.variable("v_max").valueReference)
        setter = getattr(g.fmu, pre + ("SetReal" if pre == "fmi2" else "SetFloat64"))
        args = (h, vr, 1, None) if pre == "fmi2" else (h, vr, 1, None, 1)
        with pytest.raises(FMUError) as info:
            g._call(setter, *args)
        assert info.value.status == 3
        assert "SetReal: argument value is a null pointer" in str(info.value) or \
            "SetFloat64: argument values is a null pointer" in str(info.value)
        cats = (ctypes.c_char_p * 2)(b"logEvents", None)
        with pytest.raises(FMUError) as info:
            g._call(getattr(g.fmu, pre + "SetDebugLogging"), h, 1, 2, cats)
        assert "categories[1] is a null pointer" in str(info.value)
        with pytest.raises(FMUError) as info:
            g._call(getattr(g.fmu, pre + "SetDebugLogging"), h, 1, 3, None)
        assert "SetDebugLogging: argument categories" in str(info.value)
        # the instance is unaffected: it initializes and runs
        g.set({"distance": 0.2})
        g.initialize()
        vx = (ctypes.c_uint * 1)(g.variable("x").valueReference)
        getter = getattr(g.fmu, pre + ("GetReal" if pre == "fmi2" else "GetFloat64"))
        args = (h, vx, 1, None) if pre == "fmi2" else (h, vx, 1, None, 1)
        with pytest.raises(FMUError) as info:
            g._call(getter, *args)
        assert "argument value" in str(info.value)
        g.do_step(1.0)
        assert g.get("x") == pytest.approx(0.2, rel=1e-12)
    _healthy_afterwards(fmu)


def test_null_state_pointers_are_errors_with_a_message(fmu):
    with GeneratorFMU(fmu) as g:
        h, pre = _raw(g)
        g.initialize()
        names = ({"get": "GetFMUstate", "size": "SerializedFMUstateSize"} if pre == "fmi2"
                 else {"get": "GetFMUState", "size": "SerializedFMUStateSize"})
        with pytest.raises(FMUError) as info:
            g._call(getattr(g.fmu, pre + names["get"]), h, None)
        arg = "FMUstate" if pre == "fmi2" else "FMUState"
        assert f"{pre}{names['get']}: argument {arg} is a null pointer" in str(info.value)
        state = g.get_state()
        with pytest.raises(FMUError) as info:
            g._call(getattr(g.fmu, pre + names["size"]), h, state, None)
        assert "argument size is a null pointer" in str(info.value)
        g.free_state(state)
        g.do_step(1e-3)
        assert math.isfinite(g.get("x"))


# -------------------------- variable dependencies (issue #10, item 7)

def test_fmi3_variable_dependencies_refused_but_instance_usable(fmu3):
    import ctypes

    with GeneratorFMU(fmu3) as g:
        g.initialize()
        n = ctypes.c_size_t(7)
        vr = g.variable("x").valueReference
        with pytest.raises(FMUError) as info:
            g._call(g.fmu.fmi3GetNumberOfVariableDependencies, g.fmu.component, vr,
                    ctypes.byref(n))
        assert "fmi3GetNumberOfVariableDependencies" in str(info.value)
        assert "not provided" in str(info.value)
        assert any(r.status == 3 and r.category == "logStatusError" for r in g.log)
        for _ in range(10):
            g.do_step(1e-3)
        assert math.isfinite(g.get("x"))


# --------------------------------- corrupted FMU states (issue #10, item 3)

def test_damaged_body_of_a_serialized_state_is_refused(fmu):
    rng = np.random.default_rng(10)
    with GeneratorFMU(fmu) as g:
        g.initialize()
        _record(g, 100, 1e-3)
        t_saved = g.time
        state = g.get_state()
        data = bytes(g.serialize_state(state))
        g.free_state(state)
        reference = _record(g, 50, 1e-3)
        for _ in range(200):
            blob = bytearray(data)
            pos = int(rng.integers(64, len(blob)))  # past the header
            blob[pos] ^= int(rng.integers(1, 256))
            with pytest.raises(FMUError) as info:
                g._call(g.deserialize_state, bytes(blob))
            assert "checksum" in str(info.value) or "refused" in str(info.value)
        # refusals left the instance as it was: the good state still replays identically
        g.set_state(g.deserialize_state(data), t_saved)
        assert np.array_equal(_record(g, 50, 1e-3), reference)
        g.fmu.reset()
    _healthy_afterwards(fmu)
