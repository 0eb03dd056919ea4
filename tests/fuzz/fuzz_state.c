/*
 * fuzz_state.c -- FMU state deserialisation of arbitrary bytes (issue 21), through FMI 2.
 *
 * The first byte picks the input's meaning:
 *  - raw: the rest of the input is the serialised state, as is (any size);
 *  - forged: a state the FMU saved (one of eight base scenarios: the default move at
 *    0.05 s, three segments, an input shaper timed by f_mode after a replan (both rings of
 *    its memory in use), jerk_source 3 after a replan, AL after a
 *    stop, a state saved before initialisation; and, since issue 33, a replayed table
 *    (profile 4) mid-motion with a ZV shaper, and a table after a stop; since issue 34 a
 *    blending command and a buffered one waiting behind a move), patched by the
 *    input (bytes, 4- and
 *    8-byte words, doubles from the table of fuzz_common.h; half of them within the plan
 *    and the values around it), then mostly sealed again with a valid checksum, as a
 *    forger would.
 * An accepted state is set and stepped (steps of any size, commands in between).
 * Invariants: a refusal leaves the instance usable (the base state can be set again);
 * after an accepted state every step that answers OK gives finite outputs, and done is
 * !busy; Reset always works and the default move then lands.
 */
#include "djl_vars.h"
#include "fmi2Functions.h"
#include "fmu_instance.h"
#include "fuzz_common.h"

#include <stddef.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

#define N_BASE 9

static void logger(fmi2ComponentEnvironment e, fmi2String n, fmi2Status s, fmi2String c,
                   fmi2String m, ...)
{
    (void)e;
    (void)n;
    (void)s;
    (void)c;
    if (getenv("FUZZ_VERBOSE")) fprintf(stderr, "log: %s\n", m);
}

static const fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
static model_data base[N_BASE]; /* serialised (packed) states, base_size[i] bytes */
static size_t base_size[N_BASE];
static model_data work;
static fmi2Component inst;

static void set_real(fmi2Component c, fmi2ValueReference vr, double v)
{
    FUZZ_CHECK(fmi2SetReal(c, &vr, 1, &v) == fmi2OK, "set %u", vr);
}

static void set_int(fmi2Component c, fmi2ValueReference vr, int v)
{
    fmi2Integer x = v;
    FUZZ_CHECK(fmi2SetInteger(c, &vr, 1, &x) == fmi2OK, "set %u", vr);
}

static void set_bool(fmi2Component c, fmi2ValueReference vr, int v)
{
    fmi2Boolean x = v ? fmi2True : fmi2False;
    FUZZ_CHECK(fmi2SetBoolean(c, &vr, 1, &x) == fmi2OK, "set %u", vr);
}

static double get_real(fmi2Component c, fmi2ValueReference vr)
{
    double v = NAN;
    FUZZ_CHECK(fmi2GetReal(c, &vr, 1, &v) == fmi2OK, "get %u", vr);
    return v;
}

/* A getter that may be refused (a state saved before initialisation: FMI 2 has no getters
 * there); NAN then. */
static double try_real(fmi2Component c, fmi2ValueReference vr)
{
    double v = NAN;
    if (fmi2GetReal(c, &vr, 1, &v) != fmi2OK) return NAN;
    FUZZ_CHECK(isfinite(v), "value reference %u = %g", vr, v);
    return v;
}

static int try_bool(fmi2Component c, fmi2ValueReference vr, int v)
{
    fmi2Boolean x = v ? fmi2True : fmi2False;
    return (int)fmi2SetBoolean(c, &vr, 1, &x);
}

static void steps(fmi2Component c, int n, double h)
{
    int k;
    for (k = 0; k < n; k++)
        FUZZ_CHECK(fmi2DoStep(c, get_real(c, VR_TIME), h, fmi2True) == fmi2OK, "base step");
}

