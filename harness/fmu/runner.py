"""Step the generator FMU from Python (fmpy), FMI 2.0 or 3.0 alike.

:class:`GeneratorFMU` is one instance stepped by hand (for co-simulation
masters); :func:`generate` runs a whole motion and returns a
:class:`Trajectory`.

Examples
--------
>>> from harness.fmu.runner import generate
>>> traj = generate({"profile": 2, "distance": 0.3, "T_F1": 0.05})  # doctest: +SKIP
>>> traj.x[-1]                                                      # doctest: +SKIP
0.3
"""

from __future__ import annotations

import ctypes
import math
import shutil
import tempfile
import weakref
import zipfile
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import HarnessError
from ..figures import legend_above_data
from . import spec
from .build import default_fmu

REAL_OUTPUTS = ("x", "v", "a", "j", "x_AL", "v_AL", "a_AL")
"""Real outputs recorded by :func:`generate`, in this order."""

ParamValue = float | int | bool | Sequence[float]


class FMUError(HarnessError, RuntimeError):
    """An FMI call returned an error; carries the FMU's log messages.

    Attributes
    ----------
    function : str
        The FMI function that failed.
    status : int
        Its FMI status (3 = error, 4 = fatal).
    log : list of LogRecord
        What the FMU logged up to the failure (the last error explains it).
    variable : str or None
        The variable being set when the call failed (:meth:`GeneratorFMU.set_inputs`),
        named in the message with its value; None otherwise.
    """

    def __init__(self, function: str, status: int, log: list[LogRecord], *,
                 variable: str | None = None, value: Any = None) -> None:
        self.function = function
        self.status = status
        self.log = list(log)
        self.variable = variable
        errors = [r.message for r in log if r.status >= 3]
        detail = errors[-1] if errors else "no message logged"
        what = f" setting {variable} = {value!r}" if variable is not None else ""
        super().__init__(f"{function} failed with status {status}{what}: {detail}")


@dataclass
class LogRecord:
    """One message logged by the FMU."""

    status: int
    category: str
    message: str

    def __str__(self) -> str:
        label = ["OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING"][self.status]
        return f"[{label}] {self.category}: {self.message}"


MAX_FMU_UNPACKED = 256 * 2**20
"""Largest unpacked size of an FMU file (bytes, the sum of its zip entries' declared
sizes): a larger one is refused before anything is unpacked."""

MAX_FMU_ENTRIES = 10_000
"""Largest number of files in an FMU."""


def check_fmu_archive(path: str | Path) -> None:
    """Check that ``path`` is a zip file small enough to unpack (without unpacking it).

    Raises
    ------
    ValueError
        Naming the file: not a file, not a zip archive, more than
        :data:`MAX_FMU_ENTRIES` files, an unsafe member name, or a declared
        unpacked size above :data:`MAX_FMU_UNPACKED`.
    """
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such FMU file")
    try:
        with zipfile.ZipFile(path) as z:
            infos = z.infolist()
    except (zipfile.BadZipFile, OSError, ValueError) as e:
        raise ValueError(f"cannot read {path} as an FMU: not a zip archive ({e})") from None
    if len(infos) > MAX_FMU_ENTRIES:
        raise ValueError(f"{path}: the FMU holds {len(infos)} files, more than the limit of "
                         f"{MAX_FMU_ENTRIES}")
    total = sum(i.file_size for i in infos)
    if total > MAX_FMU_UNPACKED:
        raise ValueError(f"{path}: the FMU would unpack to {total / 2**20:.0f} MiB, more than "
                         f"the limit of {MAX_FMU_UNPACKED // 2**20} MiB (MAX_FMU_UNPACKED)")
    for i in infos:
        name = i.filename
        if name.startswith(("/", "\\")) or ".." in Path(name).parts or ":" in name:
            raise ValueError(f"{path}: unsafe file name in the FMU: {name!r}")


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
    from fmpy import read_model_description  # deferred: fmpy is heavy to import

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
    import fmpy  # deferred: fmpy is heavy to import
    from fmpy import read_model_description  # deferred: fmpy is heavy to import

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


def _read_fmu(path: Path) -> Any:
    """Check the archive and read its model description; ``ValueError`` naming the file."""
    from fmpy import read_model_description  # deferred: fmpy is heavy to import

    check_fmu_archive(path)
    try:
        return read_model_description(str(path))
    except Exception as e:  # noqa: BLE001 - any failure means "not an FMU"
        raise ValueError(f"{path}: cannot read the FMU's model description: {e}") from None


