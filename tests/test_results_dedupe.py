"""Sweeps count each distinct move once (Table 2, the sweep figure), and say what was merged."""

from __future__ import annotations

import csv
import dataclasses
import math

import matplotlib.pyplot as plt
import numpy as np
import pytest

from harness.evaluation import ProfileMetrics
from harness.results import ProfileOutcome, ScenarioResult, SweepResult, format_table2, table2_rows
from harness.scenario import load_scenario
from harness.simulation.session import Session
from harness.sweeps import run_scenario


def plan(d: float, v_reached: float, N: int = 150, T: float = 0.9) -> dict:
    return {"motion_time": T, "N_F": (N, N, N, N), "v_reached": v_reached, "a_reached": 4.0,
            "d_reached": 4.0, "distance": d, "x0": 0.0, "z0": 0.0, "z_distance": 0.1,
            "z_v_max": 0.3, "z_motion_time": T}


def outcome(name: str, residual: float, settling: float, settling_paper: float,
            plan_info: dict) -> ProfileOutcome:
    met = ProfileMetrics(residual, residual, 0.9, 0.85, settling, 1e-5, 0.95 * residual,
                         settling_paper, 5e-5)
    return ProfileOutcome(name, None, None, met, (0.15,) * 4, 0.3, True, plan_info=plan_info)


def case(sc, al: tuple, jl: tuple, djl: tuple) -> ScenarioResult:
    """al/jl/djl: (residual, settling, settling in the paper's band, plan_info)."""
    prof = {n: outcome(n, *v) for n, v in (("AL", al), ("JL", jl), ("DJL", djl))}
    return ScenarioResult(sc, prof, 1e-5, "band: 1 % of AL's residual", paper_band=5e-5)


@pytest.fixture(scope="module")
def hand_sweep() -> SweepResult:
    """Four cases: the second is the first with v_max = 2 (AL differs, JL and DJL plan the
    same moves: a duplicate); the fourth's DJL plan differs from the first's by one ulp of
    v_reached (not a duplicate: moves are compared exactly)."""
    sw = load_scenario("sweep-X")
    by_name = {c.name.removeprefix("sweep-X "): c for c in sw.cases()}
    p_jl, p_djl = plan(0.1, 0.41), plan(0.1, 0.43, N=140)
    cases = [
        case(by_name["d=0.1 dz=0.1 v=0.5"], (2e-3, 4.0, 3.0, plan(0.1, 0.5)),
             (1e-4, 2.0, 1.2, p_jl), (0.5e-4, 1.5, 0.8, p_djl)),
        case(by_name["d=0.1 dz=0.1 v=2"], (2.2e-3, 4.1, 3.1, plan(0.1, 0.63)),
             (1e-4, 2.0, 1.2, dict(p_jl)), (0.5e-4, 1.0, 0.8, dict(p_djl))),
        case(by_name["d=0.2 dz=0.1 v=0.5"], (2e-3, 4.0, 3.0, plan(0.2, 0.5)),
             (2e-4, 1.0, 1.1, plan(0.2, 0.5)), (1.8e-4, 1.1, 1.0, plan(0.2, 0.5, N=140))),
        case(by_name["d=0.3 dz=0.1 v=0.5"], (2e-3, 4.0, 3.0, plan(0.1, 0.5)),
             (1e-4, 2.0, 1.0, dict(p_jl)), (0.7e-4, 1.6, 0.9,
                                            {**p_djl, "v_reached": np.nextafter(0.43, 1.0)})),
    ]
    return SweepResult(sw, cases)


def test_duplicates_are_found_exactly(hand_sweep):
    assert hand_sweep.duplicates() == [None, 0, None, None]
    assert [c.scenario.name for c in hand_sweep.distinct()] == [
        "sweep-X d=0.1 dz=0.1 v=0.5", "sweep-X d=0.2 dz=0.1 v=0.5", "sweep-X d=0.3 dz=0.1 v=0.5"]
    # with AL's move required to coincide too, nothing is merged
    assert hand_sweep.duplicates(("AL", "JL", "DJL")) == [None, None, None, None]
    assert hand_sweep.merged_note() == (
        "4 cases, 3 distinct moves (1 duplicate merged, same JL and DJL moves: "
        "d=0.1 dz=0.1 v=2 = v=0.5)")
    # a case without plan_info is never merged
    blind = dataclasses.replace(hand_sweep.cases[1], profiles={
        n: dataclasses.replace(p, plan_info={}) for n, p in hand_sweep.cases[1].profiles.items()})
    assert SweepResult(hand_sweep.scenario, [hand_sweep.cases[0], blind]).duplicates() == [
        None, None]


