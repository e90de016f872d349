/* Lemke's algorithm (lexicographic variant) and the box LCP of a tridiagonal M. See lcp.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "dfo_inline.h"
#include "lcp.h"

#include <math.h>

/* The small helpers of the pivoting loops are compiled into them. */
#define ALWAYS_INLINE DFO_FORCE_INLINE

static double dmax(double a, double b) { return a > b ? a : b; }
static double dabs(double a) { return fabs(a); }

/* x / s, by the reciprocal inv = 1 / s where that is finite (s is not subnormal) */
static ALWAYS_INLINE double scaled(double x, double s, double inv) { return isfinite(inv) ? x * inv : x / s; }

/* Tableau columns: [0, n) w, [n, 2n) z, 2n z0, 2n + 1 right-hand side. Variable ids equal the
 * column index of the variable. */
#define COLS(n) (2 * (n) + 2)

static ALWAYS_INLINE void pivot(double *T, const int n, int row, int col)
{
    const int nc = COLS(n);
    double *pr = T + row * nc;
    const double inv = 1.0 / pr[col];
    for (int j = 0; j < nc; j++) pr[j] *= inv;
    pr[col] = 1.0;
    for (int i = 0; i < n; i++) {
        if (i == row) continue;
        double *ri = T + i * nc;
        const double f = ri[col];
        if (f == 0.0) continue;
        for (int j = 0; j < nc; j++) ri[j] -= f * pr[j];
        ri[col] = 0.0;
    }
}

/* Lexicographic minimum-ratio test on column col: among rows with a positive pivot element,
 * the row whose (rhs, B^-1 row) / d is lexicographically smallest. B^-1 sits in the w columns.
 * Rows whose basic variable is z0 win ties (so the artificial variable leaves as soon as it can).
 * Returns -1 when no row qualifies (a ray). */
static double column_scale(const double *T, const int n, int c)
{
    const int nc = COLS(n);
    double cscale = 0.0;
    for (int r = 0; r < n; r++) cscale = dmax(cscale, dabs(T[r * nc + c]));
    return cscale;
}

/* cs: n doubles of scratch (the scales of the columns of B^-1, each computed once when a tie first
 * needs it) */
static ALWAYS_INLINE int ratio_test(const double *T, const int n, int col, const int *basis, double *cs)
{
    const int nc = COLS(n);
    const int rhs = 2 * n + 1;
    double colmax = 0.0;
    for (int i = 0; i < n; i++) colmax = dmax(colmax, dabs(T[i * nc + col]));
    const double tol = 1e-13 * colmax;
    int best = -1;
    double rhs_scale = -1.0;
    for (int k = 0; k < n; k++) cs[k] = -1.0;
    for (int i = 0; i < n; i++) {
        const double d = T[i * nc + col];
        if (!(d > tol)) continue;
        if (best < 0) { best = i; continue; }
        const double db = T[best * nc + col];
        const double dd = d * db;
        /* compare a = T[i][k] / d with b = T[best][k] / db for k = rhs, 0, 1, ..., n-1, cross-
         * multiplied (d, db > 0): a - b has the sign of T[i][k] db - T[best][k] d. Values closer
         * than 1e-12 of the column's scale are ties: rounding of earlier pivots must not break a
         * tie of the exact problem. The comparison is scaled by colmax (no division). */
        int cmp = 0;
        for (int k = -1; k < n && cmp == 0; k++) {
            const int c = (k < 0) ? rhs : k;
            double *slot = (k < 0) ? &rhs_scale : &cs[k];
            if (*slot < 0.0) *slot = column_scale(T, n, c);
            const double cscale = *slot;
            const double ad = T[i * nc + c] * db * colmax, bd = T[best * nc + c] * d * colmax;
            const double eps = 1e-12 * (dmax(dabs(ad), dabs(bd)) + cscale * dd);
            if (ad < bd - eps) cmp = -1;
            else if (ad > bd + eps) cmp = 1;
            if (k < 0 && cmp == 0) {
                if (basis[i] == 2 * n) { cmp = -1; }
                else if (basis[best] == 2 * n) { cmp = 1; }
            }
        }
        if (cmp < 0) best = i;
    }
    return best;
}

/* Lemke on the tableau T (n x COLS(n)) with the basis list basis (n) and the scratch cs (n), all the
 * caller's. */
