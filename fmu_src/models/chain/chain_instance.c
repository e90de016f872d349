/* The instance core of the DryFrictionChain FMUs (the model API of core/instance.h for the model of
 * fmu_src/models/chain/modelDescription.xml), its part for memory, start values, the chain model
 * built from the values, the life cycle and configuration mode (the other parts: chain_instance.h).
 * The physics is chain.[ch]. No FMI types.
 *
 * Memory: every array through the host's allocator, O(n): parameters (10 n), inputs (2 x 2 n), their
 * derivatives (2 x 2 n), the state and the step's start state (7 n each), one scratch array, the chain
 * model's workspace. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain_instance.h"
#include "bossak.h" /* DFO_STEPS_PER_PERIOD, DFO_MIN_STEPS_PER_PERIOD */

#include <math.h>
#include <stdio.h>
#include <string.h>

/* The model description's scheme values are those of the physics. */
typedef char dfo_static_assert_schemes[(DFO_MD_SCHEME_PAPER == 1 && DFO_MD_SCHEME_CONSISTENT == 2 &&
                                        DFO_MD_SCHEME_LOCATED == 3) ? 1 : -1];
#if defined(DFO_CHAIN_FIXED_N)
typedef char dfo_static_assert_fixed_n[(DFO_CHAIN_FIXED_N >= 1 && DFO_CHAIN_FIXED_N <= MAX_n) ? 1 : -1];
#endif

/* ---- memory ---------------------------------------------------------------------------------- */

static void *al_allocate(void *env, size_t nobj, size_t size)
{
    const chain_instance *in = (const chain_instance *)env;
    return in->lc.host.alloc(in->lc.host.ctx, nobj, size);
}

static void al_release(void *env, void *obj)
{
    const chain_instance *in = (const chain_instance *)env;
    in->lc.host.free(in->lc.host.ctx, obj);
}

chain_alloc chain_inst_allocator(chain_instance *in)
{
    const chain_alloc al = {al_allocate, al_release, in};
    return al;
}

static double *dalloc(chain_instance *in, size_t n) { return (double *)in->lc.host.alloc(in->lc.host.ctx, n, sizeof(double)); }

static void release(chain_instance *in, void *p)
{
    if (p) in->lc.host.free(in->lc.host.ctx, p);
}

void chain_inst_free_model(chain_values *v)
{
    if (v->M) chain_destroy(v->M);
    v->M = NULL;
}

void chain_inst_free_arrays(chain_instance *in, chain_values *v)
{
    const chain_alloc al = chain_inst_allocator(in);
    release(in, v->pa);
    release(in, v->ua);
    release(in, v->ua_used);
    release(in, v->scratch);
    release(in, v->ud);
    chain_state_release(&al, &v->s);
    chain_state_release(&al, &v->s0);
    v->pa = v->ua = v->ua_used = v->scratch = v->ud = NULL;
}

int chain_inst_alloc_arrays(chain_instance *in, chain_values *v, size_t n)
{
    const chain_alloc al = chain_inst_allocator(in);
    chain_values w;
    memset(&w, 0, sizeof w);
    w.pa = dalloc(in, (size_t)DFO_NUM_AP * n);
    w.ua = dalloc(in, (size_t)DFO_NUM_AI * n);
    w.ua_used = dalloc(in, (size_t)DFO_NUM_AI * n);
    w.scratch = dalloc(in, n);
    w.ud = dalloc(in, 2 * (size_t)DFO_NUM_AI * n);
    const int s_ok = chain_state_alloc(&al, n, &w.s);
    const int s0_ok = chain_state_alloc(&al, n, &w.s0);
    if (!w.pa || !w.ua || !w.ua_used || !w.scratch || !w.ud || !s_ok || !s0_ok) {
        chain_inst_free_arrays(in, &w);
        return 0;
    }
    v->pa = w.pa;
    v->ua = w.ua;
    v->ua_used = w.ua_used;
    v->scratch = w.scratch;
    v->ud = w.ud;
    v->ud_set = 0;
    v->s = w.s;
    v->s0 = w.s0;
    v->n = n;
    return 1;
}

/* ---- values ---------------------------------------------------------------------------------- */

double *chain_inst_stored(chain_values *v, const dfo_var_info *var, size_t i)
{
    switch (var->home) {
    case DFO_IN_PARAMS: return &v->sp[var->slot];
    case DFO_IN_ARRAYS: return &v->pa[(size_t)var->slot * v->n + i];
    case DFO_IN_INPUTS: return &v->ua[(size_t)var->slot * v->n + i];
    default: return NULL;
    }
}

