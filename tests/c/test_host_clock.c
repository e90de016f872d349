/* Results do not depend on sub-ulp jitter of the host's clock (newmark.h, "Snapping to the grid").
 *
 * 1. Two hosts drive the same run: one computes its communication points as n dt, the other adds
 *    dt to its clock (as the FMU Compliance Checker does: 0.020000000000000011 instead of 0.02).
 *    Over 10^4 and 10^5 communication steps (dt = 0.01 and 0.001 with h = 1e-3, and dt = 0.0025,
 *    not a multiple of h), on the default model and a stick-slip case, for the three schemes:
 *    where dt is a multiple of h the two hosts' states are bit-identical at every communication
 *    point (every field of the state, caches and counters included), so within any tolerance
 *    (1e-14 relative over 10^4 steps, 1e-12 over 10^5). Where it is not, every other point is off
 *    the grid: there the hosts ask for truly different times (0.0075000000000000006 is the
 *    rounding of 0.0075, not of a grid point), each gets its own exactly, and the states differ
 *    by the motion over the clock difference delta; the step split there moves the following grid
 *    states too (by O(delta) where a switch falls into a split step for the paper and consistent
 *    schemes, far less for located). Bound asserted: relative difference <= rate_max delta, the
 *    most a time shift delta can change the state by.
 * 2. Jitter within the tolerance around the grid points gives bit-identical states to asking for
 *    the grid points themselves (fast paths on and off, observables on), and the deserialised-state
 *    check keeps the caches of a snapped state.
 * 3. An explicit off-grid point farther than the tolerance is honoured exactly, with a shortened
 *    step; one closer is the grid point. */
#include "check.h"
#include "osc_params.h"
#include "scheme.h"
#include "oscillator.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

typedef struct {
    dfo_model M;
    dfo_inputs in;
    dfo_state s;
} sim;

/* The FMU's defaults (modelDescription.xml): h = 1e-3, a mostly sliding motion with short stops. */
static dfo_params default_model(int scheme)
{
    dfo_params p = osc_test_params(scheme, 1.0, 100.0, 0.0, 1.0, 5.0, 1.0, 0.4, 0.7);
    p.h = 0.001;
    return p;
}

/* Stick-slip: long stick phases (breakaway limit 0.8 of the excitation), damping, chi = 0.5. */
static dfo_params stick_slip(int scheme)
{
    dfo_params p = default_model(scheme);
    p.mu_s = 0.8;
    p.chi = 0.5;
    p.c = 0.5;
    p.x0 = 0.002;
    return p;
}

static void sim_start(sim *S, const dfo_params *p)
{
    memset(S, 0, sizeof *S);
    dfo_model_init(&S->M, p);
    dfo_start(&S->M, &S->in, 0.0, &S->s);
}

static dfo_status sim_to(sim *S, double t) { return dfo_advance(&S->M, &S->in, &S->s, t, NULL, NULL); }

#define SAME_BITS(a, b, f) (memcmp(&(a)->f, &(b)->f, sizeof (a)->f) == 0)

/* Every field of two states, bit for bit (padding excluded). */
static int same_state_bits(const dfo_state *a, const dfo_state *b)
{
    return SAME_BITS(a, b, t0) && SAME_BITS(a, b, t) && SAME_BITS(a, b, n) && SAME_BITS(a, b, X) &&
           SAME_BITS(a, b, V) && SAME_BITS(a, b, A) && SAME_BITS(a, b, hA) && SAME_BITS(a, b, F) &&
           SAME_BITS(a, b, mode) && SAME_BITS(a, b, x_max) && SAME_BITS(a, b, x_min) && SAME_BITS(a, b, t_stuck) &&
           SAME_BITS(a, b, E_friction) && SAME_BITS(a, b, transitions) && SAME_BITS(a, b, observed) &&
           SAME_BITS(a, b, stick_C) && SAME_BITS(a, b, stick_Fb) && SAME_BITS(a, b, stick_tb) &&
           SAME_BITS(a, b, stick_dir) && SAME_BITS(a, b, exc_n) && SAME_BITS(a, b, exc_c) &&
           SAME_BITS(a, b, exc_s) && SAME_BITS(a, b, steps) && SAME_BITS(a, b, lcp_solves);
}

static int on_grid(const sim *S) { return S->s.t == S->s.t0 + (double)S->s.n * S->M.p.h; }

/* ---- 1. t = n dt against t += dt ----------------------------------------------------------- */

typedef struct {
    long long grid_points, identical, offgrid_points;
    double x_scale, v_scale;   /* largest |x|, |v| of the run */
    double dx, dv;             /* largest |x_add - x_mul|, |v_add - v_mul| at common grid points */
    double offgrid_excess;     /* largest | |x_add - x_mul| - |v| |t_add - t_mul| | off the grid */
    double clock_drift;        /* largest |t_add - n dt| */
} agreement;

