"""``djl-fmu online``: DJL whose jerk times the FMU takes from ``f_mode`` during the move."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..files import OutputSet, save_figure, write_csv
from ..fmu.runner import FMUError, check_fmu_archive
from ..online import (
    COMMANDED_VARIABLES,
    format_online,
    jerk_source_values,
    online_rows,
    run_online,
)
from ..simulation.axis import samples_per_step
from ..simulation.session import Session
from ..tuning_options import DJL_METHODS
from ._common import (
    CommandError,
    add_fmu_options,
    add_out_option,
    add_quiet_option,
    add_scenarios_argument,
    check_rows_finite,
    interruptible,
    load_scenarios,
    report_written,
    write_outputs,
)

DESCRIPTION = """\
Co-simulate the commanded generator FMU  with its jerk times taken
from the input f_mode. The master sets f_mode at every communication step to
the tuned mode's frequency at the Z generator's current position (the mode map
of the scenario): the paper's DJL rule (the modal period at the start of each
stage) applied online, inside the co-simulation, with no tuning beforehand.
The FMU parameter jerk_source (--jerk-source) says how:

  3 (f_mode_ahead, default): each stage still to come takes round(1/(f Te))
    samples, f = f_mode extrapolated at its rate over the last step to the
    sample where the plan starts the stage, so the deceleration is placed for
    the jerk times it will have;
  2 (f_mode): each constant-jerk stage's jerk time is round(1/(f_mode Te))
    samples, f_mode read at the step that ends where the stage starts; the
    deceleration is placed for the jerk times of the moment.

With either, a stage whose jerk time from f_mode would no longer land the move
without moving back keeps the one it was planned with (the FMU logs it; marked
"kept"). --jerk-source both runs the two, side by side.

It runs next to the offline-tuned DJL of the same scenario (the paper's rule
iterated on the planned move, or --offline DJL-optimal / DJL-robust) through
the same plant and the same Z move (synchronised with the offline DJL move),
and prints, for all: the jerk times applied per stage, the residual vibration
(free-oscillation amplitude when the reference ends), the motion time and the
settling time in the scenario's band; and, for each online run, where each
stage started (the FMU's stage output), z and f_mode where its f_mode was
read, the rule's frequency f for the jerk source (for 3: extrapolated, with
the rate), round(1/(f Te)), the samples its ramp of constant jerk lasted (the
j output) and whether it kept its planned jerk time.

SCENARIO is a single-move TOML file (format: docs/harness.md) or an embedded
scenario name; default X. The FMU engine only (the FMU is stepped with its
input set at every step); about 1 s a scenario and jerk source.

Outputs, in --out (default ./djl-fmu-out/online), written only once every run
has succeeded:
  <name>-online.csv   one row per run (profile, jerk_source, jerk times in
                      samples, residual, motion and settling time, end position
                      error), then one row per online stage (jerk_source,
                      start, where f_mode was read, z, f_mode, rate, the rule's
                      f, N rule, N applied, kept)
  <name>-online.png   x, v, a, j of both; the stage output and f_mode; the
                      deflection; z(t) (with --jerk-source both:
                      <name>-online-js2.png and <name>-online-js3.png)
  summary.txt         the tables printed on screen
"""

EPILOG = """\
examples:
  djl-fmu online                       scenario X, jerk_source = 3
  djl-fmu online X Y --jerk-source both
                                       offline DJL, online 2 and online 3 side by side
  djl-fmu online X Y --fmi-version 3   both Table 1 moves on the FMI 3.0 FMU
  djl-fmu online Y --offline DJL-optimal
                                       against DJL tuned on the model (docs/tuning.md)
  djl-fmu online my_axis.toml --fmu my_generator.fmu

