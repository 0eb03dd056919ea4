"""The time-varying ZV shaper and the shapers on the JL profile (issue 9, point 3).

Independent references: ``scipy.integrate.solve_ivp`` on the time-varying mode
(ω given in closed form, restarted at every breakpoint of the reference),
``scipy.integrate.quad`` for the phase, ``numpy.convolve`` for the shaped JL.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp

from harness.fmu.runner import generate
from harness.peers.compare import base_motion, build_peers, stationary_variant
from harness.peers.residual import residual_amplitude
from harness.peers.shapers import al_profile, make_shaper, shape, zv
from harness.peers.trajectory import PiecewiseJerk, from_fmu
from harness.peers.tv_shaper import TimeVaryingZV, design_for_scenario, shape_time_varying
from harness.scenario import parse_scenario
from harness.simulation.session import Session

MOVE = {"distance": 0.4, "v_max": 0.5, "a_max": 4.0, "d_max": 4.0}
ZETA = 0.03
# a mode drifting at 3 Hz/s during the whole move (9 Hz -> 6 Hz over 1 s, then still):
# it moves by about 0.2 Hz (2-3 %) during each shaper delay (56-83 ms)
F0, F1, T_DRIFT = 9.0, 6.0, 1.0


def f_drift(t):
    return F0 + (F1 - F0) * np.clip(np.asarray(t, dtype=float) / T_DRIFT, 0.0, 1.0)


def residual_on_drifting_mode(motion, t_f: float) -> float:
    """Free amplitude at ``t_f`` (after the motion) on the drifting mode, by solve_ivp.

    ε'' + 2ζω(t)ε' + ω(t)²ε = -a(t) with ω(t) = 2π f_drift(t) written out here,
    restarted at every breakpoint of the reference and at the end of the drift.
    """
    kn = np.unique(np.r_[motion.breakpoints(), T_DRIFT, t_f])
    kn = kn[(kn >= motion.t_start) & (kn <= t_f)]
    y = np.zeros(2)
    for s, b in zip(kn[:-1], kn[1:], strict=True):
        _, _, a0, j0 = (float(q[0]) for q in motion.evaluate([s], side="right"))

        def rhs(t, z, s=s, a0=a0, j0=j0):
            w = 2 * math.pi * (F0 + (F1 - F0) * min(max(t / T_DRIFT, 0.0), 1.0))
            return [z[1], -(a0 + j0 * (t - s)) - 2 * ZETA * w * z[1] - w * w * z[0]]

        sol = solve_ivp(rhs, (s, b), y, method="DOP853", rtol=1e-11, atol=1e-16)
        assert sol.success
        y = sol.y[:, -1]
    w = 2 * math.pi * float(f_drift(t_f))
    return math.hypot(y[0], (y[1] + ZETA * w * y[0]) / (w * math.sqrt(1 - ZETA ** 2)))


@pytest.fixture(scope="module")
def al(fmu2) -> PiecewiseJerk:
    return al_profile(MOVE, fmu=fmu2).to_motion().simplified()


@pytest.fixture(scope="module")
def jl(fmu2) -> PiecewiseJerk:
    tr = generate({**MOVE, "profile": 2, "T_F1": 0.15, "T_F2": 0.15, "T_F3": 0.15,
                   "T_F4": 0.15}, fmu=fmu2)
    return from_fmu(tr).to_motion()


# ------------------------------------------------------------ constant mode


def test_simplified_is_the_same_motion(fmu2):
    m = al_profile(MOVE, fmu=fmu2).to_motion()
    s = m.simplified()
    assert s.tb.size == 5 < m.tb.size  # AL: four acceleration steps and the end
    t = np.linspace(-0.1, 1.2, 5001)
    for side in ("left", "right"):
        np.testing.assert_allclose(np.array(s.evaluate(t, side)), np.array(m.evaluate(t, side)),
                                   rtol=0, atol=1e-13)


@pytest.mark.parametrize("rule", ["phase", "start"])
@pytest.mark.parametrize("zeta", [0.0, 0.04])
@pytest.mark.parametrize("which", ["al", "jl"])
def test_tv_shaper_is_zv_on_a_constant_mode(request, which, zeta, rule):
    base = request.getfixturevalue(which)
    f = 7.3
    tv = TimeVaryingZV.constant(f, zeta, 0.0, 2.0, rule=rule)
    ref = zv(f, zeta)
    tau = np.linspace(0.0, 1.0, 7)
    np.testing.assert_allclose(tv.delay(tau), ref.t[1], rtol=1e-12)
    A1, A2 = tv.amplitudes(tau)
    np.testing.assert_allclose(A1, ref.A[0], rtol=1e-13)
    np.testing.assert_allclose(A2, ref.A[1], rtol=1e-13)
    got = shape_time_varying(base, tv)
    exp = shape(base, ref)
    t = np.linspace(-0.05, 1.4, 14501)
    for k, scale in enumerate((0.4, 0.5, 4.0, 100.0)):  # x, v, a, j
        np.testing.assert_allclose(got.evaluate(t)[k], exp.evaluate(t)[k], rtol=0,
                                   atol=1e-10 * scale)
    assert got.t_end == pytest.approx(exp.t_end, abs=1e-12)
    assert got.distance == pytest.approx(0.4, abs=1e-12)
    # and it leaves nothing on that mode (closed form: the ZV residual, 0)
    assert residual_amplitude(got, f, zeta) < 1e-9 * residual_amplitude(base, f, zeta)


def test_scenario_tv_peers_equal_zv_peers_on_a_stationary_mode(small_sc, fmu2):
    st = stationary_variant(small_sc)
    with Session(fmu2) as s:
        b = build_peers(st, 0.1, 0.6, peers=("AL*ZV", "AL*TV-ZV", "JL*ZV", "JL*TV-ZV"),
                        session=s)
    t = np.linspace(0.0, 1.2, 6001)
    for base in ("AL", "JL"):
        zvm, tvm = b[f"{base}*ZV"][0], b[f"{base}*TV-ZV"][0]
        np.testing.assert_allclose(tvm.evaluate(t)[0], zvm.evaluate(t)[0], rtol=0, atol=1e-12)
        np.testing.assert_allclose(tvm.evaluate(t)[2], zvm.evaluate(t)[2], rtol=0, atol=1e-9)
        assert b[f"{base}*TV-ZV"][1].params["distance_correction"] == 0.0


# ------------------------------------------------------------ drifting mode


def test_phase_condition_and_weights_by_quadrature():
    """Φ(σ) - Φ(τ) = π (quad) and A_2/A_1 = K √(ω(σ)/ω(τ)) on the drifting mode."""
    tv = TimeVaryingZV(f_drift, ZETA, 0.0, 2.0)
    sq = math.sqrt(1 - ZETA ** 2)
    K = math.exp(-ZETA * math.pi / sq)
    for tau in (0.0, 0.3, 0.95, 1.2):
        sigma = float(tv.second_time(tau)[()])
        phase = quad(lambda t: 2 * math.pi * sq * float(f_drift(t)), tau, sigma,
                     points=[T_DRIFT] if tau < T_DRIFT < sigma else None, epsabs=1e-13)[0]
        assert phase == pytest.approx(math.pi, abs=1e-11)
        A1, A2 = (float(x[()]) for x in tv.amplitudes(tau))
        assert A1 + A2 == pytest.approx(1.0, abs=1e-15)
        assert A2 / A1 == pytest.approx(K * math.sqrt(f_drift(sigma) / f_drift(tau)), rel=1e-12)
    # the delay follows the mode: half a local period, longer as the mode slows down
    d = tv.delay(np.array([0.0, 0.5, 1.0]))
    assert d[0] < d[1] < d[2]
    assert 0.5 / (F0 * sq) < d[0] < 0.5 / (float(f_drift(d[0])) * sq)
    assert d[2] == pytest.approx(0.5 / (F1 * sq), rel=1e-12)


def test_tv_shaper_beats_zv_on_a_drifting_mode(al):
    """AL on a mode drifting 9 -> 6 Hz: the TV shaper leaves far less than a fixed ZV."""
    t_f = 1.2
    tv = shape_time_varying(al, TimeVaryingZV(f_drift, ZETA, 0.0, 2.0))
    start_rule = shape_time_varying(al, TimeVaryingZV(f_drift, ZETA, 0.0, 2.0, rule="start"))
    zv_end = shape(al, zv(F1, ZETA))   # tuned at the end of the motion, as the peers
    zv_start = shape(al, zv(F0, ZETA))
    r_al = residual_on_drifting_mode(al, t_f)
    r = {n: residual_on_drifting_mode(m, t_f) / r_al for n, m in
         [("TV", tv), ("start", start_rule), ("ZV end", zv_end), ("ZV start", zv_start)]}
    # measured: TV 4.9e-4, start rule 3.1e-2, ZV(end) 0.175, ZV(start) 0.48 of AL's residual
    assert r["TV"] < 1e-3
    assert r["TV"] < 0.01 * r["ZV end"] and r["TV"] < 0.01 * r["ZV start"]
    assert r["TV"] < 0.1 * r["start"] < r["ZV end"]
    assert r["ZV end"] > 0.1  # the drift does matter for a fixed shaper
    # the shaped reference ends at rest, at the time the last delay says
    x, v, a, _ = (float(q[0]) for q in tv.evaluate([tv.t_end + 1e-6]))
    assert v == pytest.approx(0.0, abs=1e-12) and a == 0.0
    assert tv.t_end == pytest.approx(al.t_end + float(TimeVaryingZV(
        f_drift, ZETA, 0.0, 2.0).delay(al.t_end)[()]), abs=1e-12)


def test_tv_shaper_refuses_a_span_too_short(al):
    with pytest.raises(ValueError, match="span"):
        shape_time_varying(al, TimeVaryingZV(f_drift, ZETA, 0.0, 0.95))
    with pytest.raises(ValueError, match="rule"):
        TimeVaryingZV(f_drift, ZETA, 0.0, 1.0, rule="magic")


# ------------------------------------------------------------ in a scenario


SMALL = """
name = "small"
[simulation]
t_after = 0.6
[move]
distance = 0.12
v_max = 0.4
a_max = 3.0
[z]
distance = 0.2
a_max = 4.0
v_max = 1.0
T_F = 0.03
[[mode]]
zeta = 0.02
law = "linear"
z = [0.0, 0.5]
f = [12.0, 9.0]
"""


@pytest.fixture(scope="module")
def small_sc():
    import tomllib

    return parse_scenario(tomllib.loads(SMALL), "small.toml")


def test_scenario_design_ends_on_target_and_follows_z(small_sc):
    """JL*TV-ZV on a moving mode: on target, at rest, Z synchronised with the shaped move."""
    with Session(engine="fast") as s:
        des = design_for_scenario(
            small_sc, s, lambda d: base_motion(small_sc, "JL", 0.1, d, session=s),
            name="JL*TV-ZV")
        v_z, synced = s.z_velocity(small_sc, des.motion.motion_time)
    m = des.motion
    assert m.distance == pytest.approx(0.12, abs=1e-12)
    assert abs(des.distance_correction) > 1e-5  # the delays would otherwise move the end
    assert abs(des.sync_mismatch) <= 1e-12 and synced
    x, v, a, _ = (float(q[0]) for q in m.evaluate([m.t_end + 1e-6]))
    assert v == pytest.approx(0.0, abs=1e-12) and a == 0.0
    # the delay at the start follows the mode at z0, the one at the end the mode near z_end
    f0, f_end = small_sc.modemap.tuned.f(0.0), small_sc.modemap.tuned.f(0.2)
    sq = math.sqrt(1 - 0.02 ** 2)
    assert float(des.shaper.delay(des.base.t_start)[()]) == pytest.approx(0.5 / (f0 * sq),
                                                                          rel=2e-3)
    assert float(des.shaper.delay(des.base.t_end)[()]) == pytest.approx(0.5 / (f_end * sq),
                                                                        rel=2e-3)


# ------------------------------------------------------------ shapers on JL


@pytest.mark.parametrize("name", ["ZV", "ZVD", "EI"])
def test_shaper_impulses_sum_to_one(name):
    s = make_shaper(name, 6.59, ZETA)
    assert s.A.sum() == pytest.approx(1.0, abs=1e-12)


def test_shaped_jl_is_a_numpy_convolution(jl):
    """JL*ZV sampled on a fine grid equals np.convolve of the JL's samples with the impulses."""
    h = 2.5e-4
    m_delay = 300  # half damped period = 75 ms, a whole number of grid steps
    f = 1.0 / (2 * m_delay * h * math.sqrt(1 - ZETA ** 2))
    sh = zv(f, ZETA)
    assert sh.t[1] == pytest.approx(m_delay * h, abs=1e-15)
    shaped = shape(jl, sh, name="JL*ZV")
    t = h * np.arange(int(1.6 / h))
    a_jl = jl.evaluate(t)[2]
    kernel = np.zeros(m_delay + 1)
    kernel[0], kernel[-1] = sh.A
    np.testing.assert_allclose(shaped.evaluate(t)[2], np.convolve(a_jl, kernel)[:t.size],
                               rtol=0, atol=1e-9)
    assert shaped.distance == pytest.approx(jl.distance, abs=1e-12)
    # on the design mode it leaves nothing (the ZV residual, 0); JL alone does leave some
    r_jl = residual_amplitude(jl, f, ZETA)
    assert r_jl > 1e-5 and residual_amplitude(shaped, f, ZETA) < 1e-9 * r_jl


