/* The oscillator's FMI-independent instance core (fmu_src/models/oscillator/osc_instance.c, the
 * model API of fmu_src/core/instance.h) driven directly, without any FMI
 * header, as a second glue (FMI 3.0) will drive it:
 *
 * 1. a host made of plain malloc/free and a logger: start values from the generated table,
 *    get/set, initialisation, the host's time after doStep exactly tc + dt, also when the
 *    stepper's own time stands a rounding away from it;
 * 2. the early-return hook (DFO_STEP_STOP_AT_SWITCH): doStep stops at the end of the internal step
 *    holding the first stick/slip switch, at the same switch (time and position, bit for bit) as
 *    an ordinary run reports, and the run continues from there to the requested end;
 * 3. FMU states through the core: copy, serialise, deserialise, continue bit for bit. */
#include "fmu_state.h"
#include "instance_common.h"
#include "osc_instance.h"
#include "../check.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    int n_events, n_errors;
    double first_switch_t, first_switch_x;
    char last[512];
} host_log;

static void *h_alloc(void *ctx, size_t n, size_t size)
{
    (void)ctx;
    return calloc(n, size);
}

static void h_free(void *ctx, void *p)
{
    (void)ctx;
    free(p);
}

static void h_log(void *ctx, dfo_inst_status status, const char *category, const char *message)
{
    host_log *L = (host_log *)ctx;
    snprintf(L->last, sizeof L->last, "%s", message);
    if (status == DFO_INST_ERROR) L->n_errors++;
    double t, x;
    const char *at = strstr(message, " at x = ");
    if (!strcmp(category, "logEvents") && sscanf(message, "t = %lf:", &t) == 1 && at &&
        sscanf(at, " at x = %lf", &x) == 1) {
        if (L->n_events == 0) {
            L->first_switch_t = t;
            L->first_switch_x = x;
        }
        L->n_events++;
    }
}

#define OSC(lc) ((osc_instance *)(lc))

static dfo_lifecycle *start(checks *T, host_log *L)
{
    const dfo_host host = {L, h_alloc, h_free, h_log};
    memset(L, 0, sizeof *L);
    dfo_lifecycle *in = dfo_inst_new(&host, "core", 1);
    /* stick-slip from rest (lambda 0.5, mu_s sigma 0.6, chi 0.7) */
    const unsigned int vr[5] = {VR_k, VR_omega, VR_mu_s, VR_chi, VR_h};
    const double val[5] = {100.0, 5.0, 0.6, 0.7, 1e-3};
    EXPECT(dfo_inst_setup(in, "setup", 0.0, 0, 0.0) == DFO_INST_OK);
    EXPECT(dfo_inst_set_real(in, "set", vr, 5, val) == DFO_INST_OK);
    EXPECT(dfo_inst_enter_init(in) == DFO_INST_OK);
    EXPECT(dfo_inst_exit_init(in, "exit") == DFO_INST_OK);
    return in;
}

static void test_table_and_time(checks *T)
{
    host_log L;
    const dfo_host host = {&L, h_alloc, h_free, h_log};
    memset(&L, 0, sizeof L);
    dfo_lifecycle *in = dfo_inst_new(&host, "core", 0);
    /* start values come from the table (the XML's start attributes) */
    for (int i = 0; i < DFO_NUM_VARS; i++) {
        const dfo_var_info *var = &DFO_VARS[i];
        if (var->home == DFO_COMPUTED) continue;
        if (var->type == DFO_REAL) {
            double x = NAN;
            EXPECT(dfo_inst_get_real(in, "get", &var->vr, 1, &x) == DFO_INST_OK && x == var->start);
        } else {
            int i = -1;
            const dfo_inst_status st = var->type == DFO_INTEGER ? dfo_inst_get_int(in, "get", &var->vr, 1, &i)
                                                                : dfo_inst_get_bool(in, "get", &var->vr, 1, &i);
            EXPECT(st == DFO_INST_OK && i == (int)var->start);
        }
    }
    EXPECT(OSC(in)->v.p.m == START_m && OSC(in)->v.p.scheme == START_scheme && OSC(in)->v.p.observe == START_observe);
    /* a rejected value names variable, value reference, value and range */
    const unsigned int vm = VR_m;
    const double bad = -1.0;
    EXPECT(dfo_inst_set_real(in, "set", &vm, 1, &bad) == DFO_INST_ERROR);
    EXPECT(strstr(L.last, "invalid value -1 for variable m (value reference 1); valid range: in [1e-100, 1e+100]") != NULL);
    dfo_inst_delete(in);
    in = start(T, &L);
    double t = 0.0, reached = -1.0;
    for (int k = 0; k < 50; k++) {
        const double dt = 0.0123 + 1e-4 * k;
        EXPECT(dfo_inst_do_step(in, "doStep", t, dt, 0, &reached) == DFO_INST_OK);
        EXPECT(reached == t + dt && dfo_inst_time(in) == t + dt);
        t += dt;
    }
    /* the time contract with the stepper: after a good step its own time may be a grid point within
     * a snap tolerance of the target; the host's time stays the target, and is what the next
     * communication point is checked against and what is reported */
    const double t_phys = OSC(in)->v.s.t;
    OSC(in)->v.s.t = nextafter(t_phys, 0.0);
    EXPECT(dfo_inst_time(in) == t);
    EXPECT(dfo_inst_do_step(in, "doStep", t, 0.1, 0, &reached) == DFO_INST_OK && reached == t + 0.1);
    EXPECT(dfo_inst_time(in) == t + 0.1);
    dfo_inst_delete(in);
}

