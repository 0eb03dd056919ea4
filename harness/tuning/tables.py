"""Jerk-time tables: tuned JL and DJL jerk times per move, over a grid, as a documented CSV.

``djl-fmu tune`` (:mod:`harness.commands.tune`) and :func:`tune_table` tune the
jerk times of JL and DJL for one move, every case of a ``[sweep]`` or every
point of a ``[map]`` grid (Z start, Z travel, distance, v_max), with the
methods of :mod:`harness.tuning_options` (DJL ``paper`` | ``optimal`` | ``robust``,
JL ``end`` | ``optimal``), measure the residual vibration each leaves (nominal
and worst case over the stated map uncertainty) and export one row per move
in a CSV file whose ``#`` header says what every column means and how a
controller or the generator FMU uses it (docs/tune.md).

:func:`load_jerk_times` reads such a file back, :func:`fmu_parameters` turns
one of its rows into the FMU's start values (``profile``, ``T_F1..T_F4``,
``distance``, ``v_max``...) and :meth:`JerkTimeTable.nearest` picks the row
of the move nearest to a given one.

Parallel runs and determinism
    As in :mod:`harness.workspace`: the moves are cut into batches of
    consecutive indices (:func:`batch_size`, which depends on the number of
    moves only), submitted to the executor of
    :func:`harness.executors.make_executor` (this process, a local process
    pool, or a Dask cluster), and put back in order.  Each move is computed
    from the scenario and its grid point alone, on the fast engine, so the
    table -- and the CSV, byte for byte -- is the same whatever the executor.

Examples
--------
>>> from harness.tuning.tables import tune_table, load_jerk_times, fmu_parameters
>>> tab = tune_table("X", djl_method="robust", max_moves=8, workers=2)  # doctest: +SKIP
>>> tab.to_csv("X-jerk-times.csv")                                       # doctest: +SKIP
>>> row = load_jerk_times("X-jerk-times.csv").nearest(0.0, 0.45, 0.4, 0.5)  # doctest: +SKIP
>>> fmu_parameters(row, "DJL")        # {'profile': 3, 'T_F1': ..., ...}  # doctest: +SKIP
"""

from __future__ import annotations

import csv
import dataclasses
import io
import math
import os
import re
import socket
import sys
import threading
import time
from collections.abc import Iterator, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from .. import __version__
from ..errors import BatchError, MoveError
from ..executors import describe_executor, executor_workers, make_executor, run_batches
from ..files import write_text
from ..fmu import spec
from ..scenario import Scenario, load_scenario
from ..simulation.session import Session
from ..tuning_options import DJL_METHODS, JL_METHODS
from ..tuning_options import parse_tuning as parse_pairs
from ..uncertainty import check_map_error
from .tune import tune_profile

__all__ = [
    "COLUMNS",
    "DEFAULT_DJL_METHOD",
    "DEFAULT_JL_METHOD",
    "FORMAT",
    "Column",
    "JerkTimeTable",
    "MoveTuneError",
    "TuneError",
    "batch_size",
    "fmu_parameters",
    "load_jerk_times",
    "parse_tuning",
    "tune_batch",
    "tune_move",
    "tune_table",
    "with_methods",
]

FORMAT = 1
"""Version of the CSV format (the ``# format:`` line); bumped when a column changes meaning."""

MAGIC = "# djl-fmu jerk-time table"
"""First line of every jerk-time CSV file."""

DEFAULT_DJL_METHOD = "robust"
"""DJL method of ``djl-fmu tune`` when ``--tuning`` does not say."""

DEFAULT_JL_METHOD = "end"
"""JL method of ``djl-fmu tune`` when ``--tuning`` does not say."""

MAX_BATCH = 4
"""Most moves in one task (a move costs 0.05-1 s: the task overhead is negligible)."""

MIN_BATCHES = 256
"""A table of this many moves or more is cut into at least this many tasks."""

Point = tuple[float, float, float, float]
"""One move: ``(z0, z_distance, distance, v_max)`` (m, m, m, m/s)."""

METHOD_MEANINGS = {
    "paper": "the modal period at the start of each stage (the paper's rule, "
             "Bearee & Olabi 2013 sec. 3.2; rule djl_rule of the scenario)",
    "optimal": "least residual vibration on the nominal mode map (pattern search over "
               "whole samples on the time-varying model, harness.tuning.search)",
    "robust": "least worst-case residual vibration over the uncertainty below (pattern "
              "search over whole samples on the time-varying model, harness.tuning.search)",
    "end": "the modal period at the end of the motion (the paper's JL)",
}
"""What each tuning method minimises or follows (header of the CSV)."""


class TuneError(BatchError):
    """A table could not be computed: a move failed, or a worker died."""


MoveTuneError = MoveError
"""One move failed (raised in the worker; the message names the move): a :class:`MoveError`."""


# ------------------------------------------------------------------ columns


@dataclass(frozen=True)
class Column:
    """One column of the jerk-time CSV.

    Attributes
    ----------
    name : str
        Header name; its suffix is the SI unit (``_m``, ``_s``, ``_m_s``, ``_m_s2``).
    unit : str
        Unit as printed in the file's header (``samples``, ``0/1``, ``-`` for text).
    kind : {"float", "int", "bool", "str"}
        How the value is written and read back.
    meaning : str
        One line, printed in the file's header.
    """

    name: str
    unit: str
    kind: str
    meaning: str


