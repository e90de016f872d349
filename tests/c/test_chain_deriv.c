/* The chain's coupling at second order through its instance core (fmu_src/models/chain/
 * chain_inst_deriv.c, the model API of fmu_src/core/instance.h), driven without FMI headers, at the
 * FMI 2.0 build's n = 2 (element value references):
 *
 * 1. input derivatives that are zero give the bits of a run without them (every scheme);
 * 2. an FMU state taken with input derivatives set carries them (copy and serialisation);
 * 3. directional and adjoint derivatives of a and F_friction against central differences of the
 *    outputs (1e-7), in every mode (both sliding, one stuck, both stuck), every scheme, before and
 *    after inputs are set;
 * 4. output derivatives of x and v against differences of the trajectory;
 * 5. intermediate input points: unchanged inputs give the bits of a plain step; inputs set at every
 *    point give the bits of communication steps of h;
 * 6. the error sentences (order, variable, causality, a derivative at a switch, non-finite values);
 * 7. a long chain with ramped inputs: its clusters against the whole chain.
 *
 * With arguments it is the driver of tests/test_coupling_chain.py instead:
 *   test_chain_deriv run scheme=S h=H_INT H=H_COMM t_end=T order=K F_amp=a1,a2 F_omega=W F_lin=b1,b2
 *                    F_quad=q1,q2 [N_lin=.. N_quad=.. m=.. k=.. c=.. P0=.. phi=.. N=.. mu_s=.. chi=.. x0=.. v0=.. (2 values
 *                    each) omega=.. k_end=..]
 * runs the chain with F_ext_i(t) = F_amp_i sin(F_omega t) + F_lin_i t + F_quad_i t^2 / 2 given at every
 * communication point with its derivatives up to order K (0: held), N_ext_i(t) = N_lin_i t +
 * N_quad_i t^2 / 2 likewise where given, and prints "t,x1,x2,v1,v2" per
 * point. Built for the FMI 3.0 core (chain_deriv_n1: n = 1 set in configuration mode) it is that
 * driver only, with one block, printing "t,x1,v1". */
#include "chain_instance.h"
#include "fmu_state.h"
#include "instance.h"
#include "check.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if defined(DFO_CHAIN_FIXED_N)
#define N_BLOCKS 2
/* FMI 2.0 element i (0-based) of an array */
static unsigned int el(unsigned int vr, size_t i) { return vr + (unsigned int)i + 1u; }
#else
/* the FMI 3.0 build's core at n = 1 (the driver only): an array is its one value */
#define N_BLOCKS 1
static unsigned int el(unsigned int vr, size_t i)
{
    (void)i;
    return vr;
}
#endif

typedef struct {
    char last[1024];
    int errors;
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
    (void)category;
    if (status == DFO_INST_ERROR) {
        L->errors++;
        snprintf(L->last, sizeof L->last, "%s", message);
    }
}

typedef struct {
    double m[2], k[2], c[2], P0[2], phi[2], N[2], mu_s[2], chi[2], x0[2], v0[2];
    double omega, h, k_end;
    int scheme;
} params;

static params base_params(int scheme)
{
    params p = {{1.0, 1.5}, {4.0, 2.0}, {0.05, 0.02}, {1.0, 0.6}, {0.0, 0.7}, {0.5, 0.4}, {0.5, 0.4}, {0.7, 0.8},
                {0.0, 0.0}, {0.0, 0.0}, 1.3, 1e-3, 0.5, 3};
    p.scheme = scheme;
    return p;
}

static dfo_lifecycle *start(checks *T, host_log *L, const params *p)
{
    const dfo_host host = {L, h_alloc, h_free, h_log};
    dfo_lifecycle *in = dfo_inst_new(&host, "deriv", 0);
    CHECK(in != NULL);
    if (!in) return NULL;
#if !defined(DFO_CHAIN_FIXED_N)
    const unsigned int vn = VR_n;
    const unsigned long long one = 1;
    CHECK(dfo_inst_enter_config(in, "config") == DFO_INST_OK);
    CHECK(dfo_inst_set_uint64(in, "set", &vn, 1, &one) == DFO_INST_OK);
    CHECK(dfo_inst_exit_config(in, "config") == DFO_INST_OK);
#endif
    CHECK(dfo_inst_setup(in, "setup", 0.0, 0, 0.0) == DFO_INST_OK);
    const struct {
        unsigned int vr;
        const double *x;
    } arrays[] = {{VR_m, p->m}, {VR_k, p->k}, {VR_c, p->c}, {VR_P0, p->P0}, {VR_phi, p->phi}, {VR_N, p->N},
                  {VR_mu_s, p->mu_s}, {VR_chi, p->chi}, {VR_x0, p->x0}, {VR_v0, p->v0}};
    for (size_t a = 0; a < sizeof arrays / sizeof arrays[0]; a++)
        for (size_t i = 0; i < N_BLOCKS; i++) {
            const unsigned int vr = el(arrays[a].vr, i);
            CHECK(dfo_inst_set_real(in, "set", &vr, 1, &arrays[a].x[i]) == DFO_INST_OK);
        }
    const unsigned int svr[3] = {VR_omega, VR_h, VR_k_end};
    const double sval[3] = {p->omega, p->h, p->k_end};
    CHECK(dfo_inst_set_real(in, "set", svr, 3, sval) == DFO_INST_OK);
    const unsigned int vs = VR_scheme;
    CHECK(dfo_inst_set_int(in, "set", &vs, 1, &p->scheme) == DFO_INST_OK);
    CHECK(dfo_inst_enter_init(in) == DFO_INST_OK);
    CHECK(dfo_inst_exit_init(in, "exit") == DFO_INST_OK);
    return in;
}

