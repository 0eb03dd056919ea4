/*
 * bench_fmi2.h -- what the native FMI 2.0 importers of benchmarks/c/ share: a logger that
 * prints errors, a monotonic clock, and LOAD(type, name), which takes a function from the
 * dlopen()ed library `lib` or returns 2 from main naming it.
 */
#ifndef BENCH_FMI2_H
#define BENCH_FMI2_H

#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#include "fmi2Functions.h"

static void bench_logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    if (status >= fmi2Error) fprintf(stderr, "[%s] %s: %s\n", name, category, message);
}

static double bench_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#define LOAD(type, name)                                                              \
    type name = (type)dlsym(lib, #name);                                              \
    if (!name) {                                                                      \
        fprintf(stderr, "missing %s\n", #name);                                       \
        return 2;                                                                     \
    }

#endif /* BENCH_FMI2_H */
