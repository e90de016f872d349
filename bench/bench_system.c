/* ns per grid step (h) of the DryFrictionSystem model (fmu_src/models/system/system.h) against the number of
 * degrees of freedom n and of contacts nc, on stick-slip structures, with the friction solve's share.
 *
 *   bench_system [--reps R] [--periods P] [--steps-per-period S] [--seconds B] [--n N[,N...]]
 *                [--nc-at N] [--nc NC[,NC...]] [--N NORMAL] [--schemes LIST] [--structures LIST]
 *                [--wall] [--csv FILE]
 *   bench_system --case FILE     (one structure from a text file: see run_case; bench/siconos_system.py)
 *
 * The structures (n DOFs, nc contacts; deterministic):
 *   chain    M = I, K tridiagonal (springs 1 between neighbours and to the walls at both ends),
 *   banded   M = I + a random symmetric band (half-bandwidth 2, entries in [-0.05, 0.05]), K the chain's
 *            plus a random symmetric band (half-bandwidth 3, entries in [-0.1, 0]) with its diagonal
 *            raised to keep it diagonally dominant (a seeded generator: the same matrices every run),
 * both with C = 0.02 M + 0.002 K (Rayleigh), the harmonic force F_c,i = cos(0.1 i), F_s,i = sin(0.1 i)
 * at omega = 0.5 (inside the chain's band [0, 2]), at rest at t = 0. Contact j (0-based) sits at
 * DOF i_j = floor((j + 1/2) n / nc): even j against the ground (w = e_i), odd j between DOFs i_j and
 * its neighbour (w = e_i - e_{i+1}); N = 1.6 (--N), mu_s = 0.5, mu_k = 0.35: stick-slip (the stuck share
 * and switches per contact and period are reported).
 *
 * The default runs: n = 8, 16, 32, 64, 128, 256, 512 with nc = min(n / 4, 128) (at least 1), and at
 * n = 128 (--nc-at) nc = 1, 4, 16, 32, 64, 128 (--nc); for each structure and scheme (located,
 * consistent, paper; h = T / S, S = 200, alpha = -0.1; the paper scheme with one coefficient
 * update). Timed: sys_model_init's engine advanced over P periods (P = 2) after a quarter period of
 * settling (not timed), or fewer whole steps where a case would pass B seconds (B = 1: the large
 * dense structures); the minimum over R repetitions (R = 3) of the thread's CPU time
 * (bench_clock.h), every case timed once per repetition in turn. The friction solve's share: one
 * more run of the same steps with the engine's default friction solver (eng_dense_friction: the
 * Delassus matrix W M_hat^-1 W' through the model's Cholesky solves, then the basis solve or
 * Lemke) called through a wrapper that times it with the monotonic clock (so the share includes
 * the Delassus matrix's assembly), and the model's factorisations of M_hat (the modal backend's
 * O(n) each on these Rayleigh-damped structures; the dense Cholesky's O(n^3) where C is not
 * diagonal in the modal basis) timed and counted the same way; that run ends in the same state to the bit (checked). Per
 * case: ns per step, ns per step per DOF, the friction share, the share of steps with a pivot or a
 * located switch, switches per contact and period, the stuck share, the steps timed, the
 * factorisations' share and their number per step. Then the exponent p of
 * ns per step ~ n^p fitted (least squares in logs) over n >= 32 per structure and scheme, on stderr
 * and as "# fit" comment lines at the CSV's end. CSV on stdout, or to --csv FILE. */
#define _POSIX_C_SOURCE 200809L

#include "system.h"
#include "bossak.h"
#include "excitation.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_clock.h"

static void *std_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void std_free(void *env, void *obj) { (void)env; free(obj); }

#define OMEGA 0.5
#define MAX_CASES 256
#define MAX_LIST 16

/* ---- the structures ------------------------------------------------------------------------------ */

typedef struct {
    size_t n, nc;
    double *M, *C, *K, *F_c, *F_s, *x0, *v0, *W, *N, *mu_s, *mu_k, *k_t;
    double omega, t_end, h;
    int scheme;
} structure;

static double *dalloc(size_t count)
{
    double *p = (double *)calloc(count ? count : 1, sizeof(double));
    if (!p) { fprintf(stderr, "bench_system: out of memory\n"); exit(1); }
    return p;
}

