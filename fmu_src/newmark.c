/* Bossak-Newmark velocity-form stepper with the friction LCP. See newmark.h and method.md. */
#include "newmark.h"

#include "exact.h"
#include "friction.h"
#include "lcp.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

#define MAX_PHASES_PER_STEP 64  /* switches one internal step may hold before it is an error */
#define LCP_MAX_PIVOT_COUNT 16  /* a 2 x 2 problem needs at most 3 pivots */
#define STIFF_STEP 10.0         /* rate_max h above which a step does not resolve the motion */
#define EXC_ANCHOR 64

/* The few functions of every internal step are inlined into the stepping loop, so that the state
 * stays in registers (a step costs some 100 ns; a call and its spills are a good part of that). */
#if defined(__GNUC__)
#define HOT_INLINE inline __attribute__((always_inline))
#else
#define HOT_INLINE inline
#endif           /* grid points between exact evaluations of the excitation phase */

/* The coefficients of a Bossak step that depend on its length h only (eq. 4). */
typedef struct {
    double h;
    double c1;         /* 1 / (gamma h) */
    double m_hat;      /* effective mass (1 - alpha) m c1 + k beta h / gamma (+ c) */
    double inv_m_hat;  /* 1 / m_hat */
    double kV, kA;     /* x_pred = X + kV V + kA A0 */
    double kX;         /* X1 = x_pred + kX V1 */
} step_coef;

/* What is constant over one call of dfo_advance (inputs are held). */
typedef struct {
    const dfo_model *M;
    dfo_loads L;     /* external and normal force, kinetic magnitude, breakaway limit */
    step_coef full;  /* the coefficients of a step of the grid length h */
    double g1;       /* (1 - gamma) / gamma */
    double am, am1;  /* alpha m, (1 - alpha) m */
    double h_step;   /* length of the current step: h itself for a whole grid interval (the time
                      * difference of two grid points differs from h by the rounding of t) */
    int friction;    /* friction acts (the LCP is needed) */
    double t_grid;   /* end of the current step when it is a grid point (else NaN) */
    double P_grid;   /* the excitation there, from the state's excitation cache */
    dfo_status err;  /* first error met */
    dfo_switch_fn on_switch;
    void *switch_ctx;
} step_ctx;

/* One Bossak step of length h from the current state, before the velocity is known (eq. 4). */
typedef struct {
    const step_coef *k;  /* the step's coefficients: the context's for a grid step, else own */
    step_coef own;
    double A0, x_pred, p_hat;
} trial;

static int stuck(const step_ctx *C, const dfo_state *s) { return C->friction && s->mode == 0; }

/* The excitation at t: from the grid cache at the end of the current step, else evaluated. */
static double excitation(const step_ctx *C, double t)
{
    return (t == C->t_grid) ? C->P_grid : dfo_excitation(C->M, t);
}

/* Excitation at the grid point s->n from the cache of the state (see dfo_state). One rotation when
 * the cache holds the previous point, else an exact evaluation at the anchor below n and the same
 * rotations from there: the value depends on n only, never on the history of the cache. */
static void phase_at(const dfo_model *M, const dfo_state *s, long long n, double *c_out, double *s_out)
{
    const double cd = M->rot_c, sd = M->rot_s;
    double c, sn;
    long long k;
    if (s->exc_n >= 0 && s->exc_n == n - 1 && n % EXC_ANCHOR != 0) {
        c = s->exc_c;
        sn = s->exc_s;
        k = n - 1;
    } else {
        k = n - n % EXC_ANCHOR;
        const double th = M->p.omega * (s->t0 + (double)k * M->p.h) + M->p.phi;
        c = cos(th);
        sn = sin(th);
    }
    for (; k < n; k++) {
        const double c1 = c * cd - sn * sd;
        sn = sn * cd + c * sd;
        c = c1;
    }
    *c_out = c;
    *s_out = sn;
}

