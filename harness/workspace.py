"""Workspace maps: every compared profile over a grid of moves, on all cores or a Dask cluster.

A *map* runs the single-move evaluation of :func:`harness.evaluation.run_case`
(tune JL and DJL, co-simulate AL / JL / DJL, measure residual vibration,
motion and settling time) for every move of a grid: the cartesian product of
Z start positions, Z travels, move lengths and velocity limits given by the
scenario's ``[map]`` table (:class:`harness.scenario.MapSpec`; the embedded
``X`` and ``Y`` scenarios have a 10,000-move grid).

Parallel runs
    The moves are cut into batches of consecutive grid indices (one task = a
    batch, :func:`batch_size`, to amortise the task overhead), submitted to a
    :class:`concurrent.futures.Executor` (:func:`harness.executors.make_executor`:
    a local process pool, or a Dask cluster with ``scheduler``).  Each worker
    keeps one :class:`~harness.simulation.session.Session` (per process and
    thread) between batches (:func:`harness.sweeps.worker_session`).  The
    results are put back in grid order.

Determinism
    Every move is computed by the same code from the same inputs whatever the
    worker that runs it, and its result does not depend on the moves run
    before it in that worker: the CSV is identical, to the last bit, for any
    executor and any number of workers (tested).

Examples
--------
>>> from harness.workspace import run_workspace_map
>>> res = run_workspace_map("X", max_moves=200, workers=2)     # doctest: +SKIP
>>> print(res.table()); res.to_csv("X-map.csv")       # doctest: +SKIP
"""

from __future__ import annotations

import itertools
import math
import os
import socket
import sys
import time
from collections.abc import Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from .errors import BatchError, MoveError
from .evaluation import run_case
from .executors import (
    LineProgress,
    describe_executor,
    executor_workers,
    make_executor,
    run_batches,
)
from .files import write_csv
from .metrics import table2_stats
from .results import TABLE2_PROFILES, SweepResult
from .scenario import Scenario, ScenarioError, load_scenario
from .simulation.session import ENGINES, Session
from .sweeps import close_worker_session, worker_session

__all__ = [
    "ENGINES",
    "MapError",
    "MapResult",
    "MoveError",
    "WorkspaceMap",
    "WorkspaceMapError",
    "batch_size",
    "check_engine",
    "run_batch",
    "run_map",
    "run_workspace_map",
]

MAX_BATCH = 100
"""Largest number of moves in one task."""

MIN_BATCHES = 64
"""Smallest map cut into this many tasks or more (for load balancing and progress)."""

Point = tuple[float, float, float, float]
"""One move of the grid: ``(z0, z_distance, distance, v_max)`` (m, m, m, m/s)."""


class WorkspaceMapError(BatchError):
    """A workspace map could not be run: a move failed, or a worker died."""


MapError = WorkspaceMapError
"""The former name of :class:`WorkspaceMapError`."""


# ----------------------------------------------------------- the worker side

@dataclass
class BatchResult:
    """What a worker sends back for one batch of moves.

    Attributes
    ----------
    start : int
        Grid index of the first move.
    rows : list of list of dict
        The CSV rows of each move (one per profile).
    busy_time : float
        Time the worker spent on the batch (s).
    worker : str
        ``host:pid`` of the worker.
    keys : list
        For each move, the moves planned for JL and DJL (every profile when
        one of them is not run), exactly
        (:meth:`harness.results.ScenarioResult.move_key`): equal keys are the
        same move.
    """

    start: int
    rows: list[list[dict[str, Any]]]
    busy_time: float
    worker: str
    keys: list[Any] = field(default_factory=list)


