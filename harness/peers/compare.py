"""The peers against AL / JL / DJL on the harness's scenarios: same plant, same metrics.

For one scenario (:mod:`harness.scenario`), :func:`compare_scenario`

1. runs AL, JL and DJL exactly as ``djl-fmu simulate`` does
   (:func:`harness.cosim.run_case`: JL tuned to the modal period at the end of
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
   :func:`harness.cosim.cosimulate` (:func:`cosimulate_reference`: the exact
   acceleration is fed piece by piece, split at the method's own switching
   instants, so an input shaper's off-sample delays are not smeared), and
   measures it with :func:`harness.cosim.profile_metrics` in the same band;
4. measures every method against a map error on the time-varying plant: the
   whole f(z) map scaled by 1 + e, e in ±20 %, each reference planned once on
   the nominal map (:func:`reference_map_error_residuals` for the peers,
   :func:`harness.robustness.map_error_residuals` for AL / JL / DJL), and
   its worst case over ±10 %;
5. computes the residual of every method on a *stationary* mode whose
   frequency deviates from the tuned one (:func:`harness.peers.residual.robustness_curve`).

:func:`stationary_variant` turns a scenario into one whose Z axis does not
move (the mode stays at its end-of-motion frequency).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .damped_jerk import DampedJerkFilter, DampedJerkMotion
from .residual import RobustnessCurve, robustness_curve
from .ruckig_ref import time_optimal
from .sato import amplitude_table1, jerk_J1, sato_profile
from .shapers import make_shaper, shape
from .trajectory import Motion, PiecewiseJerk, SampledTrajectory

PEERS = ("time-optimal JL", "Sato III", "AL*ZV", "AL*ZVD", "AL*MZV", "AL*EI", "JL*ZV",
         "JL*ZVD", "JL*EI", "AL*TV-ZV", "JL*TV-ZV", "damped jerk")
"""The peer methods run by default, in table order (after AL, JL, DJL)."""

OPTIONAL_PEERS = ("JL*MZV",)
"""Peers run only when asked for (``peers=`` / ``--peers``)."""

ALL_PEERS = PEERS + OPTIONAL_PEERS
"""Every peer :func:`build_peers` knows."""

BASE = ("AL", "JL", "DJL")

DJL_TUNINGS = ("optimal", "robust")
"""DJL tuning methods added as rows ``DJL (<tuning>)`` when the harness has
``sc.compare.djl_tuning`` (the paper's rule is the ``DJL`` row)."""


# ------------------------------------------------------------------ building


def _placed(m: PiecewiseJerk, t_start: float, x0: float, sign: float = 1.0) -> PiecewiseJerk:
    """Start the motion at ``t_start`` from ``x0``; mirror it when ``sign < 0``."""
    return PiecewiseJerk(m.tb + t_start, x0 + sign * (m.x - m.x[0]), sign * m.v, sign * m.a,
                         sign * m.j, name=m.name, params=dict(m.params))


def sato_design(distance: float, v_max: float, a_max: float, f: float, Te: float,
                T_SUM_min: float) -> tuple[float, float]:
    """Pick ``(T_SUM, T_1)`` of a Condition III profile for a move (see the module notes).

    Condition III: peak velocity ``1.5 L / (T_SUM - T_1)``, peak acceleration
    ``6 L / (T_SUM (T_SUM - T_1))`` (from eq. 18-19).

    Parameters
    ----------
    distance : float
        Move length (m, its magnitude is used).
    v_max, a_max : float
        Limits to keep (a_max: the smaller of acceleration and deceleration).
    f : float
        Mode frequency the jerk times are designed for (Hz).
    Te : float
        Grid of T_SUM and T_1 (s).
    T_SUM_min : float
        Shortest positioning time wanted (s).

    Returns
    -------
    T_SUM, T1 : float
    """
    L = abs(distance)
    n = int(math.ceil(T_SUM_min / Te - 1e-9))
    for _ in range(1_000_000):
        T_SUM = n * Te
        t1_max = min(T_SUM - 1.5 * L / v_max, T_SUM - 6.0 * L / (a_max * T_SUM),
                     T_SUM / 2 - Te)
        k_max = int(math.floor(t1_max / Te + 1e-9))
        if k_max >= 1:
            T1 = Te * np.arange(1, k_max + 1)
            amp = np.abs(amplitude_table1("III", jerk_J1(L, T_SUM, T1, "III"), T1, T_SUM,
                                          2 * math.pi * f))
            return T_SUM, float(T1[int(np.argmin(amp))])
        n += 1
    raise RuntimeError("no feasible Sato profile")  # pragma: no cover


@dataclass
class PeerSpec:
    """How one peer was built (for the table header and the CSV).

    Attributes
    ----------
    name : str
    tuned_to : str
        Human-readable tuning.
    params : dict
        The numbers.
    """

    name: str
    tuned_to: str
    params: dict[str, Any] = field(default_factory=dict)


def base_motion(sc: Any, profile: str, T_F: float | None = None, distance: float | None = None,
                *, session: Any = None, fmu: Any = None, fmi_version: int = 2) -> PiecewiseJerk:
    """The generator's AL or JL profile of the scenario's move, as an exact motion.

    Parameters
    ----------
    sc : harness.scenario.Scenario
    profile : {"AL", "JL"}
    T_F : float, optional
        JL jerk time (s), all four stages.
    distance : float, optional
        Signed distance (m); default the scenario's.
    session : harness.cosim.Session, optional
        Plan with its excited axis (FMU or fast engine); otherwise through
        :func:`harness.fmu.runner.generate` with ``fmu`` / ``fmi_version``.
    fmu, fmi_version
        Generator FMU when no session is given (default: the scenario's).

    Returns
    -------
    PiecewiseJerk
        Rebuilt exactly from the samples, then :meth:`~PiecewiseJerk.simplified`
        (one breakpoint per stage boundary).
    """
    m, s = sc.move, sc.simulation
    params: dict[str, Any] = {
        "profile": {"AL": 1, "JL": 2}[profile], "Te": s.Te, "t_start": m.t_start, "x0": m.x0,
        "distance": m.distance if distance is None else float(distance), "v_max": m.v_max,
        "a_max": m.a_max, "d_max": m.d_max, "short_stage": s.short_stage}
    if profile == "JL":
        if T_F is None:
            raise ValueError("JL needs its jerk time T_F")
        params.update({f"T_F{i}": float(T_F) for i in range(1, 5)})
    if session is not None:
        ms = session.axis.sample(params)
        mot = PiecewiseJerk.from_samples(ms.t, ms.x, ms.v, ms.a, ms.j, name=profile,
                                         params=params)
    else:
        from ..fmu.runner import generate
        from .trajectory import from_fmu

        tr = generate(params, fmu=s.fmu if fmu is None else fmu, fmi_version=fmi_version)
        mot = from_fmu(tr, name=profile).to_motion()  # type: ignore[assignment]
    return mot.simplified()


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
        Subset of :data:`ALL_PEERS`.
    fmu, fmi_version
        Generator FMU for the AL and JL profiles when no session is given.
    session : harness.cosim.Session, optional
        Plans the AL / JL profiles and, for the time-varying shapers, the
        synchronised Z move; without it an FMU session is opened for the
        time-varying shapers.

    Returns
    -------
    dict
        ``name -> (motion, spec)``.
    """
    from .tv_shaper import design_for_scenario

    m, s = sc.move, sc.simulation
    peers = tuple(peers)
    unknown = [p for p in peers if p not in ALL_PEERS]
    if unknown:
        raise ValueError(f"unknown peer method(s) {unknown}; choose from {ALL_PEERS}")
    tm = sc.modemap.tuned
    z_end = sc.z.z0 + sc.z.distance
    f_end, zeta = float(tm.f(z_end)), float(tm.zeta)
    sign = 1.0 if m.distance > 0 else -1.0
    out: dict[str, tuple[Motion, PeerSpec]] = {}
    own = None
    if session is None and any("TV-" in p for p in peers):
        from ..cosim import Session

        own = session = Session(s.fmu if fmu is None else fmu, fmi_version)
    kw = {"session": session, "fmu": fmu, "fmi_version": fmi_version}
    bases: dict[str, PiecewiseJerk] = {}

    def base(profile: str) -> PiecewiseJerk:
        if profile not in bases:
            bases[profile] = base_motion(sc, profile, T_F_JL, **kw)
        return bases[profile]

    mode_txt = f"{f_end:.4g} Hz, zeta = {zeta:g} (mode at the end of the motion)"
    try:
        for p in peers:
            if p == "time-optimal JL":
                j_max = m.a_max / T_F_JL
                r = time_optimal(m.distance, m.v_max, m.a_max, j_max, d_max=m.d_max)
                mot = _placed(r.motion(name=p), m.t_start, m.x0)
                out[p] = (mot, PeerSpec(p, f"limits v_max, a_max, d_max, j_max = a_max/T_F(JL) "
                                           f"= {j_max:.4g} m/s3 (not tuned)",
                                        {"j_max": j_max, "T_opt": r.duration}))
            elif p == "Sato III":
                T_SUM, T1 = sato_design(m.distance, m.v_max, min(m.a_max, m.d_max), f_end, s.Te,
                                        motion_time_JL)
                prof = sato_profile(abs(m.distance), T_SUM, T1, "III")
                mot = _placed(prof.motion(name=p), m.t_start, m.x0, sign)
                out[p] = (mot, PeerSpec(p, f"T_SUM = {T_SUM * 1e3:.0f} ms, T1 = {T1 * 1e3:.0f} ms "
                                           f"(eq. 28 minimised at {f_end:.4g} Hz)",
                                        {"T_SUM": T_SUM, "T1": T1, "f": f_end}))
            elif p.endswith("*TV-ZV"):
                prof = p[:2]
                des = design_for_scenario(
                    sc, session,
                    lambda d, prof=prof: base_motion(sc, prof, T_F_JL, d, **kw), name=p)
                sh = des.shaper
                d0 = float(sh.delay(des.base.t_start)[()])
                d1 = float(sh.delay(des.base.t_end)[()])
                jl_txt = f"JL T_F {T_F_JL * 1e3:.0f} ms; " if prof == "JL" else ""
                out[p] = (des.motion, PeerSpec(
                    p, f"{jl_txt}tuned mode f(z(t)) along the synchronised Z move, zeta = "
                       f"{zeta:g}; delay {d0 * 1e3:.1f} -> {d1 * 1e3:.1f} ms; {prof} planned for "
                       f"{des.distance_correction * 1e3:+.3g} mm so that the shaped move ends "
                       "on the target",
                    {"zeta": zeta, "rule": sh.rule, "delay_start": d0, "delay_end": d1,
                     "distance_correction": des.distance_correction,
                     "iterations": des.iterations, "sync_mismatch": des.sync_mismatch}))
            elif p[:3] in ("AL*", "JL*"):
                sh = make_shaper(p[3:], f_end, zeta)
                mot = shape(base(p[:2]), sh, name=p)
                jl_txt = f"JL T_F {T_F_JL * 1e3:.0f} ms; " if p[:2] == "JL" else ""
                out[p] = (mot, PeerSpec(p, f"{jl_txt}{mode_txt}; adds {sh.duration * 1e3:.0f} ms",
                                        {"f": f_end, "zeta": zeta, "A": sh.A.tolist(),
                                         "t": sh.t.tolist()}))
            else:  # damped jerk
                flt = DampedJerkFilter(f_end, zeta)
                mot = DampedJerkMotion.from_al(base("AL"), flt, name=p)
                out[p] = (mot, PeerSpec(p, f"{mode_txt}; jerk time {flt.T * 1e3:.0f} ms",
                                        {"f": f_end, "zeta": zeta, "T": flt.T}))
    finally:
        if own is not None:
            own.close()
    return out


# ------------------------------------------------------------ co-simulation


def cosimulate_reference(sc: Any, session: Any, motion: Motion, label: str,
                         t_stop: float | None = None) -> Any:
    """Step the Z generator FMU and the scenario's plant with a precomputed reference.

    The excited axis' FMU of :func:`harness.cosim.cosimulate` is replaced by
    the exact ``motion``; everything else is the same: the Z move
    (synchronised with the motion time when the scenario asks for it), the
    scheduled plant, the mode frozen over each communication step at the Z
    position of mid-step.  Within a step the plant's input is exact: the step
    is split at the motion's breakpoints (acceleration steps or jerk changes
    between samples, e.g. the delayed copies of an input shaper) and each
    piece is advanced with its own linear acceleration -- the plant's exact
    update.  For the FMU's profiles, whose jerk only changes at samples, this
    is what :func:`harness.cosim.cosimulate` does.

    Returns
    -------
    harness.cosim.CoSimResult
    """
    from ..cosim import CoSimResult
    from ..plant import ScheduledPlant

    sim = sc.simulation
    h = sim.step
    v_z, synced = session.z_velocity(sc, motion.motion_time)
    zp = session.z_move_params(sc, v_z)
    T_z = session.z_axis.plan(zp)
    if t_stop is None:
        t_stop = sc.move.t_start + max(motion.motion_time, T_z) + sim.t_after
    n = int(math.ceil(t_stop / h - 1e-9))
    ref = motion.sample(h, t_stop=n * h)
    t = ref.t
    # sub-intervals: communication points plus the motion's breakpoints in between
    bp = motion.breakpoints()
    bp = bp[(bp > t[0]) & (bp < t[-1])]
    inner = np.searchsorted(t, bp, side="right") - 1  # step index of each breakpoint
    cuts: dict[int, list[float]] = {}
    for k, b in zip(inner.tolist(), bp.tolist(), strict=True):
        if b > t[k]:
            cuts.setdefault(k, []).append(b)
    a_end = ref.a + ref.j * h  # acceleration at the end of each step (jerk constant per step)
    sub: dict[int, list[tuple[float, float, float]]] = {}
    for k, bs in cuts.items():
        edges = [float(t[k]), *bs, float(t[k + 1])]
        ar = motion.evaluate(edges[:-1], side="right")[2]
        al = motion.evaluate(edges[1:], side="left")[2]
        sub[k] = [(e1 - e0, float(u0), float(u1)) for e0, e1, u0, u1 in
                  zip(edges[:-1], edges[1:], ar, al, strict=True) if e1 > e0]
    Za = _z_samples(session, n, h)
    plant = ScheduledPlant(sc.modemap.scheduled())
    pstep = plant.step
    a = ref.a.tolist()
    a1 = a_end.tolist()
    z, vz = Za[:, 0].tolist(), Za[:, 1].tolist()
    E = [0.0]
    S = [tuple(plant.state)]
    half = 0.125 * h
    t0 = time.perf_counter()
    for k in range(n):
        zm = 0.5 * (z[k] + z[k + 1]) + half * (vz[k] - vz[k + 1])
        pieces = sub.get(k)
        if pieces is None:
            e = pstep(h, a[k], a1[k], zm)
        else:
            for hh, u0, u1 in pieces:
                e = pstep(hh, u0, u1, zm)
        E.append(e)
        S.append(tuple(plant.state))
    wall = time.perf_counter() - t0
    Sa = np.asarray(S, dtype=float)
    nm = len(plant.modes)
    t_end = motion.t_end
    k_end = min(n, int(math.ceil(t_end / h - 1e-9)))
    f = np.vstack([md.f_array(Za[:, 0]) for md in plant.modes])
    return CoSimResult(
        profile=label, t=t, x=ref.x, v=ref.v, a=ref.a, j=ref.j, z=Za[:, 0], v_z=Za[:, 1],
        eps=np.asarray(E), eps_modes=Sa[:, 0::2].T.copy(), f=f, t_start=motion.t_start,
        t_end=t_end, z_t_end=float(session.z_axis.get("t_start")) + T_z, x0=sc.move.x0,
        target=sc.move.x0 + sc.move.distance,
        state_end=[(float(Sa[k_end, 2 * i]), float(Sa[k_end, 2 * i + 1])) for i in range(nm)],
        modes_end=[md.at(float(Za[k_end, 0])) for md in plant.modes], N_F=(0, 0, 0, 0),
        Te=sim.Te, step=h, z_v_max=v_z, z_synced=synced,
        fmi_version=session.z_axis.fmi_version, engine=getattr(session, "engine", "fmu"),
        wall_time=wall, final_state=list(plant.state),
        final_modes=[md.at(float(Za[-1, 0])) for md in plant.modes],
    )


def _z_samples(session: Any, n: int, h: float) -> np.ndarray:
    """Z position and velocity at the n + 1 communication points (session planned).

    Engine ``"fmu"``: the Z generator FMU stepped through fmpy; ``"fast"``: the
    same samples from the compiled engine in one call.
    """
    from ..fmu.runner import FMUError

    if getattr(session, "engine", "fmu") == "fast":
        ax = session.z_axis
        m = int(round(h / ax.planned.Te))
        return ax.samples(0, m, n + 1)[:2].T.copy()
    gz = session.z_axis.g
    getz = gz.fmu.getFloat64 if gz.fmi_version == 3 else gz.fmu.getReal
    stepz = gz.fmu.doStep
    vrz = gz.vr(["x", "v"])
    Z = [list(getz(vrz))]
    from fmpy.fmi1 import FMICallException

    try:
        for k in range(n):
            stepz(k * h, h)
            Z.append(getz(vrz))
    except FMICallException as e:
        raise FMUError(str(getattr(e, "function", "doStep")), int(e.status), gz.log) from None
    gz.time = n * h
    return np.asarray(Z, dtype=float)


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
    metrics : harness.cosim.ProfileMetrics
        Residual, free amplitude, motion time, rise and settling time (same band for all).
    run : harness.cosim.CoSimResult
    peaks : dict
        Largest |v|, |a|, |j| of the reference.
    params : dict
    """

    name: str
    tuned_to: str
    metrics: Any
    run: Any
    peaks: dict[str, float]
    params: dict[str, Any] = field(default_factory=dict)


