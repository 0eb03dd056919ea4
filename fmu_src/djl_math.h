/*
 * djl_math.h -- the libm functions the FMU's C sources use, without libm.
 *
 * Why: an importer may rebuild the FMU from its sources/ folder, and fmpy
 * 0.3.32 (`fmpy compile`) does so with a CMake file that links no library:
 * it reads no <Library> of an FMI 3 build description, and FMI 2 cannot name
 * one at all.  On glibc, floor, sqrt, exp2 ... live in libm.so.6, so such a
 * binary fails to load with dlopen(RTLD_NOW) into a program that has not
 * loaded libm itself ("undefined symbol: ceil").  The sources therefore call
 * these static inline functions instead, built from integer operations on the
 * IEEE 754 binary64 encoding (C99, no allocation, no __int128, no fma, no
 * compiler builtin), which compile the same on gcc, clang and MSVC:
 *
 *  - exactly specified by IEEE 754 / C99 Annex F, and bit for bit glibc's
 *    (x86-64) results, NaNs included: fabs, isfinite, floor, ceil, trunc,
 *    fmax, fmin, nextafter, ldexp (= scalbn, subnormal results rounded once,
 *    overflow to infinity), frexp, ilogb, and sqrt.  sqrt is correctly
 *    rounded: the 53-bit significand (times 2^54, a 108-bit radicand held in
 *    two uint64_t) has its integer square root taken bit by bit, 54 bits, and
 *    the remainder says on which side of the halfway point the exact root
 *    lies (round to nearest, ties to even);
 *  - hypot: correctly rounded the same way, the exact sum of the two squares
 *    being the radicand (glibc's is within 1 ulp: the two differ where
 *    glibc's is not correctly rounded);
 *  - exp2: exact for integer arguments; otherwise 2^(k + j/64 + r), |r| <=
 *    1/128, from a table of 2^(j/64) to 2^-78 and a degree-7 polynomial of
 *    e^(r ln 2), the products that matter split so that each is exact (no
 *    fma needed), the sum rounded once: error about 2^-65 before that
 *    rounding, so it is correctly rounded but for arguments whose 2^x lies
 *    within about 1e-4 ulp of a halfway point.
 *
 * tests/c/test_math.c checks all of this bit for bit against libm over
 * millions of arguments, and tests/c/test_plan_libm.c that the planner makes
 * the same plans, bit for bit, with these functions and with libm's.
 *
 * Compiled with -DDJL_USE_LIBM, the djl_ names map to <math.h> instead (the
 * reference of that comparison).
 */
#ifndef DJL_MATH_H
#define DJL_MATH_H

#ifdef DJL_USE_LIBM

#include <math.h>

#define DJL_HUGE_VAL HUGE_VAL
#define djl_isfinite(x) isfinite(x)
#define djl_fabs fabs
#define djl_floor floor
#define djl_ceil ceil
#define djl_trunc trunc
#define djl_fmax fmax
#define djl_fmin fmin
#define djl_nextafter nextafter
#define djl_ldexp ldexp
#define djl_frexp frexp
#define djl_ilogb ilogb
#define djl_sqrt sqrt
#define djl_hypot hypot
#define djl_exp2 exp2

#else

#include <float.h>
#include <limits.h>
#include <stdint.h>

#if defined(_MSC_VER) && !defined(__cplusplus)
#define DJL_INLINE static __inline
#else
#define DJL_INLINE static inline
#endif

#define DJLM_SIGN UINT64_C(0x8000000000000000)
#define DJLM_EXP UINT64_C(0x7ff0000000000000)  /* also +infinity */
#define DJLM_FRAC UINT64_C(0x000fffffffffffff)
#define DJLM_ONE UINT64_C(0x0010000000000000)  /* the implicit bit */
#define DJLM_QUIET UINT64_C(0x0008000000000000) /* the quiet bit of a NaN */

/* ilogb(0) and ilogb(NaN), as glibc on x86 (FP_ILOGB0, FP_ILOGBNAN) */
#define DJL_ILOGB0 INT_MIN
#define DJL_ILOGBNAN INT_MIN

/* --- the encoding ------------------------------------------------------- */

typedef union {
    double f;
    uint64_t u;
} djlm_dbl;

