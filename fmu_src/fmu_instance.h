/*
 * fmu_instance.h -- the FMU instance, independent of the FMI version and of
 * the model (fmu_instance.c): the state machine, logging, the checks of calls
 * and arguments, the variable table, and the FMU state (size, checksum,
 * validation).
 *
 * fmi2.c and fmi3.c are thin wrappers that translate FMI calls into the
 * functions below and into the model's (fmu_model.h, included here).
 */
#ifndef FMU_INSTANCE_H
#define FMU_INSTANCE_H

#include <stddef.h>
#include <stdint.h>

#include "djl_vars.h"
#include "fmu_model.h"

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility push(hidden)
#endif

/* States of the (co-simulation) state machine, as bit flags for masks. */
typedef enum {
    MS_START_END = 1 << 0,
    MS_INSTANTIATED = 1 << 1,
    MS_INIT = 1 << 2,
    MS_STEP = 1 << 3,      /* FMI 2 stepComplete, FMI 3 Step Mode */
    MS_TERMINATED = 1 << 4,
    MS_ERROR = 1 << 5      /* after an error: only get (diagnostics), reset and free */
} model_state;

typedef void (*model_logger)(void *env, model_status status, const char *category,
                             const char *message);

typedef struct model_instance {
    model_data d;
    /* environment: not part of an FMU state */
    int fmi_version;
    char instance_name[128];
    model_logger logger;
    void *logger_env;
    int logging_on;
    int category_on[DJL_LOG_N];
    model_work w; /* the model's work space */
} model_instance;

/* Initialise an instance (the model's start values, state Instantiated). */
void model_init(model_instance *m, int fmi_version, const char *instance_name,
                model_logger logger, void *logger_env, int logging_on);
void model_reset(model_instance *m);

/* Name of a state of the state machine (for messages). */
const char *model_state_name(int state);

/* Log through the importer's callback: errors always, warnings and events
 * only when their category is on. */
void model_log(const model_instance *m, model_status status, int category, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* The call is allowed in the current state (mask of model_state), else log and
 * return 0.  An error moves the instance to MS_ERROR. */
int model_allowed(model_instance *m, const char *fn, int mask);
/* The same test, inline for the calls of every step. */
#define MODEL_ALLOWED(m, fn, mask) (((m)->d.state & (mask)) != 0 || model_allowed((m), (fn), (mask)))
model_status model_fail(model_instance *m, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* An error that leaves the instance as it was (a bad argument detected before
 * anything was read or written): logged, the state does not change. */
model_status model_refuse(model_instance *m, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

/* A NULL pointer argument: refused with a message naming fn and arg. */
model_status model_null_arg(model_instance *m, const char *fn, const char *arg);

/* Categories are checked (NULL array, NULL entry) before anything changes. */
model_status model_set_debug_logging(model_instance *m, const char *fn, int logging_on, size_t n,
                                     const char *const categories[]);

/* A variable of the model description (djl_vars.h's table). */
typedef struct {
    unsigned int base;  /* value reference of the variable (array base) */
    unsigned int index; /* element */
    char type, causality; /* type 'R', 'I' or 'B' (an Enumeration is an 'I') */
    char enumeration;     /* 1: an Enumeration variable (FMI 3 accesses it as Int64) */
    unsigned short size;
    const char *name;
} model_var;
/* Look a value reference up; fmi3 = 1 accepts only declared (array base)
 * references.  Returns 0 if unknown. */
int model_lookup(unsigned int vr, int fmi3, model_var *out);
/* "Real", "Integer", "Boolean" for 'R', 'I', 'B' (for messages). */
const char *model_type_name(char type);

/* State machine. */
model_status model_enter_init(model_instance *m);
model_status model_exit_init(model_instance *m); /* the model starts (model_start) */
model_status model_terminate(model_instance *m);

/* FMU state: bytes of model_data, sealed with a checksum (model_state_seal)
 * when saved.  model_state_check verifies size, header, checksum, the state
 * machine value and then the structure of everything a restore would bring
 * back (model_state_flaw: counts, indices, ordering, finiteness, outputs
 * consistent with the plan); a refusal is logged (naming fn) and leaves the
 * instance as it was. */
size_t model_state_size(void);
uint64_t model_state_checksum(const model_data *d);
void model_state_seal(model_data *d);
model_status model_state_check(model_instance *m, const char *fn, const void *bytes, size_t size);

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility pop
#endif

#endif /* FMU_INSTANCE_H */