static void test_early_return(checks *T)
{
    host_log La, Lb;
    dfo_lifecycle *a = start(T, &La), *b = start(T, &Lb);
    /* ordinary: one step to 5 s, every switch reported */
    EXPECT(dfo_inst_do_step(a, "doStep", 0.0, 5.0, 0, NULL) == DFO_INST_OK);
    EXPECT(La.n_events > 2);
    /* early return: stops right after the first switch */
    double reached = -1.0;
    EXPECT(dfo_inst_do_step(b, "doStep", 0.0, 5.0, DFO_STEP_STOP_AT_SWITCH, &reached) == DFO_INST_OK);
    printf("early return: first switch at t = %.17g, returned at t = %.17g (ordinary run: %.17g)\n",
           Lb.first_switch_t, reached, La.first_switch_t);
    EXPECT(Lb.n_events == 1);
    EXPECT(Lb.first_switch_t == La.first_switch_t && Lb.first_switch_x == La.first_switch_x);
    EXPECT(reached >= Lb.first_switch_t && reached - Lb.first_switch_t <= 1e-3 * (1.0 + 1e-9));
    EXPECT(reached < 5.0 && dfo_inst_time(b) == reached && OSC(b)->v.s.t == reached);
    /* and on to the end, ordinarily: the same switches as the ordinary run, the same end */
    EXPECT(dfo_inst_do_step(b, "doStep", reached, 5.0 - reached, 0, NULL) == DFO_INST_OK);
    EXPECT(dfo_inst_time(b) == 5.0);
    EXPECT(Lb.n_events == La.n_events);
    EXPECT(fabs(OSC(b)->v.s.X - OSC(a)->v.s.X) <= 1e-12 * (fabs(OSC(a)->v.s.X) + 1e-3));
    dfo_inst_delete(a);
    dfo_inst_delete(b);
}

static void test_states(checks *T)
{
    host_log L;
    dfo_lifecycle *a = start(T, &L);
    EXPECT(dfo_inst_do_step(a, "doStep", 0.0, 1.0, 0, NULL) == DFO_INST_OK);
    void *st = NULL, *st2 = NULL;
    EXPECT(dfo_inst_get_state(a, "get", &st) == DFO_INST_OK && st != NULL);
    const size_t n = dfo_inst_state_size(a, st);
    unsigned char *buf = (unsigned char *)malloc(n);
    EXPECT(dfo_inst_serialize(a, "ser", st, buf, n) == DFO_INST_OK);
    EXPECT(dfo_inst_deserialize(a, "deser", buf, n, &st2) == DFO_INST_OK && st2 != NULL);
    EXPECT(dfo_inst_do_step(a, "doStep", 1.0, 2.0, 0, NULL) == DFO_INST_OK);
    const double x1 = OSC(a)->v.s.X;
    EXPECT(dfo_inst_set_state(a, "set", st2) == DFO_INST_OK && dfo_inst_time(a) == 1.0);
    EXPECT(dfo_inst_do_step(a, "doStep", 1.0, 2.0, 0, NULL) == DFO_INST_OK);
    EXPECT(OSC(a)->v.s.X == x1);
    /* a state whose host time strays from the stepper's is refused, even with a valid checksum */
    double t_forged;
    /* (the run ends the body, the host's time first; little-endian as the format writes it) */
    unsigned char *t_at = buf + n - DFO_STATE_RUN_BYTES;
    uint64_t bits = 0;
    for (int k = 0; k < 8; k++) bits |= (uint64_t)t_at[k] << (8 * k);
    memcpy(&t_forged, &bits, sizeof t_forged);
    t_forged += 0.5;
    memcpy(&bits, &t_forged, sizeof bits);
    for (int k = 0; k < 8; k++) t_at[k] = (unsigned char)(bits >> (8 * k));
    uint64_t h = 1469598103934665603ULL;
    for (size_t i = 24; i < n; i++) {
        h ^= buf[i];
        h *= 1099511628211ULL;
    }
    for (int k = 0; k < 8; k++) buf[16 + k] = (unsigned char)(h >> (8 * k));
    EXPECT(dfo_inst_deserialize(a, "deser", buf, n, &st2) == DFO_INST_ERROR);
    EXPECT(strstr(L.last, "the host's time does not match the state's") != NULL);
    EXPECT(dfo_inst_free_state(a, "free", &st) == DFO_INST_OK && st == NULL);
    EXPECT(dfo_inst_free_state(a, "free", &st2) == DFO_INST_OK && st2 == NULL);
    free(buf);
    dfo_inst_delete(a);
}

int main(void)
{
    checks t = {0, 0, NULL, {0}}, *T = &t;
    test_table_and_time(T);
    test_early_return(T);
    test_states(T);
    return checks_done(T, "test_instance_core");
}
