/* Bossak-Newmark velocity-form stepper with the friction LCP. See newmark.h and method.md. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "newmark.h"
#include "dmath.h"

#include "bossak.h"
#include "roots.h"
#include "friction.h"
#include "lcp.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

#define MAX_PHASES_PER_STEP 64  /* switches one internal step may hold before it is an error */
#define LCP_MAX_PIVOT_COUNT 16  /* a 2 x 2 problem needs at most 3 pivots */
#define STIFF_STEP 10.0         /* rate_max h above which a step does not resolve the motion */
#define SNAP_MAX_REL_H 1e-5     /* snap tolerance (newmark.h): at most 1e-5 h, */
#define SNAP_MIN_REL_H 1e-7     /* at least 1e-7 h, */
#define SNAP_EPS_T 0x1p16       /* else 2^16 eps |t| */
#define BELT_TINY_REL_H 1e-6    /* on a belt, a slide's sub-step below 1e-6 h is taken by Taylor's expansion */

/* The few functions of every internal step are inlined into the stepping loop, so that the state
 * stays in registers (a step costs some 100 ns; a call and its spills are a good part of that). */
#if defined(__GNUC__)
#define HOT_INLINE inline __attribute__((always_inline))
#define COLD __attribute__((noinline, cold))
#else
#define HOT_INLINE inline
#define COLD
#endif

/* The coefficients of a Bossak step that depend on its length h only (eq. 4). */
typedef struct {
    double h;
    double c1;         /* 1 / (gamma h) */
    double m_hat;      /* effective mass (1 - alpha) m c1 + k beta h / gamma (+ c) */
    double inv_m_hat;  /* 1 / m_hat */
    double pred_V, pred_A;  /* x_pred = X + pred_V V + pred_A A0 */
    double corr_V;          /* X1 = x_pred + corr_V V1 */
} step_coef;

/* What sets a scheme apart besides its step (one row per scheme in SCHEMES, below the schemes). */
typedef struct {
    /* a stuck block is at rest: V = A = 0, acceleration 0, and the friction holds the static force
     * (clamped to the limit), set once at the end of each dfo_advance rather than at every step */
    int rests_when_stuck;
    /* the stuck fast path: a stuck block's whole grid steps before its known next breakaway may be
     * taken at once (stuck_until), to the bits of stepping them (the observables' too: stuck_skip) */
    int skips_stuck_steps;
} scheme_rules;

/* What is constant over one call of dfo_advance (inputs are held; with input derivatives, ramp,
 * the loads are those at the end of the current step, set before each step). */
typedef struct {
    const dfo_model *M;
    const scheme_rules *rules;  /* the scheme's row of SCHEMES */
    const dfo_inputs *ramp;     /* the inputs when they vary over the call (their derivatives), else NULL */
    dfo_loads L;     /* external and normal force, kinetic magnitude, breakaway limit */
    step_coef full;  /* the coefficients of a step of the grid length h */
    double g1;       /* (1 - gamma) / gamma */
    double am, am1;  /* alpha m, (1 - alpha) m */
    double h_step;   /* length of the current step: h itself for a whole grid interval (the time
                      * difference of two grid points differs from h by the rounding of t) */
    int friction;    /* friction acts (the LCP is needed) */
    int skip_stuck;  /* the stuck fast path applies (stuck_until) */
    int belt;        /* v_belt set: the friction acts on V - vb, a stuck block moves with the belt */
    double vb;       /* the belt's velocity (0 when never set) */
    int general;     /* belt or Stribeck: the schemes' copies with their code (else the plain ones) */
    double t_grid;   /* end of the current step when it is a grid point (else NaN) */
    double P_grid;   /* the excitation there, from the state's excitation cache */
    dfo_status err;  /* first error met */
    dfo_switch_fn on_switch;
    void *switch_ctx;
    int observe;     /* the observables are on */
    int after_w0;    /* the call began at or after the window's start, with a sample taken */
} step_ctx;

/* One Bossak step of length h from the current state, before the velocity is known (eq. 4). */
typedef struct {
    const step_coef *co;  /* the step's coefficients: the context's for a grid step, else own */
    step_coef own;
    double A0, x_pred, p_hat;
} trial;

/* Where a phase of a step began: time, position and mode (for the observables and switch reports). */
typedef struct {
    double ta, X0;
    int mode0;
} phase_start;

static int stuck(const step_ctx *C, const dfo_state *s) { return C->friction && s->mode == 0; }

/* The kinetic friction magnitude of a block sliding at velocity V: mu_k N (coulomb), or N mu(|V -
 * vb|) (stribeck, friction.h's law). */
static double slide_magnitude(const step_ctx *C, const dfo_loads *L, double V)
{
    if (!C->M->stribeck) return L->muk_N;
    return L->N * dfo_friction_mu(&C->M->law, fabs(V - C->vb));
}

/* The loads as the rest rule and a slide's start read them: with Stribeck the kinetic magnitude is
 * that at the relative speed 0, mu_s N. */
static dfo_loads start_loads(const step_ctx *C, const dfo_loads *L)
{
    dfo_loads S = *L;
    if (C->M->stribeck) S.muk_N = L->N * dfo_friction_mu(&C->M->law, 0.0);
    return S;
}

/* The excitation at t: from the grid cache at the end of the current step, else evaluated. */
static double excitation(const step_ctx *C, double t)
{
    return (t == C->t_grid) ? C->P_grid : dfo_excitation(C->M, t);
}

/* Cosine and sine of the excitation phase at the grid point n, from the cache of the state (see
 * dfo_state; excitation.h's dfo_grid_phase): the value depends on n only. */
static HOT_INLINE void phase_at(const dfo_model *M, const dfo_state *s, long long n, double *cos_out, double *sin_out)
{
    dfo_grid_phase(M->p.omega, M->p.phi, s->t0, M->p.h, M->rot_c, M->rot_s, s->exc_n, s->exc_c, s->exc_s, n, cos_out,
                   sin_out);
}

static double grid_excitation(const dfo_model *M, dfo_state *s)
{
    phase_at(M, s, s->n, &s->exc_c, &s->exc_s);
    s->exc_n = s->n;
    return M->p.P0 * dfo_clamp1(s->exc_c);
}

/* Physical acceleration from the equation of motion in the current mode. */
static double accel_of(const step_ctx *C, const dfo_state *s, double t, double F)
{
    const dfo_model *M = C->M;
    double f = excitation(C, t) + C->L.F_ext - M->p.k * s->X + F;
    if (M->damped) f -= M->p.c * s->V;
    return f / M->p.m;
}

/* The rate of the net applied force from varying inputs, dF_ext/dt - mode mu_k dN/dt (out of the
 * stepping loop's code: held inputs never call it). */
