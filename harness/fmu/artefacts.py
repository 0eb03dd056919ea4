"""Artefacts of a reference FMU beside its binaries.

:func:`write_artefacts` adds to an unpacked FMU folder:

- ``documentation/licenses/LICENSE.txt``: the project's licence (BSD-3-Clause, the text of
  the repository's ``LICENSE``; a test checks they agree);
- an icon drawn here, without any drawing library: FMI 2 ``model.png``; FMI 3
  ``terminalsAndIcons/icon.png`` with ``terminalsAndIcons/terminalsAndIcons.xml``;
- ``documentation/index.html``: the variable table, the communication-step rule and a plot
  of the default move (``documentation/default_move.png``);
- a reference result of the default parameters: ``documentation/<model>_ref.csv`` and
  ``_ref.opt`` (the FMI cross-check layout, which :func:`write_cross_check` also writes next
  to an FMU), and the FMI-LS-REF layout under ``extra/org.fmi-standard.fmi-ls-ref/``
  (``fmi-ls-manifest.xml`` describing one experiment and its reference result).

The reference result is sampled by the generator core itself (``harness._engine``, the
FMU's own C code compiled into the harness, whose samples equal the FMU's bit for bit), at
the default experiment's step.
"""

from __future__ import annotations

import html
import struct
import zlib
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from ..errors import BuildError
from . import codegen, spec
from .codegen import DEFAULT_STOP_TIME

LICENSE_TEXT = """BSD 3-Clause License

Copyright (c) 2026, the djl-fmu developers
All rights reserved.

Redistribution and use in source and binary forms, with or without
modification, are permitted provided that the following conditions are met:

1. Redistributions of source code must retain the above copyright notice, this
   list of conditions and the following disclaimer.

2. Redistributions in binary form must reproduce the above copyright notice,
   this list of conditions and the following disclaimer in the documentation
   and/or other materials provided with the distribution.

3. Neither the name of the copyright holder nor the names of its
   contributors may be used to endorse or promote products derived from
   this software without specific prior written permission.

THIS SOFTWARE IS PROVIDED BY THE COPYRIGHT HOLDERS AND CONTRIBUTORS "AS IS"
AND ANY EXPRESS OR IMPLIED WARRANTIES, INCLUDING, BUT NOT LIMITED TO, THE
IMPLIED WARRANTIES OF MERCHANTABILITY AND FITNESS FOR A PARTICULAR PURPOSE ARE
DISCLAIMED. IN NO EVENT SHALL THE COPYRIGHT HOLDER OR CONTRIBUTORS BE LIABLE
FOR ANY DIRECT, INDIRECT, INCIDENTAL, SPECIAL, EXEMPLARY, OR CONSEQUENTIAL
DAMAGES (INCLUDING, BUT NOT LIMITED TO, PROCUREMENT OF SUBSTITUTE GOODS OR
SERVICES; LOSS OF USE, DATA, OR PROFITS; OR BUSINESS INTERRUPTION) HOWEVER
CAUSED AND ON ANY THEORY OF LIABILITY, WHETHER IN CONTRACT, STRICT LIABILITY,
OR TORT (INCLUDING NEGLIGENCE OR OTHERWISE) ARISING IN ANY WAY OUT OF THE USE
OF THIS SOFTWARE, EVEN IF ADVISED OF THE POSSIBILITY OF SUCH DAMAGE.
"""
"""The project's licence; the repository's ``LICENSE`` holds the same text."""

REF_OUTPUTS = ("x", "v", "a", "j", "x_AL", "v_AL", "a_AL")
"""Outputs in the reference result, in the order of the generator core's samples."""

LS_REF_DIR = "extra/org.fmi-standard.fmi-ls-ref"
"""Folder of the FMI-LS-REF layered standard inside the FMU."""

ICON_SIZE = 128


# --------------------------------------------------------------------------- icon


