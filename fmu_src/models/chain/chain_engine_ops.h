/* The chain as a model of the friction engine (fmu_src/engine): n blocks in a row, contact i on
 * block i against the ground or its belt (w_i = e_i). Its operators: M diagonal, K and C
 * tridiagonal (the springs and dampers between neighbours and to the walls, the site springs and
 * dampers on the diagonal), M_hat tridiagonal factored by Thomas's algorithm per slot; its friction
 * solver the box LCP of numerics/lcp.h on the velocities relative to the belts, O(n), with the
 * factorisation of the basis solves kept for the held pattern, and the Stribeck law's implicit
 * forces by Newton's iteration on the sliding rows (one tridiagonal solve per iteration); the
 * closed-form breakaway of a chain held at rest and of a held block whose neighbours are held; and
 * its sparse-structure operators (engine.h's eng_sparse): the held solves, the fused grid step in
 * the held pattern (a run of them from one packed row per block, chain_run_row), and spans (a span of the chain is a chain of its own: a view of consecutive
 * blocks whose end blocks, where they are not the chain's ends, are ghosts with Dirichlet rows).
 * Static inline: through eng_ops's function pointers or inlined into engine_step.h
 * (chain_engine.c), the same arithmetic. Plain C, no FMI types. */
#ifndef DFO_CHAIN_ENGINE_OPS_H
#define DFO_CHAIN_ENGINE_OPS_H

#include "bossak.h"
#include "dfo_inline.h"
#include "engine.h"
#include "friction.h"
#include "lcp.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

#define CHAIN_NEWTON_ITERS 60

/* The fused step of a run inlined into the engine's loop of them (chain_engine.c's ENG_STEP_RUN),
 * its rows taken at the run's first step out of line */
#define CHAIN_OP_HOT inline /* (as engine_step.h's ENG_HOT: the compiler's choice) */
#define CHAIN_OP_COLD DFO_NO_INLINE

/* Block i's data for the fused steps of a run (eng_held_step.run; chain_op_run_take), together in
 * memory: its coefficients, the run's load and mode, the slot's off-diagonal, and the slot's
 * factorisation for the basis solve kept for the held pattern (as chain_op_basis keeps its own). */
typedef struct {
    double m, Kd, Ko;             /* M and K's row (Ko: coupling i and i + 1) */
    double Pc, Ps;                /* the excitation (0 where the run's arrays are NULL) */
    double u;                     /* external force */
    double e;                     /* M_hat's off-diagonal e[i] */
    double cp, inv;               /* Thomas's cp and 1 / den of the kept factorisation (pattern kh) */
    double sl;                    /* the sliding force's term of the right-hand side: mode lim where lim > 0, else 0 */
    double Fb;                    /* breakaway limit */
    int hold;                     /* held: mode 0 with lim > 0 */
    int st;                       /* mode */
    int kh;                       /* the pattern cp, inv are for: 0 none yet, 1 free, 2 held */
    int pad;                      /* (the struct's size a multiple of 8) */
} chain_run_row;

/* The operators' data: the model's arrays (read; a span's view points into them), the slots'
 * factorisations and the solver's workspace (written; a view has its own). */
typedef struct chain_eng_ops_s {
    size_t n;
    const double *m;              /* masses */
    const double *Kd, *Ko;        /* K: diagonal, and Ko[i] coupling i and i + 1 (0 on the last) */
    const double *Cd, *Co;        /* C likewise */
    const double *P0, *phi;       /* each block's force amplitude and phase (its closed-form breakaway) */
    int damped;                   /* C is not 0 */
    double *d[ENG_NSLOTS];        /* each slot's M_hat: diagonal, */
    double *e[ENG_NSLOTS];        /* off-diagonal (e[n - 1] = 0), */
    double *cp[ENG_NSLOTS];       /* Thomas's factors cp = e / den, */
    double *inv[ENG_NSLOTS];      /* inv = 1 / den, */
    int tok[ENG_NSLOTS];          /* made (chain_op_factor makes them lazily) */
    /* the slot's factorisation for the basis solves, kept for a held pattern (chain_op_basis): per
     * row the pattern it is for (kh: 0 none yet, 1 free, 2 held), Thomas's cp and 1 / den */
    int *kh[ENG_NSLOTS];
    double *kcp[ENG_NSLOTS], *kinv[ENG_NSLOTS];
    double *q, *work;             /* n and 2 n: the box LCP's right-hand side and workspace */
    double *nd, *ne, *nr;         /* n each: Newton's tridiagonal system (Stribeck) */
    int fix_lo, fix_hi;           /* a span's view: its first / last row a ghost's (Dirichlet) */
    size_t w;                     /* a span's reach (chain_op_set_reach; 0: no spans) */
    struct chain_eng_ops_s *sub;  /* the span's view (chain_op_span_bind) */
    /* the fused steps' run (n rows; NULL: the rows not offered, runs stepped as lone steps), the slot and
     * coefficients their M_hat is of (rr_slot -1: none yet), and the arrays their coefficients are of */
    chain_run_row *rr;
    int rr_slot;
    double rr_c[3];
    const double *rr_src[5];
} chain_eng_ops;

ENG_DECLARE_SCHEMES(chain_);

