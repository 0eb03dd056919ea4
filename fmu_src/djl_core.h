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
/* Longest filter accepted, in samples. */
#define DJL_MAX_FILTER_SAMPLES 100000000
/* Longest motion accepted, in samples (keeps every sample index exact in a double). */
#define DJL_MAX_MOTION_SAMPLES 1000000000000000LL
/* Largest |x0| + sum of |distance| accepted, m (every value of a plan stays finite). */
#define DJL_MAX_POSITION 1e300
/* Smallest magnitude accepted for Te, v_max, a_max, d_max, the jerk times and
 * a non-zero distance: the smallest normal double, DBL_MIN.  A subnormal value
 * has too few significant digits to be planned exactly.  (A subnormal speed
 * is accepted: next to v_max it is 0.) */
#define DJL_MIN_MAGNITUDE 2.2250738585072014e-308

typedef enum { DJL_PROFILE_AL = 1, DJL_PROFILE_JL = 2, DJL_PROFILE_DJL = 3 } djl_profile;

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
} djl_piece;

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
} djl_plan;

typedef struct {
    double x, v, a, j;       /* generated profile */
    double x_al, v_al, a_al; /* AL profile before filtering */
    int32_t done;            /* 1 once the motion, filters included, has ended */
    int32_t segment;         /* 1-based segment of the AL profile at this time, 0 before the start */
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

/* Jerk time actually applied to stage i (0..3) in seconds (N * Te). */
double djl_applied_jerk_time(const djl_plan *plan, int stage);

/* Motion duration (filters included), s. */
double djl_motion_time(const djl_plan *plan);

const char *djl_status_name(djl_status s);

#ifdef __cplusplus
}
#endif

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility pop
#endif

#endif /* DJL_CORE_H */
