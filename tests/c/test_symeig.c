/* The symmetric generalised eigensolver (numerics/symeig.h): K phi = lambda M phi.
 *
 *   - random pencils (M = B B' + n I, K = G G' symmetric positive semi-definite or indefinite
 *     symmetric), n = 1 ... 256: the residuals max|K Phi - M Phi Lambda| relative to
 *     max|K| + max|M| max|lambda| (times max|Phi|) and max|Phi' M Phi - I|, both below 1e-12; the
 *     eigenvalues against the test's own cyclic Jacobi method on L^-1 K L^-T (n <= 48) within 1e-12
 *     of the largest;
 *   - known spectra with repeated eigenvalues and a singular K: M = D (diagonal, random), K =
 *     D^1/2 Q Lambda Q' D^1/2 with Q a product of two Householder reflections and Lambda with values
 *     repeated and zeros (the pencil's eigenvalues are Lambda's), K = c M (one eigenvalue n times),
 *     K = 0;
 *   - the fixed-free spring chain (M = I, K tridiagonal 2, -1, its last diagonal entry 1): the
 *     eigenvalues 4 sin^2((2k - 1) pi / (2 (2 n + 1))), k = 1 ... n, within 1e-13 absolute;
 *   - the same bits from the same data (a second call), ascending order, each mode's sign, M not
 *     positive definite and a NaN refused. */
#include "check.h"
#include "symeig.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double maxabs(size_t count, const double *a)
{
    double m = 0.0;
    for (size_t i = 0; i < count; i++) m = fmax(m, fabs(a[i]));
    return m;
}

/* The residuals of (lambda, PhiT) for (K, M): *rk = max|K Phi - M Phi Lambda| / ((max|K| + max|M|
 * max|lambda|) max|Phi|), *rm = max|Phi' M Phi - I|. */
static void residuals(size_t n, const double *K, const double *M, const double *lam, const double *PhiT, double *rk,
                      double *rm)
{
    double *kp = malloc(n * sizeof *kp), *mp = malloc(n * sizeof *mp);
    double ek = 0.0, em = 0.0;
    for (size_t r = 0; r < n; r++) {
        const double *p = PhiT + r * n;
        for (size_t i = 0; i < n; i++) {
            double sk = 0.0, sm = 0.0;
            for (size_t k = 0; k < n; k++) {
                sk += K[i * n + k] * p[k];
                sm += M[i * n + k] * p[k];
            }
            kp[i] = sk;
            mp[i] = sm;
            ek = fmax(ek, fabs(sk - lam[r] * sm));
        }
        for (size_t s = 0; s < n; s++) {
            double g = 0.0;
            for (size_t i = 0; i < n; i++) g += PhiT[s * n + i] * mp[i];
            em = fmax(em, fabs(g - (r == s ? 1.0 : 0.0)));
        }
    }
    const double scale = (maxabs(n * n, K) + maxabs(n * n, M) * maxabs(n, lam)) * maxabs(n * n, PhiT);
    *rk = scale > 0.0 ? ek / scale : ek;
    *rm = em;
    free(kp);
    free(mp);
}

/* The eigenvalues of (K, M) by the test's own means: the Cholesky factor of M, S = L^-1 K L^-T by
 * column solves, then cyclic Jacobi rotations until the off-diagonal part is below 1e-15 of the
 * matrix; sorted ascending. */
