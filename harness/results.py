"""Results of scenarios: Table-1 / Table-2 shaped tables, CSV rows and figures.

:class:`ScenarioResult` (one move, several profiles) prints like Table 1 of
Béarée & Olabi 2013 (absolute values and % of AL); :class:`SweepResult` (the
test set of a sweep) like Table 2 (DJL compared with JL, in %).  Both write
CSV and return a matplotlib figure from ``.plot()``.
"""

from __future__ import annotations

import csv
import math
import os
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .metrics import Table2Stats, change_percent, percent_of, table2_stats

__all__ = [
    "ProfileOutcome",
    "ScenarioResult",
    "SweepResult",
    "format_table2",
    "plot_runs",
    "write_csv",
]

COLORS = {"AL": "0.45", "JL": "tab:blue", "DJL": "tab:red"}


@dataclass
class ProfileOutcome:
    """One profile of a scenario: its run, its tuning and its metrics.

    Attributes
    ----------
    name : str
        ``AL``, ``JL`` or ``DJL``.
    run : CoSimResult or None
        Time series (None in sweeps).
    tuning : TuningResult or None
        How the jerk times were found (None for AL or imposed jerk times).
    metrics : ProfileMetrics
        Table 1 quantities.
    T_F : tuple of float
        Jerk times applied (s).
    z_v_max : float
        Velocity limit of the Z move (m/s).
    z_synced : bool
        Whether the Z move ends with the excited axis.
    """

    name: str
    run: Any
    tuning: Any
    metrics: Any
    T_F: tuple[float, ...]
    z_v_max: float
    z_synced: bool


def _fmt(v: float, digits: int = 3) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "n/a"
    if math.isinf(v):
        return "never"
    return f"{v:.{digits}g}"


def _pct(v: float, signed: bool = False) -> str:
    if v is None or not math.isfinite(v):
        return "n/a"
    if abs(v) >= 1000.0:
        return f"{v:+.3g} %" if signed else f"{v:.3g} %"
    return f"{v:+.1f} %" if signed else f"{v:.1f} %"


def _umask_mode() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return 0o666 & ~mask


