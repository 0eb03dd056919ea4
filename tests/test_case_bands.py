"""The settling band of a case (simulation.settle_band) as run_case resolves it."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from harness.evaluation import run_case
from harness.metrics import SettleBand
from harness.scenario import load_scenario
from harness.simulation.session import Session


def variant(sc, band: SettleBand | None = None, profiles: tuple[str, ...] | None = None):
    sim = sc.simulation if band is None else dataclasses.replace(sc.simulation,
                                                                 settle_band=band)
    cmp_ = sc.compare if profiles is None else dataclasses.replace(sc.compare,
                                                                   profiles=profiles)
    return dataclasses.replace(sc, simulation=sim, compare=cmp_)


@pytest.fixture(scope="module")
def base(fmu2):
    sc = load_scenario("Y")
    sc = dataclasses.replace(sc, simulation=dataclasses.replace(sc.simulation, t_after=0.5))
    with Session(fmu2) as s:
        yield sc, s, run_case(sc, s)


def test_every_band_kind_is_shared_by_the_profiles_and_labelled(base):
    sc, s, res = base
    al, djl = res.metric("AL", "residual"), res.metric("DJL", "residual")
    cases = {
        SettleBand("AL", 0.01): (0.01 * al, "band: 1 % of AL's residual"),
        SettleBand("AL", 0.05): (0.05 * al, "band: 5 % of AL's residual"),
        SettleBand("m", 2e-5): (2e-5, "band: +/-0.02 mm, given in the scenario"),
        SettleBand("paper"): (djl, "the paper's band: DJL's residual"),
    }
    for spec, (band, label) in cases.items():
        r = run_case(variant(sc, spec), s, keep_runs=False)
        assert r.band == pytest.approx(band, rel=1e-12), spec
        assert r.band_source == label
        assert r.paper_band == pytest.approx(djl, rel=1e-12)
        for p in r.profiles.values():
            assert p.metrics.band == r.band
            assert p.metrics.settling_time_paper == pytest.approx(
                res.profiles[p.name].metrics.settling_time_paper, abs=1e-12)
        text = r.table()
        assert f"Settling time [s] ({label})" in text
        # the paper's band is a separate row unless it is the case's band
        rows = [line for line in text.splitlines() if line.startswith("Settling time [s]")]
        assert len(rows) == (1 if spec.kind == "paper" else 2)
        assert rows[-1].startswith("Settling time [s] (the paper's band: DJL's residual)")
        assert r.rows()[0]["band_source"] == label
    # a wider band settles sooner, for every profile
    r1 = run_case(variant(sc, SettleBand("AL", 0.01)), s, keep_runs=False)
    r5 = run_case(variant(sc, SettleBand("AL", 0.05)), s, keep_runs=False)
    for n in ("AL", "JL", "DJL"):
        assert r5.metric(n, "settling_time") < r1.metric(n, "settling_time")


def test_default_band_without_al_runs_al_for_the_band(base):
    sc, s, res = base
    r = run_case(variant(sc, profiles=("JL", "DJL")), s)
    assert list(r.profiles) == ["JL", "DJL"]
    assert r.band == pytest.approx(0.01 * res.metric("AL", "residual"), rel=1e-12)
    assert "AL run for the band only" in r.band_source
    for n in ("JL", "DJL"):
        assert r.metric(n, "settling_time") == pytest.approx(res.metric(n, "settling_time"),
                                                             abs=1e-12)
    # the paper's band needs DJL
    with pytest.raises(ValueError, match="DJL"):
        run_case(variant(sc, SettleBand("paper"), ("AL", "JL")), s)
    # without DJL there is no paper's band, and no row for it
    r = run_case(variant(sc, profiles=("AL", "JL")), s)
    assert math.isnan(r.paper_band)
    assert all(math.isnan(p.metrics.settling_time_paper) for p in r.profiles.values())
    assert "paper's band" not in r.table()
    assert np.isnan(r.rows()[0]["settling_time_paper_band_s"])
