/*
 * fmu_model.h -- the model of the FMU (fmu_model.c): its start values, its
 * variables (parameters, inputs, outputs, calculated parameters), the plan
 * made at the end of initialisation, DoStep (the profile's time, commands,
 * replans, input shaping), and the structural checks of the model's part of an
 * FMU state.  Independent of the FMI version.
 *
 * It works on the data of fmu_base.h (model_instance: model_data, the model's
 * work space) and reports through the base's logging and errors; it knows
 * nothing of the instance above it (fmu_instance.h: life cycle, state machine,
 * FMU state), which calls the first three functions below.  fmi2.c and fmi3.c
 * include fmu_instance.h, which includes this header.
 */
#ifndef FMU_MODEL_H
#define FMU_MODEL_H

#include <stddef.h>

#include "fmu_base.h"

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility push(hidden)
#endif

/* ------------------------------------------------------------------------ */
/* called by the instance (fmu_instance.c)                                  */

/* The model's start values in d (zeroed, its header already written). */
void model_defaults(model_data *d);

/* Structure of the model's part of a state whose header, checksum and state
 * machine value were checked: NULL if sound, else why not. */
const char *model_state_flaw(const model_data *d);
/* Its part on the plan's consistency (pieces continuous, pieces and steps one motion, the
 * last piece cruising, no velocity peak above vlim inside a piece): NULL, or why not. */
const char *model_plan_inconsistency(const djl_plan *pl, double vlim);

/* At the end of initialisation: plan (if the parameters changed since) and
 * start counting the inputs' edges from here. */
model_status model_start(model_instance *m);

/* ------------------------------------------------------------------------ */
/* called by the FMI layers (fmi2.c, fmi3.c)                                */

/* The start time: the origin of the generator's sample grid. */
model_status model_setup(model_instance *m, double start_time);

/* The per-step reads of a master, in one call: when the instance is planned, its state is
 * in mask and every reference is a Real output of the profile (x, v, a, j, x_AL, v_AL,
 * a_AL), write the n values and return 1; otherwise return 0 (nothing logged: the caller
 * takes the general path, which gives the same values or the error). */
int model_get_reals_fast(const model_instance *m, int mask, const unsigned int *vr,
                         size_t n, double *value);

/* Variable access.  vr is an element value reference (FMI 2 style: arrays at
 * base + i); type is 'R', 'I' or 'B'. */
model_status model_set(model_instance *m, unsigned int vr, char type, double value);
model_status model_get(model_instance *m, unsigned int vr, char type, double *value);

model_status model_do_step(model_instance *m, double t, double h);

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility pop
#endif

#endif /* FMU_MODEL_H */
