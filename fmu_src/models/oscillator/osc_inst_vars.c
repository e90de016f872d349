/* The DryFrictionOscillator instance core (osc_instance.h), its variable access: value references
 * resolved through the table generated from modelDescription.xml (model_vars.h), get/set with every
 * value checked before any is stored, and the outputs (those a run does not compute read NaN, or -1,
 * with one sentence per run). No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "osc_instance.h"
#include "instance_common.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

/* ---- the variable table ---------------------------------------------------------------------- */

static const dfo_var_info *lookup(const osc_instance *in, const char *fn, unsigned int vr, dfo_var_type type)
{
    return dfo_inst_lookup(&in->lc, fn, vr, type);
}

static int settable(const osc_instance *in, const char *fn, const dfo_var_info *var)
{
    return dfo_inst_settable(&in->lc, fn, var, var->name, var->vr);
}

static int check_value(const osc_instance *in, const char *fn, const dfo_var_info *var, double x)
{
    return dfo_inst_value_ok(&in->lc, fn, var, x);
}

/* ---- outputs -------------------------------------------------------------------------------- */

/* Whether the inputs (values and set flags) are those of the last step: walks the table. */
int osc_inst_same_inputs(const dfo_inputs *a, const dfo_inputs *b)
{
    for (int i = 0; i < DFO_NUM_VARS; i++) {
        const dfo_var_info *var = &DFO_VARS[i];
        if (var->home != DFO_IN_INPUTS) continue;
        const char *pa = (const char *)a, *pb = (const char *)b;
        if (*(const int *)(pa + var->set_offset) != *(const int *)(pb + var->set_offset)) return 0;
        if (var->type == DFO_REAL ? *(const double *)(pa + var->offset) != *(const double *)(pb + var->offset)
                                  : *(const int *)(pa + var->offset) != *(const int *)(pb + var->offset))
            return 0;
    }
    return 1;
}

/* The friction force at the current state for the current inputs. With the inputs of the last step
 * it is the stepper's own; with inputs set since, the current mode's friction law with them:
 * sliding -s mu_k N, stuck the force that holds the block, within the breakaway limit. */
double osc_inst_friction_now(const osc_values *v)
{
    if (osc_inst_same_inputs(&v->u, &v->u_used)) return v->s.F;
    return dfo_friction_force(&v->M, &v->u, &v->s);
}

double osc_inst_acceleration_now(const osc_values *v)
{
    if (osc_inst_same_inputs(&v->u, &v->u_used)) return dfo_acceleration(&v->M, &v->u, &v->s);
    dfo_state s = v->s;
    s.F = osc_inst_friction_now(v);
    return dfo_acceleration(&v->M, &v->u, &s);
}

/* A pending event's left limit: the state at the switch in the mode before it, with that mode's
 * friction force (kinetic -from mu_k N; stuck, the static force clamped to the breakaway limit). */
dfo_state osc_inst_left_limit(const osc_values *v, int event_from)
{
    dfo_state s = v->s;
    s.mode = event_from;
    s.F = dfo_friction_force(&v->M, &v->u, &s);
    return s;
}

/* ---- Model Exchange's physics at the current state (osc_inst_me.c) -------------------------- */

/* The loads under the current inputs; whether friction acts. */
int osc_inst_loads(const osc_values *v, dfo_loads *L)
{
    dfo_loads_init(L, &v->M, &v->u);
    return L->Fb > 0.0;
}

/* The static force on the block at rest on the belt: friction.h's P + F_ext - k x, less the damper's
 * pull c v_belt, with the excitation as dfo_acceleration evaluates it. */
double osc_inst_static_force(const osc_values *v, const dfo_loads *L)
{
    const dfo_model *M = &v->M;
    const double t = v->s.t;
    const double P = M->p.scheme == DFO_SCHEME_EXACT ? dfo_excitation_exact(M, t) : dfo_excitation(M, t);
    return dfo_static_force(M->p.k, L, P, v->s.X) - M->p.c * dfo_belt_speed(&v->u);
}

