/*
 * fmu_model.c -- the model of the FMU, independent of the FMI version: its
 * variables (parameters through djl_vars.h's generated table, inputs with
 * their checks, outputs and calculated parameters), the plan made at the end
 * of initialisation, DoStep (the profile's time, commands, replans), and the
 * model's part of an FMU state's validation.  It reports through the base
 * (fmu_base.c: logging, errors, the variable table lookup) and knows nothing
 * of the instance above it (fmu_instance.c: life cycle, state machine, FMU
 * state); the generator itself is the core's (djl_core.h).
 */
#define DJL_VARS_PARAMETERS
#include "fmu_model.h"
#include "djl_math.h" /* floor, fmax, ... without libm (see there) */

#include <float.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* start values and parameters                                              */

void model_defaults(model_data *d)
{
    djl_params_default(&d->p);
    d->t_start = 0.0;
    d->start_time = 0.0;
    d->jerk_source = JERK_SOURCE_PARAMETERS;
    d->f_mode = 10.0;
    djl_shaper_params_default(&d->sp);
    djl_table_default(&d->table);
}

/* Where element index of parameter base (its value reference) is stored (djl_vars.h's
 * djl_param_table): a double for a Real, an int32_t for an Integer or an Enumeration;
 * NULL if it is not a parameter. */
static void *param_field(model_data *d, unsigned int base, unsigned int index)
{
    int i;
    for (i = 0; i < DJL_N_PARAMS; i++) {
        const djl_param_info *pi = &djl_param_table[i];
        size_t at;
        if (pi->vr != base) continue;
        if (index >= pi->size) return NULL;
        at = pi->offset + index * (pi->type == 'R' ? sizeof(double) : sizeof(int32_t));
        switch (pi->home) {
        case DJL_HOME_PARAMS: return (char *)&d->p + at;
        case DJL_HOME_T_START: return &d->t_start;
        case DJL_HOME_JERK_SOURCE: return &d->jerk_source;
        case DJL_HOME_SHAPER: return (char *)&d->sp + at;
        case DJL_HOME_TABLE: return (char *)&d->table + at;
        default: return NULL;
        }
    }
    return NULL;
}

/* The jerk time 1/f_mode in whole samples of Te (round to nearest), 0 if f_mode is
 * not a frequency or its period is outside [Te/2, DJL_MAX_FILTER_SAMPLES Te]. */
static int32_t jerk_samples(double f, double Te)
{
    double r;
    if (!(djl_isfinite(f) && f > 0.0 && djl_isfinite(Te) && Te > 0.0)) return 0;
    r = djl_floor(1.0 / (f * Te) + 0.5);
    if (!(r >= 1.0 && r <= (double)DJL_MAX_FILTER_SAMPLES)) return 0;
    return (int32_t)r;
}

static void evaluate(model_data *d)
{
    double u = (double)d->n - d->offset + d->phase;
    if (d->shaper.n == 0)
        djl_eval(&d->plan, u, &d->cursor, &d->out);
    else /* the shaped profile (docs/generator.md, "Input shaping") */
        djl_shaper_eval(&d->shaper, &d->plan, u, d->offset, &d->mem, 0, &d->cursor,
                        d->shaper_cursor, &d->out);
}

/* The shaper's copies trail the plan's end by this many samples (its largest delay; with
 * shaper_source = 2 at the f_mode now). */
static double shaper_tail(const model_data *d)
{
    if (d->shaper.n == 0) return 0.0;
    if (d->shaper.source == DJL_SHAPER_SOURCE_F_MODE)
        return d->shaper.phase_max / (d->f_mode * d->p.Te);
    return d->shaper.d_max;
}

/* The outputs done and busy: the move in progress has ended (shaper copies included) and
 * no command waits. */
static int program_done(const model_data *d)
{
    return d->out.done && d->queue_n == 0;
}

/* The output time_to_rest (s): until the move in progress ends, shaper copies included (a
 * move blending into the next: until it passes its target, where the next one starts). */
static double time_to_rest(const model_data *d)
{
    double u = (double)d->n - d->offset + d->phase, left;
    if (d->out.done) return 0.0;
    left = ((double)d->plan.k_end - u) * d->p.Te;
    if (d->plan.v_target == 0.0) left += shaper_tail(d) * d->p.Te;
    return left > 0.0 ? left : 0.0;
}

static void log_plan(const model_instance *m)
{
    const djl_plan *pl = &m->d.plan;
    int i;
    model_log(m, ST_OK, DJL_LOG_LOGEVENTS,
              "planned %s move: %d segment(s), %.17g m in %.17g s (%lld samples of Te = %g s), "
              "v_reached = %.17g m/s, a_reached = %.17g m/s2, d_reached = %.17g m/s2, "
              "jerk times %d/%d/%d/%d samples",
              djl_profile_names[pl->p.profile], (int)pl->n_segments, pl->x_target, djl_motion_time(pl),
              (long long)pl->k_end, pl->p.Te, pl->v_reached, pl->a_reached, pl->d_reached,
              (int)pl->N[0], (int)pl->N[1], (int)pl->N[2], (int)pl->N[3]);
    if (pl->p.profile == DJL_PROFILE_TABLE) {
        double jmax = 0.0;
        for (i = 0; i < pl->n_steps; i++)
            jmax = djl_fmax(jmax, djl_fabs(pl->piece[i].j));
        model_log(m, ST_OK, DJL_LOG_LOGEVENTS,
                  "table: %d pieces, %lld samples, largest |jerk| %.17g m/s3, ends at rest at "
                  "x0 + %.17g m; a commanded stop or move adds stages of the jerk times "
                  "%d/%d/%d/%d samples (T_F1..T_F4)", (int)pl->n_steps, (long long)pl->k_end,
                  jmax, pl->x_target, (int)pl->N[0], (int)pl->N[1], (int)pl->N[2],
                  (int)pl->N[3]);
    }
    for (i = 0; i < 4; i++) {
        int used = pl->p.profile == DJL_PROFILE_DJL || pl->p.profile == DJL_PROFILE_TABLE ||
                   (pl->p.profile == DJL_PROFILE_JL && i == 0);
        double T = pl->p.T_F[i], Ta = djl_applied_jerk_time(pl, i);
        if (used && djl_fabs(T - Ta) > 1e-9 * T)
            model_log(m, ST_WARNING, DJL_LOG_LOGSTATUSWARNING,
                      "T_F%d = %.17g s is not a whole number of samples of Te = %g s: the jerk "
                      "time applied is %d samples = %.17g s",
                      i + 1, T, pl->p.Te, (int)pl->N[i], Ta);
    }
    for (i = 0; i < pl->n_segments && pl->p.profile != DJL_PROFILE_TABLE; i++) {
        const djl_segment_plan *s = &pl->seg[i];
        model_log(m, ST_OK, DJL_LOG_LOGEVENTS,
                  "segment %d: start sample %lld, lead %lld, acceleration stage %lld samples at "
                  "%.17g m/s2, cruise %lld samples at %.17g m/s, deceleration stage %lld samples at "
                  "%.17g m/s2, filters %d/%d/%d/%d samples, rule %d",
                  i + 1, (long long)s->start, (long long)s->lead, (long long)s->n1, s->a_level,
                  (long long)s->k, s->v_peak, (long long)s->m, s->d_level, (int)s->N[0],
                  (int)s->N[1], (int)s->N[2], (int)s->N[3], (int)s->branch);
        if (s->merged_acc || s->merged_dec)
            model_log(m, ST_WARNING, DJL_LOG_LOGSTATUSWARNING,
                      "segment %d: %s stage too short for two jerk times (short_stage = 2, the "
                      "paper's rule): one jerk time used for it (%s)", i + 1,
                      s->merged_acc && s->merged_dec ? "acceleration and deceleration"
                      : s->merged_acc ? "acceleration" : "deceleration",
                      s->merged_acc && s->merged_dec ? "T_F2 := T_F1, T_F4 := T_F3"
                      : s->merged_acc ? "T_F2 := T_F1" : "T_F4 := T_F3");
        if (s->branch >= 2 && s->branch <= 5)
            model_log(m, ST_WARNING, DJL_LOG_LOGSTATUSWARNING,
                      "segment %d: no time-optimal profile lands exactly on a sample; landed with "
                      "%s", i + 1,
                      s->branch == 2 ? "two stages in the same direction"
                      : s->branch == 3 ? "a small velocity dip"
                      : s->branch == 4 ? "the cruise rounded to the nearest sample (another "
                                         "segment takes up the difference)"
                                       : "a stage ending between two samples");
    }
}

/* Unit in the last place of |x| (x finite): the spacing of doubles there. */
static double ulp(double x)
{
    x = djl_fabs(x);
    return djl_nextafter(x, DJL_HUGE_VAL) - x;
}

/* No output may overflow at any time the FMU can reach (n <= DJL_MAX_MOTION_SAMPLES):
 * refuse, naming the parameters, a set whose time, or position before the start (at v0)
 * or after the end (at the end velocity), would exceed DJL_MAX_POSITION.  During the
 * motion the plan's own bounds hold (djl_validate). */
static model_status check_range(model_instance *m, const char *fn, double off)
{
    const model_data *d = &m->d;
    const djl_plan *pl = &d->plan;
    double H = (double)DJL_MAX_MOTION_SAMPLES, Te = d->p.Te, before, after, x;
    if (!(Te * H <= DJL_MAX_POSITION))
        return model_fail(m, "%s: invalid parameter Te = %g s: the FMU's horizon of %g samples "
                          "would last beyond %g s", fn, Te, H, DJL_MAX_POSITION);
    if (!(djl_fabs(d->start_time) + Te * H <= DJL_MAX_POSITION))
        return model_fail(m, "%s: invalid start time %g s: the FMU's horizon of %g samples of "
                          "Te = %g s from it would end beyond %g s", fn, d->start_time, H, Te,
                          DJL_MAX_POSITION);
    before = off > 0.0 ? off : 0.0; /* samples before the motion starts */
    x = djl_fabs(d->p.x0) + djl_fabs(d->p.v0) * (before * Te);
    if (!(x <= DJL_MAX_POSITION))
        return model_fail(m, "%s: invalid parameters v0 = %g m/s with t_start = %g s (x0 = %g m): "
                          "the position before the motion starts, x0 + v0 (t - t_start), would "
                          "exceed %g m at the start time %g s", fn, d->p.v0, d->t_start, d->p.x0,
                          DJL_MAX_POSITION, d->start_time);
    after = H - off - (double)pl->k_end; /* samples the FMU may run after the motion */
    x = djl_fabs(pl->x_target) + (after > 0.0 ? djl_fabs(pl->v_target) * (after * Te) : 0.0);
    if (!(x <= DJL_MAX_POSITION)) {
        char name[40];
        if (d->p.n_segments == 0)
            snprintf(name, sizeof name, "v_e");
        else
            snprintf(name, sizeof name, "seg_v_end[%d]", (int)d->p.n_segments);
        return model_fail(m, "%s: invalid parameter %s = %g m/s: after the motion the position "
                          "grows at %g m/s from %g m and would pass %g m within the FMU's horizon "
                          "of %g samples of Te = %g s", fn, name, pl->v_target, pl->v_target,
                          pl->x_target, DJL_MAX_POSITION, H, Te);
    }
    return ST_OK;
}

/* The input shaper of the parameters (none: nothing is checked or logged), designed for the
 * plan just made; on failure log and go to Error (a bad f_mode, an input, is refused and
 * the instance stays usable). */
static model_status design_shaper(model_instance *m, const char *fn)
{
    model_data *d = &m->d;
    djl_error err;
    djl_shaper sh;
    if (djl_shaper_design(&d->sp, d->p.Te, d->f_mode, &sh, &err) != DJL_OK) {
        if (strcmp(err.param, "f_mode") == 0)
            return model_refuse(m, "%s: invalid input %s (set another f_mode)", fn, err.message);
        return model_fail(m, "%s: %s: %s", fn, djl_status_name(DJL_E_PARAM), err.message);
    }
    if (sh.n > 0 && !((double)d->plan.k_end + sh.d_max <= (double)DJL_MAX_MOTION_SAMPLES))
        return model_fail(m, "%s: invalid parameter shaper = %d: the motion of %lld samples and "
                          "the shaper's last impulse, %g samples later, exceed the %g samples a "
                          "motion may take", fn, (int)d->sp.kind, (long long)d->plan.k_end,
                          sh.d_max, (double)DJL_MAX_MOTION_SAMPLES);
    d->shaper = sh;
    memset(d->shaper_cursor, 0, sizeof d->shaper_cursor);
    djl_shaper_memory_clear(&d->mem);
    if (sh.n > 0 && sh.source == DJL_SHAPER_SOURCE_F_MODE)
        djl_shaper_phase_rate(&d->mem, (double)d->n + d->phase, d->f_mode * d->p.Te);
    return ST_OK;
}

static void log_shaper(const model_instance *m)
{
    const model_data *d = &m->d;
    const djl_shaper *sh = &d->shaper;
    char amp[256], del[256];
    size_t la = 0, ld = 0;
    int i;
    if (sh->n == 0) return;
    for (i = 0; i < sh->n; i++) {
        la += (size_t)snprintf(amp + la, sizeof amp - la, "%s%.17g", i ? ", " : "", sh->A[i]);
        if (la >= sizeof amp) la = sizeof amp - 1;
        ld += (size_t)snprintf(del + ld, sizeof del - ld, "%s%.17g", i ? ", " : "", sh->t[i]);
        if (ld >= sizeof del) ld = sizeof del - 1;
    }
    model_log(m, ST_OK, DJL_LOG_LOGEVENTS,
              "input shaper %s, %s: amplitudes [%s] at delays [%s] s%s; the output ends %.17g s "
              "after the planned motion (motion_time = %.17g s)",
              djl_shaper_names[d->sp.kind],
              sh->source == DJL_SHAPER_SOURCE_F_MODE ? "timed by the phase of f_mode (delays "
                                                       "at the f_mode of now)"
                                                     : "timed for f_shaper",
              amp, del, d->sp.kind == DJL_SHAPER_CUSTOM ? "" : " (the textbook design)",
              sh->t_max, djl_shaper_motion_time(&d->plan, sh));
    if (sh->negative)
        model_log(m, ST_WARNING, DJL_LOG_LOGSTATUSWARNING,
                  "shaper_amplitude[%d] = %.17g is negative: the shaped output still lands "
                  "exactly, but it may exceed v_max, a_max, d_max and the planned jerk (they "
                  "hold when every amplitude is >= 0)", (int)sh->negative,
                  sh->A[sh->negative - 1]);
}

