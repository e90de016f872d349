/* The friction engine's set-up and memory: eng_check_setup, eng_create, the state's arrays, the
 * status texts. See engine.h and method.md sections 2-4, 8, 9, 12 and 13.
 *
 * The schemes themselves are engine_step.h, a template over the model's operators: engine_generic.c
 * instantiates it with the operators through eng_ops's function pointers (eng_advance, ...); a
 * model may instantiate it with its own inline operators instead (models/oscillator/osc_engine.c,
 * models/chain/chain_engine.c), and then needs only this file of the engine. engine_step.h's
 * functions, in order:
 *   small algebra        dot products over contact rows, a dense Cholesky with dependent rows
 *   loads and forces     loads_at (inputs at t, ramps), exc_at (the grid cache), slip, factor_slot
 *   constrained solves   csolve: A y = r + W_S' f_S with W_S y = target_S (basis solves, physical
 *                        accelerations and jerks, holding forces); held_solve: the mass slot's, through
 *                        the model's friction solver where it offers it (eng_sparse.held_basis)
 *   dense friction       eng_dense_friction: basis solve, Stribeck's Newton, Lemke on the 2 nc LCP
 *   the trial step       trial (M_hat, the re-based A0, x_pred, p_hat), solve_trial, finish
 *   switches             rest_decide (the rest rule of the contacts at rest together), restart
 *   schemes              step_lcp (paper, consistent), step_located (the earliest switch, split),
 *                        with the model's fused step (held_step), its closed-form breakaways
 *                        (closed_breakaways) and spans (step_spans: a sub-engine steps each span, its
 *                        ghosts interpolated: ghost_at, ghosts_now), where eng_sparse offers them
 *   driving              eng_start, eng_advance, eng_new_inputs, outputs
 *
 * Every value one function hands another passes as an argument or through the state; the engine's
 * arrays are workspace, filled and read within one public call (loads_at fills the loads at the
 * start of each call from the inputs it is given). */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "engine_private.h"

/* ---- setup and memory ------------------------------------------------------------------------ */

static void *alloc_n(const eng_alloc *al, size_t n, size_t size) { return al->allocate(al->env, n ? n : 1, size); }

