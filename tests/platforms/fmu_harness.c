/* Cross-platform harness: loads an FMU's shared library (dlopen / LoadLibrary), runs a fixed set of
 * parameter sets through every scheme, and prints every output at every communication point and
 * the serialised FMU state, as %.17g and as the bits in hexadecimal. The same program cross-built
 * for Windows (run under wine) and Linux aarch64 (run under qemu) prints the same text when the
 * platforms compute the same numbers; scripts/cross_check.sh compares the texts.
 *
 *   fmu_harness fmi2|fmi3 LIBRARY run STATES       all sets, points 1..NPTS; writes the state
 *                                                  serialised at point NPTS/2 of every set to STATES
 *   fmu_harness fmi2|fmi3 LIBRARY resume STATES    every set from its state in STATES (written on
 *                                                  any platform), points NPTS/2+1..NPTS
 *
 * Output lines: "out SET POINT t x v a F_friction mode x_max x_min stick_fraction transitions
 * E_friction" (each real as %.17g:hex), "state SET HEX"; "err SET POINT what" when a call fails.
 * A resumed run's "out" lines equal the second half of the run's "out" lines.
 *
 * Sets 0 ... 299 are the fixed support; sets 300 ... NSETS - 1 (after them, so that the first 300
 * print what they always printed) put the block on a moving belt: schemes exact and located, the
 * coulomb law and (located) stribeck, v_belt set at the start and changed at two communication points
 * (the second time to 0 in every third set). */
#define __USE_MINGW_ANSI_STDIO 1 /* mingw: C99 printf (the same digits as glibc's) */
#define _POSIX_C_SOURCE 200809L

#include "fmi2Functions.h"
#include "fmi3Functions.h"
#include "model_vars.h"

#define HARNESS_NAME "fmu_harness"
#define MAX_STATE 4096
#define NSETS 340 /* 300 on a support at rest, then 40 on a belt */
#define FIRST_BELT_SET 300
#include "harness_common.h"

/* ---- the parameter sets ------------------------------------------------------------------- */

typedef struct {
    double m, k, c, P0, omega, phi, N, mu_s, chi, x0, v0, h, alpha, dt;
    int scheme, friction_updates;
    /* the belt sets: v_belt from the start, then vb[1] from point BELT_K1 and vb[2] from BELT_K2 (their
     * doSteps), friction_law 1 coulomb or 2 stribeck (v_s, delta) */
    int belt, law;
    double vb[3], v_s, delta;
} pset;

#define BELT_K1 6  /* (before the state serialised at point HALF) */
#define BELT_K2 12 /* (after it: a resumed run changes it too) */

/* Set i: every scheme in turn, the rest drawn over the model's ranges (stick-dominated to free
 * sliding, light to over-critical damping, 25 to 2000 steps per excitation period). Only +, -, *,
 * / here: the same sets on every platform. */
static pset make_set(int i)
{
    uint64_t s = 0x5EED0000ULL + (uint64_t)i;
    pset p;
    p.scheme = 1 + i % 4;
    p.m = unif(&s, 0.5, 2.0);
    p.k = unif(&s, 10.0, 200.0);
    p.c = (i % 3 == 0) ? 0.0 : unif(&s, 0.0, 3.0);
    p.P0 = unif(&s, 0.5, 2.0);
    p.omega = unif(&s, 1.0, 15.0);
    p.phi = unif(&s, -3.0, 3.0);
    p.N = (i % 7 == 0) ? 0.0 : unif(&s, 0.2, 2.0);
    p.mu_s = unif(&s, 0.0, 1.0);
    p.chi = unif(&s, 0.05, 2.0);
    p.x0 = unif(&s, -0.02, 0.02);
    p.v0 = (i % 2) ? 0.0 : unif(&s, -0.3, 0.3);
    const double T = 2.0 * PI / p.omega;
    p.h = T / (double)(25 + (int)(rng(&s) % 1976));
    p.alpha = unif(&s, -1.0 / 3.0, 0.0);
    p.friction_updates = (int)(rng(&s) % 4);
    p.dt = T / 4.0; /* NPTS points = 4 excitation periods; comm points off the internal grid */
    p.belt = 0;
    p.law = 1;
    p.vb[0] = p.vb[1] = p.vb[2] = 0.0;
    p.v_s = 0.01;
    p.delta = 1.0;
    if (i >= FIRST_BELT_SET) { /* (drawn after the rest: the sets before are unchanged) */
        const int j = i - FIRST_BELT_SET;
        p.belt = 1;
        p.scheme = (j % 2) ? 4 : 3; /* exact, located */
        p.law = (p.scheme == 3 && j % 4 == 0) ? 2 : 1;
        p.vb[0] = unif(&s, -0.3, 0.3);
        p.vb[1] = unif(&s, -0.3, 0.3);
        p.vb[2] = (j % 3 == 0) ? 0.0 : unif(&s, -0.3, 0.3);
        p.v_s = unif(&s, 0.02, 0.3);
        p.delta = unif(&s, 1.0, 3.0);
    }
    return p;
}

