/*
 * test_fmi2.c -- drives the FMI 2 layer directly (no importer), meant to run
 * under AddressSanitizer + UBSan or valgrind: normal run, FMU state save /
 * restore / serialise, every kind of bad call, reset, two instances.
 */
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "djl_vars.h"
#include "fmi2Functions.h"
#include "fmu_instance.h" /* model_data / model_state_seal: forging states with a valid checksum */

static int errors_logged = 0;
static char last_message[2048];

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    (void)name;
    (void)category;
    if (status >= fmi2Error) errors_logged++;
    strncpy(last_message, message, sizeof last_message - 1);
}

static const fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};

static fmi2Component make(const char *name)
{
    fmi2Component c = fmi2Instantiate(name, fmi2CoSimulation, DJL_INSTANTIATION_TOKEN,
                                      "file:///tmp", &cb, fmi2False, fmi2True);
    CHECK(c != NULL, "instantiate");
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK, "setup");
    return c;
}

static void set_real(fmi2Component c, fmi2ValueReference vr, double v)
{
    CHECK(fmi2SetReal(c, &vr, 1, &v) == fmi2OK, "set %u", vr);
}

static double get_real(fmi2Component c, fmi2ValueReference vr)
{
    double v = NAN;
    CHECK(fmi2GetReal(c, &vr, 1, &v) == fmi2OK, "get %u: %s", vr, last_message);
    return v;
}

static void expect_error(fmi2Status st, const char *fragment)
{
    CHECK(st == fmi2Error, "expected fmi2Error, got %d (%s)", (int)st, fragment);
    CHECK(strstr(last_message, fragment) != NULL, "message \"%s\" lacks \"%s\"", last_message,
          fragment);
}

/* A state forged from the serialised state buf: unpacked into d, changed by stmt, packed and
 * resealed into forged; deserialising and setting it must both be refused, naming fragment.
 * Uses the caller's c, buf, d, forged and s2. */
#define FORGE(stmt, fragment)                                                                     \
    do {                                                                                         \
        model_state_unpack(buf, &d);                                                             \
        stmt;                                                                                    \
        model_state_pack(&d, forged);                                                            \
        expect_error(fmi2DeSerializeFMUstate(c, forged, model_state_size(&d), &s2), fragment);   \
        expect_error(fmi2SetFMUstate(c, forged), fragment);                                      \
    } while (0)

static void run_states(void)
{
    fmi2Component c = make("states");
    fmi2FMUstate s = NULL, s2 = NULL;
    double x1[300], x2[300], t = 0.0;
    size_t size = 0;
    fmi2Byte *buf;
    int k;
    set_real(c, VR_T_F2, 0.11);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit");
    for (k = 0; k < 100; k++, t += 1e-3) CHECK(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "step");
    CHECK(fmi2GetFMUstate(c, &s) == fmi2OK && s, "get state");
    for (k = 0; k < 300; k++) {
        fmi2DoStep(c, t + k * 1e-3, 1e-3, fmi2True);
        x1[k] = get_real(c, VR_X);
    }
    CHECK(fmi2SetFMUstate(c, s) == fmi2OK, "set state");
    CHECK(fmi2SerializedFMUstateSize(c, s, &size) == fmi2OK && size > 0, "size");
    buf = (fmi2Byte *)malloc(size);
    CHECK(fmi2SerializeFMUstate(c, s, buf, size) == fmi2OK, "serialize");
    CHECK(fmi2DeSerializeFMUstate(c, buf, size, &s2) == fmi2OK && s2, "deserialize");
    CHECK(fmi2SetFMUstate(c, s2) == fmi2OK, "set deserialized");
    for (k = 0; k < 300; k++) {
        fmi2DoStep(c, t + k * 1e-3, 1e-3, fmi2True);
        x2[k] = get_real(c, VR_X);
    }
    CHECK(memcmp(x1, x2, sizeof x1) == 0, "restored run differs");
    expect_error(fmi2DeSerializeFMUstate(c, buf, size - 1, &s2), "bytes");
    fmi2FreeFMUstate(c, &s);
    fmi2FreeFMUstate(c, &s2);
    CHECK(s == NULL && s2 == NULL, "free sets NULL");
    free(buf);
    fmi2FreeInstance(c);
}

static void run_bad_inputs(void)
{
    fmi2Component c;
    fmi2ValueReference vr = 999;
    double v = 0.0, nan = NAN;
    fmi2Integer n = 40;
    /* invalid parameter found at initialization */
    c = make("bad_vmax");
    set_real(c, VR_V_MAX, nan);
    fmi2EnterInitializationMode(c);
    expect_error(fmi2ExitInitializationMode(c), "v_max = nan");
    expect_error(fmi2DoStep(c, 0.0, 1e-3, fmi2True), "state Error");
    CHECK(isfinite(get_real(c, VR_X)), "NaN output in error state");
    CHECK(fmi2Reset(c) == fmi2OK, "reset");
    fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode(c);
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "after reset");
    fmi2FreeInstance(c);
    /* outputs that would overflow (issue #10): refused by name at initialization */
    c = make("overflow_before");
    set_real(c, VR_V_MAX, 1e300);
    set_real(c, VR_V0, 1e300);
    set_real(c, VR_V_E, 1e300);
    set_real(c, VR_DISTANCE, 1e299);
    set_real(c, VR_T_START, 1e9);
    fmi2EnterInitializationMode(c);
    expect_error(fmi2ExitInitializationMode(c), "v0 = 1e+300 m/s with t_start = 1e+09 s");
    CHECK(isfinite(get_real(c, VR_X)), "infinite output after the refusal");
    fmi2FreeInstance(c);
    c = make("overflow_after");
    set_real(c, VR_V_MAX, 1e300);
    set_real(c, VR_V0, 1e300);
    set_real(c, VR_V_E, 1e300);
    set_real(c, VR_DISTANCE, 1e299);
    fmi2EnterInitializationMode(c);
    expect_error(fmi2ExitInitializationMode(c), "v_e = 1e+300 m/s");
    fmi2FreeInstance(c);
    c = make("overflow_x0");
    set_real(c, VR_X0, 1.797e308);
    set_real(c, VR_DISTANCE, 1e305);
    fmi2EnterInitializationMode(c);
    expect_error(fmi2ExitInitializationMode(c), "x0 = 1.797e+308");
    fmi2FreeInstance(c);
    /* segment count */
    c = make("bad_n");
    vr = VR_N_SEGMENTS;
    CHECK(fmi2SetInteger(c, &vr, 1, &n) == fmi2OK, "set n");
    fmi2EnterInitializationMode(c);
    expect_error(fmi2ExitInitializationMode(c), "n_segments = 40");
    fmi2FreeInstance(c);
    /* unknown value reference, wrong type, outputs */
    c = make("bad_vr");
    vr = 999;
    expect_error(fmi2SetReal(c, &vr, 1, &v), "unknown value reference 999");
    fmi2FreeInstance(c);
    c = make("bad_type");
    vr = VR_PROFILE;
    expect_error(fmi2SetReal(c, &vr, 1, &v), "profile");
    fmi2FreeInstance(c);
    c = make("bad_output");
    vr = VR_X;
    expect_error(fmi2SetReal(c, &vr, 1, &v), "output");
    fmi2FreeInstance(c);
    /* step size and state machine */
    c = make("bad_step");
    expect_error(fmi2DoStep(c, 0.0, 1e-3, fmi2True), "state Instantiated");
    fmi2FreeInstance(c);
    c = make("bad_step2");
    fmi2EnterInitializationMode(c);
    fmi2ExitInitializationMode(c);
    CHECK(fmi2DoStep(c, 0.0, 1.5e-3, fmi2True) == fmi2OK, "a step of 1.5 Te: %s", last_message);
    expect_error(fmi2DoStep(c, 1.5e-3, 0.0, fmi2True), "must be a finite number > 0");
    fmi2FreeInstance(c);
    c = make("bad_step3");
    fmi2EnterInitializationMode(c);
    fmi2ExitInitializationMode(c);
    expect_error(fmi2DoStep(c, 0.0, -1e-3, fmi2True), "must be a finite number > 0");
    fmi2FreeInstance(c);
    c = make("bad_step4");
    fmi2EnterInitializationMode(c);
    fmi2ExitInitializationMode(c);
    expect_error(fmi2DoStep(c, 0.0, NAN, fmi2True), "must be a finite number > 0");
    fmi2FreeInstance(c);
    c = make("bad_step5");
    fmi2EnterInitializationMode(c);
    fmi2ExitInitializationMode(c);
    expect_error(fmi2DoStep(c, 0.0, 1e300, fmi2True), "past");
    fmi2FreeInstance(c);
    c = make("bad_fixed");
    fmi2EnterInitializationMode(c);
    fmi2ExitInitializationMode(c);
    vr = VR_V_MAX;
    v = 2.0;
    expect_error(fmi2SetReal(c, &vr, 1, &v), "fixed parameter");
    fmi2FreeInstance(c);
    /* wrong GUID, model exchange */
    CHECK(fmi2Instantiate("x", fmi2CoSimulation, "{wrong}", "", &cb, 0, 1) == NULL, "guid");
    CHECK(fmi2Instantiate("x", fmi2ModelExchange, DJL_INSTANTIATION_TOKEN, "", &cb, 0, 1) == NULL,
          "ME");
    /* null instance */
    CHECK(fmi2DoStep(NULL, 0.0, 1e-3, fmi2True) == fmi2Error, "null");
}

static void set_int(fmi2Component c, fmi2ValueReference vr, int v)
{
    CHECK(fmi2SetInteger(c, &vr, 1, &v) == fmi2OK, "set %u", vr);
}

/* Initialisation refused with `fragment` in the message; then the instance is usable
 * again: after a reset (a parameter refused: the instance is in Error), the default move
 * lands on 0.4 m; or, an input refused (f_mode: the instance stays in Initialization Mode),
 * once f_mode is set to 10 Hz the move lands on 0.4 m. */
static void refused_at_init(fmi2Component c, const char *fragment, int input)
{
    int k;
    fmi2EnterInitializationMode(c);
    expect_error(fmi2ExitInitializationMode(c), fragment);
    if (input) {
        set_real(c, VR_F_MODE, 10.0);
        CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "initialisation with f_mode = 10 Hz: %s",
              last_message);
    } else {
        CHECK(isfinite(get_real(c, VR_X)) && isfinite(get_real(c, VR_V)),
              "outputs after refusal");
        CHECK(fmi2Reset(c) == fmi2OK, "reset after the refusal");
        CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK, "setup");
        CHECK(fmi2EnterInitializationMode(c) == fmi2OK &&
                  fmi2ExitInitializationMode(c) == fmi2OK,
              "initialisation after reset: %s", last_message);
    }
    for (k = 0; k < 1200; k++) fmi2DoStep(c, k * 1e-3, 1e-3, fmi2True);
    CHECK(fabs(get_real(c, VR_X) - 0.4) < 1e-12 && get_real(c, VR_V) == 0.0,
          "the default move after the refusal: x = %.17g", get_real(c, VR_X));
    fmi2FreeInstance(c);
}

/* The refusals of what no output may reach (the FMU's horizon, the position after a
 * multi-segment motion, a shaped motion past the horizon, a time-varying custom shaper
 * delayed past the memory window), each reached and named. */
static void run_range_refusals(void)
{
    fmi2Component c;
    int i;
    /* a start time whose horizon (10^15 samples) ends beyond 10^300 s */
    c = make("far_start");
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 2e300, fmi2False, 0.0) == fmi2OK, "setup");
    set_real(c, VR_T_START, 2e300);
    refused_at_init(c, "invalid start time 2e+300 s: the FMU's horizon of 1e+15 samples of "
                       "Te = 0.001 s from it would end beyond 1e+300 s", 0);
    /* a Te whose horizon lasts beyond 10^300 s (the jerk times at least Te/2) */
    c = make("huge_Te");
    set_real(c, VR_TE, 1e290);
    for (i = 0; i < 4; i++) set_real(c, VR_T_F1 + (fmi2ValueReference)i, 1e290);
    set_real(c, VR_DISTANCE, 0.0);
    refused_at_init(c, "invalid parameter Te = 1e+290 s: the FMU's horizon of 1e+15 samples "
                       "would last beyond 1e+300 s", 0);
    /* a multi-segment motion ending at 10^300 m/s: the position would overflow after it */
    c = make("overflow_after_segments");
    set_real(c, VR_V_MAX, 1e300);
    set_real(c, VR_V0, 1e300);
    set_int(c, VR_N_SEGMENTS, 2);
    for (i = 0; i < 2; i++) {
        set_real(c, VR_SEG_DISTANCE + (fmi2ValueReference)i, 1e299);
        set_real(c, VR_SEG_V_END + (fmi2ValueReference)i, 1e300);
    }
    refused_at_init(c, "invalid parameter seg_v_end[2] = 1e+300 m/s: after the motion the "
                       "position grows at 1e+300 m/s", 0);
    /* a motion of 10^15 - 200 samples (11 segments, AL at 1 m/s) shaped by ZV at 1 Hz,
     * whose last impulse comes 500 samples later: past the horizon */
    c = make("shaped_past_horizon");
    set_int(c, VR_PROFILE, 1);
    set_real(c, VR_V_MAX, 1.0);
    set_real(c, VR_A_MAX, 1000.0);
    set_real(c, VR_D_MAX, 1000.0);
    set_int(c, VR_N_SEGMENTS, 11);
    for (i = 0; i < 11; i++) {
        set_real(c, VR_SEG_DISTANCE + (fmi2ValueReference)i, i < 10 ? 1e11 - 10.0 : 99.8);
        set_real(c, VR_SEG_V_END + (fmi2ValueReference)i, i < 10 ? 1.0 : 0.0);
    }
    set_int(c, VR_SHAPER, 1);
    set_real(c, VR_F_SHAPER, 1.0);
    refused_at_init(c, "invalid parameter shaper = 1: the motion of 999999999999800 samples "
                       "and the shaper's last impulse, 500 samples later, exceed the 1e+15 "
                       "samples a motion may take", 0);
    /* a custom shaper timed by f_mode whose second impulse, 0.05 s at f_shaper = 10 Hz,
     * comes 50 s late at the starting f_mode = 0.01 Hz: beyond the 4096 samples kept */
    c = make("custom_delay_past_window");
    set_int(c, VR_SHAPER, 4);
    set_int(c, VR_SHAPER_SOURCE, 2);
    set_int(c, VR_SHAPER_N, 2);
    set_real(c, VR_F_SHAPER, 10.0);
    set_real(c, VR_SHAPER_AMPLITUDE, 0.5);
    set_real(c, VR_SHAPER_AMPLITUDE + 1, 0.5);
    set_real(c, VR_SHAPER_DELAY + 1, 0.05);
    set_real(c, VR_F_MODE, 0.01);
    refused_at_init(c, "invalid input f_mode = 0.01 Hz: with shaper_source = 2, "
                       "shaper_delay[2] = 0.05 s at f_shaper = 10 Hz becomes 50 s, 50000 "
                       "samples of Te = 0.001 s: more than the 4096 samples", 1);
}

