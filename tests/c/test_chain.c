/* Unit tests of the chain of n blocks (fmu_src/models/chain/chain.h), driven directly (no FMI).
 *
 * 1. n = 1 against the oscillator (scheme.h): same parameters, same communication points (every
 *    T/100, and at random), three schemes, seven cases: the same t and mode at every point, x and v
 *    to N1_TOL (the oscillator steps through the friction engine, whose arithmetic is ordered
 *    otherwise than the chain's own stepper: the two agree to rounding, not bit for bit);
 * 2. the 2n LCP: the chain's box solver (principal pivoting on the tridiagonal M_hat) and Lemke on
 *    the dense 2n x 2n problem against brute-force enumeration of all complementary bases, n <= 6,
 *    on random and degenerate problems (ties |p| = l, l = 0 on some blocks, one block stuck
 *    between sliding neighbours); complementarity residuals;
 * 3. invariants per block at every communication point of stick-slip chains (stuck: v == 0 and
 *    |F| <= limit; sliding: F = -/+ mu_k N), and the complementarity residual of the step's LCP;
 * 4. energy balance of the located scheme: residual O(h^2);
 * 5. stop_at_switch: stopping at every switch and going on gives the switches of the plain run,
 *    and a copied state continues bit for bit; the fused step (no switch) gives the general path's
 *    bits; hard inputs (stiff steps on long chains, stiff and light blocks, chi = 0, tiny h,
 *    no friction, inputs) run and stay bounded;
 * 6. invalid parameters are named with their element. */
#include "chain.h"
#include "check.h"
#include "lcp.h"
#include "scheme.h"
#include "oscillator.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *std_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void std_free(void *env, void *obj) { (void)env; free(obj); }
static const chain_alloc AL = {std_alloc, std_free, NULL};

#define NMAX 64
#define N1_TOL 1e-10 /* n = 1 against the oscillator: x and v relative to max(|value|, 1) (measured: 5.4e-12) */

typedef struct {
    size_t n;
    double m[NMAX], k[NMAX], c[NMAX], P0[NMAX], phi[NMAX], N[NMAX], mu_s[NMAX], chi[NMAX], x0[NMAX], v0[NMAX];
    chain_params p;
} chain_setup;

static void setup_fill(chain_setup *c, size_t n, double omega, double h, int scheme)
{
    memset(c, 0, sizeof *c);
    c->n = n;
    for (size_t i = 0; i < n; i++) {
        c->m[i] = 1.0; c->k[i] = 1.0; c->c[i] = 0.0; c->P0[i] = 0.0; c->phi[i] = 0.0;
        c->N[i] = 0.8; c->mu_s[i] = 0.5; c->chi[i] = 0.7; c->x0[i] = 0.0; c->v0[i] = 0.0;
    }
    c->P0[0] = 1.0;
    chain_params p = {n, c->m, c->k, c->c, c->P0, c->phi, c->N, c->mu_s, c->chi, c->x0, c->v0,
                      0.0, 0.0, omega, h, -0.1, scheme, 1, NULL, NULL, 0, NULL, NULL};
    c->p = p;
}

/* ---- 1. n = 1 against the oscillator -------------------------------------------------------- */

