/* The oscillator's time stepping, one entry point for every scheme: dfo_advance dispatches to the
 * Bossak schemes (newmark.h: paper, consistent, located) and to the exact scheme (exact.h: closed
 * form between events, no Bossak step), peers below it that know nothing of each other. The state
 * and the status they share are scheme_state.h's; start-up, the outputs at a state and the grid
 * snapping are newmark.h's (for every scheme), included here so that a caller includes this header
 * only.
 *
 * Plain C, no FMI types. */
#ifndef DFO_SCHEME_H
#define DFO_SCHEME_H

#include "newmark.h"
#include "oscillator.h"
#include "scheme_state.h"

/* Advance to t_target > s->t, with the inputs held constant, or with in->ramp varying as their
 * polynomials: every internal step (and sub-step of the located scheme) then takes the loads at its
 * end, and a stick phase's breakaway is the root of the varying static force (second order). The
 * exact scheme follows the polynomials in closed form (exact.h's dfo_exact_advance_poly, where
 * dfo_exact_poly_unsupported says it can: the caller checks). on_switch may be NULL.
 * Contract: on DFO_OK, s->t is exactly dfo_snap_target(M, s_before, t_target): t_target itself or
 * the grid point it snapped to (the caller keeps and reports its own time). Everything after a
 * snap is exactly as if the grid point had been requested (same steps, same excitation cache,
 * same fast paths), so a host adding dt and a host computing n dt get bit-identical states. A
 * t_target that snaps to s->t itself is a no-op. The exact scheme has no grid to snap to: it ends
 * exactly on t_target, where its closed form is exact (two hosts whose clocks differ by rounding
 * get the motion at their times). */
dfo_status dfo_advance(const dfo_model *M, const dfo_inputs *in, dfo_state *s, double t_target,
                       dfo_switch_fn on_switch, void *switch_ctx);

/* dfo_advance with the caller's engine of the Bossak schemes (osc_bossak.h: made on first use, kept
 * while the model is the same; NULL: dfo_advance), to the same numbers without the set-up. */
dfo_status dfo_advance_cached(const dfo_model *M, struct osc_bossak_engine_s *cache, const dfo_inputs *in,
                              dfo_state *s, double t_target, dfo_switch_fn on_switch, void *switch_ctx);

/* A sentence for a status (for the FMU's log). */
const char *dfo_status_text(dfo_status st);

#endif
