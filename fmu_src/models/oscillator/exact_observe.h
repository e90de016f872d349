/* The exact scheme's observables and switch reports (private; exact_observe.c): the bookkeeping after
 * each phase, shared by the phases of exact_spring.c and exact_free.c. The extremes of x in the
 * observation window are sampled at the phases' ends and at the window's edges (x is monotone inside a
 * slip phase on a support at rest), the stick time is a sum of intervals, the friction's work adds
 * mu_k N |dx| of each slide (or its integral with a varying normal force). */
#ifndef DFO_EXACT_OBSERVE_H
#define DFO_EXACT_OBSERVE_H

#include "exact_private.h"

/* x joins the window's extremes (the first sample sets them). */
void dfo_exact_sample(dfo_state *s, double x);

/* The grid index of s->t: t0 + n h <= t < t0 + (n + 1) h (the bookkeeping the FMU checks when a
 * state is loaded), shared by exact_spring.c and exact_free.c. */
long long dfo_exact_grid_index(const dfo_model *M, const dfo_state *s);

/* x of a slip phase at time t (from its start) by the phase's own closed form (ctx, phase: the
 * caller's); used at the observation window's edges. */
typedef double (*dfo_phase_x_fn)(const void *ctx, const void *phase, double t);

/* The bookkeeping after a phase [ta, tb] spent in mode_during from xa to xb, after which the mode is
 * mode_after (an event at tb when event is set), shared by exact_spring.c and exact_free.c: the switch
 * report, and (observe) the window's extremes, stick time, friction work mu_k N |dx| and
 * transitions. phase NULL: a stick phase (x frozen). */
void dfo_exact_after_phase(const dfo_model *M, double muk_N, dfo_switch_fn on_switch, void *switch_ctx,
                           dfo_state *s, dfo_phase_x_fn x_at, const void *ctx, const void *phase, double ta,
                           double tb, double xa, double xb, int mode_during, int mode_after, int event);

/* The friction work mu_k int N |dx| (physical) of a slip phase over [t0, t1] (times from its start) with
 * a varying normal force (ctx, phase: the caller's). */
typedef double (*dfo_phase_work_fn)(const void *ctx, const void *phase, double t0, double t1);

/* dfo_exact_after_phase with polynomial inputs, shared by exact_spring.c and exact_free.c: n the slide's normal
 * force n[0] + n[1] u + n[2] u^2 / 2 (physical; NULL: a stick phase). A constant one is the held inputs'
 * mu_k N |dx|; a varying one adds work(ctx, phase, ...) over the part of the phase inside the window. */
void dfo_exact_after_phase_poly(const dfo_model *M, dfo_switch_fn on_switch, void *switch_ctx, dfo_state *s,
                                dfo_phase_x_fn x_at, dfo_phase_work_fn work, const void *ctx, const void *phase,
                                const double *n, double ta, double tb, double xa, double xb, int mode_during,
                                int mode_after, int event);

#endif
