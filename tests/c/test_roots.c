/* The bracketed root finder of fmu_src/numerics/roots.h (Brent's method).
 *
 * 1. Known roots: polynomials (simple, triple), cos, exp - 2, a root near 0 and one of 1e300, at the
 *    tolerance of roots.h (4 DBL_EPSILON (|x0| + |x|) + DBL_MIN), with the origin x0 of the search
 *    (a time 1e6 ahead: the bracket is then resolved to the ulps of 1e6, not of x).
 * 2. The ends: a root at lo or at hi (f = 0 there: returned as is), a root within an ulp of either
 *    end; the returned end is on hi's side of the sign (f(result) of hi's sign, or 0).
 * 3. Flat functions: f = (x - r)^9 (flat to below rounding around r), f = 0 on a whole interval
 *    (the first exact zero met is returned), f constant on each side of r (a sign jump: the jump
 *    found to the tolerance, in at most as many evaluations as printed).
 * 4. Orientation: increasing f, lo > hi: the same root; no bracket (both ends of one sign, a NaN):
 *    NaN.
 * 5. The bits of the switch searches: against the Brent search the located schemes used before
 *    (copied below as it was), on random brackets of random smooth functions, the same bits. */
#include "check.h"
#include "roots.h"

#include <float.h>
#include <math.h>
#include <stdio.h>

typedef struct {
    int kind;
    double r, a;
    long evals;
} fn_ctx;

enum { POLY1, POLY3, COS, EXPM2, POW9, FLAT_ZERO, JUMP, SMOOTH };

static double f_eval(void *ctx, double x)
{
    fn_ctx *c = (fn_ctx *)ctx;
    c->evals++;
    const double d = x - c->r;
    switch (c->kind) {
    case POLY1: return -c->a * d;
    case POLY3: return -d * d * d;
    case COS: return cos(x);
    case EXPM2: return 2.0 - exp(x);
    case POW9: return -pow(d, 9.0);
    case FLAT_ZERO: return (x < c->r) ? 1.0 : (x > c->r + c->a) ? -1.0 : 0.0;
    case JUMP: return (x < c->r) ? 3.0 : -0.5;
    case SMOOTH: return c->a * (c->r - x) + 0.3 * sin(7.0 * x) * (c->r - x) * (c->r - x);
    }
    return NAN;
}

static double tol_at(double x0, double x) { return 4.0 * DBL_EPSILON * (fabs(x0) + fabs(x)) + DBL_MIN; }

/* the search from lo to hi for c's function, with the result within twice the tolerance of the
 * root r (the final bracket's width) and on hi's side */
static double check_root(checks *T, fn_ctx *c, double x0, double lo, double hi, double root, long *max_evals)
{
    c->evals = 0;
    const double flo = f_eval(c, lo), fhi = f_eval(c, hi);
    c->evals = 0;
    const double x = dfo_root_bracketed(f_eval, c, x0, lo, flo, hi, fhi);
    CHECK_RANGE(root - 2.0 * tol_at(x0, root), root + 2.0 * tol_at(x0, root), x);
    const double fx = f_eval(c, x);
    c->evals--;
    CHECK(fx == 0.0 || (fx > 0.0) == (fhi > 0.0));
    CHECK(c->evals <= 200);
    if (max_evals && c->evals > *max_evals) *max_evals = c->evals;
    return x;
}

