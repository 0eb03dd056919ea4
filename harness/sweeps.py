"""A scenario from a file to its results: one move (Table 1) or a sweep (Table 2).

:func:`run_scenario` is the one-call entry point of ``djl-fmu simulate``: it
tunes the jerk times from the mode map (:mod:`harness.tuning`), synchronises
the Z move with the excited axis, co-simulates every profile
(:mod:`harness.simulation`) and measures it (:mod:`harness.evaluation`); a
sweep's cases run in this process or on a process pool / Dask cluster
(:mod:`harness.executors`), with the same results.  See
:mod:`harness.results` for the tables and plots.

Examples
--------
>>> from harness.sweeps import run_scenario
>>> result = run_scenario("X")                      # doctest: +SKIP
>>> print(result.table())                           # doctest: +SKIP
"""

from __future__ import annotations

import math
import sys
import threading
from collections.abc import Sequence
from concurrent.futures import as_completed
from pathlib import Path
from typing import Any

from tqdm import tqdm

from .evaluation import run_case
from .executors import executor_workers, make_executor
from .results import ScenarioResult, SweepResult
from .scenario import Scenario, load_scenario
from .simulation.session import Session

__all__ = ["close_worker_session", "run_scenario", "run_sweep_batch", "simulate",
           "worker_session"]


def run_scenario(scenario: Scenario | str | Path, *, fmu: str | Path | None = None,
                 fmi_version: int | None = None, progress: bool = False,
                 session: Session | None = None, engine: str | None = None,
                 robustness: bool | str | None = "auto", workers: int | None = 1,
                 scheduler: str | None = None, recommend: bool | None = None
                 ) -> ScenarioResult | SweepResult:
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
        Evaluation engine (see :class:`~harness.simulation.session.Session`);
        default: ``"fmu"`` for a single move (the FMU drives the plant),
        ``"fast"`` for a sweep.
    robustness : bool, {"worst", "curves"} or "auto"
        Map-error robustness (:func:`harness.evaluation.run_case`); ``"auto"``:
        the curves for a single move, the worst case for a sweep.
    workers : int, optional
        A sweep's cases on this many local processes (default 1: this process;
        None: every core).
    scheduler : str, optional
        Run a sweep's cases on a Dask cluster (its scheduler's address).
    recommend : bool, optional
        Add the ``recommended`` profile (:mod:`harness.recommend`); default: for a
        single move (a sweep's cases take about half a second each to tune).

    Returns
    -------
    ScenarioResult or SweepResult
        ``.table()`` prints like Table 1 (Table 2 for a sweep), ``.to_csv(path)``,
        ``.plot()`` returns the figure.
    """
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
    try:
        rsession = _robustness_session(sc, session, robustness)
        if not sc.is_sweep:
            return run_case(sc, session, robustness=robustness, robustness_session=rsession,
                            recommend=True if recommend is None else recommend)
        results = [run_case(case, session, keep_runs=False, robustness=robustness,
                            robustness_session=rsession, recommend=bool(recommend))
                   for case in _progress(sc.cases(), progress, desc=sc.name)]
        return SweepResult(sc, results)
    finally:
        if own:
            session.close()


simulate = run_scenario
"""Alias of :func:`run_scenario`."""


def _robustness_session(sc: Scenario, session: Session, robustness: Any) -> Session:
    """Return the session of the many map-error runs: the fast engine (same results).

    Unless the scenario or the session names its own FMU file: its generator
    may differ from the package's, so it runs them itself.
    """
    own_fmu = session.fmu is not None or sc.simulation.fmu is not None
    return session if (not robustness or own_fmu) else session.fast()


def _run_sweep_parallel(sc: Scenario, engine: str, robustness: Any, workers: int | None,
                        scheduler: str | None, progress: bool) -> SweepResult:
    """Run a sweep's cases on a process pool or a Dask cluster (same results as serially)."""
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


def _progress(items: Any, enabled: bool, desc: str, total: int | None = None) -> Any:
    if not enabled or not sys.stderr.isatty():
        return items
    return tqdm(items, desc=desc, unit="case" if total is None else "batch", leave=False,
                total=total)


# ----------------------------------------------------------- the worker side

_LOCAL = threading.local()


def worker_session(engine: str, sc: Scenario) -> Session:
    """Return the session of this worker (process, thread) for ``sc``'s FMU, made once.

    A worker keeps its session between the batches it runs (creating one
    unpacks and loads the FMU), and replaces it when a batch needs another
    engine or FMU.
    """
    sim = sc.simulation
    key = (engine, str(sim.fmu) if sim.fmu is not None else None, sim.fmi_version)
    cur = getattr(_LOCAL, "session", None)
    if cur is not None and getattr(_LOCAL, "key", None) == key:
        return cur
    close_worker_session()
    _LOCAL.session = Session(sim.fmu, sim.fmi_version, engine=engine)
    _LOCAL.key = key
    return _LOCAL.session


def close_worker_session() -> None:
    """Close the session this process and thread keep between batches, if any."""
    cur = getattr(_LOCAL, "session", None)
    _LOCAL.session = _LOCAL.key = None
    if cur is not None:
        try:
            cur.close()
        except Exception:  # noqa: BLE001 (an instance that already failed)
            pass


def run_sweep_batch(scenario: Scenario, engine: str, robustness: Any,
                    indices: Sequence[int]) -> list[ScenarioResult]:
    """Run some cases of a sweep (a task of :func:`run_scenario` on workers).

    Parameters
    ----------
    scenario : Scenario
        The sweep scenario.
    engine : {"fmu", "fast"}
        Evaluation engine of the runs.
    robustness : bool or str
        As :func:`harness.evaluation.run_case` (map-error runs on the fast engine).
    indices : sequence of int
        Which cases of ``scenario.cases()``.

    Returns
    -------
    list of ScenarioResult
        In the order of ``indices``, time series dropped.
    """
    session = worker_session(engine, scenario)
    rs = _robustness_session(scenario, session, robustness)
    cases = scenario.cases()
    return [run_case(cases[i], session, keep_runs=False, robustness=robustness,
                     robustness_session=rs) for i in indices]
