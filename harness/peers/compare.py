"""The peers against AL / JL / DJL on the harness's scenarios: same plant, same metrics.

For one scenario (:mod:`harness.scenario`), :func:`compare_scenario`

1. runs AL, JL and DJL exactly as ``djl-fmu simulate`` does
   (:func:`harness.evaluation.run_case`: JL tuned to the modal period at the end of
   the motion, DJL stage by stage), which also fixes the settling band (the
   scenario's ``settle_band``, by default 1 % of AL's residual, one band for
   every method);
2. builds the peers from the same move (distance, v_max, a_max, d_max, Te),
   each tuned *to the mode at the end of the motion* (frequency of the tuned
   mode at the final Z position, its damping), as an engineer would:

   * ``time-optimal JL``: ruckig under v_max, a_max, d_max and the JL's jerk
     ``a_max / T_F(JL)`` -- the reference of the motion-time ratios;
   * ``Sato III``: Sato & Shirase's Condition III profile; ``T_SUM`` is the
     JL's motion time, lengthened to the shortest time at which the profile
     (which has no constant-velocity stage) keeps v_max and a_max, and
     ``T_1`` (a whole number of samples) minimises eq. 28 at the end-of-motion
     frequency within the limits;
   * ``AL*ZV``, ``AL*ZVD``, ``AL*MZV``, ``AL*EI``: the FMU's AL profile
     convolved with the shaper (exact delays);
   * ``JL*ZV``, ``JL*ZVD``, ``JL*EI`` (and ``JL*MZV`` on request): the FMU's JL
     profile (the harness's JL, jerk time = modal period at the end of the
     motion) convolved with the shaper, as input shapers are used on
     jerk-limited machines;
   * ``AL*TV-ZV``, ``JL*TV-ZV``: the time-varying ZV shaper
     (:mod:`harness.peers.tv_shaper`, after Chang & Park 2005), whose impulses
     follow the mode along the synchronised Z move instead of the end mode;
   * ``damped jerk``: the FMU's AL profile filtered by the damped-jerk filter;
   * ``DJL (optimal)``, ``DJL (robust)``: the DJL with the harness's other
     tuning methods (``sc.compare.djl_tuning``), when the harness has them;

3. feeds every peer's reference to the same plant (:class:`harness.plant.ScheduledPlant`)
   with the same Z axis (a generator FMU instance, its move synchronised with
   the peer's motion time, as the harness does for each profile), stepping like
   :func:`harness.simulation.master.cosimulate` (:func:`cosimulate_reference`: the exact
   acceleration is fed piece by piece, split at the method's own switching
   instants, so an input shaper's off-sample delays are not smeared), and
   measures it with :func:`harness.evaluation.profile_metrics` in the same band;
4. measures every method against a map error on the time-varying plant: the
   whole f(z) map scaled by 1 + e, e in ±2·m (m the map scale of the
   scenario's uncertainty, 0.1 by default: ±20 %), each reference planned once
   on the nominal map (:func:`reference_map_error_residuals` for the peers,
   :func:`harness.robustness.map_error_residuals` for AL / JL / DJL), and
   its worst case over ±m;
5. computes the residual of every method on a *stationary* mode whose
   frequency deviates from the tuned one (:func:`harness.peers.residual.robustness_curve`).

:func:`stationary_variant` turns a scenario into one whose Z axis does not
move (the mode stays at its end-of-motion frequency).
"""

from __future__ import annotations

import base64
import dataclasses
import html as _html
import io
import json
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..bound import bound_summary
from ..evaluation import profile_metrics, run_case
from ..figures import legend_outside
from ..files import write_csv
from ..recommend import recommend, table_of
from ..results import legacy_columns_note
from ..robustness import RobustnessResult
from ..scenario import Scenario, load_scenario
from ..scoring import peaks, score_uncertainty
from ..simulation.session import Session
from ..uncertainty import span_text
from .context import PeerContext, PeerSpec, placed
from .motion_axis import cosimulate_reference, reference_map_error_residuals
from .registry import ALL_PEERS, OPTIONAL_PEERS, PEERS, build
from .residual import RobustnessCurve, robustness_curve
from .ruckig_ref import time_optimal
from .sato import sato_design
from .shapers import base_motion
from .trajectory import Motion, PiecewiseJerk, SampledTrajectory

__all__ = [
    "ALL_PEERS",
    "BASE",
    "OPTIONAL_PEERS",
    "PEERS",
    "MethodOutcome",
    "PeerComparison",
    "PeerSpec",
    "base_motion",
    "build_peers",
    "compare_scenario",
    "cosimulate_reference",
    "placed",
    "reference_map_error_residuals",
    "sato_design",
    "stationary_variant",
]

BASE = ("AL", "JL", "DJL")

RUN_UNCERTAINTY = "uncertainty"
"""``compare_scenario(map_errors=...)``'s default: the map errors of the scenario's
uncertainty, ±2·map_scale in 41 points
(:meth:`harness.uncertainty.UncertaintySpec.curve_errors`: -20 % .. +20 %, 1 % apart by
default); the worst case is over ±map_scale."""

DJL_TUNINGS = ("optimal", "robust")
"""DJL tuning methods added as rows ``DJL (<tuning>)`` when the harness has
``sc.compare.djl_tuning`` (the paper's rule is the ``DJL`` row)."""


