"""Results of scenarios: Table-1 / Table-2 shaped tables, CSV rows and figures.

:class:`ScenarioResult` (one move, several profiles) prints like Table 1 of
Béarée & Olabi 2013 (absolute values and % of AL); :class:`SweepResult` (the
test set of a sweep) like Table 2 (DJL compared with JL, in %).  Both write
CSV and return a matplotlib figure from ``.plot()``.

Every settling time is printed with its band and the band's source; the
residual vibration is the free-oscillation amplitude when the reference ends
(:func:`harness.metrics.residual_amplitude`), the sampled peak |ε| after the
motion being shown, labelled, beside it.  A sweep counts each distinct move
once in its statistics (:meth:`SweepResult.duplicates`): at d = 0.1 m, JL and
DJL never reach v_max, and v_max = 0.5 or 2 m/s plan the same JL and DJL moves.
"""

from __future__ import annotations

import json
import math
import textwrap
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .files import write_csv
from .metrics import PAPER_BAND_LABEL, Table2Stats, change_percent, percent_of, table2_stats
from .simulation.plots import PEAK_LABEL, plot_runs
from .tables import SIGNAL_COLUMNS, TableMixin, columns_of, mat_variables, to_pandas
from .uncertainty import span_text

__all__ = [
    "ProfileOutcome",
    "ScenarioResult",
    "SweepResult",
    "format_table2",
    "plot_runs",
    "table2_rows",
]

MOVE_KEY_FIELDS = ("N_F", "motion_time", "v_reached", "a_reached", "d_reached", "distance",
                   "x0", "z0", "z_distance", "z_v_max")
"""Fields of ``CoSimResult.plan_info`` that identify a planned move (compared exactly)."""

WORST_PREFIX = "Worst residual, map error +/-"
"""Start of the label of the worst residual over a map error (:func:`worst_label`)."""


def worst_label(span: float) -> str:
    """Label of the worst residual over a map error within ±``span`` (:mod:`harness.robustness`).

    ``Worst residual, map error +/-10 %`` for the default map scale 0.1: every table
    writes the run's (``scenario.uncertainty.map_scale``).
    """
    return f"{WORST_PREFIX}{span_text(span)} %"


LEGACY_SPAN = 0.1
"""The span the CSV columns ``residual_worst_map10_*`` and ``worst_residual_10pct_*`` are
named after: they keep their names and hold the run's worst case (a legend says so when
the run's map scale is another)."""


