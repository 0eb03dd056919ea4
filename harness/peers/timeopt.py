"""How much slower than time-optimal the FIR-built JL and DJL profiles are.

The generator builds JL by filtering an acceleration-limited (AL) profile with
a moving average of ``T_F`` (Béarée & Olabi 2013, §2.1).  With
``T_F = a_max / j_max`` the jerk never exceeds ``j_max`` and, when the move
reaches both ``v_max`` and ``a_max``, the result has the structure of the
time-optimal jerk-limited profile: its duration is the AL duration plus
``T_F``, that of the time-optimal profile (Park et al.'s Case I:
``T = P/V + V/A + A/J``).

This module measures it on moves of every kind against ruckig (continuous
time, and ruckig's duration rounded up to the sampling grid), per case of
Park et al. (:func:`harness.peers.park.select_case`):

* I   v_max and a_max reached,
* II  a_max only,
* III neither,
* IV  v_max only (``v_max < a_max² / j_max``).

The generator plans on whole samples, so its motion time is a multiple of
``Te``; the best any such generator can do is the time-optimal duration
rounded up to a sample.  ``excess`` below is measured against the continuous
time-optimal duration (``excess_discrete`` against the rounded-up one).

DJL is compared with the time-optimal profile under the same ``v_max``,
``a_max`` and the DJL's own largest jerk ``a_max / min(T_Fi)``.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from tqdm import tqdm

from ..fmu.build import default_fmu
from ..fmu.runner import GeneratorFMU
from .park import select_case
from .ruckig_ref import time_optimal

METHODS = ("JL", "JL overlap", "DJL")
"""``JL``: profile 2 with the default short-stage rule (stretch); ``JL overlap``:
profile 2 with the paper's rule (``short_stage = 2``); ``DJL``: profile 3 with
four jerk times drawn in [1, 2] x a_max/j_max."""


@dataclass(frozen=True)
class MoveComparison:
    """One move planned by the generator and by ruckig.

    Attributes
    ----------
    method : str
        ``"JL"``, ``"JL overlap"`` or ``"DJL"``.
    distance, v_max, a_max : float
        The move (m, m/s, m/s²); ``d_max = a_max``.
    T_F : tuple of 4 float
        Jerk times given to the FMU (s).
    j_max : float
        Jerk limit of the time-optimal reference, ``a_max / min(T_F)`` (m/s³).
    Te : float
        Sampling period (s).
    case : str
        Park et al.'s case of the time-optimal move.
    T_opt : float
        ruckig's time-optimal duration (s).
    T_opt_discrete : float
        ruckig's duration rounded up to a multiple of ``Te`` (s): the shortest
        motion time on the sampling grid.
    T_fmu : float
        The FMU's motion time (s).
    """

    method: str
    distance: float
    v_max: float
    a_max: float
    T_F: tuple[float, float, float, float]
    j_max: float
    Te: float
    case: str
    T_opt: float
    T_opt_discrete: float
    T_fmu: float

    @property
    def excess(self) -> float:
        """``T_fmu - T_opt`` (s)."""
        return self.T_fmu - self.T_opt

    @property
    def excess_samples(self) -> float:
        """``(T_fmu - T_opt) / Te``."""
        return self.excess / self.Te

    @property
    def excess_discrete_samples(self) -> float:
        """``(T_fmu - T_opt_discrete) / Te`` (an integer up to rounding)."""
        return (self.T_fmu - self.T_opt_discrete) / self.Te

    @property
    def excess_percent(self) -> float:
        """``100 (T_fmu / T_opt - 1)``."""
        return 100.0 * (self.T_fmu / self.T_opt - 1.0)


def fmu_motion_time(params: dict[str, Any], fmu: Any = None) -> float:
    """Motion time the generator FMU plans for ``params`` (s), without stepping it."""
    path = fmu or default_fmu(2)
    with GeneratorFMU(path, params=params) as g:
        g.initialize()
        return float(g.get("motion_time"))


def compare_move(distance: float, v_max: float, a_max: float,
                 T_F: float | Sequence[float], *, Te: float = 1e-3, method: str = "JL",
                 fmu: Any = None) -> MoveComparison:
    """Plan one move with the FMU and with ruckig.

    Parameters
    ----------
    distance, v_max, a_max : float
        The move; ``d_max = a_max``.
    T_F : float or sequence of 4 float
        Jerk time(s); JL uses the first.  Whole multiples of ``Te`` keep the
        jerk exactly at ``a_max / T_F``.
    Te : float
        Sampling period (s).
    method : {"JL", "JL overlap", "DJL"}
    fmu : path-like, optional
        A generator FMU file (default: the package's FMI 2.0 build).
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    TF = tuple(float(x) for x in np.broadcast_to(np.asarray(T_F, dtype=float), (4,)))
    if method != "DJL":
        TF = (TF[0],) * 4
    params = {"profile": 3 if method == "DJL" else 2, "short_stage": 2 if method == "JL overlap"
              else 1, "distance": distance, "v_max": v_max, "a_max": a_max, "d_max": a_max,
              "Te": Te, "T_F1": TF[0], "T_F2": TF[1], "T_F3": TF[2], "T_F4": TF[3]}
    T_fmu = fmu_motion_time(params, fmu)
    j_max = a_max / min(TF)
    r = time_optimal(distance, v_max, a_max, j_max)
    # a rest-to-rest move can always be slowed down: the best duration on the
    # grid is the time-optimal one rounded up to a sample
    T_disc = float(np.ceil(r.duration / Te - 1e-9) * Te)
    return MoveComparison(method, distance, v_max, a_max, TF, j_max, Te,
                          select_case(distance, v_max, a_max, j_max), r.duration, T_disc, T_fmu)


def random_move(rng: np.random.Generator, Te: float = 1e-3, case: str | None = None
                ) -> tuple[float, float, float, int]:
    """Draw a random move ``(distance, v_max, a_max, N_F)``, ``T_F = N_F Te = a_max / j_max``.

    ``a_max`` in [1, 20] m/s², ``N_F`` in [5, 100] samples, ``v_max`` from 0.2 to
    7 times ``a_max T_F``, the distance log-uniform around the case thresholds;
    with ``case`` given, draws until the move is of that case.
    """
    for _ in range(10000):
        a = float(rng.uniform(1.0, 20.0))
        N = int(rng.integers(5, 101))
        TF = N * Te
        j = a / TF
        v = float(a * TF * np.exp(rng.uniform(-1.6, 2.0)))
        dref = max(v * (v / a + a / j), 2 * a ** 3 / j ** 2)
        d = float(dref * np.exp(rng.uniform(-4.0, 1.5)))
        if case is None or select_case(d, v, a, j) == case:
            return d, v, a, N
    raise RuntimeError(f"could not draw a move of case {case}")  # pragma: no cover


@dataclass
class TimeOptTable:
    """Measured excess over the time-optimal duration, per method and case.

    Attributes
    ----------
    rows : list of MoveComparison
    """

    rows: list[MoveComparison] = field(default_factory=list)

    def summary(self) -> list[dict[str, Any]]:
        """One dict per (method, case): counts, median / max excess (samples, %)."""
        out = []
        for m in dict.fromkeys(r.method for r in self.rows):
            for c in ("I", "II", "III", "IV"):
                rs = [r for r in self.rows if r.method == m and r.case == c]
                if not rs:
                    continue
                ex = np.array([r.excess_samples for r in rs])
                exd = np.array([r.excess_discrete_samples for r in rs])
                pc = np.array([r.excess_percent for r in rs])
                out.append({
                    "method": m, "case": c, "n": len(rs),
                    "excess_samples_median": float(np.median(ex)),
                    "excess_samples_max": float(ex.max()),
                    "excess_samples_min": float(ex.min()),
                    "within_1_sample": float(np.mean(ex <= 1.0 + 1e-9)),
                    "over_discrete_max": float(np.round(exd.max(), 6)),
                    "excess_percent_median": float(np.median(pc)),
                    "excess_percent_max": float(pc.max()),
                })
        return out

    def to_text(self) -> str:
        """Format the summary as a fixed-width table."""
        head = (f"{'method':<11} {'case':<4} {'n':>4}  {'excess [samples] med / max':>27}  "
                f"{'<=1 sample':>10}  {'over rounded-up opt. max':>24}  "
                f"{'excess [%] med / max':>21}")
        lines = [head, "-" * len(head)]
        for s in self.summary():
            lines.append(
                f"{s['method']:<11} {s['case']:<4} {s['n']:>4}  "
                f"{s['excess_samples_median']:>12.2f} / {s['excess_samples_max']:<12.2f}  "
                f"{100 * s['within_1_sample']:>9.0f}%  "
                f"{s['over_discrete_max']:>24.0f}  "
                f"{s['excess_percent_median']:>9.2f} / {s['excess_percent_max']:<9.2f}")
        return "\n".join(lines)

    def plot(self, title: str | None = None):
        """Excess (% of the time-optimal duration) against the distance, per method and case."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        methods = list(dict.fromkeys(r.method for r in self.rows))
        fig, axes = plt.subplots(1, len(methods), figsize=(5 * len(methods), 4), squeeze=False)
        for ax, m in zip(axes[0], methods, strict=True):
            for c, mk in zip(("I", "II", "III", "IV"), "o^sD", strict=True):
                rs = [r for r in self.rows if r.method == m and r.case == c]
                if rs:
                    ax.semilogx([r.distance for r in rs], [r.excess_percent for r in rs], mk,
                                ms=4, label=f"case {c}", alpha=0.7)
            ax.set_xlabel("distance [m]")
            ax.set_ylabel("motion time over time-optimal [%]")
            ax.set_title(m)
            ax.grid(True, alpha=0.3)
            ax.legend(fontsize="small")
        fig.suptitle(title or "FIR-built profiles against the time-optimal JL (ruckig)")
        fig.tight_layout()
        return fig


def measure(n_per_case: int = 50, *, seed: int = 0, Te: float = 1e-3,
            methods: Iterable[str] = METHODS, cases: Iterable[str] = ("I", "II", "III", "IV"),
            fmu: Any = None, progress: bool | None = None) -> TimeOptTable:
    """Random moves of each case through each method; see :class:`TimeOptTable`.

    Parameters
    ----------
    n_per_case : int
        Moves drawn per case (the same moves for every method).
    seed : int
        Random seed.
    Te : float
        Sampling period (s).
    methods, cases
        Subsets of :data:`METHODS` and of the cases.
    fmu : path-like, optional
        Generator FMU file.
    progress : bool, optional
        Show a tqdm bar (default: when stderr is a terminal).
    """
    rng = np.random.default_rng(seed)
    methods = tuple(methods)
    moves = []
    for c in cases:
        for _ in range(n_per_case):
            d, v, a, N = random_move(rng, Te, c)
            ratios = rng.uniform(1.0, 2.0, 4)
            ratios[rng.integers(0, 4)] = 1.0  # the largest jerk is a_max / T_F
            moves.append((d, v, a, N, ratios))
    show = sys.stderr.isatty() if progress is None else progress
    table = TimeOptTable()
    for d, v, a, N, ratios in tqdm(moves, disable=not show, desc="moves"):
        for m in methods:
            T_F = N * Te * (np.round(ratios * N) / N if m == "DJL" else np.ones(4))
            table.rows.append(compare_move(d, v, a, T_F, Te=Te, method=m, fmu=fmu))
    return table
