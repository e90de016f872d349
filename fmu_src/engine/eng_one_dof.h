/* The friction engine's operators of one degree of freedom with one contact to the ground or its
 * belt (w = 1): a mass m on a spring k and a damper c. M_hat a scalar (a solve is a product with its
 * inverse), the friction problem of the contact in closed form (the 2 x 2 LCP; a Stribeck contact
 * through the engine's dense solver), the closed-form breakaway of the block at rest (friction.h's
 * dfo_next_breakaway: the engine's stuck fast path). Static inline: through eng_ops's function
 * pointers (engine_generic.c) or inlined into engine_step.h (the oscillator's specialised schemes,
 * osc_engine.c), the same arithmetic, so every model whose structure is this one (the oscillator, a
 * DryFrictionSystem of one DOF and one rigid contact along w = 1) steps to the same bits. Plain C,
 * no FMI types. */
#ifndef DFO_ENG_ONE_DOF_H
#define DFO_ENG_ONE_DOF_H

#include "engine.h"
#include "friction.h"

#include <math.h>
#include <stddef.h>
#include <string.h>

typedef struct {
    double m, c, k;
    double a[ENG_NSLOTS];        /* each slot's factor cM m + cC c + cK k */
    double inv_a[ENG_NSLOTS];    /* and its inverse (a solve is a product, as newmark's 1 / m_hat was) */
    size_t idx[1];
    double w[1];
    eng_row row;
    double N[1], mu_s[1], mu_k[1], Pc[1];
    dfo_friction_law law[1];
    eng *E;                      /* the engine (the Stribeck contact's solver), set by its model */
    /* the engine's dense friction solver, as E's model instantiates it (eng_dense_friction, or a
     * specialised instance's: osc_eng_dense_friction); NULL: no Stribeck contact */
    eng_status (*dense)(void *engine, const eng_problem *P, int what, int *mode, double *V1, double *f, int *pivots);
} eng1_model;

/* The model for m, c, k, its contact (w = 1) with normal force N, coefficients mu_s, mu_k and law,
 * the excitation's cosine amplitude Pc (the slots unfactored, E and dense unset). */
static inline void eng1_init(eng1_model *O, double m, double c, double k, double N, double mu_s, double mu_k,
                             const dfo_friction_law *law, double Pc)
{
    memset(O, 0, sizeof *O);
    O->m = m;
    O->c = c;
    O->k = k;
    O->idx[0] = 0;
    O->w[0] = 1.0;
    O->row.nnz = 1;
    O->row.idx = O->idx;
    O->row.w = O->w;
    O->N[0] = N;
    O->mu_s[0] = mu_s;
    O->mu_k[0] = mu_k;
    O->Pc[0] = Pc;
    if (law) O->law[0] = *law;
}

/* ---- the operators ----------------------------------------------------------------------------- */

static inline void eng1_K(void *ctx, const double *x, double *y) { y[0] = ((const eng1_model *)ctx)->k * x[0]; }
static inline void eng1_C(void *ctx, const double *v, double *y) { y[0] = ((const eng1_model *)ctx)->c * v[0]; }
static inline void eng1_M(void *ctx, const double *a, double *y) { y[0] = ((const eng1_model *)ctx)->m * a[0]; }

static inline int eng1_factor(void *ctx, int slot, double cM, double cC, double cK)
{
    eng1_model *O = (eng1_model *)ctx;
    O->a[slot] = cM * O->m + cC * O->c + cK * O->k;
    O->inv_a[slot] = 1.0 / O->a[slot];
    return O->a[slot] > 0.0;
}

static inline void eng1_solve(void *ctx, int slot, const double *b, double *x)
{
    x[0] = b[0] * ((const eng1_model *)ctx)->inv_a[slot];
}

/* A Stribeck contact's friction problem through the engine's dense solver (its Newton on the implicit
 * force), from the problem's values: out of line, so that the arrays of the inlined caller do not
 * escape (the fused steps keep them in registers). */
typedef struct {
    eng_status st;
    int mode, pivots;
    double V1, f;
} eng1_stribeck_out;

