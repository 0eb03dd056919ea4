/*
 * compare_builds.c -- two builds of the FMU's binary (FMI 2 or FMI 3), loaded
 * with dlopen, run the same random scenarios: every status, every logged
 * message (status, category, text), every output after every step and every
 * calculated parameter must be the same.  Used to show that a change leaves
 * the FMU bit for bit as it was for the parameters it does not touch (issue 18:
 * shaper = 0 against the build before the input shaper; docs/generator.md,
 * "Input shaping").  Not part of the suite: it needs the other build.
 *
 * The scenarios: random parameter sets of test_core.c's families (everyday,
 * round-number and extreme magnitudes, 10 % spoiled), a random start time and
 * t_start, jerk_source 1..3 with f_mode, then up to 400 communication steps of
 * random lengths (whole samples, multiples, fractions of Te) with commands
 * (execute edges with random targets, stops, f_mode changes), an FMU state
 * saved mid-run, restored and replayed, and a serialisation round trip.
 *
 * Usage: compare_builds 2|3 OLD.so OLD_TOKEN NEW.so NEW_TOKEN [cases] [seed] [strict]
 * Each build: gcc -std=c99 -O2 -fvisibility=hidden -shared -fPIC -I<its fmu_src>
 *   -I<fmpy>/c-code <its fmu_src>/djl_*.c fmu_*.c fmi2.c (or fmi3.c), fmu_*.c being
 *   fmu_instance.c, fmu_model.c and, in builds that have it, fmu_base.c;
 * its token is DJL_INSTANTIATION_TOKEN of its djl_vars.h.  This driver links the new
 * core (test_core.c's parameter families): gcc ... -Ifmu_src -Itests/c -I<fmpy>/c-code
 *   tests/c/compare_builds.c fmu_src/djl_*.c -ldl -lm.  docs/generator.md gives the runs.
 *
 * Log messages are compared whole (up to the FMU's 1024 bytes).  "strict" (8th argument)
 * is for two builds of the same FMU (the same FMU state layout: a change of structure
 * only): the scenarios also get an input shaper in half of the cases (ZV, ZVD, EI,
 * custom; timed for f_shaper or by f_mode; a few invalid), calls that are refused
 * mid-run (NULL pointers, inputs out of range, debug-logging categories: unknown, NULL,
 * a subset switched on for a step), and at the end calls an importer gets wrong
 * (unknown value references, wrong types, setting outputs, calculated or fixed
 * parameters, bad steps), Terminate, calls after it, Reset; and the FMU state bytes
 * themselves are compared (mid-run, at the end, after Reset), as is the verdict on
 * damaged states (a byte changed, then in most of them the checksum made valid again:
 * the structural checks), a forged state both accept being restored and stepped.
 */
#define _POSIX_C_SOURCE 200809L
#define main test_core_main /* test_core.c: its parameter families and random numbers */
#include "test_core.c"
#undef main

#include <dlfcn.h>

#include "djl_vars.h"
#include "fmi2FunctionTypes.h"
#include "fmi3FunctionTypes.h"
#include "fmu_base.h" /* strict: model_data, where a damaged state is damaged */

#define MAX_LOG 4096

typedef struct {
    int n;
    char text[MAX_LOG][1100]; /* status, category and the whole message (the FMU's <= 1023) */
} log_book;

static log_book books[2];
static long diffs, compared_values, compared_logs, refused_restores, refused_saves;
static int strict; /* the same FMU state layout: see the header */
static long compared_states, compared_state_bytes, forged_states, forged_accepted, shaped_cases;

static void note(log_book *b, int status, const char *category, const char *msg)
{
    if (b->n < MAX_LOG) {
        snprintf(b->text[b->n], sizeof b->text[b->n], "%d|%s|%s", status, category, msg);
        b->n++;
    }
}

static void log2cb(fmi2ComponentEnvironment env, fmi2String name, fmi2Status st,
                   fmi2String cat, fmi2String msg, ...)
{
    (void)name;
    note((log_book *)env, (int)st, cat, msg);
}

static void log3cb(fmi3InstanceEnvironment env, fmi3Status st, fmi3String cat, fmi3String msg)
{
    note((log_book *)env, (int)st, cat, msg);
}

