/* The instance core of the TwoMass FMUs (the model API of core/instance.h): start values, get/set
 * through the variable table generated from the model's description (model_vars.h),
 * initialisation, doStep (with FMI 3.0's early return at a switch), FMU states and their
 * serialisation (core/fmu_state.h's format). The physics is two_mass.h's over the friction engine.
 * No input or output derivatives, no directional derivatives (the description says so). No FMI
 * types. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "engine.h"
#include "fmu_state.h"
#include "instance_common.h"
#include "two_mass.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#define DFO_SAME(name, a, b) typedef char dfo_static_assert_##name[((int)(a) == (int)(b)) ? 1 : -1]
DFO_SAME(scheme_paper, DFO_MD_SCHEME_PAPER, DFO_SCHEME_PAPER);
DFO_SAME(scheme_consistent, DFO_MD_SCHEME_CONSISTENT, DFO_SCHEME_CONSISTENT);
DFO_SAME(scheme_located, DFO_MD_SCHEME_LOCATED, DFO_SCHEME_LOCATED);

#define STATE_MAGIC 0x544d53544154452aULL /* "TMSTATE*" */

/* The engine's state as plain values (its arrays copied): what an FMU state holds. */
typedef struct {
    double t0, t;
    long long n_grid;
    double X[2], V[2], A[2], hA[2], F[2], t_stick[2], t_break[2];
    int mode[2], break_dir[2];
    double t_switch;
    long long steps, solves, pivot_steps, switches;
    long long exc_n;
    double exc_c, exc_s;
} tm_snap;

/* The values of an instance that an FMU state copies. */
typedef struct {
    tm_params p;
    tm_inputs u;
    int started;      /* the model is built and the state started */
    tm_snap snap;     /* the state when saved (kept in step with the engine's at every save) */
} tm_values;

typedef struct {
    dfo_lifecycle lc; /* first: the glues see the instance as its life cycle */
    tm_values v;
    tm_model m;       /* built at the end of initialisation (m.E NULL before) */
    eng_state s;      /* the engine's state (arrays through the host) */
    int s_ready;
} tm_instance;

static tm_instance *tmi(dfo_lifecycle *lc) { return (tm_instance *)lc; }
static const tm_instance *ctmi(const dfo_lifecycle *lc) { return (const tm_instance *)lc; }

/* ---- memory ----------------------------------------------------------------------------------- */

static void *host_alloc(void *env, size_t nobj, size_t size)
{
    tm_instance *in = (tm_instance *)env;
    return in->lc.host.alloc(in->lc.host.ctx, nobj, size);
}

static void host_free(void *env, void *obj)
{
    tm_instance *in = (tm_instance *)env;
    if (obj) in->lc.host.free(in->lc.host.ctx, obj);
}

static eng_alloc allocator(tm_instance *in)
{
    const eng_alloc al = {host_alloc, host_free, in};
    return al;
}

static void free_model(tm_instance *in)
{
    const eng_alloc al = allocator(in);
    if (in->s_ready) eng_state_free(in->m.E, &in->s);
    in->s_ready = 0;
    tm_model_free(&in->m, &al);
}

/* Build the model and its state arrays from v->p (NULL, or why not, in buf). */
static const char *build_model(tm_instance *in, char *buf, size_t len)
{
    free_model(in);
    const eng_alloc al = allocator(in);
    const char *err = NULL;
    if (!tm_model_init(&in->m, &in->v.p, &al, buf, len, &err)) return err;
    if (!eng_state_init(in->m.E, &in->s, 0)) {
        free_model(in);
        return "out of memory";
    }
    in->s_ready = 1;
    return NULL;
}

/* The fields of tm_snap, which are eng_state's: scalars, and arrays of 2 (one per DOF or contact). */
#define SNAP_SCALARS(DO) DO(t0) DO(t) DO(n_grid) DO(t_switch) DO(steps) DO(solves) DO(pivot_steps) DO(switches) \
    DO(exc_n) DO(exc_c) DO(exc_s)
#define SNAP_ARRAYS(DO) DO(X) DO(V) DO(A) DO(hA) DO(F) DO(t_stick) DO(t_break) DO(mode) DO(break_dir)