static void jacobi_eigs(size_t n, const double *K, const double *M, double *out)
{
    double *L = calloc(n * n, sizeof *L), *S = calloc(n * n, sizeof *S), *T = calloc(n * n, sizeof *T);
    for (size_t j = 0; j < n; j++)
        for (size_t i = j; i < n; i++) {
            double s = M[i * n + j];
            for (size_t k = 0; k < j; k++) s -= L[i * n + k] * L[j * n + k];
            L[i * n + j] = (i == j) ? sqrt(s) : s / L[j * n + j];
        }
    for (size_t c = 0; c < n; c++) /* T[:, c] = L^-1 K[:, c] */
        for (size_t i = 0; i < n; i++) {
            double s = K[i * n + c];
            for (size_t k = 0; k < i; k++) s -= L[i * n + k] * T[k * n + c];
            T[i * n + c] = s / L[i * n + i];
        }
    for (size_t r = 0; r < n; r++) /* S[r, :] = (L^-1 T[r, :]')' : S = T L^-T */
        for (size_t i = 0; i < n; i++) {
            double s = T[r * n + i];
            for (size_t k = 0; k < i; k++) s -= L[i * n + k] * S[r * n + k];
            S[r * n + i] = s / L[i * n + i];
        }
    const double norm = maxabs(n * n, S);
    for (int sweep = 0; sweep < 100; sweep++) {
        double off = 0.0;
        for (size_t p = 0; p < n; p++)
            for (size_t q = p + 1; q < n; q++) off = fmax(off, fabs(S[p * n + q]));
        if (off <= 1e-15 * norm) break;
        for (size_t p = 0; p < n; p++)
            for (size_t q = p + 1; q < n; q++) {
                const double apq = 0.5 * (S[p * n + q] + S[q * n + p]);
                if (apq == 0.0) continue;
                const double theta = (S[q * n + q] - S[p * n + p]) / (2.0 * apq);
                const double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                const double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (size_t k = 0; k < n; k++) { /* columns p, q */
                    const double a = S[k * n + p], b = S[k * n + q];
                    S[k * n + p] = c * a - s * b;
                    S[k * n + q] = s * a + c * b;
                }
                for (size_t k = 0; k < n; k++) { /* rows p, q */
                    const double a = S[p * n + k], b = S[q * n + k];
                    S[p * n + k] = c * a - s * b;
                    S[q * n + k] = s * a + c * b;
                }
            }
    }
    for (size_t i = 0; i < n; i++) out[i] = S[i * n + i];
    for (size_t i = 1; i < n; i++) /* insertion sort */
        for (size_t k = i; k > 0 && out[k] < out[k - 1]; k--) {
            const double t = out[k];
            out[k] = out[k - 1];
            out[k - 1] = t;
        }
    free(L);
    free(S);
    free(T);
}

typedef struct {
    double rk, rm, rlam; /* the worst residuals and eigenvalue error seen */
} worst;

/* Solve (K, M), check residuals, order, signs, the same bits on a second call; ref (n, ascending) the
 * reference eigenvalues or NULL; tol_lam: their tolerance relative to max(max|ref|, 1) (absolute
 * when abs_lam). */
static void solve_and_check(checks *T, size_t n, const double *K, const double *M, const double *ref, double tol_lam,
                            int abs_lam, worst *W)
{
    double *work = malloc(dfo_symeig_work(n) * sizeof *work), *lam = malloc(n * sizeof *lam),
           *PhiT = malloc(n * n * sizeof *PhiT), *lam2 = malloc(n * sizeof *lam2), *Phi2 = malloc(n * n * sizeof *Phi2);
    CHECK(dfo_symeig(n, K, M, lam, PhiT, work));
    double rk, rm;
    residuals(n, K, M, lam, PhiT, &rk, &rm);
    CHECK_RANGE(0.0, 1e-12, rk);
    CHECK_RANGE(0.0, 1e-12, rm);
    W->rk = fmax(W->rk, rk);
    W->rm = fmax(W->rm, rm);
    for (size_t i = 1; i < n; i++) CHECK(lam[i] >= lam[i - 1]);
    for (size_t r = 0; r < n; r++) {
        const double *p = PhiT + r * n;
        size_t big = 0;
        for (size_t c = 1; c < n; c++)
            if (fabs(p[c]) > fabs(p[big])) big = c;
        CHECK(p[big] > 0.0);
    }
    if (ref) {
        const double scale = abs_lam ? 1.0 : fmax(maxabs(n, ref), 1.0);
        double e = 0.0;
        for (size_t i = 0; i < n; i++) e = fmax(e, fabs(lam[i] - ref[i]) / scale);
        CHECK_RANGE(0.0, tol_lam, e);
        W->rlam = fmax(W->rlam, e);
    }
    CHECK(dfo_symeig(n, K, M, lam2, Phi2, work));
    CHECK(memcmp(lam, lam2, n * sizeof *lam) == 0 && memcmp(PhiT, Phi2, n * n * sizeof *PhiT) == 0);
    free(work);
    free(lam);
    free(PhiT);
    free(lam2);
    free(Phi2);
}

