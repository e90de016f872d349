/* FMI 2.0 co-simulation glue, the same for every model: the fmi2 signatures, argument checks,
 * status mapping and the table of the phases in which each function may be called (the functions
 * of Model Exchange, for a model that declares it: fmi2_me.c, over core/instance_me.h). Everything
 * else (life cycle, get/set through the generated variable table, doStep, FMU states, logging) is
 * the model's FMI-independent instance core behind core/instance.h (the oscillator's
 * models/oscillator/osc_instance.c, the chain's models/chain/chain_instance.c), of which this file
 * sees only the life cycle (dfo_lifecycle) and the model API. The model's generated model_vars.h
 * gives its GUID, its log categories and whether it has Model Exchange (DFO_MODEL_EXCHANGE: its
 * functions in fmi2_me.c, errors there for a model without it). */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "fmi2_glue.h"
#if DFO_MODEL_EXCHANGE
#include "instance_me.h"
#endif

#include <string.h>

static void *host_alloc(void *ctx, size_t n, size_t size)
{
    return ((Instance *)ctx)->cb.allocateMemory(n, size);
}

static void host_free(void *ctx, void *p) { ((Instance *)ctx)->cb.freeMemory(p); }

static void host_log(void *ctx, dfo_inst_status status, const char *category, const char *message)
{
    const Instance *in = (const Instance *)ctx;
    const fmi2Status st = status == DFO_INST_OK ? fmi2OK : status == DFO_INST_WARNING ? fmi2Warning : fmi2Error;
    in->cb.logger(in->cb.componentEnvironment, in->name, st, category, message);
}

/* ---- the state table (Model Exchange's functions: fmi2_me.c; P_EVENT, its event mode, is never
 * reached in co-simulation) ------------------------------------------------------------------------- */

#define PHASES_fmi2SetDebugLogging P_ANY
#define PHASES_fmi2SetupExperiment P_INST
#define PHASES_fmi2EnterInitializationMode P_INST
#define PHASES_fmi2ExitInitializationMode P_INIT
#define PHASES_fmi2Terminate (P_STEP | P_EVENT | P_ERR)
#define PHASES_fmi2Reset P_ANY
#define PHASES_fmi2GetReal (P_INIT | P_STEP | P_EVENT | P_TERM | P_ERR)
#define PHASES_fmi2GetInteger (P_INIT | P_STEP | P_EVENT | P_TERM | P_ERR)
#define PHASES_fmi2GetBoolean (P_INIT | P_STEP | P_EVENT | P_TERM | P_ERR)
#define PHASES_fmi2GetString (P_INIT | P_STEP | P_EVENT | P_TERM | P_ERR)
#define PHASES_fmi2SetReal (P_INST | P_INIT | P_STEP | P_EVENT)
#define PHASES_fmi2SetInteger (P_INST | P_INIT | P_STEP | P_EVENT)
#define PHASES_fmi2SetBoolean (P_INST | P_INIT | P_STEP | P_EVENT)
#define PHASES_fmi2SetString (P_INST | P_INIT | P_STEP | P_EVENT)
#define PHASES_fmi2DoStep P_STEP
#define PHASES_fmi2CancelStep P_STEP
#define PHASES_fmi2SetRealInputDerivatives (P_INST | P_INIT | P_STEP)
#define PHASES_fmi2GetRealOutputDerivatives (P_STEP | P_TERM | P_ERR)
#define PHASES_fmi2GetStatus P_ANY
#define PHASES_fmi2GetRealStatus P_ANY
#define PHASES_fmi2GetIntegerStatus P_ANY
#define PHASES_fmi2GetBooleanStatus P_ANY
#define PHASES_fmi2GetStringStatus P_ANY
#define PHASES_fmi2GetFMUstate (P_INIT | P_STEP | P_EVENT | P_TERM | P_ERR)
#define PHASES_fmi2SetFMUstate (P_INST | P_INIT | P_STEP | P_EVENT | P_TERM | P_ERR)
#define PHASES_fmi2FreeFMUstate P_ANY
#define PHASES_fmi2SerializedFMUstateSize P_ANY
#define PHASES_fmi2SerializeFMUstate P_ANY
#define PHASES_fmi2DeSerializeFMUstate P_ANY
#define PHASES_fmi2GetDirectionalDerivative (P_INIT | P_STEP | P_EVENT | P_TERM | P_ERR)