typedef struct {
    void *lib;
    const char *token;
    /* FMI 2 */
    fmi2InstantiateTYPE *i2;
    fmi2FreeInstanceTYPE *free2;
    fmi2SetupExperimentTYPE *setup2;
    fmi2EnterInitializationModeTYPE *enter2;
    fmi2ExitInitializationModeTYPE *exit2;
    fmi2SetRealTYPE *setR2;
    fmi2SetIntegerTYPE *setI2;
    fmi2SetBooleanTYPE *setB2;
    fmi2GetRealTYPE *getR2;
    fmi2GetIntegerTYPE *getI2;
    fmi2GetBooleanTYPE *getB2;
    fmi2DoStepTYPE *step2;
    fmi2GetFMUstateTYPE *gets2;
    fmi2SetFMUstateTYPE *sets2;
    fmi2FreeFMUstateTYPE *frees2;
    fmi2SerializedFMUstateSizeTYPE *ssize2;
    fmi2SerializeFMUstateTYPE *ser2;
    fmi2DeSerializeFMUstateTYPE *deser2;
    fmi2SetDebugLoggingTYPE *dbg2;
    fmi2TerminateTYPE *term2;
    fmi2ResetTYPE *reset2;
    /* FMI 3 */
    fmi3InstantiateCoSimulationTYPE *i3;
    fmi3FreeInstanceTYPE *free3;
    fmi3EnterInitializationModeTYPE *enter3;
    fmi3ExitInitializationModeTYPE *exit3;
    fmi3SetFloat64TYPE *setF3;
    fmi3SetInt32TYPE *setI3;
    fmi3SetInt64TYPE *setL3;
    fmi3SetBooleanTYPE *setB3;
    fmi3GetFloat64TYPE *getF3;
    fmi3GetInt32TYPE *getI3;
    fmi3GetBooleanTYPE *getB3;
    fmi3DoStepTYPE *step3;
    fmi3GetFMUStateTYPE *gets3;
    fmi3SetFMUStateTYPE *sets3;
    fmi3FreeFMUStateTYPE *frees3;
    fmi3SerializedFMUStateSizeTYPE *ssize3;
    fmi3SerializeFMUStateTYPE *ser3;
    fmi3DeserializeFMUStateTYPE *deser3;
    fmi3SetDebugLoggingTYPE *dbg3;
    fmi3TerminateTYPE *term3;
    fmi3ResetTYPE *reset3;
} build;

static int version;
static build B[2];

static void *sym(build *b, const char *name)
{
    void *f = dlsym(b->lib, name);
    if (!f) {
        fprintf(stderr, "missing %s\n", name);
        exit(2);
    }
    return f;
}

#define LOAD(b, field, name) *(void **)(&(b)->field) = sym((b), name)

static void load(build *b, const char *path, const char *token)
{
    b->lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!b->lib) {
        fprintf(stderr, "%s\n", dlerror());
        exit(2);
    }
    b->token = token;
    if (version == 2) {
        LOAD(b, i2, "fmi2Instantiate");
        LOAD(b, free2, "fmi2FreeInstance");
        LOAD(b, setup2, "fmi2SetupExperiment");
        LOAD(b, enter2, "fmi2EnterInitializationMode");
        LOAD(b, exit2, "fmi2ExitInitializationMode");
        LOAD(b, setR2, "fmi2SetReal");
        LOAD(b, setI2, "fmi2SetInteger");
        LOAD(b, setB2, "fmi2SetBoolean");
        LOAD(b, getR2, "fmi2GetReal");
        LOAD(b, getI2, "fmi2GetInteger");
        LOAD(b, getB2, "fmi2GetBoolean");
        LOAD(b, step2, "fmi2DoStep");
        LOAD(b, gets2, "fmi2GetFMUstate");
        LOAD(b, sets2, "fmi2SetFMUstate");
        LOAD(b, frees2, "fmi2FreeFMUstate");
        LOAD(b, ssize2, "fmi2SerializedFMUstateSize");
        LOAD(b, ser2, "fmi2SerializeFMUstate");
        LOAD(b, deser2, "fmi2DeSerializeFMUstate");
        LOAD(b, dbg2, "fmi2SetDebugLogging");
        LOAD(b, term2, "fmi2Terminate");
        LOAD(b, reset2, "fmi2Reset");
    } else {
        LOAD(b, i3, "fmi3InstantiateCoSimulation");
        LOAD(b, free3, "fmi3FreeInstance");
        LOAD(b, enter3, "fmi3EnterInitializationMode");
        LOAD(b, exit3, "fmi3ExitInitializationMode");
        LOAD(b, setF3, "fmi3SetFloat64");
        LOAD(b, setI3, "fmi3SetInt32");
        LOAD(b, setL3, "fmi3SetInt64");
        LOAD(b, setB3, "fmi3SetBoolean");
        LOAD(b, getF3, "fmi3GetFloat64");
        LOAD(b, getI3, "fmi3GetInt32");
        LOAD(b, getB3, "fmi3GetBoolean");
        LOAD(b, step3, "fmi3DoStep");
        LOAD(b, gets3, "fmi3GetFMUState");
        LOAD(b, sets3, "fmi3SetFMUState");
        LOAD(b, frees3, "fmi3FreeFMUState");
        LOAD(b, ssize3, "fmi3SerializedFMUStateSize");
        LOAD(b, ser3, "fmi3SerializeFMUState");
        LOAD(b, deser3, "fmi3DeserializeFMUState");
        LOAD(b, dbg3, "fmi3SetDebugLogging");
        LOAD(b, term3, "fmi3Terminate");
        LOAD(b, reset3, "fmi3Reset");
    }
}

static fmi2CallbackFunctions cb2[2];
static void *inst[2];

static int instantiate(int w)
{
    books[w].n = 0;
    if (version == 2) {
        cb2[w].logger = log2cb;
        cb2[w].allocateMemory = calloc;
        cb2[w].freeMemory = free;
        cb2[w].stepFinished = NULL;
        cb2[w].componentEnvironment = &books[w];
        inst[w] = B[w].i2("cmp", fmi2CoSimulation, B[w].token, "file:///tmp", &cb2[w], fmi2False,
                          fmi2True);
    } else {
        inst[w] = B[w].i3("cmp", B[w].token, "/tmp", fmi3False, fmi3True, fmi3False, fmi3False,
                          NULL, 0, &books[w], log3cb, NULL);
    }
    return inst[w] != NULL;
}

