/*
 * test_replan.c -- commanded moves (djl_replan, djl_jerk_times_due) under
 * random command sequences, meant to run under AddressSanitizer + UBSan
 * (tests/test_c_sanitizers.py) and, for the campaign of docs/generator.md, at
 * -O2 with many cases.
 *
 * Each case plans a random motion (test_core.c's everyday and round-number
 * families), then steps it like a master does the FMU: whole samples, or
 * steps of 0.37 Te, commands at random steps: a new target (anywhere within
 * a few times the move), a stop, and in "f_mode" cases (JL/DJL single moves
 * ending at rest) new jerk times at random steps, even at every step, applied
 * as the FMU applies them (djl_jerk_times_due).  Checked on the sampled
 * outputs, independently of the planner:
 *  - a command does not change the outputs at the time it is given, nor the jerk
 *    until the next sample (a command acts from the first sample after it);
 *  - every output finite; |v| <= v_max; |a| <= max(a_max, d_max); |j| <=
 *    (a_max + d_max) / (N Te) for the shortest jerk time N ever used (two
 *    ramps of the same sign may overlap, as in planned motions); every step
 *    of a plan has |A| <= max(a_max, d_max) and its stage's jerk time;
 *  - x, v, a continuous: at whole-sample steps, x and v at each sample equal
 *    the cubic of the previous sample (its x, v, a and the jerk over the
 *    interval) to 1e-9;
 *  - with f_mode, every ramp that starts has the jerk time of the frequency
 *    in force at its start (but a stage-ending one changed to keep v_max,
 *    which the replan reports);
 *  - the motion ends (in a bounded time) exactly at the last target, at rest
 *    (1e-9 of the move), or at rest after a stop, and stays there.
 *
 * Usage: test_replan [cases] [seed]
 */
#define main test_core_main /* test_core.c: its parameter families */
#include "test_core.c"
#undef main

/* failures: test_core.c's count */
#define CHECK(cond, ...)                                                                         \
    do {                                                                                         \
        if (!(cond)) FAIL(__VA_ARGS__);                                                          \
    } while (0)

static djl_plan plan, scratch; /* large: off the stack */

typedef struct {
    long cases, commands, stops, targets, fchanges, replans_f, clipped, fallbacks, skipped;
    long declined, kept;
} tally;

static int32_t N_of(double f, double Te)
{
    double r = floor(1.0 / (f * Te) + 0.5);
    return r < 1.0 ? 1 : r > 1e6 ? 1000000 : (int32_t)r;
}

