/*
 * djl_shaper.c -- input shaping of a planned profile (docs/generator.md,
 * "Input shaping"): the shapers designed from their parameters
 * (djl_shaper_design: ZV, ZVD, EI, custom; timed for f_shaper or by the phase
 * of f_mode), the shaped sample (djl_shaper_eval: a weighted sum of copies of
 * the profile, each delayed, each a closed-form evaluation), and the memory a
 * commanded move needs for it (djl_shaper_memory: the pieces of the plans a
 * replan replaced that the delayed copies still read, and the phase of f_mode;
 * two fixed rings, pointer-free, in the FMU state).
 *
 * No allocation; every loop is bounded by DJL_MAX_SHAPER_IMPULSES, the pieces
 * of a plan, or DJL_SHAPER_RING (a binary search, or the rare rebase of the
 * phase).
 */
#include "djl_internal.h"

#include <stdio.h>
#include <string.h>

#define SHAPER_PI 3.14159265358979323846
#define SHAPER_LOG2E 1.44269504088896340736
/* Samples of the window a memory keeps before the time it is updated at: the longest
 * delay, and two samples for the roundings of its computation. */
#define SHAPER_WINDOW ((int64_t)DJL_MAX_SHAPER_DELAY_SAMPLES + 2)

static const char *const kind_names[] = {"none", "ZV", "ZVD", "EI", "custom"};

void djl_shaper_params_default(djl_shaper_params *sp)
{
    memset(sp, 0, sizeof *sp);
    sp->kind = DJL_SHAPER_NONE;
    sp->source = DJL_SHAPER_SOURCE_F_SHAPER;
    sp->f = 10.0;
    sp->zeta = 0.0;
    sp->n = 1;
}

/* ------------------------------------------------------------------------ */
/* design                                                                   */

/* e^x without libm: 2^(x log2 e). */
static double shaper_exp(double x) { return djl_exp2(x * SHAPER_LOG2E); }

static djl_status check_frequency(djl_error *err, const char *name, double f, const char *what)
{
    if (!djl_isfinite(f) || !(f > 0.0) || f < DJL_MIN_MAGNITUDE)
        return set_error(err, DJL_E_PARAM, name, f,
                         "%s = %g Hz: must be a finite number > 0 (%s)", name, f, what);
    return DJL_OK;
}