def _stage_cols() -> list[Column]:
    names = ("start of acceleration", "end of acceleration", "start of deceleration",
             "end of deceleration")
    out = [Column(f"djl_T_F{i}_s", "s", "float",
                  f"DJL jerk time of stage {i} ({names[i - 1]}): FMU parameter T_F{i} "
                  f"with profile = 3") for i in range(1, 5)]
    out += [Column(f"djl_N_F{i}", "samples", "int",
                   f"the same in samples of Te (the FMU reports it as N_F{i})")
            for i in range(1, 5)]
    return out


COLUMNS: tuple[Column, ...] = (
    Column("z0_m", "m", "float", "Z start position"),
    Column("z_distance_m", "m", "float", "Z travel, signed (0: Z still)"),
    Column("distance_m", "m", "float", "length of the move of the excited axis, signed: FMU "
                                       "parameter distance"),
    Column("v_max_m_s", "m/s", "float", "velocity limit of the excited axis: FMU parameter "
                                        "v_max"),
    Column("jl_T_F_s", "s", "float", "JL jerk time: FMU parameter T_F1 with profile = 2"),
    *_stage_cols(),
    Column("residual_m", "m", "float",
           "DJL residual vibration on the nominal map: amplitude of the free oscillation "
           "when the reference ends, summed over the modes (Z moving, synchronised)"),
    Column("worst_residual_m", "m", "float",
           "DJL largest residual over the uncertainty (the 'uncertainty' line)"),
    Column("jl_residual_m", "m", "float", "the same for JL, nominal map"),
    Column("jl_worst_residual_m", "m", "float", "the same for JL, largest over the "
                                                "uncertainty"),
    Column("motion_time_s", "s", "float", "duration of the DJL motion, filters included (the "
                                          "FMU's motion_time)"),
    Column("jl_motion_time_s", "s", "float", "duration of the JL motion"),
    Column("method", "-", "str", "DJL tuning method: paper | optimal | robust"),
    Column("jl_method", "-", "str", "JL tuning method: end | optimal"),
    Column("jl_N_F", "samples", "int", "JL jerk time in samples of Te (the FMU's N_F1)"),
    *(Column(f"djl_period{i}_s", "s", "float",
             f"modal period of the tuned mode at the start of stage {i}, as the paper's rule "
             f"plans it (the local period; the 'paper' jerk time is its rounding"
             + (", stage 2's when merged)" if i == 3 else ")"))
      for i in range(1, 5)),
    Column("jl_period_s", "s", "float", "modal period of the tuned mode at the end of the "
                                        "JL motion (the 'end' jerk time is its rounding)"),
    Column("merged", "0/1", "bool", "1: no constant-velocity stage, DJL stages 2 and 3 form "
                                    "one (the paper gives them one jerk time)"),
    Column("converged", "0/1", "bool", "0: the paper's iteration cycled between roundings "
                                       "(within one sample); always 1 for optimal, robust"),
    Column("z_v_max_m_s", "m/s", "float", "velocity limit of the Z move, lowered so that Z "
                                          "ends with the DJL motion (the Z move of residual_m)"),
    Column("jl_z_v_max_m_s", "m/s", "float", "the same with the JL motion"),
    Column("a_max_m_s2", "m/s2", "float", "FMU parameter a_max (the scenario's)"),
    Column("d_max_m_s2", "m/s2", "float", "FMU parameter d_max (the scenario's)"),
    Column("x0_m", "m", "float", "FMU parameter x0 (the scenario's)"),
    Column("t_start_s", "s", "float", "FMU parameter t_start (the scenario's)"),
    Column("Te_s", "s", "float", "FMU parameter Te, the sampling period (the scenario's)"),
    Column("short_stage", "-", "int", "FMU parameter short_stage (the scenario's)"),
    Column("move_index", "-", "int", "0-based index of the move: [map] grid order "
                                     "((i_z0*n_dz + i_dz)*n_d + i_d)*n_v + i_v, [sweep] case "
                                     "order, 0 for a single move"),
)
"""The columns of the CSV, in file order (format :data:`FORMAT`)."""

COLUMN_NAMES = tuple(c.name for c in COLUMNS)
_KINDS = {c.name: c.kind for c in COLUMNS}
_META_LINE = re.compile(r"^# ([A-Za-z_][A-Za-z0-9_]*): (.*)$")


# ------------------------------------------------------------- the methods


def parse_tuning(text: str | None) -> tuple[str, str]:
    """Return the DJL and JL methods a ``--tuning`` value picks for a table.

    The grammar is the one of every command (:func:`harness.tuning_options.parse_tuning`):
    comma-separated items ``METHOD``, ``djl=METHOD`` or ``jl=METHOD``.  A table
    has one DJL and one JL column set, so it takes at most one method per
    profile.

    Parameters
    ----------
    text : str, optional
        The value; None or empty: the defaults.

    Returns
    -------
    djl_method, jl_method : str
        Defaults :data:`DEFAULT_DJL_METHOD` and :data:`DEFAULT_JL_METHOD` for
        what the text does not set.

    Raises
    ------
    ValueError
        An unknown method or key, or two methods for one profile.
    """
    got: dict[str, str] = {}
    for prof, method in parse_pairs(text):
        if prof in got:
            raise ValueError(f"a table has one {prof} method, {got[prof]!r} and {method!r} are "
                             f"given (to compare methods, use 'djl-fmu simulate' or 'djl-fmu "
                             f"map' with --tuning)")
        got[prof] = method
    return got.get("DJL", DEFAULT_DJL_METHOD), got.get("JL", DEFAULT_JL_METHOD)


