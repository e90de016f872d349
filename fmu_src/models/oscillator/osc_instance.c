/* The instance core of the DryFrictionOscillator FMUs (the model API of core/instance.h over
 * osc_instance.h): start values, get/set through the variable table generated from
 * modelDescription.xml (model_vars.h), initialisation, doStep with and without events, FMU states
 * and their serialisation (core/fmu_state.h's format). No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "fmu_state.h"
#include "instance_common.h"
#include "exact.h"
#include "osc_instance.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* The model description is the source of truth for the effect bits and the scheme values the
 * physics uses: a mismatch does not compile. */
#define DFO_SAME(name, a, b) typedef char dfo_static_assert_##name[((int)(a) == (int)(b)) ? 1 : -1]
DFO_SAME(effect_friction, DFO_MD_EFFECT_FRICTION, DFO_EFFECT_FRICTION);
DFO_SAME(effect_update, DFO_MD_EFFECT_COEFFICIENT_UPDATE, DFO_EFFECT_COEFF_UPDATE);
DFO_SAME(effect_damping, DFO_MD_EFFECT_DAMPING, DFO_EFFECT_DAMPING);
DFO_SAME(effect_force, DFO_MD_EFFECT_FORCE_INPUT, DFO_EFFECT_FORCE_INPUT);
DFO_SAME(effect_normal, DFO_MD_EFFECT_NORMAL_INPUT, DFO_EFFECT_NORMAL_INPUT);
DFO_SAME(effect_observables, DFO_MD_EFFECT_OBSERVABLES, DFO_EFFECT_OBSERVABLES);
DFO_SAME(effect_sensitivity, DFO_MD_EFFECT_SENSITIVITY, DFO_EFFECT_SENSITIVITY);
DFO_SAME(effect_belt, DFO_MD_EFFECT_BELT, DFO_EFFECT_BELT);
DFO_SAME(effect_stribeck, DFO_MD_EFFECT_STRIBECK, DFO_EFFECT_STRIBECK);
DFO_SAME(law_coulomb, DFO_MD_FRICTION_LAW_COULOMB, DFO_LAW_COULOMB);
DFO_SAME(law_stribeck, DFO_MD_FRICTION_LAW_STRIBECK, DFO_LAW_STRIBECK);
DFO_SAME(scheme_paper, DFO_MD_SCHEME_PAPER, DFO_SCHEME_PAPER);
DFO_SAME(scheme_consistent, DFO_MD_SCHEME_CONSISTENT, DFO_SCHEME_CONSISTENT);
DFO_SAME(scheme_located, DFO_MD_SCHEME_LOCATED, DFO_SCHEME_LOCATED);
typedef char dfo_static_assert_warn_bits[DFO_NUM_OUTS <= 32 ? 1 : -1];

#define STATE_MAGIC 0x444650534d555354ULL /* "DFPSMUST" */

/* An FMU state in memory: a tagged copy of the run and the values. */
typedef struct {
    uint64_t magic;
    dfo_run run;
    osc_values v;
} saved_state;

static osc_instance *osc(dfo_lifecycle *lc) { return (osc_instance *)lc; }
static const osc_instance *cosc(const dfo_lifecycle *lc) { return (const osc_instance *)lc; }

/* ---- the variable table ---------------------------------------------------------------------- */

/* Where a stored value lives in v (parameters and inputs only). */
static void *slot(osc_values *v, const dfo_var_info *var)
{
    char *base = (var->home == DFO_IN_PARAMS) ? (char *)&v->p : (char *)&v->u;
    return base + var->offset;
}

static const void *cslot(const osc_values *v, const dfo_var_info *var)
{
    return slot((osc_values *)v, var);
}

/* Start values, and the run at its start (phase instantiated). */
static void set_start_values(osc_instance *in)
{
    osc_values *v = &in->v;
    const osc_values zero = {0};
    const dfo_run run0 = {0};
    *v = zero;
    in->lc.run = run0;
    for (int i = 0; i < DFO_NUM_VARS; i++) {
        const dfo_var_info *var = &DFO_VARS[i];
        if (var->home == DFO_COMPUTED || !var->has_start) continue;
        if (var->type == DFO_REAL) *(double *)slot(v, var) = var->start;
        else *(int *)slot(v, var) = (int)var->start;
    }
    in->lc.run.phase = DFO_PHASE_INSTANTIATED;
}

static const dfo_var_info *lookup(const osc_instance *in, const char *fn, unsigned int vr, dfo_var_type type)
{
    const dfo_var_info *var = dfo_find_var(vr);
    if (!var) {
        dfo_inst_fail(&in->lc, "%s: unknown value reference %u.", fn, vr);
        return NULL;
    }
    if (var->type != type) {
        dfo_inst_fail(&in->lc, "%s: variable %s (value reference %u) is of type %s, not %s.", fn, var->name, vr,
                      dfo_type_name(var->type), dfo_type_name(type));
        return NULL;
    }
    return var;
}

static int settable(const osc_instance *in, const char *fn, const dfo_var_info *var)
{
    return dfo_inst_settable(&in->lc, fn, var, var->name, var->vr);
}

static int check_value(const osc_instance *in, const char *fn, const dfo_var_info *var, double x)
{
    const char *range = dfo_inst_invalid(var, x);
    if (!range) return 1;
    dfo_inst_fail(&in->lc, "%s: invalid value %.17g for variable %s (value reference %u); valid range: %s.", fn, x,
                  var->name, var->vr, range);
    return 0;
}

/* ---- start, outputs -------------------------------------------------------------------------- */

dfo_lifecycle *dfo_inst_new(const dfo_host *host, const char *name, int logging_on)
{
    osc_instance *in = (osc_instance *)dfo_lifecycle_new(host, sizeof(osc_instance), name, logging_on);
    if (!in) return NULL;
    /* values read that the run has not computed are always reported */
    in->lc.log_on[DFO_LOG_NOT_COMPUTED] = 1;
    set_start_values(in);
    return &in->lc;
}

void dfo_inst_delete(dfo_lifecycle *lc)
{
    if (lc) lc->host.free(lc->host.ctx, lc);
}

size_t dfo_inst_n_values(const dfo_lifecycle *lc, const unsigned int vr[], size_t nvr)
{
    (void)lc;
    (void)vr;
    return nvr; /* scalars only */
}

