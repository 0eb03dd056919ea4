/*
 * test_shaper.c -- the FMU's input shaper (docs/generator.md, "Input shaping")
 * through the FMI 2 API, meant to run under AddressSanitizer + UBSan
 * (tests/test_c_sanitizers.py) and, for the campaign of docs/generator.md, at
 * -O2 with many cases.
 *
 * Each case plans a random motion (test_core.c's everyday and round-number
 * families, a random t_start, jerk times from f_mode in some cases) and runs
 * two instances side by side: S with a random shaper (ZV, ZVD, EI, custom with
 * 1..8 impulses, positive amplitudes or, in some cases, one negative; delays
 * on and off the sample grid; timed for f_shaper or by the phase of f_mode)
 * and R, the same FMU without one.  Both get the same commands (execute with
 * random targets, stop) and f_mode changes; S steps by Te or by random
 * fractions and multiples of it, R by whole samples (and to S's point when a
 * command is given there).  From R's samples (the unshaped profile p, a cubic
 * on each sample interval) the driver builds its own convolution with the
 * textbook amplitudes and delays written here (or, timed by f_mode, its own
 * integration of the phase of the f_mode it applied) and checks at every
 * communication point of S:
 *  - every output finite; x, v, a, j = sum A_i p(t - t_i) (1e-9 of the move,
 *    of v_max, of the accelerations, of the largest jerk of p);
 *  - with amplitudes >= 0: |v| <= v_max, |a| <= max(a_max, d_max), |j| <= the
 *    largest |j| of p (each to 1e-9);
 *  - done only once every copy has ended (p done at t - t_i for all i);
 *    without commands, motion_time = p's + the largest delay, and done exactly
 *    when the last copy ends;
 *  - at the end, S rests exactly (bit for bit) where R rests: on the target
 *    within 1e-9 of the move, or where a stop brought it;
 *  - an FMU state saved mid-move, serialised, restored and replayed with the
 *    same steps and inputs gives the same outputs bit for bit.
 *
 * Usage: test_shaper [cases] [seed] [max samples of a motion]
 */
#define main test_core_main /* test_core.c: its parameter families */
#include "test_core.c"
#undef main

#include "djl_vars.h"
#include "fmi2Functions.h"
#include "fmu_instance.h" /* model_state_max_size: which restored states hold shaper memory */

static long case_no;
#define CHECK(cond, ...)                                                                         \
    do {                                                                                         \
        if (!(cond)) {                                                                           \
            if (failures < 40) fprintf(stderr, "case %ld: ", case_no);                           \
            if (failures < 40)                                                                   \
                FAIL(__VA_ARGS__);                                                               \
            else                                                                                 \
                failures++;                                                                      \
        }                                                                                        \
    } while (0)

static char last_message[1024];
static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...)
{
    (void)env;
    (void)name;
    (void)status;
    (void)category;
    strncpy(last_message, message, sizeof last_message - 1);
}
static const fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};

#define MAXS 600000 /* samples of R recorded */
static double rx[MAXS], rv[MAXS], ra[MAXS], rj[MAXS], rate[MAXS];
static unsigned char rdone[MAXS];

typedef struct {
    long cases, skipped, steps, commands, stops, fchanges, custom, negative, off_grid, by_fmode,
        fractional, restores, restores_mem;
} tally;

typedef struct {
    int kind, source, n;
    double f, zeta, A[8], delay[8]; /* parameters */
    double amp[8], phase[8], d[8];  /* the test's own design: amplitudes, phases (periods of
                                       f_mode, source 2), delays (samples, source 1) */
    int nonneg;
} shaper_spec;

/* ------------------------------------------------------------------------ */
/* FMU calls                                                                */

static void set_real(fmi2Component c, fmi2ValueReference vr, double v)
{
    CHECK(fmi2SetReal(c, &vr, 1, &v) == fmi2OK, "set %u = %g: %s", vr, v, last_message);
}
static void set_int(fmi2Component c, fmi2ValueReference vr, int v)
{
    fmi2Integer i = v;
    CHECK(fmi2SetInteger(c, &vr, 1, &i) == fmi2OK, "set %u = %d: %s", vr, v, last_message);
}
static void set_bool(fmi2Component c, fmi2ValueReference vr, int v)
{
    fmi2Boolean b = v;
    CHECK(fmi2SetBoolean(c, &vr, 1, &b) == fmi2OK, "set %u", vr);
}

