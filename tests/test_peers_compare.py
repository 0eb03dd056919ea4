"""The comparison on a small scenario, and ``djl-fmu compare``."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from harness.cli import main
from harness.peers.compare import (
    ALL_PEERS,
    DJL_TUNINGS,
    PEERS,
    build_peers,
    compare_scenario,
    cosimulate_reference,
    has_djl_tuning,
    reference_map_error_residuals,
    sato_design,
    stationary_variant,
)
from harness.peers.residual import residual_amplitude
from harness.peers.sato import sato_profile
from harness.peers.trajectory import PiecewiseJerk
from harness.scenario import parse_scenario
from harness.simulation.session import Session

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


MAP_ERRORS = np.linspace(-0.2, 0.2, 9)  # 5 % apart: -10, -5, 0, 5, 10 % within +/-10 %


@pytest.fixture(scope="module")
def comparison(small, session):
    return compare_scenario(small, session=session, errors=np.linspace(-0.2, 0.2, 9),
                            map_errors=MAP_ERRORS, bound=False)


@pytest.fixture(scope="module")
def fast_session():
    with Session(engine="fast") as s:
        yield s


def tuned_rows(sc) -> list[str]:
    """The tuned DJL rows compare_scenario adds when the harness has djl_tuning."""
    return [f"DJL ({t})" for t in DJL_TUNINGS] if has_djl_tuning(sc) else []


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
    built = build_peers(st, 0.1, 0.6, peers=ALL_PEERS, fmi_version=2, session=session)
    assert list(built) == list(ALL_PEERS)
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
    assert list(c.methods) == ["AL", "JL", "DJL", *tuned_rows(small), *PEERS, "recommended"]
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
    jl = rows["JL"]["motion_time_s"]
    assert rows["JL*ZV"]["motion_time_s"] == pytest.approx(jl + Td / 2, abs=1e-9)
    assert rows["JL*ZVD"]["motion_time_s"] == pytest.approx(jl + Td, abs=1e-9)
    # the limits hold for every method but the AL-based ones reach a_max exactly
    for r in rows.values():
        assert r["v_peak_over_v_max"] <= 1 + 1e-9 and r["a_peak_over_a_max"] <= 1 + 1e-9
    # vibration-aware methods beat AL on the moving mode
    for n in ("JL", "DJL", "AL*ZV", "AL*ZVD", "damped jerk", "JL*ZV", "JL*ZVD", "JL*EI",
              "AL*TV-ZV", "JL*TV-ZV"):
        assert rows[n]["residual_pct_of_AL"] < 50.0, n
    # the time-varying shaper follows the moving mode: less than the ZV tuned to its end
    assert rows["AL*TV-ZV"]["residual_m"] < 0.2 * rows["AL*ZV"]["residual_m"]
    assert rows["JL*TV-ZV"]["residual_m"] < 0.5 * rows["JL*ZV"]["residual_m"]
    band = c.band
    assert all(r["band_m"] == band for r in rows.values())
    text = c.table()
    assert "time-optimal JL" in text and "Sato III" in text and "% of AL" in text
    assert "worst±10% [mm]" in text and "Who wins on small:" in text


def test_verdict_names_the_winners(comparison):
    c = comparison
    v = "\n".join(c.verdict())
    res = {n: mo.metrics.residual for n, mo in c.methods.items()}
    st = {n: mo.metrics.settling_time for n, mo in c.methods.items()}
    wc = {n: mo.worst_10pct for n, mo in c.methods.items()}
    best_res, best_st, best_wc = (min(d, key=d.get) for d in (res, st, wc))
    assert f"least residual: {best_res} {res[best_res] * 1e3:.3g} mm" in v
    assert f"first settled (band +/-{c.band * 1e3:.3g} mm): {best_st} {st[best_st]:.3f} s" in v
    assert f"map error (time-varying plant (Z moving), whole map scaled by 1 + e): {best_wc} " \
           f"{wc[best_wc] * 1e3:.3g} mm" in v


def test_map_error_worst_case_equals_brute_force(comparison, small, fast_session):
    """A peer's map-error residuals are cosimulate_reference runs on a scaled map."""
    c = comparison
    me = c.map_error
    assert me.label == "time-varying plant (Z moving), whole map scaled by 1 + e"
    np.testing.assert_array_equal(me.errors, MAP_ERRORS)
    assert set(me.residual) == set(c.methods)
    within = np.abs(MAP_ERRORS) <= 0.1 + 1e-12
    for name in ("AL*ZVD", "JL*TV-ZV", "time-optimal JL"):
        mot = c.motions[name]
        brute = np.array([cosimulate_reference(
            dataclasses.replace(small, modemap=small.modemap.scaled(1.0 + e)), fast_session, mot,
            name).free_amplitude for e in MAP_ERRORS[within]])
        np.testing.assert_allclose(me.residual[name][within], brute, rtol=1e-12, atol=0)
        assert c.methods[name].worst_10pct == pytest.approx(brute.max(), rel=1e-12)
        assert c.methods[name].worst_10pct == max(me.residual[name][within])
        # the same function on its own
        np.testing.assert_allclose(reference_map_error_residuals(small, fast_session, mot,
                                                                 [0.1]), brute[-1:], rtol=1e-12)
    # e = 0 is the nominal run of every method (fast engine against the FMU run: 1e-9)
    i0 = int(np.flatnonzero(MAP_ERRORS == 0.0)[0])
    for name, mo in c.methods.items():
        assert me.residual[name][i0] == pytest.approx(mo.metrics.residual, rel=1e-9), name
    # the references were planned on the nominal map only: the worst case is not the nominal
    assert c.methods["AL*ZVD"].worst_10pct > 1.5 * c.methods["AL*ZVD"].metrics.residual
    rows = c.map_error_rows()
    assert len(rows) == MAP_ERRORS.size * len(c.methods)
    assert {"method", "map_error", "residual_m", "plant"} <= set(rows[0])


