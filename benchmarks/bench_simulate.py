"""Benchmark: ``djl-fmu simulate`` (the default scenarios) with a warm cache (issue 18).

Runs the command once to warm the caches (FMU builds, recommendations, figures), then
``--repeats`` more times, each a fresh process as a user would start it, and prints the
median wall time (target: 5 s) and the CPU time of the command and its workers.

    python benchmarks/bench_simulate.py [--repeats 3] [--cold-figures]

``--cold-figures`` renders every figure again (a folder of its own as the figure cache:
what a run after a change of the data or of the plotting code costs).
"""

from __future__ import annotations

import argparse
import os
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time


def _run(out: str, env: dict[str, str]) -> tuple[float, float]:
    """One ``djl-fmu simulate``: wall seconds, CPU seconds (the process and its children)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "harness.cli", "simulate", "--out", out, "--quiet"],
                   check=True, env=env, stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=3, help="timed runs (default 3)")
    ap.add_argument("--cold-figures", action="store_true",
                    help="render the figures on every run (no figure cache)")
    args = ap.parse_args()
    print(f"{platform.node()}: {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}")
    env = dict(os.environ)
    with tempfile.TemporaryDirectory(prefix="djl-bench-sim-") as tmp:
        out = os.path.join(tmp, "out")
        _run(out, env)  # warm: FMU builds, recommendations, figures
        walls, cpus = [], []
        for i in range(args.repeats):
            if args.cold_figures:  # an empty figure cache each time: every figure drawn
                env["DJL_FMU_FIGURES"] = os.path.join(tmp, f"figures-{i}")
            w, c = _run(out, env)
            walls.append(w)
            cpus.append(c)
    what = "figures rendered" if args.cold_figures else "warm cache"
    print(f"djl-fmu simulate (default scenarios, {what}), {args.repeats} runs: median "
          f"{statistics.median(walls):.2f} s wall (min {min(walls):.2f}, max {max(walls):.2f}; "
          f"target 5 s), CPU {statistics.median(cpus):.2f} s (command and workers)")


if __name__ == "__main__":
    main()
