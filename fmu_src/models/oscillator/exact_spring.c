/* The exact scheme's spring phase (k > 0): closed-form phases, events found without stepping over a
 * zero, and its event loop. See exact_spring.h, exact.h and method.md sections 5 and 10. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "exact_spring.h"
#include "ddouble.h"
#include "dmath.h"
#include "exact_observe.h"
#include "exact_poly.h"
#include "exact_sens.h"

#include "friction.h"

#include <float.h>
#include <math.h>
#include <limits.h>
#include <stddef.h>

#define TWO_PI (2.0 * DFO_PI)
#define ROUND DFO_EXACT_ROUND /* relative rounding level of the zero tests (as the reference) */
#define D_MIN 0.02                 /* |1 - lambda^2 + 2 i zeta lambda| below which the uniform form is used: above
                                    * it the steady-state form loses at most a factor 1 / D_MIN to cancellation */
#define ENERGY_SPAN 1.0            /* tau span over which the energy bound of the derivatives holds */
#define BOUND_SAFETY (1.0 + 1e-9)  /* the bounds are computed in floating point */
#define MAX_SEARCH 10000000L       /* evaluations one phase's search may take before it is an error */
#define MAX_START 200              /* steps of a slide from rest before it counts as not starting */
#define MAX_STALL 64               /* events in a row at one instant before it is an error */
#define MAX_POLISH 60              /* Newton / bisection steps of a bracketed stop */
#define START_FRACTION 0.9         /* share of the certified first step of a slide from rest */
#define QUINTIC_STEPS 1            /* Newton steps from the cubic guess to the quintic model's root */
#define SMALL_ANGLE 0.0625         /* |(wd - lambda) tau| below which wd tau's sin, cos rotate lambda tau's */
#define PHASOR_MAX 0.25            /* |p - i lambda| below which the phasor bound is tried (near resonance) */
#define SPAN_GROWTH 1.25           /* the next step's first span over the last step */
#define TAYLOR_REACH 2.0           /* the Taylor root is tried when within this multiple of the certified step */
#define CARRY_MAX 16               /* reversals in a row that carry the excitation phase (each adds a rounding of
                                    * lambda tau to it) before it is computed from the absolute time again */
#define NEAR_CRIT 0.5              /* wd or wh below which the free part is bounded without 1 / wd, 1 / wh */
#define SPAN_TURNS 64.0            /* turns of the excitation or the free vibration after which a long slip
                                    * phase restarts (its local phase lambda tau stays small: exact to rounding) */
#define SCALE_MAX 1000             /* |log2| of the length scale at most (a power of 2 that is a normal double) */
#define SCALED_MAX 0x1p400         /* a scaled length beyond this: the motion leaves the double range */

/* Inside a call the events' times are double-doubles (ddouble.h); a call starts and ends on the
 * host's times, which are doubles. */

/* What is constant over one call. Lengths are in units of the length scale Ls (a power of 2, so the
 * scaling is exact): the motion's squares never overflow or underflow, whatever its size. */
typedef struct {
    const dfo_model *M;
    dfo_loads L;                  /* the loads (physical) */
    dfo_loads Ls_;                /* the loads over Ls: the friction rules' forces in the scaled units */
    double Ls, iLs;               /* the length scale and its inverse */
    double fP, fF;                /* |P0| / Ls, F_ext / Ls */
    double omega;                 /* excitation angular frequency */
    dfo_dd ph;                        /* the excitation phase at t = 0 (phi, + pi when P0 < 0), reduced mod 2 pi */
    double k, w0, zeta, lam, a;   /* a = |P0| / (k Ls) */
    int near_crit;                /* wd or wh below NEAR_CRIT: the free part's bounds without 1 / wd, 1 / wh */
    int modal;                    /* over-damped away from critical: the derivatives from the two modes */
    double r1k[8], r2k[8];        /* r1^k, r2^k (modal) */
    double u_span;                /* tau after which a slip phase restarts (SPAN_TURNS turns) */
    double wd, wh, r1, r2;        /* sqrt(1 - zeta^2); sqrt(zeta^2 - 1), roots -1/(zeta + wh), -(zeta + wh) */
    double inv_wd, inv_D2;        /* 1 / wd (under-damped), 1 / |D|^2 */
    double Dr, Di, D2;            /* D = 1 - lambda^2 + 2 i zeta lambda, |D|^2 */
    int uniform;                  /* near resonance with little damping: the uniform form */
    int wmul;                     /* wd = wmul lambda (1 ... 4; 0: otherwise): wd tau from lambda tau's sin, cos */
    double yk[7][4];              /* y^(k) = yk[k] . (y, y', cos theta, sin theta), from the equation of motion */
    double ea[8], eb[8];          /* the energy bound of |y^(k)|: ea[k] + eb[k] R */
    double lk[8];                 /* lambda^k */
    double wd_lam;                /* wd - lambda */
    int phasor;                   /* the phasor bound (under-damped, steady form) */
    double p3r, p3i, p4r, p4i;    /* p^3, p^4, p = -zeta + i wd */
    double w_abs;                 /* |p - i lambda| */
    dfo_switch_fn on_switch;
    void *switch_ctx;
    long long events;
    double first_span;            /* the span the bounds of a phase's first step are first tried over */
    /* polynomial inputs (dfo_exact_advance_poly; poly = 0 otherwise): physical, in s = t - q_t0,
     * F_ext(t) = qF[0] + qF[1] s + qF[2] s^2 / 2 and N(t) = qN[0] + qN[1] s + qN[2] s^2 / 2 (N + N_ext(t) on a
     * piece where it is > 0, all 0 on a piece where it is <= 0: the normal force max(N + N_ext(t), 0)) */
    int poly;
    double q_t0, qF[3], qN[3];
    /* a moving belt (belt = 1, with poly = 1: its loop): the friction acts on the velocity relative to the
     * belt vb (physical; vbs = vb / Ls), a stuck block rides on it (X = X_a + vbs (t - t_a), V = vbs) */
    int belt;
    double vb, vbs;
} ex_ctx;

/* One slip phase from (ta, X, V) in direction s. */
typedef struct {
    int s;
    double ta, xc;             /* start time; offset x_c = (F_ext - s mu_k N) / k */
    double c0, s0;             /* cos, sin of the excitation phase at ta */
    double hy, hv;             /* data of the free (homogeneous) part at tau = 0 */
    double Qr, Qi;             /* steady form: Q = a e^{i theta_a} / D; uniform: q = a e^{i theta_a} / (2 i wd) */
    double q1r, q1i, q2r, q2i; /* uniform form: q p1, q p2, p1,2 = -zeta +- i wd */
    double Qabs;               /* steady form: |Q| */
    double fA, fB;             /* free part: |C| (under-damped), |A|, |B| (critical), |alpha|, |beta| (over) */
    double Cr, Ci;             /* under-damped: the free part is Re[C e^{p tau}], C = hy - i b */
    double gy, gb;             /* near critical: |hy|, |hv + zeta hy| (the free part's bounds without 1 / wd, 1 / wh) */
    double al, be;             /* modal: the free part is al e^{r1 tau} + be e^{r2 tau} */
    /* polynomial inputs (poly): x = xc + y + xp1 u + xp2 u^2 / 2 (xc + xp1 u + xp2 u^2 / 2 the polynomial
     * particular solution, y the harmonic motion above), and the normal force n0 + n1 u + n2 u^2 / 2 */
    int poly;
    double xp1, xp2, n0, n1, n2;
    /* on a belt, y' is the velocity relative to the belt (xp1 = xp1a - vbu, vbu = vbs / w0, xp1a the
     * particular solution's own): x = xc + y + vbu u, the search's zero is the stop at v = vb */
    double xp1a, vbu;
} ex_phase;

/* y and its derivatives in tau up to the sixth at tau = u, and the free part's decay factors there. */
typedef struct {
    double u, y, y1, y2, y3, y4, y5, y6;
    double cth, sth; /* cos, sin of the excitation phase theta there */
    double Fr, Fi, Gr, Gi; /* phasor bound: the forced part Q e^{i lambda tau}, the free part C e^{p tau} */
    double e1, e2; /* exp(-zeta u) (e2 unused), or exp(r1 u), exp(r2 u) (over-damped) */
    double hy, hy1; /* polynomial inputs: y, y' of the harmonic part alone (y, y1 ... y6 are the motion's) */
} ex_val;

/* The excitation's phase at t = 0: phi mod 2 pi exactly (a large phi keeps its phase), then + pi for
 * a negative amplitude. */
static dfo_dd phase0(const dfo_params *p) { return dfo_dd_phase0(p->phi, p->P0 < 0.0); }

/* The length scale: the loads over Ls, and what depends on them. */
static void ctx_scale(ex_ctx *C, int e)
{
    C->Ls = dfo_pow2(e);
    C->iLs = dfo_pow2(-e);
    C->Ls_ = C->L;
    C->Ls_.F_ext *= C->iLs;
    C->Ls_.N *= C->iLs;
    C->Ls_.muk_N *= C->iLs;
    C->Ls_.Fb *= C->iLs;
    C->fP = C->M->P_amp * C->iLs;
    C->vbs = C->vb * C->iLs;
    C->fF = C->Ls_.F_ext;
    C->a = C->fP / C->k;
    const double z = C->zeta;
    /* y'' = a cos theta - 2 zeta y' - y and its derivatives: y^(k+2) = a cos^(k) theta - 2 zeta y^(k+1) - y^(k) */
    for (int j = 0; j < 4; j++) C->yk[0][j] = C->yk[1][j] = 0.0;
    C->yk[0][0] = C->yk[1][1] = 1.0;
    for (int k = 0; k + 2 < 7; k++) {
        const double f = C->a * C->lk[k]; /* a d^k/dtau^k cos theta = f (cos, -sin, -cos, sin) theta */
        for (int j = 0; j < 4; j++) C->yk[k + 2][j] = -2.0 * z * C->yk[k + 1][j] - C->yk[k][j];
        C->yk[k + 2][2 + (k & 1)] += ((k & 3) == 0 || (k & 3) == 3) ? f : -f;
    }
    /* energy: |y| and |y'| at most R, |y^(k+2)| <= a lambda^k + 2 zeta e_(k+1) + e_k */
    C->ea[0] = C->ea[1] = 0.0;
    C->eb[0] = C->eb[1] = 1.0;
    for (int k = 0; k + 2 < 8; k++) {
        C->ea[k + 2] = C->a * C->lk[k] + 2.0 * z * C->ea[k + 1] + C->ea[k];
        C->eb[k + 2] = 2.0 * z * C->eb[k + 1] + C->eb[k];
    }
}

