/* The DryFrictionChain instance core (chain_instance.h), its variable access: value references
 * resolved through the generated table (model_vars.h gives each variable its group and slot; FMI
 * 3.0 reaches an array through its own value reference, n values; FMI 2.0 reaches element i,
 * 1-based, through the value reference of the build's layout (chain_config.h's DFO_FMI2_ARRAYS),
 * named m[i] in messages), get/set with every
 * value checked before any is stored, the outputs, and the structural parameter n. No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain_instance.h"
#include "friction.h" /* the Stribeck law of the outputs */

#include <math.h>
#include <stdio.h>
#include <string.h>

/* ---- the variable table ---------------------------------------------------------------------- */

static int resolve(const chain_instance *in, unsigned int vr, chain_ref *r)
{
    const dfo_var_info *var = dfo_find_var(vr);
#if defined(DFO_CHAIN_FIXED_N)
    (void)in;
    if (var && !var->array) {
        r->var = var;
        r->elem = -1;
        snprintf(r->name, sizeof r->name, "%s", var->name);
        return 1;
    }
    /* an element: the build's layout (chain_config.h) */
    for (size_t a = 0; a < DFO_FMI2_NUM_ARRAYS; a++) {
        const dfo_fmi2_array *L = &DFO_FMI2_ARRAYS[a];
        if (vr < L->first || vr - L->first >= L->count) continue;
        const unsigned int k = vr - L->first;
        r->var = dfo_find_var(L->vr);
        r->elem = (long)k;
        if (L->cols > 1) snprintf(r->name, sizeof r->name, "%s[%u,%u]", r->var->name, k / L->cols + 1, k % L->cols + 1);
        else snprintf(r->name, sizeof r->name, "%s[%u]", r->var->name, k + 1);
        return 1;
    }
    return 0;
#else
    (void)in;
    if (!var) return 0;
    r->var = var;
    r->elem = -1;
    snprintf(r->name, sizeof r->name, "%s", var->name);
    return 1;
#endif
}

/* Values a resolved variable holds. */
static size_t count(const chain_instance *in, const chain_ref *r)
{
    return (r->var->array && r->elem < 0) ? in->v.n : 1;
}

int chain_inst_lookup_any(const chain_instance *in, const char *fn, unsigned int vr, chain_ref *r)
{
    if (resolve(in, vr, r)) return 1;
    dfo_inst_fail(&in->lc, "%s: unknown value reference %u.", fn, vr);
    return 0;
}

size_t chain_inst_count(const chain_instance *in, const chain_ref *r) { return count(in, r); }

size_t dfo_inst_n_values(const dfo_lifecycle *lc, const unsigned int vr[], size_t nvr)
{
    const chain_instance *in = cchn(lc);
    size_t total = 0;
    for (size_t i = 0; i < nvr; i++) {
        chain_ref r;
        total += resolve(in, vr[i], &r) ? count(in, &r) : 1;
    }
    return total;
}

static int lookup(const chain_instance *in, const char *fn, unsigned int vr, dfo_var_type type, chain_ref *r)
{
    if (!resolve(in, vr, r)) {
        dfo_inst_fail(&in->lc, "%s: unknown value reference %u.", fn, vr);
        return 0;
    }
    if (r->var->type != type) {
        dfo_inst_fail(&in->lc, "%s: variable %s (value reference %u) is of type %s, not %s.", fn, r->name, vr,
                      dfo_type_name(r->var->type), dfo_type_name(type));
        return 0;
    }
    return 1;
}

static int check_value(const chain_instance *in, const char *fn, const chain_ref *r, unsigned int vr, double x)
{
    const char *range = dfo_inst_invalid(r->var, x);
    if (!range) return 1;
    const int exact = r->var->home == DFO_IN_PARAMS && r->var->slot == DFO_SP_scheme && x == 4.0;
    dfo_inst_fail(&in->lc, "%s: invalid value %.17g for %s (value reference %u); valid range: %s%s.", fn, x, r->name, vr,
                  range, exact ? " (the chain has no exact scheme)" : "");
    return 0;
}

static int settable(const chain_instance *in, const char *fn, const chain_ref *r, unsigned int vr)
{
    return dfo_inst_settable(&in->lc, fn, r->var, r->name, vr);
}

/* ---- outputs --------------------------------------------------------------------------------- */

/* Block i's external force and normal force under the inputs now (used: those of the last step). */
static void block_inputs(const chain_values *v, int used, size_t i, double *u, double *N)
{
    const chain_inputs ci = chain_inst_inputs_of(v, used);
    *u = ci.F_ext ? ci.F_ext[i] : 0.0;
    *N = fmax(v->pa[(size_t)DFO_AP_N * v->n + i] + (ci.N_ext ? ci.N_ext[i] : 0.0), 0.0);
}

