"""Drive the commanded generator FMU (issue #12) step by step, and check what it outputs.

The :class:`Driver` sets the inputs ``target``, ``execute``, ``stop`` and ``f_mode`` between
``doStep`` calls of one fmpy slave (FMI 2 or 3) and records every output at every
communication point, together with the inputs in force for each step and the command edges
the FMU must have seen.  The checks below work on that record alone: nothing here calls the
planner or re-derives a plan.  What they use is the contract of docs/generator.md
("Commanded moves") and elementary kinematics:

* a sampled reference is a piecewise cubic: over each generator sample interval the jerk is
  constant, so x, v, a at one communication point follow from those at the previous one;
* the limits v_max, max(a_max, d_max) and level / (jerk time) bound v, a and j;
* a command takes effect at the first generator sample strictly after the communication
  point t of the step that saw its edge (docs/generator.md, "When a command acts"); stop
  wins over execute at the same step;
* after the last command the axis rests at the last target (or wherever a stop left it).
"""

from __future__ import annotations

import ctypes
import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from harness.fmu.runner import FMUError, GeneratorFMU

INPUTS = ("target", "execute", "stop", "f_mode")
START: dict[str, float | bool] = {"target": 0.0, "execute": False, "stop": False,
                                  "f_mode": 10.0}
"""Start values of the inputs (docs/generator.md, "Commanded moves")."""

REALS = ("x", "v", "a", "j")
FLAGS = ("done", "busy")
CALCULATED = ("motion_time", "N_F1", "N_F2", "N_F3", "N_F4", "v_reached", "a_reached",
              "d_reached")

GRID_TOL = 1e-9
"""A communication point within this many samples of a generator sample is on it."""



# ------------------------------------------------------------------------- the axis


@dataclass(frozen=True)
class Axis:
    """Parameters of one FMU instance; jerk times are given in whole samples.

    ``T_F_i = (N_i + dither_i) Te`` with |dither| < 0.5, so the jerk time the FMU must apply
    is ``N_i`` samples whatever its rounding code does.
    """

    profile: int = 3
    jerk_source: int = 1
    Te: float = 1e-3
    v_max: float = 1.0
    a_max: float = 10.0
    d_max: float = 10.0
    N: tuple[int, int, int, int] = (20, 20, 20, 20)
    dither: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
    x0: float = 0.0
    distance: float = 0.0
    short_stage: int = 1
    f_mode0: float | None = None
    """f_mode set before initialisation (None: left at its start value, 10 Hz)."""

    def params(self) -> dict[str, Any]:
        p: dict[str, Any] = {
            "profile": self.profile, "Te": self.Te, "v_max": self.v_max, "a_max": self.a_max,
            "d_max": self.d_max, "x0": self.x0, "distance": self.distance,
            "short_stage": self.short_stage,
        }
        for i in range(4):
            p[f"T_F{i + 1}"] = (self.N[i] + self.dither[i]) * self.Te
        if self.jerk_source != 1:
            p["jerk_source"] = self.jerk_source
        return p

    @property
    def level(self) -> float:
        """Largest acceleration level any stage may have."""
        return max(self.a_max, self.d_max)

    def jerk_times(self) -> tuple[int, ...]:
        """Jerk times (samples) of jerk_source = 1 that the profile uses."""
        if self.profile == 1:
            return ()
        if self.profile == 2:
            return (self.N[0],)
        return self.N

    def char_distance(self, n_max: int | None = None) -> float:
        """A distance on the scale of one move: reach v_max and stop again."""
        n = n_max if n_max is not None else max(self.jerk_times(), default=0)
        return self.v_max**2 / min(self.a_max, self.d_max) + self.v_max * n * self.Te

    def samples_bound(self, distance: float, n_max: int) -> int:
        """Generous bound on the samples any move of ``distance`` takes, from any state."""
        t = (4 * self.v_max / min(self.a_max, self.d_max)
             + (abs(distance) + 2 * self.char_distance(n_max)) / self.v_max)
        return int(math.ceil(t / self.Te)) + 12 * n_max + 200


def n_of_f(f: float, Te: float) -> int:
    """Jerk time in samples for mode frequency ``f`` (docs/generator.md: round(1/(f Te)))."""
    q = 1.0 / (f * Te)
    n = math.floor(q + 0.5)
    assert abs(q - n) < 0.499, f"f_mode {f} is too close to a rounding tie ({q} samples)"
    return n


def f_for(n: int, Te: float, dither: float = 0.0) -> float:
    """A mode frequency whose period is ``n + dither`` samples (|dither| < 0.5)."""
    return 1.0 / ((n + dither) * Te)


# --------------------------------------------------------------------- the record


@dataclass(frozen=True)
class Step:
    """One doStep: where it started, its size, the inputs it saw and the edges among them."""

    t: float
    h: float
    target: float
    execute: bool
    stop: bool
    f_mode: float
    exec_edge: bool
    stop_edge: bool
    changed: frozenset[str]


@dataclass(frozen=True)
class Command:
    """An edge the FMU saw: ``kind`` is "execute" or "stop"."""

    step: int
    sample: float
    """Generator sample at which it takes effect."""
    kind: str
    target: float


