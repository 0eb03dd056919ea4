"""Independent reference for the peers tests: the mode simulated with solve_ivp.

``simulate_residual`` integrates ε'' + 2ζω ε' + ω² ε = -a(t) with scipy's
DOP853 at tight tolerances, restarting at every kink of a(t), and returns
the envelope of the free oscillation at the end of the motion.  It shares no
code with :mod:`harness.peers.residual`.  The tests in this file check the
reference itself against closed forms of the second-order response.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
import pytest
from scipy.integrate import solve_ivp


def simulate_residual(acc: Callable[[float, str], float], breaks: Sequence[float],
                      t_end: float, f: float, zeta: float = 0.0, *,
                      rtol: float = 1e-11, atol: float = 1e-16,
                      gain: float = 1.0) -> float:
    """Envelope of ε at ``t_end`` for ε'' + 2ζωε' + ω²ε = -gain·a(t), ε(t0) = ε'(t0) = 0.

    Parameters
    ----------
    acc : callable
        ``acc(t, side)`` the acceleration at ``t`` (``side`` "right" or "left" of a step).
    breaks : sequence of float
        Times where ``a`` or its slope jumps; the first is the start of the motion.
    t_end : float
        End of the motion (a = 0 afterwards).
    """
    w = 2 * np.pi * f
    wd = w * np.sqrt(1 - zeta ** 2)
    knots = np.unique(np.r_[np.asarray(breaks, float), t_end])
    knots = knots[knots <= t_end]
    y = np.zeros(2)
    for s, b in zip(knots[:-1], knots[1:], strict=True):
        def rhs(t, z, s=s, b=b):
            a = acc(b, "left") if t >= b else acc(max(t, s), "right")
            return [z[1], -gain * a - 2 * zeta * w * z[1] - w * w * z[0]]

        sol = solve_ivp(rhs, (s, b), y, method="DOP853", rtol=rtol, atol=atol)
        assert sol.success, sol.message
        y = sol.y[:, -1]
    eps, deps = y
    return float(np.hypot(eps, (deps + zeta * w * eps) / wd))


def motion_kinks(motion) -> np.ndarray:
    """Breakpoints of a PiecewiseJerk where a jumps or the jerk changes (others are smooth)."""
    tb, a, j = motion.tb, motion.a, motion.j
    if tb.size < 2:
        return tb.copy()
    h = np.diff(tb)
    a_end = a[:-1] + j[:-1] * h  # acceleration at the end of each piece
    jump = np.abs(a[1:] - a_end) > 1e-12 * max(1.0, np.abs(a).max())
    change = np.abs(np.diff(j)) > 1e-9 * max(1.0, np.abs(j).max())
    keep = np.r_[True, jump | change]
    return tb[keep]


def simulate_motion(motion, f: float, zeta: float = 0.0, **kw) -> float:
    """``simulate_residual`` on a harness.peers Motion (envelope at its end)."""
    bps = motion_kinks(motion) if hasattr(motion, "tb") else motion.breakpoints()

    def acc(t: float, side: str) -> float:
        return float(motion.evaluate([t], side=side)[2][0])

    return simulate_residual(acc, bps, motion.t_end, f, zeta, **kw)


# ---------------------------------------------------------------- self-tests


@pytest.mark.parametrize("zeta", [0.0, 0.05, 0.3])
def test_reference_step_of_acceleration(zeta):
    """A held acceleration step A for T: closed-form residual of the second-order mode."""
    f, A, T = 5.0, 2.0, 0.137
    w = 2 * np.pi * f
    wd = w * np.sqrt(1 - zeta ** 2)
    sig = zeta * w
    # response of eps'' + 2 sig eps' + w^2 eps = -A (on [0, T]) then free:
    # eps(t) = -A/w^2 (1 - e^{-sig t}(cos wd t + sig/wd sin wd t)) for t <= T
    # pulse = step at 0 minus step at T -> free motion after T is
    # -A/w^2 [e^{-sig T}(...)(T) - e^{0}(...)(0)] -> envelope via complex form:
    # eps(t) = -A Im( e^{p t} (1 - e^{-p T}) / p ) / wd  with p = -sig + j wd
    p = -sig + 1j * wd
    U = A * (1 - np.exp(-p * T)) / p  # int_0^T A e^{-p tau} d tau, referenced at 0
    expected = abs(U * np.exp(p * T)) / wd  # envelope at T
    got = simulate_residual(lambda t, side: A if t < T or side == "left" else 0.0,
                            [0.0], T, f, zeta)
    assert got == pytest.approx(expected, rel=1e-8)


@pytest.mark.parametrize("zeta", [0.0, 0.08])
def test_reference_bang_coast_bang(zeta):
    """AL rest-to-rest move: accelerate A for Ta, coast Tc, decelerate A for Ta."""
    f, A, Ta, Tc = 7.0, 3.0, 0.11, 0.23
    T = 2 * Ta + Tc
    w = 2 * np.pi * f
    p = -zeta * w + 1j * w * np.sqrt(1 - zeta ** 2)
    U = A * (1 - np.exp(-p * Ta)) / p * (1 - np.exp(-p * (Ta + Tc)))
    expected = abs(U * np.exp(p * T)) / w / np.sqrt(1 - zeta ** 2)

    def acc(t, side):
        if t < Ta or (side == "left" and t == Ta):
            return A
        if t < Ta + Tc or (side == "left" and t == Ta + Tc):
            return 0.0
        return -A

    got = simulate_residual(acc, [0.0, Ta, Ta + Tc], T, f, zeta)
    assert got == pytest.approx(expected, rel=1e-8)
