r"""Part programs: a sequence of moves of the excited axis X and the Z axis.

A part program is read from a CSV file (one move a line, the canonical format)
or from a small G-code subset, and checked whole: every bad line is reported at
once, each message naming the line, the field (or G-code word), the value and
why, and nothing is returned for a program with any error
(:class:`PartProgramError`).  ``docs/programs.md`` is the reference of both
formats; the rules in short:

* **CSV**: a header naming the columns, then one move a line.  ``x`` and ``z``
  (absolute targets, m) are required; ``v_max``, ``a_max``, ``d_max`` (m/s,
  m/s², m/s²; 0: the axis's), ``dwell`` (s after the move) and ``buffer_mode``
  (0/``aborting``, 1/``buffered``, 2/``blending``; default buffered) are
  optional.  ``#`` lines and blank lines are skipped.
* **G-code**: G0, G1 (F in mm/min), G4 (P s), G90/G91, G21, G61/G64, X and Z in
  mm, N, comments, M2/M30; everything else is refused naming the line and the word.
* **Dwell and blending**: a dwell needs the axis at rest, so a blending move
  (which makes the move before it pass its target without stopping) may not
  follow a move with a dwell.

>>> prog = load_part_program("x,z,dwell\n0.4,0.45,0.2\n0,0,0\n")
>>> [(m.line, m.x, m.z, m.dwell, m.buffer_mode) for m in prog.moves]
[(2, 0.4, 0.45, 0.2, 1), (3, 0.0, 0.0, 0.0, 1)]
>>> load_part_program("G21 G90\nG1 X400 Z450 F1200\n").moves[0].v_max
0.02
"""

from __future__ import annotations

import math
import os
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from decimal import Decimal, localcontext
from fractions import Fraction
from importlib import resources
from pathlib import Path
from typing import Any, Literal

import numpy as np

from harness.errors import HarnessError
from harness.files import write_text
from harness.fmu.spec import ENUMERATIONS, MAX_POSITION
from harness.tables import TableMixin

__all__ = ["BUFFER_MODES", "COLUMNS", "EXAMPLE_FILES", "GCODE_SUFFIXES", "PartProgram",
           "PartProgramError", "ProgramMove", "example_path", "example_program",
           "load_part_program"]

Format = Literal["csv", "gcode"]

BUFFER_MODES: dict[str, int] = {name: value for name, value, _ in ENUMERATIONS["BufferMode"]}
"""The FMU's buffer modes by name (``aborting`` 0, ``buffered`` 1, ``blending`` 2)."""
_MODE_NAMES = {v: k for k, v in BUFFER_MODES.items()}

COLUMNS: tuple[str, ...] = ("x", "z", "v_max", "a_max", "d_max", "dwell", "buffer_mode")
"""The CSV columns, in the order :meth:`PartProgram.to_csv` writes them."""
REQUIRED: tuple[str, ...] = ("x", "z")
"""The columns a CSV must have."""
DEFAULTS: dict[str, float | int] = {"v_max": 0.0, "a_max": 0.0, "d_max": 0.0, "dwell": 0.0,
                                    "buffer_mode": BUFFER_MODES["buffered"]}
"""The value of an optional column that is absent, or of an empty cell."""

CSV_SUFFIXES = (".csv",)
GCODE_SUFFIXES = (".nc", ".gcode", ".ngc")
"""File name extensions read as G-code (any case)."""

MAX_BYTES = 256 * 1024 * 1024
"""Largest program file read (a larger one is refused, not read to its end)."""
MAX_SHOWN = 100
"""Most errors a :class:`PartProgramError`'s message lists (``errors`` holds all)."""
MAX_NUMBER_CHARS = 50
"""Longest number of a G-code word (its digits are exact decimals)."""

EXAMPLE_FILES: dict[str, str] = {"csv": "pick-place-X.csv", "gcode": "pick-place-X.nc"}
"""The embedded example program (``harness/programs/``) in each format."""
_EXAMPLE_PACKAGE = "harness.programs"

_NONFINITE = re.compile(r"[+-]?(?:nan|inf|infinity)", re.IGNORECASE)
_WORD = re.compile(r"([A-Za-z])[ \t]*([+-]?(?:\d+(?:\.\d*)?|\.\d+))")
_LINE = re.compile(r"[ \t]*(?:[A-Za-z][ \t]*[+-]?(?:\d+(?:\.\d*)?|\.\d+)[ \t]*)*")