static void structure_alloc(structure *s, size_t n, size_t nc)
{
    memset(s, 0, sizeof *s);
    s->n = n;
    s->nc = nc;
    s->M = dalloc(n * n); s->C = dalloc(n * n); s->K = dalloc(n * n);
    s->F_c = dalloc(n); s->F_s = dalloc(n); s->x0 = dalloc(n); s->v0 = dalloc(n);
    s->W = dalloc(nc * n); s->N = dalloc(nc); s->mu_s = dalloc(nc); s->mu_k = dalloc(nc); s->k_t = dalloc(nc);
}

static void structure_free(structure *s)
{
    double *a[] = {s->M, s->C, s->K, s->F_c, s->F_s, s->x0, s->v0, s->W, s->N, s->mu_s, s->mu_k, s->k_t};
    for (size_t i = 0; i < sizeof a / sizeof a[0]; i++) free(a[i]);
    memset(s, 0, sizeof *s);
}

/* a seeded generator in [0, 1) (64-bit LCG, top 53 bits) */
static double lcg(unsigned long long *st)
{
    *st = *st * 6364136223846793005ULL + 1442695040888963407ULL;
    return (double)(*st >> 11) * (1.0 / 9007199254740992.0);
}

enum { STRUCT_CHAIN = 0, STRUCT_BANDED = 1 };
static const char *const STRUCT_NAMES[] = {"chain", "banded"};
static const char *const SCHEME_NAMES[] = {"", "paper", "consistent", "located"}; /* DFO_SCHEME_* 1..3 */

static void structure_make(structure *s, int kind, size_t n, size_t nc, double normal)
{
    structure_alloc(s, n, nc);
    for (size_t i = 0; i < n; i++) {
        s->M[i * n + i] = 1.0;
        s->K[i * n + i] = 2.0;
        if (i + 1 < n) s->K[i * n + i + 1] = s->K[(i + 1) * n + i] = -1.0;
        s->F_c[i] = cos(0.1 * (double)i);
        s->F_s[i] = sin(0.1 * (double)i);
    }
    if (kind == STRUCT_BANDED) {
        unsigned long long st = 0x5eed0000ULL + n;
        for (size_t i = 0; i < n; i++)
            for (size_t j = i + 1; j < n && j <= i + 3; j++) {
                const double k = -0.1 * lcg(&st);
                s->K[i * n + j] += k;
                s->K[j * n + i] += k;
                if (j <= i + 2) {
                    const double m = 0.1 * (lcg(&st) - 0.5);
                    s->M[i * n + j] = s->M[j * n + i] = m;
                }
            }
        for (size_t i = 0; i < n; i++) { /* diagonal dominance: K positive definite, M too (|band| <= 0.2) */
            double off = 0.0;
            for (size_t j = 0; j < n; j++)
                if (j != i) off += fabs(s->K[i * n + j]);
            if (s->K[i * n + i] < off + 0.01) s->K[i * n + i] = off + 0.01;
        }
    }
    for (size_t k = 0; k < n * n; k++) s->C[k] = 0.02 * s->M[k] + 0.002 * s->K[k];
    for (size_t j = 0; j < nc; j++) {
        const size_t i = (size_t)(((double)j + 0.5) * (double)n / (double)nc);
        s->W[j * n + i] = 1.0;
        if (j % 2 == 1 && n > 1) s->W[j * n + ((i + 1 < n) ? i + 1 : i - 1)] = -1.0;
        s->N[j] = normal;
        s->mu_s[j] = 0.5;
        s->mu_k[j] = 0.35;
    }
    s->omega = OMEGA;
}

/* ---- the timed friction solve -------------------------------------------------------------------- */

/* The model's operators forwarded (the friction solver's ctx is the operators' ctx), the default
 * friction solver timed. */
typedef struct {
    eng_ops inner;
    eng *E;
    double ns, ns_factor;            /* in the friction solver; in factor (M_hat's factorisation) */
    long long calls, factors;
} timed_ctx;

