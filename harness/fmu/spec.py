"""The FMU's variables: the single source of truth.

Both model descriptions (``modeldesc/fmi2``, ``modeldesc/fmi3``) and the C
header of value references (``fmu_src/djl_vars.h``) are generated from
:data:`VARIABLES` by :mod:`harness.fmu.codegen`; a test regenerates them and
fails if the committed files differ.

Names, units and meanings of the first variables (time .. done) are a contract
with users: extend the list, never rename.
"""

from __future__ import annotations

import hashlib
import json
import uuid
from dataclasses import asdict, dataclass, field
from typing import Literal

MODEL_IDENTIFIER = "JerkLimitedTrajectory"
MODEL_NAME = "JerkLimitedTrajectory"
MODEL_VERSION = "0.1.0"
MAX_SEGMENTS = 32
"""Capacity of the segment arrays (``DJL_MAX_SEGMENTS`` in ``djl_core.h``)."""

DEFAULT_TE = 1e-3
"""Start value of ``Te``.  FMI 3's ``fixedInternalStepSize`` is not declared: ``Te`` is a
parameter, and the FMU gives exact values at any communication step."""

LOG_CATEGORIES: tuple[tuple[str, str], ...] = (
    ("logEvents", "Planning decisions: stage lengths, reached limits, fallbacks"),
    ("logStatusWarning", "Warnings (ignored parameters)"),
    ("logStatusError", "Errors: invalid parameters, infeasible motions, calls out of order"),
)

Causality = Literal["parameter", "calculatedParameter", "input", "output", "local",
                    "independent"]
Variability = Literal["fixed", "tunable", "discrete", "continuous"]
VarType = Literal["Real", "Integer", "Boolean", "Enumeration"]

UNITS: dict[str, dict[str, int]] = {
    "s": {"s": 1},
    "m": {"m": 1},
    "m/s": {"m": 1, "s": -1},
    "m/s2": {"m": 1, "s": -2},
    "m/s3": {"m": 1, "s": -3},
    "Hz": {"s": -1},
}

DISPLAY_UNITS: dict[str, tuple[str, float]] = {
    "s": ("ms", 1000.0),
    "m": ("mm", 1000.0),
    "m/s": ("mm/s", 1000.0),
    "m/s2": ("mm/s2", 1000.0),
    "m/s3": ("mm/s3", 1000.0),
}
"""Display unit of each unit (a machine-tool user thinks in mm): name and factor
(display value = factor x value).  A unit without one (Hz) is displayed as it is."""

QUANTITIES: dict[str, str] = {
    "Time": "s",
    "Position": "m",
    "Velocity": "m/s",
    "Acceleration": "m/s2",
    "Jerk": "m/s3",
    "Frequency": "Hz",
}
"""Declared Real types: name (also its ``quantity``) and unit; every Real variable with a
unit gets the type of its unit (but the independent variable ``time``)."""

QUANTITY_OF_UNIT = {unit: q for q, unit in QUANTITIES.items()}