def _png(width: int, height: int, rgba: bytes) -> bytes:
    """Encode RGBA pixels (rows top to bottom) as a PNG file."""

    def chunk(tag: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + tag + data
                + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))

    stride = 4 * width
    raw = b"".join(b"\x00" + rgba[y * stride:(y + 1) * stride] for y in range(height))
    return (b"\x89PNG\r\n\x1a\n"
            + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def _smoothstep(u: float) -> float:
    """Position of a jerk-limited transition on [0, 1] (a cubic S)."""
    u = min(max(u, 0.0), 1.0)
    return u * u * (3.0 - 2.0 * u)


def icon_png(size: int = ICON_SIZE) -> bytes:
    """Draw the FMU's icon: a jerk-limited velocity profile (S-curves) on a rounded tile.

    Parameters
    ----------
    size : int
        Width and height in pixels.

    Returns
    -------
    bytes
        A PNG file.
    """
    bg, fg, axis = (246, 248, 252, 255), (31, 119, 180, 255), (90, 90, 90, 255)
    px = bytearray(4 * size * size)
    r = size // 8  # corner radius of the tile

    def put(x: int, y: int, c: tuple[int, int, int, int]) -> None:
        if 0 <= x < size and 0 <= y < size:
            px[4 * (y * size + x):4 * (y * size + x) + 4] = bytes(c)

    for y in range(size):
        for x in range(size):
            cx = min(max(x, r), size - 1 - r)
            cy = min(max(y, r), size - 1 - r)
            if (x - cx) ** 2 + (y - cy) ** 2 <= r * r:
                put(x, y, bg)
    m = size // 8
    x0, x1, y0, y1 = m, size - 1 - m, size - 1 - m, m + size // 6
    for x in range(x0, x1 + 1):  # time axis
        put(x, y0, axis)
    for y in range(y1 - m // 2, y0 + 1):  # velocity axis
        put(x0, y, axis)
    width = max(2, size // 40)
    prev = None
    for i in range(4 * size + 1):  # the profile: up, cruise, down (thick line)
        u = i / (4 * size)
        level = _smoothstep(u / 0.3) - _smoothstep((u - 0.62) / 0.28)
        x = x0 + 2 + u * (x1 - x0 - 4)
        y = y0 - 2 - level * (y0 - y1 - 2)
        pts = [(x, y)] if prev is None else [
            (prev[0] + (x - prev[0]) * k / 4, prev[1] + (y - prev[1]) * k / 4) for k in range(5)]
        for qx, qy in pts:
            for dx in range(-width, width + 1):
                for dy in range(-width, width + 1):
                    if dx * dx + dy * dy <= width * width:
                        put(int(round(qx)) + dx, int(round(qy)) + dy, fg)
        prev = (x, y)
    return _png(size, size, bytes(px))


def terminals_and_icons_xml() -> str:
    """Text of FMI 3's ``terminalsAndIcons/terminalsAndIcons.xml`` (an icon, no terminals)."""
    return ('<?xml version="1.0" encoding="UTF-8"?>\n'
            '<fmiTerminalsAndIcons fmiVersion="3.0">\n'
            '  <GraphicalRepresentation>\n'
            '    <CoordinateSystem x1="-100" y1="-100" x2="100" y2="100"/>\n'
            '    <Icon x1="-100" y1="-100" x2="100" y2="100"/>\n'
            '  </GraphicalRepresentation>\n'
            '</fmiTerminalsAndIcons>\n')


# --------------------------------------------------------------------------- reference result


def reference_result(step: float | None = None, stop_time: float | None = None,
                     fmu_dir: Path | None = None) -> tuple[list[float], list[list[float]]]:
    """Sample the default move at the default experiment's communication points.

    Parameters
    ----------
    step, stop_time : float, optional
        Communication step and stop time (s); the ``DefaultExperiment``'s by default.
    fmu_dir : pathlib.Path, optional
        An unpacked FMU with this machine's binary, simulated with fmpy when the harness's
        compiled core (``harness._engine``) is not importable (e.g. ``python -m`` from a
        source checkout whose extension is installed elsewhere).  Both give the same
        samples, bit for bit (tests/test_engine.py).

    Returns
    -------
    time : list of float
        The communication points, ``k * step``.
    rows : list of list of float
        For each point, the outputs :data:`REF_OUTPUTS`.
    """
    step = spec.DEFAULT_TE if step is None else step
    stop_time = DEFAULT_STOP_TIME if stop_time is None else stop_time
    try:
        from .. import _engine  # deferred: not importable from a source checkout (not built)
    except ImportError:
        if fmu_dir is None:
            raise
        from fmpy import simulate_fmu  # deferred: fmpy is heavy to import

        res = simulate_fmu(str(fmu_dir), start_time=0.0, stop_time=stop_time,
                           output_interval=step, output=list(REF_OUTPUTS))
        return ([float(t) for t in res["time"]],
                [[float(res[n][i]) for n in REF_OUTPUTS] for i in range(len(res))])
    plan = _engine.plan({})
    n = int(round(stop_time / step))
    per = step / plan.Te
    k = round(per)
    if abs(per - k) > 1e-9 or k < 1:
        raise ValueError(f"step {step!r} s is not a whole number of samples of Te = {plan.Te} s")
    out = np.empty((_engine.N_SAMPLE_VARS, n + 1))
    plan.sample_into(out, 0, k, n + 1)
    time = [i * step for i in range(n + 1)]
    return time, out.T.tolist()


def ref_csv_text(time: Sequence[float], rows: Sequence[Sequence[float]]) -> str:
    """Format the reference result as the cross-check's CSV: quoted header, ``time`` first."""
    lines = [",".join(f'"{n}"' for n in ("time", *REF_OUTPUTS))]
    lines += [",".join(repr(float(v)) for v in (t, *row))
              for t, row in zip(time, rows, strict=True)]
    return "\n".join(lines) + "\n"


def ref_opt_text(step: float | None = None, stop_time: float | None = None) -> str:
    """Write the cross-check's ``_ref.opt``: the settings that reproduce the reference result."""
    step = spec.DEFAULT_TE if step is None else step
    stop_time = DEFAULT_STOP_TIME if stop_time is None else stop_time
    return (f"StartTime, 0.0\nStopTime, {stop_time!r}\nStepSize, {step!r}\n"
            f"RelTol, 1e-06\n")


def ls_ref_manifest(ref_name: str) -> str:
    """FMI-LS-REF manifest: one experiment (the default), its reference result, the licence."""
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<fmiReferences xmlns:fmi-ls="http://fmi-standard.org/fmi-ls-manifest"
  fmi-ls:fmi-ls-name="org.fmi-standard.fmi-ls-ref" fmi-ls:fmi-ls-version="1.0.0-alpha.1"
  fmi-ls:fmi-ls-description="Reference result of the default parameters of {spec.MODEL_NAME}">
  <Experiment name="default" description="The default move (all parameters at their start \
values), sampled at every communication point" startTime="0.0" stopTime="{DEFAULT_STOP_TIME!r}" \
stepSize="{spec.DEFAULT_TE!r}">
    <References source="{ref_name}" type="text/csv"/>
  </Experiment>
  <Reference role="license" source="../../documentation/licenses/LICENSE.txt"/>
  <Reference role="documentation" source="../../documentation/index.html"/>
</fmiReferences>
"""


# --------------------------------------------------------------------------- documentation


def default_move_plot(path: Path, time: Sequence[float], rows: Sequence[Sequence[float]]) -> None:
    """Draw x, v, a and j of the default move into ``path`` (PNG)."""
    import matplotlib  # deferred: matplotlib is heavy to import

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

    fig, axes = plt.subplots(4, 1, figsize=(6.4, 6.4), sharex=True)
    units = ("m", "m/s", "m/s²", "m/s³")
    for i, (ax, unit) in enumerate(zip(axes, units, strict=True)):
        values = [r[i] for r in rows]
        if i == 3:
            ax.step(time, values, where="post", lw=1.2)
        else:
            ax.plot(time, values, lw=1.2)
        ax.set_ylabel(f"{REF_OUTPUTS[i]} ({unit})")
        ax.grid(alpha=0.3)
    axes[-1].set_xlabel("time (s)")
    axes[0].set_title(f"{spec.MODEL_NAME}: the default move (DJL, 0.4 m)")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def documentation_html(fmi_version: int, plot_name: str) -> str:
    """Text of ``documentation/index.html``: variables, the step rule, the default move."""
    def cell(v: object) -> str:
        return html.escape("" if v is None else str(v))

    rows = []
    for v in spec.VARIABLES:
        if v.causality == "independent":
            continue
        name = v.name + (f"[{v.size}]" if v.size > 1 else "")
        rng = ""
        if v.declared_type:
            rng = ", ".join(f"{value} = {item}" for item, value, _ in
                            spec.ENUMERATIONS[v.declared_type])
        elif v.min is not None or v.max is not None:
            lo = "" if v.min is None else ("> " if v.min_exclusive else "≥ ") + str(v.min)
            hi = "" if v.max is None else "≤ " + str(v.max)
            rng = ", ".join(s for s in (lo, hi) if s)
        unit = v.unit or "-"
        if v.quantity and v.unit in spec.DISPLAY_UNITS:
            unit += f" ({spec.DISPLAY_UNITS[v.unit][0]})"
        rows.append(f"<tr><td><code>{cell(name)}</code></td><td>{cell(v.causality)}</td>"
                    f"<td>{cell(v.type)}</td><td>{cell(unit)}</td><td>{cell(v.start)}</td>"
                    f"<td>{cell(rng)}</td><td>{cell(v.description)}</td></tr>")
    table = "\n".join(rows)
    return f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>{spec.MODEL_NAME}</title></head>
<body>
<h1>{spec.MODEL_NAME} (FMI {fmi_version}.0, co-simulation)</h1>
<p>{html.escape(codegen.DESCRIPTION)}</p>
<h2>Communication steps</h2>
<p>Any communication step h &gt; 0 is accepted. The outputs at a communication point are the
exact values of the planned profile at that time: x, v, a of the piecewise cubic; j and a_AL of
the sampling interval of <code>Te</code> that contains it. A step that is a whole multiple of
<code>Te</code> gives the samples themselves, bit for bit. A communication point may differ
from the FMU's time by rounding (a master that adds h, at any start time); one off by a
visible fraction of a step is refused. Invalid parameters, and parameters whose outputs would
overflow, are refused at initialisation with a message naming them.</p>
<h2>The default move</h2>
<p>All parameters at their start values: a 0.4 m DJL move. Its samples are the reference
result (<code>{spec.MODEL_IDENTIFIER}_ref.csv</code>, settings in <code>_ref.opt</code>; also
under <code>{LS_REF_DIR}</code>).</p>
<p><img src="{plot_name}" alt="x, v, a, j of the default move"></p>
<h2>Variables</h2>
<table border="1" cellpadding="3">
<tr><th>name</th><th>causality</th><th>type</th><th>unit (display)</th><th>start</th>
<th>range</th><th>meaning</th></tr>
{table}
</table>
<h2>Licence</h2>
<p>BSD-3-Clause: <a href="licenses/LICENSE.txt">licenses/LICENSE.txt</a>.</p>
</body></html>
"""


# --------------------------------------------------------------------------- writers


def write_cross_check(folder: Path) -> list[Path]:
    """Write ``<model>_ref.csv`` and ``<model>_ref.opt`` into ``folder`` (beside an FMU).

    Returns
    -------
    list of pathlib.Path
        The two files.
    """
    folder = Path(folder)
    time, rows = reference_result()
    csv = folder / f"{spec.MODEL_IDENTIFIER}_ref.csv"
    opt = folder / f"{spec.MODEL_IDENTIFIER}_ref.opt"
    csv.write_text(ref_csv_text(time, rows))
    opt.write_text(ref_opt_text())
    return [csv, opt]


def write_artefacts(root: Path, fmi_version: int) -> None:
    """Write the FMU's documentation artefacts under the unpacked FMU folder ``root``.

    Parameters
    ----------
    root : pathlib.Path
        The FMU's folder (where ``modelDescription.xml`` is).
    fmi_version : {2, 3}
        FMI version of the FMU (the icon's place differs).
    """
    root = Path(root)
    doc = root / "documentation"
    (doc / "licenses").mkdir(parents=True, exist_ok=True)
    (doc / "licenses" / "LICENSE.txt").write_text(LICENSE_TEXT)
    icon = icon_png()
    if fmi_version == 2:
        (root / "model.png").write_bytes(icon)
    else:
        (root / "terminalsAndIcons").mkdir(exist_ok=True)
        (root / "terminalsAndIcons" / "icon.png").write_bytes(icon)
        (root / "terminalsAndIcons" / "terminalsAndIcons.xml").write_text(
            terminals_and_icons_xml())
    try:
        time, rows = reference_result(fmu_dir=root)
    except Exception as e:  # noqa: BLE001  (no compiled core and no binary for this machine)
        raise BuildError(f"cannot compute the FMU's reference result: the harness's compiled "
                         f"core is not importable ({e}) and the FMU has no binary for this "
                         f"machine: install the package (pip install .) or build the host's "
                         f"platform too") from None
    ref_name = f"{spec.MODEL_IDENTIFIER}_ref.csv"
    csv = ref_csv_text(time, rows)
    (doc / ref_name).write_text(csv)
    (doc / f"{spec.MODEL_IDENTIFIER}_ref.opt").write_text(ref_opt_text())
    ls = root / LS_REF_DIR
    ls.mkdir(parents=True, exist_ok=True)
    (ls / ref_name).write_text(csv)
    (ls / "fmi-ls-manifest.xml").write_text(ls_ref_manifest(ref_name))
    default_move_plot(doc / "default_move.png", time, rows)
    (doc / "index.html").write_text(documentation_html(fmi_version, "default_move.png"))
