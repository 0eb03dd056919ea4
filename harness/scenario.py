"""Scenario files (TOML): the moves, the mode map and the profiles to compare.

A scenario is checked completely when it is loaded — unknown keys, missing or
out-of-range values, a lookup table that does not cover the motion, a
communication step that is not a multiple of ``Te``, an FMU file without the
generator's variables — and every problem is reported as
:class:`ScenarioError` naming the file, the key and the value, before anything
is simulated.

Format (all lengths in m, times in s, frequencies in Hz)::

    name = "X"                      # default: the file name
    description = "..."

    [simulation]                    # optional, defaults shown
    Te = 0.001                      # generator sampling period
    step = 0.001                    # communication step, a whole multiple of Te
    t_after = 3.0                   # simulated time after both axes have stopped
    fmi_version = 2                 # 2 or 3 (the package's own FMU)
    fmu = "my_generator.fmu"        # or a generator FMU file (relative to this file)
    settle_band = "1 % of AL"       # settling band, one for every profile of a case:
                                    # a number (m), "P % of AL" (P in (0, 100]: of AL's
                                    # residual) or "paper" (DJL's residual, Table 2's band)
    # band = 0.0005                 # old name of a settle_band in m (not both)
    short_stage = 2                 # FMU rule for short stages (2 = the paper's)

    [move]                          # the excited axis (X or Y)
    axis = "X"                      # label
    distance = 0.4                  # required, signed
    v_max = 0.5                     # required
    a_max = 4.0                     # required
    d_max = 4.0                     # default: a_max
    x0 = 0.0
    t_start = 0.0

    [z]                             # optional: the Z axis, a JL move
    z0 = 0.0                        # start position (the only key needed for a still Z)
    distance = 0.45                 # default 0 (Z does not move)
    a_max = 2.0
    v_max = 1.0                     # velocity limit
    T_F = 0.05                      # JL jerk time
    sync = true                     # lower v_max so that Z ends with the excited axis

    [[mode]]                        # one table per mode, at least one
    name = "first X mode"
    zeta = 0.03                     # required, in [0, 1)
    law = "linear"                  # "linear" | "table" | "cantilever" | "constant"
    z = [0.0, 0.5]                  # linear: two positions; table: increasing positions
    f = [8.5, 6.375]                # linear/table: frequencies; constant: one number
    # cantilever: f_ref, L_ref, z_ref (default 0), direction (+1/-1, default +1)
    gain = 1.0                      # participation factor
    mass_ratio = 1.0                # load mass / mass of the survey (f / sqrt(ratio))

    [compare]                       # optional
    profiles = ["AL", "JL", "DJL"]  # also "JL-optimal", "DJL-paper", "DJL-optimal",
                                    # "DJL-robust": a profile with its own tuning method
    tune_mode = 1                   # mode (1-based) the jerk times are tuned to
    djl_rule = "start"              # the paper's rule: "start" (paper) or "phase"
    djl_tuning = "paper"            # DJL jerk times: "paper" (the rule above), "optimal"
                                    # (least residual), "robust" (least worst case)
    jl_tuning = "end"               # JL jerk time: "end" (period at the end), "optimal"
    max_motion_time = "JL"          # optional: no longer than JL's motion (or a time in s)
    period_band = 0.5               # jerk times within +/-50 % of the local periods
    JL_T_F = 0.15                   # optional: impose the JL jerk time
    DJL_T_F = [0.12, 0.13, 0.14, 0.15]   # optional: impose the DJL jerk times

    [uncertainty]                   # optional: how far the real mode map may be off
    map_scale = 0.1                 # the whole map f(z) off by up to +/-10 % (default)
    map_slope = 0.3                 # its slope df/dz off by up to +/-30 % (default 0: off)
    z_shift = 0.05                  # the map shifted along z by up to +/-5 cm (default 0)
    damping = [0.5, 2.0]            # every damping ratio x 0.5 .. 2 (default: off)
    # robust tuning minimises over a coarse set of these, every table scores on a
    # finer one, and every worst case, curve and label uses map_scale (harness.uncertainty)
    # Deprecated aliases, read as these keys (a note on stderr; both given and
    # disagreeing: refused): [compare] map_error = E  (map_scale = E) and
    # [compare] damping = [f1, f2, ...]  (damping = [min(f, 1), max(f, 1)])

    [sweep]                         # optional: run the grid of all combinations
    distance = [0.1, 0.2, 0.3]      # replaces move.distance
    z_distance = [0.1, 0.3, 0.5]    # replaces z.distance
    v_max = [0.5, 2.0]              # replaces move.v_max

    [map]                           # optional: the workspace map of ``djl-fmu map``
    z0 = [0.0, 0.05, 0.1]           # replaces z.z0            (default: [z.z0])
    z_distance = [0.05, 0.25, 0.45] # replaces z.distance      (default: [z.distance])
    distance = [0.05, 0.1, 0.2]     # replaces move.distance   (default: [move.distance])
    v_max = [0.5, 2.0]              # replaces move.v_max      (default: [move.v_max])
    # moves: every combination, in the order z0, z_distance, distance, v_max
    # (v_max varies fastest); see docs/map.md
"""

from __future__ import annotations

import dataclasses
import difflib
import itertools
import math
import sys
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from .errors import HarnessError
from .fmu.runner import check_fmu_binary, check_fmu_variables, samples_per_step
from .metrics import DEFAULT_SETTLE_BAND, SettleBand, parse_settle_band
from .modemap import CantileverLaw, ConstantLaw, LinearLaw, ModeMap, ModeSpec, TableLaw
from .tuning_options import DJL_METHODS, JL_METHODS, RULES, VARIANTS, TuningOptions
from .uncertainty import (
    DEFAULT_UNCERTAINTY,
    DeprecatedAliasWarning,
    UncertaintySpec,
    resolve_alias,
)

__all__ = [
    "CompareSpec",
    "MapSpec",
    "MoveSpec",
    "Scenario",
    "ScenarioError",
    "SimulationSpec",
    "SweepSpec",
    "ZSpec",
    "embedded_scenarios",
    "load_scenario",
    "parse_scenario",
]

PROFILES = ("AL", "JL", "DJL")
_MISSING = object()

