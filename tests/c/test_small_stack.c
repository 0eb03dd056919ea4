/*
 * test_small_stack.c -- the FMU runs on a thread whose stack is small: an importer may call
 * it from a worker thread, and some C libraries give threads little stack (musl: 128 kB;
 * macOS: 512 kB).  Every FMI 2 and FMI 3 call the FMU has runs here on a thread of
 * STACK_KB kB (default 128): a session with a commanded replan, then FMU states got, set,
 * serialised, deserialised (also over a state to overwrite) and refused (a damaged one).
 *
 * Until the state's checks worked in place, a state was copied to the stack (about
 * 290 kB) and fmi2SetFMUstate killed the process on such a thread (SIGSEGV).
 *
 *   gcc -std=c99 -O1 -Ifmu_src -I<fmi headers> tests/c/test_small_stack.c fmu_src/fmi2.c \
 *       fmu_src/fmi3.c fmu_src/fmu_*.c fmu_src/djl_*.c -lm -lpthread && ./a.out [STACK_KB]
 * (tests/test_c_sanitizers.py::test_fmu_runs_on_a_small_thread_stack)
 */
#define _POSIX_C_SOURCE 200809L
#include <limits.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "djl_vars.h"
#include "fmi2Functions.h"
#include "fmi3Functions.h"
#include "fmu_instance.h" /* model_state_max_size: the largest state */

static int failures = 0;
#define EXPECT(cond, what)                                                                       \
    do {                                                                                         \
        if (!(cond)) {                                                                           \
            fprintf(stderr, "FAIL %s:%d: %s\n", __FILE__, __LINE__, what);                       \
            failures++;                                                                          \
        }                                                                                        \
    } while (0)

static void log2_cb(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c,
                    fmi2String m, ...)
{
    (void)e;
    (void)n;
    (void)s;
    (void)c;
    (void)m;
}

static void log3_cb(fmi3InstanceEnvironment e, fmi3Status s, fmi3String c, fmi3String m)
{
    (void)e;
    (void)s;
    (void)c;
    (void)m;
}

static const fmi2CallbackFunctions cb2 = {log2_cb, calloc, free, NULL, NULL};

