"""Claim 2: JL = AL filtered by the moving average (000 §2.1; 003 eq. 15-16, Fig. 7).

Paper's side: the jerk-limited profile is the (adapted) acceleration-limited
profile convolved with the moving average of length ``T_F`` (000 §2.1-2.2);
equivalently (003 Fig. 7) the AL profile filtered by the *integral of a
two-impulse shaper* ``(delta(t) - delta(t - T_F)) / T_F``, so the JL's
acceleration spectrum is the AL's times ``F(j omega)``, and eq. (16) is
eq. (15) times ``|sinc(omega T_j / 2)|``.

Product's side: the FMU's JL outputs against its own AL output (``x_AL``,
``v_AL``, ``a_AL``), sample by sample, and their exact spectra.  The FMU's AL
acceleration ``a_AL[k]`` is the constant value on ``[t_k, t_k + Te)``, so the
continuous filter (5) gives, exactly at the samples,

* ``a[k] = (1/N) sum_{i=1..N} a_AL[k-i]``            (eq. 8 with ``I_k = a_AL[k-1]``),
* ``j[k] = (a_AL[k] - a_AL[k-N]) / (N Te)``           (the two-impulse shaper),
* ``v[k] = (1/N) sum_{i=1..N} (v_AL[k-i] + a_AL[k-i] Te/2)``,
* ``x[k] = (1/N) sum_{i=1..N} (x_AL[k-i] + v_AL[k-i] Te/2 + a_AL[k-i] Te^2/6)``

(the interval means of the piecewise-linear / quadratic AL velocity and
position).  The one-sample index shift of the first line against eq. (8) is
the sample convention, not a delay: eq. (5) in continuous time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import formulas as fm
from .base import Check, ClaimResult, Settings, Table, dress, register
from .signals import rfft_spectrum

TITLE = "JL = AL * moving average"
SOURCE = ("Béarée & Olabi 2013, §2.1-2.2, eq. (5)-(8); Béarée 2014, eq. (15)-(16), Fig. 7")
STATEMENT = (
    "A JL profile is obtained by convolving the moving-average filter with an "
    "(adapted) acceleration-limited profile (2013 §2.1). 'La trajectoire à jerk limité peut "
    "tout simplement être décomposée en une trajectoire à accélération limitée filtrée par "
    "l'intégrale d'un shaper à impulsion négative' (2014 §4.2, Fig. 7): the JL acceleration "
    "spectrum is the AL spectrum times the filter's, eq. (16) = eq. (15) x |sinc|.")

MOVES: dict[str, dict[str, float]] = {
    "rest-to-rest, v_max reached": {"distance": 0.4, "v_max": 1.0, "a_max": 10.0,
                                    "d_max": 10.0, "T_F1": 0.05},
    "short move (v_max not reached)": {"distance": 0.02, "v_max": 1.0, "a_max": 10.0,
                                       "d_max": 10.0, "T_F1": 0.03},
    "end velocity v_e = 0.2 m/s": {"distance": 0.4, "v_max": 1.0, "a_max": 10.0,
                                   "d_max": 8.0, "T_F1": 0.03, "v_e": 0.2},
}
"""JL moves checked (FMU parameters besides ``profile = 2``)."""


def _moving_sum(x: np.ndarray, N: int, pad: float) -> np.ndarray:
    """``(1/N) sum_{i=1..N} x[k-i]`` with ``x[<0] = pad``."""
    xp = np.r_[np.full(N, pad), x]
    c = np.cumsum(np.r_[0.0, xp])
    k = np.arange(x.size)
    return (c[k + N] - c[k]) / N


@dataclass
class JLFilterMove:
    """One JL move of the FMU against its AL input."""

    name: str
    params: dict[str, float]
    Te: float
    N: int
    t: np.ndarray
    a: np.ndarray
    a_AL: np.ndarray
    j: np.ndarray
    err_a: float
    err_j: float
    err_v: float
    err_x: float
    a_scale: float
    f: np.ndarray
    A_JL: np.ndarray
    A_AL: np.ndarray
    err_dft: float
    err_cont: float


@dataclass
class JLFilterAnalysis:
    """Claim 2 data: the moves, and the eq. (16) vs (15) x sinc identity."""

    moves: list[JLFilterMove]
    Omega: np.ndarray
    identity_err: dict[tuple[float, float], float]

    def plot(self):
        """Time-domain overlay and spectra of the first move."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        m = self.moves[0]
        fig, axes = plt.subplots(2, 2, figsize=(11, 7))
        ax = axes[0, 0]
        ax.step(m.t, m.a_AL, where="post", lw=1, label="a_AL (FMU, AL input)")
        ax.plot(m.t, m.a, lw=1.5, label="a (FMU, JL output)")
        ax.plot(m.t, _moving_sum(m.a_AL, m.N, 0.0), "k:", lw=1,
                label=f"moving average of a_AL (N = {m.N})")
        dress(ax, "t [s]", "a [m/s²]", f"{m.name}: acceleration")

        ax = axes[0, 1]
        shaper = (m.a_AL - np.r_[np.zeros(m.N), m.a_AL[:-m.N]]) / (m.N * m.Te)
        ax.step(m.t, m.j, where="post", lw=1.5, label="j (FMU, JL output)")
        ax.step(m.t, shaper, where="post", ls=":", color="k", lw=1,
                label="(a_AL(t) - a_AL(t - T_F)) / T_F: two-impulse shaper")
        dress(ax, "t [s]", "j [m/s³]", "Jerk = AL acceleration through the shaper (Fig. 7)")

        ax = axes[1, 0]
        sel = (m.f > 0) & (m.f <= 5.0 / (m.N * m.Te))
        F = fm.ma_continuous(m.f[sel], m.N * m.Te)
        ax.semilogy(m.f[sel], np.abs(m.A_AL[sel]), lw=1, label="|A_AL(f)| (FMU)")
        ax.semilogy(m.f[sel], np.abs(m.A_JL[sel]), lw=1.5, label="|A_JL(f)| (FMU)")
        ax.semilogy(m.f[sel], np.abs(m.A_AL[sel] * F), "k:", lw=1,
                    label="|A_AL(f) F(j2πf)|, eq. (5)")
        ax.set_xlabel("f [Hz]")
        ax.set_ylabel("|A(f)| [m/s]")
        ax.set_ylim(1e-6, None)
        ax.set_title("Acceleration spectra (exact transforms of the FMU's profiles)")
        ax.legend(fontsize="x-small")
        ax.grid(True, alpha=0.3)

        ax = axes[1, 1]
        for alpha, beta in [k for k in self.identity_err if k[0] == 0.25]:
            ax.semilogy(self.Omega, fm.spectrum_jl_mag(self.Omega, alpha, beta), lw=1.5,
                        label=f"eq. (16), α = {alpha:g}, β = {beta:g}")
            ax.semilogy(self.Omega, fm.jl_equals_al_times_filter(self.Omega, alpha, beta), "k:",
                        lw=1)
        ax.plot([], [], "k:", label="eq. (15) of the AL input × |sinc(ω T_j/2)|")
        ax.set_ylim(1e-4, 10)
        ax.set_xlim(0, 20)
        dress(ax, "Ω = ω T / 2π", "|Q̈(Ω)| [m/s]",
              "Béarée 2014: eq. (16) = eq. (15) × filter (P = 1 m, T = 1 s)")
        fig.tight_layout()
        return fig


