"""The tuning methods' names and options: the low module every layer may read.

* :data:`DJL_METHODS`, :data:`JL_METHODS` -- how the jerk times are found;
* :data:`RULES` -- the two forms of the paper's DJL rule;
* :data:`VARIANTS` and :func:`split_profile` -- profile names that carry their
  method (``DJL-robust``);
* :class:`TuningOptions` -- what the ``optimal`` / ``robust`` searches may do;
* :func:`parse_tuning` -- the one grammar of the ``--tuning`` option of every
  command: comma-separated items, each ``METHOD``, ``djl=METHOD`` or
  ``jl=METHOD``.

Nothing here runs a simulation: the scenario files (:mod:`harness.scenario`)
check their ``[compare]`` table against these names, the tuning itself lives
in :mod:`harness.tuning.rule` (the paper's rule), :mod:`harness.tuning.search`
(optimal, robust) and :mod:`harness.tuning.tables` (a table of moves).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .uncertainty import check_map_error

__all__ = [
    "DJL_METHODS",
    "JL_METHODS",
    "RULES",
    "VARIANTS",
    "TuningOptions",
    "parse_tuning",
    "split_profile",
    "variants_of",
]

DJL_METHODS = ("paper", "optimal", "robust")
"""DJL tuning methods: the paper's rule (stage starts), minimum residual, minimum worst case."""

JL_METHODS = ("end", "optimal")
"""JL tuning methods: the period at the end of the motion (the paper's), minimum residual."""

RULES = ("start", "phase")
"""Forms of the paper's DJL rule: the modal period at each stage's start (the paper's), or
one modal cycle of the moving mode per stage (:mod:`harness.tuning.rule`)."""

VARIANTS = ("JL-optimal", "DJL-paper", "DJL-optimal", "DJL-robust")
"""Profile names that carry their tuning method: ``<profile>-<method>`` (e.g. in
``[compare] profiles``, next to ``JL`` and ``DJL`` which follow ``jl_tuning`` /
``djl_tuning``)."""

BASE_PROFILES = ("AL", "JL", "DJL")
"""The generator's profiles."""


def split_profile(name: str) -> tuple[str, str | None]:
    """Split a profile name into the generator profile and the tuning method it imposes.

    ``"DJL-robust"`` → ``("DJL", "robust")``; ``"JL"`` → ``("JL", None)``.

    Raises
    ------
    ValueError
        If the name is neither AL, JL, DJL nor one of :data:`VARIANTS`.
    """
    if name in BASE_PROFILES:
        return name, None
    if name in VARIANTS:
        base, method = name.split("-", 1)
        return base, method
    raise ValueError(f"unknown profile {name!r}: AL, JL, DJL or one of {', '.join(VARIANTS)}")


def parse_tuning(text: str | None) -> list[tuple[str, str]]:
    """Read a ``--tuning`` value: the (profile, method) pairs it names, in order.

    The grammar, shared by every command: comma-separated items, each
    ``djl=METHOD``, ``jl=METHOD`` or a bare ``METHOD``; a bare method is DJL's
    when DJL has it (``paper``, ``optimal``, ``robust``), else JL's (``end``).
    Keys and methods are case-insensitive; empty items are ignored.

    Parameters
    ----------
    text : str, optional
        The option's value; None or empty: no pair.

    Returns
    -------
    list of (str, str)
        ``("DJL", method)`` or ``("JL", method)``, duplicates dropped.

    Raises
    ------
    ValueError
        An unknown key or method (the message names the item and the choices).
    """
    out: list[tuple[str, str]] = []
    for raw in (text or "").split(","):
        item = raw.strip()
        if not item:
            continue
        key, sep, value = (s.strip() for s in item.partition("="))
        if not sep:
            value = key.lower()
            key = "djl" if value in DJL_METHODS else "jl" if value in JL_METHODS else ""
        key, value = key.lower(), value.lower()
        if key not in ("djl", "jl"):
            if sep:
                raise ValueError(f"{item!r}: unknown profile {key!r}; write djl=METHOD or "
                                 f"jl=METHOD")
            raise ValueError(f"{item!r} is not a tuning method (DJL: {', '.join(DJL_METHODS)}; "
                             f"JL: {', '.join(JL_METHODS)})")
        choices = DJL_METHODS if key == "djl" else JL_METHODS
        if value not in choices:
            raise ValueError(f"{item!r}: unknown {key.upper()} tuning method {value!r} (choose "
                             f"from {', '.join(choices)})")
        pair = (key.upper(), value)
        if pair not in out:
            out.append(pair)
    return out