static void run_case(tally *t, long ci)
{
    djl_params p;
    djl_error e;
    djl_sample s, prev;
    djl_goal g;
    int32_t cur = 0, Nf = 0, Nmin;
    int i, fmode, whole, have = 0, last_kind = 0, stopped_fixed = 0, ncmd;
    double off = 0.0, phase = 0.0, h, target, lvl, scale, f = 0.0;
    double exempt[16]; /* absolute samples of ramps that keep or adjust their jerk time */
    int n_exempt = 0;
    long n = 0, n_end, next_cmd, limit;
    if (urand() < 0.5)
        classic_params(&p);
    else
        grid_params(&p);
    p.x0 = urand() < 0.5 ? 0.0 : (urand() - 0.5) * 10.0;
    fmode = p.profile != DJL_PROFILE_AL && urand() < 0.35;
    if (fmode) {
        /* jerk times from a frequency: a single move ending at rest */
        p.n_segments = 0;
        p.v_e = 0.0;
        if (p.distance == 0.0) p.distance = 0.1 * p.v_max;
        if (p.v0 * p.distance < 0.0) p.v0 = 0.0;
        f = 1.0 / (p.Te * (1.0 + irand(60)));
        Nf = N_of(f, p.Te);
        p.profile = DJL_PROFILE_DJL;
        for (i = 0; i < 4; i++) p.T_F[i] = Nf * p.Te;
    }
    if (djl_plan_motion(&p, &plan, &e) != DJL_OK || plan.k_end > 200000) {
        t->skipped++;
        return;
    }
    t->cases++;
    lvl = fmax(p.a_max, p.d_max);
    Nmin = 1000000000;
    for (i = 0; i < 4; i++)
        if (plan.N[i] > 0 && plan.N[i] < Nmin) Nmin = plan.N[i];
    target = p.x0;
    if (p.n_segments == 0)
        target += p.distance;
    else
        for (i = 0; i < p.n_segments; i++) target += p.seg_distance[i];
    last_kind = p.n_segments == 0 && p.v_e == 0.0 ? 1 : 0; /* 0: ends moving */
    scale = fabs(target - p.x0) + p.v_max * p.Te + 1e-300;
    whole = urand() < 0.8;
    h = whole ? 1.0 : 0.37; /* in samples */
    ncmd = 1 + irand(6);
    next_cmd = irand((int)(plan.k_end * 1.1) + 2);
    limit = 4 * plan.k_end + 100000;
    memset(&prev, 0, sizeof prev);
    for (;;) {
        double u = (double)n - off + phase, un;
        int cmd = 0;
        if (n >= next_cmd && ncmd > 0) cmd = urand() < 0.25 ? 2 : 1;
        if (cmd) {
            djl_replan_info info;
            djl_sample before, after;
            int32_t c0 = 0, c1 = 0;
            djl_eval(&plan, u, &c0, &before);
            memset(&g, 0, sizeof g);
            g.kind = cmd == 2 ? DJL_GOAL_STOP : DJL_GOAL_TARGET;
            g.target = target + (urand() - 0.5) * 4.0 * scale;
            if (urand() < 0.1) g.target = target; /* the same target again */
            for (i = 0; i < 4; i++) g.N[i] = fmode ? Nf : plan.N[i];
            if (!fmode && urand() < 0.2 && p.profile != DJL_PROFILE_AL) /* new jerk times */
                for (i = 0; i < 4; i++) g.N[i] = 1 + irand(40);
            for (i = 0; i < 4; i++)
                if (g.N[i] > 0 && g.N[i] < Nmin) Nmin = g.N[i];
            if (djl_replan(&plan, u, &g, &plan, &scratch, &info, &e) != DJL_OK) {
                CHECK(0, "case %ld: replan at %g refused: %s", ci, u, e.message);
                return;
            }
            off += (double)info.origin;
            t->commands++;
            if (cmd == 2) t->stops++; else t->targets++;
            if (info.how == 2) t->fallbacks++;
            if (info.kept) t->kept++;
            if (info.clipped) t->clipped++;
            if (info.clipped)
                for (i = 0; i < plan.n_steps; i++)
                    if (plan.step[i].N > 0 && plan.step[i].N < Nmin) Nmin = plan.step[i].N;
            u = (double)n - off + phase;
            djl_eval(&plan, u, &c1, &after);
            if (getenv("TEST_REPLAN_DEBUG"))
                fprintf(stderr, "case %ld: n %ld u %g (x %.17g v %.17g a %.17g) kind %d target %g how %d end_at %lld "
                        "v_settled %g clipped %d k_end %lld N %d/%d/%d/%d\n", ci, n, u, before.x, before.v, before.a, g.kind,
                        g.target, (int)info.how, (long long)info.end_at, info.v_settled,
                        (int)info.clipped, (long long)plan.k_end, (int)g.N[0], (int)g.N[1],
                        (int)g.N[2], (int)g.N[3]);
            /* unfiltered (AL) steps at the sample itself change a there (right-continuous) */
            CHECK(fabs(after.x - before.x) <= 1e-12 * (fabs(before.x) + scale) &&
                      fabs(after.v - before.v) <= 1e-12 * p.v_max &&
                      fabs(after.a - before.a) <= 1e-9 * lvl &&
                      fabs(after.j - before.j) <= 1e-9 * fabs(before.j) + 1e-300,
                  "case %ld: the command at %g changed the outputs at its time: x %.17g -> "
                  "%.17g, v %.17g -> %.17g, a %.17g -> %.17g", ci, u, before.x, after.x, before.v,
                  after.v, before.a, after.a);
            last_kind = cmd;
            if (cmd == 1) target = g.target;
            stopped_fixed = 0;
            ncmd--;
            next_cmd = n + 1 + irand((int)fmin(plan.k_end * 1.2, 1e9) + 2);
            {
                /* no slower than stopping at d_max, then moving at the limits (each with
                 * its jerk times), twice over */
                double v, Nx = 0.0, bound;
                for (i = 0; i < 4; i++) Nx = fmax(Nx, fmax(g.N[i], plan.N[i]));
                for (i = 0; i < plan.n_steps; i++) Nx = fmax(Nx, plan.step[i].N); /* kept */
                /* the speed the ramps running may still bring */
                v = fmin(p.v_max, fabs(before.v) + lvl * (Nx + 2.0) * p.Te);
                bound = v / p.d_max + (g.kind == DJL_GOAL_STOP ? 0.0
                        : (fabs(g.target - before.x) + v * v / (2 * p.d_max)) / p.v_max +
                          p.v_max / p.a_max + p.v_max / p.d_max);
                bound = 2.0 * (bound / p.Te + 6.0 * (Nx + 1.0)) + 50.0; /* + whole samples */
                /* (from the command: a stop that keeps the move keeps its origin) */
                CHECK(info.kept || (double)plan.k_end - floor(u) <= bound, "case %ld: a command at %ld makes "
                      "a motion of %g samples, more than %g", ci, n,
                      (double)plan.k_end - floor(u), bound);
            }
            limit = n + 4 * (long)fmin(plan.k_end, 1e8) + 100000;
        }
        /* jerk times from f_mode (as the FMU applies them, once per step) */
        if (fmode) {
            double from = u, at;
            int it, now = u >= 0.0;
            if (urand() < 0.3) {
                f *= exp((urand() - 0.5) * 0.6);
                if (urand() < 0.02) f = 1.0 / (p.Te * (1.0 + irand(60))); /* a jump */
                f = fmin(fmax(f, 1.0 / (200.0 * p.Te)), 1.0 / p.Te); /* periods of 1..200 Te */
                Nf = N_of(f, p.Te);
                if (Nf < Nmin) Nmin = Nf;
                t->fchanges++;
            }
            memset(&g, 0, sizeof g);
            g.kind = last_kind == 2 ? DJL_GOAL_STOP : DJL_GOAL_TARGET;
            g.target = target;
            for (i = 0; i < 4; i++) g.N[i] = Nf;
            g.no_stop_first = 1;
            g.keep_speed = 1;
            n_exempt = 0;
            for (it = 0; it < 8; it++) {
                djl_replan_info info;
                djl_status st;
                double o;
                if (!djl_jerk_times_due(&plan, from, u + h, g.N, now, &at)) break;
                st = djl_replan(&plan, at, &g, &plan, &scratch, &info, &e);
                if (st == DJL_E_INFEASIBLE) { /* the stage keeps its planned jerk time */
                    t->declined++;
                    if (n_exempt < 16) exempt[n_exempt++] = floor(at) + 1.0 + off;
                    from = floor(at) + 1.0;
                    now = 0;
                    continue;
                }
                if (st != DJL_OK) {
                    CHECK(0, "case %ld: f_mode replan at %g refused: %s", ci, at, e.message);
                    return;
                }
                t->replans_f++;
                if (getenv("TEST_REPLAN_DEBUG"))
                    fprintf(stderr, "case %ld: n %ld f-replan at %g N %d how %d end_at %lld "
                            "v_settled %g clipped %d\n", ci, n, at, (int)Nf, (int)info.how,
                            (long long)info.end_at, info.v_settled, (int)info.clipped);
                if (getenv("TEST_REPLAN_STEPS"))
                    for (i = 0; i < plan.n_steps; i++)
                        fprintf(stderr, "    tau %lld A %.6g N %d stage %d (k_end %lld)\n",
                                (long long)plan.step[i].tau, plan.step[i].A, (int)plan.step[i].N,
                                (int)plan.step[i].stage, (long long)plan.k_end);
                if (info.clipped) {
                    t->clipped++;
                    for (i = 0; i < plan.n_steps; i++)
                        if (plan.step[i].N > 0 && plan.step[i].N < Nmin) Nmin = plan.step[i].N;
                }
                if ((info.clipped || info.lengthened) && n_exempt < 16)
                    exempt[n_exempt++] = (double)info.end_at + off;
                o = floor(at);
                off += o;
                u -= o;
                from = 1.0;
                now = 0;
            }
            /* the ramps starting within this step take Nf (but those above) */
            for (i = 0; i < plan.n_steps; i++) {
                const djl_step *st = &plan.step[i];
                int k, ex = 0;
                for (k = 0; k < n_exempt; k++) ex |= exempt[k] == (double)st->tau + off;
                if ((double)st->tau >= floor(u) + 1.0 && (double)st->tau < floor(u + h) + 1.0 && !ex)
                    CHECK(st->N == Nf, "case %ld: a ramp of stage %d starts at %lld with %d "
                          "samples, f_mode gives %d", ci, (int)st->stage, (long long)st->tau,
                          (int)st->N, (int)Nf);
            }
        }
        /* the interval from now on is the new plan's (a command acts from the sample at
         * or after it): the jerk it will have */
        if (have && whole) {
            int32_t c2 = 0;
            double x = prev.x, v = prev.v, a = prev.a;
            djl_eval(&plan, u, &c2, &prev);
            CHECK(fabs(prev.x - x) <= 1e-12 * (fabs(x) + scale) && fabs(prev.v - v) <= 1e-12 *
                  p.v_max && fabs(prev.a - a) <= 1e-9 * lvl,
                  "case %ld: replans changed the outputs at %g", ci, u);
        }
        /* step */
        phase += h;
        while (phase >= 1.0 - 1e-9) {
            phase -= 1.0;
            n++;
        }
        if (phase < 1e-9) phase = 0.0;
        un = (double)n - off + phase;
        djl_eval(&plan, un, &cur, &s);
        CHECK(isfinite(s.x) && isfinite(s.v) && isfinite(s.a) && isfinite(s.j) &&
                  isfinite(s.x_al) && isfinite(s.v_al) && isfinite(s.a_al),
              "case %ld: output not finite at %ld", ci, n);
        CHECK(fabs(s.v) <= p.v_max * (1 + 1e-12), "case %ld: |v| = %.17g > v_max = %.17g at %ld",
              ci, s.v, p.v_max, n);
        CHECK(fabs(s.a) <= lvl * (1 + 1e-9), "case %ld: |a| = %.17g > %.17g at %ld", ci, s.a, lvl,
              n);
        /* two ramps of the same sign may overlap (the end of an acceleration and the
         * start of a deceleration: planned motions allow it too) */
        CHECK(Nmin == 1000000000 || fabs(s.j) <= (p.a_max + p.d_max) / (Nmin * p.Te) * (1 + 1e-9),
              "case %ld: |j| = %.17g > %.17g at %ld", ci, s.j,
              (p.a_max + p.d_max) / (Nmin * p.Te), n);
        CHECK(s.stage >= 0 && s.stage <= 4 && (s.j == 0.0 || s.stage > 0),
              "case %ld: stage %d with jerk %g at %ld", ci, (int)s.stage, s.j, n);
        if (whole && have) {
            double T = p.Te, xp, vp;
            xp = prev.x + T * (prev.v + T * (0.5 * prev.a + T * prev.j / 6.0));
            vp = prev.v + T * (prev.a + 0.5 * T * prev.j);
            CHECK(fabs(xp - s.x) <= 1e-9 * (scale + fabs(s.x)) && fabs(vp - s.v) <= 1e-9 * p.v_max,
                  "case %ld: not continuous at %ld: x %.17g vs %.17g, v %.17g vs %.17g", ci, n,
                  xp, s.x, vp, s.v);
        }
        prev = s;
        have = 1;
        if (failures > 20) return;
        if (s.done && ncmd == 0) {
            if (last_kind == 1) {
                CHECK(fabs(s.x - target) <= 1e-9 * scale + 4e-16 * fabs(target),
                      "case %ld: ended at %.17g, target %.17g", ci, s.x, target);
            }
            if (last_kind != 0)
                CHECK(s.v == 0.0 && s.a == 0.0 && s.j == 0.0,
                      "case %ld: not at rest at the end: v %g a %g j %g", ci, s.v, s.a, s.j);
            if (++stopped_fixed > 3) break;
        }
        CHECK(n < limit, "case %ld: no end after %ld samples", ci, n);
        if (n >= limit) return;
    }
    n_end = n;
    (void)n_end;
}

