/* The exact scheme with inputs varying as polynomials over a communication step (exact.h:
 * dfo_exact_advance_poly; FMI input derivatives), driven directly (no FMI).
 *
 * Without arguments, its unit tests:
 * 1. zero derivatives: dfo_exact_advance itself, bit for bit (x, v, a, F, mode, events, observables);
 * 2. the Jacobian of a stick-slip run with ramp and quadratic F_ext and N_ext (stops, stick phases,
 *    breakaways, reversals) against central differences of the same map (1e-6);
 * 3. the same motion, bit for bit, with the sensitivity on and off;
 * 4. one input polynomial over the run, cut into other communication steps (the host re-expanding it
 *    at each point): the same motion to rounding;
 * 5. dfo_input_poly_at (the inputs at a time); non-finite derivatives an error with the state
 *    untouched; every model supported (dfo_exact_poly_unsupported: NULL
 *    for k > 0 and k = 0).
 *
 * With arguments, a driver for tests/test_exact_poly.py (against tests/poly_reference.py):
 *
 *   test_exact_poly run [m= k= c= P0= omega= phi= N= mu_s= chi= x0= v0= F0= F1= F2= Next0= N1= N2=
 *                        t_end= steps= obs_start= obs_stop=]
 *
 * The inputs are one polynomial over the run, F_ext(t) = F0 + F1 t + F2 t^2 / 2, N_ext(t) likewise
 * (Next0, N1, N2), given to each of `steps` equal communication steps as its value and derivatives at
 * the step's start. Prints one line per switch ("switch t x from to") and per communication point
 * ("point t x v mode events F A"), then "obs x_max x_min t_stuck E_friction transitions", all %.17g.
 * Bad input: one line on stderr and exit status 2. */
#include "check.h"
#include "scheme.h"
#include "osc_params.h"
#include "exact.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct {
    double F[3], N[3]; /* F_ext(t) = F[0] + F[1] t + F[2] t^2 / 2, N_ext(t) likewise */
} inputs_poly;

static dfo_params base_params(void) { return osc_test_exact_base(); }

/* The host's view at the communication point tc: the values at tc, the derivatives there. */
static void host_inputs(const inputs_poly *g, double tc, dfo_inputs *in, dfo_input_poly *q)
{
    memset(in, 0, sizeof *in);
    in->F_ext = g->F[0] + tc * (g->F[1] + 0.5 * tc * g->F[2]);
    in->N_ext = g->N[0] + tc * (g->N[1] + 0.5 * tc * g->N[2]);
    in->F_ext_set = in->N_ext_set = 1;
    q->t0 = tc;
    q->F[0] = g->F[1] + tc * g->F[2];
    q->F[1] = g->F[2];
    q->N[0] = g->N[1] + tc * g->N[2];
    q->N[1] = g->N[2];
}

typedef struct {
    int print;
    long long switches;
} run_log;

static void on_switch(void *ctx, double t, double x, int from, int to)
{
    run_log *L = (run_log *)ctx;
    L->switches++;
    if (L->print) printf("switch %.17g %.17g %d %d\n", t, x, from, to);
}

/* One run from (x0, v0) at t = 0 to t_end in n communication steps; the status of the first failure. */
static dfo_status run(const dfo_params *p, const inputs_poly *g, double t_end, int n, dfo_state *s, run_log *log)
{
    dfo_model M;
    dfo_model_init(&M, p);
    dfo_inputs in;
    dfo_input_poly q;
    host_inputs(g, 0.0, &in, &q);
    dfo_start(&M, &in, 0.0, s);
    s->J[0] = s->J[3] = 1.0;
    s->J[1] = s->J[2] = 0.0;
    double tc = 0.0;
    for (int i = 1; i <= n; i++) {
        const double tn = (i == n) ? t_end : t_end * i / n;
        host_inputs(g, tc, &in, &q);
        const dfo_status st = dfo_exact_advance_poly(&M, &in, &q, s, tn, log ? on_switch : NULL, log);
        if (st != DFO_OK) return st;
        if (log && log->print)
            printf("point %.17g %.17g %.17g %d %lld %.17g %.17g\n", s->t, s->X, s->V, s->mode, s->steps, s->F, s->A);
        tc = tn;
    }
    return DFO_OK;
}

