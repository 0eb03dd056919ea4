"""Advice that survives a wrong guess: the textbook shapers as the yardstick, and the unknown modes.

A design tuned for the worst case of the stated uncertainty spends its margin
at the edge of the stated set; a machine builder's bound on the mode map is a
guess.  This module holds what the recommendation (:mod:`harness.recommend`)
is held to outside the stated model:

* **The yardstick** (:class:`Yardstick`): for an actual error w times the stated
  one (w from 0 to 2, each stated kind alone and the whole box,
  :func:`harness.uncertainty.width_sweeps`), the worst-case settling time of
  the best *textbook* shaper on JL -- ZV, ZVD, EI at the tuned mode at the end
  of the motion, and SI over the stated map scale (delays rounded to samples,
  what the generator FMU's custom shaper takes): ``B(w)``.  A design is
  *graceful* when its own worst case over every width is no worse.  The
  yardstick also gives every point of a wider set its *deadline*
  ``B(level)``: a linear programme that keeps a design's error within the band
  from its deadline on, at every point, makes it graceful
  (:func:`harness.tuning.shaping.optimal_shaper`, ``deadlines``).
* **The unknown modes** (:class:`UnmodelledModes`): what the recommendation
  assumes about modes above the modelled ones -- any mode between 2 and 8
  times the highest modelled one (following z, damping ratio 0.02 or more,
  gain up to 0.3 of it) -- and keeps: no such mode is left a residual after
  the motion larger than the least that JL or a textbook shaper leaves it (or
  than 10 % of the band), on the nominal map and at the edges of the stated
  map scale.  A signed shaper's closely
  spaced impulses excite high frequencies that JL alone leaves alone (X: three
  times JL's residual at 2.5-3.5x); this keeps them quiet.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ..modemap import ModeMap, ModeSpec
from ..scenario import Scenario
from ..scoring import score_points
from ..shaper_designs import ei, si_shaper, zv, zvd
from ..simulation.session import Session
from ..simulation.shaped_axis import ShaperSpec
from ..uncertainty import (
    Perturbation,
    UncertaintySpec,
    WidthSweep,
    level,
    width_sweeps,
)
from .shaping import Quiet, ShapedObjective

__all__ = ["OUTER_LEVELS", "TEXTBOOK", "TOP", "UnmodelledModes", "Yardstick", "dense_points",
           "design_points", "textbook_shapers"]

TEXTBOOK = ("ZV", "ZVD", "EI", "SI")
"""The textbook shapers of the yardstick (on JL, at the tuned mode at the end of the motion)."""

TOP = 2.0
"""The widest actual error the recommendation is held to: twice the stated one."""

OUTER_LEVELS = (1.125, 1.25, 1.375, 1.5, 1.625, 1.75, 1.875, 2.0)
"""Widths beyond the stated set at which a design's deadlines are kept (each kind, each side)."""


def textbook_shapers(sc: Scenario) -> dict[str, ShaperSpec]:
    """Return the textbook shapers at the tuned mode at the motion's end, delays rounded to samples.

    ZV, ZVD and EI (5 % tolerance) of the mode's frequency and damping there;
    SI (:func:`harness.shaper_designs.si_shaper`) with V ≤ 5 % over the stated
    map scale.  A design whose rounded delays collide is left out.
    """
    tm = sc.modemap.tuned
    f_end, zeta = float(tm.f(sc.z.z0 + sc.z.distance)), float(tm.zeta)
    Te = sc.simulation.Te
    out: dict[str, ShaperSpec] = {}
    for name, sh in (("ZV", zv(f_end, zeta)), ("ZVD", zvd(f_end, zeta)),
                     ("EI", ei(f_end, zeta)), ("SI", si_shaper(f_end, zeta,
                                                               sc.uncertainty.map_scale))):
        d = [int(round(float(t) / Te)) for t in sh.t]
        if len(set(d)) != len(d):
            continue
        A = [float(a) for a in sh.A]
        rest = [a / math.fsum(A) for a in A[1:]]
        out[name] = ShaperSpec((1.0 - math.fsum(rest), *rest), tuple(d), f"{name} (rounded)")
    return out


