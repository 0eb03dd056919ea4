/*
 * djl_core.c -- planner and evaluator of the AL / JL / DJL generator.
 *
 * Vocabulary (docs/generator.md):
 *  - a segment is planned in its "positive frame" (distance >= 0); its AL
 *    profile has an acceleration phase A (steps +a at 0 and -a at n1), a
 *    cruise of k samples and a deceleration phase D (steps -d at n1+k and +d
 *    at n1+k+m).  Step i is filtered by a moving average of N_i samples.
 *  - A filtered step of amplitude A at tau with filter N contributes, once its
 *    ramp is over, A*(t - tau - N/2) to the velocity and
 *    A*((t-tau)^2/2 - N (t-tau)/2 + N^2/6) to the position (t in samples,
 *    times Te).  A phase (pair of steps +A, -A) therefore acts, once settled,
 *    like a velocity jump  A*eff  at the "centroid" time  cnum/eff  with
 *        eff  = n + (Nb - Na)/2,
 *        cnum = n^2/2 + Nb n/2 - (Na^2 - Nb^2)/6,
 *    (Na, Nb the filters of the first and second step, n their distance).
 *    This is eq. (14)-(15) of the paper for the velocity; the position term
 *    is what makes DJL land exactly when the four jerk times differ.
 *  - The distance of a segment is the integral of that staircase of
 *    velocities over the segment, so it is linear in the peak velocity v_p:
 *        D/Te = vs*c_a + v_p*(c_d - c_a) + ve*(b_end - c_d).
 *    Given whole-sample stage lengths, v_p follows exactly from D; the stage
 *    accelerations follow from v_p (the Appendix's "recompute v_max, a_max,
 *    d_max", generalised to filtered steps).
 */
#include "djl_core.h"
#include "djl_math.h" /* floor, sqrt, ... without libm (see there) */

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* Relative slack accepted on the limits, for rounding only. */
#define LIMIT_TOL 1e-13

/* ------------------------------------------------------------------------ */
/* small helpers                                                            */

static double dmax2(double a, double b) { return a > b ? a : b; }
static double dmin2(double a, double b) { return a < b ? a : b; }
static int64_t imax2(int64_t a, int64_t b) { return a > b ? a : b; }

