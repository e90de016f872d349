/* What the cross-platform harnesses (fmu_harness.c for the oscillator, chain_harness.c for the
 * chain) share: loading the FMU's shared library (dlopen / LoadLibrary) and its FMI 2.0 or 3.0
 * functions, the host callbacks, the random parameter draws, printing reals as %.17g and bits,
 * reading and writing serialised FMU states, starting an instance (new or resumed), and the command
 * line.
 *
 * Include once, after fmi2Functions.h, fmi3Functions.h and the model's model_vars.h, with
 * HARNESS_NAME (the program's name, for messages) and MAX_STATE (the largest serialised state, in
 * bytes) defined. */
#ifndef DFO_HARNESS_COMMON_H
#define DFO_HARNESS_COMMON_H

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

#ifndef NSETS
#define NSETS 300 /* (a harness may add sets after these: define it before the include) */
#endif
#define NPTS 16
#define HALF (NPTS / 2)
#define PI 3.14159265358979323846

/* ---- the parameter draws (only +, -, *, /: the same sets on every platform) -------------------- */

static uint64_t rng(uint64_t *s) /* splitmix64 */
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
}

static double unif(uint64_t *s, double a, double b) { return a + (b - a) * ((double)(rng(s) >> 11) * 0x1p-53); }

/* ---- printing and reading ----------------------------------------------------------------------- */