djl_status djl_shaper_design(const djl_shaper_params *sp, double Te, double f_mode,
                             djl_shaper *out, djl_error *err)
{
    djl_shaper s;
    const double lim = (double)DJL_MAX_SHAPER_DELAY_SAMPLES;
    const char *kname;
    djl_status st;
    int i;
    memset(&s, 0, sizeof s);
    if (sp->kind < DJL_SHAPER_NONE || sp->kind > DJL_SHAPER_CUSTOM)
        return set_error(err, DJL_E_PARAM, "shaper", (double)sp->kind,
                         "shaper = %d: must be 0 (none), 1 (ZV), 2 (ZVD), 3 (EI) or 4 (custom)",
                         (int)sp->kind);
    if (sp->kind == DJL_SHAPER_NONE) {
        *out = s;
        return DJL_OK;
    }
    kname = kind_names[sp->kind];
    if (sp->source != DJL_SHAPER_SOURCE_F_SHAPER && sp->source != DJL_SHAPER_SOURCE_F_MODE)
        return set_error(err, DJL_E_PARAM, "shaper_source", (double)sp->source,
                         "shaper_source = %d: must be 1 (the impulses timed for f_shaper) or 2 "
                         "(timed by the phase of the input f_mode)", (int)sp->source);
    if (!(djl_isfinite(Te) && Te > 0.0))
        return set_error(err, DJL_E_PARAM, "Te", Te, "Te = %g s: must be a finite number > 0",
                         Te);
    s.source = sp->source;
    if (sp->source == DJL_SHAPER_SOURCE_F_MODE &&
        (st = check_frequency(err, "f_mode", f_mode, "the input f_mode times the shaper's "
                              "impulses, shaper_source = 2")) != DJL_OK)
        return st;
    if (sp->source == DJL_SHAPER_SOURCE_F_MODE && !(f_mode * Te <= DJL_SHAPER_MAX_PHASE_RATE))
        return set_error(err, DJL_E_PARAM, "f_mode", f_mode,
                         "f_mode = %g Hz: with shaper_source = 2 its period, %g s, must be at "
                         "least Te/2 = %g s (f_mode at most %g Hz)", f_mode, 1.0 / f_mode,
                         0.5 * Te, DJL_SHAPER_MAX_PHASE_RATE / Te);
    if (sp->kind != DJL_SHAPER_CUSTOM) {
        /* ZV, ZVD, EI for the mode (f, zeta): Td = 1 / (f sqrt(1 - zeta^2)),
         * K = exp(-zeta pi / sqrt(1 - zeta^2)) */
        double zeta = sp->zeta, sq, K, f, Td, V = DJL_SHAPER_EI_VTOL;
        if (!(djl_isfinite(zeta) && zeta >= 0.0 && zeta < 1.0))
            return set_error(err, DJL_E_PARAM, "zeta_shaper", zeta,
                             "zeta_shaper = %g: must be a finite number in [0, 1) (the damping "
                             "ratio of the mode the %s shaper is designed for)", zeta, kname);
        if (sp->source == DJL_SHAPER_SOURCE_F_SHAPER) {
            if ((st = check_frequency(err, "f_shaper", sp->f, "the frequency of the mode the "
                                      "shaper is designed for")) != DJL_OK)
                return st;
            f = sp->f;
        } else {
            f = f_mode;
        }
        sq = djl_sqrt(1.0 - zeta * zeta);
        K = shaper_exp(-zeta * SHAPER_PI / sq);
        Td = 1.0 / (f * sq);
        s.f_design = f;
        if (sp->kind == DJL_SHAPER_ZV) {
            s.n = 2;
            s.A[0] = 1.0 / (1.0 + K);
            s.A[1] = K / (1.0 + K);
            s.t[1] = 0.5 * Td;
            s.phase[1] = 0.5 / sq;
        } else if (sp->kind == DJL_SHAPER_ZVD) {
            double q = (1.0 + K) * (1.0 + K);
            s.n = 3;
            s.A[0] = 1.0 / q;
            s.A[1] = 2.0 * K / q;
            s.A[2] = K * K / q;
            s.t[1] = 0.5 * Td;
            s.t[2] = Td;
            s.phase[1] = 0.5 / sq;
            s.phase[2] = 1.0 / sq;
        } else { /* EI */
            double r0 = (1.0 + V) / 4.0, r1 = (1.0 - V) / 2.0 * K, r2 = (1.0 + V) / 4.0 * (K * K);
            double q = r0 + r1 + r2;
            s.n = 3;
            s.A[0] = r0 / q;
            s.A[1] = r1 / q;
            s.A[2] = r2 / q;
            s.t[1] = 0.5 * Td;
            s.t[2] = Td;
            s.phase[1] = 0.5 / sq;
            s.phase[2] = 1.0 / sq;
        }
        if (!(s.t[s.n - 1] / Te <= lim)) {
            double f_min = s.phase[s.n - 1] / (lim * Te);
            if (sp->source == DJL_SHAPER_SOURCE_F_SHAPER)
                return set_error(err, DJL_E_PARAM, "f_shaper", sp->f,
                                 "f_shaper = %g Hz: the %s shaper's last impulse (zeta_shaper = "
                                 "%g) is %g s late, %.0f samples of Te = %g s: more than the %d "
                                 "samples of the profile's past the FMU keeps (f_shaper must be "
                                 "at least %.17g Hz at this Te)", sp->f, kname, zeta,
                                 s.t[s.n - 1], s.t[s.n - 1] / Te, Te,
                                 DJL_MAX_SHAPER_DELAY_SAMPLES, f_min);
            return set_error(err, DJL_E_PARAM, "f_mode", f_mode,
                             "f_mode = %g Hz: with shaper_source = 2 the %s shaper's last impulse "
                             "(zeta_shaper = %g) is %g s late, %.0f samples of Te = %g s: more "
                             "than the %d samples of the profile's past the FMU keeps (f_mode "
                             "must be at least %.17g Hz at this Te)", f_mode, kname, zeta,
                             s.t[s.n - 1], s.t[s.n - 1] / Te, Te, DJL_MAX_SHAPER_DELAY_SAMPLES,
                             f_min);
        }
    } else {
        double sum = 0.0;
        if (sp->n < 1 || sp->n > DJL_MAX_SHAPER_IMPULSES)
            return set_error(err, DJL_E_PARAM, "shaper_n", (double)sp->n,
                             "shaper_n = %d: a custom shaper has 1..%d impulses", (int)sp->n,
                             DJL_MAX_SHAPER_IMPULSES);
        for (i = 0; i < sp->n; i++) {
            char name[40];
            double A = sp->amplitude[i], t = sp->delay[i];
            if (!djl_isfinite(A)) {
                snprintf(name, sizeof name, "shaper_amplitude[%d]", i + 1);
                return set_error(err, DJL_E_PARAM, name, A, "%s = %g: must be finite", name, A);
            }
            if (!(djl_isfinite(t) && t >= 0.0)) {
                snprintf(name, sizeof name, "shaper_delay[%d]", i + 1);
                return set_error(err, DJL_E_PARAM, name, t,
                                 "%s = %g s: must be a finite number >= 0 (an impulse cannot "
                                 "come before the profile it copies)", name, t);
            }
            if (!(t / Te <= lim)) {
                snprintf(name, sizeof name, "shaper_delay[%d]", i + 1);
                return set_error(err, DJL_E_PARAM, name, t,
                                 "%s = %g s is %.0f samples of Te = %g s: more than the %d "
                                 "samples of the profile's past the FMU keeps (at most %.17g s "
                                 "at this Te)", name, t, t / Te, Te,
                                 DJL_MAX_SHAPER_DELAY_SAMPLES, lim * Te);
            }
            sum += A;
        }
        if (!(djl_fabs(sum - 1.0) <= DJL_SHAPER_SUM_TOLERANCE))
            return set_error(err, DJL_E_PARAM, "shaper_amplitude", sum,
                             "shaper_amplitude[1..%d] sum to %.17g: the amplitudes of a shaper "
                             "must sum to 1 (within %g), or the output would not end where the "
                             "profile ends", (int)sp->n, sum, DJL_SHAPER_SUM_TOLERANCE);
        if (sp->source == DJL_SHAPER_SOURCE_F_MODE &&
            (st = check_frequency(err, "f_shaper", sp->f, "with shaper = 4 and shaper_source "
                                  "= 2, the frequency the delays shaper_delay are given "
                                  "for")) != DJL_OK)
            return st;
        s.n = sp->n;
        s.f_design = sp->source == DJL_SHAPER_SOURCE_F_MODE ? f_mode : 0.0;
        for (i = 0; i < sp->n; i++) {
            s.A[i] = sp->amplitude[i];
            if (sp->source == DJL_SHAPER_SOURCE_F_MODE) {
                s.phase[i] = sp->delay[i] * sp->f;
                s.t[i] = s.phase[i] / f_mode;
            } else {
                s.t[i] = sp->delay[i];
            }
            if (!(s.t[i] / Te <= lim))
                return set_error(err, DJL_E_PARAM, "f_mode", f_mode,
                                 "f_mode = %g Hz: with shaper_source = 2, shaper_delay[%d] = %g s "
                                 "at f_shaper = %g Hz becomes %g s, %.0f samples of Te = %g s: "
                                 "more than the %d samples of the profile's past the FMU keeps",
                                 f_mode, i + 1, sp->delay[i], sp->f, s.t[i], s.t[i] / Te, Te,
                                 DJL_MAX_SHAPER_DELAY_SAMPLES);
        }
    }
    for (i = 0; i < s.n; i++) {
        double r;
        s.d[i] = s.t[i] / Te;
        /* a delay within 1e-9 samples of a whole number of samples is that number: the
         * copy's samples are then the plan's samples (3 Te / Te is not always 3) */
        r = djl_floor(s.d[i] + 0.5);
        if (djl_fabs(s.d[i] - r) <= 1e-9) s.d[i] = r;
        if (s.t[i] > s.t_max) s.t_max = s.t[i];
        if (s.d[i] > s.d_max) s.d_max = s.d[i];
        if (s.phase[i] > s.phase_max) s.phase_max = s.phase[i];
        if (s.A[i] < 0.0 && !s.negative) s.negative = i + 1;
    }
    *out = s;
    return DJL_OK;
}

