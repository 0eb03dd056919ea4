/*
 * test_stop.c -- a stop never brings the axis to rest beyond the target of the
 * move it stops (issue 20): random stop times during every stage of AL, JL and
 * DJL moves, DJL with N3 != N4 in both orders, meant to run under AddressSanitizer
 * + UBSan (tests/test_c_sanitizers.py, a short run) and at -O2 (the campaign,
 * tests/test_c_sanitizers.py::test_stop_campaign and docs/generator.md).
 *
 * Each case plans a rest-to-rest move (test_core.c's everyday and round-number
 * families made single moves from rest to rest), in a third of the cases replaced
 * while it runs by a move to a target further on (a commanded move, djl_replan,
 * kept only if it reaches that target without turning back), picks a part of the
 * move at random among those it has (stages 1..4 while a ramp runs, the plateaus
 * of acceleration and deceleration between them, the cruise; AL: acceleration,
 * cruise, deceleration), a random time in it (on a sample or between two), and
 * stops there (djl_replan, DJL_GOAL_STOP, with the move's jerk times, as the FMU
 * does with jerk_source = 1).  Checked on the sampled outputs, independently of
 * the planner: the outputs up to the stop unchanged; from there every output
 * finite, |v| <= v_max, the acceleration within [-d_max, a_max] in the direction
 * of the move, |j| <= (a_max + d_max) / (N Te) for the shortest jerk time N (that
 * of a stage's ending ramp the replan shortened, which it reports), the
 * axis never backing up; at rest in bounded time, and the rest between the
 * position at the stop and the move's target (1e-9 of the move).  A stop that
 * cannot be checked is counted by its reason; the driver fails if they are more
 * than a tenth of the stops.
 *
 * Usage: test_stop [cases] [seed]
 */
#define main test_core_main /* test_core.c: its parameter families */
#include "test_core.c"
#undef main

#define CHECK(cond, ...)                                                                         \
    do {                                                                                         \
        if (!(cond)) FAIL(__VA_ARGS__);                                                          \
    } while (0)

static djl_plan move, stopped, scratch; /* large: off the stack */

/* the parts of a move a stop may fall in */
enum { P_STAGE1, P_ACC, P_STAGE2, P_CRUISE, P_STAGE3, P_DEC, P_STAGE4, N_PARTS };
static const char *const part_names[N_PARTS] = {"stage 1", "acceleration plateau", "stage 2",
                                                "cruise", "stage 3", "deceleration plateau",
                                                "stage 4"};
enum { K_AL, K_JL, K_DJL_34, K_DJL_43, N_KINDS }; /* DJL_34: N3 < N4, DJL_43: N3 > N4 */
static const char *const kind_names[N_KINDS] = {"AL", "JL", "DJL N3 < N4", "DJL N3 > N4"};

typedef struct {
    long cases, skipped, checked, kept, after_command, clipped;
    long by[N_KINDS][N_PARTS];
    long no_part, turned_back; /* not checkable: the part drawn absent, a command that
                                  stops first */
} tally;

/* The part of the move at sample k (sg: its direction). */
static int part_of(const djl_sample *s, double sg, int al, double vmax)
{
    double a = al ? s->a_al : s->a;
    if (!al && s->stage >= 1 && s->stage <= 4) return 2 * (s->stage - 1);
    if (a * sg > 0.0) return P_ACC;
    if (a * sg < 0.0) return P_DEC;
    return fabs(s->v) > 1e-12 * vmax ? P_CRUISE : -1;
}

static void rest_to_rest(djl_params *p, int *kind)
{
    int i, N[4];
    if (urand() < 0.5)
        classic_params(p);
    else
        grid_params(p);
    p->n_segments = 0;
    p->v0 = 0.0;
    p->v_e = 0.0;
    if (p->distance == 0.0 || !isfinite(p->distance)) p->distance = 0.5 * p->v_max;
    *kind = irand(N_KINDS);
    p->profile = *kind == K_AL ? DJL_PROFILE_AL : *kind == K_JL ? DJL_PROFILE_JL : DJL_PROFILE_DJL;
    for (i = 0; i < 4; i++) {
        N[i] = (int)floor(p->T_F[i] / p->Te + 0.5);
        if (N[i] < 1) N[i] = 1;
    }
    if (*kind >= K_DJL_34) {
        if (N[2] == N[3]) N[3] = N[2] + 1 + irand(20);
        if ((N[2] < N[3]) != (*kind == K_DJL_34)) {
            int q = N[2];
            N[2] = N[3];
            N[3] = q;
        }
    }
    for (i = 0; i < 4; i++) p->T_F[i] = N[i] * p->Te;
}

