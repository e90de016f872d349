/* Linear complementarity problems of the friction, in one convention for both solvers:
 *
 *     w = M z + q,
 *
 * with the conditions that make it a problem of each kind:
 *   lcp_lemke*  (standard LCP, a small dense M, method.md section 3): z >= 0, w >= 0, z . w = 0,
 *               by Lemke's complementary pivoting (lexicographic minimum-ratio test, no cycling on
 *               degenerate problems, covering vector e = 1, any n);
 *   lcp_box*    (box LCP, a symmetric positive definite M, tridiagonal (lcp_box, method.md section 9)
 *               or dense (lcp_box_dense, a structure's Delassus matrix)): z free,
 *               |w_i| <= l_i, z_i > 0 => w_i = -l_i, z_i < 0 => w_i = +l_i (l_i = 0: w_i = 0),
 *               the optimality condition of min z'M z / 2 + q'z + sum l_i |z_i|; by principal
 *               pivoting on the modes (the chain's friction: z the end velocities V, w the friction
 *               forces F, q = -p_hat, l the friction limits), O(n) per pivot.
 * A basis is named by flags: Lemke's z_basic[i] (z_i basic), the box's mode[i] (0: z_i = 0 held,
 * w_i inside its box; +1 / -1: z_i free with w_i = -l_i / +l_i, i.e. the sign z_i has).
 * Both return an lcp_status and the pivots done through *pivots (NULL: not wanted); sizes are int
 * for Lemke, size_t for the box (any n, O(n) memory). Neither allocates while it solves: Lemke's
 * workspace (O(n^2)) is made once for the largest n through the caller's allocation callbacks
 * (lcp_workspace_create, the *_ws entry points) or, for n <= LCP_STACK_N, is on the solver's stack
 * (the entry points without one); the box's is the caller's.
 * Plain C, no FMI types. */
#ifndef DFO_LCP_H
#define DFO_LCP_H

#include <float.h>
#include <math.h>
#include <stddef.h>

#define LCP_STACK_N 12  /* the largest n of the Lemke entry points without a workspace (on the stack) */

typedef enum {
    LCP_OK = 0,          /* solution found */
    LCP_RAY = 1,         /* secondary ray: no solution found (infeasible for this M; Lemke only) */
    LCP_MAX_PIVOTS = 2,  /* pivot budget used up */
    LCP_BAD_INPUT = 3    /* n out of range (n < 1, above LCP_STACK_N without a workspace, above the
                          * workspace's size with one) or a non-finite entry (Lemke and the dense box; the
                          * tridiagonal box solver does not test its data, non-finite entries come out in
                          * z and w), or a dense box M not positive definite */
} lcp_status;

/* M: n x n, row-major (1 <= n <= LCP_STACK_N). q: n. On LCP_OK, z and w (n each) hold the solution and basic[i] is
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

/* Allocation callbacks (zero-filled memory, as FMI's calloc); env is passed through. */
typedef struct {
    void *(*allocate)(void *env, size_t nobj, size_t size);
    void (*release)(void *env, void *obj);
    void *env;
} lcp_alloc;

/* Lemke's workspace for problems of up to n unknowns (O(n^2) doubles: the tableau and the warm
 * start's elimination), made through al and freed with the same al. NULL when n < 1, n > 26000
 * (the tableau's int indices) or an allocation failed. One workspace serves one solve at a time. */
typedef struct lcp_workspace lcp_workspace;
lcp_workspace *lcp_workspace_create(int n, const lcp_alloc *al);
void lcp_workspace_free(lcp_workspace *ws, const lcp_alloc *al);  /* ws may be NULL */
int lcp_workspace_size(const lcp_workspace *ws);                    /* its n; 0 for NULL */

/* lcp_lemke, lcp_lemke_general and lcp_lemke_warm for any 1 <= n <= lcp_workspace_size(ws)
 * (ws NULL or smaller: LCP_BAD_INPUT). The same pivots, and the same bits, as the entry points
 * without a workspace wherever both apply. */
lcp_status lcp_lemke_ws(lcp_workspace *ws, int n, const double *M, const double *q, int max_pivots,
                        double *z, double *w, int *z_basic, int *pivots);
lcp_status lcp_lemke_general_ws(lcp_workspace *ws, int n, const double *M, const double *q, int max_pivots,
                                double *z, double *w, int *z_basic, int *pivots);
