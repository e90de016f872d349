/* The oscillator's operators for the friction engine (osc_engine.h): one mass m on a spring k and a
 * damper c, its contact to the ground or its belt (w = 1): M_hat a scalar, the friction problem of
 * one contact in closed form (the 2 x 2 LCP; a Stribeck contact through the engine's dense solver,
 * when the model knows its engine), the closed-form breakaway of the block at rest. Static inline:
 * through eng_ops's function pointers (engine.c) or inlined into engine_step.h (osc_engine.c; the
 * bench's block), the same arithmetic. Plain C, no FMI types. */
#ifndef DFO_OSC_ENGINE_OPS_H
#define DFO_OSC_ENGINE_OPS_H

#include "engine.h"
#include "scheme_state.h"

#include <math.h>
#include <stddef.h>

typedef struct {
    double m, c, k;
    double a[ENG_NSLOTS];        /* each slot's factor cM m + cC c + cK k */
    double inv_a[ENG_NSLOTS];    /* and its inverse (a solve is a product, as newmark's 1 / m_hat was) */
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

/* ---- the observables -------------------------------------------------------------------------- */

/* The part of [a, b] inside the window [w0, w1] (comparisons, not fmin/fmax: those are library calls
 * without -ffinite-math-only). */
static inline double osc_in_window(double w0, double w1, double a, double b)
{
    const double lo = (a > w0) ? a : w0, hi = (b < w1) ? b : w1;
    return (hi > lo) ? hi - lo : 0.0;
}

/* The in-FMU observables of the window [w0, w1], kept in the state s (scheme_state.h) from the
 * engine's phases: the observer's context (osc_engine.h's osc_eng_observe). */
typedef struct {
    double w0, w1;
    dfo_state *s;
} osc_observables;

/* The observables as one phase after another updates them: the window and the state's values, kept
 * in locals over a run of the engine's fused steps (ENG_OBS_RUN, osc_engine.c) so that they stay in
 * registers, written back when the run ends (on: the observer is osc_eng_observe's; else the steps
 * call the observer's function). */
typedef struct {
    int on, observed;
    int inside;  /* the run's last phase was sampled and ended at or after w0 (the next ones end after it) */
    int mode_in; /* that phase's mode at its start */
    double w0, w1, stuck_from, t_stuck, x_max, x_min, E_friction;
} osc_obs_vals;

/* the state's observables osc_obs_vals keeps (every field but on, inside, w0, w1) */
#define OSC_OBS_FIELDS(X) X(stuck_from) X(t_stuck) X(x_max) X(x_min) X(E_friction) X(observed)

static inline void osc_obs_load(osc_obs_vals *R, const osc_observables *O)
{
    const dfo_state *s = O->s;
    R->w0 = O->w0;
    R->w1 = O->w1;
#define OSC_OBS_LOAD_(f) R->f = s->f;
    OSC_OBS_FIELDS(OSC_OBS_LOAD_)
#undef OSC_OBS_LOAD_
}

static inline void osc_obs_store(const osc_obs_vals *R, const osc_observables *O)
{
    dfo_state *s = O->s;
#define OSC_OBS_STORE_(f) s->f = R->f;
    OSC_OBS_FIELDS(OSC_OBS_STORE_)
#undef OSC_OBS_STORE_
}

/* A phase [ta, tb] that overlaps the window (the engine calls no other): the stuck stretch opened or
 * closed at its start (its part inside the window added in one piece when a phase in another mode
 * begins, so that the stuck time is the same however the steps are taken), and where it ends inside
 * the window X sampled and the friction's work on the relative motion counted (none where it ends
 * on the window's start). */
static inline void osc_obs_stuck(osc_obs_vals *R, int mode0, double ta)
{
    if (mode0 == 0) {
        if (isnan(R->stuck_from)) R->stuck_from = ta;
    } else if (!isnan(R->stuck_from)) {
        const double d = osc_in_window(R->w0, R->w1, R->stuck_from, ta);
        if (d > 0.0) R->t_stuck += d;
        R->stuck_from = NAN;
    }
}

/* X sampled at the end of a phase inside the window (a sample taken before), and the friction's
 * work counted (work: the phase ends after the window's start) */
static inline void osc_obs_sample(osc_obs_vals *R, const eng_phase *ph, int work)
{
    const double X = ph->X1[0], dX = X - ph->X0[0];
    double W = ph->f[0] * (ph->v_belt ? dX - ph->v_belt[0] * (ph->tb - ph->ta) : dX);
    if (!work) W = 0.0;
    R->x_max = (X > R->x_max) ? X : R->x_max;
    R->x_min = (X < R->x_min) ? X : R->x_min;
    R->E_friction -= W;
}

static inline void osc_obs_phase(osc_obs_vals *R, const eng_phase *ph)
{
    const double tb = ph->tb;
    osc_obs_stuck(R, ph->mode0[0], ph->ta);
    if (tb < R->w0 || tb > R->w1) return;
    if (!R->observed) { R->x_max = R->x_min = ph->X1[0]; R->observed = 1; }
    osc_obs_sample(R, ph, tb > R->w0);
}

/* The observer's call for one phase (ctx: an osc_observables) */
static inline void osc_observe_phase(void *ctx, const eng_phase *ph, const eng_state *es)
{
    const osc_observables *O = (const osc_observables *)ctx;
    (void)es;
    osc_obs_vals R;
    osc_obs_load(&R, O);
    osc_obs_phase(&R, ph);
    osc_obs_store(&R, O);
}

/* ---- the operators ----------------------------------------------------------------------------- */

static inline void osc_K(void *ctx, const double *x, double *y) { y[0] = ((const osc_eng_model *)ctx)->k * x[0]; }
static inline void osc_C(void *ctx, const double *v, double *y) { y[0] = ((const osc_eng_model *)ctx)->c * v[0]; }
static inline void osc_M(void *ctx, const double *a, double *y) { y[0] = ((const osc_eng_model *)ctx)->m * a[0]; }

static inline int osc_factor(void *ctx, int slot, double cM, double cC, double cK)
{
    osc_eng_model *O = (osc_eng_model *)ctx;
    O->a[slot] = cM * O->m + cC * O->c + cK * O->k;
    O->inv_a[slot] = 1.0 / O->a[slot];
    return O->a[slot] > 0.0;
}

static inline void osc_solve(void *ctx, int slot, const double *b, double *x)
{
    x[0] = b[0] * ((const osc_eng_model *)ctx)->inv_a[slot];
}

/* A Stribeck contact's friction problem through the engine's dense solver (its Newton on the implicit
 * force), from the problem's values: out of line, so that the arrays of the inlined caller do not
 * escape (the fused steps keep them in registers). */
typedef struct {
    eng_status st;
    int mode, pivots;
    double V1, f;
} osc_stribeck_out;

#if defined(__GNUC__)
__attribute__((noinline, cold))
#endif
static osc_stribeck_out osc_stribeck_friction(const osc_eng_model *O, int slot, double h, double cM, double cC,
                                              double cK, double p_hat, int belt, double vb, double limit, double N,
                                              const dfo_friction_law *law, int what, int mode)
{
    osc_stribeck_out o = {ENG_ERR_FRICTION, mode, 0, 0.0, 0.0};
    if (!O->E) return o;
    const double ph[1] = {p_hat}, vbs[1] = {vb}, lim[1] = {limit}, Ns[1] = {N};
    const eng_problem Q = {slot, h, cM, cC, cK, ph, belt ? vbs : NULL, lim, Ns, law, NULL};
    int md[1] = {mode}, piv = 0;
    double V1[1] = {0.0}, f[1] = {0.0};
    o.st = osc_eng_dense_friction(O->E, &Q, what, md, V1, f, &piv);
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
static inline eng_status osc_friction(void *ctx, const eng_problem *P, int what, int *mode, double *V1, double *f,
                                      int *pivots)
{
    const osc_eng_model *O = (const osc_eng_model *)ctx;
    if (P->law && P->law[0].law == DFO_LAW_STRIBECK) {
        const osc_stribeck_out o =
            osc_stribeck_friction(O, P->slot, P->h, P->cM, P->cC, P->cK, P->p_hat[0], P->vb != NULL,
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
static inline double osc_breakaway(void *ctx, const eng_harmonic *exc, const eng_state *s, const eng_inputs *in,
                                   const double *Fb)
{
    const osc_eng_model *O = (const osc_eng_model *)ctx;
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
