/* Misuse of the FMI 2.0 API in C, linked against the FMU's shared library:
 *
 * 1. fmi2Instantiate rejections (NULL callbacks, wrong GUID, type, name);
 * 2. a NULL instance given to every function: fmi2Error, no crash;
 * 3. NULL arrays and buffers;
 * 4. wrong call order, currentCommunicationPoint off, zero / negative / NaN steps;
 * 5. every invalid parameter value (NaN, inf, out of range) refused with a sentence naming it;
 * 6. unknown value references and wrong types;
 * 7. FMU state get/set round trip: bit-exact continuation;
 * 8. serialisation round trip; every truncation and every single-byte corruption rejected;
 * 9. overflow reported as an error (never NaN outputs), reset recovers;
 * 10. values a run has not computed (observables while observe is false, x_max and x_min before the
 *     window's first sample): NaN (transitions -1) with fmi2OK and one logNotComputed sentence per run;
 * 11. direct feedthrough: a and F_friction follow an input set after a step, without a step;
 * 12. 10^4 instantiate/free cycles: allocations through the callbacks balance (ASan's leak
 *     checker covers the rest in the sanitizer build).
 *
 * Each failed call must return fmi2Error or fmi2Discard with a logged sentence, and the instance
 * must keep working. */
#include "harness.h"

#include <math.h>

#define N_OUT 8

static const fmi2ValueReference OUT_VR[N_OUT] = {VR_x, VR_v, VR_a, VR_F_friction, VR_x_max, VR_x_min,
                                                 VR_stick_fraction, VR_E_friction};

/* A call that must fail with a logged sentence containing `part`. */
static void expect_fail(tally *T, log_sink *sink, fmi2Status st, const char *part, const char *what)
{
    if (!expect_(T, st == fmi2Error || st == fmi2Discard, __FILE__, __LINE__, what)) return;
    if (!expect_(T, sink->last[0] != '\0', __FILE__, __LINE__, what)) return;
    if (part && !strstr(sink->last, part)) {
        char buf[1400];
        snprintf(buf, sizeof buf, "%s: message \"%s\" lacks \"%s\"", what, sink->last, part);
        expect_(T, 0, __FILE__, __LINE__, buf);
    }
    sink->last[0] = '\0';
}

#define FAILS(call, part) expect_fail(T, &sink, (call), (part), #call)

static void test_instantiate(tally *T)
{
    log_sink sink = {{0}, 0, 0};
    fmi2CallbackFunctions cb = callbacks_for(&sink);
    EXPECT(fmi2Instantiate("a", fmi2CoSimulation, MODEL_GUID, "", NULL, 0, 0) == NULL);
    fmi2CallbackFunctions no_alloc = cb;
    no_alloc.allocateMemory = NULL;
    EXPECT(fmi2Instantiate("a", fmi2CoSimulation, MODEL_GUID, "", &no_alloc, 0, 0) == NULL);
    EXPECT(fmi2Instantiate("a", fmi2CoSimulation, "{nope}", "", &cb, 0, 0) == NULL);
    EXPECT(strstr(sink.last, "GUID") != NULL);
    EXPECT(fmi2Instantiate("a", fmi2CoSimulation, NULL, "", &cb, 0, 0) == NULL);
    /* Model Exchange too (tests/test_model_exchange.py); a type that is neither is refused */
    fmi2Component me = fmi2Instantiate("a", fmi2ModelExchange, MODEL_GUID, "", &cb, 0, 0);
    EXPECT(me != NULL);
    fmi2FreeInstance(me);
    EXPECT(fmi2Instantiate("a", (fmi2Type)7, MODEL_GUID, "", &cb, 0, 0) == NULL);
    EXPECT(strstr(sink.last, "neither fmi2ModelExchange") != NULL);
    EXPECT(fmi2Instantiate("", fmi2CoSimulation, MODEL_GUID, "", &cb, 0, 0) == NULL);
    EXPECT(fmi2Instantiate(NULL, fmi2CoSimulation, MODEL_GUID, NULL, &cb, 0, 0) == NULL);
    fmi2CallbackFunctions no_logger = cb;
    no_logger.logger = NULL;
    fmi2Component c = new_instance("quiet", &no_logger);
    EXPECT(c != NULL);
    EXPECT(fmi2DoStep(c, 0.0, 1.0, fmi2True) == fmi2Error); /* no logger: still an error, no crash */
    fmi2FreeInstance(c);
    EXPECT(mem_outstanding() == 0);
    EXPECT(strcmp(fmi2GetVersion(), "2.0") == 0 && strcmp(fmi2GetTypesPlatform(), "default") == 0);
}

