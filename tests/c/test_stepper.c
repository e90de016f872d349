/* Unit tests of the Bossak-Newmark stepper with the friction LCP (fmu_src/models/oscillator/newmark.h), driven
 * directly (no FMI): dfo_model_init, dfo_start, dfo_advance to successive communication points.
 *
 * 1. time: communication points land exactly (or on the grid point they snap to, newmark.h), the
 *    grid counter n, no drift over 10^6 steps;
 * 2. friction invariants at every communication point (schemes 1, 2, 3);
 * 3. energy balance of the located scheme with viscous damping;
 * 4. fast paths give the same numbers as the general path, bit for bit; a stuck block's observables;
 * 5. second order of the located scheme by self-convergence, across chi;
 * 6. hard inputs (zero coefficients, tiny and huge steps) run and stay finite;
 * 7. the caches of the state (excitation phase, next breakaway): emptied or forged mid-run, the run
 *    continues bit for bit; the excitation from the cache stays within rounding of the cosine.
 *
 * Non-dimensional setting unless said otherwise: m = k = P0 = 1, so w0 = 1, lambda = omega,
 * sigma = N, z = x. */
#include "check.h"
#include "scheme.h"
#include "oscillator.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

typedef struct {
    dfo_model M;
    dfo_inputs u;
    dfo_state s;
} sim;

/* lambda, mu_s sigma, chi, zeta: m = k = P0 = 1, mu_s = 0.5, N = 2 mu_s sigma */
static dfo_params nondim(double lambda, double mu_s_sigma, double chi, double zeta, int scheme, int per_period)
{
    dfo_params p;
    memset(&p, 0, sizeof p);
    p.m = 1.0;
    p.k = 1.0;
    p.c = 2.0 * zeta;
    p.P0 = 1.0;
    p.omega = lambda;
    p.phi = 0.0;
    p.mu_s = 0.5;
    p.N = mu_s_sigma / p.mu_s;
    p.chi = chi;
    p.x0 = 0.0;
    p.v0 = 0.0;
    p.h = (2.0 * DFO_PI / lambda) / per_period;
    p.alpha = -0.1;
    p.t_obs_start = 0.0;
    p.t_obs_stop = 1e300;
    p.scheme = scheme;
    p.frictionUpdates = 1;
    p.observe = 0;
    p.fastPaths = 1;
    return p;
}

static void sim_start(sim *S, const dfo_params *p, double t0)
{
    memset(S, 0, sizeof *S);
    dfo_model_init(&S->M, p);
    dfo_start(&S->M, &S->u, t0, &S->s);
}

static dfo_status sim_to(sim *S, double t) { return dfo_advance(&S->M, &S->u, &S->s, t, NULL, NULL); }

static double period_of(const dfo_params *p) { return 2.0 * DFO_PI / p->omega; }

static int state_finite(const sim *S)
{
    return isfinite(S->s.X) && isfinite(S->s.V) && isfinite(S->s.A) && isfinite(S->s.F) && isfinite(S->s.t);
}

/* ---- 1. time --------------------------------------------------------------------------------- */

/* The grid counter: n is the number of grid points t0 + i h (i >= 1) at or before t (a requested
 * time that snapped to a grid point ends exactly on it). */
static void check_grid_count(checks *T, const sim *S)
{
    const double h = S->M.p.h, t0 = S->s.t0, t = S->s.t;
    const long long n = S->s.n;
    CHECK(t0 + (double)n * h <= t);
    CHECK(t0 + (double)(n + 1) * h > t);
}

/* The time reached for the requested t (newmark.h): t itself, or the grid point t0 + n h it
 * snapped to, within the snap tolerance. */
static int check_time_reached(checks *T, const sim *S, double t)
{
    if (S->s.t == t) return CHECK_SAME(t, S->s.t);
    const double grid = S->s.t0 + (double)S->s.n * S->M.p.h;
    return CHECK_SAME(grid, S->s.t) && CHECK_RANGE(0.0, dfo_snap_tolerance(&S->M, t), fabs(t - S->s.t));
}