/* M = B B' + n I (B uniform in [-1, 1]); K = G G' (psd: G n x k, k = n / 2 + 1) or G + G' (indefinite). */
static void random_pencil(rng *R, size_t n, int indefinite, double *K, double *M)
{
    double *B = malloc(n * n * sizeof *B);
    for (size_t i = 0; i < n * n; i++) B[i] = rng_range(R, -1.0, 1.0);
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j <= i; j++) {
            double s = 0.0;
            for (size_t k = 0; k < n; k++) s += B[i * n + k] * B[j * n + k];
            M[i * n + j] = M[j * n + i] = s + (i == j ? (double)n : 0.0);
        }
    for (size_t i = 0; i < n * n; i++) B[i] = rng_range(R, -1.0, 1.0);
    const size_t k = n / 2 + 1;
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j <= i; j++) {
            double s;
            if (indefinite) {
                s = B[i * n + j] + B[j * n + i];
            } else {
                s = 0.0;
                for (size_t c = 0; c < k; c++) s += B[i * n + c] * B[j * n + c];
            }
            K[i * n + j] = K[j * n + i] = s;
        }
    free(B);
}

/* K = D^1/2 Q diag(lam) Q' D^1/2, M = D, Q = (I - 2 u u') (I - 2 v v') (u, v unit, random). */
static void known_pencil(rng *R, size_t n, const double *lam, double *K, double *M)
{
    double *u = malloc(n * sizeof *u), *v = malloc(n * sizeof *v), *Q = malloc(n * n * sizeof *Q),
           *D = malloc(n * sizeof *D);
    double nu = 0.0, nv = 0.0;
    for (size_t i = 0; i < n; i++) {
        u[i] = rng_range(R, -1.0, 1.0);
        v[i] = rng_range(R, -1.0, 1.0);
        nu += u[i] * u[i];
        nv += v[i] * v[i];
        D[i] = rng_range(R, 0.5, 4.0);
    }
    for (size_t i = 0; i < n; i++) {
        u[i] /= sqrt(nu);
        v[i] /= sqrt(nv);
    }
    double udotv = 0.0;
    for (size_t i = 0; i < n; i++) udotv += u[i] * v[i];
    for (size_t i = 0; i < n; i++) /* Q_ij = (I - 2uu')(I - 2vv') = I - 2uu' - 2vv' + 4 (u.v) u v' */
        for (size_t j = 0; j < n; j++)
            Q[i * n + j] = (i == j ? 1.0 : 0.0) - 2.0 * u[i] * u[j] - 2.0 * v[i] * v[j] + 4.0 * udotv * u[i] * v[j];
    for (size_t i = 0; i < n; i++)
        for (size_t j = 0; j <= i; j++) {
            double s = 0.0;
            for (size_t k = 0; k < n; k++) s += Q[i * n + k] * lam[k] * Q[j * n + k];
            K[i * n + j] = K[j * n + i] = sqrt(D[i]) * s * sqrt(D[j]);
            M[i * n + j] = M[j * n + i] = (i == j) ? D[i] : 0.0;
        }
    free(u);
    free(v);
    free(Q);
    free(D);
}

