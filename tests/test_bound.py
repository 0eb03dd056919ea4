"""The settling bound (harness.bound): a lower bound on the worst-case settling time."""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.bound import SettlingBound, _one_step, replay, settling_bound
from harness.evaluation import profile_metrics
from harness.plant import step_mode_jerk
from harness.scenario import load_scenario, parse_scenario
from harness.simulation.master import perturbed
from harness.simulation.session import Session
from harness.tuning.tune import tune_profile
from harness.uncertainty import Perturbation

TE = 1e-3
POINTS = (Perturbation(scale=-0.1), Perturbation(), Perturbation(scale=0.1))
REPLAY_SAMPLES = 3
"""Stated tolerance: the replayed worst-case settling agrees with the bound within 3 samples."""


@pytest.fixture(scope="module")
def session():
    with Session(engine="fast") as s:
        yield s


@pytest.fixture(scope="module")
def y_bound(session) -> SettlingBound:
    return settling_bound(load_scenario("Y"), POINTS, session=session)


@pytest.fixture(scope="module")
def y_jl(session):
    """The harness's JL on Y: its run, the band, and its worst settling (harness, replay)."""
    sc = load_scenario("Y")
    T_F = tune_profile(session, sc, "JL").T_F
    band = 0.01 * session.run(sc, "AL", None).free_amplitude
    run = session.run(sc, "JL", T_F)
    n = int(round(run.motion_time / TE))
    runs = perturbed(run, sc.modemap.scheduled(), POINTS, sc.z.z0 + sc.z.distance / 2)
    harness = max(profile_metrics(r, band).settling_time for r in runs)
    rp = replay(sc, run.j[:n], POINTS, band=band, session=session)
    return run, band, harness, rp


# ------------------------------------------------------------------ inputs


@pytest.mark.parametrize(("kwargs", "name"), [
    ({"points": ()}, "points"),
    ({"points": [0.1]}, "points"),
    ({"band": 0.0}, "band"),
    ({"band": -1e-5}, "band"),
    ({"band": math.nan}, "band"),
    ({"j_max": 0.0}, "j_max"),
    ({"j_max": -3.0}, "j_max"),
    ({"T_range": (0.8, 0.5)}, "T_range"),
    ({"T_range": 0.8}, "T_range"),
])
def test_bad_inputs_raise_naming_the_argument(kwargs, name):
    args = {"points": POINTS, **kwargs}
    with pytest.raises(ValueError, match=name):
        settling_bound(load_scenario("X"), **args)


def test_a_sweep_scenario_is_refused():
    with pytest.raises(ValueError, match="sc"):
        settling_bound(load_scenario("sweep-X"), POINTS)


def test_replay_bad_inputs():
    with pytest.raises(ValueError, match="band"):
        replay(load_scenario("X"), np.zeros(10), POINTS, band=0.0)
    with pytest.raises(ValueError, match="points"):
        replay(load_scenario("X"), np.zeros(10), (), band=1e-5)


# ------------------------------------------------------------------ the plant


def test_one_step_maps_are_step_mode_jerk():
    rng = np.random.default_rng(3)
    for _ in range(20):
        w, z, g = rng.uniform(20, 80), rng.uniform(0, 0.3), rng.uniform(0.5, 2)
        e0, de0, u0, jk = rng.normal(size=4)
        phi, ga, gj = _one_step(np.array(w), np.array(z), np.array(g), TE)
        got = phi @ [e0, de0] + ga * u0 + gj * jk
        ref = step_mode_jerk(e0, de0, w, z, g, TE, u0, jk)
        np.testing.assert_allclose(got, ref, rtol=1e-12, atol=1e-15)


# ------------------------------------------------------------------ scenario Y


def test_profile_respects_every_limit_and_lands_at_rest(y_bound):
    b, mv = y_bound, load_scenario("Y").move
    assert np.max(np.abs(b.jerk)) <= b.j_max * (1 + 1e-6)
    assert np.all(b.a <= mv.a_max * (1 + 1e-6)) and np.all(b.a >= -mv.d_max * (1 + 1e-6))
    assert np.max(np.abs(b.v)) <= mv.v_max * (1 + 1e-6)
    assert b.x[0] == mv.x0 and b.v[0] == 0 and b.a[0] == 0
    assert b.x[-1] == pytest.approx(mv.x0 + mv.distance, abs=1e-10)
    assert abs(b.v[-1]) < 1e-10 and abs(b.a[-1]) < 1e-10
    assert b.jerk.size == round(b.motion_time / TE)
    assert b.rest_time <= b.motion_time + 1e-12


