"""The papers' filtering claims as executable checks.

Each module verifies one claim of Béarée & Olabi 2013 (paper ``000``) and
Béarée 2014 (paper ``003``) against the product: it computes the paper's side
(closed forms, re-derived where the text is garbled) and the product's side
(the generator FMU through fmpy, the harness's plant, python-control), and
compares them with a stated tolerance.

========  ==========================  =========================================
claim     module                      paper
========  ==========================  =========================================
1         :mod:`.moving_average`      000 eq. 5, 7-8: the moving average is a comb notch
2         :mod:`.jl_filtering`        000 §2.1, 003 eq. 15-16, Fig. 7: JL = AL * moving average
3         :mod:`.residual`            000 eq. 17-21, Fig. 11: residual vibration of jerk stages
4         :mod:`.time_varying`        000 §3.2, Fig. 12: mode varying within one jerk stage
5         :mod:`.spectra`             003 eq. 6-16, Fig. 3-5: spectra of the motion laws
6         :mod:`.vibration_filters`   003 eq. 18-22, Fig. 6: biquad, notch, ZV shaper
7         :mod:`.djl_stages`          000 §2.3, §3.2, §4: DJL stage notches vs the moving mode
========  ==========================  =========================================

A further claim plugs in the same way: a module whose ``run(settings)`` is
decorated with :func:`register`, listed in :data:`CATALOGUE` and imported by
:mod:`harness.claims.registry`, which runs them.

Examples
--------
>>> from harness.claims import Settings
>>> from harness.claims.registry import run_claims
>>> results = run_claims(Settings(fast=True), only=[1])   # doctest: +SKIP
>>> results[0].verdict                                     # doctest: +SKIP
'PASSED'
"""

from __future__ import annotations

from .base import (
    Check,
    ClaimResult,
    ClaimSpec,
    Settings,
    Table,
    register,
)

CATALOGUE: dict[int, tuple[str, str]] = {
    1: ("moving_average", "The moving average is a comb notch"),
    2: ("jl_filtering", "JL = AL * moving average"),
    3: ("residual", "Residual vibration of jerk stages"),
    4: ("time_varying", "Mode frequency varying within one jerk stage"),
    5: ("spectra", "Acceleration spectra of the motion laws"),
    6: ("vibration_filters", "Vibration filters compared: biquad, notch, ZV shaper"),
    7: ("djl_stages", "DJL stage filters against the moving mode"),
}
"""Claim number -> (module, title), readable without importing the (heavy) modules
(:mod:`harness.claims.registry` imports them and runs the claims)."""


__all__ = [
    "CATALOGUE",
    "Check",
    "ClaimResult",
    "ClaimSpec",
    "Settings",
    "Table",
    "register",
]
