/* libFuzzer target over the FMI 2.0 entry points of the DryFrictionOscillator FMU.
 *
 * The input bytes are decoded into a sequence of FMI calls: instantiate / free, setup, enter and
 * exit initialisation, set and get of every variable (and of unknown value references) with
 * special values (NaN, inf, huge, tiny, negative) or raw bytes, doStep with the right or a wrong
 * communication point and any step size, terminate, reset, FMU state get/set/free, serialise and
 * deserialise (intact, truncated, a byte flipped, or a field forged with the checksum fixed up),
 * debug logging, status queries. Calls out of order are part of the game.
 *
 * Besides ASan/UBSan, the target checks these oracles and aborts when one fails:
 *   - an fmi2Error of a live instance comes with a logged message (while error logging is on);
 *   - outputs read with fmi2OK or fmi2Warning (an observable read while observe is false) are
 *     finite, mode is -1, 0 or +1, and mode 0 means v == v_belt (every scheme, exact included: a
 *     stuck block rides on the belt; until the step after a change of v_belt, the last step's belt);
 *   - outputs read right after an input is set (direct feedthrough of a and F_friction) are finite;
 *   - output and directional derivatives read with fmi2OK are finite, x and v have no feed-through;
 *   - after an fmi2OK doStep the FMU's time (fmi2LastSuccessfulTime) is exactly tc + dt
 *     (FUZZ_TIME_ORACLE, on by default; -DFUZZ_TIME_ORACLE=0 to explore past it).
 * A doStep that would take more than FUZZ_MAX_STEPS internal steps of the step used h, counted from
 * the FMU's time, is shortened to that many (a communication point far ahead of that time is
 * replaced by it), so that long but legal runs do not read as hangs.
 *
 * Built by tests/fuzz/CMakeLists.txt (clang, -fsanitize=fuzzer) and, with tests/fuzz/replay_main.c,
 * by tests/fmi_c/CMakeLists.txt as the ctest replay of the corpus and the regression inputs. */
#include "fmi2Functions.h"
#include "model_vars.h"

#define FUZZ_NAME "fuzz_fmi"
#define FUZZ_FMI 2
#ifndef FUZZ_TIME_ORACLE
#define FUZZ_TIME_ORACLE 1
#endif
#ifndef FUZZ_MAX_STEPS
#define FUZZ_MAX_STEPS 20000.0
#endif
#define FUZZ_MAX_CALLS 400
#define SER_CAP 4096
#define SERIAL_HEADER 32 /* magic[8], version, size, checksum (bytes 16..23, of the bytes from 24 on), model hash */
#include "fuzz_common.h"

#include <limits.h>

/* this target's reals: its own special values, fewer ordinary ones */
static double any_real(reader *r)
{
    static const double special[] = {0.0, -0.0, 1.0, -1.0, 0.5, 1e-3, 1e-300, -1e-300, 1e300, -1e300,
                                     NAN, INFINITY, -INFINITY, DBL_MIN, DBL_MAX, 1e-12, 1e6, 1e15, 2.0, 100.0,
                                     -1.0 / 3.0, -0.1, 0.7, 3.0, 0.4, 5.0, 1e-9, 4.9e-324};
    return real_from(r, special, sizeof special / sizeof special[0], 224);
}

static int integer(reader *r)
{
    static const int special[] = {-1, 0, 1, 2, 3, 4, 100, 101, INT_MAX, INT_MIN};
    const unsigned sel = u8(r);
    if (sel < 200) return special[sel % 10];
    return (int)u32(r);
}

static fmi2ValueReference any_vr(reader *r)
{
    const unsigned sel = u8(r);
    if (sel < 240) return DFO_VARS[sel % DFO_NUM_VARS].vr;
    return (fmi2ValueReference)u32(r);
}

#define TRACE(X, ...) \
    do { \
        if ((X)->trace) fprintf(stderr, __VA_ARGS__); \
    } while (0)

static void check_outputs(ctx *X)
{
    static const fmi2ValueReference vr[] = {VR_x, VR_v, VR_a, VR_F_friction, VR_x_max, VR_x_min, VR_stick_fraction,
                                            VR_E_friction};
    double out[sizeof vr / sizeof vr[0]];
    const size_t n = sizeof vr / sizeof vr[0];
    if (fmi2GetReal(X->c, vr, n, out) <= fmi2Warning) {
        for (size_t i = 0; i < n; i++)
            if (!fuzz_finite_or_not_computed(vr[i], out[i])) {
                TRACE(X, "  output %u = %g\n", (unsigned)vr[i], out[i]);
                oracle_fail("non-finite output with fmi2OK");
            }
        const fmi2ValueReference vm = VR_mode;
        fmi2Integer mode = 0;
        if (fmi2GetInteger(X->c, &vm, 1, &mode) <= fmi2Warning) {
            if (mode < -1 || mode > 1) oracle_fail("mode outside -1, 0, +1");
            /* stuck: v is the belt's speed (a v_belt set since the last step starts a slide at
             * the next one, the block keeping its velocity: either speed may be read until then) */
            const fmi2ValueReference vb = VR_v_belt;
            fmi2Real v_belt = 0.0;
            if (mode == 0 && fmi2GetReal(X->c, &vb, 1, &v_belt) <= fmi2Warning && out[1] != v_belt &&
                out[1] != X->v_belt_stepped)
                oracle_fail("mode 0 (stuck) with v != v_belt");
        }
    }
}

