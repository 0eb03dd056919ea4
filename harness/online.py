"""Online f_mode: the paper's DJL rule applied by the FMU inside the co-simulation.

The offline harness tunes DJL before the move (:mod:`harness.tuning`): it plans
the move, reads where the four constant-jerk stages start, looks up the modal
period at the Z position there, and iterates until the jerk times reproduce
themselves.  The commanded FMU can apply the same rule itself while it runs,
from its ``f_mode`` input:

* ``jerk_source = 2`` (``f_mode``): each constant-jerk stage's jerk time is
  round(1/(f_mode·Te)) samples, ``f_mode`` read at the ``doStep`` whose step
  contains the stage's first sample (for steps of ``Te``: the one at
  t_start − Te).  While the axis cruises, rests or speeds up at ≥ a_max/2, a
  change of ``f_mode`` replans the stages to come at once, the deceleration
  placed for the jerk times of now; a stage whose new jerk time would no
  longer land without stopping and coming back keeps the one it was planned
  with (logged by the FMU: "keeps its planned jerk time"), so the move never
  moves back.
* ``jerk_source = 3`` (``f_mode_ahead``): the same, but each stage still to
  come takes its jerk time from ``f_mode`` extrapolated, at its rate over the
  last step, to the sample at which the current plan starts it:
  f̂ = f(t_k) + r_k·(τ − t_k), r_k = (f(t_k) − f(t_(k−1)))/(t_k − t_(k−1))
  (0 at the first step).  The deceleration is then placed for the jerk times
  it will have, and the fallback above is rarely needed.

:func:`run_online` co-simulates the excited axis' FMU in one of those modes
(profile DJL), the master setting ``f_mode`` at every communication point t_k
to the tuned mode's frequency at the Z generator's current position, f(z(t_k))
from the mode map, and compares it, through the same plant and metrics, with
the offline-tuned DJL of the scenario (:func:`harness.tuning.tune.tune_profile`, the
paper's rule unless the scenario asks for another).  Both runs share the same
Z move: the one synchronised with the offline DJL move (the online move's
duration is not known before it runs).  :func:`format_online` puts several
online runs of one scenario (both jerk sources) next to the offline DJL.

Examples
--------
>>> from harness.online import run_online, format_online
>>> res = run_online("X")                    # doctest: +SKIP
>>> print(res.table())                       # doctest: +SKIP
>>> res.plot().savefig("online.png")         # doctest: +SKIP
>>> both = [run_online("X", jerk_source=js) for js in (2, 3)]  # doctest: +SKIP
>>> print(format_online(both))               # doctest: +SKIP
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .evaluation import ProfileMetrics, profile_metrics
from .figures import legend_above_data
from .fmu.runner import LogRecord
from .metrics import ZERO_BAND_NOTE
from .plant import ScheduledMode
from .scenario import Scenario, load_scenario
from .simulation.axis import samples_per_step
from .simulation.fmu_axis import FMUAxis
from .simulation.master import CoSimResult, RunUntilDone, cosimulate
from .simulation.session import Session
from .tuning.rule import TuningResult
from .tuning.tune import jerk_times, tune_profile

__all__ = [
    "COMMANDED_VARIABLES",
    "JERK_SOURCE_F_MODE",
    "JERK_SOURCE_F_MODE_AHEAD",
    "JERK_SOURCES",
    "OnlineResult",
    "StageRecord",
    "Ramp",
    "jerk_ramps",
    "jerk_source_values",
    "cosimulate_online",
    "format_online",
    "kept_jerk_time_steps",
    "online_rows",
    "rule_frequency",
    "rule_samples",
    "run_online",
    "stage_records",
]

JERK_SOURCE_F_MODE = 2
"""Value of the FMU's ``jerk_source`` parameter: jerk times from the ``f_mode`` input."""

JERK_SOURCE_F_MODE_AHEAD = 3
"""Value of the FMU's ``jerk_source`` parameter: jerk times from ``f_mode`` extrapolated
at its rate of change to the start of each stage still to come (``f_mode_ahead``)."""

JERK_SOURCES: dict[int, str] = {JERK_SOURCE_F_MODE: "f_mode",
                                JERK_SOURCE_F_MODE_AHEAD: "f_mode_ahead"}
"""The jerk sources the online co-simulation runs: value → enumeration item name."""

COMMANDED_VARIABLES = ("jerk_source", "f_mode", "stage", "done")
"""Variables of the commanded interface the online co-simulation needs."""

ONLINE = "DJL-online"
"""Label of the online run."""

_KEPT = re.compile(r"^t = (\S+) s: f_mode = \S+ Hz: .* keeps its planned jerk time\b")


def kept_jerk_time_steps(log: Sequence[LogRecord]) -> list[float]:
    """Return the times of the ``doStep`` calls at which the FMU kept a planned jerk time.

    With ``jerk_source`` 2 or 3 the FMU logs (category ``logEvents``) "t = ...
    s: f_mode = ... Hz: the stage starting at t = ... s keeps its planned jerk
    time (...)" when the jerk time from ``f_mode`` would no longer land the
    move without stopping and coming back.  The stage that starts at the next
    sample (steps of ``Te``) then keeps the jerk time it was planned with.
    One stage may be preceded by several such messages (one per part of a
    step of ``a_AL`` split over two samples).

    Parameters
    ----------
    log : sequence of LogRecord
        The FMU's messages (:attr:`harness.fmu.runner.GeneratorFMU.log`), with
        ``logEvents`` enabled.

    Returns
    -------
    list of float
        The ``doStep`` times (s), in log order.
    """
    out: list[float] = []
    for rec in log:
        m = _KEPT.match(rec.message)
        if m is not None:
            out.append(float(m.group(1)))
    return out


