/*
 * test_fmi3.c -- drives the FMI 3 layer directly, meant to run under
 * AddressSanitizer + UBSan or valgrind: arrays, FMU state, bad calls.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "djl_vars.h"
#include "fmi3Functions.h"

static char last_message[2048];

static void log_message(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                        fmi3String message)
{
    (void)env;
    (void)status;
    (void)category;
    strncpy(last_message, message, sizeof last_message - 1);
}

static fmi3Instance make(const char *name, int with_logger)
{
    fmi3Instance c = fmi3InstantiateCoSimulation(name, DJL_INSTANTIATION_TOKEN, "/tmp", fmi3False,
                                                 fmi3True, fmi3False, fmi3False, NULL, 0, NULL,
                                                 with_logger ? log_message : NULL, NULL);
    CHECK(c != NULL, "instantiate");
    return c;
}

static void expect_error(fmi3Status st, const char *fragment)
{
    CHECK(st == fmi3Error, "expected fmi3Error, got %d (%s)", (int)st, fragment);
    CHECK(strstr(last_message, fragment) != NULL, "message \"%s\" lacks \"%s\"", last_message,
          fragment);
}

static void run_multisegment_and_state(void)
{
    fmi3Instance c = make("ms", 1);
    fmi3ValueReference vr_n = VR_N_SEGMENTS, vr_d = VR_SEG_DISTANCE, vr_v = VR_SEG_V_END,
                       vr_x = VR_X, vr_done = VR_DONE;
    fmi3Int32 n = 20;
    double d[DJL_VARS_MAX_SEGMENTS] = {0}, ve[DJL_VARS_MAX_SEGMENTS] = {0}, back[DJL_VARS_MAX_SEGMENTS];
    double x = 0.0, x1[400], x2[400], t = 0.0, total = 0.0;
    fmi3Boolean done = fmi3False, eh, term, early;
    fmi3Float64 last;
    fmi3FMUState s = NULL;
    size_t size = 0;
    fmi3Byte *buf;
    int k;
    for (k = 0; k < 20; k++) {
        d[k] = 0.1 + 0.01 * k;
        ve[k] = k % 3 == 0 ? 0.0 : 0.3;
        total += d[k];
    }
    ve[19] = 0.0;
    CHECK(fmi3SetInt32(c, &vr_n, 1, &n, 1) == fmi3OK, "n");
    CHECK(fmi3SetFloat64(c, &vr_d, 1, d, DJL_VARS_MAX_SEGMENTS) == fmi3OK, "d");
    CHECK(fmi3SetFloat64(c, &vr_v, 1, ve, DJL_VARS_MAX_SEGMENTS) == fmi3OK, "ve");
    CHECK(fmi3GetFloat64(c, &vr_d, 1, back, DJL_VARS_MAX_SEGMENTS) == fmi3OK, "get array");
    CHECK(memcmp(back, d, sizeof d) == 0, "array round trip");
    CHECK(fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK, "enter");
    CHECK(fmi3ExitInitializationMode(c) == fmi3OK, "exit: %s", last_message);
    for (k = 0; k < 500; k++, t += 2e-3)
        fmi3DoStep(c, t, 2e-3, fmi3True, &eh, &term, &early, &last);
    CHECK(fmi3GetFMUState(c, &s) == fmi3OK, "get state");
    for (k = 0; k < 400; k++) {
        fmi3DoStep(c, t + k * 2e-3, 2e-3, fmi3True, &eh, &term, &early, &last);
        fmi3GetFloat64(c, &vr_x, 1, &x1[k], 1);
    }
    CHECK(fmi3SerializedFMUStateSize(c, s, &size) == fmi3OK, "size");
    buf = (fmi3Byte *)malloc(size);
    CHECK(fmi3SerializeFMUState(c, s, buf, size) == fmi3OK, "serialize");
    fmi3FreeFMUState(c, &s);
    CHECK(fmi3DeserializeFMUState(c, buf, size, &s) == fmi3OK, "deserialize");
    CHECK(fmi3SetFMUState(c, s) == fmi3OK, "set");
    for (k = 0; k < 400; k++) {
        fmi3DoStep(c, t + k * 2e-3, 2e-3, fmi3True, &eh, &term, &early, &last);
        fmi3GetFloat64(c, &vr_x, 1, &x2[k], 1);
    }
    CHECK(memcmp(x1, x2, sizeof x1) == 0, "restored run differs");
    fmi3FreeFMUState(c, &s);
    free(buf);
    t += 400 * 2e-3;
    for (k = 0; k < 5000 && !done; k++, t += 2e-3) {
        fmi3DoStep(c, t, 2e-3, fmi3True, &eh, &term, &early, &last);
        fmi3GetBoolean(c, &vr_done, 1, &done, 1);
    }
    fmi3GetFloat64(c, &vr_x, 1, &x, 1);
    CHECK(done && fabs(x - total) < 1e-12, "end of the multi-segment move: x = %.17g, %.17g", x,
          total);
    CHECK(fmi3Terminate(c) == fmi3OK, "terminate");
    fmi3FreeInstance(c);
}

/* Enumerations (profile, short_stage) through Int64, as the standard says; Int32 still works. */
static void run_enumerations(void)
{
    fmi3Instance c = make("enum", 1);
    fmi3ValueReference vr = VR_PROFILE, vr2[2] = {VR_PROFILE, VR_SHORT_STAGE};
    fmi3Int64 two = 2, back[2] = {0, 0}, huge = (fmi3Int64)1 << 40;
    fmi3Int32 i32 = 0;
    double vmax = 0.0;
    CHECK(fmi3SetInt64(c, &vr, 1, &two, 1) == fmi3OK, "set profile as Int64");
    CHECK(fmi3GetInt64(c, vr2, 2, back, 2) == fmi3OK && back[0] == 2 && back[1] == 1,
          "get profile, short_stage as Int64: %lld %lld", (long long)back[0], (long long)back[1]);
    CHECK(fmi3GetInt32(c, &vr, 1, &i32, 1) == fmi3OK && i32 == 2, "get profile as Int32");
    expect_error(fmi3SetInt64(c, &vr, 1, &huge, 1), "out of the range");
    CHECK(fmi3GetInt64(c, &vr, 1, back, 1) == fmi3OK && back[0] == 2, "unchanged after refusal");
    vr = VR_N_SEGMENTS; /* an Int32, not an enumeration */
    expect_error(fmi3SetInt64(c, &vr, 1, &two, 1), "not an Enumeration");
    fmi3FreeInstance(c);
    c = make("enum2", 1);
    vr = VR_V_MAX;
    expect_error(fmi3GetInt64(c, &vr, 1, back, 1), "not an Enumeration");
    fmi3FreeInstance(c);
    c = make("enum3", 1);
    vr = VR_PROFILE;
    two = 7;
    CHECK(fmi3SetInt64(c, &vr, 1, &two, 1) == fmi3OK, "set profile 7 (checked at init)");
    fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    expect_error(fmi3ExitInitializationMode(c), "profile = 7");
    vr = VR_V_MAX;
    CHECK(fmi3GetFloat64(c, &vr, 1, &vmax, 1) == fmi3OK && vmax == 1.0, "diagnostics");
    fmi3FreeInstance(c);
}

