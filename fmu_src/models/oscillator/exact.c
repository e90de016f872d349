/* The exact scheme's dispatcher: a call on a belt, without a spring or with one, held or polynomial
 * inputs, each to its phase's file. See exact.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "exact.h"
#include "exact_belt.h"
#include "exact_free.h"
#include "exact_spring.h"

#include <math.h>
#include <stddef.h>

dfo_status dfo_exact_advance(const dfo_model *M, const dfo_inputs *u, dfo_state *s, double t_target,
                             dfo_switch_fn on_switch, void *switch_ctx)
{
    const double vb = dfo_belt_speed(u);
    if (dfo_belt_on(u) && (vb != 0.0 || (s->mode == 0 && s->V != 0.0) || s->mode * s->V < 0.0))
        dfo_exact_belt_start(M, u, vb, s, on_switch, switch_ctx); /* (the belt may have changed) */
    if (vb != 0.0) return dfo_exact_belt_advance(M, u, NULL, s, t_target, on_switch, switch_ctx, vb);
    if (M->p.k == 0.0) return dfo_exact_free_advance(M, u, s, t_target, on_switch, switch_ctx); /* no spring */
    return dfo_exact_spring_advance(M, u, s, t_target, on_switch, switch_ctx);
}

dfo_status dfo_exact_advance_poly(const dfo_model *M, const dfo_inputs *u, const dfo_input_poly *q, dfo_state *s,
                                  double t_target, dfo_switch_fn on_switch, void *switch_ctx)
{
    if (!dfo_input_poly_active(q)) return dfo_exact_advance(M, u, s, t_target, on_switch, switch_ctx);
    /* (the FMU refuses non-finite derivatives with a sentence; here they would be a wrong motion) */
    if (!(isfinite(q->t0) && isfinite(q->F[0]) && isfinite(q->F[1]) && isfinite(q->N[0]) && isfinite(q->N[1])))
        return DFO_ERR_NONFINITE;
    const double vb = dfo_belt_speed(u);
    if (dfo_belt_on(u) && (vb != 0.0 || (s->mode == 0 && s->V != 0.0) || s->mode * s->V < 0.0))
        dfo_exact_belt_start(M, u, vb, s, on_switch, switch_ctx);
    if (vb != 0.0) return dfo_exact_belt_advance(M, u, q, s, t_target, on_switch, switch_ctx, vb);
    if (M->p.k == 0.0) return dfo_exact_free_advance_pieces(M, u, q, s, t_target, on_switch, switch_ctx); /* no spring */
    return dfo_exact_spring_advance_poly(M, u, q, s, t_target, on_switch, switch_ctx, 0.0);
}
