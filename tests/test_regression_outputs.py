"""Every number of the commands' CSV files stays what it was (a golden-file regression test).

``tests/data/regression/<case>/`` holds the CSV files the commands of :data:`CASES`
wrote at commit 433d299, before the harness was restructured (issue 17); see the
README there.  Each case runs its command again and requires, for every stored
file, that

* every stored column is still there, in the same order among themselves
  (columns may be added);
* every stored row is still there, in the same order among the rows (rows may
  be added, e.g. a new method), with the very same text in every stored column:
  bit for bit at the 10 significant digits the CSV files print.

Header comment lines (``#``) describe the file and may change.  A change of a
number that a fix makes on purpose updates the stored file in the same commit,
with the reason in the README of the folder.
"""

from __future__ import annotations

import csv
import io
from pathlib import Path

import pytest

from harness.cli import main

DATA = Path(__file__).parent / "data" / "regression"

CASES: dict[str, list[str]] = {
    "simulate": ["simulate"],
    "simulate-X-tuned": ["simulate", "X", "--tuning", "optimal,robust"],
    "map-X-fast": ["map", "X", "--max-moves", "12", "--workers", "1", "--tuning",
                   "optimal,robust", "--no-plot"],
    "map-Y-fmu": ["map", "Y", "--max-moves", "3", "--engine", "fmu", "--workers", "1",
                  "--no-plot"],
    "tune-X-single": ["tune", "X", "--single"],
    "tune-Y-grid": ["tune", "Y", "--max-moves", "3", "--tuning", "djl=optimal,jl=optimal",
                    "--workers", "1"],
    "online": ["online", "X", "Y", "--jerk-source", "both", "--no-plot"],
    "compare-X-fast": ["compare", "X", "--engine", "fast", "--no-stationary", "--timeopt", "3",
                       "--no-plot", "--no-bound"],
    "compare-Y-fmu": ["compare", "Y", "--timeopt", "0", "--no-plot", "--no-bound"],
}
"""Case name (a folder of ``tests/data/regression``) -> the command's arguments."""


def read_table(path: Path) -> tuple[list[str], list[list[str]]]:
    """Header and rows of a CSV file, its ``#`` comment lines skipped."""
    text = "".join(line for line in path.read_text(encoding="utf-8").splitlines(keepends=True)
                   if not line.startswith("#"))
    rows = list(csv.reader(io.StringIO(text)))
    return rows[0], rows[1:]


def table_differences(stored: Path, new: Path) -> list[str]:
    """What of the stored table is not found in the new one (empty: all of it is)."""
    h0, r0 = read_table(stored)
    h1, r1 = read_table(new)
    missing = [c for c in h0 if c not in h1]
    if missing:
        return [f"{new.name}: columns gone: {missing}"]
    pos = [h1.index(c) for c in h0]
    if pos != sorted(pos):
        return [f"{new.name}: the stored columns changed order"]
    projected = [[row[i] if i < len(row) else "<missing>" for i in pos] for row in r1]
    problems: list[str] = []
    j = 0
    for k, row in enumerate(r0):
        start = j
        while j < len(projected) and projected[j] != row:
            j += 1
        if j == len(projected):
            # report the closest row: the one that differs in the fewest columns
            best = min(projected[start:] or projected, default=None,
                       key=lambda r: sum(a != b for a, b in zip(r, row, strict=True)))
            diff = [] if best is None else [
                f"{h0[i]}: {row[i]!r} -> {best[i]!r}" for i in range(len(row)) if best[i] != row[i]]
            problems.append(f"{new.name}: stored row {k + 2} not found; closest differs in "
                            f"{diff[:6]}")
            if len(problems) >= 5:
                break
            j = start
        else:
            j += 1
    return problems


def test_the_comparison_finds_a_changed_digit_a_lost_column_and_a_lost_row(tmp_path):
    stored = tmp_path / "stored.csv"
    stored.write_text("# meta\na,b,c\n1,2.000000001,x\n3,4,y\n")
    same_plus = tmp_path / "plus.csv"
    same_plus.write_text("a,new,b,c\n0,0,0,z\n1,9,2.000000001,x\n3,9,4,y\n")
    assert table_differences(stored, same_plus) == []
    digit = tmp_path / "digit.csv"
    digit.write_text("a,b,c\n1,2.000000002,x\n3,4,y\n")
    assert any("2.000000002" in p for p in table_differences(stored, digit))
    col = tmp_path / "col.csv"
    col.write_text("a,c\n1,x\n3,y\n")
    assert table_differences(stored, col) == ["col.csv: columns gone: ['b']"]
    row = tmp_path / "row.csv"
    row.write_text("a,b,c\n3,4,y\n")
    assert table_differences(stored, row) and "row 2" in table_differences(stored, row)[0]
    order = tmp_path / "order.csv"
    order.write_text("a,b,c\n3,4,y\n1,2.000000001,x\n")
    assert table_differences(stored, order)


@pytest.mark.parametrize("case", sorted(CASES))
def test_command_csv_files_keep_every_number(case, tmp_path):
    stored_dir = DATA / case
    stored = sorted(stored_dir.glob("*.csv"))
    assert stored, f"no stored files in {stored_dir}"
    out = tmp_path / case
    assert main(CASES[case] + ["-o", str(out), "-q"]) == 0
    problems = []
    for f in stored:
        new = out / f.name
        if not new.is_file():
            problems.append(f"{case}: {f.name} was not written")
            continue
        problems += table_differences(f, new)
    assert not problems, "\n".join(problems)