static double get1(dfo_lifecycle *in, unsigned int vr, size_t i)
{
    const unsigned int r = el(vr, i);
    double x = NAN;
    (void)dfo_inst_get_real(in, "get", &r, 1, &x);
    return x;
}

static void set1(dfo_lifecycle *in, unsigned int vr, size_t i, double x)
{
    const unsigned int r = el(vr, i);
    (void)dfo_inst_set_real(in, "set", &r, 1, &x);
}

#if defined(DFO_CHAIN_FIXED_N) /* the checks (the FMI 2.0 build's n = 2) */
static int mode_of(dfo_lifecycle *in, size_t i)
{
    const unsigned int r = el(VR_mode, i);
    int m = 9;
    (void)dfo_inst_get_int(in, "get", &r, 1, &m);
    return m;
}

static int same_bits(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

/* the outputs x, v, a, F_friction of both blocks bit for bit */
static int same_outputs(dfo_lifecycle *a, dfo_lifecycle *b)
{
    const unsigned int vrs[4] = {VR_x, VR_v, VR_a, VR_F_friction};
    int ok = 1;
    for (int k = 0; k < 4; k++)
        for (size_t i = 0; i < N_BLOCKS; i++) ok &= same_bits(get1(a, vrs[k], i), get1(b, vrs[k], i));
    return ok;
}

/* the master's input: a smooth force */
static double force(size_t i, double t) { return (i == 0 ? 0.4 : -0.3) * sin(0.9 * t + (double)i); }

/* 1. zero derivatives: the bits of a run without them */
static void test_zero_derivatives(checks *T)
{
    for (int scheme = 1; scheme <= 3; scheme++) {
        check_context(T, "zero derivatives, scheme %d", scheme);
        host_log La = {{0}, 0}, Lb = {{0}, 0};
        const params p = base_params(scheme);
        dfo_lifecycle *a = start(T, &La, &p), *b = start(T, &Lb, &p);
        int ok = 1;
        double t = 0.0;
        for (int s = 0; s < 200; s++) {
            for (size_t i = 0; i < N_BLOCKS; i++) {
                set1(a, VR_F_ext, i, force(i, t));
                set1(b, VR_F_ext, i, force(i, t));
                set1(b, VR_N_ext, i, 0.0);
                const unsigned int r[2] = {el(VR_F_ext, i), el(VR_N_ext, i)};
                const int o1[2] = {1, 1}, o2[2] = {2, 2};
                const double z[2] = {0.0, 0.0};
                ok &= dfo_inst_set_input_derivatives(b, "sid", r, 2, o1, z) == DFO_INST_OK;
                ok &= dfo_inst_set_input_derivatives(b, "sid", r, 2, o2, z) == DFO_INST_OK;
            }
            ok &= dfo_inst_do_step(a, "doStep", t, 0.05, 0, NULL) == DFO_INST_OK;
            ok &= dfo_inst_do_step(b, "doStep", t, 0.05, 0, NULL) == DFO_INST_OK;
            t = dfo_inst_time(a);
            ok &= same_outputs(a, b);
        }
        CHECK(ok);
        CHECK(chn(a)->v.s.switches > 0); /* stick-slip in the run */
        dfo_inst_delete(a);
        dfo_inst_delete(b);
    }
}

/* 2. an FMU state carries the input derivatives */
static void test_state(checks *T)
{
    check_context(T, "FMU state with input derivatives");
    host_log L = {{0}, 0};
    const params p = base_params(3);
    dfo_lifecycle *a = start(T, &L, &p);
    CHECK(dfo_inst_do_step(a, "doStep", 0.0, 1.0, 0, NULL) == DFO_INST_OK);
    const unsigned int r[2] = {el(VR_F_ext, 0), el(VR_N_ext, 1)};
    const int o[2] = {1, 2};
    const double d[2] = {0.7, -0.4};
    CHECK(dfo_inst_set_input_derivatives(a, "sid", r, 2, o, d) == DFO_INST_OK);
    void *st = NULL, *st2 = NULL;
    CHECK(dfo_inst_get_state(a, "get", &st) == DFO_INST_OK);
    const size_t size = dfo_inst_state_size(a, st);
    unsigned char *buf = (unsigned char *)malloc(size);
    CHECK(dfo_inst_serialize(a, "ser", st, buf, size) == DFO_INST_OK);
    CHECK(dfo_inst_deserialize(a, "deser", buf, size, &st2) == DFO_INST_OK);
    CHECK(dfo_inst_do_step(a, "doStep", 1.0, 0.5, 0, NULL) == DFO_INST_OK);
    const double x_ramp = get1(a, VR_x, 0), F_after = get1(a, VR_F_ext, 0);
    CHECK_NEAR(0.0 + 0.7 * 0.5, F_after, 1e-15); /* the input took its ramp's value at the step's end */
    CHECK(dfo_inst_set_state(a, "set", st2) == DFO_INST_OK);
    CHECK(dfo_inst_do_step(a, "doStep", 1.0, 0.5, 0, NULL) == DFO_INST_OK);
    CHECK(same_bits(x_ramp, get1(a, VR_x, 0)));
    CHECK(dfo_inst_set_state(a, "set", st) == DFO_INST_OK);
    CHECK(dfo_inst_do_step(a, "doStep", 1.0, 0.5, 0, NULL) == DFO_INST_OK);
    CHECK(same_bits(x_ramp, get1(a, VR_x, 0)));
    /* the derivatives held for one step: the next is held */
    CHECK_SAME(0.0, chn(a)->v.ud[0]);
    CHECK(chn(a)->v.ud_set == 0);
    /* a body of the size without the derivatives (the chain's fields before them) is refused */
    void *st3 = NULL;
    CHECK(dfo_inst_deserialize(a, "deser", buf, size - 8 * 8 - 4 - 16, &st3) == DFO_INST_ERROR && st3 == NULL);
    free(buf);
    dfo_inst_free_state(a, "free", &st);
    dfo_inst_free_state(a, "free", &st2);
    dfo_inst_delete(a);
}

/* 3. directional derivatives against central differences of the outputs */
static double fd_entry(dfo_lifecycle *in, unsigned int out_vr, size_t i, unsigned int in_vr, size_t j, double delta)
{
    const double u0 = get1(in, in_vr, j);
    set1(in, in_vr, j, u0 + delta);
    const double yp = get1(in, out_vr, i);
    set1(in, in_vr, j, u0 - delta);
    const double ym = get1(in, out_vr, i);
    set1(in, in_vr, j, u0);
    return (yp - ym) / (2.0 * delta);
}

static double max_jac_error(checks *T, dfo_lifecycle *in)
{
    const unsigned int outs[4] = {VR_x, VR_v, VR_a, VR_F_friction}, ins[2] = {VR_F_ext, VR_N_ext};
    unsigned int U[8], K[4];
    for (int k = 0; k < 4; k++)
        for (size_t i = 0; i < N_BLOCKS; i++) U[k * 2 + (int)i] = el(outs[k], i);
    for (int k = 0; k < 2; k++)
        for (size_t j = 0; j < N_BLOCKS; j++) K[k * 2 + (int)j] = el(ins[k], j);
    double err = 0.0;
    for (int c = 0; c < 4; c++) {
        double seed[4] = {0, 0, 0, 0}, col[8], row[4];
        seed[c] = 1.0;
        CHECK(dfo_inst_directional(in, "dd", U, 8, K, 4, seed, col) == DFO_INST_OK);
        for (int r = 0; r < 8; r++) {
            const double fd = fd_entry(in, outs[r / 2], (size_t)(r % 2), ins[c / 2], (size_t)(c % 2), 1e-6);
            err = fmax(err, fabs(fd - col[r]));
            double aseed[8] = {0, 0, 0, 0, 0, 0, 0, 0};
            aseed[r] = 1.0;
            CHECK(dfo_inst_adjoint(in, "ad", U, 8, K, 4, aseed, row) == DFO_INST_OK);
            CHECK(same_bits(row[c], col[r])); /* the adjoint is the transpose */
        }
    }
    return err;
}

static void test_directional(checks *T)
{
    /* (mode of block 1, of block 2) at the start: sliding from v0, stuck where the net force is
     * inside a large limit */
    const struct {
        const char *name;
        double v0[2], N[2];
        int m0, m1;
    } cases[] = {{"both sliding", {0.5, -0.3}, {0.5, 0.4}, 1, -1},
                 {"one stuck", {0.5, 0.0}, {0.5, 5.0}, 1, 0},
                 {"both stuck", {0.0, 0.0}, {5.0, 5.0}, 0, 0}};
    double worst = 0.0;
    for (int scheme = 1; scheme <= 3; scheme++)
        for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
            check_context(T, "directional, scheme %d, %s", scheme, cases[c].name);
            host_log L = {{0}, 0};
            params p = base_params(scheme);
            memcpy(p.v0, cases[c].v0, sizeof p.v0);
            memcpy(p.N, cases[c].N, sizeof p.N);
            dfo_lifecycle *in = start(T, &L, &p);
            /* a short step keeps the modes; then the inputs set since it (u != u_used) */
            CHECK(dfo_inst_do_step(in, "doStep", 0.0, 0.01, 0, NULL) == DFO_INST_OK);
            CHECK_INT(cases[c].m0, mode_of(in, 0));
            CHECK_INT(cases[c].m1, mode_of(in, 1));
            const double e1 = max_jac_error(T, in);
            set1(in, VR_F_ext, 0, 0.3);
            set1(in, VR_N_ext, 1, 0.2);
            const double e2 = max_jac_error(T, in);
            CHECK(e1 < 1e-7);
            CHECK(e2 < 1e-7);
            worst = fmax(worst, fmax(e1, e2));
            /* the sliding block's feed-through, by hand: da/dF_ext = 1/m, da/dN_ext = -s mu_k / m */
            if (cases[c].m0 != 0) {
                const unsigned int u = el(VR_a, 0), k2[2] = {el(VR_F_ext, 0), el(VR_N_ext, 0)};
                const double seed[2] = {1.0, 1.0};
                double s = 0.0;
                CHECK(dfo_inst_directional(in, "dd", &u, 1, k2, 2, seed, &s) == DFO_INST_OK);
                CHECK_NEAR((1.0 - cases[c].m0 * p.chi[0] * p.mu_s[0]) / p.m[0], s, 1e-15);
            }
            dfo_inst_delete(in);
        }
    printf("directional derivatives: max |J - central difference| = %.3g over 3 schemes x 3 mode sets x 2 points\n",
           worst);
}