@dataclass
class Record:
    """Outputs at every communication point (index 0: after initialisation)."""

    axis: Axis
    t: list[float] = field(default_factory=list)
    x: list[float] = field(default_factory=list)
    v: list[float] = field(default_factory=list)
    a: list[float] = field(default_factory=list)
    j: list[float] = field(default_factory=list)
    done: list[bool] = field(default_factory=list)
    busy: list[bool] = field(default_factory=list)
    stage: list[int] = field(default_factory=list)
    steps: list[Step] = field(default_factory=list)
    start_time: float = 0.0
    f_init: float = 10.0
    """f_mode in force at exitInitializationMode."""

    def arrays(self) -> dict[str, np.ndarray]:
        return {"t": np.array(self.t), "x": np.array(self.x), "v": np.array(self.v),
                "a": np.array(self.a), "j": np.array(self.j),
                "done": np.array(self.done, dtype=bool), "busy": np.array(self.busy, dtype=bool),
                "stage": np.array(self.stage, dtype=np.int64)}

    def rows(self) -> np.ndarray:
        """All outputs as one float array (for bit-for-bit comparisons)."""
        return np.column_stack([self.t, self.x, self.v, self.a, self.j,
                                np.array(self.done, float), np.array(self.busy, float),
                                np.array(self.stage, float)])

    def sample_at_or_after(self, t: float) -> float:
        Te = self.axis.Te
        k = (t - self.start_time) / Te
        kr = round(k)
        kk = kr if abs(k - kr) <= GRID_TOL * (1.0 + abs(k)) else math.ceil(k)
        return self.start_time + kk * Te

    def effect_sample(self, t: float) -> float:
        """The sample from which an input seen by the step from ``t`` acts: the first one
        strictly after t (docs/generator.md, "When a command acts")."""
        s = self.sample_at_or_after(t)
        if self.on_grid(t):
            s += self.axis.Te
        return s

    @property
    def ttol(self) -> float:
        """Tolerance of time comparisons (s): the master's t += h drifts from the grid."""
        span = abs(self.t[-1] - self.start_time) if self.t else 0.0
        return GRID_TOL * (self.axis.Te + span)

    def on_grid(self, t: float) -> bool:
        k = (t - self.start_time) / self.axis.Te
        return abs(k - round(k)) <= GRID_TOL * (1.0 + abs(k))

    def commands(self) -> list[Command]:
        """The command edges, in order (stop wins over execute at the same step)."""
        out = []
        for i, s in enumerate(self.steps):
            if s.stop_edge:
                out.append(Command(i, self.effect_sample(s.t), "stop", s.target))
            elif s.exec_edge:
                out.append(Command(i, self.effect_sample(s.t), "execute", s.target))
        return out

    def f_values(self) -> list[float]:
        return [self.f_init] + [s.f_mode for s in self.steps]

    def describe(self) -> str:
        """The inputs as a script (for failure messages)."""
        lines = [f"axis = {self.axis!r}"]
        prev: dict[str, Any] = {}
        for i, s in enumerate(self.steps):
            now = {"target": s.target, "execute": s.execute, "stop": s.stop, "f_mode": s.f_mode}
            diff = {k: v for k, v in now.items() if prev.get(k) != v}
            if diff and i:
                lines.append(f"  before step {i} (t = {s.t!r}, h = {s.h!r}): {diff}"
                             + (" EXECUTE EDGE" if s.exec_edge else "")
                             + (" STOP EDGE" if s.stop_edge else ""))
            elif i == 0:
                lines.append(f"  step 0 (t = {s.t!r}, h = {s.h!r}) inputs {now}")
            prev = now
        lines.append(f"  {len(self.steps)} steps")
        return "\n".join(lines)


# ----------------------------------------------------------------------- the driver


class Driver:
    """One FMU instance under test, its inputs set between steps, every output recorded.

    Parameters
    ----------
    g : GeneratorFMU
        An instance (reset and initialised here with ``axis``).
    axis : Axis
        The parameters.
    before_init, in_init : mapping
        Inputs set in Instantiated mode and in Initialization mode.
    check_unchanged : bool
        After each set, read the outputs again: they must not have changed (a command
        takes effect at a sample at or after the current point, never at it).
    """

    def __init__(self, g: GeneratorFMU, axis: Axis, *,
                 before_init: Mapping[str, Any] | None = None,
                 in_init: Mapping[str, Any] | None = None,
                 check_unchanged: bool = True) -> None:
        self.g = g
        self.axis = axis
        self.before_init = dict(before_init or {})
        self.in_init = dict(in_init or {})
        g.log.clear()
        self.check_unchanged = check_unchanged
        f = g.fmu
        self.v3 = g.fmi_version == 3
        self._vr_real = (ctypes.c_uint32 * 4)(*g.vr(REALS))
        self._vr_flag = (ctypes.c_uint32 * 2)(*g.vr(FLAGS))
        self._vr_stage = (ctypes.c_uint32 * 1)(*g.vr(["stage"]))
        self._out_real = (ctypes.c_double * 4)()
        self._out_flag = (ctypes.c_bool * 2)() if self.v3 else (ctypes.c_int * 2)()
        self._out_stage = (ctypes.c_int32 * 1)() if self.v3 else (ctypes.c_int * 1)()
        self._vr_in = {n: g.variable(n).valueReference for n in INPUTS}
        if self.v3:
            self._eh, self._ts = ctypes.c_bool(), ctypes.c_bool()
            self._er, self._lt = ctypes.c_bool(), ctypes.c_double()
        self._f = f
        # reset and initialise
        g._call(f.reset)
        g._initialized = False
        g.time = g.start_time
        g._setup()
        g.set(axis.params())
        self.cur: dict[str, Any] = dict(START)
        if axis.f_mode0 is not None:
            self.set(f_mode=axis.f_mode0)
        if before_init:
            self.set(**before_init)
        if self.v3:
            g._call(f.enterInitializationMode, startTime=g.start_time)
        else:
            g._call(f.enterInitializationMode)
        g._initialized = True
        if in_init:
            self.set(**in_init)
        self._exit_initialization()
        self.prev = dict(self.cur)   # what the first doStep compares against
        self.last_step_inputs = dict(self.cur)
        self.rec = Record(axis=axis, start_time=g.start_time, f_init=float(self.cur["f_mode"]))
        self.calculated = {n: g.get(n) for n in CALCULATED}
        self._read()

    def _exit_initialization(self) -> None:
        self.g._call(self._f.exitInitializationMode)

    # ---------------------------------------------------------------- low level

    @property
    def k(self) -> int:
        """Number of steps done."""
        return len(self.rec.steps)

    @property
    def time(self) -> float:
        return self.g.time

    def outputs(self) -> tuple[float, float, float, float, bool, bool, int]:
        f, c = self._f, self._f.component
        if self.v3:
            f.fmi3GetFloat64(c, self._vr_real, 4, self._out_real, 4)
            f.fmi3GetBoolean(c, self._vr_flag, 2, self._out_flag, 2)
            f.fmi3GetInt32(c, self._vr_stage, 1, self._out_stage, 1)
        else:
            f.fmi2GetReal(c, self._vr_real, 4, self._out_real)
            f.fmi2GetBoolean(c, self._vr_flag, 2, self._out_flag)
            f.fmi2GetInteger(c, self._vr_stage, 1, self._out_stage)
        r, fl = self._out_real, self._out_flag
        return (r[0], r[1], r[2], r[3], bool(fl[0]), bool(fl[1]), int(self._out_stage[0]))

    def _read(self) -> None:
        x, v, a, j, done, busy, stage = self.outputs()
        rec = self.rec
        rec.t.append(self.g.time)
        rec.x.append(x)
        rec.v.append(v)
        rec.a.append(a)
        rec.j.append(j)
        rec.done.append(done)
        rec.busy.append(busy)
        rec.stage.append(stage)

    def set_raw(self, name: str, value: Any) -> None:
        """Set one input through the FMI call of its type; FMUError on an error status."""
        g, f = self.g, self._f
        vr = [self._vr_in[name]]
        if name in ("execute", "stop"):
            g._call(f.setBoolean, vr, [bool(value)])
        elif self.v3:
            g._call(f.setFloat64, vr, [float(value)])
        else:
            g._call(f.setReal, vr, [float(value)])
        self.cur[name] = bool(value) if name in ("execute", "stop") else float(value)

    def set(self, **inputs: Any) -> None:
        """Set inputs; in step mode the outputs must stay what they were."""
        for name, value in inputs.items():
            self.set_raw(name, value)
        if self.check_unchanged and hasattr(self, "rec"):
            now = self.outputs()
            last = (self.rec.x[-1], self.rec.v[-1], self.rec.a[-1], self.rec.j[-1],
                    self.rec.done[-1], self.rec.busy[-1], self.rec.stage[-1])
            assert _same(now, last), (
                f"setting {inputs} at t = {self.g.time!r} changed the outputs at that time: "
                f"{last} -> {now}")

    def step(self, h: float) -> None:
        """One doStep(t, h): note the inputs it sees and its edges, record the outputs."""
        cur, prev = self.cur, self.prev
        st = Step(t=self.g.time, h=h, target=float(cur["target"]), execute=bool(cur["execute"]),
                  stop=bool(cur["stop"]), f_mode=float(cur["f_mode"]),
                  exec_edge=bool(cur["execute"]) and not bool(prev["execute"]),
                  stop_edge=bool(cur["stop"]) and not bool(prev["stop"]),
                  changed=frozenset(n for n in INPUTS if cur[n] != self.last_step_inputs[n]))
        t = self.g.time
        if self.v3:
            self.g._call(self._f.fmi3DoStep, self._f.component, t, h, True,
                         ctypes.byref(self._eh), ctypes.byref(self._ts), ctypes.byref(self._er),
                         ctypes.byref(self._lt))
        else:
            self.g._call(self._f.fmi2DoStep, self._f.component, t, h, 1)
        self.g.time = t + h
        self.prev = dict(cur)
        self.last_step_inputs = dict(cur)
        self.rec.steps.append(st)
        self._read()

    def run(self, n: int, h: float) -> None:
        for _ in range(n):
            self.step(h)

    def run_until_done(self, h: float, cap: int, extra: int = 10) -> None:
        """Step until done (and busy false), then ``extra`` steps more; fail after ``cap``."""
        for _ in range(cap):
            if self.rec.done[-1]:
                break
            self.step(h)
        else:
            raise AssertionError(f"not done after {cap} more steps (t = {self.g.time})\n"
                                 + self.rec.describe())
        self.run(extra, h)


