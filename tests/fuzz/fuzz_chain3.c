/* libFuzzer target over the FMI 3.0 entry points of the DryFrictionChain FMU.
 *
 * The input bytes are decoded into a sequence of FMI 3.0 calls: instantiate (eventModeUsed,
 * earlyReturnAllowed, an intermediate-update callback that may request an early return, a wrong
 * token) / free, configuration mode with a random n (valid, 0, above 4096, huge; a wrong nValues),
 * initialisation, arrays set with n values or a wrong count and special values, scalars, the
 * scheme (4 included), gets of every kind, doStep with the right or a wrong communication point,
 * event mode, terminate, reset, FMU states get/set/free, serialise and deserialise (intact,
 * truncated, a byte flipped; a state of another n). Calls out of order are part of the game.
 *
 * Oracles (abort when one fails): an fmi3Error of a live instance comes with a logged message;
 * outputs read with fmi3OK are finite and every mode is -1, 0 or +1; n reads within [1, 4096];
 * after an fmi3OK doStep the last successful time lies in (tc, tc + dt], is tc + dt unless
 * earlyReturn, and earlyReturn and eventHandlingNeeded only come when allowed.
 *
 * Replayed by ctest (tests/fmi3_c: fmi3_chain_fuzz_corpus over tests/fuzz/corpus_chain3, and
 * fmi3_chain_fuzz_random, 400 pseudo-random inputs through the same decoder, CHAIN_FUZZ_RANDOM_MAIN);
 * a libFuzzer build is tests/fuzz/CMakeLists.txt's fuzz_chain3. */
#include "fmi3Functions.h"
#include "model_vars.h"

#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define FUZZ_MAX_CALLS 300
#define FUZZ_MAX_WORK 2e5 /* internal steps x blocks per doStep */
#define SER_CAP 16384
#define NBUF 64

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
    if (sel < 240) return DFO_VR_TIME;
    if (sel < 248) return DFO_VARS[sel % DFO_NUM_VARS].vr + 1 + (sel & 3); /* an FMI 2.0 element */
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
    fprintf(stderr, "fuzz_chain3 oracle failed: %s\n", what);
    abort();
}

static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message)
{
    ctx *X = (ctx *)env;
    if (!message || !category) oracle_fail("NULL log message or category");
    if (status >= fmi3Error) X->errors_logged++;
}

static size_t blocks(const ctx *X)
{
    const fmi3ValueReference vn = VR_n;
    fmi3UInt64 n = 0;
    if (fmi3GetUInt64(X->c, &vn, 1, &n, 1) != fmi3OK) return 0;
    if (n < 1 || n > MAX_n) oracle_fail("n outside [1, 4096]");
    return (size_t)n;
}

