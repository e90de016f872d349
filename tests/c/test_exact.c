/* Unit tests of the exact scheme (fmu_src/models/oscillator/exact.h), driven directly (no FMI). The file includes
 * exact_spring.c to reach its closed-form phase (phase_init, eval) for the checks that need the motion
 * inside a phase.
 *
 * 1. the closed forms: the uniform and the steady-state forms agree where both hold; frictionless
 *    runs equal the linear oscillator's solution written out here (lambda = 1, zeta = 0 included);
 * 2. the equation of motion and the energy balance of every phase (Gauss quadrature of the closed
 *    form) for zeta in {0, 0.05, 1, 3}, chi in {0, 0.05, 0.7, 1, 2};
 * 3. the rules at every event: stops at zero velocity, stick inside the limit, slides from rest
 *    along the static force beyond it, the stuck block's force within the limit;
 * 4. a tangential touch (the velocity touches 0 with zero acceleration) and starts on the limit;
 * 5. communication points only restart phases (results within rounding); a copied state continues
 *    bit for bit; h has no effect at all;
 * 6. the observables against the event list: extremes, stick time, friction work, transitions;
 * 7. inputs held over calls; k = 0 accepted; long resonant runs stay finite and exact.
 *
 * Non-dimensional setting unless said otherwise: m = k = P0 = 1, so w0 = 1, lambda = omega,
 * sigma = N, z = x. */
#include "check.h"
#include "scheme.h"
#include "exact_spring.c"

#include <stdio.h>
#include <string.h>

typedef struct {
    dfo_model M;
    dfo_inputs u;
    dfo_state s;
} sim;

#define MAX_EV 4096
typedef struct {
    int n;
    double t[MAX_EV], x[MAX_EV];
    int from[MAX_EV], to[MAX_EV];
} event_log;

static void log_event(void *ctx, double t, double x, int from, int to)
{
    event_log *L = (event_log *)ctx;
    if (L->n < MAX_EV) {
        L->t[L->n] = t;
        L->x[L->n] = x;
        L->from[L->n] = from;
        L->to[L->n] = to;
    }
    L->n++;
}

static dfo_params nondim(double lambda, double mu_s_sigma, double chi, double zeta)
{
    dfo_params p;
    memset(&p, 0, sizeof p);
    p.m = 1.0;
    p.k = 1.0;
    p.c = 2.0 * zeta;
    p.P0 = 1.0;
    p.omega = lambda;
    p.mu_s = 0.5;
    p.N = mu_s_sigma / p.mu_s;
    p.chi = chi;
    p.h = (2.0 * DFO_PI / lambda) / 1000.0;
    p.alpha = -0.1;
    p.t_obs_start = 0.0;
    p.t_obs_stop = 1e300;
    p.scheme = DFO_SCHEME_EXACT;
    p.frictionUpdates = 1;
    p.fastPaths = 1;
    return p;
}

static void sim_start(sim *S, const dfo_params *p)
{
    memset(S, 0, sizeof *S);
    dfo_model_init(&S->M, p);
    dfo_start(&S->M, &S->u, 0.0, &S->s);
}

static double period_of(const dfo_params *p) { return 2.0 * DFO_PI / p->omega; }

/* ---- 1. closed forms ------------------------------------------------------------------------ */

/* The linear oscillator x'' + 2 zeta x' + x = cos(lambda t) from x(0) = x0, x'(0) = v0, zeta < 1,
 * (lambda, zeta) != (1, 0): steady state plus the free motion. */
static void linear_ref(double lam, double zeta, double x0, double v0, double t, double *x, double *v)
{
    const double dr = 1.0 - lam * lam, di = 2.0 * zeta * lam, d2 = dr * dr + di * di;
    const double Ar = dr / d2, Ai = -di / d2; /* H = 1 / D */
    const double xs0 = Ar, vs0 = -lam * Ai;
    const double wd = sqrt(1.0 - zeta * zeta), A = x0 - xs0, B = (v0 - vs0 + zeta * A) / wd;
    const double e = exp(-zeta * t), c = cos(wd * t), s = sin(wd * t);
    *x = Ar * cos(lam * t) - Ai * sin(lam * t) + e * (A * c + B * s);
    *v = -lam * (Ar * sin(lam * t) + Ai * cos(lam * t)) + e * ((-zeta * A + wd * B) * c - (zeta * B + wd * A) * s);
}