/* The coupling functions at the current point (no input bytes read: the corpus keeps its meaning):
 * output derivatives of x and v, directional derivatives of x, v, a, F_friction with respect to
 * F_ext and N_ext (finite with fmi2OK; x and v none), and a slope of F_ext (the current x) for the
 * next step. Each call's status passes the status oracle (an error comes with its sentence). */
static void check_coupling(ctx *X)
{
    const fmi2ValueReference ov[4] = {VR_x, VR_x, VR_v, VR_v}, unk[4] = {VR_x, VR_v, VR_a, VR_F_friction};
    const fmi2ValueReference kn[2] = {VR_F_ext, VR_N_ext};
    const fmi2Integer orders[4] = {1, 2, 1, 2};
    double d[4], J[4];
    long before = X->errors_logged;
    fmi2Status st = fmi2GetRealOutputDerivatives(X->c, ov, 4, orders, d);
    if (st == fmi2OK)
        for (int i = 0; i < 4; i++)
            if (!isfinite(d[i])) oracle_fail("non-finite output derivative with fmi2OK");
    after(X, st, before);
    const double seed[2] = {1.0, -0.5};
    before = X->errors_logged;
    st = fmi2GetDirectionalDerivative(X->c, unk, 4, kn, 2, seed, J);
    if (st == fmi2OK) {
        if (J[0] != 0.0 || J[1] != 0.0) oracle_fail("x or v with a direct feed-through");
        if (!isfinite(J[2]) || !isfinite(J[3])) oracle_fail("non-finite directional derivative with fmi2OK");
    }
    after(X, st, before);
    const fmi2ValueReference vx = VR_x;
    const fmi2Integer one = 1;
    double x = 0.0;
    if (fmi2GetReal(X->c, &vx, 1, &x) == fmi2OK && isfinite(x)) {
        before = X->errors_logged;
        after(X, fmi2SetRealInputDerivatives(X->c, &kn[0], 1, &one, &x), before);
    }
}

static uint64_t fnv1a(const fmi2Byte *p, size_t n)
{
    uint64_t h = 1469598103934665603ULL;
    for (size_t i = 0; i < n; i++) {
        h ^= (unsigned char)p[i];
        h *= 1099511628211ULL;
    }
    return h;
}