def rule_samples(f: float, Te: float) -> int:
    """Return the rule's jerk time: round(1/(f·Te)) samples, halves up, at least 1.

    Rounded as the FMU rounds (⌊1/(f·Te) + 1/2⌋), so that a value on a half
    sample gives the FMU's jerk time.

    Parameters
    ----------
    f : float
        Frequency (Hz), > 0.
    Te : float
        Sampling period (s), > 0.

    Returns
    -------
    int
        The jerk time (samples).
    """
    return max(1, math.floor(1.0 / (f * Te) + 0.5))


def rule_frequency(jerk_source: int, f_now: float, f_prev: float | None, t_now: float,
                   t_prev: float | None, tau: float) -> tuple[float, float]:
    """Return the frequency whose period the FMU gives a stage starting at ``tau``.

    With ``jerk_source = 2`` it is ``f_mode`` as read at the ``doStep`` at
    ``t_now`` (the one whose step contains ``tau``).  With ``jerk_source = 3``
    it is that value extrapolated to ``tau`` at its rate over the previous
    step: f̂ = f_now + r·(tau − t_now), r = (f_now − f_prev)/(t_now − t_prev),
    r = 0 at the first step (no ``f_prev``).

    Parameters
    ----------
    jerk_source : {2, 3}
        The FMU's ``jerk_source``.
    f_now : float
        ``f_mode`` at the ``doStep`` at ``t_now`` (Hz).
    f_prev : float or None
        ``f_mode`` at the ``doStep`` before it (Hz); None at the first one.
    t_now, t_prev : float or None
        Their communication times (s).
    tau : float
        The stage's first sample (s).

    Returns
    -------
    f : float
        The frequency (Hz).
    rate : float
        The rate of change used (Hz/s): 0 for ``jerk_source = 2`` and at the
        first step.

    Raises
    ------
    ValueError
        For a jerk source other than 2 or 3.
    """
    if jerk_source == JERK_SOURCE_F_MODE:
        return f_now, 0.0
    if jerk_source != JERK_SOURCE_F_MODE_AHEAD:
        raise ValueError(f"jerk_source must be 2 or 3, got {jerk_source!r}")
    if f_prev is None or t_prev is None or not t_now > t_prev:
        return f_now, 0.0
    rate = (f_now - f_prev) / (t_now - t_prev)
    return f_now + rate * (tau - t_now), rate


@dataclass(frozen=True)
class Ramp:
    """One ramp of the jerk: a step of ``a_AL`` through its moving average.

    Attributes
    ----------
    k : int
        Index of its first sample (where ``a_AL`` steps).
    delta_a : float
        The step of ``a_AL`` (m/s²).
    N : int or None
        Its length, the jerk time applied (samples); None when it could not
        be resolved.
    jerk : float
        Its jerk, delta_a / (N·Te) (m/s³); NaN when unresolved.
    """

    k: int
    delta_a: float
    N: int | None
    jerk: float


def jerk_ramps(j: np.ndarray, a_AL: np.ndarray, Te: float) -> tuple[list[Ramp], float]:
    """Split a sampled jerk into the ramps of the AL acceleration's steps.

    A JL/DJL profile is the AL acceleration ``a_AL`` with each of its steps
    spread by a moving average (§2.3, Fig. 7): the step Δa at sample k adds a
    jerk Δa/(N·Te) over the N samples k .. k+N-1, N the jerk time of that
    stage; ramps may overlap (``short_stage = 2``, moves without a
    constant-velocity stage).  Walking through the samples, the ramps already
    found are subtracted from the jerk; what is left where ``a_AL`` steps is
    the new ramp's jerk, and Δa / (jerk·Te) its length, which must be a whole
    number.  A change of ``a_AL`` below 1e-9 of its largest value (a
    re-plan's rounding) is not a step.

    Parameters
    ----------
    j : ndarray
        The jerk over each sample interval (m/s³): the FMU's ``j`` output at
        every sample (j(t_k) holds over [t_k, t_k + Te), replans included).
    a_AL : ndarray
        The FMU's ``a_AL`` output at the same samples (m/s²).
    Te : float
        Sampling period (s).

    Returns
    -------
    ramps : list of Ramp
        One per step of ``a_AL``, in order.  After a ramp that could not be
        resolved (no jerk left for it, or a length that is not a whole
        number), the later ones are unresolved too.
    mismatch : float
        Largest difference between the jerk and the sum of the ramps found
        (m/s³), over the samples up to the first unresolved ramp: about 1e-12
        of the jerk when the profile is such a sum.
    """
    j = np.asarray(j, dtype=float)
    a_AL = np.asarray(a_AL, dtype=float)
    ramps: list[Ramp] = []
    active: list[tuple[int, float]] = []  # (index after the last sample, jerk)
    broken = False
    mismatch = 0.0
    prev_a = 0.0
    # a re-plan may move a_AL by a rounding error (1e-13 relative): not a step
    tiny = 1e-9 * max(1.0, float(np.max(np.abs(a_AL)))) if a_AL.size else 0.0
    for k in range(j.size):
        active = [r for r in active if r[0] > k]
        known = sum(level for _, level in active)
        da = float(a_AL[k]) - prev_a
        if abs(da) > tiny:
            prev_a = float(a_AL[k])
            N: int | None = None
            level = float(j[k]) - known
            if not broken and level != 0.0:
                ratio = da / (level * Te)
                if ratio >= 0.5 and abs(ratio - round(ratio)) <= 1e-6 * ratio:
                    N = round(ratio)
            if N is None:
                broken = True
                ramps.append(Ramp(k, da, None, math.nan))
                continue
            active.append((k + N, da / (N * Te)))
            ramps.append(Ramp(k, da, N, da / (N * Te)))
            known += da / (N * Te)
        if not broken:
            mismatch = max(mismatch, abs(float(j[k]) - known))
    return ramps, mismatch


