"""The co-simulation master: two generator FMUs (FMI 2 and 3) and the scheduled plant."""

from __future__ import annotations

import dataclasses
import math
import shutil

import matplotlib.pyplot as plt
import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicHermiteSpline

from harness.evaluation import profile_metrics
from harness.fmu.runner import generate
from harness.metrics import residual_peak, settling_time
from harness.modemap import ConstantLaw, ModeMap, ModeSpec
from harness.plant import Mode, free_amplitude
from harness.results import ScenarioResult, SweepResult, format_table2
from harness.scenario import load_scenario
from harness.simulation.master import cosimulate
from harness.simulation.session import Session
from harness.sweeps import run_scenario
from harness.tuning.tune import tune_profile


def short(name: str, t_after: float = 1.0, **sim):
    sc = load_scenario(name)
    return dataclasses.replace(sc, simulation=dataclasses.replace(sc.simulation,
                                                                  t_after=t_after, **sim))


def ivp_deflection(run, spec: ModeSpec, t_stop: float):
    """ε of the time-varying ODE with ω(t) = 2π f(z(t)), DOP853, rtol 1e-11.

    q̈(t) = a_k + j_k (t - t_k) on each sample interval: the generator's own semantics (a at
    the sample, j over the interval that starts there), with AL's acceleration steps as
    steps, not ramps.  The integration restarts at every sample where the jerk changes or the
    acceleration jumps, so the solver never steps over a kink.  z(t) is the cubic Hermite
    spline of (z, v_z) (exact: the Z reference is cubic per sample).
    """
    t = run.t
    h = float(t[1] - t[0])
    zs = CubicHermiteSpline(t, run.z, run.v_z)

    # kinks: the jerk changes, or the acceleration is not continuous (AL's steps)
    jumps = np.abs(run.a[1:] - (run.a[:-1] + run.j[:-1] * h)) > 1e-9 * max(1.0, np.max(
        np.abs(run.a)))
    kinks = t[np.flatnonzero((np.diff(run.j) != 0) | jumps) + 1]
    edges = sorted({0.0, t_stop, *[k for k in kinks.tolist() if k < t_stop]})
    y = np.zeros(2)
    out = {}
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        k0, k1 = int(round(lo / h)), int(round(hi / h)) - 1

        def rhs_piece(tt, y, k0=k0, k1=k1):
            # inside (lo, hi) the input is one polynomial per sample; take the sample of tt but
            # never the one after hi (the solver may probe hi exactly)
            k = min(max(int(math.floor(tt / h + 1e-9)), k0), k1)
            w = 2 * math.pi * spec.f(float(zs(tt)))
            return [y[1], -2 * spec.zeta * w * y[1] - w * w * y[0]
                    - (run.a[k] + run.j[k] * (tt - t[k]))]

        sol = solve_ivp(rhs_piece, (lo, hi), y, method="DOP853", rtol=1e-11, atol=1e-15,
                        max_step=0.01, dense_output=True)
        y = sol.y[:, -1]
        sel = (t >= lo) & (t <= hi)
        for k in np.flatnonzero(sel):
            out[k] = sol.sol(t[k])
    idx = np.array(sorted(out))
    return idx, np.array([out[k] for k in idx]).T


@pytest.mark.parametrize("name, profile", [("X", "JL"), ("X", "DJL"), ("Y", "DJL"),
                                           ("Y", "AL")])
def test_cosimulated_deflection_matches_solve_ivp(fmu2, name, profile):
    """The co-simulation's scheduled plant against an independent high-accuracy solution of
    the same time-varying ODE: residual amplitude within 1 % (in fact ~1e-5)."""
    sc = short(name, t_after=0.3)
    with Session(fmu2) as s:
        tun = tune_profile(s, sc, profile)
        run = s.run(sc, profile, tun.T_F if tun else None)
    spec = sc.modemap.tuned
    idx, (eps, deps) = ivp_deflection(run, spec, run.t_end + 0.3)
    assert np.max(np.abs(run.eps[idx] - eps)) <= 1e-4 * np.max(np.abs(eps))
    k = int(round(run.t_end / run.step))
    A_ref = free_amplitude(eps[k], deps[k], spec.at(run.z[k]))
    assert run.free_amplitude == pytest.approx(A_ref, rel=1e-2)
    assert run.free_amplitude == pytest.approx(A_ref, rel=1e-4)
    tail = idx[idx >= k]
    assert residual_peak(run.t, run.eps, run.t_end) == pytest.approx(
        np.max(np.abs(eps[tail - idx[0]])), rel=1e-2)


