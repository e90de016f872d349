/* The DryFrictionChain instance core (chain_instance.h), its stepping: doStep, and FMI 3.0's doStep
 * with events (early return, event mode, intermediate update). No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain_instance.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* ---- doStep ---------------------------------------------------------------------------------- */

typedef struct {
    chain_instance *in;
    int log, count;
    double t;
    size_t block;
    int from, to;
} switch_rec;

static void on_switch(void *ctx, double t, size_t block, double x, int from, int to)
{
    switch_rec *r = (switch_rec *)ctx;
    static const char *const names[3] = {"backward slip", "stick", "forward slip"};
    r->count++;
    r->t = t;
    r->block = block;
    r->from = from;
    r->to = to;
    if (r->log)
        dfo_inst_log(&r->in->lc, DFO_INST_OK, DFO_LOG_EVENTS, "t = %.17g: block %lu: %s -> %s at x = %.17g.", t,
                     (unsigned long)block + 1, names[from + 1], names[to + 1], x);
}

static dfo_inst_status step_failed(chain_instance *in, const char *fn, chain_status st)
{
    chain_values *v = &in->v;
    const double t_failed = v->s.t;
    chain_state_copy(&v->s, &v->s0);
    v->acc_valid = 0;
    in->lc.run.phase = DFO_PHASE_ERROR;
    return dfo_inst_fail(&in->lc, "%s: step from t = %.17g failed at t = %.17g: %s. The FMU keeps the state at "
                         "t = %.17g; reset it or restore an earlier FMU state.", fn, in->lc.run.time, t_failed,
                         chain_status_text(st), in->lc.run.time);
}

/* Inputs set since the last step: the state takes their jump at the step's start (chain_new_inputs;
 * with derivatives, ramp, the new inputs at the state's time). */
static void take_inputs(chain_values *v, const chain_ramp *ramp, chain_switch_fn fn, void *ctx)
{
    if (!memcmp(v->u_set, v->u_set_used, sizeof v->u_set) &&
        !memcmp(v->ua, v->ua_used, (size_t)DFO_NUM_AI * v->n * sizeof(double)))
        return;
    const chain_inputs old_in = chain_inst_inputs_of(v, 1), new_in = chain_inst_inputs_of(v, 0);
    chain_new_inputs_ramped(v->M, &old_in, &new_in, (ramp && ramp->dF_ext[0]) ? ramp : NULL, chain_inst_state_belt(v),
                            &v->s);
    const double *vb_old = chain_inst_belt_of(v, 1), *vb_new = chain_inst_belt_of(v, 0);
    if (vb_old || vb_new) chain_new_belt(v->M, &new_in, vb_old, vb_new, &v->s, fn, ctx);
    v->acc_valid = 0;
}

/* A moving belt under the paper scheme: refused (its stuck blocks creep with Bossak's acceleration,
 * which the belt's moving frame does not carry over); 1 when refused. */
static int belt_refused(chain_instance *in, const char *fn)
{
    chain_values *v = &in->v;
    if (!chain_inst_belt_of(v, 0) || (int)v->sp[DFO_SP_scheme] != DFO_MD_SCHEME_PAPER) return 0;
    (void)dfo_inst_fail(&in->lc, "%s: v_belt is set but the paper scheme has no moving belt (its stuck blocks creep "
                        "with Bossak's acceleration); use scheme consistent or located.", fn);
    return 1;
}

/* The step from t_ref ends at the host's time t: the inputs with derivatives take their values at
 * the state's time, and those of the step are the ones used. */
static void step_done(chain_instance *in, double t, double t_ref, const switch_rec *rec)
{
    chain_values *v = &in->v;
    in->lc.run.time = t;
    v->acc_valid = 0;
    if (rec->count > 0) {
        v->sw_t = rec->t;
        v->sw_block = (long long)rec->block;
    }
    chain_inst_ramp_done(v, t_ref);
    memcpy(v->ua_used, v->ua, (size_t)DFO_NUM_AI * v->n * sizeof(double));
    memcpy(v->u_set_used, v->u_set, sizeof v->u_set);
    v->belts_unsynced = 0;
}

