/* The exact scheme without a spring (k = 0): closed-form phases, events bracketed between the zeros
 * of the applied force. See exact_free.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "exact_free.h"
#include "dmath.h"
#include "exact_observe.h"
#include "exact_poly.h"
#include "exact_sens.h"

#include "friction.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

#define TWO_PI (2.0 * DFO_PI)
#define HALF_PI (0.5 * DFO_PI)
#define ROUND DFO_EXACT_ROUND /* relative rounding level of the touch test (as exact_spring.c) */
#define POLISH_TOL (4.0 * DBL_EPSILON) /* relative level at which a bracketed stop is taken */
#define MAX_POLISH 200                 /* Newton / bisection steps of a bracketed stop */
#define MAX_STALL 64                   /* events in a row at one instant before it is an error */
#define SERIES_MAX 1.0                 /* |p tau| up to which E1, E2 are summed as Taylor series */
#define SERIES_TERMS 22                /* terms of those series (the remainder is below 2^-60 there) */
#define SKIP_MARGIN 1e-9               /* relative margin of the lower bound that skips intervals */

/* What is constant over one call. */
typedef struct {
    const dfo_model *M;
    dfo_loads L;
    double b;            /* c / m */
    double w;            /* omega (0: the excitation is a constant force) */
    double A;            /* |P0| / m when omega > 0, else 0 */
    double f_const;      /* the constant force per mass besides friction: (F_ext + P0 cos phi (omega = 0)) / m */
    double inv_p2;       /* 1 / (b^2 + omega^2) */
    double R_H;          /* A / |b + i omega|: the amplitude of the harmonic part of v */
    dfo_switch_fn on_switch;
    void *switch_ctx;
    long long events;
    /* polynomial inputs (dfo_exact_free_advance_poly; poly = 0 otherwise): physical, in q = t - q_t0,
     * F_ext(t) = qF[0] + qF[1] q + qF[2] q^2 / 2, N(t) = qN[0] + qN[1] q + qN[2] q^2 / 2 on a piece where
     * N + N_ext(t) > 0 (all 0 on a piece where it is <= 0) */
    int poly;
    double q_t0, qF[3], qN[3];
} fr_ctx;

/* One slip phase from (ta, xa, va) in direction s. */
typedef struct {
    int s;
    double ta, xa, va;
    double f0;       /* constant acceleration: f_const - s mu_k N / m */
    double c0, s0;   /* cos, sin of the excitation phase at ta */
    double ang_eps;  /* the rounding of that phase (rad) */
    /* polynomial inputs: the force per mass is f0 + f1 tau + f2 tau^2 / 2 (+ the excitation), the normal
     * force n0 + n1 tau + n2 tau^2 / 2 (physical) */
    int poly;
    double f1, f2, n0, n1, n2;
} fr_phase;

/* The motion at tau. */
typedef struct {
    double tau, x, v, a;
    double cth, sth; /* cos, sin of the excitation phase there */
    double vmag;     /* the size of the terms summed into v (its rounding scale) */
} fr_val;

/* ---- closed form ------------------------------------------------------------------------------ */

static void ctx_init(fr_ctx *C, const dfo_model *M, const dfo_inputs *in)
{
    const dfo_params *p = &M->p;
    C->M = M;
    dfo_loads_init(&C->L, M, in);
    C->b = p->c / p->m;
    const int harmonic = p->omega > 0.0 && M->P_amp > 0.0;
    C->w = harmonic ? p->omega : 0.0;
    C->A = harmonic ? M->P_amp / p->m : 0.0;
    C->f_const = (C->L.F_ext + (harmonic ? 0.0 : dfo_excitation(M, 0.0))) / p->m;
    const double p2 = C->b * C->b + C->w * C->w;
    C->inv_p2 = harmonic ? 1.0 / p2 : 0.0;
    C->R_H = harmonic ? C->A / sqrt(p2) : 0.0;
    C->on_switch = NULL;
    C->switch_ctx = NULL;
    C->events = 0;
    C->poly = 0;
}

static void phase_init(const fr_ctx *C, fr_phase *P, double ta, double X, double V, int s)
{
    const dfo_model *M = C->M;
    P->s = s;
    P->ta = ta;
    P->xa = X;
    P->va = V;
    P->f0 = C->f_const - s * C->L.muk_N / M->p.m;
    P->c0 = 1.0;
    P->s0 = 0.0;
    P->ang_eps = 0.0;
    P->poly = 0;
    P->f1 = P->f2 = P->n0 = P->n1 = P->n2 = 0.0;
    if (C->poly) {
        /* the polynomial force F_ext(t) - s mu_k N(t) over m at ta and its derivatives (f_const holds
         * F_ext at the call's start: replaced by F_ext(ta)) */
        const double q = ta - C->q_t0, mk = M->mu_k;
        const double F0 = C->qF[0] + q * (C->qF[1] + 0.5 * q * C->qF[2]), F1 = C->qF[1] + q * C->qF[2];
        P->n0 = C->qN[0] + q * (C->qN[1] + 0.5 * q * C->qN[2]);
        P->n1 = C->qN[1] + q * C->qN[2];
        P->n2 = C->qN[2];
        P->poly = 1;
        P->f0 = C->f_const + (F0 - C->L.F_ext - s * mk * P->n0) / M->p.m;
        P->f1 = (F1 - s * mk * P->n1) / M->p.m;
        P->f2 = (C->qF[2] - s * mk * P->n2) / M->p.m;
    }
    if (C->A > 0.0) {
        const double th = M->p.omega * ta + M->P_phase; /* from the absolute time at every phase start */
        dfo_sincos(th, &P->s0, &P->c0);
        P->ang_eps = 8.0 * DBL_EPSILON * (fabs(th) + TWO_PI);
    }
}

/* phi1(mu) = (e^mu - 1) / mu and phi2(mu) = (e^mu - 1 - mu) / mu^2 for mu <= 0, from em1 = expm1(mu). */
static double phi1_real(double mu, double em1) { return (mu == 0.0) ? 1.0 : em1 / mu; }

