"""The FMU's C sources call no libm function, and lose nothing by it (issue #11 item 5).

fmpy rebuilds a binary from the FMU's ``sources/`` and links no libm (docs/platforms.md), so
``fmu_src/`` takes floor, sqrt, exp2 ... from ``fmu_src/djl_math.h``:

- no object compiled from ``fmu_src/`` (gcc, and zig's clang for x86_64 and aarch64 Linux,
  at -O0 and -O2) needs a symbol that libm defines;
- ``tests/c/test_math.c``: each function of djl_math.h gives libm's bits (hypot and exp2,
  which IEEE 754 does not specify exactly: within 1 ulp, and correctly rounded, measured
  against quadruple precision where gcc has libquadmath);
- ``tests/c/test_plan_libm.c``: the planner makes the same plans, byte for byte, with
  djl_math.h and with libm (the campaign of 10^6 cases a family is in docs/platforms.md).
"""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from harness._resources import fmu_src_dir
from harness.fmu import codegen
from harness.fmu.build import BuildError, fmi_include_dir, zig_command

C_DIR = Path(__file__).parent / "c"
WARN = ["-Wall", "-Wextra", "-Wpedantic", "-Werror", "-ffp-contract=off"]

# C99's <math.h> functions (and their float / long double forms), glibc's helpers
MATH_NAMES = """acos acosh asin asinh atan atan2 atanh cbrt ceil copysign cos cosh erf erfc exp
exp2 expm1 fabs fdim floor fma fmax fmin fmod frexp hypot ilogb ldexp lgamma llrint llround
log log10 log1p log2 logb lrint lround modf nan nearbyint nextafter nexttoward pow remainder
remquo rint round scalbln scalbn sin sinh sqrt tan tanh tgamma trunc""".split()
GLIBC_HELPERS = ["__finite", "__isnan", "__isinf", "__fpclassify", "__signbit", "finite",
                 "isnan", "isinf"]


def _libm_symbols() -> set[str]:
    """Names libm defines: C99's and glibc's, plus whatever the host's libm.so.6 exports."""
    names = {n + s for n in MATH_NAMES + GLIBC_HELPERS for s in ("", "f", "l")}
    if shutil.which("gcc") and shutil.which("nm"):
        libm = subprocess.run(["gcc", "-print-file-name=libm.so.6"], capture_output=True,
                              text=True).stdout.strip()
        if Path(libm).is_file():
            out = subprocess.run(["nm", "-D", "--defined-only", libm], capture_output=True,
                                 text=True).stdout
            names |= {line.split()[-1].split("@")[0] for line in out.splitlines()
                      if len(line.split()) >= 3}
    return names


def _compilers() -> list[tuple[str, list[str]]]:
    out = []
    if shutil.which("gcc"):
        out.append(("gcc", ["gcc"]))
    try:
        zig = zig_command()
    except BuildError:  # no ziglang: gcc only
        return out
    out.append(("zig x86_64-linux", [*zig, "-target", "x86_64-linux-gnu"]))
    out.append(("zig aarch64-linux", [*zig, "-target", "aarch64-linux-gnu"]))
    return out


def test_fmu_sources_need_no_libm_symbol(tmp_path):
    if shutil.which("nm") is None:
        pytest.skip("nm (binutils) not available")
    compilers = _compilers()
    if not compilers:
        pytest.skip("no C compiler")
    assert "djl_math.h" in codegen.HEADERS  # shipped in sources/
    forbidden = _libm_symbols()
    assert {"floor", "ceil", "sqrt", "hypot", "exp2", "nextafter"} <= forbidden
    sources = sorted({f for v in (2, 3) for f in codegen.SOURCES[v]})
    found = {}
    for name, cc in compilers:
        for opt in ("-O0", "-O2"):
            for src in sources:
                obj = tmp_path / f"{name.replace(' ', '_')}{opt}{src}.o"
                proc = subprocess.run([*cc, "-std=c99", opt, "-fPIC", "-fvisibility=hidden",
                                       *WARN, "-Wno-strict-prototypes", f"-I{fmu_src_dir()}",
                                       f"-I{fmi_include_dir()}", "-c",
                                       str(fmu_src_dir() / src), "-o", str(obj)],
                                      capture_output=True, text=True)
                assert proc.returncode == 0, (name, opt, src, proc.stderr)
                nm = subprocess.run(["nm", "-u", str(obj)], capture_output=True, text=True,
                                    check=True).stdout
                undefined = {line.split()[-1] for line in nm.splitlines() if line.strip()}
                bad = undefined & forbidden
                if bad:
                    found[(name, opt, src)] = sorted(bad)
    assert not found, found


def _build(tmp_path: Path, name: str, files: list[Path], flags: list[str],
           libs: list[str]) -> Path:
    exe = tmp_path / name
    proc = subprocess.run(["gcc", *flags, f"-I{fmu_src_dir()}", f"-I{C_DIR}",
                           *map(str, files), "-o", str(exe), *libs, "-lm"],
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return exe


def test_djl_math_gives_libm_results(tmp_path):
    """2.2 * 10^5 random arguments per generator and function (about 10^6 to 2 * 10^6 each)."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc not available")
    src = [C_DIR / "test_math.c"]
    try:  # with the quadruple-precision reference (gcc's libquadmath)
        exe = _build(tmp_path, "test_math_quad", src, ["-std=gnu99", "-O2", "-DDJL_TEST_QUAD",
                                                       "-Wall", "-Wextra", "-Werror",
                                                       "-ffp-contract=off"], ["-lquadmath"])
    except AssertionError:
        exe = _build(tmp_path, "test_math", src, ["-std=c99", "-O2", *WARN], [])
    proc = subprocess.run([str(exe), "220000", "5"], capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "math: 0 failures" in proc.stdout, proc.stdout
    lines = {ln[2:12].strip(): ln for ln in proc.stdout.splitlines() if ln.startswith("  ")}
    for fn in ("floor", "ceil", "trunc", "fabs", "isfinite", "ilogb", "frexp", "sqrt", "fmax",
               "fmin", "nextafter", "ldexp", "exp2 grid"):
        assert " 0 differ from libm" in lines[fn], lines[fn]
    for fn in ("hypot", "exp2"):
        assert "by at most 1 ulp" in lines[fn] or " 0 differ" in lines[fn], lines[fn]
    if "quad" in exe.name:  # djl_hypot correctly rounded, ties to even
        assert "not correctly rounded 0 (djl)" in lines["hypot"], lines["hypot"]
        assert "odd: 0 (djl)" in lines["hypot"], lines["hypot"]


def test_plans_are_the_same_with_libm(tmp_path):
    """3 * 10^5 random cases of test_core's families: the same plan bytes (about 6 s)."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc not available")
    exe = _build(tmp_path, "test_plan_libm",
                 [C_DIR / "test_plan_libm.c", C_DIR / "core_libm.c",
                  *[fmu_src_dir() / f for f in codegen.CORE_SOURCES]],
                 ["-std=c99", "-O2", *WARN], [])
    proc = subprocess.run([str(exe), "300000", "3"], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout + proc.stderr[-3000:]
    assert "300000 cases, 0 differ, 0 failures" in proc.stdout, proc.stdout
