/* What the fuzz targets of tests/fuzz share (fuzz_fmi.c, fuzz_fmi3.c: the oscillator; fuzz_chain2.c,
 * fuzz_chain3.c: the chain): the input reader, the special values, the host callbacks with their
 * oracles (an error of a live instance comes with a logged message; status codes are valid), the
 * FMU-state calls, and the driver loop (one call per operation byte; without an instance only
 * operation 0, instantiate, runs; after every call the status oracle and the target's output check).
 *
 * Include once, after fmi2Functions.h or fmi3Functions.h and the model's model_vars.h, with
 * FUZZ_NAME (the target's name, for messages), FUZZ_FMI (2 or 3) and SER_CAP (the largest
 * serialised state kept, in bytes) defined. Every function is static inline: a target uses what it
 * needs. */
#ifndef DFO_FUZZ_COMMON_H
#define DFO_FUZZ_COMMON_H

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* ---- the input: bytes, read past the end as zeros ------------------------------------------------ */

typedef struct {
    const uint8_t *p;
    size_t n, i;
} reader;

static inline unsigned u8(reader *r) { return r->i < r->n ? r->p[r->i++] : 0u; }

static inline unsigned u16(reader *r)
{
    const unsigned a = u8(r);
    return a | (u8(r) << 8);
}

static inline uint32_t u32(reader *r)
{
    const uint32_t a = u16(r);
    return a | ((uint32_t)u16(r) << 16);
}

/* A real: one of special[] (selector below 2 n_special), an ordinary value in [-2, 6] (selector
 * below ordinary_below), or any 64 bits (low word first). */
static inline double real_from(reader *r, const double *special, unsigned n_special, unsigned ordinary_below)
{
    const unsigned sel = u8(r);
    if (sel < 2 * n_special) return special[sel % n_special];
    if (sel < ordinary_below) return ((double)u16(r) / 65535.0 - 0.25) * 8.0;
    uint64_t bits = (uint64_t)u32(r);
    bits |= (uint64_t)u32(r) << 32;
    double d;
    memcpy(&d, &bits, sizeof d);
    return d;
}

/* A real with NaN, infinities, extremes, a subnormal and the values of the models' ranges. */
static inline double real(reader *r)
{
    static const double special[] = {0.0, -0.0, 1.0, -1.0, 0.5, 1e-3, 1e-300, 1e300, -1e300, NAN, INFINITY,
                                     -INFINITY, DBL_MIN, DBL_MAX, 1e-12, 1e6, 2.0, 100.0, -0.1, 0.7, 3.0, 0.4, 5.0,
                                     0.1, 0.01, 4.9e-324};
    return real_from(r, special, sizeof special / sizeof special[0], 236);
}

static inline void oracle_fail(const char *what)
{
    fprintf(stderr, FUZZ_NAME " oracle failed: %s\n", what);
    abort();
}

/* The friction oracle: with N = max(N + N_ext, 0) and mu_k = chi mu_s, a sliding block's friction
 * opposes its mode and its magnitude lies within [min, max](mu_s, mu_k) N (Stribeck's mu between
 * them at any speed, Coulomb's mu_k; rounding aside); a stuck one holds at most max(mu_s, mu_k) N. */
static inline void check_friction(int mode, double F, double mu_s, double chi, double N)
{
    const double mu_k = chi * mu_s, lo = fmin(mu_s, mu_k) * N, hi = fmax(mu_s, mu_k) * N;
    if (!(isfinite(lo) && isfinite(hi) && hi <= 1e300) || !isfinite(F)) return;
    const double tol = 1e-9 * hi + 1e-300;
    if (fabs(F) > hi + tol) oracle_fail("|F_friction| above max(mu_s, mu_k) N");
    if (mode != 0 && (F * mode > tol || fabs(F) < lo - tol))
        oracle_fail("a sliding block's F_friction outside -mode [min, max](mu_s, mu_k) N");
}

#if FUZZ_FMI == 3
/* ---- FMI 3.0 ------------------------------------------------------------------------------------ */

typedef struct ctx ctx;
typedef fmi3Status fuzz_status;

/* A target: its operations (call runs operation op, n_ops of them, at most max_calls an input), the
 * check after every call, and what the intermediate-update callback reads (NULL: nothing). */
typedef struct {
    int max_calls;
    unsigned n_ops;
    fuzz_status (*call)(ctx *X, reader *r, unsigned op);
    void (*check_outputs)(ctx *X);
    void (*update_get)(ctx *X);
} fuzz_target;

struct ctx {
    const fuzz_target *T;
    fmi3Instance c;
    fmi3FMUState slot[2];
    fmi3Byte ser[SER_CAP];
    size_t ser_n;
    long errors_logged;
    int silenced, early_allowed, event_mode, request_every, updates;
    double t; /* the host's view of the time */
};

