/*
 * fmu_model.h -- the FMU instance, independent of the FMI version.
 *
 * fmi2.c and fmi3.c are thin wrappers that translate FMI calls into the
 * functions below.  All the data of an instance that an FMU state must
 * capture is in model_data: plain values, no pointers, so an FMU state is a
 * copy of it and serialising it is a memcpy.
 */
#ifndef FMU_MODEL_H
#define FMU_MODEL_H

#include <stddef.h>
#include <stdint.h>

#include "djl_core.h"
#include "djl_vars.h"

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

/* Same numbering as fmi2Status and fmi3Status. */
typedef enum { ST_OK = 0, ST_WARNING = 1, ST_DISCARD = 2, ST_ERROR = 3, ST_FATAL = 4 } model_status;

#define MODEL_MAGIC 0x4a4c4446u /* "FDLJ" */
#define MODEL_LAYOUT 4u

/* The figures of the parametric move planned at initialisation (the calculated
 * parameters motion_time, N_F1..N_F4, v_reached, a_reached, d_reached): commands
 * replace the plan, not them. */
typedef struct {
    int64_t k_end;
    int32_t N[4];
    double v_reached, a_reached, d_reached;
} plan_summary;

typedef struct {
    uint32_t magic;
    uint32_t layout;
    uint32_t size;          /* sizeof(model_data), checked on deserialisation */
    int32_t state;          /* model_state */
    uint64_t checksum;      /* FNV-1a 64 of all the other bytes, set in a saved FMU state */
    char token[48];         /* instantiation token of the FMU that made the state */
    djl_params p;
    double t_start;         /* s */
    double start_time;      /* s, FMU start time */
    int64_t n;              /* whole samples of Te since start_time: the profile's time is */
    double phase;           /* n + phase samples after start_time, phase in [0, 1) */
    double t_now;           /* s, the communication point reached (the master's clock) */
    double offset;          /* (t_start - start_time)/Te, made integral when within 1e-9 */
    int32_t planned;        /* plan matches the parameters */
    int32_t cursor;
    djl_plan plan;
    djl_sample out;         /* outputs at the current time */
    /* commanded generator (docs/generator.md, "Commanded moves") */
    int32_t jerk_source;    /* parameter: 1 jerk times T_F1..T_F4, 2 from the input f_mode,
                               3 from f_mode extrapolated to each stage's start */
    int32_t execute, stop;  /* Boolean inputs, 0 or 1 */
    int32_t execute_seen, stop_seen; /* their values at the previous DoStep (edges) */
    int32_t goal;           /* 0 the parametric move; DJL_GOAL_TARGET; DJL_GOAL_STOP */
    double target;          /* m, input */
    double f_mode;          /* Hz, input */
    double goal_target;     /* m, target of the commanded move in progress */
    double f_seen, t_seen;  /* f_mode at the previous DoStep and its time (jerk_source = 3) */
    double f_rate;          /* Hz/s, f_mode's rate of change over the last step */
    int64_t replans;        /* replans made (logs) */
    plan_summary first;
} model_data;

typedef void (*model_logger)(void *env, model_status status, const char *category,
                             const char *message);

typedef struct {
    model_data d;
    /* environment: not part of an FMU state */
    int fmi_version;
    char instance_name[128];
    model_logger logger;
    void *logger_env;
    int logging_on;
    int category_on[DJL_LOG_N];
    /* the last whole-sample step size seen by DoStep and its count of samples (a cache:
     * derived from h and Te alone, so not part of an FMU state) */
    double step_h, step_Te, step_whole;
    /* work space of a replan (its new motion): not part of an FMU state */
    djl_plan scratch;
} model_instance;

/* Initialise an instance (default parameters, state Instantiated). */
void model_init(model_instance *m, int fmi_version, const char *instance_name,
                model_logger logger, void *logger_env, int logging_on);
void model_reset(model_instance *m);

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

/* Variable access.  vr is an element value reference (FMI 2 style: arrays at
 * base + i); type is 'R', 'I' or 'B'. */
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

/* The per-step reads of a master, in one call: when the instance is planned, its state is
 * in mask and every reference is a Real output of the profile (x, v, a, j, x_AL, v_AL,
 * a_AL), write the n values and return 1; otherwise return 0 (nothing logged: the caller
 * takes the general path, which gives the same values or the error). */
int model_get_reals_fast(const model_instance *m, int mask, const unsigned int *vr, size_t n,
                         double *value);

model_status model_set(model_instance *m, unsigned int vr, char type, double value);
model_status model_get(model_instance *m, unsigned int vr, char type, double *value);

model_status model_setup(model_instance *m, double start_time);
model_status model_enter_init(model_instance *m);
model_status model_exit_init(model_instance *m);
model_status model_do_step(model_instance *m, double t, double h);
model_status model_terminate(model_instance *m);

/* FMU state: bytes of model_data, sealed with a checksum (model_state_seal)
 * when saved.  model_state_check verifies size, header, checksum and then
 * the structure of everything a restore would bring back (state value,
 * counts, indices, ordering, finiteness, outputs consistent with the plan);
 * a refusal is logged (naming fn) and leaves the instance as it was. */
size_t model_state_size(void);
uint64_t model_state_checksum(const model_data *d);
void model_state_seal(model_data *d);
model_status model_state_check(model_instance *m, const char *fn, const void *bytes, size_t size);

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility pop
#endif

#endif /* FMU_MODEL_H */