/* Each call made on both builds: the statuses must agree. */
static int st[2];
#define BOTH(call2, call3)                                                                      \
    do {                                                                                         \
        int w_;                                                                                  \
        for (w_ = 0; w_ < 2; w_++) {                                                             \
            build *b = &B[w_];                                                                   \
            void *c = inst[w_];                                                                  \
            (void)b;                                                                             \
            (void)c;                                                                             \
            st[w_] = version == 2 ? (int)(call2) : (int)(call3);                                 \
        }                                                                                        \
        if (st[0] != st[1]) differ("status", __LINE__);                                          \
    } while (0)

static long case_no;
static djl_params case_params; /* the case's parameters (COMPARE_VERBOSE) */
static void differ(const char *what, int line)
{
    if (diffs < 20) fprintf(stderr, "case %ld: %s differs (line %d)\n", case_no, what, line);
    diffs++;
}

static void set_real(unsigned vr, double v)
{
    fmi2ValueReference r2 = vr;
    fmi3ValueReference r3 = vr;
    BOTH(b->setR2(c, &r2, 1, &v), b->setF3(c, &r3, 1, &v, 1));
}

static void set_int(unsigned vr, int v, int enumeration)
{
    fmi2ValueReference r2 = vr;
    fmi3ValueReference r3 = vr;
    fmi2Integer i2 = v;
    fmi3Int32 i3 = v;
    fmi3Int64 l3 = v;
    if (enumeration)
        BOTH(b->setI2(c, &r2, 1, &i2), b->setL3(c, &r3, 1, &l3, 1));
    else
        BOTH(b->setI2(c, &r2, 1, &i2), b->setI3(c, &r3, 1, &i3, 1));
}

static void set_bool(unsigned vr, int v)
{
    fmi2ValueReference r2 = vr;
    fmi3ValueReference r3 = vr;
    fmi2Boolean b2 = v;
    fmi3Boolean b3 = v != 0;
    BOTH(b->setB2(c, &r2, 1, &b2), b->setB3(c, &r3, 1, &b3, 1));
}

static void set_array(unsigned vr, const double *v, int n)
{
    fmi2ValueReference r2[DJL_MAX_SEGMENTS];
    fmi3ValueReference r3 = vr;
    int i;
    for (i = 0; i < n; i++) r2[i] = vr + (unsigned)i;
    BOTH(b->setR2(c, r2, (size_t)n, v), b->setF3(c, &r3, 1, v, (size_t)n));
}

/* Compare the logs written since the last call, then forget them. */
static void compare_logs(void)
{
    int i;
    if (books[0].n != books[1].n) differ("number of log messages", __LINE__);
    for (i = 0; i < books[0].n && i < books[1].n; i++) {
        compared_logs++;
        if (strcmp(books[0].text[i], books[1].text[i]) != 0) {
            if (diffs < 20)
                fprintf(stderr, "  old: %s\n  new: %s\n", books[0].text[i], books[1].text[i]);
            differ("log message", __LINE__);
        }
    }
    books[0].n = books[1].n = 0;
}

static const unsigned real_out[] = {VR_X, VR_V, VR_A, VR_J, VR_X_AL, VR_V_AL, VR_A_AL, VR_TIME};
static const unsigned int_out[] = {VR_SEGMENT, VR_STAGE};
static const unsigned bool_out[] = {VR_DONE, VR_BUSY};
static const unsigned calc_real[] = {VR_MOTION_TIME, VR_V_REACHED, VR_A_REACHED, VR_D_REACHED};
static const unsigned calc_int[] = {VR_N_F1, VR_N_F2, VR_N_F3, VR_N_F4};

static void compare_values(const unsigned *vr, int n, char type)
{
    int i, w;
    for (i = 0; i < n; i++) {
        double val[2];
        for (w = 0; w < 2; w++) {
            build *b = &B[w];
            void *c = inst[w];
            fmi2ValueReference r2 = vr[i];
            fmi3ValueReference r3 = vr[i];
            val[w] = 0.0;
            if (type == 'R') {
                fmi2Real x2 = 0.0;
                fmi3Float64 x3 = 0.0;
                st[w] = version == 2 ? (int)b->getR2(c, &r2, 1, &x2)
                                     : (int)b->getF3(c, &r3, 1, &x3, 1);
                val[w] = version == 2 ? x2 : x3;
            } else if (type == 'I') {
                fmi2Integer x2 = 0;
                fmi3Int32 x3 = 0;
                st[w] = version == 2 ? (int)b->getI2(c, &r2, 1, &x2)
                                     : (int)b->getI3(c, &r3, 1, &x3, 1);
                val[w] = version == 2 ? x2 : x3;
            } else {
                fmi2Boolean x2 = 0;
                fmi3Boolean x3 = 0;
                st[w] = version == 2 ? (int)b->getB2(c, &r2, 1, &x2)
                                     : (int)b->getB3(c, &r3, 1, &x3, 1);
                val[w] = version == 2 ? (double)x2 : (double)x3;
            }
        }
        compared_values++;
        if (st[0] != st[1]) differ("get status", __LINE__);
        if (memcmp(&val[0], &val[1], sizeof(double)) != 0) {
            if (diffs < 20)
                fprintf(stderr, "  vr %u: old %.17g new %.17g\n", vr[i], val[0], val[1]);
            differ("value", __LINE__);
        }
    }
}

