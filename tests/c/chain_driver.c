/* Command-line driver of the chain's physics (fmu_src/models/chain/chain.h) for the Python tests: runs one chain
 * prints its trajectory as CSV on stdout.
 *
 *   chain_driver n=N t_end=T h=H [dt=DT | random_dt=SEED] [alpha=A] [scheme=S] [omega=W]
 *                [k_end=K] [c_end=C] [m=v1,v2,...] [k=...] [c=...] [P0=...] [phi=...] [N=...]
 *                [mu_s=...] [chi=...] [x0=...] [v0=...] [F_ext=...] [N_ext=...] [energy=0|1]
 *
 * energy=1 (default) keeps the energy accounts, which makes the located scheme split the whole
 * chain at every switch; energy=0 lets a long chain place its switches in spans around the
 * switching blocks (the engine's eng_sparse spans), with the accounts left at 0.
 * A list with one value sets every block. Output: one row per communication point, columns t,
 * then x_i, v_i, F_i, mode_i for every block, then E (mechanical energy), W_applied, W_friction,
 * D_damping, steps, pivot_steps, switches. random_dt draws communication steps in [0.1 h, 3 h].
 * Bad input: one line on stderr and exit status 2. */
#include "chain.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_N 4096

static void *std_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void std_free(void *env, void *obj) { (void)env; free(obj); }

static int parse_list(const char *v, double *out, size_t n)
{
    size_t i = 0;
    const char *p = v;
    while (*p && i < n) {
        char *end;
        out[i++] = strtod(p, &end);
        if (end == p) return 0;
        p = (*end == ',') ? end + 1 : end;
        if (*end != ',' && *end != '\0') return 0;
    }
    for (size_t j = i; j < n; j++) out[j] = out[i - 1];
    return i > 0;
}

int main(int argc, char **argv)
{
    static double arr[12][MAX_N];
    const char *names[12] = {"m", "k", "c", "P0", "phi", "N", "mu_s", "chi", "x0", "v0", "F_ext", "N_ext"};
    const double defaults[12] = {1, 100, 0, 1, 0, 1, 0.4, 0.7, 0, 0, 0, 0};
    const char *given[12] = {0};
    size_t n = 2;
    double t_end = 1.0, h = 1e-3, dt = 0.0, alpha = -0.1, omega = 5.0, k_end = 0.0, c_end = 0.0;
    int scheme = 3, energy = 1;
    unsigned long long seed = 0;
    for (int a = 1; a < argc; a++) {
        char *eq = strchr(argv[a], '=');
        if (!eq) { fprintf(stderr, "chain_driver: argument %s is not name=value\n", argv[a]); return 2; }
        *eq = '\0';
        const char *key = argv[a], *val = eq + 1;
        int found = 0;
        for (int j = 0; j < 12; j++)
            if (!strcmp(key, names[j])) { given[j] = val; found = 1; }
        if (found) continue;
        if (!strcmp(key, "n")) n = (size_t)strtoull(val, NULL, 10);
        else if (!strcmp(key, "t_end")) t_end = atof(val);
        else if (!strcmp(key, "h")) h = atof(val);
        else if (!strcmp(key, "dt")) dt = atof(val);
        else if (!strcmp(key, "random_dt")) seed = strtoull(val, NULL, 10) + 1;
        else if (!strcmp(key, "alpha")) alpha = atof(val);
        else if (!strcmp(key, "omega")) omega = atof(val);
        else if (!strcmp(key, "k_end")) k_end = atof(val);
        else if (!strcmp(key, "c_end")) c_end = atof(val);
        else if (!strcmp(key, "scheme")) scheme = atoi(val);
        else if (!strcmp(key, "energy")) energy = atoi(val);
        else { fprintf(stderr, "chain_driver: unknown argument %s\n", key); return 2; }
    }
    if (n < 1 || n > MAX_N) {
        fprintf(stderr, "chain_driver: invalid value %zu for n (valid: 1 ... %d)\n", n, MAX_N);
        return 2;
    }
    for (int j = 0; j < 12; j++) {
        if (!given[j]) { for (size_t i = 0; i < n; i++) arr[j][i] = defaults[j]; continue; }
        if (!parse_list(given[j], arr[j], n)) {
            fprintf(stderr, "chain_driver: invalid list for %s\n", names[j]);
            return 2;
        }
    }
    const chain_params p = {n, arr[0], arr[1], arr[2], arr[3], arr[4], arr[5], arr[6], arr[7], arr[8], arr[9],
                            k_end, c_end, omega, h, alpha, scheme, energy, NULL, NULL, 0, NULL, NULL};
    char buf[200];
    const char *msg = chain_check_params(&p, buf, sizeof buf);
    if (msg) { fprintf(stderr, "chain_driver: %s\n", msg); return 2; }
    const chain_alloc al = {std_alloc, std_free, NULL};
    chain_model *M = chain_create(&p, &al, NULL);
    chain_state s;
    if (!M || !chain_state_init(M, &s)) { fprintf(stderr, "chain_driver: out of memory\n"); return 1; }
    const chain_inputs in = {given[10] ? arr[10] : NULL, given[11] ? arr[11] : NULL};
    chain_start(M, &in, 0.0, &s);
    if (dt <= 0.0) dt = h;
    unsigned long long rs = seed * 0x9E3779B97F4A7C15ull + 1;
    double t = 0.0;
    long long k = 0;
    for (;;) {
        printf("%.17g", s.t);
        for (size_t i = 0; i < n; i++) printf(",%.17g,%.17g,%.17g,%d", s.X[i], s.V[i], s.F[i], s.mode[i]);
        printf(",%.17g,%.17g,%.17g,%.17g,%lld,%lld,%lld\n", chain_energy(M, &s), s.W_applied, s.W_friction,
               s.D_damping, s.steps, s.pivot_steps, s.switches);
        if (t >= t_end) break;
        if (seed) {
            rs ^= rs << 13; rs ^= rs >> 7; rs ^= rs << 17;
            t += h * (0.1 + 2.9 * (double)(rs >> 11) * 0x1.0p-53);
        } else {
            t = (double)(++k) * dt;
        }
        if (t > t_end) t = t_end;
        const chain_status st = chain_advance(M, &in, &s, t, 0, NULL, NULL);
        if (st != CHAIN_OK) {
            fprintf(stderr, "chain_driver: %s at t = %g\n", chain_status_text(st), s.t);
            chain_state_free(M, &s);
            chain_destroy(M);
            return 1;
        }
    }
    chain_state_free(M, &s);
    chain_destroy(M);
    return 0;
}
