/* The instance core of the DryFrictionChain FMUs (instance.h's API for the indexed model of
 * fmu_src/chain/modelDescription.xml): the oscillator's life cycle, phases, events and FMU state
 * framing (logging, range checks, doStep checks and the checksum are instance_common.c's, shared
 * with it), over values that are arrays of n blocks (n the
 * structural parameter, set in FMI 3.0's configuration mode, fixed by the build in FMI 2.0 where
 * DFO_CHAIN_FIXED_N is defined: by chain_config.h, the build's configuration generated from the
 * model description into the FMU's sources/, so that a plain compile of the listed sources builds
 * the right FMU). The physics is chain.[ch]. No FMI types.
 *
 * Variables: the generated table (model_vars.h) gives each variable its group and slot. FMI 3.0
 * reaches an array through its own value reference (n values); FMI 2.0 reaches element i (1-based)
 * through the array's value reference + i, named m[i] in messages.
 *
 * Memory: every array through the host's allocator, O(n): parameters (10 n), inputs (2 x 2 n),
 * the state and the step's start state (7 n each), one scratch array, the chain model's workspace. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "chain_config.h" /* DFO_CHAIN_FIXED_N in an FMI 2.0 build */
#include "instance.h"
#include "instance_common.h"
#include "oscillator.h" /* DFO_STEPS_PER_PERIOD, DFO_MIN_STEPS_PER_PERIOD */

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* The model description's scheme values are those of the physics. */
typedef char dfo_static_assert_schemes[(DFO_MD_SCHEME_PAPER == 1 && DFO_MD_SCHEME_CONSISTENT == 2 &&
                                        DFO_MD_SCHEME_LOCATED == 3) ? 1 : -1];

#define STATE_MAGIC 0x444643484d555354ULL /* FMU state tag */
#define SERIAL_MAGIC "DFCSTATE"
#define SERIAL_VERSION 1u
#define HEADER_BYTES 24u /* magic[8], version u32, size u32, checksum u64 */

#if defined(DFO_CHAIN_FIXED_N)
#define N_START ((size_t)(DFO_CHAIN_FIXED_N))
typedef char dfo_static_assert_fixed_n[(DFO_CHAIN_FIXED_N >= 1 && DFO_CHAIN_FIXED_N <= MAX_n) ? 1 : -1];
#else
#define N_START ((size_t)START_n)
#endif

/* ---- memory ---------------------------------------------------------------------------------- */

static void *al_allocate(void *env, size_t nobj, size_t size)
{
    const dfo_instance *in = (const dfo_instance *)env;
    return in->host.alloc(in->host.ctx, nobj, size);
}

static void al_release(void *env, void *obj)
{
    const dfo_instance *in = (const dfo_instance *)env;
    in->host.free(in->host.ctx, obj);
}

static chain_alloc allocator(dfo_instance *in)
{
    const chain_alloc al = {al_allocate, al_release, in};
    return al;
}

static double *dalloc(dfo_instance *in, size_t n) { return (double *)in->host.alloc(in->host.ctx, n, sizeof(double)); }

static void release(dfo_instance *in, void *p)
{
    if (p) in->host.free(in->host.ctx, p);
}

static void free_model(dfo_values *v)
{
    if (v->M) chain_destroy(v->M);
    v->M = NULL;
}

/* The arrays of v (not the model). */
static void free_arrays(dfo_instance *in, dfo_values *v)
{
    const chain_alloc al = allocator(in);
    release(in, v->pa);
    release(in, v->ua);
    release(in, v->ua_used);
    release(in, v->scratch);
    chain_state_release(&al, &v->s);
    chain_state_release(&al, &v->s0);
    v->pa = v->ua = v->ua_used = v->scratch = NULL;
}

/* Arrays for n blocks into v (v's own pointers untouched on failure: 0 returned). */
static int alloc_arrays(dfo_instance *in, dfo_values *v, size_t n)
{
    const chain_alloc al = allocator(in);
    dfo_values w;
    memset(&w, 0, sizeof w);
    w.pa = dalloc(in, (size_t)DFO_NUM_AP * n);
    w.ua = dalloc(in, (size_t)DFO_NUM_AI * n);
    w.ua_used = dalloc(in, (size_t)DFO_NUM_AI * n);
    w.scratch = dalloc(in, n);
    const int s_ok = chain_state_alloc(&al, n, &w.s);
    const int s0_ok = chain_state_alloc(&al, n, &w.s0);
    if (!w.pa || !w.ua || !w.ua_used || !w.scratch || !s_ok || !s0_ok) {
        free_arrays(in, &w);
        return 0;
    }
    v->pa = w.pa;
    v->ua = w.ua;
    v->ua_used = w.ua_used;
    v->scratch = w.scratch;
    v->s = w.s;
    v->s0 = w.s0;
    v->n = n;
    return 1;
}

/* ---- the variable table ---------------------------------------------------------------------- */

static const dfo_var_info *find_var(unsigned int vr)
{
    for (int i = 0; i < DFO_NUM_VARS; i++)
        if (DFO_VARS[i].vr == vr) return &DFO_VARS[i];
    return NULL;
}

/* A value reference resolved: the variable and, for an FMI 2.0 element, its index (0-based). */
typedef struct {
    const dfo_var_info *var;
    long elem; /* -1: the whole variable (a scalar, or every element of an array) */
    char name[48];
} ref;

static int resolve(const dfo_instance *in, unsigned int vr, ref *r)
{
    const dfo_var_info *var = find_var(vr);
#if defined(DFO_CHAIN_FIXED_N)
    (void)in;
    if (var && !var->array) {
        r->var = var;
        r->elem = -1;
        snprintf(r->name, sizeof r->name, "%s", var->name);
        return 1;
    }
    const unsigned int i = vr % DFO_ARRAY_VR_STRIDE;
    var = find_var(vr - i);
    if (var && var->array && i >= 1 && i <= in->v.n) {
        r->var = var;
        r->elem = (long)i - 1;
        snprintf(r->name, sizeof r->name, "%s[%u]", var->name, i);
        return 1;
    }
    return 0;
#else
    (void)in;
    if (!var) return 0;
    r->var = var;
    r->elem = -1;
    snprintf(r->name, sizeof r->name, "%s", var->name);
    return 1;
#endif
}

/* Values a resolved variable holds. */
static size_t count(const dfo_instance *in, const ref *r)
{
    return (r->var->array && r->elem < 0) ? in->v.n : 1;
}

