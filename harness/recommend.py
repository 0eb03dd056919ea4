"""The profile to use: the one that settles first whatever the real mode map, and fails gracefully.

:func:`recommend` tunes each family the project offers, robustly over the
*tuning* set of the scenario's uncertainty and at a jerk no higher than JL's:

* ``DJL (robust)`` -- DJL's four jerk times (:func:`harness.tuning.search.tune_optimal`,
  jerk times no shorter than JL's);
* ``JL*shaper`` -- JL (its jerk time, the modal period at the end of the
  motion) convolved with a shaper of up to 8 impulses: two or three searched
  (:func:`harness.tuning.shaping.robust_shaper`), the textbook ZVD and EI of
  the end mode (delays rounded to samples), and the linear programme's designs
  on the exact settling time (:func:`harness.tuning.shaping.optimal_shaper`),
  positive and -- unless ``signed=False`` -- with negative amplitudes, JL's
  jerk and the move's limits then kept on every sample (and, when no LP
  reference holds, *graceful* ones, held beyond the stated set: below);
* ``DJL*shaper`` -- the robust DJL convolved with a shaper;
* ``LP reference`` -- JL with each half ramp filtered on its own, designed by
  linear programming (:mod:`harness.tuning.reference`): a jerk per sample that
  the generator FMU replays (profile ``table``);

then measures each candidate exactly (the whole record, every point of the
tuning set, the case's settling band).

**Beyond the stated set** (:mod:`harness.tuning.graceful`).  The actual error
may be anything from none to twice the stated one.  For every width w from 0
to 2 (times the stated ranges; each stated kind alone, and the whole box) the
yardstick is the best textbook shaper on JL (ZV, ZVD, EI at the end mode, SI
over the stated map scale): B(w), its worst-case settling over the points of
that width.  The LP designs keep, at every point of a wider design set, the
error in the band from B(that point's width) on.  The candidates within
:data:`SCREEN` of the best are scored at every width, and the recommendation
is chosen by one stated rule, :data:`RULE`: graceful first (no later than the
best textbook shaper at any width), then the least worst case over the stated
uncertainty.  When no candidate is graceful the one least behind the textbook
shapers is taken, and the notes say which width bound the choice.

A candidate must keep the **unmodelled modes** the recommendation assumes
quiet (:class:`harness.tuning.graceful.UnmodelledModes`: any mode at 2-8x the
highest modelled one, gain up to 0.3, ζ ≥ 0.02, is left a residual no larger
than JL's, or than 10 % of the band); only when none does is the quietest
kept, and the notes say so.

The recommendation says why (:attr:`Recommendation.explanation`): the chosen
family and design, up to what width it is no worse than every textbook shaper
and which one is better beyond, why each other family lost, and its motion
time against JL's.

The shaped profiles have whole-sample delays: the generator FMU produces them
itself (parameters ``shaper = 4``, ``shaper_amplitude[i]``, ``shaper_delay[i]``,
:meth:`Recommendation.fmu_parameters`), and the harness's
:class:`~harness.simulation.shaped_axis.ShapedAxis` evaluates the same
convolution.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import __version__
from ._resources import fmu_src_dir
from .degradation import Degradation
from .files import write_text
from .fmu.build import cache_dir
from .peers.motion_axis import cosimulate_reference
from .peers.shapers import base_motion, shape
from .peers.trajectory import PiecewiseJerk
from .plant import free_amplitude
from .scenario import Scenario
from .scoring import score_points, score_uncertainty
from .shaper_designs import ei, si_shaper, zv, zvd
from .simulation.jerk_table import JerkTable
from .simulation.session import Session
from .simulation.shaped_axis import ShaperSpec
from .tuning.graceful import (
    OUTER_LEVELS,
    TOP,
    UnmodelledModes,
    Yardstick,
    dense_points,
    design_points,
)
from .tuning.reference import (
    TABLE_PIECES,
    RampObjective,
    ReferenceDesign,
    design_reference,
    kinematics,
    pieces,
    sparse_support,
)
from .tuning.rule import TuningResult
from .tuning.search import tune_optimal
from .tuning.shaping import Quiet, ShapedObjective, optimal_shaper, robust_shaper
from .tuning.tune import tune_profile
from .uncertainty import Perturbation, UncertaintySpec, level

__all__ = ["ASSUMED", "FAMILIES", "RULE", "Candidate", "Recommendation", "candidate_parameters",
           "jerk_table", "recommend", "reference_motion", "table_of", "SampledReference"]

FAMILIES = ("DJL (robust)", "JL*shaper", "DJL*shaper", "LP reference")
"""The families the recommendation chooses from."""

RULE = ("graceful first: among the candidates that keep the assumed unmodelled modes quiet and "
        f"settle, at every actual error from 0 to {TOP:g}x the stated one (each stated kind alone "
        "and together), no later than the best textbook shaper (JL*ZV, ZVD, EI, SI at the end "
        "mode) in the worst case, the one that settles first in the worst case of the stated "
        "uncertainty (then the shorter motion); when none is that graceful, the one that is "
        "least behind the textbook shapers (within 0.5 %), then the same")
"""The rule that picks the recommendation, in words."""

ASSUMED = UnmodelledModes()
"""What the recommendation assumes of unmodelled modes by default."""

TIE = 0.005
"""Excesses within this fraction of each other tie (then the stated width decides)."""

GRACE = 1e-3
"""A candidate within this fraction of the best textbook shaper at every width is graceful
(the curves are measured on the same points; the fraction absorbs their interpolation)."""

SCREEN = 0.15
"""Candidates whose worst case at the stated width is within this fraction of the best are
scored at every width (and may be recommended)."""


@dataclass
class Candidate:
    """One tuned member of a family, measured exactly.

    Attributes
    ----------
    family : str
        One of :data:`FAMILIES`.
    profile : {"JL", "DJL"}
        The generator profile.
    T_F : tuple of float
        Its jerk times (s).
    shaper : ShaperSpec or None
        The shaper (whole-sample delays), or none.
    settling_worst : float
        Worst-case settling time over the tuning set (s, from the start).
    residual_worst : float
        Largest residual over the tuning set (m).
    residual : float
        Residual on the nominal map (m).
    motion_time : float
        The motion time (s).
    design : str
        How it was designed (e.g. ``"LP, graceful"``).
    excess : float
        Its largest worst-case settling over the best *textbook* shaper's at any
        width (≤ 1: graceful); NaN if not scored.
    excess_at : str
        Where ``excess`` is reached (kind and width).
    quiet : float
        The largest residual of an assumed unmodelled mode over its bound (≤ 1:
        the assumption kept; NaN if not measured).
    curves : dict
        ``{kind: [worst-case settling at each width]}`` when scored at every width.
    jerk : tuple of float
        For a sampled reference (``profile == "table"``): its jerk on each sample
        from the motion's start (m/s³); empty otherwise.
    """

    family: str
    profile: str
    T_F: tuple[float, ...]
    shaper: ShaperSpec | None
    settling_worst: float
    residual_worst: float
    residual: float
    motion_time: float
    design: str = ""
    excess: float = math.nan
    excess_at: str = ""
    quiet: float = math.nan
    curves: dict[str, list[float]] = field(default_factory=dict)
    jerk: tuple[float, ...] = ()

    def label(self, Te: float) -> str:
        """Return the method in words: the family, the jerk times, the shaper."""
        if self.profile == "table":
            j = np.asarray(self.jerk)
            pieces = int(np.count_nonzero(np.diff(j) != 0.0)) + 1 if j.size else 0
            return (f"JL T_F {self.T_F[0] * 1e3:.0f} ms, each ramp filtered (LP): a jerk "
                    f"table of {pieces} pieces over {j.size} samples")
        ms = "/".join(f"{t * 1e3:.0f}" for t in (self.T_F[:1] if self.profile == "JL"
                                                 else self.T_F))
        txt = f"{self.profile} T_F {ms} ms"
        if self.shaper is not None:
            txt += f" * {self.shaper.describe(Te)}"
        return txt

    @property
    def graceful(self) -> bool:
        """No worse than the best textbook shaper at every width scored."""
        return bool(self.excess <= 1.0 + 1e-9)


@dataclass
class Recommendation:
    """The recommended profile of one move, and the candidates it was chosen from.

    Attributes
    ----------
    best : Candidate
        The recommended one.
    candidates : list of Candidate
        Every candidate measured, the recommended first, then by worst case at
        the stated width.
    band : float
        The settling band (m).
    tuning_set : str
        What the candidates were tuned and measured on.
    seconds : float
        Time to tune and choose.
    notes : list of str
        Anything the choice ran into.
    widths : list of float
        The widths (multiples of the stated ranges) the curves are given at.
    textbook : dict
        ``{method: {kind: [worst-case settling at each width]}}`` of the
        textbook shapers (delays rounded to samples).
    explanation : list of str
        Why this one: the rule, the family and design, how far it
        holds against the textbook shapers, why each other family lost, its
        motion time against JL's.
    rule : str
        The rule (:data:`RULE`).
    assumption : str
        What is assumed of unmodelled modes, and kept.
    jl_motion_time : float
        JL's motion time (s).
    quiet_limit : float
        The most a candidate's ``quiet`` may be (inf: nothing assumed).
    """

    best: Candidate
    candidates: list[Candidate]
    band: float
    tuning_set: str
    seconds: float
    notes: list[str] = field(default_factory=list)
    widths: list[float] = field(default_factory=list)
    textbook: dict[str, dict[str, list[float]]] = field(default_factory=dict)
    explanation: list[str] = field(default_factory=list)
    rule: str = RULE
    assumption: str = ""
    jl_motion_time: float = math.nan
    quiet_limit: float = math.inf

    @property
    def method(self) -> str:
        """The recommended family."""
        return self.best.family

    def fmu_parameters(self, sc: Scenario) -> dict[str, Any]:
        """Return the FMU parameters that produce the recommended profile (excited axis)."""
        return candidate_parameters(sc, self.best)

    def run(self, sc: Scenario, session: Session, t_stop: float | None = None):
        """Co-simulate the recommended profile (its FMU parameters, or its sampled reference).

        Returns
        -------
        harness.simulation.master.CoSimResult
        """
        return _run(sc, session, self.best, t_stop)

    def degradation(self, sc: Scenario) -> Degradation | None:
        """Return the recommended profile's and the textbook shapers' worst case at every width.

        The curves the choice was made on (:class:`harness.degradation.Degradation`:
        worst-case settling against the actual error width, 0 to 2x the stated
        one); None if the recommended profile was not scored at every width.
        """
        if not self.best.curves or not self.textbook:
            return None
        curves = {"recommended": {k: np.asarray(v) for k, v in self.best.curves.items()}}
        curves.update({m: {k: np.asarray(v) for k, v in c.items()}
                       for m, c in self.textbook.items()})
        return Degradation(sc.name, sc.uncertainty, np.asarray(self.widths), curves,
                           "recommended", tuple(self.textbook))

    def map_error_residuals(self, sc: Scenario, session: Session,
                            errors: Sequence[float] | np.ndarray) -> np.ndarray:
        """Return the recommended profile's residual (m) for each map error e (f → f·(1 + e))."""
        b = self.best
        return session.map_error_residuals(sc, b.profile, b.T_F, errors, shaper=b.shaper,
                                           table=jerk_table(sc, b))

    def fmu_parameters_json(self, sc: Scenario) -> str:
        """:meth:`fmu_parameters` as a JSON object (what a CSV row carries)."""
        return json.dumps(self.fmu_parameters(sc), sort_keys=True)

    def holds_to(self, kind: str | None = None) -> tuple[float, str]:
        """Return the widest width up to which the recommendation is no worse than every textbook.

        Parameters
        ----------
        kind : str, optional
            The sweep (default: the narrowest over every kind scored).

        Returns
        -------
        width : float
            A multiple of the stated ranges (``widths[-1]`` if it holds to the end;
            ``nan`` if the curves were not scored).
        beyond : str
            The textbook shaper that is better just beyond it ("" if none).
        """
        if not self.best.curves or not self.textbook:
            return math.nan, ""
        w = np.asarray(self.widths)
        kinds = [kind] if kind is not None else list(self.best.curves)
        out = (math.inf, "")
        for k in kinds:
            rec = np.asarray(self.best.curves[k])
            tb = {m: np.asarray(c[k]) for m, c in self.textbook.items()}
            best_tb = np.min(np.vstack(list(tb.values())), axis=0)
            bad = np.flatnonzero(rec > best_tb * (1.0 + 1e-9))
            if bad.size == 0:
                cand = (float(w[-1]), "")
            else:
                i = int(bad[0])
                who = min(tb, key=lambda m: tb[m][i])
                cand = (float(w[i - 1]) if i > 0 else 0.0, who)
            if cand[0] < out[0]:
                out = cand
        return out


