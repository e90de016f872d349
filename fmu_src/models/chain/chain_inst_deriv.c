/* The chain's instance core, coupling at second order (core/instance.h): input derivatives (orders
 * 1 and 2 of F_ext and N_ext, for the next step: chain_advance_ramped), output derivatives (of x and
 * v), directional and adjoint derivatives of the outputs with respect to the inputs at the current
 * point. No FMI types.
 *
 * The direct feed-through at the current instant is block by block: a block's a and F_friction
 * follow its own F_ext and N_ext only (the other blocks feel an input only through a step), as the
 * outputs compute them (chain_inst_vars.c):
 *   sliding block (or one without friction):  a = (P + u - K x + F - C v) / m, F = -s mu_k N:
 *     da/dF_ext = 1/m, da/dN_ext = -s mu_k / m, dF/dN_ext = -s mu_k (0 where N + N_ext <= 0);
 *   stuck block (held at rest): a = 0, its held force takes the change of its external force:
 *     dF/dF_ext = -1 inside the breakaway limit; on the limit dF/dN_ext = +-mu_b (the paper scheme's
 *     stuck block creeps, a = (S + F) / m: 0 inside the limit, on it 1/m and +-mu_b / m).
 *   x, v: 0. */
#include "dfo_fp.h"

#include "chain_instance.h"
#include "chain_internal.h" /* the model's K, C and loads (output derivative of v) */

#include <math.h>
#include <string.h>

int dfo_inst_max_input_order(void) { return 2; }
int dfo_inst_max_output_order(void) { return 2; }

static const char *order_text(int order) { return order == 1 ? "first" : order == 2 ? "second" : "an invalid"; }

/* ---- input derivatives ----------------------------------------------------------------------- */

dfo_inst_status dfo_inst_set_input_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t nvr,
                                               const int order[], const double value[])
{
    chain_instance *in = chn(lc);
    chain_values *v = &in->v;
    size_t k = 0;
    for (size_t j = 0; j < nvr; j++) {
        chain_ref r;
        if (!chain_inst_lookup_any(in, fn, vr[j], &r)) return DFO_INST_ERROR;
        if (r.var->home != DFO_IN_INPUTS || r.var->type != DFO_REAL)
            return dfo_inst_fail(lc, "%s: %s (value reference %u) is not a real input: derivatives can be set for the "
                                 "inputs F_ext and N_ext only.", fn, r.name, vr[j]);
        if (r.var->slot == DFO_AI_v_belt)
            return dfo_inst_fail(lc, "%s: v_belt (value reference %u) takes no derivatives: the belt speeds are "
                                 "held over a communication step (derivatives: F_ext and N_ext only).", fn, vr[j]);
        if (order[j] < 1 || order[j] > 2)
            return dfo_inst_fail(lc, "%s: order %d of the derivative of %s (value reference %u) is out of range "
                                 "(valid: 1 ... 2).", fn, order[j], r.name, vr[j]);
        const size_t c = chain_inst_count(in, &r);
        for (size_t i = 0; i < c; i++)
            if (!isfinite(value[k + i]))
                return dfo_inst_fail(lc, "%s: invalid value %.17g for the %s derivative of %s[%lu] (value reference "
                                     "%u); valid range: finite.", fn, value[k + i], order_text(order[j]),
                                     r.var->name, (unsigned long)(r.elem < 0 ? i : (size_t)r.elem) + 1, vr[j]);
        k += c;
    }
    k = 0;
    const size_t n = v->n;
    for (size_t j = 0; j < nvr; j++) {
        chain_ref r;
        (void)chain_inst_lookup_any(in, fn, vr[j], &r);
        const size_t c = chain_inst_count(in, &r), i0 = r.elem < 0 ? 0 : (size_t)r.elem;
        double *d = v->ud + ((size_t)(order[j] - 1) * DFO_NUM_AI + (size_t)r.var->slot) * n;
        for (size_t i = 0; i < c; i++) d[i0 + i] = value[k + i];
        v->u_set[r.var->slot] = 1; /* the input's polynomial starts from its value */
        k += c;
    }
    v->ud_set = 0;
    for (size_t i = 0; i < 2 * (size_t)DFO_NUM_AI * n && !v->ud_set; i++) v->ud_set = v->ud[i] != 0.0;
    return DFO_INST_OK;
}

/* ---- the outputs' state ---------------------------------------------------------------------- */

static dfo_inst_status need_started(chain_instance *in, const char *fn, const char *what)
{
    if (chain_inst_started(in)) return DFO_INST_OK;
    return dfo_inst_fail(&in->lc, "%s: %s are available once initialisation has ended (the model is not started).",
                         fn, what);
}

