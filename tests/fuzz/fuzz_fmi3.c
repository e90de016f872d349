/* libFuzzer target over the FMI 3.0 entry points of the DryFrictionOscillator FMU.
 *
 * The input bytes are decoded into a sequence of FMI 3.0 calls: instantiate (with any of
 * eventModeUsed, earlyReturnAllowed and an intermediate-update callback that may request an early
 * return or try to step from inside) / free, enter and exit initialisation, set and get through
 * Float64, Int32, Int64 (the enumeration) and Boolean of every variable (time, unknown value
 * references, a wrong nValues) with special values, doStep with the right or a wrong communication
 * point and any step size, event mode (enter, update, enter step mode), terminate, reset, FMU state
 * get/set/free, serialise and deserialise (intact, truncated, a byte flipped), the functions of
 * features the FMU lacks. Calls out of order are part of the game.
 *
 * Oracles (abort when one fails): an fmi3Error of a live instance comes with a logged message;
 * outputs read with fmi3OK/fmi3Warning are finite and mode is -1, 0 or +1; after an fmi3OK doStep
 * the last successful time lies in (tc, tc + dt], is tc + dt unless earlyReturn, and earlyReturn and
 * eventHandlingNeeded only come when allowed (earlyReturnAllowed; eventModeUsed with it).
 *
 * Built by tests/fuzz/CMakeLists.txt (clang, -fsanitize=fuzzer) and, with replay_main.c, by
 * tests/fmi3_c/CMakeLists.txt as the ctest replay of tests/fuzz/corpus3. */
#include "fmi3Functions.h"
#include "model_vars.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FUZZ_MAX_CALLS 400
#define FUZZ_MAX_STEPS 20000.0
#define SER_CAP 4096

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

typedef struct {
    const uint8_t *p;
    size_t n, i;
} reader;

static unsigned u8(reader *r) { return r->i < r->n ? r->p[r->i++] : 0u; }
static unsigned u16(reader *r)
{
    const unsigned a = u8(r);
    return a | (u8(r) << 8);
}
static uint32_t u32(reader *r)
{
    const uint32_t a = u16(r);
    return a | ((uint32_t)u16(r) << 16);
}

static double real(reader *r)
{
    static const double special[] = {0.0, -0.0, 1.0, -1.0, 0.5, 1e-3, 1e-300, 1e300, -1e300, NAN, INFINITY,
                                     -INFINITY, DBL_MIN, DBL_MAX, 1e-12, 1e6, 2.0, 100.0, -0.1, 0.7, 3.0, 0.4, 5.0,
                                     0.1, 0.01, 4.9e-324};
    const unsigned n_special = sizeof special / sizeof special[0];
    const unsigned sel = u8(r);
    if (sel < 2 * n_special) return special[sel % n_special];
    if (sel < 236) return ((double)u16(r) / 65535.0 - 0.25) * 8.0;
    uint64_t bits = (uint64_t)u32(r) | ((uint64_t)u32(r) << 32);
    double d;
    memcpy(&d, &bits, sizeof d);
    return d;
}

static fmi3ValueReference any_vr(reader *r)
{
    const unsigned sel = u8(r);
    if (sel < 230) return DFO_VARS[sel % DFO_NUM_VARS].vr;
    if (sel < 245) return DFO_VR_TIME;
    return (fmi3ValueReference)u32(r);
}

typedef struct {
    fmi3Instance c;
    fmi3FMUState slot[2];
    fmi3Byte ser[SER_CAP];
    size_t ser_n;
    long errors_logged;
    int silenced, early_allowed, event_mode, request_every, updates;
    double t;
} ctx;

static void oracle_fail(const char *what)
{
    fprintf(stderr, "fuzz_fmi3 oracle failed: %s\n", what);
    abort();
}

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    ctx *X = (ctx *)env;
    if (!message || !category) oracle_fail("NULL log message or category");
    if (status >= fmi3Error) X->errors_logged++;
}

static void on_update(fmi3InstanceEnvironment env, fmi3Float64 t, fmi3Boolean set_req, fmi3Boolean get_ok,
                      fmi3Boolean finished, fmi3Boolean can_return, fmi3Boolean *req, fmi3Float64 *req_t)
{
    ctx *X = (ctx *)env;
    (void)set_req; (void)finished; (void)can_return;
    if (!isfinite(t)) oracle_fail("intermediate update at a non-finite time");
    X->updates++;
    if (get_ok && X->c) {
        const fmi3ValueReference vr = VR_x;
        fmi3Float64 x;
        if (fmi3GetFloat64(X->c, &vr, 1, &x, 1) == fmi3OK && !isfinite(x)) oracle_fail("x not finite in update");
        fmi3Boolean ev, term, early;
        fmi3Float64 last;
        if (X->updates % 3 == 0 && fmi3DoStep(X->c, t, 0.1, fmi3False, &ev, &term, &early, &last) != fmi3Error)
            oracle_fail("doStep from inside the intermediate update was accepted");
    }
    *req = (X->request_every && X->updates % X->request_every == 0) ? fmi3True : fmi3False;
    *req_t = t;
}

