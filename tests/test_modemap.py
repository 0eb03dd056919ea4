"""Mode maps: linear, lookup table, cantilever laws and the load-mass shift."""

from __future__ import annotations

import math

import matplotlib.pyplot as plt
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from harness.modemap import CantileverLaw, ConstantLaw, LinearLaw, ModeMap, ModeSpec, TableLaw


def test_linear_law_through_its_two_points_and_beyond():
    law = LinearLaw((0.0, 0.5), (8.5, 6.375))
    assert law(0.0) == pytest.approx(8.5)
    assert law(0.5) == pytest.approx(6.375)
    assert law(0.25) == pytest.approx(7.4375)
    assert law(0.6) == pytest.approx(8.5 - 4.25 * 0.6)  # extrapolated linearly
    # the paper's X axis: -25 % over 0.5 m of Z
    assert 1 - law(0.5) / law(0.0) == pytest.approx(0.25)
    law.check_range(0.0, 0.5)
    with pytest.raises(ValueError, match="f = "):
        LinearLaw((0.0, 0.5), (8.0, 4.0)).check_range(0.0, 1.5)


@pytest.mark.parametrize("z, f", [((0.0, 0.0), (5.0, 6.0)), ((0.0, 1.0), (5.0, -1.0)),
                                  ((0.0, 1.0), (0.0, 3.0))])
def test_linear_law_rejects_bad_points(z, f):
    with pytest.raises(ValueError):
        LinearLaw(z, f)


@settings(max_examples=40, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0), min_size=2, max_size=8, unique=True),
       st.data())
def test_table_law_is_linear_interpolation(zs, data):
    z = sorted(zs)
    if min(np.diff(z)) < 1e-6:
        return
    f = data.draw(st.lists(st.floats(0.5, 100.0), min_size=len(z), max_size=len(z)))
    law = TableLaw(z, f)
    q = np.linspace(z[0], z[-1], 57)
    np.testing.assert_allclose([law(float(v)) for v in q], np.interp(q, z, f), rtol=1e-12)
    law.check_range(z[0], z[-1])
    with pytest.raises(ValueError, match="covers"):
        law.check_range(z[0] - 0.01, z[-1])
    with pytest.raises(ValueError, match="covers"):
        law.check_range(z[0], z[-1] + 0.01)


def test_table_law_rejects_non_increasing_and_non_positive():
    with pytest.raises(ValueError, match="increasing"):
        TableLaw((0.0, 0.2, 0.2), (5.0, 6.0, 7.0))
    with pytest.raises(ValueError, match="increasing"):
        TableLaw((0.0, 0.3, 0.2), (5.0, 6.0, 7.0))
    with pytest.raises(ValueError, match="> 0"):
        TableLaw((0.0, 0.3), (5.0, -6.0))


def test_cantilever_period_goes_with_the_square_of_the_overhang():
    """§3.2: the modal period is proportional to the square of the overhanging length."""
    law = CantileverLaw(f_ref=10.0, L_ref=0.6, z_ref=0.0, direction=1)
    for z in (0.0, 0.1, 0.25, 0.5):
        L = 0.6 + z
        assert (1.0 / law(z)) / L**2 == pytest.approx((1.0 / 10.0) / 0.6**2, rel=1e-12)
    # overhang shrinking with z
    law2 = CantileverLaw(f_ref=10.0, L_ref=0.6, z_ref=0.2, direction=-1)
    assert law2(0.4) == pytest.approx(10.0 * (0.6 / 0.4) ** 2)
    with pytest.raises(ValueError, match="overhanging"):
        law2.check_range(0.0, 0.9)


def test_mass_shift_period_goes_with_the_square_root_of_the_mass():
    """§3.2: the modal period evolves proportionally to the square root of the load mass."""
    base = ModeSpec(LinearLaw((0.0, 0.5), (8.0, 6.0)), zeta=0.03)
    heavy = ModeSpec(LinearLaw((0.0, 0.5), (8.0, 6.0)), zeta=0.03, mass_ratio=2.25)
    for z in (0.0, 0.3):
        assert heavy.period(z) / base.period(z) == pytest.approx(math.sqrt(2.25))
    assert heavy.scheduled().f_of_z(0.3) == pytest.approx(heavy.f(0.3))
    assert heavy.at(0.3).f == pytest.approx(base.f(0.3) / 1.5)
    np.testing.assert_allclose(heavy.f_array(np.array([0.0, 0.3])),
                               [heavy.f(0.0), heavy.f(0.3)])


def test_mode_spec_and_map_checks():
    with pytest.raises(ValueError):
        ModeSpec(ConstantLaw(5.0), zeta=1.0)
    with pytest.raises(ValueError):
        ModeSpec(ConstantLaw(5.0), zeta=0.1, mass_ratio=0.0)
    with pytest.raises(ValueError):
        ConstantLaw(-5.0)
    mm = ModeMap((ModeSpec(ConstantLaw(30.0), 0.02, name="a"),
                  ModeSpec(TableLaw((0.0, 0.5), (90.0, 80.0)), 0.05, name="b")), tune=1)
    assert mm.tuned.name == "b"
    assert mm.period(0.5) == pytest.approx(1 / 80.0)
    assert [m.f for m in mm.modes_at(0.25)] == pytest.approx([30.0, 85.0])
    with pytest.raises(ValueError, match="mode 2"):
        mm.check_range(0.0, 0.6)
    with pytest.raises(ValueError):
        ModeMap((), 0)
    with pytest.raises(ValueError):
        ModeMap((ModeSpec(ConstantLaw(3.0), 0.0),), tune=1)


def test_mode_map_plot():
    mm = ModeMap((ModeSpec(LinearLaw((0.0, 0.5), (8.5, 6.375)), 0.03, name="X"),))
    fig = mm.plot()
    assert fig.axes[0].get_xlabel() == "z [m]"
    plt.close(fig)
