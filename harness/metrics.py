"""Performance metrics of a positioning move, on plain arrays.

The quantities of Table 1 and Table 2 of Béarée & Olabi 2013 (§4):

* residual vibration — the amplitude of the free oscillation when the
  reference ends, summed over the modes (:func:`residual_amplitude`, i.e.
  :func:`harness.plant.free_amplitude` of each mode's state then); the sampled
  peak |ε| after the end of the reference (:func:`residual_peak`) is kept as a
  secondary, phase-dependent figure;
* settling time — from the start of the motion until the load enters, and stays
  in, a band around the target (:func:`settling_time`); the band is one for
  every profile of a case (:class:`SettleBand`: metres, a fraction of AL's
  residual, or the paper's band, DJL's residual);
* motion time — the reference's duration, the paper's "theoretical rise time"
  (:func:`motion_time`);
* rise time — from the start until the load first reaches the target
  (:func:`rise_time`);
* Table 2 statistics of one profile against another (:func:`change_percent`,
  :func:`table2_stats`).

Crossing times are interpolated linearly between samples.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from .plant import Mode, free_amplitude

__all__ = [
    "DEFAULT_SETTLE_BAND",
    "SettleBand",
    "Table2Stats",
    "change_percent",
    "motion_time",
    "parse_settle_band",
    "percent_of",
    "residual_amplitude",
    "residual_peak",
    "rise_time",
    "settling_time",
    "table2_stats",
]


def _check(t: np.ndarray, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    t = np.asarray(t, dtype=float)
    y = np.asarray(y, dtype=float)
    if t.ndim != 1 or t.shape != y.shape or t.size < 2:
        raise ValueError("t and the signal must be 1-D arrays of the same length (>= 2)")
    return t, y


def residual_amplitude(states: Iterable[tuple[float, float]], modes: Iterable[Mode]) -> float:
    """Residual vibration: the free-oscillation amplitude when the reference ends.

    Once the reference has ended (q̈ = 0), each mode oscillates freely,
    ε(τ) = e^{-ζωτ}[ε cos ω_d τ + (ε̇ + ζωε)/ω_d sin ω_d τ]; its amplitude is
    √(ε² + ((ε̇ + ζωε)/ω_d)²) (:func:`harness.plant.free_amplitude`).  The
    residual vibration is the sum over the modes: for one mode, the envelope
    of |ε| after the motion; for several, an upper bound of |Σε|.

    Parameters
    ----------
    states : iterable of (float, float)
        (ε, ε̇) of each mode when the reference ends (m, m/s).
    modes : iterable of Mode
        Each mode at that instant (its frequency then).

    Returns
    -------
    float
        Σ amplitudes (m).
    """
    return float(sum(free_amplitude(float(e), float(de), m)
                     for (e, de), m in zip(states, modes, strict=True)))


def residual_peak(t: np.ndarray, eps: np.ndarray, t_end: float) -> float:
    """Largest sampled |ε| at or after the end of the reference.

    Secondary figure (the residual vibration is :func:`residual_amplitude`):
    with light damping the first peak after ``t_end`` comes up to half a
    period later, so this is up to e^{-πζ/√(1-ζ²)} below the free-oscillation
    amplitude, depending on the phase of the oscillation at ``t_end``, and it
    depends on where the samples fall.

    Parameters
    ----------
    t : ndarray
        Sample times (s).
    eps : ndarray
        Deflection (m).
    t_end : float
        End of the reference motion (s).

    Returns
    -------
    float
        max |ε(t)| for t ≥ t_end (m); NaN if no sample is at or after t_end.
    """
    t, eps = _check(t, eps)
    sel = t >= t_end - 1e-9 * max(1.0, abs(t_end))
    if not sel.any():
        return math.nan
    return float(np.max(np.abs(eps[sel])))


def settling_time(t: np.ndarray, error: np.ndarray, band: float, t_start: float = 0.0) -> float:
    """Time from ``t_start`` until |error| enters the band for good.

    Parameters
    ----------
    t : ndarray
        Sample times (s).
    error : ndarray
        Load position minus target (m).
    band : float
        Half-width of the band (m), > 0.
    t_start : float
        Start of the motion (s).

    Returns
    -------
    float
        Settling time (s), measured from ``t_start``; the last exit is located
        by linear interpolation between samples.  0 if the error stays in the
        band from ``t_start`` on; NaN if it is still outside at the last sample
        (not settled within the record).
    """
    t, error = _check(t, error)
    if not band > 0:
        raise ValueError(f"band must be > 0, got {band!r}")
    sel = t >= t_start - 1e-12
    tt, ee = t[sel], np.abs(error[sel])
    out = np.flatnonzero(ee > band)
    if out.size == 0:
        return 0.0
    k = int(out[-1])
    if k == tt.size - 1:
        return math.nan
    # |e| crosses the band between samples k (outside) and k + 1 (inside)
    e0, e1 = ee[k], ee[k + 1]
    frac = (e0 - band) / (e0 - e1) if e0 != e1 else 1.0
    return float(tt[k] + frac * (tt[k + 1] - tt[k]) - t_start)


def rise_time(t: np.ndarray, position: np.ndarray, target: float, t_start: float = 0.0,
              start: float | None = None) -> float:
    """Time from ``t_start`` until the load first reaches the target position.

    Parameters
    ----------
    t : ndarray
        Sample times (s).
    position : ndarray
        Load position q + ε (m).
    target : float
        Target position (m).
    t_start : float
        Start of the motion (s).
    start : float, optional
        Start position (default: the position at ``t_start``); gives the
        direction of the move.

    Returns
    -------
    float
        Rise time (s), interpolated linearly between samples; NaN if the target
        is never reached.
    """
    t, position = _check(t, position)
    sel = t >= t_start - 1e-12
    tt, pp = t[sel], position[sel]
    x0 = float(pp[0]) if start is None else float(start)
    sgn = 1.0 if target >= x0 else -1.0
    s = sgn * (pp - target)  # < 0 before the target, >= 0 once reached
    hit = np.flatnonzero(s >= 0.0)
    if hit.size == 0:
        return math.nan
    k = int(hit[0])
    if k == 0:
        return float(tt[0] - t_start)
    s0, s1 = s[k - 1], s[k]
    frac = -s0 / (s1 - s0)
    return float(tt[k - 1] + frac * (tt[k] - tt[k - 1]) - t_start)


def motion_time(t: np.ndarray, x_ref: np.ndarray, v_ref: np.ndarray, t_start: float = 0.0,
                tol: float = 1e-9) -> float:
    """Duration of a reference motion: until it rests at its final position.

    Parameters
    ----------
    t : ndarray
        Sample times (s).
    x_ref, v_ref : ndarray
        Reference position (m) and velocity (m/s).
    t_start : float
        Start of the motion (s).
    tol : float
        Tolerance on position (m) and velocity (m/s).

    Returns
    -------
    float
        Time from ``t_start`` to the first sample after which the reference
        stays at its last position with zero velocity (s); NaN if it is still
        moving at the last sample.
    """
    t, x_ref = _check(t, x_ref)
    v_ref = np.asarray(v_ref, dtype=float)
    moving = (np.abs(x_ref - x_ref[-1]) > tol) | (np.abs(v_ref) > tol)
    idx = np.flatnonzero(moving)
    if idx.size == 0:
        return 0.0
    k = int(idx[-1])
    if k == t.size - 1:
        return math.nan
    return float(t[k + 1] - t_start)


def percent_of(value: float, reference: float) -> float:
    """``value`` as a percentage of ``reference`` (Table 1: "% of AL")."""
    return 100.0 * value / reference if reference else math.nan


def change_percent(value: float, reference: float) -> float:
    """Relative change in % (Table 2: DJL "in % as compared to JL", negative = better)."""
    return 100.0 * (value - reference) / reference if reference else math.nan


PAPER_BAND_LABEL = "the paper's band: DJL's residual"
"""How the paper's settling band (Table 2) is labelled wherever it is printed."""

