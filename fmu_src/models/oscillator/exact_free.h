/* The exact scheme without a spring (k = 0): a free mass on a rough support (method.md sections 1,
 * 5 and 10; one half of every split co-simulation),
 *
 *     m x'' + c x' = P0 cos(omega t + phi) + F_ext + F,   F Coulomb friction (mu_s, mu_k = chi mu_s, N),
 *
 * followed in closed form between its events, as exact_spring.c does for k > 0. A private header (exact.h
 * is the public one): exact.c's entry point dfo_exact_advance hands every k = 0 call to
 * dfo_exact_free_advance, which has the same contract
 * (exact.h): the state (t, X, V, mode, the stick phase's breakaway) is all a continuation needs, on
 * return A is the physical acceleration, hA = 0, F the friction force, the observables are exact and
 * the counter `steps` counts events.
 *
 * A slip phase in direction s from (t_a, x_a, v_a), tau = t - t_a, b = c / m, with the constant
 * acceleration f0 = (F_ext - s mu_k N) / m and the excitation's A = |P0| / m, theta = omega t + phase:
 *
 *     v(tau) = v_a e^{-b tau} + f0 tau phi1(-b tau) + A tau Re[e^{i theta_a} E1]
 *     x(tau) = x_a + v_a tau phi1(-b tau) + f0 tau^2 phi2(-b tau) + A tau^2 Re[e^{i theta_a} E2]
 *
 * with phi1(z) = (e^z - 1) / z, phi2(z) = (e^z - 1 - z) / z^2 and E1, E2 the first and second
 * divided differences of e^{lambda tau} over the nodes (-b, i omega) and (0, -b, i omega), over tau and
 * tau^2: a Taylor series where the nodes are within 1 / tau of each other, the phi1 form elsewhere.
 * c = 0 (polynomial + sinusoid) and c > 0 (exponential + sinusoid) are one formula without a case
 * split, exact in the limit b -> 0 and omega tau -> 0 (no 1/b, no 1/omega cancellation).
 *
 * Events, without ever stepping over a zero of s v: e^{b tau} v has the derivative e^{b tau} q with
 * q = A cos(theta) + f0, whose zeros are known in closed form (arccos). Between two consecutive zeros
 * of q, e^{b tau} v is monotone, so s v has at most one zero there, bracketed by the signs at the two
 * ends; it is polished by Newton's method kept inside the bracket (bisection otherwise). A tangential
 * touch (s v only touches 0) can only happen at a zero of q where e^{b tau} v has its minimum: it is
 * taken there when s v is within rounding of 0. A slide from rest (a breakaway, a reversal) starts
 * only if s q > 0 on the first interval: with chi >= 1 a breakaway starts on a zero of q (zero
 * acceleration), which is then passed over; a slide that cannot start leaves the block at rest and
 * the breakaway at that instant is passed over (no Zeno loop). Long slides: a lower bound of s v (its
 * monotone part less the amplitude of the harmonic part) skips the intervals in which it cannot
 * vanish, so a phase costs a few evaluations whatever its length. A stick phase ends at the
 * closed-form breakaway (dfo_next_breakaway: with k = 0 the static force does not depend on x).
 *
 * Inputs that vary as polynomials over a call (dfo_exact_advance_poly, exact.h) add the response to
 * the force's ramp and curvature, f1 tau^2 phi2(-b tau) + f2 tau^3 phi3(-b tau) in v, and make q a
 * polynomial plus a sinusoid: its zeros, and the breakaways, are then found by steps that a bound of
 * the second derivative proves free of a zero (docs/schemes.md).
 *
 * Plain C, no FMI types. */
#ifndef DFO_EXACT_FREE_H
#define DFO_EXACT_FREE_H

#include "exact_private.h"

/* Advance to t_target > s->t with the inputs held, for a model with k = 0: the contract of
 * dfo_exact_advance (exact.h). */
dfo_status dfo_exact_free_advance(const dfo_model *M, const dfo_inputs *u, dfo_state *s, double t_target,
                                  dfo_switch_fn on_switch, void *switch_ctx);

/* dfo_exact_advance_poly (exact.h) for a model with k = 0, over one piece of the call on which the
 * normal force is a polynomial: from the time q_t0, F_ext(t) = qF[0] + qF[1] q + qF[2] q^2 / 2 and
 * N(t) = qN[0] + qN[1] q + qN[2] q^2 / 2 (q = t - q_t0; N + N_ext(t), > 0 inside the piece, or all 0
 * where it is <= 0); u the inputs at q_t0. On return A, F are those at t_target with these loads. */
dfo_status dfo_exact_free_advance_poly(const dfo_model *M, const dfo_inputs *u, double q_t0, const double qF[3],
                                       const double qN[3], dfo_state *s, double t_target, dfo_switch_fn on_switch,
                                       void *switch_ctx);

/* dfo_exact_advance_poly (exact.h) for a model with k = 0 (q checked finite by the caller): the pieces
 * between the zeros of N + N_ext(t), each by dfo_exact_free_advance_poly. */
dfo_status dfo_exact_free_advance_pieces(const dfo_model *M, const dfo_inputs *u, const dfo_input_poly *q, dfo_state *s,
                                         double t_target, dfo_switch_fn on_switch, void *switch_ctx);

/* On a moving belt a slide's x may turn inside it (v through 0 while v - v_belt keeps its sign): the least
 * and the greatest x over [t0, t1] (ta <= t0; left alone when t1 < t0) of the slide in direction s from
 * (ta, X, V) with the inputs u held (poly NULL) or varying as poly = {q_t0, qF[3], qN[3]} (on one piece, as
 * dfo_exact_free_advance_poly's), physical units, k = 0: from its values at t0, t1 and at every zero of v
 * in between (found by the stop search on v itself); and its state at te in *Xe, *Ve. exact_belt.c's
 * observables of a belt without a spring. */
void dfo_exact_free_slide_extremes(const dfo_model *M, const dfo_inputs *u, const double *poly, double ta, double X,
                                   double V, int s, double t0, double t1, double te, double *lo, double *hi, double *Xe,
                                   double *Ve);

#endif