@dataclass(frozen=True)
class StageRecord:
    """One constant-jerk stage of a move, as applied by the FMU.

    Attributes
    ----------
    stage : int
        1 start of acceleration, 2 end of acceleration, 3 start of
        deceleration, 4 end of deceleration (the FMU's ``stage`` output).
    t_start : float
        Its first sample (s): where the FMU's ``stage`` output turns to
        ``stage``.
    t_read : float
        Where the ``f_mode`` it takes was read (s): the ``doStep`` at
        t_start − Te, whose step ends at its first sample; t_start itself for
        a stage at the first sample (planned with the ``f_mode`` at hand then).
    z : float
        Z position at ``t_read`` (m), the Z generator's output.
    f_mode : float
        The ``f_mode`` the master had given the FMU at ``t_read`` (Hz); NaN
        when not known.
    N_rule : int
        The rule's jerk time for the jerk source, round(1/(f_rule·Te)) samples
        (:func:`rule_samples`).
    N_applied : int or None
        The jerk time the FMU applied (samples): the length of the ramp that
        starts there (:func:`jerk_ramps`), even where it overlaps the next
        one.  None when no ramp starts there (a stage entered with no step of
        ``a_AL``) or it could not be resolved.
    jerk : float
        That ramp's jerk (m/s³); NaN when none.
    delta_a : float
        The step of ``a_AL`` there (m/s²); 0 when none.
    run : int
        Samples the ``stage`` output stays at ``stage`` (shorter than the
        ramp where the next stage starts before the ramp ends).
    kept : bool
        The FMU logged at ``t_read`` that the stage keeps its planned jerk
        time (:func:`kept_jerk_time_steps`): ``N_applied`` is then the one
        it was planned with, not ``N_rule``.
    jerk_source : int
        The FMU's ``jerk_source`` (2 or 3) the rule is the one of.
    f_rule : float
        The frequency of the rule (Hz), :func:`rule_frequency` from the tuned
        mode's frequency at ``z`` (and, for ``jerk_source = 3``, at the Z
        position one sample earlier): for 2 that frequency, for 3 it
        extrapolated to ``t_start``.
    f_rate : float
        The rate of change used for the extrapolation (Hz/s); 0 for
        ``jerk_source = 2`` and for a stage at the first sample.
    """

    stage: int
    t_start: float
    t_read: float
    z: float
    f_mode: float
    N_rule: int
    N_applied: int | None
    jerk: float
    delta_a: float
    run: int
    kept: bool = False
    jerk_source: int = JERK_SOURCE_F_MODE
    f_rule: float = math.nan
    f_rate: float = 0.0


def stage_records(t: np.ndarray, stage: np.ndarray, j: np.ndarray, a_AL: np.ndarray,
                  z: np.ndarray, f_of_z: Callable[[float], float], Te: float,
                  f_mode: np.ndarray | None = None,
                  kept_at: Sequence[float] = (),
                  jerk_source: int = JERK_SOURCE_F_MODE) -> list[StageRecord]:
    """Where each constant-jerk stage starts, which ``f_mode`` it took, how long its ramp lasts.

    Parameters
    ----------
    t : ndarray
        Sample times (s), one per generator sample (communication step ``Te``).
    stage : ndarray of int
        The FMU's ``stage`` output at those times (0 when no stage).
    j : ndarray
        The FMU's ``j`` output: the jerk over the sample interval that starts
        at each time (m/s³).
    a_AL : ndarray
        The FMU's ``a_AL`` output (m/s²).
    z : ndarray
        The Z position at those times (m).
    f_of_z : callable
        Frequency (Hz) of the tuned mode at z (m).
    Te : float
        Generator sampling period (s).
    f_mode : ndarray, optional
        The ``f_mode`` given to the FMU before the ``doStep`` from each time.
    kept_at : sequence of float
        Times of the ``doStep`` calls at which the FMU logged keeping a
        stage's planned jerk time (:func:`kept_jerk_time_steps`).
    jerk_source : {2, 3}
        The FMU's ``jerk_source``: which rule ``N_rule`` is
        (:func:`rule_frequency`).

    Returns
    -------
    list of StageRecord
        One per entry into a stage, in time order; the jerk times are those
        of :func:`jerk_ramps`.  A stage starting at sample k > 0 takes the
        ``f_mode`` read at sample k − 1 (for ``jerk_source = 3`` extrapolated
        to sample k at its rate from sample k − 2 to k − 1).

    Raises
    ------
    ValueError
        If the times are not one sample apart, or for a jerk source other
        than 2 or 3.
    """
    if jerk_source not in JERK_SOURCES:
        raise ValueError(f"jerk_source must be 2 or 3, got {jerk_source!r}")
    t = np.asarray(t, dtype=float)
    if t.size > 1 and not np.allclose(np.diff(t), Te, rtol=1e-9, atol=0.0):
        raise ValueError("stage_records needs one point per generator sample (step = Te)")
    st = np.asarray(stage, dtype=np.int64)
    ramps = {r.k: r for r in jerk_ramps(j, a_AL, Te)[0]}
    kept = np.asarray(sorted(kept_at), dtype=float)
    out: list[StageRecord] = []
    n = st.size
    for k in range(n):
        s = int(st[k])
        if s == 0 or (k > 0 and st[k - 1] == s):
            continue
        m = k
        while m < n and st[m] == s:
            m += 1
        kr = max(k - 1, 0)
        f = float(f_of_z(float(z[kr])))
        if kr > 0:
            f_rule, rate = rule_frequency(jerk_source, f, float(f_of_z(float(z[kr - 1]))),
                                          float(t[kr]), float(t[kr - 1]), float(t[k]))
        else:
            f_rule, rate = rule_frequency(jerk_source, f, None, float(t[kr]), None,
                                          float(t[k]))
        r = ramps.get(k)
        t_read = float(t[kr])
        was_kept = k > 0 and bool(np.any(np.abs(kept - t_read) <= 1e-6 * Te))
        out.append(StageRecord(
            stage=s, t_start=float(t[k]), t_read=t_read, z=float(z[kr]),
            f_mode=math.nan if f_mode is None else float(f_mode[kr]),
            N_rule=rule_samples(f_rule, Te), N_applied=None if r is None else r.N,
            jerk=math.nan if r is None else r.jerk, delta_a=0.0 if r is None else r.delta_a,
            run=m - k, kept=was_kept, jerk_source=jerk_source, f_rule=f_rule, f_rate=rate))
    return out


