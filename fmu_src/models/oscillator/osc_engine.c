/* The oscillator as a model of the friction engine. See osc_engine.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "osc_engine.h"

#include <math.h>
#include <string.h>

#define SNAP_MAX_REL_H 1e-5 /* the oscillator's snap of a requested time to the grid (newmark.h) */
#define SNAP_MIN_REL_H 1e-7
#define SNAP_EPS_T 0x1p16

/* ---- set-up ------------------------------------------------------------------------------------ */

eng *osc_eng_create(const dfo_model *M, osc_eng_model *O, const eng_alloc *al, const char **err)
{
    const dfo_params *p = &M->p;
    eng1_init(O, p->m, p->c, p->k, p->N, p->mu_s, M->mu_k, &M->law, p->P0);
    eng_setup S;
    memset(&S, 0, sizeof S);
    S.n = 1;
    S.nc = 1;
    /* (no damping: no C, so that its terms and the accelerations only they read are not computed) */
    const eng_ops ops = {O, eng1_K, (p->c != 0.0) ? eng1_C : NULL, eng1_M, eng1_factor, eng1_solve, eng1_friction, eng1_breakaway, 1};
    S.ops = ops;
    S.rows = &O->row;
    S.exc.omega = p->omega;
    S.exc.phi0 = p->phi;
    S.exc.Pc = O->Pc;
    S.N = O->N;
    S.mu_s = O->mu_s;
    S.mu_k = O->mu_k;
    S.law = M->stribeck ? O->law : NULL;
    S.h = p->h;
    S.alpha = p->alpha;
    S.scheme = p->scheme;
    S.friction_updates = p->frictionUpdates;
    S.fast_paths = M->fast;
    S.rate_max = M->rate_max;
    S.snap_max_rel_h = SNAP_MAX_REL_H;
    S.snap_min_rel_h = SNAP_MIN_REL_H;
    S.snap_eps_t = SNAP_EPS_T;
    O->E = eng_create(&S, al, err);
    O->dense = osc_eng_dense_friction;
    return O->E;
}

void osc_eng_inputs(const dfo_inputs *u, osc_eng_inbuf *b, eng_inputs *in)
{
    memset(b, 0, sizeof *b);
    memset(in, 0, sizeof *in);
    b->F[0] = u->F_ext;
    b->N[0] = u->N_ext;
    b->vb[0] = u->v_belt;
    in->F_ext = u->F_ext_set ? b->F : NULL;
    in->N_ext = u->N_ext_set ? b->N : NULL;
    in->v_belt = u->v_belt_set ? b->vb : NULL;
    if (!u->ramp) return;
    for (int d = 0; d < 2; d++) {
        b->dF[d][0] = u->F_ext_d[d];
        b->dN[d][0] = u->N_ext_d[d];
        in->dF_ext[d] = b->dF[d];
        in->dN_ext[d] = b->dN[d];
    }
    in->t_ref = u->t_d;
}

void osc_eng_observe(void *ctx, const eng_phase *ph, const eng_state *s) { osc_observe_phase(ctx, ph, s); }

/* The observables over a run of fused steps (engine_step.h's ENG_OBS_RUN): in locals where the
 * observer is osc_eng_observe, else R unused (the observer's own function called) */
static inline void osc_obs_run_begin(const eng_observer *obs, osc_obs_vals *R)
{
    memset(R, 0, sizeof *R);
    R->on = obs && obs->on_phase == osc_eng_observe;
    if (R->on) osc_obs_load(R, (const osc_observables *)obs->ctx);
}

/* A phase of the run. After a phase sampled inside the window (inside), one in the same mode leaves
 * the stuck stretch as it is (open in mode 0 it stays open, in a sliding mode none is open): only its
 * end's side of the window tested, X sampled and the work counted (it ends after w0). Any other
 * phase (the run's first, a mode other than the last phase's) as osc_obs_phase takes it. */