/* Found by fuzz_plan (issue 21, fourth session), every run: a stop of a motion at
 * a_max = d_max = DBL_MIN with Te = 1e-9 s, whose d_max Te is subnormal: the stop's length
 * came 80 samples short and its deceleration 8e-8 above d_max.  Each piece within the
 * limits, at rest at the end, with the plan's jerk times (JL, 0.08 s: 8e7 samples) and
 * with one-sample ones. */
static void issue21_replan_cases(void)
{
    static djl_plan out; /* large: off the stack */
    djl_params p;
    djl_error e;
    djl_goal g;
    djl_replan_info info;
    djl_sample s;
    djl_status st;
    int32_t cur = 0;
    int i, k, n;
    dbl_min_params(&p); /* test_core.c */
    st = djl_plan_motion(&p, &plan, &e);
    CHECK(st == DJL_OK, "issue 21, stop at d_max = DBL_MIN: the plan: %s", e.message);
    if (st != DJL_OK) return;
    for (k = 0; k < 2; k++) {
        memset(&g, 0, sizeof g);
        g.kind = DJL_GOAL_STOP;
        for (i = 0; i < 4; i++) g.N[i] = k == 0 ? plan.N[i] : 1;
        g.no_stop_first = 1;
        st = djl_replan(&plan, 0.0, &g, &out, &scratch, &info, &e);
        CHECK(st == DJL_OK, "issue 21, stop at d_max = DBL_MIN (N %d): %s", (int)g.N[2],
              e.message);
        if (st != DJL_OK) continue;
        n = out.n_pieces;
        for (i = 0; i < n; i++)
            CHECK(fabs(out.piece[i].a) <= p.d_max * (1.0 + 1e-12),
                  "issue 21, stop at d_max = DBL_MIN (N %d): piece %d: |a| = %.17g above "
                  "d_max %.17g", (int)g.N[2], i, fabs(out.piece[i].a), p.d_max);
        cur = 0;
        djl_eval(&out, (double)out.k_end, &cur, &s);
        CHECK(s.done && s.v == 0.0 && s.a == 0.0, "issue 21, stop at d_max = DBL_MIN: ends at "
              "v %g a %g", s.v, s.a);
    }
}

