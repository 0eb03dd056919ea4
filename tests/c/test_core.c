/*
 * test_core.c -- the generator core on its own, meant to run under
 * AddressSanitizer + UndefinedBehaviorSanitizer (tests/test_c_sanitizers.py).
 *
 * Random parameter sets (valid and invalid): every plan either succeeds and
 * lands exactly within the limits, or fails with a parameter/feasibility
 * error and a message naming the parameter; never an internal error, a
 * crash, a NaN or a hang.
 *
 * Usage: test_core [cases] [seed] [mode]
 *   mode  classic  moves of everyday size (both short_stage rules, AL/JL/DJL,
 *                  start/end speeds, up to 20 segments), 10 % spoiled
 *         grid     round numbers: v_max in {1,2,5} 10^k, T_F whole multiples
 *                  of Te (0.512/0.511/0.121/0.007 ...), round distances
 *         extreme  magnitudes over many decades: a classic or grid case
 *                  rescaled in length (1e-9..1e9, and 1e-300..1e300) and
 *                  time (1e-6..1e6, and 1e-12..1e8),
 *                  a_max / d_max down to 1e-30, subnormal and tiny distances,
 *                  x0 near 1e300, segment sums near DJL_MAX_POSITION, jerk
 *                  times up to the longest filter, 32 segments, a limit far
 *                  above what the motion reaches (v_max up to 1e300 m/s)
 *         all      (default) each case drawn from one of the three above
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "djl_core.h"

static unsigned long long rng_state = 88172645463325252ULL;

static double urand(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

static double log_uniform(double lo, double hi) { return lo * pow(hi / lo, urand()); }
static int irand(int n) { return (int)(urand() * n); }

static int failures = 0;

#define FAIL(...)                                                                                \
    do {                                                                                         \
        fprintf(stderr, __VA_ARGS__);                                                            \
        fputc('\n', stderr);                                                                     \
        failures++;                                                                              \
    } while (0)

/* ------------------------------------------------------------------------ */
/* parameter families                                                       */

static double pick_velocity(double vmax)
{
    double r = urand();
    return r < 0.4 ? 0.0 : r < 0.55 ? vmax : urand() * vmax;
}

static void classic_params(djl_params *p)
{
    int i, n;
    double sgn = urand() < 0.7 ? 1.0 : -1.0;
    djl_params_default(p);
    p->profile = 1 + (int)(urand() * 3.0);
    p->short_stage = urand() < 0.5 ? 1 : 2;
    p->Te = log_uniform(1e-4, 1e-2);
    p->v_max = log_uniform(0.1, 10.0);
    p->a_max = log_uniform(0.3, 30.0);
    p->d_max = urand() < 0.5 ? p->a_max : log_uniform(0.3, 30.0);
    for (i = 0; i < 4; i++) p->T_F[i] = fmax(log_uniform(5e-3, 0.2), p->Te);
    p->x0 = 2.0 * urand() - 1.0;
    p->v0 = urand() < 0.3 ? sgn * pick_velocity(p->v_max) : 0.0;
    n = urand() < 0.5 ? 0 : 1 + (int)(urand() * 20.0);
    p->n_segments = n;
    if (n == 0) {
        p->distance = sgn * log_uniform(1e-3, 3.0);
        p->v_e = urand() < 0.3 ? sgn * pick_velocity(p->v_max) : 0.0;
    } else {
        for (i = 0; i < n; i++) {
            p->seg_distance[i] = sgn * log_uniform(1e-3, 3.0);
            p->seg_v_end[i] = sgn * pick_velocity(p->v_max);
        }
        if (urand() < 0.6) p->seg_v_end[n - 1] = 0.0;
    }
}

/* 1, 2 or 5 times 10^k, k in [lo, hi] */
static double round_number(int lo, int hi)
{
    static const double m[3] = {1.0, 2.0, 5.0};
    return m[irand(3)] * pow(10.0, lo + irand(hi - lo + 1));
}

static double round_velocity(double vmax)
{
    static const double f[6] = {0.1, 0.2, 0.25, 0.5, 0.75, 1.0};
    return urand() < 0.6 ? 0.0 : f[irand(6)] * vmax;
}

/* The grid the planner's rest-to-rest failures of issue #10 were found on. */
static void grid_params(djl_params *p)
{
    static const double Tes[7] = {1e-4, 2e-4, 2.5e-4, 5e-4, 1e-3, 2e-3, 5e-3};
    int i, n;
    double sgn = urand() < 0.5 ? 1.0 : -1.0;
    djl_params_default(p);
    p->profile = urand() < 0.6 ? DJL_PROFILE_DJL : 1 + irand(2);
    p->short_stage = urand() < 0.5 ? 1 : 2;
    p->Te = Tes[irand(7)];
    p->v_max = round_number(-3, 1);
    p->a_max = round_number(-2, 2);
    p->d_max = urand() < 0.5 ? p->a_max : round_number(-2, 2);
    for (i = 0; i < 4; i++) {
        /* whole multiples of Te: 1..~1000 samples, often a few apart */
        double N = urand() < 0.3 && i > 0 ? floor(p->T_F[i - 1] / p->Te + 0.5) + irand(5) - 2
                                          : floor(log_uniform(1.0, 1000.0));
        if (N < 1.0) N = 1.0;
        p->T_F[i] = N * p->Te;
    }
    p->x0 = urand() < 0.5 ? 0.0 : round_number(-2, 1);
    n = urand() < 0.8 ? 0 : 2 + irand(7);
    p->n_segments = n;
    if (n == 0) {
        p->distance = sgn * round_number(-4, 1);
        if (urand() < 0.25) p->v0 = sgn * round_velocity(p->v_max);
        if (urand() < 0.25) p->v_e = sgn * round_velocity(p->v_max);
    } else {
        for (i = 0; i < n; i++) {
            p->seg_distance[i] = sgn * round_number(-4, 1);
            p->seg_v_end[i] = sgn * round_velocity(p->v_max);
        }
        if (urand() < 0.6) p->seg_v_end[n - 1] = 0.0;
    }
}