DJL_INLINE uint64_t djlm_bits(double x)
{
    djlm_dbl d;
    d.f = x;
    return d.u;
}

DJL_INLINE double djlm_double(uint64_t u)
{
    djlm_dbl d;
    d.u = u;
    return d.f;
}

#define DJL_HUGE_VAL djlm_double(DJLM_EXP)

DJL_INLINE int djlm_isnan(uint64_t u) { return (u & ~DJLM_SIGN) > DJLM_EXP; }

/* a NaN made quiet (what an arithmetic operation returns for it) */
DJL_INLINE double djlm_quiet(uint64_t u) { return djlm_double(u | DJLM_QUIET); }

/* What SSE's a + b gives when a or b is a NaN: a's NaN if a is one, else b's,
 * made quiet (glibc's results for NaN arguments are such sums). */
DJL_INLINE double djlm_nan2(double a, double b)
{
    uint64_t ua = djlm_bits(a);
    return djlm_quiet(djlm_isnan(ua) ? ua : djlm_bits(b));
}

/* |x| = m 2^e with m in [2^52, 2^53) (x finite, not zero) */
DJL_INLINE uint64_t djlm_split(uint64_t u, int *e)
{
    int be = (int)((u >> 52) & 0x7ff);
    uint64_t m = u & DJLM_FRAC;
    if (be == 0) { /* subnormal: normalize */
        be = 1;
        while (!(m & DJLM_ONE)) {
            m <<= 1;
            be--;
        }
        *e = be - 1075;
        return m;
    }
    *e = be - 1075;
    return m | DJLM_ONE;
}

/* The double nearest to (-1)^sign (m + s) 2^e, ties to even, where 0 < s < 1
 * if sticky and s = 0 otherwise (m > 0; m >= 2^53 if sticky): the one
 * rounding of a result, to 53 bits or to the grid of the subnormals;
 * overflow gives infinity. */
DJL_INLINE double djlm_pack(uint64_t sign, uint64_t m, long e, int sticky)
{
    long bexp;
    int shift;
    uint64_t q;
    while (!(m >> 63)) { /* m = 1xxx... (64 bits) */
        m <<= 1;
        e--;
    }
    bexp = e + 63 + 1023; /* biased exponent of a normal result */
    if (bexp > 2046) return djlm_double(sign | DJLM_EXP);
    shift = 11;
    if (bexp < 1) { /* subnormal: q 2^-1074 */
        if (1 - bexp > 64) return djlm_double(sign); /* below half the smallest */
        shift += (int)(1 - bexp);
        bexp = 1;
    }
    if (shift >= 64) { /* below 2^-1074: 2^-1074 if above its half, else 0 */
        uint64_t half = UINT64_C(1) << 63;
        q = shift == 64 && (m > half || (m == half && sticky)) ? 1 : 0;
    } else {
        uint64_t rem = m & ((UINT64_C(1) << shift) - 1), half = UINT64_C(1) << (shift - 1);
        q = m >> shift;
        if (rem > half || (rem == half && (sticky || (q & 1)))) q++;
    }
    /* q in [2^52, 2^53] (normal) or [0, 2^52] (subnormal): a carry of the
     * rounding into the exponent is the next binade (or infinity) */
    return djlm_double(sign | ((((uint64_t)bexp - 1) << 52) + q));
}

/* --- exactly specified functions ---------------------------------------- */

DJL_INLINE double djl_fabs(double x) { return djlm_double(djlm_bits(x) & ~DJLM_SIGN); }

/* (a comparison, not a test of the exponent bits: as fast as the compilers' own) */
DJL_INLINE int djl_isfinite(double x) { return djl_fabs(x) <= DBL_MAX; }

DJL_INLINE double djl_trunc(double x)
{
    uint64_t u = djlm_bits(x);
    int e = (int)((u >> 52) & 0x7ff) - 1023;
    if (e >= 52) return e == 1024 ? x + x : x; /* whole, infinite or NaN */
    if (e < 0) return djlm_double(u & DJLM_SIGN);
    return djlm_double(u & ~(DJLM_FRAC >> e));
}