size_t dfo_inst_n_values(const dfo_instance *in, const unsigned int vr[], size_t nvr)
{
    size_t total = 0;
    for (size_t i = 0; i < nvr; i++) {
        ref r;
        total += resolve(in, vr[i], &r) ? count(in, &r) : 1;
    }
    return total;
}

static const char *type_name(dfo_var_type t)
{
    return t == DFO_REAL ? "Real" : t == DFO_INTEGER ? "Integer" : t == DFO_UINT64 ? "UInt64" : "Boolean";
}

static int lookup(const dfo_instance *in, const char *fn, unsigned int vr, dfo_var_type type, ref *r)
{
    if (!resolve(in, vr, r)) {
        dfo_inst_fail(in, "%s: unknown value reference %u.", fn, vr);
        return 0;
    }
    if (r->var->type != type) {
        dfo_inst_fail(in, "%s: variable %s (value reference %u) is of type %s, not %s.", fn, r->name, vr,
                      type_name(r->var->type), type_name(type));
        return 0;
    }
    return 1;
}

static int check_value(const dfo_instance *in, const char *fn, const ref *r, unsigned int vr, double x)
{
    const char *range = dfo_inst_invalid(r->var, x);
    if (!range) return 1;
    const int exact = r->var->home == DFO_IN_PARAMS && r->var->slot == DFO_SP_scheme && x == 4.0;
    dfo_inst_fail(in, "%s: invalid value %.17g for %s (value reference %u); valid range: %s%s.", fn, x, r->name, vr,
                  range, exact ? " (the chain has no exact scheme)" : "");
    return 0;
}

static int settable(const dfo_instance *in, const char *fn, const ref *r, unsigned int vr)
{
    const int ph = in->v.phase;
    const dfo_var_info *var = r->var;
    if (var->causality == DFO_STRUCTURAL) {
        if (ph == DFO_PHASE_CONFIG) return 1;
        dfo_inst_fail(in, "%s: %s (value reference %u) is a structural parameter: set it in configuration mode "
                      "(fmi3EnterConfigurationMode), not in %s.", fn, r->name, vr, dfo_phase_name((dfo_phase)ph));
        return 0;
    }
    if (var->causality == DFO_PARAMETER && (ph & (DFO_PHASE_INSTANTIATED | DFO_PHASE_INIT))) return 1;
    if (var->causality == DFO_INPUT &&
        (ph & (DFO_PHASE_INSTANTIATED | DFO_PHASE_INIT | DFO_PHASE_STEP | DFO_PHASE_EVENT)))
        return 1;
    if (var->causality == DFO_PARAMETER)
        dfo_inst_fail(in, "%s: variable %s (value reference %u) is a fixed parameter and cannot be set in %s.", fn,
                      r->name, vr, dfo_phase_name((dfo_phase)ph));
    else if (var->causality == DFO_INPUT)
        dfo_inst_fail(in, "%s: input %s (value reference %u) cannot be set in %s.", fn, r->name, vr,
                      dfo_phase_name((dfo_phase)ph));
    else
        dfo_inst_fail(in, "%s: variable %s (value reference %u) is %s and cannot be set.", fn, r->name, vr,
                      var->causality == DFO_OUTPUT ? "an output" : "a calculated parameter");
    return 0;
}

/* Where a stored value of element i lives. */
static double *stored(dfo_values *v, const dfo_var_info *var, size_t i)
{
    switch (var->home) {
    case DFO_IN_PARAMS: return &v->sp[var->slot];
    case DFO_IN_ARRAYS: return &v->pa[(size_t)var->slot * v->n + i];
    case DFO_IN_INPUTS: return &v->ua[(size_t)var->slot * v->n + i];
    default: return NULL;
    }
}

/* Array parameters and inputs at their start values (every element the table's start). */
static void array_starts(dfo_values *v)
{
    for (int j = 0; j < DFO_NUM_VARS; j++) {
        const dfo_var_info *var = &DFO_VARS[j];
        if (var->home != DFO_IN_ARRAYS && var->home != DFO_IN_INPUTS) continue;
        for (size_t i = 0; i < v->n; i++) *stored(v, var, i) = var->start;
    }
    memcpy(v->ua_used, v->ua, (size_t)DFO_NUM_AI * v->n * sizeof(double));
    for (int j = 0; j < DFO_NUM_AI; j++) v->u_set[j] = v->u_set_used[j] = 0;
}

static void set_start_values(dfo_values *v)
{
    for (int j = 0; j < DFO_NUM_VARS; j++) {
        const dfo_var_info *var = &DFO_VARS[j];
        if (var->home == DFO_IN_PARAMS) v->sp[var->slot] = var->start;
    }
    array_starts(v);
    v->n_config = v->n;
    v->time = v->start_time = v->stop_time = 0.0;
    v->stop_defined = 0;
    v->phase = DFO_PHASE_INSTANTIATED;
    v->event_pending = v->event_from = 0;
    v->event_block = 0;
    v->acc_valid = 0;
}

/* ---- the chain's parameters, inputs, model ---------------------------------------------------- */

static chain_params params_of(const dfo_values *v)
{
    const size_t n = v->n;
    const double *pa = v->pa;
    chain_params p;
    memset(&p, 0, sizeof p);
    p.n = n;
    p.m = pa + (size_t)DFO_AP_m * n;
    p.k = pa + (size_t)DFO_AP_k * n;
    p.c = pa + (size_t)DFO_AP_c * n;
    p.P0 = pa + (size_t)DFO_AP_P0 * n;
    p.phi = pa + (size_t)DFO_AP_phi * n;
    p.N = pa + (size_t)DFO_AP_N * n;
    p.mu_s = pa + (size_t)DFO_AP_mu_s * n;
    p.chi = pa + (size_t)DFO_AP_chi * n;
    p.x0 = pa + (size_t)DFO_AP_x0 * n;
    p.v0 = pa + (size_t)DFO_AP_v0 * n;
    p.k_end = v->sp[DFO_SP_k_end];
    p.c_end = v->sp[DFO_SP_c_end];
    p.omega = v->sp[DFO_SP_omega];
    p.h = v->sp[DFO_SP_h];
    p.alpha = v->sp[DFO_SP_alpha];
    p.scheme = (int)v->sp[DFO_SP_scheme];
    p.account_energy = 0;
    p.h = chain_step_size(&p); /* h = 0: derived from the dynamics */
    return p;
}

