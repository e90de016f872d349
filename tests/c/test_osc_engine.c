/* The oscillator as a model of the friction engine (fmu_src/models/oscillator/osc_engine.c): its
 * schemes specialised by its inline operators (osc_eng_*) against engine.c with the same operators
 * through function pointers (eng_*): the same bits; and both against the oscillator's own Bossak
 * schemes (newmark.c's dfo_advance): the same trajectories to rounding (the engine's arithmetic is
 * ordered differently, and it finds breakaways by root finding where newmark.c uses closed forms)
 * and the same number of switches. Cases: the three schemes, damping, a belt and its change,
 * Stribeck, a ramp of F_ext, a jump of F_ext; stick-dominated motion (the stuck fast path). */
#include "check.h"
#include "osc_engine.h"
#include "osc_params.h"

#include "newmark.h"
#include "scheme.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *t_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void t_free(void *env, void *p) { (void)env; free(p); }
static const eng_alloc ALLOC = {t_alloc, t_free, NULL};

typedef struct {
    int scheme;
    double chi, c, Nn;
    double v_belt;   /* NaN: no belt */
    int stribeck;
    double F_ramp;   /* dF_ext/dt over the run (0: held) */
    double F_jump;   /* F_ext set to this at t = 10 (0: none) */
    double belt_to;  /* the belt's speed set to this at t = 10 (NaN: held) */
} osc_case;

/* The entry points of one build of the schemes. */
typedef struct {
    void (*start)(eng *, const eng_inputs *, double, const double *, const double *, eng_state *);
    eng_status (*advance)(eng *, const eng_inputs *, eng_state *, double, const eng_hooks *);
    void (*new_inputs)(eng *, const eng_inputs *, const eng_inputs *, eng_state *, const eng_hooks *);
} entry;

static const entry GENERIC = {eng_start, eng_advance, eng_new_inputs};
static const entry INLINE = {osc_eng_start, osc_eng_advance, osc_eng_new_inputs};

static void count_switch(void *ctx, double t, double x, int from, int to)
{
    (void)t; (void)x; (void)from; (void)to;
    ++*(long long *)ctx;
}

static int same_bits(const eng_state *a, const eng_state *b)
{
    return a->t == b->t && a->n_grid == b->n_grid && a->steps == b->steps && a->solves == b->solves &&
           a->switches == b->switches && !memcmp(a->X, b->X, sizeof(double)) && !memcmp(a->V, b->V, sizeof(double)) &&
           !memcmp(a->A, b->A, sizeof(double)) && !memcmp(a->F, b->F, sizeof(double)) && a->mode[0] == b->mode[0] &&
           !memcmp(&a->t_switch, &b->t_switch, sizeof(double));
}

/* Run case K: newmark.c, and the engine through both entries, communication steps of 0.1 s over 30 s
 * at h = 1e-3; max |x_engine - x_oscillator| / max |x| into *d, the switches into sw[0..2]. */
