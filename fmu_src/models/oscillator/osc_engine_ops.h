/* The oscillator's operators for the friction engine (osc_engine.h): one mass m on a spring k and a
 * damper c, its contact to the ground or its belt (w = 1): M_hat a scalar, the friction problem of
 * one contact in closed form (the 2 x 2 LCP; a Stribeck contact through the engine's dense solver,
 * when the model knows its engine), the closed-form breakaway of the block at rest. Static inline:
 * through eng_ops's function pointers (engine.c) or inlined into engine_step.h (osc_engine.c; the
 * bench's block), the same arithmetic. Plain C, no FMI types. */
#ifndef DFO_OSC_ENGINE_OPS_H
#define DFO_OSC_ENGINE_OPS_H

#include "engine.h"

#include <math.h>
#include <stddef.h>

typedef struct {
    double m, c, k;
    double a[ENG_NSLOTS];        /* each slot's factor cM m + cC c + cK k */
    size_t idx[1];
    double w[1];
    eng_row row;
    double N[1], mu_s[1], mu_k[1], Pc[1];
    dfo_friction_law law[1];
    eng *E;                      /* the engine (the Stribeck contact's solver), set by osc_eng_create */
} osc_eng_model;

/* engine_step.h's schemes specialised by these operators (osc_engine.c): osc_eng_dense_friction, the
 * Stribeck contact's solver, and the rest (osc_engine.h) */
ENG_DECLARE_SCHEMES(osc_);

/* ---- the operators ----------------------------------------------------------------------------- */

static inline void osc_K(void *ctx, const double *x, double *y) { y[0] = ((const osc_eng_model *)ctx)->k * x[0]; }
static inline void osc_C(void *ctx, const double *v, double *y) { y[0] = ((const osc_eng_model *)ctx)->c * v[0]; }
static inline void osc_M(void *ctx, const double *a, double *y) { y[0] = ((const osc_eng_model *)ctx)->m * a[0]; }

static inline int osc_factor(void *ctx, int slot, double cM, double cC, double cK)
{
    osc_eng_model *O = (osc_eng_model *)ctx;
    O->a[slot] = cM * O->m + cC * O->c + cK * O->k;
    return O->a[slot] > 0.0;
}

static inline void osc_solve(void *ctx, int slot, const double *b, double *x)
{
    x[0] = b[0] / ((const osc_eng_model *)ctx)->a[slot];
}

/* The friction problem of the block: V1 = (p_hat + f) / a. Held: V1 = vb, f the holding force
 * a vb - p_hat; sliding: f = -mode limit. The LCP: held when the holding force is within the limit,
 * else sliding the way the free motion goes. A Stribeck contact: the engine's dense solver (its
 * Newton on the implicit force). */
static inline eng_status osc_friction(void *ctx, const eng_problem *P, int what, int *mode, double *V1, double *f,
                                      int *pivots)
{
    const osc_eng_model *O = (const osc_eng_model *)ctx;
    if (P->law && P->law[0].law == DFO_LAW_STRIBECK)
        return O->E ? osc_eng_dense_friction(O->E, P, what, mode, V1, f, pivots) : ENG_ERR_FRICTION;
    const double a = O->a[P->slot];
    const double vb = P->vb ? P->vb[0] : 0.0, lim = P->limit[0], p = P->p_hat[0];
    if (pivots) *pivots = 0;
    if (!(lim > 0.0)) {
        f[0] = 0.0;
        V1[0] = p / a;
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
        V1[0] = (p + f[0]) / a;
    }
    return ENG_OK;
}

/* The block held at rest at X: its holding force balances the static force P(t) + F_ext - k X, with
 * P(t) = Pc cos(omega t + phi0) - Ps sin(omega t + phi0) written amp cos(omega t + phase) for
 * friction.h's dfo_next_breakaway. */
static inline double osc_breakaway(void *ctx, const eng_harmonic *exc, const eng_state *s, const eng_inputs *in,
                                   const double *Fb)
{
    const osc_eng_model *O = (const osc_eng_model *)ctx;
    const double Pc = exc->Pc ? exc->Pc[0] : 0.0, Ps = exc->Ps ? exc->Ps[0] : 0.0;
    const double F = in->F_ext ? in->F_ext[0] : 0.0;
    dfo_harmonic P;
    if (Ps == 0.0) dfo_harmonic_init(&P, Pc, exc->omega, exc->phi0);
    else dfo_harmonic_init(&P, hypot(Pc, Ps), exc->omega, exc->phi0 + atan2(Ps, Pc));
    dfo_loads L;
    dfo_loads_set(&L, F, 0.0, 0.0, 0.0);
    L.Fb = Fb[0];
    int dir;
    return dfo_next_breakaway(&P, &L, F - O->k * s->X[0], s->t, &dir);
}

#endif
