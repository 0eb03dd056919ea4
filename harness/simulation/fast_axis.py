"""The fast engine's axis: the FMU's generator core compiled, a whole move per call.

The reference axis (:class:`harness.simulation.fmu_axis.FMUAxis`, engine
``"fmu"``) steps the generator FMU through fmpy, one FMI call per
communication point.  :class:`FastAxis` gives the same values from the same
code, compiled into the extension module :mod:`harness._engine` (built from
``harness/_engine.c`` and the FMU's own generator core ``fmu_src/djl_*.c`` at
``pip install``):

* planning and sampling a move: the FMU's planner (``djl_plan_motion``) and
  evaluator (``djl_eval``) on the FMU's sample grid (start time + n·Te, motion
  starting at the first sample at or after ``t_start``, the core's rule), all
  samples of a move in one call;
* the Z synchronisation: the bisection of
  :meth:`harness.simulation.fmu_axis.FMUAxis.sync_velocity`, in C, with the
  same arithmetic.

Both implement :class:`harness.simulation.axis.Axis`, so the master
(:mod:`harness.simulation.master`), the tuning and the metrics are shared,
unchanged, by both engines; ``tests/test_engine.py`` runs every move of the
embedded sweeps through both and requires the same jerk times and metrics.

Examples
--------
>>> from harness.simulation.fast_axis import FastAxis
>>> ax = FastAxis()
>>> ax.plan({"profile": 2, "distance": 0.3, "T_F1": 0.05})
0.4...
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from ..compiled import engine as _compiled_engine
from ..errors import HarnessError
from ..fmu import spec
from .axis import InputsHook, MoveSamples, PlantInput, PointSamples, StopHook, samples_per_step

__all__ = ["FastAxis", "PlanError"]


class PlanError(HarnessError, ValueError):
    """The generator refused the parameters (the FMU's message, naming the parameter)."""

_DEFAULTS: dict[str, Any] = {v.name: v.start for v in spec.PARAMETERS}
_CALCULATED = {v.name for v in spec.CALCULATED}
_SAMPLE_ROWS = {"x": 0, "v": 1, "a": 2, "j": 3, "x_AL": 4, "v_AL": 5, "a_AL": 6}
"""Rows of :meth:`FastAxis.samples`."""


class FastAxis:
    """One generator axis on the compiled engine (an :class:`~harness.simulation.axis.Axis`).

    Parameters
    ----------
    name : str
        Label (used in error messages).
    """

    fmi_version = 0
    """Not an FMU (kept for the interface)."""

    engine = "fast"
    """The compiled engine."""

    def __init__(self, name: str = "axis") -> None:
        self.name = name
        self.params: dict[str, Any] = {}
        self.start_time = 0.0
        self._plan: Any = None
        self._sync_cache: dict[Any, tuple[float, float, bool]] = {}

    # ------------------------------------------------------------ planning

    def plan(self, params: Mapping[str, Any], start_time: float = 0.0) -> float:
        """Plan a move (parameters not given take the FMU's start values); return its duration.

        Raises
        ------
        PlanError
            When the generator refuses the parameters (the FMU's message).
        """
        p = dict(params)
        eng = _compiled_engine()
        try:
            self._plan = eng.plan(p, float(start_time))
        except eng.PlanError as e:
            raise PlanError(f"{self.name}: {e}") from None
        self.params = p
        self.start_time = float(start_time)
        return self._plan.motion_time

    @property
    def planned(self) -> Any:
        """The :class:`harness._engine.Plan` of the last :meth:`plan`."""
        if self._plan is None:
            raise RuntimeError(f"{self.name}: no move planned yet")
        return self._plan

    def get(self, name: str) -> Any:
        """Value of a parameter or calculated parameter, named as in the FMU."""
        pl = self.planned
        if name in _CALCULATED:
            if name.startswith("N_F"):
                return pl.N_F[int(name[3]) - 1]
            return getattr(pl, name)
        if name in self.params:
            return self.params[name]
        if name in _DEFAULTS:
            return _DEFAULTS[name]
        raise KeyError(f"{name!r} is not a parameter or calculated parameter of the generator")

    def N_F(self) -> tuple[int, int, int, int]:
        """Jerk times applied (samples)."""
        return self.planned.N_F

    def motion_start(self) -> float:
        """Time of the generator sample at which the motion starts (s)."""
        pl = self.planned
        return self.start_time + pl.offset * pl.Te

    def sync_velocity(self, params: Mapping[str, Any], target_time: float, v_cap: float,
                      start_time: float = 0.0) -> tuple[float, float, bool]:
        """Velocity limit making the move last ``target_time``.

        The bisection of :meth:`~harness.simulation.fmu_axis.FMUAxis.sync_velocity`,
        compiled; the axis is left planned with the result, as the FMU's is.
        """
        key = (tuple(sorted((k, tuple(v) if isinstance(v, (list, tuple)) else v)
                            for k, v in params.items())),
               float(target_time), float(v_cap), float(start_time))
        got = self._sync_cache.get(key)
        if got is None:  # the same synchronisation recurs (tuning, then the run): memoised
            eng = _compiled_engine()
            try:
                got = eng.sync_velocity(dict(params), float(target_time), float(v_cap),
                                        float(start_time))
            except eng.PlanError as e:
                raise PlanError(f"{self.name}: {e}") from None
            if len(self._sync_cache) >= 512:
                self._sync_cache.clear()
            self._sync_cache[key] = got
        v, T, ok = got
        self.plan({**params, "v_max": v}, start_time)
        return v, T, ok

    # ------------------------------------------------------------ sampling

    def samples(self, n0: int, step: int, count: int) -> np.ndarray:
        """Return the outputs at the FMU samples n0 + k·step, k < count.

        Rows: x, v, a, j, x_AL, v_AL, a_AL (shape (7, count)).
        """
        out = np.empty((_compiled_engine().N_SAMPLE_VARS, count))
        self.planned.sample_into(out, int(n0), int(step), int(count))
        return out

    def sample(self, params: Mapping[str, Any], t_stop: float | None = None,
               start_time: float = 0.0) -> MoveSamples:
        """Plan and sample a move at every generator sample (see :meth:`FMUAxis.sample`)."""
        motion_time = self.plan(params, start_time)
        pl = self._plan
        Te = pl.Te
        if t_stop is None:
            t_stop = max(self.motion_start(), start_time) + motion_time
        n = int(round((t_stop - start_time) / Te))
        out = self.samples(0, 1, n + 1)
        t = start_time + Te * np.arange(n + 1)
        return MoveSamples(t, out[0], out[1], out[2], out[3], out[6], motion_time, pl.N_F,
                           float(self.get("t_start")))

    def points(self, n: int, h: float, names: tuple[str, ...] = ("x", "v", "a", "j"), *,
               inputs: InputsHook | None = None, stop: StopHook | None = None
               ) -> PointSamples:
        """Return the outputs of the planned move at the points 0, h, ..., n·h (one call).

        Parameters
        ----------
        n : int
            Communication steps.
        h : float
            Communication step (s), a whole multiple of ``Te``.
        names : tuple of str
            Outputs among x, v, a, j, x_AL, v_AL, a_AL.
        inputs, stop
            Not available: the compiled engine has no inputs (use the FMU axis).

        Raises
        ------
        ValueError
            ``inputs`` or ``stop`` given, an unknown output, or ``h`` not a
            whole multiple of ``Te``.
        """
        if inputs is not None or stop is not None:
            raise ValueError(f"{self.name}: the fast engine takes no inputs; the commanded "
                             "generator runs on the FMU engine")
        unknown = [nm for nm in names if nm not in _SAMPLE_ROWS]
        if unknown:
            raise ValueError(f"{self.name}: the fast engine has no output {unknown[0]!r} "
                             f"(it has {', '.join(_SAMPLE_ROWS)})")
        m = samples_per_step(h, self.planned.Te, self.name)
        out = self.samples(0, m, n + 1)
        return PointSamples(h * np.arange(n + 1), {nm: out[_SAMPLE_ROWS[nm]] for nm in names})

    def plant_input(self, samples: PointSamples, h: float) -> PlantInput:
        """Return the generator's input: ``a`` at each point, ``j`` over the step from it."""
        return PlantInput.of_points(samples)

    def close(self) -> None:
        """Nothing to free (kept for the interface)."""

    def __enter__(self) -> FastAxis:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
