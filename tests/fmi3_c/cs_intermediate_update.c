/* FMI 3.0 host, intermediate update (as Reference-FMUs' examples/cs_intermediate_update.c): the
 * callback is called at every switch inside a step, with the outputs there readable and nothing
 * else callable, and at every internal step's end (input points, intermediateVariableSetRequested)
 * where the inputs declared intermediateUpdate="true" may be set too. Without early return the
 * outputs at the communication points are a plain instance's, bit for bit (also when the host sets
 * an input at every input point to its held value); with early return the step ends where the
 * callback requests it. */
#include "host3.h"

typedef struct {
    host_env log; /* must be first: the logger's environment */
    fmi3Instance in;
    double t[MAX_SWITCHES], x[MAX_SWITCHES];
    int n, can_return, request_at, step_status;
    long points; /* calls with intermediateVariableSetRequested (input points) */
} update_env;

static void on_update(fmi3InstanceEnvironment env, fmi3Float64 time, fmi3Boolean set_requested,
                      fmi3Boolean get_allowed, fmi3Boolean step_finished, fmi3Boolean can_return_early,
                      fmi3Boolean *early_return_requested, fmi3Float64 *early_return_time)
{
    update_env *U = (update_env *)env;
    (void)step_finished;
    if (set_requested) { /* an input point (the end of an internal step), not a switch */
        U->points++;
        *early_return_requested = fmi3False;
        *early_return_time = time;
        return;
    }
    if (U->n < MAX_SWITCHES && get_allowed) {
        U->t[U->n] = time;
        U->x[U->n] = get_real(U->in, VR_x);
    }
    U->can_return = can_return_early;
    /* no step from inside the callback */
    fmi3Boolean ev, term, early;
    fmi3Float64 last;
    U->step_status = fmi3DoStep(U->in, time, 0.1, fmi3False, &ev, &term, &early, &last);
    U->n++;
    *early_return_requested = (U->n == U->request_at) ? fmi3True : fmi3False;
    *early_return_time = time;
}

/* A host that sets F_ext at every input point (to value), and tries a parameter there. */
typedef struct {
    host_env log; /* must be first: the logger's environment */
    fmi3Instance in;
    double value;
    long points, set_ok, param_refused;
} set_env;

static void on_set(fmi3InstanceEnvironment env, fmi3Float64 time, fmi3Boolean set_requested,
                   fmi3Boolean get_allowed, fmi3Boolean step_finished, fmi3Boolean can_return_early,
                   fmi3Boolean *early_return_requested, fmi3Float64 *early_return_time)
{
    set_env *S = (set_env *)env;
    (void)get_allowed; (void)step_finished; (void)can_return_early;
    *early_return_requested = fmi3False;
    *early_return_time = time;
    if (!set_requested) return;
    S->points++;
    const fmi3ValueReference vf = VR_F_ext, vm = VR_m;
    const fmi3Float64 m = 2.0;
    if (fmi3SetFloat64(S->in, &vf, 1, &S->value, 1) == fmi3OK) S->set_ok++;
    if (fmi3SetFloat64(S->in, &vm, 1, &m, 1) == fmi3Error) S->param_refused++;
}

