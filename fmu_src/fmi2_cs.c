/* FMI 2.0 co-simulation plumbing for the dry-friction oscillator: instance life cycle, the state
 * machine, get/set of variables, doStep, FMU state and its serialisation, logging.
 * The physics lives in oscillator.c, newmark.c and lcp.c; this file knows nothing of it beyond
 * their interfaces. Variable names and value references come from model_vars.h, generated from
 * modelDescription.xml at build time. */
#include "fmi2Functions.h"
#include "model_vars.h"
#include "newmark.h"
#include "oscillator.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* ---- instance -------------------------------------------------------------------------------- */

typedef enum {
    ST_INSTANTIATED = 1 << 0,
    ST_INIT = 1 << 1,
    ST_STEP = 1 << 2,
    ST_TERMINATED = 1 << 3,
    ST_ERROR = 1 << 4
} fmu_phase;

enum { LOG_ERROR, LOG_WARNING, LOG_EVENTS, LOG_ALL }; /* order of <LogCategories> */

/* Everything that defines where a simulation is: plain values, no pointers, so that FMU states
 * are copies and serialisation is the bytes. */
typedef struct {
    dfo_params p;
    dfo_inputs u;
    dfo_model M;
    dfo_state s;
    double start_time, stop_time;
    int stop_defined;
    int effects;
    fmu_phase phase;
} values_t;

typedef struct {
    values_t v;
    fmi2CallbackFunctions cb;
    char *name;
    int log_on[DFO_NUM_LOG_CATEGORIES];
} Instance;

#define MAX_STEPS_PER_CALL 1e9 /* internal steps one fmi2DoStep may take */
#define STATE_MAGIC 0x444650534d555354ULL /* "DFPSMUST" */
#define SERIAL_MAGIC "DFOSTATE"
#define SERIAL_VERSION 1u

typedef struct {
    uint64_t magic;
    values_t v;
} saved_state;

typedef struct {
    char magic[8];
    uint32_t version, size;
    uint64_t checksum;
} serial_header;

/* ---- logging --------------------------------------------------------------------------------- */

static void log_msg(const Instance *in, fmi2Status status, int category, const char *fmt, ...)
{
    if (!in->cb.logger || !in->log_on[category]) return;
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    for (char *c = buf; *c; c++)
        if (*c == '%') *c = ' '; /* the message reaches printf-style loggers as a format */
    in->cb.logger(in->cb.componentEnvironment, in->name, status, DFO_LOG_CATEGORIES[category], buf);
}

#define LOG_CALL(in, fn) log_msg((in), fmi2OK, LOG_ALL, "%s", fn)

