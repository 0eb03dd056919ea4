"""Figure helpers shared by the commands' plots: legends kept off the data.

No matplotlib import here: the helpers take the axes they work on.
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["legend_above_data", "legend_outside"]


def legend_outside(ax: Any, **kwargs: Any) -> Any:
    """Put the legend of ``ax`` to the right of it, outside the axes: off the data.

    ``tight_layout`` then makes room for it.  Keyword arguments go to
    :meth:`matplotlib.axes.Axes.legend` (``fontsize`` defaults to x-small).
    """
    kwargs.setdefault("fontsize", "x-small")
    return ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
                     **kwargs)


def legend_above_data(ax: Any, loc: str = "upper right", **kwargs: Any) -> Any:
    """Draw the legend of ``ax`` in its top corner and raise the y limit so it covers no data.

    The axes get headroom as tall as the legend (measured once drawn), so the
    curves, which lay below the former top, stay clear of it.  Call it once the
    axes have their final size (after ``tight_layout``).

    Parameters
    ----------
    ax : matplotlib.axes.Axes
    loc : str
        ``"upper right"`` or ``"upper left"``.
    **kwargs
        Passed to :meth:`matplotlib.axes.Axes.legend` (``fontsize`` defaults to small).

    Returns
    -------
    matplotlib.legend.Legend
    """
    kwargs.setdefault("fontsize", "small")
    leg = ax.legend(loc=loc, **kwargs)
    renderer = ax.figure.canvas.get_renderer()
    frac = leg.get_window_extent(renderer).height / ax.get_window_extent(renderer).height
    frac = min(frac + 0.04, 0.75)  # the legend's border pad and a margin
    lo, hi = ax.get_ylim()
    if ax.get_yscale() == "log":
        llo, lhi = math.log10(lo), math.log10(hi)
        ax.set_ylim(lo, 10.0 ** (lhi + (lhi - llo) * frac / (1.0 - frac)))
    else:
        ax.set_ylim(lo, hi + (hi - lo) * frac / (1.0 - frac))
    return leg