static void test_closed_forms(checks *T)
{
    /* the two forms of the forced part agree where both hold: away from resonance, and down to
     * |D| = D_MIN, where the steady-state form loses a factor 1 / D_MIN to cancellation */
    const double lams[] = {0.8, 0.9, 1.1, 1.2, 0.5, 0.99, 1.01};
    const double zetas[] = {0.0, 0.02, 0.1};
    double worst = 0.0;
    for (int i = 0; i < 7; i++)
        for (int j = 0; j < 3; j++) {
            dfo_params p = nondim(lams[i], 0.3, 0.7, zetas[j]);
            dfo_model M;
            dfo_model_init(&M, &p);
            dfo_inputs in;
            memset(&in, 0, sizeof in);
            ex_ctx A, B;
            ctx_init(&A, &M, &in);
            ctx_init(&B, &M, &in);
            A.uniform = 0;
            B.uniform = 1;
            ex_phase PA, PB;
            phase_init(&A, &PA, 0.7, 0.3, -0.2, 1);
            phase_init(&B, &PB, 0.7, 0.3, -0.2, 1);
            for (double u = 0.0; u < 60.0; u += 0.37) {
                ex_val va, vb;
                eval(&A, &PA, u, &va);
                eval(&B, &PB, u, &vb);
                const double e = fmax(fabs(va.y - vb.y), fabs(va.y1 - vb.y1));
                if (e > worst) worst = e;
            }
        }
    printf("closed forms: uniform vs steady-state form, max difference %.2e\n", worst);
    check_context(T, "uniform vs steady-state form");
    CHECK(worst < 1e-12);

    /* frictionless runs (N = 0) against the formula, 30 periods, 97 communication points */
    const double lams2[] = {0.3, 0.95, 1.0, 2.5};
    const double zetas2[] = {0.0, 0.05, 0.5};
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 3; j++) {
            const double lam = lams2[i], zeta = zetas2[j];
            dfo_params p = nondim(lam, 0.0, 1.0, zeta);
            p.x0 = 0.4;
            p.v0 = -0.3;
            sim S;
            sim_start(&S, &p);
            const double tend = 30.0 * period_of(&p);
            double err = 0.0, size = 1.0;
            for (int k = 1; k <= 97; k++) {
                const double t = tend * k / 97.0;
                if (!CHECK_INT(DFO_OK, dfo_exact_advance(&S.M, &S.u, &S.s, t, NULL, NULL))) break;
                double x, v;
                if (lam == 1.0 && zeta == 0.0) { /* resonance: x = t sin t / 2 + free motion */
                    x = 0.5 * t * sin(t) + 0.4 * cos(t) - 0.3 * sin(t);
                    v = 0.5 * (sin(t) + t * cos(t)) - 0.4 * sin(t) - 0.3 * cos(t);
                } else {
                    linear_ref(lam, zeta, 0.4, -0.3, t, &x, &v);
                }
                size = fmax(size, fabs(x));
                err = fmax(err, fmax(fabs(S.s.X - x), fabs(S.s.V - v)));
            }
            check_context(T, "frictionless lambda %g zeta %g", lam, zeta);
            printf("frictionless lambda %.2f zeta %.2f: max |x - x_ref| / size = %.2e (size %.3g)\n", lam, zeta,
                   err / size, size);
            CHECK(err <= 1e-12 * size);
        }
}

/* ---- 2.-3. every phase: equation of motion, energy balance, the rules at its ends ---------- */

/* 20-point Gauss-Legendre nodes and weights on [-1, 1] (positive half) */
static const double GL_X[10] = {0.0765265211334973, 0.2277858511416451, 0.3737060887154195, 0.5108670019508271,
                                0.6360536807265150, 0.7463319064601508, 0.8391169718222188, 0.9122344282513259,
                                0.9639719272779138, 0.9931285991850949};
