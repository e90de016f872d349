/* The chain as a model of the friction engine (fmu_src/engine): n blocks in a row, contact i on
 * block i against the ground or its belt (w_i = e_i). Its operators: M diagonal, K and C
 * tridiagonal (the springs and dampers between neighbours and to the walls, the site springs and
 * dampers on the diagonal), M_hat tridiagonal factored by Thomas's algorithm per slot; its friction
 * solver the box LCP of numerics/lcp.h on the velocities relative to the belts, O(n), with the
 * Stribeck law's implicit forces by Newton's iteration on the sliding rows (one tridiagonal solve
 * per iteration; a row alone takes the oscillator's scalar iteration); and the closed-form
 * breakaway of a chain held at rest. Static inline: through eng_ops's function pointers or inlined
 * into engine_step.h (chain_engine.c), the same arithmetic. Plain C, no FMI types. */
#ifndef DFO_CHAIN_ENGINE_OPS_H
#define DFO_CHAIN_ENGINE_OPS_H

#include "engine.h"
#include "friction.h"
#include "lcp.h"

#include <math.h>
#include <stddef.h>

#define CHAIN_NEWTON_ITERS 60

/* The operators' data: the model's arrays (read), the slots' factorisations and the solver's
 * workspace (written). */
typedef struct {
    size_t n;
    const double *m;              /* masses */
    const double *Kd, *Ko;        /* K: diagonal, and Ko[i] coupling i and i + 1 (0 on the last) */
    const double *Cd, *Co;        /* C likewise */
    int damped;                   /* C is not 0 */
    double *d[ENG_NSLOTS];        /* each slot's M_hat: diagonal, */
    double *e[ENG_NSLOTS];        /* off-diagonal (e[n - 1] = 0), */
    double *cp[ENG_NSLOTS];       /* Thomas's factors cp = e / den, */
    double *inv[ENG_NSLOTS];      /* inv = 1 / den */
    double *q, *work;             /* n and 2 n: the box LCP's right-hand side and workspace */
    double *nd, *ne, *nr;         /* n each: Newton's tridiagonal system (Stribeck) */
} chain_eng_ops;

ENG_DECLARE_SCHEMES(chain_);

static inline void chain_op_K(void *ctx, const double *x, double *y)
{
    const chain_eng_ops *C = (const chain_eng_ops *)ctx;
    const size_t n = C->n;
    for (size_t i = 0; i < n; i++) {
        double s = C->Kd[i] * x[i];
        if (i > 0) s += C->Ko[i - 1] * x[i - 1];
        if (i + 1 < n) s += C->Ko[i] * x[i + 1];
        y[i] = s;
    }
}

static inline void chain_op_C(void *ctx, const double *v, double *y)
{
    const chain_eng_ops *C = (const chain_eng_ops *)ctx;
    const size_t n = C->n;
    for (size_t i = 0; i < n; i++) {
        double s = C->Cd[i] * v[i];
        if (i > 0) s += C->Co[i - 1] * v[i - 1];
        if (i + 1 < n) s += C->Co[i] * v[i + 1];
        y[i] = s;
    }
}

static inline void chain_op_M(void *ctx, const double *a, double *y)
{
    const chain_eng_ops *C = (const chain_eng_ops *)ctx;
    for (size_t i = 0; i < C->n; i++) y[i] = C->m[i] * a[i];
}

static inline int chain_op_factor(void *ctx, int slot, double cM, double cC, double cK)
{
    chain_eng_ops *C = (chain_eng_ops *)ctx;
    const size_t n = C->n;
    double *d = C->d[slot], *e = C->e[slot], *cp = C->cp[slot], *inv = C->inv[slot];
    for (size_t i = 0; i < n; i++) {
        d[i] = cM * C->m[i] + cK * C->Kd[i] + cC * C->Cd[i];
        e[i] = (i + 1 < n) ? cK * C->Ko[i] + cC * C->Co[i] : 0.0;
    }
    double prev = 0.0;
    for (size_t i = 0; i < n; i++) {
        const double den = d[i] - ((i > 0) ? e[i - 1] * prev : 0.0);
        if (!(den > 0.0)) return 0;
        inv[i] = 1.0 / den;
        cp[i] = e[i] * inv[i];
        prev = cp[i];
    }
    return 1;
}