static void compare_outputs(void)
{
    compare_values(real_out, 8, 'R');
    compare_values(int_out, 2, 'I');
    compare_values(bool_out, 2, 'B');
    compare_logs();
}

static double t_now;
static double Te;

static void step(double h)
{
    fmi3Boolean eh, term, early;
    fmi3Float64 last;
    BOTH(b->step2(c, t_now, h, fmi2True), b->step3(c, t_now, h, fmi3False, &eh, &term, &early, &last));
    if (st[0] == 0) t_now += h;
}

static double random_step(void)
{
    double r = urand();
    if (r < 0.5) return Te;
    if (r < 0.7) return Te * (double)(2 + irand(20));
    if (r < 0.9) return Te * (0.05 + urand() * 3.0);
    return Te * 0.37;
}

static void free_both(void)
{
    int w;
    for (w = 0; w < 2; w++) {
        if (!inst[w]) continue;
        if (version == 2)
            B[w].free2(inst[w]);
        else
            B[w].free3(inst[w]);
        inst[w] = NULL;
    }
}

/* strict: the serialised FMU states of the two builds, kept to be compared byte for byte */
static unsigned char *kept[2];
static size_t kept_n[2];

static void keep_bytes(int w, const void *buf, size_t n)
{
    if (!strict) return;
    free(kept[w]);
    kept[w] = malloc(n ? n : 1);
    if (!kept[w]) {
        fprintf(stderr, "out of memory\n");
        exit(2);
    }
    memcpy(kept[w], buf, n);
    kept_n[w] = n;
}

static void compare_kept(int line)
{
    size_t i;
    compared_states++;
    if (kept_n[0] != kept_n[1]) {
        differ("FMU state size", line);
        return;
    }
    compared_state_bytes += (long)kept_n[0];
    if (memcmp(kept[0], kept[1], kept_n[0]) != 0) {
        size_t j, cs = offsetof(model_data, checksum);
        for (i = 0; i < kept_n[0] && kept[0][i] == kept[1][i]; i++) continue;
        /* the first one outside the checksum (which differs whenever another byte does) */
        for (j = 0; j < kept_n[0] && (kept[0][j] == kept[1][j] || (j >= cs && j < cs + 8)); j++)
            continue;
        if (diffs < 20)
            fprintf(stderr, "  FMU state: first different byte %lu of %lu (outside the "
                    "checksum: %lu)\n", (unsigned long)i, (unsigned long)kept_n[0],
                    (unsigned long)j);
        differ("FMU state bytes", line);
    }
}

static void free_states(void *s[2])
{
    int w;
    for (w = 0; w < 2; w++) {
        if (!s[w]) continue;
        if (version == 2)
            B[w].frees2(inst[w], (fmi2FMUstate *)&s[w]);
        else
            B[w].frees3(inst[w], (fmi3FMUState *)&s[w]);
        s[w] = NULL;
    }
}

static void compare_outputs(void);
static void step(double h);
static double random_step(void);

/* strict: where a state is damaged: mostly in the fields the FMU's checks of a state read
 * (header, parameters, counts, the plan's head and counts, outputs, commands, shaper) */
static size_t damage_position(size_t n)
{
    static const size_t at[][2] = {
        {0, offsetof(model_data, plan) + 64},
        {offsetof(model_data, plan) + offsetof(djl_plan, n_pieces) - 32, 64},
        {offsetof(model_data, plan) + offsetof(djl_plan, piece), 512},
        {offsetof(model_data, plan) + offsetof(djl_plan, n_steps) - 32, 64},
        {offsetof(model_data, plan) + offsetof(djl_plan, step), 256},
        {offsetof(model_data, out), offsetof(model_data, mem) - offsetof(model_data, out) + 512},
    };
    const size_t *r = at[irand((int)(sizeof at / sizeof at[0]))];
    size_t pos = urand() < 0.1 ? (size_t)(urand() * (double)n)
                               : r[0] + (size_t)(urand() * (double)r[1]);
    return pos < n ? pos : n - 1;
}

/* strict: a damaged copy of the kept state (a byte changed, or a word made a NaN, a large
 * or a negative integer; in 4 of 5 the checksum made valid again, so that the structural
 * checks judge it) deserialised by both builds: the same verdict and message; a state both
 * accept is restored and stepped. */
