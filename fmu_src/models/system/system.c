/* The DryFrictionSystem model's operators, structure checks and engine setup (system.h). */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "system.h"

#include "bossak.h"
#include "excitation.h" /* DFO_PI */
#include "symeig.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define SYM_TOL 1e-12  /* M, C, K symmetric: |A_ij - A_ji| <= SYM_TOL max|A| */
#define PSD_TOL 1e-12  /* K, C: the Cholesky factorisation of A + PSD_TOL max|A| I must succeed */
#define POWER_ITERS 200
/* C is diagonal in the modal basis when its off-diagonal part E = offdiag(Phi' C Phi) is within
 * rounding of 0 as the solves see it. In modal coordinates M_hat = G + cC E, G = diag(cM + cC c_r +
 * cK lambda_r). For a step of length h' <= h, cM / cC = (1 - alpha) / (gamma h') >= 1.6 / h' >= 1 / h
 * (gamma = 1/2 - alpha, alpha in [-1/3, 0]) and lambda_r >= 0 (to rounding), so G_r >= cC (c_r + 1 / h)
 * and the dropped part's size relative to M_hat, ||G^-1/2 cC E G^-1/2||_2, is at most its largest row
 * sum
 *     rho = max_r sum_{s != r} |E_rs| / sqrt((c_r + 1/h) (c_s + 1/h))
 * (a symmetric matrix's 2-norm is at most its infinity norm), which bounds the relative change of a
 * solve by rho / (1 - rho). The modal backend takes C when rho <= SYS_MODAL_TOL = 1e-12: a change of
 * the solves of the order of the dense Cholesky's own rounding (n eps cond(M_hat): 2e-14 at n = 100,
 * 2e-13 at n = 1024 with cond 1). Rayleigh and modal damping computed in floating point give rho of
 * 1e-18 to 1e-15 (tests/c/test_system_modal.c prints it); a non-proportional C of any physical size
 * is far above (the dense backend). */
#define SYS_MODAL_TOL 1e-12
#define POWER_RTOL 1e-9

#define SPARSE_SHARE 8    /* a matrix with at most n^2 / SPARSE_SHARE nonzeros: its products in CSR */
#define DELASSUS_BATCH 4  /* Delassus entries summed side by side */

/* ---- dense algebra ------------------------------------------------------------------------------ */

static void matvec(size_t n, const double *A, const double *x, double *y)
{
    for (size_t i = 0; i < n; i++) {
        const double *a = A + i * n;
        double s = 0.0;
        for (size_t k = 0; k < n; k++) s += a[k] * x[k];
        y[i] = s;
    }
}

/* y = A x as matvec sums it (sys_matop: the same bits) */
static void matop_apply(size_t n, const sys_matop *A, const double *x, double *y)
{
    if (A->rp) {
        for (size_t i = 0; i < n; i++) {
            double s = 0.0;
            for (size_t p = A->rp[i]; p < A->rp[i + 1]; p++) s += A->v[p] * x[A->ci[p]];
            y[i] = s;
        }
        return;
    }
    for (size_t i = 0; i < n; i++) y[i] = 0.0;
    for (size_t k = 0; k < n; k++) {
        const double *col = A->v + k * n, xk = x[k];
        for (size_t i = 0; i < n; i++) y[i] += col[i] * xk;
    }
}

/* The lower Cholesky factor of the symmetric A (its lower triangle read) into L (n x n; the upper
 * triangle zeroed); shift added to the diagonal. Returns 0 when A + shift I is not positive definite
 * (*row: the 0-based row where the pivot fails). */
static int cholesky(size_t n, const double *A, double shift, double *L, size_t *row)
{
    for (size_t i = 0; i < n; i++) {
        double *li = L + i * n;
        for (size_t j = 0; j <= i; j++) {
            const double *lj = L + j * n;
            double s = A[i * n + j] + (i == j ? shift : 0.0);
            for (size_t k = 0; k < j; k++) s -= li[k] * lj[k];
            if (i == j) {
                if (!(s > 0.0) || !isfinite(s)) {
                    if (row) *row = i;
                    return 0;
                }
                li[i] = sqrt(s);
            } else {
                li[j] = s / lj[j];
            }
        }
        for (size_t j = i + 1; j < n; j++) li[j] = 0.0;
    }
    return 1;
}


/* y = L^-1 b (forward) or y = L^-T b (backward), in place. */
static void tri_forward(size_t n, const double *L, double *x)
{
    for (size_t i = 0; i < n; i++) {
        double s = x[i];
        for (size_t k = 0; k < i; k++) s -= L[i * n + k] * x[k];
        x[i] = s / L[i * n + i];
    }
}

static void tri_backward(size_t n, const double *L, double *x)
{
    for (size_t i = n; i-- > 0;) {
        double s = x[i];
        for (size_t k = i + 1; k < n; k++) s -= L[k * n + i] * x[k];
        x[i] = s / L[i * n + i];
    }
}

static double max_abs(size_t count, const double *a)
{
    double m = 0.0;
    for (size_t i = 0; i < count; i++) m = fmax(m, fabs(a[i]));
    return m;
}

/* The largest eigenvalue of M^-1 A (A symmetric positive semi-definite, L the Cholesky factor of M)
 * by power iteration on the symmetric L^-1 A L^-T: at most POWER_ITERS iterations, stopped when the
 * Rayleigh quotient changes by less than POWER_RTOL relatively (a lower estimate of the eigenvalue,
 * exact for n = 1). x, y: n each of scratch. */