/* 4. output derivatives against differences of the trajectory */
static void test_output_derivatives(checks *T)
{
    check_context(T, "output derivatives");
    host_log L = {{0}, 0};
    params p = base_params(3);
    p.v0[0] = 0.8;
    p.v0[1] = -0.5;
    p.N[0] = p.N[1] = 0.1;
    p.h = 1e-5;
    dfo_lifecycle *in = start(T, &L, &p);
    const double t1 = 0.3, d = 2e-3;
    CHECK(dfo_inst_do_step(in, "doStep", 0.0, t1 - d, 0, NULL) == DFO_INST_OK);
    double xm[2], vm[2], am[2], xp[2], vp[2], ap[2], der[4][2];
    for (size_t i = 0; i < 2; i++) { xm[i] = get1(in, VR_x, i); vm[i] = get1(in, VR_v, i); am[i] = get1(in, VR_a, i); }
    CHECK(dfo_inst_do_step(in, "doStep", t1 - d, d, 0, NULL) == DFO_INST_OK);
    const unsigned int r[4] = {el(VR_x, 0), el(VR_x, 1), el(VR_v, 0), el(VR_v, 1)};
    for (int o = 1; o <= 2; o++) {
        const int ord[4] = {o, o, o, o};
        double val[4];
        CHECK(dfo_inst_get_output_derivatives(in, "god", r, 4, ord, val) == DFO_INST_OK);
        for (int k = 0; k < 2; k++) { der[(o - 1) * 2 + k][0] = val[k * 2]; der[(o - 1) * 2 + k][1] = val[k * 2 + 1]; }
    }
    /* der[0]: x', der[1]: v', der[2]: x'', der[3]: v'' */
    for (size_t i = 0; i < 2; i++) {
        CHECK_SAME(get1(in, VR_v, i), der[0][i]);
        CHECK_SAME(get1(in, VR_a, i), der[1][i]);
        CHECK_SAME(get1(in, VR_a, i), der[2][i]);
    }
    CHECK(mode_of(in, 0) == 1 && mode_of(in, 1) == -1);
    CHECK(dfo_inst_do_step(in, "doStep", t1, d, 0, NULL) == DFO_INST_OK);
    for (size_t i = 0; i < 2; i++) { xp[i] = get1(in, VR_x, i); vp[i] = get1(in, VR_v, i); ap[i] = get1(in, VR_a, i); }
    double ex = 0.0, ev = 0.0, ea = 0.0;
    for (size_t i = 0; i < 2; i++) {
        ex = fmax(ex, fabs((xp[i] - xm[i]) / (2 * d) - der[0][i]));
        ev = fmax(ev, fabs((vp[i] - vm[i]) / (2 * d) - der[1][i]));
        ea = fmax(ea, fabs((ap[i] - am[i]) / (2 * d) - der[3][i]));
    }
    printf("output derivatives against central differences of the trajectory (d = %g): x' %.3g, v' %.3g, v'' %.3g\n",
           d, ex, ev, ea);
    CHECK(ex < 1e-5);
    CHECK(ev < 1e-5);
    CHECK(ea < 1e-4);
    /* a stuck block: v' = v'' = 0 */
    dfo_inst_delete(in);
    p = base_params(3);
    p.N[1] = 5.0;
    in = start(T, &L, &p);
    CHECK(dfo_inst_do_step(in, "doStep", 0.0, 0.01, 0, NULL) == DFO_INST_OK);
    CHECK(mode_of(in, 1) == 0);
    const unsigned int rv[2] = {el(VR_v, 1), el(VR_v, 1)};
    const int o12[2] = {1, 2};
    double z[2] = {1, 1};
    CHECK(dfo_inst_get_output_derivatives(in, "god", rv, 2, o12, z) == DFO_INST_OK);
    CHECK_SAME(0.0, z[0]);
    CHECK_SAME(0.0, z[1]);
    dfo_inst_delete(in);
}