def test_fmi2_and_fmi3_cosimulations_agree(fmus):
    sc = short("Y", t_after=0.5)
    runs = {}
    for v in (2, 3):
        with Session(fmus[v]) as s:
            assert s.axis.fmi_version == v
            runs[v] = s.run(sc, "DJL", (0.095, 0.104, 0.104, 0.13))
    np.testing.assert_array_equal(runs[2].x, runs[3].x)
    np.testing.assert_array_equal(runs[2].z, runs[3].z)
    np.testing.assert_allclose(runs[2].eps, runs[3].eps, atol=1e-15)
    assert runs[3].fmi_version == 3


def test_reference_is_the_generator_output_and_z_is_synchronised(fmu3):
    sc = short("X", t_after=0.2)
    T_F = (0.118, 0.12, 0.142, 0.147)
    with Session(fmu3) as s:
        run = s.run(sc, "DJL", T_F)
    tr = generate(Session.move_params(sc, "DJL", T_F), fmu=fmu3, t_stop=run.t[-1])
    np.testing.assert_array_equal(run.x, tr.x)
    np.testing.assert_array_equal(run.a, tr.a)
    assert run.motion_time == pytest.approx(tr.motion_time)
    assert run.N_F == tr.N_F
    # Z starts and ends with the excited axis (not later), at its target
    assert run.z_synced
    assert run.t_end - 0.02 <= run.z_t_end <= run.t_end + 1e-9
    assert run.z[-1] == pytest.approx(sc.z.z0 + sc.z.distance, abs=1e-12)
    assert run.z[0] == sc.z.z0
    ztr = generate(Session.z_move_params(sc, run.z_v_max), fmu=fmu3, t_stop=run.t[-1])
    np.testing.assert_array_equal(run.z, ztr.x)
    # the mode frequency follows z
    np.testing.assert_allclose(run.f[0], [sc.modemap.tuned.f(z) for z in run.z])


def test_user_supplied_fmu_file(tmp_path, fmu2):
    path = tmp_path / "some_generator.fmu"
    shutil.copy(fmu2, path)
    res = run_scenario(short("Y", t_after=0.3), fmu=path)
    assert isinstance(res, ScenarioResult)
    assert str(path) in res.header()


def test_step_must_be_a_multiple_of_Te_and_coarser_steps_work(fmu2):
    sc = short("X", t_after=0.5)
    with Session(fmu2) as s:
        params = Session.move_params(sc, "JL", (0.15,) * 4)
        zp = Session.z_move_params(sc, 0.6)

        def planned_run(t_stop, step):
            # the master takes planned axes; an FMU axis is re-planned before each run
            s.axis.plan(params)
            s.z_axis.plan(zp)
            return cosimulate(s.axis, s.z_axis, sc.modemap.scheduled(), t_stop, step)

        with pytest.raises(ValueError, match="multiple"):
            planned_run(1.0, 0.0015)
        fine = planned_run(1.6, 0.001)
        coarse = planned_run(1.6, 0.004)
    assert coarse.t[1] == pytest.approx(0.004)
    # first-order hold between communication points: close to the exact 1 ms result
    np.testing.assert_allclose(coarse.eps, fine.eps[::4], atol=2e-3 * np.max(np.abs(fine.eps)))
    assert coarse.free_amplitude == pytest.approx(fine.free_amplitude, rel=0.05)


def test_two_modes_add_up(fmu2):
    sc = short("Y", t_after=0.3)
    mm = ModeMap((sc.modemap.modes[0], ModeSpec(ConstantLaw(30.0), 0.02, gain=0.2, name="30 Hz")))
    sc2 = dataclasses.replace(sc, modemap=mm)
    with Session(fmu2) as s:
        run = s.run(sc2, "JL", (0.135,) * 4)
    assert run.eps_modes.shape == (2, run.t.size)
    np.testing.assert_allclose(run.eps, run.eps_modes.sum(axis=0), atol=1e-16)
    assert run.f[1] == pytest.approx(np.full(run.t.size, 30.0))
    assert len(run.free_amplitudes) == 2
    assert run.modes_end[1] == Mode(30.0, 0.02, 0.2)


def _amplitude_from_samples(run, spec: ModeSpec) -> float:
    """Free-oscillation amplitude at the end of the motion, read off the sampled deflection
    alone: max |ε(t)| e^{σ(t - t_end)} over 1.5 periods after the end (one mode, Z at rest
    by then, so the free oscillation is A e^{-στ} cos(ω_d τ - φ)); 2e-4 relative at 1 ms."""
    m = spec.at(float(run.z[-1]))
    sel = (run.t >= run.t_end - 1e-12) & (run.t <= run.t_end + 1.5 / m.f)
    return float(np.max(np.abs(run.eps[sel]) * np.exp(m.sigma * (run.t[sel] - run.t_end))))


