/* The DryFrictionSystem model's two backends (models/system/system.h): the modal one (C diagonal in
 * the modal basis; the engine's coupling operators) against the dense one (sys_params.dense = 1: the
 * dense Cholesky per slot, the engine's columns), on the same structures:
 *   - a chain of 16 blocks (M = I + a small random band, K tridiagonal plus a band), Rayleigh damping
 *     C = 0.02 M + 0.002 K, 4 contacts (2 against the ground, 2 between blocks), stick-slip under a
 *     harmonic force: schemes located, consistent and paper; then a Jenkins contact among them; then
 *     Stribeck contacts (located): the modal backend taken (c_offdiag below 1e-12), positions and
 *     velocities at 200 sample times within 1e-10 of the largest (measured: 5e-13 to 9e-13; rounding, amplified where a
 *     switch's time moves by a rounding-level margin) and the same number of switches;
 *   - modal damping built as System.with_modal_damping builds it, C = M Phi diag(2 zeta_r w_r) Phi' M
 *     (zeta_r from 0.01 to 0.05): the modal backend;
 *   - no damping (C = 0): the modal backend, c_offdiag 0;
 *   - a non-proportional C (Rayleigh plus a dashpot 0.05 on one block): the dense backend, to the bit
 *     the run with sys_params.dense = 1;
 *   - n = 1: the dense backend (the oscillator's bits);
 *   - the operators themselves: factor and solve of the modal backend against the dense Cholesky on
 *     random right-hand sides (cM M + cC C + cK K of the grid step and of a shorter one, and M),
 *     within 1e-13 relative. */
#include "check.h"
#include "system.h"
#include "symeig.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *std_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void std_free(void *env, void *obj) { (void)env; free(obj); }
static const eng_alloc AL = {std_alloc, std_free, NULL};

#define NMAX 16
#define NCMAX 4

typedef struct {
    size_t n, nc;
    double M[NMAX * NMAX], C[NMAX * NMAX], K[NMAX * NMAX], W[NCMAX * NMAX];
    double F_c[NMAX], F_s[NMAX], x0[NMAX], v0[NMAX];
    double N[NCMAX], mu_s[NCMAX], mu_k[NCMAX], k_t[NCMAX], law[NCMAX], v_s[NCMAX], delta[NCMAX];
    int stribeck;
} structure;

/* The chain of n blocks with nc contacts (bench_system's layout), Rayleigh C = a M + b K. */
static void make_structure(structure *s, size_t n, size_t nc, double a, double b)
{
    memset(s, 0, sizeof *s);
    s->n = n;
    s->nc = nc;
    rng R = {12345ULL};
    for (size_t i = 0; i < n; i++) {
        s->M[i * n + i] = 1.0;
        s->K[i * n + i] = 2.0;
    }
    for (size_t i = 0; i < n; i++) {
        if (i + 1 < n) s->K[i * n + i + 1] = s->K[(i + 1) * n + i] = -1.0;
        if (i + 1 < n) {
            const double e = rng_range(&R, -0.05, 0.05);
            s->M[i * n + i + 1] = s->M[(i + 1) * n + i] = e;
        }
        if (i + 2 < n) {
            const double e = rng_range(&R, -0.1, 0.0);
            s->K[i * n + i + 2] = s->K[(i + 2) * n + i] = e;
            s->K[i * n + i] -= e;
            s->K[(i + 2) * n + i + 2] -= e;
        }
        s->F_c[i] = cos(0.1 * (double)i);
        s->F_s[i] = sin(0.1 * (double)i);
    }
    for (size_t k = 0; k < n * n; k++) s->C[k] = a * s->M[k] + b * s->K[k];
    for (size_t j = 0; j < nc; j++) {
        const size_t i = (size_t)(((double)j + 0.5) * (double)n / (double)nc);
        s->W[j * n + i] = 1.0;
        if (j % 2 == 1 && i + 1 < n) s->W[j * n + i + 1] = -1.0;
        s->N[j] = 1.6;
        s->mu_s[j] = 0.5;
        s->mu_k[j] = 0.35;
        s->law[j] = 1.0;
        s->v_s[j] = 0.1;
        s->delta[j] = 2.0;
    }
}

static sys_params params_of(const structure *s, int scheme, int dense)
{
    sys_params p;
    memset(&p, 0, sizeof p);
    p.n = s->n;
    p.nc = s->nc;
    p.M = s->M;
    p.C = s->C;
    p.K = s->K;
    p.F_c = s->F_c;
    p.F_s = s->F_s;
    p.x0 = s->x0;
    p.v0 = s->v0;
    p.W = s->W;
    p.N = s->N;
    p.mu_s = s->mu_s;
    p.mu_k = s->mu_k;
    p.k_t = s->k_t;
    if (s->stribeck) {
        p.law = s->law;
        p.v_s = s->v_s;
        p.delta = s->delta;
    }
    p.omega = 0.5;
    p.h = 2.0 * 3.14159265358979323846 / 0.5 / 200.0;
    p.alpha = -0.1;
    p.scheme = scheme;
    p.frictionUpdates = 1;
    p.dense = dense;
    return p;
}

