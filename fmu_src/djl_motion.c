/*
 * djl_motion.c -- planning a motion of segments (djl_plan_motion): each
 * segment sized in turn by the solvers of djl_segment.c, the last one landed
 * exactly (the earlier ones absorbing what it cannot), the AL profile's
 * steps, the pieces of the plan (piecewise cubic between boundaries) and
 * their self-check, and the retries (relative formulas, other units).
 */
#include "djl_internal.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>


/* ------------------------------------------------------------------------ */
/* motion planning                                                          */

typedef struct {
    int64_t tau;
    double A;       /* m/s^2, real frame */
    int32_t N;
    double level;   /* AL acceleration right after this step */
    int phase_end;  /* ends a phase: v_after is the velocity once it has settled */
    double v_after;
    int32_t stage;  /* 1..4 (djl_step) */
} al_step;

typedef struct {
    segment_problem c[DJL_MAX_SEGMENTS];
    segment_solution s[DJL_MAX_SEGMENTS];
    int sigma[DJL_MAX_SEGMENTS];
    int empty[DJL_MAX_SEGMENTS];
    double Dreal[DJL_MAX_SEGMENTS], vS[DJL_MAX_SEGMENTS], vE[DJL_MAX_SEGMENTS];
    al_step step[DJL_MAX_STEPS];
    int n_steps;
    int64_t bnd[DJL_MAX_PIECES + 8];
    int lead;       /* DJL: a segment's first stage waits for the previous ramps
                       (segment_problem.g) */
    const djl_params *user; /* the user's parameters (messages) */
    int kl;         /* lengths in units of 2^kl m (djl_plan_motion's rescaled retry) */
} motion_work;

/* More samples than a plan may hold (with the bound's rounding). */
static const double too_many_samples = (double)DJL_MAX_MOTION_SAMPLES * (1.0 + 1e-9);

/* The fewest samples of Te any profile from vs to ve over D takes, in *na
 * accelerating and *nd decelerating (a lower bound).  Whatever the velocity
 * limit, no profile is faster than accelerating at a_max to v* and
 * decelerating at d_max to ve, with
 *     v*^2 = (d vs^2 + a ve^2 + 2 D a d) / (a + d),
 * and when v* < max(vs, ve) (no room to go above both) none is faster than
 * the change of velocity at its limit, nor than what a_max allows from vs
 * (vs T + a T^2/2 >= D) and d_max towards ve.  The generated profile is such
 * a profile (its acceleration stays within the limits).  (Computed without
 * overflow: a and d may be 1e-300 or 1e300.) */
static void least_samples(double D, double vs, double ve, double am, double dm, double Te,
                          double *na, double *nd)
{
    double vt = peak_without_velocity_limit(D, vs, ve, am, dm);
    if (vt >= vs && vt >= ve) {
        /* (vt - vs) / am and (vt - ve) / dm without their cancellation: with a_max
         * = 1e-300 m/s^2 vt rounds to vs, and a cruise of 10^18 samples counted 0
         * (issue 21: 1e15 m from 0.5 m/s was an internal error, not refused).  With
         * r = am / (am + dm):
         *   (vt - vs) / am = ((ve^2 - vs^2) / (am + dm) + 2 D (1 - r)) / (vt + vs),
         *   (vt - ve) / dm = ((vs^2 - ve^2) / (am + dm) + 2 D r) / (vt + ve). */
        double r = 1.0 / (1.0 + dm / am), sum = am + dm; /* sum = inf: those terms are 0 */
        double ta = ((ve - vs) * ((ve + vs) / sum) + 2.0 * D * (1.0 - r)) / (vt + vs);
        double td = ((vs - ve) * ((vs + ve) / sum) + 2.0 * D * r) / (vt + ve);
        if (!(ta >= 0.0) || !(vt + vs > 0.0)) ta = (vt - vs) / am; /* vt = vs = 0: underflow */
        if (!(td >= 0.0) || !(vt + ve > 0.0)) td = (vt - ve) / dm;
        *na = ta / Te;
        *nd = td / Te;
    } else {
        double Ta = 2.0 * D / (vs + djl_hypot(vs, djl_sqrt(2.0 * am) * djl_sqrt(D)));
        double Td = 2.0 * D / (ve + djl_hypot(ve, djl_sqrt(2.0 * dm) * djl_sqrt(D)));
        *na = dmax2(Ta, ve > vs ? (ve - vs) / am : 0.0) / Te;
        *nd = dmax2(Td, ve > vs ? 0.0 : (vs - ve) / dm) / Te;
    }
}

/* Error for segment i, planned in the frame of its direction with the
 * distance c->D (the user's distance plus what the rounding of the earlier
 * segments passed on); dmin is the shortest distance that frame allows. */
