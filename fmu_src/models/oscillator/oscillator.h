/* The dry-friction oscillator (method.md sections 1 and 7): parameters, the forces, the derived constants of the Bossak-Newmark scheme and the "effects" a run pays for.
 *
 *     m x'' + c x' + k x = P0 cos(omega t + phi) + F_ext + F,
 *     Coulomb friction F with mu_s (static), mu_k = chi mu_s (kinetic), normal force max(N + N_ext, 0),
 *     breakaway limit max(mu_s, mu_k) N.
 *
 * Plain C, no FMI types. */
#ifndef DFO_OSCILLATOR_H
#define DFO_OSCILLATOR_H

#include "bossak.h"
#include "excitation.h"
#include "friction.h"

#include <float.h>
#include <math.h>

/* Everything a user sets before a run. Each field is named as its variable in modelDescription.xml
 * (Real: double; Integer, Enumeration, Boolean: int): the generated variable table reaches it by
 * offsetof, and the valid ranges are the variables' min/max there. A new scalar parameter is one
 * line of XML plus one field here. */
typedef struct {
    double m, k, c, P0, omega, phi, N, mu_s, chi, x0, v0;
    double h, alpha;                 /* internal step (s; 0: derived, see dfo_step_size), Bossak parameter */
    double t_obs_start, t_obs_stop;  /* observation window (s) */
    int scheme;                      /* dfo_scheme */
    int frictionUpdates;             /* coefficient updates per step (scheme paper) */
    int observe;                     /* compute the in-FMU observables */
    int fastPaths;                   /* skip the physics a run does not need (same numbers) */
    int sensitivity;                 /* propagate the Jacobian of the state (exact scheme only) */
    int friction_law;                /* DFO_LAW_COULOMB or DFO_LAW_STRIBECK (friction.h) */
    double v_s, delta;               /* Stribeck velocity (m/s) and exponent */
} dfo_params;

/* Co-simulation inputs, held constant over a communication step. An input never set is never read:
 * each input X has a flag X_set, raised when a host sets it (or a nonzero derivative of it).
 * Input derivatives (FMI 2.0 SetRealInputDerivatives), for the next step only: X_d[0], X_d[1] are
 * the first and second time derivatives of X at t_d, the input over the step being its Taylor
 * polynomial X + X_d[0] (t - t_d) + X_d[1] (t - t_d)^2 / 2. ramp: one of them is nonzero; without
 * it no derivative is read (and every number is that of held inputs). */
typedef struct {
    double F_ext, N_ext;
    double F_ext_d[2], N_ext_d[2];
    double t_d;
    int F_ext_set, N_ext_set;
    int ramp;
    double v_belt;  /* velocity of the rough surface (held; no derivatives) */
    int v_belt_set;
} dfo_inputs;

/* Bits of the "effects" calculated parameter: what a run simulates. */
enum {
    DFO_EFFECT_FRICTION = 1,      /* friction LCP solved (mu N > 0 or N_ext connected) */
    DFO_EFFECT_COEFF_UPDATE = 2,  /* static/kinetic coefficient update (chi != 1) */
    DFO_EFFECT_DAMPING = 4,       /* viscous damping (c > 0) */
    DFO_EFFECT_FORCE_INPUT = 8,   /* input F_ext read */
    DFO_EFFECT_NORMAL_INPUT = 16, /* input N_ext read */
    DFO_EFFECT_OBSERVABLES = 32,  /* in-FMU observables computed */
    DFO_EFFECT_SENSITIVITY = 64,  /* Jacobian of the state propagated (exact scheme) */
    DFO_EFFECT_BELT = 128,        /* input v_belt read: friction on the velocity relative to the surface */
    DFO_EFFECT_STRIBECK = 256     /* speed-dependent friction coefficient (friction_law = stribeck) */
};