double chain_inst_kinetic_mu(const chain_values *v, size_t i)
{
    const size_t n = v->n;
    const double mu_s = v->pa[(size_t)DFO_AP_mu_s * n + i], mu_k = v->pa[(size_t)DFO_AP_chi * n + i] * mu_s;
    if ((int)v->sp[DFO_SP_friction_law] != DFO_LAW_STRIBECK) return mu_k;
    const dfo_friction_law L = {DFO_LAW_STRIBECK, mu_s, mu_k, v->pa[(size_t)DFO_AP_v_s * n + i],
                                v->pa[(size_t)DFO_AP_delta * n + i]};
    const double *vb = chain_inst_belt_of(v, 0);
    return dfo_friction_mu(&L, fabs(vb ? v->s.V[i] - vb[i] : v->s.V[i]));
}

double chain_inst_friction_out(const chain_values *v, size_t i)
{
    const double F = v->s.F[i];
    double u0, N0, u1, N1;
    block_inputs(v, 1, i, &u0, &N0);
    block_inputs(v, 0, i, &u1, &N1);
    if (u1 == u0 && N1 == N0) return F;
    const size_t n = v->n;
    const double mu_s = v->pa[(size_t)DFO_AP_mu_s * n + i], mu_k = v->pa[(size_t)DFO_AP_chi * n + i] * mu_s;
    const int mode = v->s.mode[i];
    if (mode != 0) return 0.0 - mode * (chain_inst_kinetic_mu(v, i) * N1); /* the kinetic force of the new normal force */
    const double mu_b = fmax(mu_s, mu_k);
    if (!(mu_b * N0 > 0.0)) return F; /* not held: no friction before */
    const double Fb = mu_b * N1;
    return fmin(fmax(F - (u1 - u0), -Fb), Fb); /* held: takes the change of its external force */
}

void chain_inst_accelerations(chain_values *v)
{
    const chain_inputs ci = chain_inst_inputs_of(v, 0);
    chain_accelerations(v->M, &ci, chain_inst_state_belt(v), &v->s, v->scratch);
    const size_t n = v->n;
    if ((int)v->sp[DFO_SP_friction_law] == DFO_LAW_STRIBECK) {
        /* the core's a takes a slide's force from the state: with inputs set since the step, the
         * kinetic force of the new normal force (F_friction's; the same bits when unchanged) */
        for (size_t i = 0; i < n; i++) {
            if (v->s.mode[i] == 0) continue;
            const double F = chain_inst_friction_out(v, i);
            if (F != v->s.F[i]) v->scratch[i] += (F - v->s.F[i]) / v->pa[(size_t)DFO_AP_m * n + i];
        }
    }
    if ((int)v->sp[DFO_SP_scheme] != DFO_MD_SCHEME_PAPER || v->me) return;
    /* the paper's stuck block creeps with the force that holds it: with inputs set since the step,
     * the held force that takes their change (the same bits when they are unchanged) */
    for (size_t i = 0; i < n; i++) {
        if (v->s.mode[i] != 0) continue;
        const double F = chain_inst_friction_out(v, i);
        if (F != v->s.F[i]) v->scratch[i] += (F - v->s.F[i]) / v->pa[(size_t)DFO_AP_m * n + i];
    }
}

/* A pending event's left limit of the switching block b: its mode before the switch, the friction
 * of that mode (kinetic -from mu_k N; stuck, the static force clamped to the breakaway limit), the
 * acceleration with that force. The other blocks are continuous at the switch. */
static void left_limit(const chain_values *v, int event_from, const double *a_right, double *F, double *a)
{
    const size_t n = v->n, b = v->event_block;
    const double *pa = v->pa;
    const chain_inputs ci = chain_inst_inputs_of(v, 0);
    const double m = pa[(size_t)DFO_AP_m * n + b];
    const double mu_s = pa[(size_t)DFO_AP_mu_s * n + b], mu_k = pa[(size_t)DFO_AP_chi * n + b] * mu_s;
    const double N = fmax(pa[(size_t)DFO_AP_N * n + b] + (ci.N_ext ? ci.N_ext[b] : 0.0), 0.0);
    const double F_right = chain_inst_friction_out(v, b);
    const double S = m * a_right[b] - F_right; /* the net applied force (continuous) */
    if (event_from != 0) {
        /* (Stribeck: the slide ends at zero relative speed, mu(0)) */
        double kmu = mu_k;
        if ((int)v->sp[DFO_SP_friction_law] == DFO_LAW_STRIBECK) {
            const dfo_friction_law L = {DFO_LAW_STRIBECK, mu_s, mu_k, pa[(size_t)DFO_AP_v_s * n + b],
                                        pa[(size_t)DFO_AP_delta * n + b]};
            kmu = dfo_friction_mu(&L, 0.0);
        }
        *F = -(double)event_from * kmu * N;
        *a = (S + *F) / m;
    } else {
        const double Fb = fmax(mu_s, mu_k) * N;
        *F = fmin(fmax(-S, -Fb), Fb);
        *a = 0.0;
    }
}