const char *eng_check_setup(const eng_setup *S, char *buf, size_t len)
{
    if (S->n < 1) { snprintf(buf, len, "invalid number of degrees of freedom %zu (valid: >= 1)", S->n); return buf; }
    if (!S->ops.apply_K || !S->ops.apply_M || !S->ops.factor || !S->ops.solve) {
        snprintf(buf, len, "the model's operators are incomplete (apply_K, apply_M, factor and solve are needed)");
        return buf;
    }
    if (!(S->h > 0.0) || !isfinite(S->h)) {
        snprintf(buf, len, "invalid step h = %g (valid: > 0, finite)", S->h);
        return buf;
    }
    if (!(S->alpha >= -1.0 / 3.0 && S->alpha <= 0.0)) {
        snprintf(buf, len, "invalid Bossak parameter alpha = %g (valid: -1/3 ... 0)", S->alpha);
        return buf;
    }
    if (S->scheme < DFO_SCHEME_PAPER || S->scheme > DFO_SCHEME_LOCATED) {
        snprintf(buf, len, "invalid scheme %d (valid: 1 paper, 2 consistent, 3 located)", S->scheme);
        return buf;
    }
    if (S->friction_updates < 0) {
        snprintf(buf, len, "invalid friction_updates %d (valid: >= 0)", S->friction_updates);
        return buf;
    }
    if (S->nc > 0 && (!S->rows || !S->N || !S->mu_s || !S->mu_k)) {
        snprintf(buf, len, "%zu contacts without their rows, normal forces or coefficients", S->nc);
        return buf;
    }
    for (size_t j = 0; j < S->nc; j++) {
        const eng_row *R = &S->rows[j];
        if (R->nnz < 1) { snprintf(buf, len, "contact %zu has an empty row", j + 1); return buf; }
        for (size_t k = 0; k < R->nnz; k++)
            if (R->idx[k] >= S->n || !isfinite(R->w[k])) {
                snprintf(buf, len, "contact %zu: invalid entry %zu of its row (DOF %zu, weight %g)", j + 1, k + 1,
                         R->idx[k] + 1, R->w[k]);
                return buf;
            }
        if (S->k_t && !(S->k_t[j] >= 0.0 && S->k_t[j] < INFINITY)) {
            snprintf(buf, len, "contact %zu: invalid tangential stiffness k_t %g (valid: >= 0, finite)", j + 1,
                     S->k_t[j]);
            return buf;
        }
        if (S->k_t && S->k_t[j] > 0.0 && S->law && S->law[j].law == DFO_LAW_STRIBECK) {
            snprintf(buf, len, "contact %zu: a Jenkins contact (k_t > 0) takes the Coulomb law only", j + 1);
            return buf;
        }
        if (!(S->N[j] >= 0.0) || !(S->mu_s[j] >= 0.0) || !(S->mu_k[j] >= 0.0)) {
            snprintf(buf, len, "contact %zu: invalid N %g, mu_s %g or mu_k %g (valid: >= 0)", j + 1, S->N[j],
                     S->mu_s[j], S->mu_k[j]);
            return buf;
        }
    }
    if (S->tangent) {
        int strib = 0;
        for (size_t j = 0; j < S->nc; j++) strib |= S->law && S->law[j].law == DFO_LAW_STRIBECK;
        if (S->scheme != DFO_SCHEME_LOCATED || strib || S->ops.friction || S->ops.breakaway || S->sparse) {
            snprintf(buf, len, "the map's tangent is propagated by the located scheme with the Coulomb law and the "
                               "engine's default friction solver only (scheme %d%s%s)", S->scheme,
                     strib ? ", a Stribeck contact" : "", (S->ops.friction || S->sparse) ? ", a model solver" : "");
            return buf;
        }
    }
    int jenk = 0;
    for (size_t j = 0; j < S->nc; j++) jenk |= S->k_t && S->k_t[j] > 0.0;
    if (jenk && (S->ops.friction || S->ops.breakaway || S->sparse)) {
        snprintf(buf, len, "Jenkins contacts (k_t > 0) need the engine's default friction solver (no model solver, "
                           "breakaway or sparse operators)");
        return buf;
    }
    return NULL;
}

void eng_destroy(eng *E)
{
    if (!E) return;
    void *const ptrs[] = {E->mu_b, E->u, E->Nn, E->mukN, E->Fb, E->mlN, E->zero_nc, E->A0, E->xp, E->ph,
                          E->V1, E->r, E->y, E->y2, E->X0, E->V0, E->acc, E->jk, E->rb, E->lim, E->f, E->f2, E->st,
                          E->cand, E->held, E->st2, E->mode0, E->frozen, E->tmode, E->ccol, E->cok, (void *)E->colp,
                          E->D, E->Lc, E->rhs, E->sol,
                          E->Dinv, E->gDinv, E->gd_cv, E->gd_sel, E->lM, E->lq, E->lz, E->lw, E->zb, E->guess, E->sel, E->Jn, E->res, E->sX, E->sV,
                          E->sA, E->shA, E->sF, E->smode, E->pin, E->rpin, E->hlim, E->hf, E->hmode, E->tbk,
                          E->dlab, E->clab, E->lgh, E->ldof, E->lct, E->lidx, E->gmap, E->drng, E->crng, E->lrows, E->lrw, E->lN,
                          E->lmus, E->lmuk, E->lPc, E->lPs, E->lF, E->lNe, E->lvb, E->llaw, E->ghost, E->gX0, E->gV0, E->gX1,
                          E->gV1, E->gidx, E->gve, E->ew, E->vbj, E->comp, E->jstop, E->jf0, E->rel};
    for (size_t i = 0; i < sizeof ptrs / sizeof ptrs[0]; i++)
        if (ptrs[i]) E->al.release(E->al.env, ptrs[i]);
    void *const tptrs[] = {E->tg2, E->th, E->tdh, E->tdf, E->tjk, E->tw1, E->tw2, E->tw3, E->tw4, E->tw5, E->tMV,
                           E->tKV, E->trate, E->trate2, E->trhs, E->tsol, E->tfh, E->ttgt, E->tcomp, E->theld, E->trb,
                           E->tset[0].sel, E->tset[0].dep, E->tset[0].D, E->tset[0].L, (void *)E->tset[0].col,
                           E->tset[1].sel, E->tset[1].dep, E->tset[1].D, E->tset[1].L, (void *)E->tset[1].col};
    for (size_t i = 0; i < sizeof tptrs / sizeof tptrs[0]; i++)
        if (tptrs[i]) E->al.release(E->al.env, tptrs[i]);
    if (E->ps.X || E->ps.mode) eng_state_free(E, &E->ps);
    if (E->sub) {
        eng_state_free(E->sub, &E->ss);
        eng_destroy(E->sub);
    }
    const lcp_alloc la = {E->al.allocate, E->al.release, E->al.env};
    lcp_workspace_free(E->ws, &la);
    E->al.release(E->al.env, E);
}