class PartProgramError(HarnessError, ValueError):
    """A part program that cannot be loaded: every problem of it, each naming its line.

    Parameters
    ----------
    source : str
        The file (or ``<text>``).
    errors : sequence of str
        One message a problem, e.g. ``"line 7: v_max = -1: must be a finite number
        >= 0 (0: the axis's)"``, in the order of the lines.

    Attributes
    ----------
    source : str
        The file (or ``<text>``).
    errors : tuple of str
        Every problem found (the message lists the first :data:`MAX_SHOWN`).
    """

    def __init__(self, source: str, errors: Sequence[str]) -> None:
        self.source = source
        self.errors = tuple(errors)
        if len(self.errors) == 1:
            msg = f"{source}: {self.errors[0]}"
        else:
            shown = "\n  ".join(self.errors[:MAX_SHOWN])
            more = len(self.errors) - MAX_SHOWN
            tail = f"\n  ... and {more} more" if more > 0 else ""
            msg = (f"{source}: {len(self.errors)} errors, the program is refused:\n  "
                   f"{shown}{tail}")
        super().__init__(msg)


# ----------------------------------------------------------------- values and rules

def _show(text: Any, width: int = 40) -> str:
    """Show a value in a message: printable, at most ``width`` characters."""
    s = str(text)
    if not s.isprintable():
        s = repr(s)[1:-1]
    return s if len(s) <= width else s[:width - 3] + "..."


def _fmt(v: float) -> str:
    """Write a float so that it reads back equal (``0`` for zeros)."""
    return "0" if v == 0 else repr(float(v))


def _value_problem(name: str, v: float) -> str | None:
    """Why ``v`` is not a valid value of the column ``name`` (None: it is)."""
    if name in ("x", "z"):
        if not math.isfinite(v):
            return "must be a finite number (m)"
        if abs(v) > MAX_POSITION:
            return f"must be within +-{MAX_POSITION:g} m (the largest position a motion reaches)"
        return None
    if name in ("v_max", "a_max", "d_max"):
        if not (math.isfinite(v) and v >= 0):
            return "must be a finite number >= 0 (0: the axis's)"
        return None
    if name == "dwell":
        if not (math.isfinite(v) and v >= 0):
            return "must be a finite number >= 0 (s)"
        return None
    raise KeyError(name)  # pragma: no cover - the columns are fixed


_MODE_RULE = "must be 0 (aborting), 1 (buffered) or 2 (blending)"


def _mode_value(v: Any) -> int | None:
    """Return a buffer mode (number or name) as its number, None if it is none."""
    if isinstance(v, str):
        s = v.strip().lower()
        if s in BUFFER_MODES:
            return BUFFER_MODES[s]
        return int(s) if s in ("0", "1", "2") else None
    if isinstance(v, (bool, np.bool_)):
        return None
    if isinstance(v, (int, np.integer)) and int(v) in _MODE_NAMES:
        return int(v)
    return None


def _blend_problem(dwell_before: float | None, before: str) -> str | None:
    """Why a blending move may not follow ``before``, a move with this dwell (None: it may)."""
    if dwell_before is not None and dwell_before > 0:
        return (f"blending after the dwell of {before} ({_fmt(dwell_before)} s): a "
                "dwell needs the axis at rest, and blending passes the target before it "
                "without stopping: make this move buffered (1)")
    return None


# ----------------------------------------------------------------- the program

@dataclass(frozen=True, kw_only=True)
class ProgramMove:
    """One move of a part program: both axes to their targets, then a dwell.

    Two moves are equal when they move the same way: ``line`` (where the move was
    read) is not compared.

    Parameters
    ----------
    line : int
        Line of the source the move was read from (1-based; 0: not read from a file).
    x, z : float
        Absolute targets of the excited axis X and of the Z axis (m).
    v_max, a_max, d_max : float
        Velocity, acceleration and deceleration limits of the move's command (m/s,
        m/s², m/s²; 0: the axis's own, the scenario's).
    dwell : float
        Time at rest after the move (s, >= 0).
    buffer_mode : int
        How the command follows the move before it: 0 aborting, 1 buffered, 2 blending
        (the FMU's ``buffer_mode`` input; a name is accepted and stored as its number).

    Raises
    ------
    PartProgramError
        If a value is out of its range (every such value named).
    """

    line: int = field(default=0, compare=False)
    x: float
    z: float
    v_max: float = 0.0
    a_max: float = 0.0
    d_max: float = 0.0
    dwell: float = 0.0
    buffer_mode: int = 1

    def __post_init__(self) -> None:
        errors = []
        where = f"line {self.line}" if self.line else "move"
        for name in COLUMNS[:-1]:
            v = getattr(self, name)
            if isinstance(v, (bool, np.bool_)) or not isinstance(
                    v, (int, float, np.integer, np.floating)):
                errors.append(f"{where}: {name} = {_show(v)}: must be a number")
                continue
            object.__setattr__(self, name, float(v))
            problem = _value_problem(name, float(v))
            if problem:
                errors.append(f"{where}: {name} = {_show(v)}: {problem}")
        mode = _mode_value(self.buffer_mode)
        if mode is None:
            errors.append(f"{where}: buffer_mode = {_show(self.buffer_mode)}: {_MODE_RULE}")
        else:
            object.__setattr__(self, "buffer_mode", mode)
        if errors:
            raise PartProgramError("<ProgramMove>", errors)

    def row(self) -> dict[str, float | int]:
        """Return the move as a plain row: ``line``, then the :data:`COLUMNS`."""
        return {"line": self.line, **{k: getattr(self, k) for k in COLUMNS}}


