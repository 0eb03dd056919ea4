/*
 * djl_validate.c -- the parameters checked before planning (djl_validate:
 * each bad value gets a message naming the parameter), their defaults
 * (djl_params_default), the status names, and set_error, which writes the
 * messages of the whole core.
 */
#include "djl_internal.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

DJL_INTERNAL djl_status set_error(djl_error *e, djl_status st, const char *param, double value,
                                  const char *fmt, ...)
{
    if (e) {
        va_list ap;
        e->status = st;
        e->value = value;
        if (param) {
            strncpy(e->param, param, sizeof(e->param) - 1);
            e->param[sizeof(e->param) - 1] = '\0';
        } else {
            e->param[0] = '\0';
        }
        va_start(ap, fmt);
        vsnprintf(e->message, sizeof(e->message), fmt, ap);
        va_end(ap);
    }
    return st;
}

const char *djl_status_name(djl_status s)
{
    switch (s) {
    case DJL_OK: return "ok";
    case DJL_E_PARAM: return "invalid parameter";
    case DJL_E_INFEASIBLE: return "infeasible motion";
    case DJL_E_INTERNAL: return "internal error";
    }
    return "unknown";
}

void djl_params_default(djl_params *p)
{
    memset(p, 0, sizeof(*p)); /* also: no segments, all segment arrays 0 */
    p->profile = DJL_PROFILE_DJL;
    p->short_stage = DJL_SHORT_STRETCH;
    p->Te = 1e-3;
    p->x0 = 0.0;
    p->v0 = 0.0;
    p->distance = 0.4;
    p->v_e = 0.0;
    p->v_max = 1.0;
    p->a_max = 10.0;
    p->d_max = 10.0;
    /* Fig. 9 of the paper */
    p->T_F[0] = 0.08;
    p->T_F[1] = 0.08;
    p->T_F[2] = 0.06;
    p->T_F[3] = 0.05;
}

/* ------------------------------------------------------------------------ */
/* validation                                                               */

static int stage_used(int profile, int stage)
{
    /* a table's jerk is its own; T_F1..T_F4 are the jerk times of the stages a commanded
     * stop or move adds to it (djl_table.c), checked as DJL's */
    if (profile == DJL_PROFILE_DJL || profile == DJL_PROFILE_TABLE) return 1;
    if (profile == DJL_PROFILE_JL) return stage == 0;
    return 0;
}

static djl_status check_positive(djl_error *err, const char *name, double v, const char *unit)
{
    if (!djl_isfinite(v) || !(v > 0.0))
        return set_error(err, DJL_E_PARAM, name, v,
                         "%s = %g %s: must be a finite number > 0", name, v, unit);
    if (v < DJL_MIN_MAGNITUDE)
        return set_error(err, DJL_E_PARAM, name, v,
                         "%s = %g %s: must be at least %g %s (a subnormal double has too few "
                         "significant digits to be planned exactly)", name, v, unit,
                         DJL_MIN_MAGNITUDE, unit);
    return DJL_OK;
}

/* Names of segment i's distance, end velocity and start velocity. */
static void segment_names(const djl_params *p, int i, char dname[40], char vname[40],
                          char sname[40])
{
    if (p->n_segments == 0) {
        snprintf(dname, 40, "distance");
        snprintf(vname, 40, "v_e");
    } else {
        snprintf(dname, 40, "seg_distance[%d]", i + 1);
        snprintf(vname, 40, "seg_v_end[%d]", i + 1);
    }
    if (i == 0)
        snprintf(sname, 40, "v0");
    else
        snprintf(sname, 40, "seg_v_end[%d]", i);
}