/* y = T x for the symmetric tridiagonal T of diagonal D and off-diagonal O (O[i] couples i and i + 1),
 * each row summed as D_i x_i + O_{i-1} x_{i-1} + O_i x_{i+1}; the end rows out of the loop (a loop
 * without branches). x and y do not overlap. */
static inline void chain_op_tri(size_t n, const double *D, const double *O, const double *x, double *y)
{
    if (n == 0) return;
    if (n == 1) {
        y[0] = D[0] * x[0];
        return;
    }
    y[0] = D[0] * x[0] + O[0] * x[1];
    for (size_t i = 1; i + 1 < n; i++) y[i] = (D[i] * x[i] + O[i - 1] * x[i - 1]) + O[i] * x[i + 1];
    y[n - 1] = D[n - 1] * x[n - 1] + O[n - 2] * x[n - 2];
}

static inline void chain_op_K(void *ctx, const double *x, double *y)
{
    const chain_eng_ops *C = (const chain_eng_ops *)ctx;
    chain_op_tri(C->n, C->Kd, C->Ko, x, y);
}

static inline void chain_op_C(void *ctx, const double *v, double *y)
{
    const chain_eng_ops *C = (const chain_eng_ops *)ctx;
    chain_op_tri(C->n, C->Cd, C->Co, v, y);
}

static inline void chain_op_M(void *ctx, const double *a, double *y)
{
    const chain_eng_ops *C = (const chain_eng_ops *)ctx;
    const size_t n = C->n;
    const double *m = C->m;
    for (size_t i = 0; i < n; i++) y[i] = m[i] * a[i];
}

/* p_i += m_i r_i - (K x)_i (chain_op_M's and chain_op_K's products, in one pass; the end rows out of
 * the loop) */
static inline void chain_op_add_mk(void *ctx, const double *r, const double *x, double *p)
{
    const chain_eng_ops *C = (const chain_eng_ops *)ctx;
    const size_t n = C->n;
    const double *m = C->m, *D = C->Kd, *O = C->Ko;
    if (n == 0) return;
    if (n == 1) {
        p[0] += m[0] * r[0] - D[0] * x[0];
        return;
    }
    p[0] += m[0] * r[0] - (D[0] * x[0] + O[0] * x[1]);
    for (size_t i = 1; i + 1 < n; i++) p[i] += m[i] * r[i] - ((D[i] * x[i] + O[i - 1] * x[i - 1]) + O[i] * x[i + 1]);
    p[n - 1] += m[n - 1] * r[n - 1] - (D[n - 1] * x[n - 1] + O[n - 2] * x[n - 2]);
}

/* Thomas's factors of the slot (cp, inv): 0 when a pivot is not positive. */
static inline int chain_op_thomas(chain_eng_ops *C, int slot)
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

/* M_hat of the slot, cM M + cC C + cK K (the oscillator's order); Thomas's factors made when first
 * solved with where M_hat is strictly diagonally dominant (so positive definite), else now. */
static inline int chain_op_factor(void *ctx, int slot, double cM, double cC, double cK)
{
    chain_eng_ops *C = (chain_eng_ops *)ctx;
    const size_t n = C->n;
    double *d = C->d[slot], *e = C->e[slot];
    const double *m = C->m, *Cd = C->Cd, *Kd = C->Kd, *Co = C->Co, *Ko = C->Ko;
    if (n == 0) return 1;
    /* (each loop without branches: the first row's dominance fabs(e_0) + 0.0, which compares as fabs(e_0)) */
    for (size_t i = 0; i < n; i++) d[i] = cM * m[i] + cC * Cd[i] + cK * Kd[i];
    for (size_t i = 0; i + 1 < n; i++) e[i] = cC * Co[i] + cK * Ko[i];
    e[n - 1] = 0.0;
    int dominant = d[0] > fabs(e[0]);
    for (size_t i = 1; i < n; i++) dominant &= d[i] > fabs(e[i]) + fabs(e[i - 1]);
    memset(C->kh[slot], 0, n * sizeof(int)); /* the kept basis factors anew */
    C->tok[slot] = 0;
    return dominant || chain_op_thomas(C, slot);
}

static inline void chain_op_solve(void *ctx, int slot, const double *b, double *x)
{
    chain_eng_ops *C = (chain_eng_ops *)ctx;
    const size_t n = C->n;
    if (!C->tok[slot]) (void)chain_op_thomas(C, slot); /* (positive pivots: chain_op_factor) */
    const double *e = C->e[slot], *cp = C->cp[slot], *inv = C->inv[slot];
    double prev = 0.0;
    for (size_t i = 0; i < n; i++) {
        prev = (b[i] - ((i > 0) ? e[i - 1] * prev : 0.0)) * inv[i];
        x[i] = prev;
    }
    for (size_t i = n - 1; i-- > 0;) x[i] -= cp[i] * x[i + 1];
}

/* Row i of chain_op_basis's forward elimination: its kept factor made anew where its hold changed or,
 * free, where the row above was (*refac, then set for the row below), *cprev its Thomas factor then;
 * returns its eliminated right-hand side (rhs: -q_i less the sliding force; 0 on a held row). */