static void test_time(checks *T)
{
    const double t0s[] = {0.0, 0.3, 1234.5678};
    const double hs[] = {0.01, 0.001 * DFO_PI};
    const double dt_over_h[] = {0.37, 0.5, 1.0, 1.7, 2.718281828, 13.3};
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 2; b++)
            for (int c = 0; c < 6; c++)
                for (int scheme = 1; scheme <= 3; scheme++) {
                    dfo_params p = nondim(0.5, 0.4, 0.7, 0.02, scheme, 100);
                    p.h = hs[b];
                    const double t0 = t0s[a], dt = dt_over_h[c] * hs[b];
                    check_context(T, "time: t0 = %g, h = %g, dt = %g h, scheme %d", t0, p.h, dt_over_h[c], scheme);
                    sim S;
                    sim_start(&S, &p, t0);
                    CHECK(S.s.t == t0 && S.s.n == 0);
                    long long n_prev = 0;
                    for (int k = 1; k <= 3000; k++) {
                        const double t = t0 + k * dt;
                        if (!CHECK_INT(DFO_OK, sim_to(&S, t))) break;
                        if (!check_time_reached(T, &S, t)) break;
                        check_grid_count(T, &S);
                        CHECK(S.s.n >= n_prev);
                        n_prev = S.s.n;
                        if (dt_over_h[c] == 1.0) CHECK_INT(k, S.s.n);  /* on the grid: one point per call */
                    }
                    CHECK(state_finite(&S));
                }
    /* 10^6 steps, one call per grid point: t is t0 + n h exactly at every grid point (never
     * accumulated), then 10^6 steps in a single call */
    dfo_params p = nondim(0.5, 0.4, 0.7, 0.0, 3, 1000);
    p.h = 0.001;  /* not representable: accumulating t += h would drift */
    const double t0 = 0.1;
    sim S;
    sim_start(&S, &p, t0);
    check_context(T, "time: 10^6 steps of h = 0.001 from t0 = 0.1, one call per grid point");
    long long bad_t = 0, bad_n = 0;
    dfo_status st = DFO_OK;
    double accumulated = t0;
    for (long long n = 1; n <= 1000000 && st == DFO_OK; n++) {
        const double t = t0 + (double)n * p.h;
        accumulated += p.h;
        st = sim_to(&S, t);
        bad_t += (S.s.t != t);
        bad_n += (S.s.n != n);
    }
    CHECK_INT(DFO_OK, st);
    CHECK_INT(0, bad_t);
    CHECK_INT(0, bad_n);
    CHECK(state_finite(&S));
    printf("time: after 10^6 steps t - (t0 + n h) = %.3g; accumulating t += h instead would be off by %.3g\n",
           S.s.t - (t0 + 1e6 * p.h), accumulated - (t0 + 1e6 * p.h));
    sim S1;
    sim_start(&S1, &p, t0);
    check_context(T, "time: 10^6 steps of h = 0.001 from t0 = 0.1 in one call");
    CHECK_INT(DFO_OK, sim_to(&S1, t0 + 1e6 * p.h));
    CHECK_SAME(t0 + 1e6 * p.h, S1.s.t);
    CHECK_INT(1000000, S1.s.n);
    /* the same trajectory whether the grid points are requested one by one or not */
    CHECK_SAME(S.s.X, S1.s.X);
    CHECK_SAME(S.s.V, S1.s.V);
    T->context = NULL;
}

/* ---- 2. friction invariants ------------------------------------------------------------------ */

typedef struct {
    double t_last;
    long long count, bad;
} switch_log;

static void on_switch(void *ctx, double t, double x, int from, int to)
{
    switch_log *L = ctx;
    L->count++;
    if (!(t >= L->t_last) || from == to || from < -1 || from > 1 || to < -1 || to > 1 || !isfinite(x)) L->bad++;
    L->t_last = t;
}

/* worst[scheme]: max |F| / (max(mu_s, mu_k) N) while stuck; worst[0]: paper-scheme points
 * sliding with the static coefficient */
static void invariants_at(checks *T, const sim *S, double worst[4])
{
    const dfo_model *M = &S->M;
    const dfo_state *s = &S->s;
    const int scheme = M->p.scheme;
    const double N = M->p.N, muk_N = M->mu_k * N, Fb = fmax(M->p.mu_s, M->p.chi * M->p.mu_s) * N;
    CHECK(s->mode >= -1 && s->mode <= 1);
    CHECK(state_finite(S));
    if (s->mode == 0) {
        if (Fb > 0.0) worst[scheme] = fmax(worst[scheme], fabs(s->F) / Fb);
        /* regression (scheme 2, step_consistent, before d961b44): a sliding block stopping where
         * the static force S exceeds the limit but whose re-solved velocity has the wrong sign was
         * stuck "for this step" with F = -S, up to 15x the Coulomb limit */
        CHECK_RANGE(-Fb * (1.0 + 1e-12), Fb * (1.0 + 1e-12), s->F);
        CHECK_SAME(0.0, s->V);
        if (scheme != DFO_SCHEME_PAPER) CHECK_SAME(0.0, dfo_acceleration(M, &S->u, s));
    } else {
        CHECK(s->mode * s->V >= 0.0);
        /* compared by value: with mu_k N = 0 the force is +0 or -0 depending on the path */
        if (scheme != DFO_SCHEME_PAPER || M->mu_k == M->mu_b) {
            CHECK(s->F == -s->mode * muk_N);
        } else {
            /* the paper's scheme may end a step sliding with the static coefficient */
            CHECK(s->F == -s->mode * muk_N || s->F == -s->mode * M->mu_b * N);
            if (s->F != -s->mode * muk_N) worst[0] += 1.0;
        }
    }
}

