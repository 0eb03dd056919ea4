"""The recommended profile is produced by the generator FMU itself (issues 18 and 33).

* the row's ``fmu_parameters``, given to the FMU alone (:func:`harness.fmu.runner.generate`),
  reproduce the reference the harness co-simulated; a sampled reference (profile
  ``table``) replays the design's jerk, sample for sample, as this test integrates it;
* the FMU's own shaping equals the harness's independent convolution
  (:class:`harness.simulation.shaped_axis.ShapedAxis` around the unshaped FMU);
* the compiled engine's shaping equals the FMU's.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from harness.evaluation import run_case
from harness.fmu.runner import generate
from harness.recommend import jerk_table
from harness.scenario import load_scenario
from harness.simulation.fmu_axis import FMUAxis
from harness.simulation.session import Session
from harness.simulation.shaped_axis import ShapedAxis, ShaperSpec


@pytest.fixture(scope="module", params=["X", "Y"])
def rec(request, fmu2):
    sc = load_scenario(request.param)
    with Session(fmu2) as s:
        res = run_case(sc, s, recommend=True, score_worst_cases=False)
    return sc, res


def test_the_fmu_alone_replays_the_recommended_row(rec, fmu):
    sc, res = rec
    po = res.profiles["recommended"]
    params = po.fmu_parameters
    # JSON round trip: what a user copies out of the CSV
    params = json.loads(json.dumps(params))
    best = res.recommendation.best
    if best.shaper is not None:
        assert params["shaper"] == 4 and params["shaper_n"] == len(params["shaper_amplitude"])
    if best.profile == "table":
        assert params["profile"] == 4
        assert params["table_n"] == len(params["table_samples"]) == len(params["table_jerk"])
        assert sum(params["table_samples"]) == len(best.jerk)
    run = po.run
    tr = generate(params, t_stop=float(run.t[-1]), dt=run.step, fmu=fmu)
    n = min(tr.t.size, run.t.size)
    assert n == run.t.size
    scale = abs(sc.move.distance)
    np.testing.assert_allclose(tr.x[:n], run.x, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(tr.a[:n], run.a, rtol=0, atol=1e-9 * sc.move.a_max)
    assert tr.motion_time == pytest.approx(run.t_end - run.t_start, abs=1e-12)
    if best.profile == "table":
        # the design's jerk, integrated here sample by sample (exact cubics, a plain loop)
        Te, x, v, a_ = sc.simulation.Te, 0.0, 0.0, 0.0
        xs = [0.0]
        for j in best.jerk:
            x += v * Te + a_ * Te**2 / 2 + j * Te**3 / 6
            v += a_ * Te + j * Te**2 / 2
            a_ += j * Te
            xs.append(x)
        k0 = int(round(run.t_start / Te))  # the co-simulation's motion start (the same rule)
        got = tr.x[k0:k0 + len(xs)] - sc.move.x0
        np.testing.assert_allclose(got[:-1], np.array(xs)[:got.size - 1], rtol=0,
                                   atol=1e-9 * scale)
    else:  # the shaped move rests bit for bit where the unshaped one rests (weights sum 1)
        unshaped = {k: v for k, v in params.items() if not k.startswith("shaper")}
        base = generate(unshaped, t_stop=float(run.t[-1]), dt=run.step, fmu=fmu)
        assert tr.x[-1] == base.x[-1]
    assert tr.x[-1] == pytest.approx(sc.move.x0 + sc.move.distance, abs=1e-15)


def test_fmu_shaping_equals_the_independent_convolution(rec, fmu2):
    sc, res = rec
    best = res.recommendation.best
    sh = best.shaper or ShaperSpec((0.5, 0.5), (0, 37), "two impulses")
    # a table's own shaping is tested with the table (tests/test_fmu_table.py): JL here
    params = Session.move_params(sc, "JL" if best.profile == "table" else best.profile,
                                 best.T_F)
    h = sc.simulation.Te
    with FMUAxis(fmu2) as native, FMUAxis(fmu2) as base:
        T1 = native.plan({**params, **sh.fmu_parameters(sc.simulation.Te)})
        T2 = ShapedAxis(base, sh).plan(params)
        assert T1 == pytest.approx(T2, abs=1e-12)
        n = int(round(T1 / h)) + 50
        a = native.points(n, h)
        b = ShapedAxis(base, sh).points(n, h)
    for name, tol in (("x", 1e-12), ("v", 1e-12), ("a", 1e-10), ("j", 1e-7)):
        np.testing.assert_allclose(a.values[name], b.values[name], rtol=0, atol=tol, err_msg=name)


def test_compiled_engine_shapes_as_the_fmu(rec, fmu2):
    sc, res = rec
    best = res.recommendation.best
    table = jerk_table(sc, best)
    with Session(fmu2) as s, Session(engine="fast") as f:
        r1 = s.run(sc, best.profile, best.T_F, shaper=best.shaper, table=table)
        r2 = f.run(sc, best.profile, best.T_F, shaper=best.shaper, table=table)
    np.testing.assert_allclose(r1.x, r2.x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r1.eps, r2.eps, rtol=0, atol=1e-12 * np.abs(r1.eps).max())
    assert r1.t_end == pytest.approx(r2.t_end, abs=1e-12)
