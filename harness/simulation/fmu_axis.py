"""The generator FMU as an :class:`~harness.simulation.axis.Axis`: :class:`FMUAxis`.

Creating a :class:`~harness.fmu.runner.GeneratorFMU` unzips the FMU and loads
its library (tens of milliseconds); re-planning an existing instance with
``fmiReset`` → parameters → initialisation costs tens of microseconds.  The
harness therefore keeps one instance per axis (:class:`FMUAxis`) and re-plans
it for every probe: the DJL tuning iterations, the synchronisation of the Z
move, and each profile of a scenario.

Every trajectory of the harness comes out of the generator FMU (through fmpy
here, or its C core compiled in :mod:`harness.simulation.fast_axis`): nothing
here re-implements the planner.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..fmu.runner import GeneratorFMU
from .axis import InputsHook, MoveSamples, PlantInput, PointSamples, StopHook

__all__ = ["FMUAxis"]


class FMUAxis:
    """A generator FMU instance that is re-planned (reset) rather than re-created.

    Implements :class:`~harness.simulation.axis.Axis` through fmpy.

    Parameters
    ----------
    fmu : path-like, optional
        Generator FMU file; default: the package's own build for ``fmi_version``.
    fmi_version : {2, 3}
        FMU version when ``fmu`` is not given.
    name : str
        Instance name.
    """

    def __init__(self, fmu: str | Path | None = None, *, fmi_version: int = 2,
                 name: str = "axis") -> None:
        self.g = GeneratorFMU(fmu, fmi_version=fmi_version, instance_name=name)
        self.name = name
        self._fresh = True
        self._stepped = False  # stepped since the last plan: points() re-plans first
        self.params: dict[str, Any] = {}
        self.start_time = 0.0

    engine = "fmu"
    """The generator FMU through fmpy."""

    @property
    def fmi_version(self) -> int:
        """FMI version of the FMU (2 or 3)."""
        return self.g.fmi_version

    def plan(self, params: Mapping[str, Any], start_time: float = 0.0) -> float:
        """Reset the instance, set ``params``, initialise; return the motion time (s).

        Parameters not given take the FMU's start values.
        """
        g = self.g
        if self._fresh:
            if start_time != g.start_time:
                raise ValueError("the first plan must use the instance's start time")
            g.set(params)
            g.initialize()
        else:
            g.replan(params, start_time)
        self._fresh = False
        self._stepped = False
        self.start_time = start_time
        self.params = dict(params)
        return float(g.get("motion_time"))

    def get(self, name: str) -> Any:
        """Value of one FMU variable."""
        return self.g.get(name)

    def N_F(self) -> tuple[int, int, int, int]:
        """Jerk times applied by the FMU (samples)."""
        return tuple(int(self.g.get(f"N_F{i}")) for i in range(1, 5))  # type: ignore[return-value]

    def motion_start(self) -> float:
        """Time of the generator sample at which the motion starts (s)."""
        return self.g.motion_start()

    def points(self, n: int, h: float, names: tuple[str, ...] = ("x", "v", "a", "j"), *,
               inputs: InputsHook | None = None, stop: StopHook | None = None
               ) -> PointSamples:
        """Step the planned FMU: its outputs at the points 0, h, ..., n·h.

        Always from the start of the planned move, like the fast engine: a
        second call on an instance already stepped re-plans it with the same
        parameters first (an FMU only steps forward).

        Parameters
        ----------
        n : int
            Communication steps (with ``stop``: at most that many).
        h : float
            Communication step (s).
        names : tuple of str
            Outputs to record (Real, Integer or Boolean).
        inputs : callable, optional
            ``inputs(k)`` -> the inputs to set before the step from point k.
        stop : callable, optional
            Ends the run early (see :meth:`harness.fmu.runner.GeneratorFMU.record`).

        Returns
        -------
        PointSamples
        """
        g = self.g
        if self._stepped:
            self.plan(self.params, self.start_time)
        self._stepped = True
        reals = tuple(nm for nm in names if g.variable(nm).type in ("Real", "Float64"))
        flags = tuple(nm for nm in names if nm not in reals)
        rec: dict[str, list[float]] = {}
        hook = None
        if inputs is not None:
            def hook(k: int) -> Mapping[str, Any]:
                got = inputs(k)
                for key, value in got.items():
                    rec.setdefault(key, []).append(value)
                return got
        t, values = g.record(n, h, reals, flags, inputs=hook, stop=stop)
        got_inputs = {key: np.asarray(v + [np.nan], dtype=float) for key, v in rec.items()}
        return PointSamples(t, {nm: values[nm] for nm in names}, got_inputs)

    def sync_velocity(self, params: Mapping[str, Any], target_time: float, v_cap: float,
                      start_time: float = 0.0) -> tuple[float, float, bool]:
        """Velocity limit that makes a move last ``target_time`` (not longer).

        Bisection on ``v_max`` with the FMU's own planner (its ``motion_time``),
        so that the Z move, started with the excited axis, ends with it: the
        smallest velocity whose motion time is ≤ ``target_time``.  The axis is
        left planned with the result.

        Parameters
        ----------
        params : mapping
            The move's parameters except ``v_max``.
        target_time : float
            Motion time to match (s).
        v_cap : float
            Largest velocity allowed (m/s).
        start_time : float
            FMU start time.

        Returns
        -------
        v_max : float
            The velocity limit (m/s).
        motion_time : float
            The resulting motion time (s).
        synced : bool
            False when even ``v_cap`` is too slow (the move then ends later).
        """
        p = dict(params)
        d = abs(float(p["distance"]))

        def time_at(v: float) -> float:
            p["v_max"] = v
            return self.plan(p, start_time)

        t_cap = time_at(v_cap)
        if t_cap > target_time:
            return v_cap, t_cap, False
        lo = min(d / target_time, v_cap)  # too slow: the move lasts more than d / v
        if time_at(lo) <= target_time:
            return lo, self.plan(p, start_time), True
        hi = v_cap
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if time_at(mid) <= target_time:
                hi = mid
            else:
                lo = mid
            if hi - lo <= 1e-9 * hi:
                break
        t = time_at(hi)
        return hi, t, True

    def sample(self, params: Mapping[str, Any], t_stop: float | None = None,
               start_time: float = 0.0) -> MoveSamples:
        """Plan and run a move at every generator sample.

        Parameters
        ----------
        params : mapping
            FMU parameters.
        t_stop : float, optional
            Last sample time; default: the end of the move.
        start_time : float
            Start time of the FMU.

        Returns
        -------
        MoveSamples
        """
        motion_time = self.plan(params, start_time)
        g = self.g
        Te = float(g.get("Te"))
        t_start = float(g.get("t_start"))
        if t_stop is None:
            t_stop = max(g.motion_start(), start_time) + motion_time
        n = int(round((t_stop - start_time) / Te))
        self._stepped = True
        t, v = g.record(n, Te, ("x", "v", "a", "j", "a_AL"))
        return MoveSamples(t, v["x"], v["v"], v["a"], v["j"], v["a_AL"], motion_time,
                           self.N_F(), t_start)

    def plant_input(self, samples: PointSamples, h: float) -> PlantInput:
        """Return the generator's input: ``a`` at each point, ``j`` over the step from it."""
        return PlantInput.of_points(samples)

    def close(self) -> None:
        """Free the FMU instance."""
        self.g.close()

    def __enter__(self) -> FMUAxis:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