static void run_bad_inputs(void)
{
    fmi3Instance c;
    fmi3ValueReference vr;
    double v = -1.0, two[2] = {0.1, 0.2};
    fmi3Boolean eh, term, early;
    fmi3Float64 last;
    c = make("bad_dmax", 1);
    vr = VR_D_MAX;
    fmi3SetFloat64(c, &vr, 1, &v, 1);
    fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    expect_error(fmi3ExitInitializationMode(c), "d_max = -1");
    fmi3FreeInstance(c);
    c = make("bad_array", 1);
    vr = VR_SEG_DISTANCE;
    expect_error(fmi3SetFloat64(c, &vr, 1, two, 2), "nValues");
    fmi3FreeInstance(c);
    c = make("bad_element", 1);
    vr = VR_SEG_DISTANCE + 3; /* FMI 3 has no element value references */
    expect_error(fmi3SetFloat64(c, &vr, 1, &v, 1), "unknown value reference");
    fmi3FreeInstance(c);
    c = make("bad_step", 1);
    fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    fmi3ExitInitializationMode(c);
    CHECK(fmi3DoStep(c, 0.0, 2.5e-3, fmi3True, &eh, &term, &early, &last) == fmi3OK,
          "a step of 2.5 Te");
    CHECK(last == 2.5e-3, "lastSuccessfulTime %.17g", last);
    expect_error(fmi3DoStep(c, 2.5e-3 + 1e-4, 1e-3, fmi3True, &eh, &term, &early, &last),
                 "must start where");
    fmi3FreeInstance(c);
    /* no logger at all: errors must still be reported by status, without crashing */
    c = make("no_logger", 0);
    vr = VR_TE;
    v = 0.0;
    fmi3SetFloat64(c, &vr, 1, &v, 1);
    fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    CHECK(fmi3ExitInitializationMode(c) == fmi3Error, "Te = 0 without logger");
    fmi3FreeInstance(c);
    CHECK(fmi3InstantiateModelExchange("me", DJL_INSTANTIATION_TOKEN, "", 0, 1, NULL, log_message)
              == NULL, "ME refused");
    CHECK(fmi3InstantiateCoSimulation("x", "{wrong}", "", 0, 1, 0, 0, NULL, 0, NULL, log_message,
                                      NULL) == NULL, "token");
}

/* ------------------------------------------------ null pointer arguments */

static fmi3Instance ready(const char *name)
{
    fmi3Instance c = make(name, 1);
    CHECK(fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK, "enter");
    CHECK(fmi3ExitInitializationMode(c) == fmi3OK, "exit");
    return c;
}

static double now_of(fmi3Instance c)
{
    fmi3ValueReference vr = VR_TIME;
    double t = NAN;
    CHECK(fmi3GetFloat64(c, &vr, 1, &t, 1) == fmi3OK, "time");
    return t;
}

static void still_usable(fmi3Instance c)
{
    fmi3Boolean eh, term, early;
    fmi3Float64 last;
    fmi3ValueReference vr = VR_X;
    double x = NAN, t = now_of(c);
    fmi3Status st = fmi3DoStep(c, t, 1e-3, fmi3True, &eh, &term, &early, &last);
    CHECK(st == fmi3OK, "step after a refused call: %d (%s)", (int)st, last_message);
    CHECK(fmi3GetFloat64(c, &vr, 1, &x, 1) == fmi3OK && isfinite(x), "x");
}

