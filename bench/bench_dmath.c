/* ns per call of the FMU's own elementary functions (fmu_src/dmath.c) and of the platform's libm on
 * the same arguments, in the ranges the schemes use:
 *   <build>/bench/bench_dmath [--reps 5]
 * Each row: a latency-free loop over 4096 arguments (the results summed, so nothing is folded away),
 * the minimum over the repetitions. No timing is asserted anywhere. */
#define _POSIX_C_SOURCE 199309L
#include "bench_clock.h"
#include "dmath.h"
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define N_ARGS 4096
#define N_LOOPS 200

typedef double (*fn1)(double);

static double sincos_sum(double x)
{
    double s, c;
    dfo_sincos(x, &s, &c);
    return s + c;
}
static double libm_sincos_sum(double x) { return sin(x) + cos(x); }

typedef struct {
    const char *name;
    fn1 mine, ref;
    double a, b;
} row;

static double time_fn(fn1 f, const double *x, double *sink)
{
    const double t0 = bench_now_ns();
    double acc = 0.0;
    for (int l = 0; l < N_LOOPS; l++)
        for (int i = 0; i < N_ARGS; i++) acc += f(x[i]);
    const double t1 = bench_now_ns();
    *sink += acc;
    return (t1 - t0) / ((double)N_LOOPS * N_ARGS);
}

int main(int argc, char **argv)
{
    int reps = 5;
    if (argc == 3 && strcmp(argv[1], "--reps") == 0) reps = atoi(argv[2]);
    if (reps < 1) {
        fprintf(stderr, "bench_dmath: --reps must be a positive integer\n");
        return 2;
    }
    static const row rows[] = {
        {"sin", dfo_sin, sin, -20.0, 20.0},
        {"cos", dfo_cos, cos, -20.0, 20.0},
        {"sincos", sincos_sum, libm_sincos_sum, -20.0, 20.0},
        {"sin", dfo_sin, sin, -1e5, 1e5},
        {"exp", dfo_exp, exp, -50.0, 5.0},
        {"expm1", dfo_expm1, expm1, -1.5, 1.5},
        {"acos", dfo_acos, acos, -1.0, 1.0},
    };
    static double x[N_ARGS];
    double sink = 0.0;
    printf("%-8s %-16s %10s %10s\n", "fn", "range", "dmath ns", "libm ns");
    for (size_t r = 0; r < sizeof rows / sizeof rows[0]; r++) {
        unsigned long long s = 0x9E3779B97F4A7C15ULL;
        for (int i = 0; i < N_ARGS; i++) {
            s = s * 6364136223846793005ULL + 1442695040888963407ULL;
            x[i] = rows[r].a + (rows[r].b - rows[r].a) * (double)(s >> 11) * 0x1p-53;
        }
        double best_m = 1e30, best_r = 1e30;
        for (int k = 0; k < reps; k++) {
            const double m = time_fn(rows[r].mine, x, &sink), l = time_fn(rows[r].ref, x, &sink);
            best_m = m < best_m ? m : best_m;
            best_r = l < best_r ? l : best_r;
        }
        char rg[32];
        snprintf(rg, sizeof rg, "%g .. %g", rows[r].a, rows[r].b);
        printf("%-8s %-16s %10.2f %10.2f\n", rows[r].name, rg, best_m, best_r);
    }
    return sink == 12345.678 ? 1 : 0;
}
