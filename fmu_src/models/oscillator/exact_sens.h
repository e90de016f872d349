/* The exact scheme's sensitivity (private; exact_sens.c). */
#ifndef DFO_EXACT_SENS_H
#define DFO_EXACT_SENS_H

#include "oscillator.h"

/* The sensitivity (parameter sensitivity, exact scheme only): the Jacobian J = d(X, V) / d(X, V)(t_ref)
 * in s->J, row-major, propagated in closed form (method.md section 11). Each function updates J:
 *  - dfo_sens_slide: J = Phi(dt) J, Phi the state-transition matrix exp(A dt) of the slide dynamics
 *    m x'' + c x' + k x = forcing, A = [[0, 1], [-k/m, -c/m]] (the forcing does not enter);
 *  - dfo_sens_stick: the v row is 0 (a stop, and every stick phase: x frozen, v held at 0);
 *  - dfo_sens_reversal: the v row times a+ / a- (a slide that reverses at v = 0: the saltation
 *    [[1, 0], [0, a+/a-]]);
 *  - dfo_sens_breakaway: the v row becomes coef times the x row (a breakaway at t_b from a stick
 *    phase, whose v row is 0: dz = dz_b - f(t_b+) dt_b with dt_b = k dx / P'(t_b), coef = -a+ k / P';
 *    with polynomial inputs dt_b = k dx / D, D = P' + F_ext' - s max(mu_s, mu_k) N' at t_b, s the side:
 *    the rate of the force's excess h = s (P + F_ext - k x) - max(mu_s, mu_k) N over the limit). */
void dfo_sens_slide(const dfo_model *M, double dt, double J[4]);
void dfo_sens_stick(double J[4]);
void dfo_sens_reversal(double J[4], double ratio);
void dfo_sens_breakaway(double J[4], double coef);

#endif
