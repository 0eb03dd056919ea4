/*
 * test_math.c -- fmu_src/djl_math.h against libm, bit for bit.
 *
 * Every function of djl_math.h is compared with libm's over special
 * arguments (+-0, subnormals, DBL_MIN, DBL_MAX, infinities, quiet and
 * signaling NaNs with payloads, integers and halfway cases) and n random ones
 * from several generators each (any bit pattern, subnormals, near integers,
 * halfway cases of the roundings, squares and near-halfway squares for sqrt,
 * Pythagorean triples for hypot, results in the subnormal range and near
 * overflow for ldexp and exp2):
 *
 *  - floor, ceil, trunc, fabs, isfinite, fmax, fmin, nextafter, ldexp, frexp,
 *    ilogb, sqrt: the same bits as libm's (NaN payloads included), no
 *    difference allowed;
 *  - hypot and exp2 (not exactly specified): differences counted, their
 *    largest size in ulps reported (at most 1 allowed); with -DDJL_TEST_QUAD
 *    (gcc, -lquadmath) also the error of each against a quadruple-precision
 *    reference, in ulps: at most 0.5 allowed for djl_hypot (correctly
 *    rounded), 0.5 + 1e-3 for djl_exp2;
 *  - exp2 at the arguments the planner uses (-p/3 for p = 0..60, -p/4 for
 *    p = 0..96): the same bits as libm's, required.
 *
 * libm is called through volatile function pointers: no compiler folds,
 * inlines or reorders (gcc swaps the arguments of fmax and fmin) the calls.
 *
 * Usage: test_math [n] [seed]     (n random arguments per generator; 10^6)
 */
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "djl_math.h"

#ifdef DJL_TEST_QUAD
#include <quadmath.h>
#endif

static double (*volatile lm_floor)(double) = floor;
static double (*volatile lm_ceil)(double) = ceil;
static double (*volatile lm_trunc)(double) = trunc;
static double (*volatile lm_fabs)(double) = fabs;
static double (*volatile lm_sqrt)(double) = sqrt;
static double (*volatile lm_exp2)(double) = exp2;
static double (*volatile lm_fmax)(double, double) = fmax;
static double (*volatile lm_fmin)(double, double) = fmin;
static double (*volatile lm_nextafter)(double, double) = nextafter;
static double (*volatile lm_hypot)(double, double) = hypot;
static double (*volatile lm_ldexp)(double, int) = ldexp;
static double (*volatile lm_frexp)(double, int *) = frexp;
static int (*volatile lm_ilogb)(double) = ilogb;

static int failures = 0;

/* ------------------------------------------------------------------------ */
/* arguments                                                                */

static uint64_t rng = 0x9E3779B97F4A7C15ULL;

static uint64_t next64(void) /* xorshift64* */
{
    rng ^= rng >> 12;
    rng ^= rng << 25;
    rng ^= rng >> 27;
    return rng * 0x2545F4914F6CDD1DULL;
}

static double urand(void) { return (double)(next64() >> 11) / 9007199254740992.0; }
static int irange(int lo, int hi) { return lo + (int)(next64() % (uint64_t)(hi - lo + 1)); }

