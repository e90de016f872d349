/* The harmonic excitation P0 cos(omega t + phi) that both models apply (the oscillator to its
 * block, the chain to each block), and its evaluation on the time grid t0 + n h shared by every
 * Bossak scheme: cos and sin of the phase at grid point n are exact at every multiple of
 * DFO_EXC_ANCHOR and rotations by omega h in between, from a cache of the previous point, so that
 * the value depends on n only, never on the history of the cache (method.md section 2).
 *
 * Plain C, no FMI types. */
#ifndef DFO_EXCITATION_H
#define DFO_EXCITATION_H

#include "dmath.h"

#include <math.h>

#ifndef DFO_PI
#define DFO_PI 3.14159265358979323846
#endif

#define DFO_EXC_ANCHOR 64  /* grid points between exact evaluations of the excitation phase */

/* P0 cos(omega t + phi), also written amp cos(omega t + phase) with amp = |P0| >= 0 (phase = phi,
 * + pi when P0 < 0): the form the closed-form breakaway (friction.h) reads. */
typedef struct {
    double omega, P0, phi;
    double amp, phase;
} dfo_harmonic;

static inline void dfo_harmonic_init(dfo_harmonic *H, double P0, double omega, double phi)
{
    H->omega = omega;
    H->P0 = P0;
    H->phi = phi;
    H->amp = fabs(P0);
    H->phase = phi + (P0 < 0.0 ? DFO_PI : 0.0);
}

/* P0 cos(omega t + phi) */
static inline double dfo_harmonic_at(const dfo_harmonic *H, double t) { return H->P0 * dfo_cos(H->omega * t + H->phi); }

/* Rotations keep c^2 + s^2 = 1 only to rounding: a cosine or sine read from them never exceeds 1. */
static inline double dfo_clamp1(double x) { return x > 1.0 ? 1.0 : x < -1.0 ? -1.0 : x; }

/* One grid step's rotation of (c, s) = (cos, sin) of the phase by (rc, rs) = (cos, sin) of omega h. */
static inline void dfo_phase_rotate(double *c, double *s, double rc, double rs)
{
    const double cn = *c * rc - *s * rs;
    *s = *s * rc + *c * rs;
    *c = cn;
}

/* cos and sin of the phase omega (t0 + n h) + phi at the grid point n >= 0 (not clamped): an exact
 * evaluation at the anchor below n and the rotations from there, those up to the cache's point taken
 * from the cache (cache_n, cache_c, cache_s; cache_n -1: empty) where it lies before n after the same
 * anchor (it holds those rotations' values: the same numbers, fewer rotations). */
static inline void dfo_grid_phase(double omega, double phi, double t0, double h, double rc, double rs,
                                  long long cache_n, double cache_c, double cache_s, long long n, double *c_out,
                                  double *s_out)
{
    double c, s;
    long long i;
    if (cache_n >= 0 && cache_n < n && cache_n / DFO_EXC_ANCHOR == n / DFO_EXC_ANCHOR) {
        c = cache_c;
        s = cache_s;
        i = cache_n;
    } else {
        i = n - n % DFO_EXC_ANCHOR;
        const double th = omega * (t0 + (double)i * h) + phi;
        dfo_sincos(th, &s, &c);
    }
    for (; i < n; i++) dfo_phase_rotate(&c, &s, rc, rs);
    *c_out = c;
    *s_out = s;
}

#endif