ENUMERATIONS: dict[str, tuple[tuple[str, int, str], ...]] = {
    "Profile": (
        ("AL", 1, "acceleration-limited"),
        ("JL", 2, "jerk-limited, one jerk time T_F1"),
        ("DJL", 3, "dissociated jerk-limited, jerk times T_F1..T_F4"),
        ("table", 4, "piecewise-constant jerk replayed from table_samples / table_jerk"),
    ),
    "ShortStage": (
        ("stretch", 1, "lengthen a short stage so that every constant-jerk stage lasts its "
                       "jerk time"),
        ("overlap", 2, "let the two ramps of a short stage overlap, as in the paper"),
    ),
    "JerkSource": (
        ("parameters", 1, "the jerk times T_F1..T_F4 (JL: T_F1)"),
        ("f_mode", 2, "each stage's jerk time is the period 1/f_mode read when the stage "
                      "starts (the paper's rule, applied online)"),
        ("f_mode_ahead", 3, "as f_mode, with f_mode extrapolated at its rate of change to "
                            "the stages still to come, so that the deceleration is placed "
                            "for the jerk times it will have"),
    ),
    "Shaper": (
        ("none", 0, "no input shaping: the outputs are the planned profile"),
        ("ZV", 1, "zero vibration: 2 impulses [1, K]/(1+K) at [0, Td/2]"),
        ("ZVD", 2, "zero vibration and derivative: 3 impulses [1, 2K, K^2]/(1+K)^2 at "
                   "[0, Td/2, Td]"),
        ("EI", 3, "extra-insensitive, 5 % vibration tolerance: 3 impulses at [0, Td/2, Td]"),
        ("custom", 4, "shaper_n impulses shaper_amplitude[i] at shaper_delay[i]"),
    ),
    "CmdProfile": (
        ("parameter", 0, "the profile parameter's (the jerk times of the parametric move)"),
        ("AL", 1, "acceleration-limited"),
        ("JL", 2, "jerk-limited, one jerk time (cmd_T_F[1], else T_F1)"),
        ("DJL", 3, "dissociated jerk-limited, jerk times cmd_T_F[i], else T_Fi"),
    ),
    "CmdShaper": (
        ("parameter", 0, "the shaper parameter's design"),
        ("ZV", 1, "zero vibration, for f_shaper"),
        ("ZVD", 2, "zero vibration and derivative, for f_shaper"),
        ("EI", 3, "extra-insensitive, for f_shaper"),
        ("custom", 4, "cmd_shaper_n impulses cmd_shaper_amplitude[i] at cmd_shaper_delay[i] "
                      "(cmd_shaper_n = 0: the parameters shaper_n, shaper_amplitude, "
                      "shaper_delay)"),
        ("none", 5, "no input shaping for this move"),
    ),
    "BufferMode": (
        ("aborting", 0, "replaces the move in progress and every waiting command"),
        ("buffered", 1, "waits until the moves before it have ended, then starts from rest"),
        ("blending", 2, "waits as buffered; the move before it passes its target without "
                        "stopping"),
    ),
    "ShaperSource": (
        ("f_shaper", 1, "the impulses are timed for the parameter f_shaper"),
        ("f_mode", 2, "each impulse is timed by the phase of the input f_mode accumulated "
                      "since the profile's instant it copies (time-varying shaper)"),
    ),
}
"""Enumeration types: items (name, value, description).  FMI 2 sets them with
``fmi2SetInteger``, FMI 3 with ``fmi3SetInt64`` (the FMU also takes ``fmi3SetInt32``)."""

PROFILE_CODES: dict[str, int] = {name: value for name, value, _ in ENUMERATIONS["Profile"]}
"""Code of each profile by name (``{"AL": 1, "JL": 2, "DJL": 3, "table": 4}``), from
:data:`ENUMERATIONS`."""

PROFILE_NAMES: dict[int, str] = {value: name for name, value in PROFILE_CODES.items()}
"""Name of each profile code (the inverse of :data:`PROFILE_CODES`)."""

MAX_POSITION = 1e300
"""Largest |position| a motion may reach (``DJL_MAX_POSITION``): the bound of ``x0`` and
``distance``."""

MAX_TE = 1e285
"""Largest ``Te``: the FMU's horizon of 1e15 samples stays below 1e300 s."""

MAX_FILTER_SAMPLES = 100000000
"""Longest jerk time in samples (``DJL_MAX_FILTER_SAMPLES``)."""

MAX_SHAPER_IMPULSES = 8
"""Capacity of the custom shaper's arrays (``DJL_MAX_SHAPER_IMPULSES`` in ``djl_core.h``)."""

MAX_SHAPER_DELAY_SAMPLES = 4096
"""Longest delay of an input shaper's impulse, in samples of ``Te``
(``DJL_MAX_SHAPER_DELAY_SAMPLES``): the FMU state keeps that much of the profile's past."""

SHAPER_AMPLITUDE_TOLERANCE = 1e-9
"""A custom shaper's amplitudes must sum to 1 within this (``DJL_SHAPER_SUM_TOLERANCE``)."""

QUEUE_CAPACITY = 16
"""Commands a buffered or blending execute can wait behind the move in progress
(``MODEL_QUEUE_CAPACITY`` in ``fmu_base.h``)."""

