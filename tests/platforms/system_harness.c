/* Cross-platform harness of the DryFrictionSystem FMUs (chain_harness.c's for the chain): loads the
 * FMU's shared library (dlopen / LoadLibrary), runs NSETS structures (FMI 3.0: n = 1 ... 6 degrees of
 * freedom and nc = 0 ... 4 contacts set in configuration mode; FMI 2.0 only the structures of its
 * build's sizes, DFO_SYSTEM_FIXED_N and _NC), the three schemes in turn, and prints every output at
 * every communication point and the serialised FMU state, as %.17g and as the bits in hexadecimal.
 * The same program cross-built for Windows (wine) and Linux aarch64 (qemu) prints the same text when
 * the platforms compute the same numbers; scripts/cross_check.sh compares the texts.
 *
 *   system_harness fmi2|fmi3 LIBRARY run STATES      all sets, points 1..NPTS; writes the state
 *                                                    serialised at point NPTS/2 of every set to STATES
 *   system_harness fmi2|fmi3 LIBRARY resume STATES   every set from its state in STATES, points
 *                                                    NPTS/2+1..NPTS
 *   ... fixed                                        (a fifth argument) only the sets of the FMI 2.0
 *                                                    build's sizes, as FMI 2.0 runs them
 *
 * A structure: M = B B' + diag(d) (symmetric positive definite), K = L L' (positive semi-definite:
 * L has fewer columns than n in some sets, a mode held only by friction), C Rayleigh or 0, contacts
 * on a DOF, between two DOFs or along a longer row, rigid (independent rows) or Jenkins (k_t > 0,
 * any row), mu_s and mu_k on both
 * sides of each other, a harmonic force, F_ext held, N_ext changed at a communication point, belts
 * (schemes consistent and located) changed at another.
 *
 * Output lines: "out SET POINT t" then "x v a" per DOF, "f mode s" per contact, E_friction (reals as
 * %.17g:hex); "state SET HEX"; "err SET POINT what" when a call fails. */
#define __USE_MINGW_ANSI_STDIO 1 /* mingw: C99 printf (the same digits as glibc's) */
#define _POSIX_C_SOURCE 200809L

#include "fmi2Functions.h"
#include "fmi3Functions.h"
#include "model_vars.h"         /* the system's */
#include "fmi2/system_config.h" /* the FMI 2.0 build's sizes and its elements' value references */

#define HARNESS_NAME "system_harness"
#define MAX_STATE (1 << 20)
#define NSETS 120
#include "harness_common.h"

#define NMAX 6  /* the largest n of a set */
#define NCMAX 4 /* the largest nc */
#define CHANGE_N (NPTS / 4 + 1)     /* N_ext changes before this point's step */
#define CHANGE_B (3 * NPTS / 4 + 1) /* the belts change before this one's */

/* ---- the structures ------------------------------------------------------------------------ */

typedef struct {
    size_t n, nc;
    double M[NMAX * NMAX], C[NMAX * NMAX], K[NMAX * NMAX], W[NCMAX * NMAX];
    double F_c[NMAX], F_s[NMAX], x0[NMAX], v0[NMAX], F_ext[NMAX];
    double N[NCMAX], mu_s[NCMAX], mu_k[NCMAX], k_t[NCMAX], N_ext[NCMAX], vb[2][NCMAX];
    double omega, h, alpha, dt;
    int scheme, belt;
} sset;

/* Set i: the FMI 2.0 build's sizes every third set, else drawn; the schemes in turn. Only +, -, *, /
 * here: the same sets on every platform. */
