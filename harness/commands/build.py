"""``djl-fmu build``: write a complete co-simulation FMU."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ._common import interruptible


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
    p.add_argument("-o", "--output", type=Path, required=True, metavar="PATH",
                   help="the .fmu file to write")
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
    """Build, validate, report."""
    from ..fmu.build import BuildError, build_fmu, resolve_platforms
    from ._outputs import OutputSet

    out: Path = args.output
    try:
        # built next to the destination, then renamed over it: never a partial file
        with OutputSet(out.parent) as o:
            build_fmu(args.fmi_version, o.path(out.name), platforms=args.platforms,
                      cc=args.cc)
            (path,) = o.commit()
    except BuildError as e:
        print(f"djl-fmu build: {e}", file=sys.stderr)
        return 1
    except OSError as e:
        print(f"djl-fmu build: cannot write {args.output}: {e.strerror or e}", file=sys.stderr)
        return 1
    if not args.no_validate:
        from fmpy.validation import validate_fmu

        problems = validate_fmu(str(path))
        if problems:
            print(f"djl-fmu build: {path} does not validate:", file=sys.stderr)
            for prob in problems:
                print(f"  - {prob}", file=sys.stderr)
            return 1
    names = ", ".join(resolve_platforms(args.platforms))
    print(f"wrote {path} (FMI {args.fmi_version}.0 co-simulation, validated; binaries for "
          f"{names})")
    return 0
