/* Lemke's algorithm for any size (fmu_src/numerics/lcp.h, the *_ws entry points and their workspace).
 *
 * 1. Random LCPs with P-matrices of sizes 1 to 256, three kinds: M = A A' / n + D (symmetric
 *    positive definite), M diagonally dominant by rows (non-symmetric), M = A A' / n + D + S with S
 *    skew (non-symmetric positive definite). Every answer: z >= 0, w >= 0, z . w = 0 and
 *    w = M z + q to 1e-12 of the problem's scale; z against an independent solver written here
 *    (projected Gauss-Seidel for a start, then Murty's least-index principal pivoting, finite for
 *    P-matrices, each basis solved by its own Gaussian elimination). The warm start from the
 *    solution's active set: 0 pivots and the same z; from a wrong one: the cold answer bit for bit.
 * 2. Up to LCP_STACK_N the workspace entry points give the bits of the ones without a workspace.
 * 3. Degenerate problems: q = 0, q >= 0 (z = 0, no pivot), ties (M = I + 1 1', q = -1: every row ties
 *    in every ratio test; closed form z = 1 / (n + 1)), zeros in q with a P-matrix, and a problem on
 *    which the minimum-ratio test with ties broken by the least row cycles (shown with that rule
 *    written here) while the lexicographic rule solves it.
 * 4. The workspace: made and freed through the caller's callbacks (every block released), a failed
 *    allocation (NULL, nothing leaked), n out of range, a problem larger than the workspace.
 * 5. The box LCP of a dense positive definite M (lcp_box_dense), n = 1 to 64: the box conditions to
 *    1e-12, z against a reference written here (projected Gauss-Seidel, then its modes' free rows
 *    solved by Gauss-Jordan and flipped until every row is in its box), rows without friction
 *    (l = 0), warm starts from the solution's modes (no pivot), a tridiagonal M posed densely (as
 *    lcp_box), q = 0, q on the boxes' edges, and the input it refuses. */
#include "check.h"
#include "lcp.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NMAX 256
#define BUDGET 100000

/* ---- a counting allocator ---------------------------------------------------------------------- */

typedef struct {
    long live, made, fail_after; /* fail_after >= 0: that many allocations succeed, then NULL */
} counter;

static void *count_alloc(void *env, size_t nobj, size_t size)
{
    counter *c = (counter *)env;
    if (c->fail_after >= 0 && c->made >= c->fail_after) return NULL;
    void *p = calloc(nobj, size);
    if (p) {
        c->live++;
        c->made++;
    }
    return p;
}

static void count_free(void *env, void *p)
{
    counter *c = (counter *)env;
    if (p) c->live--;
    free(p);
}

/* ---- the independent solver -------------------------------------------------------------------- */

/* Solve M_JJ x = -q_J (k = |J|) into z (0 off J) by Gauss-Jordan elimination with row pivoting on
 * the augmented matrix held by columns (A: column c of k entries at A + c k, the right-hand side
 * last; k (k + 1) doubles): not the row elimination of the solver under test. 0 when singular. */
static int solve_basis(int n, const double *M, const double *q, const int *in, double *z, double *A, int *J)
{
    int k = 0;
    for (int i = 0; i < n; i++) {
        z[i] = 0.0;
        if (in[i]) J[k++] = i;
    }
    for (int c = 0; c <= k; c++)
        for (int r = 0; r < k; r++) A[c * k + r] = (c < k) ? M[J[r] * n + J[c]] : -q[J[r]];
    for (int c = 0; c < k; c++) {
        double *col = A + c * k;
        int p = c;
        for (int r = c; r < k; r++) p = fabs(col[r]) > fabs(col[p]) ? r : p;
        const double piv = col[p];
        if (piv == 0.0) return 0;
        for (int cc = c; cc <= k; cc++) { /* swap rows c and p, then scale row c to a unit pivot */
            double *x = A + cc * k;
            const double t = x[p];
            x[p] = x[c];
            x[c] = t / piv;
        }
        for (int cc = k; cc >= c; cc--) { /* clear column c in every other row, the pivot column last */
            double *x = A + cc * k;
            for (int r = 0; r < k; r++)
                if (r != c) x[r] -= col[r] * x[c];
        }
    }
    for (int r = 0; r < k; r++) z[J[r]] = A[k * k + r];
    return 1;
}

static double scale_of(int n, const double *M, const double *q, const double *z)
{
    double s = 0.0;
    for (int i = 0; i < n; i++) {
        double a = fabs(q[i]);
        for (int j = 0; j < n; j++) a += fabs(M[i * n + j] * z[j]);
        s = fmax(s, a);
    }
    return s;
}