static sset make_set(int i)
{
    uint64_t s = 0x5157E000ULL + (uint64_t)i;
    sset p;
    memset(&p, 0, sizeof p);
    const int fixed = i % 3 == 0 && DFO_SYSTEM_FIXED_N <= NMAX && DFO_SYSTEM_FIXED_NC <= NCMAX;
    p.n = fixed ? (size_t)DFO_SYSTEM_FIXED_N : 1 + (size_t)(rng(&s) % NMAX);
    p.nc = fixed ? (size_t)DFO_SYSTEM_FIXED_NC : (size_t)(rng(&s) % (NCMAX + 1));
    p.scheme = 1 + (i / 3) % 3;
    const size_t n = p.n;
    const size_t rank = (i % 4 == 1 && n > 1) ? n - 1 : n; /* K singular in some sets */
    double B[NMAX * NMAX], L[NMAX * NMAX];
    for (size_t a = 0; a < n * n; a++) {
        B[a] = unif(&s, -0.5, 0.5);
        L[a] = unif(&s, -1.0, 1.0);
    }
    for (size_t r = 0; r < n; r++)
        for (size_t c = 0; c < n; c++) {
            double m = 0.0, k = 0.0;
            for (size_t q = 0; q < n; q++) m += B[r * n + q] * B[c * n + q];
            for (size_t q = 0; q < rank; q++) k += L[r * n + q] * L[c * n + q];
            p.M[r * n + c] = m;
            p.K[r * n + c] = 2.0 * k;
        }
    for (size_t r = 0; r < n; r++) p.M[r * n + r] += unif(&s, 0.5, 1.5);
    const double aM = (i % 2) ? unif(&s, 0.0, 0.1) : 0.0, bK = (i % 5 == 0) ? unif(&s, 0.0, 0.05) : 0.0;
    for (size_t a = 0; a < n * n; a++) p.C[a] = aM * p.M[a] + bK * p.K[a];
    for (size_t r = 0; r < n; r++) {
        p.F_c[r] = (r == 0 || rng(&s) % 2) ? unif(&s, -1.5, 1.5) : 0.0;
        p.F_s[r] = (rng(&s) % 3 == 0) ? unif(&s, -1.0, 1.0) : 0.0;
        p.x0[r] = unif(&s, -0.05, 0.05);
        p.v0[r] = (rng(&s) % 2) ? 0.0 : unif(&s, -0.3, 0.3);
        p.F_ext[r] = (i % 4 == 0) ? unif(&s, -0.3, 0.3) : 0.0;
    }
    p.belt = p.scheme != 1 && i % 3 != 1; /* (the paper scheme refuses belts) */
    /* the rigid contacts' rows independent (the model refuses dependent ones): rigid contact number
     * r has its leading 1 on DOF n - 1 - r and entries only after it (echelon rows); a Jenkins
     * contact any row; at most n rigid ones */
    size_t rigid = 0;
    for (size_t j = 0; j < p.nc; j++) {
        p.k_t[j] = (rng(&s) % 3 == 0 || rigid == n) ? unif(&s, 5.0, 200.0) : 0.0;
        const size_t d0 = (p.k_t[j] > 0.0) ? (size_t)(rng(&s) % n) : n - 1 - rigid++;
        const size_t d1 = d0 + 1 + (size_t)(rng(&s) % n);
        const int kind = (int)(rng(&s) % 3);
        double *w = &p.W[j * n];
        if (kind == 0 || d0 + 1 >= n) {
            w[d0] = 1.0;
        } else if (kind == 1 && d1 < n) {
            w[d0] = 1.0;
            w[d1] = -1.0;
        } else {
            for (size_t r = d0 + 1; r < n; r++) w[r] = unif(&s, -1.0, 1.0);
            w[d0] = 1.0; /* (never a zero row) */
        }
        p.N[j] = (rng(&s) % 6 == 0) ? 0.0 : unif(&s, 0.1, 1.5);
        p.mu_s[j] = unif(&s, 0.1, 0.8);
        p.mu_k[j] = p.mu_s[j] * unif(&s, 0.3, 1.5);
        p.N_ext[j] = unif(&s, -0.2, 0.4);
        for (int b = 0; b < 2; b++) p.vb[b][j] = (p.belt && rng(&s) % 2) ? unif(&s, -0.2, 0.2) : 0.0;
    }
    p.omega = unif(&s, 0.5, 3.0);
    const double T = 2.0 * PI / p.omega;
    p.h = T / (double)(200 + (int)(rng(&s) % 801));
    p.alpha = unif(&s, -1.0 / 3.0, 0.0);
    p.dt = T / 4.0; /* NPTS points = 4 excitation periods; comm points off the internal grid */
    return p;
}

/* ---- printing ------------------------------------------------------------------------------ */

/* r: x[n], v[n], a[n], f[nc], s[nc], E_friction */
static void put_point(int set, int k, double t, const sset *p, const double *r, const int *mode)
{
    const size_t n = p->n, nc = p->nc;
    printf("out %d %d", set, k);
    put_real(t);
    for (size_t i = 0; i < n; i++)
        for (int q = 0; q < 3; q++) put_real(r[(size_t)q * n + i]);
    for (size_t j = 0; j < nc; j++) {
        put_real(r[3 * n + j]);
        printf(" %d", mode[j]);
        if (p->k_t[j] > 0.0) put_real(r[3 * n + nc + j]);
        else printf(" rigid:%016" PRIx64, bits(r[3 * n + nc + j])); /* (NaN: its bits, not printf's spelling) */
    }
    put_real(r[3 * n + 2 * nc]);
    printf("\n");
}

