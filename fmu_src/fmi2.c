/*
 * fmi2.c -- FMI 2.0 co-simulation interface: a thin translation of the FMI 2
 * API onto the instance (fmu_instance.c), the model (fmu_model.c) and the
 * base under them (fmu_base.c: logging, errors, the variable table).  Built
 * with the FMI headers shipped by the importer (fmpy: fmpy/c-code).
 */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "fmu_instance.h"

typedef struct {
    model_instance m;
    fmi2CallbackFunctions cb;
} inst2;

/* FMI 2 loggers take a printf format: keep '%' out of messages. */
static void logger2(void *env, model_status st, const char *category, const char *message)
{
    inst2 *s = (inst2 *)env;
    char buf[1024];
    size_t i;
    if (!s || !s->cb.logger) return;
    for (i = 0; message[i] && i + 1 < sizeof buf; i++) buf[i] = message[i] == '%' ? '#' : message[i];
    buf[i] = '\0';
    s->cb.logger(s->cb.componentEnvironment, s->m.instance_name, (fmi2Status)st, category, buf);
}

#define MASK_ANY (MS_INSTANTIATED | MS_INIT | MS_STEP | MS_TERMINATED | MS_ERROR)
#define MASK_GET (MS_INIT | MS_STEP | MS_TERMINATED | MS_ERROR)
#define MASK_SET (MS_INSTANTIATED | MS_INIT | MS_STEP)
#define MASK_FMUSTATE (MS_INSTANTIATED | MS_INIT | MS_STEP | MS_TERMINATED)
/* after an error, a formerly stored FMU state may be restored (FMI 2.0.4, 2.1.3) */
#define MASK_RESTORE (MASK_FMUSTATE | MS_ERROR)

#define INST(c) ((inst2 *)(c))
#define CHECK(c, fn, mask)                                                                       \
    do {                                                                                         \
        if (!(c)) return fmi2Error;                                                              \
        if (!MODEL_ALLOWED(&INST(c)->m, fn, mask)) return fmi2Error;                             \
    } while (0)
/* A pointer argument that must not be NULL: refused, the instance unchanged. */
#define NEED(c, fn, ptr)                                                                         \
    do {                                                                                         \
        if (!(ptr)) return (fmi2Status)model_null_arg(&INST(c)->m, fn, #ptr);                    \
    } while (0)

static fmi2Status unsupported(fmi2Component c, const char *fn)
{
    if (!c) return fmi2Error;
    model_fail(&INST(c)->m, "%s is not supported: this FMU is for co-simulation only", fn);
    return fmi2Error;
}

/* ---------------------------------------------------------------- common */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }

const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    CHECK(c, "fmi2SetDebugLogging", MASK_ANY);
    return (fmi2Status)model_set_debug_logging(&INST(c)->m, "fmi2SetDebugLogging",
                                               loggingOn != fmi2False, nCategories, categories);
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    inst2 *s;
    (void)fmuResourceLocation;
    (void)visible;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    if (!instanceName || !instanceName[0]) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, "?", fmi2Error, "logStatusError",
                              "fmi2Instantiate: instanceName must be a non-empty string");
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError",
                              "fmi2Instantiate: this FMU supports co-simulation only");
        return NULL;
    }
    if (!fmuGUID || strcmp(fmuGUID, DJL_INSTANTIATION_TOKEN) != 0) {
        if (functions->logger)
            functions->logger(functions->componentEnvironment, instanceName, fmi2Error,
                              "logStatusError",
                              "fmi2Instantiate: the GUID does not match this binary's "
                              DJL_INSTANTIATION_TOKEN " (model description and binary differ)");
        return NULL;
    }
    s = (inst2 *)functions->allocateMemory(1, sizeof(inst2));
    if (!s) return NULL;
    s->cb = *functions;
    model_init(&s->m, 2, instanceName, logger2, s, loggingOn != fmi2False,
               functions->allocateMemory, functions->freeMemory);
    return s;
}

