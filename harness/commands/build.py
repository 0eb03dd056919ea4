"""``djl-fmu build``: write a complete co-simulation FMU."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..files import OutputSet
from ..fmu.build import (
    ALL_PLATFORMS,
    PLATFORMS_HINT,
    ZIG,
    BuildError,
    build_fmu,
    compilers,
    default_platforms,
    resolve_platforms,
    zig_available,
)
from ._common import CommandError, add_out_option, interruptible


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``build`` command."""
    p = sub.add_parser(
        "build",
        help="write the generator FMU (FMI 2.0 or 3.0, co-simulation)",
        description=(
            "Write a co-simulation FMU holding modelDescription.xml, binaries and sources/ "
            "from which 'fmpy compile' rebuilds it (FMI headers from the installed fmpy). "
            "With the optional cross compiler (pip install '.[platforms]': PyPI ziglang) it "
            "carries a binary for each of six platforms (FMI 3: x86_64-windows, x86-windows, "
            "x86_64-linux, aarch64-linux, x86_64-darwin, aarch64-darwin; FMI 2: win64, win32, "
            "linux64, aarch64-linux, one universal darwin64); without it, this machine's "
            "binary, compiled by the C compiler found ($CC, gcc, cc or clang). "
            "Details: docs/platforms.md."
        ),
    )
    p.add_argument("--fmi-version", type=int, choices=(2, 3), required=True,
                   help="FMI version of the FMU")
    add_out_option(p, "build", kind="file", required=True)
    p.add_argument("--platforms", default=None, metavar="host|all|LIST",
                   help="platforms to carry binaries for: all, host (this machine's), or a "
                        "comma-separated list of FMI 3 platform tuples, e.g. "
                        "x86_64-linux,x86_64-windows (default: all when ziglang is installed, "
                        f"else host; here: {default_platforms()})")
    p.add_argument("--cc", default=None, metavar="CC",
                   help="a C compiler (e.g. gcc) for the binary of the platform it builds for "
                        "(as 'CC -dumpmachine' says; that platform must be among "
                        "--platforms); the other binaries come from zig (default: zig for all; "
                        "without ziglang, the compiler found: $CC, gcc, cc or clang)")
    p.add_argument("--no-validate", action="store_true",
                   help="skip fmpy.validation.validate_fmu on the result")
    p.add_argument("-q", "--quiet", action="store_true",
                   help="no progress lines (the result line and errors still print)")
    p.set_defaults(func=interruptible(run))


def run(args: argparse.Namespace) -> int:
    """Build, validate, report.

    A :class:`~harness.errors.CommandError` it raises is reported by
    :func:`harness.cli.main` (message and exit status).
    """
    out: Path = args.out
    platforms = args.platforms or default_platforms()
    quiet = getattr(args, "quiet", False)

    def say(line: str) -> None:
        if not quiet:
            print(line, flush=True)

    try:
        names = resolve_platforms(platforms)
        ccs = compilers(names, args.cc)
        compilers_used = ", ".join(sorted({"zig" if c == ZIG else c for c in ccs.values()}))
        say(f"building the FMI {args.fmi_version}.0 FMU for {', '.join(names)} "
            f"({compilers_used})")
        # built next to the destination, then renamed over it: never a partial file
        with OutputSet(out.parent) as o:
            build_fmu(args.fmi_version, o.path(out.name), platforms=names, cc=args.cc,
                      progress=say)
            (path,) = o.commit()
    except BuildError as e:
        raise CommandError(1, str(e)) from None
    except OSError as e:
        raise CommandError(1, f"cannot write {out}: {e.strerror or e}") from None
    if not args.no_validate:
        from fmpy.validation import validate_fmu  # deferred: fmpy is heavy to import

        problems = validate_fmu(str(path))
        if problems:
            raise CommandError(1, f"{path} does not validate:\n"
                                  + "\n".join(f"  - {prob}" for prob in problems))
    checked = "" if args.no_validate else ", validated"
    print(f"wrote {path} (FMI {args.fmi_version}.0 co-simulation{checked}; binaries for "
          f"{', '.join(names)})")
    if len(names) < len(ALL_PLATFORMS) and not zig_available():
        print(f"this machine's binary only: {PLATFORMS_HINT}")
    return 0