static void test_single(checks *T)
{
    const double cases[][5] = {/* lambda, mu_s sigma, chi, zeta, x0 */
                               {0.5, 0.4, 0.7, 0.0, 0.0}, {0.8, 0.1, 0.7, 0.0, 0.0}, {0.5, 0.8, 0.6, 0.1, 0.0},
                               {0.5, 0.4, 0.05, 0.0, 0.0}, {0.5, 0.4, 0.0, 0.0, 0.0}, {0.5, 0.2, 2.0, 0.0, 0.0},
                               {1.3, 0.3, 0.9, 0.05, 0.7}};
    long long points = 0, differing = 0;
    double worst = 0.0; /* the largest difference of x or v, relative to max(|value|, 1) */
    for (size_t ci = 0; ci < sizeof cases / sizeof cases[0]; ci++) {
        for (int scheme = 1; scheme <= 3; scheme++) {
            for (int random_steps = 0; random_steps <= 1; random_steps++) {
                const double lam = cases[ci][0], T_per = 2.0 * DFO_PI / lam;
                dfo_params p;
                memset(&p, 0, sizeof p);
                p.m = 1.0; p.k = 1.0; p.c = 2.0 * cases[ci][3]; p.P0 = 1.0; p.omega = lam; p.mu_s = 0.5;
                p.N = cases[ci][1] / 0.5; p.chi = cases[ci][2]; p.x0 = cases[ci][4]; p.h = T_per / 400;
                p.alpha = -0.1; p.t_obs_stop = 1e300; p.scheme = scheme; p.frictionUpdates = 1; p.fastPaths = 1;
                dfo_model M;
                dfo_model_init(&M, &p);
                dfo_inputs u;
                memset(&u, 0, sizeof u);
                dfo_state s;
                dfo_start(&M, &u, 0.0, &s);
                chain_setup cs;
                setup_fill(&cs, 1, lam, p.h, scheme);
                cs.c[0] = p.c; cs.N[0] = p.N; cs.chi[0] = p.chi; cs.x0[0] = p.x0;
                chain_model *C = chain_create(&cs.p, &AL, NULL);
                chain_state q;
                CHECK(C != NULL && chain_state_init(C, &q));
                const chain_inputs in = {NULL, NULL};
                chain_start(C, &in, 0.0, &q);
                rng r = {0x9E3779B97F4A7C15ull + ci};
                double t = 0.0;
                check_context(T, "n = 1, case %zu, scheme %d, random steps %d", ci, scheme, random_steps);
                while (t < 10.0 * T_per) {
                    t += random_steps ? p.h * rng_range(&r, 0.1, 3.0) : 10.0 * T_per / 1000.0;
                    CHECK_INT(DFO_OK, dfo_advance(&M, &u, &s, t, NULL, NULL));
                    CHECK_INT(CHAIN_OK, chain_advance(C, &in, &q, t, 0, NULL, NULL));
                    const double dx = fabs(s.X - q.X[0]) / fmax(fabs(q.X[0]), 1.0);
                    const double dv = fabs(s.V - q.V[0]) / fmax(fabs(q.V[0]), 1.0);
                    worst = fmax(worst, fmax(dx, dv));
                    differing += !(s.t == q.t && s.mode == q.mode[0]);
                    points++;
                }
                chain_state_free(C, &q);
                chain_destroy(C);
            }
        }
    }
    check_context(T, "%s", "");
    CHECK_INT(0, differing);
    CHECK(worst <= N1_TOL);
    printf("n = 1 against the oscillator: 7 cases x 3 schemes, communication every T/100 and at random "
           "(0.1 h ... 3 h): %lld points, %lld with a differing t or mode, x and v within %.3g relative\n", points,
           differing, worst);
}

/* ---- 2. the 2n LCP against enumeration ------------------------------------------------------ */

/* Solve a dense k x k system (k <= 12) by Gaussian elimination with partial pivoting; 0 if singular. */
static int dense_solve(int k, double *A, double *b)
{
    for (int c = 0; c < k; c++) {
        int piv = c;
        for (int r = c + 1; r < k; r++) if (fabs(A[r * k + c]) > fabs(A[piv * k + c])) piv = r;
        if (fabs(A[piv * k + c]) < 1e-12) return 0;
        if (piv != c) {
            for (int j = 0; j < k; j++) {
                const double t = A[c * k + j];
                A[c * k + j] = A[piv * k + j];
                A[piv * k + j] = t;
            }
            const double t = b[c]; b[c] = b[piv]; b[piv] = t;
        }
        for (int r = c + 1; r < k; r++) {
            const double f = A[r * k + c] / A[c * k + c];
            for (int j = c; j < k; j++) A[r * k + j] -= f * A[c * k + j];
            b[r] -= f * b[c];
        }
    }
    for (int r = k - 1; r >= 0; r--) {
        double v = b[r];
        for (int j = r + 1; j < k; j++) v -= A[r * k + j] * b[j];
        b[r] = v / A[r * k + r];
    }
    return 1;
}

/* All complementary bases of the 2n LCP w = Mz + q: the velocities V = u+ - u- of every feasible one
 * must agree (V is unique: M_hat is positive definite). Returns the number of feasible bases and
 * the largest spread of V among them; V_ref gets the first. */
