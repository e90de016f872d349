/* Deterministic elementary functions (see dmath.h). Every constant is written in hexadecimal
 * (exact). The polynomials:
 *   sin, cos  |r| <= pi/4 (+ a little): Taylor terms to r^17 / r^18 (truncation below 0.01 ulp),
 *             evaluated in three independent chains (Estrin's split)
 *   exp       |r| <= ln2/256 (+ a little) after x = (k + j/128) ln2 + r: 2^(j/128) from a table of
 *             128 doubles with their relative tails, and the Taylor terms of e^r to r^5
 *             (truncation below 2^-60, 0.005 ulp)
 *   expm1     |r| <= ln2/2: Taylor terms to r^14
 *   asin      |s| <= 1/2: Taylor terms to s^53 (acos through asin)
 * Double-double steps (TwoSum, Dekker's product by Veltkamp splitting) keep the reduced argument
 * and the leading terms exact where it matters. No fused multiply-add is used or allowed. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "dmath.h"

#ifndef DFO_USE_LIBM

#include <float.h>
#include <math.h> /* sqrt only: correctly rounded by IEEE 754 on every platform */
#include <stdint.h>
#include <string.h>

#if defined(__GNUC__)
#define DFO_NOINLINE __attribute__((noinline))
#else
#define DFO_NOINLINE
#endif

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