/* The reference: projected Gauss-Seidel (converges for the matrices posed here: positive definite
 * or diagonally dominant with a positive diagonal) names a basis, Murty's least-index rule (flip
 * the infeasible pair of least index) finishes from it. Returns the pivots, -1 on failure. */
static int reference(int n, const double *M, const double *q, double *z, double *A, int *J, int *in)
{
    double w[NMAX];
    for (int i = 0; i < n; i++) z[i] = 0.0;
    for (int sweep = 0; sweep < 200; sweep++) {
        double dz = 0.0, zs = 0.0;
        for (int i = 0; i < n; i++) {
            double r = q[i] - M[i * n + i] * z[i];
            for (int j = 0; j < n; j++) r += M[i * n + j] * z[j];
            const double v = fmax(0.0, -r / M[i * n + i]);
            dz = fmax(dz, fabs(v - z[i]));
            zs = fmax(zs, v);
            z[i] = v;
        }
        if (dz <= 1e-6 * zs) break; /* the basis is settled long before; Murty's rule finishes */
    }
    for (int i = 0; i < n; i++) in[i] = z[i] > 0.0;
    for (int it = 0; it < 100 * n + 100; it++) {
        if (!solve_basis(n, M, q, in, z, A, J)) return -1;
        const double tol = 1e-13 * scale_of(n, M, q, z);
        int flip = -1;
        for (int i = 0; i < n && flip < 0; i++) {
            double r = q[i];
            for (int j = 0; j < n; j++) r += M[i * n + j] * z[j];
            w[i] = in[i] ? 0.0 : r;
            if ((in[i] && z[i] < -tol) || (!in[i] && w[i] < -tol)) flip = i;
        }
        if (flip < 0) {
            for (int i = 0; i < n; i++) z[i] = fmax(z[i], 0.0);
            return it;
        }
        in[flip] = !in[flip];
    }
    return -1;
}

/* max |a - ref| / max |ref| (absolute when ref = 0) */
static double rel_diff(int n, const double *a, const double *ref)
{
    double d = 0.0, s = 0.0;
    for (int i = 0; i < n; i++) {
        d = fmax(d, fabs(a[i] - ref[i]));
        s = fmax(s, fabs(ref[i]));
    }
    return s > 0.0 ? d / s : d;
}

/* ---- the conditions on an answer --------------------------------------------------------------- */

/* z >= 0, w >= 0, z_i w_i = 0, |w - (M z + q)| and the complementarity z . (M z + q) within tol of
 * the scale; returns the worst relative residual. */
static double complementarity(checks *T, int n, const double *M, const double *q, const double *z, const double *w,
                              double tol)
{
    const double s = scale_of(n, M, q, z);
    double res = 0.0, zmax = 0.0, dot = 0.0;
    for (int i = 0; i < n; i++) {
        double r = q[i];
        for (int j = 0; j < n; j++) r += M[i * n + j] * z[j];
        res = fmax(res, fabs(w[i] - r));
        res = fmax(res, -r); /* M z + q >= 0 as computed */
        zmax = fmax(zmax, z[i]);
        dot += z[i] * fmax(r, 0.0);
        CHECK(z[i] >= 0.0 && w[i] >= 0.0 && z[i] * w[i] == 0.0);
    }
    res = fmax(res, zmax > 0.0 ? dot / zmax : 0.0);
    const double rel = s > 0.0 ? res / s : res;
    CHECK_RANGE(0.0, tol, rel);
    return rel;
}

/* ---- the random problems ----------------------------------------------------------------------- */

enum { SPD, DIAG_DOMINANT, SKEW_PD };

static void random_P(rng *r, int n, int kind, double *M)
{
    static double A[NMAX * NMAX];
    if (kind == DIAG_DOMINANT) {
        for (int i = 0; i < n; i++) {
            double off = 0.0;
            for (int j = 0; j < n; j++)
                if (j != i) {
                    M[i * n + j] = rng_range(r, -1.0, 1.0);
                    off += fabs(M[i * n + j]);
                }
            M[i * n + i] = off * rng_range(r, 1.01, 2.0) + 0.1;
        }
        return;
    }
    for (int i = 0; i < n * n; i++) A[i] = rng_range(r, -1.0, 1.0);
    for (int i = 0; i < n; i++)
        for (int j = 0; j <= i; j++) {
            double s = 0.0;
            for (int k = 0; k < n; k++) s += A[i * n + k] * A[j * n + k];
            s /= n;
            const double skew = (kind == SKEW_PD && j < i) ? rng_range(r, -1.0, 1.0) : 0.0;
            M[i * n + j] = s + skew;
            M[j * n + i] = s - skew;
        }
    for (int i = 0; i < n; i++) M[i * n + i] += rng_range(r, 0.1, 1.0);
}

