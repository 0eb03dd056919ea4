/*
 * bench_commands.c -- cost of the DoStep that carries a command, through the FMI 3 API
 * (issue 34): today's aborting execute beside the buffered and blending ones, the steps
 * at which a waiting command starts, and an execute with min_duration.
 *
 * The axis: DJL, 0 -> 0.5 m (v_max 1 m/s, a_max = d_max = 10 m/s2, jerk times
 * 40/40/30/25 ms, Te = 1 ms, h = Te), commands at 150 ms (cruising).  Each situation is
 * an FMU state saved just before its step; a timed run restores it (not timed) and
 * times the one fmi3DoStep, `count` times; prints one line per situation: its name and
 * the median over `repeats` runs of the seconds per DoStep.
 *
 * Usage: bench_commands [count] [repeats]
 */
#define _POSIX_C_SOURCE 199309L /* clock_gettime under -std=c99 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "djl_vars.h"
#include "fmi3Functions.h"

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

static fmi3Instance inst;
static double t_now;
static const double Te = 1e-3;

static void die(const char *what)
{
    fprintf(stderr, "bench_commands: %s failed\n", what);
    exit(1);
}

static void set_r(fmi3ValueReference vr, double v)
{
    if (fmi3SetFloat64(inst, &vr, 1, &v, 1) != fmi3OK) die("fmi3SetFloat64");
}

static void set_i(fmi3ValueReference vr, long long v)
{
    fmi3Int64 x = v;
    if (fmi3SetInt64(inst, &vr, 1, &x, 1) != fmi3OK) die("fmi3SetInt64");
}

static void set_b(fmi3ValueReference vr, int v)
{
    fmi3Boolean x = v ? fmi3True : fmi3False;
    if (fmi3SetBoolean(inst, &vr, 1, &x, 1) != fmi3OK) die("fmi3SetBoolean");
}

static void step(void)
{
    fmi3Boolean ev, term, early;
    fmi3Float64 last;
    if (fmi3DoStep(inst, t_now, Te, fmi3True, &ev, &term, &early, &last) != fmi3OK)
        die("fmi3DoStep");
    t_now += Te;
}

static long long get_i(fmi3ValueReference vr)
{
    fmi3Int32 x = 0;
    if (fmi3GetInt32(inst, &vr, 1, &x, 1) != fmi3OK) die("fmi3GetInt32");
    return x;
}

/* A fresh instance at rest at 0, then an aborting execute to 0.5 m at 2 ms, stepped to
 * 150 ms: cruising. */
static void setup(void)
{
    static const fmi3ValueReference par[] = {VR_PROFILE, VR_DISTANCE, VR_V_MAX, VR_A_MAX,
                                             VR_D_MAX, VR_T_F1, VR_T_F2, VR_T_F3, VR_T_F4};
    static const double val[] = {3, 0.0, 1.0, 10.0, 10.0, 0.04, 0.04, 0.03, 0.025};
    size_t i;
    if (inst) fmi3FreeInstance(inst);
    inst = fmi3InstantiateCoSimulation("bench", DJL_INSTANTIATION_TOKEN, NULL, fmi3False,
                                       fmi3False, fmi3False, fmi3False, NULL, 0, NULL, NULL,
                                       NULL);
    if (!inst) die("fmi3InstantiateCoSimulation");
    if (fmi3EnterInitializationMode(inst, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK)
        die("fmi3EnterInitializationMode");
    for (i = 0; i < sizeof par / sizeof par[0]; i++) {
        if (par[i] == VR_PROFILE) set_i(par[i], (long long)val[i]);
        else set_r(par[i], val[i]);
    }
    if (fmi3ExitInitializationMode(inst) != fmi3OK) die("fmi3ExitInitializationMode");
    t_now = 0.0;
    step();
    step();
    set_r(VR_TARGET, 0.5);
    set_b(VR_EXECUTE, 1);
    step();
    set_b(VR_EXECUTE, 0);
    while (t_now < 0.150 - 0.5 * Te) step();
}

/* The command of a situation set (its edge: execute true), not stepped. */
static void command(int mode, double target, double min_d)
{
    set_i(VR_BUFFER_MODE, mode);
    set_r(VR_MIN_DURATION, min_d);
    set_r(VR_TARGET, target);
    set_b(VR_EXECUTE, 1);
}

/* Step on until the next step starts the waiting command (queue_length falls): that
 * step is the one timed. */
static void until_start(void)
{
    fmi3FMUState s = NULL;
    long long q = get_i(VR_QUEUE_LENGTH);
    double t0;
    int n;
    for (n = 0; n < 100000; n++) {
        t0 = t_now;
        if (fmi3GetFMUState(inst, &s) != fmi3OK) die("fmi3GetFMUState");
        step();
        if (get_i(VR_QUEUE_LENGTH) < q) {
            if (fmi3SetFMUState(inst, s) != fmi3OK) die("fmi3SetFMUState");
            t_now = t0;
            fmi3FreeFMUState(inst, &s);
            return;
        }
        fmi3FreeFMUState(inst, &s);
    }
    die("until_start");
}

static double time_situation(long count, int repeats, int what)
{
    fmi3FMUState s = NULL;
    double *runs = malloc(sizeof(double) * (size_t)repeats), t0, t_saved, med, sum;
    long k;
    int r;
    if (!runs) die("malloc");
    setup();
    switch (what) {
    case 0: break;                                  /* a step, no command */
    case 1: command(0, 0.8, 0.0); break;            /* aborting execute (today's) */
    case 2: command(1, 0.8, 0.0); break;            /* buffered execute: queued */
    case 3: command(1, 0.8, 0.0); step(); set_b(VR_EXECUTE, 0); until_start(); break;
    case 4: command(2, 0.8, 0.0); break;            /* blending execute: the blend planned */
    case 5: command(2, 0.8, 0.0); step(); set_b(VR_EXECUTE, 0); until_start(); break;
    default: command(0, 0.8, 3.0); break;           /* aborting with min_duration */
    }
    t_saved = t_now;
    if (fmi3GetFMUState(inst, &s) != fmi3OK) die("fmi3GetFMUState");
    for (r = 0; r < repeats; r++) {
        sum = 0.0;
        for (k = 0; k < count; k++) {
            if (fmi3SetFMUState(inst, s) != fmi3OK) die("fmi3SetFMUState");
            t_now = t_saved;
            t0 = now();
            step();
            sum += now() - t0;
        }
        runs[r] = sum / (double)count;
    }
    fmi3FreeFMUState(inst, &s);
    qsort(runs, (size_t)repeats, sizeof(double), cmp);
    med = runs[repeats / 2];
    free(runs);
    return med;
}

int main(int argc, char **argv)
{
    static const char *const names[] = {
        "step, no command", "aborting execute (today)", "buffered execute (queued)",
        "buffered command starts", "blending execute (blend planned)",
        "blended command starts", "aborting execute + min_duration"};
    long count = argc > 1 ? atol(argv[1]) : 2000;
    int repeats = argc > 2 ? atoi(argv[2]) : 7, i;
    if (count < 1 || repeats < 1) return 2;
    for (i = 0; i < 7; i++) printf("%s|%.9g\n", names[i], time_situation(count, repeats, i));
    fmi3FreeInstance(inst);
    return 0;
}
