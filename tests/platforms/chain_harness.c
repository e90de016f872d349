/* Cross-platform harness of the DryFrictionChain FMUs (fmu_harness.c's for the oscillator): loads
 * the FMU's shared library (dlopen / LoadLibrary), runs NSETS parameter sets (n = 1 ... 6 blocks in
 * FMI 3.0, set in configuration mode; FMI 2.0 only the sets of its build's n, DFO_CHAIN_N), the
 * three schemes in turn, and prints every output of every block at every communication point and
 * the serialised FMU state, as %.17g and as the bits in hexadecimal. The same program cross-built
 * for Windows (wine) and Linux aarch64 (qemu) prints the same text when the platforms compute the
 * same numbers; scripts/cross_check.sh compares the texts.
 *
 *   chain_harness fmi2|fmi3 LIBRARY run STATES      all sets, points 1..NPTS; writes the state
 *                                                   serialised at point NPTS/2 of every set to STATES
 *   chain_harness fmi2|fmi3 LIBRARY resume STATES   every set from its state in STATES (written on
 *                                                   any platform), points NPTS/2+1..NPTS
 *   ... fixed                                       (a fifth argument) only the sets of n = DFO_CHAIN_N,
 *                                                   as FMI 2.0 runs them: FMI 3.0 then prints the same
 *
 * Sets NSETS_BASE ... NSETS - 1 add belts (v_belt set at the start and changed before points
 * NPTS / 4 + 1 and 3 NPTS / 4 + 1), site springs and dampers and the Stribeck law (schemes located,
 * and consistent with Coulomb); the sets before them are those of the earlier harness, line for line.
 *
 * Output lines: "out SET POINT t" then per block "x v a F_friction mode" (reals as %.17g:hex),
 * "state SET HEX"; "err SET POINT what" when a call fails. A resumed run's "out" lines equal the
 * second half of the run's. */
#define __USE_MINGW_ANSI_STDIO 1 /* mingw: C99 printf (the same digits as glibc's) */
#define _POSIX_C_SOURCE 200809L

#include "fmi2Functions.h"
#include "fmi3Functions.h"
#include "model_vars.h" /* the chain's */

#define HARNESS_NAME "chain_harness"
#define MAX_STATE (1 << 20)
#define NSETS_BASE 300 /* the first sets (Coulomb on fixed supports), as before the belts */
#define NSETS 390      /* then belts changed at two points, site springs and dampers, Stribeck */
#include "harness_common.h"

#ifndef DFO_CHAIN_N
#define DFO_CHAIN_N 2
#endif
#define NB 6 /* the largest n of a set */
#define NMAXB (NB > DFO_CHAIN_N ? NB : DFO_CHAIN_N)

/* ---- the parameter sets ------------------------------------------------------------------- */

typedef struct {
    size_t n;
    double m[NMAXB], k[NMAXB], c[NMAXB], P0[NMAXB], phi[NMAXB], N[NMAXB], mu_s[NMAXB], chi[NMAXB], x0[NMAXB],
        v0[NMAXB], F_ext[NMAXB];
    double k_end, c_end, omega, h, alpha, dt;
    int scheme, inputs;
    /* sets from NSETS_BASE on: belts (vb[0] from the start, vb[1], vb[2] from the change points),
     * site springs and dampers, the friction law (1 coulomb, 2 stribeck) */
    int ext, belt, law;
    double vb[3][NMAXB], k_site[NMAXB], c_site[NMAXB], v_s[NMAXB], delta[NMAXB];
} cset;

#define BELT_CHANGE_1 (NPTS / 4 + 1) /* the belts change before these points' steps */
#define BELT_CHANGE_2 (3 * NPTS / 4 + 1)

/* Set i: n blocks (every third set the FMI 2.0 build's n), the schemes in turn, the rest drawn over
 * the model's ranges (stick-dominated to free sliding, free or walled right end, 100 to 2000 steps
 * per excitation period). Only +, -, *, / here: the same sets on every platform. */