DJL_INLINE double djl_floor(double x)
{
    uint64_t u = djlm_bits(x), m;
    int e = (int)((u >> 52) & 0x7ff) - 1023;
    if (e >= 52) return e == 1024 ? x + x : x;
    if (e < 0) /* |x| < 1 */
        return (u >> 63) && (u << 1) ? -1.0 : djlm_double(u & DJLM_SIGN);
    m = DJLM_FRAC >> e; /* the fraction bits */
    if (!(u & m)) return x;
    if (u >> 63) u += m + 1; /* negative: one more in magnitude */
    return djlm_double(u & ~m);
}

DJL_INLINE double djl_ceil(double x)
{
    uint64_t u = djlm_bits(x), m;
    int e = (int)((u >> 52) & 0x7ff) - 1023;
    if (e >= 52) return e == 1024 ? x + x : x;
    if (e < 0) return !(u >> 63) && u ? 1.0 : djlm_double(u & DJLM_SIGN);
    m = DJLM_FRAC >> e;
    if (!(u & m)) return x;
    if (!(u >> 63)) u += m + 1;
    return djlm_double(u & ~m);
}

/* fmax and fmin as glibc's x86-64 code (maxsd / minsd: y when x == y, so
 * fmax(+0, -0) = -0; a quiet NaN loses to a number, a signaling one wins) */
DJL_INLINE double djlm_minmax_nan(double x, double y)
{
    uint64_t ux = djlm_bits(x), uy = djlm_bits(y);
    if (!djlm_isnan(uy)) return ux & DJLM_QUIET ? y : djlm_quiet(ux);
    if (!djlm_isnan(ux)) return uy & DJLM_QUIET ? x : djlm_quiet(uy);
    return djlm_quiet(ux);
}

DJL_INLINE double djl_fmax(double x, double y)
{
    if (x != x || y != y) return djlm_minmax_nan(x, y);
    return x > y ? x : y;
}

DJL_INLINE double djl_fmin(double x, double y)
{
    if (x != x || y != y) return djlm_minmax_nan(x, y);
    return x < y ? x : y;
}

DJL_INLINE double djl_nextafter(double x, double y)
{
    uint64_t ux = djlm_bits(x), uy = djlm_bits(y);
    if (djlm_isnan(ux) || djlm_isnan(uy)) return djlm_nan2(y, x);
    if (x == y) return y;
    if (!(ux << 1)) return djlm_double((uy & DJLM_SIGN) | 1); /* from 0: the smallest subnormal */
    if ((y > x) == (x > 0.0))
        ux++; /* away from 0 (from DBL_MAX: infinity) */
    else
        ux--;
    return djlm_double(ux);
}

DJL_INLINE double djl_ldexp(double x, int n)
{
    uint64_t u = djlm_bits(x), m;
    int be = (int)((u >> 52) & 0x7ff), e;
    if (be == 0x7ff) return x + x;
    if (!(u << 1)) return x;
    if (be > 0 && n > -be && n < 2047 - be) /* normal to normal: the exponent only */
        return djlm_double(u + ((uint64_t)(int64_t)n << 52));
    m = djlm_split(u, &e);
    if (n > 4000) n = 4000; /* (results infinite or zero beyond) */
    if (n < -4000) n = -4000;
    return djlm_pack(u & DJLM_SIGN, m, (long)e + n, 0);
}

DJL_INLINE double djl_frexp(double x, int *exp)
{
    uint64_t u = djlm_bits(x), m;
    int e;
    *exp = 0;
    if (((u >> 52) & 0x7ff) == 0x7ff) return x + x;
    if (!(u << 1)) return x;
    m = djlm_split(u, &e);
    *exp = e + 53;
    return djlm_double((u & DJLM_SIGN) | (UINT64_C(1022) << 52) | (m & DJLM_FRAC));
}

DJL_INLINE int djl_ilogb(double x)
{
    uint64_t u = djlm_bits(x) & ~DJLM_SIGN;
    int e;
    if (u >= DJLM_EXP) return u == DJLM_EXP ? INT_MAX : DJL_ILOGBNAN;
    if (!u) return DJL_ILOGB0;
    djlm_split(u, &e);
    return e + 52;
}

/* --- square roots --------------------------------------------------------- */

/* floor(sqrt(R)) of the 108-bit R = hi 2^64 + lo (2^106 <= R < 2^108), bit by
 * bit (two bits of R for one of the root); *inexact: R is not its square. */
