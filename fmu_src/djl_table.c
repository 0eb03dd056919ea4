/*
 * djl_table.c -- profile 4: a motion replayed from a table of constant-jerk pieces
 * (docs/generator.md, "Replayed tables"): the table checked (djl_table_validate: its
 * entries, the limits, the end at rest on the target), its plan built
 * (djl_plan_table: one piece per entry, integrated exactly, and one AL step per
 * entry, so that djl_eval, the input shaper, the replanner and the FMU state work on
 * it as on any plan), and the check that a plan is a table's (djl_table_plan_flaw).
 *
 * Piece i holds the jerk j_i = jerk[i] for n_i = samples[i] samples from sample
 * tau_i = n_0 + ... + n_{i-1}.  It is the ramp of one AL step, A_i = j_i (n_i Te),
 * filtered by a moving average of n_i samples: the plan's pieces are those of its steps,
 * which the FMU's state check requires of any plan.  No allocation; every loop is
 * bounded by DJL_MAX_TABLE.
 */
#include "djl_internal.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

void djl_table_default(djl_table *t)
{
    int i;
    memset(t, 0, sizeof *t);
    for (i = 0; i < DJL_MAX_TABLE; i++) t->samples[i] = 1;
}

/* The state a table reaches, walked piece by piece (the same operations the plan's
 * pieces are made of), and its extremes. */
typedef struct {
    double x, v, a;           /* at the end (x relative to x0) */
    double amax, vmax, xmax;  /* largest |a|, |v| (boundaries and peaks), |x| */
    double up, down;          /* largest s a and -s a, s the sign of the move */
    int64_t k;                /* samples */
} table_walk;

/* Names and messages of piece i (0-based): "table_jerk[i + 1]". */
static void piece_name(char name[40], const char *what, int i)
{
    snprintf(name, 40, "%s[%d]", what, i + 1);
}

/* Walk the table from the start (x = 0, v = v0, a = 0): check each entry and the limits
 * as it goes; fill plan's pieces and steps when plan is not NULL. */