static double largest_eig(size_t n, const double *L, const double *A, double *x, double *y)
{
    if (max_abs(n * n, A) == 0.0) return 0.0;
    for (size_t i = 0; i < n; i++) x[i] = 1.0 + 0.01 * (double)(i % 7); /* not orthogonal to a mode, in practice */
    double lam = 0.0;
    for (int it = 0; it < POWER_ITERS; it++) {
        double nx = 0.0;
        for (size_t i = 0; i < n; i++) nx += x[i] * x[i];
        nx = sqrt(nx);
        if (!(nx > 0.0)) return lam;
        for (size_t i = 0; i < n; i++) x[i] /= nx;
        memcpy(y, x, n * sizeof *y);
        tri_backward(n, L, y); /* y = L^-T x */
        matvec(n, A, y, x);    /* x = A y */
        memcpy(y, x, n * sizeof *y);
        tri_forward(n, L, y); /* y = L^-1 A L^-T x_old */
        /* Rayleigh quotient x_old . y: x holds A y; recompute from y and the normalised x_old */
        double q = 0.0, ny = 0.0;
        memcpy(x, y, n * sizeof *x);
        for (size_t i = 0; i < n; i++) ny += y[i] * y[i];
        q = sqrt(ny); /* ||B x_old|| with ||x_old|| = 1: converges to the largest eigenvalue of B >= 0 */
        const int done = it > 0 && fabs(q - lam) <= POWER_RTOL * q;
        lam = q;
        if (done) break;
    }
    return lam;
}

/* ---- checks ------------------------------------------------------------------------------------- */

static int finite_all(const char *name, const double *a, size_t rows, size_t cols, char *buf, size_t len)
{
    for (size_t i = 0; i < rows; i++)
        for (size_t j = 0; j < cols; j++)
            if (!isfinite(a[i * cols + j])) {
                if (cols > 1 || rows > 1) {
                    if (rows > 1 && cols > 1)
                        snprintf(buf, len, "%s[%zu,%zu] is not a finite number", name, i + 1, j + 1);
                    else
                        snprintf(buf, len, "%s[%zu] is not a finite number", name, i * cols + j + 1);
                } else {
                    snprintf(buf, len, "%s[1] is not a finite number", name);
                }
                return 0;
            }
    return 1;
}

static int symmetric(const char *name, size_t n, const double *A, char *buf, size_t len)
{
    const double tol = SYM_TOL * max_abs(n * n, A);
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < i; j++)
            if (!(fabs(A[i * n + j] - A[j * n + i]) <= tol)) {
                snprintf(buf, len, "%s is not symmetric: %s[%zu,%zu] = %.17g but %s[%zu,%zu] = %.17g", name, name, i + 1,
                         j + 1, A[i * n + j], name, j + 1, i + 1, A[j * n + i]);
                return 0;
            }
    return 1;
}

static int nonneg(const char *name, const double *a, size_t nc, char *buf, size_t len)
{
    for (size_t j = 0; j < nc; j++)
        if (!(a[j] >= 0.0)) {
            snprintf(buf, len, "%s[%zu] = %.17g is negative; valid range: >= 0", name, j + 1, a[j]);
            return 0;
        }
    return 1;
}