/* 5. intermediate input points */
typedef struct {
    dfo_lifecycle *in;
    int calls, set, stop_at; /* stop_at > 0: set F_ext = 0.25 at that call and ask for an early return */
    double last_t;
} point_ctx;

static int at_point(void *ctx, double t, int can_return_early, int set_requested)
{
    point_ctx *P = (point_ctx *)ctx;
    if (!set_requested) return 0;
    P->calls++;
    P->last_t = t;
    if (P->stop_at > 0 && P->calls == P->stop_at && can_return_early) {
        for (size_t i = 0; i < N_BLOCKS; i++) set1(P->in, VR_F_ext, i, 0.25);
        return 1;
    }
    if (P->set)
        for (size_t i = 0; i < N_BLOCKS; i++) set1(P->in, VR_F_ext, i, force(i, t));
    return 0;
}

static void test_input_points(checks *T)
{
    for (int scheme = 1; scheme <= 3; scheme++) {
        check_context(T, "input points, scheme %d", scheme);
        host_log L = {{0}, 0};
        const params p = base_params(scheme);
        dfo_lifecycle *a = start(T, &L, &p), *b = start(T, &L, &p), *c = start(T, &L, &p);
        point_ctx P = {b, 0, 0, 0, 0.0};
        dfo_event_opts opt;
        memset(&opt, 0, sizeof opt);
        opt.intermediate = at_point;
        opt.ctx = &P;
        opt.input_points = 1;
        const double H = 0.05, h = p.h;
        int ok = 1;
        double t = 0.0;
        for (int s = 0; s < 60; s++) {
            dfo_step_result res;
            memset(&res, 0, sizeof res);
            ok &= dfo_inst_do_step(a, "doStep", t, H, 0, NULL) == DFO_INST_OK;
            ok &= dfo_inst_do_step_events(b, "doStep", t, H, &opt, &res) == DFO_INST_OK && res.t_reached == t + H;
            t = dfo_inst_time(a);
            ok &= same_outputs(a, b);
        }
        CHECK(ok);
        CHECK_INT(60 * 49, P.calls); /* every internal step but the last of each communication step */
        /* inputs set at every point = communication steps of h with them */
        P.in = c;
        P.set = 1;
        P.calls = 0;
        dfo_inst_delete(a);
        a = start(T, &L, &p);
        double ta = 0.0, tc = 0.0;
        ok = 1;
        for (int s = 0; s < 20; s++) {
            for (size_t i = 0; i < N_BLOCKS; i++) set1(c, VR_F_ext, i, force(i, tc));
            const double tc_prev = tc;
            dfo_step_result res;
            memset(&res, 0, sizeof res);
            ok &= dfo_inst_do_step_events(c, "doStep", tc, H, &opt, &res) == DFO_INST_OK;
            tc = dfo_inst_time(c);
            for (int g = 0; g < 50; g++) {
                const double tg = (g == 0) ? tc_prev : chn(a)->v.s.t; /* (the host's time at the step's start) */
                for (size_t i = 0; i < N_BLOCKS; i++) set1(a, VR_F_ext, i, force(i, tg));
                ok &= dfo_inst_do_step(a, "doStep", ta, (g == 49) ? tc - ta : h, 0, NULL) == DFO_INST_OK;
                ta = dfo_inst_time(a);
            }
            for (size_t i = 0; i < N_BLOCKS; i++)
                ok &= same_bits(get1(a, VR_x, i), get1(c, VR_x, i)) && same_bits(get1(a, VR_v, i), get1(c, VR_v, i));
        }
        CHECK(ok);
        /* an early return asked at the 10th point, inputs set there: they hold from there on */
        dfo_inst_delete(a);
        dfo_inst_delete(b);
        a = start(T, &L, &p);
        b = start(T, &L, &p);
        point_ctx Q = {b, 0, 0, 10, 0.0};
        opt.ctx = &Q;
        opt.early_return = 1;
        dfo_step_result res;
        memset(&res, 0, sizeof res);
        CHECK(dfo_inst_do_step_events(b, "doStep", 0.0, H, &opt, &res) == DFO_INST_OK);
        CHECK(res.early == 1 && res.event == 0);
        const double tp = res.t_reached;
        CHECK_SAME(chn(b)->v.s.t, tp);
        opt.intermediate = NULL;
        opt.input_points = 0;
        opt.early_return = 0;
        memset(&res, 0, sizeof res);
        CHECK(dfo_inst_do_step_events(b, "doStep", tp, H - tp, &opt, &res) == DFO_INST_OK);
        CHECK(dfo_inst_do_step(a, "doStep", 0.0, tp, 0, NULL) == DFO_INST_OK);
        for (size_t i = 0; i < N_BLOCKS; i++) set1(a, VR_F_ext, i, 0.25);
        CHECK(dfo_inst_do_step(a, "doStep", tp, H - tp, 0, NULL) == DFO_INST_OK);
        CHECK(same_outputs(a, b));
        CHECK_SAME(0.25, get1(b, VR_F_ext, 0));
        opt.intermediate = at_point;
        opt.input_points = 1;
        opt.ctx = &P;
        dfo_inst_delete(a);
        dfo_inst_delete(b);
        dfo_inst_delete(c);
    }
}

