/* The oscillator's Bossak schemes (paper, consistent, located) stepped by the friction engine: its
 * model of osc_engine.h (the engine's schemes specialised by the block's operators), the state and
 * the inputs mapped onto the engine's, the observables kept by the engine's observer hook and the
 * switches reported through its switch hook. See newmark.h (dfo_bossak_advance, dfo_new_inputs)
 * and osc_bossak.h (the engine a caller keeps; without one, made on the stack per call, so that a
 * dfo_model stays a plain value without pointers). */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "newmark.h"
#include "osc_bossak.h"
#include "osc_engine.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

/* ---- the engine ---------------------------------------------------------------------------------- */

/* calloc's: the arena is zeroed whole when it is reset (engine_of), in one memset rather than one per
 * array, and nothing is released before the next reset */
static void *arena_allocate(void *env, size_t nobj, size_t size)
{
    osc_arena *a = (osc_arena *)env;
    if (size != 0 && nobj > SIZE_MAX / size) return NULL;
    const size_t words = (nobj * size + sizeof(double) - 1) / sizeof(double);
    if (words > a->cap - a->used) return NULL;
    double *p = a->buf + a->used;
    a->used += words;
    return p;
}

static void arena_release(void *env, void *obj)
{
    (void)env;
    (void)obj;
}

/* The engine of c for the model M: kept where c was made for M at its place, else made (NULL: the
 * model's engine cannot be made, which a valid model never meets). */
static eng *engine_of(osc_bossak_engine *c, const dfo_model *M)
{
    if (c->self == c && c->E && memcmp(&c->M, M, sizeof *M) == 0) return c->E;
    c->self = NULL;
    memset(c->buf, 0, sizeof c->buf);
    c->ar.buf = c->buf;
    c->ar.used = 0;
    c->ar.cap = OSC_BOSSAK_ARENA;
    const eng_alloc al = {arena_allocate, arena_release, &c->ar};
    c->E = osc_eng_create(M, &c->O, &al, NULL);
    if (!c->E) return NULL;
    c->M = *M;
    c->self = c;
    return c->E;
}

/* The engine's state of the block: its arrays of length one. */
typedef struct {
    double X, V, A, hA, F, t_stick, t_break;
    int mode, break_dir;
} block_arrays;

/* One call's engine (the caller's, or its own) and the state mapped onto the engine's. */
typedef struct {
    osc_bossak_engine own;
    eng *E;
    block_arrays a;
    eng_state es;
} stepper;

static int stepper_init(stepper *P, const dfo_model *M, osc_bossak_engine *cache)
{
    if (!cache) {
        P->own.self = NULL;
        P->own.E = NULL;
        cache = &P->own;
    }
    P->E = engine_of(cache, M);
    return P->E != NULL;
}

/* The scalars the engine's state and dfo_state share: (eng_state's, dfo_state's). */
#define SHARED_SCALARS(DO)                                                                                           \
    DO(t, t) DO(n_grid, n) DO(t_switch, t_switch) DO(steps, steps) DO(solves, lcp_solves) DO(exc_n, exc_n)         \
    DO(exc_c, exc_c) DO(exc_s, exc_s)
/* The block's arrays of length one: (eng_state's, dfo_state's). */
#define SHARED_ARRAYS(DO) DO(X, X) DO(V, V) DO(A, A) DO(hA, hA) DO(F, F) DO(mode, mode)

static void state_to_engine(stepper *P, const dfo_state *s)
{
    eng_state *e = &P->es;
    memset(e, 0, sizeof *e);
    e->n = e->nc = 1;
    e->t0 = s->t0;
#define TO_ENG_SCALAR(ef, sf) e->ef = s->sf;
#define TO_ENG_ARRAY(ef, sf) P->a.ef = s->sf; e->ef = &P->a.ef;
    SHARED_SCALARS(TO_ENG_SCALAR)
    SHARED_ARRAYS(TO_ENG_ARRAY)
#undef TO_ENG_SCALAR
#undef TO_ENG_ARRAY
    /* written by the engine only (its schemes keep no breakaway across calls) */
    P->a.t_stick = s->t;
    P->a.t_break = NAN;
    P->a.break_dir = 0;
    e->t_stick = &P->a.t_stick;
    e->t_break = &P->a.t_break;
    e->break_dir = &P->a.break_dir;
    e->J = NULL; /* no Bossak scheme propagates the Jacobian (eng_caps): dfo_state's J is left */
    e->stick_tb = NAN; /* (dfo_bossak_advance's: kept_stick) */
}