void fmi2FreeInstance(fmi2Component c)
{
    inst2 *s = INST(c);
    fmi2CallbackFreeMemory fr;
    if (!s) return;
    fr = s->cb.freeMemory;
    model_free(&s->m);
    fr(s);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    CHECK(c, "fmi2SetupExperiment", MS_INSTANTIATED);
    return (fmi2Status)model_setup(&INST(c)->m, startTime);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    CHECK(c, "fmi2EnterInitializationMode", MS_INSTANTIATED);
    return (fmi2Status)model_enter_init(&INST(c)->m);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    CHECK(c, "fmi2ExitInitializationMode", MS_INIT);
    return (fmi2Status)model_exit_init(&INST(c)->m);
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    CHECK(c, "fmi2Terminate", MS_STEP);
    return (fmi2Status)model_terminate(&INST(c)->m);
}

fmi2Status fmi2Reset(fmi2Component c)
{
    /* always allowed: whatever state the instance is in, Reset brings it back */
    if (!c) return fmi2Error;
    model_reset(&INST(c)->m);
    return fmi2OK;
}

/* ------------------------------------------------------ getters / setters */

static fmi2Status get_values(fmi2Component c, const char *fn, const fmi2ValueReference vr[],
                             size_t nvr, char type, fmi2Real *r, fmi2Integer *i, fmi2Boolean *b)
{
    size_t k;
    CHECK(c, fn, MASK_GET);
    if (nvr > 0 && !vr) return (fmi2Status)model_null_arg(&INST(c)->m, fn, "vr");
    if (nvr > 0 && !r && !i && !b) return (fmi2Status)model_null_arg(&INST(c)->m, fn, "value");
    for (k = 0; k < nvr; k++) {
        double v = 0.0;
        if (model_get(&INST(c)->m, vr[k], type, &v) != ST_OK) return fmi2Error;
        if (r) r[k] = v;
        if (i) i[k] = (fmi2Integer)v;
        if (b) b[k] = v != 0.0 ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       fmi2Real value[])
{
    if (c && vr && value && model_get_reals_fast(&INST(c)->m, MASK_GET, vr, nvr, value))
        return fmi2OK; /* a master's per-step reads */
    return get_values(c, "fmi2GetReal", vr, nvr, 'R', value, NULL, NULL);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    return get_values(c, "fmi2GetInteger", vr, nvr, 'I', NULL, value, NULL);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    return get_values(c, "fmi2GetBoolean", vr, nvr, 'B', NULL, NULL, value);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    CHECK(c, "fmi2GetString", MASK_GET);
    if (nvr == 0) return fmi2OK;
    NEED(c, "fmi2GetString", vr);
    NEED(c, "fmi2GetString", value);
    model_fail(&INST(c)->m, "fmi2GetString: unknown value reference %u (this FMU has no String "
               "variables)", vr[0]);
    return fmi2Error;
}

static fmi2Status set_values(fmi2Component c, const char *fn, const fmi2ValueReference vr[],
                             size_t nvr, char type, const fmi2Real *r, const fmi2Integer *i,
                             const fmi2Boolean *b)
{
    size_t k;
    CHECK(c, fn, MASK_SET);
    if (nvr > 0 && !vr) return (fmi2Status)model_null_arg(&INST(c)->m, fn, "vr");
    if (nvr > 0 && !r && !i && !b) return (fmi2Status)model_null_arg(&INST(c)->m, fn, "value");
    for (k = 0; k < nvr; k++) {
        double v = r ? r[k] : i ? (double)i[k] : (b[k] ? 1.0 : 0.0);
        if (model_set(&INST(c)->m, vr[k], type, v) != ST_OK) return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    return set_values(c, "fmi2SetReal", vr, nvr, 'R', value, NULL, NULL);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    return set_values(c, "fmi2SetInteger", vr, nvr, 'I', NULL, value, NULL);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    return set_values(c, "fmi2SetBoolean", vr, nvr, 'B', NULL, NULL, value);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    CHECK(c, "fmi2SetString", MASK_SET);
    if (nvr == 0) return fmi2OK;
    NEED(c, "fmi2SetString", vr);
    NEED(c, "fmi2SetString", value);
    model_fail(&INST(c)->m, "fmi2SetString: unknown value reference %u (this FMU has no String "
               "variables)", vr[0]);
    return fmi2Error;
}

/* ------------------------------------------------------------- FMU state */

/* A state object: the instance's data packed (fmu_instance.h), allocated with the
 * importer's allocateMemory at its size; a state to overwrite of another size is replaced
 * (the new one allocated first: a failure leaves the old one). */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    inst2 *s = INST(c);
    void *d, *old;
    size_t size;
    CHECK(c, "fmi2GetFMUstate", MASK_FMUSTATE);
    NEED(c, "fmi2GetFMUstate", FMUstate);
    old = d = *FMUstate;
    if (old && model_state_check(&s->m, "fmi2GetFMUstate (state to overwrite)", old) != ST_OK)
        return fmi2Error;
    size = model_state_size(&s->m.d);
    if (!old || model_state_stored_size(old) != size) {
        d = s->cb.allocateMemory(1, size);
        if (!d) return (fmi2Status)model_refuse(&s->m, "fmi2GetFMUstate: out of memory");
        if (old) s->cb.freeMemory(old);
    }
    model_state_pack(&s->m.d, d);
    *FMUstate = d;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    inst2 *s = INST(c);
    CHECK(c, "fmi2SetFMUstate", MASK_RESTORE);
    if (model_state_check(&s->m, "fmi2SetFMUstate", FMUstate) != ST_OK) return fmi2Error;
    model_state_restore(&s->m);
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    inst2 *s = INST(c);
    if (!s) return fmi2Error;
    NEED(c, "fmi2FreeFMUstate", FMUstate);
    if (!*FMUstate) return fmi2OK; /* the standard: a NULL state is ignored */
    s->cb.freeMemory(*FMUstate);
    *FMUstate = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    inst2 *s = INST(c);
    CHECK(c, "fmi2SerializedFMUstateSize", MASK_FMUSTATE);
    NEED(c, "fmi2SerializedFMUstateSize", FMUstate);
    NEED(c, "fmi2SerializedFMUstateSize", size);
    if (model_state_check(&s->m, "fmi2SerializedFMUstateSize", FMUstate) != ST_OK)
        return fmi2Error;
    *size = model_state_stored_size(FMUstate);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size)
{
    inst2 *s = INST(c);
    size_t need;
    CHECK(c, "fmi2SerializeFMUstate", MASK_FMUSTATE);
    if (model_state_check(&s->m, "fmi2SerializeFMUstate", FMUstate) != ST_OK) return fmi2Error;
    NEED(c, "fmi2SerializeFMUstate", serializedState);
    need = model_state_stored_size(FMUstate);
    if (size < need)
        return (fmi2Status)model_refuse(&s->m, "fmi2SerializeFMUstate: buffer of %lu bytes, %lu "
                                        "needed", (unsigned long)size, (unsigned long)need);
    memcpy(serializedState, FMUstate, need);
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    inst2 *s = INST(c);
    void *d, *old;
    CHECK(c, "fmi2DeSerializeFMUstate", MASK_RESTORE);
    NEED(c, "fmi2DeSerializeFMUstate", FMUstate);
    NEED(c, "fmi2DeSerializeFMUstate", serializedState);
    old = *FMUstate;
    if (old &&
        model_state_check(&s->m, "fmi2DeSerializeFMUstate (state to overwrite)", old) != ST_OK)
        return fmi2Error;
    /* the bytes are checked where they are (any alignment); a state to overwrite is
     * replaced only by bytes that passed, and kept if its size is theirs */
    if (model_state_load(&s->m, "fmi2DeSerializeFMUstate", serializedState, size) != ST_OK)
        return fmi2Error;
    if (old && model_state_stored_size(old) == size) {
        d = old;
    } else {
        d = s->cb.allocateMemory(1, size);
        if (!d) return (fmi2Status)model_refuse(&s->m, "fmi2DeSerializeFMUstate: out of memory");
        if (old) s->cb.freeMemory(old);
    }
    memcpy(d, serializedState, size);
    *FMUstate = d;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return unsupported(c, "fmi2GetDirectionalDerivative");
}

/* -------------------------------------------------------- model exchange */

fmi2Status fmi2EnterEventMode(fmi2Component c) { return unsupported(c, "fmi2EnterEventMode"); }

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo)
{
    (void)eventInfo;
    return unsupported(c, "fmi2NewDiscreteStates");
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    return unsupported(c, "fmi2EnterContinuousTimeMode");
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode,
                                       fmi2Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return unsupported(c, "fmi2CompletedIntegratorStep");
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    (void)time;
    return unsupported(c, "fmi2SetTime");
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    (void)x;
    (void)nx;
    return unsupported(c, "fmi2SetContinuousStates");
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx)
{
    (void)derivatives;
    (void)nx;
    return unsupported(c, "fmi2GetDerivatives");
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni)
{
    (void)eventIndicators;
    (void)ni;
    return unsupported(c, "fmi2GetEventIndicators");
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    (void)x;
    (void)nx;
    return unsupported(c, "fmi2GetContinuousStates");
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx)
{
    (void)x_nominal;
    (void)nx;
    return unsupported(c, "fmi2GetNominalsOfContinuousStates");
}