static const char *check_with(const sys_params *p, double *L, char *buf, size_t len)
{
    const size_t n = p->n, nc = p->nc;
    if (n < 1 || n > 1024) {
        snprintf(buf, len, "invalid size n = %zu; valid range: 1 to 1024", n);
        return buf;
    }
    if (nc > 1024) {
        snprintf(buf, len, "invalid size nc = %zu; valid range: 0 to 1024", nc);
        return buf;
    }
    const struct {
        const char *name;
        const double *a;
        size_t rows, cols;
    } arr[] = {{"M", p->M, n, n},         {"C", p->C, n, n},       {"K", p->K, n, n},   {"F_c", p->F_c, 1, n},
               {"F_s", p->F_s, 1, n},     {"x0", p->x0, 1, n},     {"v0", p->v0, 1, n}, {"W", p->W, nc, n},
               {"N", p->N, 1, nc},        {"mu_s", p->mu_s, 1, nc}, {"mu_k", p->mu_k, 1, nc}, {"k_t", p->k_t, 1, nc}};
    for (size_t a = 0; a < sizeof arr / sizeof arr[0]; a++) {
        if (arr[a].rows == 0 || arr[a].cols == 0) continue;
        if (!finite_all(arr[a].name, arr[a].a, arr[a].rows, arr[a].cols, buf, len)) return buf;
    }
    const struct {
        const char *name;
        double v, lo, hi;
    } r[] = {{"omega", p->omega, 0.0, 1e100}, {"h", p->h, 0.0, 1e100}, {"alpha", p->alpha, -1.0 / 3.0, 0.0}};
    for (size_t i = 0; i < sizeof r / sizeof r[0]; i++)
        if (!(r[i].v >= r[i].lo && r[i].v <= r[i].hi)) {
            snprintf(buf, len, "invalid value %.17g for %s; valid range: %g to %g", r[i].v, r[i].name, r[i].lo, r[i].hi);
            return buf;
        }
    if (p->scheme < DFO_SCHEME_PAPER || p->scheme > DFO_SCHEME_LOCATED) {
        snprintf(buf, len, "invalid scheme %d: the DryFrictionSystem model steps with paper (1), consistent (2) or "
                 "located (3)", p->scheme);
        return buf;
    }
    if (p->frictionUpdates < 0 || p->frictionUpdates > 10) {
        snprintf(buf, len, "invalid value %d for frictionUpdates; valid range: 0 to 10", p->frictionUpdates);
        return buf;
    }
    if (!symmetric("M", n, p->M, buf, len) || !symmetric("K", n, p->K, buf, len) || !symmetric("C", n, p->C, buf, len))
        return buf;
    size_t row = 0;
    if (!cholesky(n, p->M, 0.0, L, &row)) {
        snprintf(buf, len, "M is not positive definite (its Cholesky factorisation fails at row %zu)", row + 1);
        return buf;
    }
    const double kmax = max_abs(n * n, p->K), cmax = max_abs(n * n, p->C);
    if (kmax > 0.0 && !cholesky(n, p->K, PSD_TOL * kmax, L, &row)) {
        snprintf(buf, len, "K has a negative eigenvalue beyond rounding (K + %g max|K| I is not positive definite)",
                 PSD_TOL);
        return buf;
    }
    if (cmax > 0.0 && !cholesky(n, p->C, PSD_TOL * cmax, L, &row)) {
        snprintf(buf, len, "C has a negative eigenvalue beyond rounding (C + %g max|C| I is not positive definite)",
                 PSD_TOL);
        return buf;
    }
    for (size_t j = 0; j < nc; j++) {
        if (max_abs(n, p->W + j * n) == 0.0) {
            snprintf(buf, len, "W row %zu is zero: contact %zu acts on no degree of freedom", j + 1, j + 1);
            return buf;
        }
    }
    if (!nonneg("N", p->N, nc, buf, len) || !nonneg("mu_s", p->mu_s, nc, buf, len) ||
        !nonneg("mu_k", p->mu_k, nc, buf, len) || !nonneg("k_t", p->k_t, nc, buf, len))
        return buf;
    for (size_t j = 0; p->law && j < nc; j++) {
        if (p->law[j] != DFO_LAW_COULOMB && p->law[j] != DFO_LAW_STRIBECK) {
            snprintf(buf, len, "invalid value %g for friction_law[%zu] (valid: 1 coulomb, 2 stribeck)", p->law[j], j + 1);
            return buf;
        }
        if (p->law[j] != DFO_LAW_STRIBECK) continue;
        if (!(p->v_s[j] > 0.0 && isfinite(p->v_s[j]))) {
            snprintf(buf, len, "v_s[%zu] = %.17g is not > 0: contact %zu's Stribeck velocity", j + 1, p->v_s[j], j + 1);
            return buf;
        }
        if (!(p->delta[j] >= 1.0 && isfinite(p->delta[j]))) {
            snprintf(buf, len, "friction_law = stribeck supports delta >= 1 only, not %g for delta[%zu] (below 1 the "
                     "friction's slope is infinite at zero slip speed)", p->delta[j], j + 1);
            return buf;
        }
        if (p->scheme != DFO_SCHEME_LOCATED) {
            snprintf(buf, len, "friction_law[%zu] = stribeck needs scheme located (the speed-dependent friction is "
                     "solved inside its steps), as the oscillator and the chain: choose scheme located, or "
                     "friction_law[%zu] = coulomb", j + 1, j + 1);
            return buf;
        }
        if (p->k_t[j] > 0.0) {
            snprintf(buf, len, "contact %zu is a Jenkins element (k_t[%zu] = %g > 0), which takes the Coulomb law only: "
                     "set friction_law[%zu] = coulomb (1) or k_t[%zu] = 0", j + 1, j + 1, p->k_t[j], j + 1, j + 1);
            return buf;
        }
        if (p->sensitivity) {
            snprintf(buf, len, "sensitivity = true propagates the map's Jacobian with the Coulomb law only, and "
                     "friction_law[%zu] = stribeck: set friction_law[%zu] = coulomb (1) or sensitivity = false", j + 1,
                     j + 1);
            return buf;
        }
    }
    if (p->sensitivity && p->scheme != DFO_SCHEME_LOCATED) {
        snprintf(buf, len, "sensitivity = true propagates the located scheme's Jacobian only, and scheme = %d: set "
                 "scheme = located (3) or sensitivity = false", p->scheme);
        return buf;
    }
    for (size_t j = 0; p->slide0 && j < nc; j++)
        if (p->k_t[j] > 0.0 && p->slide0[j] != -1.0 && p->slide0[j] != 0.0 && p->slide0[j] != 1.0) {
            snprintf(buf, len, "invalid value %g for slide0[%zu] (valid: -1, 0 or +1)", p->slide0[j], j + 1);
            return buf;
        }
    for (size_t j = 0; p->f0 && j < nc; j++) {
        if (!(p->k_t[j] > 0.0) || (p->slide0 && p->slide0[j] != 0.0)) continue; /* (not read: rigid, or sliding) */
        const double Fb = fmax(p->mu_s[j], p->mu_k[j]) * p->N[j];
        if (!(fabs(p->f0[j]) <= Fb * (1.0 + 1e-12))) { /* (a force on the limit, rounded a hair beyond) */
            snprintf(buf, len, "f0[%zu] = %.17g is beyond contact %zu's breakaway limit: valid range |f0[%zu]| <= "
                     "max(mu_s, mu_k) N = %.17g (its slider starts stuck)", j + 1, p->f0[j], j + 1, j + 1, Fb);
            return buf;
        }
    }
    return NULL;
}

