/*
 * fmu_instance.c -- the FMU instance, independent of the FMI version and of
 * the model: state machine, logging, checks of calls and arguments, the
 * variable table, FMU state (checksum, validation of its header).  The model
 * (fmu_model.c) provides its start values, its part of a state's validation
 * and what happens at the end of initialisation.
 */
#define DJL_VARS_TABLES
#include "fmu_instance.h"

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
/* logging                                                                  */

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

int model_allowed(model_instance *m, const char *fn, int mask)
{
    if (m->d.state & mask) return 1;
    model_fail(m, "%s must not be called in state %s", fn, model_state_name(m->d.state));
    return 0;
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
/* life cycle and state machine                                             */

/* A fresh state: the header, state Instantiated, the model's start values. */
static void defaults(model_data *d)
{
    memset(d, 0, sizeof(*d)); /* padding included: a state is checksummed whole */
    d->magic = MODEL_MAGIC;
    d->layout = MODEL_LAYOUT;
    d->size = (uint32_t)sizeof(model_data);
    strncpy(d->token, DJL_INSTANTIATION_TOKEN, sizeof(d->token) - 1);
    d->state = MS_INSTANTIATED;
    model_defaults(d);
}

void model_init(model_instance *m, int fmi_version, const char *instance_name,
                model_logger logger, void *logger_env, int logging_on)
{
    int i;
    memset(m, 0, sizeof(*m));
    defaults(&m->d);
    m->fmi_version = fmi_version;
    strncpy(m->instance_name, instance_name ? instance_name : "", sizeof(m->instance_name) - 1);
    m->logger = logger;
    m->logger_env = logger_env;
    m->logging_on = logging_on;
    for (i = 0; i < DJL_LOG_N; i++) m->category_on[i] = 1;
}

void model_reset(model_instance *m) { defaults(&m->d); }

model_status model_enter_init(model_instance *m)
{
    m->d.state = MS_INIT;
    return ST_OK;
}

model_status model_exit_init(model_instance *m)
{
    model_status st = model_start(m);
    if (st != ST_OK) return st;
    m->d.state = MS_STEP;
    return ST_OK;
}

model_status model_terminate(model_instance *m)
{
    m->d.state = MS_TERMINATED;
    return ST_OK;
}

/* ------------------------------------------------------------------------ */
/* variables                                                                */

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

/* ------------------------------------------------------------------------ */
/* FMU state                                                                */

size_t model_state_size(void) { return sizeof(model_data); }

/* model_state_checksum reads whole words: the checksum is one of them, the state all of them. */
typedef char model_state_words_check[(offsetof(model_data, checksum) % 8 == 0 &&
                                      sizeof(model_data) % 8 == 0) ? 1 : -1];

/* 64-bit FNV-1a over the 8-byte words of the state but the checksum itself (the padding is
 * included: model_data is zeroed before use and copied whole), a word at a time: each step
 * (h ^ w) * prime is a bijection of h and of w, so a change of any one word always changes
 * the checksum.  Word-wise, because the state holds the shaper's memory (about 260 kB). */
uint64_t model_state_checksum(const model_data *d)
{
    const unsigned char *b = (const unsigned char *)d;
    size_t i, skip = offsetof(model_data, checksum);
    uint64_t h = 0xcbf29ce484222325u, w;
    for (i = 0; i + 8 <= sizeof(model_data); i += 8) {
        if (i == skip) continue;
        memcpy(&w, b + i, 8);
        h ^= w;
        h *= 0x100000001b3u;
    }
    return h;
}

void model_state_seal(model_data *d) { d->checksum = model_state_checksum(d); }

model_status model_state_check(model_instance *m, const char *fn, const void *bytes, size_t size)
{
    model_data d;
    const char *flaw;
    char why[128];
    if (!bytes) return model_null_arg(m, fn, "FMU state");
    if (size != sizeof(model_data))
        return model_refuse(m, "%s: FMU state of %lu bytes, expected %lu (made by another version "
                            "of the FMU?)", fn, (unsigned long)size,
                            (unsigned long)sizeof(model_data));
    memcpy(&d, bytes, sizeof d);
    if (d.magic != MODEL_MAGIC || d.layout != MODEL_LAYOUT || d.size != sizeof(model_data))
        return model_refuse(m, "%s: not a state of this FMU (bad header)", fn);
    if (memchr(d.token, '\0', sizeof d.token) == NULL ||
        strcmp(d.token, DJL_INSTANTIATION_TOKEN) != 0)
        return model_refuse(m, "%s: FMU state made by an FMU with another instantiation token "
                            "(%.40s), this one is %s", fn, d.token, DJL_INSTANTIATION_TOKEN);
    if (d.checksum != model_state_checksum(&d))
        return model_refuse(m, "%s: FMU state damaged (checksum mismatch): refused", fn);
    if (d.state != MS_INSTANTIATED && d.state != MS_INIT && d.state != MS_STEP &&
        d.state != MS_TERMINATED) {
        snprintf(why, sizeof why, "state machine value %ld is not one a state can be saved in",
                 (long)d.state);
        flaw = why;
    } else {
        flaw = model_state_flaw(&d);
    }
    if (flaw) return model_refuse(m, "%s: FMU state refused: %s", fn, flaw);
    return ST_OK;
}