def _check_settling(run, band: float, ts: float) -> None:
    """ts is the last exit of |load - target| from ±band, on the record or past it."""
    err = np.abs(run.x + run.eps - run.target)
    if math.isfinite(ts) and run.t_start + ts < run.t[-1]:
        # inside the band from then on, outside just before
        assert np.all(err[run.t >= run.t_start + ts + 1e-9] <= band * (1 + 1e-9))
        assert np.any(err[(run.t < run.t_start + ts) & (run.t > run.t_start + ts - 0.05)]
                      > band * 0.999)
    else:
        # past the record: the free oscillation's envelope A e^{-στ} is at or above the band
        # when the load last leaves it, and below it (to the phase of the peaks) half a
        # period later
        assert run.z_synced and run.t[-1] < run.t_start + ts < math.inf
        (e, de), m = run.state_end[0], run.modes_end[0]
        A = free_amplitude(e, de, m)
        env = lambda t: A * math.exp(-m.sigma * (t - run.t_end))  # noqa: E731
        assert env(run.t_start + ts) >= band * (1 - 1e-9)
        assert env(run.t_start + ts + 0.5 / m.f) <= band * 1.01


def test_run_scenario_is_one_call_and_its_metrics_are_right(tmp_path, fmu2):
    res = run_scenario(short("X", t_after=2.0), fmu=fmu2)
    # a single move also gets the profile that settles first under uncertainty
    assert list(res.profiles) == ["AL", "JL", "DJL", "recommended"]
    spec = res.scenario.modemap.tuned
    amp = {n: _amplitude_from_samples(p.run, spec) for n, p in res.profiles.items()}
    for n, p in res.profiles.items():
        r = p.run
        # the residual is the free-oscillation amplitude at the end of the motion ...
        assert p.metrics.residual == pytest.approx(amp[n], rel=5e-4)
        assert p.metrics.residual == r.free_amplitude == p.metrics.free_amplitude
        # ... the sampled peak after the motion is kept beside it, and is below it
        peak = np.max(np.abs(r.eps[r.t >= r.t_end - 1e-12]))
        assert p.metrics.residual_peak == pytest.approx(peak)
        assert peak < p.metrics.residual
        assert p.metrics.motion_time == pytest.approx(r.t_end - r.t_start)
    # one band for every profile, by default 1 % of AL's residual; and the paper's, DJL's
    assert res.band == pytest.approx(0.01 * amp["AL"], rel=5e-4)
    assert res.paper_band == pytest.approx(amp["DJL"], rel=5e-4)
    assert "1 % of AL" in res.band_source
    for p in res.profiles.values():
        assert p.metrics.band == res.band and p.metrics.paper_band == res.paper_band
        _check_settling(p.run, res.band, p.metrics.settling_time)
        _check_settling(p.run, res.paper_band, p.metrics.settling_time_paper)
    djl = res.profiles["DJL"]
    # the paper's band is DJL's own residual: DJL is inside it as soon as its motion ends ...
    assert djl.metrics.settling_time_paper <= djl.metrics.motion_time + 1e-9
    # ... but needs another second to settle into the fixed band
    assert djl.metrics.settling_time > djl.metrics.motion_time + 0.5
    # the paper's ordering on this axis: JL and DJL leave far less than AL
    assert res.metric("JL", "residual") < 0.3 * res.metric("AL", "residual")
    assert res.metric("DJL", "residual") < res.metric("JL", "residual")
    text = res.table()
    for row in ("Residual vibration [mm]", "Motion time", "(100 %)",
                "peak |ε| after the motion (sampled)",
                "Settling time [s] (band: 1 % of AL's residual)",
                "Settling time [s] (the paper's band: DJL's residual)"):
        assert row in text
    # run_scenario computes the map-error curves of a single move by default
    assert "Worst residual, map error +/-10 %" in text
    for n, p in res.profiles.items():
        assert p.worst_residual_10pct == pytest.approx(res.robustness.worst()[n], rel=1e-12)
        assert p.worst_residual_10pct >= p.metrics.residual
    path = res.to_csv(tmp_path / "x.csv")
    lines = path.read_text().splitlines()
    assert len(lines) == 5 and lines[0].startswith("scenario,profile")
    import csv

    rows = list(csv.DictReader(path.open()))
    for col in ("residual_m", "residual_pct_of_AL", "free_amplitude_m", "residual_peak_m",
                "settling_time_s", "settling_time_paper_band_s", "band_m", "band_source",
                "paper_band_m", "residual_worst_map10_m", "residual_worst_map10_pct_of_AL"):
        assert col in rows[0], col
    for row, p in zip(rows, res.profiles.values(), strict=True):
        assert float(row["residual_m"]) == pytest.approx(p.metrics.residual, rel=1e-9)
        assert row["residual_m"] == row["free_amplitude_m"]
        assert float(row["settling_time_paper_band_s"]) == pytest.approx(
            p.metrics.settling_time_paper, rel=1e-9)
        assert "1 % of AL" in row["band_source"]
    fig = res.plot()
    assert len(fig.axes) >= 8
    plt.close(fig)