static dfo_inst_status get_outputs(chain_instance *in, const char *fn, const chain_ref *r, unsigned int vr, double *out,
                                   int *iout)
{
    chain_values *v = &in->v;
    if (!chain_inst_started(in)) {
        char buf[640];
        const char *msg = chain_inst_prepare(in, buf, sizeof buf);
        if (msg) return dfo_inst_fail(&in->lc, "%s: %s cannot be computed: %s.", fn, r->name, msg);
    }
    (void)vr;
    const size_t n = v->n, i0 = r->elem < 0 ? 0 : (size_t)r->elem, i1 = r->elem < 0 ? n : i0 + 1;
    const int id = r->var->slot;
    if (id == DFO_OUT_h_used) {
        *out = chain_step(v->M);
        if (!chain_inst_started(in)) chain_inst_free_model(v);
        return DFO_INST_OK;
    }
    if (v->me && chain_inst_started(in)) chain_inst_me_refresh(v); /* (the host moved the state or the inputs) */
    const int need_a = id == DFO_OUT_a || (in->lc.run.event_pending && id == DFO_OUT_F_friction);
    const int temporary = !chain_inst_started(in);
    if (need_a && (temporary || !v->acc_valid)) {
        chain_inst_accelerations(v);
        v->acc_valid = !temporary;
    }
    const dfo_run *run = &in->lc.run;
    double F_left = 0.0, a_left = 0.0;
    if (run->event_pending && need_a) left_limit(v, run->event_from, v->scratch, &F_left, &a_left);
    for (size_t i = i0; i < i1; i++) {
        const int left = run->event_pending && i == v->event_block;
        double x = 0.0;
        switch (id) {
        case DFO_OUT_x: x = v->s.X[i]; break;
        case DFO_OUT_v: x = v->s.V[i]; break;
        case DFO_OUT_a: x = left ? a_left : v->scratch[i]; break;
        case DFO_OUT_F_friction: x = left ? F_left : chain_inst_friction_out(v, i); break;
        case DFO_OUT_mode: iout[i - i0] = left ? run->event_from : v->s.mode[i]; continue;
        case DFO_OUT_event_indicator_0: x = chain_inst_me_indicator(v, 0, i); break;
        case DFO_OUT_event_indicator_1: x = chain_inst_me_indicator(v, 1, i); break;
        default: break;
        }
        if (!isfinite(x))
            return dfo_inst_fail(&in->lc, "%s: %s[%lu] (value reference %u) is not representable in double precision "
                                 "for these parameters (overflow).", fn, r->var->name, (unsigned long)i + 1, vr);
        out[i - i0] = x;
    }
    if (!chain_inst_started(in)) chain_inst_free_model(v);
    return DFO_INST_OK;
}

/* ---- get / set ------------------------------------------------------------------------------- */

