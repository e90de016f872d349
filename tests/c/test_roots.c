/* The bracketed root finder of fmu_src/numerics/roots.h (Brent's method).
 *
 * 1. Known roots: polynomials (simple, triple), cos, exp - 2, a smooth non-polynomial f on random
 *    brackets and origins, a root near 0 and one of 1e300, at the
 *    tolerance of roots.h (4 DBL_EPSILON (|x0| + |x|) + DBL_MIN), with the origin x0 of the search
 *    (a time 1e6 ahead: the bracket is then resolved to the ulps of 1e6, not of x).
 * 2. The ends: a root at lo or at hi (f = 0 there: returned as is), a root within an ulp of either
 *    end; the returned end is on hi's side of the sign (f(result) of hi's sign, or 0).
 * 3. Flat functions: f = (x - r)^9 (flat to below rounding around r), f = 0 on a whole interval
 *    (the first exact zero met is returned), f constant on each side of r (a sign jump: the jump
 *    found to the tolerance, in at most as many evaluations as printed).
 * 4. Orientation: increasing f, lo > hi: the same root; no bracket (both ends of one sign, a NaN):
 *    NaN.
 * 5. A noisy f (a line plus a deterministic rounding-like noise of amplitude d): with fnoise = d the
 *    search stops within the x over which the line changes by about d (d / slope) of the root, on
 *    hi's side, in fewer evaluations than without (which bisects on the noise's signs); fnoise = 0
 *    keeps every bit of the search without it (the same x and evaluations). */
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

enum { POLY1, POLY3, COS, EXPM2, POW9, FLAT_ZERO, JUMP, SMOOTH, NOISY };

/* a deterministic noise in [-1, 1] of x's bits (a hash of them) */
static double noise_of(double x)
{
    union { double d; unsigned long long u; } b = {x};
    unsigned long long h = b.u * 0x9E3779B97F4A7C15ull;
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 32;
    return (double)(h >> 11) / 4503599627370496.0 - 1.0; /* (2^53 values over [0, 2), minus 1) */
}

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
    case NOISY: return (c->r - x) + c->a * noise_of(x);
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
    const double x = dfo_root_bracketed(f_eval, c, x0, lo, flo, hi, fhi, 0.0);
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
    /* (r - x) (a + 0.3 sin(7 x) (r - x)), a >= 1: one root r in [r - 0.5, r + 0.5], found from
     * brackets of every width and origin */
    rng g = {99};
    for (int k = 0; k < 2000; k++) {
        c = (fn_ctx){SMOOTH, rng_range(&g, -1.0, 1.0), rng_range(&g, 1.0, 10.0), 0};
        const double x0 = (k % 2) ? rng_decades(&g, -3.0, 6.0) : 0.0;
        check_root(T, &c, x0, c.r - rng_decades(&g, -9.0, log10(0.5)), c.r + rng_decades(&g, -9.0, log10(0.5)), c.r,
                   evals);
    }
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
    CHECK_SAME(0.0, dfo_root_bracketed(f_eval, &c, 0.0, 0.0, fz, 1.0, f_eval(&c, 1.0), 0.0)); /* f(lo) = 0 */
    c.r = 1.0;
    CHECK_SAME(1.0, dfo_root_bracketed(f_eval, &c, 0.0, 0.0, f_eval(&c, 0.0), 1.0, f_eval(&c, 1.0), 0.0)); /* f(hi) = 0 */
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
    const double x = dfo_root_bracketed(f_eval, &c, 0.0, 0.0, 1.0, 1.0, -1.0, 0.0);
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
    CHECK(isnan(dfo_root_bracketed(f_eval, &c, 0.0, 0.0, 1.0, 1.0, 2.0, 0.0)));
    CHECK(isnan(dfo_root_bracketed(f_eval, &c, 0.0, 0.0, -1.0, 1.0, -2.0, 0.0)));
    CHECK(isnan(dfo_root_bracketed(f_eval, &c, 0.0, 0.0, NAN, 1.0, -2.0, 0.0)));
    CHECK(isnan(dfo_root_bracketed(f_eval, &c, 0.0, 0.0, 1.0, 1.0, NAN, 0.0)));
    T->context = NULL;
}

static void test_noisy(checks *T)
{
    T->context = "noisy";
    int fewer = 0;
    long total_with = 0, total_without = 0;
    for (int k = 0; k < 200; k++) {
        const double d = ldexp(1.0, -40 - k % 8);         /* noise 9.1e-13 .. 7.1e-15 */
        fn_ctx c = {NOISY, 0.3 + 1e-3 * k, d, 0};
        const double x0 = (double)(k % 3), lo = 0.0, hi = 0.5 + 1e-3 * (k % 7);
        const double flo = f_eval(&c, lo), fhi = f_eval(&c, hi);
        c.evals = 0;
        const double x = dfo_root_bracketed(f_eval, &c, x0, lo, flo, hi, fhi, d);
        const long with = c.evals;
        /* within the noise's reach of the root (d / slope, slope 1, plus the time tolerance), and
         * on hi's side as every search returns it */
        CHECK_RANGE(c.r - 4.0 * d - 2.0 * tol_at(x0, c.r), c.r + 4.0 * d + 2.0 * tol_at(x0, c.r), x);
        CHECK(f_eval(&c, x) <= 0.0);
        c.evals = 0;
        const double x_plain = dfo_root_bracketed(f_eval, &c, x0, lo, flo, hi, fhi, 0.0);
        const long without = c.evals;
        total_with += with;
        total_without += without;
        fewer += with < without;
        CHECK_RANGE(c.r - 4.0 * d - 2.0 * tol_at(x0, c.r), c.r + 4.0 * d + 2.0 * tol_at(x0, c.r), x_plain);
    }
    CHECK(fewer >= 100 && total_with < total_without);
    printf("noisy f: fewer evaluations with its rounding given in %d of 200 searches (%ld against %ld)\n", fewer,
           total_with, total_without);
    T->context = NULL;
}

int main(void)
{
    checks C = {0, 0, NULL, {0}}, *T = &C;
    long evals = 0, evals_jump = 0;
    test_known(T, &evals);
    test_ends(T, &evals);
    test_flat(T, &evals_jump);
    test_orientation(T);
    test_noisy(T);
    printf("known roots and ends: at most %ld evaluations; a sign jump: at most %ld\n", evals, evals_jump);
    return checks_done(T, "test_roots");
}
