/*
 * djl_core.h -- sampled AL / JL / DJL trajectory generator (no FMI code).
 *
 * Béarée & Olabi 2013, "Dissociated jerk-limited trajectory applied to
 * time-varying vibration reduction", §2 and Appendix.
 *
 * Semantics (docs/generator.md has the derivations):
 *  - The acceleration-limited (AL) profile is a sum of acceleration steps A_m
 *    at whole samples tau_m.  Each step is filtered by its own moving average
 *    of N_m samples (N_m = 0: unfiltered).  A filtered step is a ramp of
 *    constant jerk A_m / (N_m Te) lasting N_m samples, so the generated
 *    profile is piecewise cubic with a jerk that is constant on every sample
 *    interval.  Outputs are the exact values of that profile: nothing is
 *    accumulated sample after sample, hence no rounding drift and a cost per
 *    sample that does not depend on the jerk times.
 *  - The whole motion is planned at initialisation into at most
 *    DJL_MAX_PIECES constant-jerk pieces (fixed-size arrays, no allocation).
 *
 * Units: SI (m, s, m/s, m/s^2, m/s^3).  Times inside a plan are counted in
 * samples of Te.
 */
#ifndef DJL_CORE_H
#define DJL_CORE_H

#include <stdint.h>

#if defined(__GNUC__) && __GNUC__ >= 4
/* Nothing of the core is exported from the FMU's shared library. */
#pragma GCC visibility push(hidden)
#endif

