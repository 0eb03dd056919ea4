"""Benchmark: the optimal and robust tunings of issue #9 on the embedded sweeps.

Prints, per sweep (every distinct move), measured in one run:

* optimal DJL: moves where it leaves more than JL (target 0), its residual as % of JL's
  (mean, target <= 5 %; largest), tuning time per move on one core (median, max; target
  <= 0.5 s);
* robust DJL: its worst residual over a +/-10 % map error as a fraction of JL's (mean,
  target <= 0.6; largest), against the paper rule's, its nominal residual, tuning time per
  move (median, max; target <= 3 s);
* a whole sweep with AL, JL, DJL, DJL-optimal and DJL-robust (tuning, runs, metrics, worst
  cases) on 1 and on 2 worker processes: wall time and speed-up.

    python benchmarks/bench_tuning.py [--every 1] [--skip-parallel]
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import platform
import statistics
import time

import numpy as np

from harness.evaluation import run_case
from harness.results import TABLE2_PROFILES
from harness.scenario import load_scenario
from harness.simulation.session import Session
from harness.sweeps import run_scenario
from harness.tuning.tune import tune_profile


def per_sweep(name: str, every: int) -> None:
    sc = load_scenario(name)
    seen = set()
    t_opt, t_rob, r_opt, w_rob, w_pap, n_rob, worse = [], [], [], [], [], [], 0
    with Session(engine="fast") as s:
        for case in sc.cases()[::every]:
            key = run_case(case, s, keep_runs=False, robustness=False).move_key(TABLE2_PROFILES)
            if key in seen:
                continue
            seen.add(key)
            t0 = time.perf_counter()
            opt = tune_profile(s, case, "DJL-optimal")
            t1 = time.perf_counter()
            rob = tune_profile(s, case, "DJL-robust")
            t2 = time.perf_counter()
            pap = tune_profile(s, case, "DJL")
            from harness.robustness import map_error_residuals

            wp = float(np.max(map_error_residuals(case, s, "DJL", pap.T_F,
                                                  case.uncertainty.worst_errors())))
            t_opt.append(t1 - t0)
            t_rob.append(t2 - t1)
            r_opt.append(opt.search.nominal / opt.search.jl_nominal)
            worse += opt.search.nominal > opt.search.jl_nominal * (1 + 1e-12)
            w_rob.append(rob.search.worst / rob.search.jl_worst)
            w_pap.append(wp / rob.search.jl_worst)
            n_rob.append(rob.search.nominal / rob.search.jl_nominal)
    n = len(r_opt)
    print(f"  {name}: {n} distinct moves")
    print(f"    optimal DJL: worse than JL in {worse} (target 0); residual "
          f"{100 * np.mean(r_opt):.2f} % of JL's on average (target <= 5 %), largest "
          f"{100 * np.max(r_opt):.1f} %; "
          f"tuning {statistics.median(t_opt):.3f} s a move (max {max(t_opt):.3f}; target <= 0.5 s)")
    below = sum(a < b for a, b in zip(w_rob, w_pap, strict=True))
    print(f"    robust DJL: worst over +/-10 % = {np.mean(w_rob):.3f} x JL's on average (target "
          f"<= 0.6), largest {np.max(w_rob):.3f}; paper rule {np.mean(w_pap):.3f} x; below the "
          f"paper rule's in {below} of {n}; nominal "
          f"{np.mean(n_rob):.2f} x JL's; tuning {statistics.median(t_rob):.2f} s a move "
          f"(max {max(t_rob):.2f}; target <= 3 s)")


def parallel(name: str) -> None:
    sc = load_scenario(name)
    sc = dataclasses.replace(sc, compare=dataclasses.replace(
        sc.compare, profiles=("AL", "JL", "DJL", "DJL-optimal", "DJL-robust")))
    times = {}
    for w in (1, 2):
        t0 = time.perf_counter()
        run_scenario(sc, workers=w)
        times[w] = time.perf_counter() - t0
    print(f"  {name} with DJL-optimal and DJL-robust (50 cases, worst cases included): "
          f"1 worker {times[1]:.1f} s, 2 workers {times[2]:.1f} s, speed-up "
          f"{times[1] / times[2]:.2f}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--every", type=int, default=1, help="every N-th case only")
    ap.add_argument("--skip-parallel", action="store_true")
    args = ap.parse_args()
    print(f"{platform.node()}: {platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}")
    print("tuning on the time-varying model, one core")
    for name in ("sweep-X", "sweep-Y"):
        per_sweep(name, args.every)
    if not args.skip_parallel:
        print("a sweep tuned on both cores")
        parallel("sweep-X")


if __name__ == "__main__":
    main()