static uint64_t bits(double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

static double dbl(uint64_t u)
{
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

static const uint64_t special_bits[] = {
    0x0000000000000000ULL, 0x8000000000000000ULL, /* +-0 */
    0x0000000000000001ULL, 0x8000000000000001ULL, /* +-2^-1074 */
    0x0000000000000002ULL, 0x0000000000000003ULL, 0x0008000000000000ULL,
    0x000fffffffffffffULL, 0x800fffffffffffffULL, /* largest subnormals */
    0x0010000000000000ULL, 0x8010000000000000ULL, /* DBL_MIN */
    0x0010000000000001ULL, 0x7fefffffffffffffULL, 0xffefffffffffffffULL, /* DBL_MAX */
    0x7fe0000000000000ULL, 0x7ff0000000000000ULL, 0xfff0000000000000ULL, /* infinities */
    0x7ff8000000000000ULL, 0xfff8000000000000ULL, 0x7ff8000000000123ULL,
    0xfffc000000000456ULL, /* quiet NaNs */
    0x7ff0000000000001ULL, 0xfff0000000000789ULL, 0x7ff4000000000000ULL, /* signaling */
    0x3ff0000000000000ULL, 0xbff0000000000000ULL, 0x3fe0000000000000ULL, 0xbfe0000000000000ULL,
    0x3fdfffffffffffffULL, 0xbfdfffffffffffffULL, /* 0.5 - 2^-54 */
    0x3fefffffffffffffULL, 0xbfefffffffffffffULL, 0x3ff0000000000001ULL, 0xbff0000000000001ULL,
    0x3ff8000000000000ULL, 0xbff8000000000000ULL, 0x4004000000000000ULL, 0xc004000000000000ULL,
    0x4330000000000000ULL, 0xc330000000000000ULL, /* 2^52 */
    0x432fffffffffffffULL, 0xc32fffffffffffffULL, /* 2^52 - 0.5 */
    0x4330000000000001ULL, 0x4340000000000000ULL, 0xc340000000000000ULL,
    0x433fffffffffffffULL, 0x4090000000000000ULL, 0xc090000000000000ULL, /* 1024 */
    0xc090cc0000000000ULL, 0xc090c80000000000ULL, 0xc090cbffffffffffULL, /* -1075, -1074 */
    0x408fffffffffffffULL, 0xc08ff00000000000ULL, 0xc08ff80000000000ULL,
};
#define N_SPECIAL ((int)(sizeof special_bits / sizeof special_bits[0]))

/* one argument from generator g */
static double gen(int g)
{
    switch (g) {
    case 0: /* any bit pattern */
        return dbl(next64());
    case 1: /* subnormal */
        return dbl(next64() & 0x800fffffffffffffULL);
    case 2: /* exponent -60..60 */
        return dbl((next64() & 0x800fffffffffffffULL) | ((uint64_t)(1023 + irange(-60, 60)) << 52));
    case 3: /* integers, halves and their neighbours */
        {
            double k = (double)(int64_t)(next64() >> irange(1, 63)) * (next64() & 1 ? 1.0 : -1.0);
            double x = next64() & 1 ? k : k + 0.5;
            int d = irange(-2, 2);
            while (d > 0) { x = nextafter(x, HUGE_VAL); d--; }
            while (d < 0) { x = nextafter(x, -HUGE_VAL); d++; }
            return x;
        }
    case 4: /* small integers and their neighbours */
        {
            double x = (double)irange(-70, 70) * (next64() & 1 ? 1.0 : 0.5);
            int d = irange(-2, 2);
            while (d > 0) { x = nextafter(x, HUGE_VAL); d--; }
            while (d < 0) { x = nextafter(x, -HUGE_VAL); d++; }
            return x;
        }
    default: /* special */
        return dbl(special_bits[irange(0, N_SPECIAL - 1)]);
    }
}
#define N_GEN 6

/* ------------------------------------------------------------------------ */
/* comparisons                                                              */

typedef struct {
    const char *name;
    long n, diff;
    int max_ulps;       /* largest difference from libm, in ulps (hypot, exp2) */
    double err_own, err_libm; /* largest error against the quad reference, ulps */
    long cr_own, cr_libm;     /* results not correctly rounded (error > 0.5 ulp) */
    long ties, odd_own, odd_libm; /* exact results halfway: rounded to odd */
} stat_t;

static void report_diff(stat_t *s, double a, double b, double got, double want)
{
    s->diff++;
    if (s->diff <= 5)
        fprintf(stderr, "%s(%.17g [%016llx], %.17g [%016llx]) = %.17g [%016llx], libm %.17g [%016llx]\n",
                s->name, a, (unsigned long long)bits(a), b, (unsigned long long)bits(b), got,
                (unsigned long long)bits(got), want, (unsigned long long)bits(want));
}

static void exact_result(stat_t *s, double a, double b, double got, double want)
{
    s->n++;
    if (bits(got) != bits(want)) report_diff(s, a, b, got, want);
}

/* differences of finite results of the same sign, in ulps */
static void close_result(stat_t *s, double a, double b, double got, double want)
{
    uint64_t g = bits(got), w = bits(want);
    s->n++;
    if (g == w) return;
    if ((g >> 63) != (w >> 63) || !isfinite(want) || isnan(got) || isnan(want)) {
        s->max_ulps = INT_MAX; /* not close */
        report_diff(s, a, b, got, want);
        return;
    }
    {
        uint64_t d = g > w ? g - w : w - g;
        int du = d > 1000 ? 1000 : (int)d;
        s->diff++;
        if (du > s->max_ulps) s->max_ulps = du;
        if (du > 1 && s->diff <= 5)
            fprintf(stderr, "%s(%.17g, %.17g) = %.17g, libm %.17g: %d ulps\n", s->name, a, b, got,
                    want, du);
    }
}

#ifdef DJL_TEST_QUAD
/* |y - exact| in ulps of y (y finite and normal, or subnormal: ulp 2^-1074) */
static double ulp_err(double y, __float128 exact)
{
    int e;
    __float128 ulp;
    if (y == 0.0) return exact == 0 ? 0.0 : 1e9;
    frexp(y, &e);
    ulp = ldexpq(1.0Q, (e - 53 < -1074 ? -1074 : e - 53));
    return (double)(fabsq((__float128)y - exact) / ulp);
}

static void quad_errors(stat_t *s, double own, double lib, __float128 exact)
{
    double eo = ulp_err(own, exact), el = ulp_err(lib, exact);
    if (eo > s->err_own) s->err_own = eo;
    if (el > s->err_libm) s->err_libm = el;
    s->cr_own += eo > 0.5 + 1e-12;
    s->cr_libm += el > 0.5 + 1e-12;
    if (eo == 0.5 && el == 0.5) { /* halfway: ties to even */
        s->ties++;
        s->odd_own += (long)(bits(own) & 1);
        s->odd_libm += (long)(bits(lib) & 1);
    }
}

static void quad_hypot(stat_t *s, double x, double y, double own, double lib)
{
    __float128 qx = x, qy = y, ex = sqrtq(qx * qx + qy * qy);
    if (!isfinite(own) || !isfinite(lib) || own == 0.0 || (double)ex > DBL_MAX) return;
    quad_errors(s, own, lib, ex);
}

static void quad_exp2(stat_t *s, double x, double own, double lib)
{
    __float128 ex = exp2q((__float128)x);
    if (!isfinite(own) || !isfinite(lib) || own == 0.0 || lib == 0.0) return;
    quad_errors(s, own, lib, ex);
}
#endif

/* exact: no difference allowed; else at most 1 ulp, and with the quad
 * reference an error of at most own_tol ulps */
static void print_stat(const stat_t *s, int exact, double own_tol)
{
    printf("  %-10s %9ld arguments, %ld differ from libm", s->name, s->n, s->diff);
    if (!exact) {
        if (s->max_ulps == INT_MAX)
            printf(" (not all within 1 ulp)");
        else
            printf(" (by at most %d ulp)", s->max_ulps);
#ifdef DJL_TEST_QUAD
        printf("; against quad precision: error at most %.6f ulp (djl), %.6f ulp (libm), not "
               "correctly rounded %ld (djl), %ld (libm)", s->err_own, s->err_libm, s->cr_own,
               s->cr_libm);
        if (s->ties)
            printf("; %ld halfway cases, rounded to odd: %ld (djl), %ld (libm)", s->ties,
                   s->odd_own, s->odd_libm);
#endif
    }
    printf("\n");
    if (exact && s->diff) failures++;
    if (!exact && s->max_ulps > 1) failures++;
#ifdef DJL_TEST_QUAD
    if (!exact && (s->err_own > own_tol || s->odd_own)) failures++;
#else
    (void)own_tol;
#endif
}

/* ------------------------------------------------------------------------ */
/* the functions                                                            */

static void test_unary(long n)
{
    stat_t sf = {"floor", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, sc = {"ceil", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, st = {"trunc", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    stat_t sa = {"fabs", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, si = {"isfinite", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    stat_t sl = {"ilogb", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, sx = {"frexp", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    long i;
    int g;
    for (g = 0; g < N_GEN; g++)
        for (i = 0; i < (g == N_GEN - 1 ? N_SPECIAL : n); i++) {
            double x = g == N_GEN - 1 ? dbl(special_bits[i]) : gen(g);
            int e1, e2;
            double m1, m2;
            exact_result(&sf, x, 0.0, djl_floor(x), lm_floor(x));
            exact_result(&sc, x, 0.0, djl_ceil(x), lm_ceil(x));
            exact_result(&st, x, 0.0, djl_trunc(x), lm_trunc(x));
            exact_result(&sa, x, 0.0, djl_fabs(x), lm_fabs(x));
            exact_result(&si, x, 0.0, (double)(djl_isfinite(x) != 0), (double)(isfinite(x) != 0));
            exact_result(&sl, x, 0.0, (double)djl_ilogb(x), (double)lm_ilogb(x));
            m1 = djl_frexp(x, &e1);
            m2 = lm_frexp(x, &e2);
            exact_result(&sx, x, 0.0, m1, m2);
            if (e1 != e2) report_diff(&sx, x, 0.0, (double)e1, (double)e2);
        }
    print_stat(&sf, 1, 0.0);
    print_stat(&sc, 1, 0.0);
    print_stat(&st, 1, 0.0);
    print_stat(&sa, 1, 0.0);
    print_stat(&si, 1, 0.0);
    print_stat(&sl, 1, 0.0);
    print_stat(&sx, 1, 0.0);
}

static void test_sqrt(long n)
{
    stat_t s = {"sqrt", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    long i;
    int g;
    for (g = 0; g < N_GEN; g++)
        for (i = 0; i < (g == N_GEN - 1 ? N_SPECIAL : n); i++) {
            double x = g == N_GEN - 1 ? dbl(special_bits[i]) : gen(g);
            exact_result(&s, x, 0.0, djl_sqrt(x), lm_sqrt(x));
        }
    for (i = 0; i < n; i++) {
        /* squares (exact roots), and near-halfway cases: h (h + ulp) has its
         * root about half an ulp above h; their neighbours */
        double h = dbl((next64() & 0x000fffffffffffffULL) | ((uint64_t)irange(1, 2046) << 52));
        double k = (double)(next64() >> 38), x;
        int d;
        x = ldexp(k * k, 2 * irange(-560, 460));
        exact_result(&s, x, 0.0, djl_sqrt(x), lm_sqrt(x));
        x = h * nextafter(h, HUGE_VAL);
        for (d = -2; d <= 2; d++) {
            double y = dbl(bits(x) + (uint64_t)(int64_t)d);
            exact_result(&s, y, 0.0, djl_sqrt(y), lm_sqrt(y));
        }
    }
    print_stat(&s, 1, 0.0);
}

static double gen_pair_second(double x)
{
    switch (irange(0, 5)) {
    case 0: return x;
    case 1: return -x;
    case 2: return gen(irange(0, N_GEN - 1));
    case 3: return x * (1.0 + 1e-3 * urand());
    case 4: return ldexp(x, irange(-60, 60)) * urand();
    default: return dbl(special_bits[irange(0, N_SPECIAL - 1)]);
    }
}

static void test_binary(long n)
{
    stat_t smax = {"fmax", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, smin = {"fmin", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    stat_t snx = {"nextafter", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    long i;
    int g, a, b;
    for (a = 0; a < N_SPECIAL; a++)
        for (b = 0; b < N_SPECIAL; b++) {
            double x = dbl(special_bits[a]), y = dbl(special_bits[b]);
            exact_result(&smax, x, y, djl_fmax(x, y), lm_fmax(x, y));
            exact_result(&smin, x, y, djl_fmin(x, y), lm_fmin(x, y));
            exact_result(&snx, x, y, djl_nextafter(x, y), lm_nextafter(x, y));
        }
    for (g = 0; g < N_GEN; g++)
        for (i = 0; i < n; i++) {
            double x = gen(g), y = gen_pair_second(x);
            exact_result(&smax, x, y, djl_fmax(x, y), lm_fmax(x, y));
            exact_result(&smin, x, y, djl_fmin(x, y), lm_fmin(x, y));
            exact_result(&snx, x, y, djl_nextafter(x, y), lm_nextafter(x, y));
        }
    print_stat(&smax, 1, 0.0);
    print_stat(&smin, 1, 0.0);
    print_stat(&snx, 1, 0.0);
}

static void test_ldexp(long n)
{
    static const int special_n[] = {0, 1, -1, 52, -52, 53, -53, 1022, -1022, 1023, -1023, 1074,
                                    -1074, 1075, -1075, 2046, -2046, 2098, -2098, 2099, -2099,
                                    5000, -5000, INT_MAX, INT_MIN, INT_MAX - 1, INT_MIN + 1};
    int ns = (int)(sizeof special_n / sizeof special_n[0]);
    stat_t s = {"ldexp", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    long i;
    int g, a, b;
    for (a = 0; a < N_SPECIAL; a++)
        for (b = 0; b < ns; b++) {
            double x = dbl(special_bits[a]);
            exact_result(&s, x, (double)special_n[b], djl_ldexp(x, special_n[b]),
                         lm_ldexp(x, special_n[b]));
        }
    for (g = 0; g < N_GEN; g++)
        for (i = 0; i < n; i++) {
            double x = gen(g);
            int k = next64() & 1 ? irange(-2200, 2200) : irange(-80, 80);
            exact_result(&s, x, (double)k, djl_ldexp(x, k), lm_ldexp(x, k));
        }
    for (i = 0; i < n; i++) {
        /* results on the subnormal grid, with many ties: few significant bits */
        double x = ldexp((double)(next64() >> irange(11, 63)), irange(-1074, 900));
        int e, k;
        frexp(x, &e);
        k = -1022 - e + irange(-60, 2);
        if (next64() & 1) x = -x;
        exact_result(&s, x, (double)k, djl_ldexp(x, k), lm_ldexp(x, k));
    }
    print_stat(&s, 1, 0.0);
}

static void check_hypot(stat_t *s, double x, double y)
{
    double own = djl_hypot(x, y), lib = lm_hypot(x, y);
    if (isnan(own) || isnan(lib) || isinf(lib))
        exact_result(s, x, y, own, lib);
    else
        close_result(s, x, y, own, lib);
#ifdef DJL_TEST_QUAD
    quad_hypot(s, x, y, own, lib);
#endif
}

static void test_hypot(long n)
{
    stat_t s = {"hypot", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    long i;
    int g, a, b;
    for (a = 0; a < N_SPECIAL; a++)
        for (b = 0; b < N_SPECIAL; b++) check_hypot(&s, dbl(special_bits[a]), dbl(special_bits[b]));
    for (g = 0; g < N_GEN - 1; g++)
        for (i = 0; i < n; i++) {
            double x = gen(g), y = gen_pair_second(x);
            check_hypot(&s, x, y);
        }
    for (i = 0; i < n; i++) {
        /* exponents apart by 0..60, anywhere in the range */
        int e = irange(-1100, 1023);
        double x = ldexp(1.0 + urand(), e), y = ldexp(1.0 + urand(), e - irange(0, 60));
        check_hypot(&s, x, y);
        /* Pythagorean triples (m^2 - n^2, 2 m n, m^2 + n^2): exact results, and
         * (with a 54-bit odd hypotenuse) ties */
        {
            double m = floor(ldexp(0.95 + 0.02 * urand(), 26) * 1.4142135623730951);
            double nn = floor(ldexp(0.48 + 0.04 * urand(), 26) * 1.4142135623730951);
            int sc = irange(-1000, 900);
            check_hypot(&s, ldexp(m * m - nn * nn, sc), ldexp(2.0 * m * nn, sc));
            m = (double)irange(2, 40000);
            nn = (double)irange(1, (int)m - 1);
            check_hypot(&s, ldexp(m * m - nn * nn, sc), ldexp(2.0 * m * nn, sc));
        }
    }
    print_stat(&s, 0, 0.5 + 1e-9); /* correctly rounded */
}

static void check_exp2(stat_t *s, double x)
{
    double own = djl_exp2(x), lib = lm_exp2(x);
    if (isnan(own) || isnan(lib) || isinf(lib) || lib == 0.0)
        exact_result(s, x, 0.0, own, lib);
    else
        close_result(s, x, 0.0, own, lib);
#ifdef DJL_TEST_QUAD
    quad_exp2(s, x, own, lib);
#endif
}

static void test_exp2(long n)
{
    stat_t s = {"exp2", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0}, sg = {"exp2 grid", 0, 0, 0, 0, 0, 0, 0, 0, 0, 0};
    long i;
    int g, p;
    /* the planner's arguments (djl_segment.c: solve_monotone_or_dip_once,
       solve_fit_peak_grid) */
    for (p = 0; p <= 60; p++) exact_result(&sg, -p / 3.0, 0.0, djl_exp2(-p / 3.0), lm_exp2(-p / 3.0));
    for (p = 0; p <= 96; p++) exact_result(&sg, -p / 4.0, 0.0, djl_exp2(-p / 4.0), lm_exp2(-p / 4.0));
    for (i = 0; i < N_SPECIAL; i++) check_exp2(&s, dbl(special_bits[i]));
    for (g = 0; g < N_GEN - 1; g++)
        for (i = 0; i < n; i++) check_exp2(&s, gen(g));
    for (i = 0; i < n; i++) {
        check_exp2(&s, -1100.0 + 2150.0 * urand());   /* the whole range */
        check_exp2(&s, -1075.0 + 60.0 * urand());     /* subnormal results */
        check_exp2(&s, 1024.0 - ldexp(urand(), -irange(0, 40))); /* near overflow */
        check_exp2(&s, ldexp(urand() - 0.5, -irange(0, 60)));      /* near 0 */
        check_exp2(&s, (double)irange(-1080, 1030));  /* integers */
    }
    print_stat(&sg, 1, 0.0);
    print_stat(&s, 0, 0.5 + 1e-3);
}

int main(int argc, char **argv)
{
    long n = argc > 1 ? atol(argv[1]) : 1000000;
    if (argc > 2) rng ^= strtoull(argv[2], NULL, 10) * 0x9E3779B97F4A7C15ULL;
    if (rng == 0) rng = 1;
    printf("djl_math.h against libm, %ld random arguments per generator:\n", n);
    test_unary(n);
    test_sqrt(n);
    test_binary(n);
    test_ldexp(n);
    test_hypot(n);
    test_exp2(n);
    printf("math: %d failures\n", failures);
    return failures ? 1 : 0;
}
