"""Jerk times from the mode map: JL to the end of the motion, DJL stage by stage.

Béarée & Olabi 2013:

* §3.1 — a constant-jerk stage of duration T_F leaves no residual vibration on
  an undamped mode of period T when T_F = k·T; the shortest choice is T_F = T.
* §4 — the JL profile of the comparison is "tuned to cancel the residual
  vibration (jerk time is equal to the natural period of vibration at the end
  of the motion)": :func:`tune_jl`.
* §3.2 — DJL: "each constant jerk stage can be tuned to cancel the vibration
  mode at its time-dependent frequency value"; the conclusions say each stage
  is "tuned to reduce vibration induced at the beginning of the stage": T_Fi is
  the modal period at the start of stage i (rule ``"start"``, the paper's),
  given z(t) of the Z axis.  When the move has no constant-velocity stage the
  two middle stages form one stage and share a jerk time (§4), the period at
  its start.

The start of each stage depends on the jerk times themselves (and, through the
synchronised Z move, so does z(t)), so :func:`tune_djl` iterates: plan with a
guess → read the stage starts from the FMU's output → modal period at those
instants → new jerk times, rounded to samples, until the sample counts stop
changing.  The planning is a callable, so the rule is testable without an FMU.

A second rule, ``"phase"``, is offered for comparison (not the paper's): the
stage lasts exactly one modal cycle of the moving mode, ∫ f(z(t)) dt = 1 over
the stage (2 over a merged middle stage).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from ..simulation.axis import MoveSamples, stage_starts
from ..tuning_options import RULES

__all__ = ["PlanFunction", "TuningResult", "sinc_residual", "tune_djl", "tune_jl"]

PlanFunction = Callable[[tuple[float, float, float, float]], tuple[MoveSamples,
                                                                   Callable[[float], float]]]
"""Plans the excited move for jerk times (T_F1..T_F4, s); returns its samples
and z(t), the Z position (m) as a function of time (s)."""


@dataclass
class TuningResult:
    """Jerk times found by :func:`tune_jl` or :func:`tune_djl`.

    Attributes
    ----------
    profile : str
        ``"JL"`` or ``"DJL"``.
    rule : str
        ``"end"`` (JL), ``"start"`` or ``"phase"`` (DJL).
    T_F : tuple of float
        The four jerk times applied (s), whole multiples of Te.
    N_F : tuple of int
        The same in samples.
    instants : tuple of float
        Where the periods were read: the four stage starts (DJL) or the end of
        the motion (JL) (s).
    z : tuple of float
        Z position at those instants (m).
    periods : tuple of float
        Modal period of the tuned mode at those instants (s).
    merged : bool
        DJL: the two middle stages form one stage (no constant velocity).
    history : list of tuple of int
        Jerk times (samples) planned at each iteration, the last one included.
    converged : bool
        The last plan reproduced its own jerk times.
    search : harness.tuning.search.SearchReport, optional
        For the ``optimal`` and ``robust`` methods: the residual (nominal and
        worst case) of the result and of JL, evaluations and time.
    """

    profile: str
    rule: str
    T_F: tuple[float, float, float, float]
    N_F: tuple[int, int, int, int]
    instants: tuple[float, ...]
    z: tuple[float, ...]
    periods: tuple[float, ...]
    merged: bool = False
    history: list[tuple[int, int, int, int]] = field(default_factory=list)
    converged: bool = True
    search: Any = None

    @property
    def iterations(self) -> int:
        """Number of plans made."""
        return len(self.history)

    def describe(self) -> str:
        """One-line summary."""
        ms = "/".join(f"{t * 1e3:.0f}" for t in (self.T_F[:1] if self.profile == "JL"
                                                  else self.T_F))
        if self.search is not None:
            r = self.search
            what = (f"worst case over the {r.tuned_on}" if r.method == "robust"
                    else "nominal residual")
            return (f"{self.profile} jerk times {ms} ms (method '{self.rule}': minimum "
                    f"{what}; residual {r.nominal * 1e3:.3g} mm, worst over the "
                    f"{r.scored_on} {r.worst * 1e3:.3g} mm; JL {r.jl_nominal * 1e3:.3g} / "
                    f"{r.jl_worst * 1e3:.3g} mm; {r.evaluations} evaluations in "
                    f"{r.seconds:.2f} s)")
        state = "converged" if self.converged else "NOT converged"
        return (f"{self.profile} jerk times {ms} ms (rule '{self.rule}', {state} in "
                f"{self.iterations} plan(s){', middle stages merged' if self.merged else ''})")


def _samples(T: float, Te: float) -> int:
    return max(1, int(round(T / Te)))


def tune_jl(plan: PlanFunction, period_of_z: Callable[[float], float], Te: float,
            initial: float, *, max_iter: int = 20) -> TuningResult:
    """JL jerk time equal to the modal period at the end of the motion (§4).

    Parameters
    ----------
    plan : PlanFunction
        Plans the move for given jerk times.
    period_of_z : callable
        Modal period (s) of the tuned mode at z (m).
    Te : float
        Generator sampling period (s).
    initial : float
        First guess of the jerk time (s).
    max_iter : int
        Largest number of plans.

    Returns
    -------
    TuningResult
    """
    N = _samples(initial, Te)
    history: list[tuple[int, int, int, int]] = []
    seen: set[int] = set()
    move = z_of_t = None
    converged = False
    for _ in range(max_iter):
        move, z_of_t = plan((N * Te,) * 4)
        history.append((N,) * 4)
        seen.add(N)
        P = period_of_z(z_of_t(move.t_end))
        N_new = _samples(P, Te)
        if N_new == N:
            converged = True
            break
        if N_new in seen:  # a cycle: keep the longer (more conservative) jerk time
            N = max(N, N_new)
            move, z_of_t = plan((N * Te,) * 4)
            history.append((N,) * 4)
            break
        N = N_new
    assert move is not None and z_of_t is not None
    zz = z_of_t(move.t_end)
    return TuningResult("JL", "end", (N * Te,) * 4, (N,) * 4, (move.t_end,), (zz,),
                        (period_of_z(zz),), False, history, converged)


def _phase_duration(t0: float, cycles: float, z_of_t: Callable[[float], float],
                    period_of_z: Callable[[float], float], Te: float) -> float:
    """Duration from t0 over which ∫ f(z(t)) dt = cycles (trapezoid on a Te/4 grid)."""
    dt = Te / 4.0
    acc = 0.0
    t = t0
    f0 = 1.0 / period_of_z(z_of_t(t))
    for _ in range(10**7):
        f1 = 1.0 / period_of_z(z_of_t(t + dt))
        inc = 0.5 * (f0 + f1) * dt
        if acc + inc >= cycles:
            return t + dt * (cycles - acc) / inc - t0
        acc += inc
        t += dt
        f0 = f1
    raise RuntimeError("phase integration did not reach its target")  # pragma: no cover


def tune_djl(plan: PlanFunction, period_of_z: Callable[[float], float], Te: float,
             initial: float, *, rule: str = "start", max_iter: int = 20) -> TuningResult:
    """DJL jerk times from the modal period at the start of each stage (§3.2).

    Parameters
    ----------
    plan : PlanFunction
        Plans the move for given jerk times; the samples must show the FMU's
        ``a_AL`` (stage starts, see :func:`harness.simulation.axis.stage_starts`).
    period_of_z : callable
        Modal period (s) of the tuned mode at z (m).
    Te : float
        Generator sampling period (s).
    initial : float
        First guess for all four jerk times (s), e.g. the period at the start.
    rule : {"start", "phase"}
        ``"start"``: T_Fi = period at the start of stage i (the paper's);
        ``"phase"``: one modal cycle of the moving mode per stage.
    max_iter : int
        Largest number of plans.

    Returns
    -------
    TuningResult
        ``converged`` is False when the sample counts still changed after
        ``max_iter`` plans (the last plan is returned) or entered a cycle
        (rounding to samples: the member of the cycle closest to reproducing
        its own jerk times is returned).
    """
    if rule not in RULES:
        raise ValueError(f"unknown DJL tuning rule {rule!r}; choose from {RULES}")
    n0 = _samples(initial, Te)
    N: tuple[int, int, int, int] = (n0, n0, n0, n0)
    history: list[tuple[int, int, int, int]] = []
    plans: list[tuple[tuple[int, int, int, int], float, tuple]] = []
    converged = False
    for _ in range(max_iter):
        move, z_of_t = plan(tuple(n * Te for n in N))  # type: ignore[arg-type]
        history.append(N)
        starts, merged = stage_starts(move)
        zs = [z_of_t(t) for t in starts]
        periods = [period_of_z(z) for z in zs]
        if rule == "start":
            T = list(periods)
            if merged:
                T[2] = T[1]
        else:
            T = [_phase_duration(starts[i], 1.0, z_of_t, period_of_z, Te) for i in range(4)]
            if merged:
                T[1] = T[2] = _phase_duration(starts[1], 2.0, z_of_t, period_of_z, Te) / 2.0
        N_new = tuple(_samples(x, Te) for x in T)
        # how far this plan is from reproducing itself (s)
        mismatch = max(abs(n * Te - x) for n, x in zip(N, T, strict=True))
        plans.append((N, mismatch, (tuple(starts), tuple(zs), tuple(periods), merged)))
        if N_new == N:
            converged = True
            break
        if N_new in history:
            # a cycle of sample counts (rounding): keep the member of the cycle that comes
            # closest to reproducing itself; its plan is re-made so the FMU ends planned with it
            cycle = plans[history.index(N_new):]
            N, _, info = min(cycle, key=lambda c: c[1])
            if N != history[-1]:
                plan(tuple(n * Te for n in N))  # type: ignore[arg-type]
                history.append(N)
            plans.append((N, 0.0, info))
            break
        N = N_new  # type: ignore[assignment]
    starts, zs, periods, merged = plans[-1][2]
    return TuningResult("DJL", rule, tuple(n * Te for n in N), N,  # type: ignore[arg-type]
                        tuple(starts), tuple(zs), tuple(periods), merged, history, converged)


def sinc_residual(T_F: float, period: float) -> float:
    """Residual of one undamped jerk stage relative to an acceleration step (eq. 21).

    |sin(ωT_F/2) / (ωT_F/2)| with ω = 2π/period: 0 when T_F is a multiple of
    the period, 1 for T_F → 0.
    """
    x = math.pi * T_F / period
    return abs(math.sin(x) / x) if x else 1.0