# ------------------------------------------------ limits (docs/harness.md, "Limits")
MAX_SAMPLES_PER_RUN = 10**7
"""Most generator samples (``Te``) one simulated move may take: the motion (bounded
from above before running) plus ``t_after``, divided by ``Te``."""
MAX_SWEEP_CASES = 10**5
"""Most cases of a ``[sweep]`` (the product of its list lengths)."""
MAX_MAP_MOVES = 10**6
"""Most moves of a ``[map]`` grid (the product of its list lengths)."""
MAX_LIST_LENGTH = 10**5
"""Longest list of numbers in a scenario (``[sweep]``, ``[map]``, ``f``/``z`` tables)."""
MAX_GAIN = 1e6
"""Largest magnitude of a mode's ``gain``."""
FREQUENCY_RANGE = (1e-3, 1e5)
"""Frequencies of the mode laws (``f``, ``f_ref``), in Hz."""
MASS_RATIO_RANGE = (1e-6, 1e6)
"""Range of a mode's ``mass_ratio``."""
MAX_STEP = 1.0
"""Largest ``Te`` and communication ``step`` (s)."""


class ScenarioError(HarnessError, ValueError):
    """A scenario that cannot be run: names the file, the key and the value.

    Attributes
    ----------
    source : str
        The scenario file (or ``<string>``).
    key : str
        Dotted key, e.g. ``mode[1].zeta`` (empty for file-level problems).
    value : Any
        The offending value (``None`` when missing).
    problem : str
        What is wrong.
    """

    def __init__(self, source: str, key: str, value: Any, problem: str) -> None:
        self.source, self.key, self.value, self.problem = source, key, value, problem
        if not key:
            msg = f"{source}: {problem}"
        elif value is _MISSING or value is None:
            msg = f"{source}: {key} is missing: {problem}"
        else:
            msg = f"{source}: {key} = {_show(value)!r}: {problem}"
        super().__init__(msg)


# ----------------------------------------------------------------- specs


@dataclass(frozen=True)
class SimulationSpec:
    """``[simulation]``: sampling, window, FMU and settling band.

    ``settle_band`` is the settling band of every profile of a case
    (:class:`harness.metrics.SettleBand`; default 1 % of AL's residual);
    ``band`` mirrors it when it is a number of metres (None otherwise), as the
    old key of the same name did.
    """

    Te: float = 1e-3
    step: float = 1e-3
    t_after: float = 3.0
    fmi_version: int = 2
    fmu: Path | None = None
    band: float | None = None
    short_stage: int = 2
    settle_band: SettleBand = DEFAULT_SETTLE_BAND


@dataclass(frozen=True)
class MoveSpec:
    """``[move]``: the excited axis."""

    distance: float
    v_max: float
    a_max: float
    d_max: float
    axis: str = "X"
    x0: float = 0.0
    t_start: float = 0.0

    @property
    def target(self) -> float:
        """Final position (m)."""
        return self.x0 + self.distance


@dataclass(frozen=True)
class ZSpec:
    """``[z]``: the Z axis, a JL move (or still)."""

    z0: float = 0.0
    distance: float = 0.0
    a_max: float = 2.0
    v_max: float = 1.0
    T_F: float = 0.05
    sync: bool = True

    @property
    def moves(self) -> bool:
        """True if Z moves."""
        return self.distance != 0.0

    @property
    def z_range(self) -> tuple[float, float]:
        """Positions covered (m)."""
        z1 = self.z0 + self.distance
        return (min(self.z0, z1), max(self.z0, z1))


@dataclass(frozen=True)
class CompareSpec:
    """``[compare]``: profiles and their jerk times."""

    profiles: tuple[str, ...] = PROFILES
    djl_rule: str = "start"
    JL_T_F: float | None = None
    DJL_T_F: tuple[float, float, float, float] | None = None
    djl_tuning: str = "paper"
    jl_tuning: str = "end"
    max_motion_time: float | str | None = None
    period_band: float = 0.5


@dataclass(frozen=True)
class SweepSpec:
    """``[sweep]``: lists of values whose combinations are run."""

    distance: tuple[float, ...] | None = None
    z_distance: tuple[float, ...] | None = None
    v_max: tuple[float, ...] | None = None


@dataclass(frozen=True)
class MapSpec:
    """``[map]``: the workspace grid of ``djl-fmu map`` (:meth:`Scenario.map_cases`).

    The moves are every combination of the four lists, in the order
    ``z0``, ``z_distance``, ``distance``, ``v_max`` with ``v_max`` varying
    fastest: move ``k`` (0-based) is
    ``k = ((i_z0 * n_dz + i_dz) * n_d + i_d) * n_v + i_v``.  A list left as
    None takes the scenario's single value (``z.z0``, ``z.distance``,
    ``move.distance``, ``move.v_max``).

    Attributes
    ----------
    z0 : tuple of float, optional
        Start positions of Z (m).
    z_distance : tuple of float, optional
        Signed Z travels (m); 0 keeps Z still.
    distance : tuple of float, optional
        Signed lengths of the excited axis' move (m), none 0.
    v_max : tuple of float, optional
        Velocity limits of the excited axis (m/s), all > 0.
    """

    z0: tuple[float, ...] | None = None
    z_distance: tuple[float, ...] | None = None
    distance: tuple[float, ...] | None = None
    v_max: tuple[float, ...] | None = None


def _check_max_moves(max_moves: object) -> None:
    if isinstance(max_moves, bool) or not isinstance(max_moves, int) or max_moves < 1:
        raise ValueError(f"max_moves must be an integer >= 1, got {max_moves!r}")


# badly approximable fractions (golden, silver, sqrt 3 - 1, (sqrt 13 - 3) / 2): a step of
# m * f visits the m values of an axis evenly, even for a few choices
_STEPS = ((math.sqrt(5.0) - 1.0) / 2.0, math.sqrt(2.0) - 1.0, math.sqrt(3.0) - 1.0,
          (math.sqrt(13.0) - 3.0) / 2.0)


def _coprime_step(m: int, fraction: float) -> int:
    """Return the integer nearest ``m * fraction`` that is prime to ``m`` (0 for m = 1)."""
    if m == 1:
        return 0
    near = sorted(range(1, m), key=lambda s: (abs(s - m * fraction), s))
    return next(s for s in near if math.gcd(s, m) == 1)