static djl_status walk_table(const djl_params *p, const djl_table *t, djl_plan *plan,
                             table_walk *w, djl_error *err)
{
    const double Te = p->Te, tol = 1.0 + DJL_TABLE_LIMIT_TOLERANCE;
    const double sg = p->distance < 0.0 ? -1.0 : 1.0;
    const double jlim = (p->a_max + p->d_max) / Te; /* may be +inf: then only finite */
    double x = 0.0, v = p->v0, a = 0.0;
    char name[40];
    int i;
    memset(w, 0, sizeof *w);
    w->vmax = djl_fabs(v);
    if (t->n < 0 || t->n > DJL_MAX_TABLE)
        return set_error(err, DJL_E_PARAM, "table_n", (double)t->n,
                         "table_n = %d: must be 0..%d (the pieces of the table)", (int)t->n,
                         DJL_MAX_TABLE);
    for (i = 0; i < t->n; i++) {
        const int32_t n = t->samples[i];
        const double j = t->jerk[i];
        double L, A, ts, vpk, x1, v1, a1;
        if (n < 1 || n > DJL_MAX_FILTER_SAMPLES)
            return piece_name(name, "table_samples", i),
                   set_error(err, DJL_E_PARAM, name, (double)n,
                             "%s = %d: a piece of the table lasts 1..%d samples of Te", name,
                             (int)n, DJL_MAX_FILTER_SAMPLES);
        if (!djl_isfinite(j))
            return piece_name(name, "table_jerk", i),
                   set_error(err, DJL_E_PARAM, name, j, "%s = %g m/s3: must be finite", name, j);
        if (!(djl_fabs(j) <= jlim))
            return piece_name(name, "table_jerk", i),
                   set_error(err, DJL_E_PARAM, name, j,
                             "%s = %g m/s3: beyond (a_max + d_max) / Te = %g m/s3, the jerk "
                             "that takes the acceleration from -d_max to a_max in one sample",
                             name, j, jlim);
        L = (double)n * Te;
        A = j * L;
        /* the velocity's extremum inside the piece, where a crosses 0 */
        ts = j != 0.0 ? -a / j : -1.0;
        vpk = ts > 0.0 && ts < L ? v + ts * (a + 0.5 * ts * j) : v;
        x1 = x + L * (v + L * (0.5 * a + L * j / 6.0));
        v1 = v + L * (a + 0.5 * L * j);
        a1 = a + A;
        if (!djl_isfinite(x1) || !djl_isfinite(v1) || !djl_isfinite(a1) ||
            !djl_isfinite(vpk) || !(djl_fabs(p->x0 + x1) <= DJL_MAX_POSITION))
            return piece_name(name, "table_jerk", i),
                   set_error(err, DJL_E_PARAM, name, j,
                             "%s = %g m/s3 over table_samples[%d] = %d samples of Te = %g s: "
                             "the position at the end of piece %d, %g m, leaves the %g m a "
                             "motion may span (or the doubles)", name, j, i + 1, (int)n, Te,
                             i + 1, p->x0 + x1, DJL_MAX_POSITION);
        if (!(djl_fabs(vpk) <= p->v_max * tol) || !(djl_fabs(v1) <= p->v_max * tol))
            return piece_name(name, "table_jerk", i),
                   set_error(err, DJL_E_PARAM, name, j,
                             "%s = %g m/s3 over table_samples[%d] = %d samples: in piece %d "
                             "the table's velocity reaches %.17g m/s, beyond v_max = %g m/s",
                             name, j, i + 1, (int)n, i + 1,
                             djl_fabs(vpk) > djl_fabs(v1) ? vpk : v1, p->v_max);
        if (!(sg * a1 <= p->a_max * tol) || !(-sg * a1 <= p->d_max * tol))
            return piece_name(name, "table_jerk", i),
                   set_error(err, DJL_E_PARAM, name, j,
                             "%s = %g m/s3 over table_samples[%d] = %d samples: at the end of "
                             "piece %d the table's acceleration is %.17g m/s2, outside "
                             "[%g, %g] m/s2 (-d_max and a_max %s)", name, j, i + 1, (int)n,
                             i + 1, a1, sg > 0.0 ? -p->d_max : -p->a_max,
                             sg > 0.0 ? p->a_max : p->d_max,
                             sg > 0.0 ? "for a move forwards" : "mirrored: a move backwards");
        if (plan) {
            djl_piece *pc = &plan->piece[i];
            djl_step *st = &plan->step[i];
            pc->k = w->k;
            pc->x = x;
            pc->v = v;
            pc->a = a;
            pc->j = j;
            /* the AL profile of a table: the level of its steps (the acceleration the piece
             * ends at), from the output's position and velocity at the piece's start */
            pc->x_al = x;
            pc->v_al = v;
            pc->a_al = a1;
            pc->seg = 1;
            pc->stage = 0;
            st->tau = w->k;
            st->A = A;
            st->N = n;
            st->stage = 0;
        }
        x = x1;
        v = v1;
        a = a1;
        w->k += n;
        w->amax = dmax2(w->amax, djl_fabs(a));
        w->vmax = dmax2(w->vmax, dmax2(djl_fabs(vpk), djl_fabs(v)));
        w->xmax = dmax2(w->xmax, djl_fabs(x));
        w->up = dmax2(w->up, sg * a);
        w->down = dmax2(w->down, -sg * a);
    }
    w->x = x;
    w->v = v;
    w->a = a;
    return DJL_OK;
}

/* The end of the walk: at rest at distance, within DJL_TABLE_END_TOLERANCE of the table's
 * own scale (its largest acceleration, velocity, travel). */
