"""The flexible-axis plant: LTI model, exact stepping, scheduling against solve_ivp."""

from __future__ import annotations

import math

import control as ct
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad, solve_ivp

from harness.plant import (
    Mode,
    ScheduledMode,
    ScheduledPlant,
    axis_ss,
    free_amplitude,
    free_response,
    hermite_mid,
    mode_ss,
    simulate_mode,
    step_mode,
)

# ------------------------------------------------------------ references


def step_closed_form(t, mode: Mode, a0: float):
    """Deflection after an acceleration step a0 at t = 0 (textbook second-order step)."""
    w, s, wd = mode.omega, mode.sigma, mode.omega_d
    return -a0 / w**2 * (1 - np.exp(-s * t) * (np.cos(wd * t) + s / wd * np.sin(wd * t)))


def convolution(t_eval, mode: Mode, a_of_t, breaks):
    """ε(t) = -∫ g(t - τ) a(τ) dτ with the impulse response g, by adaptive quadrature."""
    s, wd = mode.sigma, mode.omega_d
    out = []
    for tt in t_eval:
        pts = [b for b in breaks if 0 < b < tt]
        val, _ = quad(lambda tau, tt=tt: math.exp(-s * (tt - tau)) * math.sin(wd * (tt - tau))
                      / wd * a_of_t(tau), 0.0, tt, points=pts or None, limit=400,
                      epsabs=1e-15, epsrel=1e-12)
        out.append(-mode.gain * val)
    return np.array(out)


def ivp_reference(t, a, f_of_t, zeta, y0=(0.0, 0.0), breaks=()):
    """Time-varying ODE ε'' + 2ζω(t)ε' + ω(t)²ε = -a(t), DOP853 with tight tolerances."""
    def rhs(tt, y):
        w = 2 * math.pi * f_of_t(tt)
        return [y[1], -2 * zeta * w * y[1] - w * w * y[0] - np.interp(tt, t, a)]

    edges = sorted({t[0], t[-1], *[b for b in breaks if t[0] < b < t[-1]]})
    y = np.array(y0, dtype=float)
    eps = np.empty(t.size)
    deps = np.empty(t.size)
    eps[0], deps[0] = y
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        sel = (t > lo) & (t <= hi)
        te = t[sel]
        extra = te.size == 0 or te[-1] < hi
        sol = solve_ivp(rhs, (lo, hi), y, method="DOP853", rtol=1e-11, atol=1e-15,
                        t_eval=np.append(te, hi) if extra else te, max_step=0.02)
        eps[sel], deps[sel] = sol.y[:, :-1] if extra else sol.y
        y = sol.y[:, -1]  # the state at hi, where the next piece starts
    return eps, deps


# --------------------------------------------------------------- LTI model


def test_mode_ss_is_the_second_order_of_bearee_2014_eq3():
    m = Mode(f=6.5, zeta=0.03)
    sys = mode_ss(m)
    assert sys.ninputs == 1 and sys.noutputs == 1 and sys.nstates == 2
    # eq. 4: H(jw) = -1 / ((w1^2 - w^2) + j 2 zeta w1 w)
    for w in (0.0, 10.0, m.omega, 200.0):
        H = complex(sys(1j * w))
        ref = -1.0 / ((m.omega**2 - w**2) + 2j * m.zeta * m.omega * w)
        assert H == pytest.approx(ref, rel=1e-12)
    poles = np.sort_complex(sys.poles())
    assert poles[0] == pytest.approx(complex(-m.sigma, -m.omega_d), rel=1e-12)


def test_mode_ss_step_response_matches_closed_form():
    m = Mode(f=6.5, zeta=0.05)
    t = np.linspace(0, 2, 2001)
    resp = ct.step_response(mode_ss(m), t)
    np.testing.assert_allclose(resp.outputs, step_closed_form(t, m, 1.0), atol=1e-12)


def test_axis_ss_sums_the_modes():
    modes = [Mode(30.0, 0.02), Mode(90.0, 0.05, gain=0.3)]
    t = np.linspace(0, 0.3, 3001)
    a = np.interp(t, [0, 0.05, 0.1, 0.3], [0, 5.0, 0.0, 0.0])
    total = ct.forced_response(axis_ss(modes), t, a).outputs
    parts = sum(ct.forced_response(mode_ss(m), t, a).outputs for m in modes)
    np.testing.assert_allclose(total, parts, atol=1e-14)
    assert axis_ss(modes).nstates == 4


