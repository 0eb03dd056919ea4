"""A precomputed motion as an :class:`~harness.simulation.axis.Axis` of the master.

The peers' references (input shapers, Sato's profile, the time-optimal
motion, ...) are exact :class:`~harness.peers.trajectory.Motion` objects.
:class:`MotionAxis` lets the co-simulation master
(:func:`harness.simulation.master.cosimulate`) run them through the same plant
as the generator's profiles: its outputs at the communication points are the
motion's samples (the FMU's semantics: ``a`` at a point, ``j`` the chord over
the step), and the plant sees its exact acceleration, each step split at the
motion's breakpoints in between (acceleration steps or jerk changes off the
grid, e.g. a shaper's delayed copies) and every piece fed with its own
linear acceleration -- the plant's exact update.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from ..simulation.axis import InputsHook, MoveSamples, PlantInput, PointSamples, StopHook
from ..simulation.master import CoSimResult, cosimulate, map_error_residuals
from ..uncertainty import check_map_errors
from .trajectory import Motion

__all__ = ["MotionAxis", "cosimulate_reference", "reference_axis", "reference_map_error_residuals"]


class MotionAxis:
    """A reference motion fed to the master in place of a generator axis.

    Parameters
    ----------
    motion : Motion
        The exact reference.
    Te : float
        The generator's sampling period of the scenario (s): the step must be a
        whole multiple of it.
    x0, distance : float
        Start position and signed length of the move (m).
    """

    engine = "reference"
    """A precomputed motion (the master takes the engine and FMI version of the Z axis)."""

    fmi_version = 0

    def __init__(self, motion: Motion, *, Te: float, x0: float, distance: float) -> None:
        self.motion = motion
        self.name = motion.name or "reference"
        self._values = {"Te": float(Te), "motion_time": float(motion.motion_time),
                        "t_start": float(motion.t_start), "x0": float(x0),
                        "distance": float(distance)}

    def plan(self, params: Mapping[str, Any] | None = None, start_time: float = 0.0) -> float:
        """Nothing to plan: the motion's duration (s)."""
        return self.motion.motion_time

    def get(self, name: str) -> Any:
        """``Te``, ``motion_time``, ``t_start``, ``x0`` or ``distance``."""
        try:
            return self._values[name]
        except KeyError:
            raise KeyError(f"{self.name}: a reference motion has no {name!r}") from None

    def N_F(self) -> tuple[int, int, int, int]:
        """No jerk times of the generator's (zeros)."""
        return (0, 0, 0, 0)

    def motion_start(self) -> float:
        """Start of the motion (s)."""
        return float(self.motion.t_start)

    def sample(self, params: Mapping[str, Any] | None = None, t_stop: float | None = None,
               start_time: float = 0.0) -> MoveSamples:
        """Return the motion at every sample of ``Te``."""
        st = self.motion.sample(self._values["Te"], t_stop=t_stop, t0=start_time)
        return MoveSamples(st.t, st.x, st.v, st.a, st.j, st.a, self.motion.motion_time,
                           (0, 0, 0, 0), float(self.motion.t_start))

    def sync_velocity(self, params: Mapping[str, Any], target_time: float, v_cap: float,
                      start_time: float = 0.0) -> tuple[float, float, bool]:
        """Not available: a reference motion has a fixed duration."""
        raise ValueError(f"{self.name}: a reference motion cannot be re-timed")

    def points(self, n: int, h: float, names: tuple[str, ...] = ("x", "v", "a", "j"), *,
               inputs: InputsHook | None = None, stop: StopHook | None = None
               ) -> PointSamples:
        """Return the motion sampled at the points 0, h, ..., n·h (no inputs)."""
        if inputs is not None or stop is not None:
            raise ValueError(f"{self.name}: a reference motion takes no inputs")
        ref = self.motion.sample(h, t_stop=n * h)
        have = {"x": ref.x, "v": ref.v, "a": ref.a, "j": ref.j}
        unknown = [nm for nm in names if nm not in have]
        if unknown:
            raise ValueError(f"{self.name}: a reference motion has no output {unknown[0]!r}")
        return PointSamples(ref.t, {nm: have[nm] for nm in names})

    def plant_input(self, samples: PointSamples, h: float) -> PlantInput:
        """Return the exact acceleration: each step from ``a`` to the chord's end, split.

        A step without a breakpoint inside is fed from a(t_k) linearly to
        a(t_k) + j_k·h; a step with breakpoints is cut there, each piece fed
        from the motion's acceleration just after its start to the one just
        before its end.
        """
        motion, t = self.motion, samples.t
        a, j = samples["a"], samples["j"]
        a_end = a + j * h  # acceleration at the end of each step (jerk constant per step)
        jerk = (a_end[:-1] - a[:-1]) / h
        bp = motion.breakpoints()
        bp = bp[(bp > t[0]) & (bp < t[-1])]
        k_bp = np.searchsorted(t, bp, side="right") - 1  # step index of each breakpoint
        off = bp > t[k_bp]
        bp, k_bp = bp[off], k_bp[off]
        pieces: dict[int, list[tuple[float, float, float]]] = {}
        if bp.size:
            ks = np.unique(k_bp)
            # every edge of every split step, in order: t[k], its breakpoints, t[k + 1]
            pts = np.unique(np.concatenate((t[ks], t[ks + 1], bp)))
            e0, e1 = pts[:-1], pts[1:]
            k0 = np.searchsorted(t, e0, side="right") - 1
            inside = np.isin(k0, ks) & (e1 <= t[np.minimum(k0 + 1, t.size - 1)]) & (e1 > e0)
            e0, e1, k0 = e0[inside], e1[inside], k0[inside]
            ar = motion.evaluate(e0, side="right")[2]
            al = motion.evaluate(e1, side="left")[2]
            for k, x0, x1, u0, u1 in zip(k0.tolist(), e0.tolist(), e1.tolist(), ar.tolist(),
                                         al.tolist(), strict=True):
                hh = x1 - x0
                pieces.setdefault(k, []).append((hh, u0, (u1 - u0) / hh))
        return PlantInput(a[:-1], jerk, pieces)

    def close(self) -> None:
        """Nothing to free."""