static void forged_restore(void)
{
    size_t n = kept_n[0], pos, i;
    unsigned char *f;
    void *s[2] = {NULL, NULL};
    int w, kind = irand(3);
    if (n < 64) return;
    f = malloc(n);
    if (!f) exit(2);
    memcpy(f, kept[0], n);
    pos = damage_position(n);
    if (kind == 0) {
        f[pos] ^= (unsigned char)(1 + irand(255));
    } else {
        uint64_t v = kind == 1 ? 0x7ff8000000000001ULL
                               : (urand() < 0.5 ? 0xffffffffffffffffULL : 0x0000000100000000ULL);
        pos &= ~(size_t)7;
        if (pos + 8 > n) pos = (n - 8) & ~(size_t)7;
        memcpy(f + pos, &v, 8);
    }
    if (urand() < 0.8) { /* the FMU's checksum: FNV-1a 64 over the words but its own (at 16) */
        uint64_t h = 0xcbf29ce484222325ULL, x;
        for (i = 0; i + 8 <= n; i += 8) {
            if (i == 16) continue;
            memcpy(&x, f + i, 8);
            h ^= x;
            h *= 0x100000001b3ULL;
        }
        memcpy(f + 16, &h, 8);
    }
    forged_states++;
    for (w = 0; w < 2; w++)
        st[w] = version == 2 ? (int)B[w].deser2(inst[w], (const fmi2Byte *)f, n,
                                                (fmi2FMUstate *)&s[w])
                             : (int)B[w].deser3(inst[w], f, n, (fmi3FMUState *)&s[w]);
    if (st[0] != st[1]) differ("damaged state status", __LINE__);
    compare_logs();
    if (st[0] == 0 && st[1] == 0) { /* both accept it: restored and stepped */
        forged_accepted++;
        for (w = 0; w < 2; w++)
            st[w] = version == 2 ? (int)B[w].sets2(inst[w], s[w]) : (int)B[w].sets3(inst[w], s[w]);
        if (st[0] != st[1]) differ("forged state restore status", __LINE__);
        compare_logs();
        compare_outputs();
        for (i = 0; i < 3; i++) {
            step(random_step());
            compare_outputs();
        }
    }
    for (w = 0; w < 2; w++)
        if (st[w] != 0) s[w] = NULL; /* not made */
    free_states(s);
    compare_logs();
    free(f);
}

/* strict: the FMU state of each build now, serialised: the same bytes (then, if forge,
 * damaged copies of it). */
static void compare_states(int forge)
{
    void *s[2] = {NULL, NULL};
    int w, ok;
    for (w = 0; w < 2; w++)
        st[w] = version == 2 ? (int)B[w].gets2(inst[w], (fmi2FMUstate *)&s[w])
                             : (int)B[w].gets3(inst[w], (fmi3FMUState *)&s[w]);
    if (st[0] != st[1]) differ("get state status", __LINE__);
    for (w = 0; w < 2; w++)
        if (st[w] != 0) s[w] = NULL;
    ok = st[0] == 0 && st[1] == 0;
    if (ok) {
        for (w = 0; w < 2; w++) {
            size_t n = 0;
            unsigned char *buf;
            int a, b;
            a = version == 2 ? (int)B[w].ssize2(inst[w], s[w], &n)
                             : (int)B[w].ssize3(inst[w], s[w], &n);
            buf = malloc(n ? n : 1);
            if (!buf) exit(2);
            b = version == 2 ? (int)B[w].ser2(inst[w], s[w], (fmi2Byte *)buf, n)
                             : (int)B[w].ser3(inst[w], s[w], buf, n);
            st[w] = a | b;
            keep_bytes(w, buf, st[w] == 0 ? n : 0); /* a refused serialisation wrote nothing */
            free(buf);
        }
        if (st[0] != st[1]) differ("serialise status", __LINE__);
        ok = st[0] == 0 && st[1] == 0;
        if (ok) compare_kept(__LINE__);
    }
    free_states(s);
    compare_logs();
    if (ok && forge && kept_n[0] == kept_n[1]) forged_restore();
}

/* Save a state in each build, run on, restore it, replay: the same outputs as the first run
 * (each build against itself, and the two builds against each other). */