def run_batch(scenario: Scenario, engine: str, start: int, points: Sequence[Point]
              ) -> BatchResult:
    """Run a batch of consecutive moves of a map (the task sent to the workers).

    Parameters
    ----------
    scenario : Scenario
        The map's scenario (with its ``[map]`` table).
    engine : {"fmu", "fast"}
        Evaluation engine.
    start : int
        Grid index of ``points[0]``.
    points : sequence of tuple of float
        The moves, ``(z0, z_distance, distance, v_max)``.

    Returns
    -------
    BatchResult

    Raises
    ------
    MoveError
        If a move fails; the message names it (grid index and values).
    """
    t0 = time.perf_counter()
    session = worker_session(engine, scenario)
    out = []
    keys = []
    compared = TABLE2_PROFILES if set(TABLE2_PROFILES) <= set(scenario.compare.profiles) else None
    for k, p in enumerate(points):
        case = scenario.map_case(*p)
        try:
            res = run_case(case, session, keep_runs=False)
        except Exception as e:  # noqa: BLE001 (reported with the move, as plain text)
            close_worker_session()
            raise MoveError(f"move {start + k} (z0 = {p[0]:g} m, z_distance = {p[1]:g} m, "
                            f"distance = {p[2]:g} m, v_max = {p[3]:g} m/s) failed: "
                            f"{type(e).__name__}: {e}") from None
        rows = SweepResult(scenario, [res]).rows()
        for r in rows:
            r["move_index"] = start + k
        out.append(rows)
        keys.append(res.move_key(compared))
    return BatchResult(start, out, time.perf_counter() - t0,
                       f"{socket.gethostname()}:{os.getpid()}", keys)


# ------------------------------------------------------------ the map side


def batch_size(n_moves: int) -> int:
    """Return the number of moves per task for a map of ``n_moves`` (and nothing else).

    At most :data:`MAX_BATCH`, and small enough that the map has at least
    :data:`MIN_BATCHES` tasks when it has that many moves.
    """
    return max(1, min(MAX_BATCH, math.ceil(n_moves / MIN_BATCHES)))


def check_engine(engine: str, scenario: Scenario | None = None) -> None:
    """Check that ``engine`` can run here (and build the package's FMU if it needs it).

    Parameters
    ----------
    engine : {"fmu", "fast"}
    scenario : Scenario, optional
        Its FMU file and FMI version are used for the ``"fmu"`` engine.

    Raises
    ------
    ValueError
        Unknown engine, or an engine that cannot start (the message says why).
    """
    if engine not in ENGINES:
        raise ValueError(f"unknown engine {engine!r}: choose from {', '.join(ENGINES)}")
    sim = scenario.simulation if scenario is not None else None
    try:
        s = Session(sim.fmu if sim else None, sim.fmi_version if sim else 2, engine=engine)
    except Exception as e:  # noqa: BLE001 (any failure to start is reported as text)
        raise ValueError(f"the {engine!r} engine cannot start: {type(e).__name__}: {e}"
                         ) from None
    s.close()


def _progress_bar(total: int, enabled: bool, desc: str) -> Any:
    """Return a tqdm bar on a terminal, else a line on stderr every 10 s (None: disabled)."""
    if not enabled:
        return None
    if not sys.stderr.isatty():
        return LineProgress(total, desc, "moves")
    return tqdm(total=total, desc=desc, unit="move", leave=False)


def run_workspace_map(scenario: Scenario | str | Path, *, engine: str = "fast",
            workers: int | None = None, scheduler: str | None = None,
            max_moves: int | None = None, progress: bool = False,
            executor: Executor | None = None, batch: int | None = None) -> WorkspaceMap:
    """Run every move of a scenario's ``[map]`` grid; results in grid order.

    Parameters
    ----------
    scenario : Scenario, str or Path
        A scenario with a ``[map]`` table: a checked
        :class:`~harness.scenario.Scenario`, a TOML file or an embedded name
        (``X``, ``Y``).
    engine : {"fast", "fmu"}
        Evaluation engine (see :class:`harness.simulation.session.Session`).
    workers : int, optional
        Local worker processes (default: every core); 1 runs in this process.
    scheduler : str, optional
        Address of a Dask scheduler (``tcp://host:8786``): run on its workers.
    max_moves : int, optional
        Run only ``max_moves`` moves, spread evenly over the whole grid
        (:meth:`~harness.scenario.Scenario.map_indices`); deterministic.
    progress : bool
        Show a tqdm progress bar (only when stderr is a terminal).
    executor : Executor, optional
        Use this executor (left open) instead of ``workers`` / ``scheduler``.
    batch : int, optional
        Moves per task (default: :func:`batch_size`); the results do not
        depend on it.

    Returns
    -------
    WorkspaceMap

    Raises
    ------
    ScenarioError
        If the scenario cannot be loaded or has no ``[map]`` table.
    ValueError
        Bad engine, ``max_moves`` or ``batch``; an engine that cannot start;
        :class:`harness.executors.ExecutorError` for bad ``workers`` or an
        unreachable scheduler.
    WorkspaceMapError
        If a move fails or a worker dies (the message names the move).
    """
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    if sc.map is None:
        raise ScenarioError(sc.source, "map", None, "the scenario has no [map] table (the "
                            "embedded X and Y have one; format: docs/map.md)")
    check_engine(engine, sc)
    indices = sc.map_indices(max_moves)
    grid = list(itertools.product(*sc.map_axes()))
    points = [grid[i] for i in indices]
    if batch is not None and (isinstance(batch, bool) or not isinstance(batch, int)
                              or batch < 1):
        raise ValueError(f"batch must be an integer >= 1, got {batch!r}")
    bs = batch or batch_size(len(points))
    if executor is not None:
        return _run_on(sc, engine, points, indices, bs, executor, executor_workers(executor),
                       describe_executor(executor, None), progress)
    with make_executor(workers, scheduler) as ex:
        return _run_on(sc, engine, points, indices, bs, ex, executor_workers(ex),
                       describe_executor(ex, scheduler), progress)