def write_csv(path: str | Path, rows: Sequence[Mapping[str, Any]]) -> Path:
    """Write dict rows as CSV atomically (temporary file, then rename).

    Parameters
    ----------
    path : path-like
        Destination.
    rows : sequence of mapping
        Rows; the columns are the keys of the first row.

    Returns
    -------
    Path
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "w", newline="", encoding="utf-8") as fh:
            w = csv.DictWriter(fh, fieldnames=list(rows[0]) if rows else [])
            w.writeheader()
            for r in rows:
                w.writerow({k: (f"{v:.10g}" if isinstance(v, float) else v) for k, v in r.items()})
        os.chmod(tmp, _umask_mode())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def save_figure(fig: Any, path: str | Path, dpi: int = 110) -> Path:
    """Save a figure atomically (temporary file, then rename) and close it."""
    import matplotlib.pyplot as plt

    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        fig.savefig(tmp, dpi=dpi)
        os.chmod(tmp, _umask_mode())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    finally:
        plt.close(fig)
    return path


@dataclass
class ScenarioResult:
    """AL / JL / DJL on one move: what Table 1 of the paper reports.

    Attributes
    ----------
    scenario : Scenario
        The scenario run.
    profiles : dict of str to ProfileOutcome
        In the scenario's order.
    band : float
        Settling band (m).
    band_source : str
        Where the band comes from.
    """

    scenario: Any
    profiles: dict[str, ProfileOutcome]
    band: float
    band_source: str

    # ------------------------------------------------------------ numbers

    def metric(self, profile: str, name: str) -> float:
        """Return one metric of one profile.

        ``name`` is ``residual``, ``free_amplitude``, ``motion_time``, ``rise_time`` or
        ``settling_time``.
        """
        return float(getattr(self.profiles[profile].metrics, name))

    def relative(self, name: str, profile: str, reference: str = "AL", *,
                 change: bool = False) -> float:
        """``profile``'s metric as % of (or, with ``change``, % change from) ``reference``."""
        if reference not in self.profiles or profile not in self.profiles:
            return math.nan
        v, r = self.metric(profile, name), self.metric(reference, name)
        if not (math.isfinite(v) and math.isfinite(r)):
            return math.nan
        return change_percent(v, r) if change else percent_of(v, r)

    def djl_vs_jl(self) -> tuple[float, float]:
        """Change of DJL against JL in % (residual vibration, settling time): Table 2's unit."""
        return (self.relative("residual", "DJL", "JL", change=True),
                self.relative("settling_time", "DJL", "JL", change=True))

    def frequency_span(self) -> tuple[float, float]:
        """Frequency of the tuned mode at the start and at the end of the move (Hz)."""
        mm, z = self.scenario.modemap, self.scenario.z
        return mm.tuned.f(z.z0), mm.tuned.f(z.z0 + z.distance)

    # ------------------------------------------------------------- table

    def header(self) -> str:
        """Return the lines describing the scenario above the table."""
        sc = self.scenario
        m, z, s = sc.move, sc.z, sc.simulation
        f0, f1 = self.frequency_span()
        shift = abs(f1 - f0) / max(f0, f1) * 100.0
        fmu = f"FMU {s.fmu}" if s.fmu else f"FMI {s.fmi_version}.0 FMU (package build)"
        lines = [f"Scenario {sc.name}" + (f": {sc.description}" if sc.description else ""),
                 f"  {m.axis}: d = {m.distance:g} m, v_max = {m.v_max:g} m/s, a_max = "
                 f"{m.a_max:g} m/s2, d_max = {m.d_max:g} m/s2; {fmu}, Te = {s.Te * 1e3:g} ms, "
                 f"step = {s.step * 1e3:g} ms"]
        first = next(iter(self.profiles.values()))
        sync = ("synchronised: ends with the excited axis" if first.z_synced
                else "too slow to end with the excited axis")
        if z.moves:
            lines.append(f"  Z: {z.z0:g} -> {z.z0 + z.distance:g} m, JL T_F = {z.T_F * 1e3:g} ms, "
                         f"a_max = {z.a_max:g} m/s2, v_max = {first.z_v_max:.3g} m/s ({sync})")
        else:
            lines.append(f"  Z: still at {z.z0:g} m")
        tm = sc.modemap.tuned
        lines.append(f"  tuned mode '{tm.name}': {f0:.3g} -> {f1:.3g} Hz over the move "
                     f"(shift {shift:.1f} %), zeta = {tm.zeta:g}"
                     + (f"; {len(sc.modemap.modes)} modes simulated"
                        if len(sc.modemap.modes) > 1 else ""))
        for p in self.profiles.values():
            if p.name == "AL":
                continue
            if p.tuning is not None:
                lines.append(f"  {p.tuning.describe()}")
            else:
                ms = "/".join(f"{x * 1e3:.0f}" for x in (p.T_F[:1] if p.name == "JL" else p.T_F))
                lines.append(f"  {p.name} jerk times {ms} ms (imposed by the scenario)")
        return "\n".join(lines)

    def table(self) -> str:
        """Format the results like Table 1 of the paper (absolute and relative to AL)."""
        names = list(self.profiles)
        ref = "AL" if "AL" in self.profiles else names[0]
        rows = [
            ("Residual vibration [mm]", "residual", 1e3, False),
            ("Free-oscillation amplitude [mm]", "free_amplitude", 1e3, False),
            ("Motion time [s] (theoretical rise)", "motion_time", 1.0, True),
            ("Rise time of the load [s]", "rise_time", 1.0, True),
            ("Settling time [s]", "settling_time", 1.0, True),
        ]
        w0, w = 36, 22
        out = [self.header(), "", " " * w0 + "".join(f"{n:>{w}}" for n in names)]
        for label, key, scale, as_change in rows:
            cells = []
            for n in names:
                v = self.metric(n, key)
                if n == ref:
                    rel = "(ref)" if as_change else "(100 %)"
                else:
                    r = self.relative(key, n, ref, change=as_change)
                    rel = f"({_pct(r, signed=as_change)})"
                cells.append(f"{_fmt(v * scale if math.isfinite(v) else v)} {rel}")
            out.append(f"{label:<{w0}}" + "".join(f"{c:>{w}}" for c in cells))
        out.append("")
        out.append(f"Settling band: +/-{self.band * 1e3:.3g} mm ({self.band_source}); "
                   f"percentages relative to {ref}.")
        if "DJL" in self.profiles and "JL" in self.profiles:
            r, s = self.djl_vs_jl()
            out.append(f"DJL compared with JL: residual vibration {_pct(r, True)}, "
                       f"settling time {_pct(s, True)}.")
        return "\n".join(out)

    # --------------------------------------------------------------- CSV

    def rows(self) -> list[dict[str, Any]]:
        """One dict per profile (the CSV rows)."""
        sc = self.scenario
        f0, f1 = self.frequency_span()
        out = []
        for n, p in self.profiles.items():
            met = p.metrics
            T: list[Any] = list(p.T_F) if n != "AL" and p.T_F else [""] * 4
            out.append({
                "scenario": sc.name, "profile": n, "axis": sc.move.axis,
                "distance_m": sc.move.distance, "v_max_m_s": sc.move.v_max,
                "a_max_m_s2": sc.move.a_max, "z0_m": sc.z.z0, "z_distance_m": sc.z.distance,
                "f_start_Hz": f0, "f_end_Hz": f1,
                "T_F1_s": T[0], "T_F2_s": T[1], "T_F3_s": T[2], "T_F4_s": T[3],
                "tuning": (p.tuning.rule if p.tuning else ("imposed" if n != "AL" else "")),
                "tuning_plans": p.tuning.iterations if p.tuning else 0,
                "tuning_converged": p.tuning.converged if p.tuning else "",
                "residual_m": met.residual,
                "residual_pct_of_AL": self.relative("residual", n),
                "free_amplitude_m": met.free_amplitude,
                "free_amplitude_pct_of_AL": self.relative("free_amplitude", n),
                "motion_time_s": met.motion_time,
                "motion_time_change_pct_vs_AL": self.relative("motion_time", n, change=True),
                "rise_time_s": met.rise_time,
                "rise_time_change_pct_vs_AL": self.relative("rise_time", n, change=True),
                "settling_time_s": met.settling_time,
                "settling_time_change_pct_vs_AL": self.relative("settling_time", n,
                                                                change=True),
                "settling_time_change_pct_vs_DJL": self.relative("settling_time", n, "DJL",
                                                                 change=True),
                "band_m": self.band, "z_v_max_m_s": p.z_v_max, "z_synced": p.z_synced,
            })
        return out

    def to_csv(self, path: str | Path) -> Path:
        """Write :meth:`rows` as CSV; return the path."""
        return write_csv(path, self.rows())

    # -------------------------------------------------------------- plot

    def plot(self, title: str | None = None):
        """One figure: reference x/v/a/j, ε(t) with the band, f(t) and z(t); return it."""
        runs = {n: p.run for n, p in self.profiles.items() if p.run is not None}
        if not runs:
            raise ValueError("no time series kept (sweep case): nothing to plot")
        sc = self.scenario
        title = title or f"Scenario {sc.name}: {sc.move.axis} move d = {sc.move.distance:g} m, " \
            f"Z {sc.z.z0:g} -> {sc.z.z0 + sc.z.distance:g} m"
        return plot_runs(runs, title=title, band=self.band,
                         metrics={n: p.metrics for n, p in self.profiles.items()})