def cosimulate_online(
    axis: FMUAxis,
    z_axis: FMUAxis,
    params: Mapping[str, Any],
    z_params: Mapping[str, Any],
    modes: Sequence[ScheduledMode],
    f_mode_of_z: Callable[[float], float],
    t_after: float,
    step: float | None = None,
    *,
    t_max: float,
    profile: str = ONLINE,
    events: list[LogRecord] | None = None,
) -> tuple[CoSimResult, dict[str, np.ndarray]]:
    """Co-simulate the excited axis with ``f_mode`` set from z at every communication point.

    The master (:func:`harness.simulation.master.cosimulate`) with its input
    hook: before the ``doStep`` from t_k it sets the excited axis' ``f_mode``
    to ``f_mode_of_z(z(t_k))``, z(t_k) the Z generator's output at t_k; its
    recorders keep ``stage``, ``done`` and ``a_AL``.  The run ends ``t_after``
    after both moves have ended (the excited one when its ``done`` output
    turns true, :class:`~harness.simulation.master.RunUntilDone`).

    The plant's input over the step from t_k is the jerk ``j(t_k)``: an input
    read at t_k changes the FMU's plan from the first sample after t_k only,
    so every output at t_k, ``j`` included, holds over [t_k, t_k + Te) (the
    FMU's contract), and with h = Te the plant gets the profile's jerk exactly
    (it equals the chord (a(t_k+1) − a(t_k))/Te to rounding, replans
    included).  With h = m·Te, ``j(t_k)`` is held over the step, as the master
    does for every run (an approximation: a stage may start within the step).

    Parameters
    ----------
    axis, z_axis : FMUAxis
        The two generator instances (re-planned here).
    params : mapping
        The excited axis' parameters (``jerk_source`` 2 or 3 for the online rule).
    z_params : mapping
        The Z move's parameters.
    modes : sequence of ScheduledMode
        The plant's modes.
    f_mode_of_z : callable
        z (m) → the frequency (Hz) given to the FMU.
    t_after : float
        Simulated time after both moves have ended (s).
    step : float, optional
        Communication step, a whole multiple of ``Te`` (default ``Te``).
    t_max : float
        Give up (``RuntimeError``) if the excited move has not ended by then (s).
    profile : str
        Label of the run.
    events : list of LogRecord, optional
        If given, the excited axis' FMU logs its events (category
        ``logEvents``: replans, stages that keep their planned jerk time)
        during the run, and they are appended to it; its logging is switched
        off again afterwards.

    Returns
    -------
    run : CoSimResult
        As :func:`harness.simulation.master.cosimulate` gives; ``t_end`` is
        where ``done`` turned true.
    inputs : dict of ndarray
        ``f_mode`` (the value set before the step from each point; NaN at the
        last), ``stage``, ``done`` and ``a_AL`` (outputs at each point).

    Raises
    ------
    ValueError
        If ``step`` is not a whole multiple of both FMUs' ``Te``.
    RuntimeError
        If the excited axis' move does not end by ``t_max``.
    FMUError
        If an FMU call fails (with the FMU's log).
    """
    axis.plan(params)
    z_axis.plan(z_params)
    g = axis.g
    n_log = len(g.log)
    if events is not None:
        g.fmu.setDebugLogging(True, ["logEvents"])
    try:
        run = cosimulate(axis, z_axis, modes, RunUntilDone(t_after, t_max), step,
                         profile=profile, record=("a_AL", "stage", "done"),
                         inputs=lambda k, z: {"f_mode": f_mode_of_z(z)})
    finally:
        if events is not None:
            events.extend(g.log[n_log:])
            try:
                g.fmu.setDebugLogging(False, [])
            except Exception:  # noqa: BLE001 (the instance failed: its error is the one to report)
                pass
    sig = run.signals
    inputs = {"f_mode": sig["f_mode"], "stage": sig["stage"].astype(np.int64),
              "done": sig["done"].astype(bool), "a_AL": sig["a_AL"].copy()}
    return run, inputs