static COLD double ramp_force_rate(const step_ctx *C, const dfo_state *s)
{
    double dF, dN;
    dfo_input_rates(C->M, C->ramp, s->t, &dF, &dN);
    return dF - s->mode * C->M->mu_k * dN;
}

/* x''' from the time derivative of the equation of motion (0 while stuck), with the inputs' rates. */
static double jerk_of(const step_ctx *C, const dfo_state *s)
{
    if (stuck(C, s)) return 0.0;
    const dfo_model *M = C->M;
    const double F = -s->mode * slide_magnitude(C, &C->L, s->V);
    double j = dfo_excitation_rate(M, s->t) - M->p.k * s->V;
    if (M->damped) j -= M->p.c * accel_of(C, s, s->t, F);
    if (C->ramp) j += ramp_force_rate(C, s);
    if (M->stribeck) /* d F / dt = -N mu'(u) a, u = |V - vb| */
        j -= C->L.N * dfo_friction_dmu(&M->law, fabs(s->V - C->vb)) * accel_of(C, s, s->t, F);
    return j / M->p.m;
}

static void coef_for(const dfo_model *M, double h, step_coef *cf)
{
    const double a = M->p.alpha, g = M->gamma, b = M->beta;
    dfo_bossak_kin kin;
    dfo_bossak_kin_for(h, g, b, &kin);
    cf->h = kin.h;
    cf->c1 = kin.c1;
    cf->m_hat = (1.0 - a) * M->p.m * cf->c1 + M->p.k * b * h / g;
    if (M->damped) cf->m_hat += M->p.c;
    cf->inv_m_hat = 1.0 / cf->m_hat;
    cf->pred_V = kin.pred_V;
    cf->pred_A = kin.pred_A;
    cf->corr_V = kin.corr_V;
}

/* The step [s->t, t1] of length h (t1 = s->t + h up to rounding: t1 names the grid point). */
static HOT_INLINE void predict(const step_ctx *C, const dfo_state *s, double h, double t1, trial *tr)
{
    const dfo_model *M = C->M;
    const double a = M->p.alpha;
    if (h == C->full.h) {
        tr->co = &C->full;
    } else {
        coef_for(M, h, &tr->own);
        tr->co = &tr->own;
    }
    double A0 = s->A;
    /* Bossak's A belongs to the step length hA; re-base it on h (method.md section 8). The
     * correction is a Taylor term that keeps second order where the steps resolve the fastest
     * time scale of the oscillator; on steps that do not (stiff), it would amplify: skipped. */
    if (a != 0.0 && h != s->hA && fabs(h - s->hA) > 1e-12 * h + 4.0 * DBL_EPSILON * fabs(s->t) &&
        M->rate_max * fmax(h, s->hA) <= 1.0)
        A0 += a * (h - s->hA) * jerk_of(C, s);
    const double c1 = tr->co->c1;
    const double x_pred = s->X + tr->co->pred_V * s->V + tr->co->pred_A * A0;
    const double P1 = excitation(C, t1) + C->L.F_ext;
    tr->A0 = A0;
    tr->x_pred = x_pred;
    tr->p_hat = P1 - C->am * A0 + C->am1 * (s->V * c1 + C->g1 * A0) - M->p.k * x_pred;
}

/* Complete the step with the end velocity V1 (X1 and A1 from Newmark's kinematics). */
static HOT_INLINE void finish(const step_ctx *C, dfo_state *s, const trial *tr, double V1)
{
    s->X = tr->x_pred + tr->co->corr_V * V1;
    s->A = (V1 - s->V) * tr->co->c1 - C->g1 * tr->A0;
    s->V = V1;
    s->hA = tr->co->h;
    s->t += tr->co->h;
}

/* Friction at the end of the step: the LCP of method.md section 3 with limit muN. Lemke decides
 * the active complementarity pair; the velocity then follows from that pair's equation. Returns
 * the mode (+1, 0, -1). */
static HOT_INLINE int solve_friction(step_ctx *C, dfo_state *s, const trial *tr, double muN, double *V1, double *F1,
                                     const int general)
{
    const int belt = general && C->belt;
    const double vb = general ? C->vb : 0.0;
    const double mh = tr->co->m_hat, im = tr->co->inv_m_hat;
    if (C->M->fast && muN == 0.0) {  /* no friction: V1 = p_hat / m_hat */
        *V1 = tr->p_hat * im;
        *F1 = 0.0;
        return dfo_sign(*V1 - vb);
    }
    /* the LCP on the velocity relative to the belt, V1 - vb: m_hat (V1 - vb) = p_hat - m_hat vb + F1 */
    const double p = belt ? tr->p_hat - mh * vb : tr->p_hat;
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
    if (zb[0] && z[0] > 0.0) { *V1 = (p - muN) * im; *F1 = 0.0 - muN; if (belt) *V1 += vb; return 1; }
    if (zb[1] && z[1] > 0.0) { *V1 = (p + muN) * im; *F1 = muN; if (belt) *V1 += vb; return -1; }
    *V1 = vb;
    *F1 = 0.0 - p;
    return 0;
}

/* A sliding step in direction dir (dir (V1 - vb) > 0) with the friction law: the relative speed u =
 * dir (V1 - vb) at its end, the root of m_hat u = q - N mu(u), q = dir (p_hat - m_hat vb) (coulomb:
 * closed form). Where no root u > 0 exists (q <= N mu(0)) it returns (q - N mu(0)) / m_hat <= 0, so
 * that the value is continuous in the step length and its sign tells a stop (dfo_root_bracketed's root).
 * The root is dfo_stribeck_speed's (friction.h), the chain's too. */
static double slide_value(const step_ctx *C, const dfo_loads *L, const trial *tr, int dir)
{
    const double im = tr->co->inv_m_hat, mh = tr->co->m_hat;
    const double q = dir * (C->belt ? tr->p_hat - mh * C->vb : tr->p_hat);
    if (!C->M->stribeck) return (q - L->muk_N) * im;
    return dfo_stribeck_speed(&C->M->law, L->N, q, mh, im);
}

/* ---- phases, stick and observables ----------------------------------------------------------- */

static HOT_INLINE phase_start begin_phase(const dfo_state *s)
{
    const phase_start b = {s->t, s->X, s->mode};
    return b;
}

/* The part of [a, b] inside the observation window (comparisons, not fmin/fmax: those are library
 * calls without -ffinite-math-only). */
static HOT_INLINE double in_window(const dfo_model *M, double a, double b)
{
    const double w0 = M->p.t_obs_start, w1 = M->p.t_obs_stop;
    const double lo = (a > w0) ? a : w0, hi = (b < w1) ? b : w1;
    return (hi > lo) ? hi - lo : 0.0;
}