void dfo_inst_log_event_handled(const dfo_lifecycle *lc)
{
    dfo_inst_log(lc, DFO_INST_OK, DFO_LOG_EVENTS, "t = %.17g: event handled, mode %d.", dfo_inst_time(lc),
                 cosc(lc)->v.s.mode);
}

/* ---- no structural parameters ------------------------------------------------------------------ */

#define NO_STRUCTURAL(lc, fn) dfo_inst_fail(lc, "%s: the FMU has no structural parameters.", fn)

int dfo_inst_has_structural(void) { return 0; }
dfo_inst_status dfo_inst_enter_config(dfo_lifecycle *lc, const char *fn) { return NO_STRUCTURAL(lc, fn); }
dfo_inst_status dfo_inst_exit_config(dfo_lifecycle *lc, const char *fn) { return NO_STRUCTURAL(lc, fn); }
dfo_inst_status dfo_inst_get_uint64(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                    unsigned long long value[])
{
    (void)vr; (void)n; (void)value;
    return NO_STRUCTURAL(lc, fn);
}
dfo_inst_status dfo_inst_set_uint64(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                    const unsigned long long value[])
{
    (void)vr; (void)n; (void)value;
    return NO_STRUCTURAL(lc, fn);
}

/* The sensitivity's reference: the Jacobian is the identity at the end of initialisation and at
 * every state restore. */
static void sens_reset(dfo_state *s)
{
    s->J[0] = s->J[3] = 1.0;
    s->J[1] = s->J[2] = 0.0;
}

/* Derive the model from the parameters and start it (exit of initialisation, or outputs asked for
 * during initialisation). */
static void prepare(osc_values *v, double start_time)
{
    dfo_model_init(&v->M, &v->p);
    dfo_start(&v->M, &v->u, start_time, &v->s);
    sens_reset(&v->s);
    v->effects = dfo_effects(&v->M, &v->u);
    v->u_used = v->u;
    v->t_switch = -INFINITY;
}

/* Values of computed variables need the started model; during initialisation it is derived from
 * the current parameters on the fly. */
static const osc_values *computed(const osc_instance *in, osc_values *tmp)
{
    if (in->lc.run.phase != DFO_PHASE_INIT) return &in->v;
    *tmp = in->v;
    prepare(tmp, in->lc.run.start_time);
    return tmp;
}

/* Whether the inputs (values and set flags) are those of the last step: walks the table. */
static int same_inputs(const dfo_inputs *a, const dfo_inputs *b)
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
static double friction_now(const osc_values *v)
{
    if (same_inputs(&v->u, &v->u_used)) return v->s.F;
    return dfo_friction_force(&v->M, &v->u, &v->s);
}

static double acceleration_now(const osc_values *v)
{
    if (same_inputs(&v->u, &v->u_used)) return dfo_acceleration(&v->M, &v->u, &v->s);
    dfo_state s = v->s;
    s.F = friction_now(v);
    return dfo_acceleration(&v->M, &v->u, &s);
}

/* A pending event's left limit: the state at the switch in the mode before it, with that mode's
 * friction force (kinetic -from mu_k N; stuck, the static force clamped to the breakaway limit). */
static dfo_state left_limit(const osc_values *v, int event_from)
{
    dfo_state s = v->s;
    s.mode = event_from;
    s.F = dfo_friction_force(&v->M, &v->u, &s);
    return s;
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
 * unless it is computed. */
static int not_computed(const osc_values *v, int id)
{
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
static const char *scheme_name(int scheme)
{
    static const char *const names[5] = {"?", "paper", "consistent", "located", "exact"};
    return (scheme >= 1 && scheme <= 4) ? names[scheme] : "?";
}

static void note_not_computed(osc_instance *in, const char *fn, const dfo_var_info *var)
{
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
                         fn, var->name, var->vr, scheme_name(in->v.p.scheme));
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
        const dfo_state left = left_limit(v, r->event_from);
        return id == DFO_OUT_a ? dfo_acceleration(&v->M, &v->u, &left) : left.F;
    }
    switch (id) {
    case DFO_OUT_x: return s->X;
    case DFO_OUT_v: return s->V;
    case DFO_OUT_a: return acceleration_now(v);
    case DFO_OUT_F_friction: return friction_now(v);
    case DFO_OUT_x_max: return s->x_max;
    case DFO_OUT_x_min: return s->x_min;
    case DFO_OUT_stick_fraction: return dfo_stick_fraction(&v->M, s);
    case DFO_OUT_E_friction: return s->E_friction;
    case DFO_OUT_h_used: return v->M.p.h;
    case DFO_OUT_dx_dx0: return s->J[0];
    case DFO_OUT_dx_dv0: return s->J[1];
    case DFO_OUT_dv_dx0: return s->J[2];
    case DFO_OUT_dv_dv0: return s->J[3];
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

/* ---- life cycle ------------------------------------------------------------------------------ */

static dfo_inst_status ramp_refused(osc_instance *in, const char *fn);
static const char *ramp_unsupported(const dfo_params *p);

/* The scales the computation honours (dfo_scale_refused): k, and the force scale of the excitation,
 * the friction limit and the initial state over m and k. NULL when inside, else the sentence. */
static const char *scale_refused(const dfo_params *p, char *buf, size_t len)
{
    const double F = fmax(fmax(fabs(p->P0), fmax(p->mu_s, p->chi * p->mu_s) * p->N),
                          fmax(p->k * fabs(p->x0), sqrt(p->k) * sqrt(p->m) * fabs(p->v0)));
    return dfo_scale_refused(DFO_SCALE_LIMIT, F, "max(|P0|, max(mu_s, mu_k) N, k |x0|, sqrt(k m) |v0|)", p->m, "m",
                             p->k, "k", buf, len);
}

dfo_inst_status dfo_inst_exit_init(dfo_lifecycle *lc, const char *fn)
{
    osc_instance *in = osc(lc);
    osc_values *v = &in->v;
    const char *msg = dfo_check_params(&v->p);
    if (msg) return dfo_inst_fail(&in->lc, "%s: %s", fn, msg);
    char buf[640];
    if ((msg = scale_refused(&v->p, buf, sizeof buf))) return dfo_inst_fail(&in->lc, "%s: %s.", fn, msg);
    if (v->u.ramp && ramp_unsupported(&v->p)) return ramp_refused(in, fn);
    v->u.t_d = in->lc.run.start_time; /* input derivatives set before: of the start */
    prepare(v, in->lc.run.start_time);
    in->lc.run.time = in->lc.run.start_time;
    const dfo_state *s = &v->s;
    if (!isfinite(s->A) || !isfinite(s->F) || !isfinite(dfo_acceleration(&v->M, &v->u, s)))
        return dfo_inst_fail(&in->lc, "%s: the initial acceleration is not representable (x0 = %.17g, v0 = %.17g, m = "
                             "%.17g): the parameters are out of the range of double precision.", fn, v->p.x0, v->p.v0,
                             v->p.m);
    in->lc.run.phase = DFO_PHASE_STEP;
    dfo_inst_status status = DFO_INST_OK;
    const double T_min = dfo_shortest_period(&v->p);
    if (v->p.h > 0.0 && v->p.scheme != DFO_SCHEME_EXACT && v->p.h * DFO_MIN_STEPS_PER_PERIOD > T_min) {
        status = DFO_INST_WARNING;
        dfo_inst_log(&in->lc, DFO_INST_WARNING, DFO_LOG_STATUS_WARNING,
                     "%s: h = %.6g s takes only %.3g internal steps per %.6g s, the shortest period of the dynamics "
                     "(natural 2 pi sqrt(m/k), excitation 2 pi/omega, damping 2 pi m/c): the results do not resolve "
                     "it. Choose h <= %.6g s (1/%g of it), or h = 0 to let the FMU derive it.", fn, v->p.h,
                     T_min / v->p.h, T_min, T_min / DFO_STEPS_PER_PERIOD, DFO_STEPS_PER_PERIOD);
    }
    if (v->p.sensitivity && v->p.scheme != DFO_SCHEME_EXACT) {
        status = DFO_INST_WARNING;
        dfo_inst_log(&in->lc, DFO_INST_WARNING, DFO_LOG_STATUS_WARNING,
                     "%s: sensitivity = true is ignored with scheme %s: only scheme exact propagates the Jacobian; "
                     "dx_dx0, dx_dv0, dv_dx0, dv_dv0 read NaN in this run. Choose scheme exact to compute them.",
                     fn, scheme_name(v->p.scheme));
    }
    dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_EVENTS, "start at t = %.17g: x = %.17g, v = %.17g, mode %d, effects %d.",
                 s->t, s->X, s->V, s->mode, v->effects);
    return status;
}

void dfo_inst_reset(dfo_lifecycle *lc)
{
    osc_instance *in = osc(lc);
    set_start_values(in);
    in->lc.warned = 0;
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
            value[i] = *(const double *)cslot(&in->v, var);
            continue;
        }
        if (!v) v = computed(in, &tmp);
        if (not_computed(v, var->id)) {
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
            value[i] = *(const int *)cslot(&in->v, var);
            continue;
        }
        if (!v) v = computed(in, &tmp);
        if (not_computed(v, var->id)) {
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
        value[i] = *(const int *)cslot(&in->v, var) ? 1 : 0;
    }
    return DFO_INST_OK;
}

