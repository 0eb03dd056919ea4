/*
 * test_time.c -- communication points and steps, through the FMI 2 layer (issue #10,
 * items 1 and 2).
 *
 *  - Masters that compute the next communication point as t += h (floating point, the
 *    standard's t(i+1) = t(i) + h(i)) or as start + i h run to the end, from start times
 *    0 and 1.7e9 s, with h = 1 ms and 0.1 ms (Te = 1 ms): `steps` doSteps each.
 *  - Along the way every whole-sample point is compared bit for bit with a reference
 *    instance stepped by Te from start time 0 (while the motion runs), and the final
 *    position is the target.
 *  - A communication point off by a visible fraction of a step (5 %, 50 %) is refused
 *    with "a step must start where the previous one ended", at every start time.
 *  - Steps that are not whole samples (h = 0.37 Te, 2.5 Te, Te/3, random): the outputs at
 *    each point are those of the profile at that time, checked against a Taylor expansion
 *    backwards from the next whole sample (another evaluation path than the FMU's).
 *
 * Usage: test_time [steps [steps_mul]]: doSteps of each t += h master (default 10^6;
 * issue #10 asks for 10^8, about 15 s at -O2) and of each t0 + i h master (default a
 * tenth).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "djl_vars.h"
#include "fmi2Functions.h"

static char last_message[2048];

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    (void)name;
    (void)status;
    (void)category;
    strncpy(last_message, message, sizeof last_message - 1);
}

static const fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};

static fmi2Component make(double t0, double t_start)
{
    fmi2ValueReference vr = VR_T_START;
    fmi2Component c = fmi2Instantiate("time", fmi2CoSimulation, DJL_INSTANTIATION_TOKEN,
                                      "file:///tmp", &cb, fmi2False, fmi2False);
    CHECK(c != NULL, "instantiate");
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, t0, fmi2False, 0.0) == fmi2OK, "setup");
    CHECK(fmi2SetReal(c, &vr, 1, &t_start) == fmi2OK, "t_start");
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", last_message);
    return c;
}

static const fmi2ValueReference OUT[7] = {VR_X, VR_V, VR_A, VR_J, VR_X_AL, VR_V_AL, VR_A_AL};

static void outputs(fmi2Component c, double y[7])
{
    CHECK(fmi2GetReal(c, OUT, 7, y) == fmi2OK, "get");
}

#define REF_SAMPLES 2000 /* the default move lasts about 1.1 s: 1100 samples */
static double ref[REF_SAMPLES + 1][7];

/* The default move, stepped by Te from start time 0, motion starting at 0.2 s. */
static void make_reference(void)
{
    fmi2Component c = make(0.0, 0.2);
    int k;
    outputs(c, ref[0]);
    for (k = 1; k <= REF_SAMPLES; k++) {
        CHECK(fmi2DoStep(c, (k - 1) * 1e-3, 1e-3, fmi2True) == fmi2OK, "reference step");
        outputs(c, ref[k]);
    }
    fmi2FreeInstance(c);
}

/* A master from start time t0 with step h: accumulate (t += h) or multiply (t0 + i h). */
static void run_master(double t0, double h, int accumulate, long steps)
{
    fmi2Component c = make(t0, t0 + 0.2);
    double t = t0, y[7];
    long i, per = (long)floor(1e-3 / h + 0.5); /* steps per sample of Te */
    int bad = 0;
    for (i = 0; i < steps; i++) {
        double tc = accumulate ? t : t0 + (double)i * h;
        if (fmi2DoStep(c, tc, h, fmi2True) != fmi2OK) {
            CHECK(0, "t0 = %g, h = %g, %s: step %ld refused: %s", t0, h,
                  accumulate ? "t += h" : "t0 + i h", i, last_message);
            break;
        }
        t += h;
        if ((i + 1) % per == 0 && (i + 1) / per <= REF_SAMPLES) {
            outputs(c, y);
            if (memcmp(y, ref[(i + 1) / per], sizeof y) != 0 && bad++ < 3)
                CHECK(0, "t0 = %g, h = %g: sample %ld differs from the reference: x = %.17g, "
                      "expected %.17g", t0, h, (i + 1) / per, y[0], ref[(i + 1) / per][0]);
        }
    }
    outputs(c, y);
    if ((double)steps * h > (double)REF_SAMPLES * 1e-3)
        CHECK(y[0] == ref[REF_SAMPLES][0] && y[1] == 0.0, "t0 = %g, h = %g: end x = %.17g v = %g", t0,
          h, y[0], y[1]);
    /* off by a visible fraction of a step: refused with today's message */
    {
        fmi2Component d = make(t0, t0 + 0.2);
        double tt = t0;
        for (i = 0; i < 1000; i++, tt += h) fmi2DoStep(d, tt, h, fmi2True);
        CHECK(fmi2DoStep(d, tt + 0.05 * h, h, fmi2True) == fmi2Error &&
                  strstr(last_message, "a step must start where the previous one ended"),
              "t0 = %g, h = %g: a point 5 %% of a step late accepted", t0, h);
        fmi2FreeInstance(d);
        d = make(t0, t0 + 0.2);
        CHECK(fmi2DoStep(d, t0 - 0.5 * h, h, fmi2True) == fmi2Error &&
                  strstr(last_message, "a step must start where the previous one ended"),
              "t0 = %g, h = %g: a point half a step early accepted", t0, h);
        fmi2FreeInstance(d);
    }
    fmi2FreeInstance(c);
}