static inline void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    ctx *X = (ctx *)env;
    if (!message || !category) oracle_fail("NULL log message or category");
    if (status >= fmi3Error) X->errors_logged++;
}

/* Reads what the target reads, tries a doStep from inside every third time (it must fail), and
 * requests an early return every request_every-th time. */
static inline void on_update(fmi3InstanceEnvironment env, fmi3Float64 t, fmi3Boolean set_req, fmi3Boolean get_ok,
                             fmi3Boolean finished, fmi3Boolean can_return, fmi3Boolean *req, fmi3Float64 *req_t)
{
    ctx *X = (ctx *)env;
    (void)set_req; (void)finished; (void)can_return;
    if (!isfinite(t)) oracle_fail("intermediate update at a non-finite time");
    X->updates++;
    if (get_ok && X->c) {
        if (X->T->update_get) X->T->update_get(X);
        fmi3Boolean ev, term, early;
        fmi3Float64 last;
        if (X->updates % 3 == 0 && fmi3DoStep(X->c, t, 0.1, fmi3False, &ev, &term, &early, &last) != fmi3Error)
            oracle_fail("doStep from inside the intermediate update was accepted");
    }
    *req = (X->request_every && X->updates % X->request_every == 0) ? fmi3True : fmi3False;
    *req_t = t;
}

/* An error of a live instance must be explained in the log. */
static inline void after(ctx *X, fmi3Status st, long before)
{
    if (st > fmi3Fatal) oracle_fail("invalid status code");
    if (st == fmi3Error && X->c && !X->silenced && X->errors_logged == before)
        oracle_fail("fmi3Error without a logged message");
}

static inline void free_all(ctx *X)
{
    if (!X->c) return;
    for (int k = 0; k < 2; k++)
        if (X->slot[k]) fmi3FreeFMUState(X->c, &X->slot[k]);
    X->slot[0] = X->slot[1] = NULL;
    fmi3FreeInstance(X->c);
    X->c = NULL;
}

/* (Re-)instantiate with eventModeUsed, earlyReturnAllowed, the update callback, logging, an empty
 * name and a wrong token as the next byte says. */
static inline fmi3Status instantiate(ctx *X, reader *r)
{
    free_all(X);
    const unsigned f = u8(r);
    X->event_mode = f & 1;
    X->early_allowed = (f >> 1) & 1;
    X->request_every = (f >> 3) & 3;
    X->silenced = 0;
    X->t = 0.0;
    X->c = fmi3InstantiateCoSimulation((f & 64) ? "" : "fuzz", (f & 128) ? "{wrong}" : MODEL_GUID, NULL, fmi3False,
                                       (f >> 5) & 1, X->event_mode, X->early_allowed, NULL, 0, X, logger,
                                       (f & 4) ? on_update : NULL);
    return fmi3OK;
}

static inline fmi3Status enter_initialization(ctx *X, reader *r)
{
    const double t0 = (u8(r) & 1) ? real(r) : 0.0;
    const fmi3Status st = fmi3EnterInitializationMode(X->c, fmi3False, 0.0, t0, u8(r) & 1, real(r));
    if (st == fmi3OK) X->t = t0;
    return st;
}

/* The oracles of an fmi3OK doStep from tc over dt: the last successful time lies in (tc, tc + dt]
 * and is tc + dt unless earlyReturn; earlyReturn and eventHandlingNeeded only when allowed. */
static inline void check_step(ctx *X, double tc, double dt, fmi3Boolean ev, fmi3Boolean early, fmi3Float64 last)
{
    if (early && !X->early_allowed) oracle_fail("early return not allowed");
    if (ev && !(X->event_mode && X->early_allowed)) oracle_fail("event handling without event mode");
    if (!(last > tc - 1e-9 * fabs(tc) - 1e-300) || last > tc + dt) oracle_fail("lastSuccessfulTime outside the step");
    if (!early && last != tc + dt) oracle_fail("lastSuccessfulTime is not tc + dt");
    X->t = last;
}

static inline fmi3Status update_discrete_states(ctx *X)
{
    fmi3Boolean a, b, c, d, e;
    fmi3Float64 t;
    const fmi3Status st = fmi3UpdateDiscreteStates(X->c, &a, &b, &c, &d, &e, &t);
    if (st == fmi3OK && (a || b || c || d || e)) oracle_fail("fmi3UpdateDiscreteStates reported a flag");
    return st;
}

static inline fmi3Status get_state(ctx *X, reader *r)
{
    const int k = u8(r) & 1;
    return fmi3GetFMUState(X->c, &X->slot[k]);
}

