"""Claim 7: DJL stage filters against the moving mode (000 §2.3, §3.2, §4).

Paper's side: DJL gives each constant-jerk stage its own moving average,
whose first notch ``1/T_Fi`` is tuned to the mode "at its time-dependent
frequency value" (§3.2), i.e. the modal period where the stage starts; the
method assumes "the variation of modal frequency during one constant jerk
stage is negligible" and §3.2 quantifies it: residual below 5 % of AL when the
frequency varies by less than ±9 % during the stage.  §4-5: DJL reduces the
residual vibration compared with JL tuned to the end of the motion.

Product's side: the harness's embedded default scenarios X and Y
(:mod:`harness.scenario`) run through its co-simulation
(:class:`harness.simulation.session.Session`: two generator FMUs through fmpy, the Z axis
moving the mode, the DJL jerk times tuned from the mode map by
:mod:`harness.tuning`).  The Bode of the flexible axis at the Z position of
each stage start is overlaid with that stage's moving-average notch.  The
co-simulated deflection is split, by linearity, into the contribution of each
constant-jerk stage (each stage's acceleration ramp simulated alone on the
same scheduled mode, :func:`harness.plant.simulate_mode`); the residual a
stage leaves is its free-oscillation amplitude at the stage end, relative to
an acceleration step of the same size at the stage start on the same moving
mode (the AL level).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..plant import Mode, free_amplitude, hermite_mid, simulate_mode
from ..scenario import load_scenario
from ..simulation.session import Session
from ..tuning.tune import tune_profile
from . import formulas as fm
from .base import Check, ClaimResult, Settings, Table, register
from .signals import db

TITLE = "DJL stage filters against the moving mode"
SOURCE = ("Béarée & Olabi 2013, §2.3 (eq. 11-16, Fig. 7), §3.2 and §4 (Fig. 14-16, Table 1); "
          "harness default scenarios X and Y")
STATEMENT = (
    "'The main idea ... consists of using a DJ profile with potentially four different jerk "
    "times. Each constant jerk stage can be tuned to cancel the vibration mode at its "
    "time-dependent frequency value. The method is based on the main hypothesis that the "
    "variation of modal frequency during one constant jerk stage is negligible.' (§3.2) "
    "'Residual vibration level would be kept below 5 % ... if the variation of omega(t) is "
    "less than ±9 % during one constant jerk stage.' 'DJL profiles verify a superior "
    "potential of vibration reduction compared to JL profile' (§4).")

SCENARIOS = ("X", "Y")


@dataclass
class StageResidual:
    """One constant-jerk stage (a run of constant jerk) of a co-simulated move."""

    label: str
    t_start: float
    duration: float
    jerk: float
    f_start: float
    f_end: float
    moving: float
    frozen: float

    @property
    def variation(self) -> float:
        """Relative change of the mode frequency during the stage."""
        return self.f_end / self.f_start - 1.0


@dataclass
class ScenarioStages:
    """Claim 7 data for one scenario."""

    name: str
    description: str
    zeta: float
    Te: float
    T_F: tuple[float, ...]
    instants: tuple[float, ...]
    z: tuple[float, ...]
    periods: tuple[float, ...]
    merged: bool
    converged: bool
    djl: list[StageResidual]
    jl: list[StageResidual]
    T_F_jl: float
    superposition_err: float
    synthesis_err: float
    amp_djl: float
    amp_jl: float
    djl_undamped: list[StageResidual]
    t: np.ndarray = field(repr=False)
    f: np.ndarray = field(repr=False)

    def plot(self):
        """Bode of the axis at each stage start with the stage notches; f(t) and residuals."""
        import control as ct  # deferred: python-control is heavy to import
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        fig, axes = plt.subplots(1, 2, figsize=(13, 4.6))
        ax = axes[0]
        f = np.geomspace(1.0, 60.0, 1500)
        w = 2 * np.pi * f
        colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
        systems, labels = [], []
        for i, (zi, Ti) in enumerate(zip(self.z, self.periods, strict=True)):
            wi = 2 * np.pi / Ti
            systems.append(ct.tf([2 * self.zeta * wi, wi**2], [1, 2 * self.zeta * wi, wi**2]))
            labels.append(f"axis at z = {zi:.3f} m ({1 / Ti:.2f} Hz), stage {i + 1}")
        ct.bode_plot(systems, omega=w, ax=np.array([[ax]]), plot_phase=False, dB=True, Hz=True,
                     label=labels, title="")
        for i, T_F in enumerate(self.T_F):
            ax.plot(f, db(fm.ma_continuous(f, T_F)), "--", lw=1, color=colors[i % len(colors)],
                    label=f"stage {i + 1} moving average, T_F = {T_F * 1e3:.0f} ms")
            ax.plot([1 / T_F], [-60], "v", color=colors[i % len(colors)], ms=6)
        ax.set_ylim(-60, 30)
        ax.legend(fontsize="xx-small", loc="lower left")
        ax.set_title(f"Scenario {self.name}: flexible axis (q+ε)/q at each DJL stage start, "
                     "stage notches", fontsize="small")

        ax = axes[1]
        ax.plot(self.t, self.f, color="k", lw=1.2, label="mode frequency f(z(t))")
        for i, s in enumerate(self.djl):
            ax.axvspan(s.t_start, s.t_start + s.duration, color=colors[i % len(colors)],
                       alpha=0.15)
            ax.text(s.t_start + s.duration / 2, ax.get_ylim()[0], s.label, ha="center",
                    va="bottom", fontsize="x-small")
        t_max = max(s.t_start + s.duration for s in self.djl + self.jl) + 0.1
        ax.set_xlim(0, t_max)
        ax.set_xlabel("t [s]")
        ax.set_ylabel("f [Hz]")
        ax2 = ax.twinx()
        x_d = [s.t_start + s.duration for s in self.djl]
        x_j = [s.t_start + s.duration for s in self.jl]
        ax2.plot(x_d, [100 * s.moving for s in self.djl], "o", color="tab:red",
                 label="DJL stage residual (moving mode)")
        ax2.plot(x_d, [100 * s.frozen for s in self.djl], "x", color="tab:red",
                 label="DJL, eq. (20) with the mode frozen at the stage start")
        ax2.plot(x_j, [100 * s.moving for s in self.jl], "s", mfc="none", color="tab:blue",
                 label=f"JL (T_F = {self.T_F_jl * 1e3:.0f} ms) stage residual")
        ax2.set_ylabel("residual left by the stage [% of AL]")
        ax2.set_ylim(0, None)
        h1, l1 = ax.get_legend_handles_labels()
        h2, l2 = ax2.get_legend_handles_labels()
        ax.legend(h1 + h2, l1 + l2, fontsize="xx-small", loc="upper right")
        ax.set_title(f"Scenario {self.name}: stages (shaded) on the moving mode",
                     fontsize="small")
        fig.tight_layout()
        return fig


def filtered_steps(a_AL: np.ndarray, N_F: tuple[int, ...]) -> list[tuple[int, int, float]]:
    """Return the four filtered acceleration steps of a rest-to-rest JL / DJL move (Fig. 7).

    Each step of the FMU's adapted AL acceleration ``a_AL`` starts one
    constant-jerk stage, filtered by its own moving average of ``N_F[i]``
    samples (eq. 11); a direct jump from acceleration to deceleration starts
    stages 2 and 3 together.

    Returns
    -------
    list of (first sample, taps, step size in m/s²)
    """
    a = np.r_[0.0, a_AL]
    ks = np.flatnonzero(np.diff(a) != 0.0)
    out: list[tuple[int, int, float]] = []
    prev = 0.0
    for k in ks.tolist():
        lv = float(a[k + 1])
        if prev > 0.0 > lv or prev < 0.0 < lv:
            out += [(k, 0, -prev), (k, 0, lv)]
        else:
            out.append((k, 0, lv - prev))
        prev = lv
    if len(out) != 4:
        raise ValueError(f"expected the 4 stages of a rest-to-rest move, found {len(out)} steps")
    return [(k, int(N_F[i]), d) for i, (k, _, d) in enumerate(out)]


def ramp(n_samples: int, k0: int, N: int, step: float) -> np.ndarray:
    """Return the samples of a step ``step`` at sample ``k0`` through an N-tap moving average."""
    k = np.arange(n_samples)
    return step * np.clip((k - k0) / N, 0.0, 1.0)


def stage_residuals(t: np.ndarray, steps: list[tuple[int, int, float]], f_mid: np.ndarray,
                    f_at: np.ndarray, zeta: float, gain: float,
                    groups: list[tuple[str, list[int]]]
                    ) -> tuple[list[StageResidual], np.ndarray, np.ndarray]:
    """Residual each constant-jerk stage leaves on the scheduled mode, stage alone.

    Parameters
    ----------
    t : ndarray
        Sample times of the co-simulation (s), one per generator sample.
    steps : list of (first sample, taps, step)
        The filtered steps (:func:`filtered_steps`).
    f_mid : ndarray
        Mode frequency applied over each interval (Hz), as the co-simulation did.
    f_at : ndarray
        Mode frequency at each sample (Hz).
    zeta, gain : float
        Damping ratio and participation factor of the mode.
    groups : list of (label, step indices)
        The stages: one filtered step each, or the two middle steps together when
        they form one constant-jerk stage (no constant-velocity stage, §4).

    Returns
    -------
    stages : list of StageResidual
    a_sum : ndarray
        Sum of the stage ramps (the profile's acceleration, eq. 11).
    eps_sum : ndarray
        Sum of the stage responses: by linearity, the co-simulated deflection.
    """
    mode = Mode(float(f_mid[0]), zeta, gain)
    a_sum = np.zeros(t.size)
    eps_sum = np.zeros(t.size)
    out = []
    h = float(t[1] - t[0])
    for label, idx in groups:
        a_i = sum(ramp(t.size, steps[i][0], steps[i][1], steps[i][2]) for i in idx)
        k0 = min(steps[i][0] for i in idx)
        ke = min(max(steps[i][0] + steps[i][1] for i in idx), t.size - 1)
        step = sum(steps[i][2] for i in idx)
        a_sum += a_i
        resp = simulate_mode(t, a_i, mode, f=f_mid)
        eps_sum += resp.eps
        # the AL reference: the whole step unfiltered at the stage start (sampled, it rises
        # over the one interval before t_k0: within 1e-4 of an ideal step here)
        ref = simulate_mode(t, ramp(t.size, k0, 1, step), mode, f=f_mid)
        m_end = Mode(float(f_at[ke]), zeta, gain)
        ss = -gain * step / m_end.omega**2
        amp = free_amplitude(resp.eps[ke] - ss, resp.deps[ke], m_end)
        amp_al = free_amplitude(ref.eps[ke] - ss, ref.deps[ke], m_end)
        duration = (ke - k0) * h
        frozen = float(fm.vib_jerk_stage(duration, 2 * np.pi * float(f_at[k0]), zeta))
        out.append(StageResidual(label, float(t[k0]), duration, step / duration,
                                 float(f_at[k0]), float(f_at[ke]), amp / amp_al, frozen))
    return out, a_sum, eps_sum


def _f_mid(run, spec) -> np.ndarray:
    """Frequency of the tuned mode per interval, as the co-simulation applied it."""
    z, vz, h = run.z, run.v_z, run.step
    law = spec.scheduled().f_of_z
    return np.array([law(hermite_mid(z[k], vz[k], z[k + 1], vz[k + 1], h))
                     for k in range(z.size - 1)])


def analyse_scenario(settings: Settings, name: str) -> ScenarioStages:
    """Tune and co-simulate DJL and JL for one default scenario; split into stages."""
    sc = load_scenario(name)
    if settings.fmu is not None or settings.fmi_version != sc.simulation.fmi_version:
        sc = sc.with_fmu(None if settings.fmu is None else Path(settings.fmu),
                         settings.fmi_version)
    spec = sc.modemap.tuned
    i_mode = sc.modemap.tune
    with Session(sc.simulation.fmu, sc.simulation.fmi_version) as s:
        tu = tune_profile(s, sc, "DJL")
        run = s.run(sc, "DJL", tu.T_F)
        mv = s.axis.sample(Session.move_params(sc, "DJL", tu.T_F), t_stop=float(run.t[-1]))
        tj = tune_profile(s, sc, "JL")
        run_jl = s.run(sc, "JL", tj.T_F)
        mv_jl = s.axis.sample(Session.move_params(sc, "JL", tj.T_F), t_stop=float(run_jl.t[-1]))
    if abs(run.step - sc.simulation.Te) > 1e-15:
        raise ValueError("claim 7 needs the communication step equal to Te")
    out = {}
    for key, r, m in (("DJL", run, mv), ("JL", run_jl, mv_jl)):
        f_mid = _f_mid(r, spec)
        steps = filtered_steps(m.a_AL, m.N_F)
        contiguous = steps[2][0] == steps[1][0] + steps[1][1]
        groups = ([("1", [0]), ("2+3", [1, 2]), ("4", [3])] if tu.merged and contiguous
                  else [(str(i + 1), [i]) for i in range(4)])
        stages, a_sum, eps_sum = stage_residuals(r.t, steps, f_mid, r.f[i_mode], spec.zeta,
                                                 spec.gain, groups)
        undamped, _, _ = stage_residuals(r.t, steps, f_mid, r.f[i_mode], 0.0, spec.gain,
                                         groups)
        eps = r.eps_modes[i_mode]
        out[key] = (stages, undamped,
                    float(np.max(np.abs(a_sum - r.a)) / np.max(np.abs(r.a))),
                    float(np.max(np.abs(eps_sum - eps)) / np.max(np.abs(eps))), f_mid)
    djl, djl0, err_a, err_eps, f_mid = out["DJL"]
    jl = out["JL"][0]
    amp_d = free_amplitude(*run.state_end[i_mode], run.modes_end[i_mode])
    amp_j = free_amplitude(*run_jl.state_end[i_mode], run_jl.modes_end[i_mode])
    return ScenarioStages(
        name=name, description=sc.description, zeta=spec.zeta, Te=sc.simulation.Te,
        T_F=tuple(tu.T_F), instants=tuple(tu.instants), z=tuple(tu.z),
        periods=tuple(tu.periods), merged=tu.merged, converged=tu.converged, djl=djl, jl=jl,
        T_F_jl=float(tj.T_F[0]), superposition_err=max(err_eps, out["JL"][3]),
        synthesis_err=max(err_a, out["JL"][2]), amp_djl=amp_d, amp_jl=amp_j,
        djl_undamped=djl0, t=run.t[:-1], f=f_mid)


@dataclass
class DJLStagesAnalysis:
    """Claim 7 data: one entry per default scenario."""

    scenarios: list[ScenarioStages]

    def plot(self):
        """One figure per scenario (the first)."""
        return self.scenarios[0].plot()


@register(7, TITLE)
def run(settings: Settings) -> ClaimResult:
    """Run claim 7."""
    ana = DJLStagesAnalysis([analyse_scenario(settings, n) for n in SCENARIOS])
    checks: list[Check] = []
    tables: list[Table] = []
    for sc in ana.scenarios:
        Te = sc.Te
        dev = []
        for i, (T_F, P) in enumerate(zip(sc.T_F, sc.periods, strict=True)):
            target = sc.T_F[1] if (sc.merged and i == 2) else P
            dev.append(abs(T_F - target))
        checks.append(Check.below(
            f"{sc.name}: each stage's notch 1/T_Fi at the mode frequency where the stage starts "
            "(|T_Fi - modal period| worst, merged middle stages share T_F2)", max(dev),
            Te / 2 + 1e-12, expected=0.0, unit="s",
            note="tolerance: rounding of the jerk times to whole samples; tuning "
                 f"{'converged' if sc.converged else 'NOT converged'}"))
        checks.append(Check.below(
            f"{sc.name}: FMU acceleration vs the sum of its four filtered steps (eq. 11, "
            "Fig. 7), DJL and JL, max difference / a_max", sc.synthesis_err, 1e-12,
            expected=0.0, note="steps read from the FMU's a_AL, each through its own "
                               "moving average of N_Fi samples"))
        checks.append(Check.below(
            f"{sc.name}: sum of the per-stage responses vs the co-simulated deflection (max "
            "difference / peak)", sc.superposition_err, 1e-9, expected=0.0,
            note="linearity: the stages' residuals below are those of the co-simulation"))
        pairs = [(s, s0) for s, s0 in zip(sc.djl, sc.djl_undamped, strict=True)
                 if abs(s.variation) <= 0.09]
        if pairs:
            worst, worst0 = max(pairs, key=lambda p: p[1].moving)
            checks.append(Check.below(
                f"{sc.name}: largest residual a DJL stage leaves because the mode moves "
                f"(zeta = 0), stages varying by less than ±9 % ({len(pairs)} of "
                f"{len(sc.djl)})", worst0.moving, 0.05, kind="paper",
                note=f"stage {worst0.label}: variation {worst0.variation:+.1%}; with the "
                     f"scenario's damping zeta = {sc.zeta:g} the stage leaves "
                     f"{worst.moving:.1%} (frozen-mode eq. (20): {worst.frozen:.1%})"))
        checks.append(Check.below(
            f"{sc.name}: DJL free-oscillation amplitude at the end of the motion / JL's "
            f"(JL tuned to the end period, T_F = {sc.T_F_jl * 1e3:.0f} ms)",
            sc.amp_djl / sc.amp_jl, 1.0, kind="paper",
            note=f"DJL {sc.amp_djl * 1e3:.4f} mm, JL {sc.amp_jl * 1e3:.4f} mm"))
        tables.append(Table(
            f"Scenario {sc.name}: {sc.description}. DJL jerk times "
            + "/".join(f"{x * 1e3:.0f}" for x in sc.T_F) + " ms"
            + (" (middle stages merged)" if sc.merged else ""),
            ["profile", "stage", "start [s]", "T_F [ms]", "step [m/s²]", "f at start [Hz]",
             "f at end [Hz]", "variation", "residual (moving mode) / AL",
             "same, zeta = 0", "eq. (20), frozen at start"],
            [["DJL", s.label, s.t_start, s.duration * 1e3, s.jerk * s.duration, s.f_start,
              s.f_end, f"{s.variation:+.2%}", s.moving, s0.moving, s.frozen]
             for s, s0 in zip(sc.djl, sc.djl_undamped, strict=True)]
            + [["JL", s.label, s.t_start, s.duration * 1e3, s.jerk * s.duration, s.f_start,
                s.f_end, f"{s.variation:+.2%}", s.moving, "", s.frozen] for s in sc.jl]))
        tables.append(Table(
            f"Scenario {sc.name}: DJL tuning (harness.tuning, rule 'start')",
            ["stage", "start [s]", "z [m]", "modal period [ms]", "T_F applied [ms]",
             "1/T_F [Hz]"],
            [[i + 1, t0, z, P * 1e3, T * 1e3, 1 / T] for i, (t0, z, P, T) in
             enumerate(zip(sc.instants, sc.z, sc.periods, sc.T_F, strict=True))]))
    method = (
        "The harness's default scenarios X and Y (embedded TOML) are tuned and co-simulated "
        "with harness.simulation.session.Session (generator FMUs through fmpy, Z axis moving "
        "the mode). "
        "Bode: (q+eps)/q = (2 zeta w s + w^2)/(s^2 + 2 zeta w s + w^2) at the mode frequency of "
        "each stage start, with |F_i| = |sinc(f T_Fi)|. Stage residuals: the DJL (and JL) "
        "acceleration is split into its four filtered steps (eq. 11, Fig. 7: each step of "
        "the FMU's a_AL through its own moving average; ramps may overlap, as in X's "
        "deceleration with the paper's short-stage rule); each ramp alone is simulated on the "
        "scheduled mode with the frequencies the co-simulation applied; its free amplitude "
        "at the ramp end, about -a/omega^2, is divided by that of the unfiltered step on the "
        "same moving mode (the AL level). 'zeta = 0' isolates the effect of the moving mode "
        "(the paper's §3.2 statement); eq. (20) frozen at the stage start is what the tuning "
        "assumes (damping alone).")
    figs = [sc.plot() for sc in ana.scenarios]
    return ClaimResult(7, TITLE, SOURCE, STATEMENT, method=method, checks=checks, figures=figs,
                       tables=tables, data=ana)