static const double GL_W[10] = {0.1527533871307258, 0.1491729864726037, 0.1420961093183820, 0.1316886384491766,
                                0.1181945319615184, 0.1019301198172404, 0.0832767415767048, 0.0626720483341091,
                                0.0406014298003869, 0.0176140071391521};

typedef struct {
    double worst_energy, worst_eom, worst_rule;
    long phases;
} phase_stats;

/* Check the slip phase from (ta, xa, va) to tb in direction s, against the recorded end xb. */
static void check_slip_phase(const dfo_model *M, const ex_ctx *C, double ta, double xa, double va, double tb,
                             double xb, double vb, int s, phase_stats *st)
{
    ex_phase P;
    phase_init(C, &P, ta, xa, va, s);
    const double w0 = C->w0, k = M->p.k, m = M->p.m, c = M->p.c;
    const double muk = C->L.muk_N, u_ext = C->L.F_ext;
    /* work of the excitation and the input, and the damping loss, by Gauss quadrature over panels */
    const int panels = 1 + (int)((tb - ta) * (w0 + M->p.omega) * 2.0);
    double W = 0.0, D = 0.0, eom = 0.0, scale = 1e-300;
    for (int j = 0; j < panels; j++) {
        const double a = ta + (tb - ta) * j / panels, b = ta + (tb - ta) * (j + 1) / panels;
        const double mid = 0.5 * (a + b), half = 0.5 * (b - a);
        for (int i = 0; i < 20; i++) {
            const double t = mid + half * (i < 10 ? -GL_X[i] : GL_X[i - 10]), wgt = half * GL_W[i % 10];
            ex_val v;
            eval(C, &P, w0 * (t - ta), &v);
            const double x = P.xc + v.y, vel = w0 * v.y1, acc = w0 * w0 * v.y2;
            const double Pt = dfo_excitation(M, t);
            W += wgt * (Pt + u_ext) * vel;
            D += wgt * c * vel * vel;
            /* the equation of motion from independent pieces: y'' from the closed form's derivative */
            const double res = m * acc + c * vel + k * x - Pt - u_ext + s * muk;
            eom = fmax(eom, fabs(res));
            scale = fmax(scale, fabs(k * x) + fabs(Pt) + fabs(u_ext) + muk + fabs(c * vel));
        }
    }
    const double E0 = 0.5 * m * va * va + 0.5 * k * xa * xa, E1 = 0.5 * m * vb * vb + 0.5 * k * xb * xb;
    const double resid = (E1 - E0) - (W - D - muk * fabs(xb - xa));
    const double escale = fmax(fmax(E0, E1), fabs(W) + D + muk * fabs(xb - xa)) + 1e-300;
    st->worst_energy = fmax(st->worst_energy, fabs(resid) / escale);
    st->worst_eom = fmax(st->worst_eom, eom / scale);
    st->phases++;
}

