/*
 * djl_replan.c -- replanning a move in progress (djl_replan): a new target,
 * a stop, or new jerk times, at any time of a motion.
 *
 * The method (docs/generator.md, "Commanded moves"):
 *  1. Keep what has been filtered: every AL step started before the command
 *     keeps its ramp, which finishes as started.  The state of the old plan at
 *     the whole sample o = floor(u) and the ramps still running are gathered
 *     (replan_state); the steps at or after b = ceil(u) are dropped, so the
 *     outputs up to u do not change.
 *  2. End the AL stage in progress: a step -a_AL at a sample e >= b, filtered
 *     by the jerk time of the stage that ends it (2 after an acceleration, 4
 *     after a deceleration).  Speeding up towards the target, e is the last
 *     sample at which v_max and the room to stop still allow it (the stage goes
 *     on as planned); otherwise e = b.  For a stop during a deceleration, the
 *     stage goes on until the velocity reaches 0 exactly (the end step split
 *     over two samples).
 *  3. Once every ramp has ended (the DJL rule: ramps of different jerk times
 *     do not overlap across stages) the axis cruises at the settled velocity
 *     v_s; from there the rest is a new single-segment motion planned by
 *     djl_plan_motion (exact landing at rest on the target).  If none exists
 *     (the target is behind, or too close to stop on), the axis stops first
 *     (d_max, stages 3 and 4) and then moves from rest to the target.
 * The velocity and position the ramps settle to are computed in closed form
 * (settle), and the pieces of the new plan by the same closed-form walk as a
 * planned motion (walk).  No allocation; every loop is bounded by the number
 * of steps, but the search of step 2 (bisection, at most 64 rounds).
 */
#include "djl_internal.h"

#include <string.h>

/* What a replan keeps of the old plan. */
typedef struct {
    int64_t o, b;          /* whole samples of the old plan: origin (floor u), first free (ceil u) */
    double x, v, a;        /* output at o (x absolute); a that of the kept steps */
    double x_al, v_al;     /* AL profile at o (x absolute) */
    double level;          /* AL acceleration of the kept steps (tau < b) */
    double settled;        /* part of it whose ramps are over at o */
    int speeding_up;       /* the AL level pushes the way the axis moves (or it starts from
                              rest): an acceleration stage, else a deceleration stage */
    int n_run;
    djl_step run[DJL_MAX_PLAN_STEPS]; /* kept ramps running at o, tau relative to o (<= 0) */
    double Te, v_max, a_max, d_max;
    int lower;             /* the goal's v_max is below the old plan's (djl_goal) */
    int above;             /* ... and the axis moves faster than it */
    double v_old;          /* the old plan's v_max */
} replan_state;

/* dv / (a Te), samples of the acceleration a for the velocity change dv: as written when
 * a Te is a normal double, else as dv / a / Te (a Te below the normal doubles keeps only
 * some of its digits: issue 21, a stop at d_max = DBL_MIN with Te = 1e-9 s came 80 samples
 * short and its deceleration 8e-8 above d_max). */
static double per_sample(double dv, double a, double Te)
{
    double aTe = a * Te;
    return djl_fabs(aTe) >= DJL_MIN_MAGNITUDE ? dv / aTe : dv / a / Te;
}

static void gather(const djl_plan *old, double u, replan_state *r)
{
    djl_sample s;
    int32_t cur = 0;
    int i;
    double fo = djl_floor(u), amag;
    r->o = (int64_t)fo;
    r->b = r->o + 1; /* the interval [o, o + 1) that contains u is the old plan's */
    djl_eval(old, fo, &cur, &s);
    r->x = s.x;
    r->v = s.v;
    r->a = s.a;
    r->x_al = s.x_al;
    r->v_al = s.v_al;
    r->level = old->level0;
    r->settled = old->level0;
    r->n_run = 0;
    r->Te = old->p.Te;
    r->v_max = old->p.v_max;
    r->a_max = old->p.a_max;
    r->d_max = old->p.d_max;
    r->lower = 0;
    r->above = 0;
    r->v_old = old->p.v_max;
    amag = djl_fabs(old->level0);
    for (i = 0; i < old->n_steps; i++) {
        const djl_step *st = &old->step[i];
        if (st->tau < r->b) {
            r->level += st->A;
            amag += djl_fabs(st->A);
            if (st->N > 0 && st->tau + st->N > r->o) {
                djl_step *k = &r->run[r->n_run++];
                *k = *st;
                k->tau = st->tau - r->o;
            } else {
                r->settled += st->A;
            }
        }
    }
    /* a rounding residue of +A - A is no acceleration (relative to the levels summed, not
     * to a_max + d_max: limits of 10^300 the motion never reaches would zero any level);
     * nor in the part that has settled, which becomes the new plan's level0: kept, such a
     * residue (6.9e-18 m/s2 after steps of 20 m/s2) outlived the steps it came from, and
     * the FMU's check of its own state (AL level and acceleration those of level0 and the
     * steps, to a billionth of what the plan holds) refused it (issue 21) */
    if (djl_fabs(r->level) <= 1e-13 * amag) r->level = 0.0;
    if (djl_fabs(r->settled) <= 1e-13 * amag) r->settled = 0.0;
    /* the output's acceleration at o from the steps (level0, then the ramps running, as
     * the new plan lists them and as the FMU's state check sums them), not from the old
     * plan's pieces: those carry their walk's rounding, relative to accelerations the new
     * plan may no longer hold (issue 21: 7.3242e-28 against 7.3271e-28 m/s2 after a stop
     * at d_max = 7.3e-28 m/s2, and the FMU refused its own state) */
    r->a = r->settled;
    for (i = 0; i < r->n_run; i++) {
        double w = (double)(-r->run[i].tau);
        r->a += r->run[i].A * (w / (double)r->run[i].N);
    }
    /* the stage in progress: planned motions never reverse within a stage, so the
     * signs of the level and of the velocity tell an acceleration from a deceleration */
    r->speeding_up = r->level * r->v >= 0.0;
}