/* Store a checked value; setting an input raises its flag (an input never set is never read). */
static void store(osc_values *v, const dfo_var_info *var, double x)
{
    if (var->type == DFO_REAL) *(double *)slot(v, var) = x;
    else *(int *)slot(v, var) = (int)x;
    if (var->home == DFO_IN_INPUTS) *(int *)((char *)&v->u + var->set_offset) = 1;
}

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

/* ---- doStep ---------------------------------------------------------------------------------- */

static void on_switch(void *ctx, double t, double x, int from, int to)
{
    osc_instance *in = (osc_instance *)ctx;
    static const char *const names[3] = {"backward slip", "stick", "forward slip"};
    in->lc.switched = 1;
    in->v.t_switch = t;
    dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_EVENTS, "t = %.17g: %s -> %s at x = %.17g.", t, names[from + 1],
                 names[to + 1], x);
}

/* Early return: one internal grid step per call of the stepper, until the first switch. Used only
 * when asked for; the ordinary path is one call up to the target. */
static dfo_status advance_to_switch(osc_instance *in, double t_target)
{
    osc_values *v = &in->v;
    const double h = v->M.p.h, snap = dfo_snap(h, t_target);
    in->lc.switched = 0;
    while (v->s.t < t_target) {
        const double grid = v->s.t0 + (double)(v->s.n + 1) * h;
        const double t_next = (grid < t_target - snap) ? grid : t_target;
        const dfo_status st = dfo_advance(&v->M, &v->u, &v->s, t_next, on_switch, in);
        if (st != DFO_OK || in->lc.switched || t_next == t_target) return st;
    }
    return DFO_OK;
}

/* After a step with input derivatives the inputs hold the values their polynomials reached at its
 * end (the state's time); the derivatives are spent (the next step holds the inputs unless the
 * host sets derivatives again). */
static void end_ramp(osc_values *v)
{
    if (!v->u.ramp) return;
    dfo_inputs w;
    dfo_inputs_at(&v->u, v->s.t, &w);
    v->u = w;
}

/* Why the exact scheme cannot follow input derivatives on these parameters (NULL: it can, and the
 * Bossak schemes always can). */
static const char *ramp_unsupported(const dfo_params *p)
{
    if (p->scheme != DFO_SCHEME_EXACT) return NULL;
    dfo_model M;
    dfo_model_init(&M, p);
    return dfo_exact_poly_unsupported(&M);
}

static const char *ramped_inputs(const dfo_inputs *u)
{
    const int F = u->F_ext_d[0] != 0.0 || u->F_ext_d[1] != 0.0, N = u->N_ext_d[0] != 0.0 || u->N_ext_d[1] != 0.0;
    return F && N ? "F_ext and N_ext" : F ? "F_ext" : "N_ext";
}

/* Input derivatives set that the scheme cannot follow (checked again at every step: the parameters
 * may have changed since they were set): an error naming the inputs and the scheme. */
static dfo_inst_status ramp_refused(osc_instance *in, const char *fn)
{
    return dfo_inst_fail(&in->lc, "%s: input derivatives of %s are not supported with scheme exact here: %s; set "
                         "them to 0, or choose scheme paper, consistent or located.", fn, ramped_inputs(&in->v.u),
                         ramp_unsupported(&in->v.p));
}

