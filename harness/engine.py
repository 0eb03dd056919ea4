"""The fast engine: the co-simulation compiled, called once per move.

The reference engine (:func:`harness.cosim.cosimulate`, engine ``"fmu"``)
steps two generator FMUs through fmpy and the plant in Python, one FMI call
and a few microseconds of Python per communication step.  This engine does
the same work with the same code, compiled into the extension module
:mod:`harness._engine` (built from ``harness/_engine.c`` and the FMU's own
generator core ``fmu_src/djl_*.c`` at ``pip install``):

* planning and sampling a move: the FMU's planner (``djl_plan_motion``) and
  evaluator (``djl_eval``) on the FMU's sample grid (start time + n·Te, motion
  starting at the first sample at or after ``t_start``), all samples of a move
  in one call;
* the Z synchronisation: the bisection of
  :func:`harness.planner.sync_z_velocity`, in C, with the same arithmetic;
* the plant: every mode advanced exactly over each step for the input
  a_k + j_k·τ (:func:`harness.plant.step_mode_jerk`, operation for operation),
  the frequencies computed per step by the vectorised mode laws from the
  Hermite mid-step Z position — the same values the reference master computes.

:class:`FastAxis` has the interface of :class:`harness.planner.AxisFMU`, so the
tuning (:mod:`harness.tuning`), the scenarios (:class:`harness.cosim.Session`
with ``engine="fast"``) and the metrics are shared, unchanged, by both engines;
``tests/test_engine.py`` runs every move of the embedded sweeps through both
and requires the same jerk times and metrics to 1e-9 relative.

Examples
--------
>>> from harness.engine import FastAxis
>>> ax = FastAxis()
>>> ax.plan({"profile": 2, "distance": 0.3, "T_F1": 0.05})
0.4...
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from . import _engine
from .fmu import spec
from .planner import MoveSamples
from .plant import Mode, ScheduledMode

__all__ = ["FastAxis", "PlanError", "cosimulate_fast", "map_error_residuals"]

PlanError = _engine.PlanError
"""The generator refused the parameters (a :class:`ValueError`; the FMU's message)."""

_DEFAULTS: dict[str, Any] = {v.name: v.start for v in spec.PARAMETERS}
_CALCULATED = {v.name for v in spec.CALCULATED}


class FastAxis:
    """One generator axis on the compiled engine (interface of :class:`~harness.planner.AxisFMU`).

    Parameters
    ----------
    name : str
        Label (used in error messages).
    """

    fmi_version = 0
    """Not an FMU (kept for the interface)."""

    def __init__(self, name: str = "axis") -> None:
        self.name = name
        self.params: dict[str, Any] = {}
        self.start_time = 0.0
        self._plan: Any = None
        self._values: dict[str, Any] = dict(_DEFAULTS)
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
        try:
            self._plan = _engine.plan(p, float(start_time))
        except PlanError as e:
            raise PlanError(f"{self.name}: {e}") from None
        self.params = p
        self.start_time = float(start_time)
        self._values = {**_DEFAULTS, **p}
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
        if name in self._values:
            return self._values[name]
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

        The bisection of :func:`~harness.planner.sync_z_velocity`, compiled; the
        axis is left planned with the result, as the FMU's is.
        """
        key = (tuple(sorted((k, tuple(v) if isinstance(v, (list, tuple)) else v)
                            for k, v in params.items())),
               float(target_time), float(v_cap), float(start_time))
        got = self._sync_cache.get(key)
        if got is None:  # the same synchronisation recurs (tuning, then the run): memoised
            try:
                got = _engine.sync_velocity(dict(params), float(target_time), float(v_cap),
                                            float(start_time))
            except PlanError as e:
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
        out = np.empty((_engine.N_SAMPLE_VARS, count))
        self.planned.sample_into(out, int(n0), int(step), int(count))
        return out

    def sample(self, params: Mapping[str, Any], t_stop: float | None = None,
               start_time: float = 0.0) -> MoveSamples:
        """Plan and sample a move at every generator sample (see :meth:`AxisFMU.sample`)."""
        motion_time = self.plan(params, start_time)
        pl = self._plan
        Te = pl.Te
        if t_stop is None:
            t_stop = max(self.motion_start(), start_time) + motion_time
        n = int(round((t_stop - start_time) / Te))
        out = self.samples(0, 1, n + 1)
        t = start_time + Te * np.arange(n + 1)
        return MoveSamples(t, out[0], out[1], out[2], out[3], out[6], motion_time, pl.N_F,
                           float(self._values["t_start"]))

    def close(self) -> None:
        """Nothing to free (kept for the interface)."""

    def __enter__(self) -> FastAxis:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _grid(axis: FastAxis, h: float) -> int:
    """Return the samples per communication step (``h`` must be a whole multiple of Te)."""
    Te = axis.planned.Te
    r = h / Te
    m = round(r)
    if abs(r - m) > 1e-9 * max(1.0, r) or m < 1:
        raise ValueError(f"communication step {h:g} s is not a whole multiple of the "
                         f"{axis.name}'s Te = {Te:g} s")
    return int(m)


def _step_plant(a: np.ndarray, j: np.ndarray, h: float, f: np.ndarray,
                modes: Sequence[ScheduledMode], state0: np.ndarray | None = None
                ) -> tuple[np.ndarray, np.ndarray]:
    """Step the modes (compiled); return Σε at each point and the states (n+1, 2·modes)."""
    n = a.size - 1
    nm = len(modes)
    zeta = np.array([m.zeta for m in modes], dtype=float)
    gain = np.array([m.gain for m in modes], dtype=float)
    state = np.zeros(2 * nm) if state0 is None else np.array(state0, dtype=float)
    eps = np.empty(n + 1)
    states = np.empty((n + 1, 2 * nm))
    _engine.step_modes(np.ascontiguousarray(a), np.ascontiguousarray(j), float(h),
                       np.ascontiguousarray(f), zeta, gain, n, state, eps, states)
    return eps, states


def _modes(modes: Sequence[ScheduledMode | Mode]) -> list[ScheduledMode]:
    out = []
    for m in modes:
        if isinstance(m, Mode):
            fc = m.f
            m = ScheduledMode(lambda z, fc=fc: fc, m.zeta, m.gain,
                              f_of_z_array=lambda z, fc=fc: np.full(np.shape(z), fc))
        out.append(m)
    return out


def cosimulate_fast(
    axis: FastAxis,
    z_axis: FastAxis,
    params: Mapping[str, Any],
    z_params: Mapping[str, Any],
    modes: Sequence[ScheduledMode | Mode],
    t_stop: float,
    step: float | None = None,
    *,
    profile: str = "",
):
    """Run the co-simulation of :func:`harness.cosim.cosimulate`, compiled (same result).

    Parameters and result as :func:`harness.cosim.cosimulate`, with
    :class:`FastAxis` instances in place of the FMUs.
    """
    from .cosim import CoSimResult, plan_info

    t0 = time.perf_counter()
    T_x = axis.plan(params)
    T_z = z_axis.plan(z_params)
    Te = axis.planned.Te
    h = Te if step is None else float(step)
    mx, mz = _grid(axis, h), _grid(z_axis, h)
    n = int(round(t_stop / h))
    X = axis.samples(0, mx, n + 1)
    Z = z_axis.samples(0, mz, n + 1)
    x, v, a, j = X[0], X[1], X[2], X[3]
    z, v_z = Z[0], Z[1]
    zm = 0.5 * (z[:-1] + z[1:]) + (0.125 * h) * (v_z[:-1] - v_z[1:])
    sm = _modes(modes)
    f_mid = np.vstack([m.f_array(zm) for m in sm]) if n else np.zeros((len(sm), 0))
    eps, states = _step_plant(a, j, h, f_mid, sm)
    t_start = float(axis.get("t_start"))
    t_end = t_start + T_x
    z_t_end = float(z_axis.get("t_start")) + T_z
    k_end = min(n, int(math.ceil(t_end / h - 1e-9)))
    nm = len(sm)
    f = np.vstack([m.f_array(z) for m in sm])
    state_end = [(float(states[k_end, 2 * i]), float(states[k_end, 2 * i + 1]))
                 for i in range(nm)]
    z_end = float(z[k_end])
    z_last = float(z[-1])
    return CoSimResult(
        profile=profile, t=h * np.arange(n + 1), x=x, v=v, a=a, j=j, z=z, v_z=v_z, eps=eps,
        eps_modes=states[:, 0::2].T.copy(), f=f, t_start=t_start, t_end=t_end, z_t_end=z_t_end,
        x0=float(params.get("x0", axis.get("x0"))),
        target=float(params.get("x0", axis.get("x0")))
        + float(params.get("distance", axis.get("distance"))),
        state_end=state_end, modes_end=[_frozen(m, z_end) for m in sm], N_F=axis.N_F(), Te=Te,
        step=h, z_v_max=float(z_params.get("v_max", math.nan)), fmi_version=0,
        wall_time=time.perf_counter() - t0, final_state=[float(s) for s in states[-1]],
        final_modes=[_frozen(m, z_last) for m in sm], plan_info=plan_info(axis, z_axis, T_x, T_z),
        engine="fast",
    )


def _frozen(m: ScheduledMode, z: float) -> Mode:
    return Mode(float(m.f_of_z(z)), m.zeta, m.gain)


def map_error_residuals(axis: FastAxis, z_axis: FastAxis, params: Mapping[str, Any],
                        z_params: Mapping[str, Any], modes: Sequence[ScheduledMode | Mode],
                        factors: Sequence[float], step: float | None = None) -> np.ndarray:
    """Residual (free-oscillation amplitude at the end of the motion) under map errors.

    The move is planned and sampled once; the plant is stepped, up to the end
    of the excited axis' motion, once per factor with every mode's frequency
    multiplied by it (the whole f(z) map scaled by 1 + e).  Equal to running
    :func:`cosimulate_fast` on the scaled map and taking
    :attr:`~harness.cosim.CoSimResult.free_amplitude`.

    Returns
    -------
    ndarray
        One residual (m) per factor.
    """
    from .plant import free_amplitude

    T_x = axis.plan(params)
    z_axis.plan(z_params)
    Te = axis.planned.Te
    h = Te if step is None else float(step)
    mx, mz = _grid(axis, h), _grid(z_axis, h)
    t_end = float(axis.get("t_start")) + T_x
    k_end = int(math.ceil(t_end / h - 1e-9))
    X = axis.samples(0, mx, k_end + 1)
    Z = z_axis.samples(0, mz, k_end + 1)
    z, v_z = Z[0], Z[1]
    zm = 0.5 * (z[:-1] + z[1:]) + (0.125 * h) * (v_z[:-1] - v_z[1:])
    sm = _modes(modes)
    f_mid = np.vstack([m.f_array(zm) for m in sm]) if k_end else np.zeros((len(sm), 0))
    f_end = [float(m.f_of_z(float(z[k_end]))) for m in sm]
    out = np.empty(len(factors))
    for i, c in enumerate(factors):
        _, states = _step_plant(X[2], X[3], h, f_mid * c, sm)
        out[i] = sum(free_amplitude(float(states[-1, 2 * q]), float(states[-1, 2 * q + 1]),
                                    Mode(f_end[q] * c, m.zeta, m.gain))
                     for q, m in enumerate(sm))
    return out
