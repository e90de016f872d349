/* The DryFrictionOscillator instance core (osc_instance.h), FMI 3.0's doStep with events: early
 * return, event mode, intermediate update. No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "osc_instance.h"
#include "instance_common.h"

#include <math.h>
#include <stddef.h>

/* ---- FMI 3.0: stepping with events --------------------------------------------------------------
 *
 * A step with events is computed as the plain step (one dfo_advance to the target, the switches
 * recorded), then each switch strictly inside it is landed on: the same stepping from the step's
 * start, ended at the switch time (dfo_advance to ts: the steps up to the switch are the plain
 * step's, the last one shortened to end at ts). A located stop is found by bisection in the
 * shortened step again and may land a few ulps later: the target is nudged by ulps until the re-run
 * holds the switch. Should that fail, the step ends on the internal grid point after the switch. */

typedef struct {
    double t_after;  /* record the first switch after this time */
    int count;       /* switches seen */
    int found, from, to, index;
    double ts;
} switch_rec;

static void record_switch(void *ctx, double t, double x, int from, int to)
{
    switch_rec *r = (switch_rec *)ctx;
    (void)x;
    if (!r->found && t > r->t_after) {
        r->found = 1;
        r->ts = t;
        r->from = from;
        r->to = to;
        r->index = r->count;
    }
    r->count++;
}

/* The state just after the switch r (index r->index of the step from start), into *out. */
static int land(const osc_values *v, osc_bossak_engine *eng, const dfo_state *start, const switch_rec *r, double t_end,
                dfo_state *out)
{
    double t = r->ts, ulp = nextafter(r->ts, INFINITY) - r->ts;
    for (int k = 0; k < 12 && t < t_end; k++, t = r->ts + ulp, ulp *= 2.0) {
        switch_rec check = {-INFINITY, 0, 0, 0, 0, 0, 0.0};
        dfo_state w = *start;
        if (dfo_advance_cached(&v->M, eng, &v->u, &w, t, record_switch, &check) != DFO_OK) return 0;
        if (check.count == r->index + 1 && w.mode == r->to && w.t < t_end) {
            *out = w;
            return 1;
        }
    }
    /* fallback: the internal grid point after the switch */
    const double h = v->M.p.h;
    const double g = start->t0 + (floor((r->ts - start->t0) / h) + 1.0) * h;
    if (!(g < t_end)) return 0;
    dfo_state w = *start;
    if (dfo_advance_cached(&v->M, eng, &v->u, &w, g, NULL, NULL) != DFO_OK || w.mode != r->to) return 0;
    *out = w;
    return 1;
}

/* One stretch of a step with events, from the current state (the host's time) to t_end: the whole
 * step, or (input points) one internal step of it, `last` when t_end is the step's target. Returns
 * 1 when the step is over (ended early at a switch, reached its target, or failed: *st, res), 0
 * when a stretch that is not the last reached t_end. A switch on the end of a stretch that is not
 * the last is one inside the step. */
static int events_stretch(osc_instance *in, const char *fn, double t_end, int last, const dfo_event_opts *opt,
                          dfo_step_result *res, dfo_inst_status *st_out)
{
    osc_values *v = &in->v;
    const dfo_state start = v->s;
    const double t_start = in->lc.run.time;
    const int events_logged = in->lc.host.log && in->lc.log_on[DFO_LOG_EVENTS];
    double t_after = -INFINITY;
    *st_out = DFO_INST_OK;
    for (;;) {
        switch_rec r = {t_after, 0, 0, 0, 0, 0, 0.0};
        dfo_state w = start;
        const dfo_status st = dfo_advance_cached(&v->M, &in->eng, &v->u, &w, t_end, record_switch, &r);
        if (st != DFO_OK) {
            *st_out = osc_inst_step_failed(in, fn, &start, &w, st);
            return 1;
        }
        dfo_state at;
        /* in a stretch that is one internal step, a switch not landed on inside it is on its end
         * (the paper and consistent schemes switch on grid points, reported to rounding) */
        const int inside = r.found && ((r.ts < w.t && land(v, &in->eng, &start, &r, w.t, &at)) || (!last && (at = w, 1)));
        if (inside) {
            /* a switch inside the step: the state at it is readable during the intermediate update */
            int stop = opt->early_return && !opt->intermediate;
            if (opt->intermediate) {
                v->s = at;
                in->lc.run.time = at.t;
                stop = opt->intermediate(opt->ctx, at.t, opt->early_return, 0) && opt->early_return;
            }
            if (stop) {
                v->s = at;
                in->lc.run.time = at.t;
                v->t_switch = at.t;
                osc_inst_end_ramp(v);
                v->u_used = v->u;
                in->lc.run.event_pending = opt->event_mode;
                in->lc.run.event_from = r.from;
                res->early = 1;
                res->event = opt->event_mode;
                res->t_reached = at.t;
                if (events_logged) osc_inst_on_switch(in, at.t, at.X, r.from, r.to);
                return 1;
            }
            v->s = start;
            in->lc.run.time = t_start;
            t_after = r.ts;
            if (at.t < w.t) continue;
            r.found = 0; /* the switch on the end of this stretch has been reported */
        }
        const int end_switch = inside || (r.found && last);
        /* no switch left inside: the stretch's end. A switch on the communication point itself
         * (the paper and consistent schemes switch on grid points) is an event there. */
        if (r.found && opt->event_mode) {
            in->lc.run.event_pending = 1;
            in->lc.run.event_from = r.from;
            res->event = 1;
        }
        if (r.found && opt->intermediate) {
            v->s = w;
            in->lc.run.time = t_end;
            (void)opt->intermediate(opt->ctx, t_end, 0, 0);
        }
        if (events_logged) {
            dfo_state again = start;
            (void)dfo_advance_cached(&v->M, &in->eng, &v->u, &again, t_end, osc_inst_on_switch, in);
        }
        v->s = w;
        in->lc.run.time = t_end;
        if (end_switch && (r.found || at.t == w.t)) v->t_switch = w.t;
        if (!last) return 0;
        osc_inst_end_ramp(v);
        v->u_used = v->u;
        res->t_reached = t_end;
        return 1;
    }
}