def analyse_move(settings: Settings, name: str, params: dict[str, float], n_fft: int
                 ) -> JLFilterMove:
    """Run one JL move on the FMU and compare it with its AL input."""
    tr = settings.generate({"profile": 2, **params})
    Te = float(tr.params["Te"])
    N = int(tr.N_F[0])
    x0 = float(tr.params["x0"])
    v0 = float(tr.params["v0"])
    a_hat = _moving_sum(tr.a_AL, N, 0.0)
    j_hat = (tr.a_AL - np.r_[np.zeros(N), tr.a_AL[:-N]]) / (N * Te)
    v_hat = _moving_sum(tr.v_AL + tr.a_AL * Te / 2, N, v0)
    x_mid = tr.x_AL + tr.v_AL * Te / 2 + tr.a_AL * Te**2 / 6
    x_hat = _moving_sum(x_mid, N, x0)
    a_scale = float(np.max(np.abs(tr.a_AL)))
    # spectra: AL acceleration piecewise constant (zoh), JL piecewise linear (foh)
    f, A_AL = rfft_spectrum(tr.a_AL, Te, n_fft, "zoh")
    _, A_JL = rfft_spectrum(tr.a, Te, n_fft, "foh")
    X_AL = np.fft.rfft(tr.a_AL, n_fft)
    X_JL = np.fft.rfft(tr.a, n_fft)
    Fd = np.exp(-2j * np.pi * f * Te) * fm.ma_discrete(f, N, Te)
    err_dft = float(np.max(np.abs(X_JL - X_AL * Fd)) / np.max(np.abs(X_AL)))
    Fc = fm.ma_continuous(f, N * Te)
    err_cont = float(np.max(np.abs(A_JL - A_AL * Fc)) / np.max(np.abs(A_AL)))
    return JLFilterMove(
        name=name, params=params, Te=Te, N=N, t=tr.t, a=tr.a, a_AL=tr.a_AL, j=tr.j,
        err_a=float(np.max(np.abs(tr.a - a_hat))), err_j=float(np.max(np.abs(tr.j - j_hat))),
        err_v=float(np.max(np.abs(tr.v - v_hat))), err_x=float(np.max(np.abs(tr.x - x_hat))),
        a_scale=a_scale, f=f, A_JL=A_JL, A_AL=A_AL, err_dft=err_dft, err_cont=err_cont)