DJL_INLINE uint64_t djlm_isqrt108(uint64_t hi, uint64_t lo, int *inexact)
{
    uint64_t root = 0, rem = 0;
    int i;
    for (i = 53; i >= 0; i--) {
        int b = 2 * i;
        uint64_t trial;
        rem = (rem << 2) | ((b >= 64 ? hi >> (b - 64) : lo >> b) & 3); /* rem < 2^57 */
        trial = (root << 2) | 1; /* (2 root + 1)^2 - (2 root)^2, in units of the new bit */
        root <<= 1;
        if (rem >= trial) {
            rem -= trial;
            root |= 1;
        }
    }
    *inexact = rem != 0;
    return root;
}

DJL_INLINE double djl_sqrt(double x)
{
    uint64_t u = djlm_bits(x), m;
    int e, inexact;
    if (!(u << 1) || u == DJLM_EXP) return x; /* +-0, +infinity */
    if (djlm_isnan(u)) return x + x;
    if (u >> 63) return (x - x) / (x - x); /* x < 0: invalid, the machine's default NaN */
    m = djlm_split(u, &e);                /* x = m 2^e */
    if (e & 1) {                          /* e even: m in [2^52, 2^54) */
        m <<= 1;
        e--;
    }
    /* R = m 2^54 in [2^106, 2^108): sqrt(x) = sqrt(R) 2^(e/2 - 27), and
     * floor(sqrt(R)) has 54 bits: 53 and the rounding bit */
    m = djlm_isqrt108(m >> 10, m << 54, &inexact);
    return djlm_pack(0, m, (long)(e / 2 - 27), inexact);
}

/* hi 2^64 + lo = a b */
DJL_INLINE void djlm_mul64(uint64_t a, uint64_t b, uint64_t *hi, uint64_t *lo)
{
    uint64_t a0 = a & 0xffffffffu, a1 = a >> 32, b0 = b & 0xffffffffu, b1 = b >> 32;
    uint64_t p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
    uint64_t mid = (p00 >> 32) + (p01 & 0xffffffffu) + (p10 & 0xffffffffu);
    *lo = (mid << 32) | (p00 & 0xffffffffu);
    *hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
}

/* sqrt(x^2 + y^2), correctly rounded: the integer square root of the exact
 * sum of the squares of the significands (bits far below it only make it
 * inexact); infinity if either is infinite, even with a NaN. */
DJL_INLINE double djl_hypot(double x, double y)
{
    uint64_t ux = djlm_bits(x) & ~DJLM_SIGN, uy = djlm_bits(y) & ~DJLM_SIGN, t;
    uint64_t ma, mb, ahi, alo, bhi, blo, rhi, rlo;
    int ea, eb, inexact = 0, s, k = 1;
    if (ux >= DJLM_EXP || uy >= DJLM_EXP) {
        if (ux == DJLM_EXP || uy == DJLM_EXP) {
            if ((djlm_isnan(ux) && !(ux & DJLM_QUIET)) || (djlm_isnan(uy) && !(uy & DJLM_QUIET)))
                return djlm_nan2(x, y); /* a signaling NaN wins */
            return DJL_HUGE_VAL;
        }
        return djlm_nan2(x, y);
    }
    if (ux < uy) { /* |x| >= |y| */
        t = ux;
        ux = uy;
        uy = t;
    }
    if (!uy) return djlm_double(ux);
    ma = djlm_split(ux, &ea);
    mb = djlm_split(uy, &eb);
    /* x^2 + y^2 = (ma^2 + mb^2 2^(-2d)) 2^(2 ea) = S 2^(2 ea), S in [2^104, 2^107):
     * R = 4 S, its lowest bits those of 4 mb^2 2^(-2d) below 1 dropped (inexact) */
    djlm_mul64(ma, ma, &ahi, &alo);
    djlm_mul64(mb, mb, &bhi, &blo);
    ahi = (ahi << 2) | (alo >> 62);
    alo <<= 2;
    bhi = (bhi << 2) | (blo >> 62);
    blo <<= 2;
    s = 2 * (ea - eb); /* shift 4 mb^2 right by s */
    if (s >= 128) {
        inexact = 1;
        bhi = blo = 0;
    } else if (s >= 64) {
        inexact = blo != 0 || (bhi & ((UINT64_C(1) << (s - 64)) - 1)) != 0;
        blo = s == 64 ? bhi : bhi >> (s - 64);
        bhi = 0;
    } else if (s > 0) {
        inexact = (blo & ((UINT64_C(1) << s) - 1)) != 0;
        blo = (blo >> s) | (bhi << (64 - s));
        bhi >>= s;
    }
    rlo = alo + blo;
    rhi = ahi + bhi + (rlo < alo);
    if (rhi >> 44) { /* R >= 2^108: R / 4 (S itself) */
        inexact |= (rlo & 3) != 0;
        rlo = (rlo >> 2) | (rhi << 62);
        rhi >>= 2;
        k = 0;
    }
    /* hypot = sqrt(R) 2^(ea - k), R in [2^106, 2^108) */
    {
        int inexact2;
        uint64_t r = djlm_isqrt108(rhi, rlo, &inexact2);
        return djlm_pack(0, r, (long)ea - k, inexact | inexact2);
    }
}