double djl_shaper_motion_time(const djl_plan *plan, const djl_shaper *sh)
{
    if (!sh || sh->n == 0) return djl_motion_time(plan);
    return djl_motion_time(plan) + sh->t_max;
}

/* ------------------------------------------------------------------------ */
/* the memory                                                               */

#define PAST(m, i) ((m)->past[((m)->past_first + (i)) % DJL_SHAPER_RING])
#define PHASE(m, i) ((m)->phase[((m)->phase_first + (i)) % DJL_SHAPER_RING])

void djl_shaper_memory_clear(djl_shaper_memory *mem)
{
    mem->n_past = mem->past_first = 0;
    mem->n_phase = mem->phase_first = 0;
}

static void past_push(djl_shaper_memory *m, int64_t k, const djl_sample *o)
{
    djl_past_piece *e;
    if (m->n_past > 0 && PAST(m, m->n_past - 1).k >= k) return; /* in order, once */
    if (m->n_past == DJL_SHAPER_RING) { /* cannot happen (one entry a sample of the window) */
        m->past_first = (m->past_first + 1) % DJL_SHAPER_RING;
        m->n_past--;
    }
    e = &PAST(m, m->n_past);
    e->k = k;
    e->x = o->x;
    e->v = o->v;
    e->a = o->a;
    e->j = o->j;
    m->n_past++;
}

