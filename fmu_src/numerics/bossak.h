/* The mathematics the friction engine (engine/), the oscillator and the chain (models/chain/) share:
 * the schemes' names, the rule of the default step, Bossak-Newmark's coefficients and the
 * kinematics of one step in velocity form (method.md section 2). The root finder that places a
 * switch inside a step is roots.h's.
 *
 * Plain C, no FMI types. */
#ifndef DFO_BOSSAK_H
#define DFO_BOSSAK_H

#include <float.h>
#include <math.h>
#include <stddef.h>

/* The schemes of both models (the FMUs' "scheme" enumeration; the chain has no exact scheme). */
typedef enum { DFO_SCHEME_PAPER = 1, DFO_SCHEME_CONSISTENT = 2, DFO_SCHEME_LOCATED = 3,
               DFO_SCHEME_EXACT = 4 } dfo_scheme;

/* The default step: h = 0 means "derived from the dynamics": 1/1000 of the shortest period of the
 * model (each model says which periods it has: oscillator.h, chain.h), so a default run resolves
 * every period at least as finely as a run at T/1000. Without any (no spring, excitation or
 * damper) the motion between events has constant acceleration, which every scheme integrates
 * exactly, and the step is DFO_STEP_FALLBACK. */
#define DFO_STEPS_PER_PERIOD 1000.0
#define DFO_STEP_FALLBACK 1e-3
/* Fewer internal steps than this per shortest period: a user-set h does not resolve the dynamics. */
#define DFO_MIN_STEPS_PER_PERIOD 20.0
/* The rule of it for any model: h when > 0, else 1/DFO_STEPS_PER_PERIOD of the shortest period T
 * (+inf: none, DFO_STEP_FALLBACK), always a normal number > 0. */
static inline double dfo_step_rule(double h, double T)
{
    if (h > 0.0) return h;
    const double d = isfinite(T) ? T / DFO_STEPS_PER_PERIOD : DFO_STEP_FALLBACK;
    return (d >= DBL_MIN && isfinite(d)) ? d : DBL_MIN;
}

/* The snap of a requested time to the time grid t0 + m h of a run that has reached the grid index
 * n_done and the time t: the nearest grid point m >= n_done, when it is at or after t and within
 * tol of t_target, else t_target itself (also before t0, beyond an exact count, or NaN). The grid
 * point as the stepping loops compute it, t0 + (double)m h. */
static inline double dfo_grid_snap(double t0, double h, long long n_done, double t, double t_target, double tol)
{
    const double r = (t_target - t0) / h; /* t_target in grid steps from t0 */
    if (!(r > -0.5 && r < 0x1p52)) return t_target;
    const long long m = (long long)floor(r + 0.5); /* the nearest grid point */
    if (m < n_done) return t_target;
    const double grid = t0 + (double)m * h;
    return (grid >= t && fabs(t_target - grid) <= tol) ? grid : t_target;
}

/* Newmark's coefficients for the Bossak parameter alpha in [-1/3, 0]: second order, stable. */
static inline double dfo_bossak_gamma(double alpha) { return 0.5 - alpha; }
static inline double dfo_bossak_beta(double alpha) { return 0.25 * (1.0 - alpha) * (1.0 - alpha); }

/* The kinematic coefficients of a step of length h, with V1 the unknown:
 *   A1 = (V1 - V0) c1 - (1 - g)/g A0,    X1 = X0 + pred_V V0 + pred_A A0 + corr_V V1. */
typedef struct {
    double h, c1, pred_V, pred_A, corr_V;
} dfo_bossak_kin;

static inline void dfo_bossak_kin_for(double h, double g, double b, dfo_bossak_kin *k)
{
    k->h = h;
    k->c1 = 1.0 / (g * h);
    k->pred_V = h * (1.0 - b / g);
    k->pred_A = h * h * (0.5 - b / g);
    k->corr_V = b * h / g;
}

/* How far a DOF's influence reaches inside one step of a structure whose M_hat is a chain of
 * couplings (a banded M_hat, its rows' diagonally scaled off-diagonal sums at most rho): M_hat^-1
 * decays like q^distance with q = (sqrt(kappa) - 1) / (sqrt(kappa) + 1) (Demko, Moss and Smith,
 * 1984), kappa <= (1 + rho) / (1 - rho) the condition number of the diagonally scaled M_hat by
 * Gershgorin; the smallest w with q^w <= 2^-56 (beyond w DOFs the influence is below rounding), n
 * where rho >= 1/2. By products (no libm log2: the same bits everywhere); q <= 0.27 below 1/2, so at
 * most 30 products. */
static inline size_t dfo_bossak_reach(double rho, size_t n)
{
    const double sk = sqrt((1.0 + rho) / (1.0 - fmin(rho, 0.5))), q = (sk - 1.0) / (sk + 1.0);
    size_t w = 1;
    if (rho >= 0.5) w = n;
    else if (rho > 0.0)
        for (double qw = q; qw > 0x1p-56; qw *= q) w++;
    return w;
}

#endif
