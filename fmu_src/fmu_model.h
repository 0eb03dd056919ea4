/*
 * fmu_model.h -- the model of the FMU: the generator's data and the functions
 * of fmu_model.c (its variables, planning, DoStep, commands), independent of
 * the FMI version.
 *
 * All the data of an instance that an FMU state must capture is in model_data:
 * plain values, no pointers, so an FMU state is a copy of it and serialising
 * it is a memcpy.  Its first fields are the FMU state's header, which the
 * instance (fmu_instance.c) fills and checks; the rest is the model's.
 *
 * The instance, its state machine, logging and FMU state are in
 * fmu_instance.h, which includes this header; fmi2.c and fmi3.c include that.
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

/* Same numbering as fmi2Status and fmi3Status. */
typedef enum { ST_OK = 0, ST_WARNING = 1, ST_DISCARD = 2, ST_ERROR = 3, ST_FATAL = 4 } model_status;

#define MODEL_MAGIC 0x4a4c4446u /* "FDLJ" */
#define MODEL_LAYOUT 5u          /* of model_data: a state of another layout is refused */

/* The figures of the parametric move planned at initialisation (the calculated
 * parameters motion_time, N_F1..N_F4, v_reached, a_reached, d_reached): commands
 * replace the plan, not them. */
typedef struct {
    int64_t k_end;
    int32_t N[4];
    double v_reached, a_reached, d_reached;
} plan_summary;

typedef struct {
    /* the FMU state's header (fmu_instance.c) */
    uint32_t magic;
    uint32_t layout;
    uint32_t size;          /* sizeof(model_data), checked on deserialisation */
    int32_t state;          /* model_state (fmu_instance.h) */
    uint64_t checksum;      /* FNV-1a 64 of all the other bytes, set in a saved FMU state */
    char token[48];         /* instantiation token of the FMU that made the state */
    /* the model (fmu_model.c) */
    djl_params p;
    double t_start;         /* s */
    double start_time;      /* s, FMU start time */
    int64_t n;              /* whole samples of Te since start_time: the profile's time is */
    double phase;           /* n + phase samples after start_time, phase in [0, 1) */
    double t_now;           /* s, the communication point reached (the master's clock) */
    double offset;          /* samples from start_time to the motion start (djl_start_offset),
                               moved by each replan */
    int32_t planned;        /* plan matches the parameters */
    int32_t cursor;
    djl_plan plan;
    djl_sample out;         /* outputs at the current time */
    /* commanded generator (docs/generator.md, "Commanded moves") */
    int32_t jerk_source;    /* parameter: JERK_SOURCE_PARAMETERS (the jerk times T_F1..T_F4),
                               JERK_SOURCE_F_MODE (from the input f_mode), JERK_SOURCE_F_MODE_AHEAD
                               (from f_mode extrapolated to each stage's start) */
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
    /* input shaping (docs/generator.md, "Input shaping") */
    djl_shaper_params sp;   /* parameters shaper, f_shaper, zeta_shaper, shaper_source, shaper_n,
                               shaper_amplitude, shaper_delay */
    djl_shaper shaper;      /* designed with the plan (n = 0: no shaping) */
    int32_t shaper_cursor[DJL_MAX_SHAPER_IMPULSES]; /* piece hints of the delayed copies */
    djl_shaper_memory mem;  /* what the delayed copies read of the plans replans replaced; the
                               phase of f_mode (shaper_source = 2) */
} model_data;

/* The model's work space in an instance: not part of an FMU state. */
typedef struct {
    /* the last whole-sample step size seen by DoStep and its count of samples (a cache:
     * derived from h and Te alone) */
    double step_h, step_Te, step_whole;
    /* work space of a replan (its new motion) */
    djl_plan scratch;
} model_work;

struct model_instance; /* fmu_instance.h */

/* ------------------------------------------------------------------------ */
/* called by the instance (fmu_instance.c)                                  */

/* The model's start values in d (zeroed, its header already written). */
void model_defaults(model_data *d);

/* Structure of the model's part of a state whose header, checksum and state
 * machine value were checked: NULL if sound, else why not. */
const char *model_state_flaw(const model_data *d);

/* At the end of initialisation: plan (if the parameters changed since) and
 * start counting the inputs' edges from here. */
model_status model_start(struct model_instance *m);

/* ------------------------------------------------------------------------ */
/* called by the FMI layers (fmi2.c, fmi3.c)                                */

/* The start time: the origin of the generator's sample grid. */
model_status model_setup(struct model_instance *m, double start_time);

/* The per-step reads of a master, in one call: when the instance is planned, its state is
 * in mask and every reference is a Real output of the profile (x, v, a, j, x_AL, v_AL,
 * a_AL), write the n values and return 1; otherwise return 0 (nothing logged: the caller
 * takes the general path, which gives the same values or the error). */
int model_get_reals_fast(const struct model_instance *m, int mask, const unsigned int *vr,
                         size_t n, double *value);

/* Variable access.  vr is an element value reference (FMI 2 style: arrays at
 * base + i); type is 'R', 'I' or 'B'. */
model_status model_set(struct model_instance *m, unsigned int vr, char type, double value);
model_status model_get(struct model_instance *m, unsigned int vr, char type, double *value);

model_status model_do_step(struct model_instance *m, double t, double h);

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility pop
#endif

#endif /* FMU_MODEL_H */
