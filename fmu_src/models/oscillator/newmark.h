/* Bossak-Newmark time stepping in velocity form with the friction LCP (method.md sections 2-4, 8).
 *
 * Three Bossak variants (dfo_scheme): the paper's literal scheme, the consistent stick test (first
 * order) and the located scheme (default; every stick/slip switch placed inside its step, second
 * order). dfo_advance also dispatches the fourth scheme, exact (exact.h: closed form between events,
 * no Bossak step), so that every caller has one entry point.
 * The internal grid is t0 + n h; dfo_advance ends exactly on any requested time off that grid with a
 * shortened step whose Bossak acceleration is corrected for the new length (method.md section 8),
 * and on the grid point itself when the requested time is a host's rounding of one (see "Snapping
 * to the grid" below).
 *
 * Plain C, no FMI types. */
#ifndef DFO_NEWMARK_H
#define DFO_NEWMARK_H

#include "oscillator.h"

typedef enum {
    DFO_OK = 0,
    DFO_ERR_LCP = 1,          /* Lemke reported failure */
    DFO_ERR_NO_PROGRESS = 2,  /* too many switches inside one internal step */
    DFO_ERR_NONFINITE = 3,    /* the state overflowed */
    DFO_ERR_RESOLUTION = 4,   /* a step would not advance time (h below the resolution of t) */
    DFO_ERR_EVENTS = 5        /* the exact scheme: more than DFO_EXACT_MAX_EVENTS events in one call */
} dfo_status;

/* The exact scheme's work bound: the events (stops, reversals, breakaways, touches) one call of
 * dfo_advance may take, i.e. one communication step. It takes no step h, so its work is counted in
 * events, not in 1e9 h as the Bossak schemes' (DFO_MAX_STEPS_PER_CALL): 1e8 events are 25 million
 * periods of a block that sticks and slips twice per period, or 50 million of a frictionless one,
 * some 10 to 60 s of one core (0.1-0.6 us per event); a communication step that needs more is
 * refused with DFO_ERR_EVENTS, never an endless loop. (Defined before the include to try it smaller.) */
#ifndef DFO_EXACT_MAX_EVENTS
#define DFO_EXACT_MAX_EVENTS 100000000LL
#endif

typedef struct {
    /* time: the last internal grid point reached is t0 + n h; t is the current time */
    double t0, t;
    long long n;
    /* kinematics: position, velocity, Bossak acceleration variable, and the step length that
     * produced A (0 when A is a physical acceleration: start-up, stick, consistent restart) */
    double X, V, A, hA;
    double F;      /* friction force at t */
    int mode;      /* -1 backward slip, 0 stuck, +1 forward slip */
    double t_switch; /* the time of the last stick/slip switch of the Bossak schemes (-inf: none), as
                      * reported (a switch on a step's end: its t + h, to rounding) */
    /* in-FMU observables over [t_obs_start, t_obs_stop] (only updated when observe is on) */
    double x_max, x_min, t_stuck, E_friction;
    long long transitions;
    int observed;  /* a sample has been taken */
    /* the stick phase's next breakaway: time and side, computed at its first step for the constant
     * part of the static force stick_C = F_ext - k X and the limit stick_Fb (NaN: to be computed) */
    double stick_C, stick_Fb, stick_tb;
    int stick_dir;
    /* excitation cache: cos and sin of the excitation phase omega (t0 + exc_n h) + phi at the grid
     * point exc_n (-1: empty). A pure function of exc_n: exact at every multiple of DFO_EXC_ANCHOR,
     * advanced by rotations by omega h in between. */
    long long exc_n;
    double exc_c, exc_s;
    /* counters */
    long long steps, lcp_solves;
    /* the Jacobian d(X, V) / d(X, V)(t_ref), row-major (dX/dX0, dX/dV0, dV/dX0, dV/dV0), t_ref the end of
     * initialisation or the last state restore: propagated by the exact scheme when sensitivity is on */
    double J[4];
} dfo_state;

/* Consistent start-up at t0 from x0, v0 (method.md section 4, "Start-up"). */
void dfo_start(const dfo_model *M, const dfo_inputs *in, double t0, dfo_state *s);

/* Empty the excitation cache of a state (it is rebuilt on demand, to the same bits). */
void dfo_forget_caches(dfo_state *s);

/* For a state that was not produced by this instance (e.g. a deserialised one): keep its excitation
 * cache only if it equals its recomputation, else empty it; a breakaway side out of range makes the
 * next breakaway be computed anew. */
void dfo_check_caches(const dfo_model *M, dfo_state *s);

/* Called at every change of mode (stick/slip switch) with its time and position. */
typedef void (*dfo_switch_fn)(void *ctx, double t, double x, int from_mode, int to_mode);

