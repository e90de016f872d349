/* The located scheme's tangent (eng_setup.tangent) against central finite differences of the same
 * map: structures given by dense M, C, K (Cholesky per factor slot, written here), run over one or
 * more excitation periods from a start (x0, v0, the Jenkins sliders s0) through stick-slip switches;
 * each column of eng_jacobian against (P(z + d e_k) - P(z - d e_k)) / 2 d. Cases: one block with a
 * rigid contact (stops, breakaways, reversals), two masses with a Jenkins element between them
 * (the slider's breakaways and stops), three DOFs with a ground contact and one between two DOFs,
 * and with Bossak alpha 0 and -0.3. The runs with the tangent on give the same trajectory bits as
 * without it (the general path: the fast paths' numbers). */
#include "check.h"
#include "dense_model.h"
#include "engine.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void *t_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void t_free(void *env, void *p) { (void)env; free(p); }
static const eng_alloc ALLOC = {t_alloc, t_free, NULL};

/* A structure and its contacts (rows of up to two entries) */
typedef struct {
    dense D;
    size_t nc;
    size_t idx[NMAX][2];
    double w[NMAX][2];
    eng_row rows[NMAX];
    double N[NMAX], mu_s[NMAX], mu_k[NMAX], k_t[NMAX], Pc[NMAX];
    double omega, h, alpha;
} structure;

static eng_setup setup_of(structure *Q, int tangent)
{
    eng_setup S;
    memset(&S, 0, sizeof S);
    S.n = Q->D.n;
    S.nc = Q->nc;
    dense_ops(&Q->D, &S);
    S.rows = Q->rows;
    S.exc.omega = Q->omega;
    S.exc.Pc = Q->Pc;
    S.N = Q->N;
    S.mu_s = Q->mu_s;
    S.mu_k = Q->mu_k;
    S.k_t = Q->k_t;
    S.h = Q->h;
    S.alpha = Q->alpha;
    S.scheme = DFO_SCHEME_LOCATED;
    S.friction_updates = 1;
    S.fast_paths = 1;
    S.rate_max = 4.0;
    S.snap_max_rel_h = S.snap_min_rel_h = 1e-7;
    S.tangent = tangent;
    return S;
}

/* The map from z = (x0, v0, s0) over t_end: the end state into out (2 n + nc; a rigid contact's
 * entry 0), the Jacobian into J where asked (tangent on). Returns the switches, -1 on failure. */
static const int *SLIDE; /* the sliders' modes at the start (eng_set_sliders; NULL: stuck), per case */

static long run_map(structure *Q, const double *z, double t_end, double *out, double *J, int tangent,
                    eng_state *keep)
{
    const size_t n = Q->D.n, nc = Q->nc;
    const eng_setup S = setup_of(Q, tangent);
    eng *E = eng_create(&S, &ALLOC, NULL);
    eng_state s;
    if (!E || !eng_state_init(E, &s, 0)) { fprintf(stderr, "test_engine_tangent: no engine\n"); exit(1); }
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    eng_start(E, &in, 0.0, z, z + n, &s);
    long sw = -1;
    const int set = eng_set_sliders(E, &in, &s, z + 2 * n, SLIDE);
    const eng_status st = set ? eng_advance(E, &in, &s, t_end, NULL) : ENG_ERR_BAD_INPUT;
    if (st != ENG_OK) printf("    sliders set %d, advance: %s at t %g\n", set, eng_status_text(st), s.t);
    if (st == ENG_OK) {
        sw = (long)s.switches;
        for (size_t i = 0; i < n; i++) {
            out[i] = s.X[i];
            out[n + i] = s.V[i];
        }
        for (size_t j = 0; j < nc; j++) out[2 * n + j] = (Q->k_t[j] > 0.0) ? s.slider[j] : 0.0;
        if (J && !eng_jacobian(&s, J)) sw = -2;
    }
    if (keep) eng_state_copy(keep, &s);
    eng_state_free(E, &s);
    eng_destroy(E);
    return sw;
}

/* The tangent against central differences over t_end from z: the largest difference relative to
 * the Jacobian's scale */
