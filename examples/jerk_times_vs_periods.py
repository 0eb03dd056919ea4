"""DJL jerk times of the paper's, the optimal and the robust tuning against the local periods.

Run:  python examples/jerk_times_vs_periods.py   (writes docs/img/jerk-times-vs-periods.png)
      python examples/jerk_times_vs_periods.py --all --scenario sweep-Y --out my.png

For the moves of an embedded sweep (default ``sweep-X``, the paper's test set:
its cases with d = 0.1, 0.3 and 0.5 m, 25 distinct moves; ``--all``: the 50
cases, 45 distinct moves) the DJL jerk times are tuned three ways on the fast engine
(``tune_profile(Session(engine="fast"), ...)``): ``paper`` (each jerk time = the modal period
where its stage starts), ``optimal`` (least residual on the nominal map) and
``robust`` (least worst residual over a ±10 % map error); see docs/tuning.md.
The figure puts each stage's jerk time against the local period at its start
(``TuningResult.periods``): the paper's points sit on the diagonal, the
optimised ones spread away from it — they do not cancel each stage but make
the four stage remainders cancel one another (harness.tuning.remainder).  A case that
plans the same move as an earlier one (same paper tuning: stage starts, jerk
times, Z positions) is tuned once.  The moves are spread over the cores: about
15 s on 2 idle cores (``--all``: 30 s).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from harness.scenario import load_scenario  # noqa: E402
from harness.simulation.session import Session  # noqa: E402
from harness.tuning.remainder import plot_jerk_times  # noqa: E402
from harness.tuning.rule import TuningResult  # noqa: E402
from harness.tuning.tune import tune_profile  # noqa: E402

METHODS = ("paper", "optimal", "robust")
ROOT = Path(__file__).resolve().parents[1]


def tune_case(args: tuple[str, int]) -> dict[str, TuningResult]:
    """Tune case ``index`` of sweep ``name`` with the three methods (in a worker)."""
    name, index = args
    case = load_scenario(name).cases()[index]
    out = {}
    with Session(engine="fast") as s:
        for m in METHODS:
            sc = dataclasses.replace(case, compare=dataclasses.replace(case.compare,
                                                                       djl_tuning=m))
            tu = tune_profile(s, sc, "DJL")
            assert tu is not None
            out[m] = tu
    return out


def main(argv: list[str] | None = None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenario", default="sweep-X", help="an embedded sweep (default sweep-X)")
    p.add_argument("--out", type=Path, default=ROOT / "docs" / "img" / "jerk-times-vs-periods.png")
    p.add_argument("--distances", default="0.1,0.3,0.5",
                   help="the sweep's move distances kept (m, comma-separated)")
    p.add_argument("--all", action="store_true", help="every case of the sweep")
    p.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    a = p.parse_args(argv)
    sc = load_scenario(a.scenario)
    keep = [float(x) for x in a.distances.split(",")]
    t0 = time.perf_counter()
    jobs, seen = [], set()
    with Session(engine="fast") as s:
        for i, case in enumerate(sc.cases()):
            if not a.all and not any(abs(case.move.distance - d) < 1e-12 for d in keep):
                continue
            tu = tune_profile(s, case, "DJL")  # the paper's rule (2 ms): identifies the move
            assert tu is not None
            key = (tu.N_F, tu.instants, tu.z, case.z.z0)
            if key not in seen:
                seen.add(key)
                jobs.append((a.scenario, i))
    n = len(jobs)
    if a.workers > 1:
        with ProcessPoolExecutor(a.workers) as ex:
            tuned = list(ex.map(tune_case, jobs))
    else:
        tuned = [tune_case(j) for j in jobs]
    results = {m: [t[m] for t in tuned] for m in METHODS}
    print(f"{a.scenario}: {n} moves tuned three ways in {time.perf_counter() - t0:.1f} s")
    print("method    mean |T_Fi / P_i - 1| per stage        mean nominal residual")
    for m, tus in results.items():
        dev = [sum(abs(tu.T_F[i] / tu.periods[i] - 1) for tu in tus) / len(tus)
               for i in range(4)]
        res = [tu.search.nominal for tu in tus if tu.search is not None]
        mean_res = f"{1e3 * sum(res) / len(res):.4f} mm" if res else "-"
        print(f"{m:9s} " + "  ".join(f"{100 * d:5.1f} %" for d in dev) + f"      {mean_res}")
    fig = plot_jerk_times(results, title=f"{sc.name}: DJL jerk times against the local "
                                         f"periods ({n} moves)")
    a.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(a.out, dpi=120)
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