/* The spans' sub-engine (eng_sparse.span) and the parent's arrays for them: the sub-engine is made
 * for span_max DOFs and contacts with placeholder rows (contact j on DOF j), then set to each span
 * in turn by the located scheme (engine_step.h's step_spans). 0 on a failed allocation. */
static int create_spans(eng *E, const char **err)
{
    const eng_setup *S = &E->S;
    const eng_alloc *al = &E->al;
    const size_t n = S->n, nc = S->nc, L = S->sparse->span_max;
    size_t nnz = 1;
    for (size_t j = 0; j < nc; j++) nnz = (S->rows[j].nnz > nnz) ? S->rows[j].nnz : nnz;
    int ok = 1;
    ok &= (E->dlab = (int *)alloc_n(al, n, sizeof(int))) != NULL;
    ok &= (E->clab = (int *)alloc_n(al, nc, sizeof(int))) != NULL;
    ok &= (E->gmap = (long *)alloc_n(al, n, sizeof(long))) != NULL;
    ok &= (E->drng = (size_t *)alloc_n(al, 2 * n, sizeof(size_t))) != NULL; /* (spans: at most n) */
    ok &= (E->crng = (size_t *)alloc_n(al, 2 * n, sizeof(size_t))) != NULL;
    ok &= (E->lgh = (int *)alloc_n(al, L, sizeof(int))) != NULL;
    ok &= (E->ldof = (size_t *)alloc_n(al, L, sizeof(size_t))) != NULL;
    ok &= (E->lct = (size_t *)alloc_n(al, L, sizeof(size_t))) != NULL;
    ok &= (E->lidx = (size_t *)alloc_n(al, L * nnz, sizeof(size_t))) != NULL;
    ok &= (E->lrw = (double *)alloc_n(al, L * nnz, sizeof(double))) != NULL;
    ok &= (E->lrows = (eng_row *)alloc_n(al, L, sizeof(eng_row))) != NULL;
    double **dl[] = {&E->lN, &E->lmus, &E->lmuk, &E->lPc, &E->lPs, &E->lF, &E->lNe, &E->lvb};
    for (size_t i = 0; i < sizeof dl / sizeof dl[0]; i++) ok &= (*dl[i] = (double *)alloc_n(al, L, sizeof(double))) != NULL;
    if (S->law) ok &= (E->llaw = (dfo_friction_law *)alloc_n(al, L, sizeof(dfo_friction_law))) != NULL;
    ok &= eng_state_init(E, &E->ps, 0);
    if (!ok) { if (err) *err = "out of memory"; return 0; }
    E->lnnz = nnz;
    for (size_t j = 0; j < L; j++) {
        E->lidx[j * nnz] = j;
        E->lrw[j * nnz] = 1.0;
        E->lrows[j].nnz = 1;
        E->lrows[j].idx = &E->lidx[j * nnz];
        E->lrows[j].w = &E->lrw[j * nnz];
    }
    eng_setup T = *S;
    T.n = T.nc = L;
    T.ops = S->sparse->span_ops;
    E->sub_sparse.held_basis = 1;
    T.sparse = &E->sub_sparse;
    T.coupling = NULL; /* (the span's operators are its own) */
    T.rows = E->lrows;
    T.N = E->lN;
    T.mu_s = E->lmus;
    T.mu_k = E->lmuk;
    T.law = S->law ? E->llaw : NULL;
    T.exc.Pc = S->exc.Pc ? E->lPc : NULL;
    T.exc.Ps = S->exc.Ps ? E->lPs : NULL;
    E->sub = eng_create(&T, al, err);
    if (!E->sub || !eng_state_init(E->sub, &E->ss, 0)) { if (err) *err = "out of memory"; return 0; }
    eng *B = E->sub;
    double **dg[] = {&B->gX0, &B->gV0, &B->gX1, &B->gV1, &B->gve};
    for (size_t i = 0; i < sizeof dg / sizeof dg[0]; i++) ok &= (*dg[i] = (double *)alloc_n(al, L, sizeof(double))) != NULL;
    ok &= (B->ghost = (int *)alloc_n(al, L, sizeof(int))) != NULL;
    ok &= (B->gidx = (size_t *)alloc_n(al, L, sizeof(size_t))) != NULL;
    if (!ok) { if (err) *err = "out of memory"; return 0; }
    return 1;
}

