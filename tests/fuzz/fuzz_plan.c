/*
 * fuzz_plan.c -- the planner's parameter space (issue 21): djl_plan_motion on parameters
 * decoded from bytes (any profile, rule, magnitudes from the table of fuzz_common.h or any
 * double, up to 32 segments), then djl_replan at any time of the plan towards any target
 * or a stop, with the plan's jerk times or others.
 *
 * Invariants (independent of the planner's own self-check):
 *  - never DJL_E_INTERNAL; a refusal is DJL_E_PARAM or DJL_E_INFEASIBLE with a message
 *    (and, for DJL_E_PARAM, the parameter's name);
 *  - a plan's pieces are finite and in order, |v| <= v_max, |a| <= max(a_max, d_max) (up
 *    to rounding, as tests/c/test_core.c), the last piece starts at k_end with a = j = 0;
 *  - the plan ends on x0 + the distances, at the end velocity (the tolerance of
 *    docs/fuzzing.md's harnesses), done from k_end on;
 *  - a replan accepted ends at rest, on the target for a target, within 10^-9 of the
 *    positions involved and of a sample's travel at the speeds the move reaches (not at
 *    v_max: issue 21), or within DJL_MIN_MAGNITUDE (a subnormal distance is no move),
 *    with finite outputs within the limits on the way.
 */
#include "djl_core.h"
#include "fuzz_common.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static djl_plan plan, out, scratch; /* large: off the stack */

/* A magnitude: the table, a power of ten (10^-30 .. 10^30, and the extremes), or anything. */
static double rd_mag(fuzz_reader *r)
{
    uint8_t k = rd_u8(r);
    if (k < 128) return rd_double(r);
    if (k < 250) return pow(10.0, (double)(k - 128) / 2.0 - 30.0) * (1.0 + (rd_u8(r) % 10) / 4.0);
    return rd_raw_double(r);
}

static double vlimit(const djl_plan *pl, double amx)
{
    double lmax = 0.0;
    int i;
    for (i = 0; i + 1 < pl->n_pieces; i++)
        lmax = fmax(lmax, (double)(pl->piece[i + 1].k - pl->piece[i].k) * pl->p.Te);
    return pl->p.v_max * (1.0 + 1e-12) + 4.0 * DBL_EPSILON * amx * lmax;
}

static void check_pieces(const djl_plan *pl, const char *what)
{
    double amx = fmax(pl->p.a_max, pl->p.d_max), vl = vlimit(pl, amx);
    int i;
    FUZZ_CHECK(pl->n_pieces >= 1 && pl->n_pieces <= DJL_MAX_PIECES, "%s: %d pieces", what,
               (int)pl->n_pieces);
    FUZZ_CHECK(pl->k_end >= 0 && pl->k_end <= DJL_MAX_PLAN_END, "%s: k_end %lld", what,
               (long long)pl->k_end);
    for (i = 0; i < pl->n_pieces; i++) {
        const djl_piece *pc = &pl->piece[i];
        FUZZ_CHECK(isfinite(pc->x) && isfinite(pc->v) && isfinite(pc->a) && isfinite(pc->j) &&
                       isfinite(pc->x_al) && isfinite(pc->v_al) && isfinite(pc->a_al),
                   "%s: piece %d not finite", what, i);
        FUZZ_CHECK(i == 0 || pc->k >= pl->piece[i - 1].k, "%s: pieces out of order", what);
        FUZZ_CHECK(fabs(pc->v) <= vl, "%s: piece %d: |v| = %.17g above v_max %.17g", what, i,
                   pc->v, pl->p.v_max);
        FUZZ_CHECK(fabs(pc->a) <= amx * (1.0 + 1e-12) * (1.0 + 1e-12),
                   "%s: piece %d: |a| = %.17g above %.17g", what, i, pc->a, amx);
    }
    FUZZ_CHECK(pl->piece[pl->n_pieces - 1].k == pl->k_end && pl->piece[pl->n_pieces - 1].a == 0.0 &&
                   pl->piece[pl->n_pieces - 1].j == 0.0,
               "%s: last piece at %lld of %lld, a %g, j %g", what,
               (long long)pl->piece[pl->n_pieces - 1].k, (long long)pl->k_end,
               pl->piece[pl->n_pieces - 1].a, pl->piece[pl->n_pieces - 1].j);
}