static inline double chain_op_elim_row(chain_eng_ops *C, int slot, size_t i, int hold, double rhs, double *cprev,
                                       double dprev, int *refac)
{
    const double *d = C->d[slot], *e = C->e[slot];
    int *kh = C->kh[slot];
    double *kcp = C->kcp[slot], *kinv = C->kinv[slot];
    const double lo_e = (i > 0) ? e[i - 1] : 0.0;
    if (kh[i] != 1 + hold || (*refac && !hold)) {
        kh[i] = 1 + hold;
        if (hold) {
            kcp[i] = 0.0;
        } else {
            kinv[i] = 1.0 / (d[i] - lo_e * *cprev);
            kcp[i] = (i + 1 < C->n) ? e[i] * kinv[i] : 0.0;
        }
        *refac = 1;
    } else {
        *refac = 0;
    }
    *cprev = kcp[i];
    return hold ? 0.0 : (rhs - lo_e * dprev) * kinv[i];
}

/* lcp_box_basis(0, n, 0, 0.0, 0, 0.0, d, e, q, l, mode, z, w, ...) of the slot's M_hat with its
 * factorisation kept for the held pattern (mode 0 with l > 0): the same operations, so the same
 * bits, without the divisions of the rows whose pattern is unchanged. A row is refactored when its
 * own hold changed, or when it is free and the row above was refactored (a held row starts the
 * elimination afresh: cp = 0). */
static inline void chain_op_basis(chain_eng_ops *C, int slot, const double *q, const double *l, const int *mode,
                                  double *z, double *w)
{
    const size_t n = C->n;
    const double *e = C->e[slot];
    double *kcp = C->kcp[slot], *dp = C->work;
    double cprev = 0.0, dprev = 0.0;
    int refac = 0;
    for (size_t i = 0; i < n; i++) {
        const int hold = mode[i] == 0 && l[i] > 0.0;
        const double rhs = -q[i] - ((l[i] > 0.0) ? mode[i] * l[i] : 0.0);
        dprev = chain_op_elim_row(C, slot, i, hold, rhs, &cprev, dprev, &refac);
        dp[i] = dprev;
    }
    double zn = 0.0;
    for (size_t j = n; j-- > 0;) {
        zn = dp[j] - kcp[j] * zn;
        z[j] = zn;
    }
    lcp_box_basis_w(0, n, 0, n, e, q, l, mode, z, w);
}

/* lcp_box_basis(0, n, fix_lo, zl, fix_hi, zh, d, e, q, l, mode, z, w, ...) of a slot whose M_hat is
 * diagonal (cC = cK = 0: e holds zeros, the mass slot of the engine's held solves): lcp_box_basis_diag,
 * the same operations, so the same bits, but with no division on the elimination's chain (a row's
 * pivot d - e cp is d itself: e cp is a zero and d > 0). */
static inline void chain_op_diag(chain_eng_ops *C, int slot, int fix_lo, double zl, int fix_hi, double zh,
                                 const double *q, const double *l, const int *mode, double *z, double *w)
{
    lcp_box_basis_diag(0, C->n, fix_lo, zl, fix_hi, zh, C->d[slot], C->e[slot], q, l, mode, z, w, C->work,
                       C->work + C->n);
}

/* A row whose W stays as the basis solve set it: held, or a span's ghost. */
static inline int chain_op_fixed(const chain_eng_ops *C, const eng_problem *P, const int *mode, size_t i)
{
    return (mode[i] == 0 && P->limit[i] > 0.0) || (i == 0 && C->fix_lo) || (i + 1 == C->n && C->fix_hi);
}

/* The Stribeck rows' implicit forces after the modes are decided: with W the velocities relative to
 * the belts, M_hat W = r + F(W) on the free rows (r = p_hat - M_hat vb, in C->q), F_i = -s_i N_i
 * mu_i(max(s_i W_i, 0)) on a sliding Stribeck row, -s_i limit_i on another sliding row, 0 without
 * friction; held rows and ghosts keep their W. Newton's iteration from the basis solve; then the
 * held rows' forces from their equations. */
static inline eng_status chain_op_stribeck(chain_eng_ops *C, const eng_problem *P, const int *mode, double *W,
                                           double *f)
{
    const size_t n = C->n;
    const double *d = C->d[P->slot], *e = C->e[P->slot], *r = C->q;
    for (int it = 0; it <= CHAIN_NEWTON_ITERS; it++) {
        double res_max = 0.0, scale = 0.0;
        for (size_t i = 0; i < n; i++) {
            const int fixed = chain_op_fixed(C, P, mode, i);
            C->ne[i] = (i + 1 < n && !fixed && !chain_op_fixed(C, P, mode, i + 1)) ? e[i] : 0.0;
            if (fixed) {
                C->nd[i] = 1.0;
                C->nr[i] = 0.0;
                continue;
            }
            double Fi = 0.0, dFi = 0.0;
            if (P->limit[i] > 0.0) {
                const int sd = mode[i];
                if (P->law[i].law == DFO_LAW_STRIBECK) {
                    const double u = fmax(sd * W[i], 0.0);
                    Fi = -sd * P->N[i] * dfo_friction_mu(&P->law[i], u);
                    dFi = (sd * W[i] > 0.0) ? -P->N[i] * dfo_friction_dmu(&P->law[i], u) : 0.0;
                } else {
                    Fi = -sd * P->limit[i];
                }
            }
            double res = d[i] * W[i] - r[i] - Fi;
            if (i > 0) res += e[i - 1] * W[i - 1];
            if (i + 1 < n) res += e[i] * W[i + 1];
            f[i] = Fi;
            C->nd[i] = d[i] - dFi;
            C->nr[i] = -res;
            res_max = fmax(res_max, fabs(res));
            scale = fmax(scale, fabs(d[i] * W[i]) + fabs(r[i]) + fabs(Fi));
        }
        if (res_max <= 1e-14 * scale) {
            for (size_t i = 0; i < n; i++) {
                if (!(mode[i] == 0 && P->limit[i] > 0.0)) continue;
                double fi = -r[i];
                if (i > 0) fi += e[i - 1] * W[i - 1];
                if (i + 1 < n) fi += e[i] * W[i + 1];
                f[i] = fi;
            }
            return ENG_OK;
        }
        if (it == CHAIN_NEWTON_ITERS) break;
        double prev = 0.0, pd = 0.0; /* Thomas on (nd, ne) */
        for (size_t i = 0; i < n; i++) {
            const double lo = (i > 0) ? C->ne[i - 1] : 0.0;
            const double den = C->nd[i] - lo * prev;
            if (!(den != 0.0) || !isfinite(den)) return ENG_ERR_FRICTION;
            prev = C->ne[i] / den;
            pd = (C->nr[i] - lo * pd) / den;
            C->work[i] = prev;
            C->nr[i] = pd;
        }
        for (size_t i = n - 1; i-- > 0;) C->nr[i] -= C->work[i] * C->nr[i + 1];
        for (size_t i = 0; i < n; i++) W[i] += C->nr[i];
    }
    return ENG_ERR_FRICTION;
}

