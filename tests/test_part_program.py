"""Issue 35 item 1: the part-program format (CSV, a G-code subset) and its checks.

The expected moves are written by hand, not computed by the parser.  Every bad
input is a :class:`PartProgramError` naming the line, the field or word and the
value, every bad line of a file at once; nothing else escapes (hostile inputs).
"""

from __future__ import annotations

import math
import random
import time
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from harness.errors import HarnessError
from harness.part_program import (
    COLUMNS,
    EXAMPLE_FILES,
    MAX_SHOWN,
    PartProgram,
    PartProgramError,
    ProgramMove,
    example_path,
    example_program,
    load_part_program,
)


def M(line: int, x: float, z: float, v_max: float = 0.0, dwell: float = 0.0,
      mode: int = 1, a_max: float = 0.0, d_max: float = 0.0) -> ProgramMove:
    return ProgramMove(line=line, x=x, z=z, v_max=v_max, a_max=a_max, d_max=d_max,
                       dwell=dwell, buffer_mode=mode)


def refused(source, **kw) -> PartProgramError:
    with pytest.raises(PartProgramError) as ei:
        load_part_program(source, **kw)
    return ei.value


def fields(move: ProgramMove) -> tuple:
    return (move.line, move.x, move.z, move.v_max, move.a_max, move.d_max, move.dwell,
            move.buffer_mode)


# ------------------------------------------------------------------ CSV

CSV = """\
# a comment, then a blank line

x,z,v_max,a_max,d_max,dwell,buffer_mode
0.4,0.45,0.5,4,3,0.2,buffered
  # an indented comment
0,0.45,0,0,0,0,0
0.1, 0 , 0.25 ,0,0,0,BLENDING
-0.2,0.1,0,2.5,0,1.5,1
"""


def test_csv_reads_the_moves_written():
    prog = load_part_program(CSV)
    assert [fields(m) for m in prog.moves] == [
        (4, 0.4, 0.45, 0.5, 4.0, 3.0, 0.2, 1),
        (6, 0.0, 0.45, 0.0, 0.0, 0.0, 0.0, 0),
        (7, 0.1, 0.0, 0.25, 0.0, 0.0, 0.0, 2),
        (8, -0.2, 0.1, 0.0, 2.5, 0.0, 1.5, 1),
    ]
    assert prog.format == "csv" and prog.source == "<text>" and (prog.x0, prog.z0) == (0, 0)
    assert len(prog) == 4


def test_csv_optional_columns_default_and_any_order():
    prog = load_part_program("dwell,Z,X\n0.5,0.2,0.1\n,0.3,0.2\n")
    assert prog.moves == (M(2, 0.1, 0.2, dwell=0.5), M(3, 0.2, 0.3))
    assert [m.buffer_mode for m in prog.moves] == [1, 1]  # buffered by default
    # an empty optional cell is its default
    prog = load_part_program("x,z,v_max,buffer_mode\n1,2,,\n")
    assert fields(prog.moves[0]) == (2, 1.0, 2.0, 0.0, 0.0, 0.0, 0.0, 1)


def test_csv_line_breaks_bom_and_numbers():
    text = "\ufeffx,z\r\n1e-3,+.5\r\n\r\n5.,-0\r\n"
    prog = load_part_program(text.encode("utf-8"))
    assert prog.moves == (M(2, 0.001, 0.5), M(4, 5.0, 0.0))
    assert [m.line for m in prog.moves] == [2, 4]
    assert [m.line for m in load_part_program("x,z\r1,2\r\r3,4").moves] == [2, 4]


def test_csv_first_blending_move_and_blending_last_move_are_accepted():
    # the first: nothing before it, it starts from rest (as buffered); the last lands at rest
    prog = load_part_program("x,z,buffer_mode\n0.1,0,blending\n0.2,0,2\n")
    assert [m.buffer_mode for m in prog.moves] == [2, 2]


# ------------------------------------------------------------------ G-code