static void check_refusal(djl_status st, const djl_error *e, const char *what)
{
    FUZZ_CHECK(st == DJL_E_PARAM || st == DJL_E_INFEASIBLE, "%s: status %d: %s", what, (int)st,
               e->message);
    FUZZ_CHECK(e->message[0] != '\0' && memchr(e->message, '\0', sizeof e->message) != NULL,
               "%s: refusal without a message", what);
    if (st == DJL_E_PARAM) FUZZ_CHECK(e->param[0] != '\0', "%s: unnamed parameter: %s", what,
                                      e->message);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fuzz_reader r;
    djl_params p;
    djl_error e;
    djl_status st;
    djl_sample s;
    djl_goal g;
    djl_replan_info info;
    int32_t cur = 0;
    int i, n;
    double D = 0.0, Dabs = 0.0, ve, u, tol;
    r.p = data;
    r.n = size;
    r.i = 0;
    djl_params_default(&p);
    p.profile = 1 + rd_u8(&r) % 3;
    if (rd_u8(&r) == 255) p.profile = (int32_t)rd_u32(&r);
    p.short_stage = 1 + rd_u8(&r) % 2;
    /* each field: the default, or a value read */
    if (rd_u8(&r) & 1) p.Te = rd_mag(&r);
    if (rd_u8(&r) & 1) p.x0 = rd_double(&r);
    if (rd_u8(&r) & 1) p.v0 = rd_double(&r);
    if (rd_u8(&r) & 1) p.distance = rd_mag(&r) * (rd_u8(&r) & 1 ? -1.0 : 1.0);
    if (rd_u8(&r) & 1) p.v_e = rd_double(&r);
    if (rd_u8(&r) & 1) p.v_max = rd_mag(&r);
    if (rd_u8(&r) & 1) p.a_max = rd_mag(&r);
    if (rd_u8(&r) & 1) p.d_max = rd_mag(&r);
    for (i = 0; i < 4; i++)
        if (rd_u8(&r) & 1) p.T_F[i] = rd_u8(&r) & 1 ? p.Te * (double)(1 + rd_u8(&r)) : rd_mag(&r);
    n = rd_u8(&r) % 40;
    p.n_segments = n <= DJL_MAX_SEGMENTS + 1 ? n : 0;
    for (i = 0; i < p.n_segments && i < DJL_MAX_SEGMENTS; i++) {
        p.seg_distance[i] = rd_double(&r);
        p.seg_v_end[i] = rd_u8(&r) & 1 ? 0.0 : rd_double(&r);
    }
    if (getenv("FUZZ_VERBOSE")) {
        fprintf(stderr, "profile %d short_stage %d Te %.17g x0 %.17g v0 %.17g distance %.17g "
                "v_e %.17g v_max %.17g a_max %.17g d_max %.17g T_F %.17g %.17g %.17g %.17g "
                "n_segments %d\n", (int)p.profile, (int)p.short_stage, p.Te, p.x0, p.v0,
                p.distance, p.v_e, p.v_max, p.a_max, p.d_max, p.T_F[0], p.T_F[1], p.T_F[2],
                p.T_F[3], (int)p.n_segments);
        for (i = 0; i < p.n_segments; i++)
            fprintf(stderr, "  segment %d: %.17g m, v_end %.17g\n", i, p.seg_distance[i],
                    p.seg_v_end[i]);
    }
    st = djl_plan_motion(&p, &plan, &e);
    if (getenv("FUZZ_VERBOSE")) fprintf(stderr, "status %d: %s\n", (int)st, e.message);
    if (st != DJL_OK) {
        check_refusal(st, &e, "plan");
        return 0;
    }
    check_pieces(&plan, "plan");
    if (p.n_segments == 0) {
        D = p.distance;
        Dabs = fabs(D);
        ve = p.v_e;
    } else {
        for (i = 0; i < p.n_segments; i++) {
            D += p.seg_distance[i];
            Dabs += fabs(p.seg_distance[i]);
        }
        ve = p.seg_v_end[p.n_segments - 1];
    }
    djl_eval(&plan, (double)plan.k_end, &cur, &s);
    FUZZ_CHECK(s.done, "not done at k_end");
    FUZZ_CHECK(fabs(s.x - (p.x0 + D)) <= 1e-9 * fmax(Dabs, p.v_max * p.Te) + 4e-16 * fabs(p.x0),
               "plan ends at %.17g, not %.17g", s.x, p.x0 + D);
    FUZZ_CHECK(fabs(s.v - ve) <= 1e-12 * fmax(p.v_max, 1.0) && fabs(s.a) <= 1e-12 * fmax(p.a_max, 1.0),
               "plan ends at v %.17g a %.17g, not v %.17g", s.v, s.a, ve);
    if (!rd_more(&r) || ve != 0.0) return 0;
    /* a command at u samples */
    u = (double)plan.k_end * (rd_u8(&r) / 255.0) * (rd_u8(&r) & 1 ? 1.0 : 1.2);
    if (rd_u8(&r) & 1) u = floor(u);
    memset(&g, 0, sizeof g);
    g.kind = rd_u8(&r) % 4 == 0 ? DJL_GOAL_STOP : DJL_GOAL_TARGET;
    g.target = p.x0 + D * (rd_u8(&r) / 64.0 - 2.0);
    if (rd_u8(&r) % 4 == 0) g.target = rd_double(&r);
    for (i = 0; i < 4; i++) g.N[i] = plan.N[i];
    if (p.profile != DJL_PROFILE_AL && rd_u8(&r) % 4 == 0)
        for (i = 0; i < 4; i++) g.N[i] = 1 + rd_u8(&r) % 64;
    g.keep_speed = rd_u8(&r) & 1;
    g.no_stop_first = rd_u8(&r) % 4 == 0;
    if (getenv("FUZZ_VERBOSE"))
        fprintf(stderr, "replan at u = %.17g samples (k_end %lld): %s %.17g, N %d %d %d %d, "
                "keep_speed %d, no_stop_first %d\n", u, (long long)plan.k_end,
                g.kind == DJL_GOAL_STOP ? "stop" : "target", g.target, (int)g.N[0], (int)g.N[1],
                (int)g.N[2], (int)g.N[3], (int)g.keep_speed, (int)g.no_stop_first);
    cur = 0;
    djl_eval(&plan, u, &cur, &s);
    st = djl_replan(&plan, u, &g, &out, &scratch, &info, &e);
    if (st != DJL_OK) {
        check_refusal(st, &e, "replan");
        return 0;
    }
    check_pieces(&out, "replan");
    /* the positions involved: the target, where the command came, the planned ones, and
     * every one the new motion passes (a stage ended with a long jerk time may carry the
     * axis far out before it comes back: fourth session, 3e7 m out for a 0.56 m target) */
    tol = fabs(g.target) + fabs(s.x) + fabs(p.x0) + Dabs + fmax(out.v_reached, fabs(s.v)) * p.Te;
    for (i = 0; i < out.n_pieces; i++) tol = fmax(tol, fabs(p.x0) + fabs(out.piece[i].x));
    cur = 0;
    djl_eval(&out, (double)out.k_end, &cur, &s);
    FUZZ_CHECK(s.done && s.v == 0.0 && s.a == 0.0, "replan ends at v %.17g a %.17g", s.v, s.a);
    /* a distance below the normal doubles is no move (docs/generator.md, "Limits of the
     * parameters"): a target that close to the rest is arrived */
    if (g.kind == DJL_GOAL_TARGET)
        FUZZ_CHECK(fabs(s.x - g.target) <= fmax(1e-9 * tol, DJL_MIN_MAGNITUDE),
                   "replan ends at %.17g, not %.17g (%g)", s.x, g.target, tol);
    return 0;
}
