/* The exact scheme's polynomial inputs (private; exact_poly.c; the public part, dfo_input_poly and
 * its functions, is exact.h's). The normal force max(N + N_ext(t), 0) is a polynomial on each piece
 * of a call between the zeros of N + N_ext(t) (or 0 there): a call is cut at those zeros (not an
 * event), and each piece is one polynomial for the phases. */
#ifndef DFO_EXACT_POLY_H
#define DFO_EXACT_POLY_H

#include "exact_private.h"

/* N + N_ext(t) = n[0] + n[1] q + n[2] q^2 / 2 (q = t - q->t0; u the inputs at q->t0) into n, and its
 * zeros in (ta, tb) as q (increasing, at most 2) into z; returns their count. */
int dfo_exact_normal_zeros(const dfo_model *M, const dfo_inputs *u, const dfo_input_poly *q, double ta, double tb,
                           double n[3], double z[2]);

/* The normal force of the piece that holds q: n itself where it is > 0 at q, else all 0, into qN. */
void dfo_exact_piece_normal(const double n[3], double q, double qN[3]);

#endif
