"""The co-simulation master: two generator axes (excited axis, Z axis) and the flexible axis.

One master serves every run of the harness (:func:`cosimulate`): the
profiles of a scenario on either engine, the online ``f_mode`` run of the
commanded FMU, and the peers' precomputed references.  At every
communication point t_k = k·h it takes

1. from the Z axis its position and velocity (z, v_z);
2. from the excited axis (X or Y) its acceleration a_k and its jerk j_k over
   the interval that starts there -- setting its inputs first when a hook
   asks for it (``inputs``: ``f_mode`` from z, the paper's rule applied online);
3. and advances the plant (:mod:`harness.plant`) over [t_k, t_k+1] with the
   input a_k + j_k·(t - t_k) (exact when h = Te for every profile, AL's
   acceleration steps included: a sample interval has one constant jerk; for
   h = m·Te, m > 1, the jerk of the first sample is held over the step, an
   approximation), each mode's frequency frozen at f(z(t_k + h/2)), z at
   mid-step from the cubic Hermite interpolant of (z, v_z)
   (:func:`harness.plant.hermite_mid`, exact when h = Te).  A reference with
   breakpoints between the points (an input shaper's delayed copies) is fed
   piece by piece (:class:`~harness.simulation.axis.PlantInput`).

The Z move does not depend on the excited axis, nor the excited axis on the
plant, so the master reads each axis over the whole run
(:meth:`~harness.simulation.axis.Axis.points`: the FMU stepped point by point
through fmpy, or the compiled engine in one call), then steps the plant in C
(``harness._engine.step_modes``: :func:`harness.plant.step_mode_jerk`
operation for operation).  Recorders (``record``: extra outputs such as
``stage`` or ``done``) and the inputs set are kept on the result.

:func:`map_error_residuals` re-runs only the plant of a planned move with
every frequency scaled (a map error), the reference computed once.

Examples
--------
>>> from harness.simulation.session import Session
>>> from harness.scenario import load_scenario
>>> with Session(engine="fast") as s:                               # doctest: +SKIP
...     run = s.run(load_scenario("X"), "JL", (0.152,) * 4)
>>> run.free_amplitude                                              # doctest: +SKIP
0.00017...
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..compiled import engine as _compiled_engine
from ..plant import Mode, ScheduledMode, free_amplitude, free_response, hermite_mid
from ..uncertainty import Perturbation
from .axis import Axis, PlantInput, samples_per_step
from .plots import plot_runs

__all__ = [
    "CoSimResult",
    "RunUntilDone",
    "cosimulate",
    "map_error_residuals",
    "perturbed",
    "plan_info",
    "step_plant",
]


@dataclass
class CoSimResult:
    """One co-simulation: the reference of both axes and the load's deflection.

    Attributes
    ----------
    profile : str
        ``AL``, ``JL`` or ``DJL`` (or a free label).
    t : ndarray
        Communication points (s).
    x, v, a, j : ndarray
        Reference of the excited axis (m, m/s, m/s², m/s³).
    z, v_z : ndarray
        Z position (m) and velocity (m/s).
    eps : ndarray
        Total deflection Σε (m); the load is at x + eps.
    eps_modes : ndarray
        Deflection of each mode, shape (n_modes, len(t)).
    f : ndarray
        Frequency of each mode at each communication point (Hz), shape
        (n_modes, len(t)).
    t_start, t_end : float
        Start and end of the excited axis' motion (s).
    z_t_end : float
        End of the Z motion (s).
    x0, target : float
        Start and final position of the excited axis (m).
    state_end : list of tuple
        (ε, ε̇) of each mode at the first communication point at or after
        ``t_end``.
    modes_end : list of Mode
        The modes frozen at that point.
    N_F : tuple of int
        Jerk times applied by the excited axis' FMU (samples).
    Te, step : float
        Generator sampling period and communication step (s).
    z_v_max : float
        Velocity limit of the Z move (m/s).
    z_synced : bool
        The Z move ends with the excited axis.
    fmi_version : int
        FMI version of the FMUs (0: the compiled engine).
    wall_time : float
        Wall-clock time of the run (s).
    final_state : list of float
        Plant state at the last point (for extending the record analytically).
    final_modes : list of Mode
        The modes at the last point.
    plan_info : dict
        What the generators planned, as the FMU reports it (identifies the move
        exactly): ``motion_time``, ``N_F``, ``v_reached``, ``a_reached``,
        ``d_reached``, ``distance``, ``x0`` of the excited axis; ``z0``,
        ``z_distance``, ``z_v_max``, ``z_motion_time`` of the Z axis.
    engine : str
        ``"fmu"`` (generator FMUs through fmpy) or ``"fast"`` (compiled engine).
    signals : dict of ndarray
        What the recorders kept: the extra outputs of the excited axis asked
        for (``record``) at each point, and the inputs set before each step
        (NaN at the last point).
    plant_input : PlantInput, optional
        What the plant was fed over each step (re-used by :func:`perturbed`).
    """

    profile: str
    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray
    z: np.ndarray
    v_z: np.ndarray
    eps: np.ndarray
    eps_modes: np.ndarray
    f: np.ndarray
    t_start: float
    t_end: float
    z_t_end: float
    x0: float
    target: float
    state_end: list[tuple[float, float]]
    modes_end: list[Mode]
    N_F: tuple[int, int, int, int]
    Te: float
    step: float
    z_v_max: float = math.nan
    z_synced: bool = True
    fmi_version: int = 2
    wall_time: float = 0.0
    final_state: list[float] = field(default_factory=list)
    final_modes: list[Mode] = field(default_factory=list)
    plan_info: dict[str, Any] = field(default_factory=dict)
    engine: str = "fmu"
    signals: dict[str, np.ndarray] = field(default_factory=dict)
    plant_input: PlantInput | None = field(default=None, repr=False)

    @property
    def motion_time(self) -> float:
        """Duration of the excited axis' motion (s)."""
        return self.t_end - self.t_start

    @property
    def load(self) -> np.ndarray:
        """Load position q + Σε (m)."""
        return self.x + self.eps

    @property
    def error(self) -> np.ndarray:
        """Load position minus target (m)."""
        return self.x + self.eps - self.target

    @property
    def T_F(self) -> tuple[float, ...]:
        """Jerk times applied (s)."""
        return tuple(n * self.Te for n in self.N_F)

    @property
    def free_amplitudes(self) -> list[float]:
        """Amplitude of each mode's free oscillation when the reference ends (m)."""
        return [free_amplitude(e, de, m) for (e, de), m in zip(self.state_end, self.modes_end,
                                                                 strict=True)]

    @property
    def free_amplitude(self) -> float:
        """Sum of the modes' free-oscillation amplitudes when the reference ends (m)."""
        return float(sum(self.free_amplitudes))

    def extend(self, duration: float) -> tuple[np.ndarray, np.ndarray]:
        """Continue the deflection past the record, analytically.

        Valid once both axes are at rest (the plant is then time-invariant and
        free): ε(t) is the sum of the modes' free responses from the final state.

        Parameters
        ----------
        duration : float
            How long after the last point (s).

        Returns
        -------
        t, eps : ndarray
            Times after the last point (excluded) and the deflection there.
        """
        n = int(math.ceil(duration / self.step))
        tau = self.step * np.arange(1, n + 1)
        eps = np.zeros(n)
        for i, m in enumerate(self.final_modes):
            eps += free_response(self.final_state[2 * i], self.final_state[2 * i + 1], m, tau)
        return self.t[-1] + tau, eps

    def to_table(self, mode: int = 0, length: int | None = None) -> dict[str, np.ndarray]:
        """Return the time series as columns.

        ``t_s``, ``x_m``, ``v_m_s``, ``a_m_s2``, ``j_m_s3``, ``eps_m``, ``z_m``, ``f_Hz``
        (see :data:`harness.tables.SIGNAL_COLUMNS`).

        Parameters
        ----------
        mode : int
            The mode whose frequency is ``f_Hz`` (the tuned one: ``ModeMap.tune``).
        length : int, optional
            Number of points (default: the record's).  A longer table continues the
            record with both axes at rest: the last reference and Z values held, the
            deflection the modes' free response (:meth:`extend`; NaN without a final
            state).

        Returns
        -------
        dict of str to ndarray
        """
        n = self.t.size
        length = n if length is None else int(length)
        if length < n:
            raise ValueError(f"length {length} is shorter than the record ({n} points)")
        cols = {"t_s": self.t, "x_m": self.x, "v_m_s": self.v, "a_m_s2": self.a,
                "j_m_s3": self.j, "eps_m": self.eps, "z_m": self.z, "f_Hz": self.f[mode]}
        if length == n:
            return {k: np.asarray(v, dtype=float).copy() for k, v in cols.items()}
        t_more, eps_more = self.extend((length - n) * self.step)
        t_more, eps_more = t_more[:length - n], eps_more[:length - n]
        if not self.final_modes:  # no final state kept: the deflection is unknown there
            eps_more = np.full(length - n, math.nan)
        out = {}
        for k, v in cols.items():
            more = (t_more if k == "t_s" else eps_more if k == "eps_m"
                    else np.full(length - n, float(v[-1])))
            out[k] = np.concatenate([np.asarray(v, dtype=float), more])
        return out

    def plot(self, title: str | None = None) -> Any:
        """Plot the reference, the deflection and the mode frequency; return the figure."""
        return plot_runs({self.profile: self}, title=title or f"{self.profile} co-simulation")