static int enumerate(int n, const double *Mq, const double *q, double *V_ref, double *spread)
{
    const int N2 = 2 * n;
    int found = 0;
    *spread = 0.0;
    for (int mask = 0; mask < (1 << N2); mask++) {
        int J[12], k = 0;
        for (int i = 0; i < N2; i++) if (mask & (1 << i)) J[k++] = i;
        double A[144], b[12], z[12] = {0};
        for (int a = 0; a < k; a++) {
            for (int c = 0; c < k; c++) A[a * k + c] = Mq[J[a] * N2 + J[c]];
            b[a] = -q[J[a]];
        }
        if (k > 0 && !dense_solve(k, A, b)) continue;
        int ok = 1;
        for (int a = 0; a < k; a++) { z[J[a]] = b[a]; if (b[a] < -1e-9) ok = 0; }
        if (!ok) continue;
        for (int i = 0; i < N2 && ok; i++) {
            double w = q[i];
            for (int j = 0; j < N2; j++) w += Mq[i * N2 + j] * z[j];
            if (!(mask & (1 << i)) && w < -1e-9) ok = 0;
        }
        if (!ok) continue;
        for (int i = 0; i < n; i++) {
            const double V = z[i] - z[n + i];
            if (found == 0) V_ref[i] = V;
            else *spread = fmax(*spread, fabs(V - V_ref[i]));
        }
        found++;
    }
    return found;
}

static void test_lcp_enumeration(checks *T)
{
    rng r = {0x2545F4914F6CDD1Dull};
    long problems = 0, worst_piv = 0, lemke_fail = 0;
    double worst_V = 0.0, worst_res = 0.0;
    for (int trial = 0; trial < 3000; trial++) {
        const int n = 1 + trial % 6;
        double d[6], e[6], p[6], l[6], V[6], F[6], work[18];
        int mode[6];
        const int kind = trial % 5; /* 0 random, 1 ties, 2 l = 0 on some, 3 stuck between sliding, 4 small h */
        for (int i = 0; i < n; i++) {
            const double m = rng_decades(&r, -1, 1), k = rng_decades(&r, -1, 2);
            const double h = (kind == 4) ? 1e-6 : rng_decades(&r, -3, -1);
            d[i] = 1.1 * m / (0.6 * h) + k * 0.3 * h;
            e[i] = (i + 1 < n) ? -rng_range(&r, 0.0, 0.45) * d[i] : 0.0;
            l[i] = rng_range(&r, 0.0, 2.0);
            p[i] = rng_range(&r, -3.0, 3.0);
            mode[i] = rng_int(&r, 3) - 1;
        }
        for (int i = 0; i + 1 < n; i++) e[i] = -fmin(fabs(e[i]), 0.45 * fmin(d[i], d[i + 1]));
        if (kind == 1) for (int i = 0; i < n; i += 2) p[i] = (i % 4 ? -1 : 1) * l[i];
        if (kind == 2) for (int i = 0; i < n; i += 2) l[i] = 0.0;
        if (kind == 3 && n >= 3) { p[0] = 5.0 + l[0]; p[2] = -5.0 - l[2]; p[1] = 0.0; l[1] = 1.5; }
        /* the dense 2n problem: M = [[Mh, -Mh], [-Mh, Mh]], q = (l - p, l + p) */
        double Mh[36] = {0}, Mq[144], q[12];
        for (int i = 0; i < n; i++) {
            Mh[i * n + i] = d[i];
            if (i + 1 < n) { Mh[i * n + i + 1] = e[i]; Mh[(i + 1) * n + i] = e[i]; }
        }
        for (int i = 0; i < n; i++) {
            for (int j = 0; j < n; j++) {
                const double v = Mh[i * n + j];
                Mq[i * 2 * n + j] = v; Mq[i * 2 * n + n + j] = -v;
                Mq[(n + i) * 2 * n + j] = -v; Mq[(n + i) * 2 * n + n + j] = v;
            }
            q[i] = l[i] - p[i];
            q[n + i] = l[i] + p[i];
        }
        double V_enum[6], spread;
        const int found = enumerate(n, Mq, q, V_enum, &spread);
        check_context(T, "LCP trial %d, n = %d, kind %d", trial, n, kind);
        CHECK(found >= 1);
        CHECK_RANGE(0.0, 1e-9, spread);
        double qb[6]; /* the box LCP's q = -p (lcp.h: w = M_hat V + q = F) */
        for (int i = 0; i < n; i++) qb[i] = -p[i];
        int piv = -1;
        CHECK_INT(LCP_OK, lcp_box((size_t)n, d, e, qb, l, mode, V, F, work, &piv));
        if (piv > worst_piv) worst_piv = piv;
        double z[12], w[12];
        int zb[12], lp = 0;
        const lcp_status st = lcp_lemke(2 * n, Mq, q, 64, z, w, zb, &lp);
        if (st != LCP_OK) lemke_fail++;
        CHECK_INT(LCP_OK, st);
        double sc = 1e-300;
        for (int i = 0; i < n; i++) sc = fmax(sc, fabs(V_enum[i]) + fabs(p[i]) / d[i]);
        for (int i = 0; i < n; i++) {
            worst_V = fmax(worst_V, fabs(V[i] - V_enum[i]) / sc);
            worst_V = fmax(worst_V, fabs((z[i] - z[n + i]) - V_enum[i]) / sc);
            CHECK_NEAR(V_enum[i], V[i], 1e-9 * sc);
            CHECK_NEAR(V_enum[i], z[i] - z[n + i], 1e-9 * sc);
            /* the box solution is complementary: the mode says which side, F within its limit */
            const double lim = l[i] * (1.0 + 1e-12) + 1e-12 * fabs(p[i]);
            CHECK(fabs(F[i]) <= lim);
            if (l[i] > 0.0 && V[i] > 0.0) CHECK_SAME(-l[i], F[i]);
            if (l[i] > 0.0 && V[i] < 0.0) CHECK_SAME(l[i], F[i]);
            /* residual of M_hat V - p - F */
            double res = d[i] * V[i] - p[i] - F[i];
            if (i > 0) res += e[i - 1] * V[i - 1];
            if (i + 1 < n) res += e[i] * V[i + 1];
            worst_res = fmax(worst_res, fabs(res) / (fabs(p[i]) + l[i] + 1e-300));
        }
        for (int i = 0; i < 2 * n; i++)
            worst_res = fmax(worst_res, fabs(z[i] * w[i]) / (1.0 + fabs(q[i]) * fabs(q[i])));
        problems++;
    }
    check_context(T, "%s", "");
    CHECK_RANGE(0.0, 1e-10, worst_res);
    printf("2n LCP: %ld problems n = 1..6 (random, ties, l = 0, stuck between sliding, tiny h): largest |V - V_enum| "
           "%.2e (relative), residual %.2e, box pivots <= %ld, Lemke failures %ld\n",
           problems, worst_V, worst_res, worst_piv, lemke_fail);
}