static int cmp_double(const void *a, const void *b)
{
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

int main(void)
{
    checks TT = {0, 0, NULL, {0}}, *T = &TT;
    rng R = {20261207ULL};
    const size_t sizes[] = {1, 2, 3, 4, 5, 7, 8, 13, 16, 24, 32, 48, 64, 100, 128, 200, 256};
    worst Wr = {0, 0, 0}, Wk = {0, 0, 0}, Wc = {0, 0, 0};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        const size_t n = sizes[s];
        double *K = malloc(n * n * sizeof *K), *M = malloc(n * n * sizeof *M), *ref = malloc(n * sizeof *ref);
        for (int indefinite = 0; indefinite <= 1; indefinite++) {
            check_context(T, "random pencil n = %zu, %s K", n, indefinite ? "indefinite" : "semi-definite");
            random_pencil(&R, n, indefinite, K, M);
            if (n <= 48) jacobi_eigs(n, K, M, ref);
            solve_and_check(T, n, K, M, n <= 48 ? ref : NULL, 1e-12, 0, &Wr);
        }
        /* repeated eigenvalues and zeros: lam_k = floor(k / 3) for k < n / 2, else 0 */
        check_context(T, "known spectrum n = %zu (repeated, zeros)", n);
        for (size_t k = 0; k < n; k++) ref[k] = (k < n / 2) ? (double)(k / 3) + 1.0 : 0.0;
        known_pencil(&R, n, ref, K, M);
        qsort(ref, n, sizeof *ref, cmp_double);
        solve_and_check(T, n, K, M, ref, 1e-12, 0, &Wk);
        /* K = 2.5 M: one eigenvalue n times; K = 0 */
        check_context(T, "K = 2.5 M, n = %zu", n);
        random_pencil(&R, n, 0, K, M);
        for (size_t i = 0; i < n * n; i++) K[i] = 2.5 * M[i];
        for (size_t k = 0; k < n; k++) ref[k] = 2.5;
        solve_and_check(T, n, K, M, ref, 1e-12, 0, &Wk);
        check_context(T, "K = 0, n = %zu", n);
        memset(K, 0, n * n * sizeof *K);
        for (size_t k = 0; k < n; k++) ref[k] = 0.0;
        solve_and_check(T, n, K, M, ref, 1e-12, 0, &Wk);
        /* the fixed-free chain */
        check_context(T, "fixed-free chain n = %zu", n);
        memset(K, 0, n * n * sizeof *K);
        memset(M, 0, n * n * sizeof *M);
        for (size_t i = 0; i < n; i++) {
            M[i * n + i] = 1.0;
            K[i * n + i] = (i + 1 < n) ? 2.0 : 1.0;
            if (i + 1 < n) K[i * n + i + 1] = K[(i + 1) * n + i] = -1.0;
        }
        for (size_t k = 1; k <= n; k++) {
            const double x = sin((double)(2 * k - 1) * 3.14159265358979323846 / (2.0 * (2.0 * (double)n + 1.0)));
            ref[k - 1] = 4.0 * x * x;
        }
        solve_and_check(T, n, K, M, ref, 1e-13, 1, &Wc);
        free(K);
        free(M);
        free(ref);
    }
    printf("random pencils: residual %.3g, M-orthonormality %.3g, eigenvalues vs Jacobi %.3g (relative)\n", Wr.rk,
           Wr.rm, Wr.rlam);
    printf("known spectra (repeated, zeros, K = c M, K = 0): residual %.3g, M-orthonormality %.3g, eigenvalues %.3g\n",
           Wk.rk, Wk.rm, Wk.rlam);
    printf("fixed-free chain: residual %.3g, orthonormality %.3g, eigenvalues vs 4 sin^2 %.3g (absolute)\n", Wc.rk,
           Wc.rm, Wc.rlam);
    /* refusals */
    check_context(T, "refusals");
    {
        double K[4] = {1, 0, 0, 1}, M[4] = {1, 2, 2, 1}, lam[2], P[4], work[12];
        CHECK(!dfo_symeig(2, K, M, lam, P, work)); /* M indefinite */
        M[1] = M[2] = 0.0;
        K[3] = NAN;
        CHECK(!dfo_symeig(2, K, M, lam, P, work));
        K[3] = 1.0;
        CHECK(dfo_symeig(2, K, M, lam, P, work));
        CHECK_SAME(1.0, lam[0]);
        CHECK_SAME(1.0, lam[1]);
    }
    return checks_done(T, "test_symeig");
}