def plan_info(axis: Axis, z_axis: Axis, T_x: float, T_z: float) -> dict[str, Any]:
    """Return what both generators planned (see :attr:`CoSimResult.plan_info`)."""
    return {
        "motion_time": T_x, "N_F": axis.N_F(),
        "v_reached": float(axis.get("v_reached")), "a_reached": float(axis.get("a_reached")),
        "d_reached": float(axis.get("d_reached")), "distance": float(axis.get("distance")),
        "x0": float(axis.get("x0")), "z0": float(z_axis.get("x0")),
        "z_distance": float(z_axis.get("distance")), "z_v_max": float(z_axis.get("v_max")),
        "z_motion_time": T_z,
    }


def scheduled(modes: Sequence[ScheduledMode | Mode]) -> list[ScheduledMode]:
    """Return the plant's modes as :class:`~harness.plant.ScheduledMode` (a Mode: constant)."""
    out = []
    for m in modes:
        if isinstance(m, Mode):
            fc = m.f
            m = ScheduledMode(lambda z, fc=fc: fc, m.zeta, m.gain,
                              f_of_z_array=lambda z, fc=fc: np.full(np.shape(z), fc))
        if not (0.0 <= m.zeta < 1.0):
            raise ValueError(f"damping ratio must be in [0, 1), got {m.zeta!r}")
        out.append(m)
    if not out:
        raise ValueError("at least one mode is needed")
    return out