def test_peer_jl_shapers_are_the_fmu_jl_convolved(small_sc, fmu2):
    """build_peers' JL*ZVD is Σ A_i a_JL(t - t_i) with the FMU's JL (planned independently)."""
    T_F = 0.1
    b = build_peers(small_sc, T_F, 0.6, peers=("JL*ZVD",), fmu=fmu2)
    mot, spec = b["JL*ZVD"]
    m = small_sc.move
    tr = generate({"profile": 2, "distance": m.distance, "v_max": m.v_max, "a_max": m.a_max,
                   "d_max": m.d_max, "Te": 1e-3, "short_stage": small_sc.simulation.short_stage,
                   "T_F1": T_F, "T_F2": T_F, "T_F3": T_F, "T_F4": T_F}, fmu=fmu2)
    jl = from_fmu(tr).to_motion()
    A, ti = np.asarray(spec.params["A"]), np.asarray(spec.params["t"])
    assert A.sum() == pytest.approx(1.0, abs=1e-12) and A.size == 3
    t = np.linspace(0.0, 1.0, 4001)
    exp = sum(Ai * jl.evaluate(t - tk)[2] for Ai, tk in zip(A, ti, strict=True))
    np.testing.assert_allclose(mot.evaluate(t)[2], exp, rtol=0, atol=1e-9)
    assert mot.t_end == pytest.approx(jl.t_end + ti[-1], abs=1e-12)
    f_end = small_sc.modemap.tuned.f(0.2)
    assert spec.params["f"] == pytest.approx(f_end)