/* Plan for the current parameters if needed; on failure log and go to Error. */
static model_status ensure_plan(model_instance *m, const char *fn)
{
    djl_error err;
    djl_status st;
    model_status st2;
    double off;
    int shifted;
    model_data *d = &m->d;
    if (d->planned) return ST_OK;
    djl_params q = d->p;
    if (djl_check_t_start(d->t_start, d->start_time, &err) != DJL_OK)
        return model_fail(m, "%s: %s", fn, err.message);
    if (d->jerk_source < JERK_SOURCE_PARAMETERS || d->jerk_source > JERK_SOURCE_F_MODE_AHEAD)
        return model_fail(m, "%s: invalid parameter jerk_source = %d: must be 1 (the jerk times "
                          "T_F1..T_F4), 2 (from the input f_mode) or 3 (from f_mode "
                          "extrapolated to each stage's start)", fn, (int)d->jerk_source);
    if (d->jerk_source >= JERK_SOURCE_F_MODE && d->p.profile == PROFILE_TABLE)
        return model_fail(m, "%s: invalid parameter jerk_source = %d with profile = 4 (table): "
                          "a table has its own jerk; the jerk times of a commanded stop or move "
                          "are T_F1..T_F4 (jerk_source must be 1)", fn, (int)d->jerk_source);
    if (d->jerk_source >= JERK_SOURCE_F_MODE) {
        int32_t Nf = jerk_samples(d->f_mode, d->p.Te);
        int i;
        if (d->p.profile == PROFILE_AL)
            return model_fail(m, "%s: invalid parameter jerk_source = %d with profile = 1 (AL): "
                              "an AL profile has no jerk time to take from f_mode; use profile "
                              "2 or 3", fn, (int)d->jerk_source);
        if (d->p.n_segments != 0 || d->p.v_e != 0.0)
            return model_fail(m, "%s: invalid parameter jerk_source = %d with n_segments = %d and "
                              "v_e = %g m/s: jerk times from f_mode are applied to single moves "
                              "ending at rest (n_segments = 0, v_e = 0)", fn,
                              (int)d->jerk_source, (int)d->p.n_segments, d->p.v_e);
        if (Nf == 0) /* an input, not a parameter: refused, the instance stays usable */
            return model_refuse(m, "%s: invalid input f_mode = %g Hz: with jerk_source = %d its "
                                "period must be between Te/2 and %d samples of Te = %g s (set "
                                "another f_mode)", fn, d->f_mode, (int)d->jerk_source,
                                DJL_MAX_FILTER_SAMPLES, d->p.Te);
        if (djl_validate(&q, &err) != DJL_OK)
            return model_fail(m, "%s: %s: %s", fn, djl_status_name(DJL_E_PARAM), err.message);
        q.profile = PROFILE_DJL;
        for (i = 0; i < 4; i++) q.T_F[i] = (double)Nf * q.Te;
    }
    if (q.profile == PROFILE_TABLE)
        st = djl_plan_table(&q, &d->table, &d->plan, &err);
    else
        st = djl_plan_motion(&q, &d->plan, &err);
    if (st != DJL_OK)
        return model_fail(m, "%s: %s: %s", fn, djl_status_name(st), err.message);
    /* The generator samples at start_time + n Te: the motion starts at the first of those
     * samples at or after t_start (the core's rule). */
    if (djl_start_offset(d->t_start, d->start_time, d->p.Te, &off, &shifted, &err) != DJL_OK)
        return model_fail(m, "%s: %s", fn, err.message);
    if (shifted)
        model_log(m, ST_WARNING, DJL_LOG_LOGSTATUSWARNING,
                  "t_start = %.17g s is not a sample of the generator (start time %.17g s + k Te, "
                  "Te = %.17g s): the motion starts at the next sample, %.17g s", d->t_start,
                  d->start_time, d->p.Te, d->start_time + off * d->p.Te);
    if ((st2 = check_range(m, fn, off)) != ST_OK) return st2;
    if ((st2 = design_shaper(m, fn)) != ST_OK) return st2;
    d->offset = off;
    d->cursor = 0;
    d->planned = 1;
    d->goal = 0;
    d->first.k_end = d->plan.k_end;
    memcpy(d->first.N, d->plan.N, sizeof d->first.N);
    d->first.v_reached = d->plan.v_reached;
    d->first.a_reached = d->plan.a_reached;
    d->first.d_reached = d->plan.d_reached;
    d->first.t_shaper = d->shaper.n > 0 ? d->shaper.t_max : 0.0;
    /* the move in progress is the parametric one: the parameters' values */
    d->mv.v_max = d->p.v_max;
    d->mv.a_max = d->p.a_max;
    d->mv.d_max = d->p.d_max;
    memcpy(d->mv.N, d->plan.N, sizeof d->mv.N);
    d->mv.profile = d->p.profile == PROFILE_TABLE ? PROFILE_DJL : d->p.profile;
    d->mv.sp = d->sp;
    d->env_v_max = d->p.v_max;
    d->env_a_max = d->p.a_max;
    d->env_d_max = d->p.d_max;
    d->cmd_error = 0;
    d->cmd_error_id = 0;
    d->command_aborted = 0;
    d->n_commands = 0;
    d->running_id = 0;
    d->queue_n = 0;
    d->queue_first = 0;
    memset(d->queue, 0, sizeof d->queue);
    evaluate(d);
    log_plan(m);
    log_shaper(m);
    return ST_OK;
}

/* An input, in any state a set is allowed in: a value that is not one is refused,
 * naming the input, and the previous value is kept. */
static model_status set_input(model_instance *m, const model_var *v, double value)
{
    model_data *d = &m->d;
    switch (v->base) {
    case VR_TARGET: /* any value: a command to a bad one is refused at its edge (cmd_error) */
        d->target = value;
        return ST_OK;
    case VR_F_MODE:
        if (!(djl_isfinite(value) && value > 0.0))
            return model_refuse(m, "set: invalid input f_mode = %g Hz: must be a finite frequency "
                                "> 0 (the previous value, %g Hz, is kept)", value, d->f_mode);
        if (d->jerk_source >= JERK_SOURCE_F_MODE && (d->state & MS_STEP) &&
            jerk_samples(value, d->p.Te) == 0)
            return model_refuse(m, "set: invalid input f_mode = %g Hz: its period, %g s, is "
                                "outside [Te/2, %d Te] at Te = %g s (the previous value, %g Hz, "
                                "is kept)", value, 1.0 / value, DJL_MAX_FILTER_SAMPLES, d->p.Te,
                                d->f_mode);
        if (d->planned && d->shaper.n > 0 && d->shaper.source == DJL_SHAPER_SOURCE_F_MODE &&
            !(value * d->p.Te <= DJL_SHAPER_MAX_PHASE_RATE))
            return model_refuse(m, "set: invalid input f_mode = %g Hz: with shaper_source = 2 its "
                                "period, %g s, must be at least Te/2 = %g s (f_mode at most %g "
                                "Hz; the previous value, %g Hz, is kept)", value, 1.0 / value,
                                0.5 * d->p.Te, DJL_SHAPER_MAX_PHASE_RATE / d->p.Te, d->f_mode);
        if (d->planned && d->shaper.n > 0 && d->shaper.source == DJL_SHAPER_SOURCE_F_MODE &&
            !(d->shaper.phase_max / (value * d->p.Te) <= (double)DJL_MAX_SHAPER_DELAY_SAMPLES))
            return model_refuse(m, "set: invalid input f_mode = %g Hz: with shaper_source = 2 the "
                                "shaper's last impulse would be %g samples of Te = %g s late, "
                                "more than the %d samples of the profile's past the FMU keeps "
                                "(f_mode must be at least %.17g Hz; the previous value, %g Hz, "
                                "is kept)", value, d->shaper.phase_max / (value * d->p.Te),
                                d->p.Te, DJL_MAX_SHAPER_DELAY_SAMPLES,
                                d->shaper.phase_max /
                                    ((double)DJL_MAX_SHAPER_DELAY_SAMPLES * d->p.Te),
                                d->f_mode);
        d->f_mode = value;
        return ST_OK;
    case VR_EXECUTE: d->execute = value != 0.0; return ST_OK;
    case VR_STOP: d->stop = value != 0.0; return ST_OK;
    default: break;
    }
    /* the per-command values: any value is kept, a command checks those it uses at its
     * edge (an invalid one: cmd_error, the command refused, the simulation goes on); an
     * integer beyond 32 bits (an FMI 3 Int64) is kept saturated, invalid all the same */
    if (v->type == 'I') value = value < -2147483648.0 ? -2147483648.0
                                : value > 2147483647.0 ? 2147483647.0 : value;
    switch (v->base) {
    case VR_CMD_V_MAX: d->cmd.v_max = value; return ST_OK;
    case VR_CMD_A_MAX: d->cmd.a_max = value; return ST_OK;
    case VR_CMD_D_MAX: d->cmd.d_max = value; return ST_OK;
    case VR_CMD_T_F: d->cmd.T_F[v->index] = value; return ST_OK;
    case VR_CMD_PROFILE: d->cmd.profile = (int32_t)value; return ST_OK;
    case VR_CMD_SHAPER: d->cmd.shaper = (int32_t)value; return ST_OK;
    case VR_CMD_SHAPER_N: d->cmd.shaper_n = (int32_t)value; return ST_OK;
    case VR_CMD_SHAPER_AMPLITUDE: d->cmd.amplitude[v->index] = value; return ST_OK;
    case VR_CMD_SHAPER_DELAY: d->cmd.delay[v->index] = value; return ST_OK;
    case VR_BUFFER_MODE: d->buffer_mode = (int32_t)value; return ST_OK;
    case VR_MIN_DURATION: d->min_duration = value; return ST_OK;
    default: return model_fail(m, "set: internal error, no storage for input %s", v->name);
    }
}

model_status model_set(model_instance *m, unsigned int vr, char type, double value)
{
    model_var v;
    model_data *d = &m->d;
    if (!model_lookup(vr, 0, &v))
        return model_fail(m, "set: unknown value reference %u", vr);
    if (v.type != type)
        return model_fail(m, "set: %s (value reference %u) is a %s, not a %s", v.name, vr,
                          model_type_name(v.type), model_type_name(type));
    if (v.causality == 'i') return set_input(m, &v, value);
    if (v.causality != 'p')
        return model_fail(m, "set: %s (value reference %u) is %s: it cannot be set", v.name, vr,
                          v.causality == 'o'   ? "an output"
                          : v.causality == 't' ? "the independent variable"
                                               : "a calculated parameter");
    if (!(d->state & (MS_INSTANTIATED | MS_INIT)))
        return model_fail(m, "set: %s is a fixed parameter: it can be set only before the end of "
                          "initialization (state is %s)", v.name, model_state_name(d->state));
    if (type == 'R' || type == 'I') {
        void *p = param_field(d, v.base, v.index);
        if (!p) return model_fail(m, "set: internal error, no storage for %s", v.name);
        if (type == 'R') {
            *(double *)p = value;
        } else {
            if (!(value >= -2147483648.0 && value <= 2147483647.0))
                return model_refuse(m, "set: %s = %.17g is out of the range of a 32-bit integer "
                                    "(nothing was changed)", v.name, value);
            *(int32_t *)p = (int32_t)value;
        }
    }
    d->planned = 0;
    return ST_OK;
}

int model_get_reals_fast(const model_instance *m, int mask, const unsigned int *vr, size_t n,
                         double *value)
{
    const model_data *d = &m->d;
    size_t i;
    if (!d->planned || !(d->state & mask)) return 0;
    for (i = 0; i < n; i++) {
        switch (vr[i]) {
        case VR_X: value[i] = d->out.x; break;
        case VR_V: value[i] = d->out.v; break;
        case VR_A: value[i] = d->out.a; break;
        case VR_J: value[i] = d->out.j; break;
        case VR_X_AL: value[i] = d->out.x_al; break;
        case VR_V_AL: value[i] = d->out.v_al; break;
        case VR_A_AL: value[i] = d->out.a_al; break;
        default: return 0;
        }
    }
    return 1;
}