/* --- exp2 ----------------------------------------------------------------- */

/* x with the 27 low bits of its significand cleared: at most 26 significant
 * bits, so that its product with a number of at most 27 bits is exact */
DJL_INLINE double djlm_head(double x) { return djlm_double(djlm_bits(x) & ~UINT64_C(0x7ffffff)); }

/* (hi + lo) 2^k rounded once (hi > 0 normal, |lo| < 2^-12 hi): the exact sum
 * to 2^-10 of hi's last place in an integer, the bits below as inexact */
DJL_INLINE double djlm_pack2(double hi, double lo, long k)
{
    int eh, el, sh, inexact = 0;
    uint64_t acc = djlm_split(djlm_bits(hi), &eh) << 10, ul = djlm_bits(lo), ml, part;
    if (ul << 1) {
        ml = djlm_split(ul, &el);
        sh = eh - 10 - el; /* >= 2 */
        part = sh >= 64 ? 0 : ml >> sh;
        inexact = sh >= 64 || (ml & ((UINT64_C(1) << sh) - 1)) != 0;
        if (!(ul >> 63)) {
            acc += part;
        } else {
            acc -= part + (uint64_t)inexact; /* floor of hi + lo */
        }
    }
    return djlm_pack(0, acc, (long)eh - 10 + k, inexact);
}