static void test_null_instance(tally *T)
{
    fmi2Real r = 0;
    fmi2Integer i = 0;
    fmi2Boolean b = 0;
    fmi2String s = NULL;
    fmi2Status st = fmi2OK;
    fmi2FMUstate fs = NULL;
    size_t sz = 0;
    fmi2Byte buf[16];
    const fmi2ValueReference vr = VR_x;
    const fmi2Integer order = 1;
    EXPECT(fmi2SetDebugLogging(NULL, 1, 0, NULL) == fmi2Error);
    EXPECT(fmi2SetupExperiment(NULL, 0, 0, 0, 0, 0) == fmi2Error);
    EXPECT(fmi2EnterInitializationMode(NULL) == fmi2Error);
    EXPECT(fmi2ExitInitializationMode(NULL) == fmi2Error);
    EXPECT(fmi2Terminate(NULL) == fmi2Error);
    EXPECT(fmi2Reset(NULL) == fmi2Error);
    EXPECT(fmi2GetReal(NULL, &vr, 1, &r) == fmi2Error);
    EXPECT(fmi2GetInteger(NULL, &vr, 1, &i) == fmi2Error);
    EXPECT(fmi2GetBoolean(NULL, &vr, 1, &b) == fmi2Error);
    EXPECT(fmi2GetString(NULL, &vr, 1, &s) == fmi2Error);
    EXPECT(fmi2SetReal(NULL, &vr, 1, &r) == fmi2Error);
    EXPECT(fmi2SetInteger(NULL, &vr, 1, &i) == fmi2Error);
    EXPECT(fmi2SetBoolean(NULL, &vr, 1, &b) == fmi2Error);
    EXPECT(fmi2SetString(NULL, &vr, 1, &s) == fmi2Error);
    EXPECT(fmi2DoStep(NULL, 0, 1, 1) == fmi2Error);
    EXPECT(fmi2CancelStep(NULL) == fmi2Error);
    EXPECT(fmi2GetStatus(NULL, fmi2DoStepStatus, &st) == fmi2Error);
    EXPECT(fmi2GetRealStatus(NULL, fmi2LastSuccessfulTime, &r) == fmi2Error);
    EXPECT(fmi2GetIntegerStatus(NULL, fmi2DoStepStatus, &i) == fmi2Error);
    EXPECT(fmi2GetBooleanStatus(NULL, fmi2Terminated, &b) == fmi2Error);
    EXPECT(fmi2GetStringStatus(NULL, fmi2PendingStatus, &s) == fmi2Error);
    EXPECT(fmi2GetFMUstate(NULL, &fs) == fmi2Error && fs == NULL);
    EXPECT(fmi2SetFMUstate(NULL, fs) == fmi2Error);
    EXPECT(fmi2FreeFMUstate(NULL, &fs) == fmi2Error);
    EXPECT(fmi2SerializedFMUstateSize(NULL, fs, &sz) == fmi2Error);
    EXPECT(fmi2SerializeFMUstate(NULL, fs, buf, sizeof buf) == fmi2Error);
    EXPECT(fmi2DeSerializeFMUstate(NULL, buf, sizeof buf, &fs) == fmi2Error);
    EXPECT(fmi2SetRealInputDerivatives(NULL, &vr, 1, &order, &r) == fmi2Error);
    EXPECT(fmi2GetRealOutputDerivatives(NULL, &vr, 1, &order, &r) == fmi2Error);
    EXPECT(fmi2GetDirectionalDerivative(NULL, &vr, 1, &vr, 1, &r, &r) == fmi2Error);
    EXPECT(fmi2EnterEventMode(NULL) == fmi2Error);
    EXPECT(fmi2SetTime(NULL, 0.0) == fmi2Error);
    fmi2FreeInstance(NULL);
}

static void test_null_arrays(tally *T)
{
    log_sink sink = {{0}, 0, 0};
    fmi2CallbackFunctions cb = callbacks_for(&sink);
    fmi2Component c = new_instance("nulls", &cb);
    EXPECT(start_run(c, 1e-3, 0, NULL, NULL) == fmi2OK);
    const fmi2ValueReference vr = VR_x;
    fmi2Real r;
    fmi2Integer i;
    fmi2Boolean b;
    fmi2FMUstate fs = NULL;
    FAILS(fmi2GetReal(c, NULL, 1, &r), "NULL");
    FAILS(fmi2GetReal(c, &vr, 1, NULL), "NULL");
    FAILS(fmi2SetReal(c, NULL, 1, &r), "NULL");
    FAILS(fmi2GetInteger(c, &vr, 1, NULL), "NULL");
    FAILS(fmi2SetInteger(c, NULL, 1, &i), "NULL");
    FAILS(fmi2GetBoolean(c, NULL, 1, &b), "NULL");
    FAILS(fmi2SetBoolean(c, &vr, 1, NULL), "NULL");
    EXPECT(fmi2GetReal(c, NULL, 0, NULL) == fmi2OK);
    FAILS(fmi2GetFMUstate(c, NULL), "NULL");
    FAILS(fmi2SetFMUstate(c, NULL), "NULL");
    FAILS(fmi2FreeFMUstate(c, NULL), "NULL");
    EXPECT(fmi2FreeFMUstate(c, &fs) == fmi2OK); /* freeing a NULL state is a no-op */
    FAILS(fmi2SerializedFMUstateSize(c, NULL, NULL), "NULL");
    FAILS(fmi2SerializeFMUstate(c, NULL, NULL, 0), "NULL");
    FAILS(fmi2DeSerializeFMUstate(c, NULL, 10, &fs), "NULL");
    FAILS(fmi2SetDebugLogging(c, 1, 3, NULL), "NULL");
    FAILS(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, NULL), NULL);
    EXPECT(fmi2DoStep(c, 0.0, 0.01, fmi2True) == fmi2OK);
    fmi2FreeInstance(c);
}

