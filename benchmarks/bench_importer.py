"""Benchmark: the generator FMU's binary driven by a native C importer (issue #10, item 8).

A C master (benchmarks/c/bench_importer.c) dlopen()s the FMU's shared library and steps
it one sample at a time: per sample one fmi2DoStep of Te and one fmi2GetReal of x, v, a,
j. Prints the samples per second (median of the repeats) next to the generator core alone
producing every sample (benchmarks/c/bench_stream.c): the difference is the FMI layer's
cost per call. Target: >= 20 M samples/s (goal 50 M).

    python benchmarks/bench_importer.py [--samples 20000000] [--repeats 5]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import tempfile
import zipfile
from pathlib import Path

from _common import build_stream, stream_rate

from harness.fmu import spec
from harness.fmu.build import default_fmu, fmi_include_dir

SRC = Path(__file__).parent / "c" / "bench_importer.c"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--samples", type=int, default=20_000_000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        fmu = default_fmu(2)
        with zipfile.ZipFile(fmu) as z:
            z.extractall(root / "fmu")
        lib = next((root / "fmu" / "binaries").rglob(f"{spec.MODEL_IDENTIFIER}.*"))
        exe = root / "bench_importer"
        subprocess.run(["gcc", "-std=c99", "-O2", "-D_POSIX_C_SOURCE=199309L",
                        f"-I{fmi_include_dir()}", str(SRC), "-o", str(exe), "-ldl"],
                       check=True, capture_output=True)
        vr = [str(spec.BY_NAME[n].vr) for n in ("x", "v", "a", "j")]
        uri = (root / "fmu" / "resources").as_uri()
        out = subprocess.run([str(exe), str(lib), spec.INSTANTIATION_TOKEN, uri, *vr, "1e-3",
                              str(args.samples), str(args.repeats)],
                             capture_output=True, text=True, check=True).stdout
        secs = [float(line.split()[1]) for line in out.splitlines()]
        rate = args.samples / statistics.median(secs)
        core_n, core_s = stream_rate(build_stream(root), 0.1, 1e-4, 1000.0, args.repeats)
    print(f"native importer, FMI 2.0, doStep(Te) + getReal(x, v, a, j) per sample: "
          f"{rate / 1e6:.1f} M samples/s ({1e9 / rate:.1f} ns a sample; target >= 20 M, "
          f"goal 50 M)")
    print(f"the generator core alone, every sample: {core_n / core_s / 1e6:.1f} M samples/s "
          f"({core_s / core_n * 1e9:.1f} ns a sample)")


if __name__ == "__main__":
    main()
