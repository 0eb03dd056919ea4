"""Planning with the generator FMU: reusable instances, stage starts, Z synchronisation.

Creating a :class:`~harness.fmu.runner.GeneratorFMU` unzips the FMU and loads
its library (tens of milliseconds); re-planning an existing instance with
``fmiReset`` → parameters → initialisation costs tens of microseconds.  The
harness therefore keeps one instance per axis (:class:`AxisFMU`) and re-plans
it for every probe: the DJL tuning iterations, the synchronisation of the Z
move, and each profile of a scenario.

Every trajectory of the harness comes out of the generator FMU through fmpy:
nothing here re-implements the planner.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .fmu.runner import GeneratorFMU

__all__ = [
    "REQUIRED_VARIABLES",
    "AxisFMU",
    "MoveSamples",
    "check_fmu_binary",
    "check_fmu_variables",
    "stage_starts",
    "sync_z_velocity",
]

REQUIRED_VARIABLES = (
    # parameters the harness sets
    "profile", "Te", "t_start", "x0", "distance", "v_max", "a_max", "d_max",
    "T_F1", "T_F2", "T_F3", "T_F4", "short_stage",
    # outputs it reads
    "x", "v", "a", "j", "a_AL", "done",
    # calculated parameters it reads
    "motion_time", "N_F1", "N_F2", "N_F3", "N_F4",
)
"""Variables a generator FMU must have for the harness (FMI 2 or 3)."""

PROFILE_CODES = {"AL": 1, "JL": 2, "DJL": 3}
"""Value of the FMU's ``profile`` parameter for each profile name."""


def check_fmu_variables(path: str | Path) -> list[str]:
    """Names of :data:`REQUIRED_VARIABLES` missing from an FMU file.

    Parameters
    ----------
    path : path-like
        An ``.fmu`` file.

    Returns
    -------
    list of str
        Missing variable names (empty when the FMU is usable).

    Raises
    ------
    ValueError
        If the file cannot be read as an FMU, or would unpack to more than
        :data:`harness.fmu.runner.MAX_FMU_UNPACKED` bytes.
    """
    from fmpy import read_model_description

    from .fmu.runner import check_fmu_archive

    check_fmu_archive(path)
    try:
        md = read_model_description(str(path))
    except Exception as e:  # noqa: BLE001 - any failure means "not an FMU"
        raise ValueError(f"cannot read {path} as an FMU: {e}") from None
    names = {v.name for v in md.modelVariables}
    return [n for n in REQUIRED_VARIABLES if n not in names]


def check_fmu_binary(path: str | Path) -> None:
    """Check that an FMU file has a co-simulation binary for this platform that loads.

    Only the library is unpacked (into a temporary folder, removed), then
    loaded and unloaded.

    Raises
    ------
    ValueError
        Naming the file: no co-simulation interface, no binary for this
        platform, or a binary that cannot be loaded (corrupt, wrong architecture).
    """
    import ctypes
    import shutil
    import tempfile
    import zipfile

    import fmpy
    from fmpy import read_model_description

    from .fmu.runner import check_fmu_archive

    path = Path(path)
    check_fmu_archive(path)
    try:
        md = read_model_description(str(path))
    except Exception as e:  # noqa: BLE001
        raise ValueError(f"cannot read {path} as an FMU: {e}") from None
    cs = md.coSimulation
    if cs is None:
        raise ValueError(f"{path}: not a co-simulation FMU")
    plat = fmpy.platform_tuple if md.fmiVersion.startswith("3") else fmpy.platform
    member = f"binaries/{plat}/{cs.modelIdentifier}{fmpy.sharedLibraryExtension}"
    tmp = tempfile.mkdtemp(prefix="djl-fmu-check-")
    try:
        try:
            with zipfile.ZipFile(path) as z:
                if member not in z.namelist():
                    raise ValueError(f"{path}: the FMU has no binary for this platform "
                                     f"({member}); rebuild it here (e.g. fmpy compile)")
                lib = Path(z.extract(member, tmp))
        except (zipfile.BadZipFile, OSError, RuntimeError) as e:
            raise ValueError(f"{path}: cannot unpack {member}: {e}") from None
        try:
            handle = ctypes.CDLL(str(lib))
        except OSError as e:
            raise ValueError(f"{path}: the FMU's binary {member} cannot be loaded: "
                             f"{str(e).replace(str(lib) + ': ', '')}") from None
        try:
            fmpy.freeLibrary(ctypes.c_void_p(handle._handle))
        except Exception:  # noqa: BLE001
            pass
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