/* 7. a long chain with ramped inputs: the located step's clusters (n > 2 w + 3) against the whole
 * chain's located step (stop_at_switch takes it): the same switches, positions within 1e-6 (they
 * split different sets of blocks' steps at a switch) */
static void *std_alloc(void *env, size_t nobj, size_t size)
{
    (void)env;
    return calloc(nobj, size);
}

static void std_release(void *env, void *obj)
{
    (void)env;
    free(obj);
}

static void test_long_chain_ramp(checks *T)
{
    check_context(T, "long chain, ramped inputs");
    enum { NB = 40 };
    double m[NB], k[NB], c[NB], P0[NB], phi[NB], N[NB], mu_s[NB], chi[NB], x0[NB], v0[NB], F[NB], dF[NB], dN[NB];
    for (size_t i = 0; i < NB; i++) {
        m[i] = 1.0; k[i] = 1.0; c[i] = 0.0; P0[i] = (i == 0) ? 1.0 : 0.0; phi[i] = 0.0; N[i] = 0.8;
        mu_s[i] = 0.5; chi[i] = 0.7; x0[i] = 0.0; v0[i] = 0.0; F[i] = 0.0;
        dF[i] = 0.02 * (double)(i % 5); dN[i] = -0.01;
    }
    const chain_params p = {NB, m, k, c, P0, phi, N, mu_s, chi, x0, v0, 0.0, 0.0, 0.5, 0.012566370614359173 /* T / 1000, T = 4 pi */, -0.1, 3, 0, NULL, NULL, 0, NULL, NULL};
    const chain_alloc al = {std_alloc, std_release, NULL};
    chain_model *A = chain_create(&p, &al, NULL), *B = chain_create(&p, &al, NULL);
    chain_state sa, sb;
    CHECK(A && B && chain_state_init(A, &sa) && chain_state_init(B, &sb));
    const chain_inputs in = {F, NULL};
    const chain_ramp r = {{dF, NULL}, {dN, NULL}, 0.0};
    chain_start(A, &in, 0.0, &sa);
    chain_start(B, &in, 0.0, &sb);
    const double t_end = 12.0;
    CHECK(chain_advance_ramped(A, &in, &r, &sa, t_end, 0, NULL, NULL) == CHAIN_OK);
    int guard = 0;
    chain_status st;
    while ((st = chain_advance_ramped(B, &in, &r, &sb, t_end, 1, NULL, NULL)) == CHAIN_SWITCHED && guard++ < 100000) {}
    CHECK(st == CHAIN_OK);
    double d = 0.0;
    for (size_t i = 0; i < NB; i++) d = fmax(d, fabs(sa.X[i] - sb.X[i]));
    printf("long chain (n = %d) with ramped inputs: clusters against the whole chain, max |dx| = %.3g, %lld switches\n",
           NB, d, sa.switches);
    CHECK(sa.switches > 20 && sa.switches == sb.switches);
    CHECK(d < 1e-6); /* measured 4.6e-7 (a sub-step to a switch with the internal step's loads for
                      * every block, before they were the root's: 3.1e-5) */
    chain_state_free(A, &sa);
    chain_state_free(B, &sb);
    chain_destroy(A);
    chain_destroy(B);
}

