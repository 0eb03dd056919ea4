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

/* The bytes of model_data a state holds before the live entries of the shaper's rings
 * (see "FMU state" below). */
#define PACK_HEAD (offsetof(model_data, mem) + offsetof(djl_shaper_memory, past))

/* A fresh state: the header, state Instantiated, the model's start values.  Zeroed up to
 * the rings' entries, padding included (a state is checksummed whole); the entries are
 * never read beyond the rings' counts, so the rest is not touched (263 kB of an
 * instance's 322 kB: memory the importer's calloc gave and that stays unmapped until a
 * shaper uses it). */
static void defaults(model_data *d)
{
    memset(d, 0, PACK_HEAD);
    d->magic = MODEL_MAGIC;
    d->layout = MODEL_LAYOUT;
    d->size = 0; /* in a saved state: its size in bytes (model_state_pack) */
    strncpy(d->token, DJL_INSTANTIATION_TOKEN, sizeof(d->token) - 1);
    d->state = MS_INSTANTIATED;
    model_defaults(d);
}

void model_init(model_instance *m, int fmi_version, const char *instance_name,
                model_logger logger, void *logger_env, int logging_on,
                void *(*alloc)(size_t n, size_t size), void (*release)(void *p))
{
    int i;
    defaults(&m->d);
    memset(&m->w, 0, sizeof m->w); /* every field but the rings' entries */
    m->load = NULL;
    m->alloc = alloc;
    m->release = release;
    m->fmi_version = fmi_version;
    strncpy(m->instance_name, instance_name ? instance_name : "", sizeof(m->instance_name));
    m->instance_name[sizeof(m->instance_name) - 1] = '\0';
    m->logger = logger;
    m->logger_env = logger_env;
    m->logging_on = logging_on;
    for (i = 0; i < DJL_LOG_N; i++) m->category_on[i] = 1;
}

void model_reset(model_instance *m) { defaults(&m->d); }

void model_free(model_instance *m)
{
    if (m->load) m->release(m->load);
    m->load = NULL;
}

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

/* A state is packed: the bytes of model_data up to the entries of the shaper's rings
 * (the header, the model's values, the rings' counts), then the live entries of each
 * ring in time order (a ring packed starts at 0: past_first = phase_first = 0).  The
 * rings take 263 kB of model_data and hold a few entries at most times (none without a
 * shaper; a piece of a replaced plan, a change of f_mode, within the shaper's window), so
 * a state is about 30 kB; 293 kB with both rings full. */
#define PAST_BYTES sizeof(djl_past_piece)
#define PHASE_BYTES sizeof(djl_phase_point)
#define MEM_FIELD(f) (offsetof(model_data, mem) + offsetof(djl_shaper_memory, f))

/* model_state_checksum reads whole words: the checksum is one of them, a state all of them. */
typedef char model_state_words_check[(offsetof(model_data, checksum) % 8 == 0 &&
                                      PACK_HEAD % 8 == 0 && PAST_BYTES % 8 == 0 &&
                                      PHASE_BYTES % 8 == 0) ? 1 : -1];

size_t model_state_size(const model_data *d)
{
    return PACK_HEAD + (size_t)d->mem.n_past * PAST_BYTES + (size_t)d->mem.n_phase * PHASE_BYTES;
}

size_t model_state_max_size(void) { return PACK_HEAD + DJL_SHAPER_RING * (PAST_BYTES + PHASE_BYTES); }

static uint32_t read_u32(const void *state, size_t at)
{
    uint32_t x;
    memcpy(&x, (const unsigned char *)state + at, 4);
    return x;
}

size_t model_state_stored_size(const void *state) { return read_u32(state, offsetof(model_data, size)); }

/* The checksum of a packed state: its 8-byte words but the checksum itself (the padding
 * of model_data included: it is zeroed before use and copied whole), in eight lanes (word
 * k to lane k % 8), each lane a chain of steps
 *     h <- rotl((h ^ w) * P, 29),   P the 64-bit FNV prime,
 * the lanes folded into one by the same step, and the result avalanched (xxHash64's
 * finaliser).  Each step is a bijection of h and of w (xor, an odd multiply, a rotation),
 * and a word reaches one lane only, so a change of any one word always changes the
 * checksum.  The rotation is what FNV-1a alone lacked (issue 39, finding C): with
 * h <- (h ^ w) * P a flipped bit 63 stays bit 63 through every step (2^63 P = 2^63 mod
 * 2^64), so two such flips cancelled; rotated down to bit 28, it is spread by the next
 * multiply.  Eight lanes, not four: the rotation lengthens each lane's chain, eight keep
 * the multiplier busy (layout 11; 7 to 10 had four FNV-1a lanes, 6 one).  Any alignment. */
