/*
 * fuzz_fmi.c -- FMI 2 and FMI 3 call sequences decoded from bytes (issue 21).
 *
 * The first byte picks the layer; then each operation is a byte and its arguments:
 * instantiate (again), set any variable (any value reference, also unknown ones and the
 * wrong type) to any value, enter / exit initialisation, steps of any size from any
 * point, getters, FMU state get / set / free / serialise / deserialise (a copy, or a
 * forged one: a word changed and the checksum recomputed), reset, terminate, commands
 * (target + execute edge, stop edge, f_mode; issue 34's per-command values: any input
 * cmd_* set to any value, a move with its own limits, jerk times or profile, a custom
 * shaper of a move, every cmd_* back to 0), debug logging; and a whole table for
 * profile 4 (bang-bang pieces that come back to rest, with the distance and limits they
 * need, or a little off them: load_table).
 *
 * Invariants checked after every call (a broken one aborts):
 *  - every getter of an output, a calculated parameter or the time that answers OK gives
 *    finite values (a parameter reads back what was set: it is validated at
 *    initialisation);
 *  - in Step Mode after an OK step: |v| <= v_max, a within the larger of a_max and d_max,
 *    times the sum of the shaper's |amplitudes| (a custom shaper may overshoot), up to
 *    rounding, the limits and the amplitudes being the largest of the parameters' and of
 *    every command the FMU accepted (cmd_error false after its edge); done == !busy;
 *    cmd_error_id is a code (0..CMD_ERR_QUEUE_FULL), 0 exactly when cmd_error is false;
 *    queue_length in 0..MODEL_QUEUE_CAPACITY, time_to_rest finite and >= 0, both 0 once
 *    done;
 *  - a move the harness can follow (from initialisation, commands decoded as the FMU
 *    sees them, no state restored) that reports done rests on its goal: the parametric
 *    end (x0 + distances) when it ends at rest, a commanded target, at rest after a stop
 *    (a command refused with cmd_error leaves the goal as it was; a buffered or blending
 *    command accepted makes its target the goal: the queue ends there; one refused when
 *    its turn comes ends the following);
 *  - a state the FMU saved itself is accepted back (set, serialise, deserialise) and
 *    restores the outputs it was saved with.
 * Built with clang -fsanitize=fuzzer,address,undefined (tests/fuzz/build.sh) or, without
 * a fuzzer, with gcc and tests/fuzz/replay.c (the suite replays the corpus).
 */
#define DJL_VARS_TABLES
#include "djl_vars.h"
#include "fmi2Functions.h"
#include "fmi3Functions.h"
#include "fmu_instance.h"
#include "fuzz_common.h"

#include <stdarg.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Variables of the table before issue 33 added table_n, table_samples, table_jerk, and
 * issue 34 the eleven per-command inputs and outputs after them, then the six of its buffer
 * modes and synchronisation (buffer_mode, min_duration, active, command_aborted,
 * queue_length, time_to_rest). */
#define FUZZ_OLD_VARS 50
#define FUZZ_TABLE_VARS 3
typedef char fuzz_old_vars_check[(DJL_N_VARS == FUZZ_OLD_VARS + FUZZ_TABLE_VARS + 11 + 6 &&
                                   VR_TABLE_N == 65 && VR_TABLE_JERK == 2000 &&
                                   VR_CMD_V_MAX == 70 && VR_CMD_ERROR_ID == 77 &&
                                   VR_BUFFER_MODE == 78 && VR_TIME_TO_REST == 83) ? 1 : -1];

/* ------------------------------------------------------------------ the two layers */

typedef struct {
    int v3;
    fmi2Component c2;
    fmi3Instance c3;
    void *state[2];
} fmu;

static char last_msg[512]; /* the FMU's last log message, for a broken invariant's report */

/* With FUZZ_VERBOSE set, each call the harness makes (with its arguments) and each message
 * the FMU logs go to stderr: the sequence an input decodes to, to read a finding (with the
 * gcc replay build, as tests/test_fuzz_corpus.py builds it). */
static int verbose = -1;