static djl_status infeasible(djl_error *err, const djl_params *p, int i, const segment_problem *c,
                             double dmin, int kl)
{
    /* p: the user's parameters; c in units of 2^kl m (djl_plan_motion's
     * rescaled retry; kl = 0 otherwise): lengths are printed converted */
    char dname[40], left[120] = "";
    double D = p->n_segments == 0 ? p->distance : p->seg_distance[i];
    double vs = (p->n_segments == 0 || i == 0 ? p->v0 : p->seg_v_end[i - 1]) + 0.0; /* no -0 */
    double ve = (p->n_segments == 0 ? p->v_e : p->seg_v_end[i]) + 0.0;
    if (p->n_segments == 0)
        snprintf(dname, sizeof dname, "distance");
    else
        snprintf(dname, sizeof dname, "seg_distance[%d]", i + 1);
    if (c->vs == c->ve && c->vs > 0.0) {
        /* a cruise that must land exactly needs room for a small dip */
        segment_problem c2 = *c;
        c2.merge23 = 1;
        dmin = distance_continuous(&c2, c->vs, 0.0);
    }
    if (c->D >= dmin && (c->ve == 0.0 || !c->last)) {
        /* the distance left to this segment may not be the user's: a rounded segment
         * before it passed on its residual (up to half a sample of travel at its speed,
         * documented).  If no profile within the limits covers that distance in the
         * samples a plan may hold, the limits are too low for the residual: infeasible
         * (issue 21: a_max = 1e-30 m/s^2 and a residual of 6e-4 m into an empty last
         * segment, a_max = 1e-300 m/s^2 with Te = 4e154 s, were internal errors) */
        double na, nd, passed = djl_ldexp(c->D, -kl) - djl_fabs(D);
        /* the stages' ramps and their rounding to whole samples lengthen a profile beyond
         * least_samples: the solver, which stops at the horizon, finds none when that bound
         * is within them (and the bound's rounding) of it (issue 21, third session: 100 m
         * from rest with a_max = 2e-22 m/s^2 needs exactly 10^15 samples of 1 ms, and was
         * an internal error, not refused) */
        double ramps = (double)c->N1 + (double)c->N2 + (double)c->N3 + (double)c->N4 + 8.0;
        least_samples(c->D, c->vs, c->ve, c->am, c->dm, c->Te, &na, &nd);
        if (na + nd + ramps > (double)DJL_MAX_MOTION_SAMPLES * (1.0 - 1e-9) &&
            !(passed > 0.5 * djl_ldexp(c->D, -kl)))
            return set_error(err, DJL_E_INFEASIBLE, na >= nd ? "a_max" : "d_max",
                             na >= nd ? p->a_max : p->d_max,
                             "%s = %g m from %g m/s to %g m/s (a_max = %g m/s2, d_max = %g "
                             "m/s2): the move needs at least %g samples of Te = %g s, %g of "
                             "them %s; with its jerk ramps (%g samples) and its stages rounded "
                             "to whole samples it does not fit in the %g a plan may hold",
                             dname, D, vs, ve, p->a_max, p->d_max, na + nd, p->Te,
                             na >= nd ? na : nd, na >= nd ? "accelerating" : "decelerating",
                             ramps - 8.0, (double)DJL_MAX_MOTION_SAMPLES);
        if (na + nd + ramps > (double)DJL_MAX_MOTION_SAMPLES * (1.0 - 1e-9))
            return set_error(err, DJL_E_INFEASIBLE, na >= nd ? "a_max" : "d_max",
                             na >= nd ? p->a_max : p->d_max,
                             "%s = %g m from %g m/s to %g m/s: the rounding of the segments "
                             "before it to whole samples passes on %g m (half a sample of "
                             "travel at their speed at most), which a_max = %g m/s2 and "
                             "d_max = %g m/s2 cannot cover in the %g samples of Te = %g s a "
                             "plan may hold (it needs %g)", dname, D, vs, ve,
                             djl_ldexp(c->D, -kl) - djl_fabs(D), p->a_max,
                             p->d_max, (double)DJL_MAX_MOTION_SAMPLES, p->Te, na + nd);
        /* theory says a profile exists (docs/generator.md): a planner limitation */
        return set_error(err, DJL_E_INTERNAL, dname, D,
                         "%s = %g m from %g m/s to %g m/s (v_max = %g m/s, a_max = %g m/s2, "
                         "d_max = %g m/s2, Te = %g s): the planner found no profile landing "
                         "exactly on a sample although one should exist; please report it",
                         dname, D, vs, ve, p->v_max, p->a_max, p->d_max, p->Te);
    }
    if (c->last && c->ve != 0.0 && c->D >= dmin) {
        /* beyond the minimum, room for a dip worth one sample of travel at v
         * (area a t^2/4 in a time t) and for the jerk times of its stages:
         * an estimate the randomised C driver checks (in the user's terms:
         * the residual carried in counts) */
        double v = dmax2(c->vs, c->ve);
        double room = dmin + djl_ldexp(djl_fabs(D), kl) - c->D +
                      v * (2.0 * djl_sqrt(v * c->Te / dmin2(c->am, c->dm)) +
                           ((double)c->N1 + c->N2 + c->N3 + c->N4) * c->Te);
        return set_error(err, DJL_E_INFEASIBLE, dname, D,
                         "%s = %g m cannot end exactly on a sample at the non-zero end speed %g "
                         "m/s (from %g m/s, v_max = %g m/s, a_max = %g m/s2, d_max = %g m/s2, "
                         "Te = %g s, the jerk times): the minimum is about %g m and from about "
                         "%g m on every distance lands, only some in between (they need room "
                         "for a speed dip); use a longer distance, or end at rest",
                         dname, D, ve, vs, p->v_max, p->a_max, p->d_max, p->Te,
                         djl_ldexp(dmin, -kl), djl_ldexp(room, -kl));
    }
    dmin = djl_ldexp(dmin, -kl);
    if (djl_fabs(djl_ldexp(c->D, -kl) - djl_fabs(D)) > 1e-12 * (djl_fabs(D) + djl_fabs(dmin)))
        snprintf(left, sizeof left, "; rounding the earlier segments to whole samples left it %g m",
                 djl_ldexp(c->D, -kl));
    if (c->vs == c->ve && c->vs > 0.0)
        return set_error(err, DJL_E_INFEASIBLE, dname, D,
                         "%s = %g m cannot end exactly on a sample cruising at %g m/s (v_max = %g "
                         "m/s, a_max = %g m/s2, d_max = %g m/s2, Te = %g s, the jerk times): a "
                         "pure cruise covers whole samples of %g m, landing in between needs a "
                         "speed dip, and a dip needs about %g m or more%s",
                         dname, D, ve, p->v_max, p->a_max, p->d_max, p->Te,
                         djl_ldexp(c->vs * c->Te, -kl), dmin, left);
    return set_error(err, DJL_E_INFEASIBLE, dname, D,
                     "%s = %g m is too short to go from %g m/s to %g m/s within v_max = %g m/s, "
                     "a_max = %g m/s2, d_max = %g m/s2 and the jerk times at Te = %g s: it needs "
                     "more than about %g m%s", dname, D, vs, ve, p->v_max, p->a_max, p->d_max,
                     p->Te, dmax2(dmin, 0.0), left);
}

static int segment_absorb(motion_work *w, int j, double r_real, int branch)
{
    segment_problem c = w->c[j];
    segment_solution s;
    if (w->empty[j]) return 0;
    /* from the distance the segment was planned for: a rounded (pinned)
     * segment already passed its own residual on */
    c.D = w->s[j].D + w->sigma[j] * r_real;
    if (!(c.D > 0.0)) return 0;
    if (branch == 1 ? !solve_time_optimal(&c, &s) : !solve_monotone_or_dip(&c, branch, &s))
        return 0;
    w->c[j] = c;
    w->s[j] = s;
    return 1;
}

/* Samples by which the ramps of segments 0..L-1 run past the start of L. */
static int64_t tail_into(const motion_work *w, int L)
{
    int64_t start = 0, tail = 0;
    int j;
    for (j = 0; j < L; j++) {
        const segment_solution *s = &w->s[j];
        int64_t e = 0;
        if (w->empty[j]) continue;
        if (s->hasA) e = imax2(e, start + s->g + s->n1 + s->N2);
        if (s->hasD) e = imax2(e, start + s->g + (s->hasA ? s->n1 : 0) + s->k + s->m + s->N4);
        start += s->len;
        tail = imax2(tail, e);
    }
    return imax2(tail - start, 0);
}