/* ---- 3. invariants and the step's LCP along stick-slip chains ------------------------------- */

static void test_invariants(checks *T)
{
    long points = 0, stuck_pts = 0, slide_pts = 0;
    double worst_lcp = 0.0;
    for (int scheme = 1; scheme <= 3; scheme++) {
        for (int variant = 0; variant < 3; variant++) {
            chain_setup cs;
            const size_t n = 5;
            setup_fill(&cs, n, 0.7, 2.0 * DFO_PI / 0.7 / 300, scheme);
            for (size_t i = 0; i < n; i++) {
                cs.N[i] = 0.2 + 0.3 * (double)i;
                cs.chi[i] = (variant == 1) ? 1.5 : 0.6;
                cs.c[i] = (variant == 2) ? 0.05 : 0.0;
                cs.P0[i] = (i == 0 || variant == 2) ? 1.0 : 0.0;
                cs.phi[i] = 0.3 * (double)i;
            }
            cs.p.k_end = (variant == 2) ? 1.0 : 0.0;
            chain_model *C = chain_create(&cs.p, &AL, NULL);
            chain_state s;
            CHECK(C != NULL && chain_state_init(C, &s));
            const chain_inputs in = {NULL, NULL};
            chain_start(C, &in, 0.0, &s);
            double d[NMAX], e[NMAX], p[NMAX], l[NMAX], V[NMAX], F[NMAX], work[3 * NMAX];
            int mode[NMAX];
            for (int j = 1; j <= 2000; j++) {
                const double t = j * cs.p.h * 0.73;
                check_context(T, "invariants scheme %d variant %d t = %g", scheme, variant, t);
                CHECK_INT(CHAIN_OK, chain_advance(C, &in, &s, t, 0, NULL, NULL));
                for (size_t i = 0; i < n; i++) {
                    const double mukN = cs.mu_s[i] * cs.chi[i] * cs.N[i];
                    const double Fb = fmax(cs.mu_s[i], cs.mu_s[i] * cs.chi[i]) * cs.N[i];
                    if (s.mode[i] == 0) {
                        if (scheme != 1) CHECK_SAME(0.0, s.V[i]);
                        CHECK(fabs(s.F[i]) <= Fb * (1.0 + 1e-12));
                        stuck_pts++;
                    } else {
                        CHECK_SAME(-s.mode[i] * mukN, s.F[i]);
                        CHECK(s.mode[i] * s.V[i] >= 0.0);
                        slide_pts++;
                    }
                }
                /* the LCP of the next step: the box solver's answer is complementary and agrees with
                 * dense Lemke on the 2n problem */
                e[n - 1] = NAN; /* not part of the problem: must not be read */
                double qb[NMAX];
                chain_step_problem(C, &in, &s, cs.p.h, d, e, qb, l);
                for (size_t i = 0; i < n; i++) { mode[i] = s.mode[i]; p[i] = -qb[i]; }
                CHECK_INT(LCP_OK, lcp_box(n, d, e, qb, l, mode, V, F, work, NULL));
                double Mq[100], q[10], z[10], w[10];
                int zb[10];
                memset(Mq, 0, sizeof Mq);
                for (size_t i = 0; i < n; i++) {
                    for (size_t jj = 0; jj < n; jj++) {
                        const double v = (i == jj) ? d[i] : (jj == i + 1) ? e[i] : (i == jj + 1) ? e[jj] : 0.0;
                        Mq[i * 10 + jj] = v;
                        Mq[i * 10 + n + jj] = -v;
                        Mq[(n + i) * 10 + jj] = -v;
                        Mq[(n + i) * 10 + n + jj] = v;
                    }
                    q[i] = l[i] - p[i];
                    q[n + i] = l[i] + p[i];
                }
                CHECK_INT(LCP_OK, lcp_lemke((int)(2 * n), Mq, q, 64, z, w, zb, NULL));
                for (size_t i = 0; i < n; i++) {
                    const double sc = fabs(p[i]) / d[i] + 1e-300;
                    worst_lcp = fmax(worst_lcp, fabs((z[i] - z[n + i]) - V[i]) / sc);
                    worst_lcp = fmax(worst_lcp, fabs(z[i] * w[i]) / (fabs(q[i]) * fabs(q[i]) / d[i] + 1e-300));
                    worst_lcp = fmax(worst_lcp, fabs(z[n + i] * w[n + i]) / (fabs(q[i]) * fabs(q[i]) / d[i] + 1e-300));
                    /* complementarity of the box solution */
                    const double rp = l[i] + F[i], rm = l[i] - F[i];
                    CHECK(rp >= -1e-12 * l[i] && rm >= -1e-12 * l[i]);
                    worst_lcp = fmax(worst_lcp, fabs(fmax(V[i], 0.0) * rp) / (sc * (l[i] + fabs(p[i]))));
                    worst_lcp = fmax(worst_lcp, fabs(fmax(-V[i], 0.0) * rm) / (sc * (l[i] + fabs(p[i]))));
                }
                points++;
            }
            chain_state_free(C, &s);
            chain_destroy(C);
        }
    }
    check_context(T, "%s", "");
    CHECK_RANGE(0.0, 1e-9, worst_lcp);
    CHECK(stuck_pts > 1000 && slide_pts > 1000);
    printf("invariants: %ld points (%ld stuck, %ld sliding block samples), step LCP: box vs Lemke and complementarity "
           "residual %.2e\n", points, stuck_pts, slide_pts, worst_lcp);
}