typedef struct {
    double residual, vs_reference, warm_vs_cold;
    long cases, warm_zero, stack_same;
    int pivots_max, nmax;
} stats;

/* One problem: cold, against the reference, the warm starts, and the stack entry point's bits. */
static void one_case(checks *T, stats *st, lcp_workspace *ws, int n, const double *M, const double *q)
{
    static double z[NMAX], w[NMAX], zr[NMAX], z2[NMAX], w2[NMAX], A[NMAX * (NMAX + 1)];
    static int zb[NMAX], zb2[NMAX], J[NMAX], in[NMAX];
    int piv = -1, piv2 = -1;
    if (!CHECK_INT(LCP_OK, lcp_lemke_ws(ws, n, M, q, BUDGET, z, w, zb, &piv))) return;
    st->cases++;
    st->pivots_max = piv > st->pivots_max ? piv : st->pivots_max;
    st->nmax = n > st->nmax ? n : st->nmax;
    st->residual = fmax(st->residual, complementarity(T, n, M, q, z, w, 1e-12));
    if (CHECK(reference(n, M, q, zr, A, J, in) >= 0)) {
        const double rel = rel_diff(n, z, zr);
        CHECK_RANGE(0.0, 1e-10, rel);
        st->vs_reference = fmax(st->vs_reference, rel);
    }
    /* warm: the solution's own basis is accepted with no pivot; a wrong guess falls back to cold */
    if (CHECK_INT(LCP_OK, lcp_lemke_warm_ws(ws, n, M, q, zb, BUDGET, z2, w2, zb2, &piv2))) {
        if (piv2 == 0) st->warm_zero++;
        const double rel = rel_diff(n, z2, z);
        st->warm_vs_cold = fmax(st->warm_vs_cold, rel);
        CHECK_RANGE(0.0, 1e-12, rel);
    }
    for (int i = 0; i < n; i++) in[i] = !zb[i]; /* the complement: not the solution for q < 0 somewhere */
    int any_neg = 0;
    for (int i = 0; i < n; i++) any_neg |= q[i] < 0.0;
    if (any_neg && CHECK_INT(LCP_OK, lcp_lemke_warm_ws(ws, n, M, q, in, BUDGET, z2, w2, zb2, &piv2))) {
        if (piv2 > 0) { /* not accepted: the cold answer, bit for bit */
            CHECK(memcmp(z, z2, (size_t)n * sizeof(double)) == 0 && memcmp(w, w2, (size_t)n * sizeof(double)) == 0);
            CHECK_INT(piv, piv2);
        }
    }
    if (n <= LCP_STACK_N) { /* the stack entry point: the same bits */
        if (CHECK_INT(LCP_OK, lcp_lemke(n, M, q, BUDGET, z2, w2, zb2, &piv2)) &&
            CHECK(memcmp(z, z2, (size_t)n * sizeof(double)) == 0 && memcmp(w, w2, (size_t)n * sizeof(double)) == 0 &&
                  memcmp(zb, zb2, (size_t)n * sizeof(int)) == 0 && piv == piv2))
            st->stack_same++;
        if (CHECK_INT(LCP_OK, lcp_lemke_general_ws(ws, n, M, q, BUDGET, z, w, zb, &piv)) &&
            CHECK_INT(LCP_OK, lcp_lemke_general(n, M, q, BUDGET, z2, w2, zb2, &piv2)))
            CHECK(memcmp(z, z2, (size_t)n * sizeof(double)) == 0 && piv == piv2);
        if (CHECK_INT(LCP_OK, lcp_lemke_warm_ws(ws, n, M, q, in, BUDGET, z, w, zb, &piv)) &&
            CHECK_INT(LCP_OK, lcp_lemke_warm(n, M, q, in, BUDGET, z2, w2, zb2, &piv2)))
            CHECK(memcmp(z, z2, (size_t)n * sizeof(double)) == 0 && piv == piv2);
    }
}