/* Let segment j (< L) absorb r_real metres, with the given branch, provided
 * this leaves the end time of the motion unchanged (the last segment was
 * planned with the ramps of the earlier segments running into it). */
static int absorb_into(motion_work *w, int j, int L, double r_real, int branch, int64_t bend_own)
{
    segment_problem c0 = w->c[j];
    segment_solution s0 = w->s[j];
    int64_t t0 = tail_into(w, L), t1;
    int i, ok = 1;
    if (!segment_absorb(w, j, r_real, branch)) return 0;
    t1 = tail_into(w, L);
    if (imax2(t0, bend_own) != imax2(t1, bend_own)) ok = 0;
    for (i = j + 1; i <= L && ok && w->lead; i++)
        if (!w->empty[i] && (double)tail_into(w, i) > w->c[i].g) ok = 0;
    if (ok) return 1;
    w->c[j] = c0;
    w->s[j] = s0;
    return 0;
}

static djl_status land_last_segment(motion_work *w, int n, djl_error *err)
{
    int L = n - 1, j;
    segment_problem *c = &w->c[L];
    segment_solution pin;
    double resid = 0.0, dmin = 0.0;
    int64_t bend_own = 0;

    c->tail_in = (double)tail_into(w, L);
    if (solve_time_optimal(c, &w->s[L])) return DJL_OK;

    if (solve_pinned_single_stage(c, &pin, &resid, &dmin)) {
        double rr = w->sigma[L] * resid;
        segment_problem c0 = *c;
        segment_solution tmp;
        double r0, d0;
        c0.tail_in = 0.0;
        if (solve_pinned_single_stage(&c0, &tmp, &r0, &d0)) bend_own = tmp.bend;
        if (resid == 0.0) {
            w->s[L] = pin;
            return DJL_OK;
        }
        /* A pinned last segment (it cannot leave its velocity) is rounded and
         * an earlier segment takes up the residual: first one that can move
         * its peak velocity, then a cruise that can dip. */
        for (j = L - 1; j >= 0; j--)
            if (absorb_into(w, j, L, rr, 1, bend_own)) {
                w->s[L] = pin;
                return DJL_OK;
            }
        for (j = L - 1; j >= 0; j--)
            if (w->c[j].vs == w->c[j].ve && absorb_into(w, j, L, rr, 3, bend_own)) {
                w->s[L] = pin;
                return DJL_OK;
            }
    }
    /* Otherwise the last segment lands by itself: its single stage ends
     * between two samples, or two stages in the same direction, or a dip. */
    if (solve_split_sample(c, &w->s[L])) return DJL_OK;
    if (solve_monotone_or_dip(c, 2, &w->s[L]) || solve_monotone_or_dip(c, 3, &w->s[L]))
        return DJL_OK;
    if (pin.ok) {
        double rr = w->sigma[L] * resid;
        for (j = L - 1; j >= 0; j--)
            if (absorb_into(w, j, L, rr, 2, bend_own) || absorb_into(w, j, L, rr, 3, bend_own)) {
                w->s[L] = pin;
                return DJL_OK;
            }
    }
    if (solve_fit_peak_grid(c, &w->s[L])) return DJL_OK;
    return infeasible(err, w->user, L, c, dmin, w->kl);
}

/* A move that the acceleration limits make longer than a plan may hold (its
 * least_samples beyond DJL_MAX_MOTION_SAMPLES) cannot be planned: it is
 * refused here, naming the limit that takes the longer part. */
static djl_status check_duration(const djl_params *p, int i, djl_error *err)
{
    double Dr = p->n_segments == 0 ? p->distance : p->seg_distance[i];
    double vE = p->n_segments == 0 ? p->v_e : p->seg_v_end[i];
    double vS = i == 0 ? p->v0 : p->seg_v_end[i - 1];
    double sg = Dr < 0.0 ? -1.0 : 1.0, D = djl_fabs(Dr), vs = sg * vS, ve = sg * vE, Te = p->Te;
    double am = p->a_max, dm = p->d_max, na, nd;
    char dname[40];
    if (!(D > 0.0)) return DJL_OK;
    least_samples(D, vs, ve, am, dm, Te, &na, &nd);
    if (!(na + nd > too_many_samples)) return DJL_OK;
    if (p->n_segments == 0)
        snprintf(dname, sizeof dname, "distance");
    else
        snprintf(dname, sizeof dname, "seg_distance[%d]", i + 1);
    if (na >= nd)
        return set_error(err, DJL_E_INFEASIBLE, "a_max", am,
                         "a_max = %g m/s2 is too low for %s = %g m from %g m/s to %g m/s "
                         "(d_max = %g m/s2): the move needs at least %g samples of Te = %g s, "
                         "%g of them accelerating, more than the %g a plan may hold", am, dname,
                         Dr, vS, vE, dm, na + nd, Te, na, (double)DJL_MAX_MOTION_SAMPLES);
    return set_error(err, DJL_E_INFEASIBLE, "d_max", dm,
                     "d_max = %g m/s2 is too low for %s = %g m from %g m/s to %g m/s "
                     "(a_max = %g m/s2): the move needs at least %g samples of Te = %g s, "
                     "%g of them decelerating, more than the %g a plan may hold", dm, dname, Dr,
                     vS, vE, am, na + nd, Te, nd, (double)DJL_MAX_MOTION_SAMPLES);
}

static void add_step(motion_work *w, int64_t tau, double A, int32_t N, double level, int phase_end,
                     double v_after, int32_t stage)
{
    al_step *st;
    if (A == 0.0) return;
    st = &w->step[w->n_steps++];
    st->stage = stage;
    st->tau = tau;
    st->A = A;
    st->N = N;
    st->level = level;
    st->phase_end = phase_end;
    st->v_after = v_after;
}

static void sort_unique(int64_t *a, int *n)
{
    int i, j, m = 0;
    for (i = 1; i < *n; i++) {
        int64_t x = a[i];
        for (j = i - 1; j >= 0 && a[j] > x; j--) a[j + 1] = a[j];
        a[j + 1] = x;
    }
    for (i = 0; i < *n; i++)
        if (m == 0 || a[i] != a[m - 1]) a[m++] = a[i];
    *n = m;
}

static int64_t ramp_tail_after(const motion_work *w, int64_t t)
{
    int i;
    int64_t tail = 0;
    for (i = 0; i < w->n_steps; i++) {
        int64_t e = w->step[i].tau + w->step[i].N;
        if (e - t > tail) tail = e - t;
    }
    return tail;
}