static void run_case(tally *t, long ci)
{
    djl_params p;
    djl_error e;
    djl_goal g;
    djl_replan_info info;
    djl_sample s, before, after;
    int32_t cur = 0;
    int kind, al, i, part, want, n_parts, present[N_PARTS];
    long k, k0, k1, cand, pick, n_in[N_PARTS];
    double target, sg, u, x_stop, lvl, scale, tol, jmax, bound, rest;
    int Nmin = 1000000000;
    rest_to_rest(&p, &kind);
    if (djl_plan_motion(&p, &move, &e) != DJL_OK || move.k_end > 100000 || move.k_end < 2) {
        t->skipped++;
        return;
    }
    t->cases++;
    al = p.profile == DJL_PROFILE_AL;
    target = p.x0 + p.distance;
    sg = p.distance > 0.0 ? 1.0 : -1.0;
    lvl = fmax(p.a_max, p.d_max);
    memset(&g, 0, sizeof g);
    for (i = 0; i < 4; i++) g.N[i] = al ? 0 : move.N[i];
    for (i = 0; i < 4; i++)
        if (g.N[i] > 0 && g.N[i] < Nmin) Nmin = g.N[i];
    if (urand() < 0.3) {
        /* a commanded move: on to a target further on, from a random time of the move */
        double u1 = urand() * (double)move.k_end, far = p.distance * (0.2 + 2.0 * urand());
        g.kind = DJL_GOAL_TARGET;
        g.target = target + far;
        if (djl_replan(&move, u1, &g, &move, &scratch, &info, &e) != DJL_OK) {
            CHECK(0, "case %ld: a move to %.17g at %g refused: %s", ci, g.target, u1, e.message);
            return;
        }
        if (info.how != 1 || move.k_end > 200000) {
            t->turned_back++; /* it stops first: the rest of a stop bounds nothing */
            return;
        }
        t->after_command++;
        target = g.target;
    }
    scale = fabs(target - p.x0) + p.v_max * p.Te;
    tol = 1e-9 * scale + 4e-16 * fabs(target);
    /* the parts of the move, then one drawn among those it has */
    memset(n_in, 0, sizeof n_in);
    for (k = 0; k < move.k_end; k++) {
        djl_eval(&move, (double)k, &cur, &s);
        part = part_of(&s, sg, al, p.v_max);
        if (part >= 0) n_in[part]++;
    }
    n_parts = 0;
    for (i = 0; i < N_PARTS; i++)
        if (n_in[i] > 0) present[n_parts++] = i;
    if (n_parts == 0) {
        t->no_part++;
        return;
    }
    want = present[irand(n_parts)];
    pick = (long)(urand() * (double)n_in[want]);
    for (k = 0, cand = 0; k < move.k_end; k++) {
        djl_eval(&move, (double)k, &cur, &s);
        if (part_of(&s, sg, al, p.v_max) == want && cand++ == pick) break;
    }
    u = (double)k + (urand() < 0.3 ? urand() : 0.0);
    djl_eval(&move, u, &cur, &before);
    x_stop = before.x;
    /* the stop */
    g.kind = DJL_GOAL_STOP;
    if (djl_replan(&move, u, &g, &stopped, &scratch, &info, &e) != DJL_OK) {
        CHECK(0, "case %ld: a stop at %g refused: %s", ci, u, e.message);
        return;
    }
    if (getenv("TEST_STOP_DEBUG"))
        fprintf(stderr, "case %ld: %s from %.17g to %.17g (N %d/%d/%d/%d, Te %g, v_max %g, a_max "
                "%g, d_max %g, rule %d, k_end %lld), stop in the %s at %.17g (x %.17g v %.17g a "
                "%.17g): how %d kept %d origin %lld k_end %lld\n", ci, kind_names[kind], p.x0,
                target, (int)g.N[0], (int)g.N[1], (int)g.N[2], (int)g.N[3], p.Te, p.v_max,
                p.a_max, p.d_max, (int)p.short_stage, (long long)move.k_end, part_names[want], u,
                before.x, before.v, before.a, (int)info.how, (int)info.kept,
                (long long)info.origin, (long long)stopped.k_end);
    t->checked++;
    t->by[kind][want]++;
    if (info.kept) t->kept++;
    /* from here on, time in samples of the stop's plan */
    u -= (double)info.origin;
    djl_eval(&stopped, u, &cur, &after);
    CHECK(fabs(after.x - before.x) <= 1e-12 * (fabs(before.x) + scale) &&
              fabs(after.v - before.v) <= 1e-12 * p.v_max,
          "case %ld: the stop at %g changed the outputs at its time: x %.17g -> %.17g, v %.17g "
          "-> %.17g", ci, u, before.x, after.x, before.v, after.v);
    if (info.clipped) { /* the stage's ending ramp changed (logged): its own jerk time */
        t->clipped++;
        for (i = 0; i < stopped.n_steps; i++)
            if (stopped.step[i].N > 0 && stopped.step[i].N < Nmin) Nmin = stopped.step[i].N;
    }
    jmax = (p.a_max + p.d_max) / (Nmin * p.Te) * (1.0 + 1e-9);
    k0 = (long)floor(u) + 1;
    /* no slower than stopping at d_max with the longest jerk times, twice over (a stop
     * that keeps the move: that move's end) */
    bound = (p.T_F[0] + p.T_F[1] + p.T_F[2] + p.T_F[3]) / p.Te; /* samples */
    bound = 2.0 * (fmin(p.v_max, fabs(before.v) + lvl * (bound + 2.0) * p.Te) / p.d_max / p.Te +
                   6.0 * bound) + 50.0; /* (with the speed the ramps running may still bring) */
    k1 = info.kept ? (long)stopped.k_end + 2 : k0 + (long)bound;
    CHECK(info.kept || (double)stopped.k_end <= (double)k0 + bound,
          "case %ld: a stop at %g rests at sample %lld, more than %g samples on", ci, u,
          (long long)stopped.k_end, bound);
    for (k = k0; k <= k1; k++) {
        djl_eval(&stopped, (double)k, &cur, &s);
        CHECK(isfinite(s.x) && isfinite(s.v) && isfinite(s.a) && isfinite(s.j),
              "case %ld: not finite at %ld", ci, k);
        CHECK(fabs(s.v) <= p.v_max * (1.0 + 1e-12), "case %ld: |v| = %.17g > v_max at %ld", ci,
              s.v, k);
        CHECK(sg * s.a <= p.a_max * (1.0 + 1e-9) + 1e-12 * lvl &&
                  -sg * s.a <= p.d_max * (1.0 + 1e-9) + 1e-12 * lvl,
              "case %ld: a = %.17g outside [-d_max, a_max] = [-%g, %g] at %ld", ci, sg * s.a,
              p.d_max, p.a_max, k);
        CHECK(al || fabs(s.j) <= jmax, "case %ld: |j| = %.17g > %.17g at %ld", ci, s.j, jmax, k);
        CHECK(sg * s.v >= -1e-9 * p.v_max, "case %ld: the axis backs up (v = %.17g) at %ld", ci,
              s.v, k);
        if (failures > 20) return;
        if (s.done) break;
    }
    CHECK(s.done && s.v == 0.0 && s.a == 0.0, "case %ld: not at rest %ld samples after a stop "
          "at %g (v %g, a %g)", ci, k - k0, u, s.v, s.a);
    rest = s.x;
    CHECK(sg * (rest - x_stop) >= -tol && sg * (rest - target) <= tol,
          "case %ld: %s, %s move from %.17g to %.17g (N %d/%d/%d/%d, rule %d): a stop at %g (x "
          "%.17g, v %.17g, a %.17g) rests at %.17g, %.3e past the target", ci, kind_names[kind],
          t->after_command && info.origin ? "a commanded" : "a", p.x0, target, (int)g.N[0],
          (int)g.N[1], (int)g.N[2], (int)g.N[3], (int)p.short_stage, u + (double)info.origin,
          before.x, before.v, before.a, rest, sg * (rest - target));
}