/* The friction force and the acceleration at the current state in its mode (stuck: 0). */
double osc_inst_me_acceleration(const osc_values *v, double *F)
{
    dfo_state s = v->s;
    s.F = dfo_friction_force(&v->M, &v->u, &s);
    if (F) *F = s.F;
    dfo_loads L;
    if (osc_inst_loads(v, &L) && s.mode == 0) return 0.0;
    return dfo_acceleration(&v->M, &v->u, &s);
}

/* Model Exchange's event indicators (osc_inst_me.c): sliding, the relative velocity mode (v - v_belt)
 * + DBL_MIN (the hysteresis: DBL_MIN > 0 where a slide starts) and 1; stuck, the margins Fb -+ the
 * static force; 1 and 1 without friction. */
void osc_inst_indicators(const osc_values *v, double z[2])
{
    dfo_loads L;
    z[0] = z[1] = 1.0;
    if (!osc_inst_loads(v, &L)) return; /* no friction: no events */
    if (v->s.mode != 0) {
        z[0] = v->s.mode * (v->s.V - dfo_belt_speed(&v->u)) + DBL_MIN;
    } else {
        const double Fs = osc_inst_static_force(v, &L);
        z[0] = L.Fb - Fs;
        z[1] = L.Fb + Fs;
    }
}

static int needs_observe(int id)
{
    return id == DFO_OUT_x_max || id == DFO_OUT_x_min || id == DFO_OUT_stick_fraction ||
           id == DFO_OUT_transitions || id == DFO_OUT_E_friction;
}

static int is_sensitivity(int id)
{
    return id == DFO_OUT_dx_dx0 || id == DFO_OUT_dx_dv0 || id == DFO_OUT_dv_dx0 || id == DFO_OUT_dv_dv0;
}

/* The sensitivity is computed: asked for, and by the exact scheme (the only one that propagates it). */
static int sens_computed(const dfo_params *p) { return p->sensitivity && p->scheme == DFO_SCHEME_EXACT; }

/* A value this run has not computed: an observable while observe is false (every one of them),
 * x_max / x_min before the observation window has taken its first sample, or the sensitivity
 * unless it is computed; in Model Exchange (me) neither the observables nor the sensitivity. */
static int not_computed(const osc_values *v, int id, int me)
{
    if (me && (is_sensitivity(id) || needs_observe(id))) return 1; /* Model Exchange computes neither */
    if (is_sensitivity(id))
        return !sens_computed(&v->p) || !(isfinite(v->s.J[0]) && isfinite(v->s.J[1]) && isfinite(v->s.J[2]) &&
                                          isfinite(v->s.J[3]));
    if (!needs_observe(id)) return 0;
    if (!v->p.observe) return 1;
    return (id == DFO_OUT_x_max || id == DFO_OUT_x_min) && !v->s.observed;
}

/* What a value not computed reads: NaN (Real), DFO_NOT_COMPUTED_INT (Integer, transitions). Status
 * OK; one sentence per run, logged under logNotComputed, says why. */
#define DFO_NOT_COMPUTED_INT (-1)
#define WARNED_OBSERVE 1u     /* lc.warned: the observables' sentence was logged */
#define WARNED_SENSITIVITY 2u /* the sensitivity's */