def step_plant(inp: PlantInput, h: float, f_mid: np.ndarray, modes: Sequence[ScheduledMode],
               n: int) -> tuple[np.ndarray, np.ndarray]:
    """Step the plant from rest over the first ``n`` communication steps (compiled).

    Parameters
    ----------
    inp : PlantInput
        The reference acceleration over each step.
    h : float
        Communication step (s).
    f_mid : ndarray
        Frequency of each mode during each step (Hz), shape (n_modes, >= n).
    modes : sequence of ScheduledMode
        Damping ratios and gains.
    n : int
        Steps to run.

    Returns
    -------
    eps : ndarray
        Σε at the n + 1 points.
    states : ndarray
        (ε_0, ε̇_0, ε_1, ...) at the n + 1 points, shape (n + 1, 2 n_modes).
    """
    nm = len(modes)
    zeta = np.array([m.zeta for m in modes], dtype=float)
    gain = np.array([m.gain for m in modes], dtype=float)
    state = np.zeros(2 * nm)
    eps = np.empty(n + 1)
    states = np.empty((n + 1, 2 * nm))

    def run(k0: int, k1: int, a: np.ndarray, j: np.ndarray, hh: float,
            e_out: np.ndarray, s_out: np.ndarray) -> None:
        _compiled_engine().step_modes(
            np.ascontiguousarray(a), np.ascontiguousarray(j), float(hh),
            np.ascontiguousarray(f_mid[:, k0:k1]), zeta, gain, k1 - k0, state, e_out, s_out)

    split = sorted(k for k in inp.pieces if k < n)
    if not split:
        run(0, n, inp.a[:n], inp.j[:n], h, eps, states)
        return eps, states
    eps[0] = float(sum(state[0::2]))
    states[0] = state
    k = 0
    for ks in [*split, n]:
        if ks > k:  # the steps before the next split one, in one call
            e = np.empty(ks - k + 1)
            s = np.empty((ks - k + 1, 2 * nm))
            run(k, ks, inp.a[k:ks], inp.j[k:ks], h, e, s)
            eps[k + 1:ks + 1] = e[1:]
            states[k + 1:ks + 1] = s[1:]
        if ks == n:
            break
        e = np.empty(2)
        s = np.empty((2, 2 * nm))
        for hh, u0, jj in inp.pieces[ks]:  # a split step, piece by piece, f of the step
            run(ks, ks + 1, np.array([u0]), np.array([jj]), hh, e, s)
        eps[ks + 1] = e[1]
        states[ks + 1] = s[1]
        k = ks + 1
    return eps, states


