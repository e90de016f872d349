/* The FMU's own elementary functions: sin, cos, exp, expm1, acos, written in plain C99 on IEEE
 * double arithmetic only (+, -, *, /, sqrt, integer operations), so that they return the same bits
 * on every platform and compiler (with -ffp-contract=off, no -ffast-math, no x87). The platforms'
 * libm differ (mingw's sin of a large argument, Microsoft's acos, ...); the FMU's numbers must not.
 *
 * Accuracy, measured against glibc by tests/platforms/test_dmath.c: sin, cos at most 1 ulp from glibc for
 * every finite argument (argument reduction to at least 85 bits: Cody-Waite with pi/2 in up to
 * four parts below 2^20, Payne-Hanek with 1280 bits of 2/pi above); exp, expm1, acos at most 1 ulp.
 * dfo_sincos(x, &s, &c) gives bit for bit dfo_sin(x) and dfo_cos(x) with one argument reduction. Special values follow
 * C99 Annex F (NaN in, NaN out; sin(inf) NaN; exp(-inf) 0; acos outside [-1, 1] NaN); the
 * floating-point flags are not part of the contract.
 *
 * Defining DFO_USE_LIBM maps the names to the platform's libm (to measure what they change). */
#ifndef DFO_DMATH_H
#define DFO_DMATH_H

#include <stdint.h>
#include <string.h>

/* ---- exact helpers (plain IEEE double operations, the same in both builds) ------------------- */

/* c ? a : b without a branch on c (the bits of a or b through a mask): for selects whose condition
 * follows data a branch predictor misses, such as contacts' mixed modes */
static inline double dfo_select(int c, double a, double b)
{
    uint64_t ua, ub;
    memcpy(&ua, &a, sizeof ua);
    memcpy(&ub, &b, sizeof ub);
    const uint64_t m = (uint64_t)0 - (uint64_t)(c != 0), r = (ua & m) | (ub & ~m);
    double x;
    memcpy(&x, &r, sizeof x);
    return x;
}

/* s + e = a + b exactly (Knuth's TwoSum: any a, b) */
static inline void dfo_two_sum(double a, double b, double *s, double *e)
{
    const double t = a + b, bb = t - a;
    *s = t;
    *e = (a - (t - bb)) + (b - bb);
}

/* s + e = a + b exactly, |a| >= |b| or a == 0 (Dekker's FastTwoSum) */
static inline void dfo_fast_two_sum(double a, double b, double *s, double *e)
{
    const double t = a + b;
    *s = t;
    *e = b - (t - a);
}

/* a * b - p exactly for p = fl(a * b) (Dekker's product by Veltkamp's split; no fused multiply-add;
 * |a|, |b| below 2^995 and a b not below 2^-969) */
static inline double dfo_two_prod_err(double a, double b, double p)
{
    const double split = 134217729.0; /* 2^27 + 1 */
    double t = split * a;
    const double ah = t - (t - a), al = a - ah;
    t = split * b;
    const double bh = t - (t - b), bl = b - bh;
    return ((ah * bh - p) + ah * bl + al * bh) + al * bl;
}

/* floor(log2 |x|) for a finite x != 0 (subnormals included) */
static inline int dfo_ilogb(double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    int e = (int)((u >> 52) & 0x7ff);
    if (e == 0) { /* subnormal: 2^-1074 times the integer mantissa */
        uint64_t m = u & 0x000fffffffffffffULL;
        e = -1075;
        while (m) { m >>= 1; e++; }
        return e;
    }
    return e - 1023;
}

/* 2^k for -1022 <= k <= 1023 */
static inline double dfo_pow2(int k)
{
    const uint64_t u = (uint64_t)(k + 1023) << 52;
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

#ifdef DFO_USE_LIBM
#include <math.h>
#define dfo_sin sin
#define dfo_cos cos
#define dfo_exp exp
#define dfo_expm1 expm1
#define dfo_acos acos
#define dfo_atan2 atan2
static inline void dfo_sincos(double x, double *s, double *c)
{
    *s = sin(x);
    *c = cos(x);
}
static inline int dfo_rem_pio2(double hi, double lo, double *r_hi, double *r_lo)
{
    const double n = nearbyint(hi * 0.63661977236758134308);
    *r_hi = (hi - n * 1.57079632679489661923) + lo;
    *r_lo = 0.0;
    return (int)fmod(fmod(n, 4.0) + 4.0, 4.0);
}
static inline void dfo_sincos_dd(double hi, double lo, double *s, double *c)
{
    *s = sin(hi + lo);
    *c = cos(hi + lo);
}
#else
double dfo_sin(double x);
double dfo_cos(double x);
double dfo_exp(double x);
double dfo_expm1(double x);
double dfo_acos(double x);
/* atan2(y, x) (IEEE's special values), within a few ulps of libm, the same bits on every platform */
double dfo_atan2(double y, double x);
/* x^y for x > 0 finite and y finite, the same bits on every platform (no libm): exp(y log x) with
 * log x to about an ulp, so within 8 + 3 |y ln x| ulp of libm (tests/platforms/test_dmath.c). */
double dfo_pow_pos(double x, double y); /* NaN for x <= 0 or not finite */
void dfo_sincos(double x, double *s, double *c);
/* The argument reduction of a double-double hi + lo (|lo| <= ulp(hi), hi finite): hi + lo =
 * n pi/2 + r_hi + r_lo with |r_hi| <= pi/4 + |lo| (+ a little), |r_lo| <= ulp(r_hi); returns n mod 4.
 * The remainder is exact to about 2^-85 relative to hi plus the rounding of lo: an angle known to
 * more than a double's precision (a phase omega t + phi at a time known as a double-double) keeps it. */
int dfo_rem_pio2(double hi, double lo, double *r_hi, double *r_lo);
/* sin and cos of hi + lo (as dfo_rem_pio2; non-finite hi: NaN) */
void dfo_sincos_dd(double hi, double lo, double *s, double *c);
#endif

#endif