static void test_call_order(tally *T)
{
    log_sink sink = {{0}, 0, 0};
    fmi2CallbackFunctions cb = callbacks_for(&sink);
    fmi2Component c = new_instance("order", &cb);
    const fmi2ValueReference vx = VR_x, vm = VR_m, vF = VR_F_ext;
    fmi2Real r = 2.0;
    FAILS(fmi2DoStep(c, 0.0, 0.1, fmi2True), "must not be called in instantiated");
    FAILS(fmi2ExitInitializationMode(c), "must not be called");
    FAILS(fmi2GetReal(c, &vx, 1, &r), "must not be called");
    FAILS(fmi2Terminate(c), "must not be called");
    EXPECT(fmi2SetupExperiment(c, 0, 0, 0.0, 0, 0) == fmi2OK);
    EXPECT(fmi2EnterInitializationMode(c) == fmi2OK);
    FAILS(fmi2EnterInitializationMode(c), "initialization mode");
    FAILS(fmi2SetupExperiment(c, 0, 0, 0.0, 0, 0), "initialization mode");
    FAILS(fmi2DoStep(c, 0.0, 0.1, fmi2True), "initialization mode");
    EXPECT(fmi2ExitInitializationMode(c) == fmi2OK);
    FAILS(fmi2SetReal(c, &vm, 1, &r), "fixed parameter");
    FAILS(fmi2DoStep(c, 0.5, 0.1, fmi2True), "currentCommunicationPoint");
    FAILS(fmi2DoStep(c, 0.0, 0.0, fmi2True), "communicationStepSize 0");
    FAILS(fmi2DoStep(c, 0.0, -1.0, fmi2True), "communicationStepSize -1");
    FAILS(fmi2DoStep(c, 0.0, NAN, fmi2True), "communicationStepSize nan");
    FAILS(fmi2DoStep(c, 0.0, INFINITY, fmi2True), "communicationStepSize inf");
    r = 0.3;
    EXPECT(fmi2SetReal(c, &vF, 1, &r) == fmi2OK);
    EXPECT(fmi2DoStep(c, 0.0, 0.1, fmi2True) == fmi2OK);
    EXPECT(fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &r) == fmi2OK && r == 0.1);
    EXPECT(fmi2Terminate(c) == fmi2OK);
    FAILS(fmi2DoStep(c, 0.1, 0.1, fmi2True), "terminated");
    EXPECT(fmi2Reset(c) == fmi2OK);
    EXPECT(start_run(c, 1e-3, 0, NULL, NULL) == fmi2OK);
    EXPECT(fmi2DoStep(c, 0.0, 0.1, fmi2True) == fmi2OK);
    fmi2FreeInstance(c);
}

