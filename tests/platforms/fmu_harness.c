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
 * A resumed run's "out" lines equal the second half of the run's "out" lines. */
#define __USE_MINGW_ANSI_STDIO 1 /* mingw: C99 printf (the same digits as glibc's) */
#define _POSIX_C_SOURCE 200809L

#include "fmi2Functions.h"
#include "fmi3Functions.h"
#include "model_vars.h"

#include <ctype.h>
#include <inttypes.h>
#include <stdarg.h>
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

#define NSETS 300
#define NPTS 16
#define HALF (NPTS / 2)
#define PI 3.14159265358979323846

/* ---- the parameter sets ------------------------------------------------------------------- */

typedef struct {
    double m, k, c, P0, omega, phi, N, mu_s, chi, x0, v0, h, alpha, dt;
    int scheme, friction_updates;
} pset;

static uint64_t rng(uint64_t *s) /* splitmix64 */
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

static double unif(uint64_t *s, double a, double b) { return a + (b - a) * ((double)(rng(s) >> 11) * 0x1p-53); }

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

static void put_state(FILE *f, int set, const unsigned char *b, size_t n)
{
    fprintf(f, "state %d ", set);
    for (size_t j = 0; j < n; j++) fprintf(f, "%02x", b[j]);
    fprintf(f, "\n");
}

/* every set's serialised state from a STATES file, read once */
typedef struct {
    unsigned char *bytes[NSETS];
    size_t size[NSETS];
} state_table;

static void read_states(FILE *f, state_table *tab, size_t max)
{
    static char line[1 << 16];
    memset(tab, 0, sizeof *tab);
    while (fgets(line, sizeof line, f)) {
        int s, off = 0;
        if (sscanf(line, "state %d %n", &s, &off) != 1 || s < 0 || s >= NSETS || tab->bytes[s]) continue;
        unsigned char *b = (unsigned char *)malloc(max);
        size_t n = 0;
        if (!b) return;
        for (const char *c = line + off; isxdigit((unsigned char)c[0]) && isxdigit((unsigned char)c[1]) && n < max;
             c += 2) {
            unsigned v;
            if (sscanf(c, "%2x", &v) != 1) break;
            b[n++] = (unsigned char)v;
        }
        tab->bytes[s] = b;
        tab->size[s] = n;
    }
}

#define REAL_OUTS {VR_x, VR_v, VR_a, VR_F_friction, VR_x_max, VR_x_min, VR_stick_fraction, VR_E_friction}
#define INT_OUTS {VR_mode, VR_transitions}
#define MAX_STATE 4096

/* ---- FMI 2.0 ------------------------------------------------------------------------------- */