/* ---- 4. energy balance ---------------------------------------------------------------------- */

static double energy_residual(int per_period)
{
    chain_setup cs;
    const double lam = 0.8, Tp = 2.0 * DFO_PI / lam;
    setup_fill(&cs, 4, lam, Tp / per_period, 3);
    for (size_t i = 0; i < 4; i++) { cs.c[i] = 0.05; cs.N[i] = 0.3 + 0.2 * (double)i; cs.v0[i] = 0.1 * (double)i; }
    cs.p.k_end = 1.0;
    cs.p.c_end = 0.1;
    chain_model *C = chain_create(&cs.p, &AL, NULL);
    chain_state s;
    chain_state_init(C, &s);
    const chain_inputs in = {NULL, NULL};
    chain_start(C, &in, 0.0, &s);
    const double E0 = chain_energy(C, &s);
    double worst = 0.0;
    for (int j = 1; j <= 200; j++) {
        chain_advance(C, &in, &s, j * 5.0 * Tp / 200.0, 0, NULL, NULL);
        const double res = chain_energy(C, &s) - E0 - s.W_applied - s.W_friction + s.D_damping;
        worst = fmax(worst, fabs(res));
    }
    chain_state_free(C, &s);
    chain_destroy(C);
    return worst;
}

static void test_energy(checks *T)
{
    double r[4];
    for (int j = 0; j < 4; j++) r[j] = energy_residual(400 << j);
    printf("energy balance (located, damped, 4 blocks, 5 periods): largest residual at T/400 ... T/3200: "
           "%.2e %.2e %.2e %.2e\n",
           r[0], r[1], r[2], r[3]);
    for (int j = 0; j < 3; j++) CHECK_RANGE(3.0, 5.5, r[j] / r[j + 1]);
    CHECK_RANGE(0.0, 2e-3, r[0]);
}