static void test_invariants(checks *T)
{
    const double lambdas[] = {0.3, 0.5, 1.0, 2.0}, sigmas[] = {0.1, 0.4, 0.9};
    const double chis[] = {0.0, 0.05, 0.3, 0.7, 1.0, 1.5, 3.0}, zetas[] = {0.0, 0.05};
    double worst[4] = {0.0, 0.0, 0.0, 0.0};
    long long points = 0, stuck_points = 0, switches = 0;
    for (int scheme = 1; scheme <= 3; scheme++)
        for (int a = 0; a < 4; a++)
            for (int b = 0; b < 3; b++)
                for (int c = 0; c < 7; c++)
                    for (int d = 0; d < 2; d++) {
                        dfo_params p = nondim(lambdas[a], sigmas[b], chis[c], zetas[d], scheme, 200);
                        p.frictionUpdates = (c % 3);  /* 0, 1, 2 for the paper's scheme */
                        const double T_ = period_of(&p), dt = T_ / 97.0;
                        check_context(T, "invariants: scheme %d, lambda %g, mu_s sigma %g, chi %g, zeta %g, h = T/200, "
                                      "communication step T/97", scheme, lambdas[a], sigmas[b], chis[c], zetas[d]);
                        sim S;
                        sim_start(&S, &p, 0.0);
                        switch_log L = {0.0, 0, 0};
                        invariants_at(T, &S, worst);
                        for (int k = 1; k <= 10 * 97; k++) {
                            const double t = k * dt;
                            if (!CHECK_INT(DFO_OK, dfo_advance(&S.M, &S.u, &S.s, t, on_switch, &L))) break;
                            invariants_at(T, &S, worst);
                            points++;
                            stuck_points += (S.s.mode == 0);
                        }
                        CHECK_INT(0, L.bad);
                        CHECK(L.t_last <= S.s.t);
                        switches += L.count;
                    }
    T->context = NULL;
    printf("invariants: %lld communication points (%lld stuck), %lld switches; max |F|/(max(mu_s,mu_k) N) while "
           "stuck: scheme 1 %.17g, scheme 2 %.17g, scheme 3 %.17g; paper-scheme points sliding with mu_s: %.0f\n",
           points, stuck_points, switches, worst[1], worst[2], worst[3], worst[0]);
}

/* ---- 3. energy balance ----------------------------------------------------------------------- */

/* Work of the excitation = change of kinetic + potential energy + friction dissipation
 * (E_friction observable) + viscous dissipation, integrals by the trapezoid rule over every
 * internal grid point (communication points on the grid, so they do not alter the run). Returns
 * the residual relative to the work of the excitation. */
static double energy_residual(checks *T, int per_period, double chi, double *work_out)
{
    dfo_params p = nondim(0.5, 0.4, chi, 0.05, 3, per_period);
    const int steps = 10 * per_period;
    p.observe = 1;
    p.t_obs_start = 0.0;
    p.t_obs_stop = steps * p.h;
    sim S;
    sim_start(&S, &p, 0.0);
    double W = 0.0, Dc = 0.0;
    double P_prev = dfo_excitation(&S.M, 0.0), v_prev = S.s.V;
    const double E0 = 0.5 * p.m * S.s.V * S.s.V + 0.5 * p.k * S.s.X * S.s.X;
    for (int n = 1; n <= steps; n++) {
        const double t = n * p.h;
        if (!CHECK_INT(DFO_OK, sim_to(&S, t))) return INFINITY;
        const double P = dfo_excitation(&S.M, t), v = S.s.V;
        W += 0.5 * p.h * (P_prev * v_prev + P * v);
        Dc += 0.5 * p.h * p.c * (v_prev * v_prev + v * v);
        P_prev = P;
        v_prev = v;
    }
    const double E1 = 0.5 * p.m * S.s.V * S.s.V + 0.5 * p.k * S.s.X * S.s.X;
    const double R = W - (E1 - E0) - S.s.E_friction - Dc;
    CHECK(S.s.E_friction > 0.0 && S.s.transitions > 0);
    *work_out = W;
    return R / W;
}

