"""What a co-simulation master needs of a generator axis: the :class:`Axis` protocol.

Two axes implement it, with the same generator core and the same values:

* :class:`harness.simulation.fmu_axis.FMUAxis` -- the generator FMU, through
  fmpy, stepped one communication point at a time (the reference: an FMU
  drives the plant, as in any importer);
* :class:`harness.simulation.fast_axis.FastAxis` -- the FMU's C core compiled
  into the extension module ``harness._engine``, every point of a move in one
  call (about a hundred times faster).

A third, :class:`harness.peers.motion_axis.MotionAxis`, wraps a precomputed
motion (the peers' references) for the same master.

The module also holds what every axis shares: :class:`MoveSamples` (a move at
every generator sample) and :func:`stage_starts` (where the four constant-jerk
stages start); :func:`samples_per_step` (the one check that a communication
step is a whole number of generator samples) is
:func:`harness.fmu.runner.samples_per_step`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from ..fmu.runner import samples_per_step

__all__ = [
    "Axis",
    "MoveSamples",
    "PlantInput",
    "PointSamples",
    "samples_per_step",
    "stage_starts",
]


@dataclass
class MoveSamples:
    """One planned move sampled at every generator sample.

    Attributes
    ----------
    t : ndarray
        Time (s).
    x, v, a, j : ndarray
        Reference position (m), velocity (m/s), acceleration (m/s²), jerk over
        the interval that starts at each sample (m/s³).
    a_AL : ndarray
        The adapted acceleration-limited profile before the FIR filters (m/s²):
        its steps are the starts of the constant-jerk stages.
    motion_time : float
        Duration of the move (s), filters included.
    N_F : tuple of int
        Jerk times applied by the FMU (samples).
    t_start : float
        Start of the move (s).
    """

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray
    a_AL: np.ndarray
    motion_time: float
    N_F: tuple[int, int, int, int]
    t_start: float

    @property
    def t_end(self) -> float:
        """End of the move (s)."""
        return self.t_start + self.motion_time

    def position_at(self, t: float) -> float:
        """Exact reference position at time ``t`` (piecewise-cubic evaluation)."""
        Te = float(self.t[1] - self.t[0])
        k = int(math.floor((t - self.t[0]) / Te + 1e-9))
        k = min(max(k, 0), self.t.size - 1)
        tau = t - self.t[k]
        return float(self.x[k] + self.v[k] * tau + self.a[k] * tau**2 / 2
                     + self.j[k] * tau**3 / 6)


@dataclass
class PointSamples:
    """An axis' outputs at the communication points 0, h, ..., n·h.

    Attributes
    ----------
    t : ndarray
        The points (s), ``n + 1`` of them.
    values : dict of ndarray
        One array per output name (``x``, ``v``, ``a``, ``j``, and whatever
        else was asked for), ``n + 1`` values each.
    inputs : dict of ndarray
        The inputs set before the step from each point (the last point has
        none: NaN), when the master set any.
    """

    t: np.ndarray
    values: dict[str, np.ndarray]
    inputs: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def n(self) -> int:
        """Number of communication steps."""
        return int(self.t.size - 1)

    def __getitem__(self, name: str) -> np.ndarray:
        return self.values[name]


@dataclass
class PlantInput:
    """The reference acceleration the plant sees over each communication step.

    Over step k (from point k), the acceleration is ``a[k] + j[k]·τ``: the
    generator's own semantics (``a`` at a point, ``j`` over the interval that
    starts there).  A reference with breakpoints between the points (an input
    shaper's delayed copies, an acceleration step off the grid) lists the
    steps it splits in ``pieces``: step k is then the pieces
    ``(duration, a at its start, jerk)`` in order, each fed exactly.

    Attributes
    ----------
    a, j : ndarray
        Acceleration at the start of each step (m/s²) and jerk over it (m/s³).
    pieces : dict
        Step index -> list of ``(duration, a0, jerk)``.
    """

    a: np.ndarray
    j: np.ndarray
    pieces: dict[int, list[tuple[float, float, float]]] = field(default_factory=dict)

    @classmethod
    def of_points(cls, samples: PointSamples) -> PlantInput:
        """Return the input of a generator's outputs: ``a`` and ``j`` at each point but the last."""
        return cls(samples["a"][:-1], samples["j"][:-1])


InputsHook = Callable[[int], Mapping[str, float]]
"""Called before the step from point k: the inputs to set (name -> value)."""

StopHook = Callable[[int, Mapping[str, np.ndarray]], "int | None"]
"""Called after each step k -> k + 1 with the values recorded so far: the total
number of steps to run once it is known (None: not yet)."""


@runtime_checkable
class Axis(Protocol):
    """A generator axis a master can plan and read (see the module notes).

    Attributes
    ----------
    name : str
        Label, used in messages.
    engine : str
        ``"fmu"``, ``"fast"`` or ``"reference"`` (a precomputed motion).
    fmi_version : int
        2 or 3 for an FMU, 0 otherwise.
    """

    name: str
    engine: str
    fmi_version: int

    def plan(self, params: Mapping[str, Any], start_time: float = 0.0) -> float:
        """Plan a move (parameters not given take the FMU's start values); its duration (s)."""
        ...

    def get(self, name: str) -> Any:
        """Value of a parameter or calculated parameter, named as in the FMU."""
        ...

    def N_F(self) -> tuple[int, int, int, int]:
        """Jerk times applied (samples)."""
        ...

    def motion_start(self) -> float:
        """Time of the generator sample at which the motion starts (s)."""
        ...

    def sample(self, params: Mapping[str, Any], t_stop: float | None = None,
               start_time: float = 0.0) -> MoveSamples:
        """Plan and sample a move at every generator sample."""
        ...

    def sync_velocity(self, params: Mapping[str, Any], target_time: float, v_cap: float,
                      start_time: float = 0.0) -> tuple[float, float, bool]:
        """Velocity limit making the move last ``target_time``; the axis is left planned."""
        ...

    def points(self, n: int, h: float, names: tuple[str, ...] = ("x", "v", "a", "j"), *,
               inputs: InputsHook | None = None, stop: StopHook | None = None
               ) -> PointSamples:
        """Return the outputs of the planned move at the points 0, h, ..., n·h from the start."""
        ...

    def plant_input(self, samples: PointSamples, h: float) -> PlantInput:
        """Return what the plant sees over each step of a run read by :meth:`points`."""
        ...

    def close(self) -> None:
        """Free what the axis holds."""
        ...


def stage_starts(move: MoveSamples) -> tuple[list[float], bool]:
    """Start times of the four constant-jerk stages of a rest-to-rest move.

    The FMU's ``a_AL`` output is the adapted acceleration-limited profile
    before the FIR filters; each of its steps starts one filtered ramp, i.e.
    one constant-jerk stage (§2.3, Fig. 7: steps at 0, T_1, T_2, T_3).  This
    holds also when ramps overlap (``short_stage = 2``), where the jerk output
    alone would be ambiguous.

    Parameters
    ----------
    move : MoveSamples
        A single-segment rest-to-rest move (JL or DJL).

    Returns
    -------
    starts : list of float
        Start times (s) of stages 1..4.
    merged : bool
        True when there is no constant-velocity stage: stage 3 starts exactly
        when stage 2 ends, so the two middle stages form one constant-jerk
        stage (§4: "the two intermediate jerk stages are combined with the
        same jerk-time").

    Raises
    ------
    ValueError
        If the move does not show the four steps of a single rest-to-rest move.
    """
    a = np.concatenate(([0.0], move.a_AL))
    k = np.flatnonzero(np.diff(a) != 0.0)
    times = move.t[k]
    levels = a[k + 1]
    # a direct jump from acceleration to deceleration starts stages 2 and 3 together
    starts: list[float] = []
    prev = 0.0
    for tk, lv in zip(times.tolist(), levels.tolist(), strict=True):
        if prev > 0.0 > lv or prev < 0.0 < lv:
            starts += [tk, tk]
        else:
            starts.append(tk)
        prev = lv
    if len(starts) != 4:
        raise ValueError(f"expected the 4 stages of a rest-to-rest move, found steps of a_AL "
                         f"at {times.tolist()}")
    Te = float(move.t[1] - move.t[0])
    merged = abs(starts[2] - (starts[1] + move.N_F[1] * Te)) < 0.5 * Te or starts[1] == starts[2]
    return starts, merged