@pytest.mark.parametrize("f, zeta", [(0.0, 0.1), (-3.0, 0.1), (5.0, 1.0), (5.0, -0.01)])
def test_mode_rejects_bad_parameters(f, zeta):
    with pytest.raises(ValueError):
        Mode(f, zeta)


# ------------------------------------------------------- exact discretisation


def test_constant_acceleration_step_matches_closed_form():
    m = Mode(6.5, 0.03)
    t = np.arange(0, 3, 1e-3)
    r = simulate_mode(t, np.full(t.size, 2.5), m)
    np.testing.assert_allclose(r.eps, step_closed_form(t, m, 2.5), atol=1e-15)


def test_piecewise_linear_input_matches_direct_convolution():
    """Exact for a constant mode: against quad() of the impulse response."""
    m = Mode(7.0, 0.04, gain=0.8)
    knots_t = [0.0, 0.1, 0.25, 0.6, 0.75, 1.0]
    knots_a = [0.0, 4.0, 4.0, -3.0, 0.0, 0.0]
    t = np.arange(0, 1.2, 1e-3)
    a = np.interp(t, knots_t, knots_a)
    r = simulate_mode(t, a, m)
    idx = np.arange(0, t.size, 97)
    ref = convolution(t[idx], m, lambda tau: np.interp(tau, knots_t, knots_a), knots_t)
    np.testing.assert_allclose(r.eps[idx], ref, atol=1e-12 * np.max(np.abs(ref)) + 1e-16)


@settings(max_examples=25, deadline=None)
@given(f=st.floats(0.5, 60.0), zeta=st.floats(0.0, 0.9), seed=st.integers(0, 2**31 - 1),
       h=st.sampled_from([1e-4, 5e-4, 1e-3, 4e-3]))
def test_exact_stepping_equals_python_control_foh(f, zeta, seed, h):
    """python-control's forced_response interpolates the input linearly (first-order hold):
    the same discretisation, computed independently (matrix exponential).

    The closed-form step subtracts quasi-static terms of size u/ω² to get changes of size
    u·h², so its relative rounding error grows like 1e-16/(ωh)²: the tolerance says so.
    """
    rng = np.random.default_rng(seed)
    rtol = max(1e-10, 1e-14 / (2 * math.pi * f * h) ** 2)
    m = Mode(f, zeta)
    t = h * np.arange(400)
    a = rng.normal(size=t.size)
    x0 = rng.normal(size=2) * np.array([1e-3, 1e-2])
    r = simulate_mode(t, a, m, state0=tuple(x0))
    resp = ct.forced_response(mode_ss(m), t, a, X0=x0)
    scale = np.max(np.abs(resp.states[0]))
    np.testing.assert_allclose(r.eps, resp.outputs, atol=rtol * scale)
    np.testing.assert_allclose(r.deps, resp.states[1],
                               atol=rtol * np.max(np.abs(resp.states[1])))
    # the vectorised constant-mode path equals the per-step path
    r2 = simulate_mode(t, a, m, f=np.full(t.size - 1, f), state0=tuple(x0))
    np.testing.assert_allclose(r.eps, r2.eps, atol=rtol * scale)


def test_single_jerk_stage_residual_is_the_sinc_of_eq21():
    """Béarée & Olabi 2013 eq. (21), undamped: after one constant-jerk stage of length T_F
    from 0 to a, the free oscillation has amplitude (a/ω²)·|sin(ωT_F/2)/(ωT_F/2)|."""
    m = Mode(5.0, 0.0)
    Te = 1e-3
    for T_F in (0.05, 0.1, 0.2, 0.3, 0.4, 0.437):
        t = Te * np.arange(int(round((T_F + 0.5) / Te)))
        a = np.clip(t / T_F, 0, 1) * 3.0
        r = simulate_mode(t, a, m)
        # around the new equilibrium -a/ω²
        A = free_amplitude(r.eps[-1] + 3.0 / m.omega**2, r.deps[-1], m)
        x = m.omega * T_F / 2
        assert A == pytest.approx(3.0 / m.omega**2 * abs(math.sin(x) / x), rel=1e-9, abs=1e-15)
    # zero residual when T_F is the period
    t = Te * np.arange(700)
    r = simulate_mode(t, np.clip(t / 0.2, 0, 1) * 3.0, m)
    assert free_amplitude(r.eps[-1] + 3.0 / m.omega**2, r.deps[-1], m) < 1e-12


