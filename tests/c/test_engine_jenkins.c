/* The engine's Jenkins contact (eng_setup.k_t: a spring k_t in series with a massless slider) on one
 * block, m x'' + k x = f, f = -k_t (x - s), against closed forms derived here:
 *   - from x0 at rest, the slider relaxed at x0 and stuck, the block swings on k + k_t about
 *     c = k_t x0 / (k + k_t): x = c + (x0 - c) cos(w1 t), w1^2 = (k + k_t) / m, until the spring
 *     force k_t (x0 - x) reaches Fb = mu_s N at t_b (cos(w1 t_b) = 1 - Fb / (k_t (x0 - c))); then the
 *     slider slides back, the force drops to Fk = mu_k N (the slider jumps by (Fb - Fk) / k_t) and the
 *     block swings on k about Fk / k: x = Fk / k + A cos(w0 tau) + B sin(w0 tau), tau = t - t_b,
 *     A = x(t_b) - Fk / k, B = v(t_b) / w0, the slider at s = x + Fk / k_t, the friction's work
 *     -(Fb^2 - Fk^2) / 2 k_t + Fk (x - x(t_b)). The located scheme at h, h/2, h/4: error ratios of
 *     about 4 (second order across the breakaway) in x, s and the friction work; the consistent and
 *     paper schemes run to the same point within O(h);
 *   - with N huge the slider never moves: x = x0 cos(w1 t) (second order).
 *   - a rigid setup (k_t NULL) and the same one with k_t = 0 everywhere: the same bits;
 *   - a rigid contact beside a Jenkins one on the block, mu_k >= mu_s on the Jenkins (F_b = F_k): from
 *     x0 at rest the rigid contact slides back (m x'' = -k x - k_t (x - x0) + Fk_r) until the spring
 *     force reaches F_b, then the slider slides too (no jump: m x'' = -k x + Fk_r + Fk_j) until the
 *     block stops at x_stop = (Fk_r + Fk_j) / k - R (R the amplitude of that swing), where the rigid
 *     contact holds (|k x_stop - Fk_j| <= Fb_r) and the slider stops with its force on its limit:
 *     both stay stuck, the slider at x_stop + Fk_j / k_t, its force within its limit (it used to
 *     break away again at once, its force a hair beyond in rounding, without end). */
#include "check.h"
#include "engine.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *t_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void t_free(void *env, void *p) { (void)env; free(p); }
static const eng_alloc ALLOC = {t_alloc, t_free, NULL};

typedef struct {
    double m, k;
    double L[ENG_NSLOTS]; /* the factor slots: the scalar A itself */
} block;

static void op_K(void *c, const double *x, double *y) { y[0] = ((block *)c)->k * x[0]; }
static void op_M(void *c, const double *a, double *y) { y[0] = ((block *)c)->m * a[0]; }
static int op_factor(void *c, int slot, double cM, double cC, double cK)
{
    block *B = c;
    (void)cC;
    B->L[slot] = cM * B->m + cK * B->k;
    return B->L[slot] > 0.0;
}
static void op_solve(void *c, int slot, const double *b, double *x) { x[0] = b[0] / ((block *)c)->L[slot]; }

typedef struct {
    double x, s, W; /* position, slider, friction work at the end */
    eng_status st;
} outcome;

static const size_t IDX0 = 0;
static const double ONE = 1.0;

/* The block from x0 at rest to t_end in steps of h with one contact (k_t as given, NULL: rigid). */
static outcome run(block *B, const double *kt, double N, double mu_s, double mu_k, double x0, double h, double t_end,
                   int scheme)
{
    const eng_row row = {1, &IDX0, &ONE};
    eng_setup S;
    memset(&S, 0, sizeof S);
    S.n = 1;
    S.nc = 1;
    S.ops.ctx = B;
    S.ops.apply_K = op_K;
    S.ops.apply_M = op_M;
    S.ops.factor = op_factor;
    S.ops.solve = op_solve;
    S.rows = &row;
    S.N = &N;
    S.mu_s = &mu_s;
    S.mu_k = &mu_k;
    S.k_t = kt;
    S.h = h;
    S.alpha = -0.1;
    S.scheme = scheme;
    S.friction_updates = 1;
    S.account_energy = 1;
    S.rate_max = sqrt((B->k + (kt ? kt[0] : 0.0)) / B->m);
    S.snap_max_rel_h = S.snap_min_rel_h = 1e-7;
    outcome o = {NAN, NAN, NAN, ENG_ERR_BAD_INPUT};
    eng *E = eng_create(&S, &ALLOC, NULL);
    eng_state s;
    if (!E || !eng_state_init(E, &s, 0)) return o;
    const double v0 = 0.0;
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    eng_start(E, &in, 0.0, &x0, &v0, &s);
    o.st = eng_advance(E, &in, &s, t_end, NULL);
    o.x = s.X[0];
    o.s = s.slider[0];
    o.W = s.W_friction;
    eng_state_free(E, &s);
    eng_destroy(E);
    return o;
}