def _run_on(sc: Scenario, engine: str, points: list[Point], indices: list[int], bs: int,
            ex: Executor, n_workers: int, where: str, progress: bool) -> WorkspaceMap:
    batches, wall = run_batches(
        ex, run_batch, (sc, engine), points, bs, error=WorkspaceMapError, passthrough=MoveError,
        progress=_progress_bar(len(points), progress, f"map {sc.name}"),
        on_serial_end=close_worker_session)
    rows = [r for br in batches for r in br.rows]
    keys = [k for br in batches for k in br.keys]
    busy = sum(br.busy_time for br in batches)
    for i, move in zip(indices, rows, strict=True):
        for r in move:
            r["move_index"] = i  # the move's index in the whole grid
    _mark_duplicates(rows, keys)
    return WorkspaceMap(sc, points, rows, engine=engine, workers=n_workers, wall_time=wall,
                        busy_time=busy, batch=bs, executor=where,
                        worker_ids=sorted({br.worker for br in batches}), indices=indices)


def _mark_duplicates(move_rows: list[Any], keys: list[Any]) -> None:
    """Fill ``duplicate_of`` (the first move, in grid order, that plans the same moves)."""
    first: dict[Any, int] = {}
    for i, k in enumerate(keys):
        if k is None:
            continue
        if k in first:
            name = move_rows[first[k]][0]["scenario"]
            for r in move_rows[i]:
                r["duplicate_of"] = name
        else:
            first[k] = i


# ------------------------------------------------------------------ results

_QUANTITIES = {  # figure name: what its colours show
    "djl-vs-jl": "residual vibration of DJL compared with JL, % change (blue: DJL leaves less)",
    "djl-vs-jl-settling": "settling time of DJL compared with JL, % change (blue: DJL "
                          "settles sooner)",
}