GCODE = """\
%
(a pick: the words of the subset)
N10 g21 g90 G64 ; lower case is read
N20 G0 Z450
N30 G4 P0.2
N40 Z0                   (modal G0)
N50 G01 X200 F30000
N60 X400 Z450            (G1 after G1 under G64: blending)
N70 G4 P0.1
N80 G4 P0.05             (dwells add up)
N90 G1 X300 F1200        (after a dwell: buffered)
N100 G61 X250            (exact stop: buffered)
N110 G0 X0 Z0
N120 M30
(after the end: comments only)
%
"""


def test_gcode_reads_the_moves_written():
    prog = load_part_program(GCODE, fmt="gcode")
    assert [fields(m) for m in prog.moves] == [
        (4, 0.0, 0.45, 0.0, 0.0, 0.0, 0.2, 1),
        (6, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1),
        (7, 0.2, 0.0, 0.5, 0.0, 0.0, 0.0, 1),  # after a G0: buffered
        (8, 0.4, 0.45, 0.5, 0.0, 0.0, 0.15, 2),  # 0.1 + 0.05 s, exactly
        (11, 0.3, 0.45, 0.02, 0.0, 0.0, 0.0, 1),
        (12, 0.25, 0.45, 0.02, 0.0, 0.0, 0.0, 1),
        (13, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1),
    ]
    assert prog.format == "gcode"
    assert load_part_program(GCODE) == prog  # the format guessed from the text


def test_feed_rate_mm_per_min_is_v_max_in_m_per_s():
    prog = load_part_program("G1 X10 F1200\nX20 F600\nG0 X0\nG1 X5\n")
    assert [m.v_max for m in prog.moves] == [0.02, 0.01, 0.0, 0.01]  # F is modal
    assert load_part_program("G1 X1 F1000\n").moves[0].v_max == 1000 / 60000


def test_incremental_mode_from_the_start_position():
    prog = load_part_program("G91 G0 X100 Z-50\nX100\nZ25.5\nG90 X0\n", x0=0.1, z0=0.3)
    assert [(m.x, m.z) for m in prog.moves] == [(0.2, 0.25), (0.3, 0.25), (0.3, 0.2755),
                                                (0.0, 0.2755)]
    # the decimal sums are exact: ten steps of 0.1 mm land on 1 mm
    prog = load_part_program("G91 G0 X0.1\n" + "X0.1\n" * 9)
    assert prog.moves[-1].x == 0.001
    # an axis not named stays where it is
    prog = load_part_program("G0 Z10\n", x0=0.123, z0=-0.5)
    assert (prog.moves[0].x, prog.moves[0].z) == (0.123, 0.01)


def test_gcode_dwell_before_any_move_is_a_dwell_at_the_start():
    prog = load_part_program("G4 P1.5\nG4 P0.5\nG0 X10\n", x0=0.2, z0=0.1)
    assert prog.moves == (M(1, 0.2, 0.1, dwell=2.0), M(3, 0.01, 0.1))


def test_gcode_blending_only_between_g1_moves_without_a_dwell():
    prog = load_part_program("G64 F6000\nG0 X10\nG1 X20\nX30\nG0 X40\nG1 X50\nX60\nG4 P0\n"
                             "X70\nG61\nX80\nG64 X90\n")
    assert [m.buffer_mode for m in prog.moves] == [1, 1, 2, 1, 1, 2, 1, 1, 2]  # G4 P0 stops
    # G61, the default: no blending
    prog = load_part_program("G1 X1 F600\nX2\n")
    assert [m.buffer_mode for m in prog.moves] == [1, 1]


def test_gcode_words_run_together_and_end_of_program():
    prog = load_part_program("G0X10Z20\nM2\n\n;done\n%\n")
    assert prog.moves == (M(1, 0.01, 0.02),)
    prog = load_part_program("G0 X1 M30\n")
    assert len(prog) == 1


# ------------------------------------------------------------------ the example