static djl_status check_end(const djl_params *p, const table_walk *w, djl_error *err)
{
    const double tol = DJL_TABLE_END_TOLERANCE;
    double X = dmax2(djl_fabs(p->distance), w->xmax);
    if (!(djl_fabs(w->a) <= tol * w->amax))
        return set_error(err, DJL_E_PARAM, "table_jerk", w->a,
                         "table_jerk: the table ends with the acceleration %.17g m/s2, not at "
                         "rest (|a| must be at most %g of its largest, %g m/s2): the sum of "
                         "table_jerk[i] table_samples[i] Te must be 0",
                         w->a, tol, w->amax);
    if (!(djl_fabs(w->v) <= tol * w->vmax))
        return set_error(err, DJL_E_PARAM, "table_jerk", w->v,
                         "table_jerk: the table ends with the velocity %.17g m/s, not at rest "
                         "(|v| must be at most %g of its largest, %g m/s)", w->v, tol, w->vmax);
    if (!(djl_fabs(w->x - p->distance) <= tol * X))
        return set_error(err, DJL_E_PARAM, "distance", p->distance,
                         "distance = %.17g m: the table ends %.17g m from x0, %g m away (it "
                         "must end at x0 + distance within %g of its travel, %g m)",
                         p->distance, w->x, w->x - p->distance, tol, X);
    return DJL_OK;
}

djl_status djl_table_validate(const djl_params *p, const djl_table *t, djl_error *err)
{
    djl_status st;
    table_walk w;
    if (err) memset(err, 0, sizeof *err);
    if ((st = djl_validate(p, err)) != DJL_OK) return st;
    if (p->profile != DJL_PROFILE_TABLE)
        return set_error(err, DJL_E_PARAM, "profile", (double)p->profile,
                         "profile = %d: a table is replayed with profile = 4", (int)p->profile);
    if ((st = walk_table(p, t, NULL, &w, err)) != DJL_OK) return st;
    return check_end(p, &w, err);
}

djl_status djl_plan_table(const djl_params *p, const djl_table *t, djl_plan *plan,
                          djl_error *err)
{
    djl_status st;
    table_walk w;
    djl_piece *end;
    int i;
    if ((st = djl_table_validate(p, t, err)) != DJL_OK) return st;
    memset(plan, 0, offsetof(djl_plan, piece));
    plan->p = *p;
    for (i = 0; i < 4; i++) plan->N[i] = (int32_t)djl_floor(p->T_F[i] / p->Te + 0.5);
    (void)walk_table(p, t, plan, &w, NULL);
    /* the rest at the end, exactly on the target */
    end = &plan->piece[t->n];
    memset(end, 0, sizeof *end);
    end->k = w.k;
    end->x = p->distance;
    end->x_al = p->distance;
    end->seg = 1;
    plan->n_pieces = t->n + 1;
    plan->n_segments = 1;
    plan->seg[0].distance = p->distance;
    plan->seg[0].branch = 0;
    plan->k_end = w.k;
    plan->x_target = p->distance;
    plan->v_target = 0.0;
    plan->v_reached = w.vmax;
    plan->a_reached = w.up;
    plan->d_reached = w.down;
    plan->n_steps = t->n;
    plan->replanned = 0;
    plan->level0 = 0.0;
    return DJL_OK;
}

const char *djl_table_plan_flaw(const djl_plan *pl, const djl_params *p, const djl_table *t)
{
    double Te = p->Te;
    int64_t k = 0;
    int i;
    if (t->n < 0 || t->n > DJL_MAX_TABLE) return "its table's piece count is out of range";
    if (pl->replanned || pl->n_steps != t->n || pl->n_pieces != t->n + 1 ||
        pl->level0 != 0.0 || pl->n_segments != 1)
        return "its plan is not the one of its table (counts)";
    for (i = 0; i < t->n; i++) {
        const djl_step *st = &pl->step[i];
        const djl_piece *pc = &pl->piece[i];
        double A = t->jerk[i] * ((double)t->samples[i] * Te);
        if (st->tau != k || st->N != t->samples[i] || st->stage != 0 ||
            memcmp(&st->A, &A, sizeof A) != 0)
            return "its plan's steps are not those of its table";
        if (pc->k != k || memcmp(&pc->j, &t->jerk[i], sizeof pc->j) != 0 || pc->stage != 0 ||
            pc->seg != 1)
            return "its plan's pieces are not those of its table";
        k += t->samples[i];
    }
    {
        const djl_piece *end = &pl->piece[t->n];
        if (pl->k_end != k || end->k != k || end->x != p->distance || end->v != 0.0 ||
            end->a != 0.0 || end->j != 0.0 || pl->x_target != p->distance ||
            pl->v_target != 0.0)
            return "its plan does not end where its table does";
    }
    return NULL;
}