@dataclass
class PeerComparison:
    """Every method on one scenario.

    Attributes
    ----------
    scenario : harness.scenario.Scenario
    methods : dict of str to MethodOutcome
        AL, JL, DJL then the peers.
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

    def rows(self) -> list[dict[str, Any]]:
        """One dict per method (the CSV rows)."""
        ref = self.methods["AL"].metrics
        sc = self.scenario
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
                "v_peak_over_v_max": mo.peaks["v"] / sc.move.v_max,
                "a_peak_over_a_max": mo.peaks["a"] / max(sc.move.a_max, sc.move.d_max),
                "j_peak_m_s3": mo.peaks["j"],
                "f_tuned_Hz": self.f_end, "zeta": self.zeta,
            })
        return out

    def table(self) -> str:
        """Format the table: motion time, ratio to time-optimal, residual, settling."""
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
        head = (f"{'method':<16}{'motion [s]':>11}{'/ t.-opt.':>10}{'residual [mm]':>15}"
                f"{'% of AL':>9}{'settling [s]':>14}{'v/v_max':>9}{'a/a_max':>9}")
        lines += [head, "-" * len(head)]
        for r in self.rows():
            st = r["settling_time_s"]
            lines.append(
                f"{r['method']:<16}{r['motion_time_s']:>11.3f}"
                f"{r['motion_time_over_time_optimal']:>10.3f}"
                f"{r['residual_m'] * 1e3:>15.4g}{r['residual_pct_of_AL']:>8.1f}%"
                f"{(f'{st:.3f}' if math.isfinite(st) else 'never'):>14}"
                f"{r['v_peak_over_v_max']:>9.2f}{r['a_peak_over_a_max']:>9.2f}")
        lines.append("")
        lines.append(f"Settling band +/-{self.band * 1e3:.3g} mm ({self.band_source}); "
                     "residual: free-oscillation amplitude when the reference ends.")
        for mo in self.methods.values():
            if mo.name not in BASE:
                lines.append(f"  {mo.name}: {mo.tuned_to}")
        return "\n".join(lines)

    def to_csv(self, path: Any) -> Any:
        """Write :meth:`rows` as CSV; return the path (robustness: :meth:`robustness_rows`)."""
        from ..results import write_csv

        return write_csv(path, self.rows())

    def robustness_rows(self) -> list[dict[str, Any]]:
        """Return the robustness curves as rows (error, method, residual, % of AL)."""
        rc = self.robustness
        pc = rc.percent()
        return [{"scenario": self.scenario.name, "frequency_error": float(e),
                 "f_Hz": rc.f_tuned * (1 + float(e)), "method": k,
                 "residual_m": float(rc.residual[k][i]), "residual_pct_of_AL": float(pc[k][i])}
                for k in rc.residual for i, e in enumerate(rc.error)]

    def plot(self, title: str | None = None):
        """Residual against the mode-frequency error, one curve per method; return the Figure."""
        import matplotlib.pyplot as plt

        rc = self.robustness
        fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(13, 4.8))
        pc = rc.percent()
        styles = {"AL": ("0.45", "-"), "JL": ("tab:blue", "-"), "DJL": ("tab:red", "-")}
        for k in rc.residual:
            c, ls = styles.get(k, (None, "--"))
            ax1.plot(100 * rc.error, pc[k], color=c, ls=ls, label=k)
            ax2.semilogy(100 * rc.error, np.maximum(rc.residual[k] * 1e3, 1e-9), color=c,
                         ls=ls, label=k)
        ax1.set_ylim(0, 60)
        ax1.set_ylabel("residual [% of AL at the same frequency]")
        ax2.set_ylabel("residual amplitude [mm]")
        for ax in (ax1, ax2):
            ax.set_xlabel(f"mode frequency error [%] around {rc.f_tuned:.3g} Hz")
            ax.grid(True, alpha=0.3)
        ax2.axhline(self.band * 1e3, color="gold", lw=2, label="settling band")
        ax2.legend(fontsize="small", ncol=2)
        fig.suptitle(title or f"Scenario {self.scenario.name}: robustness to the mode "
                     f"frequency (stationary mode, zeta = {rc.zeta:g}; methods as planned for "
                     "the scenario)")
        fig.tight_layout()
        return fig

    def html(self) -> str:
        """Return an HTML fragment (table and robustness figure, PNG embedded) for a report."""
        import base64
        import html as _html
        import io

        import matplotlib.pyplot as plt

        fig = self.plot()
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
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(2, 1, figsize=(11, 7), sharex=True)
        for n, mo in self.methods.items():
            r = mo.run
            axes[0].plot(r.t, r.a, lw=1, label=n)
            axes[1].plot(r.t, r.eps * 1e3, lw=1, label=n)
        axes[1].axhspan(-self.band * 1e3, self.band * 1e3, color="gold", alpha=0.35, lw=0)
        zoom = max(mo.metrics.residual for n, mo in self.methods.items() if n != "AL")
        axes[1].set_ylim(-3e3 * max(zoom, self.band), 3e3 * max(zoom, self.band))
        axes[0].set_ylabel("a [m/s²]")
        axes[1].set_ylabel("ε [mm] (zoom)")
        axes[1].set_xlabel("t [s]")
        axes[0].legend(fontsize="small", ncol=4)
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


def compare_scenario(scenario: Any, *, session: Any = None, peers: Sequence[str] = PEERS,
                     errors: np.ndarray | None = None, engine: str = "fmu") -> PeerComparison:
    """Run AL / JL / DJL and the peers on one (non-sweep) scenario.

    Parameters
    ----------
    scenario : Scenario, str or Path
        A scenario (or an embedded name, or a TOML file) without ``[sweep]``.
    session : harness.cosim.Session, optional
        Generator instances to reuse.
    peers : sequence of str
        Subset of :data:`PEERS`.
    errors : ndarray, optional
        Relative frequency errors of the robustness curves (default -40 % .. +40 %).
    engine : {"fmu", "fast"}
        Engine of the session made when ``session`` is not given (see
        :class:`harness.cosim.Session`).

    Returns
    -------
    PeerComparison
    """
    from ..cosim import Session, profile_metrics, run_case
    from ..scenario import Scenario, load_scenario

    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    if sc.is_sweep:
        raise ValueError(f"{sc.name}: compare takes single-move scenarios, not sweeps")
    sc = dataclasses.replace(sc, compare=dataclasses.replace(sc.compare, profiles=BASE))
    own = session is None
    if own:
        session = Session(sc.simulation.fmu, sc.simulation.fmi_version, engine=engine)
    try:
        base = run_case(sc, session)
        band = base.band
        jl = base.profiles["JL"]
        built = build_peers(sc, jl.T_F[0], jl.metrics.motion_time, peers=peers,
                            fmi_version=sc.simulation.fmi_version)
        methods: dict[str, MethodOutcome] = {}
        motions: dict[str, Motion | SampledTrajectory] = {}
        for n in BASE:
            p = base.profiles[n]
            st = _run_samples(p.run, n)
            methods[n] = MethodOutcome(n, "harness" if n == "AL" else
                                       ("T_F " + "/".join(f"{x * 1e3:.0f}" for x in
                                                          (p.T_F[:1] if n == "JL" else p.T_F))
                                        + " ms"), p.metrics, p.run, st.peaks())
            motions[n] = st
        for n, (mot, spec) in built.items():
            st = mot.sample(sc.simulation.Te)
            run = cosimulate_reference(sc, session, mot, n)
            methods[n] = MethodOutcome(n, spec.tuned_to, profile_metrics(run, band), run,
                                       st.peaks(), spec.params)
            motions[n] = mot
    finally:
        if own:
            session.close()
    tm = sc.modemap.tuned
    f_end, zeta = float(tm.f(sc.z.z0 + sc.z.distance)), float(tm.zeta)
    m = sc.move
    T_opt = time_optimal(m.distance, m.v_max, m.a_max, m.a_max / base.profiles["JL"].T_F[0],
                         d_max=m.d_max).duration
    err = np.linspace(-0.4, 0.4, 81) if errors is None else np.asarray(errors, dtype=float)
    rc = robustness_curve(motions, f_end, zeta, err, reference="AL")
    return PeerComparison(sc, methods, band, base.band_source, T_opt, f_end, zeta, rc, base)