static lcp_status lemke(const int n, const double *M, const double *q, int max_pivots,
                       double *z, double *w, int *z_basic, int *pivots, double *T, int *basis, double *cs)
{
    if (pivots) *pivots = 0;
    if (n < 1) return LCP_BAD_INPUT;
    int rmin = 0;
    double sM = 0.0, sq = 0.0;
    for (int i = 0; i < n; i++) {
        if (!isfinite(q[i])) return LCP_BAD_INPUT;
        sq = dmax(sq, dabs(q[i]));
        for (int j = 0; j < n; j++) {
            if (!isfinite(M[i * n + j])) return LCP_BAD_INPUT;
            sM = dmax(sM, dabs(M[i * n + j]));
        }
        /* ties: the last index has the lexicographically smallest row (q_i, e_i) */
        if (q[i] <= q[rmin]) rmin = i;
    }
    for (int i = 0; i < n; i++) { z[i] = 0.0; w[i] = q[i]; z_basic[i] = 0; }
    if (q[rmin] >= 0.0) return LCP_OK; /* z = 0 solves it */
    /* Solve the normalised problem M' = M / sM, q' = q / sq (entries of magnitude <= 1, so that the
     * pivot tolerances are relative): w' = M' z' + q' with z = z' sq / sM and w = w' sq. */
    if (sM == 0.0) sM = 1.0;

    const int nc = COLS(n);
    const int rhs = 2 * n + 1, z0 = 2 * n;
    const double iM = 1.0 / sM, iq = 1.0 / sq, zs = sq / sM;
    for (int i = 0; i < n; i++) {
        double *r = T + i * nc;
        for (int j = 0; j < n; j++) {
            r[j] = (i == j) ? 1.0 : 0.0;
            r[n + j] = -scaled(M[i * n + j], sM, iM);
        }
        r[z0] = -1.0;
        r[rhs] = scaled(q[i], sq, iq);
        basis[i] = i;
    }
    /* z0 enters at the most negative q (ties broken lexicographically, see above) */
    int leaving = basis[rmin];
    pivot(T, n, rmin, z0);
    basis[rmin] = z0;
    int count = 1;
    for (;;) {
        const int entering = (leaving < n) ? leaving + n : leaving - n; /* complement */
        if (count >= max_pivots) { if (pivots) *pivots = count; return LCP_MAX_PIVOTS; }
        const int row = ratio_test(T, n, entering, basis, cs);
        if (row < 0) { if (pivots) *pivots = count; return LCP_RAY; }
        leaving = basis[row];
        pivot(T, n, row, entering);
        basis[row] = entering;
        count++;
        if (leaving == z0) break;
    }
    if (pivots) *pivots = count;
    for (int i = 0; i < n; i++) { z[i] = 0.0; w[i] = 0.0; }
    for (int i = 0; i < n; i++) {
        const int v = basis[i];
        const double val = dmax(T[i * nc + rhs], 0.0);
        if (v < n) w[v] = val * sq;
        else if (v < 2 * n) { z[v - n] = val * zs; z_basic[v - n] = 1; }
    }
    return LCP_OK;
}

/* ---- n = 2 (the friction problem of one degree of freedom): the same algorithm, in revised form -
 * The same pivots, ratio test and tolerances as the tableau above, but only the basis inverse B^-1
 * (2 x 2) and the values of the basic variables are kept, in registers; the entering column is
 * B^-1 times its original column. Its results equal the tableau's to rounding (tests/c/test_lcp.c
 * compares the two on every problem it solves). Variable ids as above: w1 w2 z1 z2 z0 = 0..4. */

typedef struct {
    double B[2][2];   /* basis inverse */
    double x[2];      /* values of the basic variables, B^-1 q' */
    int basis[2];
} rev2;

static ALWAYS_INLINE void pivot_rev2(rev2 *R, int r, const double d[2])
{
    const int o = 1 - r;
    const double inv = 1.0 / d[r];
    R->B[r][0] *= inv;
    R->B[r][1] *= inv;
    R->x[r] *= inv;
    const double f = d[o];
    if (f == 0.0) return;
    R->B[o][0] -= f * R->B[r][0];
    R->B[o][1] -= f * R->B[r][1];
    R->x[o] -= f * R->x[r];
}

/* The lexicographic minimum-ratio test of ratio_test() on the entering column d. */
static ALWAYS_INLINE int ratio_rev2(const rev2 *R, const double d[2])
{
    const double d0 = d[0], d1 = d[1];
    const double colmax = dmax(dmax(0.0, dabs(d0)), dabs(d1));
    const double tol = 1e-13 * colmax;
    const int c0 = d0 > tol, c1 = d1 > tol;
    if (!c1) return c0 ? 0 : -1;
    if (!c0) return 1;
    const double dd = d1 * d0;
    /* k = 0: right-hand side; k = 1, 2: the columns of B^-1 */
    for (int k = 0; k < 3; k++) {
        const double t0 = (k == 0) ? R->x[0] : R->B[0][k - 1];
        const double t1 = (k == 0) ? R->x[1] : R->B[1][k - 1];
        const double cscale = dmax(dmax(0.0, dabs(t0)), dabs(t1));
        const double ad = t1 * d0 * colmax, bd = t0 * d1 * colmax;
        const double eps = 1e-12 * (dmax(dabs(ad), dabs(bd)) + cscale * dd);
        if (ad < bd - eps) return 1;
        if (ad > bd + eps) return 0;
        if (k == 0) {
            if (R->basis[1] == 4) return 1;
            if (R->basis[0] == 4) return 0;
        }
    }
    return 0;
}

