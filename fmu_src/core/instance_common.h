/* What every instance core shares, written once (instance_common.c, compiled with each model's
 * generated variable table): logging and phase names (instance.h's dfo_inst_log, dfo_inst_fail,
 * dfo_inst_log_category, dfo_inst_set_logging, dfo_phase_name), the life cycle's steps that touch
 * only the fields every model's values have (dfo_inst_setup, dfo_inst_enter_init,
 * dfo_inst_terminate, dfo_inst_update_events, dfo_inst_time: start, stop and host time, phase,
 * pending event), the range check of a value
 * against its variable, the checks of a doStep's arguments, and the checksum of a serialised FMU
 * state. The model's core (instance.c: the oscillator, chain_instance.c: the chain) keeps its
 * values, outputs, stepping and state layout. No FMI types. */
#ifndef DFO_INSTANCE_COMMON_H
#define DFO_INSTANCE_COMMON_H

#include "instance.h"

#include <stddef.h>
#include <stdint.h>

#define DFO_MAX_STEPS_PER_CALL 1e9 /* internal steps one doStep may take (unless in->work_by_events) */

/* NULL when x is a valid value of var, else the valid range as text. */
const char *dfo_inst_invalid(const dfo_var_info *var, double x);

/* The checks of a doStep's arguments against the host's time (in->v.time) and stop time, with the
 * internal step h (and at most DFO_MAX_STEPS_PER_CALL steps of it, unless in->work_by_events);
 * *t_target = tc + dt. */
dfo_inst_status dfo_inst_check_step(const dfo_instance *in, const char *fn, double tc, double dt, double h,
                                    double *t_target);

/* The start of dfo_inst_do_step_events in every core: a pending event is handled by this step;
 * without early return and intermediate update the events are handled inside the step, which is
 * then dfo_inst_do_step's, bit for bit. Returns 1 when the step is done (its status in *st), else 0
 * with its arguments checked and *t_target set. */
int dfo_inst_events_begin(dfo_instance *in, const char *fn, double tc, double dt, double h, const dfo_event_opts *opt,
                          dfo_step_result *res, dfo_inst_status *st, double *t_target);

/* FNV-1a over n bytes: the checksum of a serialised FMU state. */
uint64_t dfo_inst_checksum(const unsigned char *p, size_t n);

#endif
