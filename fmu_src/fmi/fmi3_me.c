/* FMI 3.0 Model Exchange glue, the same for every model: for a model that declares <ModelExchange>
 * (model_vars.h: DFO_MODEL_EXCHANGE) the fmi3 signatures of Model Exchange, their argument checks,
 * the status mapping and their part of the state table (the rest, with fmi3InstantiateModelExchange,
 * fmi3EnterEventMode and fmi3UpdateDiscreteStates, which co-simulation shares: fmi3_cs.c),
 * everything else being the model's instance core behind core/instance_me.h (phases: event mode is
 * DFO_PHASE_EVENT, continuous-time mode DFO_PHASE_STEP); for any other model the same functions as
 * errors. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "fmi3_glue.h"
#if DFO_MODEL_EXCHANGE
#include "instance_me.h"

#define PHASES_fmi3EnterContinuousTimeMode P_EVENT
#define PHASES_fmi3CompletedIntegratorStep P_STEP
#define PHASES_fmi3SetTime (P_EVENT | P_STEP)
#define PHASES_fmi3SetContinuousStates (P_EVENT | P_STEP)
#define PHASES_fmi3GetContinuousStateDerivatives (P_INIT | P_EVENT | P_STEP | P_TERM | P_ERR)
#define PHASES_fmi3GetEventIndicators (P_INIT | P_EVENT | P_STEP | P_TERM | P_ERR)
#define PHASES_fmi3GetContinuousStates (P_INIT | P_EVENT | P_STEP | P_TERM | P_ERR)
#define PHASES_fmi3GetNominalsOfContinuousStates P_ANY
#define PHASES_fmi3GetNumberOfEventIndicators P_ANY
#define PHASES_fmi3GetNumberOfContinuousStates P_ANY

/* The function is one of Model Exchange and the instance was made for it (a co-simulation
 * instance is told so in any phase), in one of the function's phases. */
#define BEGIN_ME(fn)                                                                                    \
    Instance *in = (Instance *)instance;                                                                \
    if (in && !in->me && allowed(in, #fn, P_ANY))                                                       \
        return FAIL("%s: the instance was made for co-simulation (fmi3InstantiateCoSimulation); Model " \
                    "Exchange needs one made with fmi3InstantiateModelExchange.", #fn);                 \
    if (!allowed(in, #fn, PHASES_##fn)) return fmi3Error

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    BEGIN_ME(fmi3EnterContinuousTimeMode);
    in->core->run.phase = DFO_PHASE_STEP;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation)
{
    BEGIN_ME(fmi3CompletedIntegratorStep);
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!enterEventMode || !terminateSimulation)
        return FAIL("fmi3CompletedIntegratorStep: enterEventMode or terminateSimulation is NULL.");
    int enter = 0, stop = 0;
    const dfo_inst_status st = dfo_inst_me_completed_step(in->core, "fmi3CompletedIntegratorStep", &enter, &stop);
    *enterEventMode = enter ? fmi3True : fmi3False;
    *terminateSimulation = stop ? fmi3True : fmi3False;
    return status_of(st);
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    BEGIN_ME(fmi3SetTime);
    return status_of(dfo_inst_me_set_time(in->core, "fmi3SetTime", time));
}

/* A Model Exchange function with one array of n values: the array non-NULL, then the core. */
#define ME_ARRAY(fn, core_fn, value_t, arg)                                     \
    fmi3Status fn(fmi3Instance instance, value_t arg[], size_t n)               \
    {                                                                           \
        BEGIN_ME(fn);                                                           \
        if (n > 0 && !arg) return FAIL("%s: %s is NULL.", #fn, #arg);           \
        return status_of(core_fn(in->core, #fn, arg, n));                       \
    }

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n)
{
    BEGIN_ME(fmi3GetNumberOfEventIndicators);
    if (!n) return FAIL("fmi3GetNumberOfEventIndicators: nEventIndicators is NULL.");
    *n = dfo_inst_me_n_indicators(in->core);
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n)
{
    BEGIN_ME(fmi3GetNumberOfContinuousStates);
    if (!n) return FAIL("fmi3GetNumberOfContinuousStates: nContinuousStates is NULL.");
    *n = dfo_inst_me_n_states(in->core);
    return fmi3OK;
}

#else

/* ---- a model without Model Exchange: the functions exported (hosts resolve every symbol), always an
 * error ------------------------------------------------------------------------------------------- */

static fmi3Status not_me(fmi3Instance instance, const char *fn)
{
    Instance *in = (Instance *)instance;
    if (!allowed(in, fn, P_ANY)) return fmi3Error;
    return FAIL("%s: this FMU is for co-simulation only.", fn);
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    return not_me(instance, "fmi3EnterContinuousTimeMode");
}
fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation;
    return not_me(instance, "fmi3CompletedIntegratorStep");
}
fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    (void)time;
    return not_me(instance, "fmi3SetTime");
}
fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n)
{
    (void)n;
    return not_me(instance, "fmi3GetNumberOfEventIndicators");
}
fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n)
{
    (void)n;
    return not_me(instance, "fmi3GetNumberOfContinuousStates");
}

/* A Model Exchange function with one array of n values. */
#define ME_ARRAY(fn, core_fn, value_t, arg)                                     \
    fmi3Status fn(fmi3Instance instance, value_t arg[], size_t n)               \
    {                                                                           \
        (void)arg;                                                              \
        (void)n;                                                                \
        return not_me(instance, #fn);                                           \
    }

#endif

ME_ARRAY(fmi3SetContinuousStates, dfo_inst_me_set_states, const fmi3Float64, x)
ME_ARRAY(fmi3GetContinuousStateDerivatives, dfo_inst_me_derivatives, fmi3Float64, derivatives)
ME_ARRAY(fmi3GetEventIndicators, dfo_inst_me_indicators, fmi3Float64, eventIndicators)
ME_ARRAY(fmi3GetContinuousStates, dfo_inst_me_get_states, fmi3Float64, x)
ME_ARRAY(fmi3GetNominalsOfContinuousStates, dfo_inst_me_nominals, fmi3Float64, nominals)
