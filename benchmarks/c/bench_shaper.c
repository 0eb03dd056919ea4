/*
 * bench_shaper.c -- cost of a shaped step against an unshaped one, through the FMI 2 API as
 * an importer calls it (fmi2DoStep of Te, then fmi2GetReal of x, v, a, j), and of the core's
 * evaluation alone (djl_eval against djl_shaper_eval).  docs/generator.md, "Input shaping".
 *
 *   gcc -std=c99 -O2 -Ifmu_src -I<fmpy>/c-code benchmarks/c/bench_shaper.c fmu_src/fmi2.c \
 *       fmu_src/fmu_*.c fmu_src/djl_*.c -lm -o /tmp/bench_shaper
 *   /tmp/bench_shaper            -> one line per configuration: ns per step (median of 7 runs)
 */
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "djl_core.h"
#include "djl_vars.h"
#include "fmi2Functions.h"

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

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    (void)name;
    (void)category;
    if (status >= fmi2Error) fprintf(stderr, "%s\n", message);
}
static const fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};

typedef struct {
    const char *name;
    int kind, source, n, replan, fchange;
    double f, zeta, A[8], d[8];
} config;

static void set_r(fmi2Component c, fmi2ValueReference vr, double v) { fmi2SetReal(c, &vr, 1, &v); }
static void set_i(fmi2Component c, fmi2ValueReference vr, int v)
{
    fmi2Integer i = v;
    fmi2SetInteger(c, &vr, 1, &i);
}

/* ns per step (DoStep + GetReal of x, v, a, j) over a 2 s DJL move, median of 7 */
static double bench(const config *cf)
{
    const double Te = 1e-3;
    const int steps = 2000;
    double t[7], out[4];
    fmi2ValueReference vr[4] = {VR_X, VR_V, VR_A, VR_J}, vb = VR_EXECUTE;
    int r, k, i;
    for (r = 0; r < 7; r++) {
        fmi2Component c = fmi2Instantiate("b", fmi2CoSimulation, DJL_INSTANTIATION_TOKEN,
                                          "file:///tmp", &cb, fmi2False, fmi2False);
        double t0, tt = 0.0;
        fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
        fmi2EnterInitializationMode(c);
        set_r(c, VR_DISTANCE, 0.8);
        set_r(c, VR_V_MAX, 0.5);
        set_i(c, VR_SHAPER, cf->kind);
        set_i(c, VR_SHAPER_SOURCE, cf->source);
        set_r(c, VR_F_SHAPER, cf->f);
        set_r(c, VR_ZETA_SHAPER, cf->zeta);
        set_i(c, VR_SHAPER_N, cf->n);
        for (i = 0; i < 8; i++) {
            set_r(c, VR_SHAPER_AMPLITUDE + (unsigned)i, cf->A[i]);
            set_r(c, VR_SHAPER_DELAY + (unsigned)i, cf->d[i]);
        }
        if (fmi2ExitInitializationMode(c) != fmi2OK) exit(1);
        if (cf->replan) { /* a new target early: from then on, the copies read the past */
            fmi2Boolean one = fmi2True;
            for (k = 0; k < 100; k++, tt += Te) fmi2DoStep(c, tt, Te, fmi2True);
            set_r(c, VR_TARGET, 0.7);
            fmi2SetBoolean(c, &vb, 1, &one);
        }
        t0 = now();
        for (k = 0; k < steps; k++, tt += Te) {
            if (cf->fchange) set_r(c, VR_F_MODE, 8.0 + 1e-3 * (k & 255));
            fmi2DoStep(c, tt, Te, fmi2True);
            fmi2GetReal(c, vr, 4, out);
        }
        t[r] = (now() - t0) / steps * 1e9;
        fmi2FreeInstance(c);
    }
    qsort(t, 7, sizeof t[0], cmp);
    return t[3];
}

/* ns per sample of the core's evaluation alone, median of 7 */
static djl_plan plan;
static double bench_core(int kind)
{
    djl_params p;
    djl_shaper_params sp;
    djl_shaper sh;
    djl_error e;
    double t[7], sum = 0.0;
    int r;
    djl_params_default(&p);
    djl_shaper_params_default(&sp);
    p.distance = 0.8;
    p.v_max = 0.5;
    sp.kind = kind;
    sp.f = 7.3;
    if (djl_plan_motion(&p, &plan, &e) != DJL_OK ||
        djl_shaper_design(&sp, p.Te, 0.0, &sh, &e) != DJL_OK)
        exit(1);
    for (r = 0; r < 7; r++) {
        int32_t cur = 0, cs[8] = {0};
        int64_t k;
        djl_sample s;
        double t0 = now();
        for (k = 0; k <= plan.k_end; k++) {
            if (kind == 0)
                djl_eval(&plan, (double)k, &cur, &s);
            else
                djl_shaper_eval(&sh, &plan, (double)k, 0.0, NULL, 0, &cur, cs, &s);
            sum += s.x + s.j;
        }
        t[r] = (now() - t0) / (double)(plan.k_end + 1) * 1e9;
    }
    qsort(t, 7, sizeof t[0], cmp);
    if (sum == 42.0) printf(" ");
    return t[3];
}

int main(void)
{
    static const config cfs[] = {
        {"no shaper", 0, 1, 1, 0, 0, 10.0, 0.0, {0}, {0}},
        {"ZV, 7.3 Hz", 1, 1, 1, 0, 0, 7.3, 0.05, {0}, {0}},
        {"ZVD, 7.3 Hz", 2, 1, 1, 0, 0, 7.3, 0.05, {0}, {0}},
        {"EI, 7.3 Hz", 3, 1, 1, 0, 0, 7.3, 0.05, {0}, {0}},
        {"custom, 8 impulses", 4, 1, 8, 0, 0, 7.3, 0.0,
         {0.2, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, 0.2},
         {0.0, 0.011, 0.022, 0.033, 0.044, 0.055, 0.066, 0.077}},
        {"no shaper, after a replan", 0, 1, 1, 1, 0, 10.0, 0.0, {0}, {0}},
        {"ZVD, after a replan (copies read the past)", 2, 1, 1, 1, 0, 7.3, 0.05, {0}, {0}},
        {"ZVD by f_mode, f_mode set every step", 2, 2, 1, 0, 1, 7.3, 0.05, {0}, {0}},
        {"ZVD by f_mode, after a replan", 2, 2, 1, 1, 1, 7.3, 0.05, {0}, {0}},
    };
    size_t i;
    printf("FMI 2 step (fmi2DoStep of Te + fmi2GetReal of x, v, a, j), ns, median of 7:\n");
    for (i = 0; i < sizeof cfs / sizeof cfs[0]; i++)
        printf("  %-44s %8.1f\n", cfs[i].name, bench(&cfs[i]));
    printf("core evaluation of one sample, ns, median of 7:\n");
    printf("  %-44s %8.1f\n", "djl_eval", bench_core(0));
    printf("  %-44s %8.1f\n", "djl_shaper_eval, ZV", bench_core(1));
    printf("  %-44s %8.1f\n", "djl_shaper_eval, ZVD", bench_core(2));
    return 0;
}
