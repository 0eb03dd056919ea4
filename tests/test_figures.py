"""The figures: no clipped text, legends off the data, the sweep's bars labelled by move.

Measured on the drawn figures (matplotlib's Agg renderer), in display coordinates.
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from harness.figures import legend_above_data, legend_outside
from harness.scenario import parse_scenario

from _scenarios import SMALL_AXIS

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

plt = pytest.importorskip("matplotlib.pyplot")


def _engine() -> str:
    from harness.workspace import check_engine

    try:
        check_engine("fast")
    except ValueError:
        return "fmu"
    return "fast"


def _drawn(fig):
    fig.canvas.draw()
    return fig.canvas.get_renderer()


def _inside(inner, outer, tol: float = 0.5) -> bool:
    return (inner.x0 >= outer.x0 - tol and inner.x1 <= outer.x1 + tol
            and inner.y0 >= outer.y0 - tol and inner.y1 <= outer.y1 + tol)


def _data_top(ax) -> float:
    """Highest data point of the axes' lines, in display coordinates."""
    ys = [ax.transData.transform(np.column_stack([ln.get_xdata(), ln.get_ydata()]))[:, 1].max()
          for ln in ax.get_lines() if len(ln.get_xdata())]
    return max(ys)


@pytest.mark.parametrize("log", [False, True])
def test_legend_above_data_leaves_the_curves_clear(log):
    fig, ax = plt.subplots(figsize=(6, 3))
    t = np.linspace(0.0, 1.0, 200)
    y = 1.0 + t if log else np.sin(12 * t)  # the curve reaches the top corners
    ax.plot(t, y, label="a curve with a long label")
    ax.plot(t, y[::-1], label="another one")
    if log:
        ax.set_yscale("log")
    fig.tight_layout()
    leg = legend_above_data(ax)
    r = _drawn(fig)
    box = leg.get_window_extent(r)
    assert box.y0 > _data_top(ax)  # every point of every curve below the legend
    assert _inside(box, ax.get_window_extent(r))
    plt.close(fig)


def test_legend_outside_is_right_of_the_axes():
    fig, ax = plt.subplots(figsize=(6, 3))
    ax.plot([0, 1], [0, 1], label="line")
    leg = legend_outside(ax)
    fig.tight_layout()
    r = _drawn(fig)
    assert leg.get_window_extent(r).x0 >= ax.get_window_extent(r).x1
    assert _inside(leg.get_window_extent(r), fig.bbox)
    plt.close(fig)


@pytest.fixture(scope="module")
def small_run():
    from harness.sweeps import run_scenario

    sc = parse_scenario(tomllib.loads('name = "fig"\n' + SMALL_AXIS), "fig.toml")
    return run_scenario(sc, engine=_engine(), robustness=False)


def test_run_figure_text_is_whole_and_the_legend_off_the_data(small_run):
    fig = small_run.plot()
    r = _drawn(fig)
    page = fig.bbox
    axes = [ax for ax in fig.axes if ax.axison]
    # one legend, for the figure, above every panel
    assert not any(ax.get_legend() for ax in fig.axes)
    (leg,) = fig.legends
    box = leg.get_window_extent(r)
    assert _inside(box, page)
    assert all(box.y0 >= ax.get_tightbbox(r).y1 - 1 for ax in axes)
    # the t axis labelled under both columns, clear of the table below the left one
    xlabels = [ax.xaxis.label for ax in axes if ax.get_xlabel()]
    assert len(xlabels) == 2 and all(lab.get_text() == "t [s]" for lab in xlabels)
    (table_ax,) = [ax for ax in fig.axes if not ax.axison]
    (table,) = table_ax.tables
    tbox = table.get_window_extent(r)
    left = min(xlabels, key=lambda lab: lab.get_window_extent(r).x0)  # the left column's
    assert tbox.y1 < left.get_window_extent(r).y0
    # every cell's text fits in its cell (row labels and headers included), on the page
    for cell in table.get_celld().values():
        cbox, text = cell.get_window_extent(r), cell.get_text()
        if text.get_text():
            assert _inside(text.get_window_extent(r), cbox, tol=1.0), text.get_text()
        assert _inside(cbox, page)
    # every panel with its labels, tick labels and notes on the page, and the title
    for ax in fig.axes:
        assert _inside(ax.get_tightbbox(r), page, tol=1.0)
    assert _inside(fig._suptitle.get_window_extent(r), page)
    plt.close(fig)


def test_sweep_figure_title_inside_and_bars_labelled_with_the_moves():
    from harness.sweeps import run_scenario

    sc = parse_scenario(tomllib.loads(
        'name = "sw"\n' + SMALL_AXIS
        + "\n[sweep]\ndistance = [0.1, 0.3]\nz_distance = [0.1, 0.3]\nv_max = [0.5, 2.0]\n"),
        "sw.toml")
    res = run_scenario(sc, engine=_engine(), robustness=False)
    fig = res.plot()
    r = _drawn(fig)
    assert _inside(fig._suptitle.get_window_extent(r), fig.bbox)
    bars = fig.axes[1]
    labels = [t.get_text() for t in bars.get_xticklabels()]
    assert labels == [res.case_label(c).replace("v=", "v_max=") for c in res.distinct()]
    assert all(lab.startswith("d=") and "dz=" in lab and "v_max=" in lab for lab in labels)
    for t in bars.get_xticklabels():
        assert _inside(t.get_window_extent(r), fig.bbox)
    leg = bars.get_legend()
    assert leg.get_window_extent(r).y0 >= bars.get_window_extent(r).y1 - 1  # above the bars
    plt.close(fig)


def test_robustness_figure_legend_and_labels_on_the_page():
    """The map-error figure's legend sits below the axes, off the data, and on the page."""
    from harness.sweeps import run_scenario

    sc = parse_scenario(tomllib.loads('name = "rob"\n' + SMALL_AXIS), "rob.toml")
    rob = run_scenario(sc, engine=_engine(), robustness=True).robustness
    fig = rob.plot()
    r = _drawn(fig)
    (ax,) = fig.axes
    leg = ax.get_legend()
    assert leg is not None and len(leg.get_texts()) >= 3
    box = leg.get_window_extent(r)
    assert _inside(box, fig.bbox)
    assert box.y1 <= ax.get_window_extent(r).y0  # below the axes: off every curve
    assert _inside(ax.get_tightbbox(r, bbox_extra_artists=[]), fig.bbox, tol=1.0)
    plt.close(fig)