/* 2^(j/64) = hi + lo, hi of 26 bits, to 2^-78 (bits of the doubles) */
static const uint64_t djlm_exp2_tab[128] = {
    UINT64_C(0x3ff0000000000000), UINT64_C(0x0000000000000000), /*  0 */
    UINT64_C(0x3ff02c9a40000000), UINT64_C(0xbe3887f9f1190835), /*  1 */
    UINT64_C(0x3ff059b0d0000000), UINT64_C(0x3e48ac2ba1d73e2a), /*  2 */
    UINT64_C(0x3ff0874518000000), UINT64_C(0x3e1d66f20230d7c9), /*  3 */
    UINT64_C(0x3ff0b55870000000), UINT64_C(0xbe4833b784eb3a37), /*  4 */
    UINT64_C(0x3ff0e3ec30000000), UINT64_C(0x3e469e8d10103a17), /*  5 */
    UINT64_C(0x3ff11301d0000000), UINT64_C(0x3df25b50a4ebbf1b), /*  6 */
    UINT64_C(0x3ff1429ab0000000), UINT64_C(0xbe356d2204cbefe7), /*  7 */
    UINT64_C(0x3ff172b840000000), UINT64_C(0xbe4c15742919041c), /*  8 */
    UINT64_C(0x3ff1a35be8000000), UINT64_C(0x3e4b7e5ba9e5b4c8), /*  9 */
    UINT64_C(0x3ff1d48730000000), UINT64_C(0x3e368b9aa7805b80), /* 10 */
    UINT64_C(0x3ff2063b88000000), UINT64_C(0x3e18a3358ee3bac1), /* 11 */
    UINT64_C(0x3ff2387a70000000), UINT64_C(0xbe38a9dc7993e052), /* 12 */
    UINT64_C(0x3ff26b4568000000), UINT64_C(0xbe40ec1916d42cc6), /* 13 */
    UINT64_C(0x3ff29e9df8000000), UINT64_C(0xbe470108f69ed175), /* 14 */
    UINT64_C(0x3ff2d285a8000000), UINT64_C(0xbe31bfcf4bff6e2b), /* 15 */
    UINT64_C(0x3ff306fe08000000), UINT64_C(0x3e418db8a96f46ad), /* 16 */
    UINT64_C(0x3ff33c08b0000000), UINT64_C(0x3e4320b7fa64e431), /* 17 */
    UINT64_C(0x3ff371a738000000), UINT64_C(0xbe28aac6ab1d7560), /* 18 */
    UINT64_C(0x3ff3a7db38000000), UINT64_C(0xbe48d30048af21b7), /* 19 */
    UINT64_C(0x3ff3dea650000000), UINT64_C(0xbe4f6e5eee525f6f), /* 20 */
    UINT64_C(0x3ff4160a20000000), UINT64_C(0x3e3f72e29f84325c), /* 21 */
    UINT64_C(0x3ff44e0860000000), UINT64_C(0x3e18624b40c4dbd0), /* 22 */
    UINT64_C(0x3ff486a2b8000000), UINT64_C(0xbe41f6197f61f2e2), /* 23 */
    UINT64_C(0x3ff4bfdad8000000), UINT64_C(0xbe464eaec715e343), /* 24 */
    UINT64_C(0x3ff4f9b278000000), UINT64_C(0xbe362d35952cc275), /* 25 */
    UINT64_C(0x3ff5342b58000000), UINT64_C(0xbe362b07e20f57c4), /* 26 */
    UINT64_C(0x3ff56f4738000000), UINT64_C(0xbe34ad8259913500), /* 27 */
    UINT64_C(0x3ff5ab07e0000000), UINT64_C(0xbe45bd5eb539b67f), /* 28 */
    UINT64_C(0x3ff5e76f18000000), UINT64_C(0xbe4296f5bc8b20da), /* 29 */
    UINT64_C(0x3ff6247eb0000000), UINT64_C(0x3e0d2ac258f87d03), /* 30 */
    UINT64_C(0x3ff6623880000000), UINT64_C(0x3e42a91124893ecf), /* 31 */
    UINT64_C(0x3ff6a09e68000000), UINT64_C(0xbe380c4336f74d05), /* 32 */
    UINT64_C(0x3ff6dfb240000000), UINT64_C(0xbe4cd72e886ef8ea), /* 33 */
    UINT64_C(0x3ff71f75e8000000), UINT64_C(0x3e2d8bee7ba46e1e), /* 34 */
    UINT64_C(0x3ff75feb58000000), UINT64_C(0xbe3bd98374091656), /* 35 */
    UINT64_C(0x3ff7a11470000000), UINT64_C(0x3e4f580c36bea881), /* 36 */
    UINT64_C(0x3ff7e2f338000000), UINT64_C(0xbe330b19defa2fd4), /* 37 */
    UINT64_C(0x3ff8258998000000), UINT64_C(0x3e34cce128acf88b), /* 38 */
    UINT64_C(0x3ff868d998000000), UINT64_C(0x3e4a2497640720ed), /* 39 */
    UINT64_C(0x3ff8ace540000000), UINT64_C(0x3e415506dadd3e2b), /* 40 */
    UINT64_C(0x3ff8f1ae98000000), UINT64_C(0x3e31577362b98274), /* 41 */
    UINT64_C(0x3ff93737b0000000), UINT64_C(0x3e29b8bc9e8a0388), /* 42 */
    UINT64_C(0x3ff97d82a0000000), UINT64_C(0xbe00d8d83a30b6f8), /* 43 */
    UINT64_C(0x3ff9c49180000000), UINT64_C(0x3e451f8480e3e236), /* 44 */
    UINT64_C(0x3ffa0c6678000000), UINT64_C(0x3e4aef2b2594d6d4), /* 45 */
    UINT64_C(0x3ffa5503b0000000), UINT64_C(0x3e41f12ae45a1225), /* 46 */
    UINT64_C(0x3ffa9e6b58000000), UINT64_C(0xbe44301205e0a6de), /* 47 */
    UINT64_C(0x3ffae89f98000000), UINT64_C(0x3e35ad3ad5e8734d), /* 48 */
    UINT64_C(0x3ffb33a2b8000000), UINT64_C(0x3e13c57ebdaff43a), /* 49 */
    UINT64_C(0x3ffb7f76f0000000), UINT64_C(0x3e47daf237553d84), /* 50 */
    UINT64_C(0x3ffbcc1e90000000), UINT64_C(0x3e12f074891ee83d), /* 51 */
    UINT64_C(0x3ffc199be0000000), UINT64_C(0xbe43d56b1eeef9a7), /* 52 */
    UINT64_C(0x3ffc67f130000000), UINT64_C(0xbe3a82eb4b5dec80), /* 53 */
    UINT64_C(0x3ffcb720e0000000), UINT64_C(0xbe48837cb757e1a1), /* 54 */
    UINT64_C(0x3ffd072d48000000), UINT64_C(0x3e403c4bdc687918), /* 55 */
    UINT64_C(0x3ffd5818e0000000), UINT64_C(0xbe4822dbc6d12fd3), /* 56 */
    UINT64_C(0x3ffda9e600000000), UINT64_C(0x3e4ed9942b84600d), /* 57 */
    UINT64_C(0x3ffdfc9730000000), UINT64_C(0x3e4bdcdaf5cb4656), /* 58 */
    UINT64_C(0x3ffe502ee8000000), UINT64_C(0xbe1d30027630bb40), /* 59 */
    UINT64_C(0x3ffea4afa0000000), UINT64_C(0x3e452486cc2c7b9d), /* 60 */
    UINT64_C(0x3ffefa1bf0000000), UINT64_C(0xbe39ea5d888e02de), /* 61 */
    UINT64_C(0x3fff507658000000), UINT64_C(0x3e4b722a033a7c26), /* 62 */
    UINT64_C(0x3fffa7c180000000), UINT64_C(0x3e39e90d82e90a7e), /* 63 */
};