static void snap_of(const eng_state *s, tm_snap *d)
{
#define TO_SNAP(f) d->f = s->f;
#define TO_SNAP_2(f) d->f[0] = s->f[0]; d->f[1] = s->f[1];
    SNAP_SCALARS(TO_SNAP)
    SNAP_ARRAYS(TO_SNAP_2)
#undef TO_SNAP
#undef TO_SNAP_2
}

static void state_of(const tm_snap *d, eng_state *s)
{
#define TO_STATE(f) s->f = d->f;
#define TO_STATE_2(f) s->f[0] = d->f[0]; s->f[1] = d->f[1];
    SNAP_SCALARS(TO_STATE)
    SNAP_ARRAYS(TO_STATE_2)
#undef TO_STATE
#undef TO_STATE_2
}

/* ---- the variable table ---------------------------------------------------------------------- */

static void *slot(tm_values *v, const dfo_var_info *var) { return dfo_var_slot(&v->p, &v->u, var); }

static void set_start_values(tm_instance *in)
{
    const tm_values zero = {0};
    const dfo_run run0 = {0};
    in->v = zero;
    in->lc.run = run0;
    for (int i = 0; i < DFO_NUM_VARS; i++) {
        const dfo_var_info *var = &DFO_VARS[i];
        if (var->home == DFO_COMPUTED || !var->has_start) continue;
        if (var->type == DFO_REAL) *(double *)slot(&in->v, var) = var->start;
        else *(int *)slot(&in->v, var) = (int)var->start;
    }
    in->lc.run.phase = DFO_PHASE_INSTANTIATED;
}

static const dfo_var_info *lookup(const tm_instance *in, const char *fn, unsigned int vr, dfo_var_type type)
{
    return dfo_inst_lookup(&in->lc, fn, vr, type);
}

/* ---- life cycle ------------------------------------------------------------------------------- */

dfo_lifecycle *dfo_inst_new(const dfo_host *host, const char *name, int logging_on)
{
    tm_instance *in = (tm_instance *)dfo_lifecycle_new(host, sizeof(tm_instance), name, logging_on);
    if (!in) return NULL;
    set_start_values(in);
    return &in->lc;
}

void dfo_inst_delete(dfo_lifecycle *lc)
{
    if (!lc) return;
    free_model(tmi(lc));
    lc->host.free(lc->host.ctx, lc);
}

size_t dfo_inst_n_values(const dfo_lifecycle *lc, const unsigned int vr[], size_t nvr)
{
    (void)lc;
    (void)vr;
    return nvr; /* scalars only */
}

void dfo_inst_log_event_handled(const dfo_lifecycle *lc)
{
    const tm_instance *in = ctmi(lc);
    dfo_inst_log(lc, DFO_INST_OK, DFO_LOG_EVENTS, "t = %.17g: event handled, modes %d %d.", dfo_inst_time(lc),
                 in->s_ready ? in->s.mode[0] : 0, in->s_ready ? in->s.mode[1] : 0);
}

#define NO_STRUCTURAL(lc, fn) dfo_inst_fail(lc, "%s: the FMU has no structural parameters.", fn)

int dfo_inst_has_structural(void) { return 0; }
dfo_inst_status dfo_inst_enter_config(dfo_lifecycle *lc, const char *fn) { return NO_STRUCTURAL(lc, fn); }
dfo_inst_status dfo_inst_exit_config(dfo_lifecycle *lc, const char *fn) { return NO_STRUCTURAL(lc, fn); }
dfo_inst_status dfo_inst_get_uint64(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                    unsigned long long value[])
{
    (void)vr, (void)n, (void)value;
    return NO_STRUCTURAL(lc, fn);
}
dfo_inst_status dfo_inst_set_uint64(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                    const unsigned long long value[])
{
    (void)vr, (void)n, (void)value;
    return NO_STRUCTURAL(lc, fn);
}

/* The engine's inputs from the instance's (an input never set reads 0). */
static eng_inputs inputs_of(const tm_values *v, double F[2])
{
    F[0] = v->u.F1_ext_set ? v->u.F1_ext : 0.0;
    F[1] = v->u.F2_ext_set ? v->u.F2_ext : 0.0;
    eng_inputs e;
    memset(&e, 0, sizeof e);
    e.F_ext = F;
    return e;
}