static void test_known(checks *T, long *evals)
{
    check_context(T, "known roots");
    fn_ctx c = {POLY1, 0.3, 2.0, 0};
    check_root(T, &c, 0.0, 0.0, 1.0, 0.3, evals);
    check_root(T, &c, 5.0, 0.0, 1.0, 0.3, evals);
    c.r = 1e-300;
    check_root(T, &c, 0.0, 0.0, 1.0, 1e-300, evals);
    c.r = 1e300;
    check_root(T, &c, 0.0, 0.0, 3e300, 1e300, evals);
    c = (fn_ctx){POLY3, 0.7, 0.0, 0};
    check_root(T, &c, 0.0, 0.0, 1.0, 0.7, evals);
    c = (fn_ctx){COS, 0.0, 0.0, 0};
    check_root(T, &c, 0.0, 1.0, 2.0, 2.0 * atan(1.0), evals);
    c = (fn_ctx){EXPM2, 0.0, 0.0, 0};
    check_root(T, &c, 0.0, 0.0, 1.0, log(2.0), evals);
    /* the origin: a switch 0.25 s into a step that starts at t = 1e6 is placed to the ulps of 1e6
     * (2.3e-10), not of 0.25 (the search stops early, and still within that) */
    c = (fn_ctx){POLY1, 0.25, 1.0, 0};
    const double x = check_root(T, &c, 1e6, 0.0, 1.0, 0.25, evals);
    CHECK_RANGE(0.0, 2.0 * tol_at(1e6, 0.25), fabs(x - 0.25));
    T->context = NULL;
}

static void test_ends(checks *T, long *evals)
{
    check_context(T, "ends");
    fn_ctx c = {POLY1, 0.0, 1.0, 0};
    double fz = f_eval(&c, 0.0);
    CHECK(fz == 0.0);
    CHECK_SAME(0.0, dfo_root_bracketed(f_eval, &c, 0.0, 0.0, fz, 1.0, f_eval(&c, 1.0))); /* f(lo) = 0 */
    c.r = 1.0;
    CHECK_SAME(1.0, dfo_root_bracketed(f_eval, &c, 0.0, 0.0, f_eval(&c, 0.0), 1.0, f_eval(&c, 1.0))); /* f(hi) = 0 */
    c.r = nextafter(0.0, 1.0) * 4;  /* just above lo */
    check_root(T, &c, 0.0, 0.0, 1.0, c.r, evals);
    c.r = nextafter(1.0, 0.0);      /* an ulp below hi */
    const double x = check_root(T, &c, 0.0, 0.0, 1.0, c.r, evals);
    CHECK(f_eval(&c, x) <= 0.0);
    T->context = NULL;
}

static void test_flat(checks *T, long *evals_jump)
{
    check_context(T, "flat and discontinuous");
    fn_ctx c = {POW9, 0.6, 0.0, 0};
    /* (x - r)^9 underflows to 0 within about 1e-34 of r: any point there is a root; tolerance of
     * the bracket */
    long e = 0;
    check_root(T, &c, 0.0, 0.0, 1.0, 0.6, &e);
    c = (fn_ctx){FLAT_ZERO, 0.2, 0.3, 0};
    const double x = dfo_root_bracketed(f_eval, &c, 0.0, 0.0, 1.0, 1.0, -1.0);
    CHECK_RANGE(0.2, 0.5, x);
    CHECK_SAME(0.0, f_eval(&c, x));
    for (int k = 0; k < 40; k++) {
        c = (fn_ctx){JUMP, 0.05 + 0.9 * k / 40.0 + 1e-3 * sin(k), 0.0, 0};
        check_root(T, &c, 0.0, 0.0, 1.0, c.r, evals_jump);
        check_root(T, &c, 0.0, -1.0, 3.0, c.r, evals_jump);
    }
    T->context = NULL;
}

static void test_orientation(checks *T)
{
    check_context(T, "orientation and no bracket");
    fn_ctx c = {POLY1, 0.3, -2.0, 0}; /* increasing: f(lo) < 0 < f(hi) */
    check_root(T, &c, 0.0, 0.0, 1.0, 0.3, NULL);
    c.a = 2.0;                        /* lo > hi */
    check_root(T, &c, 0.0, 1.0, 0.0, 0.3, NULL);
    CHECK(isnan(dfo_root_bracketed(f_eval, &c, 0.0, 0.0, 1.0, 1.0, 2.0)));
    CHECK(isnan(dfo_root_bracketed(f_eval, &c, 0.0, 0.0, -1.0, 1.0, -2.0)));
    CHECK(isnan(dfo_root_bracketed(f_eval, &c, 0.0, 0.0, NAN, 1.0, -2.0)));
    CHECK(isnan(dfo_root_bracketed(f_eval, &c, 0.0, 0.0, 1.0, 1.0, NAN)));
    T->context = NULL;
}