static void run_two_instances(void)
{
    fmi2Component a = make("a"), b = make("b");
    double t = 0.0;
    int k;
    set_real(b, VR_DISTANCE, -0.2);
    fmi2EnterInitializationMode(a);
    fmi2ExitInitializationMode(a);
    fmi2EnterInitializationMode(b);
    fmi2ExitInitializationMode(b);
    for (k = 0; k < 1000; k++, t += 1e-3) {
        fmi2DoStep(a, t, 1e-3, fmi2True);
        fmi2DoStep(b, t, 1e-3, fmi2True);
    }
    CHECK(fabs(get_real(a, VR_X) - 0.4) < 1e-12, "a");
    CHECK(fabs(get_real(b, VR_X) + 0.2) < 1e-12, "b");
    CHECK(fmi2Terminate(a) == fmi2OK && fmi2Terminate(b) == fmi2OK, "terminate");
    fmi2FreeInstance(a);
    fmi2FreeInstance(b);
}

/* ------------------------------------------------ null pointer arguments */

static fmi2Component ready(const char *name)
{
    fmi2Component c = make(name);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit");
    return c;
}

/* The instance is still usable: steps and outputs as a fresh one. */
static void still_usable(fmi2Component c, double t)
{
    fmi2Status st;
    CHECK(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &t) == fmi2OK, "time");
    st = fmi2DoStep(c, t, 1e-3, fmi2True);
    CHECK(st == fmi2OK, "step after a refused call: %d (%s)", (int)st, last_message);
    CHECK(isfinite(get_real(c, VR_X)), "x");
}

static void run_null_pointers(void)
{
    fmi2Component c = make("nulls");
    fmi2ValueReference vr = VR_V_MAX, vrs[2] = {VR_X, VR_V};
    fmi2Real r = 0.0;
    fmi2Integer i = 0;
    fmi2Boolean b = 0;
    fmi2String str = NULL;
    fmi2FMUstate s = NULL, s2 = NULL;
    fmi2Status st = fmi2OK;
    const fmi2String cats_bad[2] = {"logEvents", NULL};
    size_t size = 0;
    fmi2Byte *buf;
    /* before initialization: setters */
    expect_error(fmi2SetReal(c, &vr, 1, NULL), "fmi2SetReal: argument value is a null pointer");
    expect_error(fmi2SetReal(c, NULL, 1, &r), "fmi2SetReal: argument vr is a null pointer");
    vr = VR_PROFILE;
    expect_error(fmi2SetInteger(c, &vr, 1, NULL), "fmi2SetInteger: argument value");
    expect_error(fmi2SetBoolean(c, &vr, 1, NULL), "fmi2SetBoolean: argument value");
    expect_error(fmi2SetString(c, &vr, 1, NULL), "fmi2SetString: argument value");
    expect_error(fmi2SetString(c, NULL, 1, &str), "fmi2SetString: argument vr");
    expect_error(fmi2SetDebugLogging(c, fmi2True, 2, NULL), "fmi2SetDebugLogging: argument "
                 "categories");
    expect_error(fmi2SetDebugLogging(c, fmi2True, 2, cats_bad), "categories[1] is a null pointer");
    CHECK(fmi2SetReal(c, NULL, 0, NULL) == fmi2OK, "nvr = 0 with NULL arrays is a no-op");
    vr = VR_V_MAX;
    set_real(c, VR_V_MAX, 0.9); /* still usable */
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK,
          "initialization after refused calls: %s", last_message);
    /* getters */
    expect_error(fmi2GetReal(c, vrs, 2, NULL), "fmi2GetReal: argument value is a null pointer");
    expect_error(fmi2GetReal(c, NULL, 2, &r), "fmi2GetReal: argument vr");
    vr = VR_PROFILE;
    expect_error(fmi2GetInteger(c, &vr, 1, NULL), "fmi2GetInteger: argument value");
    vr = VR_DONE;
    expect_error(fmi2GetBoolean(c, &vr, 1, NULL), "fmi2GetBoolean: argument value");
    expect_error(fmi2GetString(c, &vr, 1, NULL), "fmi2GetString: argument value");
    CHECK(fmi2GetBoolean(c, &vr, 1, &b) == fmi2OK, "get boolean");
    (void)i;
    /* status */
    expect_error(fmi2GetStatus(c, fmi2DoStepStatus, NULL), "fmi2GetStatus: argument value");
    expect_error(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, NULL), "fmi2GetRealStatus: argument "
                 "value");
    expect_error(fmi2GetBooleanStatus(c, fmi2Terminated, NULL), "fmi2GetBooleanStatus: argument "
                 "value");
    /* FMU state */
    expect_error(fmi2GetFMUstate(c, NULL), "fmi2GetFMUstate: argument FMUstate");
    expect_error(fmi2SetFMUstate(c, NULL), "fmi2SetFMUstate: argument FMU state");
    expect_error(fmi2FreeFMUstate(c, NULL), "fmi2FreeFMUstate: argument FMUstate");
    CHECK(fmi2FreeFMUstate(c, &s) == fmi2OK, "free of a NULL state is ignored");
    CHECK(fmi2GetFMUstate(c, &s) == fmi2OK && s, "get state");
    expect_error(fmi2SerializedFMUstateSize(c, s, NULL), "fmi2SerializedFMUstateSize: argument "
                 "size");
    expect_error(fmi2SerializedFMUstateSize(c, NULL, &size), "fmi2SerializedFMUstateSize: "
                 "argument FMUstate");
    CHECK(fmi2SerializedFMUstateSize(c, s, &size) == fmi2OK, "size");
    buf = (fmi2Byte *)malloc(size);
    expect_error(fmi2SerializeFMUstate(c, s, NULL, size), "fmi2SerializeFMUstate: argument "
                 "serializedState");
    expect_error(fmi2SerializeFMUstate(c, NULL, buf, size), "fmi2SerializeFMUstate: argument FMU "
                 "state");
    expect_error(fmi2SerializeFMUstate(c, s, buf, size - 1), "buffer of");
    CHECK(fmi2SerializeFMUstate(c, s, buf, size) == fmi2OK, "serialize");
    expect_error(fmi2DeSerializeFMUstate(c, NULL, size, &s2), "fmi2DeSerializeFMUstate: argument "
                 "serializedState");
    expect_error(fmi2DeSerializeFMUstate(c, buf, size, NULL), "fmi2DeSerializeFMUstate: argument "
                 "FMUstate");
    CHECK(fmi2DeSerializeFMUstate(c, buf, size, &s2) == fmi2OK && s2, "deserialize");
    CHECK(fmi2SetFMUstate(c, s2) == fmi2OK, "set");
    still_usable(c, 0.0);
    fmi2FreeFMUstate(c, &s);
    fmi2FreeFMUstate(c, &s2);
    free(buf);
    /* no instance: an error (no logger to tell) */
    CHECK(fmi2SetReal(NULL, &vr, 1, &r) == fmi2Error, "null instance set");
    CHECK(fmi2GetReal(NULL, &vr, 1, &r) == fmi2Error, "null instance get");
    CHECK(fmi2GetFMUstate(NULL, &s) == fmi2Error, "null instance state");
    CHECK(fmi2SetDebugLogging(NULL, fmi2True, 0, NULL) == fmi2Error, "null instance logging");
    CHECK(fmi2Reset(NULL) == fmi2Error, "null instance reset");
    CHECK(fmi2FreeFMUstate(NULL, &s) == fmi2Error, "null instance free state");
    fmi2FreeInstance(NULL);
    (void)st;
    fmi2FreeInstance(c);
}

/* ---------------------------------------------- corrupted FMU states */

static uint64_t rng = 0x9e3779b97f4a7c15u;
static uint64_t next_rand(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}

#define REPLAY 40

/* Outputs over REPLAY steps from the instance's current time. */
static void replay(fmi2Component c, double out[REPLAY][5], fmi2Status *worst)
{
    fmi2ValueReference vrs[4] = {VR_X, VR_V, VR_A, VR_J};
    fmi2ValueReference vr_done = VR_DONE;
    double t = 0.0, h = 1e-3;
    fmi2Boolean done = 0;
    fmi2ValueReference vr_te = VR_TE;
    int k;
    fmi2Status st;
    *worst = fmi2OK;
    if (fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &t) != fmi2OK) *worst = fmi2Error;
    if (fmi2GetReal(c, &vr_te, 1, &h) != fmi2OK) *worst = fmi2Error;
    for (k = 0; k < REPLAY; k++) {
        st = fmi2DoStep(c, t, h, fmi2True);
        if (st > *worst) *worst = st;
        t += h;
        st = fmi2GetReal(c, vrs, 4, out[k]);
        if (st > *worst) *worst = st;
        st = fmi2GetBoolean(c, &vr_done, 1, &done);
        if (st > *worst) *worst = st;
        out[k][4] = done;
    }
}

/* Damage a copy of the state: a few bytes xor-ed with non-zero values, a
 * run of random bytes, or a single bit; at least one byte always changes. */
static void corrupt(fmi2Byte *b, size_t size)
{
    size_t pos, n, k;
    switch (next_rand() % 3) {
    case 0:
        n = 1 + next_rand() % 4;
        for (k = 0; k < n; k++) b[next_rand() % size] ^= (fmi2Byte)(1 + next_rand() % 255);
        break;
    case 1:
        n = 1 + next_rand() % 16;
        pos = next_rand() % (size - n);
        b[pos] ^= (fmi2Byte)(1 + next_rand() % 255);
        for (k = 1; k < n; k++) b[pos + k] = (fmi2Byte)next_rand();
        break;
    default:
        pos = next_rand() % size;
        b[pos] ^= (fmi2Byte)(1u << (next_rand() % 8));
    }
}

static void reseal(fmi2Byte *b, size_t size) { model_state_seal(b, size); }

/* n corruptions of a mid-motion serialized state.  Plain: every one must be
 * refused (checksum) with a message, or replay identically.  Resealed (the
 * checksum recomputed after the damage, as a forger would): the structural
 * checks must refuse it, or it must run without crash; Reset always works. */
static void run_state_fuzz(long n, long n_sealed)
{
    fmi2Component c = make("fuzz");
    fmi2ValueReference vr_n = VR_N_SEGMENTS, vr_d = VR_SEG_DISTANCE, vr_v = VR_SEG_V_END;
    fmi2Integer nseg = 3;
    double dist[3] = {0.1, 0.25, -0.05}, ve[3] = {0.4, 0.0, 0.0}, t = 0.0;
    static double ref[REPLAY][5], got[REPLAY][5];
    fmi2FMUstate s = NULL, s2 = NULL;
    fmi2Byte *buf, *work;
    size_t size = 0;
    long it, refused = 0, accepted = 0, refused_sealed = 0, accepted_sealed = 0, same_sealed = 0;
    fmi2Status worst;
    int k, sealed;
    fmi2ValueReference vrd[3], vrv[3];
    for (k = 0; k < 3; k++) {
        vrd[k] = vr_d + (fmi2ValueReference)k;
        vrv[k] = vr_v + (fmi2ValueReference)k;
    }
    CHECK(fmi2SetInteger(c, &vr_n, 1, &nseg) == fmi2OK, "n");
    CHECK(fmi2SetReal(c, vrd, 3, dist) == fmi2OK, "d");
    CHECK(fmi2SetReal(c, vrv, 3, ve) == fmi2OK, "v");
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", last_message);
    for (k = 0; k < 400; k++, t += 1e-3) fmi2DoStep(c, t, 1e-3, fmi2True);
    CHECK(fmi2GetFMUstate(c, &s) == fmi2OK, "get state");
    CHECK(fmi2SerializedFMUstateSize(c, s, &size) == fmi2OK, "size");
    buf = (fmi2Byte *)malloc(size);
    work = (fmi2Byte *)malloc(size);
    CHECK(fmi2SerializeFMUstate(c, s, buf, size) == fmi2OK, "serialize");
    replay(c, ref, &worst);
    CHECK(worst == fmi2OK, "reference replay");
    for (it = 0; it < n + n_sealed; it++) {
        fmi2Status st;
        sealed = it >= n;
        memcpy(work, buf, size);
        corrupt(work, size);
        if (sealed) reseal(work, size);
        last_message[0] = '\0';
        st = fmi2DeSerializeFMUstate(c, work, size, &s2);
        if (st != fmi2OK) {
            CHECK(st == fmi2Error, "refusal status %d", (int)st);
            CHECK(strstr(last_message, "fmi2DeSerializeFMUstate") != NULL, "refusal message "
                  "\"%s\"", last_message);
            if (sealed) refused_sealed++;
            else refused++;
            continue;
        }
        CHECK(fmi2SetFMUstate(c, s2) == fmi2OK, "set accepted state: %s", last_message);
        replay(c, got, &worst);
        if (sealed) {
            accepted_sealed++;
            same_sealed += worst == fmi2OK && memcmp(ref, got, sizeof ref) == 0;
        } else {
            accepted++;
            CHECK(worst == fmi2OK && memcmp(ref, got, sizeof ref) == 0,
                  "accepted corrupted state does not replay identically (iteration %ld)", it);
        }
        CHECK(fmi2Reset(c) == fmi2OK, "reset after an accepted state");
        CHECK(fmi2DeSerializeFMUstate(c, buf, size, &s2) == fmi2OK, "good state after reset");
        CHECK(fmi2SetFMUstate(c, s2) == fmi2OK, "set good state after reset");
    }
    /* the instance is as good as before */
    CHECK(fmi2SetFMUstate(c, s) == fmi2OK, "set");
    replay(c, got, &worst);
    CHECK(worst == fmi2OK && memcmp(ref, got, sizeof ref) == 0, "replay after the fuzz");
    CHECK(refused + accepted == n, "count");
    printf("fmi2 state fuzz: %ld corruptions: %ld refused, %ld accepted (identical replay); "
           "%ld resealed: %ld refused, %ld accepted (ran, no crash; %ld of them replay identically)\n",
           n, refused, accepted, n_sealed, refused_sealed, accepted_sealed, same_sealed);
    fmi2FreeFMUstate(c, &s);
    fmi2FreeFMUstate(c, &s2);
    free(buf);
    free(work);
    fmi2FreeInstance(c);
}