typedef struct {
    double x, v, a, j;
    int done;
} outs;

static outs get(fmi2Component c)
{
    fmi2ValueReference vr[4] = {VR_X, VR_V, VR_A, VR_J}, vd = VR_DONE;
    double val[4] = {NAN, NAN, NAN, NAN};
    fmi2Boolean d = 0;
    outs o;
    CHECK(fmi2GetReal(c, vr, 4, val) == fmi2OK, "get outputs");
    CHECK(fmi2GetBoolean(c, &vd, 1, &d) == fmi2OK, "get done");
    o.x = val[0];
    o.v = val[1];
    o.a = val[2];
    o.j = val[3];
    o.done = d != 0;
    return o;
}

static void set_params(fmi2Component c, const djl_params *p, double t_start, int jerk_source,
                       double f_mode)
{
    fmi2ValueReference vd = VR_SEG_DISTANCE, vv = VR_SEG_V_END;
    int i;
    set_int(c, VR_PROFILE, p->profile);
    set_int(c, VR_SHORT_STAGE, p->short_stage);
    set_real(c, VR_TE, p->Te);
    set_real(c, VR_T_START, t_start);
    set_real(c, VR_X0, p->x0);
    set_real(c, VR_DISTANCE, p->distance);
    set_real(c, VR_V_MAX, p->v_max);
    set_real(c, VR_A_MAX, p->a_max);
    set_real(c, VR_D_MAX, p->d_max);
    for (i = 0; i < 4; i++) set_real(c, VR_T_F1 + (unsigned)i, p->T_F[i]);
    set_real(c, VR_V0, p->v0);
    set_real(c, VR_V_E, p->v_e);
    set_int(c, VR_N_SEGMENTS, p->n_segments);
    for (i = 0; i < p->n_segments; i++) {
        fmi2ValueReference a = vd + (unsigned)i, b = vv + (unsigned)i;
        CHECK(fmi2SetReal(c, &a, 1, &p->seg_distance[i]) == fmi2OK, "seg");
        CHECK(fmi2SetReal(c, &b, 1, &p->seg_v_end[i]) == fmi2OK, "seg");
    }
    set_int(c, VR_JERK_SOURCE, jerk_source);
    set_real(c, VR_F_MODE, f_mode);
}

static void set_shaper(fmi2Component c, const shaper_spec *sh)
{
    int i;
    set_int(c, VR_SHAPER, sh->kind);
    set_int(c, VR_SHAPER_SOURCE, sh->source);
    set_real(c, VR_F_SHAPER, sh->f);
    set_real(c, VR_ZETA_SHAPER, sh->zeta);
    set_int(c, VR_SHAPER_N, sh->n);
    for (i = 0; i < 8; i++) {
        set_real(c, VR_SHAPER_AMPLITUDE + (unsigned)i, sh->A[i]);
        set_real(c, VR_SHAPER_DELAY + (unsigned)i, sh->delay[i]);
    }
}

/* ------------------------------------------------------------------------ */
/* the test's own shaper: the textbook formulas                             */

static void design(shaper_spec *sh, double Te)
{
    int i;
    double sq = sqrt(1.0 - sh->zeta * sh->zeta), K = exp(-sh->zeta * 3.14159265358979323846 / sq);
    double Td = 1.0 / (sh->f * sq), t[8] = {0};
    if (sh->kind == 1) { /* ZV: [1, K] / (1 + K) at [0, Td/2] */
        sh->n = 2;
        sh->amp[0] = 1.0 / (1.0 + K);
        sh->amp[1] = K / (1.0 + K);
        t[1] = Td / 2.0;
    } else if (sh->kind == 2) { /* ZVD: [1, 2K, K^2] / (1 + K)^2 at [0, Td/2, Td] */
        sh->n = 3;
        sh->amp[0] = 1.0 / ((1.0 + K) * (1.0 + K));
        sh->amp[1] = 2.0 * K / ((1.0 + K) * (1.0 + K));
        sh->amp[2] = K * K / ((1.0 + K) * (1.0 + K));
        t[1] = Td / 2.0;
        t[2] = Td;
    } else if (sh->kind == 3) { /* EI, V = 5 %: [(1+V)/4, (1-V)/2 K, (1+V)/4 K^2] normalised */
        double V = 0.05, r0 = (1 + V) / 4, r1 = (1 - V) / 2 * K, r2 = (1 + V) / 4 * K * K;
        sh->n = 3;
        sh->amp[0] = r0 / (r0 + r1 + r2);
        sh->amp[1] = r1 / (r0 + r1 + r2);
        sh->amp[2] = r2 / (r0 + r1 + r2);
        t[1] = Td / 2.0;
        t[2] = Td;
    } else {
        for (i = 0; i < sh->n; i++) {
            sh->amp[i] = sh->A[i];
            t[i] = sh->delay[i];
        }
    }
    sh->nonneg = 1;
    for (i = 0; i < sh->n; i++) {
        sh->d[i] = t[i] / Te;
        /* the phase of each copy (source 2): the delay at the design frequency in its periods
         * (standard shapers: Td / 2 and Td are half and whole damped periods) */
        sh->phase[i] = t[i] * sh->f;
        if (sh->amp[i] < 0.0) sh->nonneg = 0;
    }
}

