/* The two structures of bench_engine as engine models (fmu_src/engine): their operators as static
 * inline functions, used both through eng_ops's function pointers (engine.c's schemes) and inlined
 * into the schemes of engine_step.h (models/oscillator/osc_engine.c, engine_chain.c), so that the two builds of the
 * schemes run the same arithmetic and differ only in how the operators are reached.
 *
 *   block: the oscillator's operators (models/oscillator/osc_engine_ops.h: osc_eng_model, osc_K, ...):
 *          one mass on a spring and a damper, M_hat and the friction problem of its contact scalar;
 *   chain: n masses in a row between two walls (springs k_i from block i - 1 or the left wall to
 *          block i, k_end to the right wall, no dampers), contact i on block i: M_hat tridiagonal
 *          (Thomas), the friction problem the box LCP of numerics/lcp.h. */
#ifndef DFO_BENCH_ENGINE_MODELS_H
#define DFO_BENCH_ENGINE_MODELS_H

#include "engine.h"
#include "lcp.h"
#include "osc_engine.h" /* the block: the oscillator's operators and its specialised schemes */

#include <math.h>
#include <stddef.h>

/* ---- a chain of n blocks -------------------------------------------------------------------- */

typedef struct chn_model_s {
    size_t n;
    const double *m, *k;        /* n each: masses, springs (k[i] from block i - 1 or the left wall) */
    double k_end;               /* the spring from the last block to the right wall */
    double *d[ENG_NSLOTS];      /* n each: the slot's diagonal, */
    double *e[ENG_NSLOTS];      /* its super-diagonal (e[n - 1] = 0), */
    double *cp[ENG_NSLOTS];     /* Thomas's factors: cp = e / den, */
    double *inv[ENG_NSLOTS];    /* inv = 1 / den */
    int tok[ENG_NSLOTS];        /* cp and inv are the slot's (chn_factor makes them lazily) */
    /* the slot's factorisation for the basis solves, kept for a held pattern (chn_basis_kept): per
     * row the pattern it is for (kh: 0 none yet, 1 free, 2 held), Thomas's cp and 1 / den */
    int *kh[ENG_NSLOTS];
    double *kcp[ENG_NSLOTS], *kinv[ENG_NSLOTS];
    double *q, *work;           /* n and 2 n: the box LCP's right-hand side and workspace */
    /* spans (eng_sparse): a span of the chain is a chain of its own, a view of blocks [a - 1, b] with
     * its end blocks ghosts where they are not the chain's ends (fix_lo, fix_hi: Dirichlet rows) */
    int fix_lo, fix_hi;
    size_t w;                   /* a span's reach: beyond w blocks a block's influence in one step is below
                                 * 2^-56 (chn_set_reach; 0: no spans) */
    struct chn_model_s *sub;    /* the span's view (chn_span_bind), its arrays its own */
} chn_model;

static inline double chn_kd(const chn_model *C, size_t i)
{
    return C->k[i] + ((i + 1 < C->n) ? C->k[i + 1] : C->k_end);
}

static inline void chn_K(void *ctx, const double *x, double *y)
{
    const chn_model *C = (const chn_model *)ctx;
    const size_t n = C->n;
    for (size_t i = 0; i < n; i++) {
        double s = chn_kd(C, i) * x[i];
        if (i > 0) s -= C->k[i] * x[i - 1];
        if (i + 1 < n) s -= C->k[i + 1] * x[i + 1];
        y[i] = s;
    }
}

static inline void chn_M(void *ctx, const double *a, double *y)
{
    const chn_model *C = (const chn_model *)ctx;
    for (size_t i = 0; i < C->n; i++) y[i] = C->m[i] * a[i];
}

/* Thomas's factors of the slot (cp, inv): 0 when a pivot is not positive. */
static inline int chn_thomas(chn_model *C, int slot)
{
    const double *d = C->d[slot], *e = C->e[slot];
    double *cp = C->cp[slot], *inv = C->inv[slot], prev = 0.0;
    for (size_t i = 0; i < C->n; i++) {
        const double den = d[i] - ((i > 0) ? e[i - 1] * prev : 0.0);
        if (!(den > 0.0)) return 0;
        inv[i] = 1.0 / den;
        cp[i] = e[i] * inv[i];
        prev = cp[i];
    }
    C->tok[slot] = 1;
    return 1;
}

/* M_hat of the slot; Thomas's factors (chn_solve's) made when first solved with, where M_hat is
 * strictly diagonally dominant (so positive definite: the basis solves, chn_basis_kept, factor it
 * their own way), else now. */