/* Rescale lengths by L and times by T (the planner's problem is invariant). */
static void rescale(djl_params *p, double L, double T)
{
    int i;
    p->Te *= T;
    for (i = 0; i < 4; i++) p->T_F[i] *= T;
    p->x0 *= L;
    p->distance *= L;
    p->v0 *= L / T;
    p->v_e *= L / T;
    p->v_max *= L / T;
    p->a_max *= L / (T * T);
    p->d_max *= L / (T * T);
    for (i = 0; i < DJL_MAX_SEGMENTS; i++) {
        p->seg_distance[i] *= L;
        p->seg_v_end[i] *= L / T;
    }
}

static void extreme_params(djl_params *p)
{
    int i, n, kind = irand(11);
    if (urand() < 0.5)
        classic_params(p);
    else
        grid_params(p);
    switch (kind) {
    case 0: /* the same problem in other units */
    case 1:
        rescale(p, pow(10.0, -9.0 + 18.0 * urand()), pow(10.0, -6.0 + 12.0 * urand()));
        break;
    case 2: /* tiny acceleration limits (motions of up to and beyond 1e15 samples) */
        if (urand() < 0.7) p->a_max = pow(10.0, -30.0 + 28.0 * urand());
        if (urand() < 0.7) p->d_max = pow(10.0, -30.0 + 28.0 * urand());
        if (urand() < 0.3) rescale(p, pow(10.0, -6.0 + 12.0 * urand()), 1.0);
        break;
    case 3: /* subnormal, tiny, huge distances */
        {
            double D = urand() < 0.3 ? ldexp(floor(log_uniform(1.0, 1e16)), -1074)
                                     : pow(10.0, urand() < 0.5 ? -330.0 + 60.0 * urand()
                                                               : -40.0 + 60.0 * urand());
            double s = p->n_segments ? (p->seg_distance[0] < 0 ? -1.0 : 1.0)
                                     : (p->distance < 0 ? -1.0 : 1.0);
            if (p->n_segments == 0)
                p->distance = s * D;
            else
                for (i = 0; i < p->n_segments; i++)
                    if (urand() < 0.5) p->seg_distance[i] = s * D * (1.0 + urand());
            if (urand() < 0.5) { /* end speeds tiny too, or at rest */
                p->v0 = 0.0;
                p->v_e = 0.0;
                for (i = 0; i < p->n_segments; i++) p->seg_v_end[i] *= D;
            }
        }
        break;
    case 4: /* far from the origin */
        {
            double X = pow(10.0, 250.0 + 50.0 * urand()) * (urand() < 0.5 ? -1.0 : 1.0);
            if (urand() < 0.5) rescale(p, pow(10.0, 280.0 + 19.0 * urand()), 1.0);
            p->x0 = urand() < 0.2 ? (X < 0 ? -1.0 : 1.0) * DJL_MAX_POSITION * (0.5 + urand())
                                  : X;
        }
        break;
    case 5: /* segment sums near DJL_MAX_POSITION */
        n = 1 + irand(DJL_MAX_SEGMENTS);
        {
            double sgn = urand() < 0.5 ? 1.0 : -1.0, tot = 0.0, target;
            p->n_segments = n;
            for (i = 0; i < n; i++) {
                p->seg_distance[i] = sgn * log_uniform(0.1, 10.0);
                p->seg_v_end[i] = sgn * round_velocity(p->v_max);
                tot += fabs(p->seg_distance[i]);
            }
            if (urand() < 0.6) p->seg_v_end[n - 1] = 0.0;
            p->x0 = 0.0;
            target = DJL_MAX_POSITION * (0.3 + 1.0 * urand());
            /* a length scale that brings the sum to the target: times long
             * enough to keep the sample counts in range */
            rescale(p, target / tot, urand() < 0.5 ? 1.0 : 1e6);
            if (urand() < 0.3) p->x0 = sgn * DJL_MAX_POSITION * 0.5 * urand();
        }
        break;
    case 10: /* one limit far above what the motion reaches (v_max 1e300 m/s...) */
        {
            double f = pow(10.0, 300.0 * urand() * urand());
            int which = irand(3);
            if (which == 0) p->v_max = fmin(p->v_max * f, DBL_MAX);
            if (which == 1 || urand() < 0.3) p->a_max = fmin(p->a_max * f, DBL_MAX);
            if (which == 2 || urand() < 0.3) p->d_max = fmin(p->d_max * f, DBL_MAX);
        }
        break;
    case 8: /* lengths of any size a double holds, times from ps to years */
        rescale(p, pow(10.0, -300.0 + 600.0 * urand()), pow(10.0, -12.0 + 20.0 * urand()));
        break;
    case 6: /* jerk times far longer than the stages, up to the longest filter */
        for (i = 0; i < 4; i++)
            if (urand() < 0.6)
                p->T_F[i] = p->Te * floor(log_uniform(1.0, (double)DJL_MAX_FILTER_SAMPLES));
        break;
    case 9:
    default: /* many segments, speeds of all sizes */
        n = 1 + irand(DJL_MAX_SEGMENTS);
        {
            double sgn = urand() < 0.5 ? 1.0 : -1.0;
            p->n_segments = n;
            for (i = 0; i < n; i++) {
                p->seg_distance[i] = sgn * log_uniform(1e-6, 10.0);
                p->seg_v_end[i] = sgn * (urand() < 0.3 ? 0.0 : log_uniform(1e-9, 1.0)) *
                                  p->v_max;
            }
            if (urand() < 0.5) p->seg_v_end[n - 1] = 0.0;
            p->v0 = urand() < 0.3 ? sgn * urand() * p->v_max : 0.0;
        }
        rescale(p, pow(10.0, -9.0 + 18.0 * urand()), pow(10.0, -3.0 + 6.0 * urand()));
        break;
    }
}

