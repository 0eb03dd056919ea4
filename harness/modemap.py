"""Mode maps: how each mode's frequency depends on the Z position (and the load).

Béarée & Olabi 2013, §3.2 and §4: on a Cartesian machine the dominating mode
of the excited axis (X or Y) comes from the bending of the vertical Z axis, so
its frequency depends on the Z position.  Three ways to describe it:

* :class:`LinearLaw` — linear between two positions (what the paper fits to
  its modal survey, Fig. 14), extrapolated linearly outside them;
* :class:`TableLaw` — a lookup table from a modal survey, (z, f) with linear
  interpolation; it must cover the motion (no extrapolation);
* :class:`CantileverLaw` — the Z axis as a cantilever beam: the modal *period*
  is proportional to the square of the overhanging length L(z), so
  f(z) = f_ref · (L_ref / L(z))², with L(z) = L_ref + direction · (z - z_ref).

The load mass enters as a constant shift (§3.2: "the modal period will evolve
proportionally to the square root of the load mass"): a mode measured with a
load m_ref has, with a load m, the frequency f / √(m / m_ref)
(``mass_ratio`` = m / m_ref).

Laws are called with Python floats once per co-simulation step, so they are
written with plain arithmetic (no numpy on the scalar path).
"""

from __future__ import annotations

import bisect
import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .plant import Mode, ScheduledMode

__all__ = [
    "CantileverLaw",
    "ConstantLaw",
    "LinearLaw",
    "ModeMap",
    "ModeSpec",
    "TableLaw",
]


@dataclass(frozen=True)
class ConstantLaw:
    """A mode that does not depend on z.

    Parameters
    ----------
    f : float
        Frequency (Hz), > 0.
    """

    f: float
    kind = "constant"

    def __post_init__(self) -> None:
        if not self.f > 0:
            raise ValueError(f"f must be > 0 Hz, got {self.f!r}")

    def __call__(self, z: float) -> float:
        """Frequency (Hz) at position ``z`` (m)."""
        return self.f

    def array(self, z: np.ndarray) -> np.ndarray:
        """Frequencies (Hz) at an array of positions (m)."""
        return np.full(np.shape(z), self.f)

    def check_range(self, z_min: float, z_max: float) -> None:
        """Accept any range (a constant law is valid everywhere)."""

    def describe(self) -> str:
        """One-line description."""
        return f"constant {self.f:g} Hz"


@dataclass(frozen=True)
class LinearLaw:
    """Frequency linear in z through two points (extrapolated outside them).

    Parameters
    ----------
    z : (float, float)
        Two distinct positions (m).
    f : (float, float)
        Frequencies at those positions (Hz), > 0.
    """

    z: tuple[float, float]
    f: tuple[float, float]
    kind = "linear"

    def __post_init__(self) -> None:
        if len(self.z) != 2 or len(self.f) != 2:
            raise ValueError("a linear law takes exactly two positions and two frequencies")
        if self.z[0] == self.z[1]:
            raise ValueError(f"the two positions must differ, got z = {list(self.z)}")
        if not all(fi > 0 for fi in self.f):
            raise ValueError(f"frequencies must be > 0 Hz, got f = {list(self.f)}")
        object.__setattr__(self, "_slope", (self.f[1] - self.f[0]) / (self.z[1] - self.z[0]))

    def __call__(self, z: float) -> float:
        """Frequency (Hz) at position ``z`` (m)."""
        return self.f[0] + self._slope * (z - self.z[0])

    def array(self, z: np.ndarray) -> np.ndarray:
        """Frequencies (Hz) at an array of positions (m); the same arithmetic as a call."""
        return self.f[0] + self._slope * (np.asarray(z, dtype=float) - self.z[0])

    def check_range(self, z_min: float, z_max: float) -> None:
        """Raise ValueError if the frequency is not > 0 over [z_min, z_max]."""
        for zz in (z_min, z_max):
            if not self(zz) > 0:
                raise ValueError(f"the linear law gives f = {self(zz):.4g} Hz at z = {zz:g} m")

    def describe(self) -> str:
        """One-line description."""
        return (f"linear: {self.f[0]:g} Hz at z = {self.z[0]:g} m, "
                f"{self.f[1]:g} Hz at z = {self.z[1]:g} m")