/* Parameters plus the constants derived from them once, at initialisation. */
typedef struct {
    dfo_params p;            /* the parameters, with p.h the step used (dfo_step_size) */
    double gamma, beta;      /* Newmark coefficients: gamma = 1/2 - alpha, beta = (1 - alpha)^2 / 4 */
    double mu_k, mu_b;       /* kinetic and breakaway coefficients, mu_b = max(mu_s, mu_k) */
    double P_amp, P_phase;   /* P0 cos(w t + phi) written as P_amp cos(w t + P_phase), P_amp >= 0 */
    double rate_max;         /* fastest rate of the model, sqrt(k/m) + c/m + |omega| (1/s) */
    double rot_c, rot_s;     /* cos and sin of omega h: the excitation's phase advance per grid step */
    int fast;                /* fast paths enabled */
    int damped;              /* c != 0 (or fast paths off) */
    int update;              /* mu_k != mu_b (or fast paths off) */
    int stribeck;            /* friction_law = stribeck */
    dfo_friction_law law;    /* the sliding law (friction.h), mu_k = chi mu_s */
} dfo_model;

/* Checks that involve several parameters; NULL when consistent, else a sentence. */
const char *dfo_check_params(const dfo_params *p);

/* The default step: h = 0 means "derived from the dynamics" (bossak.h's dfo_step_rule): the
 * shortest time scale of the model is the shortest of the natural period 2 pi sqrt(m/k), the
 * excitation period 2 pi/|omega| and the damping time 2 pi m/c (the rate c/m taken like an angular
 * frequency). */
/* The shortest period (s) of the model as above; +inf when it has none. */
double dfo_shortest_period(const dfo_params *p);
/* The internal step a run uses: p->h when > 0, else derived (always a normal number > 0). */
double dfo_step_size(const dfo_params *p);
/* Derive the constants (M->p.h is the step used). The parameters must have passed the checks above. */
void dfo_model_init(dfo_model *M, const dfo_params *p);

/* Excitation P0 cos(omega t + phi) and its time derivative. */
double dfo_excitation(const dfo_model *M, double t);
double dfo_excitation_rate(const dfo_model *M, double t);
/* The excitation as the exact scheme evaluates it: phi reduced mod 2 pi exactly and omega t + phi
 * carried as a double-double (ddouble.h), so exact to rounding for any t and phi (the outputs a and
 * F_friction of the exact scheme use it). */
double dfo_excitation_exact(const dfo_model *M, double t);

/* Normal force used: max(N + N_ext, 0), N_ext read only when it has been set. */
double dfo_normal_force(const dfo_model *M, const dfo_inputs *u);
/* The belt's velocity: v_belt when it has been set, else 0 (a belt never set is never read). */
static inline double dfo_belt_speed(const dfo_inputs *u) { return u->v_belt_set ? u->v_belt : 0.0; }
/* The belt acts: v_belt set (then every scheme works on the relative velocity). */
static inline int dfo_belt_on(const dfo_inputs *u) { return u->v_belt_set; }

/* External force: F_ext when it has been set, else 0. */
double dfo_external_force(const dfo_model *M, const dfo_inputs *u);

/* The excitation as the friction rules read it (friction.h: its P_amp, P_phase as amp, phase). */
static inline dfo_harmonic dfo_model_excitation(const dfo_model *M)
{
    dfo_harmonic H;
    dfo_harmonic_init(&H, M->p.P0, M->p.omega, M->p.phi);
    return H;
}

/* The loads of the friction rules (friction.h) under these inputs (their values, derivatives not read). */
void dfo_loads_init(dfo_loads *L, const dfo_model *M, const dfo_inputs *in);

/* The inputs at time t: with a ramp its polynomials' values there (out has no ramp), else *u. */
void dfo_inputs_at(const dfo_inputs *u, double t, dfo_inputs *out);
/* The loads at time t (dfo_loads_init of dfo_inputs_at; without a ramp dfo_loads_init itself). */
void dfo_loads_ramp(dfo_loads *L, const dfo_model *M, const dfo_inputs *u, double t);
static inline void dfo_loads_at(dfo_loads *L, const dfo_model *M, const dfo_inputs *u, double t)
{
    if (u->ramp) dfo_loads_ramp(L, M, u, t);
    else dfo_loads_init(L, M, u);
}
/* The time derivatives at t of the external force and of the normal force used (0 where that is
 * max(N + N_ext, 0) = 0, and without a ramp). */
void dfo_input_rates(const dfo_model *M, const dfo_inputs *u, double t, double *dF_ext, double *dN);

/* The effects bitmask for these parameters and inputs. */
int dfo_effects(const dfo_model *M, const dfo_inputs *u);

#endif