/* The stuck stretch open since s->stuck_from ends at t: its part inside the window is stuck time. */
static HOT_INLINE void close_stuck(const dfo_model *M, dfo_state *s, double t)
{
    const double d = in_window(M, s->stuck_from, t);
    if (d > 0.0) s->t_stuck += d;
    s->stuck_from = NAN;
}

/* Book-keeping after a phase [b->ta, s->t] spent in mode_during with friction force F: the stick
 * phase's breakaway to be found anew, switch reports and observables. A phase's X is sampled where
 * it ends inside the window, its friction work and a switch counted where it ends after the window
 * opens (ta <= tb: a phase that begins after the window also ends after it). */
static HOT_INLINE void end_phase_on(step_ctx *C, dfo_state *s, const phase_start *b, int mode_during, double F,
                                    const int belt)
{
    const dfo_model *M = C->M;
    const double ta = b->ta, tb = s->t, dX = s->X - b->X0;
    const double w0 = M->p.t_obs_start, w1 = M->p.t_obs_stop;
    const int mode_before = b->mode0;
    if (s->mode == 0 && mode_before != 0) s->stick_tb = NAN; /* a new stick phase */
    if (s->mode != mode_before) {
        s->t_switch = tb;
        if (C->on_switch) C->on_switch(C->switch_ctx, tb, s->X, mode_before, s->mode);
        if (C->observe && tb > w0 && tb <= w1) s->transitions++;
    }
    if (!C->observe) return;
    if (mode_during == 0) {
        if (isnan(s->stuck_from)) s->stuck_from = ta;
    } else if (!isnan(s->stuck_from)) {
        close_stuck(M, s, ta);
    }
    /* the energy dissipated: the friction's work on the relative motion, where the phase ends after
     * the window opens (a phase of length 0 has none: dX = 0, and E_friction, +0 at the start, is
     * never -0) */
    const double X = s->X;
    double W = F * (belt ? dX - C->vb * (tb - ta) : dX);
    if (C->after_w0) {  /* the call began in the window, sampled already: tb >= w0 */
        if (tb > w1) return;
    } else {
        if (tb < w0 || tb > w1) return;
        if (!s->observed) { s->x_max = s->x_min = X; s->observed = 1; }
        if (!(tb > w0)) W = 0.0;
    }
    s->x_max = (X > s->x_max) ? X : s->x_max;
    s->x_min = (X < s->x_min) ? X : s->x_min;
    s->E_friction -= W;
}

static HOT_INLINE void end_phase(step_ctx *C, dfo_state *s, const phase_start *b, int mode_during, double F)
{
    end_phase_on(C, s, b, mode_during, F, C->belt);
}

/* The static force on the block at its current time and position. */
static double static_force_now(const step_ctx *C, const dfo_state *s)
{
    const double S = dfo_static_force(C->M->p.k, &C->L, excitation(C, s->t), s->X);
    /* riding on the belt the damper pulls with c vb */
    return (C->belt && C->M->p.c != 0.0) ? S - C->M->p.c * C->vb : S;
}

/* Enter (or stay in) stick where the block is: V = A = 0 (A is then a physical acceleration, hA
 * = 0), mode 0, and the friction holds the static force F_static, clamped to the limit (it exceeds
 * the limit only when the consistent scheme sticks a step whose velocity came out with the wrong
 * sign, or when no motion is resolvable). */
static void enter_stick(const step_ctx *C, dfo_state *s, double F_static)
{
    s->A = s->hA = 0.0;
    s->V = C->vb;
    s->mode = 0;
    s->F = dfo_stick_force(&C->L, F_static);
}

/* Complete the step with the block at rest at its end, stuck there. */
static void stick_after(const step_ctx *C, dfo_state *s, const trial *tr)
{
    finish(C, s, tr, C->vb);
    enter_stick(C, s, static_force_now(C, s));
}

/* Start sliding from rest at the current time in direction dir, with the consistent acceleration. */
static void start_slide(const step_ctx *C, dfo_state *s, int dir, double F_static)
{
    const dfo_loads L = start_loads(C, &C->L);
    s->V = C->vb;
    s->hA = 0.0;
    s->mode = dir;
    s->A = dfo_breakaway_accel(C->M->p.m, &L, dir, F_static);
    s->F = -dir * L.muk_N;
}

/* At rest after a stop (or at start-up): the rest rule decides between stick and slide. */
static void restart_from_rest(const step_ctx *C, dfo_state *s)
{
    const double F_static = static_force_now(C, s);
    const int mode = dfo_rest_mode(&C->L, F_static);  /* Fb = max(mu_s, mu_k) N: either law */
    if (mode == 0) enter_stick(C, s, F_static);
    else start_slide(C, s, mode, F_static);
}

/* Steps that resolve the oscillator's fastest time scale (a stiff step is several periods long). */
static int resolves(const dfo_model *M, double h) { return M->rate_max * h <= STIFF_STEP; }

/* ---- the steps of the schemes ---------------------------------------------------------------- */

/* Without friction every variant is plain Bossak-Newmark. */
static void step_smooth(step_ctx *C, dfo_state *s, double t_end)
{
    trial tr;
    double V1, F1;
    const phase_start b = begin_phase(s);
    predict(C, s, C->h_step, t_end, &tr);
    s->mode = solve_friction(C, s, &tr, 0.0, &V1, &F1, 1);
    finish(C, s, &tr, V1);
    s->F = F1;
    end_phase(C, s, &b, s->mode, s->F);
}

/* The paper's literal scheme: LCP with the previous mode's coefficient, then frictionUpdates
 * re-solves with the coefficient of the result; A follows Bossak's recursion throughout, also
 * while stuck (the block is then not exactly at rest, and F is the LCP's). */
static HOT_INLINE void step_paper(step_ctx *C, dfo_state *s, double t_end, const int general)
{
    const dfo_model *M = C->M;
    trial tr;
    double V1, F1;
    const phase_start b = begin_phase(s);
    predict(C, s, C->h_step, t_end, &tr);
    double mu = (s->mode == 0) ? M->mu_b : M->mu_k;
    int mode = solve_friction(C, s, &tr, mu * C->L.N, &V1, &F1, general);
    for (int i = 0; i < M->p.frictionUpdates && M->update; i++) {
        const double mu_new = (mode == 0) ? M->mu_b : M->mu_k;
        if (mu_new == mu) break;
        mu = mu_new;
        mode = solve_friction(C, s, &tr, mu * C->L.N, &V1, &F1, general);
    }
    finish(C, s, &tr, V1);
    s->mode = mode;
    s->F = F1;
    end_phase(C, s, &b, mode, F1);
}