def _same(a: Iterable[Any], b: Iterable[Any]) -> bool:
    """Equal element by element, bit for bit for floats (NaN equals NaN)."""
    for p, q in zip(a, b, strict=True):
        if isinstance(p, float):
            if np.float64(p).tobytes() != np.float64(q).tobytes():
                return False
        elif p != q:
            return False
    return True


# ------------------------------------------------------------------------- checks


@dataclass
class Tolerances:
    """Absolute tolerances of one record, from the axis' scales."""

    x: float
    v: float
    a: float

    @classmethod
    def of(cls, rec: Record) -> Tolerances:
        ax = rec.axis
        xs = max((abs(x) for x in rec.x), default=0.0)
        return cls(x=1e-9 * ax.v_max * ax.Te + 8e-16 * xs,
                   v=1e-9 * ax.level * ax.Te + 8e-16 * ax.v_max,
                   a=1e-9 * ax.level)


def check_sane(rec: Record) -> None:
    """Finite outputs, limits on v and a, stage in 0..4, a stage wherever j is not 0, busy.

    (docs/generator.md since 788e2bc: stage is 0 when no ramp runs; where two stages' ramps
    overlap it is the later one, even where their jerks cancel: a stage with j = 0 is then
    allowed, so "stage 0 when j = 0" is not checked.)
    """
    ax = rec.axis
    r = rec.arrays()
    for n in REALS:
        bad = np.nonzero(~np.isfinite(r[n]))[0]
        assert bad.size == 0, f"{n} not finite at t = {r['t'][bad[0]]}"
    vmax = np.abs(r["v"]).max()
    assert vmax <= ax.v_max * (1 + 1e-12), f"|v| = {vmax} > v_max = {ax.v_max}"
    amax = np.abs(r["a"]).max()
    assert amax <= ax.level * (1 + 1e-12), f"|a| = {amax} > max(a_max, d_max) = {ax.level}"
    st = r["stage"]
    assert st.min() >= 0 and st.max() <= 4, f"stage outside 0..4: {sorted(set(st.tolist()))}"
    bad = np.nonzero((r["j"] != 0.0) & (st == 0))[0]
    assert bad.size == 0, (f"stage 0 with j = {r['j'][bad[0]]} at t = {r['t'][bad[0]]} "
                           f"(point {bad[0]})\n" + rec.describe())
    if ax.profile == 1:
        assert np.all(r["j"] == 0.0) and np.all(st == 0), "AL: j and stage are always 0"
    bad = np.nonzero(r["busy"] == r["done"])[0]
    assert bad.size == 0, f"busy == done at t = {r['t'][bad[0]]} (point {bad[0]})"


def profile_samples(rec: Record) -> list[float]:
    """Profile time of each point, in samples since the start time, as the FMU counts it:
    the steps' h / Te added up, the phase snapped to a whole sample within 1e-9 (the
    master's t += h drifts from the grid; the FMU's profile does not)."""
    Te = rec.axis.Te
    n, ph = 0, 0.0
    out = [0.0]
    for s in rec.steps:
        q = ph + s.h / Te
        w = math.floor(q)
        n, ph = n + w, q - w
        if ph > 1.0 - 1e-9:
            n, ph = n + 1, 0.0
        elif ph < 1e-9:
            ph = 0.0
        out.append(n + ph)
    return out