CMD_ERRORS: tuple[tuple[int, str, str, str], ...] = (
    (1, "TARGET", "target", "target is not finite or beyond 1e300 m in magnitude (an execute)"),
    (2, "V_MAX", "cmd_v_max", "cmd_v_max is neither 0 nor a finite velocity > 0"),
    (3, "A_MAX", "cmd_a_max", "cmd_a_max is neither 0 nor a finite acceleration > 0"),
    (4, "D_MAX", "cmd_d_max", "cmd_d_max is neither 0 nor a finite deceleration > 0"),
    (5, "PROFILE", "cmd_profile", "cmd_profile is not 0, 1, 2 or 3"),
    (6, "T_F", "cmd_T_F",
     f"a jerk time the command uses (cmd_T_F[i], or the T_Fi its 0 stands for) is not one of "
     f"1..{MAX_FILTER_SAMPLES} samples of Te (finite, >= Te/2)"),
    (7, "JERK_WITH_F_MODE", "cmd_profile",
     "cmd_profile or a cmd_T_F[i] not 0 with jerk_source = 2 or 3 (the jerk times come from "
     "f_mode)"),
    (8, "SHAPER", "cmd_shaper",
     "cmd_shaper is not 0..5, or its design is refused (f_shaper, zeta_shaper, f_mode)"),
    (9, "SHAPER_N", "cmd_shaper_n",
     f"cmd_shaper = 4 and cmd_shaper_n is not 0..{MAX_SHAPER_IMPULSES}"),
    (10, "SHAPER_AMPLITUDE", "cmd_shaper_amplitude",
     "cmd_shaper = 4: an amplitude is not finite, or they do not sum to 1 within "
     f"{SHAPER_AMPLITUDE_TOLERANCE:g}"),
    (11, "SHAPER_DELAY", "cmd_shaper_delay",
     "cmd_shaper = 4: a delay is negative, not finite, or beyond "
     f"{MAX_SHAPER_DELAY_SAMPLES} samples of Te (with shaper_source = 2: at the f_mode of the "
     "command)"),
    (12, "SHAPER_WHILE_MOVING", "cmd_shaper",
     "another shaper than the one in force while the output is not at rest (done false, or "
     "v != 0): a shaper changes only from rest"),
    (13, "NO_MOTION", "target",
     "no motion within the command's limits reaches target (too far for them, or longer "
     "than the FMU's horizon; a stop: no stop within DJL_MAX_PLAN_END samples): the "
     "planner's reason is logged"),
    (14, "BUFFER_MODE", "buffer_mode", "buffer_mode is not 0 (aborting), 1 (buffered) or 2 "
     "(blending)"),
    (15, "MIN_DURATION", "min_duration", "min_duration is neither 0 nor a finite duration > 0 "
     "(s), or no velocity makes the move last that long within the FMU's horizon"),
    (16, "QUEUE_FULL", "buffer_mode",
     f"a buffered or blending execute while {QUEUE_CAPACITY} commands already wait"),
)
"""Codes of the output ``cmd_error_id`` (docs/generator.md, "Command errors"): code, C name
(``CMD_ERR_<name>`` in ``djl_vars.h``), the input a message names, meaning.  0: no error."""

MAX_TABLE = 256
"""Capacity of the replayed table's arrays (``DJL_MAX_TABLE`` in ``djl_core.h``): pieces of
profile 4 (``table``)."""

TABLE_END_TOLERANCE = 1e-9
"""A table must end at rest at ``x0 + distance`` within this of its own scale (its largest
acceleration, velocity and travel; ``DJL_TABLE_END_TOLERANCE``)."""

TABLE_LIMIT_TOLERANCE = 1e-10
"""A table's velocity and acceleration may pass v_max, a_max, d_max by this much of each limit
(``DJL_TABLE_LIMIT_TOLERANCE``)."""


@dataclass(frozen=True)
class Variable:
    """One FMU variable (a scalar, or an array of ``size`` elements)."""

    name: str
    vr: int
    type: VarType
    causality: Causality
    variability: Variability
    description: str
    unit: str | None = None
    start: float | int | bool | None = None
    initial: Literal["exact", "calculated", "approx"] | None = None
    size: int = 1
    """Array length; FMI 2 gets scalars ``name[1]..name[size]`` with consecutive
    value references, FMI 3 one array variable."""
    c_name: str = field(default="")
    """Enumerator stem in ``djl_vars.h`` (defaults to the upper-cased name)."""
    min: float | int | None = None
    """Declared minimum (inclusive, as FMI's ``min``)."""
    max: float | int | None = None
    """Declared maximum (inclusive)."""
    min_exclusive: bool = False
    """The minimum itself is refused (``> min``): FMI's ``min`` is inclusive, so the model
    description declares ``min`` and the description says "> min"."""
    declared_type: str | None = None
    """Enumeration type of an Enumeration variable (a key of :data:`ENUMERATIONS`)."""

    @property
    def quantity(self) -> str | None:
        """Declared Real type (and ``quantity``) of the variable, from its unit."""
        if self.type != "Real" or self.causality == "independent":
            return None
        return QUANTITY_OF_UNIT.get(self.unit or "")

    @property
    def enum(self) -> str:
        """Name of the value-reference enumerator in C."""
        return "VR_" + (self.c_name or self.name.upper())