static inline int chn_factor(void *ctx, int slot, double cM, double cC, double cK)
{
    chn_model *C = (chn_model *)ctx;
    const size_t n = C->n;
    double *d = C->d[slot], *e = C->e[slot];
    (void)cC; /* no dampers */
    int dominant = 1;
    for (size_t i = 0; i < n; i++) {
        d[i] = cM * C->m[i] + cK * chn_kd(C, i);
        e[i] = (i + 1 < n) ? -cK * C->k[i + 1] : 0.0;
        dominant &= d[i] > fabs(e[i]) + ((i > 0) ? fabs(e[i - 1]) : 0.0);
        C->kh[slot][i] = 0; /* the kept basis factors anew */
    }
    C->tok[slot] = 0;
    return dominant || chn_thomas(C, slot);
}

static inline void chn_solve(void *ctx, int slot, const double *b, double *x)
{
    chn_model *C = (chn_model *)ctx;
    const size_t n = C->n;
    if (!C->tok[slot]) (void)chn_thomas(C, slot); /* (positive pivots: chn_factor) */
    const double *e = C->e[slot], *cp = C->cp[slot], *inv = C->inv[slot];
    double prev = 0.0;
    for (size_t i = 0; i < n; i++) {
        prev = (b[i] - ((i > 0) ? e[i - 1] * prev : 0.0)) * inv[i];
        x[i] = prev;
    }
    for (size_t i = n - 1; i-- > 0;) x[i] -= cp[i] * x[i + 1];
}

/* lcp_box_basis(0, n, 0, 0.0, 0, 0.0, d, e, q, l, mode, z, w, ...) of the slot's M_hat with its
 * factorisation kept for the held pattern (mode 0 with l > 0): the same operations, so the same
 * bits, without the divisions of the rows whose pattern is unchanged. A row is refactored when its
 * own hold changed, or when it is free and the row above was refactored (a held row starts the
 * elimination afresh: cp = 0). */
static inline void chn_basis_kept(chn_model *C, int slot, const double *q, const double *l, const int *mode,
                                  double *z, double *w)
{
    const size_t n = C->n;
    const double *d = C->d[slot], *e = C->e[slot];
    int *kh = C->kh[slot];
    double *kcp = C->kcp[slot], *kinv = C->kinv[slot], *dp = C->work;
    double cprev = 0.0, dprev = 0.0;
    int refac = 0;
    for (size_t i = 0; i < n; i++) {
        const int hold = mode[i] == 0 && l[i] > 0.0;
        if (kh[i] != 1 + hold || (refac && !hold)) {
            kh[i] = 1 + hold;
            if (hold) {
                kcp[i] = 0.0;
            } else {
                const double lo_e = (i > 0) ? e[i - 1] : 0.0;
                kinv[i] = 1.0 / (d[i] - lo_e * cprev);
                kcp[i] = (i + 1 < n) ? e[i] * kinv[i] : 0.0;
            }
            refac = 1;
        } else {
            refac = 0;
        }
        double dpi = 0.0;
        if (!hold) {
            const double lo_e = (i > 0) ? e[i - 1] : 0.0;
            const double rhs = -q[i] - ((l[i] > 0.0) ? mode[i] * l[i] : 0.0);
            dpi = (rhs - lo_e * dprev) * kinv[i];
        }
        dp[i] = dpi;
        cprev = kcp[i];
        dprev = dpi;
    }
    double zn = 0.0;
    for (size_t j = n; j-- > 0;) {
        zn = dp[j] - kcp[j] * zn;
        z[j] = zn;
    }
    lcp_box_basis_w(0, n, 0, n, e, q, l, mode, z, w);
}

/* The box LCP of the slot's M_hat (W = I, no belts): lcp_box_basis in the given modes, lcp_box for
 * the LCP; z the end velocities, w the forces, q = -p_hat. (Coulomb, fixed supports only: a problem
 * with the Stribeck law or a belt is refused.) */