def check_continuity(rec: Record, tol: Tolerances | None = None) -> list[float]:
    """Consecutive points are joined by the cubic of their reported jerks; returns all jerks.

    Over each generator sample interval the jerk is constant (the reported j of any point
    inside it); for AL the acceleration is constant (the reported a).  x, v (and a, for JL and
    DJL) at each point must follow from those at the previous one.  Steps h <= Te.  An input
    set before a step acts from the first sample strictly after the step's start
    (docs/generator.md, "When a command acts"), so the reported j of every point is the
    jerk of the interval that starts there, whatever was set after it.
    """
    ax = rec.axis
    tol = tol or Tolerances.of(rec)
    Te = ax.Te
    al = ax.profile == 1
    jerks: list[float] = []
    t, x, v, a, j = rec.t, rec.x, rec.v, rec.a, rec.j

    def fail(i: int, what: str, got: float, want: float, lim: float) -> str:
        return (f"{what} discontinuous between t = {t[i]!r} and {t[i + 1]!r} (points {i}, "
                f"{i + 1}): {got!r} from the cubic, {want!r} reported, diff {got - want:.3e} "
                f"> {lim:.3e}\n" + rec.describe())

    u = profile_samples(rec)
    for i in range(len(t) - 1):
        ui, ue = u[i], u[i + 1]
        assert ue - ui <= 1 + 1e-9, "check_continuity needs steps h <= Te"
        kb = math.floor(ui) + 1          # the generator sample boundary after t[i]
        end_on_grid = ue == math.floor(ue)
        xs, vs, as_ = x[i], v[i], a[i]
        if ue <= kb:
            # one sample interval: [t[i], t[i+1]]
            tau = (ue - ui) * Te
            if end_on_grid:
                # the interval holding t[i] ends at t[i+1]: its jerk is j[i]
                ji = j[i]
            else:
                ji = j[i + 1]     # same interval as t[i + 1], reported after the step
                if al:
                    as_ = a[i + 1]
            segs = [(tau, as_, ji)]
        else:
            # a boundary inside: [t[i], b) with the jerk at t[i], [b, t[i+1]) with the jerk
            # at t[i+1] (steps h <= Te cross at most one boundary)
            segs = [((kb - ui) * Te, as_, j[i]), ((ue - kb) * Te, None, j[i + 1])]
        xc, vc, ac = xs, vs, as_
        for tau, a_start, jj in segs:
            if a_start is not None:
                ac = a_start
            elif al:
                ac = a[i + 1]   # AL: the next interval's acceleration
            xc = xc + vc * tau + ac * tau**2 / 2 + jj * tau**3 / 6
            vc = vc + ac * tau + jj * tau**2 / 2
            ac = ac + jj * tau
            jerks.append(jj)
        assert abs(xc - x[i + 1]) <= tol.x, fail(i, "x", xc, x[i + 1], tol.x)
        assert abs(vc - v[i + 1]) <= tol.v, fail(i, "v", vc, v[i + 1], tol.v)
        if not al:
            assert abs(ac - a[i + 1]) <= tol.a, fail(i, "a", ac, a[i + 1], tol.a)
    return jerks


def f_index(k: int) -> int:
    """Index of the step whose f_mode sets the jerk time of a stage starting at sample k
    (steps of Te): the one ending there, from k - 1 (docs/generator.md, "When a command
    acts": a stage that starts at sample tau takes the f_mode read at the DoStep at
    tau - Te)."""
    return k - 1


def n_min_in_force(rec: Record) -> int:
    """Smallest jerk time (samples) any stage of this record may use."""
    ax = rec.axis
    if ax.jerk_source == 1:
        return min(ax.jerk_times())
    if ax.jerk_source == 3:
        return 1   # f_mode extrapolated: any jerk time down to one sample
    return min(n_of_f(f, ax.Te) for f in set(rec.f_values()))


SHORTENED = "the jerk time of the stage that ends the current one was"
"""The FMU's warning for a stage's ending ramp shortened (docs/generator.md, exception 2b)."""


def check_jerk_bound(rec: Record, jerks: Iterable[float], *, shortened: bool = False) -> None:
    """|j| <= (largest level) / (shortest jerk time in force), reported and inferred jerks;
    with an ending ramp shortened (logged, ``shortened``) that ramp's own length, one sample
    at least."""
    ax = rec.axis
    if ax.profile == 1:
        return
    n = 1 if shortened else n_min_in_force(rec)
    level = ax.level if ax.short_stage == 1 else ax.a_max + ax.d_max
    bound = level / (n * ax.Te) * (1 + 1e-9)
    jm = max((abs(q) for q in [*jerks, *rec.j]), default=0.0)
    assert jm <= bound, (f"|j| = {jm!r} > {level} / ({n} Te) = {bound!r}\n" + rec.describe())


def _first_point_after(rec: Record, s: float) -> int:
    """Index of the first communication point strictly after time ``s``."""
    tol = rec.ttol
    for p, tp in enumerate(rec.t):
        if tp > s + tol:
            return p
    return len(rec.t)


def _point_at_or_before(rec: Record, s: float) -> int:
    tol = rec.ttol
    best = 0
    for p, tp in enumerate(rec.t):
        if tp <= s + tol:
            best = p
    return best


def check_rest_is_kept(rec: Record) -> None:
    """Once done, the axis rests (v = a = j = 0, x fixed, done) until a command takes effect.

    From the step that sees an edge to the sample where it takes effect the axis does not
    move yet (x, v, a, j, stage as they were); done and busy may already change there (the
    interface says "done goes false at the command", and this FMU flips them at the step
    that sees the edge, up to a sample early with steps shorter than Te).
    """
    cmds = rec.commands()
    tol = rec.ttol
    t = rec.t
    for p in range(len(t) - 1):
        if not rec.done[p]:
            continue
        assert rec.v[p] == 0.0 and rec.a[p] == 0.0 and rec.j[p] == 0.0, (
            f"done at t = {t[p]!r} but v, a, j = {rec.v[p]!r}, {rec.a[p]!r}, {rec.j[p]!r}\n"
            + rec.describe())
        # commands seen at this step or before and not yet in effect at t[p]
        pending = [c.sample for c in cmds if c.step <= p and c.sample >= t[p] - tol]
        if not pending:
            assert rec.done[p + 1] and rec.x[p + 1] == rec.x[p] and rec.v[p + 1] == 0.0 \
                and rec.a[p + 1] == 0.0 and rec.j[p + 1] == 0.0, (
                    f"at rest at t = {t[p]!r} (x = {rec.x[p]!r}) but not at t = {t[p + 1]!r}: "
                    f"x, v, a, j, done = {rec.x[p + 1]!r}, {rec.v[p + 1]!r}, {rec.a[p + 1]!r}, "
                    f"{rec.j[p + 1]!r}, {rec.done[p + 1]} with no command\n" + rec.describe())
            continue
        s_first = min(pending)
        if s_first >= t[p + 1] - tol:
            # nothing in effect before t[p + 1]: x, v, a there are still the rest state
            # (AL: a is that of the interval from t[p + 1], where the command may act)
            assert rec.x[p + 1] == rec.x[p] and rec.v[p + 1] == 0.0 and (
                rec.a[p + 1] == 0.0 or rec.axis.profile == 1), (
                f"a command taking effect at t = {s_first!r} moved the axis before it\n"
                + rec.describe())
        if s_first > t[p + 1] + tol:
            # ... and the interval holding t[p + 1] is still at rest
            assert rec.j[p + 1] == 0.0 and rec.stage[p + 1] == 0, (
                f"a command taking effect at t = {s_first!r} shows at t = {t[p + 1]!r}\n"
                + rec.describe())


