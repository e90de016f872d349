/* Unit tests of the LCP solvers of fmu_src/numerics/lcp.h: Lemke's algorithm and the box LCP.
 *
 * 1. The friction LCP of method.md section 3 (M = m_hat [[1,-1],[-1,1]], q = (muN - p, muN + p))
 *    against its closed form, over many decades and on the degenerate cases.
 * 2. General n: P-matrices (unique solution, compared with a brute-force enumeration of the 2^n
 *    complementary bases), positive semi-definite singular M with a feasible q, infeasible
 *    problems (ray), the pivot budget, and invalid input.
 * 3. The box LCP of a tridiagonal M (lcp_box, lcp_box_basis): against a brute-force enumeration of
 *    the 3^n modes for n <= 6, each mode set solved densely (Gaussian elimination, not the Thomas
 *    solve under test), with the box conditions verified on every answer (|w| <= l, z > 0 => w = -l,
 *    z < 0 => w = l, w = M z + q); well-conditioned, tied, frictionless and stiff problems; the
 *    basis solve with fixed end rows against the dense solve. */
#include "check.h"
#include "lcp.h"

#include <float.h>
#include <math.h>
#include <stdio.h>

#define BIG_BUDGET 1000

/* worst values seen, printed at the end (the numbers the report quotes) */
typedef struct {
    double friction_residual, friction_closed_form, general_residual, general_vs_enum, revised_vs_tableau;
    int friction_pivots_max, general_pivots_max;
    long revised_vs_tableau_cases, warm_cases, warm_zero_pivot;
    long friction_cases, friction_degenerate, pmatrix_cases, psd_cases, integer_cases;
} stats;

/* ---- helpers ----------------------------------------------------------------------------------- */

/* Verify z >= 0, w >= 0, w = M z + q (|w - (Mz + q)| <= tol * scale), z . w = 0 exactly (Lemke's
 * final basis is complementary, so one of each pair is non-basic and exactly 0). Returns the
 * relative residual. scale = max_i max(|q_i|, sum_j |M_ij z_j|). */
static double verify(checks *T, int n, const double *M, const double *q, const double *z, const double *w,
                     double tol)
{
    double scale = 0.0, res = 0.0;
    for (int i = 0; i < n; i++) {
        double r = q[i], a = fabs(q[i]);
        for (int j = 0; j < n; j++) {
            r += M[i * n + j] * z[j];
            a += fabs(M[i * n + j] * z[j]);
        }
        scale = fmax(scale, a);
        res = fmax(res, fabs(w[i] - r));
        CHECK(z[i] >= 0.0);
        CHECK(w[i] >= 0.0);
        CHECK(z[i] * w[i] == 0.0);
        CHECK(isfinite(z[i]) && isfinite(w[i]));
    }
    const double rel = scale > 0.0 ? res / scale : res;
    CHECK_RANGE(0.0, tol, rel);
    return rel;
}

/* Solve A x = b (k x k, row-major, copied) by Gaussian elimination with partial pivoting.
 * Returns the determinant (0 when singular); x may be NULL for the determinant only. */
static double gauss(int k, const double *A_in, const double *b_in, double *x)
{
    double A[LCP_STACK_N * LCP_STACK_N], b[LCP_STACK_N];
    double det = 1.0;
    for (int i = 0; i < k * k; i++) A[i] = A_in[i];
    for (int i = 0; i < k; i++) b[i] = b_in ? b_in[i] : 0.0;
    for (int c = 0; c < k; c++) {
        int p = c;
        for (int i = c + 1; i < k; i++)
            if (fabs(A[i * k + c]) > fabs(A[p * k + c])) p = i;
        if (A[p * k + c] == 0.0) return 0.0;
        if (p != c) {
            for (int j = 0; j < k; j++) { const double t = A[c * k + j]; A[c * k + j] = A[p * k + j]; A[p * k + j] = t; }
            const double t = b[c]; b[c] = b[p]; b[p] = t;
            det = -det;
        }
        det *= A[c * k + c];
        for (int i = c + 1; i < k; i++) {
            const double f = A[i * k + c] / A[c * k + c];
            for (int j = c; j < k; j++) A[i * k + j] -= f * A[c * k + j];
            b[i] -= f * b[c];
        }
    }
    if (x) {
        for (int i = k - 1; i >= 0; i--) {
            double s = b[i];
            for (int j = i + 1; j < k; j++) s -= A[i * k + j] * x[j];
            x[i] = s / A[i * k + i];
        }
    }
    return det;
}

/* Extract the principal submatrix on the index set given by the bitmask. */
static int principal(int n, const double *M, unsigned mask, double *S, int *idx)
{
    int k = 0;
    for (int i = 0; i < n; i++)
        if (mask & (1u << i)) idx[k++] = i;
    for (int a = 0; a < k; a++)
        for (int b = 0; b < k; b++) S[a * k + b] = M[idx[a] * n + idx[b]];
    return k;
}

/* All principal minors positive (relative to the entries' size, so the test is not fooled by
 * rounding near 0). */
static int is_P_matrix(int n, const double *M)
{
    double S[LCP_STACK_N * LCP_STACK_N];
    int idx[LCP_STACK_N];
    for (unsigned mask = 1; mask < (1u << n); mask++) {
        const int k = principal(n, M, mask, S, idx);
        double size = 1.0;
        for (int a = 0; a < k; a++) {
            double row = 0.0;
            for (int b = 0; b < k; b++) row += fabs(S[a * k + b]);
            size *= row;
        }
        if (!(gauss(k, S, NULL, NULL) > 1e-6 * size)) return 0;
    }
    return 1;
}

/* The unique solution of a P-matrix LCP by enumerating the complementary bases: z_a solves
 * M_aa z_a = -q_a, and the basis is the one where z_a >= 0 and w = M z + q >= 0 (up to rounding).
 * Returns the number of feasible bases found (1 for a non-degenerate P-matrix problem). */
static int enumerate_solution(int n, const double *M, const double *q, double *z_out)
{
    double S[LCP_STACK_N * LCP_STACK_N], b[LCP_STACK_N], x[LCP_STACK_N];
    int idx[LCP_STACK_N], found = 0;
    double qs = 0.0;
    for (int i = 0; i < n; i++) qs = fmax(qs, fabs(q[i]));
    for (unsigned mask = 0; mask < (1u << n); mask++) {
        const int k = principal(n, M, mask, S, idx);
        for (int a = 0; a < k; a++) b[a] = -q[idx[a]];
        if (k > 0 && gauss(k, S, b, x) == 0.0) continue;
        double z[LCP_STACK_N] = {0};
        for (int a = 0; a < k; a++) z[idx[a]] = x[a];
        int ok = 1;
        double zs = 0.0;
        for (int i = 0; i < n; i++) zs = fmax(zs, fabs(z[i]));
        const double tol = 1e-9 * (qs + zs);
        for (int i = 0; i < n && ok; i++) {
            double w = q[i];
            for (int j = 0; j < n; j++) w += M[i * n + j] * z[j];
            if (z[i] < -tol || w < -tol) ok = 0;
        }
        if (ok) {
            if (found == 0)
                for (int i = 0; i < n; i++) z_out[i] = fmax(z[i], 0.0);
            found++;
        }
    }
    return found;
}