def test_replay_meets_the_band_from_the_bound(y_bound, session):
    b = y_bound
    rp = replay(load_scenario("Y"), b.jerk, POINTS, band=b.band, session=session)
    np.testing.assert_allclose(rp.settle, b.replay_settle, atol=1e-9)
    # the replay settles where the bound says, within the stated tolerance
    assert abs(rp.worst_settle - b.t_settle) <= REPLAY_SAMPLES * TE
    # and from the settling sample on it stays in the band at every point
    assert np.max(np.abs(rp.error[:, b.settle_sample:])) <= b.band * (1 + 1e-3)
    # the harness's (discrete) plant: the LP's profile settles within one sample of the bound
    assert np.all(b.plant_settle < b.t_settle + TE + 1e-12)
    assert b.plant_worst_settle >= b.t_settle - 1e-12


def test_bound_is_below_jl_and_the_optimal_profile(y_bound, y_jl):
    b = y_bound
    run, band, harness, rp = y_jl
    assert band == pytest.approx(b.band, rel=1e-12)
    # JL's motion time is one of those searched: JL is an admissible profile there
    assert any(abs(T - run.motion_time) < TE / 2 for T, _, _ in b.searched)
    assert rp.worst_settle == pytest.approx(harness, abs=1e-5)  # replay == harness plant
    assert b.t_settle <= rp.worst_settle
    assert b.t_settle <= b.replay_worst_settle + 1e-9
    assert b.t_settle < 0.5 * rp.worst_settle  # JL needs the residual to decay: > 2 s on Y


def test_rows_and_plot(y_bound):
    rows = y_bound.rows()
    assert len(rows) == len(POINTS)
    assert {r["point"] for r in rows} == {p.label() for p in POINTS}
    assert all(r["bound_s"] == y_bound.t_settle for r in rows)
    fig = y_bound.plot()
    assert len(fig.axes) == 3


# ------------------------------------------------------------------ closed form


def toy(distance: float):
    """One undamped 10 Hz mode, Z still, a move whose time-optimal profile is a JL of T_F = 0.1 s.

    Accelerating with 4 m/s² to 0.6 m/s takes 0.15 s, cruising 0.12 m 0.2 s: the
    AL move lasts 0.5 s, its JL of jerk time 0.1 s (one period) 0.6 s, with the jerk
    a_max / T_F = 40 m/s³, and it leaves no vibration at all.
    """
    return parse_scenario({
        "name": "toy", "simulation": {"Te": TE, "step": TE, "t_after": 1.0},
        "move": {"axis": "X", "distance": distance, "v_max": 0.6, "a_max": 4.0},
        "z": {"z0": 0.0, "distance": 0.0},
        "mode": [{"name": "m", "zeta": 0.0, "law": "constant", "f": 10.0}],
        "compare": {"profiles": ["AL", "JL"]}})


def closed_form_jl() -> np.ndarray:
    k = np.arange(600)
    return 40.0 * ((k < 100).astype(float) - ((k >= 150) & (k < 250))
                   - ((k >= 350) & (k < 450)) + (k >= 500))


def test_toy_bound_does_not_exceed_the_closed_form(session):
    band = 1e-5
    jl = closed_form_jl()
    sc = toy(0.21)
    # the closed form is the harness's JL, and it rests at the target without vibration
    run = session.run(sc, "JL", (0.1,) * 4)
    assert run.motion_time == pytest.approx(0.6, abs=1e-12)
    np.testing.assert_allclose(run.j[:600], jl, atol=1e-9)
    assert run.free_amplitude < 1e-12
    rp = replay(sc, jl, [Perturbation()], band=band, session=session)
    assert rp.worst_settle <= 0.6
    b = settling_bound(sc, [Perturbation()], band=band, j_max=40.0, session=session,
                       T_range=(0.6, 0.6))
    assert b.motion_time == pytest.approx(0.6)
    assert b.t_settle <= profile_metrics(run, band).settling_time <= 0.6
    assert b.t_settle <= rp.worst_settle
    assert b.t_settle > 0.5  # the load cannot be there long before the move is
    # a negative move is the mirror image
    neg = settling_bound(toy(-0.21), [Perturbation()], band=band, j_max=40.0, session=session,
                         T_range=(0.6, 0.6))
    assert neg.settle_sample == b.settle_sample
    assert neg.x[-1] == pytest.approx(-0.21, abs=1e-10)
    np.testing.assert_allclose(neg.jerk, -b.jerk, atol=1e-6)
