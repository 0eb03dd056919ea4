/*
 * test_plan_libm.c -- the planner makes the same plans, bit for bit, with the
 * math of fmu_src/djl_math.h (the FMU's, no libm) as with libm's.
 *
 * Linked with fmu_src/djl_*.c and tests/c/core_libm.c (the same core
 * compiled with -DDJL_USE_LIBM, its functions renamed libm_djl_*).  For each
 * random parameter set of test_core.c's families (classic, grid, extreme:
 * the same generators, included from there, 10 % of the sets spoiled), both
 * plan it: the status, the error (parameter, value, message) and the whole
 * djl_plan must be the same bytes.  The planner's hypot and exp2 are the two
 * functions that are not exactly libm's: this says it does not depend on
 * their last bit where they differ.
 *
 * Usage: test_plan_libm [cases] [seed] [classic|grid|extreme|all]
 */
#define main test_core_main /* test_core.c: only its parameter families */
#include "test_core.c"
#undef main

djl_status libm_djl_plan_motion(const djl_params *p, djl_plan *plan, djl_error *err);

static djl_plan plan_own, plan_libm; /* large: off the stack */

int main(int argc, char **argv)
{
    long cases = argc > 1 ? atol(argv[1]) : 20000, i, counts[3][4], differ = 0;
    const char *mode = argc > 3 ? argv[3] : "all";
    int fam_fixed = !strcmp(mode, "classic") ? 0 : !strcmp(mode, "grid") ? 1
                  : !strcmp(mode, "extreme") ? 2 : !strcmp(mode, "all") ? -1 : -2;
    static const char *names[3] = {"classic", "grid", "extreme"};
    int f;
    if (fam_fixed == -2) {
        fprintf(stderr, "usage: test_plan_libm [cases] [seed] [classic|grid|extreme|all]\n");
        return 2;
    }
    memset(counts, 0, sizeof counts);
    if (argc > 2) rng_state ^= strtoull(argv[2], NULL, 10) * 0x9E3779B97F4A7C15ULL;
    if (rng_state == 0) rng_state = 88172645463325252ULL;
    for (i = 0; i < cases; i++) {
        djl_params p;
        djl_error e1, e2;
        djl_status s1, s2;
        const char *expect = NULL;
        int fam = fam_fixed >= 0 ? fam_fixed : irand(3);
        if (fam == 0)
            classic_params(&p);
        else if (fam == 1)
            grid_params(&p);
        else
            extreme_params(&p);
        if (urand() < 0.1) spoil(&p, &expect);
        s1 = djl_plan_motion(&p, &plan_own, &e1);
        s2 = libm_djl_plan_motion(&p, &plan_libm, &e2);
        counts[fam][s1 < 4 ? s1 : 3]++;
        if (s1 != s2 || memcmp(&e1, &e2, sizeof e1) != 0 ||
            memcmp(&plan_own, &plan_libm, sizeof plan_own) != 0) {
            differ++;
            failures++;
            fprintf(stderr, "case %ld: the plans differ (status %d / %d): %s | %s\n", i, (int)s1,
                    (int)s2, e1.message, e2.message);
            dump_params(i, &p);
            if (differ > 20) break;
        }
    }
    for (f = 0; f < 3; f++)
        printf("  %-8s %ld planned, %ld infeasible, %ld invalid, %ld internal\n", names[f],
               counts[f][0], counts[f][2], counts[f][1], counts[f][3]);
    printf("plans with djl_math.h and with libm (%s): %ld cases, %ld differ, %d failures\n", mode,
           cases, differ, failures);
    return failures ? 1 : 0;
}