static double grid_excitation(const dfo_model *M, dfo_state *s)
{
    phase_at(M, s, s->n, &s->exc_c, &s->exc_s);
    s->exc_n = s->n;
    /* rotations keep c^2 + s^2 = 1 only to rounding: a cosine never exceeds 1 */
    const double c = s->exc_c;
    return M->p.P0 * (c > 1.0 ? 1.0 : c < -1.0 ? -1.0 : c);
}

/* Physical acceleration from the equation of motion in the current mode. */
static double accel_of(const step_ctx *C, const dfo_state *s, double t, double F)
{
    const dfo_model *M = C->M;
    double f = excitation(C, t) + C->L.u - M->p.k * s->X + F;
    if (M->damped) f -= M->p.c * s->V;
    return f / M->p.m;
}

/* x''' from the time derivative of the equation of motion (0 while stuck). */
static double jerk_of(const step_ctx *C, const dfo_state *s)
{
    if (stuck(C, s)) return 0.0;
    const dfo_model *M = C->M;
    const double F = -s->mode * C->L.muk_N;
    double j = dfo_excitation_rate(M, s->t) - M->p.k * s->V;
    if (M->damped) j -= M->p.c * accel_of(C, s, s->t, F);
    return j / M->p.m;
}

static void coef_for(const dfo_model *M, double h, step_coef *cf)
{
    const double a = M->p.alpha, g = M->gamma, b = M->beta;
    cf->h = h;
    cf->c1 = 1.0 / (g * h);
    cf->m_hat = (1.0 - a) * M->p.m * cf->c1 + M->p.k * b * h / g;
    if (M->damped) cf->m_hat += M->p.c;
    cf->inv_m_hat = 1.0 / cf->m_hat;
    cf->kV = h * (1.0 - b / g);
    cf->kA = h * h * (0.5 - b / g);
    cf->kX = b * h / g;
}

/* The step [s->t, t1] of length h (t1 = s->t + h up to rounding: t1 names the grid point). */
static HOT_INLINE void predict(const step_ctx *C, const dfo_state *s, double h, double t1, trial *tr)
{
    const dfo_model *M = C->M;
    const double a = M->p.alpha, k = M->p.k;
    if (h == C->full.h) {
        tr->k = &C->full;
    } else {
        coef_for(M, h, &tr->own);
        tr->k = &tr->own;
    }
    double A0 = s->A;
    /* Bossak's A belongs to the step length hA; re-base it on h (method.md section 8). The
     * correction is a Taylor term that keeps second order where the steps resolve the fastest
     * time scale of the oscillator; on steps that do not (stiff), it would amplify: skipped. */
    if (a != 0.0 && h != s->hA && fabs(h - s->hA) > 1e-12 * h + 4.0 * DBL_EPSILON * fabs(s->t) &&
        M->rate_max * fmax(h, s->hA) <= 1.0)
        A0 += a * (h - s->hA) * jerk_of(C, s);
    const double c1 = tr->k->c1;
    const double x_pred = s->X + tr->k->kV * s->V + tr->k->kA * A0;
    const double P1 = excitation(C, t1) + C->L.u;
    tr->A0 = A0;
    tr->x_pred = x_pred;
    tr->p_hat = P1 - C->am * A0 + C->am1 * (s->V * c1 + C->g1 * A0) - k * x_pred;
}

/* Complete the step with the end velocity V1 (X1 and A1 from Newmark's kinematics). */
static HOT_INLINE void finish(const step_ctx *C, dfo_state *s, const trial *tr, double V1)
{
    s->X = tr->x_pred + tr->k->kX * V1;
    s->A = (V1 - s->V) * tr->k->c1 - C->g1 * tr->A0;
    s->V = V1;
    s->hA = tr->k->h;
    s->t += tr->k->h;
}

/* Friction at the end of the step: the LCP of method.md section 3 with limit muN. Lemke decides
 * the active complementarity pair; the velocity then follows from that pair's equation. Returns
 * the mode (+1, 0, -1). */