/* Packing (fmu_instance.c): a state holds the live entries of the shaper's rings in time
 * order from index 0, wherever they wrapped in the instance; unpacking gives them back. */
static void run_state_packing(void)
{
    static model_data d, back;
    unsigned char *b = (unsigned char *)malloc(model_state_max_size());
    size_t head = model_state_max_size() - DJL_SHAPER_RING * (sizeof(djl_past_piece) +
                                                              sizeof(djl_phase_point));
    int32_t i;
    CHECK(b != NULL, "malloc");
    memset(&d, 0, sizeof d);
    d.magic = MODEL_MAGIC;
    d.n = 12345;
    d.mem.n_past = 5;
    d.mem.past_first = DJL_SHAPER_RING - 2; /* wraps */
    d.mem.n_phase = 3;
    d.mem.phase_first = 7;
    for (i = 0; i < DJL_SHAPER_RING; i++) {
        d.mem.past[i].k = 1000 + i;
        d.mem.past[i].x = -(double)i;
        d.mem.phase[i].k = 5000 + i;
        d.mem.phase[i].rate = 0.5 * i;
    }
    CHECK(model_state_size(&d) == head + 5 * sizeof(djl_past_piece) + 3 * sizeof(djl_phase_point),
          "packed size %lu", (unsigned long)model_state_size(&d));
    memset(b, 0xAB, model_state_max_size());
    model_state_pack(&d, b);
    CHECK(model_state_stored_size(b) == model_state_size(&d), "header size");
    CHECK(b[model_state_size(&d)] == 0xAB, "packing wrote past its size");
    memset(&back, 0x55, sizeof back);
    model_state_unpack(b, &back);
    CHECK(back.n == 12345 && back.mem.n_past == 5 && back.mem.n_phase == 3 &&
          back.mem.past_first == 0 && back.mem.phase_first == 0, "unpacked counts");
    for (i = 0; i < 5; i++)
        CHECK(back.mem.past[i].k == 1000 + (DJL_SHAPER_RING - 2 + i) % DJL_SHAPER_RING &&
              back.mem.past[i].x == -(double)((DJL_SHAPER_RING - 2 + i) % DJL_SHAPER_RING),
              "past entry %d", (int)i);
    for (i = 0; i < 3; i++)
        CHECK(back.mem.phase[i].k == 5000 + 7 + i && back.mem.phase[i].rate == 0.5 * (7 + i),
              "phase entry %d", (int)i);
    /* the seal covers the entries: one changed, the checksum no longer holds */
    {
        uint64_t sum;
        memcpy(&sum, b + offsetof(model_data, checksum), 8);
        CHECK(sum == model_state_checksum(b, model_state_size(&d)), "sealed");
        b[head + 8] ^= 1;
        CHECK(sum != model_state_checksum(b, model_state_size(&d)), "entries sealed");
        b[head + 8] ^= 1;
    }
    /* the checksum as docs/generator.md states it (issue 39: eight lanes, word k in lane
     * k % 8 but the words past the last group of eight in lane 0, each step
     * h = rotl((h ^ w) P, 29), the checksum's own word read as 0, lane j starting at the
     * basis + j, the lanes folded by the same step from the basis ^ size, then xxHash64's
     * avalanche), and any one word changed changes it */
    {
        size_t n = model_state_size(&d) / 8, j, whole = n / 8 * 8;
        size_t own = offsetof(model_data, checksum) / 8;
        uint64_t lane[8], ref, w, sum, x = 0x9e3779b97f4a7c15u;
        int changed = 0;
        CHECK(n % 8 != 0, "a state whose words fill no whole group of eight (%lu)",
              (unsigned long)n);
        for (j = 0; j < 8; j++) lane[j] = 0xcbf29ce484222325u + j;
        for (j = 0; j < n; j++) {
            uint64_t *h = &lane[j < whole ? j % 8 : 0];
            memcpy(&w, b + 8 * j, 8);
            if (j == own) w = 0;
            *h = (*h ^ w) * 0x100000001b3u;
            *h = (*h << 29) | (*h >> 35);
        }
        ref = 0xcbf29ce484222325u ^ (uint64_t)(8 * n);
        for (j = 0; j < 8; j++) {
            ref = (ref ^ lane[j]) * 0x100000001b3u;
            ref = (ref << 29) | (ref >> 35);
        }
        ref ^= ref >> 33;
        ref *= 0xc2b2ae3d27d4eb4fu;
        ref ^= ref >> 29;
        ref *= 0x165667b19e3779f9u;
        ref ^= ref >> 32;
        memcpy(&sum, b + offsetof(model_data, checksum), 8);
        CHECK(sum == ref, "checksum %llx, eight rotated lanes %llx", (unsigned long long)sum,
              (unsigned long long)ref);
        for (j = 0; j < n; j++) {
            if (j == own) continue;
            x ^= x << 13, x ^= x >> 7, x ^= x << 17; /* xorshift: never 0 */
            memcpy(&w, b + 8 * j, 8);
            w ^= x;
            memcpy(b + 8 * j, &w, 8);
            changed += model_state_checksum(b, 8 * n) != sum;
            w ^= x;
            memcpy(b + 8 * j, &w, 8);
        }
        CHECK(changed == (int)n - 1, "%d of the %lu words change the checksum", changed,
              (unsigned long)n - 1);
        CHECK(model_state_checksum(b, 8 * n) == sum, "the state back as it was");
    }
    d.mem.n_past = d.mem.n_phase = 0;
    CHECK(model_state_size(&d) == head, "empty rings: the head alone");
    free(b);
}

/* Targeted structural damage with a valid checksum: each is refused by name. */
static void set_bool(fmi2Component c, fmi2ValueReference vr, int v);
static int get_bool(fmi2Component c, fmi2ValueReference vr);

static void run_forged_states(void)
{
    fmi2Component c = ready("forged");
    fmi2FMUstate s = NULL, s2 = NULL;
    size_t size = 0;
    fmi2Byte *buf, *forged;
    static model_data d; /* unpacked, changed, packed and sealed again */
    int k;
    double t = 0.0;
    for (k = 0; k < 50; k++, t += 1e-3) fmi2DoStep(c, t, 1e-3, fmi2True);
    fmi2GetFMUstate(c, &s);
    fmi2SerializedFMUstateSize(c, s, &size);
    buf = (fmi2Byte *)malloc(size);
    forged = (fmi2Byte *)malloc(model_state_max_size());
    fmi2SerializeFMUstate(c, s, buf, size);
    FORGE(d.state = 64, "state machine value 64");
    FORGE(d.state = MS_ERROR, "state machine value 32");
    FORGE(d.planned = 2, "planned flag");
    FORGE(d.plan.n_pieces = 100000, "piece count");
    FORGE(d.plan.n_pieces = 0, "piece count");
    FORGE(d.cursor = d.plan.n_pieces, "cursor");
    FORGE(d.cursor = -1, "cursor");
    FORGE(d.plan.n_segments = 33, "segment count");
    FORGE(d.plan.piece[1].k = d.plan.piece[2].k + 1, "not in order");
    FORGE(d.plan.piece[0].x = NAN, "not finite");
    FORGE(d.offset = NAN, "offset");
    FORGE(d.offset = 0.5, "offset");
    FORGE(d.start_time = INFINITY, "start time");
    FORGE(d.n = -1, "sample counter");
    FORGE(d.phase = 1.0, "phase");
    FORGE(d.phase = NAN, "phase");
    FORGE(d.phase = -0.25, "phase");
    FORGE(d.t_now = INFINITY, "communication time");
    FORGE(d.phase = 0.5, "outputs are not those of its plan");
    FORGE(d.p.Te = 0.0, "parameters are invalid");
    FORGE(d.p.v_max = 2.0, "not made from its parameters");
    FORGE(d.out.x += 1e-9, "outputs are not those of its plan");
    FORGE(d.planned = 0, "without a plan");
    /* issue 21: finite but beyond the limits it obeys (level0 = -DBL_MAX and a stop once
     * gave infinite outputs after OK) */
    FORGE(d.plan.level0 = -DBL_MAX, "acceleration level is outside the acceleration limits");
    FORGE(d.plan.level0 = 1.5 * d.p.a_max, "acceleration level is outside");
    FORGE(d.plan.step[0].A = 1e300, "step of the plan is outside the acceleration limits");
    FORGE(d.plan.piece[d.plan.n_pieces - 2].j = 1e300, "outside the limits");
    FORGE(d.plan.piece[d.plan.n_pieces - 2].v = 2.0 * d.p.v_max, "outside the limits");
    FORGE(d.plan.piece[d.plan.n_pieces - 2].a = -DBL_MAX, "outside the limits");
    FORGE(d.plan.piece[d.plan.n_pieces - 1].x = 1e305, "outside the limits");
    FORGE(d.plan.v_reached = 1e300, "outside its limits");
    FORGE(d.f_seen = -1.0, "f_mode last seen");
    /* unchecked: the checksum alone */
    model_state_unpack(buf, &d);
    d.plan.seg[0].frac += 1.0;
    model_state_pack(&d, forged);
    memcpy(forged + offsetof(model_data, checksum), buf + offsetof(model_data, checksum), 8);
    expect_error(fmi2DeSerializeFMUstate(c, forged, size, &s2), "checksum");
    expect_error(fmi2SetFMUstate(c, forged), "checksum");
    /* the packing: a size that is not the rings' (a count changed, resealed), a truncated
     * or extended state (the header's size), another layout, a ring not packed from 0 */
    FORGE(d.mem.n_past = 1, "a memory of the shaper without a shaper"); /* packed: checked */
    FORGE(d.mem.n_phase = DJL_SHAPER_RING + 1, "not that of its shaper memory");
    memcpy(forged, buf, size);
    expect_error(fmi2DeSerializeFMUstate(c, forged, size + 8, &s2), "its header says");
    expect_error(fmi2DeSerializeFMUstate(c, forged, 100, &s2), "too short");
    {
        int32_t first = 3, count = -1;
        memcpy(forged + offsetof(model_data, mem) + offsetof(djl_shaper_memory, n_past),
               &count, 4);
        model_state_seal(forged, size);
        expect_error(fmi2DeSerializeFMUstate(c, forged, size, &s2), "(-1 and 0 entries");
        expect_error(fmi2SetFMUstate(c, forged), "(-1 and 0 entries");
        memcpy(forged, buf, size);
        uint32_t layout = MODEL_LAYOUT - 1;
        memcpy(forged + offsetof(model_data, mem) + offsetof(djl_shaper_memory, past_first),
               &first, 4);
        model_state_seal(forged, size);
        expect_error(fmi2DeSerializeFMUstate(c, forged, size, &s2), "from 3 and 0");
        memcpy(forged, buf, size);
        memcpy(forged + offsetof(model_data, layout), &layout, 4);
        model_state_seal(forged, size);
        expect_error(fmi2DeSerializeFMUstate(c, forged, size, &s2), "bad header");
        expect_error(fmi2SetFMUstate(c, forged), "bad header");
    }
    /* issue 21, fourth session (fuzz_state): the replan count has no bound but its type's;
     * a state holding INT64_MAX is accepted, and the next replan (a commanded target) made
     * the count overflow (UBSan).  It now stays at INT64_MAX; the move lands. */
    {
        fmi2Component c2 = ready("forged_replans");
        int i;
        model_state_unpack(buf, &d);
        d.replans = INT64_MAX;
        model_state_pack(&d, forged);
        CHECK(fmi2SetFMUstate(c2, forged) == fmi2OK, "replans = INT64_MAX: %s", last_message);
        set_real(c2, VR_TARGET, -0.1);
        set_bool(c2, VR_EXECUTE, 1);
        for (i = 0; i < 3000; i++)
            CHECK(fmi2DoStep(c2, 0.05 + i * 1e-3, 1e-3, fmi2True) == fmi2OK, "step %d: %s", i,
                  last_message);
        CHECK(fabs(get_real(c2, VR_X) + 0.1) < 1e-12 && get_bool(c2, VR_DONE),
              "replans = INT64_MAX: the target -0.1 m, x = %.17g", get_real(c2, VR_X));
        fmi2FreeInstance(c2);
    }
    /* refusals left the instance as it was */
    still_usable(c, 0.0);
    /* from the Error state, a stored state can be restored, and Reset always works */
    expect_error(fmi2DoStep(c, 0.0, 1.5e-3, fmi2True), "must start where");
    CHECK(fmi2SetFMUstate(c, s) == fmi2OK, "restore from the Error state: %s", last_message);
    still_usable(c, 0.0);
    expect_error(fmi2DoStep(c, 0.0, 1.5e-3, fmi2True), "must start where");
    CHECK(fmi2Reset(c) == fmi2OK, "reset from Error");
    fmi2FreeFMUstate(c, &s);
    free(buf);
    free(forged);
    fmi2FreeInstance(c);
}

/* The check area of states is allocated at the first check, with the importer's
 * allocateMemory: when that fails, the restore is refused (out of memory) and the instance
 * goes on as it was; it is freed with the instance (ASan's leak check). */
static int refuse_check_area;
static void *alloc_but_check_area(size_t n, size_t size)
{
    if (refuse_check_area && n * size == sizeof(model_data)) return NULL;
    return calloc(n, size);
}

static void run_check_area_allocation(void)
{
    fmi2CallbackFunctions fcb = {logger, alloc_but_check_area, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("check area", fmi2CoSimulation, DJL_INSTANTIATION_TOKEN,
                                      "file:///tmp", &fcb, fmi2False, fmi2True);
    fmi2FMUstate s = NULL;
    double t = 0.0;
    int k;
    CHECK(c != NULL, "instantiate");
    CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK, "setup");
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK,
          "init");
    for (k = 0; k < 20; k++, t += 1e-3) fmi2DoStep(c, t, 1e-3, fmi2True);
    CHECK(fmi2GetFMUstate(c, &s) == fmi2OK, "get (packing needs no check area)");
    refuse_check_area = 1;
    expect_error(fmi2SetFMUstate(c, s), "fmi2SetFMUstate: out of memory (checking an FMU state)");
    still_usable(c, t);
    refuse_check_area = 0;
    CHECK(fmi2SetFMUstate(c, s) == fmi2OK, "set once memory is there: %s", last_message);
    refuse_check_area = 1; /* allocated once: no further allocation */
    CHECK(fmi2SetFMUstate(c, s) == fmi2OK, "set again: %s", last_message);
    refuse_check_area = 0;
    fmi2FreeFMUstate(c, &s);
    fmi2FreeInstance(c);
}