static double norm_inf(int n, const double *v)
{
    double s = 0.0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(v[i]));
    return s;
}

/* lcp_lemke solves n = 2 in revised form (basis inverse in registers): it must take the tableau's
 * path, pivot for pivot, and reach the same solution to rounding. */
static void same_as_tableau(checks *T, stats *st, int n, const double *M, const double *q, int budget,
                            lcp_status s, const double *z, const double *w, const int *zb, int piv)
{
    if (n != 2) return;
    double z2[2], w2[2];
    int zb2[2], piv2 = -1;
    const lcp_status s2 = lcp_lemke_general(2, M, q, budget, z2, w2, zb2, &piv2);
    st->revised_vs_tableau_cases++;
    CHECK_INT(s2, s);
    CHECK_INT(piv2, piv);
    if (s != LCP_OK || s2 != LCP_OK) return;
    const double scale = fmax(fmax(fabs(z2[0]), fabs(z2[1])), fmax(fabs(w2[0]), fabs(w2[1])));
    for (int i = 0; i < 2; i++) {
        CHECK_INT(zb2[i], zb[i]);
        const double e = fmax(fabs(z[i] - z2[i]), fabs(w[i] - w2[i]));
        CHECK_RANGE(0.0, 1e-12 * scale, e);
        if (scale > 0.0) st->revised_vs_tableau = fmax(st->revised_vs_tableau, e / scale);
    }
}

/* Warm starts from every complementary basis (2^n guesses): a solution of the LCP each time; for
 * the friction problem the active pair the stepper reads (z_i basic and > 0) is the cold one's;
 * with a unique solution (z_ref given) the same solution. */
static void warm_starts(checks *T, stats *st, int n, const double *M, const double *q, const double *z_cold,
                        const int *zb_cold, const double *z_ref, double tol, int friction)
{
    for (unsigned mask = 0; mask < (1u << n); mask++) {
        int guess[LCP_STACK_N];
        for (int i = 0; i < n; i++) guess[i] = (mask >> i) & 1u;
        double z[LCP_STACK_N], w[LCP_STACK_N];
        int zb[LCP_STACK_N], piv = -1;
        const lcp_status s = lcp_lemke_warm(n, M, q, guess, BIG_BUDGET, z, w, zb, &piv);
        st->warm_cases++;
        if (piv == 0) st->warm_zero_pivot++;
        if (!CHECK_INT(LCP_OK, s)) continue;
        verify(T, n, M, q, z, w, tol);
        for (int i = 0; i < n; i++) CHECK(zb[i] || z[i] == 0.0);
        if (friction)
            for (int i = 0; i < n; i++) CHECK_INT(zb_cold[i] && z_cold[i] > 0.0, zb[i] && z[i] > 0.0);
        if (z_ref) {
            const double zs = fmax(norm_inf(n, z_ref), 1e-300);
            double e = 0.0;
            for (int i = 0; i < n; i++) e = fmax(e, fabs(z[i] - z_ref[i]));
            CHECK_RANGE(0.0, 1e-8, e / zs);
        }
    }
}

/* ---- 1. the friction LCP ---------------------------------------------------------------------- */

/* Solve the friction LCP and check it against the closed form (method.md section 3). */
static void friction_case(checks *T, stats *st, double mh, double p, double muN)
{
    const double M[4] = {mh, -mh, -mh, mh}, q[2] = {muN - p, muN + p};
    double z[2] = {-1, -1}, w[2] = {-1, -1};
    int zb[2] = {-1, -1}, piv = -1;
    check_context(T, "friction LCP m_hat=%.17g p_hat=%.17g muN=%.17g", mh, p, muN);
    const lcp_status s = lcp_lemke(2, M, q, 16, z, w, zb, &piv);
    st->friction_cases++;
    same_as_tableau(T, st, 2, M, q, 16, s, z, w, zb, piv);
    if (!CHECK_INT(LCP_OK, s)) return;
    warm_starts(T, st, 2, M, q, z, zb, NULL, 1e-12, 1);
    CHECK_RANGE(0, 3, piv);
    if (piv > st->friction_pivots_max) st->friction_pivots_max = piv;
    st->friction_residual = fmax(st->friction_residual, verify(T, 2, M, q, z, w, 1e-12));
    CHECK((zb[0] == 0 || zb[0] == 1) && (zb[1] == 0 || zb[1] == 1));
    CHECK(!(zb[0] && zb[1]));  /* u1 and u2 are never both basic (M is singular) */
    CHECK(zb[0] || z[0] == 0.0);
    CHECK(zb[1] || z[1] == 0.0);

    /* closed form; velocities compared on the problem's velocity scale (|p| + muN) / m_hat */
    const double vs = (fabs(p) + muN) / mh, tol = 1e-12 * vs;
    double e = 0.0;
    if (muN == 0.0) {  /* only u1 - u2 is unique */
        CHECK_NEAR(p / mh, z[0] - z[1], tol);
        e = fabs((z[0] - z[1]) - p / mh);
    } else if (p > muN) {  /* forward slip */
        CHECK_NEAR((p - muN) / mh, z[0], tol);
        CHECK_SAME(0.0, z[1]);
        CHECK_INT(1, zb[0]);
        CHECK_NEAR(0.0, w[0], 1e-12 * (fabs(p) + muN));
        e = fabs(z[0] - (p - muN) / mh);
    } else if (p < -muN) {  /* backward slip */
        CHECK_NEAR((-p - muN) / mh, z[1], tol);
        CHECK_SAME(0.0, z[0]);
        CHECK_INT(1, zb[1]);
        CHECK_NEAR(0.0, w[1], 1e-12 * (fabs(p) + muN));
        e = fabs(z[1] - (-p - muN) / mh);
    } else {  /* stick: u = 0, F1 = -p_hat, so r1 = muN - p, r2 = muN + p */
        CHECK_SAME(0.0, z[0]);
        CHECK_SAME(0.0, z[1]);
        CHECK_INT(0, zb[0] + zb[1]);
        CHECK_NEAR(muN - p, w[0], 1e-12 * (fabs(p) + muN));
        CHECK_NEAR(muN + p, w[1], 1e-12 * (fabs(p) + muN));
    }
    if (vs > 0.0) st->friction_closed_form = fmax(st->friction_closed_form, e / vs);
}

