/* The chain's set-up: parameters, chain_create (the derived constants and the O(n) workspace),
 * the shortest period and the step, state storage, energy, status texts. See chain.h and
 * chain_internal.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain_internal.h"

#include <stdio.h>
#include <string.h>

static const char *bad(char *buf, size_t len, const char *name, size_t i, double v, const char *range)
{
    snprintf(buf, len, "invalid value %g for %s[%zu] (valid: %s)", v, name, i + 1, range);
    return buf;
}

static const char *bad_scalar(char *buf, size_t len, const char *name, double v, const char *range)
{
    snprintf(buf, len, "invalid value %g for %s (valid: %s)", v, name, range);
    return buf;
}

const char *chain_check_params(const chain_params *p, char *buf, size_t len)
{
    if (p->n < 1) { snprintf(buf, len, "invalid value %zu for n (valid: >= 1)", p->n); return buf; }
    for (size_t i = 0; i < p->n; i++) {
        if (!(p->m[i] > 0.0 && isfinite(p->m[i]))) return bad(buf, len, "m", i, p->m[i], "> 0, finite");
        if (!(p->k[i] >= 0.0 && isfinite(p->k[i]))) return bad(buf, len, "k", i, p->k[i], ">= 0, finite");
        if (!(p->c[i] >= 0.0 && isfinite(p->c[i]))) return bad(buf, len, "c", i, p->c[i], ">= 0, finite");
        if (!isfinite(p->P0[i])) return bad(buf, len, "P0", i, p->P0[i], "finite");
        if (!isfinite(p->phi[i])) return bad(buf, len, "phi", i, p->phi[i], "finite");
        if (!(p->N[i] >= 0.0 && isfinite(p->N[i]))) return bad(buf, len, "N", i, p->N[i], ">= 0, finite");
        if (!(p->mu_s[i] >= 0.0 && isfinite(p->mu_s[i]))) return bad(buf, len, "mu_s", i, p->mu_s[i], ">= 0, finite");
        if (!(p->chi[i] >= 0.0 && isfinite(p->chi[i]))) return bad(buf, len, "chi", i, p->chi[i], ">= 0, finite");
        if (!isfinite(p->x0[i])) return bad(buf, len, "x0", i, p->x0[i], "finite");
        if (!isfinite(p->v0[i])) return bad(buf, len, "v0", i, p->v0[i], "finite");
        if (p->k_site && !(p->k_site[i] >= 0.0 && isfinite(p->k_site[i])))
            return bad(buf, len, "k_site", i, p->k_site[i], ">= 0, finite");
        if (p->c_site && !(p->c_site[i] >= 0.0 && isfinite(p->c_site[i])))
            return bad(buf, len, "c_site", i, p->c_site[i], ">= 0, finite");
        if (p->v_s && !(p->v_s[i] > 0.0 && isfinite(p->v_s[i]))) return bad(buf, len, "v_s", i, p->v_s[i], "> 0, finite");
        if (p->delta && !(p->delta[i] > 0.0 && isfinite(p->delta[i])))
            return bad(buf, len, "delta", i, p->delta[i], "> 0, finite");
    }
    if (p->friction_law < 0 || p->friction_law > DFO_LAW_STRIBECK) {
        snprintf(buf, len, "invalid value %d for friction_law (valid: 1 coulomb, 2 stribeck)", p->friction_law);
        return buf;
    }
    if (!(p->k_end >= 0.0 && isfinite(p->k_end))) return bad_scalar(buf, len, "k_end", p->k_end, ">= 0, finite");
    if (!(p->c_end >= 0.0 && isfinite(p->c_end))) return bad_scalar(buf, len, "c_end", p->c_end, ">= 0, finite");
    if (!(p->omega >= 0.0 && isfinite(p->omega))) return bad_scalar(buf, len, "omega", p->omega, ">= 0, finite");
    if (!(p->h > 0.0 && isfinite(p->h))) return bad_scalar(buf, len, "h", p->h, "> 0, finite");
    if (!(p->alpha >= -1.0 / 3.0 && p->alpha <= 0.0)) return bad_scalar(buf, len, "alpha", p->alpha, "[-1/3, 0]");
    if (p->scheme < DFO_SCHEME_PAPER || p->scheme > DFO_SCHEME_LOCATED) {
        snprintf(buf, len, "invalid value %d for scheme (valid: 1 paper, 2 consistent, 3 located)", p->scheme);
        return buf;
    }
    if (p->friction_law == DFO_LAW_STRIBECK) {
        for (size_t i = 0; p->delta && i < p->n; i++)
            if (p->delta[i] < 1.0) {
                snprintf(buf, len,
                         "friction_law = stribeck supports delta >= 1 only, not %g for delta[%zu] (below 1 the "
                         "friction's slope is infinite at zero relative speed)",
                         p->delta[i], i + 1);
                return buf;
            }
        if (p->scheme != DFO_SCHEME_LOCATED)
            return "friction_law = stribeck needs scheme located (the speed-dependent friction is solved inside its "
                   "steps): choose scheme located, or friction_law = coulomb";
    }
    return NULL;
}

static double *dalloc(const chain_alloc *al, size_t n) { return (double *)al->allocate(al->env, n, sizeof(double)); }

/* Gershgorin bounds of the largest eigenvalues of M^-1 K and M^-1 C: each row's diagonal plus its
 * off-diagonals, over its mass (one block: its own). */