def test_table2_statistics_count_each_move_once(hand_sweep):
    st = hand_sweep.stats()
    # residual: DJL vs JL = -50 % (case 1), [-50 % (duplicate)], -10 %, -30 %
    r = st["residual"]
    assert r.n == 3
    assert r.mean == pytest.approx(-30.0)
    assert (r.max, r.min) == (pytest.approx(-50.0), pytest.approx(-10.0))
    assert r.std == pytest.approx(20.0)
    # settling in the case's band: -25 %, [-50 %: the duplicate, another AL so another band],
    # +10 %, -20 %
    s = st["settling"]
    assert s.n == 3 and s.mean == pytest.approx((-25.0 + 10.0 - 20.0) / 3)
    assert s.max == pytest.approx(-25.0)
    # the paper's band: -33.3 %, [-33.3 %], -9.09 %, -10 %
    sp = st["settling_paper"]
    assert sp.n == 3 and sp.mean == pytest.approx((100 * (0.8 - 1.2) / 1.2
                                                   + 100 * (1.0 - 1.1) / 1.1 - 10.0) / 3)
    assert st["worst_residual_10pct"].n == 0   # not computed
    # changes() still lists every case (the CSV's and the per-case view)
    assert hand_sweep.changes()[0] == pytest.approx([-50.0, -50.0, -10.0, -30.0])
    text = format_table2([hand_sweep])
    assert "Settling times (band: 1 % of AL's residual)" in text
    assert "Settling times (the paper's band: DJL's residual)" in text
    assert "Worst residual" not in text
    assert "distinct moves (counted)" in text and hand_sweep.merged_note() in text
    mean_line = next(line for line in text.splitlines() if "Mean value" in line)
    assert float(mean_line.split()[-1]) == pytest.approx(-30.0)
    rows = table2_rows([hand_sweep])
    assert [r["quantity"] for r in rows] == ["residual", "settling", "settling_paper"]
    assert all(r["cases"] == 3 and r["sweep_cases"] == 4 and r["distinct_moves"] == 3
               for r in rows)
    assert rows[1]["band"] == "band: 1 % of AL's residual"
    assert rows[2]["band"] == "the paper's band: DJL's residual"


def test_csv_keeps_every_case_and_names_the_first(hand_sweep, tmp_path):
    rows = list(csv.DictReader(hand_sweep.to_csv(tmp_path / "sw.csv").open()))
    assert len(rows) == 4 * 3
    dup = {r["scenario"]: r["duplicate_of"] for r in rows}
    assert dup == {"sweep-X d=0.1 dz=0.1 v=0.5": "",
                   "sweep-X d=0.1 dz=0.1 v=2": "sweep-X d=0.1 dz=0.1 v=0.5",
                   "sweep-X d=0.2 dz=0.1 v=0.5": "", "sweep-X d=0.3 dz=0.1 v=0.5": ""}
    first = next(r for r in rows if r["scenario"].endswith("v=2"))
    assert float(first["case_djl_vs_jl_residual_pct"]) == pytest.approx(-50.0)
    assert float(first["case_djl_vs_jl_settling_pct"]) == pytest.approx(-50.0)


def test_sweep_plot_shows_distinct_moves(hand_sweep):
    fig = hand_sweep.plot()
    ax1, ax2 = fig.axes[:2]
    assert len(ax1.collections[0].get_offsets()) == 3
    assert len(ax2.patches) == 3 * 3   # residual, settling, settling in the paper's band
    assert "3 distinct moves" in fig._suptitle.get_text()
    plt.close(fig)


def test_embedded_sweep_merges_the_moves_where_v_max_is_not_reached(fmu2):
    """At d = 0.1 m JL and DJL never reach 0.5 m/s: v_max = 0.5 and 2 plan the same JL and DJL
    moves (AL reaches 0.5 m/s: its move differs); at d = 0.4 m they differ."""
    sc = load_scenario("sweep-X")
    sc = dataclasses.replace(
        sc, simulation=dataclasses.replace(sc.simulation, t_after=0.5),
        sweep=dataclasses.replace(sc.sweep, distance=(0.1, 0.4), z_distance=(0.2,),
                                  v_max=(0.5, 2.0)))
    with Session(fmu2) as s:
        res = run_scenario(sc, session=s)
    assert isinstance(res, SweepResult)
    assert [c.scenario.name for c in res.cases] == [
        "sweep-X d=0.1 dz=0.2 v=0.5", "sweep-X d=0.1 dz=0.2 v=2",
        "sweep-X d=0.4 dz=0.2 v=0.5", "sweep-X d=0.4 dz=0.2 v=2"]
    assert res.duplicates() == [None, 0, None, None]
    a, b = res.cases[0], res.cases[1]
    for n in ("JL", "DJL"):
        # the same move: the same jerk times and the very same numbers
        assert a.profiles[n].T_F == b.profiles[n].T_F
        assert a.metric(n, "residual") == b.metric(n, "residual")
        assert a.metric(n, "settling_time_paper") == b.metric(n, "settling_time_paper")
        assert a.profiles[n].plan_info["v_reached"] < 0.5
    assert a.profiles["AL"].plan_info["v_reached"] == 0.5
    assert b.profiles["AL"].plan_info["v_reached"] > 0.5
    assert a.metric("AL", "residual") != b.metric("AL", "residual")
    c, d = res.cases[2], res.cases[3]
    assert c.profiles["JL"].plan_info["v_reached"] != d.profiles["JL"].plan_info["v_reached"]
    st = res.stats()
    assert st["residual"].n == 3
    expect = [res.cases[i].djl_vs_jl()[0] for i in (0, 2, 3)]
    assert st["residual"].mean == pytest.approx(float(np.mean(expect)))
    assert "4 cases, 3 distinct moves (1 duplicate merged, same JL and DJL moves: " \
           "d=0.1 dz=0.2 v=2 = v=0.5)" in format_table2([res])
    assert not any(math.isnan(x) for x in st["settling_paper"].__dict__.values())