static void state_round_trip(int steps)
{
    void *s[2] = {NULL, NULL};
    double hs[64], t0 = t_now, x_first[64][2];
    int w, i, refused, saved[2] = {0, 0};
    if (steps > 64) steps = 64;
    for (w = 0; w < 2; w++) {
        if (version == 2)
            st[w] = (int)B[w].gets2(inst[w], (fmi2FMUstate *)&s[w]);
        else
            st[w] = (int)B[w].gets3(inst[w], (fmi3FMUState *)&s[w]);
    }
    if (st[0] != st[1]) differ("get state status", __LINE__);
    if (st[0] != 0 || st[1] != 0) return;
    for (i = 0; i < steps; i++) {
        fmi2ValueReference r = VR_X;
        fmi3ValueReference r3 = VR_X;
        hs[i] = random_step();
        step(hs[i]);
        for (w = 0; w < 2; w++) {
            x_first[i][w] = 0.0;
            if (version == 2)
                B[w].getR2(inst[w], &r, 1, &x_first[i][w]);
            else
                B[w].getF3(inst[w], &r3, 1, &x_first[i][w], 1);
        }
        compare_outputs();
    }
    /* restore (through a serialisation in half of the cases) and replay; a state the FMU
     * refuses to serialise (its own check of the state) is not read back: the buffer was
     * not written */
    for (w = 0; w < 2; w++) {
        if (urand() < 2.0 && version == 2) {
            size_t n = 0;
            fmi2Byte *buf;
            saved[w] = (int)B[w].ssize2(inst[w], s[w], &n);
            buf = malloc(n);
            saved[w] |= (int)B[w].ser2(inst[w], s[w], buf, n);
            keep_bytes(w, buf, saved[w] == 0 ? n : 0);
            st[w] = saved[w] == 0 ? (int)B[w].deser2(inst[w], buf, n, (fmi2FMUstate *)&s[w])
                                  : saved[w];
            free(buf);
            st[w] |= (int)B[w].sets2(inst[w], s[w]);
        } else if (version == 3) {
            size_t n = 0;
            fmi3Byte *buf;
            saved[w] = (int)B[w].ssize3(inst[w], s[w], &n);
            buf = malloc(n);
            saved[w] |= (int)B[w].ser3(inst[w], s[w], buf, n);
            keep_bytes(w, buf, saved[w] == 0 ? n : 0);
            B[w].frees3(inst[w], (fmi3FMUState *)&s[w]);
            st[w] = saved[w] == 0 ? (int)B[w].deser3(inst[w], buf, n, (fmi3FMUState *)&s[w])
                                  : saved[w];
            free(buf);
            st[w] |= (int)B[w].sets3(inst[w], s[w]);
        }
    }
    if (saved[0] != saved[1]) differ("serialise status", __LINE__);
    if (saved[0] != 0) {
        refused_saves++;
        if (getenv("COMPARE_VERBOSE") && books[0].n > 0) {
            fprintf(stderr, "case %ld: the FMU refused its own state: %s\n", case_no,
                    books[0].text[books[0].n - 1]);
            dump_params(case_no, &case_params);
        }
    }
    if (st[0] != st[1]) differ("restore status", __LINE__);
    if (strict && saved[0] == 0 && saved[1] == 0) compare_kept(__LINE__);
    refused = st[0] != 0 || st[1] != 0;
    if (refused) { /* both refused it (a pre-existing check, the same in both): no replay */
        refused_restores++;
        if (getenv("CMP_VERBOSE"))
            for (w = 0; w < books[0].n; w++) fprintf(stderr, "case %ld restore: %s\n", case_no, books[0].text[w]);
    }
    compare_logs();
    t_now = t0;
    for (i = 0; i < steps; i++) {
        step(hs[i]);
        for (w = 0; w < 2; w++) {
            fmi2ValueReference r = VR_X;
            fmi3ValueReference r3 = VR_X;
            double x = 0.0;
            if (version == 2)
                B[w].getR2(inst[w], &r, 1, &x);
            else
                B[w].getF3(inst[w], &r3, 1, &x, 1);
            if (!refused && memcmp(&x, &x_first[i][w], sizeof x) != 0) {
                if (diffs < 20)
                    fprintf(stderr, "  build %d, step %d of the replay (h = %.17g Te): x = %.17g, "
                            "first run %.17g\n", w, i, hs[i] / Te, x, x_first[i][w]);
                differ("replay after restore", __LINE__);
            }
        }
        compare_outputs();
    }
    for (w = 0; w < 2; w++) {
        if (version == 2)
            B[w].frees2(inst[w], (fmi2FMUstate *)&s[w]);
        else
            B[w].frees3(inst[w], (fmi3FMUState *)&s[w]);
    }
}

static void debug_logging(int on, size_t n, const char *const *cats)
{
    BOTH(b->dbg2(c, on ? fmi2True : fmi2False, n, cats),
         b->dbg3(c, on ? fmi3True : fmi3False, n, cats));
}

/* strict: an input shaper (0: none) among the parameters; its kind */
static int set_shaper_params(double f_mode)
{
    double A[DJL_MAX_SHAPER_IMPULSES] = {0}, D[DJL_MAX_SHAPER_IMPULSES] = {0}, f, zeta, last, sum;
    int kind = urand() < 0.5 ? 0 : 1 + irand(4), source = urand() < 0.3 ? 2 : 1, n = 1, k;
    if (kind == 0) return 0;
    zeta = urand() < 0.5 ? 0.0 : 0.3 * urand();
    last = log_uniform(0.5, urand() < 0.9 ? 400.0 : 4000.0); /* samples */
    f = 1.0 / (sqrt(1.0 - zeta * zeta) * last * Te);
    if (source == 2) f = f_mode * (0.7 + 0.6 * urand()); /* delays near those at f_mode */
    if (urand() < 0.03) f = urand() < 0.5 ? -1.0 : 0.0; /* invalid */
    if (kind == 4) {
        n = 1 + irand(DJL_MAX_SHAPER_IMPULSES);
        sum = 0.0;
        for (k = 0; k < n; k++) {
            A[k] = 0.05 + urand();
            D[k] = urand() < 0.5 ? Te * (double)irand(300) : urand() * 300.0 * Te;
        }
        if (urand() < 0.1) A[irand(n)] = -0.3 * urand(); /* a negative amplitude */
        for (k = 0; k < n; k++) sum += A[k];
        if (!(sum > 0.05)) {
            A[0] += 1.0;
            sum += 1.0;
        }
        for (k = 0; k < n; k++) A[k] /= sum;
        if (urand() < 0.03) A[0] += 0.5; /* not summing to 1: refused */
    }
    set_int(VR_SHAPER, kind, 1);
    set_int(VR_SHAPER_SOURCE, source, 1);
    set_real(VR_F_SHAPER, f);
    set_real(VR_ZETA_SHAPER, zeta);
    set_int(VR_SHAPER_N, n, 0);
    if (kind == 4) {
        set_array(VR_SHAPER_AMPLITUDE, A, DJL_MAX_SHAPER_IMPULSES);
        set_array(VR_SHAPER_DELAY, D, DJL_MAX_SHAPER_IMPULSES);
    }
    return kind;
}