static void spoil(djl_params *p, const char **expect)
{
    switch ((int)(urand() * 10.0)) {
    case 0: p->v_max = urand() < 0.5 ? NAN : -1.0; *expect = "v_max"; break;
    case 1: p->a_max = urand() < 0.5 ? INFINITY : 0.0; *expect = "a_max"; break;
    case 2: p->d_max = -HUGE_VAL; *expect = "d_max"; break;
    case 3: p->Te = urand() < 0.5 ? 0.0 : NAN; *expect = "Te"; break;
    case 4: p->T_F[1] = urand() < 0.5 ? -0.1 : NAN; *expect = "T_F2"; break;
    case 5: p->profile = 7; *expect = "profile"; break;
    case 6: p->n_segments = 40; *expect = "n_segments"; break;
    case 7: p->v0 = 2.0 * p->v_max; *expect = "v0"; break;
    case 8: p->x0 = NAN; *expect = "x0"; break;
    default: p->short_stage = 0; *expect = "short_stage"; break;
    }
}

/* ------------------------------------------------------------------------ */
/* what a plan must satisfy                                                  */

static double total(const djl_params *p)
{
    int i;
    double d = 0.0;
    if (p->n_segments == 0) return p->distance;
    for (i = 0; i < p->n_segments; i++) d += p->seg_distance[i];
    return d;
}

static double total_abs(const djl_params *p)
{
    int i;
    double d = 0.0;
    if (p->n_segments == 0) return fabs(p->distance);
    for (i = 0; i < p->n_segments; i++) d += fabs(p->seg_distance[i]);
    return d;
}

/* All segments one way (a segment of 0 m may move either way: it takes up
 * what the rounding of the segment before it left). */
static int one_direction(const djl_params *p)
{
    int i, pos = 0, neg = 0;
    if (p->n_segments == 0) return 1;
    for (i = 0; i < p->n_segments; i++) {
        pos |= p->seg_distance[i] >= 0.0;
        neg |= p->seg_distance[i] <= 0.0;
    }
    return !(pos && neg);
}

static djl_plan plan; /* large: keep it off the stack */

static int finite_sample(const djl_sample *s)
{
    return isfinite(s->x) && isfinite(s->v) && isfinite(s->a) && isfinite(s->j) &&
           isfinite(s->x_al) && isfinite(s->v_al) && isfinite(s->a_al);
}

/* Limits checked on the pieces themselves (exact: a is linear on a piece, v
 * quadratic with its extremum where a vanishes), continuity from piece to
 * piece, the jerk bound, then the evaluator on the samples either side of
 * every piece boundary and on every sample of a motion up to 5000 samples
 * long (500 spread over a longer one), the end state. */
