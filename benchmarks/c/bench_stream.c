/*
 * bench_stream.c -- cost of producing every sample with the generator core,
 * as a controller calling it once per sampling period would.
 * Usage: bench_stream T_F Te distance repeats  -> prints one line per repeat:
 *   samples seconds checksum
 */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "djl_core.h"

static djl_plan plan;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int main(int argc, char **argv)
{
    djl_params p;
    djl_error e;
    int r, repeats;
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