/* strict: a call refused mid-run, the instance usable after it; 1 if it changed the
 * debug log's categories (switched back on after the next step) */
static int refused_call(void)
{
    static const char *const null_entry[] = {"logEvents", NULL};
    static const char *const cats[][2] = {{"logEvents", "logStatusWarning"},
                                          {"logStatusWarning", "logStatusError"},
                                          {"logStatusWarning", "noSuchCategory"},
                                          {"logStatusError", "logEvents"}};
    fmi2ValueReference r2 = VR_X;
    fmi3ValueReference r3 = VR_X;
    double x = 0.0;
    switch (irand(9)) {
    case 0: BOTH(b->getR2(c, NULL, 1, &x), b->getF3(c, NULL, 1, &x, 1)); break;
    case 1: BOTH(b->getR2(c, &r2, 1, NULL), b->getF3(c, &r3, 1, NULL, 1)); break;
    case 2:
        r2 = r3 = VR_TARGET;
        BOTH(b->setR2(c, &r2, 1, NULL), b->setF3(c, &r3, 1, NULL, 1));
        break;
    case 3: set_real(VR_TARGET, urand() < 0.5 ? 1e300 : -1e300); break;
    case 4: set_real(VR_F_MODE, urand() < 0.5 ? -1.0 : 0.0); break;
    case 5: debug_logging(1, 2, NULL); break;
    case 6: debug_logging(1, 2, null_entry); break;
    case 7: debug_logging(urand() < 0.8, (size_t)(1 + irand(2)), cats[irand(4)]); return 1;
    default: debug_logging(0, 0, NULL); return 1;
    }
    return 0;
}

/* strict, at the end of a case: calls an importer gets wrong (most move the instance to
 * Error), Terminate, a step after it, Reset; the FMU states of Terminated and of a reset
 * instance compared */
static void epilogue(void)
{
    int k, n = irand(4);
    for (k = 0; k < n; k++) {
        fmi2ValueReference r2;
        fmi3ValueReference r3;
        double x = 0.0;
        fmi2Integer i2 = 0;
        fmi3Int32 i3 = 0;
        switch (irand(9)) {
        case 0: /* an unknown value reference */
            r2 = r3 = 9999;
            BOTH(b->getR2(c, &r2, 1, &x), b->getF3(c, &r3, 1, &x, 1));
            break;
        case 1: set_real(9999, 1.0); break;
        case 2: /* an Integer read as a Real */
            r2 = r3 = VR_SEGMENT;
            BOTH(b->getR2(c, &r2, 1, &x), b->getF3(c, &r3, 1, &x, 1));
            break;
        case 3: /* a Real read as an Integer */
            r2 = r3 = VR_X;
            BOTH(b->getI2(c, &r2, 1, &i2), b->getI3(c, &r3, 1, &i3, 1));
            break;
        case 4: set_real(VR_X, 1.0); break;         /* an output */
        case 5: set_real(VR_TE, Te); break;         /* a fixed parameter after initialisation */
        case 6: set_real(VR_MOTION_TIME, 1.0); break; /* a calculated parameter */
        case 7: set_real(VR_TIME, 1.0); break;      /* the independent variable */
        default: step(urand() < 0.5 ? -Te : 0.0); break;
        }
        compare_logs();
        compare_outputs();
    }
    BOTH(b->term2(c), b->term3(c));
    compare_logs();
    compare_outputs();
    compare_states(0);
    step(Te); /* not after Terminate */
    compare_outputs();
    BOTH(b->reset2(c), b->reset3(c));
    compare_logs();
    compare_states(0);
    compare_outputs();
}