/* ------------------------------------------------------------------------ */
/* the reference: p from R's samples, the copies, the phase                 */

static long r_samples; /* samples of R recorded: 0 .. r_samples - 1 */
static double x_before, v_before, rate_before;

/* p at grid time s (samples): the cubic of the sample interval (right limit at a sample;
 * left: the interval before it) */
static void p_at(double s, int left, double o[4])
{
    long k;
    double tau, Te = 1.0; /* scaled below */
    (void)Te;
    if (s < 0.0 || (left && s <= 0.0)) { /* before the grid's start: at rest or at v0 */
        o[0] = x_before + v_before * s * o[3]; /* o[3] carries Te in */
        o[1] = v_before;
        o[2] = 0.0;
        o[3] = 0.0;
        return;
    }
    k = (long)floor(s);
    if (left && (double)k == s) k--;
    if (k >= r_samples) k = r_samples - 1; /* cannot happen: R runs ahead */
    tau = (s - (double)k) * o[3];
    o[0] = rx[k] + tau * (rv[k] + tau * (0.5 * ra[k] + tau * rj[k] / 6.0));
    o[1] = rv[k] + tau * (ra[k] + 0.5 * tau * rj[k]);
    o[2] = ra[k] + tau * rj[k];
    o[3] = rj[k];
}

/* The grid time at which the phase of f_mode was ph periods behind its value at s (rates
 * per sample as applied: rate[k] over [k, k+1), rate_before before 0). */
static double phase_back(double s, double ph)
{
    long k = (long)floor(s);
    double rem = ph, r, portion;
    if (ph == 0.0) return s;
    r = k >= 0 ? rate[k] : rate_before;
    portion = r * (s - (double)k);
    if (rem <= portion) return s - rem / r;
    rem -= portion;
    for (k = k - 1;; k--) {
        r = k >= 0 ? rate[k] : rate_before;
        if (k < 0) return (double)(k + 1) - rem / r;
        if (rem <= r) return (double)(k + 1) - rem / r;
        rem -= r;
    }
}

/* The expected shaped outputs at grid time s: the copies' values (right limits; a delayed copy
 * whose time is within rounding of a sample may be either side there: its left limit in
 * alt[i], amb[i] = 1), and whether every copy has ended. */
static void expected(const shaper_spec *sh, double s, double Te, int by_phase, double c[8][4],
                     double alt[8][4], int amb[8], int *all_done)
{
    int i;
    *all_done = 1;
    for (i = 0; i < sh->n; i++) {
        double si = by_phase ? phase_back(s, sh->phase[i]) : s - sh->d[i], r = floor(si + 0.5);
        long k;
        c[i][3] = alt[i][3] = Te;
        /* a copy with a delay: its time is rounded differently here and in the FMU */
        amb[i] = (by_phase ? sh->phase[i] != 0.0 : sh->d[i] != 0.0) && fabs(si - r) < 1e-7;
        if (amb[i]) {
            p_at(r, 0, c[i]);
            p_at(r, 1, alt[i]);
        } else {
            p_at(si, 0, c[i]);
        }
        k = (long)floor(si + 1e-9);
        if (!(si >= 0.0 && k < r_samples && rdone[k])) *all_done = 0;
    }
}

/* Does output q (x, v, a, j) match sum A_i c_i for one choice of sides of the ambiguous
 * copies?  (*want: the all-right sum, for the message.) */