def legacy_columns_note(span: float, columns: str) -> str:
    """Return the legend's note that ``columns`` (named ``...10...``) hold the run's span.

    Empty when the run's span is the one they are named after (:data:`LEGACY_SPAN`).
    """
    if span_text(span) == span_text(LEGACY_SPAN):
        return ""
    return (f" The CSV columns {columns} keep their names and hold this +/-{span_text(span)} % "
            f"worst case.")


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
    plan_info : dict
        What the generators planned (``CoSimResult.plan_info``), kept when the
        run is dropped: identifies the move (:attr:`move_key`).
    worst_map_residual : float
        Largest residual over a map error within ± the scenario's map scale
        (``uncertainty.map_scale``, 10 % by default) (m), jerk times tuned on
        the nominal map (:mod:`harness.robustness`); NaN if not computed.
        :attr:`worst_residual_10pct` is its earlier name (the CSV keeps
        ``residual_worst_map10_m``).
    method : str
        The profile in words (its jerk times, its shaper).
    fmu_parameters, z_fmu_parameters : dict
        The generator FMU's start values that reproduce the reference of the
        excited axis and of the Z axis (the CSV's replayable columns).
    """

    name: str
    run: Any
    tuning: Any
    metrics: Any
    T_F: tuple[float, ...]
    z_v_max: float
    z_synced: bool
    plan_info: dict[str, Any] = field(default_factory=dict)
    worst_map_residual: float = math.nan
    method: str = ""
    fmu_parameters: dict[str, Any] = field(default_factory=dict)
    z_fmu_parameters: dict[str, Any] = field(default_factory=dict)

    @property
    def worst_residual_10pct(self) -> float:
        """The earlier name of :attr:`worst_map_residual` (over the run's map scale)."""
        return self.worst_map_residual

    @property
    def move_key(self) -> tuple[Any, ...] | None:
        """The planned move, exactly (:data:`MOVE_KEY_FIELDS`); None if unknown."""
        info = self.plan_info or (getattr(self.run, "plan_info", None) or {})
        if any(k not in info for k in MOVE_KEY_FIELDS):
            return None
        return tuple(tuple(int(n) for n in info[k]) if k == "N_F" else float(info[k])
                     for k in MOVE_KEY_FIELDS)


def _json(params: Mapping[str, Any]) -> str:
    """FMU start values as a JSON object (empty when unknown)."""
    return json.dumps(dict(params), sort_keys=True) if params else ""


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


@dataclass
class ScenarioResult(TableMixin):
    """AL / JL / DJL on one move: what Table 1 of the paper reports.

    Attributes
    ----------
    scenario : Scenario
        The scenario run.
    profiles : dict of str to ProfileOutcome
        In the scenario's order.
    band : float
        Settling band (m), the same for every profile.
    band_source : str
        Where the band comes from (e.g. ``band: 1 % of AL's residual``).
    paper_band : float
        The paper's band, DJL's residual (m): the band of ``settling_time_paper``;
        NaN without DJL.
    robustness : RobustnessResult, optional
        Residual against a map error, in the time-varying plant
        (``run_case(..., robustness="curves")``).
    scoring_label : str
        The scoring set the worst cases are taken over (empty: not scored);
        the uncertainty itself is ``scenario.uncertainty``.
    recommendation : Recommendation, optional
        How the ``recommended`` profile was chosen (:mod:`harness.recommend`).
    """

    scenario: Any
    profiles: dict[str, ProfileOutcome]
    band: float
    band_source: str
    paper_band: float = math.nan
    robustness: Any = None
    scoring_label: str = ""
    recommendation: Any = None

    # ------------------------------------------------------------ numbers

    def metric(self, profile: str, name: str) -> float:
        """Return one metric of one profile.

        ``name`` is a field of :class:`~harness.evaluation.ProfileMetrics`
        (``residual``, ``residual_peak``, ``free_amplitude``, ``motion_time``,
        ``rise_time``, ``settling_time``, ``settling_time_paper``) or
        ``worst_map_residual`` (earlier name ``worst_residual_10pct``).
        """
        p = self.profiles[profile]
        if hasattr(p.metrics, name):
            return float(getattr(p.metrics, name))
        return float(getattr(p, name))

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
        """Change of DJL against JL in % (residual vibration, settling time): Table 2's unit.

        The settling time is the one in the case's band (:attr:`band`);
        :meth:`djl_vs_jl_all` adds the paper's band and the map-error worst case.
        """
        return (self.relative("residual", "DJL", "JL", change=True),
                self.relative("settling_time", "DJL", "JL", change=True))

    def djl_vs_jl_all(self) -> dict[str, float]:
        """Change of DJL against JL in % of every Table 2 quantity (:data:`TABLE2_METRICS`)."""
        return {k: self.relative(metric, "DJL", "JL", change=True)
                for k, (metric, _) in TABLE2_METRICS.items()}

    def frequency_span(self) -> tuple[float, float]:
        """Frequency of the tuned mode at the start and at the end of the move (Hz)."""
        mm, z = self.scenario.modemap, self.scenario.z
        return mm.tuned.f(z.z0), mm.tuned.f(z.z0 + z.distance)

    @property
    def settle_band(self) -> Any:
        """The scenario's settling band (:class:`~harness.metrics.SettleBand`)."""
        return self.scenario.simulation.settle_band

    @property
    def has_paper_settling(self) -> bool:
        """Whether a settling time into the paper's band is shown apart (DJL ran, other band)."""
        return math.isfinite(self.paper_band) and self.settle_band.kind != "paper"

    @property
    def has_uncertainty(self) -> bool:
        """Whether every profile was scored over the scenario's uncertainty."""
        return bool(self.scoring_label)

    @property
    def worst_span(self) -> float:
        """The span of the map-error worst case: the scenario's ``uncertainty.map_scale``."""
        return float(self.scenario.uncertainty.map_scale)

    @property
    def has_worst(self) -> bool:
        """Whether the worst residual over a map error within ±:attr:`worst_span` was computed."""
        return any(math.isfinite(p.worst_map_residual) for p in self.profiles.values())

    def move_key(self, profiles: Sequence[str] | None = None) -> tuple[Any, ...] | None:
        """Return the moves planned for ``profiles`` (default: every profile), exactly.

        Two cases with equal keys run the same moves for those profiles, hence
        have the same metrics for them.

        Parameters
        ----------
        profiles : sequence of str, optional
            The profiles to compare; those the case did not run are skipped.

        Returns
        -------
        tuple or None
            None if a move is unknown (no ``plan_info``) or no profile is left.
        """
        names = [n for n in (profiles or self.profiles) if n in self.profiles]
        keys = tuple((n, self.profiles[n].move_key) for n in names)
        return None if not keys or any(k is None for _, k in keys) else keys

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
            if p.name == "recommended" and self.recommendation is not None:
                rec = self.recommendation
                best: dict[str, float] = {}
                for c in rec.candidates:
                    best[c.family] = min(best.get(c.family, math.inf), c.settling_worst)
                lines.append(f"  recommended: {p.method} (chosen among "
                             + ", ".join(f"{f} {t:.3g} s" for f, t in best.items())
                             + f": worst-case settling over the {rec.tuning_set}; the rule "
                               f"and the reasons below)")
                continue
            if p.tuning is not None:
                lines.append(f"  {p.tuning.describe()}")
            else:
                ms = "/".join(f"{x * 1e3:.0f}" for x in (p.T_F[:1] if p.name == "JL" else p.T_F))
                lines.append(f"  {p.name} jerk times {ms} ms (imposed by the scenario)")
        return "\n".join(lines)

    def _rows(self) -> list[tuple[str, str, float, bool | None]]:
        """(label, metric, scale, as_change) of the Table 1 rows; as_change None: no %."""
        rows: list[tuple[str, str, float, bool | None]] = [
            ("Residual vibration [mm]", "residual", 1e3, False),
            (f"  {PEAK_LABEL} [mm]", "residual_peak", 1e3, None),
            ("Motion time [s] (theoretical rise)", "motion_time", 1.0, True),
            ("Rise time of the load [s]", "rise_time", 1.0, True),
            (f"Settling time [s] ({self.band_source})", "settling_time", 1.0, True),
        ]
        if self.has_paper_settling:
            rows.append((f"Settling time [s] ({PAPER_BAND_LABEL})", "settling_time_paper", 1.0,
                         True))
        if self.has_worst:
            rows.append((f"{worst_label(self.worst_span)} [mm]", "worst_map_residual", 1e3,
                         False))
        if self.has_uncertainty:
            rows += [("Worst residual, uncertainty [mm]", "residual_worst", 1e3, False),
                     ("Worst-case settling time [s] (same band)", "settling_time_worst", 1.0,
                      True)]
        rows += [("Peak |v| [m/s]", "v_peak", 1.0, None), ("Peak |a| [m/s2]", "a_peak", 1.0, None),
                 ("Peak |j| [m/s3] (never: no jerk limit)", "j_peak", 1.0, None)]
        return rows

    def table(self) -> str:
        """Format the results like Table 1 of the paper (absolute and relative to AL)."""
        names = list(self.profiles)
        ref = "AL" if "AL" in self.profiles else names[0]
        rows = self._rows()
        w0, w = max(36, 2 + max(len(r[0]) for r in rows)), 22
        out = [self.header(), "", " " * w0 + "".join(f"{n:>{w}}" for n in names)]
        for label, key, scale, as_change in rows:
            cells = []
            for n in names:
                v = self.metric(n, key)
                if as_change is None:
                    rel = ""
                elif n == ref:
                    rel = " (ref)" if as_change else " (100 %)"
                else:
                    r = self.relative(key, n, ref, change=as_change)
                    rel = f" ({_pct(r, signed=as_change)})"
                cells.append(f"{_fmt(v * scale if math.isfinite(v) else v)}{rel}")
            out.append(f"{label:<{w0}}" + "".join(f"{c:>{w}}" for c in cells))
        out.append("")
        out.append("Residual vibration: amplitude of the free oscillation when the reference "
                   "ends (sum over the modes);")
        out.append(f"the {PEAK_LABEL} depends on the phase at the end and is shown for "
                   "information only.")
        src = self.band_source.removeprefix("band: ")
        line = f"Settling band: +/-{self.band * 1e3:.3g} mm ({src})"
        if self.has_paper_settling:
            line += f"; {PAPER_BAND_LABEL}: +/-{self.paper_band * 1e3:.3g} mm"
        out.append(line + f"; percentages relative to {ref}.")
        if self.has_worst:
            rob = self.robustness.label if self.robustness is not None else \
                "time-varying plant, whole map scaled by 1 + e"
            span = self.worst_span
            out.append(f"{worst_label(span)}: largest residual for every f(z) x (1 + e), "
                       f"|e| <= {span_text(span)} %, jerk times tuned on the nominal map "
                       f"({rob})."
                       + legacy_columns_note(span, "residual_worst_map10_m, "
                                                   "residual_worst_map10_pct_of_AL"))
        if self.has_uncertainty:
            out.append(f"Uncertainty: {self.scoring_label}; the worst cases are over it, every "
                       f"reference planned on the nominal map, the settling band fixed.")
        if "recommended" in self.profiles:
            rec = self.profiles["recommended"]
            others = ", ".join(f"{n} {self.metric(n, 'settling_time_worst'):.3g} s"
                               for n in self.profiles if n != "recommended")
            out.insert(0, f"Recommended: {rec.method}; worst-case settling "
                          f"{rec.metrics.settling_time_worst:.3g} s ({others}), motion time "
                          f"{rec.metrics.motion_time:.3g} s, nominal residual "
                          f"{rec.metrics.residual * 1e3:.3g} mm; jerk no higher than JL's.")
        if "DJL" in self.profiles and "JL" in self.profiles:
            ch = self.djl_vs_jl_all()
            parts = [f"residual vibration {_pct(ch['residual'], True)}",
                     f"settling time {_pct(ch['settling'], True)} ({self.band_source})"]
            if self.has_paper_settling:
                parts.append(f"{_pct(ch['settling_paper'], True)} ({PAPER_BAND_LABEL})")
            if self.has_worst:
                parts.append(f"worst residual over +/-{span_text(self.worst_span)} % map "
                             f"error {_pct(ch['worst_residual_10pct'], True)}")
            out.append("DJL compared with JL: " + ", ".join(parts) + ".")
        if self.recommendation is not None:
            out.append("Why the recommended profile:")
            out.extend(f"  {x}" for x in self.recommendation.explanation)
            deg = self.degradation()
            if deg is not None:
                out.extend(deg.lines())
        return "\n".join(out)

    def degradation(self):  # -> harness.degradation.Degradation | None
        """Return the recommended and textbook shapers' worst-case settling vs the error width."""
        rec = self.recommendation
        return rec.degradation(self.scenario) if rec is not None else None

    # --------------------------------------------------------------- CSV

    def rows(self) -> list[dict[str, Any]]:
        """One dict per profile (the CSV rows).

        ``residual_m`` is the residual vibration (free-oscillation amplitude when
        the reference ends; equal to ``free_amplitude_m``), ``residual_peak_m``
        the sampled peak |ε| after the motion; the settling time is in the
        band ``band_m`` (``band_source``), ``settling_time_paper_band_s`` in the
        paper's band ``paper_band_m`` (DJL's residual).
        """
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
                # added columns
                "band_source": self.band_source,
                "residual_peak_m": met.residual_peak,
                "settling_time_paper_band_s": met.settling_time_paper,
                "paper_band_m": self.paper_band,
                # named after the default +/-10 %: the run's span (worst_span), names kept
                "residual_worst_map10_m": p.worst_map_residual,
                "residual_worst_map10_pct_of_AL": self.relative("worst_map_residual", n),
                # the uncertainty and the peaks (issue 18)
                "residual_nominal_m": met.residual,
                "residual_worst_m": met.residual_worst,
                "settling_time_worst_s": met.settling_time_worst,
                "worst_point": met.worst_point,
                "uncertainty": self.scoring_label,
                "v_peak_m_s": met.v_peak,
                "a_peak_m_s2": met.a_peak,
                "j_peak_m_s3": met.j_peak,
                "jerk_limited": math.isfinite(met.j_peak),
                "method": p.method,
                "recommended": n == "recommended",
                "fmu_parameters": _json(p.fmu_parameters),
                "z_fmu_parameters": _json(p.z_fmu_parameters),
            })
        return out

    def to_csv(self, path: str | Path) -> Path:
        """Write :meth:`rows` as CSV; return the path."""
        return write_csv(path, self.rows())

    # ------------------------------------------------------------ tables

    @property
    def has_signals(self) -> bool:
        """Whether the time series were kept (single moves; not the cases of a sweep)."""
        return any(p.run is not None for p in self.profiles.values())

    def signals(self) -> dict[str, np.ndarray]:
        """Every profile's time series as the columns of ``<scenario>-signals.csv``.

        ``t_s``; ``z_m`` and ``f_Hz``, the Z position and the tuned mode's frequency
        in the first profile's run; then, for each profile ``P``: ``P_x_m``,
        ``P_v_m_s``, ``P_a_m_s2``, ``P_j_m_s3`` (reference of the excited axis),
        ``P_eps_m`` (deflection ε of the load) and ``P_z_m``, ``P_f_Hz`` (its own Z
        position and tuned-mode frequency: the Z move ends with the excited axis,
        so they depend on the profile).

        The runs share the sampling; the table spans the longest record, the shorter
        runs continued at rest (:meth:`CoSimResult.to_table
        <harness.simulation.master.CoSimResult.to_table>`).

        Raises
        ------
        ValueError
            If no time series was kept (a sweep's case) or the runs' steps differ.
        """
        runs = {n: p.run for n, p in self.profiles.items() if p.run is not None}
        if not runs:
            raise ValueError(f"{self.scenario.name}: no time series kept (a sweep's case)")
        steps = {float(r.step) for r in runs.values()}
        if len(steps) != 1:
            raise ValueError(f"{self.scenario.name}: the runs have different steps {steps}")
        length = max(r.t.size for r in runs.values())
        mode = self.scenario.modemap.tune
        tabs = {n: r.to_table(mode, length) for n, r in runs.items()}
        first = next(iter(tabs.values()))
        longest = max(runs.values(), key=lambda r: r.t.size)
        cols = {"t_s": np.asarray(longest.t, dtype=float).copy(), "z_m": first["z_m"],
                "f_Hz": first["f_Hz"]}
        for n, tab in tabs.items():
            for _, suffix in SIGNAL_COLUMNS:
                cols[f"{n}_{suffix}"] = tab[suffix]
        return cols

    def to_table(self, what: str = "signals") -> dict[str, np.ndarray]:
        """Return the results as columns of numpy arrays.

        Parameters
        ----------
        what : {"signals", "metrics"}
            ``signals``: the time series (:meth:`signals`, the columns of
            ``<scenario>-signals.csv``); ``metrics``: one row per profile (the columns
            of ``<scenario>.csv``, :meth:`rows`).

        Returns
        -------
        dict of str to ndarray
        """
        if what == "signals":
            return self.signals()
        if what == "metrics":
            return columns_of(self.rows())
        raise ValueError(f"what must be 'signals' or 'metrics', got {what!r}")

    def to_pandas(self, what: str = "signals") -> Any:
        """:meth:`to_table` as a :class:`pandas.DataFrame` (pandas is optional).

        Raises
        ------
        ImportError
            When pandas is not installed.
        """
        return to_pandas(self.to_table(what))

    def mat_variables(self) -> dict[str, Any]:
        """Return the variables of ``<scenario>.mat``.

        ``scenario`` (its name), ``metrics`` (a struct of the CSV's columns) and, when the
        time series were kept, ``signals`` (a struct of the signals CSV's columns) and
        ``signal_columns`` (their CSV names, in order).

        Struct fields are the column names made valid MATLAB names
        (:func:`harness.tables.mat_name`: ``DJL-optimal_x_m`` -> ``DJL_optimal_x_m``).
        """
        out: dict[str, Any] = {"scenario": self.scenario.name,
                               "metrics": mat_variables(self.to_table("metrics"))}
        if self.has_signals:
            sig = self.signals()
            out["signals"] = mat_variables(sig)
            out["signal_columns"] = np.array(list(sig), dtype=object)
        return out

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
                         metrics={n: p.metrics for n, p in self.profiles.items()},
                         band_label=self.band_source)