@dataclass(frozen=True)
class PartProgram(TableMixin):
    """A checked part program: its moves, where it came from, where it starts.

    Two programs are equal when their moves and start positions are: ``source``
    and ``format`` (where it was read from) are not compared, so a G-code program
    equals the CSV it converts to.

    Parameters
    ----------
    moves : tuple of ProgramMove
        The moves, in order (at least one).
    source : str
        The file read, or ``"<text>"``.
    format : {"csv", "gcode"}
        The format it was read from.
    x0, z0 : float
        Start position of X and Z (m): the program starts there, at rest.

    Raises
    ------
    PartProgramError
        If there is no move, a start position is out of range, or a blending move
        follows a move with a dwell.
    """

    moves: tuple[ProgramMove, ...]
    source: str = field(default="<text>", compare=False)
    format: Format = field(default="csv", compare=False)
    x0: float = 0.0
    z0: float = 0.0

    def __post_init__(self) -> None:
        try:
            moves = tuple(self.moves)
        except TypeError:
            raise PartProgramError(self.source, [f"moves = {_show(self.moves)}: not a sequence "
                                                 "of ProgramMove"]) from None
        object.__setattr__(self, "moves", moves)
        errors = _start_problems(self.x0, self.z0)
        if not errors:
            object.__setattr__(self, "x0", float(self.x0))
            object.__setattr__(self, "z0", float(self.z0))
        if not moves:
            errors.append("no moves: a program needs at least one")
        for k, m in enumerate(moves):
            if not isinstance(m, ProgramMove):
                errors.append(f"moves[{k}] = {_show(m)}: not a ProgramMove")
            elif k and m.buffer_mode == BUFFER_MODES["blending"] and isinstance(
                    moves[k - 1], ProgramMove):
                problem = _blend_problem(moves[k - 1].dwell, _where(moves[k - 1], k - 1))
                if problem:
                    errors.append(f"{_where(m, k)}: buffer_mode = blending: {problem}")
        if self.format not in ("csv", "gcode"):
            errors.append(f"format = {_show(self.format)}: must be 'csv' or 'gcode'")
        if errors:
            raise PartProgramError(self.source, errors)

    def __len__(self) -> int:
        return len(self.moves)

    def rows(self) -> list[dict[str, Any]]:
        """Return the moves as plain rows (``line``, ``x``, ``z``, ... ``buffer_mode``)."""
        return [m.row() for m in self.moves]

    def table(self) -> dict[str, np.ndarray]:
        """Return the moves as columns of arrays (those of :meth:`rows`)."""
        return self.to_table()

    def csv_text(self) -> str:
        """Return the program in the canonical CSV format (what :meth:`to_csv` writes).

        Every number is written so that it reads back equal; the buffer modes by
        name.  The start position is in the comment line only: give ``x0`` and
        ``z0`` to :func:`load_part_program` again.
        """
        head = (f"# part program: {len(self.moves)} moves, from {_show(self.source, 200)} "
                f"({self.format}); starts at x0 = {_fmt(self.x0)} m, z0 = {_fmt(self.z0)} m\n"
                "# x, z: absolute targets (m); v_max (m/s), a_max, d_max (m/s2): 0 = the "
                "axis's; dwell (s) after the move; buffer_mode: aborting, buffered, blending\n")
        lines = [",".join(COLUMNS)]
        for m in self.moves:
            lines.append(",".join([*(_fmt(getattr(m, k)) for k in COLUMNS[:-1]),
                                   _MODE_NAMES[m.buffer_mode]]))
        return head + "\n".join(lines) + "\n"

    def to_csv(self, path: str | os.PathLike[str]) -> Path:
        """Write the program as a canonical CSV file (whole, or not at all).

        Parameters
        ----------
        path : path-like
            The file to write.

        Returns
        -------
        Path
            The file written; :func:`load_part_program` reads it back to an equal
            program (with the same ``x0``, ``z0``).
        """
        return write_text(path, self.csv_text())