static void test_bad_values(tally *T)
{
    log_sink sink = {{0}, 0, 0};
    fmi2CallbackFunctions cb = callbacks_for(&sink);
    fmi2Component c = new_instance("values", &cb);
    const double specials[] = {NAN, INFINITY, -INFINITY};
    char part[128];
    /* every Real parameter and input: non-finite values */
    for (int k = 0; k < DFO_NUM_VARS; k++) {
        const dfo_var_info *v = &DFO_VARS[k];
        if (v->type != DFO_REAL || (v->causality != DFO_PARAMETER && v->causality != DFO_INPUT)) continue;
        for (int j = 0; j < 3; j++) {
            snprintf(part, sizeof part, "for variable %s (value reference %u); valid range: finite", v->name, v->vr);
            FAILS(fmi2SetReal(c, &v->vr, 1, &specials[j]), part);
        }
    }
    /* ranges */
    static const struct { fmi2ValueReference vr; double value; const char *text; } bad[] = {
        {VR_m, 0.0, "invalid value 0 for variable m (value reference 1); valid range: in [1e-100, 1e+100]"},
        {VR_m, -2.0, "invalid value -2 for variable m"},
        {VR_k, -1.0, "valid range: in [0, 1e+100]"},
        {VR_c, -1e-9, "invalid value -1.0000000000000001e-09 for variable c"},
        {VR_N, -1.0, "variable N "},
        {VR_mu_s, -0.5, "variable mu_s "},
        {VR_chi, -0.5, "variable chi "},
        {VR_h, -1e-3, "variable h (value reference 12); valid range: 0 (derived from the dynamics) or > 0"},
        {VR_h, 1e-310, "variable h (value reference 12); valid range: 0 (derived from the dynamics) or > 0 (a normal"},
        {VR_alpha, -0.4, "valid range: in [-1/3, 0]"},
        {VR_alpha, 1e-300, "valid range: in [-1/3, 0]"},
        {VR_omega, -5.0, "variable omega "},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) FAILS(fmi2SetReal(c, &bad[k].vr, 1, &bad[k].value), bad[k].text);
    const fmi2ValueReference vs = VR_scheme, vf = VR_frictionUpdates;
    const fmi2Integer bad_scheme[] = {0, 5, -1}, bad_updates[] = {-1, 101, 2147483647};
    for (int k = 0; k < 3; k++) {
        FAILS(fmi2SetInteger(c, &vs, 1, &bad_scheme[k]), "valid range: one of 1 (paper), 2 (consistent), 3 (located), 4 (exact)");
        FAILS(fmi2SetInteger(c, &vf, 1, &bad_updates[k]), "valid range: in [0, 100]");
    }
    /* unknown references, wrong types */
    const fmi2ValueReference unknown[] = {0, 22, 29, 41, 1000, 0xFFFFFFFFu};
    fmi2Real r = 1.0;
    fmi2Integer i = 1;
    for (size_t k = 0; k < sizeof unknown / sizeof unknown[0]; k++) {
        snprintf(part, sizeof part, "unknown value reference %u.", unknown[k]);
        FAILS(fmi2SetReal(c, &unknown[k], 1, &r), part);
        FAILS(fmi2SetInteger(c, &unknown[k], 1, &i), part);
    }
    const fmi2ValueReference vm = VR_m;
    FAILS(fmi2SetInteger(c, &vm, 1, &i), "is of type Real, not Integer");
    FAILS(fmi2SetBoolean(c, &vs, 1, &i), "is of type Integer, not Boolean");
    /* still usable: valid values, then a run */
    const fmi2ValueReference vr2[2] = {VR_m, VR_alpha};
    const double ok2[2] = {2.0, -1.0 / 3.0};
    EXPECT(start_run(c, 1e-3, 2, vr2, ok2) == fmi2OK);
    EXPECT(fmi2DoStep(c, 0.0, 0.5, fmi2True) == fmi2OK);
    /* the observation window is checked at initialisation */
    EXPECT(fmi2Reset(c) == fmi2OK);
    const fmi2ValueReference vw[2] = {VR_t_obs_start, VR_t_obs_stop};
    const double w[2] = {2.0, 1.0};
    EXPECT(fmi2SetupExperiment(c, 0, 0, 0.0, 0, 0) == fmi2OK);
    EXPECT(fmi2SetReal(c, vw, 2, w) == fmi2OK);
    EXPECT(fmi2EnterInitializationMode(c) == fmi2OK);
    FAILS(fmi2ExitInitializationMode(c), "t_obs_stop must be >= t_obs_start");
    fmi2FreeInstance(c);
}

static void outputs(fmi2Component c, double *out)
{
    fmi2GetReal(c, OUT_VR, N_OUT, out);
}

/* Run n steps of dt from t0, filling out[n][N_OUT]. */
static fmi2Status run_steps(fmi2Component c, double t0, int n, double dt, double *out)
{
    for (int j = 0; j < n; j++) {
        const fmi2Status st = fmi2DoStep(c, t0 + j * dt, dt, fmi2True);
        if (st != fmi2OK) return st;
        outputs(c, out + (size_t)j * N_OUT);
    }
    return fmi2OK;
}

static void start_observed(fmi2Component c)
{
    const fmi2ValueReference vr[2] = {VR_x0, VR_chi};
    const double val[2] = {0.004, 0.5};
    const fmi2ValueReference vo = VR_observe;
    const fmi2Boolean on = fmi2True;
    fmi2SetupExperiment(c, 0, 0, 0.0, 0, 0);
    fmi2SetBoolean(c, &vo, 1, &on);
    fmi2SetReal(c, vr, 2, val);
    const fmi2ValueReference vh = VR_h;
    const double h = 7e-4;
    fmi2SetReal(c, &vh, 1, &h);
    fmi2EnterInitializationMode(c);
    fmi2ExitInitializationMode(c);
}

