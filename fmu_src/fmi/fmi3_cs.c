/* FMI 3.0 co-simulation glue, the same for every model: the fmi3 signatures, argument checks
 * (value references, nValues), type mapping (Float64, Int32, Enumeration as Int64, Boolean, UInt64
 * for structural parameters), status mapping and ONE table of the phases in which each function may
 * be called. Everything else (life cycle, get/set through the generated variable table, doStep with
 * its events, configuration mode, FMU states, logging) is the model's FMI-independent instance core
 * behind core/instance.h (the oscillator's osc_instance.c, the chain's chain_instance.c), of which
 * this file sees only the life cycle (dfo_lifecycle) and the model API; shared with fmi2_cs.c.
 * Structural parameters and configuration mode: only for a model that reports them
 * (dfo_inst_has_structural), an error otherwise. Model Exchange: for a model that declares it
 * (DFO_MODEL_EXCHANGE), fmi3InstantiateModelExchange here and its own functions in fmi3_me.c
 * (without it, errors there).
 *
 * Events (docs/fmi3.md): every stick/slip switch (of any block) is an event. earlyReturnAllowed: fmi3DoStep returns at
 * the first switch inside the step. eventModeUsed (with early return): eventHandlingNeeded there,
 * the outputs are the left limits until fmi3UpdateDiscreteStates, the right limits after it. Neither:
 * the step of the FMI 2.0 FMU, bit for bit. The intermediate-update callback is called at every
 * switch inside a step; its earlyReturnRequested ends the step there when early return is allowed.
 *
 * FMI 3.0 has no memory callbacks: the instance and its FMU states are allocated with calloc. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "fmi3_glue.h"
#if DFO_MODEL_EXCHANGE
#include "instance_me.h"
#endif

#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef char dfo_static_assert_int32[sizeof(int) == sizeof(fmi3Int32) ? 1 : -1];

static void *host_alloc(void *ctx, size_t n, size_t size)
{
    (void)ctx;
    return calloc(n, size);
}

static void host_free(void *ctx, void *p)
{
    (void)ctx;
    free(p);
}

static void host_log(void *ctx, dfo_inst_status status, const char *category, const char *message)
{
    const Instance *in = (const Instance *)ctx;
    const fmi3Status st = status == DFO_INST_OK ? fmi3OK : status == DFO_INST_WARNING ? fmi3Warning : fmi3Error;
    in->logger(in->env, st, category, message);
}

/* ---- the state table (Model Exchange's functions: fmi3_me.c) --------------------------------- */

#define PHASES_fmi3SetDebugLogging P_ANY
#define PHASES_fmi3EnterInitializationMode P_INST
#define PHASES_fmi3ExitInitializationMode P_INIT
#define PHASES_fmi3EnterEventMode P_STEP
#define PHASES_fmi3EnterStepMode P_EVENT
#define PHASES_fmi3UpdateDiscreteStates P_EVENT
#define PHASES_fmi3Terminate (P_STEP | P_EVENT | P_ERR)
#define PHASES_fmi3Reset P_ANY
#define PHASES_fmi3GetFloat64 P_GET
#define PHASES_fmi3GetInt32 P_GET
#define PHASES_fmi3GetInt64 P_GET
#define PHASES_fmi3GetBoolean P_GET
#define PHASES_fmi3SetFloat64 P_SET
#define PHASES_fmi3SetInt32 P_SET
#define PHASES_fmi3SetInt64 P_SET
#define PHASES_fmi3SetBoolean P_SET
#define PHASES_fmi3DoStep P_STEP
#define PHASES_fmi3GetFMUState P_GET
#define PHASES_fmi3SetFMUState (P_INST | P_INIT | P_STEP | P_EVENT | P_TERM | P_ERR)
#define PHASES_fmi3FreeFMUState P_ANY
#define PHASES_fmi3SerializedFMUStateSize P_ANY
#define PHASES_fmi3SerializeFMUState P_ANY
#define PHASES_fmi3DeserializeFMUState P_ANY
#define PHASES_fmi3GetUInt64 (P_GET | P_INST) /* the structural parameters */
#define PHASES_fmi3SetUInt64 P_SET
#define PHASES_fmi3EnterConfigurationMode P_INST
#define PHASES_fmi3ExitConfigurationMode P_CONFIG
#define PHASES_fmi3GetOutputDerivatives (P_STEP | P_EVENT | P_TERM | P_ERR)
#define PHASES_fmi3GetDirectionalDerivative (P_INIT | P_STEP | P_EVENT | P_TERM | P_ERR)
#define PHASES_fmi3GetAdjointDerivative (P_INIT | P_STEP | P_EVENT | P_TERM | P_ERR)
#define PHASES_fmi3Unsupported P_ANY /* functions of features this FMU does not have: always an error */