const char *sys_check(const sys_params *p, const eng_alloc *al, char *buf, size_t len)
{
    if (p->n < 1 || p->n > 1024) return check_with(p, NULL, buf, len); /* (a size sentence, L unused) */
    double *L = (double *)al->allocate(al->env, p->n * p->n, sizeof(double));
    if (!L) return "out of memory";
    const char *why = check_with(p, L, buf, len);
    al->release(al->env, L);
    return why;
}

/* Whether some contact of p is a Jenkins element (k_t > 0). */
static int any_jenkins(const sys_params *p)
{
    for (size_t j = 0; j < p->nc; j++)
        if (p->k_t[j] > 0.0) return 1;
    return 0;
}

/* The fastest rate with L the Cholesky factor of M (x, y: n scratch each; Kt: n x n scratch, read
 * only with Jenkins contacts: the stiffness with every slider stuck, K + sum k_t w w'). */
static double rate_with(const sys_params *p, const double *L, double *x, double *y, double *Kt)
{
    const size_t n = p->n;
    const double *K = p->K;
    if (Kt && any_jenkins(p)) {
        memcpy(Kt, p->K, n * n * sizeof(double));
        for (size_t j = 0; j < p->nc; j++)
            for (size_t a = 0; a < n; a++)
                for (size_t b = 0; b < n; b++) Kt[a * n + b] += p->k_t[j] * p->W[j * n + a] * p->W[j * n + b];
        K = Kt;
    }
    if (n == 1) /* the eigenvalues in closed form (the oscillator's rate, to its bits) */
        return sqrt(K[0] / p->M[0]) + p->C[0] / p->M[0] + fabs(p->omega);
    const double lk = largest_eig(n, L, K, x, y), lc = largest_eig(n, L, p->C, x, y);
    return sqrt(lk) + lc + fabs(p->omega);
}

double sys_step(const sys_params *p, const eng_alloc *al)
{
    if (p->h > 0.0) return p->h;
    const size_t n = p->n;
    double *L = (double *)al->allocate(al->env, 2 * n * n + 2 * n, sizeof(double));
    if (!L) return NAN;
    double h = NAN;
    if (cholesky(n, p->M, 0.0, L, NULL)) /* (no time scale, rate 0: the rule's fallback, 1 ms) */
        h = dfo_step_rule(0.0, 2.0 * DFO_PI / rate_with(p, L, L + n * n, L + n * n + n, L + n * n + 2 * n));
    al->release(al->env, L);
    return h;
}

/* ---- operators ---------------------------------------------------------------------------------- */

static void op_K(void *ctx, const double *x, double *y) { const sys_model *m = (const sys_model *)ctx; matop_apply(m->n, &m->opK, x, y); }
static void op_C(void *ctx, const double *v, double *y) { const sys_model *m = (const sys_model *)ctx; matop_apply(m->n, &m->opC, v, y); }
static void op_M(void *ctx, const double *a, double *y) { const sys_model *m = (const sys_model *)ctx; matop_apply(m->n, &m->opM, a, y); }

/* Cholesky of A = cM M + cC C + cK K into the slot (the lower triangle formed); 0 when A is not
 * positive definite. */
static int op_factor(void *ctx, int slot, double cM, double cC, double cK)
{
    sys_model *m = (sys_model *)ctx;
    const size_t n = m->n;
    if (m->modal) { /* d_r = 1 / (cM + cC c_r + cK lambda_r): positive, as the Cholesky pivots */
        double *d = m->dm[slot];
        for (size_t r = 0; r < n; r++) {
            const double g = (cM + cC * m->cdiag[r]) + cK * m->lam[r];
            if (!(g > 0.0) || !isfinite(g)) return 0;
            d[r] = 1.0 / g;
        }
        if (++m->gen[slot] == 0 && m->Dstamp[slot]) { /* (the stamps wrapped: forget every entry) */
            memset(m->Dstamp[slot], 0, m->nc * m->nc * sizeof(unsigned));
            m->gen[slot] = 1;
        }
        return 1;
    }
    double *L = m->L[slot];
    /* A's lower triangle in place in L (cholesky reads A[i n + j], j <= i, before writing L[i n + j]) */
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j <= i; j++) {
            const size_t k = i * n + j;
            L[k] = cM * m->M[k] + cC * m->C[k] + cK * m->K[k];
        }
    if (!cholesky(n, L, 0.0, L, NULL)) return 0;
    double *Lt = m->Lt[slot];
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < n; j++) Lt[j * n + i] = L[i * n + j];
    return 1;
}

/* x = (L L')^-1 b (b and x may be the same array), Lt = L': the forward substitution by columns
 * (x_i = (b_i - L_i0 x_0 - L_i1 x_1 - ...) / L_ii, each x_i's subtractions in that order, the rows
 * side by side), the backward by rows of L' (contiguous). */
static void chol_solve_t(size_t n, const double *Lt, const double *b, double *x)
{
    if (x != b) memcpy(x, b, n * sizeof *x);
    for (size_t k = 0; k < n; k++) {
        const double *col = Lt + k * n;
        const double xk = x[k] / col[k];
        x[k] = xk;
        for (size_t i = k + 1; i < n; i++) x[i] -= col[i] * xk;
    }
    for (size_t i = n; i-- > 0;) {
        const double *row = Lt + i * n;
        double s = x[i];
        for (size_t k = i + 1; k < n; k++) s -= row[k] * x[k];
        x[i] = s / row[i];
    }
}

