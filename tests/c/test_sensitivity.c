/* Unit tests of the exact scheme's sensitivity (exact_sens.h: dfo_sens_*, the Jacobian s->J propagated by
 * dfo_exact_advance when p.sensitivity is set), driven directly (no FMI):
 * 1. the slide's state-transition matrix against exp(A t) by an independent route (Taylor series
 *    with scaling and squaring in long double), under-, critically and over-damped, k = 0;
 * 2. the Jacobian of a stick-slip run (stops, stick phases, breakaways, reversals) against central
 *    differences of the same C map, at an end time inside a slide;
 * 3. x, v, the mode and the event count bit for bit the same with the sensitivity on and off.
 * Prints the Jacobians' bits (%a): the same on every platform (the transition-matrix line's worst
 * error is not: its reference is long double, 80-bit on x86, 128-bit on aarch64). */
#include "check.h"
#include "scheme.h"
#include "osc_params.h"
#include "exact.h"
#include "exact_sens.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* exp(A t), A = [[0, 1], [-k/m, -c/m]]: Taylor series of A t / 2^s, squared s times (long double) */
static void expm_ref(double m, double k, double c, double t, double E[4])
{
    long double a[4] = {0.0L, (long double)t, -(long double)k / m * t, -(long double)c / m * t};
    const long double nrm = fabsl(a[1]) + fabsl(a[2]) + fabsl(a[3]);
    int s = 0;
    while (nrm / ldexpl(1.0L, s) > 0.125L) s++;
    for (int i = 0; i < 4; i++) a[i] = ldexpl(a[i], -s);
    long double r[4] = {1.0L, 0.0L, 0.0L, 1.0L}, term[4] = {1.0L, 0.0L, 0.0L, 1.0L};
    for (int n = 1; n < 30; n++) {
        const long double t0 = term[0], t1 = term[1], t2 = term[2], t3 = term[3];
        term[0] = (t0 * a[0] + t1 * a[2]) / n;
        term[1] = (t0 * a[1] + t1 * a[3]) / n;
        term[2] = (t2 * a[0] + t3 * a[2]) / n;
        term[3] = (t2 * a[1] + t3 * a[3]) / n;
        for (int i = 0; i < 4; i++) r[i] += term[i];
    }
    for (int j = 0; j < s; j++) {
        const long double r0 = r[0], r1 = r[1], r2 = r[2], r3 = r[3];
        r[0] = r0 * r0 + r1 * r2;
        r[1] = r0 * r1 + r1 * r3;
        r[2] = r2 * r0 + r3 * r2;
        r[3] = r2 * r1 + r3 * r3;
    }
    for (int i = 0; i < 4; i++) E[i] = (double)r[i];
}

/* the largest difference over the largest entry, with x in units of v / w (w a rate of the model) */
static double rel_diff(const double A[4], const double B[4], double w)
{
    const double sc[4] = {1.0, w, 1.0 / w, 1.0};
    double d = 0.0, n = 0.0;
    for (int i = 0; i < 4; i++) {
        d = fmax(d, fabs(A[i] - B[i]) * sc[i]);
        n = fmax(n, fabs(B[i]) * sc[i]);
    }
    return d / n;
}

static dfo_params base_params(void) { return osc_test_exact_base(); }