static void save(fmi2Component c, model_data *d, size_t *size)
{
    fmi2FMUstate s = NULL;
    FUZZ_CHECK(fmi2GetFMUstate(c, &s) == fmi2OK, "base state");
    FUZZ_CHECK(fmi2SerializedFMUstateSize(c, s, size) == fmi2OK, "size");
    FUZZ_CHECK(fmi2SerializeFMUstate(c, s, (fmi2Byte *)d, sizeof *d) == fmi2OK, "serialise");
    fmi2FreeFMUstate(c, &s);
}

static void make_bases(void)
{
    fmi2Component c;
    int i;
    for (i = 0; i < N_BASE; i++) {
        c = fmi2Instantiate("base", fmi2CoSimulation, DJL_INSTANTIATION_TOKEN, "file:///tmp", &cb,
                            fmi2False, fmi2False);
        FUZZ_CHECK(c != NULL, "instantiate");
        fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0);
        if (i == 1) {
            set_int(c, VR_N_SEGMENTS, 3);
            set_real(c, VR_SEG_DISTANCE, 0.1);
            set_real(c, VR_SEG_DISTANCE + 1, 0.25);
            set_real(c, VR_SEG_DISTANCE + 2, -0.05);
            set_real(c, VR_SEG_V_END, 0.4);
        } else if (i == 2) {
            set_int(c, VR_SHAPER, SHAPER_ZVD);
            set_real(c, VR_F_SHAPER, 7.0);
            set_int(c, VR_SHAPER_SOURCE, SHAPER_SOURCE_F_MODE); /* both rings in use */
        } else if (i == 3) {
            set_int(c, VR_JERK_SOURCE, JERK_SOURCE_F_MODE_AHEAD);
            set_real(c, VR_F_MODE, 9.0);
        } else if (i == 4) {
            set_int(c, VR_PROFILE, PROFILE_AL);
        } else if (i == 6 || i == 7) { /* a table: +J, 0, -J, -J, 0, +J (J = 200 m/s3): 6.656 mm */
            static const int n[6] = {20, 12, 20, 20, 12, 20};
            static const double j[6] = {200.0, 0.0, -200.0, -200.0, 0.0, 200.0};
            int q;
            set_int(c, VR_PROFILE, PROFILE_TABLE);
            set_int(c, VR_TABLE_N, 6);
            for (q = 0; q < 6; q++) {
                set_int(c, VR_TABLE_SAMPLES + (fmi2ValueReference)q, n[q]);
                set_real(c, VR_TABLE_JERK + (fmi2ValueReference)q, j[q]);
            }
            set_real(c, VR_DISTANCE, 0.006656);
            set_real(c, VR_V_MAX, 0.5);
            set_real(c, VR_A_MAX, 4.1);
            set_real(c, VR_D_MAX, 4.1);
            if (i == 6) {
                set_int(c, VR_SHAPER, SHAPER_ZV);
                set_real(c, VR_F_SHAPER, 25.0);
            }
        }
        if (i == 5) { /* saved before initialisation */
            save(c, &base[i], &base_size[i]);
            fmi2FreeInstance(c);
            continue;
        }
        FUZZ_CHECK(fmi2EnterInitializationMode(c) == fmi2OK, "enter");
        FUZZ_CHECK(fmi2ExitInitializationMode(c) == fmi2OK, "exit");
        steps(c, i == 0 ? 50 : i == 6 || i == 7 ? 30 : 120, 1e-3);
        if (i == 8) { /* a queue: the move blends into the next, a buffered one waits */
            set_real(c, VR_TARGET, 0.6);
            set_int(c, VR_BUFFER_MODE, BUFFER_MODE_BLENDING);
            set_bool(c, VR_EXECUTE, 1);
            steps(c, 2, 1e-3);
            set_bool(c, VR_EXECUTE, 0);
            steps(c, 1, 1e-3);
            set_real(c, VR_TARGET, 0.1);
            set_int(c, VR_BUFFER_MODE, BUFFER_MODE_BUFFERED);
            set_real(c, VR_MIN_DURATION, 0.8);
            set_bool(c, VR_EXECUTE, 1);
            steps(c, 2, 1e-3);
        } else if (i == 2) { /* a replan: the shaper keeps the past of the plan it replaces */
            set_real(c, VR_F_MODE, 12.0);
            set_real(c, VR_TARGET, 0.2);
            set_bool(c, VR_EXECUTE, 1);
            steps(c, 30, 1e-3);
        } else if (i == 3) {
            set_real(c, VR_F_MODE, 14.0);
            set_real(c, VR_TARGET, -0.1);
            set_bool(c, VR_EXECUTE, 1);
            steps(c, 40, 1e-3);
        } else if (i == 4 || i == 7) {
            set_bool(c, VR_STOP, 1);
            steps(c, 3, 1e-3);
        }
        save(c, &base[i], &base_size[i]);
        fmi2FreeInstance(c);
    }
    FUZZ_CHECK(base_size[2] > base_size[0], "the shaper's base state holds no memory entries");
    inst = fmi2Instantiate("fuzz", fmi2CoSimulation, DJL_INSTANTIATION_TOKEN, "file:///tmp", &cb,
                           fmi2False, fmi2False);
    FUZZ_CHECK(inst != NULL, "instantiate");
}

