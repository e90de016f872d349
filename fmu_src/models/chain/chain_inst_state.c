/* The DryFrictionChain instance core (chain_instance.h), its FMU states: copies in memory (the
 * model rebuilt on restore) and their serialisation in the one format of core/fmu_state.h. No FMI
 * types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain_instance.h"
#include "fmu_state.h"

#include <math.h>
#include <stdint.h>
#include <string.h>

/* ---- FMU states: a tagged copy of the run and the values (arrays included, the model excepted:
 * it follows from the parameters and is rebuilt on restore) ---- */

#define STATE_MAGIC 0x444643484d555354ULL /* FMU state tag */

typedef struct {
    uint64_t magic;
    dfo_run run;
    chain_values v;
} saved_state;

static saved_state *as_state(const void *p)
{
    saved_state *st = (saved_state *)p;
    return (st && st->magic == STATE_MAGIC) ? st : NULL;
}

/* dst := src's values (dst's arrays already of src's n). */
static void copy_values(chain_values *dst, const chain_values *src)
{
    chain_values keep = *dst;
    *dst = *src;
    dst->pa = keep.pa;
    dst->ua = keep.ua;
    dst->ua_used = keep.ua_used;
    dst->scratch = keep.scratch;
    dst->ud = keep.ud;
    dst->s = keep.s;
    dst->s0 = keep.s0;
    dst->M = keep.M;
    dst->me = keep.me;
    const size_t n = src->n;
    memcpy(dst->pa, src->pa, (size_t)DFO_NUM_AP * n * sizeof(double));
    memcpy(dst->ua, src->ua, (size_t)DFO_NUM_AI * n * sizeof(double));
    memcpy(dst->ua_used, src->ua_used, (size_t)DFO_NUM_AI * n * sizeof(double));
    memcpy(dst->ud, src->ud, 2 * (size_t)DFO_NUM_AI * n * sizeof(double));
    chain_state_copy(&dst->s, &src->s);
}

/* Release a saved state and its arrays; *state NULL. */
static void free_saved(chain_instance *in, void **state)
{
    chain_inst_free_arrays(in, &((saved_state *)*state)->v);
    dfo_state_drop(&in->lc, state);
}

