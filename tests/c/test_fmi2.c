/*
 * test_fmi2.c -- drives the FMI 2 layer directly (no importer), meant to run
 * under AddressSanitizer + UBSan or valgrind: normal run, FMU state save /
 * restore / serialise, every kind of bad call, reset, two instances.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"
#include "djl_vars.h"
#include "fmi2Functions.h"

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
    CHECK(fmi2GetReal(c, &vr, 1, &v) == fmi2OK, "get %u", vr);
    return v;
}

static void expect_error(fmi2Status st, const char *fragment)
{
    CHECK(st == fmi2Error, "expected fmi2Error, got %d (%s)", (int)st, fragment);
    CHECK(strstr(last_message, fragment) != NULL, "message \"%s\" lacks \"%s\"", last_message,
          fragment);
}

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
    expect_error(fmi2DoStep(c, 0.0, 1.5e-3, fmi2True), "whole multiple");
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

int main(void)
{
    run_states();
    run_bad_inputs();
    run_two_instances();
    printf("fmi2: %d failures, %d errors logged\n", failures, errors_logged);
    return failures ? 1 : 0;
}
