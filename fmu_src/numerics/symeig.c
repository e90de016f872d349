/* The symmetric generalised eigenproblem K phi = lambda M phi (symeig.h). */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "symeig.h"

#include <float.h>
#include <math.h>

#define QL_SWEEPS_PER_N 30 /* the QL iteration's budget: 30 n sweeps in all */

size_t dfo_symeig_work(size_t n) { return 2 * n * n + 2 * n; }

/* sqrt(a^2 + b^2) without overflow or destructive underflow, by scaling (not libm's hypot, whose
 * last bit differs between platforms) */
static double pythag(double a, double b)
{
    const double x = fabs(a), y = fabs(b);
    if (x > y) {
        const double r = y / x;
        return x * sqrt(1.0 + r * r);
    }
    if (y == 0.0) return 0.0;
    const double r = x / y;
    return y * sqrt(1.0 + r * r);
}

/* The lower Cholesky factor of M into L (upper triangle zeroed); 0 when M is not positive definite. */
static int cholesky(size_t n, const double *M, double *L)
{
    for (size_t i = 0; i < n; i++) {
        double *li = L + i * n;
        for (size_t j = 0; j <= i; j++) {
            const double *lj = L + j * n;
            double s = M[i * n + j];
            for (size_t k = 0; k < j; k++) s -= li[k] * lj[k];
            if (i == j) {
                if (!(s > 0.0) || !isfinite(s)) return 0;
                li[i] = sqrt(s);
            } else {
                li[j] = s / lj[j];
            }
        }
        for (size_t j = i + 1; j < n; j++) li[j] = 0.0;
    }
    return 1;
}

/* B := L^-1 B in place (B n x n row-major, row by row: B_i = (B_i - sum_{k<i} L_ik B_k) / L_ii). */
static void forward_rows(size_t n, const double *L, double *B)
{
    for (size_t i = 0; i < n; i++) {
        double *bi = B + i * n;
        for (size_t k = 0; k < i; k++) {
            const double l = L[i * n + k];
            const double *bk = B + k * n;
            for (size_t c = 0; c < n; c++) bi[c] -= l * bk[c];
        }
        const double d = L[i * n + i];
        for (size_t c = 0; c < n; c++) bi[c] /= d;
    }
}

/* B := L^-T B in place (row by row from the last: B_i = (B_i - sum_{k>i} L_ki B_k) / L_ii). */
static void backward_rows(size_t n, const double *L, double *B)
{
    for (size_t i = n; i-- > 0;) {
        double *bi = B + i * n;
        for (size_t k = i + 1; k < n; k++) {
            const double l = L[k * n + i];
            const double *bk = B + k * n;
            for (size_t c = 0; c < n; c++) bi[c] -= l * bk[c];
        }
        const double d = L[i * n + i];
        for (size_t c = 0; c < n; c++) bi[c] /= d;
    }
}

static void transpose(size_t n, const double *A, double *B)
{
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < n; j++) B[j * n + i] = A[i * n + j];
}

/* Householder reduction of the symmetric V (n x n, row-major, overwritten) to tridiagonal form:
 * d (n) the diagonal, e (n) the subdiagonal in e[1..n-1] (e[0] = 0), V the orthogonal matrix of the
 * reduction (A = V T V'). EISPACK's tred2 (as in JAMA's public-domain translation). */
static void tred2(size_t n, double *V, double *d, double *e)
{
#define V_(i, j) V[(i) * n + (j)]
    for (size_t j = 0; j < n; j++) d[j] = V_(n - 1, j);
    for (size_t i = n - 1; i > 0; i--) {
        double scale = 0.0, h = 0.0;
        for (size_t k = 0; k < i; k++) scale += fabs(d[k]);
        if (scale == 0.0) {
            e[i] = d[i - 1];
            for (size_t j = 0; j < i; j++) {
                d[j] = V_(i - 1, j);
                V_(i, j) = 0.0;
                V_(j, i) = 0.0;
            }
        } else {
            for (size_t k = 0; k < i; k++) {
                d[k] /= scale;
                h += d[k] * d[k];
            }
            double f = d[i - 1], g = sqrt(h);
            if (f > 0.0) g = -g;
            e[i] = scale * g;
            h = h - f * g;
            d[i - 1] = f - g;
            for (size_t j = 0; j < i; j++) e[j] = 0.0;
            for (size_t j = 0; j < i; j++) {
                f = d[j];
                V_(j, i) = f;
                g = e[j] + V_(j, j) * f;
                for (size_t k = j + 1; k <= i - 1; k++) {
                    g += V_(k, j) * d[k];
                    e[k] += V_(k, j) * f;
                }
                e[j] = g;
            }
            f = 0.0;
            for (size_t j = 0; j < i; j++) {
                e[j] /= h;
                f += e[j] * d[j];
            }
            const double hh = f / (h + h);
            for (size_t j = 0; j < i; j++) e[j] -= hh * d[j];
            for (size_t j = 0; j < i; j++) {
                f = d[j];
                g = e[j];
                for (size_t k = j; k <= i - 1; k++) V_(k, j) -= (f * e[k] + g * d[k]);
                d[j] = V_(i - 1, j);
                V_(i, j) = 0.0;
            }
        }
        d[i] = h;
    }
    /* the transformations accumulated */
    for (size_t i = 0; i + 1 < n; i++) {
        V_(n - 1, i) = V_(i, i);
        V_(i, i) = 1.0;
        const double h = d[i + 1];
        if (h != 0.0) {
            for (size_t k = 0; k <= i; k++) d[k] = V_(k, i + 1) / h;
            for (size_t j = 0; j <= i; j++) {
                double g = 0.0;
                for (size_t k = 0; k <= i; k++) g += V_(k, i + 1) * V_(k, j);
                for (size_t k = 0; k <= i; k++) V_(k, j) -= g * d[k];
            }
        }
        for (size_t k = 0; k <= i; k++) V_(k, i + 1) = 0.0;
    }
    for (size_t j = 0; j < n; j++) {
        d[j] = V_(n - 1, j);
        V_(n - 1, j) = 0.0;
    }
    V_(n - 1, n - 1) = 1.0;
    e[0] = 0.0;
#undef V_
}

