"""What the commands (``simulate``, ``compare``, ``map``, ``tune``...) share.

They check every input before running anything, refuse a non-finite result, and
write their outputs only once every run has succeeded, as one set that replaces
the previous one whole (:func:`write_outputs`, :mod:`harness.commands._outputs`).
"""

from __future__ import annotations

import argparse
import functools
import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from ._outputs import OutputSet, Terminated, sigterm_raises


class CommandError(Exception):
    """A command stops: ``status`` is its exit status, the message says why."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


def safe_stem(name: str) -> str:
    """File-name stem for a scenario name."""
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", name).strip("_") or "scenario"


def load_scenarios(names: Sequence[str], fmu: Path | None, fmi_version: int | None,
                   out: Path) -> tuple[list[Any], list[str]]:
    """Load and check the scenarios and the output folder; return them and their stems.

    Raises
    ------
    CommandError
        With status 2, on a bad scenario, two scenarios of the same name, or an
        output path that is not a folder or cannot be written.
    """
    from ..scenario import ScenarioError, load_scenario

    try:
        scenarios = [load_scenario(n) for n in names]
        if fmu is not None or fmi_version is not None:
            scenarios = [s.with_fmu(fmu, fmi_version) for s in scenarios]
    except ScenarioError as e:
        raise CommandError(2, str(e)) from None
    check_stems(scenarios)
    check_out_dir(out)
    return scenarios, [safe_stem(s.name) for s in scenarios]


def _nearest_existing(path: Path) -> Path:
    base = path
    while not base.exists() and base.parent != base:
        base = base.parent
    return base


def _writable_dir(d: Path) -> bool:
    """Return True if a file can be created in the existing folder ``d`` (tried, removed)."""
    import os
    import tempfile

    if not os.access(d, os.W_OK | os.X_OK):
        return False
    try:
        fd, name = tempfile.mkstemp(dir=d, prefix=".djl-fmu-probe-")
    except OSError:
        return False
    os.close(fd)
    Path(name).unlink(missing_ok=True)
    return True


def check_out_dir(out: Path, option: str = "--out") -> None:
    """Refuse an output folder that cannot be created or written, before anything runs.

    Raises
    ------
    CommandError
        Status 2: ``out`` is a file, the nearest existing folder above it is a
        file, or it is not writable.
    """
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise CommandError(2, f"{option} {out} exists and is not a directory")
    base = _nearest_existing(out)
    if not base.is_dir():
        raise CommandError(2, f"{option} {out}: {base} is a file, not a directory")
    if not _writable_dir(base):
        raise CommandError(2, f"{option} {out}: {base} is not writable")


def check_out_file(path: Path, option: str = "-o") -> None:
    """Refuse an output file that cannot be written, before anything runs.

    Raises
    ------
    CommandError
        Status 2: ``path`` is an existing folder (or not a regular file), a
        folder above it is a file, or the folder it goes in is not writable.
    """
    path = Path(path)
    if path.is_dir():
        raise CommandError(2, f"{option} {path} is an existing directory, not a file")
    if path.exists() and not path.is_file():
        raise CommandError(2, f"{option} {path} exists and is not a regular file")
    import os

    if path.exists() and not os.access(path, os.W_OK):
        raise CommandError(2, f"{option} {path}: the file is not writable")
    base = _nearest_existing(path.parent)
    if not base.is_dir():
        raise CommandError(2, f"{option} {path}: {base} is a file, not a directory")
    if not _writable_dir(base):
        raise CommandError(2, f"{option} {path}: {base} is not writable")


FINITE_METRICS = ("residual_m", "free_amplitude_m", "residual_peak_m", "motion_time_s",
                  "residual_worst_map10_m")
"""Result columns that must be finite numbers: a NaN or an infinity there is a failure
(exit 1).  An infinite settling time is a documented outcome (an undamped mode never
settles: printed "never"), and so is a NaN rise time (not reached within the record)."""


def check_finite(name: str, result: Any) -> None:
    """Refuse a result with a NaN or an infinity in :data:`FINITE_METRICS`.

    (An infinite or NaN settling or rise time is a documented outcome: "never", or "not
    within the window".)

    Raises
    ------
    CommandError
        Status 1, naming the scenario, the profile and the column.
    """
    import math

    rows = result.rows() if hasattr(result, "rows") else []
    for row in rows:
        for k, v in row.items():
            if isinstance(v, bool) or not isinstance(v, (int, float)):
                continue
            if k in FINITE_METRICS and not math.isfinite(v):
                where = ", ".join(str(row[c]) for c in ("scenario", "profile") if c in row)
                raise CommandError(1, f"simulation failed ({name}): {k} = {v} for {where or name}"
                                      f": a non-finite result (nothing written)")


def check_parallel_options(workers: int | None, scheduler: str | None,
                           max_moves: int | None) -> None:
    """Refuse bad ``--workers``, ``--max-moves``, or both ``--workers`` and ``--scheduler``.

    Raises
    ------
    CommandError
        With status 2.
    """
    if workers is not None and workers < 1:
        raise CommandError(2, f"--workers must be >= 1, got {workers}")
    if max_moves is not None and max_moves < 1:
        raise CommandError(2, f"--max-moves must be >= 1, got {max_moves}")
    if workers is not None and scheduler is not None:
        raise CommandError(2, "give --workers or --scheduler, not both (on a Dask cluster "
                              "the cluster's workers run the moves)")


def check_stems(scenarios: Sequence[Any]) -> None:
    """Refuse two scenarios whose outputs would have the same file names."""
    stems = [safe_stem(s.name) for s in scenarios]
    if len(set(stems)) != len(stems):
        raise CommandError(2, "two scenarios have the same name: "
                           + ", ".join(s.name for s in scenarios))


def write_outputs(out: Path, write: Callable[[OutputSet], None], summary: str) -> list[Path]:
    """Write a command's output set in ``out``: ``write``'s files, then ``summary.txt``.

    ``write`` writes each file at ``o.path(name)`` of the :class:`OutputSet` it
    is given (a staging folder in ``out``); once it returns, the whole set
    replaces the previous one in a single pass (:mod:`harness.commands._outputs`):
    an error or an interruption at any point leaves the previous files as they
    were, and no temporary folder.

    Returns
    -------
    list of Path
        The files written, in the order ``write`` named them, ``summary.txt`` last.

    Raises
    ------
    CommandError
        Status 1 if a file cannot be written (nothing written); a
        :class:`CommandError` raised by ``write`` goes through as it is.
    """
    try:
        with OutputSet(out) as o:
            write(o)
            o.path("summary.txt").write_text(summary + "\n", encoding="utf-8")
            return o.commit()
    except CommandError:
        raise
    except (OSError, RuntimeError) as e:
        raise CommandError(1, f"cannot write the outputs in {out}: {e}") from None


def interruptible(run: Callable[[argparse.Namespace], int]
                  ) -> Callable[[argparse.Namespace], int]:
    """Wrap a command's ``run``: SIGTERM stops it like Ctrl-C (exit 143), clean-ups run.

    By default SIGTERM ends Python at once, skipping every ``finally`` (staging
    folders would stay behind); here it raises inside the command.
    """

    @functools.wraps(run)
    def wrapper(args: argparse.Namespace) -> int:
        with sigterm_raises():
            try:
                return run(args)
            except Terminated:
                raise CommandError(143, "terminated (SIGTERM)") from None

    return wrapper


def check_rows_finite(rows: Sequence[Mapping[str, Any]], what: str, *,
                      finite: Sequence[str], no_inf: Sequence[str] = (),
                      keys: Sequence[str] = ()) -> None:
    """Refuse a NaN or an infinity in a ``finite`` column, an infinity in a ``no_inf`` one.

    ``no_inf`` columns may be NaN (a documented "n/a": a percentage of a zero
    reference, a quantity not computed), never infinite.

    Parameters
    ----------
    rows : sequence of mapping
        The table, e.g. the rows of a CSV about to be written.
    what : str
        Start of the message, e.g. ``"map failed (X)"``.
    finite, no_inf : sequence of str
        Column names (absent columns are skipped).
    keys : sequence of str
        Columns that identify a row in the message (e.g. ``move_index``, ``profile``).

    Raises
    ------
    CommandError
        Status 1, naming the column, the row (1-based) and its keys.
    """
    import math

    for i, row in enumerate(rows):
        for cols, bad in ((finite, lambda v: not math.isfinite(v)),
                          (no_inf, math.isinf)):
            for c in cols:
                v = row.get(c)
                if isinstance(v, bool) or not isinstance(v, (int, float)) or not bad(v):
                    continue
                where = ", ".join(f"{k} = {row[k]}" for k in keys if k in row)
                raise CommandError(1, f"{what}: {c} = {v} in row {i + 1}"
                                      + (f" ({where})" if where else "")
                                      + ": a non-finite result (nothing written)")


def report_written(out: Path, written: Sequence[Path], summary: str, quiet: bool) -> None:
    """Print the tables (unless quiet) and the list of files written."""
    if not quiet:
        print(summary)
        print()
    print(f"wrote {len(written)} files in {out}/: " + ", ".join(p.name for p in written))


_TASKS: list[Callable[[], Any]] = []


def _call(i: int) -> tuple[bool, Any]:
    try:
        return True, _TASKS[i]()
    except Exception as e:  # noqa: BLE001 - sent back as text: exceptions may not pickle
        return False, f"{type(e).__name__}: {e}" if str(e) else type(e).__name__


def run_forked(tasks: Sequence[Callable[[], Any]], workers: int | None = None
               ) -> list[tuple[bool, Any]]:
    """Run independent tasks on all cores (forked workers); return (ok, result or message).

    The tasks are closures inherited by the forked workers (nothing but the
    results is pickled); an exception comes back as ``(False, "Type: message")``.
    Where ``fork`` is not available, or for a single task, they run here.
    """
    import multiprocessing
    import os

    tasks = list(tasks)
    n = min(len(tasks), workers or os.cpu_count() or 1)
    if n <= 1 or "fork" not in multiprocessing.get_all_start_methods():
        _TASKS[:] = tasks
        try:
            return [_call(i) for i in range(len(tasks))]
        finally:
            _TASKS.clear()
    from concurrent.futures import ProcessPoolExecutor

    _TASKS[:] = tasks
    try:
        with ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("fork")) as pool:
            return list(pool.map(_call, range(len(tasks))))
    finally:
        _TASKS.clear()


TUNING_HELP = (
    "add profiles tuned by other methods, comma-separated: DJL 'optimal' (least residual on "
    "the time-varying model, never worse than JL), 'robust' (least worst case over the map "
    "error), 'paper' (the paper's rule, what DJL uses by default); 'jl=optimal' for JL. "
    "E.g. --tuning optimal,robust adds the profiles DJL-optimal and DJL-robust")


def parse_tuning(text: str | None) -> list[str]:
    """Profile variants named by ``--tuning`` (e.g. ``"optimal,robust"`` → DJL-optimal, DJL-robust).

    Raises
    ------
    CommandError
        With status 2 for an unknown method.
    """
    from ..optimize import DJL_METHODS, JL_METHODS

    if not text:
        return []
    out: list[str] = []
    for item in (x.strip() for x in text.split(",")):
        if not item:
            continue
        prof, _, method = item.partition("=")
        if not method:
            prof, method = "djl", prof
        prof = prof.strip().upper()
        method = method.strip().lower()
        allowed = {"DJL": DJL_METHODS, "JL": JL_METHODS}.get(prof)
        if allowed is None or method not in allowed:
            raise CommandError(2, f"--tuning {text!r}: {item!r} is not a tuning method (DJL: "
                                  f"{', '.join(DJL_METHODS)}; JL: jl={', jl='.join(JL_METHODS)})")
        if (prof, method) in (("JL", "end"),):
            continue  # JL's own method
        name = f"{prof}-{method}"
        if name not in out:
            out.append(name)
    return out


def apply_tuning(scenarios: Sequence[Any], variants: Sequence[str],
                 map_error: float | None) -> list[Any]:
    """Add the tuned profile variants and the robust method's map error to every scenario."""
    import dataclasses

    if map_error is not None and not (0.0 <= map_error < 1.0):
        raise CommandError(2, f"--map-error {map_error!r}: must be in [0, 1) (0.1 = +/-10 %)")
    out = []
    for sc in scenarios:
        cmp = sc.compare
        profiles = tuple(cmp.profiles) + tuple(v for v in variants if v not in cmp.profiles)
        if any(v.startswith("DJL") or v.startswith("JL") for v in variants) and \
                "JL" not in profiles:
            profiles = ("JL", *profiles)  # the tuned variants are compared with JL
        cmp = dataclasses.replace(cmp, profiles=profiles)
        if map_error is not None:
            cmp = dataclasses.replace(cmp, map_error=float(map_error))
        out.append(dataclasses.replace(sc, compare=cmp))
    return out