def design_points(spec: UncertaintySpec, tuning: Sequence[Perturbation],
                  levels: Sequence[float] = OUTER_LEVELS) -> tuple[Perturbation, ...]:
    """Return the points a graceful design is held at: the tuning set, then wider ones.

    Each stated kind alone at ``levels`` times its range (both sides; the
    kinds other than the map scale at every second level), and with two kinds or
    more the corners of the box at the widest level.
    """
    pts: list[Perturbation] = list(tuning)
    on = [k for k, v in spec.active.items() if v]
    field_of = {"map_scale": "scale", "map_slope": "slope", "z_shift": "shift",
                "damping": "damping"}
    lo, hi = spec.damping
    for kind in on:
        for s in (levels if kind == "map_scale" else levels[1::2]):
            if kind == "damping":
                ends = (lo ** s, hi ** s)
            else:
                w = getattr(spec, kind) * s
                ends = (-w, w)
            for x in ends:
                p = Perturbation(**{field_of[kind]: float(x)})
                if p not in pts:
                    pts.append(p)
    if len(on) > 1:
        for s in levels[-1:]:
            axes = []
            for kind in on:
                if kind == "damping":
                    axes.append((lo ** s, hi ** s))
                else:
                    w = getattr(spec, kind) * s
                    axes.append((-w, w))
            for combo in _product(axes):
                p = Perturbation(**{field_of[k]: float(x) for k, x in zip(on, combo, strict=True)})
                if p not in pts:
                    pts.append(p)
    return tuple(pts)


def dense_points(spec: UncertaintySpec, tuning: Sequence[Perturbation], factor: int = 4
                 ) -> tuple[Perturbation, ...]:
    """Return the tuning set with the map scale ``factor`` times as dense.

    A design held exactly at the band at a few points leaves it between them:
    the phase of the oscillation turns by about a radian between two points of
    the tuning set when the damping is low.  The points added lie between the
    tuning set's (none is a point of the scoring set but those the tuning set
    already shares with it).
    """
    pts = list(tuning)
    e = spec.map_scale
    if e > 0:
        n = 8 * factor + 1
        for x in np.linspace(-e, e, n):
            p = Perturbation(scale=float(x))
            if p not in pts:
                pts.append(p)
    return tuple(pts)


def _product(axes: list[tuple[float, float]]) -> list[tuple[float, ...]]:
    out: list[tuple[float, ...]] = [()]
    for ax in axes:
        out = [(*o, x) for o in out for x in ax]
    return out


# ------------------------------------------------------------------ the yardstick


