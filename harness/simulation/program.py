"""A program of commands run on the generator: the FMU's model compiled, or the FMU itself.

A *program* is what a PLC or a CNC sends the generator FMU: at given times, values of its
inputs (``target``, ``execute``, ``stop``, ``buffer_mode``, ``min_duration``, the
``cmd_*`` values, ``f_mode``), each set before the communication step that starts at that
time and held until changed (docs/generator.md, "Commanded moves", "Buffer modes").

:func:`run_program` plays one and returns every output after every step, with either engine:

* ``"compiled"`` (default): the FMU's own model (``fmu_src/fmu_model.c`` under
  ``fmu_instance.c``: its ``DoStep``, its queue, its per-command values and errors; no FMI
  layer) compiled into :mod:`harness._engine`, the whole program in one call;
* ``"fmu"``: the generator FMU through fmpy, one FMI call per step.

Both take the same commands and give the same outputs bit for bit
(``tests/test_program_engines.py``).

Examples
--------
>>> from harness.simulation.program import run_program
>>> run = run_program({"distance": 0.0},
...                   [(0.002, {"target": 0.3, "execute": True}), (0.003, {"execute": False}),
...                    (0.004, {"target": 0.5, "buffer_mode": 1, "execute": True})], 1.5)
>>> round(float(run["x"][-1]), 9), int(run["queue_length"].max())
(0.5, 1)
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Literal

import numpy as np

from ..compiled import engine as _compiled_engine
from ..errors import HarnessError
from ..fmu import spec
from ..fmu.build import default_fmu
from ..fmu.runner import GeneratorFMU

Program = Sequence[tuple[float, Mapping[str, Any]]]
"""(time in s, inputs set before the step starting then), in time order."""


class ProgramError(HarnessError, ValueError):
    """A program the generator cannot run (a time off the step grid, an unknown input)."""


@dataclass(frozen=True)
class ProgramRun:
    """Every output of the generator after every step of a program.

    Attributes
    ----------
    t : numpy.ndarray
        Time after each step (s): ``start_time + (k + 1) h``.
    outputs : dict of str to numpy.ndarray
        Each output of the FMU (``x``, ``v``, ``a``, ``j``, ``done``, ``queue_length``,
        ``active``, ``time_to_rest``, ``cmd_error``, ...), one value per step.
    engine : str
        ``"compiled"`` or ``"fmu"``.
    """

    t: np.ndarray
    outputs: dict[str, np.ndarray] = field(repr=False)
    engine: str = "compiled"

    def __getitem__(self, name: str) -> np.ndarray:
        return self.outputs[name]

    def plot(self, names: Sequence[str] = ("x", "v", "a"), *, title: str | None = None):
        """Plot outputs against time, one panel each; the queue length shaded.

        Returns
        -------
        matplotlib.figure.Figure
        """
        import matplotlib.pyplot as plt  # deferred: plotting is optional

        fig, axes = plt.subplots(len(names), 1, sharex=True, figsize=(8, 2.2 * len(names)),
                                 squeeze=False)
        units = {v.name: v.unit for v in spec.OUTPUTS}
        for ax, n in zip(axes[:, 0], names, strict=True):
            ax.plot(self.t, self.outputs[n])
            ax.set_ylabel(f"{n} ({units.get(n) or '-'})")
            q = self.outputs["queue_length"]
            ax.fill_between(self.t, 0, 1, where=q > 0, transform=ax.get_xaxis_transform(),
                            alpha=0.1, label="commands waiting")
        axes[-1, 0].set_xlabel("t (s)")
        axes[0, 0].legend(loc="upper right")
        if title:
            axes[0, 0].set_title(title)
        fig.tight_layout()
        return fig


def _steps(program: Program, h: float, start_time: float) -> list[tuple[int, dict[str, Any]]]:
    out: list[tuple[int, dict[str, Any]]] = []
    inputs = {v.name for v in spec.INPUTS}
    last = -1
    for i, (t, values) in enumerate(program):
        k = (float(t) - start_time) / h
        kr = round(k)
        if not (abs(k - kr) <= 1e-9 * max(1.0, abs(k))) or kr < 0:
            raise ProgramError(f"program[{i}]: t = {t!r} s is not a communication point "
                               f"(start_time + k h, h = {h!r} s, k >= 0)")
        if kr < last:
            raise ProgramError(f"program[{i}]: t = {t!r} s comes before the row above")
        unknown = set(values) - inputs
        if unknown:
            raise ProgramError(f"program[{i}]: {sorted(unknown)} are not inputs of the FMU "
                               f"(its inputs: {sorted(inputs)})")
        out.append((kr, dict(values)))
        last = kr
    return out


def run_program(params: Mapping[str, Any], program: Program, t_end: float,
                h: float | None = None, *, engine: Literal["compiled", "fmu"] = "compiled",
                fmu: str | Path | None = None, start_time: float = 0.0) -> ProgramRun:
    """Run a program of commands on the generator.

    Parameters
    ----------
    params : mapping
        FMU parameters (names of :mod:`harness.fmu.spec`); the others at their start values.
    program : sequence of (float, mapping)
        (time in s, inputs): the inputs set before the step that starts at that time, held
        until changed.  Times are communication points (``start_time + k h``).
    t_end : float
        Time of the last communication point (s): ``round((t_end - start_time) / h)`` steps.
    h : float, optional
        Communication step (s); default the generator's ``Te``.
    engine : {"compiled", "fmu"}
        The FMU's model compiled into the harness (one call), or the FMU through fmpy.
    fmu : path, optional
        The FMU for ``engine="fmu"`` (default: the host build, made on first use).
    start_time : float
        The FMU's start time (s).

    Returns
    -------
    ProgramRun

    Raises
    ------
    ProgramError
        A time off the grid or out of order, or an unknown input.
    harness.errors.HarnessError
        The FMU refuses a parameter or a step (the compiled engine: its ``PlanError``).
    """
    Te = float(params.get("Te", spec.DEFAULT_TE))
    h = Te if h is None else float(h)
    if not (h > 0.0 and np.isfinite(h)):
        raise ProgramError(f"h = {h!r} s: must be a finite step > 0")
    count = max(0, round((float(t_end) - start_time) / h))
    steps = _steps(program, h, start_time)
    t = start_time + h * np.arange(1, count + 1)
    if engine == "compiled":
        eng = _compiled_engine()
        names = eng.output_names()
        out = np.zeros((len(names), count))
        # Booleans as numbers (the model takes 0/1)
        prog = [(k, {n: (float(v) if isinstance(v, bool) else v) for n, v in d.items()})
                for k, d in steps]
        eng.run_program(dict(params), prog, count, h, out, start_time)
        return ProgramRun(t, {n: out[i] for i, n in enumerate(names)}, "compiled")
    if engine != "fmu":
        raise ProgramError(f"engine = {engine!r}: 'compiled' or 'fmu'")
    booleans = {v.name for v in spec.INPUTS if v.type == "Boolean"}
    names = tuple(v.name for v in spec.OUTPUTS)
    rows = np.zeros((len(names), count))
    by_step: dict[int, dict[str, Any]] = {}
    for k, d in steps:
        by_step.setdefault(k, {}).update(d)
    with GeneratorFMU(fmu or default_fmu(2), start_time=start_time) as g:
        g.set(dict(params))
        g.initialize()
        for k in range(count):
            if k in by_step:
                g.set({n: (bool(v) if n in booleans else v) for n, v in by_step[k].items()})
            g.do_step(h)
            for i, n in enumerate(names):
                rows[i, k] = float(g.get(n))
    return ProgramRun(t, {n: rows[i] for i, n in enumerate(names)}, "fmu")