/* The internal step of the run (h_used). */
static double step_h(const dfo_values *v)
{
    if (v->M) return chain_step(v->M);
    const chain_params p = params_of(v);
    return p.h;
}

/* The inputs now (used: those of the last step); an input never set is NULL (never read). */
static chain_inputs inputs_of(const dfo_values *v, int used)
{
    const double *u = used ? v->ua_used : v->ua;
    const int *set = used ? v->u_set_used : v->u_set;
    chain_inputs ci;
    ci.F_ext = set[DFO_AI_F_ext] ? u + (size_t)DFO_AI_F_ext * v->n : NULL;
    ci.N_ext = set[DFO_AI_N_ext] ? u + (size_t)DFO_AI_N_ext * v->n : NULL;
    return ci;
}

/* Build the model from the parameters and start the state at start_time (NULL on success, else why). */
static const char *prepare(dfo_instance *in, char *buf, size_t len)
{
    dfo_values *v = &in->v;
    const chain_params p = params_of(v);
    const char *msg = chain_check_params(&p, buf, len);
    if (msg) return msg;
    free_model(v);
    const chain_alloc al = allocator(in);
    const char *err = NULL;
    v->M = chain_create(&p, &al, &err);
    if (!v->M) return err ? err : "out of memory";
    const chain_inputs ci = inputs_of(v, 0);
    chain_start(v->M, &ci, v->start_time, &v->s);
    memcpy(v->ua_used, v->ua, (size_t)DFO_NUM_AI * v->n * sizeof(double));
    memcpy(v->u_set_used, v->u_set, sizeof v->u_set);
    v->time = v->start_time;
    v->acc_valid = 0;
    return NULL;
}

/* ---- life cycle ------------------------------------------------------------------------------ */

dfo_inst_status dfo_inst_init(dfo_instance *in, const dfo_host *host, const char *name, int logging_on)
{
    memset(in, 0, sizeof *in);
    in->host = *host;
    in->name = name;
    dfo_inst_set_logging(in, -1, logging_on);
    in->log_on[DFO_LOG_STATUS_ERROR] = in->log_on[DFO_LOG_STATUS_WARNING] = 1;
    if (!alloc_arrays(in, &in->v, N_START))
        return dfo_inst_fail(in, "instantiate: out of memory for n = %lu blocks.", (unsigned long)N_START);
    set_start_values(&in->v);
    return DFO_INST_OK;
}

void dfo_inst_free(dfo_instance *in)
{
    free_model(&in->v);
    free_arrays(in, &in->v);
}

dfo_inst_status dfo_inst_exit_init(dfo_instance *in, const char *fn)
{
    char buf[200];
    const char *msg = prepare(in, buf, sizeof buf);
    if (msg) return dfo_inst_fail(in, "%s: %s.", fn, msg);
    in->v.phase = DFO_PHASE_STEP;
    dfo_inst_status status = DFO_INST_OK;
    const double h = in->v.sp[DFO_SP_h], T_min = chain_shortest_period(in->v.M);
    if (h > 0.0 && h * DFO_MIN_STEPS_PER_PERIOD > T_min) {
        status = DFO_INST_WARNING;
        dfo_inst_log(in, DFO_INST_WARNING, DFO_LOG_STATUS_WARNING,
                     "%s: h = %.6g s takes only %.3g internal steps per %.6g s, the shortest period of the chain's "
                     "dynamics (its fastest natural frequency, bounded from the springs and masses, the excitation "
                     "period 2 pi/omega, the damping rate): the results do not resolve it. Choose h <= %.6g s (1/%g "
                     "of it), or h = 0 to let the FMU derive it.", fn, h, T_min / h, T_min, T_min / DFO_STEPS_PER_PERIOD,
                     DFO_STEPS_PER_PERIOD);
    }
    dfo_inst_log(in, DFO_INST_OK, DFO_LOG_EVENTS, "start at t = %.17g: %lu blocks.", in->v.s.t,
                 (unsigned long)in->v.n);
    return status;
}

/* Size the arrays for n blocks (start values); DFO_INST_ERROR when out of memory (nothing changed). */
static dfo_inst_status resize(dfo_instance *in, const char *fn, size_t n)
{
    if (n == in->v.n) return DFO_INST_OK;
    dfo_values w = in->v;
    if (!alloc_arrays(in, &w, n))
        return dfo_inst_fail(in, "%s: out of memory for n = %lu blocks; n stays %lu.", fn, (unsigned long)n,
                             (unsigned long)in->v.n);
    free_model(&in->v);
    free_arrays(in, &in->v);
    w.M = NULL;
    w.acc_valid = 0;
    in->v = w;
    return DFO_INST_OK;
}

void dfo_inst_reset(dfo_instance *in)
{
    free_model(&in->v);
    (void)resize(in, "reset", N_START); /* on failure the arrays keep their size */
    set_start_values(&in->v);
    in->warned = 0;
}

dfo_inst_status dfo_inst_enter_config(dfo_instance *in, const char *fn)
{
    (void)fn;
    in->v.n_config = in->v.n;
    in->v.phase = DFO_PHASE_CONFIG;
    return DFO_INST_OK;
}

/* Leaving configuration mode with a new n: every array has n elements at their start values. */
dfo_inst_status dfo_inst_exit_config(dfo_instance *in, const char *fn)
{
    const size_t n = in->v.n_config;
    if (n != in->v.n) {
        if (resize(in, fn, n) != DFO_INST_OK) return DFO_INST_ERROR;
        array_starts(&in->v);
    }
    in->v.n_config = in->v.n;
    in->v.phase = DFO_PHASE_INSTANTIATED;
    return DFO_INST_OK;
}

/* ---- outputs --------------------------------------------------------------------------------- */

/* A pending event's left limit of the switching block b: its mode before the switch, the friction
 * of that mode (kinetic -from mu_k N; stuck, the static force clamped to the breakaway limit), the
 * acceleration with that force. The other blocks are continuous at the switch. */