static lcp_status lemke2(const double *M, const double *q, int max_pivots, double *z, double *w, int *z_basic,
                         int *pivots)
{
    if (pivots) *pivots = 0;
    /* x - x is 0 for finite x and NaN for an infinity or a NaN */
    if (!((q[0] - q[0]) + (q[1] - q[1]) + (M[0] - M[0]) + (M[1] - M[1]) + (M[2] - M[2]) + (M[3] - M[3]) == 0.0))
        return LCP_BAD_INPUT;
    const double sq = dmax(dmax(0.0, dabs(q[0])), dabs(q[1]));
    double sM = dmax(dmax(dmax(dmax(0.0, dabs(M[0])), dabs(M[1])), dabs(M[2])), dabs(M[3]));
    const int rmin = (q[1] <= q[0]) ? 1 : 0;
    z[0] = z[1] = 0.0;
    w[0] = q[0];
    w[1] = q[1];
    z_basic[0] = z_basic[1] = 0;
    if (q[rmin] >= 0.0) return LCP_OK;
    if (sM == 0.0) sM = 1.0;
    const double iM = 1.0 / sM, iq = 1.0 / sq, zs = sq / sM;
    /* original columns of [I | -M' | -e] */
    double A[5][2] = {{1.0, 0.0}, {0.0, 1.0}, {0.0, 0.0}, {0.0, 0.0}, {-1.0, -1.0}};
    rev2 R = {{{1.0, 0.0}, {0.0, 1.0}}, {0.0, 0.0}, {0, 1}};
    if (isfinite(iM) && isfinite(iq)) {
        A[2][0] = -(M[0] * iM);
        A[2][1] = -(M[2] * iM);
        A[3][0] = -(M[1] * iM);
        A[3][1] = -(M[3] * iM);
        R.x[0] = q[0] * iq;
        R.x[1] = q[1] * iq;
    } else {
        A[2][0] = -scaled(M[0], sM, iM);
        A[2][1] = -scaled(M[2], sM, iM);
        A[3][0] = -scaled(M[1], sM, iM);
        A[3][1] = -scaled(M[3], sM, iM);
        R.x[0] = scaled(q[0], sq, iq);
        R.x[1] = scaled(q[1], sq, iq);
    }
    int leaving = rmin;
    pivot_rev2(&R, rmin, A[4]);
    R.basis[rmin] = 4;
    int count = 1;
    for (;;) {
        const int entering = (leaving < 2) ? leaving + 2 : leaving - 2;
        if (count >= max_pivots) { if (pivots) *pivots = count; return LCP_MAX_PIVOTS; }
        const double *a = A[entering];
        const double d[2] = {R.B[0][0] * a[0] + R.B[0][1] * a[1], R.B[1][0] * a[0] + R.B[1][1] * a[1]};
        const int row = ratio_rev2(&R, d);
        if (row < 0) { if (pivots) *pivots = count; return LCP_RAY; }
        leaving = R.basis[row];
        pivot_rev2(&R, row, d);
        R.basis[row] = entering;
        count++;
        if (leaving == 4) break;
    }
    if (pivots) *pivots = count;
    w[0] = w[1] = 0.0;
    for (int i = 0; i < 2; i++) {
        const int v = R.basis[i];
        const double val = dmax(R.x[i], 0.0);
        if (v < 2) w[v] = val * sq;
        else if (v < 4) { z[v - 2] = val * zs; z_basic[v - 2] = 1; }
    }
    return LCP_OK;
}

/* ---- the workspace ------------------------------------------------------------------------------ */

/* Everything Lemke and the warm start use for problems of up to n unknowns: the tableau
 * (n x COLS(n)), the warm start's elimination matrix (n x (n + 1)), the ratio test's column scales
 * (n), the basis list and the index set. */
struct lcp_workspace {
    int n;
    double *T, *A, *cs;
    int *basis, *J;
};

/* doubles and ints a workspace for n needs, or 0 when n is out of range (the tableau's indices are
 * int: n COLS(n) + n (n + 1) must fit) */