def _checked_move(**values: Any) -> ProgramMove:
    """Make a move of values the parser has checked (by the rules ProgramMove applies)."""
    move = object.__new__(ProgramMove)
    for name in ("line", *COLUMNS):
        object.__setattr__(move, name, values[name])
    return move


def _where(m: ProgramMove, k: int) -> str:
    """Name a move: its line, or its place when it was not read from a file."""
    return f"line {m.line}" if m.line else f"move {k + 1}"


def _start_problems(x0: Any, z0: Any) -> list[str]:
    errors = []
    for name, v in (("x0", x0), ("z0", z0)):
        if isinstance(v, (bool, np.bool_)) or not isinstance(
                v, (int, float, np.integer, np.floating)):
            errors.append(f"{name} = {_show(v)}: must be a number (m)")
        elif (problem := _value_problem("x", float(v))) is not None:
            errors.append(f"{name} = {_show(v)}: {problem}")
    return errors


# ----------------------------------------------------------------- reading

def _read(source: str | os.PathLike[str] | bytes) -> tuple[str, str, str]:
    """(name, text, suffix) of a source: a path, or the program's text itself."""
    if isinstance(source, (bytes, bytearray)):
        return "<text>", _decode(bytes(source), "<text>"), ""
    if isinstance(source, str) and ("\n" in source or "\r" in source or not source.strip()):
        return "<text>", _nul_checked(source, "<text>"), ""
    if not isinstance(source, (str, os.PathLike)):
        raise PartProgramError(repr(source)[:80], ["not a path, nor the text of a program"])
    path = Path(source)
    name = str(path)
    try:
        with open(path, "rb") as fh:
            data = fh.read(MAX_BYTES + 1)
    except FileNotFoundError:
        raise PartProgramError(name, ["no such file (a program's text must hold a line "
                                      "break to be read as text)"]) from None
    except OSError as e:
        raise PartProgramError(name, [f"cannot read: {e.strerror or e}"]) from None
    if len(data) > MAX_BYTES:
        raise PartProgramError(name, [f"larger than {MAX_BYTES} bytes: not a part program"])
    return name, _decode(data, name), path.suffix.lower()


def _decode(data: bytes, name: str) -> str:
    try:
        text = data.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        line = len(_lines(data[:e.start].decode("utf-8", "replace")))
        raise PartProgramError(name, [f"line {line}: not UTF-8 text (byte 0x{data[e.start]:02x} "
                                      f"at offset {e.start}): a part program is UTF-8 text"]
                               ) from None
    return _nul_checked(text, name)


def _nul_checked(text: str, name: str) -> str:
    k = text.find("\x00")
    if k >= 0:
        line = len(_lines(text[:k]))
        raise PartProgramError(name, [f"line {line}: a NUL character: not a text file"])
    return text


def _lines(text: str) -> list[str]:
    """Split a text into lines (breaks: LF, CR LF or CR), numbered from 1 by position."""
    return text.replace("\r\n", "\n").replace("\r", "\n").split("\n")


def _sniff(lines: Iterable[str]) -> Format:
    """Guess a text's format: CSV if its first line of data has a comma, else G-code."""
    for raw in lines:
        s = raw.strip()
        if not s or s.startswith("#"):
            continue
        return "csv" if "," in s and not s.startswith(("(", ";", "%")) else "gcode"
    return "csv"


# ----------------------------------------------------------------- CSV

def _csv_number(text: str) -> float | None:
    """Read a CSV number (decimal, optional exponent; nan, inf), None if it is none."""
    try:
        v = float(text)
    except ValueError:
        return None
    if "_" in text or not text.isascii():  # float() also reads 1_0 and other digits
        return None
    return v


