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
 * Output lines: "out SET POINT t" then per block "x v a F_friction mode" (reals as %.17g:hex),
 * "state SET HEX"; "err SET POINT what" when a call fails. A resumed run's "out" lines equal the
 * second half of the run's. */
#define __USE_MINGW_ANSI_STDIO 1 /* mingw: C99 printf (the same digits as glibc's) */
#define _POSIX_C_SOURCE 200809L

#include "fmi2Functions.h"
#include "fmi3Functions.h"
#include "model_vars.h" /* the chain's */

#include <ctype.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _WIN32
#include <windows.h>
static void *open_lib(const char *path) { return (void *)LoadLibraryA(path); }
static void *sym(void *lib, const char *name)
{
    FARPROC f = GetProcAddress((HMODULE)lib, name);
    void *p;
    memcpy(&p, &f, sizeof p);
    return p;
}
#else
#include <dlfcn.h>
static void *open_lib(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *sym(void *lib, const char *name) { return dlsym(lib, name); }
#endif

#ifndef DFO_CHAIN_N
#define DFO_CHAIN_N 2
#endif
#define NSETS 300
#define NPTS 16
#define HALF (NPTS / 2)
#define NB 6 /* the largest n of a set */
#define NMAXB (NB > DFO_CHAIN_N ? NB : DFO_CHAIN_N)
#define PI 3.14159265358979323846

/* ---- the parameter sets ------------------------------------------------------------------- */

typedef struct {
    size_t n;
    double m[NMAXB], k[NMAXB], c[NMAXB], P0[NMAXB], phi[NMAXB], N[NMAXB], mu_s[NMAXB], chi[NMAXB], x0[NMAXB],
        v0[NMAXB], F_ext[NMAXB];
    double k_end, c_end, omega, h, alpha, dt;
    int scheme, inputs;
} cset;

static uint64_t rng(uint64_t *s) /* splitmix64 */
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

static double unif(uint64_t *s, double a, double b) { return a + (b - a) * ((double)(rng(s) >> 11) * 0x1p-53); }

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
    return p;
}

/* ---- printing ------------------------------------------------------------------------------ */

