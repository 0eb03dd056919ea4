"""How each method degrades when the real error is wider than stated: worst-case settling vs width.

A recommendation is made for a stated uncertainty; the real machine may be
off by more, or by less.  For actual error widths w from 0 to twice the stated
one (w = 1: the stated set; each stated kind alone, and the whole box when
several are stated), :func:`degradation` scores each method's run at every
point of :func:`harness.uncertainty.width_sweeps` and keeps, at each w, its
worst-case settling time over the points within w.  :class:`Degradation`
holds the curves, says up to what width the recommended profile is no worse
than every textbook shaper and which is better beyond, writes them as CSV rows
and draws them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .figures import legend_outside
from .scenario import Scenario
from .scoring import score_points
from .simulation.master import CoSimResult
from .tuning.graceful import TOP
from .uncertainty import UncertaintySpec, width_sweeps

__all__ = ["TEXTBOOK_METHODS", "Degradation", "degradation"]

TEXTBOOK_METHODS = ("JL*ZV", "JL*ZVD", "JL*EI", "JL*SI")
"""The textbook shapers a recommendation is held to (on JL, at the end mode)."""

_KIND_WORDS = {"map_scale": "map scale", "map_slope": "map slope", "z_shift": "z shift",
               "damping": "damping", "box": "every stated kind"}


def _absolute(spec: UncertaintySpec, kind: str, w: float) -> str:
    """Return the width ``w`` of a kind in the scenario's units (``+/-15 %``, ``x0.5..2``)."""
    if kind == "map_scale":
        return f"+/-{100 * spec.map_scale * w:.3g} %"
    if kind == "map_slope":
        return f"+/-{100 * spec.map_slope * w:.3g} % slope"
    if kind == "z_shift":
        return f"+/-{1e3 * spec.z_shift * w:.3g} mm"
    if kind == "damping":
        lo, hi = spec.damping
        return f"damping x{lo ** w:.3g}..{hi ** w:.3g}"
    return f"{w:g}x every range"