/* nValues must be the number of values the variables hold (one per scalar, n per array of the
 * structural parameter n); arrays non-NULL when used. The refusal names every variable given and
 * how many values it holds. */
static int check_arrays(Instance *in, const char *fn, const fmi3ValueReference vr[], size_t nvr, const void *value,
                        size_t nValues)
{
    if (nvr > 0 && (!vr || !value)) {
        dfo_inst_fail(in->core, "%s: the value reference or value array is NULL.", fn);
        return 0;
    }
    const size_t expected = nvr > 0 ? dfo_inst_n_values(in->core, vr, nvr) : 0;
    if (nValues == expected) return 1;
    char list[256] = "";
    size_t used = 0;
    for (size_t i = 0; i < nvr && used + 1 < sizeof list; i++) {
        const dfo_var_info *var = dfo_find_var(vr[i]);
        const size_t k = dfo_inst_n_values(in->core, &vr[i], 1);
        const int w = var ? snprintf(list + used, sizeof list - used, "%s%s (%lu)", i ? ", " : "", var->name,
                                     (unsigned long)k)
                          : snprintf(list + used, sizeof list - used, "%svalue reference %u", i ? ", " : "",
                                     (unsigned)vr[i]);
        if (w < 0) break;
        used += (size_t)w;
    }
    if (used + 1 >= sizeof list) memcpy(list + sizeof list - 5, "...", 4);
    dfo_inst_fail(in->core, "%s: nValues = %lu, but the variables given hold %lu values: %s.", fn,
                  (unsigned long)nValues, (unsigned long)expected, list);
    return 0;
}


/* FMI 3.0 separates Int32 from Enumeration (accessed as Int64): the core has one integer kind. */
static int check_int_kind(Instance *in, const char *fn, const fmi3ValueReference vr[], size_t nvr, int enumeration)
{
    for (size_t i = 0; i < nvr; i++) {
        const dfo_var_info *var = dfo_find_var(vr[i]);
        if (!var || var->type != DFO_INTEGER) continue; /* the core names the error */
        if ((var->n_items > 0) != enumeration) {
            dfo_inst_fail(in->core, "%s: variable %s (value reference %u) is of type %s, not %s.", fn, var->name,
                          vr[i], var->n_items > 0 ? "Enumeration" : "Int32", enumeration ? "Enumeration" : "Int32");
            return 0;
        }
    }
    return 1;
}

static double host_time(const Instance *in)
{
    const dfo_run *r = &in->core->run;
    return (r->phase & (P_INST | P_INIT)) ? r->start_time : dfo_inst_time(in->core);
}

/* ---- FMI functions --------------------------------------------------------------------------- */

const char *fmi3GetVersion(void) { return fmi3Version; }

/* An instance for co-simulation, or (me) for Model Exchange; fn names the instantiating function. */
static fmi3Instance instantiate(const char *fn, int me, fmi3String instanceName, fmi3String instantiationToken,
                                fmi3String resourcePath, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                fmi3InstanceEnvironment env, fmi3LogMessageCallback logger,
                                fmi3IntermediateUpdateCallback update)
{
    Instance tmp;
    memset(&tmp, 0, sizeof tmp);
    tmp.env = env;
    tmp.logger = logger;
    const dfo_host tmp_host = {&tmp, host_alloc, host_free, logger ? host_log : NULL};
    dfo_lifecycle tmp_lc; /* only its logging is used */
    dfo_lifecycle_init(&tmp_lc, &tmp_host, instanceName ? instanceName : "?", 0);
    if (!instanceName || !*instanceName) {
        dfo_inst_fail(&tmp_lc, "%s: the instance name must be a non-empty string.", fn);
        return NULL;
    }
    if (!instantiationToken || strcmp(instantiationToken, MODEL_GUID) != 0) {
        dfo_inst_fail(&tmp_lc, "%s: instantiationToken %s does not match the FMU's %s.", fn,
                      instantiationToken ? instantiationToken : "(null)", MODEL_GUID);
        return NULL;
    }
    Instance *in = (Instance *)calloc(1, sizeof(Instance));
    if (!in) return NULL;
    const size_t len = strlen(instanceName) + 1;
    in->name = (char *)calloc(len, 1);
    if (!in->name) {
        free(in);
        return NULL;
    }
    memcpy(in->name, instanceName, len);
    in->env = env;
    in->logger = logger;
    in->update = update;
    in->event_mode_used = eventModeUsed ? 1 : 0;
    in->early_return_allowed = earlyReturnAllowed ? 1 : 0;
    const dfo_host host = {in, host_alloc, host_free, logger ? host_log : NULL};
    in->core = dfo_inst_new(&host, in->name, loggingOn ? 1 : 0);
    if (!in->core) {
        free(in->name);
        free(in);
        return NULL;
    }
    /* a model that reads its resources: resourcePath is a native path already (NULL: none) */
    if (dfo_inst_resources(in->core, resourcePath && *resourcePath ? resourcePath : NULL, DFO_RES_LOAD) ==
        DFO_INST_ERROR) {
        dfo_inst_delete(in->core);
        free(in->name);
        free(in);
        return NULL;
    }
#if DFO_MODEL_EXCHANGE
    in->me = me;
    if (me) dfo_inst_me_start(in->core);
#else
    (void)me;
#endif
    dfo_inst_log(in->core, DFO_INST_OK, DFO_LOG_ALL, "%s", fn);
    return in;
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)visible;
    (void)requiredIntermediateVariables; /* every output may be read during an intermediate update */
    (void)nRequiredIntermediateVariables;
    return instantiate("fmi3InstantiateCoSimulation", 0, instanceName, instantiationToken, resourcePath, loggingOn, eventModeUsed,
                       earlyReturnAllowed, instanceEnvironment, logMessage, intermediateUpdate);
}