static size_t ws_doubles(int n)
{
    if (n < 1 || n > 26000) return 0;  /* 3 n^2 + 4 n < INT_MAX up to n = 26754 */
    return (size_t)n * (size_t)COLS(n) + (size_t)n * (size_t)(n + 1) + (size_t)n;
}

lcp_workspace *lcp_workspace_create(int n, const lcp_alloc *al)
{
    const size_t nd = ws_doubles(n);
    if (nd == 0 || !al || !al->allocate || !al->release) return NULL;
    lcp_workspace *ws = (lcp_workspace *)al->allocate(al->env, 1, sizeof(lcp_workspace));
    if (!ws) return NULL;
    ws->n = n;
    ws->T = (double *)al->allocate(al->env, nd, sizeof(double));
    ws->basis = (int *)al->allocate(al->env, 2 * (size_t)n, sizeof(int));
    if (!ws->T || !ws->basis) {
        lcp_workspace_free(ws, al);
        return NULL;
    }
    ws->A = ws->T + (size_t)n * (size_t)COLS(n);
    ws->cs = ws->A + (size_t)n * (size_t)(n + 1);
    ws->J = ws->basis + n;
    return ws;
}

void lcp_workspace_free(lcp_workspace *ws, const lcp_alloc *al)
{
    if (!ws || !al || !al->release) return;
    if (ws->T) al->release(al->env, ws->T);
    if (ws->basis) al->release(al->env, ws->basis);
    al->release(al->env, ws);
}

int lcp_workspace_size(const lcp_workspace *ws) { return ws ? ws->n : 0; }

/* A workspace on the stack for n <= LCP_STACK_N (the entry points without one). */
typedef struct {
    double T[LCP_STACK_N * COLS(LCP_STACK_N) + LCP_STACK_N * (LCP_STACK_N + 1) + LCP_STACK_N];
    int basis[2 * LCP_STACK_N];
    lcp_workspace ws;
} stack_ws;

static lcp_workspace *stack_workspace(stack_ws *s, int n)
{
    s->ws.n = n;
    s->ws.T = s->T;
    s->ws.A = s->T + (n > 0 ? n * COLS(n) : 0);
    s->ws.cs = s->ws.A + (n > 0 ? n * (n + 1) : 0);
    s->ws.basis = s->basis;
    s->ws.J = s->basis + (n > 0 ? n : 0);
    return &s->ws;
}

static int ws_fits(const lcp_workspace *ws, int n) { return ws && n >= 1 && n <= ws->n; }

lcp_status lcp_lemke_general_ws(lcp_workspace *ws, int n, const double *M, const double *q, int max_pivots,
                                double *z, double *w, int *z_basic, int *pivots)
{
    if (!ws_fits(ws, n)) {
        if (pivots) *pivots = 0;
        return LCP_BAD_INPUT;
    }
    return lemke(n, M, q, max_pivots, z, w, z_basic, pivots, ws->T, ws->basis, ws->cs);
}

lcp_status lcp_lemke_ws(lcp_workspace *ws, int n, const double *M, const double *q, int max_pivots,
                        double *z, double *w, int *z_basic, int *pivots)
{
    /* the friction problem of one degree of freedom is 2 x 2: a copy specialised for it */
    if (n == 2 && ws_fits(ws, n)) return lemke2(M, q, max_pivots, z, w, z_basic, pivots);
    return lcp_lemke_general_ws(ws, n, M, q, max_pivots, z, w, z_basic, pivots);
}

lcp_status lcp_lemke_general(int n, const double *M, const double *q, int max_pivots,
                             double *z, double *w, int *z_basic, int *pivots)
{
    if (n > LCP_STACK_N) n = 0; /* refused below */
    stack_ws s;
    return lcp_lemke_general_ws(stack_workspace(&s, n), n, M, q, max_pivots, z, w, z_basic, pivots);
}

lcp_status lcp_lemke(int n, const double *M, const double *q, int max_pivots,
                     double *z, double *w, int *z_basic, int *pivots)
{
    if (n == 2) return lemke2(M, q, max_pivots, z, w, z_basic, pivots);
    return lcp_lemke_general(n, M, q, max_pivots, z, w, z_basic, pivots);
}

/* ---- warm start -------------------------------------------------------------------------------- */

/* The complementary basis named by guess (z_i basic where guess[i], else w_i), if it solves the
 * problem: z_J = -M_JJ^-1 q_J >= 0 and w = M z + q >= 0 off J. Returns 1 and the solution, else 0.
 * A: n (n + 1) doubles, J: n ints (workspace). */