#define SUM_BASIS 0xcbf29ce484222325u
#define SUM_PRIME 0x100000001b3u
#define SUM_STEP(h, w) ((h) = rotl64(((h) ^ (w)) * SUM_PRIME))
static uint64_t rotl64(uint64_t x) { return (x << 29) | (x >> 35); }
/* the word at byte i of a state, the checksum's own read as 0 */
static uint64_t state_word(const unsigned char *b, size_t i)
{
    uint64_t w;
    memcpy(&w, b + i, 8);
    return i == offsetof(model_data, checksum) ? 0 : w;
}

uint64_t model_state_checksum(const void *state, size_t size)
{
    const unsigned char *b = (const unsigned char *)state;
    uint64_t h0 = SUM_BASIS, h1 = SUM_BASIS + 1, h2 = SUM_BASIS + 2, h3 = SUM_BASIS + 3;
    uint64_t h4 = SUM_BASIS + 4, h5 = SUM_BASIS + 5, h6 = SUM_BASIS + 6, h7 = SUM_BASIS + 7;
    uint64_t h;
    size_t i;
    for (i = 0; i + 64 <= size; i += 64) {
        if (i >= 64) break; /* the first group holds the checksum's own word: read as 0 */
        SUM_STEP(h0, state_word(b, i));
        SUM_STEP(h1, state_word(b, i + 8));
        SUM_STEP(h2, state_word(b, i + 16));
        SUM_STEP(h3, state_word(b, i + 24));
        SUM_STEP(h4, state_word(b, i + 32));
        SUM_STEP(h5, state_word(b, i + 40));
        SUM_STEP(h6, state_word(b, i + 48));
        SUM_STEP(h7, state_word(b, i + 56));
    }
    for (; i + 64 <= size; i += 64) { /* the other groups: plain words */
        uint64_t w[8];
        memcpy(w, b + i, 64);
        SUM_STEP(h0, w[0]);
        SUM_STEP(h1, w[1]);
        SUM_STEP(h2, w[2]);
        SUM_STEP(h3, w[3]);
        SUM_STEP(h4, w[4]);
        SUM_STEP(h5, w[5]);
        SUM_STEP(h6, w[6]);
        SUM_STEP(h7, w[7]);
    }
    for (; i + 8 <= size; i += 8) SUM_STEP(h0, state_word(b, i));
    h = SUM_BASIS ^ (uint64_t)size; /* the lanes folded, the size with them */
    SUM_STEP(h, h0);
    SUM_STEP(h, h1);
    SUM_STEP(h, h2);
    SUM_STEP(h, h3);
    SUM_STEP(h, h4);
    SUM_STEP(h, h5);
    SUM_STEP(h, h6);
    SUM_STEP(h, h7);
    h ^= h >> 33; /* avalanche */
    h *= 0xc2b2ae3d27d4eb4fu;
    h ^= h >> 29;
    h *= 0x165667b19e3779f9u;
    return h ^ (h >> 32);
}

void model_state_seal(void *state, size_t size)
{
    uint64_t h = model_state_checksum(state, size);
    memcpy((unsigned char *)state + offsetof(model_data, checksum), &h, 8);
}

void model_state_pack(const model_data *d, void *state)
{
    unsigned char *b = (unsigned char *)state;
    size_t at = PACK_HEAD, size = model_state_size(d);
    uint32_t size32 = (uint32_t)size;
    int32_t i, zero = 0;
    memcpy(b, d, PACK_HEAD);
    memcpy(b + offsetof(model_data, size), &size32, 4);
    memcpy(b + MEM_FIELD(past_first), &zero, 4);
    memcpy(b + MEM_FIELD(phase_first), &zero, 4);
    for (i = 0; i < d->mem.n_past; i++, at += PAST_BYTES)
        memcpy(b + at, &d->mem.past[(d->mem.past_first + i) % DJL_SHAPER_RING], PAST_BYTES);
    for (i = 0; i < d->mem.n_phase; i++, at += PHASE_BYTES)
        memcpy(b + at, &d->mem.phase[(d->mem.phase_first + i) % DJL_SHAPER_RING], PHASE_BYTES);
    model_state_seal(b, size);
}

/* The rings' entries of a packed state (counts checked) into d, after its head. */
static void unpack_entries(const unsigned char *b, model_data *d)
{
    size_t past = (size_t)d->mem.n_past * PAST_BYTES;
    memcpy(d->mem.past, b + PACK_HEAD, past);
    memcpy(d->mem.phase, b + PACK_HEAD + past, (size_t)d->mem.n_phase * PHASE_BYTES);
}

void model_state_unpack(const void *state, model_data *d)
{
    memcpy(d, state, PACK_HEAD);
    unpack_entries((const unsigned char *)state, d);
}

/* All the checks of a packed state of size bytes, which is unpacked into m->load (no
 * copy of a state on the stack: a state is 30 to 293 kB, more than the whole stack of a
 * thread in some importers; musl's default is 128 kB, and a copy on the stack here once
 * overflowed it).  m->load is allocated at the first check (an instance that never
 * restores a state does not carry its 293 kB). */