/* The friction problem of a step: with W = V1 - vb, M_hat W = p_hat - M_hat vb + f, the box LCP of
 * lcp.h on W (the kept basis solve; lcp_box for the LCP unless the warm basis holds); a span's
 * ghost rows fixed at their prescribed velocities (p_hat's entries there: Dirichlet rows); the
 * Stribeck rows' forces then by chain_op_stribeck. */
static inline eng_status chain_op_friction(void *ctx, const eng_problem *P, int what, int *mode, double *V1,
                                           double *f, int *pivots)
{
    chain_eng_ops *C = (chain_eng_ops *)ctx;
    const size_t n = C->n;
    const double *d = C->d[P->slot], *e = C->e[P->slot], *l = P->limit, *vb = P->vb;
    const double *ph = P->p_hat;
    double *q = C->q;
    if (!vb || n <= 1) {
        for (size_t i = 0; i < n; i++) q[i] = -(vb ? ph[i] - d[i] * vb[i] : ph[i]);
    } else { /* r = p_hat - M_hat vb row by row (its terms in the order d, lower, upper); the end rows
              * out of the loop */
        q[0] = -((ph[0] - d[0] * vb[0]) - e[0] * vb[1]);
        for (size_t i = 1; i + 1 < n; i++) q[i] = -(((ph[i] - d[i] * vb[i]) - e[i - 1] * vb[i - 1]) - e[i] * vb[i + 1]);
        q[n - 1] = -((ph[n - 1] - d[n - 1] * vb[n - 1]) - e[n - 2] * vb[n - 2]);
    }
    if (pivots) *pivots = 0;
    if (what == ENG_SOLVE_BASIS && P->cC == 0.0 && P->cK == 0.0) { /* M_hat diagonal (the held solves) */
        const double zl = P->p_hat[0] - (vb ? vb[0] : 0.0), zh = P->p_hat[n - 1] - (vb ? vb[n - 1] : 0.0);
        chain_op_diag(C, P->slot, C->fix_lo, zl, C->fix_hi, zh, C->q, l, mode, V1, f);
    } else if (C->fix_lo || C->fix_hi) { /* a span: the ghosts' rows fixed at their entries of p_hat */
        if (what != ENG_SOLVE_BASIS) return ENG_ERR_BAD_INPUT;
        const double zl = P->p_hat[0] - (vb ? vb[0] : 0.0), zh = P->p_hat[n - 1] - (vb ? vb[n - 1] : 0.0);
        lcp_box_basis(0, n, C->fix_lo, zl, C->fix_hi, zh, d, e, C->q, l, mode, V1, f, C->work, C->work + n);
    } else {
        chain_op_basis(C, P->slot, C->q, l, mode, V1, f);
        if (what != ENG_SOLVE_BASIS) {
            /* the warm basis: when lcp_box's first round would flip no row, its solution is this one */
            int flip = 0;
            for (size_t i = 0; i < n && !flip; i++)
                flip = l[i] > 0.0 && ((mode[i] != 0 && mode[i] * V1[i] < 0.0) || (mode[i] == 0 && f[i] > l[i]) ||
                                      (mode[i] == 0 && f[i] < -l[i]));
            if (!flip) {
                for (size_t i = 0; i < n; i++)
                    if (!(l[i] > 0.0)) mode[i] = (V1[i] > 0.0) - (V1[i] < 0.0);
            } else if (lcp_box(n, d, e, C->q, l, mode, V1, f, C->work, pivots) != LCP_OK) {
                return ENG_ERR_LCP;
            }
        }
    }
    /* (every row's f is lcp_box_basis_w's: a held row's from its equation, another's its limit's,
     * 0.0 - mode l, which is -mode l; a ghost's, which it does not set, 0) */
    if (C->fix_lo) f[0] = 0.0;
    if (C->fix_hi) f[n - 1] = 0.0;
    if (P->law) {
        int any = 0;
        for (size_t i = 0; i < n; i++) any |= mode[i] != 0 && l[i] > 0.0 && P->law[i].law == DFO_LAW_STRIBECK;
        if (any) {
            for (size_t i = 0; i < n; i++) C->q[i] = -C->q[i]; /* r */
            const eng_status st = chain_op_stribeck(C, P, mode, V1, f);
            if (st != ENG_OK) return st;
        }
    }
    if (vb)
        for (size_t i = 0; i < n; i++) V1[i] += vb[i];
    return ENG_OK;
}