def test_example_cycle_hand_checked():
    prog = example_program()
    assert len(prog) == 21 and (prog.x0, prog.z0) == (0.0, 0.0)
    assert fields(prog.moves[0])[1:] == (0.0, 0.45, 0.0, 0.0, 0.0, 0.2, 1)  # pick
    assert fields(prog.moves[2])[1:] == (0.2, 0.0, 0.5, 0.0, 0.0, 0.0, 1)   # via point
    assert fields(prog.moves[3])[1:] == (0.4, 0.45, 0.5, 0.0, 0.0, 0.15, 2)  # place, blended
    assert fields(prog.moves[5])[1:] == (0.0, 0.45, 0.0, 0.0, 0.0, 0.2, 1)  # X back, Z down
    assert fields(prog.moves[18])[1:] == (0.1, 0.45, 0.25, 0.0, 0.0, 0.15, 1)  # exact stop
    assert fields(prog.moves[-1])[1:] == (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1)  # home
    # on scenario X's machine: X within its 0.4 m, Z within the 0.5 m of the modal survey,
    # every limit at most the axis's (0.5 m/s)
    assert all(0 <= m.x <= 0.4 and 0 <= m.z <= 0.45 and m.v_max <= 0.5 for m in prog.moves)
    assert sum(m.dwell for m in prog.moves) == pytest.approx(4 * 0.35)
    assert [k for k, m in enumerate(prog.moves) if m.buffer_mode == 2] == [3, 8, 13]


def test_example_gcode_equals_example_csv(tmp_path):
    csv, gcode = example_program("csv"), example_program("gcode")
    assert gcode == csv and gcode.format == "gcode" and csv.format == "csv"
    assert [m.line for m in csv.moves] != [m.line for m in gcode.moves]  # not compared
    for fmt, name in EXAMPLE_FILES.items():
        entry = example_path(fmt)
        assert entry.name == name
        copy = tmp_path / name
        copy.write_text(entry.read_text(encoding="utf-8"), encoding="utf-8")
        assert load_part_program(copy) == csv  # the format from the extension
        assert load_part_program(str(copy)).source == str(copy)


def test_scenario_x_machine_matches_the_example():
    from harness.scenario import load_scenario
    sc = load_scenario("X")
    prog = example_program()
    assert max(m.x for m in prog.moves) - min(m.x for m in prog.moves) == sc.move.distance
    assert max(m.z for m in prog.moves) - sc.z.z0 == pytest.approx(sc.z.distance)
    assert max(m.v_max for m in prog.moves) == sc.move.v_max


# ------------------------------------------------------------------ round trip

def test_csv_round_trip_and_gcode_conversion(tmp_path):
    for prog in (load_part_program(CSV), load_part_program(GCODE, x0=0.0),
                 example_program("gcode")):
        path = prog.to_csv(tmp_path / "p.csv")
        back = load_part_program(path)
        assert back == prog and back.format == "csv"
        assert [fields(m)[1:] for m in back.moves] == [fields(m)[1:] for m in prog.moves]
    text = example_program().csv_text()
    assert text.splitlines()[2] == ",".join(COLUMNS)
    assert text.splitlines()[6] == "0.4,0.45,0.5,0,0,0.15,blending"
    # the start position is not in the file: read it back with the same x0, z0
    prog = load_part_program("G91 G0 X10\n", x0=0.5)
    back = load_part_program(prog.csv_text(), x0=0.5)
    assert back == prog and back.moves[0].x == 0.51
    assert load_part_program(prog.csv_text()) != prog  # x0 differs


def test_rows_and_table():
    prog = load_part_program(CSV)
    rows = prog.rows()
    assert rows[0] == {"line": 4, "x": 0.4, "z": 0.45, "v_max": 0.5, "a_max": 4.0,
                       "d_max": 3.0, "dwell": 0.2, "buffer_mode": 1}
    cols = prog.table()
    assert list(cols) == ["line", *COLUMNS]
    assert cols["x"].tolist() == [0.4, 0.0, 0.1, -0.2]
    assert cols["buffer_mode"].tolist() == [1, 0, 2, 1]


