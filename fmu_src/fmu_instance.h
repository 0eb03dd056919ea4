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

/* Initialise an instance (the model's start values, state Instantiated); alloc (calloc-like)
 * and release are the memory functions of the check area of states, model_free releases
 * it. */
void model_init(model_instance *m, int fmi_version, const char *instance_name,
                model_logger logger, void *logger_env, int logging_on,
                void *(*alloc)(size_t n, size_t size), void (*release)(void *p));
void model_free(model_instance *m);
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

/* FMU state: model_data packed (model_state_pack: its bytes up to the entries of the
 * shaper's rings, then their live entries; about 30 kB, at most model_state_max_size),
 * sealed with a checksum.  model_state_check verifies a state object the FMU allocated,
 * of the size its header states; model_state_load serialised bytes of a given size (any
 * alignment): header, size, token, checksum, the rings' counts against the size, the
 * state machine value and then the structure of everything a restore would bring back
 * (model_state_flaw: counts, indices, ordering, finiteness, limits, outputs consistent
 * with the plan), on the state unpacked into m->load (allocated at the first check: out
 * of memory is a refusal).  A refusal is logged (naming fn) and leaves the instance as it
 * was; after ST_OK, model_state_restore makes m->load the instance's data.  No state is ever copied to the stack. */
size_t model_state_size(const model_data *d);  /* of d packed */
size_t model_state_max_size(void);
size_t model_state_stored_size(const void *state); /* its header's (a checked state) */
uint64_t model_state_checksum(const void *state, size_t size);
void model_state_seal(void *state, size_t size);
void model_state_pack(const model_data *d, void *state); /* model_state_size(d) bytes, sealed */
void model_state_unpack(const void *state, model_data *d); /* no check (tests forge with it) */
model_status model_state_check(model_instance *m, const char *fn, const void *state);
model_status model_state_load(model_instance *m, const char *fn, const void *bytes, size_t size);
void model_state_restore(model_instance *m);

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility pop
#endif

#endif /* FMU_INSTANCE_H */
