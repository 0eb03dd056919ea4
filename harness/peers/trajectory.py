"""One representation of a motion for every method compared with AL / JL / DJL.

Two layers:

* :class:`Motion` (abstract) is a rest-to-rest motion known *exactly* at any
  time: :meth:`Motion.evaluate` returns position, velocity, acceleration and
  jerk.  :class:`PiecewiseJerk` covers every law whose jerk is piecewise
  constant (the FMU's AL / JL / DJL, Park's time-optimal profile, ruckig,
  Sato & Shirase's four-jerk-time profile, an AL profile convolved with an
  input shaper); :mod:`harness.peers.damped_jerk` adds the damped-jerk law,
  whose jerk decays exponentially.
* :class:`SampledTrajectory` is a motion sampled at ``Te`` with the same
  fields and the same semantics as the FMU's :class:`~harness.fmu.runner.Trajectory`
  (``t, x, v, a, j, params, motion_time, t_end, done``), so that one plant
  and one set of metrics can take any method.

Sampling semantics (those of the FMU): ``x[k]`` and ``v[k]`` are the exact
values at ``t[k]``; ``a[k]`` is the acceleration just after ``t[k]`` (an
acceleration step at ``t[k]`` is included); ``j[k]`` is the mean jerk over
``[t[k], t[k] + Te)``, i.e. ``(a(t[k+1]^-) - a(t[k]^+)) / Te``.  For a motion
whose jerk only changes at whole samples (the FMU's outputs) the samples
therefore describe the motion exactly; otherwise they are exact at the sample
instants and the acceleration in between is the straight line through them.

Units are SI (s, m, m/s, m/s², m/s³); angles in rad work the same way (Park
et al. give their example in degrees: any consistent unit does).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..fmu import spec

FloatArray = np.ndarray


def _as_array(t: float | Sequence[float] | np.ndarray) -> np.ndarray:
    return np.atleast_1d(np.asarray(t, dtype=float))


class Motion(ABC):
    """A rest-to-rest motion known exactly at any time.

    Attributes
    ----------
    name : str
        Label of the method (used in tables and legends).
    params : dict
        The parameters that define it (SI units).
    """

    name: str
    params: dict[str, Any]

    @property
    @abstractmethod
    def t_start(self) -> float:
        """Time at which the motion starts (s)."""

    @property
    @abstractmethod
    def t_end(self) -> float:
        """Time at which the motion ends (s): the reference is at rest afterwards."""

    @property
    def motion_time(self) -> float:
        """Duration of the motion, ``t_end - t_start`` (s)."""
        return self.t_end - self.t_start

    @abstractmethod
    def evaluate(
        self, t: float | Sequence[float] | np.ndarray, side: str = "right"
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Position, velocity, acceleration and jerk at the times ``t``.

        Parameters
        ----------
        t : array_like
            Times (s).
        side : {"right", "left"}
            At a time where the acceleration (or the jerk) steps, return the
            value just after (``"right"``, default) or just before it.

        Returns
        -------
        x, v, a, j : ndarray
            Arrays shaped like ``np.atleast_1d(t)``.
        """

    @abstractmethod
    def breakpoints(self) -> FloatArray:
        """Return the times where the acceleration or the jerk is not smooth (sorted).

        Between two consecutive breakpoints the acceleration is an analytic
        function of time; an ODE solver or a quadrature should split there.
        """

    @property
    def distance(self) -> float:
        """Signed length of the move (m)."""
        x = self.evaluate([self.t_start, self.t_end])[0]
        return float(x[1] - x[0])

    def sample(self, Te: float, t_stop: float | None = None, t0: float = 0.0,
               name: str | None = None) -> SampledTrajectory:
        """Sample the motion every ``Te`` from ``t0`` to ``t_stop`` (FMU semantics).

        Parameters
        ----------
        Te : float
            Sampling period (s).
        t_stop : float, optional
            Last sample time; default: the end of the motion rounded up to a
            sample, plus 10 samples (as :func:`harness.fmu.runner.generate`).
        t0 : float
            First sample time (s).
        name : str, optional
            Name of the result (default: the motion's).

        Returns
        -------
        SampledTrajectory
        """
        if not Te > 0.0:
            raise ValueError(f"Te must be positive, got {Te!r}")
        if t_stop is None:
            t_stop = t0 + np.ceil((self.t_end - t0) / Te - 1e-9) * Te + 10 * Te
        n = int(np.floor((t_stop - t0) / Te + 1e-9))
        t = t0 + Te * np.arange(n + 1)
        x, v, a, _ = self.evaluate(t, side="right")
        _, _, a_left, _ = self.evaluate(t[1:], side="left")
        j = np.zeros_like(t)
        j[:-1] = (a_left - a[:-1]) / Te
        j[t >= self.t_end - 1e-12 * max(1.0, abs(self.t_end))] = 0.0
        return SampledTrajectory(
            name=name or self.name, t=t, x=x, v=v, a=a, j=j, params=dict(self.params),
            motion_time=self.motion_time, t_start=self.t_start, Te=Te, exact=self,
        )

    def plot(self, Te: float | None = None, title: str | None = None):
        """Plot x, v, a, j against time; return the matplotlib Figure."""
        Te = Te or max(self.motion_time / 2000.0, 1e-6)
        return self.sample(Te).plot(title=title)