# ------------------------------------------------------------------ building


def build_peers(sc: Any, T_F_JL: float, motion_time_JL: float, *,
                peers: Iterable[str] = PEERS, fmu: Any = None,
                fmi_version: int = 2, session: Any = None) -> dict[str, tuple[Motion, PeerSpec]]:
    """Exact motions of the peer methods for the move of scenario ``sc``.

    Parameters
    ----------
    sc : harness.scenario.Scenario
    T_F_JL : float
        JL jerk time (s) found by the harness (sets the time-optimal jerk limit
        and the JL profile the ``JL*`` shapers act on).
    motion_time_JL : float
        JL motion time (s) (Sato's positioning time).
    peers : iterable of str
        Subset of :data:`ALL_PEERS` (:mod:`harness.peers.registry`).
    fmu, fmi_version
        Generator FMU of the session opened when none is given.
    session : harness.simulation.session.Session, optional
        Plans the AL / JL profiles and, for the time-varying shapers, the
        synchronised Z move; without it one is opened (and closed).

    Returns
    -------
    dict
        ``name -> (motion, spec)``.
    """
    peers = tuple(peers)
    unknown = [p for p in peers if p not in ALL_PEERS]
    if unknown:
        raise ValueError(f"unknown peer method(s) {unknown}; choose from {ALL_PEERS}")
    own = None
    if session is None:
        own = session = Session(sc.simulation.fmu if fmu is None else fmu, fmi_version)
    bases: dict[str, PiecewiseJerk] = {}

    def base(profile: str, distance: float | None = None) -> PiecewiseJerk:
        if distance is not None:
            return base_motion(sc, profile, T_F_JL, distance, session=session)
        if profile not in bases:
            bases[profile] = base_motion(sc, profile, T_F_JL, session=session)
        return bases[profile]

    tm = sc.modemap.tuned
    ctx = PeerContext(sc, T_F_JL, motion_time_JL, session,
                      float(tm.f(sc.z.z0 + sc.z.distance)), float(tm.zeta), base)
    try:
        return {p: build(ctx, p) for p in peers}
    finally:
        if own is not None:
            own.close()


# ------------------------------------------------------------ co-simulation


def _run_samples(run: Any, name: str) -> SampledTrajectory:
    """Wrap the FMU reference of a harness run (exact when step = Te)."""
    return SampledTrajectory(name=name, t=run.t, x=run.x, v=run.v, a=run.a, j=run.j,
                             params={}, motion_time=run.motion_time, t_start=run.t_start,
                             Te=run.step)


# ------------------------------------------------------------------ results


@dataclass
class MethodOutcome:
    """One method on one scenario.

    Attributes
    ----------
    name : str
    tuned_to : str
    metrics : harness.evaluation.ProfileMetrics
        Residual, free amplitude, motion time, rise and settling time (same band for all).
    run : harness.simulation.master.CoSimResult
    peaks : dict
        Largest |v|, |a|, |j| of the reference.
    params : dict
    worst_map_residual : float
        Largest residual (m) over the map errors within ± the scenario's map
        scale (``uncertainty.map_scale``, 10 % by default) on the time-varying
        plant (the reference planned on the nominal map); NaN when not
        computed.  :attr:`worst_10pct` is its earlier name (the CSV keeps
        ``worst_residual_10pct_m``).
    residual_worst, settling_worst : float
        Largest residual (m) and worst-case settling time (s) over the
        scenario's uncertainty (its scoring set), in the shared band.
    worst_point : str
        Where that settling time is reached.
    jerk_peak : float
        Largest |j| of the reference (m/s³); ``inf`` when its acceleration
        steps (no jerk limit).
    fmu_parameters : dict
        The generator FMU's start values that reproduce the reference, when
        the FMU can produce it (empty otherwise).
    """

    name: str
    tuned_to: str
    metrics: Any
    run: Any
    peaks: dict[str, float]
    params: dict[str, Any] = field(default_factory=dict)
    worst_map_residual: float = math.nan
    residual_worst: float = math.nan
    settling_worst: float = math.nan
    worst_point: str = ""
    jerk_peak: float = math.nan
    fmu_parameters: dict[str, Any] = field(default_factory=dict)

    @property
    def worst_10pct(self) -> float:
        """The earlier name of :attr:`worst_map_residual` (over the run's map scale)."""
        return self.worst_map_residual


STATIONARY_LABEL = "stationary mode at f_end (1 + error)"
"""What the stationary robustness curves vary (printed with them)."""

_STYLES: dict[str, tuple[str | None, str]] = {
    "AL": ("0.45", "-"), "JL": ("tab:blue", "-"), "DJL": ("tab:red", "-"),
    "DJL (optimal)": ("darkred", "-."), "DJL (robust)": ("lightcoral", "-."),
    "time-optimal JL": ("tab:cyan", ":"), "Sato III": ("tab:olive", ":"),
    "damped jerk": ("tab:brown", ":"),
    "AL*ZV": ("tab:green", "--"), "AL*ZVD": ("tab:purple", "--"), "AL*MZV": ("tab:pink", "--"),
    "AL*EI": ("tab:orange", "--"),
    "JL*ZV": ("tab:green", "-."), "JL*ZVD": ("tab:purple", "-."), "JL*MZV": ("tab:pink", "-."),
    "JL*EI": ("tab:orange", "-."),
    "AL*TV-ZV": ("black", "--"), "JL*TV-ZV": ("black", "-."),
}