static void on_switch(void *ctx, double t, size_t contact, const eng_state *s, int from, int to)
{
    tm_instance *in = (tm_instance *)ctx;
    in->lc.switched = 1;
    dfo_inst_log(&in->lc, DFO_INST_OK, DFO_LOG_EVENTS, "t = %.17g: contact %s switches from mode %d to %d (x1 = "
                 "%.17g, x2 = %.17g).", t, contact == 0 ? "ground" : "between", from, to, s->X[0], s->X[1]);
}

dfo_inst_status dfo_inst_exit_init(dfo_lifecycle *lc, const char *fn)
{
    tm_instance *in = tmi(lc);
    char buf[256];
    const char *why = build_model(in, buf, sizeof buf);
    if (why) return dfo_inst_fail(lc, "%s: %s.", fn, why);
    double F[2];
    const eng_inputs e = inputs_of(&in->v, F);
    const double x0[2] = {in->v.p.x1_0, in->v.p.x2_0}, v0[2] = {in->v.p.v1_0, in->v.p.v2_0};
    eng_start(in->m.E, &e, in->lc.run.start_time, x0, v0, &in->s);
    in->v.started = 1;
    in->lc.run.time = in->lc.run.start_time;
    in->lc.run.phase = DFO_PHASE_STEP;
    dfo_inst_log(lc, DFO_INST_OK, DFO_LOG_EVENTS, "start at t = %.17g: modes %d %d, h = %.17g.", in->s.t,
                 in->s.mode[0], in->s.mode[1], in->m.h);
    return DFO_INST_OK;
}

void dfo_inst_reset(dfo_lifecycle *lc)
{
    tm_instance *in = tmi(lc);
    free_model(in);
    set_start_values(in);
    in->lc.warned = 0;
}

/* ---- get / set ------------------------------------------------------------------------------- */

static double output_real(tm_instance *in, int id)
{
    if (id == DFO_OUT_h_used) return tm_step(&in->v.p);
    if (!in->v.started) return NAN;
    const eng_state *s = &in->s;
    double F[2], a[2], f[2];
    const eng_inputs e = inputs_of(&in->v, F);
    switch (id) {
    case DFO_OUT_x1: return s->X[0];
    case DFO_OUT_x2: return s->X[1];
    case DFO_OUT_v1: return s->V[0];
    case DFO_OUT_v2: return s->V[1];
    case DFO_OUT_a1:
    case DFO_OUT_a2: eng_accelerations(in->m.E, &e, s, a); return a[id == DFO_OUT_a2];
    case DFO_OUT_F_g:
    case DFO_OUT_F_c: eng_contact_forces(in->m.E, &e, s, f); return f[id == DFO_OUT_F_c];
    }
    return NAN;
}

