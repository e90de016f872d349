/* The friction rules every scheme of both models shares (method.md sections 1, 3, 4 and 9): the
 * loads held over a communication step, the static force at rest, the rest rule (stick or slide),
 * the force held while stuck, the consistent acceleration of a slide that starts from rest, and the
 * next breakaway of a stick phase in closed form. The oscillator's start-up and outputs (newmark.c),
 * its exact scheme (exact.c, exact_free.c), its engine model's breakaway (eng_one_dof.h) and the
 * chain (one block at a time) use these and nothing else to decide stick and slip.
 *
 * Model-free: plain numbers (a block's mass, stiffness, loads, excitation), no model struct. Plain
 * C, no FMI types. */
#ifndef DFO_FRICTION_H
#define DFO_FRICTION_H

#include "excitation.h"

#include <math.h>

/* What the inputs make of the forces; constant while the inputs are held. */
typedef struct {
    double F_ext;  /* external force (0 when the input was never set) */
    double N;      /* normal force max(N + N_ext, 0) */
    double muk_N;  /* kinetic friction magnitude mu_k N */
    double Fb;     /* breakaway limit max(mu_s, mu_k) N (>= muk_N) */
} dfo_loads;

/* The loads of a block with external force F_ext, normal force N (already max(N + N_ext, 0)),
 * kinetic coefficient mu_k and breakaway coefficient mu_b = max(mu_s, mu_k). */
static inline void dfo_loads_set(dfo_loads *L, double F_ext, double N, double mu_k, double mu_b)
{
    L->F_ext = F_ext;
    L->N = N;
    L->muk_N = mu_k * N;
    L->Fb = mu_b * N;
}

static inline int dfo_sign(double x) { return (x > 0.0) - (x < 0.0); }
/* Without friction a block at rest never sticks: the direction it moves off in, from the static force
 * S, or where S is 0 its rate dS, or where that is 0 too its second derivative d2S (+1 when all vanish). */
static inline int dfo_free_start_dir(double S, double dS, double d2S)
{
    return (S != 0.0) ? dfo_sign(S) : (dS != 0.0) ? dfo_sign(dS) : (d2S < 0.0 ? -1 : 1);
}

/* The static force: the net applied force on a block of stiffness k at rest at X under the
 * excitation P, F_static = P + F_ext - k X (the force the friction must hold to keep it there). */
static inline double dfo_static_force(double k, const dfo_loads *L, double P, double X)
{
    return P + L->F_ext - k * X;
}

/* The rest rule: a block at rest sticks (0) if |F_static| <= Fb, else it slides in the direction of
 * F_static. */
static inline int dfo_rest_mode(const dfo_loads *L, double F_static)
{
    return (fabs(F_static) <= L->Fb) ? 0 : dfo_sign(F_static);
}

/* The friction force that holds a stuck block: -F_static, clamped to the limit. */
static inline double dfo_stick_force(const dfo_loads *L, double F_static)
{
    return -fmax(-L->Fb, fmin(L->Fb, F_static));
}

/* The consistent acceleration of a slide of a block of mass m that starts from rest in direction
 * dir (+1 or -1) with static force F_static. The net force is at least the breakaway limit (it may
 * sit on it by rounding at a breakaway), so the acceleration is never against dir. */
static inline double dfo_breakaway_accel(double m, const dfo_loads *L, int dir, double F_static)
{
    return dir * fmax(fmax(dir * F_static, L->Fb) - L->muk_N, 0.0) / m;
}

/* While stuck at X under the excitation P the static force is F_static(t) = P->amp cos(P->omega t
 * + P->phase) + C0, with the constant part C0 = F_ext - k X (a chain's block: F_ext - (K x)_i).
 * The first time >= ta at which |F_static| exceeds Fb, with the side crossed in *dir, or INFINITY.
 * Closed form: a force that crosses the limit and comes back between two samples is not missed. */
double dfo_next_breakaway(const dfo_harmonic *P, const dfo_loads *L, double C0, double ta, int *dir);

/* The friction law of a sliding block: its coefficient at the speed u >= 0 relative to the surface.
 *   DFO_LAW_COULOMB  (1): mu(u) = mu_k
 *   DFO_LAW_STRIBECK (2): mu(u) = mu_k + (mu_s - mu_k) exp(-(u / v_s)^delta),  v_s > 0, delta > 0
 * (the enumeration friction_law of both models' descriptions). mu(0) = mu_s for Stribeck. */
enum { DFO_LAW_COULOMB = 1, DFO_LAW_STRIBECK = 2 };
typedef struct {
    int law;
    double mu_s, mu_k, v_s, delta;
} dfo_friction_law;
/* mu(u), and its derivative d mu / du (u > 0; at u = 0 the right derivative, -INFINITY for delta < 1). */
double dfo_friction_mu(const dfo_friction_law *F, double u);
double dfo_friction_dmu(const dfo_friction_law *F, double u);

/* A sliding step's relative speed at its end with the law F (stribeck): the root u > 0 of
 * mh u = q - N mu(u) (mh the step's effective mass, im = 1 / mh, q the driving force along the
 * slide), by Newton's iteration from the root with the smaller coefficient min(mu_s, mu_k)
 * (monotone: mu is convex for mu_s > mu_k, concave otherwise, while mh > N |mu'|). Where no root
 * exists (q <= N mu(0)) it returns (q - N mu(0)) im <= 0, continuous in the step length, whose
 * sign tells a stop. The arithmetic of the oscillator's located step (the chain's block of one). */
double dfo_stribeck_speed(const dfo_friction_law *F, double N, double q, double mh, double im);

#endif
