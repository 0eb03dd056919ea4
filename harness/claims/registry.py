"""Every claim check, by number: the registry (``djl-fmu report`` runs them).

Each claim module registers its ``run(settings)`` with
:func:`harness.claims.base.register` when it is imported; this module imports
them all, in the order of :data:`harness.claims.CATALOGUE`.  Adding a claim is
its module plus a line here and in the catalogue.
"""

from __future__ import annotations

import time
import traceback
from collections.abc import Callable, Sequence

from . import (  # noqa: F401 (each registers its claim when imported)
    djl_stages,
    jl_filtering,
    moving_average,
    residual,
    spectra,
    time_varying,
    vibration_filters,
)
from .base import _REGISTRY, ClaimResult, ClaimSpec, Settings

__all__ = ["registered", "run_claim", "run_claims"]


def registered() -> list[ClaimSpec]:
    """Return the registered claims, by number."""
    return [_REGISTRY[k] for k in sorted(_REGISTRY)]


def run_claim(number: int, settings: Settings | None = None) -> ClaimResult:
    """Run one claim; an exception becomes an ERROR result carrying the traceback."""
    specs = {s.number: s for s in registered()}
    if number not in specs:
        raise KeyError(f"no claim {number}; available: {sorted(specs)}")
    spec = specs[number]
    settings = settings or Settings()
    t0 = time.perf_counter()
    try:
        res = spec.run(settings)
    except Exception:  # noqa: BLE001 - reported, never hidden
        res = ClaimResult(number, spec.title, "", "", error=traceback.format_exc())
    res.elapsed = time.perf_counter() - t0
    return res


def run_claims(settings: Settings | None = None, only: Sequence[int] | None = None,
               on_result: Callable[[ClaimResult], None] | None = None) -> list[ClaimResult]:
    """Run the registered claims (all, or those in ``only``) in order."""
    numbers = [s.number for s in registered()]
    if only is not None:
        unknown = sorted(set(only) - set(numbers))
        if unknown:
            raise KeyError(f"no claim(s) {unknown}; available: {numbers}")
        numbers = [n for n in numbers if n in set(only)]
    out = []
    for n in numbers:
        res = run_claim(n, settings)
        if on_result is not None:
            on_result(res)
        out.append(res)
    return out