typedef struct {
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2SetupExperimentTYPE *setup;
    fmi2EnterInitializationModeTYPE *enter_init;
    fmi2ExitInitializationModeTYPE *exit_init;
    fmi2SetRealTYPE *set_real;
    fmi2SetIntegerTYPE *set_integer;
    fmi2SetBooleanTYPE *set_boolean;
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

#define LOAD(api, field, name)                                                                       \
    do {                                                                                             \
        void *p_ = sym(lib, name);                                                                   \
        if (!p_) {                                                                                   \
            fprintf(stderr, "fmu_harness: %s not exported\n", name);                                 \
            return 1;                                                                                \
        }                                                                                            \
        memcpy(&(api)->field, &p_, sizeof p_);                                                       \
    } while (0)

static int load2(void *lib, fmi2_api *a)
{
    LOAD(a, instantiate, "fmi2Instantiate");
    LOAD(a, free_instance, "fmi2FreeInstance");
    LOAD(a, setup, "fmi2SetupExperiment");
    LOAD(a, enter_init, "fmi2EnterInitializationMode");
    LOAD(a, exit_init, "fmi2ExitInitializationMode");
    LOAD(a, set_real, "fmi2SetReal");
    LOAD(a, set_integer, "fmi2SetInteger");
    LOAD(a, set_boolean, "fmi2SetBoolean");
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

static int run2(const fmi2_api *a, int set, FILE *states, const state_table *tab)
{
    const pset p = make_set(set);
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
        if (n == 0 || a->deserialize(c, (const fmi2Byte *)tab->bytes[set], n, &st) != fmi2OK || a->set_state(c, st) != fmi2OK) {
            printf("err %d %d resume\n", set, HALF);
            a->free_instance(c);
            return 1;
        }
        a->free_state(c, &st);
        k0 = HALF + 1;
    } else {
        const fmi2ValueReference vr[] = {VR_m, VR_k, VR_c, VR_P0, VR_omega, VR_phi, VR_N, VR_mu_s, VR_chi,
                                         VR_x0, VR_v0, VR_h, VR_alpha};
        const fmi2Real rv[] = {p.m, p.k, p.c, p.P0, p.omega, p.phi, p.N, p.mu_s, p.chi, p.x0, p.v0, p.h, p.alpha};
        const fmi2ValueReference ivr[] = {VR_scheme, VR_frictionUpdates}, bvr[] = {VR_observe};
        const fmi2Integer iv[] = {p.scheme, p.friction_updates};
        const fmi2Boolean bv[] = {fmi2True};
        if (a->setup(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK || a->set_real(c, vr, 13, rv) != fmi2OK ||
            a->set_integer(c, ivr, 2, iv) != fmi2OK || a->set_boolean(c, bvr, 1, bv) != fmi2OK ||
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
        if (a->do_step(c, t0, t1 - t0, fmi2True) != fmi2OK || a->get_real(c, rvr, 8, r) != fmi2OK ||
            a->get_integer(c, ivr, 2, n) != fmi2OK) {
            printf("err %d %d doStep\n", set, k);
            fails++;
            break;
        }
        put_point(set, k, t1, r, n);
        if (!resume && k == HALF) {
            fmi2FMUstate st = NULL;
            size_t size = 0;
            unsigned char buf[MAX_STATE];
            if (a->get_state(c, &st) != fmi2OK || a->state_size(c, st, &size) != fmi2OK || size > sizeof buf ||
                a->serialize(c, st, (fmi2Byte *)buf, size) != fmi2OK) {
                printf("err %d %d serialise\n", set, k);
                fails++;
            } else {
                put_state(states, set, buf, size);
                put_state(stdout, set, buf, size);
            }
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
    fmi3EnterInitializationModeTYPE *enter_init;
    fmi3ExitInitializationModeTYPE *exit_init;
    fmi3SetFloat64TYPE *set_float64;
    fmi3SetInt32TYPE *set_int32;
    fmi3SetInt64TYPE *set_int64;
    fmi3SetBooleanTYPE *set_boolean;
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
    LOAD(a, enter_init, "fmi3EnterInitializationMode");
    LOAD(a, exit_init, "fmi3ExitInitializationMode");
    LOAD(a, set_float64, "fmi3SetFloat64");
    LOAD(a, set_int32, "fmi3SetInt32");
    LOAD(a, set_int64, "fmi3SetInt64");
    LOAD(a, set_boolean, "fmi3SetBoolean");
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

static int run3(const fmi3_api *a, int set, FILE *states, const state_table *tab)
{
    const pset p = make_set(set);
    const int resume = tab != NULL;
    fmi3Instance c = a->instantiate("harness", MODEL_GUID, NULL, fmi3False, fmi3False, fmi3False, fmi3False, NULL,
                                    0, NULL, logger3, NULL);
    if (!c) {
        printf("err %d 0 instantiate\n", set);
        return 1;
    }
    int k0 = 1, fails = 0;
    if (resume) {
        const size_t n = tab->size[set];
        fmi3FMUState st = NULL;
        if (n == 0 || a->deserialize(c, (const fmi3Byte *)tab->bytes[set], n, &st) != fmi3OK || a->set_state(c, st) != fmi3OK) {
            printf("err %d %d resume\n", set, HALF);
            a->free_instance(c);
            return 1;
        }
        a->free_state(c, &st);
        k0 = HALF + 1;
    } else {
        const fmi3ValueReference vr[] = {VR_m, VR_k, VR_c, VR_P0, VR_omega, VR_phi, VR_N, VR_mu_s, VR_chi,
                                         VR_x0, VR_v0, VR_h, VR_alpha};
        const fmi3Float64 rv[] = {p.m, p.k, p.c, p.P0, p.omega, p.phi, p.N, p.mu_s, p.chi, p.x0, p.v0, p.h, p.alpha};
        const fmi3ValueReference svr[] = {VR_scheme}, ivr[] = {VR_frictionUpdates}, bvr[] = {VR_observe};
        const fmi3Int64 sv[] = {p.scheme};
        const fmi3Int32 iv[] = {p.friction_updates};
        const fmi3Boolean bv[] = {fmi3True};
        if (a->enter_init(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK ||
            a->set_float64(c, vr, 13, rv, 13) != fmi3OK || a->set_int64(c, svr, 1, sv, 1) != fmi3OK ||
            a->set_int32(c, ivr, 1, iv, 1) != fmi3OK || a->set_boolean(c, bvr, 1, bv, 1) != fmi3OK ||
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
        if (a->do_step(c, t0, t1 - t0, fmi3True, &ev, &term, &early, &last) != fmi3OK ||
            a->get_float64(c, rvr, 8, r, 8) != fmi3OK || a->get_int32(c, ivr, 2, n, 2) != fmi3OK) {
            printf("err %d %d doStep\n", set, k);
            fails++;
            break;
        }
        const int ni[2] = {n[0], n[1]};
        put_point(set, k, t1, r, ni);
        if (!resume && k == HALF) {
            fmi3FMUState st = NULL;
            size_t size = 0;
            unsigned char buf[MAX_STATE];
            if (a->get_state(c, &st) != fmi3OK || a->state_size(c, st, &size) != fmi3OK || size > sizeof buf ||
                a->serialize(c, st, (fmi3Byte *)buf, size) != fmi3OK) {
                printf("err %d %d serialise\n", set, k);
                fails++;
            } else {
                put_state(states, set, buf, size);
                put_state(stdout, set, buf, size);
            }
            a->free_state(c, &st);
        }
    }
    a->free_instance(c);
    return fails;
}

int main(int argc, char **argv)
{
    if (argc != 5 || (strcmp(argv[1], "fmi2") && strcmp(argv[1], "fmi3")) ||
        (strcmp(argv[3], "run") && strcmp(argv[3], "resume"))) {
        fprintf(stderr, "usage: fmu_harness fmi2|fmi3 LIBRARY run|resume STATES\n");
        return 2;
    }
    const int fmi3 = !strcmp(argv[1], "fmi3"), resume = !strcmp(argv[3], "resume");
    void *lib = open_lib(argv[2]);
    if (!lib) {
        fprintf(stderr, "fmu_harness: cannot load %s\n", argv[2]);
        return 2;
    }
    FILE *states = fopen(argv[4], resume ? "rb" : "wb"); /* the same bytes on every platform */
    if (!states) {
        fprintf(stderr, "fmu_harness: cannot open %s\n", argv[4]);
        return 2;
    }
    fmi2_api a2;
    fmi3_api a3;
    if (fmi3 ? load3(lib, &a3) : load2(lib, &a2)) return 2;
    static state_table tab;
    if (resume) read_states(states, &tab, MAX_STATE);
    int fails = 0;
    for (int set = 0; set < NSETS; set++)
        fails += fmi3 ? run3(&a3, set, states, resume ? &tab : NULL) : run2(&a2, set, states, resume ? &tab : NULL);
    fclose(states);
    for (int set = 0; set < NSETS; set++) free(tab.bytes[set]);
    fprintf(stderr, "fmu_harness: %d sets, %d failed calls\n", NSETS, fails);
    return 0; /* failed calls are part of the compared output */
}
