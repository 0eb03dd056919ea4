"""``djl-fmu tune``: tuned JL / DJL jerk times per move or over a grid, as a documented CSV."""

from __future__ import annotations

import argparse
import sys

from ..executors import ExecutorError, make_executor
from ..files import OutputSet
from ..tuning.tables import TuneError, parse_tuning, tune_table, with_methods
from ..workspace import check_engine
from ._common import (
    CommandError,
    add_map_error_option,
    add_out_option,
    add_parallel_options,
    add_quiet_option,
    add_tuning_option,
    add_uncertainty_option,
    apply_uncertainty,
    check_parallel_options,
    check_rows_finite,
    interruptible,
    load_scenarios,
    report_written,
    uncertainty_option,
    write_outputs,
)

DESCRIPTION = """\
Tune the jerk times of JL and DJL for a move, every case of a [sweep] or every
point of a [map] grid (Z start, Z travel, distance, v_max), measure the
residual vibration each leaves (on the nominal mode map and, worst case, over
the uncertainty: by default the whole map off by up to +/-10 %), print them and
write them as a CSV file that a controller or the generator FMU can load.

Methods (--tuning, default: DJL robust, JL end):
  DJL paper     the modal period at the start of each stage (the paper's rule; 3 ms)
  DJL optimal   least residual on the nominal map (about 0.1 s a move)
  DJL robust    least worst-case residual over the uncertainty's tuning set
                (--uncertainty map_scale=E, default: the scenario's [uncertainty],
                map_scale 0.1)
  JL  end       the modal period at the end of the motion (the paper's)
  JL  optimal   least residual on the nominal map
--tuning takes a bare DJL method (robust, optimal, paper), 'end', or
'djl=METHOD,jl=METHOD'. The methods come from --tuning, not from the
scenario's djl_tuning / jl_tuning; its other tuning settings (max_motion_time,
period_band, djl_rule, tune_mode) and its [uncertainty] apply. Jerk times the
scenario imposes (JL_T_F, DJL_T_F) are ignored: this command computes them.

What is tuned: a scenario with a [map] table, every grid point in grid order
(z0, then Z travel, then distance, then v_max varying fastest; --max-moves N:
the first N); else with a [sweep] table, every case in the sweep's order; else
its single move. --single tunes the scenario's own move whatever its tables
(the embedded X and Y have a 10,000-move [map]: 'djl-fmu tune X --single').

The moves run in batches on a pool of processes, one per core by default
(--workers N), or on a Dask cluster (--scheduler ADDRESS, as for 'djl-fmu
map'); the CSV is the same file whatever ran it.

Outputs, in --out (default ./djl-fmu-out/tune), written only once every move
has succeeded:
  <name>-jerk-times.csv  '#' header (format version, scenario, methods, uncertainty,
                         Te, units, the meaning of every column, how to set the FMU),
                         then the column names and one row per move:
                         z0_m, z_distance_m, distance_m, v_max_m_s, jl_T_F_s,
                         djl_T_F1_s..djl_T_F4_s, djl_N_F1..djl_N_F4, residual_m,
                         worst_residual_m, jl_residual_m, jl_worst_residual_m,
                         motion_time_s, jl_motion_time_s, method, ... (docs/tune.md)
  summary.txt            what is printed
FMU: profile = 3 with T_F1..T_F4 = djl_T_F1_s..djl_T_F4_s (DJL), profile = 2 with
T_F1 = jl_T_F_s (JL). Python: harness.tuning.tables.load_jerk_times(path),
fmu_parameters(row).
"""

EPILOG = """\
examples:
  djl-fmu tune X --single                      scenario X's move, DJL robust (default +/-10 %)
  djl-fmu tune X --single --tuning djl=optimal,jl=optimal
  djl-fmu tune sweep-X --tuning paper          the 50 cases of the test set, paper's rule
  djl-fmu tune X --max-moves 200 --workers 2   the first 200 moves of X's [map] grid
  djl-fmu tune my_axis.toml --uncertainty map_scale=0.15 --scheduler tcp://10.0.0.5:8786

Exit status: 0 on success, 2 for a bad scenario or option (nothing tuned, nothing
written), 1 if a move fails, a result is not finite or the outputs cannot be written
(nothing written).
The outputs replace the previous ones as one set: after a failure or an
interruption (Ctrl-C: 130, SIGTERM: 143) the previous files are as they were
(docs/harness.md, Outputs).
"""