static void test_random(checks *T, stats *st, lcp_workspace *ws)
{
    static double M[NMAX * NMAX], q[NMAX];
    static const int big[] = {20, 24, 32, 48, 64, 96, 128, 192, 256};
    rng r = {20261206};
    for (int c = 0; c < 16 + (int)(sizeof big / sizeof big[0]); c++) {
        const int n = c < 16 ? c + 1 : big[c - 16];
        const int reps = n <= 16 ? 8 : 1;
        for (int rep = 0; rep < reps; rep++)
            for (int kind = SPD; kind <= SKEW_PD; kind++) {
                check_context(T, "random P-matrix n = %d kind %d rep %d", n, kind, rep);
                random_P(&r, n, kind, M);
                for (int i = 0; i < n; i++) /* odd reps: q over six decades */
                    q[i] = rng_range(&r, -1.0, 1.0) * pow(10.0, rng_range(&r, -3.0, 3.0) * (rep % 2));
                one_case(T, st, ws, n, M, q);
            }
    }
    T->context = NULL;
}

/* ---- degenerate problems ----------------------------------------------------------------------- */

/* Lemke with the plain minimum-ratio test (ties to z0's row, else to the least row index): the rule
 * the lexicographic test replaces. Returns the status, as lcp_lemke. */
static lcp_status lemke_least_row(int n, const double *M, const double *q, int budget)
{
    double T[3 * 8];
    int basis[3];
    const int nc = 2 * n + 2, z0 = 2 * n, rhs = 2 * n + 1;
    int r = 0;
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < n; j++) {
            T[i * nc + j] = (i == j);
            T[i * nc + n + j] = -M[i * n + j];
        }
        T[i * nc + z0] = -1.0;
        T[i * nc + rhs] = q[i];
        basis[i] = i;
        if (q[i] <= q[r]) r = i;
    }
    int leaving = -1, col = z0;
    for (int count = 0; count < budget; count++) {
        if (count > 0) {
            col = leaving < n ? leaving + n : leaving - n;
            r = -1;
            double best = 0.0;
            for (int i = 0; i < n; i++) {
                const double d = T[i * nc + col];
                if (!(d > 1e-12)) continue;
                const double ratio = T[i * nc + rhs] / d;
                const int tie = fabs(ratio - best) <= 1e-12;
                if (r < 0 || ratio < best - 1e-12 || (tie && basis[i] == z0 && basis[r] != z0)) {
                    r = i;
                    best = ratio;
                }
            }
            if (r < 0) return LCP_RAY;
        }
        const double inv = 1.0 / T[r * nc + col];
        for (int j = 0; j < nc; j++) T[r * nc + j] *= inv;
        for (int i = 0; i < n; i++) {
            if (i == r) continue;
            const double f = T[i * nc + col];
            for (int j = 0; j < nc; j++) T[i * nc + j] -= f * T[r * nc + j];
        }
        leaving = basis[r];
        basis[r] = col;
        if (leaving == z0) return LCP_OK;
    }
    return LCP_MAX_PIVOTS;
}

