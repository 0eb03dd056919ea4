"""The FMU driven like a motion controller: a queued program and two synchronised axes (issue 34).

Run:  python examples/motion_program.py   (writes djl-fmu-out/motion_program.png and
      djl-fmu-out/axis_b_input.csv, an input file for fmusim)

1. **A program** given at once, as a PLC would: a move to 0.2 m, then two moves
   *blending* through 0.5 m and 0.8 m without stopping (``buffer_mode = 2``: each passes
   its target at the lower of the two moves' ``v_max``), then a *buffered* move back to
   0.1 m (``buffer_mode = 1``: it waits until the axis rests), with its own
   ``cmd_v_max``.  ``queue_length`` counts the commands waiting.
2. **Two axes ending together**: axis A moves 0.6 m; axis B (another jerk time) moves
   0.1 m one step later with ``min_duration`` = A's ``time_to_rest``, so its velocity is
   lowered until it ends with A.  In an importer, wire A's output ``time_to_rest`` to B's
   input ``min_duration``; the input file written here gives fmusim the same program:

       fmusim --interface-type cs --stop-time 1.5 --output-interval 0.001 \\
           --input-file $PWD/djl-fmu-out/axis_b_input.csv --output-file $PWD/b.csv \\
           --start-value profile 2 --start-value distance 0 --start-value T_F1 0.03 FMU
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from harness.fmu.build import default_fmu  # noqa: E402
from harness.fmu.runner import GeneratorFMU  # noqa: E402

Te = 1e-3
AXIS = {"profile": 3, "Te": Te, "distance": 0.0, "v_max": 1.0, "a_max": 8.0, "d_max": 8.0,
        "T_F1": 0.04, "T_F2": 0.04, "T_F3": 0.03, "T_F4": 0.025}
"""DJL axis at rest at 0: moves come from execute edges."""

PROGRAM: list[tuple[float, dict[str, Any]]] = [  # (time [s], inputs set before that step)
    (0.002, {"target": 0.2, "execute": True, "cmd_v_max": 0.8}),        # aborting (0)
    (0.003, {"execute": False, "buffer_mode": 2, "cmd_v_max": 0.5}),
    (0.004, {"target": 0.5, "execute": True}),                          # blends through 0.2
    (0.005, {"execute": False, "cmd_v_max": 0.0}),
    (0.006, {"target": 0.8, "execute": True}),                          # ... and 0.5
    (0.007, {"execute": False, "buffer_mode": 1, "cmd_v_max": 0.3}),
    (0.008, {"target": 0.1, "execute": True}),                          # waits, then back
    (0.009, {"execute": False, "buffer_mode": 0, "cmd_v_max": 0.0}),
]
OUT = ("x", "v", "queue_length", "active", "done")


def run_program(fmu: Path | None = None, t_end: float = 4.5) -> dict[str, np.ndarray]:
    """Play PROGRAM on one axis; every output of OUT after each step, and the time."""
    sets = {round(t / Te): v for t, v in PROGRAM}
    rec: list[list[float]] = []
    with GeneratorFMU(fmu or default_fmu(2)) as g:
        g.set(AXIS)
        g.initialize()
        for k in range(round(t_end / Te)):
            if k in sets:
                g.set(sets[k])
            g.do_step(Te)
            rec.append([g.time, *[float(g.get(n)) for n in OUT]])
    data = np.array(rec)
    return {n: data[:, i] for i, n in enumerate(("t", *OUT))}


def synchronised(fmu: Path | None = None, t_end: float = 1.5
                 ) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray], float]:
    """Axis A 0.6 m; axis B 0.1 m a step later with min_duration = A's time_to_rest."""
    path = fmu or default_fmu(2)
    rec: dict[str, list[list[float]]] = {"A": [], "B": []}
    with GeneratorFMU(path, instance_name="A") as a, GeneratorFMU(path, instance_name="B") as b:
        a.set(AXIS)
        b.set({**AXIS, "profile": 2, "T_F1": 0.03})
        a.initialize()
        b.initialize()
        wired = 0.0
        for k in range(round(t_end / Te)):
            # a master's communication point: read the outputs, set the inputs, step both
            if k == 2:
                a.set({"target": 0.6, "execute": True})
            if k == 3:
                wired = float(a.get("time_to_rest"))
                b.set({"target": 0.1, "execute": True, "min_duration": wired})
            a.do_step(Te)
            b.do_step(Te)
            for name, g in (("A", a), ("B", b)):
                rec[name].append([g.time, float(g.get("x")), float(g.get("v")),
                                  float(g.get("done"))])
    out = {n: dict(zip(("t", "x", "v", "done"), np.array(r).T, strict=True))
           for n, r in rec.items()}
    return out["A"], out["B"], wired


def write_fmusim_input(path: Path, min_duration: float) -> None:
    """Axis B's program as fmusim's input file (held values, set before the step at t)."""
    path.write_text("time,target,execute,min_duration\n"
                    "0,0,0,0\n"
                    f"0.003,0.1,1,{min_duration!r}\n"
                    f"0.004,0.1,0,{min_duration!r}\n")


def main() -> None:
    out = Path("djl-fmu-out")
    out.mkdir(exist_ok=True)
    p = run_program()
    A, B, wired = synchronised()
    end = {n: r["t"][np.flatnonzero(np.abs(r["v"]) > 0)[-1] + 1] for n, r in (("A", A), ("B", B))}
    print(f"program: {int(p['queue_length'].max())} commands waited; ended at "
          f"x = {p['x'][-1]:.6f} m, t = {p['t'][np.flatnonzero(np.abs(p['v']) > 0)[-1] + 1]:.3f} s")
    for x1 in (0.2, 0.5):
        k = int(np.argmin(np.abs(p["x"] - x1)))
        print(f"  passes {x1} m at {p['v'][k]:.3f} m/s (blending)")
    print(f"synchronised: A rests at {end['A']:.3f} s, B at {end['B']:.3f} s "
          f"(B's min_duration = A's time_to_rest = {wired:.3f} s)")
    write_fmusim_input(out / "axis_b_input.csv", wired)
    fig, ax = plt.subplots(3, 1, figsize=(8, 8), sharex=False)
    ax[0].plot(p["t"], p["x"], label="x (m)")
    ax[0].plot(p["t"], p["v"], label="v (m/s)")
    ax[0].step(p["t"], p["queue_length"] / 10, where="post", label="queue_length / 10")
    ax[0].set_title("A program: blending through 0.2 and 0.5 m, then buffered back to 0.1 m")
    ax[0].legend(loc="upper right")
    for name, r in (("A (0.6 m)", A), ("B (0.1 m, min_duration)", B)):
        ax[1].plot(r["t"], r["x"], label=name)
        ax[2].plot(r["t"], r["v"], label=name)
    ax[1].set_ylabel("x (m)")
    ax[2].set_ylabel("v (m/s)")
    ax[2].set_xlabel("t (s)")
    ax[1].set_title("Two axes ending together (time_to_rest -> min_duration)")
    ax[1].legend()
    fig.tight_layout()
    fig.savefig(out / "motion_program.png", dpi=100)
    print(f"wrote {out / 'motion_program.png'} and {out / 'axis_b_input.csv'}")


if __name__ == "__main__":
    main()