static inline eng_status chn_friction(void *ctx, const eng_problem *P, int what, int *mode, double *V1, double *f,
                                      int *pivots)
{
    chn_model *C = (chn_model *)ctx;
    const size_t n = C->n;
    const double *d = C->d[P->slot], *e = C->e[P->slot];
    if (P->law) return ENG_ERR_FRICTION;
    for (size_t i = 0; i < n; i++) {
        if (P->vb && P->vb[i] != 0.0) return ENG_ERR_BAD_INPUT; /* belts: not this model's */
        C->q[i] = -P->p_hat[i];
    }
    if (pivots) *pivots = 0;
    const double *l = P->limit;
    if (C->fix_lo || C->fix_hi) { /* a span: the ghosts' rows fixed at their entries of p_hat */
        if (what != ENG_SOLVE_BASIS) return ENG_ERR_BAD_INPUT;
        lcp_box_basis(0, n, C->fix_lo, P->p_hat[0], C->fix_hi, P->p_hat[n - 1], d, e, C->q, l, mode, V1, f, C->work,
                      C->work + n);
        for (size_t i = 0; i < n; i++)
            if (!(mode[i] == 0 && l[i] > 0.0)) f[i] = (l[i] > 0.0) ? -mode[i] * l[i] : 0.0;
        if (C->fix_lo) f[0] = 0.0;
        if (C->fix_hi) f[n - 1] = 0.0;
        return ENG_OK;
    }
    chn_basis_kept(C, P->slot, C->q, l, mode, V1, f);
    if (what == ENG_SOLVE_BASIS) {
        for (size_t i = 0; i < n; i++) /* a sliding row's force is its limit's (w is not set there) */
            if (!(mode[i] == 0 && l[i] > 0.0)) f[i] = (l[i] > 0.0) ? -mode[i] * l[i] : 0.0;
        return ENG_OK;
    }
    /* the warm basis: when lcp_box's first round would flip no row, its solution is this one */
    int flip = 0;
    for (size_t i = 0; i < n && !flip; i++)
        flip = l[i] > 0.0 && ((mode[i] != 0 && mode[i] * V1[i] < 0.0) || (mode[i] == 0 && f[i] > l[i]) ||
                              (mode[i] == 0 && f[i] < -l[i]));
    if (!flip) {
        for (size_t i = 0; i < n; i++)
            if (!(l[i] > 0.0)) mode[i] = (V1[i] > 0.0) - (V1[i] < 0.0);
        return ENG_OK;
    }
    return lcp_box(n, d, e, C->q, l, mode, V1, f, C->work, pivots) == LCP_OK ? ENG_OK : ENG_ERR_LCP;
}

/* The fused grid step in the held pattern (eng_sparse.step_held): x_pred and p_hat in one sweep (K's
 * row needs x_pred one block ahead), the kept basis solve, the margins, the acceptance; the
 * engine's arithmetic in its order (engine.h's eng_held_step), so the same bits. */
static inline int chn_step_held(void *ctx, const eng_held_step *F, eng_state *s)
{
    chn_model *C = (chn_model *)ctx;
    const size_t n = C->n;
    const double a = F->alpha, c1 = F->c1, g1 = F->g1, pV = F->pred_V, pA = F->pred_A;
    const double *X = s->X, *V = s->V, *A0 = F->A0;
    double *xpp = F->xp, *q = C->q, *V1 = F->V1;
    double xc = X[0] + pV * V[0] + pA * A0[0];
    for (size_t i = 0; i < n; i++) {
        const double xr = (i + 1 < n) ? X[i + 1] + pV * V[i + 1] + pA * A0[i + 1] : 0.0;
        xpp[i] = xc;
        const double r = -a * A0[i] + (1.0 - a) * (V[i] * c1 + g1 * A0[i]);
        const double y = C->m[i] * r;
        double kx = chn_kd(C, i) * xc;
        if (i > 0) kx -= C->k[i] * xpp[i - 1];
        if (i + 1 < n) kx -= C->k[i + 1] * xr;
        double p = F->u[i];
        if (F->Pc) p += F->Pc[i] * F->cw;
        if (F->Ps) p -= F->Ps[i] * F->sw;
        F->ph[i] = p + (y - kx);
        q[i] = -F->ph[i];
        xc = xr;
    }
    double *f = F->f;
    chn_basis_kept(C, F->slot, q, F->lim, F->st, V1, f);
    for (size_t j = 0; j < n; j++) {
        if (!(F->Fb[j] > 0.0)) continue;
        const double mg = (F->st[j] != 0) ? F->st[j] * ((0.0 + 1.0 * V1[j]) - 0.0) : F->Fb[j] - fabs(f[j]);
        if (mg <= 0.0) return 0;
    }
    for (size_t i = 0; i < n; i++) {
        s->X[i] = xpp[i] + F->corr_V * V1[i];
        s->A[i] = (V1[i] - s->V[i]) * c1 - g1 * A0[i];
        s->V[i] = V1[i];
        s->hA[i] = F->h;
        s->F[i] = f[i];
    }
    return 1;
}

/* Held block j's next breakaway in closed form (eng_sparse.contact_breakaway) where its neighbours
 * are held too (its static force then P_j(t) + u_j - (K x)_j with x fixed since the latest of their
 * stick phases' starts: friction.h's dfo_next_breakaway from there, as the chain's own
 * chain_block_breakaway); NaN else. */