@dataclass
class Degradation:
    """Worst-case settling of each method at every actual error width (:func:`degradation`).

    Attributes
    ----------
    scenario : str
        The scenario's name.
    spec : UncertaintySpec
        The stated uncertainty (width 1).
    widths : ndarray
        The widths, multiples of the stated ranges, from 0 to ``top``.
    curves : dict
        ``curves[method][kind]``: the worst-case settling time (s) over the
        points of that kind within each width.
    recommended : str
        The method the others are compared with.
    textbook : tuple of str
        The textbook shapers among the methods.
    """

    scenario: str
    spec: UncertaintySpec
    widths: np.ndarray
    curves: dict[str, dict[str, np.ndarray]]
    recommended: str = "recommended"
    textbook: tuple[str, ...] = field(default_factory=tuple)

    @property
    def kinds(self) -> list[str]:
        """The sweeps: each stated kind, then ``box``."""
        return list(next(iter(self.curves.values())).keys()) if self.curves else []

    def holds_to(self, kind: str | None = None) -> tuple[float, str]:
        """Return the widest width up to which the recommended is no worse than every textbook.

        Returns
        -------
        width : float
            A multiple of the stated ranges (``widths[-1]``: everywhere); the
            narrowest over the kinds when ``kind`` is None.
        beyond : str
            The textbook shaper better just beyond it ("" when it holds everywhere).
        """
        rec = self.curves.get(self.recommended)
        books = [m for m in self.textbook if m in self.curves]
        if rec is None or not books:
            return math.nan, ""
        out = (math.inf, "")
        for k in ([kind] if kind else self.kinds):
            best = np.min(np.vstack([self.curves[m][k] for m in books]), axis=0)
            bad = np.flatnonzero(rec[k] > best * (1.0 + 1e-9))
            if bad.size == 0:
                got = (float(self.widths[-1]), "")
            else:
                i = int(bad[0])
                who = min(books, key=lambda m: self.curves[m][k][i])
                got = (float(self.widths[i - 1]) if i else 0.0, who)
            out = min(out, got, key=lambda x: x[0])
        return out

    def lines(self) -> list[str]:
        """Return the table lines: per kind, how far the recommendation holds, who beats it."""
        out = []
        rec = self.curves.get(self.recommended)
        books = [m for m in self.textbook if m in self.curves]
        if rec is None or not books:
            return out
        top = float(self.widths[-1])
        for k in self.kinds:
            w, who = self.holds_to(k)
            words = _KIND_WORDS.get(k, k)
            at = {s: int(np.argmin(np.abs(self.widths - s))) for s in (1.0, 1.5, top)}
            figs = ", ".join(
                f"{_absolute(self.spec, k, self.widths[i])}: {rec[k][i]:.3f} s vs "
                f"{min(self.curves[m][k][i] for m in books):.3f} s"
                for s, i in at.items() if s <= top)
            if not who:
                out.append(f"Wider than stated ({words}): the recommended profile is no worse "
                           f"than every textbook shaper ({', '.join(books)}) at any actual error "
                           f"up to {top:g}x the stated one ({figs}).")
            else:
                i = int(np.argmin(np.abs(self.widths - w))) + 1
                i = min(i, len(self.widths) - 1)
                held = (f"holds up to {w:g}x the stated error ({_absolute(self.spec, k, w)}); "
                        f"beyond" if w > 0 else "does not hold past the exact map: there")
                out.append(f"Wider than stated ({words}): the recommended profile {held}, "
                           f"{who} is better ({_absolute(self.spec, k, self.widths[i])}: "
                           f"{self.curves[who][k][i]:.3f} s against {rec[k][i]:.3f} s; {figs}).")
        return out

    def rows(self) -> list[dict[str, Any]]:
        """One dict per method, kind and width (the CSV rows)."""
        out = []
        for m, per in self.curves.items():
            for k, v in per.items():
                for w, t in zip(self.widths.tolist(), np.asarray(v).tolist(), strict=True):
                    out.append({"scenario": self.scenario, "method": m, "kind": k,
                                "width": w, "width_text": _absolute(self.spec, k, w),
                                "settling_time_worst_s": t,
                                "textbook": m in self.textbook,
                                "recommended": m == self.recommended})
        return out

    def plot(self, title: str | None = None):  # -> matplotlib.figure.Figure
        """Draw each kind's curves: worst-case settling against the actual error width."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import



        kinds = self.kinds
        fig, axes = plt.subplots(len(kinds), 1, figsize=(8.5, 3.4 * len(kinds)), squeeze=False)
        for ax, k in zip(axes[:, 0], kinds, strict=True):
            for m, per in self.curves.items():
                rec = m == self.recommended
                ax.plot(self.widths, per[k], lw=2.4 if rec else 1.3,
                        ls="-" if rec or m in self.textbook else "--",
                        color="black" if rec else None, label=m)
            ax.axvline(1.0, color="0.5", lw=0.8, ls=":")
            ax.text(1.0, 1.0, " stated", transform=ax.get_xaxis_transform(), va="top",
                    fontsize="small", color="0.4")
            ax.set_xlabel(f"actual error / stated ({_KIND_WORDS.get(k, k)}; 1 = "
                          f"{_absolute(self.spec, k, 1.0)})")
            ax.set_ylabel("worst-case settling [s]")
            ax.grid(True, alpha=0.3)
            legend_outside(ax)
        fig.suptitle(title or f"{self.scenario}: worst-case settling when the error is wider "
                              f"(or narrower) than stated")
        fig.tight_layout()
        return fig


def degradation(sc: Scenario, runs: Mapping[str, CoSimResult], band: float, *,
                recommended: str = "recommended",
                textbook: Sequence[str] = TEXTBOOK_METHODS, top: float = TOP) -> Degradation:
    """Score each run at every actual error width from 0 to ``top`` times the stated one.

    Parameters
    ----------
    sc : Scenario
        The scenario (its uncertainty is the stated one, width 1).
    runs : mapping
        Method name -> its nominal run (the reference planned on the nominal map).
    band : float
        The settling band (m), the same for every method.
    recommended : str
        The method the textbook shapers are compared with.
    textbook : sequence of str
        The names of the textbook shapers among ``runs``.
    top : float
        The widest width.

    Returns
    -------
    Degradation
    """
    sweeps = width_sweeps(sc.uncertainty, top, box_levels=4)
    n = max(2, int(round(40 * top)))
    widths = np.linspace(0.0, top, n + 1)
    curves: dict[str, dict[str, np.ndarray]] = {}
    for name, run in runs.items():
        curves[name] = {sw.kind: sw.worst_upto(score_points(run, sc, band, sw.points).settling,
                                               widths) for sw in sweeps}
    return Degradation(sc.name, sc.uncertainty, widths, curves, recommended,
                       tuple(m for m in textbook if m in runs))