/* Real (dout) or integer (iout) values: stored ones, or computed outputs, n values per array. */
static dfo_inst_status get_values(chain_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                  dfo_var_type type, double *dout, int *iout)
{
    size_t k = 0;
    for (size_t j = 0; j < n; j++) {
        chain_ref r;
        if (!lookup(in, fn, vr[j], type, &r)) return DFO_INST_ERROR;
        const size_t c = count(in, &r);
        if (r.var->home == DFO_COMPUTED) {
            if (get_outputs(in, fn, &r, vr[j], dout ? dout + k : NULL, iout ? iout + k : NULL) != DFO_INST_OK)
                return DFO_INST_ERROR;
        } else {
            const size_t i0 = r.elem < 0 ? 0 : (size_t)r.elem;
            for (size_t i = 0; i < c; i++) {
                const double x = *chain_inst_stored(&in->v, r.var, i0 + i);
                if (dout) dout[k + i] = x;
                else iout[k + i] = (int)x;
            }
        }
        k += c;
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_get_real(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, double value[])
{
    chain_instance *in = chn(lc);
    return get_values(in, fn, vr, n, DFO_REAL, value, NULL);
}

dfo_inst_status dfo_inst_get_int(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, int value[])
{
    chain_instance *in = chn(lc);
    return get_values(in, fn, vr, n, DFO_INTEGER, NULL, value);
}

dfo_inst_status dfo_inst_get_bool(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, int value[])
{
    chain_instance *in = chn(lc);
    for (size_t j = 0; j < n; j++) {
        chain_ref r;
        if (!lookup(in, fn, vr[j], DFO_BOOLEAN, &r)) return DFO_INST_ERROR;
        value[j] = *chain_inst_stored(&in->v, r.var, 0) != 0.0;
    }
    return DFO_INST_OK;
}

/* Check every value of every variable (type, causality and phase, range per element), then store:
 * a rejected call changes nothing. */
static dfo_inst_status set_values(chain_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                  const double value[], dfo_var_type type)
{
    size_t k = 0;
    for (size_t j = 0; j < n; j++) {
        chain_ref r;
        if (!lookup(in, fn, vr[j], type, &r) || !settable(in, fn, &r, vr[j])) return DFO_INST_ERROR;
        const size_t c = count(in, &r);
        for (size_t i = 0; i < c; i++) {
            if (c > 1) snprintf(r.name, sizeof r.name, "%s[%lu]", r.var->name, (unsigned long)i + 1);
            if (!check_value(in, fn, &r, vr[j], value[k + i])) return DFO_INST_ERROR;
        }
        k += c;
    }
    k = 0;
    for (size_t j = 0; j < n; j++) {
        chain_ref r;
        (void)resolve(in, vr[j], &r);
        const size_t c = count(in, &r), i0 = r.elem < 0 ? 0 : (size_t)r.elem;
        for (size_t i = 0; i < c; i++) *chain_inst_stored(&in->v, r.var, i0 + i) = value[k + i];
        if (r.var->home == DFO_IN_INPUTS) in->v.u_set[r.var->slot] = 1;
        in->v.acc_valid = in->v.me_fresh = 0;
        k += c;
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_set_real(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                  const double value[])
{
    chain_instance *in = chn(lc);
    return set_values(in, fn, vr, n, value, DFO_REAL);
}

/* Integer values (the scheme; arrays of integers are outputs only) through doubles, in chunks. */
dfo_inst_status dfo_inst_set_int(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                 const int value[])
{
    chain_instance *in = chn(lc);
    for (size_t j = 0; j < n; j++) {
        chain_ref r;
        if (!lookup(in, fn, vr[j], DFO_INTEGER, &r) || !settable(in, fn, &r, vr[j])) return DFO_INST_ERROR;
        if (!check_value(in, fn, &r, vr[j], value[j])) return DFO_INST_ERROR;
    }
    for (size_t j = 0; j < n; j++) {
        chain_ref r;
        (void)resolve(in, vr[j], &r);
        *chain_inst_stored(&in->v, r.var, r.elem < 0 ? 0 : (size_t)r.elem) = value[j];
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_set_bool(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                  const int value[])
{
    chain_instance *in = chn(lc);
    (void)value;
    for (size_t j = 0; j < n; j++) {
        chain_ref r;
        if (!lookup(in, fn, vr[j], DFO_BOOLEAN, &r)) return DFO_INST_ERROR;
    }
    return DFO_INST_OK; /* the model has no Boolean variables: lookup has failed on any */
}

dfo_inst_status dfo_inst_get_uint64(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                    unsigned long long value[])
{
    chain_instance *in = chn(lc);
    for (size_t j = 0; j < n; j++) {
        chain_ref r;
        if (!lookup(in, fn, vr[j], DFO_UINT64, &r)) return DFO_INST_ERROR;
        value[j] = (unsigned long long)(in->lc.run.phase == DFO_PHASE_CONFIG ? in->v.n_config : in->v.n);
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_set_uint64(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                    const unsigned long long value[])
{
    chain_instance *in = chn(lc);
    for (size_t j = 0; j < n; j++) {
        chain_ref r;
        if (!lookup(in, fn, vr[j], DFO_UINT64, &r) || !settable(in, fn, &r, vr[j])) return DFO_INST_ERROR;
        if (value[j] < (unsigned long long)r.var->min || value[j] > (unsigned long long)r.var->max) {
            dfo_inst_fail(&in->lc, "%s: invalid value %llu for %s (value reference %u); valid range: %s.", fn, value[j],
                          r.name, vr[j], r.var->range);
            return DFO_INST_ERROR;
        }
    }
    for (size_t j = 0; j < n; j++) in->v.n_config = (size_t)value[j];
    return DFO_INST_OK;
}