/* 6. errors */
static int says(const host_log *L, const char *a, const char *b)
{
    return strstr(L->last, a) != NULL && (!b || strstr(L->last, b) != NULL);
}

static void test_errors(checks *T)
{
    check_context(T, "errors");
    host_log L = {{0}, 0};
    params p = base_params(3);
    dfo_lifecycle *in = start(T, &L, &p);
    const unsigned int f1 = el(VR_F_ext, 0), x2 = el(VR_x, 1), a1 = el(VR_a, 0), v1 = el(VR_v, 0);
    int o = 3;
    double d = 1.0;
    CHECK(dfo_inst_set_input_derivatives(in, "fmi2SetRealInputDerivatives", &f1, 1, &o, &d) == DFO_INST_ERROR);
    CHECK(says(&L, "order 3 of the derivative of F_ext[1]", "(valid: 1 ... 2)"));
    o = 1;
    CHECK(dfo_inst_set_input_derivatives(in, "fmi2SetRealInputDerivatives", &x2, 1, &o, &d) == DFO_INST_ERROR);
    CHECK(says(&L, "x[2] (value reference 1300002) is not a real input", NULL));
    d = NAN;
    CHECK(dfo_inst_set_input_derivatives(in, "fmi2SetRealInputDerivatives", &f1, 1, &o, &d) == DFO_INST_ERROR);
    CHECK(says(&L, "first derivative of F_ext[1]", "valid range: finite"));
    CHECK(chn(in)->v.ud_set == 0); /* rejected: nothing stored */
    CHECK(dfo_inst_get_output_derivatives(in, "fmi2GetRealOutputDerivatives", &a1, 1, &o, &d) == DFO_INST_ERROR);
    CHECK(says(&L, "a[1] (value reference 1500001) has no output derivatives", NULL));
    o = 0;
    CHECK(dfo_inst_get_output_derivatives(in, "fmi2GetRealOutputDerivatives", &v1, 1, &o, &d) == DFO_INST_ERROR);
    CHECK(says(&L, "order 0 of the derivative of v[1]", NULL));
    double seed = 1.0, sens = 0.0;
    CHECK(dfo_inst_directional(in, "fmi2GetDirectionalDerivative", &f1, 1, &f1, 1, &seed, &sens) == DFO_INST_ERROR);
    CHECK(says(&L, "F_ext[1] (value reference 1100001) is not a real output", NULL));
    CHECK(dfo_inst_directional(in, "fmi2GetDirectionalDerivative", &a1, 1, &x2, 1, &seed, &sens) == DFO_INST_ERROR);
    CHECK(says(&L, "x[2] (value reference 1300002) is not an input", NULL));
    /* at a switch: a step that ends on it */
    double reached = 0.0;
    CHECK(dfo_inst_do_step(in, "doStep", 0.0, 10.0, DFO_STEP_STOP_AT_SWITCH, &reached) == DFO_INST_OK);
    CHECK(reached < 10.0);
    const long long b = chn(in)->v.sw_block;
    CHECK(b == 0 || b == 1);
    const unsigned int vb = el(VR_v, (size_t)b), xb = el(VR_x, (size_t)b);
    o = 1;
    CHECK(dfo_inst_get_output_derivatives(in, "fmi2GetRealOutputDerivatives", &xb, 1, &o, &d) == DFO_INST_OK);
    CHECK_SAME(get1(in, VR_v, (size_t)b), d);
    CHECK(dfo_inst_get_output_derivatives(in, "fmi2GetRealOutputDerivatives", &vb, 1, &o, &d) == DFO_INST_ERROR);
    char want[80];
    snprintf(want, sizeof want, "the first derivative of v[%lld]", b + 1);
    CHECK(says(&L, want, "does not exist at t = "));
    printf("at a switch: %s\n", L.last);
    dfo_inst_delete(in);
    /* before initialisation ends */
    const dfo_host host = {&L, h_alloc, h_free, h_log};
    in = dfo_inst_new(&host, "deriv", 0);
    o = 1;
    CHECK(dfo_inst_get_output_derivatives(in, "fmi2GetRealOutputDerivatives", &v1, 1, &o, &d) == DFO_INST_ERROR);
    CHECK(says(&L, "once initialisation has ended", NULL));
    dfo_inst_delete(in);
}