static void run_and_check_phases(checks *T, dfo_params p, double periods, phase_stats *st, int *n_events)
{
    sim S;
    sim_start(&S, &p);
    ex_ctx C;
    ctx_init(&C, &S.M, &S.u);
    event_log L;
    L.n = 0;
    double ta = 0.0, xa = S.s.X, va = S.s.V;
    int mode = S.s.mode;
    const double tend = periods * period_of(&p);
    CHECK_INT(DFO_OK, dfo_exact_advance(&S.M, &S.u, &S.s, tend, log_event, &L));
    CHECK(L.n < MAX_EV);
    *n_events = L.n;
    const double Fb = C.L.Fb, scale = 1.0 + fabs(p.x0) * p.k;
    for (int e = 0; e <= L.n && e <= MAX_EV; e++) {
        const int last = (e == L.n || e == MAX_EV);
        const double tb = last ? tend : L.t[e];
        const double xb = last ? S.s.X : L.x[e];
        const double vb = last ? S.s.V : 0.0;
        if (!last) CHECK_INT(mode, L.from[e]);
        if (mode != 0) {
            if (tb > ta) check_slip_phase(&S.M, &C, ta, xa, va, tb, xb, vb, mode, st);
        } else {
            CHECK(xb == xa); /* frozen while stuck */
            /* while stuck the static force stays inside the limit (sampled) */
            for (int i = 1; i < 16; i++) {
                const double t = ta + (tb - ta) * i / 16.0;
                const double S_ = dfo_static_force(S.M.p.k, &C.L, dfo_excitation(&S.M, t), xa);
                st->worst_rule = fmax(st->worst_rule, (fabs(S_) - Fb) / scale);
            }
        }
        if (last) break;
        /* the rule at the event */
        const double Sv = dfo_static_force(S.M.p.k, &C.L, dfo_excitation(&S.M, tb), xb);
        const int to = L.to[e];
        if (mode != 0 && to == 0) st->worst_rule = fmax(st->worst_rule, (fabs(Sv) - Fb) / scale);
        if (to != 0 && mode == 0) st->worst_rule = fmax(st->worst_rule, (Fb - to * Sv) / scale);
        if (to != 0 && mode != 0) { /* a reversal: the static force beyond the limit, against the motion */
            CHECK_INT(-mode, to);
            st->worst_rule = fmax(st->worst_rule, (Fb - to * Sv) / scale);
        }
        ta = tb;
        xa = xb;
        va = 0.0;
        mode = to;
    }
}

static void test_phases(checks *T)
{
    const double zetas[] = {0.0, 0.05, 1.0, 3.0};
    const double chis[] = {0.0, 0.05, 0.7, 1.0, 2.0};
    const double lams[] = {0.5, 1.0, 2.0};
    phase_stats st = {0.0, 0.0, -1.0, 0};
    long events = 0;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 5; j++)
            for (int l = 0; l < 3; l++) {
                dfo_params p = nondim(lams[l], 0.3, chis[j], zetas[i]);
                p.x0 = 1.5;
                p.v0 = 0.7;
                check_context(T, "phases: lambda %g zeta %g chi %g", lams[l], zetas[i], chis[j]);
                int n = 0;
                phase_stats one = {0.0, 0.0, -1.0, 0};
                run_and_check_phases(T, p, 30.0, &one, &n);
                CHECK(one.worst_energy < 1e-11);
                CHECK(one.worst_eom < 1e-12);
                CHECK(one.worst_rule <= 1e-13);
                st.worst_energy = fmax(st.worst_energy, one.worst_energy);
                st.worst_eom = fmax(st.worst_eom, one.worst_eom);
                st.worst_rule = fmax(st.worst_rule, one.worst_rule);
                st.phases += one.phases;
                events += n;
            }
    printf("phases: %ld slip phases, %ld events; energy balance residual <= %.2e, equation of motion <= %.2e, "
           "rules violated by <= %.2e (relative)\n", st.phases, events, st.worst_energy, st.worst_eom, st.worst_rule);
    CHECK(st.phases > 1000);
}

/* ---- 4. tangential touch, starts on the limit ---------------------------------------------- */

