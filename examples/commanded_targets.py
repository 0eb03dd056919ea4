"""Commanded generator FMU: targets (and one stop) sent while the simulation runs (issue #12).

Run:  python examples/commanded_targets.py   (writes djl-fmu-out/commanded_targets.png)

The FMU starts at rest (``distance = 0``: no parametric move) and is driven by
its inputs only: a rising edge of ``execute`` moves from the current state —
at rest or in motion — to ``target``, ending at rest; a rising edge of ``stop``
brings the axis to rest.  ``busy`` is true while a move runs, ``stage`` shows
the constant-jerk stage in progress (1..4, 0 when none).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from harness.fmu.runner import GeneratorFMU  # noqa: E402

Te = 1e-3
PARAMS = {"profile": 3, "Te": Te, "x0": 0.0, "distance": 0.0, "v_max": 0.5, "a_max": 4.0,
          "d_max": 4.0, "T_F1": 0.05, "T_F2": 0.06, "T_F3": 0.07, "T_F4": 0.08}
"""DJL with four jerk times; no parametric move: the axis waits at x0 for a command."""

COMMANDS = [  # (time [s], inputs): an execute edge needs execute=False at some step in between
    (0.05, {"target": 0.30, "execute": True}),   # go to 0.30 m
    (0.10, {"execute": False}),
    (0.40, {"target": 0.10, "execute": True}),   # change of mind mid-move: back to 0.10 m
    (0.45, {"execute": False}),
    (1.20, {"target": 0.45, "execute": True}),   # from rest to 0.45 m ...
    (1.25, {"execute": False}),
    (1.45, {"stop": True}),                      # ... stopped on the way
    (1.50, {"stop": False}),
    (2.00, {"target": -0.05, "execute": True}),  # then to -0.05 m
    (2.05, {"execute": False}),
]
T_STOP = 3.0
REALS = ("x", "v", "a", "j")
FLAGS = ("busy", "stage")


def simulate(params: dict[str, Any] = PARAMS,
             commands: list[tuple[float, dict[str, Any]]] = COMMANDS, t_stop: float = T_STOP,
             fmi_version: int = 2, fmu: str | Path | None = None
             ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Run the FMU with the commands; return the time and the recorded outputs (one per Te)."""
    with GeneratorFMU(fmu, fmi_version=fmi_version, params=params) as g:
        g.initialize()
        ts: list[np.ndarray] = []
        vals: dict[str, list[np.ndarray]] = {n: [] for n in REALS + FLAGS}
        k = 0
        for t_cmd, inputs in [*commands, (t_stop, {})]:
            n = round(t_cmd / Te) - k        # steps of Te up to the command
            t, v = g.record(n, Te, REALS, FLAGS)
            first = 1 if ts else 0           # record() repeats the point it starts from
            ts.append(t[first:])
            for name in vals:
                vals[name].append(v[name][first:])
            k += n
            if inputs:
                g.set_inputs(**inputs)
    return np.concatenate(ts), {n: np.concatenate(v) for n, v in vals.items()}


def main() -> None:
    t, v = simulate()
    busy = v["busy"].astype(bool)
    print("commands:")
    for t_cmd, inputs in COMMANDS:
        if inputs.get("execute") or inputs.get("stop"):
            print(f"  t = {t_cmd:.2f} s: " + ", ".join(f"{k} = {x}" for k, x in inputs.items()))
    # each time busy falls, the axis has come to rest: where?
    ends = np.flatnonzero(busy[:-1] & ~busy[1:]) + 1
    print("moves ended (busy falls):")
    for k in ends:
        print(f"  t = {t[k]:.3f} s at x = {v['x'][k]:+.6f} m, v = {v['v'][k]:.1e} m/s, "
              f"a = {v['a'][k]:.1e} m/s2")
    print(f"peak |v| {np.abs(v['v']).max():.3f} m/s (v_max {PARAMS['v_max']}), "
          f"a in [{v['a'].min():.3f}, {v['a'].max():.3f}] m/s2 "
          f"(a_max {PARAMS['a_max']}, d_max {PARAMS['d_max']})")

    fig, axes = plt.subplots(5, 1, sharex=True, figsize=(9, 9))
    targets = np.full(t.size, np.nan)
    cur = np.nan
    for t_cmd, inputs in COMMANDS:
        if inputs.get("execute"):
            cur = inputs["target"]
            targets[t >= t_cmd] = cur
    axes[0].plot(t, targets, "k--", lw=0.8, drawstyle="steps-post", label="target (on execute)")
    axes[0].plot(t, v["x"], label="x")
    axes[1].plot(t, v["v"])
    axes[2].plot(t, v["a"])
    axes[3].plot(t, v["busy"], drawstyle="steps-post")
    axes[4].plot(t, v["stage"], drawstyle="steps-post")
    for ax, lab in zip(axes, ("x [m]", "v [m/s]", "a [m/s²]", "busy", "stage"), strict=True):
        ax.set_ylabel(lab)
        ax.grid(True, alpha=0.3)
        for t_cmd, inputs in COMMANDS:
            if inputs.get("execute") or inputs.get("stop"):
                ax.axvline(t_cmd, color="tab:red" if inputs.get("stop") else "0.6", lw=0.8,
                           ls=":")
    axes[0].legend(loc="lower right", fontsize="small")
    axes[3].set_yticks([0, 1])
    axes[4].set_yticks([0, 1, 2, 3, 4])
    axes[-1].set_xlabel("t [s]  (dotted: execute edges; red: the stop)")
    fig.suptitle("Commanded DJL generator FMU: targets sent during the simulation")
    fig.tight_layout()
    out = Path("djl-fmu-out")
    out.mkdir(exist_ok=True)
    fig.savefig(out / "commanded_targets.png", dpi=100)
    print(f"plot: {out / 'commanded_targets.png'}")


if __name__ == "__main__":
    main()
