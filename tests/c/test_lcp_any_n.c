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
 *    allocation (NULL, nothing leaked), n out of range, a problem larger than the workspace. */
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

/* Solve M_JJ x = -q_J (k = |J|) by Gaussian elimination with partial pivoting into z (0 off J).
 * A: k (k + 1) doubles. Returns 0 when singular. */
static int solve_basis(int n, const double *M, const double *q, const int *in, double *z, double *A, int *J)
{
    int k = 0;
    for (int i = 0; i < n; i++) {
        z[i] = 0.0;
        if (in[i]) J[k++] = i;
    }
    const int s = k + 1;
    for (int a = 0; a < k; a++) {
        for (int b = 0; b < k; b++) A[a * s + b] = M[J[a] * n + J[b]];
        A[a * s + k] = -q[J[a]];
    }
    for (int c = 0; c < k; c++) {
        int p = c;
        for (int r = c + 1; r < k; r++)
            if (fabs(A[r * s + c]) > fabs(A[p * s + c])) p = r;
        if (A[p * s + c] == 0.0) return 0;
        for (int b = 0; b <= k; b++) {
            const double t = A[c * s + b];
            A[c * s + b] = A[p * s + b];
            A[p * s + b] = t;
        }
        for (int r = c + 1; r < k; r++) {
            const double f = A[r * s + c] / A[c * s + c];
            for (int b = c; b <= k; b++) A[r * s + b] -= f * A[c * s + b];
        }
    }
    for (int c = k - 1; c >= 0; c--) {
        double v = A[c * s + k];
        for (int b = c + 1; b < k; b++) v -= A[c * s + b] * z[J[b]];
        z[J[c]] = v / A[c * s + c];
    }
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
        double d = 0.0, s = 0.0;
        for (int i = 0; i < n; i++) {
            d = fmax(d, fabs(z[i] - zr[i]));
            s = fmax(s, fabs(zr[i]));
        }
        const double rel = s > 0.0 ? d / s : d;
        CHECK_RANGE(0.0, 1e-10, rel);
        st->vs_reference = fmax(st->vs_reference, rel);
    }
    /* warm: the solution's own basis is accepted with no pivot; a wrong guess falls back to cold */
    if (CHECK_INT(LCP_OK, lcp_lemke_warm_ws(ws, n, M, q, zb, BUDGET, z2, w2, zb2, &piv2))) {
        if (piv2 == 0) st->warm_zero++;
        double d = 0.0, s = 0.0;
        for (int i = 0; i < n; i++) {
            d = fmax(d, fabs(z2[i] - z[i]));
            s = fmax(s, fabs(z[i]));
        }
        st->warm_vs_cold = fmax(st->warm_vs_cold, s > 0.0 ? d / s : d);
        CHECK_RANGE(0.0, 1e-12, s > 0.0 ? d / s : d);
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
                for (int i = 0; i < n; i++) q[i] = rng_range(&r, -1.0, 1.0) * pow(10.0, rng_range(&r, -3.0, 3.0) * (rep % 2));
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
                if (r < 0 || ratio < best - 1e-12 || (fabs(ratio - best) <= 1e-12 && basis[i] == z0 && basis[r] != z0)) {
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
    printf("random P-matrices: %ld problems, n = 1 ... %d, max pivots %d, max relative residual %.2e, max relative "
           "difference to the reference %.2e, warm start from the solution's basis: %ld with 0 pivots (max "
           "difference %.2e), stack entry points bit for bit: %ld\n",
           st.cases, st.nmax, st.pivots_max, st.residual, st.vs_reference, st.warm_zero, st.warm_vs_cold,
           st.stack_same);
    printf("the least-row tie rule cycles on the 3 x 3 degenerate problem; the lexicographic rule: %d pivots\n",
           cycle_pivots);
    return checks_done(T, "test_lcp_any_n");
}
