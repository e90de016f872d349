/* ns per internal step of the friction engine (fmu_src/engine) side by side with the models' own
 * steppers on the same motion, and what reaching the operators costs: the engine's schemes with the
 * operators through eng_ops's function pointers (engine.c) against the same schemes specialised at
 * compile time by the model's inline operators (engine_step.h included by models/oscillator/osc_engine.c
 * and models/chain/chain_engine.c, with the operators of osc_engine_ops.h and chain_engine_ops.h).
 *
 *   bench_engine [--reps N] [--periods P] [--steps-per-period S] [--n N[,N...]] [--csv FILE]
 *
 * The motion is bench_chain's: unit masses and springs, every block forced (P0 = 1, omega = 0.5,
 * phase 0.1 per block), mu_s = 0.5, N = 1.6, chi = 0.7, alpha = -0.1, h = T / S (S = 1000); one
 * block (the oscillator's dfo_advance, fastPaths on) and chains of n blocks between two walls
 * (chain_advance), in the three Bossak schemes. Per case and scheme:
 *   own        the model's own stepper (dfo_advance, chain_advance)
 *   generic    eng_advance, the model's operators and friction solver through function pointers (the
 *              chain: the engine chain_create makes, its operators chain_engine_ops.h's)
 *   dense      (one block) eng_advance with the engine's default friction solver (Delassus, Lemke)
 *   inline     the specialised schemes (osc_eng_advance; the chain's chain_eng_advance on the engine
 *              of another chain_create, so that the two runs share no operator data)
 * and the ratios generic / own and inline / own; same_bits says whether the generic and the
 * inline runs end on the same bits (they must: the same arithmetic in the same order). Timed: one
 * call over P periods after one period of settling (outside the clock), the thread's CPU time, the
 * minimum over the repetitions, every variant timed once per repetition in turn. */
#define _POSIX_C_SOURCE 200809L

#include "chain_internal.h" /* the chain's engine (chain_model.E) and its specialised schemes */
#include "osc_engine.h"     /* the block's operators and its specialised schemes */
#include "oscillator.h"
#include "scheme.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_clock.h"

#define OMEGA 0.5
#define PHASE_STEP 0.1
#define NORMAL 1.6
#define MU_S 0.5
#define CHI 0.7
#define NMAX_CASES 8

static void *std_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void std_free(void *env, void *obj) { (void)env; free(obj); }
static const eng_alloc ALLOC = {std_alloc, std_free, NULL};

static void die(const char *what)
{
    fprintf(stderr, "bench_engine: %s\n", what);
    exit(1);
}

enum { V_OWN = 0, V_GENERIC = 1, V_INLINE = 2, V_DENSE = 3, NVAR = 4 };
static const char *const VAR_NAMES[NVAR] = {"own", "generic", "inline", "dense"};

/* One structure (n blocks; n = 1: the oscillator's block) in one scheme: its data, the engines of
 * its variants, their best times and end states. */
typedef struct {
    size_t n;
    int scheme;
    double T, h;
    double *m, *k, *zero, *P0, *Pc, *Ps, *N, *mu_s, *mu_k, *phi, *chi;
    size_t *idx;
    double *w1;
    eng_row *rows;
    osc_eng_model blk;
    eng *E[NVAR];              /* the engines of the variants (the chain's: those of CM[v]) */
    eng_state es[NVAR];
    dfo_model osc;
    chain_model *CM[NVAR];     /* the chain of each variant but the dense (own: chain_advance on CM[0]) */
    chain_state cs;
    double best[NVAR];
    double steps[NVAR];
    double x_end[NVAR];
} bench_case;

static double *dalloc(size_t n)
{
    double *p = (double *)calloc(n ? n : 1, sizeof(double));
    if (!p) die("out of memory");
    return p;
}

/* The block's engine setup (the chain's is chain_create's). */
static eng_setup block_setup(bench_case *B, int variant)
{
    eng_setup S;
    memset(&S, 0, sizeof S);
    S.n = 1;
    S.nc = 1;
    const eng_ops ops = {&B->blk, eng1_K, eng1_C, eng1_M, eng1_factor, eng1_solve,
                         variant == V_DENSE ? NULL : eng1_friction, variant == V_DENSE ? NULL : eng1_breakaway, 1};
    S.ops = ops;
    S.rows = B->rows;
    S.exc.omega = OMEGA;
    S.exc.Pc = B->Pc;
    S.exc.Ps = B->Ps;
    S.N = B->N;
    S.mu_s = B->mu_s;
    S.mu_k = B->mu_k;
    S.h = B->h;
    S.alpha = -0.1;
    S.scheme = B->scheme;
    S.friction_updates = 1;
    S.fast_paths = 1;
    S.rate_max = 1.0 + OMEGA; /* sqrt of M^-1 K's Gershgorin bound, + omega */
    S.snap_max_rel_h = S.snap_min_rel_h = 1e-7;
    return S;
}

