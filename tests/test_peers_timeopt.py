"""FIR-built JL / DJL against the time-optimal jerk-limited motion (ruckig)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from harness.fmu.runner import generate
from harness.peers.park import park_profile
from harness.peers.timeopt import compare_move, measure, random_move

TE = 1e-3




def case_moves(case: str):
    """Hypothesis strategy: (distance, v_max, a_max, N_F) of one case, from a seed."""
    return st.integers(0, 2**32 - 1).map(
        lambda seed: random_move(np.random.default_rng(seed), TE, case))


@pytest.mark.parametrize("case", ["I", "II"])
@settings(max_examples=30, deadline=None)
@given(data=st.data())
def test_jl_is_time_optimal_within_one_sample(fmu2, case, data):
    """Where the time-optimal move reaches a_max (cases I and II), FIR-JL with T_F = a/j is it.

    The FMU plans on whole samples, so it is compared with the time-optimal
    duration rounded up to a sample (the best a sampled generator can do):
    at most one sample more.  Against the continuous duration: less than two.
    """
    d, v, a, N = data.draw(case_moves(case))
    r = compare_move(d, v, a, N * TE, Te=TE, method="JL", fmu=fmu2)
    assert r.case == case
    assert r.T_fmu >= r.T_opt * (1 - 1e-12)            # never faster than time-optimal
    assert r.T_fmu <= r.T_opt_discrete + TE * (1 + 1e-9)
    assert r.excess_samples < 2.0
    # ruckig against Park's closed forms (an independent time-optimal reference)
    assert park_profile(d, v, a, a / (N * TE)).total_time == pytest.approx(r.T_opt, rel=1e-9)


def test_jl_case_I_reaches_both_limits_and_respects_jerk(fmu2):
    rng = np.random.default_rng(7)
    for _ in range(4):
        d, v, a, N = random_move(rng, TE, "I")
        tr = generate({"profile": 2, "distance": d, "v_max": v, "a_max": a, "d_max": a,
                       "T_F1": N * TE, "Te": TE}, fmu=fmu2)
        j_max = a / (N * TE)
        assert np.abs(tr.v).max() <= v * (1 + 1e-9) and np.abs(tr.v).max() >= 0.99 * v
        assert np.abs(tr.a).max() <= a * (1 + 1e-9) and np.abs(tr.a).max() >= 0.97 * a
        assert np.abs(tr.j).max() <= j_max * (1 + 1e-9)
        assert tr.x[-1] == pytest.approx(d, rel=1e-9)


@settings(max_examples=25, deadline=None)
@given(st.sampled_from(["I", "II", "III", "IV"]), st.sampled_from(["JL", "JL overlap", "DJL"]),
       st.integers(0, 2**32 - 1))
def test_never_faster_than_time_optimal(fmu2, case, method, seed):
    """With limits respected no profile beats ruckig; DJL against its own largest jerk."""
    rng = np.random.default_rng(seed)
    d, v, a, N = random_move(rng, TE, case)
    T_F = N * TE * (np.round(rng.uniform(1, 2, 4) * N) / N if method == "DJL" else np.ones(4))
    r = compare_move(d, v, a, T_F, Te=TE, method=method, fmu=fmu2)
    assert r.T_fmu >= r.T_opt * (1 - 1e-12)
    assert r.j_max == pytest.approx(a / min(r.T_F))


def test_measurement_table(fmu2):
    import matplotlib.figure

    t = measure(6, seed=3, fmu=fmu2, progress=False)
    s = {(r["method"], r["case"]): r for r in t.summary()}
    assert len(s) == 12 and all(r["n"] == 6 for r in s.values())
    # within one sample of the rounded-up optimum where a_max is reached
    for c in ("I", "II"):
        assert s[("JL", c)]["over_discrete_max"] <= 1
    # short moves: the FIR-built JL must be slower (the stage is stretched to T_F)
    assert s[("JL", "III")]["excess_samples_median"] > 5
    assert s[("JL", "III")]["excess_percent_median"] > s[("JL overlap", "III")][
        "excess_percent_median"]
    text = t.to_text()
    assert "JL overlap" in text and "DJL" in text
    assert isinstance(t.plot(), matplotlib.figure.Figure)


def test_bad_method():
    with pytest.raises(ValueError):
        compare_move(0.1, 1.0, 1.0, 0.01, method="XL")
