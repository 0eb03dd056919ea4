/*
 * fmi3.c -- FMI 3.0 co-simulation interface: a thin translation of the FMI 3
 * API onto the instance (fmu_instance.c), the model (fmu_model.c) and the
 * base under them (fmu_base.c: logging, errors, the variable table).  Array
 * variables (seg_distance, seg_v_end) are expanded to their elements.
 */
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "fmu_instance.h"

typedef struct {
    model_instance m;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback log;
} inst3;

static void logger3(void *env, model_status st, const char *category, const char *message)
{
    inst3 *s = (inst3 *)env;
    if (!s || !s->log) return;
    s->log(s->env, (fmi3Status)st, category, message);
}

#define MASK_ANY (MS_INSTANTIATED | MS_INIT | MS_STEP | MS_TERMINATED | MS_ERROR)
#define MASK_GET (MS_INSTANTIATED | MS_INIT | MS_STEP | MS_TERMINATED | MS_ERROR)
#define MASK_SET (MS_INSTANTIATED | MS_INIT | MS_STEP)
#define MASK_FMUSTATE (MS_INSTANTIATED | MS_INIT | MS_STEP | MS_TERMINATED)
/* after an error, a formerly stored FMU state may be restored */
#define MASK_RESTORE (MASK_FMUSTATE | MS_ERROR)

#define INST(c) ((inst3 *)(c))
#define CHECK(c, fn, mask)                                                                       \
    do {                                                                                         \
        if (!(c)) return fmi3Error;                                                              \
        if (!MODEL_ALLOWED(&INST(c)->m, fn, mask)) return fmi3Error;                             \
    } while (0)
/* A pointer argument that must not be NULL: refused, the instance unchanged. */
#define NEED(c, fn, ptr)                                                                         \
    do {                                                                                         \
        if (!(ptr)) return (fmi3Status)model_null_arg(&INST(c)->m, fn, #ptr);                    \
    } while (0)

static fmi3Status unsupported(fmi3Instance c, const char *fn)
{
    if (!c) return fmi3Error;
    model_fail(&INST(c)->m, "%s is not supported by this FMU (co-simulation without event mode, "
               "clocks or derivatives)", fn);
    return fmi3Error;
}

/* ---------------------------------------------------------------- common */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    CHECK(instance, "fmi3SetDebugLogging", MASK_ANY);
    return (fmi3Status)model_set_debug_logging(&INST(instance)->m, "fmi3SetDebugLogging",
                                               loggingOn, nCategories, categories);
}