static void test_friction(checks *T, stats *st)
{
    rng r = {20240601u};
    /* random problems: m_hat 1e-6..1e12, muN and p_hat over many decades, both regimes */
    for (int i = 0; i < 20000; i++) {
        const double mh = rng_decades(&r, -6, 12);
        const double muN = rng_decades(&r, -12, 12);
        double p;
        switch (i % 3) {
        case 0: p = muN * rng_decades(&r, -4, 4); break;               /* around the limit */
        case 1: p = muN * (1.0 + rng_range(&r, -1e-9, 1e-9)); break;   /* nearly tied */
        default: p = rng_decades(&r, -12, 12); break;                  /* independent scale */
        }
        if (rng_uniform(&r) < 0.5) p = -p;
        friction_case(T, st, mh, p, muN);
    }
    /* degenerate: ties |p_hat| = muN exactly, muN = 0, p_hat = 0, both 0 */
    for (int i = 0; i < 2000; i++) {
        const double mh = rng_decades(&r, -6, 12), muN = rng_decades(&r, -12, 12);
        const double p = rng_decades(&r, -12, 12);
        friction_case(T, st, mh, muN, muN);
        friction_case(T, st, mh, -muN, muN);
        friction_case(T, st, mh, p, 0.0);
        friction_case(T, st, mh, -p, 0.0);
        friction_case(T, st, mh, 0.0, muN);
        friction_case(T, st, mh, 0.0, 0.0);
        friction_case(T, st, mh, -0.0, 0.0);
        friction_case(T, st, mh, nextafter(muN, INFINITY), muN);   /* one ulp beyond the limit */
        friction_case(T, st, mh, -nextafter(muN, INFINITY), muN);
        friction_case(T, st, mh, nextafter(muN, 0.0), muN);        /* one ulp inside */
        st->friction_degenerate += 10;
    }
    /* the physical extremes: m_hat 1e-6 and 1e12 with loads from tiny to huge */
    const double mhs[] = {1e-6, 1e-3, 1.0, 1e6, 1e12}, loads[] = {1e-300, 1e-12, 1.0, 1e12, 1e300};
    for (int a = 0; a < 5; a++)
        for (int b = 0; b < 5; b++)
            for (int c = 0; c < 5; c++) {
                friction_case(T, st, mhs[a], loads[b], loads[c]);
                friction_case(T, st, mhs[a], -loads[b], loads[c]);
            }
    /* subnormal p_hat and muN (and a subnormal m_hat with a subnormal load: ratio of order 1) */
    const double sub[] = {0x1p-1074, 0x3p-1074, 1e-310, DBL_MIN / 2, DBL_MIN};
    for (int a = 0; a < 5; a++)
        for (int b = 0; b < 5; b++) {
            friction_case(T, st, 1.0, sub[a], sub[b]);
            friction_case(T, st, 1.0, -sub[a], sub[b]);
            friction_case(T, st, 1e-6, sub[a], 0.0);
            friction_case(T, st, 1e-6, -sub[a], sub[b]);
            friction_case(T, st, 1.0, sub[a], 1.0);
            friction_case(T, st, 1.0, 1.0, sub[b]);
            st->friction_degenerate += 6;
        }
    T->context = NULL;
}

/* ---- 2. general n ----------------------------------------------------------------------------- */

/* Print a problem so that a failure can be reproduced exactly (C initialisers, %a). */
static void dump_problem(int n, const double *M, const double *q, lcp_status s, int piv)
{
    fprintf(stderr, "    lcp_lemke returned %d (%s) after %d pivots on n = %d:\n    M = {", (int)s,
            lcp_status_text(s), piv, n);
    for (int i = 0; i < n * n; i++) fprintf(stderr, "%a%s", M[i], i + 1 < n * n ? ", " : "};\n    q = {");
    for (int i = 0; i < n; i++) fprintf(stderr, "%a%s", q[i], i + 1 < n ? ", " : "};\n");
}

/* Solve, verify, and (when z_ref is given) compare with the reference solution. Returns the
 * pivot count, or -1 when Lemke did not report a solution. */
static int general_case(checks *T, stats *st, int n, const double *M, const double *q, const double *z_ref,
                        double tol)
{
    double z[LCP_STACK_N], w[LCP_STACK_N];
    int zb[LCP_STACK_N], piv = -1;
    const lcp_status s = lcp_lemke(n, M, q, BIG_BUDGET, z, w, zb, &piv);
    same_as_tableau(T, st, n, M, q, BIG_BUDGET, s, z, w, zb, piv);
    if (!CHECK_INT(LCP_OK, s)) {
        if (T->failures <= CHECK_MAX_REPORT) dump_problem(n, M, q, s, piv);
        return -1;
    }
    CHECK_RANGE(0, 100, piv);  /* terminates long before the budget */
    if (n <= 4) warm_starts(T, st, n, M, q, z, zb, z_ref, tol, 0);
    if (piv > st->general_pivots_max) st->general_pivots_max = piv;
    const double res = verify(T, n, M, q, z, w, tol);
    st->general_residual = fmax(st->general_residual, res);
    for (int i = 0; i < n; i++) CHECK((zb[i] != 0) || z[i] == 0.0);
    if (z_ref) {
        const double zs = fmax(norm_inf(n, z_ref), 1e-300);
        double e = 0.0;
        for (int i = 0; i < n; i++) e = fmax(e, fabs(z[i] - z_ref[i]));
        CHECK_RANGE(0.0, 1e-8, e / zs);
        st->general_vs_enum = fmax(st->general_vs_enum, e / zs);
    }
    return piv;
}

/* random n x n with entries uniform in [-1, 1] */
static void random_matrix(rng *r, int n, double *A)
{
    for (int i = 0; i < n * n; i++) A[i] = rng_range(r, -1.0, 1.0);
}

/* M = A A^T + d I (symmetric positive definite) plus, optionally, a skew part (still positive
 * definite as a quadratic form, hence a P-matrix) */
static void random_pd(rng *r, int n, double *M, int skew)
{
    double A[LCP_STACK_N * LCP_STACK_N], B[LCP_STACK_N * LCP_STACK_N];
    random_matrix(r, n, A);
    random_matrix(r, n, B);
    const double d = rng_decades(r, -2, 0);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double s = (i == j) ? d : 0.0;
            for (int k = 0; k < n; k++) s += A[i * n + k] * A[j * n + k];
            if (skew) s += B[i * n + j] - B[j * n + i];
            M[i * n + j] = s;
        }
}

/* A P-matrix that is not positive definite: a permuted triangular matrix with a positive
 * diagonal and large off-diagonal entries (all principal minors = products of the diagonal),
 * slightly perturbed; kept only when the principal minors confirm the P property. */
static int random_P_triangular(rng *r, int n, double *M)
{
    int perm[LCP_STACK_N];
    for (int i = 0; i < n; i++) perm[i] = i;
    for (int i = n - 1; i > 0; i--) {
        const int j = rng_int(r, i + 1), t = perm[i];
        perm[i] = perm[j];
        perm[j] = t;
    }
    double U[LCP_STACK_N * LCP_STACK_N];
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            U[i * n + j] = (i == j) ? rng_range(r, 0.5, 2.0) : (j > i ? rng_range(r, -5.0, 5.0) : rng_range(r, -0.01, 0.01));
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) M[perm[i] * n + perm[j]] = U[i * n + j];
    return is_P_matrix(n, M);
}

