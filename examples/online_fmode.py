"""DJL with f_mode given online, against the offline-tuned DJL (issue #12).

Run:  python examples/online_fmode.py   (writes djl-fmu-out/online_fmode.png)

The excited axis' FMU runs with ``jerk_source = 2``: each constant-jerk stage
lasts round(1/(f_mode·Te)) samples, ``f_mode`` read at the step before it starts.  The
co-simulation master sets ``f_mode`` at every step to the mode map's frequency
at the Z generator's current position: the paper's rule (the modal period at
the start of each stage) applied while the move runs, with no tuning
beforehand.  The same as ``djl-fmu online X``.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from harness.online import run_online  # noqa: E402

res = run_online("X")   # the default scenario: Table 1's X move while Z descends 0.45 m
print(res.table())
out = Path("djl-fmu-out")
out.mkdir(exist_ok=True)
res.plot().savefig(out / "online_fmode.png", dpi=100)
print(f"plot: {out / 'online_fmode.png'}")