# ------------------------------------------------------------------ measuring


@dataclass
class SampledReference(PiecewiseJerk):
    """A jerk per sample replayed from the motion's start: its span is the whole table.

    A :class:`~harness.peers.trajectory.PiecewiseJerk` starts where it leaves
    rest and ends where it comes back to it; a table replayed by the generator
    (profile ``table``) lasts all its samples, leading or trailing samples of
    zero jerk included, and the Z axis is synchronised with that.
    """

    span: tuple[float, float] = (0.0, 0.0)

    @property
    def t_start(self) -> float:
        """The table's first sample (s)."""
        return float(self.span[0])

    @property
    def t_end(self) -> float:
        """The end of the table's last sample (s)."""
        return float(self.span[1])


def reference_motion(sc: Scenario, session: Session, jerk: np.ndarray) -> SampledReference:
    """Return a sampled reference (a jerk per sample) as an exact motion of the scenario's move.

    It starts at the generator's first sample at or after ``t_start`` (planned
    through ``session``'s excited axis) from ``x0``, and lasts all its samples.
    """
    Te = sc.simulation.Te
    session.axis.plan(Session.move_params(sc, "AL"))
    t0 = session.axis.motion_start()
    j = np.asarray(jerk, dtype=float)
    x, v, a = kinematics(j, Te)
    tb = t0 + Te * np.arange(j.size + 1)
    return SampledReference(tb, sc.move.x0 + x, v, a, np.r_[j, 0.0], name="LP reference",
                            span=(float(tb[0]), float(tb[-1])))