static HOT_INLINE int solve_friction(step_ctx *C, dfo_state *s, const trial *tr, double muN, double *V1, double *F1)
{
    const double mh = tr->k->m_hat, im = tr->k->inv_m_hat, p = tr->p_hat;
    if (C->M->fast && muN == 0.0) {  /* no friction: V1 = p_hat / m_hat */
        *V1 = p * im;
        *F1 = 0.0;
        return dfo_sign(*V1);
    }
    const double Mx[4] = {mh, -mh, -mh, mh};
    const double q[2] = {muN - p, muN + p};
    double z[2], w[2];
    int zb[2];
    /* warm start from the mode before the step: while the block keeps sliding (or sticking) that
     * basis still solves the LCP and no pivot is needed; at a switch it does not, and Lemke decides */
    const int guess[2] = {s->mode > 0, s->mode < 0};
    s->lcp_solves++;
    const lcp_status st = lcp_lemke_warm2(Mx, q, guess, LCP_MAX_PIVOT_COUNT, z, w, zb, NULL);
    if (st != LCP_OK) {
        /* non-finite data means the state overflowed before the LCP */
        if (C->err == DFO_OK) C->err = (st == LCP_BAD_INPUT) ? DFO_ERR_NONFINITE : DFO_ERR_LCP;
        *V1 = 0.0;
        *F1 = 0.0;
        return 0;
    }
    /* 0.0 - x: a zero force is +0, as on the fast path */
    if (zb[0] && z[0] > 0.0) { *V1 = (p - muN) * im; *F1 = 0.0 - muN; return 1; }
    if (zb[1] && z[1] > 0.0) { *V1 = (p + muN) * im; *F1 = muN; return -1; }
    *V1 = 0.0;
    *F1 = 0.0 - p;
    return 0;
}

/* ---- observables ---------------------------------------------------------------------------- */

/* Book-keeping after each phase [ta, s->t] spent in mode_during: switch reports and observables. */
static HOT_INLINE void after_phase(const step_ctx *C, dfo_state *s, double ta, int mode_during, double dX, double F,
                        int mode_before)
{
    const dfo_model *M = C->M;
    if (s->mode == 0 && mode_before != 0) s->stick_tb = NAN; /* a new stick phase */
    if (C->on_switch && s->mode != mode_before) C->on_switch(C->switch_ctx, s->t, s->X, mode_before, s->mode);
    if (!M->p.observe) return;
    const double w0 = M->p.t_obs_start, w1 = M->p.t_obs_stop, tb = s->t;
    if (tb < w0 || ta > w1) return;
    if (mode_during == 0) s->t_stuck += fmax(fmin(tb, w1) - fmax(ta, w0), 0.0);
    if (tb > w1) return;
    if (!s->observed) { s->x_max = s->x_min = s->X; s->observed = 1; }
    if (s->X > s->x_max) s->x_max = s->X;
    if (s->X < s->x_min) s->x_min = s->X;
    if (tb > w0) {
        s->E_friction -= F * dX;
        if (s->mode != mode_before) s->transitions++;
    }
}

/* ---- the three variants --------------------------------------------------------------------- */

/* Without friction every variant is plain Bossak-Newmark. */
static void step_smooth(step_ctx *C, dfo_state *s, double t_end)
{
    const double h = C->h_step;
    trial tr;
    double V1, F1;
    const double ta = s->t, X0 = s->X;
    const int m0 = s->mode;
    predict(C, s, h, t_end, &tr);
    s->mode = solve_friction(C, s, &tr, 0.0, &V1, &F1);
    finish(C, s, &tr, V1);
    s->F = F1;
    after_phase(C, s, ta, s->mode, s->X - X0, s->F, m0);
}

/* The paper's literal scheme: LCP with the previous mode's coefficient, then frictionUpdates
 * re-solves with the coefficient of the result; A follows Bossak's recursion throughout. */