/* A failed step: the outputs stay those of the last good state, the instance is in error. */
static dfo_inst_status step_failed(osc_instance *in, const char *fn, const dfo_state *before, const dfo_state *failed,
                                   dfo_status st)
{
    osc_values *v = &in->v;
    const double t = in->lc.run.time;
    v->s = *before;
    in->lc.run.phase = DFO_PHASE_ERROR;
    return dfo_inst_fail(&in->lc, "%s: step from t = %.17g failed at t = %.17g: %s (x = %.17g, v = %.17g). The "
                         "FMU keeps the state at t = %.17g; reset it or restore an earlier FMU state.", fn, t,
                         failed->t, dfo_status_text(st), failed->X, failed->V, t);
}

dfo_inst_status dfo_inst_do_step(dfo_lifecycle *lc, const char *fn, double tc, double dt, unsigned int flags,
                                 double *t_reached)
{
    osc_instance *in = osc(lc);
    osc_values *v = &in->v;
    double t_target = 0.0;
    /* the exact scheme counts its events (no 1e9 h bound), unless it walks the grid to a switch */
    in->lc.work_by_events = v->M.p.scheme == DFO_SCHEME_EXACT && !(flags & DFO_STEP_STOP_AT_SWITCH);
    const dfo_inst_status chk = dfo_inst_check_step(&in->lc, fn, tc, dt, v->M.p.h, &t_target);
    if (chk != DFO_INST_OK) return chk;
    if (v->u.ramp && v->M.p.scheme == DFO_SCHEME_EXACT && ramp_unsupported(&v->M.p)) return ramp_refused(in, fn);
    const dfo_state before = v->s;
    if (!same_inputs(&v->u, &v->u_used)) dfo_new_inputs(&v->M, &v->u_used, &v->u, &v->s);
    dfo_status st;
    if (flags & DFO_STEP_STOP_AT_SWITCH) {
        st = advance_to_switch(in, t_target);
    } else {
        /* the switches are logged; their times (output derivatives do not exist at one) the Bossak
         * schemes keep in the state, the exact scheme's are noted by on_switch */
        const int events = (in->lc.host.log && in->lc.log_on[DFO_LOG_EVENTS]) || v->M.p.scheme == DFO_SCHEME_EXACT;
        st = dfo_advance(&v->M, &v->u, &v->s, t_target, events ? on_switch : NULL, in);
    }
    if (st != DFO_OK) {
        const dfo_state failed = v->s;
        return step_failed(in, fn, &before, &failed, st);
    }
    /* the host's time: the target (the stepper may stand on a grid point within its snap tolerance
     * of it), or where an early return stopped short of it */
    const double snap = dfo_snap(v->M.p.h, t_target);
    const int early = (flags & DFO_STEP_STOP_AT_SWITCH) && in->lc.switched && v->s.t < t_target - snap;
    in->lc.run.time = early ? v->s.t : t_target;
    end_ramp(v);
    v->u_used = v->u;
    if (t_reached) *t_reached = in->lc.run.time;
    return DFO_INST_OK;
}

/* ---- FMI 3.0: stepping with events --------------------------------------------------------------
 *
 * A step with events is computed as the plain step (one dfo_advance to the target, the switches
 * recorded), then each switch strictly inside it is landed on: the same stepping from the step's
 * start, ended at the switch time (dfo_advance to ts: the steps up to the switch are the plain
 * step's, the last one shortened to end at ts). A located stop is found by bisection in the
 * shortened step again and may land a few ulps later: the target is nudged by ulps until the re-run
 * holds the switch. Should that fail, the step ends on the internal grid point after the switch. */

typedef struct {
    double t_after;  /* record the first switch after this time */
    int count;       /* switches seen */
    int found, from, to, index;
    double ts;
} switch_rec;

static void record_switch(void *ctx, double t, double x, int from, int to)
{
    switch_rec *r = (switch_rec *)ctx;
    (void)x;
    if (!r->found && t > r->t_after) {
        r->found = 1;
        r->ts = t;
        r->from = from;
        r->to = to;
        r->index = r->count;
    }
    r->count++;
}

/* The state just after the switch r (index r->index of the step from start), into *out. */
static int land(const osc_values *v, const dfo_state *start, const switch_rec *r, double t_end, dfo_state *out)
{
    double t = r->ts, ulp = nextafter(r->ts, INFINITY) - r->ts;
    for (int k = 0; k < 12 && t < t_end; k++, t = r->ts + ulp, ulp *= 2.0) {
        switch_rec check = {-INFINITY, 0, 0, 0, 0, 0, 0.0};
        dfo_state w = *start;
        if (dfo_advance(&v->M, &v->u, &w, t, record_switch, &check) != DFO_OK) return 0;
        if (check.count == r->index + 1 && w.mode == r->to && w.t < t_end) {
            *out = w;
            return 1;
        }
    }
    /* fallback: the internal grid point after the switch */
    const double h = v->M.p.h;
    const double g = start->t0 + (floor((r->ts - start->t0) / h) + 1.0) * h;
    if (!(g < t_end)) return 0;
    dfo_state w = *start;
    if (dfo_advance(&v->M, &v->u, &w, g, NULL, NULL) != DFO_OK || w.mode != r->to) return 0;
    *out = w;
    return 1;
}

/* One stretch of a step with events, from the current state (the host's time) to t_end: the whole
 * step, or (input points) one internal step of it, `last` when t_end is the step's target. Returns
 * 1 when the step is over (ended early at a switch, reached its target, or failed: *st, res), 0
 * when a stretch that is not the last reached t_end. A switch on the end of a stretch that is not
 * the last is one inside the step. */