/* ---- the unit tests ------------------------------------------------------------------------------ */

static void test_zero_derivatives(checks *T)
{
    const double chis[] = {0.7, 1.0, 0.3};
    const double ks[] = {1.0, 0.0};
    int n_cmp = 0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 2; j++) {
            dfo_params p = base_params();
            p.chi = chis[i];
            p.k = ks[j];
            p.observe = 1;
            p.t_obs_start = 7.0;
            p.t_obs_stop = 40.0;
            dfo_model M;
            dfo_model_init(&M, &p);
            dfo_inputs in;
            memset(&in, 0, sizeof in);
            in.F_ext = 0.05;
            in.N_ext = 0.1;
            in.F_ext_set = in.N_ext_set = 1;
            dfo_state a, b, c;
            dfo_start(&M, &in, 0.0, &a);
            b = a;
            c = a;
            const dfo_input_poly zero = {0.0, {0.0, 0.0}, {0.0, 0.0}};
            check_context(T, "chi = %g, k = %g", p.chi, p.k);
            CHECK_INT(dfo_input_poly_active(&zero), 0);
            CHECK_INT(dfo_input_poly_active(NULL), 0);
            for (int n = 1; n <= 20; n++) {
                const double t = 3.0 * n;
                CHECK_INT(dfo_exact_advance(&M, &in, &a, t, NULL, NULL), DFO_OK);
                CHECK_INT(dfo_exact_advance_poly(&M, &in, &zero, &b, t, NULL, NULL), DFO_OK);
                CHECK_INT(dfo_exact_advance_poly(&M, &in, NULL, &c, t, NULL, NULL), DFO_OK);
            }
            CHECK(memcmp(&a, &b, sizeof a) == 0);
            CHECK(memcmp(&a, &c, sizeof a) == 0);
            CHECK(a.steps > 5);
            n_cmp++;
        }
    printf("zero derivatives: %d runs identical to dfo_exact_advance (the whole state, bytes)\n", n_cmp);
}

/* The largest difference over the largest entry plus FLOOR: central differences of step 1e-6 of a map
 * computed to rounding (1e-16 of x ~ 1) carry an error of about 1e-10 whatever the Jacobian, which
 * is more than 1e-6 of an entry when every entry is below 1e-4 (a stick phase late in the run). */
#define FLOOR 1e-3
static double rel_diff(const double A[4], const double B[4])
{
    double d = 0.0, n = 0.0;
    for (int i = 0; i < 4; i++) {
        d = fmax(d, fabs(A[i] - B[i]));
        n = fmax(n, fabs(B[i]));
    }
    return d / (n + FLOOR);
}

static const inputs_poly CASES[] = {
    {{0.02, 0.01, 0.0}, {0.0, 0.0, 0.0}},       /* ramp F_ext */
    {{0.0, 0.0, 0.0}, {0.05, 0.004, 0.0}},      /* ramp N_ext */
    {{0.02, 0.01, -4e-4}, {0.05, 0.004, -2e-4}}, /* both quadratic */
};