def spread_indices(sizes: Sequence[int], count: int) -> list[tuple[int, ...]]:
    """Pick ``count`` cells of a grid of shape ``sizes``, spread evenly over every axis.

    The first axis' values share ``count`` as evenly as possible (the extra
    ones to evenly spaced values); each value's share is split the same way
    over the next axis, and so on.  Where an axis gets fewer cells than it has
    values, they are evenly spaced from an offset that moves on at each
    choice on that axis by a step of its own (prime to the axis' size, near
    a badly approximable fraction of it: golden ratio, silver ratio, ...), so
    that the sub-grids take every offset in turn and the axes do not follow
    each other.  Deterministic.

    Parameters
    ----------
    sizes : sequence of int
        Number of values of each axis (>= 1).
    count : int
        Cells to pick, ``1 <= count <= prod(sizes)``.

    Returns
    -------
    list of tuple of int
        ``count`` distinct multi-indices, in lexicographic order.
    """
    if not 1 <= count <= math.prod(sizes):
        raise ValueError(f"count must be in 1..{math.prod(sizes)}, got {count}")
    # on each axis, the offset of the evenly spaced choices moves on by a step of its
    # own (about m * _STEPS[axis]; prime to m: every offset in turn)
    cursor = [0] * len(sizes)
    steps = [_coprime_step(m, _STEPS[k % len(_STEPS)]) for k, m in enumerate(sizes)]

    def pick(axis: int, k: int, m: int) -> list[int]:
        # k of m values (k <= m), evenly spaced from the axis' current offset
        c = cursor[axis]
        cursor[axis] = (c + steps[axis]) % m
        return [(c + i * m // k) % m for i in range(k)]

    def split(axis: int, k: int) -> list[tuple[int, ...]]:
        if axis == len(sizes):
            return [()]
        m = sizes[axis]
        if k < m:
            shares = dict.fromkeys(pick(axis, k, m), 1)
        else:
            base, extra = divmod(k, m)
            plus = set(pick(axis, extra, m)) if extra else set()
            shares = {i: base + (i in plus) for i in range(m)}
        return [(i, *sub) for i in sorted(shares) for sub in split(axis + 1, shares[i])]

    return split(0, count)


@dataclass(frozen=True)
class Scenario:
    """A checked scenario.

    Use :func:`load_scenario` (file or embedded name) or :func:`parse_scenario`.
    Run it with :func:`harness.sweeps.run_scenario`.
    """

    name: str
    move: MoveSpec
    z: ZSpec
    modemap: ModeMap
    simulation: SimulationSpec = SimulationSpec()
    compare: CompareSpec = CompareSpec()
    sweep: SweepSpec | None = None
    description: str = ""
    source: str = "<string>"
    map: MapSpec | None = None
    uncertainty: UncertaintySpec = DEFAULT_UNCERTAINTY

    @property
    def is_sweep(self) -> bool:
        """True when the scenario has a ``[sweep]`` table."""
        return self.sweep is not None

    def tuning_options(self) -> TuningOptions:
        """Return what the ``optimal`` / ``robust`` searches may do.

        The map error and the damping range are the scenario's ``uncertainty``
        (their only home); the bounds are ``[compare]``'s.
        """
        u, c = self.uncertainty, self.compare
        return TuningOptions(u.map_scale, u.damping if u.active["damping"] else None,
                             c.max_motion_time, c.period_band)

    def cases(self) -> list[Scenario]:
        """Return the single-move scenarios of a sweep (itself when not a sweep)."""
        if self.sweep is None:
            return [self]
        sw = self.sweep
        out = []
        for d, dz, v in itertools.product(sw.distance or (self.move.distance,),
                                          sw.z_distance or (self.z.distance,),
                                          sw.v_max or (self.move.v_max,)):
            mv = dataclasses.replace(self.move, distance=d, v_max=v)
            zz = dataclasses.replace(self.z, distance=dz)
            out.append(dataclasses.replace(
                self, move=mv, z=zz, sweep=None,
                name=f"{self.name} d={d:g} dz={dz:g} v={v:g}"))
        return out

    # ------------------------------------------------------------ the map

    def map_axes(self) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...],
                                tuple[float, ...]]:
        """Values of the map's grid: ``(z0, z_distance, distance, v_max)``.

        A list the ``[map]`` table does not give (or every list, without a
        ``[map]`` table) is the scenario's single value.
        """
        mp = self.map or MapSpec()
        return (mp.z0 or (self.z.z0,), mp.z_distance or (self.z.distance,),
                mp.distance or (self.move.distance,), mp.v_max or (self.move.v_max,))

    @property
    def map_size(self) -> int:
        """Number of moves of the map's full grid (1 without a ``[map]`` table)."""
        return math.prod(len(a) for a in self.map_axes())

    def map_points(self, max_moves: int | None = None, *, spread: bool = False
                   ) -> list[tuple[float, float, float, float]]:
        """Return the moves of the map, ``(z0, z_distance, distance, v_max)``, in grid order.

        Parameters
        ----------
        max_moves : int, optional
            Keep only ``max_moves`` moves (>= 1): the first ones of the grid, or
            with ``spread`` the moves of :meth:`map_indices`.
        spread : bool
            Sample ``max_moves`` moves across the whole grid (``djl-fmu map``)
            instead of taking the first ones (``djl-fmu tune``).

        Returns
        -------
        list of tuple of float
            The cartesian product of :meth:`map_axes`, ``v_max`` varying fastest
            (a subset of it, still in grid order, with ``max_moves``).

        Raises
        ------
        ValueError
            If ``max_moves`` is not an integer >= 1.
        """
        grid = list(itertools.product(*self.map_axes()))
        return [grid[i] for i in self.map_indices(max_moves, spread=spread)]

    def map_indices(self, max_moves: int | None = None, *, spread: bool = True) -> list[int]:
        """Return the grid indices (``v_max`` fastest) of the moves :meth:`map_points` keeps.

        Parameters
        ----------
        max_moves : int, optional
            How many moves (>= 1; default: every move of the grid).
        spread : bool
            True: ``max_moves`` moves spread evenly over the whole grid, by
            :func:`spread_indices`: every (z0, v_max) pair, a panel of the heat
            maps, gets its share, then Z travel and move length within it;
            deterministic. False: the first ``max_moves`` moves.

        Returns
        -------
        list of int
            Increasing indices into the grid.

        Raises
        ------
        ValueError
            If ``max_moves`` is not an integer >= 1.
        """
        n = self.map_size
        if max_moves is None or max_moves >= n:
            if max_moves is not None:
                _check_max_moves(max_moves)
            return list(range(n))
        _check_max_moves(max_moves)
        if not spread:
            return list(range(max_moves))
        n_z0, n_dz, n_d, n_v = (len(a) for a in self.map_axes())
        # the heat maps' panels first (z0 rows, v_max columns), then dz and d within them
        picked = spread_indices((n_z0, n_v, n_dz, n_d), max_moves)
        return sorted(((i_z0 * n_dz + i_dz) * n_d + i_d) * n_v + i_v
                      for i_z0, i_v, i_dz, i_d in picked)

    def map_case(self, z0: float, z_distance: float, distance: float, v_max: float
                 ) -> Scenario:
        """Return the single-move scenario of one point of the map (no sweep, no map)."""
        mv = dataclasses.replace(self.move, distance=distance, v_max=v_max)
        zz = dataclasses.replace(self.z, z0=z0, distance=z_distance)
        return dataclasses.replace(
            self, move=mv, z=zz, sweep=None, map=None,
            name=f"{self.name} z0={z0:g} dz={z_distance:g} d={distance:g} v={v_max:g}")

    def map_cases(self, max_moves: int | None = None) -> list[Scenario]:
        """Return the single-move scenarios of the map, in grid order (see :class:`MapSpec`).

        Parameters
        ----------
        max_moves : int, optional
            Keep only the first ``max_moves`` moves of the grid.

        Returns
        -------
        list of Scenario
        """
        return [self.map_case(*p) for p in self.map_points(max_moves)]

    def with_fmu(self, fmu: Path | None = None, fmi_version: int | None = None) -> Scenario:
        """Copy with another FMU file and/or FMI version (command-line overrides)."""
        sim = self.simulation
        if fmu is not None:
            _check_fmu(self.source, "simulation.fmu", Path(fmu))
            sim = dataclasses.replace(sim, fmu=Path(fmu))
        if fmi_version is not None:
            if (isinstance(fmi_version, bool) or not isinstance(fmi_version, int)
                    or fmi_version not in (2, 3)):
                raise ScenarioError(self.source, "simulation.fmi_version", fmi_version,
                                    "must be the integer 2 or 3")
            sim = dataclasses.replace(sim, fmi_version=fmi_version)
        return dataclasses.replace(self, simulation=sim)