def analyse(settings: Settings) -> JLFilterAnalysis:
    """All moves, and the closed-form identity on a grid of (alpha, beta)."""
    names = list(MOVES)[: settings.pick(2, 3)]
    n_fft = settings.pick(2**13, 2**15)
    moves = [analyse_move(settings, n, MOVES[n], n_fft) for n in names]
    Omega = np.linspace(0.01, 30.0, settings.pick(3000, 30000))
    ident = {}
    for alpha in (0.1, 0.25, 0.4):
        for beta in (0.2, 0.5, 0.8):
            q16 = fm.spectrum_jl_mag(Omega, alpha, beta)
            q15f = fm.jl_equals_al_times_filter(Omega, alpha, beta)
            ident[(alpha, beta)] = float(np.max(np.abs(q16 - q15f)) / np.max(q16))
    return JLFilterAnalysis(moves, Omega, ident)


@register(2, TITLE)
def run(settings: Settings) -> ClaimResult:
    """Run claim 2."""
    ana = analyse(settings)
    checks = []
    rows = []
    for m in ana.moves:
        tag = f"{m.name} (T_F = {m.N * m.Te * 1e3:g} ms)"
        s_a = m.a_scale
        v_scale = max(float(m.params.get("v_max", 1.0)), 1e-12)
        d_scale = abs(float(m.params["distance"]))
        checks += [
            Check.below(f"{tag}: max |a - (1/N) sum a_AL[k-i]| / a_max", m.err_a / s_a, 1e-12,
                        expected=0.0, note="eq. (8), sample by sample"),
            Check.below(f"{tag}: max |j - (a_AL[k] - a_AL[k-N])/(N T_e)| / (a_max/T_F)",
                        m.err_j / (s_a / (m.N * m.Te)), 1e-12, expected=0.0,
                        note="Fig. 7: the jerk is the AL acceleration through "
                             "(delta(t) - delta(t - T_F))/T_F"),
            Check.below(f"{tag}: max |v - moving average of v_AL| / v_max", m.err_v / v_scale,
                        1e-12, expected=0.0, note="eq. (5) on the piecewise-linear AL velocity"),
            Check.below(f"{tag}: max |x - moving average of x_AL| / |d|", m.err_x / d_scale,
                        1e-12, expected=0.0,
                        note="eq. (5) on the piecewise-quadratic AL position"),
            Check.below(f"{tag}: DFT(a) vs DFT(a_AL) z^-1 F(z), max error / max |DFT(a_AL)|",
                        m.err_dft, 1e-12, expected=0.0),
            Check.below(f"{tag}: continuous spectrum A_JL vs A_AL F(j omega) (eq. 5), max error"
                        " / max |A_AL|", m.err_cont, 1e-12, expected=0.0,
                        note="exact transforms: a_AL piecewise constant, a piecewise linear"),
        ]
        rows.append([m.name, m.N, m.err_a / s_a, m.err_j / (s_a / (m.N * m.Te)),
                     m.err_v / v_scale, m.err_x / d_scale, m.err_dft, m.err_cont])
    worst = max(ana.identity_err.values())
    checks.append(Check.below(
        "Béarée 2014: eq. (16) vs eq. (15) of the AL input x |sinc(omega T_j/2)|, "
        f"{len(ana.identity_err)} (alpha, beta) pairs, max difference / peak", worst, 1e-12,
        expected=0.0, kind="paper",
        note="closed forms only: eq. (16) is the AL spectrum times the filter's"))
    tables = [
        Table("Relative deviations of the FMU's JL outputs from the moving average of its "
              "AL outputs (0 = identical to rounding)",
              ["move", "N", "a", "j", "v", "x", "DFT", "continuous spectrum"], rows),
        Table("eq. (16) vs eq. (15) x filter, max difference / peak",
              ["alpha", "beta", "deviation"],
              [[a, b, e] for (a, b), e in ana.identity_err.items()]),
    ]
    method = (
        "JL moves run on the FMU (profile 2); the JL outputs are compared sample by sample "
        "with the moving average (continuous eq. 5, N = N_F1 samples) of the FMU's own AL "
        "outputs x_AL, v_AL, a_AL. Spectra are exact Fourier transforms of the FMU's "
        "continuous profiles (FFT of the samples x hold kernel: piecewise-constant a_AL, "
        "piecewise-linear a).")
    return ClaimResult(2, TITLE, SOURCE, STATEMENT, method=method, checks=checks,
                       figures=[ana.plot()], tables=tables, data=ana)
