/* Lemke's algorithm, lexicographic variant. See lcp.h. */
#include "lcp.h"

#include <math.h>

static double dmax(double a, double b) { return a > b ? a : b; }
static double dabs(double a) { return a < 0.0 ? -a : a; }

/* Tableau columns: [0, n) w, [n, 2n) z, 2n z0, 2n + 1 right-hand side. Variable ids equal the
 * column index of the variable. */
#define COLS(n) (2 * (n) + 2)

static inline void pivot(double *T, const int n, int row, int col)
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
static inline int ratio_test(const double *T, const int n, int col, const int *basis)
{
    const int nc = COLS(n);
    const int rhs = 2 * n + 1;
    double colmax = 0.0;
    for (int i = 0; i < n; i++) colmax = dmax(colmax, dabs(T[i * nc + col]));
    const double tol = 1e-13 * colmax;
    int best = -1;
    for (int i = 0; i < n; i++) {
        const double d = T[i * nc + col];
        if (!(d > tol)) continue;
        if (best < 0) { best = i; continue; }
        const double db = T[best * nc + col];
        /* compare a = T[i][k] / d with b = T[best][k] / db for k = rhs, 0, 1, ..., n-1, cross-
         * multiplied (d, db > 0): a - b has the sign of T[i][k] db - T[best][k] d. Values closer
         * than 1e-12 of the column's scale are ties: rounding of earlier pivots must not break a
         * tie of the exact problem. */
        int cmp = 0;
        for (int k = -1; k < n && cmp == 0; k++) {
            const int c = (k < 0) ? rhs : k;
            double cscale = 0.0;
            for (int r = 0; r < n; r++) cscale = dmax(cscale, dabs(T[r * nc + c]));
            const double ad = T[i * nc + c] * db, bd = T[best * nc + c] * d;
            const double eps = 1e-12 * (dmax(dabs(ad), dabs(bd)) + cscale * d * db / colmax);
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

static inline lcp_status lemke(const int n, const double *M, const double *q, int max_pivots,
                               double *z, double *w, int *z_basic, int *pivots)
{
    if (pivots) *pivots = 0;
    if (n < 1 || n > LCP_MAX_N) return LCP_BAD_INPUT;
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
    double T[LCP_MAX_N * COLS(LCP_MAX_N)];
    int basis[LCP_MAX_N];
    for (int i = 0; i < n; i++) {
        double *r = T + i * nc;
        for (int j = 0; j < n; j++) {
            r[j] = (i == j) ? 1.0 : 0.0;
            r[n + j] = -M[i * n + j] / sM;
        }
        r[z0] = -1.0;
        r[rhs] = q[i] / sq;
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
        const int row = ratio_test(T, n, entering, basis);
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
        else if (v < 2 * n) { z[v - n] = val * (sq / sM); z_basic[v - n] = 1; }
    }
    return LCP_OK;
}

lcp_status lcp_lemke(int n, const double *M, const double *q, int max_pivots,
                     double *z, double *w, int *z_basic, int *pivots)
{
    /* the friction problem of one degree of freedom is 2 x 2: a copy specialised for it */
    if (n == 2) return lemke(2, M, q, max_pivots, z, w, z_basic, pivots);
    return lemke(n, M, q, max_pivots, z, w, z_basic, pivots);
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