/* Consistent stick test (method.md section 4, variant 1). */
static HOT_INLINE void step_consistent(step_ctx *C, dfo_state *s, double t_end, const int general)
{
    const dfo_model *M = C->M;
    trial tr;
    double V1, F1;
    const phase_start b = begin_phase(s);
    predict(C, s, C->h_step, t_end, &tr);
    if (s->mode == 0) {
        /* A = V = 0: p_hat is exactly the static force P1 - k X */
        int mode = solve_friction(C, s, &tr, M->mu_b * C->L.N, &V1, &F1, general);
        if (mode == 0) {
            stick_after(C, s, &tr);
        } else {
            if (M->update) mode = solve_friction(C, s, &tr, C->L.muk_N, &V1, &F1, general);
            finish(C, s, &tr, V1);
            s->mode = mode;
            s->F = F1;
        }
    } else {
        const int dir = s->mode;
        const int mode = solve_friction(C, s, &tr, C->L.muk_N, &V1, &F1, general);
        if (mode == dir) {
            finish(C, s, &tr, V1);
            s->F = F1;
        } else {
            /* the block stops in this step: stick or reverse, judged by the static force at the
             * predicted rest position */
            double F_static = dfo_static_force(M->p.k, &C->L, excitation(C, t_end), tr.x_pred);
            if (general && C->belt) /* the rest position riding on the belt, and the damper's pull c vb */
                F_static = dfo_static_force(M->p.k, &C->L, excitation(C, t_end), tr.x_pred + tr.co->corr_V * C->vb) -
                           M->p.c * C->vb;
            const int dir_new = dfo_sign(F_static);
            const double V_new = (tr.p_hat - dir_new * C->L.muk_N) * tr.co->inv_m_hat;
            if (fabs(F_static) <= C->L.Fb || dir_new * (general ? V_new - C->vb : V_new) <= 0.0) {
                stick_after(C, s, &tr);
            } else {
                finish(C, s, &tr, V_new);
                s->mode = dir_new;
                s->F = -dir_new * C->L.muk_N;
            }
        }
    }
    end_phase(C, s, &b, s->mode, s->F);
}

/* The consistent step, each copy (with and without the belt's code) out of line. */
static void consistent_step(step_ctx *C, dfo_state *s, double t_end)
{
    if (C->belt) step_consistent(C, s, t_end, 1);
    else step_consistent(C, s, t_end, 0);
}

/* The stick phase's next breakaway in the state holds for the current static force and limit. */
static int breakaway_known(const step_ctx *C, const dfo_state *s)
{
    return !isnan(s->stick_tb) && s->stick_C == C->L.F_ext - C->M->p.k * s->X && s->stick_Fb == C->L.Fb;
}

/* With varying inputs: side times the static force beyond the limit at t (> 0: broken away). */
typedef struct {
    const step_ctx *C;
    const dfo_state *s;
    int side;
} ramp_gap_ctx;

static double ramp_gap(const step_ctx *C, const dfo_state *s, double t, int side)
{
    dfo_loads L;
    dfo_loads_at(&L, C->M, C->ramp, t);
    return side * dfo_static_force(C->M->p.k, &L, excitation(C, t), s->X) - L.Fb;
}

static double ramp_gap_fn(void *ctx, double h)
{
    const ramp_gap_ctx *g = (const ramp_gap_ctx *)ctx;
    return -ramp_gap(g->C, g->s, g->s->t + h, g->side);
}

/* The breakaway inside [ta, tb] with the inputs varying (C->ramp): the side is the one broken
 * through at tb, or at the closed form's breakaway for the loads at tb; the time the root of the
 * gap with the loads varying (Brent, to a few ulps), so that it is placed to second order. */
static COLD double ramp_breakaway(const step_ctx *C, dfo_state *s, double ta, double tb, int *dir)
{
    const dfo_model *M = C->M;
    int side = 0;
    double hi = tb, ghi = 0.0;
    for (int sd = -1; sd <= 1; sd += 2) {
        const double g = ramp_gap(C, s, tb, sd);
        if (g > 0.0) { side = sd; ghi = g; }
    }
    if (side == 0) {
        const dfo_harmonic P = dfo_model_excitation(M);
        int d = 0;
        const double t1 = dfo_next_breakaway(&P, &C->L, C->L.F_ext - M->p.k * s->X, ta, &d);
        if (t1 <= tb && d != 0) {
            const double g = ramp_gap(C, s, t1, d);
            if (g > 0.0) { side = d; hi = t1; ghi = g; }
        }
    }
    s->stick_tb = NAN; /* nothing cached: the loads change every step */
    if (side == 0) return INFINITY;
    *dir = side;
    const double g0 = ramp_gap(C, s, ta, side);
    if (g0 >= 0.0) return ta;
    dfo_state at = *s;
    at.t = ta;
    ramp_gap_ctx g = {C, &at, side};
    return ta + dfo_root_bracketed(ramp_gap_fn, &g, ta, 0.0, -g0, hi - ta, -ghi);
}

/* Riding on the belt from (ta, Xa): side times the static force beyond the limit at t (> 0: broken
 * away), the block at Xa + vb (t - ta), the loads those at t. */
typedef struct {
    const step_ctx *C;
    double ta, Xa;
    int side;
} belt_gap_ctx;

static double belt_gap(const belt_gap_ctx *g, double t)
{
    const step_ctx *C = g->C;
    dfo_loads L = C->L;
    if (C->ramp) dfo_loads_at(&L, C->M, C->ramp, t);
    const double X = g->Xa + C->vb * (t - g->ta);
    return g->side * (dfo_static_force(C->M->p.k, &L, excitation(C, t), X) - C->M->p.c * C->vb) - L.Fb;
}

static double belt_gap_fn(void *ctx, double h)
{
    const belt_gap_ctx *g = (const belt_gap_ctx *)ctx;
    return -belt_gap(g, g->ta + h);
}

/* The breakaway inside [ta, tb] of a block riding on the belt (its static force drifts with its
 * position): the side broken through at tb, the time the root of the gap (Brent, to a few ulps), so
 * that it is placed to second order. A force that crosses the limit and comes back inside one step
 * (a tangency, of order h^2 beyond it) is not seen. */
static COLD double belt_breakaway(const step_ctx *C, dfo_state *s, double ta, double tb, int *dir)
{
    s->stick_tb = NAN; /* nothing cached: the static force drifts */
    for (int sd = -1; sd <= 1; sd += 2) {
        belt_gap_ctx g = {C, ta, s->X, sd};
        const double ghi = belt_gap(&g, tb);
        if (!(ghi > 0.0)) continue;
        *dir = sd;
        const double g0 = belt_gap(&g, ta);
        if (g0 >= 0.0) return ta;
        return ta + dfo_root_bracketed(belt_gap_fn, &g, ta, 0.0, -g0, tb - ta, -ghi);
    }
    return INFINITY;
}

/* The breakaway inside [ta, tb], or INFINITY. It is computed once per stick phase, at its first
 * step, and again only when the inputs change the static force or the limit. */
