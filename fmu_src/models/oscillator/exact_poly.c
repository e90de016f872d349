/* The exact scheme's polynomial inputs: the inputs at a time, and the pieces of a call between the
 * zeros of the normal force. See exact.h (the public part) and exact_poly.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "exact_poly.h"

#include <math.h>
#include <stddef.h>

int dfo_input_poly_active(const dfo_input_poly *q)
{
    return q != NULL && (q->F[0] != 0.0 || q->F[1] != 0.0 || q->N[0] != 0.0 || q->N[1] != 0.0);
}

void dfo_input_poly_at(const dfo_inputs *u, const dfo_input_poly *q, double t, dfo_inputs *out)
{
    *out = *u;
    if (q == NULL) return;
    const double d = t - q->t0;
    const double F0 = u->F_ext_set ? u->F_ext : 0.0, N0 = u->N_ext_set ? u->N_ext : 0.0;
    if (q->F[0] != 0.0 || q->F[1] != 0.0) {
        out->F_ext = F0 + d * (q->F[0] + 0.5 * d * q->F[1]);
        out->F_ext_set = 1;
    }
    if (q->N[0] != 0.0 || q->N[1] != 0.0) {
        out->N_ext = N0 + d * (q->N[0] + 0.5 * d * q->N[1]);
        out->N_ext_set = 1;
    }
}

const char *dfo_exact_poly_unsupported(const dfo_model *M)
{
    (void)M; /* every model: k > 0 (exact_spring.c) and k = 0 (exact_free.c) */
    return NULL;
}

/* The zeros of n0 + n1 q + n2 q^2 / 2 in (lo, hi), increasing, in r (at most 2); their count. */
static int poly_zeros(double n0, double n1, double n2, double lo, double hi, double r[2])
{
    double z[2];
    int nz = 0, k = 0;
    if (n2 == 0.0) {
        if (n1 != 0.0) z[nz++] = -n0 / n1;
    } else {
        const double a = 0.5 * n2, disc = n1 * n1 - 4.0 * a * n0;
        if (disc > 0.0) {
            const double qq = -0.5 * (n1 + ((n1 >= 0.0) ? 1.0 : -1.0) * sqrt(disc));
            z[nz++] = qq / a;
            if (qq != 0.0) z[nz++] = n0 / qq;
        }
    }
    if (nz == 2 && z[1] < z[0]) {
        const double w = z[0];
        z[0] = z[1];
        z[1] = w;
    }
    for (int i = 0; i < nz; i++)
        if (z[i] > lo && z[i] < hi && (k == 0 || z[i] > r[k - 1])) r[k++] = z[i];
    return k;
}

int dfo_exact_normal_zeros(const dfo_model *M, const dfo_inputs *u, const dfo_input_poly *q, double ta, double tb,
                           double n[3], double z[2])
{
    n[0] = M->p.N + (u->N_ext_set ? u->N_ext : 0.0);
    n[1] = q->N[0];
    n[2] = q->N[1];
    return poly_zeros(n[0], n[1], n[2], ta - q->t0, tb - q->t0, z);
}

void dfo_exact_piece_normal(const double n[3], double q, double qN[3])
{
    const int pos = n[0] + q * (n[1] + 0.5 * q * n[2]) > 0.0;
    qN[0] = pos ? n[0] : 0.0;
    qN[1] = pos ? n[1] : 0.0;
    qN[2] = pos ? n[2] : 0.0;
}
