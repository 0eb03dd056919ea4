"""Claim 1: the moving average is a comb notch (Béarée & Olabi 2013, eq. 5, 7-8).

Paper's side: the continuous filter ``F(s) = (1 - exp(-T_F s))/(T_F s)``
(eq. 5) has a rectangular impulse response of unit area and length ``T_F``,
and ``|F(j 2 pi f)| = |sinc(f T_F)|``: zeros at ``f = k/T_F`` under the
envelope ``1/(pi f T_F)``; its sampled form (eq. 7-8, ``N = round(T_F/Te)``
taps) has zeros at ``k/(N Te)``.

Product's side: the impulse response is *measured on the FMU*: a JL move's
jerk during its first stage, divided by the acceleration step it smooths,
is the filter's response to a unit-area impulse.  Its spectrum (exact DTFT)
gives the notch positions and depths.  python-control gives the Bode of the
discrete filter (``ct.tf`` with ``dt = Te``), its impulse response
(``ct.impulse_response``, unit-area impulse), and carries the continuous form
with its delay as frequency-response data (``ct.frd``: python-control has no
delay element).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from . import formulas as fm
from .base import Check, ClaimResult, Settings, Table, dress, register
from .signals import db, dtft, refine_maximum, refine_minimum

TITLE = "The moving average is a comb notch"
SOURCE = "Béarée & Olabi 2013, §2.1, eq. (5), (7), (8); Fig. 2"
STATEMENT = (
    r"$F(s) = \dfrac{1 - e^{-T_F s}}{T_F\, s}$ (eq. 5) turns a step into a ramp of length "
    r"$T_F$; sampled at $T_e$ it is the moving average "
    r"$F(z) = \dfrac{1 - z^{-N_F}}{N_F\,(1 - z^{-1})}$ (eq. 7), "
    r"$F_k = \dfrac{1}{N_F} \sum_{i=1}^{N_F} I_{k-i+1}$ (eq. 8), "
    r"$N_F = \mathrm{round}(T_F / T_e)$. Its impulse response is a rectangle of unit area "
    r"and length $T_F$; its frequency response is a sinc with zeros at $f = k / T_F$ "
    r"(discrete: $k / (N_F T_e)$).")


@dataclass
class MovingAverageCase:
    """One jerk time: the FMU's measured filter against the closed forms.

    Attributes
    ----------
    T_F : float
        Requested jerk time (s).
    Te : float
        Sampling time (s).
    N : int
        Taps the FMU applied (``N_F1``).
    h_fmu : ndarray
        Measured impulse response (1/s): JL jerk / acceleration step.
    h_ct : ndarray
        python-control impulse response of eq. (7) (unit-area impulse).
    f : ndarray
        Frequency grid (Hz) of the Bode data.
    F_cont, F_disc, F_fmu : ndarray
        Continuous eq. (5) with its delay, python-control discrete eq. (7),
        spectrum of the FMU's impulse response.
    notches : ndarray
        Rows ``k, k/T_F, k/(N Te), f_min measured on the FMU, |F| there``.
    side_lobes : ndarray
        Rows ``f_peak, |F_fmu| peak, continuous envelope 1/(pi f N Te) there``.
    """

    T_F: float
    Te: float
    N: int
    h_fmu: np.ndarray
    h_ct: np.ndarray
    f: np.ndarray
    F_cont: np.ndarray
    F_disc: np.ndarray
    F_fmu: np.ndarray
    notches: np.ndarray
    side_lobes: np.ndarray
    frd: object = field(repr=False, default=None)
    dsys: object = field(repr=False, default=None)


@dataclass
class MovingAverageAnalysis:
    """Claim 1 data: one case per jerk time."""

    cases: list[MovingAverageCase]

    def plot(self):
        """Bode (python-control) and impulse responses of the first case."""
        import control as ct  # deferred: python-control is heavy to import
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        c = self.cases[0]
        fig, axes = plt.subplots(2, 2, figsize=(11, 7))
        ax_mag, ax_ph = axes[0, 0], axes[1, 0]
        frd_disc = ct.frd(c.F_disc[1:], 2 * np.pi * c.f[1:])
        ct.bode_plot([c.frd, frd_disc], ax=np.array([[ax_mag], [ax_ph]]),
                     dB=True, Hz=True, deg=True, wrap_phase=True,
                     label=[f"continuous eq. (5), T_F = {c.T_F * 1e3:g} ms (ct.frd)",
                            f"discrete eq. (7), N = {c.N} (ct.tf, dt = Te)"],
                     title="")
        ax_mag.plot(c.f[1:], db(c.F_fmu[1:]), ":", color="k", lw=1,
                    label="FMU: spectrum of the measured impulse response")
        for k in range(1, 6):
            ax_mag.axvline(k / c.T_F, color="tab:red", lw=0.8, ls=":", zorder=5)
        env = 1 / (np.pi * c.f[1:] * c.T_F)
        ax_mag.plot(c.f[1:], db(np.minimum(env, 1.0)), color="tab:red", lw=0.8, alpha=0.6,
                    label="envelope 1/(π f T_F)")
        ax_mag.set_ylim(-80, 5)
        ax_mag.legend(fontsize="x-small", loc="lower left")
        ax_mag.set_title("Bode of the moving average (dashed: k/T_F)")

        ax = axes[0, 1]
        t = np.arange(c.h_fmu.size) * c.Te
        ax.step(np.r_[-c.Te, 0.0, c.T_F, c.T_F + 10 * c.Te], [0, 1 / c.T_F, 0, 0],
                where="post", color="tab:red", lw=1.2, label="eq. (5): rectangle 1/T_F")
        ax.plot(t, c.h_ct[: t.size], "o", ms=3, mfc="none",
                label="ct.impulse_response of eq. (7)")
        ax.plot(t, c.h_fmu, ".", ms=3, color="k", label="FMU: JL jerk / acceleration step")
        dress(ax, "t [s]", "impulse response [1/s]", "Impulse response (unit-area impulse)")

        ax = axes[1, 1]
        for cc, style in zip(self.cases, ("-", "--"), strict=False):
            f1 = 1.0 / (cc.N * cc.Te)
            fz = np.linspace(0.5 * f1, 3.5 * f1, 2000)
            ax.plot(fz, db(dtft(cc.h_fmu, cc.Te, fz) * cc.Te), style,
                    label=f"FMU, T_F = {cc.T_F * 1e3:g} ms → N = {cc.N}")
            for k in range(1, 4):
                ax.axvline(k / cc.T_F, color="tab:red", lw=0.6, ls=style)
        ax.set_ylim(-100, 0)
        dress(ax, "f [Hz]", "|F| [dB]", "Notches: red lines at k/T_F; minima at k/(N T_e)")
        fig.tight_layout()
        return fig


def analyse_case(settings: Settings, T_F: float, Te: float = 1e-3, n_notch: int = 5
                 ) -> MovingAverageCase:
    """Measure the FMU's moving average for jerk time ``T_F``."""
    import control as ct  # deferred: python-control is heavy to import

    traj = settings.generate({"profile": 2, "Te": Te, "distance": 0.4, "v_max": 1.0,
                              "a_max": 10.0, "d_max": 10.0, "T_F1": T_F, "v0": 0.0,
                              "v_e": 0.0}, t_stop=T_F + 30 * Te)
    N = int(traj.N_F[0])
    step = float(traj.a_AL[0])
    h_fmu = traj.j[: N + 20] / step
    num = np.ones(N) / N
    den = np.r_[1.0, np.zeros(N - 1)]
    dsys = ct.tf(num, den, dt=Te)
    t_ir = np.arange(N + 20) * Te
    h_ct = np.asarray(ct.impulse_response(dsys, T=t_ir).outputs).ravel()

    f_max = min(6.0 / T_F, 0.45 / Te)
    f = np.unique(np.r_[0.0, np.geomspace(0.2, f_max, 1500)])
    F_cont = fm.ma_continuous(f, T_F)
    frd = ct.frd(F_cont[1:], 2 * np.pi * f[1:])
    F_disc = np.asarray(ct.frequency_response(dsys, 2 * np.pi * f[1:]).complex).ravel()
    F_disc = np.r_[1.0 + 0j, F_disc]

    def F_meas(x: float | np.ndarray) -> np.ndarray:
        return dtft(h_fmu, Te, x) * Te

    F_fmu = F_meas(f)
    rows = []
    f1 = 1.0 / (N * Te)
    for k in range(1, n_notch + 1):
        fk = k * f1
        fmin, depth = refine_minimum(F_meas, fk - 0.3 * f1, fk + 0.3 * f1)
        rows.append([k, k / T_F, fk, fmin, depth])
    lobes = []
    for k in range(1, n_notch):
        fp, peak = refine_maximum(F_meas, (k + 0.05) * f1, (k + 0.95) * f1)
        lobes.append([fp, peak, 1.0 / (np.pi * fp * N * Te)])
    return MovingAverageCase(T_F=T_F, Te=Te, N=N, h_fmu=h_fmu, h_ct=h_ct, f=f, F_cont=F_cont,
                             F_disc=F_disc, F_fmu=F_fmu, notches=np.array(rows),
                             side_lobes=np.array(lobes), frd=frd, dsys=dsys)