static void run_null_pointers(void)
{
    fmi3Instance c = make("nulls", 1);
    fmi3ValueReference vr = VR_V_MAX, vr_n = VR_N_SEGMENTS, vr_done = VR_DONE;
    double v = 0.5, seg[DJL_VARS_MAX_SEGMENTS];
    fmi3Int32 i32 = 0;
    fmi3Boolean b = fmi3False, eh, term, early;
    fmi3Float64 last;
    fmi3FMUState s = NULL, s2 = NULL;
    fmi3Byte *buf;
    size_t size = 0, nd = 0, sizes[1] = {0};
    const fmi3String cats_bad[2] = {"logEvents", NULL};
    fmi3Binary bin[1] = {NULL};
    expect_error(fmi3SetFloat64(c, &vr, 1, NULL, 1), "fmi3SetFloat64: argument values is a null "
                 "pointer");
    expect_error(fmi3SetFloat64(c, NULL, 1, &v, 1), "fmi3SetFloat64: argument valueReferences");
    expect_error(fmi3SetInt32(c, &vr_n, 1, NULL, 1), "fmi3SetInt32: argument values");
    expect_error(fmi3SetBoolean(c, &vr_done, 1, NULL, 1), "fmi3SetBoolean: argument values");
    expect_error(fmi3SetFloat32(c, &vr, 1, NULL, 1), "fmi3SetFloat32: argument values");
    expect_error(fmi3SetString(c, NULL, 1, NULL, 1), "fmi3SetString: argument valueReferences");
    expect_error(fmi3SetBinary(c, &vr, 1, NULL, bin, 1), "fmi3SetBinary: argument valueSizes");
    expect_error(fmi3SetClock(c, &vr, 1, NULL), "fmi3SetClock: argument values");
    expect_error(fmi3SetDebugLogging(c, fmi3True, 1, NULL), "fmi3SetDebugLogging: argument "
                 "categories");
    expect_error(fmi3SetDebugLogging(c, fmi3True, 2, cats_bad), "categories[1] is a null pointer");
    /* a bad count refuses the whole call before anything is written */
    vr = VR_SEG_DISTANCE;
    CHECK(fmi3GetFloat64(c, &vr, 1, seg, DJL_VARS_MAX_SEGMENTS) == fmi3OK, "get array");
    seg[0] = 123.0;
    expect_error(fmi3SetFloat64(c, &vr, 1, seg, DJL_VARS_MAX_SEGMENTS + 1), "nValues");
    CHECK(fmi3Reset(c) == fmi3OK, "reset");
    CHECK(fmi3GetFloat64(c, &vr, 1, seg, DJL_VARS_MAX_SEGMENTS) == fmi3OK && seg[0] != 123.0,
          "nothing set by a refused call");
    vr = VR_V_MAX;
    CHECK(fmi3SetFloat64(c, &vr, 1, &v, 1) == fmi3OK, "still usable: %s", last_message);
    CHECK(fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK, "enter");
    CHECK(fmi3ExitInitializationMode(c) == fmi3OK, "exit: %s", last_message);
    /* getters */
    vr = VR_X;
    expect_error(fmi3GetFloat64(c, &vr, 1, NULL, 1), "fmi3GetFloat64: argument values");
    expect_error(fmi3GetFloat64(c, NULL, 1, &v, 1), "fmi3GetFloat64: argument valueReferences");
    expect_error(fmi3GetInt32(c, &vr_n, 1, NULL, 1), "fmi3GetInt32: argument values");
    expect_error(fmi3GetBoolean(c, &vr_done, 1, NULL, 1), "fmi3GetBoolean: argument values");
    expect_error(fmi3GetUInt64(c, &vr, 1, NULL, 1), "fmi3GetUInt64: argument values");
    expect_error(fmi3GetBinary(c, &vr, 1, NULL, bin, 1), "fmi3GetBinary: argument valueSizes");
    expect_error(fmi3GetBinary(c, &vr, 1, sizes, NULL, 1), "fmi3GetBinary: argument values");
    expect_error(fmi3GetClock(c, &vr, 1, NULL), "fmi3GetClock: argument values");
    CHECK(fmi3GetInt32(c, &vr_n, 1, &i32, 1) == fmi3OK && fmi3GetBoolean(c, &vr_done, 1, &b, 1)
          == fmi3OK, "gets");
    expect_error(fmi3GetNumberOfEventIndicators(c, NULL), "fmi3GetNumberOfEventIndicators: "
                 "argument nEventIndicators");
    expect_error(fmi3GetNumberOfContinuousStates(c, NULL), "fmi3GetNumberOfContinuousStates: "
                 "argument nContinuousStates");
    /* do step: every output pointer is required, refused before stepping */
    expect_error(fmi3DoStep(c, 0.0, 1e-3, fmi3True, NULL, &term, &early, &last),
                 "fmi3DoStep: argument eventHandlingNeeded");
    expect_error(fmi3DoStep(c, 0.0, 1e-3, fmi3True, &eh, &term, &early, NULL),
                 "fmi3DoStep: argument lastSuccessfulTime");
    CHECK(now_of(c) == 0.0, "no step taken");
    still_usable(c);
    /* FMU state */
    expect_error(fmi3GetFMUState(c, NULL), "fmi3GetFMUState: argument FMUState");
    expect_error(fmi3SetFMUState(c, NULL), "fmi3SetFMUState: argument FMU state");
    expect_error(fmi3FreeFMUState(c, NULL), "fmi3FreeFMUState: argument FMUState");
    CHECK(fmi3GetFMUState(c, &s) == fmi3OK && s, "get state");
    expect_error(fmi3SerializedFMUStateSize(c, s, NULL), "fmi3SerializedFMUStateSize: argument "
                 "size");
    expect_error(fmi3SerializedFMUStateSize(c, NULL, &size), "fmi3SerializedFMUStateSize: "
                 "argument FMUState");
    CHECK(fmi3SerializedFMUStateSize(c, s, &size) == fmi3OK, "size");
    buf = (fmi3Byte *)malloc(size);
    expect_error(fmi3SerializeFMUState(c, s, NULL, size), "fmi3SerializeFMUState: argument "
                 "serializedState");
    CHECK(fmi3SerializeFMUState(c, s, buf, size) == fmi3OK, "serialize");
    expect_error(fmi3DeserializeFMUState(c, NULL, size, &s2), "fmi3DeserializeFMUState: argument "
                 "serializedState");
    expect_error(fmi3DeserializeFMUState(c, buf, size, NULL), "fmi3DeserializeFMUState: argument "
                 "FMUState");
    buf[size / 2] ^= 1;
    expect_error(fmi3DeserializeFMUState(c, buf, size, &s2), "checksum");
    buf[size / 2] ^= 1;
    CHECK(fmi3DeserializeFMUState(c, buf, size, &s2) == fmi3OK, "deserialize");
    CHECK(fmi3SetFMUState(c, s2) == fmi3OK, "set");
    still_usable(c);
    fmi3FreeFMUState(c, &s);
    fmi3FreeFMUState(c, &s2);
    free(buf);
    /* no instance */
    CHECK(fmi3SetFloat64(NULL, &vr, 1, &v, 1) == fmi3Error, "null instance");
    CHECK(fmi3GetFloat64(NULL, &vr, 1, &v, 1) == fmi3Error, "null instance");
    CHECK(fmi3GetNumberOfVariableDependencies(NULL, vr, &nd) == fmi3Error, "null instance");
    CHECK(fmi3Reset(NULL) == fmi3Error, "null instance");
    fmi3FreeInstance(NULL);
    fmi3FreeInstance(c);
}