static double breakaway_time(const step_ctx *C, dfo_state *s, double ta, double tb, int *dir)
{
    if (C->ramp) return ramp_breakaway(C, s, ta, tb, dir); /* (on a belt: belt_breakaway) */
    if (!breakaway_known(C, s)) {
        const double C0 = C->L.F_ext - C->M->p.k * s->X;
        s->stick_C = C0;
        s->stick_Fb = C->L.Fb;
        const dfo_harmonic P = dfo_model_excitation(C->M);
        s->stick_tb = dfo_next_breakaway(&P, &C->L, C0, ta, &s->stick_dir);
    }
    *dir = s->stick_dir;
    const double t = (s->stick_tb > ta) ? s->stick_tb : ta;
    return (t <= tb) ? t : INFINITY;
}

/* dir V1 at the end of a sliding Bossak step of length h (friction -dir mu_k N, dir = s->mode). */
static COLD double ramp_slide_velocity(const step_ctx *C, const dfo_state *s, double h, trial *tr);

static double slide_velocity(const step_ctx *C, const dfo_state *s, double h, trial *tr)
{
    if (C->ramp) return ramp_slide_velocity(C, s, h, tr);
    predict(C, s, h, s->t + h, tr);
    if (C->belt || C->M->stribeck) return slide_value(C, &C->L, tr, s->mode);
    return s->mode * (tr->p_hat - s->mode * C->L.muk_N) * tr->co->inv_m_hat;
}

/* With varying inputs a trial sub-step of length h takes the loads at its own end, t + h. */
static COLD double ramp_slide_velocity(const step_ctx *C, const dfo_state *s, double h, trial *tr)
{
    step_ctx D = *C;
    dfo_loads_ramp(&D.L, D.M, D.ramp, s->t + h);
    D.friction = D.L.Fb > 0.0;
    predict(&D, s, h, s->t + h, tr);
    if (tr->co == &D.full) { /* the coefficients outlive D */
        tr->own = D.full;
        tr->co = &tr->own;
    }
    if (C->belt || C->M->stribeck) return slide_value(&D, &D.L, tr, s->mode);
    return s->mode * (tr->p_hat - s->mode * D.L.muk_N) * tr->co->inv_m_hat;
}

/* At a switch inside a step with varying inputs: the rest rule and a slide's start acceleration
 * take the loads at the switch time (then those of the step's end again, for its remainder). */
static COLD void ramp_restart(step_ctx *C, dfo_state *s, int breakaway_dir)
{
    const dfo_loads L_end = C->L;
    const int friction_end = C->friction;
    dfo_loads_ramp(&C->L, C->M, C->ramp, s->t);
    C->friction = C->L.Fb > 0.0;
    if (breakaway_dir) start_slide(C, s, breakaway_dir, static_force_now(C, s));
    else restart_from_rest(C, s);
    C->L = L_end;
    C->friction = friction_end;
}

/* dir V1 of a sliding step of length h, as a root function for dfo_root_bracketed. */
typedef struct {
    const step_ctx *C;
    const dfo_state *s;
} slide_root;

static double slide_root_fn(void *ctx, double h)
{
    const slide_root *r = (const slide_root *)ctx;
    trial tr;
    return slide_velocity(r->C, r->s, h, &tr);
}

/* Root of f in (lo, hi] with f(lo) > 0 >= f(hi): Brent's method (roots.h) to a few ulps of t + h. */
static double stop_length(const step_ctx *C, const dfo_state *s, double lo, double flo, double hi, double fhi)
{
    slide_root r = {C, s};
    return dfo_root_bracketed(slide_root_fn, &r, s->t, lo, flo, hi, fhi);
}

/* The located scheme's step. general: the belt and the Stribeck law may act; 0 for the plain
 * Coulomb block on a fixed support, whose copy of this loop then carries none of their code (the
 * step cost unchanged). */
static HOT_INLINE void located(step_ctx *C, dfo_state *s, double t_end, const int general)
{
    const int belt = general && C->belt, strib = general && C->M->stribeck;
    const double vb = general ? C->vb : 0.0;
    /* Locating a switch inside a step needs steps that resolve the oscillator's fastest time scale;
     * on a stiff step (several natural periods long) restarts from rest with the physical
     * acceleration would feed the unresolved mode: there the consistent stick test, which is
     * stable, takes the step. */
    if (!resolves(C->M, C->h_step)) {
        consistent_step(C, s, t_end);
        return;
    }
    trial tr;
    double V1, F1;
    for (int phase = 0; s->t < t_end; phase++) {
        if (phase >= MAX_PHASES_PER_STEP) {
            if (C->err == DFO_OK) C->err = DFO_ERR_NO_PROGRESS;
            return;
        }
        const phase_start b = begin_phase(s);
        if (s->mode == 0) {  /* stuck: X frozen, V = A = 0 (on a belt: X = Xa + vb (t - ta), V = vb) */
            int dir = 0;
            const double tb = belt ? belt_breakaway(C, s, b.ta, t_end, &dir) : breakaway_time(C, s, b.ta, t_end, &dir);
            if (tb == INFINITY) {  /* stays stuck: F is set once, at the end of dfo_advance */
                s->t = t_end;
                if (belt) s->X = b.X0 + vb * (t_end - b.ta);
                end_phase_on(C, s, &b, 0, 0.0, belt);
                continue;
            }
            s->t = tb;
            if (belt) s->X = b.X0 + vb * (tb - b.ta);
            if (C->ramp) ramp_restart(C, s, dir);
            else start_slide(C, s, dir, static_force_now(C, s));
            end_phase_on(C, s, &b, 0, s->F, belt);
            continue;
        }
        /* sliding in direction dir over the remainder r */
        const int dir = s->mode;
        const double r = (phase == 0) ? C->h_step : t_end - b.ta;
        const double F0 = s->F;
        if (belt && s->hA == 0.0 && r <= BELT_TINY_REL_H * C->full.h) {
            /* a sliver of a step after a switch (a breakaway a few ulps before a grid point): on a belt
             * V = vb + u is not small, and Bossak's A = (V1 - V) / (gamma r) would be its rounding
             * over r; Taylor's expansion with the physical acceleration is exact to O(r^2) instead */
            s->X += (s->V + 0.5 * s->A * r) * r;
            s->V += s->A * r;
            s->t = t_end;
            end_phase_on(C, s, &b, dir, s->F, belt);
            continue;
        }
        predict(C, s, r, t_end, &tr);
        /* the LCP with the smallest kinetic magnitude decides: where it stops the block, every law does */
        const double muN_lcp = strib ? C->L.N * fmin(C->M->law.mu_s, C->M->law.mu_k) : C->L.muk_N;
        int mode = solve_friction(C, s, &tr, muN_lcp, &V1, &F1, general);
        if (strib && mode == dir) { /* the speed-dependent friction at the step's end */
            const double u = slide_value(C, &C->L, &tr, dir);
            if (u > 0.0) {
                V1 = vb + dir * u;
                F1 = -dir * C->L.N * dfo_friction_mu(&C->M->law, u);
            } else {
                mode = 0;
            }
        }
        if (mode == dir && dir * (V1 - vb) > 0.0) {
            finish(C, s, &tr, V1);
            s->t = t_end;
            s->F = F1;
            end_phase_on(C, s, &b, dir, strib ? 0.5 * (F0 + F1) : F1, belt);
            continue;
        }
        /* the block stops inside the remainder: find the sub-step that ends at V = vb */
        const double fhi = (belt || strib) ? slide_value(C, &C->L, &tr, dir)
                                                        : dir * (tr.p_hat - dir * C->L.muk_N) * tr.co->inv_m_hat;
        double lo = 0.0, flo = dir * (s->V - vb);
        if (!(flo > 0.0)) {  /* started from rest: find a point where it is still moving */
            lo = r;
            flo = 0.0;
            for (int i = 0; i < 60 && !(flo > 0.0); i++) {
                lo *= 0.5;
                flo = slide_velocity(C, s, lo, &tr);
            }
            if (!(flo > 0.0)) {  /* no motion resolvable in double precision: stays at rest */
                s->t = t_end;
                enter_stick(C, s, static_force_now(C, s));
                end_phase_on(C, s, &b, 0, s->F, belt);
                continue;
            }
        }
        const double hs = (fhi == 0.0) ? r : stop_length(C, s, lo, flo, r, fhi);
        predict(C, s, hs, (hs >= r) ? t_end : s->t + hs, &tr);
        finish(C, s, &tr, vb);
        s->t = (hs >= r) ? t_end : fmax(b.ta + hs, nextafter(b.ta, INFINITY));
        if (C->ramp) ramp_restart(C, s, 0);
        else restart_from_rest(C, s);  /* X stays: the phase's dX is the slide's */
        const double F_stop = -dir * start_loads(C, &C->L).muk_N;
        end_phase_on(C, s, &b, dir, strib ? 0.5 * (F0 + F_stop) : F_stop, belt);
    }
}