/* Array parameters and inputs at their start values (every element the table's start). */
static void array_starts(chain_values *v)
{
    for (int j = 0; j < DFO_NUM_VARS; j++) {
        const dfo_var_info *var = &DFO_VARS[j];
        if (var->home != DFO_IN_ARRAYS && var->home != DFO_IN_INPUTS) continue;
        for (size_t i = 0; i < v->n; i++) *chain_inst_stored(v, var, i) = var->start;
    }
    memcpy(v->ua_used, v->ua, (size_t)DFO_NUM_AI * v->n * sizeof(double));
    for (int j = 0; j < DFO_NUM_AI; j++) v->u_set[j] = v->u_set_used[j] = 0;
    memset(v->ud, 0, 2 * (size_t)DFO_NUM_AI * v->n * sizeof(double));
    v->ud_set = 0;
    v->sw_t = 0.0;
    v->sw_block = -1;
}

/* Start values, and the run at its start (phase instantiated). */
static void set_start_values(chain_instance *in)
{
    chain_values *v = &in->v;
    const dfo_run run0 = {0};
    for (int j = 0; j < DFO_NUM_VARS; j++) {
        const dfo_var_info *var = &DFO_VARS[j];
        if (var->home == DFO_IN_PARAMS) v->sp[var->slot] = var->start;
    }
    array_starts(v);
    v->n_config = v->n;
    in->lc.run = run0;
    in->lc.run.phase = DFO_PHASE_INSTANTIATED;
    v->event_block = 0;
    v->acc_valid = 0;
}

/* ---- the chain's parameters, inputs, model ---------------------------------------------------- */

chain_params chain_inst_params_of(const chain_values *v)
{
    const size_t n = v->n;
    const double *pa = v->pa;
    chain_params p;
    memset(&p, 0, sizeof p);
    p.n = n;
    p.m = pa + (size_t)DFO_AP_m * n;
    p.k = pa + (size_t)DFO_AP_k * n;
    p.c = pa + (size_t)DFO_AP_c * n;
    p.P0 = pa + (size_t)DFO_AP_P0 * n;
    p.phi = pa + (size_t)DFO_AP_phi * n;
    p.N = pa + (size_t)DFO_AP_N * n;
    p.mu_s = pa + (size_t)DFO_AP_mu_s * n;
    p.chi = pa + (size_t)DFO_AP_chi * n;
    p.x0 = pa + (size_t)DFO_AP_x0 * n;
    p.v0 = pa + (size_t)DFO_AP_v0 * n;
    p.k_site = pa + (size_t)DFO_AP_k_site * n;
    p.c_site = pa + (size_t)DFO_AP_c_site * n;
    p.v_s = pa + (size_t)DFO_AP_v_s * n;
    p.delta = pa + (size_t)DFO_AP_delta * n;
    p.friction_law = (int)v->sp[DFO_SP_friction_law];
    p.k_end = v->sp[DFO_SP_k_end];
    p.c_end = v->sp[DFO_SP_c_end];
    p.omega = v->sp[DFO_SP_omega];
    p.h = v->sp[DFO_SP_h];
    p.alpha = v->sp[DFO_SP_alpha];
    p.scheme = (int)v->sp[DFO_SP_scheme];
    if (v->me) p.scheme = DFO_SCHEME_LOCATED; /* Model Exchange: the physics of the schemes whose stuck blocks rest */
    p.account_energy = 0;
    p.h = chain_step_size(&p); /* h = 0: derived from the dynamics */
    return p;
}

double chain_inst_step_h(const chain_values *v)
{
    if (v->M) return chain_step(v->M);
    const chain_params p = chain_inst_params_of(v);
    return p.h;
}

chain_inputs chain_inst_inputs_of(const chain_values *v, int used)
{
    const double *u = used ? v->ua_used : v->ua;
    const int *set = used ? v->u_set_used : v->u_set;
    chain_inputs ci;
    ci.F_ext = set[DFO_AI_F_ext] ? u + (size_t)DFO_AI_F_ext * v->n : NULL;
    ci.N_ext = set[DFO_AI_N_ext] ? u + (size_t)DFO_AI_N_ext * v->n : NULL;
    return ci;
}

const double *chain_inst_belt_of(const chain_values *v, int used)
{
    const double *u = used ? v->ua_used : v->ua;
    const int *set = used ? v->u_set_used : v->u_set;
    if (!set[DFO_AI_v_belt]) return NULL;
    const double *vb = u + (size_t)DFO_AI_v_belt * v->n;
    for (size_t i = 0; i < v->n; i++)
        if (vb[i] != 0.0) return vb;
    return NULL; /* belts at rest: the fixed support's path and bits */
}

const double *chain_inst_state_belt(const chain_values *v)
{
    return chain_inst_belt_of(v, !v->belts_unsynced);
}

