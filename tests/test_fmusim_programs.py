"""fmusim with an input file reproduces fmpy on a buffered and a blended program (issue 34).

fmusim (the Modelica Association's Reference-FMUs importer) is not a Python package and not
on a fresh machine: the test runs on demand, with ``DJL_FMUSIM`` naming its executable
(docs/platforms.md, "Importers", says how the one used here was built), and is skipped
otherwise.

Each program is written as fmusim's input file (a CSV: time, then one column per input;
discrete inputs held from their row on and set before the ``doStep`` starting at that time)
and played by fmpy step by step with the same values set before the same steps.  fmusim
writes every output after each step with 16 significant digits: the two runs agree to
that, sample by sample, in FMI 2 and FMI 3 (and so do the command flags, exactly).
"""

from __future__ import annotations

import csv
import os
import subprocess
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from harness.fmu.runner import GeneratorFMU

FMUSIM = os.environ.get("DJL_FMUSIM", "")
pytestmark = pytest.mark.skipif(not (FMUSIM and Path(FMUSIM).is_file()),
                                reason="on demand: DJL_FMUSIM=<path to fmusim>")

TE = 1e-3
STOP = 2.5
PARAMS = {"Te": TE, "distance": 0.0, "profile": 3, "T_F1": 0.04, "T_F2": 0.04, "T_F3": 0.03,
          "T_F4": 0.025}
INPUTS = ("target", "execute", "buffer_mode", "cmd_v_max", "min_duration")

# (time of the row, values held from there): an execute edge is a row with execute 1 and the
# next row (a step later) with execute 0
BUFFERED = [
    (0.0, {"target": 0.0, "execute": 0, "buffer_mode": 0, "cmd_v_max": 0.0,
           "min_duration": 0.0}),
    (0.002, {"target": 0.3, "execute": 1}),
    (0.003, {"execute": 0, "buffer_mode": 1}),
    (0.010, {"target": 0.5, "execute": 1, "cmd_v_max": 0.4}),
    (0.011, {"execute": 0, "cmd_v_max": 0.0}),
    (0.020, {"target": 0.1, "execute": 1, "min_duration": 0.7}),
    (0.021, {"execute": 0, "min_duration": 0.0, "buffer_mode": 0}),
]
BLENDED = [
    (0.0, {"target": 0.0, "execute": 0, "buffer_mode": 0, "cmd_v_max": 0.0,
           "min_duration": 0.0}),
    (0.002, {"target": 0.2, "execute": 1, "cmd_v_max": 0.8}),
    (0.003, {"execute": 0, "buffer_mode": 2, "cmd_v_max": 0.6}),
    (0.004, {"target": 0.5, "execute": 1}),
    (0.005, {"execute": 0, "cmd_v_max": 0.0}),
    (0.006, {"target": 0.9, "execute": 1}),
    (0.007, {"execute": 0, "buffer_mode": 0}),
]


def _rows(program: list[tuple[float, dict[str, Any]]]) -> list[tuple[float, dict[str, Any]]]:
    """Each row with every input (the values held from the rows before)."""
    held: dict[str, Any] = {}
    out = []
    for t, values in program:
        held.update(values)
        out.append((t, dict(held)))
    return out


def _write_input(path: Path, program: list[tuple[float, dict[str, Any]]]) -> None:
    with path.open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time", *INPUTS])
        for t, values in _rows(program):
            w.writerow([repr(t), *[values[n] for n in INPUTS]])


def _fmusim(fmu: Path, program: list, tmp: Path) -> dict[str, np.ndarray]:
    inp, out = tmp / "input.csv", tmp / "output.csv"
    _write_input(inp, program)
    cmd = [FMUSIM, "--interface-type", "cs", "--stop-time", str(STOP), "--output-interval",
           str(TE), "--input-file", str(inp.resolve()), "--output-file", str(out.resolve())]
    for k, v in PARAMS.items():
        cmd += ["--start-value", k, repr(v)]
    done = subprocess.run([*cmd, str(fmu)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    with out.open() as f:
        rows = list(csv.reader(f))
    head = [h.strip('"') for h in rows[0]]
    data = np.array([[float(x) for x in r] for r in rows[1:]])
    return {h: data[:, i] for i, h in enumerate(head)}


def _fmpy(fmu: Path, program: list) -> dict[str, np.ndarray]:
    """The same program stepped by fmpy: the row of each time set before its step; outputs
    recorded at the start and after each step, as fmusim writes them."""
    names = ("x", "v", "a", "queue_length", "active", "done", "time_to_rest", "cmd_error")
    sets: Mapping[int, dict[str, Any]] = {
        round(t / TE): {**v, "execute": bool(v["execute"])} for t, v in _rows(program)}
    with GeneratorFMU(fmu) as g:
        g.set(PARAMS)
        g.set(sets[0])
        g.initialize()
        rec = [[g.time, *[float(g.get(n)) for n in names]]]
        for k in range(round(STOP / TE)):
            if k in sets and k > 0:
                g.set(sets[k])
            g.do_step(TE)
            rec.append([g.time, *[float(g.get(n)) for n in names]])
    data = np.array(rec)
    return {n: data[:, i] for i, n in enumerate(("time", *names))}


@pytest.mark.parametrize("program", [BUFFERED, BLENDED], ids=["buffered", "blended"])
def test_fmusim_input_file_reproduces_fmpy(fmu: Path, program: list, tmp_path: Path) -> None:
    sim = _fmusim(fmu, program, tmp_path)
    ref = _fmpy(fmu, program)
    assert len(sim["time"]) == len(ref["time"])
    np.testing.assert_allclose(sim["time"], ref["time"], rtol=0, atol=1e-12)
    for n in ("x", "v", "a", "time_to_rest"):
        np.testing.assert_allclose(sim[n], ref[n], rtol=1e-15, atol=1e-15, err_msg=n)
    for n in ("queue_length", "active", "done", "cmd_error"):
        np.testing.assert_array_equal(sim[n], ref[n], err_msg=n)
    # the program did what it says: it waited, then landed on the last target
    assert ref["queue_length"].max() >= 2 and not ref["cmd_error"].any()
    last = [v["target"] for _, v in program if "target" in v][-1]
    assert ref["x"][-1] == pytest.approx(last, abs=1e-12) and ref["done"][-1] == 1