@dataclass
class PiecewiseJerk(Motion):
    """A motion whose jerk is constant between breakpoints.

    Piece ``i`` spans ``[tb[i], tb[i+1])``; ``x[i], v[i], a[i]`` are the
    state just after ``tb[i]`` (so an acceleration step at ``tb[i]`` is in
    ``a[i]``) and ``j[i]`` the jerk on the piece.  Before ``tb[0]`` the
    acceleration is zero (the motion rests at ``x[0]`` when ``v[0] = 0``);
    after ``tb[-1]`` the jerk is zero (``j[-1]`` is ignored) and the
    acceleration must be zero for the motion to end at rest.

    Parameters
    ----------
    tb : array_like
        Breakpoints (s), strictly increasing.
    x, v, a, j : array_like
        State just after each breakpoint and jerk of each piece.
    name : str
        Label of the method.
    params : dict
        Parameters that define the motion.
    """

    tb: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray
    name: str = "motion"
    params: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        self.tb = _as_array(self.tb)
        self.x, self.v, self.a, self.j = (_as_array(z) for z in (self.x, self.v, self.a, self.j))
        n = self.tb.size
        if not all(z.size == n for z in (self.x, self.v, self.a, self.j)):
            raise ValueError("tb, x, v, a and j must have the same length")
        if n == 0:
            raise ValueError("a motion needs at least one breakpoint")
        if np.any(np.diff(self.tb) <= 0.0):
            raise ValueError("breakpoints must be strictly increasing")

    # ------------------------------------------------------------ builders

    @classmethod
    def from_jerk(
        cls,
        durations: Sequence[float],
        jerks: Sequence[float],
        *,
        t0: float = 0.0,
        x0: float = 0.0,
        v0: float = 0.0,
        a0: float = 0.0,
        name: str = "motion",
        params: Mapping[str, Any] | None = None,
    ) -> PiecewiseJerk:
        """Integrate a sequence of constant-jerk phases.

        Parameters
        ----------
        durations : sequence of float
            Phase durations (s, >= 0; zero-length phases are dropped, and one too
            short to advance the time at its start is folded into the state there).
        jerks : sequence of float
            Jerk of each phase (m/s³).
        t0, x0, v0, a0 : float
            Start time and state.
        name, params
            Label and parameters of the result.
        """
        d = np.asarray(durations, dtype=float)
        jr = np.asarray(jerks, dtype=float)
        if d.shape != jr.shape:
            raise ValueError("durations and jerks must have the same length")
        if np.any(d < 0.0):
            raise ValueError(f"negative phase duration in {d}")
        keep = d > 0.0
        d, jr = d[keep], jr[keep]
        tb = [t0]
        xs, vs, as_, js = [x0], [v0], [a0], []
        for h, jj in zip(d, jr, strict=True):
            x, v, a = xs[-1], vs[-1], as_[-1]
            x1 = x + v * h + a * h * h / 2 + jj * h ** 3 / 6
            v1 = v + a * h + jj * h * h / 2
            a1 = a + jj * h
            if tb[-1] + h <= tb[-1]:
                # a phase shorter than the time resolution at tb[-1] (e.g. 1e-17 s left by
                # rounding in a closed-form solution): its tiny state change is folded into
                # the breakpoint, which stays strictly increasing
                xs[-1], vs[-1], as_[-1] = x1, v1, a1
                continue
            js.append(jj)
            xs.append(x1)
            vs.append(v1)
            as_.append(a1)
            tb.append(tb[-1] + h)
        js.append(0.0)
        return cls(np.array(tb), np.array(xs), np.array(vs), np.array(as_), np.array(js),
                   name=name, params=dict(params or {}))

    @classmethod
    def from_samples(cls, t: np.ndarray, x: np.ndarray, v: np.ndarray, a: np.ndarray,
                     j: np.ndarray, *, name: str = "motion",
                     params: Mapping[str, Any] | None = None) -> PiecewiseJerk:
        """Rebuild the exact motion behind samples whose jerk is constant per sample (FMU).

        The samples must be taken every ``Te`` (communication step = ``Te``).
        """
        return cls(np.asarray(t, float).copy(), np.asarray(x, float).copy(),
                   np.asarray(v, float).copy(), np.asarray(a, float).copy(),
                   np.asarray(j, float).copy(), name=name, params=dict(params or {}))

    # ------------------------------------------------------------ Motion API

    def _moving(self) -> np.ndarray:
        """Pieces on which the acceleration or the jerk is not zero."""
        moving = (np.abs(self.a) > 0) | (np.abs(self.j) > 0)
        moving[-1] = abs(self.a[-1]) > 0
        return moving

    @property
    def t_start(self) -> float:
        """First breakpoint where the motion leaves rest (s)."""
        idx = np.flatnonzero(self._moving())
        return float(self.tb[idx[0]]) if idx.size else float(self.tb[0])

    @property
    def t_end(self) -> float:
        """Breakpoint after which jerk and acceleration stay zero (s)."""
        idx = np.flatnonzero(self._moving())
        if not idx.size:
            return float(self.tb[0])
        return float(self.tb[min(int(idx[-1]) + 1, self.tb.size - 1)])

    def breakpoints(self) -> FloatArray:
        """Return the breakpoints ``tb``."""
        return self.tb.copy()

    def evaluate(self, t, side: str = "right"):
        """Exact x, v, a, j at ``t`` (see :meth:`Motion.evaluate`)."""
        t = _as_array(t)
        if side not in ("right", "left"):
            raise ValueError("side must be 'right' or 'left'")
        i = np.searchsorted(self.tb, t, side=side) - 1
        before = i < 0
        ic = np.clip(i, 0, self.tb.size - 1)
        h = t - self.tb[ic]
        jj = np.where(ic == self.tb.size - 1, 0.0, self.j[ic])
        x0, v0, a0 = self.x[ic], self.v[ic], self.a[ic]
        x = x0 + v0 * h + a0 * h * h / 2 + jj * h ** 3 / 6
        v = v0 + a0 * h + jj * h * h / 2
        a = a0 + jj * h
        x = np.where(before, self.x[0] + self.v[0] * (t - self.tb[0]), x)
        v = np.where(before, self.v[0], v)
        a = np.where(before, 0.0, a)
        jj = np.where(before, 0.0, jj)
        return x, v, a, jj

    def simplified(self, rtol: float = 1e-9) -> PiecewiseJerk:
        """Return the same motion without the breakpoints where nothing changes.

        A breakpoint is dropped when the jerk on both sides is the same and the
        acceleration is continuous there (both to ``rtol`` times the largest
        |jerk| and |acceleration|): e.g. the FMU's profiles, rebuilt with one
        breakpoint per sample, keep only their stage boundaries.  The state at
        the kept breakpoints is unchanged, so the motion is the same to
        ``rtol`` (and to rounding for exactly constant jerk).
        """
        if self.tb.size < 3:
            return self
        j_tol = rtol * max(float(np.max(np.abs(self.j[:-1]))), 1e-300)
        a_tol = rtol * max(float(np.max(np.abs(self.a))), 1e-300)
        h = np.diff(self.tb)
        a_left = self.a[:-1] + self.j[:-1] * h  # just before tb[1:]
        same = (np.abs(self.j[1:-1] - self.j[:-2]) <= j_tol) & (
            np.abs(self.a[1:-1] - a_left[:-1]) <= a_tol)
        keep = np.r_[True, ~same, True]
        i = np.flatnonzero(keep)
        return PiecewiseJerk(self.tb[i], self.x[i], self.v[i], self.a[i], self.j[i],
                             name=self.name, params=dict(self.params))

    # ------------------------------------------------------------ algebra

    def shifted(self, delay: float, *, name: str | None = None) -> PiecewiseJerk:
        """Return the same motion ``delay`` seconds later."""
        return PiecewiseJerk(self.tb + delay, self.x, self.v, self.a, self.j,
                             name=name or self.name, params=dict(self.params))

    @staticmethod
    def weighted_sum(
        motions: Sequence[PiecewiseJerk],
        weights: Sequence[float],
        delays: Sequence[float] | None = None,
        *,
        name: str = "sum",
        params: Mapping[str, Any] | None = None,
        merge_tol: float = 1e-12,
    ) -> PiecewiseJerk:
        """Exact ``sum_i w_i m_i(t - d_i)`` of piecewise-jerk motions.

        Convolving a motion with an impulse sequence (an input shaper) is the
        weighted sum of delayed copies; the result is again piecewise-jerk.

        Parameters
        ----------
        motions : sequence of PiecewiseJerk
        weights : sequence of float
        delays : sequence of float, optional
            Delays (s); zeros by default.
        name, params
            Label and parameters of the result.
        merge_tol : float
            Breakpoints closer than ``merge_tol * max(1, |t|)`` are merged (the
            state is taken just after the later one: the error is of the order
            of the velocity times ``merge_tol``).
        """
        if delays is None:
            delays = [0.0] * len(motions)
        if not (len(motions) == len(weights) == len(delays)):
            raise ValueError("motions, weights and delays must have the same length")
        shifted = [m.shifted(d) for m, d in zip(motions, delays, strict=True)]
        tb = np.unique(np.concatenate([m.tb for m in shifted]))
        scale = np.maximum(1.0, np.abs(tb))
        new = np.ones(tb.size, dtype=bool)
        new[1:] = np.diff(tb) > merge_tol * scale[1:]
        starts = np.flatnonzero(new)
        ends = np.r_[starts[1:] - 1, tb.size - 1]
        t_keep = tb[starts]
        t_eval = tb[ends]
        mid = np.r_[0.5 * (t_eval[:-1] + t_keep[1:]), t_eval[-1] + 1.0]
        x = np.zeros(t_keep.size)
        v = np.zeros(t_keep.size)
        a = np.zeros(t_keep.size)
        j = np.zeros(t_keep.size)
        for m, w in zip(shifted, weights, strict=True):
            xm, vm, am, _ = m.evaluate(t_eval)
            x += w * xm
            v += w * vm
            a += w * am
            j += w * m.evaluate(mid)[3]
        j[-1] = 0.0
        return PiecewiseJerk(t_keep, x, v, a, j, name=name, params=dict(params or {}))