@dataclass
class MoveSamples:
    """One planned move sampled at every generator sample.

    Attributes
    ----------
    t : ndarray
        Time (s).
    x, v, a, j : ndarray
        Reference position (m), velocity (m/s), acceleration (m/s²), jerk over
        the interval that starts at each sample (m/s³).
    a_AL : ndarray
        The adapted acceleration-limited profile before the FIR filters (m/s²):
        its steps are the starts of the constant-jerk stages.
    motion_time : float
        Duration of the move (s), filters included.
    N_F : tuple of int
        Jerk times applied by the FMU (samples).
    t_start : float
        Start of the move (s).
    """

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray
    a_AL: np.ndarray
    motion_time: float
    N_F: tuple[int, int, int, int]
    t_start: float

    @property
    def t_end(self) -> float:
        """End of the move (s)."""
        return self.t_start + self.motion_time

    def position_at(self, t: float) -> float:
        """Exact reference position at time ``t`` (piecewise-cubic evaluation)."""
        Te = float(self.t[1] - self.t[0])
        k = int(math.floor((t - self.t[0]) / Te + 1e-9))
        k = min(max(k, 0), self.t.size - 1)
        tau = t - self.t[k]
        return float(self.x[k] + self.v[k] * tau + self.a[k] * tau**2 / 2
                     + self.j[k] * tau**3 / 6)


class AxisFMU:
    """A generator FMU instance that is re-planned (reset) rather than re-created.

    Parameters
    ----------
    fmu : path-like, optional
        Generator FMU file; default: the package's own build for ``fmi_version``.
    fmi_version : {2, 3}
        FMU version when ``fmu`` is not given.
    name : str
        Instance name.
    """

    def __init__(self, fmu: str | Path | None = None, *, fmi_version: int = 2,
                 name: str = "axis") -> None:
        self.g = GeneratorFMU(fmu, fmi_version=fmi_version, instance_name=name)
        self._fresh = True
        self.params: dict[str, Any] = {}
        self.start_time = 0.0

    @property
    def fmi_version(self) -> int:
        """FMI version of the FMU (2 or 3)."""
        return self.g.fmi_version

    def plan(self, params: Mapping[str, Any], start_time: float = 0.0) -> float:
        """Reset the instance, set ``params``, initialise; return the motion time (s).

        Parameters not given take the FMU's start values.
        """
        g = self.g
        if self._fresh:
            if start_time != g.start_time:
                raise ValueError("the first plan must use the instance's start time")
            g.set(params)
            g.initialize()
        else:
            g.replan(params, start_time)
        self._fresh = False
        self.start_time = start_time
        self.params = dict(params)
        return float(g.get("motion_time"))

    def get(self, name: str) -> Any:
        """Value of one FMU variable."""
        return self.g.get(name)

    def N_F(self) -> tuple[int, int, int, int]:
        """Jerk times applied by the FMU (samples)."""
        return tuple(int(self.g.get(f"N_F{i}")) for i in range(1, 5))  # type: ignore[return-value]

    def sample(self, params: Mapping[str, Any], t_stop: float | None = None,
               start_time: float = 0.0) -> MoveSamples:
        """Plan and run a move at every generator sample.

        Parameters
        ----------
        params : mapping
            FMU parameters.
        t_stop : float, optional
            Last sample time; default: the end of the move.
        start_time : float
            Start time of the FMU.

        Returns
        -------
        MoveSamples
        """
        motion_time = self.plan(params, start_time)
        g = self.g
        Te = float(g.get("Te"))
        t_start = float(g.get("t_start"))
        if t_stop is None:
            t_stop = max(g.motion_start(), start_time) + motion_time
        n = int(round((t_stop - start_time) / Te))
        t, v = g.record(n, Te, ("x", "v", "a", "j", "a_AL"))
        return MoveSamples(t, v["x"], v["v"], v["a"], v["j"], v["a_AL"], motion_time,
                           self.N_F(), t_start)

    def close(self) -> None:
        """Free the FMU instance."""
        self.g.close()

    def __enter__(self) -> AxisFMU:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def stage_starts(move: MoveSamples) -> tuple[list[float], bool]:
    """Start times of the four constant-jerk stages of a rest-to-rest move.

    The FMU's ``a_AL`` output is the adapted acceleration-limited profile
    before the FIR filters; each of its steps starts one filtered ramp, i.e.
    one constant-jerk stage (§2.3, Fig. 7: steps at 0, T_1, T_2, T_3).  This
    holds also when ramps overlap (``short_stage = 2``), where the jerk output
    alone would be ambiguous.

    Parameters
    ----------
    move : MoveSamples
        A single-segment rest-to-rest move (JL or DJL).

    Returns
    -------
    starts : list of float
        Start times (s) of stages 1..4.
    merged : bool
        True when there is no constant-velocity stage: stage 3 starts exactly
        when stage 2 ends, so the two middle stages form one constant-jerk
        stage (§4: "the two intermediate jerk stages are combined with the
        same jerk-time").

    Raises
    ------
    ValueError
        If the move does not show the four steps of a single rest-to-rest move.
    """
    a = np.concatenate(([0.0], move.a_AL))
    k = np.flatnonzero(np.diff(a) != 0.0)
    times = move.t[k]
    levels = a[k + 1]
    # a direct jump from acceleration to deceleration starts stages 2 and 3 together
    starts: list[float] = []
    prev = 0.0
    for tk, lv in zip(times.tolist(), levels.tolist(), strict=True):
        if prev > 0.0 > lv or prev < 0.0 < lv:
            starts += [tk, tk]
        else:
            starts.append(tk)
        prev = lv
    if len(starts) != 4:
        raise ValueError(f"expected the 4 stages of a rest-to-rest move, found steps of a_AL "
                         f"at {times.tolist()}")
    Te = float(move.t[1] - move.t[0])
    merged = abs(starts[2] - (starts[1] + move.N_F[1] * Te)) < 0.5 * Te or starts[1] == starts[2]
    return starts, merged