static cset make_set(int i)
{
    uint64_t s = 0xC4A10000ULL + (uint64_t)i;
    cset p;
    memset(&p, 0, sizeof p);
    p.n = (i % 3 == 0) ? (size_t)DFO_CHAIN_N : 1 + (size_t)(rng(&s) % NB);
    p.scheme = 1 + (i / 3) % 3;
    for (size_t b = 0; b < p.n; b++) {
        p.m[b] = unif(&s, 0.5, 2.0);
        p.k[b] = unif(&s, 0.5, 3.0);
        p.c[b] = (i % 4 == 0) ? 0.0 : unif(&s, 0.0, 0.3);
        p.P0[b] = (b == 0 || rng(&s) % 2) ? unif(&s, 0.2, 2.0) : 0.0;
        p.phi[b] = unif(&s, -3.0, 3.0);
        p.N[b] = (rng(&s) % 5 == 0) ? 0.0 : unif(&s, 0.2, 2.0);
        p.mu_s[b] = unif(&s, 0.0, 1.0);
        p.chi[b] = unif(&s, 0.05, 2.0);
        p.x0[b] = unif(&s, -0.05, 0.05);
        p.v0[b] = (rng(&s) % 2) ? 0.0 : unif(&s, -0.3, 0.3);
        p.F_ext[b] = unif(&s, -0.5, 0.5);
    }
    p.k_end = (i % 2) ? unif(&s, 0.0, 2.0) : 0.0;
    p.c_end = (i % 5 == 0) ? unif(&s, 0.0, 0.2) : 0.0;
    p.omega = unif(&s, 0.3, 3.0);
    const double T = 2.0 * PI / p.omega;
    p.h = T / (double)(100 + (int)(rng(&s) % 1901));
    p.alpha = unif(&s, -1.0 / 3.0, 0.0);
    p.inputs = i % 5 == 0;
    p.dt = T / 4.0; /* NPTS points = 4 excitation periods; comm points off the internal grid */
    p.law = 1;
    if (i < NSETS_BASE) return p;
    /* belts, site springs and dampers, Stribeck: drawn from a stream of their own */
    uint64_t s2 = 0xB17E0000ULL + (uint64_t)i;
    p.ext = 1;
    p.law = (i % 2) ? 2 : 1;
    p.belt = (i % 3) != 1;
    p.scheme = (p.law == 1 && i % 4 == 0) ? 2 : 3; /* consistent (Coulomb only), else located */
    static const double deltas[3] = {1.0, 2.0, 1.5};
    for (size_t b = 0; b < p.n; b++) {
        p.k_site[b] = (rng(&s2) % 2) ? unif(&s2, 0.0, 2.0) : 0.0;
        p.c_site[b] = (rng(&s2) % 3 == 0) ? unif(&s2, 0.0, 0.2) : 0.0;
        p.v_s[b] = unif(&s2, 0.02, 0.3);
        p.delta[b] = deltas[rng(&s2) % 3];
        for (int j = 0; j < 3; j++) p.vb[j][b] = (rng(&s2) % 4 == 0) ? 0.0 : unif(&s2, -0.3, 0.3);
        if (rng(&s2) % 3 == 0) p.v0[b] = p.vb[0][b]; /* starts on its belt */
    }
    return p;
}

/* ---- printing ------------------------------------------------------------------------------ */

/* r: x[n], v[n], a[n], F[n] */
static void put_point(int set, int k, double t, size_t n, const double *r, const int *mode)
{
    printf("out %d %d", set, k);
    put_real(t);
    for (size_t b = 0; b < n; b++) {
        for (int j = 0; j < 4; j++) put_real(r[(size_t)j * n + b]);
        printf(" %d", mode[b]);
    }
    printf("\n");
}

static const double *arr(const cset *p, int slot)
{
    switch (slot) {
    case DFO_AP_m: return p->m;
    case DFO_AP_k: return p->k;
    case DFO_AP_c: return p->c;
    case DFO_AP_P0: return p->P0;
    case DFO_AP_phi: return p->phi;
    case DFO_AP_N: return p->N;
    case DFO_AP_mu_s: return p->mu_s;
    case DFO_AP_chi: return p->chi;
    case DFO_AP_x0: return p->x0;
    default: return p->v0;
    }
}

/* the arrays the harness sets (the others keep their start values) */
enum { N_ARRAYS_SET = 10 };
static const unsigned ARRAY_VR[N_ARRAYS_SET] = {VR_m, VR_k, VR_c, VR_P0, VR_phi, VR_N, VR_mu_s, VR_chi, VR_x0, VR_v0};
static const unsigned SCALAR_VR[5] = {VR_k_end, VR_c_end, VR_omega, VR_h, VR_alpha};

/* ---- FMI 2.0 ------------------------------------------------------------------------------- */

/* FMI 2.0: element i (0-based) of the array with value reference base. */
static fmi2ValueReference elem(unsigned base, size_t i) { return (fmi2ValueReference)(base + i + 1); }