static void refuse_instance(fmi3String instanceName, fmi3InstanceEnvironment env, fmi3LogMessageCallback logger,
                            const char *fn)
{
    if (logger) {
        char msg[160];
        strcpy(msg, fn);
        strcat(msg, ": this FMU supports co-simulation only.");
        (void)instanceName;
        logger(env, fmi3Error, "logStatusError", msg);
    }
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)visible;
#if DFO_MODEL_EXCHANGE
    /* event mode is Model Exchange's own; no early return, no intermediate update */
    return instantiate("fmi3InstantiateModelExchange", 1, instanceName, instantiationToken, resourcePath, loggingOn, fmi3True,
                       fmi3False, instanceEnvironment, logMessage, NULL);
#else
    (void)instantiationToken; (void)loggingOn; (void)resourcePath;
    refuse_instance(instanceName, instanceEnvironment, logMessage, "fmi3InstantiateModelExchange");
    return NULL;
#endif
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instantiationToken; (void)resourcePath; (void)visible; (void)loggingOn;
    (void)clockUpdate; (void)lockPreemption; (void)unlockPreemption;
    refuse_instance(instanceName, instanceEnvironment, logMessage, "fmi3InstantiateScheduledExecution");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance)
{
    Instance *in = (Instance *)instance;
    if (!in) return;
    dfo_inst_log(in->core, DFO_INST_OK, DFO_LOG_ALL, "fmi3FreeInstance");
    (void)dfo_inst_resources(in->core, NULL, DFO_RES_FREE);
    dfo_inst_delete(in->core);
    free(in->name);
    free(in);
}

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    BEGIN(fmi3SetDebugLogging);
    if (nCategories > 0 && !categories) return FAIL("fmi3SetDebugLogging: categories is NULL.");
    for (size_t i = 0; i < nCategories; i++)
        if (dfo_inst_log_category(categories[i]) < 0)
            return FAIL("fmi3SetDebugLogging: unknown log category %s.", categories[i] ? categories[i] : "(null)");
    if (nCategories == 0) dfo_inst_set_logging(in->core, -1, loggingOn);
    for (size_t i = 0; i < nCategories; i++)
        dfo_inst_set_logging(in->core, dfo_inst_log_category(categories[i]), loggingOn);
    return fmi3OK;
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    BEGIN(fmi3EnterInitializationMode);
    (void)toleranceDefined;
    (void)tolerance;
    const dfo_inst_status st =
        dfo_inst_setup(in->core, "fmi3EnterInitializationMode", startTime, stopTimeDefined, stopTime);
    if (st != DFO_INST_OK) return status_of(st);
    return status_of(dfo_inst_enter_init(in->core));
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    BEGIN(fmi3ExitInitializationMode);
#if DFO_MODEL_EXCHANGE
    if (in->me) return status_of(dfo_inst_me_exit_init(in->core, "fmi3ExitInitializationMode")); /* to event mode */
#endif
    const dfo_inst_status st = dfo_inst_exit_init(in->core, "fmi3ExitInitializationMode");
    /* with event mode, a co-simulation FMU starts in event mode (nothing pending: the start is
     * consistent) */
    if (st != DFO_INST_ERROR && in->event_mode_used) in->core->run.phase = DFO_PHASE_EVENT;
    return status_of(st);
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    BEGIN(fmi3EnterEventMode);
    if (!in->event_mode_used && !in->me)
        return FAIL("fmi3EnterEventMode: the FMU was instantiated with eventModeUsed = false.");
    in->core->run.phase = DFO_PHASE_EVENT;
    return fmi3OK;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    BEGIN(fmi3EnterStepMode);
    if (in->me) return FAIL("fmi3EnterStepMode: the instance was made for Model Exchange, which has no step mode "
                            "(fmi3EnterContinuousTimeMode leaves event mode).");
    dfo_inst_update_events(in->core); /* an event not updated is handled by entering step mode */
    in->core->run.phase = DFO_PHASE_STEP;
    return fmi3OK;
}