def with_methods(sc: Scenario, djl_method: str = DEFAULT_DJL_METHOD,
                 jl_method: str = DEFAULT_JL_METHOD, map_error: float | None = None
                 ) -> Scenario:
    """Return the scenario set up to tune with these methods.

    Parameters
    ----------
    sc : Scenario
        Any scenario.
    djl_method : {"paper", "optimal", "robust"}
        DJL tuning method.
    jl_method : {"end", "optimal"}
        JL tuning method.
    map_error : float, optional
        Relative map error in [0, 1) of the robust objective and of the worst
        residuals: replaces the scenario's ``uncertainty.map_scale`` (default:
        keep it; the uncertainty is its only home).

    Returns
    -------
    Scenario
        ``compare`` with these methods and no imposed jerk times (``JL_T_F``,
        ``DJL_T_F``: this module computes them); ``uncertainty`` the scenario's,
        with ``map_error`` as its map scale when given.

    Raises
    ------
    ValueError
        Unknown method or map error outside [0, 1).
    """
    if djl_method not in DJL_METHODS:
        raise ValueError(f"unknown DJL tuning method {djl_method!r}: choose from "
                         f"{', '.join(DJL_METHODS)}")
    if jl_method not in JL_METHODS:
        raise ValueError(f"unknown JL tuning method {jl_method!r}: choose from "
                         f"{', '.join(JL_METHODS)}")
    unc = sc.uncertainty
    if map_error is not None:
        unc = dataclasses.replace(unc, map_scale=check_map_error(map_error, "the map error"))
    cmp = dataclasses.replace(sc.compare, djl_tuning=djl_method, jl_tuning=jl_method,
                              JL_T_F=None, DJL_T_F=None)
    out = dataclasses.replace(sc, compare=cmp, uncertainty=unc)
    out.tuning_options()  # checks the other options
    return out


# ---------------------------------------------------------------- one move


def _t(N: int, Te: float) -> float:
    """Return a jerk time of N samples (s), rounded to 12 digits (what the CSV holds)."""
    return round(N * Te, 12)


def tune_move(case: Scenario, session: Session, index: int = 0) -> dict[str, Any]:
    """Tune JL and DJL for one move and measure what each leaves: one row of the table.

    Parameters
    ----------
    case : Scenario
        A single-move scenario whose ``compare`` holds the methods
        (:func:`with_methods`).
    session : Session
        A fast-engine session (``Session(engine="fast")``).
    index : int
        The ``move_index`` of the row.

    Returns
    -------
    dict
        One value per column of :data:`COLUMNS`.

    Notes
    -----
    The residuals are computed by :meth:`harness.simulation.session.Session.residuals_under`
    (the plant stepped forward, not the searches' adjoint): the free-oscillation
    amplitude when the reference ends, Z moving as in the scenario; the worst
    case is the largest over the scoring set of the scenario's uncertainty
    (:meth:`harness.uncertainty.UncertaintySpec.scoring_set`; the robust method
    is tuned on the coarser tuning set).
    """
    Te = case.simulation.Te
    jl = tune_profile(session, case, "JL")
    djl = tune_profile(session, case, "DJL")
    if jl is None or djl is None:  # pragma: no cover - with_methods clears imposed ones
        raise ValueError("the scenario imposes jerk times (compare.JL_T_F / DJL_T_F)")
    scoring = case.uncertainty.scoring_set().points

    def measure(profile: str, N: tuple[int, ...]) -> tuple[float, float, float, float]:
        T_F = tuple(n * Te for n in N)
        rw = session.residuals_under(case, profile, T_F, scoring)  # the nominal map first
        T, _ = session.plan_move(case, profile, T_F)
        v_z, _ = session.z_velocity(case, T)
        return float(T), float(rw[0]), float(np.max(rw)), float(v_z)

    N_jl = int(jl.N_F[0])
    N = tuple(int(n) for n in djl.N_F)
    T_d, r_d, w_d, vz_d = measure("DJL", N)
    T_j, r_j, w_j, vz_j = measure("JL", (N_jl,) * 4)
    periods = tuple(float(p) for p in djl.periods)
    if len(periods) == 1:  # pragma: no cover - the DJL rules give four periods
        periods = periods * 4
    m, s, cmp = case.move, case.simulation, case.compare
    row: dict[str, Any] = {
        "z0_m": float(case.z.z0), "z_distance_m": float(case.z.distance),
        "distance_m": float(m.distance), "v_max_m_s": float(m.v_max),
        "jl_T_F_s": _t(N_jl, Te),
    }
    row.update({f"djl_T_F{i + 1}_s": _t(N[i], Te) for i in range(4)})
    row.update({f"djl_N_F{i + 1}": N[i] for i in range(4)})
    row.update({
        "residual_m": r_d, "worst_residual_m": w_d, "jl_residual_m": r_j,
        "jl_worst_residual_m": w_j, "motion_time_s": T_d, "jl_motion_time_s": T_j,
        "method": cmp.djl_tuning, "jl_method": cmp.jl_tuning, "jl_N_F": N_jl,
    })
    row.update({f"djl_period{i + 1}_s": periods[i] for i in range(4)})
    row.update({
        "jl_period_s": float(jl.periods[0]), "merged": bool(djl.merged),
        "converged": bool(djl.converged), "z_v_max_m_s": vz_d, "jl_z_v_max_m_s": vz_j,
        "a_max_m_s2": float(m.a_max), "d_max_m_s2": float(m.d_max), "x0_m": float(m.x0),
        "t_start_s": float(m.t_start), "Te_s": float(Te), "short_stage": int(s.short_stage),
        "move_index": int(index),
    })
    return row


# --------------------------------------------------------- the worker side

_LOCAL = threading.local()


def _worker_session() -> Session:
    """Return the fast-engine session of this process and thread (created on first use)."""
    cur = getattr(_LOCAL, "session", None)
    if cur is None:
        cur = _LOCAL.session = Session(engine="fast")
    return cur