def variants_of(pairs: list[tuple[str, str]]) -> list[str]:
    """Return the profile variants that (profile, method) pairs add to a comparison.

    ``("DJL", "robust")`` → ``"DJL-robust"``; ``("JL", "end")`` is JL itself
    (no variant).
    """
    return [f"{p}-{m}" for p, m in pairs if (p, m) != ("JL", "end")]


@dataclass(frozen=True)
class TuningOptions:
    """What the ``optimal`` / ``robust`` searches may do.

    A scenario's are :meth:`harness.scenario.Scenario.tuning_options`: the map
    error and the damping come from its ``uncertainty``
    (:class:`harness.uncertainty.UncertaintySpec`, their only home), whose
    tuning set is what the robust search minimises over.

    Attributes
    ----------
    map_error : float
        Robust: the whole map f(z) is scaled by 1 + e for e in
        [−map_error, +map_error] (the uncertainty's ``map_scale``; :meth:`factors`:
        a grid 1 % apart, at least 21 points).
    damping : tuple of float, optional
        Robust: every mode's damping ratio is also scaled by factors in this
        range (the uncertainty's ``damping``, e.g. ``(0.5, 2.0)``); default:
        nominal damping only.
    max_motion_time : float or "JL", optional
        The motion may not last longer than this (s), or than JL's motion.
        Default: no bound.
    period_band : float
        Each jerk time stays within [(1 − b)·P_i, (1 + b)·P_i], P_i the modal
        period at the start of stage i (the paper's value); JL's jerk times are
        always allowed (they are the fallback).
    jerk_limit : {None, "JL"}
        ``"JL"``: no jerk time shorter than JL's, so that no stage's jerk
        exceeds JL's (a comparison at the same jerk bound).
    """

    map_error: float = 0.1
    damping: tuple[float, ...] | None = None
    max_motion_time: float | str | None = None
    period_band: float = 0.5
    jerk_limit: str | None = None

    def __post_init__(self) -> None:
        if self.jerk_limit not in (None, "JL"):
            raise ValueError(f"jerk_limit must be None or 'JL', got {self.jerk_limit!r}")
        check_map_error(self.map_error)
        if self.damping is not None and (not self.damping or not all(
                math.isfinite(d) and d > 0 for d in self.damping)):
            raise ValueError(f"damping factors must be finite numbers > 0, got {self.damping!r}")
        if isinstance(self.max_motion_time, str):
            if self.max_motion_time != "JL":
                raise ValueError("max_motion_time must be a time in s or 'JL', got "
                                 f"{self.max_motion_time!r}")
        elif self.max_motion_time is not None and not (
                math.isfinite(self.max_motion_time) and self.max_motion_time > 0):
            raise ValueError(f"max_motion_time must be > 0 s, got {self.max_motion_time!r}")
        if not (math.isfinite(self.period_band) and 0.0 < self.period_band <= 10.0):
            raise ValueError(f"period_band must be in (0, 10], got {self.period_band!r}")

    def factors(self) -> np.ndarray:
        """Frequency factors 1 + e of the robust objective."""
        if self.map_error == 0.0:
            return np.ones(1)
        n = max(10, math.ceil(round(self.map_error / 0.01, 9)))
        return 1.0 + np.linspace(-self.map_error, self.map_error, 2 * n + 1)