static uint64_t bits(double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

static void put_real(double x) { printf(" %.17g:%016" PRIx64, x, bits(x)); }

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

static void put_state(FILE *f, int set, const unsigned char *b, size_t n)
{
    fprintf(f, "state %d ", set);
    for (size_t j = 0; j < n; j++) fprintf(f, "%02x", b[j]);
    fprintf(f, "\n");
}

#define MAX_STATE (1 << 20)

typedef struct {
    unsigned char *bytes[NSETS];
    size_t size[NSETS];
} state_table;

static void read_states(FILE *f, state_table *tab)
{
    static char line[2 * MAX_STATE + 64];
    memset(tab, 0, sizeof *tab);
    while (fgets(line, sizeof line, f)) {
        int s, off = 0;
        if (sscanf(line, "state %d %n", &s, &off) != 1 || s < 0 || s >= NSETS || tab->bytes[s]) continue;
        const size_t len = strlen(line + off) / 2 + 1;
        unsigned char *b = (unsigned char *)malloc(len);
        size_t n = 0;
        if (!b) return;
        for (const char *c = line + off; isxdigit((unsigned char)c[0]) && isxdigit((unsigned char)c[1]) && n < len;
             c += 2) {
            unsigned v;
            if (sscanf(c, "%2x", &v) != 1) break;
            b[n++] = (unsigned char)v;
        }
        tab->bytes[s] = b;
        tab->size[s] = n;
    }
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

static const unsigned ARRAY_VR[DFO_NUM_AP] = {VR_m, VR_k, VR_c, VR_P0, VR_phi, VR_N, VR_mu_s, VR_chi, VR_x0, VR_v0};
static const unsigned SCALAR_VR[5] = {VR_k_end, VR_c_end, VR_omega, VR_h, VR_alpha};

#define LOAD(api, field, name)                                                                       \
    do {                                                                                             \
        void *p_ = sym(lib, name);                                                                   \
        if (!p_) {                                                                                   \
            fprintf(stderr, "chain_harness: %s not exported\n", name);                               \
            return 1;                                                                                \
        }                                                                                            \
        memcpy(&(api)->field, &p_, sizeof p_);                                                       \
    } while (0)

/* ---- FMI 2.0 ------------------------------------------------------------------------------- */

typedef struct {
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter_init;
    fmi2ExitInitializationModeTYPE *exit_init;
    fmi2SetRealTYPE *set_real;
    fmi2SetIntegerTYPE *set_integer;
    fmi2GetRealTYPE *get_real;
    fmi2GetIntegerTYPE *get_integer;
    fmi2DoStepTYPE *do_step;
    fmi2GetFMUstateTYPE *get_state;
    fmi2SetFMUstateTYPE *set_state;
    fmi2FreeFMUstateTYPE *free_state;
    fmi2SerializedFMUstateSizeTYPE *state_size;
    fmi2SerializeFMUstateTYPE *serialize;
    fmi2DeSerializeFMUstateTYPE *deserialize;
} fmi2_api;

static void logger2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status st, fmi2String cat, fmi2String msg, ...)
{
    (void)env;
    (void)name;
    (void)cat;
    if (st >= fmi2Error) fprintf(stderr, "fmu: %s\n", msg);
}

static int load2(void *lib, fmi2_api *a)
{
    LOAD(a, instantiate, "fmi2Instantiate");
    LOAD(a, free_instance, "fmi2FreeInstance");
    LOAD(a, setup, "fmi2SetupExperiment");
    LOAD(a, enter_init, "fmi2EnterInitializationMode");
    LOAD(a, exit_init, "fmi2ExitInitializationMode");
    LOAD(a, set_real, "fmi2SetReal");
    LOAD(a, set_integer, "fmi2SetInteger");
    LOAD(a, get_real, "fmi2GetReal");
    LOAD(a, get_integer, "fmi2GetInteger");
    LOAD(a, do_step, "fmi2DoStep");
    LOAD(a, get_state, "fmi2GetFMUstate");
    LOAD(a, set_state, "fmi2SetFMUstate");
    LOAD(a, free_state, "fmi2FreeFMUstate");
    LOAD(a, state_size, "fmi2SerializedFMUstateSize");
    LOAD(a, serialize, "fmi2SerializeFMUstate");
    LOAD(a, deserialize, "fmi2DeSerializeFMUstate");
    return 0;
}

static const fmi2CallbackFunctions CB2 = {logger2, calloc, free, NULL, NULL};

/* FMI 2.0: element i (0-based) of the array with value reference base. */
static fmi2ValueReference elem(unsigned base, size_t i) { return (fmi2ValueReference)(base + i + 1); }

static int set_params2(const fmi2_api *a, fmi2Component c, const cset *p)
{
    for (int j = 0; j < DFO_NUM_AP; j++)
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
    return a->set_real(c, SCALAR_VR, 5, sv) == fmi2OK && a->set_integer(c, &vs, 1, &sc) == fmi2OK;
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
    fmi2Component c = a->instantiate("harness", fmi2CoSimulation, MODEL_GUID, "", &CB2, fmi2False, fmi2False);
    if (!c) {
        printf("err %d 0 instantiate\n", set);
        return 1;
    }
    int k0 = 1, fails = 0;
    if (resume) {
        const size_t n = tab->size[set];
        fmi2FMUstate st = NULL;
        if (n == 0 || a->deserialize(c, (const fmi2Byte *)tab->bytes[set], n, &st) != fmi2OK ||
            a->set_state(c, st) != fmi2OK) {
            printf("err %d %d resume\n", set, HALF);
            a->free_instance(c);
            return 1;
        }
        a->free_state(c, &st);
        k0 = HALF + 1;
    } else if (a->setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK || !set_params2(a, c, &p) ||
               a->enter_init(c) != fmi2OK || a->exit_init(c) != fmi2OK) {
        printf("err %d 0 initialisation\n", set);
        a->free_instance(c);
        return 1;
    }
    double r[4 * NMAXB];
    int mode[NMAXB];
    for (int k = k0; k <= NPTS; k++) {
        const double t0 = (k - 1) * p.dt, t1 = k * p.dt;
        if (a->do_step(c, t0, t1 - t0, fmi2True) != fmi2OK || !get_outputs2(a, c, p.n, r, mode)) {
            printf("err %d %d doStep\n", set, k);
            fails++;
            break;
        }
        put_point(set, k, t1, p.n, r, mode);
        if (!resume && k == HALF) {
            fmi2FMUstate st = NULL;
            size_t size = 0;
            unsigned char *buf = NULL;
            if (a->get_state(c, &st) != fmi2OK || a->state_size(c, st, &size) != fmi2OK || size > MAX_STATE ||
                !(buf = (unsigned char *)malloc(size)) || a->serialize(c, st, (fmi2Byte *)buf, size) != fmi2OK) {
                printf("err %d %d serialise\n", set, k);
                fails++;
            } else {
                put_state(states, set, buf, size);
                put_state(stdout, set, buf, size);
            }
            free(buf);
            a->free_state(c, &st);
        }
    }
    a->free_instance(c);
    return fails;
}

/* ---- FMI 3.0 ------------------------------------------------------------------------------- */

typedef struct {
    fmi3InstantiateCoSimulationTYPE *instantiate;
    fmi3FreeInstanceTYPE *free_instance;
    fmi3EnterConfigurationModeTYPE *enter_config;
    fmi3ExitConfigurationModeTYPE *exit_config;
    fmi3EnterInitializationModeTYPE *enter_init;
    fmi3ExitInitializationModeTYPE *exit_init;
    fmi3SetFloat64TYPE *set_float64;
    fmi3SetInt64TYPE *set_int64;
    fmi3SetUInt64TYPE *set_uint64;
    fmi3GetFloat64TYPE *get_float64;
    fmi3GetInt32TYPE *get_int32;
    fmi3DoStepTYPE *do_step;
    fmi3GetFMUStateTYPE *get_state;
    fmi3SetFMUStateTYPE *set_state;
    fmi3FreeFMUStateTYPE *free_state;
    fmi3SerializedFMUStateSizeTYPE *state_size;
    fmi3SerializeFMUStateTYPE *serialize;
    fmi3DeserializeFMUStateTYPE *deserialize;
} fmi3_api;

static void logger3(fmi3InstanceEnvironment env, fmi3Status st, fmi3String cat, fmi3String msg)
{
    (void)env;
    (void)cat;
    if (st >= fmi3Error) fprintf(stderr, "fmu: %s\n", msg);
}

static int load3(void *lib, fmi3_api *a)
{
    LOAD(a, instantiate, "fmi3InstantiateCoSimulation");
    LOAD(a, free_instance, "fmi3FreeInstance");
    LOAD(a, enter_config, "fmi3EnterConfigurationMode");
    LOAD(a, exit_config, "fmi3ExitConfigurationMode");
    LOAD(a, enter_init, "fmi3EnterInitializationMode");
    LOAD(a, exit_init, "fmi3ExitInitializationMode");
    LOAD(a, set_float64, "fmi3SetFloat64");
    LOAD(a, set_int64, "fmi3SetInt64");
    LOAD(a, set_uint64, "fmi3SetUInt64");
    LOAD(a, get_float64, "fmi3GetFloat64");
    LOAD(a, get_int32, "fmi3GetInt32");
    LOAD(a, do_step, "fmi3DoStep");
    LOAD(a, get_state, "fmi3GetFMUState");
    LOAD(a, set_state, "fmi3SetFMUState");
    LOAD(a, free_state, "fmi3FreeFMUState");
    LOAD(a, state_size, "fmi3SerializedFMUStateSize");
    LOAD(a, serialize, "fmi3SerializeFMUState");
    LOAD(a, deserialize, "fmi3DeserializeFMUState");
    return 0;
}

static int set_params3(const fmi3_api *a, fmi3Instance c, const cset *p)
{
    const fmi3ValueReference vn = VR_n;
    const fmi3UInt64 n = p->n;
    if (a->enter_config(c) != fmi3OK || a->set_uint64(c, &vn, 1, &n, 1) != fmi3OK || a->exit_config(c) != fmi3OK)
        return 0;
    for (int j = 0; j < DFO_NUM_AP; j++) {
        const fmi3ValueReference vr = ARRAY_VR[j];
        if (a->set_float64(c, &vr, 1, arr(p, j), p->n) != fmi3OK) return 0;
    }
    const fmi3ValueReference vf = VR_F_ext;
    if (p->inputs && a->set_float64(c, &vf, 1, p->F_ext, p->n) != fmi3OK) return 0;
    const double sv[5] = {p->k_end, p->c_end, p->omega, p->h, p->alpha};
    const fmi3ValueReference vs = VR_scheme;
    const fmi3Int64 sc = p->scheme;
    return a->set_float64(c, SCALAR_VR, 5, sv, 5) == fmi3OK && a->set_int64(c, &vs, 1, &sc, 1) == fmi3OK;
}

static int run3(const fmi3_api *a, int set, FILE *states, const state_table *tab)
{
    const cset p = make_set(set);
    const int resume = tab != NULL;
    fmi3Instance c = a->instantiate("harness", MODEL_GUID, NULL, fmi3False, fmi3False, fmi3False, fmi3False, NULL,
                                    0, NULL, logger3, NULL);
    if (!c) {
        printf("err %d 0 instantiate\n", set);
        return 1;
    }
    int k0 = 1, fails = 0;
    if (resume) { /* the instance has the default n: the state brings its own */
        const size_t n = tab->size[set];
        fmi3FMUState st = NULL;
        if (n == 0 || a->deserialize(c, (const fmi3Byte *)tab->bytes[set], n, &st) != fmi3OK ||
            a->set_state(c, st) != fmi3OK) {
            printf("err %d %d resume\n", set, HALF);
            a->free_instance(c);
            return 1;
        }
        a->free_state(c, &st);
        k0 = HALF + 1;
    } else if (!set_params3(a, c, &p) || a->enter_init(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK ||
               a->exit_init(c) != fmi3OK) {
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
        if (a->do_step(c, t0, t1 - t0, fmi3True, &ev, &term, &early, &last) != fmi3OK ||
            a->get_float64(c, rvr, 4, r, 4 * p.n) != fmi3OK || a->get_int32(c, &vm, 1, mode, p.n) != fmi3OK) {
            printf("err %d %d doStep\n", set, k);
            fails++;
            break;
        }
        int mi[NMAXB];
        for (size_t b = 0; b < p.n; b++) mi[b] = mode[b];
        put_point(set, k, t1, p.n, r, mi);
        if (!resume && k == HALF) {
            fmi3FMUState st = NULL;
            size_t size = 0;
            unsigned char *buf = NULL;
            if (a->get_state(c, &st) != fmi3OK || a->state_size(c, st, &size) != fmi3OK || size > MAX_STATE ||
                !(buf = (unsigned char *)malloc(size)) || a->serialize(c, st, (fmi3Byte *)buf, size) != fmi3OK) {
                printf("err %d %d serialise\n", set, k);
                fails++;
            } else {
                put_state(states, set, buf, size);
                put_state(stdout, set, buf, size);
            }
            free(buf);
            a->free_state(c, &st);
        }
    }
    a->free_instance(c);
    return fails;
}

int main(int argc, char **argv)
{
    if ((argc != 5 && !(argc == 6 && !strcmp(argv[5], "fixed"))) || (strcmp(argv[1], "fmi2") && strcmp(argv[1], "fmi3")) ||
        (strcmp(argv[3], "run") && strcmp(argv[3], "resume"))) {
        fprintf(stderr, "usage: chain_harness fmi2|fmi3 LIBRARY run|resume STATES [fixed]\n");
        return 2;
    }
    const int fixed_only = argc == 6;
    const int fmi3 = !strcmp(argv[1], "fmi3"), resume = !strcmp(argv[3], "resume");
    void *lib = open_lib(argv[2]);
    if (!lib) {
        fprintf(stderr, "chain_harness: cannot load %s\n", argv[2]);
        return 2;
    }
    FILE *states = fopen(argv[4], resume ? "rb" : "wb"); /* the same bytes on every platform */
    if (!states) {
        fprintf(stderr, "chain_harness: cannot open %s\n", argv[4]);
        return 2;
    }
    fmi2_api a2;
    fmi3_api a3;
    memset(&a2, 0, sizeof a2);
    memset(&a3, 0, sizeof a3);
    if (fmi3 ? load3(lib, &a3) : load2(lib, &a2)) return 2;
    static state_table tab;
    if (resume) read_states(states, &tab);
    int fails = 0;
    for (int set = 0; set < NSETS; set++)
        if (!fixed_only || make_set(set).n == DFO_CHAIN_N)
            fails += fmi3 ? run3(&a3, set, states, resume ? &tab : NULL) : run2(&a2, set, states, resume ? &tab : NULL);
    fclose(states);
    for (int set = 0; set < NSETS; set++) free(tab.bytes[set]);
    fprintf(stderr, "chain_harness: %d sets, %d failed calls\n", NSETS, fails);
    return 0; /* failed calls are part of the compared output */
}