/* The mode switches and the friction force and acceleration jump with it; x and v (the continuous
 * states) are continuous across every switch, and no further iteration is needed. */
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime)
{
    BEGIN(fmi3UpdateDiscreteStates);
#if DFO_MODEL_EXCHANGE
    if (in->me) {
        dfo_me_event_info e;
        const dfo_inst_status st = dfo_inst_me_update(in->core, "fmi3UpdateDiscreteStates", &e);
        if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = e.discrete_states_need_update ? fmi3True : fmi3False;
        if (terminateSimulation) *terminateSimulation = e.terminate ? fmi3True : fmi3False;
        if (nominalsOfContinuousStatesChanged)
            *nominalsOfContinuousStatesChanged = e.nominals_changed ? fmi3True : fmi3False;
        if (valuesOfContinuousStatesChanged) *valuesOfContinuousStatesChanged = e.values_changed ? fmi3True : fmi3False;
        if (nextEventTimeDefined) *nextEventTimeDefined = e.next_time_defined ? fmi3True : fmi3False;
        if (nextEventTime) *nextEventTime = e.next_time;
        return status_of(st);
    }
#endif
    const int was_pending = dfo_inst_update_events(in->core);
    if (was_pending) dfo_inst_log_event_handled(in->core);
    if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = fmi3False;
    if (terminateSimulation) *terminateSimulation = fmi3False;
    if (nominalsOfContinuousStatesChanged) *nominalsOfContinuousStatesChanged = fmi3False;
    if (valuesOfContinuousStatesChanged) *valuesOfContinuousStatesChanged = fmi3False;
    if (nextEventTimeDefined) *nextEventTimeDefined = fmi3False;
    if (nextEventTime) *nextEventTime = 0.0;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    BEGIN(fmi3Terminate);
    dfo_inst_update_events(in->core);
    return status_of(dfo_inst_terminate(in->core));
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    BEGIN(fmi3Reset);
    dfo_inst_reset(in->core);
    (void)dfo_inst_resources(in->core, NULL, DFO_RES_APPLY);
    return fmi3OK;
}

/* ---- variables ------------------------------------------------------------------------------- */

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues)
{
    BEGIN(fmi3GetFloat64);
    if (!check_arrays(in, "fmi3GetFloat64", vr, nvr, values, nValues)) return fmi3Error;
    dfo_inst_status worst = DFO_INST_OK;
    for (size_t i = 0, k = 0; i < nvr; i++) {
        if (vr[i] == DFO_VR_TIME) {
            values[k++] = host_time(in);
            continue;
        }
        const dfo_inst_status st = dfo_inst_get_real(in->core, "fmi3GetFloat64", &vr[i], 1, &values[k]);
        if (st == DFO_INST_ERROR) return fmi3Error;
        if (st > worst) worst = st;
        k += dfo_inst_n_values(in->core, &vr[i], 1);
    }
    return status_of(worst);
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues)
{
    BEGIN(fmi3SetFloat64);
    if (!check_arrays(in, "fmi3SetFloat64", vr, nvr, values, nValues)) return fmi3Error;
    for (size_t i = 0; i < nvr; i++)
        if (vr[i] == DFO_VR_TIME)
            return FAIL("fmi3SetFloat64: variable time (value reference %u) is the independent variable and cannot "
                        "be set.", vr[i]);
    if (in->in_update)
        for (size_t i = 0; i < nvr; i++) {
            const dfo_var_info *var = dfo_find_var(vr[i]);
            if (!var || !dfo_intermediate_input(var))
                return FAIL("fmi3SetFloat64 must not be called from the intermediate-update callback (only getters "
                            "may) for %s (value reference %u): only the inputs declared intermediateUpdate=\"true\" "
                            "may be set there.", var ? var->name : "an unknown variable", vr[i]);
        }
    return status_of(dfo_inst_set_real(in->core, "fmi3SetFloat64", vr, nvr, values));
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Int32 values[],
                        size_t nValues)
{
    BEGIN(fmi3GetInt32);
    if (!check_arrays(in, "fmi3GetInt32", vr, nvr, values, nValues)) return fmi3Error;
    if (!check_int_kind(in, "fmi3GetInt32", vr, nvr, 0)) return fmi3Error;
    return status_of(dfo_inst_get_int(in->core, "fmi3GetInt32", vr, nvr, (int *)values));
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Int32 values[],
                        size_t nValues)
{
    BEGIN(fmi3SetInt32);
    if (!check_arrays(in, "fmi3SetInt32", vr, nvr, values, nValues)) return fmi3Error;
    if (!check_int_kind(in, "fmi3SetInt32", vr, nvr, 0)) return fmi3Error;
    return status_of(dfo_inst_set_int(in->core, "fmi3SetInt32", vr, nvr, (const int *)values));
}

