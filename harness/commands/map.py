"""``djl-fmu map``: AL / JL / DJL over a grid of moves, on all cores or on a Dask cluster."""

from __future__ import annotations

import argparse

from ..executors import ExecutorError, make_executor
from ..files import OutputSet, save_figure
from ..fmu.runner import FMUError
from ..workspace import WorkspaceMapError, check_engine, run_workspace_map
from ._common import (
    CommandError,
    add_engine_option,
    add_map_error_option,
    add_out_option,
    add_parallel_options,
    add_quiet_option,
    add_tuning_option,
    add_uncertainty_option,
    apply_tuning,
    apply_uncertainty,
    check_parallel_options,
    check_rows_finite,
    interruptible,
    load_scenarios,
    parse_tuning,
    report_written,
    uncertainty_option,
    write_outputs,
)

DESCRIPTION = """\
Map the workspace: run every move of a grid and measure, for each compared
profile (AL, JL, DJL), the residual vibration, the motion time and the
settling time, exactly as 'djl-fmu simulate' does for one move (JL tuned to
the period at the end of the motion, DJL to the period at the start of each
constant-jerk stage).

The grid is every combination of Z start positions, Z travels, move lengths
and velocity limits, given by the [map] table of the scenario (format:
docs/map.md); the embedded scenarios X and Y have a default grid of 10,000
moves (z0 0..0.1 m, Z travel 0.025..0.5 m, move 0.02..0.5 m, v_max 0.25..2 m/s).
Moves are numbered in grid order: z0, then Z travel, then move length, then
v_max (varying fastest); --max-moves N runs N moves spread evenly over the whole
grid (every z0 and v_max, then Z travel and move length; always the same N).

The moves run in batches on a pool of processes, one per core by default
(--workers N), or on the workers of a running Dask cluster (--scheduler
ADDRESS). The results do not depend on where they ran: the CSV is identical
for any number of workers and on a cluster.

Outputs, in --out (default ./djl-fmu-out/map), written only once every move
has succeeded:
  <name>-map.csv        one row per move and profile: the columns of the sweep CSV of
                        'djl-fmu simulate', plus move_index (0-based, grid order)
  <name>-map.png        heat map of the residual vibration of DJL against JL, % change,
                        over (move length, Z travel), one panel per z0 and v_max
  <name>-map-*.png      residual of each profile as % of AL, settling time DJL vs JL
  summary.txt           moves, time per move, workers, median and max residuals

Running on a Dask cluster (dask.distributed: pip install 'djl-fmu[cluster]', or
pip install '.[cluster]' from a checkout, here and on every worker):
  dask scheduler                               # prints its address, tcp://HOST:8786
  dask worker tcp://HOST:8786 --nworkers 4 --nthreads 1   # on every machine (4 cores)
  djl-fmu map X --scheduler tcp://HOST:8786
Every worker needs this package installed (pip install '.[cluster]' from the same checkout);
with --engine fmu and a scenario that names its own FMU file, the file must
exist at the same path on the workers.
"""

EPILOG = """\
examples:
  djl-fmu map X                                the 10,000-move map of scenario X, all cores
  djl-fmu map Y --max-moves 500 --workers 2    500 moves across the grid, on 2 processes
  djl-fmu map my_axis.toml --scheduler tcp://10.0.0.5:8786
  djl-fmu map X --engine fmu --max-moves 20    through the generator FMUs (slower)

Exit status: 0 on success, 2 for a bad scenario or option, or an unreachable
scheduler (nothing simulated, nothing written), 1 if a move fails or a result is
not finite (nothing written).
The outputs replace the previous ones as one set: after a failure or an
interruption (Ctrl-C: 130, SIGTERM: 143) the previous files are as they were
(docs/harness.md, Outputs).
"""


MAP_FINITE = ("residual_m", "free_amplitude_m", "residual_peak_m", "motion_time_s")
"""Columns of ``<name>-map.csv`` that must be finite numbers (a NaN or an infinity: exit 1);
``residual_m`` is also the absolute heat map."""

MAP_NO_INF = ("residual_pct_of_AL", "case_djl_vs_jl_residual_pct",
              "case_djl_vs_jl_settling_pct", "residual_worst_map10_m")
"""Columns that may be NaN (a percentage of a zero reference, a settling time that never
comes, a worst case not computed: blank in the heat maps), never infinite.  The settling
and rise times may be infinite or NaN: "never", "not within the record"."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``map`` command."""
    p = sub.add_parser(
        "map",
        help="AL/JL/DJL over a grid of moves (residual, settling, motion time): CSV and "
             "heat maps, on all cores or a Dask cluster",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("scenario", metavar="SCENARIO",
                   help="TOML scenario file with a [map] table, or an embedded scenario "
                        "name (X, Y)")
    add_out_option(p, "map")
    add_parallel_options(p, max_moves="run only N moves, spread evenly over the whole grid "
                                    "(deterministic)")
    add_engine_option(p, "fast", "fast")
    add_tuning_option(p, "add")
    add_uncertainty_option(p)
    add_map_error_option(p, "uncertainty of the 'robust' tuning")
    add_quiet_option(p, "the PNG heat maps")
    p.set_defaults(func=interruptible(run))


def run(args: argparse.Namespace) -> int:
    """Check the inputs, run the map, then write the outputs; return the exit status.

    A :class:`~harness.errors.CommandError` it raises is reported by
    :func:`harness.cli.main` (message and exit status).
    """
    # 1. check everything before running anything
    check_parallel_options(args.workers, args.scheduler, args.max_moves)
    (sc,), (stem,) = load_scenarios([args.scenario], None, None, args.out)
    (sc,) = apply_tuning([sc], parse_tuning(args.tuning))
    (sc,) = apply_uncertainty([sc], uncertainty_option(args.uncertainty, args.map_error))
    if sc.map is None:
        raise CommandError(2, f"scenario {sc.name} ({sc.source}) has no [map] table: add one "
                              f"(format: docs/map.md), or use the embedded X or Y")
    try:
        check_engine(args.engine, sc)
    except ValueError as e:
        raise CommandError(2, f"--engine {args.engine}: {e}") from None

    import matplotlib  # deferred: matplotlib is heavy to import

    matplotlib.use("Agg")

    # 2. run (nothing is written yet); the executor is set up first, so that a bad
    #    scheduler address is reported as a bad option
    try:
        with make_executor(args.workers, args.scheduler) as ex:
            try:
                res = run_workspace_map(sc, engine=args.engine, max_moves=args.max_moves,
                              progress=not args.quiet, executor=ex)
            except (WorkspaceMapError, FMUError, ValueError, OSError) as e:
                raise CommandError(1, f"map failed ({sc.name}): {e}") from None
    except ExecutorError as e:
        raise CommandError(2, str(e)) from None
    # a NaN or an infinity in a metric (CSV, heat maps) is a failure, never written
    check_rows_finite(res.rows(), f"map failed ({sc.name}): {stem}-map.csv",
                      finite=MAP_FINITE, no_inf=MAP_NO_INF, keys=("move_index", "profile"))
    summary = res.table()

    # 3. write everything, or nothing: one set replacing the previous one
    def write(o: OutputSet) -> None:
        res.to_csv(o.path(f"{stem}-map.csv"))
        if not args.no_plot:
            for i, (name, fig) in enumerate(res.figures().items()):
                fname = f"{stem}-map.png" if i == 0 else f"{stem}-map-{name}.png"
                save_figure(fig, o.path(fname))

    written = write_outputs(args.out, write, summary)
    report_written(args.out, written, summary, args.quiet)
    return 0