static void after(ctx *X, fmi3Status st, long before)
{
    if (st > fmi3Fatal) oracle_fail("invalid status code");
    if (st == fmi3Error && X->c && !X->silenced && X->errors_logged == before)
        oracle_fail("fmi3Error without a logged message");
}

static void free_all(ctx *X)
{
    if (!X->c) return;
    for (int k = 0; k < 2; k++)
        if (X->slot[k]) fmi3FreeFMUState(X->c, &X->slot[k]);
    fmi3FreeInstance(X->c);
    X->c = NULL;
}

static void check_outputs(ctx *X)
{
    const fmi3ValueReference vr[9] = {VR_x, VR_v, VR_a, VR_F_friction, VR_x_max, VR_x_min, VR_stick_fraction,
                                      VR_E_friction, DFO_VR_TIME};
    fmi3Float64 v[9];
    const fmi3Status st = fmi3GetFloat64(X->c, vr, 9, v, 9);
    if (st == fmi3OK || st == fmi3Warning)
        for (int i = 0; i < 9; i++)
            if (!isfinite(v[i])) oracle_fail("an output read with OK is not finite");
    const fmi3ValueReference vm = VR_mode;
    fmi3Int32 m;
    if (fmi3GetInt32(X->c, &vm, 1, &m, 1) == fmi3OK && (m < -1 || m > 1)) oracle_fail("mode out of range");
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    reader R = {data, size, 0}, *r = &R;
    ctx X;
    memset(&X, 0, sizeof X);
    for (int call = 0; call < FUZZ_MAX_CALLS && r->i < r->n; call++) {
        const unsigned op = u8(r) % 24;
        if (!X.c && op != 0) continue;
        const long before = X.errors_logged;
        fmi3Status st = fmi3OK;
        switch (op) {
        case 0: { /* instantiate */
            free_all(&X);
            const unsigned f = u8(r);
            X.event_mode = f & 1;
            X.early_allowed = (f >> 1) & 1;
            X.request_every = (f >> 3) & 3;
            X.silenced = 0;
            X.t = 0.0;
            X.c = fmi3InstantiateCoSimulation((f & 64) ? "" : "fuzz",
                                              (f & 128) ? "{wrong}" : MODEL_GUID, NULL, fmi3False, (f >> 5) & 1,
                                              X.event_mode, X.early_allowed, NULL, 0, &X, logger,
                                              (f & 4) ? on_update : NULL);
            break;
        }
        case 1: free_all(&X); break;
        case 2: {
            const double t0 = (u8(r) & 1) ? real(r) : 0.0;
            st = fmi3EnterInitializationMode(X.c, fmi3False, 0.0, t0, u8(r) & 1, real(r));
            if (st == fmi3OK) X.t = t0;
            break;
        }
        case 3: st = fmi3ExitInitializationMode(X.c); break;
        case 4: case 5: { /* set Float64, sometimes a wrong nValues */
            fmi3ValueReference vr[2] = {any_vr(r), any_vr(r)};
            fmi3Float64 v[2] = {real(r), real(r)};
            const size_t n = 1 + (u8(r) & 1);
            st = fmi3SetFloat64(X.c, vr, n, v, (u8(r) < 16) ? n + 1 : n);
            break;
        }
        case 6: {
            fmi3ValueReference vr = any_vr(r);
            fmi3Int32 v = (fmi3Int32)u32(r);
            if (u8(r) < 200) v = (int)(u8(r) % 8) - 2;
            st = fmi3SetInt32(X.c, &vr, 1, &v, 1);
            break;
        }
        case 7: {
            fmi3ValueReference vr = any_vr(r);
            fmi3Int64 v = (u8(r) < 200) ? (fmi3Int64)(u8(r) % 8) - 2 : (fmi3Int64)u32(r) << 20;
            st = fmi3SetInt64(X.c, &vr, 1, &v, 1);
            break;
        }
        case 8: {
            fmi3ValueReference vr = any_vr(r);
            fmi3Boolean v = u8(r) & 1;
            st = fmi3SetBoolean(X.c, &vr, 1, &v, 1);
            break;
        }
        case 9: case 10: { /* get of any kind */
            fmi3ValueReference vr = any_vr(r);
            fmi3Float64 d;
            fmi3Int32 i;
            fmi3Int64 l;
            fmi3Boolean b;
            switch (u8(r) % 4) {
            case 0: st = fmi3GetFloat64(X.c, &vr, 1, &d, 1); break;
            case 1: st = fmi3GetInt32(X.c, &vr, 1, &i, 1); break;
            case 2: st = fmi3GetInt64(X.c, &vr, 1, &l, 1); break;
            default: st = fmi3GetBoolean(X.c, &vr, 1, &b, 1); break;
            }
            break;
        }
        case 11: case 12: case 13: { /* doStep */
            double dt = real(r);
            const double tc = (u8(r) < 230) ? X.t : real(r);
            const fmi3ValueReference vh = VR_h;
            fmi3Float64 h = 0.0;
            if (fmi3GetFloat64(X.c, &vh, 1, &h, 1) == fmi3OK && h > 0.0 && isfinite(dt) && dt > FUZZ_MAX_STEPS * h)
                dt = FUZZ_MAX_STEPS * h;
            fmi3Boolean ev = 7, term = 7, early = 7;
            fmi3Float64 last = NAN;
            st = fmi3DoStep(X.c, tc, dt, fmi3False, &ev, &term, &early, &last);
            if (st == fmi3OK) {
                if (early && !X.early_allowed) oracle_fail("early return not allowed");
                if (ev && !(X.event_mode && X.early_allowed)) oracle_fail("event handling without event mode");
                if (!(last > tc - 1e-9 * fabs(tc) - 1e-300) || last > tc + dt) oracle_fail("lastSuccessfulTime outside the step");
                if (!early && last != tc + dt) oracle_fail("lastSuccessfulTime is not tc + dt");
                X.t = last;
            }
            break;
        }
        case 14: st = fmi3EnterEventMode(X.c); break;
        case 15: {
            fmi3Boolean a, b, c, d, e;
            fmi3Float64 t;
            st = fmi3UpdateDiscreteStates(X.c, &a, &b, &c, &d, &e, &t);
            if (st == fmi3OK && (a || b || c || d || e)) oracle_fail("fmi3UpdateDiscreteStates reported a flag");
            break;
        }
        case 16: st = fmi3EnterStepMode(X.c); break;
        case 17: st = (u8(r) & 1) ? fmi3Terminate(X.c) : fmi3Reset(X.c); break;
        case 18: {
            const int k = u8(r) & 1;
            st = fmi3GetFMUState(X.c, &X.slot[k]);
            break;
        }
        case 19: {
            const int k = u8(r) & 1;
            st = fmi3SetFMUState(X.c, X.slot[k]);
            if (st == fmi3OK) {
                const fmi3ValueReference vt = DFO_VR_TIME;
                fmi3GetFloat64(X.c, &vt, 1, &X.t, 1);
            }
            break;
        }
        case 20: {
            const int k = u8(r) & 1;
            size_t n = 0;
            if (X.slot[k] && fmi3SerializedFMUStateSize(X.c, X.slot[k], &n) == fmi3OK && n <= SER_CAP &&
                fmi3SerializeFMUState(X.c, X.slot[k], X.ser, n) == fmi3OK)
                X.ser_n = n;
            break;
        }
        case 21: {
            if (!X.ser_n) break;
            fmi3Byte buf[SER_CAP];
            memcpy(buf, X.ser, X.ser_n);
            size_t n = X.ser_n;
            const unsigned how = u8(r) % 3;
            if (how == 1) n = u16(r) % n;
            if (how == 2) buf[u16(r) % n] ^= (fmi3Byte)(1u << (u8(r) % 8));
            const int k = u8(r) & 1;
            st = fmi3DeserializeFMUState(X.c, buf, n, &X.slot[k]);
            break;
        }
        case 22: { /* what the FMU lacks */
            fmi3Float32 f;
            fmi3ValueReference vr = any_vr(r);
            size_t nd;
            switch (u8(r) % 4) {
            case 0: st = fmi3GetFloat32(X.c, &vr, 1, &f, 1); break;
            case 1: st = fmi3EnterContinuousTimeMode(X.c); break;
            case 2: st = fmi3GetNumberOfVariableDependencies(X.c, vr, &nd); break;
            default: st = fmi3EnterConfigurationMode(X.c); break;
            }
            if (st != fmi3Error) oracle_fail("an unsupported function did not fail");
            break;
        }
        default: {
            const int on = u8(r) & 1;
            st = fmi3SetDebugLogging(X.c, on, 0, NULL);
            if (st == fmi3OK) X.silenced = !on; /* all categories, logStatusError with them */
            break;
        }
        }
        if (getenv("FUZZ_TRACE")) fprintf(stderr, "call %d: op %u -> status %d (t = %.17g)\n", call, op, (int)st, X.t);
        after(&X, st, before);
        if (X.c) check_outputs(&X);
    }
    free_all(&X);
    return 0;
}
