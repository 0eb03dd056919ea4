/*
 * bench_state.c -- FMU states as a rollback master uses them, over the generator FMU's binary.
 *
 * dlopen()s the FMU's shared library (FMI 2.0), brings it to a state (the default move,
 * or a ZVD shaper timed by f_mode with a commanded target: both rings of the shaper's
 * memory in use) and then, COUNT times, saves the state over the previous one and
 * restores it (fmi2GetFMUstate + fmi2SetFMUstate), then serialises and deserialises it
 * (fmi2SerializedFMUstateSize + fmi2SerializeFMUstate + fmi2DeSerializeFMUstate).
 * Prints, per repeat, "<state bytes> <seconds get+set> <seconds serialise+deserialise>".
 *
 * usage: bench_state LIB GUID URI SHAPED VR_SHAPER VR_SHAPER_SOURCE VR_F_MODE VR_TARGET
 *                    VR_EXECUTE COUNT REPEATS
 */
#include "bench_fmi2.h" /* bench_logger, bench_now, LOAD */

int main(int argc, char **argv)
{
    void *lib;
    fmi2CallbackFunctions cb = {bench_logger, calloc, free, NULL, NULL};
    fmi2ValueReference vr[5];
    long long count, i;
    int r, repeats, shaped, k;
    if (argc != 12) {
        fprintf(stderr, "usage: %s LIB GUID URI SHAPED VR_SHAPER VR_SHAPER_SOURCE VR_F_MODE "
                "VR_TARGET VR_EXECUTE COUNT REPEATS\n", argv[0]);
        return 2;
    }
    lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "%s\n", dlerror());
        return 2;
    }
    shaped = atoi(argv[4]);
    for (k = 0; k < 5; k++) vr[k] = (fmi2ValueReference)strtoul(argv[5 + k], NULL, 10);
    count = strtoll(argv[10], NULL, 10);
    repeats = atoi(argv[11]);
    {
        LOAD(fmi2InstantiateTYPE *, fmi2Instantiate)
        LOAD(fmi2SetupExperimentTYPE *, fmi2SetupExperiment)
        LOAD(fmi2EnterInitializationModeTYPE *, fmi2EnterInitializationMode)
        LOAD(fmi2ExitInitializationModeTYPE *, fmi2ExitInitializationMode)
        LOAD(fmi2DoStepTYPE *, fmi2DoStep)
        LOAD(fmi2SetRealTYPE *, fmi2SetReal)
        LOAD(fmi2SetIntegerTYPE *, fmi2SetInteger)
        LOAD(fmi2SetBooleanTYPE *, fmi2SetBoolean)
        LOAD(fmi2GetFMUstateTYPE *, fmi2GetFMUstate)
        LOAD(fmi2SetFMUstateTYPE *, fmi2SetFMUstate)
        LOAD(fmi2FreeFMUstateTYPE *, fmi2FreeFMUstate)
        LOAD(fmi2SerializedFMUstateSizeTYPE *, fmi2SerializedFMUstateSize)
        LOAD(fmi2SerializeFMUstateTYPE *, fmi2SerializeFMUstate)
        LOAD(fmi2DeSerializeFMUstateTYPE *, fmi2DeSerializeFMUstate)
        LOAD(fmi2FreeInstanceTYPE *, fmi2FreeInstance)
        for (r = 0; r < repeats; r++) {
            double t0, t1, t = 0.0, f_mode = 12.0, target = 0.2;
            fmi2Integer zvd = 2, by_fmode = 2;
            fmi2Boolean on = fmi2True;
            fmi2FMUstate s = NULL, s2 = NULL;
            fmi2Byte *buf = NULL;
            size_t size = 0;
            fmi2Component c = fmi2Instantiate("bench", fmi2CoSimulation, argv[2], argv[3], &cb,
                                              fmi2False, fmi2False);
            if (!c) return 3;
            if (shaped && (fmi2SetInteger(c, &vr[0], 1, &zvd) != fmi2OK ||
                           fmi2SetInteger(c, &vr[1], 1, &by_fmode) != fmi2OK))
                return 4;
            if (fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK ||
                fmi2EnterInitializationMode(c) != fmi2OK ||
                fmi2ExitInitializationMode(c) != fmi2OK)
                return 4;
            for (k = 0; k < 150; k++, t += 1e-3) {
                if (k == 120 && (fmi2SetReal(c, &vr[2], 1, &f_mode) != fmi2OK ||
                                 fmi2SetReal(c, &vr[3], 1, &target) != fmi2OK ||
                                 fmi2SetBoolean(c, &vr[4], 1, &on) != fmi2OK))
                    return 5;
                if (fmi2DoStep(c, t, 1e-3, fmi2True) != fmi2OK) return 5;
            }
            t0 = bench_now();
            for (i = 0; i < count; i++)
                if (fmi2GetFMUstate(c, &s) != fmi2OK || fmi2SetFMUstate(c, s) != fmi2OK) return 6;
            t1 = bench_now();
            if (fmi2SerializedFMUstateSize(c, s, &size) != fmi2OK) return 7;
            buf = (fmi2Byte *)malloc(size);
            if (!buf) return 7;
            for (i = 0; i < count; i++)
                if (fmi2SerializedFMUstateSize(c, s, &size) != fmi2OK ||
                    fmi2SerializeFMUstate(c, s, buf, size) != fmi2OK ||
                    fmi2DeSerializeFMUstate(c, buf, size, &s2) != fmi2OK)
                    return 8;
            printf("%lu %.9f %.9f\n", (unsigned long)size, t1 - t0, bench_now() - t1);
            free(buf);
            fmi2FreeFMUstate(c, &s);
            fmi2FreeFMUstate(c, &s2);
            fmi2FreeInstance(c);
        }
    }
    dlclose(lib);
    return 0;
}