chain_ramp chain_inst_ramp_of(const chain_values *v)
{
    chain_ramp r;
    memset(&r, 0, sizeof r);
    r.t_ref = v->s.t;
    if (!v->ud_set) return r;
    const size_t n = v->n;
    for (int k = 0; k < 2; k++) {
        r.dF_ext[k] = v->ud + ((size_t)k * DFO_NUM_AI + DFO_AI_F_ext) * n;
        r.dN_ext[k] = v->ud + ((size_t)k * DFO_NUM_AI + DFO_AI_N_ext) * n;
    }
    return r;
}

void chain_inst_ramp_done(chain_values *v, double t_ref)
{
    if (!v->ud_set) return;
    const chain_inputs ci = chain_inst_inputs_of(v, 0);
    chain_ramp r = chain_inst_ramp_of(v);
    r.t_ref = t_ref;
    const size_t n = v->n;
    double *F = v->ua + (size_t)DFO_AI_F_ext * n, *N = v->ua + (size_t)DFO_AI_N_ext * n;
    for (size_t i = 0; i < n; i++) {
        double u, Ne, rate;
        chain_ramp_value(&ci, &r, 0, i, v->s.t, &u, &rate);
        chain_ramp_value(&ci, &r, 1, i, v->s.t, &Ne, &rate);
        F[i] = u;
        N[i] = Ne;
    }
    memset(v->ud, 0, 2 * (size_t)DFO_NUM_AI * n * sizeof(double));
    v->ud_set = 0;
}

/* The scales the computation honours (dfo_scale_refused), for every block: each stiffness, and the
 * chain's force scale (the largest excitation, friction limit and initial spring force or momentum
 * rate of any block) over each mass and each stiffness > 0. NULL when inside, else the sentence. */
static const char *scale_refused(const chain_params *p, char *buf, size_t len)
{
    double F = 0.0;
    for (size_t i = 0; i < p->n; i++) {
        const double K = p->k[i] + (i + 1 < p->n ? p->k[i + 1] : p->k_end) + p->k_site[i];
        F = fmax(F, fmax(fmax(fabs(p->P0[i]), fmax(p->mu_s[i], p->chi[i] * p->mu_s[i]) * p->N[i]),
                         fmax(K * fabs(p->x0[i]), sqrt(K) * sqrt(p->m[i]) * fabs(p->v0[i]))));
    }
    static const char *const F_text = "max over the blocks of |P0|, max(mu_s, mu_k) N, K |x0|, sqrt(K m) |v0| "
                                      "(K: the block's springs)";
    char m_name[32], k_name[32];
    const char *msg = NULL;
    for (size_t i = 0; i < p->n && !msg; i++) {
        snprintf(m_name, sizeof m_name, "m[%zu]", i + 1);
        snprintf(k_name, sizeof k_name, "k[%zu]", i + 1);
        msg = dfo_scale_refused(DFO_SCALE_LIMIT, F, F_text, p->m[i], m_name, p->k[i], k_name, buf, len);
        snprintf(k_name, sizeof k_name, "k_site[%zu]", i + 1);
        if (!msg) msg = dfo_scale_refused(DFO_SCALE_LIMIT, F, F_text, p->m[i], m_name, p->k_site[i], k_name, buf, len);
    }
    if (msg) return msg;
    return dfo_scale_refused(DFO_SCALE_LIMIT, F, F_text, p->m[p->n - 1], m_name, p->k_end, "k_end", buf, len);
}

const char *chain_inst_prepare(chain_instance *in, char *buf, size_t len)
{
    chain_values *v = &in->v;
    const chain_params p = chain_inst_params_of(v);
    const char *msg = chain_check_params(&p, buf, len);
    if (msg) return msg;
    if ((msg = scale_refused(&p, buf, len))) return msg;
    if (chain_inst_belt_of(v, 0) && p.scheme == DFO_SCHEME_PAPER)
        return "v_belt is set but the paper scheme has no moving belt (its stuck blocks creep with Bossak's "
               "acceleration); use scheme consistent or located";
    chain_inst_free_model(v);
    const chain_alloc al = chain_inst_allocator(in);
    const char *err = NULL;
    v->M = chain_create(&p, &al, &err);
    if (!v->M) return err ? err : "out of memory";
    const chain_inputs ci = chain_inst_inputs_of(v, 0);
    chain_start_belt(v->M, &ci, chain_inst_belt_of(v, 0), in->lc.run.start_time, &v->s);
    memcpy(v->ua_used, v->ua, (size_t)DFO_NUM_AI * v->n * sizeof(double));
    memcpy(v->u_set_used, v->u_set, sizeof v->u_set);
    v->belts_unsynced = 0;
    in->lc.run.time = in->lc.run.start_time;
    v->acc_valid = 0;
    return NULL;
}