static void test_energy(checks *T)
{
    const double chis[] = {0.3, 0.7, 2.0};
    for (int c = 0; c < 3; c++) {
        double r[4], W = 0.0;
        const int per[4] = {200, 400, 800, 1600};
        for (int i = 0; i < 4; i++) {
            check_context(T, "energy balance, scheme 3, lambda 0.5, mu_s sigma 0.4, chi %g, zeta 0.05, h = T/%d",
                          chis[c], per[i]);
            r[i] = energy_residual(T, per[i], chis[c], &W);
            /* measured |R|/W: 2.1e-4 .. 4.7e-4 at T/200, 3.4e-6 .. 5.9e-6 at T/1600 */
            CHECK_RANGE(0.0, 1e-3 * pow(200.0 / per[i], 2.0), fabs(r[i]));
        }
        printf("energy balance (chi %g, 10 periods, work %.4f): relative residual %.2e %.2e %.2e %.2e at "
               "h = T/200..T/1600, ratios %.2f %.2f %.2f\n",
               chis[c], W, r[0], r[1], r[2], r[3], r[0] / r[1], r[1] / r[2], r[2] / r[3]);
        /* O(h^2): the residual falls by 4 per halving once h is small (T/400 and finer) */
        for (int i = 1; i < 3; i++) {
            check_context(T, "energy balance order, chi %g, T/%d vs T/%d", chis[c], per[i], per[i + 1]);
            CHECK_RANGE(3.4, 4.6, r[i] / r[i + 1]);
        }
    }
    T->context = NULL;
}

/* ---- 4. fast paths --------------------------------------------------------------------------- */

static void compare_fast(checks *T, const dfo_params *p, const char *what, long long *points,
                         long long *zero_sign)
{
    dfo_params pf = *p, pg = *p, po = *p, pgo = *p;
    pf.fastPaths = 1;
    pg.fastPaths = 0;
    po.fastPaths = 1;  /* the observables' bookkeeping must not touch the trajectory either */
    po.observe = 1;
    pf.observe = pg.observe = 0;
    pgo.fastPaths = 0; /* and the observables are the general path's (stuck steps skipped or not) */
    pgo.observe = 1;
    po.t_obs_start = pgo.t_obs_start = 3.3 * period_of(p);
    po.t_obs_stop = pgo.t_obs_stop = 7.7 * period_of(p);
    sim F, G, O, GO;
    sim_start(&F, &pf, 0.0);
    sim_start(&G, &pg, 0.0);
    sim_start(&O, &po, 0.0);
    sim_start(&GO, &pgo, 0.0);
    const double dt = period_of(p) / 37.3;  /* off the grid: shortened steps on both paths */
    check_context(T, "fast paths (%s): scheme %d, chi %g, c %g, mu_s %g, N %g, alpha %g", what, p->scheme, p->chi,
                  p->c, p->mu_s, p->N, p->alpha);
    for (int k = 0; k <= 373; k++) {
        if (k > 0) {
            const dfo_status a = sim_to(&F, k * dt), b = sim_to(&G, k * dt), o = sim_to(&O, k * dt),
                             go = sim_to(&GO, k * dt);
            CHECK_INT(DFO_OK, a);
            if (!CHECK_INT(a, b) || !CHECK_INT(a, o) || !CHECK_INT(a, go)) break;
        }
        if (!(CHECK_SAME(G.s.t, F.s.t) & CHECK_INT(G.s.n, F.s.n) & CHECK_INT(G.s.steps, F.s.steps))) break;
        if (!(CHECK_SAME(GO.s.x_max, O.s.x_max) & CHECK_SAME(GO.s.x_min, O.s.x_min) &
              CHECK_SAME(GO.s.t_stuck, O.s.t_stuck) & CHECK_SAME(GO.s.stuck_from, O.s.stuck_from) &
              CHECK_SAME(GO.s.E_friction, O.s.E_friction) &
              CHECK_INT(GO.s.transitions, O.s.transitions) & CHECK_INT(GO.s.observed, O.s.observed)))
            break;
        CHECK(memcmp(&O.s.X, &F.s.X, sizeof F.s.X) == 0 && memcmp(&O.s.V, &F.s.V, sizeof F.s.V) == 0 &&
              memcmp(&O.s.F, &F.s.F, sizeof F.s.F) == 0 && O.s.mode == F.s.mode);
        /* F bit for bit, except the sign of a zero force: without friction the general path returns
         * -muN = -0 from the LCP where the fast path returns +0 (equal as numbers) */
        const int same_F = (G.s.F == 0.0 && F.s.F == 0.0) ? 1 : CHECK_SAME(G.s.F, F.s.F);
        if (G.s.F == 0.0 && F.s.F == 0.0 && memcmp(&G.s.F, &F.s.F, sizeof F.s.F) != 0) (*zero_sign)++;
        const int ok = CHECK_SAME(G.s.X, F.s.X) & CHECK_SAME(G.s.V, F.s.V) & same_F &
                       CHECK_INT(G.s.mode, F.s.mode) & CHECK_SAME(G.s.A, F.s.A) &
                       CHECK_SAME(dfo_acceleration(&G.M, &G.u, &G.s), dfo_acceleration(&F.M, &F.u, &F.s));
        (*points)++;
        if (!ok) break;  /* one report per case */
    }
}

