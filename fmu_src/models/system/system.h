/* The DryFrictionSystem model: any linear structure with Coulomb friction contacts, rigid or Jenkins,
 *
 *     M x'' + C x' + K x = F_c cos(omega t) + F_s sin(omega t) + F_ext + W' f,   x in R^n,
 *
 * M (symmetric positive definite), C and K (symmetric positive semi-definite) dense n x n, row-major;
 * nc contacts, contact j along the row w_j of W (nc x n, row-major; stored sparse for the engine: its
 * nonzero entries), normal force N_j (+ the input N_ext_j, floored at 0), static and kinetic
 * coefficients mu_s_j, mu_k_j, belt speed (an input) v_belt_j, and tangential stiffness k_t_j: 0, a
 * rigid contact; > 0, a Jenkins element (a spring k_t_j in series with a massless slider whose
 * position is part of the engine's state: engine.h's eng_setup.k_t, eng_state.slider).
 *
 * Stepped by the friction engine (engine.h) with its three Bossak schemes through its generic
 * function-pointer instance (engine_generic.c), as the TwoMass model. This file holds the model's
 * operators (dense products with K, C, M and the dense Cholesky factor of cM M + cC C + cK K in each
 * of the engine's slots), the structure checks and the engine's setup. Plain C, no FMI types. */
#ifndef DFO_SYSTEM_H
#define DFO_SYSTEM_H

#include "eng_one_dof.h"
#include "engine.h"

#include <stddef.h>

/* The parameters: sizes, pointers to the caller's arrays (read by sys_model_init only: the model
 * copies what it keeps), scalars. */
typedef struct {
    size_t n, nc;                    /* degrees of freedom (>= 1), contacts (>= 0) */
    const double *M, *C, *K;         /* n x n, row-major */
    const double *F_c, *F_s;         /* n: excitation F_c cos(omega t) + F_s sin(omega t) */
    const double *x0, *v0;           /* n: initial state */
    const double *W;                 /* nc x n, row-major: the contact rows */
    const double *N, *mu_s, *mu_k;   /* nc: normal forces, static and kinetic coefficients */
    const double *k_t;               /* nc: tangential stiffness (0: rigid; > 0: a Jenkins element) */
    const double *law, *v_s, *delta; /* nc: friction law (DFO_LAW_COULOMB 1, DFO_LAW_STRIBECK 2; NULL: every
                                      * contact Coulomb), Stribeck velocity and exponent */
    double omega, h, alpha;          /* excitation frequency, internal step (0: derived), Bossak alpha */
    int scheme, frictionUpdates;     /* DFO_SCHEME_*, the paper scheme's coefficient updates */
    eng_rest_fn on_rest;             /* the engine's report of its rest rule (NULL: none), its context */
    void *rest_ctx;
} sys_params;

typedef struct {
    size_t n, nc;
    double h;                        /* the internal step used */
    double rate;                     /* the fastest rate (1/s): sys_step's, the engine's rate_max */
    double *M, *C, *K;               /* n x n copies */
    double *L[ENG_NSLOTS];           /* per slot: the lower Cholesky factor, n x n row-major */
    double *Pc, *Ps;                 /* n: the engine's excitation (Ps = -F_s; NULL when F_s = 0) */
    double *N, *mu_s, *mu_k, *k_t;   /* nc copies */
    int jenkins;                     /* some contact is a Jenkins element (k_t > 0) */
    dfo_friction_law *law;           /* nc sliding laws, or NULL: every contact Coulomb */
    eng_row *rows;                   /* nc rows, their nonzeros in idx and w */
    size_t *idx;
    double *w;
    double *work;                    /* n: scratch of the checks and the rate */
    int has_C;
    /* one DOF with one rigid contact along w = 1 (the oscillator's structure): the engine's one-DOF
     * operators (eng_one_dof.h: scalar M_hat, the contact's LCP in closed form, the closed-form
     * breakaway and the stuck fast path), so that it steps to the oscillator's bits */
    int one_dof;
    eng1_model one;
    eng *E;
} sys_model;

/* A sentence naming the first array element, size or structural test that fails (written to buf),
 * or NULL when p is a structure this build can step: sizes, finite values, M symmetric (within 1e-12
 * of its largest entry) and positive definite, K and C symmetric and positive semi-definite beyond
 * rounding (the Cholesky factorisation of K + 1e-12 max|K| I succeeds), no zero contact row, N, mu_s,
 * mu_k, k_t >= 0, the scalars in range. al: the scratch of the factorisations (freed before
 * returning); NULL with "out of memory" when it fails. */
const char *sys_check(const sys_params *p, const eng_alloc *al, char *buf, size_t len);

/* The internal step of p, for a structure that passed sys_check: p->h, or with p->h = 0 the default
 * rule (bossak.h's dfo_step_rule) over the fastest period 2 pi / rate, the fastest rate being
 *     rate = sqrt(lambda_max(M^-1 K_t)) + lambda_max(M^-1 C) + |omega|,   K_t = K + sum_j k_t_j w_j w_j'
 * (the stiffness with every Jenkins slider stuck; K without Jenkins contacts)
 * with each largest eigenvalue by power iteration on the symmetric L^-1 A L^-T (L the Cholesky
 * factor of M; at most 200 iterations, stopped at a relative change of 1e-9: a lower estimate,
 * exact for n = 1); without any (K = C = 0, omega = 0) the rule's fallback, 1 ms. NaN when M cannot
 * be factored or memory fails. */
double sys_step(const sys_params *p, const eng_alloc *al);

/* Build the model and its engine (m must not move afterwards: the engine points into it). Returns 1,
 * or 0 with *err a sentence (the structure refused by sys_check, or no memory); nothing is kept
 * allocated on failure. account_energy: keep the engine's energy accounts (eng_state.W_friction). */
int sys_model_init(sys_model *m, const sys_params *p, const eng_alloc *al, int account_energy, char *buf, size_t len,
                   const char **err);
void sys_model_free(sys_model *m, const eng_alloc *al);

#endif