static void test_against_differences(checks *T)
{
    const double chis[] = {0.7, 0.3, 1.0};
    const double T_exc = 2.0 * DFO_PI / 0.5;
    const double ends[] = {3.3, 4.6};
    double worst = 0.0;
    int runs = 0;
    for (size_t c = 0; c < sizeof CASES / sizeof CASES[0]; c++)
        for (int i = 0; i < 4; i++)
            for (int j = 0; j < 2; j++) {
                dfo_params p = base_params();
                p.chi = chis[i % 3];
                if (i == 3) { /* no spring */
                    p.k = 0.0;
                    p.c = 0.3;
                    p.N = 0.25;
                }
                p.sensitivity = 1;
                const double t_end = ends[j] * T_exc, e = 1e-6;
                dfo_state s, a, b;
                check_context(T, "case %d, chi = %g, k = %g, t = %g T", (int)c, p.chi, p.k, ends[j]);
                CHECK_INT(run(&p, &CASES[c], t_end, 50, &s, NULL), DFO_OK);
                if (s.mode == 0) continue; /* (the map is not differentiable in v while stuck) */
                CHECK(s.steps > (p.k > 0.0 ? 6 : 3));
                double F[4];
                dfo_params q = p;
                q.x0 = p.x0 + e;
                run(&q, &CASES[c], t_end, 50, &a, NULL);
                q.x0 = p.x0 - e;
                run(&q, &CASES[c], t_end, 50, &b, NULL);
                F[0] = (a.X - b.X) / (2 * e);
                F[2] = (a.V - b.V) / (2 * e);
                q.x0 = p.x0;
                q.v0 = p.v0 + e;
                run(&q, &CASES[c], t_end, 50, &a, NULL);
                q.v0 = p.v0 - e;
                run(&q, &CASES[c], t_end, 50, &b, NULL);
                F[1] = (a.X - b.X) / (2 * e);
                F[3] = (a.V - b.V) / (2 * e);
                const double r = rel_diff(s.J, F);
                if (r > 1e-6)
                    printf("  case %d chi %g t %g T: J %.9g %.9g %.9g %.9g, differences %.9g %.9g %.9g %.9g\n", (int)c,
                           p.chi, ends[j], s.J[0], s.J[1], s.J[2], s.J[3], F[0], F[1], F[2], F[3]);
                CHECK(r < 1e-6);
                if (r > worst) worst = r;
                runs++;
                /* off: the same motion, bit for bit */
                dfo_params off = p;
                off.sensitivity = 0;
                dfo_state o;
                run(&off, &CASES[c], t_end, 50, &o, NULL);
                CHECK_SAME(s.X, o.X);
                CHECK_SAME(s.V, o.V);
                CHECK_INT(s.mode, o.mode);
                CHECK_INT(s.steps, o.steps);
            }
    CHECK(runs >= 10);
    printf("Jacobian with polynomial inputs against central differences: %d runs, "
           "worst %.2e of the largest entry (+ 1e-3)\n", runs, worst);
}

static void test_other_steps(checks *T)
{
    const int ns[] = {1, 7, 50, 333};
    double worst = 0.0;
    for (size_t c = 0; c < 2 * sizeof CASES / sizeof CASES[0]; c++) {
        dfo_params p = base_params();
        if (c >= sizeof CASES / sizeof CASES[0]) { /* no spring */
            p.k = 0.0;
            p.c = 0.3;
            p.N = 0.25;
        }
        const inputs_poly *g = &CASES[c % (sizeof CASES / sizeof CASES[0])];
        dfo_state ref, s;
        run_log L0 = {0, 0};
        check_context(T, "case %d", (int)c);
        CHECK_INT(run(&p, g, 60.0, 20, &ref, &L0), DFO_OK);
        for (int i = 0; i < 4; i++) {
            run_log L = {0, 0};
            CHECK_INT(run(&p, g, 60.0, ns[i], &s, &L), DFO_OK);
            const double e = fmax(fabs(s.X - ref.X), fabs(s.V - ref.V));
            CHECK(e < 1e-12);
            CHECK_INT(s.mode, ref.mode);
            CHECK_INT(L.switches, L0.switches);
            if (e > worst) worst = e;
        }
    }
    printf("one polynomial cut into 1 ... 333 communication steps: worst |dx|, |dv| %.2e\n", worst);
}

static void test_inputs_at(checks *T)
{
    dfo_inputs u, o;
    memset(&u, 0, sizeof u);
    u.F_ext = 0.5;
    u.F_ext_set = 1; /* N_ext never set: 0 at t0, its derivatives still count */
    const dfo_input_poly q = {2.0, {0.25, -1.0}, {0.0, 4.0}};
    dfo_input_poly_at(&u, &q, 3.0, &o); /* d = 1 */
    CHECK_SAME(0.5 + 0.25 - 0.5, o.F_ext);
    CHECK_SAME(2.0, o.N_ext);
    CHECK_INT(1, o.N_ext_set);
    const dfo_input_poly f = {2.0, {0.25, 0.0}, {0.0, 0.0}};
    dfo_input_poly_at(&u, &f, 3.0, &o);
    CHECK_INT(0, o.N_ext_set); /* no derivative of N_ext: as given */
    dfo_input_poly_at(&u, NULL, 3.0, &o);
    CHECK(memcmp(&u, &o, sizeof u) == 0);
}