static void test_touch_and_limit(checks *T)
{
    /* forward slip whose velocity touches 0 at t* = 1 with zero acceleration (x* = cos(theta*) - b),
     * written backwards to t = 0 from the steady state plus free motion (zeta = 0, lambda = 0.5) */
    const double lam = 0.5, b = 0.2, ts = 1.0, th = -DFO_PI / 3.0, phi = th - lam * ts, H = 1.0 / (1.0 - lam * lam);
    const double A = cos(th) - cos(th) * H, B = lam * sin(th) * H;
    dfo_params p = nondim(lam, 0.4, 0.5, 0.0); /* mu_k N = 0.2 = b, limit 0.4 */
    p.phi = phi;
    p.x0 = cos(phi) * H + A * cos(-ts) + B * sin(-ts) - b;
    p.v0 = -lam * sin(phi) * H - A * sin(-ts) + B * cos(-ts);
    sim S;
    sim_start(&S, &p);
    event_log L;
    L.n = 0;
    check_context(T, "tangential touch at t* = 1");
    CHECK_INT(DFO_OK, dfo_exact_advance(&S.M, &S.u, &S.s, 3.0, log_event, &L));
    CHECK(L.n >= 2);
    CHECK_INT(1, L.from[0]);
    CHECK_INT(0, L.to[0]);
    CHECK_NEAR(ts, L.t[0], 1e-6);               /* a touch is located to sqrt(rounding) in time, */
    CHECK_NEAR(cos(th) - b, L.x[0], 1e-13);      /* and to rounding in position */
    printf("tangential touch: found at t = %.15f (t* = 1), x - x* = %.2e\n", L.t[0], L.x[0] - (cos(th) - b));

    /* starts exactly on the limit: S(0) = P0 - k x0 = Fb (exact in binary) at the top of the
     * excitation, where S falls: the touch does not break the block loose */
    const double chis[] = {0.5, 1.0, 2.0};
    for (int i = 0; i < 3; i++) {
        dfo_params q = nondim(0.5, 0.25, chis[i], 0.0);
        dfo_model M;
        dfo_model_init(&M, &q);
        const double Fb = M.mu_b * q.N;
        q.x0 = 1.0 - Fb;
        sim S2;
        sim_start(&S2, &q);
        check_context(T, "start on the limit, falling, chi %g", chis[i]);
        CHECK_INT(0, S2.s.mode); /* |S| <= Fb: stuck */
        event_log L2;
        L2.n = 0;
        CHECK_INT(DFO_OK, dfo_exact_advance(&S2.M, &S2.u, &S2.s, 2.0 * period_of(&q), log_event, &L2));
        CHECK(L2.n >= 1);
        CHECK(L2.t[0] > 0.5);
        CHECK_INT(-1, L2.to[0]);
        const double t_fall = L2.t[0];
        /* on the limit with S rising (phi = -pi/2, x0 = -Fb): the block slides forward at once (by the
         * rest rule at start-up, or a breakaway within rounding), and the slide is real: chi >= 1 starts
         * with zero acceleration, and no rounding noise is taken for a stop (no Zeno loop) */
        q.phi = -DFO_PI / 2.0;
        q.x0 = -Fb;
        sim_start(&S2, &q);
        check_context(T, "start on the limit, rising, chi %g", chis[i]);
        L2.n = 0;
        const int m0 = S2.s.mode;
        CHECK_INT(DFO_OK, dfo_exact_advance(&S2.M, &S2.u, &S2.s, 2.0 * period_of(&q), log_event, &L2));
        int e = 0;
        if (m0 == 0) {
            CHECK(L2.n >= 1 && L2.t[0] < 1e-6 && L2.to[0] == 1);
            e = 1;
        } else {
            CHECK_INT(1, m0);
        }
        CHECK(L2.n > e && L2.t[e] > 0.5 && L2.from[e] == 1);
        printf("start on the limit, chi %.1f: falling side stuck until t = %.6f; rising side slides from t = 0 "
               "(mode %d at start) until t = %.6f\n", chis[i], t_fall, m0, L2.t[e]);
    }
}

/* ---- 5. communication points, copies, h ----------------------------------------------------- */