static void gershgorin(const chain_params *p, double *kmax, double *cmax)
{
    const size_t n = p->n;
    *kmax = *cmax = 0.0;
    for (size_t i = 0; i < n; i++) {
        const double kr = (i + 1 < n) ? p->k[i + 1] : p->k_end, cr = (i + 1 < n) ? p->c[i + 1] : p->c_end;
        const double kl = (i > 0) ? p->k[i] : 0.0, cl = (i > 0) ? p->c[i] : 0.0;
        const double kd = p->k[i] + kr + (p->k_site ? p->k_site[i] : 0.0);
        const double cd = p->c[i] + cr + (p->c_site ? p->c_site[i] : 0.0);
        *kmax = fmax(*kmax, (n == 1 ? kd : kd + kl + ((i + 1 < n) ? kr : 0.0)) / p->m[i]);
        *cmax = fmax(*cmax, (n == 1 ? cd : cd + cl + ((i + 1 < n) ? cr : 0.0)) / p->m[i]);
    }
}

/* 2 pi over the fastest of sqrt(kmax), cmax (a rate taken as an angular frequency) and |omega|. */
static double shortest_period(double kmax, double cmax, double omega)
{
    const double fastest = fmax(fmax(sqrt(kmax), cmax), fabs(omega));
    return fastest > 0.0 ? 2.0 * DFO_PI / fastest : INFINITY;
}

static void *eng_calloc(void *env, size_t nobj, size_t size)
{
    const chain_alloc *al = (const chain_alloc *)env;
    return al->allocate(al->env, nobj, size);
}
static void eng_free(void *env, void *obj)
{
    const chain_alloc *al = (const chain_alloc *)env;
    al->release(al->env, obj);
}