# --------------------------------------------------------------- parsing


def _finite(x: Any) -> bool:
    """Return True for an int or float (not bool) that is a finite float (no 400-digit int)."""
    if isinstance(x, bool) or not isinstance(x, (int, float)):
        return False
    try:
        return math.isfinite(float(x))
    except OverflowError:
        return False


class _Table:
    """Reads one TOML table, remembering which keys were used."""

    def __init__(self, source: str, prefix: str, data: Any) -> None:
        self.source, self.prefix = source, prefix
        if not isinstance(data, Mapping):
            raise ScenarioError(source, prefix, data, "must be a table")
        self.data = dict(data)
        self.used: set[str] = set()

    def key(self, k: str) -> str:
        return f"{self.prefix}.{k}" if self.prefix else k

    def err(self, k: str, value: Any, problem: str) -> ScenarioError:
        return ScenarioError(self.source, self.key(k), value, problem)

    def raw(self, k: str, default: Any = _MISSING, what: str = "") -> Any:
        self.used.add(k)
        if k in self.data:
            return self.data[k]
        if default is _MISSING:
            # a required key missing beside an unread key spelt almost like it: the typo
            typo = _close_key(k, [d for d in self.data if d not in self.used], cutoff=0.85)
            if typo is not None:
                raise self.err(typo, self.data[typo], f"unknown key; did you mean {k}? "
                               f"({self.key(k)} is required" + (f": {what})" if what else ")"))
            raise self.err(k, _MISSING, what or "required")
        return default

    def number(self, k: str, default: Any = _MISSING, *, what: str = "", positive: bool = False,
               nonneg: bool = False, nonzero: bool = False) -> Any:
        v = self.raw(k, default, what)
        if k not in self.data:
            return v
        if not _finite(v):
            raise self.err(k, _show(v), "must be a finite number" + (f" ({what})" if what else ""))
        v = float(v)
        if positive and not v > 0:
            raise self.err(k, v, "must be > 0" + (f" ({what})" if what else ""))
        if nonneg and not v >= 0:
            raise self.err(k, v, "must be >= 0" + (f" ({what})" if what else ""))
        if nonzero and v == 0:
            raise self.err(k, v, "must not be 0" + (f" ({what})" if what else ""))
        return v

    def numbers(self, k: str, default: Any = _MISSING, *, what: str = "", min_len: int = 1
                ) -> Any:
        v = self.raw(k, default, what)
        if k not in self.data:
            return v
        if isinstance(v, list) and len(v) > MAX_LIST_LENGTH:
            raise self.err(k, _show(v), f"has {len(v)} values, more than the limit of "
                           f"{MAX_LIST_LENGTH} (MAX_LIST_LENGTH)")
        if not isinstance(v, list) or len(v) < min_len or any(not _finite(x) for x in v):
            raise self.err(k, _show(v), f"must be a list of at least {min_len} finite number(s)"
                           + (f" ({what})" if what else ""))
        return tuple(float(x) for x in v)

    def string(self, k: str, default: Any = _MISSING, *, choices: tuple[str, ...] | None = None
               ) -> Any:
        v = self.raw(k, default)
        if k not in self.data:
            return v
        if not isinstance(v, str):
            raise self.err(k, v, "must be a string")
        if choices is not None and v not in choices:
            raise self.err(k, v, f"must be one of {', '.join(choices)}")
        return v

    def boolean(self, k: str, default: Any = _MISSING) -> Any:
        v = self.raw(k, default)
        if k not in self.data:
            return v
        if not isinstance(v, bool):
            raise self.err(k, v, "must be true or false")
        return v

    def integer(self, k: str, default: Any = _MISSING, choices: tuple[int, ...] | None = None
                ) -> Any:
        v = self.raw(k, default)
        if k not in self.data:
            return v
        if isinstance(v, bool) or not isinstance(v, int):
            raise self.err(k, _show(v), "must be an integer")
        if choices is not None and v not in choices:
            raise self.err(k, v, f"must be one of {', '.join(map(str, choices))}")
        return v

    def finish(self) -> None:
        unknown = [k for k in self.data if k not in self.used]
        if unknown:
            k = unknown[0]
            near = _close_key(k, sorted(self.used), cutoff=0.6)
            hint = f"did you mean {near}? " if near is not None else ""
            raise self.err(k, self.data[k],
                           f"unknown key; {hint}(known: {', '.join(sorted(self.used))})")