static uint64_t bits(double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

static void put_real(double x) { printf(" %.17g:%016" PRIx64, x, bits(x)); }

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

/* ---- the FMI functions a harness calls ---------------------------------------------------------- */

#define LOAD(api, field, name)                                                                       \
    do {                                                                                             \
        void *p_ = sym(lib, name);                                                                   \
        if (!p_) {                                                                                   \
            fprintf(stderr, HARNESS_NAME ": %s not exported\n", name);                               \
            return 1;                                                                                \
        }                                                                                            \
        memcpy(&(api)->field, &p_, sizeof p_);                                                       \
    } while (0)

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

typedef struct {
    fmi3InstantiateCoSimulationTYPE *instantiate;
    fmi3FreeInstanceTYPE *free_instance;
    fmi3EnterConfigurationModeTYPE *enter_config;
    fmi3ExitConfigurationModeTYPE *exit_config;
    fmi3EnterInitializationModeTYPE *enter_init;
    fmi3ExitInitializationModeTYPE *exit_init;
    fmi3SetFloat64TYPE *set_float64;
    fmi3SetInt32TYPE *set_int32;
    fmi3SetInt64TYPE *set_int64;
    fmi3SetUInt64TYPE *set_uint64;
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

static int load3(void *lib, fmi3_api *a)
{
    LOAD(a, instantiate, "fmi3InstantiateCoSimulation");
    LOAD(a, free_instance, "fmi3FreeInstance");
    LOAD(a, enter_config, "fmi3EnterConfigurationMode");
    LOAD(a, exit_config, "fmi3ExitConfigurationMode");
    LOAD(a, enter_init, "fmi3EnterInitializationMode");
    LOAD(a, exit_init, "fmi3ExitInitializationMode");
    LOAD(a, set_float64, "fmi3SetFloat64");
    LOAD(a, set_int32, "fmi3SetInt32");
    LOAD(a, set_int64, "fmi3SetInt64");
    LOAD(a, set_uint64, "fmi3SetUInt64");
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

/* ---- host callbacks: errors to stderr ----------------------------------------------------------- */

static void logger2(fmi2ComponentEnvironment env, fmi2String name, fmi2Status st, fmi2String cat, fmi2String msg, ...)
{
    (void)env;
    (void)name;
    (void)cat;
    if (st >= fmi2Error) fprintf(stderr, "fmu: %s\n", msg);
}

static const fmi2CallbackFunctions CB2 = {logger2, calloc, free, NULL, NULL};

static void logger3(fmi3InstanceEnvironment env, fmi3Status st, fmi3String cat, fmi3String msg)
{
    (void)env;
    (void)cat;
    if (st >= fmi3Error) fprintf(stderr, "fmu: %s\n", msg);
}

/* ---- an instance of a set, and its state at point HALF ---------------------------------------------- */

/* A new instance for the set, in a resumed run (tab given) in the set's state from tab; NULL (with an
 * "err" line) on failure. *k0: the first point to run. */
static fmi2Component start2(const fmi2_api *a, int set, const state_table *tab, int *k0)
{
    *k0 = tab ? HALF + 1 : 1;
    fmi2Component c = a->instantiate("harness", fmi2CoSimulation, MODEL_GUID, "", &CB2, fmi2False, fmi2False);
    if (!c) {
        printf("err %d 0 instantiate\n", set);
        return NULL;
    }
    if (!tab) return c;
    const size_t n = tab->size[set];
    fmi2FMUstate st = NULL;
    if (n == 0 || a->deserialize(c, (const fmi2Byte *)tab->bytes[set], n, &st) != fmi2OK ||
        a->set_state(c, st) != fmi2OK) {
        printf("err %d %d resume\n", set, HALF);
        a->free_instance(c);
        return NULL;
    }
    a->free_state(c, &st);
    return c;
}

static fmi3Instance start3(const fmi3_api *a, int set, const state_table *tab, int *k0)
{
    *k0 = tab ? HALF + 1 : 1;
    fmi3Instance c = a->instantiate("harness", MODEL_GUID, NULL, fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0,
                                    NULL, logger3, NULL);
    if (!c) {
        printf("err %d 0 instantiate\n", set);
        return NULL;
    }
    if (!tab) return c;
    const size_t n = tab->size[set];
    fmi3FMUState st = NULL;
    if (n == 0 || a->deserialize(c, (const fmi3Byte *)tab->bytes[set], n, &st) != fmi3OK ||
        a->set_state(c, st) != fmi3OK) {
        printf("err %d %d resume\n", set, HALF);
        a->free_instance(c);
        return NULL;
    }
    a->free_state(c, &st);
    return c;
}

/* a serialised state: n bytes at b (malloc'ed), or b NULL when a call failed */
typedef struct {
    unsigned char *b;
    size_t n;
} state_bytes;

static state_bytes serialise2(const fmi2_api *a, fmi2Component c)
{
    fmi2FMUstate st = NULL;
    state_bytes s = {NULL, 0};
    if (a->get_state(c, &st) != fmi2OK || a->state_size(c, st, &s.n) != fmi2OK || s.n > MAX_STATE ||
        !(s.b = (unsigned char *)malloc(s.n)) || a->serialize(c, st, (fmi2Byte *)s.b, s.n) != fmi2OK) {
        free(s.b);
        s.b = NULL;
    }
    a->free_state(c, &st);
    return s;
}

static state_bytes serialise3(const fmi3_api *a, fmi3Instance c)
{
    fmi3FMUState st = NULL;
    state_bytes s = {NULL, 0};
    if (a->get_state(c, &st) != fmi3OK || a->state_size(c, st, &s.n) != fmi3OK || s.n > MAX_STATE ||
        !(s.b = (unsigned char *)malloc(s.n)) || a->serialize(c, st, (fmi3Byte *)s.b, s.n) != fmi3OK) {
        free(s.b);
        s.b = NULL;
    }
    a->free_state(c, &st);
    return s;
}

/* The state serialised at point k to states and stdout (freed); the number of failed calls (0 or 1). */
static int save_state(FILE *states, int set, int k, state_bytes s)
{
    if (!s.b) {
        printf("err %d %d serialise\n", set, k);
        return 1;
    }
    put_state(states, set, s.b, s.n);
    put_state(stdout, set, s.b, s.n);
    free(s.b);
    return 0;
}

/* ---- the command line ------------------------------------------------------------------------- */

typedef int (*harness_run2)(const fmi2_api *a, int set, FILE *states, const state_table *tab);
typedef int (*harness_run3)(const fmi3_api *a, int set, FILE *states, const state_table *tab);

/*   HARNESS_NAME fmi2|fmi3 LIBRARY run|resume STATES [fixed]
 * Every set through run2 or run3 (tab NULL in a run); with "fixed" (accepted only when keep_fixed is
 * given) only the sets keep_fixed keeps. Exit 2 on a wrong command line, a library or file that
 * cannot be opened or a missing FMI function; 0 otherwise (failed calls are part of the output). */
static int harness_main(int argc, char **argv, harness_run2 run2, harness_run3 run3, int (*keep_fixed)(int set))
{
    const int fixed_only = keep_fixed && argc == 6 && !strcmp(argv[5], "fixed");
    if ((argc != 5 && !fixed_only) || (strcmp(argv[1], "fmi2") && strcmp(argv[1], "fmi3")) ||
        (strcmp(argv[3], "run") && strcmp(argv[3], "resume"))) {
        fprintf(stderr, "usage: " HARNESS_NAME " fmi2|fmi3 LIBRARY run|resume STATES%s\n", keep_fixed ? " [fixed]" : "");
        return 2;
    }
    const int fmi3 = !strcmp(argv[1], "fmi3"), resume = !strcmp(argv[3], "resume");
    void *lib = open_lib(argv[2]);
    if (!lib) {
        fprintf(stderr, HARNESS_NAME ": cannot load %s\n", argv[2]);
        return 2;
    }
    FILE *states = fopen(argv[4], resume ? "rb" : "wb"); /* the same bytes on every platform */
    if (!states) {
        fprintf(stderr, HARNESS_NAME ": cannot open %s\n", argv[4]);
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
        if (!fixed_only || keep_fixed(set))
            fails += fmi3 ? run3(&a3, set, states, resume ? &tab : NULL) : run2(&a2, set, states, resume ? &tab : NULL);
    fclose(states);
    for (int set = 0; set < NSETS; set++) free(tab.bytes[set]);
    fprintf(stderr, HARNESS_NAME ": %d sets, %d failed calls\n", NSETS, fails);
    return 0; /* failed calls are part of the compared output */
}

#endif