static int check_arrays(Instance *in, const char *fn, const fmi2ValueReference vr[], size_t nvr, const void *value)
{
    if (nvr > 0 && (!vr || !value)) {
        dfo_inst_fail(in->core, "%s: the value reference or value array is NULL.", fn);
        return 0;
    }
    return 1;
}

/* ---- FMI functions --------------------------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn)
{
    (void)visible;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    /* errors before there is an instance: logged through a temporary one */
    Instance tmp;
    memset(&tmp, 0, sizeof tmp);
    tmp.cb = *functions;
    tmp.name = (char *)(instanceName ? instanceName : "?");
    const dfo_host tmp_host = {&tmp, host_alloc, host_free, functions->logger ? host_log : NULL};
    dfo_lifecycle tmp_lc; /* only its logging is used */
    dfo_lifecycle_init(&tmp_lc, &tmp_host, tmp.name, 0);
    if (!instanceName || !*instanceName) {
        dfo_inst_fail(&tmp_lc, "fmi2Instantiate: the instance name must be a non-empty string.");
        return NULL;
    }
    if (fmuType != fmi2CoSimulation && !(DFO_MODEL_EXCHANGE && fmuType == fmi2ModelExchange)) {
        dfo_inst_fail(&tmp_lc, DFO_MODEL_EXCHANGE ? "fmi2Instantiate: fmuType %d is neither fmi2ModelExchange (0) nor "
                                                    "fmi2CoSimulation (1)."
                                                  : "fmi2Instantiate: this FMU supports co-simulation only (fmuType %d "
                                                    "requested).",
                      (int)fmuType);
        return NULL;
    }
    if (!fmuGUID || strcmp(fmuGUID, MODEL_GUID) != 0) {
        dfo_inst_fail(&tmp_lc, "fmi2Instantiate: GUID %s does not match the FMU's GUID %s.",
                      fmuGUID ? fmuGUID : "(null)", MODEL_GUID);
        return NULL;
    }
    Instance *in = (Instance *)functions->allocateMemory(1, sizeof(Instance));
    if (!in) return NULL;
    const size_t len = strlen(instanceName) + 1;
    in->name = (char *)functions->allocateMemory(len, 1);
    if (!in->name) {
        functions->freeMemory(in);
        return NULL;
    }
    memcpy(in->name, instanceName, len);
    in->cb = *functions;
    const dfo_host host = {in, host_alloc, host_free, functions->logger ? host_log : NULL};
    in->core = dfo_inst_new(&host, in->name, loggingOn ? 1 : 0);
    if (!in->core) {
        functions->freeMemory(in->name);
        functions->freeMemory(in);
        return NULL;
    }
    if (in->core->resources) { /* a model that reads its resources: the URI as a native path */
        const size_t cap = fmuResourceLocation ? strlen(fmuResourceLocation) + 1 : 1;
        char *dir = (char *)functions->allocateMemory(cap, 1);
        const int have = dir && dfo_path_of_file_uri(fmuResourceLocation, dir, cap);
        const dfo_inst_status st = dir ? dfo_inst_resources(in->core, have ? dir : NULL, DFO_RES_LOAD)
                                       : dfo_inst_fail(in->core, "fmi2Instantiate: out of memory.");
        if (dir) functions->freeMemory(dir);
        if (st == DFO_INST_ERROR) {
            (void)dfo_inst_resources(in->core, NULL, DFO_RES_FREE);
    dfo_inst_delete(in->core);
            functions->freeMemory(in->name);
            functions->freeMemory(in);
            return NULL;
        }
    }
#if DFO_MODEL_EXCHANGE
    in->me = fmuType == fmi2ModelExchange;
    if (in->me) dfo_inst_me_start(in->core);
#endif
    dfo_inst_log(in->core, DFO_INST_OK, DFO_LOG_ALL, "fmi2Instantiate");
    return in;
}