static void ctx_init_scaled(ex_ctx *C, const dfo_model *M, const dfo_inputs *in, int e)
{
    const dfo_params *p = &M->p;
    C->M = M;
    dfo_loads_init(&C->L, M, in);
    C->k = p->k;
    C->w0 = sqrt(p->k / p->m);
    C->zeta = p->c / (2.0 * sqrt(p->k * p->m));
    C->lam = p->omega / C->w0;
    C->omega = p->omega;
    C->ph = phase0(p);
    const double z = C->zeta;
    C->wd = sqrt(fmax(0.0, (1.0 - z) * (1.0 + z)));
    C->wh = sqrt(fmax(0.0, (z - 1.0) * (z + 1.0)));
    C->r1 = (z > 1.0) ? -1.0 / (z + C->wh) : -z;
    C->r2 = (z > 1.0) ? -(z + C->wh) : -z;
    C->near_crit = (z < 1.0) ? C->wd < NEAR_CRIT : C->wh < NEAR_CRIT;
    C->modal = z > 1.0 && !C->near_crit;
    {
        double q1 = 1.0, q2 = 1.0;
        for (int k = 0; k < 8; k++, q1 *= C->r1, q2 *= C->r2) {
            C->r1k[k] = q1;
            C->r2k[k] = q2;
        }
    }
    {
        const double rate = C->lam + ((z < 1.0) ? C->wd : 0.0);
        C->u_span = (rate > 0.0) ? SPAN_TURNS * TWO_PI / rate : INFINITY;
    }
    C->Dr = (1.0 - C->lam) * (1.0 + C->lam);
    C->Di = 2.0 * z * C->lam;
    C->D2 = C->Dr * C->Dr + C->Di * C->Di;
    C->inv_wd = (z < 1.0) ? 1.0 / C->wd : 0.0;
    C->inv_D2 = 1.0 / C->D2;
    C->uniform = C->D2 < D_MIN * D_MIN; /* then zeta < D_MIN / 2 < 1 */
    C->wd_lam = C->wd - C->lam;
    {
        const double pr = -z, pi = C->wd, p2r = pr * pr - pi * pi, p2i = 2.0 * pr * pi;
        C->p3r = p2r * pr - p2i * pi;
        C->p3i = p2r * pi + p2i * pr;
        C->p4r = p2r * p2r - p2i * p2i;
        C->p4i = 2.0 * p2r * p2i;
        C->w_abs = sqrt(z * z + C->wd_lam * C->wd_lam);
    }
    C->phasor = z < 1.0 && !C->uniform && C->w_abs < PHASOR_MAX;
    C->wmul = 0;
    for (int n = 1; n <= 4 && z < 1.0; n++)
        if (C->wd == n * C->lam) C->wmul = n;
    /* y'' = a cos theta - 2 zeta y' - y and its derivatives: y^(k+2) = a cos^(k) theta - 2 zeta y^(k+1) - y^(k) */
    double lk = 1.0;
    for (int k = 0; k < 8; k++, lk *= C->lam) C->lk[k] = lk;
    C->belt = 0;
    C->vb = 0.0;
    ctx_scale(C, e);
    C->on_switch = NULL;
    C->switch_ctx = NULL;
    C->events = 0;
    C->first_span = ENERGY_SPAN;
    C->poly = 0;
}

/* The excitation phase omega t + phase at the time t (a double-double): exact to rounding for any t
 * and phi (the product omega t and the sum carried as double-doubles). */
static inline dfo_dd theta_at(const ex_ctx *C, dfo_dd t) { return dfo_dd_theta(C->omega, C->ph, t); }

/* cos, sin of the excitation phase at t */
static inline void phase_at(const ex_ctx *C, dfo_dd t, double *c, double *s)
{
    const dfo_dd th = theta_at(C, t);
    dfo_sincos_dd(th.hi, th.lo, s, c);
}

/* The static force (over Ls) at rest at Xs at t: |P0| cos theta + F_ext - k X. */
static double static_force(const ex_ctx *C, dfo_dd t, double Xs)
{
    double c, sn;
    phase_at(C, t, &c, &sn);
    return C->fP * c + C->fF - C->k * Xs;
}

/* The polynomial inputs' force F_ext(t) - s mu_k N(t) over Ls at ta and its two derivatives (in t);
 * the normal force N(t) (physical) likewise. */
static void poly_force(const ex_ctx *C, dfo_dd ta, int s, double g[3], double n[3])
{
    const double q = (ta.hi - C->q_t0) + ta.lo, muk = C->M->mu_k;
    n[0] = C->qN[0] + q * (C->qN[1] + 0.5 * q * C->qN[2]);
    n[1] = C->qN[1] + q * C->qN[2];
    n[2] = C->qN[2];
    const double f0 = C->qF[0] + q * (C->qF[1] + 0.5 * q * C->qF[2]), f1 = C->qF[1] + q * C->qF[2];
    g[0] = (f0 - s * muk * n[0]) * C->iLs;
    g[1] = (f1 - s * muk * n[1]) * C->iLs;
    g[2] = (C->qF[2] - s * muk * n[2]) * C->iLs;
}

/* The polynomial particular solution of a slip phase from ta in direction s (polynomial inputs):
 * m x'' + c x' + k x = g0 + g1 q + g2 q^2 / 2 (q = t - ta) is solved by x = p0 + p1 q + p2 q^2 / 2 with
 * k p2 = g2, k p1 + c p2 = g1, k p0 + c p1 + m p2 = g0; in tau = w0 q: xc = p0, xp1 = p1 / w0, xp2 = p2 / w0^2.
 * The rest of the motion, y = x - x_p, solves the phase's equation y'' + 2 zeta y' + y = a cos(theta). */
static void poly_particular(const ex_ctx *C, ex_phase *P, dfo_dd ta, int s)
{
    double g[3], n[3];
    poly_force(C, ta, s, g, n);
    const double m = C->M->p.m, c = C->M->p.c, k = C->k, w0 = C->w0;
    const double p2 = g[2] / k, p1 = (g[1] - c * p2) / k, p0 = (g[0] - c * p1 - m * p2) / k;
    P->poly = 1;
    P->xc = p0;
    P->xp1 = p1 / w0;
    P->xp2 = p2 / (w0 * w0);
    P->n0 = n[0];
    P->n1 = n[1] / w0;
    P->n2 = n[2] / (w0 * w0);
}

/* X, V in the scaled units; ta the start time; cs: cos, sin of the excitation phase at ta when known
 * (carried over a reversal), else NULL: from the absolute time. */
static void phase_start(const ex_ctx *C, ex_phase *P, dfo_dd ta, double X, double V, int s, const double *cs)
{
    const double z = C->zeta, lam = C->lam, a = C->a;
    P->s = s;
    P->ta = ta.hi;
    P->poly = 0;
    P->xc = (C->Ls_.F_ext - s * C->Ls_.muk_N) / C->k;
    if (C->poly) poly_particular(C, P, ta, s);
    if (cs) {
        P->c0 = cs[0];
        P->s0 = cs[1];
    } else {
        phase_at(C, ta, &P->c0, &P->s0);
    }
    const double y0 = X - P->xc, v0 = V / C->w0 - (P->poly ? P->xp1 : 0.0); /* (the harmonic part's data) */
    if (C->uniform) {
        const double qr = 0.5 * a * P->s0 * C->inv_wd, qi = -0.5 * a * P->c0 * C->inv_wd;
        P->Qr = qr;
        P->Qi = qi;
        P->q1r = -z * qr - qi * C->wd;
        P->q1i = qr * C->wd - z * qi;
        P->q2r = -z * qr + qi * C->wd;
        P->q2i = -qr * C->wd - z * qi;
        P->Qabs = INFINITY;
        P->hy = y0;
        P->hv = v0;
    } else {
        P->Qr = a * (P->c0 * C->Dr + P->s0 * C->Di) * C->inv_D2;
        P->Qi = a * (P->s0 * C->Dr - P->c0 * C->Di) * C->inv_D2;
        P->q1r = P->q1i = P->q2r = P->q2i = 0.0;
        P->Qabs = sqrt(P->Qr * P->Qr + P->Qi * P->Qi);
        P->hy = y0 - P->Qr;        /* y_ss(0) = Re Q */
        P->hv = v0 + lam * P->Qi;  /* y_ss'(0) = Re(i lambda Q) */
    }
    const double hy = P->hy, hv = P->hv;
    P->gy = fabs(hy);
    P->gb = fabs(hv + z * hy);
    P->al = P->be = 0.0;
    if (z < 1.0) {
        const double b = (hv + z * hy) * C->inv_wd;
        P->fA = sqrt(hy * hy + b * b);
        P->fB = 0.0;
        P->Cr = hy;
        P->Ci = -b;
    } else if (z == 1.0) {
        P->fA = fabs(hy);
        P->fB = fabs(hv + hy);
    } else if (C->near_crit) { /* the modes' amplitudes grow like 1 / wh: bounded through gy, gb instead */
        P->fA = fabs(hy);
        P->fB = P->gb;
    } else {
        const double beta = (hv - C->r1 * hy) / (C->r2 - C->r1);
        P->al = hy - beta;
        P->be = beta;
        P->fA = fabs(hy - beta);
        P->fB = fabs(beta);
    }
}

/* On a belt: the phase's y' made the velocity relative to the belt (phase_start's data are of the motion
 * itself: its harmonic part does not depend on the belt). */
static inline void belt_shift(const ex_ctx *C, ex_phase *P)
{
    P->xp1a = P->xp1;
    P->vbu = C->vbs / C->w0;
    P->xp1 = P->xp1a - P->vbu;
}

static inline void phase_init(const ex_ctx *C, ex_phase *P, double ta, double X, double V, int s)
{
    phase_start(C, P, dfo_dd_of(ta, 0.0), X, V, s, NULL);
}

/* phi1(x + i y) = (e^z - 1) / z without cancellation (x <= 0). */
static void phi1(double x, double y, double *re, double *im)
{
    if (fabs(x) + fabs(y) < 1e-5) { /* 1 + z/2 + z^2/6 (+ z^3/24 < 1e-16) */
        *re = 1.0 + 0.5 * x + (x * x - y * y) / 6.0;
        *im = 0.5 * y + x * y / 3.0;
        return;
    }
    const double sh = dfo_sin(0.5 * y);
    const double er = dfo_expm1(x) * dfo_cos(y) - 2.0 * sh * sh, ei = dfo_exp(x) * dfo_sin(y);
    const double d = x * x + y * y;
    *re = (er * x + ei * y) / d;
    *im = (ei * x - er * y) / d;
}

/* sin and cos of |x| <= SMALL_ANGLE by their Taylor polynomials (the remainders x^11 / 11! and
 * x^12 / 12! are below 2^-60 |x| and 2^-70 there). */
static void small_sincos(double x, double *s, double *c)
{
    const double z = x * x;
    *s = x + x * z * (-1.0 / 6.0 + z * (1.0 / 120.0 + z * (-1.0 / 5040.0 + z * (1.0 / 362880.0))));
    *c = 1.0 + z * (-0.5 + z * (1.0 / 24.0 + z * (-1.0 / 720.0 + z * (1.0 / 40320.0 + z * (-1.0 / 3628800.0)))));
}

/* y, y' and the higher derivatives from the equation of motion, each directly (no chain). */
static inline void derivatives(const ex_ctx *C, double y, double y1, double cth, double sth, ex_val *v)
{
    const double(*k)[4] = C->yk;
    v->y = y;
    v->y1 = y1;
    v->y2 = C->a * cth - 2.0 * C->zeta * y1 - y;
    v->y3 = (k[3][0] * y + k[3][1] * y1) + (k[3][2] * cth + k[3][3] * sth);
    v->y4 = (k[4][0] * y + k[4][1] * y1) + (k[4][2] * cth + k[4][3] * sth);
    v->y5 = (k[5][0] * y + k[5][1] * y1) + (k[5][2] * cth + k[5][3] * sth);
    v->y6 = (k[6][0] * y + k[6][1] * y1) + (k[6][2] * cth + k[6][3] * sth);
}

/* Over-damped away from critical: y and its derivatives from the two modes and the forced part
 * (F = Re, Fi = Im of Q e^{i lambda tau}), each term to its own rounding. The equation of motion's
 * recurrence would lose (2 zeta)^k to cancellation: with zeta = 1000 its y''' ... y^(6) are rounding
 * noise, and a slow creep towards equilibrium would look like a stop. */
