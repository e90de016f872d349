/* ns per internal step of the bare stepper (dfo_advance, linked from dfo_physics) side by side with
 * the FMU's own shared library (dlopen'ed, driven through its fmi2 functions) on the same cases,
 * schemes and steps; plus the cost of a whole short FMI run and the bytes one FMU instance
 * allocates. Output: CSV on stdout, or written atomically to --csv FILE.
 *
 *   bench_stepper [--fmu-lib PATH] [--reps N] [--periods P] [--steps-per-period N[,N...]]
 *                 [--schemes paper,consistent,located,exact] [--alpha A]
 *                 [--case NAME,lambda,mu_s_sigma,chi,zeta]... [--observe 0|1] [--csv FILE]
 *
 * Every timing is the minimum over --reps repetitions (bare and FMU alternate, so both see the
 * same machine load). Only the stepping is timed: dfo_advance for the bare loop, one fmi2DoStep
 * over the whole run for the FMU; start-up is outside the clock. The observables' cost: the bare
 * loop also runs with observe off and on in every repetition (whatever --observe says), and
 * observe_cost is on / off per step (window [0, inf), observe's default). The Bossak schemes' rows
 * also time the oscillator's model of the friction engine (osc_engine.h, the same motion from the
 * same model): engine_ns_per_step and engine_over_bare (empty for the exact scheme).
 *
 * The cases default to bench/cases.py's (keep the two in sync); work_precision.py passes its own
 * with --case, so the Python study is the single source when it drives this program. */
#define _POSIX_C_SOURCE 200809L

#include "fmi2Functions.h"
#include "model_vars.h"
#include "scheme.h"
#include "oscillator.h"
#include "osc_engine.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_clock.h"

/* The FMU's library: dlopen on POSIX, LoadLibrary on Windows (which has no dlfcn.h); the clock:
 * bench_clock.h. */
