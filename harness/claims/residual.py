"""Claim 3: residual vibration of jerk stages (Béarée & Olabi 2013, eq. 17-21, Fig. 11).

Paper's side: the closed forms (re-derived, see :mod:`.formulas`): a series of
jerk steps ``delta_j[i]`` at ``t_i`` leaves on the mode
``eps'' + 2 zeta omega eps' + omega^2 eps = -q''`` a free oscillation of
amplitude ``exp(-zeta omega T_n) |sum delta_j[i] exp(zeta omega t_i) exp(j omega_d t_i)|
/ (omega^2 omega_d)`` (eq. 17-18); one stage of jerk time ``T_F`` leaves
eq. (20) / (``omega a_max``) of the acceleration-limited level
``a_max / (omega omega_d)``, which is ``|sinc(omega T_F / 2)|`` undamped
(eq. 21).

Product's side: the FMU's JL / DJL profiles (fmpy) drive the harness's mode
(:func:`harness.plant.simulate_mode`, exact for a piecewise-linear
acceleration); the free-oscillation amplitude is read from the simulated
state (:func:`harness.plant.free_amplitude`) at the end of the stage (about
the quasi-static deflection ``-a/omega^2``) or of the move.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..plant import Mode, free_amplitude, simulate_mode
from . import formulas as fm
from .base import Check, ClaimResult, Settings, Table, dress, register

TITLE = "Residual vibration of jerk stages"
SOURCE = "Béarée & Olabi 2013, §3.1, eq. (17)-(21), Fig. 11"
STATEMENT = (
    r"$\mathrm{Vib}(\omega) = e^{-\zeta\omega T_n} \sqrt{\left(\sum A_i e^{\zeta\omega T_i} "
    r"\cos\omega_d T_i\right)^2 + \left(\sum A_i e^{\zeta\omega T_i} \sin\omega_d T_i"
    r"\right)^2}$ (eq. 18); for one jerk stage "
    r"$\mathrm{Vib} = \dfrac{a_{max}}{T_F} e^{-\zeta\omega T_F} \sqrt{1 + e^{2\zeta\omega T_F}"
    r" - 2 e^{\zeta\omega T_F} \cos\omega_d T_F}$ (eq. 20), and undamped 'residual vibration "
    "is a sine cardinal function of the jerk time' (eq. 21): zero when $T_F$ is a multiple "
    "of the natural period. 'In order to keep the residual vibration below 20 %, the tuning "
    "error also has to be lower than 20 %.' 'A damping value below 10 % has poor effect on "
    "the residual vibration level.' (Fig. 11: full scale = the acceleration-limited "
    "profile.)")

F_MODE = 10.0
"""Mode frequency of the checks (Hz): period 100 ms, a whole number of 1 ms samples."""

A_MAX = 10.0


@dataclass
class StagePoint:
    """Simulated residual of one jerk stage (relative to the AL level)."""

    ratio: float
    zeta: float
    T_F: float
    simulated: float
    formula: float


@dataclass
class MoveResidual:
    """Residual after a whole FMU move: simulation vs the jerk-series formula."""

    name: str
    zeta: float
    n_switch: int
    coefficients: str
    al_level: float
    simulated: float
    formula: float
    t: np.ndarray
    eps: np.ndarray


@dataclass
class ResidualAnalysis:
    """Claim 3 data."""

    f_mode: float
    ratios: np.ndarray
    zetas_map: np.ndarray
    stage_points: list[StagePoint]
    moves: list[MoveResidual]
    band_20: tuple[float, float]
    max_in_20pct: dict[float, tuple[float, float]]
    damping_effect: tuple[float, float]

    def plot(self):
        """Fig. 11 (formula curves + FMU/plant points), map, and move residuals."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        T = 1.0 / self.f_mode
        w = 2 * np.pi * self.f_mode
        fig, axes = plt.subplots(2, 2, figsize=(11, 8))
        ax = axes[0, 0]
        r = np.linspace(1e-3, 3.0, 1500)
        zs = sorted({p.zeta for p in self.stage_points} | {0.02, 0.2})
        for z in zs:
            line, = ax.plot(r, 100 * fm.vib_jerk_stage(r * T, w, z), lw=1.2,
                            label=f"eq. (20), ζ = {z:g}")
            pts = [p for p in self.stage_points if p.zeta == z]
            if pts:
                ax.plot([p.ratio for p in pts], [100 * p.simulated for p in pts], "o", ms=4,
                        mfc="none", color=line.get_color())
        ax.plot([], [], "ko", mfc="none", ms=4, label="FMU JL + harness mode (simulated)")
        ax.axhline(20, color="0.5", lw=0.8, ls="--")
        ax.axvspan(0.8, 1.2, color="tab:red", alpha=0.08, label="tuning error ±20 %")
        dress(ax, "jerk time / natural period, T_F / T", "residual [% of AL]",
              f"Fig. 11: one jerk stage, mode {self.f_mode:g} Hz")

        ax = axes[0, 1]
        zz = np.linspace(0.0, 0.3, 121)
        R, Z = np.meshgrid(r[::5], zz)
        V = fm.vib_jerk_stage(R * T, w, Z)
        pc = ax.pcolormesh(R, Z, 100 * V, shading="auto", cmap="viridis", vmin=0, vmax=100)
        cs = ax.contour(R, Z, 100 * V, levels=[5, 10, 20], colors="w", linewidths=0.8)
        ax.clabel(cs, fmt="%d %%", fontsize="x-small")
        fig.colorbar(pc, ax=ax, label="residual [% of AL]")
        ax.set_xlabel("T_F / T")
        ax.set_ylabel("damping ratio ζ")
        ax.set_title("Map of eq. (20): residual vs jerk time and damping")

        ax = axes[1, 0]
        for m in self.moves:
            if m.zeta == 0.0:
                ax.plot(m.t, m.eps * 1e3, lw=1, label=f"{m.name}: {100 * m.simulated:.2f} %")
        dress(ax, "t [s]", "ε [mm]",
              f"Deflection on the {self.f_mode:g} Hz mode (ζ = 0), FMU moves")

        ax = axes[1, 1]
        names = [f"{m.name}\nζ = {m.zeta:g}" for m in self.moves]
        x = np.arange(len(self.moves))
        ax.bar(x - 0.2, [100 * m.formula for m in self.moves], 0.4, label="eq. (17)-(18)")
        ax.bar(x + 0.2, [100 * m.simulated for m in self.moves], 0.4,
               label="simulated (FMU + plant)")
        ax.set_xticks(x, names, fontsize="xx-small", rotation=60, ha="right")
        ax.set_ylabel("residual after the move [% of AL]")
        ax.set_title("Whole moves: series of jerk steps")
        ax.legend(fontsize="x-small")
        ax.grid(True, axis="y", alpha=0.3)
        fig.tight_layout()
        return fig