static inline void derivatives_modal(const ex_ctx *C, const ex_phase *P, double Fr, double Fi, double e1, double e2,
                                     ex_val *v)
{
    const double *l = C->lk, *q1 = C->r1k, *q2 = C->r2k;
    const double A = P->al * e1, B = P->be * e2;
    v->y = Fr + (A + B);
    v->y1 = -l[1] * Fi + (q1[1] * A + q2[1] * B);
    v->y2 = -l[2] * Fr + (q1[2] * A + q2[2] * B);
    v->y3 = l[3] * Fi + (q1[3] * A + q2[3] * B);
    v->y4 = l[4] * Fr + (q1[4] * A + q2[4] * B);
    v->y5 = -l[5] * Fi + (q1[5] * A + q2[5] * B);
    v->y6 = -l[6] * Fr + (q1[6] * A + q2[6] * B);
    v->Fr = v->Fi = v->Gr = v->Gi = 0.0; /* (the phasor bound is under-damped only) */
}

/* Polynomial inputs: the particular solution's part added to the harmonic motion's y, y', y'' at u
 * (its third and higher derivatives are 0), the harmonic part kept in hy, hy1. */
static inline void poly_add(const ex_phase *P, double u, ex_val *v)
{
    v->hy = v->y;
    v->hy1 = v->y1;
    v->y += u * (P->xp1 + 0.5 * u * P->xp2);
    v->y1 += P->xp1 + u * P->xp2;
    v->y2 += P->xp2;
}

static void eval(const ex_ctx *C, const ex_phase *P, double u, ex_val *v)
{
    const double z = C->zeta, lam = C->lam;
    double cl, sl;
    dfo_sincos(lam * u, &sl, &cl);
    const double cth = P->c0 * cl - P->s0 * sl, sth = P->s0 * cl + P->c0 * sl;
    if (C->modal) {
        const double e1 = dfo_exp(C->r1 * u), e2 = dfo_exp(C->r2 * u);
        derivatives_modal(C, P, P->Qr * cl - P->Qi * sl, P->Qr * sl + P->Qi * cl, e1, e2, v);
        v->u = u;
        v->cth = cth;
        v->sth = sth;
        v->e1 = e1;
        v->e2 = e2;
        if (P->poly) poly_add(P, u, v);
        return;
    }
    double E, F;
    if (z < 1.0) {
        const double e = (z > 0.0) ? dfo_exp(-z * u) : 1.0;
        const double wu = C->wd * u;
        double cw = cl, sw = sl;
        if (C->wmul == 0) {
            const double dl = C->wd_lam * u; /* wd tau = lambda tau + dl */
            if (fabs(dl) <= SMALL_ANGLE && !C->near_crit) { /* (near critical wd tau << lambda tau would cancel) */
                double sd, cd;
                small_sincos(dl, &sd, &cd);
                cw = cl * cd - sl * sd;
                sw = sl * cd + cl * sd;
            } else {
                dfo_sincos(wu, &sw, &cw);
            }
        } else if (C->wmul > 1) { /* the angle's multiple: (cl + i sl)^wmul */
            if (C->wmul == 3) {
                const double c2 = (cl - sl) * (cl + sl), s2 = 2.0 * sl * cl;
                cw = c2 * cl - s2 * sl;
                sw = s2 * cl + c2 * sl;
            } else {
                cw = (cl - sl) * (cl + sl);
                sw = 2.0 * sl * cl;
                if (C->wmul == 4) {
                    const double c2 = cw;
                    cw = (c2 - sw) * (c2 + sw);
                    sw = 2.0 * sw * c2;
                }
            }
        }
        E = e * cw;
        F = e * sw * C->inv_wd;
        if (C->phasor) {
            v->Fr = P->Qr * cl - P->Qi * sl;
            v->Fi = P->Qr * sl + P->Qi * cl;
            v->Gr = e * (P->Cr * cw - P->Ci * sw);
            v->Gi = e * (P->Cr * sw + P->Ci * cw);
        }
        v->e1 = e;
        v->e2 = 0.0;
    } else if (z == 1.0) {
        const double e = dfo_exp(-u);
        E = e;
        F = u * e;
        v->e1 = e;
        v->e2 = 0.0;
    } else {
        const double e1 = dfo_exp(C->r1 * u), e2 = dfo_exp(C->r2 * u);
        E = 0.5 * (e1 + e2);
        F = -e1 * dfo_expm1(-2.0 * C->wh * u) / (2.0 * C->wh);
        v->e1 = e1;
        v->e2 = e2;
    }
    double y = P->hy * E + (P->hv + z * P->hy) * F;
    double y1 = P->hv * E - (P->hy + z * P->hv) * F;
    if (!C->uniform) {
        y += P->Qr * cl - P->Qi * sl;
        y1 -= lam * (P->Qr * sl + P->Qi * cl);
    } else {
        double p1r, p1i, p2r, p2i;
        phi1(-z * u, (C->wd - lam) * u, &p1r, &p1i);
        phi1(-z * u, -(C->wd + lam) * u, &p2r, &p2i);
        const double eur = cl * u, eui = sl * u;
        /* Re[q eu (P1 - P2)] */
        const double dr = p1r - p2r, di = p1i - p2i;
        const double qdr = P->Qr * dr - P->Qi * di, qdi = P->Qr * di + P->Qi * dr;
        y += eur * qdr - eui * qdi;
        /* Re[eu (q p1 P1 - q p2 P2)] */
        const double wr = (P->q1r * p1r - P->q1i * p1i) - (P->q2r * p2r - P->q2i * p2i);
        const double wi = (P->q1r * p1i + P->q1i * p1r) - (P->q2r * p2i + P->q2i * p2r);
        y1 += eur * wr - eui * wi;
    }
    v->u = u;
    v->cth = cth;
    v->sth = sth;
    derivatives(C, y, y1, cth, sth, v);
    if (P->poly) poly_add(P, u, v);
}

/* What the bounds of the derivatives at v need, computed once per step: the decomposition's
 * (forced amplitude plus the free part's envelope, valid for every later u), R = |(y, y')| for the
 * energy bound, the phasor bound's magnitudes and its drift rate. */
typedef struct {
    double d3, d4, d5, d7; /* decomposition (INFINITY in the uniform form) */
    double R0;             /* sqrt(y^2 + y'^2) at v */
    double h3, h4, drift;  /* phasor: |(i lambda)^k F + p^k G| (+ rounding), |G| |p - i lambda| (INFINITY: none) */
} ex_bnd;

/* An upper bound of |x + i y| within 8 % without a square root: max + (sqrt 2 - 1) min. */
static double cabs_bound(double x, double y)
{
    const double ax = fabs(x), ay = fabs(y);
    return (ax > ay) ? ax + 0.41421357 * ay : ay + 0.41421357 * ax;
}

static void bounds_base(const ex_ctx *C, const ex_phase *P, const ex_val *v, ex_bnd *b)
{
    const double z = C->zeta;
    double f3, f4, f5, f7;
    if (z < 1.0) {
        f3 = f4 = f5 = f7 = P->fA * v->e1; /* |p| = 1 */
        if (C->near_crit) {
            /* |C| grows like 1 / wd; also y_h^(k) = e^{-zeta u} (hy cos phi + (b'/wd) sin phi), phi = k arg p +
             * wd u, with |sin phi| <= wd u + k atan(wd / zeta): |y_h^(k)| <= e^{-zeta u} (|hy| + |b'| (u + k / zeta)),
             * falling in u for k >= 1 (so it holds for every later u) */
            const double g = P->gy, gb = P->gb, u = v->u, iz = 1.0 / z, e = v->e1;
            f3 = fmin(f3, e * (g + gb * (u + 3.0 * iz)));
            f4 = fmin(f4, e * (g + gb * (u + 4.0 * iz)));
            f5 = fmin(f5, e * (g + gb * (u + 5.0 * iz)));
            f7 = fmin(f7, e * (g + gb * (u + 7.0 * iz)));
        }
    } else if (C->near_crit && z > 1.0) {
        /* y_h = hy E + b' F, E = (e^{r1 u} + e^{r2 u}) / 2, F = (e^{r1 u} - e^{r2 u}) / (r1 - r2): |E^(k)| <= q^k e^{r1 u}
         * and (mean value) |F^(k)| <= (k q^(k-1) + u q^k) e^{r1 u}, q = |r2|, falling in u for k >= q / |r1| (< 3 here) */
        const double q = -C->r2, e = v->e1, g = P->gy, gb = P->gb, u = v->u, q2 = q * q, q3 = q2 * q;
        f3 = e * (g * q3 + gb * q2 * (3.0 + u * q));
        f4 = e * (g * q3 * q + gb * q3 * (4.0 + u * q));
        f5 = e * (g * q3 * q2 + gb * q3 * q * (5.0 + u * q));
        f7 = e * (g * q3 * q3 * q + gb * q3 * q3 * (7.0 + u * q));
    } else if (z == 1.0) {
        f3 = v->e1 * (P->fA + P->fB * (v->u + 3.0));
        f4 = v->e1 * (P->fA + P->fB * (v->u + 4.0));
        f5 = v->e1 * (P->fA + P->fB * (v->u + 5.0));
        f7 = v->e1 * (P->fA + P->fB * (v->u + 7.0));
    } else {
        const double r1 = -C->r1, r2 = -C->r2, a1 = P->fA * r1 * r1 * r1 * v->e1, a2 = P->fB * r2 * r2 * r2 * v->e2;
        f3 = a1 + a2;
        f4 = a1 * r1 + a2 * r2;
        f5 = a1 * r1 * r1 + a2 * r2 * r2;
        f7 = a1 * (r1 * r1) * (r1 * r1) + a2 * (r2 * r2) * (r2 * r2);
    }
    b->d3 = P->Qabs * C->lk[3] + f3;
    b->d4 = P->Qabs * C->lk[4] + f4;
    b->d5 = P->Qabs * C->lk[5] + f5;
    b->d7 = P->Qabs * C->lk[7] + f7;
    if (P->poly) /* the energy bound is of the harmonic part */
        b->R0 = sqrt(v->hy * v->hy + v->hy1 * v->hy1);
    else
        b->R0 = sqrt(v->y * v->y + v->y1 * v->y1);
    b->h3 = b->h4 = b->drift = INFINITY;
    if (C->phasor) {
        /* y^(k)(u + s) = Re[((i lambda)^k F + p^k G e^{(p - i lambda) s}) e^{i lambda s}] with |p| = 1 and
         * |e^{w s} - 1| <= |w| s (Re w <= 0): |y^(k)| <= |(i lambda)^k F + p^k G| + |G| |p - i lambda| s */
        const double l3 = C->lk[3], l4 = C->lk[4], g = P->fA * v->e1, round = 1e-12 * (P->Qabs * l4 + g);
        const double t3r = l3 * v->Fi + C->p3r * v->Gr - C->p3i * v->Gi;
        const double t3i = -l3 * v->Fr + C->p3r * v->Gi + C->p3i * v->Gr;
        const double t4r = l4 * v->Fr + C->p4r * v->Gr - C->p4i * v->Gi;
        const double t4i = l4 * v->Fi + C->p4r * v->Gi + C->p4i * v->Gr;
        b->h3 = cabs_bound(t3r, t3i) + round;
        b->h4 = cabs_bound(t4r, t4i) + round;
        b->drift = g * C->w_abs;
    }
}

/* Bounds of |y'''|, |y''''|, |y^(5)| on [u, u + span]; *limited when they hold only there (the
 * energy or the phasor bound), not for every later u (the decomposition's, which only decay).
 * *B7 bounds |y^(7)|, on [u, u + span] only when *limited7. */