@dataclass
class SampledTrajectory:
    """A motion sampled every ``Te`` (the FMU's :class:`Trajectory` semantics).

    Attributes
    ----------
    name : str
        Label of the method.
    t, x, v, a, j : ndarray
        Time (s), position (m), velocity (m/s), acceleration (m/s²) and mean
        jerk over the following sample interval (m/s³).
    params : dict
        Parameters of the method.
    motion_time : float
        Duration of the motion (s).
    t_start : float
        Time at which the motion starts (s).
    Te : float
        Sampling period (s).
    exact : Motion or None
        The exact motion these samples come from, when known.
    """

    name: str
    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray
    params: dict[str, Any]
    motion_time: float
    t_start: float = 0.0
    Te: float = 1e-3
    exact: Motion | None = None

    @property
    def t_end(self) -> float:
        """Time at which the motion ends (s)."""
        return self.t_start + self.motion_time

    @property
    def done(self) -> np.ndarray:
        """True from the first sample at or after the end of the motion."""
        return self.t >= self.t_end - 1e-9 * max(1.0, abs(self.t_end))

    @property
    def distance(self) -> float:
        """Signed length of the move (m)."""
        return float(self.x[-1] - self.x[0])

    def to_motion(self) -> Motion:
        """Return the exact motion if known, else the one the samples describe."""
        if self.exact is not None:
            return self.exact
        return PiecewiseJerk.from_samples(self.t, self.x, self.v, self.a, self.j,
                                          name=self.name, params=self.params)

    def peaks(self) -> dict[str, float]:
        """Largest |v|, |a|, |j| of the samples."""
        return {"v": float(np.max(np.abs(self.v))), "a": float(np.max(np.abs(self.a))),
                "j": float(np.max(np.abs(self.j)))}

    def plot(self, *, title: str | None = None, others: Sequence[SampledTrajectory] = ()):
        """Plot x, v, a, j (and those of ``others``) against time; return the Figure."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        fig, axes = plt.subplots(4, 1, sharex=True, figsize=(8, 8))
        rows = [("x", "x [m]"), ("v", "v [m/s]"), ("a", "a [m/s²]"), ("j", "j [m/s³]")]
        for tr in (self, *others):
            for ax, (nm, _) in zip(axes, rows, strict=True):
                kw = {"drawstyle": "steps-post"} if nm == "j" else {}
                ax.plot(tr.t, getattr(tr, nm), label=tr.name, **kw)
        for ax, (_, label) in zip(axes, rows, strict=True):
            ax.set_ylabel(label)
            ax.grid(True, alpha=0.3)
        axes[0].legend(loc="lower right", fontsize="small")
        axes[-1].set_xlabel("t [s]")
        fig.suptitle(title or f"{self.name}: motion time {self.motion_time:.4g} s")
        fig.tight_layout()
        return fig


def from_fmu(traj: Any, name: str | None = None) -> SampledTrajectory:
    """Wrap the FMU's :class:`~harness.fmu.runner.Trajectory` as a :class:`SampledTrajectory`.

    The FMU's jerk is constant on every sample interval, so the exact motion
    is rebuilt from the samples (:meth:`PiecewiseJerk.from_samples`); the
    trajectory must have been recorded with the communication step ``Te``.

    Parameters
    ----------
    traj : harness.fmu.runner.Trajectory
        Output of :func:`harness.fmu.runner.generate`.
    name : str, optional
        Label; default ``"AL"``, ``"JL"`` or ``"DJL"`` from the profile parameter.
    """
    profile = int(traj.params.get("profile", 3))
    name = name or spec.PROFILE_NAMES.get(profile, "FMU")
    Te = float(traj.params.get("Te", traj.t[1] - traj.t[0]))
    if not np.allclose(np.diff(traj.t), Te, rtol=1e-9, atol=0.0):
        raise ValueError("the FMU trajectory must be sampled at its Te (dt = Te)")
    t_start = float(traj.params.get("t_start", 0.0))
    exact = PiecewiseJerk.from_samples(traj.t, traj.x, traj.v, traj.a, traj.j, name=name,
                                       params=dict(traj.params))
    return SampledTrajectory(name=name, t=np.asarray(traj.t), x=np.asarray(traj.x),
                             v=np.asarray(traj.v), a=np.asarray(traj.a), j=np.asarray(traj.j),
                             params=dict(traj.params), motion_time=float(traj.motion_time),
                             t_start=t_start, Te=Te, exact=exact)