static void test_degenerate(checks *T, lcp_workspace *ws, int *cycle_pivots)
{
    static double M[NMAX * NMAX], q[NMAX], z[NMAX], w[NMAX];
    static int zb[NMAX];
    int piv = -1;
    rng r = {7};
    for (int n = 1; n <= NMAX; n = n < 8 ? n + 1 : 2 * n) {
        check_context(T, "q = 0 and q >= 0, n = %d", n);
        random_P(&r, n, SPD, M);
        for (int i = 0; i < n; i++) q[i] = 0.0;
        if (CHECK_INT(LCP_OK, lcp_lemke_ws(ws, n, M, q, BUDGET, z, w, zb, &piv))) {
            CHECK_INT(0, piv);
            for (int i = 0; i < n; i++) CHECK(z[i] == 0.0 && w[i] == 0.0 && !zb[i]);
        }
        for (int i = 0; i < n; i++) q[i] = (i % 3 == 0) ? 0.0 : rng_range(&r, 0.0, 1.0);
        if (CHECK_INT(LCP_OK, lcp_lemke_ws(ws, n, M, q, BUDGET, z, w, zb, &piv))) {
            CHECK_INT(0, piv);
            for (int i = 0; i < n; i++) CHECK(z[i] == 0.0 && w[i] == q[i]);
        }
        /* M = I + 1 1', q = -1: every ratio ties; z = 1 / (n + 1) */
        check_context(T, "ties: M = I + 1 1', q = -1, n = %d", n);
        for (int i = 0; i < n; i++) {
            for (int j = 0; j < n; j++) M[i * n + j] = 1.0 + (i == j);
            q[i] = -1.0;
        }
        if (CHECK_INT(LCP_OK, lcp_lemke_ws(ws, n, M, q, BUDGET, z, w, zb, &piv))) {
            complementarity(T, n, M, q, z, w, 1e-12);
            for (int i = 0; i < n; i++) CHECK_NEAR(1.0 / (n + 1), z[i], 1e-13);
        }
        /* zeros among the q of a P-matrix: ties at a zero ratio */
        check_context(T, "zeros in q, diagonally dominant n = %d", n);
        random_P(&r, n, DIAG_DOMINANT, M);
        for (int i = 0; i < n; i++) q[i] = (i % 2) ? 0.0 : -1.0;
        if (CHECK_INT(LCP_OK, lcp_lemke_ws(ws, n, M, q, BUDGET, z, w, zb, &piv))) {
            complementarity(T, n, M, q, z, w, 1e-12);
            static double zr[NMAX], A[NMAX * (NMAX + 1)];
            static int J[NMAX], in[NMAX];
            if (CHECK(reference(n, M, q, zr, A, J, in) >= 0))
                for (int i = 0; i < n; i++) CHECK_NEAR(zr[i], z[i], 1e-10 * (1.0 + fabs(zr[i])));
        }
    }
    /* The minimum-ratio test with ties to the least row cycles on this degenerate problem (found by a
     * search over small integer problems); the lexicographic rule solves it. */
    check_context(T, "a problem that needs the lexicographic rule");
    const double Mc[9] = {2, 2, 0, 2, 0, 2, -1, -2, 1}, qc[3] = {-1, -1, 0};
    CHECK_INT(LCP_MAX_PIVOTS, lemke_least_row(3, Mc, qc, 1000));
    if (CHECK_INT(LCP_OK, lcp_lemke_ws(ws, 3, Mc, qc, BUDGET, z, w, zb, &piv))) {
        complementarity(T, 3, Mc, qc, z, w, 1e-15);
        *cycle_pivots = piv;
    }
    T->context = NULL;
}

/* ---- the workspace ----------------------------------------------------------------------------- */

static void test_workspace(checks *T)
{
    counter c = {0, 0, -1};
    const lcp_alloc al = {count_alloc, count_free, &c};
    const double M[4] = {2, 1, 1, 2}, q[2] = {-1, -1};
    double z[3], w[3];
    int zb[3], piv = -1;
    check_context(T, "workspace");
    CHECK(lcp_workspace_create(0, &al) == NULL);
    CHECK(lcp_workspace_create(-3, &al) == NULL);
    CHECK(lcp_workspace_create(26001, &al) == NULL);
    CHECK(lcp_workspace_create(4, NULL) == NULL);
    CHECK_INT(0, c.live);
    lcp_workspace *ws = lcp_workspace_create(1, &al);
    if (CHECK(ws != NULL)) {
        CHECK_INT(1, lcp_workspace_size(ws));
        CHECK(c.live > 0);
        CHECK_INT(LCP_BAD_INPUT, lcp_lemke_ws(ws, 2, M, q, 16, z, w, zb, &piv)); /* larger than the workspace */
        CHECK_INT(0, piv);
        CHECK_INT(LCP_BAD_INPUT, lcp_lemke_warm_ws(ws, 2, M, q, zb, 16, z, w, zb, &piv));
        CHECK_INT(LCP_BAD_INPUT, lcp_lemke_ws(ws, 0, M, q, 16, z, w, zb, &piv));
        lcp_workspace_free(ws, &al);
    }
    CHECK_INT(0, c.live);
    CHECK_INT(LCP_BAD_INPUT, lcp_lemke_ws(NULL, 2, M, q, 16, z, w, zb, &piv));
    CHECK_INT(0, lcp_workspace_size(NULL));
    lcp_workspace_free(NULL, &al);
    for (long k = 0; k < 3; k++) { /* every allocation failing in turn: NULL, nothing left behind */
        counter f = {0, 0, k};
        const lcp_alloc af = {count_alloc, count_free, &f};
        CHECK(lcp_workspace_create(5, &af) == NULL);
        CHECK_INT(0, f.live);
    }
    /* the stack entry points refuse n above LCP_STACK_N, a workspace takes it */
    static double Mb[(LCP_STACK_N + 1) * (LCP_STACK_N + 1)], qb[LCP_STACK_N + 1], zz[LCP_STACK_N + 1],
        ww[LCP_STACK_N + 1];
    static int zzb[LCP_STACK_N + 1];
    const int nb = LCP_STACK_N + 1;
    for (int i = 0; i < nb; i++) {
        Mb[i * nb + i] = 1.0;
        qb[i] = -1.0;
    }
    CHECK_INT(LCP_BAD_INPUT, lcp_lemke(nb, Mb, qb, BUDGET, zz, ww, zzb, &piv));
    CHECK_INT(LCP_BAD_INPUT, lcp_lemke_warm(nb, Mb, qb, zzb, BUDGET, zz, ww, zzb, &piv));
    ws = lcp_workspace_create(nb, &al);
    if (CHECK(ws != NULL) && CHECK_INT(LCP_OK, lcp_lemke_ws(ws, nb, Mb, qb, BUDGET, zz, ww, zzb, &piv)))
        for (int i = 0; i < nb; i++) CHECK_SAME(1.0, zz[i]);
    lcp_workspace_free(ws, &al);
    CHECK_INT(0, c.live);
    T->context = NULL;
}

