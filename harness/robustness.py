"""Robustness to a mode-map error, in the time-varying plant.

The jerk times of JL and DJL are tuned on the mode map f(z) of the scenario; on
the machine the map is only known to some accuracy.  Here the whole map is off
by a factor: the plant's every f(z) becomes (1 + e)·f(z)
(:meth:`harness.modemap.ModeMap.scaled`), while each profile keeps the jerk
times tuned on the nominal map, and the Z axis moves as in the scenario (the
mode keeps moving during the motion: the time-varying plant).  The residual
vibration of each profile (the free-oscillation amplitude when the reference
ends, :func:`harness.metrics.residual_amplitude`) is computed for each e:

* :func:`map_error_residuals` — one profile, an array of errors;
* :func:`robustness` — every profile: a :class:`RobustnessResult` with the
  curves, the worst case over ±10 % (:meth:`RobustnessResult.worst`), CSV rows
  and a figure.

This is not the stationary-mode check of :mod:`harness.peers.compare`
(``djl-fmu compare``), where a single mode of *constant* frequency is off from
the one the jerk times were tuned to; here Z moves and the whole f(z) map is
scaled.

Examples
--------
>>> from harness.cosim import Session
>>> from harness.robustness import robustness
>>> from harness.scenario import load_scenario
>>> sc = load_scenario("X")                                         # doctest: +SKIP
>>> with Session() as s:                                            # doctest: +SKIP
...     T = {p: s.tune(sc, p) for p in ("AL", "JL", "DJL")}
...     rob = robustness(sc, s, T)
>>> rob.worst()                                                     # doctest: +SKIP
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from .tuning import TuningResult

if TYPE_CHECKING:
    from .cosim import Session
    from .scenario import Scenario

__all__ = [
    "DEFAULT_ERRORS",
    "WORST_ERRORS",
    "WORST_SPAN",
    "RobustnessResult",
    "map_error_residuals",
    "robustness",
    "t_stop_after_motion",
]

DEFAULT_ERRORS = np.linspace(-0.2, 0.2, 41)
"""Map errors of the curves: −20 % to +20 %, 1 % apart."""

WORST_SPAN = 0.10
"""Span of the worst case: map errors within ±10 %."""

WORST_ERRORS = np.linspace(-WORST_SPAN, WORST_SPAN, 21)
"""Map errors of the worst case alone: −10 % to +10 %, 1 % apart (a subset of the curves')."""


def t_stop_after_motion(sc: Scenario, session: Session, profile: str,
                        T_F: Sequence[float] | None) -> float:
    """End of a run that only needs the state when the excited axis' reference ends (s).

    The first communication point at or after the end of the motion, plus one
    step: the residual (the state at the end of the reference) is then in the
    record, and nothing after it is simulated.

    Parameters
    ----------
    sc : Scenario
        The scenario (its move and simulation settings).
    session : Session
        Its generator instances (the excited axis' is re-planned here).
    profile : str
        ``AL``, ``JL`` or ``DJL``.
    T_F : sequence of 4 float, optional
        Jerk times (s); None for AL.

    Returns
    -------
    float
        Stop time (s).
    """
    T_x = session.axis.plan(session.move_params(sc, profile, T_F))
    return sc.move.t_start + T_x + sc.simulation.step


def _jerk(profile: str, value: Any) -> tuple[float, float, float, float] | None:
    if isinstance(value, TuningResult):
        return tuple(value.T_F)  # type: ignore[return-value]
    if value is None:
        if profile != "AL":
            raise ValueError(f"{profile}: jerk times are needed (only AL has none)")
        return None
    if isinstance(value, (int, float)):
        return (float(value),) * 4
    T = tuple(float(x) for x in value)
    if len(T) != 4:
        raise ValueError(f"{profile}: four jerk times are needed, got {T!r}")
    return T  # type: ignore[return-value]


def map_error_residuals(sc: Scenario, session: Session, profile: str,
                        T_F: Sequence[float] | None,
                        errors: Sequence[float] | np.ndarray) -> np.ndarray:
    """Residual vibration of one profile for each map error e.

    The profile is run with the jerk times ``T_F`` (tuned on the nominal map)
    on the scenario whose mode map is ``sc.modemap.scaled(1 + e)``, Z moving as
    in the scenario, and stopped just past the end of the motion
    (:func:`t_stop_after_motion`): the residual is the free-oscillation
    amplitude when the reference ends.  If the session has a method
    ``map_error_residuals(sc, profile, T_F, factors)`` (a vectorised engine),
    it is used instead, with ``factors = 1 + errors``.

    Parameters
    ----------
    sc : Scenario
        The nominal scenario (single move).
    session : Session
        Generator instances.
    profile : str
        ``AL``, ``JL`` or ``DJL``.
    T_F : sequence of 4 float, optional
        Jerk times (s), None for AL.
    errors : array_like
        Relative map errors e (> −1; e.g. −0.2 … 0.2).

    Returns
    -------
    ndarray
        Residual (m) for each error, shape of ``errors`` flattened.

    Raises
    ------
    ValueError
        If an error is not finite or ≤ −1 (a frequency ≤ 0).
    """
    e = np.asarray(errors, dtype=float).ravel()
    if not np.all(np.isfinite(e)) or np.any(e <= -1.0):
        raise ValueError(f"map errors must be finite and > -1, got {e!r}")
    factors = 1.0 + e
    vectorised = getattr(session, "map_error_residuals", None)
    if callable(vectorised):
        return np.asarray(vectorised(sc, profile, T_F, factors), dtype=float).ravel()
    t_stop = t_stop_after_motion(sc, session, profile, T_F)
    out = np.empty(e.size)
    for i, k in enumerate(factors.tolist()):
        sck = dataclasses.replace(sc, modemap=sc.modemap.scaled(k))
        out[i] = session.run(sck, profile, T_F, t_stop=t_stop).free_amplitude
    return out


@dataclass
class RobustnessResult:
    """Residual of each profile against a map error, in the time-varying plant.

    Attributes
    ----------
    errors : ndarray
        Map errors e (the whole f(z) map scaled by 1 + e).
    residual : dict of str to ndarray
        Residual vibration (m) of each profile at each error.
    scenario : Scenario, optional
        The nominal scenario.
    T_F : dict of str to tuple
        Jerk times of each profile (s), tuned on the nominal map (None for AL).
    """

    errors: np.ndarray
    residual: dict[str, np.ndarray]
    scenario: Any = None
    T_F: dict[str, tuple[float, ...] | None] = field(default_factory=dict)

    @property
    def label(self) -> str:
        """What was varied, printed with the curves and the worst cases."""
        still = self.scenario is not None and not self.scenario.z.moves
        plant = "plant with Z still" if still else "time-varying plant (Z moving)"
        return f"{plant}, whole map scaled by 1 + e"

    def worst(self, span: float = WORST_SPAN) -> dict[str, float]:
        """Largest residual of each profile over the errors within ±``span`` (m).

        The maximum over the grid points with |e| ≤ span (1e-12 tolerance).

        Raises
        ------
        ValueError
            If no grid point lies within the span.
        """
        sel = np.abs(self.errors) <= span + 1e-12
        if not sel.any():
            raise ValueError(f"no map error within +/-{span:g} in {self.errors!r}")
        return {p: float(np.max(r[sel])) for p, r in self.residual.items()}

    def nominal(self) -> dict[str, float]:
        """Residual of each profile on the nominal map, e = 0 (m); NaN if 0 is not a point."""
        k = np.flatnonzero(np.abs(self.errors) <= 1e-12)
        return {p: float(r[k[0]]) if k.size else math.nan for p, r in self.residual.items()}

    def rows(self) -> list[dict[str, Any]]:
        """CSV rows: one per profile and error.

        ``residual_pct_of_AL`` compares with AL at the same map error.
        """
        name = self.scenario.name if self.scenario is not None else ""
        al = self.residual.get("AL")
        out = []
        for p, r in self.residual.items():
            for i, e in enumerate(self.errors.tolist()):
                out.append({
                    "scenario": name, "plant": self.label, "profile": p, "map_error": e,
                    "frequency_factor": 1.0 + e, "residual_m": float(r[i]),
                    "residual_pct_of_AL": (100.0 * float(r[i]) / float(al[i])
                                           if al is not None and al[i] > 0 else math.nan),
                })
        return out

    def plot(self, title: str | None = None, span: float = WORST_SPAN):
        """Residual against map error, one curve per profile, the ±``span`` band shaded.

        Returns
        -------
        matplotlib.figure.Figure
        """
        import matplotlib.pyplot as plt

        from .results import COLORS

        fig, ax = plt.subplots(figsize=(9, 5.5))
        x = 100.0 * self.errors
        ax.axvspan(-100 * span, 100 * span, color="0.88", lw=0,
                   label=f"+/-{100 * span:g} % (worst case)")
        try:
            worst = self.worst(span)
        except ValueError:
            worst = {}
        for p, r in self.residual.items():
            lab = p
            if p in worst:
                lab += f": worst over +/-{100 * span:g} % {worst[p] * 1e3:.3g} mm"
            ax.semilogy(x, np.maximum(r * 1e3, 1e-9), marker=".", color=COLORS.get(p), label=lab)
        ax.axvline(0.0, color="k", lw=0.6)
        ax.set_xlabel("map error e [%]: every f(z) of the plant x (1 + e); jerk times tuned "
                      "on the nominal map")
        ax.set_ylabel("residual vibration [mm]\n(free-oscillation amplitude at the end)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize="small")
        name = self.scenario.name if self.scenario is not None else ""
        ax.set_title(title or f"{name}: robustness to a map error, {self.label}",
                     fontsize="medium")
        fig.tight_layout()
        return fig


def robustness(sc: Scenario, session: Session,
               profiles: Mapping[str, TuningResult | Sequence[float] | float | None],
               errors: Sequence[float] | np.ndarray = DEFAULT_ERRORS) -> RobustnessResult:
    """Residual of every profile against a map error (the whole f(z) scaled by 1 + e).

    Parameters
    ----------
    sc : Scenario
        The nominal scenario (single move).
    session : Session
        Generator instances.
    profiles : mapping
        Profile name → its jerk times tuned on the nominal map: a
        :class:`~harness.tuning.TuningResult`, four jerk times (s), one JL jerk
        time (s), or None (AL only).
    errors : array_like
        Map errors e (default −20 % … +20 %, 41 points).

    Returns
    -------
    RobustnessResult
    """
    e = np.asarray(errors, dtype=float).ravel()
    T = {p: _jerk(p, v) for p, v in profiles.items()}
    res = {p: map_error_residuals(sc, session, p, T_F, e) for p, T_F in T.items()}
    return RobustnessResult(e, res, sc, T)