static double check_map(checks *T, structure *Q, const double *z, double t_end, const char *name)
{
    const size_t n = Q->D.n, nc = Q->nc, nz = 2 * n + nc;
    double P[2 * NMAX + NMAX], J[(3 * NMAX) * (3 * NMAX)], Pp[3 * NMAX], Pm[3 * NMAX], zz[3 * NMAX];
    const long sw = run_map(Q, z, t_end, P, J, 1, NULL);
    if (sw < 0) printf("  %s: run_map %ld\n", name, sw);
    CHECK(sw >= 0);
    if (sw < 0) return INFINITY;
    double P0[3 * NMAX];
    CHECK(run_map(Q, z, t_end, P0, NULL, 0, NULL) == sw); /* the same trajectory without the tangent */
    CHECK(!memcmp(P0, P, nz * sizeof(double)));
    double err = 0.0, scale = 0.0;
    for (size_t k = 0; k < nz; k++) {
        if (k >= 2 * n && !(Q->k_t[k - 2 * n] > 0.0)) continue;
        const double d = 1e-6 * fmax(1.0, fabs(z[k]));
        memcpy(zz, z, nz * sizeof(double));
        zz[k] = z[k] + d;
        const long a = run_map(Q, zz, t_end, Pp, NULL, 0, NULL);
        zz[k] = z[k] - d;
        const long b = run_map(Q, zz, t_end, Pm, NULL, 0, NULL);
        CHECK(a == sw && b == sw); /* (the same switches: differentiable here) */
        for (size_t i = 0; i < nz; i++) {
            if (i >= 2 * n && !(Q->k_t[i - 2 * n] > 0.0)) continue;
            const double fd = (Pp[i] - Pm[i]) / (2.0 * d);
            err = fmax(err, fabs(fd - J[i * nz + k]));
            scale = fmax(scale, fabs(J[i * nz + k]));
        }
    }
    printf("  %-44s %ld switches, |J| %.3g, tangent - central differences %.2e\n", name, sw, scale, err);
    return err / fmax(scale, 1.0);
}

static void set_row(structure *Q, size_t j, size_t i, double wi, long k, double wk)
{
    Q->idx[j][0] = i;
    Q->w[j][0] = wi;
    Q->rows[j].nnz = 1;
    if (k >= 0) {
        Q->idx[j][1] = (size_t)k;
        Q->w[j][1] = wk;
        Q->rows[j].nnz = 2;
    }
    Q->rows[j].idx = Q->idx[j];
    Q->rows[j].w = Q->w[j];
}

static void test_block(checks *T)
{
    for (int q = 0; q < 3; q++) {
        static const double alphas[3] = {-0.1, 0.0, -0.3};
        structure Q;
        memset(&Q, 0, sizeof Q);
        Q.D.n = 1;
        Q.D.M[0] = 1.0;
        Q.D.K[0] = 1.0;
        Q.D.C[0] = 0.04;
        Q.nc = 1;
        set_row(&Q, 0, 0, 1.0, -1, 0.0);
        Q.N[0] = 0.5;
        Q.mu_s[0] = 0.5;
        Q.mu_k[0] = 0.35;
        Q.Pc[0] = 0.6;
        Q.omega = 0.7;
        Q.h = 2.0 * 3.141592653589793 / Q.omega / 400.0;
        Q.alpha = alphas[q];
        check_context(T, "one block, a rigid contact, stick-slip, alpha %g", Q.alpha);
        const double z[3] = {0.31, -0.12, 0.0};
        const double e = check_map(T, &Q, z, 2.0 * 3.141592653589793 / Q.omega, "one block, stick-slip, a period");
        CHECK(e < 1e-6);
    }
}

static void test_two_mass_jenkins(checks *T)
{
    static const double omegas[3] = {1.0, 1.4, 2.5};
    for (int q = 0; q < 3; q++) {
        structure Q;
        memset(&Q, 0, sizeof Q);
        Q.D.n = 2;
        const double M[4] = {1.0, 0.0, 0.0, 0.5}, K[4] = {3.0, -1.0, -1.0, 1.0};
        for (int k = 0; k < 4; k++) {
            Q.D.M[k] = M[k];
            Q.D.K[k] = K[k];
            Q.D.C[k] = 0.02 * K[k] + 0.02 * M[k];
        }
        Q.nc = 1;
        set_row(&Q, 0, 0, 1.0, 1, -1.0);
        Q.N[0] = 0.6;
        Q.mu_s[0] = 0.5;
        Q.mu_k[0] = 0.5;
        Q.k_t[0] = 20.0;
        Q.Pc[0] = 1.0;
        Q.omega = omegas[q];
        Q.h = 2.0 * 3.141592653589793 / Q.omega / 500.0;
        Q.alpha = -0.1;
        check_context(T, "two masses, a Jenkins element between them, omega %g", Q.omega);
        /* from a state on the way to the steady motion (its slider slipping and sticking) */
        double z[5] = {0.8, 0.4, -0.3, 0.6, 0.0};
        z[4] = z[0] - z[1] - 0.01; /* (its spring force 0.2 within mu N = 0.3) */
        const double e = check_map(T, &Q, z, 2.0 * 2.0 * 3.141592653589793 / Q.omega, "two masses, Jenkins, two periods");
        CHECK(e < 1e-6);
    }
}