static double phi2_real(double mu, double em1)
{
    if (fabs(mu) <= 1.0) { /* sum mu^n / (n + 2)!, n <= 17 (remainder below 1 / 20!) */
        double t = 0.5, sum = 0.0;
        for (int n = 0; n <= 17; n++) {
            sum += t;
            t *= mu / (double)(n + 3);
        }
        return sum;
    }
    return (em1 - mu) / (mu * mu);
}

/* phi3(mu), phi4(mu) (phi_k(z) = sum z^n / (n + k)!) for mu <= 0 from phi2(mu): their series for
 * |mu| <= 1, else phi_{k+1} = (phi_k - 1/k!) / mu. */
static void phi34_real(double mu, double p2, double *p3, double *p4)
{
    if (fabs(mu) <= 1.0) {
        double t3 = 1.0 / 6.0, t4 = 1.0 / 24.0, s3 = 0.0, s4 = 0.0;
        for (int n = 0; n <= 17; n++) {
            s3 += t3;
            s4 += t4;
            t3 *= mu / (double)(n + 4);
            t4 *= mu / (double)(n + 5);
        }
        *p3 = s3;
        *p4 = s4;
        return;
    }
    *p3 = (p2 - 0.5) / mu;
    *p4 = (*p3 - 1.0 / 6.0) / mu;
}

/* E1 = (e^nu - e^mu) / (nu - mu) and E2 = (phi1(nu) - phi1(mu)) / (nu - mu) for mu = -b tau <= 0,
 * nu = i y, y = omega tau, with cw + i sw = e^{i y}, e = e^mu, em1 = expm1(mu). */
static void divided(double mu, double y, double cw, double sw, double e, double em1, double *E1r, double *E1i,
                    double *E2r, double *E2i)
{
    if (mu * mu + y * y <= SERIES_MAX * SERIES_MAX) {
        /* E1 = sum h_n / (n + 1)!, E2 = sum h_n / (n + 2)!, h_n = sum_j mu^j nu^(n - j) = nu h_(n-1) + mu^n */
        double hr = 1.0, hi = 0.0, mun = 1.0, f1 = 1.0, f2 = 0.5;
        double s1r = 0.0, s1i = 0.0, s2r = 0.0, s2i = 0.0;
        for (int n = 0; n < SERIES_TERMS; n++) {
            s1r += hr * f1;
            s1i += hi * f1;
            s2r += hr * f2;
            s2i += hi * f2;
            mun *= mu;
            const double nr = -y * hi + mun, ni = y * hr; /* nu h + mu^(n+1) */
            hr = nr;
            hi = ni;
            f1 /= (double)(n + 2);
            f2 /= (double)(n + 3);
        }
        *E1r = s1r;
        *E1i = s1i;
        *E2r = s2r;
        *E2i = s2i;
        return;
    }
    /* |nu - mu| > 1: E1 = e^nu phi1(mu - nu); phi1(z), z = mu - i y, without cancellation:
     * e^z - 1 = (expm1(mu) cos y - (1 - cos y)) - i e^mu sin y, 1 - cos y = sin^2 y / (1 + cos y) */
    const double omc = (cw > 0.0) ? sw * sw / (1.0 + cw) : 1.0 - cw;
    const double er = em1 * cw - omc, ei = -e * sw;
    const double d = mu * mu + y * y;
    const double pr = (er * mu - ei * y) / d, pi = (ei * mu + er * y) / d; /* (er + i ei) / (mu - i y) */
    *E1r = cw * pr - sw * pi;
    *E1i = cw * pi + sw * pr;
    /* E2 = (phi1(i y) - phi1(mu)) / (i y - mu), phi1(i y) = sin y / y + i (1 - cos y) / y */
    const double ar = (y != 0.0 ? sw / y : 1.0) - phi1_real(mu, em1), ai = (y != 0.0 ? omc / y : 0.0);
    /* divided by (-mu + i y) */
    *E2r = (ar * -mu + ai * y) / d;
    *E2i = (ai * -mu - ar * y) / d;
}

static void eval(const fr_ctx *C, const fr_phase *P, double tau, fr_val *out)
{
    const double mu = -C->b * tau;
    const double e = (mu != 0.0) ? dfo_exp(mu) : 1.0, em1 = (mu != 0.0) ? dfo_expm1(mu) : 0.0;
    const double p1 = phi1_real(mu, em1), p2 = phi2_real(mu, em1);
    const double t1 = P->va * e, t2 = P->f0 * tau * p1;
    double v = t1 + t2;
    double x = P->xa + (P->va * tau * p1 + P->f0 * tau * tau * p2);
    double vmag = fabs(t1) + fabs(t2);
    double cth = 1.0, sth = 0.0, q = P->f0;
    if (C->A > 0.0) {
        const double y = C->w * tau;
        double sw, cw;
        dfo_sincos(y, &sw, &cw);
        cth = P->c0 * cw - P->s0 * sw;
        sth = P->s0 * cw + P->c0 * sw;
        double E1r, E1i, E2r, E2i;
        divided(mu, y, cw, sw, e, em1, &E1r, &E1i, &E2r, &E2i);
        const double th = C->A * tau * (P->c0 * E1r - P->s0 * E1i);
        v += th;
        x += C->A * tau * tau * (P->c0 * E2r - P->s0 * E2i);
        vmag += C->A * tau * (fabs(E1r) + fabs(E1i));
        q += C->A * cth;
    }
    if (P->poly) {
        /* the response to f1 tau + f2 tau^2 / 2 from rest:
         * int_0^tau e^{-b (tau - r)} r^j / j! dr = tau^(j+1) phi_(j+1)(-b tau) */
        double p3, p4;
        phi34_real(mu, p2, &p3, &p4);
        const double t2 = tau * tau, u1 = P->f1 * t2 * p2, u2 = P->f2 * t2 * tau * p3;
        v += u1 + u2;
        x += tau * (P->f1 * t2 * p3 + P->f2 * t2 * tau * p4);
        vmag += fabs(u1) + fabs(u2);
        q += tau * (P->f1 + 0.5 * tau * P->f2);
    }
    out->tau = tau;
    out->x = x;
    out->v = v;
    out->a = q - C->b * v;
    out->cth = cth;
    out->sth = sth;
    out->vmag = vmag + C->R_H; /* (the harmonic part's amplitude: the scale of a carried velocity) */
}