_FRACTION_OF_AL = re.compile(r"^\s*([0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)\s*%\s*of\s+AL\s*$",
                             re.IGNORECASE)


@dataclass(frozen=True)
class SettleBand:
    """The settling band of a case: one half-width shared by every profile.

    Attributes
    ----------
    kind : {"m", "AL", "paper"}
        ``"m"``: a fixed half-width in metres (a machine tolerance);
        ``"AL"``: a fraction of AL's residual vibration in the same case;
        ``"paper"``: DJL's residual vibration, the band of the paper's Table 2
        (self-referential: DJL is inside it as soon as its motion ends).
    value : float
        The half-width (m) for ``"m"``, the fraction (0 < value <= 1) for
        ``"AL"``; unused (NaN) for ``"paper"``.
    """

    kind: str
    value: float = math.nan

    def __post_init__(self) -> None:
        if self.kind == "m":
            if not (math.isfinite(self.value) and self.value > 0):
                raise ValueError(f"a settling band in m must be > 0, got {self.value!r}")
        elif self.kind == "AL":
            if not (math.isfinite(self.value) and 0 < self.value <= 1):
                raise ValueError(f"a fraction of AL's residual must be in (0, 100] %, "
                                 f"got {100 * self.value!r} %")
        elif self.kind != "paper":
            raise ValueError(f"unknown settling band kind {self.kind!r} (m, AL or paper)")

    @property
    def needs(self) -> str | None:
        """The profile whose residual the band is made of (``"AL"``, ``"DJL"``), or None."""
        return {"AL": "AL", "paper": "DJL"}.get(self.kind)

    def __str__(self) -> str:
        """Return the band as written in a scenario file (``settle_band = ...``)."""
        if self.kind == "paper":
            return "paper"
        if self.kind == "AL":
            return f"{100 * self.value:g} % of AL"
        return f"{self.value:g}"

    @property
    def label(self) -> str:
        """Human-readable source of the band, printed with every settling time."""
        if self.kind == "paper":
            return PAPER_BAND_LABEL
        if self.kind == "AL":
            return f"band: {100 * self.value:g} % of AL's residual"
        return f"band: +/-{self.value * 1e3:.3g} mm, given in the scenario"

    def resolve(self, residuals: Mapping[str, float]) -> float:
        """Half-width of the band (m) in one case.

        Parameters
        ----------
        residuals : mapping of str to float
            Residual vibration of the profiles run in the case (m), by name.

        Returns
        -------
        float
            The band (m).

        Raises
        ------
        ValueError
            If the band is made of a profile's residual and that profile is
            missing.
        """
        if self.kind == "m":
            return float(self.value)
        need = self.needs
        if need not in residuals:
            raise ValueError(f"settling band '{self}' needs the residual of {need}, which was "
                             f"not run (profiles: {', '.join(residuals)})")
        r = float(residuals[need])  # type: ignore[index]
        return r * self.value if self.kind == "AL" else r

    def half_width(self, residuals: Mapping[str, float]) -> tuple[float, bool]:
        """Return the band (m) of one case, never zero, and whether it fell back to 1 nm.

        A band made of a residual of exactly 0 (an undamped move that leaves
        none) would make every settling time that of the last touch of the
        target: it falls back to :data:`NO_BAND` (1 nm), and the second value
        says so (the labels then add "zero, so 1 nm").
        """
        band = self.resolve(residuals)
        if band > 0:
            return band, False
        return NO_BAND, True