/* A ZVD shaper timed by f_mode (shaper_source = 2) whose phase history spans a long rest
 * (issue 21, third session: fuzz_state found NaN outputs after an OK step, f_mode = DBL_MAX
 * accepted and rests of 10^6 s: the phase overflowed).  f_mode above 2/Te is refused (its
 * period under Te/2, as for jerk_source 2 and 3); and a move after a rest of 10^6 s gives,
 * sample for sample, what it gives after a rest of 1 s (the shaped output depends on the
 * phase within the shaper's window only: a time shift), to the resolution of a time of
 * 10^9 samples in a double: 2 ulp(10^9) samples of travel at the move's top speed
 * (2.4e-10 m here; 4.3e-11 m measured).  Before the fix the phase spanned the whole rest
 * and kept fewer digits: 4.5e-10 m. */
static void run_fmode_phase_long_rest(void)
{
    fmi2ValueReference vr_shaper = VR_SHAPER, vr_source = VR_SHAPER_SOURCE, vr_x = VR_EXECUTE;
    fmi2ValueReference outs[3] = {VR_X, VR_V, VR_A};
    fmi2Integer zvd = SHAPER_ZVD, by_fmode = SHAPER_SOURCE_F_MODE;
    fmi2Boolean on = fmi2True;
    static double rec[2][3000][3];
    double worst = 0.0, vtop = 0.0, tol;
    int w, k;
    for (w = 0; w < 2; w++) {
        fmi2Component c = make(w ? "rest 1e9 s" : "rest 1 s");
        double t = 0.0, rest = w ? 1e6 : 1.0, f;
        fmi2Real big = DBL_MAX, above = 2.0 / 1e-3 * (1.0 + 1e-12), top = 2.0 / 1e-3;
        CHECK(fmi2SetInteger(c, &vr_shaper, 1, &zvd) == fmi2OK, "shaper");
        CHECK(fmi2SetInteger(c, &vr_source, 1, &by_fmode) == fmi2OK, "shaper_source");
        set_real(c, VR_F_MODE, 12.0);
        CHECK(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
        CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", last_message);
        for (k = 0; k < 2000; k++, t += 1e-3)
            CHECK(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "step: %s", last_message);
        if (w == 0) {
            fmi2ValueReference vf = VR_F_MODE;
            expect_error(fmi2SetReal(c, &vf, 1, &big), "its period, 5.56268e-309 s, must be "
                         "at least Te/2 = 0.0005 s (f_mode at most 2000 Hz");
            expect_error(fmi2SetReal(c, &vf, 1, &above), "must be at least Te/2");
            CHECK(fmi2SetReal(c, &vf, 1, &top) == fmi2OK, "f_mode = 2/Te: %s", last_message);
            CHECK(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "step at f_mode 2/Te");
            t += 1e-3;
            set_real(c, VR_F_MODE, 12.0);
            CHECK(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "step");
            t += 1e-3;
        } else {
            for (k = 0; k < 2; k++, t += 1e-3) fmi2DoStep(c, t, 1e-3, fmi2True);
        }
        CHECK(fmi2DoStep(c, t, rest, fmi2True) == fmi2OK, "rest: %s", last_message);
        t += rest;
        set_real(c, VR_TARGET, 0.1);
        CHECK(fmi2SetBoolean(c, &vr_x, 1, &on) == fmi2OK, "execute");
        for (k = 0; k < 3000; k++, t += 1e-3) {
            f = 12.0 + 3.0 * sin(0.01 * k); /* f_mode moving all along the move */
            set_real(c, VR_F_MODE, f);
            CHECK(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "step %d: %s", k, last_message);
            CHECK(fmi2GetReal(c, outs, 3, rec[w][k]) == fmi2OK, "outputs");
            CHECK(isfinite(rec[w][k][0]) && isfinite(rec[w][k][1]) && isfinite(rec[w][k][2]),
                  "finite outputs");
        }
        fmi2FreeInstance(c);
    }
    for (k = 0; k < 3000; k++) {
        double dx = fabs(rec[0][k][0] - rec[1][k][0]);
        if (dx > worst) worst = dx;
        if (fabs(rec[0][k][1]) > vtop) vtop = fabs(rec[0][k][1]);
    }
    tol = 2.0 * (nextafter(1e9, 2e9) - 1e9) * 1e-3 * vtop;
    if (getenv("TEST_VERBOSE")) printf("long rest: %g m, allowed %g m (top speed %g m/s)\n", worst, tol, vtop);
    CHECK(worst <= tol, "after a rest of 1e6 s the shaped move differs by %g m (allowed %g m)",
          worst, tol);
    CHECK(fabs(rec[1][2999][0] - 0.1) <= 1e-12, "the move ends at %.17g", rec[1][2999][0]);
}

/* jerk_source = 3 measures f_mode's rate of change over each step: over a step of
 * 10^-310 s a change of 990 Hz overflowed to an infinite rate, and the FMU refused the
 * state it then saved (fuzz_fmi, third session).  The rate is the largest double: the
 * state is accepted back, the outputs stay finite and the move lands. */
static void run_fmode_rate_overflow(void)
{
    fmi2Component c = make("f_mode rate");
    fmi2ValueReference vjs = VR_JERK_SOURCE;
    fmi2Integer ahead = JERK_SOURCE_F_MODE_AHEAD;
    fmi2FMUstate s = NULL;
    double t = 0.0, h = 1e-310;
    int k;
    CHECK(fmi2SetInteger(c, &vjs, 1, &ahead) == fmi2OK, "jerk_source");
    set_real(c, VR_F_MODE, 10.0);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", last_message);
    /* from t = 0, where 1e-310 s is a time a double holds: a step of it, f_mode changed,
     * and the next step measures the change over it */
    CHECK(fmi2DoStep(c, t, h, fmi2True) == fmi2OK, "a step of 1e-310 s: %s", last_message);
    t += h;
    set_real(c, VR_F_MODE, 1000.0);
    CHECK(fmi2DoStep(c, t, h, fmi2True) == fmi2OK, "again: %s", last_message);
    t += h;
    CHECK(fmi2GetFMUstate(c, &s) == fmi2OK, "get");
    CHECK(fmi2SetFMUstate(c, s) == fmi2OK, "the state it saved: %s", last_message);
    set_real(c, VR_F_MODE, 10.0);
    for (k = 0; k < 3000; k++) {
        CHECK(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "step: %s", last_message);
        t += 1e-3;
        CHECK(isfinite(get_real(c, VR_X)) && isfinite(get_real(c, VR_V)), "finite outputs");
    }
    CHECK(fabs(get_real(c, VR_X) - 0.4) <= 1e-12, "lands at %.17g", get_real(c, VR_X));
    fmi2FreeFMUstate(c, &s);
    fmi2FreeInstance(c);
}

/* The shaper's memory in a state, forged entry by entry (the packing puts each ring's live
 * entries in the bytes, so a forger reaches them): each flaw refused by name.  A ZVD shaper
 * timed by f_mode, f_mode changed and a target commanded: both rings hold entries. */
static void run_forged_memory(void)
{
    fmi2Component c = make("forged memory");
    fmi2FMUstate s2 = NULL;
    fmi2ValueReference vr_shaper = VR_SHAPER, vr_source = VR_SHAPER_SOURCE;
    fmi2ValueReference vr_x = VR_EXECUTE;
    fmi2Integer zvd = SHAPER_ZVD, by_fmode = SHAPER_SOURCE_F_MODE;
    fmi2Boolean on = fmi2True;
    fmi2Byte *buf, *forged;
    static model_data d;
    size_t size = 0;
    fmi2FMUstate s = NULL;
    double t = 0.0;
    int k;
    CHECK(fmi2SetInteger(c, &vr_shaper, 1, &zvd) == fmi2OK, "shaper");
    CHECK(fmi2SetInteger(c, &vr_source, 1, &by_fmode) == fmi2OK, "shaper_source");
    set_real(c, VR_F_SHAPER, 7.0);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", last_message);
    for (k = 0; k < 120; k++, t += 1e-3) CHECK(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "step");
    set_real(c, VR_F_MODE, 12.0);
    set_real(c, VR_TARGET, 0.2);
    CHECK(fmi2SetBoolean(c, &vr_x, 1, &on) == fmi2OK, "execute");
    for (k = 0; k < 30; k++, t += 1e-3)
        CHECK(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "step: %s", last_message);
    CHECK(fmi2GetFMUstate(c, &s) == fmi2OK, "get");
    CHECK(fmi2SerializedFMUstateSize(c, s, &size) == fmi2OK, "size");
    buf = (fmi2Byte *)malloc(size);
    forged = (fmi2Byte *)malloc(model_state_max_size());
    CHECK(fmi2SerializeFMUstate(c, s, buf, size) == fmi2OK, "serialize");
    model_state_unpack(buf, &d);
    CHECK(d.mem.n_past >= 2 && d.mem.n_phase >= 2, "rings: %d past pieces, %d phase points",
          (int)d.mem.n_past, (int)d.mem.n_phase);
    /* the state as it is: accepted */
    CHECK(fmi2DeSerializeFMUstate(c, buf, size, &s2) == fmi2OK, "deserialize: %s", last_message);
    FORGE(d.mem.n_phase = 0, "no phase of f_mode with a shaper timed by it");
    FORGE(d.mem.past[1].k = d.mem.past[0].k, "past pieces are not in order");
    FORGE(d.mem.past[0].k = -DJL_MAX_PLAN_END - 1, "past pieces are not in order");
    FORGE(d.mem.past[0].x = NAN, "past piece of the shaper is not finite");
    FORGE(d.mem.past[1].j = INFINITY, "past piece of the shaper is not finite");
    FORGE(d.mem.phase[1].k = d.mem.phase[0].k, "phase of f_mode is not in order");
    FORGE(d.mem.phase[1].P = d.mem.phase[0].P - 1.0, "phase of f_mode is not in order");
    FORGE(d.mem.phase[0].k = DJL_MAX_PLAN_END + 1, "phase of f_mode is not in order");
    FORGE(d.mem.phase[0].P = NAN, "phase of f_mode is not finite or its rate");
    FORGE(d.mem.phase[0].rate = 0.0, "phase of f_mode is not finite or its rate");
    FORGE(d.mem.phase[0].rate = 1e-300, "phase of f_mode is not finite or its rate");
    FORGE(d.mem.phase[0].rate = 2.5, "phase of f_mode is not finite or its rate");
    /* issue 39, finding F: the oldest phase entry forged to -DBL_MAX (finite, in order), the
     * outputs re-evaluated from it (NaN) and the state resealed, as a coherent forger
     * would: the outputs equal those of the plan (NaN == NaN to memcmp) but are not finite */
    {
        int32_t cur, cs[DJL_MAX_SHAPER_IMPULSES];
        model_state_unpack(buf, &d);
        d.mem.phase[d.mem.phase_first].P = -DBL_MAX;
        cur = d.cursor;
        memcpy(cs, d.shaper_cursor, sizeof cs);
        djl_shaper_eval(&d.shaper, &d.plan, (double)d.n - d.offset + d.phase, d.offset, &d.mem,
                        0, &cur, cs, &d.out);
        d.cursor = cur;
        memcpy(d.shaper_cursor, cs, sizeof cs);
        CHECK(!isfinite(d.out.x) || !isfinite(d.out.v) || !isfinite(d.out.a),
              "the forgery of finding F gives outputs x %g, v %g, a %g", d.out.x, d.out.v,
              d.out.a);
        model_state_pack(&d, forged);
        expect_error(fmi2DeSerializeFMUstate(c, forged, model_state_size(&d), &s2),
                     "its outputs are not finite");
        expect_error(fmi2SetFMUstate(c, forged), "its outputs are not finite");
    }
    /* issue 21, fourth session (fuzz_state): f_mode itself, the input the shaper is timed
     * by, beyond what a set accepts (f_mode = DBL_MIN froze the outputs, then a change of
     * f_mode gave NaN after OK steps); at the bounds a set accepts, the state is accepted */
    FORGE(d.f_mode = DBL_MIN, "the input f_mode is outside the range its shaper allows");
    FORGE(d.f_mode = 1e-3, "the input f_mode is outside the range its shaper allows");
    FORGE(d.f_mode = 2.5 / d.p.Te, "the input f_mode is outside the range its shaper allows");
    model_state_unpack(buf, &d);
    d.f_mode = 2.0 / d.p.Te;
    model_state_pack(&d, forged);
    CHECK(fmi2SetFMUstate(c, forged) == fmi2OK, "f_mode = 2/Te: %s", last_message);
    model_state_unpack(buf, &d);
    d.f_mode = d.shaper.phase_max / (DJL_MAX_SHAPER_DELAY_SAMPLES * d.p.Te);
    model_state_pack(&d, forged);
    CHECK(fmi2SetFMUstate(c, forged) == fmi2OK, "f_mode at the window's bound: %s",
          last_message);
    /* a phase of f_mode in the state of a shaper timed by f_shaper */
    {
        fmi2Component c1 = make("forged memory, f_shaper");
        fmi2FMUstate s1 = NULL;
        fmi2Byte *buf1;
        size_t size1 = 0;
        double t1 = 0.0;
        CHECK(fmi2SetInteger(c1, &vr_shaper, 1, &zvd) == fmi2OK, "shaper");
        set_real(c1, VR_F_SHAPER, 7.0);
        CHECK(fmi2EnterInitializationMode(c1) == fmi2OK && fmi2ExitInitializationMode(c1) ==
              fmi2OK, "init: %s", last_message);
        for (k = 0; k < 30; k++, t1 += 1e-3) fmi2DoStep(c1, t1, 1e-3, fmi2True);
        CHECK(fmi2GetFMUstate(c1, &s1) == fmi2OK &&
              fmi2SerializedFMUstateSize(c1, s1, &size1) == fmi2OK, "get");
        buf1 = (fmi2Byte *)malloc(size1);
        CHECK(fmi2SerializeFMUstate(c1, s1, buf1, size1) == fmi2OK, "serialize");
        model_state_unpack(buf1, &d);
        d.mem.n_phase = 1;
        d.mem.phase[0].k = 0;
        d.mem.phase[0].P = 0.0;
        d.mem.phase[0].rate = 0.007;
        model_state_pack(&d, forged);
        expect_error(fmi2DeSerializeFMUstate(c1, forged, model_state_size(&d), &s2),
                     "a phase of f_mode with a shaper timed for f_shaper");
        free(buf1);
        fmi2FreeFMUstate(c1, &s1);
        fmi2FreeInstance(c1);
    }
    still_usable(c, t);
    fmi2FreeFMUstate(c, &s);
    fmi2FreeFMUstate(c, &s2);
    free(buf);
    free(forged);
    fmi2FreeInstance(c);
}

/* Commanded moves (issue #12): inputs in Step Mode, f_mode changing at every step
 * with jerk_source = 2, an execute, a stop, another execute, bad inputs refused
 * naming them (the instance goes on), FMU state in the middle of a commanded move
 * replays bit for bit, and the move ends exactly on its target at rest. */
static void set_bool(fmi2Component c, fmi2ValueReference vr, int v)
{
    fmi2Boolean b = v ? fmi2True : fmi2False;
    CHECK(fmi2SetBoolean(c, &vr, 1, &b) == fmi2OK, "set boolean %u", vr);
}

static int get_int(fmi2Component c, fmi2ValueReference vr)
{
    fmi2Integer v = -1;
    CHECK(fmi2GetInteger(c, &vr, 1, &v) == fmi2OK, "get integer %u", vr);
    return (int)v;
}

static int get_bool(fmi2Component c, fmi2ValueReference vr)
{
    fmi2Boolean v = fmi2False;
    CHECK(fmi2GetBoolean(c, &vr, 1, &v) == fmi2OK, "get boolean %u", vr);
    return v == fmi2True;
}

static void run_commands(int jerk_source)
{
    fmi2Component c = make("commands");
    fmi2ValueReference vjs = VR_JERK_SOURCE, vp = VR_PROFILE, vt = VR_TARGET, vf = VR_F_MODE;
    fmi2Integer two = jerk_source, four = 4, one = 1;
    fmi2FMUstate s = NULL;
    double t = 0.0, x1[300], x2[300], t_saved = 0.0, bad;
    int k, stages = 0;
    CHECK(fmi2SetInteger(c, &vjs, 1, &two) == fmi2OK, "jerk_source");
    set_real(c, VR_DISTANCE, 0.3);
    set_real(c, VR_V_MAX, 0.5);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
    CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit: %s", last_message);
    for (k = 0; k < 2500; k++, t += 1e-3) {
        double f = 9.0 + 3.0 * sin(k / 40.0), v;
        set_real(c, VR_F_MODE, f);
        if (k == 200 || k == 520) {
            set_real(c, VR_TARGET, k == 200 ? 0.12 : -0.2);
            set_bool(c, VR_EXECUTE, 1);
        }
        if (k == 201 || k == 521) set_bool(c, VR_EXECUTE, 0);
        if (k == 380) set_bool(c, VR_STOP, 1);
        if (k == 381) set_bool(c, VR_STOP, 0);
        if (k == 600) {
            /* bad values: f_mode refused naming it, nothing changed; a NaN target is taken
             * and its command refused at the edge (cmd_error, issue 34) */
            bad = NAN;
            CHECK(fmi2SetReal(c, &vt, 1, &bad) == fmi2OK, "a NaN target is taken");
            CHECK(isnan(get_real(c, VR_TARGET)), "target reads back NaN");
            set_bool(c, VR_EXECUTE, 1);
            bad = -1.0;
            expect_error(fmi2SetReal(c, &vf, 1, &bad), "f_mode");
            bad = 1e6; /* a period of 1 us: below Te/2 */
            expect_error(fmi2SetReal(c, &vf, 1, &bad), "f_mode");
            CHECK(get_real(c, VR_F_MODE) == f, "the previous values are kept");
        }
        if (k == 601) {
            CHECK(get_bool(c, VR_CMD_ERROR) && get_int(c, VR_CMD_ERROR_ID) == CMD_ERR_TARGET,
                  "the execute to a NaN target is refused: cmd_error %d, id %d",
                  get_bool(c, VR_CMD_ERROR), get_int(c, VR_CMD_ERROR_ID));
            set_bool(c, VR_EXECUTE, 0);
            set_real(c, VR_TARGET, -0.2);
        }
        if (k == 700) {
            CHECK(fmi2GetFMUstate(c, &s) == fmi2OK && s, "get state");
            t_saved = t;
        }
        CHECK(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "step %d: %s", k, last_message);
        v = get_real(c, VR_V);
        CHECK(isfinite(get_real(c, VR_X)) && fabs(v) <= 0.5 * (1 + 1e-12), "step %d: v %g", k, v);
        CHECK(get_bool(c, VR_BUSY) == !get_bool(c, VR_DONE), "busy is not done");
        stages |= 1 << get_int(c, VR_STAGE);
        if (k >= 700 && k < 1000) x1[k - 700] = get_real(c, VR_X);
    }
    CHECK(fabs(get_real(c, VR_X) + 0.2) <= 1e-9 * 0.5 && get_real(c, VR_V) == 0.0 &&
              get_real(c, VR_A) == 0.0 && !get_bool(c, VR_BUSY) && get_int(c, VR_STAGE) == 0,
          "the last move ends on -0.2 at rest: x %.17g", get_real(c, VR_X));
    CHECK(stages == 0x1f, "every stage 0..4 seen (%x)", stages);
    /* the state saved in the middle replays bit for bit (f_mode as it was) */
    CHECK(fmi2SetFMUstate(c, s) == fmi2OK, "set state");
    for (k = 700, t = t_saved; k < 1000; k++, t += 1e-3) {
        set_real(c, VR_F_MODE, 9.0 + 3.0 * sin(k / 40.0));
        CHECK(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "replay step");
        x2[k - 700] = get_real(c, VR_X);
    }
    CHECK(memcmp(x1, x2, sizeof x1) == 0, "replay differs");
    fmi2FreeFMUstate(c, &s);
    fmi2FreeInstance(c);
    /* jerk_source out of range, or 2 with AL: refused at initialisation, naming it */
    c = make("commands-bad");
    CHECK(fmi2SetInteger(c, &vjs, 1, &four) == fmi2OK, "jerk_source 4 is set");
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
    expect_error(fmi2ExitInitializationMode(c), "jerk_source = 4");
    fmi2FreeInstance(c);
    c = make("commands-al");
    CHECK(fmi2SetInteger(c, &vjs, 1, &two) == fmi2OK && fmi2SetInteger(c, &vp, 1, &one) == fmi2OK,
          "AL");
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
    expect_error(fmi2ExitInitializationMode(c), "with profile = 1 (AL)");
    fmi2FreeInstance(c);
}

/* Every entry point of the FMI 2 API that this co-simulation FMU does not provide, and
 * the status getters: each refuses with fmi2Error and a message naming it (the
 * instance then in the Error state, Reset brings it back), or answers as the standard
 * says; the version strings; Instantiate's refusals (issue 21: found uncovered). */
static void run_entry_points(void)
{
    fmi2Component c = ready("entry");
    fmi2ValueReference vr = VR_X;
    fmi2Real r = 0.0;
    fmi2Integer i = 0;
    fmi2Boolean b = fmi2True;
    fmi2Status st = fmi2Error;
    fmi2String str = "x";
    fmi2EventInfo ev;
    fmi2CallbackFunctions nolog = {NULL, calloc, free, NULL, NULL};
    CHECK(strcmp(fmi2GetVersion(), "2.0") == 0, "version %s", fmi2GetVersion());
    CHECK(strcmp(fmi2GetTypesPlatform(), "default") == 0, "types platform");
    CHECK(fmi2GetStatus(c, fmi2DoStepStatus, &st) == fmi2OK && st == fmi2OK, "status");
    CHECK(fmi2GetBooleanStatus(c, fmi2Terminated, &b) == fmi2OK && b == fmi2False, "terminated");
    CHECK(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &r) == fmi2OK && r == 0.0, "last time");
    CHECK(fmi2GetString(c, &vr, 0, &str) == fmi2OK && fmi2SetString(c, &vr, 0, &str) == fmi2OK,
          "no strings asked");
    CHECK(fmi2SetRealInputDerivatives(c, &vr, 0, &i, &r) == fmi2OK &&
          fmi2GetRealOutputDerivatives(c, &vr, 0, &i, &r) == fmi2OK, "no derivatives asked");
#define REFUSED(call, fragment)                                                                  \
    do {                                                                                         \
        expect_error(call, fragment);                                                            \
        CHECK(fmi2Reset(c) == fmi2OK, "reset after %s", fragment);                              \
        CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK &&          \
              fmi2EnterInitializationMode(c) == fmi2OK &&                                        \
              fmi2ExitInitializationMode(c) == fmi2OK, "init after %s", fragment);                \
    } while (0)
    REFUSED(fmi2GetRealStatus(c, fmi2DoStepStatus, &r), "only fmi2LastSuccessfulTime");
    REFUSED(fmi2GetBooleanStatus(c, fmi2DoStepStatus, &b), "only fmi2Terminated");
    REFUSED(fmi2GetIntegerStatus(c, fmi2DoStepStatus, &i), "no integer status");
    REFUSED(fmi2GetStringStatus(c, fmi2DoStepStatus, &str), "no string status");
    REFUSED(fmi2CancelStep(c), "never returns fmi2Pending");
    REFUSED(fmi2GetString(c, &vr, 1, &str), "has no String");
    REFUSED(fmi2SetString(c, &vr, 1, &str), "has no String");
    REFUSED(fmi2SetRealInputDerivatives(c, &vr, 1, &i, &r), "input derivatives are not used");
    REFUSED(fmi2GetRealOutputDerivatives(c, &vr, 1, &i, &r), "fmi2GetRealOutputDerivatives");
    REFUSED(fmi2GetDirectionalDerivative(c, &vr, 1, &vr, 1, &r, &r), "co-simulation only");
    REFUSED(fmi2EnterEventMode(c), "fmi2EnterEventMode is not supported");
    REFUSED(fmi2NewDiscreteStates(c, &ev), "fmi2NewDiscreteStates is not supported");
    REFUSED(fmi2EnterContinuousTimeMode(c), "fmi2EnterContinuousTimeMode is not supported");
    REFUSED(fmi2CompletedIntegratorStep(c, fmi2True, &b, &b), "fmi2CompletedIntegratorStep");
    REFUSED(fmi2SetTime(c, 0.0), "fmi2SetTime is not supported");
    REFUSED(fmi2SetContinuousStates(c, &r, 1), "fmi2SetContinuousStates is not supported");
    REFUSED(fmi2GetDerivatives(c, &r, 1), "fmi2GetDerivatives is not supported");
    REFUSED(fmi2GetEventIndicators(c, &r, 1), "fmi2GetEventIndicators is not supported");
    REFUSED(fmi2GetContinuousStates(c, &r, 1), "fmi2GetContinuousStates is not supported");
    REFUSED(fmi2GetNominalsOfContinuousStates(c, &r, 1), "fmi2GetNominalsOfContinuousStates");