/* The engine's setup of the model (its operators in M->ops, its rows in M->rows). */
static eng *make_engine(chain_model *M, const char **err)
{
    const size_t n = M->n;
    chain_eng_ops *O = &M->ops;
    O->n = n;
    O->m = M->m;
    O->Kd = M->Kd;
    O->P0 = M->P0;
    O->phi = M->phi;
    O->Ko = M->Ko;
    O->Cd = M->Cd;
    O->Co = M->Co;
    O->damped = M->damped;
    for (size_t i = 0; i < n; i++) {
        M->ridx[i] = i;
        M->rw[i] = 1.0;
        M->rows[i].nnz = 1;
        M->rows[i].idx = &M->ridx[i];
        M->rows[i].w = &M->rw[i];
    }
    eng_setup S;
    memset(&S, 0, sizeof S);
    S.n = n;
    S.nc = n;
    S.ops.ctx = O;
    S.ops.apply_K = chain_op_K;
    S.ops.apply_C = M->damped ? chain_op_C : NULL;
    S.ops.apply_M = chain_op_M;
    S.ops.factor = chain_op_factor;
    S.ops.solve = chain_op_solve;
    S.ops.friction = chain_op_friction;
    S.ops.breakaway = chain_op_breakaway;
    /* its sparse-structure operators: the held solves always; the fused grid step and the spans
     * (the located scheme's local switch placement) where the energy accounts are not kept (they
     * would take the step past them), the fused step without Stribeck (its basis solve is then not
     * the step's) */
    memset(&M->sparse, 0, sizeof M->sparse);
    M->sparse.held_basis = 1;
    M->sparse.contact_breakaway = chain_op_contact_breakaway;
    if (!M->energy && !M->stribeck) M->sparse.step_held = chain_op_step_held;
    if (!M->energy) {
        O->sub = &M->view;
        chain_op_set_reach(O, M->h, M->alpha);
        M->sparse.span_max = n;
        M->sparse.span = chain_op_span;
        M->sparse.span_bind = chain_op_span_bind;
        const eng_ops view = {&M->view,        chain_op_K,        chain_op_C,         chain_op_M, chain_op_factor,
                              chain_op_solve, chain_op_friction, chain_op_breakaway, 0};
        M->sparse.span_ops = view;
        if (!M->damped) M->sparse.span_ops.apply_C = NULL;
    }
    S.sparse = &M->sparse;
    S.mass_diagonal = 1; /* (the mass slot's solves: chain_op_diag, no coupling term) */
    S.rows = M->rows;
    S.exc.omega = M->omega;
    S.exc.phi0 = M->phi0;
    S.exc.Pc = M->Pc;
    S.exc.Ps = M->Ps;
    S.N = M->N;
    S.mu_s = M->mu_s;
    S.mu_k = M->mu_k;
    S.law = M->law;
    S.h = M->h;
    S.alpha = M->alpha;
    S.scheme = M->scheme;
    S.friction_updates = 1;
    S.account_energy = M->energy;
    S.fast_paths = !M->energy;
    S.rate_max = M->rate_max;
    S.snap_max_rel_h = SNAP_REL_H;
    S.snap_min_rel_h = SNAP_REL_H;
    S.snap_eps_t = 0.0;
    const eng_alloc ea = {eng_calloc, eng_free, &M->al};
    return eng_create(&S, &ea, err);
}