NO_BAND = 1e-9
"""The band used when the one asked for is zero (a residual of exactly 0): 1 nm."""

ZERO_BAND_NOTE = "; zero, so 1 nm"
"""What a band's label adds when it fell back to :data:`NO_BAND`."""

DEFAULT_SETTLE_BAND = SettleBand("AL", 0.01)
"""Default settling band: 1 % of AL's residual vibration in the same case."""


def parse_settle_band(value: object) -> SettleBand:
    """Read a settling band as written in a scenario file.

    Parameters
    ----------
    value : float or str
        A half-width in m (a number > 0), ``"paper"`` (DJL's residual, the
        paper's Table 2 band) or ``"P % of AL"`` / ``"P% of AL"`` (P in
        (0, 100]: that fraction of AL's residual).

    Returns
    -------
    SettleBand

    Raises
    ------
    ValueError
        With the reason, if ``value`` is none of these.
    """
    if isinstance(value, SettleBand):
        return value
    if isinstance(value, bool):
        raise ValueError("must be a number (m), \"paper\" or \"P % of AL\"")
    if isinstance(value, (int, float)):
        v = float(value)
        if not (math.isfinite(v) and v > 0):
            raise ValueError("a settling band in m must be a finite number > 0")
        return SettleBand("m", v)
    if isinstance(value, str):
        if value.strip().lower() == "paper":
            return SettleBand("paper")
        m = _FRACTION_OF_AL.match(value)
        if m:
            p = float(m.group(1))
            if not 0 < p <= 100:
                raise ValueError("the percentage of AL's residual must be in (0, 100]")
            return SettleBand("AL", p / 100.0)
    raise ValueError("must be a number (m, > 0), \"paper\" (DJL's residual: the paper's "
                     "band) or \"P % of AL\" (P in (0, 100])")


@dataclass
class Table2Stats:
    """Statistics of relative changes, as in Table 2 of the paper.

    Attributes
    ----------
    mean : float
        Mean change (%).
    max : float
        Largest reduction, i.e. the most negative change (%): the paper's "Max".
    min : float
        Smallest reduction, i.e. the least negative change (%): the paper's "Min".
    std : float
        Sample standard deviation (%), ddof = 1.
    n : int
        Number of cases.
    """

    mean: float
    max: float
    min: float
    std: float
    n: int


def table2_stats(changes: Sequence[float] | np.ndarray) -> Table2Stats:
    """Mean, largest / smallest reduction and standard deviation of changes in %.

    Parameters
    ----------
    changes : sequence of float
        Relative changes in % (e.g. :func:`change_percent` of DJL vs JL); NaNs
        are ignored.

    Returns
    -------
    Table2Stats
    """
    c = np.asarray(changes, dtype=float)
    c = c[np.isfinite(c)]
    if c.size == 0:
        return Table2Stats(math.nan, math.nan, math.nan, math.nan, 0)
    std = float(np.std(c, ddof=1)) if c.size > 1 else 0.0
    return Table2Stats(float(np.mean(c)), float(np.min(c)), float(np.max(c)), std, int(c.size))