/* ---- the dense box LCP ------------------------------------------------------------------------- */

/* The box conditions on an answer (lcp_box's, for a dense M): w = M z + q to tol of the scale,
 * |w| <= l, held rows (mode 0, l > 0) at z = 0 exactly, the others with w = -mode l exactly and
 * mode z >= 0 (l = 0: w = 0, mode the sign of z). Returns the relative residual. */
static double box_conditions(checks *T, int n, const double *M, const double *q, const double *l, const int *mode,
                             const double *z, const double *w, double tol)
{
    double res = 0.0, scale = 0.0;
    for (int i = 0; i < n; i++) {
        double r = q[i], a = fabs(q[i]) + l[i];
        for (int j = 0; j < n; j++) {
            r += M[i * n + j] * z[j];
            a += fabs(M[i * n + j] * z[j]);
        }
        scale = fmax(scale, a);
        res = fmax(res, fabs(w[i] - r));
        CHECK(isfinite(z[i]) && isfinite(w[i]) && fabs(w[i]) <= l[i]);
        if (l[i] > 0.0 && mode[i] == 0) CHECK(z[i] == 0.0);
        else if (l[i] > 0.0) CHECK(w[i] == -mode[i] * l[i] && mode[i] * z[i] >= 0.0);
        else CHECK(w[i] == 0.0 && mode[i] == (z[i] > 0.0) - (z[i] < 0.0));
    }
    const double rel = scale > 0.0 ? res / scale : res;
    CHECK_RANGE(0.0, tol, rel);
    return rel;
}

/* The reference of a box LCP with M positive definite: projected Gauss-Seidel (convergent) run
 * until its modes settle, then those modes' free rows solved (solve_basis above, with the held
 * rows' z = 0 and the free rows' right-hand side moved by their limits) and the box checked; a
 * row outside its box flips its mode and the solve repeats. Returns 0 when that does not settle. */
static int box_reference(int n, const double *M, const double *q, const double *l, double *z, double *A, int *J)
{
    static double qs[NMAX], zz[NMAX];
    static int free_[NMAX], md[NMAX];
    for (int i = 0; i < n; i++) z[i] = 0.0;
    for (int sweep = 0; sweep < 5000; sweep++) {
        double dz = 0.0, zs = 0.0;
        for (int i = 0; i < n; i++) {
            double r = -q[i] + M[i * n + i] * z[i];
            for (int j = 0; j < n; j++) r -= M[i * n + j] * z[j];
            const double v = (r > l[i]) ? (r - l[i]) / M[i * n + i] : (r < -l[i]) ? (r + l[i]) / M[i * n + i] : 0.0;
            dz = fmax(dz, fabs(v - z[i]));
            zs = fmax(zs, fabs(v));
            z[i] = v;
        }
        if (dz <= 1e-13 * zs) break;
    }
    for (int i = 0; i < n; i++) md[i] = (z[i] > 0.0) - (z[i] < 0.0);
    for (int round = 0; round < 4 * n + 8; round++) {
        for (int i = 0; i < n; i++) {
            free_[i] = md[i] != 0 || !(l[i] > 0.0);
            qs[i] = q[i] + ((l[i] > 0.0) ? md[i] * l[i] : 0.0); /* M_FF z_F = -q_F - mode l */
        }
        if (!solve_basis(n, M, qs, free_, zz, A, J)) return 0;
        int flip = -1;
        for (int i = 0; i < n && flip < 0; i++) {
            double w = q[i];
            for (int j = 0; j < n; j++) w += M[i * n + j] * zz[j];
            if (!(l[i] > 0.0)) continue;
            if (md[i] != 0 && md[i] * zz[i] < 0.0) flip = i;
            else if (md[i] == 0 && fabs(w) > l[i] * (1.0 + 1e-12)) flip = i;
        }
        if (flip < 0) {
            memcpy(z, zz, (size_t)n * sizeof(double));
            return 1;
        }
        if (md[flip] != 0) md[flip] = 0;
        else {
            double w = q[flip];
            for (int j = 0; j < n; j++) w += M[flip * n + j] * zz[j];
            md[flip] = (w > 0.0) ? -1 : 1;
        }
    }
    return 0;
}