static void log_early(fmi3InstanceEnvironment env, fmi3LogMessageCallback log, const char *msg)
{
    if (log) log(env, fmi3Error, "logStatusError", msg);
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    log_early(instanceEnvironment, logMessage,
              "fmi3InstantiateModelExchange: this FMU supports co-simulation only");
    return NULL;
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate)
{
    inst3 *s;
    (void)resourcePath;
    (void)visible;
    (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables;
    (void)intermediateUpdate;
    if (!instanceName || !instanceName[0]) {
        log_early(instanceEnvironment, logMessage,
                  "fmi3InstantiateCoSimulation: instanceName must be a non-empty string");
        return NULL;
    }
    if (!instantiationToken || strcmp(instantiationToken, DJL_INSTANTIATION_TOKEN) != 0) {
        log_early(instanceEnvironment, logMessage,
                  "fmi3InstantiateCoSimulation: the instantiation token does not match this "
                  "binary's " DJL_INSTANTIATION_TOKEN " (model description and binary differ)");
        return NULL;
    }
    if (eventModeUsed) {
        log_early(instanceEnvironment, logMessage,
                  "fmi3InstantiateCoSimulation: eventModeUsed = true, but this FMU has no event "
                  "mode (hasEventMode = false)");
        return NULL;
    }
    if (nRequiredIntermediateVariables > 0) {
        log_early(instanceEnvironment, logMessage,
                  "fmi3InstantiateCoSimulation: intermediate variables requested, but this FMU "
                  "provides no intermediate update");
        return NULL;
    }
    s = (inst3 *)calloc(1, sizeof(inst3));
    if (!s) {
        log_early(instanceEnvironment, logMessage, "fmi3InstantiateCoSimulation: out of memory");
        return NULL;
    }
    s->env = instanceEnvironment;
    s->log = logMessage;
    model_init(&s->m, 3, instanceName, logger3, s, loggingOn, calloc, free);
    return s;
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instanceName;
    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    log_early(instanceEnvironment, logMessage,
              "fmi3InstantiateScheduledExecution: this FMU supports co-simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance)
{
    if (!instance) return;
    model_free(&INST(instance)->m);
    free(instance);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    model_status st;
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    CHECK(instance, "fmi3EnterInitializationMode", MS_INSTANTIATED);
    st = model_setup(&INST(instance)->m, startTime);
    if (st != ST_OK) return (fmi3Status)st;
    return (fmi3Status)model_enter_init(&INST(instance)->m);
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    CHECK(instance, "fmi3ExitInitializationMode", MS_INIT);
    return (fmi3Status)model_exit_init(&INST(instance)->m);
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EnterEventMode");
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    CHECK(instance, "fmi3Terminate", MS_STEP);
    return (fmi3Status)model_terminate(&INST(instance)->m);
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    /* always allowed: whatever state the instance is in, Reset brings it back */
    if (!instance) return fmi3Error;
    model_reset(&INST(instance)->m);
    return fmi3OK;
}

/* ------------------------------------------------------ getters / setters */

/* Expand the value references (arrays to their elements) and get or set each. */
typedef struct {
    const double *r_in;
    const int32_t *i_in;
    const fmi3Boolean *b_in;
    double *r_out;
    int32_t *i_out;
    fmi3Boolean *b_out;
    const int64_t *l_in; /* Int64: Enumeration variables only */
    int64_t *l_out;
} io3;

static fmi3Status access(fmi3Instance instance, const char *fn, int set, char type,
                         const fmi3ValueReference vr[], size_t nvr, io3 io, size_t nValues)
{
    inst3 *s = INST(instance);
    size_t k, j = 0;
    unsigned int e;
    const void *values = set ? (io.r_in   ? (const void *)io.r_in
                                : io.i_in ? (const void *)io.i_in
                                : io.l_in ? (const void *)io.l_in
                                          : (const void *)io.b_in)
                             : (io.r_out   ? (void *)io.r_out
                                : io.i_out ? (void *)io.i_out
                                : io.l_out ? (void *)io.l_out
                                           : (void *)io.b_out);
    int int64 = io.l_in || io.l_out;
    CHECK(instance, fn, set ? MASK_SET : MASK_GET);
    if (nvr > 0 && !vr) return (fmi3Status)model_null_arg(&s->m, fn, "valueReferences");
    if ((nvr > 0 || nValues > 0) && !values)
        return (fmi3Status)model_null_arg(&s->m, fn, "values");
    /* check every reference and the count before reading or writing anything */
    for (k = 0; k < nvr; k++) {
        model_var v;
        if (!model_lookup(vr[k], 1, &v)) {
            model_fail(&s->m, "%s: unknown value reference %u", fn, vr[k]);
            return fmi3Error;
        }
        if (int64 && !v.enumeration) {
            model_fail(&s->m, "%s: %s (value reference %u) is not an Enumeration (the only "
                       "variables accessed as Int64)", fn, v.name, vr[k]);
            return fmi3Error;
        }
        j += v.size;
    }
    if (j != nValues) {
        /* An illegal argument: fmi3Error, as the standard requires (2.2.3), but refused like a
         * NULL pointer -- nothing read or written, the instance left as it was -- so that an
         * importer that reads every variable with nValues = 1, arrays included, may go on
         * with the others (and may still reset, as the standard tells it to). */
        return (fmi3Status)model_refuse(&s->m,
                                        "%s: nValues = %lu, but the variables requested hold "
                                        "%lu values (nothing was read or written)",
                                        fn, (unsigned long)nValues, (unsigned long)j);
    }
    j = 0;
    for (k = 0; k < nvr; k++) {
        model_var v;
        model_lookup(vr[k], 1, &v);
        for (e = 0; e < v.size; e++, j++) {
            double x = 0.0;
            if (set) {
                /* (an input, cmd_profile or cmd_shaper, takes any value: saturated by the
                 * model, refused at the command's edge, issue 34) */
                if (io.l_in && v.causality != 'i' &&
                    (io.l_in[j] < INT32_MIN || io.l_in[j] > INT32_MAX)) {
                    model_refuse(&s->m, "%s: %s = %lld is out of the range of the enumeration "
                                 "(nothing more was set)", fn, v.name, (long long)io.l_in[j]);
                    return fmi3Error;
                }
                x = io.r_in   ? io.r_in[j]
                    : io.i_in ? (double)io.i_in[j]
                    : io.l_in ? (double)io.l_in[j]
                              : (io.b_in[j] ? 1.0 : 0.0);
                if (model_set(&s->m, v.base + e, type, x) != ST_OK) return fmi3Error;
            } else {
                if (model_get(&s->m, v.base + e, type, &x) != ST_OK) return fmi3Error;
                if (io.r_out) io.r_out[j] = x;
                if (io.i_out) io.i_out[j] = (int32_t)x;
                if (io.l_out) io.l_out[j] = (int64_t)x;
                if (io.b_out) io.b_out[j] = x != 0.0;
            }
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Float64 values[], size_t nValues)
{
    io3 io = {NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    if (instance && valueReferences && values && nValues == nValueReferences &&
        model_get_reals_fast(&INST(instance)->m, MASK_GET, valueReferences, nValueReferences,
                             values))
        return fmi3OK; /* a master's per-step reads */
    io.r_out = values;
    return access(instance, "fmi3GetFloat64", 0, 'R', valueReferences, nValueReferences, io, nValues);
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Int32 values[], size_t nValues)
{
    io3 io = {NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    io.i_out = values;
    return access(instance, "fmi3GetInt32", 0, 'I', valueReferences, nValueReferences, io, nValues);
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, fmi3Boolean values[], size_t nValues)
{
    io3 io = {NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    io.b_out = values;
    return access(instance, "fmi3GetBoolean", 0, 'B', valueReferences, nValueReferences, io, nValues);
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Float64 values[], size_t nValues)
{
    io3 io = {NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    io.r_in = values;
    return access(instance, "fmi3SetFloat64", 1, 'R', valueReferences, nValueReferences, io, nValues);
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Int32 values[], size_t nValues)
{
    io3 io = {NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    io.i_in = values;
    return access(instance, "fmi3SetInt32", 1, 'I', valueReferences, nValueReferences, io, nValues);
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                          size_t nValueReferences, const fmi3Boolean values[], size_t nValues)
{
    io3 io = {NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    io.b_in = values;
    return access(instance, "fmi3SetBoolean", 1, 'B', valueReferences, nValueReferences, io, nValues);
}

/* Enumerations (spec.ENUMERATIONS: profile, short_stage, jerk_source, shaper, shaper_source,
 * and the inputs cmd_profile, cmd_shaper, buffer_mode) are Int64 in FMI 3's API; Int32 is
 * accepted too, as before the variables were declared as enumerations. */
fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Int64 values[], size_t nValues)
{
    io3 io = {NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    io.l_out = values;
    return access(instance, "fmi3GetInt64", 0, 'I', valueReferences, nValueReferences, io, nValues);
}

fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Int64 values[], size_t nValues)
{
    io3 io = {NULL, NULL, NULL, NULL, NULL, NULL, NULL, NULL};
    io.l_in = values;
    return access(instance, "fmi3SetInt64", 1, 'I', valueReferences, nValueReferences, io, nValues);
}

/* Types this FMU does not use: any value reference is unknown. */
static fmi3Status no_such_type(fmi3Instance instance, const char *fn, int set,
                               const fmi3ValueReference vr[], size_t nvr, const void *values)
{
    CHECK(instance, fn, set ? MASK_SET : MASK_GET);
    if (nvr == 0) return fmi3OK;
    if (!vr) return (fmi3Status)model_null_arg(&INST(instance)->m, fn, "valueReferences");
    if (!values) return (fmi3Status)model_null_arg(&INST(instance)->m, fn, "values");
    model_fail(&INST(instance)->m, "%s: value reference %u is not a variable of this type", fn,
               vr[0]);
    return fmi3Error;
}

#define NO_SUCH_GET(NAME, T)                                                                    \
    fmi3Status fmi3Get##NAME(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                             size_t nValueReferences, T values[], size_t nValues)               \
    {                                                                                           \
        (void)nValues;                                                                          \
        return no_such_type(instance, "fmi3Get" #NAME, 0, valueReferences, nValueReferences,    \
                            (const void *)values);                                              \
    }
#define NO_SUCH_SET(NAME, T)                                                                    \
    fmi3Status fmi3Set##NAME(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                             size_t nValueReferences, const T values[], size_t nValues)         \
    {                                                                                           \
        (void)nValues;                                                                          \
        return no_such_type(instance, "fmi3Set" #NAME, 1, valueReferences, nValueReferences,    \
                            (const void *)values);                                              \
    }

NO_SUCH_GET(Float32, fmi3Float32)
NO_SUCH_GET(Int8, fmi3Int8)
NO_SUCH_GET(UInt8, fmi3UInt8)
NO_SUCH_GET(Int16, fmi3Int16)
NO_SUCH_GET(UInt16, fmi3UInt16)
NO_SUCH_GET(UInt32, fmi3UInt32)
NO_SUCH_GET(UInt64, fmi3UInt64)
NO_SUCH_GET(String, fmi3String)
NO_SUCH_SET(Float32, fmi3Float32)
NO_SUCH_SET(Int8, fmi3Int8)
NO_SUCH_SET(UInt8, fmi3UInt8)
NO_SUCH_SET(Int16, fmi3Int16)
NO_SUCH_SET(UInt16, fmi3UInt16)
NO_SUCH_SET(UInt32, fmi3UInt32)
NO_SUCH_SET(UInt64, fmi3UInt64)
NO_SUCH_SET(String, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, size_t valueSizes[], fmi3Binary values[],
                         size_t nValues)
{
    (void)nValues;
    if (instance && nValueReferences > 0 && !valueSizes)
        return (fmi3Status)model_null_arg(&INST(instance)->m, "fmi3GetBinary", "valueSizes");
    return no_such_type(instance, "fmi3GetBinary", 0, valueReferences, nValueReferences,
                        (const void *)values);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues)
{
    (void)nValues;
    if (instance && nValueReferences > 0 && !valueSizes)
        return (fmi3Status)model_null_arg(&INST(instance)->m, "fmi3SetBinary", "valueSizes");
    return no_such_type(instance, "fmi3SetBinary", 1, valueReferences, nValueReferences,
                        (const void *)values);
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Clock values[])
{
    return no_such_type(instance, "fmi3GetClock", 0, valueReferences, nValueReferences,
                        (const void *)values);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Clock values[])
{
    return no_such_type(instance, "fmi3SetClock", 1, valueReferences, nValueReferences,
                        (const void *)values);
}

/* ------------------------------------------------ variable dependencies */

/* Not provided: refused with a message, the instance stays usable (nothing of
 * it is read or changed).  The model description declares no dependencies. */
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance,
                                               fmi3ValueReference valueReference,
                                               size_t *nDependencies)
{
    CHECK(instance, "fmi3GetNumberOfVariableDependencies", MASK_ANY);
    NEED(instance, "fmi3GetNumberOfVariableDependencies", nDependencies);
    return (fmi3Status)model_refuse(&INST(instance)->m,
                                    "fmi3GetNumberOfVariableDependencies (value reference %u): "
                                    "variable dependencies are not provided by this FMU (the "
                                    "model description declares none); the instance is "
                                    "unaffected", valueReference);
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies)
{
    (void)elementIndicesOfDependent;
    (void)independents;
    (void)elementIndicesOfIndependents;
    (void)dependencyKinds;
    CHECK(instance, "fmi3GetVariableDependencies", MASK_ANY);
    return (fmi3Status)model_refuse(&INST(instance)->m,
                                    "fmi3GetVariableDependencies (value reference %u, "
                                    "nDependencies = %lu): variable dependencies are not provided "
                                    "by this FMU (the model description declares none); the "
                                    "instance is unaffected", dependent,
                                    (unsigned long)nDependencies);
}

/* ------------------------------------------------------------- FMU state */

/* A state object: the instance's data packed (fmu_instance.h), malloc'd at its size; a
 * state to overwrite of another size is replaced (the new one allocated first: a failure
 * leaves the old one). */
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    inst3 *s = INST(instance);
    void *d, *old;
    size_t size;
    CHECK(instance, "fmi3GetFMUState", MASK_FMUSTATE);
    NEED(instance, "fmi3GetFMUState", FMUState);
    old = d = *FMUState;
    if (old && model_state_check(&s->m, "fmi3GetFMUState (state to overwrite)", old) != ST_OK)
        return fmi3Error;
    size = model_state_size(&s->m.d);
    if (!old || model_state_stored_size(old) != size) {
        d = malloc(size);
        if (!d) return (fmi3Status)model_refuse(&s->m, "fmi3GetFMUState: out of memory");
        free(old);
    }
    model_state_pack(&s->m.d, d);
    *FMUState = d;
    return fmi3OK;
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    inst3 *s = INST(instance);
    CHECK(instance, "fmi3SetFMUState", MASK_RESTORE);
    if (model_state_check(&s->m, "fmi3SetFMUState", FMUState) != ST_OK) return fmi3Error;
    model_state_restore(&s->m);
    return fmi3OK;
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    if (!instance) return fmi3Error;
    NEED(instance, "fmi3FreeFMUState", FMUState);
    if (!*FMUState) return fmi3OK; /* the standard: a NULL state is ignored */
    free(*FMUState);
    *FMUState = NULL;
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size)
{
    inst3 *s = INST(instance);
    CHECK(instance, "fmi3SerializedFMUStateSize", MASK_FMUSTATE);
    NEED(instance, "fmi3SerializedFMUStateSize", FMUState);
    NEED(instance, "fmi3SerializedFMUStateSize", size);
    if (model_state_check(&s->m, "fmi3SerializedFMUStateSize", FMUState) != ST_OK)
        return fmi3Error;
    *size = model_state_stored_size(FMUState);
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size)
{
    inst3 *s = INST(instance);
    size_t need;
    CHECK(instance, "fmi3SerializeFMUState", MASK_FMUSTATE);
    if (model_state_check(&s->m, "fmi3SerializeFMUState", FMUState) != ST_OK) return fmi3Error;
    NEED(instance, "fmi3SerializeFMUState", serializedState);
    need = model_state_stored_size(FMUState);
    if (size < need)
        return (fmi3Status)model_refuse(&s->m, "fmi3SerializeFMUState: buffer of %lu bytes, %lu "
                                        "needed", (unsigned long)size, (unsigned long)need);
    memcpy(serializedState, FMUState, need);
    return fmi3OK;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState *FMUState)
{
    inst3 *s = INST(instance);
    void *d, *old;
    CHECK(instance, "fmi3DeserializeFMUState", MASK_RESTORE);
    NEED(instance, "fmi3DeserializeFMUState", FMUState);
    NEED(instance, "fmi3DeserializeFMUState", serializedState);
    old = *FMUState;
    if (old &&
        model_state_check(&s->m, "fmi3DeserializeFMUState (state to overwrite)", old) != ST_OK)
        return fmi3Error;
    /* the bytes are checked where they are (any alignment); a state to overwrite is
     * replaced only by bytes that passed, and kept if its size is theirs */
    if (model_state_load(&s->m, "fmi3DeserializeFMUState", serializedState, size) != ST_OK)
        return fmi3Error;
    if (old && model_state_stored_size(old) == size) {
        d = old;
    } else {
        d = malloc(size);
        if (!d) return (fmi3Status)model_refuse(&s->m, "fmi3DeserializeFMUState: out of memory");
        free(old);
    }
    memcpy(d, serializedState, size);
    *FMUState = d;
    return fmi3OK;
}

/* ------------------------------------------------------------ derivatives */

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return unsupported(instance, "fmi3GetDirectionalDerivative");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return unsupported(instance, "fmi3GetAdjointDerivative");
}

/* ------------------------------------------------- configuration, clocks */

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EnterConfigurationMode");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3ExitConfigurationMode");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)intervals;
    (void)qualifiers;
    return unsupported(instance, "fmi3GetIntervalDecimal");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance,
                                   const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[],
                                   fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    (void)qualifiers;
    return unsupported(instance, "fmi3GetIntervalFraction");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)shifts;
    return unsupported(instance, "fmi3GetShiftDecimal");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[],
                                fmi3UInt64 resolutions[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    return unsupported(instance, "fmi3GetShiftFraction");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)intervals;
    return unsupported(instance, "fmi3SetIntervalDecimal");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance,
                                   const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    return unsupported(instance, "fmi3SetIntervalFraction");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)shifts;
    return unsupported(instance, "fmi3SetShiftDecimal");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    return unsupported(instance, "fmi3SetShiftFraction");
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EvaluateDiscreteStates");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime)
{
    (void)discreteStatesNeedUpdate;
    (void)terminateSimulation;
    (void)nominalsOfContinuousStatesChanged;
    (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined;
    (void)nextEventTime;
    return unsupported(instance, "fmi3UpdateDiscreteStates");
}

/* -------------------------------------------------------- model exchange */

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EnterContinuousTimeMode");
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return unsupported(instance, "fmi3CompletedIntegratorStep");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    (void)time;
    return unsupported(instance, "fmi3SetTime");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates;
    (void)nContinuousStates;
    return unsupported(instance, "fmi3SetContinuousStates");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates)
{
    (void)derivatives;
    (void)nContinuousStates;
    return unsupported(instance, "fmi3GetContinuousStateDerivatives");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators)
{
    (void)eventIndicators;
    (void)nEventIndicators;
    return unsupported(instance, "fmi3GetEventIndicators");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates;
    (void)nContinuousStates;
    return unsupported(instance, "fmi3GetContinuousStates");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates)
{
    (void)nominals;
    (void)nContinuousStates;
    return unsupported(instance, "fmi3GetNominalsOfContinuousStates");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators)
{
    CHECK(instance, "fmi3GetNumberOfEventIndicators", MASK_ANY);
    NEED(instance, "fmi3GetNumberOfEventIndicators", nEventIndicators);
    *nEventIndicators = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates)
{
    CHECK(instance, "fmi3GetNumberOfContinuousStates", MASK_ANY);
    NEED(instance, "fmi3GetNumberOfContinuousStates", nContinuousStates);
    *nContinuousStates = 0;
    return fmi3OK;
}

/* ----------------------------------------------------------- co-simulation */

fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EnterStepMode");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance,
                                    const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[],
                                    fmi3Float64 values[], size_t nValues)
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)orders;
    (void)values;
    (void)nValues;
    return unsupported(instance, "fmi3GetOutputDerivatives");
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    inst3 *s = INST(instance);
    model_status st;
    (void)noSetFMUStatePriorToCurrentPoint;
    CHECK(instance, "fmi3DoStep", MS_STEP);
    NEED(instance, "fmi3DoStep", eventHandlingNeeded);
    NEED(instance, "fmi3DoStep", terminateSimulation);
    NEED(instance, "fmi3DoStep", earlyReturn);
    NEED(instance, "fmi3DoStep", lastSuccessfulTime);
    st = model_do_step(&s->m, currentCommunicationPoint, communicationStepSize);
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = s->m.d.t_now;
    return (fmi3Status)st;
}

/* ----------------------------------------------------- scheduled execution */

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference;
    (void)activationTime;
    return unsupported(instance, "fmi3ActivateModelPartition");
}
