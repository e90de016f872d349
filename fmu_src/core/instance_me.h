/* The Model Exchange API a model's instance core provides when its description declares
 * <ModelExchange> (model_vars.h: DFO_MODEL_EXCHANGE 1), for the glues fmi2_me.c and fmi3_me.c.
 * Generic: no model header, no FMI types. The glue checks the phase of each call (its state table)
 * and the arrays' pointers; the core checks the sizes, naming the valid one.
 *
 * Phases: an instance made for Model Exchange (dfo_inst_me_start at instantiation) runs
 * instantiated -> initialisation -> event mode (DFO_PHASE_EVENT) <-> continuous-time mode
 * (DFO_PHASE_STEP) -> terminated; the host integrates the continuous states and handles the events
 * the event indicators announce. */
#ifndef DFO_INSTANCE_ME_H
#define DFO_INSTANCE_ME_H

#include "instance.h"

#include <stddef.h>

/* What an event update reports to the host. */
typedef struct {
    int discrete_states_need_update; /* call the update again (never: no event iteration) */
    int terminate;                   /* the simulation must end */
    int nominals_changed;            /* the states' nominal values changed */
    int values_changed;              /* the host must read the continuous states again */
    int next_time_defined;           /* a time event is due at next_time */
    double next_time;
} dfo_me_event_info;

/* The instance is run by a host's integrator (Model Exchange): called once, right after
 * dfo_inst_new; every other dfo_inst_me_* function needs it. */
void dfo_inst_me_start(dfo_lifecycle *lc);
/* The number of continuous states and of event indicators of the instance (fixed for the model, or
 * by its structural parameters: read after configuration mode). */
size_t dfo_inst_me_n_states(const dfo_lifecycle *lc);
size_t dfo_inst_me_n_indicators(const dfo_lifecycle *lc);

/* The end of initialisation: dfo_inst_exit_init, then event mode. */
dfo_inst_status dfo_inst_me_exit_init(dfo_lifecycle *lc, const char *fn);
/* (Event mode and continuous-time mode: the glue sets the phase, DFO_PHASE_EVENT or DFO_PHASE_STEP.) */
/* The event update: the new discrete state (mode) from the continuous states, once (no iteration). */
dfo_inst_status dfo_inst_me_update(dfo_lifecycle *lc, const char *fn, dfo_me_event_info *info);
/* The end of an accepted integrator step: *enter_event_mode when the host must handle an event
 * there (a step event), *terminate when the simulation must end. */
dfo_inst_status dfo_inst_me_completed_step(dfo_lifecycle *lc, const char *fn, int *enter_event_mode, int *terminate);

dfo_inst_status dfo_inst_me_set_time(dfo_lifecycle *lc, const char *fn, double t);
dfo_inst_status dfo_inst_me_set_states(dfo_lifecycle *lc, const char *fn, const double x[], size_t nx);
dfo_inst_status dfo_inst_me_get_states(dfo_lifecycle *lc, const char *fn, double x[], size_t nx);
dfo_inst_status dfo_inst_me_nominals(dfo_lifecycle *lc, const char *fn, double x_nominal[], size_t nx);
/* The time derivatives of the continuous states; no allocation. */
dfo_inst_status dfo_inst_me_derivatives(dfo_lifecycle *lc, const char *fn, double dx[], size_t nx);
/* The event indicators (continuous distances; an event where one reaches 0); no allocation. */
dfo_inst_status dfo_inst_me_indicators(dfo_lifecycle *lc, const char *fn, double z[], size_t nz);

#endif