TABLE2_PROFILES = ("JL", "DJL")
"""The profiles Table 2 compares (DJL against JL): a sweep's duplicates are the cases where
both plan the same moves."""

TABLE2_METRICS: dict[str, tuple[str, str]] = {
    "residual": ("residual", "Residual vibrations"),
    "settling": ("settling_time", "Settling times"),
    "settling_paper": ("settling_time_paper", f"Settling times ({PAPER_BAND_LABEL})"),
    "worst_residual_10pct": ("worst_map_residual",
                             "{worst} (time-varying plant, whole map x (1 + e))"),
}
"""Quantities of Table 2: key → (metric of :meth:`ScenarioResult.metric`, label).

The key ``worst_residual_10pct`` (table2.csv's ``quantity``, kept) is the worst case over
the run's map scale; its label's ``{worst}`` is :func:`worst_label` of the sweeps' span."""


# ------------------------------------------------------------------ sweeps


@dataclass
class SweepResult(TableMixin):
    """A sweep over the paper's test set: every case's Table 1 and their Table 2.

    Identical moves are counted once in the statistics (:meth:`stats`,
    :func:`format_table2`, :meth:`plot`): two cases are the same move when the
    generators planned exactly the same moves for the profiles Table 2
    compares, JL and DJL (:data:`TABLE2_PROFILES`, :meth:`ScenarioResult.move_key`;
    every profile if one of them is missing), e.g. at d = 0.1 m, where JL and
    DJL never reach v_max = 0.5 m/s, so that v_max = 0.5 and 2 m/s plan the
    same JL and DJL moves (AL, which does reach 0.5 m/s, differs).  The first
    case of each move is the one counted.  The CSV keeps every case and names
    the first case of each duplicate (``duplicate_of``).

    Attributes
    ----------
    scenario : Scenario
        The sweep scenario.
    cases : list of ScenarioResult
        One per combination (time series dropped).
    """

    scenario: Any
    cases: list[ScenarioResult]

    # ------------------------------------------------------------ moves

    def duplicates(self, profiles: Sequence[str] = ()) -> list[int | None]:
        """For each case, the index of the first case with the same moves, or None.

        None for the first case of each move.  A case whose moves are unknown
        (no ``plan_info``) is never merged.

        Parameters
        ----------
        profiles : sequence of str
            Profiles whose moves must coincide; default :data:`TABLE2_PROFILES`
            (JL and DJL), or every profile of a case that lacks one of them.
        """
        first: dict[Any, int] = {}
        out: list[int | None] = []
        for i, c in enumerate(self.cases):
            names = tuple(profiles) or (TABLE2_PROFILES if all(
                p in c.profiles for p in TABLE2_PROFILES) else tuple(c.profiles))
            k = c.move_key(names)
            j = i if k is None else first.setdefault(k, i)
            out.append(None if j == i else j)
        return out

    def distinct(self) -> list[ScenarioResult]:
        """Return the cases counted in the statistics: the first of each distinct move."""
        return [c for c, d in zip(self.cases, self.duplicates(), strict=True) if d is None]

    def case_label(self, case: ScenarioResult) -> str:
        """Short name of a case: its sweep values (``d=0.1 dz=0.2 v=2``)."""
        name, prefix = case.scenario.name, self.scenario.name + " "
        return name[len(prefix):] if name.startswith(prefix) else name

    def merged_note(self) -> str:
        """How many cases, distinct moves and merged duplicates, and which.

        E.g. ``50 cases, 45 distinct moves (5 duplicates merged: d=0.1 dz=0.1 v=2 = v=0.5;
        ...)``: the duplicate first, then the sweep values in which its original differs.
        """
        dup = self.duplicates()
        pairs = [(i, j) for i, j in enumerate(dup) if j is not None]
        n, k = len(self.cases), len(self.cases) - len(pairs)
        if not pairs:
            return f"{n} cases, {k} distinct moves (no duplicate)"
        items = []
        for i, j in pairs:
            a, b = self.case_label(self.cases[i]).split(), self.case_label(self.cases[j]).split()
            diff = [y for x, y in zip(a, b, strict=False) if x != y] if len(a) == len(b) else b
            items.append(f"{' '.join(a)} = {' '.join(diff or b)}")
        return (f"{n} cases, {k} distinct moves ({len(pairs)} duplicate"
                f"{'s' if len(pairs) > 1 else ''} merged, same JL and DJL moves: "
                f"{'; '.join(items)})")

    @property
    def band_label(self) -> str:
        """Source of the settling band of the cases (the same in every case)."""
        sources = {c.band_source for c in self.cases}
        return sources.pop() if len(sources) == 1 else self.scenario.simulation.settle_band.label

    # ------------------------------------------------------------ numbers

    def changes(self) -> tuple[np.ndarray, np.ndarray]:
        """DJL against JL in % for every case: (residual vibration, settling time in the band).

        Every case, duplicates included (see :meth:`changes_all` for the others).
        """
        pairs = [c.djl_vs_jl() for c in self.cases]
        return (np.array([p[0] for p in pairs]), np.array([p[1] for p in pairs]))

    def changes_all(self, *, distinct: bool = True) -> dict[str, np.ndarray]:
        """DJL against JL in % of every Table 2 quantity (:data:`TABLE2_METRICS`).

        Parameters
        ----------
        distinct : bool
            Only the first case of each distinct move (the statistics' set);
            False: every case.
        """
        cases = self.distinct() if distinct else self.cases
        ch = [c.djl_vs_jl_all() for c in cases]
        return {k: np.array([c[k] for c in ch], dtype=float) for k in TABLE2_METRICS}

    def stats(self) -> dict[str, Table2Stats]:
        """Table 2 statistics over the distinct moves.

        Keys: ``residual``, ``settling`` (in the cases' band), ``settling_paper``
        (in the paper's band, DJL's residual), ``worst_residual_10pct`` (worst
        residual over a map error within ± the scenario's map scale, 10 % by
        default; n = 0 when not computed).
        """
        return {k: table2_stats(v) for k, v in self.changes_all(distinct=True).items()}

    def tuned_variants(self) -> list[str]:
        """Profiles with their own tuning method (``DJL-optimal``, ...) compared with JL."""
        first = self.cases[0].profiles if self.cases else {}
        return [p for p in first if "-" in p and "JL" in first]

    def tuned_stats(self, variant: str) -> dict[str, float]:
        """Compare a tuned variant with JL over the distinct moves.

        Returns
        -------
        dict
            ``residual_pct_of_JL_mean`` / ``_max`` (its residual as % of JL's),
            ``worse_than_JL`` (moves where it leaves more than JL, to 1e-12),
            ``worst_pct_of_JL_mean`` / ``_max`` (its worst residual over a
            map error within ± the map scale as % of JL's worst; NaN if not
            computed),
            ``worst_below_DJL`` (moves where its worst case is below the
            paper-rule DJL's; NaN without DJL), ``motion_time_change_pct_mean``
            / ``_max`` (motion time against JL's), ``n`` (distinct moves).
        """
        cases = self.distinct()
        res = np.array([c.metric(variant, "residual") / c.metric("JL", "residual")
                        for c in cases])
        worse = sum(c.metric(variant, "residual") > c.metric("JL", "residual") * (1 + 1e-12)
                    for c in cases)
        w = np.array([c.metric(variant, "worst_map_residual")
                      / c.metric("JL", "worst_map_residual") for c in cases])
        below = (sum(c.metric(variant, "worst_map_residual")
                     < c.metric("DJL", "worst_map_residual") for c in cases)
                 if cases and "DJL" in cases[0].profiles else math.nan)
        mt = np.array([c.relative("motion_time", variant, "JL", change=True) for c in cases])

        def stat(fn: Any, x: np.ndarray) -> float:
            x = x[np.isfinite(x)]
            return float(fn(x)) if x.size else math.nan

        return {"residual_pct_of_JL_mean": 100 * stat(np.mean, res),
                "residual_pct_of_JL_max": 100 * stat(np.max, res),
                "worse_than_JL": float(worse),
                "worst_pct_of_JL_mean": 100 * stat(np.mean, w),
                "worst_pct_of_JL_max": 100 * stat(np.max, w),
                "worst_below_DJL": float(below),
                "motion_time_change_pct_mean": stat(np.mean, mt),
                "motion_time_change_pct_max": stat(np.max, mt),
                "n": float(len(cases))}

    def table(self) -> str:
        """Table 2 of the paper for this sweep alone."""
        return format_table2([self])

    # --------------------------------------------------------------- CSV

    def rows(self) -> list[dict[str, Any]]:
        """Every case's CSV rows (duplicates included, marked in ``duplicate_of``)."""
        out = []
        dup = self.duplicates()
        for c, d in zip(self.cases, dup, strict=True):
            ch = c.djl_vs_jl_all()
            for row in c.rows():
                row = {"sweep": self.scenario.name, **row}
                row["case_djl_vs_jl_residual_pct"] = ch["residual"]
                row["case_djl_vs_jl_settling_pct"] = ch["settling"]
                row["duplicate_of"] = "" if d is None else self.cases[d].scenario.name
                row["case_djl_vs_jl_settling_paper_band_pct"] = ch["settling_paper"]
                row["case_djl_vs_jl_residual_worst_map10_pct"] = ch["worst_residual_10pct"]
                out.append(row)
        return out

    def to_csv(self, path: str | Path) -> Path:
        """Write :meth:`rows` as CSV; return the path."""
        return write_csv(path, self.rows())

    def mat_variables(self) -> dict[str, Any]:
        """Return the variables of ``<scenario>.mat``.

        ``scenario`` (its name) and ``metrics`` (a struct of the CSV's columns, one element
        per case and profile); a sweep keeps no time series.
        """
        return {"scenario": self.scenario.name, "metrics": mat_variables(self.to_table())}

    # -------------------------------------------------------------- plot

    def plot(self, title: str | None = None):
        """Per distinct move: residual of DJL against JL, and the % changes; return the figure."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        cases = self.distinct()
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(15, 9), width_ratios=(1, 1.55))
        jl = np.array([c.metric("JL", "residual") for c in cases]) * 1e3
        djl = np.array([c.metric("DJL", "residual") for c in cases]) * 1e3
        dz = np.array([c.scenario.z.distance for c in cases])
        sc = ax1.scatter(jl, djl, c=dz, cmap="viridis", s=30)
        lim = [min(jl.min(), djl.min()) * 0.8, max(jl.max(), djl.max()) * 1.25]
        ax1.plot(lim, lim, "k--", lw=0.8, label="DJL = JL")
        ax1.set_xscale("log")
        ax1.set_yscale("log")
        ax1.set_xlabel("JL residual vibration [mm] (free-oscillation amplitude at the end)")
        ax1.set_ylabel("DJL residual vibration [mm]")
        ax1.grid(True, which="both", alpha=0.3)
        ax1.legend(fontsize="small")
        fig.colorbar(sc, ax=ax1, label="Z travel dz [m]")
        ch = self.changes_all(distinct=True)
        idx = np.arange(len(cases))
        bars = [("residual", "residual vibration", "tab:red"),
                ("settling", f"settling time ({self.band_label})", "tab:purple")]
        if np.isfinite(ch["settling_paper"]).any() and "paper" not in self.band_label:
            bars.append(("settling_paper", f"settling time ({PAPER_BAND_LABEL})", "tab:orange"))
        if np.isfinite(ch["worst_residual_10pct"]).any():
            bars.append(("worst_residual_10pct", "worst residual, map error +/-"
                         f"{span_text(self.scenario.uncertainty.map_scale)} %", "tab:green"))
        wb = 0.8 / len(bars)
        for i, (k, lab, col) in enumerate(bars):
            ax2.bar(idx - 0.4 + wb * (i + 0.5), ch[k], width=wb, color=col, label=lab)
        ax2.axhline(0.0, color="k", lw=0.8)
        # every bar group labelled with its move (d [m], dz [m], v_max [m/s])
        ax2.set_xticks(idx, [self.case_label(c).replace("v=", "v_max=") for c in cases],
                       rotation=90, fontsize=6.5 if len(cases) > 30 else "small")
        ax2.set_xlim(-0.7, len(cases) - 0.3)
        ax2.set_xlabel("distinct move: d, dz [m], v_max [m/s] (duplicates counted once)")
        ax2.set_ylabel("DJL compared with JL [%]")
        ax2.grid(True, axis="y", alpha=0.3)
        # the legend above the bars: off the data
        ax2.legend(fontsize="small", loc="lower center", bbox_to_anchor=(0.5, 1.0),
                   ncol=2, frameon=False)
        st = self.stats()
        head = textwrap.fill(f"Sweep {self.scenario.name}: {self.merged_note()}", width=170)
        fig.suptitle(title or (f"{head}\nDJL vs JL residual {st['residual'].mean:+.1f} % on "
                               f"average, settling time {st['settling'].mean:+.1f} % "
                               f"({self.band_label})"),
                     fontsize="medium")
        # fixed margins (for these labels at this size): no layout pass before the drawing
        fig.subplots_adjust(left=0.07, right=0.985, top=0.82, bottom=0.2, wspace=0.25)
        return fig


def _table2_sections(sweeps: Sequence[SweepResult]) -> list[tuple[str, str]]:
    """(key, heading) of the Table 2 sections that have numbers."""
    stats = [s.stats() for s in sweeps]
    labels = {s.band_label for s in sweeps}
    band = labels.pop() if len(labels) == 1 else "band: " + "; ".join(
        f"{s.scenario.name}: {s.band_label}" for s in sweeps)
    sections = [("residual", "Residual vibrations (free-oscillation amplitude at the end of "
                             "the motion)"),
                ("settling", f"Settling times ({band})")]
    if all(s.band_label != PAPER_BAND_LABEL for s in sweeps):
        sections.append(("settling_paper", TABLE2_METRICS["settling_paper"][1]))
    sections.append(("worst_residual_10pct", TABLE2_METRICS["worst_residual_10pct"][1].format(
        worst=WORST_PREFIX + _spans(sweeps))))
    return [(k, h) for k, h in sections if any(st[k].n > 0 for st in stats)]


def _spans(sweeps: Sequence[SweepResult]) -> str:
    """Return the sweeps' map-error span for a label: ``10 %``, or ``10 % (X), +/-15 % (Y)``."""
    spans = [span_text(s.scenario.uncertainty.map_scale) for s in sweeps]
    if len(set(spans)) <= 1:
        return f"{spans[0] if spans else span_text(LEGACY_SPAN)} %"
    return ", +/-".join(f"{x} % ({s.scenario.name})" for x, s in zip(spans, sweeps, strict=True))


