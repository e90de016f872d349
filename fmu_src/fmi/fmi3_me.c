/* FMI 3.0 Model Exchange glue, the same for every model that declares <ModelExchange>: the fmi3
 * signatures of Model Exchange, their argument checks, the status mapping and their part of the
 * state table (the rest, with fmi3InstantiateModelExchange, fmi3EnterEventMode and
 * fmi3UpdateDiscreteStates, which co-simulation shares: fmi3_cs.c). Everything else is the model's
 * instance core behind core/instance_me.h. Phases: event mode is DFO_PHASE_EVENT, continuous-time
 * mode DFO_PHASE_STEP. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "fmi3_glue.h"
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
#define BEGIN_ME(fn)                                                                                        \
    Instance *in = (Instance *)instance;                                                                    \
    if (in && !in->me && allowed(in, #fn, P_ANY))                                                           \
        return FAIL("%s: the instance was made for co-simulation (fmi3InstantiateCoSimulation); Model "     \
                    "Exchange needs one made with fmi3InstantiateModelExchange.", #fn);                     \
    if (!allowed(in, #fn, PHASES_##fn)) return fmi3Error

/* An array argument of n values is not NULL. */
#define NEED(p, n, fn) \
    if ((n) > 0 && !(p)) return FAIL("%s: %s is NULL.", fn, #p)

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    BEGIN_ME(fmi3EnterContinuousTimeMode);
    return status_of(dfo_inst_me_enter_continuous(in->core));
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

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t nx)
{
    BEGIN_ME(fmi3SetContinuousStates);
    NEED(x, nx, "fmi3SetContinuousStates");
    return status_of(dfo_inst_me_set_states(in->core, "fmi3SetContinuousStates", x, nx));
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[], size_t nx)
{
    BEGIN_ME(fmi3GetContinuousStateDerivatives);
    NEED(derivatives, nx, "fmi3GetContinuousStateDerivatives");
    return status_of(dfo_inst_me_derivatives(in->core, "fmi3GetContinuousStateDerivatives", derivatives, nx));
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t ni)
{
    BEGIN_ME(fmi3GetEventIndicators);
    NEED(eventIndicators, ni, "fmi3GetEventIndicators");
    return status_of(dfo_inst_me_indicators(in->core, "fmi3GetEventIndicators", eventIndicators, ni));
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t nx)
{
    BEGIN_ME(fmi3GetContinuousStates);
    NEED(x, nx, "fmi3GetContinuousStates");
    return status_of(dfo_inst_me_get_states(in->core, "fmi3GetContinuousStates", x, nx));
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t nx)
{
    BEGIN_ME(fmi3GetNominalsOfContinuousStates);
    NEED(nominals, nx, "fmi3GetNominalsOfContinuousStates");
    return status_of(dfo_inst_me_nominals(in->core, "fmi3GetNominalsOfContinuousStates", nominals, nx));
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n)
{
    BEGIN_ME(fmi3GetNumberOfEventIndicators);
    if (!n) return FAIL("fmi3GetNumberOfEventIndicators: nEventIndicators is NULL.");
    *n = dfo_inst_me_n_indicators();
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n)
{
    BEGIN_ME(fmi3GetNumberOfContinuousStates);
    if (!n) return FAIL("fmi3GetNumberOfContinuousStates: nContinuousStates is NULL.");
    *n = dfo_inst_me_n_states();
    return fmi3OK;
}