static void test_fast_paths(checks *T)
{
    long long points = 0, zero_sign = 0;
    const double alphas[] = {-0.1, 0.0, -1.0 / 3.0};
    for (int scheme = 1; scheme <= 3; scheme++)
        for (int a = 0; a < 3; a++) {
            dfo_params p = nondim(0.5, 0.4, 0.7, 0.05, scheme, 300);
            p.alpha = alphas[a];
            p.x0 = 0.3;
            p.v0 = -0.2;
            dfo_params q = p;
            q.mu_s = 0.0;
            compare_fast(T, &q, "mu_s = 0: no LCP", &points, &zero_sign);
            q = p;
            q.N = 0.0;
            compare_fast(T, &q, "N = 0: no LCP", &points, &zero_sign);
            q = p;
            q.mu_s = 0.0;
            q.c = 0.0;
            compare_fast(T, &q, "mu_s = 0 and c = 0", &points, &zero_sign);
            q = p;
            q.chi = 1.0;
            compare_fast(T, &q, "chi = 1: no coefficient update", &points, &zero_sign);
            q = p;
            q.chi = 1.0;
            q.v0 = 0.0;
            q.x0 = 0.0;
            q.N = 1.6;  /* mu_s sigma = 0.8: long stick phases */
            compare_fast(T, &q, "chi = 1 from rest", &points, &zero_sign);
            q = p;
            q.c = 0.0;
            compare_fast(T, &q, "c = 0: no damping term", &points, &zero_sign);
            q = p;
            q.c = 0.0;
            q.chi = 1.0;
            compare_fast(T, &q, "c = 0 and chi = 1", &points, &zero_sign);
            q = p;
            q.chi = 2.0;
            compare_fast(T, &q, "general (chi = 2, c > 0)", &points, &zero_sign);
            compare_fast(T, &p, "general (chi = 0.7, c > 0)", &points, &zero_sign);
        }
    T->context = NULL;
    printf("fast paths: %lld communication points compared bit for bit (x, v, F, mode, A, acceleration; "
           "also observe = 1 vs 0); F = +0 (fast) vs -0 (general) at %lld of them\n", points, zero_sign);
}

/* A block stuck for the whole run (static force |cos| <= 1 against a limit of 2): its observables
 * are known exactly. The stuck time is the window's length w1 - w0 bit for bit (the stuck stretch
 * counted in one piece, in one call or 373), the stick fraction 1; X sampled and frozen, no work,
 * no switch; the fast path (stuck steps skipped inside the window too) gives the general path's. */
