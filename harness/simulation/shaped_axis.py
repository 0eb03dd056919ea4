"""A generator axis whose output is input-shaped: Σ Aᵢ·p(t − dᵢ), delays on the sample grid.

:class:`ShapedAxis` wraps any :class:`~harness.simulation.axis.Axis` (the FMU
or the compiled engine) and a :class:`ShaperSpec` whose delays are whole
samples: its outputs at the points are the weighted sum of the base profile's
outputs at earlier samples (the base at rest before its start and after its
end).  With whole-sample delays the shaped profile keeps the generator's
semantics -- piecewise cubic, one jerk per sample interval -- so the master
feeds the plant exactly, as for any generator profile.

The generator FMU shapes its own output (parameters ``shaper``,
``shaper_amplitude[i]``, ``shaper_delay[i]``; docs/generator.md, "Input
shaping"), and so does the compiled engine: :class:`~harness.simulation.session.Session`
runs shaped profiles that way (``Session.run(..., shaper=...)``).  This axis is
the harness's independent evaluation of the same convolution, from the
unshaped profile's samples (the tests hold the FMU's shaping against it).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..fmu.runner import samples_per_step
from .axis import Axis, InputsHook, MoveSamples, PlantInput, PointSamples, StopHook

__all__ = ["ShapedAxis", "ShaperSpec", "shaped"]


@dataclass(frozen=True)
class ShaperSpec:
    """An input shaper: impulses of amplitude ``amplitudes[i]`` at ``delays[i]`` samples.

    Attributes
    ----------
    amplitudes : tuple of float
        The impulses' amplitudes, summing to 1 (the move lands on its target);
        all ≥ 0 keeps every bound of the base profile.
    delays : tuple of int
        Their delays in samples of the generator's Te, increasing, the first 0.
    name : str
        Label (e.g. ``"robust 3-impulse"``).
    """

    amplitudes: tuple[float, ...]
    delays: tuple[int, ...]
    name: str = "shaper"

    def __post_init__(self) -> None:
        a, d = self.amplitudes, self.delays
        if not a or len(a) != len(d):
            raise ValueError(f"a shaper needs as many amplitudes as delays, got {a!r}, {d!r}")
        if not all(math.isfinite(x) for x in a) or abs(sum(a) - 1.0) > 1e-9:
            raise ValueError(f"shaper amplitudes must be finite and sum to 1, got {a!r}")
        if any(int(x) != x for x in d) or d[0] != 0 or any(y <= x for x, y in zip(d, d[1:],
                                                                                   strict=False)):
            raise ValueError(f"shaper delays must be whole samples, increasing from 0, got {d!r}")

    @property
    def span(self) -> int:
        """The largest delay (samples): what the shaper adds to the motion time."""
        return int(self.delays[-1])

    def delays_s(self, Te: float) -> tuple[float, ...]:
        """Return the delays in seconds."""
        return tuple(int(d) * Te for d in self.delays)

    def fmu_parameters(self, Te: float) -> dict[str, Any]:
        """Return the generator FMU's parameters for this shaper (custom, ``shaper = 4``)."""
        return {"shaper": 4, "shaper_n": len(self.amplitudes),
                "shaper_amplitude": [float(x) for x in self.amplitudes],
                "shaper_delay": list(self.delays_s(Te))}

    def describe(self, Te: float) -> str:
        """One line: amplitudes at delays (ms)."""
        return (f"{self.name}: " + " / ".join(f"{a:.3f}" for a in self.amplitudes) + " at "
                + " / ".join(f"{d * Te * 1e3:.0f}" for d in self.delays) + " ms")