static int try_basis(int n, const double *M, const double *q, const int *guess, double *z, double *w, double *A,
                     int *J)
{
    int k = 0;
    for (int i = 0; i < n; i++) {
        z[i] = 0.0;
        if (guess[i]) J[k++] = i;
    }
    if (k > 0) {
        /* M_JJ z_J = -q_J by Gaussian elimination with partial pivoting; A is k x (k + 1) */
        const int s = k + 1;
        double scale = 0.0;
        for (int a = 0; a < k; a++) {
            for (int b = 0; b < k; b++) {
                A[a * s + b] = M[J[a] * n + J[b]];
                scale = dmax(scale, dabs(A[a * s + b]));
            }
            A[a * s + k] = -q[J[a]];
        }
        for (int c = 0; c < k; c++) {
            int piv = c;
            for (int r = c + 1; r < k; r++)
                if (dabs(A[r * s + c]) > dabs(A[piv * s + c])) piv = r;
            if (!(dabs(A[piv * s + c]) > 1e-13 * scale)) return 0; /* singular: let Lemke decide */
            if (piv != c)
                for (int b = c; b <= k; b++) {
                    const double t = A[c * s + b];
                    A[c * s + b] = A[piv * s + b];
                    A[piv * s + b] = t;
                }
            for (int r = c + 1; r < k; r++) {
                const double f = A[r * s + c] / A[c * s + c];
                for (int b = c; b <= k; b++) A[r * s + b] -= f * A[c * s + b];
            }
        }
        for (int c = k - 1; c >= 0; c--) {
            double v = A[c * s + k];
            for (int b = c + 1; b < k; b++) v -= A[c * s + b] * z[J[b]];
            v /= A[c * s + c];
            if (!(v >= 0.0)) return 0;
            z[J[c]] = v;
        }
    }
    for (int i = 0; i < n; i++) {
        if (guess[i]) { w[i] = 0.0; continue; }
        double v = q[i];
        for (int j = 0; j < k; j++) v += M[i * n + J[j]] * z[J[j]];
        if (!(v >= 0.0)) return 0;
        w[i] = v;
    }
    return 1;
}

lcp_status lcp_lemke_warm_ws(lcp_workspace *ws, int n, const double *M, const double *q, const int *guess,
                             int max_pivots, double *z, double *w, int *z_basic, int *pivots)
{
    if (guess && n == 2 && ws_fits(ws, n) && !(guess[0] && guess[1]))
        return lcp_lemke_warm2(M, q, guess, max_pivots, z, w, z_basic, pivots);
    if (guess && ws_fits(ws, n) && try_basis(n, M, q, guess, z, w, ws->A, ws->J)) {
        /* non-finite data fails the sign tests above, except where it is never read: check all */
        double fin = 0.0;
        for (int i = 0; i < n; i++) {
            fin += q[i] - q[i];
            for (int j = 0; j < n; j++) fin += M[i * n + j] - M[i * n + j];
        }
        if (fin == 0.0) {
            for (int i = 0; i < n; i++) z_basic[i] = guess[i] != 0;
            if (pivots) *pivots = 0;
            return LCP_OK;
        }
    }
    return lcp_lemke_ws(ws, n, M, q, max_pivots, z, w, z_basic, pivots);
}

lcp_status lcp_lemke_warm(int n, const double *M, const double *q, const int *guess, int max_pivots,
                          double *z, double *w, int *z_basic, int *pivots)
{
    if (guess && n == 2 && !(guess[0] && guess[1])) return lcp_lemke_warm2(M, q, guess, max_pivots, z, w, z_basic, pivots);
    if (n > LCP_STACK_N) n = 0; /* refused below */
    stack_ws s;
    return lcp_lemke_warm_ws(stack_workspace(&s, n), n, M, q, guess, max_pivots, z, w, z_basic, pivots);
}

const char *lcp_status_text(lcp_status s)
{
    switch (s) {
    case LCP_OK: return "solved";
    case LCP_RAY: return "ray termination (no solution found)";
    case LCP_MAX_PIVOTS: return "pivot limit reached";
    case LCP_BAD_INPUT: return "invalid problem (size or non-finite entries)";
    }
    return "unknown status";
}

/* ---- the box LCP of a tridiagonal M (see lcp.h) ------------------------------------------------- */

static int sgn(double x) { return (x > 0.0) - (x < 0.0); }

/* Row i of lcp_box_basis's forward elimination (ei: e_i, 0 on the last row; elo: e_{i-1}, 0 on the
 * first; cprev, dprev: the row above's cp and dp, updated): a held row's cp, dp 0, another's Thomas
 * step, its w its limit's (lcp_box_basis_w's). diag: the pivot d_i itself (lcp_box_basis_diag). */