static void test_stuck_observables(checks *T)
{
    for (int scheme = 2; scheme <= 3; scheme++)
        for (int calls = 1; calls <= 373; calls += 372)
            for (int fast = 0; fast <= 1; fast++) {
                dfo_params p = nondim(0.5, 2.0, 0.7, 0.05, scheme, 300);
                p.x0 = 0.25;
                p.observe = 1;
                p.fastPaths = fast;
                const double Tp = period_of(&p);
                p.t_obs_start = 3.3 * Tp;
                p.t_obs_stop = 7.7 * Tp;
                check_context(T, "stuck observables: scheme %d, %d calls, fastPaths %d", scheme, calls, fast);
                sim S;
                sim_start(&S, &p, 0.0);
                for (int k = 1; k <= calls; k++) CHECK_INT(DFO_OK, sim_to(&S, 10.0 * Tp * k / calls));
                const double span = p.t_obs_stop - p.t_obs_start;
                /* one stretch, however the run is split into calls: the window's length */
                CHECK_SAME(span, dfo_stuck_time(&S.M, &S.s));
                CHECK_SAME(1.0, dfo_stick_fraction(&S.M, &S.s));
                CHECK_INT(1, S.s.observed);
                CHECK_SAME(0.25, S.s.x_max);
                CHECK_SAME(0.25, S.s.x_min);
                CHECK_SAME(0.0, S.s.E_friction);
                CHECK_INT(0, (int)S.s.transitions);
                CHECK_INT(0, S.s.mode);
                CHECK_SAME(0.25, S.s.X);
            }
    T->context = NULL;
}

/* ---- 5. order of the located scheme ---------------------------------------------------------- */

/* Errors at h, h/2, h/4 against h/64 over 10 periods, max over the communication points.
 * offgrid = 0: communication points on the coarse grid (a grid point of every run, no shortened
 * step); offgrid = 1: every T/37.3, off every grid, so each communication point shortens a step
 * and the Bossak acceleration is re-based (method.md section 8). */
static void order_case(checks *T, double chi, double alpha, int offgrid)
{
    const int base = 800;  /* h = T/800, T/1600, T/3200 against T/51200 */
    const int refine[4] = {1, 2, 4, 64};
    sim S[4];
    for (int i = 0; i < 4; i++) {
        dfo_params p = nondim(0.5, 0.4, chi, 0.0, 3, base * refine[i]);
        p.alpha = alpha;
        sim_start(&S[i], &p, 0.0);
    }
    const double h = S[0].M.p.h, Tp = period_of(&S[0].M.p);
    const int points = offgrid ? 373 : 10 * base;
    double ex[3] = {0, 0, 0}, ev[3] = {0, 0, 0};
    check_context(T, "order: scheme 3, lambda 0.5, mu_s sigma 0.4, chi %g, zeta 0, alpha %g, h = T/%d, "
                  "communication points %s", chi, alpha, base, offgrid ? "every T/37.3" : "on the grid");
    int ok = 1;
    for (int n = 1; n <= points && ok; n++) {
        const double t = offgrid ? n * (Tp / 37.3) : n * h;
        for (int i = 0; i < 4; i++) ok &= CHECK_INT(DFO_OK, sim_to(&S[i], t));
        for (int i = 0; i < 3; i++) {
            ex[i] = fmax(ex[i], fabs(S[i].s.X - S[3].s.X));
            ev[i] = fmax(ev[i], fabs(S[i].s.V - S[3].s.V));
        }
    }
    printf("order (chi %g, alpha %g, %s): max |x - x_ref| %.3e %.3e %.3e, ratios %.3f %.3f; "
           "max |v - v_ref| ratios %.3f %.3f\n", chi, alpha, offgrid ? "off-grid" : "on-grid",
           ex[0], ex[1], ex[2], ex[0] / ex[1], ex[1] / ex[2], ev[0] / ev[1], ev[1] / ev[2]);
    CHECK_RANGE(3.4, 4.6, ex[0] / ex[1]);
    CHECK_RANGE(3.4, 4.6, ex[1] / ex[2]);
    CHECK(S[3].s.lcp_solves > 0);
}

static void test_order(checks *T)
{
    const double chis[] = {0.05, 0.3, 0.7, 0.9, 2.0};
    for (int c = 0; c < 5; c++) order_case(T, chis[c], -0.1, 0);
    for (int c = 0; c < 5; c++) order_case(T, chis[c], -0.1, 1);
    order_case(T, 0.7, -0.3, 1);
    order_case(T, 0.7, 0.0, 1);
    T->context = NULL;
}

/* ---- 6. hard inputs -------------------------------------------------------------------------- */