static void check_plan(long cs, const djl_params *p)
{
    djl_sample s;
    int32_t cur = 0;
    int i, q, Nmin = 0;
    double D = total(p), ve = p->n_segments ? p->seg_v_end[p->n_segments - 1] : p->v_e;
    double sg = D < 0.0 ? -1.0 : 1.0, tol = 1.0 + 1e-12, Te = p->Te;
    double amx = fmax(p->a_max, p->d_max), jmax, xs = fmax(total_abs(p), p->v_max * Te);
    /* limits up to the rounding of the larger one (a_max and d_max may be
     * decades apart) */
    double amax = p->a_max * tol + 1e-12 * amx, dmax = p->d_max * tol + 1e-12 * amx, vlim;
    int oned = one_direction(p);
    int64_t k, K = plan.k_end;

    for (q = 0; q < 4; q++)
        if (plan.N[q] > 0 && (Nmin == 0 || plan.N[q] < Nmin)) Nmin = plan.N[q];
    /* v_max up to rounding: the jerk of a piece is a sum of ramps that may
     * cancel (a few ulps of a/T_F left), and integrated over a piece of
     * millions of samples that moves v by up to about eps a L */
    {
        double Lmax = 0.0;
        for (i = 0; i + 1 < plan.n_pieces; i++)
            Lmax = fmax(Lmax, (double)(plan.piece[i + 1].k - plan.piece[i].k) * Te);
        vlim = p->v_max * tol + 4.0 * DBL_EPSILON * amx * Lmax;
    }
    /* every stage ramps at (its level)/T_F; where ramps meet (the paper's
     * overlap, ramps 2+3 merged, JL across segments) the jerk is a change of
     * acceleration within the limits over a jerk time */
    jmax = Nmin ? (oned ? p->a_max + p->d_max : 2.0 * amx) / (Nmin * Te) * (1.0 + 1e-9) : 0.0;
    if (!(plan.n_pieces >= 1 && plan.n_pieces <= DJL_MAX_PIECES)) {
        FAIL("case %ld: %d pieces", cs, (int)plan.n_pieces);
        return;
    }
    if (!(K >= 0 && (double)K <= (double)DJL_MAX_MOTION_SAMPLES)) {
        FAIL("case %ld: k_end = %lld", cs, (long long)K);
        return;
    }
    for (i = 0; i < plan.n_pieces; i++) {
        const djl_piece *pc = &plan.piece[i];
        double L, ae, ve_, xe, sx;
        if (!(isfinite(pc->x) && isfinite(pc->v) && isfinite(pc->a) && isfinite(pc->j) &&
              isfinite(pc->x_al) && isfinite(pc->v_al) && isfinite(pc->a_al))) {
            FAIL("case %ld: piece %d not finite (x %g v %g a %g j %g x_al %g v_al %g a_al %g)", cs,
                 i, pc->x, pc->v, pc->a, pc->j, pc->x_al, pc->v_al, pc->a_al);
            return;
        }
        if (i > 0 && pc->k <= plan.piece[i - 1].k) FAIL("case %ld: pieces out of order", cs);
        if (fabs(pc->v) > vlim)
            FAIL("case %ld: piece %d: |v| = %.17g > v_max = %.17g", cs, i, pc->v, p->v_max);
        if (oned ? (sg * pc->a > amax || -sg * pc->a > dmax)
                 : fabs(pc->a) > amx * tol)
            FAIL("case %ld: piece %d: a = %.17g outside [-d_max, a_max] = [%g, %g]", cs, i, pc->a,
                 -p->d_max, p->a_max);
        if (fabs(pc->j) > jmax)
            FAIL("case %ld: piece %d: |j| = %.17g above %.17g (shortest jerk time %d samples)",
                 cs, i, pc->j, jmax, Nmin);
        if (i + 1 == plan.n_pieces) {
            if (pc->k != K || pc->a != 0.0 || pc->j != 0.0)
                FAIL("case %ld: last piece at %lld of %lld, a %g, j %g", cs, (long long)pc->k,
                     (long long)K, pc->a, pc->j);
            break;
        }
        L = (double)(plan.piece[i + 1].k - pc->k) * Te;
        ae = pc->a + L * pc->j;
        ve_ = pc->v + L * (pc->a + 0.5 * L * pc->j);
        xe = pc->x + L * (pc->v + L * (0.5 * pc->a + L * pc->j / 6.0));
        if (pc->j != 0.0) { /* the samples either side of the velocity's extremum */
            sx = -pc->a / pc->j;
            if (sx > 0.0 && sx < L) {
                double s0 = floor(sx / Te) * Te, s1 = s0 + Te;
                if (fabs(pc->v + s0 * (pc->a + 0.5 * s0 * pc->j)) > vlim ||
                    (s1 < L && fabs(pc->v + s1 * (pc->a + 0.5 * s1 * pc->j)) > vlim))
                    FAIL("case %ld: piece %d: |v| peaks above v_max inside the piece", cs, i);
            }
        }
        if (oned ? (sg * ae > amax || -sg * ae > dmax) : fabs(ae) > amx * tol)
            FAIL("case %ld: piece %d: a = %.17g at its end outside the limits", cs, i, ae);
        /* the planner carries the state from piece to piece in closed form
         * and snaps it to the AL level / plateau where no ramp runs (pieces
         * of 1e8 samples and more: rounding grows with their length) */
        if ((Nmin && fabs(ae - plan.piece[i + 1].a) > 1e-8 * amx) || /* AL: steps */
            fabs(ve_ - plan.piece[i + 1].v) > 1e-8 * p->v_max ||
            fabs(xe - plan.piece[i + 1].x) > 1e-9 * xs)
            FAIL("case %ld: piece %d -> %d not continuous: a %.17g/%.17g v %.17g/%.17g "
                 "x %.17g/%.17g", cs, i, i + 1, ae, plan.piece[i + 1].a, ve_,
                 plan.piece[i + 1].v, xe, plan.piece[i + 1].x);
    }
    /* the evaluator: around every boundary and on a sparse grid */
    for (i = 0; i <= plan.n_pieces; i++) {
        int64_t b = i < plan.n_pieces ? plan.piece[i].k : -2, d;
        for (d = -1; d <= 1; d++) {
            k = b + d;
            djl_eval(&plan, (double)k, &cur, &s);
            if (!finite_sample(&s)) {
                FAIL("case %ld: non-finite output at sample %lld", cs, (long long)k);
                return;
            }
            if (fabs(s.v) > vlim)
                FAIL("case %ld: |v| = %.17g > v_max = %.17g", cs, s.v, p->v_max);
            if ((k >= K) != (s.done != 0)) FAIL("case %ld: done flag wrong at %lld", cs,
                                                (long long)k);
        }
    }
    {
        int64_t step = K > 5000 ? K / 500 + 1 : 1; /* short motions: every sample */
        for (k = 0; k <= K; k += step) {
            djl_eval(&plan, (double)k, &cur, &s);
            if (!finite_sample(&s)) {
                FAIL("case %ld: non-finite output at sample %lld", cs, (long long)k);
                return;
            }
            if (fabs(s.v) > vlim)
                FAIL("case %ld: |v| = %.17g > v_max = %.17g", cs, s.v, p->v_max);
            if (oned && (sg * s.a > amax || -sg * s.a > dmax))
                FAIL("case %ld: a = %.17g outside [-d_max, a_max] = [%g, %g]", cs, s.a, -p->d_max,
                     p->a_max);
            if ((k >= K) != (s.done != 0)) FAIL("case %ld: done flag wrong at %lld", cs,
                                                (long long)k);
        }
    }
    djl_eval(&plan, (double)K, &cur, &s);
    if (fabs(s.x - (p->x0 + D)) > 1e-9 * fmax(fabs(D), p->v_max * Te) + 4e-16 * fabs(p->x0))
        FAIL("case %ld: end position %.17g, expected %.17g", cs, s.x, p->x0 + D);
    if (fabs(s.v - ve) > 1e-12 * fmax(p->v_max, 1.0))
        FAIL("case %ld: end velocity %.17g, expected %.17g", cs, s.v, ve);
    if (fabs(s.a) > 1e-12 * fmax(p->a_max, 1.0)) FAIL("case %ld: end acceleration %.17g", cs,
                                                      s.a);
    /* evaluating backwards (cursor moving down) gives the same values */
    {
        djl_sample f, b;
        int32_t c1 = 0, c2 = plan.n_pieces - 1;
        int64_t kk = K / 3;
        djl_eval(&plan, (double)kk, &c1, &f);
        djl_eval(&plan, (double)kk, &c2, &b);
        if (f.x != b.x || f.v != b.v || f.a != b.a)
            FAIL("case %ld: evaluation depends on the cursor", cs);
    }
}

