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
 * operators (dense products with K, C, M and the solves with cM M + cC C + cK K in each of the
 * engine's slots), the structure checks and the engine's setup.
 *
 * Two backends for the solves, chosen at sys_model_init:
 *   modal  where C is diagonal in the modal basis (C = 0, Rayleigh C = a M + b K, modal damping):
 *          the modes Phi (Phi' M Phi = I, Phi' K Phi = diag(lambda), Phi' C Phi = diag(c); symeig.h)
 *          once, then a factorisation is d_r = 1 / (cM + cC c_r + cK lambda_r) (O(n)), a solve
 *          Phi (d .* (Phi' b)) (O(n^2)), and for the trial slot (refactored at every trial sub-step
 *          of a switch search) the contacts' coupling (engine.h's eng_coupling) from U = W Phi: the
 *          Delassus entries sum_r U_ar d_r U_br (O(n) each, kept per factorisation), the response
 *          Phi (d .* (U_S' f)) (the grid and mass slots: the engine's columns, solved once a run).
 *          C counts as diagonal when its off-diagonal part in the modal basis changes M_hat by a
 *          relative 1e-12 at most for every step up to h (SYS_MODAL_TOL in system.c);
 *   dense  otherwise (a general C), for n = 1 (with one rigid contact on the engine's one-DOF
 *          operators instead, below: the oscillator's bits) or when asked (sys_params.dense):
 *          the dense Cholesky factor of M_hat per slot (O(n^3) per factorisation, O(n^2) per solve),
 *          the engine's columns for the coupling.
 * Both are the same equations: the trajectories agree to rounding (amplified where a switch time
 * is decided by a rounding-level margin). Plain C, no FMI types. */
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
    int dense;                       /* 1: the dense Cholesky backend whatever C (a comparison's); 0: the
                                      * modal one where C allows it */
    int sensitivity;                 /* 1: propagate the located map's Jacobian (eng_setup.tangent) */
    const double *f0;                /* nc: a Jenkins contact's initial spring force (NULL: 0, relaxed) */
    const double *slide0;            /* nc: a Jenkins contact's initial slide (-1, 0 stuck, +1; NULL: stuck) */
    eng_rest_fn on_rest;             /* the engine's report of its rest rule (NULL: none), its context */
    void *rest_ctx;
} sys_params;

/* A symmetric operator's product y = A x in the order of the row sums y_i = sum_k A_ik x_k (k
 * ascending, from +0): CSR over the nonzeros where A is sparse (the zero terms add nothing: the same
 * bits), else A's columns (A' row-major) added into y one after the other (each y_i's sum in the same
 * order, the n sums side by side: vectorised). */
typedef struct {
    size_t *rp, *ci;                 /* CSR: row pointers (n + 1) and column indices; NULL: dense */
    double *v;                       /* CSR: the nonzeros; dense: A' (n x n, row-major) */
} sys_matop;

typedef struct {
    size_t n, nc;
    double h;                        /* the internal step used */
    double rate;                     /* the fastest rate (1/s): sys_step's, the engine's rate_max */
    double *M, *C, *K;               /* n x n copies */
    sys_matop opM, opC, opK;         /* their products (opC unset without C) */
    double *L[ENG_NSLOTS];           /* per slot: the lower Cholesky factor, n x n row-major */
    double *Lt[ENG_NSLOTS];          /* per slot: its transpose (the solves' rows and columns contiguous) */
    double *Pc, *Ps;                 /* n: the engine's excitation (Ps = -F_s; NULL when F_s = 0) */
    double *N, *mu_s, *mu_k, *k_t;   /* nc copies */
    int jenkins;                     /* some contact is a Jenkins element (k_t > 0) */
    dfo_friction_law *law;           /* nc sliding laws, or NULL: every contact Coulomb */
    eng_row *rows;                   /* nc rows, their nonzeros in idx and w */
    size_t *idx;
    double *w;
    double *work;                    /* n: scratch of the checks and the rate */
    int has_C;
    /* the modal backend (NULL arrays with the dense one; the slots' L then NULL) */
    int modal;                       /* 1: the modal backend; 0: dense */
    double c_offdiag;                /* C's off-diagonal share in the modal basis (the test against
                                      * SYS_MODAL_TOL; 0 without C; NaN: not computed, n = 1 or dense asked) */
    double *PhiT;                    /* n x n: row r the mode phi_r */
    double *Phi;                     /* n x n: its transpose (row i: the modes' entries at DOF i) */
    double *lam, *cdiag;             /* n: Phi' K Phi's and Phi' C Phi's diagonals */
    double *dm[ENG_NSLOTS];          /* n per slot: 1 / (cM + cC c_r + cK lambda_r) */
    double *U;                       /* nc x n: W Phi */
    double *z;                       /* n: scratch of the solves */
    double *Dc[ENG_NSLOTS];          /* nc x nc per slot served by the coupling (the trial slot; else
                                      * NULL): the Delassus entries computed (lower triangle) */
    unsigned *Dstamp[ENG_NSLOTS];    /* nc x nc: the factorisation (gen) each entry of Dc is of */
    unsigned gen[ENG_NSLOTS];        /* per slot: its factorisation's number (0: none yet) */
    eng_coupling coupling;
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