static void left_limit(const dfo_values *v, const double *a_right, double *F, double *a)
{
    const size_t n = v->n, b = v->event_block;
    const double *pa = v->pa;
    const chain_inputs ci = inputs_of(v, 0);
    const double m = pa[(size_t)DFO_AP_m * n + b];
    const double mu_s = pa[(size_t)DFO_AP_mu_s * n + b], mu_k = pa[(size_t)DFO_AP_chi * n + b] * mu_s;
    const double N = fmax(pa[(size_t)DFO_AP_N * n + b] + (ci.N_ext ? ci.N_ext[b] : 0.0), 0.0);
    const double F_right = v->s.F[b];
    const double S = m * a_right[b] - F_right; /* the net applied force (continuous) */
    if (v->event_from != 0) {
        *F = -(double)v->event_from * mu_k * N;
        *a = (S + *F) / m;
    } else {
        const double Fb = fmax(mu_s, mu_k) * N;
        *F = fmin(fmax(-S, -Fb), Fb);
        *a = 0.0;
    }
}

/* Outputs need the started model: during initialisation (and before), one is built on the fly. */
static int started(const dfo_values *v)
{
    return v->M && (v->phase & (DFO_PHASE_STEP | DFO_PHASE_EVENT | DFO_PHASE_TERMINATED | DFO_PHASE_ERROR));
}

static dfo_inst_status get_outputs(dfo_instance *in, const char *fn, const ref *r, unsigned int vr, double *out,
                                   int *iout)
{
    dfo_values *v = &in->v;
    if (!started(v)) {
        char buf[200];
        const char *msg = prepare(in, buf, sizeof buf);
        if (msg) return dfo_inst_fail(in, "%s: %s cannot be computed: %s.", fn, r->name, msg);
    }
    (void)vr;
    const size_t n = v->n, i0 = r->elem < 0 ? 0 : (size_t)r->elem, i1 = r->elem < 0 ? n : i0 + 1;
    const int id = r->var->slot;
    if (id == DFO_OUT_h_used) {
        *out = chain_step(v->M);
        if (!started(v)) free_model(v);
        return DFO_INST_OK;
    }
    const int need_a = id == DFO_OUT_a || (v->event_pending && id == DFO_OUT_F_friction);
    const int temporary = !started(v);
    if (need_a && (temporary || !v->acc_valid)) {
        const chain_inputs ci = inputs_of(v, 0);
        chain_accelerations(v->M, &ci, &v->s, v->scratch);
        v->acc_valid = !temporary;
    }
    double F_left = 0.0, a_left = 0.0;
    if (v->event_pending && need_a) left_limit(v, v->scratch, &F_left, &a_left);
    for (size_t i = i0; i < i1; i++) {
        const int left = v->event_pending && i == v->event_block;
        double x = 0.0;
        switch (id) {
        case DFO_OUT_x: x = v->s.X[i]; break;
        case DFO_OUT_v: x = v->s.V[i]; break;
        case DFO_OUT_a: x = left ? a_left : v->scratch[i]; break;
        case DFO_OUT_F_friction: x = left ? F_left : v->s.F[i]; break;
        case DFO_OUT_mode: iout[i - i0] = left ? v->event_from : v->s.mode[i]; continue;
        default: break;
        }
        if (!isfinite(x))
            return dfo_inst_fail(in, "%s: %s[%lu] (value reference %u) is not representable in double precision "
                                 "for these parameters (overflow).", fn, r->var->name, (unsigned long)i + 1, vr);
        out[i - i0] = x;
    }
    if (!started(v)) free_model(v);
    return DFO_INST_OK;
}

/* ---- get / set ------------------------------------------------------------------------------- */

