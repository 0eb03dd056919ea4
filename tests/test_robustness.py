"""Robustness to a mode-map error in the time-varying plant (harness.robustness)."""

from __future__ import annotations

import csv
import dataclasses
import math

import matplotlib.pyplot as plt
import numpy as np
import pytest

from harness.evaluation import run_case
from harness.modemap import LinearLaw, ModeMap, ModeSpec
from harness.robustness import (
    RobustnessResult,
    map_error_residuals,
    robustness,
)
from harness.scenario import load_scenario
from harness.simulation.session import Session
from harness.tuning.tune import tune_profile
from harness.uncertainty import DEFAULT_UNCERTAINTY

CURVES_10 = np.linspace(-0.2, 0.2, 41)
"""The default uncertainty's map-error curves (map scale 0.1): -20 % .. +20 %, 1 % apart."""

WORST_10 = np.linspace(-0.1, 0.1, 21)
"""Their worst case alone: -10 % .. +10 %, 1 % apart."""


def short(name: str, t_after: float = 0.6):
    sc = load_scenario(name)
    return dataclasses.replace(sc, simulation=dataclasses.replace(sc.simulation,
                                                                  t_after=t_after))


def scaled_by_hand(sc, factor: float):
    """The scenario with the linear law's two frequencies multiplied by ``factor``, written out
    again (not through ModeMap.scaled)."""
    (m,) = sc.modemap.modes
    law = m.law
    assert isinstance(law, LinearLaw)
    spec = ModeSpec(LinearLaw(law.z, (law.f[0] * factor, law.f[1] * factor)), m.zeta,
                    m.gain, m.mass_ratio, m.name)
    return dataclasses.replace(sc, modemap=ModeMap((spec,)))


def amplitude_from_samples(run, spec: ModeSpec) -> float:
    """Free amplitude at the end of the motion from the sampled deflection of a full run:
    max |ε| e^{σ(t - t_end)} over 1.5 periods (Z at rest: a damped sinusoid); 2e-4 relative."""
    assert run.z_synced and run.z_t_end <= run.t_end + 1e-12
    m = spec.at(float(run.z[-1]))
    sel = (run.t >= run.t_end - 1e-12) & (run.t <= run.t_end + 1.5 / m.f)
    return float(np.max(np.abs(run.eps[sel]) * np.exp(m.sigma * (run.t[sel] - run.t_end))))


@pytest.fixture(scope="module")
def tuned(fmu2):
    """Scenario X, its session and the jerk times tuned on the nominal map."""
    sc = short("X")
    with Session(fmu2) as s:
        T = {p: tune_profile(s, sc, p) for p in ("AL", "JL", "DJL")}
        yield sc, s, {p: (t.T_F if t is not None else None) for p, t in T.items()}


def test_residuals_match_brute_force_runs_of_the_scaled_scenario(tuned):
    """Each point of the curve is the residual of a full co-simulation of the scenario whose
    map is scaled by hand, read off its sampled deflection."""
    sc, s, T = tuned
    errors = np.array([-0.2, -0.1, -0.03, 0.0, 0.06, 0.1, 0.2])
    for prof in ("JL", "DJL", "AL"):
        got = map_error_residuals(sc, s, prof, T[prof], errors)
        assert got.shape == errors.shape
        for e, r in zip(errors, got, strict=True):
            sce = scaled_by_hand(sc, 1.0 + e)
            run = s.run(sce, prof, T[prof])
            assert r == pytest.approx(amplitude_from_samples(run, sce.modemap.tuned), rel=5e-4)
            # the same state at the end of the motion as the full run: equal to rounding
            assert r == pytest.approx(run.free_amplitude, rel=1e-9)
    # a map error changes the residual (the tuning is off), by a lot at 20 %
    jl = map_error_residuals(sc, s, "JL", T["JL"], [0.0, 0.2, -0.2])
    assert jl[1] > 1.5 * jl[0] or jl[2] > 1.5 * jl[0]


def test_worst_case_over_10_percent_vs_brute_force(tuned):
    sc, s, T = tuned
    errors = np.linspace(-0.2, 0.2, 9)   # 5 % apart: ±10 % holds 5 of them
    rob = robustness(sc, s, {"JL": T["JL"], "DJL": T["DJL"]}, errors=errors)
    assert list(rob.residual) == ["JL", "DJL"]
    worst = rob.worst(0.10)
    for prof in ("JL", "DJL"):
        brute = []
        for e in (-0.1, -0.05, 0.0, 0.05, 0.1):
            sce = scaled_by_hand(sc, 1.0 + e)
            brute.append(amplitude_from_samples(s.run(sce, prof, T[prof]),
                                                sce.modemap.tuned))
        assert worst[prof] == pytest.approx(max(brute), rel=5e-4)
        # points beyond ±10 % are not in the worst case, but in the curve
        assert rob.worst(0.2)[prof] == pytest.approx(float(np.max(rob.residual[prof])))
    assert rob.nominal()["JL"] == pytest.approx(rob.residual["JL"][4])
    assert rob.worst(0.01) == rob.nominal()   # only e = 0 within ±1 %
    with pytest.raises(ValueError, match="no map error"):
        RobustnessResult(np.array([0.15, 0.2]), {"JL": np.ones(2)}).worst(0.1)


