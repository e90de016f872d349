/* Unit tests of the exact scheme without a spring (fmu_src/models/oscillator/exact_free.[ch]) and of the exact
 * schemes' work bound, driven directly (no FMI). The file includes exact_free.c (to reach its closed
 * form) with a small event budget, DFO_EXACT_MAX_EVENTS = 20000, so that a runaway communication
 * step is reached in milliseconds; tests/c/test_exact_budget.c does the same for exact_spring.c (k > 0).
 *
 * 1. the closed form: the Taylor series and the phi1 form agree where they meet (|p tau| = 1), the
 *    limits c -> 0 and omega tau -> 0 are continuous, the equation of motion holds (central
 *    differences of x and v);
 * 2. the rules at every event of a long stick-slip run: stops at zero velocity, stick inside the
 *    limit, slides from rest along the static force beyond it; chi >= 1 (zero-acceleration
 *    breakaways) makes progress;
 * 3. the work bound: a frictionless free mass under a fast excitation reverses twice per period: a
 *    communication step of 10^5 periods fails with DFO_ERR_EVENTS (and its sentence) at a finite
 *    state; the same work in shorter steps succeeds. */
#define DFO_EXACT_MAX_EVENTS 20000LL
#include "check.h"
#include "scheme.h"
#include "osc_params.h"
#include "exact_free.c"

#include <stdio.h>
#include <string.h>

static dfo_params free_params(double c, double chi)
{
    return osc_test_params(DFO_SCHEME_EXACT, 1.0, 0.0, c, 1.0, 1.0, 1.0, 0.4, chi);
}

static void test_closed_form(checks *T)
{
    const double cs[] = {0.0, 1e-300, 1e-12, 0.3, 1.0, 40.0};
    const double ws[] = {1.0, 1e-6, 7.0};
    double worst_join = 0.0, worst_eom = 0.0;
    for (int i = 0; i < 6; i++)
        for (int j = 0; j < 3; j++) {
            dfo_params p = free_params(cs[i], 0.7);
            p.omega = ws[j];
            dfo_model M;
            dfo_model_init(&M, &p);
            dfo_inputs in;
            memset(&in, 0, sizeof in);
            fr_ctx C;
            ctx_init(&C, &M, &in);
            fr_phase P;
            phase_init(&C, &P, 3.7, 0.25, -0.6, 1);
            check_context(T, "closed form, c = %g, omega = %g", cs[i], ws[j]);
            /* where the series meets the phi1 form: |p tau| = 1 */
            const double tj = 1.0 / sqrt(C.b * C.b + C.w * C.w);
            fr_val a, b;
            eval(&C, &P, nextafter(tj, 0.0), &a);
            eval(&C, &P, nextafter(tj, INFINITY), &b);
            const double jx = fabs(a.x - b.x) / (fabs(a.x) + 1.0), jv = fabs(a.v - b.v) / (fabs(a.v) + 1.0);
            if (jx > worst_join) worst_join = jx;
            if (jv > worst_join) worst_join = jv;
            CHECK(jx <= 1e-14 && jv <= 1e-14);
            /* the equation of motion: x' = v, v' = a by central differences (fourth order) */
            const double taus[] = {0.01, 0.7, 3.0, 25.0};
            for (int k = 0; k < 4; k++) {
                const double u = taus[k] * tj, d = 1e-3 * (u < tj ? u : tj);
                fr_val m2, m1, c0, p1, p2;
                eval(&C, &P, u - 2 * d, &m2);
                eval(&C, &P, u - d, &m1);
                eval(&C, &P, u, &c0);
                eval(&C, &P, u + d, &p1);
                eval(&C, &P, u + 2 * d, &p2);
                const double dx = (m2.x - 8 * m1.x + 8 * p1.x - p2.x) / (12 * d);
                const double dv = (m2.v - 8 * m1.v + 8 * p1.v - p2.v) / (12 * d);
                const double scale = fabs(c0.vmag) + fabs(c0.a) + 1.0;
                const double e = fmax(fabs(dx - c0.v), fabs(dv - c0.a)) / scale;
                if (e > worst_eom) worst_eom = e;
                CHECK(e <= 1e-8);
            }
        }
    printf("closed form: jump at |p tau| = 1 %.2e, equation of motion residual %.2e\n", worst_join, worst_eom);
}