static inline void box_elim_row(size_t i, const double *d, double ei, double elo, const double *q, const double *l,
                                const int *mode, double *cprev, double *dprev, double *cp, double *dp, double *w,
                                int diag)
{
    double c = 0.0, v = 0.0;
    if (!(mode[i] == 0 && l[i] > 0.0)) {
        /* M z = -q + w with w = -mode l: the right-hand side -q - mode l */
        const double ml = (l[i] > 0.0) ? mode[i] * l[i] : 0.0;
        const double rhs = -q[i] - ml;
        const double den = diag ? d[i] : d[i] - elo * *cprev;
        const double inv = 1.0 / den;
        c = ei * inv;
        v = (rhs - elo * *dprev) * inv;
        w[i] = 0.0 - ml;
    }
    cp[i] = c;
    dp[i] = v;
    *cprev = c;
    *dprev = v;
}

/* lcp_box_basis_w's w of held row i from its neighbours' z (zlo: row i - 1's, zhi: row i + 1's) */
static inline double box_held_w(size_t lo, size_t hi, size_t i, const double *e, const double *q, double zlo,
                                double zhi)
{
    double f = q[i];
    if (i > lo) f += e[i - 1] * zlo;
    if (i + 1 < hi) f += e[i] * zhi;
    return f;
}

/* lcp_box_basis, and lcp_box_basis_diag with diag */
static inline void box_basis(size_t lo, size_t hi, int fix_lo, double z_lo, int fix_hi, double z_hi, const double *d,
                             const double *e, const double *q, const double *l, const int *mode, double *z, double *w,
                             double *cp, double *dp, int diag)
{
    if (hi <= lo) return;
    /* forward elimination (Thomas) over the rows that are not fixed or held; a fixed or held row
     * has cp = 0 and dp its value, so it starts the elimination afresh. The fixed rows [lo, a) and
     * [b, hi) out of the loops (a row both first and last takes z_lo), and the last row's */
    const size_t a = lo + (size_t)fix_lo, b = (hi - (size_t)fix_hi > a) ? hi - (size_t)fix_hi : a;
    const size_t bl = (b < hi - 1) ? b : hi - 1; /* (the rows with an e_i) */
    double cprev = 0.0, dprev = 0.0;
    if (fix_lo) {
        cp[lo] = 0.0;
        dp[lo] = dprev = z_lo;
    }
    if (a < bl) box_elim_row(a, d, e[a], (a > lo) ? e[a - 1] : 0.0, q, l, mode, &cprev, &dprev, cp, dp, w, diag);
    for (size_t i = a + 1; i < bl; i++) box_elim_row(i, d, e[i], e[i - 1], q, l, mode, &cprev, &dprev, cp, dp, w, diag);
    if (b == hi && a < hi) { /* the last row, not fixed: its cp 0 (not 0 / den) */
        box_elim_row(hi - 1, d, 0.0, (hi - 1 > lo) ? e[hi - 2] : 0.0, q, l, mode, &cprev, &dprev, cp, dp, w, diag);
        cp[hi - 1] = 0.0;
    }
    if (b < hi) {
        cp[hi - 1] = 0.0;
        dp[hi - 1] = z_hi;
    }
    /* back substitution, with lcp_box_basis_w's end on the held rows of [a, b) once their neighbours
     * are known: a held row's z set to 0 (read as such by the row below), the row above's z as the
     * substitution left it (zr1, zr2: the substitution's z of rows j + 1 and j + 2; h1: row j + 1 is
     * such a held row) */
    double zn = 0.0, zr1 = 0.0, zr2 = 0.0;
    int h1 = 0;
    for (size_t j = hi; j-- > b;) {
        zn = dp[j] - cp[j] * zn;
        z[j] = zn;
        zr2 = zr1;
        zr1 = zn;
    }
    for (size_t j = b; j-- > a;) {
        zn = dp[j] - cp[j] * zn;
        const int held = mode[j] == 0 && l[j] > 0.0;
        const double zj = held ? 0.0 : zn;
        z[j] = zj;
        if (h1) w[j + 1] = box_held_w(lo, hi, j + 1, e, q, zj, zr2);
        h1 = held;
        zr2 = zr1;
        zr1 = zn;
    }
    for (size_t j = a; j-- > lo;) {
        zn = dp[j] - cp[j] * zn;
        z[j] = zn;
        if (h1) w[j + 1] = box_held_w(lo, hi, j + 1, e, q, zn, zr2);
        h1 = 0;
        zr2 = zr1;
        zr1 = zn;
    }
    if (h1) w[lo] = box_held_w(lo, hi, lo, e, q, 0.0, zr2);
}

void lcp_box_basis(size_t lo, size_t hi, int fix_lo, double z_lo, int fix_hi, double z_hi, const double *d,
                   const double *e, const double *q, const double *l, const int *mode, double *z, double *w,
                   double *cp, double *dp)
{
    box_basis(lo, hi, fix_lo, z_lo, fix_hi, z_hi, d, e, q, l, mode, z, w, cp, dp, 0);
}