static void step_paper(step_ctx *C, dfo_state *s, double t_end)
{
    const double h = C->h_step;
    const dfo_model *M = C->M;
    trial tr;
    double V1, F1;
    const double ta = s->t, X0 = s->X;
    const int m0 = s->mode;
    predict(C, s, h, t_end, &tr);
    double mu = (s->mode == 0) ? M->mu_b : M->mu_k;
    int o = solve_friction(C, s, &tr, mu * C->L.N, &V1, &F1);
    for (int i = 0; i < M->p.frictionUpdates && M->update; i++) {
        const double mu_new = (o == 0) ? M->mu_b : M->mu_k;
        if (mu_new == mu) break;
        mu = mu_new;
        o = solve_friction(C, s, &tr, mu * C->L.N, &V1, &F1);
    }
    finish(C, s, &tr, V1);
    s->mode = o;
    s->F = F1;
    after_phase(C, s, ta, o, s->X - X0, F1, m0);
}

/* Stick at the end of the step: V = A = 0 (A is then a physical acceleration). The friction
 * holds the static force; when the consistent scheme sticks a step whose solved velocity came out
 * with the wrong sign, the static force may exceed the limit, and the friction is the limit. */
static void stick_after(const step_ctx *C, dfo_state *s, const trial *tr)
{
    finish(C, s, tr, 0.0);
    s->A = 0.0;
    s->hA = 0.0;
    s->mode = 0;
    const double S = dfo_static_force(C->M, &C->L, excitation(C, s->t), s->X);
    s->F = dfo_stick_force(&C->L, S);
}

/* Consistent stick test (method.md section 4, variant 1). */
static void step_consistent(step_ctx *C, dfo_state *s, double t_end)
{
    const double h = C->h_step;
    const dfo_model *M = C->M;
    trial tr;
    double V1, F1;
    const double ta = s->t, X0 = s->X;
    const int m0 = s->mode;
    predict(C, s, h, t_end, &tr);
    if (s->mode == 0) {
        /* A = V = 0: p_hat is exactly the static force P1 - k X */
        int o = solve_friction(C, s, &tr, M->mu_b * C->L.N, &V1, &F1);
        if (o == 0) {
            stick_after(C, s, &tr);
        } else {
            if (M->update) o = solve_friction(C, s, &tr, C->L.muk_N, &V1, &F1);
            finish(C, s, &tr, V1);
            s->mode = o;
            s->F = F1;
        }
    } else {
        const int sdir = s->mode;
        const int o = solve_friction(C, s, &tr, C->L.muk_N, &V1, &F1);
        if (o == sdir) {
            finish(C, s, &tr, V1);
            s->F = F1;
        } else {
            /* the block stops in this step: stick or reverse, judged by the static force at the
             * predicted rest position */
            const double S = dfo_static_force(M, &C->L, excitation(C, t_end), tr.x_pred);
            const int s2 = dfo_sign(S);
            const double V2 = (tr.p_hat - s2 * C->L.muk_N) * tr.k->inv_m_hat;
            if (fabs(S) <= C->L.Fb || s2 * V2 <= 0.0) {
                stick_after(C, s, &tr);
            } else {
                finish(C, s, &tr, V2);
                s->mode = s2;
                s->F = -s2 * C->L.muk_N;
            }
        }
    }
    after_phase(C, s, ta, s->mode, s->X - X0, s->F, m0);
}

/* The stick phase's next breakaway in the state holds for the current static force and limit. */
static int breakaway_known(const step_ctx *C, const dfo_state *s)
{
    return !isnan(s->stick_tb) && s->stick_C == C->L.u - C->M->p.k * s->X && s->stick_Fb == C->L.Fb;
}

/* The breakaway inside [ta, tb], or INFINITY. It is computed once per stick phase, at its first
 * step, and again only when the inputs change the static force or the limit. */

static double breakaway_time(const step_ctx *C, dfo_state *s, double ta, double tb, int *dir)
{
    if (!breakaway_known(C, s)) {
        const double C0 = C->L.u - C->M->p.k * s->X;
        s->stick_C = C0;
        s->stick_Fb = C->L.Fb;
        s->stick_tb = dfo_next_breakaway(C->M, &C->L, C0, ta, &s->stick_dir);
    }
    *dir = s->stick_dir;
    const double t = (s->stick_tb > ta) ? s->stick_tb : ta;
    return (t <= tb) ? t : INFINITY;
}