def test_tuned_djl_rows(comparison, small, fast_session):
    """DJL (optimal) / (robust) when the harness has compare.djl_tuning, else a note."""
    c = comparison
    if not has_djl_tuning(small):
        assert not any(n.startswith("DJL (") for n in c.methods)
        assert any("djl_tuning" in n for n in c.notes)
        return
    from harness.evaluation import run_case

    for tu in DJL_TUNINGS:
        mo = c.methods[f"DJL ({tu})"]
        sct = dataclasses.replace(small, compare=dataclasses.replace(
            small.compare, djl_tuning=tu, profiles=("DJL",), DJL_T_F=None))
        ref = run_case(sct, fast_session).profiles["DJL"]
        assert mo.params["T_F"] == pytest.approx(list(ref.T_F), abs=1e-12)
        assert mo.metrics.residual == pytest.approx(ref.metrics.residual, rel=1e-12)
        assert mo.metrics.band == c.band  # the same band as every method
        assert math.isfinite(mo.worst_10pct)
    assert "DJL (optimal)" in c.table()


def test_tuned_djl_rows_skipped_gracefully(small, session, monkeypatch):
    """Without compare.djl_tuning (or with tuned_djl=False) the rows are left out."""
    import harness.peers.compare as pc

    monkeypatch.setattr(pc, "has_djl_tuning", lambda sc: False)
    c = compare_scenario(small, session=session, peers=("AL*ZV",), map_errors=None,
                         bound=False)
    assert list(c.methods) == ["AL", "JL", "DJL", "AL*ZV", "recommended"]
    assert any("skipped" in n and "djl_tuning" in n for n in c.notes)
    assert "note: DJL (optimal), DJL (robust): skipped" in c.table()
    assert c.map_error is None and math.isnan(c.methods["AL*ZV"].worst_10pct)
    assert "map error" not in "\n".join(c.verdict())
    monkeypatch.undo()
    c = compare_scenario(small, session=session, peers=("AL*ZV",), map_errors=None,
                         tuned_djl=False, recommended=False, bound=False)
    assert list(c.methods) == ["AL", "JL", "DJL", "AL*ZV"] and not c.notes


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
    fig = comparison.plot_map_error()
    assert "time-varying plant (Z moving), whole map scaled by 1 + e" in fig._suptitle.get_text()
    fig = comparison.plot_robustness()
    titles = [ax.get_title() for ax in fig.axes]
    assert any("stationary mode" in t for t in titles)
    assert any("time-varying plant (Z moving), whole map scaled by 1 + e" in t for t in titles)
    assert "stationary mode" in comparison.plot()._suptitle.get_text()


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