int64_t djl_shaper_keep_past(djl_shaper_memory *mem, const djl_plan *old, double offset,
                             double o)
{
    int64_t O = (int64_t)(offset + o), w = O - SHAPER_WINDOW, off = (int64_t)offset, b0, token;
    int32_t i, cur = 0;
    djl_sample s;
    /* what lies wholly before the window is not read any more */
    while (mem->n_past >= 2 && PAST(mem, 1).k <= w) {
        mem->past_first = (mem->past_first + 1) % DJL_SHAPER_RING;
        mem->n_past--;
    }
    token = ((int64_t)mem->past_first << 32) | (int64_t)mem->n_past;
    /* the old plan holds from its origin on (the first plan: at every time) */
    b0 = mem->n_past > 0 && off > w ? off : w;
    if (b0 >= O) return token;
    djl_eval(old, (double)(b0 - off), &cur, &s);
    past_push(mem, b0, &s);
    for (i = 0; i < old->n_pieces; i++) {
        int64_t kg = old->piece[i].k + off;
        if (kg <= b0) continue;
        if (kg >= O) break;
        djl_eval(old, (double)(kg - off), &cur, &s);
        past_push(mem, kg, &s);
    }
    return token;
}

void djl_shaper_undo(djl_shaper_memory *mem, int64_t token)
{
    mem->past_first = (int32_t)(token >> 32);
    mem->n_past = (int32_t)(token & 0xffffffff);
}

void djl_shaper_phase_rate(djl_shaper_memory *m, double s, double rate)
{
    int64_t b = (int64_t)djl_ceil(s);
    djl_phase_point *last, *e;
    int32_t i;
    if (m->n_phase == 0) {
        m->phase_first = 0;
        e = &m->phase[0];
        e->k = b;
        e->P = 0.0;
        e->rate = rate;
        m->n_phase = 1;
        return;
    }
    last = &PHASE(m, m->n_phase - 1);
    if (last->rate == rate) return;
    if (last->k >= b) { /* a rate read for the same sample: the last one read counts */
        last->rate = rate;
        return;
    }
    while (m->n_phase >= 2 && PHASE(m, 1).k <= b - SHAPER_WINDOW - 1) {
        m->phase_first = (m->phase_first + 1) % DJL_SHAPER_RING;
        m->n_phase--;
    }
    /* no read goes back further than the window from the current sample: the first entry,
     * when it starts before b - SHAPER_WINDOW - 1, is moved there, its phase counted from
     * the next entry's (or 0), so that no phase difference spans more than the window
     * (issue 21: after a rest of 10^6 s the phase was the rate times 10^9 samples, and
     * differences of such phases lost their digits; with f_mode = DBL_MAX it overflowed
     * and the outputs became NaN) */
    if (PHASE(m, 0).k < b - SHAPER_WINDOW - 1) {
        djl_phase_point *f0 = &PHASE(m, 0);
        int64_t k0 = b - SHAPER_WINDOW - 1;
        f0->P = m->n_phase >= 2 ? PHASE(m, 1).P - f0->rate * (double)(PHASE(m, 1).k - k0) : 0.0;
        f0->k = k0;
    }
    if (m->n_phase == DJL_SHAPER_RING) { /* cannot happen (one entry a sample of the window) */
        m->phase_first = (m->phase_first + 1) % DJL_SHAPER_RING;
        m->n_phase--;
    }
    last = &PHASE(m, m->n_phase - 1);
    e = &PHASE(m, m->n_phase);
    e->k = b;
    e->P = last->P + last->rate * (double)(b - last->k);
    e->rate = rate;
    m->n_phase++;
    /* phases stay small, so that differences of them keep their digits: counted from the
     * first entry again once it passes 1024 periods (rare; bounded by the ring) */
    if (PHASE(m, 0).P > 1024.0) {
        double base = PHASE(m, 0).P;
        for (i = 0; i < m->n_phase; i++) PHASE(m, i).P -= base;
    }
}

