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
    /* one block of doubles for all per-block arrays (42 of n, then fw and box of 2n), one for
     * the ints, one for the candidates and clusters */
    enum { NARR = 42 };
    double *blk = dalloc(al, (NARR + 4) * n); /* and fw, box: 2n each */
    int *iblk = (int *)al->allocate(al->env, 3 * n, sizeof(int));
    M->cand = (size_t *)al->allocate(al->env, 3 * n, sizeof(size_t));
    M->rows = (fast_row *)al->allocate(al->env, n, sizeof(fast_row));
    if (!blk || !iblk || !M->cand || !M->rows) {
        if (blk) al->release(al->env, blk);
        if (iblk) al->release(al->env, iblk);
        if (M->cand) al->release(al->env, M->cand);
        if (M->rows) al->release(al->env, M->rows);
        al->release(al->env, M);
        if (err) *err = oom;
        return NULL;
    }
    double **arr[NARR] = {&M->m, &M->am, &M->am1, &M->Pc, &M->Ps, &M->P0, &M->phi, &M->N, &M->mu_k, &M->mu_b,
                          &M->x0, &M->v0,
                          &M->Kd, &M->Ko, &M->Cd, &M->Co, &M->dF, &M->eF, &M->d, &M->e, &M->A0, &M->xp,
                          &M->q,  &M->Vt, &M->Ft, &M->cp, &M->dp, &M->u, &M->mukN, &M->Fb, &M->S, &M->l,
                          &M->sX, &M->sV, &M->sA, &M->sF, &M->shA, &M->J, &M->ks, &M->cs,
                          &M->Nn, &M->mlN};
    for (int j = 0; j < NARR; j++) *arr[j] = blk + (size_t)j * n;
    M->fw = blk + (size_t)NARR * n;
    M->box = blk + (size_t)(NARR + 2) * n;
    M->frozen = iblk;
    M->st = iblk + n;
    M->smode = iblk + 2 * n;
    M->clu = M->cand + n;
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
    M->rot_c = dfo_cos(p->omega * p->h);
    M->rot_s = dfo_sin(p->omega * p->h);
    M->phi0 = p->phi[0];
    for (size_t i = 1; i < n; i++)
        if (p->phi[i] != p->phi[0]) M->phi0 = 0.0;
    M->alpha = p->alpha;
    M->gamma = dfo_bossak_gamma(p->alpha);
    M->beta = dfo_bossak_beta(p->alpha);
    M->g1 = (1.0 - M->gamma) / M->gamma;
    M->scheme = p->scheme;
    M->energy = p->account_energy;
    M->damped = p->c_end != 0.0;
    double kmax = 0.0, cmax = 0.0;
    for (size_t i = 0; i < n; i++) {
        const double kr = (i + 1 < n) ? p->k[i + 1] : p->k_end, cr = (i + 1 < n) ? p->c[i + 1] : p->c_end;
        M->m[i] = p->m[i];
        M->am[i] = p->alpha * p->m[i];
        M->am1[i] = (1.0 - p->alpha) * p->m[i];
        M->Pc[i] = p->P0[i] * dfo_cos(p->phi[i] - M->phi0);
        M->Ps[i] = (M->phi0 == p->phi[i]) ? 0.0 : p->P0[i] * dfo_sin(p->phi[i]);
        M->P0[i] = p->P0[i];
        M->phi[i] = p->phi[i];
        M->N[i] = p->N[i];
        M->mu_k[i] = p->chi[i] * p->mu_s[i];
        M->mu_b[i] = fmax(p->mu_s[i], M->mu_k[i]);
        M->x0[i] = p->x0[i];
        M->v0[i] = p->v0[i];
        M->Kd[i] = p->k[i] + kr;
        M->Cd[i] = p->c[i] + cr;
        /* site springs and dampers only when set (else today's bits: no + 0.0) */
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
    dfo_bossak_kin_for(p->h, M->gamma, M->beta, &M->kinF);
    M->kin = M->kinF;
    const double c1 = M->kin.c1, bhg = M->beta * p->h / M->gamma;
    for (size_t i = 0; i < n; i++) {
        /* (k b) h / g, associated as the oscillator's m_hat (n = 1 gives its bits there) */
        M->dF[i] = M->am1[i] * c1 + M->Kd[i] * M->beta * p->h / M->gamma + M->Cd[i];
        M->eF[i] = M->Ko[i] * bhg + M->Co[i];
    }
    for (size_t i = 0; i < n; i++) {
        fast_row *R = &M->rows[i];
        R->Pc = M->Pc[i]; R->Ps = M->Ps[i]; R->am = M->am[i]; R->am1 = M->am1[i];
        R->Kd = M->Kd[i]; R->Ko = M->Ko[i]; R->d = M->dF[i]; R->e = M->eF[i];
        R->u = R->Fb = R->mukN = 0.0;  /* (chain_loads_init) */
        R->fh = 0;
    }
    /* beyond w blocks the influence of a block inside one step is below 2^-56 (bossak.h's
     * dfo_bossak_reach), rho the largest ratio of a row's off-diagonal sum to its diagonal (shorter
     * steps: smaller) */
    double rho = 0.0;
    for (size_t i = 0; i < n; i++) rho = fmax(rho, (fabs(i > 0 ? M->eF[i - 1] : 0.0) + fabs(M->eF[i])) / M->dF[i]);
    M->w = dfo_bossak_reach(rho, n);
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
    al.release(al.env, M->m);
    al.release(al.env, M->frozen);
    al.release(al.env, M->cand);
    al.release(al.env, M->rows);
    if (M->law) al.release(al.env, M->law);
    al.release(al.env, M);
}

size_t chain_size(const chain_model *M) { return M->n; }

int chain_state_init(const chain_model *M, chain_state *s) { return chain_state_alloc(&M->al, M->n, s); }

void chain_state_free(const chain_model *M, chain_state *s) { chain_state_release(&M->al, s); }

void chain_state_copy(chain_state *dst, const chain_state *src)
{
    double *X = dst->X, *V = dst->V, *A = dst->A, *F = dst->F, *hA = dst->hA, *ts = dst->t_stick;
    int *mode = dst->mode;
    const size_t n = src->n;
    *dst = *src;
    dst->X = X; dst->V = V; dst->A = A; dst->F = F; dst->hA = hA; dst->t_stick = ts; dst->mode = mode;
    memcpy(hA, src->hA, n * sizeof *hA);
    memcpy(ts, src->t_stick, n * sizeof *ts);
    memcpy(X, src->X, n * sizeof *X);
    memcpy(V, src->V, n * sizeof *V);
    memcpy(A, src->A, n * sizeof *A);
    memcpy(F, src->F, n * sizeof *F);
    memcpy(mode, src->mode, n * sizeof *mode);
}

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
    memset(s, 0, sizeof *s);
    s->n = n;
    double *b = dalloc(al, 6 * n);
    int *mode = (int *)al->allocate(al->env, n, sizeof(int));
    if (!b || !mode) {
        if (b) al->release(al->env, b);
        if (mode) al->release(al->env, mode);
        return 0;
    }
    s->X = b;
    s->V = b + n;
    s->A = b + 2 * n;
    s->F = b + 3 * n;
    s->hA = b + 4 * n;
    s->t_stick = b + 5 * n;
    s->mode = mode;
    s->exc_n = -1;
    return 1;
}

void chain_state_release(const chain_alloc *al, chain_state *s)
{
    if (s->X) al->release(al->env, s->X);
    if (s->mode) al->release(al->env, s->mode);
    s->X = s->V = s->A = s->F = s->hA = s->t_stick = NULL;
    s->mode = NULL;
}