typedef struct {
    double residual, vs_reference, vs_tridiagonal;
    long cases, tri_cases;
    int pivots_max, nmax;
} box_stats;

static void test_box_dense(checks *T, box_stats *bs)
{
    static double M[64 * 64], q[64], l[64], z[64], w[64], zr[64], work[64 * 64 + 128], A[64 * 65], d[64], e[64],
        z2[64], w2[64], work2[128];
    static int mode[64], mode2[64], J[64];
    rng r = {4242};
    static const int sizes[] = {1, 2, 3, 4, 5, 6, 7, 8, 10, 12, 16, 24, 32, 48, 64};
    for (size_t si = 0; si < sizeof sizes / sizeof sizes[0]; si++) {
        const int n = sizes[si];
        CHECK(lcp_box_dense_work((size_t)n) == (size_t)(n * n + 2 * n));
        for (int rep = 0; rep < (n <= 16 ? 6 : 2); rep++) {
            check_context(T, "dense box LCP n = %d rep %d", n, rep);
            random_P(&r, n, SPD, M);
            if (rep == 5) { /* stiff: masses on springs of k up to 1e7 coupling every neighbour, far from
                             * diagonal dominance, plus the random part */
                const double k = rng_decades(&r, 3.0, 7.0);
                for (int i = 0; i < n; i++) {
                    M[i * n + i] += 2.0 * k;
                    if (i + 1 < n) {
                        M[i * n + i + 1] -= k;
                        M[(i + 1) * n + i] -= k;
                    }
                }
            }
            for (int i = 0; i < n; i++) {
                q[i] = rng_range(&r, -2.0, 2.0);
                l[i] = (rep % 3 == 2 && i % 4 == 0) ? 0.0 : rng_range(&r, 0.0, 1.0); /* some rows free (l = 0) */
                mode[i] = rep % 2 ? rng_int(&r, 3) - 1 : 0;                            /* a guess, or none */
            }
            int piv = -1;
            if (!CHECK_INT(LCP_OK, lcp_box_dense((size_t)n, M, q, l, mode, z, w, work, &piv))) continue;
            bs->cases++;
            bs->pivots_max = piv > bs->pivots_max ? piv : bs->pivots_max;
            bs->nmax = n > bs->nmax ? n : bs->nmax;
            bs->residual = fmax(bs->residual, box_conditions(T, n, M, q, l, mode, z, w, 1e-12));
            if (CHECK(box_reference(n, M, q, l, zr, A, J))) {
                const double rel = rel_diff(n, z, zr);
                CHECK_RANGE(0.0, 1e-10, rel);
                bs->vs_reference = fmax(bs->vs_reference, rel);
            }
            /* warm: from the solution's own modes, no pivot */
            memcpy(mode2, mode, sizeof mode2);
            if (CHECK_INT(LCP_OK, lcp_box_dense((size_t)n, M, q, l, mode2, z2, w2, work, &piv))) CHECK_INT(0, piv);
        }
        /* a tridiagonal M posed densely: lcp_box's answer */
        check_context(T, "dense box LCP = lcp_box on a tridiagonal M, n = %d", n);
        for (int rep = 0; rep < 4; rep++) {
            for (int i = 0; i < n; i++) e[i] = -rng_range(&r, 0.0, 1.0);
            for (int i = 0; i < n * n; i++) M[i] = 0.0;
            for (int i = 0; i < n; i++) {
                d[i] = (i > 0 ? -e[i - 1] : 0.0) + (i + 1 < n ? -e[i] : 0.0) + rng_range(&r, 0.1, 1.0);
                M[i * n + i] = d[i];
                if (i + 1 < n) M[i * n + i + 1] = M[(i + 1) * n + i] = e[i];
                q[i] = rng_range(&r, -2.0, 2.0);
                l[i] = rng_range(&r, 0.0, 1.0);
                mode[i] = mode2[i] = 0;
            }
            if (CHECK_INT(LCP_OK, lcp_box_dense((size_t)n, M, q, l, mode, z, w, work, NULL)) &&
                CHECK_INT(LCP_OK, lcp_box((size_t)n, d, e, q, l, mode2, z2, w2, work2, NULL))) {
                for (int i = 0; i < n; i++) CHECK_INT(mode2[i], mode[i]);
                const double rel = rel_diff(n, z, z2);
                CHECK_RANGE(0.0, 1e-12, rel);
                bs->vs_tridiagonal = fmax(bs->vs_tridiagonal, rel);
                bs->tri_cases++;
            }
        }
    }
    /* degenerate: q = 0 (z = 0, every row held, no pivot); q on a box's edge (w = l with z = 0) */
    check_context(T, "dense box LCP degenerate");
    const int n = 5;
    random_P(&r, n, SPD, M);
    for (int i = 0; i < n; i++) { q[i] = 0.0; l[i] = 0.5; mode[i] = 0; }
    int piv = -1;
    if (CHECK_INT(LCP_OK, lcp_box_dense(n, M, q, l, mode, z, w, work, &piv))) {
        CHECK_INT(0, piv);
        for (int i = 0; i < n; i++) CHECK(z[i] == 0.0 && w[i] == 0.0 && mode[i] == 0);
    }
    for (int i = 0; i < n; i++) { q[i] = (i % 2) ? 0.5 : -0.5; mode[i] = 1; } /* on the edges: z = 0 */
    if (CHECK_INT(LCP_OK, lcp_box_dense(n, M, q, l, mode, z, w, work, &piv))) {
        box_conditions(T, n, M, q, l, mode, z, w, 1e-14);
        for (int i = 0; i < n; i++) CHECK(fabs(z[i]) <= 1e-15);
    }
    /* bad input: not positive definite (a free block with a pivot <= 0), NaN, l < 0 */
    check_context(T, "dense box LCP bad input");
    const double Mneg[4] = {1.0, 2.0, 2.0, 1.0}, qq[2] = {-5.0, -5.0}, ll[2] = {0.1, 0.1};
    int md[2] = {1, 1};
    CHECK_INT(LCP_BAD_INPUT, lcp_box_dense(2, Mneg, qq, ll, md, z, w, work, &piv));
    const double Mnan[4] = {1.0, NAN, NAN, 1.0}, lneg[2] = {0.1, -1.0};
    CHECK_INT(LCP_BAD_INPUT, lcp_box_dense(2, Mnan, qq, ll, md, z, w, work, &piv));
    CHECK_INT(LCP_BAD_INPUT, lcp_box_dense(2, M, qq, lneg, md, z, w, work, &piv));
    T->context = NULL;
}