static int run_case(checks *T, const osc_case *K, double *d, long long sw[3])
{
    const double h = 1e-3;
    dfo_params p = osc_test_params(K->scheme, 1.0, 1.0, K->c, 0.6, 0.9, K->Nn, 0.8, K->chi);
    p.h = h;
    if (K->stribeck) {
        p.friction_law = DFO_LAW_STRIBECK;
        p.v_s = 0.05;
        p.delta = 1.0;
    }
    dfo_model M;
    dfo_model_init(&M, &p);
    dfo_inputs u;
    memset(&u, 0, sizeof u);
    if (!isnan(K->v_belt)) { u.v_belt = K->v_belt; u.v_belt_set = 1; }
    if (K->F_ramp != 0.0) { u.F_ext_set = 1; u.F_ext_d[0] = K->F_ramp; u.ramp = 1; u.t_d = 0.0; }
    dfo_state so;
    dfo_start(&M, &u, 0.0, &so);
    osc_eng_model O[2];
    eng *E[2];
    eng_state s[2];
    osc_eng_inbuf b[2][2]; /* per run: the current inputs and the former ones */
    eng_inputs in[2], old[2];
    const entry *X[2] = {&GENERIC, &INLINE};
    for (int r = 0; r < 2; r++) {
        E[r] = osc_eng_create(&M, &O[r], &ALLOC, NULL);
        if (!E[r] || !eng_state_init(E[r], &s[r], 0)) { fprintf(stderr, "test_osc_engine: no engine\n"); exit(1); }
        osc_eng_inputs(&u, &b[r][0], &in[r]);
        X[r]->start(E[r], &in[r], 0.0, &p.x0, &p.v0, &s[r]);
    }
    double dmax = 0.0, xm = 0.0;
    long long sw_o = 0;
    int ok = 1;
    for (int k = 1; k <= 300 && ok; k++) {
        const double t = (double)(k * 100) * h;
        if (k == 101 && (K->F_jump != 0.0 || !isnan(K->belt_to))) { /* the inputs change at t = 10 s */
            const dfo_inputs uold = u;
            if (K->F_jump != 0.0) { u.F_ext = K->F_jump; u.F_ext_set = 1; }
            if (!isnan(K->belt_to)) { u.v_belt = K->belt_to; u.v_belt_set = 1; }
            dfo_new_inputs(&M, &uold, &u, &so);
            for (int r = 0; r < 2; r++) {
                osc_eng_inputs(&uold, &b[r][1], &old[r]);
                osc_eng_inputs(&u, &b[r][0], &in[r]);
                X[r]->new_inputs(E[r], &old[r], &in[r], &s[r], NULL);
            }
        }
        for (int r = 0; r < 2; r++) ok &= X[r]->advance(E[r], &in[r], &s[r], t, NULL) == ENG_OK;
        ok &= dfo_advance(&M, &u, &so, t, count_switch, &sw_o) == DFO_OK;
        dmax = fmax(dmax, fabs(s[0].X[0] - so.X));
        xm = fmax(xm, fabs(so.X));
    }
    CHECK(ok);
    CHECK(same_bits(&s[0], &s[1]));
    *d = dmax / xm;
    sw[0] = sw_o;
    sw[1] = s[0].switches;
    sw[2] = s[1].switches;
    for (int r = 0; r < 2; r++) {
        eng_state_free(E[r], &s[r]);
        eng_destroy(E[r]);
    }
    return ok;
}

int main(void)
{
    checks C = {0, 0, NULL, {0}};
    checks *T = &C;
    static const char *const names[] = {"", "paper", "consistent", "located"};
    const double nan = NAN;
    const osc_case cases[] = {
        {DFO_SCHEME_PAPER, 0.7, 0.0, 0.5, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_CONSISTENT, 0.3, 0.0, 0.5, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.3, 0.0, 0.5, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.7, 0.05, 0.5, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.7, 0.0, 0.7, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.6, 0.0, 0.5, 0.3, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.6, 0.0, 0.5, 0.3, 1, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.7, 0.0, 0.5, nan, 0, 0.02, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.7, 0.0, 0.5, nan, 0, 0.0, 0.25, nan},
        {DFO_SCHEME_CONSISTENT, 0.6, 0.0, 0.5, 0.3, 0, 0.0, 0.0, -0.2},
        {DFO_SCHEME_LOCATED, 0.6, 0.05, 0.5, 0.3, 1, 0.0, 0.0, 0.1},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        const osc_case *K = &cases[k];
        check_context(T, "%s chi %.1f c %.2f N %.1f belt %g (to %g) stribeck %d ramp %g jump %g", names[K->scheme],
                      K->chi, K->c, K->Nn, K->v_belt, K->belt_to, K->stribeck, K->F_ramp, K->F_jump);
        double d = INFINITY;
        long long sw[3] = {0, 0, 0};
        run_case(T, K, &d, sw);
        printf("  %-10s chi %.1f c %.2f N %.1f belt %-4g to %-4g stribeck %d ramp %-4g jump %-4g: max |dx| / max |x| "
               "%.2e, switches %lld / %lld\n",
               names[K->scheme], K->chi, K->c, K->Nn, K->v_belt, K->belt_to, K->stribeck, K->F_ramp, K->F_jump, d,
               sw[0], sw[1]);
        CHECK(d < 1e-9);
        CHECK(sw[1] >= 4);
        CHECK(sw[1] == sw[0] && sw[2] == sw[1]);
    }
    return checks_done(T, "test_osc_engine");
}