/* ---- 5. stop at switch, state copy ---------------------------------------------------------- */

typedef struct { long count; double t[4096]; size_t i[4096]; } switch_log;
static void log_switch(void *ctx, double t, size_t block, double x, int from, int to)
{
    (void)x; (void)from; (void)to;
    switch_log *L = (switch_log *)ctx;
    if (L->count < 4096) { L->t[L->count] = t; L->i[L->count] = block; }
    L->count++;
}

static void test_stop_and_copy(checks *T)
{
    chain_setup cs;
    setup_fill(&cs, 6, 0.7, 2.0 * DFO_PI / 0.7 / 500, 3);
    for (size_t i = 0; i < 6; i++) { cs.N[i] = 0.1 + 0.1 * (double)i; cs.P0[i] = (i % 2) ? 0.5 : 0.0; }
    chain_model *C = chain_create(&cs.p, &AL, NULL);
    chain_state a, b, c;
    CHECK(chain_state_init(C, &a) && chain_state_init(C, &b) && chain_state_init(C, &c));
    const chain_inputs in = {NULL, NULL};
    static switch_log La, Lb;
    La.count = Lb.count = 0;
    const double t_end = 3.0 * 2.0 * DFO_PI / 0.7;
    chain_start(C, &in, 0.0, &a);
    CHECK_INT(CHAIN_OK, chain_advance(C, &in, &a, t_end, 0, log_switch, &La));
    chain_start(C, &in, 0.0, &b);
    long stops = 0;
    for (;;) {
        const chain_status st = chain_advance(C, &in, &b, t_end, 1, log_switch, &Lb);
        if (st == CHAIN_OK) break;
        CHECK_INT(CHAIN_SWITCHED, st);
        if (st != CHAIN_SWITCHED || ++stops > 100000) break;
    }
    CHECK(La.count > 20);
    CHECK_INT(La.count, Lb.count);
    double dt = 0.0;
    for (long j = 0; j < La.count && j < Lb.count && j < 4096; j++) {
        CHECK_INT((long long)La.i[j], (long long)Lb.i[j]);
        dt = fmax(dt, fabs(La.t[j] - Lb.t[j]));
    }
    double dx = 0.0;
    for (size_t i = 0; i < 6; i++) dx = fmax(dx, fabs(a.X[i] - b.X[i]));
    CHECK_RANGE(0.0, 1e-9, dx);
    printf("stop at switch: %ld switches, %ld stops; largest difference of switch times %.2e s, of x %.2e m\n",
           La.count, stops, dt, dx);
    /* a copied state continues bit for bit */
    chain_start(C, &in, 0.0, &a);
    chain_advance(C, &in, &a, 0.5 * t_end, 0, NULL, NULL);
    chain_state_copy(&c, &a);
    chain_advance(C, &in, &a, t_end, 0, NULL, NULL);
    chain_advance(C, &in, &c, t_end, 0, NULL, NULL);
    for (size_t i = 0; i < 6; i++) {
        CHECK_SAME(a.X[i], c.X[i]);
        CHECK_SAME(a.V[i], c.V[i]);
        CHECK_INT(a.mode[i], c.mode[i]);
    }
    chain_state_free(C, &a);
    chain_state_free(C, &b);
    chain_state_free(C, &c);
    chain_destroy(C);
}