static void trace(const char *fmt, ...)
{
    va_list ap;
    if (verbose < 0) verbose = getenv("FUZZ_VERBOSE") != NULL;
    if (!verbose) return;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

static void log2_cb(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c,
                    fmi2String m, ...)
{
    (void)e;
    (void)n;
    (void)s;
    (void)c;
    FUZZ_CHECK(m != NULL && strlen(m) < 4096, "log message");
    strncpy(last_msg, m, sizeof last_msg - 1);
    trace("  log: %s", m);
}

static void log3_cb(fmi3InstanceEnvironment e, fmi3Status s, fmi3String c, fmi3String m)
{
    (void)e;
    (void)s;
    (void)c;
    FUZZ_CHECK(m != NULL && strlen(m) < 4096, "log message");
    strncpy(last_msg, m, sizeof last_msg - 1);
    trace("  log: %s", m);
}

/* FUZZ_POOL (tests/fuzz/build.sh, the libFuzzer build): the FMU's blocks of 128 kB and
 * more (an instance, 322 kB; its check area of states, 293 kB) come from a pool of the
 * harness, for FMI 2 through allocateMemory / freeMemory and for FMI 3 by building
 * fmi3.c with calloc and free renamed to fuzz_calloc and fuzz_free.  ASan maps every such
 * block afresh and unmaps it when it leaves its quarantine: that kernel work was half of
 * the harness's time (docs/fuzzing.md, "The campaign": where the FMI harness's time
 * went).  A pooled block stays poisoned until it is handed out again (an access to it is
 * reported as a use after poison) and is handed out oldest first, zeroed (calloc's
 * promise); only a stale pointer into a block already handed out again goes unseen,
 * which the gcc replay of the corpus in the suite (plain ASan, full quarantine) still
 * catches.  Smaller blocks (FMU states) go straight to ASan. */
#ifdef FUZZ_POOL
#include <sanitizer/allocator_interface.h>
#include <sanitizer/asan_interface.h>

#define POOL_MIN ((size_t)1 << 17)
#define POOL_SLOTS 8

static struct {
    void *p;
    size_t size;
    unsigned long long age; /* when it was freed: the oldest is handed out first */
} pool[POOL_SLOTS];
static unsigned long long pool_clock;

void *fuzz_calloc(size_t n, size_t size);
void fuzz_free(void *p);

void *fuzz_calloc(size_t n, size_t size)
{
    int i, best = -1;
    void *p;
    if (size != 0 && n > SIZE_MAX / size) return NULL;
    if (n * size < POOL_MIN) return calloc(n, size);
    for (i = 0; i < POOL_SLOTS; i++)
        if (pool[i].p && pool[i].size == n * size && (best < 0 || pool[i].age < pool[best].age))
            best = i;
    if (best < 0) return calloc(n, size);
    p = pool[best].p;
    pool[best].p = NULL;
    ASAN_UNPOISON_MEMORY_REGION(p, n * size);
    return memset(p, 0, n * size);
}

void fuzz_free(void *p)
{
    size_t size;
    int i, slot = -1;
    if (!p) return;
    size = __sanitizer_get_allocated_size(p);
    if (size < POOL_MIN) {
        free(p);
        return;
    }
    for (i = 0; i < POOL_SLOTS; i++) { /* a free slot, or else the oldest block's */
        if (!pool[i].p) {
            slot = i;
            break;
        }
        if (slot < 0 || pool[i].age < pool[slot].age) slot = i;
    }
    if (pool[slot].p) {
        ASAN_UNPOISON_MEMORY_REGION(pool[slot].p, pool[slot].size);
        free(pool[slot].p);
    }
    ASAN_POISON_MEMORY_REGION(p, size);
    pool[slot].p = p;
    pool[slot].size = size;
    pool[slot].age = ++pool_clock;
}

static const fmi2CallbackFunctions cb2 = {log2_cb, fuzz_calloc, fuzz_free, NULL, NULL};
#else
static const fmi2CallbackFunctions cb2 = {log2_cb, calloc, free, NULL, NULL};
#endif

static int instantiate(fmu *f, int logging)
{
    trace("instantiate (FMI %d, logging %d)", f->v3 ? 3 : 2, logging);
    if (f->v3) {
        f->c3 = fmi3InstantiateCoSimulation("fuzz", DJL_INSTANTIATION_TOKEN, "/tmp", fmi3False,
                                            logging ? fmi3True : fmi3False, fmi3False, fmi3False,
                                            NULL, 0, NULL, log3_cb, NULL);
        return f->c3 != NULL;
    }
    f->c2 = fmi2Instantiate("fuzz", fmi2CoSimulation, DJL_INSTANTIATION_TOKEN, "file:///tmp",
                            &cb2, fmi2False, logging ? fmi2True : fmi2False);
    return f->c2 != NULL;
}

static void free_states(fmu *f)
{
    int i;
    for (i = 0; i < 2; i++) {
        if (f->v3) fmi3FreeFMUState(f->c3, (fmi3FMUState *)&f->state[i]);
        else fmi2FreeFMUstate(f->c2, (fmi2FMUstate *)&f->state[i]);
        f->state[i] = NULL;
    }
}

static void free_instance(fmu *f)
{
    trace("free instance");
    free_states(f);
    if (f->v3) fmi3FreeInstance(f->c3);
    else fmi2FreeInstance(f->c2);
    f->c2 = NULL;
    f->c3 = NULL;
}

/* statuses: 0 OK, 1 warning, 2 discard, 3 error, 4 fatal (the same in both standards) */
static int get_real(fmu *f, unsigned vr, double *v)
{
    if (f->v3) return (int)fmi3GetFloat64(f->c3, &vr, 1, v, 1);
    return (int)fmi2GetReal(f->c2, &vr, 1, v);
}

static int set_real(fmu *f, unsigned vr, double v)
{
    trace("set real %u = %.17g", vr, v);
    if (f->v3) return (int)fmi3SetFloat64(f->c3, &vr, 1, &v, 1);
    return (int)fmi2SetReal(f->c2, &vr, 1, &v);
}

/* An Enumeration variable (FMI 3 reads it as Int64, the other integers as Int32). */
static int is_enumeration(unsigned vr)
{
    int i;
    for (i = 0; i < DJL_N_VARS; i++)
        if (djl_var_table[i].vr == vr) return djl_var_table[i].type == 'E';
    return 0;
}

static int get_int(fmu *f, unsigned vr, long long *v)
{
    int st;
    if (f->v3) {
        /* by the variable's type: an Int64 read of an Int32 variable is an error that puts
         * the instance in the Error state (before issue 33 the harness tried Int64 first,
         * and every FMI 3 run ended in Error at its first exit_init: parametric_end reads
         * n_segments) */
        if (is_enumeration(vr)) {
            fmi3Int64 x = 0;
            st = (int)fmi3GetInt64(f->c3, &vr, 1, &x, 1);
            *v = x;
        } else {
            fmi3Int32 y = 0;
            st = (int)fmi3GetInt32(f->c3, &vr, 1, &y, 1);
            *v = y;
        }
        return st;
    } else {
        fmi2Integer x = 0;
        st = (int)fmi2GetInteger(f->c2, &vr, 1, &x);
        *v = x;
        return st;
    }
}

static int set_int(fmu *f, unsigned vr, long long v, int as64)
{
    trace("set integer %u = %lld", vr, v);
    if (f->v3) {
        if (as64) {
            fmi3Int64 x = v;
            return (int)fmi3SetInt64(f->c3, &vr, 1, &x, 1);
        } else {
            fmi3Int32 x = (fmi3Int32)v;
            return (int)fmi3SetInt32(f->c3, &vr, 1, &x, 1);
        }
    } else {
        fmi2Integer x = (fmi2Integer)v;
        return (int)fmi2SetInteger(f->c2, &vr, 1, &x);
    }
}

static int get_bool(fmu *f, unsigned vr, int *v)
{
    int st;
    if (f->v3) {
        fmi3Boolean b = fmi3False;
        st = (int)fmi3GetBoolean(f->c3, &vr, 1, &b, 1);
        *v = b ? 1 : 0;
    } else {
        fmi2Boolean b = fmi2False;
        st = (int)fmi2GetBoolean(f->c2, &vr, 1, &b);
        *v = b ? 1 : 0;
    }
    return st;
}

static int set_bool(fmu *f, unsigned vr, int v)
{
    trace("set boolean %u = %d", vr, v);
    if (f->v3) {
        fmi3Boolean b = v ? fmi3True : fmi3False;
        return (int)fmi3SetBoolean(f->c3, &vr, 1, &b, 1);
    } else {
        fmi2Boolean b = v ? fmi2True : fmi2False;
        return (int)fmi2SetBoolean(f->c2, &vr, 1, &b);
    }
}

static int enter_init(fmu *f, double t0)
{
    trace("enter initialisation (start time %.17g)", t0);
    if (f->v3) return (int)fmi3EnterInitializationMode(f->c3, fmi3False, 0.0, t0, fmi3False, 0.0);
    if (fmi2SetupExperiment(f->c2, fmi2False, 0.0, t0, fmi2False, 0.0) != fmi2OK) return 3;
    return (int)fmi2EnterInitializationMode(f->c2);
}

static int exit_init(fmu *f)
{
    trace("exit initialisation");
    if (f->v3) return (int)fmi3ExitInitializationMode(f->c3);
    return (int)fmi2ExitInitializationMode(f->c2);
}

static int do_step(fmu *f, double t, double h)
{
    trace("step from %.17g by %.17g", t, h);
    if (f->v3) {
        fmi3Boolean eh = fmi3True, term = fmi3True, early = fmi3True;
        fmi3Float64 last = NAN;
        int st = (int)fmi3DoStep(f->c3, t, h, fmi3True, &eh, &term, &early, &last);
        if (st <= 1) FUZZ_CHECK(isfinite(last), "fmi3DoStep: lastSuccessfulTime %g", last);
        return st;
    }
    return (int)fmi2DoStep(f->c2, t, h, fmi2True);
}

static int reset(fmu *f)
{
    trace("reset");
    if (f->v3) return (int)fmi3Reset(f->c3);
    return (int)fmi2Reset(f->c2);
}

static int terminate(fmu *f)
{
    trace("terminate");
    if (f->v3) return (int)fmi3Terminate(f->c3);
    return (int)fmi2Terminate(f->c2);
}

static int get_state(fmu *f, int slot)
{
    trace("get state into slot %d", slot);
    if (f->v3) return (int)fmi3GetFMUState(f->c3, (fmi3FMUState *)&f->state[slot]);
    return (int)fmi2GetFMUstate(f->c2, (fmi2FMUstate *)&f->state[slot]);
}

static int set_state(fmu *f, int slot)
{
    trace("set state of slot %d", slot);
    if (f->v3) return (int)fmi3SetFMUState(f->c3, (fmi3FMUState)f->state[slot]);
    return (int)fmi2SetFMUstate(f->c2, (fmi2FMUstate)f->state[slot]);
}

/* The state of a slot into buf (n bytes); its size in *size. */
static int serialize(fmu *f, int slot, unsigned char *buf, size_t n, size_t *size)
{
    int st;
    trace("serialise slot %d", slot);
    *size = 0;
    if (f->v3) st = (int)fmi3SerializedFMUStateSize(f->c3, (fmi3FMUState)f->state[slot], size);
    else st = (int)fmi2SerializedFMUstateSize(f->c2, (fmi2FMUstate)f->state[slot], size);
    if (st != 0) return st;
    FUZZ_CHECK(*size > 0 && *size <= model_state_max_size(), "serialized size %lu",
               (unsigned long)*size);
    if (f->v3) st = (int)fmi3SerializeFMUState(f->c3, (fmi3FMUState)f->state[slot], buf, n);
    else st = (int)fmi2SerializeFMUstate(f->c2, (fmi2FMUstate)f->state[slot], (fmi2Byte *)buf, n);
    if (st == 0) FUZZ_CHECK(model_state_stored_size(buf) == *size, "a state's header size");
    return st;
}

static int deserialize(fmu *f, int slot, const unsigned char *buf, size_t n)
{
    trace("deserialise %lu bytes into slot %d", (unsigned long)n, slot);
    if (f->v3)
        return (int)fmi3DeserializeFMUState(f->c3, buf, n, (fmi3FMUState *)&f->state[slot]);
    return (int)fmi2DeSerializeFMUstate(f->c2, (const fmi2Byte *)buf, n, (fmi2FMUstate *)&f->state[slot]);
}

static int debug_logging(fmu *f, int on)
{
    static const char *cats[2] = {"logEvents", "logStatusError"};
    trace("debug logging %d", on);
    if (f->v3) return (int)fmi3SetDebugLogging(f->c3, on ? fmi3True : fmi3False, 2, cats);
    return (int)fmi2SetDebugLogging(f->c2, on ? fmi2True : fmi2False, 2, cats);
}

/* ---------------------------------------------------------------- the harness */

typedef struct {
    double x, v, a, j, x_al, v_al, a_al, time;
    int done, busy;
} outputs;

enum { GOAL_NONE, GOAL_PARAM, GOAL_TARGET, GOAL_STOP };

typedef struct {
    int tracked;    /* the move is one the harness follows */
    int goal;       /* GOAL_* */
    double expect;  /* where a GOAL_PARAM / GOAL_TARGET move rests */
    double scale;   /* positions seen: the tolerance of the landing */
    int exec_seen, stop_seen; /* the Boolean inputs at the last step, as the FMU saw them */
    int err_seen;   /* cmd_error after the last step */
    double t;       /* the FMU's time */
    int stepping;   /* Step Mode, the last step OK */
    double cmd_v, cmd_a, cmd_fac; /* the largest cmd_v_max, of cmd_a_max and cmd_d_max, and
                       sum of a custom cmd shaper's |amplitudes| a command was accepted with */
} follow;

static unsigned char state_buf[sizeof(model_data)]; /* more than the largest state */

static void read_outputs(fmu *f, outputs *o)
{
    static const unsigned vrs[8] = {VR_X, VR_V, VR_A, VR_J, VR_X_AL, VR_V_AL, VR_A_AL, VR_TIME};
    double *dst[8];
    int i, st;
    dst[0] = &o->x; dst[1] = &o->v; dst[2] = &o->a; dst[3] = &o->j;
    dst[4] = &o->x_al; dst[5] = &o->v_al; dst[6] = &o->a_al; dst[7] = &o->time;
    for (i = 0; i < 8; i++) {
        *dst[i] = NAN;
        st = get_real(f, vrs[i], dst[i]);
        if (st == 0) FUZZ_CHECK(isfinite(*dst[i]), "output %u = %g after OK", vrs[i], *dst[i]);
    }
    o->done = o->busy = -1;
    (void)get_bool(f, VR_DONE, &o->done);
    (void)get_bool(f, VR_BUSY, &o->busy);
}

static double par(fmu *f, unsigned vr)
{
    double v = NAN;
    (void)get_real(f, vr, &v);
    return v;
}

/* Where the parametric move rests (NAN: it ends cruising) and the scale of its positions. */
static double parametric_end(fmu *f, double *scale)
{
    long long n = 0;
    double x0 = par(f, VR_X0), end = x0, ve;
    int i;
    (void)get_int(f, VR_N_SEGMENTS, &n);
    *scale = fabs(x0);
    if (n <= 0) {
        end += par(f, VR_DISTANCE);
        *scale += fabs(par(f, VR_DISTANCE));
        ve = par(f, VR_V_E);
    } else {
        for (i = 0; i < n && i < DJL_VARS_MAX_SEGMENTS; i++) {
            double d = par(f, VR_SEG_DISTANCE + (unsigned)i);
            end += d;
            *scale += fabs(d);
        }
        ve = par(f, VR_SEG_V_END + (unsigned)(n - 1));
    }
    return ve == 0.0 ? end : NAN;
}

/* A command accepted (its edge stepped over, cmd_error false): its limits and a custom
 * shaper's amplitudes widen the bounds check_step holds the outputs to. */
static void command_accepted(fmu *f, follow *w, int execute)
{
    long long shaper = 0, n = 0;
    double fac = 0.0, x;
    int i;
    x = par(f, VR_CMD_V_MAX);
    if (x > w->cmd_v) w->cmd_v = x;
    x = par(f, VR_CMD_A_MAX);
    if (x > w->cmd_a) w->cmd_a = x;
    x = par(f, VR_CMD_D_MAX);
    if (x > w->cmd_a) w->cmd_a = x;
    if (!execute) return;
    (void)get_int(f, VR_CMD_SHAPER, &shaper);
    if (shaper != CMD_SHAPER_CUSTOM) return;
    (void)get_int(f, VR_CMD_SHAPER_N, &n);
    if (n > 0) {
        for (i = 0; i < n && i < 8; i++) fac += fabs(par(f, VR_CMD_SHAPER_AMPLITUDE + (unsigned)i));
    } else {
        (void)get_int(f, VR_SHAPER_N, &n);
        for (i = 0; i < n && i < 8; i++) fac += fabs(par(f, VR_SHAPER_AMPLITUDE + (unsigned)i));
    }
    if (fac > w->cmd_fac) w->cmd_fac = fac;
}

static void check_step(fmu *f, follow *w)
{
    outputs o;
    double vmax = par(f, VR_V_MAX), amax = par(f, VR_A_MAX), dmax = par(f, VR_D_MAX), fac = 1.0;
    double lim;
    long long shaper = 0, n = 0, id = -1;
    int i, err = -1;
    read_outputs(f, &o);
    trace("  -> x %.17g, v %.17g, a %.17g, done %d", o.x, o.v, o.a, o.done);
    if (!w->stepping) return;
    FUZZ_CHECK(o.done == !o.busy, "done %d busy %d", o.done, o.busy);
    if (get_bool(f, VR_CMD_ERROR, &err) == 0 && get_int(f, VR_CMD_ERROR_ID, &id) == 0)
        FUZZ_CHECK(id >= 0 && id <= CMD_ERR_QUEUE_FULL && (id != 0) == (err != 0),
                   "cmd_error %d, cmd_error_id %lld", err, id);
    {
        long long ql = -1;
        double ttr = NAN;
        int act = -1, ab = -1;
        if (get_int(f, VR_QUEUE_LENGTH, &ql) == 0)
            FUZZ_CHECK(ql >= 0 && ql <= MODEL_QUEUE_CAPACITY && (!o.done || ql == 0),
                       "queue_length %lld (done %d)", ql, o.done);
        if (get_real(f, VR_TIME_TO_REST, &ttr) == 0)
            FUZZ_CHECK(isfinite(ttr) && ttr >= 0.0 && (!o.done || ttr == 0.0),
                       "time_to_rest %g (done %d)", ttr, o.done);
        if (get_bool(f, VR_ACTIVE, &act) == 0 && get_bool(f, VR_COMMAND_ABORTED, &ab) == 0)
            FUZZ_CHECK((act == 0 || act == 1) && (ab == 0 || ab == 1) && !(act && o.done),
                       "active %d, command_aborted %d (done %d)", act, ab, o.done);
    }
    (void)get_int(f, VR_SHAPER, &shaper);
    if (shaper == SHAPER_CUSTOM) {
        (void)get_int(f, VR_SHAPER_N, &n);
        fac = 0.0;
        for (i = 0; i < n && i < 8; i++) fac += fabs(par(f, VR_SHAPER_AMPLITUDE + (unsigned)i));
    }
    /* the largest of the parameters' and of the commands accepted */
    if (w->cmd_fac > fac) fac = w->cmd_fac;
    if (w->cmd_v > vmax) vmax = w->cmd_v;
    if (w->cmd_a > amax) amax = w->cmd_a;
    lim = vmax * fac * (1.0 + 1e-9);
    FUZZ_CHECK(fabs(o.v) <= lim, "|v| = %.17g above v_max %.17g (x %g)", o.v, vmax, fac);
    lim = (amax > dmax ? amax : dmax) * fac * (1.0 + 1e-9);
    FUZZ_CHECK(fabs(o.a) <= lim, "|a| = %.17g above the limits %.17g, %.17g", o.a, amax, dmax);
    if (fabs(o.x) > w->scale) w->scale = fabs(o.x);
    if (!w->tracked || !o.done) return;
    if (w->goal == GOAL_PARAM && !(w->expect == w->expect)) return; /* ends cruising */
    FUZZ_CHECK(o.v == 0.0 && o.a == 0.0, "done, not at rest: v %.17g a %.17g", o.v, o.a);
    if (w->goal == GOAL_STOP) return;
    FUZZ_CHECK(fabs(o.x - w->expect) <= 1e-9 * (fabs(w->expect) + w->scale) + 1e-300,
               "done at x = %.17g, the goal is %.17g (positions up to %g)", o.x, w->expect,
               w->scale);
}

/* A table for profile 4 (docs/generator.md, "Replayed tables"): P, bumps of +-J over n
 * samples, a pause, and -+J over n (or, notched, over other lengths: the acceleration then
 * does not come back to 0), then -P; the distance and the limits it needs, from the
 * harness's own integration, or a little off them (refused by name); all 256 entries set,
 * as arrays (FMI 3) or their elements (FMI 2).  The pieces' lengths and J from the bytes;
 * Te the one the harness set (FMI 2 has no getters before initialisation). */
static void load_table(fmu *f, fuzz_reader *r, double Te)
{
    static int32_t n[256];
    static double jerk[256];
    static fmi2ValueReference vr2[256];
    uint8_t mode = rd_u8(r);
    int bumps = 1 + rd_u8(r) % (mode & 1 ? 42 : 6), m = 0, i, st;
    double J = rd_double(r), x = 0.0, v = 0.0, a = 0.0, V = 0.0, up = 0.0,
           down = 0.0, off[4] = {1.0, 1.0 + 1e-6, 0.999, 10.0};
    for (i = 0; i < 256; i++) {
        n[i] = 1;
        jerk[i] = 0.0;
    }
    for (i = 0; i < bumps && m + 3 <= 128; i++) {
        double sg = rd_u8(r) & 1 ? -1.0 : 1.0;
        n[m] = 1 + rd_u8(r);
        jerk[m++] = sg * J;
        n[m] = 1 + rd_u8(r);
        jerk[m++] = 0.0;
        n[m] = mode & 2 ? 1 + rd_u8(r) : n[m - 2];
        jerk[m++] = -sg * J;
    }
    for (i = 0; i < m; i++) { /* -P */
        n[m + i] = n[i];
        jerk[m + i] = -jerk[i];
    }
    m *= 2;
    if (mode & 4) n[rd_u8(r) % m] = (int32_t)(int8_t)rd_u8(r); /* an entry out of range */
    for (i = 0; i < m; i++) {
        double L = (double)n[i] * (isfinite(Te) ? Te : 1e-3), j = jerk[i];
        double ts = j != 0.0 ? -a / j : -1.0;
        if (ts > 0.0 && ts < L) V = fmax(V, fabs(v + ts * (a + 0.5 * ts * j)));
        x += L * (v + L * (0.5 * a + L * j / 6.0));
        v += L * (a + 0.5 * L * j);
        a += j * L;
        V = fmax(V, fabs(v));
        up = fmax(up, a);
        down = fmax(down, -a);
    }
    trace("load a table of %d pieces, J = %.17g: ends at x %.17g v %.17g a %.17g", m, J, x, v,
          a);
    (void)set_int(f, VR_PROFILE, PROFILE_TABLE, 0);
    (void)set_int(f, VR_TABLE_N, m, 0);
    if (f->v3) {
        fmi3ValueReference vs = VR_TABLE_SAMPLES, vj = VR_TABLE_JERK;
        st = (int)fmi3SetInt32(f->c3, &vs, 1, n, 256);
        FUZZ_CHECK(st == 0 || st == 3, "fmi3SetInt32 of table_samples: %d", st);
        (void)fmi3SetFloat64(f->c3, &vj, 1, jerk, 256);
    } else {
        for (i = 0; i < 256; i++) vr2[i] = VR_TABLE_SAMPLES + (fmi2ValueReference)i;
        (void)fmi2SetInteger(f->c2, vr2, 256, n);
        for (i = 0; i < 256; i++) vr2[i] = VR_TABLE_JERK + (fmi2ValueReference)i;
        (void)fmi2SetReal(f->c2, vr2, 256, jerk);
    }
    if (mode & 8) {
        x *= off[rd_u8(r) % 4];
        (void)set_real(f, VR_X0, rd_double(r));
    }
    (void)set_real(f, VR_DISTANCE, x);
    if (mode & 16) {
        double k = off[rd_u8(r) % 4];
        (void)set_real(f, VR_V_MAX, V > 0.0 ? V * k : 1.0);
        (void)set_real(f, VR_A_MAX, (x < 0.0 ? down : up) > 0.0 ? (x < 0.0 ? down : up) * k : 1.0);
        (void)set_real(f, VR_D_MAX, (x < 0.0 ? up : down) > 0.0 ? (x < 0.0 ? up : down) * k : 1.0);
    }
}

/* Interesting step sizes: multiples and fractions of Te, and anything. */
static double step_size(fuzz_reader *r, double Te)
{
    uint8_t k = rd_u8(r);
    if (!isfinite(Te) || Te <= 0.0) Te = 1e-3;
    switch (k % 6) {
    case 0: return Te;
    case 1: return Te * (double)(1 + rd_u8(r));
    case 2: return Te * (double)(1 + rd_u32(r) % 100000);
    case 3: return Te / (double)(2 + rd_u8(r) % 8);
    case 4: return Te * (rd_u8(r) / 16.0);
    default: return rd_double(r);
    }
}

/* Save, then at once restore: the FMU's own state is accepted and gives the same outputs. */
static void own_state(fmu *f, int slot, int stepping)
{
    outputs a, b;
    size_t size;
    int st;
    read_outputs(f, &a);
    st = get_state(f, slot);
    if (st != 0) return;
    st = set_state(f, slot);
    FUZZ_CHECK(st == 0, "the FMU refused a state it saved itself (set): %s", last_msg);
    st = serialize(f, slot, state_buf, sizeof state_buf, &size);
    FUZZ_CHECK(st == 0, "the FMU refused to serialise a state it saved itself: %s", last_msg);
    st = deserialize(f, 1 - slot, state_buf, size);
    FUZZ_CHECK(st == 0, "the FMU refused its own serialised state: %s", last_msg);
    st = set_state(f, 1 - slot);
    FUZZ_CHECK(st == 0, "the FMU refused its own deserialised state (set): %s", last_msg);
    read_outputs(f, &b);
    if (stepping)
        FUZZ_CHECK(memcmp(&a, &b, sizeof a) == 0, "a restored state gives other outputs");
}

/* A value of the scale of x (a factor of 1/64 to 4 of it, 0, its negative), or any double. */
static double scaled(fuzz_reader *r, double x)
{
    uint8_t k = rd_u8(r);
    switch (k % 4) {
    case 0: return 0.0;
    case 1: return x * (double)(1 + rd_u8(r)) / 64.0;
    case 2: return -x;
    default: return rd_double(r);
    }
}

/* Issue 34's buffer modes and min_duration: 0 buffer_mode set to any int8, 1 min_duration
 * to a value of its scale or any value, 2 a buffered or blending move (target, mode,
 * execute edge), 3 both back to 0. */
static void queue_command(fmu *f, fuzz_reader *r, int what)
{
    switch (what) {
    case 0: (void)set_int(f, VR_BUFFER_MODE, (long long)(int8_t)rd_u8(r), 1); break;
    case 1: (void)set_real(f, VR_MIN_DURATION, scaled(r, 0.5)); break;
    case 2:
        (void)set_int(f, VR_BUFFER_MODE, 1 + rd_u8(r) % 2, 1);
        (void)set_real(f, VR_TARGET, scaled(r, 1.0));
        (void)set_bool(f, VR_EXECUTE, 1);
        break;
    default:
        (void)set_int(f, VR_BUFFER_MODE, 0, 1);
        (void)set_real(f, VR_MIN_DURATION, 0.0);
        break;
    }
}

/* Issue 34's per-command values: 0 one input cmd_* set to a value of its scale or any
 * value (an integer: any int8), 1 a move with limits, jerk times and a profile of its own
 * (execute edge), 2 a move with a custom shaper of its own (execute edge), 3 every cmd_*
 * back to 0. */
static void per_command(fmu *f, fuzz_reader *r, int what, double Te)
{
    static const unsigned reals[] = {VR_CMD_V_MAX, VR_CMD_A_MAX, VR_CMD_D_MAX, VR_CMD_T_F,
                                     VR_CMD_SHAPER_AMPLITUDE, VR_CMD_SHAPER_DELAY};
    static const unsigned ints[] = {VR_CMD_PROFILE, VR_CMD_SHAPER, VR_CMD_SHAPER_N};
    int i;
    switch (what) {
    case 0: {
        uint8_t k = rd_u8(r);
        if (k % 3 == 0) {
            unsigned vr = ints[rd_u8(r) % 3];
            (void)set_int(f, vr, (long long)(int8_t)rd_u8(r), is_enumeration(vr));
        } else {
            unsigned q = rd_u8(r) % 6, vr = reals[q];
            double base = q == 0 ? par(f, VR_V_MAX) : q < 3 ? par(f, VR_A_MAX)
                          : q == 4 ? 0.5 : Te * 8.0;
            if (q >= 3) vr += (unsigned)(rd_u8(r) % (q == 3 ? 4 : 8));
            (void)set_real(f, vr, scaled(r, base));
        }
        break;
    }
    case 1:
        (void)set_real(f, VR_CMD_V_MAX, scaled(r, par(f, VR_V_MAX)));
        (void)set_real(f, VR_CMD_A_MAX, scaled(r, par(f, VR_A_MAX)));
        (void)set_real(f, VR_CMD_D_MAX, scaled(r, par(f, VR_D_MAX)));
        (void)set_int(f, VR_CMD_PROFILE, rd_u8(r) % 5, 1);
        for (i = 0; i < 4; i++)
            (void)set_real(f, VR_CMD_T_F + (unsigned)i, Te * (double)(rd_u8(r) % 40));
        (void)set_real(f, VR_TARGET, scaled(r, 1.0));
        (void)set_bool(f, VR_EXECUTE, 1);
        break;
    case 2: {
        int n = 1 + rd_u8(r) % 4;
        double sum = 0.0, A[8];
        for (i = 0; i < n; i++) sum += A[i] = 1.0 + rd_u8(r);
        for (i = 0; i < n; i++) {
            (void)set_real(f, VR_CMD_SHAPER_AMPLITUDE + (unsigned)i, A[i] / sum);
            (void)set_real(f, VR_CMD_SHAPER_DELAY + (unsigned)i, Te * (double)(rd_u8(r) % 64));
        }
        (void)set_int(f, VR_CMD_SHAPER_N, n, 0);
        (void)set_int(f, VR_CMD_SHAPER, rd_u8(r) % 7, 1);
        (void)set_real(f, VR_TARGET, scaled(r, 1.0));
        (void)set_bool(f, VR_EXECUTE, 1);
        break;
    }
    default:
        for (i = 0; i < 6; i++) {
            unsigned k, n = i == 3 ? 4 : i >= 4 ? 8 : 1;
            for (k = 0; k < n; k++) (void)set_real(f, reals[i] + k, 0.0);
        }
        for (i = 0; i < 3; i++) (void)set_int(f, ints[i], 0, is_enumeration(ints[i]));
        break;
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_reader r;
    fmu f;
    follow w;
    int ops = 0, st;
    double Te = 1e-3;
    r.p = data;
    r.n = size;
    r.i = 0;
    memset(&f, 0, sizeof f);
    memset(&w, 0, sizeof w);
    f.v3 = rd_u8(&r) & 1;
    if (!instantiate(&f, rd_u8(&r) & 1)) return 0;
    while (rd_more(&r) && ops++ < 400) {
        uint8_t op = rd_u8(&r);
        switch (op % 16) {
        case 0: { /* set a variable of the table (any value, sometimes the wrong type) */
            /* the variables before issue 33's table (the first FUZZ_OLD_VARS) decode as
             * they did, but from a byte of 250 up: the corpus keeps its meaning */
            uint8_t b = rd_u8(&r);
            const djl_var_info *v =
                &djl_var_table[b < 250 ? b % FUZZ_OLD_VARS
                                       : FUZZ_OLD_VARS + (b - 250) % FUZZ_TABLE_VARS];
            unsigned vr = v->vr + (v->size > 1 ? rd_u8(&r) % v->size : 0);
            uint8_t how = rd_u8(&r);
            char type = how & 0x80 ? "RIBE"[how & 3] : v->type;
            if (v->vr == VR_TABLE_JERK && (how & 0xa0) == 0x20) {
                load_table(&f, &r, Te); /* a whole table */
                break;
            }
            if (type == 'R') st = set_real(&f, vr, rd_double(&r));
            else if (type == 'B') st = set_bool(&f, vr, rd_u8(&r) & 1);
            else st = set_int(&f, vr, (long long)(int8_t)rd_u8(&r), how & 0x40);
            if (st == 0 && vr == VR_TE) Te = par(&f, VR_TE);
            (void)djl_log_category_names;
            break;
        }
        case 1: /* an unknown value reference */
            (void)set_real(&f, rd_u32(&r), rd_double(&r));
            break;
        case 2:
            (void)enter_init(&f, rd_u8(&r) & 1 ? 0.0 : rd_double(&r));
            break;
        case 3:
            st = exit_init(&f);
            if (st == 0) {
                Te = par(&f, VR_TE);
                w.tracked = 1;
                w.goal = GOAL_PARAM;
                w.expect = parametric_end(&f, &w.scale);
                (void)get_bool(&f, VR_EXECUTE, &w.exec_seen);
                (void)get_bool(&f, VR_STOP, &w.stop_seen);
                w.t = par(&f, VR_TIME);
                w.stepping = 0;
            }
            break;
        case 4:
        case 5:
        case 6: { /* a step, mostly from where the FMU is */
            double h = step_size(&r, Te), t = par(&f, VR_TIME);
            int ex = 0, sp = 0, off = rd_u8(&r) % 16 == 0;
            if (off) t += rd_double(&r);
            (void)get_bool(&f, VR_EXECUTE, &ex);
            (void)get_bool(&f, VR_STOP, &sp);
            st = do_step(&f, t, h);
            w.stepping = st == 0;
            if (st != 0) {
                w.tracked = 0;
            } else {
                int refused = 0;
                if ((ex && !w.exec_seen) || (sp && !w.stop_seen)) {
                    /* a command: refused (cmd_error, the goal as it was) or accepted */
                    (void)get_bool(&f, VR_CMD_ERROR, &refused);
                    if (!refused) command_accepted(&f, &w, !(sp && !w.stop_seen));
                }
                if (refused) {
                    /* the move in progress goes on */
                } else if (!(ex && !w.exec_seen) && !(sp && !w.stop_seen) && !w.err_seen &&
                           get_bool(&f, VR_CMD_ERROR, &refused) == 0 && refused) {
                    w.tracked = 0; /* a waiting command refused when its turn came */
                } else if (ex && !w.exec_seen && sp && !w.stop_seen) {
                    w.tracked = 0;
                } else if (ex && !w.exec_seen) {
                    w.goal = GOAL_TARGET;
                    w.expect = par(&f, VR_TARGET);
                } else if (sp && !w.stop_seen) {
                    w.goal = GOAL_STOP;
                }
                w.exec_seen = ex;
                w.stop_seen = sp;
                w.err_seen = 0;
                (void)get_bool(&f, VR_CMD_ERROR, &w.err_seen);
            }
            check_step(&f, &w);
            break;
        }
        case 7: { /* a command: a target and an execute edge, or a stop edge, or f_mode; from
                   * a byte of 252 up (the corpus keeps its meaning), issue 34's values; from
                   * 248 to 251 its buffer modes and min_duration */
            uint8_t b = rd_u8(&r);
            if (b >= 252) {
                per_command(&f, &r, b - 252, Te);
                break;
            }
            if (b >= 248) {
                queue_command(&f, &r, b - 248);
                break;
            }
            switch (b % 4) {
            case 0:
                (void)set_real(&f, VR_TARGET, rd_double(&r));
                (void)set_bool(&f, VR_EXECUTE, 1);
                break;
            case 1: (void)set_bool(&f, VR_EXECUTE, 0); break;
            case 2: (void)set_bool(&f, VR_STOP, rd_u8(&r) & 1); break;
            default: (void)set_real(&f, VR_F_MODE, rd_double(&r)); break;
            }
            break;
        }
        case 8: { /* getters of every variable */
            int i;
            outputs o;
            for (i = 0; i < DJL_N_VARS; i++) {
                const djl_var_info *v = &djl_var_table[i];
                double x = 0.0;
                long long n = 0;
                int b = 0;
                if (v->type == 'R') {
                    st = get_real(&f, v->vr, &x);
                    /* outputs, calculated parameters, time: finite (a parameter reads back
                     * what was set, validated at initialisation) */
                    if (st == 0 && strchr("oct", v->causality))
                        FUZZ_CHECK(isfinite(x), "%s = %g", v->name, x);
                } else if (v->type == 'B') {
                    (void)get_bool(&f, v->vr, &b);
                } else {
                    (void)get_int(&f, v->vr, &n);
                }
            }
            read_outputs(&f, &o);
            break;
        }
        case 9: /* save and restore at once */
            own_state(&f, rd_u8(&r) & 1, w.stepping);
            break;
        case 10: { /* restore a saved state (the move is no longer followed) */
            int slot = rd_u8(&r) & 1;
            if (f.state[slot] && set_state(&f, slot) == 0) {
                w.tracked = 0;
                w.stepping = 0;
            }
            break;
        }
        case 11: { /* a forged state: one 8-byte word of a saved one changed, resealed */
            int slot = rd_u8(&r) & 1;
            uint32_t word = rd_u32(&r);
            size_t at, n = 0;
            if (!f.state[slot] || serialize(&f, slot, state_buf, sizeof state_buf, &n) != 0)
                break;
            at = (word % (n / 8)) * 8;
            if (rd_u8(&r) & 1) {
                double x = rd_double(&r);
                memcpy(state_buf + at, &x, 8);
            } else {
                uint32_t x = rd_u32(&r);
                memcpy(state_buf + at + (rd_u8(&r) & 4), &x, 4);
            }
            if (rd_u8(&r) % 8) model_state_seal(state_buf, n);
            if (deserialize(&f, 1 - slot, state_buf, n) == 0 &&
                set_state(&f, 1 - slot) == 0) {
                w.tracked = 0;
                w.stepping = 0;
            }
            break;
        }
        case 12:
            st = reset(&f);
            FUZZ_CHECK(st == 0, "Reset returned %d", st);
            w.tracked = 0;
            w.stepping = 0;
            /* the start value: Reset restores it (a getter here, before issue 33, put every
             * FMI 2 instance in the Error state: no getters before initialisation) */
            Te = 1e-3;
            break;
        case 13:
            (void)terminate(&f);
            w.stepping = 0;
            break;
        case 14:
            (void)debug_logging(&f, rd_u8(&r) & 1);
            break;
        default: /* a new instance */
            free_instance(&f);
            memset(&w, 0, sizeof w);
            Te = 1e-3;
            if (!instantiate(&f, rd_u8(&r) & 1)) return 0;
            break;
        }
    }
    free_instance(&f);
    return 0;
}