static void test_breakaway(checks *T)
{
    block B = {1.0, 10.0, {0.0}};
    const double kt = 90.0, N = 10.0, mu_s = 0.6, mu_k = 0.4, x0 = 1.0;
    const double Fb = mu_s * N, Fk = mu_k * N;
    const double w1 = sqrt((B.k + kt) / B.m), w0 = sqrt(B.k / B.m), c = kt * x0 / (B.k + kt);
    const double tb = acos(1.0 - Fb / (kt * (x0 - c))) / w1;
    const double xb = c + (x0 - c) * cos(w1 * tb), vb = -(x0 - c) * w1 * sin(w1 * tb);
    const double A = xb - Fk / B.k, Bs = vb / w0;
    const double t_end = tb + 0.4; /* inside the slide (it ends at tau = 0.83) */
    const double tau = t_end - tb;
    const double xe = Fk / B.k + A * cos(w0 * tau) + Bs * sin(w0 * tau);
    const double se = xe + Fk / kt, We = -(Fb * Fb - Fk * Fk) / (2.0 * kt) + Fk * (xe - xb);
    CHECK(-A * w0 * sin(w0 * tau) + Bs * w0 * cos(w0 * tau) < 0.0); /* still sliding back */
    double ex[3], es[3], ew[3];
    for (int q = 0; q < 3; q++) {
        const double h = 0.01 / (double)(1 << q);
        const outcome o = run(&B, &kt, N, mu_s, mu_k, x0, h, t_end, DFO_SCHEME_LOCATED);
        CHECK_INT(ENG_OK, o.st);
        ex[q] = fabs(o.x - xe);
        es[q] = fabs(o.s - se);
        ew[q] = fabs(o.W - We);
        printf("located h = %g: |x - x_exact| = %.3e, |s - s_exact| = %.3e, |W - W_exact| = %.3e\n", h, ex[q],
               es[q], ew[q]);
    }
    CHECK(ex[0] < 1e-3);
    for (int q = 0; q < 2; q++) {
        CHECK_RANGE(3.6, 4.4, ex[q] / ex[q + 1]);
        CHECK_RANGE(3.6, 4.4, es[q] / es[q + 1]);
        CHECK_RANGE(3.6, 4.4, ew[q] / ew[q + 1]);
    }
    for (int scheme = DFO_SCHEME_PAPER; scheme <= DFO_SCHEME_CONSISTENT; scheme++) {
        const outcome o = run(&B, &kt, N, mu_s, mu_k, x0, 0.0025, t_end, scheme);
        CHECK_INT(ENG_OK, o.st);
        printf("scheme %d h = 0.0025: |x - x_exact| = %.3e, |s - s_exact| = %.3e\n", scheme, fabs(o.x - xe),
               fabs(o.s - se));
        CHECK(fabs(o.x - xe) < 0.02 && fabs(o.s - se) < 0.02);
    }
}

static void test_stuck_spring(checks *T)
{
    block B = {2.0, 30.0, {0.0}};
    const double kt = 170.0, x0 = 0.3, t_end = 1.7, w1 = sqrt((B.k + kt) / B.m);
    double e[2];
    for (int q = 0; q < 2; q++) {
        const double h = 2e-3 / (double)(1 << q);
        /* the slider relaxed at x0: the block swings about c, its spring force within 1e9 */
        const double c = kt * x0 / (B.k + kt);
        const outcome o = run(&B, &kt, 1e9, 1.0, 1.0, x0, h, t_end, DFO_SCHEME_LOCATED);
        CHECK_INT(ENG_OK, o.st);
        CHECK_SAME(x0, o.s);
        e[q] = fabs(o.x - (c + (x0 - c) * cos(w1 * t_end)));
    }
    printf("huge N: errors %.3e %.3e\n", e[0], e[1]);
    CHECK(e[0] < 1e-3);
    CHECK_RANGE(3.6, 4.4, e[0] / e[1]);
}

static void test_rigid_unchanged(checks *T)
{
    block B = {1.0, 10.0, {0.0}};
    const double zero = 0.0;
    for (int scheme = DFO_SCHEME_PAPER; scheme <= DFO_SCHEME_LOCATED; scheme++) {
        const outcome a = run(&B, NULL, 2.0, 0.5, 0.3, 1.0, 1e-3, 2.0, scheme);
        const outcome b = run(&B, &zero, 2.0, 0.5, 0.3, 1.0, 1e-3, 2.0, scheme);
        CHECK_SAME(a.x, b.x);
        CHECK_SAME(a.W, b.W);
    }
}