/* Block j held at rest with the loads (u, Fb) and its static force u - (K x)_j: its next breakaway
 * from ta under its excitation P0_j cos(omega t + phi_j) (friction.h), from the block's own
 * amplitude and phase (not from the engine's Pc, Ps: libm's hypot and atan2 differ in their last
 * bits between platforms). */
static inline double chain_op_block_breakaway(const chain_eng_ops *C, const eng_harmonic *exc, size_t j, double u,
                                              double Fb, double kx, double ta)
{
    dfo_harmonic H;
    dfo_harmonic_init(&H, C->P0[j], exc->omega, C->phi[j]);
    dfo_loads L;
    dfo_loads_set(&L, u, 0.0, 0.0, 0.0);
    L.Fb = Fb;
    int dir;
    return dfo_next_breakaway(&H, &L, u - kx, ta, &dir);
}

static inline double chain_op_Kx(const chain_eng_ops *C, const double *x, size_t i)
{
    double kx = C->Kd[i] * x[i];
    if (i > 0) kx += C->Ko[i - 1] * x[i - 1];
    if (i + 1 < C->n) kx += C->Ko[i] * x[i + 1];
    return kx;
}

/* The chain held at rest at X (every block stuck, the inputs held, the belts still): the earliest of
 * the blocks' closed-form breakaways. */
static inline double chain_op_breakaway(void *ctx, const eng_harmonic *exc, const eng_state *s,
                                        const eng_inputs *in, const double *Fb)
{
    const chain_eng_ops *C = (const chain_eng_ops *)ctx;
    double tb = INFINITY;
    for (size_t i = 0; i < C->n; i++) {
        const double u = in->F_ext ? in->F_ext[i] : 0.0;
        const double t = chain_op_block_breakaway(C, exc, i, u, Fb[i], chain_op_Kx(C, s->X, i), s->t);
        if (isnan(t)) return NAN;
        if (t < tb) tb = t;
    }
    return tb;
}

/* Held block j's next breakaway in closed form (eng_sparse.contact_breakaway) where its neighbours
 * are held too (its static force then P_j(t) + u_j - (K x)_j with x fixed); NaN else. */
static inline double chain_op_contact_breakaway(void *ctx, size_t j, const eng_harmonic *exc, const eng_state *s,
                                                const eng_inputs *in, const double *Fb)
{
    const chain_eng_ops *C = (const chain_eng_ops *)ctx;
    for (size_t k = (j > 0) ? j - 1 : j; k <= j + 1 && k < C->n; k++)
        if (k != j && !(s->mode[k] == 0 && Fb[k] > 0.0)) return NAN;
    const double u = (in && in->F_ext) ? in->F_ext[j] : 0.0;
    return chain_op_block_breakaway(C, exc, j, u, Fb[j], chain_op_Kx(C, s->X, j), s->t_stick[j]);
}

/* The fused step's acceptance (engine.h's eng_held_step): X, A, V, hA and F from its x_pred, V1, f;
 * the last row's x_pred and V1 given as xn, vn (the sweeps' registers: no store and load of them on
 * the step's chain of dependencies). */
static inline void chain_op_held_accept(const eng_held_step *F, eng_state *s, size_t n, double xn, double vn)
{
    const double *xpp = F->xp, *V1 = F->V1, *f = F->f, *A0 = F->A0; /* (A0: s->A, read before written) */
    double *X = s->X, *V = s->V, *A = s->A, *hA = s->hA, *sF = s->F;
    const double cV = F->corr_V, hh = F->h, c1 = F->c1, g1 = F->g1;
    for (size_t i = 0; i + 1 < n; i++) {
        X[i] = xpp[i] + cV * V1[i];
        A[i] = (V1[i] - V[i]) * c1 - g1 * A0[i];
        V[i] = V1[i];
        hA[i] = hh;
        sF[i] = f[i];
    }
    const size_t i = n - 1;
    X[i] = xn + cV * vn;
    A[i] = (vn - V[i]) * c1 - g1 * A0[i];
    V[i] = vn;
    hA[i] = hh;
    sF[i] = f[i];
}

/* Row i of the fused step once its neighbours' V1 are known (vlo: row i - 1's, unused for i = 0; vi:
 * its own; vhi: row i + 1's, unused for the last): its force as chain_op_basis sets it (a held row's
 * from its equation, a sliding row's its limit's) into F->f, and whether its margin is positive. */
static inline int chain_op_row_done(const chain_eng_ops *C, const eng_held_step *F, size_t i, double vlo, double vi,
                                    double vhi)
{
    const size_t n = C->n;
    const double *e = C->e[F->slot], *l = F->lim;
    const int *mode = F->st;
    double fi;
    if (mode[i] == 0 && l[i] > 0.0) {
        fi = C->q[i];
        if (i > 0) fi += e[i - 1] * vlo;
        if (i + 1 < n) fi += e[i] * vhi;
    } else {
        fi = (l[i] > 0.0) ? 0.0 - mode[i] * l[i] : 0.0;
    }
    F->f[i] = fi;
    if (!(F->Fb[i] > 0.0)) return 1;
    return (mode[i] != 0) ? mode[i] * ((0.0 + 1.0 * vi) - 0.0) > 0.0 : F->Fb[i] - fabs(fi) > 0.0;
}