@dataclass
class OnlineResult:
    """The online-f_mode DJL next to the offline-tuned DJL, on one scenario.

    Attributes
    ----------
    scenario : Scenario
        The scenario (a single move).
    online : CoSimResult
        The run with ``jerk_source`` 2 or 3 (:attr:`jerk_source`), ``f_mode``
        set from z at every step.
    offline : CoSimResult
        The offline-tuned DJL (:func:`harness.tuning.tune.tune_profile`).
    offline_tuning : TuningResult or None
        How the offline jerk times were found (None when the scenario imposes them).
    f_mode : ndarray
        The ``f_mode`` set before the step from each point of ``online.t`` (Hz;
        NaN at the last point).
    stage : ndarray of int
        The FMU's ``stage`` output at each point of the online run.
    done : ndarray of bool
        Its ``done`` output.
    stages : list of StageRecord
        The online run's stages: start, z and f_mode there, the rule's (for
        the jerk source) and the applied jerk times (empty when the step is
        not ``Te``: the ramps are then not seen sample by sample).
    metrics : dict of str to ProfileMetrics
        ``DJL-online`` and the offline profile's name: residual, motion time,
        settling time in the scenario's band.
    band : float
        That band (m).
    band_label : str
        Where the band comes from.
    offline_profile : str
        Label of the offline run (``"DJL"``, or e.g. ``"DJL-optimal"``).
    a_AL : ndarray
        The online FMU's ``a_AL`` output at each point.
    ramps : list of Ramp
        The online jerk split into the ramps of ``a_AL``'s steps
        (:func:`jerk_ramps`; empty when the step is not ``Te``).
    ramp_mismatch : float
        Largest difference between the jerk and the sum of those ramps (m/s³).
    events : list of LogRecord
        What the online FMU logged during the run (category ``logEvents``:
        its replans, and the stages that keep their planned jerk time).
    jerk_source : int
        The online FMU's ``jerk_source``: 2 (``f_mode``) or 3
        (``f_mode_ahead``, extrapolated to each stage's start).
    """

    scenario: Scenario
    online: CoSimResult
    offline: CoSimResult
    offline_tuning: TuningResult | None
    f_mode: np.ndarray
    stage: np.ndarray
    done: np.ndarray
    stages: list[StageRecord]
    metrics: dict[str, ProfileMetrics]
    band: float
    band_label: str
    offline_profile: str = "DJL"
    a_AL: np.ndarray = field(default_factory=lambda: np.zeros(0))
    ramps: list[Ramp] = field(default_factory=list)
    ramp_mismatch: float = math.nan
    events: list[LogRecord] = field(default_factory=list)
    jerk_source: int = JERK_SOURCE_F_MODE_AHEAD

    @property
    def online_label(self) -> str:
        """Name of the online run with its jerk source, e.g. ``DJL-online (f_mode_ahead)``."""
        return f"{ONLINE} ({JERK_SOURCES.get(self.jerk_source, str(self.jerk_source))})"

    @property
    def offline_N_F(self) -> tuple[int, int, int, int]:
        """Jerk times of the offline run (samples)."""
        return self.offline.N_F

    @property
    def online_N_F(self) -> tuple[int | None, ...]:
        """Jerk times the FMU applied online, one per stage entered (samples).

        None where not resolved (see :attr:`StageRecord.N_applied`).
        """
        return tuple(s.N_applied for s in self.stages)

    @staticmethod
    def overshoot(run: CoSimResult) -> float:
        """Largest excursion of a run's reference past its target (m; 0 if none)."""
        sign = 1.0 if run.target >= run.x0 else -1.0
        return max(0.0, float(np.max(sign * (run.x - run.target))))

    @staticmethod
    def backward_travel(run: CoSimResult) -> float:
        """Largest distance a run's reference moves back, against its direction (m; 0 if none).

        A rest-to-rest move never moves back; a move whose deceleration misses
        the target and is corrected does.
        """
        sign = 1.0 if run.target >= run.x0 else -1.0
        y = sign * run.x
        return max(0.0, float(np.max(np.maximum.accumulate(y) - y)))

    def rows(self) -> list[dict[str, Any]]:
        """CSV rows: one per run (metrics and jerk times), then one per online stage.

        See :func:`online_rows` (this result alone).
        """
        return online_rows([self])

    def table(self) -> str:
        """Plain-text summary: the two runs side by side, then the online stages.

        See :func:`format_online` (this result alone).
        """
        return format_online([self])

    def plot(self, title: str | None = None):
        """Figure: x, v, a, j; stage and f_mode; deflection; z; return it."""
        import matplotlib.pyplot as plt  # deferred: matplotlib is heavy to import

        on_label = self.online_label
        runs = {self.offline_profile: (self.offline, self.metrics[self.offline_profile]),
                on_label: (self.online, self.metrics[ONLINE])}
        colors = {self.offline_profile: "tab:red", on_label: "tab:green"}
        fig, axes = plt.subplots(4, 2, sharex=True, figsize=(13, 9))
        left, right = axes[:, 0], axes[:, 1]
        for name, (r, m) in runs.items():
            c = colors[name]
            ls = "-" if name == on_label else "--"
            left[0].plot(r.t, r.x, c, ls=ls, label=name)
            left[1].plot(r.t, r.v, c, ls=ls)
            left[2].plot(r.t, r.a, c, ls=ls)
            left[3].plot(r.t, r.j, c, ls=ls, drawstyle="steps-post")
            right[2].plot(r.t, r.eps * 1e3, c, lw=1.0, ls=ls,
                          label=f"{name}: residual {m.residual * 1e3:.3g} mm, motion "
                                f"{m.motion_time:.3f} s")
            right[2].axvline(r.t_end, color=c, ls=":", lw=1.0)
            right[3].plot(r.t, r.z, c, ls=ls, label=name)
        on = self.online
        right[0].plot(on.t, self.stage, "tab:green", drawstyle="steps-post",
                      label="stage (online FMU output)")
        right[0].set_ylabel("stage")
        right[0].set_yticks([0, 1, 2, 3, 4])
        for s in self.stages:
            right[0].annotate(("?" if s.N_applied is None else f"{s.N_applied}")
                              + (" kept" if s.kept else ""),
                              (s.t_start, s.stage), fontsize="x-small",
                              xytext=(2, 3), textcoords="offset points")
        right[1].plot(on.t, self.f_mode, "tab:green", drawstyle="steps-post",
                      label="f_mode given to the FMU")
        right[1].plot(on.t, on.f[self.scenario.modemap.tune], "k:", lw=0.8,
                      label="f(z(t)) of the tuned mode")
        for s in self.stages:
            right[1].plot(s.t_read, s.f_mode, "o", color="tab:green", ms=4)
        if self.jerk_source == JERK_SOURCE_F_MODE_AHEAD and self.stages:
            right[1].plot([s.t_start for s in self.stages], [s.f_rule for s in self.stages],
                          "^", color="tab:olive", ms=5,
                          label="f_mode extrapolated to the stage starts")
        if self.offline_tuning is not None:
            tu = self.offline_tuning
            right[1].plot(tu.instants, [1.0 / p for p in tu.periods], "x", color="tab:red",
                          label=f"offline {self.offline_profile}: tuned at the stage starts")
        right[1].set_ylabel("f [Hz]")
        right[2].set_ylabel("ε [mm]")
        right[2].axhspan(-self.band * 1e3, self.band * 1e3, color="gold", alpha=0.35, lw=0)
        right[3].set_ylabel("z [m]")
        for ax, lab in zip(left, ("x [m]", "v [m/s]", "a [m/s²]", "j [m/s³]"), strict=True):
            ax.set_ylabel(lab)
        for ax in axes.ravel():
            ax.grid(True, alpha=0.3)
        t_end = max(self.online.t_end, self.offline.t_end)
        left[0].set_xlim(0.0, min(float(self.online.t[-1]), t_end + 1.0))
        left[3].set_xlabel("t [s]")
        right[3].set_xlabel("t [s]")
        fig.suptitle(title or f"{self.scenario.name}: DJL with f_mode online (jerk_source = "
                              f"{self.jerk_source}) vs offline-tuned {self.offline_profile}")
        fig.tight_layout()
        # the legends in headroom above the curves: off the data
        legend_above_data(right[1], fontsize="x-small")
        legend_above_data(right[2], fontsize="x-small")
        legend_above_data(left[0], loc="upper left")
        return fig


