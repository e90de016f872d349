/* The exact scheme's sensitivity: the Jacobian of the state propagated in closed form. See
 * exact_sens.h and method.md section 11. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "exact_sens.h"
#include "dmath.h"

#include <math.h>

void dfo_sens_slide(const dfo_model *M, double dt, double J[4])
{
    /* the FMU's own elementary functions (dmath.h): the same bits on every platform */
    const double m = M->p.m, k = M->p.k, c = M->p.c;
    double p11, p12, p21, p22;
    if (!(dt > 0.0)) return;
    if (k == 0.0) { /* x'' = -b x' + forcing: Phi = [[1, dt phi1(-b dt)], [0, e^{-b dt}]] */
        const double z = -(c / m) * dt;
        p11 = 1.0;
        p12 = (z == 0.0) ? dt : dt * (dfo_expm1(z) / z);
        p21 = 0.0;
        p22 = dfo_exp(z);
    } else {
        const double w0 = sqrt(k / m), zeta = c / (2.0 * sqrt(k * m)), tau = w0 * dt;
        double e, cs, sq; /* Phi in tau: e (cs + zeta sq), e sq / w0; -w0 e sq, e (cs - zeta sq) */
        if (zeta < 1.0) {
            const double wd = sqrt((1.0 - zeta) * (1.0 + zeta));
            double sn;
            e = dfo_exp(-zeta * tau);
            dfo_sincos(wd * tau, &sn, &cs);
            sq = sn / wd; /* sin(wd tau) / wd */
        } else if (zeta == 1.0) {
            e = dfo_exp(-tau);
            cs = 1.0;
            sq = tau;
        } else { /* over-damped: e^{-zeta tau} cosh, sinh / wh from the two modes r2 < r1 < 0 */
            const double wh = sqrt((zeta - 1.0) * (zeta + 1.0)), r1 = -1.0 / (zeta + wh), r2 = -(zeta + wh);
            const double e1 = dfo_exp(r1 * tau), e2 = dfo_exp(r2 * tau);
            e = 1.0;
            cs = 0.5 * (e1 + e2); /* e^{-zeta tau} cosh(wh tau) */
            /* e^{-zeta tau} sinh(wh tau) / wh, without the cancellation of e1 - e2 near critical damping */
            sq = (2.0 * wh * tau < 1.0) ? e2 * dfo_expm1(2.0 * wh * tau) / (2.0 * wh) : (e1 - e2) / (2.0 * wh);
        }
        p11 = e * (cs + zeta * sq);
        p12 = e * sq / w0;
        p21 = -w0 * e * sq;
        p22 = e * (cs - zeta * sq);
    }
    const double a = J[0], b = J[1], cc = J[2], d = J[3];
    J[0] = p11 * a + p12 * cc;
    J[1] = p11 * b + p12 * d;
    J[2] = p21 * a + p22 * cc;
    J[3] = p21 * b + p22 * d;
}

void dfo_sens_stick(double J[4]) { J[2] = J[3] = 0.0; }

void dfo_sens_reversal(double J[4], double ratio)
{
    J[2] *= ratio;
    J[3] *= ratio;
}

void dfo_sens_breakaway(double J[4], double coef)
{
    J[2] = coef * J[0];
    J[3] = coef * J[1];
}