chain_model *chain_create(const chain_params *p, const chain_alloc *al, const char **err)
{
    static const char *const oom = "out of memory";
    char buf[160];
    const char *msg = chain_check_params(p, buf, sizeof buf);
    if (msg) { if (err) *err = "invalid parameters (chain_check_params names the first one)"; return NULL; }
    chain_model *M = (chain_model *)al->allocate(al->env, 1, sizeof(chain_model));
    if (!M) { if (err) *err = oom; return NULL; }
    const size_t n = p->n;
    M->al = *al;
    M->n = n;
    /* one block of doubles for the per-block arrays (NARR of n) and the operators' (NOPS of n, for the
     * chain and for its span's view), one of ints for the kept factorisations' patterns */
    enum { NARR = 22, NOPS = 6 * ENG_NSLOTS + 6 };
    double *blk = dalloc(al, (size_t)(NARR + 2 * NOPS) * n);
    int *iblk = (int *)al->allocate(al->env, 2 * ENG_NSLOTS * n, sizeof(int));
    M->rows = (eng_row *)al->allocate(al->env, n, sizeof(eng_row));
    M->ridx = (size_t *)al->allocate(al->env, n, sizeof(size_t));
    chain_run_row *rr = (chain_run_row *)al->allocate(al->env, n, sizeof(chain_run_row));
    if (!blk || !iblk || !M->rows || !M->ridx || !rr) {
        if (blk) al->release(al->env, blk);
        if (iblk) al->release(al->env, iblk);
        if (M->rows) al->release(al->env, M->rows);
        if (M->ridx) al->release(al->env, M->ridx);
        if (rr) al->release(al->env, rr);
        al->release(al->env, M);
        if (err) *err = oom;
        return NULL;
    }
    double **arr[NARR] = {&M->m,  &M->Pc, &M->Ps, &M->P0, &M->phi, &M->N,  &M->mu_s, &M->mu_k,
                          &M->mu_b, &M->x0, &M->v0, &M->Kd, &M->Ko, &M->Cd, &M->Co, &M->ks,
                          &M->cs, &M->u,  &M->mukN, &M->Fb, &M->Nn, &M->rw};
    for (int j = 0; j < NARR; j++) *arr[j] = blk + (size_t)j * n;
    chain_eng_ops *ops[2] = {&M->ops, &M->view};
    for (int v = 0; v < 2; v++) {
        chain_eng_ops *O = ops[v];
        double *ob = blk + (size_t)(NARR + v * NOPS) * n;
        int *ib = iblk + (size_t)(v * ENG_NSLOTS) * n;
        for (int k = 0; k < ENG_NSLOTS; k++) {
            O->d[k] = ob + (size_t)(6 * k) * n;
            O->e[k] = ob + (size_t)(6 * k + 1) * n;
            O->cp[k] = ob + (size_t)(6 * k + 2) * n;
            O->inv[k] = ob + (size_t)(6 * k + 3) * n;
            O->kcp[k] = ob + (size_t)(6 * k + 4) * n;
            O->kinv[k] = ob + (size_t)(6 * k + 5) * n;
            O->kh[k] = ib + (size_t)k * n;
        }
        O->q = ob + (size_t)(6 * ENG_NSLOTS) * n;
        O->work = ob + (size_t)(6 * ENG_NSLOTS + 1) * n; /* 2 n */
        O->nd = ob + (size_t)(6 * ENG_NSLOTS + 3) * n;
        O->ne = ob + (size_t)(6 * ENG_NSLOTS + 4) * n;
        O->nr = ob + (size_t)(6 * ENG_NSLOTS + 5) * n;
        O->rr = NULL; /* (the span's view steps no runs) */
        O->rr_slot = -1;
        for (int k = 0; k < 5; k++) O->rr_src[k] = NULL;
    }
    M->ops.rr = rr;
    M->iblk = iblk;
    M->stribeck = p->friction_law == DFO_LAW_STRIBECK;
    M->law = NULL;
    if (M->stribeck) {
        M->law = (dfo_friction_law *)al->allocate(al->env, n, sizeof(dfo_friction_law));
        if (!M->law) {
            chain_destroy(M);
            if (err) *err = oom;
            return NULL;
        }
        for (size_t i = 0; i < n; i++) {
            dfo_friction_law *L = &M->law[i];
            L->law = DFO_LAW_STRIBECK;
            L->mu_s = p->mu_s[i];
            L->mu_k = p->chi[i] * p->mu_s[i];
            L->v_s = p->v_s ? p->v_s[i] : 0.01;
            L->delta = p->delta ? p->delta[i] : 1.0;
        }
    }
    M->k_end = p->k_end;
    M->c_end = p->c_end;
    M->omega = p->omega;
    M->h = p->h;
    M->phi0 = p->phi[0];
    for (size_t i = 1; i < n; i++)
        if (p->phi[i] != p->phi[0]) M->phi0 = 0.0;
    M->alpha = p->alpha;
    M->scheme = p->scheme;
    M->energy = p->account_energy;
    M->damped = p->c_end != 0.0;
    double kmax = 0.0, cmax = 0.0;
    for (size_t i = 0; i < n; i++) {
        const double kr = (i + 1 < n) ? p->k[i + 1] : p->k_end, cr = (i + 1 < n) ? p->c[i + 1] : p->c_end;
        M->m[i] = p->m[i];
        M->Pc[i] = p->P0[i] * dfo_cos(p->phi[i] - M->phi0);
        M->Ps[i] = (M->phi0 == p->phi[i]) ? 0.0 : p->P0[i] * dfo_sin(p->phi[i]);
        M->P0[i] = p->P0[i];
        M->phi[i] = p->phi[i];
        M->N[i] = p->N[i];
        M->mu_s[i] = p->mu_s[i];
        M->mu_k[i] = p->chi[i] * p->mu_s[i];
        M->mu_b[i] = fmax(p->mu_s[i], M->mu_k[i]);
        M->x0[i] = p->x0[i];
        M->v0[i] = p->v0[i];
        M->Kd[i] = p->k[i] + kr;
        M->Cd[i] = p->c[i] + cr;
        /* site springs and dampers only when set (no + 0.0) */
        M->ks[i] = p->k_site ? p->k_site[i] : 0.0;
        if (M->ks[i] != 0.0) M->Kd[i] += M->ks[i];
        M->cs[i] = p->c_site ? p->c_site[i] : 0.0;
        if (M->cs[i] != 0.0) { M->Cd[i] += M->cs[i]; M->damped = 1; }
        M->Ko[i] = (i + 1 < n) ? -kr : 0.0;
        M->Co[i] = (i + 1 < n) ? -cr : 0.0;
        if (p->c[i] != 0.0) M->damped = 1;
    }
    gershgorin(p, &kmax, &cmax);
    M->rate_max = sqrt(kmax) + cmax + fabs(p->omega);
    M->T_min = shortest_period(kmax, cmax, p->omega);
    const char *why = NULL;
    M->E = make_engine(M, &why);
    if (!M->E) {
        chain_destroy(M);
        if (err) *err = why ? why : oom;
        return NULL;
    }
    if (err) *err = NULL;
    return M;
}

