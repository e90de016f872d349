/* The DryFrictionChain FMUs through their FMI APIs, each shared library loaded with dlopen (they
 * export the same fmi2* / fmi3* names as the oscillator's):
 *   - FMI 3.0 rules: n only in configuration mode and in [1, 4096], arrays of n values (a wrong
 *     nValues rejected), per-element range errors naming the element ("invalid value -1 for m[3]"),
 *     a rejected call changes nothing, scheme 4 (exact) rejected;
 *   - the FMI 2.0 chain (n = DFO_CHAIN_N, names m[1] ...) and the FMI 3.0 chain with the same n give
 *     the same x, v, a, F_friction and mode, bit for bit, inputs included;
 *   - n = 1 against the oscillator's FMI 3.0 FMU (three schemes, two cases): the same mode at every
 *     point, x, v, a and F_friction to N1_TOL relative (the chain's physics is the oscillator's for
 *     one block; the oscillator steps through the friction engine, whose arithmetic is ordered
 *     otherwise than the chain's own stepper: the two agree to rounding, not bit for bit);
 *   - FMU states: get/set and serialise/deserialise (into an instance of another n) continue bit for
 *     bit; a flipped byte is rejected;
 *   - early return lands on every switch of the physics' own run (chain_advance in one call), at its
 *     time to the bit; event mode gives the switching block's left limit (mode before the switch)
 *     until fmi3UpdateDiscreteStates and its right limit after, x continuous;
 *   - 8 instances of different n in threads give the numbers of serial runs. */
#include "fmi2FunctionTypes.h"
#include "fmi3FunctionTypes.h"
#include "model_vars.h" /* the chain's */
#include "chain.h"
#include "../check.h"

#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* the oscillator's value references (its modelDescription.xml) */
enum { OSC_m = 1, OSC_k = 2, OSC_c = 3, OSC_omega = 5, OSC_N = 7, OSC_mu_s = 8, OSC_chi = 9, OSC_x0 = 10, OSC_h = 12,
       OSC_scheme = 16, OSC_x = 30, OSC_v = 31, OSC_a = 32, OSC_F = 33, OSC_mode = 34 };
#define OSC_GUID "{8c4e81f4-5b2c-4d4e-9a53-2f1d6c0e7a11}"
#define N1_TOL 1e-10 /* n = 1 against the oscillator: x, v, a, F relative to max(|value|, 1) */

#define LOAD(api, field, name)                                     \
    do {                                                           \
        void *p_ = dlsym((api)->lib, name);                        \
        if (!p_) {                                                 \
            fprintf(stderr, "%s: no symbol %s\n", (api)->path, name); \
            exit(2);                                               \
        }                                                          \
        memcpy(&(api)->field, &p_, sizeof p_);                     \
    } while (0)

/* The functions each API loads: (FMI version, field, function name without fmiN); the field has the
 * function's type, fmiN<name>TYPE, and is loaded from the symbol fmiN<name>. */
#define API3(X)                                                                                              \
    X(3, inst, InstantiateCoSimulation) X(3, free_, FreeInstance) X(3, enter_cfg, EnterConfigurationMode)    \
    X(3, exit_cfg, ExitConfigurationMode) X(3, enter_init, EnterInitializationMode)                          \
    X(3, exit_init, ExitInitializationMode) X(3, setF, SetFloat64) X(3, getF, GetFloat64)                    \
    X(3, setU, SetUInt64) X(3, getU, GetUInt64) X(3, getI, GetInt32) X(3, setE, SetInt64)                    \
    X(3, step, DoStep) X(3, term, Terminate) X(3, gst, GetFMUState) X(3, sst, SetFMUState)                   \
    X(3, fst, FreeFMUState) X(3, ssize, SerializedFMUStateSize) X(3, ser, SerializeFMUState)                 \
    X(3, deser, DeserializeFMUState) X(3, eem, EnterEventMode) X(3, upd, UpdateDiscreteStates)               \
    X(3, esm, EnterStepMode)
#define API2(X)                                                                                              \
    X(2, inst, Instantiate) X(2, free_, FreeInstance) X(2, setup, SetupExperiment)                           \
    X(2, enter_init, EnterInitializationMode) X(2, exit_init, ExitInitializationMode)                        \
    X(2, setR, SetReal) X(2, getR, GetReal) X(2, getI, GetInteger) X(2, step, DoStep)
#define API_FIELD(v, field, name) fmi##v##name##TYPE *field;
#define API_LOAD(v, field, name) LOAD(a, field, "fmi" #v #name);