static void t_K(void *c, const double *x, double *y) { timed_ctx *t = (timed_ctx *)c; t->inner.apply_K(t->inner.ctx, x, y); }
static void t_C(void *c, const double *x, double *y) { timed_ctx *t = (timed_ctx *)c; t->inner.apply_C(t->inner.ctx, x, y); }
static void t_M(void *c, const double *x, double *y) { timed_ctx *t = (timed_ctx *)c; t->inner.apply_M(t->inner.ctx, x, y); }
static int t_factor(void *c, int slot, double cM, double cC, double cK)
{
    timed_ctx *t = (timed_ctx *)c;
    const double t0 = bench_now_ns();
    const int ok = t->inner.factor(t->inner.ctx, slot, cM, cC, cK);
    t->ns_factor += bench_now_ns() - t0;
    t->factors++;
    return ok;
}
static void t_solve(void *c, int slot, const double *b, double *x)
{
    timed_ctx *t = (timed_ctx *)c;
    t->inner.solve(t->inner.ctx, slot, b, x);
}
static eng_status t_friction(void *c, const eng_problem *P, int what, int *mode, double *V1, double *f, int *pivots)
{
    timed_ctx *t = (timed_ctx *)c;
    const double t0 = bench_now_ns();
    const eng_status st = eng_dense_friction(t->E, P, what, mode, V1, f, pivots);
    t->ns += bench_now_ns() - t0;
    t->calls++;
    return st;
}

/* ---- one case ------------------------------------------------------------------------------------ */

typedef struct {
    int kind, scheme;
    size_t n, nc;
    structure s;
    sys_model m;
    eng_state st;
    double best_s;
    long long best_steps;            /* the grid steps of h timed: set by the first repetition (the budget's cut) */
    double pivot_share, switches_per_contact_period, stuck_share, friction_share, factor_share, factors_per_step;
    double *X_end;
    eng_status fail;                 /* ENG_OK, or why the case stopped (reported, not timed) */
    double t_fail;
} bench_case;

static const eng_alloc AL = {std_alloc, std_free, NULL};

static sys_params params_of(const structure *s, double h, int scheme)
{
    sys_params p;
    memset(&p, 0, sizeof p);
    p.n = s->n; p.nc = s->nc;
    p.M = s->M; p.C = s->C; p.K = s->K; p.F_c = s->F_c; p.F_s = s->F_s; p.x0 = s->x0; p.v0 = s->v0;
    p.W = s->W; p.N = s->N; p.mu_s = s->mu_s; p.mu_k = s->mu_k; p.k_t = s->k_t;
    p.omega = s->omega; p.h = h; p.alpha = -0.1; p.scheme = scheme; p.frictionUpdates = 1;
    return p;
}

static void model_make(sys_model *m, const structure *s, double h, int scheme)
{
    const sys_params p = params_of(s, h, scheme);
    char buf[256];
    const char *err = NULL;
    if (!sys_model_init(m, &p, &AL, 0, buf, sizeof buf, &err)) {
        fprintf(stderr, "bench_system: n = %zu, nc = %zu: %s\n", s->n, s->nc, err ? err : "?");
        exit(1);
    }
}

/* Advance E from a fresh start to the settling time, then by grid steps of h, in chunks, to at most
 * max_grid steps, stopping after the chunk that passes the budget (CPU seconds; INFINITY: all);
 * returns the timed seconds, *grid the grid steps timed, *st_out the engine's status (ENG_OK, or the
 * failure that stopped the run: the case is reported as failed). */
static double timed_run(eng *E, const structure *s, eng_state *st, double h, double t_settle, long long max_grid,
                        double budget, int wall, long long *grid, eng_status *st_out)
{
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    eng_start(E, &in, 0.0, s->x0, s->v0, st);
    *grid = 0;
    *st_out = eng_advance(E, &in, st, t_settle, NULL);
    if (*st_out != ENG_OK) return 0.0;
    const long long chunk = (max_grid >= 20) ? max_grid / 20 : 1;
    long long done = 0;
    const double t0 = bench_seconds(wall);
    double el = 0.0;
    while (done < max_grid) {
        done += (done + chunk <= max_grid) ? chunk : max_grid - done;
        *st_out = eng_advance(E, &in, st, t_settle + (double)done * h, NULL);
        if (*st_out != ENG_OK) return 0.0;
        el = bench_seconds(wall) - t0;
        if (el > budget) break;
    }
    *grid = done;
    return el;
}

typedef struct {
    double periods, spp, budget;
    int wall;
} run_opts;