#if defined(__GNUC__)
__attribute__((noinline, cold))
#endif
static eng1_stribeck_out eng1_stribeck_friction(const eng1_model *O, int slot, double h, double cM, double cC,
                                              double cK, double p_hat, int belt, double vb, double limit, double N,
                                              const dfo_friction_law *law, int what, int mode)
{
    eng1_stribeck_out o = {ENG_ERR_FRICTION, mode, 0, 0.0, 0.0};
    if (!O->E || !O->dense) return o;
    const double ph[1] = {p_hat}, vbs[1] = {vb}, lim[1] = {limit}, Ns[1] = {N};
    const eng_problem Q = {slot, h, cM, cC, cK, ph, belt ? vbs : NULL, lim, Ns, law, NULL};
    int md[1] = {mode}, piv = 0;
    double V1[1] = {0.0}, f[1] = {0.0};
    o.st = O->dense(O->E, &Q, what, md, V1, f, &piv);
    o.mode = md[0];
    o.pivots = piv;
    o.V1 = V1[0];
    o.f = f[0];
    return o;
}

/* The friction problem of the block: V1 = (p_hat + f) / a (times 1 / a). Held: V1 = vb, f the holding force
 * a vb - p_hat; sliding: f = -mode limit. The LCP: held when the holding force is within the limit,
 * else sliding the way the free motion goes. A Stribeck contact: the engine's dense solver (its
 * Newton on the implicit force). */
static inline eng_status eng1_friction(void *ctx, const eng_problem *P, int what, int *mode, double *V1, double *f,
                                      int *pivots)
{
    const eng1_model *O = (const eng1_model *)ctx;
    if (P->law && P->law[0].law == DFO_LAW_STRIBECK) {
        const eng1_stribeck_out o =
            eng1_stribeck_friction(O, P->slot, P->h, P->cM, P->cC, P->cK, P->p_hat[0], P->vb != NULL,
                                  P->vb ? P->vb[0] : 0.0, P->limit[0], P->N[0], P->law, what, mode[0]);
        if (o.st == ENG_OK) {
            if (what == ENG_SOLVE_LCP) mode[0] = o.mode;
            V1[0] = o.V1;
            f[0] = o.f;
        }
        if (pivots) *pivots = o.pivots;
        return o.st;
    }
    const double a = O->a[P->slot], ia = O->inv_a[P->slot];
    const double vb = P->vb ? P->vb[0] : 0.0, lim = P->limit[0], p = P->p_hat[0];
    if (pivots) *pivots = 0;
    if (!(lim > 0.0)) {
        f[0] = 0.0;
        V1[0] = p * ia;
        if (what == ENG_SOLVE_LCP) mode[0] = (V1[0] - vb > 0.0) - (V1[0] - vb < 0.0);
        return ENG_OK;
    }
    const double fh = a * vb - p;
    if (what == ENG_SOLVE_LCP) {
        const int md = (fabs(fh) <= lim) ? 0 : (fh > 0.0) ? -1 : 1;
        if (pivots && md != mode[0]) *pivots = 1;
        mode[0] = md;
    }
    if (mode[0] == 0) {
        V1[0] = vb;
        f[0] = fh;
    } else {
        f[0] = -mode[0] * lim;
        V1[0] = (p + f[0]) * ia;
    }
    return ENG_OK;
}

/* The block held at rest at X: its holding force balances the static force P(t) + F_ext - k X, with
 * P(t) = Pc cos(omega t + phi0) - Ps sin(omega t + phi0) written amp cos(omega t + phase) for
 * friction.h's dfo_next_breakaway. */
static inline double eng1_breakaway(void *ctx, const eng_harmonic *exc, const eng_state *s, const eng_inputs *in,
                                   const double *Fb)
{
    const eng1_model *O = (const eng1_model *)ctx;
    const double Pc = exc->Pc ? exc->Pc[0] : 0.0, Ps = exc->Ps ? exc->Ps[0] : 0.0;
    const double F = in->F_ext ? in->F_ext[0] : 0.0;
    dfo_harmonic P; /* (amplitude and phase without libm's hypot and atan2: the same bits everywhere) */
    if (Ps == 0.0) dfo_harmonic_init(&P, Pc, exc->omega, exc->phi0);
    else dfo_harmonic_init(&P, sqrt(Pc * Pc + Ps * Ps), exc->omega, exc->phi0 + dfo_atan2(Ps, Pc));
    dfo_loads L;
    dfo_loads_set(&L, F, 0.0, 0.0, 0.0);
    L.Fb = Fb[0];
    int dir;
    return dfo_next_breakaway(&P, &L, F - O->k * s->X[0], s->t, &dir);
}

#endif