/* Located switches (method.md section 4, variant 2, the default). */
static HOT_INLINE void step_located(step_ctx *C, dfo_state *s, double t_end)
{
    if (C->general) located(C, s, t_end, 1);
    else located(C, s, t_end, 0);
}

/* ---- the schemes: their rules and their steps, in one place ---------------------------------- */

/* Adding a scheme: its value in dfo_scheme, its row here, its case in step_to. */
static const scheme_rules SCHEMES[] = {
    [DFO_SCHEME_PAPER] = {.rests_when_stuck = 0, .skips_stuck_steps = 0},
    [DFO_SCHEME_CONSISTENT] = {.rests_when_stuck = 1, .skips_stuck_steps = 0},
    /* on stiff steps the consistent test takes over (step_located): same rest rule, and the fast
     * path is off for a stiff grid (make_ctx) */
    [DFO_SCHEME_LOCATED] = {.rests_when_stuck = 1, .skips_stuck_steps = 1},
};

static const scheme_rules *rules_of(const dfo_model *M)
{
    const int sc = M->p.scheme;
    const int n = (int)(sizeof SCHEMES / sizeof SCHEMES[0]);
    return (sc >= DFO_SCHEME_PAPER && sc < n) ? &SCHEMES[sc] : &SCHEMES[DFO_SCHEME_LOCATED];
}

/* One internal step [s->t, t_end] of length C->h_step. */
static void step_to(step_ctx *C, dfo_state *s, double t_end)
{
    s->steps++;
    if (!C->friction) {
        step_smooth(C, s, t_end);
    } else {
        switch (C->M->p.scheme) {
        /* each with its copy for the belt and the Stribeck law, and one without their code */
        case DFO_SCHEME_PAPER:
            if (C->belt) step_paper(C, s, t_end, 1);
            else step_paper(C, s, t_end, 0);
            break;
        case DFO_SCHEME_CONSISTENT: consistent_step(C, s, t_end); break;
        default: step_located(C, s, t_end); break;
        }
    }
    s->t = t_end;
}

/* ---- public API ----------------------------------------------------------------------------- */

static void make_ctx(step_ctx *C, const dfo_model *M, const dfo_inputs *in)
{
    C->on_switch = NULL;
    C->switch_ctx = NULL;
    C->M = M;
    C->rules = rules_of(M);
    C->ramp = in->ramp ? in : NULL;
    dfo_loads_init(&C->L, M, in);
    C->friction = C->L.Fb > 0.0;  /* Fb >= mu_k N */
    /* the stuck fast path steps whole grid steps of the scheme's own kind: off where a stiff grid
     * hands the steps to the consistent test, and while the inputs vary */
    C->belt = dfo_belt_on(in);
    C->vb = dfo_belt_speed(in);
    C->general = C->belt || M->stribeck;
    C->skip_stuck =
        C->friction && M->fast && C->rules->skips_stuck_steps && resolves(M, M->p.h) && !C->ramp && !C->belt;
    C->err = DFO_OK;
    C->observe = M->p.observe;
    C->after_w0 = 0;
    C->t_grid = NAN;
    C->P_grid = 0.0;
    C->g1 = (1.0 - M->gamma) / M->gamma;
    C->am = M->p.alpha * M->p.m;
    C->am1 = (1.0 - M->p.alpha) * M->p.m;
    coef_for(M, M->p.h, &C->full);
}

