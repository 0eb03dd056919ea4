"""A scenario's two generator axes, re-planned for every run: :class:`Session`.

A :class:`Session` holds the excited axis and the Z axis of one engine
(:data:`ENGINES`) and turns a scenario's move into their parameters
(:meth:`Session.move_params`, :meth:`Session.z_move_params`), synchronises
the Z move with the excited one (:meth:`Session.z_velocity`) and runs a
profile through the master (:meth:`Session.run`,
:meth:`Session.map_error_residuals`).  How the jerk times are found is the
tuning's business (:func:`harness.tuning.tune.tune_profile`).

Examples
--------
>>> from harness.scenario import load_scenario
>>> from harness.simulation.session import Session
>>> sc = load_scenario("X")
>>> with Session(engine="fast") as s:                               # doctest: +SKIP
...     run = s.run(sc, "JL", (0.152,) * 4)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ..fmu import spec
from ..scenario import Scenario
from ..tuning_options import split_profile
from ..uncertainty import Perturbation, check_map_errors
from .axis import Axis, MoveSamples
from .fast_axis import FastAxis
from .fmu_axis import FMUAxis
from .jerk_table import JerkTable
from .master import CoSimResult, cosimulate, map_error_residuals, perturbed
from .shaped_axis import ShaperSpec

__all__ = ["ENGINES", "Session", "make_axis"]

ENGINES = ("fmu", "fast")
"""Evaluation engines: the generator FMUs through fmpy, or the compiled engine."""


AXES: dict[str, Callable[[str | Path | None, int, str], Axis]] = {
    "fmu": lambda fmu, fmi_version, name: FMUAxis(fmu, fmi_version=fmi_version, name=name),
    "fast": lambda fmu, fmi_version, name: FastAxis(name=name),
}
"""How each engine makes an axis (the FMU file and FMI version matter to ``fmu`` only)."""


def make_axis(engine: str, fmu: str | Path | None = None, fmi_version: int = 2,
              name: str = "axis") -> Axis:
    """Return one generator axis on ``engine`` (:data:`ENGINES`).

    Raises
    ------
    ValueError
        An unknown engine.
    """
    try:
        make = AXES[engine]
    except KeyError:
        raise ValueError(f"unknown engine {engine!r}: choose from {', '.join(ENGINES)}") from None
    return make(fmu, fmi_version, name)


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
        ``"fast"``: the same generator core (``fmu_src/djl_*.c``) compiled into
        the extension module ``harness._engine`` and called once per move
        (:mod:`harness.simulation.fast_axis`); equal results, about a hundred
        times faster.
    """

    def __init__(self, fmu: str | Path | None = None, fmi_version: int = 2,
                 engine: str = "fmu") -> None:
        if engine not in ENGINES:
            raise ValueError(f"unknown engine {engine!r}: choose from {', '.join(ENGINES)}")
        if isinstance(fmi_version, bool) or not isinstance(fmi_version, int) \
                or fmi_version not in (2, 3):
            raise ValueError(f"fmi_version must be the integer 2 or 3, got {fmi_version!r}")
        self.fmu, self.fmi_version, self.engine = fmu, fmi_version, engine
        self._fast: Session | None = None
        self.axis: Axis = make_axis(engine, fmu, fmi_version, "excited_axis")
        try:
            self.z_axis: Axis = make_axis(engine, fmu, fmi_version, "z_axis")
        except Exception:
            self.axis.close()
            raise

    def close(self) -> None:
        """Free both instances (and the fast session made for the searches, if any)."""
        self.axis.close()
        self.z_axis.close()
        if self._fast is not None:
            self._fast.close()
            self._fast = None

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def fast(self) -> Session:
        """Return a fast-engine session: this one when it is, else one kept with it.

        The tuning searches and the many map-error runs use it.
        """
        if self.engine == "fast":
            return self
        if self._fast is None:
            self._fast = Session(engine="fast")
        return self._fast

    # -------------------------------------------------------- parameters

    @staticmethod
    def move_params(sc: Scenario, profile: str, T_F: Sequence[float] | None = None,
                    shaper: ShaperSpec | None = None,
                    table: JerkTable | None = None) -> dict[str, Any]:
        """FMU parameters of the excited axis for ``profile``, jerk times ``T_F``, ``shaper``.

        A shaper becomes the generator's own custom input shaper (``shaper = 4``,
        its amplitudes and delays): the FMU and the compiled engine shape the
        profile themselves.  Profile ``"table"`` replays ``table`` (a :class:`JerkTable`,
        required then and refused otherwise): it must end at rest at the scenario's
        ``x0 + distance`` within its limits (the generator checks it, naming the entry);
        ``T_F`` then sets the jerk times of a commanded stop or move only.

        Raises
        ------
        ValueError
            An unknown profile; profile ``"table"`` without a table, or a table with
            another profile.
        """
        m, s = sc.move, sc.simulation
        if profile == "table":
            if not isinstance(table, JerkTable):
                raise ValueError(f"profile 'table' needs a JerkTable (table=...), got {table!r}")
            code = spec.PROFILE_CODES["table"]
        else:
            if table is not None:
                raise ValueError(f"a table is replayed by profile 'table', not {profile!r}")
            code = spec.PROFILE_CODES[split_profile(profile)[0]]
        p: dict[str, Any] = {
            "profile": code, "Te": s.Te,
            "t_start": m.t_start, "x0": m.x0,
            "distance": m.distance, "v_max": m.v_max, "a_max": m.a_max, "d_max": m.d_max,
            "short_stage": s.short_stage,
        }
        if T_F is not None:
            p.update({f"T_F{i + 1}": float(T_F[i]) for i in range(4)})
        if shaper is not None:
            p.update(shaper.fmu_parameters(s.Te))
        if table is not None:
            p.update(table.fmu_parameters())
        return p

    @staticmethod
    def z_move_params(sc: Scenario, v_max: float) -> dict[str, Any]:
        """FMU parameters of the Z axis (a JL move) with velocity limit ``v_max``."""
        z, s = sc.z, sc.simulation
        Tf = z.T_F if z.T_F > 0 else 0.0
        return {"profile": spec.PROFILE_CODES["JL" if Tf > 0 else "AL"], "Te": s.Te,
                "t_start": sc.move.t_start, "x0": z.z0, "distance": z.distance, "v_max": v_max,
                "a_max": z.a_max, "d_max": z.a_max, "T_F1": Tf, "T_F2": Tf, "T_F3": Tf,
                "T_F4": Tf, "short_stage": s.short_stage}

    def z_velocity(self, sc: Scenario, motion_time: float) -> tuple[float, bool]:
        """Velocity limit of the Z move: synchronised with a motion of ``motion_time``."""
        if not sc.z.moves or not sc.z.sync:
            return sc.z.v_max, not sc.z.moves
        base = self.z_move_params(sc, sc.z.v_max)
        v, _, ok = self.z_axis.sync_velocity(base, motion_time, sc.z.v_max)
        return v, ok

    def plan(self, sc: Scenario, profile: str
             ) -> Callable[[tuple[float, float, float, float]],
                           tuple[MoveSamples, Callable[[float], float]]]:
        """Return the planning function the tuning rule iterates on (:mod:`harness.tuning.rule`)."""

        def plan_fn(T_F: tuple[float, float, float, float]):
            mv = self.axis.sample(self.move_params(sc, profile, T_F))
            v, _ = self.z_velocity(sc, mv.motion_time)
            zs = self.z_axis.sample(self.z_move_params(sc, v), t_stop=mv.t_end)
            return mv, zs.position_at

        return plan_fn

    def plan_move(self, sc: Scenario, profile: str, T_F: Sequence[float] | None,
                  shaper: ShaperSpec | None = None,
                  table: JerkTable | None = None) -> tuple[float, bool]:
        """Plan both axes for one profile; return the excited axis' motion time and Z's sync.

        With ``shaper`` the generator shapes its own output (the motion time then
        includes the last delayed copy); profile ``"table"`` replays ``table``.
        """
        T_x = self.axis.plan(self.move_params(sc, profile, T_F, shaper, table))
        v_z, synced = self.z_velocity(sc, T_x)
        self.z_axis.plan(self.z_move_params(sc, v_z))
        # planning Z may re-plan nothing of the excited axis: it is a separate instance
        return T_x, synced

    # ------------------------------------------------------------- runs

    def t_stop_after_motion(self, sc: Scenario, profile: str, T_F: Sequence[float] | None,
                            shaper: ShaperSpec | None = None,
                            table: JerkTable | None = None) -> float:
        """End of a run that only needs the state when the excited axis' reference ends (s).

        The first communication point at or after the end of the motion, plus one
        step: the residual (the state at the end of the reference) is then in the
        record, and nothing after it is simulated.  The excited axis is re-planned.
        """
        T_x = self.axis.plan(self.move_params(sc, profile, T_F, shaper, table))
        return sc.move.t_start + T_x + sc.simulation.step

    def run(self, sc: Scenario, profile: str, T_F: Sequence[float] | None = None,
            t_stop: float | None = None, shaper: ShaperSpec | None = None,
            table: JerkTable | None = None) -> CoSimResult:
        """Co-simulate one profile of a scenario with the given jerk times.

        Parameters
        ----------
        sc : Scenario
            A single-move scenario.
        profile : str
            ``AL``, ``JL``, ``DJL`` or a variant (``DJL-robust``: its generator profile), or
            ``table``.
        T_F : sequence of 4 float, optional
            Jerk times (s); None for AL (for a table: those of a commanded stop or move).
        t_stop : float, optional
            End of the run (s); default ``simulation.t_after`` after both moves.
        shaper : ShaperSpec, optional
            The generator's input shaper (whole-sample delays): the FMU (or the
            compiled engine) produces the shaped reference itself.
        table : JerkTable, optional
            The reference profile ``table`` replays (:meth:`move_params`).

        Returns
        -------
        CoSimResult
        """
        T_x, synced = self.plan_move(sc, profile, T_F, shaper, table)
        T_z = float(self.z_axis.get("motion_time"))
        if t_stop is None:
            t_stop = sc.move.t_start + max(T_x, T_z) + sc.simulation.t_after
        h = sc.simulation.step
        t_stop = h * math.ceil(t_stop / h - 1e-9)
        run = cosimulate(self.axis, self.z_axis, sc.modemap.scheduled(), t_stop, h,
                         profile=profile)
        run.z_synced = synced
        return run

    def map_error_residuals(self, sc: Scenario, profile: str, T_F: Sequence[float] | None,
                            errors: Sequence[float] | np.ndarray,
                            shaper: ShaperSpec | None = None,
                            table: JerkTable | None = None) -> np.ndarray:
        """Residual of one profile for each map error e (the whole f(z) scaled by 1 + e).

        The move and the Z synchronisation are planned once on the nominal
        scenario (the jerk times do not change with the map); only the plant is
        stepped again, once per error (:func:`harness.simulation.master.map_error_residuals`).

        Raises
        ------
        ValueError
            If an error is not finite or is <= -1 (a frequency <= 0).
        """
        e = check_map_errors(errors)
        self.plan_move(sc, profile, T_F, shaper, table)
        return map_error_residuals(self.axis, self.z_axis, sc.modemap.scheduled(),
                                   1.0 + e, sc.simulation.step)

    def residuals_under(self, sc: Scenario, profile: str, T_F: Sequence[float] | None,
                        points: Sequence[Perturbation], shaper: ShaperSpec | None = None,
                        table: JerkTable | None = None) -> np.ndarray:
        """Residual (m) of one profile under each perturbation, stepping the plant forward.

        Scale-only points go through :meth:`map_error_residuals` (the plant
        stepped to the end of the motion, once per point); any other through a
        run to the end of the motion and :func:`~harness.simulation.master.perturbed`.
        """
        pts = list(points)
        if all(p.is_scale_only for p in pts):
            return self.map_error_residuals(sc, profile, T_F, [p.scale for p in pts], shaper,
                                            table)
        run = self.run(sc, profile, T_F,
                       t_stop=self.t_stop_after_motion(sc, profile, T_F, shaper, table),
                       shaper=shaper, table=table)
        pivot = sc.z.z0 + 0.5 * sc.z.distance
        return np.array([r.free_amplitude for r in perturbed(run, sc.modemap.scheduled(), pts,
                                                             pivot, full=False)])
