"""``djl-fmu simulate``: co-simulate AL / JL / DJL on a flexible axis whose mode moves with Z."""

from __future__ import annotations

import argparse
import functools
import hashlib
import os
import shutil
import tempfile
from pathlib import Path

from ..files import OutputSet, save_figure, write_csv, write_mat
from ..fmu.build import cache_dir, default_fmu
from ..results import SweepResult, format_table2, table2_rows
from ..scenario import DEFAULT_SCENARIOS, embedded_scenarios
from ..sweeps import run_scenario
from ..tables import rows_of
from ._common import (
    CommandError,
    add_engine_option,
    add_fmu_options,
    add_map_error_option,
    add_out_option,
    add_quiet_option,
    add_scenarios_argument,
    add_tuning_option,
    add_uncertainty_option,
    apply_tuning,
    apply_uncertainty,
    check_finite,
    elapsed_text,
    interruptible,
    load_scenarios,
    parse_tuning,
    progress_line,
    report_written,
    run_forked,
    uncertainty_option,
    write_outputs,
)

DESCRIPTION = """\
Co-simulate the generator FMU (one instance for the excited X or Y axis, one for
the Z axis) with a flexible axis whose vibration mode depends on the Z position
(Bearee & Olabi 2013, sections 3-4), and compare the AL, JL and DJL profiles:
residual vibration (peak |deflection| after the reference ends, and the free
oscillation amplitude), motion time, rise time and settling time.

JL is tuned to the modal period at the end of the motion, DJL to the period at
the start of each constant-jerk stage (Z motion included), as in the paper,
unless the scenario imposes jerk times.

SCENARIO is a TOML file (format: docs/harness.md) or the name of an embedded
scenario; with none, the embedded defaults run: X and Y (the two moves of
Table 1 of the paper) and sweep-X, sweep-Y (its test set, Table 2).

Outputs, in --out (default ./djl-fmu-out/simulate), written only once every
simulation has succeeded:
  <name>.csv      one row per profile (per case and profile for a sweep)
  <name>-signals.csv
                  single moves: the time series, one row per communication point:
                  t_s, z_m, f_Hz (Z position and tuned-mode frequency of the first
                  profile), then for each profile P: P_x_m, P_v_m_s, P_a_m_s2, P_j_m_s3
                  (reference), P_eps_m (deflection of the load), P_z_m, P_f_Hz
  <name>.mat      with --mat: the same for MATLAB (structs 'signals', 'metrics')
  <name>.png      reference x/v/a/j, deflection, f(t) and z(t) (a sweep: DJL vs JL per case)
  <name>-robustness.csv, <name>-robustness.png
                  single moves: each profile's residual when the whole mode map is off
                  by 1 + e, e in +/-2 x the uncertainty's map scale (41 points; by default
                  -20 %..+20 %; jerk times tuned on the nominal map); the worst case over
                  +/-map_scale (default +/-10 %) is in <name>.csv (residual_worst_map10_m:
                  the name kept, the run's range), per case for sweeps
  table2.csv      Table 2 statistics, when sweeps ran
  summary.txt     the tables printed on screen
  JerkLimitedTrajectory-fmi2.fmu, JerkLimitedTrajectory-fmi3.fmu
                  with no SCENARIO (the default run): the generator FMUs built from
                  this package, validated with fmpy (--no-fmus to skip)
"""