static void bounds(const ex_ctx *C, const ex_bnd *b, double span, double *B3, double *B4, double *B5, double *B7,
                   int *limited, int *limited7)
{
    /* energy: d/dtau (y^2 + y'^2)/2 = y' (a cos - 2 zeta y') <= a |y'|, so R grows at most by a */
    const double R = b->R0 + C->a * span;
    const double e3 = C->ea[3] + C->eb[3] * R, e4 = C->ea[4] + C->eb[4] * R, e5 = C->ea[5] + C->eb[5] * R;
    const double e7 = C->ea[7] + C->eb[7] * R;
    double b3 = (e3 < b->d3 ? e3 : b->d3), b4 = (e4 < b->d4 ? e4 : b->d4);
    *limited = (e3 < b->d3 || e4 < b->d4 || e5 < b->d5);
    if (C->phasor) {
        const double h3 = b->h3 + b->drift * span, h4 = b->h4 + b->drift * span;
        if (h3 < b3) { b3 = h3; *limited = 1; }
        if (h4 < b4) { b4 = h4; *limited = 1; }
    }
    *limited7 = e7 < b->d7;
    *B3 = BOUND_SAFETY * b3;
    *B4 = BOUND_SAFETY * b4;
    *B5 = BOUND_SAFETY * (e5 < b->d5 ? e5 : b->d5);
    *B7 = BOUND_SAFETY * (e7 < b->d7 ? e7 : b->d7);
}

/* Largest d with g0 + g1 d - B d^2 / 2 >= 0 (g0 > 0). */
static double safe_step(double g0, double g1, double B)
{
    if (!(B > 0.0)) return (g1 >= 0.0) ? INFINITY : g0 / -g1;
    const double r = sqrt(g1 * g1 + 2.0 * B * g0);
    return (g1 >= 0.0) ? (g1 + r) / B : 2.0 * g0 / (r - g1);
}

/* From rest: largest d with g1 d + g2 d^2 / 2 - B d^3 / 6 >= 0 (g1 >= 0). */
static double start_step(double g1, double g2, double B)
{
    if (!(B > 0.0)) return (g2 >= 0.0) ? INFINITY : (g1 > 0.0 ? 2.0 * g1 / -g2 : 0.0);
    const double A = B * (1.0 / 6.0), b = 0.5 * g2, r = sqrt(b * b + 4.0 * A * g1);
    return (b >= 0.0) ? (b + r) / (2.0 * A) : 2.0 * g1 / (r - b);
}

static double tol_of(const ex_ctx *C, const ex_phase *P, const ex_val *v)
{
    if (C->modal) {
        /* each term of y' to its rounding; the position's rounding (of the phase's data) moves y' by |r1|
         * times it only: a creep towards equilibrium is followed until it is within a few ulps of it */
        const double pos = C->a + fabs(P->xc) + fabs(v->y) + P->Qabs +
                           (P->poly ? fabs(v->hy) + fabs(P->xp1) + fabs(P->xp2) * (1.0 + v->u) : 0.0);
        return -C->r1 * (4.0 * DBL_EPSILON) * pos +
               ROUND * (fabs(v->y1) + C->lam * P->Qabs + fabs(P->al * C->r1) * v->e1 + fabs(P->be * C->r2) * v->e2);
    }
    const double forced = C->uniform ? 0.0 : P->Qabs * (1.0 + C->lam);
    double free = P->fA * v->e1;
    if (C->near_crit) { /* without the 1 / wd, 1 / wh of the modes' amplitudes */
        const double g = v->e1 * (P->gy + fabs(P->hv) + P->gb * (v->u + 1.0));
        if (C->zeta >= 1.0 || g < free) free = g;
    }
    if (P->poly) /* the polynomial part's terms */
        return ROUND * (C->a + fabs(P->xc) + fabs(v->y) + fabs(v->y1) + forced + free + fabs(v->hy) + fabs(v->hy1) +
                        fabs(P->xp1) + fabs(P->xp2) * (1.0 + v->u));
    return ROUND * (C->a + fabs(P->xc) + fabs(v->y) + fabs(v->y1) + forced + free);
}

enum { SEARCH_NONE = 0, SEARCH_STOP = 1, SEARCH_NULL = 2, SEARCH_FAIL = -1 };

/* The state at tau = 0 from the phase's data (no transcendental function). */
static void eval0(const ex_ctx *C, const ex_phase *P, double y0, double v0, ex_val *v)
{
    if (C->modal) {
        derivatives_modal(C, P, P->Qr, P->Qi, 1.0, 1.0, v);
        v->y = y0;
        v->y1 = v0;
        v->u = 0.0;
        v->cth = P->c0;
        v->sth = P->s0;
        v->e1 = v->e2 = 1.0;
        return;
    }
    v->u = 0.0;
    v->Fr = P->Qr;
    v->Fi = P->Qi;
    v->Gr = P->Cr;
    v->Gi = P->Ci;
    v->cth = P->c0;
    v->sth = P->s0;
    derivatives(C, y0, v0, P->c0, P->s0, v);
    v->e1 = v->e2 = 1.0;
}

/* A certified step from v: s y' > 0 on [u, u + d] (started: the quadratic bound with B3; from rest:
 * the cubic one with B4, a share of it), with the bounds B4, B5 that hold up to u + *span. The energy
 * bound holds over a span only; when the step reaches it, the span is widened once to that step (the
 * best span S is the fixed point of S = step(bound(S)), which lies between the two). */
static double certified_step(const ex_ctx *C, const ex_phase *P, const ex_val *v, int started, double g0, double g1,
                             double g2, double S, double *B4, double *B5, double *span, double *B7, double *span7)
{
    double d = 0.0;
    ex_bnd base;
    bounds_base(C, P, v, &base);
    for (int k = 0; k < 2; k++) {
        double b3, b4, b5, b7;
        int lim, lim7;
        bounds(C, &base, S, &b3, &b4, &b5, &b7, &lim, &lim7);
        const double dk = started ? safe_step(g0, g1, b3) : START_FRACTION * start_step(g1 > 0.0 ? g1 : 0.0, g2, b4);
        const double dc = (lim && dk > S) ? S : dk;
        if (k > 0 && !(dc > d)) break;
        d = dc;
        *B4 = b4;
        *B5 = b5;
        *span = lim ? S : INFINITY;
        *B7 = b7;
        *span7 = lim7 ? S : INFINITY;
        if (!lim || !(dk > S)) break; /* not limited by the span */
        S = dk;
    }
    return d;
}

/* A stop at u + d from the Taylor model at v (degree 6 in y), without evaluating there (its
 * remainder is below rounding). */
static void taylor_stop(const ex_ctx *C, const ex_val *v, double d, ex_val *out)
{
    const double ld = C->lam * d; /* the excitation phase moves by lambda d */
    double sd, cd;
    if (fabs(ld) <= SMALL_ANGLE) small_sincos(ld, &sd, &cd); else dfo_sincos(ld, &sd, &cd);
    out->cth = v->cth * cd - v->sth * sd;
    out->sth = v->sth * cd + v->cth * sd;
    const double k3 = 1.0 / 6.0, k4 = 1.0 / 24.0, k5 = 1.0 / 120.0, k6 = 1.0 / 720.0;
    out->u = v->u + d;
    out->y = v->y + d * (v->y1 + d * (0.5 * v->y2 + d * (k3 * v->y3 + d * (k4 * v->y4 + d * (k5 * v->y5 +
                                                                                             d * k6 * v->y6)))));
    out->y1 = 0.0;
    out->y2 = v->y2 + d * (v->y3 + d * (0.5 * v->y4 + d * (k3 * v->y5 + d * k4 * v->y6)));
    out->y3 = v->y3 + d * (v->y4 + d * (0.5 * v->y5 + d * k3 * v->y6));
    out->y4 = v->y4 + d * (v->y5 + 0.5 * d * v->y6);
    out->y5 = v->y5 + d * v->y6;
    out->y6 = v->y6;
    out->e1 = v->e1;
    out->e2 = v->e2;
}

/* A first guess at the zero of s y' next to v (s y'' < 0 there): the series reversion of the cubic
 * Taylor model, t - p2 t^2 + (2 p2^2 - p3) t^3 with t = -g / g', p2 = g'' / (2 g'), p3 = g''' / (6 g'). */
static double root_guess(const ex_val *v, int s)
{
    const double r = 1.0 / (s * v->y2), t = -s * v->y1 * r;
    const double p2 = 0.5 * s * v->y3 * r, p3 = (1.0 / 6.0) * s * v->y4 * r;
    return t * (1.0 + t * (-p2 + t * (2.0 * p2 * p2 - p3)));
}

/* The zero of s y' next to v on its quintic Taylor model: Newton's method from d, at most `steps`
 * steps, until the model's value after the step, (model'' / 2) step^2 by Newton's quadratic
 * convergence, is within tol / 16 (tol = 0: all the steps). 0 when the slope does not fall there (not
 * a simple downward zero) or, with tol > 0, the steps do not settle. */
static double near_root(const ex_val *v, int s, double d, double tol, int steps)
{
    const double g0 = s * v->y1, g1 = s * v->y2, g2 = 0.5 * s * v->y3, g3 = (1.0 / 6.0) * s * v->y4;
    const double g4 = (1.0 / 24.0) * s * v->y5, g5 = (1.0 / 120.0) * s * v->y6;
    const double h2 = 2.0 * g2, h3 = 3.0 * g3, h4 = 4.0 * g4, h5 = 5.0 * g5;
    const double k3 = 6.0 * g3, k4 = 12.0 * g4, k5 = 20.0 * g5;
    for (int i = 0; i < steps; i++) {
        const double c = g0 + d * (g1 + d * (g2 + d * (g3 + d * (g4 + d * g5))));
        const double cd = g1 + d * (h2 + d * (h3 + d * (h4 + d * h5)));
        const double cdd = h2 + d * (k3 + d * (k4 + d * k5));
        if (!(cd < 0.0)) return 0.0;
        const double e = c / cd;
        d -= e;
        if (fabs(cdd) * e * e <= 0.125 * tol) return d;
    }
    return (tol > 0.0) ? 0.0 : d;
}

/* The first zero of g = s y' in the bracket [lo, hi] (g(lo) >= 0 certified, g(hi) < 0 evaluated in
 * *vhi): Newton's method on the quintic Taylor model kept inside the bracket, bisection otherwise,
 * until |g| <= tol or the model's root is within rounding (B7 bounds |y^(7)| up to u_lim). */
static void polish(const ex_ctx *C, const ex_phase *P, double lo, const ex_val *vhi, double B7, double u_lim,
                   ex_val *out)
{
    const int s = P->s;
    double hi = vhi->u;
    ex_val v = *vhi;
    for (int it = 0; it < MAX_POLISH; it++) {
        const double g = s * v.y1, g1 = s * v.y2, tol = tol_of(C, P, &v);
        if (fabs(g) <= tol) break;
        if (g > 0.0) lo = v.u; else hi = v.u;
        double un = 0.5 * (lo + hi);
        if (g1 < 0.0) {
            double dn = near_root(&v, s, root_guess(&v, s), tol, 4);
            const double dn3 = dn * dn * dn;
            if (dn != 0.0 && v.u + dn > lo && v.u + dn < hi && v.u + fabs(dn) <= u_lim && B7 * dn3 * dn3 <= 360.0 * tol) {
                taylor_stop(C, &v, dn, out);
                return;
            }
            if (dn == 0.0) dn = -g / g1;
            un = v.u + dn;
        } else if (g1 != 0.0) {
            un = v.u - g / g1;
        }
        if (!(un > lo && un < hi)) un = 0.5 * (lo + hi);
        if (un == lo || un == hi) break;
        eval(C, P, un, &v);
    }
    *out = v;
}

/* The first stop of the phase in (0, u_max]: SEARCH_STOP with the state there in *out, SEARCH_NONE
 * (then *out is the state at u_max), SEARCH_NULL (a slide from rest that never leaves the rounding
 * band: the block stays at rest at *out), SEARCH_FAIL (no progress). y0, v0: the data at tau = 0. */