static inline fmi3Status set_state(ctx *X, reader *r)
{
    const int k = u8(r) & 1;
    const fmi3Status st = fmi3SetFMUState(X->c, X->slot[k]);
    if (st == fmi3OK) {
        const fmi3ValueReference vt = DFO_VR_TIME;
        fmi3GetFloat64(X->c, &vt, 1, &X->t, 1);
    }
    return st;
}

/* Serialise a slot's state into X->ser (kept when it fits). */
static inline fmi3Status serialize(ctx *X, reader *r)
{
    const int k = u8(r) & 1;
    size_t n = 0;
    if (X->slot[k] && fmi3SerializedFMUStateSize(X->c, X->slot[k], &n) == fmi3OK && n <= SER_CAP &&
        fmi3SerializeFMUState(X->c, X->slot[k], X->ser, n) == fmi3OK)
        X->ser_n = n;
    return fmi3OK;
}

/* Deserialise X->ser intact, truncated or with a bit flipped. */
static inline fmi3Status deserialize(ctx *X, reader *r)
{
    if (!X->ser_n) return fmi3OK;
    static fmi3Byte buf[SER_CAP];
    memcpy(buf, X->ser, X->ser_n);
    size_t n = X->ser_n;
    const unsigned how = u8(r) % 3;
    if (how == 1) n = u16(r) % n;
    if (how == 2) buf[u16(r) % n] ^= (fmi3Byte)(1u << (u8(r) % 8));
    const int k = u8(r) & 1;
    return fmi3DeserializeFMUState(X->c, buf, n, &X->slot[k]);
}

/* Logging of every category on or off (logStatusError with them). */
static inline fmi3Status set_logging(ctx *X, reader *r)
{
    const int on = u8(r) & 1;
    const fmi3Status st = fmi3SetDebugLogging(X->c, on, 0, NULL);
    if (st == fmi3OK) X->silenced = !on;
    return st;
}

#else
/* ---- FMI 2.0 ------------------------------------------------------------------------------------ */

typedef struct ctx ctx;
typedef fmi2Status fuzz_status;

/* A target: its operations (call runs operation op, n_ops of them, at most max_calls an input) and
 * the check after every call. */
typedef struct {
    int max_calls;
    unsigned n_ops;
    fuzz_status (*call)(ctx *X, reader *r, unsigned op);
    void (*check_outputs)(ctx *X);
} fuzz_target;

struct ctx {
    fmi2CallbackFunctions cb; /* the logger below, calloc, free; the environment: this */
    fmi2Component c;
    fmi2FMUstate slot[2];
    fmi2Byte ser[SER_CAP];
    size_t ser_n;
    long errors_logged;
    int silenced; /* error logging switched off by fmi2SetDebugLogging */
    double t;     /* the host's view of the time */
    int trace;    /* print the status of every call (fuzz_fmi.c: env FUZZ_TRACE set) */
    double v_belt_stepped; /* fuzz_fmi.c: v_belt read after the last good doStep (a stuck block rides it) */
};

static inline void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                          fmi2String message, ...)
{
    ctx *X = (ctx *)env;
    (void)name;
    if (!message || !category) oracle_fail("NULL log message or category");
    if (status >= fmi2Error) X->errors_logged++;
}

/* X empty, with its callbacks. */
static inline void ctx_init(ctx *X)
{
    memset(X, 0, sizeof *X);
    X->cb.logger = logger;
    X->cb.allocateMemory = calloc;
    X->cb.freeMemory = free;
    X->cb.stepFinished = NULL;
    X->cb.componentEnvironment = X;
}

/* An error of a live instance must be explained in the log. */
static inline void after(ctx *X, fmi2Status st, long before)
{
    if (st > fmi2Pending) oracle_fail("invalid status code");
    if (X->trace) fprintf(stderr, "  -> status %d\n", (int)st);
    if (st == fmi2Error && X->c && !X->silenced && X->errors_logged == before)
        oracle_fail("fmi2Error without a logged message");
}

static inline void free_all(ctx *X)
{
    if (!X->c) return;
    for (int k = 0; k < 2; k++)
        if (X->slot[k]) fmi2FreeFMUstate(X->c, &X->slot[k]);
    X->slot[0] = X->slot[1] = NULL;
    fmi2FreeInstance(X->c);
    X->c = NULL;
}

/* Serialise a slot's state into X->ser (kept when it fits). */
static inline fmi2Status serialize(ctx *X, reader *r)
{
    const int k = u8(r) & 1;
    size_t n = 0;
    if (X->slot[k] && fmi2SerializedFMUstateSize(X->c, X->slot[k], &n) == fmi2OK && n <= SER_CAP &&
        fmi2SerializeFMUstate(X->c, X->slot[k], X->ser, n) == fmi2OK)
        X->ser_n = n;
    return fmi2OK;
}