class GeneratorFMU:
    """One instance of the generator FMU, stepped through fmpy.

    Parameters
    ----------
    fmu : path-like, optional
        An ``.fmu`` file with the generator's variables; by default the FMU
        built from this package's sources (cached, see
        :func:`harness.fmu.build.default_fmu`).
    fmi_version : {2, 3}
        Which FMU to build when ``fmu`` is not given.
    params : mapping, optional
        Parameter values by FMU variable name (``seg_distance`` and
        ``seg_v_end`` take sequences).
    start_time : float
        FMU start time (s).
    instance_name : str
        Instance name passed to the FMU (appears in its log messages).
    debug_logging : bool
        Ask the FMU for event and warning messages too (errors always come).
    echo : bool
        Print log messages as they come (they are also kept in :attr:`log`).

    Notes
    -----
    The FMU is unzipped once per instance into a temporary directory that
    :meth:`close` removes.  Use it as a context manager.
    """

    def __init__(
        self,
        fmu: str | Path | None = None,
        *,
        fmi_version: int = 2,
        params: Mapping[str, ParamValue] | None = None,
        start_time: float = 0.0,
        instance_name: str = "generator",
        debug_logging: bool = False,
        echo: bool = False,
    ) -> None:
        from fmpy import extract  # deferred: fmpy is heavy to import

        if fmu is None:
            fmu = default_fmu(fmi_version)
        self.path = Path(fmu)
        self.log: list[LogRecord] = []
        self._echo = echo
        self._closed = False
        self._initialized = False
        self.fmu: Any = None
        md = _read_fmu(self.path)
        self.md = md
        self.fmi_version = 3 if self.md.fmiVersion.startswith("3") else 2
        self._vars = {v.name: v for v in self.md.modelVariables}
        missing = [n for n in ("x", "v", "a", "j", "done", "Te", "profile") if n not in self._vars]
        if missing:
            raise ValueError(f"{self.path}: not a generator FMU, variables missing: {missing}")
        # the unzipped copy is removed by close(), on any failure below, and (as a last
        # resort) when the object is garbage-collected or the interpreter exits
        self._tmp = tempfile.mkdtemp(prefix="djl-fmu-")
        self._finalizer = weakref.finalize(self, shutil.rmtree, self._tmp, ignore_errors=True)
        try:
            self._unzipped = extract(str(self.path), unzipdir=self._tmp)
            self._check_binary()
            self.time = float(start_time)
            self._instantiate(instance_name, debug_logging)
            self.instance_name = instance_name
            self.start_time = float(start_time)
            self._setup()
            if params:
                self.set(params)
        except BaseException:
            try:
                self.close()
            except Exception:  # noqa: BLE001 - report the first error, not this one
                pass
            raise

    def _check_binary(self) -> None:
        """Raise ``ValueError`` unless the FMU has a binary for this platform that loads."""
        import fmpy  # deferred: fmpy is heavy to import

        cs = self.md.coSimulation
        if cs is None:
            raise ValueError(f"{self.path}: not a co-simulation FMU")
        plat = fmpy.platform if self.fmi_version == 2 else fmpy.platform_tuple
        lib = (Path(self._unzipped) / "binaries" / plat
               / (cs.modelIdentifier + fmpy.sharedLibraryExtension))
        if not lib.is_file():
            raise ValueError(f"{self.path}: the FMU has no binary for this platform "
                             f"(binaries/{plat}/{lib.name})")
        try:
            handle = ctypes.CDLL(str(lib))
        except OSError as e:
            raise ValueError(f"{self.path}: the FMU's binary binaries/{plat}/{lib.name} cannot "
                             f"be loaded: {str(e).replace(str(lib) + ': ', '')}") from None
        try:
            from fmpy import freeLibrary  # deferred: fmpy is heavy to import

            freeLibrary(ctypes.c_void_p(handle._handle))
        except Exception:  # noqa: BLE001
            pass

    # ------------------------------------------------------------- plumbing

    def _record(self, status: int, category: bytes | None, message: bytes | None) -> None:
        rec = LogRecord(int(status), (category or b"").decode("utf-8", "replace"),
                        (message or b"").decode("utf-8", "replace"))
        self.log.append(rec)
        if self._echo:
            print(f"{self.path.name}: {rec}")

    def _instantiate(self, name: str, debug_logging: bool) -> None:
        cs = self.md.coSimulation
        if cs is None:
            raise ValueError(f"{self.path}: not a co-simulation FMU")
        if self.fmi_version == 2:
            from fmpy import calloc, free  # deferred: fmpy is heavy to import
            from fmpy.fmi2 import (  # deferred: fmpy is heavy to import
                FMU2Slave,
                fmi2CallbackAllocateMemoryTYPE,
                fmi2CallbackFreeMemoryTYPE,
                fmi2CallbackFunctions,
                fmi2CallbackLoggerTYPE,
            )

            self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self._unzipped,
                                 modelIdentifier=cs.modelIdentifier, instanceName=name)
            cb = fmi2CallbackFunctions()

            def logger(env, instance, status, category, message):  # noqa: ARG001
                self._record(status, category, message)

            cb.logger = fmi2CallbackLoggerTYPE(logger)
            cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
            self._callbacks = cb  # keep alive
            self.fmu.instantiate(callbacks=cb, loggingOn=debug_logging)
        else:
            from fmpy.fmi3 import FMU3Slave  # deferred: fmpy is heavy to import

            self.fmu = FMU3Slave(guid=self.md.guid, unzipDirectory=self._unzipped,
                                 modelIdentifier=cs.modelIdentifier, instanceName=name)

            def log_message(env, status, category, message):  # noqa: ARG001
                self._record(status, category, message)

            self._log_message = log_message
            self.fmu.instantiate(loggingOn=debug_logging, logMessage=log_message)

    def _setup(self) -> None:
        if self.fmi_version == 2:
            self._call(self.fmu.setupExperiment, startTime=self.start_time)

    def _call(self, fn: Any, *args: Any, **kwargs: Any) -> Any:
        """Call an fmpy method; turn an FMI error into :class:`FMUError` with the log."""
        from fmpy.fmi1 import FMICallException  # deferred: fmpy is heavy to import

        try:
            return fn(*args, **kwargs)
        except FMICallException as e:
            raise FMUError(str(getattr(e, "function", fn.__name__)), int(e.status),
                           self.log) from None

    def variable(self, name: str) -> Any:
        """Fmpy's description of the variable ``name``."""
        try:
            return self._vars[name]
        except KeyError:
            raise KeyError(f"{self.path.name} has no variable {name!r}") from None

    # ------------------------------------------------------------ values

    def _elements(self, name: str) -> list[Any]:
        """FMI 2: the scalar variables of ``name`` (arrays are unrolled)."""
        if name in self._vars:
            return [self._vars[name]]
        els = [v for n, v in self._vars.items() if n.startswith(name + "[")]
        if not els:
            raise KeyError(f"{self.path.name} has no variable {name!r}")
        return sorted(els, key=lambda v: v.valueReference)

    def set(self, params: Mapping[str, ParamValue]) -> None:
        """Set parameters by name (before :meth:`initialize`).

        Values are checked against the variable's type before anything is set:
        an Integer/Int32 or Enumeration variable (``profile``, ``short_stage``, ``n_segments``,
        the elements of ``table_samples``) takes an int (a float, even 2.0, is refused: never
        truncated or taken for an integer), a Real/Float64 a number, a Boolean a bool; a bool
        is never taken for a number.  An array parameter (``seg_distance``, ``shaper_delay``,
        ``table_jerk``, ...) takes a sequence of at most its size, the same in FMI 2 (its
        elements ``name[i]``) and FMI 3 (one array variable): the elements not given take the
        parameter's start value.

        Raises
        ------
        TypeError
            A value of the wrong type (the message names the variable).
        ValueError
            An integer out of the Int32 range, or more values than an array holds.
        KeyError
            An unknown variable.
        """
        todo = []
        for name, value in params.items():
            if self.fmi_version == 3:
                var = self.variable(name)
                vals = _as_list(name, value) if var.dimensions else [value]
                size = int(var.dimensions[0].start) if var.dimensions else 1
                vrs, typ = [var.valueReference], var.type
            else:
                els = self._elements(name)
                vals = _as_list(name, value) if len(els) > 1 else [value]
                size = len(els)
                vrs, typ = [e.valueReference for e in els], els[0].type
            kind = {"Float64": "Real", "Real": "Real", "Int32": "Integer",
                    "Integer": "Integer", "Boolean": "Boolean",
                    "Enumeration": "Integer"}.get(typ)
            if kind is None:
                raise TypeError(f"{name}: unsupported type {typ}")
            if size > 1:  # an array: the elements not given take its start value
                if len(vals) > size:
                    raise ValueError(f"{name}: {len(vals)} values, the array holds {size}")
                vals = vals + [_array_pad(name, kind)] * (size - len(vals))
            todo.append((kind, typ, vrs, [_convert(name, kind, x) for x in vals]))
        for kind, typ, vrs, vals in todo:
            if self.fmi_version == 3:
                # FMI 3 accesses an Enumeration as Int64
                fn = {"Real": self.fmu.setFloat64,
                      "Integer": self.fmu.setInt64 if typ == "Enumeration" else self.fmu.setInt32,
                      "Boolean": self.fmu.setBoolean}[kind]
            else:
                fn = {"Real": self.fmu.setReal, "Integer": self.fmu.setInteger,
                      "Boolean": self.fmu.setBoolean}[kind]
            self._call(fn, vrs, vals)

    def set_inputs(self, *, target: float | None = None, execute: bool | None = None,
                   stop: bool | None = None, f_mode: float | None = None) -> None:
        """Set the commanded inputs; the next :meth:`do_step` reads them.

        Only the inputs given are set; the others keep their values.  The FMU
        reads them at its next ``doStep``: a rising edge of ``execute`` (against
        the value seen at the previous ``doStep``) moves from the current state
        to ``target``, ending at rest; a rising edge of ``stop`` brings the axis
        to rest (stop wins over execute at the same step); ``f_mode`` (Hz) gives
        the jerk time of each constant-jerk stage when ``jerk_source = 2`` (``3``: extrapolated
        to the stages to come) and times the impulses when ``shaper_source = 2``.  A
        command takes effect at the first generator sample at or after the
        current time.  Setting ``execute=True`` twice without a ``False`` in
        between is no new edge: send ``execute=False`` at a later step first.

        Parameters
        ----------
        target : float, optional
            Absolute target position of the next ``execute`` (m).
        execute : bool, optional
            Move to ``target`` on a rising edge.
        stop : bool, optional
            Come to rest on a rising edge.
        f_mode : float, optional
            Mode frequency (Hz), used when ``jerk_source`` is 2 or 3 or ``shaper_source``
            is 2.

        Raises
        ------
        TypeError
            A Boolean input given anything but a bool (``1`` is refused), a Real
            input given a bool or a non-number; nothing is set then.
        KeyError
            The FMU has no such input (an FMU without the commanded interface).
        FMUError
            The FMU refused a value (NaN or infinite ``f_mode``, ``f_mode`` <= 0):
            the message names the input and the value, the FMU keeps its previous
            value and stays usable.  The inputs are set in the order target, f_mode,
            stop, execute; those before the refused one are set.  A ``target`` is
            always taken (issue 34): an ``execute`` to one that is not finite or
            beyond 1e300 m is refused by the next ``do_step``, which returns OK and
            sets the outputs ``cmd_error`` and ``cmd_error_id``
            (docs/generator.md, "Command errors").
        """
        given = [(name, kind, value) for name, kind, value in (
            ("target", "Real", target), ("f_mode", "Real", f_mode),
            ("stop", "Boolean", stop), ("execute", "Boolean", execute)) if value is not None]
        todo = []
        for name, kind, value in given:  # check every value before setting any
            var = self.variable(name)
            if var.causality != "input":
                raise KeyError(f"{self.path.name}: {name!r} is not an input of this FMU")
            todo.append((name, kind, var.valueReference, _convert(name, kind, value), value))
        from fmpy.fmi1 import FMICallException  # deferred: fmpy is heavy to import

        for name, kind, vr, converted, value in todo:
            if kind == "Real":
                fn = self.fmu.setFloat64 if self.fmi_version == 3 else self.fmu.setReal
            else:
                fn = self.fmu.setBoolean
            try:
                fn([vr], [converted])
            except FMICallException as e:
                raise FMUError(str(getattr(e, "function", fn.__name__)), int(e.status),
                               self.log, variable=name, value=value) from None

    def get(self, name: str) -> Any:
        """Value of one variable (arrays come back as numpy arrays)."""
        if self.fmi_version == 3:
            var = self.variable(name)
            vr = [var.valueReference]
            n = int(var.dimensions[0].start) if var.dimensions else 1
            if var.type == "Float64":
                vals = self._call(self.fmu.getFloat64, vr, n)
            elif var.type == "Int32":
                vals = self._call(self.fmu.getInt32, vr, n)
            elif var.type == "Enumeration":
                vals = self._call(self.fmu.getInt64, vr, n)
            else:
                vals = self._call(self.fmu.getBoolean, vr, n)
            return np.array(vals) if var.dimensions else vals[0]
        els = self._elements(name)
        vrs = [e.valueReference for e in els]
        typ = els[0].type
        get = (self.fmu.getReal if typ == "Real" else
               self.fmu.getInteger if typ in ("Integer", "Enumeration") else self.fmu.getBoolean)
        vals = self._call(get, vrs)
        return np.array(vals) if len(els) > 1 else vals[0]

    def vr(self, names: Iterable[str]) -> list[int]:
        """Value references of scalar variables."""
        return [self.variable(n).valueReference for n in names]

    def get_reals(self, vrs: Sequence[int]) -> list[float]:
        """Fast path: Real/Float64 scalars by value reference."""
        return self.fmu.getFloat64(vrs) if self.fmi_version == 3 else self.fmu.getReal(vrs)

    # --------------------------------------------------------- life cycle

    def initialize(self) -> None:
        """Enter and exit initialization mode (parameters are then fixed)."""
        if self.fmi_version == 2:
            self._call(self.fmu.enterInitializationMode)
        else:
            self._call(self.fmu.enterInitializationMode, startTime=self.start_time)
        self._initialized = True
        self._call(self.fmu.exitInitializationMode)

    def replan(self, params: Mapping[str, ParamValue] | None = None,
               start_time: float | None = None) -> None:
        """Reset the instance, set ``params`` (the rest at start values) and initialise again.

        Re-planning an instance costs tens of microseconds, against tens of
        milliseconds to create one (unzip and load): use it for parameter sweeps.

        Parameters
        ----------
        params : mapping, optional
            Parameters by name.
        start_time : float, optional
            New FMU start time (default: keep the current one).
        """
        if start_time is not None:
            self.start_time = float(start_time)
        self._call(self.fmu.reset)
        self._initialized = False
        self.time = self.start_time
        self._setup()
        if params:
            self.set(params)
        self.initialize()

    def motion_start(self) -> float:
        """Time of the generator sample at which the motion starts (see :func:`motion_start`)."""
        return motion_start(float(self.get("t_start")), self.start_time, float(self.get("Te")))

    def do_step(self, h: float) -> None:
        """Advance the FMU by ``h`` > 0 seconds (any step: the profile's values then)."""
        self._call(self.fmu.doStep, currentCommunicationPoint=self.time, communicationStepSize=h)
        self.time += h

    def record(self, n: int, h: float, reals: Sequence[str], flags: Sequence[str] = (), *,
               inputs: Callable[[int], Mapping[str, Any]] | None = None,
               stop: Callable[[int, Mapping[str, np.ndarray]], int | None] | None = None
               ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """Read the outputs now, then after each of ``n`` steps of ``h``.

        The one stepping loop of the harness: every FMU run (a move, a
        co-simulation's axis, the online f_mode run) goes through it.

        Parameters
        ----------
        n : int
            Number of communication steps (with ``stop``: at most).
        h : float
            Communication step (s), any value > 0.
        reals : sequence of str
            Real outputs to record.
        flags : sequence of str
            Boolean or Integer outputs to record (``done``, ``segment``, ``stage``).
        inputs : callable, optional
            ``inputs(k)`` -> {input name: value}, set (:meth:`set_inputs`) before
            the step from point k.
        stop : callable, optional
            ``stop(k, values)`` after the step to point k, ``values`` the
            outputs recorded up to it: the total number of steps once known
            (None until then); the run ends there, or after ``n`` steps.

        Returns
        -------
        t : ndarray
            The communication points reached (n + 1 without ``stop``).
        values : dict of ndarray
            One array per name, a value per point.

        Raises
        ------
        FMUError
            An FMI call failed, or the FMU refused an input (named).
        """
        vrs = self.vr(reals)
        getters = []
        for name in flags:
            var = self.variable(name)
            get = self.fmu.getBoolean if var.type == "Boolean" else (
                self.fmu.getInt32 if self.fmi_version == 3 else self.fmu.getInteger)
            getters.append((name, get, [var.valueReference]))
        rows = np.empty((n + 1, len(vrs)))
        other = {name: np.empty(n + 1, dtype=np.int64) for name in flags}
        t = self.time + h * np.arange(n + 1)
        step, get_reals = self.fmu.doStep, self.get_reals
        from fmpy.fmi1 import FMICallException  # deferred: fmpy is heavy to import

        def view(m: int) -> dict[str, np.ndarray]:
            out = {name: rows[:m, i] for i, name in enumerate(reals)}
            out.update({name: v[:m] for name, v in other.items()})
            return out

        end = None if stop is not None else n
        k = 0
        try:
            while True:
                if k:
                    step(currentCommunicationPoint=t[k - 1], communicationStepSize=h)
                rows[k] = get_reals(vrs)
                for name, get, vr in getters:
                    other[name][k] = get(vr)[0]
                if k and end is None:
                    end = stop(k, view(k + 1))  # type: ignore[misc]
                    if end is not None and not k <= end <= n:
                        raise ValueError(f"stop returned {end} steps at step {k} (at most {n})")
                if k >= (n if end is None else end):
                    break
                if inputs is not None:
                    self.set_inputs(**inputs(k))
                k += 1
        except FMICallException as e:
            raise FMUError(str(getattr(e, "function", "doStep")), int(e.status),
                           self.log) from None
        self.time = float(t[k])
        values = view(k + 1)
        values = {name: v.copy() for name, v in values.items()}
        return t[: k + 1].copy(), values

    def get_state(self) -> Any:
        """Opaque FMU state (free it with :meth:`free_state`)."""
        return self.fmu.getFMUState() if self.fmi_version == 3 else self.fmu.getFMUstate()

    def set_state(self, state: Any, time: float) -> None:
        """Restore an FMU state taken at ``time``."""
        if self.fmi_version == 3:
            self.fmu.setFMUState(state)
        else:
            self.fmu.setFMUstate(state)
        self.time = time

    def free_state(self, state: Any) -> None:
        """Release a state from :meth:`get_state`."""
        if self.fmi_version == 3:
            self.fmu.freeFMUState(state)
        else:
            self.fmu.freeFMUstate(state)

    def serialize_state(self, state: Any) -> bytes:
        """Bytes of a state."""
        if self.fmi_version == 3:
            return bytes(self.fmu.serializeFMUState(state))
        return bytes(self.fmu.serializeFMUstate(state))

    def deserialize_state(self, data: bytes) -> Any:
        """State from :meth:`serialize_state` bytes."""
        if self.fmi_version == 3:
            return self.fmu.deserializeFMUState(bytes(data))
        return self.fmu.deSerializeFMUstate(bytes(data))

    def close(self) -> None:
        """Terminate (when stepping), free the instance, remove the unzipped FMU."""
        if self._closed:
            return
        self._closed = True
        finalizer = getattr(self, "_finalizer", None)
        if self.fmu is None:  # the constructor failed before the instance existed
            if finalizer is not None:
                finalizer()
            return
        try:
            if getattr(self.fmu, "component", None):
                if self._initialized:
                    try:
                        self.fmu.terminate()
                    except Exception:  # noqa: BLE001 - already in error: still free it
                        pass
                self.fmu.freeInstance()
        finally:
            try:
                from fmpy import freeLibrary  # deferred: fmpy is heavy to import

                freeLibrary(ctypes.c_void_p(self.fmu.dll._handle))
            except Exception:  # noqa: BLE001
                pass
            if finalizer is not None:
                finalizer()

    def __enter__(self) -> GeneratorFMU:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _as_list(name: str, value: Any) -> list[Any]:
    """Return the elements of an array parameter's value (a scalar is one element)."""
    if isinstance(value, (str, bytes)) or isinstance(value, Mapping):
        raise TypeError(f"{name}: expected a number or a sequence of numbers, got {value!r}")
    try:
        return list(np.atleast_1d(np.asarray(value, dtype=object)).ravel())
    except Exception as e:  # noqa: BLE001
        raise TypeError(f"{name}: expected a sequence of numbers, got {value!r}") from e


def _array_pad(name: str, kind: str) -> Any:
    """Value of the elements of array parameter ``name`` that a caller leaves out.

    The parameter's start value (:mod:`harness.fmu.spec`) when it is of ``kind``: ``1`` for
    ``table_samples``, ``0.0`` for the Real arrays; else 0 of the kind.
    """
    var = spec.BY_NAME.get(name)
    start = var.start if var is not None else None
    if kind == "Integer":
        return int(start) if isinstance(start, int) and not isinstance(start, bool) else 0
    return float(start) if isinstance(start, (int, float)) and not isinstance(start, bool) \
        else 0.0


_INT32 = (-(2**31), 2**31 - 1)


def _convert(name: str, kind: str, x: Any) -> Any:
    """Check one value for an FMU variable of ``kind`` (Real, Integer, Boolean); return it."""
    if kind == "Boolean":
        if isinstance(x, (bool, np.bool_)):
            return bool(x)
        raise TypeError(f"{name}: a Boolean variable takes True or False, got {x!r}")
    if isinstance(x, (bool, np.bool_)):
        art = "an" if kind == "Integer" else "a"
        raise TypeError(f"{name}: {art} {kind} variable takes a number, not the bool {x!r}")
    if kind == "Integer":
        if isinstance(x, (int, np.integer)):
            v = int(x)
        else:  # a float, even 2.0, is refused: strict types
            raise TypeError(f"{name}: an Integer variable takes an int, got {x!r} (a float is "
                            f"not rounded, truncated or taken for an integer)")
        if not _INT32[0] <= v <= _INT32[1]:
            raise ValueError(f"{name}: {v} is outside the 32-bit integer range")
        return v
    if isinstance(x, (int, float, np.integer, np.floating)):
        try:
            return float(x)
        except OverflowError:
            raise ValueError(f"{name}: {x!r} is too large for a Real") from None
    raise TypeError(f"{name}: a Real variable takes a number, got {x!r}")


def samples_per_step(h: float, Te: float, what: str = "axis") -> int:
    """Return the generator samples in a step ``h``, which must be a whole multiple of ``Te``.

    Parameters
    ----------
    h : float
        Communication step (s).
    Te : float
        Sampling period of the generator (s).
    what : str
        Names the generator in the message (e.g. ``"Z axis"``).

    Returns
    -------
    int
        ``round(h / Te)``, at least 1.

    Raises
    ------
    ValueError
        If ``h`` is not a whole multiple of ``Te`` (to 1e-9 relative), or is
        shorter than ``Te``.
    """
    r = h / Te
    m = round(r) if math.isfinite(r) else 0
    if not math.isfinite(r) or abs(r - m) > 1e-9 * max(1.0, r) or m < 1:
        raise ValueError(f"communication step {h:g} s is not a whole multiple of the "
                         f"{what}'s Te = {Te:g} s")
    return int(m)


def motion_start(t_start: float, start_time: float, Te: float) -> float:
    """First generator sample (``start_time + k Te``) at or after ``t_start``.

    The FMU starts the motion there: its sampling grid is anchored at the FMU
    start time, and a ``t_start`` within rounding of a sample counts as on it.
    The rule is the generator core's own (``djl_start_offset``, through
    :func:`harness._engine.motion_start`), the one the FMU applies.

    Raises
    ------
    harness._engine.PlanError
        A ``ValueError``: ``t_start`` not finite, or too far from the start time, as the
        FMU refuses it.
    """
    from .. import _engine  # deferred: the compiled engine is not built in a source checkout

    return _engine.motion_start(float(t_start), float(start_time), float(Te))


@dataclass
class Trajectory:
    """A generated motion, sampled at the communication points.

    Attributes
    ----------
    t : ndarray
        Time (s).
    x, v, a, j : ndarray
        Reference position (m), velocity (m/s), acceleration (m/s2), jerk (m/s3).
    x_AL, v_AL, a_AL : ndarray
        The acceleration-limited profile before the FIR filters.
    done : ndarray of bool
        True once the motion has ended.
    segment : ndarray of int
        1-based segment of the AL profile (0 before the start).
    params : dict
        The parameters given (FMU defaults for the others).
    motion_time : float
        Duration of the motion (s), filters included.
    N_F : tuple of int
        Jerk times applied, in samples.
    log : list of LogRecord
        What the FMU logged.
    """

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray
    j: np.ndarray
    x_AL: np.ndarray
    v_AL: np.ndarray
    a_AL: np.ndarray
    done: np.ndarray
    segment: np.ndarray
    params: dict[str, Any]
    motion_time: float
    N_F: tuple[int, int, int, int]
    fmi_version: int
    log: list[LogRecord] = field(default_factory=list)

    @property
    def t_end(self) -> float:
        """Time at which the motion ends (s): its first generator sample plus the motion time."""
        start = max(motion_start(float(self.params["t_start"]), float(self.t[0]),
                                 float(self.params["Te"])), float(self.t[0]))
        return start + self.motion_time

    def plot(self, *, al: bool = True, title: str | None = None, legend: bool = True):
        """Plot x, v, a and j against time (the AL profile dashed); return the figure.

        ``legend=False`` leaves the legend out (to draw it once more curves are added,
        e.g. with :func:`harness.figures.legend_above_data`).
        """
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        fig, axes = plt.subplots(4, 1, sharex=True, figsize=(8, 8))
        rows = [("x", "x [m]", "x_AL"), ("v", "v [m/s]", "v_AL"), ("a", "a [m/s²]", "a_AL"),
                ("j", "j [m/s³]", None)]
        for ax, (name, label, al_name) in zip(axes, rows, strict=True):
            kw = {"drawstyle": "steps-post"} if name == "j" else {}
            ax.plot(self.t, getattr(self, name), label=name, **kw)
            if al and al_name:
                ax.plot(self.t, getattr(self, al_name), "--", lw=0.8, label=f"{name} (AL input)",
                        drawstyle="steps-post" if al_name == "a_AL" else "default")
            ax.set_ylabel(label)
            ax.grid(True, alpha=0.3)
        axes[-1].set_xlabel("t [s]")
        prof = spec.PROFILE_NAMES.get(int(self.params.get("profile", 3)), "?")
        fig.suptitle(title or f"{prof} profile, motion time {self.motion_time:.4g} s")
        fig.tight_layout()
        if legend:
            legend_above_data(axes[0], loc="upper left")
        return fig


def generate(
    params: Mapping[str, ParamValue] | None = None,
    *,
    t_stop: float | None = None,
    dt: float | None = None,
    fmi_version: int = 2,
    fmu: str | Path | None = None,
    start_time: float = 0.0,
    debug_logging: bool = False,
) -> Trajectory:
    """Run one motion of the generator FMU and record its outputs.

    Parameters
    ----------
    params : mapping, optional
        Parameters by FMU variable name; the FMU's start values for the rest.
    t_stop : float, optional
        End time; by default ten communication steps after the end of the motion.
    dt : float, optional
        Communication step (s), any value > 0; default ``Te``.
    fmi_version : {2, 3}
        FMU to use when ``fmu`` is not given.
    fmu : path-like, optional
        A generator FMU file.
    start_time : float
        FMU start time.
    debug_logging : bool
        Collect the FMU's event and warning messages in ``Trajectory.log``.

    Returns
    -------
    Trajectory
    """
    params = dict(params or {})
    with GeneratorFMU(fmu, fmi_version=fmi_version, params=params, start_time=start_time,
                      debug_logging=debug_logging) as g:
        g.initialize()
        Te = float(g.get("Te"))
        step = Te if dt is None else float(dt)
        motion_time = float(g.get("motion_time"))
        t_start = float(g.get("t_start"))
        if t_stop is None:
            # ten communication steps past the end (the start rounds up to a sample)
            t_end = max(motion_start(t_start, start_time, Te), start_time) + motion_time
            n = math.ceil((t_end - start_time) / step - 1e-9) + 10
        else:
            n = int(round((t_stop - start_time) / step))
        t, values = g.record(n, step, REAL_OUTPUTS, ("done", "segment"))
        full = {v.name: g.get(v.name) for v in spec.PARAMETERS}
        N_F = tuple(int(g.get(f"N_F{i}")) for i in range(1, 5))
        log = list(g.log)
    done = values.pop("done").astype(bool)
    segment = values.pop("segment").astype(np.int32)
    return Trajectory(t=t, done=done, segment=segment, params=full, motion_time=motion_time,
                      N_F=N_F, fmi_version=g.fmi_version, log=log, **values)
