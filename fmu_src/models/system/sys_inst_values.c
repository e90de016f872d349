/* The DryFrictionSystem instance's values (sys_instance.h): the host's memory, the layout of the
 * values array for the sizes n, nc, its allocation at those sizes with every value at its start,
 * the model's release. Below the instance core and the structure file's reader (sys_instance.c,
 * sys_inst_resources.c), which both resize through it. No FMI types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "sys_instance.h"

#include <string.h>

/* ---- memory and layout ------------------------------------------------------------------------ */

static void *host_alloc(void *env, size_t nobj, size_t size)
{
    sys_instance *in = (sys_instance *)env;
    return in->lc.host.alloc(in->lc.host.ctx, nobj, size);
}

static void host_free(void *env, void *obj)
{
    sys_instance *in = (sys_instance *)env;
    if (obj) in->lc.host.free(in->lc.host.ctx, obj);
}

eng_alloc sys_allocator(sys_instance *in)
{
    const eng_alloc al = {host_alloc, host_free, in};
    return al;
}

size_t sys_var_count(const dfo_var_info *var, size_t n, size_t nc)
{
    size_t c = 1;
    for (int d = 0; d < var->ndims; d++) c *= var->dims[d] == DFO_STRUCT_n ? n : nc;
    return c;
}

sys_layout sys_layout_of(size_t n, size_t nc)
{
    sys_layout L;
    memset(&L, 0, sizeof L);
    L.n = n;
    L.nc = nc;
    size_t k = SYS_HEAD;
    L.sp = k;
    k += DFO_NUM_SP;
    for (int j = 0; j < DFO_NUM_VARS; j++) {
        const dfo_var_info *var = &DFO_VARS[j];
        if (var->home != DFO_IN_ARRAYS) continue;
        L.ap[var->slot] = k;
        k += sys_var_count(var, n, nc);
    }
    for (int pass = 0; pass < 2; pass++)
        for (int j = 0; j < DFO_NUM_VARS; j++) {
            const dfo_var_info *var = &DFO_VARS[j];
            if (var->home != DFO_IN_INPUTS) continue;
            (pass ? L.ai_used : L.ai)[var->slot] = k;
            k += sys_var_count(var, n, nc);
        }
    L.snap = k;
    k += SYS_SNAP_NS + SYS_SNAP_NA_N * n + SYS_SNAP_NA_NC * nc;
    L.obs = k;
    k += SYS_OBS_SIZE(n, nc);
    L.ud = k;
    k += 2 * (n + nc);
    L.total = k;
    return L;
}

void sys_free_model(sys_instance *in)
{
    const eng_alloc al = sys_allocator(in);
    if (in->s_ready) eng_state_free(in->m.E, &in->s);
    in->s_ready = 0;
    sys_model_free(&in->m, &al);
}

void sys_free_values(sys_instance *in)
{
    if (in->vals) in->lc.host.free(in->lc.host.ctx, in->vals);
    if (in->scratch) in->lc.host.free(in->lc.host.ctx, in->scratch);
    in->vals = in->scratch = NULL;
}

/* Every value at its start (the run's flags cleared). */
void sys_value_starts(double *vals, const sys_layout *L)
{
    memset(vals, 0, L->total * sizeof *vals);
    vals[SYS_H_N] = (double)L->n;
    vals[SYS_H_NC] = (double)L->nc;
    vals[SYS_H_TOTAL] = (double)L->total;
    for (int j = 0; j < DFO_NUM_VARS; j++) {
        const dfo_var_info *var = &DFO_VARS[j];
        if (var->home == DFO_IN_PARAMS) vals[L->sp + (size_t)var->slot] = var->start;
        if (var->home != DFO_IN_ARRAYS && var->home != DFO_IN_INPUTS) continue;
        const size_t c = sys_var_count(var, L->n, L->nc);
        double *a = vals + (var->home == DFO_IN_ARRAYS ? L->ap[var->slot] : L->ai[var->slot]);
        for (size_t i = 0; i < c; i++) a[i] = var->start;
        if (var->home == DFO_IN_INPUTS) memcpy(vals + L->ai_used[var->slot], a, c * sizeof *a);
    }
#if DFO_NUM_DIAG_STARTS > 0
    /* matrices that start diagonal: the elements (i, j), i != j, at their own start (every matrix has
     * n columns) */
    for (int d = 0; d < DFO_NUM_DIAG_STARTS; d++) {
        const dfo_var_info *var = &DFO_VARS[DFO_DIAG_STARTS[d].var];
        const size_t c = sys_var_count(var, L->n, L->nc);
        double *a = vals + L->ap[var->slot];
        for (size_t k = 0; k < c; k++)
            if (k / L->n != k % L->n) a[k] = DFO_DIAG_STARTS[d].off;
    }
#endif
}

dfo_inst_status sys_resize(sys_instance *in, const char *fn, size_t n, size_t nc)
{
    if (in->vals && n == in->L.n && nc == in->L.nc) return DFO_INST_OK;
    const sys_layout L = sys_layout_of(n, nc);
    double *vals = (double *)in->lc.host.alloc(in->lc.host.ctx, L.total, sizeof(double));
    double *scratch = (double *)in->lc.host.alloc(in->lc.host.ctx, n + 2 * nc + 1, sizeof(double));
    if (!vals || !scratch) {
        if (vals) in->lc.host.free(in->lc.host.ctx, vals);
        if (scratch) in->lc.host.free(in->lc.host.ctx, scratch);
        return dfo_inst_fail(&in->lc, "%s: out of memory for n = %lu, nc = %lu.", fn, (unsigned long)n,
                             (unsigned long)nc);
    }
    sys_free_model(in);
    sys_free_values(in);
    in->vals = vals;
    in->scratch = scratch;
    in->L = L;
    sys_value_starts(vals, &L);
    return DFO_INST_OK;
}

