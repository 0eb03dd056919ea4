"""``djl-fmu report``: verify the papers' filtering claims, write an HTML report."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..claims import CATALOGUE
from ..fmu.build import BuildError, default_fmu
from ..fmu.runner import check_fmu_binary, check_fmu_variables
from ..peers.ruckig_ref import ruckig_available
from ..report import PEERS_SKIPPED, print_failures, write_report
from ._common import (
    CommandError,
    add_out_option,
    check_out_dir,
    check_out_file,
    interruptible,
    progress_line,
)


def _claim_list(text: str) -> list[int]:
    try:
        out = sorted({int(x) for x in text.replace(" ", "").split(",") if x})
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"--claims takes claim numbers separated by commas, e.g. 1,3 (got {text!r})"
        ) from None
    if not out:
        raise argparse.ArgumentTypeError("--claims: no claim number given")
    return out


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``report`` command."""
    available = ", ".join(f"{n} ({title})" for n, (_m, title) in sorted(CATALOGUE.items()))
    p = sub.add_parser(
        "report",
        help="verify the papers' filtering claims (Bode, impulse, residual vibration) and "
             "write one HTML report",
        description=(
            "Run every claim check of Bearee & Olabi 2013 and Bearee 2014 against the product "
            "(the generator FMU run through fmpy, the harness's flexible-axis mode, "
            "python-control filters) and write one self-contained HTML file: per claim the "
            "paper's statement with its equation / figure number, the figures, the computed "
            "numbers with their tolerances, and PASSED / FAILED. Claims available: "
            f"{available}. Takes a few seconds (the FMU is built on first use)."),
        epilog=(
            "Each check is either a 'product' check (the FMU / harness against the theory it "
            "implements) or a 'paper' check (a quantitative statement of a paper as written). "
            "Exit status: 0 when every product check passes (paper statements that fail are "
            "reported as findings), 1 when a product check fails or a claim cannot be "
            "computed, also when a paper statement fails with --strict; 2 on bad arguments."),
    )
    add_out_option(p, "report", kind="file", default=Path("report.html"))
    p.add_argument("--fast", action="store_true",
                   help="small grids, as in the test suite, and no physical-limit column in "
                        "the peers section (default: full grids, with it)")
    p.add_argument("--claims", type=_claim_list, default=None, metavar="N[,N...]",
                   help="only these claims, e.g. --claims 1,3 (default: all)")
    p.add_argument("--fmi-version", type=int, choices=(2, 3), default=2,
                   help="FMU built from this package's sources and verified (default: 2)")
    p.add_argument("--fmu", type=Path, default=None, metavar="PATH",
                   help="verify this generator FMU file instead (same variables)")
    p.add_argument("--figures-beside", action="store_true",
                   help="write the figures as PNG files in <HTML stem>_files/ instead of "
                        "embedding them")
    p.add_argument("--strict", action="store_true",
                   help="exit 1 if any check fails, paper statements included")
    p.add_argument("--no-peers", action="store_true",
                   help="leave out the section comparing AL/JL/DJL with the peer methods "
                        "(time-optimal JL, Sato, input shapers, damped jerk; needs ruckig)")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress lines (a line per claim as it finishes, on stderr)")
    p.set_defaults(func=interruptible(run))


def run(args: argparse.Namespace) -> int:
    """Run the claims, write the report, print one line per claim.

    A :class:`~harness.errors.CommandError` it raises is reported by
    :func:`harness.cli.main` (message and exit status).
    """
    out: Path = args.out
    check_out_file(out)
    if args.figures_beside:
        check_out_dir(out.with_name(out.stem + "_files"))
    numbers = set(CATALOGUE)
    if args.claims is not None:
        unknown = sorted(set(args.claims) - numbers)
        if unknown:
            raise CommandError(2, f"no claim {unknown}; available: {sorted(numbers)}")
    if args.fmu is not None:
        if not args.fmu.is_file():
            raise CommandError(2, f"--fmu {args.fmu}: no such file")
        try:
            missing = check_fmu_variables(args.fmu)
            check_fmu_binary(args.fmu)
        except ValueError as e:
            raise CommandError(2, f"--fmu {e}") from None
        if missing:
            raise CommandError(2, f"--fmu {args.fmu}: the FMU lacks the generator variables "
                                  + ", ".join(missing))
    else:
        # the package's FMU is built (or found in the cache) now, not inside a claim
        try:
            default_fmu(args.fmi_version)
        except (BuildError, OSError) as e:
            raise CommandError(1, f"cannot build the FMU: {e}") from None
    command = " ".join(
        ["djl-fmu report", "-o", str(out)]
        + (["--fast"] if args.fast else [])
        + (["--claims", ",".join(map(str, args.claims))] if args.claims else [])
        + (["--no-peers"] if args.no_peers else [])
        + (["--fmu", str(args.fmu)] if args.fmu else ["--fmi-version", str(args.fmi_version)]))
    peers = not args.no_peers and args.claims is None
    if peers and not ruckig_available():
        print(f"warning: {PEERS_SKIPPED}", file=sys.stderr, flush=True)
    try:
        summary = write_report(out, fast=args.fast, fmi_version=args.fmi_version,
                               fmu=args.fmu, only=args.claims, embed=not args.figures_beside,
                               progress=not args.quiet, command=command,
                               on_result=lambda r: progress_line(args.quiet, r.summary()),
                               peers=False if args.no_peers else None)
    except OSError as e:
        raise CommandError(1, f"cannot write {out}: {e} (the previous report, if any, is "
                              f"unchanged)") from None
    print()
    print_failures(summary)
    n_ok = sum(r.passed for r in summary.results)
    print(f"\n{n_ok}/{len(summary.results)} claims passed; report: {summary.path} "
          f"({summary.elapsed:.1f} s)")
    if not summary.product_ok:
        raise CommandError(1, "a product check failed or a claim could not be computed")
    if args.strict and not summary.all_passed:
        raise CommandError(1, "a paper statement failed (--strict)")
    return 0