static void two_hosts(checks *T, const dfo_params *p, const char *what, double dt, long long steps, double rel_tol)
{
    sim A, B;  /* A: t = n dt; B: t += dt */
    sim_start(&A, p);
    sim_start(&B, p);
    agreement g;
    memset(&g, 0, sizeof g);
    check_context(T, "hosts: %s, scheme %d, dt = %g, %lld steps", what, p->scheme, dt, steps);
    const double ratio = dt / p->h;
    const int multiple = fabs(ratio - floor(ratio + 0.5)) < 1e-9;
    double t_add = 0.0;
    int ok = 1;
    for (long long n = 1; n <= steps && ok; n++) {
        const double t_mul = (double)n * dt;
        t_add += dt;
        ok &= CHECK_INT(DFO_OK, sim_to(&A, t_mul));
        ok &= CHECK_INT(DFO_OK, sim_to(&B, t_add));
        g.clock_drift = fmax(g.clock_drift, fabs(t_add - t_mul));
        g.x_scale = fmax(g.x_scale, fabs(A.s.X));
        g.v_scale = fmax(g.v_scale, fabs(A.s.V));
        if (on_grid(&A)) {
            /* both hosts' points snapped to the same grid point, or A's is exactly one */
            ok &= CHECK_SAME(A.s.t, B.s.t);
            g.grid_points++;
            g.identical += same_state_bits(&A.s, &B.s);
            g.dx = fmax(g.dx, fabs(A.s.X - B.s.X));
            g.dv = fmax(g.dv, fabs(A.s.V - B.s.V));
        } else {
            /* an off-grid point: honoured exactly by both; the states differ by the motion over
             * the hosts' time difference */
            ok &= CHECK_SAME(t_mul, A.s.t) & CHECK_SAME(t_add, B.s.t);
            g.offgrid_points++;
            g.offgrid_excess = fmax(g.offgrid_excess,
                                    fabs(fabs(A.s.X - B.s.X) - fabs(A.s.V) * fabs(t_add - t_mul)));
        }
    }
    const double rx = g.dx / g.x_scale, rv = g.dv / g.v_scale;
    printf("hosts %-12s scheme %d dt %-6g %6lld steps: clock drift %.2e (%.2e h); %lld grid points, %lld "
           "bit-identical, max rel. |dx| %.2e |dv| %.2e; %lld off-grid points, |dx| - |v dt| within %.2e "
           "of x scale (rate_max drift %.2e)\n", what, p->scheme, dt, steps, g.clock_drift, g.clock_drift / p->h,
           g.grid_points, g.identical, rx, rv, g.offgrid_points, g.offgrid_excess / g.x_scale,
           A.M.rate_max * g.clock_drift);
    CHECK(g.grid_points > 0);
    const double bound = multiple ? rel_tol : fmax(rel_tol, A.M.rate_max * g.clock_drift);
    CHECK_RANGE(0.0, bound, rx);
    CHECK_RANGE(0.0, bound, rv);
    if (multiple) {
        CHECK_INT(steps, g.grid_points);
        CHECK_INT(g.grid_points, g.identical);  /* bit for bit, caches and counters included */
    } else {
        CHECK(g.offgrid_points > 0);
        CHECK_RANGE(0.0, bound, g.offgrid_excess / g.x_scale);
    }
    /* the drift the snap must cover really is far above a few ulps of t */
    if (steps >= 100000 && multiple) CHECK(g.clock_drift > 100.0 * DBL_EPSILON * (double)steps * dt);
    T->context = NULL;
}

static void test_two_hosts(checks *T)
{
    const double dts[] = {0.01, 0.001, 0.0025};
    for (int scheme = 1; scheme <= 3; scheme++)
        for (int model = 0; model < 2; model++) {
            const dfo_params p = model ? stick_slip(scheme) : default_model(scheme);
            const char *what = model ? "stick-slip" : "default";
            for (int d = 0; d < 3; d++) {
                two_hosts(T, &p, what, dts[d], 10000, 1e-14);
                two_hosts(T, &p, what, dts[d], 100000, 1e-12);
            }
        }
}

/* ---- 2. jitter within the tolerance --------------------------------------------------------- */

static void jitter_case(checks *T, const dfo_params *p, const char *what)
{
    sim G, J;  /* G: the grid points themselves; J: each moved by up to 0.9 tol either way */
    sim_start(&G, p);
    sim_start(&J, p);
    rng r = {12345};
    check_context(T, "jitter: %s, scheme %d, fastPaths %d, observe %d", what, p->scheme, p->fastPaths, p->observe);
    long long points = 0, identical = 0, caches_kept = 0;
    long long m = 0;
    for (int k = 1; k <= 3000; k++) {
        m += 1 + rng_int(&r, 40);  /* 1 to 40 grid steps per communication step */
        const double grid = G.s.t0 + (double)m * p->h;
        const double t_j = grid + rng_range(&r, -0.9, 0.9) * dfo_snap_tolerance(&G.M, grid);
        if (!(CHECK_INT(DFO_OK, sim_to(&G, grid)) & CHECK_INT(DFO_OK, sim_to(&J, t_j)))) break;
        CHECK_SAME(grid, J.s.t);
        points++;
        identical += same_state_bits(&G.s, &J.s);
        if (k % 50 == 0) {  /* a deserialised copy of a snapped state keeps its caches */
            dfo_state copy = J.s;
            dfo_check_caches(&J.M, &copy);
            caches_kept += same_state_bits(&copy, &J.s);
        }
    }
    CHECK_INT(points, identical);
    CHECK_INT(points / 50, caches_kept);
    T->context = NULL;
}