def test_run_case_worst_and_curves(tuned, tmp_path):
    """robustness="worst": the worst case over the 21 points of ±10 %, on each profile;
    "curves": the 41 points of ±20 % kept on the result, the worst case taken from them
    (the default uncertainty: the very grids of before it was the only home of the span)."""
    sc, s, T = tuned
    assert sc.uncertainty == DEFAULT_UNCERTAINTY
    np.testing.assert_array_equal(DEFAULT_UNCERTAINTY.curve_errors(), CURVES_10)
    np.testing.assert_array_equal(DEFAULT_UNCERTAINTY.worst_errors(), WORST_10)
    assert np.allclose(CURVES_10[10:31], WORST_10, atol=1e-15)
    base = run_case(sc, s)
    assert base.robustness is None
    assert all(math.isnan(p.worst_map_residual) for p in base.profiles.values())
    w = run_case(sc, s, keep_runs=False, robustness="worst")
    c = run_case(sc, s, robustness="curves")
    assert w.robustness is None and isinstance(c.robustness, RobustnessResult)
    np.testing.assert_array_equal(c.robustness.errors, CURVES_10)
    for prof in ("AL", "JL", "DJL"):
        expect = float(np.max(map_error_residuals(sc, s, prof, T[prof], WORST_10)))
        assert w.profiles[prof].worst_map_residual == pytest.approx(expect, rel=1e-12)
        assert c.profiles[prof].worst_map_residual == pytest.approx(expect, rel=1e-12)
        # the earlier name reads the same number
        assert c.profiles[prof].worst_residual_10pct == c.profiles[prof].worst_map_residual
        # the nominal point of the curve is the case's residual
        assert c.robustness.nominal()[prof] == pytest.approx(
            c.profiles[prof].metrics.residual, rel=1e-12)
        assert expect >= c.profiles[prof].metrics.residual
    text = c.table()
    assert "Worst residual, map error +/-10 % [mm]" in text
    assert "time-varying plant (Z moving), whole map scaled by 1 + e" in text
    rows = list(csv.DictReader(c.to_csv(tmp_path / "c.csv").open()))
    for row in rows:
        p = c.profiles[row["profile"]]
        assert float(row["residual_worst_map10_m"]) == pytest.approx(p.worst_map_residual,
                                                                    rel=1e-9)
    al = c.profiles["AL"].worst_map_residual
    assert float(rows[1]["residual_worst_map10_pct_of_AL"]) == pytest.approx(
        100 * c.profiles["JL"].worst_map_residual / al, rel=1e-9)
    with pytest.raises(ValueError, match="robustness"):
        run_case(sc, s, robustness="everything")


def test_result_rows_plot_and_label(tuned):
    sc, s, T = tuned
    rob = robustness(sc, s, {"AL": None, "JL": T["JL"][0]}, errors=[-0.1, 0.0, 0.1])
    assert rob.T_F["JL"] == (T["JL"][0],) * 4 and rob.T_F["AL"] is None
    rows = rob.rows()
    assert len(rows) == 6
    assert {r["plant"] for r in rows} == {"time-varying plant (Z moving), whole map scaled "
                                          "by 1 + e"}
    jl = [r for r in rows if r["profile"] == "JL"]
    assert [r["frequency_factor"] for r in jl] == pytest.approx([0.9, 1.0, 1.1])
    assert jl[1]["residual_pct_of_AL"] == pytest.approx(
        100 * rob.residual["JL"][1] / rob.residual["AL"][1])
    fig = rob.plot()
    ax = fig.axes[0]
    assert "whole map scaled by 1 + e" in ax.get_title()
    assert any("+/-10 %" in t.get_text() for t in ax.get_legend().get_texts())
    plt.close(fig)
    with pytest.raises(ValueError):
        map_error_residuals(sc, s, "JL", T["JL"], [-1.0])
    with pytest.raises(ValueError, match="jerk times"):
        robustness(sc, s, {"JL": None})


def test_a_vectorised_session_method_is_used(tuned):
    """The session's map_error_residuals(sc, profile, T_F, errors) answers (errors e, not
    factors 1 + e: Session.map_error_residuals)."""
    sc, s, T = tuned
    calls = []

    class Vectorised:
        def __getattr__(self, name):
            return getattr(s, name)

        def map_error_residuals(self, sc_, profile, T_F, errors):
            calls.append((profile, T_F, np.array(errors)))
            return (1.0 + np.asarray(errors)) * 1e-3

    got = map_error_residuals(sc, Vectorised(), "DJL", T["DJL"], [-0.1, 0.05])
    assert got == pytest.approx([0.9e-3, 1.05e-3])
    assert calls[0][0] == "DJL" and calls[0][1] == T["DJL"]
    assert calls[0][2] == pytest.approx([-0.1, 0.05])