#endif /* DFO_CHAIN_FIXED_N */

/* ---- the driver of tests/test_coupling_chain.py ---- */

static int parse2(const char *s, double out[2])
{
    char *end = NULL;
    out[0] = strtod(s, &end);
    if (*end != ',') { out[1] = out[0]; return *end == '\0'; }
    out[1] = strtod(end + 1, &end);
    return *end == '\0';
}

static int run_driver(int argc, char **argv)
{
    checks C = {0, 0, NULL, {0}};
    checks *T = &C;
    params p = base_params(3);
    double H = 0.01, t_end = 1.0, F_amp[2] = {0, 0}, F_omega = 1.0, F_lin[2] = {0, 0}, F_quad[2] = {0, 0};
    double N_lin[2] = {0, 0}, N_quad[2] = {0, 0};
    int order = 0;
    for (int a = 2; a < argc; a++) {
        char key[32];
        const char *eq = strchr(argv[a], '=');
        if (!eq || (size_t)(eq - argv[a]) >= sizeof key) { fprintf(stderr, "bad argument %s\n", argv[a]); return 2; }
        memcpy(key, argv[a], (size_t)(eq - argv[a]));
        key[eq - argv[a]] = '\0';
        const char *val = eq + 1;
        double two[2];
        int ok = parse2(val, two);
        if (!strcmp(key, "scheme")) p.scheme = atoi(val);
        else if (!strcmp(key, "h")) p.h = two[0];
        else if (!strcmp(key, "H")) H = two[0];
        else if (!strcmp(key, "t_end")) t_end = two[0];
        else if (!strcmp(key, "order")) order = atoi(val);
        else if (!strcmp(key, "omega")) p.omega = two[0];
        else if (!strcmp(key, "k_end")) p.k_end = two[0];
        else if (!strcmp(key, "F_omega")) F_omega = two[0];
        else if (!strcmp(key, "F_amp")) memcpy(F_amp, two, sizeof two);
        else if (!strcmp(key, "F_lin")) memcpy(F_lin, two, sizeof two);
        else if (!strcmp(key, "F_quad")) memcpy(F_quad, two, sizeof two);
        else if (!strcmp(key, "N_lin")) memcpy(N_lin, two, sizeof two);
        else if (!strcmp(key, "N_quad")) memcpy(N_quad, two, sizeof two);
#define ARR(name) else if (!strcmp(key, #name)) memcpy(p.name, two, sizeof two);
        ARR(m) ARR(k) ARR(c) ARR(P0) ARR(phi) ARR(N) ARR(mu_s) ARR(chi) ARR(x0) ARR(v0)
#undef ARR
        else ok = 0;
        if (!ok) { fprintf(stderr, "bad argument %s\n", argv[a]); return 2; }
    }
    host_log L = {{0}, 0};
    dfo_lifecycle *in = start(T, &L, &p);
    if (!in || C.failures) { fprintf(stderr, "start failed: %s\n", L.last); return 1; }
    const long steps = lround(t_end / H);
    for (long s = 0; s <= steps; s++) {
        const double t = (double)s * H;
        printf("%.17g", dfo_inst_time(in));
        for (size_t i = 0; i < N_BLOCKS; i++) printf(",%.17g", get1(in, VR_x, i));
        for (size_t i = 0; i < N_BLOCKS; i++) printf(",%.17g", get1(in, VR_v, i));
        printf("\n");
        if (s == steps) break;
        for (size_t i = 0; i < N_BLOCKS; i++) {
            const double w = F_omega, A = F_amp[i], b = F_lin[i], q = F_quad[i];
            set1(in, VR_F_ext, i, A * sin(w * t) + b * t + 0.5 * q * t * t);
            const unsigned int r = el(VR_F_ext, i);
            const double d1 = A * w * cos(w * t) + b + q * t, d2 = -A * w * w * sin(w * t) + q;
            const int o1 = 1, o2 = 2;
            if (order >= 1) (void)dfo_inst_set_input_derivatives(in, "sid", &r, 1, &o1, &d1);
            if (order >= 2) (void)dfo_inst_set_input_derivatives(in, "sid", &r, 1, &o2, &d2);
            if (N_lin[i] != 0.0 || N_quad[i] != 0.0) {
                const unsigned int rn = el(VR_N_ext, i);
                const double bn = N_lin[i], qn = N_quad[i], n1 = bn + qn * t;
                set1(in, VR_N_ext, i, bn * t + 0.5 * qn * t * t);
                if (order >= 1) (void)dfo_inst_set_input_derivatives(in, "sid", &rn, 1, &o1, &n1);
                if (order >= 2) (void)dfo_inst_set_input_derivatives(in, "sid", &rn, 1, &o2, &qn);
            }
        }
        if (dfo_inst_do_step(in, "doStep", t, H, 0, NULL) != DFO_INST_OK) {
            fprintf(stderr, "step failed: %s\n", L.last);
            return 1;
        }
    }
    dfo_inst_delete(in);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "run")) return run_driver(argc, argv);
#if !defined(DFO_CHAIN_FIXED_N)
    fprintf(stderr, "this build (n = 1) is the driver only: chain_deriv_n1 run ...\n");
    return 2;
#endif
#if defined(DFO_CHAIN_FIXED_N)
    checks C = {0, 0, NULL, {0}};
    checks *T = &C;
    test_zero_derivatives(T);
    test_state(T);
    test_directional(T);
    test_output_derivatives(T);
    test_input_points(T);
    test_errors(T);
    test_long_chain_ramp(T);
    return checks_done(T, "test_chain_deriv");
#endif
}