/* Start sliding from rest at the current time in direction sd, with the consistent acceleration.
 * The net force is at least the breakaway limit (it may sit on it by rounding at a breakaway). */
static void start_slide(const step_ctx *C, dfo_state *s, int sd, double S)
{
    s->V = 0.0;
    s->hA = 0.0;
    s->mode = sd;
    s->A = dfo_breakaway_accel(C->M, &C->L, sd, S);
    s->F = -sd * C->L.muk_N;
}

/* At rest after a stop: stick if the static force is inside the limit, else slide along it. */
static void restart_from_rest(const step_ctx *C, dfo_state *s)
{
    const double S = dfo_static_force(C->M, &C->L, excitation(C, s->t), s->X);
    const int mode = dfo_rest_mode(&C->L, S);
    if (mode == 0) {
        s->V = s->A = s->hA = 0.0;
        s->mode = 0;
        s->F = -S;
    } else {
        start_slide(C, s, mode, S);
    }
}

/* s V1 at the end of a sliding Bossak step of length h (friction -s mu_k N). */
static double slide_velocity(const step_ctx *C, const dfo_state *s, double h, trial *tr)
{
    predict(C, s, h, s->t + h, tr);
    return s->mode * (tr->p_hat - s->mode * C->L.muk_N) * tr->k->inv_m_hat;
}

/* Root of f in (lo, hi] with f(lo) > 0 >= f(hi): Brent's method to a few ulps of t + h. */
static double stop_length(const step_ctx *C, const dfo_state *s, double lo, double flo, double hi, double fhi)
{
    trial tr;
    double a = lo, b = hi, fa = flo, fb = fhi, c = a, fc = fa, d = b - a, e = d;
    for (int it = 0; it < 200; it++) {
        if (fb == 0.0) return b;
        if ((fb > 0.0) == (fc > 0.0)) { c = a; fc = fa; d = e = b - a; }
        if (fabs(fc) < fabs(fb)) { a = b; b = c; c = a; fa = fb; fb = fc; fc = fa; }
        const double tol = 4.0 * DBL_EPSILON * (fabs(s->t) + fabs(b)) + DBL_MIN;
        const double m = 0.5 * (c - b);
        if (fabs(m) <= tol) break;
        if (fabs(e) >= tol && fabs(fa) > fabs(fb)) {
            double p, q, r;
            const double sfb = fb / fa;
            if (a == c) {
                p = 2.0 * m * sfb;
                q = 1.0 - sfb;
            } else {
                q = fa / fc;
                r = fb / fc;
                p = sfb * (2.0 * m * q * (q - r) - (b - a) * (r - 1.0));
                q = (q - 1.0) * (r - 1.0) * (sfb - 1.0);
            }
            if (p > 0.0) q = -q; else p = -p;
            if (2.0 * p < fmin(3.0 * m * q - fabs(tol * q), fabs(e * q))) { e = d; d = p / q; }
            else { d = m; e = m; }
        } else {
            d = m;
            e = m;
        }
        a = b;
        fa = fb;
        b += (fabs(d) > tol) ? d : (m > 0.0 ? tol : -tol);
        fb = slide_velocity(C, s, b, &tr);
    }
    /* return the bracket end on the stopped side: the block is at rest there */
    return (fb <= 0.0) ? b : c;
}