finite = st.floats(min_value=-1e300, max_value=1e300, allow_nan=False)
limit = st.one_of(st.just(0.0), st.floats(min_value=0, max_value=1e300, allow_nan=False))


@st.composite
def programs(draw) -> PartProgram:
    n = draw(st.integers(1, 12))
    moves = []
    for k in range(n):
        mode = draw(st.sampled_from([0, 1, 2]))
        if mode == 2 and moves and moves[-1].dwell > 0:
            mode = 1  # the rule: no blending after a dwell
        moves.append(ProgramMove(line=k + 1, x=draw(finite), z=draw(finite),
                                 v_max=draw(limit), a_max=draw(limit), d_max=draw(limit),
                                 dwell=draw(limit), buffer_mode=mode))
    return PartProgram(tuple(moves), x0=draw(finite), z0=draw(finite))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(programs())
def test_random_programs_read_back_equal(prog):
    back = load_part_program(prog.csv_text(), x0=prog.x0, z0=prog.z0)
    assert back == prog
    assert [fields(m)[1:] for m in back.moves] == [fields(m)[1:] for m in prog.moves]


# ------------------------------------------------------------------ refused, named

@pytest.mark.parametrize("row, field, value, why", [
    ("0.1,0.2,-1,0,0,0,1", "v_max", "-1", "must be a finite number >= 0 (0: the axis's)"),
    ("0.1,0.2,0,-4,0,0,1", "a_max", "-4", ">= 0"),
    ("0.1,0.2,0,0,inf,0,1", "d_max", "inf", "finite"),
    ("0.1,0.2,0,0,0,-0.5,1", "dwell", "-0.5", ">= 0"),
    ("nan,0.2,0,0,0,0,1", "x", "nan", "finite"),
    ("0.1,2e300,0,0,0,0,1", "z", "2e300", "1e+300"),
    ("0.1,1e999,0,0,0,0,1", "z", "1e999", "overflows"),
    ("abc,0.2,0,0,0,0,1", "x", "abc", "not a number"),
    ("1_0,0.2,0,0,0,0,1", "x", "1_0", "not a number"),
    ("0x1,0.2,0,0,0,0,1", "x", "0x1", "not a number"),
    ("0.1,0.2,0,0,0,0,3", "buffer_mode", "3", "0 (aborting), 1 (buffered) or 2 (blending)"),
    ("0.1,0.2,0,0,0,0,1.0", "buffer_mode", "1.0", "0 (aborting)"),
    ("0.1,0.2,0,0,0,0,blend", "buffer_mode", "blend", "0 (aborting)"),
])
def test_csv_bad_value_names_line_field_value(row, field, value, why):
    err = refused(f"# head\n{','.join(COLUMNS)}\n{row}\n")
    assert len(err.errors) == 1 and err.errors[0].startswith(f"line 3: {field} = {value}: ")
    assert why in err.errors[0]
    assert str(err).startswith("<text>: line 3: ")
    assert isinstance(err, ValueError) and isinstance(err, HarnessError)


@pytest.mark.parametrize("text, expected", [
    ("x,z,y,feed\n1,2,3,4\n", "line 1: the header: unknown columns y, feed: the columns are"),
    ("x,z,x\n1,2,3\n", "line 1: the header: column x named twice"),
    ("x,v_max\n1,2\n", "line 1: the header: no column z"),
    ("x,,z\n1,2,3\n", "line 1: the header: column 2 has no name"),
    ("0.1,0.2\n0.3,0.4\n", "line 1: the header: 0.1,0.2 looks like a move"),
    ("x,z\n1,2,3\n", "line 2: 3 values for the 2 columns of the header (line 1)"),
    ("x,z\n,2\n", "line 2: x is empty: a target is required"),
    ("x,z\n", "line 1: the header, and no move after it"),
    ("# just a comment\n\n", "no header line"),
    ("x,z,dwell,buffer_mode\n1,2,0.5,1\n3,4,0,blending\n",
     "line 3: buffer_mode = blending: blending after the dwell of line 2 (0.5 s): a dwell "
     "needs the axis at rest"),
])
def test_csv_bad_structure_is_named(text, expected):
    err = refused(text, fmt="csv")
    assert any(expected in e for e in err.errors), err.errors