static void test_states(tally *T)
{
    log_sink sink = {{0}, 0, 0};
    fmi2CallbackFunctions cb = callbacks_for(&sink);
    fmi2Component c = new_instance("states", &cb), d = new_instance("other", &cb);
    static double a[300 * N_OUT], b[300 * N_OUT];
    start_observed(c);
    EXPECT(run_steps(c, 0.0, 37, 0.0123, a) == fmi2OK);
    const double t1 = 37 * 0.0123;
    fmi2FMUstate s = NULL;
    EXPECT(fmi2GetFMUstate(c, &s) == fmi2OK && s != NULL);
    EXPECT(run_steps(c, t1, 300, 0.01, a) == fmi2OK);
    EXPECT(fmi2SetFMUstate(c, s) == fmi2OK);
    EXPECT(run_steps(c, t1, 300, 0.01, b) == fmi2OK);
    EXPECT(memcmp(a, b, sizeof a) == 0); /* bit-exact continuation */

    /* serialise, deserialise into another instance that was only instantiated */
    size_t n = 0;
    EXPECT(fmi2SerializedFMUstateSize(c, s, &n) == fmi2OK && n > 24);
    fmi2Byte *ser = (fmi2Byte *)malloc(n), *bad = (fmi2Byte *)malloc(n + 1);
    EXPECT(fmi2SerializeFMUstate(c, s, ser, n) == fmi2OK);
    FAILS(fmi2SerializeFMUstate(c, s, bad, n - 1), "too small");
    fmi2FMUstate s2 = NULL;
    EXPECT(fmi2DeSerializeFMUstate(d, ser, n, &s2) == fmi2OK && s2 != NULL);
    EXPECT(fmi2SetFMUstate(d, s2) == fmi2OK);
    memset(b, 0, sizeof b);
    EXPECT(run_steps(d, t1, 300, 0.01, b) == fmi2OK);
    EXPECT(memcmp(a, b, sizeof a) == 0);
    EXPECT(fmi2SerializeFMUstate(d, s2, bad, n) == fmi2OK && memcmp(bad, ser, n) == 0);

    /* every truncation, one extra byte, every single-byte corruption: rejected, s2 untouched */
    int accepted = 0;
    for (size_t k = 0; k < n; k++) accepted += fmi2DeSerializeFMUstate(d, ser, k, &s2) != fmi2Error;
    EXPECT(fmi2DeSerializeFMUstate(d, ser, n + 1, &s2) == fmi2Error);
    for (size_t k = 0; k < n; k++) {
        for (int flip = 1; flip < 256; flip <<= 1) {
            memcpy(bad, ser, n);
            bad[k] = (fmi2Byte)(bad[k] ^ flip);
            accepted += fmi2DeSerializeFMUstate(d, bad, n, &s2) != fmi2Error;
        }
    }
    EXPECT(accepted == 0);
    EXPECT(strstr(sink.last, "checksum") != NULL || strstr(sink.last, "not a serialised state") != NULL);
    EXPECT(fmi2SetFMUstate(d, s2) == fmi2OK); /* the state is still the good one */
    EXPECT(run_steps(d, t1, 300, 0.01, b) == fmi2OK && memcmp(a, b, sizeof a) == 0);

    /* foreign pointers are refused, not freed */
    unsigned char junk[1024];
    memset(junk, 0x5a, sizeof junk);
    FAILS(fmi2SetFMUstate(c, (fmi2FMUstate)junk), "not a state of this FMU");
    fmi2FMUstate jp = (fmi2FMUstate)junk;
    FAILS(fmi2FreeFMUstate(c, &jp), "not a state of this FMU");
    FAILS(fmi2SerializeFMUstate(c, (fmi2FMUstate)junk, ser, n), "not a state of this FMU");

    EXPECT(fmi2FreeFMUstate(c, &s) == fmi2OK && s == NULL);
    EXPECT(fmi2FreeFMUstate(d, &s2) == fmi2OK && s2 == NULL);
    free(ser);
    free(bad);
    fmi2FreeInstance(c);
    fmi2FreeInstance(d);
}

static void test_overflow(tally *T)
{
    log_sink sink = {{0}, 0, 0};
    fmi2CallbackFunctions cb = callbacks_for(&sink);
    fmi2Component c = new_instance("overflow", &cb);
    const fmi2ValueReference vr[4] = {VR_P0, VR_N, VR_omega, VR_k};
    const double val[4] = {1e307, 0.0, 0.0, 1e-100};
    EXPECT(start_run(c, 1e-3, 4, vr, val) == fmi2OK);
    FAILS(fmi2DoStep(c, 0.0, 1e6, fmi2True), "non-finite");
    double out[N_OUT];
    /* readable after the failed step (for diagnosis): finite values, fmi2OK (observe is on by default) */
    EXPECT(fmi2GetReal(c, OUT_VR, N_OUT, out) == fmi2OK);
    for (int k = 0; k < N_OUT; k++) EXPECT(isfinite(out[k]));
    FAILS(fmi2DoStep(c, 0.0, 0.1, fmi2True), "must not be called in error");
    EXPECT(fmi2Reset(c) == fmi2OK);
    EXPECT(start_run(c, 1e-3, 0, NULL, NULL) == fmi2OK);
    EXPECT(fmi2DoStep(c, 0.0, 0.1, fmi2True) == fmi2OK);
    /* the default start values (observe true): every output OK and computed */
    EXPECT(fmi2GetReal(c, OUT_VR, N_OUT, out) == fmi2OK && isfinite(out[0]) && out[0] != 0.0);
    for (int k = 0; k < N_OUT; k++) EXPECT(isfinite(out[k]));
    fmi2FreeInstance(c);
}

/* A logger that counts warnings and notes (logNotComputed) and keeps the last message with its
 * category and status. */
typedef struct {
    int n_warnings, n_notes;
    char last[1024], category[64];
    fmi2Status status;
} warn_sink;

static void warn_logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                        fmi2String message, ...)
{
    (void)name;
    warn_sink *w = (warn_sink *)env;
    if (status == fmi2Warning) w->n_warnings++;
    else if (!strcmp(category, "logNotComputed")) w->n_notes++;
    else return;
    w->status = status;
    snprintf(w->last, sizeof w->last, "%s", message);
    snprintf(w->category, sizeof w->category, "%s", category);
}

