"""Damped-jerk profile: the JL law whose two-impulse shaper accounts for damping.

Béarée 2014 (Assises MUGV, §4.2, Fig. 7) reads the jerk-limited (JL) law as
the acceleration-limited (AL) law filtered by the *integral of a two-impulse
shaper with a negative impulse*: the moving average of length ``T``,

    M(s) = (1 - exp(-sT)) / (sT),

is the shaper ``[+1, -1]`` at ``[0, T]`` followed by an integrator.  Its
zeros ``s = 2jπk/T`` lie on the imaginary axis, so it cancels only an
undamped mode (``T`` = a multiple of the period).  The paper points to
Béarée 2014 (Control Eng. Practice 28) for the damped version and gives no
equation; it is re-derived here (see ``docs/peers.md``).

To leave no residual on the mode ``p = -ζω + jω_d`` the filter must vanish
at ``p``.  Keep two impulses ``[1, -K]`` at ``[0, T]`` and replace the
integrator ``1/s`` by the leaky integrator ``1/(s + λ)``:

    H(s) = c (1 - K exp(-sT)) / (s + λ),   λ = ζω,   K = exp(-λT),   c = λ / (1 - K).

* ``H`` is a finite impulse response: ``h(t) = c exp(-λt)`` on ``[0, T)``,
  0 elsewhere (the pole at ``-λ`` is cancelled since ``K exp(λT) = 1``), and
  ``H(0) = 1`` (unit area, the final position is kept).
* ``H(s) = 0`` where ``exp(-(s + λ)T) = 1``: ``s = -λ + 2jπk/T``; with
  ``T = k 2π/ω_d`` (``k`` damped periods) that includes the mode pole.
* A step of acceleration ``ΔA`` becomes a ramp whose jerk
  ``ΔA c exp(-ζω t)`` decays like the mode: the *damped jerk*.  With
  ``ζ = 0`` it is the JL law with ``T_F = k`` periods.
* ``h >= 0`` with unit area: the filtered profile keeps the AL profile's
  velocity and acceleration limits; its peak jerk is ``c ΔA``, larger than
  ``ΔA / T`` by ``λT / (1 - exp(-λT))``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .context import PeerContext, PeerSpec
from .shapers import al_profile
from .trajectory import Motion, PiecewiseJerk, SampledTrajectory


def _phi(n: int, x: np.ndarray) -> np.ndarray:
    """``phi_n(x) = (n-1)! / x^n * (exp(-x) - sum_{k<n} (-x)^k/k!) * (-1)^n``.

    phi_1 = (1 - e^-x)/x, phi_2 = (x - 1 + e^-x)/x², phi_3 = (x²/2 - x + 1 - e^-x)/x³,
    computed by series for small x; phi_n(0) = 1/n!.
    """
    x = np.asarray(x, dtype=float)
    out = np.empty_like(x)
    small = np.abs(x) < 0.1
    xs = x[small]
    # series: phi_n(x) = sum_k (-x)^k / (n + k)!
    term = np.full_like(xs, 1.0 / float(np.prod(np.arange(1, n + 1))))
    acc = term.copy()
    for k in range(1, 14):
        term = term * (-xs) / (n + k)
        acc = acc + term
    out[small] = acc
    xl = x[~small]
    em = np.exp(-xl)
    if n == 1:
        out[~small] = -np.expm1(-xl) / xl
    elif n == 2:
        out[~small] = (xl - 1.0 + em) / xl ** 2
    elif n == 3:
        out[~small] = (xl * xl / 2 - xl + 1.0 - em) / xl ** 3
    else:  # pragma: no cover - not used
        raise ValueError(n)
    return out


@dataclass(frozen=True)
class DampedJerkFilter:
    """The damped-jerk filter tuned to the mode ``f``, ``zeta``.

    Attributes
    ----------
    f : float
        Undamped natural frequency (Hz).
    zeta : float
        Damping ratio.
    k : int
        Length in damped periods (``T = k * 2π/ω_d``).
    """

    f: float
    zeta: float = 0.0
    k: int = 1

    def __post_init__(self) -> None:
        if not self.f > 0.0:
            raise ValueError(f"mode frequency must be positive, got {self.f!r}")
        if not 0.0 <= self.zeta < 1.0:
            raise ValueError(f"damping ratio must be in [0, 1), got {self.zeta!r}")
        if int(self.k) != self.k or self.k < 1:
            raise ValueError(f"k must be a positive integer, got {self.k!r}")

    @property
    def omega(self) -> float:
        """Natural angular frequency (rad/s)."""
        return 2 * np.pi * self.f

    @property
    def T(self) -> float:
        """Jerk time: ``k`` damped periods (s)."""
        return self.k * 2 * np.pi / (self.omega * np.sqrt(1 - self.zeta ** 2))

    @property
    def lam(self) -> float:
        """Decay rate of the jerk, ``ζω`` (1/s)."""
        return self.zeta * self.omega

    @property
    def K(self) -> float:
        """Ratio of the shaper's impulses, ``exp(-ζωT)``."""
        return float(np.exp(-self.lam * self.T))

    @property
    def c(self) -> float:
        """Initial value of the impulse response, ``λ / (1 - K)`` (1/s)."""
        return 1.0 / (self.T * float(_phi(1, np.array([self.lam * self.T]))[0]))

    @property
    def shaper(self) -> tuple[np.ndarray, np.ndarray]:
        """The two impulses ``(amplitudes, times)`` before the leaky integrator: ``c [1, -K]``."""
        return self.c * np.array([1.0, -self.K]), np.array([0.0, self.T])

    def kernel(self, u: np.ndarray) -> np.ndarray:
        """Impulse response ``h(u) = c exp(-λu)`` on ``[0, T)`` (1/s)."""
        u = np.asarray(u, dtype=float)
        return np.where((u >= 0) & (u < self.T), self.c * np.exp(-self.lam * u), 0.0)

    def transfer(self, s: complex | np.ndarray) -> complex | np.ndarray:
        """``H(s)`` (computed as the integral of the kernel, finite at ``s = -λ``)."""
        s = np.asarray(s, dtype=complex)
        x = (s + self.lam) * self.T
        # c (1 - K e^{-sT}) / (s + λ) = c T (1 - e^{-x}) / x
        small = np.abs(x) < 1e-8
        xs = np.where(small, 1.0, x)
        val = np.where(small, 1.0 - x / 2, -np.expm1(-xs) / xs)
        return self.c * self.T * val

    def step_response(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Filter a unit acceleration step: ``S(u)``, its integral and double integral.

        Returns acceleration, velocity and position responses to a unit
        acceleration step at ``u = 0`` (zero for ``u <= 0``).
        """
        u = np.asarray(u, dtype=float)
        T, lam = self.T, self.lam
        norm = T * float(_phi(1, np.array([lam * T]))[0])  # = 1/c
        uc = np.clip(u, 0.0, T)
        S = uc * _phi(1, lam * uc) / norm
        S1 = uc ** 2 * _phi(2, lam * uc) / norm
        S2 = uc ** 3 * _phi(3, lam * uc) / norm
        after = u > T
        d = np.where(after, u - T, 0.0)
        S2 = S2 + S1 * d + d * d / 2
        S1 = S1 + d
        S = np.where(after, 1.0, S)
        neg = u <= 0
        return (np.where(neg, 0.0, S), np.where(neg, 0.0, S1), np.where(neg, 0.0, S2))

    def residual_ratio(self, f: float | np.ndarray, zeta: float | None = None
                       ) -> float | np.ndarray:
        """Residual of the filtered AL motion over the AL one, each at its end.

        ``|H(p) exp(pT)|`` at the pole ``p`` of the mode ``f, zeta`` (default: the design mode).
        """
        zeta = self.zeta if zeta is None else zeta
        w = 2 * np.pi * np.asarray(f, dtype=float)
        p = -zeta * w + 1j * w * np.sqrt(1 - zeta ** 2)
        val = np.abs(self.transfer(p) * np.exp(p * self.T))
        return float(val) if np.ndim(val) == 0 else val


class DampedJerkMotion(Motion):
    """An AL motion (acceleration steps) filtered by a :class:`DampedJerkFilter`.

    Parameters
    ----------
    tau : array_like
        Times of the AL acceleration steps (s).
    dA : array_like
        Their sizes (m/s²).
    filt : DampedJerkFilter
    x0, v0 : float
        Start position and velocity.
    name : str
    params : dict
    """

    def __init__(self, tau: np.ndarray, dA: np.ndarray, filt: DampedJerkFilter,
                 x0: float = 0.0, v0: float = 0.0, name: str = "damped jerk",
                 params: Mapping[str, Any] | None = None) -> None:
        self.tau = np.asarray(tau, dtype=float)
        self.dA = np.asarray(dA, dtype=float)
        if self.tau.size == 0:
            raise ValueError("no acceleration step to filter")
        self.filt = filt
        self.x0 = float(x0)
        self.v0 = float(v0)
        self.name = name
        self.params = dict(params or {})
        self.params.update({"dj_f": filt.f, "dj_zeta": filt.zeta, "dj_k": filt.k,
                            "dj_T": filt.T})

    @classmethod
    def from_al(cls, al: PiecewiseJerk | SampledTrajectory, filt: DampedJerkFilter,
                name: str = "damped jerk") -> DampedJerkMotion:
        """Filter an AL profile (piecewise-constant acceleration, FMU ``profile = 1``)."""
        m = al.to_motion() if isinstance(al, SampledTrajectory) else al
        if not isinstance(m, PiecewiseJerk):
            raise TypeError("the AL profile must be piecewise-jerk")
        if np.any(np.abs(m.j[:-1]) > 0):
            raise ValueError("not an AL profile: its jerk is not zero between steps")
        a_before = np.r_[0.0, m.a[:-1]]
        dA = m.a - a_before
        keep = dA != 0.0
        return cls(m.tb[keep], dA[keep], filt, x0=float(m.x[0]), v0=float(m.v[0]), name=name,
                   params=m.params)

    @property
    def t_start(self) -> float:
        """First acceleration step (s)."""
        return float(self.tau.min())

    @property
    def t_end(self) -> float:
        """Last acceleration step plus the jerk time (s)."""
        return float(self.tau.max() + self.filt.T)

    def breakpoints(self) -> np.ndarray:
        """Return the AL steps and the steps + T."""
        return np.unique(np.r_[self.tau, self.tau + self.filt.T])

    def evaluate(self, t, side: str = "right"):
        """Exact x, v, a, j (see :meth:`Motion.evaluate`)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        if side not in ("right", "left"):
            raise ValueError("side must be 'right' or 'left'")
        u = t[:, None] - self.tau[None, :]
        S, S1, S2 = self.filt.step_response(u)
        x = self.x0 + self.v0 * (t - self.t_start) + S2 @ self.dA
        v = self.v0 + S1 @ self.dA
        a = S @ self.dA
        T = self.filt.T
        inside = (u >= 0) & (u < T) if side == "right" else (u > 0) & (u <= T)
        h = np.where(inside, self.filt.c * np.exp(-self.filt.lam * np.clip(u, 0, T)), 0.0)
        return x, v, a, h @ self.dA


def damped_jerk_profile(params: Mapping[str, Any], f: float, zeta: float, *, k: int = 1,
                        fmu: Any = None, fmi_version: int = 2) -> SampledTrajectory:
    """AL profile of the FMU filtered by the damped-jerk filter, sampled at ``Te``.

    Parameters
    ----------
    params : mapping
        FMU parameters of the move (``profile`` is forced to 1).
    f, zeta : float
        Mode to cancel (Hz, damping ratio).
    k : int
        Jerk time in damped periods.
    fmu, fmi_version
        Passed to :func:`harness.fmu.runner.generate`.
    """
    al = al_profile(params, fmu=fmu, fmi_version=fmi_version)
    m = DampedJerkMotion.from_al(al, DampedJerkFilter(f, zeta, k))
    return m.sample(al.Te, t0=float(al.t[0]))


@dataclass
class DampingSweep:
    """Residual of JL and damped-jerk laws against the damping (Béarée 2014, Fig. 8).

    Attributes
    ----------
    zeta : ndarray
        Damping ratios of the mode.
    residual : dict of str to ndarray
        Residual in % of the AL law's, each at the end of its own motion.
    """

    zeta: np.ndarray
    residual: dict[str, np.ndarray]

    def plot(self, title: str | None = None):
        """Residual (% of AL) against ζ; return the Figure."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        fig, ax = plt.subplots(figsize=(7, 4))
        for name, r in self.residual.items():
            ax.plot(100 * self.zeta, r, label=name)
        ax.set_xlabel("damping ratio ζ [%]")
        ax.set_ylabel("residual vibration [% of AL]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small")
        ax.set_title(title or "JL against damped jerk, tuned to the mode (Béarée 2014, Fig. 8)")
        fig.tight_layout()
        return fig


def damping_sweep(zeta: np.ndarray | None = None, f: float = 1.0) -> DampingSweep:
    """Residual ratio to AL of JL (``T_F`` = undamped or damped period) and damped jerk.

    Closed forms: ``|H(p) exp(pT)|`` for each filter ``H`` of length ``T``
    (the filtered motion ends ``T`` after the AL one); the tests check them
    by simulation.
    """
    zeta = np.linspace(0.0, 0.3, 61) if zeta is None else np.asarray(zeta, dtype=float)
    w = 2 * np.pi * f
    out: dict[str, list[float]] = {"JL, T_F = 1/f": [], "JL, T_F = damped period": [],
                                   "damped jerk": []}
    for z in zeta:
        p = -z * w + 1j * w * np.sqrt(1 - z * z)
        for name, T in (("JL, T_F = 1/f", 1.0 / f),
                        ("JL, T_F = damped period", 1.0 / (f * np.sqrt(1 - z * z)))):
            M = -np.expm1(-p * T) / (p * T)
            out[name].append(100 * abs(M * np.exp(p * T)))
        out["damped jerk"].append(100 * DampedJerkFilter(f, float(z)).residual_ratio(f))
    return DampingSweep(zeta, {k: np.array(v) for k, v in out.items()})


def build_damped_jerk(ctx: PeerContext, name: str) -> tuple[DampedJerkMotion, PeerSpec]:
    """Peer "damped jerk": the generator's AL profile through the damped-jerk filter.

    The filter is designed for the tuned mode at the end of the motion.
    """
    flt = DampedJerkFilter(ctx.f_end, ctx.zeta)
    mot = DampedJerkMotion.from_al(ctx.base("AL"), flt, name=name)
    return mot, PeerSpec(name, f"{ctx.mode_text}; jerk time {flt.T * 1e3:.0f} ms",
                         {"f": ctx.f_end, "zeta": ctx.zeta, "T": flt.T})
