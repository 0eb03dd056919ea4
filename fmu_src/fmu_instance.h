/*
 * fmu_instance.h -- the FMU instance, independent of the FMI version
 * (fmu_instance.c): its life cycle (start values, reset), the state machine
 * and the check of each call against it, and the FMU state (size, checksum,
 * seal, validation).
 *
 * It sits over the model (fmu_model.h, included here), which sits over the
 * base (fmu_base.h: the data of an instance, logging and error reporting, the
 * variable table).  fmi2.c and fmi3.c are thin wrappers that translate FMI
 * calls into the functions of these three headers.
 */
#ifndef FMU_INSTANCE_H
#define FMU_INSTANCE_H

#include <stddef.h>
#include <stdint.h>

#include "fmu_model.h"

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility push(hidden)
#endif

/* Initialise an instance (the model's start values, state Instantiated). */
void model_init(model_instance *m, int fmi_version, const char *instance_name,
                model_logger logger, void *logger_env, int logging_on);
void model_reset(model_instance *m);

/* The call is allowed in the current state (mask of model_state), else log and
 * return 0.  An error moves the instance to MS_ERROR. */
int model_allowed(model_instance *m, const char *fn, int mask);
/* The same test, inline for the calls of every step. */
#define MODEL_ALLOWED(m, fn, mask) (((m)->d.state & (mask)) != 0 || model_allowed((m), (fn), (mask)))

/* State machine. */
model_status model_enter_init(model_instance *m);
model_status model_exit_init(model_instance *m); /* the model starts (model_start) */
model_status model_terminate(model_instance *m);

/* FMU state: bytes of model_data, sealed with a checksum (model_state_seal)
 * when saved.  model_state_check verifies, in place, a state object the FMU
 * allocated (an aligned model_data): header, token, checksum, the state
 * machine value and then the structure of everything a restore would bring
 * back (model_state_flaw: counts, indices, ordering, finiteness, outputs
 * consistent with the plan); a refusal is logged (naming fn) and leaves the
 * instance as it was.  model_state_load takes serialised bytes (any
 * alignment): their size (model_state_check_size, also on its own: before
 * allocating), then the same checks on their copy in into (an allocated
 * model_data, not to be used if refused).  No state is ever copied to the
 * stack. */
size_t model_state_size(void);
uint64_t model_state_checksum(const model_data *d);
void model_state_seal(model_data *d);
model_status model_state_check(model_instance *m, const char *fn, const model_data *d);
model_status model_state_check_size(model_instance *m, const char *fn, size_t size);
model_status model_state_load(model_instance *m, const char *fn, const void *bytes, size_t size,
                              model_data *into);

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility pop
#endif

#endif /* FMU_INSTANCE_H */
