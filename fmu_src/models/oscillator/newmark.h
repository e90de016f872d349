/* Bossak-Newmark time stepping in velocity form with the friction LCP (method.md sections 2-4, 8).
 *
 * Three Bossak variants (dfo_scheme): the paper's literal scheme, the consistent stick test (first
 * order) and the located scheme (default; every stick/slip switch placed inside its step, second
 * order), advanced by dfo_bossak_advance below scheme.h's dfo_advance, which dispatches every scheme:
 * the friction engine's schemes (fmu_src/engine) specialised by the oscillator's operators
 * (osc_engine.h), the state, inputs, switches and observables mapped (osc_bossak.c: dfo_bossak_advance,
 * dfo_new_inputs, dfo_stuck_time, dfo_stick_fraction). Start-up, the outputs at a state and the grid
 * snapping (newmark.c) serve every scheme (the exact scheme's excitation is oscillator.h's
 * dfo_excitation_exact).
 * The internal grid is t0 + n h; dfo_advance ends exactly on any requested time off that grid with a
 * shortened step whose Bossak acceleration is corrected for the new length (method.md section 8),
 * and on the grid point itself when the requested time is a host's rounding of one (see "Snapping
 * to the grid" below).
 *
 * Plain C, no FMI types. */
#ifndef DFO_NEWMARK_H
#define DFO_NEWMARK_H

#include "oscillator.h"
#include "scheme_state.h"

/* Consistent start-up at t0 from x0, v0 (method.md section 4, "Start-up"). */
void dfo_start(const dfo_model *M, const dfo_inputs *in, double t0, dfo_state *s);

/* Empty the excitation cache of a state (it is rebuilt on demand, to the same bits). */
void dfo_forget_caches(dfo_state *s);

/* For a state that was not produced by this instance (e.g. a deserialised one): keep its excitation
 * cache only if it equals its recomputation, else empty it; a breakaway side out of range makes the
 * next breakaway be computed anew. */
void dfo_check_caches(const dfo_model *M, dfo_state *s);

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

/* The engine a caller may keep for its calls (osc_bossak.h; NULL: made per call). */
struct osc_bossak_engine_s;

/* dfo_advance (scheme.h) for the Bossak schemes (paper, consistent, located): its contract. */
dfo_status dfo_bossak_advance(const dfo_model *M, struct osc_bossak_engine_s *cache, const dfo_inputs *in,
                              dfo_state *s, double t_target, dfo_switch_fn on_switch, void *switch_ctx);

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
/* The same with the caller's engine (osc_bossak.h; NULL: made for the call). */
void dfo_new_inputs_cached(const dfo_model *M, struct osc_bossak_engine_s *cache, const dfo_inputs *old_in,
                           const dfo_inputs *new_in, dfo_state *s);

/* Physical acceleration at the current state (0 while stuck for the schemes whose stuck block is
 * at rest: consistent and located). */
double dfo_acceleration(const dfo_model *M, const dfo_inputs *in, const dfo_state *s);

/* The time derivative of the physical acceleration at the current state (0 while stuck, as
 * dfo_acceleration), from the time derivative of the equation of motion with the inputs' rates. */
double dfo_jerk(const dfo_model *M, const dfo_inputs *in, const dfo_state *s);

/* Share of the observed time spent stuck (0 before the window opens). */
double dfo_stick_fraction(const dfo_model *M, const dfo_state *s);

/* The stuck time observed so far: t_stuck and the part of the open stuck stretch (stuck_from) inside
 * the window. */
double dfo_stuck_time(const dfo_model *M, const dfo_state *s);

#endif