/* ---- 5b. the fused step of a step without switches gives the general path's bits ------------ */

static void test_fast_path(checks *T)
{
    /* the energy accounts send every step through the general path (the engine's fused step, the
     * model's step_held, is not offered with them); on a chain short enough to be split whole, the two
     * runs must agree bit for bit: one with a block without friction, one stick-dominated (every
     * block stuck for long phases), one whose external and normal force inputs change every 200
     * communication points (the fused steps' runs take the new loads) */
    static const double Fx[2][5] = {{0.0, 0.0, 0.0, 0.0, 0.0}, {0.3, -0.2, 0.0, 0.25, -0.1}};
    static const double Nx[2][5] = {{0.0, 0.0, 0.0, 0.0, 0.0}, {0.1, 0.4, -0.1, 0.0, 0.3}};
    for (int variant = 0; variant < 3; variant++) {
        chain_state st[2];
        chain_model *C[2];
        for (int k = 0; k < 2; k++) {
            chain_setup cs;
            setup_fill(&cs, 5, 0.7, 2.0 * DFO_PI / 0.7 / 400, 3);
            for (size_t i = 0; i < 5; i++) {
                cs.N[i] = (variant != 1) ? 0.2 + 0.15 * (double)i : 1.9 + 0.1 * (double)i;
                cs.c[i] = 0.02;
                cs.P0[i] = (i % 2) ? 0.0 : 1.0;
                cs.phi[i] = 0.4 * (double)i;
            }
            if (variant == 0) cs.N[2] = 0.0; /* one block without friction */
            else if (variant == 1) cs.P0[1] = -0.8;
            cs.p.k_end = 1.0;
            cs.p.account_energy = k;
            C[k] = chain_create(&cs.p, &AL, NULL);
            CHECK(C[k] != NULL && chain_state_init(C[k], &st[k]));
            const chain_inputs in = {NULL, NULL};
            chain_start(C[k], &in, 0.0, &st[k]);
        }
        chain_inputs in = {NULL, NULL};
        long long diffs = 0, all_stuck = 0;
        for (int j = 1; j <= 3000; j++) {
            const double t = j * 0.037;
            if (variant == 2 && j % 200 == 0) {
                const int u = (j / 200) % 2;
                const chain_inputs to = {Fx[u], Nx[u]};
                for (int k = 0; k < 2; k++) chain_new_inputs(C[k], &in, &to, &st[k]);
                in = to;
            }
            for (int k = 0; k < 2; k++) CHECK_INT(CHAIN_OK, chain_advance(C[k], &in, &st[k], t, 0, NULL, NULL));
            int stuck = 1;
            for (size_t i = 0; i < 5; i++) {
                diffs += (st[0].X[i] != st[1].X[i]) + (st[0].V[i] != st[1].V[i]) + (st[0].A[i] != st[1].A[i]) +
                         (st[0].F[i] != st[1].F[i]) + (st[0].mode[i] != st[1].mode[i]);
                stuck &= (st[0].mode[i] == 0);
            }
            all_stuck += stuck;
        }
        check_context(T, "fast paths, variant %d", variant);
        CHECK_INT(0, diffs);
        CHECK_INT(st[1].steps, st[0].steps);
        CHECK(st[0].switches > 40);
        if (variant == 1) CHECK(all_stuck > 300);
        check_context(T, "%s", "");
        printf("fast paths = general path (variant %d): %lld switches, %lld points all stuck, %lld differing values\n",
               variant, st[0].switches, all_stuck, diffs);
        for (int k = 0; k < 2; k++) { chain_state_free(C[k], &st[k]); chain_destroy(C[k]); }
    }
}

/* ---- 5c. hard inputs: stiff steps, stiff and light blocks, zero coefficients, inputs -------- */