void dfo_start(const dfo_model *M, const dfo_inputs *in, double t0, dfo_state *s)
{
    step_ctx C;
    make_ctx(&C, M, in);
    if (M->p.scheme == DFO_SCHEME_EXACT) { /* the exact scheme's excitation (exact for any t0, phi) */
        C.t_grid = t0;
        C.P_grid = dfo_excitation_exact(M, t0);
    }
    const dfo_state zero = {0};
    *s = zero;
    s->t0 = s->t = t0;
    s->X = M->p.x0;
    s->V = M->p.v0;
    dfo_forget_caches(s);
    s->stick_C = s->stick_Fb = s->stick_tb = NAN;
    s->stick_dir = 0;
    s->stuck_from = NAN;
    s->t_switch = -INFINITY;
    if (s->V == C.vb && C.friction) {
        restart_from_rest(&C, s);
    } else {
        s->mode = dfo_sign(s->V - C.vb);
        s->F = -s->mode * slide_magnitude(&C, &C.L, s->V);
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
        double cos_th, sin_th;
        phase_at(M, &fresh, s->exc_n, &cos_th, &sin_th);
        if (!(cos_th == s->exc_c && sin_th == s->exc_s)) dfo_forget_caches(s);
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

double dfo_snap_tolerance(const dfo_model *M, double t)
{
    const double h = M->p.h;
    return fmin(SNAP_MAX_REL_H * h, fmax(SNAP_MIN_REL_H * h, SNAP_EPS_T * DBL_EPSILON * fabs(t)));
}

double dfo_snap_target(const dfo_model *M, const dfo_state *s, double t_target)
{
    return dfo_grid_snap(s->t0, M->p.h, s->n, s->t, t_target, dfo_snap_tolerance(M, t_target));
}

/* |x| <= DBL_MAX is false for infinities and NaN; four independent tests, one branch */
static HOT_INLINE int state_finite(const dfo_state *s)
{
    return (fabs(s->X) <= DBL_MAX) & (fabs(s->V) <= DBL_MAX) & (fabs(s->A) <= DBL_MAX) & (fabs(s->F) <= DBL_MAX);
}

/* The stuck fast path (scheme_rules.skips_stuck_steps): stuck on a grid point, with the stick
 * phase's next breakaway known, the whole grid steps before it (and before t_end) change nothing but
 * the time, so they can be taken at once; the observables account them in closed form (stuck_skip).
 * They stop short of the observation window's ends (so that every step they skip is either outside
 * the window or inside it, where it samples the frozen X). Returns the last grid index they reach
 * (s->n when there is none). fastPaths = false steps them one by one, to the same bits. */
static long long stuck_until(const step_ctx *C, const dfo_state *s, double t_end)
{
    const dfo_model *M = C->M;
    const double h = M->p.h;
    if (s->mode != 0 || !C->skip_stuck || !breakaway_known(C, s)) return s->n;
    double limit = fmin(s->stick_tb, t_end);
    if (M->p.observe && !(s->t > M->p.t_obs_stop))
        limit = fmin(limit, (s->t < M->p.t_obs_start) ? M->p.t_obs_start : M->p.t_obs_stop);
    if (!(limit > s->t)) return s->n;
    /* the last m with t0 + m h < limit (the grid points as the stepping loop computes them) */
    long long m = (long long)floor((limit - s->t0) / h);
    while (m > s->n && !(s->t0 + (double)m * h < limit)) m--;
    while (s->t0 + (double)(m + 1) * h < limit) m++;
    return (m > s->n) ? m : s->n;
}

/* The observables of the stuck grid steps from s->t to t (stuck_until's), as the steps one by one
 * would leave them: the stuck stretch open (or still open), and, inside the window, X sampled (it is
 * frozen); the friction does no work on a block at rest and no switch happens. */
static void stuck_skip(step_ctx *C, dfo_state *s, double t)
{
    const dfo_model *M = C->M;
    if (!C->observe) return;
    if (isnan(s->stuck_from)) s->stuck_from = s->t;
    if (t < M->p.t_obs_start || s->t > M->p.t_obs_stop || t > M->p.t_obs_stop) return;
    if (!s->observed) { s->x_max = s->x_min = s->X; s->observed = 1; }
    s->x_max = (s->X > s->x_max) ? s->X : s->x_max;
    s->x_min = (s->X < s->x_min) ? s->X : s->x_min;
}

static COLD void ramp_loads(step_ctx *C, double t_end)
{
    dfo_loads_ramp(&C->L, C->M, C->ramp, t_end);
    C->friction = C->L.Fb > 0.0;
}

/* The steps of one call of advance, up to t_end_call. */
static dfo_status take_steps(step_ctx *C, dfo_state *s, double t_end_call)
{
    const dfo_model *M = C->M;
    const double h = M->p.h;
    double g_prev = s->t0 + (double)s->n * h;  /* the grid point at or before s->t */
    while (s->t < t_end_call) {
        if (s->t == g_prev) {
            const long long m = stuck_until(C, s, t_end_call);
            if (m > s->n) {
                const double t_m = s->t0 + (double)m * h;
                stuck_skip(C, s, t_m);
                s->steps += m - s->n;
                s->n = m;
                g_prev = s->t = t_m;
                continue;
            }
        }
        const double grid = s->t0 + (double)(s->n + 1) * h;
        double t_end = t_end_call;
        C->t_grid = NAN;
        const int from_grid = (s->t == g_prev);
        if (grid <= t_end_call) {  /* the next grid point is reached in this call: the step ends there */
            t_end = grid;
            s->n++;
            g_prev = grid;
            C->t_grid = grid;
            C->P_grid = grid_excitation(M, s);
        }
        if (!(t_end > s->t)) return DFO_ERR_RESOLUTION; /* h below the time resolution at t */
        C->h_step = (from_grid && t_end == grid) ? h : t_end - s->t;
        if (C->ramp) ramp_loads(C, t_end); /* varying inputs: the loads at the step's end, where Bossak reads them */
        step_to(C, s, t_end);
        if (C->err != DFO_OK) return C->err;
        /* An overflow is caught within 16 grid steps and at the end of the call (the friction LCP
         * also refuses non-finite data at every step with friction): in between, a non-finite
         * state only costs a few wasted steps, every loop being bounded. */
        if ((s->n & 15) == 0 && !state_finite(s)) return DFO_ERR_NONFINITE;
    }
    return DFO_OK;
}

static dfo_status advance(const dfo_model *M, const dfo_inputs *in, dfo_state *s, double t_target,
                          dfo_switch_fn on_switch, void *switch_ctx)
{
    step_ctx C;
    make_ctx(&C, M, in);
    C.on_switch = on_switch;
    C.switch_ctx = switch_ctx;
    C.after_w0 = C.observe && s->observed && s->t >= M->p.t_obs_start;
    /* from here on the call is exactly the one for the grid point t_target snapped to, if any */
    const dfo_status st = take_steps(&C, s, dfo_snap_target(M, s, t_target));
    if (st != DFO_OK) return st;
    if (!state_finite(s)) return DFO_ERR_NONFINITE;
    /* a stuck block at rest: the friction holds the static force, evaluated here, at the
     * communication point, rather than at every stuck step */
    if (stuck(&C, s) && C.rules->rests_when_stuck) s->F = dfo_friction_force(M, in, s);
    /* the acceleration output too must be representable */
    if (!isfinite(dfo_acceleration(M, in, s))) return DFO_ERR_NONFINITE;
    return DFO_OK;
}

dfo_status dfo_bossak_advance(const dfo_model *M, const dfo_inputs *in, dfo_state *s, double t_target,
                              dfo_switch_fn on_switch, void *switch_ctx)
{
    /* work on a copy that no other pointer can reach, so that the compiler may keep it in registers
     * across the steps; it is written back whatever the outcome (as if worked on in place) */
    dfo_state w = *s;
    const dfo_status st = advance(M, in, &w, t_target, on_switch, switch_ctx);
    *s = w;
    return st;
}

/* The excitation at the state's time as the stepper evaluates it: from the excitation cache when
 * the state sits on the grid point the cache holds, else in closed form. */
static double state_excitation(const dfo_model *M, const dfo_state *s)
{
    if (M->p.scheme == DFO_SCHEME_EXACT) return dfo_excitation_exact(M, s->t); /* its phase, exact for any t, phi */
    if (s->exc_n >= 0 && s->exc_n == s->n && s->t == s->t0 + (double)s->n * M->p.h) return M->p.P0 * dfo_clamp1(s->exc_c);
    return dfo_excitation(M, s->t);
}

double dfo_friction_force(const dfo_model *M, const dfo_inputs *in, const dfo_state *s)
{
    dfo_loads L;
    dfo_loads_at(&L, M, in, s->t);
    if (!(L.Fb > 0.0)) return 0.0;
    if (!dfo_belt_on(in) && !M->stribeck) {
        if (s->mode != 0) return -s->mode * L.muk_N;
        return dfo_stick_force(&L, dfo_static_force(M->p.k, &L, state_excitation(M, s), s->X));
    }
    step_ctx C;
    make_ctx(&C, M, in);
    /* a stuck block whose belt changed since the last step slides (dfo_new_inputs) */
    const int mode = (s->mode == 0 && s->V != C.vb) ? dfo_sign(s->V - C.vb) : s->mode;
    if (mode != 0) return -mode * slide_magnitude(&C, &L, s->V);
    return dfo_stick_force(&L, dfo_static_force(M->p.k, &L, state_excitation(M, s), s->X) - M->p.c * C.vb);
}

/* The belt changed at the communication point s->t: the block keeps its velocity, so its mode is
 * that of the new relative velocity; a slide (new, or reversed relative to the belt) starts with
 * the physical acceleration (hA = 0), and a block that now moves with the belt is at rest on it,
 * where the rest rule decides. A change of mode is a switch (reported, observed). */
static void new_belt(const dfo_model *M, const dfo_inputs *in, dfo_state *s)
{
    step_ctx C;
    make_ctx(&C, M, in);
    if (C.ramp) {
        dfo_loads_at(&C.L, M, in, s->t);
        C.friction = C.L.Fb > 0.0;
    }
    C.t_grid = s->t;
    C.P_grid = state_excitation(M, s);
    const phase_start b = begin_phase(s);
    if (!C.friction) return;
    if (s->V == C.vb) {
        if (s->mode == 0) return; /* riding on it already */
        restart_from_rest(&C, s);
    } else {
        s->mode = dfo_sign(s->V - C.vb);
        s->F = -s->mode * slide_magnitude(&C, &C.L, s->V);
        s->hA = 0.0;
        s->A = accel_of(&C, s, s->t, s->F);
    }
    s->stick_tb = NAN;
    if (s->mode != b.mode0) {
        s->t_switch = s->t;
        if (M->p.observe && s->t > M->p.t_obs_start && s->t <= M->p.t_obs_stop) s->transitions++;
        if (s->mode != 0 && !isnan(s->stuck_from)) close_stuck(M, s, s->t);
    }
}

void dfo_new_inputs(const dfo_model *M, const dfo_inputs *old_in, const dfo_inputs *new_in, dfo_state *s)
{
    if (M->p.scheme == DFO_SCHEME_EXACT) return;
    if (dfo_belt_speed(old_in) != dfo_belt_speed(new_in) || (old_in->v_belt_set != new_in->v_belt_set && s->V != 0.0)) {
        new_belt(M, new_in, s);
        return;
    }
    if (s->mode == 0) return;
    if (M->stribeck || dfo_belt_on(new_in)) { /* the kinetic force with the new loads (their rates aside) */
        step_ctx C;
        make_ctx(&C, M, new_in);
        dfo_loads_at(&C.L, M, new_in, s->t);
        dfo_loads a;
        dfo_loads_at(&a, M, old_in, s->t);
        const double Fb = -s->mode * slide_magnitude(&C, &C.L, s->V);
        const double dF = (C.L.F_ext - a.F_ext) + (Fb - s->F);
        if (dF == 0.0) return;
        s->A += dF / M->p.m;
        s->F = Fb;
        return;
    }
    dfo_loads a, b;
    dfo_loads_at(&a, M, old_in, s->t);
    dfo_loads_at(&b, M, new_in, s->t);
    const double dF = (b.F_ext - a.F_ext) - s->mode * (b.muk_N - a.muk_N);
    if (dF == 0.0) return;
    s->A += dF / M->p.m;
    s->F = -s->mode * b.muk_N;
}

double dfo_acceleration(const dfo_model *M, const dfo_inputs *in, const dfo_state *s)
{
    step_ctx C;
    make_ctx(&C, M, in);
    if (C.ramp) {
        dfo_loads_at(&C.L, M, in, s->t);
        C.friction = C.L.Fb > 0.0;
    }
    /* (a stuck block whose belt changed since the last step slides: dfo_friction_force) */
    if (stuck(&C, s) && C.rules->rests_when_stuck && !(C.belt && s->V != C.vb)) return 0.0;
    if (M->p.scheme == DFO_SCHEME_EXACT) { /* the exact scheme's excitation (exact for any t, phi) */
        C.t_grid = s->t;
        C.P_grid = dfo_excitation_exact(M, s->t);
    }
    return accel_of(&C, s, s->t, s->F);
}

double dfo_jerk(const dfo_model *M, const dfo_inputs *in, const dfo_state *s)
{
    step_ctx C;
    make_ctx(&C, M, in);
    dfo_loads_at(&C.L, M, in, s->t);
    C.friction = C.L.Fb > 0.0;
    if (stuck(&C, s) && C.rules->rests_when_stuck) return 0.0;
    if (M->p.scheme == DFO_SCHEME_EXACT) {
        C.t_grid = s->t;
        C.P_grid = dfo_excitation_exact(M, s->t);
    }
    /* the rate of the acceleration in the current mode (jerk_of, with the state's own friction force) */
    const dfo_model *Mm = C.M;
    double j = dfo_excitation_rate(Mm, s->t) - Mm->p.k * s->V;
    if (Mm->damped || Mm->p.c != 0.0) j -= Mm->p.c * accel_of(&C, s, s->t, s->F);
    double dF, dN;
    dfo_input_rates(Mm, in, s->t, &dF, &dN);
    j += dF;
    if (C.friction) j -= s->mode * Mm->mu_k * dN;
    return j / Mm->p.m;
}

double dfo_stuck_time(const dfo_model *M, const dfo_state *s)
{
    return isnan(s->stuck_from) ? s->t_stuck : s->t_stuck + in_window(M, s->stuck_from, s->t);
}

double dfo_stick_fraction(const dfo_model *M, const dfo_state *s)
{
    const double span = fmin(s->t, M->p.t_obs_stop) - M->p.t_obs_start;
    return span > 0.0 ? dfo_stuck_time(M, s) / span : 0.0;
}