#undef REFUSED
    CHECK(fmi2EnterEventMode(NULL) == fmi2Error, "NULL instance");
    /* debug logging: every category (none named), an unknown one (a warning) */
    CHECK(fmi2SetDebugLogging(c, fmi2True, 0, NULL) == fmi2OK, "logging on");
    {
        fmi2String cats[1] = {"noSuchCategory"};
        /* (the warning is a logStatusWarning message: filtered out, as only the named,
         * unknown, category is on) */
        CHECK(fmi2SetDebugLogging(c, fmi2True, 1, cats) == fmi2Warning, "unknown category");
    }
    /* a damaged state given to be overwritten (get) or filled (deserialise): refused */
    {
        fmi2FMUstate s = NULL, s2 = NULL;
        size_t size = 0;
        fmi2Byte *buf;
        CHECK(fmi2GetFMUstate(c, &s) == fmi2OK, "get");
        CHECK(fmi2SerializedFMUstateSize(c, s, &size) == fmi2OK, "size");
        buf = (fmi2Byte *)malloc(size);
        CHECK(fmi2SerializeFMUstate(c, s, buf, size) == fmi2OK, "serialize");
        {
            int64_t n; /* the checksum no longer holds */
            memcpy(&n, (char *)s + offsetof(model_data, n), 8);
            n += 1;
            memcpy((char *)s + offsetof(model_data, n), &n, 8);
        }
        s2 = s;
        expect_error(fmi2GetFMUstate(c, &s2), "state to overwrite");
        expect_error(fmi2SerializedFMUstateSize(c, s, &size), "fmi2SerializedFMUstateSize: FMU "
                     "state damaged"); /* a size is read from a checked state only */
        CHECK(fmi2Reset(c) == fmi2OK && fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) == fmi2OK &&
              fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK,
              "init");
        expect_error(fmi2DeSerializeFMUstate(c, buf, size, &s2), "state to overwrite");
        CHECK(fmi2Reset(c) == fmi2OK && fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) == fmi2OK &&
              fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK,
              "init");
        fmi2FreeFMUstate(c, &s);
        free(buf);
    }
    /* the outputs read with a parameter (the general path, not the per-step fast one),
     * and each read first in initialisation mode (before the plan exists): the same values */
    {
        fmi2ValueReference outs[8] = {VR_X, VR_V, VR_A, VR_J, VR_X_AL, VR_V_AL, VR_A_AL, VR_TE};
        double mixed[8], one;
        int k;
        CHECK(fmi2DoStep(c, 0.0, 0.05, fmi2True) == fmi2OK, "step");
        CHECK(fmi2GetReal(c, outs, 8, mixed) == fmi2OK, "mixed read");
        for (k = 0; k < 7; k++)
            CHECK(fmi2GetReal(c, &outs[k], 1, &one) == fmi2OK && one == mixed[k], "output %d", k);
        for (k = 0; k < 7; k++) {
            CHECK(fmi2Reset(c) == fmi2OK && fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0) == fmi2OK &&
                  fmi2EnterInitializationMode(c) == fmi2OK, "init");
            CHECK(fmi2GetReal(c, &outs[k], 1, &one) == fmi2OK && isfinite(one) &&
                  (k != 0 || one == 0.0), "output %d at the start: %g", k, one);
            CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit");
        }
    }
    still_usable(c, 0.0);
    fmi2FreeInstance(c);
    /* Instantiate: an empty name, model exchange, another GUID: NULL, with a message */
    last_message[0] = '\0';
    CHECK(fmi2Instantiate("", fmi2CoSimulation, DJL_INSTANTIATION_TOKEN, "", &cb, 0, 0) == NULL &&
          strstr(last_message, "non-empty") != NULL, "empty name: %s", last_message);
    CHECK(fmi2Instantiate("me", fmi2ModelExchange, DJL_INSTANTIATION_TOKEN, "", &cb, 0, 0) ==
          NULL && strstr(last_message, "co-simulation only") != NULL, "model exchange");
    CHECK(fmi2Instantiate("g", fmi2CoSimulation, "{0}", "", &cb, 0, 0) == NULL &&
          strstr(last_message, "GUID") != NULL, "GUID");
    CHECK(fmi2Instantiate("", fmi2CoSimulation, DJL_INSTANTIATION_TOKEN, "", &nolog, 0, 0) ==
          NULL, "without a logger");
}