def plot_runs(runs: Mapping[str, Any], *, title: str = "", band: float | None = None,
              metrics: Mapping[str, Any] | None = None):
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

    Returns
    -------
    matplotlib.figure.Figure
    """
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(13, 9.5))
    gs = fig.add_gridspec(5, 2, width_ratios=(1, 1.25), hspace=0.14, wspace=0.22)
    left = [fig.add_subplot(gs[0, 0])]
    left += [fig.add_subplot(gs[i, 0], sharex=left[0]) for i in range(1, 4)]
    ax_e = fig.add_subplot(gs[0:2, 1], sharex=left[0])
    ax_r = fig.add_subplot(gs[2, 1], sharex=left[0])
    ax_f = fig.add_subplot(gs[3, 1], sharex=left[0])
    ax_z = fig.add_subplot(gs[4, 1], sharex=left[0])
    ax_m = fig.add_subplot(gs[4, 0])
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
                       label=f"band +/-{band * 1e3:.3g} mm" if ax is ax_e else None)
        zoom = max(zoom, band)
    if zoom > 0:
        ax_r.set_ylim(-3.0 * zoom * 1e3, 3.0 * zoom * 1e3)
    for ax, lab in zip(left, ("x [m]", "v [m/s]", "a [m/s²]", "j [m/s³]"), strict=True):
        ax.set_ylabel(lab)
        ax.grid(True, alpha=0.3)
    left[0].legend(loc="lower right", fontsize="small")
    left[0].set_title("reference of the excited axis (generator FMU)", fontsize="medium")
    ax_e.set_ylabel("ε [mm]")
    ax_e.set_title("deflection of the load ε (dotted: end of each motion)", fontsize="medium")
    ax_e.legend(loc="upper right", fontsize="small")
    ax_r.set_ylabel("ε [mm], zoom")
    ax_r.text(0.01, 0.95, "residual vibration (▼: settled into the band)",
              transform=ax_r.transAxes, va="top", fontsize="small")
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
                 [f"{metrics[n].motion_time:.3g}" for n in cols],
                 [_fmt(metrics[n].settling_time) for n in cols]]
        tab = ax_m.table(cellText=cells, colLabels=cols,
                         rowLabels=["residual [mm]", "motion time [s]", "settling [s]"],
                         loc="center", cellLoc="center")
        tab.scale(0.8, 1.3)
    fig.suptitle(title)
    fig.subplots_adjust(left=0.09, right=0.98, top=0.93, bottom=0.06)
    return fig


# ------------------------------------------------------------------ sweeps


@dataclass
class SweepResult:
    """A sweep over the paper's test set: every case's Table 1 and their Table 2.

    Attributes
    ----------
    scenario : Scenario
        The sweep scenario.
    cases : list of ScenarioResult
        One per combination (time series dropped).
    """

    scenario: Any
    cases: list[ScenarioResult]

    def changes(self) -> tuple[np.ndarray, np.ndarray]:
        """DJL against JL in % for every case: (residual vibration, settling time)."""
        pairs = [c.djl_vs_jl() for c in self.cases]
        return (np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs]))

    def stats(self) -> dict[str, Table2Stats]:
        """Table 2 statistics: ``{"residual": ..., "settling": ...}``."""
        r, s = self.changes()
        return {"residual": table2_stats(r), "settling": table2_stats(s)}

    def table(self) -> str:
        """Table 2 of the paper for this sweep alone."""
        return format_table2([self])

    def rows(self) -> list[dict[str, Any]]:
        """Every case's CSV rows."""
        out = []
        for c in self.cases:
            r, s = c.djl_vs_jl()
            for row in c.rows():
                row = {"sweep": self.scenario.name, **row}
                row["case_djl_vs_jl_residual_pct"] = r
                row["case_djl_vs_jl_settling_pct"] = s
                out.append(row)
        return out

    def to_csv(self, path: str | Path) -> Path:
        """Write :meth:`rows` as CSV; return the path."""
        return write_csv(path, self.rows())

    def plot(self, title: str | None = None):
        """Per case: residual of DJL against JL, and the % changes; return the figure."""
        import matplotlib.pyplot as plt

        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(13, 5.5))
        jl = np.array([c.metric("JL", "residual") for c in self.cases]) * 1e3
        djl = np.array([c.metric("DJL", "residual") for c in self.cases]) * 1e3
        dz = np.array([c.scenario.z.distance for c in self.cases])
        sc = ax1.scatter(jl, djl, c=dz, cmap="viridis", s=30)
        lim = [min(jl.min(), djl.min()) * 0.8, max(jl.max(), djl.max()) * 1.25]
        ax1.plot(lim, lim, "k--", lw=0.8, label="DJL = JL")
        ax1.set_xscale("log")
        ax1.set_yscale("log")
        ax1.set_xlabel("JL residual vibration [mm]")
        ax1.set_ylabel("DJL residual vibration [mm]")
        ax1.grid(True, which="both", alpha=0.3)
        ax1.legend(fontsize="small")
        fig.colorbar(sc, ax=ax1, label="Z travel dz [m]")
        r, s = self.changes()
        idx = np.arange(len(self.cases))
        ax2.bar(idx - 0.2, r, width=0.4, color="tab:red", label="residual vibration")
        ax2.bar(idx + 0.2, s, width=0.4, color="tab:purple", label="settling time")
        ax2.axhline(0.0, color="k", lw=0.8)
        ax2.set_xlabel("case (d, dz, v_max: see the CSV)")
        ax2.set_ylabel("DJL compared with JL [%]")
        ax2.grid(True, alpha=0.3)
        ax2.legend(fontsize="small")
        st = self.stats()
        fig.suptitle(title or (f"Sweep {self.scenario.name} ({len(self.cases)} cases): DJL vs JL "
                               f"residual {st['residual'].mean:+.1f} % on average, settling time "
                               f"{st['settling'].mean:+.1f} %"))
        fig.tight_layout()
        return fig