def analyse(settings: Settings) -> MovingAverageAnalysis:
    """Two jerk times: a whole number of samples (50 ms) and not (52.3 ms)."""
    T_Fs = (0.05, 0.0523)
    return MovingAverageAnalysis([analyse_case(settings, T_F,
                                               n_notch=settings.pick(3, 5)) for T_F in T_Fs])


def _worst(x: np.ndarray, target: float) -> float:
    """Return the element of ``x`` farthest from ``target``."""
    return float(x[np.argmax(np.abs(x - target))])


def _checks(c: MovingAverageCase) -> list[Check]:
    Te, N = c.Te, c.N
    tag = f"T_F = {c.T_F * 1e3:g} ms (N = {N})"
    out = [
        Check.close(f"{tag}: taps applied by the FMU = round(T_F/T_e)", round(c.T_F / Te), N, 0,
                    note="eq. (7): N_F is the round integer of T_F/T_e"),
        Check.close(f"{tag}: FMU impulse response height 1/(N T_e), worst sample",
                    1 / (N * Te), _worst(c.h_fmu[:N], 1 / (N * Te)), 1e-9 / (N * Te),
                    unit="1/s",
                    note="JL jerk over its first stage divided by the AL acceleration step"),
        Check.close(f"{tag}: FMU impulse response length", N * Te,
                    np.count_nonzero(np.abs(c.h_fmu) > 1e-9 / (N * Te)) * Te, 1e-12, unit="s"),
        Check.close(f"{tag}: FMU impulse response area", 1.0, float(np.sum(c.h_fmu) * Te), 1e-12),
        Check.close(f"{tag}: python-control impulse response area", 1.0,
                    float(np.sum(c.h_ct) * Te), 1e-12,
                    note="ct.impulse_response applies a unit-area impulse (1/T_e at sample 0)"),
        Check.below(f"{tag}: |FMU spectrum - python-control eq. (7)| over the Bode grid",
                    float(np.max(np.abs(c.F_fmu - c.F_disc))), 1e-12,
                    expected=0.0),
        Check.below(f"{tag}: |python-control eq. (7) - Dirichlet closed form|",
                    float(np.max(np.abs(c.F_disc - fm.ma_discrete(c.f, N, Te)))), 1e-12,
                    expected=0.0),
    ]
    rel_pos = np.abs(c.notches[:, 3] - c.notches[:, 2]) / c.notches[:, 2]
    out.append(Check.below(
        f"{tag}: notch positions measured on the FMU vs k/(N T_e), k = 1..{len(c.notches)} "
        "(max relative error)", float(rel_pos.max()), 1e-6, expected=0.0,
        note="minimum of |F| located by Brent's method around each k/(N T_e)"))
    out.append(Check.below(
        f"{tag}: notch depths measured on the FMU (worst, dB)", float(db(c.notches[:, 4]).max()),
        -100.0, unit="dB", note="a zero of the transfer function: |F| <= 1e-5 at the minimum"))
    # Sinc envelope: discrete response vs continuous sinc below f = 0.1/Te; bound
    # |sin(Nx)| |1/(N sin x) - 1/(N x)| <= (1/(N sin x_m) - 1/(N x_m)), x = pi f Te.
    fb = c.f[(c.f > 0) & (c.f <= 0.1 / Te)]
    x_m = np.pi * fb.max() * Te
    bound = (1 / np.sin(x_m) - 1 / x_m) / N
    dev = np.max(np.abs(np.abs(dtft(c.h_fmu, Te, fb) * Te) - np.abs(np.sinc(fb * N * Te))))
    out.append(Check.below(
        f"{tag}: FMU |F| vs sinc(f N T_e) for f <= {0.1 / Te:g} Hz (max difference)",
        float(dev), float(bound), expected=0.0,
        note="bound (1/sin x - 1/x)/N at x = 0.1 pi (sampling effect)"))
    # Side lobes of sinc: peaks where tan x = x (x = pi f T_F), value 1/sqrt(1 + x^2),
    # just under the envelope 1/x.
    from scipy.optimize import brentq  # deferred: scipy is heavy to import

    x_p = np.array([brentq(lambda x: np.sin(x) - x * np.cos(x), k * np.pi + 1e-9,
                           k * np.pi + np.pi / 2 - 1e-9) for k in range(1, len(c.side_lobes) + 1)])
    peak_sinc = 1 / np.sqrt(1 + x_p**2)
    out.append(Check.below(
        f"{tag}: side-lobe peaks measured on the FMU vs sinc peaks 1/sqrt(1 + x^2), "
        "tan x = x (max difference)", float(np.max(np.abs(c.side_lobes[:, 1] - peak_sinc))),
        float(bound), expected=0.0, note="same sampling bound as above"))
    env_d = 1 / (N * np.sin(np.pi * c.side_lobes[:, 0] * Te))
    out.append(Check.below(
        f"{tag}: side-lobe peaks / discrete envelope 1/(N sin(pi f T_e)) (largest; first lobe "
        f"{c.side_lobes[0, 1] / env_d[0]:.4f})", float(np.max(c.side_lobes[:, 1] / env_d)), 1.0,
        note="the discrete envelope tends to the sinc's 1/(pi f T_F) for f << 1/T_e; the "
             f"peaks exceed the continuous envelope by up to "
             f"{np.max(c.side_lobes[:, 1] / c.side_lobes[:, 2]) - 1:.2%} (sampling)"))
    return out


