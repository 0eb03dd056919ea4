"""The yardstick of graceful advice and the assumed unmodelled modes (harness.tuning.graceful),
and the degradation curves (harness.degradation)."""

from __future__ import annotations

import math
import sys

import matplotlib
import numpy as np
import pytest

from harness.degradation import Degradation
from harness.evaluation import run_case
from harness.modemap import ModeMap
from harness.recommend import _textbook_runs
from harness.scenario import parse_scenario
from harness.scoring import score_points
from harness.simulation.session import Session
from harness.tuning.graceful import (
    OUTER_LEVELS,
    UnmodelledModes,
    Yardstick,
    dense_points,
    design_points,
    textbook_shapers,
)
from harness.tuning.tune import tune_profile
from harness.uncertainty import Perturbation, UncertaintySpec, level

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from _scenarios import SMALL_AXIS

matplotlib.use("Agg")


@pytest.fixture(scope="module")
def case():
    with Session(engine="fast") as s:
        sc = parse_scenario(tomllib.loads(SMALL_AXIS), "<small>")
        band = run_case(sc, s, score_worst_cases=False).band
        T = tuple(tune_profile(s, sc, "JL").T_F)
        runs = _textbook_runs(sc, s, T)
        yield sc, s, band, T, runs, Yardstick.measure(sc, s, T, band, runs=runs)


def test_the_yardstick_is_the_best_textbook_shaper_at_each_width(case):
    sc, s, band, T, runs, ys = case
    (sw,) = ys.sweeps
    assert set(ys.curves) == {"JL*ZV", "JL*ZVD", "JL*EI", "JL*SI"}
    E = sc.uncertainty.map_scale
    for w_i in (0, 20, 40, 60, 80):
        w = ys.widths[w_i]
        # by hand: each textbook's worst settling over |e| <= w E, scored point by point
        pts = [Perturbation(scale=float(e)) for e in np.linspace(-w * E, w * E, 2 * w_i + 1)]
        best = min(float(np.max(score_points(r, sc, band, pts).settling)) for r in runs.values())
        assert ys.best["map_scale"][w_i] == pytest.approx(best, abs=1e-12)
    assert np.all(np.diff(ys.best["map_scale"]) >= 0)  # a wider set: never sooner
    # a point's deadline is B at its width
    p = Perturbation(scale=-1.5 * E)
    assert ys.deadline(p) == pytest.approx(ys.best_at("map_scale", 1.5))
    assert ys.deadline(Perturbation(slope=0.1)) == math.inf  # a kind not stated


def test_textbook_shapers_are_whole_samples():
    sc = parse_scenario(tomllib.loads(SMALL_AXIS), "<small>")
    sh = textbook_shapers(sc)
    assert set(sh) == {"ZV", "ZVD", "EI", "SI"}
    for spec in sh.values():
        assert math.fsum(spec.amplitudes) == pytest.approx(1.0, abs=1e-12)
        assert min(spec.amplitudes) >= 0.0 and spec.delays[0] == 0


def test_design_points_hold_the_stated_set_and_wider_levels():
    spec = UncertaintySpec(map_scale=0.1, map_slope=0.3)
    tun = spec.tuning_set().points
    pts = design_points(spec, tun)
    assert pts[:len(tun)] == tun
    lev = sorted({round(level(spec, p), 9) for p in pts[len(tun):]})
    assert lev[0] == pytest.approx(OUTER_LEVELS[0]) and lev[-1] == pytest.approx(2.0)
    assert Perturbation(0.2, 0.6) in pts and Perturbation(-0.2, -0.6) in pts  # the box
    dense = dense_points(UncertaintySpec(map_scale=0.16), ())
    scales = sorted(p.scale for p in dense)
    assert scales == pytest.approx(np.linspace(-0.16, 0.16, 33))
    # none of them is a scoring point but the tuning set's (multiples of E/4)
    scoring = {round(p.scale, 12) for p in UncertaintySpec(map_scale=0.16).scoring_set().points}
    shared = {round(x, 12) for x in scales} & scoring
    assert shared == {round(x, 12) for x in np.linspace(-0.16, 0.16, 9)}


def test_unmodelled_modes_follow_the_highest_mode(case):
    sc, s, band, T, runs, ys = case
    um = UnmodelledModes()
    scq = um.scenario(sc)
    assert isinstance(scq.modemap, ModeMap) and len(scq.modemap.modes) == um.ratios().size
    top = sc.modemap.modes[0]
    for z in (0.0, 0.13, 0.3):
        f = np.array([m.f(z) for m in scq.modemap.modes])
        assert f == pytest.approx(um.ratios() * top.f(z), rel=1e-12)
    assert all(m.zeta == 0.02 and m.gain == pytest.approx(0.3 * top.gain)
               for m in scq.modemap.modes)
    q = um.quiet(sc, s, T, band)
    assert q.bound.size == 3 * um.ratios().size  # nominal and the stated scale's edges
    assert np.all(q.bound >= um.floor * band * (1 - 1e-12))
    # each row's bound is the least residual JL or a textbook shaper leaves it (or the floor)
    amps = [q.objective.residuals(np.ones((1, 1)), (0,))[0][..., 0].ravel()]
    amps += [q.objective.residuals(np.array(sh.amplitudes)[:, None], sh.delays)[0][..., 0]
             .ravel() for sh in textbook_shapers(sc).values()]
    least = np.min(np.vstack(amps), axis=0)
    assert q.bound == pytest.approx(np.maximum(least, um.floor * band), rel=1e-12)
    # a design leaving every row at its bound is quiet; JL alone is not (it excites some)
    assert q.ratio(np.ones(1), (0,)) > 1.0
    assert "2-8x" in um.describe()


def test_degradation_says_how_far_a_method_holds():
    w = np.linspace(0.0, 2.0, 9)
    curves = {"recommended": {"map_scale": np.array([1.0, 1, 1, 1, 1.1, 1.2, 1.5, 2.0, 2.5])},
              "JL*EI": {"map_scale": np.array([1.2, 1.2, 1.2, 1.2, 1.2, 1.3, 1.4, 1.6, 1.8])},
              "JL*ZV": {"map_scale": np.array([0.9, 1.5, 2, 3, 4, 5, 6, 7, 8])}}
    d = Degradation("t", UncertaintySpec(map_scale=0.1), w, curves,
                    textbook=("JL*EI", "JL*ZV"))
    # at w = 0 ZV settles sooner: the recommendation holds nowhere
    assert d.holds_to() == (0.0, "JL*ZV")
    assert "does not hold past the exact map: there, JL*ZV is better (+/-2.5 %" in d.lines()[0]
    curves["JL*ZV"]["map_scale"][0] = 1.0
    assert d.holds_to() == (1.25, "JL*EI")  # EI is better from 1.5 on
    assert "holds up to 1.25x the stated error (+/-12.5 %); beyond, JL*EI is better " \
           "(+/-15 %: 1.400 s against 1.500 s" in d.lines()[0]
    curves["JL*EI"]["map_scale"][:] = 9.0
    curves["JL*ZV"]["map_scale"][:] = 9.0
    assert d.holds_to() == (2.0, "")
    rows = d.rows()
    assert len(rows) == 3 * 9 and {r["method"] for r in rows} == set(curves)
    assert rows[1]["width_text"] == "+/-2.5 %"
    assert "at any actual error up to 2x" in d.lines()[0]
    fig = d.plot()
    assert len(fig.axes) == 1
