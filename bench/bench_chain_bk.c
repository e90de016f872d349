/* ns per block-step of the chain's located scheme on a Burridge-Knopoff chain (fmu_src/models/chain/chain.h):
 * n blocks in the frame of the driver plate, every belt at -v_p, site springs, velocity-weakening
 * Stribeck friction (or Coulomb), for n = 256, 1024, 4096 (--n), in one run, the laws side by side.
 *
 *   bench_chain_bk [--reps N] [--seconds T] [--settle S] [--n N[,N...]] [--h H] [--dt DT]
 *                  [--law coulomb|stribeck|both]
 *
 * The chain: unit masses, couplings k = 2 (block 0 free on the left, the right end free), site
 * springs k_site = 0.5 and dampers c_site = 0.01, N = 1, mu_s = 0.6, chi = 0.5, Stribeck v_s = 0.1,
 * delta = 1, every belt at -0.2 m/s, no excitation, positions from a fixed pseudo-random start in
 * [-0.6, 0.6]. Timed: chain_advance_belt over T seconds (5) in communication steps of DT (0.1),
 * after S = 2 s of settling outside the clock; the minimum over the repetitions by the thread's CPU time,
 * the models timed in turn. Reported per n and law: ns per block-step, the share of steps whose warm
 * basis failed (a located switch), switches per block and second, the share of block-steps stuck. */
#define _POSIX_C_SOURCE 200809L

#include "chain.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_clock.h"

static void *std_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void std_free(void *env, void *obj) { (void)env; free(obj); }

enum { NARR = 15 };

typedef struct {
    size_t n;
    int law;
    double *arr, *vb;
    chain_model *M;
    chain_state s;
    double best, pivot, sw, stuck;
} bk_run;

static int bk_make(bk_run *b, size_t n, int law, double h)
{
    memset(b, 0, sizeof *b);
    b->n = n;
    b->law = law;
    b->best = INFINITY;
    b->arr = (double *)calloc(NARR * n, sizeof(double));
    b->vb = (double *)calloc(n, sizeof(double));
    if (!b->arr || !b->vb) return 0;
    double *a[NARR];
    for (int j = 0; j < NARR; j++) a[j] = b->arr + (size_t)j * n;
    unsigned long long r = 88172645463325252ULL;
    for (size_t i = 0; i < n; i++) {
        r ^= r << 13; r ^= r >> 7; r ^= r << 17;
        a[0][i] = 1.0;                      /* m */
        a[1][i] = (i == 0) ? 0.0 : 2.0;     /* k: couplings, block 0 free */
        a[2][i] = 0.0;                      /* c */
        a[3][i] = 0.0;                      /* P0 */
        a[4][i] = 0.0;                      /* phi */
        a[5][i] = 1.0;                      /* N */
        a[6][i] = 0.6;                      /* mu_s */
        a[7][i] = 0.5;                      /* chi */
        a[8][i] = -0.6 + 1.2 * (double)(r >> 11) / 9007199254740992.0; /* x0 */
        a[9][i] = -0.2;                     /* v0: on the belt */
        a[10][i] = 0.5;                     /* k_site */
        a[11][i] = 0.01;                    /* c_site */
        a[12][i] = 0.1;                     /* v_s */
        a[13][i] = 1.0;                     /* delta */
        b->vb[i] = -0.2;
    }
    const chain_params p = {n, a[0], a[1], a[2], a[3], a[4], a[5], a[6], a[7], a[8], a[9], 0.0, 0.0, 0.0, h, -0.1, 3, 0,
                            a[10], a[11], law, a[12], a[13]};
    char buf[200];
    const char *msg = chain_check_params(&p, buf, sizeof buf);
    if (msg) { fprintf(stderr, "bench_chain_bk: %s\n", msg); return 0; }
    const chain_alloc al = {std_alloc, std_free, NULL};
    b->M = chain_create(&p, &al, NULL);
    return b->M && chain_state_init(b->M, &b->s);
}

