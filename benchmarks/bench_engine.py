"""Benchmark: the fast engine against the FMU engine; djl-fmu simulate; a 10,000-move map.

Prints, measured in one run on this machine (medians):

1. one sweep move (tune JL and DJL, synchronise Z, co-simulate AL/JL/DJL, metrics: one
   ``run_case`` of the embedded sweeps) through the fast engine and through the FMU engine,
   and their ratio (targets: fast <= 5 ms; issue #8);
2. ``djl-fmu simulate`` (default scenarios, plots and FMUs included) as a user runs it, in a
   subprocess, with the FMU build cache warm and cold (target <= 5 s), and where its time
   goes: Python imports, the FMU builds, each scenario, the figures;
3. a map of 10,000 moves (AL, JL, paper-rule DJL, metrics) on 2 workers (target <= 60 s),
   the per-move cost, and the speed-up from 1 to 2 workers on the first moves.

    python benchmarks/bench_engine.py [--repeat 3] [--map-moves 10000] [--skip-map]
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from harness.evaluation import run_case
from harness.scenario import load_scenario
from harness.simulation.session import Session


def sweep_moves(step: int) -> list:
    """Every ``step``-th case of both embedded sweeps."""
    cases = load_scenario("sweep-X").cases() + load_scenario("sweep-Y").cases()
    return cases[::step]


def per_move(engine: str, cases: list, repeat: int, uncertainty: bool = False) -> list[float]:
    """Seconds of ``run_case`` for each case (median over ``repeat`` runs each).

    ``uncertainty``: also score every profile over the scenario's scoring set (41 map
    scales, worst residual and worst-case settling; the default of ``run_case`` since
    issue 18); without, the nominal metrics the issue-8 target was set for.
    """
    out = []
    with Session(engine=engine) as s:
        run_case(cases[0], s, keep_runs=False, uncertainty=uncertainty)  # warm-up
        for c in cases:
            ts = []
            for _ in range(repeat):
                t0 = time.perf_counter()
                run_case(c, s, keep_runs=False, uncertainty=uncertainty)
                ts.append(time.perf_counter() - t0)
            out.append(statistics.median(ts))
    return out


def simulate_wall(out: Path, env: dict[str, str]) -> float:
    """Wall time of ``djl-fmu simulate`` (default scenarios) in a fresh process."""
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-m", "harness.cli", "simulate", "-q", "-o", str(out)],
                   check=True, capture_output=True, env=env)
    return time.perf_counter() - t0


def import_seconds() -> float:
    """Python start-up and the imports of the simulate command (median of 5)."""
    code = ("import harness.cli, harness.sweeps, harness.simulation.fast_axis, harness.results, "
            "matplotlib; matplotlib.use('Agg'); import matplotlib.pyplot")
    ts = []
    for _ in range(5):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], check=True)
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def profile_simulate() -> None:
    """Where the time of ``djl-fmu simulate`` goes, measured in this process."""
    import matplotlib

    matplotlib.use("Agg")
    from harness.files import save_figure
    from harness.fmu.build import build_fmu
    from harness.sweeps import run_scenario

    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        for v in (2, 3):
            build_fmu(v, Path(tmp) / f"f{v}.fmu")
        print(f"    building both FMUs with gcc (cold cache only): "
              f"{time.perf_counter() - t0:6.2f} s")
        for name in ("X", "Y", "sweep-X", "sweep-Y"):
            t0 = time.perf_counter()
            r = run_scenario(name)
            t1 = time.perf_counter()
            save_figure(r.plot(), Path(tmp) / f"{name}.png")
            t2 = time.perf_counter()
            engine = "fast" if name.startswith("sweep") else "fmu"
            print(f"    {name:8s} ({engine} engine): run {t1 - t0:6.2f} s, figure {t2 - t1:5.2f} s")


def bench_map(moves: int) -> None:
    from harness.workspace import run_workspace_map

    sc = load_scenario("X")
    n_small = min(moves, 1000)
    for w in (1, 2):
        t0 = time.perf_counter()
        run_workspace_map(sc, workers=w, max_moves=n_small)
        dt = time.perf_counter() - t0
        print(f"  first {n_small} moves, {w} worker(s): {dt:6.2f} s  "
              f"({dt / n_small * 1e3:.2f} ms a move)")
        if w == 1:
            t1 = dt
    print(f"  speed-up 1 -> 2 workers: {t1 / dt:.2f}")
    t0 = time.perf_counter()
    res = run_workspace_map(sc, workers=2, max_moves=moves)
    dt = time.perf_counter() - t0
    n = len(res.rows()) // max(1, len(sc.compare.profiles))
    print(f"  {n} moves on 2 workers: {dt:6.1f} s ({dt / max(n, 1) * 1e3:.2f} ms a move; "
          f"target <= 60 s for 10,000)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--map-moves", type=int, default=10000)
    ap.add_argument("--skip-map", action="store_true")
    ap.add_argument("--skip-simulate", action="store_true")
    args = ap.parse_args()
    print(f"{platform.node()}: {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, Python {platform.python_version()}")

    print("1. one sweep move (run_case: tuning, Z sync, AL/JL/DJL, metrics)")
    fast_all = per_move("fast", sweep_moves(1), args.repeat)
    common = sweep_moves(10)
    fast_c = per_move("fast", common, args.repeat)
    fmu_c = per_move("fmu", common, 1)
    mf, mu = statistics.median(fast_c), statistics.median(fmu_c)
    print(f"  fast engine, all {len(fast_all)} sweep moves: median "
          f"{statistics.median(fast_all) * 1e3:.2f} ms, max {max(fast_all) * 1e3:.2f} ms "
          f"(target <= 5 ms)")
    print(f"  the same {len(common)} moves: fast {mf * 1e3:.2f} ms, fmu {mu * 1e3:.1f} ms, "
          f"ratio fmu/fast {mu / mf:.0f}")
    unc = per_move("fast", common, args.repeat, uncertainty=True)
    mu_ = statistics.median(unc)
    print(f"  with the uncertainty scoring (41 map scales per profile, run_case's default): "
          f"fast {mu_ * 1e3:.2f} ms a move, {mu_ / mf:.1f} x the nominal metrics")

    if not args.skip_simulate:
        print("2. djl-fmu simulate (default scenarios, plots and FMUs)")
        with tempfile.TemporaryDirectory() as tmp:
            env = dict(os.environ, DJL_FMU_CACHE=str(Path(tmp) / "cache"))
            cold = simulate_wall(Path(tmp) / "out0", env)
            warm = statistics.median(simulate_wall(Path(tmp) / f"out{i}", env)
                                     for i in range(1, 4))
        print(f"  warm build cache: {warm:.2f} s (median of 3; target <= 5 s); "
              f"cold (first run, builds both FMUs): {cold:.2f} s")
        print(f"  of which Python start-up and imports: {import_seconds():.2f} s")
        profile_simulate()

    if not args.skip_map:
        print("3. map of the embedded scenario X (AL, JL, DJL paper rule, metrics)")
        bench_map(args.map_moves)


if __name__ == "__main__":
    main()