def _parse_csv(lines: list[str]) -> tuple[list[ProgramMove], list[tuple[int, str]]]:
    errors: list[tuple[int, str]] = []
    moves: list[ProgramMove] = []
    header: list[str] | None = None
    header_line = 0
    prev: tuple[int, float | None] | None = None  # (line, dwell) of the row before
    for i, raw in enumerate(lines, 1):
        s = raw.strip()
        if not s or s.startswith("#"):
            continue
        if header is None:
            header, header_line = [c.strip().lower() for c in s.split(",")], i
            problems = _header_problems(header, s.split(","))
            if problems:  # the rows cannot be read without their columns
                return [], [(i, f"line {i}: the header: {p}") for p in problems]
            continue
        cells = [c.strip() for c in s.split(",")]
        if len(cells) != len(header):
            errors.append((i, f"line {i}: {len(cells)} values for the {len(header)} columns of "
                              f"the header (line {header_line}): {_show(s, 60)}"))
            prev = (i, None)
            continue
        values: dict[str, Any] = {}
        bad = False
        for name, cell in zip(header, cells, strict=True):
            if cell == "":
                if name in REQUIRED:
                    errors.append((i, f"line {i}: {name} is empty: a target is required"))
                    bad = True
                else:
                    values[name] = DEFAULTS[name]
                continue
            if name == "buffer_mode":
                mode = _mode_value(cell)
                if mode is None:
                    errors.append((i, f"line {i}: buffer_mode = {_show(cell)}: {_MODE_RULE} "
                                      "(or the name)"))
                    bad = True
                values[name] = mode
                continue
            v = _csv_number(cell)
            problem = "not a number" if v is None else _value_problem(name, v)
            if problem and v is not None and not math.isfinite(v) and not _NONFINITE.fullmatch(
                    cell):
                problem += " (it overflows a double)"
            if problem:
                errors.append((i, f"line {i}: {name} = {_show(cell)}: {problem}"))
                bad = True
                v = None
            values[name] = v
        mode = values.get("buffer_mode", DEFAULTS["buffer_mode"])
        if prev is not None and mode == BUFFER_MODES["blending"]:
            problem = _blend_problem(prev[1], f"line {prev[0]}")
            if problem:
                cell = cells[header.index("buffer_mode")]
                errors.append((i, f"line {i}: buffer_mode = {_show(cell)}: {problem}"))
                bad = True
        prev = (i, values.get("dwell", DEFAULTS["dwell"]))
        if not bad:
            moves.append(_checked_move(line=i, **{**DEFAULTS, **values}))
    if header is None:
        errors.append((0, "no header line (its columns: x,z and any of v_max, a_max, d_max, "
                          "dwell, buffer_mode) and no moves"))
    elif not moves and not errors:
        errors.append((header_line, f"line {header_line}: the header, and no move after it: "
                                    "a program needs at least one move"))
    return moves, errors


def _header_problems(names: list[str], raw: list[str]) -> list[str]:
    if all(_csv_number(n) is not None for n in names):
        return [f"{_show(','.join(raw), 60)} looks like a move: the first line that is not a "
                "comment names the columns (x,z and any of " + ", ".join(COLUMNS[2:]) + ")"]
    problems = []
    for k, n in enumerate(names):
        if not n:
            problems.append(f"column {k + 1} has no name")
    unknown = [_show(r.strip()) for n, r in zip(names, raw, strict=True) if n and n not in COLUMNS]
    if unknown:
        problems.append(f"unknown column{'s' if len(unknown) > 1 else ''} "
                        f"{', '.join(unknown)}: the columns are {', '.join(COLUMNS)}")
    dups = sorted({n for n in names if n and names.count(n) > 1})
    if dups:
        problems.append(f"column{'s' if len(dups) > 1 else ''} {', '.join(dups)} "
                        "named twice")
    missing = [n for n in REQUIRED if n not in names]
    if missing:
        problems.append(f"no column {' or '.join(missing)} (x and z are required)")
    return problems


# ----------------------------------------------------------------- G-code

_G_SUPPORTED = "G0, G1, G4, G21, G61, G64, G90, G91"
_G_GROUPS = {0: "motion", 1: "motion", 4: "motion", 21: "units", 61: "path", 64: "path",
             90: "distance", 91: "distance"}
_G_REFUSED = {
    2: "arcs are not supported (G0 and G1 only)",
    3: "arcs are not supported (G0 and G1 only)",
    20: "inches are not supported: millimetres (G21) only",
}
_LETTER_REFUSED = {
    "Y": "only the X and Z axes are programmed",
    "S": "spindle speeds are not supported",
    "T": "tool changes are not supported",
    "I": "arcs are not supported", "J": "arcs are not supported",
    "K": "arcs are not supported", "R": "arcs are not supported",
    "O": "program numbers and subroutines are not supported",
}
_M_END = (2, 30)
_ZERO = Decimal(0)
_M_REFUSED = {0: "program stops are not supported", 1: "program stops are not supported",
              3: "spindles are not supported", 4: "spindles are not supported",
              5: "spindles are not supported", 6: "tool changes are not supported",
              7: "coolant is not supported", 8: "coolant is not supported",
              9: "coolant is not supported"}