static void test_general(checks *T, stats *st)
{
    rng r = {77u};
    double M[LCP_STACK_N * LCP_STACK_N], q[LCP_STACK_N], z_ref[LCP_STACK_N];
    /* P-matrices: symmetric PD, non-symmetric PD, permuted triangular, diagonally dominant */
    for (int i = 0; i < 4000; i++) {
        const int n = 2 + i % (LCP_STACK_N - 1), kind = (i / 7) % 4;
        switch (kind) {
        case 0: random_pd(&r, n, M, 0); break;
        case 1: random_pd(&r, n, M, 1); break;
        case 2: if (!random_P_triangular(&r, n, M)) continue; break;
        default:
            random_matrix(&r, n, M);
            for (int a = 0; a < n; a++) {
                double s = 0.0;
                for (int b = 0; b < n; b++) s += (a == b) ? 0.0 : fabs(M[a * n + b]);
                M[a * n + a] = s + rng_range(&r, 0.01, 1.0);
            }
        }
        if (kind < 2 && !is_P_matrix(n, M)) continue;  /* only near-singular draws are skipped */
        const double qs = rng_decades(&r, -3, 3);
        for (int a = 0; a < n; a++) q[a] = qs * rng_range(&r, -1.0, 1.0);
        check_context(T, "P-matrix kind %d, n = %d, case %d", kind, n, i);
        const int found = enumerate_solution(n, M, q, z_ref);
        CHECK_INT(1, found);
        general_case(T, st, n, M, q, found == 1 ? z_ref : NULL, 1e-10);
        st->pmatrix_cases++;
        /* z is invariant under scaling (M, q) by c > 0; and (M, d q) has the solution d z */
        const double c = rng_decades(&r, -12, 12), dq = rng_decades(&r, -12, 12);
        double Mc[LCP_STACK_N * LCP_STACK_N], qc[LCP_STACK_N], zc[LCP_STACK_N];
        for (int a = 0; a < n * n; a++) Mc[a] = c * M[a];
        for (int a = 0; a < n; a++) qc[a] = c * q[a];
        check_context(T, "P-matrix kind %d, n = %d, case %d, (M, q) scaled by %.3g", kind, n, i, c);
        general_case(T, st, n, Mc, qc, found == 1 ? z_ref : NULL, 1e-10);
        for (int a = 0; a < n; a++) { qc[a] = dq * q[a]; zc[a] = dq * z_ref[a]; }
        check_context(T, "P-matrix kind %d, n = %d, case %d, q scaled by %.3g", kind, n, i, dq);
        general_case(T, st, n, M, qc, found == 1 ? zc : NULL, 1e-10);
    }
    /* positive semi-definite singular M (rank < n, optionally plus a skew part) with a feasible q:
     * q = w* - M z* with z* >= 0 and w* > 0, so M z* + q = w* > 0 is strictly feasible and stays
     * feasible after rounding; Lemke must find a solution (a PSD M is copositive-plus). The
     * complementary construction (w* = 0 on the support of z*) is exactly degenerate and, with
     * real entries, becomes infeasible or not at random once M and q are rounded: it is tested
     * with exactly representable data in test_degenerate. */
    for (int i = 0; i < 3000; i++) {
        const int n = 2 + i % (LCP_STACK_N - 1), rank = 1 + rng_int(&r, n - 1), skew = (i / 7) % 2;
        double B[LCP_STACK_N * LCP_STACK_N], S[LCP_STACK_N * LCP_STACK_N], zs[LCP_STACK_N], ws[LCP_STACK_N];
        random_matrix(&r, n, B);
        random_matrix(&r, n, S);
        for (int a = 0; a < n; a++)
            for (int b = 0; b < n; b++) {
                double s = 0.0;
                for (int k = 0; k < rank; k++) s += B[a * n + k] * B[b * n + k];
                M[a * n + b] = s + (skew ? S[a * n + b] - S[b * n + a] : 0.0);
            }
        for (int a = 0; a < n; a++) {
            zs[a] = rng_uniform(&r) < 0.5 ? rng_range(&r, 0.0, 1.0) : 0.0;
            ws[a] = rng_range(&r, 0.01, 1.0);
        }
        for (int a = 0; a < n; a++) {
            double s = ws[a];
            for (int b = 0; b < n; b++) s -= M[a * n + b] * zs[b];
            q[a] = s;
        }
        check_context(T, "PSD singular, n = %d, rank %d, skew %d, case %d", n, rank, skew, i);
        general_case(T, st, n, M, q, NULL, 1e-10);
        st->psd_cases++;
    }
    T->context = NULL;
}

/* Degenerate integer problems (many ties in the ratio test): the lexicographic rule must not
 * cycle. P-matrices (diagonally dominant integer) against enumeration; PSD integer B B^T with a
 * feasible q. */
static void test_degenerate(checks *T, stats *st)
{
    rng r = {4242u};
    double M[LCP_STACK_N * LCP_STACK_N], q[LCP_STACK_N], z_ref[LCP_STACK_N];
    for (int i = 0; i < 2000; i++) {
        const int n = 2 + i % (LCP_STACK_N - 1);
        for (int a = 0; a < n; a++) {
            double s = 0.0;
            for (int b = 0; b < n; b++) {
                M[a * n + b] = (a == b) ? 0.0 : (double)(rng_int(&r, 3) - 1);
                s += fabs(M[a * n + b]);
            }
            M[a * n + a] = s + 1.0;
            q[a] = (i % 2) ? -1.0 : (double)(rng_int(&r, 5) - 2);
        }
        check_context(T, "degenerate integer P-matrix, n = %d, case %d", n, i);
        /* the enumeration may count a solution twice at a degenerate point (w_i = z_i = 0): the
         * P-matrix solution is unique, so only the first one is used */
        const int found = enumerate_solution(n, M, q, z_ref);
        CHECK(found >= 1);
        general_case(T, st, n, M, q, found >= 1 ? z_ref : NULL, 1e-12);
        /* the same degenerate problem scaled by a power of two (exact): same z */
        const double c = ldexp(1.0, rng_int(&r, 161) - 80);
        double Mc[LCP_STACK_N * LCP_STACK_N], qc[LCP_STACK_N];
        for (int a = 0; a < n * n; a++) Mc[a] = c * M[a];
        for (int a = 0; a < n; a++) qc[a] = c * q[a];
        check_context(T, "degenerate integer P-matrix, n = %d, case %d, scaled by %g", n, i, c);
        general_case(T, st, n, Mc, qc, found >= 1 ? z_ref : NULL, 1e-12);
        st->integer_cases++;
    }
    for (int i = 0; i < 2000; i++) {
        const int n = 2 + i % (LCP_STACK_N - 1), rank = 1 + rng_int(&r, n);
        double B[LCP_STACK_N * LCP_STACK_N], zs[LCP_STACK_N], ws[LCP_STACK_N];
        for (int a = 0; a < n * n; a++) B[a] = (double)(rng_int(&r, 3) - 1);
        for (int a = 0; a < n; a++)
            for (int b = 0; b < n; b++) {
                double s = 0.0;
                for (int k = 0; k < rank; k++) s += B[a * n + k] * B[b * n + k];
                M[a * n + b] = s;
            }
        for (int a = 0; a < n; a++) {
            const int in_support = rng_int(&r, 2);
            zs[a] = in_support ? (double)rng_int(&r, 3) : 0.0;
            ws[a] = in_support ? 0.0 : (double)rng_int(&r, 3);
        }
        for (int a = 0; a < n; a++) {
            double s = ws[a];
            for (int b = 0; b < n; b++) s -= M[a * n + b] * zs[b];
            q[a] = s;
        }
        check_context(T, "degenerate integer PSD, n = %d, rank %d, case %d", n, rank, i);
        general_case(T, st, n, M, q, NULL, 1e-12);
        st->integer_cases++;
    }
    T->context = NULL;
}

