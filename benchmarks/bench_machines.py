"""Benchmark: the recommendation on random machines of a class, against the physical limit.

For each machine of the class (``harness.machines``: |d| 0.05-0.5 m either sign, v_max
0.2-2 m/s, a_max 2-10 m/s2, Z travelling 0.1-0.6 m, one tabulated mode of 3-5 points at
5-20 Hz falling by up to 45 % or rising by up to 20 % with z, zeta 0.01-0.08, the map
off by +/-5-20 %), ``compare`` runs every method (fast engine, no map-error curves) and
the physical limit (``harness.bound``: no profile at JL's jerk settles sooner in the
worst case of the scoring set), and this prints:

* per machine: the recommended profile's worst-case settling over the scoring set and its
  ratio to the limit, the best jerk-limited peer's (the method of ``compare`` with the
  least worst case among those whose jerk stays within JL's, the recommended left out)
  and its ratio, whether the recommendation is first among the jerk-limited methods,
  which family it is, and the time its design took;
* then the median and the worst of both ratios, and how many machines it was first on.

    python benchmarks/bench_machines.py --n 24 --seed 7 [--workers 2]

The limits are cached on disk (``$DJL_FMU_CACHE/bound``) by the move, the map, the set and
the code: a second run of the same seed costs the recommendations and the peers only.  The
recommendations are designed cold (``DJL_FMU_RECOMMEND_CACHE=off``: the design time printed
is the design's), unless ``--warm``.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import statistics
import sys
import time
from concurrent.futures import ProcessPoolExecutor

from harness.machines import DEFAULT_CLASS, random_machine


def one(seed: int, index: int) -> dict[str, object]:
    """Compare every method on machine ``index`` of ``seed``; return its figures."""
    from harness.peers.compare import compare_scenario  # in the worker

    sc = random_machine(seed, index)
    t0 = time.perf_counter()
    cmp = compare_scenario(sc, engine="fast", map_errors=None)
    wall = time.perf_counter() - t0
    lim = cmp.bound.t_settle
    jl = cmp.jerk_jl * (1.0 + 1e-6)
    limited = {n: mo.settling_worst for n, mo in cmp.methods.items()
               if mo.jerk_peak <= jl and math.isfinite(mo.settling_worst)}
    rec = cmp.methods["recommended"].settling_worst
    peers = {n: v for n, v in limited.items() if n != "recommended"}
    best = min(peers, key=lambda n: peers[n])
    r = cmp.recommendation
    return {"name": sc.name, "description": sc.description, "limit": lim, "rec": rec,
            "peer": best, "peer_t": peers[best],
            "first": "recommended" in limited and rec <= peers[best] * (1 + 1e-9),
            "family": r.best.family if r is not None else "?",
            "design": r.best.design if r is not None else "?",
            "rec_seconds": r.seconds if r is not None else math.nan, "wall": wall}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=24, help="machines (default 24)")
    ap.add_argument("--seed", type=int, default=7, help="seed of the class (default 7)")
    ap.add_argument("--workers", type=int, default=1, help="processes (default 1)")
    ap.add_argument("--warm", action="store_true",
                    help="reuse recommendations cached by an earlier run (default: cold)")
    args = ap.parse_args()
    if not args.warm:
        os.environ["DJL_FMU_RECOMMEND_CACHE"] = "off"  # inherited by the workers
    print(f"# {platform.processor() or platform.machine()}, {os.cpu_count()} cores; "
          f"class: {DEFAULT_CLASS.describe()}; seed {args.seed}, {args.n} machines")
    t0 = time.perf_counter()
    rows = []

    def progress(r: dict[str, object]) -> None:
        print(f"  [{len(rows)}/{args.n}] {r['name']}: recommended / limit "
              f"{float(r['rec']) / float(r['limit']):.3f}, {float(r['wall']):.0f} s",
              file=sys.stderr, flush=True)

    if args.workers > 1:
        with ProcessPoolExecutor(args.workers) as ex:
            for r in ex.map(one, [args.seed] * args.n, range(args.n)):
                rows.append(r)
                progress(r)
    else:
        for i in range(args.n):
            rows.append(one(args.seed, i))
            progress(rows[-1])
    print(f"{'machine':>9} {'limit':>7} {'rec':>7} {'/limit':>7} {'best peer':>14} "
          f"{'peer':>7} {'/limit':>7} {'first':>6}  family (design), design time")
    for r in rows:
        print(f"{r['name']:>9} {r['limit']:7.3f} {r['rec']:7.3f} "
              f"{r['rec'] / r['limit']:7.3f} {r['peer']:>14} {r['peer_t']:7.3f} "
              f"{r['peer_t'] / r['limit']:7.3f} {'yes' if r['first'] else 'NO':>6}  "
              f"{r['family']} ({r['design']}), {r['rec_seconds']:.1f} s")
    rec = [r["rec"] / r["limit"] for r in rows]
    peer = [r["peer_t"] / r["limit"] for r in rows]
    print(f"recommended / limit: median {statistics.median(rec):.3f}, worst {max(rec):.3f}  "
          f"(targets: median <= 1.10, worst <= 1.25)")
    print(f"best jerk-limited peer / limit: median {statistics.median(peer):.3f}, "
          f"worst {max(peer):.3f}")
    print(f"first among the jerk-limited methods on {sum(bool(r['first']) for r in rows)} "
          f"of {len(rows)} machines; recommendation design "
          f"{statistics.median(float(r['rec_seconds']) for r in rows):.1f} s median; "
          f"{time.perf_counter() - t0:.0f} s in all")
    for r in rows:
        print(f"#   {r['name']}: {r['description']}")


if __name__ == "__main__":
    main()