/* ---- printing ------------------------------------------------------------------------------ */

static void put_point(int set, int k, double t, const double r[8], const int n[2])
{
    printf("out %d %d", set, k);
    put_real(t);
    for (int j = 0; j < 4; j++) put_real(r[j]); /* x v a F_friction */
    printf(" %d", n[0]);                         /* mode */
    for (int j = 4; j < 7; j++) put_real(r[j]); /* x_max x_min stick_fraction */
    printf(" %d", n[1]);                         /* transitions */
    put_real(r[7]);                              /* E_friction */
    printf("\n");
}

#define REAL_OUTS {VR_x, VR_v, VR_a, VR_F_friction, VR_x_max, VR_x_min, VR_stick_fraction, VR_E_friction}
#define INT_OUTS {VR_mode, VR_transitions}

/* ---- FMI 2.0 ------------------------------------------------------------------------------- */

static int run2(const fmi2_api *a, int set, FILE *states, const state_table *tab)
{
    const pset p = make_set(set);
    const int resume = tab != NULL;
    int k0, fails = 0;
    fmi2Component c = start2(a, set, tab, &k0);
    if (!c) return 1;
    if (!resume) {
        const fmi2ValueReference vr[] = {VR_m, VR_k, VR_c, VR_P0, VR_omega, VR_phi, VR_N, VR_mu_s, VR_chi,
                                         VR_x0, VR_v0, VR_h, VR_alpha};
        const fmi2Real rv[] = {p.m, p.k, p.c, p.P0, p.omega, p.phi, p.N, p.mu_s, p.chi, p.x0, p.v0, p.h, p.alpha};
        const fmi2ValueReference ivr[] = {VR_scheme, VR_frictionUpdates}, bvr[] = {VR_observe};
        const fmi2Integer iv[] = {p.scheme, p.friction_updates};
        const fmi2Boolean bv[] = {fmi2True};
        const fmi2ValueReference belt_vr[] = {VR_v_belt, VR_v_s, VR_delta}, law_vr[] = {VR_friction_law};
        const fmi2Real belt_rv[] = {p.vb[0], p.v_s, p.delta};
        const fmi2Integer law_iv[] = {p.law};
        if (a->setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK || a->set_real(c, vr, 13, rv) != fmi2OK ||
            a->set_integer(c, ivr, 2, iv) != fmi2OK || a->set_boolean(c, bvr, 1, bv) != fmi2OK ||
            (p.belt &&
             (a->set_real(c, belt_vr, 3, belt_rv) != fmi2OK || a->set_integer(c, law_vr, 1, law_iv) != fmi2OK)) ||
            a->enter_init(c) != fmi2OK || a->exit_init(c) != fmi2OK) {
            printf("err %d 0 initialisation\n", set);
            a->free_instance(c);
            return 1;
        }
    }
    const fmi2ValueReference rvr[] = REAL_OUTS, ivr[] = INT_OUTS;
    for (int k = k0; k <= NPTS; k++) {
        const double t0 = (k - 1) * p.dt, t1 = k * p.dt;
        double r[8];
        int n[2];
        const fmi2ValueReference bvr[] = {VR_v_belt};
        if (p.belt && (k == BELT_K1 || k == BELT_K2) && a->set_real(c, bvr, 1, &p.vb[k == BELT_K1 ? 1 : 2]) != fmi2OK) {
            printf("err %d %d setReal\n", set, k);
            fails++;
            break;
        }
        if (a->do_step(c, t0, t1 - t0, fmi2True) != fmi2OK || a->get_real(c, rvr, 8, r) != fmi2OK ||
            a->get_integer(c, ivr, 2, n) != fmi2OK) {
            printf("err %d %d doStep\n", set, k);
            fails++;
            break;
        }
        put_point(set, k, t1, r, n);
        if (!resume && k == HALF) fails += save_state(states, set, k, serialise2(a, c));
    }
    a->free_instance(c);
    return fails;
}