@dataclass
class _GState:
    """The modal state of a G-code program as it is read."""

    x: tuple[Decimal, float]  # (mm, exact; m, float) of the last target
    z: tuple[Decimal, float]
    motion: int | None = None  # 0 or 1, modal
    incremental: bool = False
    blending: bool = False  # G64 in force
    feed: Decimal | None = None  # mm/min
    v_max: float = 0.0  # the feed in m/s
    last_g: int | None = None  # the motion word of the last move (0 or 1)
    end_line: int = 0  # the M2 / M30 line


def _strip_comments(s: str) -> tuple[str, str | None]:
    """Remove a line's comments; say why if its parentheses do not close."""
    if "(" not in s and ")" not in s and ";" not in s:
        return s, None
    out = []
    k = 0
    while k < len(s):
        c = s[k]
        if c == ";":
            break
        if c == "(":
            end = s.find(")", k + 1)
            if end < 0:
                return "", "a comment '(' is not closed on its line"
            k = end + 1
            out.append(" ")
            continue
        if c == ")":
            return "", "a ')' with no '(' before it"
        out.append(c)
        k += 1
    return "".join(out), None


def _words(s: str) -> tuple[list[tuple[str, str]], str | None]:
    """Split a line into words (letter upper case, number text); say why at a bad one."""
    if _LINE.fullmatch(s):  # well formed: every word at once
        words = [(letter.upper(), number) for letter, number in _WORD.findall(s)]
        long = next((f"{a}{n}" for a, n in words if len(n) > MAX_NUMBER_CHARS), None)
        if long is None:
            return words, None
    words = []
    k = 0
    while k < len(s):
        if s[k] in " \t":
            k += 1
            continue
        m = _WORD.match(s, k)
        if not m or (m.end() < len(s) and (s[m.end()].isdigit() or s[m.end()] == ".")):
            bad = re.match(r"\S+?(?=[A-Za-z][^A-Za-z]|\s|$)", s[k:]) or re.match(r"\S+", s[k:])
            token = bad.group(0) if bad else s[k:]
            if s[k].isalpha():
                return words, (f"{_show(token)}: malformed word (a letter and a number: digits, "
                               "a point, a sign; no exponent)")
            return words, f"{_show(token)}: not a word (a letter and a number)"
        number = m.group(2)
        if len(number) > MAX_NUMBER_CHARS:
            return words, (f"{_show(m.group(0))}: a number of more than {MAX_NUMBER_CHARS} "
                           "characters")
        words.append((m.group(1).upper(), number))
        k = m.end()
    return words, None


def _collapsed(messages: list[str]) -> list[str]:
    """Say each message of a line once, with how many times it came."""
    counts: dict[str, int] = {}
    for m in messages:
        counts[m] = counts.get(m, 0) + 1
    return [m if n == 1 else f"{m} ({n} times on the line)" for m, n in counts.items()]


def _gword(letter: str, number: str) -> str:
    return _show(letter + number, MAX_NUMBER_CHARS + 4)


def _parse_gcode(lines: list[str], x0: float, z0: float
                 ) -> tuple[list[ProgramMove], list[tuple[int, str]]]:
    # the positions in mm are exact decimals: enough digits for a double's exact value
    # (x0, z0) and sums of 50-character numbers, so the metres are rounded once
    with localcontext() as ctx:
        ctx.prec = 2000
        return _gcode_moves(lines, x0, z0)