static int events_stretch(osc_instance *in, const char *fn, double t_end, int last, const dfo_event_opts *opt,
                          dfo_step_result *res, dfo_inst_status *st_out)
{
    osc_values *v = &in->v;
    const dfo_state start = v->s;
    const double t_start = in->lc.run.time;
    const int events_logged = in->lc.host.log && in->lc.log_on[DFO_LOG_EVENTS];
    double t_after = -INFINITY;
    *st_out = DFO_INST_OK;
    for (;;) {
        switch_rec r = {t_after, 0, 0, 0, 0, 0, 0.0};
        dfo_state w = start;
        const dfo_status st = dfo_advance(&v->M, &v->u, &w, t_end, record_switch, &r);
        if (st != DFO_OK) {
            *st_out = step_failed(in, fn, &start, &w, st);
            return 1;
        }
        dfo_state at;
        /* in a stretch that is one internal step, a switch not landed on inside it is on its end
         * (the paper and consistent schemes switch on grid points, reported to rounding) */
        const int inside = r.found && ((r.ts < w.t && land(v, &start, &r, w.t, &at)) || (!last && (at = w, 1)));
        if (inside) {
            /* a switch inside the step: the state at it is readable during the intermediate update */
            int stop = opt->early_return && !opt->intermediate;
            if (opt->intermediate) {
                v->s = at;
                in->lc.run.time = at.t;
                stop = opt->intermediate(opt->ctx, at.t, opt->early_return, 0) && opt->early_return;
            }
            if (stop) {
                v->s = at;
                in->lc.run.time = at.t;
                v->t_switch = at.t;
                end_ramp(v);
                v->u_used = v->u;
                in->lc.run.event_pending = opt->event_mode;
                in->lc.run.event_from = r.from;
                res->early = 1;
                res->event = opt->event_mode;
                res->t_reached = at.t;
                if (events_logged) on_switch(in, at.t, at.X, r.from, r.to);
                return 1;
            }
            v->s = start;
            in->lc.run.time = t_start;
            t_after = r.ts;
            if (at.t < w.t) continue;
            r.found = 0; /* the switch on the end of this stretch has been reported */
        }
        const int end_switch = inside || (r.found && last);
        /* no switch left inside: the stretch's end. A switch on the communication point itself
         * (the paper and consistent schemes switch on grid points) is an event there. */
        if (r.found && opt->event_mode) {
            in->lc.run.event_pending = 1;
            in->lc.run.event_from = r.from;
            res->event = 1;
        }
        if (r.found && opt->intermediate) {
            v->s = w;
            in->lc.run.time = t_end;
            (void)opt->intermediate(opt->ctx, t_end, 0, 0);
        }
        if (events_logged) {
            dfo_state again = start;
            (void)dfo_advance(&v->M, &v->u, &again, t_end, on_switch, in);
        }
        v->s = w;
        in->lc.run.time = t_end;
        if (end_switch && (r.found || at.t == w.t)) v->t_switch = w.t;
        if (!last) return 0;
        end_ramp(v);
        v->u_used = v->u;
        res->t_reached = t_end;
        return 1;
    }
}

/* An input point (FMI 3.0 intermediate update of inputs) at the current state, inside a step of
 * the Bossak schemes: the host may set the inputs declared intermediateUpdate="true", which then
 * hold from here on (an input set here loses its derivatives; the others keep their polynomials).
 * Returns whether the host asked for an early return (honoured with early return allowed). */
static int input_point(osc_instance *in, const dfo_event_opts *opt)
{
    osc_values *v = &in->v;
    const double t = v->s.t;
    if (v->u.ramp) { /* the polynomials re-anchored at t: their values there, the derivatives' at t */
        const double tau = t - v->u.t_d;
        dfo_inputs w;
        dfo_inputs_at(&v->u, t, &w);
        w.F_ext_d[0] = v->u.F_ext_d[0] + v->u.F_ext_d[1] * tau;
        w.N_ext_d[0] = v->u.N_ext_d[0] + v->u.N_ext_d[1] * tau;
        w.F_ext_d[1] = v->u.F_ext_d[1];
        w.N_ext_d[1] = v->u.N_ext_d[1];
        w.t_d = t;
        w.ramp = 1;
        v->u = v->u_used = w;
    }
    const dfo_inputs before = v->u;
    in->lc.run.time = t;
    const int stop = opt->intermediate(opt->ctx, t, opt->early_return, 1) && opt->early_return;
    if (v->u.ramp) {
        if (v->u.F_ext != before.F_ext) v->u.F_ext_d[0] = v->u.F_ext_d[1] = 0.0;
        if (v->u.N_ext != before.N_ext) v->u.N_ext_d[0] = v->u.N_ext_d[1] = 0.0;
        v->u.ramp = v->u.F_ext_d[0] != 0.0 || v->u.F_ext_d[1] != 0.0 || v->u.N_ext_d[0] != 0.0 ||
                    v->u.N_ext_d[1] != 0.0;
    }
    if (!same_inputs(&v->u, &v->u_used)) dfo_new_inputs(&v->M, &v->u_used, &v->u, &v->s);
    v->u_used = v->u;
    return stop;
}

dfo_inst_status dfo_inst_do_step_events(dfo_lifecycle *lc, const char *fn, double tc, double dt,
                                        const dfo_event_opts *opt, dfo_step_result *res)
{
    osc_instance *in = osc(lc);
    osc_values *v = &in->v;
    dfo_inst_status done;
    double t_target = 0.0;
    in->lc.work_by_events = v->M.p.scheme == DFO_SCHEME_EXACT;
    if (v->u.ramp && v->M.p.scheme == DFO_SCHEME_EXACT && ramp_unsupported(&v->M.p)) return ramp_refused(in, fn);
    if (dfo_inst_events_begin(&in->lc, fn, tc, dt, v->M.p.h, opt, res, &done, &t_target)) return done;
    if (!same_inputs(&v->u, &v->u_used)) {
        dfo_new_inputs(&v->M, &v->u_used, &v->u, &v->s);
        v->u_used = v->u; /* (the state now belongs to them) */
    }
    /* input points: the end of every internal step before the target (the exact scheme has none) */
    const int points = opt->input_points && opt->intermediate && v->M.p.scheme != DFO_SCHEME_EXACT;
    const double h = v->M.p.h, snap = dfo_snap(h, t_target);
    for (;;) {
        double t_end = t_target;
        if (points) {
            const double grid = v->s.t0 + (double)(v->s.n + 1) * h;
            if (grid < t_target - snap) t_end = grid;
        }
        dfo_inst_status st;
        if (events_stretch(in, fn, t_end, t_end == t_target, opt, res, &st)) return st;
        if (input_point(in, opt)) {
            end_ramp(v);
            v->u_used = v->u;
            res->early = 1;
            res->t_reached = in->lc.run.time;
            return DFO_INST_OK;
        }
    }
}

/* ---- FMU states ------------------------------------------------------------------------------ */

static saved_state *as_state(const void *p)
{
    saved_state *st = (saved_state *)p;
    return (st && st->magic == STATE_MAGIC) ? st : NULL;
}

