"""``djl-fmu demo``: build both FMUs and run the default DJL move."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ._common import interruptible

if TYPE_CHECKING:
    from ._outputs import OutputSet


def register(sub: argparse._SubParsersAction) -> None:
    """Add the ``demo`` command."""
    p = sub.add_parser(
        "demo",
        help="build and validate both FMUs, run the default DJL move, print a summary",
        description=(
            "Build the FMI 2.0 and 3.0 FMUs into OUT, validate them with fmpy, run the FMUs' "
            "default DJL move (Fig. 9 of Bearee & Olabi 2013 brought to rest: d = 0.4 m, "
            "v_max = 1 m/s, a_max = d_max = 10 m/s2, T_F = 80/80/60/50 ms, Te = 1 ms) through "
            "fmpy with both, compare them, and plot the profile against AL and JL."
        ),
    )
    p.add_argument("--out", type=Path, default=Path("djl-fmu-out"), metavar="DIR",
                   help="output folder (default: ./djl-fmu-out)")
    p.add_argument("--no-plot", action="store_true", help="do not write the PNG")
    p.set_defaults(func=interruptible(run))


def run(args: argparse.Namespace) -> int:
    """Run the demo; non-zero exit if a check fails.

    The FMUs and the figure are written as one set (:class:`~harness.commands._outputs.
    OutputSet`): built and checked in a staging folder in OUT, then swapped in together.
    """
    from ..fmu.build import BuildError, check_compiler
    from ._outputs import OutputSet

    out: Path = args.out
    try:
        check_compiler()  # before writing anything
    except BuildError as e:
        print(f"djl-fmu demo: {e}", file=sys.stderr)
        return 1
    if out.exists() and not out.is_dir():
        print(f"djl-fmu demo: --out {out} exists and is not a directory", file=sys.stderr)
        return 2
    try:
        with OutputSet(out) as o:
            ok = _demo(o, args.no_plot)
            o.commit()
    except (BuildError, OSError) as e:
        print(f"djl-fmu demo: cannot write the outputs in {out}: {e}", file=sys.stderr)
        return 1
    if not ok:
        print("djl-fmu demo: a check failed (see above)", file=sys.stderr)
        return 1
    return 0


def _demo(o: OutputSet, no_plot: bool) -> bool:
    """Build, validate and run the FMUs, draw the figure, all in ``o``; True if all passed."""
    from fmpy.validation import validate_fmu

    from ..fmu.build import build_fmu
    from ..fmu.runner import generate

    ok = True
    fmus = {}
    for v in (2, 3):
        name = f"JerkLimitedTrajectory-fmi{v}.fmu"
        fmus[v] = build_fmu(v, o.path(name))
    for v in (2, 3):
        problems = validate_fmu(str(fmus[v]))
        status = "valid" if not problems else "INVALID: " + "; ".join(problems)
        ok &= not problems
        print(f"FMU (FMI {v}.0): {o.final(f'JerkLimitedTrajectory-fmi{v}.fmu')} [{status}]")

    tr = {v: generate(fmu=fmus[v]) for v in (2, 3)}
    d = tr[2]
    p = d.params
    same = all(np.array_equal(getattr(tr[2], n), getattr(tr[3], n))
               for n in ("x", "v", "a", "j", "done"))
    ok &= same
    al = generate({"profile": 1}, fmu=fmus[2])
    jl = generate({"profile": 2}, fmu=fmus[2])
    k_end = int(np.argmax(d.done))
    err_x = d.x[k_end] - (p["x0"] + p["distance"])
    jerk = d.j
    print()
    print("Default DJL move (FMU start values):")
    print(f"  d = {p['distance']} m, v_max = {p['v_max']} m/s, a_max = {p['a_max']} m/s2, "
          f"d_max = {p['d_max']} m/s2, Te = {p['Te'] * 1e3:g} ms")
    print("  jerk times T_F1..T_F4 = " + "/".join(f"{p[f'T_F{i}'] * 1e3:g}" for i in range(1, 5))
          + " ms -> " + "/".join(str(n) for n in d.N_F) + " samples")
    print(f"  motion time        {d.motion_time:.4f} s   (AL {al.motion_time:.4f} s, "
          f"JL with T_F = {p['T_F1'] * 1e3:g} ms {jl.motion_time:.4f} s)")
    print(f"  end position error {err_x:.3g} m at t = {d.t[k_end]:.4f} s (done), "
          f"end velocity {d.v[k_end]:.3g} m/s, end acceleration {d.a[k_end]:.3g} m/s2")
    print(f"  peak |v| {np.abs(d.v).max():.6g} m/s, a in [{d.a.min():.6g}, {d.a.max():.6g}] "
          f"m/s2, |j| <= {np.abs(jerk).max():.6g} m/s3")
    print(f"  FMI 2.0 and FMI 3.0 outputs identical: {'yes' if same else 'NO'} "
          f"({len(d.t)} samples)")
    ok &= abs(err_x) <= 1e-9 * abs(p["distance"])
    if not no_plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig = d.plot(title="Default DJL move (T_F = 80/80/60/50 ms) with its AL input")
        for ax, name in zip(fig.axes, ("x", "v", "a", "j"), strict=True):
            ax.plot(jl.t, getattr(jl, name), ":", lw=1, label=f"{name} JL")
        fig.axes[2].legend(loc="lower right", fontsize="small")
        fig.savefig(o.path("demo_djl.png"), dpi=110)
        plt.close(fig)
        print(f"  plot: {o.final('demo_djl.png')}")
    return bool(ok)