#define CHUNK 64 /* Int64 and Boolean values pass through the core's int in chunks */

/* An int buffer of count values: buf (CHUNK) when it fits, else the host's memory (NULL: none). */
static int *int_buffer(Instance *in, size_t count, int *buf)
{
    if (count <= CHUNK) return buf;
    return (int *)in->core->host.alloc(in->core->host.ctx, count, sizeof(int));
}

static void int_buffer_free(Instance *in, int *p, int *buf)
{
    if (p && p != buf) in->core->host.free(in->core->host.ctx, p);
}

/* Int64 values pass through the core's int: nValues of them (an array of enumerations, such as a
 * model's per-contact friction law, holds several), in one call so that a rejected call changes
 * nothing. */
fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Int64 values[],
                        size_t nValues)
{
    BEGIN(fmi3GetInt64);
    if (!check_arrays(in, "fmi3GetInt64", vr, nvr, values, nValues)) return fmi3Error;
    if (!check_int_kind(in, "fmi3GetInt64", vr, nvr, 1)) return fmi3Error;
    if (nvr == 0) return fmi3OK;
    int stack[CHUNK], *buf = int_buffer(in, nValues, stack);
    if (!buf) return FAIL("fmi3GetInt64: out of memory for %lu values.", (unsigned long)nValues);
    const dfo_inst_status st = dfo_inst_get_int(in->core, "fmi3GetInt64", vr, nvr, buf);
    if (st != DFO_INST_ERROR)
        for (size_t i = 0; i < nValues; i++) values[i] = buf[i];
    int_buffer_free(in, buf, stack);
    return st == DFO_INST_ERROR ? fmi3Error : status_of(st);
}

fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Int64 values[],
                        size_t nValues)
{
    BEGIN(fmi3SetInt64);
    if (!check_arrays(in, "fmi3SetInt64", vr, nvr, values, nValues)) return fmi3Error;
    if (!check_int_kind(in, "fmi3SetInt64", vr, nvr, 1)) return fmi3Error;
    if (nvr == 0) return fmi3OK;
    for (size_t i = 0, k = 0; i < nvr; i++) {
        const size_t c = dfo_inst_n_values(in->core, &vr[i], 1);
        for (size_t e = 0; e < c; e++, k++)
            if (values[k] < INT_MIN || values[k] > INT_MAX) {
                const dfo_var_info *var = dfo_find_var(vr[i]);
                return FAIL("fmi3SetInt64: invalid value %lld for variable %s (value reference %u); valid range: %s.",
                            (long long)values[k], var ? var->name : "?", vr[i], var ? var->range : "?");
            }
    }
    int stack[CHUNK], *buf = int_buffer(in, nValues, stack);
    if (!buf) return FAIL("fmi3SetInt64: out of memory for %lu values.", (unsigned long)nValues);
    for (size_t k = 0; k < nValues; k++) buf[k] = (int)values[k];
    const dfo_inst_status st = dfo_inst_set_int(in->core, "fmi3SetInt64", vr, nvr, buf);
    int_buffer_free(in, buf, stack);
    return status_of(st);
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Boolean values[],
                          size_t nValues)
{
    BEGIN(fmi3GetBoolean);
    if (!check_arrays(in, "fmi3GetBoolean", vr, nvr, values, nValues)) return fmi3Error;
    for (size_t i0 = 0; i0 < nvr; i0 += CHUNK) {
        const size_t n = nvr - i0 < CHUNK ? nvr - i0 : CHUNK;
        int buf[CHUNK];
        if (dfo_inst_get_bool(in->core, "fmi3GetBoolean", vr + i0, n, buf) != DFO_INST_OK) return fmi3Error;
        for (size_t i = 0; i < n; i++) values[i0 + i] = buf[i] ? fmi3True : fmi3False;
    }
    return fmi3OK;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Boolean values[], size_t nValues)
{
    BEGIN(fmi3SetBoolean);
    if (!check_arrays(in, "fmi3SetBoolean", vr, nvr, values, nValues)) return fmi3Error;
    if (nvr > CHUNK) return FAIL("fmi3SetBoolean: at most %d values per call.", CHUNK);
    int buf[CHUNK];
    for (size_t i = 0; i < nvr; i++) buf[i] = values[i] ? 1 : 0;
    return status_of(dfo_inst_set_bool(in->core, "fmi3SetBoolean", vr, nvr, buf));
}

/* ---- co-simulation --------------------------------------------------------------------------- */

/* The core's intermediate update: the host's callback, with the state at the switch readable. */
/* With set_requested (an end of an internal step, where the step reads its inputs) the host may set
 * the inputs declared intermediateUpdate="true"; they hold from t on. */
