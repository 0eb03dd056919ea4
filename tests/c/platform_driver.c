/*
 * platform_driver.c -- loads an FMU's shared library by path (LoadLibrary / dlopen), runs the
 * default move with the FMU's start values, and prints one line per communication step:
 *
 *     t x v a j done
 *
 * Cross-compiled by zig for each platform that an emulator runs here (wine for Windows,
 * qemu-user for aarch64 Linux), so that tests/test_platforms.py can compare the outputs of
 * every binary of the FMU with the host's.
 *
 * usage: platform_driver <2|3> <library> [steps [h]]      (default: 1000 steps of 1 ms)
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
typedef HMODULE library;
static library open_library(const char *path) { return LoadLibraryA(path); }
static void *symbol(library h, const char *name) { return (void *)GetProcAddress(h, name); }
#else
#include <dlfcn.h>
typedef void *library;
static library open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *symbol(library h, const char *name) { return dlsym(h, name); }
#endif

#include "djl_vars.h"
#include "fmi2FunctionTypes.h"
#include "fmi3FunctionTypes.h"

static library lib;

/* A function of the library by name; exits when it is missing. */
static void load(void *fp, size_t size, const char *name)
{
    void *p = symbol(lib, name);
    if (p == NULL) {
        fprintf(stderr, "missing function %s\n", name);
        exit(2);
    }
    memcpy(fp, &p, size); /* object to function pointer without a cast that -Wpedantic flags */
}
#define LOAD(var, name) load(&(var), sizeof(var), name)

static void log_fmi2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                 fmi2String category, fmi2String message, ...)
{
    (void)env;
    (void)name;
    fprintf(stderr, "[%d %s] %s\n", (int)status, category, message);
}

static void log_fmi3(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                 fmi3String message)
{
    (void)env;
    fprintf(stderr, "[%d %s] %s\n", (int)status, category, message);
}

static void print(double t, const double y[4], int done)
{
    printf("%.17g %.17g %.17g %.17g %.17g %d\n", t, y[0], y[1], y[2], y[3], done);
}

static int run2(long steps, double h)
{
    fmi2InstantiateTYPE *instantiate;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter;
    fmi2ExitInitializationModeTYPE *leave;
    fmi2DoStepTYPE *step;
    fmi2GetRealTYPE *get_real;
    fmi2GetBooleanTYPE *get_boolean;
    fmi2TerminateTYPE *terminate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2CallbackFunctions cb = {log_fmi2, calloc, free, NULL, NULL};
    const fmi2ValueReference vr[4] = {VR_X, VR_V, VR_A, VR_J}, vr_done = VR_DONE;
    fmi2Component c;
    fmi2Boolean done = fmi2False;
    double y[4];
    long k;
    LOAD(instantiate, "fmi2Instantiate");
    LOAD(setup, "fmi2SetupExperiment");
    LOAD(enter, "fmi2EnterInitializationMode");
    LOAD(leave, "fmi2ExitInitializationMode");
    LOAD(step, "fmi2DoStep");
    LOAD(get_real, "fmi2GetReal");
    LOAD(get_boolean, "fmi2GetBoolean");
    LOAD(terminate, "fmi2Terminate");
    LOAD(free_instance, "fmi2FreeInstance");
    c = instantiate("driver", fmi2CoSimulation, DJL_INSTANTIATION_TOKEN, NULL, &cb, fmi2False,
                    fmi2False);
    if (c == NULL) return 1;
    if (setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) > fmi2Warning ||
        enter(c) > fmi2Warning || leave(c) > fmi2Warning)
        return 1;
    for (k = 0; k <= steps; k++) {
        if (k > 0 && step(c, (double)(k - 1) * h, h, fmi2True) > fmi2Warning) return 1;
        if (get_real(c, vr, 4, y) > fmi2Warning || get_boolean(c, &vr_done, 1, &done) > fmi2Warning)
            return 1;
        print((double)k * h, y, done != fmi2False);
    }
    terminate(c);
    free_instance(c);
    return 0;
}

static int run3(long steps, double h)
{
    fmi3InstantiateCoSimulationTYPE *instantiate;
    fmi3EnterInitializationModeTYPE *enter;
    fmi3ExitInitializationModeTYPE *leave;
    fmi3DoStepTYPE *step;
    fmi3GetFloat64TYPE *get_float64;
    fmi3GetBooleanTYPE *get_boolean;
    fmi3TerminateTYPE *terminate;
    fmi3FreeInstanceTYPE *free_instance;
    const fmi3ValueReference vr[4] = {VR_X, VR_V, VR_A, VR_J}, vr_done = VR_DONE;
    fmi3Instance c;
    fmi3Boolean done = fmi3False, event, stop, early;
    fmi3Float64 last;
    double y[4];
    long k;
    LOAD(instantiate, "fmi3InstantiateCoSimulation");
    LOAD(enter, "fmi3EnterInitializationMode");
    LOAD(leave, "fmi3ExitInitializationMode");
    LOAD(step, "fmi3DoStep");
    LOAD(get_float64, "fmi3GetFloat64");
    LOAD(get_boolean, "fmi3GetBoolean");
    LOAD(terminate, "fmi3Terminate");
    LOAD(free_instance, "fmi3FreeInstance");
    c = instantiate("driver", DJL_INSTANTIATION_TOKEN, NULL, fmi3False, fmi3False, fmi3False,
                    fmi3False, NULL, 0, NULL, log_fmi3, NULL);
    if (c == NULL) return 1;
    if (enter(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) > fmi3Warning || leave(c) > fmi3Warning)
        return 1;
    for (k = 0; k <= steps; k++) {
        if (k > 0 && step(c, (double)(k - 1) * h, h, fmi3True, &event, &stop, &early, &last) >
                         fmi3Warning)
            return 1;
        if (get_float64(c, vr, 4, y, 4) > fmi3Warning ||
            get_boolean(c, &vr_done, 1, &done, 1) > fmi3Warning)
            return 1;
        print((double)k * h, y, done != fmi3False);
    }
    terminate(c);
    free_instance(c);
    return 0;
}

int main(int argc, char **argv)
{
    long steps = argc > 3 ? atol(argv[3]) : 1000;
    double h = argc > 4 ? atof(argv[4]) : 1e-3;
    int version = argc > 2 ? atoi(argv[1]) : 0, status;
    if (version != 2 && version != 3) {
        fprintf(stderr, "usage: %s <2|3> <library> [steps [h]]\n", argv[0]);
        return 2;
    }
    lib = open_library(argv[2]);
    if (lib == NULL) {
#ifdef _WIN32
        fprintf(stderr, "cannot load %s (error %lu)\n", argv[2], (unsigned long)GetLastError());
#else
        fprintf(stderr, "cannot load %s: %s\n", argv[2], dlerror());
#endif
        return 2;
    }
    status = version == 2 ? run2(steps, h) : run3(steps, h);
    if (status != 0) fprintf(stderr, "an FMI call failed\n");
    fflush(stdout);
    return status;
}
