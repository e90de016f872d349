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

#ifdef DFO_USE_LIBM
#include <math.h>
#define dfo_sin sin
#define dfo_cos cos
#define dfo_exp exp
#define dfo_expm1 expm1
#define dfo_acos acos
static inline void dfo_sincos(double x, double *s, double *c)
{
    *s = sin(x);
    *c = cos(x);
}
#else
double dfo_sin(double x);
double dfo_cos(double x);
double dfo_exp(double x);
double dfo_expm1(double x);
double dfo_acos(double x);
void dfo_sincos(double x, double *s, double *c);
#endif

#endif