def close_worker_session() -> None:
    """Close the session this process and thread keep between batches, if any."""
    cur = getattr(_LOCAL, "session", None)
    _LOCAL.session = None
    if cur is not None:
        cur.close()


@dataclass
class TuneBatch:
    """What a worker sends back for one batch of moves.

    Attributes
    ----------
    start : int
        Index of the first move.
    rows : list of dict
        One row per move.
    busy_time : float
        Time the worker spent on the batch (s).
    worker : str
        ``host:pid`` of the worker.
    """

    start: int
    rows: list[dict[str, Any]]
    busy_time: float
    worker: str


def tune_batch(scenario: Scenario, start: int, points: Sequence[Point]) -> TuneBatch:
    """Tune a batch of consecutive moves (the task sent to the workers).

    Parameters
    ----------
    scenario : Scenario
        The scenario, methods set (:func:`with_methods`).
    start : int
        Index of ``points[0]``.
    points : sequence of tuple of float
        The moves, ``(z0, z_distance, distance, v_max)``.

    Returns
    -------
    TuneBatch

    Raises
    ------
    MoveError
        If a move fails; the message names it (index and values).
    """
    t0 = time.perf_counter()
    session = _worker_session()
    rows = []
    for k, p in enumerate(points):
        try:
            rows.append(tune_move(scenario.map_case(*p), session, start + k))
        except Exception as e:  # noqa: BLE001 (reported with the move, as plain text)
            close_worker_session()
            raise MoveError(f"move {start + k} (z0 = {p[0]:g} m, z_distance = {p[1]:g} m, "
                                f"distance = {p[2]:g} m, v_max = {p[3]:g} m/s) failed: "
                                f"{type(e).__name__}: {e}") from None
    return TuneBatch(start, rows, time.perf_counter() - t0,
                     f"{socket.gethostname()}:{os.getpid()}")


# ------------------------------------------------------------ the table


def batch_size(n_moves: int) -> int:
    """Return the moves per task for a table of ``n_moves`` (and nothing else).

    At most :data:`MAX_BATCH`, and small enough that a table of
    :data:`MIN_BATCHES` moves or more has at least that many tasks.
    """
    return max(1, min(MAX_BATCH, math.ceil(n_moves / MIN_BATCHES)))


def _grid(sc: Scenario, max_moves: int | None, single: bool = False
          ) -> tuple[str, list[Point], int]:
    """Return what is tuned: ``("map" | "sweep" | "move", points, full grid size)``."""
    if single:
        return "move", [(sc.z.z0, sc.z.distance, sc.move.distance, sc.move.v_max)], 1
    if max_moves is not None and (isinstance(max_moves, bool) or not isinstance(max_moves, int)
                                  or max_moves < 1):
        raise ValueError(f"max_moves must be an integer >= 1, got {max_moves!r}")
    if sc.map is not None:
        return "map", sc.map_points(max_moves), sc.map_size
    if sc.is_sweep:
        pts = [(float(c.z.z0), float(c.z.distance), float(c.move.distance), float(c.move.v_max))
               for c in sc.cases()]
        return "sweep", pts[:max_moves] if max_moves else pts, len(pts)
    return "move", [(sc.z.z0, sc.z.distance, sc.move.distance, sc.move.v_max)], 1


def tune_table(scenario: Scenario | str | Path, *, djl_method: str = DEFAULT_DJL_METHOD,
               jl_method: str = DEFAULT_JL_METHOD, map_error: float | None = None,
               workers: int | None = None, scheduler: str | None = None,
               max_moves: int | None = None, progress: bool = False,
               executor: Executor | None = None, batch: int | None = None,
               single: bool = False) -> JerkTimeTable:
    """Tune JL and DJL for every move of a scenario; one row per move.

    Parameters
    ----------
    scenario : Scenario, str or Path
        A scenario (object, TOML file or embedded name).  With a ``[map]``
        table: every grid point (z0, z_distance, distance, v_max), in grid
        order; else with a ``[sweep]``: every case, in the sweep's order; else
        its single move.
    djl_method : {"paper", "optimal", "robust"}
        DJL tuning method (default ``robust``).
    jl_method : {"end", "optimal"}
        JL tuning method (default ``end``).
    map_error : float, optional
        Relative map error in [0, 1) of the robust objective and of the worst
        residuals, replacing the scenario's ``uncertainty.map_scale`` (default:
        the scenario's, 0.1 unless its ``[uncertainty]`` says otherwise).
    workers : int, optional
        Local worker processes (default: every core); 1 runs in this process,
        and so does a single move.
    scheduler : str, optional
        Address of a Dask scheduler: run on its workers.
    max_moves : int, optional
        Tune only the first ``max_moves`` moves (map or sweep).
    progress : bool
        tqdm progress bar on stderr (when it is a terminal).
    executor : Executor, optional
        Use this executor (left open) instead of ``workers`` / ``scheduler``.
    batch : int, optional
        Moves per task (default :func:`batch_size`); the table does not depend on it.
    single : bool
        Tune the scenario's own move (``[move]``, ``[z]``) only, whatever its
        ``[map]`` or ``[sweep]`` table.

    Returns
    -------
    JerkTimeTable

    Raises
    ------
    ScenarioError
        If the scenario cannot be loaded.
    ValueError
        Unknown method, map error outside [0, 1), bad ``max_moves`` or
        ``batch``; :class:`harness.executors.ExecutorError` for bad workers or
        an unreachable scheduler.
    TuneError
        A move failed (the message names it) or a worker died.
    """
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    sc = with_methods(sc, djl_method, jl_method, map_error)
    kind, points, total = _grid(sc, max_moves, single)
    if batch is not None and (isinstance(batch, bool) or not isinstance(batch, int)
                              or batch < 1):
        raise ValueError(f"batch must be an integer >= 1, got {batch!r}")
    bs = batch or batch_size(len(points))
    if executor is not None:
        return _run_on(sc, kind, points, total, bs, executor, executor_workers(executor),
                       _where(executor, None), progress)
    if len(points) == 1 and scheduler is None:
        workers = 1
    with make_executor(workers, scheduler) as ex:
        return _run_on(sc, kind, points, total, bs, ex, executor_workers(ex),
                       _where(ex, scheduler), progress)


