/*
 * fmu_base.h -- the base of the FMU, below the model and the instance, both of
 * which include it (fmu_base.c): the data of an instance and the services the
 * model and the instance share.  Independent of the FMI version.
 *
 * - the values: model_status (fmi2Status / fmi3Status numbering) and the
 *   states of the state machine (model_state) with their names;
 * - the data: model_data (everything an FMU state holds: a copy of it is the
 *   state; its header is the instance's, the rest the model's), model_work
 *   (the model's work space) and model_instance (the data, the environment,
 *   the work space);
 * - logging and error reporting: model_log, model_fail (to state Error),
 *   model_refuse (the instance unchanged), model_null_arg, and the
 *   debug-logging categories (model_set_debug_logging);
 * - the variable table (djl_vars.h's): model_lookup, model_type_name.
 *
 * The layers above: the model (fmu_model.h: its variables, planning, DoStep),
 * over it the instance (fmu_instance.h: life cycle, state machine, FMU state),
 * over both the FMI layers (fmi2.c, fmi3.c).  Under all of them the generator
 * core (djl_core.h).
 */
#ifndef FMU_BASE_H
#define FMU_BASE_H

#include <stddef.h>
#include <stdint.h>

#include "djl_core.h"
#include "djl_vars.h"

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility push(hidden)
#endif

/* Same numbering as fmi2Status and fmi3Status. */
typedef enum { ST_OK = 0, ST_WARNING = 1, ST_DISCARD = 2, ST_ERROR = 3, ST_FATAL = 4 } model_status;

/* States of the (co-simulation) state machine, as bit flags for masks. */
typedef enum {
    MS_START_END = 1 << 0,
    MS_INSTANTIATED = 1 << 1,
    MS_INIT = 1 << 2,
    MS_STEP = 1 << 3,      /* FMI 2 stepComplete, FMI 3 Step Mode */
    MS_TERMINATED = 1 << 4,
    MS_ERROR = 1 << 5      /* after an error: only get (diagnostics), reset and free */
} model_state;

/* Name of a state of the state machine (for messages). */
const char *model_state_name(int state);

/* ------------------------------------------------------------------------ */
/* the data of an instance                                                  */

#define MODEL_MAGIC 0x4a4c4446u /* "FDLJ" */
#define MODEL_LAYOUT 11u         /* of model_data: a state of another layout is refused (8: the
                                    replayed table, djl_table, and 264 plan steps; 9: the
                                    per-command values and command errors, issue 34; 10: the
                                    queue of buffered and blending commands, min_duration; 11:
                                    the checksum with rotated lanes, issue 39) */
/* Commands a buffered or blending execute can wait behind (spec.QUEUE_CAPACITY). */
#define MODEL_QUEUE_CAPACITY 16

/* The figures of the parametric move planned at initialisation (the calculated
 * parameters motion_time, N_F1..N_F4, v_reached, a_reached, d_reached): commands
 * replace the plan, not them. */
typedef struct {
    int64_t k_end;
    int32_t N[4];
    double v_reached, a_reached, d_reached;
    double t_shaper;        /* s, the largest delay of the shaper of the parametric move */
} plan_summary;

/* The per-command inputs (issue 34, docs/generator.md "Per-command values"): as set, any
 * value (checked at a command's edge). */
typedef struct {
    double v_max, a_max, d_max; /* cmd_v_max, cmd_a_max, cmd_d_max; 0: the default */
    double T_F[4];              /* cmd_T_F[1..4]; 0: the default */
    int32_t profile;            /* cmd_profile (0: the default) */
    int32_t shaper;             /* cmd_shaper (0: the parameter's design, 5: none) */
    int32_t shaper_n;           /* cmd_shaper_n (0: the parameters' custom design) */
    int32_t pad;
    double amplitude[DJL_MAX_SHAPER_IMPULSES]; /* cmd_shaper_amplitude */
    double delay[DJL_MAX_SHAPER_IMPULSES];     /* cmd_shaper_delay, s */
} model_cmd_inputs;

/* A command waiting in the queue (buffer_mode 1 or 2): its inputs as latched at its edge
 * (checked there: valid), resolved when it starts. */
typedef struct {
    model_cmd_inputs cmd;       /* the cmd_* inputs at its edge */
    double target;              /* m */
    double min_duration;        /* s, 0: none */
    int32_t buffer_mode;        /* BUFFER_MODE_BUFFERED or BUFFER_MODE_BLENDING */
    int32_t pad;
    int64_t id;                 /* its number among the execute edges accepted (1, 2, ...) */
} model_queued;

