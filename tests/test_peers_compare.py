"""The comparison on a small scenario, and ``djl-fmu compare``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.cli import main
from harness.cosim import Session
from harness.peers.compare import (
    PEERS,
    build_peers,
    compare_scenario,
    cosimulate_reference,
    sato_design,
    stationary_variant,
)
from harness.peers.residual import residual_amplitude
from harness.peers.sato import sato_profile
from harness.peers.trajectory import PiecewiseJerk
from harness.scenario import parse_scenario

SMALL = """
name = "small"
description = "short move for the tests"
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
name = "m"
zeta = 0.02
law = "linear"
z = [0.0, 0.5]
f = [12.0, 9.0]
"""




@pytest.fixture(scope="module")
def small():
    import tomllib

    return parse_scenario(tomllib.loads(SMALL), "small.toml")


@pytest.fixture(scope="module")
def session(fmu2):
    with Session(fmu2) as s:
        yield s


@pytest.fixture(scope="module")
def comparison(small, session):
    return compare_scenario(small, session=session, errors=np.linspace(-0.2, 0.2, 9))


def test_reference_path_is_the_harness_plant(small, session):
    """Fed with the FMU's JL samples, cosimulate_reference gives the harness's deflection."""
    run = session.run(small, "JL", (0.1,) * 4)
    mot = PiecewiseJerk.from_samples(run.t, run.x, run.v, run.a, run.j)
    mine = cosimulate_reference(small, session, mot, "JL", t_stop=run.t[-1])
    np.testing.assert_allclose(mine.eps, run.eps, rtol=0, atol=1e-12 * np.abs(run.eps).max())
    np.testing.assert_allclose(mine.z, run.z, rtol=0, atol=1e-15)
    assert mine.t_end == pytest.approx(run.t_end)


def test_stationary_plant_matches_the_exact_residual(small, session):
    """Z still: every peer's free amplitude in the co-simulation is the exact residual."""
    st = stationary_variant(small)
    assert not st.z.moves and st.z.z0 == pytest.approx(0.2)
    f = st.modemap.tuned.f(st.z.z0)
    built = build_peers(st, 0.1, 0.6, fmi_version=2)
    assert list(built) == list(PEERS)
    scale = None
    for name, (mot, _) in built.items():
        run = cosimulate_reference(st, session, mot, name)
        k_end = math.ceil(mot.t_end / run.step - 1e-9)
        exact = residual_amplitude(mot, f, 0.02, t_ref=k_end * run.step)
        scale = scale or residual_amplitude(built["AL*ZV"][0].shifted(0.0), f * 1.3, 0.02)
        # piecewise-jerk laws are fed exactly; the damped jerk's exponential acceleration
        # is linear between samples (an error of order (ω Te)² of its jerk stages)
        assert run.free_amplitude == pytest.approx(exact, rel=1e-6, abs=1e-6 * scale), name


def test_comparison_table(comparison, small):
    c = comparison
    assert list(c.methods) == ["AL", "JL", "DJL", *PEERS]
    rows = {r["method"]: r for r in c.rows()}
    assert rows["AL"]["residual_pct_of_AL"] == pytest.approx(100.0)
    assert rows["time-optimal JL"]["motion_time_over_time_optimal"] == pytest.approx(1.0)
    # FIR-JL: time-optimal within a sample (a_max is reached on this move)
    assert rows["JL"]["motion_time_s"] - c.T_opt < 2e-3
    # shapers add their length to the AL motion
    Td = 1 / (c.f_end * math.sqrt(1 - c.zeta ** 2))
    al = rows["AL"]["motion_time_s"]
    assert rows["AL*ZV"]["motion_time_s"] == pytest.approx(al + Td / 2, abs=1e-9)
    assert rows["AL*ZVD"]["motion_time_s"] == pytest.approx(al + Td, abs=1e-9)
    # the limits hold for every method but the AL-based ones reach a_max exactly
    for r in rows.values():
        assert r["v_peak_over_v_max"] <= 1 + 1e-9 and r["a_peak_over_a_max"] <= 1 + 1e-9
    # vibration-aware methods beat AL on the moving mode
    for n in ("JL", "DJL", "AL*ZV", "AL*ZVD", "damped jerk"):
        assert rows[n]["residual_pct_of_AL"] < 50.0, n
    band = c.band
    assert all(r["band_m"] == band for r in rows.values())
    text = c.table()
    assert "time-optimal JL" in text and "Sato III" in text and "% of AL" in text