static int find_stop(ex_ctx *C, const ex_phase *P, double y0, double v0, double u_max, ex_val *out)
{
    const int s = P->s;
    ex_val v;
    if (P->poly) { /* the harmonic part's data to eval0, then the polynomial part's (v0 exact: at rest, 0) */
        eval0(C, P, y0, v0 - P->xp1, &v);
        poly_add(P, 0.0, &v);
        v.y1 = v0;
    } else {
        eval0(C, P, y0, v0, &v);
    }
    int started = s * v.y1 > tol_of(C, P, &v), tries = 0;
    ex_val v_band = v; /* last point of a slide from rest still inside the rounding band */
    double S0 = C->first_span; /* the span the bounds are first tried over: a little more than the last step */
    int first = 1;
    const double u_ulp = 4.0 * DBL_EPSILON * fabs(P->ta) * C->w0; /* rounding of the start time, in tau */
    for (long it = 0; it < MAX_SEARCH; it++) {
        const double g0 = s * v.y1, g1 = s * v.y2, g2 = s * v.y3, tol = tol_of(C, P, &v);
        const double u = v.u;
        if (!started) {
            if (g0 > tol) {
                started = 1;
            } else if (g0 < -(tol + fabs(g1) * u_ulp) || ++tries > MAX_START) {
                *out = v_band;
                return SEARCH_NULL;
            } else {
                v_band = v;
            }
        }
        if (started && g0 <= tol) {
            *out = v;
            return SEARCH_STOP;
        }
        double B4 = INFINITY, B5 = INFINITY, span = INFINITY, B7 = INFINITY, span7 = INFINITY, d;
        if (!started) {
            /* from rest the slide needs s y'' >= 0 (a negative value within rounding counts as 0; the
             * rounding includes that of the event's time, which moves y'' by y''' times it) */
            if (g1 < -(tol + fabs(g2) * u_ulp)) {
                *out = v_band;
                return SEARCH_NULL;
            }
            d = certified_step(C, P, &v, 0, g0, g1, g2, S0, &B4, &B5, &span, &B7, &span7);
            if (!(d > 0.0) && s * v.y4 > 0.0 && B5 > 0.0) { /* y'' = y''' = 0: the quartic lower bound */
                d = START_FRACTION * 4.0 * s * v.y4 / B5;
                if (d > span) d = span;
            }
            if (!(d > 0.0)) {
                *out = v_band;
                return SEARCH_NULL;
            }
        } else {
            d = certified_step(C, P, &v, 1, g0, g1, g2, S0, &B4, &B5, &span, &B7, &span7);
            if (g1 < 0.0) {
                /* the quadratic Taylor model: its first root, or its minimum when it has none */
                const double disc = g1 * g1 - 2.0 * g2 * g0;
                double dt = -1.0;
                int touch = 0;
                if (disc >= 0.0) {
                    double dq = 2.0 * g0 / (sqrt(disc) - g1);
                    /* one Newton step on the cubic model (g''' = s y'''') */
                    const double g3 = s * v.y4;
                    const double c3 = g0 + dq * (g1 + dq * (0.5 * g2 + dq * g3 * (1.0 / 6.0)));
                    const double c3d = g1 + dq * (g2 + 0.5 * dq * g3);
                    if (c3d < 0.0 && fabs(c3 / c3d) < 0.5 * dq) dq -= c3 / c3d;
                    if (dq < TAYLOR_REACH * d) { /* close: the model holds there */
                        /* on to the quintic model's root (its error is what the guess misses by) */
                        const double d5 = near_root(&v, s, dq, 0.0, QUINTIC_STEPS);
                        dt = (d5 > 0.0 && fabs(d5 - dq) < 0.5 * dq) ? d5 : dq;
                    }
                } else if (g2 > 0.0 && g0 - g1 * g1 / (2.0 * g2) <= tol) {
                    const double dm = -g1 / g2;  /* a tangential touch within rounding */
                    if (dm < 4.0 * d) { dt = dm; touch = 1; }
                }
                if (dt > 0.0 && u + dt <= u_max) {
                    /* the quintic model's remainder below rounding: its root is the stop */
                    const double dt3 = dt * dt * dt;
                    if (!touch && dt <= span7 && B7 * dt3 * dt3 <= 360.0 * tol) {
                        const double dr = near_root(&v, s, dt, tol, 4), dr3 = dr * dr * dr;
                        if (dr > 0.0 && dr <= span7 && u + dr <= u_max && B7 * dr3 * dr3 <= 360.0 * tol) {
                            taylor_stop(C, &v, dr, out);
                            return SEARCH_STOP;
                        }
                    }
                    ex_val w;
                    eval(C, P, u + dt, &w);
                    const double gw = s * w.y1, tw = tol_of(C, P, &w);
                    if (fabs(gw) <= tw) { *out = w; return SEARCH_STOP; }
                    /* close to a simple zero: finish on the quintic model at w (either side of it), whose
                     * remainder B7 dw^6 / 720 is below rounding */
                    const double dw = (s * w.y2 < 0.0) ? near_root(&w, s, root_guess(&w, s), tw, 4) : 0.0;
                    const double dw3 = dw * dw * dw;
                    if (dw != 0.0 && w.u + dw > u && w.u + dw <= u_max && u + span7 >= w.u + fabs(dw) &&
                        B7 * dw3 * dw3 <= 360.0 * tw) {
                        taylor_stop(C, &w, dw, out);
                        return SEARCH_STOP;
                    }
                    if (gw < 0.0) {
                        polish(C, P, u + (d < dt ? d : dt), &w, B7, u + span7, out);
                        return SEARCH_STOP;
                    }
                    if (s * w.y2 < 0.0 && dt >= d) { v = w; continue; } /* still falling: go on from there */
                }
            }
        }
        if (u + d >= u_max) {
            eval(C, P, u_max, out);
            /* the bound proves s y' > 0 up to u_max; at u_max it may sit on 0 by rounding */
            return SEARCH_NONE;
        }
        if (!(d > 0.0) || !(u + d > u)) return SEARCH_FAIL;
        S0 = (d * SPAN_GROWTH > ENERGY_SPAN) ? d * SPAN_GROWTH : ENERGY_SPAN;
        if (first) C->first_span = S0; /* the next phase's first step is likely alike */
        first = 0;
        eval(C, P, u + d, &v);
        if (!isfinite(v.y) || !isfinite(v.y1)) return SEARCH_FAIL;
    }
    return SEARCH_FAIL;
}

/* ---- observables (exact_observe.h) ------------------------------------------------------------ */

/* x of a slip phase (physical) at time t from its start */
static double phase_x(const void *ctx, const void *phase, double t)
{
    const ex_ctx *C = (const ex_ctx *)ctx;
    const ex_phase *P = (const ex_phase *)phase;
    ex_val v;
    const double u = C->w0 * t;
    eval(C, P, u, &v);
    if (C->belt) return (P->xc + (v.hy + u * (P->xp1a + 0.5 * u * P->xp2))) * C->Ls; /* on a belt: x itself */
    return (P->xc + v.y) * C->Ls;
}

/* ---- the phases -------------------------------------------------------------------------------- */

/* The excitation phase at t reduced to psi in [0, 2 pi) (to a few ulps of 2 pi: the reduction is of
 * the double-double phase, so its error does not grow with t). */
static double turn_of(const ex_ctx *C, dfo_dd t)
{
    const dfo_dd th = theta_at(C, t);
    double rh, rl;
    const int q = dfo_rem_pio2(th.hi, th.lo, &rh, &rl);
    const double psi = q * DFO_PIO2_HI + (rh + (q * DFO_PIO2_LO + rl));
    return (psi < 0.0) ? psi + TWO_PI : psi;
}

/* Earliest phase >= psi (in [0, 2 pi)) with cos > lim, as an offset from psi; acos_lim = acos(lim)
 * for -1 <= lim < 1 (friction.c's rule, acos(-1) = pi included). */
static double until_above(double psi, double lim, double acos_lim)
{
    if (lim >= 1.0) return INFINITY;
    if (lim < -1.0) return 0.0;
    if (psi < acos_lim || psi > TWO_PI - acos_lim) return 0.0;
    return (DFO_TWOPI_HI - acos_lim - psi) + DFO_TWOPI_LO;
}

/* While stuck at Xs the static force is |P0| cos theta(t) + C0 (C0 = F_ext - k X, over Ls): the first
 * time >= ta at which its magnitude exceeds the breakaway limit, with the side in *dir (friction.h's
 * dfo_next_breakaway in closed form, on the phase reduced from the double-double time: its error
 * is a few ulps of 2 pi whatever t, so a run cut into other communication steps finds the same time
 * to rounding). {INFINITY, 0}: none. cs[0], cs[1]: cos and sin of the excitation phase there when it
 * is a crossing later than ta (cos theta = the limit: known without evaluating), else cs[0] = NaN. */
static dfo_dd next_breakaway(const ex_ctx *C, double Xs, dfo_dd ta, int *dir, double *cs)
{
    cs[0] = NAN;
    const double Fb = C->Ls_.Fb, C0 = C->fF - C->k * Xs, amp = C->fP, w = C->omega;
    if (w == 0.0 || amp == 0.0) { /* a constant force */
        const double F = static_force(C, ta, Xs);
        *dir = dfo_sign(F);
        if (fabs(F) > Fb) return ta;
        const dfo_dd never = {INFINITY, 0.0};
        return never;
    }
    const double lim_hi = (Fb - C0) / amp; /* F_static >  Fb  <=>  cos(theta)      > lim_hi */
    const double lim_lo = (Fb + C0) / amp; /* F_static < -Fb  <=>  cos(theta + pi) > lim_lo */
    const double acos_hi = (lim_hi >= -1.0 && lim_hi < 1.0) ? dfo_acos(lim_hi) : 0.0;
    const double acos_lo = (lim_lo >= -1.0 && lim_lo < 1.0) ? dfo_acos(lim_lo) : 0.0;
    const double psi = turn_of(C, ta);
    double psi2 = psi + DFO_PI;
    if (psi2 >= TWO_PI) psi2 -= TWO_PI;
    const double up = until_above(psi, lim_hi, acos_hi), down = until_above(psi2, lim_lo, acos_lo);
    *dir = (up <= down) ? 1 : -1;
    const double off = fmin(up, down);
    if (!isfinite(off)) {
        const dfo_dd never = {INFINITY, 0.0};
        return never;
    }
    if (off > 0.0) { /* cos theta rises through lim_hi (sin < 0), or cos(theta + pi) through lim_lo */
        const double l = (*dir > 0) ? lim_hi : lim_lo, sn = sqrt((1.0 - l) * (1.0 + l));
        cs[0] = (*dir > 0) ? l : -l;
        cs[1] = (*dir > 0) ? -sn : sn;
    }
    return dfo_dd_add_quot(ta, off, 0.0, w);
}

/* The next breakaway of the stick phase at Xs from ta (kept in *tb for the stick phase: valid while
 * tb->hi is not NaN). With skip, a breakaway at ta itself (a limit touched, not crossed: the slide
 * just tried did not start) is passed over: the search restarts a little later, further each time,
 * until it finds a later one. */
static dfo_dd breakaway(const ex_ctx *C, double Xs, dfo_dd ta, int skip, dfo_dd *tb, int *dir, double *cs)
{
    if (isnan(tb->hi) || (skip && !dfo_dd_lt(ta, *tb))) {
        dfo_dd b = next_breakaway(C, Xs, ta, dir, cs);
        if (skip) {
            double d = 4.0 * DBL_EPSILON * fmax(fabs(ta.hi), 1.0 / (C->w0 + fabs(C->omega)));
            for (int i = 0; i < 200 && !dfo_dd_lt(dfo_dd_add(ta, dfo_dd_of(d, 0.0)), b) && isfinite(b.hi); i++, d *= 2.0)
                b = next_breakaway(C, Xs, dfo_dd_add(ta, dfo_dd_of(d, 0.0)), dir, cs);
        }
        *tb = b;
    }
    if (!dfo_dd_lt(ta, *tb)) {
        cs[0] = NAN; /* at ta itself: the phase from the time */
        return ta;
    }
    return *tb;
}

