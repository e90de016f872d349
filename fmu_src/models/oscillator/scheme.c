/* The dispatching advance of every scheme. See scheme.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "scheme.h"
#include "exact.h"
#include "newmark.h"

dfo_status dfo_advance(const dfo_model *M, const dfo_inputs *in, dfo_state *s, double t_target,
                       dfo_switch_fn on_switch, void *switch_ctx)
{
    return dfo_advance_cached(M, NULL, in, s, t_target, on_switch, switch_ctx);
}

dfo_status dfo_advance_cached(const dfo_model *M, struct osc_bossak_engine_s *cache, const dfo_inputs *in,
                              dfo_state *s, double t_target, dfo_switch_fn on_switch, void *switch_ctx)
{
    if (M->p.scheme != DFO_SCHEME_EXACT) return dfo_bossak_advance(M, cache, in, s, t_target, on_switch, switch_ctx);
    if (!in->ramp) return dfo_exact_advance(M, in, s, t_target, on_switch, switch_ctx);
    /* varying inputs: its closed form with the input polynomials (the values at t_d held apart) */
    dfo_inputs held = *in;
    const dfo_input_poly q = {in->t_d, {in->F_ext_d[0], in->F_ext_d[1]}, {in->N_ext_d[0], in->N_ext_d[1]}};
    held.F_ext_d[0] = held.F_ext_d[1] = held.N_ext_d[0] = held.N_ext_d[1] = 0.0;
    held.ramp = 0;
    return dfo_exact_advance_poly(M, &held, &q, s, t_target, on_switch, switch_ctx);
}

const char *dfo_status_text(dfo_status st)
{
    switch (st) {
    case DFO_OK: return "ok";
    case DFO_ERR_LCP: return "the friction LCP could not be solved (Lemke failed)";
    case DFO_ERR_NO_PROGRESS: return "too many stick/slip switches inside one internal step";
    case DFO_ERR_NONFINITE: return "the state became non-finite (overflow)";
    case DFO_ERR_RESOLUTION: return "the internal step h is below the time resolution at this time";
    case DFO_ERR_EVENTS:
        return "the communication step needs more than 1e8 events (stops, reversals, breakaways) of the exact "
               "scheme, its work bound; use shorter communication steps";
    }
    return "unknown status";
}