#ifdef _WIN32
#include <windows.h>
static void *lib_open(const char *path) { return (void *)LoadLibraryA(path); }
static void *lib_sym(void *handle, const char *name)
{
    FARPROC f = GetProcAddress((HMODULE)handle, name);
    void *p;
    memcpy(&p, &f, sizeof p);
    return p;
}
static void lib_close(void *handle) { FreeLibrary((HMODULE)handle); }
static const char *lib_error(void) { return "LoadLibrary failed"; }
/* no open_memstream either: a temporary file read back at the end */
static FILE *mem_open(char **buf, size_t *len)
{
    *buf = NULL;
    *len = 0;
    return tmpfile();
}
static int mem_close(FILE *f, char **buf, size_t *len)
{
    long n;
    if (fflush(f) != 0 || fseek(f, 0, SEEK_END) != 0 || (n = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) return -1;
    *buf = (char *)malloc((size_t)n + 1);
    if (!*buf || fread(*buf, 1, (size_t)n, f) != (size_t)n) return -1;
    *len = (size_t)n;
    return fclose(f);
}
#else
#include <dlfcn.h>
static void *lib_open(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *lib_sym(void *handle, const char *name) { return dlsym(handle, name); }
static void lib_close(void *handle) { dlclose(handle); }
static const char *lib_error(void) { return dlerror(); }
static FILE *mem_open(char **buf, size_t *len) { return open_memstream(buf, len); }
static int mem_close(FILE *f, char **buf, size_t *len)
{
    (void)buf;
    (void)len;
    return fclose(f); /* sets *buf and *len */
}
#endif

#ifndef DFO_FMU_LIB_DEFAULT
#define DFO_FMU_LIB_DEFAULT "DryFrictionOscillator.so"
#endif

#define MAX_CASES 16
#define MAX_SPP 16
#define MAX_NAME 64

typedef struct {
    char name[MAX_NAME];
    double lam, mu_s_sigma, chi, zeta;
} bench_case;

typedef struct {
    const char *fmu_lib;
    const char *csv;
    int reps;
    double periods;
    double alpha;
    int observe; /* the in-FMU observables on (bare loop and FMU alike); default off */
    int n_spp;
    double spp[MAX_SPP];
    int schemes[4];
    int n_schemes;
    int n_cases;
    bench_case cases[MAX_CASES];
} options;

/* The FMI functions this benchmark calls, resolved from the FMU's shared library. */
typedef struct {
    void *handle;
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *freeInstance;
    fmi2SetupExperimentTYPE *setupExperiment;
    fmi2EnterInitializationModeTYPE *enterInit;
    fmi2ExitInitializationModeTYPE *exitInit;
    fmi2ResetTYPE *reset;
    fmi2SetRealTYPE *setReal;
    fmi2SetIntegerTYPE *setInteger;
    fmi2SetBooleanTYPE *setBoolean;
    fmi2GetRealTYPE *getReal;
    fmi2DoStepTYPE *doStep;
} fmu_api;

/* FMI 2.0's allocateMemory callback has no context argument, so the bytes an instance allocates
 * can only be counted in a file-scope counter. This is the benchmark executable's only mutable
 * global; the FMU and the physics have none. */
static size_t g_allocated_bytes;

static void *counting_calloc(size_t nobj, size_t size)
{
    g_allocated_bytes += nobj * size;
    return calloc(nobj, size);
}

static void quiet_logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                         fmi2String message, ...)
{
    (void)env;
    (void)name;
    (void)category;
    if (status >= fmi2Error) fprintf(stderr, "bench_stepper: FMU error: %s\n", message);
}

static void die(const char *fmt, ...)
{
    va_list ap;
    fputs("bench_stepper: ", stderr);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    exit(2);
}

/* ---- arguments ------------------------------------------------------------------------------- */

static double parse_double(const char *what, const char *text)
{
    char *end = NULL;
    errno = 0;
    const double v = strtod(text, &end);
    if (errno || end == text || *end != '\0' || !isfinite(v)) die("%s must be a finite number, not '%s'", what, text);
    return v;
}

static void parse_case(options *o, const char *text)
{
    if (o->n_cases >= MAX_CASES) die("at most %d --case options", MAX_CASES);
    bench_case *c = &o->cases[o->n_cases];
    char buf[256];
    if (strlen(text) >= sizeof buf) die("--case value too long: '%s'", text);
    strcpy(buf, text);
    char *fields[5];
    int n = 0;
    for (char *tok = strtok(buf, ","); tok && n < 6; tok = strtok(NULL, ",")) {
        if (n == 5) die("--case takes NAME,lambda,mu_s_sigma,chi,zeta, not '%s'", text);
        fields[n++] = tok;
    }
    if (n != 5) die("--case takes NAME,lambda,mu_s_sigma,chi,zeta, not '%s'", text);
    if (strlen(fields[0]) >= MAX_NAME) die("case name too long: '%s'", fields[0]);
    strcpy(c->name, fields[0]);
    c->lam = parse_double("--case lambda", fields[1]);
    c->mu_s_sigma = parse_double("--case mu_s_sigma", fields[2]);
    c->chi = parse_double("--case chi", fields[3]);
    c->zeta = parse_double("--case zeta", fields[4]);
    if (!(c->lam > 0.0) || c->mu_s_sigma < 0.0 || c->chi < 0.0 || c->zeta < 0.0)
        die("--case needs lambda > 0 and mu_s_sigma, chi, zeta >= 0, not '%s'", text);
    o->n_cases++;
}

static void parse_schemes(options *o, const char *text)
{
    char buf[128];
    if (strlen(text) >= sizeof buf) die("--schemes value too long");
    strcpy(buf, text);
    o->n_schemes = 0;
    for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
        int s;
        if (!strcmp(tok, "paper")) s = DFO_SCHEME_PAPER;
        else if (!strcmp(tok, "consistent")) s = DFO_SCHEME_CONSISTENT;
        else if (!strcmp(tok, "located")) s = DFO_SCHEME_LOCATED;
        else if (!strcmp(tok, "exact")) s = DFO_SCHEME_EXACT; /* (its steps are its events) */
        else die("--schemes: unknown scheme '%s' (paper, consistent, located, exact)", tok);
        if (o->n_schemes >= 4) die("--schemes: at most four schemes");
        o->schemes[o->n_schemes++] = s;
    }
    if (o->n_schemes == 0) die("--schemes needs at least one scheme");
}

