/*
 * djl_eval.c -- a sample of a plan: djl_eval evaluates the piece in force at
 * a time (in samples, possibly fractional; djl_eval_left its limit from the
 * left), and the plan's durations; where
 * the motion starts on a generator's sample grid (djl_start_offset).
 */
#include "djl_internal.h"

/* ------------------------------------------------------------------------ */
/* evaluation                                                               */

void djl_eval(const djl_plan *pl, double u, int32_t *cursor, djl_sample *o)
{
    const djl_params *p = &pl->p;
    int32_t i = cursor ? *cursor : 0;
    const djl_piece *pc;
    double s;
    if (!(u >= 0.0)) {
        s = u * p->Te;
        o->x = p->x0 + p->v0 * s;
        o->v = p->v0;
        o->a = 0.0;
        o->j = 0.0;
        o->x_al = o->x;
        o->v_al = p->v0;
        o->a_al = 0.0;
        o->done = 0;
        o->segment = 0;
        o->stage = 0;
        return;
    }
    if (i < 0 || i >= pl->n_pieces) i = 0;
    while (i + 1 < pl->n_pieces && u >= (double)pl->piece[i + 1].k) i++;
    while (i > 0 && u < (double)pl->piece[i].k) i--;
    if (cursor) *cursor = i;
    pc = &pl->piece[i];
    s = (u - (double)pc->k) * p->Te;
    o->x = p->x0 + (pc->x + s * (pc->v + s * (0.5 * pc->a + s * pc->j / 6.0)));
    o->v = pc->v + s * (pc->a + 0.5 * s * pc->j);
    o->a = pc->a + s * pc->j;
    o->j = pc->j;
    o->x_al = p->x0 + (pc->x_al + s * (pc->v_al + 0.5 * s * pc->a_al));
    o->v_al = pc->v_al + s * pc->a_al;
    o->a_al = pc->a_al;
    o->done = u >= (double)pl->k_end;
    o->segment = pc->seg;
    o->stage = pc->stage;
}

void djl_eval_left(const djl_plan *pl, double u, int32_t *cursor, djl_sample *o)
{
    const djl_params *p = &pl->p;
    int32_t i = cursor ? *cursor : 0;
    const djl_piece *pc;
    double s;
    if (!(u > 0.0)) { /* up to the start (its limit at 0 from the left): at v0 */
        s = u * p->Te;
        o->x = p->x0 + p->v0 * s;
        o->v = p->v0;
        o->a = 0.0;
        o->j = 0.0;
        o->x_al = o->x;
        o->v_al = p->v0;
        o->a_al = 0.0;
        o->done = 0;
        o->segment = 0;
        o->stage = 0;
        return;
    }
    /* the last piece that starts before u */
    if (i < 0 || i >= pl->n_pieces) i = 0;
    while (i + 1 < pl->n_pieces && u > (double)pl->piece[i + 1].k) i++;
    while (i > 0 && !(u > (double)pl->piece[i].k)) i--;
    if (cursor) *cursor = i;
    pc = &pl->piece[i];
    s = (u - (double)pc->k) * p->Te;
    o->x = p->x0 + (pc->x + s * (pc->v + s * (0.5 * pc->a + s * pc->j / 6.0)));
    o->v = pc->v + s * (pc->a + 0.5 * s * pc->j);
    o->a = pc->a + s * pc->j;
    o->j = pc->j;
    o->x_al = p->x0 + (pc->x_al + s * (pc->v_al + 0.5 * s * pc->a_al));
    o->v_al = pc->v_al + s * pc->a_al;
    o->a_al = pc->a_al;
    o->done = u > (double)pl->k_end;
    o->segment = pc->seg;
    o->stage = pc->stage;
}

double djl_applied_jerk_time(const djl_plan *plan, int stage)
{
    if (stage < 0 || stage > 3) return 0.0;
    return plan->N[stage] * plan->p.Te;
}

double djl_motion_time(const djl_plan *plan) { return (double)plan->k_end * plan->p.Te; }

/* ------------------------------------------------------------------------ */
/* the motion on a sample grid                                              */

/* Unit in the last place of |x| (x finite): the spacing of doubles there. */
static double ulp(double x)
{
    x = djl_fabs(x);
    return djl_nextafter(x, DJL_HUGE_VAL) - x;
}

djl_status djl_check_t_start(double t_start, double start_time, djl_error *err)
{
    if (!djl_isfinite(t_start) || !djl_isfinite(start_time))
        return set_error(err, DJL_E_PARAM, "t_start", t_start,
                         "invalid parameter t_start = %g s: must be finite", t_start);
    return DJL_OK;
}

djl_status djl_start_offset(double t_start, double start_time, double Te, double *offset,
                            int *shifted, djl_error *err)
{
    djl_status st = djl_check_t_start(t_start, start_time, err);
    double off;
    if (st != DJL_OK) return st;
    if (!(djl_isfinite(Te) && Te > 0.0))
        return set_error(err, DJL_E_PARAM, "Te", Te, "Te = %g s: must be a finite number > 0",
                         Te);
    off = (t_start - start_time) / Te;
    if (!djl_isfinite(off) || djl_fabs(off) > 1e15)
        return set_error(err, DJL_E_PARAM, "t_start", t_start,
                         "t_start = %g s is %g samples of Te = %g s away from the start time "
                         "%g s: too far", t_start, off, Te, start_time);
    /* on a sample to rounding: 1e-9 of the offset, or what t_start and the start time
     * can resolve at their magnitude */
    if (djl_fabs(off - djl_floor(off + 0.5)) <=
        djl_fmax(1e-9 * (1.0 + djl_fabs(off)),
                 4.0 * ulp(djl_fmax(djl_fabs(t_start), djl_fabs(start_time))) / Te)) {
        *offset = djl_floor(off + 0.5);
        *shifted = 0;
    } else {
        *offset = djl_ceil(off);
        *shifted = 1;
    }
    return DJL_OK;
}