/* The fused grid step in the held pattern (eng_sparse.step_held): x_pred, p_hat and the kept basis
 * solve's elimination in one forward sweep (K's row needs x_pred one block ahead), its back
 * substitution with the held rows' forces and the margins in one backward sweep, the acceptance;
 * the engine's arithmetic in its order (engine.h's eng_held_step, chain_op_basis), so the same
 * bits. A step of a run (F->run > 0) is chain_op_step_run's, from the rows (C->rr). */
static CHAIN_OP_HOT int chain_op_step_run(void *ctx, const eng_held_step *F, eng_state *s);

static inline int chain_op_step_held(void *ctx, const eng_held_step *F, eng_state *s)
{
    chain_eng_ops *C = (chain_eng_ops *)ctx;
    if (F->run && C->rr) return chain_op_step_run(C, F, s);
    const size_t n = C->n;
    const int slot = F->slot;
    const double a = F->alpha, c1 = F->c1, g1 = F->g1, pV = F->pred_V, pA = F->pred_A;
    const double *X = s->X, *V = s->V, *A0 = F->A0, *l = F->lim;
    const int *mode = F->st;
    double *kcp = C->kcp[slot], *dp = C->work;
    double *xpp = F->xp, *q = C->q, *V1 = F->V1, *ph = F->ph;
    /* the inputs read once (a store through an output may not change them) */
    const double *m = C->m, *Kd = C->Kd, *Ko = C->Ko, *u = F->u, *Pc = F->Pc, *Ps = F->Ps;
    const double cw = F->cw, sw = F->sw;
    double xc = X[0] + pV * V[0] + pA * A0[0], cprev = 0.0, dprev = 0.0;
    int refac = 0;
    for (size_t i = 0; i < n; i++) {
        /* x_pred and p_hat */
        const double xr = (i + 1 < n) ? X[i + 1] + pV * V[i + 1] + pA * A0[i + 1] : 0.0;
        xpp[i] = xc;
        const double r = -a * A0[i] + (1.0 - a) * (V[i] * c1 + g1 * A0[i]);
        const double y = m[i] * r;
        double kx = Kd[i] * xc;
        if (i > 0) kx += Ko[i - 1] * xpp[i - 1];
        if (i + 1 < n) kx += Ko[i] * xr;
        double p = u[i];
        if (Pc) p += Pc[i] * cw;
        if (Ps) p -= Ps[i] * sw;
        const double phi = p + (y - kx);
        ph[i] = phi;
        q[i] = -phi;
        xc = xr;
        /* chain_op_basis's forward elimination of row i */
        const int hold = mode[i] == 0 && l[i] > 0.0;
        const double rhs = -q[i] - ((l[i] > 0.0) ? mode[i] * l[i] : 0.0);
        dprev = chain_op_elim_row(C, slot, i, hold, rhs, &cprev, dprev, &refac);
        dp[i] = dprev;
    }
    /* back substitution (zn: the elimination's value; a held row's V1 then 0) and row j + 1's force
     * and margin once row j is known (its neighbours' V1 then are); row 0's after */
    int ok = 1;
    double zn = 0.0, v1 = 0.0, v2 = 0.0, vn = 0.0; /* V1 of rows j + 1 and j + 2, and of the last */
    for (size_t j = n; j-- > 0;) {
        zn = dp[j] - kcp[j] * zn;
        const double vj = (mode[j] == 0 && l[j] > 0.0) ? 0.0 : zn;
        V1[j] = vj;
        if (j + 1 < n) ok &= chain_op_row_done(C, F, j + 1, vj, v1, v2);
        else vn = vj;
        v2 = v1;
        v1 = vj;
    }
    ok &= chain_op_row_done(C, F, 0, 0.0, v1, v2);
    if (!ok) return 0;
    chain_op_held_accept(F, s, n, xpp[n - 1], vn);
    return 1;
}

/* The run's first step (eng_held_step.run = 1): the coefficients into the rows where their arrays
 * are not those the rows hold, M_hat's off-diagonal where the slot or its coefficients changed (then
 * the kept factorisation anew). */
static CHAIN_OP_COLD void chain_op_run_take(chain_eng_ops *C, const eng_held_step *F)
{
    const size_t n = C->n;
    chain_run_row *R = C->rr;
    if (C->rr_src[0] != C->m || C->rr_src[1] != C->Kd || C->rr_src[2] != C->Ko || C->rr_src[3] != F->Pc ||
        C->rr_src[4] != F->Ps) {
        for (size_t i = 0; i < n; i++) {
            R[i].m = C->m[i];
            R[i].Kd = C->Kd[i];
            R[i].Ko = C->Ko[i];
            R[i].Pc = F->Pc ? F->Pc[i] : 0.0;
            R[i].Ps = F->Ps ? F->Ps[i] : 0.0;
        }
        C->rr_src[0] = C->m;
        C->rr_src[1] = C->Kd;
        C->rr_src[2] = C->Ko;
        C->rr_src[3] = F->Pc;
        C->rr_src[4] = F->Ps;
    }
    if (C->rr_slot != F->slot || C->rr_c[0] != F->cM || C->rr_c[1] != F->cC || C->rr_c[2] != F->cK) {
        const double *e = C->e[F->slot];
        for (size_t i = 0; i < n; i++) {
            R[i].e = e[i];
            R[i].kh = 0;
        }
        C->rr_slot = F->slot;
        C->rr_c[0] = F->cM;
        C->rr_c[1] = F->cC;
        C->rr_c[2] = F->cK;
    }
}