/* Located switches (method.md section 4, variant 2, the default). */
static void step_located(step_ctx *C, dfo_state *s, double t_end)
{
    const dfo_model *M = C->M;
    trial tr;
    double V1, F1;
    for (int phase = 0; s->t < t_end; phase++) {
        if (phase >= MAX_PHASES_PER_STEP) {
            if (C->err == DFO_OK) C->err = DFO_ERR_NO_PROGRESS;
            return;
        }
        const double ta = s->t, X0 = s->X;
        const int m0 = s->mode;
        if (s->mode == 0) {  /* stuck: X frozen, V = A = 0 */
            int dir = 0;
            const double tb = breakaway_time(C, s, ta, t_end, &dir);
            if (tb == INFINITY) {  /* stays stuck: F is set once, at the end of dfo_advance */
                s->t = t_end;
                after_phase(C, s, ta, 0, 0.0, 0.0, 0);
                continue;
            }
            s->t = tb;
            start_slide(C, s, dir, dfo_static_force(M, &C->L, excitation(C, tb), s->X));
            after_phase(C, s, ta, 0, 0.0, s->F, 0);
            continue;
        }
        /* sliding in direction sd over the remainder r */
        const int sd = s->mode;
        const double r = (phase == 0) ? C->h_step : t_end - ta;
        predict(C, s, r, t_end, &tr);
        const int o = solve_friction(C, s, &tr, C->L.muk_N, &V1, &F1);
        if (o == sd && sd * V1 > 0.0) {
            finish(C, s, &tr, V1);
            s->t = t_end;
            s->F = F1;
            after_phase(C, s, ta, sd, s->X - X0, F1, m0);
            continue;
        }
        /* the block stops inside the remainder: find the sub-step that ends at V = 0 */
        const double fhi = sd * (tr.p_hat - sd * C->L.muk_N) * tr.k->inv_m_hat;
        double lo = 0.0, flo = sd * s->V;
        if (!(flo > 0.0)) {  /* started from rest: find a point where it is still moving */
            lo = r;
            flo = 0.0;
            for (int i = 0; i < 60 && !(flo > 0.0); i++) {
                lo *= 0.5;
                flo = slide_velocity(C, s, lo, &tr);
            }
            if (!(flo > 0.0)) {  /* no motion resolvable in double precision: stays at rest */
                const double S = dfo_static_force(M, &C->L, excitation(C, t_end), s->X);
                s->t = t_end;
                s->V = s->A = s->hA = 0.0;
                s->mode = 0;
                s->F = dfo_stick_force(&C->L, S);
                after_phase(C, s, ta, 0, 0.0, s->F, m0);
                continue;
            }
        }
        const double hs = (fhi == 0.0) ? r : stop_length(C, s, lo, flo, r, fhi);
        predict(C, s, hs, (hs >= r) ? t_end : s->t + hs, &tr);
        finish(C, s, &tr, 0.0);
        s->t = (hs >= r) ? t_end : fmax(ta + hs, nextafter(ta, INFINITY));
        const double dX = s->X - X0;
        restart_from_rest(C, s);
        after_phase(C, s, ta, sd, dX, -sd * C->L.muk_N, m0);
    }
}

/* ---- public API ----------------------------------------------------------------------------- */

static void make_ctx(step_ctx *C, const dfo_model *M, const dfo_inputs *u)
{
    C->on_switch = NULL;
    C->switch_ctx = NULL;
    C->M = M;
    dfo_loads_init(&C->L, M, u);
    C->friction = C->L.Fb > 0.0;  /* Fb >= mu_k N */
    C->err = DFO_OK;
    C->t_grid = NAN;
    C->P_grid = 0.0;
    C->g1 = (1.0 - M->gamma) / M->gamma;
    C->am = M->p.alpha * M->p.m;
    C->am1 = (1.0 - M->p.alpha) * M->p.m;
    coef_for(M, M->p.h, &C->full);
}

void dfo_start(const dfo_model *M, const dfo_inputs *u, double t0, dfo_state *s)
{
    step_ctx C;
    make_ctx(&C, M, u);
    const dfo_state zero = {0};
    *s = zero;
    s->t0 = s->t = t0;
    s->X = M->p.x0;
    s->V = M->p.v0;
    dfo_forget_caches(s);
    s->stick_C = s->stick_Fb = s->stick_tb = NAN;
    s->stick_dir = 0;
    if (s->V == 0.0 && C.L.Fb > 0.0) {
        restart_from_rest(&C, s);
    } else {
        s->mode = dfo_sign(s->V);
        s->F = -s->mode * C.L.muk_N;
        s->A = accel_of(&C, s, t0, s->F);
    }
    s->hA = 0.0;
    if (M->p.observe && t0 >= M->p.t_obs_start && t0 <= M->p.t_obs_stop) {
        s->x_max = s->x_min = s->X;
        s->observed = 1;
    }
}

