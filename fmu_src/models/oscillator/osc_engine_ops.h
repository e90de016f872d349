/* The oscillator as the friction engine sees it (osc_engine.h): its operators are the engine's of one
 * DOF with one contact (eng_one_dof.h: M_hat a scalar, the 2 x 2 LCP in closed form, the closed-form
 * breakaway), its observables kept from the engine's phases, inlined into the specialised schemes
 * (osc_engine.c; the bench's block). Plain C, no FMI types. */
#ifndef DFO_OSC_ENGINE_OPS_H
#define DFO_OSC_ENGINE_OPS_H

#include "eng_one_dof.h"
#include "engine.h"
#include "scheme_state.h"

#include <math.h>
#include <stddef.h>

typedef eng1_model osc_eng_model; /* (eng_one_dof.h) */

/* engine_step.h's schemes specialised by these operators (osc_engine.c): osc_eng_dense_friction, the
 * Stribeck contact's solver, and the rest (osc_engine.h) */
ENG_DECLARE_SCHEMES(osc_);

/* ---- the observables -------------------------------------------------------------------------- */

/* The part of [a, b] inside the window [w0, w1] (comparisons, not fmin/fmax: those are library calls
 * without -ffinite-math-only). */
static inline double osc_in_window(double w0, double w1, double a, double b)
{
    const double lo = (a > w0) ? a : w0, hi = (b < w1) ? b : w1;
    return (hi > lo) ? hi - lo : 0.0;
}

/* The in-FMU observables of the window [w0, w1], kept in the state s (scheme_state.h) from the
 * engine's phases: the observer's context (osc_engine.h's osc_eng_observe). */
typedef struct {
    double w0, w1;
    dfo_state *s;
} osc_observables;

/* The observables as one phase after another updates them: the window and the state's values, kept
 * in locals over a run of the engine's fused steps (ENG_OBS_RUN, osc_engine.c) so that they stay in
 * registers, written back when the run ends (on: the observer is osc_eng_observe's; else the steps
 * call the observer's function). */
typedef struct {
    int on, observed;
    int inside;  /* the run's last phase was sampled and ended at or after w0 (the next ones end after it) */
    int mode_in; /* that phase's mode at its start */
    double w0, w1, stuck_from, t_stuck, x_max, x_min, E_friction;
} osc_obs_vals;

/* the state's observables osc_obs_vals keeps (every field but on, inside, w0, w1) */
#define OSC_OBS_FIELDS(X) X(stuck_from) X(t_stuck) X(x_max) X(x_min) X(E_friction) X(observed)

static inline void osc_obs_load(osc_obs_vals *R, const osc_observables *O)
{
    const dfo_state *s = O->s;
    R->w0 = O->w0;
    R->w1 = O->w1;
#define OSC_OBS_LOAD_(f) R->f = s->f;
    OSC_OBS_FIELDS(OSC_OBS_LOAD_)
#undef OSC_OBS_LOAD_
}

static inline void osc_obs_store(const osc_obs_vals *R, const osc_observables *O)
{
    dfo_state *s = O->s;
#define OSC_OBS_STORE_(f) s->f = R->f;
    OSC_OBS_FIELDS(OSC_OBS_STORE_)
#undef OSC_OBS_STORE_
}

/* A phase [ta, tb] that overlaps the window (the engine calls no other): the stuck stretch opened or
 * closed at its start (its part inside the window added in one piece when a phase in another mode
 * begins, so that the stuck time is the same however the steps are taken), and where it ends inside
 * the window X sampled and the friction's work on the relative motion counted (none where it ends
 * on the window's start). */
static inline void osc_obs_stuck(osc_obs_vals *R, int mode0, double ta)
{
    if (mode0 == 0) {
        if (isnan(R->stuck_from)) R->stuck_from = ta;
    } else if (!isnan(R->stuck_from)) {
        const double d = osc_in_window(R->w0, R->w1, R->stuck_from, ta);
        if (d > 0.0) R->t_stuck += d;
        R->stuck_from = NAN;
    }
}

/* X sampled at the end of a phase inside the window (a sample taken before), and the friction's
 * work counted (work: the phase ends after the window's start) */
static inline void osc_obs_sample(osc_obs_vals *R, const eng_phase *ph, int work)
{
    const double X = ph->X1[0], dX = X - ph->X0[0];
    double W = ph->f[0] * (ph->v_belt ? dX - ph->v_belt[0] * (ph->tb - ph->ta) : dX);
    if (!work) W = 0.0;
    R->x_max = (X > R->x_max) ? X : R->x_max;
    R->x_min = (X < R->x_min) ? X : R->x_min;
    R->E_friction -= W;
}

static inline void osc_obs_phase(osc_obs_vals *R, const eng_phase *ph)
{
    const double tb = ph->tb;
    osc_obs_stuck(R, ph->mode0[0], ph->ta);
    if (tb < R->w0 || tb > R->w1) return;
    if (!R->observed) { R->x_max = R->x_min = ph->X1[0]; R->observed = 1; }
    osc_obs_sample(R, ph, tb > R->w0);
}

/* The observer's call for one phase (ctx: an osc_observables) */
static inline void osc_observe_phase(void *ctx, const eng_phase *ph, const eng_state *es)
{
    const osc_observables *O = (const osc_observables *)ctx;
    (void)es;
    osc_obs_vals R;
    osc_obs_load(&R, O);
    osc_obs_phase(&R, ph);
    osc_obs_store(&R, O);
}

#endif