/* Velocity v_s the ramps settle to, and the intercept X_s (m, relative to the
 * output at o) of the line x = X_s + v_s t Te they settle on (t samples after o),
 * for the kept ramps and the new steps nw (tau relative to o, >= 0).  Exact
 * sums of the ramps' contributions: with the AL level back to 0 the terms in t
 * cancel (docs/generator.md). */
static void settle(const replan_state *r, const djl_step *nw, int n_new, double *v_s, double *X_s)
{
    double sv = 0.0, sx = 0.0;
    int i;
    for (i = 0; i < r->n_run; i++) {
        double A = r->run[i].A, N = r->run[i].N, w = N + (double)r->run[i].tau; /* N - u */
        sv -= A * (w * w / (2.0 * N));
        sx += A * (w * w * w / (6.0 * N));
    }
    for (i = 0; i < n_new; i++) {
        double A = nw[i].A, N = nw[i].N, t = (double)nw[i].tau;
        sv -= A * (t + 0.5 * N);
        sx += A * (0.5 * t * t + 0.5 * N * t + N * N / 6.0);
    }
    *v_s = r->v + r->Te * sv;
    *X_s = r->Te * r->Te * sx;
}

/* Sample (relative to o) at which every ramp has ended. */
static int64_t ramps_end(const replan_state *r, const djl_step *nw, int n_new)
{
    int64_t T = 0;
    int i;
    for (i = 0; i < r->n_run; i++) T = imax2(T, r->run[i].tau + r->run[i].N);
    for (i = 0; i < n_new; i++) T = imax2(T, nw[i].tau + (nw[i].N > 0 ? nw[i].N : 0));
    return T;
}

/* The steps of a stop from the cruise velocity v at sample t0: -d at t0
 * (stage 3, N3), +d at t0 + m (stage 4, N4), m the fewest samples (and at
 * least N3: the ramps of a stage do not overlap) for which d <= d_max.
 * Returns the number of steps (0 if v = 0). */
static int stop_steps(double v, int64_t t0, const int32_t N[4], double d_max, double Te,
                      djl_step *out)
{
    double n3 = N[2], n4 = N[3], lag = 0.5 * (n4 - n3), m, d, sg = v < 0.0 ? -1.0 : 1.0;
    if (v == 0.0) return 0;
    m = djl_ceil(per_sample(djl_fabs(v), d_max, Te) - lag);
    m = dmax2(m, dmax2(n3, 1.0));
    /* (a stop this long ends past DJL_MAX_PLAN_END: compose refuses it) */
    if (m > 4e15) m = 4e15;
    d = djl_fabs(v) / ((m + lag) * Te);
    if (d > d_max) { /* rounding of the division: one sample more */
        m += 1.0;
        d = djl_fabs(v) / ((m + lag) * Te);
    }
    out[0].tau = t0;
    out[0].A = -sg * d;
    out[0].N = N[2];
    out[0].stage = 3;
    out[1].tau = t0 + (int64_t)m;
    out[1].A = sg * d;
    out[1].N = N[3];
    out[1].stage = 4;
    return 2;
}

/* The steps placed from b on, before any new motion. */
typedef struct {
    int n;
    djl_step s[8];
    int64_t end_at;     /* sample (relative to o) of the step ending the stage, -1 if none */
    int clipped, lengthened;
} transition;

/* Sample (relative to o) at which the running ramps that push the same way as
 * the AL level (the start of the stage in progress) end; 0 if none runs. */
static int64_t stage_start_end(const replan_state *r)
{
    int64_t T = 0;
    int i;
    for (i = 0; i < r->n_run; i++)
        if (r->run[i].A * r->level > 0.0) T = imax2(T, r->run[i].tau + r->run[i].N);
    return T;
}

/* End the AL stage in progress at e (relative to o) with the filter N.
 *  - The ending ramp ends no earlier than the ramp that started the stage (if it
 *    still runs): the acceleration then keeps its sign until it is 0, the
 *    velocity does not overshoot the value it settles to (a shorter ending ramp
 *    would take the acceleration past 0 while the starting one still rises).
 *  - Within that, the filter is shortened or lengthened (t->clipped) if the speed
 *    would settle above v_max: each sample of it moves the settled velocity by
 *    level Te / 2. */
