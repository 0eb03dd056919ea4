"""Co-simulation master: two generator FMUs (excited axis, Z axis) and the flexible axis.

The master steps, at every communication point t_k = k·h,

1. the generator FMU of the excited axis (X or Y) and the one of the Z axis
   (a JL move), both by ``fmi2DoStep`` / ``fmi3DoStep`` through fmpy;
2. reads their outputs: the acceleration a of the excited axis, the position
   and velocity (z, v_z) of Z;
3. advances the plant (:class:`harness.plant.ScheduledPlant`) over [t_k, t_k+1]
   with the input a_k + j_k·(t - t_k): the generator's acceleration at t_k and
   its jerk over the interval that starts there (exact when h = Te for every
   profile, AL's acceleration steps included: a sample interval has one
   constant jerk; for h = m·Te, m > 1, the jerk of the first sample is held
   over the step, an approximation), and each mode's frequency is frozen at
   f(z(t_k + h/2)), with z at mid-step from the cubic Hermite interpolant of
   (z, v_z) (exact when h = Te).

No python-control object is built in the loop: a step costs two ``doStep``,
two ``getReal`` and a few microseconds of plant arithmetic.

:func:`run_scenario` is the one-call entry point: it tunes the jerk times from
the mode map (:mod:`harness.tuning`), synchronises the Z move with the excited
axis, co-simulates every profile and computes the metrics
(:mod:`harness.metrics`); see :mod:`harness.results` for the tables and plots.

Examples
--------
>>> from harness.cosim import run_scenario
>>> result = run_scenario("X")                      # doctest: +SKIP
>>> print(result.table())                           # doctest: +SKIP
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .evaluation import ProfileMetrics, profile_metrics, run_case  # noqa: F401 (re-exported)
from .fmu.runner import FMUError
from .optimize import split_profile
from .planner import PROFILE_CODES, AxisFMU, MoveSamples, sync_z_velocity
from .plant import Mode, ScheduledMode, ScheduledPlant, free_amplitude, free_response
from .scenario import Scenario, load_scenario
from .tuning import TuningResult, tune_djl, tune_jl

ENGINES = ("fmu", "fast")
"""Evaluation engines: the generator FMUs through fmpy, or the compiled engine."""

__all__ = [
    "ENGINES",
    "CoSimResult",
    "ProfileMetrics",
    "profile_metrics",
    "run_case",
    "Session",
    "cosimulate",
    "run_scenario",
    "simulate",
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
        FMI version of the FMUs.
    wall_time : float
        Wall-clock time of the stepping loop (s).
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

    def plot(self, title: str | None = None):
        """Plot the reference, the deflection and the mode frequency; return the figure."""
        from .results import plot_runs

        return plot_runs({self.profile: self}, title=title or f"{self.profile} co-simulation")


def cosimulate(
    axis: AxisFMU,
    z_axis: AxisFMU,
    params: Mapping[str, Any],
    z_params: Mapping[str, Any],
    modes: Sequence[ScheduledMode | Mode],
    t_stop: float,
    step: float | None = None,
    *,
    profile: str = "",
) -> CoSimResult:
    """Step both generator FMUs and the plant together from 0 to ``t_stop``.

    Parameters
    ----------
    axis : AxisFMU
        FMU instance of the excited axis (re-planned here with ``params``).
    z_axis : AxisFMU
        FMU instance of the Z axis (re-planned with ``z_params``).
    params, z_params : mapping
        FMU parameters of the two moves.
    modes : sequence of ScheduledMode or Mode
        The plant's modes, f as a function of z.
    t_stop : float
        End time (s).
    step : float, optional
        Communication step (s), a whole multiple of ``Te``; default ``Te``.
    profile : str
        Label of the run.

    Returns
    -------
    CoSimResult

    Raises
    ------
    ValueError
        If ``step`` is not a whole multiple of the FMUs' ``Te``.
    FMUError
        If an FMU call fails (with the FMU's log message).
    """
    T_x = axis.plan(params)
    T_z = z_axis.plan(z_params)
    gx, gz = axis.g, z_axis.g
    Te = float(gx.get("Te"))
    Te_z = float(gz.get("Te"))
    h = Te if step is None else float(step)
    for name, te in (("excited axis", Te), ("Z axis", Te_z)):
        r = h / te
        if abs(r - round(r)) > 1e-9 * max(1.0, r) or round(r) < 1:
            raise ValueError(f"communication step {h:g} s is not a whole multiple of the "
                             f"{name}'s Te = {te:g} s")
    n = int(round(t_stop / h))
    plant = ScheduledPlant(modes)
    pstep = plant.step_jerk
    v3x, v3z = gx.fmi_version == 3, gz.fmi_version == 3
    getx = gx.fmu.getFloat64 if v3x else gx.fmu.getReal
    getz = gz.fmu.getFloat64 if v3z else gz.fmu.getReal
    stepx, stepz = gx.fmu.doStep, gz.fmu.doStep
    vrx = gx.vr(["x", "v", "a", "j"])
    vrz = gz.vr(["x", "v"])
    t_start = float(gx.get("t_start"))
    t_end = t_start + T_x
    z_t_end = float(gz.get("t_start")) + T_z
    k_end = min(n, int(math.ceil(t_end / h - 1e-9)))

    ox = list(getx(vrx))
    oz = list(getz(vrz))
    X = [ox]
    Z = [oz]
    E = [0.0]
    S = [tuple(plant.state)]
    half = 0.125 * h
    from fmpy.fmi1 import FMICallException

    t0 = time.perf_counter()
    try:
        for k in range(n):
            tk = k * h
            stepx(tk, h)
            stepz(tk, h)
            ox1 = getx(vrx)
            oz1 = getz(vrz)
            zm = 0.5 * (oz[0] + oz1[0]) + half * (oz[1] - oz1[1])
            E.append(pstep(h, ox[2], ox[3], zm))
            S.append(tuple(plant.state))
            X.append(ox1)
            Z.append(oz1)
            ox, oz = ox1, oz1
    except FMICallException as e:
        raise FMUError(str(getattr(e, "function", "doStep")), int(e.status),
                       gx.log + gz.log) from None
    wall = time.perf_counter() - t0
    gx.time = gz.time = n * h

    t = h * np.arange(n + 1)
    Xa = np.asarray(X, dtype=float)
    Za = np.asarray(Z, dtype=float)
    Sa = np.asarray(S, dtype=float)
    nm = len(plant.modes)
    eps_modes = Sa[:, 0::2].T.copy()
    f = np.vstack([m.f_array(Za[:, 0]) for m in plant.modes])
    state_end = [(float(Sa[k_end, 2 * i]), float(Sa[k_end, 2 * i + 1])) for i in range(nm)]
    modes_end = [m.at(float(Za[k_end, 0])) for m in plant.modes]
    x0 = float(params.get("x0", gx.get("x0")))
    dist = float(params.get("distance", gx.get("distance")))
    return CoSimResult(
        profile=profile, t=t, x=Xa[:, 0], v=Xa[:, 1], a=Xa[:, 2], j=Xa[:, 3],
        z=Za[:, 0], v_z=Za[:, 1], eps=np.asarray(E), eps_modes=eps_modes, f=f,
        t_start=t_start, t_end=t_end, z_t_end=z_t_end, x0=x0, target=x0 + dist,
        state_end=state_end, modes_end=modes_end, N_F=axis.N_F(), Te=Te, step=h,
        z_v_max=float(z_params.get("v_max", math.nan)), fmi_version=gx.fmi_version,
        wall_time=wall, final_state=list(plant.state),
        final_modes=[m.at(float(Za[-1, 0])) for m in plant.modes],
        plan_info=plan_info(axis, z_axis, T_x, T_z),
    )


def plan_info(axis: Any, z_axis: Any, T_x: float, T_z: float) -> dict[str, Any]:
    """Return what both generators planned (see :attr:`CoSimResult.plan_info`)."""
    return {
        "motion_time": T_x, "N_F": axis.N_F(),
        "v_reached": float(axis.get("v_reached")), "a_reached": float(axis.get("a_reached")),
        "d_reached": float(axis.get("d_reached")), "distance": float(axis.get("distance")),
        "x0": float(axis.get("x0")), "z0": float(z_axis.get("x0")),
        "z_distance": float(z_axis.get("distance")), "z_v_max": float(z_axis.get("v_max")),
        "z_motion_time": T_z,
    }


# ------------------------------------------------------------- scenarios


class Session:
    """The two generator instances a scenario runs on (re-planned, not re-created).

    Parameters
    ----------
    fmu : path-like, optional
        Generator FMU file; default: the package's own FMU for ``fmi_version``
        (engine ``"fmu"`` only).
    fmi_version : {2, 3}
        FMI version of the package's FMU (engine ``"fmu"`` only).
    engine : {"fmu", "fast"}
        ``"fmu"``: the generator FMUs driven through fmpy, one FMI call per
        communication step (the reference: the FMU drives the plant).
        ``"fast"``: the same generator core (``fmu_src/djl_*.c``) and the
        same plant, compiled into the extension module ``harness._engine`` and
        called once per move (:mod:`harness.engine`); equal results, about a
        hundred times faster.
    """

    def __init__(self, fmu: str | Path | None = None, fmi_version: int = 2,
                 engine: str = "fmu") -> None:
        if engine not in ENGINES:
            raise ValueError(f"unknown engine {engine!r}: choose from {', '.join(ENGINES)}")
        if isinstance(fmi_version, bool) or not isinstance(fmi_version, int) \
                or fmi_version not in (2, 3):
            raise ValueError(f"fmi_version must be the integer 2 or 3, got {fmi_version!r}")
        self.fmu, self.fmi_version, self.engine = fmu, fmi_version, engine
        if engine == "fast":
            from .engine import FastAxis

            self.axis: Any = FastAxis(name="excited_axis")
            self.z_axis: Any = FastAxis(name="z_axis")
            # vectorised over map errors (harness.robustness uses it when present)
            self.map_error_residuals = self._fast_map_error_residuals
            return
        self.axis = AxisFMU(fmu, fmi_version=fmi_version, name="excited_axis")
        try:
            self.z_axis = AxisFMU(fmu, fmi_version=fmi_version, name="z_axis")
        except Exception:
            self.axis.close()
            raise

    def close(self) -> None:
        """Free both instances."""
        self.axis.close()
        self.z_axis.close()
        fast = getattr(self, "_fast", None)
        if fast is not None:
            fast.close()

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -------------------------------------------------------- parameters

    @staticmethod
    def move_params(sc: Scenario, profile: str,
                    T_F: Sequence[float] | None = None) -> dict[str, Any]:
        """FMU parameters of the excited axis for ``profile`` and jerk times ``T_F``."""
        m, s = sc.move, sc.simulation
        p: dict[str, Any] = {
            "profile": PROFILE_CODES[split_profile(profile)[0]], "Te": s.Te,
            "t_start": m.t_start, "x0": m.x0,
            "distance": m.distance, "v_max": m.v_max, "a_max": m.a_max, "d_max": m.d_max,
            "short_stage": s.short_stage,
        }
        if T_F is not None:
            p.update({f"T_F{i + 1}": float(T_F[i]) for i in range(4)})
        return p

    @staticmethod
    def z_move_params(sc: Scenario, v_max: float) -> dict[str, Any]:
        """FMU parameters of the Z axis (a JL move) with velocity limit ``v_max``."""
        z, s = sc.z, sc.simulation
        Tf = z.T_F if z.T_F > 0 else 0.0
        return {"profile": 2 if Tf > 0 else 1, "Te": s.Te, "t_start": sc.move.t_start,
                "x0": z.z0, "distance": z.distance, "v_max": v_max, "a_max": z.a_max,
                "d_max": z.a_max, "T_F1": Tf, "T_F2": Tf, "T_F3": Tf, "T_F4": Tf,
                "short_stage": s.short_stage}

    def z_velocity(self, sc: Scenario, motion_time: float) -> tuple[float, bool]:
        """Velocity limit of the Z move: synchronised with a motion of ``motion_time``."""
        if not sc.z.moves or not sc.z.sync:
            return sc.z.v_max, not sc.z.moves
        base = self.z_move_params(sc, sc.z.v_max)
        v, _, ok = sync_z_velocity(self.z_axis, base, motion_time, sc.z.v_max)
        return v, ok

    def plan(self, sc: Scenario, profile: str
             ) -> Callable[[tuple[float, float, float, float]],
                           tuple[MoveSamples, Callable[[float], float]]]:
        """Return the planning function the tuning iterates on (see :mod:`harness.tuning`)."""

        def plan_fn(T_F: tuple[float, float, float, float]):
            mv = self.axis.sample(self.move_params(sc, profile, T_F))
            v, _ = self.z_velocity(sc, mv.motion_time)
            zs = self.z_axis.sample(self.z_move_params(sc, v), t_stop=mv.t_end)
            return mv, zs.position_at

        return plan_fn

    # ------------------------------------------------------------- runs

    def tune(self, sc: Scenario, profile: str) -> TuningResult | None:
        """Jerk times of ``profile`` from the mode map (None for AL or imposed ones).

        The method is the scenario's (``[compare]``): JL ``end`` (period at the
        end of the motion) or ``optimal``; DJL ``paper`` (the period at the
        start of each stage, rule ``djl_rule``), ``optimal`` or ``robust``
        (:mod:`harness.optimize`, on the fast engine whatever this session's).
        """
        profile, method = split_profile(profile)
        if method is not None:  # a variant: "DJL-robust" is DJL tuned with "robust"
            field = "jl_tuning" if profile == "JL" else "djl_tuning"
            sc = dataclasses.replace(sc, compare=dataclasses.replace(
                sc.compare, **{field: method}, JL_T_F=None, DJL_T_F=None))
        mm, Te, cmp = sc.modemap, sc.simulation.Te, sc.compare
        if profile == "JL" and cmp.JL_T_F is None:
            jl = tune_jl(self.plan(sc, "JL"), mm.period, Te, mm.period(sc.z.z0 + sc.z.distance))
            if cmp.jl_tuning == "end":
                return jl
            return self._search(sc, "JL", cmp.jl_tuning, None, jl)
        if profile == "DJL" and cmp.DJL_T_F is None:
            paper = tune_djl(self.plan(sc, "DJL"), mm.period, Te, mm.period(sc.z.z0),
                             rule=cmp.djl_rule)
            if cmp.djl_tuning == "paper":
                return paper
            jl = tune_jl(self.plan(sc, "JL"), mm.period, Te, mm.period(sc.z.z0 + sc.z.distance))
            return self._search(sc, "DJL", cmp.djl_tuning, paper, jl)
        return None

    def _search(self, sc: Scenario, profile: str, method: str, paper: TuningResult | None,
                jl: TuningResult) -> TuningResult:
        from .optimize import tune_optimal

        if self.engine == "fast":
            fast = self
        else:
            fast = getattr(self, "_fast", None)
            if fast is None:
                fast = self._fast = Session(engine="fast")
        return tune_optimal(sc, fast, profile, method, paper, jl, sc.compare.tuning_options())

    def _fast_map_error_residuals(self, sc: Scenario, profile: str,
                                  T_F: Sequence[float] | None,
                                  factors: Sequence[float]) -> np.ndarray:
        """Residual of one profile with every mode frequency scaled by each factor (fast).

        The move and the Z synchronisation are planned once on the nominal
        scenario (the jerk times do not change with the map), the plant is
        stepped once per factor (:func:`harness.engine.map_error_residuals`).
        """
        from .engine import map_error_residuals

        params = self.move_params(sc, profile, T_F)
        T_x = self.axis.plan(params)
        v_z, _ = self.z_velocity(sc, T_x)
        return map_error_residuals(self.axis, self.z_axis, params, self.z_move_params(sc, v_z),
                                   sc.modemap.scheduled(), factors, sc.simulation.step)

    def run(self, sc: Scenario, profile: str, T_F: Sequence[float] | None = None,
            t_stop: float | None = None) -> CoSimResult:
        """Co-simulate one profile of a scenario with the given jerk times."""
        params = self.move_params(sc, profile, T_F)
        T_x = self.axis.plan(params)
        v_z, synced = self.z_velocity(sc, T_x)
        zp = self.z_move_params(sc, v_z)
        T_z = self.z_axis.plan(zp)
        if t_stop is None:
            t_stop = sc.move.t_start + max(T_x, T_z) + sc.simulation.t_after
        h = sc.simulation.step
        t_stop = h * math.ceil(t_stop / h - 1e-9)
        if self.engine == "fast":
            from .engine import cosimulate_fast

            run = cosimulate_fast(self.axis, self.z_axis, params, zp, sc.modemap.scheduled(),
                                  t_stop, h, profile=profile)
        else:
            run = cosimulate(self.axis, self.z_axis, params, zp, sc.modemap.scheduled(), t_stop,
                             h, profile=profile)
        run.z_synced = synced
        return run


def run_scenario(scenario: Scenario | str | Path, *, fmu: str | Path | None = None,
                 fmi_version: int | None = None, progress: bool = False,
                 session: Session | None = None, engine: str | None = None,
                 robustness: bool | str | None = "auto", workers: int | None = 1,
                 scheduler: str | None = None):
    """Run a scenario: one call from a TOML file (or embedded name) to the results.

    Parameters
    ----------
    scenario : Scenario, str or Path
        A checked :class:`~harness.scenario.Scenario`, a TOML file, or the name of
        an embedded scenario (``X``, ``Y``, ``sweep-X``, ``sweep-Y``).
    fmu : path-like, optional
        Generator FMU file, overriding the scenario's.
    fmi_version : {2, 3}, optional
        FMI version, overriding the scenario's.
    progress : bool
        Show a tqdm progress bar over the cases of a sweep (only on a TTY).
    session : Session, optional
        Generator instances to reuse (must match the scenario's FMU and the engine).
    engine : {"fmu", "fast"}, optional
        Evaluation engine (see :class:`Session`); default: ``"fmu"`` for a single
        move (the FMU drives the plant), ``"fast"`` for a sweep.

    Returns
    -------
    harness.results.ScenarioResult or harness.results.SweepResult
        ``.table()`` prints like Table 1 (Table 2 for a sweep), ``.to_csv(path)``,
        ``.plot()`` returns the figure.
    """
    from .results import SweepResult

    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    if fmu is not None or fmi_version is not None:
        sc = sc.with_fmu(Path(fmu) if fmu is not None else None, fmi_version)
    own = session is None
    if engine is None:
        engine = session.engine if session is not None else ("fast" if sc.is_sweep else "fmu")
    if robustness == "auto":
        robustness = "worst" if sc.is_sweep else "curves"
    if sc.is_sweep and own and (workers != 1 or scheduler is not None):
        return _run_sweep_parallel(sc, engine, robustness, workers, scheduler, progress)
    if session is None:
        session = Session(sc.simulation.fmu, sc.simulation.fmi_version, engine=engine)
    # the many map-error runs go to the fast engine (same results), unless the scenario names
    # its own FMU file: its generator may differ from the package's, so it runs them itself
    own_fmu = session.fmu is not None or sc.simulation.fmu is not None
    rsession = (session if session.engine == "fast" or not robustness or own_fmu
                else Session(engine="fast"))
    try:
        if not sc.is_sweep:
            return run_case(sc, session, robustness=robustness, robustness_session=rsession)
        cases = sc.cases()
        results = []
        for case in _progress(cases, progress, desc=sc.name):
            results.append(run_case(case, session, keep_runs=False, robustness=robustness,
                                    robustness_session=rsession))
        return SweepResult(sc, results)
    finally:
        if own:
            session.close()
        if rsession is not session:
            rsession.close()


def _run_sweep_parallel(sc: Scenario, engine: str, robustness: Any, workers: int | None,
                        scheduler: str | None, progress: bool):
    """Run a sweep's cases on a process pool or a Dask cluster (same results as serially)."""
    from concurrent.futures import as_completed

    from .executors import executor_workers, make_executor
    from .results import SweepResult
    from .workspace import run_sweep_batch

    n = len(sc.cases())
    with make_executor(workers, scheduler) as ex:
        size = max(1, math.ceil(n / (4 * max(1, executor_workers(ex)))))
        batches = [list(range(i, min(n, i + size))) for i in range(0, n, size)]
        futures = {ex.submit(run_sweep_batch, sc, engine, robustness, b): b for b in batches}
        results: list[Any] = [None] * n
        done = _progress(as_completed(futures), progress, desc=sc.name, total=len(batches))
        for fut in done:
            for i, r in zip(futures[fut], fut.result(), strict=True):
                results[i] = r
    return SweepResult(sc, results)


def _progress(items: Any, enabled: bool, desc: str, total: int | None = None):
    import sys

    if not enabled or not sys.stderr.isatty():
        return items
    from tqdm import tqdm

    return tqdm(items, desc=desc, unit="case" if total is None else "batch", leave=False,
                total=total)


simulate = run_scenario
"""Alias of :func:`run_scenario`."""