/* The values of the move in progress, latched at its command (the parametric move: the
 * parameters'): what a replan of it (jerk times from f_mode) and a stop without values of
 * its own use. */
typedef struct {
    double v_max, a_max, d_max;
    int32_t N[4];               /* jerk times of its stages, samples (all 0: AL) */
    int32_t profile;            /* DJL_PROFILE_AL, _JL or _DJL (a table's commands: DJL) */
    int32_t pad;
    djl_shaper_params sp;       /* the design of its shaper (d->shaper is it, designed) */
} model_move;

/* All the data of an instance that an FMU state must capture: plain values, no
 * pointers, so an FMU state is a copy of it (packed: the shaper's rings hold only their
 * live entries, fmu_instance.c) and serialising it is a memcpy.  Its first fields are the FMU state's header, which the instance (fmu_instance.c)
 * fills and checks; the rest is the model's (fmu_model.c). */
typedef struct {
    /* the FMU state's header (fmu_instance.c) */
    uint32_t magic;
    uint32_t layout;
    uint32_t size;          /* a saved state's size in bytes (packed: fmu_instance.c) */
    int32_t state;          /* model_state */
    uint64_t checksum;      /* FNV-1a 64 of a saved state's other bytes */
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
    djl_table table;        /* parameters table_n, table_samples, table_jerk (profile = 4) */
    djl_shaper shaper;      /* designed with the plan (n = 0: no shaping) */
    int32_t shaper_cursor[DJL_MAX_SHAPER_IMPULSES]; /* piece hints of the delayed copies */
    /* per-command values and command errors (issue 34) */
    model_cmd_inputs cmd;   /* the inputs cmd_* */
    model_move mv;          /* the values of the move in progress */
    double env_v_max, env_a_max, env_d_max; /* the largest limits of every move since the
                               start (the plan's own p limits: its pieces may hold parts of
                               earlier moves) */
    /* buffer modes and synchronisation (issue 34 items 2 and 4) */
    int32_t buffer_mode;    /* input (any value: checked at an execute edge) */
    int32_t command_aborted; /* output, 0 or 1 */
    double min_duration;    /* s, input (any value: checked at an execute edge) */
    int64_t n_commands;     /* execute edges accepted since the start (their ids) */
    int64_t running_id;     /* id of the command whose move is in progress (0: the
                               parametric move, or a stop) */
    int32_t queue_n, queue_first; /* waiting: queue[(queue_first + i) % CAPACITY], i < n */
    model_queued queue[MODEL_QUEUE_CAPACITY];
    int32_t cmd_error;      /* output cmd_error, 0 or 1 */
    int32_t cmd_error_id;   /* output cmd_error_id (spec.CMD_ERRORS), 0 without error */
    djl_shaper_memory mem;  /* what the delayed copies read of the plans replans replaced; the
                               phase of f_mode (shaper_source = 2); the last field (a state
                               packs the live entries of its rings only) */
} model_data;

/* The model's work space in an instance: not part of an FMU state. */
typedef struct {
    /* the last whole-sample step size seen by DoStep and its count of samples (a cache:
     * derived from h and Te alone) */
    double step_h, step_Te, step_whole;
    /* work space of a replan (its new motion) */
    djl_plan scratch;
    /* a trial plan: a replan planned aside (min_duration's search, a blend's speed) */
    djl_plan trial;
} model_work;

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
    /* a state being checked, unpacked (model_state_check, model_state_load): allocated at
     * the first check with the importer's memory functions, freed by model_free */
    model_data *load;
    void *(*alloc)(size_t n, size_t size); /* calloc-like (FMI 2's allocateMemory) */
    void (*release)(void *p);
} model_instance;

/* ------------------------------------------------------------------------ */
/* logging and error reporting                                              */

/* Log through the importer's callback: errors always, warnings and events
 * only when their category is on. */
void model_log(const model_instance *m, model_status status, int category, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* An error: logged, and the instance moves to MS_ERROR. */
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

/* ------------------------------------------------------------------------ */
/* the variable table                                                       */

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

#if defined(__GNUC__) && __GNUC__ >= 4
#pragma GCC visibility pop
#endif

#endif /* FMU_BASE_H */