def test_all_bad_lines_at_once_and_nothing_returned():
    text = "x,z,v_max,dwell\n0,0,0.5,0\n1,2,-1,0\n# ok\n3,nan,0,0\n4,5,0,0\n6,7,0,-2\n"
    err = refused(text)
    assert err.errors == (
        "line 3: v_max = -1: must be a finite number >= 0 (0: the axis's)",
        "line 5: z = nan: must be a finite number (m)",
        "line 7: dwell = -2: must be a finite number >= 0 (s)",
    )
    assert str(err) == ("<text>: 3 errors, the program is refused:\n  " + "\n  ".join(err.errors))
    # two bad values of one line: both named
    err = refused("x,z,v_max\nfoo,1,-3\n")
    assert err.errors == ("line 2: x = foo: not a number",
                          "line 2: v_max = -3: must be a finite number >= 0 (0: the axis's)")


@pytest.mark.parametrize("line, expected", [
    ("G2 X1 Z1 I1", ["G2: arcs are not supported", "I1: arcs are not supported"]),
    ("G3 X1 Z1 R5", ["G3: arcs are not supported", "R5: arcs are not supported"]),
    ("G0 Y5", ["Y5: only the X and Z axes are programmed"]),
    ("G20", ["G20: inches are not supported"]),
    ("T1 M6", ["T1: tool changes are not supported", "M6: tool changes are not supported"]),
    ("M3 S1000", ["M3: spindles are not supported", "S1000: spindle speeds are not supported"]),
    ("G28", ["G28: not supported (the G codes: G0, G1, G4, G21, G61, G64, G90, G91)"]),
    ("G61.1", ["G61.1: not supported"]),
    ("G0 X1.2.3", ["X1.2.3: malformed word"]),
    ("G0 X1e3", ["E3: E words are not supported"]),
    ("G0 X", ["X: malformed word"]),
    ("G0 X--1", ["X--1: malformed word"]),
    ("G0 X" + "1" * 60, ["a number of more than 50 characters"]),
    ("G0 #1=5", ["#1=5: not a word"]),
    ("G0 X1 X2", ["X2: X more than once on the line (X1 before)"]),
    ("G0 G1 X1 F10", ["G1: a second motion word on the line (G0 before)"]),
    ("G90 G91 X1", ["G91: a second distance word on the line (G90 before)"]),
    ("G4", ["G4: a dwell needs P (seconds)"]),
    ("G4 P-1", ["P-1: a dwell must be >= 0 s"]),
    ("G4 P1 X5", ["X5: no axis word with G4 (a dwell)"]),
    ("G64 P0.01", ["P0.01: P only with G4 (the dwell in seconds)"]),
    ("G1 X5", ["G1: G1 with no feed rate: give F (mm/min) on this line or before"]),
    ("G1 X5 F0", ["F0: a feed rate must be > 0 (mm/min)"]),
    ("X5", ["X5: no motion mode yet: G0 or G1 first"]),
    ("G0 X1 (open", ["a comment '(' is not closed on its line"]),
    ("G0 X1 )", ["a ')' with no '(' before it"]),
    ("O100", ["O100: program numbers and subroutines are not supported"]),
    ("/G0 X1", ["/: not a word"]),  # no block delete
])
def test_gcode_refused_words_are_named(line, expected):
    err = refused(f"G21\n{line}\nG0 X0\n", fmt="gcode")
    assert len(err.errors) == len(expected), err.errors
    for e, x in zip(err.errors, expected, strict=True):
        assert e.startswith("line 2: ") and x in e, (e, x)