static void end_stage(const replan_state *r, transition *t, int64_t e, int32_t N)
{
    double v_s, X_s, over, Nmin, vlim;
    t->n = 0;
    t->end_at = -1;
    t->clipped = 0;
    t->lengthened = 0;
    if (r->level == 0.0) return;
    Nmin = (double)(stage_start_end(r) - e);
    t->s[0].tau = e;
    t->s[0].A = -r->level;
    t->s[0].N = (int32_t)dmax2((double)N, Nmin);
    t->lengthened = t->s[0].N != N;
    t->s[0].stage = r->speeding_up ? 2 : 4;
    t->n = 1;
    t->end_at = e;
    settle(r, t->s, 1, &v_s, &X_s);
    /* (an axis already above a goal's lower v_max: the stage ends within the old plan's,
     * the speed comes down by the stop that follows) */
    vlim = r->above ? r->v_old : r->v_max;
    over = djl_fabs(v_s) - vlim;
    if (over > 1e-12 * vlim && N > 0) {
        /* shorten the filter when the level pushes the speed up, else lengthen it */
        double cut = djl_ceil(2.0 * per_sample(over, djl_fabs(r->level), r->Te));
        double N0 = t->s[0].N;
        double N2 = (r->level > 0.0) == (v_s > 0.0)
                        ? dmax2(N0 - cut, dmax2(Nmin, 1.0))
                        : dmin2(N0 + cut, (double)DJL_MAX_FILTER_SAMPLES);
        t->s[0].N = (int32_t)N2;
        t->clipped = 1;
    }
}

/* A stop: a deceleration in progress ends at rest at the latest, never by reversing (an
 * ending ramp much longer than the stage's starting one, as N4 >> N3, would take the
 * velocity through 0 and the axis back): the filter of t's ending step is shortened,
 * each sample of it moving the settled velocity by level Te / 2, not below the ramp
 * that started the stage.  (A new move needs no such care: it stops and comes back, or
 * the jerk times are declined, no_stop_first.) */
static void no_reversal(const replan_state *r, transition *t)
{
    double sv, v_s, X_s, rev;
    if (t->n != 1 || r->speeding_up || r->v == 0.0 || t->s[0].N <= 0) return;
    sv = r->v > 0.0 ? 1.0 : -1.0;
    settle(r, t->s, 1, &v_s, &X_s);
    rev = -sv * v_s;
    if (rev > 1e-12 * r->v_max) {
        double cut = djl_ceil(2.0 * per_sample(rev, djl_fabs(r->level), r->Te));
        double Nmin = (double)(stage_start_end(r) - t->s[0].tau);
        t->s[0].N = (int32_t)dmax2((double)t->s[0].N - cut, dmax2(Nmin, 1.0));
        t->clipped = 2;
    }
}

/* Filter of the step that ends the stage in progress. */
static int32_t ending_filter(const replan_state *r, const int32_t N[4])
{
    return r->speeding_up ? N[1] : N[3];
}

/* Rest position (relative to o) if the transition t is followed at once by a stop. */
static double rest_after(const replan_state *r, const transition *t, const int32_t N[4],
                         double *v_s_out)
{
    djl_step all[12];
    memset(all, 0, sizeof all);
    double v_s, X_s;
    int n = t->n, i;
    int64_t T;
    for (i = 0; i < n; i++) all[i] = t->s[i];
    settle(r, all, n, &v_s, &X_s);
    T = imax2(ramps_end(r, all, n), r->b - r->o);
    n += stop_steps(v_s, T, N, r->d_max, r->Te, all + n);
    if (v_s_out) *v_s_out = v_s;
    settle(r, all, n, &v_s, &X_s);
    return X_s;
}

/* Speeding up towards the target (relative to o, Dt) at a level of at least
 * a_max / 2: the last sample e >= b at which the acceleration stage may end, so
 * that the settled velocity stays within v_max and a stop right after still
 * ends short of the target; e = b when there is no such room.  The ending ramp's filter is shortened (clipped)
 * when even e = b would settle above v_max. */
static void choose_end(const replan_state *r, transition *t, int32_t Nend, const int32_t N[4],
                       double Dt)
{
    double sg = r->level > 0.0 ? 1.0 : -1.0, v_s, X_s, room;
    int64_t b = r->b - r->o, lo, hi;
    int round;
    end_stage(r, t, b, Nend);
    if (t->clipped) return;
    settle(r, t->s, t->n, &v_s, &X_s);
    if (!(sg * (Dt - rest_after(r, t, N, NULL)) > 0.0)) return;
    /* a weak stage (as that of a small move, its level far below a_max) is not
     * worth going on with: the new motion may use a_max */
    if (djl_fabs(r->level) < 0.5 * r->a_max) return;
    room = per_sample(r->v_max - sg * v_s, djl_fabs(r->level), r->Te);
    if (!(room >= 1.0)) return;
    lo = b;                                          /* satisfies both */
    hi = b + (int64_t)dmin2(djl_floor(room), 1e12);  /* satisfies v_max */
    for (round = 0; round < 64 && hi > lo; round++) {
        int64_t mid = lo + (hi - lo + 1) / 2;
        end_stage(r, t, mid, Nend);
        if (sg * (Dt - rest_after(r, t, N, NULL)) >= 0.0)
            lo = mid;
        else
            hi = mid - 1;
    }
    end_stage(r, t, lo, Nend);
}