eng *eng_create(const eng_setup *S, const eng_alloc *al, const char **err)
{
    static const char *const oom = "out of memory";
    char buf[1];
    if (eng_check_setup(S, buf, sizeof buf)) {
        if (err) *err = "invalid engine setup (eng_check_setup says which field)";
        return NULL;
    }
    eng *E = (eng *)al->allocate(al->env, 1, sizeof *E);
    if (!E) { if (err) *err = oom; return NULL; }
    E->S = *S;
    E->al = *al;
    const size_t n = S->n, nc = S->nc, nn = nc * nc;
    E->g = dfo_bossak_gamma(S->alpha);
    E->b = dfo_bossak_beta(S->alpha);
    E->g1 = (1.0 - E->g) / E->g;
    double **dn[] = {&E->u, &E->A0, &E->xp, &E->ph, &E->V1, &E->r, &E->y, &E->y2, &E->X0, &E->V0, &E->acc, &E->jk, &E->rb,
                     &E->sX, &E->sV, &E->sA, &E->shA};
    double **dc[] = {&E->mu_b, &E->Nn, &E->mukN, &E->Fb, &E->mlN, &E->zero_nc, &E->lim, &E->f, &E->f2,
                     &E->rhs, &E->sol, &E->res, &E->sF, &E->hlim, &E->hf, &E->tbk};
    int **ic[] = {&E->st, &E->cand, &E->held, &E->st2, &E->mode0, &E->frozen, &E->tmode, &E->sel, &E->smode, &E->hmode};
    int ok = 1;
    for (size_t i = 0; i < sizeof dn / sizeof dn[0]; i++)
        ok &= (*dn[i] = (double *)alloc_n(al, n, sizeof(double))) != NULL;
    for (size_t i = 0; i < sizeof dc / sizeof dc[0]; i++)
        ok &= (*dc[i] = (double *)alloc_n(al, nc, sizeof(double))) != NULL;
    for (size_t i = 0; i < sizeof ic / sizeof ic[0]; i++) ok &= (*ic[i] = (int *)alloc_n(al, nc, sizeof(int))) != NULL;
    ok &= (E->pin = (int *)alloc_n(al, n, sizeof(int))) != NULL;
    ok &= (E->vbj = (double *)alloc_n(al, nc, sizeof(double))) != NULL;
    ok &= (E->comp = (double *)alloc_n(al, nc, sizeof(double))) != NULL;
    ok &= (E->jstop = (int *)alloc_n(al, nc, sizeof(int))) != NULL;
    ok &= (E->jf0 = (double *)alloc_n(al, nc, sizeof(double))) != NULL;
    ok &= (E->rel = (eng_release *)alloc_n(al, nc, sizeof(eng_release))) != NULL;
    ok &= (E->rpin = (int *)alloc_n(al, n, sizeof(int))) != NULL;
    E->rpin_ok = 0;
    if (S->account_energy) ok &= (E->ew = (double *)alloc_n(al, 3 * n, sizeof(double))) != NULL;
    /* the dense friction solver's workspace, O(n nc + nc^2): only where it may run (no model solver, or
     * one that falls back on it) */
    const int dense = !S->ops.friction || S->ops.dense_fallback || !(S->sparse && S->sparse->held_basis);
    const size_t dnc = dense ? nc : 0, dnn = dense ? nn : 0;
    ok &= (E->ccol = (double *)alloc_n(al, ENG_NSLOTS * n * dnc, sizeof(double))) != NULL;
    ok &= (E->cok = (int *)alloc_n(al, ENG_NSLOTS * nc, sizeof(int))) != NULL;
    ok &= (E->colp = (const double **)alloc_n(al, nc, sizeof(double *))) != NULL;
    ok &= (E->D = (double *)alloc_n(al, dnn, sizeof(double))) != NULL;
    ok &= (E->Lc = (double *)alloc_n(al, dnn, sizeof(double))) != NULL;
    ok &= (E->Dinv = (double *)alloc_n(al, dnn, sizeof(double))) != NULL;
    ok &= (E->gDinv = (double *)alloc_n(al, dnn, sizeof(double))) != NULL;
    ok &= (E->gd_cv = (double *)alloc_n(al, nc, sizeof(double))) != NULL;
    ok &= (E->gd_sel = (int *)alloc_n(al, nc, sizeof(int))) != NULL;
    E->gd_ok = 0;
    ok &= (E->Jn = (double *)alloc_n(al, dnn, sizeof(double))) != NULL;
    ok &= (E->lM = (double *)alloc_n(al, 4 * dnn, sizeof(double))) != NULL;
    ok &= (E->lq = (double *)alloc_n(al, 2 * nc, sizeof(double))) != NULL;
    ok &= (E->lz = (double *)alloc_n(al, 2 * nc, sizeof(double))) != NULL;
    ok &= (E->lw = (double *)alloc_n(al, 2 * nc, sizeof(double))) != NULL;
    ok &= (E->zb = (int *)alloc_n(al, 2 * nc, sizeof(int))) != NULL;
    ok &= (E->guess = (int *)alloc_n(al, 2 * nc, sizeof(int))) != NULL;
    if (dnc > 0) {
        const lcp_alloc la = {al->allocate, al->release, al->env};
        ok &= (E->ws = lcp_workspace_create((int)(2 * nc), &la)) != NULL;
    }
    if (S->tangent) { /* the located map's tangent (engine_tangent.h) */
        const size_t nz = 2 * n + nc, L = 4 * n + nc + 1;
        double **tn[] = {&E->tw1, &E->tw2, &E->tw3, &E->tw4, &E->tw5, &E->tMV, &E->tKV, &E->trate, &E->trate2};
        double **tc[] = {&E->tdf, &E->trhs, &E->tsol, &E->tfh, &E->ttgt, &E->tcomp};
        for (size_t i = 0; i < sizeof tn / sizeof tn[0]; i++) ok &= (*tn[i] = (double *)alloc_n(al, n, sizeof(double))) != NULL;
        for (size_t i = 0; i < sizeof tc / sizeof tc[0]; i++) ok &= (*tc[i] = (double *)alloc_n(al, nc, sizeof(double))) != NULL;
        ok &= (E->tg2 = (double *)alloc_n(al, nz * L, sizeof(double))) != NULL;
        ok &= (E->th = (double *)alloc_n(al, L, sizeof(double))) != NULL;
        ok &= (E->tdh = (double *)alloc_n(al, nz, sizeof(double))) != NULL;
        ok &= (E->tjk = (double *)alloc_n(al, nz * n, sizeof(double))) != NULL;
        ok &= (E->theld = (int *)alloc_n(al, nc, sizeof(int))) != NULL;
        ok &= (E->trb = (int *)alloc_n(al, n, sizeof(int))) != NULL;
        for (int k = 0; k < 2; k++) {
            tan_set *T = &E->tset[k];
            ok &= (T->sel = (int *)alloc_n(al, nc, sizeof(int))) != NULL;
            ok &= (T->dep = (int *)alloc_n(al, nc, sizeof(int))) != NULL;
            ok &= (T->D = (double *)alloc_n(al, nc * nc, sizeof(double))) != NULL;
            ok &= (T->L = (double *)alloc_n(al, nc * nc, sizeof(double))) != NULL;
            ok &= (T->col = (const double **)alloc_n(al, nc, sizeof(double *))) != NULL;
        }
    }
    if (!ok) {
        eng_destroy(E);
        if (err) *err = oom;
        return NULL;
    }
    E->any_law = 0;
    E->any_jenk = 0;
    for (size_t j = 0; j < nc; j++) {
        E->any_jenk |= S->k_t && S->k_t[j] > 0.0;
        E->mu_b[j] = fmax(S->mu_s[j], S->mu_k[j]);
        E->any_law |= S->law && S->law[j].law == DFO_LAW_STRIBECK;
    }
    E->vb = E->zero_nc;
    E->loads_for = NULL;
    E->pin_all = eng_pin_all(E);
    E->rest_apart = eng_rest_apart(E);
    dfo_bossak_kin_for(S->h, E->g, E->b, &E->kin_grid);
    E->rot_c = dfo_cos(S->exc.omega * S->h);
    E->rot_s = dfo_sin(S->exc.omega * S->h);
    E->trig_tc = E->trig_ts = NAN;
    const eng_sparse *sp = S->sparse;
    if (sp && sp->span && sp->span_bind && sp->span_max > 0 && sp->held_basis && S->ops.friction &&
        sp->span_ops.friction && nc > 0 &&
        !create_spans(E, err)) {
        eng_destroy(E);
        return NULL;
    }
    return E;
}

