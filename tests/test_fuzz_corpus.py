"""The fuzz corpus of tests/fuzz/ replayed without a fuzzer (issue 21).

The harnesses (FMI 2 / FMI 3 call sequences, FMU state deserialisation, the planner's
parameter space) check their invariants themselves: finite outputs, limits, landing when
done, states the FMU saved accepted back.  Here each is built with gcc and
tests/fuzz/replay.c, under AddressSanitizer + UBSan where gcc has them, and run over
its committed, minimised corpus (the inputs of the campaign in docs/fuzzing.md and the
reproducers of issue 21).
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from harness._resources import fmu_src_dir
from harness.fmu.build import fmi_include_dir
from harness.fmu.codegen import CORE_SOURCES as CORE
from harness.fmu.codegen import FMU_SOURCES as FMU

FUZZ = Path(__file__).parent / "fuzz"
SAN = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer"]
BASE = ["-std=c99", "-g", "-O1", "-Wall", "-Wextra", "-Wpedantic", "-Werror"]

HARNESSES = {
    "fmi": ["fmi2.c", "fmi3.c", *FMU, *CORE],
    "state": ["fmi2.c", *FMU, *CORE],
    "plan": list(CORE),
}


def _sanitizers_work(tmp: Path) -> bool:
    probe = tmp / "probe.c"
    probe.write_text("int main(void){return 0;}\n")
    proc = subprocess.run(["gcc", *SAN, str(probe), "-o", str(tmp / "probe")],
                          capture_output=True)
    return proc.returncode == 0 and subprocess.run([str(tmp / "probe")]).returncode == 0


def _build_replay(name: str, tmp_path: Path) -> Path:
    """The gcc replay of harness fuzz_<name>.c (under ASan + UBSan where gcc has them)."""
    san = SAN if _sanitizers_work(tmp_path) else []
    exe = tmp_path / f"replay_{name}"
    cmd = ["gcc", *BASE, *san, f"-I{fmu_src_dir()}", f"-I{fmi_include_dir()}",
           str(FUZZ / f"fuzz_{name}.c"), str(FUZZ / "replay.c"),
           *[str(fmu_src_dir() / s) for s in HARNESSES[name]], "-o", str(exe), "-lm"]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return exe


@pytest.mark.parametrize("name", sorted(HARNESSES))
def test_fuzz_corpus_replays_clean(name: str, tmp_path: Path) -> None:
    if shutil.which("gcc") is None:
        pytest.skip("gcc not available")
    files = sorted(p for p in (FUZZ / "corpus" / name).iterdir() if p.is_file())
    assert len(files) >= 5, "the corpus is committed"
    exe = _build_replay(name, tmp_path)
    proc = subprocess.run([str(exe), *map(str, files)], capture_output=True, text=True,
                          timeout=600, env={"ASAN_OPTIONS": "detect_leaks=1",
                                            "UBSAN_OPTIONS": "print_stacktrace=1"})
    report = proc.stdout + proc.stderr
    assert proc.returncode == 0, report[-4000:]
    assert "runtime error" not in report and "AddressSanitizer" not in report, report[-4000:]
    assert f"replay: {len(files)} inputs replayed" in proc.stdout


def test_replay_driver_fails_on_a_broken_invariant(tmp_path: Path) -> None:
    """The replay is not a test that cannot fail: a harness whose invariant breaks stops it."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc not available")
    harness = tmp_path / "broken.c"
    harness.write_text('#include "fuzz_common.h"\n'
                       "int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n);\n"
                       "int LLVMFuzzerTestOneInput(const uint8_t *d, size_t n)\n"
                       "{ FUZZ_CHECK(n == 0 || d[0] != 7, \"byte 7\"); return 0; }\n")
    good, bad = tmp_path / "good", tmp_path / "bad"
    good.write_bytes(b"\x01\x02")
    bad.write_bytes(b"\x07")
    exe = tmp_path / "replay_broken"
    proc = subprocess.run(["gcc", *BASE, f"-I{FUZZ}", str(harness), str(FUZZ / "replay.c"),
                           "-o", str(exe), "-lm"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert subprocess.run([str(exe), str(good)], capture_output=True).returncode == 0
    proc = subprocess.run([str(exe), str(good), str(bad)], capture_output=True, text=True)
    assert proc.returncode != 0 and "fuzz invariant broken" in proc.stderr


def test_open_findings_still_break_the_fmi_harness(tmp_path: Path) -> None:
    """tests/fuzz/open/ holds FMI inputs whose finding is not fixed yet (docs/fuzzing.md,
    "The campaign"): each still breaks an invariant, and FUZZ_VERBOSE traces the calls it
    decodes to.  When this fails because an input passes, the finding is fixed: move the
    input into corpus/fmi with its regression test."""
    if shutil.which("gcc") is None:
        pytest.skip("gcc not available")
    files = sorted((FUZZ / "open").glob("crash-*"))
    if not files:
        pytest.skip("no open finding")
    exe = _build_replay("fmi", tmp_path)
    for f in files:
        proc = subprocess.run([str(exe), str(f)], capture_output=True, text=True, timeout=60,
                              env={"FUZZ_VERBOSE": "1", "ASAN_OPTIONS": "detect_leaks=0"})
        assert proc.returncode != 0 and "fuzz invariant broken" in proc.stderr, (
            f"{f.name} no longer breaks an invariant: fixed? {proc.stderr[-2000:]}")
        assert "instantiate (FMI " in proc.stderr and "step from " in proc.stderr, (
            proc.stderr[-2000:])


def _defines(sources: list[Path], name: str) -> bool:
    """Whether one of ``sources`` defines C function ``name``: its return type starts at
    column 0 (the style of fmu_src/), and its parameter list, on one line or several, is
    followed by ``{``, not by ``;`` as a prototype's is."""
    pattern = re.compile(
        rf"^[A-Za-z_][\w \t\*]*\b{re.escape(name)}\s*\([^;{{}}]*\)\s*\{{", re.M)
    return any(pattern.search(s.read_text()) for s in sources)


def test_defines_tells_a_definition_from_a_prototype(tmp_path: Path) -> None:
    """The ignorelist check below counts only definitions, whatever their layout."""
    c = tmp_path / "f.c"
    c.write_text("static int f(int a,\n             int b);\n"
                 "int g(void (*cb)(int), int n) { return n; }\n"
                 "static uint32_t h(const uint8_t *p,\n                  size_t n)\n{\n"
                 "    return f(1,\n             2);\n}\n")
    assert not _defines([c], "f")
    assert _defines([c], "g")
    assert _defines([c], "h")


@pytest.mark.parametrize("ignorelist", ["sanitize_ignore.txt", "coverage_ignore.txt"])
def test_fuzz_ignorelists_name_functions_that_exist(ignorelist: str) -> None:
    """tests/fuzz/build.sh passes these lists to clang, which ignores a name it never
    meets: a misspelt or renamed function would silently be instrumented again (the
    sanitizers back on the checksum, its time back in fuzzing).  Each ``fun:`` entry must
    name a function defined in fmu_src/ or tests/fuzz/, by its plain name (no pattern)."""
    sources = sorted(fmu_src_dir().glob("*.c")) + sorted(FUZZ.glob("*.c"))
    names = [n.strip() for n in
             re.findall(r"^fun:(.*)$", (FUZZ / ignorelist).read_text(), re.M)]
    assert names, f"{ignorelist} lists no function"
    missing = [n for n in names if not re.fullmatch(r"\w+", n) or not _defines(sources, n)]
    assert not missing, (f"{ignorelist}: entries not the plain name of a function defined"
                         f" in fmu_src/ or tests/fuzz/: {missing}")
    assert not _defines(sources, names[0] + "_misspelt"), "the check can fail"
