/* What every model's instance core shares, written once (instance_common.c, compiled with each
 * model's generated variable table model_vars.h): the variable table's lookup (dfo_find_var,
 * dfo_type_name), the checks of a value against its variable and of a setter's causality and
 * phase, the checks of a doStep's arguments, the start of a step with events, the snap tolerance
 * of the host's time on the internal grid, and the plausibility of a deserialised run. The model's
 * core keeps its values, outputs, stepping and state layout. No FMI types. */
#ifndef DFO_INSTANCE_COMMON_H
#define DFO_INSTANCE_COMMON_H

#include "instance.h"
#include "model_vars.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

#define DFO_MAX_STEPS_PER_CALL 1e9 /* internal steps one doStep may take (unless lc->work_by_events) */

/* The variable of a value reference (NULL when none). */
const dfo_var_info *dfo_find_var(unsigned int vr);
/* An input a host may set during an FMI 3.0 intermediate update (declared intermediateUpdate="true":
 * the continuous real inputs of a model that can interpolate its inputs). */
static inline int dfo_intermediate_input(const dfo_var_info *var)
{
    return DFO_CAN_INTERPOLATE_INPUTS && var->causality == DFO_INPUT && var->type == DFO_REAL &&
           var->variability == DFO_CONTINUOUS;
}
/* "Real", "Integer", "Boolean", "UInt64". */
const char *dfo_type_name(dfo_var_type t);

/* NULL when x is a valid value of var, else the valid range as text. */
const char *dfo_inst_invalid(const dfo_var_info *var, double x);

/* The variable of vr when it is of type, else NULL with the reason logged (unknown value
 * reference, or the variable's name and its type). Scalar variable tables only. */
const dfo_var_info *dfo_inst_lookup(const dfo_lifecycle *lc, const char *fn, unsigned int vr, dfo_var_type type);
/* Whether x is a valid value of var; logs the variable, the value and the valid range when not. */
int dfo_inst_value_ok(const dfo_lifecycle *lc, const char *fn, const dfo_var_info *var, double x);

#ifdef DFO_VARS_BY_OFFSET
/* Where a stored value of a scalar variable table lives: in the model's parameter struct p or its
 * input struct u (the generated offsets). */
static inline void *dfo_var_slot(void *p, void *u, const dfo_var_info *var)
{
    return (char *)(var->home == DFO_IN_PARAMS ? p : u) + var->offset;
}
/* Store a checked value there; setting an input raises its flag (an input never set is never read). */
static inline void dfo_var_store(void *p, void *u, const dfo_var_info *var, double x)
{
    if (var->type == DFO_REAL) *(double *)dfo_var_slot(p, u, var) = x;
    else *(int *)dfo_var_slot(p, u, var) = (int)x;
    if (var->home == DFO_IN_INPUTS) *(int *)((char *)u + var->set_offset) = 1;
}
#endif

/* Whether a variable of this causality may be set in the current phase; logs the reason (naming the
 * variable `name`, value reference vr) when not. */
int dfo_inst_settable(const dfo_lifecycle *lc, const char *fn, const dfo_var_info *var, const char *name,
                      unsigned int vr);

/* The checks of a doStep's arguments against the host's time (lc->run.time) and stop time, with the
 * internal step h (and at most DFO_MAX_STEPS_PER_CALL steps of it, unless lc->work_by_events);
 * *t_target = tc + dt. */
dfo_inst_status dfo_inst_check_step(const dfo_lifecycle *lc, const char *fn, double tc, double dt, double h,
                                    double *t_target);

/* The start of dfo_inst_do_step_events in every core: a pending event is handled by this step;
 * without early return and intermediate update the events are handled inside the step, which is
 * then dfo_inst_do_step's, bit for bit. Returns 1 when the step is done (its status in *st), else 0
 * with its arguments checked and *t_target set. */
int dfo_inst_events_begin(dfo_lifecycle *lc, const char *fn, double tc, double dt, double h,
                          const dfo_event_opts *opt, dfo_step_result *res, dfo_inst_status *st, double *t_target);

/* A model's step from its state's time to t_target (stop_at_switch: end at the first switch strictly
 * inside), the life cycle's time set to where it ended; DFO_INST_OK or the failure, logged. */
typedef dfo_inst_status (*dfo_advance_fn)(dfo_lifecycle *lc, const char *fn, double t_target, int stop_at_switch);

/* dfo_inst_do_step of a model that steps by advance (internal step h) and keeps no left limits:
 * the step checked, taken (DFO_STEP_STOP_AT_SWITCH: to the first switch), *t_reached set. */
dfo_inst_status dfo_inst_step_by(dfo_lifecycle *lc, const char *fn, double tc, double dt, double h, unsigned int flags,
                                 double *t_reached, dfo_advance_fn advance);

/* dfo_inst_do_step_events of such a model: with early return the step ends at the first switch
 * strictly inside it (the state just after it); the intermediate update called at a switch; in event
 * mode a switch on which the step ends stays pending until the host handles it (the outputs are the
 * right limits already). */
dfo_inst_status dfo_inst_step_events_by(dfo_lifecycle *lc, const char *fn, double tc, double dt, double h,
                                        const dfo_event_opts *opt, dfo_step_result *res, dfo_advance_fn advance);

/* The snap tolerance: a stepper's time within it of a target t (internal step h) stands on it. */
static inline double dfo_snap(double h, double t) { return fmax(1e-9 * h, 8.0 * DBL_EPSILON * fabs(t)); }

/* The scales a run honours, limit the model's DFO_SCALE_LIMIT (m's declared maximum, 1/limit its
 * minimum): a stiffness k (named k_name) is 0 or within [1/limit, limit] N/m, and a force scale F > 0
 * (F_text: how it is formed) gives an acceleration scale F/m and, with k > 0, a static deflection
 * F/k of at least 1/limit^2 (m/s2, m); below that the motion underflows double precision and is
 * lost (measured: stuck where it slides, with status OK). NULL when inside, else the sentence in
 * buf naming the variables and the valid range. */
const char *dfo_scale_refused(double limit, double F, const char *F_text, double m, const char *m_name, double k,
                              const char *k_name, char *buf, size_t len);

/* A deserialised run: NULL when plausible, else why not. config: the model has a configuration mode. */
const char *dfo_run_implausible(const dfo_run *r, int config);
/* A deserialised stepper time t on the internal grid (start t0, interval n_grid of step h) and, once
 * started, the host's time within the snap tolerance of it: NULL, else why not. */
const char *dfo_grid_implausible(const dfo_run *r, double t0, long long n_grid, double h, double t);

#endif
