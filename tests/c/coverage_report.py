"""Line and branch coverage of fmu_src/ from gcc's coverage data (tests/c/coverage.sh).

Runs ``gcov --json-format --stdout --branch-probabilities`` on every ``.gcda`` file of
the folders given, keeps the files of ``fmu_src/`` and sums them: a line is covered when
any build ran it, a branch (line, index) when any build took it.  Prints every line left
uncovered (with its text), each file's figures, and last ``lines: P %  branches: Q %``.

Standard library only: the suite's machines have gcc, not gcovr or lcov.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from collections import defaultdict
from pathlib import Path


def gcov_json(gcda: Path) -> list[dict]:
    """The JSON documents gcov prints for one ``.gcda`` file (one per line)."""
    proc = subprocess.run(["gcov", "--json-format", "--stdout", "--branch-probabilities",
                           "--object-directory", str(gcda.parent), str(gcda)],
                          capture_output=True, text=True, cwd=gcda.parent)
    if proc.returncode != 0:
        raise RuntimeError(f"gcov failed on {gcda}: {proc.stderr}")
    return [json.loads(line) for line in proc.stdout.splitlines() if line.startswith("{")]


def collect(folders: list[Path], src: Path) -> tuple[dict, dict]:
    """Line and branch hits of the files of ``src`` over every ``.gcda`` of ``folders``.

    Returns
    -------
    lines : dict
        ``{file: {line: count}}`` for every instrumented line.
    branches : dict
        ``{file: {(line, index): count}}`` for every branch.
    """
    lines: dict[str, dict[int, int]] = defaultdict(dict)
    branches: dict[str, dict[tuple[int, int], int]] = defaultdict(dict)
    for folder in folders:
        for gcda in sorted(folder.rglob("*.gcda")):
            for doc in gcov_json(gcda):
                cwd = Path(doc.get("current_working_directory", gcda.parent))
                for f in doc["files"]:
                    path = (cwd / f["file"]).resolve()
                    if path.parent != src:
                        continue
                    name = path.name
                    for ln in f["lines"]:
                        n = ln["line_number"]
                        lines[name][n] = lines[name].get(n, 0) + ln["count"]
                        for i, b in enumerate(ln["branches"]):
                            if b.get("throw"):
                                continue
                            key = (n, i)
                            branches[name][key] = branches[name].get(key, 0) + b["count"]
    return lines, branches


def pct(hit: int, total: int) -> float:
    """Percentage, 100 for nothing to cover."""
    return 100.0 * hit / total if total else 100.0


def main(argv: list[str] | None = None) -> int:
    """Print the report; returns 1 when nothing was measured."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+", type=Path, help="folders holding .gcda files")
    ap.add_argument("--root", type=Path, default=Path.cwd(), help="the repository root")
    args = ap.parse_args(argv)
    src = (args.root / "fmu_src").resolve()
    lines, branches = collect(args.folders, src)
    if not lines:
        print("coverage_report: no coverage data for fmu_src/", file=sys.stderr)
        return 1
    print("uncovered lines of fmu_src/:")
    tl = hl = tb = hb = 0
    rows = []
    for name in sorted(lines):
        text = (src / name).read_text().splitlines()
        for n in sorted(lines[name]):
            if lines[name][n] == 0:
                print(f"  {name}:{n}: {text[n - 1].strip() if n <= len(text) else ''}")
        fl, fh = len(lines[name]), sum(1 for c in lines[name].values() if c > 0)
        fb, fbh = len(branches[name]), sum(1 for c in branches[name].values() if c > 0)
        rows.append((name, fh, fl, fbh, fb))
        tl += fl
        hl += fh
        tb += fb
        hb += fbh
    print("per file (lines hit/total, branches taken/total):")
    for name, fh, fl, fbh, fb in rows:
        print(f"  {name:20s} {fh:5d}/{fl:<5d} {pct(fh, fl):6.2f} %   "
              f"{fbh:5d}/{fb:<5d} {pct(fbh, fb):6.2f} %")
    print(f"lines: {pct(hl, tl):.1f} %  branches: {pct(hb, tb):.1f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