/* The accelerations (output a) of the state and inputs into scratch. */
static void accelerations(chain_values *v)
{
    if (v->acc_valid) return;
    chain_inst_accelerations(v);
    v->acc_valid = 1;
}

/* Block i is at a stick/slip switch now: a pending event of its own, or its switch at the state's time. */
static int at_switch(const chain_instance *in, size_t i)
{
    const chain_values *v = &in->v;
    if (in->lc.run.event_pending && v->event_block == i) return 1;
    return v->sw_block == (long long)i && v->sw_t == v->s.t;
}

/* ---- output derivatives ---------------------------------------------------------------------- */

/* d a_i / dt of block i at the state (the accelerations in scratch, the model's loads those of the
 * current inputs): stuck 0, else (P' + u' - s mu_k N_ext' - (K v)_i - (C a)_i) / m_i with the rates
 * of the inputs the derivatives set for the next step give. */
static double jerk(chain_values *v, size_t i)
{
    chain_model *M = v->M;
    const chain_state *s = &v->s;
    if (chain_held(M, s, i)) return 0.0;
    const double cw = dfo_cos(M->omega * s->t + M->phi0), sw = dfo_sin(M->omega * s->t + M->phi0);
    const double Pd = -M->Pc[i] * M->omega * sw + -M->Ps[i] * M->omega * cw;
    const size_t n = v->n;
    const double du = v->ud[(size_t)DFO_AI_F_ext * n + i], dNe = v->ud[(size_t)DFO_AI_N_ext * n + i];
    const double *ua = v->ua;
    const double Ne = v->u_set[DFO_AI_N_ext] ? ua[(size_t)DFO_AI_N_ext * n + i] : 0.0;
    const double dN = (M->N[i] + Ne > 0.0 && chain_has_friction(M, i)) ? dNe : 0.0;
    const double kmu = M->stribeck ? chain_inst_kinetic_mu(v, i) : M->mu_k[i];
    double f = Pd + du - s->mode[i] * kmu * dN - chain_Kx(M, s->V, i) - chain_Cv(M, v->scratch, i);
    /* Stribeck: d F / dt = -N mu'(u) a, u the relative speed */
    if (M->stribeck && chain_has_friction(M, i))
        f -= M->Nn[i] * dfo_friction_dmu(&M->law[i], chain_rel_speed(chain_inst_state_belt(v), s, i)) * v->scratch[i];
    return f / M->m[i];
}

dfo_inst_status dfo_inst_get_output_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[],
                                                size_t nvr, const int order[], double value[])
{
    chain_instance *in = chn(lc);
    chain_values *v = &in->v;
    if (need_started(in, fn, "output derivatives") != DFO_INST_OK) return DFO_INST_ERROR;
    size_t k = 0;
    for (size_t j = 0; j < nvr; j++) {
        chain_ref r;
        if (!chain_inst_lookup_any(in, fn, vr[j], &r)) return DFO_INST_ERROR;
        const int id = r.var->slot;
        if (r.var->home != DFO_COMPUTED || (id != DFO_OUT_x && id != DFO_OUT_v))
            return dfo_inst_fail(lc, "%s: %s (value reference %u) has no output derivatives: the chain gives them for "
                                 "x and v only (a and F_friction follow the inputs at once).", fn, r.name, vr[j]);
        if (order[j] < 1 || order[j] > 2)
            return dfo_inst_fail(lc, "%s: order %d of the derivative of %s (value reference %u) is out of range "
                                 "(valid: 1 ... 2).", fn, order[j], r.name, vr[j]);
        const size_t c = chain_inst_count(in, &r), i0 = r.elem < 0 ? 0 : (size_t)r.elem;
        const int needs_a = id == DFO_OUT_v || order[j] == 2;
        for (size_t e = 0; e < c; e++) {
            const size_t i = i0 + e;
            if (needs_a && at_switch(in, i))
                return dfo_inst_fail(lc, "%s: the %s derivative of %s[%lu] (value reference %u) does not exist at "
                                     "t = %.17g: block %lu switches between stick and slip there (its acceleration "
                                     "jumps); step past the switch first.", fn, order_text(order[j]), r.var->name,
                                     (unsigned long)i + 1, vr[j], in->lc.run.time, (unsigned long)i + 1);
        }
        if (needs_a) {
            v->acc_valid = 0; /* (the model's loads those of the current inputs too) */
            accelerations(v);
        }
        for (size_t e = 0; e < c; e++) {
            const size_t i = i0 + e;
            double x;
            if (id == DFO_OUT_x) x = (order[j] == 1) ? v->s.V[i] : v->scratch[i];
            else x = (order[j] == 1) ? v->scratch[i] : jerk(v, i);
            if (!isfinite(x))
                return dfo_inst_fail(lc, "%s: the %s derivative of %s[%lu] (value reference %u) is not representable "
                                     "in double precision (overflow).", fn, order_text(order[j]), r.var->name,
                                     (unsigned long)i + 1, vr[j]);
            value[k + e] = x;
        }
        k += c;
    }
    return DFO_INST_OK;
}

