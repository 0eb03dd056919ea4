"""The jerk times of a profile of a scenario, by its tuning method: :func:`tune_profile`.

The scenario's ``[compare]`` table names the methods: JL ``end`` (the modal
period at the end of the motion, :func:`harness.tuning.rule.tune_jl`) or
``optimal``; DJL ``paper`` (the period at the start of each stage, rule
``djl_rule``, :func:`harness.tuning.rule.tune_djl`), ``optimal`` or ``robust``
(:func:`harness.tuning.search.tune_optimal`, on the fast engine whatever the
session's).  A profile variant (``DJL-robust``) imposes its own method.
"""

from __future__ import annotations

import dataclasses

from ..scenario import Scenario
from ..simulation.session import Session
from ..tuning_options import split_profile
from .rule import TuningResult, tune_djl, tune_jl
from .search import tune_optimal

__all__ = ["jerk_times", "tune_profile"]


def tune_profile(session: Session, sc: Scenario, profile: str) -> TuningResult | None:
    """Jerk times of ``profile`` from the mode map (None for AL or imposed ones).

    Parameters
    ----------
    session : Session
        The scenario's generator instances (re-planned here).
    sc : Scenario
        A single-move scenario.
    profile : str
        ``AL``, ``JL``, ``DJL`` or a variant such as ``DJL-robust``.

    Returns
    -------
    TuningResult or None
        None for AL, and for a profile whose jerk times the scenario imposes
        (``JL_T_F``, ``DJL_T_F``).
    """
    profile, method = split_profile(profile)
    if method is not None:  # a variant: "DJL-robust" is DJL tuned with "robust"
        field = "jl_tuning" if profile == "JL" else "djl_tuning"
        sc = dataclasses.replace(sc, compare=dataclasses.replace(
            sc.compare, **{field: method}, JL_T_F=None, DJL_T_F=None))
    mm, Te, cmp = sc.modemap, sc.simulation.Te, sc.compare
    if profile == "JL" and cmp.JL_T_F is None:
        jl = tune_jl(session.plan(sc, "JL"), mm.period, Te, mm.period(sc.z.z0 + sc.z.distance))
        if cmp.jl_tuning == "end":
            return jl
        return tune_optimal(sc, session, "JL", cmp.jl_tuning, None, jl, sc.tuning_options())
    if profile == "DJL" and cmp.DJL_T_F is None:
        paper = tune_djl(session.plan(sc, "DJL"), mm.period, Te, mm.period(sc.z.z0),
                         rule=cmp.djl_rule)
        if cmp.djl_tuning == "paper":
            return paper
        jl = tune_jl(session.plan(sc, "JL"), mm.period, Te, mm.period(sc.z.z0 + sc.z.distance))
        return tune_optimal(sc, session, "DJL", cmp.djl_tuning, paper, jl, sc.tuning_options())
    return None


def jerk_times(sc: Scenario, profile: str, tuning: TuningResult | None
               ) -> tuple[float, float, float, float] | None:
    """Return the jerk times a profile runs with: tuned, imposed, or None (AL).

    Parameters
    ----------
    sc : Scenario
        The scenario (its imposed ``JL_T_F`` / ``DJL_T_F``).
    profile : str
        ``AL``, ``JL``, ``DJL`` or a variant.
    tuning : TuningResult or None
        What :func:`tune_profile` returned.
    """
    base = split_profile(profile)[0]
    if base == "AL":
        return None
    if tuning is not None:
        return tuning.T_F
    if base == "JL":
        if sc.compare.JL_T_F is None:
            raise ValueError(f"{sc.name}: {profile} has neither tuned nor imposed jerk times")
        return (sc.compare.JL_T_F,) * 4
    if sc.compare.DJL_T_F is None:
        raise ValueError(f"{sc.name}: {profile} has neither tuned nor imposed jerk times")
    return sc.compare.DJL_T_F
