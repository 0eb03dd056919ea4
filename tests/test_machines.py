"""The random machines of a class (harness.machines): seeded, within the class, refused when bad."""

from __future__ import annotations

import math

import numpy as np
import pytest

from harness.machines import DEFAULT_CLASS, MachineClass, machines, random_machine
from harness.scenario import Scenario


def test_a_machine_depends_on_its_seed_and_index_only():
    a = random_machine(3, 5)
    assert a == random_machine(3, 5)
    assert machines(8, 3)[5] == a  # the same whatever the number asked for
    assert random_machine(4, 5) != a and random_machine(3, 6) != a
    assert a.name == "m3-5" and isinstance(a, Scenario)


def test_every_machine_is_in_the_class():
    cls = DEFAULT_CLASS
    signs, rising, falling = set(), 0, 0
    for sc in machines(150, 11):
        m, z = sc.move, sc.z
        assert cls.distance[0] * 0.999 <= abs(m.distance) <= cls.distance[1] * 1.001
        signs.add(math.copysign(1.0, m.distance))
        assert cls.v_max[0] * 0.999 <= m.v_max <= cls.v_max[1] * 1.001
        assert cls.a_max[0] * 0.999 <= m.a_max <= cls.a_max[1] * 1.001 and m.d_max == m.a_max
        assert cls.z_travel[0] * 0.999 <= abs(z.distance) <= cls.z_travel[1] * 1.001
        (mode,) = sc.modemap.modes
        law = mode.law
        assert law.kind == "table" and cls.points[0] <= len(law.z) <= cls.points[1]
        assert law.z[0] == 0.0 and law.z[-1] == pytest.approx(abs(z.distance))
        # the table covers Z's travel, whichever way Z moves
        assert min(z.z0, z.z0 + z.distance) == pytest.approx(0.0, abs=1e-12)
        f = np.array(law.f)
        assert np.all(f >= cls.f[0] * 0.999) and np.all(f <= cls.f[1] * 1.001)
        d = np.diff(f)
        assert np.all(d <= 1e-9) or np.all(d >= -1e-9)  # monotone
        change = f[-1] / f[0] - 1.0  # in the direction of increasing z
        assert cls.change[0] - 1e-3 <= change <= cls.change[1] + 1e-3
        rising += change > 0
        falling += change < 0
        assert cls.zeta[0] * 0.999 <= mode.zeta <= cls.zeta[1] * 1.001
        u = sc.uncertainty
        assert cls.map_scale[0] * 0.999 <= u.map_scale <= cls.map_scale[1] * 1.001
        assert not (u.map_slope or u.z_shift) and u.damping == (1.0, 1.0)
    assert signs == {-1.0, 1.0} and rising > 10 and falling > 50


@pytest.mark.parametrize(("seed", "index", "name"), [(-1, 0, "seed"), (0, -2, "index"),
                                                     (1.5, 0, "seed"), (True, 0, "seed"),
                                                     (0, "3", "index")])
def test_bad_seed_or_index_is_refused_by_name(seed, index, name):
    with pytest.raises(ValueError, match=name):
        random_machine(seed, index)


def test_bad_count_is_refused():
    with pytest.raises(ValueError, match="n must be"):
        machines(-1, 0)
    assert machines(0, 0) == []


@pytest.mark.parametrize(("field", "value"), [("distance", (0.5, 0.05)), ("v_max", (0.0, 1.0)),
                                             ("zeta", (float("nan"), 0.1)),
                                             ("change", (-1.0, 0.2)),
                                             ("points", (1, 3)), ("map_scale", (0.1, 1.0))])
def test_bad_class_is_refused_naming_the_range(field, value):
    with pytest.raises(ValueError, match=f"machine class {field}"):
        MachineClass(**{field: value})
    assert "zeta 0.01-0.08" in DEFAULT_CLASS.describe()  # nothing else broke
