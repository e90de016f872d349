/* Lemke's complementary pivoting algorithm for a small dense linear complementarity problem.
 *
 * Finds z >= 0 with w = M z + q >= 0 and z . w = 0 (method.md section 3), for any n <= LCP_MAX_N.
 * Lexicographic minimum-ratio test (no cycling on degenerate problems), covering vector e = 1,
 * pivot count bounded by the caller. No allocation: the workspace lives on the caller's stack.
 * Plain C, no FMI types. */
#ifndef DFO_LCP_H
#define DFO_LCP_H

#include <float.h>
#include <math.h>

#define LCP_MAX_N 12  /* the 2n problem of a chain of up to 6 blocks */

typedef enum {
    LCP_OK = 0,          /* solution found */
    LCP_RAY = 1,         /* secondary ray: no solution found (infeasible for this M) */
    LCP_MAX_PIVOTS = 2,  /* pivot budget used up */
    LCP_BAD_INPUT = 3    /* n out of range or a non-finite entry */
} lcp_status;

/* M: n x n, row-major. q: n. On LCP_OK, z and w (n each) hold the solution and basic[i] is
 * 1 when z[i] is basic (its complementarity pair is "active" on the z side). pivots, if not NULL,
 * receives the number of pivots done. */
lcp_status lcp_lemke(int n, const double *M, const double *q, int max_pivots,
                     double *z, double *w, int *z_basic, int *pivots);

/* The same on the general tableau, also for n = 2 (for tests: lcp_lemke solves n = 2 in revised
 * form, and the two must agree). */
lcp_status lcp_lemke_general(int n, const double *M, const double *q, int max_pivots,
                             double *z, double *w, int *z_basic, int *pivots);

/* Warm start: guess (n flags, may be NULL) names a complementary basis, z_i basic where guess[i]
 * and w_i basic elsewhere, e.g. the active set of the previous time step. When that basis solves the
 * problem (its basic variables come out >= 0 from one solve of M_JJ z_J = -q_J), it is returned
 * with 0 pivots; otherwise Lemke's algorithm runs from the start, as lcp_lemke. */
lcp_status lcp_lemke_warm(int n, const double *M, const double *q, const int *guess, int max_pivots,
                          double *z, double *w, int *z_basic, int *pivots);

/* The basis {z_i, w_o} (o = 1 - i) of a 2 x 2 problem, if it solves it; i is a constant at each
 * call below, so that everything stays in registers. */
static inline int lcp_basis2_zw(const double *M, const double *q, int i, double *z, double *w, int *z_basic)
{
    const int o = 1 - i;
    const double mii = M[3 * i];
    if (mii == 0.0) return 0;
    const double zi = -q[i] / mii, wo = q[o] + M[2 * o + i] * zi;
    if (!(zi >= 0.0 && wo >= 0.0)) return 0;
    z[i] = zi;
    z[o] = 0.0;
    w[i] = 0.0;
    w[o] = wo;
    z_basic[i] = 1;
    z_basic[o] = 0;
    return 1;
}

/* lcp_lemke_warm for n = 2 with at most one z in the guessed basis (the friction problem of one
 * degree of freedom: stuck, or sliding one way), inline: the stepper calls it at every step. */
static inline lcp_status lcp_lemke_warm2(const double *M, const double *q, const int *guess, int max_pivots,
                                         double *z, double *w, int *z_basic, int *pivots)
{
    if (guess[0] && guess[1]) return lcp_lemke_warm(2, M, q, guess, max_pivots, z, w, z_basic, pivots);
    /* |x| <= DBL_MAX is false for infinities and NaN: non-finite data goes to Lemke, which reports
     * it (the six tests are independent, not a chain) */
    const int finite = (fabs(q[0]) <= DBL_MAX) & (fabs(q[1]) <= DBL_MAX) & (fabs(M[0]) <= DBL_MAX) &
                       (fabs(M[1]) <= DBL_MAX) & (fabs(M[2]) <= DBL_MAX) & (fabs(M[3]) <= DBL_MAX);
    int ok = 0;
    if (finite) {
        if (guess[0]) {
            ok = lcp_basis2_zw(M, q, 0, z, w, z_basic);
        } else if (guess[1]) {
            ok = lcp_basis2_zw(M, q, 1, z, w, z_basic);
        } else if (q[0] >= 0.0 && q[1] >= 0.0) { /* w basic: z = 0 */
            z[0] = z[1] = 0.0;
            w[0] = q[0];
            w[1] = q[1];
            z_basic[0] = z_basic[1] = 0;
            ok = 1;
        }
    }
    if (!ok) return lcp_lemke(2, M, q, max_pivots, z, w, z_basic, pivots);
    if (pivots) *pivots = 0;
    return LCP_OK;
}

const char *lcp_status_text(lcp_status s);

#endif