/* x = Phi (d .* (Phi' b)) (b and x may be the same array) */
static void modal_solve(const sys_model *m, const double *d, const double *b, double *x)
{
    const size_t n = m->n;
    double *z = m->z;
    /* z_r = d_r (phi_r . b), each dot product summed over i ascending (Phi's rows added into z) */
    for (size_t r = 0; r < n; r++) z[r] = 0.0;
    for (size_t i = 0; i < n; i++) {
        const double *p = m->Phi + i * n, bi = b[i];
        for (size_t r = 0; r < n; r++) z[r] += p[r] * bi;
    }
    for (size_t r = 0; r < n; r++) z[r] = d[r] * z[r];
    for (size_t i = 0; i < n; i++) x[i] = 0.0;
    for (size_t r = 0; r < n; r++) {
        const double *p = m->PhiT + r * n;
        const double zr = z[r];
        for (size_t i = 0; i < n; i++) x[i] += zr * p[i];
    }
}

static void op_solve(void *ctx, int slot, const double *b, double *x)
{
    const sys_model *m = (const sys_model *)ctx;
    if (m->modal) {
        modal_solve(m, m->dm[slot], b, x);
        return;
    }
    chol_solve_t(m->n, m->Lt[slot], b, x);
}

/* The Delassus entries (lo[q], hi[q]) of the slot, q <= DELASSUS_BATCH: sum_r (U_lo,r d_r) U_hi,r, r
 * ascending, the q sums side by side (independent chains: each in its own order, the same bits). */
static void delassus_entries(sys_model *m, int slot, const size_t *lo, const size_t *hi, size_t q)
{
    const size_t n = m->n, nc = m->nc;
    const double *d = m->dm[slot];
    double *Dc = m->Dc[slot];
    if (q == DELASSUS_BATCH) {
        const double *l0 = m->U + lo[0] * n, *l1 = m->U + lo[1] * n, *l2 = m->U + lo[2] * n, *l3 = m->U + lo[3] * n;
        const double *h0 = m->U + hi[0] * n, *h1 = m->U + hi[1] * n, *h2 = m->U + hi[2] * n, *h3 = m->U + hi[3] * n;
        double v0 = 0.0, v1 = 0.0, v2 = 0.0, v3 = 0.0;
        for (size_t r = 0; r < n; r++) {
            const double dr = d[r];
            v0 += (l0[r] * dr) * h0[r];
            v1 += (l1[r] * dr) * h1[r];
            v2 += (l2[r] * dr) * h2[r];
            v3 += (l3[r] * dr) * h3[r];
        }
        Dc[hi[0] * nc + lo[0]] = v0;
        Dc[hi[1] * nc + lo[1]] = v1;
        Dc[hi[2] * nc + lo[2]] = v2;
        Dc[hi[3] * nc + lo[3]] = v3;
        return;
    }
    for (size_t c = 0; c < q; c++) {
        const double *ul = m->U + lo[c] * n, *uh = m->U + hi[c] * n;
        double v = 0.0;
        for (size_t r = 0; r < n; r++) v += (ul[r] * d[r]) * uh[r];
        Dc[hi[c] * nc + lo[c]] = v;
    }
}

/* eng_coupling.delassus: D_ab = sum_r U_ja d_r U_jb (j_a = sel[a]), each entry computed once per
 * factorisation of the slot (the pair's lower index first: the same bits whichever order asks) */
static void op_delassus(void *ctx, int slot, const int *sel, size_t k, double *D)
{
    sys_model *m = (sys_model *)ctx;
    const size_t nc = m->nc;
    double *Dc = m->Dc[slot];
    unsigned *st = m->Dstamp[slot];
    const unsigned gen = m->gen[slot];
    size_t lo4[DELASSUS_BATCH] = {0}, hi4[DELASSUS_BATCH] = {0}, q = 0;
    for (size_t a = 0; a < k; a++) /* the entries not yet computed, DELASSUS_BATCH at a time */
        for (size_t b = 0; b <= a; b++) {
            const size_t ja = (size_t)sel[a], jb = (size_t)sel[b];
            const size_t lo = ja < jb ? ja : jb, hi = ja < jb ? jb : ja, e = hi * nc + lo;
            if (st[e] == gen) continue;
            st[e] = gen;
            lo4[q] = lo;
            hi4[q++] = hi;
            if (q == DELASSUS_BATCH) {
                delassus_entries(m, slot, lo4, hi4, q);
                q = 0;
            }
        }
    if (q) delassus_entries(m, slot, lo4, hi4, q);
    for (size_t a = 0; a < k; a++)
        for (size_t b = 0; b <= a; b++) {
            const size_t ja = (size_t)sel[a], jb = (size_t)sel[b];
            const size_t lo = ja < jb ? ja : jb, hi = ja < jb ? jb : ja;
            D[a * k + b] = D[b * k + a] = Dc[hi * nc + lo];
        }
}