/* *state := a copy of the run and v (a state of another n is replaced). */
static dfo_inst_status store_state(chain_instance *in, const char *fn, void **state, const dfo_run *run,
                                   const chain_values *v)
{
    const saved_state *old = as_state(*state);
    if (old && old->v.n != v->n) free_saved(in, state);
    int fresh;
    if (dfo_state_take(&in->lc, fn, state, STATE_MAGIC, sizeof(saved_state), &fresh) != DFO_INST_OK)
        return DFO_INST_ERROR;
    saved_state *st = (saved_state *)*state;
    if (fresh && !chain_inst_alloc_arrays(in, &st->v, v->n)) {
        dfo_state_drop(&in->lc, state);
        return dfo_inst_fail(&in->lc, "%s: out of memory for a state of %lu blocks.", fn, (unsigned long)v->n);
    }
    st->run = *run;
    copy_values(&st->v, v);
    st->v.M = NULL;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_get_state(dfo_lifecycle *lc, const char *fn, void **state)
{
    chain_instance *in = chn(lc);
    return store_state(in, fn, state, &in->lc.run, &in->v);
}

dfo_inst_status dfo_inst_set_state(dfo_lifecycle *lc, const char *fn, const void *state)
{
    chain_instance *in = chn(lc);
    const saved_state *st = (const saved_state *)dfo_state_block(lc, fn, state, STATE_MAGIC);
    if (!st) return DFO_INST_ERROR;
    if (chain_inst_resize(in, fn, st->v.n) != DFO_INST_OK) return DFO_INST_ERROR;
    chain_inst_free_model(&in->v);
    in->lc.run = st->run;
    copy_values(&in->v, &st->v);
    in->v.M = NULL;
    in->v.acc_valid = in->v.me_fresh = 0;
    if (in->lc.run.phase & DFO_PHASES_STARTED) {
        /* the model follows from the parameters (the state is kept: it is the saved one) */
        const chain_params p = chain_inst_params_of(&in->v);
        const chain_alloc al = chain_inst_allocator(in);
        const char *err = NULL;
        in->v.M = chain_create(&p, &al, &err);
        if (!in->v.M) {
            in->lc.run.phase = DFO_PHASE_ERROR;
            return dfo_inst_fail(&in->lc, "%s: the chain could not be rebuilt: %s.", fn, err ? err : "out of memory");
        }
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_free_state(dfo_lifecycle *lc, const char *fn, void **state)
{
    chain_instance *in = chn(lc);
    if (!dfo_state_droppable(lc, fn, state, STATE_MAGIC)) return DFO_INST_ERROR;
    if (*state) free_saved(in, state);
    return DFO_INST_OK;
}

/* ---- serialisation (core/fmu_state.h's format): fixed-size little-endian fields, the same bytes on
 * every platform: n, n_config, the scalar parameters, the input flags, the pending event's block,
 * the arrays, the input derivatives and the last switch, the state, then the run. The chain's
 * fields of format version 4 (a body without the input derivatives, or one without the site arrays
 * k_site, c_site) are refused by their size. ---- */

static size_t body_size(size_t n)
{
    const size_t doubles = DFO_NUM_SP + (size_t)DFO_NUM_AP * n + 2 * (size_t)DFO_NUM_AI * n /* params, inputs */
                           + 2 * (size_t)DFO_NUM_AI * n + 1                                  /* derivatives, sw_t */
                           + 7 + 6 * n;                                                      /* state */
    const size_t int64s = 3 + 1 + 6; /* n, n_config, event_block; sw_block; the state's counters */
    const size_t int32s = 2 * (size_t)DFO_NUM_AI + 1 + n; /* the input flags, ud_set, the modes */
    return 8 * doubles + 8 * int64s + 4 * int32s + DFO_STATE_RUN_BYTES;
}

size_t dfo_inst_state_size(const dfo_lifecycle *lc, const void *state)
{
    (void)lc;
    const saved_state *st = as_state(state);
    return st ? DFO_STATE_HEADER_BYTES + body_size(st->v.n) : 0;
}

static void write_body(dfo_cursor *c, const dfo_run *run, const chain_values *v)
{
    const size_t n = v->n;
    dfo_put_u64(c, n);
    dfo_put_u64(c, v->n_config);
    dfo_put_f64s(c, v->sp, DFO_NUM_SP);
    for (int j = 0; j < DFO_NUM_AI; j++) dfo_put_i32(c, v->u_set[j]);
    for (int j = 0; j < DFO_NUM_AI; j++) dfo_put_i32(c, v->u_set_used[j]);
    dfo_put_u64(c, v->event_block);
    dfo_put_f64s(c, v->pa, (size_t)DFO_NUM_AP * n);
    dfo_put_f64s(c, v->ua, (size_t)DFO_NUM_AI * n);
    dfo_put_f64s(c, v->ua_used, (size_t)DFO_NUM_AI * n);
    dfo_put_f64s(c, v->ud, 2 * (size_t)DFO_NUM_AI * n);
    dfo_put_i32(c, v->ud_set);
    dfo_put_f64(c, v->sw_t);
    dfo_put_u64(c, (uint64_t)v->sw_block);
    const chain_state *s = &v->s;
    dfo_put_f64(c, s->t0);
    dfo_put_f64(c, s->t);
    dfo_put_u64(c, (uint64_t)s->n_grid);
    dfo_put_f64(c, s->W_applied);
    dfo_put_f64(c, s->W_friction);
    dfo_put_f64(c, s->D_damping);
    dfo_put_u64(c, (uint64_t)s->steps);
    dfo_put_u64(c, (uint64_t)s->pivot_steps);
    dfo_put_u64(c, (uint64_t)s->switches);
    dfo_put_u64(c, (uint64_t)s->solves);
    dfo_put_u64(c, (uint64_t)s->exc_n);
    dfo_put_f64(c, s->exc_c);
    dfo_put_f64(c, s->exc_s);
    dfo_put_f64s(c, s->X, n);
    dfo_put_f64s(c, s->V, n);
    dfo_put_f64s(c, s->A, n);
    dfo_put_f64s(c, s->F, n);
    dfo_put_f64s(c, s->hA, n);
    dfo_put_f64s(c, s->t_stick, n);
    for (size_t i = 0; i < n; i++) dfo_put_i32(c, s->mode[i]);
    dfo_put_run(c, run);
}

/* v's arrays allocated for n (read first by the caller). */
static void read_body(dfo_cursor *c, dfo_run *run, chain_values *v)
{
    const size_t n = v->n;
    (void)dfo_get_u64(c);
    v->n_config = (size_t)dfo_get_u64(c);
    dfo_get_f64s(c, v->sp, DFO_NUM_SP);
    for (int j = 0; j < DFO_NUM_AI; j++) v->u_set[j] = dfo_get_i32(c);
    for (int j = 0; j < DFO_NUM_AI; j++) v->u_set_used[j] = dfo_get_i32(c);
    v->event_block = (size_t)dfo_get_u64(c);
    dfo_get_f64s(c, v->pa, (size_t)DFO_NUM_AP * n);
    dfo_get_f64s(c, v->ua, (size_t)DFO_NUM_AI * n);
    dfo_get_f64s(c, v->ua_used, (size_t)DFO_NUM_AI * n);
    dfo_get_f64s(c, v->ud, 2 * (size_t)DFO_NUM_AI * n);
    v->ud_set = dfo_get_i32(c);
    v->sw_t = dfo_get_f64(c);
    v->sw_block = (long long)dfo_get_u64(c);
    v->belts_unsynced = 0; /* a state between steps: on the belts of ua_used */
    chain_state *s = &v->s;
    s->n = n;
    s->t0 = dfo_get_f64(c);
    s->t = dfo_get_f64(c);
    s->n_grid = (long long)dfo_get_u64(c);
    s->W_applied = dfo_get_f64(c);
    s->W_friction = dfo_get_f64(c);
    s->D_damping = dfo_get_f64(c);
    s->steps = (long long)dfo_get_u64(c);
    s->pivot_steps = (long long)dfo_get_u64(c);
    s->switches = (long long)dfo_get_u64(c);
    s->solves = (long long)dfo_get_u64(c);
    s->exc_n = (long long)dfo_get_u64(c);
    s->exc_c = dfo_get_f64(c);
    s->exc_s = dfo_get_f64(c);
    dfo_get_f64s(c, s->X, n);
    dfo_get_f64s(c, s->V, n);
    dfo_get_f64s(c, s->A, n);
    dfo_get_f64s(c, s->F, n);
    dfo_get_f64s(c, s->hA, n);
    dfo_get_f64s(c, s->t_stick, n);
    for (size_t i = 0; i < n; i++) s->mode[i] = dfo_get_i32(c);
    /* the engine's own bookkeeping, not serialised: no breakaway known, no switch (the instance keeps
     * the last switch it reported in sw_t) */
    s->t_switch = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        s->t_break[i] = NAN;
        s->break_dir[i] = 0;
    }
    dfo_get_run(c, run);
}

dfo_inst_status dfo_inst_serialize(dfo_lifecycle *lc, const char *fn, const void *state, unsigned char *buf,
                                   size_t size)
{
    const saved_state *st = (const saved_state *)dfo_state_block(lc, fn, state, STATE_MAGIC);
    if (!st) return DFO_INST_ERROR;
    const size_t body = body_size(st->v.n);
    if (size < DFO_STATE_HEADER_BYTES + body)
        return dfo_inst_fail(lc, "%s: buffer of %lu bytes is too small (%lu needed).", fn, (unsigned long)size,
                             (unsigned long)(DFO_STATE_HEADER_BYTES + body));
    dfo_cursor c = {buf + DFO_STATE_HEADER_BYTES, NULL};
    write_body(&c, &st->run, &st->v);
    dfo_state_seal(buf, body, MODEL_GUID);
    return DFO_INST_OK;
}

/* A deserialised state must describe a simulation this FMU could have reached. */
static const char *implausible(const dfo_run *run, const chain_values *v)
{
    const size_t n = v->n;
    for (int j = 0; j < DFO_NUM_VARS; j++) {
        const dfo_var_info *var = &DFO_VARS[j];
        if (var->home != DFO_IN_PARAMS && var->home != DFO_IN_ARRAYS && var->home != DFO_IN_INPUTS) continue;
        const size_t c = var->array ? n : 1;
        for (size_t i = 0; i < c; i++) {
            chain_values *w = (chain_values *)v;
            if (dfo_inst_invalid(var, *chain_inst_stored(w, var, i))) return "a parameter or input is out of range";
            if (var->home == DFO_IN_INPUTS && !isfinite(v->ua_used[(size_t)var->slot * n + i]))
                return "an input is not finite";
        }
    }
    if (v->n_config < 1 || v->n_config > MAX_n) return "the configured n is out of range";
    const char *why = dfo_run_implausible(run, 1);
    if (why) return why;
    if (v->event_block >= n) return "the pending event is invalid";
    for (size_t i = 0; i < 2 * (size_t)DFO_NUM_AI * n; i++)
        if (!isfinite(v->ud[i])) return "an input derivative is not finite";
    if ((v->ud_set != 0 && v->ud_set != 1) || !isfinite(v->sw_t) || v->sw_block < -1 || v->sw_block >= (long long)n)
        return "the input derivatives' flag or the last switch is invalid";
    for (int j = 0; j < DFO_NUM_AI; j++)
        if ((v->u_set[j] != 0 && v->u_set[j] != 1) || (v->u_set_used[j] != 0 && v->u_set_used[j] != 1))
            return "an input flag is invalid";
    const chain_state *s = &v->s;
    if (!isfinite(s->t) || !isfinite(s->t0) || s->n_grid < 0 || !isfinite(s->exc_c) || !isfinite(s->exc_s) ||
        s->exc_n < -1)
        return "the state is not finite";
    for (size_t i = 0; i < n; i++) {
        if (!isfinite(s->X[i]) || !isfinite(s->V[i]) || !isfinite(s->A[i]) || !isfinite(s->F[i]) ||
            !isfinite(s->hA[i]) || !isfinite(s->t_stick[i]))
            return "the state is not finite";
        if (s->mode[i] < -1 || s->mode[i] > 1) return "a mode is invalid";
    }
    if (run->phase & DFO_PHASES_STARTED)
        return dfo_grid_implausible(run, s->t0, s->n_grid, chain_inst_step_h(v), s->t);
    return NULL;
}

dfo_inst_status dfo_inst_deserialize(dfo_lifecycle *lc, const char *fn, const unsigned char *buf, size_t size,
                                     void **state)
{
    chain_instance *in = chn(lc);
    size_t body = 0;
    if (dfo_state_open(lc, fn, buf, size, MODEL_GUID, &body) != DFO_INST_OK) return DFO_INST_ERROR;
    dfo_cursor c = {NULL, buf + DFO_STATE_HEADER_BYTES};
    const uint64_t n = body >= 8 ? dfo_get_u64(&c) : 0;
    if (n < 1 || n > MAX_n || body != body_size((size_t)n))
        return dfo_inst_fail(lc, "%s: %lu bytes given, not the size of a state of this FMU.", fn, (unsigned long)size);
    chain_values v;
    dfo_run run;
    memset(&v, 0, sizeof v);
    if (!chain_inst_alloc_arrays(in, &v, (size_t)n)) return dfo_inst_fail(lc, "%s: out of memory.", fn);
    c.q = buf + DFO_STATE_HEADER_BYTES;
    read_body(&c, &run, &v);
    const char *why = implausible(&run, &v);
    dfo_inst_status st = DFO_INST_OK;
    if (why) st = dfo_inst_fail(lc, "%s: rejected, %s.", fn, why);
    else st = store_state(in, fn, state, &run, &v);
    chain_inst_free_arrays(in, &v);
    return st;
}
