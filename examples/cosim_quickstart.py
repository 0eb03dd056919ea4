"""Co-simulation quickstart: AL / JL / DJL on a flexible axis whose mode moves with Z.

Run:  python examples/cosim_quickstart.py   (writes djl-fmu-out/cosim_quickstart.png)

1. the embedded scenario "X" of the paper (Béarée & Olabi 2013, §4) in one call;
2. the same axis built in Python: a lookup-table mode map, a heavier load, a second
   mode, on the FMI 3.0 FMU;
3. the low-level pieces: tuning DJL, one co-simulation, and the plant alone.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import matplotlib

matplotlib.use("Agg")

from harness.modemap import ConstantLaw, ModeMap, ModeSpec, TableLaw  # noqa: E402
from harness.plant import Mode, simulate_mode  # noqa: E402
from harness.scenario import load_scenario  # noqa: E402
from harness.simulation.session import Session  # noqa: E402
from harness.sweeps import run_scenario  # noqa: E402
from harness.tuning.tune import tune_profile  # noqa: E402

# 1. one call: tune JL and DJL from the mode map, co-simulate, measure
result = run_scenario("X")
print(result.table())
fig = result.plot()
Path("djl-fmu-out").mkdir(exist_ok=True)
fig.savefig("djl-fmu-out/cosim_quickstart.png", dpi=100)

# 2. my axis: a modal survey (z, f) instead of the linear law, a load 20 % heavier
#    (period ∝ √mass), and a 30 Hz second mode; FMI 3.0 FMU
sc = load_scenario("X")
survey = TableLaw(z=(0.0, 0.1, 0.2, 0.3, 0.4, 0.5), f=(8.6, 8.3, 7.8, 7.3, 6.9, 6.4))
mine = dataclasses.replace(
    sc, name="my axis", description="X move on my axis: surveyed mode, heavier load, 30 Hz mode",
    modemap=ModeMap((ModeSpec(survey, zeta=0.03, mass_ratio=1.2, name="Z bending"),
                     ModeSpec(ConstantLaw(30.0), zeta=0.02, gain=0.1, name="30 Hz"))),
)
res2 = run_scenario(mine, fmi_version=3)
print()
print(res2.table())

# 3. the pieces
with Session(fmi_version=2) as s:
    tuning = tune_profile(s, sc, "DJL")  # iterates plan -> stage starts -> periods
    print("\n" + tuning.describe())
    print("stage starts [s]:", [round(t, 3) for t in tuning.instants],
          " z there [m]:", [round(z, 3) for z in tuning.z])
    run = s.run(sc, "DJL", tuning.T_F)  # the master: 2 FMUs + plant, 1 ms steps
    print(f"free-oscillation amplitude at the end: {run.free_amplitude * 1e3:.3f} mm "
          f"({run.t.size - 1} steps in {run.wall_time * 1e3:.0f} ms)")

# the plant alone, on the recorded reference: same numbers as inside the co-simulation
spec = sc.modemap.tuned
r = simulate_mode(run.t, run.a, Mode(spec.f(0.0), spec.zeta), f=spec.f, z=run.z, v_z=run.v_z)
print(f"plant alone: max |difference| with the co-simulation "
      f"{abs(r.eps - run.eps).max():.1e} m")