def format_table2(sweeps: Sequence[SweepResult]) -> str:
    """Table 2 of the paper: one column per sweep (e.g. X and Y directions).

    Each distinct move is counted once; the settling times are given in the
    sweeps' band and, separately, in the paper's band (DJL's residual), each
    labelled; the worst residual over a map error within ± the sweeps' map scale
    (``uncertainty.map_scale``, 10 % by default) when computed.

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
    out = ["Statistics of the DJL profile compared with the JL profile (Table 2), in %; "
           "each distinct move counted once",
           " " * w0 + "".join(f"{n:>{w}}" for n in names)]
    for key, label in _table2_sections(sweeps):
        out.append(label)
        for field_, lab in (("mean", "Mean value"), ("max", "Max value (largest reduction)"),
                            ("min", "Min value (smallest reduction)"),
                            ("std", "Standard deviation")):
            out.append(f"  {lab:<{w0 - 2}}" + "".join(
                f"{getattr(st[key], field_):>{w}.1f}" for st in stats))
    out.append(f"  {'cases':<{w0 - 2}}" + "".join(f"{len(s.cases):>{w}d}" for s in sweeps))
    out.append(f"  {'distinct moves (counted)':<{w0 - 2}}"
               + "".join(f"{len(s.distinct()):>{w}d}" for s in sweeps))
    for s in sweeps:
        out.append(f"{s.scenario.name}: {s.merged_note()}")
    variants = [v for v in sweeps[0].tuned_variants()
                if all(v in s.tuned_variants() for s in sweeps)] if sweeps else []
    for v in variants:
        st = [s.tuned_stats(v) for s in sweeps]
        out.append("")
        out.append(f"{v} against JL (jerk times tuned on the time-varying model), per distinct "
                   "move")
        for key, lab, fmt in (
                ("residual_pct_of_JL_mean", "residual, % of JL's: mean", ".2f"),
                ("residual_pct_of_JL_max", "  largest", ".2f"),
                ("worse_than_JL", "moves leaving more than JL", ".0f"),
                ("worst_pct_of_JL_mean", f"worst over +/-{_spans(sweeps)} map, % of JL's",
                 ".1f"),
                ("worst_pct_of_JL_max", "  largest", ".1f"),
                ("worst_below_DJL", "worst case below paper-rule DJL's", ".0f"),
                ("motion_time_change_pct_mean", "motion time vs JL, %: mean", "+.2f"),
                ("motion_time_change_pct_max", "  largest", "+.2f")):
            out.append(f"  {lab:<{w0 - 2}}" + "".join(
                f"{format(x[key], fmt) if math.isfinite(x[key]) else 'n/a':>{w}}" for x in st))
    return "\n".join(out)


def table2_rows(sweeps: Sequence[SweepResult]) -> list[dict[str, Any]]:
    """Table 2 as CSV rows (one per statistic and sweep; ``cases``: values counted)."""
    rows = []
    for s in sweeps:
        st_all = s.stats()
        for key, _ in _table2_sections([s]):
            st = st_all[key]
            rows.append({"sweep": s.scenario.name, "quantity": key, "mean_pct": st.mean,
                         "max_reduction_pct": st.max, "min_reduction_pct": st.min,
                         "std_pct": st.std, "cases": st.n,
                         "band": PAPER_BAND_LABEL if key == "settling_paper" else
                         (s.band_label if key == "settling" else ""),
                         "sweep_cases": len(s.cases), "distinct_moves": len(s.distinct()),
                         "duplicates_merged": s.merged_note()})
    return rows