def _style(name: str) -> tuple[str | None, str]:
    return _STYLES.get(name, (None, "--"))


def _ranking(values: dict[str, float], tie: float) -> list[list[str]]:
    """Methods grouped by value, best (smallest) first; values within ``tie`` share a group."""
    items = sorted(((v, n) for n, v in values.items() if not math.isnan(v)),
                   key=lambda x: x[0])
    groups: list[list[str]] = []
    best = math.nan
    for v, n in items:
        if groups and (v == best or abs(v - best) <= tie):
            groups[-1].append(n)
        else:
            groups.append([n])
            best = v
    return groups


@dataclass
class PeerComparison:
    """Every method on one scenario.

    Attributes
    ----------
    scenario : harness.scenario.Scenario
    methods : dict of str to MethodOutcome
        AL, JL, DJL (and the tuned DJL rows) then the peers.
    band : float
        Settling band (m) and where it comes from (``band_source``).
    T_opt : float
        Time-optimal motion time under the move's limits and the JL's jerk (s).
    f_end, zeta : float
        Mode the peers are tuned to.
    robustness : RobustnessCurve
        Residual on a stationary mode against its frequency error.
    base : harness.results.ScenarioResult
        The harness's own AL / JL / DJL result.
    map_error : harness.robustness.RobustnessResult, optional
        Residual of every method when the whole map f(z) of the plant is
        scaled by 1 + e (time-varying plant, references planned on the
        nominal map); None when not computed.
    scoring_label : str
        The scoring set the worst-case settling times are over (the scenario's
        uncertainty, ``scenario.uncertainty``).
    bound : harness.bound.BoundSummary, optional
        The physical limit: the least worst-case settling time any profile at
        JL's jerk can reach over the scoring set; None when not computed.
    notes : list of str
        What was skipped and why.
    motions : dict
        Each method's reference: the peers' exact motions, the harness's
        profiles as their samples.
    """

    scenario: Any
    methods: dict[str, MethodOutcome]
    band: float
    band_source: str
    T_opt: float
    f_end: float
    zeta: float
    robustness: RobustnessCurve
    base: Any
    map_error: Any = None
    notes: list[str] = field(default_factory=list)
    motions: dict[str, Any] = field(default_factory=dict)
    recommendation: Any = None
    scoring_label: str = ""
    bound: Any = None

    @property
    def worst_span(self) -> float:
        """The span of the map-error worst case: the scenario's ``uncertainty.map_scale``."""
        return float(self.scenario.uncertainty.map_scale)

    def rows(self) -> list[dict[str, Any]]:
        """One dict per method (the CSV rows)."""
        ref = self.methods["AL"].metrics
        sc = self.scenario
        limit = self.bound.t_settle if self.bound is not None else math.nan
        out = []
        for n, mo in self.methods.items():
            me = mo.metrics
            out.append({
                "scenario": sc.name, "method": n, "tuned_to": mo.tuned_to,
                "motion_time_s": me.motion_time,
                "motion_time_over_time_optimal": me.motion_time / self.T_opt,
                "residual_m": me.residual,
                "residual_pct_of_AL": 100.0 * me.residual / ref.residual,
                "free_amplitude_m": me.free_amplitude,
                "settling_time_s": me.settling_time,
                "rise_time_s": me.rise_time,
                "band_m": self.band,
                # named after the default +/-10 %: the run's span (worst_span), names kept
                "worst_residual_10pct_m": mo.worst_map_residual,
                "worst_residual_10pct_pct_of_AL": 100.0 * mo.worst_map_residual / ref.residual,
                "v_peak_over_v_max": mo.peaks["v"] / sc.move.v_max,
                "a_peak_over_a_max": mo.peaks["a"] / max(sc.move.a_max, sc.move.d_max),
                "j_peak_m_s3": mo.peaks["j"],
                "f_tuned_Hz": self.f_end, "zeta": self.zeta,
                # issue 18: the uncertainty, the jerk bound, replayable rows
                "residual_worst_m": mo.residual_worst,
                "settling_time_worst_s": mo.settling_worst,
                "worst_point": mo.worst_point,
                "settling_bound_s": limit,
                "settling_worst_over_bound": mo.settling_worst / limit,
                "uncertainty": self.scoring_label,
                "jerk_peak_m_s3": mo.jerk_peak,
                "jerk_over_JL": mo.jerk_peak / self.jerk_jl,
                "jerk_limited": math.isfinite(mo.jerk_peak),
                "recommended": n == "recommended",
                "fmu_parameters": json.dumps(mo.fmu_parameters, sort_keys=True)
                if mo.fmu_parameters else "",
                "z_fmu_parameters": json.dumps(
                    Session.z_move_params(sc, mo.run.z_v_max), sort_keys=True)
                if mo.fmu_parameters else "",
            })
        return out

    @property
    def jerk_jl(self) -> float:
        """JL's jerk (m/s³): a_max / T_F(JL), the bound every jerk-limited method keeps."""
        return self.scenario.move.a_max / float(self.base.profiles["JL"].T_F[0])

    @property
    def map_error_label(self) -> str:
        """What the map-error curves vary (RobustnessResult's label)."""
        if self.map_error is not None:
            return str(self.map_error.label)
        still = not self.scenario.z.moves
        return ("plant with Z still" if still else "time-varying plant (Z moving)") + \
            ", whole map scaled by 1 + e"

    def verdict(self) -> list[str]:
        """Who wins where, with the numbers: least residual, first settled, best worst case.

        Methods within 1e-9 of AL's residual (or 1e-9 s) of each other tie.
        """
        al = self.methods["AL"].metrics.residual
        res = {n: mo.metrics.residual for n, mo in self.methods.items()}
        st = {n: mo.metrics.settling_time for n, mo in self.methods.items()}
        wc = {n: mo.worst_map_residual for n, mo in self.methods.items()}
        ws = {n: mo.settling_worst for n, mo in self.methods.items()}

        def fmt_res(n: str, v: float) -> str:
            return f"{n} {v * 1e3:.3g} mm ({100 * v / al:.2g} % of AL)"

        def fmt_t(n: str, v: float) -> str:
            return f"{n} {v:.3f} s" if math.isfinite(v) else f"{n} never"

        def two(groups: list[list[str]], values: dict[str, float], fmt: Any) -> str:
            parts = []
            for g in groups[:2]:
                parts.append(" = ".join(g[:4]) + (f" (+{len(g) - 4} more)" if len(g) > 4 else "")
                             + " " + fmt("", values[g[0]]).strip())
            return "; then ".join(parts) if parts else "-"

        name = self.scenario.name
        out = [f"Who wins on {name}:",
               "  least residual: " + two(_ranking(res, 1e-9 * al), res, fmt_res),
               "  first settled (band +/-" + f"{self.band * 1e3:.3g} mm): "
               + two(_ranking(st, 1e-9), st, fmt_t)]
        if any(math.isfinite(v) for v in wc.values()):
            out.append(f"  smallest worst case over +/-{span_text(self.worst_span)} % map error ("
                       + self.map_error_label + "): " + two(_ranking(wc, 1e-9 * al), wc, fmt_res))
        if any(math.isfinite(v) for v in ws.values()):
            out.append("  first settled in the worst case (" + self.scoring_label + "): "
                       + two(_ranking(ws, 1e-9), ws, fmt_t))
        if self.bound is not None and any(math.isfinite(v) for v in ws.values()):
            jl_jerk = self.jerk_jl * (1 + 1e-6)
            limited = [(v, n) for n, v in ws.items()
                       if math.isfinite(v) and self.methods[n].jerk_peak <= jl_jerk]
            lim = self.bound.t_settle
            if limited:
                v, n = min(limited)
                out.append(f"  physical limit (any profile at JL's jerk, same set): {lim:.3f} s;"
                           f" the first jerk-limited method, {n}, at {v / lim:.3f} x it "
                           f"(+{100 * (v / lim - 1):.1f} %)")
        return out

    def table(self) -> str:
        """Format the table: motion time, ratio to time-optimal, residual, settling, worst case."""
        sc = self.scenario
        m = sc.move
        f0 = sc.modemap.tuned.f(sc.z.z0)
        z_txt = (f"Z {sc.z.z0:g} -> {sc.z.z0 + sc.z.distance:g} m, tuned mode "
                 f"{f0:.3g} -> {self.f_end:.3g} Hz" if sc.z.moves else
                 f"Z still at {sc.z.z0:g} m, mode {self.f_end:.3g} Hz")
        lines = [f"Scenario {sc.name}: {m.axis} d = {m.distance:g} m, v_max = {m.v_max:g} m/s, "
                 f"a_max = {m.a_max:g} m/s2; {z_txt}, zeta = {self.zeta:g}",
                 f"  peers tuned to the mode at the end of the motion ({self.f_end:.4g} Hz); "
                 f"time-optimal JL: {self.T_opt:.4g} s "
                 f"(j_max = a_max / T_F(JL))", ""]
        worst_head = f"worst±{span_text(self.worst_span)}% [mm]"
        head = (f"{'method':<16}{'motion [s]':>11}{'/ t.-opt.':>10}{'residual [mm]':>15}"
                f"{'% of AL':>9}{'settling [s]':>14}{worst_head:>16}"
                f"{'worst settle [s]':>18}{'/ bound':>9}{'v/v_max':>9}{'a/a_max':>9}"
                f"{'j/j_JL':>10}")
        lines += [head, "-" * len(head)]
        for r in self.rows():
            st = r["settling_time_s"]
            w = r["worst_residual_10pct_m"]
            ws = r["settling_time_worst_s"]
            wb = r["settling_worst_over_bound"]
            jj = r["jerk_over_JL"]
            lines.append(
                f"{r['method']:<16}{r['motion_time_s']:>11.3f}"
                f"{r['motion_time_over_time_optimal']:>10.3f}"
                f"{r['residual_m'] * 1e3:>15.4g}{r['residual_pct_of_AL']:>8.1f}%"
                f"{(f'{st:.3f}' if math.isfinite(st) else 'never'):>14}"
                f"{(f'{w * 1e3:.4g}' if math.isfinite(w) else '-'):>16}"
                f"{(f'{ws:.3f}' if math.isfinite(ws) else 'never'):>18}"
                f"{(f'{wb:.3f}' if math.isfinite(wb) else '-'):>9}"
                f"{r['v_peak_over_v_max']:>9.2f}{r['a_peak_over_a_max']:>9.2f}"
                f"{(f'{jj:.2f}' if math.isfinite(jj) else 'no limit'):>10}")
        lines.append("")
        lines.append(f"Settling band +/-{self.band * 1e3:.3g} mm ({self.band_source}); "
                     "residual: free-oscillation amplitude when the reference ends.")
        if self.map_error is not None:
            pct = span_text(self.worst_span)
            lines.append(f"worst±{pct}%: largest residual over map errors e in +/-{pct} % "
                         f"({self.map_error_label}; each reference planned on the nominal map)."
                         + legacy_columns_note(self.worst_span, "worst_residual_10pct_m, "
                                                                "worst_residual_10pct_pct_of_AL"))
        if self.scoring_label:
            lines.append(f"worst settle: worst-case settling time over the {self.scoring_label} "
                         f"(never the points a method was tuned on); j/j_JL: largest jerk over "
                         f"JL's, 'no limit' where the acceleration steps (AL-based).")
        if self.bound is not None:
            lines.append(f"/ bound: worst settle over the {self.bound.describe()}.")
        for mo in self.methods.values():
            if mo.name not in BASE:
                lines.append(f"  {mo.name}: {mo.tuned_to}")
        lines.extend(f"  note: {n}" for n in self.notes)
        lines.append("")
        lines.extend(self.verdict())
        rec = self.recommendation
        if rec is not None:
            lines.append("")
            lines.append("Why the recommended profile:")
            lines.extend(f"  {x}" for x in rec.explanation)
            deg = rec.degradation(sc)
            if deg is not None:
                lines.extend(deg.lines())
        return "\n".join(lines)

    def degradation(self):  # -> Degradation | None
        """Return the worst-case settling of the recommended and textbook shapers vs width."""
        rec = self.recommendation
        return rec.degradation(self.scenario) if rec is not None else None

    def to_csv(self, path: Any) -> Any:
        """Write :meth:`rows` as CSV; return the path.

        The curves: :meth:`robustness_rows`, :meth:`map_error_rows`.
        """
        return write_csv(path, self.rows())

    def robustness_rows(self) -> list[dict[str, Any]]:
        """Return the stationary-mode curves as rows (error, method, residual, % of AL)."""
        rc = self.robustness
        pc = rc.percent()
        return [{"scenario": self.scenario.name, "plant": STATIONARY_LABEL,
                 "frequency_error": float(e), "f_Hz": rc.f_tuned * (1 + float(e)), "method": k,
                 "residual_m": float(rc.residual[k][i]), "residual_pct_of_AL": float(pc[k][i])}
                for k in rc.residual for i, e in enumerate(rc.error)]

    def map_error_rows(self) -> list[dict[str, Any]]:
        """Return the map-error curves (time-varying plant) as rows; empty if not computed."""
        if self.map_error is None:
            return []
        return [{("method" if k == "profile" else k): v for k, v in r.items()}
                for r in self.map_error.rows()]

    def _plot_stationary(self, ax: Any, percent: bool) -> None:
        rc = self.robustness
        data = rc.percent() if percent else {k: np.maximum(v * 1e3, 1e-9)
                                              for k, v in rc.residual.items()}
        for k, v in data.items():
            c, ls = _style(k)
            (ax.plot if percent else ax.semilogy)(100 * rc.error, v, color=c, ls=ls, label=k)
        ax.set_xlabel(f"mode frequency error [%] around {rc.f_tuned:.3g} Hz "
                      f"({STATIONARY_LABEL})", fontsize="small")
        ax.grid(True, which="both", alpha=0.3)

    def _plot_map(self, ax: Any, percent: bool) -> None:
        me = self.map_error
        al = me.residual["AL"]
        worst = {}
        try:
            worst = me.worst(self.worst_span)
        except ValueError:
            pass
        pct = 100.0 * self.worst_span
        ax.axvspan(-pct, pct, color="0.92", lw=0)
        for k, v in me.residual.items():
            c, ls = _style(k)
            lab = k if k not in worst or percent else f"{k}: worst {worst[k] * 1e3:.3g} mm"
            if percent:
                ax.plot(100 * me.errors, 100 * v / al, color=c, ls=ls, label=lab)
            else:
                ax.semilogy(100 * me.errors, np.maximum(v * 1e3, 1e-9), color=c, ls=ls,
                            label=lab)
        ax.set_xlabel("map error e [%]: the plant's f(z) x (1 + e); references planned "
                      "on the nominal map", fontsize="small")
        ax.grid(True, which="both", alpha=0.3)

    def plot(self, title: str | None = None):
        """Residual against the mode-frequency error on a *stationary* mode; return the Figure."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(15, 5.2))
        self._plot_stationary(ax1, True)
        self._plot_stationary(ax2, False)
        ax1.set_ylim(0, 60)
        ax1.set_ylabel("residual [% of AL at the same frequency]")
        ax2.set_ylabel("residual amplitude [mm]")
        ax2.axhline(self.band * 1e3, color="gold", lw=2, label="settling band")
        legend_outside(ax2)
        fig.suptitle(title or f"Scenario {self.scenario.name}: robustness to the mode "
                     f"frequency, {STATIONARY_LABEL}, zeta = {self.robustness.zeta:g} "
                     "(methods as planned for the scenario)", fontsize="medium")
        fig.tight_layout()
        return fig

    def plot_map_error(self, title: str | None = None):
        """Residual against a map error on the time-varying plant; return the Figure.

        Raises
        ------
        ValueError
            If the map-error curves were not computed.
        """
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        if self.map_error is None:
            raise ValueError("no map-error curves (compare_scenario(..., map_errors=None))")
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(15, 5.2))
        self._plot_map(ax1, True)
        self._plot_map(ax2, False)
        ax1.set_ylim(0, 60)
        ax1.set_ylabel("residual [% of AL at the same map error]")
        ax2.set_ylabel("residual amplitude [mm]")
        ax2.axhline(self.band * 1e3, color="gold", lw=2, label="settling band")
        legend_outside(ax2)
        fig.suptitle(title or f"Scenario {self.scenario.name}: robustness to a map error, "
                     f"{self.map_error_label} (shaded: +/-{span_text(self.worst_span)} %, the "
                     "worst case)",
                     fontsize="medium")
        fig.tight_layout()
        return fig

    def plot_robustness(self, title: str | None = None):
        """Both robustness checks side by side (the report's figure); return the Figure.

        Left: stationary mode at ``f_end (1 + error)``; right (when computed):
        time-varying plant, whole map scaled by 1 + e.
        """
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        two = self.map_error is not None
        fig, axes = plt.subplots(1, 2 if two else 1, figsize=(16 if two else 10, 5.4),
                                 squeeze=False)
        ax1 = axes[0, 0]
        self._plot_stationary(ax1, False)
        ax1.set_ylabel("residual amplitude [mm]")
        ax1.set_title(f"{STATIONARY_LABEL}, zeta = {self.robustness.zeta:g}",
                      fontsize="medium")
        ax1.axhline(self.band * 1e3, color="gold", lw=2, label="settling band")
        if two:
            ax2 = axes[0, 1]
            self._plot_map(ax2, False)
            ax2.set_ylabel("residual amplitude [mm]")
            ax2.set_title(self.map_error_label + f" (shaded: +/-{span_text(self.worst_span)} %)",
                          fontsize="medium")
            ax2.axhline(self.band * 1e3, color="gold", lw=2)
        # one legend, right of the panels (the same methods in both): off the data
        legend_outside(axes[0, -1], handles=ax1.get_legend_handles_labels()[0])
        fig.suptitle(title or f"Scenario {self.scenario.name}: residual of every method "
                     "against a frequency error", fontsize="medium")
        fig.tight_layout()
        return fig

    def html(self) -> str:
        """Return an HTML fragment (table and robustness figures, PNG embedded) for a report."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        fig = self.plot_robustness()
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=90)
        plt.close(fig)
        png = base64.b64encode(buf.getvalue()).decode("ascii")
        return (f"<h3>Scenario {_html.escape(self.scenario.name)}</h3>\n"
                f"<pre>{_html.escape(self.table())}</pre>\n"
                f'<img alt="robustness, scenario {_html.escape(self.scenario.name)}" '
                f'src="data:image/png;base64,{png}">\n')

    def plot_runs(self, title: str | None = None):
        """Deflection of every method in the scenario's co-simulation; return the Figure."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        fig, axes = plt.subplots(2, 1, figsize=(13, 7), sharex=True)
        for n, mo in self.methods.items():
            r = mo.run
            c, ls = _style(n)
            axes[0].plot(r.t, r.a, lw=1, color=c, ls=ls, label=n)
            axes[1].plot(r.t, r.eps * 1e3, lw=1, color=c, ls=ls, label=n)
        axes[1].axhspan(-self.band * 1e3, self.band * 1e3, color="gold", alpha=0.35, lw=0)
        zoom = max(mo.metrics.residual for n, mo in self.methods.items() if n != "AL")
        axes[1].set_ylim(-3e3 * max(zoom, self.band), 3e3 * max(zoom, self.band))
        axes[0].set_ylabel("a [m/s²]")
        axes[1].set_ylabel("ε [mm] (zoom)")
        axes[1].set_xlabel("t [s]")
        legend_outside(axes[0])
        for ax in axes:
            ax.grid(True, alpha=0.3)
        fig.suptitle(title or f"Scenario {self.scenario.name}: every method through the plant")
        fig.tight_layout()
        return fig


def stationary_variant(sc: Any) -> Any:
    """Return the scenario with Z still at its final position (a stationary mode)."""
    z = dataclasses.replace(sc.z, z0=sc.z.z0 + sc.z.distance, distance=0.0)
    return dataclasses.replace(sc, z=z, name=f"{sc.name}-stationary",
                               description=f"{sc.name} with Z still at {z.z0:g} m")


def has_djl_tuning(sc: Any) -> bool:
    """Whether the harness tunes DJL by other methods than the paper's (``compare.djl_tuning``)."""
    return hasattr(sc.compare, "djl_tuning")