/* Infeasible problems end in a ray, within a few pivots (no looping). */
static void ray_case(checks *T, int n, const double *M, const double *q, const char *what)
{
    double z[LCP_STACK_N], w[LCP_STACK_N];
    int zb[LCP_STACK_N], piv = -1;
    check_context(T, "infeasible: %s", what);
    CHECK_INT(LCP_RAY, lcp_lemke(n, M, q, BIG_BUDGET, z, w, zb, &piv));
    CHECK_RANGE(1, 2 * n + 2, piv);
    T->context = NULL;
}

static void test_infeasible(checks *T)
{
    const double M1[1] = {-1}, q1[1] = {-1};
    ray_case(T, 1, M1, q1, "M = [[-1]], q = [-1]");
    const double M0[1] = {0}, q0[1] = {-1};
    ray_case(T, 1, M0, q0, "M = [[0]], q = [-1]");
    /* skew-symmetric (copositive-plus): w2 = -z1 - 1 < 0 always */
    const double Ms[4] = {0, 1, -1, 0}, qs[2] = {-1, -1};
    ray_case(T, 2, Ms, qs, "M = [[0,1],[-1,0]], q = (-1,-1)");
    /* the friction matrix with a negative friction limit: w1 + w2 = -2 < 0 */
    const double Mf[4] = {1, -1, -1, 1}, qf[2] = {-1, -1};
    ray_case(T, 2, Mf, qf, "M = [[1,-1],[-1,1]], q = (-1,-1)");
    const double Mz[4] = {0, 0, 0, 0}, qz[2] = {-1, 1};
    ray_case(T, 2, Mz, qz, "M = 0, q = (-1, 1)");
    /* PSD rank one with q outside the cone: w1 + w2 = (z1 - z2)(1 - 1) - 1 - 0.5 < 0 */
    const double Mp[9] = {1, -1, 0, -1, 1, 0, 0, 0, 2}, qp[3] = {-1, -0.5, 1};
    ray_case(T, 3, Mp, qp, "PSD rank one 3x3, infeasible q");
}

/* The pivot budget is exact: a problem needing k pivots is solved with max_pivots = k and
 * reported as LCP_MAX_PIVOTS with k - 1. */
static void test_budget(checks *T)
{
    double z[LCP_STACK_N], w[LCP_STACK_N];
    int zb[LCP_STACK_N], piv = -1;
    /* the friction LCP in forward slip needs 2 pivots */
    const double M[4] = {10, -10, -10, 10}, q[2] = {0.4 - 1.0, 0.4 + 1.0};
    CHECK_INT(LCP_OK, lcp_lemke(2, M, q, 16, z, w, zb, &piv));
    CHECK_INT(2, piv);
    CHECK_INT(LCP_MAX_PIVOTS, lcp_lemke(2, M, q, 1, z, w, zb, &piv));
    CHECK_INT(1, piv);
    CHECK_INT(LCP_OK, lcp_lemke(2, M, q, 2, z, w, zb, &piv));
    /* random P-matrices with n = 8 */
    rng r = {99u};
    double P[LCP_STACK_N * LCP_STACK_N], qq[LCP_STACK_N];
    int tested = 0;
    for (int i = 0; i < 200; i++) {
        const int n = LCP_STACK_N;
        random_pd(&r, n, P, 1);
        for (int a = 0; a < n; a++) qq[a] = rng_range(&r, -1.0, 1.0);
        int k = -1;
        if (lcp_lemke(n, P, qq, BIG_BUDGET, z, w, zb, &k) != LCP_OK || k < 2) continue;
        tested++;
        check_context(T, "pivot budget, case %d needing %d pivots", i, k);
        CHECK_INT(LCP_OK, lcp_lemke(n, P, qq, k, z, w, zb, &piv));
        CHECK_INT(k, piv);
        CHECK_INT(LCP_MAX_PIVOTS, lcp_lemke(n, P, qq, k - 1, z, w, zb, &piv));
        CHECK_INT(k - 1, piv);
        CHECK_INT(LCP_MAX_PIVOTS, lcp_lemke(n, P, qq, 1, z, w, zb, &piv));
    }
    T->context = NULL;
    CHECK(tested > 100);
    /* q >= 0 needs no pivot at all, whatever the budget */
    const double qp[2] = {1, 0};
    CHECK_INT(LCP_OK, lcp_lemke(2, M, qp, 0, z, w, zb, &piv));
    CHECK_INT(0, piv);
}

static void test_bad_input(checks *T)
{
    double z[LCP_STACK_N + 1], w[LCP_STACK_N + 1];
    int zb[LCP_STACK_N + 1], piv = -1;
    double M[4] = {1, 0, 0, 1}, q[2] = {-1, -1};
    const double bad[] = {NAN, INFINITY, -INFINITY};
    for (int b = 0; b < 3; b++) {
        for (int i = 0; i < 4; i++) {
            const double keep = M[i];
            M[i] = bad[b];
            piv = -1;
            CHECK_INT(LCP_BAD_INPUT, lcp_lemke(2, M, q, 16, z, w, zb, &piv));
            CHECK_INT(0, piv);
            M[i] = keep;
        }
        for (int i = 0; i < 2; i++) {
            const double keep = q[i];
            q[i] = bad[b];
            CHECK_INT(LCP_BAD_INPUT, lcp_lemke(2, M, q, 16, z, w, zb, &piv));
            q[i] = keep;
        }
    }
    /* a NaN in q where q >= 0 otherwise (z = 0 would "solve" it) */
    const double qn[2] = {1, NAN};
    CHECK_INT(LCP_BAD_INPUT, lcp_lemke(2, M, qn, 16, z, w, zb, &piv));
    double big[(LCP_STACK_N + 1) * (LCP_STACK_N + 1)] = {0}, qb[LCP_STACK_N + 1] = {0};
    for (int i = 0; i <= LCP_STACK_N; i++) big[i * (LCP_STACK_N + 1) + i] = 1.0;
    CHECK_INT(LCP_BAD_INPUT, lcp_lemke(0, M, q, 16, z, w, zb, &piv));
    CHECK_INT(LCP_BAD_INPUT, lcp_lemke(-1, M, q, 16, z, w, zb, &piv));
    CHECK_INT(LCP_BAD_INPUT, lcp_lemke(LCP_STACK_N + 1, big, qb, 16, z, w, zb, &piv));
    CHECK_INT(LCP_OK, lcp_lemke(LCP_STACK_N, big, qb, 16, z, w, zb, &piv));  /* the largest valid n */
    CHECK(lcp_status_text(LCP_BAD_INPUT) != NULL && lcp_status_text((lcp_status)42) != NULL);
}

/* ---- regressions and findings ---------------------------------------------------------------- */

/* Regression (failed before d961b44): a feasible, exactly representable PSD problem (M = B B^T,
 * integer, rank 5 of 7) with a known solution z* = (2, 1, 0, 0, 0, 0, 2) ended in a ray after
 * 6 pivots. At the 4th pivot four rows tie exactly in the ratio test (ratio 1, z0's row among
 * them: z0 must leave); rounding made the ratios differ by ~6e-15 relative, more than the 1e-15
 * tie tolerance of ratio_test, so another row left and the path ended in a ray. */