typedef struct {
    const char *path;
    void *lib;
    API3(API_FIELD)
} api3;

typedef struct {
    const char *path;
    void *lib;
    API2(API_FIELD)
} api2;

static void open_lib(const char *path, void **lib)
{
    *lib = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (!*lib) {
        fprintf(stderr, "dlopen %s: %s\n", path, dlerror());
        exit(2);
    }
}

static void load3(api3 *a, const char *path)
{
    a->path = path;
    open_lib(path, &a->lib);
    API3(API_LOAD)
}

static void load2(api2 *a, const char *path)
{
    a->path = path;
    open_lib(path, &a->lib);
    API2(API_LOAD)
}

/* ---- a host: the last message, the errors ---------------------------------------------------- */

typedef struct {
    int errors;
    char last[512];
} env;

static void log3(fmi3InstanceEnvironment e, fmi3Status status, fmi3String category, fmi3String message)
{
    env *E = (env *)e;
    (void)category;
    if (!E) return;
    if (status == fmi3Error) E->errors++;
    snprintf(E->last, sizeof E->last, "%s", message);
}

static void logger2(fmi2ComponentEnvironment e, fmi2String name, fmi2Status status, fmi2String category,
                 fmi2String message, ...)
{
    env *E = (env *)e;
    (void)name;
    (void)category;
    if (!E) return;
    if (status == fmi2Error) E->errors++;
    snprintf(E->last, sizeof E->last, "%s", message);
}

static int has(const env *E, const char *what) { return strstr(E->last, what) != NULL; }

/* ---- the test chains -------------------------------------------------------------------------- */

#define NMAX (DFO_CHAIN_N > 16 ? DFO_CHAIN_N : 16) /* blocks of the test chains and of the FMI 2.0 build */
typedef struct {
    size_t n;
    double m[NMAX], k[NMAX], c[NMAX], P0[NMAX], phi[NMAX], N[NMAX], mu_s[NMAX], chi[NMAX], x0[NMAX], v0[NMAX];
    double k_end, c_end, omega, h, alpha;
    int scheme;
} chain_case;

/* Unit blocks and springs, heavy friction (a stick-dominated chain), varied per block. */
static chain_case make_case(size_t n, int scheme)
{
    chain_case C;
    memset(&C, 0, sizeof C);
    C.n = n;
    for (size_t i = 0; i < n; i++) {
        C.m[i] = 1.0 + 0.1 * (double)(i % 3);
        C.k[i] = 1.0;
        C.c[i] = 0.02 * (double)(i % 2);
        C.P0[i] = (i == 0) ? 1.0 : 0.3 * (double)(i % 2);
        C.phi[i] = 0.0;
        C.N[i] = 1.2 - 0.2 * (double)(i % 3);
        C.mu_s[i] = 0.4;
        C.chi[i] = (i % 2) ? 1.3 : 0.7;
        C.x0[i] = 0.01 * (double)i;
        C.v0[i] = (i == 1) ? 0.2 : 0.0;
    }
    C.k_end = 0.5;
    C.c_end = 0.05;
    C.omega = 0.5;
    C.h = 2.0 * 3.14159265358979323846 / 0.5 / 400.0;
    C.alpha = -0.1;
    C.scheme = scheme;
    return C;
}

static const double *arr(const chain_case *C, int slot)
{
    switch (slot) {
    case DFO_AP_m: return C->m;
    case DFO_AP_k: return C->k;
    case DFO_AP_c: return C->c;
    case DFO_AP_P0: return C->P0;
    case DFO_AP_phi: return C->phi;
    case DFO_AP_N: return C->N;
    case DFO_AP_mu_s: return C->mu_s;
    case DFO_AP_chi: return C->chi;
    case DFO_AP_x0: return C->x0;
    default: return C->v0;
    }
}

/* the arrays these tests set (the others keep their start values) */
enum { N_ARRAYS_SET = 10 };
static const fmi3ValueReference ARRAY_VR[N_ARRAYS_SET] = {VR_m, VR_k, VR_c, VR_P0, VR_phi, VR_N, VR_mu_s, VR_chi,
                                                       VR_x0, VR_v0};

