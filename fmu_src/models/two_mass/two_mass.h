/* The TwoMass model: two masses with one friction contact between them and one to the ground,
 *
 *     M x'' + C x' + K x = P(t) + F_ext + W' f,   x = (x1, x2),
 *     M = diag(m1, m2),  K = [[k1 + k12, -k12], [-k12, k2 + k12]],  C likewise (c1, c2, c12),
 *     P(t) = (P1, P2) cos(omega t + phi),
 *     contact 0 (mass 1 on the ground):  w = (1, 0),  N_g, mu_s_g, mu_k_g,
 *     contact 1 (mass 2 on mass 1):      w = (1, -1), N_c, mu_s_c, mu_k_c,
 *
 * stepped by the friction engine (engine.h) with its three Bossak schemes. This file holds the
 * model's operators (2 x 2 dense: K, C, M and the Cholesky factor of a_M M + a_C C + a_K K in each of
 * the engine's slots) and the engine's setup from the parameters. Plain C, no FMI types. */
#ifndef DFO_TWO_MASS_H
#define DFO_TWO_MASS_H

#include "engine.h"

#include <stddef.h>

typedef struct {
    double m1, m2, k1, k2, k12, c1, c2, c12; /* masses, springs (to the walls, between), dampers */
    double P1, P2, omega, phi;               /* harmonic excitation of each mass */
    double N_g, mu_s_g, mu_k_g;              /* contact 0: mass 1 on the ground */
    double N_c, mu_s_c, mu_k_c;              /* contact 1: mass 2 on mass 1 */
    double x1_0, x2_0, v1_0, v2_0;           /* initial state */
    double h, alpha;                         /* internal step (0: derived), Bossak parameter */
    int scheme, frictionUpdates, fastPaths;  /* (the FMU's variable names) */
} tm_params;

/* The inputs (held over a communication step); <name>_set: the input has been set. */
typedef struct {
    double F1_ext, F2_ext;
    int F1_ext_set, F2_ext_set;
} tm_inputs;

typedef struct {
    tm_params p;
    double h;                       /* the internal step used */
    double M[4], C[4], K[4];        /* row-major 2 x 2 */
    double L[ENG_NSLOTS][3];        /* per slot: l11, l21, l22 of the Cholesky factor */
    size_t idx_g[1], idx_c[2];
    double w_g[1], w_c[2];
    eng_row rows[2];
    double N[2], mu_s[2], mu_k[2], Pc[2];
    eng *E;
} tm_model;

/* A sentence naming the first parameter out of range (written to buf), or NULL when p is valid. */
const char *tm_check(const tm_params *p, char *buf, size_t len);

/* The fastest rate of the model (1/s): sqrt of the largest eigenvalue of M^-1 K, plus the damping
 * rate and |omega|. */
double tm_rate_max(const tm_params *p);

/* The internal step of p: p->h, or with p->h = 0 the default rule (bossak.h's dfo_step_rule) over
 * the fastest period 2 pi / tm_rate_max. */
double tm_step(const tm_params *p);

/* Build the model and its engine in place (m must not move afterwards: the engine points into it).
 * Returns 1, or 0 with *err a sentence (invalid parameters or no memory). */
int tm_model_init(tm_model *m, const tm_params *p, const eng_alloc *al, char *buf, size_t len, const char **err);
void tm_model_free(tm_model *m, const eng_alloc *al);

#endif