static void case_make(bench_case *B, size_t n, int scheme, double spp)
{
    memset(B, 0, sizeof *B);
    B->n = n;
    B->scheme = scheme;
    B->T = 2.0 * DFO_PI / OMEGA;
    B->h = B->T / spp;
    B->m = dalloc(n); B->k = dalloc(n); B->zero = dalloc(n); B->Pc = dalloc(n); B->Ps = dalloc(n);
    B->N = dalloc(n); B->mu_s = dalloc(n); B->mu_k = dalloc(n); B->phi = dalloc(n); B->chi = dalloc(n);
    B->w1 = dalloc(1);
    B->w1[0] = 1.0;
    B->idx = (size_t *)calloc(n, sizeof(size_t));
    B->rows = (eng_row *)calloc(n, sizeof(eng_row));
    if (!B->idx || !B->rows) die("out of memory");
    for (size_t i = 0; i < n; i++) {
        B->m[i] = 1.0; B->k[i] = 1.0; B->N[i] = NORMAL; B->mu_s[i] = MU_S; B->chi[i] = CHI;
        B->mu_k[i] = CHI * MU_S;
        B->phi[i] = PHASE_STEP * (double)i;
        B->Pc[i] = cos(B->phi[i]);
        B->Ps[i] = sin(B->phi[i]);
        B->idx[i] = i;
        B->rows[i].nnz = 1;
        B->rows[i].idx = &B->idx[i];
        B->rows[i].w = B->w1;
    }
    if (n == 1) {
        B->blk.m = 1.0; B->blk.k = 1.0; B->blk.c = 0.0;
        dfo_params p;
        memset(&p, 0, sizeof p);
        p.m = 1.0; p.k = 1.0; p.P0 = 1.0; p.omega = OMEGA; p.N = NORMAL; p.mu_s = MU_S; p.chi = CHI;
        p.h = B->h; p.alpha = -0.1; p.t_obs_stop = 1e300; p.scheme = scheme; p.frictionUpdates = 1; p.fastPaths = 1;
        dfo_model_init(&B->osc, &p);
    } else {
        B->P0 = dalloc(n);
        for (size_t i = 0; i < n; i++) B->P0[i] = 1.0;
        const chain_params q = {n, B->m, B->k, B->zero, B->P0, B->phi, B->N, B->mu_s, B->chi, B->zero, B->zero,
                                1.0, 0.0, OMEGA, B->h, -0.1, scheme, 0, NULL, NULL, 0, NULL, NULL};
        const chain_alloc al = {std_alloc, std_free, NULL};
        for (int v = V_OWN; v <= V_INLINE; v++) {
            B->CM[v] = chain_create(&q, &al, NULL);
            if (!B->CM[v]) die("cannot make the chain");
        }
        if (!chain_state_init(B->CM[V_OWN], &B->cs)) die("cannot make the chain");
    }
    for (int v = V_GENERIC; v < NVAR; v++) {
        if (v == V_DENSE && n != 1) continue;
        if (n == 1) {
            const eng_setup S = block_setup(B, v);
            B->E[v] = eng_create(&S, &ALLOC, NULL);
        } else {
            B->E[v] = B->CM[v]->E;
        }
        if (!B->E[v] || !eng_state_init(B->E[v], &B->es[v], 0)) die("cannot make an engine");
    }
    for (int v = 0; v < NVAR; v++) B->best[v] = INFINITY;
}