/* Exact-mode state at sample b (see walk_pieces): the velocity from the
 * plateau of the last phase that has settled (with every phase before it),
 * plus what the phases after it have brought so far; the acceleration from
 * the phases under way.  A phase of two steps +A, -A is evaluated as a
 * whole, in forms free of the cancellation between its two ramps (long
 * overlapping ramps of opposite signs differ by little). */
static double ramp_g1(double u, double N) /* velocity of a unit step, in samples */
{
    if (u <= 0.0) return 0.0;
    if (u >= N) return u - 0.5 * N;
    return 0.5 * u * u / N;
}

static double ramp_r(double u, double N) /* acceleration of a unit step */
{
    if (u < 0.0) return 0.0;
    if (u >= N) return 1.0;
    return u / N;
}

/* Acceleration (*a, per unit) and velocity (*dv, per unit and Te) the steps
 * q0..q1 of one phase have brought at sample b. */
static void phase_state(const motion_work *w, int q0, int q1, int64_t b, double *a, double *dv)
{
    int r;
    *a = 0.0;
    *dv = 0.0;
    if (q1 == q0 + 1 && w->step[q1].A == -w->step[q0].A) {
        double A = w->step[q0].A, Na = w->step[q0].N, Nb = w->step[q1].N;
        double ua = (double)(b - w->step[q0].tau), ub = (double)(b - w->step[q1].tau);
        double n = ua - ub; /* whole samples: exact */
        if (ub < 0.0) { /* second step still to come */
            *a = A * ramp_r(ua, Na);
            *dv = A * ramp_g1(ua, Na);
        } else if (ua >= Na && ub >= Nb) { /* over: the phase's velocity jump */
            *dv = A * (n + 0.5 * (Nb - Na));
        } else if (ua >= Na) { /* first ramp over, second running */
            *a = A * ((Nb - ub) / Nb);
            *dv = A * (n + 0.5 * (Nb - Na) - 0.5 * (Nb - ub) * (Nb - ub) / Nb);
        } else if (ub >= Nb) { /* second ramp (the shorter) over, first running */
            *a = -A * ((Na - ua) / Na);
            *dv = A * (n + 0.5 * (Nb - Na) + 0.5 * (Na - ua) * (Na - ua) / Na);
        } else if (Na == Nb) { /* both running, same length */
            *a = A * (n / Na);
            *dv = A * (n * (ua + ub) / (2.0 * Na));
        } else {
            *a = A * (ua / Na - ub / Nb);
            *dv = A * (0.5 * ua * ua / Na - 0.5 * ub * ub / Nb);
        }
        return;
    }
    for (r = q0; r <= q1; r++) {
        double u = (double)(b - w->step[r].tau), N = w->step[r].N;
        *a += w->step[r].A * ramp_r(u, N);
        *dv += w->step[r].A * ramp_g1(u, N);
    }
}

static void exact_state(const motion_work *w, int64_t b, double v0, double Te, double *a_out,
                        double *v_out)
{
    int q = 0, r, settled = 1;
    double a = 0.0, v = v0, dv = 0.0;
    while (q < w->n_steps && w->step[q].tau <= b) {
        int q0 = q, over = 1;
        while (q + 1 < w->n_steps && !w->step[q].phase_end) q++; /* q: the phase's last step */
        for (r = q0; r <= q; r++)
            if (b < w->step[r].tau + w->step[r].N) over = 0;
        if (over && settled) {
            v = w->step[q].v_after; /* every phase up to this one has settled */
        } else {
            double pa, pv;
            settled = 0;
            phase_state(w, q0, q, b, &pa, &pv);
            if (!over) a += pa;
            dv += pv;
        }
        q++;
    }
    *a_out = a;
    *v_out = v + Te * dv;
}

/* Walk the pieces: jerk summed afresh on every piece, state carried from
 * piece to piece in closed form; where no ramp is running the acceleration is
 * the AL level exactly, and where that level is 0 the velocity is the plateau
 * velocity exactly.  With exact, the acceleration and velocity at every
 * boundary are taken from the steps instead of carried: a rounding error of
 * the velocity or acceleration carried into a piece millions of samples long
 * (a jerk time far longer than the stages) grows with its length, or its
 * square, in the position. */
static djl_status walk_pieces(const motion_work *w, djl_plan *plan, const djl_params *p, int n,
                              int nb,
                              double tolx, double scale, int exact, djl_error *err)
{
    int j;
    double x = 0.0, v = p->v0, a = 0.0, xal = 0.0, val = p->v0;
    double vsnap = p->v0, level = 0.0, reach = 0.0;
    int si = 0, seg = 1, last_seg_start = 0;
    plan->n_pieces = 0;
    for (j = 0; j < nb; j++) {
        int64_t b = w->bnd[j];
        djl_piece *pc = &plan->piece[plan->n_pieces++];
        double jerk = 0.0, Lt;
        int quiet = 1, q;
        /* AL level and plateau velocity after the steps at or before b */
        while (si < w->n_steps && w->step[si].tau <= b) {
            level = w->step[si].level;
            if (w->step[si].phase_end) vsnap = w->step[si].v_after;
            si++;
        }
        while (last_seg_start + 1 < n && plan->seg[last_seg_start + 1].start <= b &&
               plan->seg[last_seg_start + 1].start < plan->k_end) {
            last_seg_start++;
        }
        seg = last_seg_start + 1;
        pc->stage = 0;
        for (q = 0; q < w->n_steps; q++) {
            const al_step *sq = &w->step[q];
            if (sq->N > 0 && sq->tau <= b && b < sq->tau + sq->N) {
                jerk += sq->A / (sq->N * p->Te);
                quiet = 0;
                pc->stage = sq->stage; /* steps are in time order: the last started */
            }
        }
        if (quiet) a = level;
        if (quiet && level == 0.0) v = vsnap;
        if (exact && !(quiet && level == 0.0)) {
            exact_state(w, b, p->v0, p->Te, &a, &v);
            if (quiet) a = level;
        }
        if (level == 0.0) val = vsnap;
        if (b >= plan->k_end) {
            /* terminal piece: constant velocity for ever */
            double verr = djl_fabs(v - plan->v_target);
            if (!(verr <= 1e-9 * (p->v_max + djl_fabs(plan->v_target))) || a != 0.0)
                return set_error(err, DJL_E_INTERNAL, "", 0.0,
                                 "planner self-check: end velocity %.17g, expected %.17g "
                                 "(acceleration %.3g)", v, plan->v_target, a);
            jerk = 0.0;
            v = plan->v_target;
        }
        pc->k = b;
        pc->x = x;
        pc->v = v;
        pc->a = a;
        pc->j = jerk;
        pc->x_al = xal;
        pc->v_al = val;
        pc->a_al = level;
        pc->seg = seg;
        if (j + 1 < nb) {
            Lt = (double)(w->bnd[j + 1] - b) * p->Te;
            x += Lt * (v + Lt * (0.5 * a + Lt * jerk / 6.0));
            v += Lt * (a + 0.5 * Lt * jerk);
            a += Lt * jerk;
            xal += Lt * (val + 0.5 * Lt * level);
            val += Lt * level;
        }
    }
    /* self-check: the plan lands where it was asked to, to within tolx of the
     * distances asked for; the exact walk also of the positions it went through
     * (a pinned last segment's residual, up to half a sample of travel at its
     * end speed, taken up by an earlier segment can carry the axis far beyond
     * the distances: the rounding of x there is that of those positions;
     * issue 21: 6e11 m/s at the end of 0.05 m with Te = 0.05 s went through
     * -1.5e10 m and was an internal error) */
    for (j = 0; exact && j < plan->n_pieces; j++)
        if (djl_fabs(plan->piece[j].x) > reach) reach = djl_fabs(plan->piece[j].x);
    if (!(djl_fabs(plan->piece[plan->n_pieces - 1].x - plan->x_target) <= tolx * (scale + reach)))
        return set_error(err, DJL_E_INTERNAL, "", 0.0,
                         "planner self-check: final displacement %.17g m, expected %.17g m",
                         plan->piece[plan->n_pieces - 1].x, plan->x_target);
    return DJL_OK;
}