@dataclass(frozen=True)
class TableLaw:
    """Lookup table from a modal survey, linearly interpolated.

    Parameters
    ----------
    z : sequence of float
        Strictly increasing positions (m), at least two.
    f : sequence of float
        Frequencies (Hz), > 0.
    """

    z: tuple[float, ...]
    f: tuple[float, ...]
    kind = "table"

    def __post_init__(self) -> None:
        object.__setattr__(self, "z", tuple(float(v) for v in self.z))
        object.__setattr__(self, "f", tuple(float(v) for v in self.f))
        if len(self.z) < 2 or len(self.z) != len(self.f):
            raise ValueError("a table needs at least two (z, f) points, as many z as f")
        if any(b <= a for a, b in zip(self.z, self.z[1:], strict=False)):
            raise ValueError(f"z must be strictly increasing, got {list(self.z)}")
        if not all(fi > 0 for fi in self.f):
            raise ValueError(f"frequencies must be > 0 Hz, got {list(self.f)}")

    def __call__(self, z: float) -> float:
        """Frequency (Hz) at ``z`` (m); the end values outside the table."""
        zs, fs = self.z, self.f
        i = bisect.bisect_right(zs, z)
        if i <= 0:
            return fs[0]
        if i >= len(zs):
            return fs[-1]
        z0, z1 = zs[i - 1], zs[i]
        return fs[i - 1] + (fs[i] - fs[i - 1]) * (z - z0) / (z1 - z0)

    def array(self, z: np.ndarray) -> np.ndarray:
        """Frequencies (Hz) at an array of positions (m); the same arithmetic as a call."""
        z = np.asarray(z, dtype=float)
        zs = np.asarray(self.z)
        fs = np.asarray(self.f)
        i = np.clip(np.searchsorted(zs, z, side="right"), 1, zs.size - 1)
        z0, z1, f0, f1 = zs[i - 1], zs[i], fs[i - 1], fs[i]
        out = f0 + (f1 - f0) * (z - z0) / (z1 - z0)
        out = np.where(z < zs[0], fs[0], out)
        return np.where(z >= zs[-1], fs[-1], out)

    def check_range(self, z_min: float, z_max: float) -> None:
        """Raise ValueError if the table does not cover [z_min, z_max]."""
        tol = 1e-12
        if z_min < self.z[0] - tol or z_max > self.z[-1] + tol:
            raise ValueError(f"the table covers z in [{self.z[0]:g}, {self.z[-1]:g}] m but the "
                             f"motion spans [{z_min:g}, {z_max:g}] m")

    def describe(self) -> str:
        """One-line description."""
        return (f"table of {len(self.z)} points, z in [{self.z[0]:g}, {self.z[-1]:g}] m, "
                f"f in [{min(self.f):g}, {max(self.f):g}] Hz")


@dataclass(frozen=True)
class CantileverLaw:
    """Cantilever beam: period ∝ (overhanging length)² (§3.2).

    f(z) = f_ref · (L_ref / L(z))², L(z) = L_ref + direction · (z - z_ref).

    Parameters
    ----------
    f_ref : float
        Frequency at ``z_ref`` (Hz), > 0.
    L_ref : float
        Overhanging length at ``z_ref`` (m), > 0.
    z_ref : float
        Reference position (m).
    direction : {+1, -1}
        +1 if the overhang grows when z increases.
    """

    f_ref: float
    L_ref: float
    z_ref: float = 0.0
    direction: int = 1
    kind = "cantilever"

    def __post_init__(self) -> None:
        if not self.f_ref > 0:
            raise ValueError(f"f_ref must be > 0 Hz, got {self.f_ref!r}")
        if not self.L_ref > 0:
            raise ValueError(f"L_ref must be > 0 m, got {self.L_ref!r}")
        if self.direction not in (1, -1):
            raise ValueError(f"direction must be +1 or -1, got {self.direction!r}")

    def length(self, z: float) -> float:
        """Overhanging length L(z) (m)."""
        return self.L_ref + self.direction * (z - self.z_ref)

    def __call__(self, z: float) -> float:
        """Frequency (Hz) at ``z`` (m)."""
        r = self.L_ref / (self.L_ref + self.direction * (z - self.z_ref))
        return self.f_ref * r * r

    def array(self, z: np.ndarray) -> np.ndarray:
        """Frequencies (Hz) at an array of positions (m); the same arithmetic as a call."""
        r = self.L_ref / (self.L_ref + self.direction * (np.asarray(z, dtype=float) - self.z_ref))
        return self.f_ref * r * r

    def check_range(self, z_min: float, z_max: float) -> None:
        """Raise ValueError if the overhang is not > 0 over [z_min, z_max]."""
        for zz in (z_min, z_max):
            if not self.length(zz) > 0:
                raise ValueError(f"the overhanging length is {self.length(zz):.4g} m at "
                                 f"z = {zz:g} m")

    def describe(self) -> str:
        """One-line description."""
        return (f"cantilever: {self.f_ref:g} Hz with overhang {self.L_ref:g} m at "
                f"z = {self.z_ref:g} m, overhang {'+' if self.direction > 0 else '-'}z")


FrequencyLaw = ConstantLaw | LinearLaw | TableLaw | CantileverLaw