def test_robustness_zero_at_tuned_mode(comparison):
    rc = comparison.robustness
    i0 = int(np.argmin(np.abs(rc.error)))
    assert rc.error[i0] == 0.0
    pc = rc.percent()
    for n in ("AL*ZV", "AL*ZVD", "AL*MZV", "damped jerk"):
        assert pc[n][i0] < 1e-6, n
    assert pc["AL*EI"][i0] == pytest.approx(5.0, rel=1e-3)
    assert len(comparison.robustness_rows()) == len(rc.error) * len(rc.residual)


def test_plots(comparison):
    import matplotlib.figure

    assert isinstance(comparison.plot(), matplotlib.figure.Figure)
    assert isinstance(comparison.plot_runs(), matplotlib.figure.Figure)


def test_sato_design_keeps_limits():
    T_SUM, T1 = sato_design(0.3, 2.0, 4.0, 7.4, 1e-3, 0.6)
    p = sato_profile(0.3, T_SUM, T1, "III")
    t = np.linspace(0, T_SUM, 2001)
    _, v, a, _ = p.motion().evaluate(t)
    assert np.abs(v).max() <= 2.0 * (1 + 1e-9)
    assert np.abs(a).max() <= 4.0 * (1 + 1e-9)
    assert T_SUM >= 0.6 and T1 >= 1e-3
    # v_max forces a longer positioning time: peak velocity 1.5 L / (T_SUM - T1)
    T_SUM, T1 = sato_design(0.4, 0.5, 4.0, 6.6, 1e-3, 1.0)
    assert T_SUM == pytest.approx(1.201) and T1 == pytest.approx(1e-3)


def test_cli_writes_outputs(tmp_path, fmu2):
    scen = tmp_path / "small.toml"
    scen.write_text(SMALL, encoding="utf-8")
    out = tmp_path / "out"
    rc = main(["compare", str(scen), "-o", str(out), "--timeopt", "0", "--no-stationary",
               "--peers", "AL*ZV,damped jerk", "--no-plot", "-q", "--fmu", str(fmu2)])
    assert rc == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == ["small-robustness.csv", "small.csv", "summary.txt"]
    text = (out / "summary.txt").read_text()
    assert "AL*ZV" in text and "damped jerk" in text and "AL*ZVD" not in text


@pytest.mark.parametrize("argv,msg", [
    (["compare", "no-such-scenario"], "no such scenario"),
    (["compare", "sweep-X"], "sweeps are not compared"),
    (["compare", "X", "--peers", "AL*XX"], "unknown peer"),
    (["compare", "X", "--timeopt", "-1"], "--timeopt"),
])
def test_cli_bad_input(tmp_path, capsys, argv, msg):
    out = tmp_path / "out"
    assert main([*argv, "-o", str(out)]) == 2
    assert msg in capsys.readouterr().err
    assert not out.exists()


def test_cli_help(capsys):
    with pytest.raises(SystemExit):
        main(["compare", "--help"])
    text = capsys.readouterr().out
    for word in ("time-optimal", "Sato", "ZVD", "damped jerk", "robustness", "--timeopt",
                 "summary.txt", "ruckig"):
        assert word in text


def test_html_fragment(comparison):
    h = comparison.html()
    assert h.startswith("<h3>Scenario small</h3>") and "data:image/png;base64," in h
    assert "AL*ZVD" in h
