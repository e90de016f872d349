/* ns per block-step of the chain (fmu_src/models/chain/chain.h) on a stick-slip chain, for n = 1, 2, 8, 64, 512, 4096,
 * side by side with the oscillator's stepper (newmark.[ch]) on the same single block, in one run.
 *
 *   bench_chain [--reps N] [--periods P] [--steps-per-period S] [--n N[,N...]] [--N NORMAL] [--wall]
 *               [--csv FILE]
 *
 * The chain: unit masses and springs, both ends on the wall (k_end = 1), every block forced
 * (P0 = 1, omega = 0.5, phase 0.1 per block), mu_s = 0.5, N = 1.6 (--N), chi = 0.7, scheme located,
 * alpha = -0.1, h = T / S (S = 1000). Timed: chain_advance over P periods (after one period of
 * settling, outside the clock) in one call, as dfo_advance for the oscillator; the minimum over
 * the repetitions, every model timed once per repetition in turn (so that a change of the
 * machine's load reaches all of them alike), by the thread's CPU time (bench_clock.h's
 * bench_seconds). Reported per n: ns per block-step, ns per step, the share of steps whose warm
 * basis was infeasible (a pivot or a located switch), switches per block and period, and the
 * share of time stuck. For n = 1 the oscillator's dfo_advance on the same block (fastPaths on and
 * off). CSV on stdout, or to --csv FILE. */
#define _POSIX_C_SOURCE 200809L

#include "chain.h"
#include "scheme.h"
#include "oscillator.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_clock.h"

static void *std_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void std_free(void *env, void *obj) { (void)env; free(obj); }

#define OMEGA 0.5
#define PHASE_STEP 0.1

typedef struct {
    double ns_block_step, ns_step, pivot_share, switches_per_block_period, stuck_share;
} result;

/* One chain of the run: its model and state, and its best repetition so far. */
typedef struct {
    size_t n;
    double *arr;
    chain_model *M;
    chain_state s;
    double best;
    result r;
} chain_case;

static void chain_case_make(chain_case *cc, size_t n, double spp, double normal)
{
    memset(cc, 0, sizeof *cc);
    cc->n = n;
    cc->best = INFINITY;
    double *arr = (double *)calloc(10 * n, sizeof(double));
    if (!arr) { fprintf(stderr, "bench_chain: out of memory for n = %zu\n", n); exit(1); }
    double *m = arr, *k = arr + n, *c = arr + 2 * n, *P0 = arr + 3 * n, *phi = arr + 4 * n, *N = arr + 5 * n,
           *mu_s = arr + 6 * n, *chi = arr + 7 * n, *x0 = arr + 8 * n, *v0 = arr + 9 * n;
    for (size_t i = 0; i < n; i++) {
        m[i] = 1.0; k[i] = 1.0; c[i] = 0.0; P0[i] = 1.0; phi[i] = PHASE_STEP * (double)i;
        N[i] = normal; mu_s[i] = 0.5; chi[i] = 0.7; x0[i] = 0.0; v0[i] = 0.0;
    }
    const double T = 2.0 * DFO_PI / OMEGA, h = T / spp;
    const chain_params p = {n, m, k, c, P0, phi, N, mu_s, chi, x0, v0, (n == 1) ? 0.0 : 1.0, 0.0, OMEGA, h, -0.1, 3, 0, NULL, NULL, 0, NULL, NULL};
    const chain_alloc al = {std_alloc, std_free, NULL};
    cc->arr = arr;
    cc->M = chain_create(&p, &al, NULL);
    if (!cc->M || !chain_state_init(cc->M, &cc->s)) {
        fprintf(stderr, "bench_chain: cannot make n = %zu\n", n);
        exit(1);
    }
}

/* One timed repetition: start, one period of settling (not timed), then P periods in one call. */
static void chain_case_rep(chain_case *cc, double periods, double spp, int wall)
{
    const double T = 2.0 * DFO_PI / OMEGA, h = T / spp;
    const chain_inputs in = {NULL, NULL};
    chain_state *s = &cc->s;
    chain_start(cc->M, &in, 0.0, s);
    chain_advance(cc->M, &in, s, T, 0, NULL, NULL);
    const long long steps0 = s->steps, piv0 = s->pivot_steps, sw0 = s->switches;
    const long long nsteps = (long long)(periods * spp + 0.5);
    const double t0 = bench_seconds(wall);
    if (chain_advance(cc->M, &in, s, T + (double)nsteps * h, 0, NULL, NULL) != CHAIN_OK) {
        fprintf(stderr, "bench_chain: n = %zu failed at t = %g\n", cc->n, s->t);
        exit(1);
    }
    const double el = bench_seconds(wall) - t0;
    const double steps = (double)(s->steps - steps0);
    if (el < cc->best) {
        cc->best = el;
        cc->r.ns_step = 1e9 * el / steps;
        cc->r.ns_block_step = cc->r.ns_step / (double)cc->n;
        cc->r.pivot_share = (double)(s->pivot_steps - piv0) / steps;
        cc->r.switches_per_block_period = (double)(s->switches - sw0) / (double)cc->n / periods;
    }
}

