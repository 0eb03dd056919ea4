/*
 * bench_stream.c -- cost of producing every sample with the generator core,
 * as a controller calling it once per sampling period would.
 * Usage: bench_stream T_F Te distance repeats  -> prints one line per repeat:
 *   samples seconds checksum
 *        bench_stream plan profile distance count  -> seconds per plan (median of 7)
 */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "djl_core.h"

static djl_plan plan;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Planning cost: the default move (profile, distance), planned count times. */
static int bench_plan(int profile, double distance, long count)
{
    djl_params p;
    djl_error e;
    double t[7];
    int r;
    long i;
    djl_params_default(&p);
    p.profile = profile;
    p.distance = distance;
    p.v_max = 0.5;
    p.a_max = p.d_max = 4.0;
    p.T_F[0] = 0.152;
    for (r = 0; r < 7; r++) {
        double t0 = now();
        for (i = 0; i < count; i++) {
            p.distance = distance * (1.0 + 1e-9 * (double)(i & 7)); /* defeat caching */
            if (djl_plan_motion(&p, &plan, &e) != DJL_OK) {
                fprintf(stderr, "%s\n", e.message);
                return 1;
            }
        }
        t[r] = (now() - t0) / (double)count;
    }
    qsort(t, 7, sizeof t[0], cmp);
    printf("%.9g\n", t[3]);
    return 0;
}

int main(int argc, char **argv)
{
    djl_params p;
    djl_error e;
    int r, repeats;
    if (argc == 5 && strcmp(argv[1], "plan") == 0)
        return bench_plan(atoi(argv[2]), atof(argv[3]), atol(argv[4]));
    if (argc < 5) {
        fprintf(stderr, "usage: bench_stream T_F Te distance repeats\n");
        return 2;
    }
    djl_params_default(&p);
    p.profile = DJL_PROFILE_JL;
    p.T_F[0] = atof(argv[1]);
    p.Te = atof(argv[2]);
    p.distance = atof(argv[3]);
    p.v_max = 1.0;
    p.a_max = p.d_max = 2.0;
    repeats = atoi(argv[4]);
    if (djl_plan_motion(&p, &plan, &e) != DJL_OK) {
        fprintf(stderr, "%s\n", e.message);
        return 1;
    }
    for (r = 0; r < repeats; r++) {
        djl_sample s;
        int32_t cur = 0;
        int64_t k;
        double sum = 0.0, t0 = now(), t1;
        for (k = 0; k <= plan.k_end; k++) {
            djl_eval(&plan, (double)k, &cur, &s);
            sum += s.x + s.v + s.a + s.j;
        }
        t1 = now();
        printf("%lld %.9f %.17g\n", (long long)(plan.k_end + 1), t1 - t0, sum);
    }
    return 0;
}
