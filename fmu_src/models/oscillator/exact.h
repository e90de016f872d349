/* The exact scheme (scheme 4, method.md sections 5 and 10): the closed-form motion between events,
 * the events (stops, reversals, breakaways, tangential touches) found without ever stepping over a
 * zero of the velocity, the stick/slip decision at each event by the rules every scheme shares
 * (friction.h). Exact to rounding: no time step.
 *
 * Between two events the block slides in one direction s (friction -s mu_k N) or sticks. A slip
 * phase is, in tau = w0 (t - t_a) and y = x - x_c (x_c = (F_ext - s mu_k N) / k),
 *
 *     y'' + 2 zeta y' + y = a cos(theta_a + lambda tau),   a = |P0| / k,
 *
 * solved in closed form: the steady-state form plus the free motion (under-, critically and
 * over-damped bases), or, near resonance with little damping, the uniform form of method.md
 * section 5 in which lambda = 1, zeta = 0 is a limit. The phase ends where s y' reaches 0: the
 * search steps only as far as an exact bound of |y'''| proves s y' positive (the least of the
 * forced amplitude plus the free part's envelope, the energy bound and, near resonance, the bound
 * of the two parts' phasor sum; a cubic bound from rest, where a slide with chi >= 1 starts with
 * zero acceleration), guesses the stop on the Taylor model (the derivatives up to the sixth come
 * from the equation of motion), evaluates there and finishes on the quintic Taylor model of that
 * point when its remainder, bounded by |y^(7)|, is below rounding (Newton's method on it inside the
 * bracket otherwise), and takes a tangential touch at the minimum of s y' when that minimum is
 * within rounding of 0. About two evaluations per stop. A stick phase ends at the closed-form
 * breakaway (dfo_next_breakaway).
 *
 * Every call restarts a phase at its start time (the inputs F_ext, N_ext are held over the call, or vary
 * as the polynomials of their derivatives: dfo_exact_advance_poly below, docs/schemes.md), so
 * the state (t, X, V, mode) is all a continuation needs: FMU states and their serialisation continue
 * bit for bit (a stick phase's breakaway is found anew at each call, to the same time).
 *
 * Exact at the edges:
 *  - time: inside a call the events' times are double-doubles (a call starts and ends on the host's
 *    times, doubles), and the excitation phase omega t + phi at a phase start is computed from that
 *    absolute time (phi reduced mod 2 pi exactly, omega t carried as a double-double; carried over at
 *    most CARRY_MAX reversals in a row): one call over 1e6 periods equals one call per period to
 *    rounding, whatever phi. A slip phase longer than SPAN_TURNS turns restarts (not an event);
 *  - size: lengths are over a power-of-2 scale chosen at each call (exact), so that no square of the
 *    motion over- or underflows; a motion that leaves the double range is DFO_ERR_NONFINITE (never OK
 *    with a wrong number);
 *  - damping: near critical damping (wd or wh < 1/2) the free part is bounded without the modes'
 *    1 / wd, 1 / wh; over-damped away from it the derivatives come from the two modes (the equation
 *    of motion's recurrence would lose (2 zeta)^k), so a slow creep is followed to within a few ulps
 *    of its equilibrium. On return A is the physical acceleration, hA = 0, F the
 * friction force. Observables are exact: x is monotone in a slip phase, so the window's extremes
 * are at its ends, the stops and the window's edges (evaluated in closed form); the stick time is a
 * sum of intervals; E_friction adds mu_k N |dx| of each slip inside the window.
 *
 * The step h has no effect on the results. It keeps only its bookkeeping roles: the grid index n
 * (t0 + n h <= t < t0 + (n + 1) h, checked when a state is loaded). The work of one call is bounded by
 * its events (DFO_EXACT_MAX_EVENTS, below), not by h. The counter `steps` counts events.
 *
 * A moving belt (v_belt != 0, held; friction_law coulomb): a slide's motion does not depend on the belt,
 * only its end, the zero of s (v - v_belt) (the phase's velocity written relative to the belt, its
 * position that of the block); at it the rest rule decides with the holding force P + F_ext - c v_belt -
 * k x; a stuck block rides on the belt (x = x_a + v_belt (t - t_a), v = v_belt) and its holding force
 * drifts, so its breakaway is found by the polynomial inputs' search (every call on a belt runs that
 * loop; the held inputs' loop has none of the belt's code). A call whose belt changed at its start keeps
 * the block's velocity: a stuck block slides, a slide whose v - v_belt points the other way reverses.
 * x's extremes include the turning points inside slides (v through 0), E_friction is the work on the
 * relative motion, the sensitivity's saltations are those at v = v_belt. k = 0 on a belt: the belt's
 * frame, where the motion is the one on a support at rest with the force -c v_belt added (docs/belt.md).
 *
 * The files, one job each behind its private header (no file calls into one that calls it):
 *     exact.c          this header's calls: each to the phases of its kind (belt, no spring, spring)
 *     exact_spring.c   k > 0: the closed-form slide, the certified stop search, the breakaway, a
 *                      walk's phases (held and polynomial inputs; on a belt)           exact_spring.h
 *     exact_free.c     k = 0: a free mass on a rough support, a walk's phases          exact_free.h
 *     exact_loop.h     the one event loop of every walk: the work and stall bounds, the choice of
 *                      the phase, the rule at a stop and its saltation (header only)
 *     exact_belt.c     a moving belt: the call's start after a change, k = 0 in the belt's frame
 *                                                                                     exact_belt.h
 *     exact_poly.c     polynomial inputs: the inputs at t, the pieces of the normal force
 *                                                                                     exact_poly.h
 *     exact_observe.c  the observables and switch reports after each phase; the grid index
 *                                                                                     exact_observe.h
 *     exact_sens.c     the sensitivity's closed forms                                 exact_sens.h
 * and what they share, exact_private.h. Double-double arithmetic: numerics/ddouble.h. Plain C, no FMI
 * types. */