/* The block with a rigid contact (contact 0) and a Jenkins one (contact 1) from x0 at rest to t_end
 * (located, step h): its end position, slider, slider force and switches. */
static outcome run_pair(block *B, const double *N, const double *mu_s, const double *mu_k, double kt, double x0,
                        double h, double t_end, double *f1, long long *switches)
{
    const eng_row rows[2] = {{1, &IDX0, &ONE}, {1, &IDX0, &ONE}};
    const double k_t[2] = {0.0, kt};
    eng_setup S;
    memset(&S, 0, sizeof S);
    S.n = 1;
    S.nc = 2;
    S.ops.ctx = B;
    S.ops.apply_K = op_K;
    S.ops.apply_M = op_M;
    S.ops.factor = op_factor;
    S.ops.solve = op_solve;
    S.rows = rows;
    S.N = N;
    S.mu_s = mu_s;
    S.mu_k = mu_k;
    S.k_t = k_t;
    S.h = h;
    S.alpha = -0.1;
    S.scheme = DFO_SCHEME_LOCATED;
    S.friction_updates = 1;
    S.rate_max = sqrt((B->k + kt) / B->m);
    S.snap_max_rel_h = S.snap_min_rel_h = 1e-7;
    outcome o = {NAN, NAN, NAN, ENG_ERR_BAD_INPUT};
    eng *E = eng_create(&S, &ALLOC, NULL);
    eng_state s;
    if (!E || !eng_state_init(E, &s, 0)) return o;
    const double v0 = 0.0;
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    eng_start(E, &in, 0.0, &x0, &v0, &s);
    o.st = eng_advance(E, &in, &s, t_end, NULL);
    o.x = s.X[0];
    o.s = s.slider[1];
    *f1 = s.F[1];
    *switches = s.switches;
    eng_state_free(E, &s);
    eng_destroy(E);
    return o;
}

static void test_slider_stops_beside_rigid(checks *T)
{
    block B = {1.0, 10.0, {0.0}};
    const double N[2] = {10.0, 10.0}, mu_s[2] = {0.3, 0.3}, mu_k[2] = {0.2, 0.4}, kt = 50.0;
    const double Fb_r = 3.0, Fk_r = 2.0, Fk_j = 4.0; /* the Jenkins contact's F_b = F_k */
    const double w1 = sqrt((B.k + kt) / B.m), w0 = sqrt(B.k / B.m);
    for (int q = 0; q < 8; q++) { /* (x0 varied: the stop's force rounds either side of the limit) */
        const double x0 = 1.0 + 0.005 * q;
        const double c = (kt * x0 + Fk_r) / (B.k + kt), x1 = x0 - Fk_j / kt;
        const double ct = (x1 - c) / (x0 - c), v1 = -(x0 - c) * w1 * sqrt(1.0 - ct * ct);
        const double c2 = (Fk_r + Fk_j) / B.k, R = hypot(x1 - c2, v1 / w0), x_stop = c2 - R;
        CHECK(ct > -1.0 && fabs(B.k * x_stop - Fk_j) <= Fb_r); /* the slider breaks away, the block then held */
        double f1 = NAN;
        long long sw = 0;
        const outcome o = run_pair(&B, N, mu_s, mu_k, kt, x0, 1e-3, 2.0, &f1, &sw);
        CHECK_INT(ENG_OK, o.st);
        printf("rigid + Jenkins, x0 = %g: |x - x_stop| = %.3e, |s - s_stop| = %.3e, f = %.17g, %lld switches\n", x0,
               fabs(o.x - x_stop), fabs(o.s - (x_stop + Fk_j / kt)), f1, sw);
        CHECK(fabs(o.x - x_stop) < 1e-6);
        CHECK(fabs(o.s - (x_stop + Fk_j / kt)) < 1e-6);
        CHECK(fabs(f1) <= Fk_j && fabs(f1) > Fk_j - 1e-9);
        /* the rigid contact's stop, the slider's breakaway and stop (the start's slide not counted) */
        CHECK_INT(3, (int)sw);
    }
}

int main(void)
{
    checks C = {0, 0, NULL, {0}}, *T = &C;
    test_breakaway(T);
    test_stuck_spring(T);
    test_rigid_unchanged(T);
    test_slider_stops_beside_rigid(T);
    return checks_done(T, "test_engine_jenkins");
}