def table_of(jerk: Sequence[float]) -> tuple[list[int], list[float]]:
    """Return a per-sample jerk as pieces: samples and jerk of each run of equal values."""
    j = np.asarray(jerk, dtype=float)
    if j.size == 0:
        return [], []
    starts = np.flatnonzero(np.r_[True, np.diff(j) != 0.0])
    lengths = np.diff(np.r_[starts, j.size])
    return [int(n) for n in lengths], [float(x) for x in j[starts]]


def jerk_table(sc: Scenario, c: Candidate) -> JerkTable | None:
    """Return a sampled reference's table (None for a candidate of another profile)."""
    if c.profile != "table":
        return None
    return JerkTable.from_jerk_samples(np.asarray(c.jerk), sc.simulation.Te)


def candidate_parameters(sc: Scenario, c: Candidate) -> dict[str, Any]:
    """Return the generator FMU's parameters that produce a candidate (excited axis)."""
    return Session.move_params(sc, c.profile, c.T_F, c.shaper, jerk_table(sc, c))


def _run(sc: Scenario, session: Session, c: Candidate, t_stop: float | None = None
         ):  # -> CoSimResult
    """Co-simulate a candidate: the generator makes its profile (shaped, or a table)."""
    return session.run(sc, c.profile, c.T_F, t_stop=t_stop, shaper=c.shaper,
                       table=jerk_table(sc, c))


def _measure(sc: Scenario, session: Session, family: str, profile: str,
             T_F: tuple[float, ...], shaper: ShaperSpec | None, band: float,
             design: str = "", jerk: tuple[float, ...] = ()) -> Candidate:
    c = Candidate(family, profile, tuple(T_F), shaper, math.nan, math.nan, math.nan, math.nan,
                  design, jerk=tuple(jerk))
    run = _run(sc, session, c)
    sco = score_uncertainty(run, sc, band, sc.uncertainty.tuning_set())
    c.settling_worst = float(sco["settling_time_worst"])
    c.residual_worst = float(sco["residual_worst"])
    c.residual, c.motion_time = run.free_amplitude, run.motion_time
    return c


def _textbook_runs(sc: Scenario, session: Session, T_jl: tuple[float, ...]
                   ) -> dict[str, Any]:
    """Run the textbook shapers on JL with their exact delays (the yardstick, as ``compare``'s).

    ZV, ZVD, EI at the tuned mode at the end of the motion, SI with V <= 5 % over
    the stated map scale (:func:`harness.shaper_designs.si_shaper`).
    """
    tm = sc.modemap.tuned
    f_end, zeta = float(tm.f(sc.z.z0 + sc.z.distance)), float(tm.zeta)
    base = base_motion(sc, "JL", T_jl[0], session=session)
    out = {}
    for name, sh in (("ZV", zv(f_end, zeta)), ("ZVD", zvd(f_end, zeta)), ("EI", ei(f_end, zeta)),
                     ("SI", si_shaper(f_end, zeta, sc.uncertainty.map_scale))):
        out[f"JL*{name}"] = cosimulate_reference(sc, session, shape(base, sh, name=f"JL*{name}"),
                                                 f"JL*{name}")
    return out