const eng_setup *eng_setup_of(const eng *E) { return &E->S; }

int eng_caps(int scheme)
{
    (void)scheme;
    return 0; /* no Bossak scheme propagates the Jacobian yet (the oscillator's exact scheme does, outside) */
}

int eng_state_alloc(const eng_alloc *al, size_t n, size_t nc, int with_jacobian, eng_state *s)
{
    memset(s, 0, sizeof *s);
    s->n = n;
    s->nc = nc;
    int ok = 1;
    ok &= (s->X = (double *)alloc_n(al, n, sizeof(double))) != NULL;
    ok &= (s->V = (double *)alloc_n(al, n, sizeof(double))) != NULL;
    ok &= (s->A = (double *)alloc_n(al, n, sizeof(double))) != NULL;
    ok &= (s->hA = (double *)alloc_n(al, n, sizeof(double))) != NULL;
    ok &= (s->F = (double *)alloc_n(al, nc, sizeof(double))) != NULL;
    ok &= (s->slider = (double *)alloc_n(al, nc, sizeof(double))) != NULL;
    ok &= (s->mode = (int *)alloc_n(al, nc, sizeof(int))) != NULL;
    ok &= (s->t_stick = (double *)alloc_n(al, nc, sizeof(double))) != NULL;
    ok &= (s->t_break = (double *)alloc_n(al, nc, sizeof(double))) != NULL;
    ok &= (s->break_dir = (int *)alloc_n(al, nc, sizeof(int))) != NULL;
    if (with_jacobian) ok &= (s->J = (double *)alloc_n(al, 4 * n * n, sizeof(double))) != NULL;
    if (with_jacobian & 2) ok &= (s->tan = (double *)alloc_n(al, eng_tan_size(n, nc), sizeof(double))) != NULL;
    if (!ok) eng_state_release(al, s);
    return ok;
}

