/* libFuzzer target over the FMI 2.0 entry points of the DryFrictionChain FMU (n fixed by the build,
 * DFO_CHAIN_N; elements m[i] reached through the array's value reference + i).
 *
 * The input bytes are decoded into a sequence of FMI 2.0 calls: instantiate / free, setup,
 * initialisation, fmi2SetReal / fmi2GetReal of elements (i = 0 ... n + 1, so one below and one
 * beyond the range), of the arrays' own value references (unknown in FMI 2.0) and of the scalars,
 * the scheme (4 included), doStep with the right or a wrong communication point, terminate, reset,
 * FMU states get/set/free, serialise and deserialise (intact, truncated, a byte flipped), logging.
 *
 * Oracles (abort when one fails): an fmi2Error of a live instance comes with a logged message;
 * outputs read with fmi2OK are finite and every mode is -1, 0 or +1; an fmi2OK doStep ends at
 * tc + dt (fmi2GetRealStatus fmi2LastSuccessfulTime).
 *
 * Replayed by ctest (tests/fmi_c: fmi2_chain_fuzz_random, 300 pseudo-random inputs through the same
 * decoder, CHAIN_FUZZ_RANDOM_MAIN); a libFuzzer build is tests/fuzz/CMakeLists.txt's fuzz_chain2. */
#include "fmi2Functions.h"
#include "model_vars.h"

#define FUZZ_NAME "fuzz_chain2"
#define FUZZ_FMI 2
#define FUZZ_MAX_CALLS 300
#define FUZZ_MAX_WORK 2e5 /* internal steps x blocks per doStep */
#define SER_CAP 65536
#include "fuzz_common.h"

/* An element of an array (i = 0 ... n + 1), an array's own reference, a scalar, or anything. */
static fmi2ValueReference any_vr(reader *r)
{
    const unsigned sel = u8(r);
    const dfo_var_info *var = &DFO_VARS[u8(r) % DFO_NUM_VARS];
    if (sel < 200 && var->array) return var->vr + (u8(r) % (DFO_CHAIN_N + 2));
    if (sel < 240) return var->vr;
    return (fmi2ValueReference)u32(r);
}


static void check_outputs(ctx *X)
{
    const unsigned outs[4] = {VR_x, VR_v, VR_a, VR_F_friction};
    for (int j = 0; j < 4; j++)
        for (unsigned i = 1; i <= DFO_CHAIN_N; i++) {
            const fmi2ValueReference vr = outs[j] + i;
            fmi2Real v;
            if (fmi2GetReal(X->c, &vr, 1, &v) == fmi2OK && !isfinite(v)) oracle_fail("an output read with OK is not finite");
        }
    for (unsigned i = 1; i <= DFO_CHAIN_N; i++) {
        const fmi2ValueReference vr = VR_mode + i;
        fmi2Integer m;
        if (fmi2GetInteger(X->c, &vr, 1, &m) != fmi2OK) continue;
        if (m < -1 || m > 1) oracle_fail("mode out of range");
        const fmi2ValueReference pv[5] = {VR_mu_s + i, VR_chi + i, VR_N + i, VR_N_ext + i, VR_F_friction + i};
        fmi2Real p[5];
        if (fmi2GetReal(X->c, pv, 5, p) == fmi2OK) check_friction(m, p[4], p[0], p[1], fmax(p[2] + p[3], 0.0));
    }
}

