/* The oscillator's parameters as the C tests build them: every field 0 but the FMU's numerical
 * defaults (alpha = -0.1, observation window open, one friction update per step, fast paths), then
 * the physics given. */
#ifndef DFO_TEST_OSC_PARAMS_H
#define DFO_TEST_OSC_PARAMS_H

#include "oscillator.h"
#include <string.h>

static inline dfo_params osc_test_params(int scheme, double m, double k, double c, double P0, double omega,
                                         double N, double mu_s, double chi)
{
    dfo_params p;
    memset(&p, 0, sizeof p);
    p.m = m;
    p.k = k;
    p.c = c;
    p.P0 = P0;
    p.omega = omega;
    p.N = N;
    p.mu_s = mu_s;
    p.chi = chi;
    p.alpha = -0.1;
    p.t_obs_stop = 1e300;
    p.scheme = scheme;
    p.frictionUpdates = 1;
    p.fastPaths = 1;
    return p;
}

/* The Stribeck law on p, with the velocity v_s and the exponent delta (friction.h). */
static inline void osc_test_stribeck(dfo_params *p, double v_s, double delta)
{
    p->friction_law = DFO_LAW_STRIBECK;
    p->v_s = v_s;
    p->delta = delta;
}

/* The exact scheme's test case with an excitation, damping and stick-slip, started sliding. */
static inline dfo_params osc_test_exact_base(void)
{
    dfo_params p = osc_test_params(DFO_SCHEME_EXACT, 1.0, 1.0, 0.05, 1.0, 0.5, 0.4, 1.0, 0.7);
    p.x0 = 0.3;
    p.v0 = 0.5;
    return p;
}

#endif