/* An input point (FMI 3.0 intermediate update of inputs) at the current state, inside a step of
 * the Bossak schemes: the host may set the inputs declared intermediateUpdate="true", which then
 * hold from here on (an input set here loses its derivatives; the others keep their polynomials).
 * Returns whether the host asked for an early return (honoured with early return allowed). */
static int input_point(osc_instance *in, const dfo_event_opts *opt)
{
    osc_values *v = &in->v;
    const double t = v->s.t;
    if (v->u.ramp) { /* the polynomials re-anchored at t: their values there, the derivatives' at t */
        const double tau = t - v->u.t_d;
        dfo_inputs w;
        dfo_inputs_at(&v->u, t, &w);
        w.F_ext_d[0] = v->u.F_ext_d[0] + v->u.F_ext_d[1] * tau;
        w.N_ext_d[0] = v->u.N_ext_d[0] + v->u.N_ext_d[1] * tau;
        w.F_ext_d[1] = v->u.F_ext_d[1];
        w.N_ext_d[1] = v->u.N_ext_d[1];
        w.t_d = t;
        w.ramp = 1;
        v->u = v->u_used = w;
    }
    const dfo_inputs before = v->u;
    in->lc.run.time = t;
    const int stop = opt->intermediate(opt->ctx, t, opt->early_return, 1) && opt->early_return;
    if (v->u.ramp) {
        if (v->u.F_ext != before.F_ext) v->u.F_ext_d[0] = v->u.F_ext_d[1] = 0.0;
        if (v->u.N_ext != before.N_ext) v->u.N_ext_d[0] = v->u.N_ext_d[1] = 0.0;
        v->u.ramp = v->u.F_ext_d[0] != 0.0 || v->u.F_ext_d[1] != 0.0 || v->u.N_ext_d[0] != 0.0 ||
                    v->u.N_ext_d[1] != 0.0;
    }
    if (!osc_inst_same_inputs(&v->u, &v->u_used)) dfo_new_inputs_cached(&v->M, &in->eng, &v->u_used, &v->u, &v->s);
    v->u_used = v->u;
    return stop;
}

dfo_inst_status dfo_inst_do_step_events(dfo_lifecycle *lc, const char *fn, double tc, double dt,
                                        const dfo_event_opts *opt, dfo_step_result *res)
{
    osc_instance *in = osc(lc);
    osc_values *v = &in->v;
    dfo_inst_status done;
    double t_target = 0.0;
    in->lc.work_by_events = v->M.p.scheme == DFO_SCHEME_EXACT;
    if (v->u.ramp && v->M.p.scheme == DFO_SCHEME_EXACT && osc_inst_ramp_unsupported(&v->M.p))
        return osc_inst_ramp_refused(in, fn);
    if (dfo_inst_events_begin(&in->lc, fn, tc, dt, v->M.p.h, opt, res, &done, &t_target)) return done;
    if (!osc_inst_same_inputs(&v->u, &v->u_used)) {
        dfo_new_inputs_cached(&v->M, &in->eng, &v->u_used, &v->u, &v->s);
        v->u_used = v->u; /* (the state now belongs to them) */
    }
    /* input points: the end of every internal step before the target (the exact scheme has none) */
    const int points = opt->input_points && opt->intermediate && v->M.p.scheme != DFO_SCHEME_EXACT;
    const double h = v->M.p.h, snap = dfo_snap(h, t_target);
    for (;;) {
        double t_end = t_target;
        if (points) {
            const double grid = v->s.t0 + (double)(v->s.n + 1) * h;
            if (grid < t_target - snap) t_end = grid;
        }
        dfo_inst_status st;
        if (events_stretch(in, fn, t_end, t_end == t_target, opt, res, &st)) return st;
        if (input_point(in, opt)) {
            osc_inst_end_ramp(v);
            v->u_used = v->u;
            res->early = 1;
            res->t_reached = in->lc.run.time;
            return DFO_INST_OK;
        }
    }
}