static fmi2Status fail(Instance *in, const char *fmt, ...)
{
    if (!in->cb.logger || !in->log_on[LOG_ERROR]) return fmi2Error;
    char buf[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    log_msg(in, fmi2Error, LOG_ERROR, "%s", buf);
    return fmi2Error;
}

static const char *phase_name(fmu_phase p)
{
    switch (p) {
    case ST_INSTANTIATED: return "instantiated";
    case ST_INIT: return "initialization mode";
    case ST_STEP: return "step mode";
    case ST_TERMINATED: return "terminated";
    case ST_ERROR: return "error";
    }
    return "unknown";
}

/* The instance is usable (non-NULL) and in one of the allowed phases. */
static int allowed(Instance *in, const char *fn, int phases)
{
    if (!in) return 0;
    LOG_CALL(in, fn);
    if (in->v.phase & phases) return 1;
    fail(in, "%s must not be called in %s.", fn, phase_name(in->v.phase));
    return 0;
}

#define ANY_PHASE (ST_INSTANTIATED | ST_INIT | ST_STEP | ST_TERMINATED | ST_ERROR)
#define CHECK(fn, phases)                          \
    Instance *in = (Instance *)c;                  \
    if (!allowed(in, fn, phases)) return fmi2Error

static const dfo_var_info *find_var(unsigned int vr)
{
    for (int i = 0; i < DFO_NUM_VARS; i++)
        if (DFO_VARS[i].vr == vr) return &DFO_VARS[i];
    return NULL;
}

static const char *type_name(dfo_var_type t)
{
    return t == DFO_REAL ? "Real" : t == DFO_INTEGER ? "Integer" : "Boolean";
}

static const dfo_var_info *lookup(Instance *in, const char *fn, fmi2ValueReference vr, dfo_var_type type)
{
    const dfo_var_info *var = find_var(vr);
    if (!var) {
        fail(in, "%s: unknown value reference %u.", fn, vr);
        return NULL;
    }
    if (var->type != type) {
        fail(in, "%s: variable %s (value reference %u) is of type %s, not %s.", fn, var->name, vr,
             type_name(var->type), type_name(type));
        return NULL;
    }
    return var;
}

/* ---- start values, preparation --------------------------------------------------------------- */

static void set_start_values(values_t *v)
{
    const values_t zero = {0};
    *v = zero;
    dfo_params *p = &v->p;
    p->m = START_m;
    p->k = START_k;
    p->c = START_c;
    p->P0 = START_P0;
    p->omega = START_omega;
    p->phi = START_phi;
    p->N = START_N;
    p->mu_s = START_mu_s;
    p->chi = START_chi;
    p->x0 = START_x0;
    p->v0 = START_v0;
    p->h = START_h;
    p->alpha = START_alpha;
    p->t_obs_start = START_t_obs_start;
    p->t_obs_stop = START_t_obs_stop;
    p->scheme = START_scheme;
    p->frictionUpdates = START_frictionUpdates;
    p->observe = START_observe;
    p->fastPaths = START_fastPaths;
    v->u.F_ext = START_F_ext;
    v->u.N_ext = START_N_ext;
    v->phase = ST_INSTANTIATED;
}

/* Derive the model from the parameters and start it (exit of initialisation, or outputs asked
 * for during initialisation). */
static void prepare(values_t *v)
{
    dfo_model_init(&v->M, &v->p);
    dfo_start(&v->M, &v->u, v->start_time, &v->s);
    v->effects = dfo_effects(&v->M, &v->u);
}

/* ---- variables ------------------------------------------------------------------------------- */

static double *real_slot(values_t *v, fmi2ValueReference vr)
{
    dfo_params *p = &v->p;
    switch (vr) {
    case VR_m: return &p->m;
    case VR_k: return &p->k;
    case VR_c: return &p->c;
    case VR_P0: return &p->P0;
    case VR_omega: return &p->omega;
    case VR_phi: return &p->phi;
    case VR_N: return &p->N;
    case VR_mu_s: return &p->mu_s;
    case VR_chi: return &p->chi;
    case VR_x0: return &p->x0;
    case VR_v0: return &p->v0;
    case VR_h: return &p->h;
    case VR_alpha: return &p->alpha;
    case VR_t_obs_start: return &p->t_obs_start;
    case VR_t_obs_stop: return &p->t_obs_stop;
    case VR_F_ext: return &v->u.F_ext;
    case VR_N_ext: return &v->u.N_ext;
    default: return NULL;
    }
}

static int *int_slot(values_t *v, fmi2ValueReference vr)
{
    switch (vr) {
    case VR_scheme: return &v->p.scheme;
    case VR_frictionUpdates: return &v->p.frictionUpdates;
    case VR_observe: return &v->p.observe;
    case VR_fastPaths: return &v->p.fastPaths;
    default: return NULL;
    }
}

static double output_real(const values_t *v, fmi2ValueReference vr)
{
    const dfo_state *s = &v->s;
    const int seen = v->p.observe && s->observed;
    switch (vr) {
    case VR_x: return s->X;
    case VR_v: return s->V;
    case VR_a: return dfo_acceleration(&v->M, &v->u, s);
    case VR_F_friction: return s->F;
    case VR_x_max: return seen ? s->x_max : 0.0;
    case VR_x_min: return seen ? s->x_min : 0.0;
    case VR_stick_fraction: return v->p.observe ? dfo_stick_fraction(&v->M, s) : 0.0;
    case VR_E_friction: return v->p.observe ? s->E_friction : 0.0;
    default: return 0.0;
    }
}

static int output_int(const values_t *v, fmi2ValueReference vr)
{
    switch (vr) {
    case VR_mode: return v->s.mode;
    case VR_transitions: return v->p.observe ? (int)v->s.transitions : 0;
    case VR_effects: return v->effects;
    default: return 0;
    }
}

/* Values of calculated variables need the started model; during initialisation it is derived
 * from the current parameters on the fly. */
static const values_t *computed(const Instance *in, values_t *tmp)
{
    if (in->v.phase != ST_INIT) return &in->v;
    *tmp = in->v;
    prepare(tmp);
    return tmp;
}

/* Whether a variable of this causality may be set now; logs the reason when not. */
static int settable(Instance *in, const char *fn, const dfo_var_info *var)
{
    const fmu_phase ph = in->v.phase;
    if (var->causality == DFO_PARAMETER && (ph & (ST_INSTANTIATED | ST_INIT))) return 1;
    if (var->causality == DFO_INPUT && (ph & (ST_INSTANTIATED | ST_INIT | ST_STEP))) return 1;
    if (var->causality == DFO_PARAMETER)
        fail(in, "%s: variable %s (value reference %u) is a fixed parameter and cannot be set in %s.", fn,
             var->name, var->vr, phase_name(ph));
    else if (var->causality == DFO_INPUT)
        fail(in, "%s: input %s (value reference %u) cannot be set in %s.", fn, var->name, var->vr,
             phase_name(ph));
    else
        fail(in, "%s: variable %s (value reference %u) is %s and cannot be set.", fn, var->name, var->vr,
             var->causality == DFO_OUTPUT ? "an output" : "a calculated parameter");
    return 0;
}

static int check_value(Instance *in, const char *fn, const dfo_var_info *var, double value)
{
    const char *range = dfo_value_range(var->name, value);
    if (!range) return 1;
    fail(in, "%s: invalid value %.17g for variable %s (value reference %u); valid range: %s.", fn, value,
         var->name, var->vr, range);
    return 0;
}

/* ---- FMI functions --------------------------------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn)
{
    (void)fmuResourceLocation;
    (void)visible;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    Instance tmp;
    memset(&tmp, 0, sizeof tmp);
    tmp.cb = *functions;
    tmp.name = (char *)(instanceName ? instanceName : "?");
    tmp.log_on[LOG_ERROR] = tmp.log_on[LOG_WARNING] = 1;
    if (!instanceName || !*instanceName) {
        fail(&tmp, "fmi2Instantiate: the instance name must be a non-empty string.");
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        fail(&tmp, "fmi2Instantiate: this FMU supports co-simulation only (fmuType %d requested).", (int)fmuType);
        return NULL;
    }
    if (!fmuGUID || strcmp(fmuGUID, MODEL_GUID) != 0) {
        fail(&tmp, "fmi2Instantiate: GUID %s does not match the FMU's GUID %s.", fmuGUID ? fmuGUID : "(null)",
             MODEL_GUID);
        return NULL;
    }
    Instance *in = (Instance *)functions->allocateMemory(1, sizeof(Instance));
    if (!in) return NULL;
    const size_t len = strlen(instanceName) + 1;
    in->name = (char *)functions->allocateMemory(len, 1);
    if (!in->name) {
        functions->freeMemory(in);
        return NULL;
    }
    memcpy(in->name, instanceName, len);
    in->cb = *functions;
    for (int i = 0; i < DFO_NUM_LOG_CATEGORIES; i++) in->log_on[i] = loggingOn ? 1 : 0;
    in->log_on[LOG_ERROR] = in->log_on[LOG_WARNING] = 1; /* problems are always reported */
    set_start_values(&in->v);
    LOG_CALL(in, "fmi2Instantiate");
    return in;
}