/* The state at tau = 0 (no evaluation). */
static void eval0(const fr_ctx *C, const fr_phase *P, fr_val *out)
{
    out->tau = 0.0;
    out->x = P->xa;
    out->v = P->va;
    out->cth = P->c0;
    out->sth = P->s0;
    out->a = P->f0 + C->A * P->c0 - C->b * P->va;
    out->vmag = fabs(P->va) + C->R_H;
}

/* ---- the zeros of q = A cos(theta) + f0 --------------------------------------------------------- */

/* The zeros after tau = 0 in increasing order: zero j at (d[j % 2] + 2 pi (j / 2)) / omega; before a
 * zero of kind up[.] = 1 (theta = alpha, cos falling through -f0 / A) q > 0, after it q < 0. */
typedef struct {
    int n;           /* 0: q keeps the sign of f0 (or is 0); 2: two zeros per period */
    double d[2];     /* offsets of the phase, in [0, 2 pi) */
    int up[2];
    long long j;     /* the next zero */
    double w;
    int min_at_start; /* a zero within rounding of the start is a minimum of e^{b tau} s v */
} fr_zeros;

/* The angle of (c, s) in (-pi, pi], from the better conditioned of acos(c) and acos(s). */
static double angle_of(double c, double s)
{
    if (fabs(c) <= fabs(s)) {
        const double a = dfo_acos(fmax(-1.0, fmin(1.0, c)));
        return (s >= 0.0) ? a : -a;
    }
    const double as = HALF_PI - dfo_acos(fmax(-1.0, fmin(1.0, s))); /* asin(s), |s| < 0.71 */
    if (c > 0.0) return as;
    return (s >= 0.0) ? DFO_PI - as : -DFO_PI - as;
}

static double wrap(double d)
{
    while (d < 0.0) d += TWO_PI;
    while (d >= TWO_PI) d -= TWO_PI;
    return d;
}

static void zeros_init(const fr_ctx *C, const fr_phase *P, fr_zeros *Z)
{
    Z->n = 0;
    Z->j = 0;
    Z->w = C->w;
    Z->min_at_start = 0;
    if (!(C->A > 0.0)) return;
    const double r = -P->f0 / C->A;
    if (!(r > -1.0 && r < 1.0)) return; /* q does not change sign */
    const double alpha = dfo_acos(r), th = angle_of(P->c0, P->s0);
    double d0 = wrap(alpha - th), d1 = wrap(-alpha - th);
    int u0 = 1, u1 = 0;
    if (d1 < d0) {
        const double t = d0;
        d0 = d1;
        d1 = t;
        u0 = 0;
        u1 = 1;
    }
    Z->n = 2;
    Z->d[0] = d0;
    Z->d[1] = d1;
    Z->up[0] = u0;
    Z->up[1] = u1;
    /* the zeros within the rounding of the start's phase are the start's */
    while (Z->j < 2 && Z->d[Z->j] <= P->ang_eps) Z->j++;
    /* s q rises through 0 there (up: q falls through 0) */
    for (int i = 0; i < 2; i++)
        if (Z->d[i] <= P->ang_eps || Z->d[i] >= TWO_PI - P->ang_eps)
            if ((Z->up[i] && P->s < 0) || (!Z->up[i] && P->s > 0)) Z->min_at_start = 1;
}

static double zero_at(const fr_zeros *Z, long long j)
{
    return (Z->d[j & 1] + TWO_PI * (double)(j >> 1)) / Z->w;
}

/* The sign of s q on the interval that ends at zero j (before it). */
static int sign_before(const fr_zeros *Z, long long j, int s, double f0)
{
    if (Z->n == 0) return s * dfo_sign(f0);
    return Z->up[j & 1] ? s : -s;
}

/* ---- the search for the first stop -------------------------------------------------------------- */

enum { SEARCH_NONE = 0, SEARCH_STOP = 1, SEARCH_NULL = 2 };

/* The single zero of g = s v in [lo, hi] with g(lo) > 0 >= g(hi) (e^{b tau} v monotone there): a
 * secant step from the ends (both are extrema of e^{b tau} v, where Newton's method has no slope),
 * then Newton's method kept inside the bracket, bisection when it leaves it or does not halve |g|;
 * done when |g| is at rounding or the step is below the resolution of t. */
static void polish(const fr_ctx *C, const fr_phase *P, const fr_val *vlo, const fr_val *vhi, fr_val *out)
{
    const int s = P->s;
    fr_val lo = *vlo, hi = *vhi, cur;
    double g_prev = INFINITY; /* |g| before the last Newton step */
    {
        const double glo = s * lo.v, ghi = s * hi.v;
        double t = lo.tau + (hi.tau - lo.tau) * (glo / (glo - ghi));
        if (!(t > lo.tau && t < hi.tau)) t = 0.5 * (lo.tau + hi.tau);
        eval(C, P, t, &cur);
    }
    for (int it = 0; it < MAX_POLISH; it++) {
        /* a quarter of the resolution of t = ta + tau: the stop time is then the double nearest to it */
        const double g = s * cur.v, g1 = s * cur.a, res = 0.25 * DBL_EPSILON * (fabs(P->ta) + cur.tau);
        if (fabs(g) <= POLISH_TOL * cur.vmag) break;
        if (g > 0.0) lo = cur; else hi = cur;
        if (hi.tau - lo.tau <= 2.0 * res) break; /* the bracket is at the resolution of t */
        double t = (g1 < 0.0) ? cur.tau - g / g1 : NAN;
        if (t > lo.tau && t < hi.tau && fabs(g) <= 0.5 * g_prev) {
            if (fabs(t - cur.tau) <= res) { /* Newton's step is below the resolution of t: take it */
                cur.x += cur.v * (t - cur.tau) * 0.5;
                cur.tau = t;
                cur.v = 0.0;
                break;
            }
            g_prev = fabs(g);
        } else {
            t = 0.5 * (lo.tau + hi.tau);
            g_prev = INFINITY;
        }
        eval(C, P, t, &cur);
    }
    /* the evaluated point nearest to the stop */
    const fr_val *best = &cur;
    if (fabs(lo.v) < fabs(best->v)) best = &lo;
    if (fabs(hi.v) < fabs(best->v)) best = &hi;
    *out = *best;
}

