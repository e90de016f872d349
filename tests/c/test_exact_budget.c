/* The exact scheme's work bound with a spring (exact_spring.c): the file includes it with a small event
 * budget, DFO_EXACT_MAX_EVENTS = 20000, so that a runaway communication step is reached in
 * milliseconds. A frictionless oscillator reverses twice per natural period: a communication step of
 * 10^5 periods fails with DFO_ERR_EVENTS at a finite state; the same motion in 20 steps succeeds and
 * ends where one unbounded step would (a chained run at 1/20 of the work per call). */
#define DFO_EXACT_MAX_EVENTS 20000LL
#include "check.h"
#include "scheme.h"
#include "osc_params.h"
#include "exact_spring.c"

#include <stdio.h>
#include <string.h>

int main(void)
{
    checks T0 = {0, 0, NULL, {0}};
    checks *T = &T0;
    dfo_params p = osc_test_params(DFO_SCHEME_EXACT, 1.0, 1.0, 0.0, 1.0, 0.3, 0.0, 0.0, 0.0);
    p.v0 = 1.0;
    dfo_model M;
    dfo_model_init(&M, &p);
    dfo_inputs in;
    memset(&in, 0, sizeof in);
    dfo_state s, s2;
    dfo_start(&M, &in, 0.0, &s);
    s2 = s;
    const double t_end = 1e5 * 2.0 * DFO_PI;
    check_context(T, "work bound, k > 0");
    CHECK_INT(DFO_ERR_EVENTS, dfo_exact_advance(&M, &in, &s, t_end, NULL, NULL));
    CHECK(s.steps == DFO_EXACT_MAX_EVENTS);
    CHECK(isfinite(s.X) && isfinite(s.V) && s.t > 0.0 && s.t < t_end);
    for (int k = 1; k <= 20; k++)
        if (!CHECK_INT(DFO_OK, dfo_exact_advance(&M, &in, &s2, t_end * k / 20.0, NULL, NULL))) break;
    CHECK(s2.steps > 5 * DFO_EXACT_MAX_EVENTS);
    printf("work bound (k > 0): %lld events refused at t = %.6g of %.6g; in 20 steps: %lld events\n", s.steps, s.t,
           t_end, s2.steps);
    printf("%s\n", dfo_status_text(DFO_ERR_EVENTS));
    return checks_done(T, "test_exact_budget");
}