def _fmt(x: float) -> str:
    return "never" if math.isinf(x) else f"{x:.3f}"


def _check_same_case(results: Sequence[OnlineResult]) -> None:
    """Refuse online runs that do not share one scenario and one offline run."""
    if not results:
        raise ValueError("no online result given")
    first = results[0]
    for r in results[1:]:
        if (r.scenario.name != first.scenario.name or r.offline_profile != first.offline_profile
                or r.offline.N_F != first.offline.N_F or r.offline.t.size != first.offline.t.size
                or not np.array_equal(r.offline.x, first.offline.x)):
            raise ValueError("online results to put side by side must share the scenario and "
                             f"the offline run: {first.scenario.name} ({first.offline_profile}) "
                             f"and {r.scenario.name} ({r.offline_profile})")


_BLANK_STAGE = {"stage": "", "t_stage_s": "", "t_read_s": "", "z_m": "", "f_mode_hz": "",
                "f_rate_hz_per_s": "", "f_rule_hz": "", "N_rule": "", "N_applied": "",
                "kept_planned": "", "stage_run_samples": ""}


def online_rows(results: Sequence[OnlineResult]) -> list[dict[str, Any]]:
    """CSV rows of online runs of one scenario next to its offline DJL.

    One row per run (the offline one first, then each online run in the
    order given: metrics and jerk times), then one per stage of each online
    run.  Column ``jerk_source`` says which jerk source an online row is of
    (empty for the offline run); a stage row gives, next to the applied jerk
    time ``N_applied``, the rule's one for that jerk source, ``N_rule`` =
    round(1/(``f_rule_hz``·Te)), with ``f_rule_hz`` the ``f_mode`` read (2) or
    it extrapolated to the stage's start at ``f_rate_hz_per_s`` (3).

    Parameters
    ----------
    results : sequence of OnlineResult
        Runs of one scenario with one offline run (e.g. jerk sources 2 and 3).

    Returns
    -------
    list of dict
        The rows, all with the same keys.

    Raises
    ------
    ValueError
        If the results do not share the scenario and the offline run.
    """
    _check_same_case(results)
    first = results[0]
    name = first.scenario.name
    rows: list[dict[str, Any]] = []

    def run_row(profile: str, js: int | str, run: CoSimResult, m: ProfileMetrics,
                N: Sequence[int | None]) -> dict[str, Any]:
        return {
            "scenario": name, "row": "run", "profile": profile, "jerk_source": js,
            "jerk_times_samples": "/".join("?" if n is None else str(n) for n in N),
            "residual_m": m.residual, "residual_peak_m": m.residual_peak,
            "motion_time_s": m.motion_time, "settling_time_s": m.settling_time,
            "band_m": m.band, "end_error_m": float(run.x[-1] - run.target),
            "overshoot_m": OnlineResult.overshoot(run),
            "backward_travel_m": OnlineResult.backward_travel(run), **_BLANK_STAGE,
        }

    rows.append(run_row(first.offline_profile, "", first.offline,
                        first.metrics[first.offline_profile], first.offline.N_F))
    for r in results:
        rows.append(run_row(ONLINE, r.jerk_source, r.online, r.metrics[ONLINE], r.online_N_F))
    for r in results:
        for s in r.stages:
            rows.append({
                "scenario": name, "row": "stage", "profile": ONLINE,
                "jerk_source": r.jerk_source, "jerk_times_samples": "", "residual_m": "",
                "residual_peak_m": "", "motion_time_s": "", "settling_time_s": "",
                "band_m": "", "end_error_m": "", "overshoot_m": "", "backward_travel_m": "",
                "stage": s.stage, "t_stage_s": s.t_start, "t_read_s": s.t_read, "z_m": s.z,
                "f_mode_hz": s.f_mode, "f_rate_hz_per_s": s.f_rate, "f_rule_hz": s.f_rule,
                "N_rule": s.N_rule, "N_applied": "" if s.N_applied is None else s.N_applied,
                "kept_planned": int(s.kept), "stage_run_samples": s.run,
            })
    return rows


_SOURCE_TEXT = {
    JERK_SOURCE_F_MODE: "each stage's jerk time round(1/(f_mode Te)), f_mode read at the step "
                        "before the stage starts",
    JERK_SOURCE_F_MODE_AHEAD: "each stage still to come takes round(1/(f Te)), f = f_mode "
                              "extrapolated at its rate over the last step to where the plan "
                              "starts the stage",
}


