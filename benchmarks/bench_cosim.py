"""Benchmark: a 10 s co-simulation at 1 ms (10,000 steps, two generator FMUs and the plant).

Prints, for the FMI 2.0 and FMI 3.0 FMUs, the median wall time over several runs and the
real-time factor (simulated time / wall time).  Target (issue 3): under 1 s.

    python benchmarks/bench_cosim.py [--repeat 7] [--t-stop 10] [--step 0.001]

"run" is one call of Session.run: re-planning both FMU instances (reset), synchronising
the Z move (bisection on the FMU's planner), the 10,000-step loop (two doStep, two
getReal and the plant per step) and the result arrays.  "loop" is the stepping loop alone.
Creating the two FMU instances (unzip + load, once per scenario) is reported apart.
"""

from __future__ import annotations

import argparse
import dataclasses
import platform
import statistics
import time

from harness.scenario import load_scenario
from harness.simulation.session import Session


def bench(fmi_version: int, repeat: int, t_stop: float, step: float) -> None:
    sc = load_scenario("X")
    sc = dataclasses.replace(sc, simulation=dataclasses.replace(sc.simulation, step=step))
    t0 = time.perf_counter()
    session = Session(fmi_version=fmi_version)
    t_open = time.perf_counter() - t0
    runs, loops = [], []
    try:
        session.run(sc, "DJL", (0.118, 0.120, 0.142, 0.147), t_stop=t_stop)  # warm-up
        for _ in range(repeat):
            t0 = time.perf_counter()
            r = session.run(sc, "DJL", (0.118, 0.120, 0.142, 0.147), t_stop=t_stop)
            runs.append(time.perf_counter() - t0)
            loops.append(r.wall_time)
    finally:
        session.close()
    n = r.t.size - 1
    med, med_loop = statistics.median(runs), statistics.median(loops)
    print(f"FMI {fmi_version}.0: {t_stop:g} s at {step * 1e3:g} ms = {n} steps, 2 FMU instances "
          f"+ plant ({len(r.eps_modes)} mode)")
    print(f"  run  median {med * 1e3:7.1f} ms   real-time factor {t_stop / med:6.1f}   "
          f"({med / n * 1e6:.2f} us/step)   min {min(runs) * 1e3:.1f} ms, max "
          f"{max(runs) * 1e3:.1f} ms over {repeat}")
    print(f"  loop median {med_loop * 1e3:7.1f} ms   real-time factor {t_stop / med_loop:6.1f}")
    print(f"  opening the two FMU instances: {t_open * 1e3:.1f} ms (once per scenario)")
    print(f"  target < 1 s: {'met' if med < 1.0 else 'NOT met'}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--t-stop", type=float, default=10.0)
    ap.add_argument("--step", type=float, default=1e-3)
    args = ap.parse_args()
    print(f"python {platform.python_version()}, {platform.machine()}, {platform.processor() or ''}")
    for v in (2, 3):
        bench(v, args.repeat, args.t_stop, args.step)


if __name__ == "__main__":
    main()