/* s + e = a + b exactly, |a| >= |b| or a == 0 */
static void fast_two_sum(double a, double b, double *s, double *e)
{
    const double t = a + b;
    *s = t;
    *e = b - (t - a);
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
/* the rounded tails: P1T = P2 + P3 + P4, P2T = P3 + P4 (to the nearest double) */
static const double P1T = 0x1.0b4611a626331p-34, P2T = 0x1.3198a2e037073p-69;
/* round to the nearest integer by adding and subtracting 1.5 2^52 (IEEE round-to-nearest doubles,
 * no extended precision, no fused operations: the same on every platform); the integer is then in
 * the low bits of the sum */
static const double SHIFT = 0x1.8p52;
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

/* the rounding error of x * x: x * x - fl(x * x), exactly (Dekker, one Veltkamp split) */
static double two_sqr_err(double x, double z)
{
    const double t = 134217729.0 * x; /* 2^27 + 1 */
    const double xh = t - (t - x), xl = x - xh;
    return ((xh * xh - z) + 2.0 * xh * xl) + xl * xl;
}

/* sin(x + y), |x| <= pi/4 + a little, |y| <= ulp(x) */
static inline double ksin(double x, double y)
{
    const double z = x * x;
    const double z2 = z * z, z4 = z2 * z2; /* Estrin: three independent chains */
    const double p = (S3 + z * S5) + z2 * (S7 + z * S9) + z4 * ((S11 + z * S13) + z2 * (S15 + z * S17));
    return x + (x * z * p + y * (1.0 - 0.5 * z));
}

/* cos(x + y), same range; x^2 and 1 - x^2/2 carried exactly */
static inline double kcos(double x, double y)
{
    const double z = x * x, zl = two_sqr_err(x, z);
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
    const double pl = dfo_two_prod_err(da, PIO2_HI, ph) + (da * PIO2_LO + db * PIO2_HI);
    double rh, rl;
    fast_two_sum(ph, pl, &rh, &rl);
    *hi = neg ? -rh : rh;
    *lo = neg ? -rl : rl;
    return q;
}

/* reduce_large for a signed x (|x| >= 2^20), kept out of line: the common range stays small */
static DFO_NOINLINE int reduce_huge(double x, double ax, double *hi, double *lo)
{
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

/* x = n pi/2 + hi + lo, |hi + lo| <= pi/4 (+ a little); returns n mod 4. x finite. */
static inline int reduce(double x, double *hi, double *lo)
{
    const double ax = x < 0.0 ? -x : x;
    if (ax <= PIO4) {
        *hi = x;
        *lo = 0.0;
        return 0;
    }
    if (ax < 0x1p20) {
        /* Cody-Waite (fdlibm's e_rem_pio2.c): x - n P1 exactly, then n times the tail of pi/2 to
         * 85 bits; where that cancels (x close to a multiple of pi/2) a second and a third step
         * with P2, P3 carry it to 118 and 151 bits */
        const double t = x * INV_PIO2 + SHIFT;
        const int n = (int)(bits_of(t) & 3u); /* fn mod 4 (two's complement in the low bits) */
        const double fn = t - SHIFT;
        const int ex = (int)(bits_of(x) >> 52 & 0x7ff);
        double r = x - fn * P1; /* exact: fn P1 has at most 53 bits and lies within a factor 2 of x */
        double w = fn * P1T;
        double y = r - w;
        if (ex - (int)(bits_of(y) >> 52 & 0x7ff) > 16) {
            double u = r;
            w = fn * P2;
            r = u - w;
            w = fn * P2T - ((u - r) - w);
            y = r - w;
            if (ex - (int)(bits_of(y) >> 52 & 0x7ff) > 49) {
                u = r;
                w = fn * P3;
                r = u - w;
                w = fn * P4 - ((u - r) - w);
                y = r - w;
            }
        }
        *hi = y;
        *lo = (r - y) - w;
        return n;
    }
    return reduce_huge(x, ax, hi, lo);
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

void dfo_sincos(double x, double *s, double *c)
{
    const uint64_t a = ABS_BITS(bits_of(x));
    if (a >= EXP_ALL_ONES) {
        *s = *c = x - x;
        return;
    }
    if (a < 0x3e40000000000000ULL) { /* |x| < 2^-27: the same as dfo_sin, dfo_cos */
        *s = x;
        *c = 1.0;
        return;
    }
    double hi, lo;
    const int q = reduce(x, &hi, &lo);
    const double sr = ksin(hi, lo), cr = kcos(hi, lo);
    switch (q) {
    case 0: *s = sr; *c = cr; return;
    case 1: *s = cr; *c = -sr; return;
    case 2: *s = -sr; *c = -cr; return;
    default: *s = -cr; *c = sr; return;
    }
}

int dfo_rem_pio2(double hi, double lo, double *r_hi, double *r_lo)
{
    double h, l;
    const int q = reduce(hi, &h, &l);
    const double t = l + lo; /* |l| <= ulp(h), |lo| <= ulp(hi): t is tiny against 1 */
    dfo_two_sum(h, t, r_hi, r_lo);
    return q;
}

void dfo_sincos_dd(double hi, double lo, double *s, double *c)
{
    if (ABS_BITS(bits_of(hi)) >= EXP_ALL_ONES) {
        *s = *c = hi - hi;
        return;
    }
    double rh, rl;
    const int q = dfo_rem_pio2(hi, lo, &rh, &rl);
    const double sr = ksin(rh, rl), cr = kcos(rh, rl);
    switch (q) {
    case 0: *s = sr; *c = cr; return;
    case 1: *s = cr; *c = -sr; return;
    case 2: *s = -sr; *c = -cr; return;
    default: *s = -cr; *c = sr; return;
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

/* exp: x = (k + j/128) ln2 + r. EXP_TAB[2j] is the tail t_j and EXP_TAB[2j+1] the bits of s_j minus
 * j 2^45, where s_j is 2^(j/128) rounded to the nearest double and 2^(j/128) = s_j (1 + t_j) to
 * about 2^-105 (computed in 80-digit decimal arithmetic); adding (k 128 + j) 2^45 to the second word
 * gives the bits of 2^k s_j. */
#define EXP_N 128
static const double INV_LN2_N = 0x1.71547652b82fep+7;                           /* 128 / ln2 */
static const double LN2_N_HI = 0x1.62e42fefp-8, LN2_N_LO = 0x1.473de6af278edp-41; /* ln2 / 128 */
static const double X2 = 0x1p-1, X3 = 0x1.5555555555555p-3, X4 = 0x1.5555555555555p-5,
                    X5 = 0x1.1111111111111p-7; /* 1/k! */
static const uint64_t EXP_TAB[2 * EXP_N] = {
    0x0000000000000000ULL, 0x3ff0000000000000ULL, 0x3c9b3b4f1a88bf6eULL, 0x3feff63da9fb3335ULL,
    0xbc7160139cd8dc5dULL, 0x3fefec9a3e778061ULL, 0xbc905e7a108766d1ULL, 0x3fefe315e86e7f85ULL,
    0x3c8cd2523567f613ULL, 0x3fefd9b0d3158574ULL, 0xbc8bce8023f98efaULL, 0x3fefd06b29ddf6deULL,
    0x3c60f74e61e6c861ULL, 0x3fefc74518759bc8ULL, 0x3c90a3e45b33d399ULL, 0x3fefbe3ecac6f383ULL,
    0x3c979aa65d837b6dULL, 0x3fefb5586cf9890fULL, 0x3c8eb51a92fdeffcULL, 0x3fefac922b7247f7ULL,
    0x3c3ebe3d702f9cd1ULL, 0x3fefa3ec32d3d1a2ULL, 0xbc6a033489906e0bULL, 0x3fef9b66affed31bULL,
    0xbc9556522a2fbd0eULL, 0x3fef9301d0125b51ULL, 0xbc5080ef8c4eea55ULL, 0x3fef8abdc06c31ccULL,
    0xbc91c923b9d5f416ULL, 0x3fef829aaea92de0ULL, 0x3c80d3e3e95c55afULL, 0x3fef7a98c8a58e51ULL,
    0xbc801b15eaa59348ULL, 0x3fef72b83c7d517bULL, 0xbc8f1ff055de323dULL, 0x3fef6af9388c8deaULL,
    0x3c8b898c3f1353bfULL, 0x3fef635beb6fcb75ULL, 0xbc96d99c7611eb26ULL, 0x3fef5be084045cd4ULL,
    0x3c9aecf73e3a2f60ULL, 0x3fef54873168b9aaULL, 0xbc8fe782cb86389dULL, 0x3fef4d5022fcd91dULL,
    0x3c8a6f4144a6c38dULL, 0x3fef463b88628cd6ULL, 0x3c807a05b0e4047dULL, 0x3fef3f49917ddc96ULL,
    0x3c968efde3a8a894ULL, 0x3fef387a6e756238ULL, 0x3c875e18f274487dULL, 0x3fef31ce4fb2a63fULL,
    0x3c80472b981fe7f2ULL, 0x3fef2b4565e27cddULL, 0xbc96b87b3f71085eULL, 0x3fef24dfe1f56381ULL,
    0x3c82f7e16d09ab31ULL, 0x3fef1e9df51fdee1ULL, 0xbc3d219b1a6fbffaULL, 0x3fef187fd0dad990ULL,
    0x3c8b3782720c0ab4ULL, 0x3fef1285a6e4030bULL, 0x3c6e149289cecb8fULL, 0x3fef0cafa93e2f56ULL,
    0x3c834d754db0abb6ULL, 0x3fef06fe0a31b715ULL, 0x3c864201e2ac744cULL, 0x3fef0170fc4cd831ULL,
    0x3c8fdd395dd3f84aULL, 0x3feefc08b26416ffULL, 0xbc86a3803b8e5b04ULL, 0x3feef6c55f929ff1ULL,
    0xbc924aedcc4b5068ULL, 0x3feef1a7373aa9cbULL, 0xbc9907f81b512d8eULL, 0x3feeecae6d05d866ULL,
    0xbc71d1e83e9436d2ULL, 0x3feee7db34e59ff7ULL, 0xbc991919b3ce1b15ULL, 0x3feee32dc313a8e5ULL,
    0x3c859f48a72a4c6dULL, 0x3feedea64c123422ULL, 0xbc9312607a28698aULL, 0x3feeda4504ac801cULL,
    0xbc58a78f4817895bULL, 0x3feed60a21f72e2aULL, 0xbc7c2c9b67499a1bULL, 0x3feed1f5d950a897ULL,
    0x3c4363ed60c2ac11ULL, 0x3feece086061892dULL, 0x3c9666093b0664efULL, 0x3feeca41ed1d0057ULL,
    0x3c6ecce1daa10379ULL, 0x3feec6a2b5c13cd0ULL, 0x3c93ff8e3f0f1230ULL, 0x3feec32af0d7d3deULL,
    0x3c7690cebb7aafb0ULL, 0x3feebfdad5362a27ULL, 0x3c931dbdeb54e077ULL, 0x3feebcb299fddd0dULL,
    0xbc8f94340071a38eULL, 0x3feeb9b2769d2ca7ULL, 0xbc87deccdc93a349ULL, 0x3feeb6daa2cf6642ULL,
    0xbc78dec6bd0f385fULL, 0x3feeb42b569d4f82ULL, 0xbc861246ec7b5cf6ULL, 0x3feeb1a4ca5d920fULL,
    0x3c93350518fdd78eULL, 0x3feeaf4736b527daULL, 0x3c7b98b72f8a9b05ULL, 0x3feead12d497c7fdULL,
    0x3c9063e1e21c5409ULL, 0x3feeab07dd485429ULL, 0x3c34c7855019c6eaULL, 0x3feea9268a5946b7ULL,
    0x3c9432e62b64c035ULL, 0x3feea76f15ad2148ULL, 0xbc8ce44a6199769fULL, 0x3feea5e1b976dc09ULL,
    0xbc8c33c53bef4da8ULL, 0x3feea47eb03a5585ULL, 0xbc845378892be9aeULL, 0x3feea34634ccc320ULL,
    0xbc93cedd78565858ULL, 0x3feea23882552225ULL, 0x3c5710aa807e1964ULL, 0x3feea155d44ca973ULL,
    0xbc93b3efbf5e2228ULL, 0x3feea09e667f3bcdULL, 0xbc6a12ad8734b982ULL, 0x3feea012750bdabfULL,
    0xbc6367efb86da9eeULL, 0x3fee9fb23c651a2fULL, 0xbc80dc3d54e08851ULL, 0x3fee9f7df9519484ULL,
    0xbc781f647e5a3ecfULL, 0x3fee9f75e8ec5f74ULL, 0xbc86ee4ac08b7db0ULL, 0x3fee9f9a48a58174ULL,
    0xbc8619321e55e68aULL, 0x3fee9feb564267c9ULL, 0x3c909ccb5e09d4d3ULL, 0x3feea0694fde5d3fULL,
    0xbc7b32dcb94da51dULL, 0x3feea11473eb0187ULL, 0x3c94ecfd5467c06bULL, 0x3feea1ed0130c132ULL,
    0x3c65ebe1abd66c55ULL, 0x3feea2f336cf4e62ULL, 0xbc88a1c52fb3cf42ULL, 0x3feea427543e1a12ULL,
    0xbc9369b6f13b3734ULL, 0x3feea589994cce13ULL, 0xbc805e843a19ff1eULL, 0x3feea71a4623c7adULL,
    0xbc94d450d872576eULL, 0x3feea8d99b4492edULL, 0x3c90ad675b0e8a00ULL, 0x3feeaac7d98a6699ULL,
    0x3c8db72fc1f0eab4ULL, 0x3feeace5422aa0dbULL, 0xbc65b6609cc5e7ffULL, 0x3feeaf3216b5448cULL,
    0x3c7bf68359f35f44ULL, 0x3feeb1ae99157736ULL, 0xbc93091fa71e3d83ULL, 0x3feeb45b0b91ffc6ULL,
    0xbc5da9b88b6c1e29ULL, 0x3feeb737b0cdc5e5ULL, 0xbc6c23f97c90b959ULL, 0x3feeba44cbc8520fULL,
    0xbc92434322f4f9aaULL, 0x3feebd829fde4e50ULL, 0xbc85ca6cd7668e4bULL, 0x3feec0f170ca07baULL,
    0x3c71affc2b91ce27ULL, 0x3feec49182a3f090ULL, 0x3c6dd235e10a73bbULL, 0x3feec86319e32323ULL,
    0xbc87c50422622263ULL, 0x3feecc667b5de565ULL, 0x3c8b1c86e3e231d5ULL, 0x3feed09bec4a2d33ULL,
    0xbc91bbd1d3bcbb15ULL, 0x3feed503b23e255dULL, 0x3c90cc319cee31d2ULL, 0x3feed99e1330b358ULL,
    0x3c8469846e735ab3ULL, 0x3feede6b5579fdbfULL, 0xbc82dfcd978e9db4ULL, 0x3feee36bbfd3f37aULL,
    0x3c8c1a7792cb3387ULL, 0x3feee89f995ad3adULL, 0xbc907b8f4ad1d9faULL, 0x3feeee07298db666ULL,
    0xbc55c3d956dcaebaULL, 0x3feef3a2b84f15fbULL, 0xbc90a40e3da6f640ULL, 0x3feef9728de5593aULL,
    0xbc68d6f438ad9334ULL, 0x3feeff76f2fb5e47ULL, 0xbc91eee26b588a35ULL, 0x3fef05b030a1064aULL,
    0x3c74ffd70a5fddcdULL, 0x3fef0c1e904bc1d2ULL, 0xbc91bdfbfa9298acULL, 0x3fef12c25bd71e09ULL,
    0x3c736eae30af0cb3ULL, 0x3fef199bdd85529cULL, 0x3c8ee3325c9ffd94ULL, 0x3fef20ab5fffd07aULL,
    0x3c84e08fd10959acULL, 0x3fef27f12e57d14bULL, 0x3c63cdaf384e1a67ULL, 0x3fef2f6d9406e7b5ULL,
    0x3c676b2c6c921968ULL, 0x3fef3720dcef9069ULL, 0xbc808a1883ccb5d2ULL, 0x3fef3f0b555dc3faULL,
    0xbc8fad5d3ffffa6fULL, 0x3fef472d4a07897cULL, 0xbc900dae3875a949ULL, 0x3fef4f87080d89f2ULL,
    0x3c74a385a63d07a7ULL, 0x3fef5818dcfba487ULL, 0xbc82919e2040220fULL, 0x3fef60e316c98398ULL,
    0x3c8e5a50d5c192acULL, 0x3fef69e603db3285ULL, 0x3c843a59ac016b4bULL, 0x3fef7321f301b460ULL,
    0xbc82d52107b43e1fULL, 0x3fef7c97337b9b5fULL, 0xbc892ab93b470dc9ULL, 0x3fef864614f5a129ULL,
    0x3c74b604603a88d3ULL, 0x3fef902ee78b3ff6ULL, 0x3c83c5ec519d7271ULL, 0x3fef9a51fbc74c83ULL,
    0xbc8ff7128fd391f0ULL, 0x3fefa4afa2a490daULL, 0xbc8dae98e223747dULL, 0x3fefaf482d8e67f1ULL,
    0x3c8ec3bc41aa2008ULL, 0x3fefba1bee615a27ULL, 0x3c842b94c3a9eb32ULL, 0x3fefc52b376bba97ULL,
    0x3c8a64a931d185eeULL, 0x3fefd0765b6e4540ULL, 0xbc8e37bae43be3edULL, 0x3fefdbfdad9cbe14ULL,
    0x3c77893b4d91cd9dULL, 0x3fefe7c1819e90d8ULL, 0x3c5305c14160cc89ULL, 0x3feff3c22b8f71f1ULL,
};

double dfo_exp(double x)
{
    if (x != x) return x + x;
    if (x > EXP_MAX) return of_bits(EXP_ALL_ONES);
    if (x < -746.0) return 0.0;
    const uint64_t a = ABS_BITS(bits_of(x));
    if (a < 0x3c90000000000000ULL) return 1.0 + x; /* |x| < 2^-54 */
    const double t = x * INV_LN2_N + SHIFT;
    const uint64_t ki = bits_of(t); /* k 128 + j in the low bits (two's complement) */
    const double kd = t - SHIFT;
    /* kd LN2_N_HI is exact (|kd| < 2^18) and x - kd LN2_N_HI too (Sterbenz, or kd = 0) */
    const double r = (x - kd * LN2_N_HI) - kd * LN2_N_LO;
    const unsigned j = (unsigned)(ki % EXP_N);
    const double tail = of_bits(EXP_TAB[2 * j]);
    const double r2 = r * r;
    const double p = tail + r + r2 * (X2 + r * X3) + r2 * r2 * (X4 + r * X5); /* e^r (1 + t_j) - 1 */
    const uint64_t top = ki << 45; /* (k 128 + j) 2^45 mod 2^64: k in the exponent field */
    if (a < 0x4086200000000000ULL) { /* |x| < 708: 2^k s_j is a normal double */
        const double sc = of_bits(EXP_TAB[2 * j + 1] + top);
        return sc + sc * p;
    }
    if (x > 0.0) { /* 2^k s_j may overflow: scale by 2^-1009 first */
        const double sc = of_bits(EXP_TAB[2 * j + 1] + top - (1009ULL << 52));
        return 0x1p1009 * (sc + sc * p);
    }
    /* result near or in the subnormal range: form y = 2^(k+1022) s_j e^r, then round y 2^-1022
     * once (y - 1 + 1 rounds at the subnormal quantum when y < 1) */
    const double sc = of_bits(EXP_TAB[2 * j + 1] + top + (1022ULL << 52));
    double y = sc + sc * p;
    if (y < 1.0) {
        const double lo0 = sc - y + sc * p;
        const double h = 1.0 + y;
        const double lo = ((1.0 - h) + y) + lo0;
        y = (h + lo) - 1.0;
    }
    return 0x1p-1022 * y;
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
    /* Estrin's scheme: 13 pairs A[2i] + z A[2i+1], combined with z^2, z^4, z^8, z^16 */
    const double *A = ASIN_A;
    const double z2 = z * z, z4 = z2 * z2, z8 = z4 * z4, z16 = z8 * z8;
    const double p0 = A[0] + z * A[1], p1 = A[2] + z * A[3], p2 = A[4] + z * A[5], p3 = A[6] + z * A[7],
                 p4 = A[8] + z * A[9], p5 = A[10] + z * A[11], p6 = A[12] + z * A[13],
                 p7 = A[14] + z * A[15], p8 = A[16] + z * A[17], p9 = A[18] + z * A[19],
                 p10 = A[20] + z * A[21], p11 = A[22] + z * A[23], p12 = A[24] + z * A[25];
    const double q0 = p0 + z2 * p1, q1 = p2 + z2 * p3, q2 = p4 + z2 * p5, q3 = p6 + z2 * p7,
                 q4 = p8 + z2 * p9, q5 = p10 + z2 * p11;
    const double r0 = q0 + z4 * q1, r1 = q2 + z4 * q3, r2 = q4 + z4 * q5;
    return (r0 + z8 * r1) + z16 * (r2 + z8 * p12);
}

/* asin(sqrt(w)) for 0 <= w <= 1/4, the square root's rounding carried as a correction */
static double asin_sqrt(double w)
{
    if (w == 0.0) return 0.0;
    const double s = sqrt(w);
    const double ss = s * s;
    const double c = ((w - ss) - dfo_two_prod_err(s, s, ss)) / (s + s);
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

/* asin x for |x| <= 1 / sqrt(2) (a little beyond it by rounding): the kernels of dfo_acos */
static double asin_part(double x)
{
    const double ax = x < 0.0 ? -x : x;
    if (ax <= 0.5) return x + x * (x * x) * asin_poly(x * x);
    const double r = PIO2_HI - (2.0 * asin_sqrt((1.0 - ax) * 0.5) - PIO2_LO);
    return x < 0.0 ? -r : r;
}

double dfo_atan2(double y, double x)
{
    if (x != x || y != y) return x + y;
    const double ax = x < 0.0 ? -x : x, ay = y < 0.0 ? -y : y;
    double t; /* the angle of (|x|, |y|), in [0, pi/2] */
    if (ay == 0.0) t = 0.0;
    else if (ax == 0.0) t = PIO2_HI;
    else if (ax == INFINITY || ay == INFINITY) t = (ax == ay) ? 0.5 * PIO2_HI : (ax == INFINITY) ? 0.0 : PIO2_HI;
    else {
        /* scaled by a power of 2 (exact) so that the squares neither overflow nor underflow; the
         * smaller side over the radius is at most 1 / sqrt(2): asin is well conditioned there */
        const double m = ax > ay ? ax : ay;
        int e = 0;
        (void)frexp(m, &e);
        const double u = ldexp(ax, -e), v = ldexp(ay, -e), r = sqrt(u * u + v * v);
        t = (ay <= ax) ? asin_part(v / r) : PIO2_HI - (asin_part(u / r) - PIO2_LO);
    }
    if (signbit(x)) t = PI_HI - (t - PI_LO);
    return signbit(y) ? -t : t;
}

#else
typedef int dfo_dmath_uses_libm; /* ISO C: a translation unit is not empty */
#endif

/* log x for x > 0 finite: x = 2^k m, m in [sqrt(1/2), sqrt(2)), log m = 2 atanh(s), s = (m - 1) / (m + 1),
 * |s| < 0.172, by its series to s^27 (the next term is below 2^-70 of the sum), k ln 2 in two parts.
 * Plain double arithmetic: the same bits everywhere. */
static double log_pos(double x)
{
    int k = 0;
    while (x >= 0x1p+500) { x *= 0x1p-500; k += 500; }
    while (x < 0x1p-500) { x *= 0x1p+500; k -= 500; }
    while (x >= 2.0) { x *= 0.5; k++; }
    while (x < 1.0) { x *= 2.0; k--; }
    if (x > 1.4142135623730951) { x *= 0.5; k++; }
    const double s = (x - 1.0) / (x + 1.0), s2 = s * s;
    double sum = 1.0 / 27.0;
    for (int j = 25; j >= 1; j -= 2) sum = 1.0 / j + s2 * sum;
    const double LN2_HI = 6.93147180369123816490e-01, LN2_LO = 1.90821492927058770002e-10;
    return (k * LN2_HI + 2.0 * s * sum) + k * LN2_LO;
}

double dfo_pow_pos(double x, double y)
{
    if (x == 1.0 || y == 0.0) return 1.0;
    if (!(x > 0.0 && x <= DBL_MAX) || y != y) return NAN; /* outside the domain: never a loop */
    return dfo_exp(y * log_pos(x));
}
