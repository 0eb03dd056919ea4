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
  jerk and the move's limits then kept on every sample; among them the
  *graceful* designs, held beyond the stated set (below);
* ``DJL*shaper`` -- the robust DJL convolved with a shaper;

then measures each candidate exactly (the whole record, every point of the
tuning set, the case's settling band).

**Beyond the stated set** (:mod:`harness.tuning.graceful`).  The actual error
may be anything from none to twice the stated one.  For every width w from 0
to 2 (times the stated ranges; each stated kind alone, and the whole box) the
yardstick is the best textbook shaper on JL (ZV, ZVD, EI, SI at the end
mode): B(w), its worst-case settling over the points of that width.  The
graceful LP designs keep, at every point of a wider design set, the error in
the band from B(that point's width) on.  The competitive candidates are then
scored at every width, and the recommendation is chosen by one stated rule:

    **least regret**: the candidate whose worst-case settling, at every width
    from 0 to 2 and for every kind, exceeds the best of all the methods
    considered at that width (the candidates and the textbook shapers) by the
    least factor; ties (within 0.5 %) go to the least worst case at the stated
    width, then to the shorter motion.

A candidate must keep the **unmodelled modes** the recommendation assumes
quiet (:class:`harness.tuning.graceful.UnmodelledModes`: any mode at 2-8x the
highest modelled one, gain up to 0.3, ζ ≥ 0.02, is left a residual no larger
than JL's, or than 10 % of the band); only when none does is the quietest
kept, and the notes say so.  The regrets are taken among the candidates that
keep it.

The recommendation says why (:attr:`Recommendation.explanation`): the chosen
family and design, its regret and where it is reached, up to what width it is
no worse than every textbook shaper and which one is better beyond, why each
other family lost, and its motion time against JL's.

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
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from . import __version__
from .files import write_text
from .fmu.build import cache_dir
from .scenario import Scenario
from .scoring import score_uncertainty
from .shaper_designs import ei, zvd
from .simulation.session import Session
from .simulation.shaped_axis import ShaperSpec
from .tuning.graceful import TOP, UnmodelledModes, Yardstick, design_points
from .tuning.rule import TuningResult
from .tuning.search import tune_optimal
from .tuning.shaping import Quiet, ShapedObjective, optimal_shaper, robust_shaper
from .tuning.tune import tune_profile
from .uncertainty import level

__all__ = ["ASSUMED", "FAMILIES", "RULE", "Candidate", "Recommendation", "recommend"]

FAMILIES = ("DJL (robust)", "JL*shaper", "DJL*shaper")
"""The families the recommendation chooses from."""

RULE = ("least regret: the least factor by which the worst-case settling, at any actual error "
        f"from 0 to {TOP:g}x the stated one (each stated kind alone and together), exceeds the "
        "best of every method considered at that width (the candidates and the textbook "
        "shapers JL*ZV, ZVD, EI, SI); ties within 0.5 %: the least worst case at the stated "
        "width, then the shorter motion")
"""The rule that picks the recommendation, in words."""

ASSUMED = UnmodelledModes()
"""What the recommendation assumes of unmodelled modes by default."""

TIE = 0.005
"""Regrets within this fraction of each other tie (then the stated width decides)."""

SCREEN = 0.15
"""Candidates whose worst case at the stated width is within this fraction of the best are
scored at every width (the others cannot have the least regret there)."""


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
    regret : float
        Its largest worst-case settling over the best method's, at any width up
        to :data:`~harness.tuning.graceful.TOP` (1: the best everywhere); NaN if
        not scored at every width.
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
    regret: float = math.nan
    excess: float = math.nan
    excess_at: str = ""
    quiet: float = math.nan
    curves: dict[str, list[float]] = field(default_factory=dict)

    def label(self, Te: float) -> str:
        """Return the method in words: the family, the jerk times, the shaper."""
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
        Why this one: the rule, the family and design, the regret, how far it
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
        p = Session.move_params(sc, self.best.profile, self.best.T_F)
        if self.best.shaper is not None:
            p.update(self.best.shaper.fmu_parameters(sc.simulation.Te))
        return p

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


def _measure(sc: Scenario, session: Session, family: str, profile: str,
             T_F: tuple[float, ...], shaper: ShaperSpec | None, band: float,
             design: str = "") -> Candidate:
    run = session.run(sc, profile, T_F, shaper=shaper)
    sco = score_uncertainty(run, sc, band, sc.uncertainty.tuning_set())
    return Candidate(family, profile, tuple(T_F), shaper, float(sco["settling_time_worst"]),
                     float(sco["residual_worst"]), run.free_amplitude, run.motion_time, design)


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
    key = (c.profile, c.T_F)
    if key not in quiets:
        quiets[key] = assumed.quiet(sc, session, T_jl, band, c.profile, c.T_F)
    sh = c.shaper if c.shaper is not None else ShaperSpec((1.0,), (0,), "none")
    return quiets[key].ratio(np.array(sh.amplitudes), sh.delays)


# ------------------------------------------------------------------ the cache


_SOURCES = ("recommend.py", "tuning/shaping.py", "tuning/search.py", "tuning/rule.py",
            "tuning/tune.py", "tuning/graceful.py", "scoring.py", "uncertainty.py",
            "simulation/master.py", "simulation/shaped_axis.py", "shaper_designs.py")
"""The modules whose code a cached recommendation depends on (their digest is in its key)."""


def _cache_key(sc: Scenario, band: float, signed: bool = True,
               assumed: UnmodelledModes | None = None) -> str:
    """Return a recommendation's key: the move, the map, the uncertainty, the band, the code."""
    root = Path(__file__).resolve().parent
    h = hashlib.sha256()
    for name in _SOURCES:
        h.update((root / name).read_bytes())
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
                     str(d["design"]), float(d["regret"]), float(d["excess"]),
                     str(d["excess_at"]), float(d["quiet"]),
                     {k: [float(x) for x in v] for k, v in d["curves"].items()})


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


def _regrets(cands: list[Candidate], ys: Yardstick) -> None:
    """Set every scored candidate's regret: its worst case over the best method's, at any width."""
    scored = [c for c in cands if c.curves]
    for sw in ys.sweeps:
        k = sw.kind
        best = np.min(np.vstack([ys.best[k]] + [np.asarray(c.curves[k]) for c in scored]),
                      axis=0)
        for c in scored:
            r = float(np.max(np.asarray(c.curves[k]) / best))
            c.regret = r if math.isnan(c.regret) else max(c.regret, r)


def _explain(rec: Recommendation, sc: Scenario, ys: Yardstick) -> list[str]:
    b, Te = rec.best, sc.simulation.Te
    out = [f"chosen by {RULE}",
           f"{b.family} ({b.design}): {b.label(Te)}; worst-case settling {b.settling_worst:.3f} s "
           f"over the stated uncertainty ({rec.tuning_set})"]
    if math.isfinite(b.regret):
        out.append(f"regret {100 * (b.regret - 1):.1f} %: at no actual error from 0 to "
                   f"{TOP:g}x the stated one is another method faster than that in the "
                   f"worst case")
    w, who = rec.holds_to()
    if math.isfinite(w):
        if who:
            out.append(f"no worse than every textbook shaper (JL*ZV, ZVD, EI, SI) up to "
                       f"{w:g}x the stated error; beyond, JL*{who} is better (largest excess "
                       f"{100 * (b.excess - 1):.1f} % at {b.excess_at})")
        else:
            out.append(f"no worse than every textbook shaper (JL*ZV, ZVD, EI, SI) at any "
                       f"actual error up to {w:g}x the stated one")
    if math.isfinite(b.quiet):
        out.append(f"unmodelled modes: {rec.assumption}; its largest such residual is "
                   f"{b.quiet:.2f} x that bound")
    for fam in FAMILIES:
        if fam == b.family:
            continue
        got = [c for c in rec.candidates if c.family == fam]
        if not got:
            out.append(f"{fam}: no design")
            continue
        c = min(got, key=lambda c: c.settling_worst)
        why = f"{fam}: worst-case settling {c.settling_worst:.3f} s"
        if math.isfinite(c.regret):
            why += f", regret {100 * (c.regret - 1):.1f} %"
        if math.isfinite(c.quiet) and c.quiet > rec.quiet_limit:
            why += f", excites an unmodelled mode {c.quiet:.2f} x the bound"
        out.append(why)
    for n in rec.notes:
        if n.startswith("no "):
            out.append(n)
    if math.isfinite(rec.jl_motion_time):
        extra = 100 * (b.motion_time / rec.jl_motion_time - 1)
        out.append(f"motion time {b.motion_time:.3f} s, {extra:+.1f} % against JL's "
                   f"{rec.jl_motion_time:.3f} s")
    return out


def recommend(sc: Scenario, session: Session, band: float, *,
              jl: TuningResult | None = None, cache: bool = True,
              signed: bool = True, unmodelled: UnmodelledModes | None = ASSUMED
              ) -> Recommendation:
    """Tune every family robustly and recommend by least regret over every actual error width.

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
        the tuning: the same case is not tuned twice.
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
    ys = Yardstick.measure(sc, fast, T_jl, band)
    quiet = unmodelled.quiet(sc, fast, T_jl, band) if unmodelled is not None else None
    classic = _classic_shapers(sc)
    pts = sc.uncertainty.tuning_set().points
    for family, profile, T_F in (("JL*shaper", "JL", T_jl), ("DJL*shaper", "DJL", T_djl)):
        specs: list[tuple[ShaperSpec, str]] = [(c, "textbook") for c in classic]
        obj = ShapedObjective(sc, fast, profile, T_F, pts, band)
        for impulses in (2, 3):
            st = robust_shaper(sc, fast, profile, T_F, band, impulses=impulses, objective=obj)
            specs += [(spec, "robust search") for _, spec in st.candidates[:2]]
        if profile == "JL":
            specs += _lp_shapers(sc, fast, T_F, band, obj, st.shaper.span, signed, notes)
            specs += _graceful_shapers(sc, fast, T_F, band, ys, quiet, signed, notes)
        for spec, design in specs:
            cands.append(_measure(sc, fast, family, profile, T_F, spec, band, design))
    # the competitive ones at every width, and their unmodelled modes
    best_e = min(c.settling_worst for c in cands)
    quiets: dict[tuple[str, tuple[float, ...]], Quiet] = {}
    if quiet is not None:
        quiets[("JL", T_jl)] = quiet
    for c in cands:
        if c.settling_worst <= best_e * (1.0 + SCREEN):
            run = fast.run(sc, c.profile, c.T_F, shaper=c.shaper)
            curve = ys.curve(ys.score(run, sc, band))
            c.curves = {k: [float(x) for x in v] for k, v in curve.items()}
            r = {k: np.asarray(curve[k]) / ys.best[k] for k in curve}
            k_worst = max(r, key=lambda k: float(np.max(r[k])))
            i = int(np.argmax(r[k_worst]))
            c.excess = float(r[k_worst][i])
            c.excess_at = f"{ys.widths[i]:g}x the stated {k_worst.replace('_', ' ')}"
            if unmodelled is not None:
                c.quiet = _quiet_of(c, sc, fast, band, unmodelled, T_jl, quiets)
    limit = 1.0 + 1e-6 if unmodelled is not None else math.inf
    scored = [c for c in cands if c.curves]
    ok = [c for c in scored if not c.quiet > limit]
    if not ok:
        ok = sorted(scored, key=lambda c: c.quiet)[:1]
        notes.append(f"no candidate keeps the assumed unmodelled modes quiet; the quietest "
                     f"({ok[0].quiet:.2f} x its bound) was kept")
    _regrets(ok, ys)
    r_min = min(c.regret for c in ok)
    pick = min((c for c in ok if c.regret <= r_min * (1.0 + TIE)),
               key=lambda c: (c.settling_worst, c.motion_time))
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
