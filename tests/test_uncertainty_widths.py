"""Actual errors wider than stated (harness.uncertainty.width_sweeps, level, scaled_uncertainty)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.uncertainty import (
    Perturbation,
    UncertaintySpec,
    level,
    scaled_uncertainty,
    width_sweeps,
)

BOX = UncertaintySpec(map_scale=0.1, map_slope=0.3, z_shift=0.05, damping=(0.5, 2.0))


def test_map_scale_alone():
    (sw,) = width_sweeps(UncertaintySpec(map_scale=0.15), top=2.0, per_side=80)
    assert sw.kind == "map_scale" and len(sw.points) == 161
    scales = np.array([p.scale for p in sw.points])
    # the points 0, +/-0.15/40, ... +/-0.3; each one's level its |scale| / 0.15
    assert sorted(scales) == pytest.approx(np.linspace(-0.3, 0.3, 161), abs=1e-15)
    assert np.array(sw.levels) == pytest.approx(np.abs(scales) / 0.15, abs=1e-12)
    # the worst over the points within a width: written out by hand on made-up values
    vals = np.abs(scales) * 10 + (scales < 0)  # the negative side one higher
    w = np.array([0.0, 0.5, 1.0, 2.0])
    expect = [0.0, 0.075 * 10 + 1, 0.15 * 10 + 1, 0.3 * 10 + 1]
    assert sw.worst_upto(vals, w) == pytest.approx(expect)


def test_each_kind_and_the_box():
    sweeps = width_sweeps(BOX, top=2.0, per_side=20, box_levels=4)
    assert [s.kind for s in sweeps] == ["map_scale", "map_slope", "z_shift", "damping", "box"]
    damp = sweeps[3]
    f = np.array([p.damping for p in damp.points])
    # widths of the damping range: factors 0.5**s .. 2**s
    assert f.min() == pytest.approx(0.25) and f.max() == pytest.approx(4.0)
    for p, lv in zip(damp.points, damp.levels, strict=True):
        assert lv == pytest.approx(abs(math.log(p.damping)) / math.log(2.0), abs=1e-12)
    box = sweeps[-1]
    # the box at the widest level: every corner of the doubled ranges is there
    corner = Perturbation(0.2, 0.6, 0.1, 4.0)
    assert corner in box.points
    assert box.levels[box.points.index(corner)] == pytest.approx(2.0)
    for p, lv in zip(box.points, box.levels, strict=True):
        # the level, computed here from the ranges
        mine = max(abs(p.scale) / 0.1, abs(p.slope) / 0.3, abs(p.shift) / 0.05,
                   abs(math.log(p.damping)) / math.log(2.0))
        assert lv == pytest.approx(mine, abs=1e-12)


def test_level_of_an_unstated_kind_is_infinite():
    spec = UncertaintySpec(map_scale=0.1)
    assert level(spec, Perturbation(scale=0.05)) == pytest.approx(0.5)
    assert level(spec, Perturbation(slope=0.01)) == math.inf
    assert level(spec, Perturbation()) == 0.0


def test_scaled_uncertainty_and_bad_widths():
    wide = scaled_uncertainty(BOX, 1.5)
    assert (wide.map_scale, wide.map_slope, wide.z_shift) == pytest.approx((0.15, 0.45, 0.075))
    assert wide.damping == pytest.approx((0.5 ** 1.5, 2.0 ** 1.5))
    with pytest.raises(ValueError, match="width factor"):
        scaled_uncertainty(BOX, -1.0)
    with pytest.raises(ValueError, match="map_scale"):
        scaled_uncertainty(UncertaintySpec(map_scale=0.6), 2.0)  # 1.2: not a map error
    with pytest.raises(ValueError, match="top"):
        width_sweeps(BOX, top=0.0)
    assert width_sweeps(UncertaintySpec(map_scale=0.0)) == []  # nothing stated