/* ---- FMI 3.0 ------------------------------------------------------------------------------- */

static int run3(const fmi3_api *a, int set, FILE *states, const state_table *tab)
{
    const pset p = make_set(set);
    const int resume = tab != NULL;
    int k0, fails = 0;
    fmi3Instance c = start3(a, set, tab, &k0);
    if (!c) return 1;
    if (!resume) {
        const fmi3ValueReference vr[] = {VR_m, VR_k, VR_c, VR_P0, VR_omega, VR_phi, VR_N, VR_mu_s, VR_chi,
                                         VR_x0, VR_v0, VR_h, VR_alpha};
        const fmi3Float64 rv[] = {p.m, p.k, p.c, p.P0, p.omega, p.phi, p.N, p.mu_s, p.chi, p.x0, p.v0, p.h, p.alpha};
        const fmi3ValueReference svr[] = {VR_scheme}, ivr[] = {VR_frictionUpdates}, bvr[] = {VR_observe};
        const fmi3Int64 sv[] = {p.scheme};
        const fmi3Int32 iv[] = {p.friction_updates};
        const fmi3Boolean bv[] = {fmi3True};
        const fmi3ValueReference belt_vr[] = {VR_v_belt, VR_v_s, VR_delta}, law_vr[] = {VR_friction_law};
        const fmi3Float64 belt_rv[] = {p.vb[0], p.v_s, p.delta};
        const fmi3Int64 law_iv[] = {p.law};
        if (a->enter_init(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK ||
            a->set_float64(c, vr, 13, rv, 13) != fmi3OK || a->set_int64(c, svr, 1, sv, 1) != fmi3OK ||
            a->set_int32(c, ivr, 1, iv, 1) != fmi3OK || a->set_boolean(c, bvr, 1, bv, 1) != fmi3OK ||
            (p.belt && (a->set_float64(c, belt_vr, 3, belt_rv, 3) != fmi3OK ||
                        a->set_int64(c, law_vr, 1, law_iv, 1) != fmi3OK)) ||
            a->exit_init(c) != fmi3OK) {
            printf("err %d 0 initialisation\n", set);
            a->free_instance(c);
            return 1;
        }
    }
    const fmi3ValueReference rvr[] = REAL_OUTS, ivr[] = INT_OUTS;
    for (int k = k0; k <= NPTS; k++) {
        const double t0 = (k - 1) * p.dt, t1 = k * p.dt;
        double r[8];
        fmi3Int32 n[2];
        fmi3Boolean ev, term, early;
        fmi3Float64 last;
        const fmi3ValueReference bvr[] = {VR_v_belt};
        if (p.belt && (k == BELT_K1 || k == BELT_K2) &&
            a->set_float64(c, bvr, 1, &p.vb[k == BELT_K1 ? 1 : 2], 1) != fmi3OK) {
            printf("err %d %d setFloat64\n", set, k);
            fails++;
            break;
        }
        if (a->do_step(c, t0, t1 - t0, fmi3True, &ev, &term, &early, &last) != fmi3OK ||
            a->get_float64(c, rvr, 8, r, 8) != fmi3OK || a->get_int32(c, ivr, 2, n, 2) != fmi3OK) {
            printf("err %d %d doStep\n", set, k);
            fails++;
            break;
        }
        const int ni[2] = {n[0], n[1]};
        put_point(set, k, t1, r, ni);
        if (!resume && k == HALF) fails += save_state(states, set, k, serialise3(a, c));
    }
    a->free_instance(c);
    return fails;
}

int main(int argc, char **argv) { return harness_main(argc, argv, run2, run3, NULL); }
