/* The chain's private header: the model struct and the small functions every part of the chain
 * reads. chain.h is the public API; the implementation is split by concern:
 *
 *   chain_setup.c     parameters, chain_create (the derived constants, the operators' arrays, the
 *                     engine), shortest period, state storage, energy, status texts
 *   chain_engine_ops.h  the chain's operators for the friction engine (fmu_src/engine): M, K, C,
 *                     the tridiagonal M_hat, the box LCP with belts and Stribeck, the breakaway
 *   chain_engine.c    the engine's schemes specialised by those operators, and chain.h's stepping
 *                     API over them (start, advance, input and belt changes, accelerations)
 *   chain_forces.c    the loads of the inputs, input ramps (the instance core's outputs)
 *
 * Every array is through the caller's allocation callbacks; no global state. Plain C, no FMI types. */
#ifndef DFO_CHAIN_INTERNAL_H
#define DFO_CHAIN_INTERNAL_H

#include "chain.h"
#include "chain_engine_ops.h"

#include "bossak.h"
#include "dmath.h"
#include "excitation.h"
#include "friction.h"

#include <float.h>
#include <math.h>
#include <stddef.h>

#define SNAP_REL_H 1e-7         /* a requested time this close (in h) to a grid point is that point */

struct chain_model {
    chain_alloc al;             /* the caller's allocation callbacks (every array below) */
    size_t n;                   /* number of blocks */
    double k_end, c_end;        /* spring and damper from the last block to the right wall */
    double omega, h, alpha;     /* excitation frequency, internal step, Bossak parameter */
    double rate_max;            /* sqrt(Gershgorin bound of M^-1 K) + that of M^-1 C + |omega| (1/s) */
    double T_min;               /* the shortest period of the dynamics (chain_shortest_period) */
    double phi0;                /* the phase every block shares (then Pc = P0, Ps = 0: each block's excitation
                                 * is P0 cos(omega t + phi0), evaluated as the oscillator's), else 0 */
    int scheme;                 /* dfo_scheme: DFO_SCHEME_PAPER, _CONSISTENT or _LOCATED */
    int energy;                 /* keep the energy accounts (chain_params.account_energy) */
    int damped;                 /* some damper is not 0 (else C is not applied) */
    int stribeck;               /* friction_law = stribeck: sliding friction N mu(|v_rel|) (law) */
    /* per block (length n): parameters and constants */
    double *m;                  /* masses */
    double *Pc, *Ps;            /* excitation P_i = Pc cos(omega t + phi0) - Ps sin(omega t + phi0) */
    double *P0, *phi;           /* the excitation's amplitude and phase as set */
    double *N;                  /* normal forces (without N_ext) */
    double *mu_s, *mu_k, *mu_b; /* static, kinetic chi mu_s and breakaway max(mu_s, mu_k) coefficients */
    double *x0, *v0;            /* initial state */
    double *Kd, *Ko, *Cd, *Co;  /* K and C: diagonal, and Ko[i], Co[i] coupling i and i + 1 (0 on the last) */
    double *ks, *cs;            /* k_site, c_site: the parts of Kd[i], Cd[i] tying block i to the ground */
    dfo_friction_law *law;      /* per block (stribeck only, else NULL) */
    /* per block: the loads of the inputs last given to chain_loads_init (the outputs' derivatives) */
    double *u;                  /* external force F_ext (0 when never set) */
    double *mukN, *Fb;          /* kinetic friction mu_k N and breakaway limit mu_b N, N = max(N + N_ext, 0) */
    double *Nn;                 /* that normal force N */
    /* the engine: the contact rows (w_i = e_i), the operators' data, the engine object */
    eng_row *rows;
    size_t *ridx;
    double *rw;
    chain_eng_ops ops;
    chain_eng_ops view;         /* a span's view of the chain (its arrays its own) */
    int *iblk;                  /* the operators' int arrays */
    eng_sparse sparse;          /* its sparse-structure operators (engine.h) */
    eng *E;
};

static inline int chain_sgn(double x) { return (x > 0.0) - (x < 0.0); }

/* cos and sin of omega t + phi0: from the state's grid cache when t is its grid point, else
 * evaluated */
static inline void chain_phase_of(const chain_model *M, const chain_state *s, double t, double *cw, double *sw)
{
    if (s->exc_n >= 0 && t == s->t0 + (double)s->exc_n * M->h) {
        *cw = dfo_clamp1(s->exc_c);
        *sw = dfo_clamp1(s->exc_s);
        return;
    }
    *cw = dfo_cos(M->omega * t + M->phi0);
    *sw = dfo_sin(M->omega * t + M->phi0);
}

/* block i's excitation at the phase (cw, sw) */
static inline double chain_P_at(const chain_model *M, size_t i, double cw, double sw)
{
    return M->Pc[i] * cw - M->Ps[i] * sw;
}

/* (K x)_i and (C v)_i */
static inline double chain_Kx(const chain_model *M, const double *x, size_t i)
{
    double f = M->Kd[i] * x[i];
    if (i > 0) f += M->Ko[i - 1] * x[i - 1];
    if (i + 1 < M->n) f += M->Ko[i] * x[i + 1];
    return f;
}
static inline double chain_Cv(const chain_model *M, const double *v, size_t i)
{
    if (!M->damped) return 0.0;
    double f = M->Cd[i] * v[i];
    if (i > 0) f += M->Co[i - 1] * v[i - 1];
    if (i + 1 < M->n) f += M->Co[i] * v[i + 1];
    return f;
}

static inline int chain_has_friction(const chain_model *M, size_t i) { return M->Fb[i] > 0.0; }

/* Block i's speed relative to its belt vrel (NULL: the state's velocity, as while stepping in the
 * belt's frame) */
static inline double chain_rel_speed(const double *vrel, const chain_state *s, size_t i)
{
    return fabs(vrel ? s->V[i] - vrel[i] : s->V[i]);
}

/* The kinetic friction magnitude of sliding block i at the state: mu_k N, or N mu(|v_rel|) */
static inline double chain_slide_mag(const chain_model *M, const double *vrel, const chain_state *s, size_t i)
{
    if (!M->stribeck) return M->mukN[i];
    return M->Nn[i] * dfo_friction_mu(&M->law[i], chain_rel_speed(vrel, s, i));
}

/* The kinetic magnitude a slide starts with from rest (the rest rule's and breakaway's): mu_k N, or
 * N mu(0) (as the oscillator's start_loads) */
static inline double chain_start_mag(const chain_model *M, size_t i)
{
    if (!M->stribeck) return M->mukN[i];
    return M->Nn[i] * dfo_friction_mu(&M->law[i], 0.0);
}

/* held at rest in the current step: stuck (schemes whose stuck blocks rest) */
static inline int chain_held(const chain_model *M, const chain_state *s, size_t i)
{
    return s->mode[i] == 0 && chain_has_friction(M, i);
}

/* The loads of the inputs (held): u, mukN, Fb, Nn. */
void chain_loads_init(chain_model *M, const chain_inputs *in);

/* The engine's inputs of the chain's: in (held), ramp (NULL: held), belts vb (NULL: none). */
void chain_eng_inputs(const chain_inputs *in, const chain_ramp *ramp, const double *vb, eng_inputs *ei);

#endif