/* The share of time stuck, sampled every 10th grid point of one more run (not timed); frees. */
static void chain_case_finish(chain_case *cc, double periods, double spp)
{
    const double T = 2.0 * DFO_PI / OMEGA, h = T / spp;
    const chain_inputs in = {NULL, NULL};
    chain_state *s = &cc->s;
    long long stuck = 0, samples = 0;
    chain_start(cc->M, &in, 0.0, s);
    chain_advance(cc->M, &in, s, T, 0, NULL, NULL);
    const long long nsteps = (long long)(periods * spp + 0.5);
    for (long long j = 10; j <= nsteps; j += 10) {
        chain_advance(cc->M, &in, s, T + (double)j * h, 0, NULL, NULL);
        for (size_t i = 0; i < cc->n; i++) stuck += (s->mode[i] == 0);
        samples += (long long)cc->n;
    }
    cc->r.stuck_share = (samples > 0) ? (double)stuck / (double)samples : 0.0;
    chain_state_free(cc->M, s);
    chain_destroy(cc->M);
    free(cc->arr);
}

/* The oscillator's stepper on the same block: one timed repetition, as chain_case_rep. */
typedef struct {
    dfo_model M;
    double best, per;
} osc_case;

static void osc_case_make(osc_case *oc, double spp, int fast, double normal)
{
    dfo_params p;
    memset(&p, 0, sizeof p);
    p.m = 1.0; p.k = 1.0; p.P0 = 1.0; p.omega = OMEGA; p.N = normal; p.mu_s = 0.5; p.chi = 0.7;
    const double T = 2.0 * DFO_PI / OMEGA;
    p.h = T / spp; p.alpha = -0.1; p.t_obs_stop = 1e300; p.scheme = 3; p.frictionUpdates = 1; p.fastPaths = fast;
    dfo_model_init(&oc->M, &p);
    oc->best = INFINITY;
    oc->per = 0.0;
}

static void osc_case_rep(osc_case *oc, double periods, double spp, int wall)
{
    const double T = 2.0 * DFO_PI / OMEGA;
    dfo_inputs u;
    memset(&u, 0, sizeof u);
    dfo_state s;
    dfo_start(&oc->M, &u, 0.0, &s);
    dfo_advance(&oc->M, &u, &s, T, NULL, NULL);
    const long long steps0 = s.steps;
    const long long nsteps = (long long)(periods * spp + 0.5);
    const double t0 = bench_seconds(wall);
    dfo_advance(&oc->M, &u, &s, T + (double)nsteps * oc->M.p.h, NULL, NULL);
    const double el = bench_seconds(wall) - t0;
    if (el < oc->best) { oc->best = el; oc->per = 1e9 * el / (double)(s.steps - steps0); }
}

int main(int argc, char **argv)
{
    size_t ns[16] = {1, 2, 8, 64, 512, 4096};
    bench_run_opts o = {5, 4.0, 1000.0, NULL, ns, 16, 6};
    int wall = 0;
    double normal = 1.6;
    for (int a = 1; a < argc; a++) {
        if (bench_run_opt(argc, argv, &a, &o)) continue;
        if (!strcmp(argv[a], "--N") && a + 1 < argc) normal = atof(argv[++a]);
        else if (!strcmp(argv[a], "--wall")) wall = 1;
        else {
            fprintf(stderr, "bench_chain: unknown or incomplete argument %s\n", argv[a]);
            return 2;
        }
    }
    if (bench_run_opts_bad(&o, "bench_chain")) return 2;
    const int reps = o.reps, nn = o.nn;
    const double periods = o.periods, spp = o.spp;
    const char *csv = o.csv;
    FILE *out = bench_out(&o, "bench_chain");
    if (!out) return 2;
    /* every model is timed once per repetition, in turn, so that a change of the machine's load
     * reaches all of them alike; each keeps its best repetition */
    osc_case osc[2];
    osc_case_make(&osc[0], spp, 1, normal);
    osc_case_make(&osc[1], spp, 0, normal);
    chain_case cases[16];
    for (int j = 0; j < nn; j++) chain_case_make(&cases[j], ns[j], spp, normal);
    for (int rep = 0; rep < reps; rep++) {
        for (int k = 0; k < 2; k++) osc_case_rep(&osc[k], periods, spp, wall);
        for (int j = 0; j < nn; j++) chain_case_rep(&cases[j], periods, spp, wall);
    }
    fprintf(out, "model,n,ns_per_block_step,ns_per_step,pivot_step_share,switches_per_block_period,stuck_share\n");
    fprintf(out, "oscillator(fastPaths),1,%.2f,%.2f,,,\n", osc[0].per, osc[0].per);
    fprintf(out, "oscillator(general),1,%.2f,%.2f,,,\n", osc[1].per, osc[1].per);
    for (int j = 0; j < nn; j++) {
        chain_case_finish(&cases[j], periods, spp);
        const result r = cases[j].r;
        fprintf(out, "chain,%zu,%.2f,%.1f,%.4f,%.3f,%.3f\n", ns[j], r.ns_block_step, r.ns_step, r.pivot_share,
                r.switches_per_block_period, r.stuck_share);
    }
    if (csv) fclose(out);
    return 0;
}
