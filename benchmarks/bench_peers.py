"""Benchmark: the generator FMU against ruckig, and the co-simulation with either reference.

Prints, in one run on this machine (medians of --repeats runs):

1. samples per second of the reference, produced one sample at a time from Python:
   the FMU (C) through fmpy (``doStep(h = Te)`` + ``getReal`` of x, v, a, j) and
   ruckig's ``Trajectory.at_time`` -- and, for scale, the C core computing every
   sample in a C loop (benchmarks/c/bench_stream.c, when gcc is available);
2. planning time per move: the FMU re-planned (``fmi2Reset``, parameters,
   initialisation, read ``motion_time``) against ``Ruckig.calculate``, and Park et
   al.'s closed forms in Python;
3. the co-simulation real-time factor (simulated / wall time) of a 10 s run at 1 ms
   of scenario X: the generator FMU as the excited axis (harness.simulation), and a
   precomputed time-optimal reference from ruckig (harness.peers.compare).

The ratios FMU / ruckig are printed beside the numbers.

    python benchmarks/bench_peers.py [--repeats 7]
"""

from __future__ import annotations

import argparse
import platform
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np
from _common import (
    build_stream,
    c_plan_seconds,
    fmu_seconds_per_sample,
    seconds_per_call,
    stream_rate,
)

from harness.fmu.build import default_fmu
from harness.peers.compare import cosimulate_reference
from harness.peers.park import park_profile
from harness.peers.ruckig_ref import planner, time_optimal
from harness.scenario import load_scenario
from harness.simulation.fmu_axis import FMUAxis
from harness.simulation.session import Session

TE = 1e-3
MOVE = {"distance": 0.4, "v_max": 0.5, "a_max": 4.0, "d_max": 4.0}
T_F = 0.152  # JL of scenario X
J_MAX = MOVE["a_max"] / T_F


def fmu_per_sample(n: int, repeats: int) -> float:
    """Median seconds per sample: doStep(h = Te) + getReal(x, v, a, j) through fmpy."""
    return fmu_seconds_per_sample(2, dict(MOVE, profile=2, T_F1=T_F, Te=TE), n, repeats)


def ruckig_per_sample(n: int, repeats: int) -> float:
    """Median seconds per ``at_time`` call (position, velocity, acceleration)."""
    r = time_optimal(MOVE["distance"], MOVE["v_max"], MOVE["a_max"], J_MAX)
    return seconds_per_call(r.trajectory.at_time, np.arange(n) * (r.duration / n), repeats)


def c_core(repeats: int) -> tuple[float, float] | None:
    """Samples/s of the C core computing every sample, and its planning time per JL move (s).

    None without gcc.
    """
    try:
        with tempfile.TemporaryDirectory() as tmp:
            exe = build_stream(Path(tmp))
            n, seconds = stream_rate(exe, 0.01, 1e-4, 1000.0, repeats)
            return n / seconds, c_plan_seconds(exe, 2, MOVE["distance"])
    except (OSError, subprocess.CalledProcessError):
        return None


def _distances(n: int) -> list[float]:
    return np.random.default_rng(0).uniform(0.05, 1.0, n).tolist()


def fmu_plan(n: int, repeats: int) -> float:
    """Median seconds per re-plan of one FMU instance (distances vary)."""
    with FMUAxis(default_fmu(2)) as ax:
        base = dict(MOVE, profile=2, T_F1=T_F, Te=TE)
        return seconds_per_call(lambda d: ax.plan(dict(base, distance=d)), _distances(n),
                                repeats)


def ruckig_plan(n: int, repeats: int) -> float:
    """Median seconds per ``Ruckig.calculate`` (objects reused, distances vary)."""
    otg, inp, traj = planner(MOVE["v_max"], MOVE["a_max"], J_MAX)

    def plan(d: float) -> None:
        inp.target_position = [d]
        otg.calculate(inp, traj)

    return seconds_per_call(plan, _distances(n), repeats)


def park_plan(n: int, repeats: int) -> float:
    """Median seconds per closed-form plan (Python)."""
    return seconds_per_call(lambda d: park_profile(d, MOVE["v_max"], MOVE["a_max"], J_MAX),
                            _distances(n), repeats)


def cosim_rtf(repeats: int, t_stop: float = 10.0) -> tuple[float, float]:
    """Real-time factors of 10 s of scenario X: FMU reference, and ruckig's reference."""
    sc = load_scenario("X")
    ref = time_optimal(MOVE["distance"], MOVE["v_max"], MOVE["a_max"], J_MAX).motion()
    fmu_w, ref_w = [], []
    with Session() as s:
        s.run(sc, "JL", (T_F,) * 4, t_stop=t_stop)  # warm-up
        for _ in range(repeats):
            t0 = time.perf_counter()
            s.run(sc, "JL", (T_F,) * 4, t_stop=t_stop)
            fmu_w.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            cosimulate_reference(sc, s, ref, "time-optimal JL", t_stop=t_stop)
            ref_w.append(time.perf_counter() - t0)
    return t_stop / statistics.median(fmu_w), t_stop / statistics.median(ref_w)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    r = args.repeats
    print(f"{platform.processor() or platform.machine()}, Python {platform.python_version()}; "
          f"move {MOVE['distance']} m, v_max {MOVE['v_max']} m/s, a_max {MOVE['a_max']} m/s2, "
          f"j_max {J_MAX:.3g} m/s3 (T_F = {T_F * 1e3:g} ms), Te = {TE * 1e3:g} ms; "
          f"medians of {r} runs\n")

    fs = fmu_per_sample(20000, r)
    rs = ruckig_per_sample(20000, r)
    cc = c_core(r)
    print(f"{'':44s}{'FMU (C)':>14s}{'ruckig':>14s}{'FMU/ruckig':>12s}")
    print(f"{'samples/s, one at a time from Python':44s}{1 / fs:14.3e}{1 / rs:14.3e}"
          f"{rs / fs:12.2f}")
    print(f"{'  (us per sample)':44s}{fs * 1e6:14.2f}{rs * 1e6:14.2f}")
    if cc is not None:
        print(f"{'samples/s, C core, every sample in C':44s}{cc[0]:14.3e}{'-':>14s}")

    fp = fmu_plan(2000, r)
    rp = ruckig_plan(20000, r)
    pp = park_plan(20000, r)
    print(f"{'planning time per move, from Python [us]':44s}{fp * 1e6:14.2f}{rp * 1e6:14.2f}"
          f"{fp / rp:12.1f}")
    if cc is not None:
        print(f"{'planning time per move, C core alone [us]':44s}{cc[1] * 1e6:14.2f}"
              f"{rp * 1e6:14.2f}{cc[1] / rp:12.1f}")
        print("  (from Python the FMU pays fmpy's calls: reset, one setter per parameter, "
              "initialisation)")
    print(f"  (Park et al.'s closed forms in Python: {pp * 1e6:.2f} us per move)")

    rtf_fmu, rtf_ref = cosim_rtf(max(3, r // 2))
    print(f"{'co-simulation real-time factor, 10 s of X':44s}{rtf_fmu:14.1f}{rtf_ref:14.1f}"
          f"{rtf_fmu / rtf_ref:12.2f}")
    print("\nFMU: the generator FMU through fmpy (a few us per call); ruckig: the Python "
          "binding.\nThe co-simulation steps the Z-axis FMU and the plant in both columns; the "
          "'ruckig'\ncolumn feeds the plant a precomputed time-optimal reference instead of "
          "stepping the\nexcited axis' FMU.")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