def reference_axis(sc: Any, motion: Motion) -> MotionAxis:
    """Return the motion as an axis of the scenario's excited axis (its Te, start, length)."""
    return MotionAxis(motion, Te=sc.simulation.Te, x0=sc.move.x0, distance=sc.move.distance)


def cosimulate_reference(sc: Any, session: Any, motion: Motion, label: str,
                         t_stop: float | None = None) -> CoSimResult:
    """Step the Z generator and the scenario's plant with a precomputed reference.

    The master of every run (:func:`harness.simulation.master.cosimulate`)
    with the exact ``motion`` in place of the excited axis' generator
    (:class:`~harness.peers.motion_axis.MotionAxis`); everything else is the
    same: the Z move (synchronised with the motion time when the scenario asks
    for it), the scheduled plant, the mode frozen over each communication step
    at the Z position of mid-step.  Within a step the plant's input is exact:
    the step is split at the motion's breakpoints (acceleration steps or jerk
    changes between samples, e.g. the delayed copies of an input shaper) and
    each piece is advanced with its own linear acceleration.

    Returns
    -------
    harness.simulation.master.CoSimResult
    """
    v_z, synced = session.z_velocity(sc, motion.motion_time)
    T_z = session.z_axis.plan(session.z_move_params(sc, v_z))
    if t_stop is None:
        t_stop = sc.move.t_start + max(motion.motion_time, T_z) + sc.simulation.t_after
    run = cosimulate(reference_axis(sc, motion), session.z_axis, sc.modemap.scheduled(),
                     t_stop, sc.simulation.step, profile=label)
    run.z_synced = synced
    return run


def reference_map_error_residuals(sc: Any, session: Any, motion: Motion,
                                  errors: Sequence[float] | np.ndarray) -> np.ndarray:
    """Residual of a precomputed reference when the whole mode map is off by 1 + e.

    The reference is the one planned on the nominal map, the Z move the same
    (it does not depend on the map); only the plant's frequencies are scaled,
    and it is stepped to the end of the reference once per error
    (:func:`harness.simulation.master.map_error_residuals`, as for AL / JL /
    DJL).

    Parameters
    ----------
    sc : harness.scenario.Scenario
        The nominal scenario.
    session : harness.simulation.session.Session
        Its Z axis.
    motion : Motion
        The reference (planned on the nominal map).
    errors : array_like
        Relative map errors e (> -1).

    Returns
    -------
    ndarray
        Residual (m) for each error.
    """
    e = check_map_errors(errors)
    v_z, _ = session.z_velocity(sc, motion.motion_time)
    session.z_axis.plan(session.z_move_params(sc, v_z))
    return map_error_residuals(reference_axis(sc, motion), session.z_axis,
                               sc.modemap.scheduled(), 1.0 + e, sc.simulation.step)
