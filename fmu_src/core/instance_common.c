/* The life cycle every model shares (instance.h) and the helpers of the instance cores
 * (instance_common.h), compiled with the model's generated variable table. No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "instance_common.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef char dfo_static_assert_log_categories[DFO_NUM_LOG_CATEGORIES <= DFO_MAX_LOG_CATEGORIES ? 1 : -1];

/* ---- logging --------------------------------------------------------------------------------- */

static void vlog(const dfo_lifecycle *lc, dfo_inst_status status, int category, const char *fmt, va_list ap)
{
    char buf[512];
    vsnprintf(buf, sizeof buf, fmt, ap);
    for (char *c = buf; *c; c++)
        if (*c == '%') *c = ' '; /* the message reaches printf-style loggers as a format */
    lc->host.log(lc->host.ctx, status, DFO_LOG_CATEGORIES[category], buf);
}

void dfo_inst_log(const dfo_lifecycle *lc, dfo_inst_status status, int category, const char *fmt, ...)
{
    if (!lc->host.log || !lc->log_on[category]) return;
    va_list ap;
    va_start(ap, fmt);
    vlog(lc, status, category, fmt, ap);
    va_end(ap);
}

dfo_inst_status dfo_inst_fail(const dfo_lifecycle *lc, const char *fmt, ...)
{
    if (!lc->host.log || !lc->log_on[DFO_LOG_STATUS_ERROR]) return DFO_INST_ERROR;
    va_list ap;
    va_start(ap, fmt);
    vlog(lc, DFO_INST_ERROR, DFO_LOG_STATUS_ERROR, fmt, ap);
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

void dfo_inst_set_logging(dfo_lifecycle *lc, int category, int on)
{
    for (int j = 0; j < DFO_NUM_LOG_CATEGORIES; j++)
        if (category < 0 || category == j) lc->log_on[j] = on ? 1 : 0;
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

void dfo_lifecycle_init(dfo_lifecycle *lc, const dfo_host *host, const char *name, int logging_on)
{
    memset(lc, 0, sizeof *lc);
    lc->host = *host;
    lc->name = name;
    lc->run.phase = DFO_PHASE_INSTANTIATED;
    dfo_inst_set_logging(lc, -1, logging_on);
    /* problems are always reported */
    lc->log_on[DFO_LOG_STATUS_ERROR] = lc->log_on[DFO_LOG_STATUS_WARNING] = 1;
}

dfo_lifecycle *dfo_lifecycle_new(const dfo_host *host, size_t size, const char *name, int logging_on)
{
    dfo_lifecycle *lc = (dfo_lifecycle *)host->alloc(host->ctx, 1, size);
    if (!lc) {
        dfo_lifecycle tmp;
        dfo_lifecycle_init(&tmp, host, name, 0);
        dfo_inst_fail(&tmp, "instantiate: out of memory.");
        return NULL;
    }
    dfo_lifecycle_init(lc, host, name, logging_on);
    return lc;
}

/* ---- the FMU's resources ----------------------------------------------------------------------- */

dfo_inst_status dfo_inst_resources(dfo_lifecycle *lc, const char *dir, int op)
{
    if (!lc || !lc->resources) return DFO_INST_OK;
    return lc->resources(lc, dir, op);
}

static int hex_value(char c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

int dfo_path_of_file_uri(const char *uri, char *out, size_t len)
{
    if (!uri || !out || len == 0) return 0;
    if (strncmp(uri, "file:", 5) != 0) return 0;
    const char *p = uri + 5;
    if (p[0] == '/' && p[1] == '/') { /* file://authority/path: an empty authority or localhost only */
        p += 2;
        if (strncmp(p, "localhost", 9) == 0 && (p[9] == '/' || p[9] == '\0')) p += 9;
        if (*p != '/') return 0;
    }
    /* file:///C:/x or file:/C:/x: a Windows drive letter, no leading slash */
    if (p[0] == '/' && ((p[1] >= 'A' && p[1] <= 'Z') || (p[1] >= 'a' && p[1] <= 'z')) &&
        (p[2] == ':' || (p[2] == '%' && p[3] == '3' && (p[4] == 'A' || p[4] == 'a'))))
        p += 1;
    size_t k = 0;
    while (*p) {
        char c = *p++;
        if (c == '%') {
            const int hi = hex_value(p[0]), lo = hi < 0 ? -1 : hex_value(p[1]);
            if (lo < 0) return 0;
            c = (char)(hi * 16 + lo);
            p += 2;
            if (c == '\0') return 0;
        }
        if (k + 1 >= len) return 0;
        out[k++] = c;
    }
    out[k] = '\0';
    return k > 0;
}

/* ---- the variable table ---------------------------------------------------------------------- */

const dfo_var_info *dfo_find_var(unsigned int vr)
{
    for (int i = 0; i < DFO_NUM_VARS; i++)
        if (DFO_VARS[i].vr == vr) return &DFO_VARS[i];
    return NULL;
}

const char *dfo_type_name(dfo_var_type t)
{
    return t == DFO_REAL ? "Real" : t == DFO_INTEGER ? "Integer" : t == DFO_UINT64 ? "UInt64" : "Boolean";
}

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

const dfo_var_info *dfo_inst_lookup(const dfo_lifecycle *lc, const char *fn, unsigned int vr, dfo_var_type type)
{
    const dfo_var_info *var = dfo_find_var(vr);
    if (!var) {
        dfo_inst_fail(lc, "%s: unknown value reference %u.", fn, vr);
        return NULL;
    }
    if (var->type != type) {
        dfo_inst_fail(lc, "%s: variable %s (value reference %u) is of type %s, not %s.", fn, var->name, vr,
                      dfo_type_name(var->type), dfo_type_name(type));
        return NULL;
    }
    return var;
}

int dfo_inst_value_ok(const dfo_lifecycle *lc, const char *fn, const dfo_var_info *var, double x)
{
    const char *range = dfo_inst_invalid(var, x);
    if (!range) return 1;
    dfo_inst_fail(lc, "%s: invalid value %.17g for variable %s (value reference %u); valid range: %s.", fn, x,
                  var->name, var->vr, range);
    return 0;
}

int dfo_inst_settable(const dfo_lifecycle *lc, const char *fn, const dfo_var_info *var, const char *name,
                      unsigned int vr)
{
    const dfo_phase ph = lc->run.phase;
    if (var->causality == DFO_STRUCTURAL) {
        if (ph == DFO_PHASE_CONFIG) return 1;
        dfo_inst_fail(lc, "%s: %s (value reference %u) is a structural parameter: set it in configuration mode "
                      "(fmi3EnterConfigurationMode), not in %s.", fn, name, vr, dfo_phase_name(ph));
        return 0;
    }
    if (var->causality == DFO_PARAMETER && (ph & (DFO_PHASE_INSTANTIATED | DFO_PHASE_INIT))) return 1;
    if (var->causality == DFO_INPUT &&
        (ph & (DFO_PHASE_INSTANTIATED | DFO_PHASE_INIT | DFO_PHASE_STEP | DFO_PHASE_EVENT)))
        return 1;
    if (var->causality == DFO_PARAMETER)
        dfo_inst_fail(lc, "%s: variable %s (value reference %u) is a fixed parameter and cannot be set in %s.", fn,
                      name, vr, dfo_phase_name(ph));
    else if (var->causality == DFO_INPUT)
        dfo_inst_fail(lc, "%s: input %s (value reference %u) cannot be set in %s.", fn, name, vr,
                      dfo_phase_name(ph));
    else
        dfo_inst_fail(lc, "%s: variable %s (value reference %u) is %s and cannot be set.", fn, name, vr,
                      var->causality == DFO_OUTPUT ? "an output"
                      : var->causality == DFO_LOCAL ? "a local variable"
                                                    : "a calculated parameter");
    return 0;
}

/* ---- doStep arguments ------------------------------------------------------------------------ */

dfo_inst_status dfo_inst_check_step(const dfo_lifecycle *lc, const char *fn, double tc, double dt, double h,
                                    double *t_target_out)
{
    const dfo_run *r = &lc->run;
    const double t = r->time;
    if (!isfinite(tc))
        return dfo_inst_fail(lc, "%s: currentCommunicationPoint %.17g must be finite (the FMU's time is %.17g).", fn,
                             tc, t);
    if (!isfinite(dt) || !(dt > 0.0))
        return dfo_inst_fail(lc, "%s: communicationStepSize %.17g must be finite and > 0 (at t = %.17g).", fn, dt,
                             tc);
    const double tol = 1e3 * DBL_EPSILON * fmax(1.0, fabs(t)) + 1e-9 * h;
    if (fabs(tc - t) > tol)
        return dfo_inst_fail(lc, "%s: currentCommunicationPoint %.17g does not equal the FMU's time %.17g.", fn,
                             tc, t);
    const double t_target = tc + dt;
    if (!(t_target > t))
        return dfo_inst_fail(lc, "%s: communicationStepSize %.17g is below the time resolution at t = %.17g.", fn,
                             dt, t);
    if (r->stop_defined && t_target > r->stop_time + tol)
        return dfo_inst_fail(lc, "%s: the step would end at %.17g, after the stop time %.17g.", fn, t_target,
                             r->stop_time);
    if (!lc->work_by_events && (t_target - t) / h > DFO_MAX_STEPS_PER_CALL)
        return dfo_inst_fail(lc, "%s: a communication step of %.17g s would take more than %.0e internal "
                             "steps of h = %.17g s; use a larger h or shorter communication steps.", fn, dt,
                             DFO_MAX_STEPS_PER_CALL, h);
    *t_target_out = t_target;
    return DFO_INST_OK;
}

int dfo_inst_events_begin(dfo_lifecycle *lc, const char *fn, double tc, double dt, double h,
                          const dfo_event_opts *opt, dfo_step_result *res, dfo_inst_status *st, double *t_target)
{
    res->early = res->event = 0;
    lc->run.event_pending = 0; /* an event not handled in event mode is handled by the next step */
    if (!opt->early_return && !opt->intermediate) {
        *st = dfo_inst_do_step(lc, fn, tc, dt, 0, NULL);
        res->t_reached = lc->run.time;
        return 1;
    }
    *st = dfo_inst_check_step(lc, fn, tc, dt, h, t_target);
    return *st != DFO_INST_OK;
}

dfo_inst_status dfo_inst_step_by(dfo_lifecycle *lc, const char *fn, double tc, double dt, double h, unsigned int flags,
                                 double *t_reached, dfo_advance_fn advance)
{
    double t_target = 0.0;
    lc->work_by_events = 0;
    const dfo_inst_status chk = dfo_inst_check_step(lc, fn, tc, dt, h, &t_target);
    if (chk != DFO_INST_OK) return chk;
    const dfo_inst_status st = advance(lc, fn, t_target, (flags & DFO_STEP_STOP_AT_SWITCH) != 0);
    if (st == DFO_INST_OK && t_reached) *t_reached = lc->run.time;
    return st;
}

dfo_inst_status dfo_inst_step_events_by(dfo_lifecycle *lc, const char *fn, double tc, double dt, double h,
                                        const dfo_event_opts *opt, dfo_step_result *res, dfo_advance_fn advance)
{
    dfo_inst_status done;
    double t_target = 0.0;
    lc->work_by_events = 0;
    if (dfo_inst_events_begin(lc, fn, tc, dt, h, opt, res, &done, &t_target)) return done;
    const dfo_inst_status st = advance(lc, fn, t_target, opt->early_return || opt->intermediate);
    if (st != DFO_INST_OK) return st;
    const int switched = lc->switched;
    if (switched && opt->intermediate) opt->intermediate(opt->ctx, lc->run.time, opt->early_return, 0);
    if (switched && lc->run.time < t_target && !opt->early_return) {
        /* a switch inside the step without early return: go on to the target */
        const dfo_inst_status st2 = advance(lc, fn, t_target, 0);
        if (st2 != DFO_INST_OK) return st2;
    }
    res->t_reached = lc->run.time;
    res->early = lc->run.time < t_target;
    res->event = opt->event_mode && switched;
    if (res->event) {
        lc->run.event_pending = 1;
        lc->run.event_from = 0;
    }
    return DFO_INST_OK;
}

/* ---- deserialised runs ----------------------------------------------------------------------- */

const char *dfo_run_implausible(const dfo_run *r, int config)
{
    const int ph = (int)r->phase;
    if (ph != DFO_PHASE_INSTANTIATED && ph != DFO_PHASE_INIT && ph != DFO_PHASE_STEP && ph != DFO_PHASE_TERMINATED &&
        ph != DFO_PHASE_ERROR && ph != DFO_PHASE_EVENT && !(config && ph == DFO_PHASE_CONFIG))
        return "the life-cycle phase is invalid";
    if ((r->event_pending != 0 && r->event_pending != 1) || r->event_from < -1 || r->event_from > 1)
        return "the pending event is invalid";
    if (r->stop_defined != 0 && r->stop_defined != 1) return "the stop time flag is invalid";
    if (!isfinite(r->start_time) || !isfinite(r->stop_time) || !isfinite(r->time))
        return "the experiment's times are not finite";
    return NULL;
}

const char *dfo_grid_implausible(const dfo_run *r, double t0, long long n_grid, double h, double t)
{
    /* the time lies on the internal grid's interval n: t0 + n h <= t < t0 + (n + 1) h */
    const double slack = 1e-6 * h + 8.0 * DBL_EPSILON * fabs(t);
    if (t < t0 || t0 + (double)n_grid * h > t + slack || t0 + (double)(n_grid + 1) * h < t - slack)
        return "the time does not match the internal grid";
    /* once started, the host's time is the stepper's within its snap tolerance */
    if ((r->phase & DFO_PHASES_STARTED) && fabs(r->time - t) > dfo_snap(h, r->time) + slack)
        return "the host's time does not match the state's";
    return NULL;
}

/* ---- the life cycle's model-independent steps ------------------------------------------------- */

dfo_inst_status dfo_inst_setup(dfo_lifecycle *lc, const char *fn, double start_time, int stop_defined,
                               double stop_time)
{
    if (!isfinite(start_time)) return dfo_inst_fail(lc, "%s: startTime %g is not finite.", fn, start_time);
    if (stop_defined && !(stop_time >= start_time))
        return dfo_inst_fail(lc, "%s: stopTime %.17g must be finite and >= startTime %.17g.", fn, stop_time,
                             start_time);
    lc->run.start_time = start_time;
    lc->run.stop_defined = stop_defined ? 1 : 0;
    lc->run.stop_time = stop_defined ? stop_time : 0.0;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_enter_init(dfo_lifecycle *lc)
{
    lc->run.phase = DFO_PHASE_INIT;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_terminate(dfo_lifecycle *lc)
{
    lc->run.phase = DFO_PHASE_TERMINATED;
    return DFO_INST_OK;
}

int dfo_inst_update_events(dfo_lifecycle *lc)
{
    const int pending = lc->run.event_pending;
    lc->run.event_pending = 0;
    return pending;
}

double dfo_inst_time(const dfo_lifecycle *lc) { return lc->run.time; }

const char *dfo_scale_refused(double limit, double F, const char *F_text, double m, const char *m_name, double k,
                              const char *k_name, char *buf, size_t len)
{
    const double lo = 1.0 / limit, floor = lo * lo;
    if (k != 0.0 && !(k >= lo)) {
        char kt[32]; /* the shortest of 15 and 17 digits that reads back as k */
        snprintf(kt, sizeof kt, "%.15g", k);
        if (strtod(kt, NULL) != k) snprintf(kt, sizeof kt, "%.17g", k);
        snprintf(buf, len, "invalid value %s for %s; valid range: 0 (no spring) or %g to %g N/m: a softer spring "
                 "takes the oscillator's scales (the natural frequency sqrt(k/m) among them) out of double precision",
                 kt, k_name, lo, limit);
        return buf;
    }
    if (!(F > 0.0)) return NULL;
    const int accel = !(F / m >= floor);
    if (!accel && !(k > 0.0 && !(F / k >= floor))) return NULL;
    snprintf(buf, len, "the motion is too small for double precision: the force scale %s = %.6g N over %s = %.6g %s "
             "is below %g %s (its velocities and accelerations underflow and the motion is lost); valid range: "
             "force scale / m >= %g m/s2 and force scale / k >= %g m (k > 0), or no force at all: choose smaller "
             "units (micrometres, micronewtons) for this oscillator",
             F_text, F, accel ? m_name : k_name, accel ? m : k, accel ? "kg" : "N/m", floor, accel ? "m/s2" : "m",
             floor, floor);
    return buf;
}