static int walk(const replan_state *r, const djl_step *nw, int n_new, int64_t T, djl_plan *out,
                double st[4]);

/* The scale of the velocities a walk to T sums (m/s): the output's and the AL
 * profile's at o and every change of velocity the level, the kept ramps and
 * the new steps bring by T.  A velocity below 10^-12 of it is a rounding
 * residue; the scale holds only speeds the motion reaches, never v_max itself
 * (v_max = 10^300 must not make a real speed a residue). */
static double v_scale(const replan_state *r, const djl_step *nw, int n_new, int64_t T)
{
    double s = djl_fabs(r->v) + djl_fabs(r->v_al) + djl_fabs(r->level) * r->Te * (double)T;
    int i;
    for (i = 0; i < r->n_run; i++) s += djl_fabs(r->run[i].A) * r->Te * (double)r->run[i].N;
    for (i = 0; i < n_new; i++)
        s += djl_fabs(nw[i].A) * r->Te * (double)imax2(T - nw[i].tau, nw[i].N);
    return s;
}

/* Velocity the ramps settle to, as the pieces will have it (their walk: the
 * closed-form settle differs from it by roundings, which a stop must not leave
 * behind as a creeping speed). */
static double settled_v(const replan_state *r, const djl_step *nw, int n_new)
{
    double st[4];
    int64_t T = imax2(ramps_end(r, nw, n_new), r->b - r->o);
    (void)walk(r, nw, n_new, T, NULL, st);
    /* a rounding residue: at rest */
    return djl_fabs(st[1]) <= 1e-12 * v_scale(r, nw, n_new, T) ? 0.0 : st[1];
}

/* A stop: the stage in progress ends, then stages 3 and 4 bring the axis to
 * rest from the velocity it settles to.  A deceleration in progress may
 * instead go on until the velocity is 0 exactly (its end step split over two
 * samples): whichever comes to rest first (a weak deceleration, as the last
 * stage of a small move, is not worth going on with). */
static void stop_transition(const replan_state *r, transition *t, const int32_t N[4])
{
    int64_t b = r->b - r->o;
    double v_s;
    int32_t Nend = ending_filter(r, N);
    transition on;
    end_stage(r, t, b, Nend);
    no_reversal(r, t);
    on.n = 0;
    if (t->n == 1) {
        /* going on: e and the split f; the ending filter is end_stage's, which
         * already ends no earlier than the stage's starting ramp */
        double q, e, f;
        on = *t;
        v_s = settled_v(r, on.s, 1);
        q = v_s * r->level < 0.0 ? per_sample(-v_s, r->level, r->Te) : -1.0;
        if (q >= 0.0 && q < 1e15) {
            e = djl_floor(q);
            f = q - e;
            on.s[0].tau = b + (int64_t)e;
            on.s[0].A = -r->level * (1.0 - f);
            on.s[1] = on.s[0];
            on.s[1].tau = on.s[0].tau + 1;
            on.s[1].A = -r->level * f;
            on.n = f > 0.0 ? 2 : 1;
            on.end_at = on.s[0].tau;
        } else {
            on.n = 0;
        }
    }
    v_s = settled_v(r, t->s, t->n);
    t->n += stop_steps(v_s, imax2(ramps_end(r, t->s, t->n), b), N, r->d_max, r->Te,
                       t->s + t->n);
    if (on.n > 0 && ramps_end(r, on.s, on.n) <= ramps_end(r, t->s, t->n)) *t = on;
}

/* Walk the pieces from o (relative sample 0) to T: the kept ramps and the
 * new steps, state carried in closed form from piece to piece (as a planned
 * motion's walk).  With out, the pieces are written from out->piece[0];
 * returns their number (-1 if they do not fit) and the state at T. */