static void hard_case(checks *T, const dfo_params *p, const char *what, double t_end, int calls)
{
    for (int fast = 0; fast <= 1; fast++) {
        dfo_params q = *p;
        q.fastPaths = fast;
        check_context(T, "hard input (%s): scheme %d, fastPaths %d", what, q.scheme, fast);
        sim S;
        sim_start(&S, &q, 0.0);
        CHECK(state_finite(&S));
        for (int k = 1; k <= calls; k++) {
            const double t = t_end * k / calls;
            const dfo_status st = sim_to(&S, t);
            if (!CHECK_INT(DFO_OK, st)) {
                fprintf(stderr, "    advancing to t = %.17g: %s (state X = %.3g, V = %.3g)\n", t, dfo_status_text(st),
                        S.s.X, S.s.V);
                break;
            }
            if (!CHECK(state_finite(&S) && isfinite(dfo_acceleration(&S.M, &S.u, &S.s)))) break;
            if (!CHECK(S.s.mode >= -1 && S.s.mode <= 1)) break;
            check_time_reached(T, &S, t);
        }
    }
}

static void test_hard_inputs(checks *T)
{
    for (int scheme = 1; scheme <= 3; scheme++) {
        const dfo_params base = nondim(0.5, 0.4, 0.7, 0.02, scheme, 200);
        const double Tp = period_of(&base), t_end = 10 * Tp;
        dfo_params p;
        p = base; p.chi = 0.0; hard_case(T, &p, "chi = 0", t_end, 333);
        p = base; p.chi = 0.0; p.x0 = 0.5; hard_case(T, &p, "chi = 0, x0 = 0.5", t_end, 333);
        p = base; p.N = 0.0; hard_case(T, &p, "N = 0", t_end, 333);
        p = base; p.mu_s = 0.0; p.v0 = 1.0; hard_case(T, &p, "mu_s = 0, v0 = 1", t_end, 333);
        p = base; p.k = 0.0; hard_case(T, &p, "k = 0", t_end, 333);
        p = base; p.k = 0.0; p.N = 0.1; hard_case(T, &p, "k = 0, weak friction (drifts)", t_end, 333);
        p = base; p.omega = 0.0; hard_case(T, &p, "omega = 0 (constant force inside the limit)", t_end, 333);
        p = base; p.omega = 0.0; p.N = 0.5; hard_case(T, &p, "omega = 0 (constant force beyond the limit)", t_end, 333);
        p = base; p.omega = 0.0; p.k = 0.0; p.N = 0.5; hard_case(T, &p, "omega = 0, k = 0 (uniform acceleration)", t_end, 333);
        p = base; p.P0 = 0.0; hard_case(T, &p, "P0 = 0", t_end, 333);
        p = base; p.P0 = 0.0; p.x0 = 2.0; hard_case(T, &p, "P0 = 0, x0 = 2 (free decay to stick)", t_end, 333);
        p = base; p.P0 = -1.0; hard_case(T, &p, "P0 < 0", t_end, 333);
        p = base; p.P0 = -1.0; p.phi = 1.0; p.chi = 2.0; hard_case(T, &p, "P0 < 0, phi = 1, chi = 2", t_end, 333);
        p = base; p.h = Tp / 1e6; hard_case(T, &p, "h = T/1e6, 100 steps", 100 * p.h, 100);
        p = base; p.h = Tp / 1e6; p.x0 = 1.0; hard_case(T, &p, "h = T/1e6 sliding, 100 steps", 100 * p.h, 7);
        p = base; p.h = Tp / 1e6; p.chi = 2.0; p.phi = 1.0; hard_case(T, &p, "h = T/1e6, chi = 2, 100 steps", 100 * p.h, 100);
        p = base; p.h = 1.7 * Tp; hard_case(T, &p, "h = 1.7 T", t_end, 10);
        p = base; p.h = 3.0 * Tp; p.chi = 2.0; hard_case(T, &p, "h = 3 T, chi = 2", 30 * Tp, 7);
        p = base; p.h = 10.0 * Tp; p.x0 = 3.0; hard_case(T, &p, "h = 10 T, x0 = 3", 100 * Tp, 10);
        p = base; p.alpha = -1.0 / 3.0; p.h = 2.0 * Tp; hard_case(T, &p, "alpha = -1/3, h = 2 T", 40 * Tp, 9);
        p = base; p.mu_s = 100.0; hard_case(T, &p, "mu_s = 100: always stuck", t_end, 333);
        /* regression (before d961b44): the re-basing of Bossak's A for a changed step length
         * (predict(), A0 += alpha (h - hA) x''') is a Taylor step that amplified when w0 h or
         * (c/m) h is large: these overflowed (DFO_ERR_NONFINITE, or DFO_ERR_LCP once p_hat was
         * infinite) for every scheme with alpha != 0 */
        p = base; p.c = 1e6; p.x0 = 1.0; p.N = 0.01; hard_case(T, &p, "c = 1e6 (overdamped)", t_end, 333);
        p = base; p.c = 1e6; p.x0 = 1.0; p.N = 0.0; hard_case(T, &p, "c = 1e6, no friction", t_end, 333);
        p = base; p.m = 1e-6; hard_case(T, &p, "m = 1e-6 (w0 h = 63)", t_end, 333);
        p = base; p.m = 1e-6; p.N = 0.0; p.x0 = 1.0; hard_case(T, &p, "m = 1e-6, no friction", t_end, 1333);
        p = base; p.m = 1e6; hard_case(T, &p, "m = 1e6", t_end, 333);
        p = base; p.omega = 1.0; p.c = 0.0; p.N = 0.1; p.h = Tp / 50; hard_case(T, &p, "resonance, 100 periods", 100 * Tp, 100);
        p = base; p.chi = 1.0; p.N = 0.8; hard_case(T, &p, "force touches the limit (P0 = mu_s N)", t_end, 333);
    }
    T->context = NULL;
}