def test_undamped_mode_settles_into_djls_own_band_only(tmp_path, fmu2):
    """ζ = 0: the free oscillation never decays.  In the paper's band (DJL's residual) DJL is
    inside from the end of its motion and a profile leaving more never settles; in the
    fixed band (1 % of AL's residual) every profile leaving more than it never settles."""
    from harness.metrics import SettleBand

    sc = short("Y", t_after=0.5)
    sc = dataclasses.replace(sc, modemap=ModeMap((ModeSpec(ConstantLaw(12.0), 0.0),)))
    res = run_scenario(sc, fmu=fmu2)
    djl, al = res.profiles["DJL"], res.profiles["AL"]
    assert djl.metrics.settling_time_paper <= djl.metrics.motion_time + 1e-9
    assert al.metrics.residual > res.paper_band
    assert al.metrics.settling_time_paper == math.inf
    for p in res.profiles.values():
        assert (p.metrics.settling_time == math.inf) == (p.metrics.residual > res.band)
    assert al.metrics.settling_time == math.inf
    # settle_band = "paper": the case's band is the paper's, labelled so
    sc2 = dataclasses.replace(sc, simulation=dataclasses.replace(
        sc.simulation, settle_band=SettleBand("paper")))
    res2 = run_scenario(sc2, fmu=fmu2)
    assert res2.band == res2.paper_band == pytest.approx(res.paper_band, rel=1e-12)
    assert res2.profiles["DJL"].metrics.settling_time == pytest.approx(
        djl.metrics.settling_time_paper, abs=1e-12)
    assert res2.band_source == "the paper's band: DJL's residual"
    assert "Settling time [s] (the paper's band: DJL's residual)" in res2.table()


def test_settling_beyond_the_record_is_extended_analytically(fmu2):
    """A short record is continued with the free response: same settling time as a long one."""
    long_ = run_scenario(short("X", t_after=4.0), fmu=fmu2)
    with Session(fmu2) as s:
        sc = short("X", t_after=0.3)
        run = s.run(sc, "AL")
    m_short = profile_metrics(run, long_.band)
    m_long = long_.profiles["AL"].metrics
    assert run.t[-1] < m_long.settling_time  # the short record ends before AL settles
    assert m_short.settling_time == pytest.approx(m_long.settling_time, abs=1.5e-3)
    # and directly on the long record
    r = long_.profiles["AL"].run
    assert settling_time(r.t, r.error, long_.band, r.t_start) == pytest.approx(
        m_long.settling_time, abs=1e-9)


def test_small_sweep_and_table2(fmu2, tmp_path):
    sc = short("sweep-Y", t_after=1.0)
    sc = dataclasses.replace(sc, sweep=dataclasses.replace(sc.sweep, distance=(0.3,),
                                                           z_distance=(0.2, 0.45), v_max=(2.0,)))
    res = run_scenario(sc, fmu=fmu2)
    assert isinstance(res, SweepResult) and len(res.cases) == 2
    r, s = res.changes()
    for c, rr in zip(res.cases, r, strict=True):
        jl, djl = c.metric("JL", "residual"), c.metric("DJL", "residual")
        assert rr == pytest.approx(100 * (djl - jl) / jl)
    st = res.stats()
    assert st["residual"].mean == pytest.approx(np.mean(r))
    assert st["settling"].std == pytest.approx(np.std(s, ddof=1))
    assert "Mean value" in format_table2([res])
    assert len(res.to_csv(tmp_path / "sw.csv").read_text().splitlines()) == 1 + 2 * 3
    plt.close(res.plot())


def test_fmu_axis_points_always_start_from_the_planned_move(fmu2):
    """A second points() on an already stepped FMU axis replays the move from its start (an
    FMU only steps forward: without the re-plan the second run would silently be shifted)."""
    from harness.simulation.fmu_axis import FMUAxis

    params = {"profile": 2, "distance": 0.1, "v_max": 0.5, "a_max": 4.0, "T_F1": 0.05}
    with FMUAxis(fmu2) as ax:
        ax.plan(params)
        a = ax.points(300, 1e-3)
        b = ax.points(300, 1e-3)
        s = ax.sample(params)
        c = ax.points(300, 1e-3)
    for name in ("x", "v", "a", "j"):
        np.testing.assert_array_equal(a.values[name], b.values[name])
        np.testing.assert_array_equal(a.values[name], c.values[name])
    np.testing.assert_array_equal(a.t, b.t)
    assert a.values["x"][-1] > 0.09 and s.x[-1] == pytest.approx(0.1, abs=1e-12)