/* Issue 34: goals with limits of their own (djl_goal's v_max, a_max, d_max: a command's
 * cmd_v_max, cmd_a_max, cmd_d_max), lower and higher than the plan's, at a random time of a
 * random motion.  Checked on the new plan, sample by sample: finite; |v| within the larger
 * v_max, |a| within the largest acceleration limit; once |v| is within the goal's v_max and
 * not rising (at once, after the acceleration in progress has ramped down, or after the
 * stop a slower goal starts with) it stays within it; the motion ends exactly on the
 * target at rest; the new plan's limits are the larger of the two. */
static void goal_limit_cases(long cases)
{
    static djl_plan out; /* large: off the stack */
    static const double fv[4] = {0.2, 0.5, 1.0, 1.6}, fa[3] = {0.3, 1.0, 2.0};
    long c, made = 0, refused = 0, slowed = 0;
    for (c = 0; c < cases; c++) {
        djl_params p;
        djl_error e;
        djl_goal g;
        djl_replan_info info;
        djl_sample s;
        djl_status st;
        int32_t cur = 0;
        int i, within = 0;
        double u, x_now, target, vlim, alim, scale;
        int64_t k;
        if (urand() < 0.5)
            classic_params(&p);
        else
            grid_params(&p);
        p.n_segments = 0;
        p.v0 = 0.0;
        p.v_e = 0.0;
        if (djl_plan_motion(&p, &plan, &e) != DJL_OK || plan.k_end > 200000 || plan.k_end < 2)
            continue;
        u = floor(urand() * (double)plan.k_end) + (urand() < 0.5 ? 0.0 : 0.37);
        djl_eval(&plan, floor(u), &cur, &s);
        x_now = s.x;
        memset(&g, 0, sizeof g);
        g.kind = DJL_GOAL_TARGET;
        target = x_now + (urand() - 0.3) * 2.0 * fabs(p.distance);
        g.target = target;
        memcpy(g.N, plan.N, sizeof g.N);
        g.v_max = p.v_max * fv[irand(4)];
        g.a_max = p.a_max * fa[irand(3)];
        g.d_max = p.d_max * fa[irand(3)];
        st = djl_replan(&plan, u, &g, &out, &scratch, &info, &e);
        if (st != DJL_OK) {
            refused++;
            continue;
        }
        made++;
        slowed += info.how == 2;
        vlim = fmax(p.v_max, g.v_max) * (1.0 + 1e-9);
        alim = fmax(fmax(p.a_max, p.d_max), fmax(g.a_max, g.d_max)) * (1.0 + 1e-9);
        scale = fabs(target) + fabs(x_now) + p.v_max * p.Te;
        CHECK(out.p.v_max == fmax(p.v_max, g.v_max) && out.p.a_max == fmax(p.a_max, g.a_max) &&
                  out.p.d_max == fmax(p.d_max, g.d_max),
              "goal limits, case %ld: the new plan's limits are not the larger ones", c);
        cur = 0;
        for (k = 1; k <= out.k_end + 2; k++) {
            djl_eval(&out, (double)k, &cur, &s);
            CHECK(isfinite(s.x) && isfinite(s.v) && isfinite(s.a),
                  "goal limits, case %ld: not finite at %lld", c, (long long)k);
            CHECK(fabs(s.v) <= vlim && fabs(s.a) <= alim, "goal limits, case %ld, sample %lld: "
                  "v %.17g a %.17g beyond %.17g, %.17g", c, (long long)k, s.v, s.a, vlim, alim);
            /* within and no longer speeding up: the ramps the command found running have
             * ended their push (they finish as started: an axis accelerating near the goal's
             * v_max gains speed while its acceleration ramps down) */
            if (fabs(s.v) <= g.v_max && s.a * s.v <= 0.0) within = 1;
            else
                CHECK(!within || fabs(s.v) <= g.v_max * (1.0 + 1e-9), "goal limits, case %ld, "
                      "sample %lld: |v| = %.17g back above the goal's v_max %.17g", c,
                      (long long)k, fabs(s.v), g.v_max);
            if (failures > 20) return;
        }
        CHECK(s.done && s.v == 0.0 && fabs(s.x - target) <= 1e-9 * scale,
              "goal limits, case %ld: ends at x %.17g v %g, not at rest on %.17g", c, s.x, s.v,
              target);
        for (i = 0; i < out.n_steps; i++)
            CHECK(fabs(out.step[i].A) <= out.p.a_max + out.p.d_max,
                  "goal limits, case %ld: a step beyond the limits", c);
    }
    printf("test_replan: %ld goals with limits of their own (%ld stopped first, %ld refused by "
           "the planner)\n", made, slowed, refused);
}