static void parse_spp(options *o, const char *text)
{
    char buf[256];
    if (strlen(text) >= sizeof buf) die("--steps-per-period value too long");
    strcpy(buf, text);
    o->n_spp = 0;
    for (char *tok = strtok(buf, ","); tok; tok = strtok(NULL, ",")) {
        if (o->n_spp >= MAX_SPP) die("--steps-per-period: at most %d values", MAX_SPP);
        const double v = parse_double("--steps-per-period", tok);
        if (!(v >= 1.0)) die("--steps-per-period must be >= 1, not '%s'", tok);
        o->spp[o->n_spp++] = v;
    }
    if (o->n_spp == 0) die("--steps-per-period needs at least one value");
}

static const bench_case DEFAULT_CASES[] = {
    /* mirror of bench/cases.py */
    {"stick_dominated", 0.25, 0.6, 0.6, 0.0},
    {"reversal_resonance", 0.9, 0.1, 0.8, 0.0},
    {"heavy_damped", 1.0, 0.7, 0.9, 0.2},
    {"chi_above_1", 0.5, 0.3, 1.5, 0.0},
    {"chi_near_0", 0.5, 0.4, 0.05, 0.0},
};

static void parse_args(options *o, int argc, char **argv)
{
    memset(o, 0, sizeof *o);
    o->fmu_lib = DFO_FMU_LIB_DEFAULT;
    o->reps = 7;
    o->periods = 10.0;
    o->alpha = -0.1;
    o->n_spp = 1;
    o->spp[0] = 1000.0;
    o->n_schemes = 3;
    o->schemes[0] = DFO_SCHEME_PAPER;
    o->schemes[1] = DFO_SCHEME_CONSISTENT;
    o->schemes[2] = DFO_SCHEME_LOCATED;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            printf("usage: bench_stepper [--fmu-lib PATH] [--reps N] [--periods P] [--steps-per-period N[,N...]]\n"
                   "                     [--schemes paper,consistent,located,exact] [--alpha A]\n"
                   "                     [--case NAME,lambda,mu_s_sigma,chi,zeta]... [--observe 0|1] [--csv FILE]\n");
            exit(0);
        }
        if (i + 1 >= argc) die("option %s needs a value (see --help)", a);
        const char *v = argv[++i];
        if (!strcmp(a, "--fmu-lib")) o->fmu_lib = v;
        else if (!strcmp(a, "--csv")) o->csv = v;
        else if (!strcmp(a, "--reps")) {
            const double r = parse_double("--reps", v);
            if (!(r >= 1.0 && r <= 1000.0) || r != floor(r)) die("--reps must be an integer in [1, 1000], not '%s'", v);
            o->reps = (int)r;
        } else if (!strcmp(a, "--periods")) {
            o->periods = parse_double("--periods", v);
            if (!(o->periods > 0.0 && o->periods <= 1e6)) die("--periods must be in (0, 1e6], not '%s'", v);
        } else if (!strcmp(a, "--alpha")) {
            o->alpha = parse_double("--alpha", v);
            if (!(o->alpha >= -1.0 / 3.0 && o->alpha <= 0.0)) die("--alpha must be in [-1/3, 0], not '%s'", v);
        } else if (!strcmp(a, "--observe")) {
            if (strcmp(v, "0") && strcmp(v, "1")) die("--observe takes 0 or 1, not '%s'", v);
            o->observe = v[0] == '1';
        } else if (!strcmp(a, "--steps-per-period")) parse_spp(o, v);
        else if (!strcmp(a, "--schemes")) parse_schemes(o, v);
        else if (!strcmp(a, "--case")) parse_case(o, v);
        else die("unknown option %s (see --help)", a);
    }
    if (o->n_cases == 0) {
        o->n_cases = (int)(sizeof DEFAULT_CASES / sizeof DEFAULT_CASES[0]);
        memcpy(o->cases, DEFAULT_CASES, sizeof DEFAULT_CASES);
    }
}

/* ---- the FMU --------------------------------------------------------------------------------- */

static void *sym(void *handle, const char *name, const char *path)
{
    void *p = lib_sym(handle, name);
    if (!p) die("%s does not export %s", path, name);
    return p;
}

/* dlsym returns an object pointer; copying its bytes is the POSIX-sanctioned way to a function
 * pointer in ISO C. */
#define LOAD(api, field, name)                                   \
    do {                                                         \
        void *p_ = sym((api)->handle, name, path);               \
        memcpy(&(api)->field, &p_, sizeof (api)->field);         \
    } while (0)