model_status model_get(model_instance *m, unsigned int vr, char type, double *value)
{
    model_var v;
    model_data *d = &m->d;
    /* Fast path of a master's per-step reads: the Real outputs of a planned instance (the
     * same values the general path below returns, without the table lookup). */
    if (type == 'R' && d->planned) {
        switch (vr) {
        case VR_X: *value = d->out.x; return ST_OK;
        case VR_V: *value = d->out.v; return ST_OK;
        case VR_A: *value = d->out.a; return ST_OK;
        case VR_J: *value = d->out.j; return ST_OK;
        case VR_X_AL: *value = d->out.x_al; return ST_OK;
        case VR_V_AL: *value = d->out.v_al; return ST_OK;
        case VR_A_AL: *value = d->out.a_al; return ST_OK;
        default: break;
        }
    }
    if (!model_lookup(vr, 0, &v))
        return model_fail(m, "get: unknown value reference %u", vr);
    if (v.type != type)
        return model_fail(m, "get: %s (value reference %u) is a %s, not a %s", v.name, vr,
                          model_type_name(v.type), model_type_name(type));
    if (v.causality == 't') {
        *value = d->t_now;
        return ST_OK;
    }
    if (v.causality == 'i') {
        switch (v.base) {
        case VR_TARGET: *value = d->target; break;
        case VR_F_MODE: *value = d->f_mode; break;
        case VR_EXECUTE: *value = d->execute; break;
        case VR_STOP: *value = d->stop; break;
        case VR_CMD_V_MAX: *value = d->cmd.v_max; break;
        case VR_CMD_A_MAX: *value = d->cmd.a_max; break;
        case VR_CMD_D_MAX: *value = d->cmd.d_max; break;
        case VR_CMD_T_F: *value = d->cmd.T_F[v.index]; break;
        case VR_CMD_PROFILE: *value = (double)d->cmd.profile; break;
        case VR_CMD_SHAPER: *value = (double)d->cmd.shaper; break;
        case VR_CMD_SHAPER_N: *value = (double)d->cmd.shaper_n; break;
        case VR_CMD_SHAPER_AMPLITUDE: *value = d->cmd.amplitude[v.index]; break;
        case VR_CMD_SHAPER_DELAY: *value = d->cmd.delay[v.index]; break;
        case VR_BUFFER_MODE: *value = (double)d->buffer_mode; break;
        case VR_MIN_DURATION: *value = d->min_duration; break;
        default: return model_fail(m, "get: internal error, no value for input %s", v.name);
        }
        return ST_OK;
    }
    if (v.causality == 'p') {
        const void *p = param_field(d, v.base, v.index);
        if (!p) return model_fail(m, "get: internal error, no storage for %s", v.name);
        *value = type == 'R' ? *(const double *)p : (double)*(const int32_t *)p;
        return ST_OK;
    }
    if (d->state == MS_ERROR && !d->planned) {
        *value = 0.0;
        return ST_OK; /* diagnostics only */
    }
    if (ensure_plan(m, "get") != ST_OK) return ST_ERROR;
    switch (v.base) {
    case VR_X: *value = d->out.x; break;
    case VR_V: *value = d->out.v; break;
    case VR_A: *value = d->out.a; break;
    case VR_J: *value = d->out.j; break;
    case VR_DONE: *value = program_done(d) ? 1.0 : 0.0; break;
    case VR_X_AL: *value = d->out.x_al; break;
    case VR_V_AL: *value = d->out.v_al; break;
    case VR_A_AL: *value = d->out.a_al; break;
    case VR_SEGMENT: *value = (double)d->out.segment; break;
    case VR_BUSY: *value = program_done(d) ? 0.0 : 1.0; break;
    case VR_STAGE: *value = (double)d->out.stage; break;
    case VR_MOTION_TIME: /* with a shaper: until its last delayed copy ends (the shaper of
                            the parametric move: a calculated parameter is fixed) */
        *value = (double)d->first.k_end * d->p.Te;
        if (d->first.t_shaper != 0.0) *value += d->first.t_shaper;
        break;
    case VR_N_F1: *value = (double)d->first.N[0]; break;
    case VR_N_F2: *value = (double)d->first.N[1]; break;
    case VR_N_F3: *value = (double)d->first.N[2]; break;
    case VR_N_F4: *value = (double)d->first.N[3]; break;
    case VR_V_REACHED: *value = d->first.v_reached; break;
    case VR_A_REACHED: *value = d->first.a_reached; break;
    case VR_D_REACHED: *value = d->first.d_reached; break;
    case VR_CMD_ERROR: *value = d->cmd_error ? 1.0 : 0.0; break;
    case VR_CMD_ERROR_ID: *value = (double)d->cmd_error_id; break;
    case VR_ACTIVE:
        *value = d->running_id != 0 && d->running_id == d->n_commands && !d->out.done ? 1.0 : 0.0;
        break;
    case VR_COMMAND_ABORTED: *value = d->command_aborted ? 1.0 : 0.0; break;
    case VR_QUEUE_LENGTH: *value = (double)d->queue_n; break;
    case VR_TIME_TO_REST: *value = time_to_rest(d); break;
    default: return model_fail(m, "get: internal error, no value for %s", v.name);
    }
    return ST_OK;
}

/* ------------------------------------------------------------------------ */
/* initialisation                                                           */

model_status model_setup(model_instance *m, double start_time)
{
    if (!djl_isfinite(start_time))
        return model_fail(m, "start time %g s: must be finite", start_time);
    m->d.start_time = start_time;
    m->d.t_now = start_time;
    m->d.planned = 0;
    return ST_OK;
}

model_status model_start(model_instance *m)
{
    model_status st = ensure_plan(m, "ExitInitializationMode");
    if (st != ST_OK) return st;
    m->d.execute_seen = m->d.execute; /* edges are counted from here */
    m->d.stop_seen = m->d.stop;
    m->d.f_seen = m->d.f_mode; /* and f_mode's rate of change (jerk_source = 3) */
    m->d.t_seen = m->d.t_now;
    m->d.f_rate = 0.0;
    return ST_OK;
}

/* ------------------------------------------------------------------------ */
/* DoStep                                                                   */

/* Tolerance between a communication point and the FMU's own time: the rounding a master
 * may make computing it (t += h, or start + i h: a few units in the last place), or a
 * millionth of a sample, whichever is larger.  Anything beyond is a visible fraction of
 * a step, whatever the start time. */
static double time_tolerance(const model_data *d, double t)
{
    return djl_fmax(1e-6 * d->p.Te, 4.0 * ulp(djl_fmax(djl_fabs(t), djl_fabs(d->t_now))));
}

static const char *const replan_how[] = {"", "the stage in progress ended, then a new move",
                                         "a stop, then a new move from rest", "a stop"};

/* Book-keeping and logs of a replan made. */
static void replanned(model_instance *m, double t, const djl_goal *g,
                      const djl_replan_info *info, const char *why)
{
    model_data *d = &m->d;
    d->offset += (double)info->origin;
    d->cursor = 0;
    memset(d->shaper_cursor, 0, sizeof d->shaper_cursor);
    if (d->replans < INT64_MAX) d->replans++; /* a restored state may hold any count */
    if (d->plan.v_target != 0.0) /* a move blending into the next: it ends moving */
        model_log(m, ST_OK, DJL_LOG_LOGEVENTS,
                  "t = %.17g s: %s: replanned from sample %lld (%s; stage ending at sample "
                  "%lld, settled velocity %.17g m/s), jerk times %d/%d/%d/%d samples, passing "
                  "its target at %.17g m/s %.17g s after sample %lld", t, why,
                  (long long)info->b,
                  replan_how[info->how >= 1 && info->how <= 3 ? info->how : 0],
                  (long long)info->end_at, info->v_settled, (int)g->N[0], (int)g->N[1],
                  (int)g->N[2], (int)g->N[3], d->plan.v_target, djl_motion_time(&d->plan),
                  (long long)info->origin);
    else
        model_log(m, ST_OK, DJL_LOG_LOGEVENTS,
                  "t = %.17g s: %s: replanned from sample %lld (%s; stage ending at sample "
                  "%lld, settled velocity %.17g m/s), jerk times %d/%d/%d/%d samples, at rest "
                  "%.17g s after sample %lld", t, why, (long long)info->b,
                  replan_how[info->how >= 1 && info->how <= 3 ? info->how : 0],
                  (long long)info->end_at, info->v_settled, (int)g->N[0], (int)g->N[1],
                  (int)g->N[2], (int)g->N[3], djl_motion_time(&d->plan),
                  (long long)info->origin);
    if (info->clipped == 1)
        model_log(m, ST_WARNING, DJL_LOG_LOGSTATUSWARNING,
                  "t = %.17g s: %s: the jerk time of the stage that ends the current one was "
                  "changed so that the velocity settles within v_max = %g m/s", t, why,
                  d->p.v_max);
    else if (info->clipped == 2)
        model_log(m, ST_WARNING, DJL_LOG_LOGSTATUSWARNING,
                  "t = %.17g s: %s: the jerk time of the stage that ends the current one was "
                  "shortened so that the axis comes to rest without reversing", t, why);
}

/* With a shaper, before the plan is replaced by one starting at its sample floor(u): the
 * memory keeps what the delayed copies still read of it (undone if the replan fails). */
static int64_t keep_past(model_data *d, double u)
{
    return djl_shaper_keep_past(&d->mem, &d->plan, d->offset, djl_floor(u));
}

/* djl_replan of the current plan at u (its samples), towards g, in place; with a
 * shaper the memory keeps the past the delayed copies read (undone if nothing is
 * replaced: a failure, or a stop that keeps the move in progress). */
static djl_status replan_try(model_instance *m, double u, const djl_goal *g,
                             djl_replan_info *info, djl_error *err)
{
    model_data *d = &m->d;
    int64_t kept = d->shaper.n > 0 ? keep_past(d, u) : 0;
    djl_status st = djl_replan(&d->plan, u, g, &d->plan, &m->w.scratch, info, err);
    if ((st != DJL_OK || info->kept) && d->shaper.n > 0) djl_shaper_undo(&d->mem, kept);
    return st;
}

/* A command (an execute or stop edge) refused: the output cmd_error set with its code
 * (spec.CMD_ERRORS, docs/generator.md "Command errors"), the reason logged as a warning;
 * the move in progress and everything else untouched.  Returns ST_DISCARD, which the
 * caller takes for "refused, go on" (DoStep itself returns OK). */