static int matches(const shaper_spec *sh, double c[8][4], double alt[8][4], const int amb[8],
                   int q, double got, double tol, double *want)
{
    int m = 0, idx[8], i, combo;
    for (i = 0; i < sh->n; i++)
        if (amb[i]) idx[m++] = i;
    for (combo = 0; combo < (1 << m); combo++) {
        double y = 0.0;
        int b;
        for (i = 0; i < sh->n; i++) {
            int left = 0;
            for (b = 0; b < m; b++)
                if (idx[b] == i && ((combo >> b) & 1)) left = 1;
            y += sh->amp[i] * (left ? alt[i][q] : c[i][q]);
        }
        if (combo == 0) *want = y;
        if (fabs(got - y) <= tol) return 1;
    }
    return 0;
}

/* ------------------------------------------------------------------------ */
/* one case                                                                 */

static long kmax = 20000;

typedef struct {
    double h, target, f;
    int set_target, set_f, exec_val, stop_val; /* exec_val, stop_val: -1 unchanged, else 0/1 */
} action;

/* Apply the inputs of an action to S and (first run) R. */
static void apply(fmi2Component S, fmi2Component R, const action *a, int to_r)
{
    if (a->set_target) {
        set_real(S, VR_TARGET, a->target);
        if (to_r) set_real(R, VR_TARGET, a->target);
    }
    if (a->exec_val >= 0) {
        set_bool(S, VR_EXECUTE, a->exec_val);
        if (to_r) set_bool(R, VR_EXECUTE, a->exec_val);
    }
    if (a->stop_val >= 0) {
        set_bool(S, VR_STOP, a->stop_val);
        if (to_r) set_bool(R, VR_STOP, a->stop_val);
    }
    if (a->set_f) {
        set_real(S, VR_F_MODE, a->f);
        if (to_r) set_real(R, VR_F_MODE, a->f);
    }
}