void fmi2FreeInstance(fmi2Component c)
{
    Instance *in = (Instance *)c;
    if (!in) return;
    dfo_inst_log(in->core, DFO_INST_OK, DFO_LOG_ALL, "fmi2FreeInstance");
    (void)dfo_inst_resources(in->core, NULL, DFO_RES_FREE);
    dfo_inst_delete(in->core);
    fmi2CallbackFreeMemory freeMemory = in->cb.freeMemory;
    freeMemory(in->name);
    freeMemory(in);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    BEGIN(fmi2SetDebugLogging);
    if (nCategories > 0 && !categories) return FAIL("fmi2SetDebugLogging: categories is NULL.");
    for (size_t i = 0; i < nCategories; i++)
        if (dfo_inst_log_category(categories[i]) < 0)
            return FAIL("fmi2SetDebugLogging: unknown log category %s.", categories[i] ? categories[i] : "(null)");
    if (nCategories == 0) dfo_inst_set_logging(in->core, -1, loggingOn);
    for (size_t i = 0; i < nCategories; i++)
        dfo_inst_set_logging(in->core, dfo_inst_log_category(categories[i]), loggingOn);
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    BEGIN(fmi2SetupExperiment);
    (void)toleranceDefined;
    (void)tolerance;
    return status_of(dfo_inst_setup(in->core, "fmi2SetupExperiment", startTime, stopTimeDefined, stopTime));
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    BEGIN(fmi2EnterInitializationMode);
    return status_of(dfo_inst_enter_init(in->core));
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    BEGIN(fmi2ExitInitializationMode);
#if DFO_MODEL_EXCHANGE
    if (in->me) return status_of(dfo_inst_me_exit_init(in->core, "fmi2ExitInitializationMode")); /* to event mode */
#endif
    return status_of(dfo_inst_exit_init(in->core, "fmi2ExitInitializationMode"));
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    BEGIN(fmi2Terminate);
    return status_of(dfo_inst_terminate(in->core));
}

fmi2Status fmi2Reset(fmi2Component c)
{
    BEGIN(fmi2Reset);
    dfo_inst_reset(in->core);
    (void)dfo_inst_resources(in->core, NULL, DFO_RES_APPLY);
    return fmi2OK;
}

/* ---- variables: fmi2ValueReference is unsigned int, fmi2Integer and fmi2Boolean are int ------- */

