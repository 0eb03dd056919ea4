"""The remainder the paper's tuning rule leaves (harness.tuning.remainder), against simulation.

Independent references: ``scipy.integrate.solve_ivp`` (DOP853, split at every
kink of the input) on ε̈ + 2ζω(t)ε̇ + ω(t)²ε = −q̈ for one ramp, a drifting
mode and a four-stage move; the co-simulation harness (fast engine) for the
default scenarios X and Y and for a constant mode.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from harness.modemap import ConstantLaw, ModeMap, ModeSpec
from harness.scenario import load_scenario
from harness.simulation.axis import stage_starts
from harness.simulation.session import Session
from harness.tuning import remainder as rm
from harness.tuning.rule import sinc_residual
from harness.tuning.tune import tune_profile

A = 4.0  # acceleration step (m/s2)


def ramp_state(T: float, omega, zeta: float, t_stop: float | None = None):
    """(ε, ε̇) at ``t_stop`` (default T) after a ramp 0 -> A over [0, T], solve_ivp.

    ``omega`` is a constant (rad/s) or a function of time.
    """
    w_of = omega if callable(omega) else (lambda t: omega)
    j = A / T

    def rhs(t, y):
        w = w_of(t)
        u = j * t if t < T else A
        return [y[1], -2.0 * zeta * w * y[1] - w * w * y[0] - u]

    t_stop = T if t_stop is None else t_stop
    y = np.zeros(2)
    for a, b in ((0.0, T), (T, t_stop)):
        if b > a:
            y = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=1e-12, atol=1e-18).y[:, -1]
    return float(y[0]), float(y[1])


def w_of_state(e: float, de: float, w: float, zeta: float, a_final: float,
               equilibrium_rate: float = 0.0) -> complex:
    """Complex free oscillation (ε̇ + σE)/ω_d + iE about −a/ω² (the module's convention).

    ``equilibrium_rate``: d(1/ω²)/dt, to measure about a moving equilibrium.
    """
    E = e + a_final / w**2
    dE = de + a_final * equilibrium_rate
    wd = w * math.sqrt(1.0 - zeta**2)
    return (dE + zeta * w * E) / wd + 1j * E


# ------------------------------------------------------------ one stage


@pytest.mark.parametrize("zeta", [0.0, 0.03, 0.1])
@pytest.mark.parametrize("ratio", [0.3, 0.8, 1.0, 1.3, 2.0, 2.5])
def test_stage_phasor_matches_ivp(ratio, zeta):
    f = 7.0
    w = 2 * np.pi * f
    T = ratio / f
    e, de = ramp_state(T, w, zeta)
    sim = w_of_state(e, de, w, zeta, A) / (A / (w * w * math.sqrt(1 - zeta**2)))
    rho = complex(rm.stage_phasor(T, f, zeta))
    assert abs(sim - rho) < 1e-8
    assert abs(rm.stage_remainder(T, f, zeta) - abs(sim)) < 1e-8


def test_stage_remainder_is_the_sinc_and_eq20():
    T = np.linspace(0.01, 0.4, 40)
    for Ti in T:
        assert rm.stage_remainder(Ti, 9.0, 0.0) == pytest.approx(sinc_residual(Ti, 1 / 9.0),
                                                               abs=1e-14)
    # eq. 20 written out, divided by its T_F -> 0 limit (omega a_max)
    w, z = 2 * np.pi * 9.0, 0.05
    wd = w * math.sqrt(1 - z * z)
    eq20 = np.sqrt(1 + np.exp(-2 * z * w * T) - 2 * np.exp(-z * w * T) * np.cos(wd * T)) / T / w
    assert np.allclose(rm.stage_remainder(T, 9.0, z), eq20, rtol=1e-12)
    assert rm.stage_remainder(0.0, 9.0, z) == pytest.approx(1.0)


@pytest.mark.parametrize("zeta", [0.01, 0.03, 0.04, 0.1])
def test_period_leaves_about_zeta(zeta):
    f = 8.0
    w = 2 * np.pi * f
    e, de = ramp_state(1 / f, w, zeta)
    sim = abs(w_of_state(e, de, w, zeta, A)) / (A / (w * w * math.sqrt(1 - zeta**2)))
    closed = -math.expm1(-2 * math.pi * zeta) / (2 * math.pi)
    assert sim == pytest.approx(float(rm.stage_remainder(1 / f, f, zeta)), abs=1e-9)
    # (1 - e^{-2 pi zeta})/(2 pi) + zeta^3/8 + O(zeta^4)
    assert abs(sim - closed - zeta**3 / 8) <= zeta**4
    assert float(rm.stage_remainder_first_order(1 / f, f, zeta)) == pytest.approx(zeta, rel=1e-12)
    # the "about zeta A/omega^2": right to first order, high by pi*zeta
    assert abs(sim / zeta - (1 - math.pi * zeta)) < 3 * (math.pi * zeta) ** 2


def test_first_order_in_zeta_error_is_quadratic():
    f = 6.0
    ratios = np.array([0.5, 0.9, 1.0, 1.1, 1.7, 2.0, 2.6])
    errs = []
    for zeta in (0.04, 0.02, 0.01):
        sims = []
        for r in ratios:
            e, de = ramp_state(r / f, 2 * np.pi * f, zeta)
            w = 2 * np.pi * f
            sims.append(abs(w_of_state(e, de, w, zeta, A)) / (A / (w * w * math.sqrt(1 - zeta**2))))
        errs.append(np.max(np.abs(rm.stage_remainder_first_order(ratios / f, f, zeta)
                                  - np.array(sims))))
    assert errs[0] < 12 * 0.04**2
    assert 0.15 < errs[1] / errs[0] < 0.35
    assert 0.15 < errs[2] / errs[1] < 0.35


@pytest.mark.parametrize("zeta", [0.03, 0.04, 0.1])
def test_no_jerk_time_cancels_a_damped_mode(zeta):
    f = 5.0
    w = 2 * np.pi * f
    Td = 1 / (f * math.sqrt(1 - zeta**2))
    e, de = ramp_state(Td, w, zeta)
    sim = abs(w_of_state(e, de, w, zeta, A)) / (A / (w * w * math.sqrt(1 - zeta**2)))
    assert sim == pytest.approx(float(rm.damped_period_remainder(zeta)), rel=1e-8)
    T_opt, r_min = rm.optimal_jerk_time(f, zeta)
    # first orders: T_d (1 + pi zeta^3), depth (1 - e^{-2 pi zeta})/(2 pi)
    assert T_opt == pytest.approx(Td * (1 + math.pi * zeta**3), rel=5 * zeta**4)
    assert r_min == pytest.approx(-math.expm1(-2 * math.pi * zeta) / (2 * math.pi),
                                  abs=3 * zeta**4)
    # the simulation agrees that it is a minimum, and that it is not zero
    vals = []
    for T in (T_opt * (1 - 2e-3), T_opt, T_opt * (1 + 2e-3)):
        e, de = ramp_state(T, w, zeta)
        vals.append(abs(w_of_state(e, de, w, zeta, A)) / (A / (w * w * math.sqrt(1 - zeta**2))))
    assert vals[1] < vals[0] and vals[1] < vals[2]
    assert vals[1] == pytest.approx(r_min, rel=1e-7)
    assert r_min > 0.9 * zeta * (1 - math.pi * zeta)
    # the second minimum (two periods) is hardly deeper
    _, r2 = rm.optimal_jerk_time(f, zeta, cycles=2)
    assert r2 == pytest.approx(-math.expm1(-4 * math.pi * zeta) / (4 * math.pi),
                               abs=6 * zeta**4)
    assert r2 > 0.75 * r_min


# ------------------------------------------------------------ drift in a stage


def drift_sim(x: float, delta: float, zeta: float, reference: str, f0: float = 10.0) -> complex:
    """Normalised remainder of a ramp of x/omega0 on a mode drifting linearly by delta."""
    w0 = 2 * np.pi * f0
    T = x / w0
    rate = delta * w0 / T

    def omega(t):
        return w0 + rate * t

    e, de = ramp_state(T, omega, zeta)
    w1 = omega(T)
    eq_rate = -2 * rate / w1**3 if reference == "moving" else 0.0
    wd0 = w0 * math.sqrt(1 - zeta**2)
    return w_of_state(e, de, w1, zeta, A, eq_rate) / (A / (w0 * wd0))


@pytest.mark.parametrize("reference", ["moving", "frozen"])
@pytest.mark.parametrize("x", [2 * np.pi, 0.8 * 2 * np.pi, 1.3 * 2 * np.pi, 4 * np.pi])
def test_drift_phasor_first_order(x, reference):
    f0 = 10.0
    T = x / (2 * np.pi * f0)
    errs = []
    for s in (1.0, 0.5, 0.25):
        delta, zeta = -0.04 * s, 0.03 * s
        sim = drift_sim(x, delta, zeta, reference, f0)
        form = complex(rm.drift_phasor(T, f0, f0 * (1 + delta), zeta, reference=reference))
        errs.append(abs(sim - form))
    assert errs[0] < 8 * 0.04**2
    # second-order error: halving delta and zeta divides it by about 4
    assert 0.15 < errs[1] / errs[0] < 0.35
    assert 0.15 < errs[2] / errs[1] < 0.35


@pytest.mark.parametrize("reference", ["moving", "frozen"])
def test_drift_coefficient_at_the_start_rule(reference):
    c = rm.DRIFT_COEFFICIENT[reference]
    for delta in (0.004, 0.002):
        up = abs(drift_sim(2 * np.pi, delta, 0.0, reference))
        down = abs(drift_sim(2 * np.pi, -delta, 0.0, reference))
        # the odd O(delta^2) term cancels in the mean of +delta and -delta
        assert 0.5 * (up + down) / delta == pytest.approx(c, rel=2e-3)
    # the accumulated phase alone (eq. 21 with the phase int omega dt) is not enough
    assert c > 1.25 * rm.DRIFT_COEFFICIENT["phase_only"]
    assert float(rm.drift_remainder(0.1, 10.0, 10.0 * 0.99, reference=reference)) == \
        pytest.approx(0.01 * c, rel=1e-12)


def test_claim4_numbers_follow_from_the_drift_formula():
    # claim 4 (docs/claims.md): +-9 % over a 10 Hz stage tuned to the start period leaves
    # 9.8 % and 6.4 % of an AL step on the same moving mode (frozen reference at the end)
    f0, T = 10.0, 0.1
    w0 = 2 * np.pi * f0
    out = {}
    for delta in (-0.09, 0.09):
        def omega(t, d=delta):
            return w0 * (1 + d * min(t / T, 1.0))

        w1 = omega(T)
        e, de = ramp_state(T, omega, 0.0)
        e_al, de_al = ramp_state(1e-9, omega, 0.0, t_stop=T)  # the unfiltered step
        out[delta] = (abs(w_of_state(e, de, w1, 0.0, A))
                      / abs(w_of_state(e_al, de_al, w1, 0.0, A)))
    assert out[-0.09] == pytest.approx(0.098, abs=0.0006)
    assert out[0.09] == pytest.approx(0.064, abs=0.0006)
    # their mean is the first-order coefficient (the O(delta^2) term is odd); the phase
    # alone (the paper's reasoning, claim 4's estimate) would give 4.5 %
    mean = 0.5 * (out[-0.09] + out[0.09])
    assert mean == pytest.approx(0.09 * rm.DRIFT_COEFFICIENT["frozen"], rel=0.05)
    assert mean > 1.6 * 0.09 * rm.DRIFT_COEFFICIENT["phase_only"]


@pytest.mark.parametrize("reference", ["moving", "frozen"])
@pytest.mark.parametrize("delta", [-0.04, 0.04])
def test_phase_rule_cancels_the_phase_term_only(delta, reference):
    f0 = 1.0
    w0 = 2 * np.pi * f0
    rate = delta * w0  # the mode drifts by delta over one start-rule period

    def remainder(T: float) -> float:
        e, de = ramp_state(T, lambda t: w0 + rate * t, 0.0)
        w1 = w0 + rate * T
        eq_rate = -2 * rate / w1**3 if reference == "moving" else 0.0
        return abs(w_of_state(e, de, w1, 0.0, A, eq_rate)) / (A / w0**2)

    # the phase rule: int_0^T omega dt = 2 pi
    T_phase = (-w0 + math.sqrt(w0 * w0 + 4 * math.pi * rate)) / rate
    assert T_phase == pytest.approx((1 - delta / 2) / f0, rel=delta**2)
    c = rm.PHASE_RULE_COEFFICIENT[reference]
    r_phase = remainder(T_phase)
    assert r_phase == pytest.approx(c * abs(delta), rel=0.15)
    # ... and no jerk time does much better: the compliance term is in quadrature
    Ts = T_phase * (1 + np.linspace(-0.02, 0.02, 41))
    r = np.array([remainder(T) for T in Ts])
    assert r.min() > 0.85 * c * abs(delta)
    assert r.min() > 0.97 * r_phase
    # while the start rule leaves the full first-order coefficient
    assert remainder(1 / f0) == pytest.approx(rm.DRIFT_COEFFICIENT[reference] * abs(delta),
                                              rel=0.15)


# ------------------------------------------------------------ four stages

AMPS = [4.0, -4.0, -4.0, 4.0]
STARTS = [0.0, 0.30, 0.80, 1.10]
TF = [0.12, 0.12, 0.14, 0.15]
T_END = 1.25


def _acc(t):
    return sum(a * np.clip((t - s) / T, 0.0, 1.0) for a, s, T in zip(AMPS, STARTS, TF,
                                                                         strict=True))


def _freq(t, k, f0=8.5):
    u = np.clip(np.asarray(t) / T_END, 0.0, 1.0)
    return f0 * (1.0 - k * (3 * u * u - 2 * u**3))  # drifts by -k, at rest at both ends


def _ivp_move(k: float, zeta: float) -> complex:
    kinks = sorted(set([0.0, T_END] + STARTS + [s + T for s, T in zip(STARTS, TF, strict=True)]))

    def rhs(t, y):
        w = 2 * np.pi * float(_freq(t, k))
        return [y[1], -2 * zeta * w * y[1] - w * w * y[0] - float(_acc(t))]

    y = np.zeros(2)
    for a, b in zip(kinks[:-1], kinks[1:], strict=True):
        y = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=1e-11, atol=1e-16).y[:, -1]
    w = 2 * np.pi * float(_freq(T_END, k))
    return w_of_state(float(y[0]), float(y[1]), w, zeta, 0.0)


def test_moving_mode_residual_and_its_stage_split_against_ivp():
    zeta = 0.03
    t = np.linspace(0.0, T_END, 1251)
    al = 4.0 / (2 * np.pi * 8.5) ** 2
    errs = []
    for k in (0.3, 0.15):
        ref = _ivp_move(k, zeta)
        w = rm.moving_mode_residual(t, _acc(t), _freq(t, k), zeta)
        ph = rm.stage_phasors(t, _freq(t, k), zeta, STARTS, TF, AMPS, T_END)
        errs.append(abs(w - ref) / al)
        # the split is an identity (integration by parts), to quadrature error
        assert abs(ph.total - w) < 1e-4 * abs(w)
        # the residual is at most the sum of the magnitudes
        assert abs(ref) <= ph.bound
        assert 0.0 < ph.cancellation <= 1.0
    assert errs[0] < 1e-3  # of the AL level, with the mode falling by 30 %
    assert errs[1] < 0.5 * errs[0]  # first order in the slowness of the drift
    # a constant mode: the split is the exact closed form, the drift term vanishes
    ph0 = rm.stage_phasors(t, _freq(t, 0.0), zeta, STARTS, TF, AMPS, T_END)
    exact = rm.constant_mode_phasors(AMPS, STARTS, TF, 8.5, zeta, T_END)
    assert abs(ph0.drift) == 0.0
    assert np.max(np.abs(np.array(ph0.stages) - exact)) < 1e-5 * np.max(np.abs(exact))
    assert abs(exact.sum() - _ivp_move(0.0, zeta)) < 1e-6 * al


@pytest.fixture(scope="module")
def session():
    s = Session(engine="fast")
    yield s
    s.close()


def _with(sc, **kw):
    return dataclasses.replace(sc, compare=dataclasses.replace(sc.compare, **kw))


def test_constant_mode_four_stages_exact_in_the_harness(session):
    sc = load_scenario("X")
    sc = dataclasses.replace(sc, modemap=ModeMap((ModeSpec(ConstantLaw(7.0), zeta=0.03),)))
    T = (0.100, 0.125, 0.160, 0.090)
    move = session.axis.sample(Session.move_params(sc, "DJL", T))
    starts, _ = stage_starts(move)
    run = session.run(sc, "DJL", T)
    info = run.plan_info
    amps = [info["a_reached"], -info["a_reached"], -info["d_reached"], info["d_reached"]]
    w = rm.constant_mode_phasors(amps, starts, T, 7.0, 0.03, run.t_end)
    e, de = run.state_end[0]
    harness_w = w_of_state(e, de, run.modes_end[0].omega, 0.03, 0.0)
    assert abs(w.sum() - harness_w) < 1e-9 * abs(harness_w)
    assert run.free_amplitude <= np.abs(w).sum()
    assert run.free_amplitude <= rm.four_stage_bound(amps, T, [7.0] * 4, 0.03)


@pytest.mark.parametrize("name", ["X", "Y"])
def test_four_stages_in_the_default_scenarios(session, name):
    sc = load_scenario(name)
    zeta = sc.modemap.tuned.zeta
    out = {}
    for method in ("paper", "optimal", "robust"):
        sc_m = _with(sc, djl_tuning=method)
        tu = tune_profile(session, sc_m, "DJL")
        ph, run = rm.move_phasors(session, sc_m, tu.T_F)
        res = run.free_amplitude
        out[method] = (ph, res)
        # the WKB phasor sum reproduces the harness (first order: within 3 % of the
        # paper-rule residual, the scale of the neglected terms)
        if method == "paper":
            paper_res = res
        assert abs(ph.residual - res) < 0.03 * paper_res
        # the vector sum is at most the sum of the magnitudes
        assert res <= ph.bound
        # the closed-form bound: stage remainders at the local frequencies, from the
        # FMU's reached accelerations (drift in the stage and amplitude growth neglected:
        # an estimate, which holds here with a margin of 1.5 or more)
        move = session.axis.sample(Session.move_params(sc_m, "DJL", tu.T_F))
        starts, _ = stage_starts(move)
        T = [n * sc.simulation.Te for n in move.N_F]
        f_s = [float(np.interp(t0, run.t, run.f[0])) for t0 in starts]
        f_e = [float(np.interp(t0 + Ti, run.t, run.f[0])) for t0, Ti in zip(starts, T,
                                                                            strict=True)]
        info = run.plan_info
        amps = [info["a_reached"], -info["a_reached"], -info["d_reached"], info["d_reached"]]
        assert res * 1.5 <= rm.four_stage_bound(amps, T, f_s, zeta)
        assert res * 1.5 <= rm.four_stage_bound(amps, T, f_s, zeta, f_e)
    ph_p, res_p = out["paper"]
    ph_o, res_o = out["optimal"]
    # the paper's rule: remainders of a few % each, added with chance phases
    assert all(0.02 < r < 0.15 for r in ph_p.relative)
    assert res_p / ph_p.bound > 0.3
    # the optimal tuning makes the four contributions cancel
    assert res_o / ph_o.bound < 0.02
    assert ph_o.cancellation < 0.05
    # ... which hangs on their phases: stage 1's rotates by tens of rad until the end
    assert ph_o.phases[0] > 25.0 and ph_o.phases[3] == pytest.approx(0.0, abs=1e-9)
    sc_o = _with(sc, djl_tuning="optimal")
    tu_o = tune_profile(session, sc_o, "DJL")
    r = session.map_error_residuals(sc_o, "DJL", tu_o.T_F, [-0.01, 0.0, 0.01])
    assert min(r[0], r[2]) > 30 * r[1]
    sc_p = _with(sc, djl_tuning="paper")
    rp = session.map_error_residuals(sc_p, "DJL", tune_profile(session, sc_p, "DJL").T_F,
                                     [-0.01, 0.0, 0.01])
    assert max(rp[0], rp[2]) < 1.3 * rp[1]


def test_paper_rule_against_jl_is_decided_by_phases(session):
    # sweep-Y: DJL's stage remainders are smaller than JL's in every move (their sum of
    # magnitudes, the bound), yet DJL leaves more than JL in some moves: the phases decide
    sc = load_scenario("sweep-Y")
    smaller_bound = larger_residual = n = 0
    for case in sc.cases():
        if case.move.v_max != 2.0:
            continue
        n += 1
        tj, td = tune_profile(session, case, "JL"), tune_profile(session, case, "DJL")
        pj, rj = rm.move_phasors(session, case, tj.T_F, "JL")
        pd, rd = rm.move_phasors(session, case, td.T_F, "DJL")
        assert rd.free_amplitude <= pd.bound and rj.free_amplitude <= pj.bound
        smaller_bound += pd.bound < pj.bound
        larger_residual += rd.free_amplitude > rj.free_amplitude
    assert smaller_bound == n == 25
    assert larger_residual >= 3


def test_plot_jerk_times(session):
    import matplotlib

    matplotlib.use("Agg")
    results: dict[str, list] = {"paper": [], "optimal": []}
    for name in ("X", "Y"):
        sc = load_scenario(name)
        for m in results:
            results[m].append(tune_profile(session, _with(sc, djl_tuning=m), "DJL"))
    fig = rm.plot_jerk_times(results)
    ax = fig.axes[0]
    pts = [ln for ln in ax.lines if len(ln.get_xdata()) == 1]
    assert len(pts) == 2 * 2 * 4
    xs = sorted(float(ln.get_xdata()[0]) for ln in pts)
    assert xs[0] == pytest.approx(1e3 * min(min(tu.periods) for v in results.values()
                                            for tu in v))
    import matplotlib.pyplot as plt

    plt.close(fig)


def test_input_checks():
    with pytest.raises(ValueError):
        rm.stage_remainder(0.1, -1.0, 0.0)
    with pytest.raises(ValueError):
        rm.stage_remainder(0.1, 1.0, 1.0)
    with pytest.raises(ValueError):
        rm.drift_phasor(0.1, 10.0, 9.0, reference="sideways")
    with pytest.raises(ValueError):
        rm.stage_phasors([0, 1], [1, 1], 0.0, [0, 0.1, 0.2, 0.3], [0.1] * 4, [1, -1, -1, 0.5], 1)


def test_example_jerk_times_vs_periods(tmp_path, capsys):
    import runpy
    from pathlib import Path

    example = Path(__file__).resolve().parents[1] / "examples" / "jerk_times_vs_periods.py"
    mod = runpy.run_path(str(example), run_name="example")
    out = tmp_path / "jt.png"
    mod["main"](["--distances", "0.1", "--workers", "1", "--out", str(out)])
    text = capsys.readouterr().out
    assert "sweep-X: 5 moves tuned three ways" in text  # v_max = 0.5 and 2 plan the same moves
    assert out.stat().st_size > 10_000