/* Two masses, the Jenkins slider started sliding forward (mu_s > mu_k: its mode is not a function of
 * the state, eng_set_sliders' slide): the map does not depend on s0 (the slider where its kinetic force
 * puts it), and the tangent equals the differences through the slider's stop and the switches after. */
static void test_sliding_start(checks *T)
{
    structure Q;
    memset(&Q, 0, sizeof Q);
    Q.D.n = 2;
    const double M[4] = {1.0, 0.0, 0.0, 0.5}, K[4] = {3.0, -1.0, -1.0, 1.0};
    for (int k = 0; k < 4; k++) {
        Q.D.M[k] = M[k];
        Q.D.K[k] = K[k];
        Q.D.C[k] = 0.02 * K[k] + 0.02 * M[k];
    }
    Q.nc = 1;
    set_row(&Q, 0, 0, 1.0, 1, -1.0);
    Q.N[0] = 0.6;
    Q.mu_s[0] = 0.6;
    Q.mu_k[0] = 0.4;
    Q.k_t[0] = 20.0;
    Q.Pc[0] = 1.0;
    Q.omega = 1.4;
    Q.h = 2.0 * 3.141592653589793 / Q.omega / 500.0;
    Q.alpha = -0.1;
    static const int forward[1] = {1};
    SLIDE = forward;
    check_context(T, "two masses, the Jenkins slider started sliding (mu_s > mu_k)");
    const double z[5] = {0.8, 0.4, 0.9, -0.2, 0.0}; /* (slip velocity w . v = 1.1 > 0: forward) */
    const double e = check_map(T, &Q, z, 2.0 * 3.141592653589793 / Q.omega, "two masses, a sliding start, a period");
    CHECK(e < 1e-6);
    SLIDE = NULL;
}

static void test_three_dofs(checks *T)
{
    structure Q;
    memset(&Q, 0, sizeof Q);
    Q.D.n = 3;
    const double M[9] = {1.0, 0.1, 0.0, 0.1, 0.8, 0.0, 0.0, 0.0, 1.2};
    const double K[9] = {2.0, -1.0, 0.0, -1.0, 2.5, -1.0, 0.0, -1.0, 1.5};
    for (int k = 0; k < 9; k++) {
        Q.D.M[k] = M[k];
        Q.D.K[k] = K[k];
        Q.D.C[k] = 0.03 * K[k];
    }
    Q.nc = 3;
    set_row(&Q, 0, 0, 1.0, -1, 0.0);
    set_row(&Q, 1, 1, 1.0, 2, -1.0);
    set_row(&Q, 2, 2, 1.0, -1, 0.0);
    const double N[3] = {0.4, 0.3, 0.5}, ms[3] = {0.5, 0.4, 0.3}, mk[3] = {0.4, 0.4, 0.2}, kt[3] = {0.0, 0.0, 15.0};
    for (int j = 0; j < 3; j++) {
        Q.N[j] = N[j];
        Q.mu_s[j] = ms[j];
        Q.mu_k[j] = mk[j];
        Q.k_t[j] = kt[j];
    }
    Q.Pc[0] = 0.8;
    Q.Pc[2] = -0.5;
    Q.omega = 1.1;
    Q.h = 2.0 * 3.141592653589793 / Q.omega / 600.0;
    Q.alpha = -0.1;
    check_context(T, "three DOFs: rigid contacts on the ground and between DOFs, a Jenkins one");
    const double z[9] = {0.5, -0.2, 0.3, 0.1, 0.4, -0.6, 0.0, 0.0, 0.3 - 0.005};
    const double e = check_map(T, &Q, z, 2.0 * 3.141592653589793 / Q.omega, "three DOFs, three contacts, a period");
    CHECK(e < 1e-6);
}

int main(void)
{
    checks C = {0, 0, NULL, {0}};
    checks *T = &C;
    test_block(T);
    test_two_mass_jenkins(T);
    test_three_dofs(T);
    test_sliding_start(T);
    return checks_done(T, "test_engine_tangent");
}