@dataclass(frozen=True)
class RunUntilDone:
    """End a run ``t_after`` after the excited axis reports ``done`` (and Z has stopped).

    For the commanded FMU, whose motion time is not known beforehand: the
    motion ends at the first point after its start where the ``done`` output
    is true; the run goes on ``t_after`` past the later of that point and the
    end of the Z move.

    Attributes
    ----------
    t_after : float
        Simulated time after both moves have ended (s).
    t_max : float
        Give up (``RuntimeError``) if the motion has not ended by then (s).
    """

    t_after: float
    t_max: float


def cosimulate(
    axis: Axis,
    z_axis: Axis,
    modes: Sequence[ScheduledMode | Mode],
    t_stop: float | RunUntilDone,
    step: float | None = None,
    *,
    profile: str = "",
    record: tuple[str, ...] = (),
    inputs: Callable[[int, float], Mapping[str, float]] | None = None,
) -> CoSimResult:
    """Co-simulate two planned generator axes and the plant from 0 to ``t_stop``.

    Parameters
    ----------
    axis : Axis
        The excited axis, planned (an FMU, the compiled engine or a reference motion).
    z_axis : Axis
        The Z axis, planned.
    modes : sequence of ScheduledMode or Mode
        The plant's modes, f as a function of z.
    t_stop : float or RunUntilDone
        End time (s): the run covers the points up to the first at or after it;
        or run until the excited axis is done (commanded FMU).
    step : float, optional
        Communication step (s), a whole multiple of both axes' ``Te``; default
        the excited axis' ``Te``.
    profile : str
        Label of the run.
    record : tuple of str
        Further outputs of the excited axis to keep (``result.signals``).
    inputs : callable, optional
        The input hook: ``inputs(k, z_k)`` -> the excited axis' inputs to set
        before the step from point k (e.g. ``{"f_mode": f(z_k)}``), z_k the Z
        position there (FMU axis only).

    Returns
    -------
    CoSimResult

    Raises
    ------
    ValueError
        If ``step`` is not a whole multiple of an axis' ``Te``.
    RuntimeError
        With :class:`RunUntilDone`: the motion did not end by ``t_max``.
    FMUError
        If an FMU call fails (with the FMU's log message).
    """
    t0 = time.perf_counter()
    Te = float(axis.get("Te"))
    h = Te if step is None else float(step)
    samples_per_step(h, Te, "excited axis")
    samples_per_step(h, float(z_axis.get("Te")), "Z axis")
    T_x = float(axis.get("motion_time"))
    T_z = float(z_axis.get("motion_time"))
    t_start = float(axis.get("t_start"))
    t_end = t_start + T_x
    z_t_end = float(z_axis.get("t_start")) + T_z
    names = ("x", "v", "a", "j", *record)
    until = t_stop if isinstance(t_stop, RunUntilDone) else None
    stop = None
    done_at: list[int] = []
    if until is None:
        n = math.ceil(t_stop / h - 1e-9)
    else:
        # the motion must end by t_max; the run goes on t_after past it and past Z's end
        n_max = math.ceil(until.t_max / h)
        n = n_max + math.ceil((until.t_after + max(0.0, z_t_end)) / h) + 1
        k_start = max(0, math.ceil(t_start / h - 1e-9))

        def stop(k: int, values: Mapping[str, np.ndarray]) -> int | None:
            if k > k_start and values["done"][-1]:
                done_at.append(k)
                return math.ceil((max(k * h, z_t_end) + until.t_after) / h - 1e-9)
            return k if k >= n_max else None

        if "done" not in names:
            names = (*names, "done")
    Z = z_axis.points(n, h, ("x", "v"))
    z_pts = Z["x"]
    hook = None if inputs is None else (lambda k: inputs(k, float(z_pts[k])))
    X = axis.points(n, h, names, inputs=hook, stop=stop)
    if until is not None:
        if not done_at:
            raise RuntimeError(f"the online move has not ended by t = {until.t_max:g} s (its "
                               f"done output is still false)")
        n = X.n
        t_end = done_at[0] * h
    z, v_z = Z["x"][: n + 1], Z["v"][: n + 1]
    sm = scheduled(modes)
    zm = hermite_mid(z[:-1], v_z[:-1], z[1:], v_z[1:], h)
    f_mid = np.vstack([m.f_array(zm) for m in sm]) if n else np.zeros((len(sm), 0))
    inp = axis.plant_input(X, h)
    eps, states = step_plant(inp, h, f_mid, sm, n)
    k_end = min(n, math.ceil(t_end / h - 1e-9))
    nm = len(sm)
    z_end, z_last = float(z[k_end]), float(z[-1])
    info = {} if axis.engine == "reference" else plan_info(axis, z_axis, T_x, T_z)
    if until is not None:
        info["motion_time"] = t_end - t_start
    signals = {nm_: X[nm_] for nm_ in record}
    signals.update(X.inputs)
    return CoSimResult(
        profile=profile, t=h * np.arange(n + 1), x=X["x"], v=X["v"], a=X["a"], j=X["j"],
        z=z, v_z=v_z, eps=eps, eps_modes=states[:, 0::2].T.copy(),
        f=np.vstack([m.f_array(z) for m in sm]), t_start=t_start, t_end=t_end,
        z_t_end=z_t_end, x0=float(axis.get("x0")),
        target=float(axis.get("x0")) + float(axis.get("distance")),
        state_end=[(float(states[k_end, 2 * i]), float(states[k_end, 2 * i + 1]))
                   for i in range(nm)],
        modes_end=[m.at(z_end) for m in sm], N_F=axis.N_F(), Te=Te, step=h,
        z_v_max=float(z_axis.get("v_max")),
        fmi_version=axis.fmi_version if axis.engine != "reference" else z_axis.fmi_version,
        wall_time=time.perf_counter() - t0, final_state=[float(s) for s in states[-1]],
        final_modes=[m.at(z_last) for m in sm], plan_info=info,
        engine=axis.engine if axis.engine != "reference" else z_axis.engine, signals=signals,
        plant_input=inp,
    )