/* ----------------------------------------------------------- co-simulation */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr;
    (void)order;
    (void)value;
    CHECK(c, "fmi2SetRealInputDerivatives", MASK_SET);
    if (nvr == 0) return fmi2OK;
    model_fail(&INST(c)->m, "fmi2SetRealInputDerivatives: input derivatives are not used "
               "(canInterpolateInputs is false: inputs are held over a step)");
    return fmi2Error;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr;
    (void)order;
    (void)value;
    CHECK(c, "fmi2GetRealOutputDerivatives", MASK_GET);
    if (nvr == 0) return fmi2OK;
    model_fail(&INST(c)->m, "fmi2GetRealOutputDerivatives: not supported "
               "(canInterpolateInputs/maxOutputDerivativeOrder are not declared)");
    return fmi2Error;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    CHECK(c, "fmi2DoStep", MS_STEP);
    return (fmi2Status)model_do_step(&INST(c)->m, currentCommunicationPoint,
                                     communicationStepSize);
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    CHECK(c, "fmi2CancelStep", MS_STEP);
    model_fail(&INST(c)->m, "fmi2CancelStep: fmi2DoStep never returns fmi2Pending");
    return fmi2Error;
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s;
    CHECK(c, "fmi2GetStatus", MS_STEP | MS_TERMINATED);
    NEED(c, "fmi2GetStatus", value);
    *value = fmi2OK;
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    inst2 *st = INST(c);
    CHECK(c, "fmi2GetRealStatus", MS_STEP | MS_TERMINATED);
    NEED(c, "fmi2GetRealStatus", value);
    if (s != fmi2LastSuccessfulTime) {
        model_fail(&st->m, "fmi2GetRealStatus: only fmi2LastSuccessfulTime is available");
        return fmi2Error;
    }
    *value = st->m.d.t_now;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s;
    (void)value;
    CHECK(c, "fmi2GetIntegerStatus", MS_STEP | MS_TERMINATED);
    model_fail(&INST(c)->m, "fmi2GetIntegerStatus: no integer status is defined");
    return fmi2Error;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    CHECK(c, "fmi2GetBooleanStatus", MS_STEP | MS_TERMINATED);
    NEED(c, "fmi2GetBooleanStatus", value);
    if (s != fmi2Terminated) {
        model_fail(&INST(c)->m, "fmi2GetBooleanStatus: only fmi2Terminated is available");
        return fmi2Error;
    }
    *value = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s;
    (void)value;
    CHECK(c, "fmi2GetStringStatus", MS_STEP | MS_TERMINATED);
    model_fail(&INST(c)->m, "fmi2GetStringStatus: no string status is defined");
    return fmi2Error;
}