EPILOG = """\
examples:
  djl-fmu simulate                         the default scenarios (X, Y, sweep-X, sweep-Y)
  djl-fmu simulate X --fmi-version 3       scenario X on the FMI 3.0 FMU
  djl-fmu simulate my_axis.toml --fmu my_generator.fmu
  djl-fmu simulate --list                  the embedded scenarios

Exit status: 0 on success, 2 for a bad scenario or option (nothing simulated, nothing
written), 1 if a simulation fails or a result is not finite (nothing written).
The outputs replace the previous ones as one set: after a failure or an
interruption (Ctrl-C: 130, SIGTERM: 143) the previous files are as they were
(docs/harness.md, Outputs).
"""


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``simulate`` command."""
    p = sub.add_parser(
        "simulate",
        help="co-simulate AL/JL/DJL on a flexible axis whose mode moves with Z "
             "(scenario files; default: the paper's X, Y and test-set scenarios)",
        description=DESCRIPTION,
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_scenarios_argument(p, "X Y sweep-X sweep-Y")
    add_out_option(p, "simulate")
    add_fmu_options(p)
    add_engine_option(p, None, "fmu for single moves, fast for sweeps")
    add_tuning_option(p, "add")
    add_uncertainty_option(p)
    add_map_error_option(p, "uncertainty of the 'robust' tuning")
    p.add_argument("--workers", type=int, default=None, metavar="N",
                   help="with --tuning: run each sweep's cases on N processes (default: every "
                        "core); without it the scenarios already share the cores")
    add_quiet_option(p)
    p.add_argument("--mat", action="store_true",
                   help="also write <name>.mat (MATLAB, scipy.io.savemat): the structs "
                        "'signals' (single moves) and 'metrics' (the CSV's columns)")
    p.add_argument("--list", action="store_true",
                   help="list the embedded scenarios and exit")
    p.add_argument("--no-fmus", action="store_true",
                   help="in the default run, do not write the FMI 2.0 / 3.0 FMU files")
    p.set_defaults(func=interruptible(run))


def run(args: argparse.Namespace) -> int:
    """Check every scenario, run them, then write the outputs; return the exit status.

    A :class:`~harness.errors.CommandError` it raises is reported by
    :func:`harness.cli.main` (message and exit status).
    """
    if args.list:
        for name, desc in embedded_scenarios().items():
            print(f"{name:10s} {desc}")
        return 0

    # 1. check everything before simulating anything
    scenarios, stems = load_scenarios(args.scenarios or list(DEFAULT_SCENARIOS), args.fmu,
                                      args.fmi_version, args.out)
    variants = parse_tuning(args.tuning)
    scenarios = apply_tuning(scenarios, variants)
    scenarios = apply_uncertainty(scenarios, uncertainty_option(args.uncertainty,
                                                                args.map_error))
    if args.workers is not None and args.workers < 1:
        raise CommandError(2, f"--workers {args.workers}: must be >= 1")

    # 2. simulate (nothing is written yet)
    import matplotlib  # deferred: matplotlib is heavy to import

    matplotlib.use("Agg")
    if not args.no_plot:
        import matplotlib.pyplot  # noqa: F401  imported once here, not in every forked worker
    # the scenarios are independent: each is run, and its figures drawn into a staging folder,
    # by a forked worker (all cores); nothing is written in --out before they all succeeded
    progress = not args.quiet and (len(scenarios) == 1 or bool(variants))
    staging = Path(tempfile.mkdtemp(prefix="djl-fmu-simulate-"))
    try:
        tasks = [functools.partial(_scenario_task, sc, stem, staging, progress, args.engine,
                                   not args.no_plot, args.workers if variants else 1)
                 for sc, stem in zip(scenarios, stems, strict=True)]
        # tuned variants make sweeps long: then each sweep uses the cores itself, one
        # scenario after the other; otherwise the scenarios share the cores
        finished = []

        def on_done(i: int, ok: bool, seconds: float) -> None:
            finished.append(i)
            sc = scenarios[i]
            what = f"{len(sc.cases())} cases" if sc.is_sweep else "one move"
            progress_line(args.quiet, f"simulate: {sc.name} ({what}) "
                                      f"{'done' if ok else 'FAILED'} in {elapsed_text(seconds)} "
                                      f"[{len(finished)}/{len(scenarios)}]")

        outcomes = run_forked(tasks, workers=1 if variants else None, on_done=on_done)
        results, figures = [], []
        for sc, (ok, value) in zip(scenarios, outcomes, strict=True):
            if not ok:
                raise CommandError(1, f"simulation failed ({sc.name}): {value}")
            check_finite(sc.name, value[0])
            results.append(value[0])
            figures += value[1]

        texts = [r.table() for r in results if not isinstance(r, SweepResult)]
        sweeps = [r for r in results if isinstance(r, SweepResult)]
        if sweeps:
            texts.append(format_table2(sweeps))
        summary = "\n\n".join(texts)

        # 3. write everything, or nothing: one set replacing the previous one
        def write(o: OutputSet) -> None:
            for stem, r in zip(stems, results, strict=True):
                r.to_csv(o.path(f"{stem}.csv"))
                if getattr(r, "has_signals", False):
                    write_csv(o.path(f"{stem}-signals.csv"), rows_of(r.signals()))
                if args.mat:
                    write_mat(o.path(f"{stem}.mat"), r.mat_variables())
                rob = getattr(r, "robustness", None)
                if rob is not None:
                    write_csv(o.path(f"{stem}-robustness.csv"), rob.rows())
                deg = r.degradation() if hasattr(r, "degradation") else None
                if deg is not None:
                    write_csv(o.path(f"{stem}-degradation.csv"), deg.rows())
            for name in figures:
                shutil.copyfile(staging / name, o.path(name))
            if sweeps:
                write_csv(o.path("table2.csv"), table2_rows(sweeps))
            if not args.scenarios and not args.no_fmus:
                _write_fmus(o)

        written = write_outputs(args.out, write, summary)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    report_written(args.out, written, summary, args.quiet)
    return 0


def _scenario_task(sc, stem: str, staging: Path, progress: bool, engine: str | None,
                   plot: bool, workers: int | None = 1) -> tuple[object, list[str]]:
    """Run one scenario and draw its figures into ``staging``; return it and their names."""
    r = run_scenario(sc, progress=progress, engine=engine, workers=workers)
    names = []
    if plot:
        # a figure that draws what one drawn before (same data, same code) is copied from
        # the cache, not rendered again (harness.files.save_figure)
        cache = Path(os.environ.get("DJL_FMU_FIGURES") or cache_dir() / "figures")
        salt = _plot_code_digest()
        names.append(save_figure(r.plot(), staging / f"{stem}.png", cache=cache,
                                 salt=salt).name)
        rob = getattr(r, "robustness", None)
        if rob is not None:
            names.append(save_figure(rob.plot(), staging / f"{stem}-robustness.png",
                                     cache=cache, salt=salt).name)
        deg = r.degradation() if hasattr(r, "degradation") else None
        if deg is not None:
            names.append(save_figure(deg.plot(), staging / f"{stem}-degradation.png",
                                     cache=cache, salt=salt).name)
    return r, names


_PLOT_SOURCES = ("simulation/plots.py", "results.py", "robustness.py", "files.py",
                 "degradation.py")
"""The modules that draw simulate's figures (their digest is in each cached figure's key)."""


@functools.lru_cache(maxsize=1)
def _plot_code_digest() -> str:
    """Digest of the plotting code and of matplotlib's version (a new one may draw otherwise)."""
    import matplotlib  # deferred: matplotlib is heavy to import (pyplot is loaded by now)

    root = Path(__file__).resolve().parents[1]
    h = hashlib.sha256(matplotlib.__version__.encode())
    for name in _PLOT_SOURCES:
        h.update((root / name).read_bytes())
    return h.hexdigest()


def _write_fmus(o: OutputSet) -> None:
    """Add the two FMUs (built from this package, validated) to the default run's outputs.

    The FMUs come from the build cache (:func:`harness.fmu.build.default_fmu`, keyed by a
    hash of the sources, model description and flags: editing the C code rebuilds them);
    validation with fmpy is remembered beside each cached file, keyed by its SHA-256.
    """
    for v in (2, 3):
        cached = default_fmu(v)
        digest = hashlib.sha256(cached.read_bytes()).hexdigest()
        stamp = cached.with_name(cached.name + ".valid")
        if not (stamp.is_file() and stamp.read_text(encoding="utf-8").strip() == digest):
            from fmpy.validation import validate_fmu  # deferred: fmpy is heavy to import

            problems = validate_fmu(str(cached))
            if problems:
                raise CommandError(1, f"{cached} does not validate: " + "; ".join(problems))
            stamp.write_text(digest + "\n", encoding="utf-8")
        shutil.copyfile(cached, o.path(f"JerkLimitedTrajectory-fmi{v}.fmu"))