/* Shortest time (s) of a single move from rest to rest at the limits,
 * continuous time: a lower bound of what any plan takes. */
static double rest_to_rest_time(const djl_params *p)
{
    double D = fabs(p->distance), a = p->a_max, d = p->d_max, v = p->v_max;
    double h = fmin(a, d) / (1.0 + fmin(a, d) / fmax(a, d)); /* a d / (a + d) */
    double vt = sqrt(2.0 * D) * sqrt(h);
    if (vt <= v) return vt / a + vt / d;
    return D / v + 0.5 * v / a + 0.5 * v / d;
}

/* The documented limits a plan may run into without either parameter
 * being out of its own domain: a motion of more than DJL_MAX_MOTION_SAMPLES
 * samples (10x margin: the estimate is a bound), a jerk (an acceleration over
 * a jerk time) beyond the range of a double, or near its bottom (about
 * distance / time^3). */
static int beyond_documented_limits(const djl_params *p)
{
    double T = 0.0, Nmin = 0.0;
    int i;
    for (i = 0; i < 4; i++) {
        double N = floor(p->T_F[p->profile == DJL_PROFILE_DJL ? i : 0] / p->Te + 0.5);
        T += p->T_F[i];
        if (p->profile != DJL_PROFILE_AL && (Nmin == 0.0 || N < Nmin)) Nmin = N;
    }
    if (Nmin > 0.0 && fmax(p->a_max, p->d_max) / (Nmin * p->Te) > 0.5 * DBL_MAX) return 1;
    /* a jerk near the bottom of the normal doubles (the plan would lose digits) */
    T += rest_to_rest_time(p);
    if (fabs(p->distance) / T / T / T < ldexp(DBL_MIN, 60)) return 1;
    return T / p->Te > 1e14;
}

/* Found by fuzz_plan (issue 21; tests/fuzz/corpus/plan/crash_issue21_*), every run: each
 * was an internal error. */
/* Issue 21, third session (fuzz_plan): rest-to-rest moves whose least duration is the
 * horizon, 10^15 samples (100 m with a_max = 2e-22 m/s^2, d_max = 10 m/s^2, Te = 1 ms, was
 * an internal error).  Around the distance D* at which accelerating at a_max and
 * decelerating at d_max take exactly 10^15 samples, T = sqrt(2 D (1/a + 1/d)), every move
 * is planned (and checked) or refused as infeasible naming a_max or d_max (or Te: the
 * ramps that end the motion past the horizon), never an internal error; 4e-9 below D* it
 * is planned, 4e-9 above it refused. */
