/* The TwoMass model's operators and its engine setup (two_mass.h). */
#include "two_mass.h"

#include "bossak.h"
#include "excitation.h" /* DFO_PI */

#include <math.h>
#include <stdio.h>
#include <string.h>

/* ---- operators: 2 x 2 dense ------------------------------------------------------------------- */

static void mul2(const double *A, const double *x, double *y)
{
    y[0] = A[0] * x[0] + A[1] * x[1];
    y[1] = A[2] * x[0] + A[3] * x[1];
}

static void op_K(void *ctx, const double *x, double *y) { mul2(((const tm_model *)ctx)->K, x, y); }
static void op_C(void *ctx, const double *v, double *y) { mul2(((const tm_model *)ctx)->C, v, y); }
static void op_M(void *ctx, const double *a, double *y) { mul2(((const tm_model *)ctx)->M, a, y); }

/* Cholesky of A = cM M + cC C + cK K into the slot; 0 when A is not positive definite. */
static int op_factor(void *ctx, int slot, double cM, double cC, double cK)
{
    tm_model *m = (tm_model *)ctx;
    double A[4];
    for (int i = 0; i < 4; i++) A[i] = cM * m->M[i] + cC * m->C[i] + cK * m->K[i];
    if (!(A[0] > 0.0)) return 0;
    const double l11 = sqrt(A[0]), l21 = A[2] / l11, d = A[3] - l21 * l21;
    if (!(d > 0.0)) return 0;
    m->L[slot][0] = l11;
    m->L[slot][1] = l21;
    m->L[slot][2] = sqrt(d);
    return 1;
}

static void op_solve(void *ctx, int slot, const double *b, double *x)
{
    const double *L = ((const tm_model *)ctx)->L[slot];
    const double y0 = b[0] / L[0], y1 = (b[1] - L[1] * y0) / L[2];
    x[1] = y1 / L[2];
    x[0] = (y0 - L[1] * x[1]) / L[0];
}

/* ---- parameters ------------------------------------------------------------------------------- */

const char *tm_check(const tm_params *p, char *buf, size_t len)
{
    const struct {
        const char *name;
        double v, lo, hi;
    } r[] = {{"m1", p->m1, 1e-100, 1e100},   {"m2", p->m2, 1e-100, 1e100},   {"k1", p->k1, 0.0, 1e100},
             {"k2", p->k2, 0.0, 1e100},      {"k12", p->k12, 0.0, 1e100},    {"c1", p->c1, 0.0, 1e100},
             {"c2", p->c2, 0.0, 1e100},      {"c12", p->c12, 0.0, 1e100},    {"P1", p->P1, -1e100, 1e100},
             {"P2", p->P2, -1e100, 1e100},   {"omega", p->omega, 0.0, 1e100}, {"phi", p->phi, -1e100, 1e100},
             {"N_g", p->N_g, 0.0, 1e100},    {"mu_s_g", p->mu_s_g, 0.0, 1e100}, {"mu_k_g", p->mu_k_g, 0.0, 1e100},
             {"N_c", p->N_c, 0.0, 1e100},    {"mu_s_c", p->mu_s_c, 0.0, 1e100}, {"mu_k_c", p->mu_k_c, 0.0, 1e100},
             {"x1_0", p->x1_0, -1e100, 1e100}, {"x2_0", p->x2_0, -1e100, 1e100}, {"v1_0", p->v1_0, -1e100, 1e100},
             {"v2_0", p->v2_0, -1e100, 1e100}, {"h", p->h, 0.0, 1e100},     {"alpha", p->alpha, -1.0 / 3.0, 0.0}};
    for (size_t i = 0; i < sizeof r / sizeof r[0]; i++)
        if (!(r[i].v >= r[i].lo && r[i].v <= r[i].hi)) {
            snprintf(buf, len, "invalid value %.17g for %s; valid range: %g to %g", r[i].v, r[i].name, r[i].lo,
                     r[i].hi);
            return buf;
        }
    if (p->scheme < DFO_SCHEME_PAPER || p->scheme > DFO_SCHEME_LOCATED) {
        snprintf(buf, len, "invalid scheme %d: the TwoMass model steps with paper (1), consistent (2) or located (3)",
                 p->scheme);
        return buf;
    }
    if (p->frictionUpdates < 0 || p->frictionUpdates > 10) {
        snprintf(buf, len, "invalid value %d for frictionUpdates; valid range: 0 to 10", p->frictionUpdates);
        return buf;
    }
    if (!(tm_rate_max(p) > 0.0)) {
        snprintf(buf, len, "the model has no time scale (k1 = k2 = k12 = 0, no damping, omega = 0): set h");
        if (!(p->h > 0.0)) return buf;
    }
    return NULL;
}