#define SAMPLES 200

typedef struct {
    double X[SAMPLES][NMAX], V[SAMPLES][NMAX];
    long long switches;
    int modal;
    double c_offdiag;
    eng_status st;
} run_out;

/* Four periods from rest, sampled at 200 times (communication steps of T / 50). */
static void run(const structure *s, int scheme, int dense, run_out *o)
{
    memset(o, 0, sizeof *o);
    const sys_params p = params_of(s, scheme, dense);
    sys_model m;
    char buf[256];
    const char *err = NULL;
    if (!sys_model_init(&m, &p, &AL, 0, buf, sizeof buf, &err)) {
        fprintf(stderr, "test_system_modal: %s\n", err ? err : "?");
        o->st = ENG_ERR_BAD_INPUT;
        return;
    }
    o->modal = m.modal;
    o->c_offdiag = m.c_offdiag;
    eng_state st;
    if (!eng_state_init(m.E, &st, 0)) abort();
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    eng_start(m.E, &in, 0.0, s->x0, s->v0, &st);
    const double T = 2.0 * 3.14159265358979323846 / 0.5;
    for (int k = 0; k < SAMPLES; k++) {
        const eng_status e = eng_advance(m.E, &in, &st, (double)(k + 1) * T / 50.0, NULL);
        if (e != ENG_OK) {
            o->st = e;
            break;
        }
        memcpy(o->X[k], st.X, s->n * sizeof(double));
        memcpy(o->V[k], st.V, s->n * sizeof(double));
    }
    o->switches = st.switches;
    eng_state_free(m.E, &st);
    sys_model_free(&m, &AL);
}

/* max |a - b| over the samples relative to max |b| (positions and velocities each) */
static double rel_diff(size_t n, const double (*a)[NMAX], const double (*b)[NMAX])
{
    double d = 0.0, m = 0.0;
    for (int k = 0; k < SAMPLES; k++)
        for (size_t i = 0; i < n; i++) {
            d = fmax(d, fabs(a[k][i] - b[k][i]));
            m = fmax(m, fabs(b[k][i]));
        }
    return d / m;
}

static void compare(checks *T, const char *what, const structure *s, int scheme)
{
    static run_out a, b; /* (large: not on the stack) */
    check_context(T, "%s, scheme %d", what, scheme);
    run(s, scheme, 0, &a);
    run(s, scheme, 1, &b);
    CHECK_INT(ENG_OK, a.st);
    CHECK_INT(ENG_OK, b.st);
    CHECK_INT(1, a.modal);
    CHECK_INT(0, b.modal);
    CHECK_RANGE(0.0, 1e-12, a.c_offdiag);
    const double dx = rel_diff(s->n, (const double(*)[NMAX])a.X, (const double(*)[NMAX])b.X);
    const double dv = rel_diff(s->n, (const double(*)[NMAX])a.V, (const double(*)[NMAX])b.V);
    CHECK_RANGE(0.0, 1e-10, dx);
    CHECK_RANGE(0.0, 1e-10, dv);
    CHECK_INT(b.switches, a.switches);
    printf("%-34s scheme %d: c_offdiag %.3g, modal vs dense: x %.3g, v %.3g (relative), switches %lld / %lld\n", what,
           scheme, a.c_offdiag, dx, dv, a.switches, b.switches);
}

/* factor + solve of the modal backend against the dense one, random right-hand sides */
static void operators(checks *T, const structure *s)
{
    check_context(T, "the operators");
    const sys_params pm = params_of(s, DFO_SCHEME_LOCATED, 0), pd = params_of(s, DFO_SCHEME_LOCATED, 1);
    sys_model mm, md;
    char buf[256];
    const char *err = NULL;
    if (!CHECK(sys_model_init(&mm, &pm, &AL, 0, buf, sizeof buf, &err))) { fprintf(stderr, "%s\n", err); exit(1); }
    CHECK(sys_model_init(&md, &pd, &AL, 0, buf, sizeof buf, &err));
    const eng_ops *om = &eng_setup_of(mm.E)->ops, *od = &eng_setup_of(md.E)->ops;
    const double h = pm.h, g = 0.5 + 0.1, be = 0.25 * (1.0 + 0.1) * (1.0 + 0.1);
    const double coef[3][3] = {{(1.0 + 0.1) / (g * h), 1.0, be * h / g},
                               {(1.0 + 0.1) / (g * 0.01 * h), 1.0, be * 0.01 * h / g},
                               {1.0, 0.0, 0.0}};
    rng R = {777ULL};
    double worst = 0.0;
    for (int c = 0; c < 3; c++) {
        CHECK(om->factor(om->ctx, ENG_SLOT_TRIAL, coef[c][0], coef[c][1], coef[c][2]));
        CHECK(od->factor(od->ctx, ENG_SLOT_TRIAL, coef[c][0], coef[c][1], coef[c][2]));
        for (int t = 0; t < 5; t++) {
            double b[NMAX], xm[NMAX], xd[NMAX], e = 0.0, mx = 0.0;
            for (size_t i = 0; i < s->n; i++) b[i] = rng_range(&R, -1.0, 1.0);
            om->solve(om->ctx, ENG_SLOT_TRIAL, b, xm);
            od->solve(od->ctx, ENG_SLOT_TRIAL, b, xd);
            for (size_t i = 0; i < s->n; i++) {
                e = fmax(e, fabs(xm[i] - xd[i]));
                mx = fmax(mx, fabs(xd[i]));
            }
            CHECK_RANGE(0.0, 1e-13, e / mx);
            worst = fmax(worst, e / mx);
        }
    }
    printf("the operators: modal solve vs dense Cholesky %.3g (relative, worst of 15)\n", worst);
    sys_model_free(&mm, &AL);
    sys_model_free(&md, &AL);
}

