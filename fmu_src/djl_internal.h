/*
 * djl_internal.h -- what the files of the generator core share (not part of
 * the public interface, djl_core.h; included by the core's .c files only).
 *
 * Map of the core (docs/generator.md, "Map of the core"):
 *   djl_validate.c  parameter checks (djl_validate), defaults, error messages
 *   djl_segment.c   one segment: its stages sized (size_stages) and its
 *                   landing solved, whole samples and exact distance
 *                   (solve_time_optimal, solve_monotone_or_dip,
 *                   solve_pinned_single_stage, solve_fit_peak_grid,
 *                   solve_split_sample)
 *   djl_motion.c    a motion of segments (djl_plan_motion): the segments
 *                   sized one after the other, the last one landed exactly,
 *                   the AL steps, the pieces of the plan, the retries
 *   djl_replan.c    a move in progress replanned (djl_replan): the ramps
 *                   started kept, the stage in progress ended, a new segment
 *                   planned from the state the ramps settle to; and when jerk
 *                   times read from a frequency call for it (djl_jerk_times_due)
 *   djl_eval.c      a sample of a plan (djl_eval); the sample of a grid at
 *                   which the motion starts (djl_start_offset)
 *
 * Functions shared between the files are declared DJL_INTERNAL: external and
 * hidden (the visibility pragma below), so the FMU exports none of them.
 * tests/c/core_libm.c compiles all the core's files in one unit with
 * DJL_INTERNAL defined as static.
 */
#ifndef DJL_INTERNAL_H
#define DJL_INTERNAL_H

#include "djl_core.h"
#include "djl_math.h" /* floor, sqrt, ... without libm (see there) */

#ifndef DJL_INTERNAL
#define DJL_INTERNAL
#endif

/* No contraction of a*b + c into a fused multiply-add, whatever the compiler's
 * default (GCC's GNU dialects, clang's fp-contract=on, any target with FMA): the
 * planner's exact landing is derived, and tested, for separately rounded products
 * and sums; with FMA contraction its self-check fails on some plans with jerk
 * times of 10^7 samples (tests/test_c_sanitizers.py builds the core with
 * -mfma -ffp-contract=fast to check this pragma). */
#if defined(__clang__)
#pragma STDC FP_CONTRACT OFF
#elif defined(__GNUC__)
#pragma GCC optimize("fp-contract=off")
#elif defined(_MSC_VER)
#pragma fp_contract(off)
#endif

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility push(hidden)
#endif

static inline double dmax2(double a, double b) { return a > b ? a : b; }
static inline double dmin2(double a, double b) { return a < b ? a : b; }
static inline int64_t imax2(int64_t a, int64_t b) { return a > b ? a : b; }

/* ------------------------------------------------------------------------ */
/* one segment (djl_segment.c), planned in its positive frame (distance >= 0,
 * velocities >= 0), times in samples                                        */

/* What a segment must do: the problem its stages are sized for. */
typedef struct {
    double D;           /* m, >= 0 */
    double vs, ve;      /* m/s, >= 0 */
    double vm, am, dm;  /* limits */
    double Te;
    int rule;           /* djl_short_rule */
    int last;           /* the motion ends with this segment */
    double tail_in;     /* samples the ramps of earlier segments run past this one's start */
    double g;           /* samples of cruise at vs before the first stage (DJL: wait for the
                           previous segment's ramps to end) */
    int merge23;        /* fallback branches: ramps 2 and 3 may coincide */
    int precise;        /* distance formulas relative to each stage (djl_plan_motion's retry) */
    int32_t N1, N2, N3, N4; /* filter (jerk time) of each stage, samples */
} segment_problem;

/* How it does it: the stages found (whole samples) and their levels. */
typedef struct {
    int ok;             /* a solution was found */
    int hasA, hasD;     /* the acceleration phase A, the deceleration phase D exist */
    int64_t n1, k, m;   /* samples of phase A, of the cruise, of phase D */
    int32_t N1, N2, N3, N4; /* the stages' filters, samples (after merges) */
    int mergedA, mergedD;   /* a phase too short for two jerk times uses one */
    double vp, al, dl;  /* peak velocity; accel of phase A (+ speeds up); decel of phase D (+ slows down) */
    double D;           /* distance covered (m) */
    int64_t g;          /* leading cruise, samples */
    double f;           /* branch 5: fraction of the split sample */
    int split, after;   /* branch 5: split at the stage's start (1) or end (0); cruise after (1) or before (0) */
    int64_t len;        /* samples of the segment on the AL time line */
    int64_t bend;       /* samples until the segment's staircase ends (len, or the motion end) */
    int branch;
} segment_solution;

/* ------------------------------------------------------------------------ */
/* error reporting (djl_validate.c)                                          */

/* Fill *e (if not NULL): status st, the parameter's name and value, the
 * message (printf format); returns st. */
DJL_INTERNAL djl_status set_error(djl_error *e, djl_status st, const char *param, double value,
                                  const char *fmt, ...);

/* ------------------------------------------------------------------------ */
/* the landing solvers of one segment (djl_segment.c): each sizes the stages
 * and solves the landing of one shape of profile; 1 and *out on success.    */

/* Branch 1: the time-optimal profile, v_p above both end velocities. */
DJL_INTERNAL int solve_time_optimal(const segment_problem *c0, segment_solution *out);
/* Branches 2 (v_p between the end velocities: two stages in the same
 * direction) and 3 (v_p below both: a dip). */
DJL_INTERNAL int solve_monotone_or_dip(const segment_problem *c0, int branch,
                                       segment_solution *out);
/* Branch 4: a single stage (or pure cruise) at v_p = max(vs, ve), the cruise
 * rounded to the nearest sample; the residual distance in *resid, or 0 and
 * the shortest distance possible in *dmin. */
DJL_INTERNAL int solve_pinned_single_stage(const segment_problem *c, segment_solution *s,
                                           double *resid, double *dmin);
/* Last resort of branch 1: stages sized for peaks of a grid, the cruise fit
 * to the distance. */
DJL_INTERNAL int solve_fit_peak_grid(const segment_problem *c0, segment_solution *out);
/* Branch 5 (last segment): a single stage whose start or end falls between
 * two samples. */
DJL_INTERNAL int solve_split_sample(const segment_problem *c, segment_solution *out);
/* Distance (m) of the profile with peak vp and kx extra cruise samples, the
 * stages as short as the limits allow (not rounded to whole samples). */
DJL_INTERNAL double distance_continuous(const segment_problem *c, double vp, double kx);
/* Peak of the fastest profile vs -> ve over D with no velocity limit. */
DJL_INTERNAL double peak_without_velocity_limit(double D, double vs, double ve, double am,
                                                double dm);

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility pop
#endif

#endif /* DJL_INTERNAL_H */
