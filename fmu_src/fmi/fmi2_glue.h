/* What the FMI 2.0 glues share (fmi2_cs.c: the life cycle, variables, co-simulation, FMU states;
 * fmi2_me.c: Model Exchange): the glue's instance, the status mapping, the phases and the check of
 * the phase in which a function is called (each glue's part of the state table: PHASES_<function>
 * next to its functions). No model names. */
#ifndef DFO_FMI2_GLUE_H
#define DFO_FMI2_GLUE_H

#include "fmi2Functions.h"
#include "instance.h"
#include "model_vars.h" /* MODEL_GUID, the log categories, DFO_MODEL_EXCHANGE */

/* ---- instance: the model's core plus what FMI 2.0 gives at instantiation ---------------------- */

typedef struct {
    dfo_lifecycle *core;         /* the model's instance (its life cycle first) */
    fmi2CallbackFunctions cb;
    char *name;
    int me;                      /* made for Model Exchange (fmi2ModelExchange) */
} Instance;

static inline fmi2Status status_of(dfo_inst_status st)
{
    switch (st) {
    case DFO_INST_OK: return fmi2OK;
    case DFO_INST_WARNING: return fmi2Warning;
    case DFO_INST_ERROR: return fmi2Error;
    }
    return fmi2Error;
}

/* ---- the state table: in which phases each function may be called ---------------------------- */

#define P_INST DFO_PHASE_INSTANTIATED
#define P_INIT DFO_PHASE_INIT
#define P_STEP DFO_PHASE_STEP
#define P_TERM DFO_PHASE_TERMINATED
#define P_ERR DFO_PHASE_ERROR
#define P_ANY DFO_PHASE_ANY

/* (DFO_PHASE_EVENT is Model Exchange's event mode; DFO_PHASE_STEP its continuous-time mode) */
#define P_EVENT DFO_PHASE_EVENT

/* The instance is usable (non-NULL) and in one of the allowed phases; logs the call (logAll). */
static inline int allowed(Instance *in, const char *fn, int phases)
{
    if (!in) return 0;
    dfo_inst_log(in->core, DFO_INST_OK, DFO_LOG_ALL, "%s", fn);
    if (in->core->run.phase & phases) return 1;
    dfo_inst_fail(in->core, "%s must not be called in %s.", fn, dfo_phase_name(in->core->run.phase));
    return 0;
}

#define BEGIN(fn)                                   \
    Instance *in = (Instance *)c;                   \
    if (!allowed(in, #fn, PHASES_##fn)) return fmi2Error
#define FAIL(...) ((void)dfo_inst_fail(in->core, __VA_ARGS__), fmi2Error)

#endif