static dfo_inst_status store_state(osc_instance *in, const char *fn, void **state, const dfo_run *run,
                                   const osc_values *v)
{
    int fresh;
    if (dfo_state_take(&in->lc, fn, state, STATE_MAGIC, sizeof(saved_state), &fresh) != DFO_INST_OK)
        return DFO_INST_ERROR;
    saved_state *st = (saved_state *)*state;
    st->run = *run;
    st->v = *v;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_get_state(dfo_lifecycle *lc, const char *fn, void **state)
{
    osc_instance *in = osc(lc);
    return store_state(in, fn, state, &in->lc.run, &in->v);
}

dfo_inst_status dfo_inst_set_state(dfo_lifecycle *lc, const char *fn, const void *state)
{
    osc_instance *in = osc(lc);
    const saved_state *st = (const saved_state *)dfo_state_block(lc, fn, state, STATE_MAGIC);
    if (!st) return DFO_INST_ERROR;
    in->lc.run = st->run;
    in->v = st->v;
    sens_reset(&in->v.s); /* the sensitivity is of the state restored */
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_free_state(dfo_lifecycle *lc, const char *fn, void **state)
{
    if (!dfo_state_droppable(lc, fn, state, STATE_MAGIC)) return DFO_INST_ERROR;
    dfo_state_drop(lc, state);
    return DFO_INST_OK;
}

/* The serialised body (core/fmu_state.h's format): the values' bytes, then the run. */
#define BODY_BYTES (sizeof(osc_values) + DFO_STATE_RUN_BYTES)

size_t dfo_inst_state_size(const dfo_lifecycle *lc, const void *state)
{
    (void)lc;
    return as_state(state) ? DFO_STATE_HEADER_BYTES + BODY_BYTES : 0;
}

dfo_inst_status dfo_inst_serialize(dfo_lifecycle *lc, const char *fn, const void *state, unsigned char *buf,
                                   size_t size)
{
    const saved_state *st = (const saved_state *)dfo_state_block(lc, fn, state, STATE_MAGIC);
    if (!st) return DFO_INST_ERROR;
    if (size < DFO_STATE_HEADER_BYTES + BODY_BYTES)
        return dfo_inst_fail(lc, "%s: buffer of %lu bytes is too small (%lu needed).", fn, (unsigned long)size,
                             (unsigned long)(DFO_STATE_HEADER_BYTES + BODY_BYTES));
    dfo_cursor c = {buf + DFO_STATE_HEADER_BYTES, NULL};
    dfo_put_bytes(&c, &st->v, sizeof st->v);
    dfo_put_run(&c, &st->run);
    dfo_state_seal(buf, BODY_BYTES, MODEL_GUID);
    return DFO_INST_OK;
}

static int finite_inputs(const dfo_inputs *u)
{
    return isfinite(u->F_ext) && isfinite(u->N_ext) && isfinite(u->v_belt) && isfinite(u->F_ext_d[0]) && isfinite(u->F_ext_d[1]) &&
           isfinite(u->N_ext_d[0]) && isfinite(u->N_ext_d[1]) && isfinite(u->t_d);
}

/* A deserialised state must describe a simulation this FMU could have reached. */
static const char *implausible(const dfo_run *r, const osc_values *v)
{
    for (int i = 0; i < DFO_NUM_VARS; i++) {
        const dfo_var_info *var = &DFO_VARS[i];
        if (var->home == DFO_COMPUTED || var->type == DFO_BOOLEAN) continue;
        const double x = var->type == DFO_REAL ? *(const double *)cslot(v, var) : *(const int *)cslot(v, var);
        if (dfo_inst_invalid(var, x))
            return var->type == DFO_REAL ? "a parameter is out of range" : "an integer parameter is out of range";
    }
    const char *why = dfo_run_implausible(r, 0);
    if (why) return why;
    if (dfo_check_params(&v->p)) return dfo_check_params(&v->p);
    if (!finite_inputs(&v->u) || !finite_inputs(&v->u_used)) return "an input is not finite";
    if ((v->u.ramp != 0 && v->u.ramp != 1) || (v->u_used.ramp != 0 && v->u_used.ramp != 1))
        return "the input derivatives are invalid";
    if (isnan(v->t_switch)) return "the time of the last switch is not a number";
    if (v->effects < 0 || (v->effects & ~DFO_MD_EFFECTS_ALL)) return "the effects are invalid";
    const dfo_state *s = &v->s;
    if (!isfinite(s->t) || !isfinite(s->t0) || !isfinite(s->X) || !isfinite(s->V) || !isfinite(s->A) ||
        !isfinite(s->F) || !isfinite(s->hA) || s->n < 0 || isnan(s->t_switch))
        return "the state is not finite";
    if (s->mode < -1 || s->mode > 1) return "the mode is invalid";
    return dfo_grid_implausible(r, s->t0, (long long)s->n, dfo_step_size(&v->p), s->t);
}

dfo_inst_status dfo_inst_deserialize(dfo_lifecycle *lc, const char *fn, const unsigned char *buf, size_t size,
                                     void **state)
{
    size_t body = 0;
    if (dfo_state_open(lc, fn, buf, size, MODEL_GUID, &body) != DFO_INST_OK) return DFO_INST_ERROR;
    if (body != BODY_BYTES)
        return dfo_inst_fail(lc, "%s: %lu bytes given, a state of this FMU has %lu.", fn, (unsigned long)size,
                             (unsigned long)(DFO_STATE_HEADER_BYTES + BODY_BYTES));
    osc_values v;
    dfo_run run;
    dfo_cursor c = {NULL, buf + DFO_STATE_HEADER_BYTES};
    dfo_get_bytes(&c, &v, sizeof v);
    dfo_get_run(&c, &run);
    const char *why = implausible(&run, &v);
    if (why) return dfo_inst_fail(lc, "%s: rejected, %s.", fn, why);
    dfo_model_init(&v.M, &v.p);   /* derived constants follow from the parameters, never trusted */
    dfo_check_caches(&v.M, &v.s); /* and caches that do not follow from the state are dropped */
    return store_state(osc(lc), fn, state, &run, &v);
}

/* ---- coupling at second order (core/instance.h) ----------------------------------------------
 *
 * Input derivatives: F_ext and N_ext, orders 1 and 2, for the next step (the Bossak schemes take the
 * input polynomial at every internal step, the exact scheme in closed form where it can:
 * dfo_exact_poly_unsupported). Output derivatives: x (order 1 v, order 2 a) and v (order 1 a, order
 * 2 da/dt), none at a switch on the current time (left and right limits differ). Directional and
 * adjoint derivatives: of the outputs with respect to F_ext, N_ext at the current point, the direct
 * feed-through of a and F_friction by mode (x, v and the rest: 0). */

#define MAX_INPUT_ORDER 2

int dfo_inst_max_input_order(void) { return DFO_CAN_INTERPOLATE_INPUTS ? MAX_INPUT_ORDER : 0; }
int dfo_inst_max_output_order(void) { return DFO_MAX_OUTPUT_DERIVATIVE_ORDER; }

/* The derivative slots of a real input (NULL for any other variable). */
static double *input_derivatives(osc_values *v, const dfo_var_info *var)
{
    if (var->vr == VR_F_ext) return v->u.F_ext_d;
    if (var->vr == VR_N_ext) return v->u.N_ext_d;
    return NULL;
}

dfo_inst_status dfo_inst_set_input_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t nvr,
                                               const int order[], const double value[])
{
    osc_instance *in = osc(lc);
    osc_values *v = &in->v;
    const int max_order = dfo_inst_max_input_order();
    for (size_t i = 0; i < nvr; i++) {
        const dfo_var_info *var = dfo_find_var(vr[i]);
        if (!var) return dfo_inst_fail(lc, "%s: unknown value reference %u.", fn, vr[i]);
        if (var->vr == VR_v_belt)
            return dfo_inst_fail(lc, "%s: input derivatives of v_belt (value reference %u) are not supported: the belt's "
                                 "velocity is held over a communication step; set v_belt at the communication points "
                                 "(only the inputs F_ext and N_ext take derivatives).", fn, vr[i]);
        if (var->causality != DFO_INPUT || var->type != DFO_REAL || !input_derivatives(v, var))
            return dfo_inst_fail(lc, "%s: variable %s (value reference %u) is not a real input: only the inputs "
                                 "F_ext and N_ext take derivatives.", fn, var->name, vr[i]);
        if (order[i] < 1 || order[i] > max_order)
            return dfo_inst_fail(lc, "%s: invalid order %d of the derivative of %s (value reference %u); valid range: "
                                 "1 to %d.", fn, order[i], var->name, vr[i], max_order);
        if (!isfinite(value[i]))
            return dfo_inst_fail(lc, "%s: invalid value %.17g of the order-%d derivative of %s (value reference %u); "
                                 "valid range: finite.", fn, value[i], order[i], var->name, vr[i]);
        const char *why = value[i] != 0.0 ? ramp_unsupported(&v->p) : NULL;
        if (why)
            return dfo_inst_fail(lc, "%s: input derivatives of %s (value reference %u) are not supported with scheme "
                                 "exact here: %s; set them to 0, or choose scheme paper, consistent or located.", fn,
                                 var->name, vr[i], why);
    }
    const double t_now = (lc->run.phase & (DFO_PHASE_INSTANTIATED | DFO_PHASE_INIT)) ? lc->run.start_time
                                                                                      : dfo_inst_time(lc);
    if (v->u.ramp && v->u.t_d != t_now) { /* derivatives of an earlier point (not stepped): forgotten */
        v->u.F_ext_d[0] = v->u.F_ext_d[1] = v->u.N_ext_d[0] = v->u.N_ext_d[1] = 0.0;
        v->u.ramp = 0;
    }
    for (size_t i = 0; i < nvr; i++) {
        const dfo_var_info *var = dfo_find_var(vr[i]);
        input_derivatives(v, var)[order[i] - 1] = value[i];
        /* a nonzero derivative connects the input (its value is then read, 0 until set) */
        if (value[i] != 0.0) *(int *)((char *)&v->u + var->set_offset) = 1;
    }
    v->u.t_d = t_now;
    v->u.ramp = v->u.F_ext_d[0] != 0.0 || v->u.F_ext_d[1] != 0.0 || v->u.N_ext_d[0] != 0.0 || v->u.N_ext_d[1] != 0.0;
    return DFO_INST_OK;
}

/* The step ended on a switch (left and right limits of the acceleration differ at the current time). */
static int at_switch(const osc_instance *in)
{
    const osc_values *v = &in->v;
    /* a Bossak scheme's switch on a step's end is reported at its t + h (to rounding): within the
     * snap tolerance of the end */
    return in->lc.run.event_pending || v->t_switch == v->s.t ||
           (v->M.p.scheme != DFO_SCHEME_EXACT && fabs(v->s.t_switch - v->s.t) <= dfo_snap(v->M.p.h, v->s.t));
}

dfo_inst_status dfo_inst_get_output_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[],
                                                size_t nvr, const int order[], double value[])
{
    osc_instance *in = osc(lc);
    const osc_values *v = &in->v;
    const int max_order = dfo_inst_max_output_order();
    for (size_t i = 0; i < nvr; i++) {
        const dfo_var_info *var = dfo_find_var(vr[i]);
        if (!var) return dfo_inst_fail(lc, "%s: unknown value reference %u.", fn, vr[i]);
        if (var->home != DFO_COMPUTED || (var->id != DFO_OUT_x && var->id != DFO_OUT_v))
            return dfo_inst_fail(lc, "%s: no output derivative for %s (value reference %u): only the outputs x and v "
                                 "have time derivatives.", fn, var->name, vr[i]);
        if (order[i] < 1 || order[i] > max_order)
            return dfo_inst_fail(lc, "%s: invalid order %d of the derivative of %s (value reference %u); valid range: "
                                 "1 to %d.", fn, order[i], var->name, vr[i], max_order);
        const int k = order[i] + (var->id == DFO_OUT_v); /* the order of the derivative of x */
        if (k == 1) {
            value[i] = v->s.V;
            continue;
        }
        if (at_switch(in))
            return dfo_inst_fail(lc, "%s: the order-%d derivative of %s (value reference %u) does not exist at t = "
                                 "%.17g: the step ended on a stick/slip switch, where the acceleration jumps (its left "
                                 "and right limits differ).", fn, order[i], var->name, vr[i], v->s.t);
        if (k == 2) {
            value[i] = acceleration_now(v);
        } else {
            dfo_state s = v->s;
            s.F = friction_now(v);
            value[i] = dfo_jerk(&v->M, &v->u, &s);
        }
        if (!isfinite(value[i]))
            return dfo_inst_fail(lc, "%s: the order-%d derivative of %s (value reference %u) is not representable in "
                                 "double precision (overflow).", fn, order[i], var->name, vr[i]);
    }
    return DFO_INST_OK;
}