static void load_fmu(fmu_api *api, const char *path)
{
    api->handle = lib_open(path);
    if (!api->handle) die("cannot load the FMU library %s: %s", path, lib_error());
    LOAD(api, instantiate, "fmi2Instantiate");
    LOAD(api, freeInstance, "fmi2FreeInstance");
    LOAD(api, setupExperiment, "fmi2SetupExperiment");
    LOAD(api, enterInit, "fmi2EnterInitializationMode");
    LOAD(api, exitInit, "fmi2ExitInitializationMode");
    LOAD(api, reset, "fmi2Reset");
    LOAD(api, setReal, "fmi2SetReal");
    LOAD(api, setInteger, "fmi2SetInteger");
    LOAD(api, setBoolean, "fmi2SetBoolean");
    LOAD(api, getReal, "fmi2GetReal");
    LOAD(api, doStep, "fmi2DoStep");
}

static void check(fmi2Status st, const char *what)
{
    if (st > fmi2Warning) die("%s failed (status %d)", what, (int)st);
}

/* ---- the runs -------------------------------------------------------------------------------- */

/* Physical parameters of a case, as dryfriction.params.Oscillator.from_nondimensional does it
 * (m = 1, k = 100, P0 = 1, mu_s = 0.4, start from rest). */
static dfo_params case_params(const bench_case *c, int scheme, double alpha, double steps_per_period, int observe)
{
    dfo_params p;
    memset(&p, 0, sizeof p);
    p.m = 1.0;
    p.k = 100.0;
    p.P0 = 1.0;
    p.mu_s = 0.4;
    const double w0 = sqrt(p.k / p.m);
    p.c = 2.0 * c->zeta * sqrt(p.k * p.m);
    p.omega = c->lam * w0;
    p.phi = 0.0;
    p.N = c->mu_s_sigma * p.P0 / p.mu_s;
    p.chi = c->chi;
    p.x0 = p.v0 = 0.0;
    p.h = (2.0 * DFO_PI / p.omega) / steps_per_period;
    p.alpha = alpha;
    p.t_obs_start = 0.0;
    p.t_obs_stop = 1e300;
    p.scheme = scheme;
    p.frictionUpdates = 1;
    p.observe = observe;
    p.fastPaths = 1;
    return p;
}

/* Reset and initialise an FMU instance with p (everything before the first doStep). */
static void fmu_setup(const fmu_api *api, fmi2Component comp, const dfo_params *p)
{
    const fmi2ValueReference rvr[] = {VR_m, VR_k, VR_c, VR_P0, VR_omega, VR_phi, VR_N, VR_mu_s,
                                      VR_chi, VR_x0, VR_v0, VR_h, VR_alpha, VR_t_obs_start, VR_t_obs_stop};
    const fmi2Real rv[] = {p->m, p->k, p->c, p->P0, p->omega, p->phi, p->N, p->mu_s,
                           p->chi, p->x0, p->v0, p->h, p->alpha, p->t_obs_start, p->t_obs_stop};
    const fmi2ValueReference ivr[] = {VR_scheme, VR_frictionUpdates};
    const fmi2Integer iv[] = {p->scheme, p->frictionUpdates};
    const fmi2ValueReference bvr[] = {VR_observe, VR_fastPaths};
    const fmi2Boolean bv[] = {p->observe, p->fastPaths};
    check(api->reset(comp), "fmi2Reset");
    check(api->setupExperiment(comp, fmi2False, 0.0, 0.0, fmi2False, 0.0), "fmi2SetupExperiment");
    check(api->setReal(comp, rvr, sizeof rvr / sizeof rvr[0], rv), "fmi2SetReal");
    check(api->setInteger(comp, ivr, 2, iv), "fmi2SetInteger");
    check(api->setBoolean(comp, bvr, 2, bv), "fmi2SetBoolean");
    check(api->enterInit(comp), "fmi2EnterInitializationMode");
    check(api->exitInit(comp), "fmi2ExitInitializationMode");
}

typedef struct {
    double bare_ns, fmu_ns; /* best time of the stepping, ns */
    double off_ns, on_ns;   /* best time of the bare loop with observe off and on, ns */
    double eng_ns;          /* best time of the oscillator's engine model (Bossak schemes; else NaN), ns */
    long long steps;
} step_timing;