double tm_rate_max(const tm_params *p)
{
    /* M^-1 K = [[a, b], [c, d]]: its eigenvalues are real and >= 0 (K symmetric, M > 0) */
    const double a = (p->k1 + p->k12) / p->m1, b = -p->k12 / p->m1, c = -p->k12 / p->m2,
                 d = (p->k2 + p->k12) / p->m2;
    const double tr = a + d, disc = sqrt(fmax((a - d) * (a - d) + 4.0 * b * c, 0.0));
    const double cmax = fmax((p->c1 + p->c12) / p->m1, (p->c2 + p->c12) / p->m2);
    return sqrt(0.5 * (tr + disc)) + cmax + fabs(p->omega);
}

double tm_step(const tm_params *p) { return dfo_step_rule(p->h, 2.0 * DFO_PI / tm_rate_max(p)); }

/* ---- the engine ------------------------------------------------------------------------------- */

int tm_model_init(tm_model *m, const tm_params *p, const eng_alloc *al, char *buf, size_t len, const char **err)
{
    memset(m, 0, sizeof *m);
    *err = tm_check(p, buf, len);
    if (*err) return 0;
    m->p = *p;
    m->h = tm_step(p);
    m->M[0] = p->m1;
    m->M[3] = p->m2;
    m->K[0] = p->k1 + p->k12;
    m->K[1] = m->K[2] = -p->k12;
    m->K[3] = p->k2 + p->k12;
    m->C[0] = p->c1 + p->c12;
    m->C[1] = m->C[2] = -p->c12;
    m->C[3] = p->c2 + p->c12;
    m->idx_g[0] = 0;
    m->w_g[0] = 1.0;
    m->idx_c[0] = 0;
    m->idx_c[1] = 1;
    m->w_c[0] = 1.0;
    m->w_c[1] = -1.0;
    m->rows[0].nnz = 1;
    m->rows[0].idx = m->idx_g;
    m->rows[0].w = m->w_g;
    m->rows[1].nnz = 2;
    m->rows[1].idx = m->idx_c;
    m->rows[1].w = m->w_c;
    m->N[0] = p->N_g;
    m->N[1] = p->N_c;
    m->mu_s[0] = p->mu_s_g;
    m->mu_s[1] = p->mu_s_c;
    m->mu_k[0] = p->mu_k_g;
    m->mu_k[1] = p->mu_k_c;
    m->Pc[0] = p->P1;
    m->Pc[1] = p->P2;
    eng_setup S;
    memset(&S, 0, sizeof S);
    S.n = 2;
    S.nc = 2;
    S.ops.ctx = m;
    S.ops.apply_K = op_K;
    S.ops.apply_C = (p->c1 != 0.0 || p->c2 != 0.0 || p->c12 != 0.0) ? op_C : NULL;
    S.ops.apply_M = op_M;
    S.ops.factor = op_factor;
    S.ops.solve = op_solve;
    S.ops.friction = NULL; /* the engine's dense Delassus (2 x 2) and Lemke */
    S.rows = m->rows;
    S.exc.omega = p->omega;
    S.exc.phi0 = p->phi;
    S.exc.Pc = m->Pc;
    S.N = m->N;
    S.mu_s = m->mu_s;
    S.mu_k = m->mu_k;
    S.h = m->h;
    S.alpha = p->alpha;
    S.scheme = p->scheme;
    S.friction_updates = p->frictionUpdates;
    S.fast_paths = p->fastPaths;
    S.rate_max = tm_rate_max(p);
    S.margin_rounding = eng_dense_margin_rounding(2); /* (its dense 2 x 2 solves, as the structure's) */
    /* the oscillator's snap of a host's rounded times to the grid */
    S.snap_max_rel_h = 1e-5;
    S.snap_min_rel_h = 1e-7;
    S.snap_eps_t = 65536.0;
    m->E = eng_create(&S, al, err);
    if (!m->E) {
        if (!*err) *err = "out of memory";
        return 0;
    }
    return 1;
}

void tm_model_free(tm_model *m, const eng_alloc *al)
{
    (void)al;
    if (m->E) eng_destroy(m->E);
    m->E = NULL;
}
