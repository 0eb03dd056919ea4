"""The LP reference (harness.tuning.reference): each JL ramp filtered, by linear programming.

Every claim is checked by a path independent of the design's own programme:

* the programme's load error (its window: the final states taken back through
  the inputs, then forward while Z still moves) against the co-simulation of
  the same jerk (:func:`harness.peers.motion_axis.cosimulate_reference`, the
  plant stepped by the compiled master) at every point, for designs that do
  not land as well as for ones that do;
* the landing and the limits on the design's own kinematics, integrated here;
* the settling time the programme claims against an independent integration of
  the continuous ODE (:func:`harness.bound.replay`, DOP853 restarted at every
  sample) and against the harness's scoring.
"""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest

from harness.bound import replay
from harness.evaluation import run_case
from harness.peers.motion_axis import cosimulate_reference
from harness.recommend import reference_motion
from harness.scenario import parse_scenario
from harness.scoring import score_points
from harness.simulation.master import perturbed
from harness.simulation.session import Session
from harness.tuning.reference import (
    TABLE_PIECES,
    RampObjective,
    design_reference,
    pieces,
    sparse_support,
)
from harness.tuning.tune import tune_profile
from harness.uncertainty import Perturbation

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from _scenarios import SMALL_AXIS

SHORT = SMALL_AXIS.replace("distance = 0.3\nv_max = 2.0", "distance = 0.06\nv_max = 2.0") \
    .replace("[z]\ndistance = 0.3", "[z]\ndistance = 0.5")
"""A short move while Z travels far: Z still moves when the excited axis has ended."""


@pytest.fixture(scope="module")
def fast():
    with Session(engine="fast") as s:
        yield s


def _case(fast, text, name):
    sc = parse_scenario(tomllib.loads(text), f"<{name}>")
    band = run_case(sc, fast, score_worst_cases=False).band
    T = tuple(tune_profile(fast, sc, "JL").T_F)
    return sc, band, T


@pytest.fixture(scope="module")
def small(fast):
    return _case(fast, SMALL_AXIS, "small")


@pytest.fixture(scope="module")
def short(fast):
    return _case(fast, SHORT, "short")


def kin(jerk, Te):
    """x - x0, v, a at the samples, integrated here (exact cubics, in a plain loop)."""
    x = v = a = 0.0
    xs, vs, as_ = [0.0], [0.0], [0.0]
    for j in jerk:
        x += v * Te + a * Te**2 / 2 + j * Te**3 / 6
        v += a * Te + j * Te**2 / 2
        a += j * Te
        xs.append(x)
        vs.append(v)
        as_.append(a)
    return np.array(xs), np.array(vs), np.array(as_)


def predicted_vs_cosimulated(fast, sc, obj, D, stride, amps, after=0.0, landed=True):
    """Largest |programme's error - co-simulated error| / band over the window and points.

    The programme's error after the motion assumes the reference landed (the
    design's equalities): for a reference that does not, only up to its end.
    """
    sp = obj.span(D, after, stride)
    jerk = np.zeros(obj.n_base + D)
    for g in range(obj.G):
        for i, d in enumerate(sp.delays):
            jerk[d:d + obj.n_base] += amps[g, i] * obj.ramps[g]
    pred = np.einsum("pgik,gi->pk", sp.E, amps)
    run = cosimulate_reference(sc, fast, reference_motion(sc, fast, jerk), "check")
    res = perturbed(run, sc.modemap.scheduled(), obj.points, sc.z.z0 + 0.5 * sc.z.distance,
                    full=True)
    ks = np.arange(sp.k_w, sp.k_w + pred.shape[1])
    if not landed:
        pred, ks = pred[:, :sp.k_end - sp.k_w + 1], ks[:sp.k_end - sp.k_w + 1]
    worst = 0.0
    for p, rr in enumerate(res):
        err = rr.x + rr.eps - rr.target
        k = ks[ks < err.size]
        worst = max(worst, float(np.max(np.abs(pred[p, :k.size] - err[k]))))
    return worst / obj.band, sp