/* One timed repetition of variant v: start, one period untimed, then P periods in one call. */
static void case_rep(bench_case *B, int v, double periods, double spp)
{
    const long long nsteps = (long long)(periods * spp + 0.5);
    const double t1 = B->T, t2 = B->T + (double)nsteps * B->h;
    double el = 0.0, steps = 0.0, x = 0.0;
    if (v == V_OWN && B->n == 1) {
        dfo_inputs u;
        memset(&u, 0, sizeof u);
        dfo_state s;
        dfo_start(&B->osc, &u, 0.0, &s);
        dfo_advance(&B->osc, &u, &s, t1, NULL, NULL);
        const long long s0 = s.steps;
        const double c0 = bench_seconds(0);
        if (dfo_advance(&B->osc, &u, &s, t2, NULL, NULL) != DFO_OK) die("dfo_advance failed");
        el = bench_seconds(0) - c0;
        steps = (double)(s.steps - s0);
        x = s.X;
    } else if (v == V_OWN) {
        const chain_inputs in = {NULL, NULL};
        chain_start(B->CM[V_OWN], &in, 0.0, &B->cs);
        chain_advance(B->CM[V_OWN], &in, &B->cs, t1, 0, NULL, NULL);
        const long long s0 = B->cs.steps;
        const double c0 = bench_seconds(0);
        if (chain_advance(B->CM[V_OWN], &in, &B->cs, t2, 0, NULL, NULL) != CHAIN_OK) die("chain_advance failed");
        el = bench_seconds(0) - c0;
        steps = (double)(B->cs.steps - s0);
        x = B->cs.X[B->n - 1];
    } else {
        eng *E = B->E[v];
        eng_state *s = &B->es[v];
        const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
        const int inl = v == V_INLINE;
        const int one = B->n == 1;
        if (inl && one) osc_eng_start(E, &in, 0.0, B->zero, B->zero, s);
        else if (inl) chain_eng_start(E, &in, 0.0, B->zero, B->zero, s);
        else eng_start(E, &in, 0.0, B->zero, B->zero, s);
        eng_status st = inl ? (one ? osc_eng_advance(E, &in, s, t1, NULL) : chain_eng_advance(E, &in, s, t1, NULL))
                            : eng_advance(E, &in, s, t1, NULL);
        const long long s0 = s->steps;
        const double c0 = bench_seconds(0);
        if (st == ENG_OK)
            st = inl ? (one ? osc_eng_advance(E, &in, s, t2, NULL) : chain_eng_advance(E, &in, s, t2, NULL))
                     : eng_advance(E, &in, s, t2, NULL);
        el = bench_seconds(0) - c0;
        if (st != ENG_OK) die(eng_status_text(st));
        steps = (double)(s->steps - s0);
        x = s->X[B->n - 1];
    }
    if (el < B->best[v]) B->best[v] = el;
    B->steps[v] = steps;
    B->x_end[v] = x;
}

int main(int argc, char **argv)
{
    size_t ns[NMAX_CASES] = {1, 8, 64};
    bench_run_opts o = {5, 4.0, 1000.0, NULL, ns, NMAX_CASES, 3};
    for (int a = 1; a < argc; a++)
        if (!bench_run_opt(argc, argv, &a, &o)) {
            fprintf(stderr, "bench_engine: unknown or incomplete argument %s\n", argv[a]);
            return 2;
        }
    if (bench_run_opts_bad(&o, "bench_engine")) return 2;
    FILE *out = bench_out(&o, "bench_engine");
    if (!out) return 2;
    const int nn = o.nn;
    static const char *const schemes[] = {"", "paper", "consistent", "located"};
    bench_case *cases = (bench_case *)calloc((size_t)nn * 3, sizeof(bench_case));
    if (!cases) die("out of memory");
    for (int j = 0; j < nn; j++)
        for (int sc = 0; sc < 3; sc++) case_make(&cases[j * 3 + sc], ns[j], DFO_SCHEME_PAPER + sc, o.spp);
    for (int rep = 0; rep < o.reps; rep++)
        for (int c = 0; c < nn * 3; c++)
            for (int v = 0; v < NVAR; v++)
                if (v != V_DENSE || cases[c].n == 1) case_rep(&cases[c], v, o.periods, o.spp);
    fprintf(out, "n,scheme,ns_per_step_%s,ns_per_step_%s,ns_per_step_%s,ns_per_step_%s,generic/own,inline/own,"
                 "same_bits,x_end_own,x_end_engine\n", VAR_NAMES[0], VAR_NAMES[1], VAR_NAMES[2], VAR_NAMES[3]);
    for (int c = 0; c < nn * 3; c++) {
        const bench_case *B = &cases[c];
        double ns_step[NVAR];
        for (int v = 0; v < NVAR; v++) ns_step[v] = (B->steps[v] > 0.0) ? 1e9 * B->best[v] / B->steps[v] : NAN;
        fprintf(out, "%zu,%s,%.2f,%.2f,%.2f,%.2f,%.3f,%.3f,%d,%.17g,%.17g\n", B->n, schemes[B->scheme], ns_step[0],
                ns_step[1], ns_step[2], ns_step[3], ns_step[1] / ns_step[0], ns_step[2] / ns_step[0],
                memcmp(&B->x_end[V_GENERIC], &B->x_end[V_INLINE], sizeof(double)) == 0, B->x_end[V_OWN],
                B->x_end[V_GENERIC]);
    }
    if (o.csv) fclose(out);
    return 0;
}