static void session2(void)
{
    fmi2Component c = fmi2Instantiate("stack2", fmi2CoSimulation, DJL_INSTANTIATION_TOKEN,
                                      "file:///tmp", &cb2, fmi2False, fmi2False);
    fmi2FMUstate s = NULL, s2 = NULL;
    fmi2ValueReference vr_target = VR_TARGET, vr_execute = VR_EXECUTE, vr_x = VR_X;
    fmi2Real target = 0.1, x_saved = 0.0, x = 0.0, t = 0.0;
    fmi2Boolean on = fmi2True;
    fmi2Byte *buf;
    size_t size = 0;
    int k;
    EXPECT(c != NULL, "fmi2Instantiate");
    if (!c) return;
    EXPECT(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK, "setup");
    EXPECT(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
    EXPECT(fmi2ExitInitializationMode(c) == fmi2OK, "exit");
    for (k = 0; k < 200; k++, t += 1e-3) EXPECT(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "step");
    /* a commanded move: a replan */
    EXPECT(fmi2SetReal(c, &vr_target, 1, &target) == fmi2OK, "target");
    EXPECT(fmi2SetBoolean(c, &vr_execute, 1, &on) == fmi2OK, "execute");
    EXPECT(fmi2DoStep(c, t, 1e-3, fmi2True) == fmi2OK, "replan step");
    t += 1e-3;
    EXPECT(fmi2GetFMUstate(c, &s) == fmi2OK && s, "fmi2GetFMUstate");
    EXPECT(fmi2GetReal(c, &vr_x, 1, &x_saved) == fmi2OK, "x");
    EXPECT(fmi2DoStep(c, t, 0.05, fmi2True) == fmi2OK, "step on");
    EXPECT(fmi2GetFMUstate(c, &s) == fmi2OK, "fmi2GetFMUstate over a state");
    EXPECT(fmi2SetFMUstate(c, s) == fmi2OK, "fmi2SetFMUstate");
    EXPECT(fmi2SerializedFMUstateSize(c, s, &size) == fmi2OK && size > 1000 &&
           size <= model_state_max_size(),
           "size");
    buf = (fmi2Byte *)malloc(size + 1);
    EXPECT(buf != NULL, "malloc");
    if (!buf) return;
    EXPECT(fmi2SerializeFMUstate(c, s, buf + 1, size) == fmi2OK, "serialise (unaligned)");
    EXPECT(fmi2DeSerializeFMUstate(c, buf + 1, size, &s2) == fmi2OK && s2, "deserialise");
    EXPECT(fmi2DeSerializeFMUstate(c, buf + 1, size, &s2) == fmi2OK, "deserialise over");
    buf[1 + size / 2] ^= 1;
    EXPECT(fmi2DeSerializeFMUstate(c, buf + 1, size, &s2) == fmi2Error, "damaged: refused");
    EXPECT(fmi2SetFMUstate(c, s2) == fmi2OK, "the state overwritten is intact");
    EXPECT(fmi2GetReal(c, &vr_x, 1, &x) == fmi2OK && x != x_saved, "x");
    free(buf);
    fmi2FreeFMUstate(c, &s);
    fmi2FreeFMUstate(c, &s2);
    fmi2FreeInstance(c);
}

static void session3(void)
{
    fmi3Instance c = fmi3InstantiateCoSimulation("stack3", DJL_INSTANTIATION_TOKEN, "/tmp",
                                                 fmi3False, fmi3False, fmi3False, fmi3False, NULL,
                                                 0, NULL, log3_cb, NULL);
    fmi3FMUState s = NULL, s2 = NULL;
    fmi3ValueReference vr_target = VR_TARGET, vr_execute = VR_EXECUTE;
    fmi3Float64 target = -0.05, t = 0.0, last = 0.0;
    fmi3Boolean on = fmi3True, eh, term, early;
    fmi3Byte *buf;
    size_t size = 0;
    int k;
    EXPECT(c != NULL, "fmi3InstantiateCoSimulation");
    if (!c) return;
    EXPECT(fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK, "enter");
    EXPECT(fmi3ExitInitializationMode(c) == fmi3OK, "exit");
    for (k = 0; k < 200; k++, t += 1e-3)
        EXPECT(fmi3DoStep(c, t, 1e-3, fmi3True, &eh, &term, &early, &last) == fmi3OK, "step");
    EXPECT(fmi3SetFloat64(c, &vr_target, 1, &target, 1) == fmi3OK, "target");
    EXPECT(fmi3SetBoolean(c, &vr_execute, 1, &on, 1) == fmi3OK, "execute");
    EXPECT(fmi3DoStep(c, t, 1e-3, fmi3True, &eh, &term, &early, &last) == fmi3OK, "replan");
    EXPECT(fmi3GetFMUState(c, &s) == fmi3OK && s, "fmi3GetFMUState");
    EXPECT(fmi3GetFMUState(c, &s) == fmi3OK, "fmi3GetFMUState over a state");
    EXPECT(fmi3SetFMUState(c, s) == fmi3OK, "fmi3SetFMUState");
    EXPECT(fmi3SerializedFMUStateSize(c, s, &size) == fmi3OK && size > 1000 &&
           size <= model_state_max_size(),
           "size");
    buf = (fmi3Byte *)malloc(size + 3);
    EXPECT(buf != NULL, "malloc");
    if (!buf) return;
    EXPECT(fmi3SerializeFMUState(c, s, buf + 3, size) == fmi3OK, "serialise (unaligned)");
    EXPECT(fmi3DeserializeFMUState(c, buf + 3, size, &s2) == fmi3OK && s2, "deserialise");
    EXPECT(fmi3DeserializeFMUState(c, buf + 3, size, &s2) == fmi3OK, "deserialise over");
    buf[3 + size / 3] ^= 4;
    EXPECT(fmi3DeserializeFMUState(c, buf + 3, size, &s2) == fmi3Error, "damaged: refused");
    EXPECT(fmi3SetFMUState(c, s2) == fmi3OK, "the state overwritten is intact");
    free(buf);
    fmi3FreeFMUState(c, &s);
    fmi3FreeFMUState(c, &s2);
    fmi3FreeInstance(c);
}

static void *run(void *arg)
{
    (void)arg;
    session2();
    session3();
    return NULL;
}

int main(int argc, char **argv)
{
    pthread_attr_t attr;
    pthread_t th;
    long kb = argc > 1 ? strtol(argv[1], NULL, 10) : 128;
    size_t stack = (size_t)kb * 1024;
    if (stack < PTHREAD_STACK_MIN) stack = PTHREAD_STACK_MIN;
    if (pthread_attr_init(&attr) != 0 || pthread_attr_setstacksize(&attr, stack) != 0 ||
        pthread_create(&th, &attr, run, NULL) != 0 || pthread_join(th, NULL) != 0) {
        fprintf(stderr, "cannot run a thread of %ld kB\n", kb);
        return 2;
    }
    printf("every FMI 2 and FMI 3 call ran on a thread of %ld kB: %d failure(s)\n", kb, failures);
    return failures != 0;
}