static void case_make(bench_case *c, int kind, int scheme, size_t n, size_t nc, double normal, const run_opts *o)
{
    memset(c, 0, sizeof *c);
    c->kind = kind; c->scheme = scheme; c->n = n; c->nc = nc;
    structure_make(&c->s, kind, n, nc, normal);
    const double T = 2.0 * DFO_PI / OMEGA, h = T / o->spp;
    model_make(&c->m, &c->s, h, scheme);
    if (!eng_state_init(c->m.E, &c->st, 0)) { fprintf(stderr, "bench_system: out of memory\n"); exit(1); }
    c->best_s = INFINITY;
    c->X_end = dalloc(n);
}

static void case_rep(bench_case *c, const run_opts *o)
{
    const double T = 2.0 * DFO_PI / OMEGA, h = c->m.h;
    if (c->fail != ENG_OK) return;
    /* the first repetition cuts the run at the budget; the others take the same grid steps */
    const long long max_grid = c->best_steps ? c->best_steps : (long long)(o->periods * T / h + 0.5);
    long long grid = 0;
    eng_status es = ENG_OK;
    const double el = timed_run(c->m.E, &c->s, &c->st, h, 0.25 * T, max_grid, c->best_steps ? INFINITY : o->budget,
                                o->wall, &grid, &es);
    if (es != ENG_OK) {
        c->fail = es;
        c->t_fail = c->st.t;
        return;
    }
    c->best_steps = grid;
    if (el < c->best_s) c->best_s = el;
    memcpy(c->X_end, c->st.X, c->n * sizeof(double));
}

/* The untimed diagnostics over the same steps as the last repetition, and the friction solve's share
 * (a run with the timed solver); frees the case's model. */
static void case_finish(bench_case *c, const run_opts *o)
{
    const double T = 2.0 * DFO_PI / OMEGA, h = c->m.h;
    const double t_settle = 0.25 * T;
    const long long steps = c->best_steps;
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    eng_state *st = &c->st;
    if (c->fail != ENG_OK) {
        eng_state_free(c->m.E, st);
        sys_model_free(&c->m, &AL);
        structure_free(&c->s);
        free(c->X_end);
        return;
    }
    /* stuck share, pivots, switches: every step of one more run (the end of the last repetition) */
    eng_start(c->m.E, &in, 0.0, c->s.x0, c->s.v0, st);
    eng_advance(c->m.E, &in, st, t_settle, NULL);
    const long long st0 = st->steps, pv0 = st->pivot_steps, sw0 = st->switches;
    long long stuck = 0, samples = 0;
    for (long long k = 1; k <= steps; k++) {
        eng_advance(c->m.E, &in, st, t_settle + (double)k * h, NULL);
        for (size_t j = 0; j < c->nc; j++) stuck += (st->mode[j] == 0);
        samples += (long long)c->nc;
    }
    const double took = (double)(st->steps - st0), periods = (double)steps * h / T;
    c->pivot_share = (double)(st->pivot_steps - pv0) / took;
    c->switches_per_contact_period = (c->nc > 0) ? (double)(st->switches - sw0) / (double)c->nc / periods : 0.0;
    c->stuck_share = (samples > 0) ? (double)stuck / (double)samples : 0.0;
    /* the friction share: the same run with the default solver wrapped and timed */
    timed_ctx tc;
    memset(&tc, 0, sizeof tc);
    eng_setup S = *eng_setup_of(c->m.E);
    tc.inner = S.ops;
    S.ops.ctx = &tc;
    S.ops.apply_K = t_K;
    S.ops.apply_C = tc.inner.apply_C ? t_C : NULL;
    S.ops.apply_M = t_M;
    S.ops.factor = t_factor;
    S.ops.solve = t_solve;
    S.ops.friction = t_friction;
    const char *err = NULL;
    tc.E = eng_create(&S, &AL, &err);
    if (!tc.E) { fprintf(stderr, "bench_system: the timed engine: %s\n", err ? err : "?"); exit(1); }
    eng_state s2;
    if (!eng_state_init(tc.E, &s2, 0)) { fprintf(stderr, "bench_system: out of memory\n"); exit(1); }
    eng_start(tc.E, &in, 0.0, c->s.x0, c->s.v0, &s2);
    eng_advance(tc.E, &in, &s2, t_settle, NULL);
    tc.ns = tc.ns_factor = 0.0;
    tc.factors = 0;
    const double t0 = bench_now_ns();
    const long long chunk = (steps >= 20) ? steps / 20 : 1;
    for (long long k = chunk; k <= steps; k += chunk)
        eng_advance(tc.E, &in, &s2, t_settle + (double)k * h, NULL);
    if (steps % chunk) eng_advance(tc.E, &in, &s2, t_settle + (double)steps * h, NULL);
    const double total = bench_now_ns() - t0;
    c->friction_share = tc.ns / total;
    c->factor_share = tc.ns_factor / total;
    c->factors_per_step = (double)tc.factors / (double)steps;
    for (size_t i = 0; i < c->n; i++)
        if (memcmp(&s2.X[i], &c->X_end[i], sizeof(double)) != 0) {
            fprintf(stderr, "bench_system: %s %s n = %zu nc = %zu: the timed-solver run ends elsewhere (x[%zu] %.17g vs %.17g)\n",
                    STRUCT_NAMES[c->kind], SCHEME_NAMES[c->scheme], c->n, c->nc, i, s2.X[i], c->X_end[i]);
            exit(1);
        }
    eng_state_free(tc.E, &s2);
    eng_destroy(tc.E);
    eng_state_free(c->m.E, st);
    sys_model_free(&c->m, &AL);
    structure_free(&c->s);
    free(c->X_end);
    (void)o;
}

