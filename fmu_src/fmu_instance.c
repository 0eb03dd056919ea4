/*
 * fmu_instance.c -- the FMU instance, independent of the FMI version: its life
 * cycle (start values, reset), the state machine and the check of each call
 * against it, and the FMU state (size, checksum, seal, the checks of a state:
 * size, header, token, checksum, state machine value).  It sits over the model
 * (fmu_model.h), which provides its start values, its part of a state's
 * validation and what happens at the end of initialisation; logging, error
 * reporting and the variable table are the base's (fmu_base.c).
 */
#include "fmu_instance.h"

#include <stdio.h>
#include <string.h>

/* ------------------------------------------------------------------------ */
/* life cycle and state machine                                             */

int model_allowed(model_instance *m, const char *fn, int mask)
{
    if (m->d.state & mask) return 1;
    model_fail(m, "%s must not be called in state %s", fn, model_state_name(m->d.state));
    return 0;
}

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

/* In place, with no copy: a state is about 290 kB, more than the whole stack of a thread
 * in some importers (musl's default is 128 kB; a copy on the stack here once overflowed
 * it). */
model_status model_state_check(model_instance *m, const char *fn, const model_data *d)
{
    const char *flaw;
    char why[128];
    if (!d) return model_null_arg(m, fn, "FMU state");
    if (d->magic != MODEL_MAGIC || d->layout != MODEL_LAYOUT || d->size != sizeof(model_data))
        return model_refuse(m, "%s: not a state of this FMU (bad header)", fn);
    if (memchr(d->token, '\0', sizeof d->token) == NULL ||
        strcmp(d->token, DJL_INSTANTIATION_TOKEN) != 0)
        return model_refuse(m, "%s: FMU state made by an FMU with another instantiation token "
                            "(%.40s), this one is %s", fn, d->token, DJL_INSTANTIATION_TOKEN);
    if (d->checksum != model_state_checksum(d))
        return model_refuse(m, "%s: FMU state damaged (checksum mismatch): refused", fn);
    if (d->state != MS_INSTANTIATED && d->state != MS_INIT && d->state != MS_STEP &&
        d->state != MS_TERMINATED) {
        snprintf(why, sizeof why, "state machine value %ld is not one a state can be saved in",
                 (long)d->state);
        flaw = why;
    } else {
        flaw = model_state_flaw(d);
    }
    if (flaw) return model_refuse(m, "%s: FMU state refused: %s", fn, flaw);
    return ST_OK;
}

model_status model_state_check_size(model_instance *m, const char *fn, size_t size)
{
    if (size != sizeof(model_data))
        return model_refuse(m, "%s: FMU state of %lu bytes, expected %lu (made by another version "
                            "of the FMU?)", fn, (unsigned long)size,
                            (unsigned long)sizeof(model_data));
    return ST_OK;
}

model_status model_state_load(model_instance *m, const char *fn, const void *bytes, size_t size,
                              model_data *into)
{
    model_status st;
    if (!bytes) return model_null_arg(m, fn, "serializedState");
    if ((st = model_state_check_size(m, fn, size)) != ST_OK) return st;
    memcpy(into, bytes, sizeof(model_data));
    return model_state_check(m, fn, into);
}