def test_gcode_after_the_end_and_several_bad_lines():
    err = refused("G0 X1\nM30\nG0 X2\n(fine)\nG1 X3\n")
    assert err.errors == (
        "line 3: G0: after the end of the program (line 2): remove it, or the end",
        "line 5: G1: after the end of the program (line 2): remove it, or the end",
    )
    err = refused("G0 Y1\nG0 X1\nG2 X1\nG0 X2\nM5\n")
    assert [e.split(":")[0] for e in err.errors] == ["line 1", "line 3", "line 5"]


def test_gcode_without_moves_is_refused():
    assert "no moves" in refused("G21 G90\nF1000\n(nothing)\n", fmt="gcode").errors[0]
    assert "no moves" in refused("%\n%\n", fmt="gcode").errors[0]


def test_program_rules_hold_for_programs_built_in_python():
    with pytest.raises(PartProgramError, match="move: v_max = -1: must be"):
        ProgramMove(x=0, z=0, v_max=-1)
    with pytest.raises(PartProgramError, match="line 4: buffer_mode = 7"):
        ProgramMove(line=4, x=0, z=0, buffer_mode=7)
    with pytest.raises(PartProgramError, match="x = a: must be a number"):
        ProgramMove(x="a", z=0)  # type: ignore[arg-type]
    assert ProgramMove(x=1, z=0, buffer_mode="blending").buffer_mode == 2
    with pytest.raises(PartProgramError, match="no moves"):
        PartProgram(())
    with pytest.raises(PartProgramError, match="move 2: buffer_mode = blending: blending after"):
        PartProgram((M(0, 0, 0, dwell=1), M(0, 1, 0, mode=2)))
    with pytest.raises(PartProgramError, match="x0 = nan"):
        PartProgram((M(0, 0, 0),), x0=math.nan)
    with pytest.raises(PartProgramError, match="z0 = a: must be a number"):
        PartProgram((M(0, 0, 0),), z0="a")  # type: ignore[arg-type]
    with pytest.raises(PartProgramError, match=r"moves\[1\] = 1: not a ProgramMove"):
        PartProgram((M(0, 0, 0), 1))  # type: ignore[arg-type]
    with pytest.raises(PartProgramError, match="moves = 5: not a sequence"):
        PartProgram(5)  # type: ignore[arg-type]
    assert M(1, 0.5, 0) == M(9, 0.5, 0)  # the line is not compared
    assert PartProgram((M(1, 0.5, 0),), source="a", format="gcode") == PartProgram(
        (M(2, 0.5, 0),), source="b", format="csv")


# ------------------------------------------------------------------ hostile inputs

def test_sources_that_cannot_be_read(tmp_path):
    assert "no such file" in refused(tmp_path / "missing.csv").errors[0]
    assert "cannot read" in refused(tmp_path).errors[0]
    odd = tmp_path / "prog.txt"
    odd.write_text("x,z\n1,2\n", encoding="utf-8")
    assert "unknown extension .txt" in refused(odd).errors[0]
    assert load_part_program(odd, fmt="csv").moves == (M(2, 1, 2),)
    for name in ("p.nc", "p.NGC", "p.gcode"):
        (tmp_path / name).write_text("G0 X1\n", encoding="utf-8")
        assert load_part_program(tmp_path / name).format == "gcode"
    assert "fmt = xml" in refused("x,z\n1,2\n", fmt="xml").errors[0]  # type: ignore[arg-type]
    assert "x0 = inf" in refused("x,z\n1,2\n", x0=math.inf).errors[0]
    assert "z0 = 2e+300" in refused("x,z\n1,2\n", z0=2e300).errors[0]
    with pytest.raises(PartProgramError, match="not a path"):
        load_part_program(42)  # type: ignore[arg-type]