def format_online(results: Sequence[OnlineResult]) -> str:
    """Plain-text table of online runs of one scenario next to its offline DJL.

    The runs side by side (jerk times, residual, peak after the motion,
    motion and settling time, overshoot, backward travel, end error), then
    each online run's stages: where each started, ``f_mode`` read at the step
    before, the frequency of the rule for the jerk source, the rule's jerk
    time round(1/(f·Te)) and the one applied.

    Parameters
    ----------
    results : sequence of OnlineResult
        Runs of one scenario with one offline run (e.g. jerk sources 2 and 3).

    Returns
    -------
    str

    Raises
    ------
    ValueError
        If the results do not share the scenario and the offline run.
    """
    _check_same_case(results)
    first = results[0]
    off = first.offline_profile
    Te = first.online.Te
    how = (first.offline_tuning.describe() if first.offline_tuning is not None
           else "jerk times imposed by the scenario")

    def jerk_text(r: OnlineResult | None) -> str:
        if r is None:
            return "/".join(f"{n * Te * 1e3:.0f}" for n in first.offline_N_F)
        if not r.stages:
            return "(not measured)"
        return "/".join(("?" if s.N_applied is None else f"{s.N_applied * Te * 1e3:.0f}")
                        + ("*" if s.kept else "") for s in r.stages)

    cols: list[tuple[str, CoSimResult, ProfileMetrics, OnlineResult | None]] = [
        (off, first.offline, first.metrics[off], None)]
    cols += [(f"{ONLINE} js={r.jerk_source}", r.online, r.metrics[ONLINE], r) for r in results]
    jt = [jerk_text(c[3]) for c in cols]
    w = max(16, *(len(c[0]) + 2 for c in cols), *(len(x) + 2 for x in jt))

    def line(label: str, cells: Sequence[str]) -> str:
        return f"{label:32s}" + "".join(f"{c:>{w}s}" for c in cells)

    lines = [f"Scenario {first.scenario.name}: DJL with f_mode online against offline-tuned "
             f"{off}",
             f"  offline: {how}"]
    for r in results:
        lines.append(f"  {ONLINE} js={r.jerk_source}: jerk_source = {r.jerk_source} "
                     f"({JERK_SOURCES.get(r.jerk_source, '?')}): "
                     f"{_SOURCE_TEXT.get(r.jerk_source, '')}")
    lines += [
        f"  f_mode = f(z(t_k)) of the tuned mode, set before every step of "
        f"{first.online.step * 1e3:g} ms; the same Z move for all (v_max "
        f"{first.online.z_v_max:.4g} m/s)",
        "",
        line("", [c[0] for c in cols]),
        line("jerk times [ms]", jt),
        line("residual vibration [mm]", [f"{c[2].residual * 1e3:.4g}" for c in cols]),
        line("peak |eps| after motion [mm]", [f"{c[2].residual_peak * 1e3:.4g}" for c in cols]),
        line("motion time [s]", [f"{c[2].motion_time:.4f}" for c in cols]),
        line("settling time [s]", [_fmt(c[2].settling_time) for c in cols]),
        line("overshoot past the target [mm]",
             [f"{OnlineResult.overshoot(c[1]) * 1e3:.4g}" for c in cols]),
        line("backward travel [mm]",
             [f"{OnlineResult.backward_travel(c[1]) * 1e3:.4g}" for c in cols]),
        line("end position error [m]", [f"{c[1].x[-1] - c[1].target:.2g}" for c in cols]),
        f"  settling {first.band_label}: +/-{first.band * 1e3:.3g} mm"
        + ("; *: the stage kept its planned jerk time"
           if any(s.kept for r in results for s in r.stages) else ""),
    ]
    for r in results:
        if r.stages:
            ahead = r.jerk_source == JERK_SOURCE_F_MODE_AHEAD
            f_text = ("f_mode extrapolated to the stage's start at its rate over the step "
                      "before (rate)" if ahead else "f_mode as read")
            lines += ["", f"Online stages, jerk_source = {r.jerk_source} ({len(r.stages)} "
                          f"entered; start: the FMU's stage output; z, f_mode: where the f_mode "
                          f"the stage takes was read, the step before its start; f: the rule's "
                          f"frequency, {f_text}; N applied: the length of the jerk ramp "
                          f"starting there (the jerk split into the ramps of a_AL's steps, "
                          f"largest misfit {r.ramp_mismatch:.1e} m/s3; '?': no ramp starts "
                          f"there; 'kept': the FMU kept the planned jerk time, the rule's would "
                          f"not land without moving back); run: samples the stage output "
                          f"stays):",
                      f"  {'stage':>5s} {'t [s]':>8s} {'z [m]':>8s} {'f_mode [Hz]':>12s} "
                      + (f"{'rate [Hz/s]':>12s} " if ahead else "")
                      + f"{'f [Hz]':>10s} {'round(1/(f Te))':>16s} {'N applied':>10s} "
                        f"{'run':>6s}"]
            for s in r.stages:
                na = "?" if s.N_applied is None else str(s.N_applied)
                lines.append(f"  {s.stage:5d} {s.t_start:8.3f} {s.z:8.4f} {s.f_mode:12.4f} "
                             + (f"{s.f_rate:12.4f} " if ahead else "")
                             + f"{s.f_rule:10.4f} {s.N_rule:16d} {na:>10s} {s.run:6d}"
                             + ("  kept" if s.kept else ""))
        elif abs(r.online.step - Te) > 1e-12 * Te:
            lines += ["", f"(stages not measured, jerk_source = {r.jerk_source}: the step "
                          f"{r.online.step * 1e3:g} ms is not Te = {Te * 1e3:g} ms)"]
    if first.offline_tuning is not None and first.offline_tuning.instants:
        tu = first.offline_tuning
        lines += ["", f"Offline {off} stage starts [s]: "
                  + "/".join(f"{x:.3f}" for x in tu.instants)
                  + ", z there [m]: " + "/".join(f"{x:.4f}" for x in tu.z)]
    return "\n".join(lines)


