/* The oscillator's start-up, outputs and grid snapping, for every scheme (newmark.h); the Bossak
 * schemes' stepping is the friction engine's (osc_bossak.c). See newmark.h and method.md. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "newmark.h"
#include "dmath.h"

#include "friction.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

#define SNAP_MAX_REL_H 1e-5     /* snap tolerance (newmark.h): at most 1e-5 h, */
#define SNAP_MIN_REL_H 1e-7     /* at least 1e-7 h, */
#define SNAP_EPS_T 0x1p16       /* else 2^16 eps |t| */

/* What the start-up and the outputs read of a model and its inputs at one time. */
typedef struct {
    const dfo_model *M;
    dfo_loads L;     /* external and normal force, kinetic magnitude, breakaway limit */
    int friction;    /* friction acts */
    int belt;        /* v_belt set: the friction acts on V - vb, a stuck block moves with the belt */
    double vb;       /* the belt's velocity (0 when never set) */
    double t_grid;   /* a time whose excitation is P_grid (else NaN) */
    double P_grid;
} step_ctx;

/* A stuck block is at rest (V = A = 0, its force the static force clamped to the limit) in every
 * scheme but the paper's. */
static int rests_when_stuck(const dfo_model *M) { return M->p.scheme != DFO_SCHEME_PAPER; }

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
static void phase_at(const dfo_model *M, const dfo_state *s, long long n, double *cos_out, double *sin_out)
{
    dfo_grid_phase(M->p.omega, M->p.phi, s->t0, M->p.h, M->rot_c, M->rot_s, s->exc_n, s->exc_c, s->exc_s, n, cos_out,
                   sin_out);
}

/* Physical acceleration from the equation of motion in the current mode. */
static double accel_of(const step_ctx *C, const dfo_state *s, double t, double F)
{
    const dfo_model *M = C->M;
    double f = excitation(C, t) + C->L.F_ext - M->p.k * s->X + F;
    if (M->damped) f -= M->p.c * s->V;
    return f / M->p.m;
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

/* ---- public API ----------------------------------------------------------------------------- */

static void make_ctx(step_ctx *C, const dfo_model *M, const dfo_inputs *in)
{
    C->M = M;
    dfo_loads_init(&C->L, M, in);
    C->friction = C->L.Fb > 0.0;  /* Fb >= mu_k N */
    C->belt = dfo_belt_on(in);
    C->vb = dfo_belt_speed(in);
    C->t_grid = NAN;
    C->P_grid = 0.0;
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

double dfo_acceleration(const dfo_model *M, const dfo_inputs *in, const dfo_state *s)
{
    step_ctx C;
    make_ctx(&C, M, in);
    if (in->ramp) {
        dfo_loads_at(&C.L, M, in, s->t);
        C.friction = C.L.Fb > 0.0;
    }
    /* (a stuck block whose belt changed since the last step slides: dfo_friction_force) */
    if (stuck(&C, s) && rests_when_stuck(M) && !(C.belt && s->V != C.vb)) return 0.0;
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
    if (stuck(&C, s) && rests_when_stuck(M)) return 0.0;
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