/* Phase 1 of plan_in_units: the plan and the work area cleared, each stage's
 * filter length in samples (N), the segments' distances and end velocities
 * in the real frame, the scale of the self-check. */
static void setup_motion(const djl_params *p, const djl_params *user, int kl, djl_plan *plan,
                         motion_work *w, int32_t N[4], double *scale)
{
    int n = p->n_segments == 0 ? 1 : p->n_segments, i;
    /* Cleared: what the phases read before writing it (the segments' problems and
     * solutions, the plan's header, its segments and its running totals); not the
     * large arrays of pieces and steps, written before they are read (a replan
     * plans a new move in a few microseconds, half of them went to clearing 46 kB). */
    memset(plan, 0, offsetof(djl_plan, seg) + (size_t)n * sizeof(plan->seg[0]));
    plan->n_pieces = 0;
    memset(&plan->k_end, 0, offsetof(djl_plan, step) - offsetof(djl_plan, k_end));
    memset(w->c, 0, (size_t)n * sizeof(w->c[0]));
    memset(w->s, 0, (size_t)n * sizeof(w->s[0]));
    memset(w->sigma, 0, sizeof w->sigma);
    memset(w->empty, 0, sizeof w->empty);
    memset(w->Dreal, 0, sizeof w->Dreal);
    memset(w->vS, 0, sizeof w->vS);
    memset(w->vE, 0, sizeof w->vE);
    w->n_steps = 0;
    w->lead = 0;
    w->user = user;
    w->kl = kl;
    plan->p = *p;

    for (i = 0; i < 4; i++) {
        int src = p->profile == DJL_PROFILE_DJL ? i : 0;
        N[i] = p->profile == DJL_PROFILE_AL ? 0 : (int32_t)djl_floor(p->T_F[src] / p->Te + 0.5);
        plan->N[i] = N[i];
    }

    plan->n_segments = n;
    w->lead = !(N[0] == N[1] && N[1] == N[2] && N[2] == N[3]);
    *scale = djl_fabs(p->v0) * p->Te;
    for (i = 0; i < n; i++) {
        w->Dreal[i] = p->n_segments == 0 ? p->distance : p->seg_distance[i];
        w->vE[i] = p->n_segments == 0 ? p->v_e : p->seg_v_end[i];
        w->vS[i] = i == 0 ? p->v0 : w->vE[i - 1];
        *scale += djl_fabs(w->Dreal[i]);
        plan->x_target += w->Dreal[i];
    }
    plan->v_target = w->vE[n - 1];
}

/* Phase 2: each segment sized and landed in turn (djl_segment.c). */
static djl_status size_segments(motion_work *w, const djl_params *p, const int32_t N[4], int n,
                                int precise, djl_error *err)
{
    double r = 0.0;
    int i;

    /* Forward pass: each segment is planned time-optimally and exactly when
     * it can; a segment pinned at a velocity it cannot leave (pure cruise,
     * single stage) is rounded to the nearest sample and passes the
     * residual on, so nothing accumulates. */
    for (i = 0; i < n; i++) {
        segment_problem *c = &w->c[i];
        segment_solution *s = &w->s[i];
        double Dr = w->Dreal[i] + r, resid = 0.0, dmin = 0.0;
        int sg = w->Dreal[i] > 0.0 ? 1 : w->Dreal[i] < 0.0 ? -1 : (Dr >= 0.0 ? 1 : -1);
        w->sigma[i] = sg;
        c->D = sg * Dr;
        c->vs = sg * w->vS[i];
        c->ve = sg * w->vE[i];
        c->vm = p->v_max;
        c->am = p->a_max;
        c->dm = p->d_max;
        c->Te = p->Te;
        c->rule = p->short_stage;
        c->last = i == n - 1;
        c->N1 = N[0];
        c->N2 = N[1];
        c->N3 = N[2];
        c->N4 = N[3];
        c->precise = precise;
        /* DJL: ramps with different filters must not overlap across a
         * boundary (their lags differ, the velocities would add up above
         * v_max); JL ramps may, the output then being a moving average of
         * the AL profile. */
        c->g = 0.0;
        if (i > 0 && w->lead) c->g = (double)tail_into(w, i);
        r = 0.0;
        if (Dr == 0.0 && w->vS[i] == 0.0 && w->vE[i] == 0.0) {
            w->empty[i] = 1;
            memset(s, 0, sizeof(*s));
            s->ok = 1;
            continue;
        }
        if (solve_time_optimal(c, s)) continue;
        if (!c->last) {
            if (solve_pinned_single_stage(c, s, &resid, &dmin)) {
                r = sg * resid;
                continue;
            }
            if (solve_monotone_or_dip(c, 2, s) || solve_monotone_or_dip(c, 3, s)) continue;
            if (solve_fit_peak_grid(c, s)) continue;
            return infeasible(err, w->user, i, c, dmin, w->kl);
        }
    }
    return DJL_OK;
}

/* Phase 3: the steps of the AL profile (real frame), the segments' entries
 * of the plan, the speeds and accelerations reached; returns the samples of
 * the segments end to end. */