@dataclass(frozen=True)
class ModeSpec:
    """One mode of the mode map.

    Parameters
    ----------
    law : FrequencyLaw
        f(z) for the reference load.
    zeta : float
        Damping ratio in [0, 1).
    gain : float
        Participation factor (see :class:`harness.plant.Mode`).
    mass_ratio : float
        Load mass over the mass the law was measured with (> 0); the frequency
        is divided by √mass_ratio (period ∝ √mass).
    name : str
        Label.
    """

    law: FrequencyLaw
    zeta: float
    gain: float = 1.0
    mass_ratio: float = 1.0
    name: str = ""

    def __post_init__(self) -> None:
        if not (0.0 <= self.zeta < 1.0):
            raise ValueError(f"zeta must be in [0, 1), got {self.zeta!r}")
        if not self.mass_ratio > 0:
            raise ValueError(f"mass_ratio must be > 0, got {self.mass_ratio!r}")

    @property
    def scale(self) -> float:
        """Frequency factor of the load, 1/√mass_ratio."""
        return 1.0 / math.sqrt(self.mass_ratio)

    def f(self, z: float) -> float:
        """Frequency (Hz) at ``z`` with this load."""
        return self.law(z) * self.scale

    def f_array(self, z: np.ndarray) -> np.ndarray:
        """Frequencies (Hz) at an array of positions (the same values as :meth:`f`)."""
        f = self.law.array(np.asarray(z, dtype=float))
        return f if self.scale == 1.0 else f * self.scale

    def scaled(self, factor: float) -> ModeSpec:
        """Return the same mode with every frequency multiplied by ``factor`` (> 0).

        A map error of e (the whole f(z) law off by 1 + e) is ``scaled(1 + e)``;
        it is carried as a load-mass ratio 1/factor², so ``f = law(z) · factor``.
        """
        if not (math.isfinite(factor) and factor > 0):
            raise ValueError(f"frequency factor must be a finite number > 0, got {factor!r}")
        return dataclasses.replace(self, mass_ratio=self.mass_ratio / (factor * factor))

    def period(self, z: float) -> float:
        """Natural period (s) at ``z``."""
        return 1.0 / self.f(z)

    def at(self, z: float) -> Mode:
        """Return the frozen :class:`~harness.plant.Mode` at ``z``."""
        return Mode(self.f(z), self.zeta, self.gain)

    def scheduled(self) -> ScheduledMode:
        """Return the mode as a :class:`harness.plant.ScheduledMode`."""
        law, s = self.law, self.scale
        fz = law if s == 1.0 else (lambda z: law(z) * s)
        return ScheduledMode(fz, self.zeta, self.gain, self.name, f_of_z_array=self.f_array)

    def check_range(self, z_min: float, z_max: float) -> None:
        """Raise ValueError if the law is not valid over [z_min, z_max]."""
        self.law.check_range(z_min, z_max)


@dataclass(frozen=True)
class ModeMap:
    """The modes of the excited axis and which one the jerk times are tuned to.

    Parameters
    ----------
    modes : sequence of ModeSpec
        At least one.
    tune : int
        Index (0-based) of the mode the JL / DJL jerk times are tuned to.
    """

    modes: tuple[ModeSpec, ...]
    tune: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "modes", tuple(self.modes))
        if not self.modes:
            raise ValueError("a mode map needs at least one mode")
        if not 0 <= self.tune < len(self.modes):
            raise ValueError(f"tune must index one of the {len(self.modes)} modes")

    @property
    def tuned(self) -> ModeSpec:
        """The mode the jerk times are tuned to."""
        return self.modes[self.tune]

    def period(self, z: float) -> float:
        """Period (s) of the tuned mode at ``z``."""
        return self.tuned.period(z)

    def modes_at(self, z: float) -> list[Mode]:
        """All modes frozen at ``z``."""
        return [m.at(z) for m in self.modes]

    def scheduled(self) -> list[ScheduledMode]:
        """Return the modes for :class:`harness.plant.ScheduledPlant`."""
        return [m.scheduled() for m in self.modes]

    def scaled(self, factor: float) -> ModeMap:
        """Return the map with every frequency multiplied by ``factor`` (a map error 1 + e)."""
        return ModeMap(tuple(m.scaled(factor) for m in self.modes), self.tune)

    def check_range(self, z_min: float, z_max: float) -> None:
        """Raise ValueError naming the mode whose law is invalid over the range."""
        for i, m in enumerate(self.modes):
            try:
                m.check_range(z_min, z_max)
            except ValueError as e:
                raise ValueError(f"mode {i + 1}{f' ({m.name})' if m.name else ''}: {e}") from None

    def plot(self, z: Sequence[float] | np.ndarray | None = None, ax=None):
        """Plot f(z) of every mode; return the figure."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        if ax is None:
            fig, ax = plt.subplots(figsize=(6, 3.5))
        else:
            fig = ax.figure
        zz = np.linspace(0.0, 0.5, 101) if z is None else np.asarray(z, dtype=float)
        for i, m in enumerate(self.modes):
            ax.plot(zz, m.f_array(zz), label=m.name or f"mode {i + 1}")
        ax.set_xlabel("z [m]")
        ax.set_ylabel("f [Hz]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize="small")
        return fig
