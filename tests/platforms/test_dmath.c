/* The FMU's own elementary functions (fmu_src/dmath.c) against the C library's.
 *
 *   test_dmath          compares dfo_sin, dfo_cos, dfo_exp, dfo_expm1, dfo_acos with libm (glibc on
 *                       Linux) over the ranges the model uses and beyond (sin/cos up to 1e300,
 *                       arguments next to multiples of pi/2, the whole range of exp, the ends of
 *                       acos), prints the largest difference in ulps and the share of identical
 *                       results per range, and fails if any difference exceeds MAX_ULPS or a special
 *                       value or one of the hard arguments' correctly rounded results is wrong, or
 *                       if dfo_sincos differs from dfo_sin, dfo_cos by a single bit.
 *                       dfo_atan2 within 4 ulps of atan2 on random points of every quadrant.
 *                       dfo_select with the bits of the ternary's choice (signed zeros, NaNs, ...).
 *   test_dmath --dump   prints the bits of every result (also dfo_pow_pos's, dfo_atan2's) on a fixed
 *                       set of arguments (no libm): the cross-platform check compares these dumps between Linux x86-64, Windows
 *                       (wine) and Linux aarch64 (qemu) bit for bit. */
#include <float.h>
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dmath.h"

#define MAX_ULPS 1

typedef double (*fn1)(double);

static uint64_t rng_next(uint64_t *s) /* xorshift64* */
{
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return *s * 0x2545F4914F6CDD1DULL;
}

static double uniform(uint64_t *s, double a, double b)
{
    return a + (b - a) * ((double)(rng_next(s) >> 11) * 0x1p-53);
}

/* log-uniform in [a, b] (0 < a < b), random sign; exact operations only (frexp, ldexp), so that
 * every platform draws the same arguments */
static double loguniform(uint64_t *s, double a, double b)
{
    int ea, eb;
    frexp(a, &ea);
    frexp(b, &eb);
    for (;;) {
        const int e = ea + (int)(rng_next(s) % (uint64_t)(eb - ea + 1));
        const double x = ldexp(1.0 + (double)(rng_next(s) >> 12) * 0x1p-52, e - 1);
        if (x >= a && x <= b) return (rng_next(s) & 1) ? -x : x;
    }
}

static int64_t ordered(double x) /* doubles in order as integers, ulps apart = difference */
{
    int64_t i;
    memcpy(&i, &x, sizeof i);
    return i < 0 ? INT64_MIN - i : i;
}