/* d output / d input at the current point (the direct feed-through; a pending event's left limit,
 * mode event_from). out: the output's id, input: the input's value reference. */
static double feed_through(const osc_values *v, const dfo_run *r, int out, unsigned int input)
{
    if (out != DFO_OUT_a && out != DFO_OUT_F_friction) return 0.0;
    const dfo_model *M = &v->M;
    dfo_inputs u;
    dfo_inputs_at(&v->u, v->s.t, &u);
    dfo_loads L;
    dfo_loads_init(&L, M, &u);
    const double N_sum = M->p.N + u.N_ext;
    dfo_state s = r->event_pending ? left_limit(v, r->event_from) : v->s;
    double dF = 0.0, dFr = 0.0; /* d friction / d F_ext, d friction / d N_ext */
    int rests = 0;
    if (L.Fb > 0.0 && s.mode == 0) {
        /* stuck: the friction holds the static force, or sits on the limit beyond it */
        const double S = -dfo_friction_force(M, &u, &s); /* the static force, clamped to the limit */
        if (fabs(S) < L.Fb) dF = -1.0;
        else dFr = N_sum > 0.0 ? -dfo_sign(S) * M->mu_b : 0.0;
        rests = M->p.scheme != DFO_SCHEME_PAPER;
    } else if (s.mode != 0 && (L.Fb > 0.0 || N_sum > 0.0)) {
        const double mu = M->stribeck ? dfo_friction_mu(&M->law, fabs(s.V - dfo_belt_speed(&u))) : M->mu_k;
        dFr = N_sum > 0.0 ? -s.mode * mu : 0.0;
    }
    if (input == VR_v_belt) {
        /* stuck within the limit: the friction holds f = P + F_ext - c v_belt - k x (dF = c); sliding
         * with Stribeck: F = -s N mu(|v - v_belt|), dF = N mu'(u); coulomb sliding: 0 */
        double dB = 0.0;
        if (L.Fb > 0.0 && s.mode == 0) {
            if (fabs(dfo_friction_force(M, &u, &s)) < L.Fb && s.V == dfo_belt_speed(&u)) dB = M->p.c;
        } else if (s.mode != 0 && M->stribeck && L.N > 0.0) {
            dB = L.N * dfo_friction_dmu(&M->law, fabs(s.V - dfo_belt_speed(&u)));
        }
        if (out == DFO_OUT_F_friction) return dB;
        return rests ? 0.0 : dB / M->p.m;
    }
    const int force = input == VR_F_ext;
    if (out == DFO_OUT_F_friction) return force ? dF : dFr;
    if (rests) return 0.0;
    return ((force ? 1.0 : 0.0) + (force ? dF : dFr)) / M->p.m;
}