static djl_status set_error(djl_error *e, djl_status st, const char *param, double value,
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
    if (profile == DJL_PROFILE_DJL) return 1;
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

djl_status djl_validate(const djl_params *p, djl_error *err)
{
    djl_status st;
    int i, n;
    char name[40];
    double reach;

    if (p->profile < DJL_PROFILE_AL || p->profile > DJL_PROFILE_DJL)
        return set_error(err, DJL_E_PARAM, "profile", (double)p->profile,
                         "profile = %d: must be 1 (AL), 2 (JL) or 3 (DJL)", (int)p->profile);
    if (p->short_stage != DJL_SHORT_STRETCH && p->short_stage != DJL_SHORT_OVERLAP)
        return set_error(err, DJL_E_PARAM, "short_stage", (double)p->short_stage,
                         "short_stage = %d: must be 1 (stretch the stage to its jerk times) "
                         "or 2 (let the ramps overlap, as in the paper)", (int)p->short_stage);
    if ((st = check_positive(err, "Te", p->Te, "s")) != DJL_OK) return st;
    if ((st = check_positive(err, "v_max", p->v_max, "m/s")) != DJL_OK) return st;
    if ((st = check_positive(err, "a_max", p->a_max, "m/s2")) != DJL_OK) return st;
    if ((st = check_positive(err, "d_max", p->d_max, "m/s2")) != DJL_OK) return st;
    for (i = 0; i < 4; i++) {
        double T = p->T_F[i];
        snprintf(name, sizeof name, "T_F%d", i + 1);
        if ((st = check_positive(err, name, T, "s")) != DJL_OK) return st;
        if (stage_used(p->profile, i)) {
            double N = djl_floor(T / p->Te + 0.5);
            if (N < 1.0)
                return set_error(err, DJL_E_PARAM, name, T,
                                 "%s = %g s rounds to 0 samples at Te = %g s: a jerk time must "
                                 "be at least half a sampling period", name, T, p->Te);
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

    n = p->n_segments == 0 ? 1 : p->n_segments;
    reach = djl_fabs(p->x0);
    for (i = 0; i < n; i++) {
        double D = p->n_segments == 0 ? p->distance : p->seg_distance[i];
        double ve = p->n_segments == 0 ? p->v_e : p->seg_v_end[i];
        double vs = i == 0 ? p->v0 : p->seg_v_end[i - 1];
        char dname[40], vname[40], sname[40];
        if (p->n_segments == 0) {
            snprintf(dname, sizeof dname, "distance");
            snprintf(vname, sizeof vname, "v_e");
        } else {
            snprintf(dname, sizeof dname, "seg_distance[%d]", i + 1);
            snprintf(vname, sizeof vname, "seg_v_end[%d]", i + 1);
        }
        if (i == 0)
            snprintf(sname, sizeof sname, "v0");
        else
            snprintf(sname, sizeof sname, "seg_v_end[%d]", i);
        if (!djl_isfinite(D))
            return set_error(err, DJL_E_PARAM, dname, D, "%s = %g m: must be finite", dname, D);
        if (D != 0.0 && djl_fabs(D) < DJL_MIN_MAGNITUDE)
            return set_error(err, DJL_E_PARAM, dname, D,
                             "%s = %g m: a non-zero distance must be at least %g m in magnitude "
                             "(a subnormal double has too few significant digits to be planned "
                             "exactly)", dname, D, DJL_MIN_MAGNITUDE);
        reach += djl_fabs(D);
        if (reach > DJL_MAX_POSITION)
            return set_error(err, DJL_E_PARAM, dname, D,
                             "%s = %g m: |x0| + the sum of |distance| up to it is %g m, more than "
                             "the %g m a motion may span", dname, D, reach, DJL_MAX_POSITION);
        if (!djl_isfinite(ve) || djl_fabs(ve) > p->v_max)
            return set_error(err, DJL_E_PARAM, vname, ve,
                             "%s = %g m/s: must be finite and not above v_max = %g m/s in "
                             "magnitude", vname, ve, p->v_max);
        if (D > 0.0 && ve < 0.0)
            return set_error(err, DJL_E_PARAM, vname, ve,
                             "%s = %g m/s points backwards while %s = %g m moves forwards: the "
                             "velocity must be 0 where the direction reverses", vname, ve, dname, D);
        if (D < 0.0 && ve > 0.0)
            return set_error(err, DJL_E_PARAM, vname, ve,
                             "%s = %g m/s points forwards while %s = %g m moves backwards: the "
                             "velocity must be 0 where the direction reverses", vname, ve, dname, D);
        if (D > 0.0 && vs < 0.0)
            return set_error(err, DJL_E_PARAM, sname, vs,
                             "%s = %g m/s points backwards while %s = %g m moves forwards: the "
                             "velocity must be 0 where the direction reverses", sname, vs, dname, D);
        if (D < 0.0 && vs > 0.0)
            return set_error(err, DJL_E_PARAM, sname, vs,
                             "%s = %g m/s points forwards while %s = %g m moves backwards: the "
                             "velocity must be 0 where the direction reverses", sname, vs, dname, D);
        if (D == 0.0 && (vs != 0.0 || ve != 0.0))
            return set_error(err, DJL_E_PARAM, dname, D,
                             "%s = 0 m with a non-zero velocity at its start (%g m/s) or end "
                             "(%g m/s): a null segment must start and end at rest", dname, vs, ve);
        if (djl_fabs(D) / (p->v_max * p->Te) > 1e14)
            return set_error(err, DJL_E_PARAM, dname, D,
                             "%s = %g m would take more than 1e14 samples at v_max = %g m/s and "
                             "Te = %g s", dname, D, p->v_max, p->Te);
    }
    return DJL_OK;
}

/* ------------------------------------------------------------------------ */
/* segment planning (positive frame, times in samples)                      */

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
    int32_t N1, N2, N3, N4;
} sctx;

typedef struct {
    int ok;
    int hasA, hasD;
    int64_t n1, k, m;
    int32_t N1, N2, N3, N4;
    int mergedA, mergedD;
    double vp, al, dl;  /* peak velocity; accel of phase A (+ speeds up); decel of phase D (+ slows down) */
    double D;           /* distance covered (m) */
    int64_t g;          /* leading cruise, samples */
    double f;           /* branch 5: fraction of the split sample */
    int split, after;   /* branch 5: split at the stage's start (1) or end (0); cruise after (1) or before (0) */
    int64_t len;        /* samples of the segment on the AL time line */
    int64_t bend;       /* samples until the segment's staircase ends (len, or the motion end) */
    int branch;
} ssol;

static double cnum(double n, double Na, double Nb)
{
    return 0.5 * n * n + 0.5 * Nb * n - (Na * Na - Nb * Nb) / 6.0;
}

static double effl(double n, double Na, double Nb) { return n + 0.5 * (Nb - Na); }

static int64_t nmin_a(const sctx *c)
{
    if (c->rule == DJL_SHORT_STRETCH) return imax2(c->N1, 1);
    return imax2((int64_t)c->N1 - c->N2, 1);
}

static int64_t nmin_d(const sctx *c)
{
    if (c->rule == DJL_SHORT_STRETCH) return imax2(c->N3, 1);
    return imax2((int64_t)c->N3 - c->N4, 1);
}

/* Cruise between the two phases: ramps 2 and 3 must not overlap, except in
 * the fallback branches when they share one filter: they then merge into a
 * single ramp of jerk (change of acceleration)/T_F.  (Two ramps of different
 * lengths starting together would let the faster one push the acceleration
 * past the limit before the slower one has taken its share off.) */
static int64_t kmin(const sctx *c)
{
    if (c->merge23 && c->N2 == c->N3) return 0;
    return c->N2;
}

static double La(const sctx *c) { return (double)nmin_a(c) + 0.5 * (c->N2 - c->N1); }
static double Ld(const sctx *c) { return (double)nmin_d(c) + 0.5 * (c->N4 - c->N3); }

/* ad_coeffs of the precise retry: the same quantities without differences of
 * long absolute times (the end of the staircase and the centroids taken from
 * the start of the deceleration, t3). */
static void ad_coeffs_rel(const sctx *c, double n1, double k, double m, double *K0, double *K1,
                          double *bend)
{
    double g = c->g;
    double cna = cnum(n1, c->N1, c->N2) / effl(n1, c->N1, c->N2);
    double cnd = cnum(m, c->N3, c->N4) / effl(m, c->N3, c->N4);
    double rel = m; /* be - t3 */
    if (c->last) {
        rel = dmax2(rel, m + c->N4);
        rel = dmax2(rel, c->N3);
        rel = dmax2(rel, c->N2 - k);
        rel = dmax2(rel, c->N1 - n1 - k);
        rel = dmax2(rel, c->tail_in - (g + n1 + k));
    }
    *K0 = c->vs * (g + cna) + c->ve * (rel - cnd);
    *K1 = (n1 + k) + (cnd - cna);
    *bend = (g + n1 + k) + rel;
}

/* AD structure: D/Te = K0 + vp*K1 for given (possibly fractional) stage lengths. */
static void ad_coeffs(const sctx *c, double n1, double k, double m, double *K0, double *K1,
                      double *bend)
{
    double g = c->g;
    double ea = effl(n1, c->N1, c->N2), ed = effl(m, c->N3, c->N4);
    double ca = g + cnum(n1, c->N1, c->N2) / ea;
    double t3 = g + n1 + k;
    double cd = t3 + cnum(m, c->N3, c->N4) / ed;
    double send = t3 + m;
    double be = send;
    if (c->precise) {
        ad_coeffs_rel(c, n1, k, m, K0, K1, bend);
        return;
    }
    if (c->last) {
        be = dmax2(be, send + c->N4);
        be = dmax2(be, t3 + c->N3);
        be = dmax2(be, g + n1 + c->N2);
        be = dmax2(be, g + c->N1);
        be = dmax2(be, c->tail_in);
    }
    *K0 = c->vs * ca + c->ve * (be - cd);
    *K1 = cd - ca;
    *bend = be;
}

/* Stage length (eff, samples) needed for the velocity change dv at the limits. */
static double need_eff(const sctx *c, double dv, double Lmin)
{
    double t = dv >= 0.0 ? dv / (c->am * c->Te) : -dv / (c->dm * c->Te);
    return dmax2(t, Lmin);
}

/* Continuous relaxation: distance of the AD structure with peak vp and kx
 * extra cruise samples, stages as short as the limits allow. */
static double D_cont(const sctx *c, double vp, double kx)
{
    double ea = need_eff(c, vp - c->vs, La(c));
    double ed = need_eff(c, c->ve - vp, Ld(c));
    double n1 = ea - 0.5 * (c->N2 - c->N1), m = ed - 0.5 * (c->N4 - c->N3);
    double K0, K1, be;
    ad_coeffs(c, n1, (double)kmin(c) + kx, m, &K0, &K1, &be);
    return c->Te * (K0 + vp * K1);
}

static int64_t ceil_len(double x)
{
    if (!(x < (double)DJL_MAX_MOTION_SAMPLES)) return DJL_MAX_MOTION_SAMPLES;
    if (x < 0.0) return 0;
    return (int64_t)djl_ceil(x);
}

/* Whole-sample stage lengths for the peak vp, each f times as long (in
 * effective samples) as the limits need. */
static void stage_lengths(const sctx *c, double vp, double f, int64_t *n1, int64_t *m)
{
    double ea = need_eff(c, vp - c->vs, La(c)), ed = need_eff(c, c->ve - vp, Ld(c));
    *n1 = imax2(ceil_len(f * ea - 0.5 * (c->N2 - c->N1)), nmin_a(c));
    *m = imax2(ceil_len(f * ed - 0.5 * (c->N4 - c->N3)), nmin_d(c));
}

/* Exact solution of the AD structure for whole-sample lengths. */
static int try_ad(const sctx *c, int64_t n1, int64_t k, int64_t m, int signfree, ssol *s)
{
    double K0, K1, be, vp, ea, ed, al, dl;
    if (n1 < nmin_a(c) || m < nmin_d(c) || k < kmin(c)) return 0;
    if ((double)(n1 + k + m) > (double)DJL_MAX_MOTION_SAMPLES) return 0;
    ad_coeffs(c, (double)n1, (double)k, (double)m, &K0, &K1, &be);
    if (!(K1 > 0.0)) return 0;
    vp = (c->D / c->Te - K0) / K1;
    ea = effl((double)n1, c->N1, c->N2);
    ed = effl((double)m, c->N3, c->N4);
    al = (vp - c->vs) / (ea * c->Te);
    dl = (vp - c->ve) / (ed * c->Te);
    if (!djl_isfinite(vp) || vp < 0.0 || vp > c->vm * (1.0 + LIMIT_TOL)) return 0;
    if (!signfree && (al < 0.0 || dl < 0.0)) return 0;
    if (al > c->am * (1.0 + LIMIT_TOL) || -al > c->dm * (1.0 + LIMIT_TOL)) return 0;
    if (dl > c->dm * (1.0 + LIMIT_TOL) || -dl > c->am * (1.0 + LIMIT_TOL)) return 0;
    memset(s, 0, sizeof(*s));
    s->ok = 1;
    s->hasA = s->hasD = 1;
    s->n1 = n1;
    s->k = k;
    s->m = m;
    s->N1 = c->N1;
    s->N2 = c->N2;
    s->N3 = c->N3;
    s->N4 = c->N4;
    s->vp = vp;
    s->al = al;
    s->dl = dl;
    s->D = c->D;
    s->g = (int64_t)c->g;
    s->len = s->g + n1 + k + m;
    s->bend = (int64_t)be;
    return 1;
}

static int better(const ssol *a, const ssol *b)
{
    if (!b->ok) return 1;
    if (a->bend != b->bend) return a->bend < b->bend;
    return a->vp > b->vp;
}

/* Round the continuous solution (vp, kx) to whole samples and keep the best
 * exact neighbour.  Rounding a length up usually lowers v_p, but not always:
 * with overlapping ramps of different lengths (short_stage = 2) a longer
 * stage can move its centroid earlier and push v_p above v_max, so if no
 * neighbour one sample shorter lands, those one sample longer are tried. */
static int round_ad(const sctx *c, double vp, double kx, int signfree, ssol *best)
{
    int64_t n1c, mc, kc = imax2(ceil_len((double)kmin(c) + kx), kmin(c));
    int i, j, l, up;
    stage_lengths(c, vp, 1.0, &n1c, &mc);
    best->ok = 0;
    for (up = 0; up <= 1 && !best->ok; up++) /* one sample longer only if needed */
        for (i = -1; i <= up; i++)
            for (j = -1; j <= up; j++)
                for (l = -1; l <= up; l++) {
                    ssol s;
                    if (try_ad(c, n1c + i, kc + j, mc + l, signfree, &s) && better(&s, best))
                        *best = s;
                }
    return best->ok;
}

/* Find vp in [lo, hi] with D_cont(vp, 0) = D (D_cont increasing); above
 * D_cont(hi, 0), vp = hi and the cruise grows. */
static int cont_solve(const sctx *c, double lo, double hi, double *vp, double *kx)
{
    double Dhi = D_cont(c, hi, 0.0), Dlo;
    int it;
    if (c->D >= Dhi) {
        if (!(hi > 0.0)) return 0;
        *vp = hi;
        *kx = (c->D - Dhi) / (hi * c->Te);
        return djl_isfinite(*kx);
    }
    Dlo = D_cont(c, lo, 0.0);
    if (!(c->D >= Dlo)) return 0;
    for (it = 0; it < 200 && hi - lo > 1e-15 * dmax2(hi, 1e-300); it++) {
        double mid = 0.5 * (lo + hi);
        if (D_cont(c, mid, 0.0) <= c->D)
            lo = mid;
        else
            hi = mid;
    }
    *vp = lo;
    *kx = 0.0;
    return 1;
}

/* Branch 1: the time-optimal profile, v_p above both end velocities. */
static int solve_b1(const sctx *c0, ssol *out)
{
    sctx c = *c0;
    double vlo = dmax2(c.vs, c.ve), vp, kx;
    int mergedA = 0, mergedD = 0;
    if (!(vlo < c.vm)) return 0;
    if (!cont_solve(&c, vlo, c.vm, &vp, &kx)) return 0;
    if (c.rule == DJL_SHORT_OVERLAP) {
        /* The paper's fallback (end of §2.3): a phase too short for its two
         * jerk times (T_1 or T_3 would be negative; we also merge when the
         * acceleration would change sign) uses one jerk time. */
        double Ta = (vp - c.vs) / (c.am * c.Te), Td = (vp - c.ve) / (c.dm * c.Te);
        if (c.N1 != c.N2 && Ta < 0.5 * djl_fabs((double)c.N2 - c.N1)) {
            c.N2 = c.N1;
            mergedA = 1;
        }
        if (c.N3 != c.N4 && Td < 0.5 * djl_fabs((double)c.N4 - c.N3)) {
            c.N4 = c.N3;
            mergedD = 1;
        }
        if ((mergedA || mergedD) && !cont_solve(&c, vlo, c.vm, &vp, &kx)) return 0;
    }
    if (!round_ad(&c, vp, kx, 0, out) && !round_ad(&c, vp, kx, 1, out)) return 0;
    out->mergedA = mergedA;
    out->mergedD = mergedD;
    out->branch = 1;
    return 1;
}

/* Whole-sample lengths for a peak velocity near vt: stages sized for vt,
 * the cruise rounded up for the distance; rounding moves the peak, so the
 * stages are resized for it (the total kept) until the limits hold. */
static int fit_ad(const sctx *c, double vt, ssol *out)
{
    int64_t n1, m, k;
    double K0, K1, be, kr;
    int it;
    if (!(vt > 0.0)) return 0;
    stage_lengths(c, vt, 1.0, &n1, &m);
    ad_coeffs(c, (double)n1, (double)kmin(c), (double)m, &K0, &K1, &be);
    kr = (double)kmin(c) + (c->D / c->Te - K0 - vt * K1) / vt;
    if (!(kr > (double)kmin(c) - 1.0) || !(kr < (double)DJL_MAX_MOTION_SAMPLES)) return 0;
    k = imax2(ceil_len(kr), kmin(c));
    for (it = 0; it < 8; it++) {
        int64_t n1v, mv;
        double v;
        if (try_ad(c, n1, k, m, 1, out)) return 1;
        ad_coeffs(c, (double)n1, (double)k, (double)m, &K0, &K1, &be);
        v = (c->D / c->Te - K0) / K1;
        if (!djl_isfinite(v)) return 0;
        stage_lengths(c, v, 1.0, &n1v, &mv);
        if (n1v <= n1 && mv <= m) return 0;
        k -= imax2(n1v - n1, 0) + imax2(mv - m, 0);
        if (k < kmin(c)) return 0;
        n1 = imax2(n1, n1v);
        m = imax2(m, mv);
    }
    return 0;
}

/* Branches 2 (v_p between the end velocities: two stages in the same
 * direction) and 3 (v_p below both: a dip), used to land exactly when the
 * time-optimal shape cannot. */
static int solve_b23_once(const sctx *c, int branch, ssol *out)
{
    double lo, hi, vp, kx;
    int p;
    if (branch == 2) {
        lo = dmin2(c->vs, c->ve);
        hi = dmax2(c->vs, c->ve);
        if (!(lo < hi)) return 0;
    } else {
        lo = 0.0;
        hi = dmin2(c->vs, c->ve);
        if (!(hi > 0.0)) return 0;
    }
    if (!cont_solve(c, lo, hi, &vp, &kx)) return 0;
    if (round_ad(c, vp, kx, 1, out)) {
        out->branch = branch;
        return 1;
    }
    /* Lengthen both stages until their accelerations fit the limits. */
    for (p = 1; p <= 40; p++) {
        double K0, K1, be, kr;
        int64_t n1, m, k;
        int j;
        stage_lengths(c, vp, djl_ldexp(1.0, p), &n1, &m);
        ad_coeffs(c, (double)n1, (double)kmin(c), (double)m, &K0, &K1, &be);
        if (!(vp > 0.0)) break;
        kr = (double)kmin(c) + (c->D / c->Te - K0 - vp * K1) / vp;
        if (kr < (double)kmin(c) - 1.0) break; /* longer stages only make it worse */
        k = imax2(ceil_len(kr), kmin(c));
        out->ok = 0;
        for (j = 0; j < 2; j++) {
            ssol s;
            if (try_ad(c, n1, k - j, m, 1, &s) && better(&s, out)) *out = s;
        }
        if (out->ok) {
            out->branch = branch;
            return 1;
        }
    }
    /* Or size the stages for a peak velocity vt of a grid spanning the
     * branch (a deep dip needs both stages long, not in the ratio of the
     * shallow one), the cruise for the distance at vt. */
    out->ok = 0;
    for (p = 0; p <= 60; p++) {
        double vt = hi - (hi - lo) * djl_exp2(-p / 3.0); /* lo .. hi - 2^-20 (hi - lo) */
        ssol s;
        if (fit_ad(c, vt, &s) && better(&s, out)) *out = s;
    }
    if (out->ok) out->branch = branch;
    return out->ok;
}

/* Try first with ramps 2 and 3 kept apart, then letting them merge (kmin). */
static int solve_b23(const sctx *c0, int branch, ssol *out)
{
    sctx c = *c0;
    if (solve_b23_once(&c, branch, out)) return 1;
    c.merge23 = 1;
    return solve_b23_once(&c, branch, out);
}

/* The peak v* of the fastest profile from vs to ve over D without a velocity
 * limit: accelerating at am, then decelerating at dm,
 *     v*^2 = (dm vs^2 + am ve^2 + 2 D am dm) / (am + dm),
 * computed without overflow (am and dm may be 1e-300 or 1e300). */
static double peak_unlimited(double D, double vs, double ve, double am, double dm)
{
    double r = 1.0 / (1.0 + dm / am);               /* a / (a + d) */
    double h = am < dm ? am * (1.0 - r) : dm * r;   /* a d / (a + d) */
    double w = djl_sqrt(2.0 * D) * djl_sqrt(h);     /* v* from rest to rest */
    double V = dmax2(dmax2(vs, ve), w);
    return V * djl_sqrt((1.0 - r) * (vs / V) * (vs / V) + r * (ve / V) * (ve / V) +
                        (w / V) * (w / V));
}

/* Last resort of the AD structure (v_p above both end velocities): for a peak
 * vt of a grid from the continuous optimum (or v_max) down towards
 * max(vs, ve), the stages are sized for
 * vt and the cruise is found from the distance (fit_ad), instead of rounding
 * the continuous optimum to its neighbours (round_ad).  Rounding can fail
 * when a stage is far shorter than its jerk times (short_stage = 2 with
 * different T_F): one more sample of stage then moves the phase's centroid
 * by many samples, more than a neighbouring cruise length makes up.  From
 * rest to rest this always lands: with the stages sized for vt <= v_max and
 * the cruise rounded up, v_p <= vt and each level <= its limit. */
static int solve_fit(const sctx *c0, ssol *out)
{
    double lo = dmax2(c0->vs, c0->ve), hi = c0->vm, vc, kx;
    int p, q;
    out->ok = 0;
    /* no peak far above what the accelerations reach with no velocity limit
     * (v_max may be 1e300: a bisection from it would not come down) */
    hi = dmin2(hi, 2.0 * peak_unlimited(c0->D, c0->vs, c0->ve, c0->am, c0->dm) + lo);
    if (!(lo < hi)) return 0;
    /* from the continuous optimum (the limits at their most) down */
    if (cont_solve(c0, lo, hi, &vc, &kx) && vc > lo) hi = vc;
    for (p = 0; p <= 96; p++) {
        double vt = lo + (hi - lo) * djl_exp2(-p / 4.0); /* hi .. 1e-7 (hi - lo) above lo */
        sctx c = *c0;
        int mergedA = 0, mergedD = 0;
        if (!(vt > lo)) break;
        if (c.rule == DJL_SHORT_OVERLAP) { /* the paper's fallback, as in solve_b1 */
            double Ta = (vt - c.vs) / (c.am * c.Te), Td = (vt - c.ve) / (c.dm * c.Te);
            if (c.N1 != c.N2 && Ta < 0.5 * djl_fabs((double)c.N2 - c.N1)) {
                c.N2 = c.N1;
                mergedA = 1;
            }
            if (c.N3 != c.N4 && Td < 0.5 * djl_fabs((double)c.N4 - c.N3)) {
                c.N4 = c.N3;
                mergedD = 1;
            }
        }
        for (q = 0; q < 2; q++) {
            ssol s;
            c.merge23 = q;
            if (q && c.N2 != c.N3) break;
            if (fit_ad(&c, vt, &s) && better(&s, out)) {
                *out = s;
                out->mergedA = mergedA;
                out->mergedD = mergedD;
            }
        }
    }
    if (!out->ok) return 0;
    out->branch = out->vp >= lo ? 1 : out->vp >= dmin2(c0->vs, c0->ve) ? 2 : 3;
    return 1;
}

/* Single-stage (or pure cruise) profile at v_p = max(vs, ve) with the cruise
 * rounded to the nearest sample.  Returns the structure in *s and the
 * distance it covers; the caller carries the residual. */
static double pinned_D(const sctx *c, const ssol *s, int64_t k, int64_t *bend_out)
{
    double vlo = dmax2(c->vs, c->ve), D, be, g = c->g;
    if (s->hasA) {
        double ea = effl((double)s->n1, s->N1, s->N2);
        double ca = g + cnum((double)s->n1, s->N1, s->N2) / ea;
        double send = g + (double)(s->n1 + k);
        be = send;
        if (c->last) {
            be = dmax2(be, g + (double)s->n1 + s->N2);
            be = dmax2(be, g + (double)s->N1);
            be = dmax2(be, c->tail_in);
        }
        D = c->vs * ca + vlo * (be - ca);
    } else if (s->hasD) {
        double ed = effl((double)s->m, s->N3, s->N4);
        double cd = g + (double)k + cnum((double)s->m, s->N3, s->N4) / ed;
        double send = g + (double)(k + s->m);
        be = send;
        if (c->last) {
            be = dmax2(be, send + s->N4);
            be = dmax2(be, g + (double)k + s->N3);
            be = dmax2(be, c->tail_in);
        }
        D = c->vs * cd + c->ve * (be - cd);
    } else {
        be = g + (double)k;
        if (c->last) be = dmax2(be, c->tail_in);
        D = c->vs * be;
    }
    *bend_out = (int64_t)be;
    return D * c->Te;
}

/* Returns 1 on success (residual in *resid), 0 if the distance is too short
 * even for the single stage (min distance in *dmin). */
static int solve_pinned(const sctx *c, ssol *s, double *resid, double *dmin)
{
    double vlo = dmax2(c->vs, c->ve), D0, D1, kr;
    int64_t be, k, kk[2];
    int i, found = 0;
    double bestr = 0.0;
    memset(s, 0, sizeof(*s));
    s->N1 = c->N1;
    s->N2 = c->N2;
    s->N3 = c->N3;
    s->N4 = c->N4;
    s->hasA = c->vs < vlo;
    s->hasD = c->ve < vlo;
    if (s->hasA) {
        s->n1 = imax2(ceil_len((vlo - c->vs) / (c->am * c->Te) - 0.5 * (c->N2 - c->N1)), nmin_a(c));
        s->al = (vlo - c->vs) / (effl((double)s->n1, s->N1, s->N2) * c->Te);
    }
    if (s->hasD) {
        s->m = imax2(ceil_len((vlo - c->ve) / (c->dm * c->Te) - 0.5 * (c->N4 - c->N3)), nmin_d(c));
        s->dl = (vlo - c->ve) / (effl((double)s->m, s->N3, s->N4) * c->Te);
    }
    D0 = pinned_D(c, s, 0, &be);
    *dmin = D0;
    if (!(vlo > 0.0)) return 0;
    /* far enough from the tails, D grows by vlo*Te per cruise sample */
    D1 = pinned_D(c, s, 1000000, &be);
    kr = 1000000.0 - (D1 - c->D) / (vlo * c->Te);
    if (kr < -0.5 && c->D < D0) return 0;
    /* a cruise longer than a plan may hold (a speed far too low for the
     * distance): not this way */
    if (!(kr < (double)DJL_MAX_MOTION_SAMPLES)) return 0;
    kk[0] = kr <= 0.0 ? 0 : (int64_t)djl_floor(kr);
    kk[1] = kr <= 0.0 ? 0 : ceil_len(kr);
    k = 0;
    for (i = 0; i < 2; i++) {
        double r = c->D - pinned_D(c, s, kk[i], &be);
        if (!found || djl_fabs(r) < djl_fabs(bestr)) {
            found = 1;
            bestr = r;
            k = kk[i];
        }
    }
    if (c->D < D0 - 0.5 * vlo * c->Te) return 0;
    s->ok = 1;
    s->k = k;
    s->vp = vlo;
    s->D = pinned_D(c, s, k, &be);
    s->bend = be;
    s->g = (int64_t)c->g;
    s->len = s->g + (s->hasA ? s->n1 : 0) + k + (s->hasD ? s->m : 0);
    s->branch = 4;
    *resid = c->D - s->D;
    return 1;
}

/* Branch 5 (last segment only): a single stage vs -> ve whose start or end
 * falls between two samples.  That sample carries the mean acceleration over
 * it (what sampling a continuous AL stage whose boundary falls between
 * samples gives), so the distance becomes continuous in the fraction f and a
 * segment between two speeds lands exactly where no whole-sample stage does.
 * Shapes: the stage then a cruise at ve, or a cruise at vs then the stage;
 * split at the stage's end (split = 0) or start (split = 1).
 *
 * For steps (tau_i, A_i, N_i) with sum A_i = 0, the settled phase is a
 * velocity jump  eff * a  at time  cnum / eff  with
 *   eff  = -sum A_i (tau_i + N_i/2),
 *   cnum = -sum A_i (tau_i^2/2 + N_i tau_i/2 + N_i^2/6)      (A_i per unit a);
 * both are linear in f here. */
static void split_moments(int split, double n, double Na, double Nb, double *e0, double *e1,
                          double *c0, double *c1)
{
    /* unit steps: end split: (0,+1,Na) (n,-(1-f),Nb) (n+1,-f,Nb)
     *             start split: (0,+(1-f),Na) (1,+f,Na) (n+1,-1,Nb) */
#define MOM_E(t, N) ((t) + 0.5 * (N))
#define MOM_C(t, N) (0.5 * (t) * (t) + 0.5 * (N) * (t) + (N) * (N) / 6.0)
    if (split == 0) {
        /* A = +1, -(1-f), -f  ->  f=0: (+1,-1,0), slope (0,+1,-1) */
        *e0 = -(MOM_E(0.0, Na) - MOM_E(n, Nb));
        *e1 = -(MOM_E(n, Nb) - MOM_E(n + 1.0, Nb));
        *c0 = -(MOM_C(0.0, Na) - MOM_C(n, Nb));
        *c1 = -(MOM_C(n, Nb) - MOM_C(n + 1.0, Nb));
    } else {
        /* A = +(1-f), +f, -1  ->  f=0: (+1,0,-1), slope (-1,+1,0) */
        *e0 = -(MOM_E(0.0, Na) - MOM_E(n + 1.0, Nb));
        *e1 = -(-MOM_E(0.0, Na) + MOM_E(1.0, Na));
        *c0 = -(MOM_C(0.0, Na) - MOM_C(n + 1.0, Nb));
        *c1 = -(-MOM_C(0.0, Na) + MOM_C(1.0, Na));
    }
#undef MOM_E
#undef MOM_C
}

static int solve_split(const sctx *c, ssol *out)
{
    double vlo = dmax2(c->vs, c->ve), g = c->g;
    int acc = c->vs < c->ve, split, after;
    double Na = acc ? c->N1 : c->N3, Nb = acc ? c->N2 : c->N4;
    int64_t nmin = acc ? nmin_a(c) : nmin_d(c), n0, kf, n, k;
    double dv = djl_fabs(c->ve - c->vs), lim = acc ? c->am : c->dm, kr;
    int found = 0;
    ssol best;
    if (c->vs == c->ve || !c->last) return 0;
    memset(&best, 0, sizeof(best));
    n0 = imax2(ceil_len(dv / (lim * c->Te) - 0.5 * (Nb - Na)), nmin);
    {
        ssol pin;
        double resid, dmin;
        if (!solve_pinned(c, &pin, &resid, &dmin)) return 0;
        kr = (double)pin.k + resid / (vlo * c->Te);
    }
    if (!(kr < (double)DJL_MAX_MOTION_SAMPLES)) return 0;
    kf = kr < 0.0 ? 0 : (int64_t)djl_floor(kr);
    for (after = 0; after < 2; after++)
        for (split = 0; split < 2; split++)
            for (n = imax2(n0 - 1, nmin); n <= n0 + 3; n++)
                for (k = kf + 2; k >= 0 && k >= kf - 3; k--) {
                    /* stage occupies slots [t0, t0+n+1); cruise k at vs before
                     * (after = 0) or at ve after (after = 1) */
                    double t0 = g + (after ? 0.0 : (double)k);
                    double send = t0 + (double)n + 1.0 + (after ? (double)k : 0.0);
                    double e0, e1, c0, c1, be, tgt, fr, lvl, den;
                    split_moments(split, (double)n, Na, Nb, &e0, &e1, &c0, &c1);
                    be = dmax2(send, t0 + (double)n + 1.0 + Nb);
                    be = dmax2(be, t0 + Na + (split ? 1.0 : 0.0));
                    be = dmax2(be, c->tail_in);
                    /* D/Te = vs*C + ve*(be - C), C = t0 + cnum/eff */
                    tgt = (c->ve * be - c->D / c->Te) / (c->ve - c->vs) - t0;
                    den = c1 - tgt * e1;
                    if (!(den != 0.0)) continue;
                    fr = (tgt * e0 - c0) / den;
                    if (!(fr >= 0.0 && fr < 1.0)) continue;
                    lvl = dv / ((e0 + fr * e1) * c->Te);
                    if (!(lvl > 0.0) || lvl > lim * (1.0 + LIMIT_TOL)) continue;
                    if (!found || (int64_t)be < best.bend) {
                        found = 1;
                        memset(&best, 0, sizeof(best));
                        best.ok = 1;
                        best.hasA = acc;
                        best.hasD = !acc;
                        best.N1 = c->N1;
                        best.N2 = c->N2;
                        best.N3 = c->N3;
                        best.N4 = c->N4;
                        best.g = (int64_t)g;
                        best.f = fr;
                        best.split = split;
                        best.after = after;
                        if (acc) {
                            best.n1 = n;
                            best.al = lvl;
                        } else {
                            best.m = n;
                            best.dl = lvl;
                        }
                        best.k = k;
                        best.vp = vlo;
                        best.D = c->D;
                        best.len = (int64_t)send;
                        best.bend = (int64_t)be;
                        best.branch = 5;
                    }
                }
    if (found) *out = best;
    return found;
}

/* ------------------------------------------------------------------------ */
/* motion planning                                                          */

typedef struct {
    int64_t tau;
    double A;       /* m/s^2, real frame */
    int32_t N;
    double level;   /* AL acceleration right after this step */
    int phase_end;  /* ends a phase: v_after is the velocity once it has settled */
    double v_after;
} step_t;

typedef struct {
    sctx c[DJL_MAX_SEGMENTS];
    ssol s[DJL_MAX_SEGMENTS];
    int sigma[DJL_MAX_SEGMENTS];
    int empty[DJL_MAX_SEGMENTS];
    double Dreal[DJL_MAX_SEGMENTS], vS[DJL_MAX_SEGMENTS], vE[DJL_MAX_SEGMENTS];
    step_t step[DJL_MAX_STEPS];
    int n_steps;
    int64_t bnd[DJL_MAX_PIECES + 8];
    int lead;       /* DJL: a segment's first stage waits for the previous ramps (sctx.g) */
    const djl_params *user; /* the user's parameters (messages) */
    int kl;         /* lengths in units of 2^kl m (djl_plan_motion's rescaled retry) */
} work_t;

/* Error for segment i, planned in the frame of its direction with the
 * distance c->D (the user's distance plus what the rounding of the earlier
 * segments passed on); dmin is the shortest distance that frame allows. */
static djl_status infeasible(djl_error *err, const djl_params *p, int i, const sctx *c,
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
        sctx c2 = *c;
        c2.merge23 = 1;
        dmin = D_cont(&c2, c->vs, 0.0);
    }
    if (c->D >= dmin && (c->ve == 0.0 || !c->last))
        /* theory says a profile exists (docs/generator.md): a planner limitation */
        return set_error(err, DJL_E_INTERNAL, dname, D,
                         "%s = %g m from %g m/s to %g m/s (v_max = %g m/s, a_max = %g m/s2, "
                         "d_max = %g m/s2, Te = %g s): the planner found no profile landing "
                         "exactly on a sample although one should exist; please report it",
                         dname, D, vs, ve, p->v_max, p->a_max, p->d_max, p->Te);
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

static int segment_absorb(work_t *w, int j, double r_real, int branch)
{
    sctx c = w->c[j];
    ssol s;
    if (w->empty[j]) return 0;
    /* from the distance the segment was planned for: a rounded (pinned)
     * segment already passed its own residual on */
    c.D = w->s[j].D + w->sigma[j] * r_real;
    if (!(c.D > 0.0)) return 0;
    if (branch == 1 ? !solve_b1(&c, &s) : !solve_b23(&c, branch, &s)) return 0;
    w->c[j] = c;
    w->s[j] = s;
    return 1;
}

/* Samples by which the ramps of segments 0..L-1 run past the start of L. */
static int64_t tail_into(const work_t *w, int L)
{
    int64_t start = 0, tail = 0;
    int j;
    for (j = 0; j < L; j++) {
        const ssol *s = &w->s[j];
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
static int absorb_into(work_t *w, int j, int L, double r_real, int branch, int64_t bend_own)
{
    sctx c0 = w->c[j];
    ssol s0 = w->s[j];
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

static djl_status plan_last(work_t *w, int n, djl_error *err)
{
    int L = n - 1, j;
    sctx *c = &w->c[L];
    ssol pin;
    double resid = 0.0, dmin = 0.0;
    int64_t bend_own = 0;

    c->tail_in = (double)tail_into(w, L);
    if (solve_b1(c, &w->s[L])) return DJL_OK;

    if (solve_pinned(c, &pin, &resid, &dmin)) {
        double rr = w->sigma[L] * resid;
        sctx c0 = *c;
        ssol tmp;
        double r0, d0;
        c0.tail_in = 0.0;
        if (solve_pinned(&c0, &tmp, &r0, &d0)) bend_own = tmp.bend;
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
    if (solve_split(c, &w->s[L])) return DJL_OK;
    if (solve_b23(c, 2, &w->s[L]) || solve_b23(c, 3, &w->s[L])) return DJL_OK;
    if (pin.ok) {
        double rr = w->sigma[L] * resid;
        for (j = L - 1; j >= 0; j--)
            if (absorb_into(w, j, L, rr, 2, bend_own) || absorb_into(w, j, L, rr, 3, bend_own)) {
                w->s[L] = pin;
                return DJL_OK;
            }
    }
    if (solve_fit(c, &w->s[L])) return DJL_OK;
    return infeasible(err, w->user, L, c, dmin, w->kl);
}

/* A move that the acceleration limits make longer than a plan may hold.
 * Whatever the velocity limit, no profile from vs to ve over D is faster than
 * accelerating at a_max to v* and decelerating at d_max to ve, with
 *     v*^2 = (d vs^2 + a ve^2 + 2 D a d) / (a + d),
 * and when v* < max(vs, ve) (no room to go above both) none is faster than
 * the change of velocity at its limit, nor than what a_max allows from vs
 * (vs T + a T^2/2 >= D) and d_max towards ve.  The generated profile is such
 * a profile (its acceleration stays within the limits), so a move whose bound
 * exceeds DJL_MAX_MOTION_SAMPLES cannot be planned: it is refused here,
 * naming the limit that takes the longer part.  (Computed without overflow:
 * a and d may be 1e-300 or 1e300.) */
static djl_status check_duration(const djl_params *p, int i, djl_error *err)
{
    double Dr = p->n_segments == 0 ? p->distance : p->seg_distance[i];
    double vE = p->n_segments == 0 ? p->v_e : p->seg_v_end[i];
    double vS = i == 0 ? p->v0 : p->seg_v_end[i - 1];
    double sg = Dr < 0.0 ? -1.0 : 1.0, D = djl_fabs(Dr), vs = sg * vS, ve = sg * vE, Te = p->Te;
    double am = p->a_max, dm = p->d_max, lim = (double)DJL_MAX_MOTION_SAMPLES * (1.0 + 1e-9);
    double vt, na, nd;
    char dname[40];
    if (!(D > 0.0)) return DJL_OK;
    vt = peak_unlimited(D, vs, ve, am, dm);
    if (vt >= vs && vt >= ve) {
        na = (vt - vs) / am / Te;
        nd = (vt - ve) / dm / Te;
    } else {
        double Ta = 2.0 * D / (vs + djl_hypot(vs, djl_sqrt(2.0 * am) * djl_sqrt(D)));
        double Td = 2.0 * D / (ve + djl_hypot(ve, djl_sqrt(2.0 * dm) * djl_sqrt(D)));
        na = dmax2(Ta, ve > vs ? (ve - vs) / am : 0.0) / Te;
        nd = dmax2(Td, ve > vs ? 0.0 : (vs - ve) / dm) / Te;
    }
    if (!(na + nd > lim)) return DJL_OK;
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

static void add_step(work_t *w, int64_t tau, double A, int32_t N, double level, int phase_end,
                     double v_after)
{
    step_t *st;
    if (A == 0.0) return;
    st = &w->step[w->n_steps++];
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

static int64_t ramp_tail_after(const work_t *w, int64_t t)
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
static void phase_state(const work_t *w, int q0, int q1, int64_t b, double *a, double *dv)
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

static void exact_state(const work_t *w, int64_t b, double v0, double Te, double *a_out,
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
static djl_status walk_pieces(const work_t *w, djl_plan *plan, const djl_params *p, int n, int nb,
                              double tolx, double scale, int exact, djl_error *err)
{
    int j;
    double x = 0.0, v = p->v0, a = 0.0, xal = 0.0, val = p->v0;
    double vsnap = p->v0, level = 0.0;
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
        for (q = 0; q < w->n_steps; q++) {
            const step_t *sq = &w->step[q];
            if (sq->N > 0 && sq->tau <= b && b < sq->tau + sq->N) {
                jerk += sq->A / (sq->N * p->Te);
                quiet = 0;
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
    /* self-check: the plan lands where it was asked to */
    if (!(djl_fabs(plan->piece[plan->n_pieces - 1].x - plan->x_target) <= tolx * scale))
        return set_error(err, DJL_E_INTERNAL, "", 0.0,
                         "planner self-check: final displacement %.17g m, expected %.17g m",
                         plan->piece[plan->n_pieces - 1].x, plan->x_target);
    return DJL_OK;
}

/* Plan validated parameters p; precise: the retries of djl_plan_motion (see
 * there), p then possibly the user's parameters in units of 2^kl m and some
 * power of two of seconds (user: the user's, for messages). */
static djl_status plan_once(const djl_params *p, const djl_params *user, int kl, djl_plan *plan,
                            djl_error *err, int precise)
{
    static const double tolx = 1e-11;
    work_t w;
    djl_status st;
    int n, i, nb;
    int32_t N[4];
    double r = 0.0, scale;
    int64_t S;

    if (err) memset(err, 0, sizeof(*err));
    memset(plan, 0, sizeof(*plan));
    memset(&w, 0, sizeof(w));
    w.user = user;
    w.kl = kl;
    plan->p = *p;

    for (i = 0; i < 4; i++) {
        int src = p->profile == DJL_PROFILE_DJL ? i : 0;
        N[i] = p->profile == DJL_PROFILE_AL ? 0 : (int32_t)djl_floor(p->T_F[src] / p->Te + 0.5);
        plan->N[i] = N[i];
    }

    n = p->n_segments == 0 ? 1 : p->n_segments;
    plan->n_segments = n;
    w.lead = !(N[0] == N[1] && N[1] == N[2] && N[2] == N[3]);
    scale = djl_fabs(p->v0) * p->Te;
    for (i = 0; i < n; i++) {
        w.Dreal[i] = p->n_segments == 0 ? p->distance : p->seg_distance[i];
        w.vE[i] = p->n_segments == 0 ? p->v_e : p->seg_v_end[i];
        w.vS[i] = i == 0 ? p->v0 : w.vE[i - 1];
        scale += djl_fabs(w.Dreal[i]);
        plan->x_target += w.Dreal[i];
    }
    plan->v_target = w.vE[n - 1];
    for (i = 0; i < n; i++)
        if ((st = check_duration(user, i, err)) != DJL_OK) return st;

    /* Forward pass: each segment is planned time-optimally and exactly when
     * it can; a segment pinned at a velocity it cannot leave (pure cruise,
     * single stage) is rounded to the nearest sample and passes the
     * residual on, so nothing accumulates. */
    for (i = 0; i < n; i++) {
        sctx *c = &w.c[i];
        ssol *s = &w.s[i];
        double Dr = w.Dreal[i] + r, resid = 0.0, dmin = 0.0;
        int sg = w.Dreal[i] > 0.0 ? 1 : w.Dreal[i] < 0.0 ? -1 : (Dr >= 0.0 ? 1 : -1);
        w.sigma[i] = sg;
        c->D = sg * Dr;
        c->vs = sg * w.vS[i];
        c->ve = sg * w.vE[i];
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
        if (i > 0 && w.lead) c->g = (double)tail_into(&w, i);
        r = 0.0;
        if (Dr == 0.0 && w.vS[i] == 0.0 && w.vE[i] == 0.0) {
            w.empty[i] = 1;
            memset(s, 0, sizeof(*s));
            s->ok = 1;
            continue;
        }
        if (solve_b1(c, s)) continue;
        if (!c->last) {
            if (solve_pinned(c, s, &resid, &dmin)) {
                r = sg * resid;
                continue;
            }
            if (solve_b23(c, 2, s) || solve_b23(c, 3, s)) continue;
            if (solve_fit(c, s)) continue;
            return infeasible(err, user, i, c, dmin, kl);
        }
    }

    /* The last segment must land exactly. */
    if (!w.empty[n - 1] && !w.s[n - 1].ok) {
        st = plan_last(&w, n, err);
        if (st != DJL_OK) return st;
    }

    /* Steps of the AL profile, real frame. */
    w.n_steps = 0;
    S = 0;
    for (i = 0; i < n; i++) {
        const ssol *s = &w.s[i];
        djl_segment_plan *sp = &plan->seg[i];
        double sg = w.sigma[i];
        sp->start = S;
        sp->distance = sg * s->D;
        if (w.empty[i]) {
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
            /* single stage vs -> ve with one split sample (see solve_split) */
            double lv = s->hasA ? s->al : -s->dl; /* signed level, positive frame */
            double fl = s->f * lv;
            int32_t Na = s->hasA ? s->N1 : s->N3, Nb = s->hasA ? s->N2 : s->N4;
            int64_t t0 = S + s->g + (s->after ? 0 : s->k);
            int64_t nn = s->hasA ? s->n1 : s->m;
            double vend = w.vE[i];
            if (s->split == 0) {
                add_step(&w, t0, sg * lv, Na, sg * lv, 0, 0.0);
                add_step(&w, t0 + nn, -sg * (lv - fl), Nb, sg * fl, fl == 0.0, vend);
                add_step(&w, t0 + nn + 1, -sg * fl, Nb, 0.0, 1, vend);
            } else {
                add_step(&w, t0, sg * (lv - fl), Na, sg * (lv - fl), 0, 0.0);
                add_step(&w, t0 + 1, sg * fl, Na, sg * lv, 0, 0.0);
                add_step(&w, t0 + nn + 1, -sg * lv, Nb, 0.0, 1, vend);
            }
        } else {
            if (s->hasA) {
                add_step(&w, S + s->g, sg * s->al, s->N1, sg * s->al, 0, 0.0);
                add_step(&w, S + s->g + s->n1, -sg * s->al, s->N2, 0.0, 1, sg * s->vp);
            }
            if (s->hasD) {
                int64_t t3 = S + s->g + (s->hasA ? s->n1 : 0) + s->k;
                add_step(&w, t3, -sg * s->dl, s->N3, -sg * s->dl, 0, 0.0);
                add_step(&w, t3 + s->m, sg * s->dl, s->N4, 0.0, 1, w.vE[i]);
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
    {
        int L = n - 1;
        int64_t kend = plan->seg[L].start + (w.empty[L] ? 0 : w.s[L].bend);
        int64_t tail = ramp_tail_after(&w, 0);
        if (tail > kend) kend = tail;
        if (S > kend) kend = S;
        if ((double)kend > (double)DJL_MAX_MOTION_SAMPLES)
            return set_error(err, DJL_E_INFEASIBLE, "Te", user->Te,
                             "the motion would last %g samples of Te = %g s: more than the %g "
                             "a plan may hold", (double)kend, user->Te,
                             (double)DJL_MAX_MOTION_SAMPLES);
        plan->k_end = kend;
    }

    /* Piece boundaries. */
    nb = 0;
    w.bnd[nb++] = 0;
    w.bnd[nb++] = plan->k_end;
    for (i = 0; i < w.n_steps; i++) {
        w.bnd[nb++] = w.step[i].tau;
        w.bnd[nb++] = w.step[i].tau + w.step[i].N;
    }
    for (i = 0; i < n; i++)
        if (plan->seg[i].start < plan->k_end) w.bnd[nb++] = plan->seg[i].start;
    sort_unique(w.bnd, &nb);
    if (nb > DJL_MAX_PIECES)
        return set_error(err, DJL_E_INTERNAL, "", 0.0, "plan needs %d pieces (max %d)", nb,
                         DJL_MAX_PIECES);

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
    return st;
}

/* Every value of the plan finite, and no quantity (x, v, a, j, x_al, v_al,
 * a_al) whose largest magnitude over the pieces is a subnormal double: its
 * values would have lost their digits (smaller values of a quantity that
 * also has normal ones, rounding residues, are harmless). */
static int plan_clean(const djl_plan *pl)
{
    double big[7] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    int i, q;
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
    for (q = 0; q < 7; q++)
        if (big[q] != 0.0 && big[q] < DJL_MIN_MAGNITUDE) return 0;
    return 1;
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
    double big = 0.0;
    int i, n = p->n_segments == 0 ? 1 : p->n_segments, Nmin = 0;
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
    /* the parameters must survive the change of units (they may span more
     * than a double's range between them) */
    if (djl_validate(&q, NULL) != DJL_OK) return DJL_E_INTERNAL;
    st = plan_once(&q, p, kl, plan, err, 1);
    if (st != DJL_OK) return st;
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
    plan->piece[plan->n_pieces - 1].v = plan->v_target;
    if (djl_isfinite(big) && !plan_clean(plan)) {
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
    st = plan_once(p, p, 0, plan, err, 0);
    if (st == DJL_OK && plan_clean(plan)) return DJL_OK;
    /* Times are counted in samples from a segment's start; with jerk times
     * of millions of samples (or stages of billions) the distance formula
     * then loses digits to the difference of two long times.  A plan that
     * fails its checks is made again with the formulas taken relative to the
     * stage they describe (only the plans the first way fails get the
     * second: the others stay as they are, bit for bit). */
    if (st == DJL_E_INTERNAL) {
        precise = 1;
        st = plan_once(p, p, 0, plan, err, 1);
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
    if (st == DJL_OK) return plan_once(p, p, 0, plan, err, precise); /* the plan made above */
    return st; /* and its message */
}

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
}

double djl_applied_jerk_time(const djl_plan *plan, int stage)
{
    if (stage < 0 || stage > 3) return 0.0;
    return plan->N[stage] * plan->p.Te;
}

double djl_motion_time(const djl_plan *plan) { return (double)plan->k_end * plan->p.Te; }