static void op(ctx *X, reader *r)
{
    const unsigned code = u8(r) % 20;
    const long before = X->errors_logged;
    fmi2Status st = fmi2OK;
    switch (code) {
    case 0: { /* (re-)instantiate */
        TRACE(X, "fmi2FreeInstance + fmi2Instantiate\n");
        free_all(X);
        X->silenced = 0;
        X->c = fmi2Instantiate(u8(r) & 1 ? "fuzz" : "f", fmi2CoSimulation, MODEL_GUID, "", &X->cb, fmi2False,
                               (fmi2Boolean)(u8(r) & 1));
        if (!X->c) oracle_fail("fmi2Instantiate failed with valid arguments");
        X->t = 0.0;
        return;
    }
    case 1: {
        const unsigned f = u8(r);
        const double start = (f & 4) ? any_real(r) : 0.0, stop = (f & 2) ? any_real(r) : 0.0;
        TRACE(X, "fmi2SetupExperiment(start %.17g, stopDefined %u, stop %.17g)\n", start, (f >> 1) & 1, stop);
        st = fmi2SetupExperiment(X->c, (fmi2Boolean)(f & 1), 1e-6, start, (fmi2Boolean)((f >> 1) & 1), stop);
        if (st == fmi2OK) X->t = start;
        break;
    }
    case 2:
        TRACE(X, "fmi2EnterInitializationMode\n");
        st = fmi2EnterInitializationMode(X->c);
        break;
    case 3:
        TRACE(X, "fmi2ExitInitializationMode\n");
        st = fmi2ExitInitializationMode(X->c);
        if (st == fmi2OK) check_outputs(X);
        break;
    case 4: {
        fmi2ValueReference vr[3];
        double v[3];
        const size_t n = 1 + u8(r) % 3;
        for (size_t i = 0; i < n; i++) {
            vr[i] = any_vr(r);
            v[i] = any_real(r);
        }
        for (size_t i = 0; i < n; i++) TRACE(X, "fmi2SetReal(vr %u = %.17g)\n", (unsigned)vr[i], v[i]);
        st = fmi2SetReal(X->c, vr, n, v);
        if (st == fmi2OK && X->c) check_outputs(X); /* a and F_friction follow the inputs at once */
        break;
    }
    case 5: {
        const fmi2ValueReference vr = any_vr(r);
        const fmi2Integer v = integer(r);
        TRACE(X, "fmi2SetInteger(vr %u = %d)\n", (unsigned)vr, (int)v);
        st = fmi2SetInteger(X->c, &vr, 1, &v);
        break;
    }
    case 6: {
        const fmi2ValueReference vr = any_vr(r);
        const fmi2Boolean v = (fmi2Boolean)(u8(r) % 3);
        TRACE(X, "fmi2SetBoolean(vr %u = %d)\n", (unsigned)vr, (int)v);
        st = fmi2SetBoolean(X->c, &vr, 1, &v);
        break;
    }
    case 7: { /* doStep */
        const unsigned f = u8(r);
        double tc = X->t, dt;
        if (f & 1) tc = any_real(r);
        if (f & 2) dt = any_real(r);
        else dt = (double)(1 + u16(r)) * 1e-4;
        const fmi2ValueReference vh = VR_h_used; /* the step used (h = 0: derived) */
        double h = 0.0;
        if (X->c && isfinite(dt) && dt > 0.0 && fmi2GetReal(X->c, &vh, 1, &h) == fmi2OK && h > 0.0) {
            /* a tc the FMU takes for its own time (within its tolerance) still steps from its time:
             * the steps are counted from there, and a tc that far ahead is replaced by the time */
            if (isfinite(tc) && (tc - X->t) / h > FUZZ_MAX_STEPS / 2) tc = X->t;
            const double ahead = isfinite(tc) && tc > X->t ? tc - X->t : 0.0;
            if ((ahead + dt) / h > FUZZ_MAX_STEPS) dt = FUZZ_MAX_STEPS * h - ahead;
        }
        TRACE(X, "fmi2DoStep(%.17g, %.17g)\n", tc, dt);
        st = fmi2DoStep(X->c, tc, dt, (fmi2Boolean)((f >> 2) & 1));
        if (st == fmi2OK) {
            double t = NAN;
            if (fmi2GetRealStatus(X->c, fmi2LastSuccessfulTime, &t) != fmi2OK) oracle_fail("no last time");
            if (FUZZ_TIME_ORACLE && t != tc + dt) oracle_fail("time after doStep is not tc + dt");
            X->t = t;
            const fmi2ValueReference vb = VR_v_belt;
            if (fmi2GetReal(X->c, &vb, 1, &X->v_belt_stepped) > fmi2Warning) X->v_belt_stepped = NAN;
            check_outputs(X);
        }
        break;
    }
    case 8: {
        fmi2ValueReference vr[DFO_NUM_VARS];
        double v[DFO_NUM_VARS];
        size_t n = 0;
        for (int i = 0; i < DFO_NUM_VARS; i++)
            if (DFO_VARS[i].type == DFO_REAL) vr[n++] = DFO_VARS[i].vr;
        TRACE(X, "fmi2GetReal(all Real variables)\n");
        st = fmi2GetReal(X->c, vr, n, v);
        if (st <= fmi2Warning)
            for (size_t i = 0; i < n; i++)
                if (!fuzz_finite_or_not_computed(vr[i], v[i]) && vr[i] != VR_t_obs_stop) oracle_fail("non-finite Real with fmi2OK");
        break;
    }
    case 9: {
        const fmi2ValueReference vr = any_vr(r);
        fmi2Integer i = 0;
        fmi2Boolean b = 0;
        st = (u8(r) & 1) ? fmi2GetInteger(X->c, &vr, 1, &i) : fmi2GetBoolean(X->c, &vr, 1, &b);
        break;
    }
    case 10:
        TRACE(X, "fmi2Terminate\n");
        st = fmi2Terminate(X->c);
        break;
    case 11:
        TRACE(X, "fmi2Reset\n");
        st = fmi2Reset(X->c);
        if (st == fmi2OK) X->t = 0.0;
        break;
    case 12: {
        const unsigned k = u8(r) & 1;
        TRACE(X, "fmi2GetFMUstate(slot %u)\n", k);
        st = fmi2GetFMUstate(X->c, &X->slot[k]);
        break;
    }
    case 13: {
        const unsigned k = u8(r) & 1;
        TRACE(X, "fmi2SetFMUstate(slot %u)\n", k);
        st = fmi2SetFMUstate(X->c, X->slot[k]);
        double t = 0.0;
        if (st == fmi2OK && fmi2GetRealStatus(X->c, fmi2LastSuccessfulTime, &t) == fmi2OK) X->t = t;
        break;
    }
    case 14: {
        const unsigned k = u8(r) & 1;
        TRACE(X, "fmi2FreeFMUstate(slot %u)\n", k);
        st = fmi2FreeFMUstate(X->c, &X->slot[k]);
        break;
    }
    case 15: {
        const unsigned k = u8(r) & 1;
        const fmi2FMUstate s = X->slot[k];
        TRACE(X, "fmi2SerializeFMUstate(slot %u)\n", k);
        size_t n = 0;
        st = fmi2SerializedFMUstateSize(X->c, s, &n);
        if (st == fmi2OK && n <= SER_CAP) {
            st = fmi2SerializeFMUstate(X->c, s, X->ser, n);
            X->ser_n = st == fmi2OK ? n : 0;
        }
        break;
    }
    case 16: { /* deserialise, possibly damaged or forged */
        fmi2Byte buf[SER_CAP];
        size_t n = X->ser_n;
        memcpy(buf, X->ser, n);
        const unsigned how = u8(r) % 5;
        if (how == 1) n = n ? u16(r) % n : 0;
        if (how == 2 && n) {
            const size_t at = u16(r) % n;
            buf[at] = (fmi2Byte)(buf[at] ^ (1 + u8(r) % 255));
        }
        if ((how == 3 || how == 4) && n >= SERIAL_HEADER + 8) {
            const size_t at = SERIAL_HEADER + 8 * (u16(r) % ((n - SERIAL_HEADER) / 8));
            const double v = any_real(r);
            memcpy(buf + at, &v, sizeof v);
            TRACE(X, "  forged payload double at byte %lu = %.17g\n", (unsigned long)at, v);
            if (how == 3) {
                const uint64_t h = fnv1a(buf + 24, n - 24);
                memcpy(buf + 16, &h, sizeof h);
            }
        }
        const unsigned k = u8(r) & 1;
        TRACE(X, "fmi2DeSerializeFMUstate(%lu bytes, damage %u, slot %u)\n", (unsigned long)n, how, k);
        st = fmi2DeSerializeFMUstate(X->c, buf, n, &X->slot[k]);
        break;
    }
    case 17: {
        static const char *const names[] = {"logStatusError", "logStatusWarning", "logEvents", "logAll", "bogus"};
        const unsigned f = u8(r);
        const fmi2Boolean on = (fmi2Boolean)(f & 1);
        const char *cats[2] = {names[(f >> 1) % 5], names[(f >> 4) % 5]};
        const size_t nc = (f >> 7) ? 2 : (f & 2) ? 1 : 0;
        TRACE(X, "fmi2SetDebugLogging(%d, %lu categories)\n", (int)on, (unsigned long)nc);
        st = fmi2SetDebugLogging(X->c, on, nc, cats);
        if (st == fmi2OK && !on) {
            if (nc == 0) X->silenced = 1;
            for (size_t i = 0; i < nc; i++)
                if (!strcmp(cats[i], "logStatusError")) X->silenced = 1;
        }
        if (st == fmi2OK && on) {
            if (nc == 0) X->silenced = 0;
            for (size_t i = 0; i < nc; i++)
                if (!strcmp(cats[i], "logStatusError")) X->silenced = 0;
        }
        break;
    }
    case 18: {
        double t;
        fmi2Status s2;
        st = fmi2GetRealStatus(X->c, (fmi2StatusKind)(u8(r) % 5), &t);
        after(X, st, before);
        st = fmi2GetStatus(X->c, fmi2DoStepStatus, &s2);
        break;
    }
    default: {
        TRACE(X, "outputs, coupling, fmi2CancelStep\n");
        check_outputs(X);
        check_coupling(X);
        st = fmi2CancelStep(X->c);
        break;
    }
    }
    after(X, st, before);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static ctx X; /* SER_CAP bytes: not on the stack */
    ctx_init(&X);
    X.trace = getenv("FUZZ_TRACE") != NULL;
    X.c = fmi2Instantiate("fuzz", fmi2CoSimulation, MODEL_GUID, "", &X.cb, fmi2False, fmi2False);
    if (!X.c) oracle_fail("fmi2Instantiate failed with valid arguments");
    reader r = {data, size, 0};
    for (int k = 0; k < FUZZ_MAX_CALLS && r.i < r.n; k++) op(&X, &r);
    free_all(&X);
    return 0;
}