static int intermediate(void *ctx, double t, int can_return_early, int set_requested)
{
    Instance *in = (Instance *)ctx;
    fmi3Boolean requested = fmi3False;
    fmi3Float64 requested_time = t;
    in->in_update = 1;
    in->set_requested = set_requested ? 1 : 0;
    in->update(in->env, t, set_requested ? fmi3True : fmi3False, fmi3True, fmi3True,
               can_return_early ? fmi3True : fmi3False, &requested, &requested_time);
    in->in_update = 0;
    in->set_requested = 0;
    return requested ? 1 : 0;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastSuccessfulTime)
{
    BEGIN(fmi3DoStep);
    if (in->me) return FAIL("fmi3DoStep: the instance was made for Model Exchange (fmi3InstantiateModelExchange); "
                            "co-simulation needs one made with fmi3InstantiateCoSimulation.");
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!eventHandlingNeeded || !terminateSimulation || !earlyReturn || !lastSuccessfulTime)
        return FAIL("fmi3DoStep: eventHandlingNeeded, terminateSimulation, earlyReturn and lastSuccessfulTime must "
                    "not be NULL.");
    const dfo_event_opts opt = {in->early_return_allowed, in->event_mode_used && in->early_return_allowed,
                                in->update ? intermediate : NULL, in, in->update && DFO_CAN_INTERPOLATE_INPUTS};
    dfo_step_result res = {0.0, 0, 0};
    const dfo_inst_status st = dfo_inst_do_step_events(in->core, "fmi3DoStep", currentCommunicationPoint,
                                                       communicationStepSize, &opt, &res);
    *terminateSimulation = fmi3False;
    *eventHandlingNeeded = (st != DFO_INST_ERROR && res.event) ? fmi3True : fmi3False;
    *earlyReturn = (st != DFO_INST_ERROR && res.early) ? fmi3True : fmi3False;
    *lastSuccessfulTime = dfo_inst_time(in->core);
    return status_of(st);
}

/* ---- FMU state ------------------------------------------------------------------------------- */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    BEGIN(fmi3GetFMUState);
    if (!FMUState) return FAIL("fmi3GetFMUState: FMUState is NULL.");
    return status_of(dfo_inst_get_state(in->core, "fmi3GetFMUState", FMUState));
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    BEGIN(fmi3SetFMUState);
    return status_of(dfo_inst_set_state(in->core, "fmi3SetFMUState", FMUState));
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    BEGIN(fmi3FreeFMUState);
    if (!FMUState) return FAIL("fmi3FreeFMUState: FMUState is NULL.");
    return status_of(dfo_inst_free_state(in->core, "fmi3FreeFMUState", FMUState));
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size)
{
    BEGIN(fmi3SerializedFMUStateSize);
    if (!size) return FAIL("fmi3SerializedFMUStateSize: size is NULL.");
    *size = dfo_inst_state_size(in->core, FMUState);
    if (*size == 0) return FAIL("fmi3SerializedFMUStateSize: FMUState is NULL or not a state of this FMU.");
    return fmi3OK;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size)
{
    BEGIN(fmi3SerializeFMUState);
    if (!FMUState) return FAIL("fmi3SerializeFMUState: FMUState is NULL or not a state of this FMU.");
    if (!serializedState) return FAIL("fmi3SerializeFMUState: serializedState is NULL.");
    return status_of(dfo_inst_serialize(in->core, "fmi3SerializeFMUState", FMUState, serializedState, size));
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState)
{
    BEGIN(fmi3DeserializeFMUState);
    if (!serializedState || !FMUState)
        return FAIL("fmi3DeserializeFMUState: serializedState or FMUState is NULL.");
    return status_of(dfo_inst_deserialize(in->core, "fmi3DeserializeFMUState", serializedState, size, FMUState));
}

/* ---- what this FMU does not have: exported (hosts resolve every symbol), always an error ------- */

static fmi3Status unsupported(fmi3Instance instance, const char *fn, const char *why)
{
    Instance *in = (Instance *)instance;
    if (!allowed(in, fn, PHASES_fmi3Unsupported)) return fmi3Error;
    return FAIL("%s: %s", fn, why);
}

#define NO_TYPE "the FMU has no variables of this type."
#define CS_ONLY "this FMU is for co-simulation only."
#define NO_CLOCKS "the FMU has no clocks."

