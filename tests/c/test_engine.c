/* The friction engine (fmu_src/engine) on small dense models: its located scheme against the
 * oscillator's exact scheme (an independent closed form) with the error falling 4x per halving of
 * h, the consistent scheme first order; chains of 2 and 8 blocks against the chain's own stepper
 * (another implementation of the same schemes) in all three schemes and with the Stribeck law,
 * with the dense friction solver and with a model's own (the box LCP of numerics/lcp.h through the
 * friction hook); two masses with a contact between them (w = [1, -1]) and one to the ground,
 * second order under refinement, the stuck contact's slip held; the dense friction solver against
 * the enumeration of the 3^nc mode sets; one block against the oscillator's three Bossak schemes
 * (belt, Stribeck, input ramps, input and belt changes); stop at switch and state copy. Prints the
 * measured errors and ratios. */
#include "check.h"
#include "engine.h"

#include "chain.h"
#include "lcp.h"
#include "scheme.h"
#include "osc_params.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define NMAX 8

/* A dense model: M, C, K (n x n, row-major), factors by Cholesky in three slots (dense_model.h) */
#include "dense_model.h"
typedef dense dense_model;

/* A model's own friction solver, as the chain's: W = I (contact i on DOF i), no belts, M_hat
 * tridiagonal: the box LCP of numerics/lcp.h (lcp_box_basis in the given modes, lcp_box for the
 * LCP), z the end velocities, w the forces, q = -p_hat. */
static eng_status tri_friction(void *c, const eng_problem *P, int what, int *mode, double *V1, double *f, int *pivots)
{
    const dense_model *D = c;
    const size_t n = D->n;
    double d[NMAX], e[NMAX], q[NMAX], cp[NMAX], dp[NMAX], work[2 * NMAX];
    for (size_t i = 0; i < n; i++) {
        d[i] = P->cM * D->M[i * n + i] + P->cC * D->C[i * n + i] + P->cK * D->K[i * n + i];
        const size_t o = i * n + i + 1; /* (i, i + 1) */
        e[i] = (i + 1 < n) ? P->cM * D->M[o] + P->cC * D->C[o] + P->cK * D->K[o] : 0.0;
        q[i] = -P->p_hat[i];
    }
    if (pivots) *pivots = 0;
    if (what == ENG_SOLVE_BASIS) {
        lcp_box_basis(0, n, 0, 0.0, 0, 0.0, d, e, q, P->limit, mode, V1, f, cp, dp);
        for (size_t i = 0; i < n; i++) /* a sliding row's force is its limit's (w is not set there) */
            if (!(mode[i] == 0 && P->limit[i] > 0.0)) f[i] = (P->limit[i] > 0.0) ? -mode[i] * P->limit[i] : 0.0;
        return ENG_OK;
    }
    return lcp_box(n, d, e, q, P->limit, mode, V1, f, work, pivots) == LCP_OK ? ENG_OK : ENG_ERR_LCP;
}

static void *t_alloc(void *env, size_t nobj, size_t size) { (void)env; return calloc(nobj, size); }
static void t_free(void *env, void *p) { (void)env; free(p); }
static const eng_alloc ALLOC = {t_alloc, t_free, NULL};

/* A setup over the dense model D with the given rows and friction data (arrays the caller's). */
static eng_setup setup_of(dense_model *D, size_t nc, const eng_row *rows, const double *N, const double *mu_s,
                          const double *mu_k, const double *Pc, double omega, double h, int scheme)
{
    eng_setup S;
    memset(&S, 0, sizeof S);
    S.n = D->n;
    S.nc = nc;
    S.ops.ctx = D;
    S.ops.apply_K = op_K;
    S.ops.apply_C = op_C;
    S.ops.apply_M = op_M;
    S.ops.factor = op_factor;
    S.ops.solve = op_solve;
    S.rows = rows;
    S.exc.omega = omega;
    S.exc.Pc = Pc;
    S.N = N;
    S.mu_s = mu_s;
    S.mu_k = mu_k;
    S.h = h;
    S.alpha = -0.1;
    S.scheme = scheme;
    S.friction_updates = 1;
    S.fast_paths = 1;
    double rate = 0.0;
    for (size_t i = 0; i < D->n; i++) rate = fmax(rate, sqrt(D->K[i * D->n + i] / D->M[i * D->n + i]) * 2.0);
    S.rate_max = rate + fabs(omega);
    S.snap_max_rel_h = S.snap_min_rel_h = 1e-7;
    return S;
}