/* The located schemes' search as it was (bossak.h's dfo_brent), for the bit comparison. */
static double brent_before(dfo_root_fn f, void *ctx, double t_abs, double lo, double flo, double hi, double fhi)
{
    double a = lo, b = hi, fa = flo, fb = fhi, c = a, fc = fa, d = b - a, e = d;
    for (int it = 0; it < 200; it++) {
        if (fb == 0.0) return b;
        if ((fb > 0.0) == (fc > 0.0)) { c = a; fc = fa; d = e = b - a; }
        if (fabs(fc) < fabs(fb)) { a = b; b = c; c = a; fa = fb; fb = fc; fc = fa; }
        const double tol = 4.0 * DBL_EPSILON * (fabs(t_abs) + fabs(b)) + DBL_MIN;
        const double m = 0.5 * (c - b);
        if (fabs(m) <= tol) break;
        if (fabs(e) >= tol && fabs(fa) > fabs(fb)) {
            double p, q, r;
            const double ratio = fb / fa;
            if (a == c) {
                p = 2.0 * m * ratio;
                q = 1.0 - ratio;
            } else {
                q = fa / fc;
                r = fb / fc;
                p = ratio * (2.0 * m * q * (q - r) - (b - a) * (r - 1.0));
                q = (q - 1.0) * (r - 1.0) * (ratio - 1.0);
            }
            if (p > 0.0) q = -q; else p = -p;
            if (2.0 * p < fmin(3.0 * m * q - fabs(tol * q), fabs(e * q))) { e = d; d = p / q; }
            else { d = m; e = m; }
        } else {
            d = m;
            e = m;
        }
        a = b;
        fa = fb;
        b += (fabs(d) > tol) ? d : (m > 0.0 ? tol : -tol);
        fb = f(ctx, b);
    }
    return (fb <= 0.0) ? b : c;
}

static void test_bits(checks *T, long *same)
{
    check_context(T, "the bits of the search before");
    rng r = {1234567};
    for (int k = 0; k < 20000; k++) {
        fn_ctx c = {k % 4 == 0 ? JUMP : (k % 4 == 1 ? POW9 : SMOOTH), rng_range(&r, 0.0, 1.0),
                    rng_decades(&r, -3.0, 3.0), 0};
        const double t0 = (k % 3) ? 0.0 : rng_decades(&r, -2.0, 8.0);
        const double lo = 0.0, hi = c.r + rng_range(&r, 1e-9, 1.0);
        const double flo = f_eval(&c, lo), fhi = f_eval(&c, hi);
        if (!(flo > 0.0 && fhi <= 0.0)) continue;
        const double x1 = brent_before(f_eval, &c, t0, lo, flo, hi, fhi);
        const double x2 = dfo_root_bracketed(f_eval, &c, t0, lo, flo, hi, fhi);
        if (CHECK_SAME(x1, x2)) (*same)++;
    }
    T->context = NULL;
}

int main(void)
{
    checks C = {0, 0, NULL, {0}}, *T = &C;
    long evals = 0, evals_jump = 0, same = 0;
    test_known(T, &evals);
    test_ends(T, &evals);
    test_flat(T, &evals_jump);
    test_orientation(T);
    test_bits(T, &same);
    printf("known roots and ends: at most %ld evaluations; a sign jump: at most %ld; %ld random searches "
           "with the bits of the search before\n",
           evals, evals_jump, same);
    return checks_done(T, "test_roots");
}