def _close_key(key: str, candidates: list[str], *, cutoff: float) -> str | None:
    """Return the candidate closest to ``key`` (case and underscores ignored), if any is close."""
    def norm(x: str) -> str:
        return x.lower().replace("_", "").replace("-", "")

    by_norm: dict[str, str] = {}
    for c in candidates:
        by_norm.setdefault(norm(c), c)
    best = difflib.get_close_matches(norm(key), list(by_norm), n=1, cutoff=cutoff)
    return by_norm[best[0]] if best else None


def _show(v: Any, limit: int = 60) -> Any:
    """Return the value for an error message, huge integers and long lists shortened."""
    if isinstance(v, list):
        items = [_show(x, limit) for x in v[:8]]
        return items + (["..."] if len(v) > 8 else [])
    if isinstance(v, int) and not isinstance(v, bool) and abs(v) > 10**18:
        n = int(abs(v).bit_length() * 0.30103) + 1  # about its number of digits
        return _Shown(f"{'-' if v < 0 else ''}<an integer of about {n} digits>")
    if isinstance(v, str) and len(v) > 10 * limit:
        return v[:10 * limit] + "..."
    return v


class _Shown(str):
    def __repr__(self) -> str:
        return str(self)


def _check_fmu(source: str, key: str, path: Path) -> None:
    if not path.is_file():
        raise ScenarioError(source, key, str(path), "no such FMU file")
    try:
        missing = check_fmu_variables(path)
    except ValueError as e:
        raise ScenarioError(source, key, str(path), str(e)) from None
    if missing:
        raise ScenarioError(source, key, str(path),
                            "the FMU lacks the generator variables " + ", ".join(missing))
    try:
        check_fmu_binary(path)
    except ValueError as e:
        raise ScenarioError(source, key, str(path), str(e)) from None


def _check_frequencies(t: _Table, k: str, values: Any) -> None:
    lo, hi = FREQUENCY_RANGE
    bad = [x for x in values if not lo <= x <= hi]
    if bad:
        v = list(values) if len(values) > 1 else values[0]
        raise t.err(k, _show(v), f"frequencies must be in [{lo:g}, {hi:g}] Hz "
                    f"(FREQUENCY_RANGE; got {bad[0]:g})")


def _parse_mode(source: str, i: int, data: Any) -> ModeSpec:
    t = _Table(source, f"mode[{i}]", data)
    name = t.string("name", f"mode {i}")
    zeta = t.number("zeta", what="damping ratio in [0, 1)")
    if not 0.0 <= zeta < 1.0:
        raise t.err("zeta", zeta, "damping ratio must be in [0, 1)")
    law_name = t.string("law", choices=("linear", "table", "cantilever", "constant"))
    law: Any
    if law_name == "constant":
        f = t.number("f", what="frequency in Hz")
        if not f > 0:
            raise t.err("f", f, "frequency must be > 0 Hz")
        _check_frequencies(t, "f", [f])
        law = ConstantLaw(f)
    elif law_name in ("linear", "table"):
        z = t.numbers("z", what="positions in m", min_len=2)
        f = t.numbers("f", what="frequencies in Hz", min_len=2)
        bad = [x for x in f if not x > 0]
        if bad:
            raise t.err("f", list(f), f"frequencies must be > 0 Hz (got {bad[0]:g})")
        _check_frequencies(t, "f", f)
        if len(z) != len(f):
            raise t.err("f", list(f), f"needs as many values as z ({len(z)})")
        if law_name == "linear":
            if len(z) != 2:
                raise t.err("z", list(z), "a linear law takes exactly two positions")
            if z[0] == z[1]:
                raise t.err("z", list(z), "the two positions must differ")
            law = LinearLaw((z[0], z[1]), (f[0], f[1]))
        else:
            if any(b <= a for a, b in zip(z, z[1:], strict=False)):
                raise t.err("z", list(z), "table positions must be strictly increasing")
            law = TableLaw(z, f)
    else:
        f_ref = t.number("f_ref", what="frequency in Hz at z_ref")
        if not f_ref > 0:
            raise t.err("f_ref", f_ref, "frequency must be > 0 Hz")
        _check_frequencies(t, "f_ref", [f_ref])
        L_ref = t.number("L_ref", positive=True, what="overhanging length in m at z_ref")
        z_ref = t.number("z_ref", 0.0)
        direction = t.integer("direction", 1, choices=(1, -1))
        law = CantileverLaw(f_ref, L_ref, z_ref, direction)
    gain = t.number("gain", 1.0, nonzero=True)
    if abs(gain) > MAX_GAIN:
        raise t.err("gain", gain, f"magnitude must be <= {MAX_GAIN:g} (MAX_GAIN)")
    mass_ratio = t.number("mass_ratio", 1.0, positive=True,
                          what="load mass / mass of the modal survey")
    if not MASS_RATIO_RANGE[0] <= mass_ratio <= MASS_RATIO_RANGE[1]:
        raise t.err("mass_ratio", mass_ratio, f"must be in [{MASS_RATIO_RANGE[0]:g}, "
                    f"{MASS_RATIO_RANGE[1]:g}] (MASS_RATIO_RANGE)")
    t.finish()
    return ModeSpec(law, zeta, gain, mass_ratio, name)