@pytest.mark.parametrize("data, expected", [
    (b"", "empty"),
    (b"   \n\n", "empty"),
    (b"x,z\n", "no move after it"),
    (b"x,z\n1,2\n\xff\xfe", "line 3: not UTF-8 text (byte 0xff"),
    (b"x,z\n1,\x002\n", "line 2: a NUL character"),
    (b"\x89PNG\r\n\x1a\n\x00\x00", "line 1: not UTF-8 text (byte 0x89"),
])
def test_hostile_bytes(data, expected, tmp_path):
    path = tmp_path / "h.csv"
    path.write_bytes(data)
    for source in (path, data):
        err = refused(source)
        assert expected in str(err), str(err)


@pytest.mark.parametrize("fmt", ["csv", "gcode"])
def test_binary_garbage_is_a_part_program_error(fmt, tmp_path):
    rng = random.Random(35)
    for k in range(20):
        data = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 4000)))
        with pytest.raises(PartProgramError):
            load_part_program(data, fmt=fmt)
        text = "".join(chr(rng.choice([rng.randrange(1, 128), rng.randrange(128, 0x2FFF)]))
                       for _ in range(2000 + k))
        with pytest.raises(PartProgramError):
            load_part_program(text + "\n", fmt=fmt)


def test_many_errors_listed_message_capped():
    n = MAX_SHOWN + 50
    err = refused("x,z\n" + "a,0\n" * n)
    assert len(err.errors) == n and err.errors[-1] == f"line {n + 1}: x = a: not a number"
    assert str(err).endswith("... and 50 more") and str(err).count("\n") == MAX_SHOWN + 1


@pytest.mark.slow
def test_huge_programs_load_in_reasonable_time(tmp_path):
    n = 100_000
    rng = random.Random(1)
    rows = [f"{rng.uniform(0, 0.4):.6f},{rng.uniform(0, 0.45):.6f},0.5,0,0,0,buffered"
            for _ in range(n)]
    path = tmp_path / "big.csv"
    path.write_text(",".join(COLUMNS) + "\n" + "\n".join(rows) + "\n", encoding="utf-8")
    t = time.perf_counter()
    prog = load_part_program(path)
    assert len(prog) == n and time.perf_counter() - t < 30  # about 2 s on 2 shared cores
    gcode = tmp_path / "big.nc"
    gcode.write_text("G21 G90 G64 F30000\n" + "".join(
        f"G1 X{rng.uniform(0, 400):.3f} Z{rng.uniform(0, 450):.3f}\n" for _ in range(n)),
        encoding="utf-8")
    t = time.perf_counter()
    assert len(load_part_program(gcode)) == n and time.perf_counter() - t < 30
    # a huge file of bad lines: every one listed, quickly
    t = time.perf_counter()
    err = refused("x,z\n" + "nan,0\n" * n)
    assert len(err.errors) == n and time.perf_counter() - t < 30
    # a line of a million characters
    err = refused("G0 " + "X1" * 500_000 + "\n")
    assert err.errors == ("line 1: X1: X more than once on the line (X1 before) "
                          "(499999 times on the line)",)


@settings(max_examples=300, deadline=None)
@given(st.lists(st.sampled_from(list("GXZFPNM0123456789.-+ ;()%,#\n\txzgbuffered_")
                                + ["nan", "inf", "G4", "G64", "G91", "M30", "x,z\n", "\r"]),
                max_size=200).map("".join),
       st.sampled_from(["csv", "gcode", None]))
def test_any_text_loads_or_is_a_part_program_error(text, fmt):
    try:
        prog = load_part_program(text + "\n", fmt=fmt)
    except PartProgramError as e:
        assert e.errors and all(isinstance(m, str) and m for m in e.errors)
    else:
        assert len(prog) >= 1
        assert load_part_program(prog.csv_text()) == prog


def test_a_path_given_as_text_with_no_line_break_is_a_path(tmp_path):
    p = Path(tmp_path / "prog.csv")
    p.write_text("x,z\n0.1,0.2\n", encoding="utf-8")
    assert load_part_program(str(p)).moves == (M(2, 0.1, 0.2),)