/* One bare run from the start to t_end: the ns of dfo_advance; its steps in *steps. */
static double time_bare(const dfo_model *M, double t_end, long long *steps)
{
    const dfo_inputs u = {0};
    dfo_state s;
    dfo_start(M, &u, 0.0, &s);
    const double t0 = bench_now_ns();
    const dfo_status st = dfo_advance(M, &u, &s, t_end, NULL, NULL);
    const double t1 = bench_now_ns();
    if (st != DFO_OK) die("dfo_advance failed: %s", dfo_status_text(st));
    *steps = s.steps;
    return t1 - t0;
}

static void *eng_calloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void eng_free(void *env, void *obj) { (void)env; free(obj); }

/* One run of the oscillator's engine model (osc_engine.h: the engine's schemes specialised by its
 * operators) from the start to t_end: its ns; its steps must be the bare loop's. */
static double time_engine(const dfo_model *M, double t_end, long long steps)
{
    static const eng_alloc al = {eng_calloc, eng_free, NULL};
    osc_eng_model O;
    const char *err = NULL;
    eng *E = osc_eng_create(M, &O, &al, &err);
    eng_state s;
    if (!E || !eng_state_init(E, &s, 0)) die("cannot make the engine: %s", err ? err : "out of memory");
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    osc_eng_start(E, &in, 0.0, &M->p.x0, &M->p.v0, &s);
    const double t0 = bench_now_ns();
    const eng_status st = osc_eng_advance(E, &in, &s, t_end, NULL);
    const double t1 = bench_now_ns();
    if (st != ENG_OK) die("osc_eng_advance failed: %s", eng_status_text(st));
    if (s.steps != steps) die("the engine took %lld steps, dfo_advance %lld", s.steps, steps);
    eng_state_free(E, &s);
    eng_destroy(E);
    return t1 - t0;
}

static step_timing time_stepping(const options *o, const fmu_api *api, fmi2Component comp, const dfo_params *p)
{
    const double t_end = o->periods * 2.0 * DFO_PI / p->omega;
    dfo_model M, M_obs[2];
    dfo_model_init(&M, p);
    for (int ob = 0; ob < 2; ob++) {
        dfo_params q = *p;
        q.observe = ob;
        dfo_model_init(&M_obs[ob], &q);
    }
    const int bossak = p->scheme != DFO_SCHEME_EXACT;
    step_timing r = {INFINITY, INFINITY, INFINITY, INFINITY, bossak ? INFINITY : NAN, 0};
    for (int rep = 0; rep < o->reps; rep++) {
        r.bare_ns = fmin(r.bare_ns, time_bare(&M, t_end, &r.steps));
        long long steps_ob;
        r.off_ns = fmin(r.off_ns, time_bare(&M_obs[0], t_end, &steps_ob));
        r.on_ns = fmin(r.on_ns, time_bare(&M_obs[1], t_end, &steps_ob));
        if (bossak) r.eng_ns = fmin(r.eng_ns, time_engine(&M, t_end, r.steps));

        fmu_setup(api, comp, p);
        const double t0 = bench_now_ns();
        check(api->doStep(comp, 0.0, t_end, fmi2True), "fmi2DoStep");
        const double t1 = bench_now_ns();
        if (t1 - t0 < r.fmu_ns) r.fmu_ns = t1 - t0;
    }
    return r;
}

/* A whole short run through the FMI API, as a host does it for every sweep point: reset, setup,
 * parameters, initialisation, one doStep of one period (50 steps), read x. Returns the best ns. */
static double time_short_run(const options *o, const fmu_api *api, fmi2Component comp, const dfo_params *p,
                             int with_step)
{
    const double T = 2.0 * DFO_PI / p->omega;
    const fmi2ValueReference xvr[] = {VR_x};
    fmi2Real x;
    double best = INFINITY;
    for (int rep = 0; rep < 20 * o->reps; rep++) {
        const double t0 = bench_now_ns();
        fmu_setup(api, comp, p);
        if (with_step) check(api->doStep(comp, 0.0, T, fmi2True), "fmi2DoStep");
        check(api->getReal(comp, xvr, 1, &x), "fmi2GetReal");
        const double t1 = bench_now_ns();
        if (t1 - t0 < best) best = t1 - t0;
    }
    return best;
}