static void note_not_computed(osc_instance *in, const char *fn, const dfo_var_info *var)
{
    if (in->me) {
        if (in->lc.warned & WARNED_OBSERVE) return;
        in->lc.warned |= WARNED_OBSERVE;
        dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_NOT_COMPUTED,
                     "%s: variable %s (value reference %u) is not computed in Model Exchange (the host integrates "
                     "x and v): the observables x_max, x_min, stick_fraction, E_friction and the Jacobian dx_dx0, "
                     "dx_dv0, dv_dx0, dv_dv0 read NaN and transitions reads -1; a co-simulation instance computes "
                     "them.", fn, var->name, var->vr);
        return;
    }
    if (is_sensitivity(var->id)) {
        if (in->lc.warned & WARNED_SENSITIVITY) return;
        in->lc.warned |= WARNED_SENSITIVITY;
        if (sens_computed(&in->v.p))
            dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_NOT_COMPUTED,
                         "%s: variable %s (value reference %u) reads NaN: the Jacobian dx_dx0, dx_dv0, dv_dx0, "
                         "dv_dv0 overflowed or met a tangential event since t_ref (a breakaway with a stationary "
                         "force, a stop with zero deceleration), where the map is not differentiable; it is the "
                         "identity again after a state restore.", fn, var->name, var->vr);
        else if (!in->v.p.sensitivity)
            dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_NOT_COMPUTED,
                         "%s: variable %s (value reference %u) is not computed while sensitivity is false: the "
                         "Jacobian dx_dx0, dx_dv0, dv_dx0, dv_dv0 reads NaN in this run; set sensitivity = true "
                         "(before initialisation, with scheme exact) to compute it.", fn, var->name, var->vr);
        else
            dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_NOT_COMPUTED,
                         "%s: variable %s (value reference %u) is not computed with scheme %s: the Jacobian "
                         "dx_dx0, dx_dv0, dv_dx0, dv_dv0 reads NaN in this run; only scheme exact computes it.",
                         fn, var->name, var->vr, osc_inst_scheme_name(in->v.p.scheme));
        return;
    }
    if (in->lc.warned & WARNED_OBSERVE) return;
    in->lc.warned |= WARNED_OBSERVE;
    if (!in->v.p.observe)
        dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_NOT_COMPUTED,
                     "%s: variable %s (value reference %u) is not computed while observe is false: the "
                     "observables x_max, x_min, stick_fraction, E_friction read NaN and transitions reads -1 in "
                     "this run; set observe = true (before initialisation) to compute them.", fn, var->name,
                     var->vr);
    else
        dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_NOT_COMPUTED,
                     "%s: variable %s (value reference %u) reads NaN: the observation window [%.17g, %.17g] has "
                     "not taken a sample yet (t = %.17g).", fn, var->name, var->vr, in->v.p.t_obs_start,
                     in->v.p.t_obs_stop, in->v.s.t);
}

static double output_real(const osc_values *v, const dfo_run *r, int id)
{
    const dfo_state *s = &v->s;
    if (r->event_pending && (id == DFO_OUT_a || id == DFO_OUT_F_friction)) {
        const dfo_state left = osc_inst_left_limit(v, r->event_from);
        return id == DFO_OUT_a ? dfo_acceleration(&v->M, &v->u, &left) : left.F;
    }
    switch (id) {
    case DFO_OUT_x: return s->X;
    case DFO_OUT_v: return s->V;
    case DFO_OUT_a: return osc_inst_acceleration_now(v);
    case DFO_OUT_F_friction: return osc_inst_friction_now(v);
    case DFO_OUT_x_max: return s->x_max;
    case DFO_OUT_x_min: return s->x_min;
    case DFO_OUT_stick_fraction: return dfo_stick_fraction(&v->M, s);
    case DFO_OUT_E_friction: return s->E_friction;
    case DFO_OUT_h_used: return v->M.p.h;
    case DFO_OUT_dx_dx0: return s->J[0];
    case DFO_OUT_dx_dv0: return s->J[1];
    case DFO_OUT_dv_dx0: return s->J[2];
    case DFO_OUT_dv_dv0: return s->J[3];
    case DFO_OUT_event_indicator_0:
    case DFO_OUT_event_indicator_1: {
        double z[2];
        osc_inst_indicators(v, z);
        return z[id == DFO_OUT_event_indicator_1];
    }
    default: return 0.0;
    }
}

static int output_int(const osc_values *v, const dfo_run *r, int id)
{
    switch (id) {
    case DFO_OUT_mode: return r->event_pending ? r->event_from : v->s.mode;
    case DFO_OUT_transitions: return (int)v->s.transitions;
    case DFO_OUT_effects: return v->effects;
    default: return 0;
    }
}

