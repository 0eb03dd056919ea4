"""What the real machine may differ by: the uncertainty the harness tunes and scores against.

A *map error* e scales the whole mode map: every frequency f(z) becomes
f(z)·(1 + e), the jerk times staying those tuned on the nominal map.  More
generally a :class:`Perturbation` also scales the map's slope, shifts it along
z and scales the damping; a scenario's ``[uncertainty]`` table
(:class:`UncertaintySpec`) gives the ranges, from which two deterministic sets
are drawn: the *tuning* set the robust methods minimise over, and the finer
*scoring* set every table reports (never the points a method was tuned on).

* :class:`UncertaintySpec` -- the ranges; the *only* home of the map scale
  (the relative error of the whole map): its tuning and scoring sets, and the
  map-error grids of the robustness curves (:meth:`UncertaintySpec.curve_errors`,
  ±2·map_scale) and of their worst case (:meth:`UncertaintySpec.worst_errors`,
  ±map_scale); :func:`span_text` writes that span in every label;
* :func:`parse_uncertainty`, :func:`uncertainty_items` -- the ``--uncertainty``
  grammar (``map_scale=0.1,map_slope=0.3,z_shift=0.05,damping=0.5:2``);
* :func:`resolve_alias`, :class:`DeprecatedAliasWarning` -- the earlier places
  of the map scale (``[compare] map_error``, ``--map-error``), read once as
  deprecated aliases, a disagreement refused;
* :func:`check_map_error` -- a bound ``map_error`` in [0, 1) (tuning, tables);
* :func:`check_map_errors` -- errors e, finite and > −1 (a frequency > 0);
* :func:`width_sweeps`, :class:`WidthSweep`, :func:`level`, :func:`scaled_uncertainty` --
  the actual error wider than stated: each kind alone and the whole box, out to
  twice the stated ranges, every point with its width (1 = the stated edge).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .errors import DeprecatedAliasWarning

__all__ = [
    "DEFAULT_UNCERTAINTY",
    "KINDS",
    "DeprecatedAliasWarning",
    "Perturbation",
    "UncertaintySet",
    "UncertaintySpec",
    "WidthSweep",
    "check_map_error",
    "check_map_errors",
    "level",
    "parse_uncertainty",
    "resolve_alias",
    "scaled_uncertainty",
    "span_text",
    "uncertainty_items",
    "width_sweeps",
]


def span_text(span: float) -> str:
    """Return a relative span in percent for a label: ``10`` for 0.1, ``12.5`` for 0.125.

    Every label of a map-error span (``+/-10 %``, ``worst±10%``, ``|e| <= 10 %``) is
    written with it, from the run's :attr:`UncertaintySpec.map_scale`.
    """
    return f"{100.0 * float(span):g}"


def resolve_alias(new: tuple[str, Any], old: tuple[str, Any]) -> Any:
    """Return a setting given under its new key, its deprecated alias, or both.

    Parameters
    ----------
    new, old : (str, value)
        The key's name (as the user wrote it, e.g. ``uncertainty.map_scale`` or
        ``--uncertainty map_scale``) and its value, None when not given.

    Returns
    -------
    value
        The one given (the new key's when both agree); None when neither is.

    Raises
    ------
    ValueError
        When both are given with different values: the message names both keys and
        values (nothing is guessed).
    """
    (new_key, new_value), (old_key, old_value) = new, old
    if new_value is None:
        return old_value
    if old_value is not None and old_value != new_value:
        raise ValueError(f"{old_key} = {_shown(old_value)} (deprecated) and {new_key} = "
                         f"{_shown(new_value)} disagree: give only {new_key}")
    return new_value


def _shown(value: Any) -> str:
    return repr(list(value)) if isinstance(value, tuple) else repr(value)


def check_map_error(map_error: object, name: str = "map_error") -> float:
    """Check a bound on the map error: a number in [0, 1); return it as a float.

    Parameters
    ----------
    map_error : object
        The bound (relative, 0.1 = ±10 %).
    name : str
        What to call it in the message (an option, a key).

    Raises
    ------
    ValueError
        Naming ``name`` and the value, if it is not a real number in [0, 1).
    """
    if isinstance(map_error, bool) or not isinstance(map_error, (int, float, np.floating,
                                                                 np.integer)):
        raise ValueError(f"{name} must be a number in [0, 1), got {map_error!r}")
    v = float(map_error)
    if not (math.isfinite(v) and 0.0 <= v < 1.0):
        raise ValueError(f"{name} must be in [0, 1), got {map_error!r}")
    return v


def check_map_errors(errors: Sequence[float] | np.ndarray | float) -> np.ndarray:
    """Check map errors e (each finite and > −1: a frequency stays > 0); return them flat.

    Raises
    ------
    ValueError
        If an error is not finite or is <= −1.
    """
    e = np.asarray(errors, dtype=float).ravel()
    if not np.all(np.isfinite(e)) or np.any(e <= -1.0):
        raise ValueError(f"map errors must be finite and > -1, got {e!r}")
    return e


# ------------------------------------------------------------ uncertainty sets


@dataclass(frozen=True)
class Perturbation:
    """One way the real machine may differ from the mode map: one point of an uncertainty set.

    The perturbed frequency of a mode at z is, in this order,

    1. shifted along z: g(z) = f(z − ``shift``);
    2. its slope scaled about the pivot z_p (the middle of the Z travel):
       g(z_p) + (1 + ``slope``)·(g(z) − g(z_p));
    3. the whole map scaled: × (1 + ``scale``) (a map error e);

    and every damping ratio is multiplied by ``damping``.

    Attributes
    ----------
    scale : float
        Relative error of the whole map (> −1).
    slope : float
        Relative error of the map's slope df/dz (> −1).
    shift : float
        Shift of the map along z (m).
    damping : float
        Factor of every damping ratio (> 0; the result is capped at 0.999).
    """

    scale: float = 0.0
    slope: float = 0.0
    shift: float = 0.0
    damping: float = 1.0

    def __post_init__(self) -> None:
        for name in ("scale", "slope", "shift", "damping"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"perturbation {name} must be finite, got {getattr(self, name)!r}")
        if self.scale <= -1.0 or self.slope <= -1.0:
            raise ValueError(f"scale and slope must be > -1, got {self.scale!r}, {self.slope!r}")
        if not self.damping > 0.0:
            raise ValueError(f"damping factor must be > 0, got {self.damping!r}")

    @property
    def is_scale_only(self) -> bool:
        """Only the whole map is scaled (the map error of the robustness curves)."""
        return self.slope == 0.0 and self.shift == 0.0 and self.damping == 1.0

    def frequencies(self, f_of_z: Callable[[np.ndarray], np.ndarray], z: np.ndarray,
                    pivot: float, nominal: np.ndarray | None = None) -> np.ndarray:
        """Return the perturbed frequencies (Hz) at ``z`` of a vectorised law ``f_of_z``.

        With only ``scale`` set, ``f_of_z(z) * (1 + scale)``: the very arithmetic of the
        map-error runs (:func:`harness.simulation.master.map_error_residuals`).
        ``nominal``, if given, is ``f_of_z(z)`` already computed.
        """
        z = np.asarray(z, dtype=float)
        if self.shift:
            g = f_of_z(z - self.shift)
        else:
            g = f_of_z(z) if nominal is None else nominal
        if self.slope:
            gp = float(np.asarray(f_of_z(np.array([pivot - self.shift])))[0])
            g = gp + (1.0 + self.slope) * (g - gp)
        return g * (1.0 + self.scale)

    def zeta(self, zeta: float) -> float:
        """Return the perturbed damping ratio."""
        return zeta if self.damping == 1.0 else min(zeta * self.damping, 0.999)

    def label(self) -> str:
        """Short description, e.g. ``scale +10 %, damping x0.5``."""
        parts = []
        if self.scale:
            parts.append(f"scale {100 * self.scale:+.3g} %")
        if self.slope:
            parts.append(f"slope {100 * self.slope:+.3g} %")
        if self.shift:
            parts.append(f"shift {1e3 * self.shift:+.3g} mm")
        if self.damping != 1.0:
            parts.append(f"damping x{self.damping:.3g}")
        return ", ".join(parts) or "nominal"


@dataclass(frozen=True)
class UncertaintySet:
    """A deterministic set of perturbations, nominal first.

    Attributes
    ----------
    points : tuple of Perturbation
        The points; ``points[0]`` is the nominal map.
    label : str
        What the set covers, in words.
    """

    points: tuple[Perturbation, ...]
    label: str

    def __len__(self) -> int:
        return len(self.points)


def _grid(half: float, n: int) -> list[float]:
    """``n`` points from −half to +half (0 included when n is odd)."""
    return [0.0] if half == 0.0 else [float(x) for x in np.linspace(-half, half, n)]


@dataclass(frozen=True)
class UncertaintySpec:
    """``[uncertainty]`` of a scenario: how far the real mode map may be from the model.

    Every range is symmetric about the nominal map, and off (0, or (1, 1) for the
    damping) unless given.

    Attributes
    ----------
    map_scale : float
        The whole map f(z) off by up to ±``map_scale`` (relative; default 0.1).
    map_slope : float
        Its slope df/dz off by up to ±``map_slope`` (relative), about the middle
        of the Z travel.
    z_shift : float
        The map shifted along z by up to ±``z_shift`` (m).
    damping : tuple of float
        Every damping ratio multiplied by a factor in [lo, hi].

    Notes
    -----
    Two sets are drawn from the ranges, deterministically: the *tuning* set
    (:meth:`tuning_set`, what the robust methods minimise over) and the finer
    *scoring* set (:meth:`scoring_set`, what every table reports), so that no
    method is scored on the points it was tuned on.
    """

    map_scale: float = 0.1
    map_slope: float = 0.0
    z_shift: float = 0.0
    damping: tuple[float, float] = (1.0, 1.0)

    CURVE_POINTS = 41
    """Points of the robustness curves over ±2·map_scale (:meth:`curve_errors`)."""

    WORST_POINTS = 21
    """Points of the worst case alone over ±map_scale (:meth:`worst_errors`)."""

    TUNING_POINTS = {"map_scale": 9, "map_slope": 5, "z_shift": 5, "damping": 3}
    """Points of each range in the tuning set (plus the corners of the box)."""

    SCORING_POINTS = {"map_scale": 41, "map_slope": 21, "z_shift": 21, "damping": 9}
    """Points of each range in the scoring set (plus the 3^d grid of the box, corners included)."""

    def __post_init__(self) -> None:
        check_map_error(self.map_scale, "uncertainty map_scale")
        check_map_error(self.map_slope, "uncertainty map_slope")
        if not (math.isfinite(self.z_shift) and 0.0 <= self.z_shift <= 1.0):
            raise ValueError(f"uncertainty z_shift must be in [0, 1] m, got {self.z_shift!r}")
        lo, hi = self.damping
        if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo <= 1.0 <= hi <= 100.0):
            raise ValueError(f"uncertainty damping must be [lo, hi] with 0 < lo <= 1 <= hi <= "
                             f"100, got {list(self.damping)!r}")

    @property
    def active(self) -> dict[str, bool]:
        """Which ranges are on."""
        return {"map_scale": self.map_scale > 0, "map_slope": self.map_slope > 0,
                "z_shift": self.z_shift > 0, "damping": self.damping != (1.0, 1.0)}

    def _axes(self, counts: Mapping[str, int]) -> dict[str, list[float]]:
        lo, hi = self.damping
        damp = sorted({1.0, *[float(x) for x in np.geomspace(lo, hi, counts["damping"])]}) \
            if self.active["damping"] else [1.0]
        return {"map_scale": _grid(self.map_scale, counts["map_scale"]),
                "map_slope": _grid(self.map_slope, counts["map_slope"]),
                "z_shift": _grid(self.z_shift, counts["z_shift"]),
                "damping": damp}

    def _set(self, counts: Mapping[str, int], box: int, what: str) -> UncertaintySet:
        axes = self._axes(counts)
        on = [k for k, v in self.active.items() if v]
        pts: list[Perturbation] = [Perturbation()]

        def add(values: Mapping[str, float]) -> None:
            p = Perturbation(values.get("map_scale", 0.0), values.get("map_slope", 0.0),
                             values.get("z_shift", 0.0), values.get("damping", 1.0))
            if p not in pts:
                pts.append(p)

        for k in on:  # each range alone, the others nominal
            for x in axes[k]:
                add({k: x})
        if len(on) > 1:  # the box: its corners (box = 2) or its 3^d grid (box = 3)
            ends = {k: ([min(axes[k]), max(axes[k])] if box == 2 else
                        [min(axes[k]), 1.0 if k == "damping" else 0.0, max(axes[k])])
                    for k in on}
            for combo in itertools.product(*(ends[k] for k in on)):
                add(dict(zip(on, combo, strict=True)))
        return UncertaintySet(tuple(pts), f"{self.describe()}; {what}, {len(pts)} points")

    def tuning_set(self) -> UncertaintySet:
        """Return the points the robust methods are tuned on (coarse grids, the corners)."""
        return _drawn(self, "tuning")

    def scoring_set(self) -> UncertaintySet:
        """Return the points every method is scored on: finer grids, the box's 3^d grid."""
        return _drawn(self, "scoring")

    def curve_errors(self, points: int = CURVE_POINTS) -> np.ndarray:
        """Return the map errors e of the robustness curves: ±2·map_scale, ``points`` of them.

        41 points by default, the worst case's (:meth:`worst_errors`) among them: with
        the default map scale 0.1, −20 % … +20 %, 1 % apart.  A map scale of 0 gives
        the nominal map alone (e = 0).
        """
        if isinstance(points, bool) or not isinstance(points, int) or points < 1:
            raise ValueError(f"points must be an integer >= 1, got {points!r}")
        if self.map_scale == 0.0:
            return np.zeros(1)
        return np.linspace(-2.0 * self.map_scale, 2.0 * self.map_scale, points)

    def worst_errors(self) -> np.ndarray:
        """Return the map errors e of the worst case alone: ±map_scale, 21 points.

        With the default map scale 0.1, −10 % … +10 %, 1 % apart; the same points as
        the curves' within ±map_scale (:meth:`curve_errors`).  A map scale of 0 gives
        the nominal map alone (e = 0).
        """
        if self.map_scale == 0.0:
            return np.zeros(1)
        return np.linspace(-self.map_scale, self.map_scale, self.WORST_POINTS)

    def describe(self) -> str:
        """Return the ranges in words, e.g. ``map scale +/-10 %, damping x0.5..2``."""
        parts = []
        if self.map_scale:
            parts.append(f"map scale +/-{100 * self.map_scale:g} %")
        if self.map_slope:
            parts.append(f"map slope +/-{100 * self.map_slope:g} %")
        if self.z_shift:
            parts.append(f"map shifted +/-{1e3 * self.z_shift:g} mm in z")
        if self.active["damping"]:
            parts.append(f"damping x{self.damping[0]:g}..{self.damping[1]:g}")
        return ", ".join(parts) or "none (nominal map only)"

    def __str__(self) -> str:
        """Return the spec in the ``--uncertainty`` grammar (:func:`parse_uncertainty`)."""
        parts = [f"map_scale={self.map_scale:g}"]
        if self.map_slope:
            parts.append(f"map_slope={self.map_slope:g}")
        if self.z_shift:
            parts.append(f"z_shift={self.z_shift:g}")
        if self.active["damping"]:
            parts.append(f"damping={self.damping[0]:g}:{self.damping[1]:g}")
        return ",".join(parts)


DEFAULT_UNCERTAINTY = UncertaintySpec()
"""The default: the whole map off by up to ±10 %, nothing else."""


_KEYS = ("map_scale", "map_slope", "z_shift", "damping")
"""The keys of ``[uncertainty]`` and ``--uncertainty``."""

_NONE: dict[str, Any] = {"map_scale": 0.0, "map_slope": 0.0, "z_shift": 0.0,
                         "damping": (1.0, 1.0)}
"""What ``none`` sets: every range off."""


def uncertainty_items(text: str | None) -> dict[str, Any]:
    """Read the keys an ``--uncertainty`` value sets, and only those (later items win).

    ``none`` sets every key (every range off); ``damping`` gives a (lo, hi) pair.

    Raises
    ------
    ValueError
        An unknown key, or a value that is not a number (naming the item).
    """
    values: dict[str, Any] = {}
    for raw in (text or "").split(","):
        item = raw.strip()
        if not item:
            continue
        if item.lower() == "none":
            values.update(_NONE)
            continue
        key, sep, value = (s.strip() for s in item.partition("="))
        if not sep or key not in _KEYS:
            raise ValueError(f"{item!r}: write KEY=VALUE with KEY one of {', '.join(_KEYS)} "
                             f"(or 'none')")
        try:
            if key == "damping":
                lo, sep2, hi = value.partition(":")
                values[key] = (float(lo), float(hi) if sep2 else float(lo))
            else:
                values[key] = float(value)
        except ValueError:
            raise ValueError(f"{item!r}: {value!r} is not a number"
                             + (" (damping takes LO:HI)" if key == "damping" else "")) from None
    return values


def parse_uncertainty(text: str | None, base: UncertaintySpec = DEFAULT_UNCERTAINTY
                      ) -> UncertaintySpec:
    """Read an ``--uncertainty`` value: ``KEY=VALUE`` items, comma-separated.

    Keys: ``map_scale`` (±, relative), ``map_slope`` (±, relative), ``z_shift``
    (±, m), ``damping`` (``LO:HI`` factors); ``none`` turns every range off.
    Keys not given keep ``base``'s value.

    Raises
    ------
    ValueError
        An unknown key, a malformed or out-of-range value (naming it).
    """
    values: dict[str, Any] = {"map_scale": base.map_scale, "map_slope": base.map_slope,
                              "z_shift": base.z_shift, "damping": base.damping}
    values.update(uncertainty_items(text))
    return UncertaintySpec(**values)


@functools.lru_cache(maxsize=64)
def _drawn(spec: UncertaintySpec, which: str) -> UncertaintySet:
    """Return a spec's tuning or scoring set, drawn once per spec (both are immutable)."""
    if which == "tuning":
        return spec._set(spec.TUNING_POINTS, 2, "tuning set")
    return spec._set(spec.SCORING_POINTS, 3, "scoring set")


# ------------------------------------------------------------ wider than stated

KINDS = ("map_scale", "map_slope", "z_shift", "damping")
"""The kinds of error an :class:`UncertaintySpec` states, in its order."""

_FIELD = {"map_scale": "scale", "map_slope": "slope", "z_shift": "shift", "damping": "damping"}
"""The :class:`Perturbation` field of each kind."""

_KIND_LABEL = {"map_scale": "map scale", "map_slope": "map slope", "z_shift": "z shift",
               "damping": "damping"}


@dataclass(frozen=True)
class WidthSweep:
    """Points of one kind of error, or of the whole box, out to a multiple of the stated width.

    A point's *level* is the least factor s such that the point lies within the
    stated ranges scaled by s (:meth:`UncertaintySpec.level`): level 1 is the
    edge of the stated set, level 2 twice as wide.  The worst case over the
    points of level ≤ s is the worst case of an actual error s times the stated
    one (for this kind alone, or for the whole box).

    Attributes
    ----------
    kind : str
        One of :data:`KINDS`, or ``"box"`` (every stated kind at once).
    points : tuple of Perturbation
        The points, nominal first.
    levels : tuple of float
        The level of each point.
    """

    kind: str
    points: tuple[Perturbation, ...]
    levels: tuple[float, ...]

    @property
    def label(self) -> str:
        """The kind in words (``map scale``, ``box``)."""
        return "every stated kind at once" if self.kind == "box" else _KIND_LABEL[self.kind]

    def worst_upto(self, values: np.ndarray, widths: np.ndarray) -> np.ndarray:
        """Largest of ``values`` (one per point) over the points of level ≤ each width."""
        lev = np.asarray(self.levels)
        v = np.asarray(values, dtype=float)
        return np.array([float(np.max(np.where(lev <= w + 1e-9, v, -np.inf)))
                         for w in np.asarray(widths, dtype=float)])


def _wide(spec: UncertaintySpec, s: float) -> dict[str, Any]:
    lo, hi = spec.damping
    return {"map_scale": spec.map_scale * s, "map_slope": spec.map_slope * s,
            "z_shift": spec.z_shift * s, "damping": (lo ** s, hi ** s)}


def scaled_uncertainty(spec: UncertaintySpec, s: float) -> UncertaintySpec:
    """Return ``spec`` with every range ``s`` times as wide (damping factors to the power s).

    Raises
    ------
    ValueError
        If ``s`` is not finite and >= 0, or a widened range leaves its domain
        (a map scale or slope of 1 or more, damping factors beyond 100).
    """
    if not (math.isfinite(s) and s >= 0.0):
        raise ValueError(f"width factor must be finite and >= 0, got {s!r}")
    return UncertaintySpec(**_wide(spec, s))


def level(spec: UncertaintySpec, p: Perturbation) -> float:
    """Return the least factor s such that ``p`` lies within ``spec``'s ranges times s.

    ``inf`` if ``p`` varies a kind the spec does not state.
    """
    out = 0.0
    for kind, on in spec.active.items():
        x = getattr(p, _FIELD[kind])
        if kind == "damping":
            if x == 1.0:
                continue
            lo, hi = spec.damping
            ref = math.log(hi) if x > 1.0 else math.log(lo)
            r = math.log(x) / ref if on else math.inf
        else:
            if x == 0.0:
                continue
            r = abs(x) / getattr(spec, kind) if on else math.inf
        out = max(out, r)
    return out


def width_sweeps(spec: UncertaintySpec, top: float = 2.0, per_side: int = 80,
                 box_levels: int = 8) -> list[WidthSweep]:
    """Return the points of each stated kind alone, and of the box, out to ``top`` times its width.

    Parameters
    ----------
    spec : UncertaintySpec
        The stated uncertainty.
    top : float
        The widest level (2: twice the stated ranges).
    per_side : int
        Points of each kind on each side of the nominal value (levels
        ``top/per_side`` apart; half as many for the kinds other than the map
        scale).
    box_levels : int
        Levels of the box (``top/box_levels`` apart), each the 3^d grid of the
        widened box; only when two or more kinds are stated.

    Returns
    -------
    list of WidthSweep
        One per stated kind, then the box; empty when nothing is stated.
    """
    if not (math.isfinite(top) and top > 0.0):
        raise ValueError(f"top must be finite and > 0, got {top!r}")
    scaled_uncertainty(spec, top)  # the widest ranges must be valid
    on = [k for k, v in spec.active.items() if v]
    out: list[WidthSweep] = []
    for kind in on:
        n = per_side if kind == "map_scale" else max(4, per_side // 2)
        levels = [top * i / n for i in range(1, n + 1)]
        pts: list[Perturbation] = [Perturbation()]
        lev: list[float] = [0.0]
        for s in levels:
            w = _wide(spec, s)[kind]
            ends = (w[0], w[1]) if kind == "damping" else (-w, w)
            for x in ends:
                pts.append(Perturbation(**{_FIELD[kind]: float(x)}))
                lev.append(s)
        out.append(WidthSweep(kind, tuple(pts), tuple(lev)))
    if len(on) > 1:
        pts = [Perturbation()]
        lev = [0.0]
        for i in range(1, box_levels + 1):
            s = top * i / box_levels
            w = _wide(spec, s)
            axes = [((w[k][0], 1.0, w[k][1]) if k == "damping" else (-w[k], 0.0, w[k]))
                    for k in on]
            for combo in itertools.product(*axes):
                p = Perturbation(**{_FIELD[k]: float(x) for k, x in zip(on, combo, strict=True)})
                if p not in pts:
                    pts.append(p)
                    lev.append(level(spec, p))
        out.append(WidthSweep("box", tuple(pts), tuple(lev)))
    return out
