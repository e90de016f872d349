/* The DryFrictionOscillator instance core (osc_instance.h), coupling at second order
 * (core/instance.h): input derivatives, output derivatives, directional and adjoint derivatives.
 * No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "osc_instance.h"
#include "instance_common.h"

#include <math.h>
#include <stddef.h>

/* ---- coupling at second order (core/instance.h) ----------------------------------------------
 *
 * Input derivatives: F_ext and N_ext, orders 1 and 2, for the next step (the Bossak schemes take the
 * input polynomial at every internal step, the exact scheme in closed form where it can:
 * dfo_exact_poly_unsupported). Output derivatives: x (order 1 v, order 2 a) and v (order 1 a, order
 * 2 da/dt), none at a switch on the current time (left and right limits differ). Directional and
 * adjoint derivatives: of the outputs with respect to F_ext, N_ext at the current point, the direct
 * feed-through of a and F_friction by mode (x, v and the rest: 0). */

#define MAX_INPUT_ORDER 2

int dfo_inst_max_input_order(void) { return DFO_CAN_INTERPOLATE_INPUTS ? MAX_INPUT_ORDER : 0; }
int dfo_inst_max_output_order(void) { return DFO_MAX_OUTPUT_DERIVATIVE_ORDER; }

/* The derivative slots of a real input (NULL for any other variable). */
static double *input_derivatives(osc_values *v, const dfo_var_info *var)
{
    if (var->vr == VR_F_ext) return v->u.F_ext_d;
    if (var->vr == VR_N_ext) return v->u.N_ext_d;
    return NULL;
}

dfo_inst_status dfo_inst_set_input_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t nvr,
                                               const int order[], const double value[])
{
    osc_instance *in = osc(lc);
    osc_values *v = &in->v;
    const int max_order = dfo_inst_max_input_order();
    for (size_t i = 0; i < nvr; i++) {
        const dfo_var_info *var = dfo_find_var(vr[i]);
        if (!var) return dfo_inst_fail(lc, "%s: unknown value reference %u.", fn, vr[i]);
        if (var->vr == VR_v_belt)
            return dfo_inst_fail(lc, "%s: input derivatives of v_belt (value reference %u) are not supported: the belt's "
                                 "velocity is held over a communication step; set v_belt at the communication points "
                                 "(only the inputs F_ext and N_ext take derivatives).", fn, vr[i]);
        if (var->causality != DFO_INPUT || var->type != DFO_REAL || !input_derivatives(v, var))
            return dfo_inst_fail(lc, "%s: variable %s (value reference %u) is not a real input: only the inputs "
                                 "F_ext and N_ext take derivatives.", fn, var->name, vr[i]);
        if (order[i] < 1 || order[i] > max_order)
            return dfo_inst_fail(lc, "%s: invalid order %d of the derivative of %s (value reference %u); valid range: "
                                 "1 to %d.", fn, order[i], var->name, vr[i], max_order);
        if (!isfinite(value[i]))
            return dfo_inst_fail(lc, "%s: invalid value %.17g of the order-%d derivative of %s (value reference %u); "
                                 "valid range: finite.", fn, value[i], order[i], var->name, vr[i]);
        const char *why = value[i] != 0.0 ? osc_inst_ramp_unsupported(&v->p) : NULL;
        if (why)
            return dfo_inst_fail(lc, "%s: input derivatives of %s (value reference %u) are not supported with scheme "
                                 "exact here: %s; set them to 0, or choose scheme paper, consistent or located.", fn,
                                 var->name, vr[i], why);
    }
    const double t_now = (lc->run.phase & (DFO_PHASE_INSTANTIATED | DFO_PHASE_INIT)) ? lc->run.start_time
                                                                                      : dfo_inst_time(lc);
    if (v->u.ramp && v->u.t_d != t_now) { /* derivatives of an earlier point (not stepped): forgotten */
        v->u.F_ext_d[0] = v->u.F_ext_d[1] = v->u.N_ext_d[0] = v->u.N_ext_d[1] = 0.0;
        v->u.ramp = 0;
    }
    for (size_t i = 0; i < nvr; i++) {
        const dfo_var_info *var = dfo_find_var(vr[i]);
        input_derivatives(v, var)[order[i] - 1] = value[i];
        /* a nonzero derivative connects the input (its value is then read, 0 until set) */
        if (value[i] != 0.0) *(int *)((char *)&v->u + var->set_offset) = 1;
    }
    v->u.t_d = t_now;
    v->u.ramp = v->u.F_ext_d[0] != 0.0 || v->u.F_ext_d[1] != 0.0 || v->u.N_ext_d[0] != 0.0 || v->u.N_ext_d[1] != 0.0;
    return DFO_INST_OK;
}