dfo_inst_status dfo_inst_do_step(dfo_lifecycle *lc, const char *fn, double tc, double dt, unsigned int flags,
                                 double *t_reached)
{
    chain_instance *in = chn(lc);
    chain_values *v = &in->v;
    double t_target = 0.0;
    const dfo_inst_status chk = dfo_inst_check_step(&in->lc, fn, tc, dt, chain_inst_step_h(v), &t_target);
    if (chk != DFO_INST_OK) return chk;
    if (belt_refused(in, fn)) return DFO_INST_ERROR;
    chain_state_copy(&v->s0, &v->s);
    chain_ramp ramp = chain_inst_ramp_of(v);
    ramp.t_ref = in->lc.run.time; /* the polynomials are in the host's time (as the oscillator's) */
    switch_rec rec = {in, in->lc.host.log && in->lc.log_on[DFO_LOG_EVENTS], 0, 0.0, 0, 0, 0};
    take_inputs(v, &ramp, on_switch, &rec);
    v->belts_unsynced = 1;
    const chain_inputs ci = chain_inst_inputs_of(v, 0);
    const int stop = (flags & DFO_STEP_STOP_AT_SWITCH) != 0;
    const chain_status st = chain_advance_belt(v->M, &ci, &ramp, chain_inst_belt_of(v, 0), &v->s, t_target, stop,
                                               on_switch, &rec);
    if (st != CHAIN_OK && st != CHAIN_SWITCHED) return step_failed(in, fn, st);
    const double snap = dfo_snap(chain_inst_step_h(v), t_target);
    in->lc.switched = rec.count > 0;
    step_done(in, (st == CHAIN_SWITCHED && v->s.t < t_target - snap) ? v->s.t : t_target, ramp.t_ref, &rec);
    if (t_reached) *t_reached = in->lc.run.time;
    return DFO_INST_OK;
}

/* ---- FMI 3.0: stepping with events ----------------------------------------------------------
 * The step runs with the physics' own stop_at_switch: chain_advance returns at every switch (the
 * located scheme at its time, the others at the end of the internal step holding it) with the
 * state complete there, and goes on from it bit for bit as one call would. A switch strictly inside
 * the step is offered to the intermediate update and ends the step early when asked (or always with
 * early return and no callback); one on the communication point is an event there. */
/* An input point inside the step (opt->input_points): the inputs the host set there hold from the
 * state's time on (their jump taken as at a step's start); derivatives, if any, end there. */
static void point_inputs(chain_values *v, switch_rec *rec)
{
    const int changed = memcmp(v->u_set, v->u_set_used, sizeof v->u_set) ||
                        memcmp(v->ua, v->ua_used, (size_t)DFO_NUM_AI * v->n * sizeof(double));
    if (!changed) return;
    take_inputs(v, NULL, on_switch, rec);
    memcpy(v->ua_used, v->ua, (size_t)DFO_NUM_AI * v->n * sizeof(double));
    memcpy(v->u_set_used, v->u_set, sizeof v->u_set);
    memset(v->ud, 0, 2 * (size_t)DFO_NUM_AI * v->n * sizeof(double));
    v->ud_set = 0;
}

