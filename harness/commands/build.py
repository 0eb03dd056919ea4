"""``djl-fmu build``: write a complete co-simulation FMU."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..files import OutputSet
from ..fmu.build import BuildError, build_fmu, resolve_platforms
from ._common import CommandError, add_out_option, interruptible


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``build`` command."""
    p = sub.add_parser(
        "build",
        help="write the generator FMU (FMI 2.0 or 3.0, co-simulation)",
        description=(
            "Cross-compile the generator with zig's clang (PyPI ziglang) and write a "
            "co-simulation FMU holding modelDescription.xml, a binary for each platform "
            "(FMI 3: binaries/x86_64-windows, x86-windows, x86_64-linux, aarch64-linux, "
            "x86_64-darwin, aarch64-darwin; FMI 2: win64, win32, linux64, aarch64-linux and "
            "one universal darwin64) and sources/ from which 'fmpy compile' rebuilds it. "
            "The FMI headers come from the installed fmpy."
        ),
    )
    p.add_argument("--fmi-version", type=int, choices=(2, 3), required=True,
                   help="FMI version of the FMU")
    add_out_option(p, "build", kind="file", required=True)
    p.add_argument("--platforms", default="all", metavar="host|all|LIST",
                   help="platforms to carry binaries for: all (default), host (this "
                        "machine's), or a comma-separated list of FMI 3 platform tuples, "
                        "e.g. x86_64-linux,x86_64-windows")
    p.add_argument("--cc", default=None, metavar="CC",
                   help="a C compiler (e.g. gcc) for the binary of the platform it builds for "
                        "(as 'CC -dumpmachine' says; that platform must be among "
                        "--platforms); the other binaries come from zig (default: zig for all)")
    p.add_argument("--no-validate", action="store_true",
                   help="skip fmpy.validation.validate_fmu on the result")
    p.set_defaults(func=interruptible(run))


def run(args: argparse.Namespace) -> int:
    """Build, validate, report.

    A :class:`~harness.errors.CommandError` it raises is reported by
    :func:`harness.cli.main` (message and exit status).
    """
    out: Path = args.out
    try:
        # built next to the destination, then renamed over it: never a partial file
        with OutputSet(out.parent) as o:
            build_fmu(args.fmi_version, o.path(out.name), platforms=args.platforms,
                      cc=args.cc)
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
    names = ", ".join(resolve_platforms(args.platforms))
    print(f"wrote {path} (FMI {args.fmi_version}.0 co-simulation, validated; binaries for "
          f"{names})")
    return 0