@dataclass
class WorkspaceMap:
    """The results of a map: CSV rows per move, in grid order, and how they were computed.

    Attributes
    ----------
    scenario : Scenario
        The map's scenario.
    points : list of tuple of float
        The moves run, ``(z0, z_distance, distance, v_max)``, in grid order
        (every move of the grid, or those ``max_moves`` picked across it).
    move_rows : list of list of dict
        For each move, one CSV row per profile (the columns of ``djl-fmu
        simulate``'s sweep CSV, plus ``move_index``: its index in the grid).
    engine : str
        Evaluation engine.
    workers : int
        Tasks run at once (processes, or Dask worker threads).
    wall_time : float
        Wall-clock time from the first submission to the last result (s).
    busy_time : float
        Sum over the batches of the time a worker spent on them (s).
    batch : int
        Moves per task.
    executor : str
        Where it ran.
    worker_ids : list of str
        ``host:pid`` of the workers that ran batches.
    indices : list of int, optional
        Index of each move of ``points`` in the whole grid (``v_max`` fastest);
        default: the first ``len(points)``.
    """

    scenario: Scenario
    points: list[Point]
    move_rows: list[list[dict[str, Any]]]
    engine: str = "fast"
    workers: int = 1
    wall_time: float = 0.0
    busy_time: float = 0.0
    batch: int = 1
    executor: str = ""
    worker_ids: list[str] = field(default_factory=list)
    indices: list[int] | None = None

    # ------------------------------------------------------------ numbers

    @property
    def n_moves(self) -> int:
        """Number of moves run."""
        return len(self.points)

    @property
    def distinct(self) -> np.ndarray:
        """Boolean mask of the moves counted in statistics (not a duplicate of an earlier one).

        Two moves are duplicates when they plan exactly the same JL and DJL
        moves (every profile's when one of them is not compared), e.g. a
        v_max that neither reaches: see ``duplicate_of`` in the CSV.
        """
        return np.array([not rows[0].get("duplicate_of") for rows in self.move_rows],
                        dtype=bool)

    @property
    def profiles(self) -> tuple[str, ...]:
        """Profiles compared (the scenario's order)."""
        return tuple(self.scenario.compare.profiles)

    @property
    def per_move(self) -> float:
        """Wall-clock time per move (s): ``wall_time / n_moves``."""
        return self.wall_time / self.n_moves if self.n_moves else math.nan

    @property
    def cost_per_move(self) -> float:
        """Worker time per move (s): ``busy_time / n_moves`` (what one core spends)."""
        return self.busy_time / self.n_moves if self.n_moves else math.nan

    def rows(self) -> list[dict[str, Any]]:
        """All CSV rows: for each move in grid order, one per profile."""
        return [r for rows in self.move_rows for r in rows]

    def to_csv(self, path: str | Path) -> Path:
        """Write :meth:`rows` as CSV (atomically); return the path."""
        return write_csv(path, self.rows())

    def values(self, column: str, profile: str | None = None) -> np.ndarray:
        """One CSV column for every move (float array in grid order).

        Parameters
        ----------
        column : str
            A CSV column, e.g. ``residual_m``, ``settling_time_s``,
            ``case_djl_vs_jl_residual_pct``.
        profile : str, optional
            The profile whose row is read (default: the first one; the
            ``case_*`` columns are the same in every row of a move).

        Returns
        -------
        ndarray
            NaN where the value is empty or not a number.
        """
        profile = profile or self.profiles[0]
        out = np.full(self.n_moves, np.nan)
        for i, rows in enumerate(self.move_rows):
            for r in rows:
                if r["profile"] == profile:
                    v = r.get(column)
                    if isinstance(v, (int, float)) and not isinstance(v, bool):
                        out[i] = float(v)
                    break
        return out

    def grid(self, column: str, profile: str | None = None) -> np.ndarray:
        """One CSV column on the grid: shape ``(n_z0, n_z_distance, n_distance, n_v_max)``.

        Moves not run (``max_moves``) are NaN.
        """
        shape = tuple(len(a) for a in self.scenario.map_axes())
        arr = np.full(math.prod(shape), np.nan)
        idx = self.indices if self.indices is not None else list(range(self.n_moves))
        arr[idx] = self.values(column, profile)
        return arr.reshape(shape)

    # -------------------------------------------------------------- table

    def table(self) -> str:
        """Short text summary: moves, time, cost per move, and per-profile residuals."""
        sc = self.scenario
        axes = sc.map_axes()
        dims = " x ".join(f"{n} {len(a)}" for n, a in zip(("z0", "dz", "d", "v_max"), axes,
                                                          strict=True))
        out = [f"Map {sc.name}: {self.n_moves} of {sc.map_size} moves ({dims}), profiles "
               f"{', '.join(self.profiles)}, engine {self.engine}",
               f"  wall time {self.wall_time:.3g} s on {self.workers} worker(s) "
               f"({self.executor}; batches of {self.batch} moves): "
               f"{self.per_move * 1e3:.3g} ms per move; compute "
               f"{self.cost_per_move * 1e3:.3g} ms per move per worker",
               "",
               f"  {'profile':<8}{'residual median':>17}{'residual max':>15}"
               f"{'motion time median':>20}{'settling median':>17}{'settling max':>15}",
               f"  {'':<8}{'[mm]':>17}{'[mm]':>15}{'[s]':>20}{'[s]':>17}{'[s]':>15}"]
        for p in self.profiles:
            res = self.values("residual_m", p) * 1e3
            mt = self.values("motion_time_s", p)
            st = self.values("settling_time_s", p)
            out.append(f"  {p:<8}{_nanstat(np.nanmedian, res):>17}{_nanstat(np.nanmax, res):>15}"
                       f"{_nanstat(np.nanmedian, mt):>20}{_nanstat(np.nanmedian, st):>17}"
                       f"{_nanstat(np.nanmax, st):>15}")
        if "JL" in self.profiles and "DJL" in self.profiles:
            out.append("")
            out.append("  DJL compared with JL over the moves, % change (Table 2 statistics):")
            out.append(f"  {'':<22}{'mean':>8}{'largest':>10}{'smallest':>10}{'std':>8}"
                       f"   DJL better")
            out.append(f"  {'':<22}{'':>8}{'reduction':>10}{'reduction':>10}")
            keep = self.distinct
            for lab, col in (("residual vibration", "case_djl_vs_jl_residual_pct"),
                             ("settling time", "case_djl_vs_jl_settling_pct")):
                ch = self.values(col)[keep]
                st2 = table2_stats(ch)
                better = (f"{np.mean(ch[np.isfinite(ch)] < 0) * 100.0:.0f} % of {st2.n} moves"
                          if st2.n else "n/a")
                out.append(f"  {lab:<22}{st2.mean:>+8.1f}{st2.max:>+10.1f}{st2.min:>+10.1f}"
                           f"{st2.std:>8.1f}   {better}")
            n_dup = int(np.sum(~keep))
            out.append(f"  {int(np.sum(keep))} distinct moves counted"
                       + (f" ({n_dup} duplicates merged: the same JL and DJL moves as an "
                          f"earlier move of the grid, see duplicate_of in the CSV)"
                          if n_dup else ""))
        return "\n".join(out)

    # -------------------------------------------------------------- plots

    def figures(self) -> dict[str, Any]:
        """All the heat maps, by short name (used in the file names).

        * ``djl-vs-jl``: residual of DJL against JL, % change;
        * ``<P>-residual``: residual of profile P as % of AL (absolute in mm
          without AL);
        * ``djl-vs-jl-settling``: settling time of DJL against JL, % change.

        Each figure has one panel per (z0, v_max) slice (rows: z0, columns:
        v_max; at most 6 of each, evenly chosen), the move length on x and
        the Z travel on y.

        Returns
        -------
        dict of str to matplotlib.figure.Figure
        """
        out: dict[str, Any] = {}
        profs = self.profiles
        both = "JL" in profs and "DJL" in profs
        if both:
            out["djl-vs-jl"] = self._heatmaps(self.grid("case_djl_vs_jl_residual_pct"),
                                              _QUANTITIES["djl-vs-jl"], "% change", True)
        for p in profs:
            if p == "AL" and "AL" in profs and len(profs) > 1:
                continue
            if "AL" in profs and p != "AL":
                out[f"{p}-residual"] = self._heatmaps(
                    self.grid("residual_pct_of_AL", p),
                    f"residual vibration of {p} as % of AL", "% of AL", False)
            else:
                out[f"{p}-residual"] = self._heatmaps(
                    self.grid("residual_m", p) * 1e3, f"residual vibration of {p} [mm]",
                    "mm", False)
        if both:
            out["djl-vs-jl-settling"] = self._heatmaps(
                self.grid("case_djl_vs_jl_settling_pct"), _QUANTITIES["djl-vs-jl-settling"],
                "% change", True)
        return out

    def plot(self) -> Any:
        """Return the main heat map (DJL against JL when both ran); see :meth:`figures`."""
        figs = self.figures()
        first = next(iter(figs))
        for k, f in figs.items():
            if k != first:
                import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

                plt.close(f)
        return figs[first]

    def _heatmaps(self, arr: np.ndarray, what: str, unit: str, diverging: bool) -> Any:
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import
        from matplotlib import colors  # deferred: matplotlib is heavy to import

        z0s, dzs, ds, vs = (np.asarray(a, dtype=float) for a in self.scenario.map_axes())
        # slices with data only (a small map may leave whole z0 or v_max slices empty)
        has = np.isfinite(arr)
        z_ok = [i for i in range(len(z0s)) if has[i].any()] or list(range(len(z0s)))
        v_ok = [j for j in range(len(vs)) if has[..., j].any()] or list(range(len(vs)))
        rows_i = [z_ok[k] for k in _pick(len(z_ok), 6)]
        cols_i = [v_ok[k] for k in _pick(len(v_ok), 6)]
        od, odz = np.argsort(ds), np.argsort(dzs)
        fin = arr[np.isfinite(arr)]
        if diverging:
            lo = float(np.percentile(fin, 2)) if fin.size else -1.0
            hi = float(np.percentile(fin, 98)) if fin.size else 1.0
            norm: Any = colors.TwoSlopeNorm(vcenter=0.0, vmin=min(lo, -1.0), vmax=max(hi, 1.0))
            cmap = "RdBu_r"
        else:
            pos = fin[fin > 0]
            if pos.size and float(pos.max()) > 10.0 * float(pos.min()):
                norm = colors.LogNorm(vmin=float(np.percentile(pos, 1)),
                                      vmax=float(np.percentile(pos, 99)))
            else:
                norm = colors.Normalize(vmin=float(fin.min()) if fin.size else 0.0,
                                        vmax=float(fin.max()) if fin.size else 1.0)
            cmap = "viridis"
        nr, nc = len(rows_i), len(cols_i)
        W, H = 3.3 * nc + 1.8, 2.7 * nr + 1.7
        fig, axes = plt.subplots(nr, nc, figsize=(W, H), squeeze=False, sharex=True,
                                 sharey=True)
        xe, ye = _edges(ds[od]), _edges(dzs[odz])
        mesh = None
        for a, i in enumerate(rows_i):
            for b, j in enumerate(cols_i):
                ax = axes[a][b]
                ax.set_facecolor("0.85")
                c = arr[i][:, :, j][np.ix_(odz, od)]
                mesh = ax.pcolormesh(xe, ye, np.ma.masked_invalid(c), norm=norm, cmap=cmap,
                                     shading="flat")
                ax.set_title(f"z0 = {z0s[i]:g} m, v_max = {vs[j]:g} m/s", fontsize="small")
                if a == nr - 1:
                    ax.set_xlabel("move length d [m]")
                if b == 0:
                    ax.set_ylabel("Z travel dz [m]")
        shown = ""
        if nr < len(z0s) or nc < len(vs):
            shown = (f"; {nr} of {len(z0s)} z0 values and {nc} of {len(vs)} v_max values "
                     f"shown")
        med = float(np.median(fin)) if fin.size else math.nan
        fig.suptitle(f"Map {self.scenario.name} ({self.n_moves} moves{shown}): {what}\n"
                     f"median {med:.3g} {unit}; grey: not run, or not defined",
                     fontsize="medium")
        # margins in inches, whatever the number of panels
        bottom, top = 0.6 / H, 1.0 - 1.05 / H
        fig.subplots_adjust(left=0.8 / W, right=1.0 - 1.3 / W, bottom=bottom, top=top,
                            hspace=0.45, wspace=0.12)
        cax = fig.add_axes((1.0 - 1.05 / W, bottom, 0.18 / W, top - bottom))
        fig.colorbar(mesh, cax=cax, label=unit, extend="both" if diverging else "neither")
        return fig


def _nanstat(fn: Any, a: np.ndarray) -> str:
    a = a[np.isfinite(a)]
    return f"{fn(a):.4g}" if a.size else "n/a"


def _pick(n: int, most: int) -> list[int]:
    """Return the indices of at most ``most`` evenly spread slices out of ``n``."""
    if n <= most:
        return list(range(n))
    return sorted({int(round(x)) for x in np.linspace(0, n - 1, most)})


def _edges(v: np.ndarray) -> np.ndarray:
    """Cell edges around sorted cell centres (half-way between them)."""
    if v.size == 1:
        w = abs(float(v[0])) * 0.2 or 0.1
        return np.array([v[0] - w, v[0] + w])
    mid = 0.5 * (v[1:] + v[:-1])
    return np.concatenate(([v[0] - (mid[0] - v[0])], mid, [v[-1] + (v[-1] - mid[-1])]))


run_map = run_workspace_map
"""The former name of :func:`run_workspace_map`."""

MapResult = WorkspaceMap
"""The former name of :class:`WorkspaceMap`."""