/* Start, settle 2 s, then time T seconds in steps of dt. Returns 0 on a failed step. */
static int bk_time(bk_run *b, double T, double dt, double settle)
{
    const chain_inputs in = {NULL, NULL};
    chain_start_belt(b->M, &in, b->vb, 0.0, &b->s);
    double t = 0.0;
    for (; t < settle - 1e-12; t += dt) {
        const chain_status st = chain_advance_belt(b->M, &in, NULL, b->vb, &b->s, t + dt, 0, NULL, NULL);
        if (st != CHAIN_OK) {
            fprintf(stderr, "bench_chain_bk: n = %zu, %s: t = %g: %s\n", b->n, b->law == 2 ? "stribeck" : "coulomb",
                    b->s.t, chain_status_text(st));
            return 0;
        }
    }
    const long long steps0 = b->s.steps, piv0 = b->s.pivot_steps, sw0 = b->s.switches;
    double stuck = 0.0;
    long long samples = 0;
    const double c0 = bench_seconds(0);
    const int k_end = (int)floor(T / dt + 0.5);
    for (int k = 0; k < k_end; k++) {
        t += dt;
        const chain_status st = chain_advance_belt(b->M, &in, NULL, b->vb, &b->s, t, 0, NULL, NULL);
        if (st != CHAIN_OK) {
            fprintf(stderr, "bench_chain_bk: n = %zu, %s: t = %g: %s\n", b->n, b->law == 2 ? "stribeck" : "coulomb",
                    b->s.t, chain_status_text(st));
            return 0;
        }
        for (size_t i = 0; i < b->n; i++) stuck += (b->s.mode[i] == 0);
        samples += (long long)b->n;
    }
    const double el = bench_seconds(0) - c0;
    const long long steps = b->s.steps - steps0;
    const double ns = 1e9 * el / ((double)steps * (double)b->n);
    if (ns < b->best) {
        b->best = ns;
        b->pivot = (double)(b->s.pivot_steps - piv0) / (double)steps;
        b->sw = (double)(b->s.switches - sw0) / ((double)b->n * T);
        b->stuck = stuck / (double)samples;
    }
    return 1;
}

int main(int argc, char **argv)
{
    int reps = 3, laws[2] = {2, 1}, nlaws = 2;
    double T = 5.0, h = 1e-3, dt = 0.1, settle = 2.0;
    size_t ns[16] = {256, 1024, 4096};
    int nn = 3;
    for (int a = 1; a < argc; a++) {
        const char *v = (a + 1 < argc) ? argv[a + 1] : "";
        if (!strcmp(argv[a], "--reps")) { reps = atoi(v); a++; }
        else if (!strcmp(argv[a], "--seconds")) { T = atof(v); a++; }
        else if (!strcmp(argv[a], "--h")) { h = atof(v); a++; }
        else if (!strcmp(argv[a], "--settle")) { settle = atof(v); a++; }
        else if (!strcmp(argv[a], "--dt")) { dt = atof(v); a++; }
        else if (!strcmp(argv[a], "--law")) {
            if (!strcmp(v, "coulomb")) { laws[0] = 1; nlaws = 1; }
            else if (!strcmp(v, "stribeck")) { laws[0] = 2; nlaws = 1; }
            else if (strcmp(v, "both")) { fprintf(stderr, "bench_chain_bk: --law coulomb|stribeck|both\n"); return 2; }
            a++;
        } else if (!strcmp(argv[a], "--n")) {
            nn = bench_sizes(argv[++a], ns, 16);
        } else {
            fprintf(stderr, "usage: bench_chain_bk [--reps N] [--seconds T] [--settle S] [--n N,...] [--h H] [--dt DT] "
                            "[--law coulomb|stribeck|both]\n");
            return 2;
        }
    }
    if (reps < 1 || nn < 1 || !(T > 0.0) || !(h > 0.0) || !(dt > 0.0)) {
        fprintf(stderr, "bench_chain_bk: reps, n, seconds, h and dt must be positive\n");
        return 2;
    }
    bk_run runs[32];
    int nr = 0;
    for (int i = 0; i < nn; i++)
        for (int l = 0; l < nlaws; l++)
            if (!bk_make(&runs[nr++], ns[i], laws[l], h)) { fprintf(stderr, "bench_chain_bk: set-up failed\n"); return 1; }
    for (int r = 0; r < reps; r++)
        for (int k = 0; k < nr; k++)
            if (!bk_time(&runs[k], T, dt, settle)) { fprintf(stderr, "bench_chain_bk: a step failed\n"); return 1; }
    printf("n,law,ns_per_block_step,switch_step_share,switches_per_block_s,stuck_share\n");
    for (int k = 0; k < nr; k++)
        printf("%zu,%s,%.2f,%.4f,%.3f,%.3f\n", runs[k].n, runs[k].law == 2 ? "stribeck" : "coulomb", runs[k].best,
               runs[k].pivot, runs[k].sw, runs[k].stuck);
    for (int k = 0; k < nr; k++) {
        chain_state_free(runs[k].M, &runs[k].s);
        chain_destroy(runs[k].M);
        free(runs[k].arr);
        free(runs[k].vb);
    }
    return 0;
}