def _where(ex: Executor, scheduler: str | None) -> str:
    return describe_executor(ex, scheduler)


def _run_on(sc: Scenario, kind: str, points: list[Point], total: int, bs: int, ex: Executor,
            n_workers: int, where: str, progress: bool) -> JerkTimeTable:
    bar = None
    if progress and len(points) > 1 and sys.stderr.isatty():
        bar = tqdm(total=len(points), desc=f"tune {sc.name}", unit="move", leave=False)
    batches, wall = run_batches(ex, tune_batch, (sc,), points, bs, error=TuneError,
                                passthrough=MoveError, progress=bar,
                                on_serial_end=close_worker_session)
    rows = [r for br in batches for r in br.rows]
    assert len(rows) == len(points)
    return JerkTimeTable(rows, _header(sc, kind, len(points), total), scenario=sc, kind=kind,
                         wall_time=wall, busy_time=sum(br.busy_time for br in batches),
                         workers=n_workers, executor=where)


# --------------------------------------------------------------- the header


def _uncertainty_text(sc: Scenario) -> str:
    u = sc.uncertainty
    return (f"{u.describe()} (robust tuning: the {len(u.tuning_set())}-point tuning set; the "
            f"worst_* columns: the {len(u.scoring_set())}-point scoring set)")


def _header(sc: Scenario, kind: str, n: int, total: int) -> list[str]:
    """Return the comment lines of the CSV (without the leading ``# ``)."""
    cmp, s = sc.compare, sc.simulation
    opts = sc.tuning_options()
    if kind == "map":
        axes = sc.map_axes()
        grid = ("[map] z0 x z_distance x distance x v_max = "
                + " x ".join(str(len(a)) for a in axes)
                + f" = {total} moves, in this order, v_max varying fastest")
    elif kind == "sweep":
        grid = (f"[sweep] {total} cases, distance x z_distance x v_max (v_max fastest), Z "
                f"from z0 = {sc.z.z0:g} m")
    else:
        grid = "a single move"
    rows = f"{n}" + (f" (the first {n} of {total})" if n < total else "")
    mode = sc.modemap.tuned
    bound = opts.max_motion_time
    bound_txt = ("at most JL's" if bound == "JL" else f"at most {bound:g} s" if bound
                 else "not bounded")
    out = [
        MAGIC[2:],
        f"format: {FORMAT}",
        f"generated_by: djl-fmu {__version__} (djl-fmu tune; harness.tuning.tables)",
        f"scenario: {sc.name}",
        f"source: {sc.source}",
    ]
    if sc.description:
        out.append("description: " + " ".join(sc.description.split()))
    out += [
        f"grid: {grid}",
        f"rows: {rows}",
        f"djl_method: {cmp.djl_tuning}",
        f"djl_method_meaning: {METHOD_MEANINGS[cmp.djl_tuning]}",
        f"jl_method: {cmp.jl_tuning}",
        f"jl_method_meaning: {METHOD_MEANINGS[cmp.jl_tuning]}",
        f"uncertainty: {_uncertainty_text(sc)}; the worst_* columns are the largest residual "
        f"over the scoring set, for every method",
        f"map_error: {sc.uncertainty.map_scale:g}",
        "damping_factors: " + (f"{sc.uncertainty.damping[0]:g}..{sc.uncertainty.damping[1]:g}"
                               if sc.uncertainty.active["damping"] else "1"),
        f"constraints: jerk times within +/-{opts.period_band:g} x the local periods; motion "
        f"time {bound_txt} (optimal, robust)",
        f"djl_rule: {cmp.djl_rule}",
        f"tuned_mode: {sc.modemap.tune + 1}" + (f" ({mode.name})" if mode.name else ""),
        f"modes: {len(sc.modemap.modes)}, damping ratios "
        + ", ".join(f"{m.zeta:g}" for m in sc.modemap.modes),
        f"z_axis: a_max {sc.z.a_max:g} m/s2, v_max {sc.z.v_max:g} m/s, T_F {sc.z.T_F:g} s, "
        f"synchronised {'yes' if sc.z.sync else 'no'}",
        f"Te_s: {s.Te!r}",
        "units: SI, given by each column's suffix: _m metres, _s seconds, _m_s m/s, _m_s2 "
        "m/s2; N_F columns in samples of Te; 0/1 flags; residuals are amplitudes in m",
        "columns (in this order):",
    ]
    w = max(len(c.name) for c in COLUMNS)
    out += [f"  {c.name:<{w}}  {'[' + c.unit + ']':<9}  {c.meaning}" for c in COLUMNS]
    out += [
        "use: one row per move. Set these start values of the generator FMU "
        "(JerkLimitedTrajectory) before its initialisation:",
        "  DJL: profile = 3, T_F1 = djl_T_F1_s, T_F2 = djl_T_F2_s, T_F3 = djl_T_F3_s, "
        "T_F4 = djl_T_F4_s",
        "  JL:  profile = 2, T_F1 = jl_T_F_s",
        "  both: distance = distance_m, v_max = v_max_m_s, a_max = a_max_m_s2, "
        "d_max = d_max_m_s2, x0 = x0_m, t_start = t_start_s, Te = Te_s, "
        "short_stage = short_stage",
        "  The FMU then reports N_F1..N_F4 = djl_N_F1..djl_N_F4 (JL: jl_N_F) and "
        "motion_time = motion_time_s (JL: jl_motion_time_s).",
        "  The residuals are with the Z axis moving z_distance_m from z0_m, its velocity "
        "limit lowered to z_v_max_m_s (JL: jl_z_v_max_m_s) so that it ends with the move.",
        "  For another move take the nearest row, or tune that move: jerk times interpolated "
        "between rows are not checked.",
        "  Python: harness.tuning.tables.load_jerk_times(path) reads this file, "
        ".nearest(z0, z_distance, distance, v_max) picks a row, fmu_parameters(row, 'DJL') "
        "gives the start values.",
        "  Other tools: skip the lines that start with '#'; the first other line is the "
        "column header, then one row per move (comma-separated, '.' decimal point).",
    ]
    return out