int main(int argc, char **argv)
{
    long cases = argc > 1 ? atol(argv[1]) : 2000, c;
    tally t;
    memset(&t, 0, sizeof t);
    if (argc > 2) rng_state ^= strtoull(argv[2], NULL, 10) * 0x9E3779B97F4A7C15ULL;
    issue21_replan_cases();
    for (c = 0; c < cases && failures <= 20; c++) {
        if (getenv("TEST_REPLAN_CASE") && c != atol(getenv("TEST_REPLAN_CASE"))) {
            /* the same random draws, quietly */
            int f0 = failures;
            FILE *saved = stderr;
            stderr = fopen("/dev/null", "w");
            run_case(&t, c);
            fclose(stderr);
            stderr = saved;
            failures = f0;
            continue;
        }
        run_case(&t, c);
    }
    /* after the campaign: its random cases are those they were before issue 34 */
    if (!getenv("TEST_REPLAN_CASE")) goal_limit_cases(cases / 4 + 50);
    printf("test_replan: %ld motions (%ld skipped), %ld commands (%ld targets, %ld stops; %ld "
           "stopped first), %ld f_mode changes, %ld f_mode replans (%ld declined: the stage "
           "kept its jerk time), %ld stage ends clipped to v_max, %ld stops that kept the move: "
           "%d failures\n",
           t.cases, t.skipped, t.commands, t.targets, t.stops, t.fallbacks, t.fchanges,
           t.replans_f, t.declined, t.clipped, t.kept, failures);
    return failures != 0;
}