#define UNSUPPORTED_GETSET(name, ctype)                                                                       \
    fmi3Status fmi3Get##name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, ctype values[], \
                             size_t nValues)                                                                  \
    {                                                                                                         \
        (void)vr; (void)values; (void)nValues;                                                                \
        if (nvr == 0 && instance) return fmi3OK;                                                              \
        return unsupported(instance, "fmi3Get" #name, NO_TYPE);                                               \
    }                                                                                                         \
    fmi3Status fmi3Set##name(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,                \
                             const ctype values[], size_t nValues)                                            \
    {                                                                                                         \
        (void)vr; (void)values; (void)nValues;                                                                \
        if (nvr == 0 && instance) return fmi3OK;                                                              \
        return unsupported(instance, "fmi3Set" #name, NO_TYPE);                                               \
    }

UNSUPPORTED_GETSET(Float32, fmi3Float32)
UNSUPPORTED_GETSET(Int8, fmi3Int8)
UNSUPPORTED_GETSET(UInt8, fmi3UInt8)
UNSUPPORTED_GETSET(Int16, fmi3Int16)
UNSUPPORTED_GETSET(UInt16, fmi3UInt16)
UNSUPPORTED_GETSET(UInt32, fmi3UInt32)
fmi3Status fmi3GetUInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3UInt64 values[],
                         size_t nValues)
{
    if (!dfo_inst_has_structural()) return nvr == 0 && instance ? fmi3OK : unsupported(instance, "fmi3GetUInt64", NO_TYPE);
    BEGIN(fmi3GetUInt64);
    if (!check_arrays(in, "fmi3GetUInt64", vr, nvr, values, nValues)) return fmi3Error;
    if (nvr > CHUNK) return FAIL("fmi3GetUInt64: at most %d values per call.", CHUNK);
    unsigned long long buf[CHUNK];
    const dfo_inst_status st = dfo_inst_get_uint64(in->core, "fmi3GetUInt64", vr, nvr, buf);
    if (st == DFO_INST_ERROR) return fmi3Error;
    for (size_t i = 0; i < nvr; i++) values[i] = (fmi3UInt64)buf[i];
    return status_of(st);
}

fmi3Status fmi3SetUInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3UInt64 values[], size_t nValues)
{
    if (!dfo_inst_has_structural()) return nvr == 0 && instance ? fmi3OK : unsupported(instance, "fmi3SetUInt64", NO_TYPE);
    BEGIN(fmi3SetUInt64);
    if (!check_arrays(in, "fmi3SetUInt64", vr, nvr, values, nValues)) return fmi3Error;
    if (nvr > CHUNK) return FAIL("fmi3SetUInt64: at most %d values per call.", CHUNK);
    unsigned long long buf[CHUNK];
    for (size_t i = 0; i < nvr; i++) buf[i] = (unsigned long long)values[i];
    return status_of(dfo_inst_set_uint64(in->core, "fmi3SetUInt64", vr, nvr, buf));
}
UNSUPPORTED_GETSET(String, fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, size_t valueSizes[],
                         fmi3Binary values[], size_t nValues)
{
    (void)vr; (void)nvr; (void)valueSizes; (void)values; (void)nValues;
    return unsupported(instance, "fmi3GetBinary", NO_TYPE);
}
fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues)
{
    (void)vr; (void)nvr; (void)valueSizes; (void)values; (void)nValues;
    return unsupported(instance, "fmi3SetBinary", NO_TYPE);
}
fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Clock values[])
{
    (void)vr; (void)nvr; (void)values;
    return unsupported(instance, "fmi3GetClock", NO_CLOCKS);
}
fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Clock values[])
{
    (void)vr; (void)nvr; (void)values;
    return unsupported(instance, "fmi3SetClock", NO_CLOCKS);
}
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t *nDependencies)
{
    (void)valueReference; (void)nDependencies;
    return unsupported(instance, "fmi3GetNumberOfVariableDependencies",
                       "dependencies are declared in the model description only.");
}
fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies)
{
    (void)dependent; (void)elementIndicesOfDependent; (void)independents; (void)elementIndicesOfIndependents;
    (void)dependencyKinds; (void)nDependencies;
    return unsupported(instance, "fmi3GetVariableDependencies",
                       "dependencies are declared in the model description only.");
}
/* Directional (adjoint: transposed) derivatives: seed over the knowns (unknowns), sensitivity over
 * the unknowns (knowns), each as many values as its variables hold. */
