/* FMI 2.0 Model Exchange glue, the same for every model: for a model that declares <ModelExchange>
 * (model_vars.h: DFO_MODEL_EXCHANGE) the fmi2 signatures of Model Exchange, their argument checks,
 * the status mapping and their part of the state table (the rest: fmi2_cs.c), everything else being
 * the model's instance core behind core/instance_me.h (phases: event mode is DFO_PHASE_EVENT,
 * continuous-time mode DFO_PHASE_STEP); for any other model the same functions as errors. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "fmi2_glue.h"
#if DFO_MODEL_EXCHANGE
#include "instance_me.h"

#define PHASES_fmi2EnterEventMode P_STEP
#define PHASES_fmi2NewDiscreteStates P_EVENT
#define PHASES_fmi2EnterContinuousTimeMode P_EVENT
#define PHASES_fmi2CompletedIntegratorStep P_STEP
#define PHASES_fmi2SetTime (P_EVENT | P_STEP)
#define PHASES_fmi2SetContinuousStates (P_EVENT | P_STEP)
#define PHASES_fmi2GetDerivatives (P_INIT | P_EVENT | P_STEP | P_TERM | P_ERR)
#define PHASES_fmi2GetEventIndicators (P_INIT | P_EVENT | P_STEP | P_TERM | P_ERR)
#define PHASES_fmi2GetContinuousStates (P_INIT | P_EVENT | P_STEP | P_TERM | P_ERR)
#define PHASES_fmi2GetNominalsOfContinuousStates P_ANY

/* The function is one of Model Exchange and the instance was made for it (a co-simulation
 * instance is told so in any phase), in one of the function's phases. */
#define BEGIN_ME(fn)                                                                                 \
    Instance *in = (Instance *)c;                                                                    \
    if (in && !in->me && allowed(in, #fn, P_ANY))                                                    \
        return FAIL("%s: the instance was made for co-simulation (fmuType fmi2CoSimulation); Model " \
                    "Exchange needs one made with fmuType fmi2ModelExchange.", #fn);                 \
    if (!allowed(in, #fn, PHASES_##fn)) return fmi2Error

fmi2Status fmi2EnterEventMode(fmi2Component c)
{
    BEGIN_ME(fmi2EnterEventMode);
    in->core->run.phase = DFO_PHASE_EVENT;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info)
{
    BEGIN_ME(fmi2NewDiscreteStates);
    if (!info) return FAIL("fmi2NewDiscreteStates: fmi2EventInfo is NULL.");
    dfo_me_event_info e;
    const dfo_inst_status st = dfo_inst_me_update(in->core, "fmi2NewDiscreteStates", &e);
    info->newDiscreteStatesNeeded = e.discrete_states_need_update ? fmi2True : fmi2False;
    info->terminateSimulation = e.terminate ? fmi2True : fmi2False;
    info->nominalsOfContinuousStatesChanged = e.nominals_changed ? fmi2True : fmi2False;
    info->valuesOfContinuousStatesChanged = e.values_changed ? fmi2True : fmi2False;
    info->nextEventTimeDefined = e.next_time_defined ? fmi2True : fmi2False;
    info->nextEventTime = e.next_time;
    return status_of(st);
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    BEGIN_ME(fmi2EnterContinuousTimeMode);
    in->core->run.phase = DFO_PHASE_STEP;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation)
{
    BEGIN_ME(fmi2CompletedIntegratorStep);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!enterEventMode || !terminateSimulation)
        return FAIL("fmi2CompletedIntegratorStep: enterEventMode or terminateSimulation is NULL.");
    int enter = 0, stop = 0;
    const dfo_inst_status st = dfo_inst_me_completed_step(in->core, "fmi2CompletedIntegratorStep", &enter, &stop);
    *enterEventMode = enter ? fmi2True : fmi2False;
    *terminateSimulation = stop ? fmi2True : fmi2False;
    return status_of(st);
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    BEGIN_ME(fmi2SetTime);
    return status_of(dfo_inst_me_set_time(in->core, "fmi2SetTime", time));
}

/* A Model Exchange function with one array of n values: the array non-NULL, then the core. */
#define ME_ARRAY(fn, core_fn, value_t, arg)                                     \
    fmi2Status fn(fmi2Component c, value_t arg[], size_t n)                     \
    {                                                                           \
        BEGIN_ME(fn);                                                           \
        if (n > 0 && !arg) return FAIL("%s: %s is NULL.", #fn, #arg);           \
        return status_of(core_fn(in->core, #fn, arg, n));                       \
    }

#else

/* ---- a model without Model Exchange: the functions exported (hosts resolve every symbol), always an
 * error ------------------------------------------------------------------------------------------- */

#define PHASES_fmi2ModelExchange P_ANY

static fmi2Status not_me(fmi2Component c, const char *fn)
{
    Instance *in = (Instance *)c;
    if (!allowed(in, fn, PHASES_fmi2ModelExchange)) return fmi2Error;
    return FAIL("%s: this FMU is for co-simulation only.", fn);
}

fmi2Status fmi2EnterEventMode(fmi2Component c) { return not_me(c, "fmi2EnterEventMode"); }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info)
{
    (void)info;
    return not_me(c, "fmi2NewDiscreteStates");
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { return not_me(c, "fmi2EnterContinuousTimeMode"); }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation;
    return not_me(c, "fmi2CompletedIntegratorStep");
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    (void)time;
    return not_me(c, "fmi2SetTime");
}

/* A Model Exchange function with one array of n values. */
#define ME_ARRAY(fn, core_fn, value_t, arg)                                     \
    fmi2Status fn(fmi2Component c, value_t arg[], size_t n)                     \
    {                                                                           \
        (void)arg;                                                              \
        (void)n;                                                                \
        return not_me(c, #fn);                                                  \
    }

#endif

ME_ARRAY(fmi2SetContinuousStates, dfo_inst_me_set_states, const fmi2Real, x)
ME_ARRAY(fmi2GetDerivatives, dfo_inst_me_derivatives, fmi2Real, derivatives)
ME_ARRAY(fmi2GetEventIndicators, dfo_inst_me_indicators, fmi2Real, eventIndicators)
ME_ARRAY(fmi2GetContinuousStates, dfo_inst_me_get_states, fmi2Real, x)
ME_ARRAY(fmi2GetNominalsOfContinuousStates, dfo_inst_me_nominals, fmi2Real, x_nominal)
