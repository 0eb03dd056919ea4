"""Claim 6: inverse-model biquad, notch and ZV shaper (Béarée 2014, eq. 18-22).

Independent references: the shaper's transfer function summed directly, the
filters' polynomial roots, and solve_ivp on the continuous filter + mode
equations driven by the FMU's AL acceleration.
"""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from harness.claims import Settings
from harness.claims import formulas as fm
from harness.claims import vibration_filters as vf
from harness.claims.registry import run_claim
from harness.fmu.runner import generate


@settings(max_examples=40, deadline=None)
@given(f=st.floats(1.0, 50.0), zeta=st.floats(0.0, 0.5), x=st.floats(0.0, 10.0))
def test_zv_eq22_is_the_shaper_magnitude(f, zeta, x):
    omega = 2 * np.pi * f
    zv = fm.ZVShaper.tuned(omega, zeta)
    w = x * omega
    direct = abs(zv.A1 + zv.A2 * np.exp(-1j * w * zv.T_ZV))
    assert zv.magnitude(w) == pytest.approx(direct, abs=1e-12)
    assert zv.A1 + zv.A2 == pytest.approx(1.0, abs=1e-15)
    assert zv.T_ZV == pytest.approx(0.5 / (f * math.sqrt(1 - zeta**2)), rel=1e-12)


@settings(max_examples=10, deadline=None)
@given(f=st.floats(2.0, 20.0), zeta=st.floats(0.0, 0.3))
def test_zv_leaves_no_residual_on_a_damped_mode(f, zeta):
    omega = 2 * np.pi * f
    zv = fm.ZVShaper.tuned(omega, zeta)

    def rhs(t, y, u):
        return [y[1], -2 * zeta * omega * y[1] - omega**2 * y[0] - u]

    y = solve_ivp(rhs, (0, zv.T_ZV), [0.0, 0.0], args=(zv.A1,), method="DOP853", rtol=1e-12,
                  atol=1e-15).y[:, -1]
    wd = omega * math.sqrt(1 - zeta**2)
    e = y[0] + zv.A1 / omega**2
    before = math.hypot(e, (y[1] + zeta * omega * e) / wd)
    # second impulse of the shaper: the acceleration step becomes A1 + A2 = 1
    e = y[0] + 1.0 / omega**2
    after = math.hypot(e, (y[1] + zeta * omega * e) / wd)
    assert before > 0.1 / (omega * wd)
    assert after < 1e-9 / (omega * wd)


def test_biquad_zeros_are_the_mode_poles_and_unit_gain():
    omega, zeta = 2 * np.pi * 7.0, 0.04
    bq = fm.biquad_inverse_tf(omega, zeta, 1e-3, 2e-3)
    zeros = np.sort_complex(np.roots(np.asarray(bq.num[0][0], dtype=float)))
    poles = np.sort_complex(np.roots([1.0, 2 * zeta * omega, omega**2]))
    assert np.allclose(zeros, poles, rtol=1e-12)
    assert float(np.real(ct.dcgain(bq))) == pytest.approx(1.0, abs=1e-12)


def test_notch_zero_and_gain():
    nt = fm.notch_tf(40.0, 40.0, 0.7)
    assert abs(np.asarray(ct.frequency_response(nt, [40.0]).complex).ravel()[0]) < 1e-12
    assert float(np.real(ct.dcgain(nt))) == pytest.approx(1.0, abs=1e-12)
    assert abs(np.asarray(ct.frequency_response(nt, [4000.0]).complex).ravel()[0]) == \
        pytest.approx(1.0, abs=1e-3)


def _notch_residual_solve_ivp(fmu) -> float:
    """Residual of the notch-filtered FMU AL move / the AL move's, by solve_ivp."""
    tr = generate(vf.AL_MOVE, fmu=fmu)
    omega1 = 2 * np.pi * vf.F_D / math.sqrt(1 - vf.ZETA**2)
    zeta, Q = vf.ZETA, vf.Q_NOTCH
    k = np.nonzero(np.diff(np.r_[0.0, tr.a_AL]))[0]
    breaks = list(tr.t[k])
    levels = list(tr.a_AL[k])
    t_eval = tr.t_end + vf.T_WAIT

    def u(t):
        i = np.searchsorted(breaks, t, side="right") - 1
        return levels[i] if i >= 0 else 0.0

    def rhs(t, y, filtered):
        ut = u(t)
        if filtered:  # notch (s^2 + w^2)/(s^2 + w/Q s + w^2) in controllable form
            x1, x2, e, de = y
            dx1, dx2 = x2, -omega1**2 * x1 - omega1 / Q * x2 + ut
            v = dx2 + omega1**2 * x1  # numerator: x1'' + w^2 x1
        else:
            dx1 = dx2 = 0.0
            e, de = y[2], y[3]
            v = ut
        return [dx1, dx2, de, -2 * zeta * omega1 * de - omega1**2 * e - v]

    amps = []
    for filtered in (True, False):
        y = np.zeros(4)
        pts = [0.0, *breaks[1:], t_eval]
        for t0, t1 in zip(pts[:-1], pts[1:], strict=True):
            y = solve_ivp(rhs, (t0, t1), y, args=(filtered,), method="DOP853", rtol=1e-11,
                          atol=1e-14, first_step=1e-6).y[:, -1]
        wd = omega1 * math.sqrt(1 - zeta**2)
        amps.append(math.hypot(y[2], (y[3] + zeta * omega1 * y[2]) / wd))
    return amps[0] / amps[1]


def test_claim6_numbers(fmu2):
    res = run_claim(6, Settings(fast=True, fmu=fmu2))
    assert res.error is None, res.error
    assert res.passed, [c.describe() for c in res.failed_checks()]
    F = res.data.filters
    assert F["ZV shaper"].added_time == pytest.approx(0.05, abs=1e-9)  # half of 1/10 Hz
    assert F["JL: moving average"].added_time == pytest.approx(0.1, abs=1e-9)
    assert F["notch"].residual == pytest.approx(_notch_residual_solve_ivp(fmu2), rel=1e-4)
    assert 0.01 < F["notch"].residual < 1.0  # the notch does not cancel the mode