def _p(name, vr, typ, start, desc, unit=None, size=1, c_name="", min=None, max=None,
       declared_type=None, positive=False):
    if positive:
        min = 0.0
    return Variable(name, vr, typ, "parameter", "fixed", desc, unit, start, "exact", size, c_name,
                    min, max, positive, declared_type)


def _o(name, vr, typ, desc, unit=None, c_name="", variability="discrete", min=None, max=None):
    return Variable(name, vr, typ, "output", variability, desc, unit, None, "calculated", 1, c_name,
                    min, max)


def _i(name, vr, typ, start, desc, unit=None, variability="discrete", min=None, max=None,
       positive=False, size=1, declared_type=None):
    if positive:
        min = 0.0
    return Variable(name, vr, typ, "input", variability, desc, unit, start, None, size, "", min,
                    max, positive, declared_type)


def _c(name, vr, typ, desc, unit=None, min=None, max=None):
    return Variable(name, vr, typ, "calculatedParameter", "fixed", desc, unit, None, "calculated",
                    1, "", min, max)


VARIABLES: tuple[Variable, ...] = (
    Variable("time", 0, "Real", "independent", "continuous", "Simulation time", "s",
             c_name="TIME"),
    # --- parameters (issue #2 contract) ---------------------------------------
    _p("profile", 1, "Enumeration", 3, "Profile: 1 = AL (acceleration-limited), 2 = JL "
       "(jerk-limited, one jerk time T_F1), 3 = DJL (dissociated jerk-limited, jerk times "
       "T_F1..T_F4), 4 = table (the jerk table_jerk[i] for table_samples[i] samples, i <= "
       "table_n, replayed from x0; it must end at rest at x0 + distance)", min=1, max=4,
       declared_type="Profile"),
    _p("Te", 2, "Real", DEFAULT_TE, "Sampling period of the generator (any communication step "
       "is accepted: outputs are the profile's exact values at the communication point)",
       "s", c_name="TE", positive=True, max=MAX_TE),
    _p("t_start", 3, "Real", 0.0, "Time at which the motion starts (at the first sample of the "
       "generator, FMU start time + k Te, at or after it)", "s"),
    _p("x0", 4, "Real", 0.0, "Start position", "m", min=-MAX_POSITION, max=MAX_POSITION),
    _p("distance", 5, "Real", 0.4, "Signed length of a single-segment move (n_segments = 0)", "m",
       min=-MAX_POSITION, max=MAX_POSITION),
    _p("v_max", 6, "Real", 1.0, "Velocity limit (magnitude, > 0)", "m/s", positive=True),
    _p("a_max", 7, "Real", 10.0, "Acceleration limit (magnitude, speeding up, > 0)", "m/s2",
       positive=True),
    _p("d_max", 8, "Real", 10.0, "Deceleration limit (magnitude, slowing down, > 0)", "m/s2",
       positive=True),
    _p("T_F1", 9, "Real", 0.08, "Jerk time of stage 1 (start of acceleration); JL uses it for "
       "all four stages; at least Te/2", "s", positive=True),
    _p("T_F2", 10, "Real", 0.08, "Jerk time of stage 2 (end of acceleration), DJL", "s",
       positive=True),
    _p("T_F3", 11, "Real", 0.06, "Jerk time of stage 3 (start of deceleration), DJL", "s",
       positive=True),
    _p("T_F4", 12, "Real", 0.05, "Jerk time of stage 4 (end of deceleration), DJL", "s",
       positive=True),
    # --- outputs (issue #2 contract) ------------------------------------------
    _o("x", 13, "Real", "Reference position", "m", variability="continuous"),
    _o("v", 14, "Real", "Reference velocity", "m/s", variability="continuous"),
    _o("a", 15, "Real", "Reference acceleration", "m/s2", variability="continuous"),
    _o("j", 16, "Real", "Reference jerk over the sample interval that contains now (0 for AL)",
       "m/s3"),
    _o("done", 17, "Boolean", "True once the motion, filters included, has ended "
       "(with a shaper: its last delayed copy)"),
    # --- extensions -----------------------------------------------------------
    _p("v0", 20, "Real", 0.0, "Start velocity (the axis moves at v0 before t_start)", "m/s"),
    _p("v_e", 21, "Real", 0.0, "End velocity of a single-segment move (n_segments = 0)", "m/s"),
    _p("short_stage", 22, "Enumeration", 1, "Acceleration/deceleration stage shorter than its "
       "jerk times: 1 = stretch it so that every constant-jerk stage lasts its jerk time (lower "
       "acceleration); 2 = let the two ramps overlap as in the paper (shorter stages, lower peak "
       "acceleration; DJL merges a phase's jerk times when T_1 or T_3 would be negative)",
       min=1, max=2, declared_type="ShortStage"),
    _p("n_segments", 23, "Integer", 0, "0: single move given by distance and v_e; 1..32: "
       "multi-segment move given by seg_distance[1..n] and seg_v_end[1..n]", min=0,
       max=MAX_SEGMENTS),
    _o("x_AL", 30, "Real", "Acceleration-limited profile before the FIR filters: position "
       "(starts at x0)", "m", variability="continuous"),
    _o("v_AL", 31, "Real", "Acceleration-limited profile before the FIR filters: velocity", "m/s",
       variability="continuous"),
    _o("a_AL", 32, "Real", "Acceleration-limited profile before the FIR filters: acceleration "
       "over the sample interval that contains now", "m/s2"),
    _o("segment", 33, "Integer", "1-based segment of the AL profile now; 0 before t_start",
       min=0, max=MAX_SEGMENTS),
    # --- commanded generator (issue #12) ----------------------------------------
    _o("busy", 34, "Boolean", "True while a move is planned and not finished (not done)"),
    _o("stage", 35, "Integer", "Constant-jerk stage in progress: 1 start of acceleration, 2 end "
       "of acceleration, 3 start of deceleration, 4 end of deceleration; 0 when none",
       min=0, max=4),
    _p("jerk_source", 24, "Enumeration", 1, "Jerk times: 1 = the parameters T_F1..T_F4; 2 = "
       "from the input f_mode, each constant-jerk stage's jerk time being round(1/(f_mode Te)) "
       "samples read when the stage starts; 3 = the same with f_mode extrapolated at its rate "
       "of change to the stages still to come (JL or DJL, n_segments = 0, v_e = 0)", min=1,
       max=3, declared_type="JerkSource"),
    _i("target", 50, "Real", 0.0, "Target position of the next execute command (absolute); "
       "any value is accepted when set, a command to one that is not finite or beyond 1e300 m "
       "is refused at its edge (cmd_error)", "m"),
    _i("execute", 51, "Boolean", False, "Rising edge: move from the current state (any velocity "
       "and acceleration) to target, ending at rest; a move in progress is replaced (with "
       "buffer_mode = 1 or 2 the command waits its turn instead)"),
    _i("stop", 52, "Boolean", False, "Rising edge: come to rest with d_max and the stages' jerk "
       "times (wins over execute at the same step); the axis then waits for execute"),
    _i("f_mode", 53, "Real", 10.0, "Frequency of the vibration mode, used when jerk_source = 2 "
       "(its period is the jerk time of the stages that start), when jerk_source = 3 (the same, "
       "f_mode extrapolated at its rate of change to the stages still to come) and when "
       "shaper_source = 2 (its phase times the shaper's impulses); ignored otherwise", "Hz",
       variability="continuous", positive=True),
    _c("motion_time", 40, "Real", "Duration of the motion, filters included (ends at "
       "t_start + motion_time); with a shaper, until its last delayed copy ends (the "
       "shaper's largest delay added)", "s"),
    _c("N_F1", 41, "Integer", "Jerk time of stage 1 in samples, round(T_F1/Te) (0 for AL)",
       min=0, max=MAX_FILTER_SAMPLES),
    _c("N_F2", 42, "Integer", "Jerk time of stage 2 in samples (JL: N_F1)", min=0,
       max=MAX_FILTER_SAMPLES),
    _c("N_F3", 43, "Integer", "Jerk time of stage 3 in samples (JL: N_F1)", min=0,
       max=MAX_FILTER_SAMPLES),
    _c("N_F4", 44, "Integer", "Jerk time of stage 4 in samples (JL: N_F1)", min=0,
       max=MAX_FILTER_SAMPLES),
    _c("v_reached", 45, "Real", "Largest peak velocity of the planned segments (magnitude)",
       "m/s"),
    _c("a_reached", 46, "Real", "Largest acceleration level of the planned stages (the "
       "Appendix's recomputed a_max)", "m/s2"),
    _c("d_reached", 47, "Real", "Largest deceleration level of the planned stages (the "
       "Appendix's recomputed d_max)", "m/s2"),
    _p("seg_distance", 100, "Real", 0.0, "Signed length of each segment", "m", size=MAX_SEGMENTS,
       min=-MAX_POSITION, max=MAX_POSITION),
    _p("seg_v_end", 200, "Real", 0.0, "Velocity at the end of each segment (the last one is the "
       "end velocity of the motion)", "m/s", size=MAX_SEGMENTS),
    # --- input shaping (issue #18) ----------------------------------------------
    _p("shaper", 60, "Enumeration", 0, "Input shaper applied to the planned profile p: x, v, a, j "
       "become sum A_i p(t - t_i) (x_AL, v_AL, a_AL, segment and stage stay those of p): 0 = "
       "none, 1 = ZV, 2 = ZVD, 3 = EI (5 % tolerance), 4 = custom (shaper_n, "
       "shaper_amplitude, shaper_delay)", min=0, max=4, declared_type="Shaper"),
    _p("f_shaper", 61, "Real", 10.0, "Frequency of the mode the ZV, ZVD and EI shapers are "
       "designed for (shaper_source = 1), > 0; with shaper = 4 and shaper_source = 2, the "
       "frequency the delays shaper_delay are given for", "Hz", positive=True),
    _p("zeta_shaper", 62, "Real", 0.0, "Damping ratio of the mode the ZV, ZVD and EI shapers are "
       "designed for, in [0, 1)", min=0.0, max=1.0),
    _p("shaper_source", 63, "Enumeration", 1, "Timing of the impulses: 1 = for f_shaper; 2 = from "
       "the input f_mode, each delay being the time over which the mode's phase advanced by "
       "the impulse's share of a period (a time-varying shaper)", min=1, max=2,
       declared_type="ShaperSource"),
    _p("shaper_n", 64, "Integer", 1, "Number of impulses of the custom shaper (shaper = 4), "
       f"1..{MAX_SHAPER_IMPULSES}", min=1, max=MAX_SHAPER_IMPULSES),
    _p("shaper_amplitude", 300, "Real", 0.0, "Amplitude of each impulse of the custom shaper "
       f"(shaper_amplitude[1..shaper_n] sum to 1 within {SHAPER_AMPLITUDE_TOLERANCE:g}; a "
       "negative one is accepted with a warning: the limits then do not hold)",
       size=MAX_SHAPER_IMPULSES),
    _p("shaper_delay", 400, "Real", 0.0, "Delay of each impulse of the custom shaper, >= 0, at "
       f"most {MAX_SHAPER_DELAY_SAMPLES} samples of Te (with shaper_source = 2: the delay at "
       "f_shaper, scaled to f_mode)", "s", size=MAX_SHAPER_IMPULSES, min=0.0),
    # --- replayed table (issue #33) ------------------------------------------------
    _p("table_n", 65, "Integer", 0, f"Pieces of the table replayed by profile = 4, 0..{MAX_TABLE}",
       min=0, max=MAX_TABLE),
    _p("table_samples", 1000, "Integer", 1, "Length of each piece of the table (profile = 4), "
       f"in samples of Te, 1..{MAX_FILTER_SAMPLES}", size=MAX_TABLE, min=1,
       max=MAX_FILTER_SAMPLES),
    _p("table_jerk", 2000, "Real", 0.0, "Jerk over each piece of the table (profile = 4), at "
       "most (a_max + d_max)/Te in magnitude; the table must keep the speed within v_max and the "
       "acceleration within [-d_max, a_max] (mirrored for distance < 0) and end at rest at x0 + "
       "distance", "m/s3", size=MAX_TABLE),
    # --- per-command values and command errors (issue #34) -------------------------
    _i("cmd_v_max", 70, "Real", 0.0, "Velocity limit of the move commanded by execute (latched "
       "at its rising edge; at a stop edge, of the stop); 0 = the parameter v_max (a stop: the "
       "stopped move's)", "m/s"),
    _i("cmd_a_max", 71, "Real", 0.0, "Acceleration limit of the commanded move (latched as "
       "cmd_v_max); 0 = a_max (a stop: the stopped move's)", "m/s2"),
    _i("cmd_d_max", 72, "Real", 0.0, "Deceleration limit of the commanded move or stop (latched "
       "as cmd_v_max); 0 = d_max (a stop: the stopped move's)", "m/s2"),
    _i("cmd_profile", 73, "Enumeration", 0, "Profile of the commanded move or stop (latched as "
       "cmd_v_max): 0 = the parameter's (a stop: the stopped move's), 1 = AL, 2 = JL "
       "(cmd_T_F[1]), 3 = DJL (cmd_T_F[1..4]); another value is refused at the edge (cmd_error)",
       min=0, max=3, declared_type="CmdProfile"),
    _i("cmd_T_F", 500, "Real", 0.0, "Jerk times of the stages of the commanded move or stop "
       "(latched as cmd_v_max); an element 0 = the parameter T_Fi (a stop: the stopped move's); "
       "JL uses the first", "s", size=4),
    _i("cmd_shaper", 74, "Enumeration", 0, "Input shaper of the commanded move (latched at the "
       "execute edge; a stop keeps the move's): 0 = the parameter's design, 1 = ZV, 2 = ZVD, "
       "3 = EI (for f_shaper), 4 = custom (cmd_shaper_n, cmd_shaper_amplitude, "
       "cmd_shaper_delay), 5 = none; another shaper than the one in force only from rest "
       "(done and v = 0); another value is refused at the edge (cmd_error)", min=0, max=5,
       declared_type="CmdShaper"),
    _i("cmd_shaper_n", 75, "Integer", 0, "Impulses of the custom shaper of the commanded move "
       f"(cmd_shaper = 4), 1..{MAX_SHAPER_IMPULSES}; 0 = the parameters' custom design "
       "(shaper_n, shaper_amplitude, shaper_delay)"),
    _i("cmd_shaper_amplitude", 600, "Real", 0.0, "Amplitude of each impulse of the commanded "
       "move's custom shaper (cmd_shaper = 4, cmd_shaper_n > 0; they sum to 1 within "
       f"{SHAPER_AMPLITUDE_TOLERANCE:g})", size=MAX_SHAPER_IMPULSES),
    _i("cmd_shaper_delay", 700, "Real", 0.0, "Delay of each impulse of the commanded move's "
       f"custom shaper (cmd_shaper = 4, cmd_shaper_n > 0), >= 0, at most "
       f"{MAX_SHAPER_DELAY_SAMPLES} samples of Te", "s", size=MAX_SHAPER_IMPULSES),
    # --- buffer modes and synchronisation (issue #34 items 2 and 4) ------------------
    _i("buffer_mode", 78, "Enumeration", 0, "How the command of an execute edge (latched with "
       "it) takes over: 0 = aborting (the move in progress and every waiting command are "
       "replaced), 1 = buffered (it waits until the move in progress and the commands before "
       "it have ended, shaper copies included, then starts from rest), 2 = blending (it "
       "waits as buffered, but the move before it passes its target without stopping: at the "
       "lower of the two moves' v_max, or the highest speed both can pass it at; "
       "docs/generator.md, \"Buffer modes\"); another value is refused at the edge "
       "(cmd_error)", min=0, max=2, declared_type="BufferMode"),
    _i("min_duration", 79, "Real", 0.0, "Shortest duration of the commanded move, from its "
       "start to its end (shaper copies included), latched at the execute edge: the move's "
       "velocity limit is lowered (the fastest move lasting at least this); 0 = none; wire "
       "another instance's time_to_rest to it to end together", "s"),
    _o("active", 80, "Boolean", "True while the last command accepted (an execute) is the one "
       "moving: started, not yet ended (shaper copies included)"),
    _o("command_aborted", 81, "Boolean", "True once a move still in progress or waiting "
       "commands were discarded by an aborting execute or a stop; an execute edge that "
       "discards nothing clears it"),
    _o("queue_length", 82, "Integer", "Commands waiting (buffered or blending) behind the move "
       f"in progress, 0..{QUEUE_CAPACITY}", min=0, max=QUEUE_CAPACITY),
    _o("time_to_rest", 83, "Real", "Time from now until the move in progress ends (shaper "
       "copies included; a move blending into the next: until it passes its target); 0 at "
       "rest.  Wired to another instance's min_duration, the two end together", "s"),
    _o("cmd_error", 76, "Boolean", "True when the last command (execute or stop edge) was "
       "refused: its values were invalid; the move in progress and every other value are "
       "untouched, the step returns OK; the next valid command clears it"),
    _o("cmd_error_id", 77, "Integer", "Why the last command was refused (docs/generator.md, "
       "\"Command errors\"); 0 when cmd_error is false", min=0, max=len(CMD_ERRORS)),
)