def stage_residuals(settings: Settings, ratios: np.ndarray, zetas: tuple[float, ...],
                    f_mode: float = F_MODE, Te: float = 1e-3) -> list[StagePoint]:
    """Residual left by the FMU's first JL stage, for jerk times ``ratio * period``."""
    T = 1.0 / f_mode
    out = []
    for ratio in settings.progress_bar(ratios, "claim 3: jerk stages"):
        T_F = float(ratio) * T
        # long acceleration phase: the first stage ends on a constant acceleration
        tr = settings.generate({"profile": 2, "Te": Te, "distance": 50.0, "v_max": 10.0,
                                "a_max": A_MAX, "d_max": A_MAX, "T_F1": T_F},
                               t_stop=T_F + 5 * Te)
        N = int(tr.N_F[0])
        a_lvl = float(tr.a[N])
        T_F_applied = N * Te
        for z in zetas:
            mode = Mode(f_mode, z)
            resp = simulate_mode(tr.t, tr.a, mode)
            eps_ss = -a_lvl / mode.omega**2
            amp = free_amplitude(resp.eps[N] - eps_ss, resp.deps[N], mode)
            ref = fm.al_reference_amplitude(a_lvl, mode.omega, z)
            out.append(StagePoint(T_F_applied / T, z, T_F_applied, amp / ref,
                                  float(fm.vib_jerk_stage(T_F_applied, mode.omega, z))))
    return out