static model_status verify(model_instance *m, const char *fn, const unsigned char *b, size_t size)
{
    const char *flaw;
    char why[128], token[sizeof m->d.token];
    int32_t n_past, n_phase, past_first, phase_first;
    uint32_t stated;
    uint64_t sum;
    if (size < PACK_HEAD)
        return model_refuse(m, "%s: FMU state of %lu bytes, too short for a state of this FMU "
                            "(at least %lu: made by another version of the FMU?)", fn,
                            (unsigned long)size, (unsigned long)PACK_HEAD);
    if (read_u32(b, offsetof(model_data, magic)) != MODEL_MAGIC)
        return model_refuse(m, "%s: not a state of this FMU (bad header)", fn);
    if (read_u32(b, offsetof(model_data, layout)) != MODEL_LAYOUT)
        return model_refuse(m, "%s: a state of layout %lu, this FMU reads layout %lu (bad "
                            "header: made by another version of the FMU)", fn,
                            (unsigned long)read_u32(b, offsetof(model_data, layout)),
                            (unsigned long)MODEL_LAYOUT);
    stated = read_u32(b, offsetof(model_data, size));
    if (stated != size)
        return model_refuse(m, "%s: FMU state of %lu bytes, its header says %lu (truncated or "
                            "extended?)", fn, (unsigned long)size, (unsigned long)stated);
    memcpy(token, b + offsetof(model_data, token), sizeof token);
    if (memchr(token, '\0', sizeof token) == NULL || strcmp(token, DJL_INSTANTIATION_TOKEN) != 0)
        return model_refuse(m, "%s: FMU state made by an FMU with another instantiation token "
                            "(%.40s), this one is %s", fn, token, DJL_INSTANTIATION_TOKEN);
    memcpy(&sum, b + offsetof(model_data, checksum), 8);
    if (sum != model_state_checksum(b, size))
        return model_refuse(m, "%s: FMU state damaged (checksum mismatch): refused", fn);
    memcpy(&n_past, b + MEM_FIELD(n_past), 4);
    memcpy(&n_phase, b + MEM_FIELD(n_phase), 4);
    memcpy(&past_first, b + MEM_FIELD(past_first), 4);
    memcpy(&phase_first, b + MEM_FIELD(phase_first), 4);
    if (n_past < 0 || n_past > DJL_SHAPER_RING || n_phase < 0 || n_phase > DJL_SHAPER_RING ||
        past_first != 0 || phase_first != 0 ||
        PACK_HEAD + (size_t)n_past * PAST_BYTES + (size_t)n_phase * PHASE_BYTES != size)
        return model_refuse(m, "%s: FMU state refused: its size (%lu bytes) is not that of its "
                            "shaper memory (%ld and %ld entries, from %ld and %ld)", fn,
                            (unsigned long)size, (long)n_past, (long)n_phase, (long)past_first,
                            (long)phase_first);
    if (!m->load) {
        m->load = (model_data *)m->alloc(1, sizeof(model_data));
        if (!m->load) return model_refuse(m, "%s: out of memory (checking an FMU state)", fn);
    }
    model_state_unpack(b, m->load);
    if (m->load->state != MS_INSTANTIATED && m->load->state != MS_INIT &&
        m->load->state != MS_STEP && m->load->state != MS_TERMINATED) {
        snprintf(why, sizeof why, "state machine value %ld is not one a state can be saved in",
                 (long)m->load->state);
        flaw = why;
    } else {
        flaw = model_state_flaw(m->load);
    }
    if (flaw) return model_refuse(m, "%s: FMU state refused: %s", fn, flaw);
    return ST_OK;
}

model_status model_state_check(model_instance *m, const char *fn, const void *state)
{
    if (!state) return model_null_arg(m, fn, "FMU state");
    if (read_u32(state, offsetof(model_data, magic)) != MODEL_MAGIC ||
        read_u32(state, offsetof(model_data, layout)) != MODEL_LAYOUT ||
        model_state_stored_size(state) > model_state_max_size())
        return model_refuse(m, "%s: not a state of this FMU (bad header)", fn);
    return verify(m, fn, (const unsigned char *)state, model_state_stored_size(state));
}

model_status model_state_load(model_instance *m, const char *fn, const void *bytes, size_t size)
{
    if (!bytes) return model_null_arg(m, fn, "serializedState");
    return verify(m, fn, (const unsigned char *)bytes, size);
}

void model_state_restore(model_instance *m)
{
    memcpy(&m->d, m->load, PACK_HEAD);
    memcpy(m->d.mem.past, m->load->mem.past, (size_t)m->load->mem.n_past * PAST_BYTES);
    memcpy(m->d.mem.phase, m->load->mem.phase, (size_t)m->load->mem.n_phase * PHASE_BYTES);
}