/* The time (grid samples) at which the phase of f_mode was ph periods behind its value at
 * grid time s: the delayed copy of an impulse of phase ph reads the profile there. */
static double phase_back(const djl_shaper_memory *m, double s, double ph)
{
    int32_t lo = 0, hi = m->n_phase - 1, mid;
    const djl_phase_point *e;
    double target, tau, r;
    if (ph == 0.0) return s;
    /* the entry in force at s (the first if none) */
    while (lo < hi) {
        mid = (lo + hi + 1) / 2;
        if ((double)PHASE(m, mid).k <= s) lo = mid; else hi = mid - 1;
    }
    e = &PHASE(m, lo);
    target = e->P + e->rate * (s - (double)e->k) - ph;
    if (target >= e->P) { /* in the same entry: directly */
        tau = s - ph / e->rate;
    } else {
        hi = lo;
        lo = 0;
        while (lo < hi) { /* the last entry whose phase is at most the target (else the first) */
            mid = (lo + hi + 1) / 2;
            if (PHASE(m, mid).P <= target) lo = mid; else hi = mid - 1;
        }
        e = &PHASE(m, lo);
        tau = (double)e->k + (target - e->P) / e->rate;
    }
    /* within 1e-9 samples of a sample it is that sample, as a delay of shaper_source = 1 is
     * (f_mode Te = 1/16: delays of 8 samples, not 8 + 2e-15 read on the sample before) */
    r = djl_floor(tau + 0.5);
    if (djl_fabs(tau - r) <= 1e-9) tau = r;
    return tau;
}

/* The profile at grid time s from the past pieces (the last that starts at or before s;
 * left: before s; the first if none). */
static void past_eval(const djl_shaper_memory *m, double s, double Te, int left,
                      djl_sample *o)
{
    int32_t lo = 0, hi = m->n_past - 1, mid;
    const djl_past_piece *e;
    double tau;
    while (lo < hi) {
        mid = (lo + hi + 1) / 2;
        if (left ? (double)PAST(m, mid).k < s : (double)PAST(m, mid).k <= s)
            lo = mid;
        else
            hi = mid - 1;
    }
    e = &PAST(m, lo);
    tau = (s - (double)e->k) * Te;
    o->x = e->x + tau * (e->v + tau * (0.5 * e->a + tau * e->j / 6.0));
    o->v = e->v + tau * (e->a + 0.5 * tau * e->j);
    o->a = e->a + tau * e->j;
    o->j = e->j;
}

/* ------------------------------------------------------------------------ */
/* the shaped sample                                                        */