static void run_case(tally *t)
{
    djl_params p;
    djl_error e;
    static djl_plan plan;
    shaper_spec sh;
    fmi2Component S, R;
    double Te, t_start = 0.0, f_mode = 10.0, f_lo, f_hi, scale, target, jmax = 0.0, lvl, tS = 0.0,
           tR = 0.0, sS = 0.0, cv[8][4], alt[8][4], tol[4];
    long n_end, limit, nR = 0, step_no, save_at, commands = 0;
    int jerk_source = 1, whole, ex = 0, st = 0, by_phase, commands_left, all_done, k, dj, amb[8];
    int replaying = 0, n_record = 0, n_replay = 0, last_stop = 0;
    fmi2FMUstate saved = NULL;
    static action acts[400];
    static outs rec[400];
    memset(&sh, 0, sizeof sh);
    if (urand() < 0.5)
        classic_params(&p);
    else
        grid_params(&p);
    p.x0 = urand() < 0.5 ? 0.0 : (urand() - 0.5) * 10.0;
    Te = p.Te;
    if (p.profile != DJL_PROFILE_AL && urand() < 0.25) {
        jerk_source = 2 + irand(2);
        p.n_segments = 0;
        p.v_e = 0.0;
        if (p.distance == 0.0) p.distance = 0.1 * p.v_max;
        if (p.v0 * p.distance < 0.0) p.v0 = 0.0;
        f_mode = 1.0 / (Te * (2.0 + irand(60)));
        for (k = 0; k < 4; k++) p.T_F[k] = Te * floor(1.0 / (f_mode * Te) + 0.5);
        p.profile = DJL_PROFILE_DJL;
    }
    if (djl_plan_motion(&p, &plan, &e) != DJL_OK || plan.k_end > kmax) {
        t->skipped++;
        return;
    }
    if (urand() < 0.3) t_start = Te * (double)irand(50) + (urand() < 0.5 ? 0.0 : 0.3 * Te);
    /* the shaper */
    sh.kind = 1 + irand(4);
    sh.source = urand() < 0.25 ? 2 : 1;
    sh.zeta = urand() < 0.5 ? 0.0 : 0.3 * urand();
    sh.n = 1;
    {
        double last = log_uniform(0.5, urand() < 0.9 ? 400.0 : 4000.0); /* samples */
        double sq = sqrt(1.0 - sh.zeta * sh.zeta);
        sh.f = 1.0 / (sq * last * Te);
        if (urand() < 0.3) sh.f = 1.0 / (sq * 2.0 * floor(last / 2.0 + 1.0) * Te); /* ~on grid */
    }
    if (sh.kind == 4) {
        double sum = 0.0;
        t->custom++;
        sh.n = 1 + irand(8);
        for (k = 0; k < sh.n; k++) {
            sh.A[k] = 0.05 + urand();
            sh.delay[k] = urand() < 0.5 ? Te * (double)irand(300) : urand() * 300.0 * Te;
        }
        if (urand() < 0.1) { /* one negative amplitude */
            sh.A[irand(sh.n)] = -0.3 * urand();
            t->negative++;
        }
        for (k = 0; k < sh.n; k++) sum += sh.A[k];
        if (!(sum > 0.05)) {
            sh.A[0] += 1.0;
            sum += 1.0;
        }
        for (k = 0; k < sh.n; k++) sh.A[k] /= sum;
    }
    design(&sh, Te);
    by_phase = sh.source == 2;
    /* f_mode: the shaper (source 2: its phase) and jerk_source 2, 3 need it in range */
    {
        double ph_max = 0.0;
        for (k = 0; k < sh.n; k++) ph_max = fmax(ph_max, sh.phase[k]);
        f_lo = fmax(by_phase ? 1.01 * ph_max / (4000.0 * Te) : 0.0,
                    jerk_source > 1 ? 1.0 / (100.0 * Te) : 0.0);
        f_hi = jerk_source > 1 ? 1.0 / (2.0 * Te) : 1.0 / Te;
        if (by_phase && jerk_source == 1) /* delays around those at f_shaper (jerk_source 2,
                                               3: f_mode is the jerk times' already) */
            f_mode = sh.f * (0.7 + 0.6 * urand());
        if (!(f_mode >= f_lo && f_mode <= f_hi) || f_lo > f_hi) {
            t->skipped++;
            return;
        }
    }
    for (k = 0; k < sh.n; k++)
        if (fabs(sh.d[k] - floor(sh.d[k] + 0.5)) > 1e-6) {
            t->off_grid++;
            break;
        }
    if (by_phase) t->by_fmode++;
    whole = jerk_source > 1 || urand() < 0.5; /* f_mode changes only with whole steps */
    if (!whole) t->fractional++;
    t->cases++;
    /* the two instances */
    S = fmi2Instantiate("S", fmi2CoSimulation, DJL_INSTANTIATION_TOKEN, "file:///tmp", &cb,
                        fmi2False, fmi2False);
    R = fmi2Instantiate("R", fmi2CoSimulation, DJL_INSTANTIATION_TOKEN, "file:///tmp", &cb,
                        fmi2False, fmi2False);
    CHECK(S && R, "instantiate");
    if (!S || !R) return;
    fmi2SetupExperiment(S, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2SetupExperiment(R, fmi2False, 0.0, 0.0, fmi2False, 0.0);
    fmi2EnterInitializationMode(S);
    fmi2EnterInitializationMode(R);
    set_params(S, &p, t_start, jerk_source, f_mode);
    set_params(R, &p, t_start, jerk_source, f_mode);
    set_shaper(S, &sh);
    target = p.x0 + (p.n_segments == 0 ? p.distance : 0.0);
    for (k = 0; k < p.n_segments; k++) target += p.seg_distance[k];
    set_real(S, VR_TARGET, target);
    set_real(R, VR_TARGET, target);
    CHECK(fmi2ExitInitializationMode(R) == fmi2OK, "R exit: %s", last_message);
    if (fmi2ExitInitializationMode(S) != fmi2OK) {
        CHECK(0, "S exit (shaper %d source %d f %g zeta %g n %d): %s", sh.kind, sh.source, sh.f,
              sh.zeta, sh.n, last_message);
        fmi2FreeInstance(S);
        fmi2FreeInstance(R);
        return;
    }
    {
        fmi2ValueReference vm = VR_MOTION_TIME;
        double mS = 0.0, mR = 0.0, dmax = 0.0;
        fmi2GetReal(S, &vm, 1, &mS);
        fmi2GetReal(R, &vm, 1, &mR);
        for (k = 0; k < sh.n; k++)
            dmax = fmax(dmax, by_phase ? sh.phase[k] / (f_mode * Te) : sh.d[k]);
        CHECK(fabs(mS - (mR + dmax * Te)) <= 1e-9 * (mR + dmax * Te) + 1e-12 * Te,
              "motion_time %.17g, expected %.17g + %.17g", mS, mR, dmax * Te);
    }
    if (getenv("SHAPER_DEBUG") && atol(getenv("SHAPER_DEBUG")) == case_no)
        fprintf(stderr, "case: profile %d Te %g t_start %g v0 %g shaper %d n %d A %g %g %g d %.17g "
                "%.17g %.17g f %g zeta %g jerk_source %d whole %d\n", p.profile, Te, t_start,
                p.v0, sh.kind, sh.n, sh.amp[0], sh.amp[1], sh.amp[2], sh.d[0], sh.d[1], sh.d[2],
                sh.f, sh.zeta, jerk_source, whole);
    v_before = p.v0;
    rate_before = f_mode * Te;
    x_before = p.x0 - p.v0 * ceil(t_start / Te - 1e-9) * Te; /* p at grid 0 */
    scale = fabs(target - p.x0) + p.v_max * Te + fabs(p.x0) * 1e-12 + 1e-300;
    lvl = fmax(p.a_max, p.d_max);
    n_end = (long)(plan.k_end + ceil(t_start / Te) + 10);
    /* samples a commanded move may take: a stop from v_max, a move of 4 scale, the jerk times */
    {
        double stop = p.v_max / fmin(p.a_max, p.d_max) / Te, travel = 4.0 * scale / p.v_max / Te;
        double lim = 10.0 * (double)n_end + 8.0 * (stop + travel) + 20000.0;
        if (!(lim < (double)(MAXS - 10000))) {
            t->skipped++;
            t->cases--;
            fmi2FreeInstance(S);
            fmi2FreeInstance(R);
            return;
        }
        limit = (long)lim;
    }
    commands_left = urand() < 0.3 ? 0 : 1 + irand(5);
    save_at = whole && urand() < 0.6 ? irand((int)n_end + 1) : -1;
    {
        outs o = get(R);
        rx[0] = o.x;
        rv[0] = o.v;
        ra[0] = o.a;
        rj[0] = o.j;
        rdone[0] = (unsigned char)o.done;
        rate[0] = f_mode * Te;
        jmax = fabs(o.j);
        r_samples = 1;
    }
    for (step_no = 0;; step_no++) {
        action a;
        outs o;
        double s_next;
        memset(&a, 0, sizeof a);
        a.exec_val = a.stop_val = -1;
        if (replaying) {
            a = acts[n_replay];
        } else {
            /* releases of the previous command, a command, f_mode, the step */
            int busy_now = 1;
            if (ex) a.exec_val = ex = 0;
            if (st) a.stop_val = st = 0;
            if (r_samples > 0) busy_now = !rdone[r_samples - 1];
            if (commands_left > 0 && a.exec_val < 0 && a.stop_val < 0 &&
                urand() < (busy_now ? 3.0 / (double)(n_end + 10) : 0.05)) {
                commands_left--;
                commands++;
                t->commands++;
                if (urand() < 0.25) {
                    a.stop_val = st = 1;
                    last_stop = 1;
                    t->stops++;
                } else {
                    a.set_target = 1;
                    a.target = target + (urand() - 0.5) * 4.0 * scale;
                    if (urand() < 0.1) a.target = target;
                    target = a.target;
                    a.exec_val = ex = 1;
                    last_stop = 0;
                }
            }
            if ((by_phase || jerk_source > 1) && whole && step_no > 0 && urand() < 0.2) {
                double f = f_mode * (1.0 + (urand() - 0.5) * (urand() < 0.1 ? 0.5 : 0.02));
                if (f >= f_lo && f <= f_hi) {
                    a.set_f = 1;
                    a.f = f;
                    f_mode = f;
                    t->fchanges++;
                }
            }
            a.h = whole ? Te
                        : (urand() < 0.5 ? Te * (1.0 + irand(3)) : Te * (1 + irand(23)) / 8.0);
        }
        /* S's grid time after the step (steps of k/8 samples) */
        s_next = sS + floor(a.h / Te * 8.0 + 0.5) / 8.0;
        /* R first runs to S's point when an input changes there */
        if (!replaying && (a.exec_val >= 0 || a.stop_val >= 0 || a.set_f || a.set_target) &&
            sS > (double)nR + 1e-12) {
            double hr = tS - tR;
            CHECK(fmi2DoStep(R, tR, hr, fmi2True) == fmi2OK, "R step: %s", last_message);
            tR += hr;
        }
        apply(S, R, &a, !replaying);
        CHECK(fmi2DoStep(S, tS, a.h, fmi2True) == fmi2OK, "S step at %.17g: %s", tS, last_message);
        tS += a.h;
        sS = s_next;
        o = get(S);
        t->steps++;
        if (replaying) { /* the replay: the outputs recorded, bit for bit */
            CHECK(memcmp(&o.x, &rec[n_replay].x, 8) == 0 && memcmp(&o.v, &rec[n_replay].v, 8) == 0 &&
                      memcmp(&o.a, &rec[n_replay].a, 8) == 0 &&
                      memcmp(&o.j, &rec[n_replay].j, 8) == 0 && o.done == rec[n_replay].done,
                  "replay after restore differs at step %d: x %.17g vs %.17g", n_replay, o.x,
                  rec[n_replay].x);
            if (++n_replay == n_record) replaying = 0;
            continue;
        }
        /* R runs to the whole samples up to S's time; rate[k]: f_mode applied over [k, k+1) */
        while ((double)nR + 1.0 <= sS + 1e-12 && nR + 2 < MAXS) {
            /* whole steps: the same times as S's (jerk_source = 3 reads f_mode's rate of
             * change over them) */
            double hr = whole ? Te : ((double)nR + 1.0) * Te - tR;
            outs q;
            rate[nR] = f_mode * Te;
            CHECK(fmi2DoStep(R, tR, hr, fmi2True) == fmi2OK, "R step: %s", last_message);
            tR += hr;
            nR++;
            q = get(R);
            rx[nR] = q.x;
            rv[nR] = q.v;
            ra[nR] = q.a;
            rj[nR] = q.j;
            rdone[nR] = (unsigned char)q.done;
            rate[nR] = f_mode * Te;
            if (fabs(q.j) > jmax) jmax = fabs(q.j);
            r_samples = nR + 1;
        }
        if (getenv("SHAPER_DEBUG") && atol(getenv("SHAPER_DEBUG")) == case_no)
            fprintf(stderr, "s %g: exec %d stop %d tgt %d f %d | S x %.12g v %.6g a %.6g j %.6g d %d"
                    " | R[%ld] j %.6g done %d\n", sS, a.exec_val, a.stop_val, a.set_target,
                    a.set_f, o.x, o.v, o.a, o.j, o.done, nR, rj[nR], rdone[nR]);
        /* the checks at S's point */
        tol[0] = 1e-9 * (scale + fabs(o.x) * 1e-3);
        tol[1] = 1e-9 * p.v_max + 1e-12 * fabs(o.v);
        tol[2] = 1e-9 * lvl;
        tol[3] = 1e-9 * (jmax + lvl / Te);
        CHECK(isfinite(o.x) && isfinite(o.v) && isfinite(o.a) && isfinite(o.j),
              "output not finite at s = %g", sS);
        expected(&sh, sS, Te, by_phase, cv, alt, amb, &all_done);
        for (dj = 0; dj < 4; dj++) {
            double got = dj == 0 ? o.x : dj == 1 ? o.v : dj == 2 ? o.a : o.j, want = 0.0;
            CHECK(matches(&sh, cv, alt, amb, dj, got, tol[dj], &want),
                  "%s = %.17g at s = %.17g, expected %.17g [shaper %d source %d n %d "
                  "jerk_source %d]", dj == 0 ? "x" : dj == 1 ? "v" : dj == 2 ? "a" : "j", got,
                  sS, want, sh.kind, sh.source, sh.n, jerk_source);
        }
        if (sh.nonneg) {
            CHECK(fabs(o.v) <= p.v_max * (1.0 + 1e-9), "|v| = %.17g > v_max = %g", o.v, p.v_max);
            CHECK(fabs(o.a) <= lvl * (1.0 + 1e-9), "|a| = %.17g > %g", o.a, lvl);
            CHECK(fabs(o.j) <= jmax * (1.0 + 1e-9) + 1e-12 * lvl / Te,
                  "|j| = %.17g > the profile's largest %.17g", o.j, jmax);
        }
        CHECK(!o.done || all_done, "done at s = %.17g before every copy ended", sS);
        if (commands == 0 && !by_phase) /* the parametric move: done exactly at its end */
            CHECK(o.done == all_done, "done = %d at s = %.17g, every copy ended: %d", o.done, sS,
                  all_done);
        /* an FMU state: saved after this step, restored and replayed later */
        if (step_no == save_at) {
            CHECK(fmi2GetFMUstate(S, &saved) == fmi2OK, "get state: %s", last_message);
            n_record = 0;
        } else if (saved && n_record < 400) {
            acts[n_record] = a;
            rec[n_record] = o;
            n_record++;
            if (n_record == 1 + irand(300) || n_record == 400 || o.done) {
                size_t size = 0;
                fmi2Byte *buf;
                fmi2FMUstate back = NULL;
                CHECK(fmi2SerializedFMUstateSize(S, saved, &size) == fmi2OK, "size");
                /* a packed state holds the live entries of the shaper's rings */
                t->restores_mem += size > model_state_max_size() - DJL_SHAPER_RING *
                                                      (sizeof(djl_past_piece) +
                                                       sizeof(djl_phase_point));
                buf = (fmi2Byte *)malloc(size);
                CHECK(fmi2SerializeFMUstate(S, saved, buf, size) == fmi2OK, "serialize");
                CHECK(fmi2DeSerializeFMUstate(S, buf, size, &back) == fmi2OK,
                      "deserialize: %s", last_message);
                CHECK(fmi2SetFMUstate(S, back) == fmi2OK, "set state: %s", last_message);
                free(buf);
                fmi2FreeFMUstate(S, &back);
                fmi2FreeFMUstate(S, &saved);
                saved = NULL;
                t->restores++;
                replaying = 1;
                n_replay = 0;
                tS -= (double)n_record * Te; /* whole steps of Te */
                sS -= (double)n_record;
                continue;
            }
        }
        if (o.done && commands_left == 0 && !saved) {
            outs q = get(R);
            if (q.done && sS >= (double)nR - 1e-9 && q.v == 0.0) {
                /* at rest: S exactly where R is */
                CHECK(o.x == q.x && o.v == q.v && o.a == q.a && o.j == q.j,
                      "at rest: S x %.17g v %g a %g, R x %.17g v %g a %g", o.x, o.v, o.a, q.x,
                      q.v, q.a);
                if (!last_stop) /* the last command was not a stop: on the target */
                    CHECK(fabs(q.x - target) <= 1e-9 * scale,
                          "R rests at %.17g, target %.17g", q.x, target);
                break;
            }
            if (q.done && q.v != 0.0 && sS > (double)n_end + 10.0) break; /* ends moving */
        }
        if (sS > (double)limit || nR + 3 >= MAXS) {
            CHECK(0, "the motion did not end (s = %g, limit %ld, done %d)", sS, limit, o.done);
            break;
        }
    }
    if (saved) fmi2FreeFMUstate(S, &saved);
    fmi2FreeInstance(S);
    fmi2FreeInstance(R);
}

int main(int argc, char **argv)
{
    long cases = argc > 1 ? atol(argv[1]) : 200, i;
    tally t;
    memset(&t, 0, sizeof t);
    if (argc > 2) rng_state ^= strtoull(argv[2], NULL, 10) * 0x9E3779B97F4A7C15ULL;
    if (rng_state == 0) rng_state = 88172645463325252ULL;
    if (argc > 3) kmax = atol(argv[3]);
    for (i = 0; i < cases; i++) {
        case_no = i;
        run_case(&t);
    }
    printf("test_shaper: %ld motions (%ld parameter sets skipped), %ld steps of S; %ld custom "
           "shapers (%ld with a negative amplitude), %ld with delays off the grid, %ld timed by "
           "f_mode (%ld f_mode changes), %ld with fractional steps; %ld commands (%ld stops); "
           "%ld FMU states restored and replayed (%ld with entries in the shaper's memory)\n",
           t.cases, t.skipped, t.steps, t.custom, t.negative, t.off_grid, t.by_fmode, t.fchanges,
           t.fractional, t.commands, t.stops, t.restores, t.restores_mem);
    CHECK(t.restores < 100 || t.restores_mem > 0, "no state restored held shaper memory");
    printf("test_shaper: %d failures\n", failures);
    return failures != 0;
}