/* A lower bound of s v after the point v: its monotone part less the harmonic amplitude,
 *   L(d) = s f0 d phi1(-b d) + (s v - s H) e^{-b d} - R_H,   H = Re[A e^{i theta} / (b + i omega)],
 * whose derivative has one sign. Returns the tau up to which s v > 0 is proven (INFINITY: forever;
 * v.tau: nothing proven). L is convex when it falls: one Newton step from 0 stays below its root. */
static double proven_positive(const fr_ctx *C, const fr_phase *P, const fr_val *v)
{
    const int s = P->s;
    const double H = C->A * (C->b * v->cth + C->w * v->sth) * C->inv_p2;
    const double sE = s * (v->v - H), L0 = sE - C->R_H;
    const double margin = SKIP_MARGIN * (fabs(sE) + C->R_H + v->vmag) + ROUND * v->vmag;
    if (!(L0 > margin)) return v->tau;
    const double L1 = s * P->f0 - C->b * sE; /* the sign of L' */
    if (L1 >= 0.0) return INFINITY;
    if (C->b > 0.0 && s * P->f0 - C->b * C->R_H > SKIP_MARGIN * fabs(s * P->f0)) return INFINITY; /* L(inf) > 0 */
    return v->tau + (L0 - margin) / -L1 * (1.0 - SKIP_MARGIN);
}

/* The first stop of the phase in (0, U]: SEARCH_STOP with the state there in *out, SEARCH_NONE (then
 * *out is the state at U) or SEARCH_NULL (a slide from rest that cannot start: *out is the start). */
static int find_stop(const fr_ctx *C, const fr_phase *P, double U, fr_val *out)
{
    const int s = P->s;
    fr_zeros Z;
    zeros_init(C, P, &Z);
    fr_val lo;
    eval0(C, P, &lo);
    int skip_ok = 1;
    if (!(s * P->va > 0.0)) {
        /* from rest: the slide starts only if e^{b tau} s v grows on the first interval */
        if (s * P->va < 0.0 || sign_before(&Z, Z.j, s, P->f0) <= 0) {
            *out = lo;
            out->v = 0.0;
            return SEARCH_NULL;
        }
    } else if (Z.min_at_start && s * P->va <= ROUND * lo.vmag) {
        /* a touch at the start (a communication point on it): s v at its minimum, within rounding */
        *out = lo;
        return SEARCH_STOP;
    }
    for (;;) {
        double hi_tau = (Z.n > 0) ? zero_at(&Z, Z.j) : INFINITY;
        const int dir = sign_before(&Z, Z.j, s, P->f0);
        if (skip_ok && s * lo.v > 0.0) {
            /* skip what the lower bound proves positive, when that passes the interval's end (should
             * rounding defeat the bound, the walk below goes on without it) */
            const double until = proven_positive(C, P, &lo);
            if (until >= U) {
                eval(C, P, U, out);
                if (s * out->v > 0.0) return SEARCH_NONE;
                skip_ok = 0;
            } else if (until > hi_tau) {
                fr_val t;
                eval(C, P, until, &t);
                if (s * t.v > 0.0) {
                    lo = t;
                    while (Z.n > 0 && zero_at(&Z, Z.j) <= until) Z.j++;
                    continue;
                }
                skip_ok = 0;
            }
        }
        const int end = !(hi_tau < U);
        if (end) hi_tau = U;
        fr_val hi;
        eval(C, P, hi_tau, &hi);
        if (!isfinite(hi.x) || !isfinite(hi.v)) {
            *out = hi;
            return SEARCH_NONE;
        }
        const double g_hi = s * hi.v;
        if (dir <= 0) {
            if (g_hi <= 0.0) {
                if (!(s * lo.v > 0.0)) { /* at rest already (rounding) */
                    *out = lo;
                    return SEARCH_STOP;
                }
                polish(C, P, &lo, &hi, out);
                return SEARCH_STOP;
            }
            if (!end && g_hi <= ROUND * hi.vmag) { /* a touch at the minimum of e^{b tau} s v */
                *out = hi;
                return SEARCH_STOP;
            }
        }
        if (end) {
            *out = hi;
            if (g_hi > 0.0) return SEARCH_NONE;
            return SEARCH_STOP; /* rising, yet not above 0 at U (rounding): at rest there */
        }
        lo = hi;
        Z.j++;
    }
}

/* ---- observables (exact_observe.h) ------------------------------------------------------------ */

/* x of a slip phase at time t from its start */
static double phase_x(const void *ctx, const void *phase, double t)
{
    fr_val v;
    eval((const fr_ctx *)ctx, (const fr_phase *)phase, t, &v);
    return v.x;
}

/* ---- the phases (the event loop, as exact_spring.c's) ------------------------------------------- */

/* The next breakaway of the stick phase from ta (cached in the state per stick phase). With skip, a
 * breakaway at ta itself (a slide just tried did not start) is passed over: the search restarts a
 * little later, further each time, until it finds a later one. */
static double breakaway(const fr_ctx *C, dfo_state *s, double ta, int skip, int *dir)
{
    const double C0 = C->L.F_ext - C->M->p.k * s->X;
    const int known = !isnan(s->stick_tb) && s->stick_C == C0 && s->stick_Fb == C->L.Fb;
    if (!known || (skip && s->stick_tb <= ta)) {
        s->stick_C = C0;
        s->stick_Fb = C->L.Fb;
        const dfo_harmonic P = dfo_model_excitation(C->M);
        double tb = dfo_next_breakaway(&P, &C->L, C0, ta, &s->stick_dir);
        if (skip) {
            const double rate = C->b + fabs(C->M->p.omega);
            double d = 4.0 * DBL_EPSILON * fmax(fabs(ta), rate > 0.0 ? 1.0 / rate : 1.0);
            for (int i = 0; i < 200 && tb <= ta + d && isfinite(tb); i++, d *= 2.0)
                tb = dfo_next_breakaway(&P, &C->L, C0, ta + d, &s->stick_dir);
        }
        s->stick_tb = tb;
    }
    *dir = s->stick_dir;
    return (s->stick_tb > ta) ? s->stick_tb : ta;
}

