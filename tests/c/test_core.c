/*
 * test_core.c -- the generator core on its own, meant to run under
 * AddressSanitizer + UndefinedBehaviorSanitizer (tests/test_c_sanitizers.py).
 *
 * Random parameter sets (valid and invalid): every plan either succeeds and
 * lands exactly within the limits, or fails with a parameter/feasibility
 * error and a message naming the parameter; never a crash, NaN or hang.
 * Usage: test_core [cases] [seed]
 */
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

static int failures = 0;

#define FAIL(...)                                                                                \
    do {                                                                                         \
        fprintf(stderr, __VA_ARGS__);                                                            \
        fputc('\n', stderr);                                                                     \
        failures++;                                                                              \
    } while (0)

static double pick_velocity(double vmax)
{
    double r = urand();
    return r < 0.4 ? 0.0 : r < 0.55 ? vmax : urand() * vmax;
}

static void random_params(djl_params *p)
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

static double total(const djl_params *p)
{
    int i;
    double d = 0.0;
    if (p->n_segments == 0) return p->distance;
    for (i = 0; i < p->n_segments; i++) d += p->seg_distance[i];
    return d;
}

static int one_direction(const djl_params *p)
{
    int i, pos = 0, neg = 0;
    if (p->n_segments == 0) return 1;
    for (i = 0; i < p->n_segments; i++) {
        pos |= p->seg_distance[i] > 0.0;
        neg |= p->seg_distance[i] < 0.0;
    }
    return !(pos && neg);
}

static djl_plan plan; /* large: keep it off the stack */

static void check_plan(const djl_params *p)
{
    djl_sample s;
    int32_t cur = 0;
    double D = total(p), ve = p->n_segments ? p->seg_v_end[p->n_segments - 1] : p->v_e;
    double sg = D < 0.0 ? -1.0 : 1.0, tol = 1.0 + 1e-12;
    int64_t k, K = plan.k_end, step = K > 200000 ? K / 200000 + 1 : 1;
    for (k = -3; k <= K + 3; k += (k < 0 || k >= K - 2) ? 1 : step) {
        djl_eval(&plan, (double)k, &cur, &s);
        if (!(isfinite(s.x) && isfinite(s.v) && isfinite(s.a) && isfinite(s.j) &&
              isfinite(s.x_al) && isfinite(s.v_al) && isfinite(s.a_al))) {
            FAIL("non-finite output at sample %lld", (long long)k);
            return;
        }
        if (fabs(s.v) > p->v_max * tol) FAIL("|v| = %.17g > v_max = %.17g", s.v, p->v_max);
        if (one_direction(p) && (sg * s.a > p->a_max * tol || -sg * s.a > p->d_max * tol))
            FAIL("a = %.17g outside [-d_max, a_max] = [%g, %g]", s.a, -p->d_max, p->a_max);
        if ((k >= K) != (s.done != 0)) FAIL("done flag wrong at %lld", (long long)k);
    }
    djl_eval(&plan, (double)K, &cur, &s);
    if (fabs(s.x - (p->x0 + D)) > 1e-9 * fmax(fabs(D), p->v_max * p->Te) + 4e-16 * fabs(p->x0))
        FAIL("end position %.17g, expected %.17g", s.x, p->x0 + D);
    if (fabs(s.v - ve) > 1e-12 * fmax(p->v_max, 1.0)) FAIL("end velocity %.17g, expected %.17g",
                                                           s.v, ve);
    if (fabs(s.a) > 1e-12 * fmax(p->a_max, 1.0)) FAIL("end acceleration %.17g", s.a);
    /* evaluating backwards (cursor moving down) gives the same values */
    {
        djl_sample f, b;
        int32_t c1 = 0, c2 = plan.n_pieces - 1;
        int64_t kk = K / 3;
        djl_eval(&plan, (double)kk, &c1, &f);
        djl_eval(&plan, (double)kk, &c2, &b);
        if (f.x != b.x || f.v != b.v || f.a != b.a) FAIL("evaluation depends on the cursor");
    }
}

int main(int argc, char **argv)
{
    long cases = argc > 1 ? atol(argv[1]) : 20000, i, ok = 0, refused = 0, invalid = 0;
    djl_params p;
    djl_error e;
    if (argc > 2) /* mix the seed: xorshift needs a non-zero state */
        rng_state ^= strtoull(argv[2], NULL, 10) * 0x9E3779B97F4A7C15ULL;
    if (rng_state == 0) rng_state = 88172645463325252ULL;
    for (i = 0; i < cases; i++) {
        const char *expect = NULL;
        djl_status st;
        random_params(&p);
        if (urand() < 0.1) spoil(&p, &expect);
        st = djl_plan_motion(&p, &plan, &e);
        if (st == DJL_OK) {
            if (expect) FAIL("case %ld: invalid %s accepted", i, expect);
            ok++;
            check_plan(&p);
        } else if (st == DJL_E_PARAM) {
            invalid++;
            if (!e.param[0] || !strstr(e.message, e.param))
                FAIL("case %ld: message does not name the parameter: %s", i, e.message);
        } else if (st == DJL_E_INFEASIBLE) {
            refused++;
            if (expect) FAIL("case %ld: invalid %s reported as infeasible: %s", i, expect,
                             e.message);
            /* always feasible: a single move from rest to rest, and a single move long
             * enough to reach v_max and come back, with room for the jerk times and, at
             * a non-zero end speed, for a speed dip worth one sample of travel at v_max
             * (area a*T^2/4 in a time T) */
            if (p.n_segments == 0 && p.v0 == 0.0 && p.v_e == 0.0)
                FAIL("case %ld: rest-to-rest move refused: %s", i, e.message);
            if (p.n_segments == 0) {
                double vm = p.v_max, room = 4.0 * p.Te, dip = 0.0;
                int k;
                for (k = 0; k < 4; k++) room += p.T_F[k];
                if (p.v_e != 0.0) dip = 2.0 * vm * sqrt(vm * p.Te / fmin(p.a_max, p.d_max));
                if (fabs(p.distance) >= 2.0 * ((vm * vm - p.v0 * p.v0) / (2.0 * p.a_max) +
                                               (vm * vm - p.v_e * p.v_e) / (2.0 * p.d_max)) +
                                            2.0 * vm * room + 2.0 * dip)
                    FAIL("case %ld: long single move refused: %s", i, e.message);
            }
            if (strlen(e.message) + 1 >= sizeof e.message)
                FAIL("case %ld: message truncated: %s", i, e.message);
            /* the distance from which the message says every distance lands */
            if (strstr(e.message, "every distance lands")) {
                const char *q = strstr(e.message, "and from about ");
                if (!q || fabs(p.n_segments ? p.seg_distance[p.n_segments - 1] : p.distance) >=
                              atof(q + strlen("and from about ")))
                    FAIL("case %ld: refused a distance its message says lands: %s", i, e.message);
            }
            if (!strstr(e.message, e.param)) FAIL("case %ld: %s", i, e.message);
        } else {
            FAIL("case %ld: %s: %s", i, djl_status_name(st), e.message);
        }
        if (failures > 20) break;
    }
    printf("core: %ld cases, %ld planned and checked, %ld infeasible, %ld invalid, %d failures\n",
           cases, ok, refused, invalid, failures);
    return failures ? 1 : 0;
}