@register(1, TITLE)
def run(settings: Settings) -> ClaimResult:
    """Run claim 1."""
    ana = analyse(settings)
    checks: list[Check] = []
    tables = []
    for c in ana.cases:
        checks += _checks(c)
        tables.append(Table(
            f"Notches of the FMU's moving average, T_F = {c.T_F * 1e3:g} ms requested, "
            f"N = {c.N} taps applied (T_e = {c.Te * 1e3:g} ms)",
            ["k", "k/T_F [Hz]", "k/(N T_e) [Hz]", "measured minimum [Hz]", "depth [dB]"],
            [[int(r[0]), r[1], r[2], r[3], float(db(r[4]))] for r in c.notches]))
    c2 = ana.cases[1]
    shift = (1 / (c2.N * c2.Te) - 1 / c2.T_F) / (1 / c2.T_F)
    method = (
        "Impulse response measured on the FMU (JL move, d = 0.4 m, v_max = 1 m/s, "
        "a_max = 10 m/s², jerk of the first stage / acceleration step); python-control "
        "discrete eq. (7) as ct.tf(dt = T_e) for Bode and ct.impulse_response; continuous "
        "eq. (5) with its delay as ct.frd. Notches located by Brent's method on the exact "
        f"DTFT of the measured response. With T_F = {c2.T_F * 1e3:g} ms (not a multiple of "
        f"T_e) the FMU applies N = {c2.N}: the first notch moves from 1/T_F = "
        f"{1 / c2.T_F:.3f} Hz to 1/(N T_e) = {1 / (c2.N * c2.Te):.3f} Hz ({shift:+.2%}); "
        "tune jerk times as whole samples.")
    fig = ana.plot()
    return ClaimResult(1, TITLE, SOURCE, STATEMENT, method=method, checks=checks,
                       figures=[fig], tables=tables, data=ana)