static double static_force(const fr_ctx *C, double t, double X)
{
    return dfo_static_force(C->M->p.k, &C->L, dfo_excitation(C->M, t), X);
}

/* The phases from s to t_target with the inputs held (the loop below the polynomial inputs' helpers). */
static dfo_status advance(fr_ctx *C, dfo_state *s, double t_target);

/* The end of a call: A and F at s->t from the loads L there and the static force S. */
static dfo_status end_state(const dfo_model *M, dfo_state *s, const dfo_loads *L, double S)
{
    if (s->mode == 0) {
        s->V = 0.0;
        s->A = 0.0;
        s->F = dfo_stick_force(L, S);
    } else {
        s->F = -s->mode * L->muk_N;
        s->A = (S - M->p.c * s->V + s->F) / M->p.m;
    }
    if (!(fabs(s->X) <= DBL_MAX && fabs(s->V) <= DBL_MAX && fabs(s->A) <= DBL_MAX)) return DFO_ERR_NONFINITE;
    return DFO_OK;
}

dfo_status dfo_exact_free_advance(const dfo_model *M, const dfo_inputs *u, dfo_state *s, double t_target,
                                  dfo_switch_fn on_switch, void *switch_ctx)
{
    fr_ctx C;
    ctx_init(&C, M, u);
    C.on_switch = on_switch;
    C.switch_ctx = switch_ctx;
    dfo_status st = advance(&C, s, t_target);
    s->steps += C.events;
    s->n = dfo_exact_grid_index(M, s);
    s->hA = 0.0;
    if (st != DFO_OK) return st;
    return end_state(M, s, &C.L, static_force(&C, s->t, s->X));
}

/* ---- polynomial inputs (dfo_exact_free_advance_poly) ---------------------------------------------- */
/* A slide is the closed form above plus the response to the force's ramp and curvature (eval). Its
 * stop: e^{b tau} s v still has the derivative e^{b tau} s q, now with q = A cos(theta) + f0 + f1 tau +
 * f2 tau^2 / 2, whose zeros are no longer known in closed form: they are found by stepping only as far
 * as |q''| <= A omega^2 + |f2| proves q of one sign (converging on the zero from its side like Newton's
 * method), and between two of them s v has at most one zero, bracketed and polished as above. A stick
 * phase ends where |P(t) + F_ext(t)| reaches max(mu_s, mu_k) N(t), found the same way. */

#define POLY_RES (4.0 * DBL_EPSILON) /* relative resolution of the searches' steps */

/* Largest d with g0 + g1 d - B d^2 / 2 >= 0 (g0 >= 0): how far a function with these value and slope
 * and |second derivative| <= B provably stays positive (as exact.c's). */
static double safe_step(double g0, double g1, double B)
{
    if (!(B > 0.0)) return (g1 >= 0.0) ? INFINITY : g0 / -g1;
    const double r = sqrt(g1 * g1 + 2.0 * B * g0);
    return (g1 >= 0.0) ? (g1 + r) / B : 2.0 * g0 / (r - g1);
}

/* q = A cos(theta) + f0 + f1 tau + f2 tau^2 / 2 at tau and its derivatives */
static void q_at(const fr_ctx *C, const fr_phase *P, double tau, double *q, double *q1, double *q2)
{
    double cth = 1.0, sth = 0.0;
    if (C->A > 0.0) {
        double sw, cw;
        dfo_sincos(C->w * tau, &sw, &cw);
        cth = P->c0 * cw - P->s0 * sw;
        sth = P->s0 * cw + P->c0 * sw;
    }
    *q = C->A * cth + P->f0 + tau * (P->f1 + 0.5 * tau * P->f2);
    *q1 = -C->A * C->w * sth + P->f1 + tau * P->f2;
    *q2 = -C->A * C->w * C->w * cth + P->f2;
}

/* The first tau > tau0 at which sg q (> 0 just after tau0) reaches 0, or U when it stays positive up to U. */
static double q_zero(const fr_ctx *C, const fr_phase *P, double tau0, double U, int sg)
{
    const double B = (1.0 + 1e-9) * (C->A * C->w * C->w + fabs(P->f2));
    double tau = tau0;
    for (int first = 1;; first = 0) {
        double q, q1, q2;
        q_at(C, P, tau, &q, &q1, &q2);
        const double g = sg * q, g1 = sg * q1;
        const double tol = POLY_RES * (C->A + fabs(P->f0) + fabs(tau * P->f1) + fabs(0.5 * tau * tau * P->f2));
        if (!first && g <= tol) return tau;
        const double res = POLY_RES * (fabs(P->ta) + tau) + DBL_MIN;
        double d = safe_step(fmax(g, 0.0), g1, B);
        if (!(d > res)) {
            if (!first) return tau; /* on the zero, to the resolution of t */
            d = res;
        }
        if (!(tau + d < U)) return U;
        tau += d;
    }
}

/* The sign of s q just after tau (from q, or its first nonzero derivative there). */
static int q_sign_after(const fr_ctx *C, const fr_phase *P, double tau)
{
    double q, q1, q2;
    q_at(C, P, tau, &q, &q1, &q2);
    const int s = P->s;
    const double tol = POLY_RES * (C->A + fabs(P->f0) + fabs(tau * P->f1) + fabs(0.5 * tau * tau * P->f2));
    if (fabs(q) > tol) return s * dfo_sign(q);
    return (q1 != 0.0) ? s * dfo_sign(q1) : s * dfo_sign(q2);
}