static fmi2Status call(ctx *X, reader *r, unsigned op)
{
    fmi2Status st = fmi2OK;
    switch (op) {
    case 0: {
        free_all(X);
        const unsigned f = u8(r);
        X->silenced = 0;
        X->t = 0.0;
        X->c = fmi2Instantiate((f & 64) ? "" : "fuzz", (f & 32) ? fmi2ModelExchange : fmi2CoSimulation,
                               (f & 128) ? "{wrong}" : MODEL_GUID, NULL, &X->cb, fmi2False, f & 1);
        break;
    }
    case 1: free_all(X); break;
    case 2: {
        const double t0 = (u8(r) & 1) ? real(r) : 0.0;
        st = fmi2SetupExperiment(X->c, fmi2False, 0.0, t0, u8(r) & 1, real(r));
        if (st == fmi2OK) X->t = t0;
        break;
    }
    case 3: st = fmi2EnterInitializationMode(X->c); break;
    case 4: st = fmi2ExitInitializationMode(X->c); break;
    case 5: case 6: { /* set reals: one or two */
        fmi2ValueReference vr[2] = {any_vr(r), any_vr(r)};
        const fmi2Real v[2] = {real(r), real(r)};
        st = fmi2SetReal(X->c, vr, 1 + (u8(r) & 1), v);
        break;
    }
    case 7: {
        const fmi2ValueReference vr = (u8(r) < 220) ? VR_scheme : any_vr(r);
        const fmi2Integer v = (fmi2Integer)(u8(r) % 7) - 1;
        st = fmi2SetInteger(X->c, &vr, 1, &v);
        break;
    }
    case 8: {
        const fmi2ValueReference vr = any_vr(r);
        fmi2Real d;
        fmi2Integer i;
        fmi2Boolean b;
        switch (u8(r) % 3) {
        case 0: st = fmi2GetReal(X->c, &vr, 1, &d); break;
        case 1: st = fmi2GetInteger(X->c, &vr, 1, &i); break;
        default: st = fmi2GetBoolean(X->c, &vr, 1, &b); break;
        }
        break;
    }
    case 9: case 10: case 11: {
        double dt = real(r);
        const double tc = (u8(r) < 230) ? X->t : real(r);
        const fmi2ValueReference vh = VR_h_used; /* the step used (h = 0: derived) */
        fmi2Real h = 0.0;
        if (fmi2GetReal(X->c, &vh, 1, &h) == fmi2OK && h > 0.0 && isfinite(dt) &&
            dt > FUZZ_MAX_WORK / DFO_CHAIN_N * h)
            dt = FUZZ_MAX_WORK / DFO_CHAIN_N * h;
        st = fmi2DoStep(X->c, tc, dt, fmi2True);
        if (st == fmi2OK) {
            fmi2Real last = NAN;
            if (fmi2GetRealStatus(X->c, fmi2LastSuccessfulTime, &last) == fmi2OK && last != tc + dt)
                oracle_fail("lastSuccessfulTime is not tc + dt");
            X->t = tc + dt;
        }
        break;
    }
    case 12: st = (u8(r) & 1) ? fmi2Terminate(X->c) : fmi2Reset(X->c); break;
    case 13: st = fmi2GetFMUstate(X->c, &X->slot[u8(r) & 1]); break;
    case 14: {
        st = fmi2SetFMUstate(X->c, X->slot[u8(r) & 1]);
        if (st == fmi2OK) {
            fmi2Real t;
            if (fmi2GetRealStatus(X->c, fmi2LastSuccessfulTime, &t) == fmi2OK) X->t = t;
        }
        break;
    }
    case 15: return serialize(X, r);
    case 16: return deserialize(X, r);
    default: return set_logging(X, r);
    }
    return st;
}

static const fuzz_target TARGET = {FUZZ_MAX_CALLS, 18, call, check_outputs};

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) { return fuzz_drive(&TARGET, data, size); }

#if defined(CHAIN_FUZZ_RANDOM_MAIN)
/* Pseudo-random input k (any compiler, no libFuzzer), after a plausible start (instantiate, setup,
 * initialise) so that most reach stepping. */
static size_t random_input(long k, uint64_t *s, uint8_t *buf)
{
    size_t n = 0;
    const uint8_t start[] = {0, (uint8_t)(k & 1), 2, 0, 0, 0, 3, 4};
    memcpy(buf, start, sizeof start);
    n = (k % 4) ? sizeof start : 2;
    const size_t len = 64 + (size_t)(k % 8) * 96;
    while (n + 16 < len) {
        const uint64_t x = xorshift64(s);
        const unsigned pick = (unsigned)(x >> 40) % 8;
        if (pick < 3) { /* doStep at the FMU's time, dt 0.1 or 0.01 */
            buf[n++] = 9;
            buf[n++] = (pick & 1) ? 23 : 24;
            buf[n++] = 0;
        } else if (pick == 3) { /* an input element */
            const uint8_t set[] = {5,
                                   0, (uint8_t)(17 + (x & 1)), (uint8_t)(x >> 8), /* F_ext[i] or N_ext[i] */
                                   0, 1,                                          /* k_end (not sent) */
                                   100, (uint8_t)(x >> 16), (uint8_t)(x >> 24),   /* its value */
                                   0,                                             /* k_end's */
                                   0};                                            /* one value */
            memcpy(buf + n, set, sizeof set);
            n += sizeof set;
        } else if (pick == 4) { /* FMU states */
            n = put_state_op(buf, n, 13, x);
        } else {
            n = put_any(buf, n, x);
        }
    }
    return n;
}

int main(int argc, char **argv) { return fuzz_random_main(argc, argv, 300, 0x2545F4914F6CDD1DULL, random_input); }
#endif