static uint64_t bits(double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

static double ulps(double a, double b)
{
    if (a != a || b != b) return (a != a && b != b) ? 0.0 : 1e30;
    const int64_t d = ordered(a) - ordered(b);
    return (double)(d < 0 ? -d : d);
}

typedef struct {
    const char *name;
    fn1 mine, ref;
} func;

static const func FUNCS[] = {{"sin", dfo_sin, sin}, {"cos", dfo_cos, cos}, {"exp", dfo_exp, exp},
                             {"expm1", dfo_expm1, expm1}, {"acos", dfo_acos, acos}};

typedef enum { UNIFORM, LOG, NEAR_PIO2 } kind;
typedef struct {
    int f; /* index in FUNCS */
    kind k;
    double a, b;
    const char *what;
} range;

static const range RANGES[] = {
    {0, UNIFORM, -0.785, 0.785, "|x| <= pi/4"},
    {0, UNIFORM, -20.0, 20.0, "|x| <= 20 (excitation phase, exact scheme)"},
    {0, UNIFORM, -1e6, 1e6, "|x| <= 1e6 (Cody-Waite)"},
    {0, LOG, 1e-300, 1e-5, "tiny"},
    {0, LOG, 1048576.0, 1e300, "2^20 .. 1e300 (Payne-Hanek)"},
    {0, NEAR_PIO2, 1.0, 1e6, "next to k pi/2"},
    {1, UNIFORM, -0.785, 0.785, "|x| <= pi/4"},
    {1, UNIFORM, -20.0, 20.0, "|x| <= 20"},
    {1, UNIFORM, -1e6, 1e6, "|x| <= 1e6"},
    {1, LOG, 1048576.0, 1e300, "2^20 .. 1e300"},
    {1, NEAR_PIO2, 1.0, 1e6, "next to k pi/2"},
    {2, UNIFORM, -50.0, 5.0, "-50 .. 5 (damping factors)"},
    {2, UNIFORM, -745.0, 709.7, "whole range"},
    {2, LOG, 1e-20, 1.0, "|x| <= 1"},
    {2, UNIFORM, -745.2, -708.0, "-745.2 .. -708 (subnormal results)"},
    {2, UNIFORM, 708.0, 709.78, "708 .. 709.78 (next to overflow)"},
    {3, UNIFORM, -0.35, 0.35, "|x| <= ln2/2"},
    {3, LOG, 1e-20, 1e-3, "tiny"},
    {3, UNIFORM, -40.0, 40.0, "-40 .. 40"},
    {3, UNIFORM, -1.5, 1.5, "-1.5 .. 1.5"},
    {3, UNIFORM, 40.0, 709.7, "40 .. 709.7"},
    {4, UNIFORM, -1.0, 1.0, "[-1, 1]"},
    {4, UNIFORM, -0.5, 0.5, "[-1/2, 1/2]"},
    {4, LOG, 1e-20, 1e-3, "1 - |x| tiny (ends)"},
};

#define N_PER_RANGE 200000

static double sample(uint64_t *s, const range *r)
{
    switch (r->k) {
    case UNIFORM: return uniform(s, r->a, r->b);
    case LOG: {
        const double x = loguniform(s, r->a, r->b);
        if (r->f == 4) return (x < 0.0) ? -1.0 - x : 1.0 - x; /* acos near the ends */
        return x;
    }
    default: { /* the double nearest k pi/2, and its neighbours */
        const double k = floor(uniform(s, r->a, r->b));
        double x = k * 1.5707963267948966;
        const int d = (int)(rng_next(s) % 5) - 2;
        for (int i = 0; i < (d < 0 ? -d : d); i++) x = nextafter(x, d < 0 ? 0.0 : 1e300);
        return x;
    }
    }
}

static int check_specials(void)
{
    int bad = 0;
    const double inf = INFINITY, nan_ = NAN;
#define EXPECT(cond)                                                                                 \
    do {                                                                                             \
        if (!(cond)) {                                                                               \
            printf("FAIL %s\n", #cond);                                                              \
            bad++;                                                                                   \
        }                                                                                            \
    } while (0)
    EXPECT(isnan(dfo_sin(inf)) && isnan(dfo_sin(-inf)) && isnan(dfo_sin(nan_)));
    EXPECT(isnan(dfo_cos(inf)) && isnan(dfo_cos(nan_)));
    double sv = 0.0, cv = 0.0;
    dfo_sincos(-inf, &sv, &cv);
    EXPECT(isnan(sv) && isnan(cv));
    dfo_sincos(-0.0, &sv, &cv);
    EXPECT(sv == 0.0 && signbit(sv) && cv == 1.0);
    dfo_sincos(1e-300, &sv, &cv);
    EXPECT(sv == 1e-300 && cv == 1.0);
    EXPECT(dfo_exp(-745.1) == 0x1p-1074 && dfo_exp(-709.0) == 0x0.8bfe55de02338p-1022);
    EXPECT(dfo_sin(0.0) == 0.0 && !signbit(dfo_sin(0.0)) && signbit(dfo_sin(-0.0)));
    EXPECT(dfo_cos(0.0) == 1.0 && dfo_cos(-0.0) == 1.0);
    EXPECT(dfo_exp(0.0) == 1.0 && dfo_exp(-inf) == 0.0 && dfo_exp(inf) == inf && isnan(dfo_exp(nan_)));
    EXPECT(dfo_exp(710.0) == inf && dfo_exp(-746.0) == 0.0 && dfo_exp(1.0) == 0x1.5bf0a8b145769p+1);
    EXPECT(dfo_exp(-745.0) > 0.0 && dfo_exp(709.78) < inf);
    EXPECT(dfo_expm1(0.0) == 0.0 && signbit(dfo_expm1(-0.0)) && dfo_expm1(-inf) == -1.0);
    EXPECT(dfo_expm1(inf) == inf && isnan(dfo_expm1(nan_)) && dfo_expm1(1e-300) == 1e-300);
    EXPECT(dfo_acos(1.0) == 0.0 && dfo_acos(-1.0) == 0x1.921fb54442d18p+1 && dfo_acos(0.0) == 0x1.921fb54442d18p+0);
    EXPECT(isnan(dfo_acos(1.0000000000000002)) && isnan(dfo_acos(-2.0)) && isnan(dfo_acos(nan_)));
    /* atan2: IEEE's special values, and within 4 ulps of libm on random points of every quadrant and
     * scale (the smaller side down to 1e-12 of the larger) */
    EXPECT(dfo_atan2(0.0, 1.0) == 0.0 && signbit(dfo_atan2(-0.0, 1.0)) && dfo_atan2(0.0, -1.0) == 0x1.921fb54442d18p+1);
    EXPECT(dfo_atan2(1.0, 0.0) == 0x1.921fb54442d18p+0 && dfo_atan2(-1.0, 0.0) == -0x1.921fb54442d18p+0);
    EXPECT(dfo_atan2(inf, inf) == atan2(inf, inf) && dfo_atan2(-inf, -inf) == atan2(-inf, -inf));
    EXPECT(isnan(dfo_atan2(nan_, 1.0)) && isnan(dfo_atan2(1.0, nan_)) && dfo_atan2(1e-300, 1e300) == atan2(1e-300, 1e300));
    {
        uint64_t st = 12345;
        double worst = 0.0;
        for (int i = 0; i < 200000; i++) {
            const double x = uniform(&st, -1.0, 1.0) * loguniform(&st, 1e-12, 1e12);
            const double y = uniform(&st, -1.0, 1.0) * fabs(x) * loguniform(&st, 1e-12, 1e12);
            const double d = (i & 1) ? ulps(dfo_atan2(y, x), atan2(y, x)) : ulps(dfo_atan2(x, y), atan2(x, y));
            worst = d > worst ? d : worst;
        }
        printf("atan2: worst %.0f ulps against libm on 200000 points\n", worst);
        EXPECT(worst <= 4.0);
    }
    /* Payne-Hanek against correctly rounded values (4000-bit arithmetic), not against libm: glibc
     * 2.36 returns cos(hard) 8 ulps off, and the compiler may fold sin(constant) correctly at -O2 but
     * not at -O0. hard = 6381956970095103 2^797 lies 2^-61 from a multiple of pi/2 (the hardest
     * double for the reduction). */
    volatile double hard_m = 6381956970095103.0, big = 1e22, top = DBL_MAX;
    const double hard = ldexp(hard_m, 797);
    EXPECT(dfo_sin(hard) == 1.0 && dfo_cos(hard) == -0x1.14ae72e6ba22fp-61);
    EXPECT(dfo_sin(big) == -0x1.b453ab76bf397p-1 && dfo_cos(big) == 0x1.0be2cef01c8f4p-1);
    EXPECT(dfo_sin(top) == 0x1.452fc98b34e97p-8 && dfo_cos(top) == -0x1.fffe62ecfab75p-1);
#undef EXPECT
    return bad;
}

/* dfo_select(c, a, b): the bits of c ? a : b for any c (0, 1, other values) and any a, b: signed
 * zeros, infinities, NaNs with payloads, subnormals, random doubles. Returns the failures. */
static int check_select(void)
{
    double v[12] = {0.0, -0.0, INFINITY, -INFINITY, DBL_MIN / 4.0, -DBL_MIN, 1.0, -3.5, DBL_MAX, 0.0, 0.0, 0.0};
    uint64_t nan_bits = 0x7FF8000000000123ULL, seed = 0x243F6A8885A308D3ULL;
    memcpy(&v[9], &nan_bits, sizeof nan_bits);
    nan_bits = 0xFFF0000000000001ULL; /* a signalling NaN's bits, negative */
    memcpy(&v[10], &nan_bits, sizeof nan_bits);
    const int cs[5] = {0, 1, -1, 2, 1 << 30};
    int bad = 0;
    for (int r = 0; r < 64; r++) {
        v[11] = ldexp(uniform(&seed, -1.0, 1.0), (int)(rng_next(&seed) % 2000) - 1000);
        for (size_t i = 0; i < 12; i++)
            for (size_t j = 0; j < 12; j++)
                for (size_t k = 0; k < 5; k++) {
                    const double want = cs[k] ? v[i] : v[j], got = dfo_select(cs[k], v[i], v[j]);
                    bad += bits(got) != bits(want);
                }
    }
    printf("dfo_select: %d of %d selections differ from the ternary's bits\n", bad, 64 * 12 * 12 * 5);
    return bad != 0;
}

static int compare(void)
{
    int failed = check_specials();
    failed |= check_select();
    uint64_t seed = 0x9E3779B97F4A7C15ULL;
    printf("%-6s %-44s %10s %10s\n", "fn", "range", "max ulps", "identical");
    for (size_t i = 0; i < sizeof RANGES / sizeof RANGES[0]; i++) {
        const range *r = &RANGES[i];
        const func *f = &FUNCS[r->f];
        double worst = 0.0, worst_x = 0.0;
        long same = 0;
        long sincos_differs = 0;
        for (int n = 0; n < N_PER_RANGE; n++) {
            const double x = sample(&seed, r);
            const double a = f->mine(x), b = f->ref(x), u = ulps(a, b);
            same += (bits(a) == bits(b));
            if (r->f <= 1) { /* dfo_sincos: bit for bit dfo_sin and dfo_cos */
                double sv, cv;
                dfo_sincos(x, &sv, &cv);
                sincos_differs += (bits(sv) != bits(dfo_sin(x))) || (bits(cv) != bits(dfo_cos(x)));
            }
            if (u > worst) {
                worst = u;
                worst_x = x;
            }
        }
        printf("%-6s %-44s %10.0f %9.4f%%%s\n", f->name, r->what, worst, 100.0 * same / N_PER_RANGE,
               worst > MAX_ULPS ? "  FAIL" : "");
        if (sincos_differs) {
            printf("       dfo_sincos differs from dfo_sin, dfo_cos on %ld arguments  FAIL\n", sincos_differs);
            failed++;
        }
        if (worst > MAX_ULPS) {
            printf("       worst at x = %a: %a vs libm %a\n", worst_x, f->mine(worst_x), f->ref(worst_x));
            failed++;
        }
    }
    /* dfo_pow_pos (the Stribeck law's (u / v_s)^delta): within 8 + 3 |y ln x| ulp of libm, the error
     * of exp at an exponent rounded to a double */
    {
        double worst = 0.0, wx = 0.0, wy = 0.0;
        for (int n = 0; n < N_PER_RANGE; n++) {
            const double x = fabs(loguniform(&seed, 1e-6, 1e6)), y = uniform(&seed, 0.2, 4.0);
            const double u = ulps(dfo_pow_pos(x, y), pow(x, y)) / (8.0 + 3.0 * fabs(y * log(x)));
            if (u > worst) { worst = u; wx = x; wy = y; }
        }
        printf("pow    x in [1e-6, 1e6], y in [0.2, 4]: worst %.3f of the bound 8 + 3 |y ln x| ulp%s\n", worst,
               worst > 1.0 ? "  FAIL" : "");
        if (worst > 1.0) {
            printf("       worst at x = %a, y = %a\n", wx, wy);
            failed++;
        }
        if (dfo_pow_pos(1.0, 3.0) != 1.0 || dfo_pow_pos(7.0, 0.0) != 1.0 || dfo_pow_pos(2.0, 1.0) != 2.0 ||
            !isnan(dfo_pow_pos(-2.0, 0.5)) || !isnan(dfo_pow_pos(INFINITY, 0.5)) || !isnan(dfo_pow_pos(0.0, 0.5))) {
            printf("       dfo_pow_pos: 1^y, x^0 or 2^1 not exact  FAIL\n");
            failed++;
        }
    }
    printf("test_dmath: %zu ranges x %d arguments, bound %d ulp, %d failed\n",
           sizeof RANGES / sizeof RANGES[0], N_PER_RANGE, MAX_ULPS, failed);
    return failed ? 1 : 0;
}

static int dump(void)
{
    uint64_t seed = 0x2545F4914F6CDD1DULL;
    for (size_t i = 0; i < sizeof RANGES / sizeof RANGES[0]; i++) {
        const range *r = &RANGES[i];
        for (int n = 0; n < 2000; n++) {
            const double x = sample(&seed, r);
            printf("%s %016" PRIx64 " %016" PRIx64 "\n", FUNCS[r->f].name, bits(x), bits(FUNCS[r->f].mine(x)));
        }
    }
    for (int n = 0; n < 2000; n++) {
        const double x = fabs(loguniform(&seed, 1e-6, 1e6)), y = uniform(&seed, 0.2, 4.0);
        printf("pow %016" PRIx64 " %016" PRIx64 " %016" PRIx64 "\n", bits(x), bits(y), bits(dfo_pow_pos(x, y)));
    }
    for (int n = 0; n < 2000; n++) {
        const double x = uniform(&seed, -1.0, 1.0) * loguniform(&seed, 1e-6, 1e6), y = uniform(&seed, -4.0, 4.0);
        printf("atan2 %016" PRIx64 " %016" PRIx64 " %016" PRIx64 "\n", bits(y), bits(x), bits(dfo_atan2(y, x)));
    }
    return 0;
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "--dump") == 0) return dump();
    return compare();
}