static model_status command_refused(model_instance *m, int code, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static model_status command_refused(model_instance *m, int code, const char *fmt, ...)
{
    char buf[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    m->d.cmd_error = 1;
    m->d.cmd_error_id = code;
    model_log(m, ST_WARNING, DJL_LOG_LOGSTATUSWARNING, "%s: command refused (cmd_error = true, "
              "cmd_error_id = %d); the move in progress goes on unchanged", buf, code);
    return ST_DISCARD;
}

/* The plan replaced by djl_replan at u (samples of the current plan), towards g; *origin:
 * the sample of the current plan the new one starts at (0: a stop kept the move), *kept:
 * a stop kept the move.  No motion: the command refused (ST_DISCARD, cmd_error). */
static model_status replan_at(model_instance *m, double t, double u, const djl_goal *g,
                              const char *why, int64_t *origin, int *kept)
{
    model_data *d = &m->d;
    djl_replan_info info;
    djl_error err;
    djl_status st = replan_try(m, u, g, &info, &err);
    if (st != DJL_OK)
        return command_refused(m, CMD_ERR_NO_MOTION, "DoStep at t = %.17g s: %s to target = "
                               "%.17g m: %s: %s", t, why, g->target, djl_status_name(st),
                               err.message);
    *origin = info.origin;
    *kept = info.kept;
    if (info.kept) {
        model_log(m, ST_OK, DJL_LOG_LOGEVENTS,
                  "t = %.17g s: stop: with the jerk times %d/%d/%d/%d samples it would rest "
                  "past where the move in progress rests (at %.17g s): the move is kept", t,
                  (int)g->N[0], (int)g->N[1], (int)g->N[2], (int)g->N[3],
                  d->start_time + (d->offset + (double)d->plan.k_end) * d->p.Te);
        return ST_OK;
    }
    replanned(m, t, g, &info, why);
    return ST_OK;
}

/* A command with jerk times from f_mode (jerk_source 2, 3): f_mode's jerk times g->N if
 * the axis then neither stops and comes back nor (a stop) rests past the move's target;
 * else the jerk times the plan in progress has, on the same terms; else (the target
 * needs a stop first whatever the jerk times) those of the plan in progress, without
 * the terms.  Landing wins over the rule (docs/generator.md, "Commanded moves"). */
static model_status command_from_f_mode(model_instance *m, double t, double u, djl_goal *g,
                                        const char *why, int64_t *origin, int *kept)
{
    model_data *d = &m->d;
    djl_replan_info info;
    djl_error err;
    djl_status st;
    int i, same = 1;
    g->no_stop_first = 1;
    st = replan_try(m, u, g, &info, &err);
    if (st == DJL_OK) {
        *origin = info.origin;
        replanned(m, t, g, &info, why);
        return ST_OK;
    }
    if (st != DJL_E_INFEASIBLE)
        return command_refused(m, CMD_ERR_NO_MOTION, "DoStep at t = %.17g s: %s to target = "
                               "%.17g m: %s: %s", t, why, g->target, djl_status_name(st),
                               err.message);
    for (i = 0; i < 4; i++) same &= g->N[i] == d->plan.N[i] || d->plan.N[i] <= 0;
    if (!same) {
        model_log(m, ST_OK, DJL_LOG_LOGEVENTS,
                  "t = %.17g s: %s: f_mode = %g Hz: the stages keep their planned jerk times "
                  "%d/%d/%d/%d samples (%s)", t, why, d->f_mode, (int)d->plan.N[0],
                  (int)d->plan.N[1], (int)d->plan.N[2], (int)d->plan.N[3], err.message);
        for (i = 0; i < 4; i++)
            if (d->plan.N[i] > 0) g->N[i] = d->plan.N[i];
        st = replan_try(m, u, g, &info, &err);
        if (st == DJL_OK) {
            *origin = info.origin;
            replanned(m, t, g, &info, why);
            return ST_OK;
        }
        if (st != DJL_E_INFEASIBLE)
            return command_refused(m, CMD_ERR_NO_MOTION, "DoStep at t = %.17g s: %s to target "
                                   "= %.17g m: %s: %s", t, why, g->target,
                                   djl_status_name(st), err.message);
    }
    g->no_stop_first = 0;
    return replan_at(m, t, u, g, why, origin, kept);
}

/* A stop while the move in progress only slows down to rest (no step ahead but
 * stages 3 and 4, ending at rest): the move is kept if it rests no later than the
 * stop would (the stop ends the deceleration at once, with a ramp that may not end
 * before stage 3's, and can rest past the move's target).  1 if kept. */
static int stop_kept(model_instance *m, double t, double u0, djl_goal *g)
{
    model_data *d = &m->d;
    const djl_plan *pl = &d->plan;
    djl_replan_info info;
    djl_error err;
    double b = djl_floor(u0) + 1.0;
    int i, ahead = 0;
    if (pl->v_target != 0.0 || (double)pl->k_end <= b) return 0;
    for (i = 0; i < pl->n_steps; i++) {
        const djl_step *st = &pl->step[i];
        if ((double)st->tau >= b) {
            if (st->stage != 3 && st->stage != 4) return 0;
            ahead = 1;
        }
    }
    if (!ahead) return 0;
    g->kind = DJL_GOAL_STOP;
    /* the stop, planned aside (a stop uses no work space of its own) */
    if (djl_replan(pl, u0, g, &m->w.scratch, &m->w.scratch, &info, &err) != DJL_OK) return 0;
    if ((double)m->w.scratch.k_end + (double)info.origin < (double)pl->k_end) return 0;
    model_log(m, ST_OK, DJL_LOG_LOGEVENTS,
              "t = %.17g s: stop: the move in progress already slows down to rest, and no "
              "later than a stop would (at %.17g s): it is kept", t,
              d->start_time + (d->offset + (double)pl->k_end) * d->p.Te);
    return 1;
}

/* jerk_source = 3: each stage's jerk time from f_mode extrapolated (at its rate of
 * change over the last step) to the next sample at which the plan starts that stage;
 * f_mode itself for a stage the plan does not start again. */
static void predicted_jerk_times(const model_data *d, double u0, int32_t N[4])
{
    const djl_plan *pl = &d->plan;
    double next[4] = {-1.0, -1.0, -1.0, -1.0}, b = djl_floor(u0) + 1.0;
    int i;
    for (i = 0; i < pl->n_steps; i++) {
        const djl_step *st = &pl->step[i];
        double tau = (double)st->tau;
        if (st->stage >= 1 && st->stage <= 4 && tau >= b &&
            (next[st->stage - 1] < 0.0 || tau < next[st->stage - 1]))
            next[st->stage - 1] = tau;
    }
    for (i = 0; i < 4; i++) {
        double f = next[i] < 0.0 ? d->f_mode
                                 : d->f_mode + d->f_rate * ((next[i] - u0) * d->p.Te);
        int32_t n = jerk_samples(f, d->p.Te);
        if (n > 0) N[i] = n; /* else f_mode's own (an extrapolation out of range) */
    }
}

/* ------------------------------------------------------------------------ */
/* per-command values (issue 34, docs/generator.md "Per-command values")    */

/* The values a command (an execute or stop edge) runs with, its inputs resolved. */
typedef struct {
    double v_max, a_max, d_max;
    int32_t N[4];
    int32_t profile;
    int switch_shaper;        /* an execute with another shaper than the one in force */
    djl_shaper_params sp;     /* its shaper's design (an execute) */
    djl_shaper sh;            /* designed, when switch_shaper */
} command_values;

/* A jerk time T (s) in samples of Te, round(T/Te) as the planner takes it; 0 if it is not
 * one the FMU takes (not finite, <= 0, or outside 1..DJL_MAX_FILTER_SAMPLES samples). */
static int32_t jerk_time_samples(double T, double Te)
{
    double r;
    if (!(djl_isfinite(T) && T > 0.0)) return 0;
    r = djl_floor(T / Te + 0.5);
    if (!(r >= 1.0 && r <= (double)DJL_MAX_FILTER_SAMPLES)) return 0;
    return (int32_t)r;
}

static int same_shaper_params(const djl_shaper_params *a, const djl_shaper_params *b)
{
    return a->kind == b->kind && a->source == b->source &&
           memcmp(&a->f, &b->f, sizeof a->f) == 0 && memcmp(&a->zeta, &b->zeta, sizeof a->zeta) == 0 &&
           a->n == b->n && memcmp(a->amplitude, b->amplitude, sizeof a->amplitude) == 0 &&
           memcmp(a->delay, b->delay, sizeof a->delay) == 0;
}

/* The values of a command at t (stop: a stop edge, else an execute edge), Nf the jerk
 * times of f_mode (jerk_source 2, 3): ST_OK, or refused (ST_DISCARD, cmd_error set and
 * logged, naming the input and its value).  Nothing else changes. */
static model_status command_values_of(model_instance *m, double t, int stop, const int32_t Nf[4],
                                      const model_cmd_inputs *c, double target, int from_rest,
                                      command_values *cv)
{
    const model_data *d = &m->d;
    const char *what = stop ? "stop" : "execute";
    static const char *const lim_name[3] = {"cmd_v_max", "cmd_a_max", "cmd_d_max"};
    static const char *const lim_unit[3] = {"m/s", "m/s2", "m/s2"};
    double lim[3], Te = d->p.Te;
    int i, any_T = 0;
    memset(cv, 0, sizeof *cv);
    if (!stop && !(djl_isfinite(target) && djl_fabs(target) <= DJL_MAX_POSITION))
        return command_refused(m, CMD_ERR_TARGET, "DoStep at t = %.17g s: execute: invalid "
                               "target = %g m: must be finite and |target| <= %g m", t,
                               target, DJL_MAX_POSITION);
    lim[0] = c->v_max;
    lim[1] = c->a_max;
    lim[2] = c->d_max;
    for (i = 0; i < 3; i++)
        if (!(lim[i] == 0.0 || (djl_isfinite(lim[i]) && lim[i] > 0.0)))
            return command_refused(m, CMD_ERR_V_MAX + i, "DoStep at t = %.17g s: %s: invalid "
                                   "%s = %g %s: must be 0 (%s) or a finite number > 0", t, what,
                                   lim_name[i], lim[i], lim_unit[i],
                                   stop ? "the stopped move's" : "the parameter's");
    cv->v_max = c->v_max > 0.0 ? c->v_max : stop ? d->mv.v_max : d->p.v_max;
    cv->a_max = c->a_max > 0.0 ? c->a_max : stop ? d->mv.a_max : d->p.a_max;
    cv->d_max = c->d_max > 0.0 ? c->d_max : stop ? d->mv.d_max : d->p.d_max;
    if (c->profile < CMD_PROFILE_PARAMETER || c->profile > CMD_PROFILE_DJL)
        return command_refused(m, CMD_ERR_PROFILE, "DoStep at t = %.17g s: %s: invalid "
                               "cmd_profile = %d: must be 0 (%s), 1 (AL), 2 (JL) or 3 (DJL)", t,
                               what, (int)c->profile,
                               stop ? "the stopped move's" : "the parameter's");
    for (i = 0; i < 4; i++) {
        if (c->T_F[i] == 0.0) continue;
        any_T = 1;
        if (jerk_time_samples(c->T_F[i], Te) == 0)
            return command_refused(m, CMD_ERR_T_F, "DoStep at t = %.17g s: %s: invalid "
                                   "cmd_T_F[%d] = %g s: must be 0 (%s) or a jerk time of 1..%d "
                                   "samples of Te = %g s", t, what, i + 1, c->T_F[i],
                                   stop ? "the stopped move's" : "the parameter T_F",
                                   DJL_MAX_FILTER_SAMPLES, Te);
    }
    if (d->jerk_source >= JERK_SOURCE_F_MODE) {
        if (c->profile != CMD_PROFILE_PARAMETER || any_T)
            return command_refused(m, CMD_ERR_JERK_WITH_F_MODE, "DoStep at t = %.17g s: %s: "
                                   "cmd_profile = %d and cmd_T_F = [%g, %g, %g, %g] s: with "
                                   "jerk_source = %d the jerk times come from f_mode (leave "
                                   "them 0)", t, what, (int)c->profile, c->T_F[0], c->T_F[1],
                                   c->T_F[2], c->T_F[3], (int)d->jerk_source);
        memcpy(cv->N, Nf, sizeof cv->N);
        cv->profile = d->mv.profile;
    } else if (c->profile == CMD_PROFILE_PARAMETER && !any_T) {
        /* today's values: the parametric move's jerk times (a stop: the stopped move's) */
        memcpy(cv->N, stop ? d->mv.N : d->first.N, sizeof cv->N);
        cv->profile = stop ? d->mv.profile
                           : d->p.profile == PROFILE_TABLE ? PROFILE_DJL : d->p.profile;
    } else {
        int32_t base[4];
        cv->profile = c->profile != CMD_PROFILE_PARAMETER ? c->profile
                      : stop ? d->mv.profile
                      : d->p.profile == PROFILE_TABLE ? PROFILE_DJL : d->p.profile;
        for (i = 0; i < 4; i++) {
            /* the stage's own value: cmd_T_F[i], else the stopped move's, else T_Fi */
            base[i] = c->T_F[i] != 0.0 ? jerk_time_samples(c->T_F[i], Te)
                      : stop && d->mv.N[i] > 0 ? d->mv.N[i]
                      : jerk_time_samples(d->p.T_F[i], Te);
        }
        for (i = 0; i < 4; i++) {
            int src = cv->profile == PROFILE_JL ? 0 : i;
            cv->N[i] = cv->profile == PROFILE_AL ? 0 : base[src];
            if (cv->profile != PROFILE_AL && cv->N[i] == 0)
                return command_refused(m, CMD_ERR_T_F, "DoStep at t = %.17g s: %s: cmd_T_F[%d] "
                                       "= 0 takes the parameter T_F%d = %g s, which is not a "
                                       "jerk time of 1..%d samples of Te = %g s", t, what,
                                       src + 1, src + 1, d->p.T_F[src],
                                       DJL_MAX_FILTER_SAMPLES, Te);
        }
    }
    cv->sp = d->mv.sp;
    if (stop) return ST_OK; /* a stop keeps the move's shaper */
    if (c->shaper < CMD_SHAPER_PARAMETER || c->shaper > CMD_SHAPER_NONE)
        return command_refused(m, CMD_ERR_SHAPER, "DoStep at t = %.17g s: execute: invalid "
                               "cmd_shaper = %d: must be 0 (the parameter's), 1 (ZV), 2 (ZVD), "
                               "3 (EI), 4 (custom) or 5 (none)", t, (int)c->shaper);
    cv->sp = d->sp;
    if (c->shaper == CMD_SHAPER_NONE) {
        cv->sp.kind = DJL_SHAPER_NONE;
    } else if (c->shaper != CMD_SHAPER_PARAMETER) {
        cv->sp.kind = c->shaper;
        if (c->shaper == CMD_SHAPER_CUSTOM) {
            if (c->shaper_n < 0 || c->shaper_n > DJL_MAX_SHAPER_IMPULSES)
                return command_refused(m, CMD_ERR_SHAPER_N, "DoStep at t = %.17g s: execute: "
                                       "invalid cmd_shaper_n = %d: a custom shaper has 1..%d "
                                       "impulses (0: the parameters' custom design)", t,
                                       (int)c->shaper_n, DJL_MAX_SHAPER_IMPULSES);
            if (c->shaper_n > 0) {
                cv->sp.n = c->shaper_n;
                memcpy(cv->sp.amplitude, c->amplitude, sizeof cv->sp.amplitude);
                memcpy(cv->sp.delay, c->delay, sizeof cv->sp.delay);
            }
        }
    }
    if (!same_shaper_params(&cv->sp, &d->mv.sp)) {
        djl_error err;
        int from_cmd = c->shaper == CMD_SHAPER_CUSTOM && c->shaper_n > 0, code = CMD_ERR_SHAPER;
        if (djl_shaper_design(&cv->sp, Te, d->f_mode, &cv->sh, &err) != DJL_OK) {
            if (strncmp(err.param, "shaper_amplitude", 16) == 0)
                code = CMD_ERR_SHAPER_AMPLITUDE;
            else if (strncmp(err.param, "shaper_delay", 12) == 0 || strcmp(err.param, "f_mode") == 0)
                code = CMD_ERR_SHAPER_DELAY;
            else if (strcmp(err.param, "shaper_n") == 0)
                code = CMD_ERR_SHAPER_N;
            return command_refused(m, code, "DoStep at t = %.17g s: execute: invalid shaper "
                                   "of cmd_shaper = %d%s: %s%s", t, (int)c->shaper,
                                   from_cmd ? " (cmd_shaper_n, cmd_shaper_amplitude, "
                                              "cmd_shaper_delay)" : "",
                                   from_cmd && strncmp(err.message, "shaper_", 7) == 0 ? "cmd_" : "",
                                   err.message);
        }
        if (!from_rest && !(d->out.done && d->out.v == 0.0))
            return command_refused(m, CMD_ERR_SHAPER_WHILE_MOVING, "DoStep at t = %.17g s: "
                                   "execute: cmd_shaper = %d gives another shaper (%s) than the "
                                   "one in force (%s) while the output is not at rest (done = "
                                   "%d, v = %g m/s): another shaper starts from rest", t,
                                   (int)c->shaper, djl_shaper_names[cv->sp.kind],
                                   djl_shaper_names[d->mv.sp.kind], (int)d->out.done, d->out.v);
        cv->switch_shaper = 1;
    }
    return ST_OK;
}

/* A command done: its values become those of the move in progress (a stop: the shaper
 * stays), the limits' envelope grows, the error is cleared; an execute with another
 * shaper takes it from here (at rest: its copies of the time before read the rest). */
static void command_latched(model_instance *m, int stop, const command_values *cv, double grid)
{
    model_data *d = &m->d;
    d->mv.v_max = cv->v_max;
    d->mv.a_max = cv->a_max;
    d->mv.d_max = cv->d_max;
    memcpy(d->mv.N, cv->N, sizeof d->mv.N);
    d->mv.profile = cv->profile;
    d->env_v_max = djl_fmax(d->env_v_max, cv->v_max);
    d->env_a_max = djl_fmax(d->env_a_max, cv->a_max);
    d->env_d_max = djl_fmax(d->env_d_max, cv->d_max);
    d->cmd_error = 0;
    d->cmd_error_id = 0;
    if (stop || !cv->switch_shaper) return;
    d->mv.sp = cv->sp;
    d->shaper = cv->sh;
    memset(d->shaper_cursor, 0, sizeof d->shaper_cursor);
    djl_shaper_memory_clear(&d->mem);
    if (cv->sh.n > 0 && cv->sh.source == DJL_SHAPER_SOURCE_F_MODE)
        djl_shaper_phase_rate(&d->mem, grid, d->f_mode * d->p.Te);
    model_log(m, ST_OK, DJL_LOG_LOGEVENTS, "execute: input shaper %s from here",
              djl_shaper_names[cv->sp.kind]);
}

/* ------------------------------------------------------------------------ */
/* buffer modes, the queue and min_duration (issue 34, docs/generator.md "Buffer modes") */

/* An accepted stop or aborting execute: the waiting commands dropped; command_aborted set
 * when it discarded a move in progress or waiting commands. */
static void queue_discarded(model_instance *m, double t, int discards)
{
    model_data *d = &m->d;
    if (d->queue_n > 0)
        model_log(m, ST_OK, DJL_LOG_LOGEVENTS, "t = %.17g s: %d waiting command(s) discarded",
                  t, (int)d->queue_n);
    d->queue_n = 0;
    d->queue_first = 0;
    memset(d->queue, 0, sizeof d->queue);
    if (discards) d->command_aborted = 1;
}

/* Seconds from the plan time u to the end of a trial plan replanned at u (its origin
 * floor(u)), a shaper trailing it by t_sh s. */
static double trial_duration(const model_data *d, const djl_plan *pl, double u, double t_sh)
{
    return ((djl_floor(u) + (double)pl->k_end) - u) * d->p.Te + t_sh;
}

/* min_duration (s): g's velocity limit lowered, if need be, to the fastest (to 1e-9 of it,
 * bisection) with which the move replanned at u lasts at least min_d, a shaper trailing
 * it by t_sh s.  Trials only; g unchanged when no trial plans (the command's own replan
 * then says why), the move lasts long enough already, or it has no distance to stretch.
 * 0, or -1 when no velocity makes it last that long (the command is refused). */
static int apply_min_duration(model_instance *m, double t, double u, djl_goal *g, double t_sh,
                              double min_d)
{
    model_data *d = &m->d;
    djl_replan_info info;
    djl_error err;
    djl_goal q = *g;
    double lo, hi = g->v_max, dist;
    int i;
    if (!(min_d > 0.0)) return 0;
    if (djl_replan(&d->plan, u, &q, &m->w.trial, &m->w.scratch, &info, &err) != DJL_OK) return 0;
    if (trial_duration(d, &m->w.trial, u, t_sh) >= min_d) return 0;
    dist = djl_fabs(m->w.trial.x_target) + djl_fabs(m->w.trial.p.v0) * d->p.Te;
    if (dist == 0.0) return 0; /* at its target: nothing to stretch */
    lo = dist / min_d < hi ? dist / min_d : 0.5 * hi;
    for (i = 0; i < 64; i++) { /* a velocity slow enough (d / min_d from rest) */
        q.v_max = lo;
        if (!(lo >= DJL_MIN_MAGNITUDE)) return -1;
        if (djl_replan(&d->plan, u, &q, &m->w.trial, &m->w.scratch, &info, &err) == DJL_OK &&
            trial_duration(d, &m->w.trial, u, t_sh) >= min_d)
            break;
        lo *= 0.5;
    }
    if (i == 64) return -1;
    for (i = 0; i < 64 && hi - lo > 1e-9 * hi; i++) {
        double mid = 0.5 * (lo + hi);
        q.v_max = mid;
        if (djl_replan(&d->plan, u, &q, &m->w.trial, &m->w.scratch, &info, &err) == DJL_OK &&
            trial_duration(d, &m->w.trial, u, t_sh) >= min_d)
            lo = mid;
        else
            hi = mid;
    }
    model_log(m, ST_OK, DJL_LOG_LOGEVENTS, "t = %.17g s: min_duration = %g s: velocity limit "
              "%.17g m/s instead of %.17g m/s", t, min_d, lo, g->v_max);
    g->v_max = lo;
    return 0;
}

/* Whether the move of g replanned at u can end at its target moving at v (signed, m/s)
 * within g's limits without turning back, and the next move (values nv, to x2) then land
 * at rest from there within its own limits without turning back (it starts one sample
 * after the target is passed: the replan's first free sample). */
static int blend_ok(model_instance *m, double u, const djl_goal *g, double v,
                    const command_values *nv, double x2)
{
    model_data *d = &m->d;
    djl_plan *tr = &m->w.trial;
    djl_goal q = *g;
    djl_replan_info info;
    djl_error err;
    double sg = v > 0.0 ? 1.0 : -1.0, tol = 1e-9 * djl_fabs(v);
    int i;
    q.v_end = v;
    q.no_stop_first = 1;
    if (djl_replan(&d->plan, u, &q, tr, &m->w.scratch, &info, &err) != DJL_OK) return 0;
    for (i = 0; i < tr->n_pieces; i++)
        if (tr->piece[i].k > 0 && sg * tr->piece[i].v < -tol) return 0;
    if (!(sg * ((x2 - g->target) - v * d->p.Te) > 0.0)) return 0;
    /* the next move as it will be planned: replanned at the end of the trial, no stop */
    memset(&q, 0, sizeof q);
    q.kind = DJL_GOAL_TARGET;
    q.target = x2;
    memcpy(q.N, nv->N, sizeof q.N);
    q.v_max = nv->v_max;
    q.a_max = nv->a_max;
    q.d_max = nv->d_max;
    q.no_stop_first = 1;
    if (djl_replan(tr, (double)tr->k_end, &q, tr, &m->w.scratch, &info, &err) != DJL_OK)
        return 0;
    for (i = 0; i < tr->n_pieces; i++)
        if (sg * tr->piece[i].v < -tol) return 0;
    return 1;
}

/* The speed the move of g (replanned at u) passes its target at, blending into the next
 * (values nv, to x2): the lower of the two moves' velocity limits (vcap), or, when either
 * cannot pass it that fast, the highest speed both can (to 1e-6 of vcap, bisection);
 * signed.  0 (the next waits as buffered) when the two go opposite ways, the move is at
 * its target, or no speed is possible. */
static double blend_speed(model_instance *m, double u, const djl_goal *g, double vcap,
                          const command_values *nv, double x2)
{
    model_data *d = &m->d;
    djl_sample s;
    int32_t cur = 0;
    double sg, lo = 0.0, hi = vcap;
    int i;
    djl_eval(&d->plan, djl_floor(u), &cur, &s);
    sg = g->target > s.x ? 1.0 : g->target < s.x ? -1.0 : 0.0;
    if (sg == 0.0 || !(sg * (x2 - g->target) > 0.0) || !(vcap > 0.0)) return 0.0;
    if (blend_ok(m, u, g, sg * vcap, nv, x2)) return sg * vcap;
    for (i = 0; i < 48 && hi - lo > 1e-6 * vcap; i++) {
        double mid = 0.5 * (lo + hi);
        if (blend_ok(m, u, g, sg * mid, nv, x2))
            lo = mid;
        else
            hi = mid;
    }
    return lo >= DJL_MIN_MAGNITUDE ? sg * lo : 0.0;
}

/* The values of a waiting command, resolved without a word (a refusal is reported when
 * it starts): 1 if valid. */
static int queued_values(model_instance *m, const model_queued *q, const int32_t Nf[4],
                         command_values *cv)
{
    model_data *d = &m->d;
    int32_t e = d->cmd_error, id = d->cmd_error_id, w = m->category_on[DJL_LOG_LOGSTATUSWARNING];
    model_status st;
    m->category_on[DJL_LOG_LOGSTATUSWARNING] = 0;
    st = command_values_of(m, 0.0, 0, Nf, &q->cmd, q->target, 1, cv);
    m->category_on[DJL_LOG_LOGSTATUSWARNING] = w;
    d->cmd_error = e;
    d->cmd_error_id = id;
    return st == ST_OK;
}

/* A blend keeps the shaper: the next command's (nv) must be the one in force (sp), else it
 * waits as buffered (a shaper changes from rest).  1 if it may blend. */
static int blend_shaper_ok(model_instance *m, double t, const command_values *nv,
                           const djl_shaper_params *sp)
{
    if (same_shaper_params(&nv->sp, sp)) return 1;
    model_log(m, ST_OK, DJL_LOG_LOGEVENTS, "t = %.17g s: blending: the next command has another "
              "shaper (%s) than the move before it (%s): it waits as buffered (a shaper changes "
              "from rest)", t, djl_shaper_names[nv->sp.kind], djl_shaper_names[sp->kind]);
    return 0;
}

/* The move of an execute (values cv, to target) planned at u (plan time, t its time): the
 * velocity limit lowered for min_d, ending moving when the first waiting command blends
 * into it; latched as the move in progress.  *origin: the sample the new plan starts at. */
static model_status plan_command(model_instance *m, double t, double u, const command_values *cv,
                                 double target, double min_d, const int32_t Nf[4],
                                 const char *why, int64_t *origin)
{
    model_data *d = &m->d;
    djl_goal gc;
    model_status st;
    int kept = 0;
    memset(&gc, 0, sizeof gc);
    gc.kind = DJL_GOAL_TARGET;
    gc.target = target;
    memcpy(gc.N, cv->N, sizeof gc.N);
    gc.v_max = cv->v_max;
    gc.a_max = cv->a_max;
    gc.d_max = cv->d_max;
    if (apply_min_duration(m, t, u, &gc,
                           cv->switch_shaper ? (cv->sh.n > 0 ? cv->sh.t_max : 0.0)
                                             : shaper_tail(d) * d->p.Te,
                           min_d) != 0)
        return command_refused(m, CMD_ERR_MIN_DURATION, "DoStep at t = %.17g s: %s to target = "
                               "%.17g m: min_duration = %g s: no velocity makes the move last "
                               "that long within the FMU's horizon", t, why, target, min_d);
    if (d->queue_n > 0) {
        const model_queued *nq = &d->queue[d->queue_first];
        command_values nv;
        if (nq->buffer_mode == BUFFER_MODE_BLENDING && nq->min_duration == 0.0 &&
            queued_values(m, nq, Nf, &nv) &&
            blend_shaper_ok(m, t, &nv, cv->switch_shaper ? &cv->sp : &d->mv.sp))
            gc.v_end = blend_speed(m, u, &gc, djl_fmin(gc.v_max, nv.v_max), &nv, nq->target);
    }
    for (;;) {
        if (d->jerk_source >= JERK_SOURCE_F_MODE) {
            djl_goal gf = gc;
            st = command_from_f_mode(m, t, u, &gf, why, origin, &kept);
        } else {
            st = replan_at(m, t, u, &gc, why, origin, &kept);
        }
        if (st != ST_DISCARD || gc.v_end == 0.0) break;
        gc.v_end = 0.0; /* (a blend refused: the next command waits as buffered) */
    }
    if (st != ST_OK) return st;
    command_latched(m, 0, cv, d->offset + (u - djl_floor(u))); /* (the new plan's grid) */
    d->mv.v_max = gc.v_max;
    d->goal = DJL_GOAL_TARGET;
    d->goal_target = target;
    if (gc.v_end != 0.0)
        model_log(m, ST_OK, DJL_LOG_LOGEVENTS, "t = %.17g s: %s: passes target = %.17g m at "
                  "%.17g m/s, blending into the next command", t, why, target, gc.v_end);
    return ST_OK;
}

/* A blending command now first in the queue: the move in progress replanned to pass its
 * target at the blend's speed (left as it is when none: the command then waits as
 * buffered).  *origin as plan_command's. */
static void reblend(model_instance *m, double t, double u, const int32_t Nf[4], int64_t *origin)
{
    model_data *d = &m->d;
    const model_queued *nq = &d->queue[d->queue_first];
    command_values nv;
    djl_goal g;
    int32_t e = d->cmd_error, id = d->cmd_error_id;
    int kept = 0;
    model_status st;
    memset(&g, 0, sizeof g);
    if (d->goal == DJL_GOAL_TARGET)
        g.target = d->goal_target;
    else if (d->goal == 0 && d->p.n_segments == 0 && d->p.v_e == 0.0)
        g.target = d->p.x0 + d->p.distance;
    else
        return; /* a stop, or a parametric move that does not end at rest */
    if (d->plan.v_target != 0.0 || !(u < (double)d->plan.k_end)) return;
    if (nq->min_duration != 0.0) return; /* its duration counts from rest: buffered */
    if (!queued_values(m, nq, Nf, &nv) || !blend_shaper_ok(m, t, &nv, &d->mv.sp)) return;
    g.kind = DJL_GOAL_TARGET;
    if (d->jerk_source >= JERK_SOURCE_F_MODE)
        memcpy(g.N, Nf, sizeof g.N);
    else
        memcpy(g.N, d->mv.N, sizeof g.N);
    g.v_max = d->mv.v_max;
    g.a_max = d->mv.a_max;
    g.d_max = d->mv.d_max;
    g.keep_speed = 1;
    g.v_end = blend_speed(m, u, &g, djl_fmin(d->mv.v_max, nv.v_max), &nv, nq->target);
    if (g.v_end == 0.0) {
        model_log(m, ST_OK, DJL_LOG_LOGEVENTS, "t = %.17g s: blending: the move in progress "
                  "cannot pass its target towards %.17g m without stopping: the command waits "
                  "as buffered", t, nq->target);
        return;
    }
    if (d->jerk_source >= JERK_SOURCE_F_MODE)
        st = command_from_f_mode(m, t, u, &g, "blending", origin, &kept);
    else
        st = replan_at(m, t, u, &g, "blending", origin, &kept);
    if (st != ST_OK) { /* the move keeps its plan; the command waits as buffered */
        *origin = 0;
        d->cmd_error = e;
        d->cmd_error_id = id;
        return;
    }
    model_log(m, ST_OK, DJL_LOG_LOGEVENTS, "t = %.17g s: blending: the move in progress passes "
              "its target %.17g m at %.17g m/s", t, g.target, g.v_end);
}

/* An execute edge at t (plan time u0): its buffer_mode and min_duration checked, then
 * aborting (or nothing to wait for): planned now; buffered or blending: queued. */
static model_status execute_edge(model_instance *m, double t, double u0, const int32_t Nf[4],
                                 int64_t *origin)
{
    model_data *d = &m->d;
    int32_t mode = d->buffer_mode;
    int idle = d->queue_n == 0 && d->out.done && d->out.v == 0.0 && d->plan.v_target == 0.0;
    command_values cv;
    model_status st;
    *origin = 0;
    if (mode < BUFFER_MODE_ABORTING || mode > BUFFER_MODE_BLENDING)
        return command_refused(m, CMD_ERR_BUFFER_MODE, "DoStep at t = %.17g s: execute: invalid "
                               "buffer_mode = %d: must be 0 (aborting), 1 (buffered) or 2 "
                               "(blending)", t, (int)mode);
    if (!(d->min_duration == 0.0 || (djl_isfinite(d->min_duration) && d->min_duration > 0.0)))
        return command_refused(m, CMD_ERR_MIN_DURATION, "DoStep at t = %.17g s: execute: invalid "
                               "min_duration = %g s: must be 0 (none) or a finite duration > 0",
                               t, d->min_duration);
    if (mode == BUFFER_MODE_ABORTING || idle) {
        int discards = !idle && (d->queue_n > 0 || !d->out.done);
        int32_t kn = d->queue_n;
        st = command_values_of(m, t, 0, Nf, &d->cmd, d->target, 0, &cv);
        if (st != ST_OK) return st;
        /* planned as if no command waited (it replaces them; they stay if it is refused) */
        d->queue_n = 0;
        st = plan_command(m, t, u0, &cv, d->target, d->min_duration, Nf, "execute", origin);
        d->queue_n = kn;
        if (st != ST_OK) return st;
        queue_discarded(m, t, discards);
        if (!discards) d->command_aborted = 0;
        d->running_id = ++d->n_commands;
        return ST_OK;
    }
    if (d->queue_n >= MODEL_QUEUE_CAPACITY)
        return command_refused(m, CMD_ERR_QUEUE_FULL, "DoStep at t = %.17g s: execute: "
                               "buffer_mode = %d: the queue is full (%d commands wait)", t,
                               (int)mode, MODEL_QUEUE_CAPACITY);
    st = command_values_of(m, t, 0, Nf, &d->cmd, d->target, 1, &cv);
    if (st != ST_OK) return st;
    {
        model_queued *q = &d->queue[(d->queue_first + d->queue_n) % MODEL_QUEUE_CAPACITY];
        memset(q, 0, sizeof *q);
        q->cmd = d->cmd;
        q->target = d->target;
        q->min_duration = d->min_duration;
        q->buffer_mode = mode;
        q->id = ++d->n_commands;
        d->queue_n++;
    }
    d->cmd_error = 0;
    d->cmd_error_id = 0;
    d->command_aborted = 0;
    model_log(m, ST_OK, DJL_LOG_LOGEVENTS, "t = %.17g s: execute to target = %.17g m %s: %d "
              "command(s) waiting", t, d->target,
              mode == BUFFER_MODE_BUFFERED ? "buffered" : "blending", (int)d->queue_n);
    if (mode == BUFFER_MODE_BLENDING && d->queue_n == 1) reblend(m, t, u0, Nf, origin);
    return ST_OK;
}

/* The plan time (samples) at which the move in progress has ended for the command waiting
 * first: where it passes its target when it blends into it (the plan ends moving), else
 * the first whole sample at which it rests, shaper copies included. */
static double move_end(const model_data *d)
{
    double tail = shaper_tail(d);
    if (d->plan.v_target != 0.0) return (double)d->plan.k_end;
    return (double)d->plan.k_end + (tail > 0.0 ? -djl_floor(-tail) : 0.0);
}

/* The waiting commands whose turn comes within the step (plan times *u0 .. *u_end), each
 * at the end of the move before it (move_end), in order.  A refused one is dropped
 * (cmd_error) and the next one tried at the same time. */
static model_status serve_queue(model_instance *m, double *u0, double *u_end,
                                const int32_t Nf[4])
{
    model_data *d = &m->d;
    int guard;
    for (guard = 0; guard < MODEL_QUEUE_CAPACITY && d->queue_n > 0; guard++) {
        double at = move_end(d), t;
        model_queued q;
        command_values cv;
        int64_t origin = 0;
        model_status st;
        if (at < *u0) at = *u0;
        if (!(at < *u_end)) break;
        t = d->start_time + (d->offset + at) * d->p.Te;
        q = d->queue[d->queue_first];
        memset(&d->queue[d->queue_first], 0, sizeof q);
        d->queue_first = (d->queue_first + 1) % MODEL_QUEUE_CAPACITY;
        d->queue_n--;
        if (d->queue_n == 0) d->queue_first = 0;
        st = command_values_of(m, t, 0, Nf, &q.cmd, q.target, d->plan.v_target == 0.0, &cv);
        if (st == ST_OK && d->plan.v_target != 0.0 && cv.switch_shaper)
            st = command_refused(m, CMD_ERR_SHAPER_WHILE_MOVING, "t = %.17g s: blending: "
                                 "another shaper (%s) than the one of the move it blends from "
                                 "(%s): a shaper changes only from rest", t,
                                 djl_shaper_names[cv.sp.kind], djl_shaper_names[d->mv.sp.kind]);
        if (st == ST_OK) {
            /* (cmd_error tells of the last edge: a start accepted leaves it as it is) */
            int32_t e = d->cmd_error, id = d->cmd_error_id;
            st = plan_command(m, t, at, &cv, q.target, q.min_duration, Nf,
                              q.buffer_mode == BUFFER_MODE_BLENDING ? "blending" : "buffered",
                              &origin);
            if (st == ST_OK) {
                d->cmd_error = e;
                d->cmd_error_id = id;
            }
        }
        if (st == ST_OK) {
            d->running_id = q.id;
            *u0 -= (double)origin;
            *u_end -= (double)origin;
        } else if (st != ST_DISCARD) {
            return st;
        } else if (d->queue_n == 0 && d->plan.v_target != 0.0) {
            /* the move it blended from ends moving and nothing follows: it stops (with its
             * own values), rather than cruise on */
            djl_goal gs;
            int kept = 0;
            memset(&gs, 0, sizeof gs);
            gs.kind = DJL_GOAL_STOP;
            memcpy(gs.N, d->mv.N, sizeof gs.N);
            gs.v_max = d->mv.v_max;
            gs.a_max = d->mv.a_max;
            gs.d_max = d->mv.d_max;
            if (replan_at(m, t, at, &gs, "blending refused: stop", &origin, &kept) == ST_OK) {
                d->goal = DJL_GOAL_STOP;
                *u0 -= (double)origin;
                *u_end -= (double)origin;
            }
        }
    }
    return ST_OK;
}

/* The commands read at a DoStep (t, plan time u0, the step covering du samples):
 * edges of stop and execute, then with jerk_source = 2 the jerk times of the
 * stages that start within the step from f_mode. */
static model_status commands(model_instance *m, double t, double u0, double du)
{
    model_data *d = &m->d;
    int stop_edge = d->stop && !d->stop_seen, exec_edge = d->execute && !d->execute_seen;
    double u_end = u0 + du, from, at;
    djl_goal g;
    int i, it, now;
    int64_t kept;
    memset(&g, 0, sizeof g);
    if (d->jerk_source >= JERK_SOURCE_F_MODE) {
        int32_t Nf = jerk_samples(d->f_mode, d->p.Te);
        if (Nf == 0)
            return model_refuse(m, "DoStep at t = %.17g s: invalid input f_mode = %g Hz: with "
                                "jerk_source = %d its period must be between Te/2 and %d "
                                "samples of Te = %g s (nothing was done)", t, d->f_mode,
                                (int)d->jerk_source, DJL_MAX_FILTER_SAMPLES, d->p.Te);
        for (i = 0; i < 4; i++) g.N[i] = Nf;
        if (d->jerk_source == JERK_SOURCE_F_MODE_AHEAD) {
            /* f_mode's rate of change over the last step, then each stage's jerk time
             * from f_mode extrapolated to where the plan starts it */
            if (t > d->t_seen) {
                /* a change over a vanishing step (10^-310 s) overflows: a rate beyond the
                 * doubles is the largest one (its extrapolation is out of range either way,
                 * and the stages keep f_mode's own jerk time); a state holds finite values
                 * only (issue 21, third session: the FMU refused such a state it had
                 * saved) */
                double r = (d->f_mode - d->f_seen) / (t - d->t_seen);
                d->f_rate = djl_isfinite(r) ? r : r > 0.0 ? DBL_MAX : -DBL_MAX;
            }
            d->f_seen = d->f_mode;
            d->t_seen = t;
            predicted_jerk_times(d, u0, g.N);
        }
    } else {
        memcpy(g.N, d->mv.N, sizeof g.N);
    }
    if (stop_edge) {
        command_values cv;
        djl_goal gc = g;
        model_status st = command_values_of(m, t, 1, g.N, &d->cmd, d->target, 0, &cv);
        /* (a target that is not a position is kept out of the state's goal) */
        double goal_target = djl_isfinite(d->target) && djl_fabs(d->target) <= DJL_MAX_POSITION
                                 ? d->target : d->goal_target;
        int discards = d->queue_n > 0 || !d->out.done;
        memcpy(gc.N, cv.N, sizeof gc.N);
        gc.v_max = cv.v_max;
        gc.a_max = cv.a_max;
        gc.d_max = cv.d_max;
        if (st != ST_OK) {
            /* refused: cmd_error set; the edges are taken, nothing else changes */
        } else if (stop_kept(m, t, u0, &gc)) {
            d->goal = DJL_GOAL_STOP;
            d->goal_target = goal_target;
            d->cmd_error = 0;
            d->cmd_error_id = 0;
            queue_discarded(m, t, discards);
        } else {
            int64_t origin = 0;
            int kept = 0;
            gc.kind = DJL_GOAL_STOP;
            gc.target = d->target;
            if (d->jerk_source >= JERK_SOURCE_F_MODE)
                st = command_from_f_mode(m, t, u0, &gc, "stop", &origin, &kept);
            else
                st = replan_at(m, t, u0, &gc, "stop", &origin, &kept);
            if (st == ST_OK) {
                d->goal = gc.kind;
                d->goal_target = goal_target;
                if (kept) { /* a stop that keeps the move: the move's values stay */
                    d->cmd_error = 0;
                    d->cmd_error_id = 0;
                } else {
                    command_latched(m, 1, &cv, 0.0);
                }
                queue_discarded(m, t, discards);
                u0 -= (double)origin;
                u_end = u0 + du;
            } else if (st != ST_DISCARD) {
                return st;
            }
        }
    } else if (exec_edge) {
        int64_t origin = 0;
        model_status st = execute_edge(m, t, u0, g.N, &origin);
        if (st == ST_OK) {
            u0 -= (double)origin;
            u_end = u0 + du;
        } else if (st != ST_DISCARD) {
            return st;
        }
    }
    if (d->queue_n > 0) {
        model_status st = serve_queue(m, &u0, &u_end, g.N);
        if (st != ST_OK) return st;
    }
    d->stop_seen = d->stop;
    d->execute_seen = d->execute;
    if (d->jerk_source < JERK_SOURCE_F_MODE) return ST_OK;
    /* the move's limits (latched at its command) */
    g.v_max = d->mv.v_max;
    g.a_max = d->mv.a_max;
    g.d_max = d->mv.d_max;
    /* jerk times from f_mode: a stage that starts within the step with another jerk
     * time is replanned as it starts; while cruising or speeding up, the stages to
     * come are replanned at once (a stop or the landing then falls on the right
     * sample).  Each replan is at a later sample than the one before: at most a
     * few per step. */
    g.kind = d->goal == DJL_GOAL_STOP ? DJL_GOAL_STOP : DJL_GOAL_TARGET;
    g.target = d->goal == 0 ? d->p.x0 + d->p.distance : d->goal_target;
    g.v_end = g.kind == DJL_GOAL_TARGET ? d->plan.v_target : 0.0; /* a blend keeps its speed */
    g.no_stop_first = 1;
    g.keep_speed = 1;
    from = u0;
    now = u0 >= 0.0;
    for (it = 0; it < 8; it++) {
        djl_replan_info info;
        djl_error err;
        djl_status st;
        double o;
        if (!djl_jerk_times_due(&d->plan, from, u_end, g.N, now, &at)) break;
        kept = d->shaper.n > 0 ? keep_past(d, at) : 0;
        st = djl_replan(&d->plan, at, &g, &d->plan, &m->w.scratch, &info, &err);
        if (st != DJL_OK && d->shaper.n > 0) djl_shaper_undo(&d->mem, kept);
        if (st == DJL_E_INFEASIBLE) {
            /* the jerk time of f_mode no longer lands from here without stopping and
             * coming back: the stage keeps the one it was planned with */
            int k, starts = 0; /* a stage starts at the sample after at (else a replan
                                   ahead of it, at now, was only not made) */
            for (k = 0; k < d->plan.n_steps; k++)
                starts |= (double)d->plan.step[k].tau == djl_floor(at) + 1.0;
            if (starts)
                model_log(m, ST_OK, DJL_LOG_LOGEVENTS,
                          "t = %.17g s: f_mode = %g Hz: the stage starting at t = %.17g s "
                          "keeps its planned jerk time (%s)", t, d->f_mode,
                          d->start_time + (d->offset + djl_floor(at) + 1.0) * d->p.Te,
                          err.message);
            from = djl_floor(at) + 1.0; /* past the stage that keeps its jerk time */
            now = 0;
            continue;
        }
        if (st != DJL_OK)
            return model_refuse(m, "DoStep at t = %.17g s: f_mode: %s: %s (nothing was done)", t,
                                djl_status_name(st), err.message);
        replanned(m, t, &g, &info, "f_mode");
        o = djl_floor(at);
        u0 -= o;
        u_end -= o;
        from = 1.0; /* from b = origin + 1 on, the steps the replan placed are right */
        now = 0;
    }
    /* a move the jerk times of f_mode made end earlier within the step: its successor */
    if (d->queue_n > 0) return serve_queue(m, &u0, &u_end, g.N);
    return ST_OK;
}

model_status model_do_step(model_instance *m, double t, double h)
{
    model_data *d = &m->d;
    double r, k, phase, whole, t_end;
    int64_t n;
    if (!(djl_isfinite(h) && h > 0.0))
        return model_fail(m, "DoStep: communication step %g s: must be a finite number > 0", h);
    if (t != d->t_now && !(djl_isfinite(t) && djl_fabs(t - d->t_now) <= time_tolerance(d, t)))
        return model_fail(m, "DoStep: currentCommunicationPoint = %.17g s, but the FMU is at "
                          "%.17g s: a step must start where the previous one ended", t, d->t_now);
    t_end = t + h;
    if (!djl_isfinite(t_end))
        return model_fail(m, "DoStep: %.17g s + a step of %g s is not a finite time", t, h);
    /* The profile's time advances by h exactly: in whole samples when h is one (to a
     * millionth of a sample, as always), else by whole samples plus a phase. */
    if (h == m->w.step_h && d->p.Te == m->w.step_Te) { /* the same step as last time */
        whole = m->w.step_whole;
        phase = d->phase;
    } else if (r = h / d->p.Te, k = djl_floor(r + 0.5),
               k >= 1.0 && djl_fabs(r - k) <= 1e-6 + 1e-12 * k) {
        whole = k;
        phase = d->phase;
        m->w.step_h = h; /* remembered: a master's next step is usually the same */
        m->w.step_Te = d->p.Te;
        m->w.step_whole = k;
    } else {
        double f = d->phase + (r - djl_floor(r));
        whole = djl_floor(r) + djl_floor(f);
        phase = f - djl_floor(f);
        if (phase >= 1.0 - 1e-9) { /* rounding of fractions that add up to a sample */
            whole += 1.0;
            phase = 0.0;
        } else if (phase <= 1e-9) {
            phase = 0.0;
        }
    }
    if (!(whole + (double)d->n + phase <= (double)DJL_MAX_MOTION_SAMPLES))
        return model_fail(m, "DoStep: communication step %g s takes the FMU past %g samples of "
                          "Te = %g s", h, (double)DJL_MAX_MOTION_SAMPLES, d->p.Te);
    if (d->execute != d->execute_seen || d->stop != d->stop_seen || d->queue_n > 0 ||
        d->jerk_source >= JERK_SOURCE_F_MODE) {
        model_status st = commands(m, t, (double)d->n - d->offset + d->phase,
                                   whole + phase - d->phase);
        if (st != ST_OK) return st;
    }
    if (d->shaper.n > 0 && d->shaper.source == DJL_SHAPER_SOURCE_F_MODE)
        /* f_mode read now times the copies from the first sample at or after now */
        djl_shaper_phase_rate(&d->mem, (double)d->n + d->phase, d->f_mode * d->p.Te);
    n = d->n + (int64_t)whole;
    d->n = n;
    d->phase = phase;
    d->t_now = t_end;
    evaluate(d);
    return ST_OK;
}

/* ------------------------------------------------------------------------ */
/* the model's part of an FMU state's validation                            */

static int finite_all(const double *x, size_t n)
{
    size_t i;
    for (i = 0; i < n; i++)
        if (!djl_isfinite(x[i])) return 0;
    return 1;
}

static int same_params(const djl_params *a, const djl_params *b)
{
    return a->profile == b->profile && a->short_stage == b->short_stage &&
           memcmp(&a->Te, &b->Te, offsetof(djl_params, T_F) - offsetof(djl_params, Te)) == 0 &&
           memcmp(a->T_F, b->T_F, sizeof a->T_F) == 0 && a->n_segments == b->n_segments &&
           memcmp(a->seg_distance, b->seg_distance, sizeof a->seg_distance) == 0 &&
           memcmp(a->seg_v_end, b->seg_v_end, sizeof a->seg_v_end) == 0;
}

/* The same outputs, bit for bit (field by field: the struct has padding). */
static int same_sample(const djl_sample *a, const djl_sample *b)
{
    return memcmp(&a->x, &b->x, sizeof a->x) == 0 && memcmp(&a->v, &b->v, sizeof a->v) == 0 &&
           memcmp(&a->a, &b->a, sizeof a->a) == 0 && memcmp(&a->j, &b->j, sizeof a->j) == 0 &&
           memcmp(&a->x_al, &b->x_al, sizeof a->x_al) == 0 &&
           memcmp(&a->v_al, &b->v_al, sizeof a->v_al) == 0 &&
           memcmp(&a->a_al, &b->a_al, sizeof a->a_al) == 0 && a->done == b->done &&
           a->segment == b->segment && a->stage == b->stage;
}

/* A plan is one motion, and a replan reads all of it: the AL level at o from level0 and
 * the steps listed, the output at o from the pieces (djl_replan.c, gather).  So each
 * piece must continue the one before (x and v, to rounding), its AL level, acceleration
 * and jerk must be those of level0 and the steps (a_al = level0 + the steps at or before
 * k; a = level0 + each step times its ramp's progress at k; j = the ramps running over
 * the piece, A / (N Te) each), the last piece must cruise (a = j = 0: it runs for ever)
 * and no piece's velocity may peak above vlim between its ends (where a crosses 0).  The
 * AL profile's x_al and v_al are not continuous: a new motion after a replan starts its
 * AL profile at the output's velocity, and with jerk times that differ between stages
 * the two differ by A (N1 - N2) Te / 2.  Issue 21, FMI run 11: a state with level0
 * forged from 0 to 0.56 m/s2, its pieces untouched, passed every check of a value
 * against its limit; a stop replanned from it then ended a stage that was not running
 * and its output reached 1.013 v_max.  The tolerances are a billionth of what the plan
 * itself holds (its levels, steps, speeds and positions), never of a limit it does not
 * reach: rounding is far below it (the walks carry it over at most DJL_MAX_PIECES
 * pieces), and a forged change that small moves nothing by more than the outputs' own
 * rounding. */
const char *model_plan_inconsistency(const djl_plan *pl, double vlim)
{
    const double rel = 1e-9, tiny = 64.0 * 4.9406564584124654e-324, Te = pl->p.Te;
    double amag = djl_fabs(pl->level0), jmag = 0.0, vmag = 0.0, xmag = 0.0, sv, sx;
    int32_t i, q;
    for (q = 0; q < pl->n_steps; q++) {
        amag += djl_fabs(pl->step[q].A);
        if (pl->step[q].N > 0) jmag += djl_fabs(pl->step[q].A) / ((double)pl->step[q].N * Te);
    }
    for (i = 0; i < pl->n_pieces; i++) {
        const djl_piece *pc = &pl->piece[i];
        amag = djl_fmax(amag, djl_fmax(djl_fabs(pc->a), djl_fabs(pc->a_al)));
        jmag = djl_fmax(jmag, djl_fabs(pc->j));
        vmag = djl_fmax(vmag, djl_fabs(pc->v));
        xmag = djl_fmax(xmag, djl_fabs(pc->x));
    }
    sv = vmag;
    sx = xmag;
    for (i = 0; i < pl->n_pieces; i++) {
        const djl_piece *pc = &pl->piece[i];
        double k = (double)pc->k, level = pl->level0, a = pl->level0, j = 0.0;
        for (q = 0; q < pl->n_steps; q++) {
            const djl_step *st = &pl->step[q];
            double u = k - (double)st->tau;
            if (u < 0.0) continue;
            level += st->A;
            if (st->N == 0 || u >= (double)st->N) {
                a += st->A;
            } else {
                a += st->A * (u / (double)st->N);
                j += st->A / ((double)st->N * Te);
            }
        }
        if (!(djl_fabs(pc->a_al - level) <= rel * amag + tiny))
            return "a piece's AL acceleration is not that of the plan's steps";
        if (!(djl_fabs(pc->a - a) <= rel * amag + tiny))
            return "a piece's acceleration is not that of the plan's steps";
        if (!(djl_fabs(pc->j - j) <= rel * jmag + tiny))
            return "a piece's jerk is not that of the plan's steps";
        if (i + 1 == pl->n_pieces) {
            if (pc->a != 0.0 || pc->j != 0.0) return "the plan's last piece does not cruise";
        } else {
            const djl_piece *nx = &pl->piece[i + 1];
            double L = ((double)nx->k - k) * Te;
            double dv = L * (pc->a + 0.5 * L * pc->j);
            double dx = L * (pc->v + L * (0.5 * pc->a + L * pc->j / 6.0));
            /* rounding carried from piece to piece: what the walk has summed so far (an
             * acceleration's residue of 6e-33 m/s2 over a stop of 1e9 s at d_max = 7e-26
             * m/s2 leaves 6e-24 m/s at rest, which the last piece sets to 0) */
            sv += L * (amag + 0.5 * L * jmag);
            sx += L * (vmag + L * (0.5 * amag + L * jmag / 6.0));
            /* pieces of 1e154 s and more (Te beyond 1e139 s): L * L overflows, and times a
             * magnitude of 0 gives NaN; no bound then (the values are within their limits) */
            if (!(sv >= 0.0)) sv = DJL_HUGE_VAL;
            if (!(sx >= 0.0)) sx = DJL_HUGE_VAL;
            if (!(djl_fabs(pc->v + dv - nx->v) <= rel * sv + tiny) ||
                !(djl_fabs(pc->x + dx - nx->x) <= rel * sx + tiny))
                return "a piece of the plan does not continue the one before";
            if (pc->j != 0.0) {
                /* the velocity's extremum inside the piece, where a crosses 0 */
                double ts = -pc->a / pc->j;
                if (ts > 0.0 && ts < L &&
                    !(djl_fabs(pc->v + ts * (pc->a + 0.5 * ts * pc->j)) <= vlim))
                    return "a piece of the plan peaks above v_max";
            }
        }
    }
    return NULL;
}

/* The queue's part of a state (issue 34): counts and ids in range, each waiting command's
 * mode, target and min_duration such as an edge accepts, its cmd_* inputs within their
 * domains (its shaper's design is checked again when it starts).  NULL if sound. */
static const char *queue_flaw(const model_data *d)
{
    int32_t i, k;
    int64_t last;
    if (d->command_aborted != 0 && d->command_aborted != 1)
        return "command_aborted is neither 0 nor 1";
    if (d->n_commands < 0 || d->running_id < 0 || d->running_id > d->n_commands)
        return "the command count is out of range";
    if (d->queue_n < 0 || d->queue_n > MODEL_QUEUE_CAPACITY || d->queue_first < 0 ||
        d->queue_first >= MODEL_QUEUE_CAPACITY)
        return "the queue's length or first entry is out of range";
    last = d->running_id;
    for (i = 0; i < d->queue_n; i++) {
        const model_queued *q = &d->queue[(d->queue_first + i) % MODEL_QUEUE_CAPACITY];
        const model_cmd_inputs *c = &q->cmd;
        if (q->buffer_mode != BUFFER_MODE_BUFFERED && q->buffer_mode != BUFFER_MODE_BLENDING)
            return "a waiting command is neither buffered nor blending";
        if (q->id <= last || q->id > d->n_commands) return "a waiting command's id is out of order";
        last = q->id;
        if (!(djl_isfinite(q->target) && djl_fabs(q->target) <= DJL_MAX_POSITION))
            return "a waiting command's target is out of range";
        if (!(q->min_duration == 0.0 || (djl_isfinite(q->min_duration) && q->min_duration > 0.0)))
            return "a waiting command's min_duration is invalid";
        if (!((c->v_max == 0.0 || (djl_isfinite(c->v_max) && c->v_max > 0.0)) &&
              (c->a_max == 0.0 || (djl_isfinite(c->a_max) && c->a_max > 0.0)) &&
              (c->d_max == 0.0 || (djl_isfinite(c->d_max) && c->d_max > 0.0))))
            return "a waiting command's limits are invalid";
        if (c->profile < CMD_PROFILE_PARAMETER || c->profile > CMD_PROFILE_DJL ||
            c->shaper < CMD_SHAPER_PARAMETER || c->shaper > CMD_SHAPER_NONE ||
            c->shaper_n < 0 || c->shaper_n > DJL_MAX_SHAPER_IMPULSES)
            return "a waiting command's profile or shaper is invalid";
        for (k = 0; k < 4; k++)
            if (c->T_F[k] != 0.0 && jerk_time_samples(c->T_F[k], d->p.Te) == 0)
                return "a waiting command's jerk time is invalid";
        for (k = 0; k < DJL_MAX_SHAPER_IMPULSES; k++)
            if (!djl_isfinite(c->amplitude[k]) || !djl_isfinite(c->delay[k]))
                return "a waiting command's shaper impulse is not finite";
    }
    return NULL;
}

const char *model_state_flaw(const model_data *d)
{
    const djl_plan *pl = &d->plan;
    int32_t i, cur;
    djl_sample o;
    double amx, alim, vlim, valim, jlim, lmax = 0.0;
    int32_t nmin, nmax;
    const char *why;
    if (d->planned != 0 && d->planned != 1) return "the planned flag is neither 0 nor 1";
    if (!djl_isfinite(d->start_time)) return "the start time is not finite";
    if (d->n < 0 || d->n > DJL_MAX_MOTION_SAMPLES) return "the sample counter is out of range";
    if (!(d->phase >= 0.0 && d->phase < 1.0)) return "the phase is not in [0, 1)";
    if (!djl_isfinite(d->t_now)) return "the communication time is not finite";
    if ((d->state & (MS_STEP | MS_TERMINATED)) && !d->planned)
        return "a state after initialization without a plan";
    if (d->jerk_source < JERK_SOURCE_PARAMETERS || d->jerk_source > JERK_SOURCE_F_MODE_AHEAD)
        return "jerk_source is not 1, 2 or 3";
    if (!djl_isfinite(d->f_seen) || !djl_isfinite(d->t_seen) || !djl_isfinite(d->f_rate))
        return "f_mode's rate of change is not finite";
    if ((d->execute | d->stop | d->execute_seen | d->stop_seen) & ~1)
        return "a Boolean input is neither 0 nor 1";
    /* (the inputs target and cmd_* take any value: a command checks them at its edge) */
    if (!(djl_isfinite(d->f_mode) && d->f_mode > 0.0)) return "the input f_mode is not > 0";
    if (d->cmd_error != 0 && d->cmd_error != 1) return "cmd_error is neither 0 nor 1";
    if (d->cmd_error_id < 0 || d->cmd_error_id > CMD_ERR_QUEUE_FULL ||
        (d->cmd_error_id != 0) != (d->cmd_error != 0))
        return "cmd_error_id is not a code of cmd_error";
    if ((why = queue_flaw(d)) != NULL) return why;
    if (!d->planned) return NULL; /* the plan is rebuilt before any use */
    if ((d->state & (MS_STEP | MS_TERMINATED)) && !(d->f_seen > 0.0))
        return "the f_mode last seen is not > 0"; /* an f_mode accepted (model_start) */
    if (djl_validate(&d->p, NULL) != DJL_OK) return "its parameters are invalid";
    if (d->goal != 0 && d->goal != DJL_GOAL_TARGET && d->goal != DJL_GOAL_STOP)
        return "the goal of the move is unknown";
    if (!(djl_isfinite(d->goal_target) && djl_fabs(d->goal_target) <= DJL_MAX_POSITION))
        return "the target of the move is out of range";
    if (d->replans < 0) return "the replan count is negative";
    if (pl->replanned != 0 && pl->replanned != 1) return "the replanned flag is neither 0 nor 1";
    if (!pl->replanned && d->jerk_source == JERK_SOURCE_PARAMETERS && !same_params(&d->p, &pl->p))
        return "its plan was not made from its parameters";
    if (d->p.profile == DJL_PROFILE_TABLE) {
        /* a replayed table: valid (the limits, the end at rest on the target), with
         * jerk_source = 1; a plan not replanned since is the table's, step for step */
        if (d->jerk_source != JERK_SOURCE_PARAMETERS)
            return "a table with jerk times from f_mode";
        if (djl_table_validate(&d->p, &d->table, NULL) != DJL_OK) return "its table is invalid";
        if (!pl->replanned && (why = djl_table_plan_flaw(pl, &d->p, &d->table)) != NULL)
            return why;
    }
    /* the move in progress: limits within the envelope of every move's (the parameters'
     * included), jerk times in range, its shaper's design checked below */
    {
        double mv[6];
        mv[0] = d->mv.v_max; mv[1] = d->mv.a_max; mv[2] = d->mv.d_max;
        mv[3] = d->env_v_max; mv[4] = d->env_a_max; mv[5] = d->env_d_max;
        if (!finite_all(mv, 6) || !(mv[0] > 0.0 && mv[1] > 0.0 && mv[2] > 0.0) ||
            mv[0] > mv[3] || mv[1] > mv[4] || mv[2] > mv[5] || mv[3] < d->p.v_max ||
            mv[4] < d->p.a_max || mv[5] < d->p.d_max)
            return "the limits of the move in progress are out of range";
        if (d->mv.profile < DJL_PROFILE_AL || d->mv.profile > DJL_PROFILE_DJL)
            return "the profile of the move in progress is unknown";
        for (i = 0; i < 4; i++)
            if (d->mv.N[i] < 0 || d->mv.N[i] > DJL_MAX_FILTER_SAMPLES)
                return "a jerk time of the move in progress is out of range";
        if (!pl->replanned && (memcmp(&d->env_v_max, &d->p.v_max, sizeof(double)) != 0 ||
                               memcmp(&d->env_a_max, &d->p.a_max, sizeof(double)) != 0 ||
                               memcmp(&d->env_d_max, &d->p.d_max, sizeof(double)) != 0))
            return "the limits of a plan not replanned are not the parameters'";
        if (!djl_isfinite(d->first.t_shaper) || d->first.t_shaper < 0.0)
            return "the shaper delay of the parametric move is out of range";
    }
    if (d->first.k_end < 0 || d->first.k_end > DJL_MAX_MOTION_SAMPLES ||
        !djl_isfinite(d->first.v_reached) || !djl_isfinite(d->first.a_reached) ||
        !djl_isfinite(d->first.d_reached))
        return "the figures of the parametric move are out of range";
    for (i = 0; i < 4; i++)
        if (d->first.N[i] < 0 || d->first.N[i] > DJL_MAX_FILTER_SAMPLES)
            return "a jerk time of the parametric move is out of range";
    if (pl->replanned || d->jerk_source >= JERK_SOURCE_F_MODE) {
        /* a plan of its own (a replan, or jerk times from f_mode): sound values */
        double v[7];
        v[0] = pl->p.Te; v[1] = pl->p.x0; v[2] = pl->p.v0; v[3] = pl->p.v_max;
        v[4] = pl->p.a_max; v[5] = pl->p.d_max; v[6] = pl->p.distance;
        if (!finite_all(v, 7) || pl->p.Te != d->p.Te || pl->p.v_max != d->env_v_max ||
            pl->p.a_max != d->env_a_max || pl->p.d_max != d->env_d_max ||
            djl_fabs(pl->p.x0) > DJL_MAX_POSITION || djl_fabs(pl->p.v0) > pl->p.v_max)
            return "its plan's parameters are not those of the FMU";
    }
    if (pl->n_steps < 0 || pl->n_steps > DJL_MAX_PLAN_STEPS)
        return "the plan's step count is out of range";
    /* every value against the limits it obeys (issue 21: a finite level0 of -DBL_MAX
     * passed and a stop then gave infinite outputs): a level within the larger of
     * a_max and d_max, a step (a change of level) within their sum, up to rounding */
    amx = djl_fmax(pl->p.a_max, pl->p.d_max);
    alim = amx * (1.0 + 1e-9);
    if (!(djl_fabs(pl->level0) <= alim))
        return "the plan's acceleration level is outside the acceleration limits";
    for (i = 0; i < pl->n_steps; i++) {
        const djl_step *st = &pl->step[i];
        /* a motion planned up to the horizon may hold a step a few samples past it */
        if (st->tau < -DJL_MAX_PLAN_END || st->tau > DJL_MAX_PLAN_END ||
            !djl_isfinite(st->A) || st->N < 0 || st->N > DJL_MAX_FILTER_SAMPLES ||
            st->stage < 0 || st->stage > 4)
            return "a step of the plan is out of range";
        if (!(djl_fabs(st->A) <= (pl->p.a_max + pl->p.d_max) * (1.0 + 1e-9)))
            return "a step of the plan is outside the acceleration limits";
    }
    if (!djl_isfinite(d->t_start)) return "t_start is not finite";
    if (!djl_isfinite(d->offset) || djl_fabs(d->offset) > 1e15 || d->offset != djl_floor(d->offset))
        return "the start offset is not a whole number of samples in range";
    if (pl->n_segments < 1 || pl->n_segments > DJL_MAX_SEGMENTS)
        return "the plan's segment count is out of range";
    if (pl->n_pieces < 1 || pl->n_pieces > DJL_MAX_PIECES)
        return "the plan's piece count is out of range";
    if (d->cursor < 0 || d->cursor >= pl->n_pieces) return "the piece cursor is out of range";
    if (pl->k_end < 0 || pl->k_end > DJL_MAX_PLAN_END) return "the motion end is out of range";
    for (i = 0; i < 4; i++)
        if (pl->N[i] < 0 || pl->N[i] > DJL_MAX_FILTER_SAMPLES)
            return "a jerk time in samples is out of range";
    vlim = pl->p.v_max * (1.0 + 1e-9);
    if (!djl_isfinite(pl->x_target) || !djl_isfinite(pl->v_target) ||
        !djl_isfinite(pl->v_reached) || !djl_isfinite(pl->a_reached) ||
        !djl_isfinite(pl->d_reached))
        return "a value of the plan is not finite";
    if (!(djl_fabs(pl->x_target) <= 2.0 * DJL_MAX_POSITION && djl_fabs(pl->v_target) <= vlim &&
          djl_fabs(pl->v_reached) <= vlim && djl_fabs(pl->a_reached) <= alim &&
          djl_fabs(pl->d_reached) <= alim))
        return "a value of the plan is outside its limits";
    /* v_max up to the rounding a piece of L seconds accumulates (tests/c/test_core.c) */
    for (i = 0; i + 1 < pl->n_pieces; i++)
        /* in doubles: the pieces' order is checked below (found by fuzz_state: int64_t
         * differences of forged indices overflowed) */
        lmax = djl_fmax(lmax, ((double)pl->piece[i + 1].k - (double)pl->piece[i].k) * pl->p.Te);
    vlim += 4.0 * 2.220446049250313e-16 * amx * lmax;
    /* the jerk: a sum of the ramps running (each A / (N Te)), of the steps listed, or of
     * stages of the plan's jerk times within the limits */
    nmin = 0;
    for (i = 0; i < 4; i++)
        if (pl->N[i] > 0 && (nmin == 0 || pl->N[i] < nmin)) nmin = pl->N[i];
    jlim = nmin > 0 ? 2.0 * amx / ((double)nmin * pl->p.Te) : 0.0;
    nmax = 1;
    for (i = 0; i < 4; i++) nmax = pl->N[i] > nmax ? pl->N[i] : nmax;
    for (i = 0; i < pl->n_steps; i++)
        if (pl->step[i].N > 0) {
            jlim += djl_fabs(pl->step[i].A) / ((double)pl->step[i].N * pl->p.Te);
            nmax = pl->step[i].N > nmax ? pl->step[i].N : nmax;
        }
    /* with jerk times from f_mode, earlier replans may have run ramps of any length the
     * FMU accepts, which the plan no longer lists (issue 21: the AL velocity of a state
     * the FMU saved itself, 3.5 % above v_max after ramps of 613 samples, was refused by
     * an allowance of the current 2-sample jerk times) */
    if (d->jerk_source != JERK_SOURCE_PARAMETERS) nmax = DJL_MAX_FILTER_SAMPLES;
    jlim *= 1.0 + 1e-9;
    /* the AL profile leads the output by up to a jerk time: a replan's transition may take
     * it past v_max while the output settles within */
    valim = vlim + 2.0 * alim * pl->p.Te * (double)nmax;
    for (i = 0; i < pl->n_pieces; i++) {
        const djl_piece *pc = &pl->piece[i];
        double v[7];
        v[0] = pc->x; v[1] = pc->v; v[2] = pc->a; v[3] = pc->j;
        v[4] = pc->x_al; v[5] = pc->v_al; v[6] = pc->a_al;
        if (pc->k < 0 || pc->k > DJL_MAX_PLAN_END || (i > 0 && pc->k < pl->piece[i - 1].k))
            return "the plan's pieces are not in order";
        if (pc->seg < 0 || pc->seg > pl->n_segments) return "a piece's segment is out of range";
        if (pc->stage < 0 || pc->stage > 4) return "a piece's stage is out of range";
        if (!finite_all(v, 7)) return "a piece of the plan is not finite";
        if (!(djl_fabs(pc->x) <= 2.0 * DJL_MAX_POSITION &&
              djl_fabs(pc->x_al) <= 2.0 * DJL_MAX_POSITION && djl_fabs(pc->v) <= vlim &&
              djl_fabs(pc->v_al) <= valim && djl_fabs(pc->a) <= alim && djl_fabs(pc->a_al) <= alim &&
              djl_fabs(pc->j) <= jlim))
            return "a piece of the plan is outside the limits";
    }
    if ((why = model_plan_inconsistency(pl, vlim)) != NULL) return why;
    /* the shaper is the one of its parameters, its memory sound */
    {
        djl_shaper sh;
        if (djl_shaper_design(&d->mv.sp, d->p.Te, d->shaper.f_design, &sh, NULL) != DJL_OK)
            return "its shaper's parameters are invalid";
        if (memcmp(&sh, &d->shaper, sizeof sh) != 0)
            return "its shaper is not the one of its parameters";
        for (i = 0; i < DJL_MAX_SHAPER_IMPULSES; i++)
            if (d->shaper_cursor[i] < 0 || d->shaper_cursor[i] >= pl->n_pieces)
                return "a piece cursor of the shaper is out of range";
        if ((why = djl_shaper_memory_flaw(&d->mem, &d->shaper)) != NULL) return why;
        /* f_mode, the input such a shaper is timed by, within the bounds a set keeps it in,
         * as the memory's rates (issue 21, fourth session: f_mode = DBL_MIN in a resealed
         * state froze the outputs, then gave NaN) */
        if (d->shaper.n > 0 && d->shaper.source == DJL_SHAPER_SOURCE_F_MODE &&
            !djl_shaper_rate_ok(&d->shaper, d->f_mode * d->p.Te))
            return "the input f_mode is outside the range its shaper allows";
    }
    /* the outputs are those of the plan (shaped) at the current sample */
    cur = d->cursor;
    {
        int32_t cs[DJL_MAX_SHAPER_IMPULSES];
        memcpy(cs, d->shaper_cursor, sizeof cs);
        djl_shaper_eval(&d->shaper, pl, (double)d->n - d->offset + d->phase, d->offset,
                        &d->mem, 0, &cur, cs, &o);
    }
    if (cur != d->cursor || !same_sample(&o, &d->out))
        return "its outputs are not those of its plan at its time";
    {
        /* and finite (issue 39, finding F: a phase entry forged to -DBL_MAX, finite and in
         * order, gave x = NaN, equal to itself as memcmp compares it) */
        const double out7[7] = {o.x, o.v, o.a, o.j, o.x_al, o.v_al, o.a_al};
        if (!finite_all(out7, 7)) return "its outputs are not finite";
    }
    return NULL;
}