static inline double chn_contact_breakaway(void *ctx, size_t j, const eng_harmonic *exc, const eng_state *s,
                                           const eng_inputs *in, const double *Fb)
{
    const chn_model *C = (const chn_model *)ctx;
    const size_t n = C->n;
    double ta = s->t_stick[j]; /* since when block j and its neighbours are held: its static force fixed */
    for (size_t k = (j > 0) ? j - 1 : j; k <= j + 1 && k < n; k++) {
        if (k != j && !(s->mode[k] == 0 && Fb[k] > 0.0)) return NAN;
        ta = fmax(ta, s->t_stick[k]);
    }
    const double Pc = exc->Pc ? exc->Pc[j] : 0.0, Ps = exc->Ps ? exc->Ps[j] : 0.0;
    dfo_harmonic P;
    dfo_harmonic_init(&P, hypot(Pc, Ps), exc->omega, exc->phi0 + atan2(Ps, Pc));
    const double u = (in && in->F_ext) ? in->F_ext[j] : 0.0;
    double kx = chn_kd(C, j) * s->X[j];
    if (j > 0) kx -= C->k[j] * s->X[j - 1];
    if (j + 1 < n) kx -= C->k[j + 1] * s->X[j + 1];
    const dfo_loads L = {u, 0.0, 0.0, Fb[j]}; /* (N and the kinetic magnitude are not read) */
    int dir = 0;
    return dfo_next_breakaway(&P, &L, u - kx, ta, &dir);
}

/* A span's reach for the step h and the Bossak parameter alpha: bossak.h's dfo_bossak_reach of
 * M_hat's largest diagonally scaled off-diagonal row sum (the chain's own rule, chain_setup.c). */
static inline void chn_set_reach(chn_model *C, double h, double alpha)
{
    const size_t n = C->n;
    const double g = dfo_bossak_gamma(alpha), b = dfo_bossak_beta(alpha);
    const double cM = (1.0 - alpha) / (g * h), cK = b * h / g;
    double rho = 0.0;
    for (size_t i = 0; i < n; i++) {
        const double lo = (i > 0) ? cK * C->k[i] : 0.0, up = (i + 1 < n) ? cK * C->k[i + 1] : 0.0;
        rho = fmax(rho, (lo + up) / (cM * C->m[i] + cK * chn_kd(C, i)));
    }
    C->w = dfo_bossak_reach(rho, n);
}

/* The spans around the candidate blocks (eng_sparse.span): engine.h's eng_row_spans with the reach w. */
static inline size_t chn_span(void *ctx, const int *cand, int *dof_lab, int *ct_lab, size_t *dof_rng,
                              size_t *ct_rng)
{
    const chn_model *C = (const chn_model *)ctx;
    return eng_row_spans(C->n, C->w, cand, dof_lab, ct_lab, dof_rng, ct_rng);
}

/* The span's view (eng_sparse.span_bind): blocks dofs[0] ... dofs[nd - 1] (consecutive), its ends
 * fixed where they are ghosts. */
static inline void chn_span_bind(void *ctx, const size_t *dofs, const int *ghost, size_t nd, const size_t *cts,
                                 size_t nct)
{
    const chn_model *C = (const chn_model *)ctx;
    chn_model *V = C->sub;
    (void)cts;
    (void)nct; /* (the span's contacts are its blocks') */
    V->n = nd;
    V->m = C->m + dofs[0];
    V->k = C->k + dofs[0];
    V->k_end = C->k_end;
    V->fix_lo = ghost[0];
    V->fix_hi = ghost[nd - 1];
    V->w = 0;
    V->sub = NULL;
}

/* The chain's sparse-structure operators: its box LCP takes the held solves of M, and (with spans,
 * C->sub the view's arrays, C->w set) the located scheme's switches are placed in spans. */
static inline eng_sparse chn_sparse(chn_model *C, int spans)
{
    eng_sparse sp;
    const eng_ops view = {C->sub, chn_K, NULL, chn_M, chn_factor, chn_solve, chn_friction, NULL, 0};
    sp.held_basis = 1;
    sp.step_held = chn_step_held;
    sp.contact_breakaway = chn_contact_breakaway;
    sp.span_max = spans ? C->n : 0;
    sp.span = spans ? chn_span : NULL;
    sp.span_bind = spans ? chn_span_bind : NULL;
    sp.span_ops = view;
    return sp;
}

/* ---- the chain's specialised schemes (engine_chain.c; the block's: osc_engine.h) ------------ */

ENG_DECLARE_SCHEMES(chn_);

#endif
