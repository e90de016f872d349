/* The chain on the friction engine: engine_step.h's schemes specialised by the chain's inline
 * operators (chain_engine_ops.h) as chain_eng_start, chain_eng_advance, ..., and chain.h's stepping
 * API over them: the start, advancing with held, ramped or belt inputs, input and belt changes, the
 * physical accelerations. The chain's switch callback is the engine's, given the block's position.
 * See chain_internal.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain_internal.h"

#include <string.h>

/* ---- the schemes, specialised ------------------------------------------------------------------ */

#define ENG_FN(name) chain_##name
#define ENG_CTX(E) ((E)->S.ops.ctx)
#define ENG_APPLY_K(E, x, y) chain_op_K(ENG_CTX(E), (x), (y))
#define ENG_APPLY_C(E, v, y) chain_op_C(ENG_CTX(E), (v), (y))
#define ENG_HAS_C(E) ((E)->S.ops.apply_C != NULL)
#define ENG_HAS_JENKINS(E) ((void)(E), 0) /* (no Jenkins contact: eng_create refuses one with the model's own friction solver) */
#define ENG_APPLY_M(E, a, y) chain_op_M(ENG_CTX(E), (a), (y))
#define ENG_ADD_MK(E, r, x, p) chain_op_add_mk(ENG_CTX(E), (r), (x), (p))
#define ENG_FACTOR(E, slot, cM, cC, cK) chain_op_factor(ENG_CTX(E), (slot), (cM), (cC), (cK))
#define ENG_SOLVE(E, slot, b, x) chain_op_solve(ENG_CTX(E), (slot), (b), (x))
#define ENG_HAS_FRICTION(E) ((void)(E), 1)
#define ENG_FRICTION(E, P, what, mode, V1, f, pivots) \
    chain_op_friction(ENG_CTX(E), (P), (what), (mode), (V1), (f), (pivots))
#define ENG_STEP_HELD(E, F, s) chain_op_step_held(ENG_CTX(E), (F), (s))
#define ENG_STEP_RUN(E, F, s) chain_op_step_run(ENG_CTX(E), (F), (s))
#define ENG_CONTACT_BREAKAWAY(E, j, s, in, Fb) chain_op_contact_breakaway(ENG_CTX(E), (j), &(E)->S.exc, (s), (in), (Fb))
#define ENG_HAS_BREAKAWAY(E) ((E)->S.ops.breakaway != NULL)
/* contact j's row is e_j (a span's too: its contacts are its blocks, in the same local numbering):
 * row_dot's 0.0 + 1.0 x_j */
#define ENG_ROW_DOT(E, j, x) ((void)(E), 0.0 + (x)[(j)])
#define ENG_BREAKAWAY(E, s, in, Fb) chain_op_breakaway(ENG_CTX(E), &(E)->S.exc, (s), (in), (Fb))

#include "engine_step.h"

/* ---- the chain's API ------------------------------------------------------------------------------ */

static chain_status status_of(eng_status st)
{
    switch (st) {
    case ENG_OK: return CHAIN_OK;
    case ENG_ERR_LCP: return CHAIN_ERR_LCP;
    case ENG_ERR_NO_PROGRESS: return CHAIN_ERR_NO_PROGRESS;
    case ENG_ERR_NONFINITE: return CHAIN_ERR_NONFINITE;
    case ENG_ERR_RESOLUTION: return CHAIN_ERR_RESOLUTION;
    case ENG_SWITCHED: return CHAIN_SWITCHED;
    case ENG_ERR_FRICTION: return CHAIN_ERR_FRICTION;
    case ENG_ERR_BAD_INPUT: return CHAIN_ERR_NONFINITE;
    }
    return CHAIN_ERR_NONFINITE;
}

/* The chain's switch callback behind the engine's. */
typedef struct {
    chain_switch_fn fn;
    void *ctx;
} switch_relay;

static void relay(void *ctx, double t, size_t contact, const eng_state *s, int from, int to)
{
    const switch_relay *r = (const switch_relay *)ctx;
    r->fn(r->ctx, t, contact, s->X[contact], from, to);
}

static void hooks_of(const switch_relay *r, int stop_at_switch, eng_hooks *hk)
{
    memset(hk, 0, sizeof *hk);
    hk->on_switch = r->fn ? relay : NULL;
    hk->switch_ctx = (void *)r;
    hk->stop_at_switch = stop_at_switch;
}

void chain_start_belt(chain_model *M, const chain_inputs *in, const double *vb, double t0, chain_state *s)
{
    chain_loads_init(M, in);
    eng_inputs ei;
    chain_eng_inputs(in, NULL, vb, &ei);
    chain_eng_start(M->E, &ei, t0, M->x0, M->v0, s);
}

void chain_start(chain_model *M, const chain_inputs *in, double t0, chain_state *s)
{
    chain_start_belt(M, in, NULL, t0, s);
}

chain_status chain_advance_belt(chain_model *M, const chain_inputs *in, const chain_ramp *ramp, const double *vb,
                                chain_state *s, double t_target, int stop_at_switch, chain_switch_fn on_switch,
                                void *ctx)
{
    eng_inputs ei;
    chain_eng_inputs(in, ramp, vb, &ei);
    const switch_relay r = {on_switch, ctx};
    eng_hooks hk;
    hooks_of(&r, stop_at_switch, &hk);
    return status_of(chain_eng_advance(M->E, &ei, s, t_target, &hk));
}

chain_status chain_advance_ramped(chain_model *M, const chain_inputs *in, const chain_ramp *ramp, chain_state *s,
                                  double t_target, int stop_at_switch, chain_switch_fn on_switch, void *ctx)
{
    return chain_advance_belt(M, in, ramp, NULL, s, t_target, stop_at_switch, on_switch, ctx);
}

chain_status chain_advance(chain_model *M, const chain_inputs *in, chain_state *s, double t_target,
                           int stop_at_switch, chain_switch_fn on_switch, void *ctx)
{
    return chain_advance_belt(M, in, NULL, NULL, s, t_target, stop_at_switch, on_switch, ctx);
}

void chain_new_belt(chain_model *M, const chain_inputs *in, const double *vb_old, const double *vb_new, chain_state *s,
                    chain_switch_fn on_switch, void *ctx)
{
    chain_loads_init(M, in);
    eng_inputs old_in, new_in;
    chain_eng_inputs(in, NULL, vb_old, &old_in);
    chain_eng_inputs(in, NULL, vb_new, &new_in);
    const switch_relay r = {on_switch, ctx};
    eng_hooks hk;
    hooks_of(&r, 0, &hk);
    chain_eng_new_inputs(M->E, &old_in, &new_in, s, &hk);
}

void chain_new_inputs_ramped(const chain_model *M, const chain_inputs *old_in, const chain_inputs *new_in,
                             const chain_ramp *ramp, const double *vb, chain_state *s)
{
    eng_inputs o, n;
    chain_eng_inputs(old_in, NULL, vb, &o);
    chain_eng_inputs(new_in, ramp, vb, &n);
    chain_eng_new_inputs(M->E, &o, &n, s, NULL);
}

void chain_new_inputs(const chain_model *M, const chain_inputs *old_in, const chain_inputs *new_in, chain_state *s)
{
    chain_new_inputs_ramped(M, old_in, new_in, NULL, NULL, s);
}

void chain_accelerations(chain_model *M, const chain_inputs *in, const double *vb, const chain_state *s, double *a)
{
    chain_loads_init(M, in);
    eng_inputs ei;
    chain_eng_inputs(in, NULL, vb, &ei);
    chain_eng_accelerations(M->E, &ei, s, a);
}