double chain_shortest_period(const chain_model *M) { return M->T_min; }

double chain_step(const chain_model *M) { return M->h; }

double chain_shortest_period_of(const chain_params *p)
{
    double kmax, cmax;
    gershgorin(p, &kmax, &cmax);
    return shortest_period(kmax, cmax, p->omega);
}

double chain_step_size(const chain_params *p)
{
    return p->h > 0.0 ? p->h : dfo_step_rule(0.0, chain_shortest_period_of(p));
}

void chain_destroy(chain_model *M)
{
    if (!M) return;
    const chain_alloc al = M->al;
    if (M->E) eng_destroy(M->E);
    al.release(al.env, M->m);
    al.release(al.env, M->iblk);
    al.release(al.env, M->rows);
    al.release(al.env, M->ridx);
    al.release(al.env, M->ops.rr);
    if (M->law) al.release(al.env, M->law);
    al.release(al.env, M);
}

size_t chain_size(const chain_model *M) { return M->n; }

int chain_state_init(const chain_model *M, chain_state *s) { return chain_state_alloc(&M->al, M->n, s); }

void chain_state_free(const chain_model *M, chain_state *s) { chain_state_release(&M->al, s); }

void chain_state_copy(chain_state *dst, const chain_state *src) { eng_state_copy(dst, src); }

double chain_energy(const chain_model *M, const chain_state *s)
{
    double E = 0.0;
    for (size_t i = 0; i < M->n; i++) {
        const double ext = s->X[i] - (i > 0 ? s->X[i - 1] : 0.0);
        const double kl = (M->Kd[i] - M->ks[i]) + ((i + 1 < M->n) ? M->Ko[i] : -M->k_end);
        E += 0.5 * M->m[i] * s->V[i] * s->V[i] + 0.5 * kl * ext * ext;
        if (M->ks[i] != 0.0) E += 0.5 * M->ks[i] * s->X[i] * s->X[i];
    }
    E += 0.5 * M->k_end * s->X[M->n - 1] * s->X[M->n - 1];
    return E;
}

const char *chain_status_text(chain_status st)
{
    switch (st) {
    case CHAIN_OK: return "ok";
    case CHAIN_ERR_LCP: return "the chain's friction LCP could not be solved (pivot budget)";
    case CHAIN_ERR_NO_PROGRESS: return "too many stick/slip switches inside one internal step";
    case CHAIN_ERR_NONFINITE: return "the state became non-finite (overflow)";
    case CHAIN_ERR_RESOLUTION: return "the internal step h is below the time resolution at this time";
    case CHAIN_SWITCHED: return "stopped at a switch";
    case CHAIN_ERR_FRICTION:
        return "the speed-dependent friction's implicit solve did not converge (the step does not resolve the "
               "friction's fall: a smaller h, or a larger v_s)";
    }
    return "unknown status";
}

int chain_state_alloc(const chain_alloc *al, size_t n, chain_state *s)
{
    const eng_alloc ea = {eng_calloc, eng_free, (void *)al};
    if (!eng_state_alloc(&ea, n, n, 0, s)) return 0;
    s->exc_n = -1;
    return 1;
}

void chain_state_release(const chain_alloc *al, chain_state *s)
{
    const eng_alloc ea = {eng_calloc, eng_free, (void *)al};
    eng_state_release(&ea, s);
}