static void run_case(void)
{
    djl_params p;
    double start_time = 0.0, t_start, f_mode, target, scale;
    int fam = irand(3), jerk_source = 1, i, steps, ex = 0, sp = 0, stateful, shaper = 0;
    int restore_logging = 0;
    if (fam == 0)
        classic_params(&p);
    else if (fam == 1)
        grid_params(&p);
    else
        extreme_params(&p);
    case_params = p;
    Te = p.Te;
    if (urand() < 0.3) start_time = (urand() - 0.3) * 100.0 * Te;
    t_start = urand() < 0.5 ? 0.0 : urand() * 50.0 * Te;
    if (urand() < 0.2) t_start = start_time + Te * (double)irand(20); /* on the grid */
    if (p.profile != DJL_PROFILE_AL && urand() < 0.3) jerk_source = 2 + irand(2);
    f_mode = 1.0 / (Te * (1.0 + irand(80)));
    target = p.x0 + (urand() - 0.5) * 2.0 * (fabs(p.distance) + 0.1);
    scale = fabs(p.distance) + p.v_max * Te;
    for (i = 0; i < 2; i++)
        if (!instantiate(i)) {
            fprintf(stderr, "instantiate failed\n");
            exit(2);
        }
    if (version == 2) {
        BOTH(b->setup2(c, fmi2False, 0.0, start_time, fmi2False, 0.0), 0);
        BOTH(b->enter2(c), 0);
    } else {
        BOTH(0, b->enter3(c, fmi3False, 0.0, start_time, fmi3False, 0.0));
    }
    t_now = start_time;
    set_int(VR_PROFILE, p.profile, 1);
    set_int(VR_SHORT_STAGE, p.short_stage, 1);
    set_real(VR_TE, p.Te);
    set_real(VR_T_START, t_start);
    set_real(VR_X0, p.x0);
    set_real(VR_DISTANCE, p.distance);
    set_real(VR_V_MAX, p.v_max);
    set_real(VR_A_MAX, p.a_max);
    set_real(VR_D_MAX, p.d_max);
    set_real(VR_T_F1, p.T_F[0]);
    set_real(VR_T_F2, p.T_F[1]);
    set_real(VR_T_F3, p.T_F[2]);
    set_real(VR_T_F4, p.T_F[3]);
    set_real(VR_V0, p.v0);
    set_real(VR_V_E, p.v_e);
    set_int(VR_N_SEGMENTS, p.n_segments, 0);
    if (p.n_segments > 0) {
        set_array(VR_SEG_DISTANCE, p.seg_distance, DJL_MAX_SEGMENTS);
        set_array(VR_SEG_V_END, p.seg_v_end, DJL_MAX_SEGMENTS);
    }
    set_int(VR_JERK_SOURCE, jerk_source, 1);
    set_real(VR_F_MODE, f_mode);
    set_real(VR_TARGET, target);
    if (strict) shaper = set_shaper_params(f_mode);
    compare_logs();
    BOTH(b->exit2(c), b->exit3(c));
    compare_logs();
    if (shaper && st[0] == 0) shaped_cases++;
    compare_values(calc_real, 4, 'R');
    compare_values(calc_int, 4, 'I');
    compare_outputs();
    if (st[0] != 0) { /* refused: a few calls in the error state, then free */
        step(Te);
        compare_outputs();
        if (strict) epilogue();
        free_both();
        return;
    }
    steps = 20 + irand(380);
    stateful = irand(steps);
    for (i = 0; i < steps; i++) {
        double r = urand();
        if (r < 0.03) {
            ex = !ex;
            set_real(VR_TARGET, p.x0 + (urand() - 0.5) * 4.0 * scale);
            set_bool(VR_EXECUTE, ex);
        } else if (r < 0.04) {
            sp = !sp;
            set_bool(VR_STOP, sp);
        }
        if (jerk_source >= 2 && urand() < 0.3) {
            f_mode *= 1.0 + (urand() - 0.5) * (urand() < 0.1 ? 1.0 : 0.05);
            set_real(VR_F_MODE, f_mode);
        }
        if (strict && urand() < 0.03) restore_logging = refused_call();
        compare_logs();
        step(random_step());
        compare_outputs();
        if (restore_logging) {
            debug_logging(1, 0, NULL);
            compare_logs();
            restore_logging = 0;
        }
        if (i == stateful) state_round_trip(1 + irand(30));
    }
    compare_values(calc_real, 4, 'R');
    compare_values(calc_int, 4, 'I');
    if (strict) {
        compare_states(1);
        epilogue();
    }
    free_both();
}

int main(int argc, char **argv)
{
    long cases, c;
    if (argc < 6) {
        fprintf(stderr, "usage: compare_builds 2|3 OLD.so OLD_TOKEN NEW.so NEW_TOKEN [cases] "
                        "[seed] [strict]\n");
        return 2;
    }
    version = atoi(argv[1]);
    load(&B[0], argv[2], argv[3]);
    load(&B[1], argv[4], argv[5]);
    cases = argc > 6 ? atol(argv[6]) : 1000;
    if (argc > 7) rng_state ^= strtoull(argv[7], NULL, 10) * 0x9E3779B97F4A7C15ULL;
    strict = argc > 8 && strcmp(argv[8], "strict") == 0;
    if (rng_state == 0) rng_state = 88172645463325252ULL;
    for (c = 0; c < cases; c++) {
        case_no = c;
        run_case();
    }
    printf("FMI %d: %ld cases, %ld values and %ld log messages compared (%ld FMU states "
           "refused by both): %ld differences\n", version, cases, compared_values, compared_logs,
           refused_restores, diffs);
    if (refused_saves)
        printf("(%ld of those refused at serialisation by the FMU's own check of the state "
               "it saved)\n", refused_saves);
    if (strict)
        printf("strict: %ld shaped cases, %ld FMU states compared (%ld bytes), %ld damaged "
               "states (%ld accepted by both, restored and stepped)\n", shaped_cases,
               compared_states, compared_state_bytes, forged_states, forged_accepted);
    return diffs != 0;
}
