/* The DryFrictionSystem instance core (sys_instance.h), its part for doStep (with FMI 3.0's early
 * return at a switch), FMU states and their serialisation (core/fmu_state.h's format: the values
 * array, whose size follows n and nc, then the run), and the derivatives it does not provide. No FMI
 * types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "fmu_state.h"
#include "sys_instance.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define STATE_MAGIC 0x5359535354415445ULL /* "SYSSTATE" */

/* ---- doStep ----------------------------------------------------------------------------------- */

static void on_switch(void *ctx, double t, size_t contact, const eng_state *s, int from, int to)
{
    sys_instance *in = (sys_instance *)ctx;
    (void)s;
    in->lc.switched = 1;
    const double *sp = in->vals + in->L.sp;
    if (sp[DFO_SP_observe] != 0.0 && t > sp[DFO_SP_t_obs_start] && t <= sp[DFO_SP_t_obs_stop])
        in->vals[in->L.obs + SYS_OBS_TRANSITIONS(in->L.n, in->L.nc) + contact] += 1.0;
    dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_EVENTS, "t = %.17g: contact %lu switches from mode %d to %d.", t,
                 (unsigned long)contact + 1, from, to);
}

/* Advance to t_target (stop_at_switch: at the first switch); the host's time follows. Inputs set
 * since the last step are taken at its start (eng_new_inputs). On failure the state of the step's
 * start is kept (the snapshot in vals). */
