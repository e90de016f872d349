/* The friction rules shared by every scheme. See friction.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "friction.h"
#include "dmath.h"

#define TWO_PI (2.0 * DFO_PI)

/* Earliest theta >= th0 with cos(theta) > lim, as an offset from th0; acos_lim = acos(lim). */
static double until_above(double th0, double lim, double acos_lim)
{
    if (lim >= 1.0) return INFINITY;
    if (lim < -1.0) return 0.0;
    double psi = fmod(th0, TWO_PI);
    if (psi < 0.0) psi += TWO_PI;
    if (psi < acos_lim || psi > TWO_PI - acos_lim) return 0.0;
    return TWO_PI - acos_lim - psi;
}

double dfo_next_breakaway(const dfo_harmonic *P, const dfo_loads *L, double C0, double ta, int *dir)
{
    const double Fb = L->Fb, w = P->omega, amp = P->amp;
    if (w == 0.0 || amp == 0.0) { /* a constant force */
        const double F_static = dfo_harmonic_at(P, ta) + C0;
        *dir = dfo_sign(F_static);
        return (fabs(F_static) > Fb) ? ta : INFINITY;
    }
    const double lim_hi = (Fb - C0) / amp; /* F_static >  Fb  <=>  cos(theta)      > lim_hi */
    const double lim_lo = (Fb + C0) / amp; /* F_static < -Fb  <=>  cos(theta + pi) > lim_lo */
    const double acos_hi = (lim_hi > -1.0 && lim_hi < 1.0) ? dfo_acos(lim_hi) : 0.0;
    const double acos_lo = (lim_lo > -1.0 && lim_lo < 1.0) ? dfo_acos(lim_lo) : 0.0;
    const double th = w * ta + P->phase;
    const double up = until_above(th, lim_hi, acos_hi), down = until_above(th + DFO_PI, lim_lo, acos_lo);
    *dir = (up <= down) ? 1 : -1;
    return ta + fmin(up, down) / w;
}