def _gcode_moves(lines: list[str], x0: float, z0: float
                 ) -> tuple[list[ProgramMove], list[tuple[int, str]]]:
    errors: list[tuple[int, str]] = []
    # each move as a dict until its dwell is known (G4 lines after it add to it)
    moves: list[dict[str, Any]] = []
    # the start as the decimal its float prints as (0.3, not 0.29999999999999998889...)
    st = _GState(x=(Decimal(repr(x0)).scaleb(3), x0), z=(Decimal(repr(z0)).scaleb(3), z0))
    blend = BUFFER_MODES["blending"]
    buffered = BUFFER_MODES["buffered"]
    for i, raw in enumerate(lines, 1):
        s = raw.strip()
        if not s or s == "%":
            continue
        body, problem = _strip_comments(s)
        if problem:
            errors.append((i, f"line {i}: {problem}"))
            continue
        words, problem = _words(body)
        line_errors = [f"line {i}: {problem}"] if problem else []
        if not words and not problem:
            continue  # a comment line
        if st.end_line:
            errors.append((i, f"line {i}: {_gword(*words[0]) if words else _show(body)}: after "
                              f"the end of the program (line {st.end_line}): remove it, or "
                              "the end"))
            continue
        seen: dict[str, str] = {}  # letter -> the word as written (G: the last)
        gs: dict[str, tuple[int, str]] = {}  # modal group -> (G number, word)
        end = False
        values: dict[str, Decimal] = {}
        for letter, number in words:
            word = letter + number  # printable: the number matched _WORD
            if letter in seen and letter != "G":
                line_errors.append(f"line {i}: {word}: {letter} more than once on the line "
                                   f"({seen[letter]} before)")
                continue
            seen[letter] = word
            value = Decimal(number)
            whole = value == value.to_integral_value()
            if letter == "N":
                continue
            if letter == "G":
                g = int(value) if whole else None
                if g is None or g not in _G_GROUPS:
                    why = _G_REFUSED.get(g if g is not None else -1,
                                         f"not supported (the G codes: {_G_SUPPORTED})")
                    line_errors.append(f"line {i}: {word}: {why}")
                    continue
                group = _G_GROUPS[g]
                if group in gs:
                    line_errors.append(f"line {i}: {word}: a second {group} word on the line "
                                       f"({gs[group][1]} before)")
                    continue
                gs[group] = (g, word)
            elif letter == "M":
                if not whole or int(value) not in _M_END:
                    m = int(value) if whole else -1
                    line_errors.append(f"line {i}: {word}: {_M_REFUSED.get(m, 'not supported')} "
                                       "(M2 and M30 only, the end of the program)")
                    continue
                end = True
            elif letter in ("X", "Z"):
                values[letter] = value
            elif letter == "F":
                if value <= 0:
                    line_errors.append(f"line {i}: {word}: a feed rate must be > 0 (mm/min)")
                    continue
                values["F"] = value
            elif letter == "P":
                if value < 0:
                    line_errors.append(f"line {i}: {word}: a dwell must be >= 0 s")
                    continue
                values["P"] = value
            else:
                why = _LETTER_REFUSED.get(letter, f"{letter} words are not supported")
                line_errors.append(f"line {i}: {word}: {why}")
        # the modal words first (as a CNC reads a block), then the dwell or the move
        if "F" in values and values["F"] != st.feed:
            st.feed = values["F"]  # mm/min to m/s, rounded once
            st.v_max = float(Fraction(st.feed) / 60000)
        if "path" in gs:
            st.blending = gs["path"][0] == 64
        if "distance" in gs:
            st.incremental = gs["distance"][0] == 91
        motion, motion_word = gs.get("motion", (None, ""))
        axes = [k for k in ("X", "Z") if k in values]
        if motion == 4:
            if "P" not in seen:
                line_errors.append(f"line {i}: {motion_word}: a dwell needs P (seconds)")
            for k in axes:
                line_errors.append(f"line {i}: {seen[k]}: no axis word with G4 (a dwell)")
        else:
            if "P" in seen:
                line_errors.append(f"line {i}: {seen['P']}: P only with G4 (the dwell in "
                                   "seconds)")
            if motion is not None:
                st.motion = motion
            if line_errors:
                pass  # a bad word: its consequences (no mode, no feed) are not reported
            elif axes and st.motion is None:
                line_errors.append(f"line {i}: {seen[axes[0]]}: no motion mode yet: G0 or G1 "
                                   "first")
            elif axes and st.motion == 1 and st.feed is None:
                line_errors.append(f"line {i}: {motion_word or seen[axes[0]]}: G1 with no feed "
                                   "rate: give F (mm/min) on this line or before")
        target: dict[str, tuple[Decimal, float]] = {}
        for k in axes:
            base = st.x[0] if k == "X" else st.z[0]
            mm = base + values[k] if st.incremental else values[k]
            m = float(mm.scaleb(-3))
            if not math.isfinite(m) or abs(m) > MAX_POSITION:
                line_errors.append(f"line {i}: {seen[k]}: the target {k.lower()} = {m:g} m is "
                                   f"beyond +-{MAX_POSITION:g} m")
            target[k] = (mm, m)
        if line_errors:
            errors.extend((i, e) for e in _collapsed(line_errors))
            if end:
                st.end_line = i
            continue
        if motion == 4:
            dwell = values.get("P", _ZERO)
            if not moves:  # a dwell at the start: a move to where the axes are, then it
                moves.append({"line": i, "x": st.x[1], "z": st.z[1], "v_max": 0.0,
                              "buffer_mode": buffered, "dwell": _ZERO})
                st.last_g = 0
            moves[-1]["dwell"] += dwell
            moves[-1]["stop"] = True  # a G4, even P0, is an exact stop
        elif axes:
            st.x = target.get("X", st.x)
            st.z = target.get("Z", st.z)
            g1 = st.motion == 1
            mode = buffered
            if (g1 and st.blending and st.last_g == 1 and moves
                    and not moves[-1].get("stop")):
                mode = blend
            v_max = st.v_max if g1 else 0.0
            moves.append({"line": i, "x": st.x[1], "z": st.z[1], "v_max": v_max,
                          "buffer_mode": mode, "dwell": _ZERO})
            st.last_g = st.motion
        if end:
            st.end_line = i
    out: list[ProgramMove] = []
    if not errors:
        for m in moves:
            m.pop("stop", None)
            out.append(_checked_move(**{**DEFAULTS, **m, "dwell": float(m["dwell"])}))
        if not out:
            errors.append((0, "no moves (a G0 or G1 with X or Z): a program needs at least one"))
    return out, errors