/* Instantiate an FMI 3.0 chain of C's n with C's parameters, initialised at t = 0. */
static fmi3Instance start3(const api3 *A, env *E, const chain_case *C, int event_mode, int early_return)
{
    fmi3Instance in = A->inst("chain", MODEL_GUID, NULL, fmi3False, fmi3False, event_mode ? fmi3True : fmi3False,
                              early_return ? fmi3True : fmi3False, NULL, 0, E, log3, NULL);
    if (!in) return NULL;
    const fmi3ValueReference vn = VR_n;
    const fmi3UInt64 n = C->n;
    int ok = A->enter_cfg(in) == fmi3OK && A->setU(in, &vn, 1, &n, 1) == fmi3OK && A->exit_cfg(in) == fmi3OK;
    for (int j = 0; ok && j < N_ARRAYS_SET; j++) ok = A->setF(in, &ARRAY_VR[j], 1, arr(C, j), C->n) == fmi3OK;
    const fmi3ValueReference svr[5] = {VR_k_end, VR_c_end, VR_omega, VR_h, VR_alpha};
    const fmi3Float64 sv[5] = {C->k_end, C->c_end, C->omega, C->h, C->alpha};
    const fmi3ValueReference vs = VR_scheme;
    const fmi3Int64 sc = C->scheme;
    ok = ok && A->setF(in, svr, 5, sv, 5) == fmi3OK && A->setE(in, &vs, 1, &sc, 1) == fmi3OK;
    ok = ok && A->enter_init(in, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK && A->exit_init(in) == fmi3OK;
    if (ok && event_mode) ok = A->esm(in) == fmi3OK;
    if (!ok) {
        fprintf(stderr, "start3: %s\n", E->last);
        A->free_(in);
        return NULL;
    }
    return in;
}

typedef struct {
    double x[NMAX], v[NMAX], a[NMAX], F[NMAX];
    int mode[NMAX];
} outputs;

static int read3(const api3 *A, fmi3Instance in, size_t n, outputs *o)
{
    const fmi3ValueReference vr[4] = {VR_x, VR_v, VR_a, VR_F_friction};
    double buf[4 * NMAX];
    const fmi3ValueReference vm = VR_mode;
    if (A->getF(in, vr, 4, buf, 4 * n) != fmi3OK || A->getI(in, &vm, 1, o->mode, n) != fmi3OK) return 0;
    for (size_t i = 0; i < n; i++) {
        o->x[i] = buf[i];
        o->v[i] = buf[n + i];
        o->a[i] = buf[2 * n + i];
        o->F[i] = buf[3 * n + i];
    }
    return 1;
}

static int same(const outputs *a, const outputs *b, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (memcmp(&a->x[i], &b->x[i], 8) || memcmp(&a->v[i], &b->v[i], 8) || memcmp(&a->a[i], &b->a[i], 8) ||
            memcmp(&a->F[i], &b->F[i], 8) || a->mode[i] != b->mode[i])
            return 0;
    return 1;
}

static int step3(const api3 *A, fmi3Instance in, double t, double dt)
{
    fmi3Boolean ev, term, early;
    fmi3Float64 last;
    return A->step(in, t, dt, fmi3True, &ev, &term, &early, &last) == fmi3OK;
}

/* ---- 1. FMI 3.0 rules ------------------------------------------------------------------------- */

static void test_rules(tally *T, const api3 *A)
{
    env E = {0, ""};
    fmi3Instance in = A->inst("rules", MODEL_GUID, NULL, fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, &E, log3,
                              NULL);
    EXPECT(in != NULL);
    if (!in) return;
    const fmi3ValueReference vn = VR_n, vm = VR_m, vs = VR_scheme, vx = VR_x;
    fmi3UInt64 n = 0;
    EXPECT(A->getU(in, &vn, 1, &n, 1) == fmi3OK && n == START_n);
    fmi3UInt64 five = 5, zero = 0, big = 4097;
    EXPECT(A->setU(in, &vn, 1, &five, 1) == fmi3Error && has(&E, "structural parameter"));
    EXPECT(A->enter_cfg(in) == fmi3OK);
    EXPECT(A->setU(in, &vn, 1, &zero, 1) == fmi3Error && has(&E, "invalid value 0 for n"));
    EXPECT(A->setU(in, &vn, 1, &big, 1) == fmi3Error && has(&E, "invalid value 4097 for n"));
    EXPECT(A->setU(in, &vn, 1, &five, 1) == fmi3OK);
    EXPECT(A->exit_cfg(in) == fmi3OK);
    EXPECT(A->getU(in, &vn, 1, &n, 1) == fmi3OK && n == 5);
    EXPECT(A->enter_init(in, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK);
    double m[8] = {0};
    EXPECT(A->getF(in, &vm, 1, m, 5) == fmi3OK && m[0] == START_m && m[4] == START_m);
    EXPECT(A->getF(in, &vm, 1, m, 2) == fmi3Error && has(&E, "nValues = 2") && has(&E, "hold 5 values: m (5)"));
    const double bad[5] = {2.0, 2.0, -1.0, 2.0, 2.0};
    EXPECT(A->setF(in, &vm, 1, bad, 5) == fmi3Error && has(&E, "invalid value -1 for m[3]"));
    EXPECT(A->getF(in, &vm, 1, m, 5) == fmi3OK && m[0] == START_m); /* nothing stored */
    EXPECT(A->setF(in, &vm, 1, bad, 4) == fmi3Error && has(&E, "nValues"));
    const fmi3Int64 four = 4;
    EXPECT(A->setE(in, &vs, 1, &four, 1) == fmi3Error && has(&E, "no exact scheme"));
    EXPECT(A->setU(in, &vn, 1, &five, 1) == fmi3Error && has(&E, "configuration mode"));
    EXPECT(A->enter_cfg(in) == fmi3Error);
    double x[5];
    EXPECT(A->getF(in, &vx, 1, x, 5) == fmi3OK && x[0] == 0.0); /* outputs during initialisation */
    const fmi3ValueReference vN = VR_N, va = VR_a, vf = VR_F_ext;
    const double no_friction[5] = {0.0, 0.0, 0.0, 0.0, 0.0};
    EXPECT(A->setF(in, &vN, 1, no_friction, 5) == fmi3OK);
    EXPECT(A->exit_init(in) == fmi3OK);
    EXPECT(step3(A, in, 0.0, 0.5));
    EXPECT(A->getF(in, &vx, 1, x, 5) == fmi3OK && isfinite(x[4]));
    /* a follows an input at once (no stale value): F_ext = 1 on block 1 adds 1/m = 1 to its a only */
    double a0[5], a1[5];
    const double push[5] = {1.0, 0.0, 0.0, 0.0, 0.0};
    EXPECT(A->getF(in, &va, 1, a0, 5) == fmi3OK && A->setF(in, &vf, 1, push, 5) == fmi3OK &&
           A->getF(in, &va, 1, a1, 5) == fmi3OK);
    EXPECT(fabs(a1[0] - a0[0] - 1.0) < 1e-12 && !memcmp(a0 + 1, a1 + 1, 4 * sizeof(double)));
    EXPECT(A->setF(in, &vm, 1, m, 5) == fmi3Error && has(&E, "fixed parameter"));
    EXPECT(A->term(in) == fmi3OK);
    A->free_(in);
}

/* ---- 2. FMI 2.0 against FMI 3.0 -------------------------------------------------------------- */

static void test_fmi2_vs_fmi3(tally *T, const api2 *B, const api3 *A)
{
    const size_t n = DFO_CHAIN_N;
    for (int scheme = 1; scheme <= 3; scheme++) {
        chain_case C = make_case(n, scheme);
        env E2 = {0, ""}, E3 = {0, ""};
        const fmi2CallbackFunctions cb = {logger2, calloc, free, NULL, &E2};
        fmi2Component c2 = B->inst("chain2", fmi2CoSimulation, MODEL_GUID, NULL, &cb, fmi2False, fmi2False);
        fmi3Instance c3 = start3(A, &E3, &C, 0, 0);
        EXPECT(c2 != NULL && c3 != NULL);
        if (!c2 || !c3) return;
        int ok = B->setup(c2, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK && B->enter_init(c2) == fmi2OK;
        for (int j = 0; ok && j < N_ARRAYS_SET; j++)
            for (size_t i = 0; ok && i < n; i++) {
                const fmi2ValueReference vr = ARRAY_VR[j] + (unsigned)i + 1;
                ok = B->setR(c2, &vr, 1, &arr(&C, j)[i]) == fmi2OK;
            }
        const fmi2ValueReference svr[5] = {VR_k_end, VR_c_end, VR_omega, VR_h, VR_alpha};
        const fmi2Real sv[5] = {C.k_end, C.c_end, C.omega, C.h, C.alpha};
        ok = ok && B->setR(c2, svr, 5, sv) == fmi2OK;
        const fmi2ValueReference vs = VR_scheme;
        fmi2SetIntegerTYPE *setI2;
        void *p = dlsym(B->lib, "fmi2SetInteger");
        memcpy(&setI2, &p, sizeof p);
        const fmi2Integer sc = scheme;
        ok = ok && setI2(c2, &vs, 1, &sc) == fmi2OK && B->exit_init(c2) == fmi2OK;
        EXPECT(ok);
        /* an element beyond n is unknown to the FMI 2.0 FMU */
        const fmi2ValueReference beyond = VR_m + (unsigned)n + 1;
        double dummy;
        EXPECT(B->getR(c2, &beyond, 1, &dummy) == fmi2Error);
        double t = 0.0;
        long differ = 0, points = 0;
        for (int k = 0; k < 300 && ok; k++) {
            const double dt = 0.05 + 0.03 * (double)(k % 7);
            if (k % 50 == 25) { /* inputs on the first block */
                const double F = 0.2 * sin((double)k), Nx = 0.1 * (double)(k % 3);
                const fmi2ValueReference f2[2] = {VR_F_ext + 1, VR_N_ext + 1};
                const fmi2Real fv[2] = {F, Nx};
                ok = B->setR(c2, f2, 2, fv) == fmi2OK;
                double F3[NMAX] = {0}, N3[NMAX] = {0};
                F3[0] = F;
                N3[0] = Nx;
                const fmi3ValueReference vf = VR_F_ext, vnx = VR_N_ext;
                ok = ok && A->setF(c3, &vf, 1, F3, n) == fmi3OK && A->setF(c3, &vnx, 1, N3, n) == fmi3OK;
            }
            ok = ok && B->step(c2, t, dt, fmi2True) == fmi2OK && step3(A, c3, t, dt);
            t += dt;
            outputs o2, o3;
            for (size_t i = 0; ok && i < n; i++) {
                const fmi2ValueReference vr[4] = {VR_x + (unsigned)i + 1, VR_v + (unsigned)i + 1,
                                                  VR_a + (unsigned)i + 1, VR_F_friction + (unsigned)i + 1};
                double r[4];
                const fmi2ValueReference vmo = VR_mode + (unsigned)i + 1;
                ok = B->getR(c2, vr, 4, r) == fmi2OK && B->getI(c2, &vmo, 1, &o2.mode[i]) == fmi2OK;
                o2.x[i] = r[0];
                o2.v[i] = r[1];
                o2.a[i] = r[2];
                o2.F[i] = r[3];
            }
            ok = ok && read3(A, c3, n, &o3);
            differ += ok && !same(&o2, &o3, n);
            points++;
        }
        EXPECT(ok);
        EXPECT(differ == 0);
        printf("FMI 2.0 vs FMI 3.0, n = %lu, scheme %d: %ld points, %ld differ\n", (unsigned long)n, scheme, points,
               differ);
        B->free_(c2);
        A->free_(c3);
    }
}

/* ---- 3. n = 1 against the oscillator ---------------------------------------------------------- */

static void test_n1_vs_oscillator(tally *T, const api3 *A, const api3 *O)
{
    for (int variant = 0; variant < 2; variant++)
        for (int scheme = 1; scheme <= 3; scheme++) {
            chain_case C = make_case(1, scheme);
            C.k_end = 0.0;
            C.c_end = 0.0;
            C.k[0] = variant ? 40.0 : 100.0;
            C.c[0] = variant ? 0.3 : 0.0;
            C.chi[0] = variant ? 1.5 : 0.7;
            C.x0[0] = variant ? 0.01 : 0.0;
            C.v0[0] = 0.0;
            C.m[0] = 1.0;
            C.N[0] = 1.0;
            C.P0[0] = 1.0;
            C.omega = 5.0;
            C.h = 1e-3;
            env E3 = {0, ""}, EO = {0, ""};
            fmi3Instance c = start3(A, &E3, &C, 0, 0);
            fmi3Instance o = O->inst("osc", OSC_GUID, NULL, fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, &EO,
                                     log3, NULL);
            EXPECT(c != NULL && o != NULL);
            if (!c || !o) return;
            const fmi3ValueReference ovr[9] = {OSC_m, OSC_k, OSC_c, OSC_omega, OSC_N, OSC_mu_s, OSC_chi, OSC_x0, OSC_h};
            const fmi3Float64 ov[9] = {C.m[0], C.k[0], C.c[0], C.omega, C.N[0], C.mu_s[0], C.chi[0], C.x0[0], C.h};
            const fmi3ValueReference os = OSC_scheme;
            const fmi3Int64 sc = scheme;
            int ok = O->enter_init(o, fmi3False, 0.0, 0.0, fmi3False, 0.0) == fmi3OK &&
                     O->setF(o, ovr, 9, ov, 9) == fmi3OK && O->setE(o, &os, 1, &sc, 1) == fmi3OK &&
                     O->exit_init(o) == fmi3OK;
            EXPECT(ok);
            long points = 0, differ = 0;
            double rel = 0.0, t = 0.0;
            for (int k = 0; k < 400 && ok; k++) {
                const double dt = (k % 3) ? 0.01 : 0.0137;
                ok = step3(A, c, t, dt) && step3(O, o, t, dt);
                t += dt;
                outputs oc;
                const fmi3ValueReference vr[4] = {OSC_x, OSC_v, OSC_a, OSC_F}, vm = OSC_mode;
                double r[4];
                fmi3Int32 mode = 9;
                ok = ok && read3(A, c, 1, &oc) && O->getF(o, vr, 4, r, 4) == fmi3OK &&
                     O->getI(o, &vm, 1, &mode, 1) == fmi3OK;
                points++;
                const double got[4] = {oc.x[0], oc.v[0], oc.a[0], oc.F[0]};
                double worst = 0.0;
                for (int i = 0; i < 4; i++) worst = fmax(worst, fabs(got[i] - r[i]) / fmax(fabs(r[i]), 1.0));
                const int d = oc.mode[0] != mode || !(worst <= N1_TOL);
                if (d && !differ)
                    printf("  first difference at t = %.17g: x %.17g %.17g v %.17g %.17g F %.17g %.17g mode %d %d\n", t,
                           oc.x[0], r[0], oc.v[0], r[1], oc.F[0], r[3], oc.mode[0], mode);
                differ += d;
                rel = fmax(rel, worst);
            }
            EXPECT(ok);
            EXPECT(differ == 0);
            printf("n = 1 vs oscillator, variant %d, scheme %d: %ld points, mode or x v a F beyond %g at %ld "
                   "(largest relative %.3g)\n", variant, scheme, points, N1_TOL, differ, rel);
            A->free_(c);
            O->free_(o);
        }
}

/* ---- 4. FMU states ---------------------------------------------------------------------------- */

static int run_outputs(const api3 *A, fmi3Instance in, size_t n, double t, int steps, outputs *out)
{
    for (int k = 0; k < steps; k++) {
        if (!step3(A, in, t, 0.1)) return 0;
        t += 0.1;
        if (!read3(A, in, n, &out[k])) return 0;
    }
    return 1;
}

static void test_states(tally *T, const api3 *A)
{
    const size_t n = 5;
    chain_case C = make_case(n, 3);
    env E = {0, ""};
    fmi3Instance in = start3(A, &E, &C, 0, 0);
    EXPECT(in != NULL);
    if (!in) return;
    double t = 0.0;
    for (int k = 0; k < 30; k++, t += 0.1) EXPECT(step3(A, in, t, 0.1));
    fmi3FMUState st = NULL;
    EXPECT(A->gst(in, &st) == fmi3OK);
    enum { K = 40 };
    static outputs first[K], again[K], other[K];
    EXPECT(run_outputs(A, in, n, t, K, first));
    EXPECT(A->sst(in, st) == fmi3OK);
    EXPECT(run_outputs(A, in, n, t, K, again));
    int equal = 1;
    for (int k = 0; k < K; k++) equal &= same(&first[k], &again[k], n);
    EXPECT(equal);
    size_t size = 0;
    EXPECT(A->ssize(in, st, &size) == fmi3OK && size > 100);
    unsigned char *buf = (unsigned char *)malloc(size);
    EXPECT(A->ser(in, st, buf, size) == fmi3OK);
    /* into a fresh instance of the default n: the state brings its own n */
    env E2 = {0, ""};
    chain_case C2 = make_case(2, 1);
    fmi3Instance in2 = start3(A, &E2, &C2, 0, 0);
    fmi3FMUState st2 = NULL;
    EXPECT(in2 && A->deser(in2, buf, size, &st2) == fmi3OK);
    EXPECT(in2 && A->sst(in2, st2) == fmi3OK);
    const fmi3ValueReference vn = VR_n;
    fmi3UInt64 n2 = 0;
    EXPECT(in2 && A->getU(in2, &vn, 1, &n2, 1) == fmi3OK && n2 == n);
    EXPECT(in2 && run_outputs(A, in2, n, t, K, other));
    equal = 1;
    for (int k = 0; k < K; k++) equal &= same(&first[k], &other[k], n);
    EXPECT(equal);
    /* damaged bytes are rejected */
    fmi3FMUState bad = NULL;
    buf[size / 2] ^= 0x10;
    EXPECT(A->deser(in, buf, size, &bad) == fmi3Error && has(&E, "checksum"));
    buf[size / 2] ^= 0x10;
    EXPECT(A->deser(in, buf, size - 8, &bad) == fmi3Error);
    EXPECT(A->fst(in, &st) == fmi3OK && st == NULL);
    if (in2) {
        EXPECT(A->fst(in2, &st2) == fmi3OK);
        A->free_(in2);
    }
    free(buf);
    A->free_(in);
}

/* ---- 5. events -------------------------------------------------------------------------------- */
/* (the left limit of a switching block: its mode before the switch with that mode's friction law) */

#define MAXSW 4096
typedef struct {
    int count;
    double t[MAXSW];
    size_t block[MAXSW];
    int from[MAXSW], to[MAXSW];
} switches;

static void record(void *ctx, double t, size_t block, double x, int from, int to)
{
    switches *S = (switches *)ctx;
    (void)x;
    if (S->count >= MAXSW) return;
    S->t[S->count] = t;
    S->block[S->count] = block;
    S->from[S->count] = from;
    S->to[S->count] = to;
    S->count++;
}

static void *c_alloc(void *env_, size_t n, size_t size)
{
    (void)env_;
    return calloc(n, size);
}
static void c_free(void *env_, void *p)
{
    (void)env_;
    free(p);
}

/* The physics' own switches over [0, t_end] with communication points every dt (as the FMU's
 * parameters; a communication point inside an internal step shortens it). */
static void reference(const chain_case *C, double t_end, double dt, switches *S)
{
    const chain_params p = {C->n, C->m, C->k, C->c, C->P0, C->phi, C->N, C->mu_s, C->chi, C->x0, C->v0,
                            C->k_end, C->c_end, C->omega, C->h, C->alpha, C->scheme, 0, NULL, NULL, 0, NULL, NULL};
    const chain_alloc al = {c_alloc, c_free, NULL};
    chain_model *M = chain_create(&p, &al, NULL);
    chain_state s;
    chain_state_init(M, &s);
    const chain_inputs in = {NULL, NULL};
    chain_start(M, &in, 0.0, &s);
    S->count = 0;
    for (int k = 1; k * dt <= t_end + 1e-12; k++) (void)chain_advance(M, &in, &s, k * dt, 0, record, S);
    chain_state_free(M, &s);
    chain_destroy(M);
}

static void test_events(tally *T, const api3 *A)
{
    const size_t n = 3;
    const double dt = 0.5, t_end = 25.0;
    static switches S;
    chain_case C = make_case(n, 3);
    reference(&C, t_end, dt, &S);
    EXPECT(S.count > 10);
    /* early return: every switch strictly inside a step is landed on, at the physics' time */
    env E = {0, ""};
    fmi3Instance in = start3(A, &E, &C, 0, 1);
    EXPECT(in != NULL);
    if (!in) return;
    int landed = 0, matched = 0, inside = 0, ok = 1;
    double t = 0.0;
    for (int k = 1; ok && t < t_end; k++) {
        const double target = k * dt;
        for (int j = 0; j < S.count; j++) inside += S.t[j] > t && S.t[j] < target;
        while (ok && t < target) {
            fmi3Boolean ev, term, early;
            fmi3Float64 last;
            ok = A->step(in, t, target - t, fmi3True, &ev, &term, &early, &last) == fmi3OK;
            if (ok && early) {
                landed++;
                for (int j = 0; j < S.count; j++) matched += S.t[j] == last;
            }
            t = last;
        }
    }
    EXPECT(ok);
    EXPECT(landed == inside && matched == inside);
    printf("early return: %d switches of the physics inside steps, %d landed, %d at the physics' time\n", inside,
           landed, matched);
    outputs end_early, end_plain;
    EXPECT(read3(A, in, n, &end_early));
    A->free_(in);
    env E0 = {0, ""};
    fmi3Instance plain = start3(A, &E0, &C, 0, 0);
    t = 0.0;
    for (int k = 1; plain && t < t_end; k++) {
        EXPECT(step3(A, plain, t, k * dt - t));
        t = k * dt;
    }
    EXPECT(plain && read3(A, plain, n, &end_plain) && same(&end_early, &end_plain, n));
    if (plain) A->free_(plain);

    /* event mode: the switching block's left limit until the update, its right limit after */
    env E2 = {0, ""};
    fmi3Instance ev_in = start3(A, &E2, &C, 1, 1);
    EXPECT(ev_in != NULL);
    if (!ev_in) return;
    int events = 0, limits_ok = 0, j = 0;
    t = 0.0;
    ok = 1;
    for (int k = 1; ok && t < t_end; k++) {
        const double target = k * dt;
        while (ok && t < target) {
            fmi3Boolean evh, term, early;
            fmi3Float64 last;
            ok = A->step(ev_in, t, target - t, fmi3True, &evh, &term, &early, &last) == fmi3OK;
            t = last;
            if (!ok || !evh) continue;
            events++;
            while (j < S.count && S.t[j] < last) j++;
            outputs left, right;
            fmi3Boolean need, stop, nom, val, def;
            fmi3Float64 next;
            ok = read3(A, ev_in, n, &left) && A->eem(ev_in) == fmi3OK &&
                 A->upd(ev_in, &need, &stop, &nom, &val, &def, &next) == fmi3OK && read3(A, ev_in, n, &right) &&
                 A->esm(ev_in) == fmi3OK;
            if (ok && j < S.count && S.t[j] == last) {
                /* the friction law of each side's mode: sliding -s mu_k N exactly, stuck at rest within
                 * the breakaway limit; the other blocks unchanged */
                const size_t b = S.block[j];
                const double mukN = C.chi[b] * C.mu_s[b] * C.N[b], Fb = fmax(C.mu_s[b], C.chi[b] * C.mu_s[b]) * C.N[b];
                const int law_left = S.from[j] ? left.F[b] == -S.from[j] * mukN
                                                : (left.a[b] == 0.0 && fabs(left.F[b]) <= Fb * (1.0 + 1e-12));
                const int law_right = S.to[j] ? right.F[b] == -S.to[j] * mukN
                                               : (right.a[b] == 0.0 && fabs(right.F[b]) <= Fb * (1.0 + 1e-12));
                int others = 1;
                for (size_t i = 0; i < n; i++)
                    if (i != b)
                        others &= left.mode[i] == right.mode[i] && !memcmp(&left.F[i], &right.F[i], 8) &&
                                  !memcmp(&left.a[i], &right.a[i], 8);
                limits_ok += left.mode[b] == S.from[j] && right.mode[b] == S.to[j] &&
                             !memcmp(left.x, right.x, n * sizeof(double)) &&
                             !memcmp(left.v, right.v, n * sizeof(double)) && law_left && law_right && others;
            }
        }
    }
    EXPECT(ok);
    EXPECT(events > 10 && limits_ok == events);
    printf("event mode: %d events, %d with the left limit before and the right limit after the update\n", events,
           limits_ok);
    A->free_(ev_in);
}

/* ---- 6. threads ------------------------------------------------------------------------------- */

typedef struct {
    const api3 *A;
    size_t n;
    double result[NMAX];
    int ok;
} job;

static void *run_job(void *arg)
{
    job *J = (job *)arg;
    env E = {0, ""};
    chain_case C = make_case(J->n, 1 + (int)(J->n % 3));
    fmi3Instance in = start3(J->A, &E, &C, 0, 0);
    J->ok = in != NULL;
    double t = 0.0;
    for (int k = 0; J->ok && k < 200; k++, t += 0.07) J->ok = step3(J->A, in, t, 0.07);
    const fmi3ValueReference vx = VR_x;
    if (J->ok) J->ok = J->A->getF(in, &vx, 1, J->result, J->n) == fmi3OK;
    if (in) J->A->free_(in);
    return NULL;
}

static void test_threads(tally *T, const api3 *A)
{
    enum { NT = 8 };
    job serial[NT], para[NT];
    pthread_t th[NT];
    for (int i = 0; i < NT; i++) {
        serial[i].A = para[i].A = A;
        serial[i].n = para[i].n = 1 + (size_t)i * 2;
        run_job(&serial[i]);
    }
    for (int i = 0; i < NT; i++) pthread_create(&th[i], NULL, run_job, &para[i]);
    for (int i = 0; i < NT; i++) pthread_join(th[i], NULL);
    int equal = 1;
    for (int i = 0; i < NT; i++)
        equal &= serial[i].ok && para[i].ok && !memcmp(serial[i].result, para[i].result, serial[i].n * sizeof(double));
    EXPECT(equal);
}

int main(void)
{
    tally t = {0, 0, NULL, {0}}, *T = &t;
    setvbuf(stdout, NULL, _IONBF, 0);
    static api3 chain3, osc3;
    static api2 chain2;
    load3(&chain3, DFO_CHAIN3_LIB);
    load3(&osc3, DFO_OSC3_LIB);
    load2(&chain2, DFO_CHAIN2_LIB);
    test_rules(T, &chain3);
    test_fmi2_vs_fmi3(T, &chain2, &chain3);
    test_n1_vs_oscillator(T, &chain3, &osc3);
    test_states(T, &chain3);
    test_events(T, &chain3);
    test_threads(T, &chain3);
    return tally_done(T, "chain_fmu");
}
