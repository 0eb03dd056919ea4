"""Scoring over an uncertainty set (harness.scoring.score_uncertainty).

The fast scorer (one compiled plant run for every point, the free part evaluated
only where an exit from the band can still be) is checked against the generic
path written here: every point's run re-stepped over the whole record
(:func:`harness.simulation.master.perturbed`) and measured by
:func:`harness.scoring.settling_of`; and against a densely sampled closed-form
free response for the settling of one point.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from harness.evaluation import run_case
from harness.modemap import ConstantLaw, ModeMap, ModeSpec
from harness.scenario import load_scenario
from harness.scoring import score_uncertainty, settling_of
from harness.simulation.master import perturbed
from harness.simulation.session import Session
from harness.uncertainty import Perturbation, UncertaintySet, UncertaintySpec


@pytest.fixture(scope="module")
def fast():
    with Session(engine="fast") as s:
        yield s


def generic(run, sc, band, uset):
    pivot = sc.z.z0 + 0.5 * sc.z.distance
    res = perturbed(run, sc.modemap.scheduled(), uset.points, pivot, full=False)
    r = [x.free_amplitude for x in res]
    ts = [settling_of(x, band) for x in res]
    return r, ts


BOX = UncertaintySpec(map_scale=0.1, map_slope=0.3, z_shift=0.05, damping=(0.5, 2.0))


@pytest.mark.parametrize("name", ["X", "Y"])
@pytest.mark.parametrize("spec", [None, BOX], ids=["scale", "box"])
def test_fast_scoring_equals_the_generic_path(fast, name, spec):
    sc = load_scenario(name)
    if spec is not None:
        sc = dataclasses.replace(sc, uncertainty=spec)
    # the recommended profile with the map scale only: with the whole box its design takes
    # 10-30 s (docs/recommend.md), and what is checked here is the scoring of any run
    res = run_case(sc, fast, recommend=spec is None, score_worst_cases=False)
    uset = sc.uncertainty.scoring_set()
    for prof, po in res.profiles.items():
        got = score_uncertainty(po.run, sc, res.band, uset)
        r, ts = generic(po.run, sc, res.band, uset)
        assert got["residual_worst"] == pytest.approx(max(r), rel=1e-12), prof
        k = int(np.argmax(ts))
        assert got["settling_time_worst"] == pytest.approx(ts[k], abs=1e-9), prof
        assert got["worst_point"] == uset.points[k].label()
        # the nominal point is the run itself
        assert r[0] == pytest.approx(po.run.free_amplitude, rel=1e-12)
        assert ts[0] == pytest.approx(po.metrics.settling_time, abs=1e-9)


def test_one_point_against_the_closed_form_free_response(fast):
    """A still Z and a constant mode: after the move the deflection is the closed-form free
    oscillation; the settling time is read off it on a 10x finer grid (to 1e-3 s)."""
    sc = load_scenario("Y")
    mm = ModeMap((ModeSpec(ConstantLaw(7.0), 0.03),), sc.modemap.tune)
    sc = dataclasses.replace(sc, modemap=mm, z=dataclasses.replace(sc.z, distance=0.0),
                             uncertainty=UncertaintySpec(map_scale=0.0))
    run = fast.run(sc, "JL", (0.1,) * 4)
    band = 0.2 * run.free_amplitude
    one = UncertaintySet((Perturbation(0.05),), "one point")
    got = score_uncertainty(run, sc, band, one)["settling_time_worst"]
    # the plant at 7.35 Hz, from the state when the reference ends, exactly
    r = generic(run, sc, band, one)
    assert got == pytest.approx(r[1][0], abs=1e-9)
    m_f, zeta = 7.0 * 1.05, 0.03
    pert = perturbed(run, sc.modemap.scheduled(), one.points, 0.0, full=False)[0]
    e0, de0 = pert.state_end[0]
    w = 2 * math.pi * m_f
    sig, wd = zeta * w, w * math.sqrt(1 - zeta**2)
    tau = np.arange(0, 5.0, 1e-4)
    eps = np.exp(-sig * tau) * (e0 * np.cos(wd * tau) + (de0 + sig * e0) / wd * np.sin(wd * tau))
    err = np.abs(eps + run.x[-1] - run.target)
    last = tau[np.flatnonzero(err > band)[-1]]
    assert got == pytest.approx(run.t_end - run.t_start + last, abs=1e-3)


def test_an_undamped_mode_never_settles_and_a_wide_band_at_once(fast):
    sc = load_scenario("Y")
    mm = ModeMap((ModeSpec(ConstantLaw(7.0), 0.0),), sc.modemap.tune)
    sc = dataclasses.replace(sc, modemap=mm, uncertainty=UncertaintySpec(map_scale=0.1))
    run = fast.run(sc, "JL", (0.1,) * 4)
    got = score_uncertainty(run, sc, 1e-6)
    assert got["settling_time_worst"] == math.inf and got["residual_worst"] > 1e-6
    wide = score_uncertainty(run, sc, 10.0)  # a 10 m band: inside from the start
    assert wide["settling_time_worst"] == 0.0


def test_bad_inputs_are_named(fast):
    sc = load_scenario("Y")
    run = fast.run(sc, "JL", (0.1,) * 4)
    for band in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="band must be > 0"):
            score_uncertainty(run, sc, band)
    with pytest.raises(ValueError, match="plant input"):
        score_uncertainty(dataclasses.replace(run, plant_input=None), sc, 1e-5)
    # nothing broke: the same run still scores
    assert score_uncertainty(run, sc, 1e-5)["residual_worst"] > 0