def format_table2(sweeps: Sequence[SweepResult]) -> str:
    """Table 2 of the paper: one column per sweep (e.g. X and Y directions).

    Parameters
    ----------
    sweeps : sequence of SweepResult

    Returns
    -------
    str
    """
    names = [s.scenario.name for s in sweeps]
    stats = [s.stats() for s in sweeps]
    w0, w = 34, 14
    out = ["Statistics of the DJL profile compared with the JL profile (Table 2), in %",
           " " * w0 + "".join(f"{n:>{w}}" for n in names)]
    for key, label in (("residual", "Residual vibrations"), ("settling", "Settling times")):
        out.append(label)
        for field_, lab in (("mean", "Mean value"), ("max", "Max value (largest reduction)"),
                            ("min", "Min value (smallest reduction)"),
                            ("std", "Standard deviation")):
            out.append(f"  {lab:<{w0 - 2}}" + "".join(
                f"{getattr(st[key], field_):>{w}.1f}" for st in stats))
    out.append(f"  {'cases':<{w0 - 2}}" + "".join(f"{st['residual'].n:>{w}d}" for st in stats))
    return "\n".join(out)


def table2_rows(sweeps: Sequence[SweepResult]) -> list[dict[str, Any]]:
    """Table 2 as CSV rows (one per statistic and sweep)."""
    rows = []
    for s in sweeps:
        for key, st in s.stats().items():
            rows.append({"sweep": s.scenario.name, "quantity": key, "mean_pct": st.mean,
                         "max_reduction_pct": st.max, "min_reduction_pct": st.min,
                         "std_pct": st.std, "cases": st.n})
    return rows
