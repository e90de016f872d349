/* Deterministic elementary functions (see dmath.h). Every constant is written in hexadecimal
 * (exact); the polynomial coefficients are the Taylor coefficients rounded to the nearest double,
 * with enough terms that the truncation stays below 0.01 ulp on the reduced ranges:
 *   sin, cos  |r| <= pi/4 (+ a few ulps),  terms to r^17 / r^18
 *   exp       |r| <= ln2/2,                terms to r^14
 *   asin      |s| <= 1/2,                  terms to s^53  (acos through asin)
 * Double-double steps (TwoSum, Dekker's product by Veltkamp splitting) keep the reduced argument
 * and the leading terms exact where it matters. No fused multiply-add is used or allowed. */
#include "dmath.h"

#ifndef DFO_USE_LIBM

#include <math.h> /* sqrt only: correctly rounded by IEEE 754 on every platform */
#include <stdint.h>
#include <string.h>

static uint64_t bits_of(double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

static double of_bits(uint64_t u)
{
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

/* 2^k for -1022 <= k <= 1023 */
static double pow2(int k) { return of_bits((uint64_t)(k + 1023) << 52); }

/* y 2^k for any k (two steps where 2^k itself is not a normal double) */
static double scale(double y, int k)
{
    if (k > 1023) return y * pow2(1023) * pow2(k - 1023);
    if (k < -1022) return y * pow2(-1022) * pow2(k + 1022);
    return y * pow2(k);
}

#define ABS_BITS(u) ((u) & 0x7fffffffffffffffULL)
#define EXP_ALL_ONES 0x7ff0000000000000ULL /* inf / NaN when ABS_BITS >= this */

/* s + e = a + b exactly (Knuth's TwoSum) */
static void two_sum(double a, double b, double *s, double *e)
{
    const double t = a + b, bb = t - a;
    *s = t;
    *e = (a - (t - bb)) + (b - bb);
}

/* s + e = a + b exactly, |a| >= |b| or a == 0 */
static void fast_two_sum(double a, double b, double *s, double *e)
{
    const double t = a + b;
    *s = t;
    *e = b - (t - a);
}

/* the rounding error of a * b: a * b - fl(a * b), exactly (Dekker, Veltkamp's split) */
static double two_prod_err(double a, double b, double p)
{
    const double split = 134217729.0; /* 2^27 + 1 */
    double t = split * a;
    const double ah = t - (t - a), al = a - ah;
    t = split * b;
    const double bh = t - (t - b), bl = b - bh;
    return ((ah * bh - p) + ah * bl + al * bh) + al * bl;
}

/* ---- constants ------------------------------------------------------------------------------ */

static const double PIO4 = 0x1.921fb54442d18p-1;
static const double PIO2_HI = 0x1.921fb54442d18p+0, PIO2_LO = 0x1.1a62633145c07p-54;
static const double PI_HI = 0x1.921fb54442d18p+1, PI_LO = 0x1.1a62633145c07p-53;
static const double INV_PIO2 = 0x1.45f306dc9c883p-1;
/* pi/2 = P1 + P2 + P3 + P4 (+ 2^-157): P1, P2, P3 with 33 significant bits, so that n P1, n P2,
 * n P3 are exact for |n| < 2^20 */
static const double P1 = 0x1.921fb544p+0, P2 = 0x1.0b4611a6p-34, P3 = 0x1.3198a2ep-69,
                    P4 = 0x1.b839a252049c1p-104;
/* ln 2 = LN2_HI + LN2_LO, LN2_HI with 32 significant bits (k LN2_HI exact for |k| < 2^21) */
static const double LN2_HI = 0x1.62e42feep-1, LN2_LO = 0x1.a39ef35793c76p-33;
static const double INV_LN2 = 0x1.71547652b82fep+0;

/* the bits of 2/pi: word j holds the bits of weights 2^-(32j+1) ... 2^-(32j+32) */
static const uint32_t TWO_OVER_PI[40] = {
    0xA2F9836E, 0x4E441529, 0xFC2757D1, 0xF534DDC0, 0xDB629599, 0x3C439041, 0xFE5163AB, 0xDEBBC561,
    0xB7246E3A, 0x424DD2E0, 0x06492EEA, 0x09D1921C, 0xFE1DEB1C, 0xB129A73E, 0xE88235F5, 0x2EBB4484,
    0xE99C7026, 0xB45F7E41, 0x3991D639, 0x835339F4, 0x9C845F8B, 0xBDF9283B, 0x1FF897FF, 0xDE05980F,
    0xEF2F118B, 0x5A0A6D1F, 0x6D367ECF, 0x27CB09B7, 0x4F463F66, 0x9E5FEA2D, 0x7527BAC7, 0xEBE5F17B,
    0x3D0739F7, 0x8A5292EA, 0x6BFB5FB1, 0x1F8D5D08, 0x56033046, 0xFC7B6BAB, 0xF0CFBC20, 0x9AF4361D};

/* sin r = r + r^3 (S3 + S5 r^2 + ...), S(2i+1) = (-1)^i / (2i+1)! */
static const double S3 = -0x1.5555555555555p-3, S5 = 0x1.1111111111111p-7, S7 = -0x1.a01a01a01a01ap-13,
                    S9 = 0x1.71de3a556c734p-19, S11 = -0x1.ae64567f544e4p-26, S13 = 0x1.6124613a86d09p-33,
                    S15 = -0x1.ae7f3e733b81fp-41, S17 = 0x1.952c77030ad4ap-49;
/* cos r = 1 - r^2/2 + r^4 (C4 + C6 r^2 + ...), C(2i) = (-1)^i / (2i)! */
static const double C4 = 0x1.5555555555555p-5, C6 = -0x1.6c16c16c16c17p-10, C8 = 0x1.a01a01a01a01ap-16,
                    C10 = -0x1.27e4fb7789f5cp-22, C12 = 0x1.1eed8eff8d898p-29, C14 = -0x1.93974a8c07c9dp-37,
                    C16 = 0x1.ae7f3e733b81fp-45, C18 = -0x1.6827863b97d97p-53;
/* exp r - 1 - r = r^2 (E2 + E3 r + ...), Ek = 1/k! */
static const double E2 = 0x1p-1, E3 = 0x1.5555555555555p-3, E4 = 0x1.5555555555555p-5,
                    E5 = 0x1.1111111111111p-7, E6 = 0x1.6c16c16c16c17p-10, E7 = 0x1.a01a01a01a01ap-13,
                    E8 = 0x1.a01a01a01a01ap-16, E9 = 0x1.71de3a556c734p-19, E10 = 0x1.27e4fb7789f5cp-22,
                    E11 = 0x1.ae64567f544e4p-26, E12 = 0x1.1eed8eff8d898p-29, E13 = 0x1.6124613a86d09p-33,
                    E14 = 0x1.93974a8c07c9dp-37;
/* asin s = s + s^3 (A[0] + A[1] s^2 + ...), A[n-1] = (2n)! / (4^n n!^2 (2n+1)) */
static const double ASIN_A[26] = {
    0x1.5555555555555p-3, 0x1.3333333333333p-4, 0x1.6db6db6db6db7p-5, 0x1.f1c71c71c71c7p-6,
    0x1.6e8ba2e8ba2e9p-6, 0x1.1c4ec4ec4ec4fp-6, 0x1.c99999999999ap-7, 0x1.7a87878787878p-7,
    0x1.3fde50d79435ep-7, 0x1.12ef3cf3cf3cfp-7, 0x1.df3bd37a6f4dfp-8, 0x1.a6863d70a3d71p-8,
    0x1.782dda12f684cp-8, 0x1.51ba308d3dcb1p-8, 0x1.31683bdef7bdfp-8, 0x1.15ee9d45d1746p-8,
    0x1.fcaf8fb6db6dbp-9, 0x1.d3d2a8e0dd67dp-9, 0x1.b026f57b13b14p-9, 0x1.90cb77f60c7cep-9,
    0x1.750de64d7d05fp-9, 0x1.5c5f56efaaaabp-9, 0x1.464c0950f7d47p-9, 0x1.3275586c5f2f0p-9,
    0x1.208d3570ae5a6p-9, 0x1.1052bc5fa960ap-9};

/* ---- sin and cos ---------------------------------------------------------------------------- */

/* sin(x + y), |x| <= pi/4 + a little, |y| <= ulp(x) */
static double ksin(double x, double y)
{
    const double z = x * x;
    const double z2 = z * z, z4 = z2 * z2; /* Estrin: three independent chains */
    const double p = (S3 + z * S5) + z2 * (S7 + z * S9) + z4 * ((S11 + z * S13) + z2 * (S15 + z * S17));
    return x + (x * z * p + y * (1.0 - 0.5 * z));
}

/* cos(x + y), same range; x^2 and 1 - x^2/2 carried exactly */
static double kcos(double x, double y)
{
    const double z = x * x, zl = two_prod_err(x, x, z);
    const double z2 = z * z, z4 = z2 * z2;
    const double q = (C4 + z * C6) + z2 * (C8 + z * C10) + z4 * ((C12 + z * C14) + z2 * (C16 + z * C18));
    const double hz = 0.5 * z, w = 1.0 - hz;
    return w + (((1.0 - w) - hz) + (z2 * q - x * y - 0.5 * zl));
}

/* bits pos ... pos+63 of the little-endian 32-bit limbs p[0..n-1] */
static uint64_t bits64(const uint64_t *p, int n, int pos)
{
    const int li = pos >> 5, sh = pos & 31;
    const uint64_t lo = p[li] | ((li + 1 < n) ? p[li + 1] << 32 : 0);
    const uint64_t hi = (li + 2 < n) ? p[li + 2] : 0;
    return sh ? (lo >> sh) | (hi << (64 - sh)) : lo;
}

/* ax * 2/pi for ax >= 2^20: the quadrant (mod 4) and ax - n pi/2 as hi + lo (Payne-Hanek: only the
 * 224 bits of 2/pi that matter mod 4 and to 190 bits below the binary point, multiplied exactly) */
static int reduce_large(double ax, double *hi, double *lo)
{
    const uint64_t u = bits_of(ax);
    const int E = (int)(u >> 52) - 1075; /* ax = M 2^E */
    const uint64_t M = (u & 0x000fffffffffffffULL) | 0x0010000000000000ULL;
    const uint64_t m0 = M & 0xffffffffULL, m1 = M >> 32;
    const int j0 = (E > 2) ? (E - 2) / 32 : 0; /* earlier words contribute multiples of 4 */
    uint64_t w[7], p[9];
    for (int i = 0; i < 7; i++) w[i] = TWO_OVER_PI[j0 + 6 - i];
    uint64_t carry = 0;
    for (int i = 0; i < 7; i++) {
        const uint64_t t = m0 * w[i] + carry;
        p[i] = t & 0xffffffffULL;
        carry = t >> 32;
    }
    p[7] = carry;
    carry = 0;
    for (int i = 0; i < 7; i++) {
        const uint64_t t = m1 * w[i] + p[i + 1] + carry;
        p[i + 1] = t & 0xffffffffULL;
        carry = t >> 32;
    }
    p[8] = carry;
    /* value = P 2^(E - 32 j0 - 224): s bits below the binary point */
    const int s = 32 * j0 + 224 - E;
    int q = (int)(bits64(p, 9, s) & 3u);
    uint64_t fh = bits64(p, 9, s - 64), fl = bits64(p, 9, s - 128);
    int neg = 0;
    if (fh >> 63) { /* fraction >= 1/2: the next quadrant, negative remainder */
        q = (q + 1) & 3;
        neg = 1;
        fl = ~fl + 1u;
        fh = ~fh + (fl == 0 ? 1u : 0u);
    }
    int lz = 0;
    if (fh == 0) { /* cannot happen for doubles (at most 61 bits cancel), kept for safety */
        fh = fl;
        fl = 0;
        lz = 64;
    }
    int k = 0;
    while (!(fh >> 63)) {
        fh = (fh << 1) | (fl >> 63);
        fl <<= 1;
        k++;
    }
    lz += k;
    const uint64_t a = fh >> 11, b = ((fh & 0x7ffULL) << 42) | (fl >> 22);
    const double da = (double)a * pow2(-53 - lz), db = (double)b * pow2(-106 - lz);
    /* (da + db) (PIO2_HI + PIO2_LO) in double-double */
    const double ph = da * PIO2_HI;
    const double pl = two_prod_err(da, PIO2_HI, ph) + (da * PIO2_LO + db * PIO2_HI);
    double rh, rl;
    fast_two_sum(ph, pl, &rh, &rl);
    *hi = neg ? -rh : rh;
    *lo = neg ? -rl : rl;
    return q;
}

/* x = n pi/2 + hi + lo, |hi + lo| <= pi/4 (+ a little); returns n mod 4. x finite. */
static int reduce(double x, double *hi, double *lo)
{
    const double ax = x < 0.0 ? -x : x;
    if (ax <= PIO4) {
        *hi = x;
        *lo = 0.0;
        return 0;
    }
    if (ax < 0x1p20) { /* Cody-Waite, pi/2 in four parts */
        const double t = x * INV_PIO2;
        const double fn = (double)(long long)(t < 0.0 ? t - 0.5 : t + 0.5);
        const double r1 = x - fn * P1; /* exact */
        double s1, e1, s2, e2, h, l;
        two_sum(r1, -(fn * P2), &s1, &e1);
        two_sum(s1, -(fn * P3), &s2, &e2);
        fast_two_sum(s2, (e1 + e2) - fn * P4, &h, &l);
        *hi = h;
        *lo = l;
        return (int)((unsigned long long)(long long)fn & 3u);
    }
    double h, l;
    int q = reduce_large(ax, &h, &l);
    if (x < 0.0) {
        h = -h;
        l = -l;
        q = (4 - q) & 3;
    }
    *hi = h;
    *lo = l;
    return q;
}

double dfo_sin(double x)
{
    const uint64_t a = ABS_BITS(bits_of(x));
    if (a >= EXP_ALL_ONES) return x - x;    /* NaN for NaN and +-inf */
    if (a < 0x3e50000000000000ULL) return x; /* |x| < 2^-26: sin x = x to the last bit */
    double hi, lo;
    switch (reduce(x, &hi, &lo)) {
    case 0: return ksin(hi, lo);
    case 1: return kcos(hi, lo);
    case 2: return -ksin(hi, lo);
    default: return -kcos(hi, lo);
    }
}

double dfo_cos(double x)
{
    const uint64_t a = ABS_BITS(bits_of(x));
    if (a >= EXP_ALL_ONES) return x - x;
    if (a < 0x3e40000000000000ULL) return 1.0; /* |x| < 2^-27 */
    double hi, lo;
    switch (reduce(x, &hi, &lo)) {
    case 0: return kcos(hi, lo);
    case 1: return -ksin(hi, lo);
    case 2: return -kcos(hi, lo);
    default: return ksin(hi, lo);
    }
}

/* ---- exp and expm1 -------------------------------------------------------------------------- */

static double expm1_poly(double r) /* exp(r) - 1 - r, |r| <= ln2/2 */
{
    return r * r * (E2 + r * (E3 + r * (E4 + r * (E5 + r * (E6 + r * (E7 + r * (E8 + r * (E9 + r * (E10 +
           r * (E11 + r * (E12 + r * (E13 + r * E14))))))))))));
}

/* x = k ln2 + r with |r| <= ln2/2 (+ a little); returns exp(r) - 1 (for |x| < 746) */
static double reduce_exp(double x, int *k)
{
    const double t = x * INV_LN2;
    const double fk = (double)(long long)(t < 0.0 ? t - 0.5 : t + 0.5);
    const double hi = x - fk * LN2_HI; /* exact */
    const double kl = fk * LN2_LO;
    const double r = hi - kl, rl = (hi - r) - kl;
    *k = (int)fk;
    return r + (expm1_poly(r) + rl * (1.0 + r));
}

static const double EXP_MAX = 0x1.62e42fefa39efp+9; /* ln(DBL_MAX) rounded down: 709.78... */

double dfo_exp(double x)
{
    if (x != x) return x + x;
    if (x > EXP_MAX) return of_bits(EXP_ALL_ONES);
    if (x < -746.0) return 0.0;
    const uint64_t a = ABS_BITS(bits_of(x));
    if (a < 0x3c90000000000000ULL) return 1.0 + x; /* |x| < 2^-54 */
    int k;
    const double em1 = reduce_exp(x, &k);
    return scale(1.0 + em1, k);
}

double dfo_expm1(double x)
{
    if (x != x) return x + x;
    if (x > EXP_MAX) return of_bits(EXP_ALL_ONES);
    if (x < -40.0) return -1.0; /* exp(-40) < 2^-57: -1 to the last bit */
    const uint64_t a = ABS_BITS(bits_of(x));
    if (a < 0x3c90000000000000ULL) return x;
    if (a <= 0x3fd62e42fefa39efULL) return x + expm1_poly(x); /* |x| <= ln2/2 */
    int k;
    const double em1 = reduce_exp(x, &k);
    if (k >= 53) return scale(1.0 + em1, k) - 1.0;
    const double two_k = pow2(k); /* -58 <= k <= 52 here */
    return (two_k - 1.0) + two_k * em1;
}

/* ---- acos ----------------------------------------------------------------------------------- */

static double asin_poly(double z) /* (asin s - s) / s^3 as a polynomial in z = s^2, s^2 <= 1/4 */
{
    double p = ASIN_A[25];
    for (int i = 24; i >= 0; i--) p = ASIN_A[i] + z * p;
    return p;
}

/* asin(sqrt(w)) for 0 <= w <= 1/4, the square root's rounding carried as a correction */
static double asin_sqrt(double w)
{
    if (w == 0.0) return 0.0;
    const double s = sqrt(w);
    const double ss = s * s;
    const double c = ((w - ss) - two_prod_err(s, s, ss)) / (s + s);
    return s + (c + s * w * asin_poly(w));
}

double dfo_acos(double x)
{
    if (x != x) return x + x;
    const double ax = x < 0.0 ? -x : x;
    if (ax > 1.0) return (x - x) / (x - x); /* NaN */
    if (ax <= 0.5) {
        const double p = x * (x * x) * asin_poly(x * x); /* asin x = x + p */
        return PIO2_HI - (x - (PIO2_LO - p));
    }
    if (x > 0.0) return 2.0 * asin_sqrt((1.0 - x) * 0.5); /* (1 - x) exact for x >= 1/2 */
    return PI_HI - (2.0 * asin_sqrt((1.0 + x) * 0.5) - PI_LO);
}

#else
typedef int dfo_dmath_uses_libm; /* ISO C: a translation unit is not empty */
#endif