/* Variable dependencies are not provided: an error with a message that leaves
 * the instance usable (item 7 of issue #10). */
static void run_dependencies(void)
{
    fmi3Instance c = ready("deps");
    size_t nd = 99, ei[1], eo[1];
    fmi3ValueReference ind[1];
    fmi3DependencyKind kinds[1];
    expect_error(fmi3GetNumberOfVariableDependencies(c, VR_X, &nd),
                 "fmi3GetNumberOfVariableDependencies (value reference");
    CHECK(nd == 99, "nothing written");
    expect_error(fmi3GetNumberOfVariableDependencies(c, VR_X, NULL), "argument nDependencies");
    expect_error(fmi3GetVariableDependencies(c, VR_X, ei, ind, eo, kinds, 1),
                 "fmi3GetVariableDependencies (value reference");
    still_usable(c);
    still_usable(c);
    CHECK(fmi3Terminate(c) == fmi3OK, "terminate after refused dependency calls");
    fmi3FreeInstance(c);
}

/* Input shaping through FMI 3 (docs/generator.md, "Input shaping"): the shaper's arrays as
 * FMI 3 arrays, the enumerations as Int64; the shaped output equals the convolution of an
 * unshaped instance's samples (delays on and off the grid), an execute mid-move replans with
 * the past kept, an FMU state serialised mid-move replays bit for bit, and a bad shaper is
 * refused naming its parameter. */
