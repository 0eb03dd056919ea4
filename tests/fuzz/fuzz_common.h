/* fuzz_common.h -- what the fuzz harnesses of tests/fuzz/ share: a reader that decodes
 * the fuzzer's bytes into choices and values (running out of bytes reads zeros), the
 * invariant check that stops the run, and the table of interesting numbers. */
#ifndef FUZZ_COMMON_H
#define FUZZ_COMMON_H

#include <float.h>
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A broken invariant is a crash: libFuzzer / AFL++ keep the input, the replay driver
 * fails. */
#define FUZZ_CHECK(cond, ...)                                                                    \
    do {                                                                                         \
        if (!(cond)) {                                                                           \
            fprintf(stderr, "fuzz invariant broken at %s:%d: ", __FILE__, __LINE__);             \
            fprintf(stderr, __VA_ARGS__);                                                        \
            fputc('\n', stderr);                                                                 \
            abort();                                                                             \
        }                                                                                        \
    } while (0)

typedef struct {
    const uint8_t *p;
    size_t n, i;
} fuzz_reader;

static inline uint8_t rd_u8(fuzz_reader *r) { return r->i < r->n ? r->p[r->i++] : 0; }

static inline int rd_more(const fuzz_reader *r) { return r->i < r->n; }

static inline uint32_t rd_u32(fuzz_reader *r)
{
    uint32_t v = 0;
    int k;
    for (k = 0; k < 4; k++) v = (v << 8) | rd_u8(r);
    return v;
}

static inline double rd_raw_double(fuzz_reader *r)
{
    uint64_t u = 0;
    double d;
    int k;
    for (k = 0; k < 8; k++) u = (u << 8) | rd_u8(r);
    memcpy(&d, &u, sizeof d);
    return d;
}

/* Values that matter to the FMU: its defaults and limits, the cases of issue 21, the
 * edges of the doubles. */
static const double fuzz_values[] = {
    0.0, 1.0, -1.0, 0.4, 0.3, -0.2, 0.5, 2.0, 10.0, 1e-3, 2e-3, 1e-4, 5e-4, 0.1, 0.05, 0.11,
    0.02, 0.005, 7e-4, 16.0, 3.4e9, 6e11, 1e300, -1e300, 1e-300, 1e15, 1e14, 1e8, 1e-12,
    1e-9, 2.2250738585072014e-308, 4.9e-324, 1.7976931348623157e308, -1.7976931348623157e308,
    1e-30, 1e30, 9.0, 12.0, 0.25, 1.5e-3, 1.7e9, -0.05, 3.0, 4.0, 0.999, 1.0 / 3.0, 0.1234567,
    100.0, 1e6};

static inline double rd_double(fuzz_reader *r)
{
    uint8_t k = rd_u8(r);
    size_t n = sizeof fuzz_values / sizeof fuzz_values[0];
    if (k < 2 * n) return fuzz_values[k % n] * (k >= n ? -1.0 : 1.0);
    if (k < 240) return (double)(k - 2 * n) * 0.01;
    if (k == 250) return NAN;
    if (k == 251) return INFINITY;
    if (k == 252) return -INFINITY;
    return rd_raw_double(r);
}

#endif