static int64_t build_al_steps(motion_work *w, djl_plan *plan, int n)
{
    int64_t S;
    int i;

    w->n_steps = 0;
    S = 0;
    for (i = 0; i < n; i++) {
        const segment_solution *s = &w->s[i];
        djl_segment_plan *sp = &plan->seg[i];
        double sg = w->sigma[i];
        sp->start = S;
        sp->distance = sg * s->D;
        if (w->empty[i]) {
            sp->branch = 0;
            continue;
        }
        sp->n1 = s->hasA ? s->n1 : 0;
        sp->k = s->k;
        sp->m = s->hasD ? s->m : 0;
        sp->N[0] = s->N1;
        sp->N[1] = s->N2;
        sp->N[2] = s->N3;
        sp->N[3] = s->N4;
        sp->has_acc = s->hasA;
        sp->has_dec = s->hasD;
        sp->merged_acc = s->mergedA;
        sp->merged_dec = s->mergedD;
        sp->branch = s->branch;
        sp->frac = s->f;
        sp->lead = s->g;
        sp->v_peak = sg * s->vp;
        sp->a_level = s->hasA ? sg * s->al : 0.0;
        sp->d_level = s->hasD ? -sg * s->dl : 0.0;
        if (s->branch == 5) {
            /* single stage vs -> ve with one split sample (see solve_split_sample) */
            double lv = s->hasA ? s->al : -s->dl; /* signed level, positive frame */
            double fl = s->f * lv;
            int32_t Na = s->hasA ? s->N1 : s->N3, Nb = s->hasA ? s->N2 : s->N4;
            int64_t t0 = S + s->g + (s->after ? 0 : s->k);
            int64_t nn = s->hasA ? s->n1 : s->m;
            double vend = w->vE[i];
            int32_t sa = s->hasA ? 1 : 3, sb = s->hasA ? 2 : 4; /* the stages */
            if (s->split == 0) {
                add_step(w, t0, sg * lv, Na, sg * lv, 0, 0.0, sa);
                add_step(w, t0 + nn, -sg * (lv - fl), Nb, sg * fl, fl == 0.0, vend, sb);
                add_step(w, t0 + nn + 1, -sg * fl, Nb, 0.0, 1, vend, sb);
            } else {
                add_step(w, t0, sg * (lv - fl), Na, sg * (lv - fl), 0, 0.0, sa);
                add_step(w, t0 + 1, sg * fl, Na, sg * lv, 0, 0.0, sa);
                add_step(w, t0 + nn + 1, -sg * lv, Nb, 0.0, 1, vend, sb);
            }
        } else {
            if (s->hasA) {
                add_step(w, S + s->g, sg * s->al, s->N1, sg * s->al, 0, 0.0, 1);
                add_step(w, S + s->g + s->n1, -sg * s->al, s->N2, 0.0, 1, sg * s->vp, 2);
            }
            if (s->hasD) {
                int64_t t3 = S + s->g + (s->hasA ? s->n1 : 0) + s->k;
                add_step(w, t3, -sg * s->dl, s->N3, -sg * s->dl, 0, 0.0, 3);
                add_step(w, t3 + s->m, sg * s->dl, s->N4, 0.0, 1, w->vE[i], 4);
            }
        }
        if (djl_fabs(s->vp) > plan->v_reached) plan->v_reached = djl_fabs(s->vp);
        if (s->hasA) {
            if (s->al > plan->a_reached) plan->a_reached = s->al;
            if (-s->al > plan->d_reached) plan->d_reached = -s->al;
        }
        if (s->hasD) {
            if (s->dl > plan->d_reached) plan->d_reached = s->dl;
            if (-s->dl > plan->a_reached) plan->a_reached = -s->dl;
        }
        S += s->len;
    }
    return S;
}

/* Phase 4: the sample at which the motion ends (the last ramp over). */
static djl_status find_motion_end(const motion_work *w, djl_plan *plan, int n, int64_t S,
                                  const djl_params *user, djl_error *err)
{
    int L = n - 1;
    int64_t kend = plan->seg[L].start + (w->empty[L] ? 0 : w->s[L].bend);
    int64_t tail = ramp_tail_after(w, 0);
    if (tail > kend) kend = tail;
    if (S > kend) kend = S;
    if ((double)kend > (double)DJL_MAX_MOTION_SAMPLES)
        return set_error(err, DJL_E_INFEASIBLE, "Te", user->Te,
                         "the motion would last %g samples of Te = %g s: more than the %g "
                         "a plan may hold", (double)kend, user->Te,
                         (double)DJL_MAX_MOTION_SAMPLES);
    plan->k_end = kend;
    return DJL_OK;
}

/* Phase 5: the boundaries of the plan's pieces, sorted, in w->bnd. */
static djl_status piece_boundaries(motion_work *w, const djl_plan *plan, int n, int *nb_out,
                                   djl_error *err)
{
    int i, nb = 0;
    w->bnd[nb++] = 0;
    w->bnd[nb++] = plan->k_end;
    for (i = 0; i < w->n_steps; i++) {
        w->bnd[nb++] = w->step[i].tau;
        w->bnd[nb++] = w->step[i].tau + w->step[i].N;
    }
    for (i = 0; i < n; i++)
        if (plan->seg[i].start < plan->k_end) w->bnd[nb++] = plan->seg[i].start;
    sort_unique(w->bnd, &nb);
    *nb_out = nb;
    if (nb > DJL_MAX_PIECES)
        return set_error(err, DJL_E_INTERNAL, "", 0.0, "plan needs %d pieces (max %d)", nb,
                         DJL_MAX_PIECES);
    return DJL_OK;
}

/* Plan validated parameters p; precise: the retries of djl_plan_motion (see
 * there), p then possibly the user's parameters in units of 2^kl m and some
 * power of two of seconds (user: the user's, for messages).  The phases:
 * setup, the segments sized, the last one landed exactly, the AL steps, the
 * motion's end, the pieces, and the pieces walked with their self-check. */
