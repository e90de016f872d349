/* The bracketed root finder (Brent's method). See roots.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "roots.h"

#include <float.h>
#include <math.h>

double dfo_root_bracketed(dfo_root_fn f, void *ctx, double x0, double lo, double flo, double hi, double fhi,
                          double fnoise)
{
    if (isnan(flo) || isnan(fhi)) return NAN;
    /* the x over which f changes by its rounding (0: none, or no finite slope) */
    const double xnoise = (fnoise > 0.0 && isfinite(fhi - flo) && fhi != flo) ? fnoise * fabs((hi - lo) / (fhi - flo)) : 0.0;
    if (flo == 0.0) return lo;
    /* s f has s f(lo) > 0 >= s f(hi): the search below is written for that orientation (s = 1
     * keeps every value's bits, s = -1 flips the signs exactly) */
    const double s = (flo > 0.0) ? 1.0 : -1.0;
    if (s * fhi > 0.0) return NAN;
    double a = lo, b = hi, fa = s * flo, fb = s * fhi, c = a, fc = fa, d = b - a, e = d;
    for (int it = 0; it < 200; it++) {
        if (fb == 0.0) return b;
        if ((fb > 0.0) == (fc > 0.0)) { c = a; fc = fa; d = e = b - a; }
        if (fabs(fc) < fabs(fb)) { a = b; b = c; c = a; fa = fb; fb = fc; fc = fa; }
        double tol = 4.0 * DBL_EPSILON * (fabs(x0) + fabs(b)) + DBL_MIN;
        if (tol < xnoise) tol = xnoise;
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
            /* fmin of the two bounds by comparison (a library call otherwise), NaN as fmin takes it */
            const double b1 = 3.0 * m * q - fabs(tol * q), b2 = fabs(e * q);
            if (2.0 * p < ((b1 < b2 || b2 != b2) ? b1 : b2)) { e = d; d = p / q; }
            else { d = m; e = m; }
        } else {
            d = m;
            e = m;
        }
        a = b;
        fa = fb;
        b += (fabs(d) > tol) ? d : (m > 0.0 ? tol : -tol);
        fb = s * f(ctx, b);
    }
    return (fb <= 0.0) ? b : c;
}