/* ---- held inputs --------------------------------------------------------------------------------- */

/* The phases from s to t_target with the inputs held (the loop below the polynomial inputs' helpers). */
static dfo_status advance(ex_ctx *C, dfo_state *s, double t_target);

static inline void ctx_init(ex_ctx *C, const dfo_model *M, const dfo_inputs *in) { ctx_init_scaled(C, M, in, 0); }

/* The length scale's exponent for this call: of the largest length of the motion (|P0|, |F_ext|, the
 * breakaway limit over k; |X|; |V| / w0), from the exponents alone (no quotient can overflow),
 * bounded to +-SCALE_MAX. */
static int scale_exponent(const dfo_model *M, const dfo_inputs *u, const dfo_state *s)
{
    int e = INT_MIN;
    dfo_loads L;
    dfo_loads_init(&L, M, u);
    const int ek = dfo_ilogb(M->p.k);
    const double w0 = sqrt(M->p.k / M->p.m);
    const double forces[3] = {M->P_amp, L.F_ext, L.Fb};
    for (int i = 0; i < 3; i++)
        if (forces[i] != 0.0 && isfinite(forces[i])) {
            const int f = dfo_ilogb(forces[i]) - ek;
            if (f > e) e = f;
        }
    if (s->X != 0.0 && isfinite(s->X) && dfo_ilogb(s->X) > e) e = dfo_ilogb(s->X);
    if (s->V != 0.0 && isfinite(s->V) && w0 > 0.0 && isfinite(w0)) {
        const int f = dfo_ilogb(s->V) - dfo_ilogb(w0);
        if (f > e) e = f;
    }
    if (e == INT_MIN) return 0;
    return (e > SCALE_MAX) ? SCALE_MAX : (e < -SCALE_MAX) ? -SCALE_MAX : e;
}

/* 1 (with hA = 0) when the scaled phase cannot hold the call's lengths: the motion leaves the double range. */
static int out_of_range(const ex_ctx *C, dfo_state *s)
{
    const double big = fmax(fmax(C->a, fabs(C->fF / C->k)), fmax(C->Ls_.Fb / C->k, fabs(s->X * C->iLs)));
    if (!(big <= SCALED_MAX) || !(fabs(s->V * C->iLs) / C->w0 <= SCALED_MAX)) {
        s->hA = 0.0;
        return 1;
    }
    return 0;
}

/* The end of a call: A and F at s->t from the loads L there (over Ls) and the static force S (over Ls). */
static dfo_status end_state(const ex_ctx *C, dfo_state *s, const dfo_loads *L, double S)
{
    const dfo_params *p = &C->M->p;
    const double Vs = s->V * C->iLs;
    if (s->mode == 0) {
        s->V = 0.0;
        s->A = 0.0;
        s->F = dfo_stick_force(L, S) * C->Ls;
    } else {
        const double F = -s->mode * L->muk_N;
        s->F = F * C->Ls;
        s->A = ((S - p->c * Vs + F) / p->m) * C->Ls;
    }
    if (!(fabs(s->X) <= DBL_MAX && fabs(s->V) <= DBL_MAX && fabs(s->A) <= DBL_MAX)) return DFO_ERR_NONFINITE;
    return DFO_OK;
}

dfo_status dfo_exact_spring_advance(const dfo_model *M, const dfo_inputs *u, dfo_state *s, double t_target,
                                    dfo_switch_fn on_switch, void *switch_ctx)
{
    ex_ctx C;
    ctx_init_scaled(&C, M, u, scale_exponent(M, u, s));
    C.on_switch = on_switch;
    C.switch_ctx = switch_ctx;
    if (out_of_range(&C, s)) return DFO_ERR_NONFINITE; /* the motion leaves the double range */
    dfo_status st = advance(&C, s, t_target);
    s->steps += C.events;
    s->n = dfo_exact_grid_index(M, s);
    s->hA = 0.0;
    if (st != DFO_OK) return st;
    const dfo_dd te = {s->t, 0.0};
    return end_state(&C, s, &C.Ls_, static_force(&C, te, s->X * C.iLs));
}

/* ---- polynomial inputs (dfo_exact_advance_poly) ------------------------------------------------- */
/* The inputs vary over the call as polynomials of degree <= 2 (exact.h). A slip phase is the phase of
 * advance() plus the polynomial particular solution (poly_particular): the same closed form, bounds
 * (the polynomial's third derivative is 0, so the bounds of y''' ... y^(7) are the harmonic part's) and
 * search for the first zero of s x'. A stick phase ends where |S(t)| = |P(t) + F_ext(t) - k X| reaches
 * the limit F_b(t) = max(mu_s, mu_k) N(t): no closed form now, so the search steps, from each point,
 * only as far as g = F_b -+ S provably stays positive (|g''| <= B = |P0| omega^2 + |F_ext''| +
 * max(mu_s, mu_k) |N''| everywhere), which converges on the crossing from below like Newton's method
 * and never steps over it. The normal force max(N + N_ext(t), 0) is a polynomial on each piece between
 * the zeros of N + N_ext(t) (or 0): the call is cut there (not an event). */

/* The loads (over Ls) at t, with the rates of F_ext and F_b (over Ls, per s) in *dF, *dFb. */
static void poly_loads(const ex_ctx *C, dfo_dd t, dfo_loads *L, double *dF, double *dFb)
{
    const double q = (t.hi - C->q_t0) + t.lo, iLs = C->iLs;
    const double F = C->qF[0] + q * (C->qF[1] + 0.5 * q * C->qF[2]);
    const double N = C->qN[0] + q * (C->qN[1] + 0.5 * q * C->qN[2]);
    dfo_loads_set(L, F * iLs, fmax(N, 0.0) * iLs, C->M->mu_k, C->M->mu_b);
    if (dF) *dF = (C->qF[1] + q * C->qF[2]) * iLs;
    if (dFb) *dFb = C->M->mu_b * (C->qN[1] + q * C->qN[2]) * iLs;
}

/* The static force (over Ls) at rest at Xs at t with the loads there, and its rate (per s) in *dS. */
static double poly_static_force(const ex_ctx *C, dfo_dd t, double Xs, dfo_loads *L, double *dS, double *dFb)
{
    double c, sn, dF;
    phase_at(C, t, &c, &sn);
    poly_loads(C, t, L, &dF, dFb);
    if (dS) *dS = -C->fP * C->omega * sn + dF;
    return C->fP * c + L->F_ext - C->k * Xs;
}

/* The first time in [ta, tend) at which the stick phase at Xs breaks away (|S| > F_b, or within
 * rounding of it and not receding), with the side in *dir, the rates of S and F_b there in *dS, *dFb and
 * *at_start = 1 when it is ta itself with the force beyond the limit (no crossing); tend when none. */
static dfo_dd poly_breakaway_from(const ex_ctx *C, double Xs, dfo_dd ta, dfo_dd tend, int *dir, int *at_start, double *dS,
                              double *dFb)
{
    const double iLs = C->iLs, mub = C->M->mu_b;
    const double B = BOUND_SAFETY * (C->fP * C->omega * C->omega + (fabs(C->qF[2]) + mub * fabs(C->qN[2])) * iLs);
    dfo_dd t = ta;
    *at_start = 0;
    for (long it = 0; it < MAX_SEARCH; it++) {
        dfo_loads L;
        double S1, Fb1;
        /* on a belt the block rides on it, X = Xs + vbs (t - ta): the holding force S - c vbs drifts with
         * -k vbs (a ramp: |g''| is bounded by B as without the belt) */
        const double Xt = C->belt ? Xs + C->vbs * dfo_dd_span(ta, t) : Xs;
        double S = poly_static_force(C, t, Xt, &L, &S1, &Fb1);
        if (C->belt) {
            S -= C->M->p.c * C->vbs;
            S1 -= C->k * C->vbs;
        }
        const double gp = L.Fb - S, gm = L.Fb + S, gp1 = Fb1 - S1, gm1 = Fb1 + S1;
        const double tol = 4.0 * DBL_EPSILON * (C->fP + fabs(L.F_ext) + fabs(C->k * Xt) + L.Fb +
                                                (C->belt ? fabs(C->M->p.c * C->vbs) : 0.0));
        *dS = S1;
        *dFb = Fb1;
        if (gp < 0.0 || gm < 0.0) { /* beyond the limit */
            *dir = (gp < 0.0) ? 1 : -1;
            *at_start = (it == 0);
            return t;
        }
        if ((gp <= tol && gp1 <= 0.0) || (gm <= tol && gm1 <= 0.0)) { /* on it, to rounding, and rising */
            *dir = (gp <= gm) ? 1 : -1;
            return t;
        }
        const double d = fmin(safe_step(gp, gp1, B), safe_step(gm, gm1, B));
        const dfo_dd tn = dfo_dd_add(t, dfo_dd_of(d, 0.0));
        if (!dfo_dd_lt(tn, tend)) return tend;
        if (!dfo_dd_lt(t, tn)) { /* no progress: on the limit to the resolution of t */
            *dir = (gp <= gm) ? 1 : -1;
            return t;
        }
        t = tn;
    }
    *dir = 0;
    return ta; /* (not reached: the steps converge on the crossing) */
}

/* The next breakaway from ta; with skip, one at ta itself (a slide just tried did not start) is passed
 * over: the search restarts a little later, further each time, until it finds a later one. */
static dfo_dd poly_breakaway(const ex_ctx *C, double Xs, dfo_dd ta, dfo_dd tend, int skip, int *dir, int *at_start, double *dS,
                         double *dFb)
{
    dfo_dd b = poly_breakaway_from(C, Xs, ta, tend, dir, at_start, dS, dFb);
    if (skip && !dfo_dd_lt(ta, b)) {
        double d = 4.0 * DBL_EPSILON * fmax(fabs(ta.hi), 1.0 / (C->w0 + fabs(C->omega)));
        for (int i = 0; i < 200; i++, d *= 2.0) {
            const dfo_dd t1 = dfo_dd_add(ta, dfo_dd_of(d, 0.0));
            if (!dfo_dd_lt(t1, tend)) return tend;
            b = poly_breakaway_from(C, Xs, t1, tend, dir, at_start, dS, dFb);
            if (dfo_dd_lt(t1, b)) break;
        }
    }
    return b;
}

/* int_0^D cos(l w) dw, int_0^D sin(l w) dw, int_0^D w cos(l w) dw, int_0^D w sin(l w) dw, without the
 * cancellation of the closed forms at small l D (their series there). */
static void trig_moments(double l, double D, double *S1, double *S2, double *T1, double *T2)
{
    const double z = l * D;
    if (fabs(z) < 0.5) { /* 14 terms: the remainder is below z^28 / 28! */
        double p = 1.0, s1 = 0.0, s2 = 0.0, t1 = 0.0, t2 = 0.0; /* p = z^j / j! */
        for (int j = 0; j < 28; j++) {
            const double sg = ((j >> 1) & 1) ? -1.0 : 1.0;
            if ((j & 1) == 0) {
                s1 += sg * p / (j + 1);
                t1 += sg * p / (j + 2);
            } else {
                s2 += sg * p / (j + 1);
                t2 += sg * p / (j + 2);
            }
            p *= z / (j + 1);
        }
        *S1 = D * s1;
        *S2 = D * s2;
        *T1 = D * D * t1;
        *T2 = D * D * t2;
        return;
    }
    double sn, cs;
    dfo_sincos(z, &sn, &cs);
    const double h = dfo_sin(0.5 * z);
    *S1 = sn / l;
    *S2 = 2.0 * h * h / l; /* (1 - cos z) / l */
    *T1 = D * sn / l - *S2 / l;
    *T2 = -D * cs / l + sn / (l * l);
}