/* The implicit QL iteration on the tridiagonal (d, e from tred2), its rotations applied to the rows
 * of Z (n x n row-major: Z = V', row i the i-th column of V): d out the eigenvalues, row i of Z the
 * eigenvector of d[i]. EISPACK's tql2 (JAMA's translation), on rows. 0 when it does not converge. */
static int tql2(size_t n, double *d, double *e, double *Z)
{
    for (size_t i = 1; i < n; i++) e[i - 1] = e[i];
    e[n - 1] = 0.0;
    double f = 0.0, tst1 = 0.0;
    const double eps = DBL_EPSILON;
    long budget = (long)(QL_SWEEPS_PER_N * n);
    for (size_t l = 0; l < n; l++) {
        tst1 = fmax(tst1, fabs(d[l]) + fabs(e[l]));
        size_t m = l;
        while (m < n) {
            if (fabs(e[m]) <= eps * tst1) break;
            m++;
        }
        if (m == n) m = n - 1; /* (e[n - 1] = 0: not reached) */
        if (m > l) {
            do {
                if (--budget < 0) return 0;
                double g = d[l];
                double p = (d[l + 1] - g) / (2.0 * e[l]);
                double r = pythag(p, 1.0);
                if (p < 0) r = -r;
                d[l] = e[l] / (p + r);
                d[l + 1] = e[l] * (p + r);
                const double dl1 = d[l + 1];
                double h = g - d[l];
                for (size_t i = l + 2; i < n; i++) d[i] -= h;
                f = f + h;
                p = d[m];
                double c = 1.0, c2 = c, c3 = c, s = 0.0, s2 = 0.0;
                const double el1 = e[l + 1];
                for (size_t i = m; i-- > l;) {
                    c3 = c2;
                    c2 = c;
                    s2 = s;
                    g = c * e[i];
                    h = c * p;
                    r = pythag(p, e[i]);
                    e[i + 1] = s * r;
                    s = e[i] / r;
                    c = p / r;
                    p = c * d[i] - s * g;
                    d[i + 1] = h + s * (c * g + s * d[i]);
                    double *zi = Z + i * n, *zi1 = Z + (i + 1) * n;
                    for (size_t k = 0; k < n; k++) {
                        h = zi1[k];
                        zi1[k] = s * zi[k] + c * h;
                        zi[k] = c * zi[k] - s * h;
                    }
                }
                p = -s * s2 * c3 * el1 * e[l] / dl1;
                e[l] = s * p;
                d[l] = c * p;
            } while (fabs(e[l]) > eps * tst1);
        }
        d[l] = d[l] + f;
        e[l] = 0.0;
    }
    return 1;
}

int dfo_symeig(size_t n, const double *K, const double *M, double *lambda, double *PhiT, double *work)
{
    double *L = work, *A = work + n * n, *e = work + 2 * n * n + n, *d = work + 2 * n * n;
    if (n == 0) return 1;
    for (size_t k = 0; k < n * n; k++)
        if (!isfinite(K[k]) || !isfinite(M[k])) return 0;
    if (!cholesky(n, M, L)) return 0;
    /* A = L^-1 K L^-T: B = L^-1 K (K's lower triangle mirrored), then A = L^-1 B' */
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j < n; j++) PhiT[i * n + j] = (j <= i) ? K[i * n + j] : K[j * n + i];
    forward_rows(n, L, PhiT);
    transpose(n, PhiT, A);
    forward_rows(n, L, A);
    for (size_t i = 0; i < n; i++) /* symmetric to the bit: the mean of the two triangles */
        for (size_t j = 0; j < i; j++) A[i * n + j] = A[j * n + i] = 0.5 * (A[i * n + j] + A[j * n + i]);
    tred2(n, A, d, e);
    transpose(n, A, PhiT); /* Z: rows the columns of the reduction's V */
    if (!tql2(n, d, e, PhiT)) return 0;
    for (size_t k = 0; k < n; k++)
        if (!isfinite(d[k])) return 0;
    /* ascending (selection sort: equal eigenvalues keep their order) */
    for (size_t i = 0; i + 1 < n; i++) {
        size_t k = i;
        for (size_t j = i + 1; j < n; j++)
            if (d[j] < d[k]) k = j;
        if (k != i) {
            const double t = d[k];
            d[k] = d[i];
            d[i] = t;
            double *zi = PhiT + i * n, *zk = PhiT + k * n;
            for (size_t c = 0; c < n; c++) {
                const double z = zi[c];
                zi[c] = zk[c];
                zk[c] = z;
            }
        }
    }
    /* Phi = L^-T Q (Q = Z', its columns the eigenvectors of A), then PhiT = Phi' */
    transpose(n, PhiT, A);
    backward_rows(n, L, A);
    transpose(n, A, PhiT);
    for (size_t r = 0; r < n; r++) {
        double *p = PhiT + r * n;
        size_t big = 0;
        for (size_t c = 1; c < n; c++)
            if (fabs(p[c]) > fabs(p[big])) big = c;
        if (p[big] < 0.0)
            for (size_t c = 0; c < n; c++) p[c] = -p[c];
        lambda[r] = d[r];
    }
    return 1;
}
