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
 * outputs read with fmi3OK/fmi3Warning are finite and mode is -1, 0 or +1; output and directional
 * derivatives read with fmi3OK are finite, x and v have no feed-through, the adjoint is the
 * transposed directional derivative; a parameter set in the intermediate update is refused; after an fmi3OK doStep
 * the last successful time lies in (tc, tc + dt], is tc + dt unless earlyReturn, and earlyReturn and
 * eventHandlingNeeded only come when allowed (earlyReturnAllowed; eventModeUsed with it).
 *
 * Built by tests/fuzz/CMakeLists.txt (clang, -fsanitize=fuzzer) and, with replay_main.c, by
 * tests/fmi3_c/CMakeLists.txt as the ctest replay of tests/fuzz/corpus3. */
#include "fmi3Functions.h"
#include "model_vars.h"

#define FUZZ_NAME "fuzz_fmi3"
#define FUZZ_FMI 3
#define FUZZ_MAX_CALLS 400
#define FUZZ_MAX_STEPS 20000.0
#define SER_CAP 4096
#include "fuzz_common.h"

static fmi3ValueReference any_vr(reader *r)
{
    const unsigned sel = u8(r);
    if (sel < 230) return DFO_VARS[sel % DFO_NUM_VARS].vr;
    if (sel < 245) return DFO_VR_TIME;
    return (fmi3ValueReference)u32(r);
}

/* read in the intermediate update: x is finite; a parameter cannot be set there (an input declared
 * intermediateUpdate="true" only where the update asks for inputs: F_ext set to its own value) */
static void update_get(ctx *X)
{
    const fmi3ValueReference vr = VR_x, vm = VR_m, vf = VR_F_ext;
    fmi3Float64 x, f, m = 1.0;
    if (fmi3GetFloat64(X->c, &vr, 1, &x, 1) == fmi3OK && !isfinite(x)) oracle_fail("x not finite in update");
    if (fmi3SetFloat64(X->c, &vm, 1, &m, 1) != fmi3Error) oracle_fail("a parameter was set in the update");
    if (fmi3GetFloat64(X->c, &vf, 1, &f, 1) == fmi3OK) (void)fmi3SetFloat64(X->c, &vf, 1, &f, 1);
}

static void check_outputs(ctx *X)
{
    const fmi3ValueReference vr[9] = {VR_x, VR_v, VR_a, VR_F_friction, VR_x_max, VR_x_min, VR_stick_fraction,
                                      VR_E_friction, DFO_VR_TIME};
    fmi3Float64 v[9];
    const fmi3Status st = fmi3GetFloat64(X->c, vr, 9, v, 9);
    if (st == fmi3OK || st == fmi3Warning)
        for (int i = 0; i < 9; i++)
            if (!fuzz_finite_or_not_computed(vr[i], v[i])) oracle_fail("an output read with OK is not finite");
    const fmi3ValueReference vm = VR_mode;
    fmi3Int32 m;
    if (fmi3GetInt32(X->c, &vm, 1, &m, 1) == fmi3OK && (m < -1 || m > 1)) oracle_fail("mode out of range");
    /* the coupling functions: finite with OK, x and v without feed-through, the adjoint transposed */
    const fmi3ValueReference ov[4] = {VR_x, VR_x, VR_v, VR_v}, unk[4] = {VR_x, VR_v, VR_a, VR_F_friction};
    const fmi3ValueReference kn[2] = {VR_F_ext, VR_N_ext};
    const fmi3Int32 orders[4] = {1, 2, 1, 2};
    fmi3Float64 d[4], J[4], A[2];
    if (fmi3GetOutputDerivatives(X->c, ov, 4, orders, d, 4) == fmi3OK)
        for (int i = 0; i < 4; i++)
            if (!isfinite(d[i])) oracle_fail("an output derivative read with OK is not finite");
    const fmi3Float64 seed[2] = {1.0, 0.0}, seed_a[4] = {0.0, 0.0, 1.0, 0.0};
    if (fmi3GetDirectionalDerivative(X->c, unk, 4, kn, 2, seed, 2, J, 4) == fmi3OK) {
        if (J[0] != 0.0 || J[1] != 0.0) oracle_fail("x or v with a direct feed-through");
        if (fmi3GetAdjointDerivative(X->c, unk, 4, kn, 2, seed_a, 4, A, 2) == fmi3OK && A[0] != J[2])
            oracle_fail("the adjoint is not the transposed directional derivative");
    }
}