/* eng_coupling.respond: y += Phi (d .* (U_S' f)) */
static void op_respond(void *ctx, int slot, const int *sel, size_t k, const double *f, double *y)
{
    sys_model *m = (sys_model *)ctx;
    const size_t n = m->n;
    const double *d = m->dm[slot];
    double *z = m->z;
    for (size_t r = 0; r < n; r++) z[r] = 0.0;
    for (size_t a = 0; a < k; a++) {
        const double *u = m->U + (size_t)sel[a] * n;
        const double fa = f[a];
        for (size_t r = 0; r < n; r++) z[r] += fa * u[r];
    }
    for (size_t r = 0; r < n; r++) {
        const double *p = m->PhiT + r * n;
        const double zr = z[r] * d[r];
        for (size_t i = 0; i < n; i++) y[i] += zr * p[i];
    }
}

/* ---- the engine --------------------------------------------------------------------------------- */

void sys_model_free(sys_model *m, const eng_alloc *al)
{
    if (m->E) eng_destroy(m->E);
    m->E = NULL;
    void *arrays[] = {m->M, m->C, m->K, m->L[0], m->L[1], m->L[2], m->Lt[0], m->Lt[1], m->Lt[2], m->Pc, m->Ps,
                      m->N, m->mu_s, m->mu_k, m->k_t, m->rows, m->idx, m->w, m->work, m->law, m->PhiT, m->Phi,
                      m->lam, m->cdiag, m->dm[0], m->dm[1], m->dm[2], m->U, m->z, m->Dc[0], m->Dc[1], m->Dc[2],
                      m->Dstamp[0], m->Dstamp[1], m->Dstamp[2], m->opM.rp, m->opM.ci, m->opM.v, m->opC.rp,
                      m->opC.ci, m->opC.v, m->opK.rp, m->opK.ci, m->opK.v};
    for (size_t i = 0; i < sizeof arrays / sizeof arrays[0]; i++)
        if (arrays[i]) al->release(al->env, arrays[i]);
    memset(m, 0, sizeof *m);
}

static void *alloc_n(const eng_alloc *al, size_t count, size_t size, int *ok)
{
    void *p = al->allocate(al->env, count ? count : 1, size);
    if (!p) *ok = 0;
    return p;
}

/* The product of the n x n A (sys_matop): CSR where it has at most n^2 / SPARSE_SHARE nonzeros,
 * else its transpose. *ok = 0 when memory fails. */
static void matop_make(sys_matop *op, const eng_alloc *al, size_t n, const double *A, int *ok)
{
    size_t nnz = 0;
    for (size_t k = 0; k < n * n; k++) nnz += A[k] != 0.0;
    if (nnz * SPARSE_SHARE <= n * n) {
        op->rp = (size_t *)alloc_n(al, n + 1, sizeof(size_t), ok);
        op->ci = (size_t *)alloc_n(al, nnz, sizeof(size_t), ok);
        op->v = (double *)alloc_n(al, nnz, sizeof(double), ok);
        if (!*ok) return;
        size_t p = 0;
        for (size_t i = 0; i < n; i++) {
            op->rp[i] = p;
            for (size_t k = 0; k < n; k++)
                if (A[i * n + k] != 0.0) {
                    op->ci[p] = k;
                    op->v[p++] = A[i * n + k];
                }
        }
        op->rp[n] = p;
        return;
    }
    op->v = (double *)alloc_n(al, n * n, sizeof(double), ok);
    if (!*ok) return;
    for (size_t i = 0; i < n; i++)
        for (size_t k = 0; k < n; k++) op->v[k * n + i] = A[i * n + k];
}

/* The modal backend where C allows it (the model's M, C, K, rows and h set): the modes, C's test
 * (SYS_MODAL_TOL), the per-slot and coupling arrays; m->modal = 1 when taken. 0 when memory fails. */