/* ---- 7. caches ------------------------------------------------------------------------------- */

static int same_state(const dfo_state *a, const dfo_state *b)
{
    return a->t == b->t && a->X == b->X && a->V == b->V && a->A == b->A && a->F == b->F && a->mode == b->mode &&
           a->n == b->n && a->transitions == b->transitions;
}

static void test_caches(checks *T)
{
    const int schemes[] = {1, 2, 3};
    const double dts[] = {1.0, 0.37, 2.5}; /* communication step / h */
    for (int si = 0; si < 3; si++)
        for (int di = 0; di < 3; di++) {
            dfo_params p = nondim(0.5, 0.6, 0.3, 0.0, schemes[si], 1000);
            p.x0 = 1.3;
            p.observe = 1;
            check_context(T, "caches: scheme %d, dt = %g h", schemes[si], dts[di]);
            sim A, B, F;
            sim_start(&A, &p, 0.25);
            const double dt = dts[di] * p.h;
            long long mismatches = 0, forged_kept = 0;
            for (int k = 1; k <= 6000; k++) {
                const double t = 0.25 + k * dt;
                if (!CHECK_INT(DFO_OK, sim_to(&A, t))) break;
                if (k % 97 == 0) {
                    /* B: a copy with its caches emptied; F: with them forged, then checked */
                    B = A;
                    dfo_forget_caches(&B.s);
                    F = A;
                    F.s.exc_c += 1e-3;
                    dfo_check_caches(&F.M, &F.s);
                    forged_kept += (F.s.exc_n != -1);
                    for (int j = 1; j <= 50; j++) {
                        const double tj = t + j * dt;
                        sim_to(&A, tj);
                        sim_to(&B, tj);
                        sim_to(&F, tj);
                        mismatches += !same_state(&A.s, &B.s) || !same_state(&A.s, &F.s);
                    }
                    k += 50;
                }
                /* the cache's cosine against the library's, at the grid point it holds */
                if (A.s.exc_n > 0) {
                    const double th = p.omega * (A.s.t0 + (double)A.s.exc_n * p.h) + p.phi;
                    CHECK_RANGE(0.0, 5e-14, fabs(A.s.exc_c - cos(th)));
                }
            }
            CHECK_INT(0, mismatches);
            CHECK_INT(0, forged_kept);
        }
    /* a state whose caches are consistent keeps them */
    dfo_params p = nondim(0.5, 0.6, 0.3, 0.0, 3, 1000);
    sim S;
    sim_start(&S, &p, 0.0);
    CHECK_INT(DFO_OK, sim_to(&S, 123.4 * p.h));
    const dfo_state before = S.s;
    dfo_check_caches(&S.M, &S.s);
    CHECK(memcmp(&before, &S.s, sizeof before) == 0);
    /* a breakaway side that cannot be is reset, and the run goes on within the invariants */
    S.s.stick_dir = 7;
    dfo_check_caches(&S.M, &S.s);
    CHECK_INT(0, S.s.stick_dir);
    CHECK_INT(DFO_OK, sim_to(&S, 2000.0 * p.h));
    CHECK(state_finite(&S) && S.s.mode >= -1 && S.s.mode <= 1);
    T->context = NULL;
}

int main(void)
{
    checks C = {0, 0, NULL, {0}}, *T = &C;
    test_time(T);
    test_invariants(T);
    test_energy(T);
    test_fast_paths(T);
    test_stuck_observables(T);
    test_order(T);
    test_hard_inputs(T);
    test_caches(T);
    return checks_done(T, "test_stepper");
}