void fmi2FreeInstance(fmi2Component c)
{
    Instance *in = (Instance *)c;
    if (!in) return;
    LOG_CALL(in, "fmi2FreeInstance");
    fmi2CallbackFreeMemory freeMemory = in->cb.freeMemory;
    freeMemory(in->name);
    freeMemory(in);
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    CHECK("fmi2SetDebugLogging", ANY_PHASE);
    if (nCategories > 0 && !categories) return fail(in, "fmi2SetDebugLogging: categories is NULL.");
    for (size_t i = 0; i < nCategories; i++) {
        int found = -1;
        for (int j = 0; j < DFO_NUM_LOG_CATEGORIES; j++)
            if (categories[i] && !strcmp(categories[i], DFO_LOG_CATEGORIES[j])) found = j;
        if (found < 0)
            return fail(in, "fmi2SetDebugLogging: unknown log category %s.", categories[i] ? categories[i] : "(null)");
    }
    if (nCategories == 0) {
        for (int j = 0; j < DFO_NUM_LOG_CATEGORIES; j++) in->log_on[j] = loggingOn ? 1 : 0;
    } else {
        for (size_t i = 0; i < nCategories; i++)
            for (int j = 0; j < DFO_NUM_LOG_CATEGORIES; j++)
                if (!strcmp(categories[i], DFO_LOG_CATEGORIES[j])) in->log_on[j] = loggingOn ? 1 : 0;
    }
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    CHECK("fmi2SetupExperiment", ST_INSTANTIATED);
    (void)toleranceDefined;
    (void)tolerance;
    if (!isfinite(startTime)) return fail(in, "fmi2SetupExperiment: startTime %g is not finite.", startTime);
    if (stopTimeDefined && !(stopTime >= startTime))
        return fail(in, "fmi2SetupExperiment: stopTime %.17g must be finite and >= startTime %.17g.", stopTime,
                    startTime);
    in->v.start_time = startTime;
    in->v.stop_defined = stopTimeDefined ? 1 : 0;
    in->v.stop_time = stopTimeDefined ? stopTime : 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    CHECK("fmi2EnterInitializationMode", ST_INSTANTIATED);
    in->v.phase = ST_INIT;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    CHECK("fmi2ExitInitializationMode", ST_INIT);
    const char *msg = dfo_check_params(&in->v.p);
    if (msg) return fail(in, "fmi2ExitInitializationMode: %s", msg);
    prepare(&in->v);
    const dfo_state *s = &in->v.s;
    if (!isfinite(s->A) || !isfinite(s->F) || !isfinite(dfo_acceleration(&in->v.M, &in->v.u, s)))
        return fail(in, "fmi2ExitInitializationMode: the initial acceleration is not representable (x0 = %.17g, "
                    "v0 = %.17g, m = %.17g): the parameters are out of the range of double precision.",
                    in->v.p.x0, in->v.p.v0, in->v.p.m);
    in->v.phase = ST_STEP;
    log_msg(in, fmi2OK, LOG_EVENTS, "start at t = %.17g: x = %.17g, v = %.17g, mode %d, effects %d.",
            in->v.s.t, in->v.s.X, in->v.s.V, in->v.s.mode, in->v.effects);
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    CHECK("fmi2Terminate", ST_STEP | ST_ERROR);
    in->v.phase = ST_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    CHECK("fmi2Reset", ANY_PHASE);
    set_start_values(&in->v);
    return fmi2OK;
}

