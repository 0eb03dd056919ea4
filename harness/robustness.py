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
  curves (by default over ±2·map_scale of the scenario's uncertainty,
  :meth:`~harness.uncertainty.UncertaintySpec.curve_errors`), the worst case
  over ±map_scale (:meth:`RobustnessResult.worst`), CSV rows and a figure
  shading that span.

This is not the stationary-mode check of :mod:`harness.peers.compare`
(``djl-fmu compare``), where a single mode of *constant* frequency is off from
the one the jerk times were tuned to; here Z moves and the whole f(z) map is
scaled.

Examples
--------
>>> from harness.robustness import robustness
>>> from harness.scenario import load_scenario
>>> from harness.simulation.session import Session
>>> from harness.tuning.tune import tune_profile
>>> sc = load_scenario("X")                                         # doctest: +SKIP
>>> with Session() as s:                                            # doctest: +SKIP
...     T = {p: tune_profile(s, sc, p) for p in ("AL", "JL", "DJL")}
...     rob = robustness(sc, s, T)
>>> rob.worst()                                                     # doctest: +SKIP
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .scenario import Scenario
from .simulation.plots import COLORS
from .simulation.session import Session
from .tuning.rule import TuningResult
from .uncertainty import DEFAULT_UNCERTAINTY, span_text

__all__ = [
    "RobustnessResult",
    "map_error_residuals",
    "robustness",
]

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

    The profile is planned with the jerk times ``T_F`` (tuned on the nominal
    map), Z moving as in the scenario; the plant is stepped to the end of the
    motion once per error with every frequency of the map multiplied by 1 + e
    (:meth:`harness.simulation.session.Session.map_error_residuals`): the
    residual is the free-oscillation amplitude when the reference ends.

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
    return session.map_error_residuals(sc, profile, T_F, errors)


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
    span : float, optional
        The worst case is over the errors within ±``span``: the map scale of the
        scenario's uncertainty (default: ``scenario.uncertainty.map_scale``; without
        a scenario, the default uncertainty's).
    """

    errors: np.ndarray
    residual: dict[str, np.ndarray]
    scenario: Any = None
    T_F: dict[str, tuple[float, ...] | None] = field(default_factory=dict)
    span: float | None = None

    def __post_init__(self) -> None:
        if self.span is None:
            unc = getattr(self.scenario, "uncertainty", DEFAULT_UNCERTAINTY)
            self.span = float(unc.map_scale)

    @property
    def label(self) -> str:
        """What was varied, printed with the curves and the worst cases."""
        still = self.scenario is not None and not self.scenario.z.moves
        plant = "plant with Z still" if still else "time-varying plant (Z moving)"
        return f"{plant}, whole map scaled by 1 + e"

    def worst(self, span: float | None = None) -> dict[str, float]:
        """Largest residual of each profile over the errors within ±``span`` (m).

        The maximum over the grid points with |e| ≤ span (1e-12 tolerance);
        ``span`` defaults to :attr:`span` (the run's map scale).

        Raises
        ------
        ValueError
            If no grid point lies within the span.
        """
        span = self.span if span is None else span
        assert span is not None
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

    def plot(self, title: str | None = None, span: float | None = None):
        """Residual against map error, one curve per profile, the ±``span`` band shaded.

        ``span`` defaults to :attr:`span` (the run's map scale).

        Returns
        -------
        matplotlib.figure.Figure
        """
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        span = self.span if span is None else span
        assert span is not None
        fig, ax = plt.subplots(figsize=(9, 7))
        x = 100.0 * self.errors
        ax.axvspan(-100 * span, 100 * span, color="0.88", lw=0,
                   label=f"+/-{span_text(span)} % (worst case)")
        try:
            worst = self.worst(span)
        except ValueError:
            worst = {}
        for p, r in self.residual.items():
            lab = p
            if p in worst:
                lab += f": worst over +/-{span_text(span)} % {worst[p] * 1e3:.3g} mm"
            ax.semilogy(x, np.maximum(r * 1e3, 1e-9), marker=".", color=COLORS.get(p), label=lab)
        ax.axvline(0.0, color="k", lw=0.6)
        ax.set_xlabel("map error e [%]: every f(z) of the plant x (1 + e); jerk times tuned "
                      "on the nominal map")
        ax.set_ylabel("residual vibration [mm]\n(free-oscillation amplitude at the end)")
        ax.grid(True, which="both", alpha=0.3)
        # below the axes: off the data
        ax.legend(fontsize="small", loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2,
                  frameon=False)
        name = self.scenario.name if self.scenario is not None else ""
        ax.set_title(title or f"{name}: robustness to a map error, {self.label}",
                     fontsize="medium")
        # fixed margins (for these labels at this size): no layout pass before the drawing
        fig.subplots_adjust(left=0.1, right=0.98, top=0.94, bottom=0.24)
        return fig


def robustness(sc: Scenario, session: Session,
               profiles: Mapping[str, TuningResult | Sequence[float] | float | None],
               errors: Sequence[float] | np.ndarray | None = None) -> RobustnessResult:
    """Residual of every profile against a map error (the whole f(z) scaled by 1 + e).

    Parameters
    ----------
    sc : Scenario
        The nominal scenario (single move).
    session : Session
        Generator instances.
    profiles : mapping
        Profile name → its jerk times tuned on the nominal map: a
        :class:`~harness.tuning.rule.TuningResult`, four jerk times (s), one JL jerk
        time (s), or None (AL only).
    errors : array_like, optional
        Map errors e (default: the scenario's uncertainty's curves, ±2·map_scale in
        41 points, :meth:`~harness.uncertainty.UncertaintySpec.curve_errors`:
        −20 % … +20 % with the default map scale).

    Returns
    -------
    RobustnessResult
        Its worst case is over ±map_scale of the scenario's uncertainty.
    """
    e = np.asarray(sc.uncertainty.curve_errors() if errors is None else errors,
                   dtype=float).ravel()
    T = {p: _jerk(p, v) for p, v in profiles.items()}
    res = {p: map_error_residuals(sc, session, p, T_F, e) for p, T_F in T.items()}
    return RobustnessResult(e, res, sc, T, span=sc.uncertainty.map_scale)