TABLE_PROFILE = 4
"""The generator FMU's profile code of a replayed jerk table (``profile = table``)."""

REFERENCE_SPANS = (0.6, 1.0, 1.5)
"""Spans of the LP reference's filters, in end-mode periods: the next one while a span has no
design, or (up to 1 period) its design settles, in the programme, more than 5 % after JL's
motion time."""

REFERENCE_PIECE = 0.5
"""The LP reference filters each half jerk time of JL's ramps on its own."""

REFERENCE_STRIDE = 6
"""The delays (samples apart) the LP reference's filters may use, at least."""

REFERENCE_DELAYS = 25
"""About this many delays a period of the end mode (a slow mode: delays further apart)."""

REFERENCE_SOLVES = 120
"""Programmes a design may solve: past them, the earliest settling found so far is kept (a
count, not a time: the recommendation is the same on any machine)."""


def _check_points(spec: UncertaintySpec) -> list[Perturbation]:
    """Points between the design set's, to check a design between the points it holds.

    On the map scale: halfway between the dense set's points (odd multiples of
    E/32: none is a point of the scoring set, whose points are multiples of
    E/20), and halfway between the outer levels.
    """
    e = spec.map_scale
    out: list[Perturbation] = []
    if e > 0:
        out += [Perturbation(scale=float(x)) for x in e * (np.arange(-31, 32, 2) / 32.0)]
        mids = 0.5 * (np.r_[1.0, OUTER_LEVELS[:-1]] + np.array(OUTER_LEVELS))
        out += [Perturbation(scale=float(sg * e * w)) for w in mids for sg in (-1.0, 1.0)]
    return out