/* Deserialise X->ser intact, truncated or with a bit flipped. */
static inline fmi2Status deserialize(ctx *X, reader *r)
{
    if (!X->ser_n) return fmi2OK;
    static fmi2Byte buf[SER_CAP];
    memcpy(buf, X->ser, X->ser_n);
    size_t n = X->ser_n;
    const unsigned how = u8(r) % 3;
    if (how == 1) n = u16(r) % n;
    if (how == 2) buf[u16(r) % n] ^= (fmi2Byte)(1u << (u8(r) % 8));
    const int k = u8(r) & 1;
    return fmi2DeSerializeFMUstate(X->c, buf, n, &X->slot[k]);
}

/* Logging of every category on or off (logStatusError with them). */
static inline fmi2Status set_logging(ctx *X, reader *r)
{
    const int on = u8(r) & 1;
    const fmi2Status st = fmi2SetDebugLogging(X->c, on, 0, NULL);
    if (st == fmi2OK) X->silenced = !on;
    return st;
}
#endif

/* ---- pseudo-random inputs (ctest: any compiler, no libFuzzer) ----------------------------------------- */

#define FUZZ_RANDOM_LEN 1024 /* bytes of a pseudo-random input at most */

static inline uint64_t xorshift64(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return *s;
}

/* An FMU-state operation: opcode first + (x >> 8) % 4 (get, set, serialise, deserialise), then
 * three bytes of x. Returns the new length. */
static inline size_t put_state_op(uint8_t *buf, size_t n, unsigned first, uint64_t x)
{
    buf[n++] = (uint8_t)(first + (x >> 8) % 4);
    buf[n++] = (uint8_t)(x >> 16);
    buf[n++] = (uint8_t)(x >> 24);
    buf[n++] = (uint8_t)(x >> 32);
    return n;
}

/* Four bytes of x: anything. Returns the new length. */
static inline size_t put_any(uint8_t *buf, size_t n, uint64_t x)
{
    for (int b = 0; b < 4; b++) buf[n++] = (uint8_t)(x >> (8 * b + 3));
    return n;
}

/* Runs count (argv[1], else default_count) pseudo-random inputs through LLVMFuzzerTestOneInput:
 * input k from make(k, s, buf) (its length; buf holds FUZZ_RANDOM_LEN bytes), s a xorshift state
 * started at seed. */
static inline int fuzz_random_main(int argc, char **argv, long default_count, uint64_t seed,
                                   size_t (*make)(long k, uint64_t *s, uint8_t *buf))
{
    const long count = argc > 1 ? atol(argv[1]) : default_count;
    uint64_t s = seed;
    static uint8_t buf[FUZZ_RANDOM_LEN];
    for (long k = 0; k < count; k++) {
        const size_t n = make(k, &s, buf);
        LLVMFuzzerTestOneInput(buf, n);
    }
    printf(FUZZ_NAME ": %ld pseudo-random inputs, no oracle failed\n", count);
    return 0;
}

/* ---- the driver --------------------------------------------------------------------------------- */

/* Runs the operations the input holds through T from no instance; env FUZZ_TRACE set: one line a call. */
static inline int fuzz_drive(const fuzz_target *T, const uint8_t *data, size_t size)
{
    reader R = {data, size, 0}, *r = &R;
    static ctx X; /* SER_CAP bytes: not on the stack */
#if FUZZ_FMI == 3
    memset(&X, 0, sizeof X);
    X.T = T;
#else
    ctx_init(&X);
#endif
    for (int call = 0; call < T->max_calls && r->i < r->n; call++) {
        const unsigned op = u8(r) % T->n_ops;
        if (!X.c && op != 0) continue;
        const long before = X.errors_logged;
        const clock_t c0 = clock();
        const fuzz_status st = T->call(&X, r, op);
        if (getenv("FUZZ_TRACE"))
            fprintf(stderr, "call %d: op %u -> status %d (t = %.17g, %.3f s)\n", call, op, (int)st, X.t,
                    (double)(clock() - c0) / CLOCKS_PER_SEC);
        after(&X, st, before);
        if (X.c) T->check_outputs(&X);
    }
    free_all(&X);
    return 0;
}

#ifdef VR_x_max
/* The oscillator's rule for a value not computed (observe false, or a window not yet sampled): its
 * observables read NaN with OK (transitions -1), and so do the local variables of the sensitivity
 * unless sensitivity is on with scheme exact. Any other non-finite value read with OK is a bug. */
static int fuzz_finite_or_not_computed(unsigned vr, double v)
{
    if (isfinite(v)) return 1;
    return isnan(v) && (vr == VR_x_max || vr == VR_x_min || vr == VR_stick_fraction || vr == VR_E_friction ||
                        vr == VR_dx_dx0 || vr == VR_dx_dv0 || vr == VR_dv_dx0 || vr == VR_dv_dv0);
}
#endif

#endif
