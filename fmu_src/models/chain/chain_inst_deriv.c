/* The chain's instance core, coupling at second order (core/instance.h): input derivatives, output
 * derivatives, directional and adjoint derivatives. No FMI types. */
#include "dfo_fp.h"

#include "chain_instance.h"

int dfo_inst_max_input_order(void) { return 0; }
int dfo_inst_max_output_order(void) { return 0; }

dfo_inst_status dfo_inst_set_input_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t nvr,
                                               const int order[], const double value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return dfo_inst_fail(lc, "%s: input derivatives are not supported (canInterpolateInputs=false).", fn);
}

dfo_inst_status dfo_inst_get_output_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[],
                                                size_t nvr, const int order[], double value[])
{
    (void)vr; (void)nvr; (void)order; (void)value;
    return dfo_inst_fail(lc, "%s: output derivatives are not supported (maxOutputDerivativeOrder=0).", fn);
}

dfo_inst_status dfo_inst_directional(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                     const unsigned int known[], size_t nk, const double seed[], double sensitivity[])
{
    (void)unknown; (void)nu; (void)known; (void)nk; (void)seed; (void)sensitivity;
    return dfo_inst_fail(lc, "%s: directional derivatives are not provided.", fn);
}

dfo_inst_status dfo_inst_adjoint(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                 const unsigned int known[], size_t nk, const double seed[], double sensitivity[])
{
    (void)unknown; (void)nu; (void)known; (void)nk; (void)seed; (void)sensitivity;
    return dfo_inst_fail(lc, "%s: adjoint derivatives are not provided.", fn);
}