/* Values a run has not computed read NaN (the Integer transitions -1) with fmi2OK, never a number
 * that looks like a result and never a warning status: the observables while observe is false, and
 * x_max / x_min before the observation window's first sample. One sentence per run (logNotComputed,
 * status OK) says which and why; with observe = true (the default) and the window open, fmi2OK and
 * the real values, no note. */
static void test_not_computed_outputs(tally *T)
{
    static const fmi2ValueReference obs_real[4] = {VR_x_max, VR_x_min, VR_stick_fraction, VR_E_friction};
    const fmi2ValueReference vtr = VR_transitions, vo = VR_observe;
    const fmi2ValueReference vw[4] = {VR_t_obs_start, VR_t_obs_stop, VR_x0, VR_chi};
    const double w[4] = {1.0, 3.0, 0.004, 0.5};
    for (int observe = 0; observe <= 1; observe++) {
        warn_sink sink;
        memset(&sink, 0, sizeof sink);
        fmi2CallbackFunctions cb = callbacks_for(NULL);
        cb.logger = warn_logger;
        cb.componentEnvironment = &sink;
        fmi2Component c = new_instance("not_computed", &cb); /* logging off: the notes come all the same */
        const fmi2Boolean on = observe ? fmi2True : fmi2False;
        EXPECT(fmi2SetBoolean(c, &vo, 1, &on) == fmi2OK);
        EXPECT(start_run(c, 1e-3, 4, vw, w) == fmi2OK);
        double x[4];
        fmi2Integer tr = 7;
        /* at t = 0, before the window [1, 3]: x_max and x_min have no sample */
        EXPECT(fmi2GetReal(c, obs_real, 4, x) == fmi2OK && isnan(x[0]) && isnan(x[1]));
        EXPECT(sink.n_notes == 1 && sink.status == fmi2OK && strcmp(sink.category, "logNotComputed") == 0);
        EXPECT(strstr(sink.last, "x_max") != NULL);
        EXPECT(strstr(sink.last, observe ? "not taken a sample" : "observe = true") != NULL);
        if (observe) EXPECT(x[2] == 0.0 && x[3] == 0.0); /* nothing stuck or dissipated in the window yet */
        else EXPECT(isnan(x[2]) && isnan(x[3]));
        EXPECT(fmi2DoStep(c, 0.0, 4.0, fmi2True) == fmi2OK);
        for (int k = 0; k < 4; k++) {
            /* read twice (a host sampling every step): the same answer, no second note */
            for (int again = 0; again < 2; again++) {
                EXPECT(fmi2GetReal(c, &obs_real[k], 1, &x[k]) == fmi2OK);
                EXPECT(observe ? isfinite(x[k]) : isnan(x[k]));
            }
        }
        const fmi2Status st = fmi2GetInteger(c, &vtr, 1, &tr);
        if (observe) {
            /* the window [1, 3] of a stick-slip motion: extremes of both signs, stuck part of it */
            EXPECT(st == fmi2OK && tr > 0 && x[0] > 0.0 && x[1] < 0.0 && x[2] > 0.0 && x[2] < 1.0 && x[3] > 0.0);
        } else {
            EXPECT(st == fmi2OK && tr == -1);
        }
        EXPECT(sink.n_notes == 1 && sink.n_warnings == 0);
        /* the other outputs are not concerned */
        const fmi2ValueReference vx = VR_x;
        double xx;
        EXPECT(fmi2GetReal(c, &vx, 1, &xx) == fmi2OK && isfinite(xx));
        /* a new run (reset) notes again, once */
        EXPECT(fmi2Reset(c) == fmi2OK);
        EXPECT(fmi2SetBoolean(c, &vo, 1, &on) == fmi2OK && start_run(c, 1e-3, 4, vw, w) == fmi2OK);
        EXPECT(fmi2GetReal(c, obs_real, 4, x) == fmi2OK && isnan(x[0]) && sink.n_notes == 2);
        EXPECT(fmi2GetReal(c, obs_real, 4, x) == fmi2OK && sink.n_notes == 2 && sink.n_warnings == 0);
        fmi2FreeInstance(c);
    }
}

/* Direct feedthrough (ModelStructure: a and F_friction depend on F_ext and N_ext, x, v and mode do
 * not): an input set after a step changes a and F_friction at once, through the current mode's
 * friction law, without a step; setting the inputs back gives the step's own values bit for bit. */