dfo_inst_status dfo_inst_do_step_events(dfo_lifecycle *lc, const char *fn, double tc, double dt,
                                        const dfo_event_opts *opt, dfo_step_result *res)
{
    chain_instance *in = chn(lc);
    chain_values *v = &in->v;
    dfo_inst_status done;
    double t_target = 0.0;
    if (dfo_inst_events_begin(&in->lc, fn, tc, dt, chain_inst_step_h(v), opt, res, &done, &t_target)) return done;
    if (belt_refused(in, fn)) return DFO_INST_ERROR;
    chain_state_copy(&v->s0, &v->s);
    const double t_start = in->lc.run.time;
    chain_ramp ramp = chain_inst_ramp_of(v);
    ramp.t_ref = t_start;
    switch_rec rec = {in, in->lc.host.log && in->lc.log_on[DFO_LOG_EVENTS], 0, 0.0, 0, 0, 0};
    take_inputs(v, &ramp, on_switch, &rec);
    v->belts_unsynced = 1;
    chain_inputs ci = chain_inst_inputs_of(v, 0);
    const double t_ref = ramp.t_ref, h = chain_inst_step_h(v);
    const double snap = dfo_snap(h, t_target);
    /* input points: every internal step ends on one (its grid point), where the host may set inputs */
    const int points = opt->input_points && opt->intermediate;
    if (points) { /* the inputs of the step's start are the used ones (a failed step ends in the error phase) */
        memcpy(v->ua_used, v->ua, (size_t)DFO_NUM_AI * v->n * sizeof(double));
        memcpy(v->u_set_used, v->u_set, sizeof v->u_set);
        v->belts_unsynced = 0;
    }
    int at_end = 0;
    for (;;) {
        const int before = rec.count;
        double t_call = t_target;
        if (points) {
            const double g = v->s.t0 + (double)(v->s.n_grid + 1) * h;
            if (g < t_target - snap) t_call = g;
        }
        const chain_status st = chain_advance_belt(v->M, &ci, &ramp, chain_inst_belt_of(v, 0), &v->s, t_call, 1,
                                                   on_switch, &rec);
        if (st != CHAIN_OK && st != CHAIN_SWITCHED) {
            in->lc.run.time = t_start;
            return step_failed(in, fn, st);
        }
        if (st == CHAIN_OK && t_call == t_target) break;
        int stop = 0;
        if (st == CHAIN_OK) { /* an input point */
            in->lc.run.time = v->s.t;
            v->acc_valid = 0;
            stop = opt->intermediate(opt->ctx, v->s.t, opt->early_return, 1) && opt->early_return;
            point_inputs(v, &rec); /* (also before an early return there: the inputs hold from t on) */
            if (!stop) {
                ci = chain_inst_inputs_of(v, 0);
                ramp = chain_inst_ramp_of(v);
                ramp.t_ref = t_ref;
                continue;
            }
        } else {
            if (!(v->s.t < t_target - snap)) { /* a switch on the communication point */
                at_end = rec.count > before;
                if (v->s.t < t_target) continue;
                break;
            }
            stop = opt->early_return && !opt->intermediate;
            if (opt->intermediate) {
                in->lc.run.time = v->s.t;
                v->acc_valid = 0;
                stop = opt->intermediate(opt->ctx, v->s.t, opt->early_return, 0) && opt->early_return;
            }
            /* a switch at the end of an internal step (the paper and consistent schemes): an input
             * point too */
            if (!stop && points && v->s.t == t_call && t_call != t_target) {
                stop = opt->intermediate(opt->ctx, v->s.t, opt->early_return, 1) && opt->early_return;
                point_inputs(v, &rec);
                if (!stop) {
                    ci = chain_inst_inputs_of(v, 0);
                    ramp = chain_inst_ramp_of(v);
                    ramp.t_ref = t_ref;
                }
            }
        }
        if (stop) {
            const int switched = st == CHAIN_SWITCHED;
            step_done(in, v->s.t, t_ref, &rec);
            in->lc.run.event_pending = switched && opt->event_mode;
            in->lc.run.event_from = rec.from;
            if (switched) v->event_block = rec.block;
            res->early = 1;
            res->event = switched && opt->event_mode;
            res->t_reached = in->lc.run.time;
            return DFO_INST_OK;
        }
    }
    if (at_end && opt->event_mode) {
        in->lc.run.event_pending = 1;
        in->lc.run.event_from = rec.from;
        v->event_block = rec.block;
        res->event = 1;
    }
    step_done(in, t_target, t_ref, &rec);
    if (at_end && opt->intermediate) (void)opt->intermediate(opt->ctx, t_target, 0, 0);
    res->t_reached = t_target;
    return DFO_INST_OK;
}

void dfo_inst_log_event_handled(const dfo_lifecycle *lc)
{
    const chain_instance *in = cchn(lc);
    const chain_values *v = &in->v;
    dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_EVENTS, "t = %.17g: event handled, block %lu in mode %d.", in->lc.run.time,
                 (unsigned long)v->event_block + 1, v->s.mode ? v->s.mode[v->event_block] : 0);
}

