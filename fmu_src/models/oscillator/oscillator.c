/* The dry-friction oscillator: parameters, forces. See oscillator.h. */
#include "dfo_fp.h" /* first: no fused multiply-add, whatever the flags */
#include "oscillator.h"
#include "ddouble.h"
#include "dmath.h"

#include "bossak.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

double dfo_shortest_period(const dfo_params *p)
{
    const double rate = fmax(fmax(sqrt(p->k / p->m), fabs(p->omega)), p->c / p->m);
    return rate > 0.0 ? 2.0 * DFO_PI / rate : INFINITY;
}

double dfo_step_size(const dfo_params *p)
{
    return p->h > 0.0 ? p->h : dfo_step_rule(0.0, dfo_shortest_period(p));
}

const char *dfo_check_params(const dfo_params *p)
{
    if (p->t_obs_stop < p->t_obs_start)
        return "The observation window is empty: t_obs_stop must be >= t_obs_start.";
    if (p->friction_law == DFO_LAW_STRIBECK && p->delta < 1.0)
        return "friction_law = stribeck supports delta >= 1 only here (below 1 the friction's slope is infinite at "
               "zero relative speed, which the located scheme's step does not resolve): choose delta >= 1.";
    if (p->friction_law == DFO_LAW_STRIBECK && p->scheme != DFO_SCHEME_LOCATED)
        return p->scheme == DFO_SCHEME_EXACT
                   ? "scheme exact supports friction_law = coulomb only (its closed form needs a constant kinetic "
                     "friction): choose scheme located for friction_law = stribeck."
                   : "friction_law = stribeck needs scheme located (the speed-dependent friction is solved inside "
                     "its steps): choose scheme located, or friction_law = coulomb.";
    return NULL;
}

void dfo_model_init(dfo_model *M, const dfo_params *p)
{
    M->p = *p;
    M->p.h = dfo_step_size(p);
    M->gamma = dfo_bossak_gamma(p->alpha);
    M->beta = dfo_bossak_beta(p->alpha);
    M->mu_k = p->chi * p->mu_s;
    M->mu_b = fmax(p->mu_s, M->mu_k);
    M->P_amp = fabs(p->P0);
    M->P_phase = p->phi + (p->P0 < 0.0 ? DFO_PI : 0.0);
    M->rate_max = sqrt(p->k / p->m) + p->c / p->m + fabs(p->omega);
    M->rot_c = dfo_cos(p->omega * M->p.h);
    M->rot_s = dfo_sin(p->omega * M->p.h);
    M->fast = p->fastPaths != 0;
    M->damped = !M->fast || p->c != 0.0;
    M->update = !M->fast || M->mu_k != M->mu_b;
    M->stribeck = p->friction_law == DFO_LAW_STRIBECK;
    M->law.law = M->stribeck ? DFO_LAW_STRIBECK : DFO_LAW_COULOMB;
    M->law.mu_s = p->mu_s;
    M->law.mu_k = M->mu_k;
    M->law.v_s = p->v_s;
    M->law.delta = p->delta;
}

double dfo_excitation(const dfo_model *M, double t)
{
    return M->p.P0 * dfo_cos(M->p.omega * t + M->p.phi);
}

double dfo_excitation_exact(const dfo_model *M, double t)
{
    const dfo_dd tt = {t, 0.0};
    const dfo_dd theta = dfo_dd_theta(M->p.omega, dfo_dd_phase0(M->p.phi, M->p.P0 < 0.0), tt);
    double c, sn;
    dfo_sincos_dd(theta.hi, theta.lo, &sn, &c);
    return M->P_amp * c;
}

double dfo_excitation_rate(const dfo_model *M, double t)
{
    return -M->p.P0 * M->p.omega * dfo_sin(M->p.omega * t + M->p.phi);
}

double dfo_normal_force(const dfo_model *M, const dfo_inputs *u)
{
    if (!u->N_ext_set) return M->p.N;
    return fmax(M->p.N + u->N_ext, 0.0);
}

double dfo_external_force(const dfo_model *M, const dfo_inputs *u)
{
    (void)M;
    return u->F_ext_set ? u->F_ext : 0.0;
}

void dfo_loads_init(dfo_loads *L, const dfo_model *M, const dfo_inputs *in)
{
    dfo_loads_set(L, dfo_external_force(M, in), dfo_normal_force(M, in), M->mu_k, M->mu_b);
}

void dfo_inputs_at(const dfo_inputs *u, double t, dfo_inputs *out)
{
    *out = *u;
    if (!u->ramp) return;
    const double tau = t - u->t_d;
    out->F_ext = u->F_ext + (u->F_ext_d[0] + 0.5 * u->F_ext_d[1] * tau) * tau;
    out->N_ext = u->N_ext + (u->N_ext_d[0] + 0.5 * u->N_ext_d[1] * tau) * tau;
    out->F_ext_d[0] = out->F_ext_d[1] = out->N_ext_d[0] = out->N_ext_d[1] = 0.0;
    out->ramp = 0;
}

void dfo_loads_ramp(dfo_loads *L, const dfo_model *M, const dfo_inputs *u, double t)
{
    dfo_inputs w;
    dfo_inputs_at(u, t, &w);
    dfo_loads_init(L, M, &w);
}

void dfo_input_rates(const dfo_model *M, const dfo_inputs *u, double t, double *dF_ext, double *dN)
{
    *dF_ext = *dN = 0.0;
    if (!u->ramp) return;
    const double tau = t - u->t_d;
    if (u->F_ext_set) *dF_ext = u->F_ext_d[0] + u->F_ext_d[1] * tau;
    dfo_inputs w;
    dfo_inputs_at(u, t, &w);
    if (u->N_ext_set && M->p.N + w.N_ext > 0.0) *dN = u->N_ext_d[0] + u->N_ext_d[1] * tau;
}

int dfo_effects(const dfo_model *M, const dfo_inputs *u)
{
    int e = 0;
    if ((M->p.mu_s > 0.0 && M->p.N > 0.0 && M->mu_b > 0.0) || u->N_ext_set) e |= DFO_EFFECT_FRICTION;
    if ((e & DFO_EFFECT_FRICTION) && M->mu_k != M->mu_b) e |= DFO_EFFECT_COEFF_UPDATE;
    if (M->p.c != 0.0) e |= DFO_EFFECT_DAMPING;
    if (u->F_ext_set) e |= DFO_EFFECT_FORCE_INPUT;
    if (u->N_ext_set) e |= DFO_EFFECT_NORMAL_INPUT;
    if (M->p.observe) e |= DFO_EFFECT_OBSERVABLES;
    if (M->p.sensitivity && M->p.scheme == DFO_SCHEME_EXACT) e |= DFO_EFFECT_SENSITIVITY;
    if (dfo_belt_on(u)) e |= DFO_EFFECT_BELT;
    if (M->stribeck && (e & DFO_EFFECT_FRICTION)) e |= DFO_EFFECT_STRIBECK;
    return e;
}
