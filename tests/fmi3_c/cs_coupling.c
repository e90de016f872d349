/* FMI 3.0 host, the coupling functions (fmi3GetOutputDerivatives, fmi3GetDirectionalDerivative,
 * fmi3GetAdjointDerivative): NULL arrays and counts refused with a sentence, the phases they may be
 * called in, the adjoint the transposed directional derivatives (bit for bit) in a sliding and a
 * stuck state, and the inputs declared intermediateUpdate="true" (and only those) settable from the
 * callback where it is called with intermediateVariableSetRequested. */
#include "host3.h"

static int has(const host_env *E, const char *part) { return strstr(E->last, part) != NULL; }

/* The 4 x 2 Jacobian d(x, v, a, F_friction)/d(F_ext, N_ext), by columns (directional) and by rows
 * (adjoint). */
static void jacobians(tally *T, fmi3Instance in, double J[8], double A[8])
{
    const fmi3ValueReference unk[4] = {VR_x, VR_v, VR_a, VR_F_friction}, kn[2] = {VR_F_ext, VR_N_ext};
    for (int j = 0; j < 2; j++) {
        const fmi3Float64 seed[2] = {j == 0, j == 1};
        fmi3Float64 col[4];
        EXPECT(fmi3GetDirectionalDerivative(in, unk, 4, kn, 2, seed, 2, col, 4) == fmi3OK);
        for (int i = 0; i < 4; i++) J[2 * i + j] = col[i];
    }
    for (int i = 0; i < 4; i++) {
        const fmi3Float64 seed[4] = {i == 0, i == 1, i == 2, i == 3};
        fmi3Float64 row[2];
        EXPECT(fmi3GetAdjointDerivative(in, unk, 4, kn, 2, seed, 4, row, 2) == fmi3OK);
        A[2 * i] = row[0];
        A[2 * i + 1] = row[1];
    }
}

int main(void)
{
    tally tt = {0, 0, NULL, {0}}, *T = &tt;
    host_env E;
    memset(&E, 0, sizeof E);
    fmi3Instance in = host_instantiate(&E, 0, 0, 0, NULL);
    EXPECT(in != NULL);
    if (!in) return 1;
    const fmi3ValueReference vx = VR_x, va = VR_a, vF = VR_F_ext, vv = VR_v;
    const fmi3Int32 one = 1, three = 3;
    fmi3Float64 r = 1.0, out[4] = {0};
    /* phases: none before initialisation */
    EXPECT(fmi3GetOutputDerivatives(in, &vx, 1, &one, out, 1) == fmi3Error && has(&E, "must not be called"));
    EXPECT(fmi3GetDirectionalDerivative(in, &va, 1, &vF, 1, &r, 1, out, 1) == fmi3Error &&
           has(&E, "must not be called"));
    EXPECT(host_start(in, 3, HOST_T / 400) == fmi3OK);
    /* NULL arrays and counts */
    EXPECT(fmi3GetOutputDerivatives(in, &vx, 1, NULL, out, 1) == fmi3Error && has(&E, "orders array is NULL"));
    EXPECT(fmi3GetOutputDerivatives(in, &vx, 1, &one, NULL, 1) == fmi3Error && has(&E, "NULL"));
    EXPECT(fmi3GetOutputDerivatives(in, &vx, 1, &one, out, 2) == fmi3Error && has(&E, "nValues = 2"));
    EXPECT(fmi3GetOutputDerivatives(in, &vv, 1, &three, out, 1) == fmi3Error && has(&E, "valid range: 1 to 2"));
    EXPECT(fmi3GetDirectionalDerivative(in, &va, 1, &vF, 1, NULL, 1, out, 1) == fmi3Error && has(&E, "NULL"));
    EXPECT(fmi3GetDirectionalDerivative(in, &va, 1, &vF, 1, &r, 2, out, 1) == fmi3Error && has(&E, "nSeed = 2"));
    EXPECT(fmi3GetAdjointDerivative(in, &va, 1, &vF, 1, &r, 1, out, 2) == fmi3Error && has(&E, "nSensitivity = 2"));
    EXPECT(fmi3GetAdjointDerivative(in, &vF, 1, &va, 1, &r, 1, out, 1) == fmi3Error && has(&E, "not a real output"));
    EXPECT(fmi3GetOutputDerivatives(in, NULL, 0, NULL, NULL, 0) == fmi3OK);
    /* sliding (after a quarter period) and stuck states: adjoint = transposed directional */
    fmi3Boolean ev, term, early;
    fmi3Float64 last;
    int seen_slide = 0, seen_stuck = 0;
    double t = 0.0;
    for (int k = 0; k < 400 && !(seen_slide && seen_stuck); k++, t += HOST_T / 40) {
        EXPECT(fmi3DoStep(in, t, HOST_T / 40, fmi3False, &ev, &term, &early, &last) == fmi3OK);
        double J[8], A[8];
        jacobians(T, in, J, A);
        EXPECT(memcmp(J, A, sizeof J) == 0);
        EXPECT(J[0] == 0.0 && J[1] == 0.0 && J[2] == 0.0 && J[3] == 0.0); /* x, v: no feed-through */
        const int m = get_mode(in);
        if (m != 0) seen_slide |= J[4] == 1.0 && J[6] == 0.0;   /* m = 1: da/dF_ext = 1/m */
        else seen_stuck |= J[4] == 0.0 && J[6] == -1.0;        /* the friction holds the block */
    }
    EXPECT(seen_slide && seen_stuck);
    EXPECT(fmi3Terminate(in) == fmi3OK);
    EXPECT(fmi3GetOutputDerivatives(in, &vx, 1, &one, out, 1) == fmi3OK && out[0] == get_real(in, VR_v));
    fmi3FreeInstance(in);
    return tally_done(T, "cs_coupling");
}