/* The knowns (inputs) and unknowns (real outputs) of a directional derivative, checked. */
static int check_partials(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                          const unsigned int known[], size_t nk)
{
    for (size_t i = 0; i < nu; i++) {
        const dfo_var_info *var = dfo_find_var(unknown[i]);
        if (!var || var->causality != DFO_OUTPUT || var->type != DFO_REAL) {
            dfo_inst_fail(lc, "%s: unknown %s (value reference %u) is not a real output: directional derivatives are "
                          "of the outputs x, v, a, F_friction and the other real outputs.", fn,
                          var ? var->name : "?", unknown[i]);
            return 0;
        }
    }
    for (size_t j = 0; j < nk; j++) {
        const dfo_var_info *var = dfo_find_var(known[j]);
        if (!var || var->causality != DFO_INPUT || var->type != DFO_REAL) {
            dfo_inst_fail(lc, "%s: known %s (value reference %u) is not an input: directional derivatives are with "
                          "respect to the inputs F_ext, N_ext and v_belt.", fn, var ? var->name : "?", known[j]);
            return 0;
        }
    }
    return 1;
}

static dfo_inst_status partials(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                const unsigned int known[], size_t nk, const double seed[], double sensitivity[],
                                int adjoint)
{
    if (!check_partials(lc, fn, unknown, nu, known, nk)) return DFO_INST_ERROR;
    osc_instance *in = osc(lc);
    osc_values tmp;
    const osc_values *v = computed(in, &tmp);
    const size_t n_out = adjoint ? nk : nu, n_seed = adjoint ? nu : nk;
    const unsigned int *seed_vr = adjoint ? unknown : known, *out_vr = adjoint ? known : unknown;
    for (size_t o = 0; o < n_seed; o++)
        if (!isfinite(seed[o]))
            return dfo_inst_fail(lc, "%s: invalid seed %.17g for %s (value reference %u); valid range: finite.", fn,
                                 seed[o], dfo_find_var(seed_vr[o])->name, seed_vr[o]);
    for (size_t o = 0; o < n_out; o++) sensitivity[o] = 0.0;
    for (size_t i = 0; i < nu; i++)
        for (size_t j = 0; j < nk; j++) {
            const double J = feed_through(v, &lc->run, dfo_find_var(unknown[i])->id, known[j]);
            if (J == 0.0) continue;
            if (adjoint) sensitivity[j] += J * seed[i];
            else sensitivity[i] += J * seed[j];
        }
    for (size_t o = 0; o < n_out; o++)
        if (!isfinite(sensitivity[o]))
            return dfo_inst_fail(lc, "%s: the %s derivative of %s (value reference %u) is not representable in double "
                                 "precision (overflow: a tiny mass m = %.17g or a huge friction coefficient).", fn,
                                 adjoint ? "adjoint" : "directional", dfo_find_var(out_vr[o])->name, out_vr[o],
                                 v->M.p.m);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_directional(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                     const unsigned int known[], size_t nk, const double seed[], double sensitivity[])
{
    return partials(lc, fn, unknown, nu, known, nk, seed, sensitivity, 0);
}

dfo_inst_status dfo_inst_adjoint(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                 const unsigned int known[], size_t nk, const double seed[], double sensitivity[])
{
    return partials(lc, fn, unknown, nu, known, nk, seed, sensitivity, 1);
}