int main(void)
{
    checks C = {0, 0, NULL, {0}}, *T = &C;
    stats st = {0};
    counter c = {0, 0, -1};
    const lcp_alloc al = {count_alloc, count_free, &c};
    lcp_workspace *ws = lcp_workspace_create(NMAX, &al);
    if (!CHECK(ws != NULL)) return checks_done(T, "test_lcp_any_n");
    int cycle_pivots = -1;
    test_random(T, &st, ws);
    test_degenerate(T, ws, &cycle_pivots);
    lcp_workspace_free(ws, &al);
    CHECK_INT(0, c.live);
    test_workspace(T);
    box_stats bs = {0};
    test_box_dense(T, &bs);
    printf("dense box LCP: %ld problems, n = 1 ... %d, max pivots %d, max relative residual %.2e, max relative "
           "difference to the reference %.2e; %ld tridiagonal problems as lcp_box's to %.2e\n",
           bs.cases, bs.nmax, bs.pivots_max, bs.residual, bs.vs_reference, bs.tri_cases, bs.vs_tridiagonal);
    printf("random P-matrices: %ld problems, n = 1 ... %d, max pivots %d, max relative residual %.2e, max relative "
           "difference to the reference %.2e, warm start from the solution's basis: %ld with 0 pivots (max "
           "difference %.2e), stack entry points bit for bit: %ld\n",
           st.cases, st.nmax, st.pivots_max, st.residual, st.vs_reference, st.warm_zero, st.warm_vs_cold,
           st.stack_same);
    printf("the least-row tie rule cycles on the 3 x 3 degenerate problem; the lexicographic rule: %d pivots\n",
           cycle_pivots);
    return checks_done(T, "test_lcp_any_n");
}