/* ---- --case: one structure from a file ----------------------------------------------------------- */

static int read_d(FILE *f, double *v, size_t count)
{
    for (size_t k = 0; k < count; k++)
        if (fscanf(f, "%lf", &v[k]) != 1) return 0;
    return 1;
}

/* The file: n nc scheme omega h t_end n_samples reps, then M, C, K (n x n row-major), F_c, F_s, x0,
 * v0 (n), W (nc x n), N, mu_s, mu_k (nc), whitespace-separated. The structure run from rest (x0, v0)
 * to t_end with the step h (alpha = -0.1), x sampled at t_end k / n_samples (k = 1 .. n_samples: a
 * multiple of h); the run repeated reps times, the minimum of the thread's CPU time kept. Out, one
 * line each: "cpu_s <seconds> steps <steps>", then one line of the n positions per sample. */
static int run_case(const char *path)
{
    FILE *f = fopen(path, "r");
    if (!f) { fprintf(stderr, "bench_system: cannot open %s\n", path); return 2; }
    double hdr[8];
    if (!read_d(f, hdr, 8)) { fprintf(stderr, "bench_system: %s: a bad header\n", path); fclose(f); return 2; }
    structure s;
    structure_alloc(&s, (size_t)hdr[0], (size_t)hdr[1]);
    const size_t n = s.n, nc = s.nc;
    const int ok = read_d(f, s.M, n * n) && read_d(f, s.C, n * n) && read_d(f, s.K, n * n) && read_d(f, s.F_c, n) &&
                   read_d(f, s.F_s, n) && read_d(f, s.x0, n) && read_d(f, s.v0, n) && read_d(f, s.W, nc * n) &&
                   read_d(f, s.N, nc) && read_d(f, s.mu_s, nc) && read_d(f, s.mu_k, nc);
    fclose(f);
    if (!ok) { fprintf(stderr, "bench_system: %s: fewer numbers than the sizes say\n", path); return 2; }
    s.omega = hdr[3];
    const double h = hdr[4], t_end = hdr[5];
    const long long ns = (long long)hdr[6];
    const int reps = (int)hdr[7];
    sys_model m;
    model_make(&m, &s, h, (int)hdr[2]);
    eng_state st;
    if (!eng_state_init(m.E, &st, 0)) return 1;
    double *xs = dalloc((size_t)ns * n);
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    double best = INFINITY;
    long long steps = 0;
    for (int r = 0; r < (reps > 0 ? reps : 1); r++) {
        const double t0 = bench_seconds(0);
        eng_start(m.E, &in, 0.0, s.x0, s.v0, &st);
        for (long long k = 1; k <= ns; k++) {
            const eng_status e = eng_advance(m.E, &in, &st, t_end * (double)k / (double)ns, NULL);
            if (e != ENG_OK) {
                fprintf(stderr, "bench_system: %s at t = %g\n", eng_status_text(e), st.t);
                return 1;
            }
            memcpy(xs + (size_t)(k - 1) * n, st.X, n * sizeof(double));
        }
        const double el = bench_seconds(0) - t0;
        if (el < best) best = el;
        steps = st.steps;
    }
    printf("cpu_s %.9g steps %lld\n", best, steps);
    for (long long k = 0; k < ns; k++) {
        for (size_t i = 0; i < n; i++) printf(i ? " %.17g" : "%.17g", xs[(size_t)k * n + i]);
        printf("\n");
    }
    free(xs);
    eng_state_free(m.E, &st);
    sys_model_free(&m, &AL);
    structure_free(&s);
    return 0;
}