static void horizon_sweep(void)
{
    static const double lim[3][2] = {{2e-22, 10.0}, {10.0, 2e-22}, {1e-20, 1e-20}};
    djl_params p;
    djl_error e;
    djl_status st;
    long planned = 0, refused = 0;
    int prof, ss, sgn, l, k;
    for (prof = 1; prof <= 3; prof++)
        for (ss = 1; ss <= 2; ss++)
            for (sgn = -1; sgn <= 1; sgn += 2)
                for (l = 0; l < 3; l++)
                    for (k = -400; k <= 400; k += (k > -20 && k < 20) ? 1 : 10) {
                        double a = lim[l][0], d = lim[l][1], T = 1e15 * 1e-3;
                        double Dstar = T * T / (2.0 * (1.0 / a + 1.0 / d));
                        djl_params_default(&p);
                        p.profile = prof;
                        p.short_stage = ss;
                        p.v_max = 100.0;
                        p.a_max = a;
                        p.d_max = d;
                        p.distance = sgn * Dstar * (1.0 + k * 1e-11);
                        st = djl_plan_motion(&p, &plan, &e);
                        if (st == DJL_OK) {
                            planned++;
                            check_plan(-1, &p);
                        } else if (st == DJL_E_INFEASIBLE && (strcmp(e.param, "a_max") == 0 ||
                                                              strcmp(e.param, "d_max") == 0 ||
                                                              strcmp(e.param, "Te") == 0)) {
                            refused++;
                        } else {
                            FAIL("horizon sweep (profile %d, short_stage %d, distance %.17g, "
                                 "a_max %g, d_max %g): %s %s: %s", prof, ss, p.distance, a, d,
                                 djl_status_name(st), e.param, e.message);
                        }
                        if ((k == -400 && st != DJL_OK) || (k == 400 && st == DJL_OK))
                            FAIL("horizon sweep: distance %.17g (D* (1 %+g)), profile %d: %s",
                                 p.distance, k * 1e-11, prof, st == DJL_OK ? "planned" : e.message);
                    }
    printf("test_core: horizon sweep: %ld planned, %ld refused as infeasible\n", planned,
           refused);
}

/* The motion of fuzz_plan's DBL_MIN findings (issue 21, third and fourth sessions): JL,
 * a_max = d_max = DBL_MIN, Te = 1e-9 s, v0 = DBL_MIN, two segments of DBL_MIN metres (then
 * seven empty ones); T_F2 = DBL_MIN as the fuzzer drew it (JL uses T_F1 alone). */
static void dbl_min_params(djl_params *p)
{
    int i;
    djl_params_default(p);
    p->profile = DJL_PROFILE_JL;
    p->short_stage = DJL_SHORT_OVERLAP;
    p->Te = 1.0000000000000001e-09;
    p->x0 = 0.1;
    p->v0 = DBL_MIN;
    p->v_max = 0.1;
    p->a_max = p->d_max = DBL_MIN;
    p->T_F[1] = DBL_MIN;
    p->n_segments = 9;
    for (i = 0; i < 9; i++) p->seg_distance[i] = p->seg_v_end[i] = 0.0;
    p->seg_distance[0] = p->seg_distance[1] = DBL_MIN;
}

static void issue21_cases(void)
{
    djl_params p;
    djl_error e;
    djl_status st;
    int i;
    /* 17 segments, the last 0.05 m to 6e11 m/s (AL, Te = 0.05 s): its rounding residual,
     * half a sample of travel at 6e11 m/s, is taken up by an earlier segment (documented);
     * the axis goes through -1.5e10 m, and the self-check compared the landing's rounding
     * with the distances only */
    djl_params_default(&p);
    p.profile = DJL_PROFILE_AL;
    p.Te = 0.05;
    p.x0 = p.v0 = 0.05;
    p.v_max = p.a_max = 869626356546304.38;
    p.d_max = 1.0;
    p.n_segments = 17;
    for (i = 0; i < 17; i++) p.seg_distance[i] = i < 9 ? 1.19 : 0.05;
    p.seg_distance[10] = 0.0;
    p.seg_distance[14] = -0.11;
    p.seg_v_end[16] = 6e11;
    if ((st = djl_plan_motion(&p, &plan, &e)) != DJL_OK)
        FAIL("issue 21, 6e11 m/s at the end: %s: %s", djl_status_name(st), e.message);
    else
        check_plan(-1, &p);
    /* an empty last segment handed a residual of 4e-4 m that a_max = 7e-307 m/s^2 cannot
     * cover in a plan's samples: infeasible, naming a_max */
    djl_params_default(&p);
    p.profile = DJL_PROFILE_DJL;
    p.short_stage = DJL_SHORT_OVERLAP;
    p.v0 = 1.0;
    p.v_max = 1.0;
    p.a_max = 7.0663478397123231e-307;
    p.d_max = 10.0;
    p.T_F[2] = 0.218;
    p.T_F[3] = 0.05;
    p.n_segments = 4;
    p.seg_distance[0] = p.seg_distance[1] = 0.999;
    p.seg_v_end[0] = p.seg_v_end[1] = 0.999;
    p.seg_distance[2] = 0.61;
    st = djl_plan_motion(&p, &plan, &e);
    if (st != DJL_E_INFEASIBLE || strcmp(e.param, "a_max") != 0 || !strstr(e.message, "passes on"))
        FAIL("issue 21, residual into an empty segment: %s %s: %s", djl_status_name(st), e.param,
             e.message);
    /* 1e15 m from 0.5 m/s with a_max = 1e-300 m/s^2: 2e18 samples, refused (the bound of
     * the duration rounded the peak to 0.5 m/s and counted 0) */
    djl_params_default(&p);
    p.short_stage = DJL_SHORT_OVERLAP;
    p.v0 = 0.5;
    p.v_max = 6e11;
    p.a_max = 1e-300;
    p.distance = 1e15;
    st = djl_plan_motion(&p, &plan, &e);
    if (st != DJL_E_INFEASIBLE || strcmp(e.param, "a_max") != 0 || !strstr(e.message, "2e+18"))
        FAIL("issue 21, 1e15 m at a_max = 1e-300: %s %s: %s", djl_status_name(st), e.param,
             e.message);
    horizon_sweep();
    /* a_max = d_max = DBL_MIN, Te = 1e-9 s, JL with DBL_MIN segments (fuzz_plan, third
     * session): the jerk of a sample is subnormal and a level came out 8e-8 above a_max;
     * such a plan is made again in scaled units */
    dbl_min_params(&p);
    st = djl_plan_motion(&p, &plan, &e);
    if (st == DJL_OK) {
        for (i = 0; i < plan.n_pieces; i++)
            if (fabs(plan.piece[i].a) > p.a_max * (1.0 + 1e-12))
                FAIL("issue 21, a_max = DBL_MIN: piece %d: |a| = %.17g above a_max %.17g", i,
                     fabs(plan.piece[i].a), p.a_max);
        check_plan(-1, &p);
    } else if (st != DJL_E_INFEASIBLE) {
        FAIL("issue 21, a_max = DBL_MIN: %s: %s", djl_status_name(st), e.message);
    }
}