class ShapedAxis:
    """A base axis shaped by a :class:`ShaperSpec` (an :class:`~harness.simulation.axis.Axis`).

    Parameters
    ----------
    base : Axis
        The generator axis (planned through this object).
    shaper : ShaperSpec
        The shaper, delays in samples of the base's Te.
    """

    def __init__(self, base: Axis, shaper: ShaperSpec) -> None:
        self.base = base
        self.shaper = shaper
        self.name = f"{base.name}*{shaper.name}"
        self.engine = base.engine
        self.fmi_version = base.fmi_version

    def plan(self, params: Mapping[str, Any], start_time: float = 0.0) -> float:
        """Plan the base move; return the shaped move's duration (s)."""
        T = self.base.plan(params, start_time)
        return T + self.shaper.span * float(self.base.get("Te"))

    def get(self, name: str) -> Any:
        """Return the base's values, but ``motion_time``: the shaped one."""
        if name == "motion_time":
            return float(self.base.get("motion_time")) \
                + self.shaper.span * float(self.base.get("Te"))
        return self.base.get(name)

    def N_F(self) -> tuple[int, int, int, int]:
        """Return the base's jerk times (samples)."""
        return self.base.N_F()

    def motion_start(self) -> float:
        """Where the base motion starts (s)."""
        return self.base.motion_start()

    def _shape(self, values: np.ndarray, m: int, rest0: float, rest1: float | None = None
               ) -> np.ndarray:
        """Σ Aᵢ values[k − dᵢ/m] (points ``m`` samples apart; rest before the start)."""
        out = np.zeros_like(values)
        for A, d in zip(self.shaper.amplitudes, self.shaper.delays, strict=True):
            if d % m:
                raise ValueError(f"{self.name}: delay {d} samples is not a whole number of "
                                 f"communication steps of {m} samples")
            s = d // m
            shifted = np.empty_like(values)
            shifted[:s] = rest0
            shifted[s:] = values[: values.size - s]
            out += A * shifted
        return out

    def points(self, n: int, h: float, names: tuple[str, ...] = ("x", "v", "a", "j"), *,
               inputs: InputsHook | None = None, stop: StopHook | None = None
               ) -> PointSamples:
        """Return the shaped outputs at the points 0, h, ..., n·h."""
        if inputs is not None or stop is not None:
            raise ValueError(f"{self.name}: a shaped axis takes no inputs")
        m = samples_per_step(h, float(self.base.get("Te")), self.name)
        base = self.base.points(n, h, names)
        x0 = float(self.base.get("x0"))
        values = {nm: self._shape(v, m, x0 if nm in ("x", "x_AL") else 0.0)
                  for nm, v in base.values.items()}
        return PointSamples(base.t, values)

    def sample(self, params: Mapping[str, Any], t_stop: float | None = None,
               start_time: float = 0.0) -> MoveSamples:
        """Plan and sample the shaped move at every generator sample."""
        T = self.plan(params, start_time)
        Te = float(self.base.get("Te"))
        if t_stop is None:
            t_stop = max(self.motion_start(), start_time) + T
        n = int(round((t_stop - start_time) / Te))
        pts = self.points(n, Te, ("x", "v", "a", "j", "a_AL"))
        return MoveSamples(pts.t + start_time, pts["x"], pts["v"], pts["a"], pts["j"],
                           pts["a_AL"], T, self.N_F(), float(self.get("t_start")))

    def sync_velocity(self, params: Mapping[str, Any], target_time: float, v_cap: float,
                      start_time: float = 0.0) -> tuple[float, float, bool]:
        """Synchronise the base so that the shaped move lasts ``target_time``."""
        span = self.shaper.span * float(params.get("Te", self.base.get("Te")))
        v, T, ok = self.base.sync_velocity(params, target_time - span, v_cap, start_time)
        return v, T + span, ok

    def plant_input(self, samples: PointSamples, h: float) -> PlantInput:
        """Return the generator's input: whole-sample delays keep one jerk per interval."""
        return PlantInput.of_points(samples)

    def close(self) -> None:
        """Close the base axis."""
        self.base.close()


def shaped(base: Axis, shaper: ShaperSpec | None) -> Axis:
    """Return ``base`` shaped by ``shaper`` (``base`` itself when there is none)."""
    return base if shaper is None else ShapedAxis(base, shaper)