void djl_shaper_eval(const djl_shaper *sh, const djl_plan *plan, double u, double offset,
                     const djl_shaper_memory *mem, int left, int32_t *cursor,
                     int32_t cursors[DJL_MAX_SHAPER_IMPULSES], djl_sample *out)
{
    double x = 0.0, v = 0.0, a = 0.0, j = 0.0, x0 = 0.0, v0 = 0.0, a0 = 0.0, j0 = 0.0, ui;
    djl_sample c;
    const djl_sample *cp;
    int32_t i, done = 1, past = mem && mem->n_past > 0;
    int phase;
    if (left)
        djl_eval_left(plan, u, cursor, out);
    else
        djl_eval(plan, u, cursor, out);
    if (!sh || sh->n == 0) return;
    phase = sh->source == DJL_SHAPER_SOURCE_F_MODE && mem && mem->n_phase > 0;
    for (i = 0; i < sh->n; i++) {
        int before;
        ui = phase ? phase_back(mem, u + offset, sh->phase[i]) - offset : u - sh->d[i];
        before = past && (left ? ui <= 0.0 : ui < 0.0); /* before the plan: from the past */
        if (ui == u && !before) {
            cp = out; /* the plan at u itself: the values just evaluated */
        } else {
            if (before)
                past_eval(mem, ui + offset, plan->p.Te, left, &c);
            else if (left)
                djl_eval_left(plan, ui, &cursors[i], &c);
            else
                djl_eval(plan, ui, &cursors[i], &c);
            cp = &c;
        }
        if (!(left ? ui > (double)plan->k_end : ui >= (double)plan->k_end)) done = 0;
        if (i == 0) {
            x0 = cp->x;
            v0 = cp->v;
            a0 = cp->a;
            j0 = cp->j;
        } else {
            double A = sh->A[i];
            x += A * (cp->x - x0);
            v += A * (cp->v - v0);
            a += A * (cp->a - a0);
            j += A * (cp->j - j0);
        }
    }
    out->x = x0 + x;
    out->v = v0 + v;
    out->a = a0 + a;
    out->j = j0 + j;
    out->done = done;
}

/* ------------------------------------------------------------------------ */
/* the structure of a memory (an FMU state's)                               */

int djl_shaper_rate_ok(const djl_shaper *sh, double rate)
{
    return djl_isfinite(rate) && rate > 0.0 &&
           rate >= 0.999999 * sh->phase_max / (double)DJL_MAX_SHAPER_DELAY_SAMPLES &&
           rate <= DJL_SHAPER_MAX_PHASE_RATE * (1.0 + 1e-9);
}

const char *djl_shaper_memory_flaw(const djl_shaper_memory *m, const djl_shaper *sh)
{
    int32_t i;
    if (m->n_past < 0 || m->n_past > DJL_SHAPER_RING || m->past_first < 0 ||
        m->past_first >= DJL_SHAPER_RING || m->n_phase < 0 || m->n_phase > DJL_SHAPER_RING ||
        m->phase_first < 0 || m->phase_first >= DJL_SHAPER_RING)
        return "the shaper's memory counts are out of range";
    if (sh->n == 0 && (m->n_past != 0 || m->n_phase != 0))
        return "a memory of the shaper without a shaper";
    if (sh->source != DJL_SHAPER_SOURCE_F_MODE && m->n_phase != 0)
        return "a phase of f_mode with a shaper timed for f_shaper";
    if (sh->n > 0 && sh->source == DJL_SHAPER_SOURCE_F_MODE && m->n_phase == 0)
        return "no phase of f_mode with a shaper timed by it";
    for (i = 0; i < m->n_past; i++) {
        const djl_past_piece *e = &PAST(m, i);
        if (e->k < -DJL_MAX_PLAN_END || e->k > DJL_MAX_PLAN_END ||
            (i > 0 && e->k <= PAST(m, i - 1).k))
            return "the shaper's past pieces are not in order";
        if (!djl_isfinite(e->x) || !djl_isfinite(e->v) || !djl_isfinite(e->a) ||
            !djl_isfinite(e->j))
            return "a past piece of the shaper is not finite";
    }
    for (i = 0; i < m->n_phase; i++) {
        const djl_phase_point *e = &PHASE(m, i);
        if (e->k < -DJL_MAX_PLAN_END || e->k > DJL_MAX_PLAN_END ||
            (i > 0 && (e->k <= PHASE(m, i - 1).k || !(e->P >= PHASE(m, i - 1).P))))
            return "the phase of f_mode is not in order";
        /* the rate of an f_mode accepted: no delay beyond the memory's window */
        if (!djl_isfinite(e->P) || !djl_shaper_rate_ok(sh, e->rate))
            return "the phase of f_mode is not finite or its rate out of range";
    }
    return NULL;
}