static int walk(const replan_state *r, const djl_step *nw, int n_new, int64_t T, djl_plan *out,
                double st[4])
{
    int64_t bnd[2 * DJL_MAX_PLAN_STEPS + 24];
    int nb = 0, i, j, q, np = 0;
    double x = 0.0, v = r->v, a = r->a, xal = r->x_al - r->x, val = r->v_al, level = r->level;
    bnd[nb++] = 0;
    bnd[nb++] = T;
    for (i = 0; i < r->n_run; i++) bnd[nb++] = r->run[i].tau + r->run[i].N;
    for (i = 0; i < n_new; i++) {
        bnd[nb++] = nw[i].tau;
        bnd[nb++] = nw[i].tau + nw[i].N;
    }
    /* sort, unique, keep [0, T] */
    for (i = 1; i < nb; i++) {
        int64_t k = bnd[i];
        for (j = i - 1; j >= 0 && bnd[j] > k; j--) bnd[j + 1] = bnd[j];
        bnd[j + 1] = k;
    }
    for (i = 0, j = 0; i < nb; i++)
        if (bnd[i] >= 0 && bnd[i] <= T && (j == 0 || bnd[i] != bnd[j - 1])) bnd[j++] = bnd[i];
    nb = j;
    if (out && nb > DJL_MAX_PIECES - 1) return -1;
    for (i = 0; i < nb; i++) {
        int64_t k = bnd[i];
        double jerk = 0.0, L;
        int32_t stage = 0;
        int64_t started = INT64_MIN;
        for (q = 0; q < n_new; q++)
            if (nw[q].tau == k) {
                level += nw[q].A;
                if (nw[q].N == 0) a += nw[q].A;
            }
        for (q = 0; q < r->n_run; q++) {
            const djl_step *s = &r->run[q];
            if (s->tau <= k && k < s->tau + s->N) {
                jerk += s->A / (s->N * r->Te);
                if (s->tau >= started) {
                    started = s->tau;
                    stage = s->stage;
                }
            }
        }
        for (q = 0; q < n_new; q++) {
            const djl_step *s = &nw[q];
            if (s->N > 0 && s->tau <= k && k < s->tau + s->N) {
                jerk += s->A / (s->N * r->Te);
                if (s->tau >= started) {
                    started = s->tau;
                    stage = s->stage;
                }
            }
        }
        if (k == T) break;
        if (out) {
            djl_piece *pc = &out->piece[np];
            pc->k = k;
            pc->x = x;
            pc->v = v;
            pc->a = a;
            pc->j = jerk;
            pc->x_al = xal;
            pc->v_al = val;
            pc->a_al = level;
            pc->seg = 1;
            pc->stage = stage;
        }
        np++;
        L = (double)(bnd[i + 1] - k) * r->Te;
        x += L * (v + L * (0.5 * a + L * jerk / 6.0));
        v += L * (a + 0.5 * L * jerk);
        a += L * jerk;
        xal += L * (val + 0.5 * L * level);
        val += L * level;
    }
    st[0] = x;
    st[1] = v;
    st[2] = xal;
    st[3] = level;
    return np;
}

/* The new motion after the transition: from the cruise at v (m/s) to dist m
 * further, at rest, with the goal's jerk times (0: none needed). */
static djl_status fresh_plan(const djl_plan *old, const replan_state *r, const djl_goal *g,
                             double v, double dist, djl_plan *scratch, djl_error *err)
{
    djl_params q = old->p;
    int i, al = g->N[0] == 0 && g->N[1] == 0 && g->N[2] == 0 && g->N[3] == 0;
    q.v_max = r->v_max;
    q.a_max = r->a_max;
    q.d_max = r->d_max;
    q.profile = al ? DJL_PROFILE_AL : DJL_PROFILE_DJL;
    for (i = 0; i < 4; i++) q.T_F[i] = al ? q.Te : (double)g->N[i] * q.Te;
    q.x0 = 0.0;
    q.v0 = dmax2(-q.v_max, dmin2(q.v_max, v));
    q.distance = dist;
    q.v_e = g->kind == DJL_GOAL_TARGET ? g->v_end : 0.0;
    q.n_segments = 0;
    if (g->keep_speed && q.v0 * dist >= 0.0 && dist != 0.0) {
        /* no faster than planned (or than now): a cruise keeps its speed, the landing
         * falls to the deceleration */
        djl_params k = q;
        k.v_max = dmin2(q.v_max, dmax2(djl_fabs(q.v0), old->v_reached));
        if (djl_plan_motion(&k, scratch, err) == DJL_OK) {
            scratch->p.v_max = q.v_max;
            return DJL_OK;
        }
    }
    return djl_plan_motion(&q, scratch, err);
}

/* The new plan: the transition's pieces and steps, then those of the new
 * motion in fresh (if any), or a rest at T.  Nothing is written before every
 * check has passed (out may be the old plan). */