/* find_stop with polynomial inputs (the same results: SEARCH_STOP, SEARCH_NONE, SEARCH_NULL). */
static int find_stop_poly(const fr_ctx *C, const fr_phase *P, double U, fr_val *out)
{
    const int s = P->s;
    fr_val lo;
    eval0(C, P, &lo);
    int sg = q_sign_after(C, P, 0.0); /* the sign of s q on the current interval */
    if (!(s * P->va > 0.0)) {
        if (s * P->va < 0.0 || sg <= 0) { /* from rest: the slide starts only if e^{b tau} s v grows */
            *out = lo;
            out->v = 0.0;
            return SEARCH_NULL;
        }
    } else if (s * P->va <= ROUND * lo.vmag && sg > 0) {
        double q, q1, q2;
        q_at(C, P, 0.0, &q, &q1, &q2);
        if (fabs(q) <= ROUND * (C->A + fabs(P->f0))) { /* a touch at the start: s v at its minimum */
            *out = lo;
            return SEARCH_STOP;
        }
    }
    double tau = 0.0;
    for (;;) {
        const double z = q_zero(C, P, tau, U, s * sg);
        const int end = !(z < U);
        fr_val hi;
        eval(C, P, end ? U : z, &hi);
        if (!isfinite(hi.x) || !isfinite(hi.v)) {
            *out = hi;
            return SEARCH_NONE;
        }
        const double g_hi = s * hi.v;
        if (sg <= 0) {
            if (g_hi <= 0.0) {
                if (!(s * lo.v > 0.0)) {
                    *out = lo;
                    return SEARCH_STOP;
                }
                polish(C, P, &lo, &hi, out);
                return SEARCH_STOP;
            }
            if (!end && g_hi <= ROUND * hi.vmag) {
                *out = hi;
                return SEARCH_STOP;
            }
        }
        if (end) {
            *out = hi;
            return (g_hi > 0.0) ? SEARCH_NONE : SEARCH_STOP;
        }
        lo = hi;
        tau = z;
        sg = -sg;
    }
}

/* The loads at t (polynomial inputs), and the rates of F_ext and of the limit F_b in *dF, *dFb. */
static void poly_loads(const fr_ctx *C, double t, dfo_loads *L, double *dF, double *dFb)
{
    const double q = t - C->q_t0;
    const double F = C->qF[0] + q * (C->qF[1] + 0.5 * q * C->qF[2]);
    const double N = C->qN[0] + q * (C->qN[1] + 0.5 * q * C->qN[2]);
    dfo_loads_set(L, F, fmax(N, 0.0), C->M->mu_k, C->M->mu_b);
    if (dF) *dF = C->qF[1] + q * C->qF[2];
    if (dFb) *dFb = C->M->mu_b * (C->qN[1] + q * C->qN[2]);
}

/* The first time in [ta, tend) at which the stick phase breaks away (|S| > F_b, or within rounding of
 * it and not receding; S = P(t) + F_ext(t): no spring), its side in *dir; tend when none. */
static double poly_breakaway_from(const fr_ctx *C, double ta, double tend, int *dir)
{
    const dfo_model *M = C->M;
    const double w = M->p.omega;
    const double B = (1.0 + 1e-9) * (M->P_amp * w * w + fabs(C->qF[2]) + M->mu_b * fabs(C->qN[2]));
    double t = ta;
    for (;;) {
        dfo_loads L;
        double dF, dFb;
        poly_loads(C, t, &L, &dF, &dFb);
        const double S = dfo_excitation(M, t) + L.F_ext, S1 = dfo_excitation_rate(M, t) + dF;
        const double gp = L.Fb - S, gm = L.Fb + S, gp1 = dFb - S1, gm1 = dFb + S1;
        const double tol = POLY_RES * (M->P_amp + fabs(L.F_ext) + L.Fb);
        if (gp < 0.0 || gm < 0.0) {
            *dir = (gp < 0.0) ? 1 : -1;
            return t;
        }
        if ((gp <= tol && gp1 <= 0.0) || (gm <= tol && gm1 <= 0.0)) {
            *dir = (gp <= gm) ? 1 : -1;
            return t;
        }
        const double d = fmin(safe_step(gp, gp1, B), safe_step(gm, gm1, B));
        if (!(t + d < tend)) return tend;
        if (!(t + d > t)) {
            *dir = (gp <= gm) ? 1 : -1;
            return t;
        }
        t += d;
    }
}

/* The next breakaway from ta; with skip, one at ta itself (a slide just tried did not start) is passed over. */
static double poly_breakaway(const fr_ctx *C, double ta, double tend, int skip, int *dir)
{
    double b = poly_breakaway_from(C, ta, tend, dir);
    if (skip && !(b > ta)) {
        const double rate = C->b + fabs(C->M->p.omega);
        double d = 4.0 * DBL_EPSILON * fmax(fabs(ta), rate > 0.0 ? 1.0 / rate : 1.0);
        for (int i = 0; i < 200; i++, d *= 2.0) {
            if (!(ta + d < tend)) return tend;
            b = poly_breakaway_from(C, ta + d, tend, dir);
            if (b > ta + d) break;
        }
    }
    return b;
}

/* The friction work mu_k int N |v| dt of the slip phase P over tau in [t0, t1] with a varying normal
 * force: Gauss-Legendre quadrature (8 nodes) on pieces of at most an eighth of the excitation period and
 * of the damping time 1 / b (of s v N, smooth there: the error is below rounding, as for a polynomial of
 * degree 15). */
static double poly_work(const fr_ctx *C, const fr_phase *P, double t0, double t1)
{
    static const double X[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363};
    static const double Wg[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763};
    if (!(t1 > t0)) return 0.0;
    double len = INFINITY;
    if (C->w > 0.0) len = 0.25 * DFO_PI / C->w;
    if (C->b > 0.0 && 0.125 / C->b < len) len = 0.125 / C->b;
    const double span = t1 - t0;
    double n = isfinite(len) ? ceil(span / len) : 1.0;
    if (n < 1.0) n = 1.0;
    if (n > 1e6) n = 1e6;
    const double h = span / n;
    double sum = 0.0;
    for (double i = 0.0; i < n; i += 1.0) {
        const double mid = t0 + (i + 0.5) * h, r = 0.5 * h;
        double part = 0.0;
        for (int j = 0; j < 4; j++)
            for (int side = -1; side <= 1; side += 2) {
                const double tau = mid + side * r * X[j];
                fr_val v;
                eval(C, P, tau, &v);
                part += Wg[j] * fmax(P->n0 + tau * (P->n1 + 0.5 * tau * P->n2), 0.0) * fabs(v.v);
            }
        sum += part * r;
    }
    return C->M->mu_k * sum;
}

