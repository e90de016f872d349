/* FMI 3.0 host, early return (as Reference-FMUs' examples/cs_early_return.c): the host steps on its
 * grid k dt; with earlyReturnAllowed, fmi3DoStep returns at every stick/slip switch, the mode has
 * changed there, lastSuccessfulTime is the switch time reported by the FMU's event log of a plain
 * run (same_switch_time), and the next step starts there and goes on to the interrupted grid point.
 * For every scheme of the Scheme enumeration. */
#include "host3.h"

static void run_scheme(tally *T, int scheme)
{
    const double h = HOST_T / 1000.0;
    host_env ref, E;
    EXPECT(reference_switches(scheme, h, &ref));
    EXPECT(ref.n >= 10);
    memset(&E, 0, sizeof E);
    fmi3Instance in = host_instantiate(&E, 0, 1, 0, NULL);
    if (!EXPECT(in != NULL) || !EXPECT(host_start(in, scheme, h) == fmi3OK)) return;
    fmi3Boolean ev, term, early;
    fmi3Float64 last;
    double t = 0.0;
    int mode = get_mode(in), n = 0, k = 1;
    while (t < HOST_T_END) {
        const double target = fmin(k * HOST_DT, HOST_T_END);
        if (!EXPECT(fmi3DoStep(in, t, target - t, fmi3False, &ev, &term, &early, &last) == fmi3OK)) break;
        EXPECT(!ev && !term);
        const int m = get_mode(in);
        if (early) {
            EXPECT(last > t && last < target);
            EXPECT(m != mode); /* an early return is at a switch */
            if (EXPECT(n < ref.n)) {
                EXPECT(same_switch_time(last, ref.t[n]));
                EXPECT(ref.from[n] == mode && ref.to[n] == m);
            }
            n++;
            /* the step must start where it returned, not at the old point */
            if (t > 0.0) {
                const int errors = E.errors;
                EXPECT(fmi3DoStep(in, t, target - t, fmi3False, &ev, &term, &early, &last) == fmi3Error);
                EXPECT(E.errors == errors + 1 && strstr(E.last, "does not equal the FMU's time") != NULL);
            }
            t = last;
        } else {
            EXPECT(last == t + (target - t));
            if (m != mode) { /* a switch exactly on the communication point */
                if (EXPECT(n < ref.n)) EXPECT(same_switch_time(last, ref.t[n]));
                n++;
            }
            t = target;
            k++;
        }
        mode = m;
    }
    EXPECT(n == ref.n);
    printf("scheme %d: %d switches, %d in the reference run\n", scheme, n, ref.n);
    EXPECT(fmi3Terminate(in) == fmi3OK);
    fmi3FreeInstance(in);
}

int main(void)
{
    tally tt = {0, 0, NULL, {0}}, *T = &tt;
    int schemes[16];
    const int ns = host_schemes(schemes, 16);
    EXPECT(ns >= 3);
    for (int i = 0; i < ns; i++) run_scheme(T, schemes[i]);
    return tally_done(T, "cs_early_return");
}