# ---------------------------------------------------------------- the table


def _fmt(kind: str, v: Any) -> str:
    if kind == "float":
        return repr(float(v))
    if kind == "int":
        return str(int(v))
    if kind == "bool":
        return "1" if v else "0"
    return str(v)


def _parse(kind: str, text: str) -> Any:
    if kind == "float":
        return float(text)
    if kind == "int":
        return int(text)
    if kind == "bool":
        if text not in ("0", "1"):
            raise ValueError(f"expected 0 or 1, got {text!r}")
        return text == "1"
    return text


@dataclass
class JerkTimeTable:
    """Tuned jerk times, one row per move (from :func:`tune_table` or :func:`load_jerk_times`).

    Attributes
    ----------
    rows : list of dict
        One dict per move, keyed by :data:`COLUMN_NAMES` (floats, ints,
        bools for the 0/1 flags, str for the methods), in move order.
    comments : list of str
        The header lines, without the leading ``# ``.
    scenario : Scenario, optional
        The scenario tuned (None when read from a file).
    kind : {"map", "sweep", "move", ""}
        What the rows are ("" when read from a file).
    wall_time, busy_time : float
        Wall-clock time and the sum of the workers' time (s); NaN when read.
    workers : int
        Tasks run at once.
    executor : str
        Where it ran.
    """

    rows: list[dict[str, Any]]
    comments: list[str]
    scenario: Scenario | None = None
    kind: str = ""
    wall_time: float = math.nan
    busy_time: float = math.nan
    workers: int = 0
    executor: str = ""
    columns: tuple[str, ...] = field(default=COLUMN_NAMES)

    def __len__(self) -> int:
        return len(self.rows)

    def __iter__(self) -> Iterator[dict[str, Any]]:
        return iter(self.rows)

    @property
    def meta(self) -> dict[str, str]:
        """The ``key: value`` lines of the header (``format``, ``scenario``, ``djl_method``...)."""
        out: dict[str, str] = {}
        for line in self.comments:
            m = _META_LINE.match("# " + line)
            if m:
                out.setdefault(m.group(1), m.group(2))
        return out

    def column(self, name: str) -> np.ndarray:
        """One numeric column as a float array, in row order."""
        if name not in self.columns:
            raise KeyError(f"no column {name!r}")
        return np.array([float(r[name]) for r in self.rows], dtype=float)

    # ----------------------------------------------------------- files

    def to_text(self) -> str:
        """Return the CSV file's text: ``#`` header, column names, one line per row."""
        buf = io.StringIO()
        for line in self.comments:
            buf.write(f"# {line}".rstrip() + "\n")
        w = csv.writer(buf, lineterminator="\n")
        w.writerow(self.columns)
        for r in self.rows:
            w.writerow([_fmt(_KINDS.get(c, "str"), r[c]) for c in self.columns])
        return buf.getvalue()

    def to_csv(self, path: str | Path) -> Path:
        """Write the CSV file atomically (temporary file, then rename); return its path."""
        return write_text(path, self.to_text())

    # ---------------------------------------------------------- lookup

    def nearest(self, z0: float, z_distance: float, distance: float, v_max: float
                ) -> dict[str, Any]:
        """Return the row of the move nearest to ``(z0, z_distance, distance, v_max)``.

        Each coordinate is divided by the spread of its column in the table
        (1 where the column is constant), so that metres of Z and m/s weigh
        alike; ties go to the first row.  No interpolation: the jerk times of
        the returned row are those tuned for that row's move.

        Raises
        ------
        ValueError
            If the table is empty or a coordinate is not finite.
        """
        q = np.array([z0, z_distance, distance, v_max], dtype=float)
        if not self.rows:
            raise ValueError("the table has no rows")
        if not np.all(np.isfinite(q)):
            raise ValueError(f"the move must be finite numbers, got {tuple(q)}")
        names = ("z0_m", "z_distance_m", "distance_m", "v_max_m_s")
        pts = np.column_stack([self.column(n) for n in names])
        spread = pts.max(axis=0) - pts.min(axis=0)
        spread[spread == 0.0] = 1.0
        d = (((pts - q) / spread) ** 2).sum(axis=1)
        return self.rows[int(np.argmin(d))]

    # ------------------------------------------------------------ text

    @property
    def per_move(self) -> float:
        """Wall-clock time per move (s)."""
        return self.wall_time / len(self.rows) if self.rows else math.nan

    @property
    def cost_per_move(self) -> float:
        """Worker time per move (s): what one core spends on a move."""
        return self.busy_time / len(self.rows) if self.rows else math.nan

    def table(self) -> str:
        """Return what ``djl-fmu tune`` prints: a single move in full, else summary and rows."""
        meta = self.meta
        if len(self.rows) == 1 and self.kind in ("move", ""):
            return self._move_table(self.rows[0], meta)
        return self._grid_table(meta)

    def _title(self, meta: dict[str, str]) -> list[str]:
        unc = meta.get("uncertainty", "").split(";")[0]
        return [f"DJL method {meta.get('djl_method', '?')}: "
                f"{METHOD_MEANINGS.get(meta.get('djl_method', ''), '?')}",
                f"JL method {meta.get('jl_method', '?')}: "
                f"{METHOD_MEANINGS.get(meta.get('jl_method', ''), '?')}",
                f"uncertainty (worst case): {unc}"]

    def _move_table(self, r: dict[str, Any], meta: dict[str, str]) -> str:
        name = meta.get("scenario", "?")
        e = meta.get("map_error", "?")
        lines = [f"Jerk times of {name}: d = {r['distance_m']:g} m, v_max = "
                 f"{r['v_max_m_s']:g} m/s, Z {r['z0_m']:g} m -> "
                 f"{r['z0_m'] + r['z_distance_m']:g} m", *self._title(meta), ""]
        hdr = f"{'':<24}" + "".join(f"{'stage ' + str(i):>10}" for i in range(1, 5))
        lines.append(hdr)
        lines.append(f"{'local period [ms]':<24}" + "".join(
            f"{r[f'djl_period{i}_s'] * 1e3:>10.1f}" for i in range(1, 5))
            + ("   (stages 2, 3 merged)" if r["merged"] else ""))
        lines.append(f"{'DJL T_F [ms]':<24}" + "".join(
            f"{r[f'djl_T_F{i}_s'] * 1e3:>10g}" for i in range(1, 5)))
        lines.append(f"{'DJL N_F [samples]':<24}" + "".join(
            f"{r[f'djl_N_F{i}']:>10d}" for i in range(1, 5)))
        lines.append(f"{'JL T_F [ms]':<24}{r['jl_T_F_s'] * 1e3:>10g}   ({r['jl_N_F']} samples; "
                     f"period at the end of the motion {r['jl_period_s'] * 1e3:.1f} ms)")
        lines.append("")
        wname = f"worst, map +/-{float(e) * 100:g} % [mm]" if e != "?" else "worst [mm]"
        lines.append(f"{'':<12}{'residual [mm]':>16}{wname:>28}{'motion time [s]':>18}")
        lines.append(f"{'JL':<12}{r['jl_residual_m'] * 1e3:>16.4g}"
                     f"{r['jl_worst_residual_m'] * 1e3:>28.4g}{r['jl_motion_time_s']:>18.4f}")
        lines.append(f"{'DJL':<12}{r['residual_m'] * 1e3:>16.4g}"
                     f"{r['worst_residual_m'] * 1e3:>28.4g}{r['motion_time_s']:>18.4f}")
        lines.append(f"{'DJL vs JL':<12}{_pct(r['residual_m'], r['jl_residual_m']):>16}"
                     f"{_pct(r['worst_residual_m'], r['jl_worst_residual_m']):>28}"
                     f"{_pct(r['motion_time_s'], r['jl_motion_time_s']):>18}")
        lines.append("(residual: amplitude of the free oscillation when the reference ends)")
        if math.isfinite(self.wall_time):
            lines.append(f"tuned in {self.wall_time:.2f} s")
        return "\n".join(lines)

    def _grid_table(self, meta: dict[str, str]) -> str:
        n = len(self.rows)
        lines = [f"Jerk times of {meta.get('scenario', '?')}: {n} moves "
                 f"({meta.get('grid', '')}; rows: {meta.get('rows', n)})", *self._title(meta)]
        if math.isfinite(self.wall_time):
            lines.append(f"wall time {self.wall_time:.2f} s on {self.workers} worker(s) "
                         f"({self.executor}): {self.per_move:.3g} s a move, "
                         f"{self.cost_per_move:.3g} s a move on one worker")
        if n:
            rd, rj = self.column("residual_m"), self.column("jl_residual_m")
            wd, wj = self.column("worst_residual_m"), self.column("jl_worst_residual_m")
            td, tj = self.column("motion_time_s"), self.column("jl_motion_time_s")
            lines.append("")
            lines.append(f"{'DJL against JL, % change':<34}{'median':>9}{'min':>9}{'max':>9}"
                         f"{'DJL <= JL':>12}")
            for label, a, b in (("residual, nominal map", rd, rj),
                                ("worst residual over the uncertainty", wd, wj),
                                ("motion time", td, tj)):
                with np.errstate(divide="ignore", invalid="ignore"):
                    ch = np.where(b > 0, (a - b) / b * 100.0, np.nan)
                fin = ch[np.isfinite(ch)]
                stats = (f"{np.median(fin):>9.1f}{fin.min():>9.1f}{fin.max():>9.1f}"
                         if fin.size else f"{'n/a':>9}{'n/a':>9}{'n/a':>9}")
                lines.append(f"{label:<34}{stats}{int(np.sum(a <= b)):>7d} of {n}")
        lines.append("")
        shown = self.rows if n <= 30 else self.rows[:20]
        lines.append(f"{'move':>6}{'z0':>7}{'dz':>7}{'d':>7}{'v_max':>7}{'JL T_F':>8}"
                     f"{'DJL T_F1..T_F4 [ms]':>22}{'residual DJL/JL [mm]':>22}"
                     f"{'worst DJL/JL [mm]':>20}")
        for r in shown:
            tf = "/".join(f"{r[f'djl_T_F{i}_s'] * 1e3:g}" for i in range(1, 5))
            lines.append(f"{r['move_index']:>6d}{r['z0_m']:>7g}{r['z_distance_m']:>7g}"
                         f"{r['distance_m']:>7g}{r['v_max_m_s']:>7g}"
                         f"{r['jl_T_F_s'] * 1e3:>8g}{tf:>22}"
                         f"{_pair(r['residual_m'], r['jl_residual_m']):>22}"
                         f"{_pair(r['worst_residual_m'], r['jl_worst_residual_m']):>20}")
        if len(shown) < n:
            lines.append(f"... {n - len(shown)} more moves in the CSV")
        lines.append("(z0, dz, d in m, v_max in m/s; residual: amplitude of the free "
                     "oscillation when the reference ends)")
        return "\n".join(lines)


