/* The oscillator as a model of the friction engine (fmu_src/engine): one DOF, one contact to the
 * ground or its belt (w = 1). Its operators (M_hat a scalar), its friction solver (the 2 x 2 LCP of one
 * contact in closed form, belts; a Stribeck contact through the engine's dense solver) and its
 * closed-form breakaway (friction.h's dfo_next_breakaway: the engine's stuck fast path), and the
 * engine's schemes specialised by them (engine_step.h with the prefix osc_: osc_eng_start,
 * osc_eng_advance, ...). The engine object is made by osc_eng_create; the same operators through
 * eng_ops's function pointers (engine_generic.c's eng_* functions) give the same bits.
 *
 * The oscillator's Bossak schemes step with it: osc_bossak.c's dfo_bossak_advance (below scheme.h's
 * dfo_advance) makes the engine per call and maps the state, the inputs, the switches and the
 * observables (osc_eng_observe, inlined into the specialised schemes).
 *
 * Plain C, no FMI types. */
#ifndef DFO_OSC_ENGINE_H
#define DFO_OSC_ENGINE_H

#include "osc_engine_ops.h"
#include "oscillator.h"


/* The engine of the model M (its scheme, step, Bossak parameter, friction updates, fast paths, law)
 * over O (filled here; it must outlive the engine). NULL on failure (*err, if not NULL, says why). */
eng *osc_eng_create(const dfo_model *M, osc_eng_model *O, const eng_alloc *al, const char **err);

/* The inputs u as the engine reads them (arrays in b, which must outlive in's use): only the inputs
 * that were set, the derivatives only with a ramp. */
typedef struct {
    double F[1], N[1], vb[1], dF[2][1], dN[2][1];
} osc_eng_inbuf;
void osc_eng_inputs(const dfo_inputs *u, osc_eng_inbuf *b, eng_inputs *in);

/* The observer of the oscillator's observables (ctx: an osc_observables): osc_engine_ops.h's
 * osc_observe_phase, which the specialised schemes call inline. */
void osc_eng_observe(void *ctx, const eng_phase *ph, const eng_state *s);

/* engine.h's entry points, the schemes specialised by the oscillator's operators (osc_eng_start,
 * osc_eng_advance, ...), are declared by osc_engine_ops.h. */

#endif