/* ---- get / set ------------------------------------------------------------------------------- */

dfo_inst_status dfo_inst_get_real(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, double value[])
{
    osc_instance *in = osc(lc);
    osc_values tmp;
    const osc_values *v = NULL;
    for (size_t i = 0; i < n; i++) {
        const dfo_var_info *var = lookup(in, fn, vr[i], DFO_REAL);
        if (!var) return DFO_INST_ERROR;
        if (var->home != DFO_COMPUTED) {
            value[i] = *(const double *)osc_cslot(&in->v, var);
            continue;
        }
        if (!v) v = osc_inst_computed(in, &tmp);
        if (not_computed(v, var->id, in->me)) {
            value[i] = NAN;
            note_not_computed(in, fn, var);
            continue;
        }
        value[i] = output_real(v, &in->lc.run, var->id);
        if (!isfinite(value[i]))
            return dfo_inst_fail(&in->lc, "%s: variable %s (value reference %u) is not representable in double precision "
                                 "for these parameters (overflow).", fn, var->name, vr[i]);
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_get_int(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, int value[])
{
    osc_instance *in = osc(lc);
    osc_values tmp;
    const osc_values *v = NULL;
    for (size_t i = 0; i < n; i++) {
        const dfo_var_info *var = lookup(in, fn, vr[i], DFO_INTEGER);
        if (!var) return DFO_INST_ERROR;
        if (var->home != DFO_COMPUTED) {
            value[i] = *(const int *)osc_cslot(&in->v, var);
            continue;
        }
        if (!v) v = osc_inst_computed(in, &tmp);
        if (not_computed(v, var->id, in->me)) {
            value[i] = DFO_NOT_COMPUTED_INT;
            note_not_computed(in, fn, var);
            continue;
        }
        value[i] = output_int(v, &in->lc.run, var->id);
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_get_bool(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, int value[])
{
    osc_instance *in = osc(lc);
    for (size_t i = 0; i < n; i++) {
        const dfo_var_info *var = lookup(in, fn, vr[i], DFO_BOOLEAN);
        if (!var) return DFO_INST_ERROR;
        value[i] = *(const int *)osc_cslot(&in->v, var) ? 1 : 0;
    }
    return DFO_INST_OK;
}

static void store(osc_values *v, const dfo_var_info *var, double x) { dfo_var_store(&v->p, &v->u, var, x); }

dfo_inst_status dfo_inst_set_real(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                  const double value[])
{
    osc_instance *in = osc(lc);
    for (size_t i = 0; i < n; i++) {
        const dfo_var_info *var = lookup(in, fn, vr[i], DFO_REAL);
        if (!var || !settable(in, fn, var) || !check_value(in, fn, var, value[i])) return DFO_INST_ERROR;
    }
    for (size_t i = 0; i < n; i++) store(&in->v, dfo_find_var(vr[i]), value[i]);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_set_int(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                 const int value[])
{
    osc_instance *in = osc(lc);
    for (size_t i = 0; i < n; i++) {
        const dfo_var_info *var = lookup(in, fn, vr[i], DFO_INTEGER);
        if (!var || !settable(in, fn, var) || !check_value(in, fn, var, value[i])) return DFO_INST_ERROR;
    }
    for (size_t i = 0; i < n; i++) store(&in->v, dfo_find_var(vr[i]), value[i]);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_set_bool(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                  const int value[])
{
    osc_instance *in = osc(lc);
    for (size_t i = 0; i < n; i++) {
        const dfo_var_info *var = lookup(in, fn, vr[i], DFO_BOOLEAN);
        if (!var || !settable(in, fn, var)) return DFO_INST_ERROR;
    }
    for (size_t i = 0; i < n; i++) store(&in->v, dfo_find_var(vr[i]), value[i] ? 1.0 : 0.0);
    return DFO_INST_OK;
}
