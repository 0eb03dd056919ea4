"""Checks, claim results and the registry of claims.

A *claim* is a statement of one of the papers (with its equation or figure
number) turned into numbers: the paper's side (a closed form, a published
threshold) and the product's side (the generator FMU run through fmpy, the
harness's plant, python-control), compared with a stated tolerance.  Each
claim module registers a function ``run(settings) -> ClaimResult`` with
:func:`register`; :func:`run_claims` runs them and never hides a failure: a
check that fails, or a claim whose computation raises, comes back as FAILED
with its numbers (or its traceback).

Two kinds of checks are kept apart:

``"product"``
    The product (FMU, plant, filters) against the theory it implements.  A
    failure is a defect of the product (or of the theory as we derived it).
``"paper"``
    A quantitative remark of a paper ("below 20 %", "2 to 3 times") checked
    as stated.  A failure is a finding about the paper, reported as such.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np
from tqdm import tqdm

from ..fmu.runner import Trajectory, generate

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.figure import Figure  # a type only: matplotlib is heavy to import

CheckKind = Literal["product", "paper"]


def _fmt(x: float | None) -> str:
    if x is None:
        return "-"
    if isinstance(x, (bool, np.bool_)):
        return str(bool(x))
    x = float(x)
    if not np.isfinite(x):
        return str(x)
    if x == 0.0:
        return "0"
    ax = abs(x)
    if ax >= 1e4 or ax < 1e-3:
        return f"{x:.3e}"
    return f"{x:.6g}"


@dataclass
class Check:
    """One comparison of a claim.

    Attributes
    ----------
    name : str
        What is compared, in words.
    expected : float or None
        The paper's side (closed form, threshold); ``None`` for a pure bound.
    measured : float
        The product's / simulation's side.
    tolerance : float
        Allowed deviation (absolute, in ``unit``), or the bound itself for
        one-sided checks.
    passed : bool
        Verdict.
    rule : str
        The comparison applied, e.g. ``"|measured - expected| <= tol"``.
    unit : str
        Unit of ``expected`` / ``measured`` (SI), ``""`` when dimensionless.
    kind : {"product", "paper"}
        Product check or paper statement (see the module docstring).
    note : str
        Where the numbers come from, in one sentence.
    """

    name: str
    expected: float | None
    measured: float
    tolerance: float
    passed: bool
    rule: str
    unit: str = ""
    kind: CheckKind = "product"
    note: str = ""

    @classmethod
    def close(cls, name: str, expected: float, measured: float, tol: float, *,
              unit: str = "", kind: CheckKind = "product", note: str = "",
              relative: bool = False) -> Check:
        """``|measured - expected| <= tol`` (``tol * |expected|`` when ``relative``)."""
        expected = float(expected)
        measured = float(measured)
        bound = tol * abs(expected) if relative else tol
        ok = bool(np.isfinite(measured) and abs(measured - expected) <= bound)
        rule = ("|measured - expected| <= tol * |expected|" if relative
                else "|measured - expected| <= tol")
        return cls(name, expected, measured, float(tol), ok, rule, unit, kind, note)

    @classmethod
    def below(cls, name: str, measured: float, limit: float, *, expected: float | None = None,
              unit: str = "", kind: CheckKind = "product", note: str = "") -> Check:
        """``measured <= limit`` (``expected`` shown for information)."""
        measured = float(measured)
        ok = bool(np.isfinite(measured) and measured <= limit)
        return cls(name, expected, measured, float(limit), ok, "measured <= tol", unit, kind,
                   note)

    @classmethod
    def above(cls, name: str, measured: float, limit: float, *, expected: float | None = None,
              unit: str = "", kind: CheckKind = "product", note: str = "") -> Check:
        """``measured >= limit``."""
        measured = float(measured)
        ok = bool(np.isfinite(measured) and measured >= limit)
        return cls(name, expected, measured, float(limit), ok, "measured >= tol", unit, kind,
                   note)

    @classmethod
    def true(cls, name: str, condition: bool, *, measured: float = float("nan"),
             kind: CheckKind = "product", note: str = "", unit: str = "") -> Check:
        """Check a condition that is not a single comparison (explain it in ``name``)."""
        return cls(name, None, measured, float("nan"), bool(condition), "condition holds", unit,
                   kind, note)

    @property
    def tol_text(self) -> str:
        """The tolerance formatted, ``""`` when the check has none."""
        return "" if np.isnan(self.tolerance) else _fmt(self.tolerance)

    def row(self) -> list[str]:
        """Cells for a table: name, kind, expected, measured, rule/tol, unit, verdict."""
        tol = self.tol_text
        return [self.name, self.kind, _fmt(self.expected), _fmt(self.measured),
                f"{self.rule}" + (f", tol = {tol}" if tol else ""), self.unit, self.status]

    @property
    def status(self) -> str:
        """Return ``PASSED``, ``REFUTED`` or ``FAILED``.

        ``REFUTED``: a paper statement that does not hold (a finding); ``FAILED``: a
        product check that does not (a defect).
        """
        if self.passed:
            return "PASSED"
        return "REFUTED" if self.kind == "paper" else "FAILED"

    def describe(self) -> str:
        """One line: name, measured value, rule and tolerance, verdict."""
        tol = self.tol_text
        exp = "" if self.expected is None else f", paper side {_fmt(self.expected)}"
        return (f"{self.name}: measured {_fmt(self.measured)}{exp} ({self.rule}"
                + (f", tol = {tol}" if tol else "") + f") {self.status}")


@dataclass
class Table:
    """A small table of computed numbers shown with a claim."""

    caption: str
    header: list[str]
    rows: list[list[Any]]

    def formatted(self) -> list[list[str]]:
        """Rows with numbers formatted like the checks."""
        return [[c if isinstance(c, str) else _fmt(c) for c in r] for r in self.rows]


@dataclass
class ClaimResult:
    """What a claim computed, and its verdict.

    Attributes
    ----------
    number : int
        Claim number (docs/claims.md).
    title : str
        Short title.
    source : str
        Paper, section, equations, figures.
    statement : str
        The paper's statement (quoted or paraphrased).
    method : str
        How both sides are computed.
    checks : list of Check
    figures : list of matplotlib Figure
        Closed by the report builder once written.
    tables : list of Table
    derivations : list of str
        Where an equation of the paper was garbled or wrong, what we used.
    error : str or None
        Traceback when the computation itself raised (then the claim failed).
    elapsed : float
        Wall time of the computation (s).
    data : object
        The claim's own result object (with a ``.plot()``), for callers.
    """

    number: int
    title: str
    source: str
    statement: str
    method: str = ""
    checks: list[Check] = field(default_factory=list)
    figures: list[Figure] = field(default_factory=list)
    tables: list[Table] = field(default_factory=list)
    derivations: list[str] = field(default_factory=list)
    error: str | None = None
    elapsed: float = 0.0
    data: Any = None

    @property
    def passed(self) -> bool:
        """True when it ran, has checks, and every check passed."""
        return self.error is None and bool(self.checks) and all(c.passed for c in self.checks)

    @property
    def product_passed(self) -> bool:
        """True when it ran and every *product* check passed."""
        return self.error is None and all(c.passed for c in self.checks if c.kind == "product")

    @property
    def verdict(self) -> str:
        """``"PASSED"``, ``"FAILED"`` or ``"ERROR"``."""
        if self.error is not None:
            return "ERROR"
        return "PASSED" if self.passed else "FAILED"

    @property
    def status(self) -> str:
        """What the report's badge says.

        ``PASSED`` (every check), ``REFUTED`` (every product check passed, a paper
        statement does not hold: a finding about the paper), ``FAILED`` (a product
        check failed: a defect) or ``ERROR`` (the computation raised).
        """
        if self.error is not None:
            return "ERROR"
        if self.passed:
            return "PASSED"
        return "REFUTED" if self.product_passed and self.checks else "FAILED"

    def failed_checks(self) -> list[Check]:
        """Return the checks that failed."""
        return [c for c in self.checks if not c.passed]

    def summary(self) -> str:
        """One line: number, title, verdict, counts."""
        n_ok = sum(c.passed for c in self.checks)
        return (f"claim {self.number}: {self.status:7s} {n_ok}/{len(self.checks)} checks  "
                f"{self.title}  ({self.elapsed:.1f} s)")


@dataclass
class Settings:
    """How hard the claims work, and which FMU they exercise.

    Parameters
    ----------
    fast : bool
        Small grids (the test suite); the report uses ``fast=False``.
    fmi_version : {2, 3}
        FMU built from this package's sources when ``fmu`` is not given.
    fmu : path-like, optional
        A generator FMU file to verify instead.
    progress : bool
        Show tqdm progress bars in the longer sweeps.
    """

    fast: bool = False
    fmi_version: int = 2
    fmu: str | Path | None = None
    progress: bool = False

    def generate(self, params: dict[str, Any], **kw: Any) -> Trajectory:
        """Run the generator FMU (through fmpy) with these settings."""
        return generate(params, fmi_version=self.fmi_version, fmu=self.fmu, **kw)

    def pick(self, fast: Any, full: Any) -> Any:
        """``fast`` in fast mode, else ``full``."""
        return fast if self.fast else full

    def progress_bar(self, iterable: Iterable[Any], desc: str, total: int | None = None
                     ) -> Iterable[Any]:
        """Wrap ``iterable`` in a tqdm bar when progress is on and stderr is a TTY."""
        if not self.progress or not sys.stderr.isatty():
            return iterable
        return tqdm(iterable, desc=desc, total=total, leave=False)


ClaimFunction = Callable[[Settings], ClaimResult]


@dataclass(frozen=True)
class ClaimSpec:
    """A registered claim: its number, title and function."""

    number: int
    title: str
    run: ClaimFunction


_REGISTRY: dict[int, ClaimSpec] = {}


def register(number: int, title: str) -> Callable[[ClaimFunction], ClaimFunction]:
    """Register ``run(settings) -> ClaimResult`` as claim ``number`` (decorator)."""

    def deco(fn: ClaimFunction) -> ClaimFunction:
        if number in _REGISTRY and _REGISTRY[number].run is not fn:
            raise ValueError(f"claim {number} registered twice")
        _REGISTRY[number] = ClaimSpec(number, title, fn)
        return fn

    return deco


def dress(ax, xlabel: str, ylabel: str, title: str | None = None) -> None:
    """Label a claim figure's axes, title it, and add the legend and grid they all use."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title is not None:
        ax.set_title(title)
    ax.legend(fontsize="x-small")
    ax.grid(True, alpha=0.3)