static djl_status plan_in_units(const djl_params *p, const djl_params *user, int kl,
                                djl_plan *plan, djl_error *err, int precise)
{
    static const double tolx = 1e-11;
    motion_work w;
    djl_status st;
    int n, i, nb;
    int32_t N[4];
    double scale;
    int64_t S;

    if (err) memset(err, 0, sizeof(*err));
    setup_motion(p, user, kl, plan, &w, N, &scale);
    n = plan->n_segments;
    for (i = 0; i < n; i++)
        if ((st = check_duration(user, i, err)) != DJL_OK) return st;

    if ((st = size_segments(&w, p, N, n, precise, err)) != DJL_OK) return st;

    /* The last segment must land exactly. */
    if (!w.empty[n - 1] && !w.s[n - 1].ok) {
        st = land_last_segment(&w, n, err);
        if (st != DJL_OK) return st;
    }

    S = build_al_steps(&w, plan, n);
    if ((st = find_motion_end(&w, plan, n, S, user, err)) != DJL_OK) return st;
    if ((st = piece_boundaries(&w, plan, n, &nb, err)) != DJL_OK) return st;

    /* Walk the pieces; if the self-check fails, once more with the state
     * taken from the steps at every boundary.  That walk adds no error of its
     * own, but the stage levels were found from times counted from the
     * segment's start: with jerk times of millions of samples their rounding
     * alone reaches 1e-11 of the distance, hence the wider tolerance (still a
     * hundredth of the 1e-9 promised). */
    st = walk_pieces(&w, plan, p, n, nb, tolx, scale, 0, err);
    if (st != DJL_OK) {
        st = walk_pieces(&w, plan, p, n, nb, 10.0 * tolx, scale, 1, err);
        if (st == DJL_OK && err) memset(err, 0, sizeof(*err));
    }
    /* the steps, for a replan (djl_replan.c) */
    plan->n_steps = w.n_steps;
    for (i = 0; i < w.n_steps; i++) {
        plan->step[i].tau = w.step[i].tau;
        plan->step[i].A = w.step[i].A;
        plan->step[i].N = w.step[i].N;
        plan->step[i].stage = w.step[i].stage;
    }
    return st;
}

/* Every value of the plan finite, and no quantity (x, v, a, j, x_al, v_al,
 * a_al) whose largest magnitude over the pieces is a subnormal double: its
 * values would have lost their digits (smaller values of a quantity that
 * also has normal ones, rounding residues, are harmless). */
static int plan_big(const djl_plan *pl, double big[7])
{
    int i, q;
    for (q = 0; q < 7; q++) big[q] = 0.0;
    for (i = 0; i < pl->n_pieces; i++) {
        const djl_piece *pc = &pl->piece[i];
        double val[7];
        val[0] = pc->x;
        val[1] = pc->v;
        val[2] = pc->a;
        val[3] = pc->j;
        val[4] = pc->x_al;
        val[5] = pc->v_al;
        val[6] = pc->a_al;
        for (q = 0; q < 7; q++) {
            if (!djl_isfinite(val[q])) return 0;
            big[q] = dmax2(big[q], djl_fabs(val[q]));
        }
    }
    return 1;
}

/* The largest magnitude of each quantity over the pieces (plan_big: 0 if one is not
 * finite), then whether the plan is clean: no quantity wholly subnormal, and the
 * acceleration within the larger limit up to rounding (issue 21, third session: with
 * a_max = d_max = 2.2e-308 m/s^2 and Te = 1e-9 s the jerk of a sample, 2.8e-316, is
 * subnormal and keeps 8 digits: a level came out 8e-8 above a_max; in scaled units it
 * does not). */
static int plan_clean(const djl_plan *pl)
{
    double big[7];
    int q;
    if (!plan_big(pl, big)) return 0;
    for (q = 0; q < 7; q++)
        if (big[q] != 0.0 && big[q] < DJL_MIN_MAGNITUDE) return 0;
    return big[2] <= dmax2(pl->p.a_max, pl->p.d_max) * (1.0 + 1e-12);
}

/* Units in which the problem is ordinary: lengths in 2^-kl m (the total
 * distance about 1), times in 2^-kt s (Te about 1 ms).  Returns 1 if the
 * user's units are far from them (a length, speed, acceleration or jerk unit
 * beyond 2^600 ~ 1e180 either way): only then can values of the plan leave
 * the range of normal doubles, floating point being otherwise exactly the
 * same in units that differ by powers of two. */
static int units(const djl_params *p, int *kl, int *kt)
{
    double sum = 0.0;
    int i, n = p->n_segments == 0 ? 1 : p->n_segments;
    for (i = 0; i < n; i++) sum += djl_fabs(p->n_segments == 0 ? p->distance : p->seg_distance[i]);
    *kt = -djl_ilogb(p->Te) - 10;
    *kl = sum > 0.0 ? -djl_ilogb(sum) : -(djl_ilogb(p->v_max) + djl_ilogb(p->Te));
    for (i = 0; i < 4; i++) /* length, speed, acceleration, jerk */
        if (*kl - i * *kt > 600 || *kl - i * *kt < -600) return 1;
    return 0;
}

/* The problem planned in the units of units() (powers of two: every
 * conversion exact), then converted back. */