def _pct(a: float, b: float) -> str:
    return f"{(a - b) / b * 100.0:+.1f} %" if b > 0 else "n/a"


def _pair(a: float, b: float) -> str:
    return f"{a * 1e3:.3g}/{b * 1e3:.3g}"


# ---------------------------------------------------------------- reading


def load_jerk_times(path: str | Path) -> JerkTimeTable:
    """Read a jerk-time CSV file written by ``djl-fmu tune`` (:meth:`JerkTimeTable.to_csv`).

    Parameters
    ----------
    path : path-like
        The file.

    Returns
    -------
    JerkTimeTable
        ``rows`` typed by column (float, int, bool for 0/1, str); columns
        this version does not know are kept as text.

    Raises
    ------
    ValueError
        If the file is not a jerk-time table, has a format this version
        cannot read, lacks a column, or has a value that does not parse (the
        message gives the line).
    OSError
        If the file cannot be read.
    """
    path = Path(path)
    text = path.read_text(encoding="utf-8")
    lines = text.splitlines()
    if not lines or lines[0].rstrip() != MAGIC:
        raise ValueError(f"{path}: not a djl-fmu jerk-time table (the first line must be "
                         f"{MAGIC!r})")
    comments: list[str] = []
    i = 0
    while i < len(lines) and lines[i].startswith("#"):
        comments.append(lines[i][2:] if lines[i].startswith("# ") else lines[i][1:])
        i += 1
    tab = JerkTimeTable([], comments)
    fmt = tab.meta.get("format")
    if fmt is None or not fmt.strip().isdigit():
        raise ValueError(f"{path}: no '# format: N' line in the header")
    if int(fmt) != FORMAT:
        raise ValueError(f"{path}: format {fmt} of the jerk-time table is not supported "
                         f"(this version reads format {FORMAT})")
    reader = csv.reader(lines[i:])
    try:
        columns = tuple(next(reader))
    except StopIteration:
        raise ValueError(f"{path}: no column header after the comments") from None
    missing = [c for c in COLUMN_NAMES if c not in columns]
    if missing:
        raise ValueError(f"{path}: missing column(s) {', '.join(missing)}")
    rows = []
    for k, rec in enumerate(reader):
        lineno = i + 2 + k
        if not rec or all(not x.strip() for x in rec):
            continue
        if len(rec) != len(columns):
            raise ValueError(f"{path}, line {lineno}: {len(rec)} values for "
                             f"{len(columns)} columns")
        row: dict[str, Any] = {}
        for c, v in zip(columns, rec, strict=True):
            try:
                row[c] = _parse(_KINDS.get(c, "str"), v)
            except ValueError as e:
                raise ValueError(f"{path}, line {lineno}, column {c}: {e}") from None
        rows.append(row)
    return JerkTimeTable(rows, comments, columns=columns)


