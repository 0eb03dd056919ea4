"""A reference the generator replays sample by sample: :class:`JerkTable` (profile ``table``).

A jerk table is a piecewise-constant jerk on the generator's sampling grid: piece ``i``
holds the jerk ``jerk[i]`` (m/s³) for ``samples[i]`` samples of Te.  The FMU and the
compiled engine replay it from ``x0`` (profile 4, parameters ``table_n``,
``table_samples``, ``table_jerk``; docs/generator.md, "Replayed tables"): x, v, a are
the exact piecewise cubic, and the table must end at rest at ``x0 + distance``, within
the limits ``v_max``, ``a_max``, ``d_max``.  References that no AL/JL/DJL plan or input
shaper represents (a linear programme's bang-bang jerk, say) reach a simulator user
through it, without Python.

Examples
--------
>>> from harness.simulation.jerk_table import JerkTable
>>> t = JerkTable.from_jerk_samples([100.0] * 50 + [-100.0] * 100 + [100.0] * 50, 1e-3)
>>> t.samples, t.jerk
((50, 100, 50), (100.0, -100.0, 100.0))
>>> round(t.motion_time(1e-3), 12)
0.2
>>> t.fmu_parameters()["table_n"]
3
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..fmu import spec

__all__ = ["JerkTable", "MERGE_RTOL"]

MERGE_RTOL = 1e-12
"""Neighbouring samples whose jerks differ by at most this much of the array's largest
|jerk| are one piece (:meth:`JerkTable.from_jerk_samples`)."""


def _check_te(Te: float) -> float:
    if isinstance(Te, bool) or not isinstance(Te, (int, float, np.integer, np.floating)) \
            or not math.isfinite(float(Te)) or not float(Te) > 0.0:
        raise ValueError(f"Te must be a finite number > 0 (s), got {Te!r}")
    return float(Te)


@dataclass(frozen=True)
class JerkTable:
    """Piecewise-constant jerk on the sample grid: ``jerk[i]`` for ``samples[i]`` samples.

    Attributes
    ----------
    samples : tuple of int
        Length of each piece, in samples of the generator's Te, each in
        1..``spec.MAX_FILTER_SAMPLES``.
    jerk : tuple of float
        Jerk over each piece (m/s³), finite.

    Raises
    ------
    ValueError
        Naming the entry: samples and jerk of different lengths, more than
        ``spec.MAX_TABLE`` pieces, a length that is not an int in range, a jerk that is
        not a finite number.  (What needs the move's parameters -- the limits, the end
        at rest on the target -- the generator checks, naming the entry.)
    """

    samples: tuple[int, ...]
    jerk: tuple[float, ...]

    def __post_init__(self) -> None:
        try:
            s, j = tuple(self.samples), tuple(self.jerk)
        except TypeError:
            raise ValueError("samples and jerk must be sequences") from None
        if len(s) != len(j):
            raise ValueError(f"a table needs as many samples as jerks, got {len(s)} and "
                             f"{len(j)}")
        if len(s) > spec.MAX_TABLE:
            raise ValueError(f"a table holds at most {spec.MAX_TABLE} pieces, got {len(s)}")
        for i, n in enumerate(s):
            if isinstance(n, (bool, np.bool_)) or not isinstance(n, (int, np.integer)) \
                    or not 1 <= int(n) <= spec.MAX_FILTER_SAMPLES:
                raise ValueError(f"samples[{i}] = {n!r}: a piece lasts a whole number of "
                                 f"samples, 1..{spec.MAX_FILTER_SAMPLES}")
        for i, x in enumerate(j):
            if isinstance(x, (bool, np.bool_)) or not isinstance(
                    x, (int, float, np.integer, np.floating)) or not math.isfinite(float(x)):
                raise ValueError(f"jerk[{i}] = {x!r}: must be a finite number (m/s3)")
        object.__setattr__(self, "samples", tuple(int(n) for n in s))
        object.__setattr__(self, "jerk", tuple(float(x) for x in j))

    def __len__(self) -> int:
        return len(self.samples)

    @classmethod
    def from_jerk_samples(cls, jerk_per_sample: Sequence[float] | np.ndarray, Te: float,
                          rtol: float = MERGE_RTOL) -> JerkTable:
        """Run-length encode a jerk given per sample of Te.

        Neighbouring samples whose jerks differ by at most ``rtol`` times the array's
        largest |jerk| make one piece; its jerk is their mean (their exact value when they
        are all equal), so that the acceleration each piece ends at is the array's.

        Parameters
        ----------
        jerk_per_sample : sequence of float
            The jerk over each sample interval (m/s³), finite.
        Te : float
            The sampling period (s) the array is on: the table's end state (acceleration,
            velocity, position after every piece, :meth:`end_state`) is checked to equal
            the array's to 1e-9 of its largest value, so that merging never moves the
            end (with the default ``rtol`` it moves it by rounding only).
        rtol : float
            The merge tolerance, in [0, 1e-6].

        Raises
        ------
        ValueError
            A jerk that is not finite, a Te that is not a finite number > 0, a ``rtol`` out
            of range, more runs than ``spec.MAX_TABLE``, or a merge that moves the end
            state.
        """
        Te = _check_te(Te)
        if isinstance(rtol, bool) or not isinstance(rtol, (int, float)) \
                or not 0.0 <= float(rtol) <= 1e-6:
            raise ValueError(f"rtol must be in [0, 1e-6], got {rtol!r}")
        j = np.asarray(jerk_per_sample, dtype=float).ravel()
        if not np.all(np.isfinite(j)):
            k = int(np.flatnonzero(~np.isfinite(j))[0])
            raise ValueError(f"jerk_per_sample[{k}] = {float(j[k])!r}: must be finite")
        tol = float(rtol) * (float(np.max(np.abs(j))) if j.size else 0.0)
        samples: list[int] = []
        jerk: list[float] = []
        start = 0
        for k in range(1, j.size + 1):
            if k < j.size and abs(j[k] - j[start]) <= tol and k - start < spec.MAX_FILTER_SAMPLES:
                continue
            run = j[start:k]
            samples.append(k - start)
            jerk.append(float(run[0]) if np.all(run == run[0]) else math.fsum(run) / run.size)
            start = k
        if len(samples) > spec.MAX_TABLE:
            raise ValueError(f"the jerk has {len(samples)} runs of equal values (to {rtol:g} of "
                             f"its largest), more than the {spec.MAX_TABLE} pieces of a table")
        table = cls(tuple(samples), tuple(jerk))
        if j.size:
            mine = np.array(table.end_state(Te))
            theirs = np.array(_end_state_per_sample(j, Te))
            scale = np.maximum(np.array(table.extremes(Te)), 1e-300)
            if np.any(np.abs(mine - theirs) > 1e-9 * scale):
                raise ValueError(f"merging the jerk's runs (rtol = {rtol:g}) moves its end "
                                 f"state (x, v, a) from {tuple(theirs)} to {tuple(mine)}: "
                                 f"use a smaller rtol")
        return table

    def fmu_parameters(self) -> dict[str, Any]:
        """Return the generator's parameters of this table.

        ``profile`` (4), ``table_n``, ``table_samples``, ``table_jerk``; the move's
        ``distance`` (the end position, see :meth:`end_state`) and limits are the caller's.
        """
        return {"profile": spec.PROFILE_CODES["table"], "table_n": len(self.samples),
                "table_samples": list(self.samples), "table_jerk": list(self.jerk)}

    def motion_time(self, Te: float) -> float:
        """Duration of the table (s): its samples times ``Te``."""
        return sum(self.samples) * _check_te(Te)

    def end_state(self, Te: float, v0: float = 0.0) -> tuple[float, float, float]:
        """Position (relative to the start), velocity and acceleration at the table's end.

        Integrated exactly piece by piece (a cubic over each), from rest or ``v0``, in the
        order of operations of the generator: the generator replays the table when its
        ``distance`` is this position (within 1e-9 of the travel) and the velocity and
        acceleration are 0 (within 1e-9 of their largest values).
        """
        Te = _check_te(Te)
        x, v, a = 0.0, float(v0), 0.0
        for n, j in zip(self.samples, self.jerk, strict=True):
            L = n * Te
            x, v, a = (x + L * (v + L * (0.5 * a + L * j / 6.0)), v + L * (a + 0.5 * L * j),
                       a + j * L)
        return x, v, a

    def extremes(self, Te: float, v0: float = 0.0) -> tuple[float, float, float]:
        """Return the largest |x − x0|, |v|, |a| over the table.

        At the piece boundaries, and |v| also where it peaks inside a piece: the scales of
        the generator's tolerances.
        """
        Te = _check_te(Te)
        x, v, a = 0.0, float(v0), 0.0
        X, V, A = 0.0, abs(v), 0.0
        for n, j in zip(self.samples, self.jerk, strict=True):
            L = n * Te
            if j != 0.0 and 0.0 < -a / j < L:
                ts = -a / j
                V = max(V, abs(v + ts * (a + 0.5 * ts * j)))
            x, v, a = (x + L * (v + L * (0.5 * a + L * j / 6.0)), v + L * (a + 0.5 * L * j),
                       a + j * L)
            X, V, A = max(X, abs(x)), max(V, abs(v)), max(A, abs(a))
        return X, V, A


def _end_state_per_sample(j: np.ndarray, Te: float) -> tuple[float, float, float]:
    """End state of a jerk given per sample (one piece per sample), in closed form."""
    # the jerk j of sample k acts over [k Te, (k + 1) Te): at the end, r = n - k samples
    # after its start, it has added j Te to a, j Te^2 (r - 1/2) to v and
    # j Te^3 (r^3 - (r - 1)^3) / 6 to x
    r = j.size - np.arange(j.size, dtype=float)
    a = math.fsum(j * Te)
    v = math.fsum(j * Te * Te * (r - 0.5))
    x = math.fsum(j * Te ** 3 * (r ** 3 - (r - 1.0) ** 3) / 6.0)
    return x, v, a