#define GET_PHASES (ST_INIT | ST_STEP | ST_TERMINATED | ST_ERROR)

static int check_arrays(Instance *in, const char *fn, const fmi2ValueReference vr[], size_t nvr, const void *value)
{
    if (nvr > 0 && (!vr || !value)) {
        fail(in, "%s: the value reference or value array is NULL.", fn);
        return 0;
    }
    return 1;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    CHECK("fmi2GetReal", GET_PHASES);
    if (!check_arrays(in, "fmi2GetReal", vr, nvr, value)) return fmi2Error;
    values_t tmp;
    const values_t *v = NULL;
    for (size_t i = 0; i < nvr; i++) {
        const dfo_var_info *var = lookup(in, "fmi2GetReal", vr[i], DFO_REAL);
        if (!var) return fmi2Error;
        const double *slot = real_slot(&in->v, vr[i]);
        if (slot) {
            value[i] = *slot;
        } else {
            if (!v) v = computed(in, &tmp);
            value[i] = output_real(v, vr[i]);
            if (!isfinite(value[i]))
                return fail(in, "fmi2GetReal: variable %s (value reference %u) is not representable in double "
                            "precision for these parameters (overflow).", var->name, vr[i]);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
{
    CHECK("fmi2GetInteger", GET_PHASES);
    if (!check_arrays(in, "fmi2GetInteger", vr, nvr, value)) return fmi2Error;
    values_t tmp;
    const values_t *v = NULL;
    for (size_t i = 0; i < nvr; i++) {
        if (!lookup(in, "fmi2GetInteger", vr[i], DFO_INTEGER)) return fmi2Error;
        const int *slot = int_slot(&in->v, vr[i]);
        if (slot) {
            value[i] = *slot;
        } else {
            if (!v) v = computed(in, &tmp);
            value[i] = output_int(v, vr[i]);
        }
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[])
{
    CHECK("fmi2GetBoolean", GET_PHASES);
    if (!check_arrays(in, "fmi2GetBoolean", vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        if (!lookup(in, "fmi2GetBoolean", vr[i], DFO_BOOLEAN)) return fmi2Error;
        value[i] = *int_slot(&in->v, vr[i]) ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{
    CHECK("fmi2GetString", GET_PHASES);
    (void)value;
    if (nvr == 0) return fmi2OK;
    return fail(in, "fmi2GetString: the FMU has no String variables (value reference %u).", vr ? vr[0] : 0u);
}

#define SET_PHASES (ST_INSTANTIATED | ST_INIT | ST_STEP)

/* All values are checked before any is stored: a rejected call changes nothing. */
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[])
{
    CHECK("fmi2SetReal", SET_PHASES);
    if (!check_arrays(in, "fmi2SetReal", vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        const dfo_var_info *var = lookup(in, "fmi2SetReal", vr[i], DFO_REAL);
        if (!var || !settable(in, "fmi2SetReal", var) || !check_value(in, "fmi2SetReal", var, value[i]))
            return fmi2Error;
    }
    for (size_t i = 0; i < nvr; i++) {
        *real_slot(&in->v, vr[i]) = value[i];
        if (vr[i] == VR_F_ext) in->v.u.F_ext_set = 1;
        if (vr[i] == VR_N_ext) in->v.u.N_ext_set = 1;
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[])
{
    CHECK("fmi2SetInteger", SET_PHASES);
    if (!check_arrays(in, "fmi2SetInteger", vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        const dfo_var_info *var = lookup(in, "fmi2SetInteger", vr[i], DFO_INTEGER);
        if (!var || !settable(in, "fmi2SetInteger", var) || !check_value(in, "fmi2SetInteger", var, value[i]))
            return fmi2Error;
    }
    for (size_t i = 0; i < nvr; i++) *int_slot(&in->v, vr[i]) = value[i];
    return fmi2OK;
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[])
{
    CHECK("fmi2SetBoolean", SET_PHASES);
    if (!check_arrays(in, "fmi2SetBoolean", vr, nvr, value)) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        const dfo_var_info *var = lookup(in, "fmi2SetBoolean", vr[i], DFO_BOOLEAN);
        if (!var || !settable(in, "fmi2SetBoolean", var)) return fmi2Error;
    }
    for (size_t i = 0; i < nvr; i++) *int_slot(&in->v, vr[i]) = value[i] ? 1 : 0;
    return fmi2OK;
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{
    CHECK("fmi2SetString", SET_PHASES);
    (void)value;
    if (nvr == 0) return fmi2OK;
    return fail(in, "fmi2SetString: the FMU has no String variables (value reference %u).", vr ? vr[0] : 0u);
}

/* ---- co-simulation --------------------------------------------------------------------------- */

static void report_switch(void *ctx, double t, double x, int from, int to)
{
    const Instance *in = (const Instance *)ctx;
    static const char *const names[3] = {"backward slip", "stick", "forward slip"};
    log_msg(in, fmi2OK, LOG_EVENTS, "t = %.17g: %s -> %s at x = %.17g.", t, names[from + 1], names[to + 1], x);
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    CHECK("fmi2DoStep", ST_STEP);
    (void)noSetFMUStatePriorToCurrentPoint;
    values_t *v = &in->v;
    const double t = v->s.t, tc = currentCommunicationPoint, dt = communicationStepSize;
    if (!isfinite(tc))
        return fail(in, "fmi2DoStep: currentCommunicationPoint %.17g must be finite (the FMU's time is %.17g).", tc, t);
    if (!isfinite(dt) || !(dt > 0.0))
        return fail(in, "fmi2DoStep: communicationStepSize %.17g must be finite and > 0 (at t = %.17g).", dt, tc);
    const double tol = 1e3 * DBL_EPSILON * fmax(1.0, fabs(t)) + 1e-9 * v->p.h;
    if (fabs(tc - t) > tol)
        return fail(in, "fmi2DoStep: currentCommunicationPoint %.17g does not equal the FMU's time %.17g.", tc, t);
    const double t_target = tc + dt;
    if (!(t_target > t))
        return fail(in, "fmi2DoStep: communicationStepSize %.17g is below the time resolution at t = %.17g.", dt, t);
    if (v->stop_defined && t_target > v->stop_time + tol)
        return fail(in, "fmi2DoStep: the step would end at %.17g, after the stop time %.17g.", t_target,
                    v->stop_time);
    if ((t_target - t) / v->p.h > MAX_STEPS_PER_CALL)
        return fail(in, "fmi2DoStep: a communication step of %.17g s would take more than %.0e internal steps of "
                    "h = %.17g s; use a larger h or shorter communication steps.", dt, MAX_STEPS_PER_CALL, v->p.h);
    const int events = in->cb.logger && in->log_on[LOG_EVENTS];
    const dfo_state before = v->s;
    const dfo_status st = dfo_advance(&v->M, &v->u, &v->s, t_target, events ? report_switch : NULL, in);
    if (st != DFO_OK) {
        const dfo_state failed = v->s;
        v->s = before; /* the outputs stay those of the last good state */
        v->phase = ST_ERROR;
        return fail(in, "fmi2DoStep: step from t = %.17g failed at t = %.17g: %s (x = %.17g, v = %.17g). The FMU "
                    "keeps the state at t = %.17g; reset it or restore an earlier FMU state.", t, failed.t,
                    dfo_status_text(st), failed.X, failed.V, t);
    }
    return fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    CHECK("fmi2CancelStep", ST_STEP);
    return fail(in, "fmi2CancelStep: steps are synchronous and cannot be cancelled.");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    CHECK("fmi2SetRealInputDerivatives", ANY_PHASE);
    (void)vr; (void)nvr; (void)order; (void)value;
    return fail(in, "fmi2SetRealInputDerivatives: input derivatives are not supported (canInterpolateInputs=false).");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    CHECK("fmi2GetRealOutputDerivatives", ANY_PHASE);
    (void)vr; (void)nvr; (void)order; (void)value;
    return fail(in, "fmi2GetRealOutputDerivatives: output derivatives are not supported (maxOutputDerivativeOrder=0).");
}

static fmi2Status no_status(fmi2Component c, const char *fn)
{
    CHECK(fn, ANY_PHASE);
    return fail(in, "%s: steps are synchronous; there is no asynchronous status to report.", fn);
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s; (void)value;
    return no_status(c, "fmi2GetStatus");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    Instance *in = (Instance *)c;
    if (in && s == fmi2LastSuccessfulTime && value) {
        if (!allowed(in, "fmi2GetRealStatus", ANY_PHASE)) return fmi2Error;
        *value = in->v.s.t;
        return fmi2OK;
    }
    return no_status(c, "fmi2GetRealStatus");
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s; (void)value;
    return no_status(c, "fmi2GetIntegerStatus");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    (void)s; (void)value;
    return no_status(c, "fmi2GetBooleanStatus");
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s; (void)value;
    return no_status(c, "fmi2GetStringStatus");
}

/* ---- FMU state ------------------------------------------------------------------------------- */

#define STATE_PHASES (ST_INIT | ST_STEP | ST_TERMINATED | ST_ERROR)

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    CHECK("fmi2GetFMUstate", STATE_PHASES);
    if (!FMUstate) return fail(in, "fmi2GetFMUstate: FMUstate is NULL.");
    saved_state *st = (saved_state *)*FMUstate;
    if (st && st->magic != STATE_MAGIC) return fail(in, "fmi2GetFMUstate: *FMUstate is not a state of this FMU.");
    if (!st) {
        st = (saved_state *)in->cb.allocateMemory(1, sizeof(saved_state));
        if (!st) return fail(in, "fmi2GetFMUstate: out of memory.");
        st->magic = STATE_MAGIC;
        *FMUstate = st;
    }
    st->v = in->v;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    CHECK("fmi2SetFMUstate", STATE_PHASES | ST_INSTANTIATED);
    const saved_state *st = (const saved_state *)FMUstate;
    if (!st || st->magic != STATE_MAGIC) return fail(in, "fmi2SetFMUstate: FMUstate is NULL or not a state of this FMU.");
    in->v = st->v;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    CHECK("fmi2FreeFMUstate", ANY_PHASE);
    if (!FMUstate) return fail(in, "fmi2FreeFMUstate: FMUstate is NULL.");
    saved_state *st = (saved_state *)*FMUstate;
    if (!st) return fmi2OK;
    if (st->magic != STATE_MAGIC) return fail(in, "fmi2FreeFMUstate: *FMUstate is not a state of this FMU.");
    st->magic = 0;
    in->cb.freeMemory(st);
    *FMUstate = NULL;
    return fmi2OK;
}

static uint64_t fnv1a(const unsigned char *p, size_t n)
{
    uint64_t h = 1469598103934665603ULL;
    for (size_t i = 0; i < n; i++) {
        h ^= p[i];
        h *= 1099511628211ULL;
    }
    return h;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    CHECK("fmi2SerializedFMUstateSize", ANY_PHASE);
    (void)FMUstate;
    if (!size) return fail(in, "fmi2SerializedFMUstateSize: size is NULL.");
    *size = sizeof(serial_header) + sizeof(values_t);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size)
{
    CHECK("fmi2SerializeFMUstate", ANY_PHASE);
    const saved_state *st = (const saved_state *)FMUstate;
    if (!st || st->magic != STATE_MAGIC) return fail(in, "fmi2SerializeFMUstate: FMUstate is NULL or not a state of this FMU.");
    if (!serializedState) return fail(in, "fmi2SerializeFMUstate: serializedState is NULL.");
    if (size < sizeof(serial_header) + sizeof(values_t))
        return fail(in, "fmi2SerializeFMUstate: buffer of %lu bytes is too small (%lu needed).", (unsigned long)size,
                    (unsigned long)(sizeof(serial_header) + sizeof(values_t)));
    serial_header hdr;
    memcpy(hdr.magic, SERIAL_MAGIC, 8);
    hdr.version = SERIAL_VERSION;
    hdr.size = (uint32_t)sizeof(values_t);
    hdr.checksum = fnv1a((const unsigned char *)&st->v, sizeof(values_t));
    memcpy(serializedState, &hdr, sizeof hdr);
    memcpy(serializedState + sizeof hdr, &st->v, sizeof(values_t));
    return fmi2OK;
}

/* A deserialised state must describe a simulation this FMU could have reached. */
static const char *implausible(const values_t *v)
{
    static const char *const names[] = {"m", "k", "c", "P0", "omega", "phi", "N", "mu_s", "chi", "x0", "v0", "h",
                                        "alpha", "t_obs_start", "t_obs_stop"};
    const double *vals[] = {&v->p.m, &v->p.k, &v->p.c, &v->p.P0, &v->p.omega, &v->p.phi, &v->p.N, &v->p.mu_s,
                            &v->p.chi, &v->p.x0, &v->p.v0, &v->p.h, &v->p.alpha, &v->p.t_obs_start,
                            &v->p.t_obs_stop};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (dfo_value_range(names[i], *vals[i])) return "a parameter is out of range";
    if (dfo_value_range("scheme", v->p.scheme) || dfo_value_range("frictionUpdates", v->p.frictionUpdates))
        return "an integer parameter is out of range";
    if (v->phase != ST_INSTANTIATED && v->phase != ST_INIT && v->phase != ST_STEP && v->phase != ST_TERMINATED &&
        v->phase != ST_ERROR)
        return "the life-cycle phase is invalid";
    if (dfo_check_params(&v->p)) return "the observation window is empty";
    if (!isfinite(v->u.F_ext) || !isfinite(v->u.N_ext) || !isfinite(v->start_time) || !isfinite(v->stop_time))
        return "an input or the experiment's times are not finite";
    const dfo_state *s = &v->s;
    if (!isfinite(s->t) || !isfinite(s->t0) || !isfinite(s->X) || !isfinite(s->V) || !isfinite(s->A) ||
        !isfinite(s->F) || !isfinite(s->hA) || s->n < 0)
        return "the state is not finite";
    if (s->mode < -1 || s->mode > 1) return "the mode is invalid";
    /* the time lies on the internal grid's interval n: t0 + n h <= t < t0 + (n + 1) h */
    const double h = v->p.h, slack = 1e-6 * h + 8.0 * DBL_EPSILON * fabs(s->t);
    if (s->t < s->t0 || s->t0 + (double)s->n * h > s->t + slack || s->t0 + (double)(s->n + 1) * h < s->t - slack)
        return "the time does not match the internal grid";
    return NULL;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    CHECK("fmi2DeSerializeFMUstate", ANY_PHASE);
    if (!serializedState || !FMUstate) return fail(in, "fmi2DeSerializeFMUstate: serializedState or FMUstate is NULL.");
    serial_header hdr;
    if (size != sizeof hdr + sizeof(values_t))
        return fail(in, "fmi2DeSerializeFMUstate: %lu bytes given, a state of this FMU has %lu.", (unsigned long)size,
                    (unsigned long)(sizeof hdr + sizeof(values_t)));
    memcpy(&hdr, serializedState, sizeof hdr);
    if (memcmp(hdr.magic, SERIAL_MAGIC, 8) != 0 || hdr.version != SERIAL_VERSION || hdr.size != sizeof(values_t))
        return fail(in, "fmi2DeSerializeFMUstate: not a serialised state of this FMU version.");
    values_t v;
    memcpy(&v, serializedState + sizeof hdr, sizeof v);
    if (fnv1a((const unsigned char *)&v, sizeof v) != hdr.checksum)
        return fail(in, "fmi2DeSerializeFMUstate: checksum mismatch, the serialised state is corrupted.");
    const char *why = implausible(&v);
    if (why) return fail(in, "fmi2DeSerializeFMUstate: rejected, %s.", why);
    dfo_model_init(&v.M, &v.p); /* derived constants follow from the parameters, never trusted */
    dfo_check_caches(&v.M, &v.s); /* and caches that do not follow from the state are dropped */
    fmi2FMUstate st = *FMUstate;
    if (st && ((saved_state *)st)->magic != STATE_MAGIC)
        return fail(in, "fmi2DeSerializeFMUstate: *FMUstate is not a state of this FMU.");
    if (!st) {
        st = in->cb.allocateMemory(1, sizeof(saved_state));
        if (!st) return fail(in, "fmi2DeSerializeFMUstate: out of memory.");
        ((saved_state *)st)->magic = STATE_MAGIC;
        *FMUstate = st;
    }
    ((saved_state *)st)->v = v;
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[])
{
    CHECK("fmi2GetDirectionalDerivative", ANY_PHASE);
    (void)vUnknown_ref; (void)nUnknown; (void)vKnown_ref; (void)nKnown; (void)dvKnown; (void)dvUnknown;
    return fail(in, "fmi2GetDirectionalDerivative: directional derivatives are not provided.");
}

/* ---- model-exchange functions: exported (hosts resolve every symbol), always an error --------- */

static fmi2Status not_me(fmi2Component c, const char *fn)
{
    CHECK(fn, ANY_PHASE);
    return fail(in, "%s: this FMU is for co-simulation only.", fn);
}

fmi2Status fmi2EnterEventMode(fmi2Component c) { return not_me(c, "fmi2EnterEventMode"); }
fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info)
{
    (void)info;
    return not_me(c, "fmi2NewDiscreteStates");
}
fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) { return not_me(c, "fmi2EnterContinuousTimeMode"); }
fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint; (void)enterEventMode; (void)terminateSimulation;
    return not_me(c, "fmi2CompletedIntegratorStep");
}
fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    (void)time;
    return not_me(c, "fmi2SetTime");
}
fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    (void)x; (void)nx;
    return not_me(c, "fmi2SetContinuousStates");
}
fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx)
{
    (void)derivatives; (void)nx;
    return not_me(c, "fmi2GetDerivatives");
}
fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni)
{
    (void)eventIndicators; (void)ni;
    return not_me(c, "fmi2GetEventIndicators");
}
fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    (void)x; (void)nx;
    return not_me(c, "fmi2GetContinuousStates");
}
fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx)
{
    (void)x_nominal; (void)nx;
    return not_me(c, "fmi2GetNominalsOfContinuousStates");
}