int main(void)
{
    tally tt = {0, 0, NULL, {0}}, *T = &tt;
    const double h = HOST_T / 1000.0;
    host_env ref;
    EXPECT(reference_switches(3, h, &ref));
    /* 1. no early return: callbacks at the switches, outputs bit for bit a plain instance's */
    update_env U;
    set_env S;
    memset(&U, 0, sizeof U);
    U.request_at = -1;
    host_env P;
    memset(&P, 0, sizeof P);
    fmi3Instance plain = host_instantiate(&P, 0, 0, 0, NULL);
    U.in = host_instantiate(&U.log, 0, 0, 0, on_update);
    EXPECT(plain && U.in && host_start(plain, 3, h) == fmi3OK && host_start(U.in, 3, h) == fmi3OK);
    fmi3Boolean ev, term, early;
    fmi3Float64 last;
    double t = 0.0;
    for (int k = 1; t < HOST_T_END; k++) {
        const double target = fmin(k * HOST_DT, HOST_T_END);
        EXPECT(fmi3DoStep(plain, t, target - t, fmi3False, &ev, &term, &early, &last) == fmi3OK);
        EXPECT(fmi3DoStep(U.in, t, target - t, fmi3False, &ev, &term, &early, &last) == fmi3OK);
        EXPECT(!early && !ev);
        const fmi3ValueReference vr[4] = {VR_x, VR_v, VR_a, VR_F_friction};
        fmi3Float64 a[4], b[4];
        fmi3GetFloat64(plain, vr, 4, a, 4);
        fmi3GetFloat64(U.in, vr, 4, b, 4);
        EXPECT(memcmp(a, b, sizeof a) == 0 && get_mode(plain) == get_mode(U.in));
        t = target;
    }
    EXPECT(U.n == ref.n && !U.can_return && U.step_status == fmi3Error);
    for (int i = 0; i < U.n && i < ref.n; i++)
        EXPECT(fabs(U.t[i] - ref.t[i]) <= 4.0 * (nextafter(ref.t[i], INFINITY) - ref.t[i]));
    EXPECT(U.points > 100); /* the internal steps' ends of the steps (h = T/1000) */
    printf("no early return: %d intermediate updates at switches, %d switches in the event log, %ld input points\n",
           U.n, ref.n, U.points);
    fmi3FreeInstance(plain);
    fmi3FreeInstance(U.in);

    /* 2. early return allowed: the steps go through the switches until the callback asks (at the
     * third), then on from there */
    memset(&U, 0, sizeof U);
    U.request_at = 3;
    U.in = host_instantiate(&U.log, 0, 1, 0, on_update);
    EXPECT(U.in && host_start(U.in, 3, h) == fmi3OK);
    t = 0.0;
    int returns = 0;
    for (int k = 1; t < HOST_T_END;) {
        const double target = fmin(k * HOST_DT, HOST_T_END);
        if (!EXPECT(fmi3DoStep(U.in, t, target - t, fmi3False, &ev, &term, &early, &last) == fmi3OK)) break;
        if (early) {
            returns++;
            EXPECT(U.n == 3 && U.can_return && last == U.t[2] && get_real(U.in, VR_x) == U.x[2]);
            EXPECT(fabs(last - ref.t[2]) <= 4.0 * (nextafter(ref.t[2], INFINITY) - ref.t[2]));
            t = last;
        } else {
            t = target;
            k++;
        }
    }
    EXPECT(returns == 1 && U.n == ref.n);
    fmi3FreeInstance(U.in);

    /* 3. inputs at the input points: F_ext set to its held value changes no bit; a parameter, or an
     * input outside an input point, is refused with the sentence naming the rule */
    memset(&S, 0, sizeof S);
    memset(&P, 0, sizeof P);
    plain = host_instantiate(&P, 0, 0, 0, NULL);
    S.in = host_instantiate(&S.log, 0, 0, 0, on_set);
    EXPECT(plain && S.in && host_start(plain, 3, h) == fmi3OK && host_start(S.in, 3, h) == fmi3OK);
    const fmi3ValueReference vf = VR_F_ext;
    const fmi3Float64 f0 = 0.25;
    EXPECT(fmi3SetFloat64(plain, &vf, 1, &f0, 1) == fmi3OK && fmi3SetFloat64(S.in, &vf, 1, &f0, 1) == fmi3OK);
    S.value = f0;
    t = 0.0;
    for (int k = 1; t < HOST_T_END; k++) {
        const double target = fmin(k * HOST_DT, HOST_T_END);
        EXPECT(fmi3DoStep(plain, t, target - t, fmi3False, &ev, &term, &early, &last) == fmi3OK);
        EXPECT(fmi3DoStep(S.in, t, target - t, fmi3False, &ev, &term, &early, &last) == fmi3OK);
        const fmi3ValueReference vr[4] = {VR_x, VR_v, VR_a, VR_F_friction};
        fmi3Float64 a[4], b[4];
        fmi3GetFloat64(plain, vr, 4, a, 4);
        fmi3GetFloat64(S.in, vr, 4, b, 4);
        EXPECT(memcmp(a, b, sizeof a) == 0);
        t = target;
    }
    EXPECT(S.points > 100 && S.set_ok == S.points && S.param_refused == S.points);
    EXPECT(strstr(S.log.last, "only the inputs declared intermediateUpdate=\"true\" may be set there") != NULL);
    printf("inputs at input points: %ld points, F_ext set at each, bits unchanged\n", S.points);
    fmi3FreeInstance(plain);
    fmi3FreeInstance(S.in);
    return tally_done(T, "cs_intermediate_update");
}