dfo_inst_status dfo_inst_get_real(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, double value[])
{
    tm_instance *in = tmi(lc);
    for (size_t i = 0; i < n; i++) {
        const dfo_var_info *var = lookup(in, fn, vr[i], DFO_REAL);
        if (!var) return DFO_INST_ERROR;
        value[i] = (var->home != DFO_COMPUTED) ? *(const double *)slot(&in->v, var) : output_real(in, var->id);
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_get_int(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, int value[])
{
    tm_instance *in = tmi(lc);
    for (size_t i = 0; i < n; i++) {
        const dfo_var_info *var = lookup(in, fn, vr[i], DFO_INTEGER);
        if (!var) return DFO_INST_ERROR;
        if (var->home != DFO_COMPUTED) value[i] = *(const int *)slot(&in->v, var);
        else value[i] = in->v.started ? in->s.mode[var->id == DFO_OUT_mode_c] : 0;
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_get_bool(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, int value[])
{
    tm_instance *in = tmi(lc);
    for (size_t i = 0; i < n; i++) {
        const dfo_var_info *var = lookup(in, fn, vr[i], DFO_BOOLEAN);
        if (!var) return DFO_INST_ERROR;
        value[i] = *(const int *)slot(&in->v, var) ? 1 : 0;
    }
    return DFO_INST_OK;
}

static void store(tm_values *v, const dfo_var_info *var, double x) { dfo_var_store(&v->p, &v->u, var, x); }

static dfo_inst_status set_values(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                  const double value[], dfo_var_type type)
{
    tm_instance *in = tmi(lc);
    for (size_t i = 0; i < n; i++) {
        const dfo_var_info *var = lookup(in, fn, vr[i], type);
        if (!var || !dfo_inst_settable(lc, fn, var, var->name, var->vr)) return DFO_INST_ERROR;
        if (type != DFO_BOOLEAN && !dfo_inst_value_ok(lc, fn, var, value[i])) return DFO_INST_ERROR;
    }
    for (size_t i = 0; i < n; i++) store(&in->v, dfo_find_var(vr[i]), value[i]);
    return DFO_INST_OK;
}

/* A batch of values as doubles (at most this many per call; a longer call is split). */
#define BATCH 64

dfo_inst_status dfo_inst_set_real(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                  const double value[])
{
    return set_values(lc, fn, vr, n, value, DFO_REAL);
}

static dfo_inst_status set_ints(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n, const int value[],
                                dfo_var_type type)
{
    double x[BATCH];
    /* all checked before any is stored: one batch at a time would store part of a rejected call */
    if (n > BATCH) return dfo_inst_fail(lc, "%s: at most %d values per call.", fn, BATCH);
    for (size_t i = 0; i < n; i++) x[i] = (type == DFO_BOOLEAN) ? (value[i] ? 1.0 : 0.0) : (double)value[i];
    return set_values(lc, fn, vr, n, x, type);
}

dfo_inst_status dfo_inst_set_int(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                 const int value[])
{
    return set_ints(lc, fn, vr, n, value, DFO_INTEGER);
}

dfo_inst_status dfo_inst_set_bool(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t n,
                                  const int value[])
{
    return set_ints(lc, fn, vr, n, value, DFO_BOOLEAN);
}

/* ---- doStep ---------------------------------------------------------------------------------- */

/* Advance to t_target (stop_at_switch: at the first switch); the host's time follows. */
static dfo_inst_status advance(dfo_lifecycle *lc, const char *fn, double t_target, int stop_at_switch)
{
    tm_instance *in = tmi(lc);
    tm_snap before;
    snap_of(&in->s, &before);
    double F[2];
    const eng_inputs e = inputs_of(&in->v, F);
    eng_hooks hk;
    memset(&hk, 0, sizeof hk);
    hk.on_switch = on_switch;
    hk.switch_ctx = in;
    hk.stop_at_switch = stop_at_switch;
    in->lc.switched = 0;
    const eng_status st = eng_advance(in->m.E, &e, &in->s, t_target, &hk);
    if (st != ENG_OK && st != ENG_SWITCHED) {
        const double t_fail = in->s.t;
        state_of(&before, &in->s);
        in->lc.run.phase = DFO_PHASE_ERROR;
        return dfo_inst_fail(&in->lc, "%s: step from t = %.17g failed at t = %.17g: %s. The FMU keeps the state at "
                             "t = %.17g; reset it or restore an earlier FMU state.", fn, in->lc.run.time, t_fail,
                             eng_status_text(st), in->lc.run.time);
    }
    const double snap = dfo_snap(in->m.h, t_target);
    in->lc.run.time = (st == ENG_SWITCHED && in->s.t < t_target - snap) ? in->s.t : t_target;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_do_step(dfo_lifecycle *lc, const char *fn, double tc, double dt, unsigned int flags,
                                 double *t_reached)
{
    return dfo_inst_step_by(lc, fn, tc, dt, tmi(lc)->m.h, flags, t_reached, advance);
}

dfo_inst_status dfo_inst_do_step_events(dfo_lifecycle *lc, const char *fn, double tc, double dt,
                                        const dfo_event_opts *opt, dfo_step_result *res)
{
    return dfo_inst_step_events_by(lc, fn, tc, dt, tmi(lc)->m.h, opt, res, advance);
}

/* ---- FMU states ------------------------------------------------------------------------------ */

static dfo_inst_status store_state(tm_instance *in, const char *fn, void **state, const dfo_run *run,
                                   const tm_values *v)
{
    return dfo_values_state_store(&in->lc, fn, state, STATE_MAGIC, run, v, sizeof *v);
}

dfo_inst_status dfo_inst_get_state(dfo_lifecycle *lc, const char *fn, void **state)
{
    tm_instance *in = tmi(lc);
    if (in->v.started) snap_of(&in->s, &in->v.snap);
    return store_state(in, fn, state, &in->lc.run, &in->v);
}

dfo_inst_status dfo_inst_set_state(dfo_lifecycle *lc, const char *fn, const void *state)
{
    tm_instance *in = tmi(lc);
    dfo_run run;
    const tm_values *sv = (const tm_values *)dfo_values_state_get(lc, fn, state, STATE_MAGIC, &run);
    if (!sv) return DFO_INST_ERROR;
    const tm_values v = *sv;
    if (v.started) {
        /* the model from the state's parameters (rebuilt only when they differ from the built one's) */
        if (!in->s_ready || memcmp(&in->m.p, &v.p, sizeof v.p) != 0) {
            in->v = v;
            char buf[256];
            const char *why = build_model(in, buf, sizeof buf);
            if (why) return dfo_inst_fail(lc, "%s: %s.", fn, why);
        }
        state_of(&v.snap, &in->s);
    } else {
        free_model(in);
    }
    in->v = v;
    in->lc.run = run;
    return DFO_INST_OK;
}

DFO_VALUES_STATE_ENTRY_POINTS(tm_values, STATE_MAGIC, MODEL_GUID)

/* A deserialised state must describe a simulation this FMU could have reached. */
static const char *implausible(const dfo_run *r, tm_values *v, char *buf, size_t len)
{
    for (int i = 0; i < DFO_NUM_VARS; i++) {
        const dfo_var_info *var = &DFO_VARS[i];
        if (var->home == DFO_COMPUTED || var->type == DFO_BOOLEAN) continue;
        const double x = var->type == DFO_REAL ? *(const double *)slot(v, var) : *(const int *)slot(v, var);
        if (dfo_inst_invalid(var, x)) return "a parameter or input is out of range";
    }
    const char *why = dfo_run_implausible(r, 0);
    if (why) return why;
    if ((why = tm_check(&v->p, buf, len))) return why;
    if (v->started != 0 && v->started != 1) return "the start flag is invalid";
    if (!v->started) return NULL;
    const tm_snap *s = &v->snap;
    for (int i = 0; i < 2; i++) {
        if (!isfinite(s->X[i]) || !isfinite(s->V[i]) || !isfinite(s->A[i]) || !isfinite(s->F[i]) ||
            !isfinite(s->hA[i]))
            return "the state is not finite";
        if (s->mode[i] < -1 || s->mode[i] > 1 || s->break_dir[i] < -1 || s->break_dir[i] > 1)
            return "a mode is invalid";
    }
    if (!isfinite(s->t) || !isfinite(s->t0) || s->n_grid < 0 || isnan(s->t_switch)) return "the state is not finite";
    if (s->exc_n < -1) return "the excitation cache is invalid";
    return dfo_grid_implausible(r, s->t0, s->n_grid, tm_step(&v->p), s->t);
}

dfo_inst_status dfo_inst_deserialize(dfo_lifecycle *lc, const char *fn, const unsigned char *buf, size_t size,
                                     void **state)
{
    tm_values v;
    dfo_run run;
    if (dfo_values_state_read(lc, fn, buf, size, MODEL_GUID, sizeof v, &v, &run) != DFO_INST_OK)
        return DFO_INST_ERROR;
    char msg[256];
    const char *why = implausible(&run, &v, msg, sizeof msg);
    if (why) return dfo_inst_fail(lc, "%s: rejected, %s.", fn, why);
    v.snap.exc_n = -1; /* the excitation cache is rebuilt, never trusted */
    return store_state(tmi(lc), fn, state, &run, &v);
}

/* ---- no derivatives (the description: canInterpolateInputs false, maxOutputDerivativeOrder 0,
 * providesDirectionalDerivative false) ------------------------------------------------------------ */

int dfo_inst_max_input_order(void) { return 0; }
int dfo_inst_max_output_order(void) { return 0; }

#define NO_DERIVATIVES(lc, fn, what) dfo_inst_fail(lc, "%s: the TwoMass FMU provides no %s.", fn, what)

dfo_inst_status dfo_inst_set_input_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[], size_t nvr,
                                               const int order[], const double value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    return NO_DERIVATIVES(lc, fn, "input derivatives");
}

dfo_inst_status dfo_inst_get_output_derivatives(dfo_lifecycle *lc, const char *fn, const unsigned int vr[],
                                                size_t nvr, const int order[], double value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    return NO_DERIVATIVES(lc, fn, "output derivatives");
}

/* Directional and adjoint derivatives alike: none. */
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