/* Steps of h = ratio Te (not whole samples): values at every point on the profile. */
static long checked = 0;

static void run_fractional(double ratio, unsigned seed)
{
    fmi2Component c = make(0.0, 0.2);
    double Te = 1e-3, t = 0.0, y[7], worst = 0.0;
    unsigned long long s = 0x9E3779B97F4A7C15ULL * (seed + 1);
    int i;
    for (i = 0; t < 1.5; i++) {
        double h = ratio * Te, u, sig, xr, vr, ar;
        long k;
        if (ratio <= 0.0) { /* random steps of 0.01 .. 3 samples */
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            h = Te * (0.01 + 3.0 * (double)(s >> 11) / 9007199254740992.0);
        }
        CHECK(fmi2DoStep(c, t, h, fmi2True) == fmi2OK, "ratio %g: step %d: %s", ratio, i,
              last_message);
        t += h;
        outputs(c, y);
        /* the interval [k, k+1) of Te that holds t; expand backwards from sample k+1 */
        u = t / Te;
        k = (long)floor(u + 1e-9);
        if (fabs(u - floor(u + 0.5)) < 1e-9) { /* on a sample: the reference itself */
            long kk = (long)floor(u + 0.5);
            if (kk <= REF_SAMPLES)
                CHECK(memcmp(y, ref[kk], 4 * sizeof(double)) == 0,
                      "ratio %g: on sample %ld, x = %.17g, expected %.17g", ratio, kk, y[0],
                      ref[kk][0]);
            continue;
        }
        if (k + 1 > REF_SAMPLES) continue;
        sig = (double)(k + 1) * Te - t;
        /* j of the interval [k, k+1) is the reference's jerk at sample k */
        ar = ref[k + 1][2] - ref[k][3] * sig;
        vr = ref[k + 1][1] - ref[k + 1][2] * sig + 0.5 * ref[k][3] * sig * sig;
        xr = ref[k + 1][0] - ref[k + 1][1] * sig + 0.5 * ref[k + 1][2] * sig * sig -
             ref[k][3] * sig * sig * sig / 6.0;
        worst = fmax(worst, fabs(y[0] - xr));
        checked++;
        CHECK(fabs(y[0] - xr) <= 1e-12 && fabs(y[1] - vr) <= 1e-10 && fabs(y[2] - ar) <= 1e-7 &&
                  y[3] == ref[k][3] && y[6] == ref[k][6],
              "ratio %g: t = %.17g: x v a j = %.17g %.17g %.17g %.17g, expected %.17g %.17g "
              "%.17g %.17g", ratio, t, y[0], y[1], y[2], y[3], xr, vr, ar, ref[k][3]);
        if (failures > 20) break;
    }
    CHECK(worst > 0.0 || ratio == 2.5, "ratio %g: no point between samples was checked", ratio);
    fmi2FreeInstance(c);
}

int main(int argc, char **argv)
{
    long steps = argc > 1 ? atol(argv[1]) : 1000000;
    long steps_mul = argc > 2 ? atol(argv[2]) : steps / 10; /* masters computing t0 + i h */
    static const double t0s[2] = {0.0, 1.7e9}, hs[2] = {1e-3, 1e-4};
    int a, b, acc;
    make_reference();
    for (a = 0; a < 2; a++)
        for (b = 0; b < 2; b++)
            for (acc = 1; acc >= 0; acc--) run_master(t0s[a], hs[b], acc, acc ? steps : steps_mul);
    run_fractional(0.37, 0);
    run_fractional(2.5, 0);
    run_fractional(1.0 / 3.0, 0);
    run_fractional(-1.0, 1);
    run_fractional(-1.0, 2);
    printf("time: %ld steps per master, %ld points between samples checked, %d failures\n",
           steps, checked, failures);
    return failures ? 1 : 0;
}