def _move_scale(rec: Record, p0: int, p1: int, target: float) -> float:
    xs = rec.x[p0:p1 + 1]
    x0 = rec.x[p0]
    return max(abs(target - x0), max(abs(q - x0) for q in xs), rec.axis.v_max * rec.axis.Te)


def check_final(rec: Record, *, param_end: float | None = None) -> None:
    """After the last command the motion ends at rest: at its target after an execute.

    ``param_end``: with no command, where the parametric move must end (x0 + distance).
    """
    cmds = rec.commands()
    p_from = _first_point_after(rec, cmds[-1].sample) if cmds else 0
    done = rec.done
    assert any(done[p_from:]), "not done at the end of the record\n" + rec.describe()
    pd = next(p for p in range(p_from, len(done)) if done[p])
    assert all(done[pd:]), "done went false again after the last command\n" + rec.describe()
    assert not any(rec.busy[pd:]), "busy after the end"
    for p in range(pd, len(done)):
        assert rec.v[p] == 0.0 and rec.a[p] == 0.0 and rec.j[p] == 0.0, (
            f"not at rest at t = {rec.t[p]!r} after the end: v, a, j = {rec.v[p]!r}, "
            f"{rec.a[p]!r}, {rec.j[p]!r}\n" + rec.describe())
        assert rec.x[p] == rec.x[pd], "x moves after the end"
    target: float | None = None
    if cmds and cmds[-1].kind == "execute":
        target = cmds[-1].target
        p0 = _point_at_or_before(rec, cmds[-1].sample)
    elif not cmds and param_end is not None:
        target, p0 = param_end, 0
    if target is not None:
        scale = _move_scale(rec, p0, len(rec.t) - 1, target)
        err = abs(rec.x[pd] - target)
        lim = 1e-9 * scale + 4e-16 * abs(target)
        assert err <= lim, (f"ends at x = {rec.x[pd]!r}, target {target!r}: off by {err:.3e} "
                            f"> {lim:.3e}\n" + rec.describe())


def negligible(rec: Record, d: float, x: float) -> bool:
    """A move of ``d`` from ``x`` below the accuracy promised (1e-9 of a step at v_max, and
    the rounding of x): the FMU may leave the axis where it is."""
    return abs(d) <= 1e-9 * rec.axis.v_max * rec.axis.Te + 1e-11 * abs(x)


def check_done_drops(rec: Record) -> None:
    """done is false right after an execute that moves the axis (target away, or the axis
    moving), unless the move already ended there."""
    cmds = rec.commands()
    for i, c in enumerate(cmds):
        if c.kind != "execute":
            continue
        p = _first_point_after(rec, c.sample)
        if p >= len(rec.t):
            continue
        if i + 1 < len(cmds) and cmds[i + 1].sample <= rec.t[p] + rec.ttol:
            continue   # replaced before that point
        p0 = _point_at_or_before(rec, c.sample)
        # (AL: the reported a is that of the interval after the point, not a state)
        moving = rec.v[p0] != 0.0 or (rec.a[p0] != 0.0 and rec.axis.profile != 1)
        if moving or not negligible(rec, c.target - rec.x[p0], rec.x[p0]):
            # done only if the move already ended there (its last sample was the first)
            arrived = (rec.v[p] == 0.0 and rec.a[p] == 0.0
                       and negligible(rec, c.target - rec.x[p], c.target))
            assert not rec.done[p] or arrived, (
                f"done at t = {rec.t[p]!r} right after an execute to {c.target!r} from "
                f"x = {rec.x[p0]!r}, not there (x = {rec.x[p]!r})\n" + rec.describe())


@dataclass(frozen=True)
class Move:
    """An execute that starts from rest and runs to its end before the next command."""

    cmd: Command
    p0: int
    """Point at the command's sample (the state the move starts from)."""
    p_end: int
    """First point with done true again."""
    direction: float


def _from_rest(rec: Record, c: Command) -> int | None:
    """The point at the command's sample, if the axis rests (done, v = 0, x fixed; JL, DJL:
    a = 0) from the point where the command was set up to it; else None."""
    tol = rec.ttol
    pc = c.step                       # the point where it was set: the step's start
    p0 = _point_at_or_before(rec, c.sample)
    if abs(rec.t[p0] - c.sample) > tol or not rec.done[pc]:
        return None
    if any(rec.v[p] != 0.0 or rec.x[p] != rec.x[pc] for p in range(pc, p0 + 1)):
        return None
    if rec.axis.profile != 1 and rec.a[p0] != 0.0:
        return None
    return p0


def rest_to_rest_moves(rec: Record) -> list[Move]:
    """Executes from rest that run to their end before the next command."""
    cmds = rec.commands()
    out = []
    for i, c in enumerate(cmds):
        if c.kind != "execute":
            continue
        p0 = _from_rest(rec, c)
        if p0 is None:
            continue
        nxt = cmds[i + 1].sample if i + 1 < len(cmds) else math.inf
        p1 = _first_point_after(rec, c.sample)
        pe = next((p for p in range(p1, len(rec.t)) if rec.done[p]), None)
        if pe is None or rec.t[pe] > nxt - rec.ttol:
            continue
        d = c.target - rec.x[p0]
        if negligible(rec, d, rec.x[p0]):
            continue
        out.append(Move(c, p0, pe, 1.0 if d > 0 else -1.0))
    return out