void dfo_forget_caches(dfo_state *s)
{
    s->exc_n = -1;
    s->exc_c = s->exc_s = 0.0;
}

void dfo_check_caches(const dfo_model *M, dfo_state *s)
{
    if (s->exc_n >= 0) {
        dfo_state fresh = *s;
        fresh.exc_n = -1;
        double c, sn;
        phase_at(M, &fresh, s->exc_n, &c, &sn);
        if (!(c == s->exc_c && sn == s->exc_s)) dfo_forget_caches(s);
    } else if (s->exc_n != -1) {
        dfo_forget_caches(s);
    }
    /* the next breakaway is state, not cache (it depends on when the stick phase began): only a
     * side that cannot be is caught, and then the breakaway is computed anew */
    if (s->stick_dir < -1 || s->stick_dir > 1) {
        s->stick_tb = NAN;
        s->stick_dir = 0;
    }
}

static void step_to(step_ctx *C, dfo_state *s, double t_end)
{
    const double h = C->h_step;
    s->steps++;
    if (!C->friction) { step_smooth(C, s, t_end); s->t = t_end; return; }
    switch (C->M->p.scheme) {
    case DFO_SCHEME_PAPER: step_paper(C, s, t_end); break;
    case DFO_SCHEME_CONSISTENT: step_consistent(C, s, t_end); break;
    default:
        /* Locating a switch inside a step needs steps that resolve the oscillator's fastest time
         * scale; on a stiff step (several natural periods long) restarts from rest with the
         * physical acceleration would feed the unresolved mode: there the consistent stick test,
         * which is stable, takes the step. */
        if (C->M->rate_max * h > STIFF_STEP) step_consistent(C, s, t_end);
        else step_located(C, s, t_end);
        break;
    }
    s->t = t_end;
}

/* |x| <= DBL_MAX is false for infinities and NaN; four independent tests, one branch */
static HOT_INLINE int state_finite(const dfo_state *s)
{
    return (fabs(s->X) <= DBL_MAX) & (fabs(s->V) <= DBL_MAX) & (fabs(s->A) <= DBL_MAX) & (fabs(s->F) <= DBL_MAX);
}

/* A fast path of the located scheme: stuck on a grid point, with the stick phase's next breakaway
 * known, the whole grid steps before it (and before the target, and outside the observation
 * window) change nothing but the time, so they can be taken at once. Returns the last grid index
 * they reach (s->n when there is none). fastPaths = false steps them one by one, to the same bits. */
static long long stuck_until(const step_ctx *C, const dfo_state *s, double t_target, double snap)
{
    const dfo_model *M = C->M;
    const double h = M->p.h;
    if (s->mode != 0 || !C->friction || !M->fast || M->p.scheme != DFO_SCHEME_LOCATED ||
        M->rate_max * h > STIFF_STEP)
        return s->n;
    if (!breakaway_known(C, s)) return s->n;
    double limit = fmin(s->stick_tb, t_target - snap);
    if (M->p.observe && !(s->t > M->p.t_obs_stop)) limit = fmin(limit, M->p.t_obs_start);
    if (!(limit > s->t)) return s->n;
    /* the last m with t0 + m h < limit (the grid points as the stepping loop computes them) */
    long long m = (long long)floor((limit - s->t0) / h);
    while (m > s->n && !(s->t0 + (double)m * h < limit)) m--;
    while (s->t0 + (double)(m + 1) * h < limit) m++;
    return (m > s->n) ? m : s->n;
}