static void on_update(fmi3InstanceEnvironment env, fmi3Float64 t, fmi3Boolean set_req, fmi3Boolean get_ok,
                      fmi3Boolean finished, fmi3Boolean can_return, fmi3Boolean *req, fmi3Float64 *req_t)
{
    ctx *X = (ctx *)env;
    (void)set_req; (void)finished; (void)can_return;
    if (!isfinite(t)) oracle_fail("intermediate update at a non-finite time");
    X->updates++;
    if (get_ok && X->c) {
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
    const size_t n = blocks(X);
    if (n == 0 || n > NBUF) return;
    const fmi3ValueReference vr[5] = {VR_x, VR_v, VR_a, VR_F_friction, DFO_VR_TIME};
    fmi3Float64 v[4 * NBUF + 1];
    if (fmi3GetFloat64(X->c, vr, 5, v, 4 * n + 1) == fmi3OK)
        for (size_t i = 0; i < 4 * n + 1; i++)
            if (!isfinite(v[i])) oracle_fail("an output read with OK is not finite");
    const fmi3ValueReference vm = VR_mode;
    fmi3Int32 m[NBUF];
    if (fmi3GetInt32(X->c, &vm, 1, m, n) == fmi3OK)
        for (size_t i = 0; i < n; i++)
            if (m[i] < -1 || m[i] > 1) oracle_fail("mode out of range");
}

static fmi3UInt64 any_n(reader *r)
{
    static const fmi3UInt64 ns[] = {1, 2, 3, 5, 8, 13, 1, 2, 0, 4097, 64, 4096};
    const unsigned sel = u8(r);
    if (sel < 240) return ns[sel % (sizeof ns / sizeof ns[0])];
    return (fmi3UInt64)u32(r) << (u8(r) % 33);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    reader R = {data, size, 0}, *r = &R;
    ctx X;
    memset(&X, 0, sizeof X);
    for (int call = 0; call < FUZZ_MAX_CALLS && r->i < r->n; call++) {
        const unsigned op = u8(r) % 22;
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
            X.c = fmi3InstantiateCoSimulation((f & 64) ? "" : "fuzz", (f & 128) ? "{wrong}" : MODEL_GUID, NULL,
                                              fmi3False, (f >> 5) & 1, X.event_mode, X.early_allowed, NULL, 0, &X,
                                              logger, (f & 4) ? on_update : NULL);
            break;
        }
        case 1: free_all(&X); break;
        case 2: st = fmi3EnterConfigurationMode(X.c); break;
        case 3: case 4: { /* n: valid, out of range, a wrong nValues */
            const fmi3ValueReference vr = (u8(r) < 240) ? VR_n : any_vr(r);
            const fmi3UInt64 n = any_n(r);
            st = fmi3SetUInt64(X.c, &vr, 1, &n, (u8(r) < 16) ? 2 : 1);
            break;
        }
        case 5: st = fmi3ExitConfigurationMode(X.c); break;
        case 6: {
            const double t0 = (u8(r) & 1) ? real(r) : 0.0;
            st = fmi3EnterInitializationMode(X.c, fmi3False, 0.0, t0, u8(r) & 1, real(r));
            if (st == fmi3OK) X.t = t0;
            break;
        }
        case 7: st = fmi3ExitInitializationMode(X.c); break;
        case 8: case 9: { /* an array (or any variable) with n values, sometimes a wrong count */
            const fmi3ValueReference vr = (u8(r) < 200) ? (fmi3ValueReference)(DFO_ARRAY_VR_STRIDE * (1 + u8(r) % 12))
                                                        : any_vr(r);
            const size_t n = blocks(&X);
            size_t nv = n;
            if (u8(r) < 24) nv = u8(r) % 6;
            if (nv > NBUF) break;
            fmi3Float64 v[NBUF];
            const double base = real(r);
            for (size_t i = 0; i < nv; i++) v[i] = (u8(r) < 230) ? base : real(r);
            st = fmi3SetFloat64(X.c, &vr, 1, v, nv);
            break;
        }
        case 10: { /* scalars and the scheme */
            if (u8(r) & 1) {
                const fmi3ValueReference vr = 2 + u8(r) % 4; /* k_end, c_end, omega, h */
                const fmi3Float64 v = real(r);
                st = fmi3SetFloat64(X.c, &vr, 1, &v, 1);
            } else {
                const fmi3ValueReference vr = (u8(r) < 230) ? VR_scheme : any_vr(r);
                const fmi3Int64 v = (fmi3Int64)(u8(r) % 7) - 1;
                st = fmi3SetInt64(X.c, &vr, 1, &v, 1);
            }
            break;
        }
        case 11: { /* get of any kind, any nValues */
            const fmi3ValueReference vr = any_vr(r);
            const size_t nv = u8(r) % 4;
            fmi3Float64 d[4];
            fmi3Int32 i[4];
            fmi3Int64 l[4];
            fmi3UInt64 u[4];
            switch (u8(r) % 4) {
            case 0: st = fmi3GetFloat64(X.c, &vr, 1, d, nv); break;
            case 1: st = fmi3GetInt32(X.c, &vr, 1, i, nv); break;
            case 2: st = fmi3GetInt64(X.c, &vr, 1, l, nv); break;
            default: st = fmi3GetUInt64(X.c, &vr, 1, u, nv); break;
            }
            break;
        }
        case 12: case 13: case 14: { /* doStep */
            double dt = real(r);
            const double tc = (u8(r) < 230) ? X.t : real(r);
            const fmi3ValueReference vh = VR_h;
            fmi3Float64 h = 0.0;
            const size_t n = blocks(&X);
            if (fmi3GetFloat64(X.c, &vh, 1, &h, 1) == fmi3OK && h > 0.0 && n > 0 && isfinite(dt) &&
                dt > FUZZ_MAX_WORK / (double)n * h)
                dt = FUZZ_MAX_WORK / (double)n * h;
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
        case 15: {
            switch (u8(r) % 3) {
            case 0: st = fmi3EnterEventMode(X.c); break;
            case 1: {
                fmi3Boolean a, b, c, d, e;
                fmi3Float64 t;
                st = fmi3UpdateDiscreteStates(X.c, &a, &b, &c, &d, &e, &t);
                if (st == fmi3OK && (a || b || c || d || e)) oracle_fail("fmi3UpdateDiscreteStates reported a flag");
                break;
            }
            default: st = fmi3EnterStepMode(X.c); break;
            }
            break;
        }
        case 16: st = (u8(r) & 1) ? fmi3Terminate(X.c) : fmi3Reset(X.c); break;
        case 17: {
            const int k = u8(r) & 1;
            st = fmi3GetFMUState(X.c, &X.slot[k]);
            break;
        }
        case 18: {
            const int k = u8(r) & 1;
            st = fmi3SetFMUState(X.c, X.slot[k]);
            if (st == fmi3OK) {
                const fmi3ValueReference vt = DFO_VR_TIME;
                fmi3GetFloat64(X.c, &vt, 1, &X.t, 1);
            }
            break;
        }
        case 19: {
            const int k = u8(r) & 1;
            size_t n = 0;
            if (X.slot[k] && fmi3SerializedFMUStateSize(X.c, X.slot[k], &n) == fmi3OK && n <= SER_CAP &&
                fmi3SerializeFMUState(X.c, X.slot[k], X.ser, n) == fmi3OK)
                X.ser_n = n;
            break;
        }
        case 20: {
            if (!X.ser_n) break;
            static fmi3Byte buf[SER_CAP];
            memcpy(buf, X.ser, X.ser_n);
            size_t n = X.ser_n;
            const unsigned how = u8(r) % 3;
            if (how == 1) n = u16(r) % n;
            if (how == 2) buf[u16(r) % n] ^= (fmi3Byte)(1u << (u8(r) % 8));
            const int k = u8(r) & 1;
            st = fmi3DeserializeFMUState(X.c, buf, n, &X.slot[k]);
            break;
        }
        default: {
            const int on = u8(r) & 1;
            st = fmi3SetDebugLogging(X.c, on, 0, NULL);
            if (st == fmi3OK) X.silenced = !on;
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

#if defined(CHAIN_FUZZ_RANDOM_MAIN)
/* Pseudo-random inputs through the decoder (any compiler, no libFuzzer): a sanity sweep that runs in
 * every ctest. Inputs start with a plausible session prefix so that most of them reach stepping. */
int main(int argc, char **argv)
{
    const long count = argc > 1 ? atol(argv[1]) : 400;
    uint64_t s = 0x9e3779b97f4a7c15ULL;
    static uint8_t buf[1024];
    for (long k = 0; k < count; k++) {
        size_t n = 0;
        /* instantiate (event mode and early return as k says), configure n (1, 2, 3, 5, 8, 13) */
        buf[n++] = 0;
        buf[n++] = (uint8_t)(k & 0x1f);
        buf[n++] = 2;
        buf[n++] = 3;
        buf[n++] = 0;
        buf[n++] = (uint8_t)(k % 6);
        buf[n++] = 255; /* nValues 1 */
        buf[n++] = 5;
        if (k % 3) { /* initialise at t = 0 */
            buf[n++] = 6;
            buf[n++] = 0;
            buf[n++] = 0;
            buf[n++] = 0;
            buf[n++] = 7;
            if (k & 1) { /* event mode used: into step mode */
                buf[n++] = 15;
                buf[n++] = 2;
            }
        }
        static const size_t ns[6] = {1, 2, 3, 5, 8, 13};
        const size_t blocks_k = ns[k % 6], len = 64 + (size_t)(k % 8) * 96;
        while (n + 24 < len) {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            const unsigned pick = (unsigned)(s >> 40) % 9;
            if (pick < 4) { /* doStep at the FMU's time, dt 0.1 or 0.01 */
                buf[n++] = 12;
                buf[n++] = (pick & 1) ? 23 : 24;
                buf[n++] = 0;
            } else if (pick == 4 && n + blocks_k + 8 < sizeof buf) { /* an input array of n values */
                buf[n++] = 8;
                buf[n++] = 0;
                buf[n++] = (uint8_t)(10 + (s & 1)); /* F_ext, N_ext */
                buf[n++] = 255;
                buf[n++] = 100; /* a value from the next two bytes */
                buf[n++] = (uint8_t)(s >> 8);
                buf[n++] = (uint8_t)(s >> 16);
                for (size_t i = 0; i < blocks_k; i++) buf[n++] = 0;
            } else if (pick == 5) { /* event mode */
                buf[n++] = 15;
                buf[n++] = (uint8_t)(s >> 8);
            } else if (pick == 6) { /* FMU states */
                buf[n++] = (uint8_t)(17 + (s >> 8) % 4);
                buf[n++] = (uint8_t)(s >> 16);
                buf[n++] = (uint8_t)(s >> 24);
                buf[n++] = (uint8_t)(s >> 32);
            } else { /* anything */
                for (int b = 0; b < 4; b++) buf[n++] = (uint8_t)(s >> (8 * b + 3));
            }
        }
        LLVMFuzzerTestOneInput(buf, n);
    }
    printf("fuzz_chain3: %ld pseudo-random inputs, no oracle failed\n", count);
    return 0;
}
#endif