def run_online(scenario: Scenario | str | Path, *, fmu: str | Path | None = None,
               fmi_version: int | None = None, step: float | None = None,
               offline: str = "DJL", session: Session | None = None,
               jerk_source: int = JERK_SOURCE_F_MODE_AHEAD) -> OnlineResult:
    """Co-simulate DJL with ``f_mode`` given online, next to the offline-tuned DJL.

    Parameters
    ----------
    scenario : Scenario, str or Path
        A single-move scenario, a TOML file or an embedded name (``X``, ``Y``).
    fmu : path-like, optional
        A generator FMU file with the commanded interface (overrides the scenario's).
    fmi_version : {2, 3}, optional
        FMI version of the package's FMU (overrides the scenario's).
    step : float, optional
        Communication step (s), a whole multiple of ``Te``; default the
        scenario's ``simulation.step``.  The per-stage jerk times are measured
        when it is ``Te``.
    offline : str
        The offline profile compared: ``"DJL"`` (the scenario's DJL tuning,
        the paper's rule by default) or a variant such as ``"DJL-optimal"``.
    session : Session, optional
        FMU-engine instances to reuse (they are re-planned).
    jerk_source : {3, 2}
        The online FMU's ``jerk_source``: 3 (``f_mode_ahead``, default) each
        stage still to come takes its jerk time from ``f_mode`` extrapolated
        at its rate over the last step to the stage's start, so that the
        deceleration is placed for the jerk times it will have; 2
        (``f_mode``) from ``f_mode`` as read.

    Returns
    -------
    OnlineResult

    Raises
    ------
    ValueError
        A sweep, a step that is not a whole multiple of ``Te``, a session on
        the fast engine, a jerk source other than 2 or 3, or an FMU without
        the commanded interface or that jerk source.
    """
    if isinstance(jerk_source, bool) or jerk_source not in JERK_SOURCES:
        raise ValueError(f"jerk_source must be 2 (f_mode) or 3 (f_mode_ahead), got "
                         f"{jerk_source!r}")
    sc = scenario if isinstance(scenario, Scenario) else load_scenario(scenario)
    if fmu is not None or fmi_version is not None:
        sc = sc.with_fmu(Path(fmu) if fmu is not None else None, fmi_version)
    if sc.is_sweep:
        raise ValueError(f"{sc.name}: the online co-simulation runs a single move, not a sweep")
    if not offline.split("-")[0] == "DJL":
        raise ValueError(f"offline profile must be DJL or a DJL variant, got {offline!r}")
    if session is not None and session.engine != "fmu":
        raise ValueError("the online co-simulation steps the FMUs: give a session on the "
                         "'fmu' engine")
    own = session is None
    if session is None:
        session = Session(sc.simulation.fmu, sc.simulation.fmi_version, engine="fmu")
    try:
        return _run(sc, session, step, offline, int(jerk_source))
    finally:
        if own:
            session.close()


def jerk_source_values(md: Any) -> set[int] | None:
    """Return the values a model description allows for ``jerk_source``.

    Parameters
    ----------
    md : fmpy.model_description.ModelDescription
        The FMU's model description.

    Returns
    -------
    set of int or None
        The items of its enumeration type (or 1 .. its ``max``); None when it
        has no ``jerk_source`` or does not say.
    """
    for v in md.modelVariables:
        if v.name != "jerk_source":
            continue
        dt = getattr(v, "declaredType", None)
        items = getattr(dt, "items", None) if dt is not None else None
        if items:
            return {int(i.value) for i in items}
        if v.max is not None:
            return set(range(1, int(v.max) + 1))
    return None


def _run(sc: Scenario, session: Session, step: float | None, offline: str,
         jerk_source: int) -> OnlineResult:
    md = session.axis.g.md
    names = {v.name for v in md.modelVariables}
    missing = [n for n in COMMANDED_VARIABLES if n not in names]
    if missing:
        raise ValueError(f"{session.axis.g.path}: the FMU lacks the commanded interface "
                         f"(docs/generator.md): no {', '.join(missing)}")
    allowed = jerk_source_values(md)
    if allowed is not None and jerk_source not in allowed:
        raise ValueError(f"{session.axis.g.path}: the FMU has no jerk_source = {jerk_source} "
                         f"({JERK_SOURCES[jerk_source]}); it allows "
                         f"{', '.join(str(v) for v in sorted(allowed))}")
    if step is not None:
        h = float(step)
        samples_per_step(h, sc.simulation.Te, "generator")
        sc = dataclasses.replace(sc, simulation=dataclasses.replace(sc.simulation, step=h))
    h = sc.simulation.step
    tuning = tune_profile(session, sc, offline)
    T_F = jerk_times(sc, "DJL", tuning)
    off = session.run(sc, offline, T_F)

    # the online run: the same move and Z move, jerk times from f_mode
    mode = sc.modemap.tuned
    params = session.move_params(sc, "DJL", T_F)
    params["jerk_source"] = jerk_source
    params["f_mode"] = mode.f(sc.z.z0)
    T_x = off.plan_info["motion_time"]
    v_z, _ = session.z_velocity(sc, T_x)
    zp = session.z_move_params(sc, v_z)
    t_max = sc.move.t_start + 2.0 * T_x + off.plan_info["z_motion_time"] + 1.0
    events: list[LogRecord] = []
    on, rec = cosimulate_online(session.axis, session.z_axis, params, zp,
                                sc.modemap.scheduled(), mode.f, sc.simulation.t_after, h,
                                t_max=t_max, events=events)
    on.z_synced = off.z_synced
    Te = sc.simulation.Te
    stages: list[StageRecord] = []
    ramps: list[Ramp] = []
    mismatch = math.nan
    if abs(h - Te) <= 1e-9 * Te:
        stages = stage_records(on.t, rec["stage"], on.j, rec["a_AL"], on.z, mode.f, Te,
                               rec["f_mode"], kept_jerk_time_steps(events), jerk_source)
        ramps, mismatch = jerk_ramps(on.j, rec["a_AL"], Te)

    # metrics: one band for both (the scenario's settle_band)
    spec = sc.simulation.settle_band
    residuals = {offline: off.free_amplitude, ONLINE: on.free_amplitude,
                 "DJL": off.free_amplitude}
    if spec.needs == "AL":
        al = session.run(sc, "AL", None, t_stop=session.t_stop_after_motion(sc, "AL", None))
        residuals["AL"] = al.free_amplitude
    band, fell_back = spec.half_width(residuals)
    label = spec.label + (ZERO_BAND_NOTE if fell_back else "")
    metrics = {offline: profile_metrics(off, band), ONLINE: profile_metrics(on, band)}
    return OnlineResult(sc, on, off, tuning, rec["f_mode"], rec["stage"], rec["done"], stages,
                        metrics, band, label, offline_profile=offline, a_AL=rec["a_AL"],
                        ramps=ramps, ramp_mismatch=mismatch, events=events,
                        jerk_source=jerk_source)