def parse_scenario(data: Mapping[str, Any], source: str = "<string>",
                   base_dir: Path | None = None) -> Scenario:
    """Check a scenario given as a dict (parsed TOML).

    Parameters
    ----------
    data : mapping
        The TOML document.
    source : str
        Name used in error messages (the file).
    base_dir : Path, optional
        Directory against which a relative ``simulation.fmu`` is resolved.

    Returns
    -------
    Scenario

    Raises
    ------
    ScenarioError
        On the first problem found.
    """
    top = _Table(source, "", data)
    name = top.string("name", Path(source).stem if source != "<string>" else "scenario")
    description = top.string("description", "")

    # [simulation]
    s = _Table(source, "simulation", top.raw("simulation", {}))
    Te = s.number("Te", 1e-3, positive=True, what="generator sampling period in s")
    step = s.number("step", Te, positive=True, what="communication step in s")
    for k_, v_ in (("Te", Te), ("step", step)):
        if v_ > MAX_STEP:
            raise s.err(k_, v_, f"must be <= {MAX_STEP:g} s (MAX_STEP)")
    try:
        samples_per_step(step, Te, "generator")
    except ValueError:
        raise s.err("step", step, f"must be a whole multiple of Te = {Te:g} s") from None
    t_after = s.number("t_after", 3.0, nonneg=True, what="s after the motion")
    fmi_version = s.integer("fmi_version", 2, choices=(2, 3))
    fmu_raw = s.string("fmu", "")
    fmu = None
    if fmu_raw:
        fmu = Path(fmu_raw)
        if not fmu.is_absolute() and base_dir is not None:
            fmu = base_dir / fmu
        _check_fmu(source, "simulation.fmu", fmu)
    band = s.number("band", None, positive=True, what="settling band in m (old name of "
                    "settle_band)")
    settle_raw = s.raw("settle_band", None)
    if settle_raw is not None and band is not None:
        raise s.err("settle_band", settle_raw, f"give settle_band or its old name band "
                    f"(= {band:g}), not both")
    settle_band = DEFAULT_SETTLE_BAND if band is None else SettleBand("m", band)
    if settle_raw is not None:
        try:
            settle_band = parse_settle_band(settle_raw)
        except ValueError as e:
            raise s.err("settle_band", settle_raw, str(e)) from None
        # a band made of a profile's residual needs that profile (checked on the raw list:
        # a bad list is reported by [compare] below)
        listed = top.data.get("compare", {})
        listed = listed.get("profiles") if isinstance(listed, Mapping) else None
        if (settle_band.needs and isinstance(listed, list)
                and all(isinstance(p, str) for p in listed) and settle_band.needs not in listed):
            raise s.err("settle_band", settle_raw, f"needs the residual of {settle_band.needs}, "
                        f"which is not among compare.profiles = {listed!r}")
    short_stage = s.integer("short_stage", 2, choices=(1, 2))
    s.finish()
    sim = SimulationSpec(Te, step, t_after, fmi_version, fmu,
                         settle_band.value if settle_band.kind == "m" else None, short_stage,
                         settle_band)

    # [move]
    m = _Table(source, "move", top.raw("move", what="the excited axis' move ([move] table)"))
    distance = m.number("distance", what="signed move length in m", nonzero=True)
    v_max = m.number("v_max", what="velocity limit in m/s", positive=True)
    a_max = m.number("a_max", what="acceleration limit in m/s2", positive=True)
    d_max = m.number("d_max", a_max, positive=True, what="deceleration limit in m/s2")
    axis = m.string("axis", "X")
    x0 = m.number("x0", 0.0)
    t_start = m.number("t_start", 0.0, nonneg=True)
    m.finish()
    move = MoveSpec(distance, v_max, a_max, d_max, axis, x0, t_start)

    # [z]
    zt = _Table(source, "z", top.raw("z", {}))
    z = ZSpec(
        z0=zt.number("z0", 0.0),
        distance=zt.number("distance", 0.0),
        a_max=zt.number("a_max", 2.0, positive=True, what="m/s2"),
        v_max=zt.number("v_max", 1.0, positive=True, what="m/s"),
        T_F=zt.number("T_F", 0.05, nonneg=True, what="JL jerk time in s"),
        sync=zt.boolean("sync", True),
    )
    zt.finish()

    # [[mode]]
    modes_raw = top.raw("mode", what="at least one [[mode]] table")
    if not isinstance(modes_raw, list) or not modes_raw:
        raise ScenarioError(source, "mode", modes_raw, "needs at least one [[mode]] table")
    modes = tuple(_parse_mode(source, i + 1, md) for i, md in enumerate(modes_raw))

    # [compare]
    c = _Table(source, "compare", top.raw("compare", {}))
    profiles = c.raw("profiles", list(PROFILES))
    known = PROFILES + VARIANTS
    if (not isinstance(profiles, list) or not profiles
            or any(p not in known for p in profiles) or len(set(profiles)) != len(profiles)):
        raise c.err("profiles", profiles, f"must be a non-empty list of distinct names among "
                    f"{', '.join(known)}")
    tune_mode = c.integer("tune_mode", 1)
    if not 1 <= tune_mode <= len(modes):
        raise c.err("tune_mode", tune_mode, f"must be between 1 and {len(modes)} (the modes)")
    djl_rule = c.string("djl_rule", "start", choices=RULES)
    JL_T_F = c.number("JL_T_F", None, positive=True, what="JL jerk time in s")
    DJL_T_F = c.numbers("DJL_T_F", None, what="four DJL jerk times in s", min_len=4)
    if DJL_T_F is not None and (len(DJL_T_F) != 4 or not all(x > 0 for x in DJL_T_F)):
        raise c.err("DJL_T_F", list(DJL_T_F), "must hold four jerk times > 0 s")
    djl_tuning = c.string("djl_tuning", "paper", choices=DJL_METHODS)
    jl_tuning = c.string("jl_tuning", "end", choices=JL_METHODS)
    # deprecated aliases of [uncertainty] map_scale and damping (their earlier place)
    map_error = c.number("map_error", None, nonneg=True, what="relative map error, e.g. 0.1")
    if map_error is not None and not map_error < 1.0:
        raise c.err("map_error", map_error, "must be < 1 (a relative error of the map)")
    damping = c.numbers("damping", None, what="damping factors, e.g. [0.5, 1.0, 2.0]")
    if damping is not None and not all(x > 0 for x in damping):
        raise c.err("damping", list(damping), "damping factors must be > 0")
    mmt_raw = c.raw("max_motion_time", None)
    max_motion_time: float | str | None = None
    if mmt_raw is not None:
        if mmt_raw == "JL":
            max_motion_time = "JL"
        else:
            max_motion_time = c.number("max_motion_time", positive=True,
                                       what="a bound in s, or \"JL\"")
    period_band = c.number("period_band", 0.5, positive=True,
                           what="band around the local periods, a fraction")
    if period_band > 10.0:
        raise c.err("period_band", period_band, "must be <= 10")
    c.finish()
    compare = CompareSpec(tuple(profiles), djl_rule, JL_T_F, DJL_T_F, djl_tuning, jl_tuning,
                          max_motion_time, period_band)

    # [uncertainty], the one home of the map scale and the damping range; [compare]
    # map_error and damping, their earlier place, are read here once as its aliases
    u = _Table(source, "uncertainty", top.raw("uncertainty", {}))
    u_scale = u.number("map_scale", None, nonneg=True,
                       what="relative error of the whole map, e.g. 0.1")
    u_slope = u.number("map_slope", 0.0, nonneg=True,
                       what="relative error of the map's slope, e.g. 0.3")
    u_shift = u.number("z_shift", 0.0, nonneg=True, what="shift of the map along z in m")
    u_damp = u.numbers("damping", None, what="damping factor range [lo, hi], e.g. [0.5, 2.0]")
    u.finish()
    if u_damp is not None and len(u_damp) != 2:
        raise u.err("damping", list(u_damp), "must be two factors [lo, hi]")
    alias_damp = None if damping is None else (min(min(damping), 1.0), max(max(damping), 1.0))
    try:
        u_scale = resolve_alias(("uncertainty.map_scale", u_scale),
                                ("compare.map_error", map_error))
        u_damp = resolve_alias(("uncertainty.damping", u_damp),
                               (f"compare.damping {list(damping or ())!r} as a range",
                                alias_damp))
    except ValueError as e:
        raise ScenarioError(source, "", None, str(e)) from None
    for old_key, new_key, value in (("map_error", "map_scale", map_error),
                                    ("damping", "damping", alias_damp)):
        if value is not None:
            shown = f"{value!r}" if old_key == "map_error" else f"{list(value)!r}"
            warnings.warn(f"{source}: [compare] {old_key} is deprecated: write [uncertainty] "
                          f"{new_key} = {shown} instead (read as that)",
                          DeprecatedAliasWarning, stacklevel=2)
    try:
        uncertainty = UncertaintySpec(DEFAULT_UNCERTAINTY.map_scale if u_scale is None
                                      else u_scale, u_slope, u_shift,
                                      tuple(u_damp) if u_damp is not None else (1.0, 1.0))
    except ValueError as e:
        raise ScenarioError(source, "uncertainty", None, str(e)) from None

    # [sweep]
    sweep = None
    if "sweep" in top.data:
        w = _Table(source, "sweep", top.raw("sweep"))
        sd = w.numbers("distance", None, what="move lengths in m")
        sz = w.numbers("z_distance", None, what="Z move lengths in m")
        sv = w.numbers("v_max", None, what="velocity limits in m/s")
        w.finish()
        if sd and any(x == 0 for x in sd):
            raise w.err("distance", list(sd), "move lengths must not be 0")
        if sv and any(not x > 0 for x in sv):
            raise w.err("v_max", list(sv), "velocity limits must be > 0")
        if not (sd or sz or sv):
            raise ScenarioError(source, "sweep", {}, "give at least one of distance, "
                                "z_distance, v_max")
        sweep = SweepSpec(sd, sz, sv)

    # [map]
    wmap = None
    if "map" in top.data:
        mt = _Table(source, "map", top.raw("map"))
        m_z0 = mt.numbers("z0", None, what="Z start positions in m")
        m_dz = mt.numbers("z_distance", None, what="Z move lengths in m")
        m_d = mt.numbers("distance", None, what="move lengths in m")
        m_v = mt.numbers("v_max", None, what="velocity limits in m/s")
        mt.finish()
        for k, vals in (("z0", m_z0), ("z_distance", m_dz), ("distance", m_d), ("v_max", m_v)):
            if vals and len(set(vals)) != len(vals):
                raise mt.err(k, list(vals), "values must be distinct")
        if m_d and any(x == 0 for x in m_d):
            raise mt.err("distance", list(m_d), "move lengths must not be 0")
        if m_v and any(not x > 0 for x in m_v):
            raise mt.err("v_max", list(m_v), "velocity limits must be > 0")
        if not (m_z0 or m_dz or m_d or m_v):
            raise ScenarioError(source, "map", {}, "give at least one of z0, z_distance, "
                                "distance, v_max")
        wmap = MapSpec(m_z0, m_dz, m_d, m_v)
    top.finish()

    scen = Scenario(name, move, z, ModeMap(modes, tune_mode - 1), sim, compare, sweep,
                    description, source, wmap, uncertainty)
    _check_grids(scen)
    # the mode laws must be valid wherever Z goes, in every case
    for case in scen.cases():
        _check_z_range(source, modes, case.z.z0, case.z.distance)
    if wmap is not None:
        # once per distinct Z move of the grid (not per move: a map has 10^4 of them)
        z0s, dzs, _, _ = scen.map_axes()
        for z0_, dz_ in itertools.product(z0s, dzs):
            _check_z_range(source, modes, z0_, dz_, " in the [map] grid")
    _check_samples(scen)
    return scen