static inline void osc_obs_run_phase(osc_obs_vals *R, const eng_phase *ph)
{
    if (R->inside && ph->mode0[0] == R->mode_in) {
        if (ph->tb > R->w1) return;
        osc_obs_sample(R, ph, 1);
        return;
    }
    osc_obs_phase(R, ph);
    R->inside = R->observed && ph->tb >= R->w0;
    R->mode_in = ph->mode0[0];
}

/* Another observer's call for a phase of the run, out of line and from the phase's values (the run's
 * arrays, whose addresses it does not take, stay in registers) */
#if defined(__GNUC__)
__attribute__((noinline, cold))
#endif
static void osc_obs_run_call(const eng_observer *obs, double ta, double tb, double X0, double X1, int mode0, double f,
                             const double *v_belt, const eng_state *s)
{
    const double x0[1] = {X0}, x1[1] = {X1}, f1[1] = {f};
    const int m0[1] = {mode0};
    const eng_phase ph = {ta, tb, x0, x1, m0, f1, v_belt, NULL, NULL};
    obs->on_phase(obs->ctx, &ph, s);
}

/* ---- the schemes, specialised ------------------------------------------------------------------ */

#define ENG_FN(name) osc_##name
#define ENG_N(E) ((void)(E), (size_t)1)
#define ENG_NC(E) ((void)(E), (size_t)1)
#define ENG_FUSED_N 1
#define ENG_OBSERVE(obs, ph, s)                                                                                      \
    (((obs)->on_phase == osc_eng_observe) ? osc_observe_phase((obs)->ctx, (ph), (s))                                \
                                          : (obs)->on_phase((obs)->ctx, (ph), (s)))
#define ENG_OBS_RUN osc_obs_vals
#define ENG_OBS_RUN_BEGIN(obs, R, s) ((void)(s), osc_obs_run_begin((obs), &(R)))
#define ENG_OBS_RUN_PHASE(obs, R, ph, s)                                                                            \
    ((R).on ? osc_obs_run_phase(&(R), (ph))                                                                           \
            : osc_obs_run_call((obs), (ph)->ta, (ph)->tb, (ph)->X0[0], (ph)->X1[0], (ph)->mode0[0], (ph)->f[0],      \
                               (ph)->v_belt, (s)))
#define ENG_OBS_RUN_END(obs, R) ((R).on ? osc_obs_store(&(R), (const osc_observables *)(obs)->ctx) : (void)0)
#define ENG_ROW_DOT(E, j, x) ((void)(E), (void)(j), 0.0 + (x)[0]) /* row_dot of w = 1 */
#define ENG_FUSED_NC 1
#define ENG_CTX(E) ((E)->S.ops.ctx)
#define ENG_APPLY_K(E, x, y) eng1_K(ENG_CTX(E), (x), (y))
#define ENG_APPLY_C(E, v, y) eng1_C(ENG_CTX(E), (v), (y))
#define ENG_HAS_C(E) ((void)(E), 1) /* (c v whatever c is; ops.apply_C: NULL where c = 0) */
#define ENG_HAS_JENKINS(E) ((void)(E), 0) /* (no Jenkins contact: eng_create refuses one with the model's own friction solver) */
#define ENG_APPLY_M(E, a, y) eng1_M(ENG_CTX(E), (a), (y))
#define ENG_FACTOR(E, slot, cM, cC, cK) eng1_factor(ENG_CTX(E), (slot), (cM), (cC), (cK))
#define ENG_SOLVE(E, slot, b, x) eng1_solve(ENG_CTX(E), (slot), (b), (x))
#define ENG_HAS_FRICTION(E) ((void)(E), 1)
#define ENG_FRICTION(E, P, what, mode, V1, f, pivots) eng1_friction(ENG_CTX(E), (P), (what), (mode), (V1), (f), (pivots))
#define ENG_HAS_BREAKAWAY(E) ((E)->S.ops.breakaway != NULL)
#define ENG_BREAKAWAY(E, s, in, Fb) eng1_breakaway(ENG_CTX(E), &(E)->S.exc, (s), (in), (Fb))

#include "engine_step.h"