static int modal_setup(sys_model *m, const sys_params *p, const eng_alloc *al)
{
    const size_t n = m->n, nc = m->nc;
    m->c_offdiag = NAN;
    if (n < 2 || p->dense) return 1; /* (n = 1: the 1 x 1 Cholesky, the oscillator's bits) */
    int ok = 1;
    double *tmp = (double *)alloc_n(al, dfo_symeig_work(n), sizeof(double), &ok);
    m->PhiT = (double *)alloc_n(al, n * n, sizeof(double), &ok);
    m->lam = (double *)alloc_n(al, n, sizeof(double), &ok);
    m->cdiag = (double *)alloc_n(al, n, sizeof(double), &ok);
    if (!ok) {
        if (tmp) al->release(al->env, tmp);
        return 0;
    }
    m->Phi = (double *)alloc_n(al, n * n, sizeof(double), &ok);
    if (!ok) {
        al->release(al->env, tmp);
        return 0;
    }
    int modal = dfo_symeig(n, m->K, m->M, m->lam, m->PhiT, tmp);
    if (modal && m->has_C) { /* Ct = Phi' C Phi: G (rows C phi_s), then Ct_rs = phi_r . G_s */
        double *G = tmp, *Ct = tmp + n * n;
        for (size_t r = 0; r < n; r++) matvec(n, m->C, m->PhiT + r * n, G + r * n);
        for (size_t r = 0; r < n; r++)
            for (size_t c = 0; c < n; c++) {
                const double *a = m->PhiT + r * n, *g = G + c * n;
                double v = 0.0;
                for (size_t i = 0; i < n; i++) v += a[i] * g[i];
                Ct[r * n + c] = v;
            }
        const double sig = 1.0 / m->h;
        double rho = 0.0;
        for (size_t r = 0; r < n; r++) {
            m->cdiag[r] = Ct[r * n + r];
            double row = 0.0;
            const double cr = fmax(Ct[r * n + r], 0.0) + sig;
            for (size_t c = 0; c < n; c++)
                if (c != r) row += fabs(Ct[r * n + c]) / sqrt(cr * (fmax(Ct[c * n + c], 0.0) + sig));
            rho = fmax(rho, row);
        }
        m->c_offdiag = rho;
        modal = rho <= SYS_MODAL_TOL;
    } else if (modal) {
        m->c_offdiag = 0.0;
    }
    al->release(al->env, tmp);
    if (!modal) { /* the dense backend */
        void *arrays[] = {m->PhiT, m->Phi, m->lam, m->cdiag};
        for (size_t i = 0; i < 4; i++) al->release(al->env, arrays[i]);
        m->PhiT = m->Phi = m->lam = m->cdiag = NULL;
        return 1;
    }
    for (size_t r = 0; r < n; r++)
        for (size_t i = 0; i < n; i++) m->Phi[i * n + r] = m->PhiT[r * n + i];
    for (int sl = 0; sl < ENG_NSLOTS; sl++) {
        m->dm[sl] = (double *)alloc_n(al, n, sizeof(double), &ok);
        if (sl != ENG_SLOT_TRIAL) continue; /* (the coupling operators serve the trial slot only) */
        m->Dc[sl] = (double *)alloc_n(al, nc * nc, sizeof(double), &ok);
        m->Dstamp[sl] = (unsigned *)alloc_n(al, nc * nc, sizeof(unsigned), &ok);
    }
    m->U = (double *)alloc_n(al, nc * n, sizeof(double), &ok);
    m->z = (double *)alloc_n(al, n, sizeof(double), &ok);
    if (!ok) return 0;
    for (size_t j = 0; j < nc; j++) /* U_jr = w_j . phi_r */
        for (size_t r = 0; r < n; r++) {
            double v = 0.0;
            for (size_t k = 0; k < m->rows[j].nnz; k++) v += m->rows[j].w[k] * m->PhiT[r * n + m->rows[j].idx[k]];
            m->U[j * n + r] = v;
        }
    for (int sl = 0; sl < ENG_NSLOTS; sl++) { /* (the Cholesky factors are not needed) */
        al->release(al->env, m->L[sl]);
        al->release(al->env, m->Lt[sl]);
        m->L[sl] = m->Lt[sl] = NULL;
    }
    m->modal = 1;
    return 1;
}