def _check_grids(scen: Scenario) -> None:
    """Refuse a ``[sweep]`` or ``[map]`` grid larger than the documented limits."""
    src = scen.source
    if scen.sweep is not None:
        sw = scen.sweep
        n = math.prod(len(x) for x in (sw.distance, sw.z_distance, sw.v_max) if x)
        if n > MAX_SWEEP_CASES:
            sizes = " x ".join(f"{len(x)} {k}" for k, x in (
                ("distance", sw.distance), ("z_distance", sw.z_distance), ("v_max", sw.v_max))
                if x)
            raise ScenarioError(src, "sweep", _Shown(sizes), f"{n} cases, more than the limit "
                                f"of {MAX_SWEEP_CASES} (MAX_SWEEP_CASES)")
    if scen.map is not None and scen.map_size > MAX_MAP_MOVES:
        raise ScenarioError(src, "map", _Shown(" x ".join(str(len(a)) for a in scen.map_axes())),
                            f"{scen.map_size} moves, more than the limit of {MAX_MAP_MOVES} "
                            f"(MAX_MAP_MOVES)")


def _check_samples(scen: Scenario) -> None:
    """Refuse, before running, a run longer than :data:`MAX_SAMPLES_PER_RUN` samples.

    The samples of a run are bounded from above cheaply: motion time <= t_start
    + |d|/v + v/a + v/d + four jerk times (imposed, or (1 + period_band) modal
    periods), the Z move likewise, plus ``t_after``, divided by ``Te`` -- with
    the worst values of the sweep/map lists.
    """
    src, sim, mv, zz, cmp = scen.source, scen.simulation, scen.move, scen.z, scen.compare
    # the worst values over the single move, the sweep and the map
    where = "move"
    ds, vs, z0s, dzs = [mv.distance], [mv.v_max], [zz.z0], [zz.distance]
    for tab, spec in (("sweep", scen.sweep), ("map", scen.map)):
        if spec is None:
            continue
        if spec.distance:
            ds += spec.distance
        if spec.v_max:
            vs += spec.v_max
            where = tab
        if spec.z_distance:
            dzs += spec.z_distance
        if getattr(spec, "z0", None):
            z0s += spec.z0
    d, v_lo, v_hi = max(abs(x) for x in ds), min(vs), max(vs)
    # jerk times: imposed, or tuned to the modal periods over the Z positions reached
    if cmp.DJL_T_F is not None or cmp.JL_T_F is not None:
        jerk = max(sum(cmp.DJL_T_F or ()), 4 * (cmp.JL_T_F or 0.0))
    else:
        zs = np.unique(np.add.outer(np.asarray(z0s), np.asarray([0.0, *dzs])))
        try:
            f_lo = float(np.min(scen.modemap.tuned.f_array(zs)))
        except Exception:  # noqa: BLE001 - a law outside its range: checked elsewhere
            f_lo = FREQUENCY_RANGE[0]
        jerk = 4 * (1.0 + cmp.period_band) / max(f_lo, 1e-300)
    t_x = mv.t_start + d / v_lo + v_hi / mv.a_max + v_hi / mv.d_max + jerk
    dz = max(abs(x) for x in dzs)
    t_z = (dz / zz.v_max + 2 * zz.v_max / zz.a_max + 2 * zz.T_F) if dz else 0.0
    motion = max(t_x, t_z)
    total = motion + sim.t_after + sim.step
    n = total / sim.Te
    if n <= MAX_SAMPLES_PER_RUN:
        return
    limit = f"more than the limit of {MAX_SAMPLES_PER_RUN:.0e} samples per run " \
            f"(MAX_SAMPLES_PER_RUN)"
    about = f"a run would simulate up to {total:.3g} s at Te = {sim.Te:g} s, {n:.3g} samples: "
    if total / 1e-3 <= MAX_SAMPLES_PER_RUN:
        raise ScenarioError(src, "simulation.Te", sim.Te, about + limit)
    if sim.t_after >= motion:
        raise ScenarioError(src, "simulation.t_after", sim.t_after, about + limit)
    if t_z > t_x:
        raise ScenarioError(src, "z.v_max", zz.v_max, f"a Z move of up to {t_z:.3g} s: "
                            + about + limit)
    if jerk > d / v_lo:
        key = "compare.DJL_T_F" if cmp.DJL_T_F else "compare.JL_T_F" if cmp.JL_T_F else \
            f"mode[{scen.modemap.tune + 1}].f"
        raise ScenarioError(src, key, _Shown(f"jerk times up to {jerk:.3g} s"),
                            about + limit)
    key, val = (f"{where}.v_max", v_lo) if where != "move" else ("move.v_max", mv.v_max)
    raise ScenarioError(src, key, val, f"a motion of up to {t_x:.3g} s (distance "
                        f"{d:g} m at {v_lo:g} m/s): " + about + limit)