static void run_shaper(void)
{
    fmi3Instance c = make("shaped", 1), r = make("plain", 1);
    fmi3ValueReference vr_k = VR_SHAPER, vr_n = VR_SHAPER_N, vr_a = VR_SHAPER_AMPLITUDE,
                       vr_dl = VR_SHAPER_DELAY, vr_p = VR_PROFILE, vr_x = VR_X, vr_tgt = VR_TARGET,
                       vr_ex = VR_EXECUTE, vr_done = VR_DONE, out4[4] = {VR_X, VR_V, VR_A, VR_J};
    fmi3Int64 custom = 4, jl = 2;
    fmi3Int32 n = 3;
    double A[8] = {0.5, 0.3, 0.2, 0, 0, 0, 0, 0}, D[8] = {0.0, 0.0123, 0.031, 0, 0, 0, 0, 0};
    double back[8], Te = 1e-3, t = 0.0, xr[1200][4], ys[1200][4], x1[300], x2[300], tgt = 0.1;
    fmi3Boolean eh, term, early, one = fmi3True, done = fmi3False;
    fmi3Float64 last;
    fmi3FMUState s = NULL;
    size_t size = 0;
    fmi3Byte *buf;
    int k, i;
    CHECK(fmi3SetInt64(c, &vr_k, 1, &custom, 1) == fmi3OK, "set shaper as Int64");
    CHECK(fmi3SetInt32(c, &vr_n, 1, &n, 1) == fmi3OK, "set shaper_n");
    CHECK(fmi3SetFloat64(c, &vr_a, 1, A, 8) == fmi3OK, "set shaper_amplitude (array)");
    CHECK(fmi3SetFloat64(c, &vr_dl, 1, D, 8) == fmi3OK, "set shaper_delay (array)");
    CHECK(fmi3GetFloat64(c, &vr_dl, 1, back, 8) == fmi3OK && memcmp(back, D, sizeof D) == 0,
          "shaper_delay round trip");
    CHECK(fmi3SetInt64(c, &vr_p, 1, &jl, 1) == fmi3OK && fmi3SetInt64(r, &vr_p, 1, &jl, 1) ==
          fmi3OK, "profile");
    fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    fmi3EnterInitializationMode(r, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    CHECK(fmi3ExitInitializationMode(c) == fmi3OK, "exit shaped: %s", last_message);
    CHECK(fmi3ExitInitializationMode(r) == fmi3OK, "exit plain: %s", last_message);
    for (k = 0; k < 1200; k++, t = k * Te) {
        if (k == 150) { /* a new target mid-move: both replan, the past is kept */
            fmi3SetFloat64(c, &vr_tgt, 1, &tgt, 1);
            fmi3SetFloat64(r, &vr_tgt, 1, &tgt, 1);
            fmi3SetBoolean(c, &vr_ex, 1, &one, 1);
            fmi3SetBoolean(r, &vr_ex, 1, &one, 1);
        }
        if (k == 400) CHECK(fmi3GetFMUState(c, &s) == fmi3OK, "get state");
        fmi3DoStep(c, t, Te, fmi3True, &eh, &term, &early, &last);
        fmi3DoStep(r, t, Te, fmi3True, &eh, &term, &early, &last);
        fmi3GetFloat64(c, out4, 4, ys[k], 4);
        fmi3GetFloat64(r, out4, 4, xr[k], 4);
        if (k >= 400 && k < 700) x1[k - 400] = ys[k][0];
    }
    /* sample k + 1 of the plain one is p at (k + 1) Te: each copy at (k + 1) Te - D[i] is the
     * cubic of its sample interval */
    for (k = 100; k < 1200; k++) {
        double y[4] = {0, 0, 0, 0};
        for (i = 0; i < 3; i++) {
            double si = (k + 1) - D[i] / Te, tau;
            int q = (int)floor(si + 1e-9);
            tau = (si - q) * Te;
            y[0] += A[i] * (xr[q - 1][0] + tau * (xr[q - 1][1] + tau * (0.5 * xr[q - 1][2] +
                                                                       tau * xr[q - 1][3] / 6.0)));
            y[1] += A[i] * (xr[q - 1][1] + tau * (xr[q - 1][2] + 0.5 * tau * xr[q - 1][3]));
            y[2] += A[i] * (xr[q - 1][2] + tau * xr[q - 1][3]);
            y[3] += A[i] * xr[q - 1][3];
        }
        CHECK(fabs(ys[k][0] - y[0]) < 1e-12 && fabs(ys[k][1] - y[1]) < 1e-10 &&
                  fabs(ys[k][2] - y[2]) < 1e-8 && fabs(ys[k][3] - y[3]) < 1e-6,
              "shaped sample %d: x %.17g (%.17g) v %g (%g) a %g (%g) j %g (%g)", k + 1, ys[k][0],
              y[0], ys[k][1], y[1], ys[k][2], y[2], ys[k][3], y[3]);
    }
    fmi3GetBoolean(c, &vr_done, 1, &done, 1);
    CHECK(done && ys[1199][0] == tgt && ys[1199][0] == xr[1199][0], "shaped rests at %.17g",
          ys[1199][0]);
    CHECK(fmi3SerializedFMUStateSize(c, s, &size) == fmi3OK, "size");
    buf = (fmi3Byte *)malloc(size);
    CHECK(fmi3SerializeFMUState(c, s, buf, size) == fmi3OK, "serialize");
    fmi3FreeFMUState(c, &s);
    CHECK(fmi3DeserializeFMUState(c, buf, size, &s) == fmi3OK, "deserialize: %s", last_message);
    CHECK(fmi3SetFMUState(c, s) == fmi3OK, "set state: %s", last_message);
    for (k = 400; k < 700; k++) {
        fmi3DoStep(c, k * Te, Te, fmi3True, &eh, &term, &early, &last);
        fmi3GetFloat64(c, &vr_x, 1, &x2[k - 400], 1);
    }
    CHECK(memcmp(x1, x2, sizeof x1) == 0, "shaped replay after restore differs");
    fmi3FreeFMUState(c, &s);
    free(buf);
    fmi3FreeInstance(c);
    fmi3FreeInstance(r);
    /* refused, naming the parameter */
    c = make("bad_shaper", 1);
    A[0] = 0.6;
    CHECK(fmi3SetInt64(c, &vr_k, 1, &custom, 1) == fmi3OK, "shaper");
    CHECK(fmi3SetInt32(c, &vr_n, 1, &n, 1) == fmi3OK, "shaper_n");
    CHECK(fmi3SetFloat64(c, &vr_a, 1, A, 8) == fmi3OK, "amplitudes");
    fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    expect_error(fmi3ExitInitializationMode(c), "shaper_amplitude[1..3] sum to 1.09999");
    fmi3FreeInstance(c);
}

/* Every entry point of the FMI 3 API that this co-simulation FMU does not provide: each
 * refuses with fmi3Error and a message naming it (Reset brings the instance back); the
 * types it has no variables of refuse any value reference; Instantiate's refusals
 * (issue 21: found uncovered). */
static void run_entry_points(void)
{
    fmi3Instance c = ready("entry");
    fmi3ValueReference vr = VR_X;
    fmi3Float64 r = 0.0;
    fmi3Float32 f32 = 0.0f;
    fmi3Int8 i8 = 0;
    fmi3UInt8 u8 = 0;
    fmi3Int16 i16 = 0;
    fmi3UInt16 u16 = 0;
    fmi3UInt32 u32 = 0;
    fmi3UInt64 u64 = 0;
    fmi3Int32 order = 1;
    fmi3String str = "x";
    fmi3Boolean b = fmi3False;
    fmi3IntervalQualifier q;
    CHECK(strcmp(fmi3GetVersion(), "3.0") == 0, "version %s", fmi3GetVersion());
#define REFUSED(call, fragment)                                                                  \
    do {                                                                                         \
        expect_error(call, fragment);                                                            \
        CHECK(fmi3Reset(c) == fmi3OK, "reset after %s", fragment);                              \
        CHECK(fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK &&  \
              fmi3ExitInitializationMode(c) == fmi3OK, "init after %s", fragment);                \
    } while (0)
    REFUSED(fmi3GetFloat32(c, &vr, 1, &f32, 1), "fmi3GetFloat32: value reference");
    REFUSED(fmi3GetInt8(c, &vr, 1, &i8, 1), "fmi3GetInt8: value reference");
    REFUSED(fmi3GetUInt8(c, &vr, 1, &u8, 1), "fmi3GetUInt8: value reference");
    REFUSED(fmi3GetInt16(c, &vr, 1, &i16, 1), "fmi3GetInt16: value reference");
    REFUSED(fmi3GetUInt16(c, &vr, 1, &u16, 1), "fmi3GetUInt16: value reference");
    REFUSED(fmi3GetUInt32(c, &vr, 1, &u32, 1), "fmi3GetUInt32: value reference");
    REFUSED(fmi3GetString(c, &vr, 1, &str, 1), "fmi3GetString: value reference");
    REFUSED(fmi3SetInt8(c, &vr, 1, &i8, 1), "fmi3SetInt8: value reference");
    REFUSED(fmi3SetUInt8(c, &vr, 1, &u8, 1), "fmi3SetUInt8: value reference");
    REFUSED(fmi3SetInt16(c, &vr, 1, &i16, 1), "fmi3SetInt16: value reference");
    REFUSED(fmi3SetUInt16(c, &vr, 1, &u16, 1), "fmi3SetUInt16: value reference");
    REFUSED(fmi3SetUInt32(c, &vr, 1, &u32, 1), "fmi3SetUInt32: value reference");
    REFUSED(fmi3SetUInt64(c, &vr, 1, &u64, 1), "fmi3SetUInt64: value reference");
    REFUSED(fmi3EnterEventMode(c), "fmi3EnterEventMode is not supported");
    REFUSED(fmi3GetDirectionalDerivative(c, &vr, 1, &vr, 1, &r, 1, &r, 1),
            "fmi3GetDirectionalDerivative is not supported");
    REFUSED(fmi3GetAdjointDerivative(c, &vr, 1, &vr, 1, &r, 1, &r, 1),
            "fmi3GetAdjointDerivative is not supported");
    REFUSED(fmi3EnterConfigurationMode(c), "fmi3EnterConfigurationMode is not supported");
    REFUSED(fmi3ExitConfigurationMode(c), "fmi3ExitConfigurationMode is not supported");
    REFUSED(fmi3GetIntervalDecimal(c, &vr, 1, &r, &q), "fmi3GetIntervalDecimal is not");
    REFUSED(fmi3GetIntervalFraction(c, &vr, 1, &u64, &u64, &q), "fmi3GetIntervalFraction is");
    REFUSED(fmi3GetShiftDecimal(c, &vr, 1, &r), "fmi3GetShiftDecimal is not supported");
    REFUSED(fmi3GetShiftFraction(c, &vr, 1, &u64, &u64), "fmi3GetShiftFraction is not");
    REFUSED(fmi3SetIntervalDecimal(c, &vr, 1, &r), "fmi3SetIntervalDecimal is not supported");
    REFUSED(fmi3SetIntervalFraction(c, &vr, 1, &u64, &u64), "fmi3SetIntervalFraction is not");
    REFUSED(fmi3SetShiftDecimal(c, &vr, 1, &r), "fmi3SetShiftDecimal is not supported");
    REFUSED(fmi3SetShiftFraction(c, &vr, 1, &u64, &u64), "fmi3SetShiftFraction is not");
    REFUSED(fmi3EvaluateDiscreteStates(c), "fmi3EvaluateDiscreteStates is not supported");
    REFUSED(fmi3UpdateDiscreteStates(c, &b, &b, &b, &b, &b, &r), "fmi3UpdateDiscreteStates is");
    REFUSED(fmi3EnterContinuousTimeMode(c), "fmi3EnterContinuousTimeMode is not supported");
    REFUSED(fmi3CompletedIntegratorStep(c, fmi3True, &b, &b), "fmi3CompletedIntegratorStep is");
    REFUSED(fmi3SetTime(c, 0.0), "fmi3SetTime is not supported");
    REFUSED(fmi3SetContinuousStates(c, &r, 1), "fmi3SetContinuousStates is not supported");
    REFUSED(fmi3GetContinuousStateDerivatives(c, &r, 1), "fmi3GetContinuousStateDerivatives");
    REFUSED(fmi3GetEventIndicators(c, &r, 1), "fmi3GetEventIndicators is not supported");
    REFUSED(fmi3GetContinuousStates(c, &r, 1), "fmi3GetContinuousStates is not supported");
    REFUSED(fmi3GetNominalsOfContinuousStates(c, &r, 1), "fmi3GetNominalsOfContinuousStates");
    REFUSED(fmi3EnterStepMode(c), "fmi3EnterStepMode is not supported");
    REFUSED(fmi3GetOutputDerivatives(c, &vr, 1, &order, &r, 1), "fmi3GetOutputDerivatives is");
    REFUSED(fmi3ActivateModelPartition(c, vr, 0.0), "fmi3ActivateModelPartition is not");
    CHECK(fmi3EnterEventMode(NULL) == fmi3Error, "NULL instance");
    {
        size_t n = 7, sz = 1;
        fmi3Binary bin = NULL;
        fmi3FMUState s = NULL, s2 = NULL;
        fmi3Byte *buf;
        fmi3String cats[1] = {"noSuchCategory"};
        CHECK(fmi3GetNumberOfEventIndicators(c, &n) == fmi3OK && n == 0, "event indicators");
        n = 7;
        CHECK(fmi3GetNumberOfContinuousStates(c, &n) == fmi3OK && n == 0, "continuous states");
        REFUSED(fmi3SetBinary(c, &vr, 1, &sz, (const fmi3Binary *)&bin, 1),
                "fmi3SetBinary: value reference");
        CHECK(fmi3SetDebugLogging(c, fmi3True, 0, NULL) == fmi3OK, "logging on");
        CHECK(fmi3SetDebugLogging(c, fmi3True, 1, cats) == fmi3Warning, "unknown category");
        /* a damaged state to overwrite or fill, a buffer too small: refused */
        CHECK(fmi3GetFMUState(c, &s) == fmi3OK, "get");
        CHECK(fmi3SerializedFMUStateSize(c, s, &sz) == fmi3OK, "size");
        buf = (fmi3Byte *)malloc(sz);
        REFUSED(fmi3SerializeFMUState(c, s, buf, sz - 1), "buffer of");
        CHECK(fmi3SerializeFMUState(c, s, buf, sz) == fmi3OK, "serialize");
        ((char *)s)[sz - 1] ^= 1; /* the checksum no longer holds */
        s2 = s;
        REFUSED(fmi3GetFMUState(c, &s2), "state to overwrite");
        REFUSED(fmi3SerializeFMUState(c, s, buf, sz), "checksum");
        REFUSED(fmi3SerializedFMUStateSize(c, s, &sz), "fmi3SerializedFMUStateSize: FMU state "
                "damaged"); /* a size is read from a checked state only */
        REFUSED(fmi3DeserializeFMUState(c, buf, sz, &s2), "state to overwrite");
        fmi3FreeFMUState(c, &s);
        free(buf);
    }
#undef REFUSED
    still_usable(c);
    fmi3FreeInstance(c);
    /* Instantiate: refusals, NULL with a message */
    last_message[0] = '\0';
    CHECK(fmi3InstantiateModelExchange("me", DJL_INSTANTIATION_TOKEN, "", fmi3False, fmi3False,
                                       NULL, log_message) == NULL &&
          strstr(last_message, "co-simulation only") != NULL, "model exchange: %s", last_message);
    last_message[0] = '\0';
    CHECK(fmi3InstantiateScheduledExecution("se", DJL_INSTANTIATION_TOKEN, "", fmi3False,
                                            fmi3False, NULL, log_message, NULL, NULL, NULL) ==
          NULL && strstr(last_message, "co-simulation only") != NULL, "scheduled execution");
    last_message[0] = '\0';
    CHECK(fmi3InstantiateCoSimulation("", DJL_INSTANTIATION_TOKEN, "", fmi3False, fmi3False,
                                      fmi3False, fmi3False, NULL, 0, NULL, log_message, NULL) ==
          NULL && strstr(last_message, "non-empty") != NULL, "empty name");
    CHECK(fmi3InstantiateCoSimulation("t", "{0}", "", fmi3False, fmi3False, fmi3False, fmi3False,
                                      NULL, 0, NULL, log_message, NULL) == NULL &&
          strstr(last_message, "instantiation token") != NULL, "token");
    CHECK(fmi3InstantiateCoSimulation("e", DJL_INSTANTIATION_TOKEN, "", fmi3False, fmi3False,
                                      fmi3True, fmi3False, NULL, 0, NULL, log_message, NULL) ==
          NULL && strstr(last_message, "eventModeUsed") != NULL, "event mode");
    CHECK(fmi3InstantiateCoSimulation("i", DJL_INSTANTIATION_TOKEN, "", fmi3False, fmi3False,
                                      fmi3False, fmi3False, &vr, 1, NULL, log_message, NULL) ==
          NULL && strstr(last_message, "intermediate") != NULL, "intermediate variables");
    CHECK(fmi3InstantiateCoSimulation("", DJL_INSTANTIATION_TOKEN, "", fmi3False, fmi3False,
                                      fmi3False, fmi3False, NULL, 0, NULL, NULL, NULL) == NULL,
          "without a logger");
}

/* Profile 4 through FMI 3's arrays: table_samples (Int32[256]) and table_jerk
 * (Float64[256]) set whole, read back; the table (+J, -J, -J, +J over 50 samples each:
 * 0.025 m) lands exactly; an entry refused by name; an array of the wrong count refused
 * without changing anything. */
static void run_table(void)
{
    fmi3Instance c = make("table", 1);
    fmi3ValueReference vp = VR_PROFILE, vn = VR_TABLE_N, vs = VR_TABLE_SAMPLES,
                       vj = VR_TABLE_JERK, vd = VR_DISTANCE, vx = VR_X, vv = VR_V, vm = VR_V_MAX;
    fmi3Int64 four = 4;
    fmi3Int32 n = 4, samples[256], back_s[256];
    double jerk[256] = {100.0, -100.0, -100.0, 100.0}, back_j[256], dist = 0.025, x = 0.0,
           v = 1.0, t = 0.0, vmax = 0.2;
    fmi3Boolean eh, term, early;
    fmi3Float64 last;
    int k;
    for (k = 0; k < 256; k++) samples[k] = k < 4 ? 50 : 1;
    CHECK(fmi3SetInt64(c, &vp, 1, &four, 1) == fmi3OK, "profile = 4: %s", last_message);
    CHECK(fmi3SetInt32(c, &vn, 1, &n, 1) == fmi3OK, "table_n");
    CHECK(fmi3SetInt32(c, &vs, 1, samples, 256) == fmi3OK, "table_samples");
    CHECK(fmi3SetFloat64(c, &vj, 1, jerk, 256) == fmi3OK, "table_jerk");
    CHECK(fmi3SetFloat64(c, &vd, 1, &dist, 1) == fmi3OK, "distance");
    CHECK(fmi3GetInt32(c, &vs, 1, back_s, 256) == fmi3OK &&
              memcmp(back_s, samples, sizeof samples) == 0,
          "table_samples round trip");
    CHECK(fmi3GetFloat64(c, &vj, 1, back_j, 256) == fmi3OK &&
              memcmp(back_j, jerk, sizeof jerk) == 0,
          "table_jerk round trip");
    /* a count that is not the array's: refused, nothing set */
    samples[0] = 0;
    expect_error(fmi3SetInt32(c, &vs, 1, samples, 255), "nValues = 255");
    CHECK(fmi3GetInt32(c, &vs, 1, back_s, 256) == fmi3OK && back_s[0] == 50, "nothing set");
    /* v_max below the table's peak (0.25 m/s): refused naming the piece */
    CHECK(fmi3SetFloat64(c, &vm, 1, &vmax, 1) == fmi3OK, "v_max");
    CHECK(fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK, "enter");
    expect_error(fmi3ExitInitializationMode(c), "table_jerk[2] = -100 m/s3 over table_samples[2] "
                                                "= 50 samples: in piece 2 the table's velocity "
                                                "reaches 0.25 m/s, beyond v_max = 0.2 m/s");
    CHECK(fmi3Reset(c) == fmi3OK, "reset");
    vmax = 0.25;
    CHECK(fmi3SetInt64(c, &vp, 1, &four, 1) == fmi3OK && fmi3SetInt32(c, &vn, 1, &n, 1) == fmi3OK &&
              fmi3SetFloat64(c, &vj, 1, jerk, 256) == fmi3OK &&
              fmi3SetFloat64(c, &vd, 1, &dist, 1) == fmi3OK &&
              fmi3SetFloat64(c, &vm, 1, &vmax, 1) == fmi3OK,
          "set again");
    samples[0] = 50;
    CHECK(fmi3SetInt32(c, &vs, 1, samples, 256) == fmi3OK, "table_samples again");
    CHECK(fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK, "enter");
    CHECK(fmi3ExitInitializationMode(c) == fmi3OK, "exit: %s", last_message);
    for (k = 0; k < 210; k++, t += 1e-3)
        CHECK(fmi3DoStep(c, t, 1e-3, fmi3True, &eh, &term, &early, &last) == fmi3OK, "step");
    fmi3GetFloat64(c, &vx, 1, &x, 1);
    fmi3GetFloat64(c, &vv, 1, &v, 1);
    CHECK(x == 0.025 && v == 0.0, "the table lands: x %.17g v %.17g", x, v);
    fmi3FreeInstance(c);
}

int main(void)
{
    run_shaper();
    run_table();
    run_enumerations();
    run_multisegment_and_state();
    run_bad_inputs();
    run_null_pointers();
    run_dependencies();
    run_entry_points();
    printf("fmi3: %d failures\n", failures);
    return failures ? 1 : 0;
}