/* The cases of issue #10 item 6, every run. */
static void issue_cases(void)
{
    djl_params p;
    djl_error e;
    djl_status st;
    int i, sgn;
    for (sgn = -1; sgn <= 1; sgn += 2) { /* rest-to-rest, the rounding missed it */
        djl_params_default(&p);
        p.short_stage = DJL_SHORT_OVERLAP;
        p.v_max = 0.002;
        p.a_max = p.d_max = 1.0;
        p.T_F[0] = 0.512;
        p.T_F[1] = 0.511;
        p.T_F[2] = 0.121;
        p.T_F[3] = 0.007;
        p.distance = sgn * 0.02;
        if ((st = djl_plan_motion(&p, &plan, &e)) != DJL_OK)
            FAIL("issue case 1 (distance %g): %s", p.distance, e.message);
        else
            check_plan(-1, &p);
    }
    djl_params_default(&p); /* more samples than a plan holds */
    p.a_max = 1e-26;
    p.distance = 1.0;
    st = djl_plan_motion(&p, &plan, &e);
    if (st != DJL_E_INFEASIBLE || strcmp(e.param, "a_max") != 0)
        FAIL("issue case 2: %s %s: %s", djl_status_name(st), e.param, e.message);
    p.distance = 1e-12; /* the same a_max plans a short enough move */
    if ((st = djl_plan_motion(&p, &plan, &e)) != DJL_OK)
        FAIL("issue case 2 (1e-12 m): %s", e.message);
    else
        check_plan(-1, &p);
    djl_params_default(&p); /* subnormal distance */
    p.distance = 4e-320;
    st = djl_plan_motion(&p, &plan, &e);
    if (st != DJL_E_PARAM || strcmp(e.param, "distance") != 0)
        FAIL("issue case 3: %s %s: %s", djl_status_name(st), e.param, e.message);
    djl_params_default(&p); /* positions beyond a double's comfort */
    p.n_segments = DJL_MAX_SEGMENTS;
    for (i = 0; i < DJL_MAX_SEGMENTS; i++) p.seg_distance[i] = 1e307;
    st = djl_plan_motion(&p, &plan, &e);
    if (st != DJL_E_PARAM || strcmp(e.param, "seg_distance[1]") != 0 || !strstr(e.message, "span"))
        FAIL("issue case 4: %s %s: %s", djl_status_name(st), e.param, e.message);
    p.v_max = 1e290; /* (not too many samples at v_max) */
    for (i = 0; i < DJL_MAX_SEGMENTS; i++) p.seg_distance[i] = 0.9e299; /* the 12th exceeds */
    st = djl_plan_motion(&p, &plan, &e);
    if (st != DJL_E_PARAM || strcmp(e.param, "seg_distance[12]") != 0)
        FAIL("issue case 4 (sum): %s %s: %s", djl_status_name(st), e.param, e.message);
    p.n_segments = 0;
    p.x0 = -2e300;
    st = djl_plan_motion(&p, &plan, &e);
    if (st != DJL_E_PARAM || strcmp(e.param, "x0") != 0)
        FAIL("issue case 4 (x0): %s %s: %s", djl_status_name(st), e.param, e.message);
    issue21_cases();
}

/* The parameters of a failing case, to reproduce it. */
static void dump_params(long cs, const djl_params *p)
{
    int i, n = p->n_segments > 0 && p->n_segments <= DJL_MAX_SEGMENTS ? p->n_segments : 0;
    fprintf(stderr, "  case %ld: profile %d short_stage %d Te %.17g x0 %.17g v0 %.17g distance "
            "%.17g v_e %.17g v_max %.17g a_max %.17g d_max %.17g T_F %.17g %.17g %.17g %.17g "
            "n_segments %d\n", cs, (int)p->profile, (int)p->short_stage, p->Te, p->x0, p->v0,
            p->distance, p->v_e, p->v_max, p->a_max, p->d_max, p->T_F[0], p->T_F[1], p->T_F[2],
            p->T_F[3], (int)p->n_segments);
    for (i = 0; i < n; i++)
        fprintf(stderr, "    seg %d: %.17g m to %.17g m/s\n", i + 1, p->seg_distance[i],
                p->seg_v_end[i]);
}

