"""Benchmark: FMU states as a rollback master uses them (issue 21, third session).

A C master (benchmarks/c/bench_state.c) dlopen()s the FMI 2.0 binary, brings it to a
state, then saves it over the previous one and restores it (fmi2GetFMUstate +
fmi2SetFMUstate) COUNT times, and serialises and deserialises it COUNT times. Two states:
the default move, and a ZVD shaper timed by f_mode after a commanded target (both rings of
the shaper's memory in use). Prints each state's size and the microseconds per save +
restore and per serialise + deserialise (medians of the repeats). With ``--against REV``
the same for the FMU built from the sources of a git revision (e.g. the one before states
were packed, ``aa2688d``: 292 824 bytes whatever the state), and the ratios.

    python benchmarks/bench_state.py [--count 20000] [--repeats 5] [--against REV]
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess
import tempfile
import zipfile
from pathlib import Path

from harness.fmu import spec
from harness.fmu.build import CFLAGS, default_fmu, fmi_include_dir
from harness.fmu.codegen import SOURCES

SRC = Path(__file__).parent / "c" / "bench_state.c"
ROOT = Path(__file__).resolve().parent.parent


def _old_library(rev: str, folder: Path) -> tuple[Path, str]:
    """Build the FMI 2 library of revision ``rev``'s fmu_src/; return it and its token."""
    src = folder / "old_src"
    src.mkdir()
    archive = subprocess.run(["git", "-C", str(ROOT), "archive", rev, "fmu_src"],
                             check=True, capture_output=True).stdout
    subprocess.run(["tar", "-x", "-C", str(src)], input=archive, check=True)
    fsrc = src / "fmu_src"
    token = re.search(r'#define DJL_INSTANTIATION_TOKEN "([^"]+)"',
                      (fsrc / "djl_vars.h").read_text())
    if token is None:
        raise SystemExit(f"no instantiation token in {rev}'s fmu_src/djl_vars.h")
    lib = folder / "old.so"
    flags = [f for f in CFLAGS if not f.startswith("-W")]
    subprocess.run(["gcc", *flags, "-shared", f"-I{fsrc}", f"-I{fmi_include_dir()}",
                    *[str(fsrc / f) for f in SOURCES[2]], "-o", str(lib), "-lm"],
                   check=True, capture_output=True)
    return lib, token.group(1)


def _measure(exe: Path, lib: Path, token: str, uri: str, shaped: bool, count: int,
             repeats: int) -> tuple[int, float, float]:
    """State bytes, microseconds per save + restore and per serialise + deserialise."""
    vr = [str(spec.BY_NAME[n].vr) for n in ("shaper", "shaper_source", "f_mode", "target",
                                             "execute")]
    out = subprocess.run([str(exe), str(lib), token, uri, "1" if shaped else "0", *vr,
                          str(count), str(repeats)], capture_output=True, text=True,
                         check=True).stdout
    rows = [line.split() for line in out.splitlines()]
    size = int(rows[0][0])
    return (size, statistics.median(float(r[1]) for r in rows) / count * 1e6,
            statistics.median(float(r[2]) for r in rows) / count * 1e6)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--count", type=int, default=20000, help="operations per repeat")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--against", metavar="REV",
                    help="also the FMU built from this git revision's fmu_src/ (ratios)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        with zipfile.ZipFile(default_fmu(2)) as z:
            z.extractall(root / "fmu")
        lib = next((root / "fmu" / "binaries").rglob(f"{spec.MODEL_IDENTIFIER}.*"))
        uri = (root / "fmu" / "resources").as_uri()
        exe = root / "bench_state"
        subprocess.run(["gcc", "-std=c99", "-O2", "-D_POSIX_C_SOURCE=199309L",
                        f"-I{fmi_include_dir()}", str(SRC), "-o", str(exe), "-ldl"],
                       check=True, capture_output=True)
        builds = [("this build", lib, spec.INSTANTIATION_TOKEN)]
        if args.against:
            old, token = _old_library(args.against, root)
            builds.append((args.against, old, token))
        for shaped, what in ((False, "the default move"),
                             (True, "a ZVD shaper timed by f_mode, after a commanded target")):
            print(f"{what}:")
            got = []
            for name, library, token in builds:
                size, gs, sd = _measure(exe, library, token, uri, shaped, args.count,
                                        args.repeats)
                got.append((size, gs, sd))
                print(f"  {name:>12}: state {size:7d} bytes; save + restore {gs:7.2f} us, "
                      f"serialise + deserialise {sd:7.2f} us")
            if len(got) == 2:
                (s1, g1, d1), (s0, g0, d0) = got
                print(f"  {'ratio':>12}: {s0 / s1:.1f}x smaller, save + restore "
                      f"{g0 / g1:.1f}x faster, serialise + deserialise {d0 / d1:.1f}x faster")


if __name__ == "__main__":
    main()