/* The step ended on a switch (left and right limits of the acceleration differ at the current time). */
static int at_switch(const osc_instance *in)
{
    const osc_values *v = &in->v;
    /* a Bossak scheme's switch on a step's end is reported at its t + h (to rounding): within the
     * snap tolerance of the end */
    return in->lc.run.event_pending || v->t_switch == v->s.t ||
           (v->M.p.scheme != DFO_SCHEME_EXACT && fabs(v->s.t_switch - v->s.t) <= dfo_snap(v->M.p.h, v->s.t));
}

dfo_inst_status dfo_inst_get_output_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[],
                                                size_t nvr, const int order[], double value[])
{
    osc_instance *in = osc(lc);
    const osc_values *v = &in->v;
    const int max_order = dfo_inst_max_output_order();
    for (size_t i = 0; i < nvr; i++) {
        const dfo_var_info *var = dfo_find_var(vr[i]);
        if (!var) return dfo_inst_fail(lc, "%s: unknown value reference %u.", fn, vr[i]);
        if (var->home != DFO_COMPUTED || (var->id != DFO_OUT_x && var->id != DFO_OUT_v))
            return dfo_inst_fail(lc, "%s: no output derivative for %s (value reference %u): only the outputs x and v "
                                 "have time derivatives.", fn, var->name, vr[i]);
        if (order[i] < 1 || order[i] > max_order)
            return dfo_inst_fail(lc, "%s: invalid order %d of the derivative of %s (value reference %u); valid range: "
                                 "1 to %d.", fn, order[i], var->name, vr[i], max_order);
        const int k = order[i] + (var->id == DFO_OUT_v); /* the order of the derivative of x */
        if (k == 1) {
            value[i] = v->s.V;
            continue;
        }
        if (at_switch(in))
            return dfo_inst_fail(lc, "%s: the order-%d derivative of %s (value reference %u) does not exist at t = "
                                 "%.17g: the step ended on a stick/slip switch, where the acceleration jumps (its left "
                                 "and right limits differ).", fn, order[i], var->name, vr[i], v->s.t);
        if (k == 2) {
            value[i] = osc_inst_acceleration_now(v);
        } else {
            dfo_state s = v->s;
            s.F = osc_inst_friction_now(v);
            value[i] = dfo_jerk(&v->M, &v->u, &s);
        }
        if (!isfinite(value[i]))
            return dfo_inst_fail(lc, "%s: the order-%d derivative of %s (value reference %u) is not representable in "
                                 "double precision (overflow).", fn, order[i], var->name, vr[i]);
    }
    return DFO_INST_OK;
}

/* d output / d input at the current point (the direct feed-through; a pending event's left limit,
 * mode event_from). out: the output's id, input: the input's value reference. */
static double feed_through(const osc_values *v, const dfo_run *r, int out, unsigned int input)
{
    if (out != DFO_OUT_a && out != DFO_OUT_F_friction) return 0.0;
    const dfo_model *M = &v->M;
    dfo_inputs u;
    dfo_inputs_at(&v->u, v->s.t, &u);
    dfo_loads L;
    dfo_loads_init(&L, M, &u);
    const double N_sum = M->p.N + u.N_ext;
    dfo_state s = r->event_pending ? osc_inst_left_limit(v, r->event_from) : v->s;
    double dF = 0.0, dFr = 0.0; /* d friction / d F_ext, d friction / d N_ext */
    int rests = 0;
    if (L.Fb > 0.0 && s.mode == 0) {
        /* stuck: the friction holds the static force, or sits on the limit beyond it */
        const double S = -dfo_friction_force(M, &u, &s); /* the static force, clamped to the limit */
        if (fabs(S) < L.Fb) dF = -1.0;
        else dFr = N_sum > 0.0 ? -dfo_sign(S) * M->mu_b : 0.0;
        rests = M->p.scheme != DFO_SCHEME_PAPER;
    } else if (s.mode != 0 && (L.Fb > 0.0 || N_sum > 0.0)) {
        const double mu = M->stribeck ? dfo_friction_mu(&M->law, fabs(s.V - dfo_belt_speed(&u))) : M->mu_k;
        dFr = N_sum > 0.0 ? -s.mode * mu : 0.0;
    }
    if (input == VR_v_belt) {
        /* stuck within the limit: the friction holds f = P + F_ext - c v_belt - k x (dF = c); sliding
         * with Stribeck: F = -s N mu(|v - v_belt|), dF = N mu'(u); coulomb sliding: 0 */
        double dB = 0.0;
        if (L.Fb > 0.0 && s.mode == 0) {
            if (fabs(dfo_friction_force(M, &u, &s)) < L.Fb && s.V == dfo_belt_speed(&u)) dB = M->p.c;
        } else if (s.mode != 0 && M->stribeck && L.N > 0.0) {
            dB = L.N * dfo_friction_dmu(&M->law, fabs(s.V - dfo_belt_speed(&u)));
        }
        if (out == DFO_OUT_F_friction) return dB;
        return rests ? 0.0 : dB / M->p.m;
    }
    const int force = input == VR_F_ext;
    if (out == DFO_OUT_F_friction) return force ? dF : dFr;
    if (rests) return 0.0;
    return ((force ? 1.0 : 0.0) + (force ? dF : dFr)) / M->p.m;
}