static int set_belts2(const fmi2_api *a, fmi2Component c, const cset *p, int j)
{
    for (size_t b = 0; b < p->n; b++) {
        const fmi2ValueReference vr = elem(VR_v_belt, b);
        if (a->set_real(c, &vr, 1, &p->vb[j][b]) != fmi2OK) return 0;
    }
    return 1;
}

static int set_params2(const fmi2_api *a, fmi2Component c, const cset *p)
{
    for (int j = 0; j < N_ARRAYS_SET; j++)
        for (size_t b = 0; b < p->n; b++) {
            const fmi2ValueReference vr = elem(ARRAY_VR[j], b);
            if (a->set_real(c, &vr, 1, &arr(p, j)[b]) != fmi2OK) return 0;
        }
    for (size_t b = 0; p->inputs && b < p->n; b++) {
        const fmi2ValueReference vr = elem(VR_F_ext, b);
        if (a->set_real(c, &vr, 1, &p->F_ext[b]) != fmi2OK) return 0;
    }
    const double sv[5] = {p->k_end, p->c_end, p->omega, p->h, p->alpha};
    const fmi2ValueReference vs = VR_scheme;
    const fmi2Integer sc = p->scheme;
    if (a->set_real(c, SCALAR_VR, 5, sv) != fmi2OK || a->set_integer(c, &vs, 1, &sc) != fmi2OK) return 0;
    if (!p->ext) return 1; /* (the first sets: as before) */
    if (p->law == 2) {
        const fmi2ValueReference vl = VR_friction_law;
        const fmi2Integer law = p->law;
        if (a->set_integer(c, &vl, 1, &law) != fmi2OK) return 0;
    }
    const unsigned extra[4] = {VR_k_site, VR_c_site, VR_v_s, VR_delta};
    const double *ev[4] = {p->k_site, p->c_site, p->v_s, p->delta};
    for (int j = 0; j < 4 && (p->law == 2 || j < 2); j++)
        for (size_t b = 0; b < p->n; b++) {
            const fmi2ValueReference vr = elem(extra[j], b);
            if (a->set_real(c, &vr, 1, &ev[j][b]) != fmi2OK) return 0;
        }
    return !p->belt || set_belts2(a, c, p, 0);
}

static int get_outputs2(const fmi2_api *a, fmi2Component c, size_t n, double *r, int *mode)
{
    const unsigned outs[4] = {VR_x, VR_v, VR_a, VR_F_friction};
    for (int j = 0; j < 4; j++)
        for (size_t b = 0; b < n; b++) {
            const fmi2ValueReference vr = elem(outs[j], b);
            if (a->get_real(c, &vr, 1, &r[(size_t)j * n + b]) != fmi2OK) return 0;
        }
    for (size_t b = 0; b < n; b++) {
        const fmi2ValueReference vr = elem(VR_mode, b);
        if (a->get_integer(c, &vr, 1, &mode[b]) != fmi2OK) return 0;
    }
    return 1;
}

static int run2(const fmi2_api *a, int set, FILE *states, const state_table *tab)
{
    const cset p = make_set(set);
    if (p.n != DFO_CHAIN_N) return 0; /* the FMI 2.0 FMU's n is fixed */
    const int resume = tab != NULL;
    int k0, fails = 0;
    fmi2Component c = start2(a, set, tab, &k0);
    if (!c) return 1;
    if (!resume && (a->setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK || !set_params2(a, c, &p) ||
                    a->enter_init(c) != fmi2OK || a->exit_init(c) != fmi2OK)) {
        printf("err %d 0 initialisation\n", set);
        a->free_instance(c);
        return 1;
    }
    double r[4 * NMAXB];
    int mode[NMAXB];
    for (int k = k0; k <= NPTS; k++) {
        const double t0 = (k - 1) * p.dt, t1 = k * p.dt;
        const int change = p.belt && (k == BELT_CHANGE_1 || k == BELT_CHANGE_2);
        if ((change && !set_belts2(a, c, &p, (k == BELT_CHANGE_1) ? 1 : 2)) ||
            a->do_step(c, t0, t1 - t0, fmi2True) != fmi2OK || !get_outputs2(a, c, p.n, r, mode)) {
            printf("err %d %d doStep\n", set, k);
            fails++;
            break;
        }
        put_point(set, k, t1, p.n, r, mode);
        if (!resume && k == HALF) fails += save_state(states, set, k, serialise2(a, c));
    }
    a->free_instance(c);
    return fails;
}

