/* The one root finder of the C sources: the zero of a continuous function of one variable inside
 * a bracket, for every switch location (a stop inside a sliding step, a breakaway under varying
 * loads or on a belt, the chain's first switch).
 *
 * Method: Brent's (inverse quadratic interpolation and secant steps, bisection whenever they would
 * not shrink the bracket fast enough). The bracket always holds a sign change and at least halves
 * every few evaluations, so it converges for any f, continuous or not (a jump is found as a root;
 * tests/c/test_roots.c: at most 70 evaluations for a jump inside [0, 1]); at most 200 evaluations.
 *
 * Bracket: f(lo) and f(hi) of opposite signs, lo < hi or lo > hi alike; an end where f = 0 is the
 * root itself and is returned.
 *
 * Tolerance (the one convention): x is measured from an origin x0 (the switch searches measure
 * time from the step's start, x0 = t, x = h; x0 = 0 for an absolute coordinate); the search stops
 * when the bracket's half width is at most 4 DBL_EPSILON (|x0| + |x|) + DBL_MIN, a few ulps of the
 * absolute position x0 + x (nothing finer is representable there), or at an evaluation f = 0.
 * fnoise >= 0: the rounding of f's values (0: none); the half width may then also be up to the x
 * over which f changes by fnoise at the bracket's mean slope, fnoise |hi - lo| / |f(hi) - f(lo)|:
 * inside it f's signs are rounding, and bisecting on them only costs evaluations (a margin computed
 * through a large solve is noisy at 1e-13 of its scale, which is 1e-13 s of a switch time).
 *
 * Result: x with f(x) = 0 where an evaluation gives exactly 0, else the end of the final bracket
 * on the side of hi's sign (where the event has happened, when hi is the later end); NaN when the
 * input is no bracket (both ends of one sign, or a NaN).
 *
 * Plain C, no FMI types. */
#ifndef DFO_ROOTS_H
#define DFO_ROOTS_H

/* f is called as f(ctx, x). */
typedef double (*dfo_root_fn)(void *ctx, double x);

double dfo_root_bracketed(dfo_root_fn f, void *ctx, double x0, double lo, double flo, double hi, double fhi,
                          double fnoise);

#endif
