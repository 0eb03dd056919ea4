"""Claim 7: the DJL stage notches against the moving mode of the default scenarios.

Independent references: np.convolve of each a_AL step with its own
rectangle, the scenarios' linear mode laws written out here, and solve_ivp
on the time-varying ODE for one stage.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from harness.claims import Settings
from harness.claims.djl_stages import filtered_steps, ramp
from harness.claims.registry import run_claim
from harness.fmu.runner import generate


def test_filtered_steps_of_a_synthetic_profile():
    a_AL = np.r_[np.full(5, 2.0), np.zeros(3), np.full(4, -3.0), np.zeros(6)]
    steps = filtered_steps(a_AL, (2, 3, 4, 5))
    assert steps == [(0, 2, 2.0), (5, 3, -2.0), (8, 4, -3.0), (12, 5, 3.0)]
    # a direct jump from acceleration to deceleration starts stages 2 and 3 together
    a_AL = np.r_[np.full(5, 2.0), np.full(4, -1.0), np.zeros(6)]
    assert filtered_steps(a_AL, (2, 3, 4, 5)) == [(0, 2, 2.0), (5, 3, -2.0), (5, 4, -1.0),
                                                   (9, 5, 1.0)]
    with pytest.raises(ValueError):
        filtered_steps(np.r_[np.full(5, 2.0), np.zeros(3)], (2, 3, 4, 5))


def test_djl_acceleration_is_four_filtered_steps(fmu2):
    tr = generate({"profile": 3, "distance": 0.4, "v_max": 1.0, "a_max": 10.0, "d_max": 8.0,
                   "T_F1": 0.031, "T_F2": 0.047, "T_F3": 0.052, "T_F4": 0.013}, fmu=fmu2)
    steps = filtered_steps(tr.a_AL, tr.N_F)
    total = np.zeros(tr.a.size)
    for k0, N, d in steps:
        impulse = np.zeros(tr.a.size)
        impulse[k0] = d
        # a step through an N-tap moving average, with the FMU's one-sample convention
        total += np.r_[0.0, np.cumsum(np.convolve(impulse, np.ones(N) / N))[: tr.a.size - 1]]
        assert np.allclose(ramp(tr.a.size, k0, N, d)[1:],
                           np.cumsum(np.convolve(impulse, np.ones(N) / N))[: tr.a.size - 1])
    assert np.max(np.abs(total - tr.a)) < 1e-12 * 10.0


def test_claim7_numbers(fmu2):
    res = run_claim(7, Settings(fast=True, fmu=fmu2))
    assert res.error is None, res.error
    assert res.product_passed, [c.describe() for c in res.failed_checks()]
    laws = {"X": (8.5, 6.375, 0.03), "Y": (10.5, 7.035, 0.04)}  # the embedded TOML files
    for sc in res.data.scenarios:
        f0, f1, zeta = laws[sc.name]
        assert sc.zeta == zeta
        for z, P in zip(sc.z, sc.periods, strict=True):
            assert P == pytest.approx(1.0 / (f0 + (f1 - f0) * z / 0.5), rel=1e-12)
        for i, (T_F, P) in enumerate(zip(sc.T_F, sc.periods, strict=True)):
            target = sc.T_F[1] if sc.merged and i == 2 else P
            assert abs(T_F - target) <= 0.5e-3 + 1e-12
    assert [sc.merged for sc in res.data.scenarios] == [False, True]  # Y: no constant velocity


def test_claim7_stage_residual_against_solve_ivp(fmu2):
    res = run_claim(7, Settings(fast=True, fmu=fmu2))
    sc = res.data.scenarios[0]
    st = sc.djl[0]  # stage 1 of X: a ramp of `duration` from 0 to `step`
    h = float(sc.t[1] - sc.t[0])
    t_mid, f_mid = sc.t + h / 2, sc.f
    step = st.jerk * st.duration
    zeta = sc.zeta

    def omega(t):
        return 2 * np.pi * np.interp(t, t_mid, f_mid)

    def rhs(t, y, jerk):
        acc = jerk * min(t, st.duration) if jerk else step
        w = omega(t)
        return [y[1], -2 * zeta * w * y[1] - w * w * y[0] - acc]

    def amp(jerk):
        y = solve_ivp(rhs, (0.0, st.duration), [0.0, 0.0], args=(jerk,), method="DOP853",
                      rtol=1e-11, atol=1e-15, max_step=h).y[:, -1]
        w = 2 * np.pi * st.f_end
        e = y[0] + step / w**2
        return math.hypot(e, (y[1] + zeta * w * e) / (w * math.sqrt(1 - zeta**2)))

    assert st.moving == pytest.approx(amp(st.jerk) / amp(0.0), abs=2e-3)