int main(int argc, char **argv)
{
    long cases = argc > 1 ? atol(argv[1]) : 2000, c, unchecked;
    int i, j;
    tally t;
    memset(&t, 0, sizeof t);
    if (argc > 2) rng_state ^= strtoull(argv[2], NULL, 10) * 0x9E3779B97F4A7C15ULL;
    for (c = 0; c < cases && failures <= 20; c++) run_case(&t, c);
    unchecked = t.no_part + t.turned_back;
    printf("test_stop: %ld moves (%ld parameter sets skipped: refused or longer than 10^5 "
           "samples), %ld stops checked (%ld after a commanded move; %ld kept the move; %ld with "
           "the stage's ending ramp shortened), %ld not checkable (%ld: a commanded move that "
           "stops first; %ld: no part to stop in)\n",
           t.cases, t.skipped, t.checked, t.after_command, t.kept, t.clipped, unchecked,
           t.turned_back, t.no_part);
    for (i = 0; i < N_KINDS; i++) {
        printf("  %-12s", kind_names[i]);
        for (j = 0; j < N_PARTS; j++)
            if (i != K_AL || j == P_ACC || j == P_CRUISE || j == P_DEC)
                printf(" %s %ld,", part_names[j], t.by[i][j]);
        printf("\n");
        for (j = 0; j < N_PARTS; j++)
            CHECK(cases < 2000 || t.by[i][j] > 0 ||
                      (i == K_AL && j != P_ACC && j != P_CRUISE && j != P_DEC),
                  "no stop checked in the %s of a %s move", part_names[j], kind_names[i]);
    }
    CHECK(t.checked > 0 && unchecked * 10 <= t.checked + unchecked,
          "%ld stops could not be checked, more than a tenth of the %ld", unchecked,
          t.checked + unchecked);
    printf("test_stop: %d failures\n", failures);
    return failures != 0;
}