static djl_status compose(const djl_plan *old, const replan_state *r, const transition *t,
                          int64_t T, const djl_plan *fresh, const djl_goal *g, djl_plan *out,
                          djl_error *err)
{
    double st[4], x_goal, kend;
    djl_params p = old->p;
    int np, i, ns;
    /* the new plan's limits: the larger of the old plan's and the goal's (its pieces hold
     * the old plan's ramps as well as the new motion) */
    p.v_max = dmax2(p.v_max, r->v_max);
    p.a_max = dmax2(p.a_max, r->a_max);
    p.d_max = dmax2(p.d_max, r->d_max);
    /* a motion ending past DJL_MAX_PLAN_END: the FMU could neither reach its end nor
     * keep it in a state (issue 21: a stop at d_max = 3e-27 m/s^2 planned 1.6e15
     * samples, and the FMU then refused its own state) */
    kend = (double)T + (fresh ? (double)fresh->k_end : 0.0);
    if (!(kend <= (double)DJL_MAX_PLAN_END))
        return set_error(err, DJL_E_INFEASIBLE, "d_max", p.d_max,
                         "replan: the new motion would end %g samples of Te = %g s after the "
                         "replan, past the %g a motion may reach: with d_max = %g m/s2 a stop "
                         "from %g m/s takes too long", kend - (double)r->o, p.Te,
                         (double)DJL_MAX_PLAN_END, p.d_max, djl_fabs(r->v));
    np = walk(r, t->s, t->n, T, NULL, st);
    if (r->n_run + t->n + (fresh ? fresh->n_steps : 0) > DJL_MAX_PLAN_STEPS ||
        np + (fresh ? fresh->n_pieces : 1) > DJL_MAX_PIECES)
        return set_error(err, DJL_E_INTERNAL, "", 0.0,
                         "replan: %d ramps still running and the new motion do not fit in a "
                         "plan", r->n_run);
    x_goal = g->kind == DJL_GOAL_TARGET ? g->target - r->x : 0.0;
    /* the old plan is read no more from here on */
    np = walk(r, t->s, t->n, T, out, st);
    ns = 0;
    for (i = 0; i < r->n_run; i++) out->step[ns++] = r->run[i];
    for (i = 0; i < t->n; i++) out->step[ns++] = t->s[i];
    if (fresh) {
        for (i = 0; i < fresh->n_pieces; i++) {
            djl_piece pc = fresh->piece[i];
            pc.k += T;
            pc.x += st[0];
            pc.x_al += st[2];
            out->piece[np++] = pc;
        }
        for (i = 0; i < fresh->n_steps; i++) {
            out->step[ns] = fresh->step[i];
            out->step[ns++].tau += T;
        }
        out->k_end = T + fresh->k_end;
        out->v_reached = dmax2(fresh->v_reached, djl_fabs(st[1]));
        out->a_reached = fresh->a_reached;
        out->d_reached = fresh->d_reached;
        out->seg[0] = fresh->seg[0];
        out->seg[0].start += T;
    } else {
        /* at rest (a stop's steps settle to v = 0, up to rounding) */
        djl_piece *pc = &out->piece[np++];
        pc->k = T;
        pc->x = st[0];
        pc->v = 0.0;
        pc->a = 0.0;
        pc->j = 0.0;
        pc->x_al = st[2];
        pc->v_al = 0.0;
        pc->a_al = 0.0;
        pc->seg = 1;
        pc->stage = 0;
        out->k_end = T;
        out->v_reached = djl_fabs(st[1]);
        out->a_reached = 0.0;
        out->d_reached = 0.0;
        memset(&out->seg[0], 0, sizeof out->seg[0]);
        x_goal = st[0];
    }
    out->n_pieces = np;
    out->n_steps = ns;
    out->level0 = r->settled;
    out->replanned = 1;
    for (i = 0; i < 4; i++) out->N[i] = g->N[i];
    out->n_segments = 1;
    p.x0 = r->x;
    p.v0 = dmax2(-p.v_max, dmin2(p.v_max, r->v));
    p.n_segments = 0;
    p.distance = x_goal;
    p.v_e = fresh ? fresh->p.v_e : 0.0;
    out->p = p;
    out->x_target = x_goal;
    out->v_target = fresh ? fresh->v_target : 0.0;
    return DJL_OK;
}

/* Does the stop of t rest past where *old rests?  In the direction the axis moves at o
 * (from rest: towards that rest), when *old goes there without turning back: a stop
 * never rests past the target of the move it stops (nor, for a stop replanned, past the
 * rest it was planned to).  A plan that ends moving, or that comes to rest or turns back
 * before its end (it stops first and comes back: its target lies within its stopping
 * distance, and so within the stop's), bounds nothing. */
static int stop_passes(const djl_plan *old, const replan_state *r, const transition *t,
                       double *rest, double *bound)
{
    djl_sample s;
    int32_t cur = 0;
    double st[4], xe, sg, tol;
    int64_t T;
    int i;
    if (old->v_target != 0.0) return 0;
    djl_eval(old, (double)old->k_end, &cur, &s);
    xe = s.x - r->x; /* where the plan in progress rests, relative to o */
    sg = r->v > 0.0 ? 1.0 : r->v < 0.0 ? -1.0 : xe > 0.0 ? 1.0 : xe < 0.0 ? -1.0 : 0.0;
    if (sg == 0.0 || sg * xe < 0.0) return 0;
    if (old->p.profile == DJL_PROFILE_TABLE && !old->replanned) {
        /* a replayed table may rest on the way, and at its target before its end (pieces
         * of zero jerk): only turning back bounds nothing -- a velocity against the move
         * at a piece's start or where it is least inside a piece, from o on */
        for (i = 0; i + 1 < old->n_pieces; i++) {
            const djl_piece *pc = &old->piece[i];
            double L = (double)(old->piece[i + 1].k - pc->k) * r->Te, ts;
            if (old->piece[i + 1].k <= r->o) continue;
            if (pc->k > r->o && sg * pc->v < -1e-12 * r->v_max) return 0;
            ts = pc->j != 0.0 ? -pc->a / pc->j : -1.0;
            if (ts > 0.0 && ts < L && sg * (pc->v + ts * (pc->a + 0.5 * ts * pc->j)) <
                                          -1e-12 * r->v_max)
                return 0;
        }
    } else {
        for (i = 0; i < old->n_pieces; i++) /* at rest or turning back before the end? */
            if (old->piece[i].k > r->o && old->piece[i].k < old->k_end &&
                sg * old->piece[i].v <= 1e-12 * r->v_max)
                return 0;
    }
    T = imax2(ramps_end(r, t->s, t->n), r->b - r->o);
    (void)walk(r, t->s, t->n, T, NULL, st);
    /* rounding: a trillionth of the distance to that rest and of a sample at v_max, and
     * the resolution of the positions */
    tol = 1e-12 * (djl_fabs(xe) + r->v_max * r->Te) + 4e-16 * (djl_fabs(s.x) + djl_fabs(r->x));
    *rest = r->x + st[0];
    *bound = s.x;
    return sg * (st[0] - xe) > tol;
}