/* The friction work mu_k int N(t) |dx| (physical) of the slip phase P over tau in [u0, u1], exactly for
 * the polynomial N(u) = n0 + n1 u + n2 u^2 / 2: with x = xc + Y, Y = y + q(u) (q the particular solution's
 * xp1 u + xp2 u^2 / 2, y the harmonic part), int N dY = [N Y] - int N' Y, int N' q a polynomial's integral
 * and int y, int u y from the equation of motion y = a cos(theta) - y'' - 2 zeta y':
 *   int y = a int cos(theta) - [y' + 2 zeta y],
 *   int u y = a int u cos(theta) - [u y'] + [y] - 2 zeta [u y] + 2 zeta int y. */
static double poly_work(const ex_ctx *C, const ex_phase *P, double u0, double u1)
{
    if (!(u1 > u0)) return 0.0;
    ex_val a0, a1;
    eval(C, P, u0, &a0);
    eval(C, P, u1, &a1);
    const double z = C->zeta, D = u1 - u0;
    double S1, S2, T1, T2;
    trig_moments(C->lam, D, &S1, &S2, &T1, &T2);
    const double C0 = a0.cth * S1 - a0.sth * S2, C1 = u0 * C0 + (a0.cth * T1 - a0.sth * T2);
    const double I0 = C->a * C0 - ((a1.hy1 + 2.0 * z * a1.hy) - (a0.hy1 + 2.0 * z * a0.hy));
    const double I1 = C->a * C1 - (u1 * a1.hy1 - u0 * a0.hy1) + (a1.hy - a0.hy) - 2.0 * z * (u1 * a1.hy - u0 * a0.hy) +
                      2.0 * z * I0;
    /* int (n1 + n2 u)(xp1 u + xp2 u^2 / 2) du */
    const double e2 = 0.5 * (u1 - u0) * (u1 + u0), e3 = (u1 * u1 * u1 - u0 * u0 * u0) / 3.0;
    const double e4 = 0.25 * (u1 * u1 - u0 * u0) * (u1 * u1 + u0 * u0);
    const double Iq = P->n1 * P->xp1 * e2 + (0.5 * P->n1 * P->xp2 + P->n2 * P->xp1) * e3 + 0.5 * P->n2 * P->xp2 * e4;
    const double N0 = P->n0 + u0 * (P->n1 + 0.5 * u0 * P->n2), N1 = P->n0 + u1 * (P->n1 + 0.5 * u1 * P->n2);
    const double W = (N1 * a1.y - N0 * a0.y) - (P->n1 * I0 + P->n2 * I1 + Iq);
    return C->M->mu_k * P->s * W * C->Ls;
}

/* poly_work over times from the phase's start (dfo_phase_work_fn) */
static double phase_work(const void *ctx, const void *phase, double t0, double t1)
{
    const ex_ctx *C = (const ex_ctx *)ctx;
    return poly_work(C, (const ex_phase *)phase, C->w0 * t0, C->w0 * t1);
}

#define MAX_TURNS DFO_EXACT_MAX_EVENTS /* turning points of x in one slide on a belt (observe): the work bound */

/* On a belt the block may turn inside a slide (v through 0 while v - vb keeps its sign): the turning
 * points of the slide P in tau in (ua, ub) (from its start) sampled for the window's extremes, found by
 * the stop search itself on the absolute velocity (a phase of the same motion restarted at each one). */
static void belt_turns(const ex_ctx *C, const ex_phase *P, double ua, double ub, dfo_state *s)
{
    ex_ctx D = *C; /* phase_start without the belt's shift: y' is then v itself */
    D.belt = 0;
    const double w0 = C->w0, vbu = P->vbu;
    double u = ua;
    for (long long n = 0; n < MAX_TURNS && u < ub; n++) {
        ex_val w;
        eval(C, P, u, &w);
        const double X = P->xc + (w.hy + u * (P->xp1a + 0.5 * u * P->xp2)), va = w.y1 + vbu; /* x, v / w0 */
        const double tol = tol_of(C, P, &w) + ROUND * fabs(vbu);
        int dir = (fabs(va) > tol) ? dfo_sign(va) : dfo_sign(w.y2);
        if (dir == 0) dir = 1;
        int r = SEARCH_NULL;
        ex_val z;
        for (int k = 0; k < 2 && r == SEARCH_NULL; k++, dir = -dir) {
            ex_phase Q;
            phase_start(&D, &Q, dfo_dd_add_quot(dfo_dd_of(P->ta, 0.0), u, 0.0, w0), X, w0 * va, P->s, NULL);
            Q.s = dir; /* the motion of P (its friction), searched for the zero of dir v */
            r = find_stop(&D, &Q, X - Q.xc, va, ub - u, &z);
        }
        if (r != SEARCH_STOP || !(z.u > 0.0)) return;
        u += z.u;
        if (u < ub) dfo_exact_sample(s, phase_x(C, P, u / w0));
    }
}

/* The bookkeeping of a phase on a belt (after_phase): x moves while stuck (X = xa + vb (t - ta)), and in
 * a slide it may turn (belt_turns); the friction's work is on the relative motion. */
static void belt_after_phase(const ex_ctx *C, dfo_state *s, const ex_phase *P, double ta, double tb, double xa,
                             double xb, int mode_during, int mode_after, int event)
{
    const dfo_model *M = C->M;
    if (event && mode_after != mode_during && C->on_switch)
        C->on_switch(C->switch_ctx, tb, xb, mode_during, mode_after);
    if (!M->p.observe) return;
    const double w0 = M->p.t_obs_start, w1 = M->p.t_obs_stop;
    if (tb < w0 || ta > w1) return;
    const double a = fmax(ta, w0), b = fmin(tb, w1);
    if (P == NULL) { /* riding on the belt */
        s->t_stuck += (mode_during == 0) ? fmax(b - a, 0.0) : 0.0;
        dfo_exact_sample(s, (a == ta) ? xa : xa + C->vb * (a - ta));
        dfo_exact_sample(s, (b == tb) ? xb : xa + C->vb * (b - ta));
    } else {
        dfo_exact_sample(s, (a == ta) ? xa : phase_x(C, P, a - ta));
        dfo_exact_sample(s, (b == tb) ? xb : phase_x(C, P, b - ta));
        if (b > a) {
            s->E_friction += poly_work(C, P, C->w0 * (a - ta), C->w0 * (b - ta)); /* relative: y is */
            belt_turns(C, P, C->w0 * (a - ta), C->w0 * (b - ta), s);
        }
    }
    if (event && mode_after != mode_during && tb > w0 && tb <= w1) s->transitions++;
}

/* A phase [ta, tb] spent in mode_during (P its slip, NULL while stuck), from xa to xb (physical), after
 * which the mode is mode_after (an event at tb when event is set): with polynomial inputs (poly), a
 * slide's friction work from its normal force (varying or not). */
static DFO_EXACT_INLINE void after_phase(const ex_ctx *C, int poly, dfo_state *s, const ex_phase *P, double ta,
                                         double tb, double xa, double xb, int mode_during, int mode_after, int event)
{
    if (poly && C->belt) {
        belt_after_phase(C, s, P, ta, tb, xa, xb, mode_during, mode_after, event);
    } else if (poly) {
        const double n[3] = {P ? P->n0 : 0.0, P ? P->n1 : 0.0, P ? P->n2 : 0.0};
        dfo_exact_after_phase_poly(C->M, C->on_switch, C->switch_ctx, s, phase_x, phase_work, C, P, P ? n : NULL, ta,
                                   tb, xa, xb, mode_during, mode_after, event);
    } else {
        dfo_exact_after_phase(C->M, C->L.muk_N, C->on_switch, C->switch_ctx, s, phase_x, C, P, ta, tb, xa, xb,
                              mode_during, mode_after, event);
    }
}

/* The phases from s to t_target, the inputs held (poly 0) or varying as polynomials (poly 1) over one piece
 * (C->qN a polynomial > 0 inside it, or 0): one loop, the two kinds of inputs differing only in the
 * stick phase's breakaway, the loads at a stop and the phases' bookkeeping. */
