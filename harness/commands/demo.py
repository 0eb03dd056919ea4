"""``djl-fmu demo``: build both FMUs and run the default DJL move."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ..figures import legend_above_data
from ..files import OutputSet
from ..fmu.build import BuildError, build_fmu, check_compiler
from ..fmu.runner import generate
from ._common import OUT_ROOT, CommandError, add_out_option, add_quiet_option, interruptible


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
    add_out_option(p, "demo", default=OUT_ROOT)
    add_quiet_option(p, "the PNG")
    p.set_defaults(func=interruptible(run))


def run(args: argparse.Namespace) -> int:
    """Run the demo; non-zero exit if a check fails.

    The FMUs and the figure are written as one set (:class:`~harness.files.OutputSet`):
    built and checked in a staging folder in OUT, then swapped in together.  A
    :class:`~harness.errors.CommandError` it raises is reported by
    :func:`harness.cli.main` (message and exit status).
    """
    out: Path = args.out
    try:
        check_compiler()  # before writing anything
    except BuildError as e:
        raise CommandError(1, str(e)) from None
    if out.exists() and not out.is_dir():
        raise CommandError(2, f"--out {out} exists and is not a directory")
    try:
        with OutputSet(out) as o:
            ok = _demo(o, args.no_plot, args.quiet)
            o.commit()
    except (BuildError, OSError) as e:
        raise CommandError(1, f"cannot write the outputs in {out}: {e}") from None
    if not ok:
        raise CommandError(1, "a check failed (see above)")
    return 0


def _demo(o: OutputSet, no_plot: bool, quiet: bool = False) -> bool:
    """Build, validate and run the FMUs, draw the figure, all in ``o``; True if all passed."""
    from fmpy.validation import validate_fmu  # deferred: fmpy is heavy to import

    say = (lambda *a, **k: None) if quiet else print
    ok = True
    fmus = {}
    for v in (2, 3):
        name = f"JerkLimitedTrajectory-fmi{v}.fmu"
        fmus[v] = build_fmu(v, o.path(name))
    for v in (2, 3):
        problems = validate_fmu(str(fmus[v]))
        status = "valid" if not problems else "INVALID: " + "; ".join(problems)
        ok &= not problems
        say(f"FMU (FMI {v}.0): {o.final(f'JerkLimitedTrajectory-fmi{v}.fmu')} [{status}]")

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
    say()
    say("Default DJL move (FMU start values):")
    say(f"  d = {p['distance']} m, v_max = {p['v_max']} m/s, a_max = {p['a_max']} m/s2, "
          f"d_max = {p['d_max']} m/s2, Te = {p['Te'] * 1e3:g} ms")
    say("  jerk times T_F1..T_F4 = " + "/".join(f"{p[f'T_F{i}'] * 1e3:g}" for i in range(1, 5))
          + " ms -> " + "/".join(str(n) for n in d.N_F) + " samples")
    say(f"  motion time        {d.motion_time:.4f} s   (AL {al.motion_time:.4f} s, "
          f"JL with T_F = {p['T_F1'] * 1e3:g} ms {jl.motion_time:.4f} s)")
    say(f"  end position error {err_x:.3g} m at t = {d.t[k_end]:.4f} s (done), "
          f"end velocity {d.v[k_end]:.3g} m/s, end acceleration {d.a[k_end]:.3g} m/s2")
    say(f"  peak |v| {np.abs(d.v).max():.6g} m/s, a in [{d.a.min():.6g}, {d.a.max():.6g}] "
          f"m/s2, |j| <= {np.abs(jerk).max():.6g} m/s3")
    say(f"  FMI 2.0 and FMI 3.0 outputs identical: {'yes' if same else 'NO'} "
          f"({len(d.t)} samples)")
    ok &= abs(err_x) <= 1e-9 * abs(p["distance"])
    if not no_plot:
        import matplotlib  # deferred: matplotlib is heavy to import

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        fig = d.plot(title="Default DJL move (T_F = 80/80/60/50 ms) with its AL input",
                     legend=False)
        for ax, name in zip(fig.axes, ("x", "v", "a", "j"), strict=True):
            ax.plot(jl.t, getattr(jl, name), ":", lw=1, label=f"{name} JL")
        # one legend, in headroom above the curves (the styles are the same in every panel)
        legend_above_data(fig.axes[0], loc="upper left",
                          labels=["DJL", "its AL input", f"JL, T_F = {p['T_F1'] * 1e3:g} ms"])
        fig.savefig(o.path("demo_djl.png"), dpi=110)
        plt.close(fig)
        say(f"  plot: {o.final('demo_djl.png')}")
    return bool(ok)
