/*
 * bench_replan.c -- cost of one replan (djl_replan, issue #12: <= 5 us).
 *
 * For the default DJL move (0.4 m, v_max 1 m/s, a_max = d_max = 10 m/s2, jerk
 * times 80/80/60/50 ms at Te = 1 ms) and for a JL move, commands at 9 points of
 * the motion (during acceleration, cruise and deceleration): a new target ahead
 * (farther), a target behind (the axis stops and comes back), a stop, and new
 * jerk times (the f_mode replan of the same target).  Each situation is replanned
 * `count` times in a row; prints one line per situation: its name, the median over
 * `repeats` runs of the seconds per replan, and how the replan went (1 new move
 * after the stage, 2 stop then move, 3 stop).
 *
 * Usage: bench_replan [count] [repeats]
 */
#define _POSIX_C_SOURCE 199309L /* clock_gettime under -std=c99 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "djl_core.h"

static djl_plan plan, out, scratch; /* large: off the stack */

static double now(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

static int cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

int main(int argc, char **argv)
{
    long count = argc > 1 ? atol(argv[1]) : 20000, k;
    int repeats = argc > 2 ? atoi(argv[2]) : 7, profile, q, kind, r, i;
    static const char *const kinds[] = {"target ahead", "target behind", "stop", "jerk times"};
    for (profile = 2; profile <= 3; profile++) {
        djl_params p;
        djl_error e;
        djl_params_default(&p);
        p.profile = profile;
        if (djl_plan_motion(&p, &plan, &e) != DJL_OK) return 1;
        for (q = 1; q <= 9; q++) {
            double u = 0.1 * q * (double)plan.k_end + 0.5;
            for (kind = 0; kind < 4; kind++) {
                djl_goal g;
                djl_replan_info info;
                double t[32];
                memset(&g, 0, sizeof g);
                g.kind = kind == 2 ? DJL_GOAL_STOP : DJL_GOAL_TARGET;
                g.target = kind == 0 ? 0.8 : kind == 1 ? 0.05 : p.distance;
                for (i = 0; i < 4; i++) g.N[i] = plan.N[i] + (kind == 3 ? 7 : 0);
                for (r = 0; r < repeats && r < 32; r++) {
                    double t0 = now();
                    for (k = 0; k < count; k++)
                        if (djl_replan(&plan, u, &g, &out, &scratch, &info, &e) != DJL_OK) {
                            fprintf(stderr, "replan failed: %s\n", e.message);
                            return 1;
                        }
                    t[r] = (now() - t0) / (double)count;
                }
                qsort(t, (size_t)r, sizeof t[0], cmp);
                printf("%s %d%% %s %.9e %d\n", profile == 2 ? "JL" : "DJL", 10 * q,
                       kinds[kind], t[r / 2], (int)info.how);
            }
        }
    }
    return 0;
}