def _check_z_range(source: str, modes: tuple[ModeSpec, ...], z0: float, dz: float,
                   where: str = "") -> None:
    """Raise :class:`ScenarioError` unless every mode law is valid from z0 to z0 + dz."""
    z_min, z_max = min(z0, z0 + dz), max(z0, z0 + dz)
    for i, md in enumerate(modes):
        try:
            md.check_range(z_min, z_max)
        except ValueError as e:
            key = f"mode[{i + 1}]." + ("z" if md.law.kind == "table" else
                                       "L_ref" if md.law.kind == "cantilever" else "f")
            raise ScenarioError(source, key, _law_value(md), f"{e} (Z moves from "
                                f"{z0:g} m by {dz:g} m{where})") from None


def _law_value(md: ModeSpec) -> Any:
    law = md.law
    if isinstance(law, TableLaw):
        return list(law.z)
    if isinstance(law, CantileverLaw):
        return law.L_ref
    if isinstance(law, LinearLaw):
        return list(law.f)
    return law.f


# ---------------------------------------------------------------- loading

_PACKAGE = "harness.scenarios"


def embedded_scenarios() -> dict[str, str]:
    """Names of the scenarios shipped with the package → their description."""
    out = {}
    for entry in sorted(resources.files(_PACKAGE).iterdir(), key=lambda p: p.name):
        if entry.name.endswith(".toml"):
            data = tomllib.loads(entry.read_text(encoding="utf-8"))
            out[data.get("name", entry.name[:-5])] = data.get("description", "")
    return out


DEFAULT_SCENARIOS = ("X", "Y", "sweep-X", "sweep-Y")
"""Embedded scenarios run by ``djl-fmu simulate`` without arguments."""


def load_scenario(spec: str | Path) -> Scenario:
    """Load and check a scenario: a TOML file, or the name of an embedded one.

    Parameters
    ----------
    spec : str or Path
        Path to a ``.toml`` file, or an embedded scenario name (see
        :func:`embedded_scenarios`: ``X``, ``Y``, ``sweep-X``, ``sweep-Y``).

    Returns
    -------
    Scenario

    Raises
    ------
    ScenarioError
        If the file is missing, is not valid TOML, or fails a check.
    """
    path = Path(spec)
    if path.is_file():
        try:
            text = path.read_text(encoding="utf-8")
        except OSError as e:
            raise ScenarioError(str(path), "", None, f"cannot read: {e}") from None
        except UnicodeDecodeError as e:
            raise ScenarioError(str(path), "", None, f"not UTF-8 text (byte {e.start}): a "
                                "scenario file must be UTF-8 TOML") from None
        try:
            data = tomllib.loads(text)
        except (tomllib.TOMLDecodeError, ValueError) as e:
            # ValueError: e.g. an integer beyond Python's int-string conversion limit
            raise ScenarioError(str(path), "", None, f"not valid TOML: {e}") from None
        return parse_scenario(data, str(path), path.parent)
    for entry in resources.files(_PACKAGE).iterdir():
        if entry.name.endswith(".toml"):
            data = tomllib.loads(entry.read_text(encoding="utf-8"))
            if str(data.get("name", "")).lower() == str(spec).lower():
                return parse_scenario(data, f"<embedded {data['name']}>")
    names = ", ".join(embedded_scenarios())
    raise ScenarioError(str(spec), "", None,
                        f"no such scenario file, and not an embedded scenario ({names})")