static void test_feedthrough(tally *T)
{
    log_sink sink = {{0}, 0, 0};
    fmi2CallbackFunctions cb = callbacks_for(&sink);
    const fmi2ValueReference out_vr[4] = {VR_x, VR_v, VR_a, VR_F_friction};
    const fmi2ValueReference vm = VR_mode, vin[2] = {VR_F_ext, VR_N_ext};
    const double k = 100.0, N = 1.0, mu_s = 0.4, chi = 0.5, P0 = 1.0, omega = 5.0;
    for (int sliding = 0; sliding <= 1; sliding++) {
        fmi2Component c = new_instance("feedthrough", &cb);
        const fmi2ValueReference vp[6] = {VR_k, VR_N, VR_mu_s, VR_chi, VR_P0, VR_omega};
        const double p[6] = {k, N, mu_s, chi, P0, omega};
        EXPECT(start_run(c, 1e-3, 6, vp, p) == fmi2OK);
        const double zero[2] = {0.0, 0.0};
        EXPECT(fmi2SetReal(c, vin, 2, zero) == fmi2OK);
        /* find a communication point in the wanted mode */
        double t = 0.0, y[4], y2[4];
        fmi2Integer mode = 0, mode2 = 0;
        for (int j = 0; j < 4000; j++) {
            EXPECT(fmi2DoStep(c, t, 0.00125, fmi2True) == fmi2OK);
            t += 0.00125;
            fmi2GetInteger(c, &vm, 1, &mode);
            if ((mode != 0) == sliding && j > 40) break;
        }
        EXPECT((mode != 0) == sliding);
        EXPECT(fmi2GetReal(c, out_vr, 4, y) == fmi2OK);
        const double dF = 0.05, dN = 0.5;
        /* F_ext */
        EXPECT(fmi2SetReal(c, &vin[0], 1, &dF) == fmi2OK);
        EXPECT(fmi2GetReal(c, out_vr, 4, y2) == fmi2OK && fmi2GetInteger(c, &vm, 1, &mode2) == fmi2OK);
        EXPECT(y2[0] == y[0] && y2[1] == y[1] && mode2 == mode); /* x, v, mode: only through a step */
        if (sliding) {
            /* sliding: the friction stays -s mu_k N, the acceleration takes F_ext / m */
            EXPECT(y2[3] == y[3]);
            EXPECT(fabs(y2[2] - (y[2] + dF)) <= 1e-12 * (1.0 + fabs(y[2])));
        } else {
            /* stuck: the friction takes F_ext up (inside the limit), the acceleration stays 0 */
            const double S = P0 * cos(omega * t) - k * y[0];
            EXPECT(fabs(y2[3] - (-(S + dF))) <= 1e-12);
            EXPECT(fabs(y2[3] - (y[3] - dF)) <= 1e-12 && y2[2] == 0.0 && y[2] == 0.0);
        }
        /* N_ext */
        EXPECT(fmi2SetReal(c, vin, 2, zero) == fmi2OK);
        EXPECT(fmi2SetReal(c, &vin[1], 1, &dN) == fmi2OK);
        EXPECT(fmi2GetReal(c, out_vr, 4, y2) == fmi2OK);
        EXPECT(y2[0] == y[0] && y2[1] == y[1]);
        if (sliding) {
            const double mu_k = chi * mu_s;
            EXPECT(fabs(y2[3] - (-mode * mu_k * (N + dN))) <= 1e-15);
            EXPECT(fabs(y2[2] - (y[2] - mode * mu_k * dN)) <= 1e-12 * (1.0 + fabs(y[2])));
        } else {
            EXPECT(y2[3] == y[3]); /* stuck inside the limit: the friction does not depend on N */
        }
        /* back to the step's inputs: the step's own values, bit for bit */
        EXPECT(fmi2SetReal(c, vin, 2, zero) == fmi2OK);
        EXPECT(fmi2GetReal(c, out_vr, 4, y2) == fmi2OK && memcmp(y, y2, sizeof y) == 0);
        fmi2FreeInstance(c);
    }
}

static void test_cycles(tally *T)
{
    log_sink sink = {{0}, 0, 0};
    fmi2CallbackFunctions cb = callbacks_for(&sink);
    const long before = mem_outstanding();
    long ok = 0;
    for (int k = 0; k < 10000; k++) {
        fmi2Component c = new_instance("cycle", &cb);
        if (!c) continue;
        ok++;
        if (k % 10 == 0) {
            start_run(c, 1e-3, 0, NULL, NULL);
            fmi2DoStep(c, 0.0, 0.02, fmi2True);
            fmi2FMUstate s = NULL, s2 = NULL;
            fmi2GetFMUstate(c, &s);
            size_t n = 0;
            fmi2SerializedFMUstateSize(c, s, &n);
            fmi2Byte buf[2048];
            if (n <= sizeof buf && fmi2SerializeFMUstate(c, s, buf, n) == fmi2OK) fmi2DeSerializeFMUstate(c, buf, n, &s2);
            fmi2FreeFMUstate(c, &s);
            fmi2FreeFMUstate(c, &s2);
        }
        fmi2FreeInstance(c);
    }
    EXPECT(ok == 10000);
    EXPECT(mem_outstanding() == before);
    printf("cycles: %ld allocations, %ld frees\n", g_mem.allocs, g_mem.frees);
}

/* The coupling functions: NULL arrays, the phases they may be called in, and a rejected call that
 * changes nothing; a ramp input set by its derivative reaches the state (x differs from the held
 * input's) and is spent after one step. */
