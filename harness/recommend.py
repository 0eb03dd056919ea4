"""The profile to use: the one that settles first whatever the real mode map (within reason).

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
  jerk and the move's limits then kept on every sample;
* ``DJL*shaper`` -- the robust DJL convolved with a shaper;

then measures each candidate exactly (the whole record, every point of the
tuning set, the case's settling band) and recommends the one whose worst-case
settling time is least (ties: the shorter motion).  Every table reports it on
the finer *scoring* set, never on the points it was chosen on.

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
from .tuning.rule import TuningResult
from .tuning.search import tune_optimal
from .tuning.shaping import ShapedObjective, optimal_shaper, robust_shaper
from .tuning.tune import tune_profile

__all__ = ["FAMILIES", "Candidate", "Recommendation", "recommend"]

FAMILIES = ("DJL (robust)", "JL*shaper", "DJL*shaper")
"""The families the recommendation chooses from."""


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
    """

    family: str
    profile: str
    T_F: tuple[float, ...]
    shaper: ShaperSpec | None
    settling_worst: float
    residual_worst: float
    residual: float
    motion_time: float

    def label(self, Te: float) -> str:
        """Return the method in words: the family, the jerk times, the shaper."""
        ms = "/".join(f"{t * 1e3:.0f}" for t in (self.T_F[:1] if self.profile == "JL"
                                                 else self.T_F))
        txt = f"{self.profile} T_F {ms} ms"
        if self.shaper is not None:
            txt += f" * {self.shaper.describe(Te)}"
        return txt


@dataclass
class Recommendation:
    """The recommended profile of one move, and the candidates it was chosen from.

    Attributes
    ----------
    best : Candidate
        The recommended one.
    candidates : list of Candidate
        Every family's best, measured the same way, best first.
    band : float
        The settling band (m).
    tuning_set : str
        What the candidates were tuned and chosen on.
    seconds : float
        Time to tune and choose.
    notes : list of str
        Anything the choice ran into.
    """

    best: Candidate
    candidates: list[Candidate]
    band: float
    tuning_set: str
    seconds: float
    notes: list[str] = field(default_factory=list)

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


def _measure(sc: Scenario, session: Session, family: str, profile: str,
             T_F: tuple[float, ...], shaper: ShaperSpec | None, band: float) -> Candidate:
    run = session.run(sc, profile, T_F, shaper=shaper)
    sco = score_uncertainty(run, sc, band, sc.uncertainty.tuning_set())
    return Candidate(family, profile, tuple(T_F), shaper, float(sco["settling_time_worst"]),
                     float(sco["residual_worst"]), run.free_amplitude, run.motion_time)


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
                ) -> list[ShaperSpec]:
    """Return the LP designs on JL (:func:`harness.tuning.shaping.optimal_shaper`).

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
    out: list[ShaperSpec] = []
    for sgn, spans in runs:
        try:
            st = optimal_shaper(sc, session, "JL", T_F, band, spans=spans, signed=sgn,
                                enough=2, objective=obj)
        except ValueError as e:
            notes.append(str(e))
            continue
        out += [spec for _, spec in st.candidates[:2]]
    return out


_SOURCES = ("recommend.py", "tuning/shaping.py", "tuning/search.py", "tuning/rule.py",
            "tuning/tune.py", "scoring.py", "uncertainty.py", "simulation/master.py",
            "simulation/shaped_axis.py", "shaper_designs.py")
"""The modules whose code a cached recommendation depends on (their digest is in its key)."""


def _cache_key(sc: Scenario, band: float, signed: bool = True) -> str:
    """Return a recommendation's key: the move, the map, the uncertainty, the band, the code."""
    root = Path(__file__).resolve().parent
    h = hashlib.sha256()
    for name in _SOURCES:
        h.update((root / name).read_bytes())
    case = (sc.move, sc.z, sc.modemap, sc.uncertainty, sc.simulation.Te, sc.simulation.step,
            sc.simulation.short_stage, sc.compare.JL_T_F, sc.compare.jl_tuning,
            sc.compare.djl_rule, sc.compare.period_band, sc.compare.max_motion_time)
    h.update(repr((case, float(band).hex(), bool(signed), __version__)).encode())
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
                                             "motion_time")))


def recommend(sc: Scenario, session: Session, band: float, *,
              jl: TuningResult | None = None, cache: bool = True,
              signed: bool = True) -> Recommendation:
    """Tune every family robustly and recommend the one that settles first in the worst case.

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

    Returns
    -------
    Recommendation
    """
    t0 = time.perf_counter()
    path = cache_dir() / "recommend" / f"{_cache_key(sc, band, signed)}.json" if cache else None
    if path is not None and path.is_file():
        try:
            got = json.loads(path.read_text(encoding="utf-8"))
            cands = [_candidate_of(d) for d in got["candidates"]]
            return Recommendation(cands[0], cands, band, got["tuning_set"],
                                  time.perf_counter() - t0, ["from the cache"])
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
    cands.append(_measure(sc, fast, "DJL (robust)", "DJL", T_djl, None, band))
    classic = _classic_shapers(sc)
    pts = sc.uncertainty.tuning_set().points
    for family, profile, T_F in (("JL*shaper", "JL", T_jl), ("DJL*shaper", "DJL", T_djl)):
        best: Candidate | None = None
        specs = list(classic)
        obj = ShapedObjective(sc, fast, profile, T_F, pts, band)
        for impulses in (2, 3):
            st = robust_shaper(sc, fast, profile, T_F, band, impulses=impulses, objective=obj)
            specs += [spec for _, spec in st.candidates[:2]]
        if profile == "JL":
            specs += _lp_shapers(sc, fast, T_F, band, obj, st.shaper.span, signed, notes)
        for spec in specs:
            c = _measure(sc, fast, family, profile, T_F, spec, band)
            if best is None or (c.settling_worst, c.motion_time) < (best.settling_worst,
                                                                      best.motion_time):
                best = c
        assert best is not None
        cands.append(best)
    cands.sort(key=lambda c: (c.settling_worst if math.isfinite(c.settling_worst) else math.inf,
                              c.motion_time))
    label = sc.uncertainty.tuning_set().label
    if path is not None:
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            write_text(path, json.dumps({"candidates": [_candidate_json(c) for c in cands],
                                         "tuning_set": label}, indent=1))
        except OSError as e:  # a read-only cache: tuned again next time
            notes.append(f"not cached ({e.strerror or e})")
    return Recommendation(cands[0], cands, band, label, time.perf_counter() - t0, notes)