PARAMETERS = tuple(v for v in VARIABLES if v.causality == "parameter")
INPUTS = tuple(v for v in VARIABLES if v.causality == "input")
OUTPUTS = tuple(v for v in VARIABLES if v.causality == "output")
CALCULATED = tuple(v for v in VARIABLES if v.causality == "calculatedParameter")
BY_NAME = {v.name: v for v in VARIABLES}


FMI2_ENUM_ALIAS_SUFFIX = "_code"
"""Suffix of the FMI 2 Integer alias of each Enumeration parameter (``profile_code``, ...)."""


def fmi2_integer_aliases() -> tuple[Variable, ...]:
    """Integer aliases of the Enumeration parameters and inputs (FMI 2 model description only).

    ``profile_code`` .. ``shaper_source_code``, and for the inputs ``cmd_profile_code`` and
    ``cmd_shaper_code``.  Some FMI 2 importers (those built on the FMI Library: libcosim,
    ecos) skip Enumeration variables, so ``profile``, ``short_stage``, ``jerk_source``,
    ``shaper``, ``shaper_source``, ``cmd_profile`` and ``cmd_shaper`` could not be set
    there.  FMI 2.0 (section 2.2.7, ``valueReference``) makes a value reference unique per
    base type "Real, Integer/Enumeration, Boolean, String" except for alias variables: an
    Integer with the value reference of an Enumeration is an alias of it, the same value
    read and written with ``fmi2SetInteger`` / ``fmi2GetInteger``.  Each alias is
    ``<name>_code``, declared after every other variable (the indices of
    ``<ModelStructure>`` do not move); FMI 3 has none (its ``<Alias>`` keeps the type).
    """
    out = []
    for v in VARIABLES:
        if v.type != "Enumeration" or v.causality not in ("parameter", "input"):
            continue
        items = ", ".join(f"{value} = {item}" for item, value, _ in ENUMERATIONS[v.declared_type])
        desc = (f"Integer alias of the Enumeration {v.name} (same value reference), for "
                f"importers that skip FMI 2 Enumeration variables: {items}")
        out.append(Variable(v.name + FMI2_ENUM_ALIAS_SUFFIX, v.vr, "Integer", v.causality,
                            v.variability, desc, None, v.start, v.initial, 1,
                            min=v.min, max=v.max))
    return tuple(out)


def fmi2_scalars(var: Variable) -> list[tuple[str, int]]:
    """FMI 2 scalar names and value references of ``var`` (arrays are unrolled)."""
    if var.size == 1:
        return [(var.name, var.vr)]
    return [(f"{var.name}[{i + 1}]", var.vr + i) for i in range(var.size)]


def _fingerprint() -> str:
    payload = json.dumps(
        {"id": MODEL_IDENTIFIER, "version": MODEL_VERSION,
         "vars": [asdict(v) for v in VARIABLES]},
        sort_keys=True,
    )
    return hashlib.sha256(payload.encode()).hexdigest()


INSTANTIATION_TOKEN = "{" + str(uuid.uuid5(uuid.NAMESPACE_URL, "djl-fmu:" + _fingerprint())) + "}"
"""FMI 2 ``guid`` and FMI 3 ``instantiationToken``: derived from the variable
list, so it changes whenever the interface does.  Written into the model
descriptions and ``djl_vars.h`` by codegen: this is its only definition."""