def check_rest_to_rest(rec: Record, *, stage_lengths: bool = True) -> int:
    """Moves from rest with fixed jerk times: sign-aware limits, no reversal, stages in order.

    Speeding up (a in the direction of the move) is bounded by a_max, slowing down by d_max;
    the axis never backs up; stage labels go 1, 2, 3, 4 with jerk signs +, -, -, + (in the
    direction of the move).  With steps of Te and the stretch rule each stage lasts its jerk
    time.  Jerk times are fixed with jerk_source = 1, or = 2 with f_mode never changed (with
    f_mode changing during a move, its later stages may have to be longer than planned and
    nothing forbids an overshoot then).  Returns the number of moves checked.
    """
    ax = rec.axis
    fvals = set(rec.f_values())
    if ax.jerk_source >= 2 and len(fvals) > 1:
        return 0
    tol = Tolerances.of(rec)
    moves = rest_to_rest_moves(rec)
    for m in moves:
        sg = m.direction
        sl = slice(m.p0, m.p_end + 1)
        a = sg * np.array(rec.a[sl])
        v = sg * np.array(rec.v[sl])
        x = sg * np.array(rec.x[sl])
        ctx = f"move to {m.cmd.target!r} at t = {m.cmd.sample!r}\n" + rec.describe()
        assert a.max() <= ax.a_max * (1 + 1e-12), f"a = {a.max()!r} > a_max; {ctx}"
        assert -a.min() <= ax.d_max * (1 + 1e-12), f"-a = {-a.min()!r} > d_max; {ctx}"
        assert v.min() >= -tol.v, f"the axis backs up (v = {v.min()!r}); {ctx}"
        assert np.all(np.diff(x) >= -tol.x), f"x goes back; {ctx}"
        if ax.profile == 1 or ax.short_stage != 1:
            continue   # (the overlap rule lets ramps of two stages overlap)
        q0 = m.p0
        st = np.array(rec.stage[q0:m.p_end + 1])
        j = sg * np.array(rec.j[q0:m.p_end + 1])
        labels = [int(q) for q in st if q]
        assert labels == sorted(labels), f"stages out of order {_runs(st)}; {ctx}"
        want = {1: 1.0, 2: -1.0, 3: -1.0, 4: 1.0}
        for q in range(1, 5):
            sel = st == q
            assert np.all(np.sign(j[sel]) == want[q]), f"stage {q}: jerk of wrong sign; {ctx}"
        if not (stage_lengths and ax.short_stage == 1
                and all(s.h == ax.Te for s in rec.steps)):
            continue
        if ax.jerk_source >= 2:
            N: tuple[int, ...] = (n_of_f(next(iter(fvals)), ax.Te),) * 4
        else:
            N = (ax.N[0],) * 4 if ax.profile == 2 else ax.N
        # the ramps, from the change of a over each sample (whatever the labels say):
        # four, with the jerk times in order and the signs +, -, -, +
        ramps = ramps_of(rec, m.p0, m.p_end)
        got = [(ln, int(np.sign(jj) * sg)) for _, ln, jj in ramps]
        assert got == [(N[0], 1), (N[1], -1), (N[2], -1), (N[3], 1)], (
            f"ramps (samples, sign) {got}, jerk times {N}; {ctx}")
    return len(moves)


def ramps_of(rec: Record, p0: int, p1: int) -> list[tuple[int, int, float]]:
    """Constant-jerk ramps over the sample intervals p0 .. p1-1 (steps of Te): (first sample,
    samples, jerk), the jerk of each interval being the change of a over it; a ramp ends
    where the jerk changes or a passes through 0."""
    a = np.array(rec.a[p0:p1 + 1])
    J = np.diff(a) / rec.axis.Te
    scale = max(np.abs(J).max() if J.size else 0.0, 1e-300)
    ea = 1e-12 * rec.axis.level
    out = []
    k = 0
    while k < len(J):
        if abs(J[k]) <= 1e-9 * scale:
            k += 1
            continue
        s = k
        while (k + 1 < len(J) and abs(J[k + 1] - J[s]) <= 1e-9 * scale
               and abs(a[k + 1]) > ea):
            k += 1
        out.append((p0 + s, k - s + 1, float(J[s])))
        k += 1
    return out


def _runs(st: np.ndarray) -> list[tuple[int, int, int]]:
    """Maximal runs of equal labels: (label, start, length)."""
    out = []
    k = 0
    while k < len(st):
        e = k
        while e + 1 < len(st) and st[e + 1] == st[k]:
            e += 1
        out.append((int(st[k]), k, e - k + 1))
        k = e + 1
    return out


def check_stage_ramps(rec: Record) -> int:
    """jerk_source = 1, stretch rule, steps of Te: a clean ramp lasts its stage's jerk time
    (its jerk is its level / jerk time).

    A ramp is a maximal run of one non-zero jerk (the change of a over each sample interval),
    split where a passes through 0; it is clean when a was constant for the longest jerk
    time before it and is constant right after it, and it starts or ends at a = 0: then no
    other ramp overlaps it, whatever was commanded earlier.  Its stage is the label of its
    first sample.  Ramps near a command edge are left out.  Returns the number checked.
    """
    ax = rec.axis
    if (ax.profile == 1 or ax.jerk_source != 1 or ax.short_stage != 1
            or not all(s.h == ax.Te for s in rec.steps)):
        return 0
    N = (ax.N[0],) * 4 if ax.profile == 2 else ax.N
    P = max(N)
    a = np.array(rec.a)
    J = np.diff(a) / ax.Te
    jscale = max(np.abs(J).max() if J.size else 0.0, 1e-300)
    flat = np.abs(J) <= 1e-9 * jscale
    st = np.array(rec.stage)
    edges = [i for i, s in enumerate(rec.steps) if s.exec_edge or s.stop_edge]
    ea = 1e-12 * ax.level
    n = 0
    for start, length, jerk in ramps_of(rec, 0, len(rec.t) - 1):
        end = start + length
        if start < P or end >= len(J):
            continue
        if any(start - P - 1 <= e <= end + 1 for e in edges):
            continue
        if not (flat[start - P:start].all() and flat[end]):
            continue
        if not (abs(a[start]) <= ea or abs(a[end]) <= ea):
            continue
        q = int(st[start])
        ctx = (f"ramp over samples {start}..{end - 1} (stage {q}): jerk {jerk:.6g}, a from "
               f"{a[start]!r} to {a[end]!r}\n" + rec.describe())
        assert 1 <= q <= 4, "a clean ramp without a stage: " + ctx
        assert length == N[q - 1], f"lasts {length} samples, jerk time {N[q - 1]}: " + ctx
        n += 1
    return n