djl_status djl_replan(const djl_plan *old, double u, const djl_goal *g, djl_plan *out,
                      djl_plan *scratch, djl_replan_info *info, djl_error *err)
{
    replan_state r;
    transition t;
    djl_error e2;
    djl_replan_info inf;
    double Dt, st[4];
    int64_t T;
    int i, how;
    int32_t Nend;
    if (err) memset(err, 0, sizeof(*err));
    memset(&inf, 0, sizeof inf);
    if (!djl_isfinite(u) || djl_fabs(u) > (double)DJL_MAX_MOTION_SAMPLES)
        return set_error(err, DJL_E_PARAM, "u", u, "replan at %g samples: out of range", u);
    if (g->kind != DJL_GOAL_TARGET && g->kind != DJL_GOAL_STOP)
        return set_error(err, DJL_E_PARAM, "goal", (double)g->kind, "replan: unknown goal %d",
                         (int)g->kind);
    if (!djl_isfinite(g->v_end) || (g->v_end != 0.0 && g->kind != DJL_GOAL_TARGET))
        return set_error(err, DJL_E_PARAM, "v_end", g->v_end,
                         "replan: end velocity %g m/s: must be finite, and 0 for a stop",
                         g->v_end);
    if (g->kind == DJL_GOAL_TARGET &&
        !(djl_isfinite(g->target) && djl_fabs(g->target) <= DJL_MAX_POSITION))
        return set_error(err, DJL_E_PARAM, "target", g->target,
                         "target = %g m: must be finite and |target| <= %g m", g->target,
                         DJL_MAX_POSITION);
    for (i = 0; i < 4; i++)
        if (g->N[i] < 0 || g->N[i] > DJL_MAX_FILTER_SAMPLES)
            return set_error(err, DJL_E_PARAM, "N", (double)g->N[i],
                             "replan: jerk time of stage %d, %d samples, out of range", i + 1,
                             (int)g->N[i]);
    for (i = 0; i < 3; i++) {
        double lim = i == 0 ? g->v_max : i == 1 ? g->a_max : g->d_max;
        if (!(lim == 0.0 || (djl_isfinite(lim) && lim > 0.0)))
            return set_error(err, DJL_E_PARAM, i == 0 ? "v_max" : i == 1 ? "a_max" : "d_max",
                             lim, "replan: limit %g: must be 0 (the old plan's) or a finite "
                             "number > 0", lim);
    }
    gather(old, u, &r);
    /* the goal's limits, where it gives them (0: the old plan's) */
    if (g->v_max > 0.0) r.v_max = g->v_max;
    if (g->a_max > 0.0) r.a_max = g->a_max;
    if (g->d_max > 0.0) r.d_max = g->d_max;
    /* the axis already faster than the goal's v_max: ending its stage cannot bring it
     * within, and keeps it within the old plan's (the new motion then starts with a
     * stop) */
    r.lower = g->v_max > 0.0 && g->v_max < old->p.v_max;
    r.above = r.lower && djl_fabs(r.v) > r.v_max;
    inf.origin = r.o;
    inf.b = r.b;
    Nend = ending_filter(&r, g->N);

    if (g->kind == DJL_GOAL_STOP) {
        double rest, bound;
        stop_transition(&r, &t, g->N);
        how = 3;
        if (stop_passes(old, &r, &t, &rest, &bound)) {
            if (g->no_stop_first)
                return set_error(err, DJL_E_INFEASIBLE, "N", (double)g->N[2],
                                 "with the jerk times %d/%d/%d/%d samples the stop would rest "
                                 "at %.17g m, past %.17g m where the motion in progress rests",
                                 (int)g->N[0], (int)g->N[1], (int)g->N[2], (int)g->N[3], rest,
                                 bound);
            /* the motion in progress is kept: it rests no further */
            if (out != old) memcpy(out, old, sizeof *out);
            inf.origin = 0;
            inf.how = 0;
            inf.end_at = -1;
            inf.kept = 1;
            inf.v_settled = 0.0;
            if (info) *info = inf;
            return DJL_OK;
        }
    } else {
        Dt = g->target - r.x;
        if (r.level != 0.0 && r.speeding_up)
            choose_end(&r, &t, Nend, g->N, Dt);
        else
            end_stage(&r, &t, r.b - r.o, Nend);
        how = 1;
    }
    /* 1: the new motion once the stage has ended; 4: the same, the stage ended at
     * b; 2: a stop, then the new motion from rest; 3: a stop */
    for (;;) {
        djl_status s2;
        double dist, v, vs;
        T = ramps_end(&r, t.s, t.n);
        if (r.b - r.o > T) T = r.b - r.o; /* nothing new before b */
        (void)walk(&r, t.s, t.n, T, NULL, st); /* the state at T, as the pieces will have it */
        inf.v_settled = st[1];
        if (how == 3) {
            s2 = compose(old, &r, &t, T, NULL, g, out, err);
            if (s2 != DJL_OK) return s2;
            break;
        }
        dist = (g->target - r.x) - st[0];
        vs = v_scale(&r, t.s, t.n, T);
        v = how == 2 || djl_fabs(st[1]) <= 1e-12 * vs ? 0.0 : st[1]; /* at rest: rounding */
        /* at rest within a trillionth of the positions (and of a sample's travel at the
         * speeds the walk sums): arrived (a new move for a rounding residue would be all
         * rounding itself).  Only quantities the motion reaches: a tolerance growing
         * with v_max once took a real distance of 3e-4 m for a residue (issue 21) */
        if (v == 0.0 && djl_fabs(dist) <= 1e-12 * (djl_fabs(g->target) + djl_fabs(r.x) +
                                                  djl_fabs(st[0]) + vs * r.Te))
            dist = 0.0;
        if (djl_fabs(dist) < DJL_MIN_MAGNITUDE) dist = 0.0;
        if (dist == 0.0 && v == 0.0 && g->v_end == 0.0) {
            s2 = compose(old, &r, &t, T, NULL, g, out, err);
            if (s2 != DJL_OK) return s2;
            break;
        }
        if (how != 2 && v != 0.0 && g->v_end == 0.0) {
            /* no new motion from v if stopping at once already passes the target */
            double vv, X = rest_after(&r, &t, g->N, &vv);
            if ((v > 0.0 ? 1.0 : -1.0) * ((g->target - r.x) - X) < 0.0) {
                s2 = DJL_E_INFEASIBLE;
                goto fallback;
            }
        }
        if (r.lower && djl_fabs(v) > r.v_max * (1.0 + 1e-9)) {
            /* faster than the goal's v_max (a lower one than the old plan's): no motion
             * starts from there, the axis stops first */
            set_error(&e2, DJL_E_INFEASIBLE, "v_max", r.v_max, "replan: the axis settles "
                      "at %g m/s, above v_max = %g m/s", v, r.v_max);
            s2 = DJL_E_INFEASIBLE;
            goto fallback;
        }
        s2 = fresh_plan(old, &r, g, v, dist, scratch, &e2);
        if (s2 == DJL_OK) {
            s2 = compose(old, &r, &t, T, scratch, g, out, err);
            if (s2 != DJL_OK) return s2;
            break;
        }
    fallback:
        if (how == 1 && t.end_at > r.b - r.o) {
            /* the stage went on too long for the landing: end it at b */
            end_stage(&r, &t, r.b - r.o, Nend);
            how = 4;
            continue;
        }
        if (how == 1 || how == 4) {
            if (g->no_stop_first || g->v_end != 0.0)
                return set_error(err, DJL_E_INFEASIBLE, "N", (double)g->N[0],
                                 "with the jerk times %d/%d/%d/%d samples the axis would have "
                                 "to stop and come back to land", (int)g->N[0], (int)g->N[1],
                                 (int)g->N[2], (int)g->N[3]);
            stop_transition(&r, &t, g->N);
            how = 2;
            continue;
        }
        /* from rest, the planner refused: its reason */
        if (err) *err = e2;
        return s2;
    }
    inf.how = how == 4 ? 1 : how;
    inf.end_at = t.end_at < 0 ? -1 : t.end_at + r.o;
    inf.clipped = t.clipped;
    inf.lengthened = t.lengthened;
    if (info) *info = inf;
    return DJL_OK;
}

