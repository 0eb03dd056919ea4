/*
 * fmu_base.c -- the base of the FMU (fmu_base.h), below the model and the
 * instance: the names of the states, logging and error reporting (the
 * importer's callback, the debug-logging categories, the errors that move the
 * instance to Error or leave it as it was), and the lookup of value references
 * in the variable table (djl_vars.h).  It knows nothing of the model's
 * variables, planning or FMU state.
 */
#define DJL_VARS_TABLES
#include "fmu_base.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

const char *model_state_name(int s)
{
    switch (s) {
    case MS_START_END: return "StartAndEnd";
    case MS_INSTANTIATED: return "Instantiated";
    case MS_INIT: return "InitializationMode";
    case MS_STEP: return "StepMode";
    case MS_TERMINATED: return "Terminated";
    case MS_ERROR: return "Error";
    }
    return "?";
}

/* ------------------------------------------------------------------------ */
/* logging and error reporting                                              */

static const char *status_category(model_status s)
{
    if (s >= ST_ERROR) return djl_log_category_names[DJL_LOG_LOGSTATUSERROR];
    if (s == ST_WARNING) return djl_log_category_names[DJL_LOG_LOGSTATUSWARNING];
    return djl_log_category_names[DJL_LOG_LOGEVENTS];
}

static void vlog(const model_instance *m, model_status status, int category, const char *fmt,
                 va_list ap)
{
    char buf[1024];
    if (!m->logger) return;
    if (status < ST_ERROR) {
        if (!m->logging_on) return;
        if (category >= 0 && category < DJL_LOG_N && !m->category_on[category]) return;
    }
    vsnprintf(buf, sizeof buf, fmt, ap);
    m->logger(m->logger_env, status,
              category >= 0 && category < DJL_LOG_N ? djl_log_category_names[category]
                                                    : status_category(status),
              buf);
}

void model_log(const model_instance *m, model_status status, int category, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vlog(m, status, category, fmt, ap);
    va_end(ap);
}

model_status model_fail(model_instance *m, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vlog(m, ST_ERROR, DJL_LOG_LOGSTATUSERROR, fmt, ap);
    va_end(ap);
    m->d.state = MS_ERROR;
    return ST_ERROR;
}

model_status model_refuse(model_instance *m, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vlog(m, ST_ERROR, DJL_LOG_LOGSTATUSERROR, fmt, ap);
    va_end(ap);
    return ST_ERROR;
}

model_status model_null_arg(model_instance *m, const char *fn, const char *arg)
{
    return model_refuse(m, "%s: argument %s is a null pointer (nothing was read or written)", fn,
                        arg);
}

model_status model_set_debug_logging(model_instance *m, const char *fn, int logging_on, size_t n,
                                     const char *const categories[])
{
    size_t i;
    int c;
    if (n > 0 && !categories) return model_null_arg(m, fn, "categories");
    for (i = 0; i < n; i++)
        if (!categories[i])
            return model_refuse(m, "%s: categories[%lu] is a null pointer (nothing was changed)",
                                fn, (unsigned long)i);
    m->logging_on = logging_on;
    if (n == 0) {
        for (c = 0; c < DJL_LOG_N; c++) m->category_on[c] = logging_on;
        return ST_OK;
    }
    for (c = 0; c < DJL_LOG_N; c++) m->category_on[c] = 0;
    for (i = 0; i < n; i++) {
        int found = 0;
        for (c = 0; c < DJL_LOG_N; c++) {
            if (strcmp(categories[i], djl_log_category_names[c]) == 0) {
                m->category_on[c] = logging_on;
                found = 1;
            }
        }
        if (!found) {
            model_log(m, ST_WARNING, DJL_LOG_LOGSTATUSWARNING,
                      "%s: unknown log category \"%s\"", fn, categories[i]);
            return ST_WARNING;
        }
    }
    return ST_OK;
}

/* ------------------------------------------------------------------------ */
/* the variable table                                                       */

int model_lookup(unsigned int vr, int fmi3, model_var *out)
{
    int i;
    for (i = 0; i < DJL_N_VARS; i++) {
        const djl_var_info *v = &djl_var_table[i];
        unsigned int span = fmi3 ? 1u : v->size;
        if (vr >= v->vr && vr < v->vr + span) {
            out->base = v->vr;
            out->index = vr - v->vr;
            out->type = v->type == 'E' ? 'I' : v->type;
            out->enumeration = v->type == 'E';
            out->causality = v->causality;
            out->size = v->size;
            out->name = v->name;
            return 1;
        }
    }
    return 0;
}

const char *model_type_name(char t)
{
    return t == 'R' ? "Real" : t == 'I' ? "Integer" : t == 'B' ? "Boolean" : "?";
}