def _uniq(seg: np.ndarray) -> str:
    """Runs of (nearly) equal values, as "value xcount"."""
    out: list[list[float]] = []
    for q in seg:
        if out and abs(q - out[-1][0]) <= 1e-9 * max(abs(q), abs(out[-1][0])):
            out[-1][1] += 1
        else:
            out.append([float(q), 1])
    return ", ".join(f"{q:.6g} x{int(c)}" for q, c in out)


@dataclass(frozen=True)
class StopCount:
    """Stops :func:`check_stops` checked, and those it could not check."""

    checked: int
    unchecked: int
    """Stops of a move from rest that another command replaced before the axis rested."""


def check_stops(rec: Record) -> StopCount:
    """A stop never brings the axis to rest beyond the target of the move it stops.

    docs/generator.md, "Commanded moves": in the direction of the move, the rest lies between
    the position at the stop and the move's target, and the axis does not back up on the way
    (a stop that would rest past the target keeps the move instead).  Checked for every stop
    that follows an execute from rest (a move that reaches its target without turning back),
    whatever the phase of the move, the jerk times or f_mode: the position at the stop is
    that of the last point at or before the sample where it acts, the rest that of the first
    point from there with ``done``.  A stop replaced by another command before that point
    cannot be checked: it is counted in ``unchecked``.
    """
    cmds = rec.commands()
    moves = {m.cmd.step: m for m in _moves_from_rest_any_end(rec)}
    tv = Tolerances.of(rec).v
    checked = unchecked = 0
    for i, c in enumerate(cmds):
        if c.kind != "stop" or i == 0 or cmds[i - 1].step not in moves:
            continue
        mv = moves[cmds[i - 1].step]
        ps = _point_at_or_before(rec, c.sample)
        nxt = cmds[i + 1].sample if i + 1 < len(cmds) else math.inf
        pe = next((p for p in range(max(ps, c.step + 1), len(rec.t)) if rec.done[p]), None)
        if pe is None or rec.t[pe] > nxt - rec.ttol:
            unchecked += 1
            continue
        sg, target = mv.direction, mv.cmd.target
        tol = 1e-9 * _move_scale(rec, mv.p0, pe, target) + 4e-16 * abs(target)
        x_stop, rest = rec.x[ps], rec.x[pe]
        ctx = (f"a stop at t = {c.sample!r} (x = {x_stop!r}, v = {rec.v[ps]!r}, a = "
               f"{rec.a[ps]!r}) of the move to {target!r} came to rest at {rest!r}")
        assert sg * (rest - target) <= tol, (
            f"{ctx}, {sg * (rest - target):.3e} past the move's target\n" + rec.describe())
        assert sg * (rest - x_stop) >= -tol, (
            f"{ctx}, behind the position at the stop\n" + rec.describe())
        back = -min(sg * q for q in rec.v[ps:pe + 1])
        assert back <= tv, f"{ctx}, backing up on the way (v = {-sg * back!r})\n" + rec.describe()
        checked += 1
    return StopCount(checked, unchecked)


def _moves_from_rest_any_end(rec: Record) -> list[Move]:
    """Executes from rest (on a sample), whatever interrupts them."""
    out = []
    for c in rec.commands():
        if c.kind != "execute":
            continue
        p0 = _from_rest(rec, c)
        if p0 is None or negligible(rec, c.target - rec.x[p0], rec.x[p0]):
            continue
        out.append(Move(c, p0, -1, 1.0 if c.target > rec.x[p0] else -1.0))
    return out


def check_calculated_unchanged(drv: Driver) -> None:
    """Calculated parameters describe the initial move: commands do not change them."""
    now = {n: drv.g.get(n) for n in CALCULATED}
    assert now == drv.calculated, (drv.calculated, now)


def check_all(drv: Driver, *, param_end: float | None = None) -> dict[str, int]:
    """Every check of this module on a finished record; returns a few counts."""
    rec = drv.rec
    check_sane(rec)
    jerks = check_continuity(rec)
    check_jerk_bound(rec, jerks, shortened=any(SHORTENED in r.message for r in drv.g.log))
    check_rest_is_kept(rec)
    check_done_drops(rec)
    check_final(rec, param_end=param_end)
    n_moves = check_rest_to_rest(rec)
    n_ramps = check_stage_ramps(rec)
    stops = check_stops(rec)
    check_calculated_unchanged(drv)
    return {"rest_to_rest": n_moves, "ramps": n_ramps, "stops": stops.checked,
            "stops_unchecked": stops.unchecked}


# --------------------------------------------------------------- phase of a motion


def phase_of(v: float, a: float, ax: Axis) -> str:
    """Where a motion is, from its outputs alone."""
    ea, ev = 1e-9 * ax.level, 1e-9 * ax.v_max
    if abs(a) <= ea:
        return "rest" if abs(v) <= ev else "cruise"
    if abs(v) <= ev:
        return "start"
    return "acc" if a * v > 0 else "dec"


def expect_fmu_error(fn: Callable[[], object], *fragments: str) -> FMUError:
    """Run ``fn``: it must fail with an FMI error whose message holds every fragment."""
    try:
        fn()
    except FMUError as e:
        msg = str(e)
        assert e.status == 3, (e.status, msg)
        for f in fragments:
            assert f in msg, (f, msg)
        return e
    raise AssertionError(f"no error; expected one naming {fragments}")


# ------------------------------------------------------------- scripted commands


@dataclass(frozen=True)
class Event:
    """One input event of a random script, placed relative to the motion in progress.

    kind
        ``execute`` (a pulse of ``execute`` with a new target), ``stop`` (a pulse of
        ``stop``), ``exec_stop`` (both pulses at the same step: stop wins), ``fmode`` (one new
        f_mode), ``sweep`` (a new f_mode at each of ``len(f)`` steps), ``target`` (a new
        target without an edge: inert).
    phase
        Where to fire: ``acc`` / ``cruise`` / ``dec`` (a point where the motion speeds up /
        cruises / slows down, ``frac`` of the way through those points), ``rest`` (after the
        motion ended), ``any`` (``frac`` of the way to its end), ``early`` (within 3 steps).
    rel
        Target minus the position at the firing point, in characteristic distances of the
        axis; NaN: the target input's current value again.
    hold
        Steps a pulse stays high.
    """

    kind: str
    phase: str
    frac: float
    rel: float = 0.0
    hold: int = 1
    f: tuple[float, ...] = ()