/* the arrays the harness sets, their value references and lengths */
enum { N_ARRAYS = 13 };
static const unsigned ARRAY_VR[N_ARRAYS] = {VR_M, VR_C, VR_K, VR_F_c, VR_F_s, VR_x0, VR_v0,
                                            VR_W, VR_N, VR_mu_s, VR_mu_k, VR_k_t, VR_F_ext};
static const double *arr(const sset *p, int q, size_t *len)
{
    const size_t n = p->n, nc = p->nc;
    const double *v[N_ARRAYS] = {p->M, p->C, p->K, p->F_c, p->F_s, p->x0, p->v0,
                                 p->W, p->N, p->mu_s, p->mu_k, p->k_t, p->F_ext};
    const size_t l[N_ARRAYS] = {n * n, n * n, n * n, n, n, n, n, nc * n, nc, nc, nc, nc, n};
    *len = l[q];
    return v[q];
}
static const unsigned SCALAR_VR[3] = {VR_omega, VR_h, VR_alpha};

/* ---- FMI 2.0 ------------------------------------------------------------------------------- */

/* FMI 2.0: element e (0-based, row-major) of the array with value reference vr, from the build's
 * layout (0 where the array is not in it) */
static fmi2ValueReference elem(unsigned vr, size_t e)
{
    for (int q = 0; q < DFO_FMI2_NUM_ARRAYS; q++)
        if (DFO_FMI2_ARRAYS[q].vr == vr) return (fmi2ValueReference)(DFO_FMI2_ARRAYS[q].first + e);
    return 0;
}

static int set_array2(const fmi2_api *a, fmi2Component c, unsigned vr, const double *v, size_t len)
{
    for (size_t e = 0; e < len; e++) {
        const fmi2ValueReference r = elem(vr, e);
        if (a->set_real(c, &r, 1, &v[e]) != fmi2OK) return 0;
    }
    return 1;
}

static int set_params2(const fmi2_api *a, fmi2Component c, const sset *p)
{
    for (int q = 0; q < N_ARRAYS; q++) {
        size_t len;
        const double *v = arr(p, q, &len);
        if (!set_array2(a, c, ARRAY_VR[q], v, len)) return 0;
    }
    const double sv[3] = {p->omega, p->h, p->alpha};
    const fmi2ValueReference vs = VR_scheme;
    const fmi2Integer sc = p->scheme;
    if (a->set_real(c, SCALAR_VR, 3, sv) != fmi2OK || a->set_integer(c, &vs, 1, &sc) != fmi2OK) return 0;
    return !p->belt || set_array2(a, c, VR_v_belt, p->vb[0], p->nc);
}

static int get_outputs2(const fmi2_api *a, fmi2Component c, const sset *p, double *r, int *mode)
{
    const size_t n = p->n, nc = p->nc;
    const unsigned outs[3] = {VR_x, VR_v, VR_a};
    for (int q = 0; q < 3; q++)
        for (size_t i = 0; i < n; i++) {
            const fmi2ValueReference vr = elem(outs[q], i);
            if (a->get_real(c, &vr, 1, &r[(size_t)q * n + i]) != fmi2OK) return 0;
        }
    for (size_t j = 0; j < nc; j++) {
        const fmi2ValueReference vf = elem(VR_f, j), vs = elem(VR_s, j), vm = elem(VR_mode, j);
        if (a->get_real(c, &vf, 1, &r[3 * n + j]) != fmi2OK || a->get_real(c, &vs, 1, &r[3 * n + nc + j]) != fmi2OK ||
            a->get_integer(c, &vm, 1, &mode[j]) != fmi2OK)
            return 0;
    }
    const fmi2ValueReference ve = VR_E_friction;
    return a->get_real(c, &ve, 1, &r[3 * n + 2 * nc]) == fmi2OK;
}

static int run2(const fmi2_api *a, int set, FILE *states, const state_table *tab)
{
    const sset p = make_set(set);
    if (p.n != DFO_SYSTEM_FIXED_N || p.nc != DFO_SYSTEM_FIXED_NC) return 0; /* the FMI 2.0 FMU's sizes are fixed */
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
    double r[3 * NMAX + 2 * NCMAX + 1];
    int mode[NCMAX];
    for (int k = k0; k <= NPTS; k++) {
        const double t0 = (k - 1) * p.dt, t1 = k * p.dt;
        if ((k == CHANGE_N && !set_array2(a, c, VR_N_ext, p.N_ext, p.nc)) ||
            (p.belt && k == CHANGE_B && !set_array2(a, c, VR_v_belt, p.vb[1], p.nc)) ||
            a->do_step(c, t0, t1 - t0, fmi2True) != fmi2OK || !get_outputs2(a, c, &p, r, mode)) {
            printf("err %d %d doStep\n", set, k);
            fails++;
            break;
        }
        put_point(set, k, t1, &p, r, mode);
        if (!resume && k == HALF) fails += save_state(states, set, k, serialise2(a, c));
    }
    a->free_instance(c);
    return fails;
}

