"""What the commands (``simulate``, ``compare``, ``map``, ``tune``...) share.

Their options, spelt and explained once (``add_*_option``: the scenario, the
FMU, the engine, ``--tuning``, the parallel options, ``-o/--out``); every
command checks every input before running anything, refuses a non-finite
result, reports a failure by raising :class:`~harness.errors.CommandError`,
and writes its outputs only once every run has succeeded, as one set that
replaces the previous one whole (:func:`write_outputs`, :mod:`harness.files`).
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import math
import multiprocessing
import os
import re
import sys
import tempfile
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path
from typing import Any

from ..errors import CommandError
from ..executors import ExecutorError, require_distributed
from ..files import OutputSet, Terminated, sigterm_raises
from ..scenario import ScenarioError, load_scenario
from ..tuning_options import DJL_METHODS, JL_METHODS, variants_of
from ..tuning_options import parse_tuning as parse_tuning_pairs
from ..uncertainty import (
    DeprecatedAliasWarning,
    check_map_error,
    parse_uncertainty,
    resolve_alias,
    uncertainty_items,
)

__all__ = ["CommandError", "add_engine_option", "add_fmu_options", "add_map_error_option",
           "add_out_option", "add_parallel_options", "add_quiet_option", "add_tuning_option",
           "check_map_error_option", "load_scenarios", "note", "parse_tuning",
           "uncertainty_option", "write_outputs"]

OUT_ROOT = Path("djl-fmu-out")
"""Where the commands write by default: ``./djl-fmu-out/<command>``."""


# ------------------------------------------------------------------ options


def add_out_option(p: argparse.ArgumentParser, command: str, *, kind: str = "dir",
                   default: Path | None = None, required: bool = False) -> None:
    """Add the one output option of every command: ``-o/--out``.

    Parameters
    ----------
    p : ArgumentParser
        The command's parser.
    command : str
        Its name (the default folder is ``./djl-fmu-out/<command>``).
    kind : {"dir", "file"}
        A folder of outputs, or one file (``build``'s FMU, ``report``'s HTML).
    default : Path, optional
        Another default.
    required : bool
        No default: the user names it.

    Notes
    -----
    ``--output`` is accepted as another spelling (the earlier one of ``build``
    and ``report``), and not shown.
    """
    dflt = None if required else (default if default is not None else OUT_ROOT / command)
    meta = "DIR" if kind == "dir" else "PATH"
    what = "output folder" if kind == "dir" else "the file to write"
    help_ = what if required else f"{what} (default: ./{dflt})"
    p.add_argument("-o", "--out", "--output", dest="out", type=Path, default=dflt,
                   required=required, metavar=meta, help=help_)


def add_scenarios_argument(p: argparse.ArgumentParser, default: str) -> None:
    """Add the scenarios of a command: TOML files or embedded names, ``default`` when none."""
    p.add_argument("scenarios", nargs="*", metavar="SCENARIO",
                   help=f"TOML scenario file or embedded scenario name (default: {default}; "
                        "'djl-fmu simulate --list' lists the embedded ones; format: "
                        "docs/harness.md)")


def add_fmu_options(p: argparse.ArgumentParser, what: str = "with the same variables") -> None:
    """``--fmi-version`` and ``--fmu``: which generator FMU the command runs."""
    p.add_argument("--fmi-version", type=int, choices=(2, 3), default=None,
                   help="use the package's FMI 2.0 or 3.0 FMU (default: the scenario's, "
                        "which defaults to 2)")
    p.add_argument("--fmu", type=Path, default=None, metavar="PATH",
                   help=f"a generator FMU file {what} (overrides the scenario's)")


def add_engine_option(p: argparse.ArgumentParser, default: str | None,
                      default_text: str) -> None:
    """``--engine {fmu,fast}``: the generator FMUs through fmpy, or the compiled engine."""
    p.add_argument("--engine", choices=("fmu", "fast"), default=default,
                   help="fmu: the generator FMUs stepped through fmpy (the reference); fast: "
                        "the same generator core and plant compiled, called once per move "
                        f"(default: {default_text})")


TUNING_GRAMMAR = ("comma-separated METHOD, djl=METHOD or jl=METHOD; DJL methods: "
                  + ", ".join(DJL_METHODS) + "; JL methods: " + ", ".join(JL_METHODS)
                  + " (a bare method is DJL's, 'end' JL's)")
"""The one grammar of ``--tuning`` (:func:`harness.tuning_options.parse_tuning`)."""


def add_tuning_option(p: argparse.ArgumentParser, use: str) -> None:
    """``--tuning LIST``: one grammar; ``use`` says what the command does with the methods.

    Parameters
    ----------
    use : {"add", "pick"}
        ``add``: each method adds a profile tuned by it (simulate, map);
        ``pick``: the methods of the table's DJL and JL columns (tune).
    """
    if use == "add":
        text = ("add profiles tuned by these methods: " + TUNING_GRAMMAR + ". DJL 'optimal': "
                "least residual on the time-varying model, never worse than JL; 'robust': "
                "least worst case over the map error; 'paper': the paper's rule, what DJL uses "
                "by default. E.g. --tuning optimal,robust adds the profiles DJL-optimal and "
                "DJL-robust")
    else:
        text = ("the methods of the table, at most one per profile: " + TUNING_GRAMMAR
                + " (default: DJL robust, JL end)")
    p.add_argument("--tuning", default=None, metavar="LIST", help=text)


def add_map_error_option(p: argparse.ArgumentParser, what: str) -> None:
    """``--map-error E``: deprecated, read as ``--uncertainty map_scale=E``.

    :func:`uncertainty_option` reads it into ``--uncertainty`` (and says so on stderr).
    """
    p.add_argument("--map-error", type=float, default=None, metavar="E",
                   help=f"deprecated: the same as --uncertainty map_scale=E ({what})")


def add_uncertainty_option(p: argparse.ArgumentParser) -> None:
    """Add ``--uncertainty``: how far the real mode map may be off (``[uncertainty]``)."""
    p.add_argument("--uncertainty", default=None, metavar="SPEC",
                   help="what the robust tunings and the worst cases cover: comma-separated "
                        "map_scale=E (the whole map off by +/-E, default 0.1), map_slope=S "
                        "(its slope off by +/-S), z_shift=M (shifted +/-M metres in z), "
                        "damping=LO:HI (damping ratios x LO..HI), or 'none'; keys not given "
                        "keep the scenario's [uncertainty] (docs/harness.md)")


def note(text: str) -> None:
    """Print a note for the user on stderr, one line: ``djl-fmu: note: <text>``.

    The deprecated aliases of the uncertainty (``--map-error``, a scenario's
    ``[compare] map_error`` or ``damping``) are reported this way, even with ``-q``.
    """
    print(f"djl-fmu: note: {text}", file=sys.stderr, flush=True)


def uncertainty_option(text: str | None, map_error: float | None) -> str | None:
    """Return ``--uncertainty`` with the deprecated ``--map-error E`` read into it, once.

    ``--map-error E`` is ``--uncertainty map_scale=E``: given alone, it becomes that (and
    a note says so); given with an ``--uncertainty`` that sets another map scale (``none``
    sets 0), the two are refused.

    Parameters
    ----------
    text : str, optional
        The ``--uncertainty`` value.
    map_error : float, optional
        The ``--map-error`` value.

    Returns
    -------
    str or None
        The ``--uncertainty`` value to apply (:func:`apply_uncertainty`); None: neither.

    Raises
    ------
    CommandError
        Status 2: ``--map-error`` outside [0, 1), a malformed ``--uncertainty``, or both
        options with different map scales (the message names both values).
    """
    e = check_map_error_option(map_error)
    if e is None:
        return text
    try:
        given = uncertainty_items(text).get("map_scale")
    except ValueError as err:
        raise CommandError(2, f"--uncertainty {text!r}: {err}") from None
    try:
        resolve_alias(("--uncertainty map_scale", given), ("--map-error", e))
    except ValueError as err:
        raise CommandError(2, f"{err} (--map-error E is the same as --uncertainty "
                              f"map_scale=E)") from None
    note(f"--map-error is deprecated: write --uncertainty map_scale={e!r} instead (read as "
         f"that)")
    return f"{text},map_scale={e!r}" if text else f"map_scale={e!r}"


def apply_uncertainty(scenarios: Sequence[Any], text: str | None) -> list[Any]:
    """Set ``--uncertainty`` on every scenario (None: unchanged).

    The text is :func:`uncertainty_option`'s (``--map-error`` already read into it).

    Raises
    ------
    CommandError
        With status 2 for a malformed or out-of-range value.
    """
    if text is None:
        return list(scenarios)
    try:
        return [dataclasses.replace(sc, uncertainty=parse_uncertainty(text, sc.uncertainty))
                for sc in scenarios]
    except ValueError as e:
        raise CommandError(2, f"--uncertainty {text!r}: {e}") from None


def add_parallel_options(p: argparse.ArgumentParser, what: str = "moves",
                         max_moves: str | None = "run only the first N moves of the grid"
                         ) -> None:
    """``--workers``, ``--scheduler`` (and ``--max-moves``): where and how much runs."""
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help=f"run the {what} on N local processes (default: one per core; 1 runs "
                        "in this process)")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="run on a Dask cluster: the scheduler's address, e.g. "
                        "tcp://10.0.0.5:8786 (needs the [cluster] extra: pip install "
                        "'djl-fmu[cluster]')")
    if max_moves is not None:
        p.add_argument("--max-moves", type=int, default=None, metavar="N", help=max_moves)


def add_quiet_option(p: argparse.ArgumentParser, plots: str | None = "the PNG figures") -> None:
    """``-q/--quiet`` (and ``--no-plot`` when the command draws figures)."""
    if plots is not None:
        p.add_argument("--no-plot", action="store_true", help=f"do not write {plots}")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress lines (on stderr), do not print the tables")


def progress_line(quiet: bool, text: str) -> None:
    """Print one progress line on stderr at once, unless ``quiet``.

    Every command reports its progress there (a line per scenario or claim as it
    finishes), so that its tables on stdout can be redirected alone; ``-q`` silences it.
    """
    if not quiet:
        print(text, file=sys.stderr, flush=True)


def elapsed_text(seconds: float) -> str:
    """``12.3 s`` or ``4 min 05 s``."""
    if seconds < 60:
        return f"{seconds:.1f} s"
    m, s = divmod(int(round(seconds)), 60)
    return f"{m} min {s:02d} s"


def parse_tuning(text: str | None) -> list[str]:
    """Profile variants that ``--tuning`` adds (``"optimal,robust"`` → DJL-optimal, DJL-robust).

    Raises
    ------
    CommandError
        With status 2 for an unknown method.
    """
    try:
        return variants_of(parse_tuning_pairs(text))
    except ValueError as e:
        raise CommandError(2, f"--tuning {text!r}: {e}") from None


def check_map_error_option(map_error: float | None) -> float | None:
    """Check ``--map-error`` (None: not given).

    Raises
    ------
    CommandError
        With status 2 when it is not in [0, 1).
    """
    if map_error is None:
        return None
    try:
        return check_map_error(map_error, "--map-error")
    except ValueError as e:
        raise CommandError(2, f"{e} (0.1 = +/-10 %)") from None


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
    try:
        with warnings.catch_warnings(record=True) as noted:
            warnings.simplefilter("always", DeprecatedAliasWarning)
            scenarios = [load_scenario(n) for n in names]
        if fmu is not None or fmi_version is not None:
            scenarios = [s.with_fmu(fmu, fmi_version) for s in scenarios]
    except ScenarioError as e:
        raise CommandError(2, str(e)) from None
    for w in noted:  # a deprecated alias read as its key: one line each, on stderr
        if issubclass(w.category, DeprecatedAliasWarning):
            note(str(w.message))
        else:
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
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


def check_out_file(path: Path, option: str = "--out") -> None:
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

    ``--scheduler`` without dask.distributed (the optional extra ``[cluster]``) is refused
    too, the message saying how to install it.

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
    if scheduler is not None:  # dask.distributed is the optional extra [cluster]
        try:
            require_distributed()
        except ExecutorError as e:
            raise CommandError(2, f"--scheduler {scheduler}: {e}") from None


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
    replaces the previous one in a single pass (:mod:`harness.files`):
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


def _call(i: int) -> tuple[bool, Any, float]:
    t0 = time.perf_counter()
    try:
        return True, _TASKS[i](), time.perf_counter() - t0
    except Exception as e:  # noqa: BLE001 - sent back as text: exceptions may not pickle
        return (False, f"{type(e).__name__}: {e}" if str(e) else type(e).__name__,
                time.perf_counter() - t0)


def run_forked(tasks: Sequence[Callable[[], Any]], workers: int | None = None,
               on_done: Callable[[int, bool, float], None] | None = None
               ) -> list[tuple[bool, Any]]:
    """Run independent tasks on all cores (forked workers); return (ok, result or message).

    The tasks are closures inherited by the forked workers (nothing but the
    results is pickled); an exception comes back as ``(False, "Type: message")``.
    Where ``fork`` is not available, or for a single task, they run here.

    Parameters
    ----------
    tasks : sequence of callable
        Independent tasks without arguments.
    workers : int, optional
        Processes (default: one per core).
    on_done : callable, optional
        Called here as each task finishes, in the order they finish, with its index,
        whether it succeeded and how long it ran (s): the progress lines.

    Returns
    -------
    list of (bool, object)
        In the order of ``tasks``.
    """
    tasks = list(tasks)
    n = min(len(tasks), workers or os.cpu_count() or 1)
    out: list[tuple[bool, Any]] = [(False, "not run")] * len(tasks)

    def done(i: int, res: tuple[bool, Any, float]) -> None:
        out[i] = res[:2]
        if on_done is not None:
            on_done(i, res[0], res[2])

    _TASKS[:] = tasks
    try:
        if n <= 1 or "fork" not in multiprocessing.get_all_start_methods():
            for i in range(len(tasks)):
                done(i, _call(i))
            return out
        with ProcessPoolExecutor(n, mp_context=multiprocessing.get_context("fork")) as pool:
            futures = {pool.submit(_call, i): i for i in range(len(tasks))}
            for fut in as_completed(futures):
                done(futures[fut], fut.result())
        return out
    finally:
        _TASKS.clear()


def apply_tuning(scenarios: Sequence[Any], variants: Sequence[str]) -> list[Any]:
    """Add the tuned profile variants to every scenario (uncertainty: :func:`apply_uncertainty`)."""
    out = []
    for sc in scenarios:
        cmp = sc.compare
        profiles = tuple(cmp.profiles) + tuple(v for v in variants if v not in cmp.profiles)
        if any(v.startswith("DJL") or v.startswith("JL") for v in variants) and \
                "JL" not in profiles:
            profiles = ("JL", *profiles)  # the tuned variants are compared with JL
        out.append(dataclasses.replace(sc, compare=dataclasses.replace(cmp, profiles=profiles)))
    return out