def test_cli_writes_outputs(tmp_path, fmu2, monkeypatch):
    # the physical limit's plumbing (the bound itself: tests/test_bound.py), with a stand-in
    import harness.peers.compare as pc
    from harness.bound import BoundSummary

    seen = []

    def fake_bound(sc, band, **kw):
        seen.append(band)
        return BoundSummary(0.5, 0.6, 0.501, 30.0, band, 41, "a stand-in set", 1.0)

    monkeypatch.setattr(pc, "bound_summary", fake_bound)
    scen = tmp_path / "small.toml"
    scen.write_text(SMALL, encoding="utf-8")
    out = tmp_path / "out"
    rc = main(["compare", str(scen), "-o", str(out), "--timeopt", "0", "--no-stationary",
               "--peers", "AL*ZV,JL*ZV,JL*TV-ZV,damped jerk", "--no-plot", "-q", "--fmu",
               str(fmu2), "--no-tuned-djl"])
    assert rc == 0
    names = sorted(p.name for p in out.iterdir())
    assert names == ["small-degradation.csv", "small-map-error.csv", "small-robustness.csv",
                     "small.csv", "summary.txt"]
    text = (out / "summary.txt").read_text()
    assert "AL*ZV" in text and "damped jerk" in text and "AL*ZVD" not in text
    assert "JL*ZV" in text and "JL*TV-ZV" in text and "DJL (optimal)" not in text
    # the new column and the verdict
    assert "worst±10% [mm]" in text
    assert "Who wins on small:" in text and "least residual:" in text
    assert "first settled" in text and "smallest worst case over +/-10 % map error" in text
    import csv

    with open(out / "small.csv", newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    assert [r["method"] for r in rows] == ["AL", "JL", "DJL", "AL*ZV", "JL*ZV", "JL*TV-ZV",
                                           "damped jerk", "recommended"]
    # one bound, in the shared band; every method's worst settle as a ratio to it
    assert len(seen) == 1 and seen[0] == pytest.approx(float(rows[0]["band_m"]), rel=1e-12)
    for r in rows:
        assert float(r["settling_bound_s"]) == 0.5
        assert float(r["settling_worst_over_bound"]) == pytest.approx(
            float(r["settling_time_worst_s"]) / 0.5, rel=1e-9)  # CSV: 10 digits
    assert "/ bound" in text and "physical limit (any profile at JL's jerk, same set): 0.500 s" \
        in text and "a stand-in set" in text
    assert all(float(r["worst_residual_10pct_m"]) > 0 for r in rows)
    with open(out / "small-map-error.csv", newline="", encoding="utf-8") as fh:
        mrows = list(csv.DictReader(fh))
    assert len(mrows) == 41 * 8  # with the recommended row's curve
    assert mrows[0]["plant"] == "time-varying plant (Z moving), whole map scaled by 1 + e"


def test_cli_tuned_djl_rows(tmp_path, fmu2):
    """``djl-fmu compare`` adds the tuned DJL rows when the harness has them."""
    scen = tmp_path / "small.toml"
    scen.write_text(SMALL, encoding="utf-8")
    out = tmp_path / "out"
    rc = main(["compare", str(scen), "-o", str(out), "--timeopt", "0", "--no-stationary",
               "--peers", "AL*ZV", "-q", "--engine", "fast", "--no-bound"])
    assert rc == 0
    text = (out / "summary.txt").read_text()
    import tomllib

    sc = parse_scenario(tomllib.loads(SMALL), "small.toml")
    if has_djl_tuning(sc):
        assert "DJL (optimal)" in text and "DJL (robust)" in text
    else:
        assert "DJL (optimal), DJL (robust): skipped" in text
    names = {p.name for p in out.iterdir()}
    assert {"small-map-error.png", "small-robustness.png", "small-runs.png",
            "small-degradation.png", "small-degradation.csv"} <= names


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
        main(["compare", "--help-full"])
    text = capsys.readouterr().out
    for word in ("time-optimal", "Sato", "ZVD", "damped jerk", "robustness", "--timeopt",
                 "summary.txt", "ruckig", "JL*ZV", "TV-ZV", "Chang & Park", "--no-tuned-djl",
                 "map-error.csv", "DJL (optimal)", "+/-10 %"):
        assert word in text


def test_html_fragment(comparison):
    h = comparison.html()
    assert h.startswith("<h3>Scenario small</h3>") and "data:image/png;base64," in h
    assert "AL*ZVD" in h and "JL*TV-ZV" in h and h.count("data:image/png;base64,") == 1
