"""Benchmark: the cost of one replan of the commanded generator (issue #12: <= 5 us).

Compiles benchmarks/c/bench_replan.c with the FMU's optimisation flags and runs it:
for the default DJL move and a JL move, commands at 10 %, 20 %, ... 90 % of the
motion (acceleration, cruise, deceleration): a target ahead, a target behind (the
axis stops and comes back: two plans), a stop, and new jerk times (an f_mode
replan).  Prints each situation's median time per replan, then the median and the
worst over all situations against the 5 us target.  Medians of repeated runs: the
machine is small and shared.

Then (issue 34) the cost of the whole FMI 3 ``DoStep`` that carries a command
(benchmarks/c/bench_commands.c, through the FMU's API): a step without command, today's
aborting execute, a buffered execute (queued), the step at which it starts, a blending
execute (the blend speed and the move in progress replanned), the step at which the
blended command starts, and an aborting execute with ``min_duration`` (a bisection of
replans), each beside today's aborting execute as a ratio.

    python benchmarks/bench_replan.py [--count 20000] [--repeats 7]
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import tempfile
from pathlib import Path

from harness._resources import fmu_src_dir
from harness.fmu.build import CFLAGS, PORTABLE_CFLAGS, fmi_include_dir
from harness.fmu.codegen import CORE_SOURCES

SRC = Path(__file__).parent / "c" / "bench_replan.c"
SRC_COMMANDS = Path(__file__).parent / "c" / "bench_commands.c"
TARGET_S = 5e-6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--count", type=int, default=20000, help="replans per timed run")
    ap.add_argument("--repeats", type=int, default=7, help="timed runs per situation")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        exe = Path(tmp) / "bench_replan"
        flags = [f for f in CFLAGS if f not in ("-fPIC", "-fvisibility=hidden")]
        subprocess.run(["gcc", *flags, f"-I{fmu_src_dir()}", str(SRC),
                        *[str(fmu_src_dir() / f) for f in CORE_SOURCES], "-o", str(exe),
                        "-lm"], check=True, capture_output=True)
        out = subprocess.run([str(exe), str(args.count), str(args.repeats)],
                             capture_output=True, text=True, check=True).stdout
        cmd_exe = Path(tmp) / "bench_commands"
        src = fmu_src_dir()
        subprocess.run(["gcc", *flags, *PORTABLE_CFLAGS, f"-I{src}", f"-I{fmi_include_dir()}",
                        str(SRC_COMMANDS), str(src / "fmi3.c"),
                        *[str(f) for f in sorted(src.glob("fmu_*.c"))],
                        *[str(src / f) for f in CORE_SOURCES], "-o", str(cmd_exe), "-lm"],
                       check=True, capture_output=True)
        cmd_out = subprocess.run([str(cmd_exe), str(max(args.count // 10, 1)),
                                  str(args.repeats)],
                                 capture_output=True, text=True, check=True).stdout
    rows = [line.rsplit(" ", 2) for line in out.splitlines()]
    hows = {"1": "new move", "2": "stop, then move", "3": "stop"}
    print(f"{'situation':<34} {'us/replan':>10}  replan")
    for name, sec, how in rows:
        print(f"{name:<34} {float(sec) * 1e6:10.2f}  {hows.get(how, how)}")
    times = [float(sec) for _, sec, _ in rows]
    med, worst = statistics.median(times), max(times)
    print(f"\nmedian over {len(times)} situations: {med * 1e6:.2f} us; worst: "
          f"{worst * 1e6:.2f} us; target <= {TARGET_S * 1e6:.0f} us: "
          f"{'met' if med <= TARGET_S else 'NOT met'} (median), "
          f"{'met' if worst <= TARGET_S else 'not met'} (worst)")
    cmds = [line.rsplit("|", 1) for line in cmd_out.splitlines()]
    today = dict(cmds)["aborting execute (today)"]
    print(f"\n{'FMI 3 DoStep carrying (issue 34)':<34} {'us/step':>10}  x today's execute")
    for name, sec in cmds:
        print(f"{name:<34} {float(sec) * 1e6:10.2f}  {float(sec) / float(today):6.2f}")


if __name__ == "__main__":
    main()
