/*
 * djl_segment.c -- one segment of a motion: its stages sized and its landing
 * solved, in whole samples and to the exact distance.
 *
 *  - size_stages: the whole-sample stage lengths for a peak velocity;
 *  - land_with_lengths: for given lengths, the peak velocity and the stage
 *    accelerations that cover the distance exactly (the landing);
 *  - the solvers, one per shape of profile (branch), tried by djl_motion.c:
 *    solve_time_optimal (1), solve_monotone_or_dip (2, 3),
 *    solve_pinned_single_stage (4), solve_split_sample (5) and the last
 *    resort solve_fit_peak_grid.
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
 *    (Na, Nb the filters of the first and second step, n their distance;
 *    phase_effective_length computes eff, phase_moment cnum).
 *    This is eq. (14)-(15) of the paper for the velocity; the position term
 *    is what makes DJL land exactly when the four jerk times differ.
 *  - The distance of a segment is the integral of that staircase of
 *    velocities over the segment, so it is linear in the peak velocity v_p:
 *        D/Te = vs*c_a + v_p*(c_d - c_a) + ve*(b_end - c_d).
 *    Given whole-sample stage lengths, v_p follows exactly from D; the stage
 *    accelerations follow from v_p (the Appendix's "recompute v_max, a_max,
 *    d_max", generalised to filtered steps).
 */
#include "djl_internal.h"

#include <string.h>

/* Relative slack accepted on the limits, for rounding only. */
#define LIMIT_TOL 1e-13

/* cnum of the vocabulary above: the first moment of a phase's settled
 * velocity jump (its centroid time is phase_moment / phase_effective_length). */
static double phase_moment(double n, double Na, double Nb)
{
    return 0.5 * n * n + 0.5 * Nb * n - (Na * Na - Nb * Nb) / 6.0;
}

/* eff of the vocabulary above: the phase's effective length, samples. */
static double phase_effective_length(double n, double Na, double Nb) { return n + 0.5 * (Nb - Na); }

static int64_t min_accel_samples(const segment_problem *c)
{
    if (c->rule == DJL_SHORT_STRETCH) return imax2(c->N1, 1);
    return imax2((int64_t)c->N1 - c->N2, 1);
}

static int64_t min_decel_samples(const segment_problem *c)
{
    if (c->rule == DJL_SHORT_STRETCH) return imax2(c->N3, 1);
    return imax2((int64_t)c->N3 - c->N4, 1);
}

/* Cruise between the two phases: ramps 2 and 3 must not overlap, except in
 * the fallback branches when they share one filter: they then merge into a
 * single ramp of jerk (change of acceleration)/T_F.  (Two ramps of different
 * lengths starting together would let the faster one push the acceleration
 * past the limit before the slower one has taken its share off.) */
static int64_t min_cruise_samples(const segment_problem *c)
{
    if (c->merge23 && c->N2 == c->N3) return 0;
    return c->N2;
}

static double min_accel_effective_length(const segment_problem *c)
{
    return (double)min_accel_samples(c) + 0.5 * (c->N2 - c->N1);
}
static double min_decel_effective_length(const segment_problem *c)
{
    return (double)min_decel_samples(c) + 0.5 * (c->N4 - c->N3);
}

/* distance_coefficients of the precise retry: the same quantities without differences of
 * long absolute times (the end of the staircase and the centroids taken from
 * the start of the deceleration, t3). */
