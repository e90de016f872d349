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

#define FUZZ_NAME "fuzz_chain3"
#define FUZZ_FMI 3
#define FUZZ_MAX_CALLS 300
#define FUZZ_MAX_WORK 2e5 /* internal steps x blocks per doStep */
#define SER_CAP 16384
#define NBUF 64
#include "fuzz_common.h"

static fmi3ValueReference any_vr(reader *r)
{
    const unsigned sel = u8(r);
    if (sel < 230) return DFO_VARS[sel % DFO_NUM_VARS].vr;
    if (sel < 240) return DFO_VR_TIME;
    if (sel < 248) return DFO_VARS[sel % DFO_NUM_VARS].vr + 1 + (sel & 3); /* an FMI 2.0 element */
    return (fmi3ValueReference)u32(r);
}

static size_t blocks(const ctx *X)
{
    const fmi3ValueReference vn = VR_n;
    fmi3UInt64 n = 0;
    if (fmi3GetUInt64(X->c, &vn, 1, &n, 1) != fmi3OK) return 0;
    if (n < 1 || n > MAX_n) oracle_fail("n outside [1, 4096]");
    return (size_t)n;
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
    if (fmi3GetInt32(X->c, &vm, 1, m, n) != fmi3OK) return;
    for (size_t i = 0; i < n; i++)
        if (m[i] < -1 || m[i] > 1) oracle_fail("mode out of range");
    /* the friction oracle, with the parameters and the inputs read back */
    const fmi3ValueReference pv[4] = {VR_mu_s, VR_chi, VR_N, VR_N_ext};
    fmi3Float64 pr[4 * NBUF];
    if (fmi3GetFloat64(X->c, pv, 4, pr, 4 * n) != fmi3OK) return;
    if (fmi3GetFloat64(X->c, vr, 5, v, 4 * n + 1) != fmi3OK) return;
    for (size_t i = 0; i < n; i++)
        check_friction(m[i], v[3 * n + i], pr[i], pr[n + i], fmax(pr[2 * n + i] + pr[3 * n + i], 0.0));
}

static fmi3UInt64 any_n(reader *r)
{
    static const fmi3UInt64 ns[] = {1, 2, 3, 5, 8, 13, 1, 2, 0, 4097, 64, 4096};
    const unsigned sel = u8(r);
    if (sel < 240) return ns[sel % (sizeof ns / sizeof ns[0])];
    return (fmi3UInt64)u32(r) << (u8(r) % 33);
}

static fmi3Status call(ctx *X, reader *r, unsigned op)
{
    fmi3Status st = fmi3OK;
    switch (op) {
    case 0: return instantiate(X, r);
    case 1: free_all(X); break;
    case 2: st = fmi3EnterConfigurationMode(X->c); break;
    case 3: case 4: { /* n: valid, out of range, a wrong nValues */
        const fmi3ValueReference vr = (u8(r) < 240) ? VR_n : any_vr(r);
        const fmi3UInt64 n = any_n(r);
        st = fmi3SetUInt64(X->c, &vr, 1, &n, (u8(r) < 16) ? 2 : 1);
        break;
    }
    case 5: st = fmi3ExitConfigurationMode(X->c); break;
    case 6: return enter_initialization(X, r);
    case 7: st = fmi3ExitInitializationMode(X->c); break;
    case 8: case 9: { /* an array (or any variable) with n values, sometimes a wrong count */
        /* (arrays 1 ... 22: m ... N_ext, k_site, c_site, v_belt, v_s, delta among them) */
        const fmi3ValueReference vr = (u8(r) < 200) ? (fmi3ValueReference)DFO_ARRAY_VRS[u8(r) % DFO_NUM_ARRAYS]
                                                    : any_vr(r);
        const size_t n = blocks(X);
        size_t nv = n;
        if (u8(r) < 24) nv = u8(r) % 6;
        if (nv > NBUF) break;
        fmi3Float64 v[NBUF];
        const double base = real(r);
        for (size_t i = 0; i < nv; i++) v[i] = (u8(r) < 230) ? base : real(r);
        st = fmi3SetFloat64(X->c, &vr, 1, v, nv);
        break;
    }
    case 10: { /* scalars, the scheme and the friction law */
        if (u8(r) & 1) {
            const fmi3ValueReference vr = 2 + u8(r) % 4; /* k_end, c_end, omega, h */
            const fmi3Float64 v = real(r);
            st = fmi3SetFloat64(X->c, &vr, 1, &v, 1);
        } else {
            const unsigned sel = u8(r);
            const fmi3ValueReference vr = (sel < 160) ? VR_scheme : (sel < 230) ? VR_friction_law : any_vr(r);
            const fmi3Int64 v = (fmi3Int64)(u8(r) % 7) - 1;
            st = fmi3SetInt64(X->c, &vr, 1, &v, 1);
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
        case 0: st = fmi3GetFloat64(X->c, &vr, 1, d, nv); break;
        case 1: st = fmi3GetInt32(X->c, &vr, 1, i, nv); break;
        case 2: st = fmi3GetInt64(X->c, &vr, 1, l, nv); break;
        default: st = fmi3GetUInt64(X->c, &vr, 1, u, nv); break;
        }
        break;
    }
    case 12: case 13: case 14: { /* doStep */
        double dt = real(r);
        const double tc = (u8(r) < 230) ? X->t : real(r);
        const fmi3ValueReference vh = VR_h_used; /* the step used (h = 0: derived) */
        fmi3Float64 h = 0.0;
        const size_t n = blocks(X);
        if (fmi3GetFloat64(X->c, &vh, 1, &h, 1) == fmi3OK && h > 0.0 && n > 0 && isfinite(dt) &&
            dt > FUZZ_MAX_WORK / (double)n * h)
            dt = FUZZ_MAX_WORK / (double)n * h;
        fmi3Boolean ev = 7, term = 7, early = 7;
        fmi3Float64 last = NAN;
        st = fmi3DoStep(X->c, tc, dt, fmi3False, &ev, &term, &early, &last);
        if (st == fmi3OK) check_step(X, tc, dt, ev, early, last);
        break;
    }
    case 15: {
        switch (u8(r) % 3) {
        case 0: st = fmi3EnterEventMode(X->c); break;
        case 1: st = update_discrete_states(X); break;
        default: st = fmi3EnterStepMode(X->c); break;
        }
        break;
    }
    case 16: st = (u8(r) & 1) ? fmi3Terminate(X->c) : fmi3Reset(X->c); break;
    case 17: return get_state(X, r);
    case 18: return set_state(X, r);
    case 19: return serialize(X, r);
    case 20: return deserialize(X, r);
    default: return set_logging(X, r);
    }
    return st;
}