#ifdef __cplusplus
extern "C" {
#endif

#define DJL_MAX_SEGMENTS 32
#define DJL_MAX_STEPS (4 * DJL_MAX_SEGMENTS)
#define DJL_MAX_PIECES (2 * DJL_MAX_STEPS + DJL_MAX_SEGMENTS + 2)
/* Pieces of a replayed table (profile 4, djl_plan_table): its plan holds one piece per
 * entry and the rest at its end, DJL_MAX_TABLE + 1 <= DJL_MAX_PIECES. */
#define DJL_MAX_TABLE 256
/* Steps a plan records: a planned motion's (DJL_MAX_STEPS), a table's (one ramp per
 * entry, DJL_MAX_TABLE), or a replanned move's (the ramps still running, the steps that
 * end a stage or stop, and those of the new move), and a margin of 8. */
#define DJL_MAX_PLAN_STEPS ((DJL_MAX_TABLE > DJL_MAX_STEPS ? DJL_MAX_TABLE : DJL_MAX_STEPS) + 8)
/* A table's plan fits (compile-time check). */
typedef char djl_table_fits[(DJL_MAX_TABLE + 1 <= DJL_MAX_PIECES &&
                             DJL_MAX_TABLE <= DJL_MAX_PLAN_STEPS) ? 1 : -1];
/* Longest filter accepted, in samples. */
#define DJL_MAX_FILTER_SAMPLES 100000000
/* Longest motion accepted, in samples (keeps every sample index exact in a double). */
#define DJL_MAX_MOTION_SAMPLES 1000000000000000LL
/* Latest sample a replanned motion may end at: a replan at the FMU's horizon
 * (DJL_MAX_MOTION_SAMPLES) followed by a motion as long, and the ramps of a
 * transition; a replan that would end later is refused (a stop at a d_max too
 * low to stop in that time).  Still exact in a double. */
#define DJL_MAX_PLAN_END (2 * DJL_MAX_MOTION_SAMPLES + 4LL * DJL_MAX_FILTER_SAMPLES)
/* Largest |x0| + sum of |distance| accepted, m (every value of a plan stays finite). */
#define DJL_MAX_POSITION 1e300
/* Smallest magnitude accepted for Te, v_max, a_max, d_max, the jerk times and
 * a non-zero distance: the smallest normal double, DBL_MIN.  A subnormal value
 * has too few significant digits to be planned exactly.  (A subnormal speed
 * is accepted: next to v_max it is 0.) */
#define DJL_MIN_MAGNITUDE 2.2250738585072014e-308

typedef enum {
    DJL_PROFILE_AL = 1,
    DJL_PROFILE_JL = 2,
    DJL_PROFILE_DJL = 3,
    DJL_PROFILE_TABLE = 4 /* piecewise-constant jerk replayed from a djl_table (djl_plan_table) */
} djl_profile;

/* What to do when an acceleration or deceleration stage of the AL profile is
 * shorter than the jerk times that shape it. */
typedef enum {
    /* Lengthen the stage (lowering its acceleration) so that no two ramps of a
     * stage overlap: every constant-jerk stage lasts exactly its jerk time. */
    DJL_SHORT_STRETCH = 1,
    /* The paper: keep T_a / T_d, let the two ramps overlap (the peak
     * acceleration drops, the jerk never exceeds a/T_F); in DJL, a phase whose
     * T_1 (T_3) would be negative uses one jerk time (T_F2 := T_F1,
     * T_F4 := T_F3). */
    DJL_SHORT_OVERLAP = 2
} djl_short_rule;

typedef enum {
    DJL_OK = 0,
    DJL_E_PARAM = 1,      /* a parameter is out of its domain */
    DJL_E_INFEASIBLE = 2, /* parameters valid one by one, but the motion cannot be planned */
    DJL_E_INTERNAL = 3    /* the planner's own checks failed (a bug: please report) */
} djl_status;

typedef struct {
    int32_t profile;     /* djl_profile */
    int32_t short_stage; /* djl_short_rule */
    double Te;           /* s, sampling period */
    double x0;           /* m, start position */
    double v0;           /* m/s, start velocity */
    double distance;     /* m, signed length of a single-segment move (n_segments == 0) */
    double v_e;          /* m/s, end velocity of a single-segment move (n_segments == 0) */
    double v_max, a_max, d_max; /* m/s, m/s^2, m/s^2 (magnitudes) */
    double T_F[4];       /* s, jerk times of the four stages (JL uses T_F[0]) */
    int32_t n_segments;  /* 0: single segment (distance, v_e); 1..DJL_MAX_SEGMENTS: the arrays below */
    double seg_distance[DJL_MAX_SEGMENTS]; /* m, signed */
    double seg_v_end[DJL_MAX_SEGMENTS];    /* m/s, signed */
} djl_params;

typedef struct {
    djl_status status;
    char param[40];    /* offending parameter, e.g. "T_F2" or "seg_v_end[3]" ("" if none) */
    double value;      /* its value */
    char message[640]; /* full sentence, names the parameter and the value */
} djl_error;

/* One constant-jerk piece, valid for samples k .. next piece's k. */
typedef struct {
    int64_t k;                /* first sample (relative to the motion start) */
    double x, v, a, j;        /* generated profile at k (x relative to x0); j constant over the piece */
    double x_al, v_al, a_al;  /* AL profile (filter input) at k (x_al relative to x0) */
    int32_t seg;              /* 1-based segment of the AL profile */
    int32_t stage;            /* constant-jerk stage of the ramp started last among those
                                 running over the piece (1..4), 0 if none runs */
} djl_piece;

/* One step of the AL profile: its acceleration A, filtered by a moving average
 * of N samples, is a ramp of jerk A / (N Te) from sample tau to tau + N. */
typedef struct {
    int64_t tau;   /* sample (relative to the plan's start; negative: before it) */
    double A;      /* m/s^2 */
    int32_t N;     /* filter length, samples (0: unfiltered) */
    int32_t stage; /* 1 start of acceleration, 2 end of acceleration, 3 start of
                      deceleration, 4 end of deceleration */
} djl_step;

/* What the planner decided for one segment (for logs and diagnostics). */
typedef struct {
    int64_t start;          /* first sample of the segment on the AL time line */
    int64_t n1, k, m;       /* samples: acceleration stage, cruise, deceleration stage */
    int32_t N[4];           /* filter lengths applied to the four steps (after any merge) */
    int32_t has_acc, has_dec;
    int32_t merged_acc, merged_dec; /* paper's fallback used (DJL_SHORT_OVERLAP) */
    int32_t branch;         /* 1 time-optimal; 2 two stages one way; 3 dip; 4 rounded to the
                               nearest sample (residual taken up elsewhere); 5 single stage
                               ending f of a sample late (see frac) */
    double frac;            /* branch 5: fraction of a sample */
    int64_t lead;           /* samples of cruise before the first stage (DJL multi-segment) */
    double v_peak;          /* m/s, signed */
    double a_level;         /* m/s^2, acceleration of the first stage (signed) */
    double d_level;         /* m/s^2, acceleration of the deceleration stage (signed) */
    double distance;        /* m, distance this segment was planned for (signed) */
} djl_segment_plan;

typedef struct {
    djl_params p;                 /* parameters the plan was made from */
    int32_t N[4];                 /* jerk times in samples (0 for AL) */
    int32_t n_segments;           /* number of segments actually planned (>= 1) */
    djl_segment_plan seg[DJL_MAX_SEGMENTS];
    int32_t n_pieces;
    djl_piece piece[DJL_MAX_PIECES]; /* the last piece starts at k_end and is constant-velocity */
    int64_t k_end;                /* samples from the start until the motion (filters included) has ended */
    double x_target;              /* m, x0 + total distance */
    double v_target;              /* m/s, requested end velocity */
    double v_reached, a_reached, d_reached; /* largest |v_peak|, acceleration and deceleration levels */
    /* The AL steps of the plan (what a replan keeps of it): every step of a
     * planned motion; for a replanned one (djl_replan) the ramps that were still
     * running at the command and the steps placed since.  level0 is the AL
     * acceleration of the steps not listed (0 for a planned motion). */
    int32_t n_steps;
    int32_t replanned;            /* 0: planned from p by djl_plan_motion; 1: by djl_replan */
    double level0;
    djl_step step[DJL_MAX_PLAN_STEPS];
} djl_plan;

typedef struct {
    double x, v, a, j;       /* generated profile */
    double x_al, v_al, a_al; /* AL profile before filtering */
    int32_t done;            /* 1 once the motion, filters included, has ended */
    int32_t segment;         /* 1-based segment of the AL profile at this time, 0 before the start */
    int32_t stage;           /* constant-jerk stage in progress (1..4), 0 when none */
} djl_sample;

/* Default parameters (a 0.4 m DJL move). */
void djl_params_default(djl_params *p);

/* Check every parameter; on error fill err (if not NULL) and return DJL_E_PARAM. */
djl_status djl_validate(const djl_params *p, djl_error *err);

/* Validate and plan.  On success the plan is complete and self-checked. */
djl_status djl_plan_motion(const djl_params *p, djl_plan *plan, djl_error *err);

/* Evaluate the planned profile at u samples after the motion start (u may be
 * negative or fractional).  *cursor is a piece index hint kept between calls
 * (start with 0); evaluation cost is O(1) for monotone times. */
void djl_eval(const djl_plan *plan, double u, int32_t *cursor, djl_sample *out);

/* The same, as the limit from the left at u (the piece in force just before u: its jerk,
 * its acceleration at u; before the start, u <= 0, the rest or cruise at v0); done once
 * u > the motion end.  Equal to djl_eval wherever the profile is continuous (x, v, and a
 * but for AL at a step). */
void djl_eval_left(const djl_plan *plan, double u, int32_t *cursor, djl_sample *out);

/* Jerk time actually applied to stage i (0..3) in seconds (N * Te). */
double djl_applied_jerk_time(const djl_plan *plan, int stage);

/* Motion duration (filters included), s. */
double djl_motion_time(const djl_plan *plan);

const char *djl_status_name(djl_status s);

/* ------------------------------------------------------------------------ */
/* a replayed table (djl_table.c; docs/generator.md, "Replayed tables")       */

/* The end state of a table is accepted within this of the table's own scale (its largest
 * acceleration, velocity, travel), and then set exactly to rest at the target. */
#define DJL_TABLE_END_TOLERANCE 1e-9
/* The table's velocity and acceleration may exceed the limits by this much of each limit
 * (rounding); the outputs, evaluated anywhere, then stay within 1e-9 of them. */
#define DJL_TABLE_LIMIT_TOLERANCE 1e-10

/* Profile 4: the jerk table_jerk[i] held for table_samples[i] samples of Te, i < n, from
 * the motion's start at x0 (with v0, acceleration 0).  The FMU's parameters table_n,
 * table_samples, table_jerk. */
typedef struct {
    int32_t n;                      /* pieces, 0..DJL_MAX_TABLE */
    int32_t samples[DJL_MAX_TABLE]; /* samples of Te of each piece, 1..DJL_MAX_FILTER_SAMPLES */
    double jerk[DJL_MAX_TABLE];     /* m/s^3 over each piece */
} djl_table;

/* Start values: n = 0, samples 1, jerk 0. */
void djl_table_default(djl_table *t);

/* Check p (djl_validate: profile 4 needs n_segments = 0 and v_e = 0) and the table t: n in
 * range, each piece's samples and jerk (finite, |jerk| <= (a_max + d_max) / Te), the
 * motion within v_max and [-d_max, a_max] (mirrored for distance < 0) up to
 * DJL_TABLE_LIMIT_TOLERANCE, ending at rest at x0 + distance within DJL_TABLE_END_TOLERANCE.
 * DJL_E_PARAM naming the parameter (e.g. "table_jerk[3]", 1-based) and its value. */
djl_status djl_table_validate(const djl_params *p, const djl_table *t, djl_error *err);

/* Validate and plan p->profile = DJL_PROFILE_TABLE from t: one piece per entry (its jerk
 * exactly table_jerk[i]; x, v, a integrated exactly from the start) and the rest at the
 * end, at x0 + distance exactly; one step per entry (a ramp of A = jerk samples Te over
 * samples: a replan keeps them as any plan's); N[] the jerk times of p (those of a
 * commanded stop or move).  djl_plan_motion refuses profile 4. */
djl_status djl_plan_table(const djl_params *p, const djl_table *t, djl_plan *plan,
                          djl_error *err);

/* Whether plan is the one djl_plan_table makes from p and t (not replanned): the steps
 * those of the table, bit for bit, the pieces' starts, jerks and end.  NULL if so, else
 * why not (for checking an FMU state). */
const char *djl_table_plan_flaw(const djl_plan *plan, const djl_params *p, const djl_table *t);

/* ------------------------------------------------------------------------ */
/* the motion on a sample grid (djl_eval.c)                                  */

/* A generator samples at start_time + k Te (k whole).  The motion starts at the
 * first of those samples at or after t_start; a t_start within rounding of a
 * sample counts as on it: within 1e-9 of its offset (1 + |offset| samples), or
 * within 4 ulp of the larger of |t_start| and |start_time| (what they resolve
 * at their magnitude: 2.4e-7 s at 1.7e9 s).
 *
 * djl_check_t_start: t_start (and the start time) finite, else DJL_E_PARAM
 * naming t_start.
 *
 * djl_start_offset: that check, then the sample: *offset = k (a whole number,
 * |k| <= 1e15; the motion's sample u = 0 is the grid's sample k) and *shifted
 * = 1 when t_start was not on the grid (moved to the next sample), 0 when it
 * was.  DJL_E_PARAM naming t_start when it lies more than 1e15 samples away;
 * naming Te when Te is not a finite number > 0 (a valid plan's is).  On error
 * *offset and *shifted are left as they were. */
djl_status djl_check_t_start(double t_start, double start_time, djl_error *err);
djl_status djl_start_offset(double t_start, double start_time, double Te, double *offset,
                            int *shifted, djl_error *err);

/* ------------------------------------------------------------------------ */
/* input shaping (djl_shaper.c; docs/generator.md, "Input shaping")          */

/* Impulses of a custom shaper, at most. */
#define DJL_MAX_SHAPER_IMPULSES 8
/* Longest delay of an impulse, samples of Te: the past of the profile that the
 * delayed copies read is kept that far back (djl_shaper_memory). */
#define DJL_MAX_SHAPER_DELAY_SAMPLES 4096
/* A custom shaper's amplitudes must sum to 1 within this. */
#define DJL_SHAPER_SUM_TOLERANCE 1e-9
/* Vibration tolerance of the EI shaper (5 %). */
#define DJL_SHAPER_EI_VTOL 0.05
/* With shaper_source = 2, the most periods of f_mode a sample may hold: f_mode <= 2 / Te
 * (its period at least Te/2, as with jerk_source 2 and 3), so that the phase over the
 * memory's window stays small (issue 21: f_mode = DBL_MAX made it infinite). */
#define DJL_SHAPER_MAX_PHASE_RATE 2.0
/* Entries of each ring of djl_shaper_memory (at most one per sample of the
 * window DJL_MAX_SHAPER_DELAY_SAMPLES + 2, and a margin). */
#define DJL_SHAPER_RING (DJL_MAX_SHAPER_DELAY_SAMPLES + 8)

typedef enum {
    DJL_SHAPER_NONE = 0,
    DJL_SHAPER_ZV = 1,  /* [1, K] / (1 + K) at [0, Td/2] */
    DJL_SHAPER_ZVD = 2, /* [1, 2K, K^2] / (1 + K)^2 at [0, Td/2, Td] */
    DJL_SHAPER_EI = 3,  /* [(1+V)/4, (1-V)/2 K, (1+V)/4 K^2] normalised, at [0, Td/2, Td] */
    DJL_SHAPER_CUSTOM = 4
} djl_shaper_kind;

typedef enum {
    DJL_SHAPER_SOURCE_F_SHAPER = 1, /* impulses timed for the parameter f_shaper */
    DJL_SHAPER_SOURCE_F_MODE = 2    /* timed by the phase of the input f_mode */
} djl_shaper_source;

/* The shaper's parameters (the FMU's shaper, f_shaper, zeta_shaper, shaper_source,
 * shaper_n, shaper_amplitude, shaper_delay). */
typedef struct {
    int32_t kind;    /* djl_shaper_kind */
    int32_t source;  /* djl_shaper_source */
    double f;        /* Hz */
    double zeta;
    int32_t n;       /* custom: impulses */
    double amplitude[DJL_MAX_SHAPER_IMPULSES];
    double delay[DJL_MAX_SHAPER_IMPULSES]; /* s */
} djl_shaper_params;

/* A shaper designed from its parameters: the shaped output is
 *   y = c_0 + sum_{i>=1} A_i (c_i - c_0),   c_i = p(t - t_i)
 * for each of x, v, a, j (p the planned profile): the impulse 0 weighs
 * 1 - sum_{i>=1} A_i, so that the weights sum to 1 exactly and the output
 * rests exactly where p rests. */
typedef struct {
    int32_t n;        /* impulses (0: no shaping) */
    int32_t source;   /* djl_shaper_source */
    int32_t negative; /* 1 + the first impulse with a negative amplitude, 0 if none */
    int32_t pad;
    double f_design;  /* Hz: the frequency the delays t, d are for (f_shaper, or with
                         source 2 the f_mode of the design) */
    double A[DJL_MAX_SHAPER_IMPULSES];     /* amplitudes as designed (they sum to 1) */
    double t[DJL_MAX_SHAPER_IMPULSES];     /* s, delays (source 2: at f_design) */
    double d[DJL_MAX_SHAPER_IMPULSES];     /* samples of Te, t / Te */
    double phase[DJL_MAX_SHAPER_IMPULSES]; /* source 2: periods of f_mode each copy lags */
    double t_max, d_max;  /* the largest delay, s and samples */
    double phase_max;     /* the largest phase, periods */
} djl_shaper;

/* The past a shaped output reads (a commanded move: each replan keeps what the
 * delayed copies still need of the plan it replaces) and, with source 2, the
 * phase of f_mode: two rings, entries in time order, pointer-free. */
typedef struct {
    int64_t k;          /* grid sample at which the piece starts */
    double x, v, a, j;  /* the profile there (x absolute), j constant until the next entry */
} djl_past_piece;

typedef struct {
    int64_t k;     /* grid sample from which rate applies */
    double P;      /* periods of f_mode accumulated at k (from the first entry) */
    double rate;   /* periods per sample, f_mode Te (> 0) */
} djl_phase_point;

typedef struct {
    int32_t n_past, past_first;   /* live entries past[(past_first + i) % RING], i < n_past */
    int32_t n_phase, phase_first;
    djl_past_piece past[DJL_SHAPER_RING];
    djl_phase_point phase[DJL_SHAPER_RING];
} djl_shaper_memory;

/* Start values: no shaper, source 1, f = 10 Hz, zeta = 0, n = 1, arrays 0. */
void djl_shaper_params_default(djl_shaper_params *sp);

/* Check the shaper's parameters and design it for the sampling period Te; with
 * source 2 the delays t, d are those at f_mode (a constant f_mode: what
 * motion_time reports).  Parameters a kind does not use are not checked (kind 0
 * checks nothing else).  DJL_E_PARAM naming the parameter (or the input f_mode)
 * and its value; *out untouched on error. */
djl_status djl_shaper_design(const djl_shaper_params *sp, double Te, double f_mode,
                             djl_shaper *out, djl_error *err);

/* The shaped sample at u (samples of the plan, the plan starting at grid sample
 * offset): x, v, a, j of the shaped profile, done once every copy has ended;
 * x_AL, v_AL, a_AL, segment and stage those of the plan at u (djl_eval with
 * *cursor).  A copy at u - d_i < 0 with past pieces in mem reads them (the plan
 * then starts at a replan); mem may be NULL (a planned motion: the plan holds
 * every time).  left: limits from the left (djl_eval_left).  cursors: one hint
 * per impulse.  sh->n == 0: djl_eval (djl_eval_left) itself. */
void djl_shaper_eval(const djl_shaper *sh, const djl_plan *plan, double u, double offset,
                     const djl_shaper_memory *mem, int left, int32_t *cursor,
                     int32_t cursors[DJL_MAX_SHAPER_IMPULSES], djl_sample *out);

/* Motion time of the shaped output, s: the plan's, plus the largest delay. */
double djl_shaper_motion_time(const djl_plan *plan, const djl_shaper *sh);

/* Empty both rings. */
void djl_shaper_memory_clear(djl_shaper_memory *mem);

/* Before old (starting at grid sample offset) is replaced by a plan starting at its
 * sample o (whole): keep its pieces over [o - DJL_MAX_SHAPER_DELAY_SAMPLES - 2, o) not
 * kept yet.  Returns what djl_shaper_undo needs to take them back (the replan failed). */
int64_t djl_shaper_keep_past(djl_shaper_memory *mem, const djl_plan *old, double offset,
                             double o);
void djl_shaper_undo(djl_shaper_memory *mem, int64_t token);

/* Source 2: f_mode read at grid time s (samples) gives the phase rate (f_mode Te,
 * periods per sample) from the first sample at or after s on. */
void djl_shaper_phase_rate(djl_shaper_memory *mem, double s, double rate);

/* Source 2: whether a phase rate (f_mode Te, periods per sample) is one an accepted
 * f_mode gives: at most DJL_SHAPER_MAX_PHASE_RATE, and no delay of sh beyond the memory's
 * window (DJL_MAX_SHAPER_DELAY_SAMPLES), each up to rounding.  For checking a state. */
int djl_shaper_rate_ok(const djl_shaper *sh, double rate);

/* Structure of a memory (an FMU state's): NULL if sound, else why not. */
const char *djl_shaper_memory_flaw(const djl_shaper_memory *mem, const djl_shaper *sh);

/* ------------------------------------------------------------------------ */
/* replanning a move in progress (djl_replan.c)                              */

typedef enum { DJL_GOAL_TARGET = 1, DJL_GOAL_STOP = 2 } djl_goal_kind;

/* What a replan must do from sample b on. */
typedef struct {
    int32_t kind;   /* djl_goal_kind */
    double target;  /* m, absolute position to end at, at rest (DJL_GOAL_TARGET) */
    int32_t N[4];   /* jerk times of the stages to come, samples (all 0: AL) */
    int32_t keep_speed;    /* the new motion goes no faster than the old plan's peak (or
                              the axis now), if it can (new jerk times for the same target:
                              the landing is re-timed, a cruise is not raised) */
    int32_t no_stop_first; /* refuse (DJL_E_INFEASIBLE, *out untouched) a replan that would
                              stop and then come back (new jerk times that no longer land
                              from where the axis is: the caller keeps its plan), or a stop
                              that would rest past where the plan in progress rests */
    double v_max, a_max, d_max; /* limits of the stages placed from b on and of the new
                              motion (m/s, m/s2); 0: the old plan's.  Below the speed the
                              axis settles at, a new motion is preceded by a stop (its
                              d_max): the axis rests, then moves within v_max.  The new
                              plan's own limits (its p) are the larger of the old plan's and
                              these: its pieces hold the old plan's ramps. */
    double v_end;   /* m/s, signed: the new motion ends at the target moving at v_end (a
                       blend into the next move: it then cruises on at v_end from its end,
                       plan->v_target); 0: at rest.  DJL_GOAL_TARGET only; no fallback
                       that stops first (DJL_E_INFEASIBLE instead) */
} djl_goal;

/* What a replan decided (for logs and diagnostics). */
typedef struct {
    int64_t origin;     /* whole sample of the old plan the new one starts at (floor(u)) */
    int64_t b;          /* first sample whose steps may change (floor(u) + 1) */
    int64_t end_at;     /* sample of the step ending the stage in progress (-1: none) */
    int32_t how;        /* 1 new move after the stage in progress ends; 2 stop and then move;
                           3 stop */
    int32_t clipped;    /* the ending stage's jerk time was changed: 1 to stay within v_max,
                           2 (a stop) so that the axis rests without reversing */
    int32_t lengthened; /* ... lengthened, so as not to end before the ramp that started the
                           stage (still running at b) */
    double v_settled;   /* m/s, velocity once the ramps running have ended */
    int32_t kept;       /* a stop that would have rested past where *old rests (the target
                           of the move it stops): *old is kept (copied to *out), origin 0,
                           how 0 (with no_stop_first: DJL_E_INFEASIBLE instead) */
} djl_replan_info;

/* Replan the motion of *old at the (possibly fractional) time u, in samples
 * of old, towards goal: the outputs of *old up to the first sample after u,
 * b = floor(u) + 1, stay as they are (the jerk reported at u holds until b),
 * every ramp started before b finishes as started, the AL stage in progress
 * ends at b (or, speeding up towards the target, goes on as long as v_max and
 * the room to stop allow), and the rest is a new move planned from the state
 * reached, ending exactly at the target at rest (or at rest for a stop).  The
 * new plan, written to *out (which may be old), starts at sample origin =
 * floor(u) of the old one; scratch is work space.  A stop never rests past
 * where *old rests when that lies ahead (the target of the move it stops):
 * such a stop keeps *old instead (info->kept).  No allocation; bounded work. */
djl_status djl_replan(const djl_plan *old, double u, const djl_goal *goal, djl_plan *out,
                      djl_plan *scratch, djl_replan_info *info, djl_error *err);

/* Jerk times N (read from a frequency, each stage taking the value in force
 * when it starts): is a replan due for the samples after u up to u_end?
 * Returns 1 and *at (the time to replan at, djl_replan) when a stage still to
 * come was planned with another jerk time and either
 *  - now (allow_now) the axis cruises, rests or speeds up at a level of at
 *    least a_max / 2: *at = u (the stages to come are placed anew before they
 *    start), or
 *  - such a stage starts at a sample tau in (u, floor(u_end) + 1): *at = tau - 1
 *    (the first such stage).
 * Returns 0 otherwise. */
int djl_jerk_times_due(const djl_plan *plan, double u, double u_end, const int32_t N[4],
                       int allow_now, double *at);

#ifdef __cplusplus
}
#endif

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility pop
#endif

#endif /* DJL_CORE_H */
