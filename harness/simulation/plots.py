"""Figures of co-simulation runs: reference, deflection with the band, f(t) and z(t).

:func:`plot_runs` draws one figure for any number of runs of one case
(:class:`harness.simulation.master.CoSimResult`); the results of the studies
(:mod:`harness.results`) and :meth:`CoSimResult.plot` use it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np

from ..metrics import PAPER_BAND_LABEL
from ..plant import free_amplitude

__all__ = ["COLORS", "PEAK_LABEL", "plot_runs"]

COLORS = {"AL": "0.45", "JL": "tab:blue", "DJL": "tab:red", "JL-optimal": "tab:cyan",
          "DJL-paper": "tab:pink", "DJL-optimal": "tab:green", "DJL-robust": "tab:purple",
          "recommended": "tab:orange"}

PEAK_LABEL = "peak |ε| after the motion (sampled)"
"""Label of :attr:`~harness.evaluation.ProfileMetrics.residual_peak` wherever it is shown."""



def _fmt(v: float, digits: int = 3) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "n/a"
    if math.isinf(v):
        return "never"
    return f"{v:.{digits}g}"


def _envelope(run: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """Free-oscillation envelope Σ A_i e^{-σ_i (t - t_end)} from the end of the reference."""
    states, modes = getattr(run, "state_end", None), getattr(run, "modes_end", None)
    if not states or not modes:
        return None
    t = run.t[run.t >= run.t_end - 1e-12]
    if t.size == 0:
        return None
    tau = t - t[0]
    env = np.zeros_like(t)
    for (e, de), m in zip(states, modes, strict=True):
        env += free_amplitude(e, de, m) * np.exp(-m.sigma * tau)
    return t, env


def plot_runs(runs: Mapping[str, Any], *, title: str = "", band: float | None = None,
              metrics: Mapping[str, Any] | None = None, band_label: str | None = None):
    """Figure of co-simulation runs: x, v, a, j | ε with band, f(t), z(t).

    Parameters
    ----------
    runs : mapping of str to CoSimResult
        Runs by profile name.
    title : str
        Figure title.
    band : float, optional
        Settling band (m), shaded on the ε plot.
    metrics : mapping of str to ProfileMetrics, optional
        Shown in the legend of the ε plot.
    band_label : str, optional
        Source of the band, shown in its legend entry.

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

    fig = plt.figure(figsize=(13, 10.5))
    outer = fig.add_gridspec(1, 2, width_ratios=(1, 1.25), wspace=0.22)
    # left: x, v, a, j over a shared t axis (labelled), then the table of numbers below it
    gl = outer[0, 0].subgridspec(2, 1, height_ratios=(4.0, 1.4), hspace=0.2)
    gx = gl[0].subgridspec(4, 1, hspace=0.14)
    gr = outer[0, 1].subgridspec(5, 1, hspace=0.14)
    left = [fig.add_subplot(gx[0])]
    left += [fig.add_subplot(gx[i], sharex=left[0]) for i in range(1, 4)]
    ax_e = fig.add_subplot(gr[0:2], sharex=left[0])
    ax_r = fig.add_subplot(gr[2], sharex=left[0])
    ax_f = fig.add_subplot(gr[3], sharex=left[0])
    ax_z = fig.add_subplot(gr[4], sharex=left[0])
    ax_m = fig.add_subplot(gl[1])
    t_max, t_min_end, zoom = 0.0, math.inf, 0.0
    for name, r in runs.items():
        c = COLORS.get(name, None)
        left[0].plot(r.t, r.x, color=c, label=name)
        left[1].plot(r.t, r.v, color=c)
        left[2].plot(r.t, r.a, color=c)
        left[3].plot(r.t, r.j, color=c, drawstyle="steps-post")
        lab = name
        if metrics and name in metrics:
            m = metrics[name]
            lab = (f"{name}: residual {m.residual * 1e3:.3g} mm, settles "
                   f"{_fmt(m.settling_time)} s")
            if name != "AL" or len(runs) == 1:
                zoom = max(zoom, m.residual)
        for ax in (ax_e, ax_r):
            ax.plot(r.t, r.eps * 1e3, color=c, lw=1.0, label=lab if ax is ax_e else None)
        env = _envelope(r)
        if env is not None:
            ax_r.plot(env[0], env[1] * 1e3, color=c, lw=0.8, ls="--")
            ax_r.plot(env[0], -env[1] * 1e3, color=c, lw=0.8, ls="--")
        for ax in (ax_e, ax_r, ax_f):
            ax.axvline(r.t_end, color=c, ls=":", lw=1.0)
        if metrics and name in metrics and math.isfinite(metrics[name].settling_time):
            ax_r.plot(r.t_start + metrics[name].settling_time, 0.0, "v", color=c, ms=8)
        ax_f.plot(r.t, r.f[0], color=c, label=name)
        ax_z.plot(r.t, r.z, color=c, label=name)
        t_max = max(t_max, r.t_end)
        t_min_end = min(t_min_end, r.t_end)
    if band:
        for ax in (ax_e, ax_r):
            ax.axhspan(-band * 1e3, band * 1e3, color="gold", alpha=0.35, lw=0,
                       label=(f"settling band +/-{band * 1e3:.3g} mm"
                              + (f" ({band_label})" if band_label else ""))
                       if ax is ax_e else None)
        zoom = max(zoom, band)
    if zoom > 0:
        ax_r.set_ylim(-3.0 * zoom * 1e3, 3.0 * zoom * 1e3)
    for ax, lab in zip(left, ("x [m]", "v [m/s]", "a [m/s²]", "j [m/s³]"), strict=True):
        ax.set_ylabel(lab)
        ax.grid(True, alpha=0.3)
    left[0].set_title("reference of the excited axis (generator FMU)", fontsize="medium")
    ax_e.set_ylabel("ε [mm]")
    ax_e.set_title("deflection of the load ε (dotted: end of each motion)", fontsize="medium")
    # one legend for the whole figure (the colours are the same in every panel), above
    # the panels: off the data
    handles, labels = ax_e.get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.96),
               ncol=min(3, len(handles)), fontsize="small", frameon=False)
    ax_r.set_ylabel("ε [mm], zoom")
    ax_r.text(0.01, 0.95, "residual vibration (dashed: free-oscillation envelope after the "
              "motion;\nat the end of the motion it equals the residual; ▼: settled into the band)",
              transform=ax_r.transAxes, va="top", fontsize="x-small",
              bbox={"facecolor": "white", "alpha": 0.75, "lw": 0, "pad": 1.5})
    ax_f.set_ylabel("f [Hz] (tuned mode)")
    ax_z.set_ylabel("z [m]")
    for ax in (ax_e, ax_r, ax_f, ax_z):
        ax.grid(True, alpha=0.3)
    left[3].set_xlabel("t [s]")
    ax_z.set_xlabel("t [s]")
    end = max(r.t[-1] for r in runs.values())
    left[0].set_xlim(0.0, min(end, max(2.0 * t_max, t_max + 1.5)))
    for ax in left[:-1] + [ax_e, ax_r, ax_f]:
        ax.tick_params(labelbottom=False)
    # bottom-left: the numbers
    ax_m.axis("off")
    if metrics:
        cols = list(metrics)
        cells = [[f"{metrics[n].residual * 1e3:.3g}" for n in cols],
                 [f"{getattr(metrics[n], 'residual_peak', math.nan) * 1e3:.3g}" for n in cols],
                 [f"{metrics[n].motion_time:.3g}" for n in cols],
                 [_fmt(metrics[n].settling_time) for n in cols]]
        labels = ["residual [mm]", "peak |ε| (sampled) [mm]", "motion time [s]",
                  "settling [s] (1)"]
        notes = ["residual: free-oscillation amplitude at the end;",
                 f"{PEAK_LABEL}: phase-dependent",
                 "(1) settling band" + (f": {band_label.removeprefix('band: ')}"
                                        if band_label else "")]
        if any(math.isfinite(getattr(metrics[n], "settling_time_paper", math.nan))
               and getattr(metrics[n], "paper_band", math.nan) != metrics[n].band
               for n in cols):
            cells.append([_fmt(metrics[n].settling_time_paper) for n in cols])
            labels.append("settling [s] (2)")
            notes.append(f"(2) {PAPER_BAND_LABEL}")
        # no bbox: every column as wide as its text (a bbox squeezes them and clips it)
        tab = ax_m.table(cellText=cells, colLabels=cols, rowLabels=labels, cellLoc="center",
                         loc="upper center")
        tab.auto_set_font_size(False)
        tab.set_fontsize(8 if len(cols) <= 4 else 7 if len(cols) <= 6 else 6)  # fits the column
        tab.auto_set_column_width(list(range(-1, len(cols))))
        tab.scale(1.0, 1.25)
        # under the table, which is centred: the block centred too, its lines left-aligned
        ax_m.text(0.5, 0.0, "\n".join(notes), transform=ax_m.transAxes, fontsize="x-small",
                  va="bottom", ha="center", multialignment="left")
    fig.suptitle(title, y=0.985)
    top = 0.92 - 0.022 * math.ceil(len(handles) / 3)  # below the legend's rows
    fig.subplots_adjust(left=0.08, right=0.98, top=top, bottom=0.05)
    return fig
