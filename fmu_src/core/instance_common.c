/* What every instance core shares (see instance_common.h), compiled with the model's generated
 * variable table. No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "instance_common.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* ---- logging --------------------------------------------------------------------------------- */

static void vlog(const dfo_instance *in, dfo_inst_status status, int category, const char *fmt, va_list ap)
{
    char buf[512];
    vsnprintf(buf, sizeof buf, fmt, ap);
    for (char *c = buf; *c; c++)
        if (*c == '%') *c = ' '; /* the message reaches printf-style loggers as a format */
    in->host.log(in->host.ctx, status, DFO_LOG_CATEGORIES[category], buf);
}

void dfo_inst_log(const dfo_instance *in, dfo_inst_status status, int category, const char *fmt, ...)
{
    if (!in->host.log || !in->log_on[category]) return;
    va_list ap;
    va_start(ap, fmt);
    vlog(in, status, category, fmt, ap);
    va_end(ap);
}

dfo_inst_status dfo_inst_fail(const dfo_instance *in, const char *fmt, ...)
{
    if (!in->host.log || !in->log_on[DFO_LOG_STATUS_ERROR]) return DFO_INST_ERROR;
    va_list ap;
    va_start(ap, fmt);
    vlog(in, DFO_INST_ERROR, DFO_LOG_STATUS_ERROR, fmt, ap);
    va_end(ap);
    return DFO_INST_ERROR;
}

int dfo_inst_log_category(const char *name)
{
    if (!name) return -1;
    for (int j = 0; j < DFO_NUM_LOG_CATEGORIES; j++)
        if (!strcmp(name, DFO_LOG_CATEGORIES[j])) return j;
    return -1;
}

void dfo_inst_set_logging(dfo_instance *in, int category, int on)
{
    for (int j = 0; j < DFO_NUM_LOG_CATEGORIES; j++)
        if (category < 0 || category == j) in->log_on[j] = on ? 1 : 0;
}

const char *dfo_phase_name(dfo_phase p)
{
    switch (p) {
    case DFO_PHASE_INSTANTIATED: return "instantiated";
    case DFO_PHASE_INIT: return "initialization mode";
    case DFO_PHASE_STEP: return "step mode";
    case DFO_PHASE_TERMINATED: return "terminated";
    case DFO_PHASE_ERROR: return "error";
    case DFO_PHASE_EVENT: return "event mode";
    case DFO_PHASE_CONFIG: return "configuration mode";
    }
    return "unknown";
}

/* ---- values, doStep arguments, checksums ------------------------------------------------------ */

const char *dfo_inst_invalid(const dfo_var_info *var, double x)
{
    if (!isfinite(x)) return "finite";
    if (var->n_items > 0) {
        for (int k = 0; k < var->n_items; k++)
            if (x == var->items[k]) return NULL;
        return var->range;
    }
    if (var->normal && x != 0.0 && fabs(x) < DBL_MIN) return var->range; /* 0 or a normal number */
    return (x >= var->min && x <= var->max) ? NULL : var->range;
}

dfo_inst_status dfo_inst_check_step(const dfo_instance *in, const char *fn, double tc, double dt, double h,
                                    double *t_target_out)
{
    const dfo_values *v = &in->v;
    const double t = v->time;
    if (!isfinite(tc))
        return dfo_inst_fail(in, "%s: currentCommunicationPoint %.17g must be finite (the FMU's time is %.17g).", fn,
                             tc, t);
    if (!isfinite(dt) || !(dt > 0.0))
        return dfo_inst_fail(in, "%s: communicationStepSize %.17g must be finite and > 0 (at t = %.17g).", fn, dt,
                             tc);
    const double tol = 1e3 * DBL_EPSILON * fmax(1.0, fabs(t)) + 1e-9 * h;
    if (fabs(tc - t) > tol)
        return dfo_inst_fail(in, "%s: currentCommunicationPoint %.17g does not equal the FMU's time %.17g.", fn,
                             tc, t);
    const double t_target = tc + dt;
    if (!(t_target > t))
        return dfo_inst_fail(in, "%s: communicationStepSize %.17g is below the time resolution at t = %.17g.", fn,
                             dt, t);
    if (v->stop_defined && t_target > v->stop_time + tol)
        return dfo_inst_fail(in, "%s: the step would end at %.17g, after the stop time %.17g.", fn, t_target,
                             v->stop_time);
    if (!in->work_by_events && (t_target - t) / h > DFO_MAX_STEPS_PER_CALL)
        return dfo_inst_fail(in, "%s: a communication step of %.17g s would take more than %.0e internal "
                             "steps of h = %.17g s; use a larger h or shorter communication steps.", fn, dt,
                             DFO_MAX_STEPS_PER_CALL, h);
    *t_target_out = t_target;
    return DFO_INST_OK;
}

int dfo_inst_events_begin(dfo_instance *in, const char *fn, double tc, double dt, double h, const dfo_event_opts *opt,
                          dfo_step_result *res, dfo_inst_status *st, double *t_target)
{
    res->early = res->event = 0;
    in->v.event_pending = 0; /* an event not handled in event mode is handled by the next step */
    if (!opt->early_return && !opt->intermediate) {
        *st = dfo_inst_do_step(in, fn, tc, dt, 0, NULL);
        res->t_reached = in->v.time;
        return 1;
    }
    *st = dfo_inst_check_step(in, fn, tc, dt, h, t_target);
    return *st != DFO_INST_OK;
}

uint64_t dfo_inst_checksum(const unsigned char *p, size_t n)
{
    uint64_t h = 1469598103934665603ULL;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211ULL;
    }
    return h;
}

/* ---- the life cycle's model-independent steps (the values' common fields) --------------------- */

dfo_inst_status dfo_inst_setup(dfo_instance *in, const char *fn, double start_time, int stop_defined,
                               double stop_time)
{
    if (!isfinite(start_time)) return dfo_inst_fail(in, "%s: startTime %g is not finite.", fn, start_time);
    if (stop_defined && !(stop_time >= start_time))
        return dfo_inst_fail(in, "%s: stopTime %.17g must be finite and >= startTime %.17g.", fn, stop_time,
                             start_time);
    in->v.start_time = start_time;
    in->v.stop_defined = stop_defined ? 1 : 0;
    in->v.stop_time = stop_defined ? stop_time : 0.0;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_enter_init(dfo_instance *in)
{
    in->v.phase = DFO_PHASE_INIT;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_terminate(dfo_instance *in)
{
    in->v.phase = DFO_PHASE_TERMINATED;
    return DFO_INST_OK;
}

int dfo_inst_update_events(dfo_instance *in)
{
    const int pending = in->v.event_pending;
    in->v.event_pending = 0;
    return pending;
}

double dfo_inst_time(const dfo_instance *in) { return in->v.time; }