/* Snapping to the grid. A host that builds its communication points by adding dt repeatedly asks
 * for t = 0.020000000000000011 where it means the grid point 0.02, and after 10^5 additions of
 * dt = 0.01 (or 0.001) its clock is off by 7.6e-10 s (1.1e-10 s): 3.4e3 (5.1e3) eps |t|, far more
 * than a few ulps. Honoured literally, every such remainder would become an extra shortened step
 * and the results would depend on the host's rounding. So a requested time within
 *
 *     tol(t) = min(1e-5 h, max(1e-7 h, 2^16 eps |t|))
 *
 * of a grid point t0 + m h is that grid point. The bounds:
 *  - 2^16 eps |t| covers the drift of a host that adds its step some 10^5 to 10^6 times (measured
 *    after 10^5 additions: 3.4e3, 5.1e3, 8.5e3 and 1.2e4 eps |t| for dt = 0.01, 0.001, 0.1 and
 *    0.0015); a clock that drifted farther is honoured as an off-grid time, with shortened steps;
 *  - the floor 1e-7 h covers small |t|; no meaningful time lies that close to a grid point;
 *  - the cap 1e-5 h bounds what a snap can change: a shift delta moves the state by about
 *    |v| delta, at most a relative 1e-5 rate h (rate: the model's fastest rate, rate_max), against
 *    the scheme's own error of order (rate h)^2 / 12: below a tenth of it wherever rate h >= 1e-3,
 *    below 1 % on the default model (rate h = 0.015). And the shift only undoes the host's own
 *    rounding: the point it means is the grid point.
 * A requested time farther than tol from every grid point is honoured exactly, with a shortened
 * step. */
double dfo_snap_tolerance(const dfo_model *M, double t);

/* The time dfo_advance ends on for t_target: the grid point t0 + m h (m >= s->n, at or after
 * s->t) that t_target snaps to, else t_target itself. */
double dfo_snap_target(const dfo_model *M, const dfo_state *s, double t_target);

/* Advance to t_target > s->t, with the inputs held constant, or with in->ramp varying as their
 * polynomials: every internal step (and sub-step of the located scheme) then takes the loads at its
 * end, and a stick phase's breakaway is the root of the varying static force (second order). The
 * exact scheme follows the polynomials in closed form (exact.h's dfo_exact_advance_poly; not with
 * k = 0 yet: dfo_exact_poly_unsupported, which the caller checks). on_switch may be NULL.
 * Contract: on DFO_OK, s->t is exactly dfo_snap_target(M, s_before, t_target): t_target itself or
 * the grid point it snapped to (the caller keeps and reports its own time). Everything after a
 * snap is exactly as if the grid point had been requested (same steps, same excitation cache,
 * same fast paths), so a host adding dt and a host computing n dt get bit-identical states. A
 * t_target that snaps to s->t itself is a no-op. */
dfo_status dfo_advance(const dfo_model *M, const dfo_inputs *in, dfo_state *s, double t_target,
                       dfo_switch_fn on_switch, void *switch_ctx);

/* The friction force at the current state with the inputs in, by the current mode's law: sliding
 * -mode mu_k N; stuck, the force that holds the block (the static force, clamped to the breakaway
 * limit), with the excitation evaluated as the stepper does. dfo_advance sets a stuck block's force
 * with it at the end of each call (schemes whose stuck block rests); the FMU uses it for inputs set
 * since the last step. */
double dfo_friction_force(const dfo_model *M, const dfo_inputs *in, const dfo_state *s);

/* Inputs changed at the communication point s->t (from old_in to new_in, held over the next step):
 * the acceleration jumps there. A sliding block's A takes the jump of the physical acceleration,
 * (dF_ext - mode d(mu_k N)) / m, and its F the new kinetic force, so that the Bossak step from s
 * starts on the right limit (without it, every input change costs a first-order error); a stuck
 * block's next step decides afresh. The exact scheme starts a new phase anyway: no change. */
void dfo_new_inputs(const dfo_model *M, const dfo_inputs *old_in, const dfo_inputs *new_in, dfo_state *s);

/* Physical acceleration at the current state (0 while stuck for the schemes whose stuck block is
 * at rest: consistent and located). */
double dfo_acceleration(const dfo_model *M, const dfo_inputs *in, const dfo_state *s);

/* The time derivative of the physical acceleration at the current state (0 while stuck, as
 * dfo_acceleration), from the time derivative of the equation of motion with the inputs' rates. */
double dfo_jerk(const dfo_model *M, const dfo_inputs *in, const dfo_state *s);

/* Share of the observed time spent stuck (0 before the window opens). */
double dfo_stick_fraction(const dfo_model *M, const dfo_state *s);

const char *dfo_status_text(dfo_status st);

#endif