/* Row i's kept factor at a run's first step, as chain_op_elim_row makes it (so the same bits): anew
 * where its hold changed or, free, where the row above's was (refac, returned for the row below). */
static inline int chain_op_run_factor(chain_run_row *R, const double *d, size_t i, size_t n, int hold, int refac)
{
    if (R[i].kh == 1 + hold && !(refac && !hold)) return 0;
    R[i].kh = 1 + hold;
    if (hold) {
        R[i].cp = 0.0;
    } else {
        const double lo_e = (i > 0) ? R[i - 1].e : 0.0, cprev = (i > 0) ? R[i - 1].cp : 0.0;
        R[i].inv = 1.0 / (d[i] - lo_e * cprev);
        R[i].cp = (i + 1 < n) ? R[i].e * R[i].inv : 0.0;
    }
    return 1;
}

/* chain_op_row_done from the rows: row i's force into f, whether its margin is positive (lo, hi:
 * whether row i has a row above, below) */
static inline int chain_op_run_done(const chain_run_row *R, const double *ph, double *f, size_t i, int lo, int hi,
                                    double vlo, double vi, double vhi)
{
    double fi;
    if (R[i].hold) {
        fi = -ph[i];
        if (lo) fi += R[i - 1].e * vlo;
        if (hi) fi += R[i].e * vhi;
    } else {
        fi = 0.0 - R[i].sl;
    }
    f[i] = fi;
    return !(R[i].Fb > 0.0) || (R[i].st != 0 ? R[i].st * vi > 0.0 : R[i].Fb - fabs(fi) > 0.0);
}

/* Row i's part of a run step's forward sweep (lo, hi: whether it has a row above, below): at the run's
 * first step (first) its loads and mode taken into the row and its kept factor made (*refac: the row
 * above's was, then row i's); p_hat from x_pred (xc its own, xl the row above's, xr the row below's)
 * and r, and the elimination with the kept factors (elo, dprev: the row above's e and eliminated
 * value); returns its eliminated value. */
static inline double chain_op_run_fwd(const chain_eng_ops *C, chain_run_row *R, size_t i, int lo, int hi, int first,
                                      int *refac, double xc, double xl, double xr, double r, const eng_held_step *F,
                                      double elo, double dprev, double *ph, double *dp)
{
    if (first) {
        const int st = F->st[i];
        const double li = F->lim[i];
        const int hold = st == 0 && li > 0.0;
        R[i].u = F->u[i];
        R[i].Fb = F->Fb[i];
        R[i].st = st;
        R[i].hold = hold;
        R[i].sl = (li > 0.0) ? st * li : 0.0;
        *refac = chain_op_run_factor(R, C->d[F->slot], i, C->n, hold, *refac);
    }
    const double y = R[i].m * r;
    double kx = R[i].Kd * xc;
    if (lo) kx += R[i - 1].Ko * xl;
    if (hi) kx += R[i].Ko * xr;
    double p = R[i].u;
    if (F->Pc) p += R[i].Pc * F->cw;
    if (F->Ps) p -= R[i].Ps * F->sw;
    const double phi = p + (y - kx);
    ph[i] = phi;
    /* (row 0: x - 0 0 is x, one subtraction less on the step's chain of dependencies) */
    const double rhs = phi - R[i].sl;
    const double v = R[i].hold ? 0.0 : (lo ? rhs - elo * dprev : rhs) * R[i].inv;
    dp[i] = v;
    return v;
}

/* A fused step of a run (eng_held_step.run > 0) from the rows: chain_op_step_held's arithmetic in
 * its order, so the same bits. The run's first step takes F's loads and modes into the rows and
 * makes the kept factorisation for its held pattern, row by row in its forward sweep; the later ones
 * read the rows alone. The first and last rows out of the sweeps' loops. */
