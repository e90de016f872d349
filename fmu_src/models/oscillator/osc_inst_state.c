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

/* An FMU state in memory: a tagged copy of the run and the values. */
typedef struct {
    uint64_t magic;
    dfo_run run;
    osc_values v;
} saved_state;

/* ---- FMU states ------------------------------------------------------------------------------ */

static saved_state *as_state(const void *p)
{
    saved_state *st = (saved_state *)p;
    return (st && st->magic == STATE_MAGIC) ? st : NULL;
}

static dfo_inst_status store_state(osc_instance *in, const char *fn, void **state, const dfo_run *run,
                                   const osc_values *v)
{
    int fresh;
    if (dfo_state_take(&in->lc, fn, state, STATE_MAGIC, sizeof(saved_state), &fresh) != DFO_INST_OK)
        return DFO_INST_ERROR;
    saved_state *st = (saved_state *)*state;
    st->run = *run;
    st->v = *v;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_get_state(dfo_lifecycle *lc, const char *fn, void **state)
{
    osc_instance *in = osc(lc);
    return store_state(in, fn, state, &in->lc.run, &in->v);
}

dfo_inst_status dfo_inst_set_state(dfo_lifecycle *lc, const char *fn, const void *state)
{
    osc_instance *in = osc(lc);
    const saved_state *st = (const saved_state *)dfo_state_block(lc, fn, state, STATE_MAGIC);
    if (!st) return DFO_INST_ERROR;
    in->lc.run = st->run;
    in->v = st->v;
    osc_inst_sens_reset(&in->v.s); /* the sensitivity is of the state restored */
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_free_state(dfo_lifecycle *lc, const char *fn, void **state)
{
    if (!dfo_state_droppable(lc, fn, state, STATE_MAGIC)) return DFO_INST_ERROR;
    dfo_state_drop(lc, state);
    return DFO_INST_OK;
}

/* The serialised body (core/fmu_state.h's format): the values' bytes, then the run. */
#define BODY_BYTES (sizeof(osc_values) + DFO_STATE_RUN_BYTES)

size_t dfo_inst_state_size(const dfo_lifecycle *lc, const void *state)
{
    (void)lc;
    return as_state(state) ? DFO_STATE_HEADER_BYTES + BODY_BYTES : 0;
}

dfo_inst_status dfo_inst_serialize(dfo_lifecycle *lc, const char *fn, const void *state, unsigned char *buf,
                                   size_t size)
{
    const saved_state *st = (const saved_state *)dfo_state_block(lc, fn, state, STATE_MAGIC);
    if (!st) return DFO_INST_ERROR;
    if (size < DFO_STATE_HEADER_BYTES + BODY_BYTES)
        return dfo_inst_fail(lc, "%s: buffer of %lu bytes is too small (%lu needed).", fn, (unsigned long)size,
                             (unsigned long)(DFO_STATE_HEADER_BYTES + BODY_BYTES));
    dfo_cursor c = {buf + DFO_STATE_HEADER_BYTES, NULL};
    dfo_put_bytes(&c, &st->v, sizeof st->v);
    dfo_put_run(&c, &st->run);
    dfo_state_seal(buf, BODY_BYTES, MODEL_GUID);
    return DFO_INST_OK;
}

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
    size_t body = 0;
    if (dfo_state_open(lc, fn, buf, size, MODEL_GUID, &body) != DFO_INST_OK) return DFO_INST_ERROR;
    if (body != BODY_BYTES)
        return dfo_inst_fail(lc, "%s: %lu bytes given, a state of this FMU has %lu.", fn, (unsigned long)size,
                             (unsigned long)(DFO_STATE_HEADER_BYTES + BODY_BYTES));
    osc_values v;
    dfo_run run;
    dfo_cursor c = {NULL, buf + DFO_STATE_HEADER_BYTES};
    dfo_get_bytes(&c, &v, sizeof v);
    dfo_get_run(&c, &run);
    const char *why = implausible(&run, &v);
    if (why) return dfo_inst_fail(lc, "%s: rejected, %s.", fn, why);
    dfo_model_init(&v.M, &v.p);   /* derived constants follow from the parameters, never trusted */
    dfo_check_caches(&v.M, &v.s); /* and caches that do not follow from the state are dropped */
    return store_state(osc(lc), fn, state, &run, &v);
}