#ifndef DFO_EXACT_H
#define DFO_EXACT_H

#include "oscillator.h"
#include "scheme_state.h"

/* The exact scheme's work bound: the events (stops, reversals, breakaways, touches) one call of
 * dfo_advance may take, i.e. one communication step. It takes no step h, so its work is counted in
 * events, not in 1e9 h as the Bossak schemes' (DFO_MAX_STEPS_PER_CALL): 1e8 events are 25 million
 * periods of a block that sticks and slips twice per period, or 50 million of a frictionless one,
 * some 10 to 60 s of one core (0.1-0.6 us per event); a communication step that needs more is
 * refused with DFO_ERR_EVENTS, never an endless loop. (Defined before the include to try it smaller.) */
#ifndef DFO_EXACT_MAX_EVENTS
#define DFO_EXACT_MAX_EVENTS 100000000LL
#endif

/* Advance to t_target > s->t with the inputs held: the contract of dfo_advance (scheme.h). */
dfo_status dfo_exact_advance(const dfo_model *M, const dfo_inputs *u, dfo_state *s, double t_target,
                             dfo_switch_fn on_switch, void *switch_ctx);

/* Inputs that vary over one call as polynomials (FMI input derivatives, which hold for one
 * communication step): from the time t0 (the communication point),
 *
 *     F_ext(t) = F_ext + F[0] (t - t0) + F[1] (t - t0)^2 / 2,   N_ext(t) likewise with N[0], N[1],
 *
 * F_ext, N_ext the values of dfo_inputs at t0 (dfo_external_force, and N_ext as dfo_normal_force reads
 * it); F[0], N[0] the first derivatives, F[1], N[1] the second (0: that order not given). The
 * derivatives are used whether or not the value itself was set (an input never set is 0 at t0). The
 * normal force is max(N + N_ext(t), 0). */
typedef struct {
    double t0;
    double F[2], N[2];
} dfo_input_poly;

/* 1 when a derivative of q is nonzero (then dfo_exact_advance_poly takes its polynomial path), else 0
 * (q NULL included). */
int dfo_input_poly_active(const dfo_input_poly *q);

/* The inputs at time t: out->F_ext = F_ext(t), out->N_ext = N_ext(t) (q's polynomials; the set flags
 * copied from u, and raised where q has a nonzero derivative of that input). q NULL: *out = *u. */
void dfo_input_poly_at(const dfo_inputs *u, const dfo_input_poly *q, double t, dfo_inputs *out);

/* NULL when dfo_exact_advance_poly can follow polynomial inputs on this model, else a sentence saying
 * why not (for the FMU's error message when a host sets an input derivative). Every model can
 * (k > 0 and k = 0): NULL. */
const char *dfo_exact_poly_unsupported(const dfo_model *M);

/* Advance to t_target > s->t with the inputs varying as q's polynomials (q->t0 <= s->t): the contract
 * of dfo_exact_advance otherwise (on return A, F are those at t_target with the inputs there). When
 * no derivative is nonzero (dfo_input_poly_active(q) == 0) it is dfo_exact_advance itself, bit for bit.
 * A non-finite derivative or t0 is DFO_ERR_NONFINITE with the state untouched (the caller should refuse
 * it first, naming the variable). */
dfo_status dfo_exact_advance_poly(const dfo_model *M, const dfo_inputs *u, const dfo_input_poly *q, dfo_state *s,
                                  double t_target, dfo_switch_fn on_switch, void *switch_ctx);

#endif
