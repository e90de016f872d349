/* The instance core of the DryFrictionOscillator FMUs (the model API of core/instance.h), its part for
 * start values, the model derived from the parameters, the life cycle and the input derivatives a
 * scheme cannot follow (the other parts: osc_instance.h). No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "osc_instance.h"
#include "exact.h"

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

/* ---- start values ---------------------------------------------------------------------------- */

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
        if (var->type == DFO_REAL) *(double *)osc_slot(v, var) = var->start;
        else *(int *)osc_slot(v, var) = (int)var->start;
    }
    in->lc.run.phase = DFO_PHASE_INSTANTIATED;
}

/* ---- the instance ---------------------------------------------------------------------------- */

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
void osc_inst_sens_reset(dfo_state *s)
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
    osc_inst_sens_reset(&v->s);
    v->effects = dfo_effects(&v->M, &v->u);
    v->u_used = v->u;
    v->t_switch = -INFINITY;
}

/* Values of computed variables need the started model; during initialisation it is derived from
 * the current parameters on the fly. */
const osc_values *osc_inst_computed(const osc_instance *in, osc_values *tmp)
{
    if (in->lc.run.phase != DFO_PHASE_INIT) return &in->v;
    *tmp = in->v;
    prepare(tmp, in->lc.run.start_time);
    return tmp;
}

const char *osc_inst_scheme_name(int scheme)
{
    static const char *const names[5] = {"?", "paper", "consistent", "located", "exact"};
    return (scheme >= 1 && scheme <= 4) ? names[scheme] : "?";
}

/* ---- life cycle ------------------------------------------------------------------------------ */

/* Why the exact scheme cannot follow input derivatives on these parameters (NULL: it can, and the
 * Bossak schemes always can). */
const char *osc_inst_ramp_unsupported(const dfo_params *p)
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
dfo_inst_status osc_inst_ramp_refused(osc_instance *in, const char *fn)
{
    return dfo_inst_fail(&in->lc, "%s: input derivatives of %s are not supported with scheme exact here: %s; set "
                         "them to 0, or choose scheme paper, consistent or located.", fn, ramped_inputs(&in->v.u),
                         osc_inst_ramp_unsupported(&in->v.p));
}

/* The scales the computation honours (dfo_scale_refused): k, and the force scale of the excitation,
 * the friction limit and the initial state over m and k. NULL when inside, else the sentence. */
double osc_inst_force_scale(const dfo_params *p)
{
    return fmax(fmax(fabs(p->P0), fmax(p->mu_s, p->chi * p->mu_s) * p->N),
                fmax(p->k * fabs(p->x0), sqrt(p->k) * sqrt(p->m) * fabs(p->v0)));
}

static const char *scale_refused(const dfo_params *p, char *buf, size_t len)
{
    const double F = osc_inst_force_scale(p);
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
    if (v->u.ramp && osc_inst_ramp_unsupported(&v->p)) return osc_inst_ramp_refused(in, fn);
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
                     fn, osc_inst_scheme_name(v->p.scheme));
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