/* One block of unit mass and stiffness with damping c, its contact to the ground (row). */
static void one_block(dense_model *D, double c, eng_row *row)
{
    static const size_t idx0[1] = {0};
    static const double w1[1] = {1.0};
    memset(D, 0, sizeof *D);
    D->n = 1;
    D->M[0] = 1.0;
    D->K[0] = 1.0;
    D->C[0] = c;
    row->nnz = 1;
    row->idx = idx0;
    row->w = w1;
}

/* The oscillator's model and state, started at 0 from rest (in: its inputs). */
static void osc_begin(const dfo_params *p, const dfo_inputs *in, dfo_model *Mo, dfo_state *so)
{
    dfo_model_init(Mo, p);
    dfo_start(Mo, in, 0.0, so);
}

/* An engine of S, its state s started at 0 from rest with the inputs in. */
static eng *eng_begin(const eng_setup *S, const eng_inputs *in, eng_state *s)
{
    static const double zeros[NMAX] = {0.0};
    eng *E = eng_create(S, &ALLOC, NULL);
    eng_state_init(E, s, 0);
    eng_start(E, in, 0.0, zeros, zeros, s);
    return E;
}

/* ---- one block against the oscillator's exact scheme ---------------------------------------- */

/* max |x - x_exact| over the communication points T/8 apart in [0, periods T], the engine at h = T/steps */
static double block_error(int scheme, double chi, double c, long steps, int periods)
{
    const double omega = 0.5, T = 2.0 * DFO_PI / omega, Nn = 0.4, mu_s = 1.0;
    dfo_params p = osc_test_params(DFO_SCHEME_EXACT, 1.0, 1.0, c, 1.0, omega, Nn, mu_s, chi);
    p.h = T / (double)steps;
    dfo_model Mo;
    dfo_inputs in0;
    memset(&in0, 0, sizeof in0);
    dfo_state so;
    osc_begin(&p, &in0, &Mo, &so);
    dense_model D;
    eng_row row;
    one_block(&D, c, &row);
    const double N[1] = {Nn}, ms[1] = {mu_s}, mk[1] = {chi * mu_s}, Pc[1] = {1.0};
    eng_setup S = setup_of(&D, 1, &row, N, ms, mk, Pc, omega, T / (double)steps, scheme);
    eng_state s;
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    eng *E = eng_begin(&S, &in, &s);
    double err = 0.0;
    for (int k = 1; k <= 8 * periods; k++) {
        const double t = s.t0 + (double)(k * steps / 8) * S.h;
        if (eng_advance(E, &in, &s, t, NULL) != ENG_OK) { err = INFINITY; break; }
        if (dfo_advance(&Mo, &in0, &so, s.t, NULL, NULL) != DFO_OK) { err = INFINITY; break; }
        err = fmax(err, fabs(s.X[0] - so.X));
    }
    eng_state_free(E, &s);
    eng_destroy(E);
    return err;
}

static void test_block_orders(checks *T)
{
    static const double chis[] = {0.3, 0.7, 0.9};
    for (size_t k = 0; k < sizeof chis / sizeof chis[0]; k++) {
        const double chi = chis[k];
        check_context(T, "one block, located, chi %.2f", chi);
        const double e1 = block_error(DFO_SCHEME_LOCATED, chi, 0.0, 400, 4);
        const double e2 = block_error(DFO_SCHEME_LOCATED, chi, 0.0, 800, 4);
        const double e3 = block_error(DFO_SCHEME_LOCATED, chi, 0.0, 1600, 4);
        printf("  located chi %.2f: max error %.3e %.3e %.3e (T/400, T/800, T/1600), ratios %.2f %.2f\n", chi, e1, e2,
               e3, e1 / e2, e2 / e3);
        CHECK(e1 < 1e-2);
        CHECK_RANGE(3.0, 5.5, e2 / e3);
    }
    check_context(T, "one block, located, damped");
    {
        const double e1 = block_error(DFO_SCHEME_LOCATED, 0.7, 0.1, 400, 4);
        const double e2 = block_error(DFO_SCHEME_LOCATED, 0.7, 0.1, 800, 4);
        printf("  located chi 0.70, c 0.1: %.3e %.3e, ratio %.2f\n", e1, e2, e1 / e2);
        CHECK_RANGE(3.0, 5.5, e1 / e2);
    }
    check_context(T, "one block, consistent");
    {
        const double e1 = block_error(DFO_SCHEME_CONSISTENT, 0.3, 0.0, 800, 4);
        const double e2 = block_error(DFO_SCHEME_CONSISTENT, 0.3, 0.0, 6400, 4);
        printf("  consistent chi 0.30: %.3e %.3e (T/800, T/6400), ratio %.2f\n", e1, e2, e1 / e2);
        CHECK(e1 < 1e-2);
        CHECK(e2 < 0.5 * e1);
    }
}

