"""Command line: ``djl-fmu <command> ...``.

Each command lives in its own module of :mod:`harness.commands` exposing
``register(subparsers)``; the command list below is the only place that names
them.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from . import __version__
from .compiled import EngineMissingError
from .errors import CommandError

COMMANDS = ("build", "demo", "simulate", "map", "tune", "online", "report", "compare")

EPILOG = """\
typical use:
  djl-fmu simulate
      the main job: AL/JL/DJL on the paper's default scenarios; tables and plots in
      ./djl-fmu-out/simulate (also writes the two FMUs there)
  djl-fmu simulate my_axis.toml
      your moves and mode map (scenario format: docs/harness.md)
  djl-fmu simulate sweep-X --tuning optimal,robust
      add DJL tuned on the time-varying model (never worse than JL; robust to a map
      error), Table 2 for them too (docs/tuning.md)
  djl-fmu map X
      the workspace map: AL/JL/DJL over 10,000 moves on all cores (or a Dask cluster,
      --scheduler ADDRESS); CSV and heat maps in ./djl-fmu-out/map (docs/map.md)
  djl-fmu tune X --single
      tuned JL/DJL jerk times (DJL robust by default; a [map] grid: one row per move), as a
      CSV the FMU or a controller loads, in ./djl-fmu-out/tune (docs/tune.md)
  djl-fmu online X
      DJL whose jerk times the FMU takes online from f_mode (the mode map at the current Z
      position), against the offline-tuned DJL; in ./djl-fmu-out/online
  djl-fmu build --fmi-version 3 -o out/JerkLimitedTrajectory.fmu
      write an FMI 3.0 co-simulation FMU (binaries for six platforms with the
      [platforms] extra, else for this one; C sources)
  djl-fmu report
      check the papers' filtering claims against the FMU, write report.html
  djl-fmu compare --engine fast
      AL/JL/DJL (paper, optimal, robust) against time-optimal JL, Sato, input shapers on
      AL and JL, a time-varying shaper, damped jerk; worst case under a map error
  djl-fmu demo
      the generator alone: build both FMUs, validate, run the default DJL move

Run 'djl-fmu <command> --help' for the options of a command.
Units are SI throughout (m, s, m/s, m/s2, m/s3, Hz).
"""


DOCS: dict[str, str] = {
    "build": "docs/platforms.md", "demo": "docs/generator.md", "simulate": "docs/harness.md",
    "map": "docs/map.md", "tune": "docs/tune.md", "online": "docs/harness.md",
    "report": "docs/claims.md", "compare": "docs/peers.md",
}
"""Where each command is documented (in the source checkout, and online with the project)."""

SHORT_DESCRIPTION = 400
"""A command's ``--help`` shows its description's first paragraph, cut to about this many
characters; ``--help-full`` shows everything."""


class _FullHelp(argparse.Action):
    """``--help-full``: the command's whole description, options and epilog."""

    def __init__(self, option_strings: list[str], dest: str = argparse.SUPPRESS,
                 default: str = argparse.SUPPRESS, help: str | None = None) -> None:
        super().__init__(option_strings, dest, nargs=0, default=default, help=help)

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: object, option_string: str | None = None) -> None:
        parser.description, parser.epilog, parser.formatter_class = (
            parser._djl_full)  # type: ignore[attr-defined]
        parser.print_help()
        parser.exit()


def _shorten_help(name: str, p: argparse.ArgumentParser) -> None:
    """Make a command's ``--help`` short: first paragraph, options, where to read more."""
    full = (p.description, p.epilog, p.formatter_class)
    p._djl_full = full  # type: ignore[attr-defined]
    first = (p.description or "").strip().split("\n\n")[0]
    first = " ".join(first.split())
    if len(first) > SHORT_DESCRIPTION:
        cut = first[:SHORT_DESCRIPTION]
        first = cut[:cut.rfind(". ") + 1] if ". " in cut else cut.rsplit(" ", 1)[0] + " ..."
    p.description = first
    p.formatter_class = argparse.HelpFormatter
    p.epilog = (f"Inputs, outputs and examples: djl-fmu {name} --help-full; "
                f"documentation: {DOCS.get(name, 'README.md')}.")
    p.add_argument("--help-full", action=_FullHelp,
                   help="the full help: every output file, the scenario keys, examples")


def build_parser(commands: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """Build the argument parser with every available command (or only ``commands``).

    Each command's module is imported to register its options, and some import
    heavy libraries: :func:`main` registers only the command it runs.
    """
    parser = argparse.ArgumentParser(
        prog="djl-fmu",
        description=(
            "Jerk-limited (JL) and dissociated jerk-limited (DJL) trajectory generator as an "
            "FMI 2.0 / 3.0 co-simulation FMU, and a co-simulation harness measuring the residual "
            "vibration it leaves on a flexible axis."
        ),
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="<command>")
    for name in COMMANDS if commands is None else commands:
        try:
            module = importlib.import_module(f"harness.commands.{name}")
        except ModuleNotFoundError as e:
            if e.name == f"harness.commands.{name}":
                continue  # command not available in this build
            raise
        module.register(sub)
    for name, p in sub.choices.items():
        _shorten_help(name, p)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of ``djl-fmu``; returns the exit status."""
    given = sys.argv[1:] if argv is None else list(argv)
    # "djl-fmu simulate ...": only that command's module is imported; anything else (help,
    # --version, an unknown command) builds the whole parser
    parser = build_parser([given[0]] if given and given[0] in COMMANDS else None)
    args = parser.parse_args(given)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except CommandError as e:  # a command stops: its exit status, and why
        print(f"djl-fmu {args.command}: {e}", file=sys.stderr)
        return e.status
    except EngineMissingError as e:  # run from a source checkout without the extension
        print(f"djl-fmu {args.command}: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