def map_error_residuals(axis: Axis, z_axis: Axis, modes: Sequence[ScheduledMode | Mode],
                        factors: Sequence[float] | np.ndarray, step: float | None = None
                        ) -> np.ndarray:
    """Residual (free-oscillation amplitude at the end of the motion) under map errors.

    The planned move is read once, up to the first point at or after the end
    of the excited axis' motion; the plant is stepped there once per factor
    with every mode's frequency multiplied by it (the whole f(z) map scaled by
    1 + e).  Equal to co-simulating on the scaled map and taking
    :attr:`CoSimResult.free_amplitude`.

    Parameters
    ----------
    axis, z_axis : Axis
        The two axes, planned (the move does not depend on the map).
    modes : sequence of ScheduledMode or Mode
        The nominal modes.
    factors : array_like
        Frequency factors 1 + e (> 0).
    step : float, optional
        Communication step (s); default the excited axis' ``Te``.

    Returns
    -------
    ndarray
        One residual (m) per factor.
    """
    Te = float(axis.get("Te"))
    h = Te if step is None else float(step)
    samples_per_step(h, Te, "excited axis")
    samples_per_step(h, float(z_axis.get("Te")), "Z axis")
    t_end = float(axis.get("t_start")) + float(axis.get("motion_time"))
    k_end = int(math.ceil(t_end / h - 1e-9))
    Z = z_axis.points(k_end, h, ("x", "v"))
    z, v_z = Z["x"], Z["v"]
    sm = scheduled(modes)
    zm = hermite_mid(z[:-1], v_z[:-1], z[1:], v_z[1:], h)
    f_mid = np.vstack([m.f_array(zm) for m in sm]) if k_end else np.zeros((len(sm), 0))
    f_end = [float(m.f_of_z(float(z[k_end]))) for m in sm]
    if getattr(axis, "engine", None) == "fast" and k_end:
        # the compiled plan steps the plant itself, every factor in one call (the same
        # arithmetic as step_plant and free_amplitude below, without the samples)
        out = np.empty(len(factors))
        axis.planned.residuals(
            int(round(h / Te)), k_end, h, np.ascontiguousarray(f_mid),
            np.array([m.zeta for m in sm]), np.array([m.gain for m in sm]),
            np.array(f_end), np.ascontiguousarray(factors, dtype=float), out)
        return out
    X = axis.points(k_end, h)
    inp = axis.plant_input(X, h)
    out = np.empty(len(factors))
    for i, c in enumerate(factors):
        _, states = step_plant(inp, h, f_mid * c, sm, k_end)
        out[i] = sum(free_amplitude(float(states[-1, 2 * q]), float(states[-1, 2 * q + 1]),
                                    Mode(f_end[q] * c, m.zeta, m.gain))
                     for q, m in enumerate(sm))
    return out