/* Offsets: anywhere in a packed state of size bytes, or (half the time) within the
 * model's values before the shaper's memory. */
static size_t pick_offset(fuzz_reader *r, size_t width, size_t size)
{
    size_t lo = 0, hi = size;
    if (rd_u8(r) & 1) {
        lo = offsetof(model_data, p);
        hi = offsetof(model_data, mem);
    }
    return (lo + rd_u32(r) % (hi - lo - width)) / width * width;
}

static void run(fuzz_reader *r)
{
    fmi2FMUstate s = NULL;
    int n = 1 + rd_u8(r) % 64, k;
    fmi2ValueReference vrs[7] = {VR_X, VR_V, VR_A, VR_J, VR_X_AL, VR_V_AL, VR_A_AL};
    for (k = 0; k < n; k++) {
        double out[7], t, h, Te = try_real(inst, VR_TE);
        fmi2Boolean done = 0, busy = 0;
        fmi2ValueReference vd = VR_DONE, vb = VR_BUSY;
        uint8_t op = rd_u8(r);
        int i;
        if (op % 8 == 1) (void)try_bool(inst, VR_STOP, rd_u8(r) & 1);
        if (op % 8 == 2) {
            double x = rd_double(r);
            fmi2ValueReference vt = VR_TARGET;
            int ex = rd_u8(r) & 1;
            (void)fmi2SetReal(inst, &vt, 1, &x);
            (void)try_bool(inst, VR_EXECUTE, ex);
            if (getenv("FUZZ_VERBOSE")) fprintf(stderr, "target := %.17g, execute %d\n", x, ex);
        }
        if (op % 8 == 3) {
            double x = rd_double(r);
            fmi2ValueReference vf = VR_F_MODE;
            (void)fmi2SetReal(inst, &vf, 1, &x);
            if (getenv("FUZZ_VERBOSE")) fprintf(stderr, "f_mode := %.17g\n", x);
        }
        t = try_real(inst, VR_TIME);
        if (!(Te > 0.0) || !(t == t)) break;
        h = op & 0x80 ? Te * (double)(1 + rd_u32(r) % 1000000) : Te * (double)(1 + op % 4);
        if (fmi2DoStep(inst, t, h, fmi2True) != fmi2OK) break;
        if (getenv("FUZZ_VERBOSE")) {
            double o[3];
            (void)fmi2GetReal(inst, vrs, 3, o);
            fprintf(stderr, "step %d: t %.17g + h %.17g (op %u): x %.17g v %.17g a %.17g\n", k,
                    t, h, (unsigned)op, o[0], o[1], o[2]);
        }
        FUZZ_CHECK(fmi2GetReal(inst, vrs, 7, out) == fmi2OK, "get outputs");
        for (i = 0; i < 7; i++)
            FUZZ_CHECK(isfinite(out[i]), "output %u = %g after an OK step (step %d)", vrs[i],
                       out[i], k);
        FUZZ_CHECK(fmi2GetBoolean(inst, &vd, 1, &done) == fmi2OK &&
                       fmi2GetBoolean(inst, &vb, 1, &busy) == fmi2OK && done == !busy,
                   "done %d busy %d", done, busy);
    }
    (void)s;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_reader r;
    fmi2FMUstate s = NULL;
    uint8_t mode;
    int which, accepted;
    double x;
    if (!inst) make_bases();
    r.p = data;
    r.n = size;
    r.i = 0;
    mode = rd_u8(&r);
    /* the six bases before issue 33 as they were decoded (the corpus keeps its meaning),
     * the table's from a byte of 252 up, the queue's (issue 34) from 248 to 251 */
    which = rd_u8(&r);
    which = which >= 252 ? 6 + which % 2 : which >= 248 ? 8 : which % 6;
    if (mode % 8 == 0) {
        accepted = fmi2DeSerializeFMUstate(inst, (const fmi2Byte *)data + 2,
                                           size >= 2 ? size - 2 : 0, &s) == fmi2OK;
    } else {
        int n = 1 + rd_u8(&r) % 8, k;
        size_t n_work = base_size[which];
        memcpy(&work, &base[which], n_work);
        for (k = 0; k < n; k++) {
            uint8_t how = rd_u8(&r);
            size_t at;
            if (how % 4 == 0) {
                at = pick_offset(&r, 8, n_work);
                x = rd_double(&r);
                memcpy((char *)&work + at, &x, 8);
            } else if (how % 4 == 1) {
                uint32_t u = rd_u32(&r);
                at = pick_offset(&r, 4, n_work);
                memcpy((char *)&work + at, &u, 4);
            } else if (how % 4 == 2) {
                uint64_t u = 0;
                at = pick_offset(&r, 8, n_work);
                memcpy(&u, (char *)&work + at, 8);
                u ^= (uint64_t)1 << (rd_u8(&r) % 64);
                memcpy((char *)&work + at, &u, 8);
            } else {
                at = pick_offset(&r, 1, n_work);
                ((unsigned char *)&work)[at] = rd_u8(&r);
            }
            if (getenv("FUZZ_VERBOSE"))
                fprintf(stderr, "base %d: patch %d at byte %lu (kind %d)\n", which, k,
                        (unsigned long)at, how % 4);
            if (getenv("FUZZ_NO_PATCH")) /* (debugging: is the patch what matters?) */
                memcpy((char *)&work + at, (const char *)&base[which] + at, 8);
        }
        if (mode % 8 != 7) model_state_seal(&work, n_work);
        accepted = fmi2DeSerializeFMUstate(inst, (const fmi2Byte *)&work, n_work, &s) == fmi2OK;
    }
    if (accepted) {
        FUZZ_CHECK(fmi2SetFMUstate(inst, s) == fmi2OK, "set an accepted state");
        run(&r);
    } else {
        /* refused: the instance is as it was; a good state is still accepted */
        FUZZ_CHECK(fmi2DeSerializeFMUstate(inst, (const fmi2Byte *)&base[which],
                                           base_size[which], &s) == fmi2OK, "base refused");
    }
    fmi2FreeFMUstate(inst, &s);
    FUZZ_CHECK(fmi2Reset(inst) == fmi2OK, "reset");
    if (rd_u8(&r) % 16 == 0) { /* after Reset the default move lands */
        FUZZ_CHECK(fmi2SetupExperiment(inst, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK &&
                       fmi2EnterInitializationMode(inst) == fmi2OK &&
                       fmi2ExitInitializationMode(inst) == fmi2OK, "init after reset");
        FUZZ_CHECK(fmi2DoStep(inst, 0.0, 10.0, fmi2True) == fmi2OK, "step after reset");
        x = get_real(inst, VR_X);
        FUZZ_CHECK(fabs(x - 0.4) <= 1e-12, "the default move after reset ends at %.17g", x);
        FUZZ_CHECK(fmi2Reset(inst) == fmi2OK, "reset");
    }
    return 0;
}