static inline void chain_op_solve(void *ctx, int slot, const double *b, double *x)
{
    const chain_eng_ops *C = (const chain_eng_ops *)ctx;
    const size_t n = C->n;
    const double *e = C->e[slot], *cp = C->cp[slot], *inv = C->inv[slot];
    double prev = 0.0;
    for (size_t i = 0; i < n; i++) {
        prev = (b[i] - ((i > 0) ? e[i - 1] * prev : 0.0)) * inv[i];
        x[i] = prev;
    }
    for (size_t i = n - 1; i-- > 0;) x[i] -= cp[i] * x[i + 1];
}

/* The Stribeck rows' implicit forces after the modes are decided: with W the velocities relative to
 * the belts, M_hat W = r + F(W) on the free rows (r = p_hat - M_hat vb), F_i = -s_i N_i mu_i(max(s_i
 * W_i, 0)) on a sliding Stribeck row, -s_i limit_i on another sliding row, 0 without friction; held
 * rows stay at W = 0. Newton's iteration from the basis solve; a sliding Stribeck row with only held
 * neighbours takes friction.h's scalar iteration. */
static inline eng_status chain_op_stribeck(chain_eng_ops *C, const eng_problem *P, const int *mode, double *W,
                                           double *f)
{
    const size_t n = C->n;
    const double *d = C->d[P->slot], *e = C->e[P->slot], *r = C->q; /* q holds -r */
    for (int it = 0; it < CHAIN_NEWTON_ITERS; it++) {
        double res_max = 0.0, scale = 0.0;
        for (size_t i = 0; i < n; i++) {
            const int held = mode[i] == 0 && P->limit[i] > 0.0;
            if (held) {
                C->nd[i] = 1.0;
                C->ne[i] = 0.0;
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
            if (i > 0 && !(mode[i - 1] == 0 && P->limit[i - 1] > 0.0)) res += e[i - 1] * W[i - 1];
            if (i + 1 < n && !(mode[i + 1] == 0 && P->limit[i + 1] > 0.0)) res += e[i] * W[i + 1];
            f[i] = Fi;
            C->nd[i] = d[i] - dFi;
            C->ne[i] = (i + 1 < n && !(mode[i + 1] == 0 && P->limit[i + 1] > 0.0)) ? e[i] : 0.0;
            C->nr[i] = -res;
            res_max = fmax(res_max, fabs(res));
            scale = fmax(scale, fabs(d[i] * W[i]) + fabs(r[i]) + fabs(Fi));
        }
        if (!(res_max <= 1e-14 * scale)) {
            /* Thomas on (nd, ne) */
            double prev = 0.0, pd = 0.0;
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
            continue;
        }
        /* converged: the held rows' forces from their equations */
        for (size_t i = 0; i < n; i++) {
            if (!(mode[i] == 0 && P->limit[i] > 0.0)) continue;
            double fi = -r[i];
            if (i > 0) fi += e[i - 1] * W[i - 1];
            if (i + 1 < n) fi += e[i] * W[i + 1];
            f[i] = fi;
        }
        return ENG_OK;
    }
    return ENG_ERR_FRICTION;
}

/* The friction problem of a step: with W = V1 - vb, M_hat W = p_hat - M_hat vb + f, the box LCP of
 * lcp.h on W (lcp_box_basis in the given modes, lcp_box for the LCP); the Stribeck rows' forces
 * then by chain_op_stribeck. */
static inline eng_status chain_op_friction(void *ctx, const eng_problem *P, int what, int *mode, double *V1,
                                           double *f, int *pivots)
{
    chain_eng_ops *C = (chain_eng_ops *)ctx;
    const size_t n = C->n;
    const double *d = C->d[P->slot], *e = C->e[P->slot];
    for (size_t i = 0; i < n; i++) {
        double r = P->p_hat[i];
        if (P->vb) {
            r -= d[i] * P->vb[i];
            if (i > 0) r -= e[i - 1] * P->vb[i - 1];
            if (i + 1 < n) r -= e[i] * P->vb[i + 1];
        }
        C->q[i] = -r;
    }
    if (pivots) *pivots = 0;
    if (what == ENG_SOLVE_BASIS) {
        lcp_box_basis(0, n, 0, 0.0, 0, 0.0, d, e, C->q, P->limit, mode, V1, f, C->work, C->work + n);
        for (size_t i = 0; i < n; i++) /* a sliding row's force is its limit's (w is not set there) */
            if (!(mode[i] == 0 && P->limit[i] > 0.0)) f[i] = (P->limit[i] > 0.0) ? -mode[i] * P->limit[i] : 0.0;
    } else if (lcp_box(n, d, e, C->q, P->limit, mode, V1, f, C->work, pivots) != LCP_OK) {
        return ENG_ERR_LCP;
    }
    if (P->law) {
        int any = 0;
        for (size_t i = 0; i < n; i++) any |= mode[i] != 0 && P->limit[i] > 0.0 && P->law[i].law == DFO_LAW_STRIBECK;
        if (any) {
            for (size_t i = 0; i < n; i++) C->q[i] = -C->q[i]; /* r */
            const eng_status st = chain_op_stribeck(C, P, mode, V1, f);
            if (st != ENG_OK) return st;
        }
    }
    if (P->vb)
        for (size_t i = 0; i < n; i++) V1[i] += P->vb[i];
    for (size_t i = 0; i < n; i++)
        if (!isfinite(V1[i]) || !isfinite(f[i])) return ENG_ERR_NONFINITE;
    return ENG_OK;
}

/* The chain held at rest at X (every block stuck, the inputs held, the belts still): block i's
 * holding force balances its static force P_i(t) + F_ext_i - (K X)_i, P_i(t) = Pc_i cos(omega t +
 * phi0) - Ps_i sin(omega t + phi0); the earliest of the blocks' closed-form breakaways (friction.h's
 * dfo_next_breakaway). */
static inline double chain_op_breakaway(void *ctx, const eng_harmonic *exc, const eng_state *s,
                                        const eng_inputs *in, const double *Fb)
{
    const chain_eng_ops *C = (const chain_eng_ops *)ctx;
    const size_t n = C->n;
    double tb = INFINITY;
    for (size_t i = 0; i < n; i++) {
        const double Pc = exc->Pc ? exc->Pc[i] : 0.0, Ps = exc->Ps ? exc->Ps[i] : 0.0;
        const double F = in->F_ext ? in->F_ext[i] : 0.0;
        double kx = C->Kd[i] * s->X[i];
        if (i > 0) kx += C->Ko[i - 1] * s->X[i - 1];
        if (i + 1 < n) kx += C->Ko[i] * s->X[i + 1];
        dfo_harmonic H;
        if (Ps == 0.0) dfo_harmonic_init(&H, Pc, exc->omega, exc->phi0);
        else dfo_harmonic_init(&H, hypot(Pc, Ps), exc->omega, exc->phi0 + atan2(Ps, Pc));
        dfo_loads L;
        dfo_loads_set(&L, F, 0.0, 0.0, 0.0);
        L.Fb = Fb[i];
        int dir;
        const double t = dfo_next_breakaway(&H, &L, F - kx, s->t, &dir);
        if (isnan(t)) return NAN;
        if (t < tb) tb = t;
    }
    return tb;
}

#endif