/* Real (dout) or integer (iout) values: stored ones, or computed outputs, n values per array. */
static dfo_inst_status get_values(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                  dfo_var_type type, double *dout, int *iout)
{
    size_t k = 0;
    for (size_t j = 0; j < n; j++) {
        ref r;
        if (!lookup(in, fn, vr[j], type, &r)) return DFO_INST_ERROR;
        const size_t c = count(in, &r);
        if (r.var->home == DFO_COMPUTED) {
            if (get_outputs(in, fn, &r, vr[j], dout ? dout + k : NULL, iout ? iout + k : NULL) != DFO_INST_OK)
                return DFO_INST_ERROR;
        } else {
            const size_t i0 = r.elem < 0 ? 0 : (size_t)r.elem;
            for (size_t i = 0; i < c; i++) {
                const double x = *stored(&in->v, r.var, i0 + i);
                if (dout) dout[k + i] = x;
                else iout[k + i] = (int)x;
            }
        }
        k += c;
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_get_real(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n, double value[])
{
    return get_values(in, fn, vr, n, DFO_REAL, value, NULL);
}

dfo_inst_status dfo_inst_get_int(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n, int value[])
{
    return get_values(in, fn, vr, n, DFO_INTEGER, NULL, value);
}

dfo_inst_status dfo_inst_get_bool(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n, int value[])
{
    for (size_t j = 0; j < n; j++) {
        ref r;
        if (!lookup(in, fn, vr[j], DFO_BOOLEAN, &r)) return DFO_INST_ERROR;
        value[j] = *stored(&in->v, r.var, 0) != 0.0;
    }
    return DFO_INST_OK;
}

/* Check every value of every variable (type, causality and phase, range per element), then store:
 * a rejected call changes nothing. */
static dfo_inst_status set_values(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                  const double value[], dfo_var_type type)
{
    size_t k = 0;
    for (size_t j = 0; j < n; j++) {
        ref r;
        if (!lookup(in, fn, vr[j], type, &r) || !settable(in, fn, &r, vr[j])) return DFO_INST_ERROR;
        const size_t c = count(in, &r);
        for (size_t i = 0; i < c; i++) {
            if (c > 1) snprintf(r.name, sizeof r.name, "%s[%lu]", r.var->name, (unsigned long)i + 1);
            if (!check_value(in, fn, &r, vr[j], value[k + i])) return DFO_INST_ERROR;
        }
        k += c;
    }
    k = 0;
    for (size_t j = 0; j < n; j++) {
        ref r;
        (void)resolve(in, vr[j], &r);
        const size_t c = count(in, &r), i0 = r.elem < 0 ? 0 : (size_t)r.elem;
        for (size_t i = 0; i < c; i++) *stored(&in->v, r.var, i0 + i) = value[k + i];
        if (r.var->home == DFO_IN_INPUTS) in->v.u_set[r.var->slot] = 1;
        in->v.acc_valid = 0;
        k += c;
    }
    return DFO_INST_OK;
}

#define SET_CHUNK 64

dfo_inst_status dfo_inst_set_real(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                  const double value[])
{
    return set_values(in, fn, vr, n, value, DFO_REAL);
}

/* Integer values (the scheme; arrays of integers are outputs only) through doubles, in chunks. */
dfo_inst_status dfo_inst_set_int(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                 const int value[])
{
    for (size_t j = 0; j < n; j++) {
        ref r;
        if (!lookup(in, fn, vr[j], DFO_INTEGER, &r) || !settable(in, fn, &r, vr[j])) return DFO_INST_ERROR;
        if (!check_value(in, fn, &r, vr[j], value[j])) return DFO_INST_ERROR;
    }
    for (size_t j = 0; j < n; j++) {
        ref r;
        (void)resolve(in, vr[j], &r);
        *stored(&in->v, r.var, r.elem < 0 ? 0 : (size_t)r.elem) = value[j];
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_set_bool(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                  const int value[])
{
    (void)value;
    for (size_t j = 0; j < n; j++) {
        ref r;
        if (!lookup(in, fn, vr[j], DFO_BOOLEAN, &r)) return DFO_INST_ERROR;
    }
    return DFO_INST_OK; /* the model has no Boolean variables: lookup has failed on any */
}

dfo_inst_status dfo_inst_get_uint64(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                    unsigned long long value[])
{
    for (size_t j = 0; j < n; j++) {
        ref r;
        if (!lookup(in, fn, vr[j], DFO_UINT64, &r)) return DFO_INST_ERROR;
        value[j] = (unsigned long long)(in->v.phase == DFO_PHASE_CONFIG ? in->v.n_config : in->v.n);
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_set_uint64(dfo_instance *in, const char *fn, const unsigned int vr[], size_t n,
                                    const unsigned long long value[])
{
    for (size_t j = 0; j < n; j++) {
        ref r;
        if (!lookup(in, fn, vr[j], DFO_UINT64, &r) || !settable(in, fn, &r, vr[j])) return DFO_INST_ERROR;
        if (value[j] < (unsigned long long)r.var->min || value[j] > (unsigned long long)r.var->max) {
            dfo_inst_fail(in, "%s: invalid value %llu for %s (value reference %u); valid range: %s.", fn, value[j],
                          r.name, vr[j], r.var->range);
            return DFO_INST_ERROR;
        }
    }
    for (size_t j = 0; j < n; j++) in->v.n_config = (size_t)value[j];
    return DFO_INST_OK;
}

/* ---- doStep ---------------------------------------------------------------------------------- */

typedef struct {
    dfo_instance *in;
    int log, count;
    double t;
    size_t block;
    int from, to;
} switch_rec;

static void on_switch(void *ctx, double t, size_t block, double x, int from, int to)
{
    switch_rec *r = (switch_rec *)ctx;
    static const char *const names[3] = {"backward slip", "stick", "forward slip"};
    r->count++;
    r->t = t;
    r->block = block;
    r->from = from;
    r->to = to;
    if (r->log)
        dfo_inst_log(r->in, DFO_INST_OK, DFO_LOG_EVENTS, "t = %.17g: block %lu: %s -> %s at x = %.17g.", t,
                     (unsigned long)block + 1, names[from + 1], names[to + 1], x);
}

static dfo_inst_status step_failed(dfo_instance *in, const char *fn, chain_status st)
{
    dfo_values *v = &in->v;
    const double t_failed = v->s.t;
    chain_state_copy(&v->s, &v->s0);
    v->acc_valid = 0;
    v->phase = DFO_PHASE_ERROR;
    return dfo_inst_fail(in, "%s: step from t = %.17g failed at t = %.17g: %s. The FMU keeps the state at "
                         "t = %.17g; reset it or restore an earlier FMU state.", fn, v->time, t_failed,
                         chain_status_text(st), v->time);
}

/* Inputs set since the last step: the state takes their jump at the step's start (chain_new_inputs). */
static void take_inputs(dfo_values *v)
{
    if (!memcmp(v->u_set, v->u_set_used, sizeof v->u_set) &&
        !memcmp(v->ua, v->ua_used, (size_t)DFO_NUM_AI * v->n * sizeof(double)))
        return;
    const chain_inputs old_in = inputs_of(v, 1), new_in = inputs_of(v, 0);
    chain_new_inputs(v->M, &old_in, &new_in, &v->s);
    v->acc_valid = 0;
}

static void step_done(dfo_values *v, double t)
{
    v->time = t;
    v->acc_valid = 0;
    memcpy(v->ua_used, v->ua, (size_t)DFO_NUM_AI * v->n * sizeof(double));
    memcpy(v->u_set_used, v->u_set, sizeof v->u_set);
}

dfo_inst_status dfo_inst_do_step(dfo_instance *in, const char *fn, double tc, double dt, unsigned int flags,
                                 double *t_reached)
{
    dfo_values *v = &in->v;
    double t_target = 0.0;
    const dfo_inst_status chk = dfo_inst_check_step(in, fn, tc, dt, step_h(v), &t_target);
    if (chk != DFO_INST_OK) return chk;
    chain_state_copy(&v->s0, &v->s);
    take_inputs(v);
    const chain_inputs ci = inputs_of(v, 0);
    switch_rec rec = {in, in->host.log && in->log_on[DFO_LOG_EVENTS], 0, 0.0, 0, 0, 0};
    const int stop = (flags & DFO_STEP_STOP_AT_SWITCH) != 0;
    const chain_status st = chain_advance(v->M, &ci, &v->s, t_target, stop, on_switch, &rec);
    if (st != CHAIN_OK && st != CHAIN_SWITCHED) return step_failed(in, fn, st);
    const double snap = fmax(1e-9 * step_h(v), 8.0 * DBL_EPSILON * fabs(t_target));
    in->switched = rec.count > 0;
    step_done(v, (st == CHAIN_SWITCHED && v->s.t < t_target - snap) ? v->s.t : t_target);
    if (t_reached) *t_reached = v->time;
    return DFO_INST_OK;
}

/* ---- FMI 3.0: stepping with events ----------------------------------------------------------
 * The step runs with the physics' own stop_at_switch: chain_advance returns at every switch (the
 * located scheme at its time, the others at the end of the internal step holding it) with the
 * state complete there, and goes on from it bit for bit as one call would. A switch strictly inside
 * the step is offered to the intermediate update and ends the step early when asked (or always with
 * early return and no callback); one on the communication point is an event there. */
dfo_inst_status dfo_inst_do_step_events(dfo_instance *in, const char *fn, double tc, double dt,
                                        const dfo_event_opts *opt, dfo_step_result *res)
{
    dfo_values *v = &in->v;
    dfo_inst_status done;
    double t_target = 0.0;
    if (dfo_inst_events_begin(in, fn, tc, dt, step_h(v), opt, res, &done, &t_target)) return done;
    chain_state_copy(&v->s0, &v->s);
    take_inputs(v);
    const double t_start = v->time;
    const chain_inputs ci = inputs_of(v, 0);
    const double snap = fmax(1e-9 * step_h(v), 8.0 * DBL_EPSILON * fabs(t_target));
    switch_rec rec = {in, in->host.log && in->log_on[DFO_LOG_EVENTS], 0, 0.0, 0, 0, 0};
    int at_end = 0;
    for (;;) {
        const int before = rec.count;
        const chain_status st = chain_advance(v->M, &ci, &v->s, t_target, 1, on_switch, &rec);
        if (st != CHAIN_OK && st != CHAIN_SWITCHED) {
            v->time = t_start;
            return step_failed(in, fn, st);
        }
        if (st == CHAIN_OK) break;
        if (!(v->s.t < t_target - snap)) { /* a switch on the communication point */
            at_end = rec.count > before;
            if (v->s.t < t_target) continue;
            break;
        }
        int stop = opt->early_return && !opt->intermediate;
        if (opt->intermediate) {
            v->time = v->s.t;
            v->acc_valid = 0;
            stop = opt->intermediate(opt->ctx, v->s.t, opt->early_return) && opt->early_return;
        }
        if (stop) {
            step_done(v, v->s.t);
            v->event_pending = opt->event_mode;
            v->event_from = rec.from;
            v->event_block = rec.block;
            res->early = 1;
            res->event = opt->event_mode;
            res->t_reached = v->time;
            return DFO_INST_OK;
        }
    }
    if (at_end && opt->event_mode) {
        v->event_pending = 1;
        v->event_from = rec.from;
        v->event_block = rec.block;
        res->event = 1;
    }
    step_done(v, t_target);
    if (at_end && opt->intermediate) (void)opt->intermediate(opt->ctx, t_target, 0);
    res->t_reached = t_target;
    return DFO_INST_OK;
}

void dfo_inst_log_event_handled(const dfo_instance *in)
{
    const dfo_values *v = &in->v;
    dfo_inst_log(in, DFO_INST_OK, DFO_LOG_EVENTS, "t = %.17g: event handled, block %lu in mode %d.", v->time,
                 (unsigned long)v->event_block + 1, v->s.mode ? v->s.mode[v->event_block] : 0);
}

/* ---- FMU states: a tagged copy of the values (arrays included, the model excepted: it follows
 * from the parameters and is rebuilt on restore) ---- */

typedef struct {
    uint64_t magic;
    dfo_values v;
} saved_state;

static saved_state *as_state(const void *p)
{
    saved_state *st = (saved_state *)p;
    return (st && st->magic == STATE_MAGIC) ? st : NULL;
}

/* dst := src's values (dst's arrays already of src's n). */
static void copy_values(dfo_values *dst, const dfo_values *src)
{
    dfo_values keep = *dst;
    *dst = *src;
    dst->pa = keep.pa;
    dst->ua = keep.ua;
    dst->ua_used = keep.ua_used;
    dst->scratch = keep.scratch;
    dst->s = keep.s;
    dst->s0 = keep.s0;
    dst->M = keep.M;
    const size_t n = src->n;
    memcpy(dst->pa, src->pa, (size_t)DFO_NUM_AP * n * sizeof(double));
    memcpy(dst->ua, src->ua, (size_t)DFO_NUM_AI * n * sizeof(double));
    memcpy(dst->ua_used, src->ua_used, (size_t)DFO_NUM_AI * n * sizeof(double));
    chain_state_copy(&dst->s, &src->s);
}

static void free_saved(dfo_instance *in, saved_state *st)
{
    st->magic = 0;
    free_arrays(in, &st->v);
    in->host.free(in->host.ctx, st);
}

/* *state := a copy of v (a state of another n is replaced). */
static dfo_inst_status store_state(dfo_instance *in, const char *fn, void **state, const dfo_values *v)
{
    saved_state *st = (saved_state *)*state;
    if (st && st->magic != STATE_MAGIC) return dfo_inst_fail(in, "%s: *FMUstate is not a state of this FMU.", fn);
    if (st && st->v.n != v->n) {
        free_saved(in, st);
        *state = st = NULL;
    }
    if (!st) {
        st = (saved_state *)in->host.alloc(in->host.ctx, 1, sizeof(saved_state));
        if (!st) return dfo_inst_fail(in, "%s: out of memory.", fn);
        if (!alloc_arrays(in, &st->v, v->n)) {
            in->host.free(in->host.ctx, st);
            return dfo_inst_fail(in, "%s: out of memory for a state of %lu blocks.", fn, (unsigned long)v->n);
        }
        st->magic = STATE_MAGIC;
        *state = st;
    }
    copy_values(&st->v, v);
    st->v.M = NULL;
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_get_state(dfo_instance *in, const char *fn, void **state)
{
    return store_state(in, fn, state, &in->v);
}

dfo_inst_status dfo_inst_set_state(dfo_instance *in, const char *fn, const void *state)
{
    const saved_state *st = as_state(state);
    if (!st) return dfo_inst_fail(in, "%s: FMUstate is NULL or not a state of this FMU.", fn);
    if (resize(in, fn, st->v.n) != DFO_INST_OK) return DFO_INST_ERROR;
    free_model(&in->v);
    copy_values(&in->v, &st->v);
    in->v.M = NULL;
    in->v.acc_valid = 0;
    if (in->v.phase & (DFO_PHASE_STEP | DFO_PHASE_EVENT | DFO_PHASE_TERMINATED | DFO_PHASE_ERROR)) {
        /* the model follows from the parameters (the state is kept: it is the saved one) */
        const chain_params p = params_of(&in->v);
        const chain_alloc al = allocator(in);
        const char *err = NULL;
        in->v.M = chain_create(&p, &al, &err);
        if (!in->v.M) {
            in->v.phase = DFO_PHASE_ERROR;
            return dfo_inst_fail(in, "%s: the chain could not be rebuilt: %s.", fn, err ? err : "out of memory");
        }
    }
    return DFO_INST_OK;
}

dfo_inst_status dfo_inst_free_state(dfo_instance *in, const char *fn, void **state)
{
    saved_state *st = (saved_state *)*state;
    if (!st) return DFO_INST_OK;
    if (st->magic != STATE_MAGIC) return dfo_inst_fail(in, "%s: *FMUstate is not a state of this FMU.", fn);
    free_saved(in, st);
    *state = NULL;
    return DFO_INST_OK;
}

/* ---- serialisation: a fixed little-endian layout of fixed-size fields (the same bytes on every
 * platform), after a header of magic, version, size and checksum ---- */

enum { N_SCALARS_D = 3 + DFO_NUM_SP, N_SCALARS_I = 5 + 2 * DFO_NUM_AI };

static size_t body_size(size_t n)
{
    const size_t doubles = N_SCALARS_D + (size_t)DFO_NUM_AP * n + 2 * (size_t)DFO_NUM_AI * n /* params, inputs */
                           + 7 + 6 * n;                                                       /* state */
    const size_t int64s = 3 + 6; /* n, n_config, event_block; the state's counters */
    const size_t int32s = N_SCALARS_I + n;
    return 8 * doubles + 8 * int64s + 4 * int32s;
}

size_t dfo_inst_serialized_size(void) { return HEADER_BYTES + body_size(START_n); }

size_t dfo_inst_state_size(const dfo_instance *in, const void *state)
{
    (void)in;
    const saved_state *st = as_state(state);
    return st ? HEADER_BYTES + body_size(st->v.n) : 0;
}

typedef struct {
    unsigned char *p;
    const unsigned char *q;
} cursor;

static void put_u64(cursor *c, uint64_t x)
{
    for (int b = 0; b < 8; b++) *c->p++ = (unsigned char)(x >> (8 * b));
}
static void put_u32(cursor *c, uint32_t x)
{
    for (int b = 0; b < 4; b++) *c->p++ = (unsigned char)(x >> (8 * b));
}
static void put_f64(cursor *c, double x)
{
    uint64_t u;
    memcpy(&u, &x, 8);
    put_u64(c, u);
}
static void put_i32(cursor *c, int x) { put_u32(c, (uint32_t)x); }
static void put_f64s(cursor *c, const double *x, size_t n)
{
    for (size_t i = 0; i < n; i++) put_f64(c, x[i]);
}
static uint64_t get_u64(cursor *c)
{
    uint64_t x = 0;
    for (int b = 0; b < 8; b++) x |= (uint64_t)*c->q++ << (8 * b);
    return x;
}
static uint32_t get_u32(cursor *c)
{
    uint32_t x = 0;
    for (int b = 0; b < 4; b++) x |= (uint32_t)*c->q++ << (8 * b);
    return x;
}
static double get_f64(cursor *c)
{
    const uint64_t u = get_u64(c);
    double x;
    memcpy(&x, &u, 8);
    return x;
}
static int get_i32(cursor *c) { return (int)(int32_t)get_u32(c); }
static void get_f64s(cursor *c, double *x, size_t n)
{
    for (size_t i = 0; i < n; i++) x[i] = get_f64(c);
}

static void write_body(cursor *c, const dfo_values *v)
{
    const size_t n = v->n;
    put_u64(c, n);
    put_u64(c, v->n_config);
    put_f64(c, v->time);
    put_f64(c, v->start_time);
    put_f64(c, v->stop_time);
    put_f64s(c, v->sp, DFO_NUM_SP);
    put_i32(c, v->stop_defined);
    put_i32(c, v->phase);
    put_i32(c, v->event_pending);
    put_i32(c, v->event_from);
    put_i32(c, 0); /* reserved */
    for (int j = 0; j < DFO_NUM_AI; j++) put_i32(c, v->u_set[j]);
    for (int j = 0; j < DFO_NUM_AI; j++) put_i32(c, v->u_set_used[j]);
    put_u64(c, v->event_block);
    put_f64s(c, v->pa, (size_t)DFO_NUM_AP * n);
    put_f64s(c, v->ua, (size_t)DFO_NUM_AI * n);
    put_f64s(c, v->ua_used, (size_t)DFO_NUM_AI * n);
    const chain_state *s = &v->s;
    put_f64(c, s->t0);
    put_f64(c, s->t);
    put_u64(c, (uint64_t)s->n_grid);
    put_f64(c, s->W_applied);
    put_f64(c, s->W_friction);
    put_f64(c, s->D_damping);
    put_u64(c, (uint64_t)s->steps);
    put_u64(c, (uint64_t)s->pivot_steps);
    put_u64(c, (uint64_t)s->switches);
    put_u64(c, (uint64_t)s->solves);
    put_u64(c, (uint64_t)s->exc_n);
    put_f64(c, s->exc_c);
    put_f64(c, s->exc_s);
    put_f64s(c, s->X, n);
    put_f64s(c, s->V, n);
    put_f64s(c, s->A, n);
    put_f64s(c, s->F, n);
    put_f64s(c, s->hA, n);
    put_f64s(c, s->t_stick, n);
    for (size_t i = 0; i < n; i++) put_i32(c, s->mode[i]);
}

/* v's arrays allocated for n (read first by the caller). */
static void read_body(cursor *c, dfo_values *v)
{
    const size_t n = v->n;
    (void)get_u64(c);
    v->n_config = (size_t)get_u64(c);
    v->time = get_f64(c);
    v->start_time = get_f64(c);
    v->stop_time = get_f64(c);
    get_f64s(c, v->sp, DFO_NUM_SP);
    v->stop_defined = get_i32(c);
    v->phase = get_i32(c);
    v->event_pending = get_i32(c);
    v->event_from = get_i32(c);
    (void)get_i32(c);
    for (int j = 0; j < DFO_NUM_AI; j++) v->u_set[j] = get_i32(c);
    for (int j = 0; j < DFO_NUM_AI; j++) v->u_set_used[j] = get_i32(c);
    v->event_block = (size_t)get_u64(c);
    get_f64s(c, v->pa, (size_t)DFO_NUM_AP * n);
    get_f64s(c, v->ua, (size_t)DFO_NUM_AI * n);
    get_f64s(c, v->ua_used, (size_t)DFO_NUM_AI * n);
    chain_state *s = &v->s;
    s->n = n;
    s->t0 = get_f64(c);
    s->t = get_f64(c);
    s->n_grid = (long long)get_u64(c);
    s->W_applied = get_f64(c);
    s->W_friction = get_f64(c);
    s->D_damping = get_f64(c);
    s->steps = (long long)get_u64(c);
    s->pivot_steps = (long long)get_u64(c);
    s->switches = (long long)get_u64(c);
    s->solves = (long long)get_u64(c);
    s->exc_n = (long long)get_u64(c);
    s->exc_c = get_f64(c);
    s->exc_s = get_f64(c);
    get_f64s(c, s->X, n);
    get_f64s(c, s->V, n);
    get_f64s(c, s->A, n);
    get_f64s(c, s->F, n);
    get_f64s(c, s->hA, n);
    get_f64s(c, s->t_stick, n);
    for (size_t i = 0; i < n; i++) s->mode[i] = get_i32(c);
}

dfo_inst_status dfo_inst_serialize(dfo_instance *in, const char *fn, const void *state, unsigned char *buf,
                                   size_t size)
{
    const saved_state *st = as_state(state);
    if (!st) return dfo_inst_fail(in, "%s: FMUstate is NULL or not a state of this FMU.", fn);
    const size_t body = body_size(st->v.n);
    if (size < HEADER_BYTES + body)
        return dfo_inst_fail(in, "%s: buffer of %lu bytes is too small (%lu needed).", fn, (unsigned long)size,
                             (unsigned long)(HEADER_BYTES + body));
    cursor c = {buf + HEADER_BYTES, NULL};
    write_body(&c, &st->v);
    cursor h = {buf, NULL};
    memcpy(h.p, SERIAL_MAGIC, 8);
    h.p += 8;
    put_u32(&h, SERIAL_VERSION);
    put_u32(&h, (uint32_t)body);
    put_u64(&h, dfo_inst_checksum(buf + HEADER_BYTES, body));
    return DFO_INST_OK;
}

/* A deserialised state must describe a simulation this FMU could have reached. */
static const char *implausible(const dfo_values *v)
{
    const size_t n = v->n;
    for (int j = 0; j < DFO_NUM_VARS; j++) {
        const dfo_var_info *var = &DFO_VARS[j];
        if (var->home != DFO_IN_PARAMS && var->home != DFO_IN_ARRAYS && var->home != DFO_IN_INPUTS) continue;
        const size_t c = var->array ? n : 1;
        for (size_t i = 0; i < c; i++) {
            dfo_values *w = (dfo_values *)v;
            if (dfo_inst_invalid(var, *stored(w, var, i))) return "a parameter or input is out of range";
            if (var->home == DFO_IN_INPUTS && !isfinite(v->ua_used[(size_t)var->slot * n + i]))
                return "an input is not finite";
        }
    }
    if (v->n_config < 1 || v->n_config > MAX_n) return "the configured n is out of range";
    const int ph = v->phase;
    if (ph != DFO_PHASE_INSTANTIATED && ph != DFO_PHASE_INIT && ph != DFO_PHASE_STEP && ph != DFO_PHASE_TERMINATED &&
        ph != DFO_PHASE_ERROR && ph != DFO_PHASE_EVENT && ph != DFO_PHASE_CONFIG)
        return "the life-cycle phase is invalid";
    if ((v->event_pending != 0 && v->event_pending != 1) || v->event_from < -1 || v->event_from > 1 ||
        v->event_block >= n)
        return "the pending event is invalid";
    for (int j = 0; j < DFO_NUM_AI; j++)
        if ((v->u_set[j] != 0 && v->u_set[j] != 1) || (v->u_set_used[j] != 0 && v->u_set_used[j] != 1))
            return "an input flag is invalid";
    if (v->stop_defined != 0 && v->stop_defined != 1) return "the stop time flag is invalid";
    if (!isfinite(v->start_time) || !isfinite(v->stop_time) || !isfinite(v->time))
        return "the experiment's times are not finite";
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
    if (ph & (DFO_PHASE_STEP | DFO_PHASE_TERMINATED | DFO_PHASE_ERROR | DFO_PHASE_EVENT)) {
        const double h = step_h(v), slack = 1e-6 * h + 8.0 * DBL_EPSILON * fabs(s->t);
        if (s->t < s->t0 || s->t0 + (double)s->n_grid * h > s->t + slack ||
            s->t0 + (double)(s->n_grid + 1) * h < s->t - slack)
            return "the time does not match the internal grid";
        if (fabs(v->time - s->t) > fmax(1e-9 * h, 8.0 * DBL_EPSILON * fabs(v->time)) + slack)
            return "the host's time does not match the state's";
    }
    return NULL;
}

dfo_inst_status dfo_inst_deserialize(dfo_instance *in, const char *fn, const unsigned char *buf, size_t size,
                                     void **state)
{
    if (size < HEADER_BYTES + 8)
        return dfo_inst_fail(in, "%s: %lu bytes are too few for a state of this FMU.", fn, (unsigned long)size);
    cursor h = {NULL, buf + 8};
    const uint32_t version = get_u32(&h), body = get_u32(&h);
    const uint64_t checksum = get_u64(&h);
    if (memcmp(buf, SERIAL_MAGIC, 8) != 0 || version != SERIAL_VERSION)
        return dfo_inst_fail(in, "%s: not a serialised state of this FMU version.", fn);
    cursor c = {NULL, buf + HEADER_BYTES};
    const uint64_t n = get_u64(&c);
    if (n < 1 || n > MAX_n || (size_t)body != body_size((size_t)n) || size != HEADER_BYTES + (size_t)body)
        return dfo_inst_fail(in, "%s: %lu bytes given, not the size of a state of this FMU.", fn,
                             (unsigned long)size);
    if (dfo_inst_checksum(buf + HEADER_BYTES, body) != checksum)
        return dfo_inst_fail(in, "%s: checksum mismatch, the serialised state is corrupted.", fn);
    dfo_values v;
    memset(&v, 0, sizeof v);
    if (!alloc_arrays(in, &v, (size_t)n)) return dfo_inst_fail(in, "%s: out of memory.", fn);
    c.q = buf + HEADER_BYTES;
    read_body(&c, &v);
    const char *why = implausible(&v);
    dfo_inst_status st = DFO_INST_OK;
    if (why) st = dfo_inst_fail(in, "%s: rejected, %s.", fn, why);
    else st = store_state(in, fn, state, &v);
    free_arrays(in, &v);
    return st;
}
