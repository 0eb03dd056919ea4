"""Redraw the generator figures of Béarée & Olabi 2013 with the FMU.

- Fig. 4: adapted AL profile and the JL profile it gives (T_F = 30 ms,
  a_max = 10 m/s², v_max = 2 m/s, v_e = 0.4 m/s, d = 1 m);
- Fig. 5: JL on a multi-segment motion (T_F = 10 ms; the figure's segment
  list is garbled in the text, a representative one is used);
- Fig. 9: DJL example 1 (T_F = 80/80/60/50 ms, v_e = 0.2 m/s, d = 0.4 m);
- Fig. 10: DJL example 2 (T_F = 20/30/60/80 ms, d = 0.1 m).

Run: ``python examples/paper_generator_figures.py [OUT_DIR]`` (PNG files).
"""

from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from harness.fmu.runner import generate  # noqa: E402

FIGURES = {
    "fig4_jl_from_adapted_al": (
        {"profile": 2, "T_F1": 0.03, "a_max": 10.0, "d_max": 10.0, "v_max": 2.0, "v_e": 0.4,
         "distance": 1.0},
        "Fig. 4: adapted AL profile and JL (T_F = 30 ms)"),
    "fig5_multisegment_jl": (
        {"profile": 2, "T_F1": 0.01, "a_max": 10.0, "d_max": 10.0, "v_max": 2.0,
         "n_segments": 4, "seg_distance": [0.2, 0.5, 0.3, 0.4],
         "seg_v_end": [0.5, 1.0, 0.8, 0.0]},
        "Fig. 5: JL on a multi-segment motion (T_F = 10 ms)"),
    "fig9_djl_example1": (
        {"profile": 3, "T_F1": 0.08, "T_F2": 0.08, "T_F3": 0.06, "T_F4": 0.05, "a_max": 10.0,
         "d_max": 10.0, "v_max": 1.0, "v_e": 0.2, "distance": 0.4},
        "Fig. 9: DJL example 1 (T_F = 80/80/60/50 ms)"),
    "fig10_djl_example2": (
        {"profile": 3, "T_F1": 0.02, "T_F2": 0.03, "T_F3": 0.06, "T_F4": 0.08, "a_max": 10.0,
         "d_max": 10.0, "v_max": 1.0, "v_e": 0.0, "distance": 0.1},
        "Fig. 10: DJL example 2 (T_F = 20/30/60/80 ms)"),
}


def main(out: Path) -> list[Path]:
    """Write one PNG per figure into ``out``; return their paths."""
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name, (params, title) in FIGURES.items():
        traj = generate(params)
        fig = traj.plot(title=title)
        path = out / f"{name}.png"
        fig.savefig(path, dpi=100)
        plt.close(fig)
        k = int(traj.done.argmax())
        print(f"{path}: motion time {traj.motion_time:.3f} s, x at the end = {traj.x[k]:.12g} m, "
              f"jerk times {'/'.join(map(str, traj.N_F))} samples")
        written.append(path)
    return written


if __name__ == "__main__":
    main(Path(sys.argv[1]) if len(sys.argv) > 1 else Path("djl-fmu-out/paper-figures"))