/* ---- directional and adjoint derivatives ----------------------------------------------------- */

/* d (output id of block i) / d (input slot of block i) at the current point (see the top). */
static double jac(const chain_values *v, int id, int slot, size_t i)
{
    if (id != DFO_OUT_a && id != DFO_OUT_F_friction) return 0.0;
    const size_t n = v->n;
    const double *pa = v->pa;
    const chain_inputs now = chain_inst_inputs_of(v, 0), used = chain_inst_inputs_of(v, 1);
    const double m = pa[(size_t)DFO_AP_m * n + i], N = pa[(size_t)DFO_AP_N * n + i];
    const double mu_s = pa[(size_t)DFO_AP_mu_s * n + i], mu_k = pa[(size_t)DFO_AP_chi * n + i] * mu_s;
    const double mu_b = fmax(mu_s, mu_k), kmu = chain_inst_kinetic_mu(v, i);
    const double Ne = now.N_ext ? now.N_ext[i] : 0.0, Ne0 = used.N_ext ? used.N_ext[i] : 0.0;
    const double N1 = fmax(N + Ne, 0.0), N0 = fmax(N + Ne0, 0.0);
    const int live = N + Ne > 0.0; /* the normal force follows N_ext */
    const int mode = v->s.mode[i];
    const int F_ext = slot == DFO_AI_F_ext;
    if (id == DFO_OUT_a && !(mode == 0 && mu_b * N1 > 0.0)) { /* moving, or no friction */
        if (F_ext) return 1.0 / m;
        return (mu_b * N1 > 0.0 && live) ? -mode * kmu / m : 0.0;
    }
    /* F_friction (chain_inst_friction_out) */
    double dF = 0.0;
    if (mode != 0) {
        dF = (!F_ext && live) ? -mode * kmu : 0.0;
    } else if (mu_b * N0 > 0.0) { /* held: its force takes the change of F_ext, up to the limit */
        const double u1 = now.F_ext ? now.F_ext[i] : 0.0, u0 = used.F_ext ? used.F_ext[i] : 0.0;
        const double Fs = v->s.F[i] - (u1 - u0);
        if (fabs(Fs) < mu_b * N1) dF = F_ext ? -1.0 : 0.0;
        else dF = (!F_ext && live) ? (Fs > 0.0 ? mu_b : -mu_b) : 0.0;
    }
    if (id == DFO_OUT_F_friction) return dF;
    /* a of a held block: 0 at rest; the paper's creeps, (S + F) / m */
    if (v->M->scheme != DFO_SCHEME_PAPER) return 0.0;
    return ((F_ext ? 1.0 : 0.0) + dF) / m;
}

typedef struct {
    const dfo_var_info *var;
    size_t i0, c, off;  /* its first element, number of values, offset in its vector */
} span_ref;

/* Resolve and check a list of unknowns (outputs: kind 0) or knowns (inputs: 1) into refs. */
static int resolve_list(chain_instance *in, const char *fn, const unsigned int vr[], size_t nv, int kind,
                        span_ref *out)
{
    size_t off = 0;
    for (size_t j = 0; j < nv; j++) {
        chain_ref r;
        if (!chain_inst_lookup_any(in, fn, vr[j], &r)) return 0;
        const int id = r.var->slot;
        if (kind == 0 && !(r.var->home == DFO_COMPUTED && r.var->type == DFO_REAL && id != DFO_OUT_h_used)) {
            dfo_inst_fail(&in->lc, "%s: %s (value reference %u) is not a real output: the directional derivatives are "
                          "those of x, v, a and F_friction.", fn, r.name, vr[j]);
            return 0;
        }
        if (kind == 1 && !(r.var->home == DFO_IN_INPUTS && r.var->type == DFO_REAL)) {
            dfo_inst_fail(&in->lc, "%s: %s (value reference %u) is not an input: the directional derivatives are with "
                          "respect to F_ext and N_ext.", fn, r.name, vr[j]);
            return 0;
        }
        out[j].var = r.var;
        out[j].i0 = r.elem < 0 ? 0 : (size_t)r.elem;
        out[j].c = chain_inst_count(in, &r);
        out[j].off = off;
        off += out[j].c;
    }
    return 1;
}

