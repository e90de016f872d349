/* A structure given by dense M, C, K (n <= NMAX) as the friction engine's operators (eng_ops): the
 * products, and a Cholesky factorisation per factor slot with its solve (the factorisations counted).
 * For the C tests that build an engine over a small structure of their own (test_engine.c,
 * test_engine_tangent.c, test_engine_dinv.c). NMAX: defined before the include, else 4. */
#ifndef DFO_TEST_DENSE_MODEL_H
#define DFO_TEST_DENSE_MODEL_H

#include "engine.h"

#include <math.h>
#include <stddef.h>

#ifndef NMAX
#define NMAX 4
#endif

typedef struct {
    size_t n;
    double M[NMAX * NMAX], C[NMAX * NMAX], K[NMAX * NMAX];
    double L[ENG_NSLOTS][NMAX * NMAX];
    long factors; /* factorisations done */
} dense;

static inline void mv(const dense *D, const double *A, const double *x, double *y)
{
    for (size_t i = 0; i < D->n; i++) {
        double s = 0.0;
        for (size_t k = 0; k < D->n; k++) s += A[i * D->n + k] * x[k];
        y[i] = s;
    }
}
static inline void op_K(void *c, const double *x, double *y) { mv(c, ((dense *)c)->K, x, y); }
static inline void op_C(void *c, const double *x, double *y) { mv(c, ((dense *)c)->C, x, y); }
static inline void op_M(void *c, const double *x, double *y) { mv(c, ((dense *)c)->M, x, y); }
static inline int op_factor(void *c, int slot, double cM, double cC, double cK)
{
    dense *D = c;
    const size_t n = D->n;
    double *L = D->L[slot];
    D->factors++;
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j <= i; j++) {
            double s = cM * D->M[i * n + j] + cC * D->C[i * n + j] + cK * D->K[i * n + j];
            for (size_t k = 0; k < j; k++) s -= L[i * n + k] * L[j * n + k];
            if (i == j) {
                if (!(s > 0.0)) return 0;
                L[i * n + i] = sqrt(s);
            } else {
                L[i * n + j] = s / L[j * n + j];
            }
        }
    return 1;
}
static inline void op_solve(void *c, int slot, const double *b, double *x)
{
    const dense *D = c;
    const size_t n = D->n;
    const double *L = D->L[slot];
    double y[NMAX];
    for (size_t i = 0; i < n; i++) {
        double s = b[i];
        for (size_t k = 0; k < i; k++) s -= L[i * n + k] * y[k];
        y[i] = s / L[i * n + i];
    }
    for (size_t i = n; i-- > 0;) {
        double s = y[i];
        for (size_t k = i + 1; k < n; k++) s -= L[k * n + i] * x[k];
        x[i] = s / L[i * n + i];
    }
}

/* the operators of D (ctx: D) into S */
static inline void dense_ops(dense *D, eng_setup *S)
{
    S->ops.ctx = D;
    S->ops.apply_K = op_K;
    S->ops.apply_C = op_C;
    S->ops.apply_M = op_M;
    S->ops.factor = op_factor;
    S->ops.solve = op_solve;
}

#endif