/* Issue 21 (A): a replanned move reported done off its target when v_max was huge (the
 * arrival tolerance grew with v_max Te).  Steps of 0.4 s, then on to rest: done only on
 * the target, to a few ulps. */
static double land_on(fmi2Component c, double target, double t, const char *what)
{
    int k;
    double x;
    k = 0;
    do { /* at least one step: a command acts from the next */
        CHECK(fmi2DoStep(c, t, 0.4, fmi2True) == fmi2OK, "%s: step: %s", what, last_message);
        t += 0.4;
    } while (++k < 200 && !get_bool(c, VR_DONE));
    x = get_real(c, VR_X);
    CHECK(get_bool(c, VR_DONE) && !get_bool(c, VR_BUSY) && get_real(c, VR_V) == 0.0 &&
              get_real(c, VR_A) == 0.0, "%s: not at rest", what);
    CHECK(fabs(x - target) <= 4.0 * DBL_EPSILON * fabs(target), "%s: done at x = %.17g, not %.17g",
          what, x, target);
    return t;
}

static void run_issue21_landing(void)
{
    static const double targets[2] = {7e-4, 16.0};
    fmi2Component c;
    fmi2ValueReference vjs = VR_JERK_SOURCE, vp = VR_PROFILE;
    fmi2Integer three = 3, al = 1;
    double t;
    int i;
    /* the default move with v_max = 1e300, a new target with an execute edge, one step */
    for (i = 0; i < 2; i++) {
        c = make("issue21-a");
        set_real(c, VR_V_MAX, 1e300);
        CHECK(fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK,
              "init");
        set_real(c, VR_TARGET, targets[i]);
        set_bool(c, VR_EXECUTE, 1);
        CHECK(fmi2DoStep(c, 0.0, 0.4, fmi2True) == fmi2OK, "step: %s", last_message);
        CHECK(!get_bool(c, VR_DONE) || fabs(get_real(c, VR_X) - targets[i]) <= 1e-18 +
              4.0 * DBL_EPSILON * targets[i], "done off the target: x = %.17g",
              get_real(c, VR_X));
        land_on(c, targets[i], 0.4, i ? "v_max 1e300, target 16" : "v_max 1e300, target 7e-4");
        fmi2FreeInstance(c);
    }
    /* jerk_source 3, f_mode changed, no command: the parametric 0.3 m move (rested at 0.105
     * or 0.119 before) */
    c = make("issue21-js3");
    CHECK(fmi2SetInteger(c, &vjs, 1, &three) == fmi2OK, "jerk_source");
    set_real(c, VR_DISTANCE, 0.3);
    set_real(c, VR_V_MAX, 1e300);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK,
          "init");
    set_real(c, VR_F_MODE, 5.0);
    CHECK(fmi2DoStep(c, 0.0, 0.05, fmi2True) == fmi2OK, "step");
    set_real(c, VR_F_MODE, 13.0);
    land_on(c, 0.3, 0.05, "jerk_source 3, f_mode 5 -> 13");
    fmi2FreeInstance(c);
    /* AL, v_max = 3.4e9: a new target in the middle of the move, then one 3e-8 m past the
     * rest (taken for arrived before: 3e-8 < 1e-12 v_max Te) */
    c = make("issue21-al");
    CHECK(fmi2SetInteger(c, &vp, 1, &al) == fmi2OK, "AL");
    set_real(c, VR_V_MAX, 3.4e9);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK,
          "init");
    CHECK(fmi2DoStep(c, 0.0, 0.1, fmi2True) == fmi2OK, "step");
    set_real(c, VR_TARGET, 0.05);
    set_bool(c, VR_EXECUTE, 1);
    t = land_on(c, 0.05, 0.1, "AL, v_max 3.4e9, target 0.05");
    set_bool(c, VR_EXECUTE, 0);
    CHECK(fmi2DoStep(c, t, 0.1, fmi2True) == fmi2OK, "step: %s", last_message);
    set_real(c, VR_TARGET, 0.05 + 3e-8);
    set_bool(c, VR_EXECUTE, 1);
    land_on(c, 0.05 + 3e-8, t + 0.1, "AL, v_max 3.4e9, 3e-8 m on");
    fmi2FreeInstance(c);
}

/* Stops that take 10^15 samples and more: AL cruising at 93 m/s (a case of compare_builds,
 * issue 21).  With d_max = 3e-27 m/s^2 the stop would end past DJL_MAX_PLAN_END: it used to
 * be planned over 10^15 samples (decelerating above d_max), and the FMU then refused its own
 * FMU state ("the motion end is out of range"); it is refused now (naming d_max, nothing
 * done).  With d_max = 3.26e-10 m/s^2 it takes 1.5e15 samples, past the FMU's horizon but
 * not past DJL_MAX_PLAN_END: it is planned at d_max (before: squeezed into 10^15 samples
 * at 4.9e-10 m/s^2, and its state refused).  Either way the state is accepted. */
static void run_issue21_long_stops(void)
{
    static const double dmax[2] = {2.9574595199869485e-27, 3.26e-10};
    fmi2ValueReference vp = VR_PROFILE;
    fmi2Integer al = 1;
    int i, k;
    for (i = 0; i < 2; i++) {
        fmi2Component c = make("issue21-stop");
        fmi2FMUstate s = NULL, s2 = NULL;
        fmi2Byte *buf;
        size_t size = 0;
        double t = 0.0, x;
        CHECK(fmi2SetInteger(c, &vp, 1, &al) == fmi2OK, "AL");
        set_real(c, VR_TE, 0.00019057090891615758);
        set_real(c, VR_X0, 1503.3588308745057);
        set_real(c, VR_DISTANCE, 1437.0273942781971);
        set_real(c, VR_V_E, 93.074781997001764);
        set_real(c, VR_V_MAX, 191.59645464440737);
        set_real(c, VR_A_MAX, 3738.1078240590796);
        set_real(c, VR_D_MAX, dmax[i]);
        CHECK(fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK,
              "init: %s", last_message);
        for (k = 0; k < 100; k++, t += 0.02)
            CHECK(fmi2DoStep(c, t, 0.02, fmi2True) == fmi2OK, "step: %s", last_message);
        x = get_real(c, VR_X);
        set_bool(c, VR_STOP, 1);
        if (i == 0) {
            /* refused at its edge (issue 34): the step OK, cmd_error, the cruise goes on */
            double v = get_real(c, VR_V);
            CHECK(fmi2DoStep(c, t, 0.02, fmi2True) == fmi2OK, "refused stop: %s", last_message);
            CHECK(strstr(last_message, "takes too long") != NULL &&
                  strstr(last_message, "d_max") != NULL, "message: %s", last_message);
            CHECK(get_bool(c, VR_CMD_ERROR) && get_int(c, VR_CMD_ERROR_ID) == CMD_ERR_NO_MOTION,
                  "cmd_error after a stop that cannot be made");
            CHECK(get_real(c, VR_V) == v && fabs(get_real(c, VR_X) - (x + v * 0.02)) <=
                  1e-12 * fabs(x), "a refused stop changed the cruise");
        } else {
            CHECK(fmi2DoStep(c, t, 0.02, fmi2True) == fmi2OK, "long stop: %s", last_message);
            CHECK(fabs(get_real(c, VR_A)) <= dmax[i] * (1.0 + 1e-9),
                  "the stop decelerates at %.17g m/s2, above d_max", get_real(c, VR_A));
        }
        CHECK(fmi2GetFMUstate(c, &s) == fmi2OK, "get state: %s", last_message);
        CHECK(fmi2SerializedFMUstateSize(c, s, &size) == fmi2OK, "size");
        buf = (fmi2Byte *)malloc(size);
        CHECK(buf != NULL, "malloc");
        CHECK(fmi2SerializeFMUstate(c, s, buf, size) == fmi2OK, "serialise: %s", last_message);
        CHECK(fmi2DeSerializeFMUstate(c, buf, size, &s2) == fmi2OK, "deserialise: %s",
              last_message);
        CHECK(fmi2SetFMUstate(c, s2) == fmi2OK, "set: %s", last_message);
        set_bool(c, VR_STOP, 0);
        CHECK(fmi2DoStep(c, t + 0.02, 0.02, fmi2True) == fmi2OK, "step on: %s", last_message);
        free(buf);
        fmi2FreeFMUstate(c, &s);
        fmi2FreeFMUstate(c, &s2);
        fmi2FreeInstance(c);
    }
}

/* Issue 39, finding C: damage the checksum must see.  A state mid-motion (a ZVD shaper
 * timed by f_mode after a commanded target: both rings in use), then
 *  - every single-bit flip of 512 words spread over the state,
 *  - every pair of flips among bits 56..63 of 64 words (the top bytes: FNV-1a without a
 *    rotation let two flipped bit 63 cancel),
 *  - the finding's own: the sign bits of the target and of an unused 0.0 flipped,
 *  - n_random random damages of 2 to 8 words (a random word, bits or bytes changed),
 * each compared with the seal (model_state_checksum against the stored sum; the finding's
 * also through fmi2DeSerializeFMUstate): none may be accepted. */
static void run_checksum_damage(long n_random)
{
    fmi2Component c = make("checksum");
    fmi2FMUstate s = NULL, s2 = NULL;
    fmi2Byte *buf, *work;
    size_t size = 0, n_words, w, k, i, j;
    uint64_t stored;
    long accepted = 0, tried = 0, it;
    double t = 0.0;
    set_int(c, VR_SHAPER, SHAPER_ZVD);
    set_real(c, VR_F_SHAPER, 7.0);
    set_int(c, VR_SHAPER_SOURCE, SHAPER_SOURCE_F_MODE);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK,
          "init: %s", last_message);
    for (k = 0; k < 120; k++, t += 1e-3) fmi2DoStep(c, t, 1e-3, fmi2True);
    set_real(c, VR_F_MODE, 12.0);
    set_real(c, VR_TARGET, 0.3);
    set_bool(c, VR_EXECUTE, 1);
    for (k = 0; k < 30; k++, t += 1e-3) fmi2DoStep(c, t, 1e-3, fmi2True);
    CHECK(fmi2GetFMUstate(c, &s) == fmi2OK && fmi2SerializedFMUstateSize(c, s, &size) == fmi2OK,
          "state: %s", last_message);
    buf = (fmi2Byte *)malloc(size);
    work = (fmi2Byte *)malloc(size);
    CHECK(buf && work && fmi2SerializeFMUstate(c, s, buf, size) == fmi2OK, "serialise");
    memcpy(&stored, buf + offsetof(model_data, checksum), 8);
    CHECK(stored == model_state_checksum(buf, size), "the seal");
    n_words = size / 8;
#define DAMAGE_SEEN() (memcpy(&stored, work + offsetof(model_data, checksum), 8), \
                       tried++, accepted += stored == model_state_checksum(work, size))
    for (i = 0; i < 512; i++) { /* every single-bit flip of 512 words */
        w = (i * n_words) / 512;
        if (w * 8 == offsetof(model_data, checksum)) continue;
        for (k = 0; k < 64; k++) {
            memcpy(work, buf, size);
            work[w * 8 + k / 8] ^= (fmi2Byte)(1u << (k % 8));
            DAMAGE_SEEN();
        }
    }
    for (i = 0; i < 64 * 8; i++) /* every pair of flips in bits 56..63 of 64 words */
        for (j = i + 1; j < 64 * 8; j++) {
            size_t wi = ((i / 8) * n_words) / 64, wj = ((j / 8) * n_words) / 64;
            if (wi * 8 == offsetof(model_data, checksum) ||
                wj * 8 == offsetof(model_data, checksum))
                continue;
            memcpy(work, buf, size);
            work[wi * 8 + 7] ^= (fmi2Byte)(1u << (i % 8)); /* little-endian: byte 7 holds */
            work[wj * 8 + 7] ^= (fmi2Byte)(1u << (j % 8)); /* bits 56..63 */
            DAMAGE_SEEN();
        }
    for (it = 0; it < n_random; it++) { /* random damage of 2 to 8 words */
        int n = 2 + (int)(next_rand() % 7), q;
        memcpy(work, buf, size);
        for (q = 0; q < n; q++) {
            size_t at = (size_t)(next_rand() % n_words) * 8;
            uint64_t x;
            if (at == offsetof(model_data, checksum)) at += 8;
            memcpy(&x, work + at, 8);
            x ^= next_rand() % 2 ? (uint64_t)1 << (next_rand() % 64) : next_rand() | 1u;
            memcpy(work + at, &x, 8);
        }
        if (memcmp(work, buf, size) != 0) DAMAGE_SEEN();
    }
#undef DAMAGE_SEEN
    CHECK(accepted == 0, "%ld of %ld damaged states pass the checksum", accepted, tried);
    printf("fmi2 checksum: %ld damaged states (single bits of 512 words, pairs of top-byte bits "
           "of 64 words, %ld random damages of 2-8 words): %ld accepted\n", tried, n_random,
           accepted);
    { /* the finding: target 0.3 -> -0.3 and an unused 0.0 -> -0.0 */
        static model_data d;
        size_t at_t = offsetof(model_data, target) + 7, at_z = offsetof(model_data, cmd) + 7;
        model_state_unpack(buf, &d);
        CHECK(d.target == 0.3 && d.cmd.v_max == 0.0, "the finding's two doubles");
        memcpy(work, buf, size);
        work[at_t] ^= 0x80;
        work[at_z] ^= 0x80;
        expect_error(fmi2DeSerializeFMUstate(c, work, size, &s2), "checksum mismatch");
    }
    free(buf);
    free(work);
    fmi2FreeFMUstate(c, &s);
    fmi2FreeInstance(c);
}

/* Issue 34: a state holding a queue (a blending and two buffered commands waiting behind a
 * move) round-trips and replays; each field of the queue changed to what no edge makes,
 * resealed, is refused naming what is wrong. */