static void test_transition_matrix(checks *T)
{
    const double mkc[][3] = {{1.0, 1.0, 0.0}, {1.3, 2.0, 0.1}, {2.0, 50.0, 3.0}, {1.0, 4.0, 4.0},
                             {1.0, 4.0, 4.5}, {1.0, 4.0, 4.000001}, {1.0, 4.0, 3.999999}, {1.0, 0.0, 0.7},
                             {1.0, 0.0, 0.0}, {1.0, 0.0, 1e-300}};
    const double ts[] = {1e-9, 0.01, 0.7, 3.0, 11.0};
    double worst = 0.0;
    for (size_t i = 0; i < sizeof mkc / sizeof mkc[0]; i++)
        for (size_t j = 0; j < sizeof ts / sizeof ts[0]; j++) {
            dfo_params p = base_params();
            p.m = mkc[i][0];
            p.k = mkc[i][1];
            p.c = mkc[i][2];
            dfo_model M;
            dfo_model_init(&M, &p);
            double J[4] = {1.0, 0.0, 0.0, 1.0}, E[4];
            dfo_sens_slide(&M, ts[j], J);
            expm_ref(p.m, p.k, p.c, ts[j], E);
            const double w = (p.k > 0.0) ? sqrt(p.k / p.m) : 1.0;
            const double e = rel_diff(J, E, w);
            check_context(T, "m = %g, k = %g, c = %g, t = %g", p.m, p.k, p.c, ts[j]);
            CHECK(e < 1e-13);
            if (e > worst) worst = e;
        }
    printf("transition matrix against exp(A t): worst %.2e of the largest entry\n", worst);
}

static void run_to(const dfo_params *p, double x0, double v0, double t_end, dfo_state *s)
{
    dfo_params q = *p;
    q.x0 = x0;
    q.v0 = v0;
    dfo_model M;
    dfo_model_init(&M, &q);
    dfo_inputs in;
    memset(&in, 0, sizeof in);
    dfo_start(&M, &in, 0.0, s);
    s->J[0] = s->J[3] = 1.0;
    s->J[1] = s->J[2] = 0.0;
    const int n = 50;
    for (int i = 1; i <= n; i++)
        if (dfo_advance(&M, &in, s, t_end * i / n, NULL, NULL) != DFO_OK) s->X = NAN;
}

static void test_against_differences(checks *T)
{
    const double chis[] = {0.7, 1.0, 0.3};
    const double T_exc = 2.0 * DFO_PI / 0.5;
    const double ends[] = {3.3, 5.7};
    double worst = 0.0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 2; j++) {
            dfo_params p = base_params();
            p.chi = chis[i];
            p.sensitivity = 1;
            const double t_end = ends[j] * T_exc, e = 1e-6;
            dfo_state s, a, b;
            run_to(&p, p.x0, p.v0, t_end, &s);
            check_context(T, "chi = %g, t = %g T", p.chi, ends[j]);
            CHECK(s.mode != 0 && s.steps > 6); /* inside a slide, after stops, sticks and breakaways */
            double F[4];
            run_to(&p, p.x0 + e, p.v0, t_end, &a);
            run_to(&p, p.x0 - e, p.v0, t_end, &b);
            F[0] = (a.X - b.X) / (2 * e);
            F[2] = (a.V - b.V) / (2 * e);
            run_to(&p, p.x0, p.v0 + e, t_end, &a);
            run_to(&p, p.x0, p.v0 - e, t_end, &b);
            F[1] = (a.X - b.X) / (2 * e);
            F[3] = (a.V - b.V) / (2 * e);
            /* the Jacobian's bits (the same on every platform: the FMU's own elementary functions) */
            printf("J chi %g t %g T: %a %a %a %a\n", p.chi, ends[j], s.J[0], s.J[1], s.J[2], s.J[3]);
            const double r = rel_diff(s.J, F, 1.0);
            CHECK(r < 1e-6);
            if (r > worst) worst = r;
            /* off: the same motion, bit for bit */
            dfo_params off = p;
            off.sensitivity = 0;
            dfo_state o;
            run_to(&off, p.x0, p.v0, t_end, &o);
            CHECK_SAME(s.X, o.X);
            CHECK_SAME(s.V, o.V);
            CHECK_INT(s.mode, o.mode);
            CHECK_INT(s.steps, o.steps);
        }
    printf("stick-slip Jacobian against central differences: worst %.2e of the largest entry\n", worst);
}

int main(void)
{
    checks T0 = {0, 0, NULL, {0}};
    checks *T = &T0;
    test_transition_matrix(T);
    test_against_differences(T);
    return checks_done(T, "test_sensitivity");
}