/* ---- FMI 3.0 ------------------------------------------------------------------------------- */

static int set_params3(const fmi3_api *a, fmi3Instance c, const cset *p)
{
    const fmi3ValueReference vn = VR_n;
    const fmi3UInt64 n = p->n;
    if (a->enter_config(c) != fmi3OK || a->set_uint64(c, &vn, 1, &n, 1) != fmi3OK || a->exit_config(c) != fmi3OK)
        return 0;
    for (int j = 0; j < N_ARRAYS_SET; j++) {
        const fmi3ValueReference vr = ARRAY_VR[j];
        if (a->set_float64(c, &vr, 1, arr(p, j), p->n) != fmi3OK) return 0;
    }
    const fmi3ValueReference vf = VR_F_ext;
    if (p->inputs && a->set_float64(c, &vf, 1, p->F_ext, p->n) != fmi3OK) return 0;
    const double sv[5] = {p->k_end, p->c_end, p->omega, p->h, p->alpha};
    const fmi3ValueReference vs = VR_scheme;
    const fmi3Int64 sc = p->scheme;
    if (a->set_float64(c, SCALAR_VR, 5, sv, 5) != fmi3OK || a->set_int64(c, &vs, 1, &sc, 1) != fmi3OK) return 0;
    if (!p->ext) return 1; /* (the first sets: as before) */
    if (p->law == 2) {
        const fmi3ValueReference vl = VR_friction_law;
        const fmi3Int64 law = p->law;
        if (a->set_int64(c, &vl, 1, &law, 1) != fmi3OK) return 0;
    }
    const fmi3ValueReference extra[4] = {VR_k_site, VR_c_site, VR_v_s, VR_delta};
    const double *ev[4] = {p->k_site, p->c_site, p->v_s, p->delta};
    for (int j = 0; j < 4 && (p->law == 2 || j < 2); j++)
        if (a->set_float64(c, &extra[j], 1, ev[j], p->n) != fmi3OK) return 0;
    const fmi3ValueReference vb = VR_v_belt;
    return !p->belt || a->set_float64(c, &vb, 1, p->vb[0], p->n) == fmi3OK;
}

static int run3(const fmi3_api *a, int set, FILE *states, const state_table *tab)
{
    const cset p = make_set(set);
    const int resume = tab != NULL;
    int k0, fails = 0;
    fmi3Instance c = start3(a, set, tab, &k0); /* resumed: the default n, the state brings its own */
    if (!c) return 1;
    if (!resume && (!set_params3(a, c, &p) || a->enter_init(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK ||
                    a->exit_init(c) != fmi3OK)) {
        printf("err %d 0 initialisation\n", set);
        a->free_instance(c);
        return 1;
    }
    const fmi3ValueReference rvr[4] = {VR_x, VR_v, VR_a, VR_F_friction}, vm = VR_mode;
    double r[4 * NMAXB];
    fmi3Int32 mode[NMAXB];
    for (int k = k0; k <= NPTS; k++) {
        const double t0 = (k - 1) * p.dt, t1 = k * p.dt;
        fmi3Boolean ev, term, early;
        fmi3Float64 last;
        const fmi3ValueReference vb = VR_v_belt;
        const int change = p.belt && (k == BELT_CHANGE_1 || k == BELT_CHANGE_2);
        if ((change && a->set_float64(c, &vb, 1, p.vb[(k == BELT_CHANGE_1) ? 1 : 2], p.n) != fmi3OK) ||
            a->do_step(c, t0, t1 - t0, fmi3True, &ev, &term, &early, &last) != fmi3OK ||
            a->get_float64(c, rvr, 4, r, 4 * p.n) != fmi3OK || a->get_int32(c, &vm, 1, mode, p.n) != fmi3OK) {
            printf("err %d %d doStep\n", set, k);
            fails++;
            break;
        }
        int mi[NMAXB];
        for (size_t b = 0; b < p.n; b++) mi[b] = mode[b];
        put_point(set, k, t1, p.n, r, mi);
        if (!resume && k == HALF) fails += save_state(states, set, k, serialise3(a, c));
    }
    a->free_instance(c);
    return fails;
}

static int of_fixed_n(int set) { return make_set(set).n == DFO_CHAIN_N; }

int main(int argc, char **argv) { return harness_main(argc, argv, run2, run3, of_fixed_n); }