static void test_restarts(checks *T)
{
    rng r = {12345};
    double worst = 0.0;
    for (int c = 0; c < 40; c++) {
        const double lam = rng_range(&r, 0.2, 2.5), zeta = (c % 4 == 0) ? 0.0 : rng_range(&r, 0.0, 1.5);
        dfo_params p = nondim(lam, rng_range(&r, 0.05, 0.9), rng_range(&r, 0.0, 2.0), zeta);
        p.x0 = rng_range(&r, -2.0, 2.0);
        p.v0 = rng_range(&r, -1.0, 1.0);
        const double tend = 10.0 * period_of(&p);
        sim A, B;
        sim_start(&A, &p);
        sim_start(&B, &p);
        check_context(T, "restarts: case %d", c);
        CHECK_INT(DFO_OK, dfo_exact_advance(&A.M, &A.u, &A.s, tend, NULL, NULL));
        double t = 0.0;
        while (t < tend) {
            t = fmin(tend, t + rng_range(&r, 0.001, 0.3) * period_of(&p));
            if (!CHECK_INT(DFO_OK, dfo_exact_advance(&B.M, &B.u, &B.s, t, NULL, NULL))) break;
        }
        const double size = fmax(fabs(A.s.X), 1.0);
        worst = fmax(worst, fabs(A.s.X - B.s.X) / size);
        CHECK(fabs(A.s.X - B.s.X) <= 1e-11 * size);
        /* a copy continues bit for bit; h has no effect */
        sim Cc = B, D;
        p.h *= 7.3;
        sim_start(&D, &p);
        CHECK_INT(DFO_OK, dfo_exact_advance(&D.M, &D.u, &D.s, tend, NULL, NULL));
        CHECK_SAME(A.s.X, D.s.X);
        CHECK_SAME(A.s.V, D.s.V);
        CHECK_INT(DFO_OK, dfo_exact_advance(&B.M, &B.u, &B.s, tend * 1.5, NULL, NULL));
        CHECK_INT(DFO_OK, dfo_exact_advance(&Cc.M, &Cc.u, &Cc.s, tend * 1.5, NULL, NULL));
        CHECK(memcmp(&B.s, &Cc.s, sizeof B.s) == 0);
    }
    printf("restarts: 40 random cases, 10 periods, random communication points vs one call: max |dx| / size = "
           "%.2e\n", worst);
}

/* ---- 6. observables ------------------------------------------------------------------------- */

static void test_observables(checks *T)
{
    dfo_params p = nondim(0.5, 0.4, 0.6, 0.05);
    const double Tp = period_of(&p);
    p.observe = 1;
    p.t_obs_start = 3.3 * Tp;
    p.t_obs_stop = 7.6 * Tp;
    sim S;
    sim_start(&S, &p);
    event_log L;
    L.n = 0;
    check_context(T, "observables");
    CHECK_INT(DFO_OK, dfo_exact_advance(&S.M, &S.u, &S.s, 9.0 * Tp, log_event, &L));
    /* dense reference from many short calls (each restarts its phase) */
    sim R;
    dfo_params q = p;
    q.observe = 0;
    sim_start(&R, &q);
    const int n = 40000;
    double xmax = -INFINITY, xmin = INFINITY, stuck = 0.0, work = 0.0, xprev = 0.0;
    for (int i = 0; i <= n; i++) {
        const double t = p.t_obs_start + (p.t_obs_stop - p.t_obs_start) * i / n;
        CHECK_INT(DFO_OK, dfo_exact_advance(&R.M, &R.u, &R.s, t, NULL, NULL));
        xmax = fmax(xmax, R.s.X);
        xmin = fmin(xmin, R.s.X);
        if (i > 0) work += R.M.mu_k * R.M.p.N * fabs(R.s.X - xprev);
        xprev = R.s.X;
    }
    /* stick time and transitions from the event list */
    double tprev = 0.0;
    int mode = 0, trans = 0;
    dfo_state s0;
    dfo_start(&S.M, &S.u, 0.0, &s0);
    mode = s0.mode;
    for (int e = 0; e <= L.n; e++) {
        const double tb = (e == L.n) ? 9.0 * Tp : L.t[e];
        if (mode == 0) stuck += fmax(0.0, fmin(tb, p.t_obs_stop) - fmax(tprev, p.t_obs_start));
        if (e < L.n) {
            if (tb > p.t_obs_start && tb <= p.t_obs_stop) trans++;
            mode = L.to[e];
        }
        tprev = tb;
    }
    printf("observables: x_max %.15g (sampled %.15g), x_min %.15g (sampled %.15g), stuck %.15g (events %.15g), "
           "E_friction %.15g (sampled %.15g), transitions %lld (events %d)\n", S.s.x_max, xmax, S.s.x_min, xmin,
           S.s.t_stuck, stuck, S.s.E_friction, work, S.s.transitions, trans);
    /* the sampled extremes come from restarted phases (rounding 1e-14) and miss the exact ones by
     * at most the motion between samples */
    CHECK(S.s.x_max >= xmax - 1e-12 && S.s.x_max - xmax < 1e-7);
    CHECK(S.s.x_min <= xmin + 1e-12 && xmin - S.s.x_min < 1e-7);
    CHECK_NEAR(stuck, S.s.t_stuck, 1e-12 * stuck);
    CHECK_NEAR(work, S.s.E_friction, 1e-10);
    CHECK_INT(trans, S.s.transitions);
    CHECK(trans > 10);
}

