/*
 * core_libm.c -- the planner of fmu_src/djl_*.c compiled with libm's math
 * (-DDJL_USE_LIBM: djl_math.h maps djl_floor to floor, ...), its functions
 * renamed libm_djl_*, so that tests/c/test_plan_libm.c can link it beside the
 * FMU's own core and compare their plans.  (A function added to the core's
 * interface and not renamed here makes the link fail: add it below.)  The
 * core's files are compiled here as one unit, the functions they share
 * (DJL_INTERNAL, djl_internal.h) made static: they do not clash with the
 * FMU's own core's.
 */
#define DJL_USE_LIBM
#define djl_status_name libm_djl_status_name
#define djl_params_default libm_djl_params_default
#define djl_validate libm_djl_validate
#define djl_plan_motion libm_djl_plan_motion
#define djl_eval libm_djl_eval
#define djl_eval_left libm_djl_eval_left
#define djl_applied_jerk_time libm_djl_applied_jerk_time
#define djl_motion_time libm_djl_motion_time
#define djl_replan libm_djl_replan
#define djl_jerk_times_due libm_djl_jerk_times_due
#define djl_check_t_start libm_djl_check_t_start
#define djl_start_offset libm_djl_start_offset

#define DJL_INTERNAL static

#include "djl_validate.c"
#include "djl_segment.c"
#include "djl_motion.c"
#include "djl_replan.c"
#include "djl_eval.c"