static int check_derivative_sizes(Instance *in, const char *fn, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                  const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                  size_t nSeed, const fmi3Float64 sensitivity[], size_t nSensitivity, int adjoint)
{
    if ((nUnknowns > 0 && !unknowns) || (nKnowns > 0 && !knowns) || (nSeed > 0 && !seed) ||
        (nSensitivity > 0 && !sensitivity)) {
        dfo_inst_fail(in->core, "%s: the unknowns, knowns, seed or sensitivity array is NULL.", fn);
        return 0;
    }
    const size_t nu = nUnknowns > 0 ? dfo_inst_n_values(in->core, unknowns, nUnknowns) : 0;
    const size_t nk = nKnowns > 0 ? dfo_inst_n_values(in->core, knowns, nKnowns) : 0;
    const size_t want_seed = adjoint ? nu : nk, want_sens = adjoint ? nk : nu;
    if (nSeed != want_seed || nSensitivity != want_sens) {
        dfo_inst_fail(in->core, "%s: nSeed = %lu and nSensitivity = %lu, but the %s hold %lu values and the %s "
                      "%lu.", fn, (unsigned long)nSeed, (unsigned long)nSensitivity, adjoint ? "unknowns" : "knowns",
                      (unsigned long)want_seed, adjoint ? "knowns" : "unknowns", (unsigned long)want_sens);
        return 0;
    }
    return 1;
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity)
{
    BEGIN(fmi3GetDirectionalDerivative);
    if (!check_derivative_sizes(in, "fmi3GetDirectionalDerivative", unknowns, nUnknowns, knowns, nKnowns, seed, nSeed,
                                sensitivity, nSensitivity, 0))
        return fmi3Error;
    return status_of(dfo_inst_directional(in->core, "fmi3GetDirectionalDerivative", unknowns, nUnknowns, knowns,
                                          nKnowns, seed, sensitivity));
}
fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                    size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity)
{
    BEGIN(fmi3GetAdjointDerivative);
    if (!check_derivative_sizes(in, "fmi3GetAdjointDerivative", unknowns, nUnknowns, knowns, nKnowns, seed, nSeed,
                                sensitivity, nSensitivity, 1))
        return fmi3Error;
    return status_of(dfo_inst_adjoint(in->core, "fmi3GetAdjointDerivative", unknowns, nUnknowns, knowns, nKnowns,
                                      seed, sensitivity));
}
#define NO_STRUCTURAL "the FMU has no structural parameters."
fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    if (!dfo_inst_has_structural()) return unsupported(instance, "fmi3EnterConfigurationMode", NO_STRUCTURAL);
    BEGIN(fmi3EnterConfigurationMode);
    return status_of(dfo_inst_enter_config(in->core, "fmi3EnterConfigurationMode"));
}
fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    if (!dfo_inst_has_structural()) return unsupported(instance, "fmi3ExitConfigurationMode", NO_STRUCTURAL);
    BEGIN(fmi3ExitConfigurationMode);
    return status_of(dfo_inst_exit_config(in->core, "fmi3ExitConfigurationMode"));
}
fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[])
{
    (void)vr; (void)nvr; (void)intervals; (void)qualifiers;
    return unsupported(instance, "fmi3GetIntervalDecimal", NO_CLOCKS);
}
fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                   fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[])
{
    (void)vr; (void)nvr; (void)counters; (void)resolutions; (void)qualifiers;
    return unsupported(instance, "fmi3GetIntervalFraction", NO_CLOCKS);
}
fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 shifts[])
{
    (void)vr; (void)nvr; (void)shifts;
    return unsupported(instance, "fmi3GetShiftDecimal", NO_CLOCKS);
}
fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                fmi3UInt64 counters[], fmi3UInt64 resolutions[])
{
    (void)vr; (void)nvr; (void)counters; (void)resolutions;
    return unsupported(instance, "fmi3GetShiftFraction", NO_CLOCKS);
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                  const fmi3Float64 intervals[])
{
    (void)vr; (void)nvr; (void)intervals;
    return unsupported(instance, "fmi3SetIntervalDecimal", NO_CLOCKS);
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                   const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    (void)vr; (void)nvr; (void)counters; (void)resolutions;
    return unsupported(instance, "fmi3SetIntervalFraction", NO_CLOCKS);
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                               const fmi3Float64 shifts[])
{
    (void)vr; (void)nvr; (void)shifts;
    return unsupported(instance, "fmi3SetShiftDecimal", NO_CLOCKS);
}
fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    (void)vr; (void)nvr; (void)counters; (void)resolutions;
    return unsupported(instance, "fmi3SetShiftFraction", NO_CLOCKS);
}
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    return unsupported(instance, "fmi3EvaluateDiscreteStates",
                       DFO_MODEL_EXCHANGE ? "the FMU has no clocks, so no discrete states to evaluate outside event mode."
                                          : CS_ONLY);
}
fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                                    const fmi3Int32 orders[], fmi3Float64 values[], size_t nValues)
{
    BEGIN(fmi3GetOutputDerivatives);
    if (nvr > 0 && !orders) return FAIL("fmi3GetOutputDerivatives: the orders array is NULL.");
    if (!check_arrays(in, "fmi3GetOutputDerivatives", vr, nvr, values, nValues)) return fmi3Error;
    return status_of(dfo_inst_get_output_derivatives(in->core, "fmi3GetOutputDerivatives", vr, nvr,
                                                     (const int *)orders, values));
}
fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference; (void)activationTime;
    return unsupported(instance, "fmi3ActivateModelPartition", "this FMU is not for scheduled execution.");
}