static fmi3Status call(ctx *X, reader *r, unsigned op)
{
    fmi3Status st = fmi3OK;
    switch (op) {
    case 0: return instantiate(X, r);
    case 1: free_all(X); break;
    case 2: return enter_initialization(X, r);
    case 3: st = fmi3ExitInitializationMode(X->c); break;
    case 4: case 5: { /* set Float64, sometimes a wrong nValues */
        fmi3ValueReference vr[2] = {any_vr(r), any_vr(r)};
        fmi3Float64 v[2] = {real(r), real(r)};
        const size_t n = 1 + (u8(r) & 1);
        st = fmi3SetFloat64(X->c, vr, n, v, (u8(r) < 16) ? n + 1 : n);
        break;
    }
    case 6: {
        fmi3ValueReference vr = any_vr(r);
        fmi3Int32 v = (fmi3Int32)u32(r);
        if (u8(r) < 200) v = (int)(u8(r) % 8) - 2;
        st = fmi3SetInt32(X->c, &vr, 1, &v, 1);
        break;
    }
    case 7: {
        fmi3ValueReference vr = any_vr(r);
        fmi3Int64 v = (u8(r) < 200) ? (fmi3Int64)(u8(r) % 8) - 2 : (fmi3Int64)u32(r) << 20;
        st = fmi3SetInt64(X->c, &vr, 1, &v, 1);
        break;
    }
    case 8: {
        fmi3ValueReference vr = any_vr(r);
        fmi3Boolean v = u8(r) & 1;
        st = fmi3SetBoolean(X->c, &vr, 1, &v, 1);
        break;
    }
    case 9: case 10: { /* get of any kind */
        fmi3ValueReference vr = any_vr(r);
        fmi3Float64 d;
        fmi3Int32 i;
        fmi3Int64 l;
        fmi3Boolean b;
        switch (u8(r) % 4) {
        case 0: st = fmi3GetFloat64(X->c, &vr, 1, &d, 1); break;
        case 1: st = fmi3GetInt32(X->c, &vr, 1, &i, 1); break;
        case 2: st = fmi3GetInt64(X->c, &vr, 1, &l, 1); break;
        default: st = fmi3GetBoolean(X->c, &vr, 1, &b, 1); break;
        }
        break;
    }
    case 11: case 12: case 13: { /* doStep */
        double dt = real(r);
        double tc = (u8(r) < 230) ? X->t : real(r);
        const fmi3ValueReference vh = VR_h_used; /* the step used (h = 0: derived) */
        fmi3Float64 h = 0.0;
        if (fmi3GetFloat64(X->c, &vh, 1, &h, 1) == fmi3OK && h > 0.0 && isfinite(dt)) {
            /* the steps counted from the FMU's time (a tc it takes for its time still steps from it) */
            if (isfinite(tc) && (tc - X->t) / h > FUZZ_MAX_STEPS / 2) tc = X->t;
            const double ahead = isfinite(tc) && tc > X->t ? tc - X->t : 0.0;
            if ((ahead + dt) / h > FUZZ_MAX_STEPS) dt = FUZZ_MAX_STEPS * h - ahead;
        }
        fmi3Boolean ev = 7, term = 7, early = 7;
        fmi3Float64 last = NAN;
        st = fmi3DoStep(X->c, tc, dt, fmi3False, &ev, &term, &early, &last);
        if (st == fmi3OK) check_step(X, tc, dt, ev, early, last);
        break;
    }
    case 14: st = fmi3EnterEventMode(X->c); break;
    case 15: return update_discrete_states(X);
    case 16: st = fmi3EnterStepMode(X->c); break;
    case 17: st = (u8(r) & 1) ? fmi3Terminate(X->c) : fmi3Reset(X->c); break;
    case 18: return get_state(X, r);
    case 19: return set_state(X, r);
    case 20: return serialize(X, r);
    case 21: return deserialize(X, r);
    case 22: { /* what the FMU lacks */
        fmi3Float32 f;
        fmi3ValueReference vr = any_vr(r);
        size_t nd;
        switch (u8(r) % 4) {
        case 0: st = fmi3GetFloat32(X->c, &vr, 1, &f, 1); break;
        case 1: st = fmi3EnterContinuousTimeMode(X->c); break;
        case 2: st = fmi3GetNumberOfVariableDependencies(X->c, vr, &nd); break;
        default: st = fmi3EnterConfigurationMode(X->c); break;
        }
        if (st != fmi3Error) oracle_fail("an unsupported function did not fail");
        break;
    }
    default: return set_logging(X, r);
    }
    return st;
}

static const fuzz_target TARGET = {FUZZ_MAX_CALLS, 24, call, check_outputs, update_get};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) { return fuzz_drive(&TARGET, data, size); }
