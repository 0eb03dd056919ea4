"""The ``ruckig`` package as the time-optimal jerk-limited reference.

ruckig (Berscheid & Kröger 2021) computes time-optimal jerk-limited
trajectories from any state.  It is an optional dependency of the comparison
only (``pip install '.[compare]'`` from a checkout), never of the FMU: it is imported when
first needed, with a clear error if it is missing.

Only rest-to-rest, one-axis moves are used here.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import HarnessError
from .context import PeerContext, PeerSpec, placed
from .trajectory import PiecewiseJerk, SampledTrajectory

COMPARE_HINT = "pip install '.[compare]' in the source checkout (or pip install ruckig)"
"""How to install the optional ruckig, for messages."""


class RuckigMissingError(HarnessError, ImportError):
    """ruckig is not installed."""


def _ruckig() -> Any:
    try:
        import ruckig  # deferred: an optional dependency (the [compare] extra)
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise RuckigMissingError(
            "the comparison with the time-optimal trajectory needs the 'ruckig' package: "
            + COMPARE_HINT
        ) from e
    return ruckig


def ruckig_available() -> bool:
    """Whether ruckig can be imported."""
    try:
        _ruckig()
    except RuckigMissingError:
        return False
    return True


@dataclass
class RuckigProfile:
    """ruckig's time-optimal rest-to-rest move.

    Attributes
    ----------
    distance, v_max, a_max, j_max : float
        The move and its limits (SI).
    duration : float
        ruckig's duration (s).
    phases : ndarray
        The 7 phase durations of ruckig's profile (s).
    jerks : ndarray
        Jerk of each phase (m/s³).
    Te : float or None
        When set, the duration was rounded up to a multiple of ``Te``
        (ruckig's ``DurationDiscretization.Discrete``).
    trajectory : ruckig.Trajectory
        The ruckig object (for :meth:`at_time`).
    """

    distance: float
    v_max: float
    a_max: float
    j_max: float
    duration: float
    phases: np.ndarray
    jerks: np.ndarray
    Te: float | None = None
    trajectory: Any = field(default=None, repr=False)

    def at_time(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position, velocity and acceleration sampled through ruckig's ``at_time``."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        x = np.empty_like(t)
        v = np.empty_like(t)
        a = np.empty_like(t)
        at = self.trajectory.at_time
        for k, tk in enumerate(t):
            p_, v_, a_ = at(float(tk))
            x[k], v[k], a[k] = p_[0], v_[0], a_[0]
        return x, v, a

    def motion(self, name: str = "time-optimal JL (ruckig)") -> PiecewiseJerk:
        """Rebuild the exact profile from ruckig's phases and jerks."""
        return PiecewiseJerk.from_jerk(self.phases, self.jerks, name=name, params={
            "distance": self.distance, "v_max": self.v_max, "a_max": self.a_max,
            "j_max": self.j_max})

    def sample(self, Te: float, name: str = "time-optimal JL") -> SampledTrajectory:
        """Sample every ``Te`` (exact, from the rebuilt profile)."""
        return self.motion(name).sample(Te)


def time_optimal(distance: float, v_max: float, a_max: float, j_max: float, *,
                 d_max: float | None = None, Te: float | None = None) -> RuckigProfile:
    """Plan ruckig's time-optimal rest-to-rest move of ``distance`` under the limits.

    Parameters
    ----------
    distance : float
        Signed length (m).
    v_max, a_max, j_max : float
        Limits (m/s, m/s², m/s³).
    d_max : float, optional
        Deceleration limit (m/s²); default ``a_max``.
    Te : float, optional
        Round the duration up to a multiple of ``Te`` (ruckig's discrete
        duration mode, limits kept).

    Returns
    -------
    RuckigProfile
    """
    rk = _ruckig()
    otg = rk.Ruckig(1, Te) if Te else rk.Ruckig(1)
    inp = rk.InputParameter(1)
    inp.current_position = [0.0]
    inp.current_velocity = [0.0]
    inp.current_acceleration = [0.0]
    inp.target_position = [float(distance)]
    inp.target_velocity = [0.0]
    inp.target_acceleration = [0.0]
    inp.max_velocity = [float(v_max)]
    inp.max_acceleration = [float(a_max)]
    if d_max is not None:
        inp.min_acceleration = [-float(d_max)]
    inp.max_jerk = [float(j_max)]
    if Te:
        inp.duration_discretization = rk.DurationDiscretization.Discrete
    traj = rk.Trajectory(1)
    result = otg.calculate(inp, traj)
    if result != rk.Result.Working:
        raise RuntimeError(f"ruckig failed on distance={distance}, v_max={v_max}, "
                           f"a_max={a_max}, j_max={j_max}: {result}")
    prof = traj.profiles[0][0]
    return RuckigProfile(float(distance), float(v_max), float(a_max), float(j_max),
                         float(traj.duration), np.array(list(prof.t)), np.array(list(prof.j)),
                         Te, traj)


def planner(v_max: float, a_max: float, j_max: float) -> Any:
    """Return a reusable ``(otg, inp, traj)`` triple for timing many plans (benchmarks)."""
    rk = _ruckig()
    otg = rk.Ruckig(1)
    inp = rk.InputParameter(1)
    inp.current_position = [0.0]
    inp.target_position = [0.0]
    inp.max_velocity = [float(v_max)]
    inp.max_acceleration = [float(a_max)]
    inp.max_jerk = [float(j_max)]
    return otg, inp, rk.Trajectory(1)


def build_time_optimal(ctx: PeerContext, name: str) -> tuple[PiecewiseJerk, PeerSpec]:
    """Peer "time-optimal JL": ruckig under v_max, a_max, d_max and the JL's jerk a_max/T_F(JL).

    Not tuned to the mode; the reference of the motion-time ratios.
    """
    m = ctx.sc.move
    j_max = m.a_max / ctx.T_F_JL
    r = time_optimal(m.distance, m.v_max, m.a_max, j_max, d_max=m.d_max)
    mot = placed(r.motion(name=name), m.t_start, m.x0)
    return mot, PeerSpec(name, f"limits v_max, a_max, d_max, j_max = a_max/T_F(JL) "
                               f"= {j_max:.4g} m/s3 (not tuned)",
                         {"j_max": j_max, "T_opt": r.duration})