/* ---- FMI 3.0 ------------------------------------------------------------------------------- */

static int set_params3(const fmi3_api *a, fmi3Instance c, const sset *p)
{
    const fmi3ValueReference vsz[2] = {VR_n, VR_nc};
    const fmi3UInt64 sz[2] = {p->n, p->nc};
    if (a->enter_config(c) != fmi3OK || a->set_uint64(c, vsz, 2, sz, 2) != fmi3OK || a->exit_config(c) != fmi3OK)
        return 0;
    for (int q = 0; q < N_ARRAYS; q++) {
        size_t len;
        const double *v = arr(p, q, &len);
        const fmi3ValueReference vr = ARRAY_VR[q];
        if (len && a->set_float64(c, &vr, 1, v, len) != fmi3OK) return 0;
    }
    const double sv[3] = {p->omega, p->h, p->alpha};
    const fmi3ValueReference vs = VR_scheme;
    const fmi3Int64 sc = p->scheme;
    if (a->set_float64(c, SCALAR_VR, 3, sv, 3) != fmi3OK || a->set_int64(c, &vs, 1, &sc, 1) != fmi3OK) return 0;
    const fmi3ValueReference vb = VR_v_belt;
    return !p->belt || !p->nc || a->set_float64(c, &vb, 1, p->vb[0], p->nc) == fmi3OK;
}

static int run3(const fmi3_api *a, int set, FILE *states, const state_table *tab)
{
    const sset p = make_set(set);
    const size_t n = p.n, nc = p.nc;
    const int resume = tab != NULL;
    int k0, fails = 0;
    fmi3Instance c = start3(a, set, tab, &k0); /* resumed: the default sizes, the state brings its own */
    if (!c) return 1;
    if (!resume && (!set_params3(a, c, &p) || a->enter_init(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK ||
                    a->exit_init(c) != fmi3OK)) {
        printf("err %d 0 initialisation\n", set);
        a->free_instance(c);
        return 1;
    }
    const fmi3ValueReference rvr[3] = {VR_x, VR_v, VR_a}, cvr[2] = {VR_f, VR_s}, vm = VR_mode, ve = VR_E_friction;
    const fmi3ValueReference vN = VR_N_ext, vb = VR_v_belt;
    double r[3 * NMAX + 2 * NCMAX + 1];
    fmi3Int32 mode[NCMAX];
    for (int k = k0; k <= NPTS; k++) {
        const double t0 = (k - 1) * p.dt, t1 = k * p.dt;
        fmi3Boolean ev, term, early;
        fmi3Float64 last;
        if ((nc && k == CHANGE_N && a->set_float64(c, &vN, 1, p.N_ext, nc) != fmi3OK) ||
            (nc && p.belt && k == CHANGE_B && a->set_float64(c, &vb, 1, p.vb[1], nc) != fmi3OK) ||
            a->do_step(c, t0, t1 - t0, fmi3True, &ev, &term, &early, &last) != fmi3OK ||
            a->get_float64(c, rvr, 3, r, 3 * n) != fmi3OK ||
            (nc && a->get_float64(c, cvr, 2, &r[3 * n], 2 * nc) != fmi3OK) ||
            (nc && a->get_int32(c, &vm, 1, mode, nc) != fmi3OK) ||
            a->get_float64(c, &ve, 1, &r[3 * n + 2 * nc], 1) != fmi3OK) {
            printf("err %d %d doStep\n", set, k);
            fails++;
            break;
        }
        int mi[NCMAX];
        for (size_t j = 0; j < nc; j++) mi[j] = mode[j];
        put_point(set, k, t1, &p, r, mi);
        if (!resume && k == HALF) fails += save_state(states, set, k, serialise3(a, c));
    }
    a->free_instance(c);
    return fails;
}

static int of_fixed_sizes(int set)
{
    const sset p = make_set(set);
    return p.n == DFO_SYSTEM_FIXED_N && p.nc == DFO_SYSTEM_FIXED_NC;
}

int main(int argc, char **argv) { return harness_main(argc, argv, run2, run3, of_fixed_sizes); }