def _design_one(sc: Scenario, session: Session, T_F: tuple[float, ...], band: float,
                pts: list[Perturbation], mm: list[bool], dl: list[float], frac: float,
                quiet: tuple[RampObjective, np.ndarray] | None, notes: list[str]
                ) -> tuple[ReferenceDesign, str, RampObjective] | None:
    """Design the LP reference of one span on a set (the window past the motion if needed)."""
    obj = RampObjective(sc, session, T_F, tuple(pts), band, piece=REFERENCE_PIECE)
    D = max(2, int(round(frac * obj.period / obj.Te)))
    # about REFERENCE_DELAYS delays a period, at least REFERENCE_STRIDE samples apart
    st = max(REFERENCE_STRIDE, int(round(obj.period / obj.Te / REFERENCE_DELAYS)))
    m_a, d_a = np.array(mm), np.array(dl)
    for after in (0.0, 0.5 * obj.period, 2.0 * obj.period):
        r = design_reference(obj, D, deadlines=d_a, minimax=m_a, quiet=quiet, after=after,
                             stride=st, max_solves=REFERENCE_SOLVES)
        if r is not None and pieces(r.jerk) > TABLE_PIECES:  # fewer amplitudes, once
            n_too = pieces(r.jerk)
            r = design_reference(obj, D, deadlines=d_a, minimax=m_a, quiet=quiet,
                                 after=after, stride=st, max_solves=REFERENCE_SOLVES,
                                 support=sparse_support(r, TABLE_PIECES // 3))
            if r is None or pieces(r.jerk) > TABLE_PIECES:
                notes.append(f"an LP reference of {frac:g} period had {n_too} pieces, more "
                             f"than the FMU's table holds ({TABLE_PIECES})")
                r = None
        if r is not None:
            late = f", settling up to {after:.2f} s after" if after else ""
            return r, f"LP, graceful beyond the stated set, {frac:g} period{late}", obj
    return None


def _reference_designs(sc: Scenario, session: Session, T_F: tuple[float, ...], band: float,
                       ys: Yardstick, unmodelled: UnmodelledModes | None, notes: list[str]
                       ) -> list[tuple[ReferenceDesign, str]]:
    """Return the LP references (:func:`harness.tuning.reference.design_reference`).

    Held at the tuning set made four times as dense on the map scale
    (:func:`harness.tuning.graceful.dense_points`), and beyond it at the
    textbook shapers' deadlines (:func:`~harness.tuning.graceful.design_points`);
    the assumed unmodelled modes kept quiet.  Spans :data:`REFERENCE_SPANS`;
    when a span has no design settling within the motion, the window runs half
    a period, then two, past it.

    Each design is then checked between the points it holds (:func:`_check_points`:
    none of them a scoring point): where its settling there is later than the
    programme's (inside the stated set) or than the point's deadline (beyond
    it), the worst such points join the set and the span is designed again
    (twice at most).  Every design found is returned (the caller measures
    them all).
    """
    spec = sc.uncertainty
    dense = dense_points(spec, spec.tuning_set().points)
    pts0 = list(design_points(spec, dense))
    mm0 = [i < len(dense) for i in range(len(pts0))]
    dl0 = [ys.deadline(p) if level(spec, p) > 1.0 + 1e-9 else math.inf for p in pts0]
    checks = _check_points(spec)
    quiet = None
    if unmodelled is not None:
        qobj = RampObjective(unmodelled.scenario(sc), session, T_F, unmodelled.points(spec),
                             band, piece=REFERENCE_PIECE, window=False)
        quiet = (qobj, unmodelled.quiet(sc, session, T_F, band).bound)
    out: list[tuple[ReferenceDesign, str]] = []
    for frac in REFERENCE_SPANS:
        pts, mm, dl = list(pts0), list(mm0), list(dl0)
        got = None
        for _ in range(3):
            got = _design_one(sc, session, T_F, band, pts, mm, dl, frac, quiet, notes)
            if got is None or not checks:
                break
            r, _, obj = got
            run = session.run(sc, "table", T_F,
                              table=JerkTable.from_jerk_samples(r.jerk, sc.simulation.Te))
            t_c = score_points(run, sc, band, checks).settling
            claim = r.settle_sample * obj.Te - sc.move.t_start
            lim = np.array([claim + obj.Te if level(spec, p) <= 1.0 + 1e-9
                            else ys.deadline(p) for p in checks])
            over = np.flatnonzero(t_c > lim + 1e-9)
            if over.size == 0:
                break
            for i in over[np.argsort(-(t_c[over] - lim[over]))][:4]:
                p = checks[int(i)]
                inner = level(spec, p) <= 1.0 + 1e-9
                pts.append(p)
                mm.append(inner)
                dl.append(math.inf if inner else ys.deadline(p))
        if got is not None:
            r, _, obj = got
            out.append((r, got[1]))
            # a longer span only where this one settles more than 5 % after JL's motion
            # time (the constraints bind: a longer span frees them), and not past 1 period
            # once a design is found (a longer one costs several times more)
            if r.settle_sample * obj.Te - sc.move.t_start <= 1.05 * obj.T_base \
                    or frac >= 1.0:
                break
    if not out:
        notes.append("no LP reference of " + "/".join(f"{f:g}" for f in REFERENCE_SPANS)
                     + " end-mode periods holds every constraint")
    return out


def _classic_shapers(sc: Scenario) -> list[ShaperSpec]:
    """ZVD and EI for the tuned mode at the end of the motion, delays rounded to samples.

    The family's robust search starts from nothing; these textbook designs are
    measured beside its results, so that the family's best is never worse than
    them (up to the rounding of their delays).
    """
    tm = sc.modemap.tuned
    f_end, zeta = float(tm.f(sc.z.z0 + sc.z.distance)), float(tm.zeta)
    Te = sc.simulation.Te
    out = []
    for sh in (zvd(f_end, zeta), ei(f_end, zeta)):
        d = [int(round(t / Te)) for t in sh.t]
        if len(set(d)) == len(d):
            A = [float(a) for a in sh.A]
            rest = [round(a / sum(A), 6) for a in A[1:]]
            out.append(ShaperSpec((1.0 - sum(rest), *rest), tuple(d), f"{sh.name} (rounded)"))
    return out


def _lp_shapers(sc: Scenario, session: Session, T_F: tuple[float, ...], band: float,
                obj: ShapedObjective, span3: int, signed: bool, notes: list[str]
                ) -> list[tuple[ShaperSpec, str]]:
    """Return the LP designs on JL held at the tuning set alone (:func:`optimal_shaper`).

    Positive amplitudes at spans a little longer than the best three-impulse
    design's ``span3`` (what the LP gains there: the delays and amplitudes of
    every impulse chosen together, on the exact settling time); with
    ``signed``, shapers with negative amplitudes too (their bounds kept on every
    sample), at the first two spans from 0.5 to 0.9 of the end mode's period
    (by 0.05) that admit one.
    """
    n_d = obj.period / obj.Te
    runs = [(False, (span3 + 4, span3 + 10))]
    if signed:
        runs.append((True, tuple(int(round(f * n_d)) for f in np.arange(0.5, 0.91, 0.05))))
    out: list[tuple[ShaperSpec, str]] = []
    for sgn, spans in runs:
        try:
            st = optimal_shaper(sc, session, "JL", T_F, band, spans=spans, signed=sgn,
                                enough=2, objective=obj)
        except ValueError as e:
            notes.append(str(e))
            continue
        out += [(spec, "LP on the tuning set") for _, spec in st.candidates[:2]]
    return out


def _graceful_shapers(sc: Scenario, session: Session, T_F: tuple[float, ...], band: float,
                      ys: Yardstick, quiet: Quiet | None, signed: bool, notes: list[str]
                      ) -> list[tuple[ShaperSpec, str]]:
    """Return the LP designs on JL held beyond the stated set (the textbook deadlines).

    The design set is the tuning set and each stated kind at 1.125 … 2 times
    its range (:func:`harness.tuning.graceful.design_points`); the worst case
    over the tuning set is minimised, every point keeps the error in the band
    from its deadline on (B at its width; inside the stated set too, and, as a
    second design, only beyond it), and the assumed unmodelled modes stay quiet.
    """
    spec = sc.uncertainty
    tun = sc.uncertainty.tuning_set().points
    pts = design_points(spec, tun)
    mm = np.array([i < len(tun) for i in range(len(pts))])
    dl_all = np.array([ys.deadline(p) for p in pts])
    lev = np.array([level(spec, p) for p in pts])
    obj = ShapedObjective(sc, session, "JL", T_F, pts, band)
    n_d = obj.period / obj.Te
    out: list[tuple[ShaperSpec, str]] = []
    settings = (("graceful", dl_all), ("graceful beyond the stated set",
                                       np.where(lev > 1.0 + 1e-9, dl_all, np.inf)))
    runs = [(False, (0.9, 1.0, 1.2))]
    if signed:
        runs.append((True, (0.6, 0.7, 0.8, 0.9)))
    for what, dl in settings:
        for sgn, fracs in runs:
            spans = tuple(int(round(f * n_d)) for f in fracs)
            try:
                st = optimal_shaper(sc, session, "JL", T_F, band, spans=spans, signed=sgn,
                                    enough=2, objective=obj, minimax=mm, deadlines=dl,
                                    quiet=quiet)
            except ValueError:
                notes.append(f"no {'signed' if sgn else 'positive'} LP shaper of "
                             f"{'/'.join(f'{f:g}' for f in fracs)} end-mode periods is {what} "
                             f"(settling within the motion at every point of the stated set)")
                continue
            out += [(s, f"LP, {what}") for _, s in st.candidates[:2]]
    return out


def _quiet_of(c: Candidate, sc: Scenario, session: Session, band: float,
              assumed: UnmodelledModes, T_jl: tuple[float, ...],
              quiets: dict[tuple[str, tuple[float, ...]], Quiet]) -> float:
    """Return a candidate's largest residual of an assumed unmodelled mode over its bound."""
    if c.profile == "table":  # replayed on the assumed modes, at each point
        if ("JL", T_jl) not in quiets:
            quiets[("JL", T_jl)] = assumed.quiet(sc, session, T_jl, band)
        bound = quiets[("JL", T_jl)].bound
        scq = assumed.scenario(sc)
        amps = []
        for p in assumed.points(sc.uncertainty):
            modes = tuple(dataclasses.replace(m, mass_ratio=m.mass_ratio / (1.0 + p.scale) ** 2)
                          for m in scq.modemap.modes)
            scp = dataclasses.replace(scq, modemap=dataclasses.replace(scq.modemap,
                                                                         modes=modes))
            table = jerk_table(sc, c)
            t_stop = session.t_stop_after_motion(scp, "table", c.T_F, table=table) \
                + sc.simulation.step
            run = session.run(scp, "table", c.T_F, t_stop=t_stop, table=table)
            amps += [free_amplitude(e, de, m) for (e, de), m in zip(run.state_end,
                                                                     run.modes_end, strict=True)]
        return float(np.max(np.array(amps) / bound))
    key = (c.profile, c.T_F)
    if key not in quiets:
        quiets[key] = assumed.quiet(sc, session, T_jl, band, c.profile, c.T_F)
    sh = c.shaper if c.shaper is not None else ShaperSpec((1.0,), (0,), "none")
    return quiets[key].ratio(np.array(sh.amplitudes), sh.delays)


# ------------------------------------------------------------------ the cache


def _sources() -> list[Path]:
    """Return the code a cached recommendation may depend on (harness but its CLI, C core).

    Their digest is in its key: any change of the code a design runs through
    (the LP, the objectives, the simulation, the scoring) tunes it again.
    """
    root = Path(__file__).resolve().parent
    out = sorted(p for p in root.rglob("*.py") if "commands" not in p.relative_to(root).parts)
    try:  # and the C core the fast engine and the FMU are built from
        out += sorted(p for p in fmu_src_dir().glob("*.[ch]"))
    except (OSError, RuntimeError):  # pragma: no cover - an install without the sources
        pass
    return out


def _cache_key(sc: Scenario, band: float, signed: bool = True,
               assumed: UnmodelledModes | None = None) -> str:
    """Return a recommendation's key: the move, the map, the uncertainty, the band, the code."""
    h = hashlib.sha256()
    for path in _sources():
        h.update(path.read_bytes())
    case = (sc.move, sc.z, sc.modemap, sc.uncertainty, sc.simulation.Te, sc.simulation.step,
            sc.simulation.short_stage, sc.compare.JL_T_F, sc.compare.jl_tuning,
            sc.compare.djl_rule, sc.compare.period_band, sc.compare.max_motion_time)
    h.update(repr((case, float(band).hex(), bool(signed), assumed, __version__)).encode())
    return h.hexdigest()[:32]


def _candidate_json(c: Candidate) -> dict[str, Any]:
    d = dataclasses.asdict(c)
    d["shaper"] = None if c.shaper is None else dataclasses.asdict(c.shaper)
    return d


def _candidate_of(d: dict[str, Any]) -> Candidate:
    sh = d["shaper"]
    spec = None if sh is None else ShaperSpec(tuple(sh["amplitudes"]), tuple(sh["delays"]),
                                              sh["name"])
    return Candidate(d["family"], d["profile"], tuple(d["T_F"]), spec,
                     *(float(d[k]) for k in ("settling_worst", "residual_worst", "residual",
                                             "motion_time")),
                     str(d["design"]), float(d["excess"]),
                     str(d["excess_at"]), float(d["quiet"]),
                     {k: [float(x) for x in v] for k, v in d["curves"].items()},
                     tuple(float(x) for x in d.get("jerk", ())))


def _to_json(rec: Recommendation) -> str:
    return json.dumps({"candidates": [_candidate_json(c) for c in rec.candidates],
                       "tuning_set": rec.tuning_set, "notes": rec.notes,
                       "widths": rec.widths, "textbook": rec.textbook,
                       "explanation": rec.explanation, "rule": rec.rule,
                       "assumption": rec.assumption, "jl_motion_time": rec.jl_motion_time,
                       "quiet_limit": rec.quiet_limit},
                      indent=1)


def _of_json(text: str, band: float, seconds: float) -> Recommendation:
    got = json.loads(text)
    cands = [_candidate_of(d) for d in got["candidates"]]
    return Recommendation(cands[0], cands, band, str(got["tuning_set"]), seconds,
                          [*got["notes"], "from the cache"], [float(w) for w in got["widths"]],
                          {m: {k: [float(x) for x in v] for k, v in c.items()}
                           for m, c in got["textbook"].items()},
                          [str(x) for x in got["explanation"]], str(got["rule"]),
                          str(got["assumption"]), float(got["jl_motion_time"]),
                          float(got["quiet_limit"]))


# ------------------------------------------------------------------ the choice


def _explain(rec: Recommendation, sc: Scenario, ys: Yardstick) -> list[str]:
    b, Te = rec.best, sc.simulation.Te
    out = [f"chosen by {RULE}",
           f"{b.family} ({b.design}): {b.label(Te)}; worst-case settling {b.settling_worst:.3f} s "
           f"over the stated uncertainty ({rec.tuning_set})"]
    w, who = rec.holds_to()
    if math.isfinite(w):
        if who:
            upto = (f"up to {w:g}x the stated error; beyond" if w > 0
                    else "not past the exact map; there")
            out.append(f"no worse than every textbook shaper (JL*ZV, ZVD, EI, SI) {upto}, "
                       f"{who} is better (largest excess "
                       f"{100 * (b.excess - 1):.1f} % at {b.excess_at})")
        else:
            out.append(f"no worse than every textbook shaper (JL*ZV, ZVD, EI, SI) at any "
                       f"actual error up to {w:g}x the stated one")
    if math.isfinite(b.quiet):
        out.append(f"unmodelled modes: {rec.assumption}; its largest such residual is "
                   f"{b.quiet:.2f} x that bound")
    best_e = min(c.settling_worst for c in rec.candidates)

    def rank(c: Candidate) -> tuple[int, int, float, float]:
        return (int(c.quiet > rec.quiet_limit), int(not c.excess <= 1.0 + GRACE),
                c.settling_worst, c.motion_time)

    for fam in FAMILIES:
        if fam == b.family:
            continue
        got = [c for c in rec.candidates if c.family == fam]
        if not got:
            out.append(f"{fam}: no design")
            continue
        scored = [c for c in got if c.curves]
        if not scored:
            c = min(got, key=lambda c: c.settling_worst)
            out.append(f"{fam}: worst-case settling {c.settling_worst:.3f} s, more than "
                       f"{100 * SCREEN:g} % later than the best ({best_e:.3f} s)")
            continue
        c = min(scored, key=rank)
        why = f"{fam} ({c.design}): worst-case settling {c.settling_worst:.3f} s"
        if c.quiet > rec.quiet_limit:
            why += f"; excites an unmodelled mode {c.quiet:.2f} x the bound"
        elif not c.excess <= 1.0 + GRACE:
            why += f"; {100 * (c.excess - 1):.1f} % behind a textbook shaper at {c.excess_at}"
        else:
            why += f"; graceful too, but {c.settling_worst - b.settling_worst:+.3f} s in the " \
                   f"worst case of the stated uncertainty"
        out.append(why)
    out.extend(n for n in rec.notes if n != "from the cache")
    if math.isfinite(rec.jl_motion_time):
        extra = 100 * (b.motion_time / rec.jl_motion_time - 1)
        out.append(f"motion time {b.motion_time:.3f} s, {extra:+.1f} % against JL's "
                   f"{rec.jl_motion_time:.3f} s")
    return out


def recommend(sc: Scenario, session: Session, band: float, *,
              jl: TuningResult | None = None, cache: bool = True,
              signed: bool = True, unmodelled: UnmodelledModes | None = ASSUMED
              ) -> Recommendation:
    """Tune every family robustly; recommend the graceful one that settles first (:data:`RULE`).

    Parameters
    ----------
    sc : Scenario
        A single-move scenario (its ``uncertainty`` gives the tuning set).
    session : Session
        Its generator instances (the tuning runs on the fast engine).
    band : float
        The settling band (m), the case's.
    jl : TuningResult, optional
        JL's tuning, if already done.
    cache : bool
        Keep the result on disk (next to the FMU builds, ``$DJL_FMU_CACHE``),
        keyed by the move, the map, the uncertainty, the band and the code of
        the harness: the same case is not tuned twice (the environment variable
        ``DJL_FMU_RECOMMEND_CACHE=off`` turns it off everywhere).
    signed : bool
        Let the JL*shaper family use shapers with negative amplitudes, their
        bounds kept on every sample (:func:`harness.tuning.shaping.optimal_shaper`):
        |j| no higher than JL's, the acceleration and velocity within the move's
        limits, the velocity never reversed.  False: positive amplitudes only.
    unmodelled : UnmodelledModes or None
        What is assumed of modes above the modelled ones (None: nothing; the
        graceful designs then ignore them).

    Returns
    -------
    Recommendation
    """
    t0 = time.perf_counter()
    if os.environ.get("DJL_FMU_RECOMMEND_CACHE", "").strip().lower() in ("0", "off", "no"):
        cache = False  # the benchmarks' cold designs
    path = cache_dir() / "recommend" / f"{_cache_key(sc, band, signed, unmodelled)}.json" \
        if cache else None
    if path is not None and path.is_file():
        try:
            return _of_json(path.read_text(encoding="utf-8"), band, time.perf_counter() - t0)
        except (OSError, ValueError, KeyError, TypeError):
            pass  # a stale or damaged entry: tuned again, and rewritten
    fast = session.fast()
    if jl is None:
        jl = tune_profile(fast, sc, "JL")
    if jl is None:
        raise ValueError(f"{sc.name}: JL's jerk time is imposed; the recommendation tunes it")
    T_jl = tuple(jl.T_F)
    notes: list[str] = []
    cands: list[Candidate] = []
    # DJL robust, no jerk above JL's
    scd = dataclasses.replace(sc, compare=dataclasses.replace(
        sc.compare, djl_tuning="paper", DJL_T_F=None))
    paper = tune_profile(fast, scd, "DJL")
    opts = dataclasses.replace(sc.tuning_options(), jerk_limit="JL")
    djl = tune_optimal(sc, fast, "DJL", "robust", paper, jl, opts)
    T_djl = tuple(djl.T_F)
    cands.append(_measure(sc, fast, "DJL (robust)", "DJL", T_djl, None, band, "robust search"))
    ys = Yardstick.measure(sc, fast, T_jl, band, runs=_textbook_runs(sc, fast, T_jl))
    quiet = unmodelled.quiet(sc, fast, T_jl, band) if unmodelled is not None else None
    quiets: dict[tuple[str, tuple[float, ...]], Quiet] = {}
    if quiet is not None:
        quiets[("JL", T_jl)] = quiet
    limit = 1.0 + 1e-6 if unmodelled is not None else math.inf

    def score(c: Candidate) -> None:
        """Score a candidate at every width, and its unmodelled modes."""
        run = _run(sc, fast, c)
        curve = ys.curve(ys.score(run, sc, band))
        c.curves = {k: [float(x) for x in v] for k, v in curve.items()}
        with np.errstate(invalid="ignore", divide="ignore"):  # both never settle: a tie
            r = {k: np.where(np.asarray(curve[k]) == ys.best[k], 1.0,
                             np.asarray(curve[k]) / ys.best[k]) for k in curve}
        k_worst = max(r, key=lambda k: float(np.max(r[k])))
        i = int(np.argmax(r[k_worst]))
        c.excess = float(r[k_worst][i])
        c.excess_at = f"{ys.widths[i]:g}x the stated {k_worst.replace('_', ' ')}"
        if unmodelled is not None:
            c.quiet = _quiet_of(c, sc, fast, band, unmodelled, T_jl, quiets)

    refs = _reference_designs(sc, fast, T_jl, band, ys, unmodelled, notes)
    for r, design in refs:
        c = _measure(sc, fast, "LP reference", "table", T_jl, None, band, design,
                     tuple(float(x) for x in r.jerk))
        score(c)
        cands.append(c)
    classic = _classic_shapers(sc)
    # the shaper families: designed in full only when no LP reference is graceful and quiet
    # (where one is, it settles sooner in the worst case than every shaper measured: on X, Y
    # and the machines of benchmarks/bench_machines.py); the textbook ones always
    held = any(c.excess <= 1.0 + GRACE and not c.quiet > limit for c in cands)
    pts = sc.uncertainty.tuning_set().points
    for family, profile, T_F in (("JL*shaper", "JL", T_jl), ("DJL*shaper", "DJL", T_djl)):
        specs: list[tuple[ShaperSpec, str]] = [(c, "textbook") for c in classic]
        if not held:
            obj = ShapedObjective(sc, fast, profile, T_F, pts, band)
            for impulses in (2, 3):
                st = robust_shaper(sc, fast, profile, T_F, band, impulses=impulses,
                                   objective=obj)
                specs += [(spec, "robust search") for _, spec in st.candidates[:2]]
            if profile == "JL":
                specs += _lp_shapers(sc, fast, T_F, band, obj, st.shaper.span, signed, notes)
                specs += _graceful_shapers(sc, fast, T_F, band, ys, quiet, signed, notes)
        for spec, design in specs:
            cands.append(_measure(sc, fast, family, profile, T_F, spec, band, design))
    if held:
        notes.append("the searched and LP shapers were not designed: an LP reference is "
                     "graceful and keeps the unmodelled modes quiet")
    # the competitive ones at every width, and their unmodelled modes
    best_e = min(c.settling_worst for c in cands)
    for c in cands:
        if not c.curves and c.settling_worst <= best_e * (1.0 + SCREEN):
            score(c)
    scored = [c for c in cands if c.curves]
    ok = [c for c in scored if not c.quiet > limit]
    if not ok:
        ok = sorted(scored, key=lambda c: c.quiet)[:1]
        notes.append(f"no candidate keeps the assumed unmodelled modes quiet; the quietest "
                     f"({ok[0].quiet:.2f} x its bound) was kept")
    def excess(c: Candidate) -> float:
        return c.excess if math.isfinite(c.excess) else math.inf

    def order(c: Candidate) -> tuple[float, float]:
        t = c.settling_worst
        return (t if math.isfinite(t) else math.inf, c.motion_time)

    graceful = [c for c in ok if excess(c) <= 1.0 + GRACE]
    if graceful:
        pick = min(graceful, key=order)
    else:  # the trade-off: the least excess, then the stated width
        e_min = min((excess(c) for c in ok), default=math.inf)
        pool = [c for c in ok if excess(c) <= e_min * (1.0 + TIE)] if math.isfinite(e_min) \
            else (ok or cands)
        pick = min(pool, key=order)
        notes.append(f"no candidate is as good as the best textbook shaper at every width: "
                     f"the least excess, {100 * (e_min - 1):.1f} %, bound the choice"
                     if math.isfinite(e_min) else
                     "no candidate could be compared with the textbook shapers at every width "
                     "(they never settle): the least worst case of the stated uncertainty")
    rest = sorted((c for c in cands if c is not pick),
                  key=lambda c: (c.settling_worst if math.isfinite(c.settling_worst)
                                 else math.inf, c.motion_time))
    label = sc.uncertainty.tuning_set().label
    jl_run = fast.run(sc, "JL", T_jl, t_stop=fast.t_stop_after_motion(sc, "JL", T_jl))
    rec = Recommendation(pick, [pick, *rest], band, label, 0.0, notes,
                         [float(w) for w in ys.widths],
                         {m: {k: [float(x) for x in v] for k, v in c.items()}
                          for m, c in ys.curves.items()},
                         assumption=unmodelled.describe() if unmodelled is not None else "",
                         jl_motion_time=float(jl_run.motion_time), quiet_limit=limit)
    rec.explanation = _explain(rec, sc, ys)
    rec.seconds = time.perf_counter() - t0
    if path is not None:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            write_text(path, _to_json(rec))
        except OSError as e:  # a read-only cache: tuned again next time
            notes.append(f"not cached ({e.strerror or e})")
    return rec