static void run_forged_queue(void)
{
    static model_data d;
    fmi2Component c = make("forged-queue");
    fmi2FMUstate s = NULL, s2 = NULL;
    fmi2Byte *buf, *forged;
    size_t size = 0;
    double t = 0.0;
    int i;
    static const double tg[4] = {0.3, 0.5, 0.2, 0.25};
    static const int mode[4] = {0, 2, 1, 1};
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK,
          "init: %s", last_message);
    for (i = 0; i < 4; i++) {
        set_int(c, VR_BUFFER_MODE, mode[i]);
        set_real(c, VR_TARGET, tg[i]);
        set_bool(c, VR_EXECUTE, 1);
        CHECK(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "edge %d: %s", i, last_message);
        t += 1e-3;
        set_bool(c, VR_EXECUTE, 0);
        CHECK(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "step %d: %s", i, last_message);
        t += 1e-3;
    }
    CHECK(get_bool(c, VR_CMD_ERROR) == 0, "every command accepted: %s", last_message);
    CHECK(fmi2GetFMUstate(c, &s) == fmi2OK, "get state: %s", last_message);
    CHECK(fmi2SerializedFMUstateSize(c, s, &size) == fmi2OK, "size");
    buf = (fmi2Byte *)malloc(size);
    forged = (fmi2Byte *)malloc(model_state_max_size());
    CHECK(buf != NULL && forged != NULL, "malloc");
    CHECK(fmi2SerializeFMUstate(c, s, buf, size) == fmi2OK, "serialise: %s", last_message);
    CHECK(fmi2DeSerializeFMUstate(c, buf, size, &s2) == fmi2OK, "its own state: %s",
          last_message);
    model_state_unpack(buf, &d);
    CHECK(d.queue_n == 3 && d.n_commands == 4 && d.running_id == 1, "the queue: %d waiting, "
          "%lld commands, running %lld", (int)d.queue_n, (long long)d.n_commands,
          (long long)d.running_id);
    FORGE(d.queue_n = MODEL_QUEUE_CAPACITY + 1, "queue's length");
    FORGE(d.queue_first = -1, "queue's length or first entry");
    FORGE(d.queue[d.queue_first].buffer_mode = 0, "neither buffered nor blending");
    FORGE(d.queue[d.queue_first].target = NAN, "waiting command's target");
    FORGE(d.queue[d.queue_first].min_duration = -1.0, "waiting command's min_duration");
    FORGE(d.queue[d.queue_first].cmd.v_max = -2.0, "waiting command's limits");
    FORGE(d.queue[d.queue_first].cmd.shaper = 9, "waiting command's profile or shaper");
    FORGE(d.queue[d.queue_first].cmd.T_F[2] = 1e-9, "waiting command's jerk time");
    FORGE(d.queue[d.queue_first].cmd.delay[7] = INFINITY, "shaper impulse is not finite");
    FORGE(d.queue[d.queue_first + 1].id = d.queue[d.queue_first].id, "id is out of order");
    FORGE(d.running_id = d.n_commands + 1, "command count");
    FORGE(d.command_aborted = 2, "command_aborted");
    FORGE(d.cmd_error_id = CMD_ERR_QUEUE_FULL + 1, "cmd_error_id");
    /* its own state replays: the queue runs to the last target */
    CHECK(fmi2SetFMUstate(c, s2) == fmi2OK, "set its own state: %s", last_message);
    for (i = 0; i < 6000 && !get_bool(c, VR_DONE); i++, t += 1e-3)
        CHECK(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "step %d: %s", i, last_message);
    CHECK(get_bool(c, VR_DONE) && fabs(get_real(c, VR_X) - 0.25) <= 1e-12,
          "the queue ran to 0.25 m: x = %.17g", get_real(c, VR_X));
    free(buf);
    free(forged);
    fmi2FreeFMUstate(c, &s);
    fmi2FreeFMUstate(c, &s2);
    fmi2FreeInstance(c);
}

/* Issue 21, FMI run 11 (tests/fuzz/corpus/fmi/crash-36b2..., -44f5..., -c866...): a state
 * whose plan.level0 was forged from 0 to 0.56 m/s2 and resealed passed every check of a
 * value against its limit; a stop replanned from it ended a stage that was not running,
 * and an OK step then output v = -1.0129 m/s with v_max = 1 m/s.  The scenario: jerk_source
 * 3, a ZV shaper at 12 Hz, the 0.3 m move done, a target of -0.2 m executed at 40.671 s,
 * a stop at 40.8614375 s.  Its true state is accepted and the stop stays within the
 * limits; the forged one, and any one value of the plan changed within its limits, is
 * refused for what no longer agrees. */
static void run_issue21_forged_plan(void)
{
    static const double h[5] = {0.0024375, 0.086, 0.008, 0.086, 0.008};
    static model_data d;
    fmi2ValueReference vjs = VR_JERK_SOURCE, vsh = VR_SHAPER;
    fmi2Integer three = 3, zv = SHAPER_ZV;
    fmi2Component c = make("issue21-forged-plan");
    fmi2FMUstate s = NULL, s2 = NULL;
    fmi2Byte *buf, *forged;
    size_t size = 0;
    double t = 40.671, vpeak = 0.0, apeak = 0.0;
    int i, q, piece;
    CHECK(fmi2SetInteger(c, &vjs, 1, &three) == fmi2OK, "jerk_source");
    CHECK(fmi2SetInteger(c, &vsh, 1, &zv) == fmi2OK, "shaper");
    set_real(c, VR_DISTANCE, 0.3);
    set_real(c, VR_F_SHAPER, 12.0);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK,
          "init: %s", last_message);
    CHECK(fmi2DoStep(c, 0.0, t, fmi2True) == fmi2OK, "the move: %s", last_message);
    set_real(c, VR_TARGET, -0.2);
    set_bool(c, VR_EXECUTE, 1);
    for (i = 0; i < 5; t += h[i], i++)
        CHECK(fmi2DoStep(c, t, h[i], fmi2True) == fmi2OK, "step %d: %s", i, last_message);
    set_bool(c, VR_STOP, 1);
    CHECK(fmi2GetFMUstate(c, &s) == fmi2OK, "get state: %s", last_message);
    CHECK(fmi2SerializedFMUstateSize(c, s, &size) == fmi2OK, "size");
    buf = (fmi2Byte *)malloc(size);
    forged = (fmi2Byte *)malloc(model_state_max_size());
    CHECK(buf != NULL && forged != NULL, "malloc");
    CHECK(fmi2SerializeFMUstate(c, s, buf, size) == fmi2OK, "serialise: %s", last_message);
    CHECK(fmi2DeSerializeFMUstate(c, buf, size, &s2) == fmi2OK, "its own state: %s",
          last_message);
    model_state_unpack(buf, &d);
    CHECK(d.plan.replanned == 1 && d.plan.level0 == 0.0, "the plan of the finding: replanned "
          "%d, level0 %.17g", (int)d.plan.replanned, d.plan.level0);
    /* the forged state of the finding, and values of the plan changed within their limits */
    FORGE(d.plan.level0 = 0.56, "AL acceleration is not that of the plan's steps");
    FORGE(d.plan.level0 = -1e-3, "AL acceleration is not that of the plan's steps");
    for (q = 0; q < d.plan.n_steps && d.plan.step[q].N == 0; q++) continue;
    CHECK(q < d.plan.n_steps, "a ramp in the plan");
    FORGE(d.plan.step[q].A *= 1.01, "not that of the plan's steps");
    FORGE(d.plan.step[q].tau += 1, "not that of the plan's steps");
    FORGE(d.plan.step[q].N += 1, "jerk is not that of the plan's steps");
    for (piece = 1; piece + 1 < d.plan.n_pieces && d.plan.piece[piece].j == 0.0; piece++) continue;
    CHECK(piece + 1 < d.plan.n_pieces, "a ramp's piece inside the plan");
    FORGE(d.plan.piece[piece].a += 0.01, "acceleration is not that of the plan's steps");
    FORGE(d.plan.piece[piece].a_al += 0.01, "AL acceleration is not that of the plan's steps");
    FORGE(d.plan.piece[piece].j *= 1.001, "jerk is not that of the plan's steps");
    FORGE(d.plan.piece[piece].v += 1e-6, "does not continue the one before");
    FORGE(d.plan.piece[piece].x += 1e-9, "does not continue the one before");
    FORGE(d.plan.piece[piece].k += 1, "acceleration is not that of the plan's steps");
    /* nothing refused changed the instance: its true state stops within the limits */
    CHECK(fmi2SetFMUstate(c, s2) == fmi2OK, "set its own state: %s", last_message);
    for (i = 0; i < 2000 && !get_bool(c, VR_DONE); i++, t += 5e-4) {
        CHECK(fmi2DoStep(c, t, 5e-4, fmi2True) == fmi2OK, "stop, step %d: %s", i, last_message);
        vpeak = fmax(vpeak, fabs(get_real(c, VR_V)));
        apeak = fmax(apeak, fabs(get_real(c, VR_A)));
    }
    CHECK(get_bool(c, VR_DONE) && get_real(c, VR_V) == 0.0, "the stop comes to rest: v %.17g",
          get_real(c, VR_V));
    CHECK(vpeak <= 1.0 && vpeak > 0.9, "the stop's peak velocity %.17g m/s, v_max 1 m/s", vpeak);
    CHECK(apeak <= 10.0, "the stop's peak acceleration %.17g m/s2, a_max 10 m/s2", apeak);
    free(buf);
    free(forged);
    fmi2FreeFMUstate(c, &s);
    fmi2FreeFMUstate(c, &s2);
    fmi2FreeInstance(c);
}

/* The plan check on plans built here, independently of the planner: ramps of a moving
 * average (each step A over N samples adds A / (N Te) of jerk while it runs), the pieces
 * walked by Taylor polynomials from v0.  A plan that peaks inside a piece and one whose
 * steps do not come back to rest are refused; the same plans made sound are accepted. */
static void synthetic_plan(djl_plan *pl, double v0, int rest)
{
    /* Te = 1 s: +1 over 4 samples, -3 over 4 from 4 (a crosses 0 inside [4, 8), at 16/3),
     * +2 over 4 from 8: back to a = 0 at 12 */
    static const int64_t tau[3] = {0, 4, 8};
    static const double A[3] = {1.0, -3.0, 2.0};
    double x = 0.0, v = v0;
    int i, q;
    memset(pl, 0, sizeof *pl);
    pl->p.Te = 1.0;
    pl->n_steps = rest ? 3 : 1;
    for (q = 0; q < pl->n_steps; q++) {
        pl->step[q].tau = tau[q];
        pl->step[q].A = A[q];
        pl->step[q].N = 4;
        pl->step[q].stage = 1 + q;
    }
    pl->n_pieces = rest ? 4 : 2;
    for (i = 0; i < pl->n_pieces; i++) {
        djl_piece *pc = &pl->piece[i];
        double a = 0.0, j = 0.0, level = 0.0;
        pc->k = 4 * i;
        for (q = 0; q < pl->n_steps; q++)
            if (pc->k >= tau[q]) {
                level += A[q];
                if (pc->k < tau[q] + 4) {
                    a += A[q] * (double)(pc->k - tau[q]) / 4.0;
                    j += A[q] / 4.0;
                } else {
                    a += A[q];
                }
            }
        pc->x = x;
        pc->v = v;
        pc->a = a;
        pc->j = j;
        pc->a_al = level;
        x += 4.0 * v + 8.0 * a + 64.0 * j / 6.0;
        v += 4.0 * a + 8.0 * j;
    }
}

static void run_plan_consistency(void)
{
    static djl_plan pl;
    const char *why;
    /* v: 2.5 at 0, 4.5 at 4, peak 4.5 + 2/3 at 16/3, 2.5 at 8, -1.5 at 12 */
    synthetic_plan(&pl, 2.5, 1);
    why = model_plan_inconsistency(&pl, 5.0);
    CHECK(why != NULL && strstr(why, "peaks above v_max") != NULL,
          "a peak of 5.1667 m/s inside a piece, v_max 5: %s", why ? why : "accepted");
    CHECK(fabs(pl.piece[2].v - 2.5) < 1e-12 && fabs(pl.piece[3].v + 1.5) < 1e-12,
          "the synthetic plan's velocities %.17g %.17g", pl.piece[2].v, pl.piece[3].v);
    why = model_plan_inconsistency(&pl, 5.2);
    CHECK(why == NULL, "the same plan with v_max 5.2: %s", why);
    synthetic_plan(&pl, 0.0, 0);
    why = model_plan_inconsistency(&pl, 5.0);
    CHECK(why != NULL && strstr(why, "last piece does not cruise") != NULL,
          "a plan that ends accelerating at 1 m/s2: %s", why ? why : "accepted");
    synthetic_plan(&pl, 2.5, 1);
    pl.piece[3].x += 1e-6;
    why = model_plan_inconsistency(&pl, 5.2);
    CHECK(why != NULL && strstr(why, "does not continue") != NULL, "x off by 1e-6: %s",
          why ? why : "accepted");
}

/* ------------------------------------------------ profile 4: a replayed table */

/* A bang-bang table built here that comes back to rest: P (+J and -J over lengths of equal
 * sums, zero-jerk pieces between) then -P; its piecewise cubic integrated in long double
 * (the driver's own reference, independent of the FMU's operations). */
#define TBL_P 11
static const int tbl_len[TBL_P] = {7, 5, 10, 12, 3, 4, 5, 13, 9, 8, 6};
static const double tbl_sgn[TBL_P] = {1, 0, -1, 1, 0, -1, 1, -1, 1, 0, -1};
typedef struct {
    int n;
    int32_t samples[2 * TBL_P];
    double jerk[2 * TBL_P];
    long double k[2 * TBL_P + 1], x[2 * TBL_P + 1], v[2 * TBL_P + 1], a[2 * TBL_P + 1];
    double X, V, A, up, down;
} ref_table;

static void ref_build(ref_table *r, double J, double Te)
{
    int i;
    r->n = 2 * TBL_P;
    r->k[0] = r->x[0] = r->v[0] = r->a[0] = 0.0L;
    r->X = r->V = r->A = r->up = r->down = 0.0;
    for (i = 0; i < r->n; i++) {
        long double j, L, s;
        r->samples[i] = tbl_len[i % TBL_P];
        r->jerk[i] = (i < TBL_P ? 1.0 : -1.0) * tbl_sgn[i % TBL_P] * J;
        j = r->jerk[i];
        L = (long double)r->samples[i] * Te;
        s = j != 0.0L ? -r->a[i] / j : -1.0L;
        if (s > 0.0L && s < L)
            r->V = fmax(r->V, (double)fabsl(r->v[i] + r->a[i] * s + j * s * s / 2.0L));
        r->k[i + 1] = r->k[i] + r->samples[i];
        r->x[i + 1] = r->x[i] + r->v[i] * L + r->a[i] * L * L / 2.0L + j * L * L * L / 6.0L;
        r->v[i + 1] = r->v[i] + r->a[i] * L + j * L * L / 2.0L;
        r->a[i + 1] = r->a[i] + j * L;
        r->X = fmax(r->X, (double)fabsl(r->x[i + 1]));
        r->V = fmax(r->V, (double)fabsl(r->v[i + 1]));
        r->A = fmax(r->A, (double)fabsl(r->a[i + 1]));
        r->up = fmax(r->up, (double)r->a[i + 1]);
        r->down = fmax(r->down, (double)-r->a[i + 1]);
    }
}