# ------------------------------------------------------------- free motion


@pytest.mark.parametrize("zeta", [0.0, 0.03, 0.3])
def test_free_response_and_amplitude(zeta):
    m = Mode(4.0, zeta)
    e0, de0 = 2e-3, -0.05
    tau = np.linspace(0, 2, 20001)
    sol = solve_ivp(lambda _t, y: [y[1], -2 * m.sigma * y[1] - m.omega**2 * y[0]], (0, 2),
                    [e0, de0], t_eval=tau, rtol=1e-12, atol=1e-16, method="DOP853")
    np.testing.assert_allclose(free_response(e0, de0, m, tau), sol.y[0], atol=1e-11)
    A = free_amplitude(e0, de0, m)
    # the envelope A e^{-σt} bounds the response and touches it once per half period
    env = A * np.exp(-m.sigma * tau)
    assert np.all(np.abs(sol.y[0]) <= env + 1e-12)
    first = tau <= 1.0 / m.f
    ratio = np.abs(sol.y[0][first]) / env[first]
    assert ratio.max() == pytest.approx(1.0, abs=1e-6)


# ---------------------------------------------------------------- scheduling


def fmu_reference(fmu2, profile=2, **kw):
    from harness.fmu.runner import generate

    params = {"profile": profile, "distance": 0.3, "v_max": 1.0, "a_max": 4.0, "d_max": 4.0,
              "T_F1": 0.12, "T_F2": 0.11, "T_F3": 0.13, "T_F4": 0.14}
    params.update(kw)
    return generate(params, fmu=fmu2, t_stop=1.6)


SCHEDULES = {
    "linear down 25 %": (lambda t: 8.0 - 2.0 * min(t, 0.9) / 0.9, 0.03),
    "linear up 30 %": (lambda t: 6.0 + 1.8 * min(t, 0.8) / 0.8, 0.02),
    "parabolic": (lambda t: 10.0 - 12.0 * (min(t, 0.7) - 0.35) ** 2, 0.05),
    "fast sine": (lambda t: 7.0 + 1.5 * math.sin(2 * math.pi * 1.5 * t), 0.0),
    "two-step table": (lambda t: float(np.interp(t, [0, 0.3, 0.6, 1.0], [9, 7, 7.5, 6])), 0.08),
}


@pytest.mark.parametrize("name", list(SCHEDULES))
def test_scheduled_mode_matches_solve_ivp(fmu2, name):
    """The exponential-midpoint scheme against DOP853 (rtol 1e-11) on the time-varying ODE:
    residual amplitude within 1 % (in fact within 1e-4), on FMU-generated references."""
    f_of_t, zeta = SCHEDULES[name]
    tr = fmu_reference(fmu2, profile=3)
    t, a = tr.t, tr.a
    r = simulate_mode(t, a, Mode(f_of_t(0.0), zeta), f=f_of_t)
    breaks = t[np.flatnonzero(np.diff(tr.j) != 0) + 1].tolist() + [0.3, 0.6, 0.7, 0.8, 0.9]
    eps, deps = ivp_reference(t, a, f_of_t, zeta, breaks=breaks)
    assert np.max(np.abs(r.eps - eps)) <= 1e-4 * np.max(np.abs(eps))
    k = int(np.argmax(tr.done))
    m_end = Mode(f_of_t(t[k]), zeta)
    A_ref = free_amplitude(eps[k], deps[k], m_end)
    A = free_amplitude(r.eps[k], r.deps[k], m_end)
    assert A == pytest.approx(A_ref, rel=1e-2)
    assert A == pytest.approx(A_ref, rel=1e-4)


def test_scheduling_converges_at_second_order():
    """Error against solve_ivp divides by ~4 when the step is halved (exponential midpoint)."""
    knots_t = [0.0, 0.12, 0.3, 0.42, 0.6]
    knots_a = [0.0, 4.0, 4.0, 0.0, 0.0]
    f_of_t = lambda t: 12.0 - 8.0 * t  # noqa: E731 - strong variation to see the error
    T = 0.6
    t_ref = np.linspace(0, T, 241)
    a_ref = np.interp(t_ref, knots_t, knots_a)
    eps_ref, _ = ivp_reference(t_ref, a_ref, f_of_t, 0.02, breaks=knots_t)
    errors = []
    for h in (2e-3, 1e-3, 5e-4):
        t = np.arange(0, T + h / 2, h)
        r = simulate_mode(t, np.interp(t, knots_t, knots_a), Mode(12.0, 0.02), f=f_of_t)
        errors.append(abs(np.interp(T, t, r.eps) - eps_ref[-1]))
    for e1, e2 in zip(errors, errors[1:], strict=False):
        assert 3.5 < e1 / e2 < 4.5