@pytest.mark.parametrize("which", ["small", "short"])
def test_the_programme_predicts_the_cosimulation(fast, small, short, which):
    sc, band, T = small if which == "small" else short
    pts = (Perturbation(), Perturbation(scale=-0.1), Perturbation(scale=0.07))
    obj = RampObjective(sc, fast, T, pts, band, piece=0.5)
    D = int(round(0.7 * obj.period / obj.Te))
    rng = np.random.default_rng(3)
    nd = obj.span(D, 0.0, 5).delays.size
    # each piece's filter sums to 1 (the acceleration levels), the rest random: the
    # reference need not land, the error is still linear in the amplitudes
    amps = rng.normal(scale=0.3, size=(obj.G, nd))
    amps[:, 0] += 1.0 - amps.sum(axis=1)
    off, sp = predicted_vs_cosimulated(fast, sc, obj, D, 5, amps, after=0.2, landed=False)
    assert off < 1e-6
    # a design that lands: after the motion too, Z still moving ("short") or not
    r = design_reference(obj, D, stride=5, after=0.2)
    assert r is not None
    off, sp = predicted_vs_cosimulated(fast, sc, obj, D, 5, r.amplitudes[:, sp.delays],
                                       after=0.2)
    assert off < 1e-6
    if which == "short":  # Z still moves after the motion: the window runs on while it does
        z_end = fast.z_axis.motion_start() + float(fast.z_axis.get("motion_time"))
        assert z_end > sp.k_end * obj.Te + 0.02
        assert sp.k_hi > round(z_end / obj.Te) + round(0.2 / obj.Te)


def test_a_design_lands_within_the_limits_and_settles_as_claimed(fast, small):
    sc, band, T = small
    pts = sc.uncertainty.tuning_set().points
    obj = RampObjective(sc, fast, T, pts, band, piece=0.5)
    D = int(round(0.6 * obj.period / obj.Te))
    r = design_reference(obj, D, stride=6)
    assert r is not None and r.t_lp <= 0.95
    Te, m = sc.simulation.Te, sc.move
    x, v, a = kin(r.jerk, Te)
    assert x[-1] == pytest.approx(m.distance, abs=1e-12)
    assert abs(v[-1]) < 1e-12 and abs(a[-1]) < 1e-12
    assert np.max(np.abs(r.jerk)) <= obj.j_max * (1 + 1e-9)
    assert np.max(a) <= m.a_max * (1 + 1e-9) and np.min(a) >= -m.d_max * (1 + 1e-9)
    assert np.max(v) <= m.v_max * (1 + 1e-9) and np.min(v) >= -1e-9 * m.v_max
    assert pieces(r.jerk) <= TABLE_PIECES
    assert r.motion_time == pytest.approx((obj.n_base + D) * Te)
    claim = r.settle_sample * Te - m.t_start
    # the harness's scoring of the co-simulated reference at the design's points
    run = cosimulate_reference(sc, fast, reference_motion(sc, fast, r.jerk), "ref")
    got = score_points(run, sc, band, pts).settling
    assert np.max(got) <= claim + 1e-9 and np.max(got) >= claim - Te - 1e-9
    # the continuous ODE, integrated independently: within a few samples of the claim
    rp = replay(sc, r.jerk, pts, band=band, session=fast)
    assert rp.worst_settle <= claim + 3 * Te


def test_sparse_support_keeps_the_largest_amplitudes(fast, small):
    sc, band, T = small
    obj = RampObjective(sc, fast, T, sc.uncertainty.tuning_set().points, band, piece=0.5)
    D = int(round(0.6 * obj.period / obj.Te))
    r = design_reference(obj, D, stride=6)
    sup = sparse_support(r, 12)
    assert len(sup) == obj.G and sum(s.size for s in sup) <= 12 + obj.G
    assert all(s[0] == 0 for s in sup)
    r2 = design_reference(obj, D, stride=6, support=sup)
    if r2 is not None:  # on fewer delays: no sooner than the full design
        assert r2.settle_sample >= r.settle_sample
        assert np.count_nonzero(np.abs(r2.amplitudes) > 1e-12) <= sum(s.size for s in sup)


def test_bad_inputs_are_refused(fast, small):
    sc, band, T = small
    with pytest.raises(ValueError, match="band"):
        RampObjective(sc, fast, T, (Perturbation(),), 0.0)
    obj = RampObjective(sc, fast, T, (Perturbation(),), band)
    with pytest.raises(ValueError, match="support must hold delays among"):
        design_reference(obj, 30, stride=6, support=np.array([0, 7]))
    assert design_reference(obj, 30, stride=6) is None or True  # nothing else broke
    assert math.isfinite(obj.period)
