/* The instance of the DryFrictionOscillator FMUs and the private interface of its core, split by
 * concern (the model API of core/instance.h):
 *   osc_instance.c     start values, the model derived from the parameters, the life cycle, the input
 *                      derivatives a scheme cannot follow
 *   osc_inst_vars.c    variable access: value references, get/set, the outputs
 *   osc_inst_step.c    doStep (with early return when asked for)
 *   osc_inst_events.c  FMI 3.0's doStep with events (early return, event mode, intermediate update)
 *   osc_inst_state.c   FMU-state copies and their serialisation (core/fmu_state.h's format)
 *   osc_inst_deriv.c   coupling at second order: input, output, directional and adjoint derivatives
 *   osc_inst_me.c      Model Exchange (core/instance_me.h): derivatives, event indicators, events
 * Each calls only the ones listed above it (osc_inst_state.c and osc_inst_deriv.c: the life cycle
 * and the variables; osc_inst_me.c: the life cycle and the switch callback of osc_inst_step.c).
 *
 * The instance: the life cycle first, then the values that define where a simulation is, plain
 * values without pointers (an FMU state copies them, its serialisation writes their bytes). The
 * variable table generated from modelDescription.xml (model_vars.h) reaches the parameters and
 * inputs by offsetof into osc_values' p and u. No FMI types. */
#ifndef DFO_OSC_INSTANCE_H
#define DFO_OSC_INSTANCE_H

#include "instance_common.h"
#include "model_vars.h"
#include "oscillator.h"
#include "scheme.h"
#include "osc_bossak.h"

typedef struct {
    dfo_params p;
    dfo_inputs u;
    dfo_inputs u_used;        /* the inputs of the last step (or of initialisation) */
    dfo_model M;
    dfo_state s;
    double t_switch;          /* the time of the last stick/slip switch a step met (-inf: none) */
    int effects;
} osc_values;

typedef struct {
    dfo_lifecycle lc;         /* first: the glues see the instance as its life cycle */
    osc_values v;
    osc_bossak_engine eng;    /* the Bossak schemes' engine (no part of the values: a cache) */
    int me;                   /* made for Model Exchange (osc_inst_me.c): the host integrates x, v */
} osc_instance;

static inline osc_instance *osc(dfo_lifecycle *lc) { return (osc_instance *)lc; }
static inline const osc_instance *cosc(const dfo_lifecycle *lc) { return (const osc_instance *)lc; }

/* Where a stored value lives in v (parameters and inputs only). */
static inline void *osc_slot(osc_values *v, const dfo_var_info *var) { return dfo_var_slot(&v->p, &v->u, var); }
static inline const void *osc_cslot(const osc_values *v, const dfo_var_info *var)
{
    return osc_slot((osc_values *)v, var);
}

/* ---- osc_instance.c ---- */
/* The sensitivity's reference: the Jacobian is the identity at the end of initialisation and at
 * every state restore. */
void osc_inst_sens_reset(dfo_state *s);
/* The values with the started model: the instance's own, or during initialisation a copy in tmp
 * with the model derived from the current parameters. */
const osc_values *osc_inst_computed(const osc_instance *in, osc_values *tmp);
/* The force scale of a run: max(|P0|, max(mu_s, mu_k) N, k |x0|, sqrt(k m) |v0|) (N). */
double osc_inst_force_scale(const dfo_params *p);
/* The scheme's name in the model description ("?" out of range). */
const char *osc_inst_scheme_name(int scheme);
/* Why the exact scheme cannot follow input derivatives on these parameters (NULL: it can, and the
 * Bossak schemes always can). */
const char *osc_inst_ramp_unsupported(const dfo_params *p);
/* Input derivatives set that the scheme cannot follow: an error naming the inputs and the scheme. */
dfo_inst_status osc_inst_ramp_refused(osc_instance *in, const char *fn);

/* ---- osc_inst_vars.c ---- */
/* Whether the inputs (values and set flags) are those of the last step. */
int osc_inst_same_inputs(const dfo_inputs *a, const dfo_inputs *b);
/* The friction force and the acceleration at the current state for the current inputs (with the
 * inputs of the last step the stepper's own). */
double osc_inst_friction_now(const osc_values *v);
double osc_inst_acceleration_now(const osc_values *v);
/* A pending event's left limit: the state at the switch in the mode before it, with that mode's
 * friction force. */
dfo_state osc_inst_left_limit(const osc_values *v, int event_from);

/* Model Exchange's physics at the current state (osc_inst_me.c), written with the schemes' (newmark.h,
 * friction.h): the loads under the current inputs, whether friction acts; the static force on the
 * block at rest on the belt; the friction force (in *F, if not NULL) and the acceleration in the
 * current mode (stuck: 0); the two event indicators (the outputs event_indicator_0, _1). */
int osc_inst_loads(const osc_values *v, dfo_loads *L);
double osc_inst_static_force(const osc_values *v, const dfo_loads *L);
double osc_inst_me_acceleration(const osc_values *v, double *F);
void osc_inst_indicators(const osc_values *v, double z[2]);

/* ---- osc_inst_step.c ---- */
/* The stepper's switch callback (ctx: the instance): notes the switch and logs it. */
void osc_inst_on_switch(void *ctx, double t, double x, int from, int to);
/* After a step with input derivatives the inputs hold their polynomials' values at its end. */
void osc_inst_end_ramp(osc_values *v);
/* A failed step: the state back to before, the instance in error, the message. */
dfo_inst_status osc_inst_step_failed(osc_instance *in, const char *fn, const dfo_state *before,
                                     const dfo_state *failed, dfo_status st);

#endif
