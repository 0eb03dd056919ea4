"""``djl-fmu compare``: AL / JL / DJL against the methods a user would otherwise pick."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from tqdm import tqdm

from ..files import OutputSet, save_figure, write_csv
from ..fmu.runner import FMUError
from ..peers.compare import ALL_PEERS, PEERS, compare_scenario, stationary_variant
from ..peers.ruckig_ref import COMPARE_HINT, ruckig_available
from ..peers.timeopt import measure
from ._common import (
    CommandError,
    add_engine_option,
    add_fmu_options,
    add_map_error_option,
    add_out_option,
    add_quiet_option,
    add_scenarios_argument,
    add_uncertainty_option,
    apply_uncertainty,
    check_rows_finite,
    check_stems,
    elapsed_text,
    interruptible,
    load_scenarios,
    progress_line,
    report_written,
    safe_stem,
    uncertainty_option,
    write_outputs,
)

DESCRIPTION = """\
Answer "which law ends the motion soonest with the vibration inside my
tolerance?" on the harness's scenarios: the generator's AL, JL and DJL
profiles and their peers go through the same co-simulation (the Z axis FMU and
the flexible axis whose mode follows Z) and the same metrics.

Peers, each tuned to the mode at the end of the motion (its frequency at the
final Z position and its damping) unless said otherwise:
  time-optimal JL   ruckig under v_max, a_max and the JL's jerk a_max/T_F(JL)
                    (Park et al. 2017); the motion-time ratios refer to it
  Sato III          Sato & Shirase 2021, Condition III, T_SUM = the JL's motion
                    time (longer if v_max or a_max demand it), T1 from eq. 28
  AL*ZV, AL*ZVD, AL*MZV, AL*EI
                    the FMU's AL profile convolved with an input shaper
  JL*ZV, JL*ZVD, JL*EI (JL*MZV on request)
                    the FMU's JL profile (the harness's JL, jerk time = modal
                    period at the end) convolved with an input shaper
  AL*TV-ZV, JL*TV-ZV
                    time-varying ZV shaper (after Chang & Park 2005): each
                    impulse pair placed half a local damped period apart and
                    weighted from the mode along the synchronised Z move
  JL*SI             the JL convolved with a specified-insensitivity shaper
                    (Singhose et al. 1996): three impulses, V <= 5 % over the
                    end frequency x (1 +/- the uncertainty's map scale)
  JL*MM-ZVD         one ZVD per mode of the map, convolved (added by default
                    when the map has several modes)
  damped jerk       the AL profile filtered by the damped-jerk filter
                    (Bearee 2014, 4.2)
  DJL (optimal), DJL (robust)
                    the DJL with the harness's optimal and robust tuning
                    ([compare] djl_tuning), fast engine; --no-tuned-djl skips
                    them

Per scenario: motion time and its ratio to the time-optimal JL, residual
vibration (free-oscillation amplitude when the reference ends) and % of AL,
settling time into the band of the scenario (default: 1 % of AL's residual,
shared by every method), the worst residual over a map error within
+/- the uncertainty's map scale (--uncertainty map_scale=E; default +/-10 %)
on the time-varying plant (the whole f(z) map scaled by 1 + e, every reference
planned once on the nominal map; curves over +/-2E, by default +/-20 %, fast
engine), and the residual against the mode-frequency error on a stationary mode
at the end frequency.  Every method is also scored over the scenario's
uncertainty (default map scale +/-10 %, its 41-point scoring set): worst
residual and worst-case settling time, and that settling as a ratio to the
physical limit ("/ bound": a linear programme over piecewise-constant jerk
proves that no profile at JL's jerk, under the same v_max and a_max, settles
sooner over the same set; about 30 s per scenario the first time, then cached;
--no-bound skips it; not computed for the stationary variants).  The row
"recommended" is the profile the project recommends (docs/recommend.md).
A verdict closes each table: who leaves the least residual, who settles
first, who has the smallest worst case, how far the best jerk-limited method
is from the limit, with the numbers.
Each scenario also runs as a stationary variant (Z still at its final
position), unless --no-stationary.  With --timeopt N (default 30), random moves
measure how much slower than time-optimal the FIR-built JL and DJL are (per
case of Park et al.).

SCENARIO is a TOML file (format: docs/harness.md) or an embedded single-move
scenario; default: X and Y.  Sweeps are not accepted.

Outputs, in --out (default ./djl-fmu-out/compare), written once every run has
succeeded:
  <name>.csv              one row per method (worst_residual_10pct_m: the
                          worst case over a map error within +/- the run's
                          map scale, by default +/-10 %: the name is kept;
                          settling_time_worst_s, settling_bound_s and
                          settling_worst_over_bound: the worst-case settling,
                          the physical limit and their ratio)
  <name>-map-error.csv    residual against the map error e (time-varying plant,
                          whole map scaled by 1 + e, e in +/-2 x the map scale),
                          per method
  <name>-map-error.png    the same, plotted (shaded: +/- the map scale)
  <name>-robustness.csv   residual against the frequency error of a stationary
                          mode, per method
  <name>-robustness.png   the same, plotted
  <name>-runs.png         acceleration and deflection of every method
  timeopt.csv             the random moves (with --timeopt)
  summary.txt             the tables printed on screen
Needs the optional dependency ruckig (pip install '.[compare]' from a checkout).
"""

EPILOG = """\
examples:
  djl-fmu compare                       X and Y, each also with a stationary mode
  djl-fmu compare Y --no-stationary     scenario Y only
  djl-fmu compare my_axis.toml --peers AL*ZVD,damped jerk --timeopt 0
  djl-fmu compare --engine fast --no-tuned-djl

Exit status: 0 on success, 2 for a bad scenario or option (nothing run, nothing
written), 1 if a run fails or a result is not finite (nothing written).
The outputs replace the previous ones as one set: after a failure or an
interruption (Ctrl-C: 130, SIGTERM: 143) the previous files are as they were
(docs/harness.md, Outputs).
"""


COMPARE_FINITE = ("motion_time_s", "motion_time_over_time_optimal", "residual_m",
                  "free_amplitude_m")
"""Columns of ``<name>.csv`` that must be finite numbers (a NaN or an infinity: exit 1)."""

COMPARE_NO_INF = ("worst_residual_10pct_m", "residual_pct_of_AL", "worst_residual_10pct_pct_of_AL")
"""Columns that may be NaN (not computed, or a percentage of a zero AL residual), never
infinite.  The settling time may be infinite: a mode that never settles ("never")."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``compare`` command."""
    p = sub.add_parser(
        "compare",
        help="compare AL/JL/DJL with time-optimal JL, Sato's designed jerk times, input "
             "shapers (on AL and JL, and time-varying), the damped-jerk law and the optimal "
             "and robust DJL on the same plant (default: scenarios X, Y)",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_scenarios_argument(p, "X Y; single moves")
    add_out_option(p, "compare")
    p.add_argument("--no-stationary", action="store_true",
                   help="do not add the stationary-mode variant of each scenario")
    p.add_argument("--peers", default=None, metavar="LIST",
                   help="comma-separated subset of the peers (default: time-optimal JL, "
                        "Sato III, AL*ZV, AL*ZVD, AL*MZV, AL*EI, JL*ZV, JL*ZVD, JL*EI, "
                        "JL*SI, AL*TV-ZV, JL*TV-ZV, damped jerk; JL*MM-ZVD with several "
                        "modes; also JL*MZV)")
    p.add_argument("--no-tuned-djl", action="store_true",
                   help="do not add the rows DJL (optimal) and DJL (robust)")
    p.add_argument("--no-bound", action="store_true",
                   help="do not compute the physical limit (the '/ bound' column; about 30 s "
                        "per scenario the first time, then cached)")
    p.add_argument("--timeopt", type=int, default=30, metavar="N",
                   help="random moves per case for the FIR-JL/DJL vs time-optimal "
                        "measurement (default 30; 0 to skip)")
    add_fmu_options(p)
    add_engine_option(p, "fmu", "fmu")
    add_uncertainty_option(p)
    add_map_error_option(p, "uncertainty of the robust DJL's tuning")
    add_quiet_option(p)
    p.set_defaults(func=interruptible(run))


def run(args: argparse.Namespace) -> int:
    """Check the inputs, run every comparison, then write the outputs; return the exit status.

    A :class:`~harness.errors.CommandError` it raises is reported by
    :func:`harness.cli.main` (message and exit status).
    """
    # 1. check everything first
    if not ruckig_available():
        raise CommandError(2, "needs the 'ruckig' package for the time-optimal reference: "
                              + COMPARE_HINT)
    peers = PEERS
    if args.peers:
        peers = tuple(x.strip() for x in args.peers.split(",") if x.strip())
        bad = [x for x in peers if x not in ALL_PEERS]
        if bad or not peers:
            raise CommandError(2, f"unknown peer(s) {bad}; choose from: {', '.join(ALL_PEERS)}")
    if args.timeopt < 0:
        raise CommandError(2, "--timeopt must be >= 0")
    scenarios, _ = load_scenarios(args.scenarios or ["X", "Y"], args.fmu, args.fmi_version,
                                  args.out)
    scenarios = apply_uncertainty(scenarios, uncertainty_option(args.uncertainty,
                                                                args.map_error))
    sweeps = [s.name for s in scenarios if s.is_sweep]
    if sweeps:
        raise CommandError(2, f"{', '.join(sweeps)}: sweeps are not compared (give "
                              "single-move scenarios such as X or Y)")
    if not args.no_stationary:
        scenarios = [v for s in scenarios for v in
                     ((s, stationary_variant(s)) if s.z.moves else (s,))]
        check_stems(scenarios)
    stems = [safe_stem(s.name) for s in scenarios]

    # 2. run (nothing written yet)
    import matplotlib  # deferred: matplotlib is heavy to import

    matplotlib.use("Agg")

    show = not args.quiet and sys.stderr.isatty()
    results = []
    current = ""
    try:
        for k, sc in enumerate(tqdm(scenarios, disable=not show, desc="scenarios",
                                    leave=False)):
            current = sc.name
            t0 = time.perf_counter()
            results.append(compare_scenario(sc, peers=peers, engine=args.engine,
                                            tuned_djl=not args.no_tuned_djl,
                                            bound=not args.no_bound and sc.z.moves))
            progress_line(args.quiet, f"compare: {sc.name} done in "
                                      f"{elapsed_text(time.perf_counter() - t0)} "
                                      f"[{k + 1}/{len(scenarios)}]")
        table_t = None
        if args.timeopt:
            current = "time-optimal measurement"
            t0 = time.perf_counter()
            table_t = measure(args.timeopt, fmu=scenarios[0].simulation.fmu, progress=show)
            progress_line(args.quiet, f"compare: time-optimal measurement ({args.timeopt} "
                                      f"moves per case) done in "
                                      f"{elapsed_text(time.perf_counter() - t0)}")
    except (FMUError, ValueError, RuntimeError, OSError) as e:
        raise CommandError(1, f"run failed ({current}): {e}") from None

    # a NaN or an infinity in a metric is a failure, never written
    timeopt_rows = []
    if table_t is not None:
        timeopt_rows = [{"method": m.method, "case": m.case, "distance_m": m.distance,
                         "v_max_m_s": m.v_max, "a_max_m_s2": m.a_max, "j_max_m_s3": m.j_max,
                         "T_F1_s": m.T_F[0], "T_F2_s": m.T_F[1], "T_F3_s": m.T_F[2],
                         "T_F4_s": m.T_F[3], "T_opt_s": m.T_opt, "T_fmu_s": m.T_fmu,
                         "excess_samples": m.excess_samples, "excess_pct": m.excess_percent}
                        for m in table_t.rows]
    for stem, r in zip(stems, results, strict=True):
        check_rows_finite(r.rows(), f"run failed ({r.scenario.name}): {stem}.csv",
                          finite=COMPARE_FINITE, no_inf=COMPARE_NO_INF,
                          keys=("scenario", "method"))
        check_rows_finite(r.robustness_rows(),
                          f"run failed ({r.scenario.name}): {stem}-robustness.csv",
                          finite=("residual_m",), keys=("method", "frequency_error"))
        check_rows_finite(r.map_error_rows(),
                          f"run failed ({r.scenario.name}): {stem}-map-error.csv",
                          finite=("residual_m",), keys=("method", "map_error"))
    check_rows_finite(timeopt_rows, "run failed (time-optimal measurement): timeopt.csv",
                      finite=("T_opt_s", "T_fmu_s", "excess_pct"), keys=("method", "case"))

    texts = [r.table() for r in results]
    if table_t is not None:
        texts.append("FIR-built profiles against the time-optimal JL (ruckig), random moves "
                     f"({args.timeopt} per case; case I: v_max and a_max reached, II: a_max "
                     "only, III: neither, IV: v_max only):\n" + table_t.to_text())
    summary = "\n\n".join(texts)

    # 3. write everything, or nothing: one set replacing the previous one
    out: Path = args.out

    def write(o: OutputSet) -> None:
        for stem, r in zip(stems, results, strict=True):
            r.to_csv(o.path(f"{stem}.csv"))
            if r.map_error is not None:
                write_csv(o.path(f"{stem}-map-error.csv"), r.map_error_rows())
            write_csv(o.path(f"{stem}-robustness.csv"), r.robustness_rows())
            deg = r.degradation()
            if deg is not None:
                write_csv(o.path(f"{stem}-degradation.csv"), deg.rows())
                if not args.no_plot:
                    save_figure(deg.plot(), o.path(f"{stem}-degradation.png"))
            if not args.no_plot:
                if r.map_error is not None:
                    save_figure(r.plot_map_error(), o.path(f"{stem}-map-error.png"))
                save_figure(r.plot(), o.path(f"{stem}-robustness.png"))
                save_figure(r.plot_runs(), o.path(f"{stem}-runs.png"))
        if table_t is not None:
            write_csv(o.path("timeopt.csv"), timeopt_rows)

    written = write_outputs(out, write, summary)
    report_written(out, written, summary, args.quiet)
    return 0