static void regression_tie_tolerance(checks *T)
{
    const double M[49] = {5, -3, -3, 1, 2, -1, -1,  -3, 3, 3, -2, 0, 2, 1,  -3, 3, 5, -1, 0, 1, -1,
                          1, -2, -1, 3, -2, -3, -2,  2, 0, 0, -2, 4, 2, 1,  -1, 2, 1, -3, 2, 3, 2,
                          -1, 1, -1, -2, 1, 2, 3};
    const double q[7] = {-5, 1, 5, 4, -4, -4, -5}, z_star[7] = {2, 1, 0, 0, 0, 0, 2};
    double z[7], w[7];
    int zb[7], piv = -1;
    check_context(T, "regression: degenerate integer PSD 7x7 (ratio-test tie tolerance)");
    for (int i = 0; i < 7; i++) {  /* z* really solves it (exact integer arithmetic) */
        double wi = q[i];
        for (int j = 0; j < 7; j++) wi += M[i * 7 + j] * z_star[j];
        CHECK(wi >= 0.0 && wi * z_star[i] == 0.0);
    }
    const lcp_status s = lcp_lemke(7, M, q, BIG_BUDGET, z, w, zb, &piv);
    if (CHECK_INT(LCP_OK, s)) verify(T, 7, M, q, z, w, 1e-12);
    T->context = NULL;
}

/* Regression (failed before d961b44): finite input, LCP_OK, infinite output. With a subnormal
 * m_hat the pivot 1 / pr[col] overflowed to +inf, so z = inf where z = p_hat / m_hat = 1. */
static void regression_subnormal_pivot(checks *T)
{
    const double mh = 1e-310, p = 1e-310, M[4] = {mh, -mh, -mh, mh}, q[2] = {-p, p};
    double z[2], w[2];
    int zb[2], piv = -1;
    check_context(T, "regression: friction LCP m_hat = p_hat = 1e-310, muN = 0 (pivot overflow)");
    if (CHECK_INT(LCP_OK, lcp_lemke(2, M, q, 16, z, w, zb, &piv))) CHECK_NEAR(1.0, z[0] - z[1], 1e-12);
    T->context = NULL;
}

/* Regression (failed before e7d2575): the solution of (c M, c q) is that of (M, q) for any c > 0,
 * and here c = 2^-58 is exact. M = c [[2, 1], [1, 2]], q = -c (1, 1), solution z = (1/3, 1/3).
 *   f177924 (tol = 1e-13 colmax mixed the unscaled identity/z0 entries with the scaled ones):
 *     LCP_RAY after 2 pivots;
 *   d961b44 (tie = 1e-12 (rhsmax + 1) / colmax: the "+ 1" is absolute, so for small data every
 *     ratio was a "tie"): LCP_OK with z = (0, 0.5), w reported (0, 0), but M z + q = (-c/2, 0),
 *     a wrong answer reported as a solution.
 * Solving the normalised problem (M / max|M_ij|, q / max|q_i|) makes every tolerance relative. */
static void regression_scale(checks *T)
{
    const double c = 0x1p-58, M[4] = {2 * c, c, c, 2 * c}, q[2] = {-c, -c};
    double z[2], w[2];
    int zb[2], piv = -1;
    check_context(T, "regression: M = 2^-58 [[2,1],[1,2]], q = -2^-58 (1,1) (scale invariance)");
    if (CHECK_INT(LCP_OK, lcp_lemke(2, M, q, 16, z, w, zb, &piv))) {
        verify(T, 2, M, q, z, w, 1e-12);
        CHECK_NEAR(1.0 / 3.0, z[0], 1e-12);
        CHECK_NEAR(1.0 / 3.0, z[1], 1e-12);
    }
    T->context = NULL;
}


/* ---- 3. the box LCP of a tridiagonal M --------------------------------------------------------- */

/* The dense solve of the mode set s[] (s[i] in -1, 0, 1; rows with l = 0: free, w = 0) for the box
 * problem (d, e, q, l); fix[i] (may be NULL): row i fixed at z = zf[i]. z and w = M z + q out. */
static int box_dense(int n, const double *d, const double *e, const double *q, const double *l, const int *s,
                     const int *fix, const double *zf, double *z, double *w)
{
    double A[LCP_STACK_N * LCP_STACK_N] = {0}, b[LCP_STACK_N] = {0};
    for (int i = 0; i < n; i++) {
        if ((fix && fix[i]) || (s[i] == 0 && l[i] > 0.0)) {
            A[i * n + i] = 1.0;
            b[i] = (fix && fix[i]) ? zf[i] : 0.0;
            continue;
        }
        A[i * n + i] = d[i];
        if (i > 0) A[i * n + i - 1] = e[i - 1];
        if (i + 1 < n) A[i * n + i + 1] = e[i];
        b[i] = -q[i] - ((l[i] > 0.0) ? s[i] * l[i] : 0.0);
    }
    if (gauss(n, A, b, z) == 0.0) return 0;
    for (int i = 0; i < n; i++) {
        w[i] = q[i] + d[i] * z[i];
        if (i > 0) w[i] += e[i - 1] * z[i - 1];
        if (i + 1 < n) w[i] += e[i] * z[i + 1];
    }
    return 1;
}

/* The solution by enumeration of the 3^n mode sets: the one z of every feasible set (M positive
 * definite: unique); returns the number of feasible sets, *spread their largest disagreement. */
static int box_enumerate(int n, const double *d, const double *e, const double *q, const double *l, double *z_out,
                         double *spread)
{
    int s[LCP_STACK_N], found = 0;
    double sc = 0.0;
    for (int i = 0; i < n; i++) sc = fmax(sc, (fabs(q[i]) + l[i]) / d[i]);
    *spread = 0.0;
    int total = 1;
    for (int i = 0; i < n; i++) total *= 3;
    for (int code = 0; code < total; code++) {
        int c = code, skip = 0;
        for (int i = 0; i < n; i++) {
            s[i] = c % 3 - 1;
            c /= 3;
            if (!(l[i] > 0.0) && s[i] != 0) skip = 1; /* a frictionless row is free: one of its 3 */
        }
        if (skip) continue;
        double z[LCP_STACK_N], w[LCP_STACK_N];
        if (!box_dense(n, d, e, q, l, s, NULL, NULL, z, w)) continue;
        int ok = 1;
        for (int i = 0; i < n && ok; i++) {
            if (!(l[i] > 0.0)) continue;
            const double tol = 1e-12 * (fabs(q[i]) + l[i] + d[i] * sc);
            if (s[i] == 0) ok = fabs(w[i]) <= l[i] + tol;
            else ok = s[i] * z[i] >= -1e-12 * sc;
        }
        if (!ok) continue;
        if (found == 0)
            for (int i = 0; i < n; i++) z_out[i] = z[i];
        else
            for (int i = 0; i < n; i++) *spread = fmax(*spread, fabs(z[i] - z_out[i]) / (sc + 1e-300));
        found++;
    }
    return found;
}

/* The box conditions on an answer of lcp_box: w = M z + q (to rounding), |w| <= l, the sides
 * exact (z > 0: w = -l, z < 0: w = l), held rows at z = 0 exactly, modes the signs of z. Returns
 * the relative residual of w = M z + q. */