def perturbed(run: CoSimResult, modes: Sequence[ScheduledMode | Mode],
              points: Sequence[Perturbation], pivot: float, *, full: bool = True
              ) -> list[CoSimResult]:
    """Return the run on perturbed plants: the reference and the Z move kept, the plant re-run.

    The reference was planned on the nominal map and does not change with it;
    for each point the plant is stepped again over the whole record
    (:func:`step_plant`, in C) with the perturbed frequencies and damping
    (:class:`harness.uncertainty.Perturbation`).  A scale-only point gives the
    numbers of :func:`map_error_residuals` for the same error.

    Parameters
    ----------
    run : CoSimResult
        A run of :func:`cosimulate` (it keeps its plant input).
    modes : sequence of ScheduledMode or Mode
        The nominal modes of that run.
    points : sequence of Perturbation
        The perturbations.
    pivot : float
        Z position (m) the slope perturbations turn about.
    full : bool
        Also the deflection of each mode and the frequencies at every point
        (for plots); without, those two keep the nominal run's arrays.

    Returns
    -------
    list of CoSimResult
        One per point: the run with the perturbed plant's deflection, states and
        frequencies.
    """
    if run.plant_input is None:
        raise ValueError("the run keeps no plant input (made by an older master?)")
    sm = scheduled(modes)
    h, n = run.step, run.t.size - 1
    z, v_z = run.z, run.v_z
    zm = hermite_mid(z[:-1], v_z[:-1], z[1:], v_z[1:], h)
    k_end = min(n, math.ceil(run.t_end / h - 1e-9))
    ends = np.array([z[k_end], z[-1]])
    nominal_mid = [m.f_array(zm) for m in sm]
    nominal_end = [m.f_array(ends) for m in sm]
    nominal_all = [m.f_array(z) for m in sm] if full else None
    out = []
    for p in points:
        pm = [ScheduledMode(m.f_of_z, p.zeta(m.zeta), m.gain, m.name, m.f_of_z_array)
              for m in sm]
        f_mid = (np.vstack([p.frequencies(m.f_array, zm, pivot, nominal_mid[i])
                            for i, m in enumerate(sm)]) if n else np.zeros((len(sm), 0)))
        f_ends = [p.frequencies(m.f_array, ends, pivot, nominal_end[i])
                  for i, m in enumerate(sm)]
        eps, states = step_plant(run.plant_input, h, f_mid, pm, n)
        extra: dict[str, Any] = {}
        if nominal_all is not None:
            extra = {"eps_modes": states[:, 0::2].T.copy(),
                     "f": np.vstack([p.frequencies(m.f_array, z, pivot, nominal_all[i])
                                     for i, m in enumerate(sm)])}
        out.append(dataclasses.replace(
            run, eps=eps, **extra,
            state_end=[(float(states[k_end, 2 * i]), float(states[k_end, 2 * i + 1]))
                       for i in range(len(sm))],
            modes_end=[Mode(float(f_ends[i][0]), p.zeta(m.zeta), m.gain)
                       for i, m in enumerate(sm)],
            final_state=[float(s) for s in states[-1]],
            final_modes=[Mode(float(f_ends[i][1]), p.zeta(m.zeta), m.gain)
                         for i, m in enumerate(sm)]))
    return out
