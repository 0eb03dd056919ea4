"""Random machines of a stated class: seeded scenarios to check advice on machines it never saw.

The class (issue 33, item 3) is what a machine builder's axis may look like:

* the excited axis moves 0.05–0.5 m, either sign, with v_max 0.2–2 m/s and
  a_max 2–10 m/s² (d_max = a_max);
* Z travels 0.1–0.6 m, either direction, synchronised with the excited axis;
* one mode, tabulated at 3–5 points over Z's travel, 5–20 Hz, falling with z
  by up to 45 % or rising by up to 20 % (monotone between its two ends);
* damping ratio ζ 0.01–0.08;
* the map off by up to ±E, E (``[uncertainty] map_scale``) 0.05–0.2.

The ranges are drawn log-uniform where they span a decade or near it (the
distance, the limits, ζ), uniform otherwise; every draw comes from
``numpy.random.default_rng((seed, index))``, so machine ``index`` of a seed is
the same whatever the number of machines asked for.

* :class:`MachineClass` -- the ranges (the issue's by default);
* :func:`random_machine` -- machine ``index`` of ``seed``, as a :class:`Scenario`;
* :func:`machines` -- the first ``n`` of a seed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .scenario import Scenario, parse_scenario

__all__ = ["DEFAULT_CLASS", "MachineClass", "machines", "random_machine"]


@dataclass(frozen=True)
class MachineClass:
    """The ranges machines are drawn from (each a closed interval ``(lo, hi)``).

    Attributes
    ----------
    distance : tuple of float
        |move| (m); the sign is drawn too.
    v_max, a_max : tuple of float
        Limits of the excited axis (m/s, m/s²).
    z_travel : tuple of float
        |Z travel| (m); the direction is drawn too.
    f : tuple of float
        Every frequency of the mode's table (Hz).
    change : tuple of float
        Relative change of the frequency over Z's travel, in the direction of
        increasing z (−0.45: falls by up to 45 %, +0.2: rises by up to 20 %).
    points : tuple of int
        Points of the mode's table.
    zeta : tuple of float
        Damping ratio.
    map_scale : tuple of float
        The stated uncertainty: the whole map off by up to ± this.
    """

    distance: tuple[float, float] = (0.05, 0.5)
    v_max: tuple[float, float] = (0.2, 2.0)
    a_max: tuple[float, float] = (2.0, 10.0)
    z_travel: tuple[float, float] = (0.1, 0.6)
    f: tuple[float, float] = (5.0, 20.0)
    change: tuple[float, float] = (-0.45, 0.2)
    points: tuple[int, int] = (3, 5)
    zeta: tuple[float, float] = (0.01, 0.08)
    map_scale: tuple[float, float] = (0.05, 0.2)

    def __post_init__(self) -> None:
        for name in ("distance", "v_max", "a_max", "z_travel", "f", "zeta", "map_scale"):
            lo, hi = getattr(self, name)
            if not (math.isfinite(lo) and math.isfinite(hi) and 0.0 < lo <= hi):
                raise ValueError(f"machine class {name} must be (lo, hi) with 0 < lo <= hi, "
                                 f"got {(lo, hi)!r}")
        lo, hi = self.change
        if not (-1.0 < lo <= hi and math.isfinite(hi)):
            raise ValueError(f"machine class change must be (lo, hi) with -1 < lo <= hi, "
                             f"got {(lo, hi)!r}")
        if not 2 <= self.points[0] <= self.points[1]:
            raise ValueError(f"machine class points must be (lo, hi) with 2 <= lo <= hi, "
                             f"got {self.points!r}")
        if self.map_scale[1] >= 1.0:
            raise ValueError(f"machine class map_scale must be < 1, got {self.map_scale!r}")

    def describe(self) -> str:
        """Return the class in one line."""
        return (f"|d| {self.distance[0]:g}-{self.distance[1]:g} m, v_max {self.v_max[0]:g}-"
                f"{self.v_max[1]:g} m/s, a_max {self.a_max[0]:g}-{self.a_max[1]:g} m/s2, "
                f"|Z travel| {self.z_travel[0]:g}-{self.z_travel[1]:g} m, one mode of "
                f"{self.points[0]}-{self.points[1]} points at {self.f[0]:g}-{self.f[1]:g} Hz "
                f"changing {100 * self.change[0]:+.0f}..{100 * self.change[1]:+.0f} % with z, "
                f"zeta {self.zeta[0]:g}-{self.zeta[1]:g}, map scale +/-{self.map_scale[0]:g}-"
                f"{self.map_scale[1]:g}")


DEFAULT_CLASS = MachineClass()
"""The class of issue 33."""


def _log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def _round(x: float, digits: int = 4) -> float:
    """``x`` to ``digits`` significant digits (a scenario a person can read and retype)."""
    return float(f"{x:.{digits}g}")


def random_machine(seed: int, index: int, cls: MachineClass = DEFAULT_CLASS,
                   *, t_after: float = 3.0) -> Scenario:
    """Return machine ``index`` of ``seed``: a single-move scenario of the class.

    Parameters
    ----------
    seed, index : int
        Non-negative; the draws come from ``default_rng((seed, index))``.
    cls : MachineClass
        The ranges.
    t_after : float
        Seconds recorded after the motion (the scoring extends the free
        oscillation past the record where it needs to).

    Returns
    -------
    Scenario
        Named ``m<seed>-<index>``; its description lists the draws.
    """
    for name, v in (("seed", seed), ("index", index)):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 0:
            raise ValueError(f"{name} must be an integer >= 0, got {v!r}")
    rng = np.random.default_rng((int(seed), int(index)))
    sign = 1.0 if rng.random() < 0.5 else -1.0
    d = sign * _round(_log_uniform(rng, *cls.distance), 3)
    v_max = _round(_log_uniform(rng, *cls.v_max), 3)
    a_max = _round(_log_uniform(rng, *cls.a_max), 3)
    dz = _round(rng.uniform(*cls.z_travel), 3)
    z_down = rng.random() < 0.5  # Z travels towards increasing z, or back
    change = float(rng.uniform(*cls.change))
    lo_f, hi_f = cls.f
    # f at z = 0 such that the whole table stays within [lo_f, hi_f]
    f_lo0 = lo_f / min(1.0, 1.0 + change)
    f_hi0 = hi_f / max(1.0, 1.0 + change)
    f0 = _log_uniform(rng, f_lo0, max(f_lo0, f_hi0))
    n = int(rng.integers(cls.points[0], cls.points[1] + 1))
    # positions: the ends of the travel and n - 2 points between, the frequencies monotone
    zs = np.sort(np.concatenate([[0.0, dz], rng.uniform(0.1, 0.9, n - 2) * dz]))
    frac = np.sort(rng.uniform(0.0, 1.0, n - 2))
    w = np.concatenate([[0.0], frac, [1.0]])
    fs = f0 * (1.0 + change * w)
    zeta = _round(_log_uniform(rng, *cls.zeta), 3)
    E = _round(rng.uniform(*cls.map_scale), 3)
    zs_t = [_round(float(z), 4) for z in zs]
    if len(set(zs_t)) != len(zs_t):  # two draws rounded together: spread them evenly
        zs_t = [_round(float(z), 4) for z in np.linspace(0.0, dz, n)]
    fs_t = [_round(float(f), 4) for f in fs]
    z0, z_dist = (0.0, dz) if z_down else (dz, -dz)
    doc = {
        "name": f"m{seed}-{index}",
        "description": (f"random machine {index} of seed {seed}: d = {d:g} m, v_max = {v_max:g} "
                        f"m/s, a_max = {a_max:g} m/s2; Z {z0:g} -> {z0 + z_dist:g} m, mode "
                        f"{fs_t[0] if z_down else fs_t[-1]:.4g} -> "
                        f"{fs_t[-1] if z_down else fs_t[0]:.4g} Hz, zeta = {zeta:g}; map "
                        f"+/-{100 * E:g} %"),
        "simulation": {"Te": 0.001, "step": 0.001, "t_after": float(t_after)},
        "move": {"distance": d, "v_max": v_max, "a_max": a_max},
        "z": {"z0": z0, "distance": z_dist, "a_max": 8.0, "v_max": 2.0, "T_F": 0.04,
              "sync": True},
        "mode": [{"name": "first mode", "zeta": zeta, "law": "table", "z": zs_t, "f": fs_t}],
        "uncertainty": {"map_scale": E},
    }
    return parse_scenario(doc, f"<machine {seed}:{index}>")


def machines(n: int, seed: int, cls: MachineClass = DEFAULT_CLASS) -> list[Scenario]:
    """Return machines 0..n−1 of ``seed`` (:func:`random_machine`)."""
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 0:
        raise ValueError(f"n must be an integer >= 0, got {n!r}")
    return [random_machine(seed, i, cls) for i in range(int(n))]