int eng_jacobian(const eng_state *s, double *J)
{
    if (!s->tan || s->tan_lost) return 0;
    const size_t n = s->n, nc = s->nc, nz = 2 * n + nc, L = 4 * n + nc + 1;
    for (size_t c = 0; c < nz; c++) {
        const double *T = s->tan + c * L;
        for (size_t i = 0; i < 2 * n; i++) J[i * nz + c] = T[i];
        for (size_t j = 0; j < nc; j++) J[(2 * n + j) * nz + c] = T[4 * n + j];
    }
    return 1;
}

void eng_state_release(const eng_alloc *al, eng_state *s)
{
    void *const ptrs[] = {s->X,    s->V,       s->A,       s->hA,         s->F, s->slider,
                          s->mode, s->t_stick, s->t_break, s->break_dir, s->J, s->tan};
    for (size_t i = 0; i < sizeof ptrs / sizeof ptrs[0]; i++)
        if (ptrs[i]) al->release(al->env, ptrs[i]);
    memset(s, 0, sizeof *s);
}

int eng_state_init(const eng *E, eng_state *s, int with_jacobian)
{
    return eng_state_alloc(&E->al, E->S.n, E->S.nc, with_jacobian | (E->S.tangent ? 2 : 0), s);
}

void eng_state_free(const eng *E, eng_state *s) { eng_state_release(&E->al, s); }