def test_scheduled_plant_equals_simulate_mode_and_hermite_midpoint():
    law = lambda z: 9.0 - 5.0 * z  # noqa: E731
    plant = ScheduledPlant([ScheduledMode(law, 0.03, 1.0), Mode(25.0, 0.05, 0.2)])
    h = 1e-3
    t = h * np.arange(800)
    a = np.interp(t, [0, 0.1, 0.3, 0.4, 0.8], [0, 3, 3, 0, 0])
    # a cubic z(t): the Hermite midpoint is exact
    z = 0.1 + 0.4 * t**2 - 0.2 * t**3
    vz = 0.8 * t - 0.6 * t**2
    zm_exact = 0.1 + 0.4 * (t[:-1] + h / 2) ** 2 - 0.2 * (t[:-1] + h / 2) ** 3
    zm = np.array([hermite_mid(z[k], vz[k], z[k + 1], vz[k + 1], h) for k in range(t.size - 1)])
    np.testing.assert_allclose(zm, zm_exact, atol=1e-15)
    total = [0.0]
    for k in range(t.size - 1):
        total.append(plant.step(h, a[k], a[k + 1], zm[k]))
    r1 = simulate_mode(t, a, Mode(9.0, 0.03), f=law(zm))
    r1z = simulate_mode(t, a, Mode(9.0, 0.03), f=law, z=z, v_z=vz)
    np.testing.assert_allclose(r1z.eps, r1.eps, atol=1e-16)
    r2 = simulate_mode(t, a, Mode(25.0, 0.05, 0.2))
    np.testing.assert_allclose(total, r1.eps + r2.eps, atol=1e-15)
    assert plant.frequencies(0.2) == pytest.approx([8.0, 25.0])
    amps = plant.free_amplitudes(float(z[-1]))
    assert amps[1] == pytest.approx(free_amplitude(r2.eps[-1], r2.deps[-1],
                                                   Mode(25.0, 0.05, 0.2)))


def test_step_mode_is_exact_over_a_long_step():
    """One big step with a linear input equals many small ones (constant ω)."""
    e, de = 1e-3, 0.02
    w, z, g = 2 * math.pi * 5.0, 0.1, 1.0
    big = step_mode(e, de, w, z, g, 0.3, 1.0, -2.0)
    n = 3000
    ee, dd = e, de
    for k in range(n):
        u0 = 1.0 - 3.0 * k / n
        ee, dd = step_mode(ee, dd, w, z, g, 0.3 / n, u0, u0 - 3.0 / n)
    assert big == pytest.approx((ee, dd), rel=1e-10, abs=1e-15)


def test_simulate_mode_input_checks():
    m = Mode(5.0, 0.1)
    with pytest.raises(ValueError):
        simulate_mode(np.array([0.0, 1e-3, 3e-3]), np.zeros(3), m)
    with pytest.raises(ValueError):
        simulate_mode(np.arange(5) * 1e-3, np.zeros(5), m, f=np.ones(3))
    with pytest.raises(ValueError):
        simulate_mode(np.arange(5) * 1e-3, np.zeros(5), m, f=np.array([1.0, -1.0, 1.0, 1.0]))


def test_transitions_are_the_matrix_exponential():
    """plant.transitions (used by the shaper design and the physical limit) is exp(A h) of
    the damped oscillator for every mode of an array, against scipy's expm."""
    from scipy.linalg import expm

    from harness.plant import transition, transitions

    omega = np.array([[2 * np.pi * 3.0, 2 * np.pi * 8.5], [2 * np.pi * 40.0, 1.0]])
    zeta = np.array([[0.0], [0.3]])
    h = 1e-3
    phi = transitions(omega, zeta, h)
    assert phi.shape == (2, 2, 2, 2)
    for i in range(2):
        for j in range(2):
            w, z = omega[i, j], zeta[i, 0]
            A = np.array([[0.0, 1.0], [-w * w, -2 * z * w]])
            np.testing.assert_allclose(phi[i, j], expm(A * h), rtol=1e-12, atol=1e-15)
            assert tuple(phi[i, j].ravel()) == transition(w, z, h)  # the same operations