/* poly_work as a dfo_phase_work_fn */
static double phase_work(const void *ctx, const void *phase, double t0, double t1)
{
    return poly_work((const fr_ctx *)ctx, (const fr_phase *)phase, t0, t1);
}

/* The bookkeeping of a phase (as exact.c's after_phase; poly: with polynomial inputs). */
static DFO_EXACT_INLINE void after_phase(const fr_ctx *C, int poly, dfo_state *s, const fr_phase *P, double ta,
                                         double tb, double xa, double xb, int mode_during, int mode_after, int event)
{
    if (poly) {
        const double n[3] = {P ? P->n0 : 0.0, P ? P->n1 : 0.0, P ? P->n2 : 0.0};
        dfo_exact_after_phase_poly(C->M, C->on_switch, C->switch_ctx, s, phase_x, phase_work, C, P, P ? n : NULL, ta,
                                   tb, xa, xb, mode_during, mode_after, event);
    } else {
        dfo_exact_after_phase(C->M, C->L.muk_N, C->on_switch, C->switch_ctx, s, phase_x, C, P, ta, tb, xa, xb,
                              mode_during, mode_after, event);
    }
}

/* The phases from s to t_target, the inputs held (poly 0) or varying as polynomials (poly 1) over one piece
 * (C->qN > 0 inside it, or all 0): one loop, the two kinds of inputs differing only in the breakaway,
 * the stop's search, the loads at a stop and the phases' bookkeeping. */
static DFO_EXACT_INLINE dfo_status advance_loop(fr_ctx *C, dfo_state *s, double t_target, const int poly)
{
    int skip = 0, stall = 0;
    double t_last = s->t;
    const int sens = C->M->p.sensitivity; /* propagate s->J (exact.h) */
    const int fric = poly ? (C->M->mu_b > 0.0 && (C->qN[0] != 0.0 || C->qN[1] != 0.0 || C->qN[2] != 0.0))
                          : C->L.Fb > 0.0;
    while (s->t < t_target) {
        if (C->events >= DFO_EXACT_MAX_EVENTS) return DFO_ERR_EVENTS;
        if (s->t == t_last) {
            if (++stall > MAX_STALL) return DFO_ERR_NO_PROGRESS;
        } else {
            stall = 0;
            t_last = s->t;
        }
        const double ta = s->t, xa = s->X;
        if (s->mode == 0 && !fric) {
            /* no friction: a block at rest never sticks; it moves along the force (or its rate) */
            double S, dS, d2S;
            if (poly) {
                dfo_loads L;
                double dF;
                poly_loads(C, ta, &L, &dF, NULL);
                S = dfo_excitation(C->M, ta) + L.F_ext;
                dS = dfo_excitation_rate(C->M, ta) + dF;
                d2S = -C->M->p.omega * C->M->p.omega * dfo_excitation(C->M, ta) + C->qF[2];
            } else {
                S = static_force(C, ta, s->X);
                dS = dfo_excitation_rate(C->M, ta);
                d2S = -C->M->p.omega * C->M->p.omega * dfo_excitation(C->M, ta);
            }
            const int dir = dfo_free_start_dir(S, dS, d2S);
            s->mode = dir;
            C->events++;
            after_phase(C, poly, s, NULL, ta, ta, xa, xa, 0, dir, 1);
            continue;
        }
        if (s->mode == 0) {
            int dir = 0;
            /* (held: never NaN) */
            const double tb = poly ? poly_breakaway(C, ta, t_target, skip, &dir) : breakaway(C, s, ta, skip, &dir);
            skip = 0;
            /* stuck: x frozen, v held at 0; without a spring the breakaway time does not depend on x,
             * so the v row stays 0 across it */
            if (sens) dfo_sens_stick(s->J);
            if (!(tb < t_target)) {
                s->t = t_target;
                after_phase(C, poly, s, NULL, ta, t_target, xa, xa, 0, 0, 0);
                break;
            }
            s->t = tb;
            s->V = 0.0;
            s->mode = dir;
            C->events++;
            after_phase(C, poly, s, NULL, ta, tb, xa, xa, 0, dir, 1);
            continue;
        }
        /* a slip in direction sd from (ta, X, V) */
        const int sd = s->mode;
        fr_phase P;
        fr_val v;
        phase_init(C, &P, ta, s->X, s->V, sd);
        const int r = poly ? find_stop_poly(C, &P, t_target - ta, &v) : find_stop(C, &P, t_target - ta, &v);
        if (!isfinite(v.x) || !isfinite(v.v)) return DFO_ERR_NONFINITE;
        if (r == SEARCH_NONE) {
            if (sens) dfo_sens_slide(C->M, t_target - ta, s->J);
            s->t = t_target;
            s->X = v.x;
            s->V = v.v;
            after_phase(C, poly, s, &P, ta, t_target, xa, s->X, sd, sd, 0);
            break;
        }
        double ts = ta + v.tau;
        if (ts > t_target) ts = t_target;
        if (sens) dfo_sens_slide(C->M, ts - ta, s->J);
        s->t = ts;
        s->X = v.x;
        s->V = 0.0;
        /* the static force at a stop from the excitation phase there (known from the search), and the
         * loads there */
        const int known = r == SEARCH_STOP && ts < t_target && C->A > 0.0;
        dfo_loads Lp;
        const dfo_loads *L = &C->L;
        double Fs;
        if (poly) {
            poly_loads(C, ts, &Lp, NULL, NULL);
            Fs = (known ? C->M->P_amp * v.cth : dfo_excitation(C->M, ts)) + Lp.F_ext;
            L = &Lp;
        } else {
            Fs = known ? dfo_static_force(C->M->p.k, &C->L, C->M->P_amp * v.cth, s->X) : static_force(C, ts, s->X);
        }
        int next = dfo_rest_mode(L, Fs);
        if (!fric) {
            /* no friction: never stuck; at a zero force the velocity, falling through 0, reverses */
            if (next == 0 || (r == SEARCH_NULL && next == sd)) next = -sd;
        } else if (r == SEARCH_NULL && next != -sd) { /* the slide could not start: the block stays at */
            next = 0;                                 /* rest, and a breakaway right now is passed over */
            skip = 1;
        }
        if (next == 0) s->stick_tb = NAN; /* a new stick phase (polynomial inputs: NaN throughout) */
        if (sens) { /* the saltation at the stop (as exact.c) */
            if (next == 0 || r == SEARCH_NULL) dfo_sens_stick(s->J);
            else if (next == -sd && L->muk_N > 0.0)
                dfo_sens_reversal(s->J, (Fs + sd * L->muk_N) / (Fs - sd * L->muk_N));
        }
        s->mode = next;
        C->events++;
        after_phase(C, poly, s, &P, ta, ts, xa, s->X, sd, next, 1);
    }
    return DFO_OK;
}

