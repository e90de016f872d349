/* The symmetric generalised eigenproblem of a structure's modes:
 *
 *     K phi = lambda M phi,     M symmetric positive definite, K symmetric,
 *
 * all n pairs, as Phi (n x n, its columns the modes) and Lambda = diag(lambda) with
 *     Phi' M Phi = I,   Phi' K Phi = Lambda,   lambda ascending.
 * The method: the Cholesky factor L of M (M = L L'), the symmetric A = L^-1 K L^-T, its Householder
 * reduction to a tridiagonal matrix and the implicit QL iteration with Wilkinson's shift on it (the
 * orthogonal Q of A = Q Lambda Q', accumulated; EISPACK's tred2 and tql2), then Phi = L^-T Q.
 * Backward stable: the residuals ||K Phi - M Phi Lambda|| and ||Phi' M Phi - I|| are of the order
 * of n eps relative to ||K||, ||M|| (times M's condition for the second).
 *
 * Deterministic: plain IEEE arithmetic (+, -, *, /, sqrt) in a fixed order, no libm function but
 * sqrt and fabs (the hypotenuse by scaling, not hypot), no fused multiply-add (dfo_fp.h): the same
 * bits on every platform. No allocation (the caller's workspace), no global state. Plain C99. */
#ifndef DFO_SYMEIG_H
#define DFO_SYMEIG_H

#include <stddef.h>

/* The workspace dfo_symeig needs for n: 2 n^2 + 2 n doubles. */
size_t dfo_symeig_work(size_t n);

/* The generalised eigenpairs of (K, M), n >= 1, both n x n row-major (their lower triangles read:
 * A[i n + j], j <= i). Out: lambda (n, ascending) and PhiT (n x n row-major: row r is the mode r,
 * phi_r, normalised phi_r' M phi_r = 1; each mode's sign such that its entry of largest magnitude,
 * the first one on ties, is positive). work: dfo_symeig_work(n) doubles. Returns 1; 0 when M is not
 * positive definite (its Cholesky factorisation fails), a value is not finite, or the QL iteration
 * does not converge in 30 n sweeps (then lambda and PhiT are not set). */
int dfo_symeig(size_t n, const double *K, const double *M, double *lambda, double *PhiT, double *work);

#endif
