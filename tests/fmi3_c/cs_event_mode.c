/* FMI 3.0 host, event mode (as Reference-FMUs' examples/cs_event_mode.c): instantiated with
 * eventModeUsed and earlyReturnAllowed, the FMU starts in event mode; at every switch fmi3DoStep
 * returns early with eventHandlingNeeded; the outputs are then the left limits (the old mode, its
 * friction force and acceleration), after fmi3UpdateDiscreteStates the right limits; x and v are
 * continuous; fmi3UpdateDiscreteStates reports nothing else to do. Located scheme, default model. */
#include "host3.h"

int main(void)
{
    tally tt = {0, 0, NULL, {0}}, *T = &tt;
    const double h = HOST_T / 1000.0, mu_s = START_mu_s, muk_N = START_chi * START_mu_s * START_N;
    const double Fb = (mu_s > START_chi * mu_s ? mu_s : START_chi * mu_s) * START_N;
    host_env ref, E;
    EXPECT(reference_switches(3, h, &ref));
    memset(&E, 0, sizeof E);
    fmi3Instance in = host_instantiate(&E, 1, 1, 0, NULL);
    if (!EXPECT(in != NULL) || !EXPECT(host_start(in, 3, h) == fmi3OK)) return tally_done(T, "cs_event_mode");
    fmi3Boolean ev, term, early, need, terminate, nominals, values, next_defined;
    fmi3Float64 last, next_time;
    /* the FMU starts in event mode: no step before fmi3EnterStepMode */
    EXPECT(fmi3DoStep(in, 0.0, HOST_DT, fmi3False, &ev, &term, &early, &last) == fmi3Error);
    EXPECT(fmi3UpdateDiscreteStates(in, &need, &terminate, &nominals, &values, &next_defined, &next_time) == fmi3OK);
    EXPECT(!need && !terminate && !nominals && !values && !next_defined);
    EXPECT(fmi3EnterStepMode(in) == fmi3OK);
    double t = 0.0;
    int k = 1, n = 0, mode = get_mode(in), kinds[3] = {0, 0, 0};
    while (t < HOST_T_END) {
        const double target = fmin(k * HOST_DT, HOST_T_END);
        if (!EXPECT(fmi3DoStep(in, t, target - t, fmi3False, &ev, &term, &early, &last) == fmi3OK)) break;
        t = early ? last : target;
        if (!early) k++;
        if (!ev) {
            EXPECT(get_mode(in) == mode); /* located switches are inside steps */
            continue;
        }
        EXPECT(early);
        const double xl = get_real(in, VR_x), vl = get_real(in, VR_v), Fl = get_real(in, VR_F_friction),
                     al = get_real(in, VR_a);
        const int ml = get_mode(in);
        EXPECT(ml == mode);
        EXPECT(fmi3EnterEventMode(in) == fmi3OK);
        EXPECT(fmi3UpdateDiscreteStates(in, &need, &terminate, &nominals, &values, &next_defined, &next_time) ==
               fmi3OK);
        EXPECT(!need && !terminate && !nominals && !values && !next_defined);
        const double xr = get_real(in, VR_x), vr = get_real(in, VR_v), Fr = get_real(in, VR_F_friction),
                     ar = get_real(in, VR_a);
        const int mr = get_mode(in);
        EXPECT(mr != ml && xr == xl && vr == vl && vl == 0.0);
        if (ml != 0) {
            EXPECT(Fl == -ml * muk_N);
        } else { /* breakaway: the static force at the limit, at rest; then the kinetic force */
            EXPECT(fabs(fabs(Fl) - Fb) <= 1e-12 && Fl == -mr * fabs(Fl));
            EXPECT(al == 0.0);
        }
        if (mr != 0) {
            EXPECT(Fr == -mr * muk_N);
            EXPECT(ar * mr >= 0.0); /* the slide starts in its own direction */
        } else {
            EXPECT(ar == 0.0 && fabs(Fr) <= Fb);
        }
        kinds[ml == 0 ? 0 : mr == 0 ? 1 : 2]++;
        if (EXPECT(n < ref.n)) EXPECT(same_switch_time(t, ref.t[n]));
        n++;
        mode = mr;
        EXPECT(fmi3EnterStepMode(in) == fmi3OK);
    }
    EXPECT(n == ref.n && kinds[0] > 0 && kinds[1] > 0 && kinds[2] > 0);
    printf("%d events: %d breakaways, %d stops, %d reversals\n", n, kinds[0], kinds[1], kinds[2]);
    EXPECT(fmi3Terminate(in) == fmi3OK);
    fmi3FreeInstance(in);
    return tally_done(T, "cs_event_mode");
}
