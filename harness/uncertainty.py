"""What the real machine may differ by: the map errors the harness scores and tunes against.

A *map error* e scales the whole mode map: every frequency f(z) becomes
f(z)·(1 + e), the jerk times staying those tuned on the nominal map.  This
module holds the ranges used everywhere and the one check of a map error:

* :data:`DEFAULT_ERRORS` -- the robustness curves, −20 % … +20 %, 1 % apart;
* :data:`WORST_SPAN`, :data:`WORST_ERRORS` -- the worst case, over ±10 %;
* :func:`check_map_error` -- a bound ``map_error`` in [0, 1) (tuning, tables);
* :func:`check_map_errors` -- errors e, finite and > −1 (a frequency > 0).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

__all__ = [
    "DEFAULT_ERRORS",
    "WORST_ERRORS",
    "WORST_SPAN",
    "check_map_error",
    "check_map_errors",
]

DEFAULT_ERRORS = np.linspace(-0.2, 0.2, 41)
"""Map errors of the robustness curves: −20 % to +20 %, 1 % apart."""

WORST_SPAN = 0.10
"""Span of the worst case: map errors within ±10 %."""

WORST_ERRORS = np.linspace(-WORST_SPAN, WORST_SPAN, 21)
"""Map errors of the worst case alone: −10 % to +10 %, 1 % apart (a subset of the curves')."""


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