int main(void)
{
    checks TT = {0, 0, NULL, {0}}, *T = &TT;
    static structure s;
    make_structure(&s, 16, 4, 0.02, 0.002);
    operators(T, &s);
    compare(T, "Rayleigh", &s, DFO_SCHEME_LOCATED);
    compare(T, "Rayleigh", &s, DFO_SCHEME_CONSISTENT);
    compare(T, "Rayleigh", &s, DFO_SCHEME_PAPER);
    /* a Jenkins contact (contact 1, between blocks) */
    s.k_t[1] = 20.0;
    compare(T, "Rayleigh, one Jenkins contact", &s, DFO_SCHEME_LOCATED);
    compare(T, "Rayleigh, one Jenkins contact", &s, DFO_SCHEME_CONSISTENT);
    s.k_t[1] = 0.0;
    /* Stribeck contacts */
    s.stribeck = 1;
    for (size_t j = 0; j < s.nc; j++) s.law[j] = 2.0;
    compare(T, "Rayleigh, Stribeck contacts", &s, DFO_SCHEME_LOCATED);
    s.stribeck = 0;
    /* modal damping: C = M Phi diag(2 zeta w) Phi' M */
    {
        const size_t n = s.n;
        double lam[NMAX], PhiT[NMAX * NMAX], work[2 * NMAX * NMAX + 2 * NMAX], MP[NMAX * NMAX];
        CHECK(dfo_symeig(n, s.K, s.M, lam, PhiT, work));
        for (size_t r = 0; r < n; r++) /* MP row r = (M phi_r)' */
            for (size_t i = 0; i < n; i++) {
                double v = 0.0;
                for (size_t k = 0; k < n; k++) v += s.M[i * n + k] * PhiT[r * n + k];
                MP[r * n + i] = v;
            }
        for (size_t i = 0; i < n; i++)
            for (size_t j = 0; j < n; j++) {
                double v = 0.0;
                for (size_t r = 0; r < n; r++) {
                    const double zeta = 0.01 + 0.04 * (double)r / (double)(n - 1);
                    v += MP[r * n + i] * (2.0 * zeta * sqrt(lam[r])) * MP[r * n + j];
                }
                s.C[i * n + j] = v;
            }
        for (size_t i = 0; i < n; i++) /* symmetric to the bit, as the structure's check wants it within 1e-12 */
            for (size_t j = 0; j < i; j++) s.C[i * n + j] = s.C[j * n + i];
        compare(T, "modal damping", &s, DFO_SCHEME_LOCATED);
    }
    /* no damping */
    memset(s.C, 0, sizeof s.C);
    compare(T, "C = 0", &s, DFO_SCHEME_LOCATED);
    /* non-proportional C: the dense backend, the bits of dense = 1 */
    {
        static run_out a, b;
        make_structure(&s, 16, 4, 0.02, 0.002);
        s.C[5 * 16 + 5] += 0.05;
        check_context(T, "non-proportional C");
        run(&s, DFO_SCHEME_LOCATED, 0, &a);
        run(&s, DFO_SCHEME_LOCATED, 1, &b);
        CHECK_INT(ENG_OK, a.st);
        CHECK_INT(0, a.modal);
        CHECK(a.c_offdiag > 1e-12);
        CHECK(memcmp(a.X, b.X, sizeof a.X) == 0 && memcmp(a.V, b.V, sizeof a.V) == 0);
        CHECK_INT(b.switches, a.switches);
        printf("non-proportional C (a dashpot 0.05 on DOF 6): c_offdiag %.3g, dense backend %s\n", a.c_offdiag,
               a.modal ? "NOT taken" : "taken, the bits of dense = 1");
    }
    /* n = 1: dense */
    {
        static run_out a;
        make_structure(&s, 1, 1, 0.02, 0.002);
        check_context(T, "n = 1");
        run(&s, DFO_SCHEME_LOCATED, 0, &a);
        CHECK_INT(ENG_OK, a.st);
        CHECK_INT(0, a.modal);
    }
    return checks_done(T, "test_system_modal");
}