static double box_verify(checks *T, int n, const double *d, const double *e, const double *q, const double *l,
                         const int *mode, const double *z, const double *w, double tol, double sign_tol)
{
    double res = 0.0, zs = 0.0;
    for (int i = 0; i < n; i++) zs = fmax(zs, fabs(z[i]));
    for (int i = 0; i < n; i++) {
        double r = q[i] + d[i] * z[i], a = fabs(q[i]) + fabs(d[i] * z[i]);
        if (i > 0) { r += e[i - 1] * z[i - 1]; a += fabs(e[i - 1] * z[i - 1]); }
        if (i + 1 < n) { r += e[i] * z[i + 1]; a += fabs(e[i] * z[i + 1]); }
        res = fmax(res, fabs(w[i] - r) / (a + l[i] + 1e-300));
        CHECK(isfinite(z[i]) && isfinite(w[i]));
        CHECK(fabs(w[i]) <= l[i] * (1.0 + 1e-12) + tol * (fabs(q[i]) + l[i]));
        if (l[i] > 0.0) {
            /* the side: held at z = 0 exactly, or w at the limit against the motion (its sign
             * exact where the pivoting's rule is exact, sign_tol of the scale after the fallback) */
            if (mode[i] == 0) CHECK_SAME(0.0, z[i]);
            else CHECK_SAME(-mode[i] * l[i], w[i]);
            CHECK(mode[i] * z[i] >= -sign_tol * zs);
            if (sign_tol == 0.0 && z[i] > 0.0) CHECK_SAME(-l[i], w[i]);
            if (sign_tol == 0.0 && z[i] < 0.0) CHECK_SAME(l[i], w[i]);
        } else {
            CHECK_SAME(0.0, w[i]);
            CHECK_INT((z[i] > 0.0) - (z[i] < 0.0), mode[i]);
        }
    }
    CHECK_RANGE(0.0, tol, res);
    return res;
}

static void test_box(checks *T)
{
    rng r = {0x9E3779B97F4A7C15ull};
    long cases = 0, fallback = 0, multi = 0;
    int max_piv = 0;
    double worst_enum = 0.0, worst_res = 0.0;
    for (int trial = 0; trial < 4000; trial++) {
        const int n = 1 + trial % 6;
        const int kind = (trial / 6) % 5; /* 0 random, 1 ties on the limits, 2 frictionless rows, 3 stiff, 4 tiny l */
        double d[6], e[6], q[6], l[6], z[6], w[6], work[12], z_enum[6], spread;
        int mode[6];
        for (int i = 0; i < n; i++) {
            l[i] = rng_range(&r, 0.0, 2.0);
            q[i] = rng_range(&r, -3.0, 3.0);
            mode[i] = rng_int(&r, 3) - 1;
        }
        if (kind == 3) { /* masses on stiff springs: M = a + K, K = k tridiag(-1, 2, -1), far from diagonal dominance */
            const double k = rng_decades(&r, 3, 7);
            for (int i = 0; i < n; i++) d[i] = rng_decades(&r, -1, 1) + 2.0 * k;
            for (int i = 0; i + 1 < n; i++) e[i] = -k;
        } else {
            for (int i = 0; i < n; i++) d[i] = rng_decades(&r, -1, 2);
            for (int i = 0; i + 1 < n; i++) e[i] = -rng_range(&r, 0.0, 0.45) * fmin(d[i], d[i + 1]);
        }
        if (n > 0) e[n - 1] = NAN; /* not part of the problem: must not be read */
        if (kind == 1) for (int i = 0; i < n; i += 2) q[i] = (i % 4 ? -1.0 : 1.0) * l[i];
        if (kind == 2) for (int i = 0; i < n; i += 2) l[i] = 0.0;
        if (kind == 4) for (int i = 0; i < n; i++) l[i] *= 1e-9;
        const int found = box_enumerate(n, d, e, q, l, z_enum, &spread);
        check_context(T, "box LCP trial %d, n = %d, kind %d", trial, n, kind);
        CHECK(found >= 1);
        CHECK_RANGE(0.0, 1e-9, spread);
        if (found > 1) multi++;
        int piv = -1;
        CHECK_INT(LCP_OK, lcp_box((size_t)n, d, e, q, l, mode, z, w, work, &piv));
        CHECK(piv >= 0);
        if (piv >= 8 * n + 32) fallback++;

        if (piv > max_piv) max_piv = piv;
        const int fell_back = piv >= 8 * n + 32; /* (the polish accepts 1e-10 of the scale) */
        worst_res = fmax(worst_res, box_verify(T, n, d, e, q, l, mode, z, w, (kind == 3) ? 1e-9 : 1e-12,
                                               fell_back ? 1e-9 : 0.0));
        double sc = 1e-300;
        for (int i = 0; i < n; i++) sc = fmax(sc, fabs(z_enum[i]) + (fabs(q[i]) + l[i]) / d[i]);
        for (int i = 0; i < n; i++) {
            worst_enum = fmax(worst_enum, fabs(z[i] - z_enum[i]) / sc);
            CHECK_NEAR(z_enum[i], z[i], 1e-9 * sc);
        }
        /* from the solution's own modes: no pivot, the same answer */
        int mode2[6];
        double z2[6], w2[6];
        for (int i = 0; i < n; i++) mode2[i] = mode[i];
        int piv2 = -1;
        CHECK_INT(LCP_OK, lcp_box((size_t)n, d, e, q, l, mode2, z2, w2, work, &piv2));
        if (kind != 3) CHECK_INT(0, piv2);
        for (int i = 0; i < n; i++) CHECK_NEAR(z[i], z2[i], 1e-9 * sc);
        cases++;
    }
    /* the basis solve with fixed end rows (a cluster with its ghosts) against the dense solve */
    double worst_basis = 0.0;
    for (int trial = 0; trial < 2000; trial++) {
        const int n = 3 + trial % 4;
        double d[6], e[6], q[6], l[6], z[6], w[6], zr[6], wr[6], zf[6] = {0}, cp[6], dp[6];
        int mode[6], fix[6] = {0};
        for (int i = 0; i < n; i++) {
            d[i] = rng_decades(&r, -1, 2);
            l[i] = (rng_int(&r, 4) == 0) ? 0.0 : rng_range(&r, 0.0, 2.0);
            q[i] = rng_range(&r, -3.0, 3.0);
            mode[i] = rng_int(&r, 3) - 1;
            w[i] = NAN;
        }
        for (int i = 0; i + 1 < n; i++) e[i] = -rng_range(&r, 0.0, 0.45) * fmin(d[i], d[i + 1]);
        const int fl = rng_int(&r, 2), fr = rng_int(&r, 2);
        fix[0] = fl;
        fix[n - 1] = fr;
        zf[0] = rng_range(&r, -1.0, 1.0);
        zf[n - 1] = rng_range(&r, -1.0, 1.0);
        check_context(T, "box basis trial %d, n = %d, fixed %d %d", trial, n, fl, fr);
        lcp_box_basis(0, (size_t)n, fl, zf[0], fr, zf[n - 1], d, e, q, l, mode, z, w, cp, dp);
        CHECK(box_dense(n, d, e, q, l, mode, fix, zf, zr, wr));
        double sc = 1e-300;
        for (int i = 0; i < n; i++) sc = fmax(sc, fabs(zr[i]) + (fabs(q[i]) + l[i]) / d[i]);
        for (int i = 0; i < n; i++) {
            worst_basis = fmax(worst_basis, fabs(z[i] - zr[i]) / sc);
            CHECK_NEAR(zr[i], z[i], 1e-12 * sc);
            if (fix[i]) { CHECK_SAME(zf[i], z[i]); CHECK(isnan(w[i])); continue; } /* fixed rows' w not set */
            if (mode[i] == 0 && l[i] > 0.0) {
                CHECK_SAME(0.0, z[i]);
                CHECK_NEAR(wr[i], w[i], 1e-12 * (fabs(q[i]) + d[i] * sc));
            } else {
                CHECK_SAME((l[i] > 0.0) ? -mode[i] * l[i] : 0.0, w[i]);
            }
        }
    }
    check_context(T, "%s", "");
    printf("box LCP: %ld problems n = 1..6 (random, ties, l = 0, stiff, tiny l) against the 3^n enumeration "
           "(%ld with several feasible mode sets): largest |z - z_enum| %.2e (relative), residual %.2e, "
           "pivots <= %d, %ld through the Gauss-Seidel fallback; basis solve with fixed rows vs dense %.2e\n",
           cases, multi, worst_enum, worst_res, max_piv, fallback, worst_basis);
}