void lcp_box_basis_diag(size_t lo, size_t hi, int fix_lo, double z_lo, int fix_hi, double z_hi, const double *d,
                        const double *e, const double *q, const double *l, const int *mode, double *z, double *w,
                        double *cp, double *dp)
{
    box_basis(lo, hi, fix_lo, z_lo, fix_hi, z_hi, d, e, q, l, mode, z, w, cp, dp, 1);
}

/* ---- the box LCP's driver, for any M ----------------------------------------------------------
 * The same pivoting for the tridiagonal and the dense M, written once over what differs: the basis
 * solve of the modes (solve), and a row of M for projected Gauss-Seidel (row: -q_i minus the
 * off-diagonal terms of row i times z, and M_ii). Inlined into each solver with its own functions,
 * so that neither pays for the other. */

typedef struct box_ops box_ops;
struct box_ops {
    void (*solve)(box_ops *ops, const int *mode, double *z, double *w);
    double (*row)(const box_ops *ops, size_t i, const double *z, double *diag);
    const double *d, *e, *M, *q, *l; /* the tridiagonal's d, e, or the dense M */
    size_t n;
    double *work;
    int failed;                       /* the dense solve met a pivot <= 0: M not positive definite */
};

/* Principal pivoting from the modes: all infeasible rows flipped for three rounds, then the least
 * index only (Murty's rule); infeasibilities up to tol of the problem's scale accepted. Returns the
 * pivots, or -1 when max_it ran out. */
static ALWAYS_INLINE long box_pivoting(box_ops *ops, int *mode, double *z, double *w, long max_it, double tol)
{
    const size_t n = ops->n;
    const double *q = ops->q, *l = ops->l;
    for (long it = 0; it < max_it; it++) {
        ops->solve(ops, mode, z, w);
        if (ops->failed) return -1;
        double zs = 0.0, ws = 0.0;
        if (tol > 0.0)
            for (size_t i = 0; i < n; i++) { zs = fmax(zs, fabs(z[i])); ws = fmax(ws, fabs(q[i]) + l[i]); }
        int flipped = 0;
        for (size_t i = 0; i < n; i++) {
            if (!(l[i] > 0.0)) { mode[i] = sgn(z[i]); continue; }
            int to = mode[i];
            if (mode[i] != 0 && mode[i] * z[i] < -tol * zs) to = 0;
            else if (mode[i] == 0 && w[i] > l[i] + tol * ws) to = -1;
            else if (mode[i] == 0 && w[i] < -l[i] - tol * ws) to = 1;
            if (to != mode[i] && (it < 3 || !flipped)) {
                mode[i] = to;
                flipped = 1;
            }
        }
        if (!flipped) return it;
    }
    return -1;
}

static ALWAYS_INLINE lcp_status box_solve(box_ops *ops, int *mode, double *z, double *w, int *pivots)
{
    const size_t n = ops->n;
    const double *l = ops->l;
    const long budget = 8 * (long)n + 32;
    long piv = box_pivoting(ops, mode, z, w, budget, 0.0);
    if (piv < 0 && !ops->failed) {
        /* Stiff problems (M far from diagonal dominance) can make the pivoting wander: projected
         * Gauss-Seidel (coordinate descent on the strictly convex min z'M z / 2 + q'z + sum l |z|,
         * convergent for M positive definite) finds the modes, the pivoting polishes. */
        for (size_t i = 0; i < n; i++) z[i] = 0.0;
        for (long sweep = 0; sweep < 1000000; sweep++) {
            double dz = 0.0, zs = 0.0;
            for (size_t i = 0; i < n; i++) {
                double di;
                const double r = ops->row(ops, i, z, &di);
                const double v = (r > l[i]) ? (r - l[i]) / di : (r < -l[i]) ? (r + l[i]) / di : 0.0;
                dz = fmax(dz, fabs(v - z[i]));
                zs = fmax(zs, fabs(v));
                z[i] = v;
            }
            if (dz <= 1e-15 * zs) break;
        }
        for (size_t i = 0; i < n; i++) mode[i] = sgn(z[i]);
        /* the polish accepts infeasibilities of rounding size (1e-10 of the problem's scale): on an
         * ill-conditioned M they would make the exact rule cycle */
        piv = box_pivoting(ops, mode, z, w, budget, 1e-10);
        if (piv >= 0) piv += budget;
    }
    if (pivots) *pivots = (piv >= 0) ? (int)piv : 0;
    if (ops->failed) return LCP_BAD_INPUT;
    return (piv >= 0) ? LCP_OK : LCP_MAX_PIVOTS;
}

