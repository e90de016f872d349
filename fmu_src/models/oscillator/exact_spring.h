/* The exact scheme's spring phase, k > 0 (private; exact_spring.c): a slide is, in tau = w0 (t - t_a)
 * and y = x - x_c, y'' + 2 zeta y' + y = a cos(theta_a + lambda tau) in closed form, its end the first
 * zero of s y' found by the certified stop search, a stick phase's end the closed-form breakaway (the
 * root of the varying static force with polynomial inputs); exact.h says how. Lengths over a power-of-2
 * scale chosen per call; times inside a call as double-doubles. The event loop is compiled once for
 * held and once for polynomial inputs; a belt (vb != 0) runs the polynomial inputs' loop. */
#ifndef DFO_EXACT_SPRING_H
#define DFO_EXACT_SPRING_H

#include "exact_private.h"

/* dfo_exact_advance for k > 0 and no belt. */
dfo_status dfo_exact_spring_advance(const dfo_model *M, const dfo_inputs *u, dfo_state *s, double t_target,
                                    dfo_switch_fn on_switch, void *switch_ctx);

/* dfo_exact_advance_poly for k > 0 (q checked finite by the caller), and every call on a belt vb != 0
 * (vb 0: none; q with zero derivatives for held inputs): the pieces between the zeros of N + N_ext(t),
 * each by the polynomial inputs' loop. */
dfo_status dfo_exact_spring_advance_poly(const dfo_model *M, const dfo_inputs *u, const dfo_input_poly *q, dfo_state *s,
                                         double t_target, dfo_switch_fn on_switch, void *switch_ctx, double vb);

#endif