static CHAIN_OP_HOT int chain_op_step_run(void *ctx, const eng_held_step *F, eng_state *s)
{
    chain_eng_ops *C = (chain_eng_ops *)ctx;
    const size_t n = C->n;
    chain_run_row *restrict R = C->rr;
    const int first = F->run == 1;
    if (first) chain_op_run_take(C, F);
    int refac = 0;
    const double a = F->alpha, c1 = F->c1, g1 = F->g1, pV = F->pred_V, pA = F->pred_A, am = 1.0 - a;
    const double *X = s->X, *V = s->V, *A0 = F->A0;
    double *restrict xpp = F->xp, *restrict ph = F->ph, *restrict V1 = F->V1, *restrict f = F->f;
    double *restrict dp = C->work;
    /* forward: x_pred one block ahead, p_hat, the elimination with the kept factors */
    double xc = X[0] + pV * V[0] + pA * A0[0], xl = 0.0, dprev;
    const double r0 = -a * A0[0] + am * (V[0] * c1 + g1 * A0[0]);
    if (n == 1) {
        xpp[0] = xc;
        dprev = chain_op_run_fwd(C, R, 0, 0, 0, first, &refac, xc, 0.0, 0.0, r0, F, 0.0, 0.0, ph, dp);
        xl = xc;
    } else {
        double xr = X[1] + pV * V[1] + pA * A0[1];
        xpp[0] = xc;
        dprev = chain_op_run_fwd(C, R, 0, 0, 1, first, &refac, xc, 0.0, xr, r0, F, 0.0, 0.0, ph, dp);
        xl = xc;
        xc = xr;
        for (size_t i = 1; i + 1 < n; i++) {
            xr = X[i + 1] + pV * V[i + 1] + pA * A0[i + 1];
            xpp[i] = xc;
            const double r = -a * A0[i] + am * (V[i] * c1 + g1 * A0[i]);
            dprev = chain_op_run_fwd(C, R, i, 1, 1, first, &refac, xc, xl, xr, r, F, R[i - 1].e, dprev, ph, dp);
            xl = xc;
            xc = xr;
        }
        const size_t i = n - 1;
        xpp[i] = xc;
        const double r = -a * A0[i] + am * (V[i] * c1 + g1 * A0[i]);
        dprev = chain_op_run_fwd(C, R, i, 1, 0, first, &refac, xc, xl, 0.0, r, F, R[i - 1].e, dprev, ph, dp);
        xl = xc;
    }
    /* back substitution, and row j + 1's force and margin once row j is known; row 0's after. The
     * last row's from the forward sweep's register: its elimination's value dp - cp 0 is dp, as its
     * cp is +0 (the last row's, or a held row's). */
    int ok = 1;
    const double vn = dprev; /* (a held row's dprev is 0.0, its V1) */
    double zn = dprev, v1 = vn, v2 = 0.0; /* V1 of rows j + 1 and j + 2 */
    V1[n - 1] = vn;
    if (n > 1) {
        size_t j = n - 2;
        zn = dp[j] - R[j].cp * zn;
        double vj = R[j].hold ? 0.0 : zn;
        V1[j] = vj;
        ok &= chain_op_run_done(R, ph, f, j + 1, 1, 0, vj, v1, v2);
        v2 = v1;
        v1 = vj;
        while (j-- > 0) {
            zn = dp[j] - R[j].cp * zn;
            vj = R[j].hold ? 0.0 : zn;
            V1[j] = vj;
            ok &= chain_op_run_done(R, ph, f, j + 1, 1, 1, vj, v1, v2);
            v2 = v1;
            v1 = vj;
        }
    }
    ok &= chain_op_run_done(R, ph, f, 0, 0, n > 1, 0.0, v1, v2);
    if (!ok) return 0;
    chain_op_held_accept(F, s, n, xl, vn);
    return 1;
}

/* A span's reach for the step h and the Bossak parameter alpha: bossak.h's dfo_bossak_reach of
 * M_hat's largest diagonally scaled off-diagonal row sum. */
static inline void chain_op_set_reach(chain_eng_ops *C, double h, double alpha)
{
    const size_t n = C->n;
    const double g = dfo_bossak_gamma(alpha), b = dfo_bossak_beta(alpha);
    const double cM = (1.0 - alpha) / (g * h), cK = b * h / g;
    double rho = 0.0;
    for (size_t i = 0; i < n; i++) {
        const double lo = (i > 0) ? fabs(C->Co[i - 1] + cK * C->Ko[i - 1]) : 0.0;
        const double up = (i + 1 < n) ? fabs(C->Co[i] + cK * C->Ko[i]) : 0.0;
        rho = fmax(rho, (lo + up) / (cM * C->m[i] + C->Cd[i] + cK * C->Kd[i]));
    }
    C->w = dfo_bossak_reach(rho, n);
}

/* The spans around the candidate blocks (eng_sparse.span): engine.h's eng_row_spans with the reach w. */
static inline size_t chain_op_span(void *ctx, const int *cand, int *dof_lab, int *ct_lab, size_t *dof_rng,
                                   size_t *ct_rng)
{
    const chain_eng_ops *C = (const chain_eng_ops *)ctx;
    return eng_row_spans(C->n, C->w, cand, dof_lab, ct_lab, dof_rng, ct_rng);
}

/* The span's view (eng_sparse.span_bind): blocks dofs[0] ... dofs[nd - 1] (consecutive), its ends
 * fixed where they are ghosts. */
static inline void chain_op_span_bind(void *ctx, const size_t *dofs, const int *ghost, size_t nd, const size_t *cts,
                                      size_t nct)
{
    const chain_eng_ops *C = (const chain_eng_ops *)ctx;
    chain_eng_ops *V = C->sub;
    (void)cts;
    (void)nct; /* (the span's contacts are its blocks') */
    const size_t o = dofs[0];
    V->n = nd;
    V->m = C->m + o;
    V->Kd = C->Kd + o;
    V->Ko = C->Ko + o;
    V->Cd = C->Cd + o;
    V->Co = C->Co + o;
    V->P0 = C->P0 + o;
    V->phi = C->phi + o;
    V->damped = C->damped;
    V->fix_lo = ghost[0];
    V->fix_hi = ghost[nd - 1];
    V->w = 0;
    V->sub = NULL;
}

#endif