static dfo_inst_status advance(dfo_lifecycle *lc, const char *fn, double t_target, int stop_at_switch)
{
    sys_instance *in = sysi(lc);
    double *vals = in->vals;
    const sys_layout *L = &in->L;
    const char *refused = sys_belt_refused(vals, L);
    if (refused) return dfo_inst_fail(&in->lc, "%s: %s.", fn, refused); /* (nothing changed) */
    sys_snap_of(&in->s, vals, L); /* the state at the step's start */
    eng_hooks hk;
    memset(&hk, 0, sizeof hk);
    hk.on_switch = on_switch;
    hk.switch_ctx = in;
    hk.stop_at_switch = stop_at_switch;
    hk.obs = sys_observer(in);
    in->lc.switched = 0;
    if (sys_inputs_changed(vals, L)) {
        const eng_inputs old_in = sys_inputs_of(vals, L, 1), new_in = sys_inputs_of(vals, L, 0);
        eng_new_inputs(in->m.E, &old_in, &new_in, &in->s, &hk);
        sys_sync_inputs(vals, L);
    }
    eng_inputs e = sys_inputs_of(vals, L, 1);
    const double t_ref = in->lc.run.time;
    sys_ramp_of(vals, L, t_ref, &e);
    /* the state's stick breakaway (eng_state.stick_tb) is of these inputs: every change of them went
     * through eng_new_inputs, which forgets it (a ramp keeps none): kept across the host's steps, so that
     * a run split into steps places the breakaway where one step does */
    hk.stick_kept = !(e.dF_ext[0] || e.dF_ext[1] || e.dN_ext[0] || e.dN_ext[1]);
    const eng_status st = eng_advance(in->m.E, &e, &in->s, t_target, &hk);
    if (st != ENG_OK && st != ENG_SWITCHED) {
        const double t_fail = in->s.t;
        sys_state_of(vals, L, &in->s);
        in->lc.run.phase = DFO_PHASE_ERROR;
        return dfo_inst_fail(&in->lc, "%s: step from t = %.17g failed at t = %.17g: %s. The FMU keeps the state at "
                             "t = %.17g; reset it or restore an earlier FMU state.", fn, in->lc.run.time, t_fail,
                             eng_status_text(st), in->lc.run.time);
    }
    const double snap = dfo_snap(in->m.h, t_target);
    in->lc.run.time = (st == ENG_SWITCHED && in->s.t < t_target - snap) ? in->s.t : t_target;
    sys_ramp_done(vals, L, t_ref, in->lc.run.time);
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_do_step(dfo_lifecycle *lc, const char *fn, double tc, double dt, unsigned int flags,
                                 double *t_reached)
{
    return dfo_inst_step_by(lc, fn, tc, dt, sysi(lc)->m.h, flags, t_reached, advance);
}

dfo_inst_status dfo_inst_do_step_events(dfo_lifecycle *lc, const char *fn, double tc, double dt,
                                        const dfo_event_opts *opt, dfo_step_result *res)
{
    return dfo_inst_step_events_by(lc, fn, tc, dt, sysi(lc)->m.h, opt, res, advance);
}

/* ---- FMU states ------------------------------------------------------------------------------- */

/* A state's values: the values array of its sizes (its head says them and its length). */
static const double *state_values(const dfo_lifecycle *lc, const char *fn, const void *state, dfo_run *run)
{
    return (const double *)dfo_values_state_get(lc, fn, state, STATE_MAGIC, run);
}

dfo_inst_status dfo_inst_get_state(dfo_lifecycle *lc, const char *fn, void **state)
{
    sys_instance *in = sysi(lc);
    if (in->s_ready && in->vals[SYS_H_STARTED] != 0.0) sys_snap_of(&in->s, in->vals, &in->L);
    if (*state) {
        /* an existing state of other sizes is dropped and taken anew */
        const double *old = state_values(lc, fn, *state, NULL);
        if (!old) return DFO_INST_ERROR;
        if ((size_t)old[SYS_H_TOTAL] != in->L.total) {
            if (!dfo_state_droppable(lc, fn, state, STATE_MAGIC)) return DFO_INST_ERROR;
            dfo_state_drop(lc, state);
        }
    }
    return dfo_values_state_store(lc, fn, state, STATE_MAGIC, &in->lc.run, in->vals, in->L.total * sizeof(double));
}

dfo_inst_status dfo_inst_set_state(dfo_lifecycle *lc, const char *fn, const void *state)
{
    sys_instance *in = sysi(lc);
    dfo_run run;
    const double *sv = state_values(lc, fn, state, &run);
    if (!sv) return DFO_INST_ERROR;
    const size_t n = (size_t)sv[SYS_H_N], nc = (size_t)sv[SYS_H_NC];
    const sys_layout L = sys_layout_of(n, nc);
    /* the model is rebuilt only when the sizes or the parameters differ from the built one's */
    const int same = in->s_ready && n == in->L.n && nc == in->L.nc &&
                     memcmp(in->vals + L.sp, sv + L.sp, (L.ai[0] - L.sp) * sizeof(double)) == 0;
    if (sys_resize(in, fn, n, nc) != DFO_INST_OK) return DFO_INST_ERROR;
    memcpy(in->vals, sv, L.total * sizeof(double));
    if (sv[SYS_H_STARTED] != 0.0) {
        if (!same) {
            char buf[320];
            const char *why = sys_build(in, buf, sizeof buf);
            if (why) return dfo_inst_fail(lc, "%s: %s.", fn, why);
        }
        sys_state_of(in->vals, &in->L, &in->s);
    } else {
        sys_free_model(in);
    }
    in->lc.run = run;
    in->n_config = n;
    in->nc_config = nc;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_free_state(dfo_lifecycle *lc, const char *fn, void **state)
{
    if (!dfo_state_droppable(lc, fn, state, STATE_MAGIC)) return DFO_INST_ERROR;
    dfo_state_drop(lc, state);
    return DFO_INST_OK;
}

size_t dfo_inst_state_size(const dfo_lifecycle *lc, const void *state)
{
    const double *sv = state ? state_values(lc, "fmi3SerializedFMUStateSize", state, NULL) : NULL;
    if (!sv) return 0;
    return dfo_values_state_size(state, STATE_MAGIC, (size_t)sv[SYS_H_TOTAL] * sizeof(double));
}

dfo_inst_status dfo_inst_serialize(dfo_lifecycle *lc, const char *fn, const void *state, unsigned char *buf,
                                   size_t size)
{
    const double *sv = state_values(lc, fn, state, NULL);
    if (!sv) return DFO_INST_ERROR;
    return dfo_values_state_serialize(lc, fn, state, STATE_MAGIC, (size_t)sv[SYS_H_TOTAL] * sizeof(double), buf, size,
                                      MODEL_GUID);
}

/* A deserialised values array (total doubles) must describe a simulation this FMU could have reached. */
static const char *implausible(sys_instance *in, const dfo_run *r, const double *v, size_t total, char *buf,
                               size_t len)
{
    const double dn = v[SYS_H_N], dnc = v[SYS_H_NC];
    if (!(dn >= 1.0 && dn <= (double)MAX_n && dn == floor(dn)) || !(dnc >= 0.0 && dnc <= (double)MAX_nc && dnc == floor(dnc)))
        return "the sizes n, nc are out of range";
#if defined(DFO_SYSTEM_FIXED_N)
    /* FMI 2.0 has no configuration mode: the sizes are the instance's (its structure file's, else the
     * build's), and its value references are laid out for them */
    if (dn != (double)in->L.n || dnc != (double)in->L.nc) {
        snprintf(buf, len, "its sizes n = %.17g, nc = %.17g are not this instance's (n = %lu, nc = %lu, from its "
                 "structure file or its build)", dn, dnc, (unsigned long)in->L.n, (unsigned long)in->L.nc);
        return buf;
    }
#endif
    const size_t n = (size_t)dn, nc = (size_t)dnc;
    const sys_layout L = sys_layout_of(n, nc);
    if (L.total != total || v[SYS_H_TOTAL] != (double)total) return "its length does not match its sizes";
    if (v[SYS_H_STARTED] != 0.0 && v[SYS_H_STARTED] != 1.0) return "the start flag is invalid";
    for (int j = 0; j < 2 * DFO_NUM_AI; j++)
        if (v[SYS_H_SET + j] != 0.0 && v[SYS_H_SET + j] != 1.0) return "an input flag is invalid";
    for (int j = 0; j < DFO_NUM_VARS; j++) {
        const dfo_var_info *var = &DFO_VARS[j];
        if (var->home == DFO_IN_PARAMS) {
            if (dfo_inst_invalid(var, v[L.sp + (size_t)var->slot])) return "a parameter is out of range";
            continue;
        }
        if (var->home != DFO_IN_ARRAYS && var->home != DFO_IN_INPUTS) continue;
        const size_t c = sys_var_count(var, n, nc);
        for (int used = 0; used < (var->home == DFO_IN_INPUTS ? 2 : 1); used++) {
            const double *a = v + (var->home == DFO_IN_ARRAYS ? L.ap[var->slot] : (used ? L.ai_used : L.ai)[var->slot]);
            for (size_t i = 0; i < c; i++)
                if (dfo_inst_invalid(var, a[i])) return "a parameter or input is out of range";
        }
    }
    const char *why = dfo_run_implausible(r, 1);
    if (why) return why;
    const eng_alloc al = sys_allocator(in);
    const sys_params p = sys_params_of(v, &L);
    if ((why = sys_check(&p, &al, buf, len))) return why;
    if (v[SYS_H_STARTED] == 0.0) return NULL;
    const double *s = v + L.snap;
    for (size_t k = 0; k < SYS_SNAP_NS + SYS_SNAP_NA_N * n + 3 * nc; k++)
        if (k != 4 && k != 12 && k != 3 && !(k >= SYS_SNAP_NS + SYS_SNAP_NA_N * n + 2 * nc) && !isfinite(s[k]))
            return "the state is not finite";
    for (size_t j = 0; j < 2 * nc; j++) {
        const double m = s[SYS_SNAP_NS + SYS_SNAP_NA_N * n + 3 * nc + j];
        if (!(m == -1.0 || m == 0.0 || m == 1.0)) return "a mode is invalid";
    }
    for (size_t j = 0; j < nc; j++)
        if (!isfinite(s[SYS_SNAP_NS + SYS_SNAP_NA_N * n + 5 * nc + j])) return "the state is not finite"; /* sliders */
    if (isnan(s[3])) return "the state is not finite"; /* t_switch: -inf allowed */
    if (s[2] < 0.0 || s[2] != floor(s[2])) return "the state's grid index is invalid";
    if (s[12] < -1.0) return "the excitation cache is invalid";
    const double h = sys_step(&p, &al);
    return dfo_grid_implausible(r, s[0], (long long)s[2], h, s[1]);
}

dfo_inst_status dfo_inst_deserialize(dfo_lifecycle *lc, const char *fn, const unsigned char *buf, size_t size,
                                     void **state)
{
    sys_instance *in = sysi(lc);
    size_t body = 0;
    if (dfo_state_open(lc, fn, buf, size, MODEL_GUID, &body) != DFO_INST_OK) return DFO_INST_ERROR;
    if (body < DFO_STATE_RUN_BYTES + SYS_HEAD * sizeof(double) || (body - DFO_STATE_RUN_BYTES) % sizeof(double))
        return dfo_inst_fail(lc, "%s: rejected, its length fits no state of this FMU.", fn);
    const size_t vsize = body - DFO_STATE_RUN_BYTES, total = vsize / sizeof(double);
    double *v = (double *)lc->host.alloc(lc->host.ctx, total, sizeof(double));
    if (!v) return dfo_inst_fail(lc, "%s: out of memory.", fn);
    dfo_run run;
    dfo_inst_status st = dfo_values_state_read(lc, fn, buf, size, MODEL_GUID, vsize, v, &run);
    if (st == DFO_INST_OK) {
        char msg[320];
        const char *why = implausible(in, &run, v, total, msg, sizeof msg);
        if (why) st = dfo_inst_fail(lc, "%s: rejected, %s.", fn, why);
    }
    if (st == DFO_INST_OK) {
        const sys_layout L = sys_layout_of((size_t)v[SYS_H_N], (size_t)v[SYS_H_NC]);
        v[L.snap + 12] = -1.0; /* the excitation cache is rebuilt, never trusted */
        if (*state) st = dfo_inst_free_state(lc, fn, state);
        if (st == DFO_INST_OK) st = dfo_values_state_store(lc, fn, state, STATE_MAGIC, &run, v, vsize);
    }
    lc->host.free(lc->host.ctx, v);
    return st;
}

/* ---- no output derivatives (the description: maxOutputDerivativeOrder 0,
 * providesDirectionalDerivative false) ------------------------------------------------------------ */

int dfo_inst_max_output_order(void) { return 0; }

#define NO_DERIVATIVES(lc, fn, what) dfo_inst_fail(lc, "%s: the DryFrictionSystem FMU provides no %s.", fn, what)

dfo_inst_status dfo_inst_get_output_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[],
                                                size_t nvr, const int order[], double value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    return NO_DERIVATIVES(lc, fn, "output derivatives");
}

static dfo_inst_status no_partials(dfo_lifecycle *lc, const char *fn, const char *what, const unsigned int unknown[],
                                   size_t nu, const unsigned int known[], size_t nk, const double seed[],
                                   double sensitivity[])
{
    (void)unknown, (void)nu, (void)known, (void)nk, (void)seed, (void)sensitivity;
    return NO_DERIVATIVES(lc, fn, what);
}

dfo_inst_status dfo_inst_directional(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                     const unsigned int known[], size_t nk, const double seed[], double sensitivity[])
{
    return no_partials(lc, fn, "directional derivatives", unknown, nu, known, nk, seed, sensitivity);
}

dfo_inst_status dfo_inst_adjoint(dfo_lifecycle *lc, const char *fn, const unsigned int unknown[], size_t nu,
                                 const unsigned int known[], size_t nk, const double seed[], double sensitivity[])
{
    return no_partials(lc, fn, "adjoint derivatives", unknown, nu, known, nk, seed, sensitivity);
}