def fmu_parameters(row: dict[str, Any], profile: str = "DJL") -> dict[str, Any]:
    """Start values of the generator FMU for one row of a jerk-time table.

    Parameters
    ----------
    row : dict
        A row of :class:`JerkTimeTable` (or any mapping with its columns).
    profile : {"DJL", "JL"}
        ``DJL``: ``profile = 3`` and ``T_F1..T_F4 = djl_T_F1_s..djl_T_F4_s``;
        ``JL``: ``profile = 2`` and ``T_F1 = jl_T_F_s`` (T_F2..T_F4 set to the
        same value; the FMU's JL uses T_F1 only).

    Returns
    -------
    dict
        ``profile``, ``Te``, ``t_start``, ``x0``, ``distance``, ``v_max``,
        ``a_max``, ``d_max``, ``short_stage``, ``T_F1`` .. ``T_F4``: the
        excited axis' parameters, exactly those the harness gives the FMU
        (:meth:`harness.simulation.session.Session.move_params`).

    Raises
    ------
    ValueError
        For another profile.
    """
    if profile not in ("DJL", "JL"):
        raise ValueError(f"profile must be 'DJL' or 'JL', got {profile!r}")
    p: dict[str, Any] = {
        "profile": spec.PROFILE_CODES[profile], "Te": float(row["Te_s"]),
        "t_start": float(row["t_start_s"]), "x0": float(row["x0_m"]),
        "distance": float(row["distance_m"]), "v_max": float(row["v_max_m_s"]),
        "a_max": float(row["a_max_m_s2"]), "d_max": float(row["d_max_m_s2"]),
        "short_stage": int(row["short_stage"]),
    }
    if profile == "DJL":
        p.update({f"T_F{i}": float(row[f"djl_T_F{i}_s"]) for i in range(1, 5)})
    else:
        p.update({f"T_F{i}": float(row["jl_T_F_s"]) for i in range(1, 5)})
    return p

