"""What a peer method is built from: a :class:`PeerContext` in, a motion and its spec out.

Every peer module has a builder ``build_*(ctx, name) -> (motion, spec)``; the
registry (:mod:`harness.peers.registry`) lists them in table order.  The
context holds the scenario's move, the JL the peers are compared with, the
mode at the end of the motion they are tuned to, and the generator's own AL
and JL profiles of the move (planned once, through the session).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from .trajectory import Motion, PiecewiseJerk

__all__ = ["PeerBuilder", "PeerContext", "PeerSpec", "placed"]


@dataclass
class PeerSpec:
    """How one peer was built (for the table header and the CSV).

    Attributes
    ----------
    name : str
    tuned_to : str
        Human-readable tuning.
    params : dict
        The numbers.
    """

    name: str
    tuned_to: str
    params: dict[str, Any] = field(default_factory=dict)


@dataclass
class PeerContext:
    """The move a peer is built for, and what it is tuned to.

    Attributes
    ----------
    sc : harness.scenario.Scenario
        The single-move scenario.
    T_F_JL : float
        JL jerk time (s) found by the harness (the time-optimal jerk limit and
        the JL profile the ``JL*`` shapers act on).
    motion_time_JL : float
        JL motion time (s) (Sato's positioning time).
    session : harness.simulation.session.Session
        Plans the generator's profiles and the synchronised Z move.
    f_end, zeta : float
        The tuned mode at the end of the motion (Hz, -): what the peers are
        tuned to.
    base : callable
        ``base(profile, distance=None)``: the generator's AL or JL profile of
        the move (for another signed distance when given), an exact motion.
    """

    sc: Any
    T_F_JL: float
    motion_time_JL: float
    session: Any
    f_end: float
    zeta: float
    base: Callable[..., PiecewiseJerk]

    @property
    def sign(self) -> float:
        """Direction of the move (+1 or -1)."""
        return 1.0 if self.sc.move.distance > 0 else -1.0

    @property
    def mode_text(self) -> str:
        """The mode the peers are tuned to, in words."""
        return f"{self.f_end:.4g} Hz, zeta = {self.zeta:g} (mode at the end of the motion)"


PeerBuilder = Callable[[PeerContext, str], tuple[Motion, PeerSpec]]
"""Builds the peer ``name`` for a context."""


def placed(m: PiecewiseJerk, t_start: float, x0: float, sign: float = 1.0) -> PiecewiseJerk:
    """Start the motion at ``t_start`` from ``x0``; mirror it when ``sign < 0``."""
    return PiecewiseJerk(m.tb + t_start, x0 + sign * (m.x - m.x[0]), sign * m.v, sign * m.a,
                         sign * m.j, name=m.name, params=dict(m.params))