@dataclass
class Yardstick:
    """The best textbook shaper's worst-case settling at every width up to :data:`TOP`.

    Attributes
    ----------
    spec : UncertaintySpec
        The stated uncertainty.
    sweeps : list of WidthSweep
        Each stated kind alone, then the box.
    widths : ndarray
        The widths (multiples of the stated ranges) the curves are given at.
    curves : dict
        ``curves[method][kind]``: a textbook shaper's worst-case settling (s)
        over the sweep's points of level ≤ each width.
    best : dict
        ``best[kind]``: the least of the curves at each width: ``B(w)``.
    settling : dict
        ``settling[method][kind]``: each textbook's settling at every point of the sweep.
    """

    spec: UncertaintySpec
    sweeps: list[WidthSweep]
    widths: np.ndarray
    curves: dict[str, dict[str, np.ndarray]]
    best: dict[str, np.ndarray] = field(default_factory=dict)
    settling: dict[str, dict[str, np.ndarray]] = field(default_factory=dict)

    @classmethod
    def measure(cls, sc: Scenario, session: Session, T_F: Sequence[float], band: float,
                shapers: dict[str, ShaperSpec] | None = None, top: float = TOP,
                runs: dict[str, object] | None = None) -> Yardstick:
        """Run each textbook shaper on JL and score it at every point of the sweeps.

        Parameters
        ----------
        sc : Scenario
            A single-move scenario (its uncertainty is the stated one).
        session : Session
            Runs the shaped JL (the generator shapes it itself).
        T_F : sequence of float
            JL's jerk times.
        band : float
            The settling band (m).
        shapers : dict, optional
            Default :func:`textbook_shapers`.
        top : float
            The widest width.
        runs : dict, optional
            The textbook shapers' runs already made (name -> CoSimResult): for
            instance with their exact delays (:func:`harness.peers.shapers.shape`),
            which the generator's whole-sample shaper rounds.  Then ``shapers``
            is not used.
        """
        sweeps = width_sweeps(sc.uncertainty, top, box_levels=4)
        n = max(2, int(round(40 * top)))
        widths = np.linspace(0.0, top, n + 1)
        ys = cls(sc.uncertainty, sweeps, widths, {})
        if runs is None:
            runs = {name: session.run(sc, "JL", tuple(T_F), shaper=spec) for name, spec in
                    (textbook_shapers(sc) if shapers is None else shapers).items()}
        for name, run in runs.items():
            per = ys.score(run, sc, band)
            ys.settling[name] = per
            ys.curves[name] = {sw.kind: sw.worst_upto(per[sw.kind], widths) for sw in sweeps}
        for sw in sweeps:
            ys.best[sw.kind] = np.min(np.vstack([c[sw.kind] for c in ys.curves.values()]),
                                      axis=0)
        return ys

    def score(self, run: object, sc: Scenario, band: float) -> dict[str, np.ndarray]:
        """Settling time (s) of a run at every point of every sweep (``{kind: array}``)."""
        out: dict[str, np.ndarray] = {}
        for sw in self.sweeps:
            out[sw.kind] = score_points(run, sc, band, sw.points).settling  # type: ignore[arg-type]
        return out

    def curve(self, per_point: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Worst-case settling at each width of a design scored by :meth:`score`."""
        return {sw.kind: sw.worst_upto(per_point[sw.kind], self.widths) for sw in self.sweeps}

    def best_at(self, kind: str, w: float) -> float:
        """``B(w)`` of a sweep: the best textbook's worst over the points of level ≤ w."""
        sw = next(s for s in self.sweeps if s.kind == kind)
        return float(min(sw.worst_upto(per[kind], np.array([w]))[0]
                         for per in self.settling.values()))

    def best_method(self, kind: str, i: int) -> str:
        """Name of the textbook shaper with the least worst case at ``widths[i]``."""
        return min(self.curves, key=lambda m: self.curves[m][kind][i])

    def deadline(self, p: Perturbation) -> float:
        """Return a point's deadline: ``B`` at its width, for its kind alone or the box."""
        s = level(self.spec, p)
        if not math.isfinite(s):
            return math.inf
        kinds = [k for k, f in (("map_scale", p.scale), ("map_slope", p.slope),
                                ("z_shift", p.shift)) if f != 0.0]
        if p.damping != 1.0:
            kinds.append("damping")
        if not kinds:  # the nominal point: the least of every sweep's B(0)
            return min(self.best_at(sw.kind, 0.0) for sw in self.sweeps) if self.sweeps \
                else math.inf
        kind = kinds[0] if len(kinds) == 1 else "box"
        if not any(sw.kind == kind for sw in self.sweeps):
            return math.inf
        return self.best_at(kind, s)

    def ratios(self, per_point: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """Return a design's worst case over B at each width, per sweep (> 1: behind a textbook)."""
        c = self.curve(per_point)
        return {k: c[k] / self.best[k] for k in c}

    def excess(self, per_point: dict[str, np.ndarray]) -> tuple[float, str, float]:
        """Return the largest ratio of :meth:`ratios`, its sweep and its width."""
        worst = (-math.inf, "", 0.0)
        for k, r in self.ratios(per_point).items():
            i = int(np.argmax(r))
            if r[i] > worst[0]:
                worst = (float(r[i]), k, float(self.widths[i]))
        return worst


# ------------------------------------------------------------------ unknown modes


@dataclass(frozen=True)
class UnmodelledModes:
    """What a design assumes of modes above the modelled ones, and keeps.

    A mode the map does not hold may lie anywhere from ``ratio[0]`` to
    ``ratio[1]`` times the highest modelled mode (following it along z), with a
    damping ratio of ``zeta`` or more and a participation up to ``gain`` of
    that mode's.  A design keeps each such mode's residual after the motion no
    larger than the least that JL or any textbook shaper on it leaves it
    (:meth:`bound`), or than ``floor`` of the band, whichever is larger (on the
    nominal map and at the edges of the stated map scale): the recommended
    reference excites no such mode more than the quietest of the profiles a
    user would otherwise pick.

    Attributes
    ----------
    ratio : tuple of float
        Where such a mode may be (multiples of the highest modelled mode).
    step : float
        Spacing of the ratios the design is held at.
    gain : float
        Its participation, relative to that mode's.
    zeta : float
        Its damping ratio (the least assumed).
    floor : float
        A residual below this fraction of the band is accepted whatever JL's.
    """

    ratio: tuple[float, float] = (2.0, 8.0)
    step: float = 0.1
    gain: float = 0.3
    zeta: float = 0.02
    floor: float = 0.1

    def ratios(self) -> np.ndarray:
        """Return the ratios the design is held at."""
        lo, hi = self.ratio
        return np.arange(lo, hi + 0.5 * self.step, self.step)

    def scenario(self, sc: Scenario) -> Scenario:
        """Return ``sc`` with the modelled modes replaced by the assumed ones (one per ratio)."""
        z_end = sc.z.z0 + sc.z.distance
        top = max(sc.modemap.modes, key=lambda m: float(m.f(z_end)))
        modes = tuple(ModeSpec(top.law, self.zeta, self.gain * top.gain,
                               top.mass_ratio / (k * k), f"unmodelled {k:.2g}x")
                      for k in self.ratios())
        return dataclasses.replace(sc, modemap=ModeMap(modes, 0))

    def points(self, spec: UncertaintySpec) -> tuple[Perturbation, ...]:
        """Return where the assumed modes are held: the nominal map, the stated scale's edges."""
        e = spec.map_scale
        return (Perturbation(),) + ((Perturbation(scale=-e), Perturbation(scale=e)) if e else ())

    def quiet(self, sc: Scenario, session: Session, T_jl: Sequence[float], band: float,
              profile: str = "JL", T_F: Sequence[float] | None = None) -> Quiet:
        """Return the constraint a design keeps: each assumed mode's bound from JL's residual.

        Parameters
        ----------
        sc : Scenario
            The scenario (its modelled modes give where the assumed ones are).
        session : Session
            Plans the profiles and Z.
        T_jl : sequence of float
            JL's jerk times (the bounds are JL's residuals).
        band : float
            The settling band (m).
        profile : {"JL", "DJL"}
            The profile the designs shape.
        T_F : sequence of float, optional
            Its jerk times (default ``T_jl``).
        """
        scq, pts = self.scenario(sc), self.points(sc.uncertainty)
        jl = ShapedObjective(scq, session, "JL", tuple(T_jl), pts, band)
        obj = jl if profile == "JL" and T_F is None else ShapedObjective(
            scq, session, profile, tuple(T_jl if T_F is None else T_F), pts, band)
        return Quiet(obj, self.bound(sc, jl, band))

    def bound(self, sc: Scenario, jl: ShapedObjective, band: float) -> np.ndarray:
        """Return each (point, assumed mode) row's bound: the quietest of JL and the textbooks.

        ``jl`` is a :class:`~harness.tuning.shaping.ShapedObjective` of JL on
        :meth:`scenario` at :meth:`points`: the residual each row is left by JL
        and by each textbook shaper on it (:func:`textbook_shapers`), the least
        of them, and no less than ``floor`` of the band.
        """
        amps = [jl.residuals(np.ones((1, 1)), (0,))[0][..., 0].ravel()]
        for spec in textbook_shapers(sc).values():
            amps.append(jl.residuals(np.array(spec.amplitudes)[:, None],
                                     spec.delays)[0][..., 0].ravel())
        return np.maximum(np.min(np.vstack(amps), axis=0), self.floor * band)

    def describe(self) -> str:
        """Return the assumption in words."""
        return (f"any mode at {self.ratio[0]:g}-{self.ratio[1]:g}x the highest modelled one "
                f"(following z, zeta >= {self.zeta:g}, gain up to {self.gain:g} of it) is left a "
                f"residual no larger than the least JL or a textbook shaper leaves it, or than "
                f"{self.floor:g} band")