static dfo_status advance(fr_ctx *C, dfo_state *s, double t_target) { return advance_loop(C, s, t_target, 0); }

static dfo_status advance_poly(fr_ctx *C, dfo_state *s, double t_target) { return advance_loop(C, s, t_target, 1); }

dfo_status dfo_exact_free_advance_poly(const dfo_model *M, const dfo_inputs *u, double q_t0, const double qF[3],
                                       const double qN[3], dfo_state *s, double t_target, dfo_switch_fn on_switch,
                                       void *switch_ctx)
{
    fr_ctx C;
    ctx_init(&C, M, u);
    C.on_switch = on_switch;
    C.switch_ctx = switch_ctx;
    C.poly = 1;
    C.q_t0 = q_t0;
    for (int i = 0; i < 3; i++) {
        C.qF[i] = qF[i];
        C.qN[i] = qN[i];
    }
    s->stick_tb = NAN; /* (the stick phase's cache is of held inputs) */
    dfo_status st = advance_poly(&C, s, t_target);
    s->steps += C.events;
    s->n = dfo_exact_grid_index(M, s);
    s->hA = 0.0;
    s->stick_tb = NAN;
    if (st != DFO_OK) return st;
    dfo_loads L;
    poly_loads(&C, s->t, &L, NULL, NULL);
    return end_state(M, s, &L, dfo_excitation(M, s->t) + L.F_ext);
}

dfo_status dfo_exact_free_advance_pieces(const dfo_model *M, const dfo_inputs *u, const dfo_input_poly *q, dfo_state *s,
                                         double t_target, dfo_switch_fn on_switch, void *switch_ctx)
{
    double n[3], z[2];
    const int nz = dfo_exact_normal_zeros(M, u, q, s->t, t_target, n, z);
    const double qF[3] = {dfo_external_force(M, u), q->F[0], q->F[1]};
    dfo_status st = DFO_OK;
    for (int i = 0; i <= nz && st == DFO_OK; i++) {
        const double a = (i == 0) ? s->t : q->t0 + z[i - 1], b = (i == nz) ? t_target : q->t0 + z[i];
        if (!(b > s->t)) continue;
        double qN[3];
        dfo_exact_piece_normal(n, 0.5 * (a + b) - q->t0, qN);
        st = dfo_exact_free_advance_poly(M, u, q->t0, qF, qN, s, b, on_switch, switch_ctx);
    }
    return st;
}

/* ---- a belt's turning points (exact_belt.c's free_belt) ------------------------------------------- */

#define MAX_TURNS DFO_EXACT_MAX_EVENTS /* turning points of x looked for in one slide (the work bound, exact.h) */

void dfo_exact_free_slide_extremes(const dfo_model *M, const dfo_inputs *u, const double *poly, double ta, double X,
                                   double V, int s, double t0, double t1, double te, double *lo, double *hi, double *Xe,
                                   double *Ve)
{
    fr_ctx C;
    ctx_init(&C, M, u);
    if (poly) {
        C.poly = 1;
        C.q_t0 = poly[0];
        for (int i = 0; i < 3; i++) {
            C.qF[i] = poly[1 + i];
            C.qN[i] = poly[4 + i];
        }
    }
    fr_phase P;
    phase_init(&C, &P, ta, X, V, s);
    fr_val a, b, e;
    eval(&C, &P, te - ta, &e);
    *Xe = e.x;
    *Ve = e.v;
    if (!(t1 >= t0)) return;
    eval(&C, &P, t0 - ta, &a);
    eval(&C, &P, t1 - ta, &b);
    *lo = fmin(a.x, b.x);
    *hi = fmax(a.x, b.x);
    double t = t0, x = a.x, v = a.v, acc = a.a, vm = a.vmag;
    for (long long n = 0; n < MAX_TURNS && t < t1; n++) {
        /* the same motion from t (its friction that of P), searched for the next zero of v */
        fr_phase Q;
        phase_init(&C, &Q, t, x, v, s);
        const int rest = !(fabs(v) > ROUND * vm); /* at a turning point: from rest */
        int dir = rest ? dfo_sign(acc) : dfo_sign(v);
        if (dir == 0) dir = 1;
        if (rest) Q.va = 0.0;
        fr_val z;
        int r = SEARCH_NULL;
        for (int k = 0; k < 2 && r == SEARCH_NULL; k++, dir = -dir) {
            Q.s = dir;
            r = poly ? find_stop_poly(&C, &Q, t1 - t, &z) : find_stop(&C, &Q, t1 - t, &z);
        }
        if (r != SEARCH_STOP || !(z.tau > 0.0)) return;
        t += z.tau;
        if (!(t < t1)) return;
        fr_val w;
        eval(&C, &P, t - ta, &w); /* x there by P's own closed form */
        *lo = fmin(*lo, w.x);
        *hi = fmax(*hi, w.x);
        x = w.x;
        v = 0.0;
        acc = w.a;
        vm = w.vmag;
    }
}