# ----------------------------------------------------------------- loading

def load_part_program(source: str | os.PathLike[str] | bytes, *, x0: float = 0.0,
                      z0: float = 0.0, fmt: Format | None = None) -> PartProgram:
    """Load and check a part program: a CSV file or a G-code subset (``docs/programs.md``).

    Parameters
    ----------
    source : str, path-like or bytes
        A path, or the program's text itself (a ``str`` holding a line break, or
        ``bytes``).
    x0, z0 : float
        Where X and Z start (m): the G-code's incremental moves, its moves that
        leave an axis unnamed and a dwell before the first move start there.
    fmt : {"csv", "gcode"}, optional
        The format; by default the file's extension (``.csv``; ``.nc``, ``.gcode``,
        ``.ngc``), and for a text its first line of data (a comma: CSV).

    Returns
    -------
    PartProgram
        The moves, checked.

    Raises
    ------
    PartProgramError
        With every problem found, each naming its line, the field or word, the value
        and why; also for a file that cannot be read or is not UTF-8 text.
    """
    name, text, suffix = _read(source)
    if fmt is None:
        if suffix in CSV_SUFFIXES:
            fmt = "csv"
        elif suffix in GCODE_SUFFIXES:
            fmt = "gcode"
        elif name != "<text>":
            raise PartProgramError(name, [
                f"unknown extension {_show(suffix or '(none)')}: name the format "
                f"(fmt='csv' or 'gcode'), or use .csv or {', '.join(GCODE_SUFFIXES)}"])
    elif fmt not in ("csv", "gcode"):
        raise PartProgramError(name, [f"fmt = {_show(fmt)}: must be 'csv' or 'gcode'"])
    return _load_text(text, name, fmt, x0, z0)


def _load_text(text: str, name: str, fmt: Format | None, x0: float, z0: float) -> PartProgram:
    start = _start_problems(x0, z0)
    if start:
        raise PartProgramError(name, start)
    lines = _lines(text)
    if not text.strip():
        raise PartProgramError(name, ["empty: no moves"])
    fmt = fmt or _sniff(lines)
    x0, z0 = float(x0), float(z0)
    moves, errors = _parse_csv(lines) if fmt == "csv" else _parse_gcode(lines, x0, z0)
    if errors:
        errors.sort(key=lambda e: e[0])  # stable: a line's problems in the order found
        raise PartProgramError(name, [e for _, e in errors])
    return PartProgram(tuple(moves), source=name, format=fmt, x0=x0, z0=z0)


def example_path(fmt: Format = "csv") -> Any:
    """Return the embedded example program's file (a :class:`importlib.resources` entry).

    Parameters
    ----------
    fmt : {"csv", "gcode"}
        Which of its two files.

    Returns
    -------
    importlib.resources.abc.Traversable
        ``harness/programs/pick-place-X.csv`` or ``pick-place-X.nc``.
    """
    return resources.files(_EXAMPLE_PACKAGE).joinpath(EXAMPLE_FILES[fmt])


def example_program(fmt: Format = "csv") -> PartProgram:
    """Return the embedded example: a pick-and-place cycle on scenario X's machine.

    Four parts picked at x = 0 and placed at x = 0.4, 0.3, 0.2 and 0.1 m, Z
    descending 0.45 m to pick and to place (scenario X's move: X travels while Z
    descends, the mode dropping from 8.5 to 6.6 Hz), 21 moves from x0 = z0 = 0
    (``docs/programs.md``).  The CSV and the G-code files load to equal programs.

    Parameters
    ----------
    fmt : {"csv", "gcode"}
        Which file to read (the programs are equal).

    Returns
    -------
    PartProgram
    """
    entry = example_path(fmt)
    return _load_text(entry.read_text(encoding="utf-8"), f"<embedded {EXAMPLE_FILES[fmt]}>",
                      fmt, 0.0, 0.0)
