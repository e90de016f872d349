/* What the FMI 3.0 glues share (fmi3_cs.c: the life cycle, variables, co-simulation, FMU states;
 * fmi3_me.c: Model Exchange): the glue's instance, the status mapping, the phases and the check of
 * the phase in which a function is called (each glue's part of the state table: PHASES_<function>
 * next to its functions). No model names. */
#ifndef DFO_FMI3_GLUE_H
#define DFO_FMI3_GLUE_H

#include "fmi3Functions.h"
#include "instance_common.h" /* the model API, its variable table (dfo_find_var), model_vars.h */

#include <string.h>

/* ---- instance: the model's core plus what FMI 3.0 gives at instantiation ---------------------- */

typedef struct {
    dfo_lifecycle *core;         /* the model's instance (its life cycle first) */
    char *name;
    fmi3InstanceEnvironment env;
    fmi3LogMessageCallback logger;
    fmi3IntermediateUpdateCallback update;
    int early_return_allowed, event_mode_used;
    int in_update; /* inside the intermediate-update callback: only getters may be called, */
    int set_requested; /* and, where the step reads its inputs, fmi3SetFloat64 of the inputs declared
                        * intermediateUpdate="true" */
    int me;            /* made for Model Exchange (fmi3InstantiateModelExchange) */
} Instance;

static inline fmi3Status status_of(dfo_inst_status st)
{
    switch (st) {
    case DFO_INST_OK: return fmi3OK;
    case DFO_INST_WARNING: return fmi3Warning;
    case DFO_INST_ERROR: return fmi3Error;
    }
    return fmi3Error;
}

/* ---- the state table: in which phases each function may be called ---------------------------- */

#define P_INST DFO_PHASE_INSTANTIATED
#define P_INIT DFO_PHASE_INIT
#define P_STEP DFO_PHASE_STEP
#define P_EVENT DFO_PHASE_EVENT
#define P_TERM DFO_PHASE_TERMINATED
#define P_ERR DFO_PHASE_ERROR
#define P_ANY DFO_PHASE_ANY
#define P_CONFIG DFO_PHASE_CONFIG
#define P_GET (P_INIT | P_STEP | P_EVENT | P_TERM | P_ERR | P_CONFIG)
#define P_SET (P_INST | P_INIT | P_STEP | P_EVENT | P_CONFIG)

/* Functions a host may call from inside the intermediate-update callback (fmi3SetFloat64 of the
 * inputs declared intermediateUpdate="true" too, where the step asks for them: see fmi3SetFloat64). */
#define IN_UPDATE_OK(in, fn)                                                                                     \
    ((!strncmp(fn, "fmi3Get", 7) && strcmp(fn, "fmi3GetFMUState") != 0) ||                                     \
     ((in)->set_requested && !strcmp(fn, "fmi3SetFloat64")))

/* The instance is usable (non-NULL) and in one of the allowed phases; logs the call (logAll). */
static inline int allowed(Instance *in, const char *fn, int phases)
{
    if (!in) return 0;
    dfo_inst_log(in->core, DFO_INST_OK, DFO_LOG_ALL, "%s", fn);
    if (in->in_update && !IN_UPDATE_OK(in, fn)) {
        dfo_inst_fail(in->core, "%s must not be called from the intermediate-update callback (only getters may).",
                      fn);
        return 0;
    }
    if (in->core->run.phase & phases) return 1;
    dfo_inst_fail(in->core, "%s must not be called in %s.", fn, dfo_phase_name(in->core->run.phase));
    return 0;
}

#define BEGIN(fn)                                   \
    Instance *in = (Instance *)instance;            \
    if (!allowed(in, #fn, PHASES_##fn)) return fmi3Error
#define FAIL(...) ((void)dfo_inst_fail(in->core, __VA_ARGS__), fmi3Error)

#endif