lcp_status lcp_lemke_warm_ws(lcp_workspace *ws, int n, const double *M, const double *q, const int *guess,
                             int max_pivots, double *z, double *w, int *z_basic, int *pivots);

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

/* ---- the box LCP of a tridiagonal M ------------------------------------------------------------ *
 * M is given by its diagonal d[n] and off-diagonal e[n - 1] (e[i] couples rows i and i + 1; M
 * symmetric positive definite, so the problem has one solution z). */

/* The end of a basis solve of rows [lo, hi) on its rows [a, b): a held row's (mode 0, l > 0) z_i set to
 * 0 and its w_i = (M z + q)_i, another row's w_i = -mode_i l_i (0 where l_i = 0). */
static inline void lcp_box_basis_w(size_t lo, size_t hi, size_t a, size_t b, const double *e, const double *q,
                                   const double *l, const int *mode, double *z, double *w)
{
    for (size_t i = a; i < b; i++) {
        if (mode[i] == 0 && l[i] > 0.0) {
            z[i] = 0.0;
            double f = q[i];
            if (i > lo) f += e[i - 1] * z[i - 1];
            if (i + 1 < hi) f += e[i] * z[i + 1];
            w[i] = f;
        } else {
            w[i] = (l[i] > 0.0) ? 0.0 - mode[i] * l[i] : 0.0;
        }
    }
}

/* The basis solve of rows [lo, hi): rows with mode 0 and l > 0 held at z_i = 0, the others with
 * w_i = -mode_i l_i (l_i = 0: w_i = 0, z_i free); the first row (fix_lo) and the last row (fix_hi)
 * may be fixed at the given values z_lo, z_hi instead (Dirichlet rows: the neighbours of a cluster
 * solved on its own; their w is not set). Held rows get w_i = (M z + q)_i. cp, dp: hi entries of
 * workspace (the Thomas algorithm's). One solve, no test of the box: O(hi - lo). */
void lcp_box_basis(size_t lo, size_t hi, int fix_lo, double z_lo, int fix_hi, double z_hi, const double *d,
                   const double *e, const double *q, const double *l, const int *mode, double *z, double *w,
                   double *cp, double *dp);

/* lcp_box_basis for an M whose off-diagonal e holds zeros (signed or not) and whose diagonal is not 0:
 * each free row's pivot taken as d_i, which the elimination's d_i - e_{i-1} cp_{i-1} is then (the same
 * results, without the elimination's chain of dependencies through the pivots). */
void lcp_box_basis_diag(size_t lo, size_t hi, int fix_lo, double z_lo, int fix_hi, double z_hi, const double *d,
                        const double *e, const double *q, const double *l, const int *mode, double *z, double *w,
                        double *cp, double *dp);

/* Solve the box LCP by principal pivoting from the basis in mode[] (in: a guess, e.g. the modes of
 * the previous step; out: the solution's, 0 where z_i = 0): every infeasible row flipped for three
 * rounds, then the one of least index (Murty's rule), at most 8 n + 32 pivots; when that budget
 * runs out (a stiff M far from diagonal dominance), projected Gauss-Seidel (convergent for M
 * positive definite) finds the modes and the pivoting polishes them, accepting infeasibilities of
 * 1e-10 of the problem's scale (its pivots are counted from 8 n + 32 on). work: 2n doubles.
 * LCP_OK, or LCP_MAX_PIVOTS when the polish did not settle either. */
lcp_status lcp_box(size_t n, const double *d, const double *e, const double *q, const double *l, int *mode,
                   double *z, double *w, double *work, int *pivots);

/* ---- the box LCP of a dense M ------------------------------------------------------------------- *
 * The same problem for a dense symmetric positive definite M (n x n, row-major; e.g. a structure's
 * contacts through their Delassus matrix W M^-1 W'): the same conditions, modes, pivoting rules,
 * budget and Gauss-Seidel fallback as lcp_box, each basis solved by Cholesky's factorisation of its
 * free rows, O(n^3) per pivot. work: lcp_box_dense_work(n) doubles (n^2 + 2n), the caller's. M is
 * not tested for symmetry; a free block whose Cholesky pivot is <= 0 (M not positive definite to
 * rounding) and a non-finite entry (or l < 0) give LCP_BAD_INPUT. */
size_t lcp_box_dense_work(size_t n);
lcp_status lcp_box_dense(size_t n, const double *M, const double *q, const double *l, int *mode, double *z,
                         double *w, double *work, int *pivots);

const char *lcp_status_text(lcp_status s);

#endif