static void test_non_finite(checks *T)
{
    dfo_params p = base_params();
    const double ks[] = {1.0, 0.0};
    for (int i = 0; i < 2; i++) {
        p.k = ks[i];
        dfo_model M;
        dfo_model_init(&M, &p);
        dfo_inputs in;
        memset(&in, 0, sizeof in);
        dfo_state s, s0;
        dfo_start(&M, &in, 0.0, &s);
        s0 = s;
        for (int j = 0; j < 4; j++) {
            dfo_input_poly q = {0.0, {0.0, 0.0}, {0.0, 0.0}};
            double *f[4] = {&q.F[0], &q.F[1], &q.N[0], &q.N[1]};
            *f[j] = (j & 1) ? INFINITY : NAN;
            check_context(T, "k = %g, derivative %d", p.k, j);
            CHECK_INT(DFO_ERR_NONFINITE, dfo_exact_advance_poly(&M, &in, &q, &s, 1.0, NULL, NULL));
            CHECK(memcmp(&s, &s0, sizeof s) == 0);
        }
    }
}

static void test_supported(checks *T)
{
    const double ks[] = {1.0, 0.0};
    for (int i = 0; i < 2; i++) {
        dfo_params p = base_params();
        p.k = ks[i];
        dfo_model M;
        dfo_model_init(&M, &p);
        CHECK(dfo_exact_poly_unsupported(&M) == NULL);
    }
}

/* ---- the driver ---------------------------------------------------------------------------------- */

static int driver(int argc, char **argv)
{
    dfo_params p = base_params();
    inputs_poly g;
    memset(&g, 0, sizeof g);
    double t_end = 10.0;
    int steps = 1;
    struct {
        const char *name;
        double *v;
    } keys[] = {{"m", &p.m},       {"k", &p.k},         {"c", &p.c},          {"P0", &p.P0},       {"omega", &p.omega},
                {"phi", &p.phi},   {"N", &p.N},         {"mu_s", &p.mu_s},    {"chi", &p.chi},     {"x0", &p.x0},
                {"v0", &p.v0},     {"F0", &g.F[0]},     {"F1", &g.F[1]},      {"F2", &g.F[2]},     {"Next0", &g.N[0]},
                {"N1", &g.N[1]},   {"N2", &g.N[2]},     {"t_end", &t_end},    {"obs_start", &p.t_obs_start},
                {"obs_stop", &p.t_obs_stop}};
    for (int a = 2; a < argc; a++) {
        char *eq = strchr(argv[a], '=');
        if (!eq) {
            fprintf(stderr, "test_exact_poly: argument %s is not name=value\n", argv[a]);
            return 2;
        }
        *eq = '\0';
        int found = 0;
        if (!strcmp(argv[a], "steps")) {
            steps = atoi(eq + 1);
            found = 1;
        }
        for (size_t j = 0; j < sizeof keys / sizeof keys[0]; j++)
            if (!strcmp(argv[a], keys[j].name)) {
                *keys[j].v = strtod(eq + 1, NULL);
                found = 1;
            }
        if (!found) {
            fprintf(stderr, "test_exact_poly: unknown argument %s\n", argv[a]);
            return 2;
        }
    }
    p.observe = 1;
    const char *bad = dfo_check_params(&p);
    if (bad || steps < 1) {
        fprintf(stderr, "test_exact_poly: %s\n", bad ? bad : "steps must be >= 1");
        return 2;
    }
    dfo_state s;
    run_log L = {1, 0};
    const dfo_status st = run(&p, &g, t_end, steps, &s, &L);
    if (st != DFO_OK) {
        fprintf(stderr, "test_exact_poly: %s\n", dfo_status_text(st));
        return 1;
    }
    printf("obs %.17g %.17g %.17g %.17g %lld\n", s.x_max, s.x_min, s.t_stuck, s.E_friction, s.transitions);
    return 0;
}

int main(int argc, char **argv)
{
    if (argc > 1 && !strcmp(argv[1], "run")) return driver(argc, argv);
    checks T0 = {0, 0, NULL, {0}};
    checks *T = &T0;
    test_zero_derivatives(T);
    test_against_differences(T);
    test_other_steps(T);
    test_inputs_at(T);
    test_non_finite(T);
    test_supported(T);
    return checks_done(T, "test_exact_poly");
}