Exit status: 0 on success, 2 for a bad scenario or option or an FMU without the
commanded interface or the jerk source (nothing run, nothing written), 1 if a
run fails or a result is not finite (nothing written).
"""

ONLINE_FINITE = ("residual_m", "residual_peak_m", "motion_time_s", "end_error_m")
"""Columns of ``<name>-online.csv`` that must be finite (else exit 1, nothing written)."""


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``online`` command."""
    p = sub.add_parser(
        "online",
        help="DJL with f_mode given to the FMU online from the mode map at the current Z "
             "position, against the offline-tuned DJL ",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_scenarios_argument(p, "X; a single move")
    add_out_option(p, "online")
    add_fmu_options(p, "with the commanded interface")
    p.add_argument("--step", type=float, default=None, metavar="S",
                   help="communication step in s, a whole multiple of Te (default: the "
                        "scenario's; the stages are measured only when it is Te)")
    p.add_argument("--offline", default="DJL", metavar="PROFILE",
                   help="offline profile compared: DJL (the scenario's DJL tuning, the paper's "
                        "rule by default), DJL-paper, DJL-optimal or DJL-robust")
    p.add_argument("--jerk-source", choices=("3", "2", "both"), default="3",
                   help="the FMU's jerk_source online: 3 (f_mode_ahead, f_mode extrapolated to "
                        "each stage's start; default), 2 (f_mode as read) or both side by side")
    add_quiet_option(p)
    p.set_defaults(func=interruptible(run))


def run(args: argparse.Namespace) -> int:
    """Check the scenarios, run them, then write the outputs; return the exit status."""
    # 1. check everything before running anything
    scenarios, stems = load_scenarios(args.scenarios or ["X"], args.fmu, args.fmi_version,
                                      args.out)
    allowed = ["DJL"] + [f"DJL-{m}" for m in DJL_METHODS]
    if args.offline not in allowed:
        raise CommandError(2, f"--offline {args.offline!r}: choose from {', '.join(allowed)}")
    sources = (2, 3) if args.jerk_source == "both" else (int(args.jerk_source),)
    for sc in scenarios:
        if sc.is_sweep:
            raise CommandError(2, f"{sc.name}: a sweep; the online co-simulation runs single "
                                  f"moves (e.g. X, Y, or a file without [sweep])")
        if args.step is not None:
            try:
                samples_per_step(args.step, sc.simulation.Te, f"{sc.name} generator")
            except ValueError as e:
                raise CommandError(2, f"--step {args.step!r}: {e}") from None
        fmu = sc.simulation.fmu
        if fmu is not None:
            names = fmu_variable_names(fmu)
            lacking = [n for n in COMMANDED_VARIABLES if n not in names]
            if lacking:
                raise CommandError(2, f"{fmu}: not a commanded generator FMU : no "
                                      f"{', '.join(lacking)}")
            values = fmu_jerk_sources(fmu)
            if values is not None and not set(sources) <= values:
                raise CommandError(2, f"{fmu}: no jerk_source = "
                                      f"{', '.join(str(v) for v in sources if v not in values)} "
                                      f"(it allows {', '.join(str(v) for v in sorted(values))})")

    # 2. run (nothing is written yet)
    import matplotlib  # deferred: matplotlib is heavy to import

    matplotlib.use("Agg")
    results = []  # per scenario: one result per jerk source
    for sc in scenarios:
        runs = []
        try:
            session = Session(sc.simulation.fmu, sc.simulation.fmi_version, engine="fmu")
            try:
                for js in sources:
                    runs.append(run_online(sc, step=args.step, offline=args.offline,
                                           session=session, jerk_source=js))
            finally:
                session.close()
        except (FMUError, RuntimeError, ValueError) as e:
            raise CommandError(1, f"online co-simulation failed ({sc.name}): {e}") from None
        check_rows_finite([r for r in online_rows(runs) if r["row"] == "run"],
                          f"online co-simulation failed ({sc.name})",
                          finite=ONLINE_FINITE, keys=("profile", "jerk_source"))
        results.append(runs)
    summary = "\n\n".join(format_online(runs) for runs in results)

    # 3. write everything, or nothing
    def write(o: OutputSet) -> None:
        for stem, runs in zip(stems, results, strict=True):
            write_csv(o.path(f"{stem}-online.csv"), online_rows(runs))
            if args.no_plot:
                continue
            for r in runs:
                suffix = f"-js{r.jerk_source}" if len(runs) > 1 else ""
                save_figure(r.plot(), o.path(f"{stem}-online{suffix}.png"))

    written = write_outputs(args.out, write, summary)
    report_written(args.out, written, summary, args.quiet)
    return 0


def fmu_variable_names(path: Path) -> set[str]:
    """Names of every variable of an FMU file (``ValueError`` if it is not one)."""
    from fmpy import read_model_description  # deferred: fmpy is heavy to import

    check_fmu_archive(path)
    return {v.name for v in read_model_description(str(path)).modelVariables}


def fmu_jerk_sources(path: Path) -> set[int] | None:
    """Values an FMU file allows for ``jerk_source`` (None if it does not say)."""
    from fmpy import read_model_description  # deferred: fmpy is heavy to import

    return jerk_source_values(read_model_description(str(path)))