static djl_status plan_scaled(const djl_params *p, int kl, int kt, djl_plan *plan, djl_error *err)
{
    djl_params q = *p;
    djl_status st;
    double big = 0.0, before[7], after[7];
    djl_error eq;
    int i, n = p->n_segments == 0 ? 1 : p->n_segments, Nmin = 0, lost = 0;
    int ev = kl - kt, ea = kl - 2 * kt, ej = kl - 3 * kt; /* m/s, m/s^2, m/s^3 */
    q.Te = djl_ldexp(p->Te, kt);
    for (i = 0; i < 4; i++) q.T_F[i] = djl_ldexp(p->T_F[i], kt);
    q.x0 = 0.0;
    q.distance = djl_ldexp(p->distance, kl);
    q.v0 = djl_ldexp(p->v0, ev);
    q.v_e = djl_ldexp(p->v_e, ev);
    q.v_max = djl_ldexp(p->v_max, ev);
    q.a_max = djl_ldexp(p->a_max, ea);
    q.d_max = djl_ldexp(p->d_max, ea);
    for (i = 0; i < DJL_MAX_SEGMENTS; i++) {
        q.seg_distance[i] = djl_ldexp(p->seg_distance[i], kl);
        q.seg_v_end[i] = djl_ldexp(p->seg_v_end[i], ev);
    }
    /* A limit beyond a double in these units is one the motion never comes near (a
     * distance of about 1 over samples of about 1 ms): planned with 2^1000 instead, a
     * stricter limit, so that the plan is made (and, if its values leave the normal
     * doubles, refused as too small below).  Issue 21: Te = 8e298 s with a_max = 10
     * m/s^2 overflowed here and the motion was reported as an internal error. */
    if (!djl_isfinite(q.v_max)) q.v_max = djl_ldexp(1.0, 1000);
    if (!djl_isfinite(q.a_max)) q.a_max = djl_ldexp(1.0, 1000);
    if (!djl_isfinite(q.d_max)) q.d_max = djl_ldexp(1.0, 1000);
    /* the parameters must survive the change of units (they may span more
     * than a double's range between them): if not, no double plan holds them all
     * (issue 21: Te = 5e303 s with jerk times of 0.08 s was an internal error) */
    if (djl_validate(&q, &eq) != DJL_OK)
        return set_error(err, DJL_E_INFEASIBLE, "Te", p->Te,
                         "Te = %g s: the time scales and lengths of this motion span more than "
                         "a double holds (%s leaves the normal doubles in units where Te and "
                         "the distance are ordinary): it cannot be planned exactly", p->Te,
                         eq.param);
    st = plan_in_units(&q, p, kl, plan, err, 1);
    if (st != DJL_OK) return st;
    (void)plan_big(plan, before);
    /* back to the user's units */
    plan->p = *p;
    plan->x_target = 0.0;
    for (i = 0; i < n; i++) plan->x_target += p->n_segments == 0 ? p->distance : p->seg_distance[i];
    plan->v_target = p->n_segments == 0 ? p->v_e : p->seg_v_end[n - 1];
    plan->v_reached = djl_ldexp(plan->v_reached, -ev);
    plan->a_reached = djl_ldexp(plan->a_reached, -ea);
    plan->d_reached = djl_ldexp(plan->d_reached, -ea);
    for (i = 0; i < plan->n_segments; i++) {
        djl_segment_plan *sp = &plan->seg[i];
        sp->v_peak = djl_ldexp(sp->v_peak, -ev);
        sp->a_level = djl_ldexp(sp->a_level, -ea);
        sp->d_level = djl_ldexp(sp->d_level, -ea);
        sp->distance = djl_ldexp(sp->distance, -kl);
    }
    for (i = 0; i < plan->n_pieces; i++) {
        djl_piece *pc = &plan->piece[i];
        pc->x = djl_ldexp(pc->x, -kl);
        pc->v = djl_ldexp(pc->v, -ev);
        pc->a = djl_ldexp(pc->a, -ea);
        pc->j = djl_ldexp(pc->j, -ej);
        pc->x_al = djl_ldexp(pc->x_al, -kl);
        pc->v_al = djl_ldexp(pc->v_al, -ev);
        pc->a_al = djl_ldexp(pc->a_al, -ea);
        big = dmax2(big, djl_fabs(pc->j));
    }
    for (i = 0; i < plan->n_steps; i++) plan->step[i].A = djl_ldexp(plan->step[i].A, -ea);
    plan->piece[plan->n_pieces - 1].v = plan->v_target;
    /* a quantity the plan has (not 0 in these units) that does not survive the way
     * back (wholly below the normal doubles, or 0: issue 21, an acceleration of
     * 1e-598 m/s^2 became 0 and the plan passed) */
    (void)plan_big(plan, after);
    for (i = 0; i < 7; i++) lost |= before[i] != 0.0 && after[i] < DJL_MIN_MAGNITUDE;
    if (djl_isfinite(big) && (lost || !plan_clean(plan))) {
        /* values of the motion itself below the normal doubles: it is too
         * small to be planned exactly at these time scales */
        char name[40];
        double D = p->distance, tiny = 0.0;
        int at = 0;
        if (p->n_segments == 0)
            snprintf(name, sizeof name, "distance");
        else {
            for (i = 0; i < n; i++)
                if (p->seg_distance[i] != 0.0 &&
                    (tiny == 0.0 || djl_fabs(p->seg_distance[i]) < tiny)) {
                    tiny = djl_fabs(p->seg_distance[i]);
                    at = i;
                }
            D = p->seg_distance[at];
            snprintf(name, sizeof name, "seg_distance[%d]", at + 1);
        }
        return set_error(err, DJL_E_INFEASIBLE, name, D,
                         "%s = %g m is too small for the time scales of this motion (Te = %g s, "
                         "the jerk times, v_max = %g m/s, a_max = %g m/s2, d_max = %g m/s2): "
                         "values of its plan (the jerk first) would be below the smallest normal "
                         "double, %g, and lose their digits", name, D, p->Te, p->v_max, p->a_max,
                         p->d_max, DJL_MIN_MAGNITUDE);
    }
    if (!djl_isfinite(big)) {
        /* the jerk (a level over a jerk time) beyond a double */
        char name[40];
        for (i = 0; i < 4; i++)
            if (plan->N[i] > 0 && (Nmin == 0 || plan->N[i] < plan->N[Nmin - 1])) Nmin = i + 1;
        if (Nmin == 0) Nmin = 1;
        snprintf(name, sizeof name, "T_F%d", Nmin);
        return set_error(err, DJL_E_INFEASIBLE, name, p->T_F[Nmin - 1],
                         "%s = %g s: with the accelerations of this motion (a_max = %g m/s2, "
                         "d_max = %g m/s2) the jerk (an acceleration over a jerk time) exceeds "
                         "the range of a double", name, p->T_F[Nmin - 1], p->a_max, p->d_max);
    }
    return DJL_OK;
}

djl_status djl_plan_motion(const djl_params *p, djl_plan *plan, djl_error *err)
{
    djl_status st, st2;
    djl_error e2;
    int precise = 0, kl, kt;
    if (err) memset(err, 0, sizeof(*err));
    if ((st = djl_validate(p, err)) != DJL_OK) return st;
    if (p->profile == DJL_PROFILE_TABLE)
        return set_error(err, DJL_E_PARAM, "profile", (double)p->profile,
                         "profile = 4 (table) is planned from its table (djl_plan_table), not "
                         "from its parameters alone");
    st = plan_in_units(p, p, 0, plan, err, 0);
    if (st == DJL_OK && plan_clean(plan)) return DJL_OK;
    /* Times are counted in samples from a segment's start; with jerk times
     * of millions of samples (or stages of billions) the distance formula
     * then loses digits to the difference of two long times.  A plan that
     * fails its checks is made again with the formulas taken relative to the
     * stage they describe (only the plans the first way fails get the
     * second: the others stay as they are, bit for bit). */
    if (st == DJL_E_INTERNAL) {
        precise = 1;
        st = plan_in_units(p, p, 0, plan, err, 1);
        if (st == DJL_OK && plan_clean(plan)) return DJL_OK;
    }
    /* Magnitudes far from 1 (1e-300 m, 1e300 m/s^2, Te of 1e-12 s...) lose
     * digits to subnormal, or overflowing, intermediate values: the same
     * problem once more, in units where it is ordinary.  Kept if it plans; a
     * refusal is the first one's (in the user's units, as computed). */
    if (!units(p, &kl, &kt)) return st;
    st2 = plan_scaled(p, kl, kt, plan, &e2);
    if (st2 == DJL_OK || (st2 == DJL_E_INFEASIBLE && st != DJL_E_INFEASIBLE)) {
        if (err) *err = e2;
        return st2;
    }
    if (st == DJL_OK) return plan_in_units(p, p, 0, plan, err, precise); /* the plan made above */
    return st; /* and its message */
}