static dfo_status advance(const dfo_model *M, const dfo_inputs *u, dfo_state *s, double t_target,
                          dfo_switch_fn on_switch, void *switch_ctx)
{
    step_ctx C;
    make_ctx(&C, M, u);
    C.on_switch = on_switch;
    C.switch_ctx = switch_ctx;
    const double h = M->p.h;
    /* a grid point this close to the target is the target (rounding of the host's times) */
    const double snap = fmax(1e-9 * h, 8.0 * DBL_EPSILON * fabs(t_target));
    double g_prev = s->t0 + (double)s->n * h;  /* the grid point at or before s->t */
    while (s->t < t_target) {
        if (s->t == g_prev) {
            const long long m = stuck_until(&C, s, t_target, snap);
            if (m > s->n) {
                s->steps += m - s->n;
                s->n = m;
                g_prev = s->t = s->t0 + (double)m * h;
                continue;
            }
        }
        const double grid = s->t0 + (double)(s->n + 1) * h;
        double t_end = t_target;
        C.t_grid = NAN;
        const int from_grid = (s->t == g_prev);
        if (grid - t_target <= snap) {  /* the next grid point is reached in this call */
            if (t_target - grid > snap) t_end = grid;
            s->n++;
            g_prev = grid;
            const double P = grid_excitation(M, s);
            if (t_end == grid) { C.t_grid = grid; C.P_grid = P; }
        }
        if (!(t_end > s->t)) return DFO_ERR_RESOLUTION; /* h below the time resolution at t */
        C.h_step = (from_grid && t_end == grid) ? h : t_end - s->t;
        step_to(&C, s, t_end);
        if (C.err != DFO_OK) return C.err;
        /* An overflow is caught within 16 grid steps and at the end of the call (the friction LCP
         * also refuses non-finite data at every step with friction): in between, a non-finite
         * state only costs a few wasted steps, every loop being bounded. */
        if ((s->n & 15) == 0 && !state_finite(s)) return DFO_ERR_NONFINITE;
    }
    if (!state_finite(s)) return DFO_ERR_NONFINITE;
    /* while stuck (located, consistent) the friction holds the static force: evaluated here, at the
     * communication point, rather than at every stuck step */
    if (C.friction && s->mode == 0 && M->p.scheme != DFO_SCHEME_PAPER) {
        const double S = dfo_static_force(M, &C.L, excitation(&C, s->t), s->X);
        s->F = dfo_stick_force(&C.L, S);
    }
    /* the acceleration output too must be representable */
    if (!isfinite(dfo_acceleration(M, u, s))) return DFO_ERR_NONFINITE;
    return DFO_OK;
}

dfo_status dfo_advance(const dfo_model *M, const dfo_inputs *u, dfo_state *s, double t_target,
                       dfo_switch_fn on_switch, void *switch_ctx)
{
    if (M->p.scheme == DFO_SCHEME_EXACT) return dfo_exact_advance(M, u, s, t_target, on_switch, switch_ctx);
    /* work on a copy that no other pointer can reach, so that the compiler may keep it in registers
     * across the steps; it is written back whatever the outcome (as if worked on in place) */
    dfo_state w = *s;
    const dfo_status st = advance(M, u, &w, t_target, on_switch, switch_ctx);
    *s = w;
    return st;
}

double dfo_acceleration(const dfo_model *M, const dfo_inputs *u, const dfo_state *s)
{
    step_ctx C;
    make_ctx(&C, M, u);
    if (stuck(&C, s) && M->p.scheme != DFO_SCHEME_PAPER) return 0.0;
    return accel_of(&C, s, s->t, s->F);
}

double dfo_stick_fraction(const dfo_model *M, const dfo_state *s)
{
    const double span = fmin(s->t, M->p.t_obs_stop) - M->p.t_obs_start;
    return span > 0.0 ? s->t_stuck / span : 0.0;
}

const char *dfo_status_text(dfo_status st)
{
    switch (st) {
    case DFO_OK: return "ok";
    case DFO_ERR_LCP: return "the friction LCP could not be solved (Lemke failed)";
    case DFO_ERR_NO_PROGRESS: return "too many stick/slip switches inside one internal step";
    case DFO_ERR_NONFINITE: return "the state became non-finite (overflow)";
    case DFO_ERR_RESOLUTION: return "the internal step h is below the time resolution at this time";
    }
    return "unknown status";
}