int main(int argc, char **argv)
{
    long cases = argc > 1 ? atol(argv[1]) : 20000, i, ok = 0, refused = 0, invalid = 0;
    const char *mode = argc > 3 ? argv[3] : "all";
    int fam_fixed = !strcmp(mode, "classic") ? 0 : !strcmp(mode, "grid") ? 1
                  : !strcmp(mode, "extreme") ? 2 : !strcmp(mode, "all") ? -1 : -2;
    long per_family[3][4];
    djl_params p;
    djl_error e;
    if (fam_fixed == -2) {
        fprintf(stderr, "usage: test_core [cases] [seed] [classic|grid|extreme|all]\n");
        return 2;
    }
    memset(per_family, 0, sizeof per_family);
    if (argc > 2) /* mix the seed: xorshift needs a non-zero state */
        rng_state ^= strtoull(argv[2], NULL, 10) * 0x9E3779B97F4A7C15ULL;
    if (rng_state == 0) rng_state = 88172645463325252ULL;
    issue_cases();
    for (i = 0; i < cases; i++) {
        const char *expect = NULL;
        djl_status st;
        int failures_before = failures;
        int fam = fam_fixed >= 0 ? fam_fixed : irand(3);
        if (fam == 0)
            classic_params(&p);
        else if (fam == 1)
            grid_params(&p);
        else
            extreme_params(&p);
        if (urand() < 0.1) spoil(&p, &expect);
        st = djl_plan_motion(&p, &plan, &e);
        per_family[fam][st < 4 ? st : 3]++;
        if (st == DJL_OK) {
            if (expect) FAIL("case %ld: invalid %s accepted", i, expect);
            ok++;
            check_plan(i, &p);
        } else if (st == DJL_E_PARAM) {
            invalid++;
            if (!e.param[0] || !strstr(e.message, e.param))
                FAIL("case %ld: message does not name the parameter: %s", i, e.message);
        } else if (st == DJL_E_INFEASIBLE) {
            refused++;
            if (expect) FAIL("case %ld: invalid %s reported as infeasible: %s", i, expect,
                             e.message);
            /* always feasible: a single move from rest to rest (within the
             * documented limits), and a single move long enough to reach v_max
             * and come back, with room for the jerk times and, at a non-zero end
             * speed, for a speed dip worth one sample of travel at v_max (area
             * a*T^2/4 in a time T) */
            if (p.n_segments == 0 && p.v0 == 0.0 && p.v_e == 0.0 &&
                !beyond_documented_limits(&p))
                FAIL("case %ld: rest-to-rest move refused: %s", i, e.message);
            if (p.n_segments == 0 && !beyond_documented_limits(&p)) {
                double vm = p.v_max, room = 4.0 * p.Te, dip = 0.0;
                int k;
                for (k = 0; k < 4; k++) room += p.T_F[k];
                if (p.v_e != 0.0) dip = 2.0 * vm * sqrt(vm / fmin(p.a_max, p.d_max)) * sqrt(p.Te);
                /* (written so that no square of a tiny speed underflows) */
                if (fabs(p.distance) >=
                    2.0 * ((vm - fabs(p.v0)) / p.a_max * (0.5 * (vm + fabs(p.v0))) +
                           (vm - fabs(p.v_e)) / p.d_max * (0.5 * (vm + fabs(p.v_e)))) +
                        2.0 * vm * room + 2.0 * dip)
                    FAIL("case %ld: long single move refused: %s", i, e.message);
            }
            /* the distance from which the message says every distance lands */
            if (strstr(e.message, "every distance lands")) {
                const char *q = strstr(e.message, "and from about ");
                if (!q || fabs(p.n_segments ? p.seg_distance[p.n_segments - 1] : p.distance) >=
                              atof(q + strlen("and from about ")))
                    FAIL("case %ld: refused a distance its message says lands: %s", i, e.message);
            }
            if (!e.param[0] || !strstr(e.message, e.param))
                FAIL("case %ld: message does not name the parameter: %s", i, e.message);
        } else {
            FAIL("case %ld: %s: %s", i, djl_status_name(st), e.message);
        }
        if (st != DJL_OK && strlen(e.message) + 1 >= sizeof e.message)
            FAIL("case %ld: message truncated: %s", i, e.message);
        if (failures > failures_before) dump_params(i, &p);
        if (failures > 20) break;
    }
    if (fam_fixed < 0) {
        static const char *names[3] = {"classic", "grid", "extreme"};
        int f;
        for (f = 0; f < 3; f++)
            printf("  %-8s %ld planned, %ld infeasible, %ld invalid, %ld internal\n", names[f],
                   per_family[f][0], per_family[f][2], per_family[f][1], per_family[f][3]);
    }
    printf("core (%s): %ld cases, %ld planned and checked, %ld infeasible, %ld invalid, "
           "%d failures\n", mode, cases, ok, refused, invalid, failures);
    return failures ? 1 : 0;
}