/* ---- main ------------------------------------------------------------------------------------------- */

static int parse_list(char *arg, const char *const *names, int count, int *out, int max)
{
    int k = 0;
    for (char *tok = strtok(arg, ","); tok && k < max; tok = strtok(NULL, ",")) {
        int found = -1;
        for (int i = 0; i < count; i++)
            if (names[i][0] && !strcmp(tok, names[i])) found = i;
        if (found < 0) return -1;
        out[k++] = found;
    }
    return k;
}

int main(int argc, char **argv)
{
    size_t ns[MAX_LIST] = {8, 16, 32, 64, 128, 256, 512};
    size_t ncs[MAX_LIST] = {1, 4, 16, 32, 64, 128};
    int nnc = 6;
    size_t nc_at = 128;
    bench_run_opts o = {3, 2.0, 200.0, NULL, ns, MAX_LIST, 7};
    run_opts ro = {2.0, 200.0, 1.0, 0};
    double normal = 1.6;
    int schemes[3] = {DFO_SCHEME_LOCATED, DFO_SCHEME_CONSISTENT, DFO_SCHEME_PAPER}, nsch = 3;
    int kinds[2] = {STRUCT_CHAIN, STRUCT_BANDED}, nk = 2;
    for (int a = 1; a < argc; a++) {
        if (!strcmp(argv[a], "--case") && a + 1 < argc) return run_case(argv[a + 1]);
        if (bench_run_opt(argc, argv, &a, &o)) continue;
        if (!strcmp(argv[a], "--N") && a + 1 < argc) normal = atof(argv[++a]);
        else if (!strcmp(argv[a], "--seconds") && a + 1 < argc) ro.budget = atof(argv[++a]);
        else if (!strcmp(argv[a], "--nc-at") && a + 1 < argc) nc_at = (size_t)atol(argv[++a]);
        else if (!strcmp(argv[a], "--nc") && a + 1 < argc) nnc = bench_sizes(argv[++a], ncs, MAX_LIST);
        else if (!strcmp(argv[a], "--schemes") && a + 1 < argc) nsch = parse_list(argv[++a], SCHEME_NAMES, 4, schemes, 3);
        else if (!strcmp(argv[a], "--structures") && a + 1 < argc) nk = parse_list(argv[++a], STRUCT_NAMES, 2, kinds, 2);
        else if (!strcmp(argv[a], "--wall")) ro.wall = 1;
        else {
            fprintf(stderr, "bench_system: unknown or incomplete argument %s\n", argv[a]);
            return 2;
        }
    }
    if (bench_run_opts_bad(&o, "bench_system")) return 2;
    if (nsch < 1 || nk < 1 || nnc < 0 || !(ro.budget > 0.0)) {
        fprintf(stderr, "bench_system: --schemes of located,consistent,paper; --structures of chain,banded; --seconds > 0\n");
        return 2;
    }
    for (int j = 0; j < o.nn; j++)
        if (ns[j] > 1024) { fprintf(stderr, "bench_system: --n sizes up to 1024 (the model's limit)\n"); return 2; }
    ro.periods = o.periods;
    ro.spp = o.spp;
    FILE *out = bench_out(&o, "bench_system");
    if (!out) return 2;
    /* the cases: the n sweep (nc = n / 4, at most 128, at least 1), then the nc sweep at n = nc_at */
    bench_case *cases = (bench_case *)calloc(MAX_CASES, sizeof(bench_case));
    if (!cases) { fprintf(stderr, "bench_system: out of memory\n"); return 1; }
    int nca = 0;
    for (int k = 0; k < nk; k++)
        for (int sc = 0; sc < nsch; sc++) {
            for (int j = 0; j < o.nn && nca < MAX_CASES; j++) {
                size_t nc = ns[j] / 4;
                nc = nc < 1 ? 1 : nc > 128 ? 128 : nc;
                case_make(&cases[nca++], kinds[k], schemes[sc], ns[j], nc, normal, &ro);
            }
            for (int j = 0; j < nnc && nca < MAX_CASES; j++) {
                int dup = 0;
                for (int i = 0; i < o.nn; i++) {
                    size_t nc = ns[i] / 4;
                    nc = nc < 1 ? 1 : nc > 128 ? 128 : nc;
                    dup |= (ns[i] == nc_at && nc == ncs[j]);
                }
                if (!dup && ncs[j] <= nc_at) case_make(&cases[nca++], kinds[k], schemes[sc], nc_at, ncs[j], normal, &ro);
            }
        }
    for (int rep = 0; rep < o.reps; rep++)
        for (int c = 0; c < nca; c++) case_rep(&cases[c], &ro);
    fprintf(out, "structure,scheme,n,nc,ns_per_step,ns_per_step_per_dof,friction_share,pivot_or_switch_step_share,"
                 "switches_per_contact_period,stuck_share,steps_timed,factor_share,factors_per_step\n");
    double fit_x[MAX_CASES], fit_y[MAX_CASES];
    for (int c = 0; c < nca; c++) {
        bench_case *b = &cases[c];
        case_finish(b, &ro);
        if (b->fail != ENG_OK) {
            fprintf(out, "%s,%s,%zu,%zu,failed: %s at t = %.6g,,,,,,,,\n", STRUCT_NAMES[b->kind], SCHEME_NAMES[b->scheme],
                    b->n, b->nc, eng_status_text(b->fail), b->t_fail);
            b->best_s = NAN;
            continue;
        }
        const double nsps = 1e9 * b->best_s / (double)b->best_steps;
        fprintf(out, "%s,%s,%zu,%zu,%.1f,%.2f,%.4f,%.4f,%.3f,%.3f,%lld,%.4f,%.3f\n", STRUCT_NAMES[b->kind],
                SCHEME_NAMES[b->scheme], b->n, b->nc, nsps, nsps / (double)b->n, b->friction_share, b->pivot_share,
                b->switches_per_contact_period, b->stuck_share, b->best_steps, b->factor_share, b->factors_per_step);
        b->best_s = nsps; /* kept for the fit */
    }
    /* the growth: ns per step ~ n^p over the n sweep's n >= 32 (nc = n / 4 there), per structure and scheme */
    for (int k = 0; k < nk; k++)
        for (int sc = 0; sc < nsch; sc++) {
            int m = 0;
            for (int c = 0; c < nca; c++) {
                const bench_case *b = &cases[c];
                size_t nc = b->n / 4;
                nc = nc < 1 ? 1 : nc > 128 ? 128 : nc;
                if (b->kind == kinds[k] && b->scheme == schemes[sc] && b->n >= 32 && b->nc == nc && b->fail == ENG_OK) {
                    fit_x[m] = log((double)b->n);
                    fit_y[m] = log(b->best_s);
                    m++;
                }
            }
            if (m < 2) continue;
            double mx = 0.0, my = 0.0, sxx = 0.0, sxy = 0.0;
            for (int i = 0; i < m; i++) { mx += fit_x[i] / m; my += fit_y[i] / m; }
            for (int i = 0; i < m; i++) {
                sxx += (fit_x[i] - mx) * (fit_x[i] - mx);
                sxy += (fit_x[i] - mx) * (fit_y[i] - my);
            }
            fprintf(out, "# fit %s %s: ns_per_step ~ n^%.3f (%d sizes, n >= 32)\n", STRUCT_NAMES[kinds[k]], SCHEME_NAMES[schemes[sc]], sxy / sxx, m);
            fprintf(stderr, "bench_system: %s %s: ns per step ~ n^%.2f over n >= 32 (nc = n / 4, at most 128)\n",
                    STRUCT_NAMES[kinds[k]], SCHEME_NAMES[schemes[sc]], sxy / sxx);
        }
    free(cases);
    if (o.csv) fclose(out);
    return 0;
}
