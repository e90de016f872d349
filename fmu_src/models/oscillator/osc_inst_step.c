/* The DryFrictionOscillator instance core (osc_instance.h), its stepping: doStep, with early return
 * at the first switch when asked for. No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "osc_instance.h"
#include "instance_common.h"

#include <math.h>
#include <stddef.h>

/* ---- doStep ---------------------------------------------------------------------------------- */

void osc_inst_on_switch(void *ctx, double t, double x, int from, int to)
{
    osc_instance *in = (osc_instance *)ctx;
    static const char *const names[3] = {"backward slip", "stick", "forward slip"};
    in->lc.switched = 1;
    in->v.t_switch = t;
    dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_EVENTS, "t = %.17g: %s -> %s at x = %.17g.", t, names[from + 1],
                 names[to + 1], x);
}

/* Early return: one internal grid step per call of the stepper, until the first switch. Used only
 * when asked for; the ordinary path is one call up to the target. */
static dfo_status advance_to_switch(osc_instance *in, double t_target)
{
    osc_values *v = &in->v;
    const double h = v->M.p.h, snap = dfo_snap(h, t_target);
    in->lc.switched = 0;
    while (v->s.t < t_target) {
        const double grid = v->s.t0 + (double)(v->s.n + 1) * h;
        const double t_next = (grid < t_target - snap) ? grid : t_target;
        const dfo_status st = dfo_advance_cached(&v->M, &in->eng, &v->u, &v->s, t_next, osc_inst_on_switch, in);
        if (st != DFO_OK || in->lc.switched || t_next == t_target) return st;
    }
    return DFO_OK;
}

/* After a step with input derivatives the inputs hold the values their polynomials reached at its
 * end (the state's time); the derivatives are spent (the next step holds the inputs unless the
 * host sets derivatives again). */
void osc_inst_end_ramp(osc_values *v)
{
    if (!v->u.ramp) return;
    dfo_inputs w;
    dfo_inputs_at(&v->u, v->s.t, &w);
    v->u = w;
}

/* A failed step: the outputs stay those of the last good state, the instance is in error. */
dfo_inst_status osc_inst_step_failed(osc_instance *in, const char *fn, const dfo_state *before, const dfo_state *failed,
                                   dfo_status st)
{
    osc_values *v = &in->v;
    const double t = in->lc.run.time;
    v->s = *before;
    in->lc.run.phase = DFO_PHASE_ERROR;
    return dfo_inst_fail(&in->lc, "%s: step from t = %.17g failed at t = %.17g: %s (x = %.17g, v = %.17g). The "
                         "FMU keeps the state at t = %.17g; reset it or restore an earlier FMU state.", fn, t,
                         failed->t, dfo_status_text(st), failed->X, failed->V, t);
}

dfo_inst_status dfo_inst_do_step(dfo_lifecycle *lc, const char *fn, double tc, double dt, unsigned int flags,
                                 double *t_reached)
{
    osc_instance *in = osc(lc);
    osc_values *v = &in->v;
    double t_target = 0.0;
    /* the exact scheme counts its events (no 1e9 h bound), unless it walks the grid to a switch */
    in->lc.work_by_events = v->M.p.scheme == DFO_SCHEME_EXACT && !(flags & DFO_STEP_STOP_AT_SWITCH);
    const dfo_inst_status chk = dfo_inst_check_step(&in->lc, fn, tc, dt, v->M.p.h, &t_target);
    if (chk != DFO_INST_OK) return chk;
    if (v->u.ramp && v->M.p.scheme == DFO_SCHEME_EXACT && osc_inst_ramp_unsupported(&v->M.p))
        return osc_inst_ramp_refused(in, fn);
    const dfo_state before = v->s;
    if (!osc_inst_same_inputs(&v->u, &v->u_used)) dfo_new_inputs_cached(&v->M, &in->eng, &v->u_used, &v->u, &v->s);
    dfo_status st;
    if (flags & DFO_STEP_STOP_AT_SWITCH) {
        st = advance_to_switch(in, t_target);
    } else {
        /* the switches are logged; their times (output derivatives do not exist at one) the Bossak
         * schemes keep in the state, the exact scheme's are noted by osc_inst_on_switch */
        const int events = (in->lc.host.log && in->lc.log_on[DFO_LOG_EVENTS]) || v->M.p.scheme == DFO_SCHEME_EXACT;
        st = dfo_advance_cached(&v->M, &in->eng, &v->u, &v->s, t_target, events ? osc_inst_on_switch : NULL, in);
    }
    if (st != DFO_OK) {
        const dfo_state failed = v->s;
        return osc_inst_step_failed(in, fn, &before, &failed, st);
    }
    /* the host's time: the target (the stepper may stand on a grid point within its snap tolerance
     * of it), or where an early return stopped short of it */
    const double snap = dfo_snap(v->M.p.h, t_target);
    const int early = (flags & DFO_STEP_STOP_AT_SWITCH) && in->lc.switched && v->s.t < t_target - snap;
    in->lc.run.time = early ? v->s.t : t_target;
    osc_inst_end_ramp(v);
    v->u_used = v->u;
    if (t_reached) *t_reached = in->lc.run.time;
    return DFO_INST_OK;
}
