/*
 * bench_importer.c -- a native FMI 2.0 importer loop over the generator FMU's binary.
 *
 * dlopen()s the FMU's shared library, instantiates it, and steps it one sample at
 * a time as a C master would: per sample one fmi2DoStep of Te and one fmi2GetReal
 * of x, v, a, j.  Prints "<samples> <seconds>" for each repeat.
 *
 * usage: bench_importer LIB GUID RESOURCE_URI VR_X VR_V VR_A VR_J TE SAMPLES REPEATS
 */
#include "bench_fmi2.h" /* bench_logger, bench_now, LOAD */

int main(int argc, char **argv)
{
    void *lib;
    fmi2CallbackFunctions cb = {bench_logger, calloc, free, NULL, NULL};
    fmi2ValueReference vr[4];
    double Te, out[4], sink = 0.0;
    long long n, i;
    int r, repeats;
    if (argc != 11) {
        fprintf(stderr, "usage: %s LIB GUID URI VR_X VR_V VR_A VR_J TE SAMPLES REPEATS\n",
                argv[0]);
        return 2;
    }
    lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        fprintf(stderr, "%s\n", dlerror());
        return 2;
    }
    for (r = 0; r < 4; r++) vr[r] = (fmi2ValueReference)strtoul(argv[4 + r], NULL, 10);
    Te = strtod(argv[8], NULL);
    n = strtoll(argv[9], NULL, 10);
    repeats = atoi(argv[10]);
    {
        LOAD(fmi2InstantiateTYPE *, fmi2Instantiate)
        LOAD(fmi2SetupExperimentTYPE *, fmi2SetupExperiment)
        LOAD(fmi2EnterInitializationModeTYPE *, fmi2EnterInitializationMode)
        LOAD(fmi2ExitInitializationModeTYPE *, fmi2ExitInitializationMode)
        LOAD(fmi2DoStepTYPE *, fmi2DoStep)
        LOAD(fmi2GetRealTYPE *, fmi2GetReal)
        LOAD(fmi2FreeInstanceTYPE *, fmi2FreeInstance)
        for (r = 0; r < repeats; r++) {
            double t0, t = 0.0;
            fmi2Component c = fmi2Instantiate("bench", fmi2CoSimulation, argv[2], argv[3], &cb,
                                              fmi2False, fmi2False);
            if (!c) return 3;
            if (fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK ||
                fmi2EnterInitializationMode(c) != fmi2OK ||
                fmi2ExitInitializationMode(c) != fmi2OK)
                return 4;
            t0 = bench_now();
            for (i = 0; i < n; i++) {
                if (fmi2DoStep(c, t, Te, fmi2True) != fmi2OK) return 5;
                if (fmi2GetReal(c, vr, 4, out) != fmi2OK) return 6;
                sink += out[0];
                t = (double)(i + 1) * Te;
            }
            printf("%lld %.9f\n", n, bench_now() - t0);
            fmi2FreeInstance(c);
        }
    }
    fprintf(stderr, "checksum %g\n", sink);
    dlclose(lib);
    return 0;
}