typedef struct {
    const dfo_model *M;
    checks *T;
    int n;
} rule_ctx;

static void on_event(void *ctx, double t, double x, int from, int to)
{
    rule_ctx *R = (rule_ctx *)ctx;
    (void)x;
    R->n++;
    dfo_loads L;
    dfo_inputs in;
    memset(&in, 0, sizeof in);
    dfo_loads_init(&L, R->M, &in);
    const double S = dfo_excitation(R->M, t);
    checks *T = R->T;
    if (from != 0 && to == 0) CHECK(fabs(S) <= L.Fb * (1.0 + 1e-12)); /* stick inside the limit */
    if (to != 0 && from != to) CHECK(to * S >= L.Fb * (1.0 - 1e-9) || from != 0); /* breakaway along S */
    if (from != 0 && to == -from) CHECK(to * S >= L.Fb * (1.0 - 1e-9)); /* reversal beyond the limit */
}

static void test_rules(checks *T)
{
    const double chis[] = {0.0, 0.7, 1.0, 2.0};
    const double cs[] = {0.0, 0.2};
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 2; j++) {
            dfo_params p = free_params(cs[j], chis[i]);
            if (chis[i] > 1.0) p.mu_s = 0.2;
            dfo_model M;
            dfo_model_init(&M, &p);
            dfo_inputs in;
            memset(&in, 0, sizeof in);
            dfo_state s;
            dfo_start(&M, &in, 0.0, &s);
            rule_ctx R = {&M, T, 0};
            check_context(T, "rules, chi = %g, c = %g", chis[i], cs[j]);
            double t = 0.0;
            for (int k = 0; k < 50; k++) {
                t += 2.0 * DFO_PI * 0.37;
                if (!CHECK_INT(DFO_OK, dfo_exact_free_advance(&M, &in, &s, t, on_event, &R))) break;
                CHECK(s.mode != 0 || s.V == 0.0);
                CHECK(s.mode == 0 || s.mode * s.V >= 0.0);
            }
            CHECK(R.n >= 20);
        }
}

static void test_work_bound(checks *T)
{
    dfo_params p = free_params(0.0, 0.7);
    p.N = 0.0;
    p.omega = 50.0;
    dfo_model M;
    dfo_model_init(&M, &p);
    dfo_inputs in;
    memset(&in, 0, sizeof in);
    dfo_state s, s2;
    dfo_start(&M, &in, 0.0, &s);
    s2 = s;
    const double t_end = 1e5 * 2.0 * DFO_PI / p.omega; /* 2e5 reversals, ten times the budget */
    check_context(T, "work bound");
    CHECK_INT(DFO_ERR_EVENTS, dfo_exact_free_advance(&M, &in, &s, t_end, NULL, NULL));
    CHECK(s.steps == DFO_EXACT_MAX_EVENTS);
    CHECK(isfinite(s.X) && isfinite(s.V) && s.t > 0.0 && s.t < t_end);
    CHECK(strstr(dfo_status_text(DFO_ERR_EVENTS), "events") != NULL);
    /* the same work in shorter steps is fine */
    for (int k = 1; k <= 20; k++) {
        if (!CHECK_INT(DFO_OK, dfo_exact_free_advance(&M, &in, &s2, t_end * k / 20.0, NULL, NULL))) break;
    }
    CHECK(s2.steps > 10 * DFO_EXACT_MAX_EVENTS / 2);
    printf("work bound: %lld events refused at t = %.6g of %.6g; in 20 steps: %lld events\n", s.steps, s.t, t_end,
           s2.steps);
}

int main(void)
{
    checks T0 = {0, 0, NULL, {0}};
    checks *T = &T0;
    test_closed_form(T);
    test_rules(T);
    test_work_bound(T);
    return checks_done(T, "test_exact_free");
}