#define GET_SET(fn, core_fn, value_t)                                                                  \
    fmi2Status fn(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, value_t value[])         \
    {                                                                                                   \
        BEGIN(fn);                                                                                      \
        if (!check_arrays(in, #fn, vr, nvr, value)) return fmi2Error;                                  \
        return status_of(core_fn(in->core, #fn, vr, nvr, value));                                      \
    }

GET_SET(fmi2GetReal, dfo_inst_get_real, fmi2Real)
GET_SET(fmi2GetInteger, dfo_inst_get_int, fmi2Integer)
GET_SET(fmi2GetBoolean, dfo_inst_get_bool, fmi2Boolean)
GET_SET(fmi2SetReal, dfo_inst_set_real, const fmi2Real)
GET_SET(fmi2SetInteger, dfo_inst_set_int, const fmi2Integer)
GET_SET(fmi2SetBoolean, dfo_inst_set_bool, const fmi2Boolean)

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{
    BEGIN(fmi2GetString);
    (void)value;
    if (nvr == 0) return fmi2OK;
    return FAIL("fmi2GetString: the FMU has no String variables (value reference %u).", vr ? vr[0] : 0u);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{
    BEGIN(fmi2SetString);
    (void)value;
    if (nvr == 0) return fmi2OK;
    return FAIL("fmi2SetString: the FMU has no String variables (value reference %u).", vr ? vr[0] : 0u);
}

/* ---- co-simulation --------------------------------------------------------------------------- */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    BEGIN(fmi2DoStep);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (in->me) return FAIL("fmi2DoStep: the instance was made for Model Exchange (fmuType fmi2ModelExchange); "
                            "co-simulation needs one made with fmuType fmi2CoSimulation.");
    /* FMI 2.0 has no early return: always up to the communication point */
    return status_of(dfo_inst_do_step(in->core, "fmi2DoStep", currentCommunicationPoint, communicationStepSize, 0,
                                      NULL));
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    BEGIN(fmi2CancelStep);
    return FAIL("fmi2CancelStep: steps are synchronous and cannot be cancelled.");
}

/* The orders and values of input and output derivatives: one per value reference. */
static int check_derivative_arrays(Instance *in, const char *fn, const fmi2ValueReference vr[], size_t nvr,
                                   const fmi2Integer order[], const void *value)
{
    if (nvr > 0 && (!vr || !order || !value)) {
        dfo_inst_fail(in->core, "%s: the value reference, order or value array is NULL.", fn);
        return 0;
    }
    return 1;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    BEGIN(fmi2SetRealInputDerivatives);
    if (!check_derivative_arrays(in, "fmi2SetRealInputDerivatives", vr, nvr, order, value)) return fmi2Error;
    return status_of(dfo_inst_set_input_derivatives(in->core, "fmi2SetRealInputDerivatives", vr, nvr, order, value));
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    BEGIN(fmi2GetRealOutputDerivatives);
    if (!check_derivative_arrays(in, "fmi2GetRealOutputDerivatives", vr, nvr, order, value)) return fmi2Error;
    return status_of(dfo_inst_get_output_derivatives(in->core, "fmi2GetRealOutputDerivatives", vr, nvr, order, value));
}

#define NO_STATUS(fn)                                                                             \
    return FAIL("%s: steps are synchronous; there is no asynchronous status to report.", #fn)

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    BEGIN(fmi2GetStatus);
    (void)s; (void)value;
    NO_STATUS(fmi2GetStatus);
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    BEGIN(fmi2GetRealStatus);
    if (s == fmi2LastSuccessfulTime && value) {
        *value = dfo_inst_time(in->core);
        return fmi2OK;
    }
    NO_STATUS(fmi2GetRealStatus);
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    BEGIN(fmi2GetIntegerStatus);
    (void)s; (void)value;
    NO_STATUS(fmi2GetIntegerStatus);
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    BEGIN(fmi2GetBooleanStatus);
    (void)s; (void)value;
    NO_STATUS(fmi2GetBooleanStatus);
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    BEGIN(fmi2GetStringStatus);
    (void)s; (void)value;
    NO_STATUS(fmi2GetStringStatus);
}

/* ---- FMU state ------------------------------------------------------------------------------- */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    BEGIN(fmi2GetFMUstate);
    if (!FMUstate) return FAIL("fmi2GetFMUstate: FMUstate is NULL.");
    return status_of(dfo_inst_get_state(in->core, "fmi2GetFMUstate", FMUstate));
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    BEGIN(fmi2SetFMUstate);
    return status_of(dfo_inst_set_state(in->core, "fmi2SetFMUstate", FMUstate));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    BEGIN(fmi2FreeFMUstate);
    if (!FMUstate) return FAIL("fmi2FreeFMUstate: FMUstate is NULL.");
    return status_of(dfo_inst_free_state(in->core, "fmi2FreeFMUstate", FMUstate));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    BEGIN(fmi2SerializedFMUstateSize);
    if (!size) return FAIL("fmi2SerializedFMUstateSize: size is NULL.");
    *size = dfo_inst_state_size(in->core, FMUstate);
    if (*size == 0) return FAIL("fmi2SerializedFMUstateSize: FMUstate is NULL or not a state of this FMU.");
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size)
{
    BEGIN(fmi2SerializeFMUstate);
    if (!FMUstate) return FAIL("fmi2SerializeFMUstate: FMUstate is NULL or not a state of this FMU.");
    if (!serializedState) return FAIL("fmi2SerializeFMUstate: serializedState is NULL.");
    return status_of(dfo_inst_serialize(in->core, "fmi2SerializeFMUstate", FMUstate,
                                        (unsigned char *)serializedState, size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    BEGIN(fmi2DeSerializeFMUstate);
    if (!serializedState || !FMUstate) return FAIL("fmi2DeSerializeFMUstate: serializedState or FMUstate is NULL.");
    return status_of(dfo_inst_deserialize(in->core, "fmi2DeSerializeFMUstate",
                                          (const unsigned char *)serializedState, size, FMUstate));
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[])
{
    BEGIN(fmi2GetDirectionalDerivative);
    if ((nUnknown > 0 && (!vUnknown_ref || !dvUnknown)) || (nKnown > 0 && (!vKnown_ref || !dvKnown)))
        return FAIL("fmi2GetDirectionalDerivative: the value reference, dvKnown or dvUnknown array is NULL.");
    return status_of(dfo_inst_directional(in->core, "fmi2GetDirectionalDerivative", vUnknown_ref, nUnknown, vKnown_ref,
                                          nKnown, dvKnown, dvUnknown));
}