/* The basis solve written row by row, every row's tests inside the loops (a fixed row, a held row, the
 * first and last rows' missing neighbours), then the rows' w in a pass of their own (lcp_box_basis_w):
 * the reference whose operations, in their order, lcp_box_basis and lcp_box_basis_diag keep (diag:
 * each free row's pivot d_i) */
static void ref_box_basis(size_t lo, size_t hi, int fix_lo, double z_lo, int fix_hi, double z_hi, const double *d,
                          const double *e, const double *q, const double *l, const int *mode, double *z, double *w,
                          int diag)
{
    double cp[16], dp[16], cprev = 0.0, dprev = 0.0;
    for (size_t i = lo; i < hi; i++) {
        if ((fix_lo && i == lo) || (fix_hi && i == hi - 1)) {
            cp[i] = 0.0;
            dp[i] = (fix_lo && i == lo) ? z_lo : z_hi;
        } else if (mode[i] == 0 && l[i] > 0.0) {
            cp[i] = 0.0;
            dp[i] = 0.0;
        } else {
            const double lo_e = (i > lo) ? e[i - 1] : 0.0;
            const double rhs = -q[i] - ((l[i] > 0.0) ? mode[i] * l[i] : 0.0);
            const double inv = 1.0 / (diag ? d[i] : d[i] - lo_e * cprev);
            cp[i] = (i + 1 < hi) ? e[i] * inv : 0.0;
            dp[i] = (rhs - lo_e * dprev) * inv;
        }
        cprev = cp[i];
        dprev = dp[i];
    }
    double zn = 0.0;
    for (size_t j = hi; j-- > lo;) {
        zn = dp[j] - cp[j] * zn;
        z[j] = zn;
    }
    if (hi - (size_t)fix_hi > lo + (size_t)fix_lo)
        lcp_box_basis_w(lo, hi, lo + (size_t)fix_lo, hi - (size_t)fix_hi, e, q, l, mode, z, w);
}

/* lcp_box_basis and lcp_box_basis_diag (an M with zeros off the diagonal, of either sign) bit for bit
 * the row-by-row reference, on sub-ranges [lo, hi) of 1 to 9 rows with every choice of fixed ends,
 * held, sliding and frictionless rows, zeros of either sign among q and the fixed values, and the
 * entries outside the range (and the fixed rows' w) left as they were */
static void test_box_basis_forms(checks *T)
{
    rng r = {0x243F6A8885A308D3ull};
    long cases = 0;
    for (int trial = 0; trial < 6000; trial++) {
        const size_t lo = (size_t)rng_int(&r, 3), len = 1 + (size_t)(trial % 9), hi = lo + len;
        const int diag = (trial / 9) % 2, fl = rng_int(&r, 2), fh = rng_int(&r, 2);
        double d[16], e[16], q[16], l[16], z[16], w[16], zr[16], wr[16], cp[16], dp[16];
        int mode[16];
        for (size_t i = 0; i < 16; i++) {
            d[i] = rng_decades(&r, -1, 2);
            e[i] = diag ? ((rng_int(&r, 2) == 0) ? 0.0 : -0.0) : -rng_range(&r, 0.0, 0.45) * d[i];
            l[i] = (rng_int(&r, 4) == 0) ? 0.0 : rng_range(&r, 0.0, 2.0);
            q[i] = (rng_int(&r, 8) == 0) ? ((rng_int(&r, 2) == 0) ? 0.0 : -0.0) : rng_range(&r, -3.0, 3.0);
            mode[i] = rng_int(&r, 3) - 1;
            z[i] = zr[i] = w[i] = wr[i] = (double)i + 0.5; /* (untouched outside the range) */
        }
        const double zl = (rng_int(&r, 4) == 0) ? -0.0 : rng_range(&r, -1.0, 1.0), zh = rng_range(&r, -1.0, 1.0);
        check_context(T, "box basis forms trial %d, [%zu, %zu), fixed %d %d, diag %d", trial, lo, hi, fl, fh, diag);
        if (diag) lcp_box_basis_diag(lo, hi, fl, zl, fh, zh, d, e, q, l, mode, z, w, cp, dp);
        else lcp_box_basis(lo, hi, fl, zl, fh, zh, d, e, q, l, mode, z, w, cp, dp);
        ref_box_basis(lo, hi, fl, zl, fh, zh, d, e, q, l, mode, zr, wr, diag);
        for (size_t i = 0; i < 16; i++) {
            CHECK_SAME(zr[i], z[i]);
            CHECK_SAME(wr[i], w[i]);
        }
        cases++;
    }
    check_context(T, "%s", "");
    printf("box basis solve: %ld problems (1 to 9 rows, fixed ends, diagonal M) bit for bit the row-by-row "
           "reference\n", cases);
}

int main(void)
{
    checks C = {0, 0, NULL, {0}}, *T = &C;
    stats st = {0};
    test_friction(T, &st);
    test_general(T, &st);
    test_degenerate(T, &st);
    test_infeasible(T);
    test_budget(T);
    test_bad_input(T);
    regression_tie_tolerance(T);
    regression_subnormal_pivot(T);
    regression_scale(T);
    test_box(T);
    test_box_basis_forms(T);
    printf("friction LCP: %ld cases (%ld degenerate/extreme), max pivots %d, max relative residual %.2e, "
           "max error vs closed form %.2e (on the velocity scale (|p|+muN)/m_hat)\n",
           st.friction_cases, st.friction_degenerate, st.friction_pivots_max, st.friction_residual,
           st.friction_closed_form);
    printf("general n: %ld P-matrix, %ld PSD-singular and %ld degenerate integer cases, max pivots %d, max relative residual %.2e, "
           "max relative difference to enumeration %.2e\n",
           st.pmatrix_cases, st.psd_cases, st.integer_cases, st.general_pivots_max, st.general_residual, st.general_vs_enum);
    printf("warm starts: %ld solves from every complementary basis (%ld accepted with 0 pivots), all "
           "solutions, the friction problem's active pair as cold\n",
           st.warm_cases, st.warm_zero_pivot);
    printf("n = 2, revised form against the tableau: %ld cases, same status, pivots and basis, max relative "
           "difference %.2e\n",
           st.revised_vs_tableau_cases, st.revised_vs_tableau);
    return checks_done(T, "test_lcp");
}
