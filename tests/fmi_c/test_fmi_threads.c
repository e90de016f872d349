/* 32 instances of the FMU stepped in 32 parallel threads (pthreads), each with its own parameters,
 * give bit for bit the numbers of the same 32 runs done one after the other. Catches any shared
 * mutable state in the FMU (statics, caches, non-reentrant library calls). */
#include "harness.h"

#include <math.h>

#define N_THREADS 32
#define N_STEPS 400
#define N_OUT 6

typedef struct {
    int k;
    double out[N_STEPS][N_OUT];
    int mode[N_STEPS];
    fmi2Status status;
    log_sink sink;
} job;

static void *simulate(void *arg)
{
    job *J = (job *)arg;
    const int k = J->k;
    fmi2CallbackFunctions cb = callbacks_for(&J->sink);
    char name[32];
    snprintf(name, sizeof name, "thread%d", k);
    fmi2Component c = new_instance(name, &cb);
    J->status = fmi2Error;
    if (!c) return NULL;
    const fmi2ValueReference vr[4] = {VR_omega, VR_x0, VR_chi, VR_c};
    const double val[4] = {3.0 + 0.25 * k, 0.001 * (k % 7), 0.2 + 0.1 * (k % 10), 0.02 * (k % 3)};
    const fmi2ValueReference vs = VR_scheme, vo = VR_observe, vout[N_OUT] = {VR_x, VR_v, VR_a, VR_F_friction,
                                                                            VR_E_friction, VR_stick_fraction};
    const fmi2Integer scheme = 1 + k % 3;
    const fmi2Boolean on = fmi2True;
    fmi2SetInteger(c, &vs, 1, &scheme);
    fmi2SetBoolean(c, &vo, 1, &on);
    fmi2Status st = start_run(c, 7e-4, 4, vr, val);
    const fmi2ValueReference vm = VR_mode;
    for (int j = 0; j < N_STEPS && st == fmi2OK; j++) {
        st = fmi2DoStep(c, j * 0.01, 0.01, fmi2True);
        if (st == fmi2OK) st = fmi2GetReal(c, vout, N_OUT, J->out[j]);
        if (st == fmi2OK) st = fmi2GetInteger(c, &vm, 1, &J->mode[j]);
    }
    J->status = st;
    fmi2FreeInstance(c);
    return NULL;
}

int main(void)
{
    tally t = {0, 0, NULL, {0}}, *T = &t;
    static job serial[N_THREADS], parallel[N_THREADS];
    for (int k = 0; k < N_THREADS; k++) {
        memset(&serial[k], 0, sizeof serial[k]);
        memset(&parallel[k], 0, sizeof parallel[k]);
        serial[k].k = parallel[k].k = k;
        simulate(&serial[k]);
        EXPECT(serial[k].status == fmi2OK);
    }
    for (int round = 0; round < 3; round++) {
        pthread_t th[N_THREADS];
        for (int k = 0; k < N_THREADS; k++) EXPECT(pthread_create(&th[k], NULL, simulate, &parallel[k]) == 0);
        for (int k = 0; k < N_THREADS; k++) pthread_join(th[k], NULL);
        for (int k = 0; k < N_THREADS; k++) {
            EXPECT(parallel[k].status == fmi2OK);
            EXPECT(memcmp(serial[k].out, parallel[k].out, sizeof serial[k].out) == 0);
            EXPECT(memcmp(serial[k].mode, parallel[k].mode, sizeof serial[k].mode) == 0);
        }
    }
    int finite = 1, distinct = 1;
    for (int k = 0; k < N_THREADS; k++) {
        for (int j = 0; j < N_STEPS; j++)
            for (int i = 0; i < N_OUT; i++) finite &= isfinite(serial[k].out[j][i]) != 0;
        if (k) distinct &= memcmp(serial[k].out, serial[k - 1].out, sizeof serial[k].out) != 0;
    }
    EXPECT(finite && distinct);
    EXPECT(mem_outstanding() == 0);
    return tally_done(T, "test_fmi_threads");
}