def _switches(j: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Jerk steps of a sampled jerk (constant per interval): times and jumps."""
    dj = np.diff(np.r_[0.0, j])
    k = np.nonzero(np.abs(dj) > 1e-9 * max(np.abs(j).max(), 1.0))[0]
    return t[k], dj[k]


MOVES: dict[str, dict[str, float]] = {
    "JL, T_F = 0.7 T": {"profile": 2, "T_F1": 0.07},
    "JL, T_F = T": {"profile": 2, "T_F1": 0.1},
    "JL, T_F = 2T": {"profile": 2, "T_F1": 0.2},
    "DJL 80/80/60/50 ms": {"profile": 3, "T_F1": 0.08, "T_F2": 0.08, "T_F3": 0.06,
                           "T_F4": 0.05},
    "JL, T_F = T, short move": {"profile": 2, "T_F1": 0.1, "distance": 0.08},
}
"""FMU moves (besides d = 0.43 m, v_max = 1 m/s, a_max = d_max = 8 m/s²).

The AL acceleration phase (125 ms) and the time from the start of the
acceleration to the start of the deceleration (d/v_max = 430 ms) are not
multiples of the 10 Hz mode's period: the AL profile alone would cancel the
mode otherwise, whatever the jerk time.
"""


def move_residuals(settings: Settings, names: list[str], zetas: tuple[float, ...],
                   f_mode: float = F_MODE) -> list[MoveResidual]:
    """Residual after whole FMU moves against the jerk-series formula (eq. 17-18)."""
    out = []
    for name in names:
        p = {"distance": 0.43, "v_max": 1.0, "a_max": 8.0, "d_max": 8.0, **MOVES[name]}
        tr = settings.generate(p, t_stop=1.2)  # every move ends before 1 s
        t_sw, dj = _switches(tr.j, tr.t)
        k_n = int(np.argmin(np.abs(tr.t - t_sw[-1])))
        a_ref = float(np.max(np.abs(tr.a_AL)))
        jmin = float(np.min(np.abs(dj)))
        coeffs = " ".join(f"{d / jmin:+.3g}" for d in dj)
        for z in zetas:
            mode = Mode(f_mode, z)
            resp = simulate_mode(tr.t, tr.a, mode)
            amp = free_amplitude(resp.eps[k_n], resp.deps[k_n], mode)
            ref = fm.al_reference_amplitude(a_ref, mode.omega, z)
            formula = fm.jerk_series_residual(t_sw, dj, mode.omega, z)
            out.append(MoveResidual(name, z, len(t_sw), coeffs, ref, amp / ref, formula / ref,
                                    tr.t, resp.eps))
    return out


def analyse(settings: Settings) -> ResidualAnalysis:
    """Fig. 11 map, FMU/plant points, whole moves, and the paper's two remarks."""
    T = 1.0 / F_MODE
    w = 2 * np.pi * F_MODE
    ratios = settings.pick(np.array([0.25, 0.5, 0.8, 1.0, 1.2, 2.0, 2.5]),
                           np.round(np.arange(0.1, 3.0001, 0.1), 10))
    zetas = settings.pick((0.0, 0.1), (0.0, 0.05, 0.1))
    pts = stage_residuals(settings, ratios, zetas)
    names = settings.pick(["JL, T_F = 0.7 T", "JL, T_F = T", "DJL 80/80/60/50 ms"], list(MOVES))
    moves = move_residuals(settings, names, (0.0, 0.05))
    r = np.linspace(1e-4, 3.0, 300001)
    v0 = fm.vib_jerk_stage(r * T, w, 0.0)
    i1 = int(np.argmin(np.abs(r - 1.0)))
    lo = i1
    while lo > 0 and v0[lo - 1] <= 0.2:
        lo -= 1
    hi = i1
    while hi < r.size - 1 and v0[hi + 1] <= 0.2:
        hi += 1
    band = (r >= 0.8) & (r <= 1.2)
    max_band = {}
    for z in (0.0, 0.05, 0.1):
        vz = fm.vib_jerk_stage(r * T, w, z)
        i = int(np.argmax(np.where(band, vz, -1)))
        max_band[z] = (float(vz[i]), float(r[i]))
    d = np.abs(fm.vib_jerk_stage(r * T, w, 0.1) - v0)
    i = int(np.argmax(d))
    return ResidualAnalysis(F_MODE, ratios, np.array(zetas), pts, moves, (float(r[lo]),
                            float(r[hi])), max_band, (float(d[i]), float(r[i])))


@register(3, TITLE)
def run(settings: Settings) -> ClaimResult:
    """Run claim 3."""
    ana = analyse(settings)
    T = 1.0 / ana.f_mode
    checks = []
    errs = np.array([abs(p.simulated - p.formula) for p in ana.stage_points])
    worst = ana.stage_points[int(np.argmax(errs))]
    checks.append(Check.below(
        f"one jerk stage: |simulated - eq. (20)/(omega a_max)|, {len(ana.stage_points)} points "
        f"(T_F/T in [{ana.ratios.min():g}, {ana.ratios.max():g}], zeta in "
        f"{sorted({p.zeta for p in ana.stage_points})}), worst, fraction of the AL level",
        float(errs.max()), 0.01, expected=0.0,
        note=f"worst at T_F/T = {worst.ratio:g}, zeta = {worst.zeta:g}: simulated "
             f"{worst.simulated:.6f}, formula {worst.formula:.6f}"))
    for m in ana.moves:
        checks.append(Check.close(
            f"{m.name}, zeta = {m.zeta:g}: residual after the move, simulated vs eq. (17)-(18) "
            f"({m.n_switch} jerk steps), fraction of the AL level", m.formula, m.simulated, 0.01,
            note="tolerance: 1 % of the AL reference level a_max/(omega omega_d)"))
    for m in ana.moves:
        if m.zeta == 0.0 and m.name in ("JL, T_F = T", "JL, T_F = 2T", "JL, T_F = T, short move"):
            checks.append(Check.below(
                f"{m.name}, zeta = 0: residual vanishes (T_F a multiple of the period)",
                m.simulated, 1e-6, expected=0.0, note="eq. (21): sinc zero; simulated"))
    zero_pts = [p for p in ana.stage_points if p.zeta == 0.0 and abs(p.ratio - round(p.ratio))
                < 1e-9 and round(p.ratio) >= 1]
    if zero_pts:
        checks.append(Check.below(
            "one jerk stage, zeta = 0, T_F = k T: simulated residual (worst)",
            max(p.simulated for p in zero_pts), 1e-6, expected=0.0))
    vmax, rmax = ana.max_in_20pct[0.0]
    lo, hi = ana.band_20
    checks.append(Check.below(
        "'tuning error below 20 % keeps residual below 20 %': max residual (eq. 21) for "
        "T_F/T in [0.8, 1.2], zeta = 0", vmax, 0.20, kind="paper",
        note=f"maximum at T_F/T = {rmax:.3f} (jerk time 20 % short); the residual stays "
             f"below 20 % for T_F/T in [{lo:.3f}, {hi:.3f}], i.e. tuning errors from "
             f"{lo - 1:+.1%} to {hi - 1:+.1%}. Read as an error on the mode's period relative "
             "to the jerk time (T/T_F in [0.8, 1.2]) the claim holds: max "
             f"{float(fm.vib_jerk_stage(T / 1.2, 2 * np.pi / T, 0.0)):.3f}."))
    sim_08 = [p for p in ana.stage_points if abs(p.ratio - 0.8) < 1e-9 and p.zeta == 0.0]
    if sim_08:
        checks.append(Check.close(
            "residual at T_F = 0.8 T, zeta = 0: simulated (FMU + plant) vs eq. (21)",
            float(fm.vib_eq21_sinc(0.8 * T, 2 * np.pi / T)), sim_08[0].simulated, 0.01))
    d, rd = ana.damping_effect
    checks.append(Check.below(
        "'damping below 10 % has poor effect': max |Vib(zeta = 0.1) - Vib(0)| over "
        "T_F/T in (0, 3], fraction of the AL level", d, 0.10, kind="paper",
        note=f"reading: changes smaller than 10 % of the AL level; maximum at T_F/T = {rd:.2f}. "
             "At the tuned point T_F = T damping 0.1 leaves "
             f"{float(fm.vib_jerk_stage(T, 2 * np.pi / T, 0.1)):.1%} instead of 0."))
    tables = [
        Table("One jerk stage: residual / AL level, simulated (FMU + harness mode) vs "
              "eq. (20)", ["T_F/T", "zeta", "simulated", "eq. (20)", "difference"],
              [[p.ratio, p.zeta, p.simulated, p.formula, p.simulated - p.formula]
               for p in ana.stage_points]),
        Table("Whole FMU moves (d = 0.43 m, v_max = 1 m/s, a_max = d_max = 8 m/s² unless stated) "
              f"on a "
              f"{ana.f_mode:g} Hz mode: residual after the move / AL level",
              ["move", "zeta", "jerk steps", "steps / smallest step (A_i)", "eq. (17)-(18)",
               "simulated"],
              [[m.name, m.zeta, m.n_switch, m.coefficients, m.formula, m.simulated]
               for m in ana.moves]),
        Table("Largest residual for a tuning error within ±20 % (T_F/T in [0.8, 1.2])",
              ["zeta", "max residual / AL", "at T_F/T"],
              [[z, v, rr] for z, (v, rr) in ana.max_in_20pct.items()]),
    ]
    method = (
        f"Mode {ana.f_mode:g} Hz (period {T * 1e3:g} ms = whole samples). One stage: FMU JL "
        "(a_max = 10 m/s², long acceleration phase) run to the end of its first stage, "
        "harness.plant.simulate_mode (exact for piecewise-linear acceleration), free amplitude "
        "about -a/omega^2 at the stage end, divided by a_max/(omega omega_d). Whole moves: "
        "jerk steps read from the FMU's jerk output, eq. (17)-(18) with T_n the last step, "
        "against the simulated free amplitude at that instant.")
    return ClaimResult(3, TITLE, SOURCE, STATEMENT, method=method, checks=checks,
                       figures=[ana.plot()], tables=tables,
                       derivations=[fm.DERIVATIONS["000 eq. (18)"],
                                    fm.DERIVATIONS["000 eq. (20)-(21)"]], data=ana)