static void test_jitter(checks *T)
{
    for (int scheme = 1; scheme <= 3; scheme++)
        for (int fast = 0; fast <= 1; fast++)
            for (int model = 0; model < 2; model++) {
                dfo_params p = model ? stick_slip(scheme) : default_model(scheme);
                p.fastPaths = fast;
                p.observe = 1;
                p.t_obs_start = 5.0;
                p.t_obs_stop = 40.0;
                jitter_case(T, &p, model ? "stick-slip" : "default");
            }
    printf("jitter: 3000 communication points within 0.9 tol of the grid, bit-identical to the grid "
           "points (3 schemes x fastPaths x 2 models)\n");
}

/* ---- 3. explicit off-grid points ------------------------------------------------------------ */

static void test_offgrid(checks *T)
{
    for (int scheme = 1; scheme <= 3; scheme++) {
        const dfo_params p = default_model(scheme);
        sim S;
        sim_start(&S, &p);
        check_context(T, "off-grid points: scheme %d", scheme);
        const double h = p.h, g1 = 1234.0 * h, g2 = 1235.0 * h, tol = dfo_snap_tolerance(&S.M, g2);
        CHECK_RANGE(1e-7 * h, 1e-5 * h, tol);
        CHECK_INT(DFO_OK, sim_to(&S, g1));
        CHECK_SAME(g1, S.s.t);
        CHECK_INT(1234, S.s.n);
        const long long steps0 = S.s.steps;
        /* a point within the tolerance after the current grid point: that grid point, no step */
        CHECK_SAME(g1, dfo_snap_target(&S.M, &S.s, g1 + 0.5 * tol));
        CHECK_INT(DFO_OK, sim_to(&S, g1 + 0.5 * tol));
        CHECK_SAME(g1, S.s.t);
        CHECK_INT(steps0, S.s.steps);
        /* farther than the tolerance: honoured exactly with a shortened step (a step of 2 tol) */
        const dfo_state before = S.s;
        const double t_off = g1 + 2.0 * tol;
        CHECK_SAME(t_off, dfo_snap_target(&S.M, &S.s, t_off));
        CHECK_INT(DFO_OK, sim_to(&S, t_off));
        CHECK_SAME(t_off, S.s.t);
        CHECK_INT(1234, S.s.n);
        CHECK_INT(steps0 + 1, S.s.steps);
        /* a sliding block's Bossak acceleration belongs to the shortened step */
        if (S.s.mode != 0) CHECK_SAME(t_off - g1, S.s.hA);
        CHECK(before.t == g1);
        /* the rest of the grid step, then points just before and after the next grid point */
        CHECK_INT(DFO_OK, sim_to(&S, g2 - 0.5 * tol));
        CHECK_SAME(g2, S.s.t);
        CHECK_INT(1235, S.s.n);
        CHECK_INT(steps0 + 2, S.s.steps);
        const double g3 = 1236.0 * h;
        CHECK_INT(DFO_OK, sim_to(&S, g3 - 2.0 * tol));
        CHECK_SAME(g3 - 2.0 * tol, S.s.t);
        CHECK_INT(1235, S.s.n);
        CHECK_INT(DFO_OK, sim_to(&S, g3 + 0.5 * tol));
        CHECK_SAME(g3, S.s.t);
        CHECK_INT(1236, S.s.n);
        CHECK_INT(steps0 + 4, S.s.steps);
        /* the tolerance: 2^16 eps |t| between the bounds 1e-7 h and 1e-5 h */
        CHECK_SAME(1e-7 * h, dfo_snap_tolerance(&S.M, 0.0));
        CHECK_SAME(0x1p16 * DBL_EPSILON * 100.0, dfo_snap_tolerance(&S.M, 100.0));
        CHECK_SAME(1e-5 * h, dfo_snap_tolerance(&S.M, 1e6));
        /* the Compliance Checker's clock: 0.001 added 20 times is 0.020000000000000011, which is
         * the grid point 20 h = 0.02 */
        sim K;
        sim_start(&K, &p);
        double t_add = 0.0;
        for (int i = 0; i < 20; i++) t_add += 0.001;
        CHECK(t_add != 20.0 * h);
        CHECK_SAME(20.0 * h, dfo_snap_target(&K.M, &K.s, t_add));
        CHECK_INT(DFO_OK, sim_to(&K, t_add));
        CHECK_SAME(20.0 * h, K.s.t);
        CHECK_INT(20, K.s.steps);
        /* far beyond an exact grid count: never snapped */
        CHECK_SAME(1e300, dfo_snap_target(&S.M, &S.s, 1e300));
    }
    T->context = NULL;
}

int main(void)
{
    checks C = {0, 0, NULL, {0}}, *T = &C;
    test_two_hosts(T);
    test_jitter(T);
    test_offgrid(T);
    return checks_done(T, "test_host_clock");
}