int djl_jerk_times_due(const djl_plan *plan, double u, double u_end, const int32_t N[4],
                       int allow_now, double *at)
{
    double b = djl_floor(u) + 1.0, end = djl_floor(u_end) + 1.0, first = DJL_HUGE_VAL;
    double level = plan->level0, amag = djl_fabs(plan->level0);
    int i, ahead = 0;
    if (!(u < u_end)) return 0;
    for (i = 0; i < plan->n_steps; i++) {
        const djl_step *st = &plan->step[i];
        double tau = (double)st->tau;
        if (tau < b) {
            level += st->A;
            amag += djl_fabs(st->A);
        } else if (st->stage >= 1 && st->stage <= 4 && st->N != N[st->stage - 1]) {
            ahead = 1;
            if (tau < first) first = tau;
        }
    }
    if (!ahead) return 0;
    if (djl_fabs(level) <= 1e-13 * amag) level = 0.0; /* a residue of +A - A (as gather) */
    if (allow_now && level != 0.0 && djl_fabs(level) >= 0.5 * plan->p.a_max) {
        /* speeding up (not slowing down)? */
        djl_sample s;
        int32_t cur = 0;
        djl_eval(plan, djl_floor(u), &cur, &s);
        if (level * s.v < 0.0) allow_now = 0;
    } else if (level != 0.0) {
        allow_now = 0;
    }
    if (allow_now) {
        *at = u;
        return 1;
    }
    if (first < end) {
        *at = first - 1.0; /* a replan at first - 1 changes the plan from first on */
        return 1;
    }
    return 0;
}