int chain_inst_started(const chain_instance *in)
{
    return in->v.M && (in->lc.run.phase & DFO_PHASES_STARTED);
}

/* ---- life cycle ------------------------------------------------------------------------------ */

dfo_lifecycle *dfo_inst_new(const dfo_host *host, const char *name, int logging_on)
{
    chain_instance *in = (chain_instance *)dfo_lifecycle_new(host, sizeof(chain_instance), name, logging_on);
    if (!in) return NULL;
    if (!chain_inst_alloc_arrays(in, &in->v, CHAIN_N_START)) {
        dfo_inst_fail(&in->lc, "instantiate: out of memory for n = %lu blocks.", (unsigned long)CHAIN_N_START);
        host->free(host->ctx, in);
        return NULL;
    }
    set_start_values(in);
    return &in->lc;
}

void dfo_inst_delete(dfo_lifecycle *lc)
{
    if (!lc) return;
    chain_instance *in = chn(lc);
    chain_inst_free_model(&in->v);
    chain_inst_free_arrays(in, &in->v);
    lc->host.free(lc->host.ctx, in);
}

dfo_inst_status dfo_inst_exit_init(dfo_lifecycle *lc, const char *fn)
{
    chain_instance *in = chn(lc);
    char buf[640];
    const char *msg = chain_inst_prepare(in, buf, sizeof buf);
    if (msg) return dfo_inst_fail(&in->lc, "%s: %s.", fn, msg);
    in->lc.run.phase = DFO_PHASE_STEP;
    dfo_inst_status status = DFO_INST_OK;
    const double h = in->v.sp[DFO_SP_h], T_min = chain_shortest_period(in->v.M);
    if (h > 0.0 && h * DFO_MIN_STEPS_PER_PERIOD > T_min) {
        status = DFO_INST_WARNING;
        dfo_inst_log(&in->lc, DFO_INST_WARNING, DFO_LOG_STATUS_WARNING,
                     "%s: h = %.6g s takes only %.3g internal steps per %.6g s, the shortest period of the chain's "
                     "dynamics (its fastest natural frequency, bounded from the springs and masses, the excitation "
                     "period 2 pi/omega, the damping rate): the results do not resolve it. Choose h <= %.6g s (1/%g "
                     "of it), or h = 0 to let the FMU derive it.", fn, h, T_min / h, T_min, T_min / DFO_STEPS_PER_PERIOD,
                     DFO_STEPS_PER_PERIOD);
    }
    dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_EVENTS, "start at t = %.17g: %lu blocks.", in->v.s.t,
                 (unsigned long)in->v.n);
    return status;
}

dfo_inst_status chain_inst_resize(chain_instance *in, const char *fn, size_t n)
{
    if (n == in->v.n) return DFO_INST_OK;
    chain_values w = in->v;
    if (!chain_inst_alloc_arrays(in, &w, n))
        return dfo_inst_fail(&in->lc, "%s: out of memory for n = %lu blocks; n stays %lu.", fn, (unsigned long)n,
                             (unsigned long)in->v.n);
    chain_inst_free_model(&in->v);
    chain_inst_free_arrays(in, &in->v);
    w.M = NULL;
    w.acc_valid = 0;
    in->v = w;
    return DFO_INST_OK;
}

void dfo_inst_reset(dfo_lifecycle *lc)
{
    chain_instance *in = chn(lc);
    chain_inst_free_model(&in->v);
    (void)chain_inst_resize(in, "reset", CHAIN_N_START); /* on failure the arrays keep their size */
    set_start_values(in);
    in->lc.warned = 0;
}

int dfo_inst_has_structural(void) { return 1; }

dfo_inst_status dfo_inst_enter_config(dfo_lifecycle *lc, const char *fn)
{
    chain_instance *in = chn(lc);
    (void)fn;
    in->v.n_config = in->v.n;
    in->lc.run.phase = DFO_PHASE_CONFIG;
    return DFO_INST_OK;
}

/* Leaving configuration mode with a new n: every array has n elements at their start values. */
dfo_inst_status dfo_inst_exit_config(dfo_lifecycle *lc, const char *fn)
{
    chain_instance *in = chn(lc);
    const size_t n = in->v.n_config;
    if (n != in->v.n) {
        if (chain_inst_resize(in, fn, n) != DFO_INST_OK) return DFO_INST_ERROR;
        array_starts(&in->v);
    }
    in->v.n_config = in->v.n;
    in->lc.run.phase = DFO_PHASE_INSTANTIATED;
    return DFO_INST_OK;
}