static void test_hard(checks *T)
{
    const struct { size_t n; double h, N, chi, mratio; int scheme; } cases[] = {
        {3, 20.0, 0.8, 0.7, 1.0, 3},   {64, 30.0, 1.6, 0.7, 1.0, 3}, {64, 30.0, 1.6, 0.7, 1.0, 1},
        {300, 5.0, 0.6, 0.7, 1.0, 2},  {3, 0.01, 0.8, 0.7, 1e6, 3},  {8, 0.01, 0.8, 0.0, 1.0, 3},
        {8, 1e-5, 0.8, 1.0, 1.0, 3},   {40, 0.01, 0.0, 0.7, 1.0, 3},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        static double arr[10][300];
        const size_t n = cases[c].n;
        for (size_t i = 0; i < n; i++) {
            arr[0][i] = (i == 0) ? 1.0 / cases[c].mratio : (i == n - 1) ? cases[c].mratio : 1.0;
            arr[1][i] = (i == 0) ? cases[c].mratio : 1.0;
            arr[2][i] = 0.01; arr[3][i] = 1.0; arr[4][i] = 0.3 * (double)i; arr[5][i] = cases[c].N;
            arr[6][i] = 0.5; arr[7][i] = cases[c].chi; arr[8][i] = 0.0; arr[9][i] = 0.0;
        }
        const chain_params p = {n, arr[0], arr[1], arr[2], arr[3], arr[4], arr[5], arr[6], arr[7], arr[8], arr[9],
                                1.0, 0.0, 0.5, cases[c].h, -0.1, cases[c].scheme, 0, NULL, NULL, 0, NULL, NULL};
        chain_model *C = chain_create(&p, &AL, NULL);
        chain_state s;
        CHECK(C != NULL && chain_state_init(C, &s));
        double Fext[300], Next[300];
        for (size_t i = 0; i < n; i++) { Fext[i] = 0.05 * (double)(i % 3); Next[i] = -0.3 * (double)(i % 2); }
        const chain_inputs in = {Fext, Next};
        chain_start(C, &in, 0.0, &s);
        check_context(T, "hard case %zu", c);
        const double t_end = (cases[c].h < 1e-3) ? 0.5 : 200.0 * (cases[c].h > 1.0 ? cases[c].h : 1.0);
        chain_status st = CHAIN_OK;
        for (int j = 1; j <= 50 && st == CHAIN_OK; j++) st = chain_advance(C, &in, &s, j * t_end / 50, 0, NULL, NULL);
        CHECK_INT(CHAIN_OK, st);
        double xmax = 0.0;
        for (size_t i = 0; i < n; i++) xmax = fmax(xmax, fabs(s.X[i]));
        CHECK_RANGE(0.0, 1e3, xmax);
        chain_state_free(C, &s);
        chain_destroy(C);
    }
    check_context(T, "%s", "");
}

/* ---- 6. invalid parameters ------------------------------------------------------------------ */

static void test_params(checks *T)
{
    chain_setup cs;
    setup_fill(&cs, 4, 1.0, 0.01, 3);
    char buf[200];
    CHECK(chain_check_params(&cs.p, buf, sizeof buf) == NULL);
    cs.m[2] = -1.0;
    const char *msg = chain_check_params(&cs.p, buf, sizeof buf);
    CHECK(msg != NULL && strstr(msg, "invalid value -1 for m[3]") != NULL);
    CHECK(chain_create(&cs.p, &AL, NULL) == NULL);
    cs.m[2] = 1.0;
    cs.chi[3] = NAN;
    msg = chain_check_params(&cs.p, buf, sizeof buf);
    CHECK(msg != NULL && strstr(msg, "chi[4]") != NULL);
    cs.chi[3] = 0.5;
    cs.p.alpha = 0.1;
    msg = chain_check_params(&cs.p, buf, sizeof buf);
    CHECK(msg != NULL && strstr(msg, "alpha") != NULL);
}

int main(void)
{
    checks TT = {0};
    checks *T = &TT;
    test_single(T);
    test_lcp_enumeration(T);
    test_invariants(T);
    test_energy(T);
    test_stop_and_copy(T);
    test_fast_path(T);
    test_hard(T);
    test_params(T);
    return checks_done(T, "test_chain");
}