def _mirror_into(drv: Driver, scout: GeneratorFMU) -> Driver | None:
    """Put the scout in the driver's state: an FMU state copy, else a replay from scratch."""
    g = drv.g
    try:
        st = g.get_state()
        data = g.serialize_state(st)
        g.free_state(st)
        if not scout._initialized:
            scout.initialize()
        s2 = scout.deserialize_state(data)
        scout.set_state(s2, g.time)
        scout.free_state(s2)
        mirror = Driver.__new__(Driver)
        mirror.__dict__.update({k: v for k, v in drv.__dict__.items()
                                if k in ("axis", "v3", "_vr_real", "_vr_flag", "_vr_stage",
                                         "_out_real", "_out_flag", "_out_stage", "_vr_in",
                                         "calculated")})
        mirror.g, mirror._f, mirror.check_unchanged = scout, scout.fmu, False
        if mirror.v3:
            mirror._eh, mirror._ts = ctypes.c_bool(), ctypes.c_bool()
            mirror._er, mirror._lt = ctypes.c_bool(), ctypes.c_double()
        mirror.cur, mirror.prev = dict(drv.cur), dict(drv.prev)
        mirror.last_step_inputs = dict(drv.last_step_inputs)
        mirror.rec = Record(axis=drv.axis, start_time=drv.rec.start_time)
        for name in INPUTS:   # the inputs as the driver has them, whatever the state holds
            mirror.set_raw(name, drv.cur[name])
        mirror._read()
        return mirror
    except Exception:  # noqa: BLE001 - the scout only places events: replay instead
        return None


def _replay(drv: Driver, scout: GeneratorFMU) -> Driver:
    d2 = Driver(scout, drv.axis, before_init=drv.before_init, in_init=drv.in_init,
                check_unchanged=False)
    for s in drv.rec.steps:
        want = {"target": s.target, "execute": s.execute, "stop": s.stop, "f_mode": s.f_mode}
        d2.set(**{n: v for n, v in want.items() if d2.cur[n] != v})
        d2.step(s.h)
    d2.set(**{n: v for n, v in drv.cur.items() if d2.cur[n] != v})
    return d2


class Script:
    """Runs random events on a driver, firing each where the motion is in a given phase.

    To place an event the scout (a second instance of the same FMU) is put in the driver's
    state and run ahead with no new command; the driver itself only ever steps forward.
    """

    def __init__(self, drv: Driver, scout: GeneratorFMU, h: float, n_max: int,
                 dist_scale: float) -> None:
        self.drv, self.scout, self.h = drv, scout, h
        self.schedule: dict[int, dict[str, Any]] = {}
        self.low_at = {"execute": -1, "stop": -1}
        self.n_max = n_max
        self.dist_scale = dist_scale
        self.fired: list[tuple[str, str]] = []

    @property
    def look_cap(self) -> int:
        """Steps within which the motion in progress must end (from any state)."""
        drv = self.drv
        far = max(abs(drv.cur["target"] - drv.rec.x[-1]), 4 * self.dist_scale)
        return int(drv.axis.samples_bound(far, self.n_max) * drv.axis.Te / self.h) + 50

    def _pending(self, k: int) -> bool:
        return any(q >= k for q in self.schedule)

    def _step(self, d: Driver) -> None:
        todo = self.schedule.get(d.k)
        if todo:
            d.set(**{n: v for n, v in todo.items() if d.cur[n] != v})
        d.step(self.h)

    def lookahead(self) -> list[tuple[float, float, bool]]:
        """(v, a, done) at the current point and the following ones, no new command."""
        drv = self.drv
        m = _mirror_into(drv, self.scout)
        if m is None:
            m = _replay(drv, self.scout)
        out = [(m.rec.v[-1], m.rec.a[-1], m.rec.done[-1])]
        after_done = 0
        for _ in range(self.look_cap + max(self.schedule, default=0) - drv.k):
            if m.rec.done[-1] and not self._pending(m.k):
                after_done += 1
                if after_done > 12:
                    break
            self._step(m)
            out.append((m.rec.v[-1], m.rec.a[-1], m.rec.done[-1]))
        return out

    def _wait(self, ev: Event) -> int:
        look = self.lookahead()
        ax = self.drv.axis
        end = next((i for i, (_, _, d) in enumerate(look) if d), len(look) - 1)
        if ev.phase == "early":
            return int(ev.frac * 4)
        if ev.phase == "rest":
            return end + int(ev.frac * 8)
        cand: list[int] = []
        if ev.phase in ("acc", "cruise", "dec"):
            cand = [i for i, (v, a, d) in enumerate(look[:end]) if phase_of(v, a, ax) == ev.phase]
        if not cand:
            cand = list(range(end + 1))
        return cand[min(int(ev.frac * len(cand)), len(cand) - 1)]

    def fire(self, ev: Event) -> None:
        drv = self.drv
        w = self._wait(ev)
        k = drv.k + w
        needs = {"execute": ("execute",), "stop": ("stop",), "exec_stop": ("execute", "stop")}
        for name in needs.get(ev.kind, ()):
            k = max(k, self.low_at[name] + 1)
        while drv.k < k:
            self._step(drv)
        sets = dict(self.schedule.pop(drv.k, {}))
        x_now = drv.rec.x[-1]
        target = drv.cur["target"] if math.isnan(ev.rel) else x_now + ev.rel * self.dist_scale
        if ev.kind in ("execute", "exec_stop"):
            sets.update(target=target, execute=True)
            self.low_at["execute"] = drv.k + ev.hold
            self.schedule.setdefault(drv.k + ev.hold, {})["execute"] = False
        if ev.kind in ("stop", "exec_stop"):
            sets["stop"] = True
            self.low_at["stop"] = drv.k + ev.hold
            self.schedule.setdefault(drv.k + ev.hold, {})["stop"] = False
        if ev.kind == "target":
            sets["target"] = target
        if ev.kind == "fmode":
            sets["f_mode"] = ev.f[0]
        if ev.kind == "sweep":
            sets["f_mode"] = ev.f[0]
            for i, f in enumerate(ev.f[1:], 1):
                self.schedule.setdefault(drv.k + i, {})["f_mode"] = f
        self.fired.append((ev.kind, phase_of(drv.rec.v[-1], drv.rec.a[-1], drv.axis)))
        drv.set(**{n: v for n, v in sets.items() if drv.cur[n] != v})
        drv.step(self.h)

    def finish(self, extra: int = 10) -> None:
        """Play what is scheduled, then run to the end of the motion and ``extra`` steps on."""
        drv = self.drv
        while self._pending(drv.k):
            self._step(drv)
        drv.run_until_done(self.h, self.look_cap + 10, extra)