static void state_from_engine(const stepper *P, dfo_state *s)
{
    const eng_state *e = &P->es;
#define FROM_ENG_SCALAR(ef, sf) s->sf = e->ef;
#define FROM_ENG_ARRAY(ef, sf) s->sf = P->a.ef;
    SHARED_SCALARS(FROM_ENG_SCALAR)
    SHARED_ARRAYS(FROM_ENG_ARRAY)
#undef FROM_ENG_SCALAR
#undef FROM_ENG_ARRAY
}

static dfo_status status_of(eng_status st)
{
    switch (st) {
    case ENG_OK:
    case ENG_SWITCHED: return DFO_OK;
    case ENG_ERR_NO_PROGRESS: return DFO_ERR_NO_PROGRESS;
    case ENG_ERR_NONFINITE: return DFO_ERR_NONFINITE;
    case ENG_ERR_RESOLUTION: return DFO_ERR_RESOLUTION;
    case ENG_ERR_LCP:
    case ENG_ERR_FRICTION:
    case ENG_ERR_BAD_INPUT: break;
    }
    return DFO_ERR_LCP;
}

/* ---- the hooks: switches (the observables: osc_engine.h's osc_eng_observe) ------------------------- */

typedef struct {
    const dfo_model *M;
    dfo_state *s;           /* the observables' home */
    dfo_switch_fn on_switch;
    void *switch_ctx;
    osc_observables obs;    /* the observer's context */
} hook_ctx;

/* A switch: reported with the block's position, counted as a transition where it lies in the window
 * (t_obs_start, t_obs_stop]. */
static void on_switch(void *ctx, double t, size_t contact, const eng_state *es, int from, int to)
{
    const hook_ctx *H = (const hook_ctx *)ctx;
    const dfo_params *p = &H->M->p;
    (void)contact;
    if (p->observe && t > p->t_obs_start && t <= p->t_obs_stop) H->s->transitions++;
    if (H->on_switch) H->on_switch(H->switch_ctx, t, es->X[0], from, to);
}

static void hooks_of(const dfo_model *M, hook_ctx *H, eng_observer *obs, eng_hooks *hk)
{
    memset(hk, 0, sizeof *hk);
    hk->on_switch = on_switch;
    hk->report_turns = 1; /* a block without friction: its turns are mode changes (as the exact scheme's) */
    hk->switch_ctx = H;
    if (!M->p.observe) return;
    H->obs.w0 = M->p.t_obs_start;
    H->obs.w1 = M->p.t_obs_stop;
    H->obs.s = H->s;
    obs->t_start = M->p.t_obs_start;
    obs->t_stop = M->p.t_obs_stop;
    obs->on_phase = osc_eng_observe;
    obs->ctx = &H->obs;
    obs->velocities = 0; /* (its extremes sampled at the phases' ends) */
    hk->obs = obs;
}

/* ---- the stick's breakaway, kept in dfo_state ---------------------------------------------------- */

/* The key of the block's stick breakaway at the state and inputs: the constant part of the static
 * force F_ext - k X and the limit (the exact scheme's stick_C, stick_Fb). */
static void stick_key(const dfo_model *M, const dfo_inputs *in, const dfo_state *s, double *C, double *Fb)
{
    dfo_loads L;
    dfo_loads_init(&L, M, in);
    *C = L.F_ext - M->p.k * s->X;
    *Fb = L.Fb;
}

/* The breakaway of the block's stick the state keeps (dfo_state.stick_tb, the engine's stick_tb) where
 * it was found for these inputs at this position (stick_key's); else NaN (to be found). */