static void distance_coefficients_relative(const segment_problem *c, double n1, double k, double m,
                                           double *K0, double *K1, double *bend)
{
    double g = c->g;
    double cna = phase_moment(n1, c->N1, c->N2) / phase_effective_length(n1, c->N1, c->N2);
    double cnd = phase_moment(m, c->N3, c->N4) / phase_effective_length(m, c->N3, c->N4);
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
static void distance_coefficients(const segment_problem *c, double n1, double k, double m,
                                  double *K0, double *K1, double *bend)
{
    double g = c->g;
    double ea = phase_effective_length(n1, c->N1, c->N2),
           ed = phase_effective_length(m, c->N3, c->N4);
    double ca = g + phase_moment(n1, c->N1, c->N2) / ea;
    double t3 = g + n1 + k;
    double cd = t3 + phase_moment(m, c->N3, c->N4) / ed;
    double send = t3 + m;
    double be = send;
    if (c->precise) {
        distance_coefficients_relative(c, n1, k, m, K0, K1, bend);
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
static double needed_effective_length(const segment_problem *c, double dv, double Lmin)
{
    double t = dv >= 0.0 ? dv / (c->am * c->Te) : -dv / (c->dm * c->Te);
    return dmax2(t, Lmin);
}

/* Continuous relaxation: distance of the AD structure with peak vp and kx
 * extra cruise samples, stages as short as the limits allow. */
DJL_INTERNAL double distance_continuous(const segment_problem *c, double vp, double kx)
{
    double ea = needed_effective_length(c, vp - c->vs, min_accel_effective_length(c));
    double ed = needed_effective_length(c, c->ve - vp, min_decel_effective_length(c));
    double n1 = ea - 0.5 * (c->N2 - c->N1), m = ed - 0.5 * (c->N4 - c->N3);
    double K0, K1, be;
    distance_coefficients(c, n1, (double)min_cruise_samples(c) + kx, m, &K0, &K1, &be);
    return c->Te * (K0 + vp * K1);
}

static int64_t ceil_samples(double x)
{
    if (!(x < (double)DJL_MAX_MOTION_SAMPLES)) return DJL_MAX_MOTION_SAMPLES;
    if (x < 0.0) return 0;
    return (int64_t)djl_ceil(x);
}

/* Whole-sample stage lengths for the peak vp, each f times as long (in
 * effective samples) as the limits need. */
static void size_stages(const segment_problem *c, double vp, double f, int64_t *n1, int64_t *m)
{
    double ea = needed_effective_length(c, vp - c->vs, min_accel_effective_length(c)),
           ed = needed_effective_length(c, c->ve - vp, min_decel_effective_length(c));
    *n1 = imax2(ceil_samples(f * ea - 0.5 * (c->N2 - c->N1)), min_accel_samples(c));
    *m = imax2(ceil_samples(f * ed - 0.5 * (c->N4 - c->N3)), min_decel_samples(c));
}

/* Exact solution of the AD structure for whole-sample lengths. */
static int land_with_lengths(const segment_problem *c, int64_t n1, int64_t k, int64_t m,
                             int signfree, segment_solution *s)
{
    double K0, K1, be, vp, ea, ed, al, dl;
    if (n1 < min_accel_samples(c) || m < min_decel_samples(c) || k < min_cruise_samples(c))
        return 0;
    if ((double)(n1 + k + m) > (double)DJL_MAX_MOTION_SAMPLES) return 0;
    distance_coefficients(c, (double)n1, (double)k, (double)m, &K0, &K1, &be);
    if (!(K1 > 0.0)) return 0;
    vp = (c->D / c->Te - K0) / K1;
    ea = phase_effective_length((double)n1, c->N1, c->N2);
    ed = phase_effective_length((double)m, c->N3, c->N4);
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

static int solution_better(const segment_solution *a, const segment_solution *b)
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
static int round_to_whole_samples(const segment_problem *c, double vp, double kx, int signfree,
                                  segment_solution *best)
{
    int64_t n1c, mc,
        kc = imax2(ceil_samples((double)min_cruise_samples(c) + kx), min_cruise_samples(c));
    int i, j, l, up;
    size_stages(c, vp, 1.0, &n1c, &mc);
    best->ok = 0;
    for (up = 0; up <= 1 && !best->ok; up++) /* one sample longer only if needed */
        for (i = -1; i <= up; i++)
            for (j = -1; j <= up; j++)
                for (l = -1; l <= up; l++) {
                    segment_solution s;
                    if (land_with_lengths(c, n1c + i, kc + j, mc + l, signfree, &s) &&
                        solution_better(&s, best))
                        *best = s;
                }
    return best->ok;
}

/* Find vp in [lo, hi] with distance_continuous(vp, 0) = D (distance_continuous increasing); above
 * distance_continuous(hi, 0), vp = hi and the cruise grows. */
static int solve_peak_continuous(const segment_problem *c, double lo, double hi, double *vp,
                                 double *kx)
{
    double Dhi = distance_continuous(c, hi, 0.0), Dlo;
    int it;
    if (c->D >= Dhi) {
        if (!(hi > 0.0)) return 0;
        *vp = hi;
        *kx = (c->D - Dhi) / (hi * c->Te);
        return djl_isfinite(*kx);
    }
    Dlo = distance_continuous(c, lo, 0.0);
    if (!(c->D >= Dlo)) return 0;
    for (it = 0; it < 200 && hi - lo > 1e-15 * dmax2(hi, 1e-300); it++) {
        double mid = 0.5 * (lo + hi);
        if (distance_continuous(c, mid, 0.0) <= c->D)
            lo = mid;
        else
            hi = mid;
    }
    *vp = lo;
    *kx = 0.0;
    return 1;
}

/* Branch 1: the time-optimal profile, v_p above both end velocities. */
DJL_INTERNAL int solve_time_optimal(const segment_problem *c0, segment_solution *out)
{
    segment_problem c = *c0;
    double vlo = dmax2(c.vs, c.ve), vp, kx;
    int mergedA = 0, mergedD = 0;
    if (!(vlo < c.vm)) return 0;
    if (!solve_peak_continuous(&c, vlo, c.vm, &vp, &kx)) return 0;
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
        if ((mergedA || mergedD) && !solve_peak_continuous(&c, vlo, c.vm, &vp, &kx)) return 0;
    }
    if (!round_to_whole_samples(&c, vp, kx, 0, out) && !round_to_whole_samples(&c, vp, kx, 1, out))
        return 0;
    out->mergedA = mergedA;
    out->mergedD = mergedD;
    out->branch = 1;
    return 1;
}

/* Whole-sample lengths for a peak velocity near vt: stages sized for vt,
 * the cruise rounded up for the distance; rounding moves the peak, so the
 * stages are resized for it (the total kept) until the limits hold. */
static int fit_cruise_for_peak(const segment_problem *c, double vt, segment_solution *out)
{
    int64_t n1, m, k;
    double K0, K1, be, kr;
    int it;
    if (!(vt > 0.0)) return 0;
    size_stages(c, vt, 1.0, &n1, &m);
    distance_coefficients(c, (double)n1, (double)min_cruise_samples(c), (double)m, &K0, &K1, &be);
    kr = (double)min_cruise_samples(c) + (c->D / c->Te - K0 - vt * K1) / vt;
    if (!(kr > (double)min_cruise_samples(c) - 1.0) || !(kr < (double)DJL_MAX_MOTION_SAMPLES))
        return 0;
    k = imax2(ceil_samples(kr), min_cruise_samples(c));
    for (it = 0; it < 8; it++) {
        int64_t n1v, mv;
        double v;
        if (land_with_lengths(c, n1, k, m, 1, out)) return 1;
        distance_coefficients(c, (double)n1, (double)k, (double)m, &K0, &K1, &be);
        v = (c->D / c->Te - K0) / K1;
        if (!djl_isfinite(v)) return 0;
        size_stages(c, v, 1.0, &n1v, &mv);
        if (n1v <= n1 && mv <= m) return 0;
        k -= imax2(n1v - n1, 0) + imax2(mv - m, 0);
        if (k < min_cruise_samples(c)) return 0;
        n1 = imax2(n1, n1v);
        m = imax2(m, mv);
    }
    return 0;
}

/* Branches 2 (v_p between the end velocities: two stages in the same
 * direction) and 3 (v_p below both: a dip), used to land exactly when the
 * time-optimal shape cannot. */
static int solve_monotone_or_dip_once(const segment_problem *c, int branch, segment_solution *out)
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
    if (!solve_peak_continuous(c, lo, hi, &vp, &kx)) return 0;
    if (round_to_whole_samples(c, vp, kx, 1, out)) {
        out->branch = branch;
        return 1;
    }
    /* Lengthen both stages until their accelerations fit the limits. */
    for (p = 1; p <= 40; p++) {
        double K0, K1, be, kr;
        int64_t n1, m, k;
        int j;
        size_stages(c, vp, djl_ldexp(1.0, p), &n1, &m);
        distance_coefficients(c, (double)n1, (double)min_cruise_samples(c), (double)m, &K0, &K1,
                              &be);
        if (!(vp > 0.0)) break;
        kr = (double)min_cruise_samples(c) + (c->D / c->Te - K0 - vp * K1) / vp;
        if (kr < (double)min_cruise_samples(c) - 1.0) break; /* longer stages only make it worse */
        k = imax2(ceil_samples(kr), min_cruise_samples(c));
        out->ok = 0;
        for (j = 0; j < 2; j++) {
            segment_solution s;
            if (land_with_lengths(c, n1, k - j, m, 1, &s) && solution_better(&s, out)) *out = s;
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
        segment_solution s;
        if (fit_cruise_for_peak(c, vt, &s) && solution_better(&s, out)) *out = s;
    }
    if (out->ok) out->branch = branch;
    return out->ok;
}

/* Try first with ramps 2 and 3 kept apart, then letting them merge (min_cruise_samples). */
DJL_INTERNAL int solve_monotone_or_dip(const segment_problem *c0, int branch, segment_solution *out)
{
    segment_problem c = *c0;
    if (solve_monotone_or_dip_once(&c, branch, out)) return 1;
    c.merge23 = 1;
    return solve_monotone_or_dip_once(&c, branch, out);
}

/* The peak v* of the fastest profile from vs to ve over D without a velocity
 * limit: accelerating at am, then decelerating at dm,
 *     v*^2 = (dm vs^2 + am ve^2 + 2 D am dm) / (am + dm),
 * computed without overflow (am and dm may be 1e-300 or 1e300). */
DJL_INTERNAL double peak_without_velocity_limit(double D, double vs, double ve, double am,
                                                double dm)
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
 * vt and the cruise is found from the distance (fit_cruise_for_peak), instead of rounding
 * the continuous optimum to its neighbours (round_to_whole_samples).  Rounding can fail
 * when a stage is far shorter than its jerk times (short_stage = 2 with
 * different T_F): one more sample of stage then moves the phase's centroid
 * by many samples, more than a neighbouring cruise length makes up.  From
 * rest to rest this always lands: with the stages sized for vt <= v_max and
 * the cruise rounded up, v_p <= vt and each level <= its limit. */
DJL_INTERNAL int solve_fit_peak_grid(const segment_problem *c0, segment_solution *out)
{
    double lo = dmax2(c0->vs, c0->ve), hi = c0->vm, vc, kx;
    int p, q;
    out->ok = 0;
    /* no peak far above what the accelerations reach with no velocity limit
     * (v_max may be 1e300: a bisection from it would not come down) */
    hi = dmin2(hi, 2.0 * peak_without_velocity_limit(c0->D, c0->vs, c0->ve, c0->am, c0->dm) + lo);
    if (!(lo < hi)) return 0;
    /* from the continuous optimum (the limits at their most) down */
    if (solve_peak_continuous(c0, lo, hi, &vc, &kx) && vc > lo) hi = vc;
    for (p = 0; p <= 96; p++) {
        double vt = lo + (hi - lo) * djl_exp2(-p / 4.0); /* hi .. 1e-7 (hi - lo) above lo */
        segment_problem c = *c0;
        int mergedA = 0, mergedD = 0;
        if (!(vt > lo)) break;
        if (c.rule == DJL_SHORT_OVERLAP) { /* the paper's fallback, as in solve_time_optimal */
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
            segment_solution s;
            c.merge23 = q;
            if (q && c.N2 != c.N3) break;
            if (fit_cruise_for_peak(&c, vt, &s) && solution_better(&s, out)) {
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
static double pinned_distance(const segment_problem *c, const segment_solution *s, int64_t k,
                              int64_t *bend_out)
{
    double vlo = dmax2(c->vs, c->ve), D, be, g = c->g;
    if (s->hasA) {
        double ea = phase_effective_length((double)s->n1, s->N1, s->N2);
        double ca = g + phase_moment((double)s->n1, s->N1, s->N2) / ea;
        double send = g + (double)(s->n1 + k);
        be = send;
        if (c->last) {
            be = dmax2(be, g + (double)s->n1 + s->N2);
            be = dmax2(be, g + (double)s->N1);
            be = dmax2(be, c->tail_in);
        }
        D = c->vs * ca + vlo * (be - ca);
    } else if (s->hasD) {
        double ed = phase_effective_length((double)s->m, s->N3, s->N4);
        double cd = g + (double)k + phase_moment((double)s->m, s->N3, s->N4) / ed;
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
DJL_INTERNAL int solve_pinned_single_stage(const segment_problem *c, segment_solution *s,
                                           double *resid, double *dmin)
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
        s->n1 = imax2(ceil_samples((vlo - c->vs) / (c->am * c->Te) - 0.5 * (c->N2 - c->N1)),
                      min_accel_samples(c));
        s->al = (vlo - c->vs) / (phase_effective_length((double)s->n1, s->N1, s->N2) * c->Te);
    }
    if (s->hasD) {
        s->m = imax2(ceil_samples((vlo - c->ve) / (c->dm * c->Te) - 0.5 * (c->N4 - c->N3)),
                     min_decel_samples(c));
        s->dl = (vlo - c->ve) / (phase_effective_length((double)s->m, s->N3, s->N4) * c->Te);
    }
    D0 = pinned_distance(c, s, 0, &be);
    *dmin = D0;
    if (!(vlo > 0.0)) return 0;
    /* far enough from the tails, D grows by vlo*Te per cruise sample */
    D1 = pinned_distance(c, s, 1000000, &be);
    kr = 1000000.0 - (D1 - c->D) / (vlo * c->Te);
    if (kr < -0.5 && c->D < D0) return 0;
    /* a cruise longer than a plan may hold (a speed far too low for the
     * distance): not this way */
    if (!(kr < (double)DJL_MAX_MOTION_SAMPLES)) return 0;
    kk[0] = kr <= 0.0 ? 0 : (int64_t)djl_floor(kr);
    kk[1] = kr <= 0.0 ? 0 : ceil_samples(kr);
    k = 0;
    for (i = 0; i < 2; i++) {
        double r = c->D - pinned_distance(c, s, kk[i], &be);
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
    s->D = pinned_distance(c, s, k, &be);
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
 * velocity jump  eff * a  at time  phase_moment / eff  with
 *   eff  = -sum A_i (tau_i + N_i/2),
 *   phase_moment = -sum A_i (tau_i^2/2 + N_i tau_i/2 + N_i^2/6)      (A_i per unit a);
 * both are linear in f here. */
static void split_stage_moments(int split, double n, double Na, double Nb, double *e0, double *e1,
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

DJL_INTERNAL int solve_split_sample(const segment_problem *c, segment_solution *out)
{
    double vlo = dmax2(c->vs, c->ve), g = c->g;
    int acc = c->vs < c->ve, split, after;
    double Na = acc ? c->N1 : c->N3, Nb = acc ? c->N2 : c->N4;
    int64_t nmin = acc ? min_accel_samples(c) : min_decel_samples(c), n0, kf, n, k;
    double dv = djl_fabs(c->ve - c->vs), lim = acc ? c->am : c->dm, kr;
    int found = 0;
    segment_solution best;
    if (c->vs == c->ve || !c->last) return 0;
    memset(&best, 0, sizeof(best));
    n0 = imax2(ceil_samples(dv / (lim * c->Te) - 0.5 * (Nb - Na)), nmin);
    {
        segment_solution pin;
        double resid, dmin;
        if (!solve_pinned_single_stage(c, &pin, &resid, &dmin)) return 0;
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
                    split_stage_moments(split, (double)n, Na, Nb, &e0, &e1, &c0, &c1);
                    be = dmax2(send, t0 + (double)n + 1.0 + Nb);
                    be = dmax2(be, t0 + Na + (split ? 1.0 : 0.0));
                    be = dmax2(be, c->tail_in);
                    /* D/Te = vs*C + ve*(be - C), C = t0 + phase_moment/eff */
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