static DFO_EXACT_INLINE dfo_status advance_loop(ex_ctx *C, dfo_state *s, double t_target, const int poly)
{
    int skip = 0, stall = 0, stick_dir = 0, carried = 0;
    double cs[2] = {1.0, 0.0}; /* the excitation phase at t when carried (carried > 0) */
    double stick_cs[2] = {NAN, 0.0}; /* held: the phase at the stick phase's breakaway (NaN: from the time) */
    const double Ls = C->Ls, w0 = C->w0;
    const dfo_dd target = {t_target, 0.0};
    dfo_dd t = {s->t, 0.0}, t_last = t, stick_tb = {NAN, 0.0};
    double Xs = s->X * C->iLs, Vs = s->V * C->iLs; /* the state over Ls */
    const int sens = C->M->p.sensitivity; /* propagate s->J (exact.h) */
    const int belt = poly && C->belt;     /* a moving belt (its calls take the polynomial inputs' loop) */
    const double cvb = belt ? C->M->p.c * C->vbs : 0.0; /* riding on the belt, the damper pulls with c vb */
    const int fric = poly ? (C->M->mu_b > 0.0 && (C->qN[0] != 0.0 || C->qN[1] != 0.0 || C->qN[2] != 0.0))
                          : C->Ls_.Fb > 0.0;
    while (dfo_dd_lt(t, target)) {
        if (C->events >= DFO_EXACT_MAX_EVENTS) return DFO_ERR_EVENTS; /* the work bound (newmark.h) */
        if (t.hi == t_last.hi && t.lo == t_last.lo) {
            if (++stall > MAX_STALL) return DFO_ERR_NO_PROGRESS;
        } else {
            stall = 0;
            t_last = t;
        }
        const double ta = t.hi, xa = s->X;
        if (s->mode == 0 && !fric) {
            /* no friction: a block at rest never sticks; it moves along the force (or its rate) */
            double c, sn, S, dS, d2S;
            if (poly) {
                dfo_loads L;
                S = poly_static_force(C, t, Xs, &L, &dS, NULL);
                phase_at(C, t, &c, &sn);
                d2S = -C->omega * C->omega * (C->fP * c) + C->qF[2] * C->iLs;
                if (belt) { /* at v = vb: the relative acceleration's sign and rates */
                    S -= cvb;
                    dS -= C->k * C->vbs;
                }
            } else {
                phase_at(C, t, &c, &sn);
                S = C->fP * c + C->fF - C->k * Xs;
                dS = -C->fP * C->omega * sn;
                d2S = -C->omega * C->omega * (C->fP * c);
            }
            const int dir = dfo_free_start_dir(S, dS, d2S);
            s->mode = dir;
            C->events++;
            after_phase(C, poly, s, NULL, ta, ta, xa, xa, 0, dir, 1);
            continue;
        }
        if (s->mode == 0) {
            int dir = 0, at_start = 0;
            double dS = 0.0, dFb = 0.0;
            dfo_dd tb;
            if (poly) {
                tb = poly_breakaway(C, Xs, t, target, skip, &dir, &at_start, &dS, &dFb);
            } else {
                if (isnan(stick_tb.hi)) stick_dir = 0;
                tb = breakaway(C, Xs, t, skip, &stick_tb, &stick_dir, stick_cs);
                dir = stick_dir;
            }
            skip = 0;
            if (sens) dfo_sens_stick(s->J);
            if (!dfo_dd_lt(tb, target)) {
                if (belt) { /* riding on the belt to the end */
                    Xs += C->vbs * dfo_dd_span(t, target);
                    s->X = Xs * Ls;
                    if (!(fabs(s->X) <= DBL_MAX)) return DFO_ERR_NONFINITE;
                }
                s->t = t_target;
                t = target;
                after_phase(C, poly, s, NULL, ta, t_target, xa, s->X, 0, 0, 0);
                break;
            }
            if (belt) {
                Xs += C->vbs * dfo_dd_span(t, tb);
                s->X = Xs * Ls;
                if (!(fabs(s->X) <= DBL_MAX)) return DFO_ERR_NONFINITE;
            }
            t = tb;
            s->t = tb.hi;
            Vs = belt ? C->vbs : 0.0;
            s->V = belt ? C->vb : 0.0;
            s->mode = dir;
            if (poly) {
                carried = 0;
                if (sens && !at_start) {
                    /* h = dir S(t) - F_b(t) = 0 at t_b: dt_b = k dx / D, D = S' - dir F_b' (S' = P' + F_ext'), and
                     * the slide starts with a+ = dir (F_b - mu_k N) / m: the v row becomes -a+ k / D times the x
                     * row */
                    dfo_loads L;
                    poly_loads(C, tb, &L, NULL, NULL);
                    const double a_plus = dir * (L.Fb - L.muk_N) / C->M->p.m, D = dS - dir * dFb;
                    /* (D = 0: a tangential breakaway, the Jacobian not finite, as with held inputs) */
                    dfo_sens_breakaway(s->J, (a_plus != 0.0) ? -a_plus * C->k / D : 0.0);
                }
            } else if (!isnan(stick_cs[0])) { /* the slide starts with the crossing's phase */
                carried = 1;
                cs[0] = stick_cs[0];
                cs[1] = stick_cs[1];
                if (sens) { /* dt_b = k dx / P'(t_b); the slide starts with a+ = dir (F_b - mu_k N) / m */
                    const double dP = -C->fP * C->omega * stick_cs[1];
                    const double a_plus = dir * (C->Ls_.Fb - C->Ls_.muk_N) / C->M->p.m;
                    dfo_sens_breakaway(s->J, (a_plus != 0.0) ? -a_plus * C->k / dP : 0.0);
                }
            } /* (a breakaway at the phase's start: the force is beyond the limit already, dt_b = 0) */
            C->events++;
            after_phase(C, poly, s, NULL, ta, tb.hi, xa, s->X, 0, dir, 1);
            continue;
        }
        /* a slip in direction sd from (t, X, V) */
        const int sd = s->mode;
        ex_phase P;
        ex_val v;
        phase_start(C, &P, t, Xs, Vs, sd, carried ? cs : NULL);
        if (belt) belt_shift(C, &P);
        const double u_max = w0 * ((t_target - t.hi) - t.lo);
        const int cut = u_max > C->u_span; /* a long phase: restart after u_span (not an event) */
        const double u_end = cut ? C->u_span : u_max;
        const int r = find_stop(C, &P, Xs - P.xc, belt ? (Vs - C->vbs) / w0 : Vs / w0, u_end, &v);
        if (r == SEARCH_FAIL) return DFO_ERR_NO_PROGRESS;
        if (!isfinite(v.y) || !isfinite(v.y1)) return DFO_ERR_NONFINITE;
        if (r == SEARCH_NONE) {
            Xs = P.xc + v.y;
            Vs = w0 * v.y1;
            if (belt) { /* (eval: v.hy is the harmonic part) */
                Xs = P.xc + (v.hy + v.u * (P.xp1a + 0.5 * v.u * P.xp2));
                Vs = w0 * v.y1 + C->vbs;
            }
            s->X = Xs * Ls;
            s->V = Vs * Ls;
            if (!(fabs(s->X) <= DBL_MAX && fabs(s->V) <= DBL_MAX)) return DFO_ERR_NONFINITE;
            const dfo_dd tc = cut ? dfo_dd_add_quot(t, u_end, 0.0, w0) : target;
            if (sens) dfo_sens_slide(C->M, dfo_dd_span(t, tc), s->J);
            carried = 0;
            s->t = tc.hi;
            after_phase(C, poly, s, &P, ta, tc.hi, xa, s->X, sd, sd, 0);
            t = tc;
            if (cut) continue;
            break;
        }
        dfo_dd ts = dfo_dd_add_quot(t, v.u, 0.0, w0);
        if (dfo_dd_lt(target, ts)) ts = target;
        const int at_end = !dfo_dd_lt(ts, target);
        if (sens) dfo_sens_slide(C->M, dfo_dd_span(t, ts), s->J);
        t = ts;
        s->t = ts.hi;
        Xs = P.xc + v.y;
        Vs = 0.0;
        if (belt) { /* x itself from the harmonic part (v may be a Taylor model's, without it) */
            ex_val w;
            eval(C, &P, v.u, &w);
            Xs = P.xc + (w.hy + w.u * (P.xp1a + 0.5 * w.u * P.xp2));
            Vs = C->vbs;
        }
        s->X = Xs * Ls;
        s->V = belt ? C->vb : 0.0;
        if (!(fabs(s->X) <= DBL_MAX)) return DFO_ERR_NONFINITE; /* (never an event at an infinite x) */
        /* the static force at a stop from the excitation phase there (known from the search), and the
         * loads there */
        dfo_loads Lp;
        const dfo_loads *L = &C->Ls_;
        double Fs;
        if (poly) {
            Fs = poly_static_force(C, ts, Xs, &Lp, NULL, NULL);
            if (r == SEARCH_STOP && !at_end) Fs = C->fP * v.cth + Lp.F_ext - C->k * Xs;
            Fs -= cvb; /* (on a belt, the holding force: the damper pulls with c vb) */
            L = &Lp;
        } else {
            Fs = (r == SEARCH_STOP && !at_end) ? C->fP * v.cth + C->fF - C->k * Xs : static_force(C, ts, Xs);
        }
        int next = dfo_rest_mode(L, Fs);
        if (!fric) {
            /* no friction: never stuck; at a zero force the velocity, falling through 0, reverses */
            if (next == 0 || (r == SEARCH_NULL && next == sd)) next = -sd;
            if (r == SEARCH_STOP && !at_end) {
                /* the motion is the same in either direction: the next phase starts from the motion's
                 * own state there (its velocity within rounding of 0, not set to 0: undamped, a
                 * velocity error would never decay, and one made at every reversal would add up) */
                ex_val w;
                eval(C, &P, v.u, &w);
                Xs = P.xc + w.y;
                Vs = w0 * w.y1;
                if (belt) {
                    Xs = P.xc + (w.hy + w.u * (P.xp1a + 0.5 * w.u * P.xp2));
                    Vs += C->vbs;
                }
                s->X = Xs * Ls;
                s->V = Vs * Ls;
                v.cth = w.cth;
                v.sth = w.sth;
            }
        } else if (r == SEARCH_NULL && next != -sd) { /* the slide could not start: the block stays at */
            next = 0;                                 /* rest, and a breakaway right now is passed over */
            skip = 1;
        }
        if (next == 0) stick_tb.hi = NAN; /* a new stick phase */
        if (sens) {
            /* the saltation at the stop: stick (rank one), or a reversal (a- = (F_s - sd mu_k N) / m before,
             * a+ = (F_s + sd mu_k N) / m after, the kinetic force at ts); a touch that slides on, or a
             * reversal without friction (a+ = a-), leaves J as it is */
            if (next == 0 || r == SEARCH_NULL) dfo_sens_stick(s->J);
            else if (next == -sd && L->muk_N > 0.0)
                dfo_sens_reversal(s->J, (Fs + sd * L->muk_N) / (Fs - sd * L->muk_N));
        }
        if (next == -sd && r == SEARCH_STOP && !at_end && carried < CARRY_MAX) {
            /* a reversal: the next slide starts here, with the phase the search reached (exact for the
             * stop's time as a double-double, to the rounding of lambda tau) */
            carried++;
            cs[0] = v.cth;
            cs[1] = v.sth;
        } else {
            carried = 0;
        }
        s->mode = next;
        C->events++;
        after_phase(C, poly, s, &P, ta, ts.hi, xa, s->X, sd, next, 1);
    }
    s->X = Xs * Ls;
    s->V = Vs * Ls;
    return DFO_OK;
}

static dfo_status advance(ex_ctx *C, dfo_state *s, double t_target) { return advance_loop(C, s, t_target, 0); }

static dfo_status advance_poly(ex_ctx *C, dfo_state *s, double t_target) { return advance_loop(C, s, t_target, 1); }

dfo_status dfo_exact_spring_advance_poly(const dfo_model *M, const dfo_inputs *u, const dfo_input_poly *q, dfo_state *s,
                                         double t_target, dfo_switch_fn on_switch, void *switch_ctx, double vb)
{
    double n[3], z[2];
    const int nz = dfo_exact_normal_zeros(M, u, q, s->t, t_target, n, z);
    /* the length scale of the loads at both ends and at the middle */
    dfo_inputs u1, u2;
    dfo_input_poly_at(u, q, t_target, &u1);
    dfo_input_poly_at(u, q, 0.5 * (s->t + t_target), &u2);
    int e = scale_exponent(M, u, s);
    e = (scale_exponent(M, &u1, s) > e) ? scale_exponent(M, &u1, s) : e;
    e = (scale_exponent(M, &u2, s) > e) ? scale_exponent(M, &u2, s) : e;
    if (vb != 0.0) { /* on a belt: its speed over w0, and where a block riding on it gets to */
        dfo_state sb = *s;
        sb.V = vb;
        sb.X = s->X + vb * (t_target - s->t);
        e = (scale_exponent(M, u, &sb) > e) ? scale_exponent(M, u, &sb) : e;
    }
    ex_ctx C;
    ctx_init_scaled(&C, M, u, e);
    C.on_switch = on_switch;
    C.switch_ctx = switch_ctx;
    C.poly = 1;
    C.q_t0 = q->t0;
    C.qF[0] = dfo_external_force(M, u);
    C.qF[1] = q->F[0];
    C.qF[2] = q->F[1];
    if (vb != 0.0) {
        C.belt = 1;
        C.vb = vb;
        C.vbs = vb * C.iLs;
    }
    if (out_of_range(&C, s)) return DFO_ERR_NONFINITE;
    /* the pieces between the zeros of N + N_ext(t) */
    dfo_status st = DFO_OK;
    for (int i = 0; i <= nz && st == DFO_OK; i++) {
        const double a = (i == 0) ? s->t : q->t0 + z[i - 1], b = (i == nz) ? t_target : q->t0 + z[i];
        if (!(b > s->t)) continue;
        dfo_exact_piece_normal(n, 0.5 * (a + b) - q->t0, C.qN);
        st = advance_poly(&C, s, b);
    }
    s->steps += C.events;
    s->n = dfo_exact_grid_index(M, s);
    s->hA = 0.0;
    if (st != DFO_OK) return st;
    dfo_exact_piece_normal(n, t_target - q->t0, C.qN); /* the loads at the end: the piece there */
    const dfo_dd te = {s->t, 0.0};
    dfo_loads L;
    const double S = poly_static_force(&C, te, s->X * C.iLs, &L, NULL, NULL);
    if (C.belt && s->mode == 0) { /* riding on the belt: the friction holds S - c vb */
        s->V = vb;
        s->A = 0.0;
        s->F = dfo_stick_force(&L, S - M->p.c * C.vbs) * C.Ls;
        if (!(fabs(s->X) <= DBL_MAX)) return DFO_ERR_NONFINITE;
        return DFO_OK;
    }
    return end_state(&C, s, &L, S);
}