static double kept_stick(const dfo_model *M, const dfo_inputs *in, const dfo_state *s)
{
    if (in->ramp || isnan(s->stick_tb)) return NAN;
    double C, Fb;
    stick_key(M, in, s, &C, &Fb);
    return (s->stick_C == C && s->stick_Fb == Fb) ? s->stick_tb : NAN;
}

/* The engine's stick breakaway tb kept in the state with its key */
static void keep_stick(const dfo_model *M, const dfo_inputs *in, double tb, dfo_state *s)
{
    s->stick_tb = tb;
    stick_key(M, in, s, &s->stick_C, &s->stick_Fb);
    s->stick_dir = 0;
}

/* ---- the entry points ----------------------------------------------------------------------------- */

/* One call: the engine, its hooks, the state mapped onto the engine's. */
typedef struct {
    stepper P;
    hook_ctx H;
    eng_observer obs;
    eng_hooks hk;
} call;

static int call_begin(call *C, const dfo_model *M, osc_bossak_engine *cache, dfo_state *s, dfo_switch_fn on_switch_fn,
                      void *switch_ctx)
{
    if (!stepper_init(&C->P, M, cache)) return 0;
    const hook_ctx H = {M, s, on_switch_fn, switch_ctx, {0.0, 0.0, NULL}};
    C->H = H;
    hooks_of(M, &C->H, &C->obs, &C->hk);
    state_to_engine(&C->P, s);
    return 1;
}

dfo_status dfo_bossak_advance(const dfo_model *M, osc_bossak_engine *cache, const dfo_inputs *in, dfo_state *s,
                              double t_target, dfo_switch_fn on_switch_fn, void *switch_ctx)
{
    call C;
    if (!call_begin(&C, M, cache, s, on_switch_fn, switch_ctx)) return DFO_ERR_LCP;
    osc_eng_inbuf ib;
    eng_inputs ei;
    osc_eng_inputs(in, &ib, &ei);
    C.P.es.stick_tb = kept_stick(M, in, s);
    C.hk.stick_kept = 1;
    const eng_status st = osc_eng_advance(C.P.E, &ei, &C.P.es, t_target, &C.hk);
    state_from_engine(&C.P, s);
    keep_stick(M, in, C.P.es.stick_tb, s);
    if (st != ENG_OK) return status_of(st);
    if (!(fabs(s->X) <= DBL_MAX && fabs(s->V) <= DBL_MAX && fabs(s->A) <= DBL_MAX && fabs(s->F) <= DBL_MAX))
        return DFO_ERR_NONFINITE;
    /* the acceleration output too must be representable */
    if (!isfinite(dfo_acceleration(M, in, s))) return DFO_ERR_NONFINITE;
    return DFO_OK;
}

void dfo_new_inputs_cached(const dfo_model *M, osc_bossak_engine *cache, const dfo_inputs *old_in,
                           const dfo_inputs *new_in, dfo_state *s)
{
    call C;
    if (M->p.scheme == DFO_SCHEME_EXACT || !call_begin(&C, M, cache, s, NULL, NULL)) return;
    osc_eng_inbuf ib_old, ib_new;
    eng_inputs e_old, e_new;
    osc_eng_inputs(old_in, &ib_old, &e_old);
    osc_eng_inputs(new_in, &ib_new, &e_new);
    osc_eng_new_inputs(C.P.E, &e_old, &e_new, &C.P.es, &C.hk);
    state_from_engine(&C.P, s);
    s->stick_tb = NAN; /* (found anew for the new inputs) */
}

void dfo_new_inputs(const dfo_model *M, const dfo_inputs *old_in, const dfo_inputs *new_in, dfo_state *s)
{
    dfo_new_inputs_cached(M, NULL, old_in, new_in, s);
}

double dfo_stuck_time(const dfo_model *M, const dfo_state *s)
{
    return isnan(s->stuck_from) ? s->t_stuck : s->t_stuck + osc_in_window(M->p.t_obs_start, M->p.t_obs_stop, s->stuck_from, s->t);
}

double dfo_stick_fraction(const dfo_model *M, const dfo_state *s)
{
    const double span = fmin(s->t, M->p.t_obs_stop) - M->p.t_obs_start;
    return span > 0.0 ? dfo_stuck_time(M, s) / span : 0.0;
}