TUNE_FINITE = ("jl_T_F_s", "djl_T_F1_s", "djl_T_F2_s", "djl_T_F3_s", "djl_T_F4_s",
               "residual_m", "worst_residual_m", "jl_residual_m", "jl_worst_residual_m",
               "motion_time_s", "jl_motion_time_s")
"""Columns of ``<name>-jerk-times.csv`` that must be finite numbers: the exported jerk
times, residuals and motion times (a NaN or an infinity: exit 1, nothing written)."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``tune`` command."""
    p = sub.add_parser(
        "tune",
        help="tuned JL/DJL jerk times (paper, optimal, robust) per move or over a [map] "
             "grid: printed and written as a CSV the FMU or a controller can load",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("scenario", metavar="SCENARIO",
                   help="TOML scenario file, or an embedded scenario name (X, Y, sweep-X, "
                        "sweep-Y)")
    add_tuning_option(p, "pick")
    add_uncertainty_option(p)
    add_map_error_option(p, "uncertainty of the robust method and of the worst-case residuals")
    p.add_argument("--single", action="store_true",
                   help="tune the scenario's own move only, whatever its [map] or [sweep]")
    add_out_option(p, "tune")
    add_parallel_options(p, max_moves="tune only the first N moves of the [map] grid or "
                                      "[sweep]")
    add_quiet_option(p, None)
    p.set_defaults(func=interruptible(run))


def run(args: argparse.Namespace) -> int:
    """Check the inputs, tune, then write the outputs; return the exit status.

    A :class:`~harness.errors.CommandError` it raises is reported by
    :func:`harness.cli.main` (message and exit status).
    """
    # 1. check everything before running anything
    check_parallel_options(args.workers, args.scheduler, args.max_moves)
    try:
        djl, jl = parse_tuning(args.tuning)
    except ValueError as e:
        raise CommandError(2, f"--tuning {args.tuning}: {e}") from None
    unc = uncertainty_option(args.uncertainty, args.map_error)
    (sc,), (stem,) = load_scenarios([args.scenario], None, None, args.out)
    (sc,) = apply_uncertainty([sc], unc)
    try:
        sc = with_methods(sc, djl, jl)
    except ValueError as e:
        raise CommandError(2, f"scenario {sc.name} ({sc.source}): {e}") from None
    try:
        check_engine("fast")
    except ValueError as e:
        raise CommandError(2, f"the tuning searches need the compiled engine: {e}") from None

    # 2. run (nothing is written yet); the executor is set up first, so that a bad
    #    scheduler address is reported as a bad option
    workers = args.workers
    single = args.single or (sc.map is None and not sc.is_sweep)
    if single and args.scheduler is None:
        workers = 1
    if not single and not args.quiet:
        n = sc.map_size if sc.map is not None else len(sc.cases())
        what = "[map] grid" if sc.map is not None else "[sweep]"
        todo = min(n, args.max_moves) if args.max_moves else n
        print(f"djl-fmu tune: {todo} of the {n} moves of the {what} of {sc.name} "
              f"(--single: the scenario's own move; --max-moves N: the first N)",
              file=sys.stderr)
    try:
        with make_executor(workers, args.scheduler) as ex:
            try:
                tab = tune_table(sc, djl_method=djl, jl_method=jl, max_moves=args.max_moves,
                                 progress=not args.quiet, executor=ex, single=args.single)
            except (TuneError, ValueError, OSError) as e:
                raise CommandError(1, f"tuning failed ({sc.name}): {e}") from None
    except ExecutorError as e:
        raise CommandError(2, str(e)) from None
    # a NaN or an infinity in an exported jerk time or residual is a failure, never written
    check_rows_finite(tab.rows, f"tuning failed ({sc.name}): {stem}-jerk-times.csv",
                      finite=TUNE_FINITE, keys=("move_index", "z0_m", "z_distance_m",
                                                "distance_m", "v_max_m_s"))
    summary = tab.table()

    # 3. write everything, or nothing: one set replacing the previous one
    def write(o: OutputSet) -> None:
        tab.to_csv(o.path(f"{stem}-jerk-times.csv"))

    written = write_outputs(args.out, write, summary)
    report_written(args.out, written, summary, args.quiet)
    return 0