/* ---- the tridiagonal M ---- */

static void tri_solve(box_ops *ops, const int *mode, double *z, double *w)
{
    lcp_box_basis(0, ops->n, 0, 0.0, 0, 0.0, ops->d, ops->e, ops->q, ops->l, mode, z, w, ops->work,
                  ops->work + ops->n);
}

static double tri_row(const box_ops *ops, size_t i, const double *z, double *diag)
{
    double r = -ops->q[i];
    if (i > 0) r -= ops->e[i - 1] * z[i - 1];
    if (i + 1 < ops->n) r -= ops->e[i] * z[i + 1];
    *diag = ops->d[i];
    return r;
}

lcp_status lcp_box(size_t n, const double *d, const double *e, const double *q, const double *l, int *mode,
                   double *z, double *w, double *work, int *pivots)
{
    box_ops ops = {tri_solve, tri_row, d, e, NULL, q, l, n, work, 0};
    return box_solve(&ops, mode, z, w, pivots);
}

/* ---- the dense M ---- */

size_t lcp_box_dense_work(size_t n) { return n * n + 2 * n; }

/* The basis solve of the modes: rows held at z_i = 0 (mode 0, l > 0) out, the others with
 * w_i = -mode_i l_i (l_i = 0: w_i = 0); M_FF z_F = -q_F - mode_F l_F by Cholesky (M_FF = L L', L
 * by columns into work), then w = M z + q on the held rows. */
static void dense_solve(box_ops *ops, const int *mode, double *z, double *w)
{
    const size_t n = ops->n;
    const double *M = ops->M, *q = ops->q, *l = ops->l;
    double *L = ops->work, *b = ops->work + n * n;
    double *Fd = ops->work + n * n + n; /* the free rows' indices (as doubles: exact) */
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        z[i] = 0.0;
        if (!(mode[i] == 0 && l[i] > 0.0)) Fd[k++] = (double)i;
    }
#define F(r) ((size_t)Fd[r])
    for (size_t c = 0; c < k; c++) { /* L's column c, from row c down */
        for (size_t r = c; r < k; r++) {
            double v = M[F(r) * n + F(c)];
            for (size_t j = 0; j < c; j++) v -= L[j * k + r] * L[j * k + c];
            L[c * k + r] = v;
        }
        const double piv = L[c * k + c];
        if (!(piv > 0.0)) {
            ops->failed = 1;
            return;
        }
        const double s = sqrt(piv);
        for (size_t r = c; r < k; r++) L[c * k + r] /= s;
    }
    for (size_t r = 0; r < k; r++) { /* L y = b */
        const size_t i = F(r);
        double v = -q[i] - ((l[i] > 0.0) ? mode[i] * l[i] : 0.0);
        for (size_t j = 0; j < r; j++) v -= L[j * k + r] * b[j];
        b[r] = v / L[r * k + r];
    }
    for (size_t r = k; r-- > 0;) { /* L' z = y */
        double v = b[r];
        for (size_t j = r + 1; j < k; j++) v -= L[r * k + j] * z[F(j)];
        z[F(r)] = v / L[r * k + r];
    }
    for (size_t i = 0; i < n; i++) {
        if (mode[i] == 0 && l[i] > 0.0) {
            double v = q[i];
            for (size_t j = 0; j < n; j++) v += M[i * n + j] * z[j];
            w[i] = v;
        } else {
            w[i] = (l[i] > 0.0) ? 0.0 - mode[i] * l[i] : 0.0;
        }
    }
#undef F
}

static double dense_row(const box_ops *ops, size_t i, const double *z, double *diag)
{
    const size_t n = ops->n;
    const double *Mi = ops->M + i * n;
    double r = -ops->q[i];
    for (size_t j = 0; j < n; j++)
        if (j != i) r -= Mi[j] * z[j];
    *diag = Mi[i];
    return r;
}

lcp_status lcp_box_dense(size_t n, const double *M, const double *q, const double *l, int *mode, double *z,
                         double *w, double *work, int *pivots)
{
    if (pivots) *pivots = 0;
    for (size_t i = 0; i < n; i++) {
        if (!(fabs(q[i]) <= DBL_MAX) || !(l[i] >= 0.0 && l[i] <= DBL_MAX)) return LCP_BAD_INPUT;
        for (size_t j = 0; j < n; j++)
            if (!(fabs(M[i * n + j]) <= DBL_MAX)) return LCP_BAD_INPUT;
    }
    box_ops ops = {dense_solve, dense_row, NULL, NULL, M, q, l, n, work, 0};
    return box_solve(&ops, mode, z, w, pivots);
}