static void test_coupling(tally *T)
{
    log_sink sink = {{0}, 0, 0};
    fmi2CallbackFunctions cb = callbacks_for(&sink);
    fmi2Component c = new_instance("coupling", &cb);
    const fmi2ValueReference vF = VR_F_ext, vN = VR_N_ext, vx = VR_x, va = VR_a, vv = VR_v;
    const fmi2Integer one = 1, two = 2, three = 3;
    fmi2Real r = 0.5, out = 0.0;
    /* phases: input derivatives before initialisation (for the first step), none of the others */
    EXPECT(fmi2SetRealInputDerivatives(c, &vF, 1, &one, &r) == fmi2OK);
    FAILS(fmi2GetRealOutputDerivatives(c, &vx, 1, &one, &out), "must not be called in instantiated");
    FAILS(fmi2GetDirectionalDerivative(c, &va, 1, &vF, 1, &r, &out), "must not be called in instantiated");
    fmi2Reset(c);
    EXPECT(start_run(c, 1e-3, 0, NULL, NULL) == fmi2OK);
    /* NULL arrays */
    FAILS(fmi2SetRealInputDerivatives(c, NULL, 1, &one, &r), "NULL");
    FAILS(fmi2SetRealInputDerivatives(c, &vF, 1, NULL, &r), "NULL");
    FAILS(fmi2SetRealInputDerivatives(c, &vF, 1, &one, NULL), "NULL");
    FAILS(fmi2GetRealOutputDerivatives(c, &vx, 1, &one, NULL), "NULL");
    FAILS(fmi2GetRealOutputDerivatives(c, &vx, 1, NULL, &out), "NULL");
    FAILS(fmi2GetDirectionalDerivative(c, NULL, 1, &vF, 1, &r, &out), "NULL");
    FAILS(fmi2GetDirectionalDerivative(c, &va, 1, &vF, 1, NULL, &out), "NULL");
    FAILS(fmi2GetDirectionalDerivative(c, &va, 1, &vF, 1, &r, NULL), "NULL");
    EXPECT(fmi2SetRealInputDerivatives(c, NULL, 0, NULL, NULL) == fmi2OK);
    EXPECT(fmi2GetRealOutputDerivatives(c, NULL, 0, NULL, NULL) == fmi2OK);
    EXPECT(fmi2GetDirectionalDerivative(c, NULL, 0, NULL, 0, NULL, NULL) == fmi2OK);
    /* orders out of range, a rejected call changes nothing */
    FAILS(fmi2SetRealInputDerivatives(c, &vF, 1, &three, &r), "valid range: 1 to 2");
    FAILS(fmi2GetRealOutputDerivatives(c, &vv, 1, &three, &out), "valid range: 1 to 2");
    const fmi2ValueReference both[2] = {VR_F_ext, VR_m};
    const fmi2Integer orders[2] = {1, 1};
    const fmi2Real values[2] = {5.0, 1.0};
    FAILS(fmi2SetRealInputDerivatives(c, both, 2, orders, values), "not a real input");
    EXPECT(fmi2DoStep(c, 0.0, 0.1, fmi2True) == fmi2OK);
    fmi2Real x_held = 0.0;
    EXPECT(fmi2GetReal(c, &vx, 1, &x_held) == fmi2OK);
    /* a ramp: F_ext' = 5 over the next step, then spent (F_ext holds its end value 0.5) */
    fmi2Component d = new_instance("coupling-ramp", &cb);
    EXPECT(start_run(d, 1e-3, 0, NULL, NULL) == fmi2OK);
    const fmi2Real slope = 5.0, second = 0.0;
    EXPECT(fmi2DoStep(d, 0.0, 0.1, fmi2True) == fmi2OK);
    EXPECT(fmi2SetRealInputDerivatives(d, &vF, 1, &one, &slope) == fmi2OK);
    EXPECT(fmi2SetRealInputDerivatives(d, &vN, 1, &two, &second) == fmi2OK);
    EXPECT(fmi2DoStep(d, 0.1, 0.1, fmi2True) == fmi2OK);
    fmi2Real F_end = 0.0;
    EXPECT(fmi2GetReal(d, &vF, 1, &F_end) == fmi2OK && fabs(F_end - 0.5) < 1e-15);
    EXPECT(fmi2GetReal(d, &vx, 1, &out) == fmi2OK && out != x_held);
    fmi2Real J[2] = {0.0, 0.0};
    const fmi2ValueReference unk[2] = {VR_a, VR_x};
    EXPECT(fmi2GetDirectionalDerivative(d, unk, 2, &vF, 1, &slope, J) == fmi2OK && J[1] == 0.0);
    EXPECT(fmi2Terminate(d) == fmi2OK);
    EXPECT(fmi2GetRealOutputDerivatives(d, &vx, 1, &one, &out) == fmi2OK);
    FAILS(fmi2SetRealInputDerivatives(d, &vF, 1, &one, &slope), "must not be called in terminated");
    fmi2FreeInstance(d);
    fmi2FreeInstance(c);
}

int main(void)
{
    tally t = {0, 0, NULL, {0}}, *T = &t;
    test_instantiate(T);
    test_null_instance(T);
    test_null_arrays(T);
    test_call_order(T);
    test_bad_values(T);
    test_states(T);
    test_overflow(T);
    test_not_computed_outputs(T);
    test_feedthrough(T);
    test_cycles(T);
    test_coupling(T);
    EXPECT(mem_outstanding() == 0);
    return tally_done(T, "test_fmi_api");
}
