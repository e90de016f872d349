/* Double-double arithmetic: a time or an angle as hi + lo (|lo| <= ulp(hi) / 2), exact to about 106
 * bits, on plain IEEE double operations (dmath.h's error-free transformations), the same bits on every
 * platform. The exact scheme keeps its events' times so: a time rounded to a double at every event
 * would shift the motion against the excitation by an ulp of t each time (omega ulp(t) relative,
 * growing with t), and the same run cut into other communication steps would round elsewhere. A
 * harmonic's phase omega t + phi is carried the same way (dfo_dd_phase0, dfo_dd_theta), so that its
 * cosine is exact to rounding for any t and phi.
 *
 * Header only (static inline: the exact scheme's inner loops use them). Plain C, no FMI types. */
#ifndef DFO_DDOUBLE_H
#define DFO_DDOUBLE_H

#include "dmath.h"

/* pi/2, pi, 2 pi as double-doubles (hi + lo to 107 bits) */
#define DFO_PIO2_HI 0x1.921fb54442d18p+0
#define DFO_PIO2_LO 0x1.1a62633145c07p-54
#define DFO_PI_HI 0x1.921fb54442d18p+1
#define DFO_PI_LO 0x1.1a62633145c07p-53
#define DFO_TWOPI_HI 0x1.921fb54442d18p+2
#define DFO_TWOPI_LO 0x1.1a62633145c07p-52

typedef struct {
    double hi, lo;
} dfo_dd;

/* hi + lo renormalised (any hi, lo) */
static inline dfo_dd dfo_dd_of(double hi, double lo)
{
    dfo_dd r;
    dfo_two_sum(hi, lo, &r.hi, &r.lo);
    return r;
}

/* a + b */
static inline dfo_dd dfo_dd_add(dfo_dd a, dfo_dd b)
{
    dfo_dd r;
    double e;
    dfo_two_sum(a.hi, b.hi, &r.hi, &e);
    e += a.lo + b.lo;
    dfo_fast_two_sum(r.hi, e, &r.hi, &r.lo);
    return r;
}

/* a + (d + d_lo) / w (a time plus a span of tau or of phase over its rate) */
static inline dfo_dd dfo_dd_add_quot(dfo_dd a, double d, double d_lo, double w)
{
    const double q = d / w, p = q * w;
    const double q_lo = (((d - p) - dfo_two_prod_err(q, w, p)) + d_lo) / w;
    return dfo_dd_add(a, dfo_dd_of(q, q_lo));
}

/* a < b */
static inline int dfo_dd_lt(dfo_dd a, dfo_dd b) { return a.hi < b.hi || (a.hi == b.hi && a.lo < b.lo); }

/* b - a as a double (the span between two nearby times) */
static inline double dfo_dd_span(dfo_dd a, dfo_dd b) { return (b.hi - a.hi) + (b.lo - a.lo); }

/* A harmonic's phase at t = 0: phi mod 2 pi exactly (a large phi keeps its phase), then + pi when
 * negative is set (a negative amplitude written as a positive one). */
static inline dfo_dd dfo_dd_phase0(double phi, int negative)
{
    double rh, rl;
    const int q = dfo_rem_pio2(phi, 0.0, &rh, &rl);
    const double n = (q == 3) ? -1.0 : (double)q; /* n pi/2 + r, n in -1 ... 2: |phase| <= 5 pi / 4 */
    dfo_dd ph = dfo_dd_add(dfo_dd_of(rh, rl), dfo_dd_of(n * DFO_PIO2_HI, n * DFO_PIO2_LO));
    if (negative) ph = dfo_dd_add(ph, dfo_dd_of(-DFO_PI_HI, -DFO_PI_LO));
    return ph;
}

/* The phase omega t + ph at the time t (a double-double): exact to rounding for any t and ph (the
 * product omega t and the sum carried as double-doubles; not renormalised: dfo_rem_pio2 takes any
 * small tail). */
static inline dfo_dd dfo_dd_theta(double omega, dfo_dd ph, dfo_dd t)
{
    const double p = omega * t.hi;
    dfo_dd th;
    double e;
    dfo_two_sum(p, ph.hi, &th.hi, &e);
    th.lo = e + ((dfo_two_prod_err(omega, t.hi, p) + omega * t.lo) + ph.lo);
    return th;
}

#endif