static const fuzz_target TARGET = {FUZZ_MAX_CALLS, 22, call, check_outputs, NULL};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) { return fuzz_drive(&TARGET, data, size); }

#if defined(CHAIN_FUZZ_RANDOM_MAIN)
/* Pseudo-random input k (any compiler, no libFuzzer): a sanity sweep that runs in every ctest.
 * Inputs start with a plausible session prefix so that most of them reach stepping. */
static size_t random_input(long k, uint64_t *s, uint8_t *buf)
{
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
        const uint64_t x = xorshift64(s);
        const unsigned pick = (unsigned)(x >> 40) % 9;
        if (pick < 4) { /* doStep at the FMU's time, dt 0.1 or 0.01 */
            buf[n++] = 12;
            buf[n++] = (pick & 1) ? 23 : 24;
            buf[n++] = 0;
        } else if (pick == 4 && n + blocks_k + 8 < FUZZ_RANDOM_LEN) { /* an input array of n values */
            buf[n++] = 8;
            buf[n++] = 0;
            buf[n++] = (uint8_t)(10 + (x & 1)); /* F_ext, N_ext */
            buf[n++] = 255;
            buf[n++] = 100; /* a value from the next two bytes */
            buf[n++] = (uint8_t)(x >> 8);
            buf[n++] = (uint8_t)(x >> 16);
            for (size_t i = 0; i < blocks_k; i++) buf[n++] = 0;
        } else if (pick == 5) { /* event mode */
            buf[n++] = 15;
            buf[n++] = (uint8_t)(x >> 8);
        } else if (pick == 6) { /* FMU states */
            n = put_state_op(buf, n, 17, x);
        } else if (pick == 7 && (x & 1)) { /* friction_law = stribeck (takes effect at a (re)start) */
            buf[n++] = 10;
            buf[n++] = 0;   /* the scheme branch */
            buf[n++] = 200; /* friction_law */
            buf[n++] = 3;   /* 3 % 7 - 1 = 2 */
        } else if (pick == 7 && n + blocks_k + 8 < FUZZ_RANDOM_LEN) { /* belts of n values */
            buf[n++] = 8;
            buf[n++] = 0;
            buf[n++] = 19; /* array 20: v_belt */
            buf[n++] = 255;
            buf[n++] = 100;
            buf[n++] = (uint8_t)(x >> 8);
            buf[n++] = (uint8_t)(x >> 16);
            for (size_t i = 0; i < blocks_k; i++) buf[n++] = 0;
        } else {
            n = put_any(buf, n, x);
        }
    }
    return n;
}

int main(int argc, char **argv) { return fuzz_random_main(argc, argv, 400, 0x9e3779b97f4a7c15ULL, random_input); }
#endif
