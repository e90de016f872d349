/* The friction rules shared by every scheme. See friction.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "friction.h"
#include "dmath.h"

#include <float.h>

#define TWO_PI (2.0 * DFO_PI)

/* Earliest theta >= th0 with cos(theta) > lim, as an offset from th0; acos_lim = acos(lim) for
 * -1 <= lim < 1. lim = -1 (a limit that rounds to the static force's extreme, as a breakaway force
 * below the rounding of the excitation) needs acos(-1) = pi, not 0: cos > -1 everywhere but at pi,
 * so the offset is 0 (the force leaves the limit at once), never half a turn. */
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
    const double acos_hi = (lim_hi >= -1.0 && lim_hi < 1.0) ? dfo_acos(lim_hi) : 0.0;
    const double acos_lo = (lim_lo >= -1.0 && lim_lo < 1.0) ? dfo_acos(lim_lo) : 0.0;
    const double th = w * ta + P->phase;
    const double up = until_above(th, lim_hi, acos_hi), down = until_above(th + DFO_PI, lim_lo, acos_lo);
    *dir = (up <= down) ? 1 : -1;
    return ta + fmin(up, down) / w;
}

/* (u / v_s)^delta for u >= 0: exact products for delta 1 and 2 (the same bits everywhere). */
static double stribeck_power(const dfo_friction_law *F, double u)
{
    const double r = u / F->v_s;
    if (F->delta == 1.0) return r;
    if (F->delta == 2.0) return r * r;
    if (r == 0.0) return 0.0;
    return dfo_pow_pos(r, F->delta);
}

double dfo_friction_mu(const dfo_friction_law *F, double u)
{
    if (F->law != DFO_LAW_STRIBECK) return F->mu_k;
    return F->mu_k + (F->mu_s - F->mu_k) * dfo_exp(-stribeck_power(F, u));
}

double dfo_friction_dmu(const dfo_friction_law *F, double u)
{
    if (F->law != DFO_LAW_STRIBECK) return 0.0;
    const double r = u / F->v_s;
    /* d/du (r^delta) = delta r^(delta - 1) / v_s */
    double dp;
    if (F->delta == 1.0) dp = 1.0 / F->v_s;
    else if (F->delta == 2.0) dp = 2.0 * r / F->v_s;
    else if (r == 0.0) dp = F->delta > 1.0 ? 0.0 : INFINITY;
    else dp = F->delta * dfo_pow_pos(r, F->delta - 1.0) / F->v_s;
    return -(F->mu_s - F->mu_k) * dp * dfo_exp(-stribeck_power(F, u));
}

double dfo_stribeck_speed(const dfo_friction_law *F, double N, double q, double mh, double im)
{
    const double g0 = q - N * dfo_friction_mu(F, 0.0);
    if (!(g0 > 0.0)) return g0 * im;
    double u = fmax((q - N * fmin(F->mu_s, F->mu_k)) * im, DBL_MIN);
    for (int i = 0; i < 60; i++) {
        const double g = mh * u - q + N * dfo_friction_mu(F, u);
        const double dg = mh + N * dfo_friction_dmu(F, u);
        double u1 = (dg > 0.0) ? u - g / dg : 0.5 * u;
        if (!(u1 > 0.0)) u1 = 0.5 * u;
        const int done = fabs(u1 - u) <= 4.0 * DBL_EPSILON * u;
        u = u1;
        if (done) break;
    }
    return u;
}