/* The knowns (inputs) and unknowns (real outputs) of a directional derivative, checked. */
static int check_partials(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                          const unsigned int known[], size_t nk)
{
    for (size_t i = 0; i < nu; i++) {
        const dfo_var_info *var = dfo_find_var(unknown[i]);
        if (!var || var->causality != DFO_OUTPUT || var->type != DFO_REAL) {
            dfo_inst_fail(lc, "%s: unknown %s (value reference %u) is not a real output: directional derivatives are "
                          "of the outputs x, v, a, F_friction and the other real outputs.", fn,
                          var ? var->name : "?", unknown[i]);
            return 0;
        }
    }
    for (size_t j = 0; j < nk; j++) {
        const dfo_var_info *var = dfo_find_var(known[j]);
        if (!var || var->causality != DFO_INPUT || var->type != DFO_REAL) {
            dfo_inst_fail(lc, "%s: known %s (value reference %u) is not an input: directional derivatives are with "
                          "respect to the inputs F_ext, N_ext and v_belt.", fn, var ? var->name : "?", known[j]);
            return 0;
        }
    }
    return 1;
}

static dfo_inst_status partials(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                const unsigned int known[], size_t nk, const double seed[], double sensitivity[],
                                int adjoint)
{
    if (!check_partials(lc, fn, unknown, nu, known, nk)) return DFO_INST_ERROR;
    osc_instance *in = osc(lc);
    osc_values tmp;
    const osc_values *v = osc_inst_computed(in, &tmp);
    const size_t n_out = adjoint ? nk : nu, n_seed = adjoint ? nu : nk;
    const unsigned int *seed_vr = adjoint ? unknown : known, *out_vr = adjoint ? known : unknown;
    for (size_t o = 0; o < n_seed; o++)
        if (!isfinite(seed[o]))
            return dfo_inst_fail(lc, "%s: invalid seed %.17g for %s (value reference %u); valid range: finite.", fn,
                                 seed[o], dfo_find_var(seed_vr[o])->name, seed_vr[o]);
    for (size_t o = 0; o < n_out; o++) sensitivity[o] = 0.0;
    for (size_t i = 0; i < nu; i++)
        for (size_t j = 0; j < nk; j++) {
            const double J = feed_through(v, &lc->run, dfo_find_var(unknown[i])->id, known[j]);
            if (J == 0.0) continue;
            if (adjoint) sensitivity[j] += J * seed[i];
            else sensitivity[i] += J * seed[j];
        }
    for (size_t o = 0; o < n_out; o++)
        if (!isfinite(sensitivity[o]))
            return dfo_inst_fail(lc, "%s: the %s derivative of %s (value reference %u) is not representable in double "
                                 "precision (overflow: a tiny mass m = %.17g or a huge friction coefficient).", fn,
                                 adjoint ? "adjoint" : "directional", dfo_find_var(out_vr[o])->name, out_vr[o],
                                 v->M.p.m);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_directional(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                     const unsigned int known[], size_t nk, const double seed[], double sensitivity[])
{
    return partials(lc, fn, unknown, nu, known, nk, seed, sensitivity, 0);
}

dfo_inst_status dfo_inst_adjoint(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                 const unsigned int known[], size_t nk, const double seed[], double sensitivity[])
{
    return partials(lc, fn, unknown, nu, known, nk, seed, sensitivity, 1);
}