/* ---- 7. inputs, bad parameters, long resonance --------------------------------------------- */

static void test_inputs_and_hard(checks *T)
{
    /* an input held over a call shifts the equilibrium: with F_ext = k d and no excitation and no
     * friction, x oscillates about d: x = d + (x0 - d) cos t */
    dfo_params p = nondim(1.0, 0.0, 1.0, 0.0);
    p.P0 = 0.0;
    p.x0 = 0.25;
    sim S;
    sim_start(&S, &p);
    S.u.F_ext = 0.75;
    S.u.F_ext_set = 1;
    check_context(T, "F_ext held");
    CHECK_INT(DFO_OK, dfo_exact_advance(&S.M, &S.u, &S.s, 2.0, NULL, NULL));
    CHECK_NEAR(0.75 + (0.25 - 0.75) * cos(2.0), S.s.X, 1e-15);
    /* N_ext: a normal force that makes the limit exceed the static force sticks the block */
    dfo_params q = nondim(0.5, 0.0, 1.0, 0.0);
    q.mu_s = 0.5;
    q.v0 = 0.1;
    sim S2;
    sim_start(&S2, &q);
    S2.u.N_ext = 10.0;
    S2.u.N_ext_set = 1;
    check_context(T, "N_ext held");
    CHECK_INT(DFO_OK, dfo_exact_advance(&S2.M, &S2.u, &S2.s, 20.0, NULL, NULL));
    CHECK_INT(0, S2.s.mode);
    CHECK_SAME(0.0, S2.s.V);
    /* k = 0 is accepted for every scheme (the exact one: exact_free.c, tests/c/test_exact_free.c) */
    dfo_params r = nondim(0.5, 0.3, 0.7, 0.0);
    r.k = 0.0;
    check_context(T, "k = 0");
    CHECK(dfo_check_params(&r) == NULL);
    r.scheme = DFO_SCHEME_LOCATED;
    CHECK(dfo_check_params(&r) == NULL);
    /* exact resonance with friction below the non-stop limit: amplitude growth pi - 4 mu_k N / P0 per
     * period (averaging), measured by the in-FMU extremes over periods 2000 and 2001 */
    double amp[2];
    for (int w = 0; w < 2; w++) {
        dfo_params g = nondim(1.0, 0.1, 1.0, 0.0);
        g.observe = 1;
        g.t_obs_start = (2000.0 + w) * period_of(&g);
        g.t_obs_stop = g.t_obs_start + period_of(&g);
        sim G;
        sim_start(&G, &g);
        check_context(T, "long resonance");
        CHECK_INT(DFO_OK, dfo_exact_advance(&G.M, &G.u, &G.s, g.t_obs_stop, NULL, NULL));
        CHECK(isfinite(G.s.X));
        amp[w] = 0.5 * (G.s.x_max - G.s.x_min);
    }
    printf("long resonance: amplitude in period 2000 %.6f, growth per period %.6f (pi - 4 mu_k N / P0 = %.6f)\n",
           amp[0], amp[1] - amp[0], DFO_PI - 0.4);
    CHECK_NEAR(DFO_PI - 0.4, amp[1] - amp[0], 1e-3);
}

int main(void)
{
    checks T_ = {0, 0, NULL, {0}};
    checks *T = &T_;
    test_closed_forms(T);
    test_phases(T);
    test_touch_and_limit(T);
    test_restarts(T);
    test_observables(T);
    test_inputs_and_hard(T);
    return checks_done(T, "test_exact");
}