/* x, v, a at u samples after the start (after the end: at rest at its end). */
static void ref_at(const ref_table *r, long double u, double Te, long double out[3])
{
    int i = 0;
    long double s;
    if (u < 0.0L) u = 0.0L;
    while (i < r->n && u >= r->k[i + 1]) i++;
    if (i == r->n) {
        out[0] = r->x[r->n];
        out[1] = out[2] = 0.0L;
        return;
    }
    s = (u - r->k[i]) * Te;
    out[0] = r->x[i] + r->v[i] * s + r->a[i] * s * s / 2.0L + r->jerk[i] * s * s * s / 6.0L;
    out[1] = r->v[i] + r->a[i] * s + r->jerk[i] * s * s / 2.0L;
    out[2] = r->a[i] + r->jerk[i] * s;
}

static void set_table(fmi2Component c, const ref_table *r, double x0, double margin)
{
    fmi2ValueReference vr[2 * TBL_P];
    fmi2Integer n[2 * TBL_P];
    int i;
    set_int(c, VR_PROFILE, PROFILE_TABLE);
    set_int(c, VR_TABLE_N, r->n);
    for (i = 0; i < r->n; i++) {
        vr[i] = VR_TABLE_SAMPLES + (fmi2ValueReference)i;
        n[i] = r->samples[i];
    }
    CHECK(fmi2SetInteger(c, vr, (size_t)r->n, n) == fmi2OK, "table_samples");
    for (i = 0; i < r->n; i++) vr[i] = VR_TABLE_JERK + (fmi2ValueReference)i;
    CHECK(fmi2SetReal(c, vr, (size_t)r->n, r->jerk) == fmi2OK, "table_jerk");
    set_real(c, VR_X0, x0);
    set_real(c, VR_DISTANCE, (double)r->x[r->n]);
    set_real(c, VR_V_MAX, r->V * (1.0 + margin));
    set_real(c, VR_A_MAX, r->up * (1.0 + margin));
    set_real(c, VR_D_MAX, r->down * (1.0 + margin));
}

/* Run a table at steps of 0.37 Te: the outputs against the driver's reference, the end
 * exactly on x0 + distance, at rest; a state mid-table replayed bit for bit; forged
 * states of a table refused by name; a stop and an execute mid-table; bad tables refused
 * at initialisation naming the entry, the instance usable after a reset. */
static void run_table(void)
{
    static model_data d;
    static ref_table r;
    const double Te = 1e-3, h = 0.37e-3, x0 = 0.25;
    fmi2Component c = make("table");
    fmi2FMUstate s = NULL, s2 = NULL;
    fmi2Byte *buf, *forged;
    size_t size = 0;
    double t = 0.0, x1[400], x2[400], dist;
    long double want[3];
    int k, n_steps, i;
    ref_build(&r, 400.0, Te);
    dist = (double)r.x[r.n];
    set_table(c, &r, x0, 1e-6);
    CHECK(fmi2EnterInitializationMode(c) == fmi2OK && fmi2ExitInitializationMode(c) == fmi2OK,
          "init: %s", last_message);
    CHECK(get_real(c, VR_MOTION_TIME) == (double)r.k[r.n] * Te, "motion_time %.17g",
          get_real(c, VR_MOTION_TIME));
    n_steps = (int)((double)r.k[r.n] / 0.37) + 20;
    for (k = 0; k < n_steps; k++, t += h) {
        double got[3];
        CHECK(fmi2DoStep(c, t, h, fmi2True) == fmi2OK, "step %d: %s", k, last_message);
        got[0] = get_real(c, VR_X);
        got[1] = get_real(c, VR_V);
        got[2] = get_real(c, VR_A);
        ref_at(&r, (long double)(k + 1) * 0.37L, Te, want);
        CHECK(fabs(got[0] - (double)(x0 + want[0])) <= 1e-12 * (r.X + x0) &&
                  fabs(got[1] - (double)want[1]) <= 1e-12 * r.V &&
                  fabs(got[2] - (double)want[2]) <= 1e-12 * r.A,
              "table at %.17g s: x %.17g v %.17g a %.17g, want %.17Lg %.17Lg %.17Lg", t + h,
              got[0], got[1], got[2], x0 + want[0], want[1], want[2]);
        if (k == n_steps / 2) CHECK(fmi2GetFMUstate(c, &s) == fmi2OK, "get state");
    }
    CHECK(get_real(c, VR_X) == x0 + dist && get_real(c, VR_V) == 0.0 &&
              get_real(c, VR_A) == 0.0 && get_real(c, VR_J) == 0.0 && get_bool(c, VR_DONE),
          "table end: x %.17g, want %.17g", get_real(c, VR_X), x0 + dist);
    /* the state mid-table, serialised and restored: the same outputs */
    CHECK(fmi2SetFMUstate(c, s) == fmi2OK, "set state: %s", last_message);
    t = 0.37e-3 * (n_steps / 2 + 1);
    for (k = 0; k < 400; k++) {
        fmi2DoStep(c, t + k * Te, Te, fmi2True);
        x1[k] = get_real(c, VR_X);
    }
    CHECK(fmi2SerializedFMUstateSize(c, s, &size) == fmi2OK, "size");
    buf = (fmi2Byte *)malloc(size);
    forged = (fmi2Byte *)malloc(model_state_max_size());
    CHECK(buf != NULL && forged != NULL, "malloc");
    CHECK(fmi2SerializeFMUstate(c, s, buf, size) == fmi2OK, "serialise");
    CHECK(fmi2DeSerializeFMUstate(c, buf, size, &s2) == fmi2OK, "deserialise: %s", last_message);
    CHECK(fmi2SetFMUstate(c, s2) == fmi2OK, "set: %s", last_message);
    for (k = 0; k < 400; k++) {
        fmi2DoStep(c, t + k * Te, Te, fmi2True);
        x2[k] = get_real(c, VR_X);
    }
    CHECK(memcmp(x1, x2, sizeof x1) == 0, "a table's state replays other outputs");
    /* forged: the table damaged, or the plan no longer the table's (checksums valid) */
    FORGE(d.table.jerk[3] = NAN, "its table is invalid");
    FORGE(d.table.jerk[0] = 1e300, "its table is invalid");
    FORGE(d.table.samples[2] = 0, "its table is invalid");
    FORGE(d.table.samples[2] = -7, "its table is invalid");
    FORGE(d.table.n = DJL_MAX_TABLE + 1, "its table is invalid");
    FORGE(d.table.n = -1, "its table is invalid");
    FORGE(d.table.n = r.n - 1, "its table is invalid"); /* no longer at rest at its end */
    /* (entries 0, 2, 3 and 5 hold a jerk, 1 and 4 none) */
    FORGE(d.table.jerk[0] *= 1.0 + 1e-13, "its plan's steps are not those of its table");
    FORGE(d.plan.step[3].A *= 1.0 + 1e-15, "its plan's steps are not those of its table");
    FORGE(d.plan.step[4].N += 1, "its plan's steps are not those of its table");
    FORGE(d.plan.step[2].stage = 3, "its plan's steps are not those of its table");
    FORGE(d.plan.piece[5].j *= 1.0 + 1e-15, "its plan's pieces are not those of its table");
    FORGE(d.plan.piece[6].k += 1, "its plan's pieces are not those of its table");
    FORGE(d.plan.piece[r.n].x += 1e-9, "does not end where its table does");
    FORGE(d.plan.n_steps = r.n - 1, "not the one of its table (counts)");
    FORGE(d.jerk_source = JERK_SOURCE_F_MODE, "a table with jerk times from f_mode");
    FORGE(d.p.distance += 1e-6, "not made from its parameters");
    FORGE(d.plan.piece[7].v += 1e-7, "does not continue the one before");
    /* refusals left the instance as it was */
    CHECK(fmi2SetFMUstate(c, s2) == fmi2OK, "its own state again: %s", last_message);
    fmi2FreeFMUstate(c, &s);
    fmi2FreeFMUstate(c, &s2);
    free(buf);
    free(forged);
    fmi2FreeInstance(c);

    /* a stop, then an execute, mid-table: at rest within the limits; the execute on target */
    for (i = 0; i < 2; i++) {
        double vpk = 0.0, apk = 0.0, amin = 0.0, xs = 0.0;
        c = make(i ? "table-execute" : "table-stop");
        set_table(c, &r, x0, 0.0);
        fmi2EnterInitializationMode(c);
        CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "init: %s", last_message);
        for (k = 0, t = 0.0; k < 3000; k++, t += Te) {
            if (k == 83) {
                xs = get_real(c, VR_X);
                if (i) set_real(c, VR_TARGET, -0.05);
                set_bool(c, i ? VR_EXECUTE : VR_STOP, 1);
            }
            CHECK(fmi2DoStep(c, t, Te, fmi2True) == fmi2OK, "step %d: %s", k, last_message);
            vpk = fmax(vpk, fabs(get_real(c, VR_V)));
            apk = fmax(apk, get_real(c, VR_A));
            amin = fmin(amin, get_real(c, VR_A));
        }
        CHECK(get_bool(c, VR_DONE) && get_real(c, VR_V) == 0.0 && get_real(c, VR_A) == 0.0,
              "%s: at rest", i ? "execute" : "stop");
        CHECK(vpk <= r.V * (1 + 1e-9) && apk <= r.up * (1 + 1e-9) &&
                  -amin <= fmax(r.up, r.down) * (1 + 1e-9),
              "%s: within the limits: |v| %.17g / %.17g, a %.17g %.17g / %.17g %.17g",
              i ? "execute" : "stop", vpk, r.V, apk, amin, r.up, r.down);
        if (i)
            CHECK(fabs(get_real(c, VR_X) + 0.05) <= 1e-12, "execute: on -0.05 m: %.17g",
                  get_real(c, VR_X));
        else
            CHECK(get_real(c, VR_X) >= xs && get_real(c, VR_X) <= x0 + dist + 1e-12,
                  "stop: rests at %.17g, between %.17g and %.17g", get_real(c, VR_X), xs,
                  x0 + dist);
        fmi2FreeInstance(c);
    }

    /* the planner of the other profiles refuses a table (it needs its table) */
    {
        static djl_plan pl;
        djl_params q;
        djl_error err;
        djl_params_default(&q);
        q.profile = DJL_PROFILE_TABLE;
        q.distance = 0.0;
        CHECK(djl_plan_motion(&q, &pl, &err) == DJL_E_PARAM && strcmp(err.param, "profile") == 0 &&
                  strstr(err.message, "planned from its table") != NULL,
              "djl_plan_motion of a table: %s", err.message);
        CHECK(djl_table_validate(&q, &(djl_table){0}, &err) == DJL_OK, "an empty table at rest: %s",
              err.message);
        q.profile = DJL_PROFILE_DJL;
        CHECK(djl_table_validate(&q, &(djl_table){0}, &err) == DJL_E_PARAM &&
                  strstr(err.message, "profile = 4") != NULL,
              "a table needs profile 4: %s", err.message);
    }
    /* bad tables: refused at initialisation naming the entry; usable after a reset */
    {
        static const struct {
            int what; /* 0 table_n, 1 a length, 2 a jerk, 3 v_max, 4 distance */
            double value;
            const char *fragment;
        } bad[] = {
            {0, 257, "table_n = 257: must be 0..256"},
            {0, -2, "table_n = -2"},
            {1, 0, "table_samples[4] = 0: a piece of the table lasts 1..100000000 samples"},
            {2, NAN, "table_jerk[4] = nan m/s3: must be finite"},
            {2, 1e6, "table_jerk[4] = 1e+06 m/s3: beyond (a_max + d_max) / Te"},
            {3, 0.5, "beyond v_max = "},
            {4, 0.0, "distance = 0 m: the table ends"},
        };
        for (i = 0; i < (int)(sizeof bad / sizeof bad[0]); i++) {
            fmi2ValueReference vr;
            c = make("bad-table");
            set_table(c, &r, 0.0, 0.0);
            switch (bad[i].what) {
            case 0: set_int(c, VR_TABLE_N, (int)bad[i].value); break;
            case 1: set_int(c, VR_TABLE_SAMPLES + 3, (int)bad[i].value); break;
            case 2:
                vr = VR_TABLE_JERK + 3;
                CHECK(fmi2SetReal(c, &vr, 1, &bad[i].value) == fmi2OK, "set");
                break;
            case 3: set_real(c, VR_V_MAX, r.V * bad[i].value); break;
            default: set_real(c, VR_DISTANCE, bad[i].value); break;
            }
            fmi2EnterInitializationMode(c);
            expect_error(fmi2ExitInitializationMode(c), bad[i].fragment);
            CHECK(fmi2Reset(c) == fmi2OK, "reset");
            CHECK(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK, "setup");
            set_table(c, &r, 0.0, 0.0);
            fmi2EnterInitializationMode(c);
            CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "the table after a reset: %s",
                  last_message);
            for (k = 0; k < 400; k++) fmi2DoStep(c, k * Te, Te, fmi2True);
            CHECK(get_real(c, VR_X) == dist, "the table after a refusal lands: %.17g",
                  get_real(c, VR_X));
            fmi2FreeInstance(c);
        }
    }
}

int main(int argc, char **argv)
{
    /* argv[1]: corruptions of a serialized state (10^6 for the full campaign of
     * issue #10: ./test_fmi2 1000000), argv[2]: resealed ones (default a tenth) */
    long n_fuzz = argc > 1 ? atol(argv[1]) : 100000;
    long n_sealed = argc > 2 ? atol(argv[2]) : n_fuzz / 10;
    /* argv[3]: random multi-word damages the checksum must see (issue 39: 10^6 on demand) */
    long n_damage = argc > 3 ? atol(argv[3]) : 20000;
    run_checksum_damage(n_damage);
    run_states();
    run_bad_inputs();
    run_range_refusals();
    run_two_instances();
    run_null_pointers();
    run_state_packing();
    run_forged_states();
    run_forged_memory();
    run_fmode_phase_long_rest();
    run_fmode_rate_overflow();
    run_check_area_allocation();
    run_commands(2);
    run_commands(3);
    run_issue21_landing();
    run_issue21_long_stops();
    run_issue21_forged_plan();
    run_forged_queue();
    run_plan_consistency();
    run_table();
    run_entry_points();
    run_state_fuzz(n_fuzz, n_sealed);
    printf("fmi2: %d failures, %d errors logged\n", failures, errors_logged);
    return failures ? 1 : 0;
}