void eng_state_copy(eng_state *dst, const eng_state *src)
{
    const size_t n = src->n, nc = src->nc;
    eng_state d = *src;
    d.X = dst->X; d.V = dst->V; d.A = dst->A; d.hA = dst->hA; d.F = dst->F; d.slider = dst->slider; d.mode = dst->mode;
    d.t_stick = dst->t_stick; d.t_break = dst->t_break; d.break_dir = dst->break_dir; d.J = dst->J;
    d.tan = dst->tan;
    memcpy(d.X, src->X, n * sizeof(double));
    memcpy(d.V, src->V, n * sizeof(double));
    memcpy(d.A, src->A, n * sizeof(double));
    memcpy(d.hA, src->hA, n * sizeof(double));
    if (nc) {
        memcpy(d.F, src->F, nc * sizeof(double));
        memcpy(d.slider, src->slider, nc * sizeof(double));
        memcpy(d.mode, src->mode, nc * sizeof(int));
        memcpy(d.t_stick, src->t_stick, nc * sizeof(double));
        memcpy(d.t_break, src->t_break, nc * sizeof(double));
        memcpy(d.break_dir, src->break_dir, nc * sizeof(int));
    }
    if (d.J && src->J) memcpy(d.J, src->J, 4 * n * n * sizeof(double));
    if (d.tan && src->tan) memcpy(d.tan, src->tan, eng_tan_size(n, nc) * sizeof(double));
    else if (d.tan) d.tan_lost = 1; /* (a tangent not carried over: not computed) */
    *dst = d;
}

const char *eng_status_text(eng_status st)
{
    switch (st) {
    case ENG_OK: return "ok";
    case ENG_ERR_LCP: return "the friction problem could not be solved";
    case ENG_ERR_NO_PROGRESS: return "too many stick/slip switches inside one internal step";
    case ENG_ERR_NONFINITE: return "the state became non-finite (overflow)";
    case ENG_ERR_RESOLUTION: return "the internal step h is below the time resolution at this time";
    case ENG_SWITCHED: return "stopped at a switch";
    case ENG_ERR_FRICTION: return "the speed-dependent friction's implicit solve did not converge";
    case ENG_ERR_BAD_INPUT: return "the step matrix is not positive definite or an argument is out of range";
    }
    return "unknown status";
}
