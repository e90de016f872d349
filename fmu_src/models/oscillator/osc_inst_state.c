/* The DryFrictionOscillator instance core (osc_instance.h), its FMU states: copies in memory and
 * their serialisation in the one format of core/fmu_state.h (the values' bytes, checked for
 * plausibility when read back). No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "osc_instance.h"
#include "fmu_state.h"
#include "instance_common.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

#define STATE_MAGIC 0x444650534d555354ULL /* "DFPSMUST" */

/* ---- FMU states: the run and a copy of the values (core/fmu_state.h) ---------------------- */

static dfo_inst_status store_state(osc_instance *in, const char *fn, void **state, const dfo_run *run,
                                   const osc_values *v)
{
    return dfo_values_state_store(&in->lc, fn, state, STATE_MAGIC, run, v, sizeof *v);
}

dfo_inst_status dfo_inst_get_state(dfo_lifecycle *lc, const char *fn, void **state)
{
    osc_instance *in = osc(lc);
    return store_state(in, fn, state, &in->lc.run, &in->v);
}

dfo_inst_status dfo_inst_set_state(dfo_lifecycle *lc, const char *fn, const void *state)
{
    osc_instance *in = osc(lc);
    dfo_run run;
    const osc_values *v = (const osc_values *)dfo_values_state_get(lc, fn, state, STATE_MAGIC, &run);
    if (!v) return DFO_INST_ERROR;
    in->lc.run = run;
    in->v = *v;
    osc_inst_sens_reset(&in->v.s); /* the sensitivity is of the state restored */
    return DFO_INST_OK;
}

DFO_VALUES_STATE_ENTRY_POINTS(osc_values, STATE_MAGIC, MODEL_GUID)

static int finite_inputs(const dfo_inputs *u)
{
    return isfinite(u->F_ext) && isfinite(u->N_ext) && isfinite(u->v_belt) && isfinite(u->F_ext_d[0]) && isfinite(u->F_ext_d[1]) &&
           isfinite(u->N_ext_d[0]) && isfinite(u->N_ext_d[1]) && isfinite(u->t_d);
}

/* A deserialised state must describe a simulation this FMU could have reached. */
static const char *implausible(const dfo_run *r, const osc_values *v)
{
    for (int i = 0; i < DFO_NUM_VARS; i++) {
        const dfo_var_info *var = &DFO_VARS[i];
        if (var->home == DFO_COMPUTED || var->type == DFO_BOOLEAN) continue;
        const double x = var->type == DFO_REAL ? *(const double *)osc_cslot(v, var) : *(const int *)osc_cslot(v, var);
        if (dfo_inst_invalid(var, x))
            return var->type == DFO_REAL ? "a parameter is out of range" : "an integer parameter is out of range";
    }
    const char *why = dfo_run_implausible(r, 0);
    if (why) return why;
    if (dfo_check_params(&v->p)) return dfo_check_params(&v->p);
    if (!finite_inputs(&v->u) || !finite_inputs(&v->u_used)) return "an input is not finite";
    if ((v->u.ramp != 0 && v->u.ramp != 1) || (v->u_used.ramp != 0 && v->u_used.ramp != 1))
        return "the input derivatives are invalid";
    if (isnan(v->t_switch)) return "the time of the last switch is not a number";
    if (v->effects < 0 || (v->effects & ~DFO_MD_EFFECTS_ALL)) return "the effects are invalid";
    const dfo_state *s = &v->s;
    if (!isfinite(s->t) || !isfinite(s->t0) || !isfinite(s->X) || !isfinite(s->V) || !isfinite(s->A) ||
        !isfinite(s->F) || !isfinite(s->hA) || s->n < 0 || isnan(s->t_switch))
        return "the state is not finite";
    if (!isnan(s->stuck_from) && !(s->stuck_from >= s->t0 && s->stuck_from <= s->t))
        return "the stuck stretch does not lie in the run";
    if (s->mode < -1 || s->mode > 1) return "the mode is invalid";
    return dfo_grid_implausible(r, s->t0, (long long)s->n, dfo_step_size(&v->p), s->t);
}

dfo_inst_status dfo_inst_deserialize(dfo_lifecycle *lc, const char *fn, const unsigned char *buf, size_t size,
                                     void **state)
{
    osc_values v;
    dfo_run run;
    if (dfo_values_state_read(lc, fn, buf, size, MODEL_GUID, sizeof v, &v, &run) != DFO_INST_OK)
        return DFO_INST_ERROR;
    const char *why = implausible(&run, &v);
    if (why) return dfo_inst_fail(lc, "%s: rejected, %s.", fn, why);
    dfo_model_init(&v.M, &v.p);   /* derived constants follow from the parameters, never trusted */
    dfo_check_caches(&v.M, &v.s); /* and caches that do not follow from the state are dropped */
    return store_state(osc(lc), fn, state, &run, &v);
}