DJL_INLINE double djl_exp2(double x)
{
    /* ln 2 = L1 + L2 to 2^-78, L1 of 27 bits */
    const double L1 = djlm_double(UINT64_C(0x3fe62e4300000000));
    const double L2 = djlm_double(UINT64_C(0xbe205c610ca86c39));
    double ti, r, rh, t, th, tl, u, a1, Th, Tl, H, L;
    int i, j;
    if (x != x) return x + x;
    if (x >= 1024.0) return DJL_HUGE_VAL;
    if (x <= -1075.0) return 0.0; /* 2^-1075 is a tie: to the even 0 */
    if (djl_trunc(x) == x) return djlm_pack(0, 1, (long)x, 0);
    /* x = i/64 + r, i = k 64 + j (0 <= j < 64), |r| <= 1/128, all exact */
    ti = djl_floor(64.0 * x + 0.5);
    r = x - ti / 64.0;
    i = (int)ti;
    j = ((i % 64) + 64) % 64;
    /* t = r ln 2 = th + tl, th = rh L1 exact (rh: r's 26 leading bits) */
    rh = djlm_head(r);
    th = rh * L1;
    tl = (r - rh) * L1 + r * L2;
    t = th + tl;
    /* e^t = 1 + th + u, u = tl + t^2/2 + ... + t^7/7! (the rest < 2^-75) */
    u = tl + t * t * (0.5 + t * (1.0 / 6.0 + t * (1.0 / 24.0 + t * (1.0 / 120.0 +
                                       t * (1.0 / 720.0 + t * (1.0 / 5040.0))))));
    /* 2^(j/64) e^t = Th + Th a1 + [Th (th - a1) + Th u + Tl e^t], each Th a exact */
    Th = djlm_double(djlm_exp2_tab[2 * j]);
    Tl = djlm_double(djlm_exp2_tab[2 * j + 1]);
    a1 = djlm_head(th);
    H = Th + Th * a1;
    L = (Th * a1 - (H - Th)) + (Th * (th - a1) + (Th * u + (Tl + Tl * (th + u))));
    return djlm_pack2(H, L, (long)((i - j) / 64));
}

#endif /* DJL_USE_LIBM */

#endif /* DJL_MATH_H */