def sync_z_velocity(
    axis: Any,
    params: Mapping[str, Any],
    target_time: float,
    v_cap: float,
    start_time: float = 0.0,
) -> tuple[float, float, bool]:
    """Velocity limit that makes a move last ``target_time`` (not longer).

    Bisection on ``v_max`` with the FMU's own planner (its ``motion_time``),
    so that the Z move, started with the excited axis, ends with it: the
    smallest velocity whose motion time is ≤ ``target_time``.

    Parameters
    ----------
    axis : AxisFMU or harness.engine.FastAxis
        The instance to plan with (it is left planned with the result); a
        :class:`~harness.engine.FastAxis` runs the same bisection compiled.
    params : mapping
        The Z move's parameters except ``v_max``.
    target_time : float
        Motion time to match (s).
    v_cap : float
        Largest velocity allowed (m/s).
    start_time : float
        FMU start time.

    Returns
    -------
    v_max : float
        The velocity limit (m/s).
    motion_time : float
        The resulting motion time (s).
    synced : bool
        False when even ``v_cap`` is too slow (the Z move then ends later).
    """
    if hasattr(axis, "sync_velocity"):  # the fast engine: the same bisection, compiled
        return axis.sync_velocity(params, target_time, v_cap, start_time)
    p = dict(params)
    d = abs(float(p["distance"]))

    def time_at(v: float) -> float:
        p["v_max"] = v
        return axis.plan(p, start_time)

    t_cap = time_at(v_cap)
    if t_cap > target_time:
        return v_cap, t_cap, False
    lo = min(d / target_time, v_cap)  # too slow: the move lasts more than d / v
    if time_at(lo) <= target_time:
        return lo, axis.plan(p, start_time), True
    hi = v_cap
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if time_at(mid) <= target_time:
            hi = mid
        else:
            lo = mid
        if hi - lo <= 1e-9 * hi:
            break
    t = time_at(hi)
    return hi, t, True