/* sens = J seed (adjoint 0) or J^T seed (1); J over the unknowns' and knowns' values. */
static dfo_inst_status directional(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                   const unsigned int known[], size_t nk, const double seed[], double sens[],
                                   int adjoint)
{
    chain_instance *in = chn(lc);
    chain_values *v = &in->v;
    const char *what = adjoint ? "adjoint derivatives" : "directional derivatives";
    if (need_started(in, fn, what) != DFO_INST_OK) return DFO_INST_ERROR;
    span_ref *U = (span_ref *)lc->host.alloc(lc->host.ctx, nu + nk + 1, sizeof(span_ref));
    if (!U) return dfo_inst_fail(lc, "%s: out of memory.", fn);
    span_ref *K = U + nu;
    dfo_inst_status st = DFO_INST_OK;
    if (!resolve_list(in, fn, unknown, nu, 0, U) || !resolve_list(in, fn, known, nk, 1, K)) st = DFO_INST_ERROR;
    const size_t n_unknown = nu ? U[nu - 1].off + U[nu - 1].c : 0, n_known = nk ? K[nk - 1].off + K[nk - 1].c : 0;
    for (size_t a = 0; a < nu && st == DFO_INST_OK; a++) {
        const int id = U[a].var->slot;
        if (!in->lc.run.event_pending || (id != DFO_OUT_a && id != DFO_OUT_F_friction)) continue;
        const size_t b = v->event_block;
        if (b >= U[a].i0 && b < U[a].i0 + U[a].c)
            st = dfo_inst_fail(lc, "%s: the derivatives of %s[%lu] do not exist at t = %.17g: block %lu switches "
                               "between stick and slip there (event pending); update the discrete states first.", fn,
                               U[a].var->name, (unsigned long)b + 1, in->lc.run.time, (unsigned long)b + 1);
    }
    /* the seeds (over the knowns, or the unknowns for the adjoint) are finite */
    const span_ref *S = adjoint ? U : K, *O = adjoint ? K : U;
    const size_t n_s = adjoint ? nu : nk, n_o = adjoint ? nk : nu;
    for (size_t b = 0; b < n_s && st == DFO_INST_OK; b++)
        for (size_t e = 0; e < S[b].c; e++)
            if (!isfinite(seed[S[b].off + e])) {
                st = dfo_inst_fail(lc, "%s: invalid seed %.17g for %s[%lu]; valid range: finite.", fn,
                                   seed[S[b].off + e], S[b].var->name, (unsigned long)(S[b].i0 + e) + 1);
                break;
            }
    if (st == DFO_INST_OK) {
        if (adjoint) memset(sens, 0, n_known * sizeof(double));
        else memset(sens, 0, n_unknown * sizeof(double));
        for (size_t a = 0; a < nu; a++) {
            for (size_t e = 0; e < U[a].c; e++) {
                const size_t i = U[a].i0 + e, pu = U[a].off + e;
                for (size_t b = 0; b < nk; b++) {
                    if (i < K[b].i0 || i >= K[b].i0 + K[b].c) continue;
                    const size_t pk = K[b].off + (i - K[b].i0);
                    const double J = jac(v, U[a].var->slot, K[b].var->slot, i);
                    if (adjoint) sens[pk] += J * seed[pu];
                    else sens[pu] += J * seed[pk];
                }
            }
        }
        for (size_t b = 0; b < n_o && st == DFO_INST_OK; b++) /* a tiny m or a huge mu: not representable */
            for (size_t e = 0; e < O[b].c; e++)
                if (!isfinite(sens[O[b].off + e])) {
                    st = dfo_inst_fail(lc, "%s: the %s derivative of %s[%lu] is not representable in double "
                                       "precision (overflow: a tiny mass or a huge friction coefficient).", fn,
                                       adjoint ? "adjoint" : "directional",
                                       O[b].var->name, (unsigned long)(O[b].i0 + e) + 1);
                    break;
                }
    }
    lc->host.free(lc->host.ctx, U);
    return st;
}

dfo_inst_status dfo_inst_directional(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                     const unsigned int known[], size_t nk, const double seed[], double sensitivity[])
{
    return directional(lc, fn, unknown, nu, known, nk, seed, sensitivity, 0);
}

dfo_inst_status dfo_inst_adjoint(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                 const unsigned int known[], size_t nk, const double seed[], double sensitivity[])
{
    return directional(lc, fn, unknown, nu, known, nk, seed, sensitivity, 1);
}