/* ---- one block against the oscillator's Bossak schemes (newmark.c) ----------------------- */

/* What a comparison varies. */
typedef struct {
    int scheme;
    double chi, c;
    double v_belt;     /* NaN: no belt */
    int stribeck;
    double F_ramp;     /* dF_ext/dt over the run (0: held) */
    double F_jump;     /* F_ext set to this at t = 10 (dfo_new_inputs / eng_new_inputs) */
    double belt_to;    /* the belt's speed set to this at t = 10 (NaN: held) */
} osc_case;

/* max |x_engine - x_oscillator| / max |x| over 30 s of communication steps of 0.1 s at h = 1e-3;
 * the switches of both through *sw_e, *sw_o. */
static double osc_agreement(const osc_case *K, long long *sw_e, long long *sw_o)
{
    const double h = 1e-3, omega = 0.9, P0 = 0.6, Nn = 0.5, mu_s = 0.8;
    dfo_params p = osc_test_params(K->scheme, 1.0, 1.0, K->c, P0, omega, Nn, mu_s, K->chi);
    p.h = h;
    if (K->stribeck) osc_test_stribeck(&p, 0.05, 1.0);
    dfo_model Mo;
    dfo_inputs oi;
    memset(&oi, 0, sizeof oi);
    const int belt = !isnan(K->v_belt);
    if (belt) { oi.v_belt = K->v_belt; oi.v_belt_set = 1; }
    if (K->F_ramp != 0.0) { oi.F_ext_set = 1; oi.F_ext_d[0] = K->F_ramp; oi.ramp = 1; oi.t_d = 0.0; }
    dfo_state so;
    osc_begin(&p, &oi, &Mo, &so);
    dense_model D;
    eng_row row;
    one_block(&D, K->c, &row);
    const double N[1] = {Nn}, ms[1] = {mu_s}, mk[1] = {K->chi * mu_s}, Pc[1] = {P0};
    dfo_friction_law law[1] = {{DFO_LAW_STRIBECK, mu_s, K->chi * mu_s, 0.05, 1.0}};
    eng_setup S = setup_of(&D, 1, &row, N, ms, mk, Pc, omega, h, K->scheme);
    S.rate_max = Mo.rate_max;
    if (K->stribeck) S.law = law;
    double F0[1] = {0.0}, dF[1] = {K->F_ramp}, vb[1] = {belt ? K->v_belt : 0.0};
    eng_inputs in = {NULL, NULL, belt ? vb : NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    if (K->F_ramp != 0.0) { in.F_ext = F0; in.dF_ext[0] = dF; }
    eng_state s;
    eng *E = eng_begin(&S, &in, &s);
    double d = 0.0, xm = 0.0;
    for (int k = 1; k <= 300; k++) {
        const double t = (double)(k * 100) * h;
        if (k == 101 && (K->F_jump != 0.0 || !isnan(K->belt_to))) { /* the inputs change at t = 10 s */
            const eng_inputs old = in;
            const dfo_inputs oold = oi;
            static double Fj[1];
            if (K->F_jump != 0.0) {
                Fj[0] = K->F_jump;
                in.F_ext = Fj;
                oi.F_ext = K->F_jump;
                oi.F_ext_set = 1;
            }
            if (!isnan(K->belt_to)) {
                vb[0] = K->belt_to;
                in.v_belt = vb;
                oi.v_belt = K->belt_to;
                oi.v_belt_set = 1;
            }
            eng_new_inputs(E, &old, &in, &s, NULL);
            dfo_new_inputs(&Mo, &oold, &oi, &so);
        }
        if (eng_advance(E, &in, &s, t, NULL) != ENG_OK) { d = INFINITY; break; }
        if (dfo_advance(&Mo, &oi, &so, t, NULL, NULL) != DFO_OK) { d = INFINITY; break; }
        d = fmax(d, fabs(s.X[0] - so.X));
        xm = fmax(xm, fabs(so.X));
    }
    *sw_e = s.switches;
    *sw_o = so.transitions;
    eng_state_free(E, &s);
    eng_destroy(E);
    return d / xm;
}

static void test_vs_oscillator(checks *T)
{
    static const char *const names[] = {"", "paper", "consistent", "located"};
    const double nan = NAN;
    const osc_case cases[] = {
        {DFO_SCHEME_PAPER, 0.7, 0.0, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_CONSISTENT, 0.3, 0.0, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.3, 0.0, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.7, 0.05, nan, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.6, 0.0, 0.3, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_CONSISTENT, 0.6, 0.0, 0.3, 0, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.6, 0.0, 0.3, 1, 0.0, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.7, 0.0, nan, 0, 0.02, 0.0, nan},
        {DFO_SCHEME_LOCATED, 0.7, 0.0, nan, 0, 0.0, 0.25, nan},
        {DFO_SCHEME_CONSISTENT, 0.7, 0.0, nan, 0, 0.0, 0.25, nan},
        {DFO_SCHEME_LOCATED, 0.6, 0.0, 0.3, 0, 0.0, 0.0, -0.2},
        {DFO_SCHEME_CONSISTENT, 0.6, 0.0, 0.3, 0, 0.0, 0.0, -0.2},
        {DFO_SCHEME_LOCATED, 0.6, 0.05, 0.3, 1, 0.0, 0.0, 0.1},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        const osc_case *K = &cases[k];
        check_context(T, "one block against the oscillator: %s chi %.1f c %.2f belt %g (to %g) stribeck %d ramp %g "
                      "jump %g", names[K->scheme], K->chi, K->c, K->v_belt, K->belt_to, K->stribeck, K->F_ramp,
                      K->F_jump);
        long long se = 0, so = 0;
        const double d = osc_agreement(K, &se, &so);
        printf("  vs oscillator %-10s chi %.1f c %.2f belt %-4g to %-4g stribeck %d ramp %-4g jump %-4g: max |dx| / "
               "max |x| %.2e, switches %lld\n",
               names[K->scheme], K->chi, K->c, K->v_belt, K->belt_to, K->stribeck, K->F_ramp, K->F_jump, d, se);
        CHECK(d < 1e-9);
        CHECK(se >= 4);
    }
}

/* ---- a chain of two blocks against the chain's stepper --------------------------------------- */

/* A chain of n blocks (n <= NMAX) stepped by chain_advance and by the engine over the same dense
 * operators (W = I): max |x_engine - x_chain| / max |x| over 40 s, the switches of both. */
static double chain_agreement(size_t n, int scheme, int hook, int stribeck, long long *sw_e, long long *sw_c)
{
    const double omega = 0.7, h = 2e-3;
    double m[NMAX], k[NMAX], c[NMAX], P0[NMAX], phi[NMAX], N[NMAX], mu_s[NMAX], chi[NMAX], mk[NMAX], zero[NMAX];
    for (size_t i = 0; i < n; i++) {
        m[i] = 1.0 + 0.5 * (double)(i % 3);
        k[i] = 1.0 - 0.1 * (double)(i % 4);
        c[i] = (i % 2) ? 0.05 : 0.0;
        P0[i] = (i % 3 == 1) ? 0.0 : 1.0 - 0.1 * (double)i;
        phi[i] = zero[i] = 0.0;
        N[i] = 0.3 + 0.05 * (double)(i % 3);
        mu_s[i] = 1.0 - 0.05 * (double)i;
        chi[i] = (i % 4 == 3) ? 1.2 : 0.7 - 0.05 * (double)(i % 3);
        mk[i] = chi[i] * mu_s[i];
    }
    chain_params cp;
    memset(&cp, 0, sizeof cp);
    cp.n = n;
    cp.m = m; cp.k = k; cp.c = c; cp.P0 = P0; cp.phi = phi; cp.N = N; cp.mu_s = mu_s; cp.chi = chi;
    cp.x0 = zero; cp.v0 = zero; cp.omega = omega; cp.h = h; cp.alpha = -0.1; cp.scheme = scheme;
    double vs[NMAX], dl[NMAX];
    dfo_friction_law law[NMAX];
    for (size_t i = 0; i < n; i++) {
        vs[i] = 0.05 + 0.01 * (double)(i % 3);
        dl[i] = 1.0;
        law[i].law = DFO_LAW_STRIBECK;
        law[i].mu_s = mu_s[i];
        law[i].mu_k = mk[i];
        law[i].v_s = vs[i];
        law[i].delta = dl[i];
    }
    if (stribeck) {
        cp.friction_law = DFO_LAW_STRIBECK;
        cp.v_s = vs;
        cp.delta = dl;
    }
    const chain_alloc cal = {t_alloc, t_free, NULL};
    chain_model *CM = chain_create(&cp, &cal, NULL);
    chain_state cs;
    chain_state_init(CM, &cs);
    const chain_inputs cin = {NULL, NULL};
    chain_start(CM, &cin, 0.0, &cs);

    dense_model D;  /* wall -k0- m0 -k1- m1 - ... - m(n-1), free right end */
    memset(&D, 0, sizeof D);
    D.n = n;
    for (size_t i = 0; i < n; i++) {
        D.M[i * n + i] = m[i];
        D.K[i * n + i] = k[i] + ((i + 1 < n) ? k[i + 1] : 0.0);
        D.C[i * n + i] = c[i] + ((i + 1 < n) ? c[i + 1] : 0.0);
        if (i + 1 < n) {
            D.K[i * n + i + 1] = D.K[(i + 1) * n + i] = -k[i + 1];
            D.C[i * n + i + 1] = D.C[(i + 1) * n + i] = -c[i + 1];
        }
    }
    static const size_t idx[NMAX] = {0, 1, 2, 3, 4, 5, 6, 7};
    static const double w1[1] = {1.0};
    eng_row rows[NMAX];
    for (size_t i = 0; i < n; i++) { rows[i].nnz = 1; rows[i].idx = &idx[i]; rows[i].w = w1; }
    eng_setup S = setup_of(&D, n, rows, N, mu_s, mk, P0, omega, h, scheme);
    if (hook) S.ops.friction = tri_friction;
    if (stribeck) S.law = law;
    eng_state s;
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    eng *E = eng_begin(&S, &in, &s);
    double dmax = 0.0, xmax = 0.0;
    for (int j = 1; j <= 400; j++) {
        const double t = (double)(j * 50) * h;
        if (eng_advance(E, &in, &s, t, NULL) != ENG_OK || chain_advance(CM, &cin, &cs, t, 0, NULL, NULL) != CHAIN_OK) {
            dmax = INFINITY;
            break;
        }
        for (size_t i = 0; i < n; i++) {
            dmax = fmax(dmax, fabs(s.X[i] - cs.X[i]));
            xmax = fmax(xmax, fabs(cs.X[i]));
        }
    }
    *sw_e = s.switches;
    *sw_c = cs.switches;
    eng_state_free(E, &s);
    eng_destroy(E);
    chain_state_free(CM, &cs);
    chain_destroy(CM);
    return dmax / xmax;
}

static void test_chains(checks *T)
{
    static const char *const names[] = {"", "paper", "consistent", "located"};
    static const size_t sizes[] = {2, 8};
    for (int hook = 0; hook <= 1; hook++) {
        for (size_t a = 0; a < 2; a++)
            for (int scheme = DFO_SCHEME_PAPER; scheme <= DFO_SCHEME_LOCATED; scheme++) {
                const size_t n = sizes[a];
                check_context(T, "chain of %zu blocks, %s, %s, against chain_advance", n, names[scheme],
                              hook ? "the model's box LCP" : "dense friction");
                long long se = 0, sc = 0;
                const double d = chain_agreement(n, scheme, hook, 0, &se, &sc);
                printf("  chain n = %zu %-10s %-13s 40 s: max |x_engine - x_chain| / max |x| %.2e, switches %lld / "
                       "%lld\n", n, names[scheme], hook ? "box LCP hook" : "dense", d, se, sc);
                CHECK(d < 1e-9);
                CHECK(se >= 5 * (long long)n);
                CHECK_RANGE(0.97 * (double)sc - 2.0, 1.03 * (double)sc + 2.0, (double)se);
            }
    }
    /* Stribeck on every block (located: the chain's law): the engine's Newton on the sliding
     * contacts together against the chain's per run of free rows */
    for (size_t a = 0; a < 2; a++) {
        const size_t n = sizes[a];
        check_context(T, "chain of %zu blocks, located, Stribeck, against chain_advance", n);
        long long se = 0, sc = 0;
        const double d = chain_agreement(n, DFO_SCHEME_LOCATED, 0, 1, &se, &sc);
        printf("  chain n = %zu located   Stribeck      40 s: max |x_engine - x_chain| / max |x| %.2e, switches %lld / "
               "%lld\n", n, d, se, sc);
        CHECK(d < 1e-9);
        CHECK(se >= 5 * (long long)n);
        CHECK_RANGE(0.97 * (double)sc - 2.0, 1.03 * (double)sc + 2.0, (double)se);
    }
}

/* ---- two masses, a contact between them and one to the ground ---------------------------------- */

/* An observer: over the phases in which the contact between the masses was stuck (and stays so),
 * the largest slip velocity at their ends, and the stuck time it saw inside the window. */
typedef struct {
    double max_rel_slip;
    long stuck_phases;
    double t_stuck;
    long phases, velocities_off; /* the phases, and those whose velocities (asked for) are not the state's */
} slip_watch;

static void watch_phase(void *ctx, const eng_phase *ph, const eng_state *s)
{
    slip_watch *W = ctx;
    W->phases++;
    W->velocities_off += !(ph->V0 && ph->V1 && ph->V1[0] == s->V[0] && ph->V1[1] == s->V[1]);
    if (ph->mode0[0] != 0 || s->mode[0] != 0) return;
    W->max_rel_slip = fmax(W->max_rel_slip, fabs(s->V[0] - s->V[1]));
    W->stuck_phases++;
    W->t_stuck += ph->tb - ph->ta;
}

/* Two masses, each on its own spring to the wall, the first damped and forced; contact 0 between
 * them (w = [1, -1]), contact 1 from the first to the ground (w = [1, 0]). */
static void two_mass_model(dense_model *D, eng_row rows[2])
{
    static const size_t ib[2] = {0, 1}, ig[1] = {0};
    static const double wb[2] = {1.0, -1.0}, wg[1] = {1.0};
    memset(D, 0, sizeof *D);
    D->n = 2;
    D->M[0] = 1.0; D->M[3] = 0.5;
    D->K[0] = 1.0; D->K[3] = 2.0;  /* each to the wall on its own spring: coupled through the contact only */
    D->C[0] = 0.02;
    rows[0].nnz = 2; rows[0].idx = ib; rows[0].w = wb;
    rows[1].nnz = 1; rows[1].idx = ig; rows[1].w = wg;
}

static double two_mass_run(long steps_per_T, int scheme, double *x_out, slip_watch *W, long long *switches)
{
    const double omega = 0.8, T = 2.0 * DFO_PI / omega;
    dense_model D;
    eng_row rows[2];
    two_mass_model(&D, rows);
    const double N[2] = {1.0, 0.3}, ms[2] = {0.6, 0.8}, mk[2] = {0.45, 0.6}, Pc[2] = {1.0, 0.0};
    eng_setup S = setup_of(&D, 2, rows, N, ms, mk, Pc, omega, T / (double)steps_per_T, scheme);
    eng_state s;
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    eng *E = eng_begin(&S, &in, &s);
    int ok = 1;
    const eng_observer obs = {T, 4.0 * T, watch_phase, W, 1};
    const eng_hooks hk = {NULL, NULL, W ? &obs : NULL, 0, 0, 0};
    for (int k = 1; k <= 32 && ok; k++)
        ok = eng_advance(E, &in, &s, (double)(k * steps_per_T / 8) * S.h, &hk) == ENG_OK;
    x_out[0] = s.X[0];
    x_out[1] = s.X[1];
    if (switches) *switches = s.switches;
    eng_state_free(E, &s);
    eng_destroy(E);
    return ok ? 0.0 : INFINITY;
}

static void test_two_masses(checks *T)
{
    check_context(T, "two masses, contact between them and to the ground, located");
    double x[4][2];
    slip_watch W = {0.0, 0, 0.0, 0, 0};
    long long sw = 0;
    const long base = 400;
    for (int r = 0; r < 4; r++)
        CHECK(two_mass_run(base << r, DFO_SCHEME_LOCATED, x[r], r == 3 ? &W : NULL, r == 3 ? &sw : NULL) == 0.0);
    const double d1 = fmax(fabs(x[0][0] - x[1][0]), fabs(x[0][1] - x[1][1]));
    const double d2 = fmax(fabs(x[1][0] - x[2][0]), fabs(x[1][1] - x[2][1]));
    const double d3 = fmax(fabs(x[2][0] - x[3][0]), fabs(x[2][1] - x[3][1]));
    printf("  two masses: x(4T) = (%.9f, %.9f); differences under halving %.3e %.3e %.3e, ratios %.2f %.2f; "
           "%lld switches; stuck slip <= %.1e over %ld stuck phases (%.2f s of the window [T, 4T])\n",
           x[3][0], x[3][1], d1, d2, d3, d1 / d2, d2 / d3, sw, W.max_rel_slip, W.stuck_phases, W.t_stuck);
    CHECK(sw >= 4);
    CHECK_RANGE(3.0, 5.5, d2 / d3);
    CHECK(W.stuck_phases > 100);
    CHECK(W.max_rel_slip <= 1e-12);
    CHECK(W.phases > 100 && W.velocities_off == 0); /* (each phase's end velocities, where asked for) */
    check_context(T, "two masses, consistent and paper run");
    double xc[2], xp[2];
    CHECK(two_mass_run(1600, DFO_SCHEME_CONSISTENT, xc, NULL, NULL) == 0.0);
    CHECK(two_mass_run(1600, DFO_SCHEME_PAPER, xp, NULL, NULL) == 0.0);
    printf("  two masses at T/1600: consistent (%.6f, %.6f), paper (%.6f, %.6f), located (%.6f, %.6f)\n", xc[0],
           xc[1], xp[0], xp[1], x[2][0], x[2][1]);
    CHECK(fabs(xc[0] - x[2][0]) < 2e-2 && fabs(xc[1] - x[2][1]) < 2e-2);
}

/* ---- the dense friction solver against enumeration ------------------------------------------ */

static void test_dense_lcp(checks *T)
{
    rng R = {0x2545F4914F6CDD1DULL};
    long bad = 0, cases = 0;
    double worst = 0.0;
    for (int c = 0; c < 300; c++) {
        dense_model D;
        memset(&D, 0, sizeof D);
        D.n = 3;
        for (size_t i = 0; i < 3; i++) {
            D.M[i * 3 + i] = rng_range(&R, 0.5, 2.0);
            D.K[i * 3 + i] = rng_range(&R, 0.5, 2.0);
        }
        D.K[1] = D.K[3] = -0.3;
        D.K[5] = D.K[7] = -0.2;
        static const size_t i01[2] = {0, 1}, i12[2] = {1, 2}, i2[1] = {2};
        static const double wd[2] = {1.0, -1.0}, w1[1] = {1.0};
        const eng_row rows[3] = {{2, i01, wd}, {2, i12, wd}, {1, i2, w1}};
        const double N[3] = {1, 1, 1}, ms[3] = {1, 1, 1}, mk[3] = {1, 1, 1};
        eng_setup S = setup_of(&D, 3, rows, N, ms, mk, NULL, 0.0, 0.1, DFO_SCHEME_LOCATED);
        eng *E = eng_create(&S, &ALLOC, NULL);
        CHECK(op_factor(&D, ENG_SLOT_GRID, 10.0, 1.0, 0.03));
        double p[3], lim[3], vb[3];
        for (int i = 0; i < 3; i++) {
            p[i] = rng_range(&R, -5.0, 5.0);
            lim[i] = rng_range(&R, 0.0, 3.0);
            vb[i] = (c % 3 == 0) ? rng_range(&R, -0.3, 0.3) : 0.0;
        }
        eng_problem P = {ENG_SLOT_GRID, 0.1, 10.0, 1.0, 0.03, p, vb, lim, N, NULL, NULL};
        int mode[3];
        for (int i = 0; i < 3; i++) mode[i] = rng_int(&R, 3) - 1;
        double V1[3], f[3];
        const eng_status st = eng_dense_friction(E, &P, ENG_SOLVE_LCP, mode, V1, f, NULL);
        cases++;
        if (st != ENG_OK) { bad++; eng_destroy(E); continue; }
        /* complementarity of every contact, and agreement with the enumeration's solution */
        double scale = 1.0;
        for (int j = 0; j < 3; j++) {
            double v = -vb[j];
            for (size_t k = 0; k < rows[j].nnz; k++) v += rows[j].w[k] * V1[rows[j].idx[k]];
            double viol = 0.0;
            if (mode[j] == 0) viol = fmax(fabs(v), fmax(fabs(f[j]) - lim[j], 0.0));
            else viol = fmax(fmax(-mode[j] * v, 0.0), fabs(f[j] + mode[j] * lim[j]));
            worst = fmax(worst, viol / scale);
        }
        /* the enumeration: every mode set's basis solve; the feasible ones agree on V1 */
        int found = 0;
        double dv = 0.0;
        for (int code = 0; code < 27; code++) {
            int md[3] = {code % 3 - 1, (code / 3) % 3 - 1, code / 9 - 1};
            double Ve[3], fe[3];
            if (eng_dense_friction(E, &P, ENG_SOLVE_BASIS, md, Ve, fe, NULL) != ENG_OK) continue;
            int feas = 1;
            for (int j = 0; j < 3; j++) {
                double v = -vb[j];
                for (size_t k = 0; k < rows[j].nnz; k++) v += rows[j].w[k] * Ve[rows[j].idx[k]];
                if (md[j] == 0) feas &= fabs(fe[j]) <= lim[j] * (1.0 + 1e-12) + 1e-12;
                else feas &= md[j] * v >= -1e-12;
            }
            if (!feas) continue;
            found = 1;
            for (int i = 0; i < 3; i++) dv = fmax(dv, fabs(Ve[i] - V1[i]));
        }
        CHECK(found);
        worst = fmax(worst, dv);
        eng_destroy(E);
    }
    printf("  dense friction, 300 random 3-contact problems: %ld unsolved, worst violation / disagreement %.2e\n", bad,
           worst);
    check_context(T, "dense friction LCP");
    CHECK_INT(0, bad);
    CHECK(worst < 1e-10);
}

/* ---- stop at switch, state copy ------------------------------------------------------------ */

typedef struct {
    int count;
    double t;
} switch_log;

static void on_switch(void *ctx, double t, size_t contact, const eng_state *s, int from, int to)
{
    (void)contact; (void)s; (void)from; (void)to;
    switch_log *L = ctx;
    L->count++;
    L->t = t;
}

static void test_stop_and_copy(checks *T)
{
    check_context(T, "stop at switch, state copy");
    dense_model D;
    eng_row rows[2];
    two_mass_model(&D, rows);
    const double N[2] = {0.5, 0.3}, ms[2] = {0.6, 0.8}, mk[2] = {0.45, 0.6}, Pc[2] = {1.0, 0.0};
    eng_setup S = setup_of(&D, 2, rows, N, ms, mk, Pc, 0.8, 1e-2, DFO_SCHEME_LOCATED);
    eng_state a, b;
    const eng_inputs in = {NULL, NULL, NULL, {NULL, NULL}, {NULL, NULL}, 0.0};
    eng *E = eng_begin(&S, &in, &a);
    eng_state_init(E, &b, 0);
    eng_state_copy(&b, &a);
    switch_log L = {0, 0.0};
    const eng_hooks stop = {on_switch, &L, NULL, 1, 0, 0};
    int stops = 0;
    while (a.t < 20.0 && stops < 1000) {
        const eng_status st = eng_advance(E, &in, &a, 20.0, &stop);
        CHECK(st == ENG_OK || st == ENG_SWITCHED);
        if (st == ENG_SWITCHED) { stops++; CHECK(a.t == L.t); }
        if (st != ENG_OK && st != ENG_SWITCHED) break;
    }
    CHECK_INT(ENG_OK, eng_advance(E, &in, &b, 20.0, NULL));
    printf("  stop at switch: %d stops, %lld switches; straight run %lld switches; x %.12f / %.12f\n", stops,
           a.switches, b.switches, a.X[0], b.X[0]);
    CHECK(stops >= 3);
    CHECK_INT(b.switches, a.switches);
    CHECK(fabs(a.X[0] - b.X[0]) < 1e-9 && fabs(a.X[1] - b.X[1]) < 1e-9);
    eng_state_free(E, &a);
    eng_state_free(E, &b);
    eng_destroy(E);
}

int main(void)
{
    checks C = {0, 0, NULL, {0}};
    checks *T = &C;
    test_block_orders(T);
    test_chains(T);
    test_two_masses(T);
    test_dense_lcp(T);
    test_vs_oscillator(T);
    test_stop_and_copy(T);
    return checks_done(T, "test_engine");
}