int sys_model_init(sys_model *m, const sys_params *p, const eng_alloc *al, int account_energy, char *buf, size_t len,
                   const char **err)
{
    memset(m, 0, sizeof *m);
    *err = sys_check(p, al, buf, len);
    if (*err) return 0;
    const size_t n = p->n, nc = p->nc;
    size_t nnz = 0;
    for (size_t k = 0; k < nc * n; k++) nnz += p->W[k] != 0.0;
    int ok = 1, has_Fs = 0;
    for (size_t i = 0; i < n; i++) has_Fs |= p->F_s[i] != 0.0;
    m->n = n;
    m->nc = nc;
    m->M = (double *)alloc_n(al, n * n, sizeof(double), &ok);
    m->C = (double *)alloc_n(al, n * n, sizeof(double), &ok);
    m->K = (double *)alloc_n(al, n * n, sizeof(double), &ok);
    for (int s = 0; s < ENG_NSLOTS; s++) {
        m->L[s] = (double *)alloc_n(al, n * n, sizeof(double), &ok);
        m->Lt[s] = (double *)alloc_n(al, n * n, sizeof(double), &ok);
    }
    m->Pc = (double *)alloc_n(al, n, sizeof(double), &ok);
    if (has_Fs) m->Ps = (double *)alloc_n(al, n, sizeof(double), &ok);
    m->N = (double *)alloc_n(al, nc, sizeof(double), &ok);
    m->mu_s = (double *)alloc_n(al, nc, sizeof(double), &ok);
    m->mu_k = (double *)alloc_n(al, nc, sizeof(double), &ok);
    m->k_t = (double *)alloc_n(al, nc, sizeof(double), &ok);
    m->rows = (eng_row *)alloc_n(al, nc, sizeof(eng_row), &ok);
    m->idx = (size_t *)alloc_n(al, nnz, sizeof(size_t), &ok);
    m->w = (double *)alloc_n(al, nnz, sizeof(double), &ok);
    m->work = (double *)alloc_n(al, 2 * n, sizeof(double), &ok);
    int stribeck = 0;
    for (size_t j = 0; p->law && j < nc; j++) stribeck |= p->law[j] == DFO_LAW_STRIBECK;
    if (stribeck) m->law = (dfo_friction_law *)alloc_n(al, nc, sizeof(dfo_friction_law), &ok);
    if (!ok) {
        sys_model_free(m, al);
        *err = "out of memory";
        return 0;
    }
    memcpy(m->M, p->M, n * n * sizeof(double));
    memcpy(m->C, p->C, n * n * sizeof(double));
    memcpy(m->K, p->K, n * n * sizeof(double));
    m->has_C = max_abs(n * n, p->C) > 0.0;
    matop_make(&m->opM, al, n, p->M, &ok);
    matop_make(&m->opK, al, n, p->K, &ok);
    if (m->has_C) matop_make(&m->opC, al, n, p->C, &ok);
    if (!ok) {
        sys_model_free(m, al);
        *err = "out of memory";
        return 0;
    }
    memcpy(m->Pc, p->F_c, n * sizeof(double));
    if (m->Ps)
        for (size_t i = 0; i < n; i++) m->Ps[i] = -p->F_s[i]; /* the engine's P = Pc cos - Ps sin */
    if (nc) {
        memcpy(m->N, p->N, nc * sizeof(double));
        memcpy(m->mu_s, p->mu_s, nc * sizeof(double));
        memcpy(m->mu_k, p->mu_k, nc * sizeof(double));
        memcpy(m->k_t, p->k_t, nc * sizeof(double));
    }
    m->jenkins = any_jenkins(p);
    for (size_t j = 0; m->law && j < nc; j++) {
        dfo_friction_law *F = &m->law[j];
        F->law = p->law[j] == DFO_LAW_STRIBECK ? DFO_LAW_STRIBECK : DFO_LAW_COULOMB;
        F->mu_s = p->mu_s[j];
        F->mu_k = p->mu_k[j];
        F->v_s = p->v_s[j];
        F->delta = p->delta[j];
    }
    size_t k = 0;
    for (size_t j = 0; j < nc; j++) {
        m->rows[j].idx = m->idx + k;
        m->rows[j].w = m->w + k;
        size_t c = 0;
        for (size_t i = 0; i < n; i++)
            if (p->W[j * n + i] != 0.0) {
                m->idx[k + c] = i;
                m->w[k + c] = p->W[j * n + i];
                c++;
            }
        m->rows[j].nnz = c;
        k += c;
    }
    (void)cholesky(n, p->M, 0.0, m->L[ENG_SLOT_MASS], NULL); /* (passed sys_check) */
    /* (the stiffness with the sliders stuck in a factor slot's storage, before its first factorisation) */
    m->rate = rate_with(p, m->L[ENG_SLOT_MASS], m->work, m->work + n, m->L[ENG_SLOT_GRID]);
    m->h = dfo_step_rule(p->h, 2.0 * DFO_PI / m->rate); /* (no time scale, rate 0: the rule's fallback, 1 ms) */
    if (!modal_setup(m, p, al)) {
        sys_model_free(m, al);
        *err = "out of memory";
        return 0;
    }
    eng_setup S;
    memset(&S, 0, sizeof S);
    S.n = n;
    S.nc = nc;
    S.ops.ctx = m;
    S.ops.apply_K = op_K;
    S.ops.apply_C = m->has_C ? op_C : NULL;
    S.ops.apply_M = op_M;
    S.ops.factor = op_factor;
    S.ops.solve = op_solve;
    S.ops.friction = NULL; /* the engine's dense Delassus matrix and Lemke */
    S.rows = m->rows;
    /* (the Jacobian needs the engine's own solver: the general operators) */
    m->one_dof = n == 1 && nc == 1 && p->W[0] == 1.0 && !(p->k_t[0] > 0.0) && !p->sensitivity;
    if (m->one_dof) { /* the oscillator's structure: the engine's one-DOF operators (eng_one_dof.h) */
        eng1_init(&m->one, p->M[0], p->C[0], p->K[0], p->N[0], p->mu_s[0], p->mu_k[0], m->law, p->F_c[0]);
        const eng_ops ops = {&m->one, eng1_K, m->has_C ? eng1_C : NULL, eng1_M, eng1_factor, eng1_solve,
                             eng1_friction, eng1_breakaway, 1};
        S.ops = ops;
        S.rows = &m->one.row;
    }
    S.exc.omega = p->omega;
    S.exc.phi0 = 0.0;
    S.exc.Pc = m->Pc;
    S.exc.Ps = m->Ps;
    S.N = m->N;
    S.mu_s = m->mu_s;
    S.mu_k = m->mu_k;
    S.k_t = m->jenkins ? m->k_t : NULL; /* (all rigid: NULL, the rigid paths as they were) */
    S.law = m->law;                     /* (all Coulomb: NULL) */
    S.h = m->h;
    S.alpha = p->alpha;
    S.scheme = p->scheme;
    S.friction_updates = p->frictionUpdates;
    if (m->modal) {
        m->coupling.slots = 1u << ENG_SLOT_TRIAL; /* (the grid and mass slots: the engine's columns, once a run) */
        m->coupling.ctx = m;
        m->coupling.delassus = op_delassus;
        m->coupling.respond = op_respond;
        S.coupling = &m->coupling;
    }
    S.account_energy = account_energy;
    S.fast_paths = m->one_dof; /* (else no closed-form breakaway: nothing to skip) */
    S.rate_max = m->rate;
    S.margin_rounding = eng_dense_margin_rounding(p->n); /* (dense solves: O(n) ulps) */
    /* the oscillator's (and TwoMass's) snap of a host's rounded times to the grid */
    S.snap_max_rel_h = 1e-5;
    S.snap_min_rel_h = 1e-7;
    S.snap_eps_t = 65536.0;
    S.on_rest = p->on_rest;
    S.rest_ctx = p->rest_ctx;
    S.tangent = p->sensitivity;
    m->E = eng_create(&S, al, err);
    m->one.E = m->E;
    m->one.dense = eng_dense_friction; /* (a Stribeck contact's solver) */
    if (!m->E) {
        if (!*err) *err = "out of memory";
        sys_model_free(m, al);
        return 0;
    }
    return 1;
}
