"""DJL with f_mode given online, against the offline-tuned DJL (issue #12).

Run:  python examples/online_fmode.py   (writes djl-fmu-out/online_fmode.png)

The excited axis' FMU runs with ``jerk_source = 3`` (``f_mode_ahead``): each
constant-jerk stage still to come lasts round(1/(f·Te)) samples, f the
``f_mode`` input extrapolated at its rate over the last step to the sample
where the plan starts the stage, so the deceleration is placed for the jerk
times it will have (``jerk_source = 2`` takes ``f_mode`` as read at the step
before the stage).  The co-simulation master sets ``f_mode`` at every step to
the mode map's frequency at the Z generator's current position: the paper's
rule (the modal period at the start of each stage) applied while the move
runs, with no tuning beforehand.  The same as ``djl-fmu online X``
(``--jerk-source both`` puts 2 and 3 side by side).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from harness.online import JERK_SOURCE_F_MODE_AHEAD, run_online  # noqa: E402

# the default scenario: Table 1's X move while Z descends 0.45 m
res = run_online("X", jerk_source=JERK_SOURCE_F_MODE_AHEAD)
print(res.table())
out = Path("djl-fmu-out")
out.mkdir(exist_ok=True)
res.plot().savefig(out / "online_fmode.png", dpi=100)
print(f"plot: {out / 'online_fmode.png'}")
