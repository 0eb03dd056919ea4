"""Measurements shared by the benchmark scripts (imported from this folder)."""

from __future__ import annotations

import statistics
import subprocess
import time
from collections.abc import Callable, Iterable, Mapping
from pathlib import Path
from typing import Any

from harness._resources import fmu_src_dir
from harness.fmu.build import CFLAGS, default_fmu
from harness.fmu.codegen import CORE_SOURCES
from harness.fmu.runner import GeneratorFMU

STREAM_SRC = Path(__file__).parent / "c" / "bench_stream.c"


def build_stream(folder: Path) -> Path:
    """Compile benchmarks/c/bench_stream.c with the FMU's optimisation flags; return the exe."""
    exe = folder / "bench_stream"
    flags = [f for f in CFLAGS if f not in ("-fPIC", "-fvisibility=hidden")]
    subprocess.run(["gcc", *flags, f"-I{fmu_src_dir()}", str(STREAM_SRC),
                    *[str(fmu_src_dir() / f) for f in CORE_SOURCES], "-o", str(exe), "-lm"],
                   check=True, capture_output=True)
    return exe


def stream_rate(exe: Path, T_F: float, Te: float, distance: float,
                repeats: int) -> tuple[int, float]:
    """Samples of a JL move computed one by one in C, and the median seconds it took."""
    out = subprocess.run([str(exe), repr(T_F), repr(Te), repr(distance), str(repeats)],
                         capture_output=True, text=True, check=True).stdout
    rows = [line.split() for line in out.splitlines()]
    return int(rows[0][0]), statistics.median(float(r[1]) for r in rows)


def c_plan_seconds(exe: Path, profile: int, distance: float, count: int = 20000) -> float:
    """Median seconds the C core takes to plan one move (v_max 0.5, a_max 4, T_F 152 ms)."""
    out = subprocess.run([str(exe), "plan", str(profile), repr(distance), str(count)],
                         capture_output=True, text=True, check=True).stdout
    return float(out)


def fmu_seconds_per_sample(fmi_version: int, params: Mapping[str, Any], n: int,
                           repeats: int) -> float:
    """Median seconds per doStep(h = Te) + getReal of x, v, a, j through fmpy."""
    with GeneratorFMU(default_fmu(fmi_version), params=params) as g:
        g.initialize()
        Te = float(g.get("Te"))
        vrs = g.vr(["x", "v", "a", "j"])
        step, get = g.fmu.doStep, g.get_reals
        state = g.get_state()
        times = []
        for _ in range(repeats):
            g.set_state(state, 0.0)
            t = 0.0
            t0 = time.perf_counter()
            for _ in range(n):
                step(currentCommunicationPoint=t, communicationStepSize=Te)
                get(vrs)
                t += Te
            times.append((time.perf_counter() - t0) / n)
        g.free_state(state)
    return statistics.median(times)


def seconds_per_call(call: Callable[[Any], Any], args: Iterable[Any], repeats: int) -> float:
    """Median over ``repeats`` runs of the mean seconds of ``call(a)`` over ``args``."""
    args = list(args)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for a in args:
            call(a)
        times.append((time.perf_counter() - t0) / len(args))
    return statistics.median(times)