static void write_atomically(const char *path, const char *data, size_t len)
{
    char tmp[4096];
    if ((size_t)snprintf(tmp, sizeof tmp, "%s.tmp", path) >= sizeof tmp) die("--csv path too long: %s", path);
    FILE *f = fopen(tmp, "w");
    if (!f) die("cannot write %s: %s", tmp, strerror(errno));
    const int ok = fwrite(data, 1, len, f) == len;
    if (fclose(f) != 0 || !ok) {
        remove(tmp);
        die("cannot write %s: %s", tmp, strerror(errno));
    }
    if (rename(tmp, path) != 0) {
        remove(tmp);
        die("cannot rename %s to %s: %s", tmp, path, strerror(errno));
    }
}

static const char *scheme_name(int s)
{
    return s == DFO_SCHEME_PAPER ? "paper" : s == DFO_SCHEME_CONSISTENT ? "consistent" : s == DFO_SCHEME_LOCATED ? "located" : "exact";
}

int main(int argc, char **argv)
{
    options o;
    parse_args(&o, argc, argv);

    fmu_api api;
    load_fmu(&api, o.fmu_lib);
    const fmi2CallbackFunctions cb = {quiet_logger, counting_calloc, free, NULL, NULL};

    /* bytes one instance allocates through the host's callbacks (instance struct and name) */
    const size_t before = g_allocated_bytes;
    fmi2Component comp = api.instantiate("bench", fmi2CoSimulation, MODEL_GUID, "", &cb, fmi2False, fmi2False);
    if (!comp) die("fmi2Instantiate failed for %s", o.fmu_lib);
    const size_t instance_bytes = g_allocated_bytes - before;

    /* with --csv the rows are collected in memory and the file is written at the end, through a
     * temporary file and a rename: a failed run leaves nothing half-written behind */
    char *buf = NULL;
    size_t buf_len = 0;
    FILE *out = stdout;
    if (o.csv) {
        out = mem_open(&buf, &buf_len);
        if (!out) die("cannot allocate the output buffer");
    }
    fprintf(out, "kind,case,scheme,alpha,steps_per_period,periods,steps,bare_ns_per_step,fmu_ns_per_step,"
                 "fmu_over_bare,value,unit,observe_off_ns_per_step,observe_on_ns_per_step,observe_cost,"
                 "engine_ns_per_step,engine_over_bare\n");
    fprintf(out, "instance_bytes,,,,,,,,,,%zu,bytes,,,,,\n", instance_bytes);

    /* the whole short run of the first case with the located scheme (compare with the host's) */
    const dfo_params p_run = case_params(&o.cases[0], DFO_SCHEME_LOCATED, o.alpha, 50.0, o.observe);
    fprintf(out, "fmi2_setup,%s,located,%.17g,50,0,0,,,,%.1f,ns,,,,,\n", o.cases[0].name, o.alpha,
            time_short_run(&o, &api, comp, &p_run, 0));
    fprintf(out, "fmi2_run,%s,located,%.17g,50,1,50,,,,%.1f,ns,,,,,\n", o.cases[0].name, o.alpha,
            time_short_run(&o, &api, comp, &p_run, 1));

    for (int ci = 0; ci < o.n_cases; ci++) {
        for (int si = 0; si < o.n_schemes; si++) {
            for (int k = 0; k < o.n_spp; k++) {
                const dfo_params p = case_params(&o.cases[ci], o.schemes[si], o.alpha, o.spp[k], o.observe);
                const step_timing r = time_stepping(&o, &api, comp, &p);
                const double bare = r.bare_ns / (double)r.steps, fmu = r.fmu_ns / (double)r.steps;
                const double off = r.off_ns / (double)r.steps, on = r.on_ns / (double)r.steps;
                const double en = r.eng_ns / (double)r.steps;
                fprintf(out, "step,%s,%s,%.17g,%.17g,%.17g,%lld,%.3f,%.3f,%.4f,,,%.3f,%.3f,%.4f,%.3f,%.4f\n",
                        o.cases[ci].name, scheme_name(o.schemes[si]), o.alpha, o.spp[k], o.periods, r.steps, bare, fmu,
                        fmu / bare, off, on, on / off, en, en / bare);
                fflush(out);
            }
        }
    }
    api.freeInstance(comp);
    if (o.csv) {
        if (mem_close(out, &buf, &buf_len) != 0) die("cannot finish the output buffer");
        write_atomically(o.csv, buf, buf_len);
        free(buf);
    }
    lib_close(api.handle);
    return 0;
}