djl_status djl_validate(const djl_params *p, djl_error *err)
{
    djl_status st;
    int i, n;
    double reach;

    if (p->profile < DJL_PROFILE_AL || p->profile > DJL_PROFILE_TABLE)
        return set_error(err, DJL_E_PARAM, "profile", (double)p->profile,
                         "profile = %d: must be 1 (AL), 2 (JL), 3 (DJL) or 4 (table)",
                         (int)p->profile);
    if (p->short_stage != DJL_SHORT_STRETCH && p->short_stage != DJL_SHORT_OVERLAP)
        return set_error(err, DJL_E_PARAM, "short_stage", (double)p->short_stage,
                         "short_stage = %d: must be 1 (stretch the stage to its jerk times) "
                         "or 2 (let the ramps overlap, as in the paper)", (int)p->short_stage);
    if ((st = check_positive(err, "Te", p->Te, "s")) != DJL_OK) return st;
    if ((st = check_positive(err, "v_max", p->v_max, "m/s")) != DJL_OK) return st;
    if ((st = check_positive(err, "a_max", p->a_max, "m/s2")) != DJL_OK) return st;
    if ((st = check_positive(err, "d_max", p->d_max, "m/s2")) != DJL_OK) return st;
    for (i = 0; i < 4; i++) {
        static const char *const tf[4] = {"T_F1", "T_F2", "T_F3", "T_F4"};
        double T = p->T_F[i];
        const char *name = tf[i];
        if ((st = check_positive(err, name, T, "s")) != DJL_OK) return st;
        if (stage_used(p->profile, i)) {
            double N = djl_floor(T / p->Te + 0.5);
            if (N < 1.0)
                return set_error(err, DJL_E_PARAM, name, T,
                                 "%s = %g s rounds to 0 samples at Te = %g s: a jerk time must "
                                 "be at least half a sampling period%s", name, T, p->Te,
                                 p->profile == DJL_PROFILE_TABLE
                                     ? " (profile = 4, table: the jerk times of the stages a "
                                       "commanded stop or move adds)"
                                     : "");
            if (N > (double)DJL_MAX_FILTER_SAMPLES)
                return set_error(err, DJL_E_PARAM, name, T,
                                 "%s = %g s is %.0f samples at Te = %g s: more than the %d "
                                 "samples a filter may hold", name, T, N, p->Te,
                                 DJL_MAX_FILTER_SAMPLES);
        }
    }
    if (!djl_isfinite(p->x0))
        return set_error(err, DJL_E_PARAM, "x0", p->x0, "x0 = %g m: must be finite", p->x0);
    if (djl_fabs(p->x0) > DJL_MAX_POSITION)
        return set_error(err, DJL_E_PARAM, "x0", p->x0,
                         "x0 = %g m: |x0| must not exceed %g m", p->x0, DJL_MAX_POSITION);
    if (!djl_isfinite(p->v0) || djl_fabs(p->v0) > p->v_max)
        return set_error(err, DJL_E_PARAM, "v0", p->v0,
                         "v0 = %g m/s: must be finite and |v0| <= v_max = %g m/s", p->v0,
                         p->v_max);
    if (p->n_segments < 0 || p->n_segments > DJL_MAX_SEGMENTS)
        return set_error(err, DJL_E_PARAM, "n_segments", (double)p->n_segments,
                         "n_segments = %d: must be 0 (single move given by distance and v_e) or "
                         "1..%d", (int)p->n_segments, DJL_MAX_SEGMENTS);
    if (p->profile == DJL_PROFILE_TABLE && p->n_segments != 0)
        return set_error(err, DJL_E_PARAM, "n_segments", (double)p->n_segments,
                         "n_segments = %d with profile = 4 (table): a table is one move, "
                         "from x0 to x0 + distance (n_segments must be 0)", (int)p->n_segments);
    if (p->profile == DJL_PROFILE_TABLE && p->v_e != 0.0)
        return set_error(err, DJL_E_PARAM, "v_e", p->v_e,
                         "v_e = %g m/s with profile = 4 (table): a table ends at rest "
                         "(v_e must be 0)", p->v_e);

    n = p->n_segments == 0 ? 1 : p->n_segments;
    reach = djl_fabs(p->x0);
    for (i = 0; i < n; i++) {
        double D = p->n_segments == 0 ? p->distance : p->seg_distance[i];
        double ve = p->n_segments == 0 ? p->v_e : p->seg_v_end[i];
        double vs = i == 0 ? p->v0 : p->seg_v_end[i - 1];
        char dname[40], vname[40], sname[40];
        /* the names, for the messages: written only when a check fails (a replan
         * validates a new motion in its few microseconds) */
#define NAMES() segment_names(p, i, dname, vname, sname)
        if (!djl_isfinite(D))
            return NAMES(), set_error(err, DJL_E_PARAM, dname, D, "%s = %g m: must be finite",
                                      dname, D);
        if (D != 0.0 && djl_fabs(D) < DJL_MIN_MAGNITUDE)
            return NAMES(), set_error(err, DJL_E_PARAM, dname, D,
                             "%s = %g m: a non-zero distance must be at least %g m in magnitude "
                             "(a subnormal double has too few significant digits to be planned "
                             "exactly)", dname, D, DJL_MIN_MAGNITUDE);
        reach += djl_fabs(D);
        if (reach > DJL_MAX_POSITION)
            return NAMES(), set_error(err, DJL_E_PARAM, dname, D,
                             "%s = %g m: |x0| + the sum of |distance| up to it is %g m, more than "
                             "the %g m a motion may span", dname, D, reach, DJL_MAX_POSITION);
        if (!djl_isfinite(ve) || djl_fabs(ve) > p->v_max)
            return NAMES(), set_error(err, DJL_E_PARAM, vname, ve,
                             "%s = %g m/s: must be finite and not above v_max = %g m/s in "
                             "magnitude", vname, ve, p->v_max);
        if (D > 0.0 && ve < 0.0)
            return NAMES(), set_error(err, DJL_E_PARAM, vname, ve,
                             "%s = %g m/s points backwards while %s = %g m moves forwards: the "
                             "velocity must be 0 where the direction reverses", vname, ve, dname, D);
        if (D < 0.0 && ve > 0.0)
            return NAMES(), set_error(err, DJL_E_PARAM, vname, ve,
                             "%s = %g m/s points forwards while %s = %g m moves backwards: the "
                             "velocity must be 0 where the direction reverses", vname, ve, dname, D);
        if (D > 0.0 && vs < 0.0)
            return NAMES(), set_error(err, DJL_E_PARAM, sname, vs,
                             "%s = %g m/s points backwards while %s = %g m moves forwards: the "
                             "velocity must be 0 where the direction reverses", sname, vs, dname, D);
        if (D < 0.0 && vs > 0.0)
            return NAMES(), set_error(err, DJL_E_PARAM, sname, vs,
                             "%s = %g m/s points forwards while %s = %g m moves backwards: the "
                             "velocity must be 0 where the direction reverses", sname, vs, dname, D);
        if (D == 0.0 && (vs != 0.0 || ve != 0.0))
            return NAMES(), set_error(err, DJL_E_PARAM, dname, D,
                             "%s = 0 m with a non-zero velocity at its start (%g m/s) or end "
                             "(%g m/s): a null segment must start and end at rest", dname, vs, ve);
        if (djl_fabs(D) / (p->v_max * p->Te) > 1e14)
            return NAMES(), set_error(err, DJL_E_PARAM, dname, D,
                             "%s = %g m would take more than 1e14 samples at v_max = %g m/s and "
                             "Te = %g s", dname, D, p->v_max, p->Te);
    }
#undef NAMES
    return DJL_OK;
}