def _T_F_text(T_F: Sequence[float]) -> str:
    return "T_F " + "/".join(f"{x * 1e3:.0f}" for x in T_F) + " ms"


def compare_scenario(scenario: Any, *, session: Any = None, peers: Sequence[str] = PEERS,
                     errors: np.ndarray | None = None, engine: str = "fmu",
                     map_errors: Sequence[float] | np.ndarray | str | None = RUN_UNCERTAINTY,
                     map_engine: str = "fast", tuned_djl: bool = True,
                     recommended: bool = True, bound: bool = True) -> PeerComparison:
    """Run AL / JL / DJL and the peers on one (non-sweep) scenario.

    Parameters
    ----------
    scenario : Scenario, str or Path
        A scenario (or an embedded name, or a TOML file) without ``[sweep]``.
    session : harness.simulation.session.Session, optional
        Generator instances to reuse.
    peers : sequence of str
        Subset of :data:`ALL_PEERS` (default :data:`PEERS`).
    errors : ndarray, optional
        Relative frequency errors of the stationary-mode robustness curves
        (default -40 % .. +40 %).
    engine : {"fmu", "fast"}
        Engine of the session made when ``session`` is not given (see
        :class:`harness.simulation.session.Session`).
    map_errors : array_like, "uncertainty" or None
        Map errors e of the time-varying robustness (the plant's whole f(z)
        scaled by 1 + e; default ``"uncertainty"``: ±2·map_scale of the
        scenario's uncertainty in 41 points, -20 % .. +20 % by default); the
        worst case is taken over the points within ± the map scale.  None: not
        computed.
    map_engine : {"fast", "fmu"}
        Engine of the map-error runs and of the tuned DJL rows (default the
        fast engine: the same results, many runs).
    tuned_djl : bool
        Add ``DJL (optimal)`` and ``DJL (robust)`` when the harness has
        ``sc.compare.djl_tuning`` (the ``JL`` and ``DJL`` rows are then run
        with ``jl_tuning = "end"`` and ``djl_tuning = "paper"`` whatever the
        scenario says: the harness's JL and the paper's DJL).
    recommended : bool
        Add the row ``recommended`` (:func:`harness.recommend.recommend`: the
        robust-tuned member of DJL, JL*shaper and DJL*shaper that settles first
        in the worst case of the tuning set, at JL's jerk).
    bound : bool
        Compute the physical limit (:func:`harness.bound.bound_summary`: no
        profile at JL's jerk settles sooner in the worst case of the scoring
        set) and report every method's worst-case settling as a ratio to it.
        About 30 s the first time per move and band, then from the disk cache.

    Returns
    -------
    PeerComparison
    """
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    if sc.is_sweep:
        raise ValueError(f"{sc.name}: compare takes single-move scenarios, not sweeps")
    if isinstance(map_errors, str) and map_errors != RUN_UNCERTAINTY:
        raise ValueError(f"map_errors must be map errors, {RUN_UNCERTAINTY!r} or None, got "
                         f"{map_errors!r}")
    base_cmp: dict[str, Any] = {"profiles": BASE}
    if has_djl_tuning(sc):  # the JL and DJL rows are the harness's usual ones
        base_cmp.update(djl_tuning="paper", jl_tuning="end")
    sc = dataclasses.replace(sc, compare=dataclasses.replace(sc.compare, **base_cmp))
    own = session is None
    if own:
        session = Session(sc.simulation.fmu, sc.simulation.fmi_version, engine=engine)
    own_map = False
    msession = session
    notes: list[str] = []
    try:
        if session.engine != map_engine and (
                map_errors is not None or tuned_djl):
            msession = Session(sc.simulation.fmu, sc.simulation.fmi_version, engine=map_engine)
            own_map = True
        base = run_case(sc, session)
        band = base.band
        jl = base.profiles["JL"]
        methods: dict[str, MethodOutcome] = {}
        motions: dict[str, Motion | SampledTrajectory] = {}
        for n in BASE:
            p = base.profiles[n]
            st = _run_samples(p.run, n)
            methods[n] = MethodOutcome(n, "harness" if n == "AL" else
                                       _T_F_text(p.T_F[:1] if n == "JL" else p.T_F),
                                       p.metrics, p.run, st.peaks())
            motions[n] = st
        # the DJL with the harness's other tuning methods (when it has them)
        tuned_sc: dict[str, Any] = {}
        if tuned_djl and has_djl_tuning(sc):
            for tu in DJL_TUNINGS:
                name = f"DJL ({tu})"
                sct = dataclasses.replace(sc, compare=dataclasses.replace(
                    sc.compare, djl_tuning=tu, profiles=("DJL",), DJL_T_F=None))
                p = run_case(sct, msession).profiles["DJL"]
                st = _run_samples(p.run, name)
                methods[name] = MethodOutcome(
                    name, f"{_T_F_text(p.T_F)} ({tu} tuning, {map_engine} engine)",
                    profile_metrics(p.run, band), p.run, st.peaks(),
                    {"T_F": list(p.T_F), "djl_tuning": tu})
                motions[name] = st
                tuned_sc[name] = (sct, tuple(p.T_F))
        elif tuned_djl:
            notes.append("DJL (optimal), DJL (robust): skipped, this harness has no "
                         "compare.djl_tuning yet")
        if len(sc.modemap.modes) > 1 and "JL*MM-ZVD" not in peers and tuple(peers) == PEERS:
            peers = (*peers, "JL*MM-ZVD")  # several modes: add the multi-mode shaper
        built = build_peers(sc, jl.T_F[0], jl.metrics.motion_time, peers=peers,
                            fmi_version=sc.simulation.fmi_version, session=session)
        for n, (mot, spec) in built.items():
            st = mot.sample(sc.simulation.Te)
            run = cosimulate_reference(sc, session, mot, n)
            methods[n] = MethodOutcome(n, spec.tuned_to, profile_metrics(run, band), run,
                                       st.peaks(), spec.params)
            motions[n] = mot
        rec = None
        if recommended:
            rec = recommend(sc, msession, band, jl=jl.tuning)
            b = rec.best
            run = rec.run(sc, session)
            st = _run_samples(run, "recommended")
            methods["recommended"] = MethodOutcome(
                "recommended", f"{b.family}: {b.label(sc.simulation.Te)}",
                profile_metrics(run, band), run, st.peaks(),
                {"family": b.family, "T_F": list(b.T_F),
                 "shaper_amplitude": list(b.shaper.amplitudes) if b.shaper else [],
                 "shaper_delay_s": list(b.shaper.delays_s(sc.simulation.Te))
                 if b.shaper else [],
                 "table_pieces": len(table_of(b.jerk)[0])})
            motions["recommended"] = st
        # every method over the scenario's uncertainty (scoring set), in the shared band
        for n, mo in methods.items():
            sco = score_uncertainty(mo.run, sc, band)
            mo.residual_worst = float(sco["residual_worst"])
            mo.settling_worst = float(sco["settling_time_worst"])
            mo.worst_point = str(sco["worst_point"])
            mo.jerk_peak = float(peaks(mo.run)["j_peak"])
            mo.fmu_parameters = _fmu_parameters(sc, n, mo, base, built, rec)
        limit = bound_summary(sc, band, session=msession) if bound else None
        map_result = None
        if map_errors is not None:
            e = (sc.uncertainty.curve_errors() if isinstance(map_errors, str)
                 else np.asarray(map_errors, dtype=float).ravel())
            res: dict[str, np.ndarray] = {}
            T_F: dict[str, tuple[float, ...] | None] = {}
            for n in BASE:
                T_F[n] = None if n == "AL" else tuple(base.profiles[n].T_F)
                res[n] = msession.map_error_residuals(sc, n, T_F[n], e)
            for n, (sct, tf) in tuned_sc.items():
                T_F[n] = tf
                res[n] = msession.map_error_residuals(sct, "DJL", tf, e)
            for n, (mot, _) in built.items():
                T_F[n] = None
                res[n] = reference_map_error_residuals(sc, msession, mot, e)
            if rec is not None:
                T_F["recommended"] = tuple(rec.best.T_F)
                res["recommended"] = rec.map_error_residuals(sc, msession, e)
            span = sc.uncertainty.map_scale
            map_result = RobustnessResult(e, {n: res[n] for n in methods}, sc, T_F, span=span)
            if np.any(np.abs(e) <= span + 1e-12):
                for n, w in map_result.worst(span).items():
                    methods[n].worst_map_residual = w
    finally:
        if own_map:
            msession.close()
        if own:
            session.close()
    tm = sc.modemap.tuned
    f_end, zeta = float(tm.f(sc.z.z0 + sc.z.distance)), float(tm.zeta)
    m = sc.move
    T_opt = time_optimal(m.distance, m.v_max, m.a_max, m.a_max / base.profiles["JL"].T_F[0],
                         d_max=m.d_max).duration
    err = np.linspace(-0.4, 0.4, 81) if errors is None else np.asarray(errors, dtype=float)
    rc = robustness_curve(motions, f_end, zeta, err, reference="AL")
    return PeerComparison(sc, methods, band, base.band_source, T_opt, f_end, zeta, rc, base,
                          map_result, notes, motions, recommendation=rec,
                          scoring_label=base.scoring_label, bound=limit)


def _fmu_parameters(sc: Any, name: str, mo: MethodOutcome, base: Any, built: dict[str, Any],
                    rec: Any) -> dict[str, Any]:
    """Return the FMU start values that produce a method's reference (empty: it cannot)."""
    if name in base.profiles:
        return dict(base.profiles[name].fmu_parameters)
    if name == "recommended" and rec is not None:
        return rec.fmu_parameters(sc)
    if name.startswith("DJL (") and "T_F" in mo.params:
        return Session.move_params(sc, "DJL", mo.params["T_F"])
    spec = built.get(name, (None, None))[1]
    if spec is not None and name[:3] in ("AL*", "JL*") and "TV" not in name \
            and "A" in spec.params and "t" in spec.params:
        prof = name[:2]
        T_F = None if prof == "AL" else tuple(base.profiles["JL"].T_F)
        p = Session.move_params(sc, prof, T_F)
        p.update({"shaper": 4, "shaper_n": len(spec.params["A"]),
                  "shaper_amplitude": [float(a) for a in spec.params["A"]],
                  "shaper_delay": [float(t) for t in spec.params["t"]]})
        return p
    return {}
