/* The exact scheme on a moving belt, v_belt set (private; exact_belt.c; exact.h says how). */
#ifndef DFO_EXACT_BELT_H
#define DFO_EXACT_BELT_H

#include "exact_private.h"

/* A call's start after a change of the belt (vb) at this communication point (the block keeps its
 * velocity): a stuck block whose velocity is not the belt's slides in the direction of v - vb, and a
 * sliding one whose v - vb now points against its mode slides the other way: a switch (reported,
 * observed). */
void dfo_exact_belt_start(const dfo_model *M, const dfo_inputs *u, double vb, dfo_state *s, dfo_switch_fn on_switch,
                          void *switch_ctx);

/* A call on a belt vb != 0, the inputs held (q NULL or inactive) or polynomial (q, checked finite by the
 * caller): with a spring, exact_spring.c's loop in the belt's terms; without one, the free mass in the
 * belt's frame (x - vb (t - t0), v - vb), where the motion is the one on a support at rest with the
 * force -c vb added, its observables but x's extremes those of that frame. */
dfo_status dfo_exact_belt_advance(const dfo_model *M, const dfo_inputs *u, const dfo_input_poly *q, dfo_state *s,
                                  double t_target, dfo_switch_fn on_switch, void *switch_ctx, double vb);

#endif
